# Li, Quan, Wu 2017, 3-6 Stewart platform: tables and figures (src/parakin/papers/li2017_stewart36/).
S36 = f"{FIG}/li2017_stewart36"

# artefact -> its files
LI2017_STEWART36 = {
    "table1": ["table1.csv", "table1.md", "table1_stats.csv", "table1_stats.md"],
    "fig02": ["fig02_chaotic_weights.png", "fig02_chaotic_weights.csv"],
    "fig03": ["fig03_convergence.png", "fig03_convergence.csv", "fitness_stats.csv", "fitness_stats.md"],
    "table3": ["table3.csv", "table3.md"],
    "extra_solutions": ["extra_solutions.csv", "extra_solutions.md", "extra_solution_counts_b.csv",
                        "extra_solution_counts_b.md"],
    "extra_solution_counts": ["extra_solution_counts.csv", "extra_solution_counts.md", "extra_solution_counts.png",
                              "extra_solution_counts_richest.csv"],
    "fig01": ["fig01_structure.png", "fig01_structure.csv", "extra_solutions.png"],
    "adams": ["fig05_cm_velocity.png", "fig05_cm_velocity.csv", "fig06_cm_position.png", "fig06_cm_position.csv",
              "fig09_euler_angles.png", "fig09_euler_angles.csv", "extra_adams_trajectory.csv",
              "extra_adams_surrogate.csv", "extra_adams_surrogate.md"],
}
LI2017_STEWART36_OUTPUTS = [f"{S36}/{f}" for files in LI2017_STEWART36.values() for f in files]

for _artefact, _files in LI2017_STEWART36.items():

    rule:
        name:
            f"li2017_stewart36_{_artefact}"
        input:
            "data/reference/li2017_stewart36.csv",
        output:
            [f"{S36}/{f}" for f in _files],
        params:
            cfg=CONFIG_JSON,
            artefact=_artefact,
        shell:
            "parakin reproduce li2017_stewart36 {params.artefact} --outdir {S36} --config-json {params.cfg}"
