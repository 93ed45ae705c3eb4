# One rule per pipeline job (parakin.registry.jobs): an artefact with threads, resources, an
# upstream or downstream artefact or chunks to gather is a job of its own; the small artefacts of
# one module share a job, made one after the other in one process (Python, the imports and numba
# start once per module, not once per artefact). Inputs: the papers' reference CSVs and the
# outputs of the artefacts they need; scattered studies (the 6-6 census) also gather their chunk
# files (workflow/rules/census.smk). Params: a digest of the source files the job runs (its
# modules and every parakin module they import: editing one reruns it, common.smk code_digest),
# and only the config sections its artefacts declare and the seed, so editing one section reruns
# only the jobs that read it (each artefact is still given only its own sections). group: the
# small jobs share a cluster submission (common.smk). threads/resources: what the artefact
# declares (the long jobs: training, GA, NSGA-II, PSO, the solver atlas), threads at most the
# config's max_threads (common.smk threads_of); every figure and table goes into the report
# (snakemake --report) with its one-line caption from the registry.


for _job in JOBS:
    _first = _job.items[0]

    rule:
        name:
            _job.rule
        input:
            reference=union(reference(item) for item in _job.items),
            upstream=union(upstream(item) for item in _job.items),
            chunks=union(scattered(item) for item in _job.items),
            files=union(item.files for item in _job.items),
        output:
            report_outputs(_job),
        log:
            f"{LOGS}/{_job.study}/{_first.name if len(_job.items) == 1 else _job.rule}.log",
        params:
            code=code_digest(*_job.items),
            cfg=job_config(_job),
            study=_job.study,
            name=" ".join(item.name for item in _job.items),
            module=_first.module,
            outdir=outdir_of(_job),
            caption=verbatim(rst_escape(_first.description)),
            captions=verbatim(
                "\n".join(f"- ``{item.name}``: {rst_escape(item.description)}" for item in _job.items)
            ),
        threads: threads_of(_job)
        priority: priority_of(_job)
        resources:
            **resources_of(_first),
        group:
            group_of(_job)
        conda:
            ENV
        shell:
            "rm -f {log:q}; "  # a log is written anew, never through what stands at its path
            "OMP_NUM_THREADS={threads} OPENBLAS_NUM_THREADS={threads} MKL_NUM_THREADS={threads} "
            "parakin reproduce {params.study} {params.name} --module {params.module} "
            "--outdir {params.outdir:q} --config-json {params.cfg} --validated 2>&1 | tee {log:q}"
