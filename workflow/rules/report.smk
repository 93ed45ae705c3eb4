# The claim-by-claim report (published numbers from data/reference beside our outputs) and the
# reproduction check of this run against the committed record (figures/).
REPORT = f"{FIG}/REPORT.md"
CHECK = [f"{RESULTS}/reproduction_check.md", f"{RESULTS}/reproduction_check.csv"] if RECORD else []


# cheap bookkeeping runs on the machine that runs snakemake, never as a cluster job
localrules:
    report,


rule report:
    input:
        ALL_OUTPUTS,
        expand("{ref}/{paper}.csv", ref=REFERENCE, paper=sorted({a.study for a in ARTEFACTS.values() if reference(a)})),
        f"{REFERENCE}/items.csv",
    output:
        report(REPORT, caption="../report/claims.rst", category="REPORT.md (claim by claim)"),
    log:
        f"{LOGS}/report.log",
    params:
        figures=lambda wildcards, output: str(Path(output[0]).parent),
    conda:
        ENV
    shell:
        "rm -f {log:q}; "  # a log is written anew, never through what stands at its path
        "parakin report --figures {params.figures:q} --out {output:q} 2>&1 | tee {log:q}"


if RECORD:

    localrules:
        reproduction_check,

    rule reproduction_check:
        input:
            ALL_OUTPUTS,
            REPORT,
        output:
            report(CHECK[0], caption="../report/check.rst", category="reproduction check"),
            CHECK[1],
        log:
            f"{LOGS}/reproduction_check.log",
        params:
            results=lambda wildcards, input: str(Path(input[-1]).parent),
            record=RECORD,
            out=lambda wildcards, output: str(Path(output[0]).with_suffix("")),
            studies=" ".join(config["studies"]),
        conda:
            ENV
        shell:
            "rm -f {log:q}; "  # a log is written anew, never through what stands at its path
            "parakin check --results {params.results:q} --record {params.record:q} --out {params.out:q} "
            "--studies {params.studies} 2>&1 | tee {log:q}"
