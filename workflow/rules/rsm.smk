# Regression and ANOVA (Design-Expert style) on the printed responses of PB and BBD stages.


rule regression:
    input:
        table=stage_table,
    output:
        anova="results/{soil}/published/{stage}/anova.csv",
        fit="results/{soil}/published/{stage}/fit.csv",
        coefficients="results/{soil}/published/{stage}/coefficients.csv",
        effects="results/{soil}/published/{stage}/effects.csv",
    params:
        stage=lambda w: stage_cfg(w.soil, w.stage),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/published/{stage}/regression.log",
    benchmark:
        "benchmarks/workflow/{soil}/published/{stage}/regression.tsv"
    script:
        "../scripts/regression.py"
