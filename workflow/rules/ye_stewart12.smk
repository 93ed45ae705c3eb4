# Ye, You et al., 12-leg Stewart-derived cube mechanism (src/parakin/papers/ye_stewart12/).
Y12 = f"{FIG}/ye_stewart12"

# artefact -> its files
YE_STEWART12 = {
    "table1": ["table1.csv", "table1.md", "table1_random.csv"],
    "table3": ["table3.csv", "table3.md"],
    "fig01": ["fig01_mechanism.png", "fig01_mechanism.csv"],
    "fig02": ["fig02_topology.png", "fig02_topology.csv"],
    "fig06": ["fig06_prototype.png", "fig06_prototype.csv"],
    "fk_speed": ["extra_fk_speed.csv", "extra_fk_speed.md"],
    "table2": ["table2.csv", "table2.md"],
    "table4": ["table4.csv", "table4.md", "table4_summary.csv"],
    "table5": ["table5.csv", "table5.md"],
    "fig08": ["fig08_convergence.png", "fig08_convergence.csv"],
    "fig09": ["fig09_drive_modes.png", "fig09_drive_modes.csv"],
    "fig10": ["fig10_steps_tol1e-6.png", "fig10_steps_tol1e-6.csv"],
    "fig11": ["fig11_steps_tol1e-9.png", "fig11_steps_tol1e-9.csv"],
    "fig12": ["fig12_dmax_structures.png", "fig12_dmax_structures.csv", "table6.csv", "table6.md",
              "extra_scan_speed.csv", "extra_scan_speed.md"],
    "conditioning": ["extra_conditioning.csv", "extra_conditioning.md"],
    "basin": ["extra_basin.png", "extra_basin.csv"],
}
YE_STEWART12_OUTPUTS = [f"{Y12}/{f}" for files in YE_STEWART12.values() for f in files]

for _artefact, _files in YE_STEWART12.items():

    rule:
        name:
            f"ye_stewart12_{_artefact}"
        input:
            "data/reference/ye_stewart12.csv",
        output:
            [f"{Y12}/{f}" for f in _files],
        params:
            cfg=CONFIG_JSON,
            artefact=_artefact,
        shell:
            "parakin reproduce ye_stewart12 {params.artefact} --outdir {Y12} --config-json {params.cfg}"
