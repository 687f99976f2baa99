# Regression and ANOVA (Design-Expert style) of every PB and BBD stage, whatever the source of
# its responses.


rule regression:
    input:
        stage="results/{soil}/{source}/{stage}/stage.json",
        responses="results/{soil}/{source}/{stage}/responses.csv",
    output:
        anova="results/{soil}/{source}/{stage}/anova.csv",
        fit="results/{soil}/{source}/{stage}/fit.csv",
        coefficients="results/{soil}/{source}/{stage}/coefficients.csv",
        effects="results/{soil}/{source}/{stage}/effects.csv",
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/{source}/{stage}/regression.log",
    benchmark:
        "benchmarks/workflow/{soil}/{source}/{stage}/regression.tsv"
    script:
        "../scripts/regression.py"
