# One rule per registered artefact. Inputs: its paper's reference CSV and the outputs of the
# artefacts it needs; scattered studies (the 6-6 census) also gather their chunk files
# (workflow/rules/census.smk). Params: a digest of the source files it runs (its module and every
# parakin module that imports: editing one reruns it, common.smk code_digest), and only the config
# sections it declares and the seed, so editing one section reruns only the artefacts that read
# it. group: the small jobs share a cluster submission (common.smk). threads/resources: what the
# artefact declares (the long jobs: training, GA, NSGA-II, PSO, the solver atlas); every figure
# and table goes into the report (snakemake --report) with its one-line caption from the registry.

for _item in ARTEFACTS.values():

    rule:
        name:
            _item.rule
        input:
            reference=reference(_item),
            upstream=upstream(_item),
            chunks=scattered(_item),
            files=list(_item.files),
        output:
            report_outputs(_item),
        log:
            f"{LOGS}/{_item.study}/{_item.name}.log",
        params:
            code=code_digest(_item),
            cfg=shlex.quote(json.dumps(registry.prune_config(config, _item), sort_keys=True)),
            study=_item.study,
            name=_item.name,
            module=_item.module,
            outdir=outdir_of(_item),
            caption=verbatim(rst_escape(_item.description)),
        threads: _item.threads
        resources:
            **resources_of(_item),
        group:
            group_of(_item)
        conda:
            ENV
        shell:
            "rm -f {log:q}; "  # a log is written anew, never through what stands at its path
            "OMP_NUM_THREADS={threads} OPENBLAS_NUM_THREADS={threads} MKL_NUM_THREADS={threads} "
            "parakin reproduce {params.study} {params.name} --module {params.module} "
            "--outdir {params.outdir:q} --config-json {params.cfg} --validated 2>&1 | tee {log:q}"
