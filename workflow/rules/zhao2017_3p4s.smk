# Zhao et al. 2017, 3-P(4S): tables and figures (src/parakin/papers/zhao2017_3p4s.py).
Z3 = f"{FIG}/zhao2017_3p4s"
G3 = f"{GEN}/zhao2017_3p4s"

# §3 (src/parakin/papers/zhao2017_3p4s/optimization.py): artefact -> its files
_ATLAS = {15: "dynamic_before", 17: "dynamic_after", 19: "stiffness_before", 21: "stiffness_after",
          23: "speed_before", 25: "speed_after"}
ZHAO2017_3P4S_OPTIMIZATION = {
    "fig11": ["fig11_velocity_sphere.png", "fig11_velocity_sphere.csv"],
    "fig12": ["fig12_velocity_ellipsoid.png", "fig12_velocity_ellipsoid.csv", "fig12_velocity_ellipsoid_axes.csv"],
    **{f"fig{n:02d}": [f"fig{n:02d}_{s}_atlas.png", f"fig{n:02d}_{s}_atlas.csv",
                       f"fig{n + 1:02d}_{s}_contour.png", f"fig{n + 1:02d}_{s}_contour.csv"] for n, s in _ATLAS.items()},
    "global_indices": ["extra_global_indices.csv", "extra_global_indices.md"],
    "index_convergence": ["extra_index_convergence.csv", "extra_index_convergence.md", "extra_index_convergence.png"],
    "index_sensitivity": ["extra_index_sensitivity.csv", "extra_index_sensitivity.md"],
    "index_benchmark": ["extra_index_benchmark.csv", "extra_index_benchmark.md"],
    "fig14": ["fig14_ga_convergence.png", "fig14_ga_convergence.csv"],
    "table3": ["table3.csv", "table3.md"],
    "pareto": ["extra_pareto.png", "extra_pareto.csv", "extra_pareto_marks.csv"],
    "ga_paper_box": ["extra_ga_paper_box.csv", "extra_ga_paper_box.md"],
}

# §1.2-2.4 (src/parakin/papers/zhao2017_3p4s/dynamics.py): figure stem -> artefact name
ZHAO2017_3P4S_DYNAMICS = {
    "fig05_drive_velocities": "fig05",
    "fig06_drive_accelerations": "fig06",
    "fig07_velocity_check": "fig07",
    "fig08_acceleration_check": "fig08",
    "fig09_driving_forces": "fig09",
    "fig10_mujoco_forces": "fig10",
    "extra_power_balance": "power_balance",
    "extra_dynamics_printed": "dynamics_printed",
    "extra_mujoco_tracking": "mujoco_tracking",
}

ZHAO2017_3P4S_OUTPUTS = [
    f"{Z3}/table1.csv",
    f"{Z3}/table1.md",
    f"{Z3}/extra_table1_fit.csv",
    f"{Z3}/extra_table1_region.png",
    f"{Z3}/fig01_mechanism.png",
    f"{Z3}/fig02_sketch.png",
    f"{Z3}/table2.md",
    f"{Z3}/extra_bp_training.png",
    f"{Z3}/fk_benchmark.md",
    *[f"{Z3}/{stem}.png" for stem in ZHAO2017_3P4S_DYNAMICS],
    f"{Z3}/extra_dynamics_slips.md",
    *[f"{Z3}/{o}" for outs in ZHAO2017_3P4S_OPTIMIZATION.values() for o in outs],
]


rule zhao2017_3p4s_table1:
    input:
        "data/reference/zhao2017_3p4s.csv",
    output:
        f"{Z3}/table1.csv",
        f"{Z3}/table1.md",
        f"{Z3}/extra_table1_fit.csv",
        f"{Z3}/extra_table1_fit.md",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce zhao2017_3p4s table1 --outdir {Z3} --config-json {params.cfg}"


rule zhao2017_3p4s_table1_region:
    input:
        "data/reference/zhao2017_3p4s.csv",
        f"{Z3}/extra_table1_fit.csv",
    output:
        f"{Z3}/extra_table1_region.png",
        f"{Z3}/extra_table1_region.csv",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce zhao2017_3p4s table1_region --outdir {Z3} --config-json {params.cfg}"


rule zhao2017_3p4s_fig:
    # Figs 1-2 redrawn from our model (the paper's are a CAD rendering and a sketch)
    output:
        f"{Z3}/fig{{n}}_{{slug}}.png",
        f"{Z3}/fig{{n}}_{{slug}}.csv",
    wildcard_constraints:
        n="01|02",
        slug="mechanism|sketch",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce zhao2017_3p4s fig{wildcards.n} --outdir {Z3} --config-json {params.cfg}"


rule zhao2017_3p4s_samples:
    # training samples of the BP network: IK (eq 5) over the workspace, seeded from config
    output:
        f"{G3}/bp_samples.npz",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce zhao2017_3p4s samples --outdir {Z3} --config-json {params.cfg}"


rule zhao2017_3p4s_train:
    # the 3-10-3 BP network trained by Levenberg-Marquardt (§1.1)
    input:
        f"{G3}/bp_samples.npz",
    output:
        f"{G3}/bp_network.npz",
        f"{G3}/bp_training_log.csv",
        f"{G3}/bp_training_summary.json",
        f"{Z3}/extra_bp_accuracy.csv",
        f"{Z3}/extra_bp_accuracy.md",
        f"{Z3}/extra_bp_training.csv",
        f"{Z3}/extra_bp_training.png",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce zhao2017_3p4s train --outdir {Z3} --config-json {params.cfg}"


rule zhao2017_3p4s_table2:
    # hybrid FK (network + quasi-Newton) of the Table 1 poses
    input:
        "data/reference/zhao2017_3p4s.csv",
        f"{G3}/bp_network.npz",
    output:
        f"{Z3}/table2.csv",
        f"{Z3}/table2.md",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce zhao2017_3p4s table2 --outdir {Z3} --config-json {params.cfg}"


rule zhao2017_3p4s_fk_benchmark:
    # every FK solver on the same random reachable strokes (our addition)
    input:
        f"{G3}/bp_network.npz",
    output:
        f"{Z3}/fk_benchmark.csv",
        f"{Z3}/fk_benchmark.md",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce zhao2017_3p4s fk_benchmark --outdir {Z3} --config-json {params.cfg}"


rule zhao2017_3p4s_dynamics_figure:
    # velocity, acceleration and force curves along x = y = 0.001 sin(40 pi t), checked against
    # IK finite differences, an energy balance and MuJoCo (the paper used ADAMS)
    output:
        f"{Z3}/{{stem}}.png",
        f"{Z3}/{{stem}}.csv",
    wildcard_constraints:
        stem="|".join(ZHAO2017_3P4S_DYNAMICS),
    params:
        cfg=CONFIG_JSON,
        artefact=lambda w: ZHAO2017_3P4S_DYNAMICS[w.stem],
    shell:
        "parakin reproduce zhao2017_3p4s {params.artefact} --outdir {Z3} --config-json {params.cfg}"


rule zhao2017_3p4s_dynamics_slips:
    # the three slips of the printed dynamics (eq 13's H, eq 21, eq 23), each checked four ways
    output:
        f"{Z3}/extra_dynamics_slips.csv",
        f"{Z3}/extra_dynamics_slips.md",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce zhao2017_3p4s dynamics_slips --outdir {Z3} --config-json {params.cfg}"


# §3: indices, atlases, GA and Pareto front, one rule per artefact
for _artefact, _files in ZHAO2017_3P4S_OPTIMIZATION.items():

    rule:
        name:
            f"zhao2017_3p4s_{_artefact}"
        output:
            [f"{Z3}/{f}" for f in _files],
        params:
            cfg=CONFIG_JSON,
            artefact=_artefact,
        shell:
            "parakin reproduce zhao2017_3p4s {params.artefact} --outdir {Z3} --config-json {params.cfg}"
