# The claim-by-claim report (published numbers from data/reference beside our outputs) and the
# reproduction check of this run against the committed record (figures/).
REPORT = f"{FIG}/REPORT.md"
CHECK = [f"{RESULTS}/reproduction_check.md", f"{RESULTS}/reproduction_check.csv"] if RECORD else []


rule report:
    input:
        ALL_OUTPUTS,
        expand("{ref}/{paper}.csv", ref=REFERENCE, paper=sorted({a.study for a in ARTEFACTS.values() if reference(a)})),
    output:
        REPORT,
    log:
        f"{LOGS}/report.log",
    params:
        figures=shlex.quote(FIG),
    shell:
        "parakin report --figures {params.figures} --out {output:q} 2>&1 | tee {log:q}"


if RECORD:

    rule reproduction_check:
        input:
            ALL_OUTPUTS,
            REPORT,
        output:
            CHECK,
        log:
            f"{LOGS}/reproduction_check.log",
        params:
            results=shlex.quote(FIG),
            record=shlex.quote(RECORD),
            out=shlex.quote(f"{RESULTS}/reproduction_check"),
            studies=" ".join(config["studies"]),
        shell:
            "parakin check --results {params.results} --record {params.record} --out {params.out} "
            "--studies {params.studies} 2>&1 | tee {log:q}"
