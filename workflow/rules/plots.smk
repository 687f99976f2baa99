# Figures for the report (PNG) and for papers (PDF).


rule figures:
    input:
        table=stage_table,
    output:
        report(
            directory("results/{soil}/published/{stage}/figures/{kind}"),
            patterns=["{name}.png"],
            caption="../report/figures.rst",
            category="{soil}",
            subcategory="{stage}",
        ),
    params:
        stage=lambda w: stage_cfg(w.soil, w.stage),
        targets=lambda w: soil_cfg(w.soil)["targets"],
        parameters=lambda w: soil_cfg(w.soil)["parameters"],
    wildcard_constraints:
        kind="pareto|steepest|surfaces|diagnostics",
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/published/{stage}/figures_{kind}.log",
    benchmark:
        "benchmarks/workflow/{soil}/published/{stage}/figures_{kind}.tsv"
    script:
        "../scripts/figures.py"
