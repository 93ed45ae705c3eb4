# One rule per registered artefact. Inputs: the source files it runs (its module and every parakin
# module that imports), its paper's reference CSV and the outputs of the artefacts it needs.
# Params: only the config sections it declares and the seed, so editing one section reruns only
# the artefacts that read it.

for _item in ARTEFACTS.values():

    rule:
        name:
            _item.rule
        input:
            sources=_item.sources(),
            reference=reference(_item),
            upstream=upstream(_item),
        output:
            outputs(_item),
        log:
            f"{LOGS}/{_item.study}/{_item.name}.log",
        params:
            cfg=shlex.quote(json.dumps(registry.prune_config(config, _item), sort_keys=True)),
            study=_item.study,
            name=_item.name,
            module=_item.module,
            outdir=shlex.quote(str(Path(FIG) / _item.study_folder)),
        shell:
            "parakin reproduce {params.study} {params.name} --module {params.module} "
            "--outdir {params.outdir} --config-json {params.cfg} 2>&1 | tee {log:q}"
