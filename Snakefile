# parakin: recompute every table and figure of the four papers, then check them against the record.
#   full:  snakemake --cores 2                                  (writes results/, checks against figures/)
#   quick: snakemake --cores 2 --configfile config/quick.yaml   (CI / tests; writes build/quick/)
# One rule per job, generated from the artefact registry (src/parakin/registry.py: jobs): each
# table or figure is declared beside the function that makes it (`parakin which FILE` finds it and
# its rule); the small artefacts of one module share a job, every other artefact has its own.
# The committed figures/ folder is the record; updating it is an explicit step: `parakin record`.
# Report: snakemake --report report.html (every figure and table, captioned); on a SLURM cluster:
#   snakemake --workflow-profile profiles/slurm    (docs/cluster.md)

configfile: "config/config.yaml"


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/artefacts.smk"
include: "workflow/rules/census.smk"
include: "workflow/rules/report.smk"


rule all:
    default_target: True
    input:
        ALL_OUTPUTS,
        REPORT,
        CHECK,
