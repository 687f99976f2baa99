# Errata: every printed number the recomputation does not reproduce, per soil (published source).


rule errata:
    input:
        errata_inputs,
    output:
        report("results/{soil}/published/errata.csv", caption="../report/errata.rst", category="{soil}"),
    params:
        soil=lambda w: without_search_ranges(soil_cfg(w.soil)),
        published=lambda w: f"{RES}/published/{w.soil}",
        stage_dirs=lambda w: {st["id"]: stage_dir(w.soil, st["id"]) for st in SOILS[w.soil].stages},
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/published/errata.log",
    benchmark:
        "benchmarks/workflow/{soil}/published/errata.tsv"
    script:
        "../scripts/errata.py"
