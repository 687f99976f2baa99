# Response sources: the one place where the two sources differ.  published: the printed table
# is the stage's response table.  dem: one DEM job per design point (integer run id; the point's
# levels, DEM parameters, scenarios and seed are the job's params, so a config edit re-runs
# exactly the points it changes), gathered into a table of the printed table's layout.


rule dem_kernels:
    # compiles the engine's kernels into Numba's cache once, before the DEM jobs start side by
    # side (each would otherwise compile them, minutes each); they take it as an ancient input,
    # so a rebuilt cache re-runs no result
    output:
        DEM_KERNELS,
    threads: 1
    priority: 1000
    resources:
        mem_mb=1000,
        runtime=30,
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/dem_kernels.log",
    benchmark:
        "benchmarks/workflow/dem_kernels.tsv"
    script:
        "../scripts/dem_kernels.py"


rule published_responses:
    input:
        table=lambda w: printed_table(w.soil, w.stage),
    output:
        "results/{soil}/published/{stage}/responses.csv",
    log:
        "logs/{soil}/published/{stage}/responses.log",
    conda:
        "../../envs/soilcal.yaml"
    script:
        "../scripts/published_responses.py"


rule dem_point:
    input:
        design=lambda w: ancient(dem_design(w)),
        kernels=ancient(DEM_KERNELS),
    output:
        "results/{soil}/dem/{stage}/runs/{run}.csv",
    params:
        spec=point_spec,
    threads: lambda w: dem_threads(w.soil)
    priority: dem_priority
    resources:
        mem_mb=dem_mem_mb(point_spec),
        runtime=dem_runtime(point_spec),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/{stage}/runs/{run}.log",
    benchmark:
        "benchmarks/workflow/{soil}/dem/{stage}/runs/{run}.tsv"
    script:
        "../scripts/dem_point.py"


rule dem_responses:
    input:
        stage="results/{soil}/dem/{stage}/stage.json",
        design="results/{soil}/dem/{stage}/design.csv",
        runs=dem_runs,
    output:
        "results/{soil}/dem/{stage}/responses.csv",
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/{stage}/responses.log",
    benchmark:
        "benchmarks/workflow/{soil}/dem/{stage}/responses.tsv"
    script:
        "../scripts/dem_responses.py"


rule printed_comparison:
    input:
        stage="results/{soil}/dem/{stage}/stage.json",
        responses="results/{soil}/dem/{stage}/responses.csv",
        table=lambda w: printed_table(w.soil, w.stage),
    output:
        "results/{soil}/dem/{stage}/printed_comparison.csv",
    params:
        printed_stage=lambda w: stage_cfg(w.soil, w.stage),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/{stage}/printed_comparison.log",
    script:
        "../scripts/printed_comparison.py"


rule simulation_setup:
    # what the soil's DEM runs are set up with and where each value comes from (the soil, a
    # documented default, the named setup, the preset): results/<soil>/dem/simulation.csv
    output:
        report("results/{soil}/dem/simulation.csv", caption="../report/simulation.rst", category="{soil}",
               subcategory="dem setup"),
    params:
        # only what simulation.csv reads: an edit elsewhere in the soil file reruns nothing here
        soil=lambda w: setup_inputs(soil_cfg(w.soil)),
        path=lambda w: str(SOILS[w.soil].path),
        resources_root=RES,
        defaulted=lambda w: [k for k in SOILS[w.soil].defaulted if k == "seed"],  # the one default it reads
        design=config.get("design"),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/simulation.log",
    script:
        "../scripts/simulation_setup.py"
