# Errata: every printed number the recomputation does not reproduce, per soil.


def errata_inputs(wildcards):
    out = []
    for st in SOILS[wildcards.soil].stages:
        out += [f for f in stage_targets(wildcards.soil, st) if f.endswith(".csv")]
        if st.get("table") is not None:
            out.append(f"{stage_dir(wildcards.soil, st['id'])}/design_check.csv")
    return out


rule errata:
    input:
        errata_inputs,
    output:
        report("results/{soil}/published/errata.csv", caption="../report/errata.rst", category="{soil}"),
    params:
        soil=lambda w: soil_cfg(w.soil),
        published=lambda w: f"{RES}/published/{w.soil}",
        stage_dirs=lambda w: {st["id"]: stage_dir(w.soil, st["id"]) for st in SOILS[w.soil].stages},
    log:
        "logs/{soil}/published/errata.log",
    benchmark:
        "benchmarks/workflow/{soil}/published/errata.tsv"
    script:
        "../scripts/errata.py"
