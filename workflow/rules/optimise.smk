# Optimisation to the measured targets: desirability (several distinct solutions), PSO where
# the paper used it, and the step closest to the target on a steepest-ascent path.


rule optimum:
    input:
        table=stage_table,
    output:
        "results/{soil}/published/{stage}/optimum.csv",
    params:
        stage=lambda w: stage_cfg(w.soil, w.stage),
        targets=lambda w: soil_cfg(w.soil)["targets"],
        seed=lambda w: soil_cfg(w.soil)["seed"],
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/published/{stage}/optimum.log",
    benchmark:
        "benchmarks/workflow/{soil}/published/{stage}/optimum.tsv"
    script:
        "../scripts/optimum.py"
