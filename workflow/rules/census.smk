# The scatter of the 6-6 census (src/parakin/studies/stewart66_census.py): config
# stewart66_census.chunks jobs, each writes the platforms of its range to its own file
# ({generated}/stewart66_census/I-of-N.csv); the census artefact gathers them (input `chunks` of
# its rule, common.smk: scattered). A failed chunk leaves the others' files in place: rerunning
# the workflow redoes that chunk alone. Each input draws from its platform's own random stream, so
# the census does not depend on the number of chunks.
CENSUS = "parakin.studies.stewart66_census"

if CENSUS in config["studies"]:

    scattergather:
        census=config["stewart66_census"]["chunks"],

    rule stewart66_census_chunk:
        output:
            f"{GEN}/stewart66_census/{{scatteritem}}.csv",
        log:
            f"{LOGS}/stewart66_census/chunk_{{scatteritem}}.log",
        params:
            code=code_digest(ARTEFACTS["stewart66_census:census"]),
            module=CENSUS,
            cfg=shlex.quote(
                json.dumps(registry.prune_config(config, ARTEFACTS["stewart66_census:census"]), sort_keys=True)
            ),
        threads: 1
        resources:
            runtime=60,
            mem_mb=2000,
        conda:
            ENV
        shell:
            "rm -f {log:q}; "  # a log is written anew, never through what stands at its path
            "OMP_NUM_THREADS={threads} OPENBLAS_NUM_THREADS={threads} MKL_NUM_THREADS={threads} "
            "NUMBA_NUM_THREADS={threads} python -m {params.module} {wildcards.scatteritem} {output:q} "
            "--config-json {params.cfg} 2>&1 | tee {log:q}"
