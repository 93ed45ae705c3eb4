# Li et al. 2020, 2-UPS/(S+SPR)R: tables and figures (src/parakin/papers/li2020_2ups/).
L2 = f"{FIG}/li2020_2ups"

# artefact -> its files
LI2020_2UPS = {
    "fig01": ["fig01_mechanism.png", "fig01_mechanism.csv"],
    "concomitant": ["extra_concomitant.csv", "extra_concomitant.md"],
    "parasitic": ["extra_parasitic.png", "extra_parasitic.csv"],
    "fk_solutions": ["extra_fk_solutions.png", "extra_fk_solutions.csv"],
    "table1": ["table1.csv", "table1.md"],
    "table2": ["table2.csv", "table2.md", "table2_consistency.csv", "table2_consistency.md"],
    "fig02": ["fig02_fitness.png", "fig02_fitness.csv"],
    "solvers": ["extra_solvers.csv", "extra_solvers.md"],
    "singularity_workspace": ["extra_singularity_workspace.png", "extra_singularity_workspace.csv"],
    "benchmark": ["extra_benchmark.csv", "extra_benchmark.md"],
}
LI2020_2UPS_OUTPUTS = [f"{L2}/{f}" for files in LI2020_2UPS.values() for f in files]

for _artefact, _files in LI2020_2UPS.items():

    rule:
        name:
            f"li2020_2ups_{_artefact}"
        input:
            "data/reference/li2020_2ups.csv",
        output:
            [f"{L2}/{f}" for f in _files],
        params:
            cfg=CONFIG_JSON,
            artefact=_artefact,
        shell:
            "parakin reproduce li2020_2ups {params.artefact} --outdir {L2} --config-json {params.cfg}"
