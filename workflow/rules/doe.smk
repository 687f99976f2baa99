# Designs: generate each stage's design (pyDOE3 / Plackett-Burman) and compare it with the
# printed one as a set of rows.


rule design:
    input:
        table=stage_table,
    output:
        design="results/{soil}/published/{stage}/design.csv",
        check="results/{soil}/published/{stage}/design_check.csv",
    params:
        stage=lambda w: stage_cfg(w.soil, w.stage),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/published/{stage}/design.log",
    benchmark:
        "benchmarks/workflow/{soil}/published/{stage}/design.tsv"
    script:
        "../scripts/design.py"
