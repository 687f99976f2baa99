# Figures for the report (PNG) and for papers (PDF): per stage, whatever the source (the DEM
# figures overlay the paper's published values where the figure has them), and the DEM
# verification, tool tests and the comparison of the soils.


rule figures:
    input:
        stage="results/{soil}/{source}/{stage}/stage.json",
        responses="results/{soil}/{source}/{stage}/responses.csv",
        targets="results/{soil}/{source}/targets.csv",
        reference=lambda w: [printed_table(w.soil, w.stage)]
        if w.source == "dem" and printed_table(w.soil, w.stage)
        else [],
    output:
        report(
            directory("results/{soil}/{source}/{stage}/figures/{kind}"),
            patterns=["{name}.png"],
            caption="../report/figures.rst",
            category="{soil}",
            subcategory="{source} {stage}",
        ),
    params:
        parameters=lambda w: soil_cfg(w.soil)["parameters"],
        reference_stage=lambda w: stage_cfg(w.soil, w.stage) if w.source == "dem" else None,
    wildcard_constraints:
        kind="pareto|steepest|surfaces|diagnostics",
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/{source}/{stage}/figures_{kind}.log",
    benchmark:
        "benchmarks/workflow/{soil}/{source}/{stage}/figures_{kind}.tsv"
    script:
        "../scripts/figures.py"


rule verification_figures:
    input:
        verification="results/{soil}/dem/verification.csv",
    output:
        report(
            directory("results/{soil}/dem/figures/verification"),
            patterns=["{name}.png"],
            caption="../report/verification.rst",
            category="{soil}",
            subcategory="dem verification",
        ),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/figures_verification.log",
    script:
        "../scripts/dem_figures.py"


rule tool_figures:
    input:
        tools="results/{soil}/dem/tool_verification.csv",
    output:
        report(
            directory("results/{soil}/dem/figures/tools"),
            patterns=["{name}.png"],
            caption="../report/tools.rst",
            category="{soil}",
            subcategory="dem tool tests",
        ),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/figures_tools.log",
    script:
        "../scripts/dem_figures.py"


rule summary:
    input:
        verification=lambda w: [f"results/{s}/dem/verification.csv" for s in SOILS if "dem" in SOURCES[s]],
        responses=lambda w: [f for s in SOILS if "dem" in SOURCES[s]
                             for sid in source_stages(s, "dem")
                             for f in [f"{stage_dir(s, sid, 'dem')}/responses.csv"]],
    output:
        table="results/summary.csv",
        figures=report(
            directory("results/figures/summary"),
            patterns=["{name}.png"],
            caption="../report/summary.rst",
            category="summary",
        ),
    params:
        soils=lambda w: [s for s in SOILS if "dem" in SOURCES[s]],
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/summary.log",
    script:
        "../scripts/summary.py"
