# The claim-by-claim report: published numbers (data/reference) beside our pipeline outputs.
REPORT = f"{FIG}/REPORT.md"


rule report:
    input:
        ZHAO2017_3P4S_OUTPUTS,
        LI2020_2UPS_OUTPUTS,
        YE_STEWART12_OUTPUTS,
        LI2017_STEWART36_OUTPUTS,
        f"{FIG}/extra_solver_atlas.csv",
        expand("data/reference/{paper}.csv", paper=["zhao2017_3p4s", "li2020_2ups", "ye_stewart12", "li2017_stewart36"]),
    output:
        REPORT,
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin report --figures {FIG} --out {output} --config-json {params.cfg}"
