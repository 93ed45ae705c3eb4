# Beyond the papers: every FK solver on every mechanism (the solver atlas) and the benchmark summary
# that README quotes (src/parakin/extras.py, src/parakin/atlas.py).
EXTRA_OUTPUTS = [f"{FIG}/extra_solver_atlas.{ext}" for ext in ("csv", "md", "png")] + [f"{FIG}/benchmarks.md"]


rule extra_solver_atlas:
    # the 3-P(4S) row set includes the hybrid solver, so the atlas waits for the trained network
    input:
        f"{GEN}/zhao2017_3p4s/bp_network.npz",
    output:
        f"{FIG}/extra_solver_atlas.csv",
        f"{FIG}/extra_solver_atlas.md",
        f"{FIG}/extra_solver_atlas.png",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce extra solver_atlas --outdir {FIG} --config-json {params.cfg}"


rule extra_benchmarks:
    input:
        f"{FIG}/extra_solver_atlas.csv",
        f"{FIG}/zhao2017_3p4s/fk_benchmark.md",
        f"{FIG}/zhao2017_3p4s/extra_index_benchmark.md",
        f"{FIG}/li2020_2ups/extra_benchmark.md",
        f"{FIG}/ye_stewart12/extra_fk_speed.md",
        f"{FIG}/ye_stewart12/extra_scan_speed.md",
    output:
        f"{FIG}/benchmarks.md",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce extra benchmarks --outdir {FIG} --config-json {params.cfg}"
