# Zhao et al. 2017, 3-P(4S): tables and figures (src/parakin/papers/zhao2017_3p4s.py).
Z3 = f"{FIG}/zhao2017_3p4s"

ZHAO2017_3P4S_OUTPUTS = [
    f"{Z3}/table1.csv",
    f"{Z3}/table1.md",
    f"{Z3}/extra_table1_fit.csv",
    f"{Z3}/extra_table1_region.png",
    f"{Z3}/fig01_mechanism.png",
    f"{Z3}/fig02_sketch.png",
]


rule zhao2017_3p4s_table1:
    input:
        "data/reference/zhao2017_3p4s.csv",
    output:
        f"{Z3}/table1.csv",
        f"{Z3}/table1.md",
        f"{Z3}/extra_table1_fit.csv",
        f"{Z3}/extra_table1_fit.md",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce zhao2017_3p4s table1 --outdir {Z3} --config-json {params.cfg}"


rule zhao2017_3p4s_table1_region:
    input:
        "data/reference/zhao2017_3p4s.csv",
        f"{Z3}/extra_table1_fit.csv",
    output:
        f"{Z3}/extra_table1_region.png",
        f"{Z3}/extra_table1_region.csv",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce zhao2017_3p4s table1_region --outdir {Z3} --config-json {params.cfg}"


rule zhao2017_3p4s_fig:
    # Figs 1-2 redrawn from our model (the paper's are a CAD rendering and a sketch)
    output:
        f"{Z3}/fig{{n}}_{{slug}}.png",
        f"{Z3}/fig{{n}}_{{slug}}.csv",
    wildcard_constraints:
        n="01|02",
    params:
        cfg=CONFIG_JSON,
    shell:
        "parakin reproduce zhao2017_3p4s fig{wildcards.n} --outdir {Z3} --config-json {params.cfg}"
