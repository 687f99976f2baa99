# The adaptive design (simulation.design: adaptive, or --config design=adaptive): per
# optimisation case, one checkpoint per iteration decides the next runs from every run so far
# (soilcal.doe.adaptive), one DEM job per run, until a verified set meets every target, the
# budget is spent or the target is out of reach.  Outputs under results/<soil>/dem/adaptive/
# with the recipe's file names (optimum.csv, identifiability.csv, verification.csv).


checkpoint adaptive_step:
    input:
        unpack(adaptive_step_inputs),
    output:
        "results/{soil}/dem/adaptive/{stage}/{case}/step/{it}.json",
    params:
        soil=lambda w: dem_context(soil_cfg(w.soil), search_ranges=True),
        iteration=lambda w: int(w.it),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/adaptive/{stage}/{case}/step/{it}.log",
    benchmark:
        "benchmarks/workflow/{soil}/dem/adaptive/{stage}/{case}/step/{it}.tsv"
    script:
        "../scripts/adaptive_step.py"


rule adaptive_point:
    input:
        step=lambda w: ancient(adaptive_step_file(w.soil, w.stage, w.case, int(w.it))),
        kernels=ancient(DEM_KERNELS),
    output:
        "results/{soil}/dem/adaptive/{stage}/{case}/runs/{it}/{run}.csv",
    params:
        spec=adaptive_spec,
    threads: lambda w: dem_threads(w.soil)
    resources:
        mem_mb=dem_mem_mb(adaptive_spec),
        runtime=dem_runtime(adaptive_spec),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/adaptive/{stage}/{case}/runs/{it}/{run}.log",
    benchmark:
        "benchmarks/workflow/{soil}/dem/adaptive/{stage}/{case}/runs/{it}/{run}.tsv"
    script:
        "../scripts/dem_point.py"


rule adaptive_case:
    input:
        unpack(adaptive_case_inputs),
    output:
        runs="results/{soil}/dem/adaptive/{stage}/{case}/runs.csv",
        surrogates="results/{soil}/dem/adaptive/{stage}/{case}/surrogates.csv",
        region="results/{soil}/dem/adaptive/{stage}/{case}/region.csv",
        result="results/{soil}/dem/adaptive/{stage}/{case}/result.json",
        verification_runs="results/{soil}/dem/adaptive/{stage}/{case}/verification_runs.csv",
    params:
        soil=lambda w: dem_context(soil_cfg(w.soil), search_ranges=True),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/adaptive/{stage}/{case}/case.log",
    script:
        "../scripts/adaptive_case.py"


rule adaptive_stage:
    input:
        unpack(adaptive_stage_inputs),
    output:
        stage="results/{soil}/dem/adaptive/{stage}/stage.json",
        optimum="results/{soil}/dem/adaptive/{stage}/optimum.csv",
        identifiability="results/{soil}/dem/adaptive/{stage}/identifiability.csv",
    params:
        soil=lambda w: dem_context(soil_cfg(w.soil), search_ranges=True),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/adaptive/{stage}/stage.log",
    script:
        "../scripts/adaptive_stage.py"


rule adaptive_verification:
    input:
        unpack(adaptive_verification_inputs),
    output:
        verification="results/{soil}/dem/adaptive/verification.csv",
        summary="results/{soil}/dem/adaptive/summary.csv",
    params:
        # citation: whether the soil has a paper whose targets and verification to set beside
        soil=lambda w: dict(dem_context(soil_cfg(w.soil), search_ranges=True), citation=bool(soil_cfg(w.soil).get("citation"))),
        stage_dirs=lambda w: {s: f"results/{w.soil}/dem/adaptive/{s}" for s in adaptive_stages(w.soil)},
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/adaptive/verification.log",
    script:
        "../scripts/adaptive_verification.py"


rule adaptive_figures:
    input:
        unpack(adaptive_verification_inputs),
        verification="results/{soil}/dem/adaptive/verification.csv",
    output:
        report(
            directory("results/{soil}/dem/adaptive/figures"),
            patterns=["{name}.png"],
            caption="../report/adaptive.rst",
            category="{soil}",
            subcategory="dem adaptive",
        ),
    params:
        cases=lambda w: [adaptive_dir(w.soil, s, c) for s in adaptive_stages(w.soil) for c in adaptive_case_ids(w.soil, s)],
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/adaptive/figures.log",
    script:
        "../scripts/adaptive_figures.py"
