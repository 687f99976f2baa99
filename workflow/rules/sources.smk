# Response sources: the one place where the two sources differ.  published: the printed table
# is the stage's response table.  dem: one DEM job per design point (integer run id; the point's
# levels, DEM parameters, scenarios and seed are the job's params, so a config edit re-runs
# exactly the points it changes), gathered into a table of the printed table's layout.


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
