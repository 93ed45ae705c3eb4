# parakin: reproduce every table and figure of the four papers.
#   full:  snakemake --cores 2
#   quick: snakemake --cores 2 --configfile config/quick.yaml   (CI / tests; writes under build/quick)
# Every rule calls the `parakin` CLI; the code behind each output is one `parakin reproduce` artefact.

configfile: "config/config.yaml"


include: "workflow/rules/common.smk"
include: "workflow/rules/zhao2017_3p4s.smk"
include: "workflow/rules/li2020_2ups.smk"
include: "workflow/rules/ye_stewart12.smk"
include: "workflow/rules/li2017_stewart36.smk"
include: "workflow/rules/extra.smk"
include: "workflow/rules/report.smk"


rule all:
    default_target: True
    input:
        ZHAO2017_3P4S_OUTPUTS,
        LI2020_2UPS_OUTPUTS,
        YE_STEWART12_OUTPUTS,
        LI2017_STEWART36_OUTPUTS,
        EXTRA_OUTPUTS,
        REPORT,


# README quotes the benchmark summary between markers; after a full run (the committed figures/)
# copy the regenerated block in, so that README never shows a typed number.
onsuccess:
    if FIG == "figures":
        shell("parakin readme")
