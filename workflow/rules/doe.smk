# Designs: the stage each source runs (stage.json) and its design.  The published source takes
# the stage as the config prints it; the DEM source derives a stage that follows another one
# from the DEM results of that stage (steepest path from the screening, Box-Behnken centre
# from the path, fixed values from an earlier optimum).  A checkpoint: the number of DEM jobs
# of a stage is known once its design is.


checkpoint design:
    input:
        unpack(stage_inputs),
    output:
        stage="results/{soil}/{source}/{stage}/stage.json",
        design="results/{soil}/{source}/{stage}/design.csv",
        check="results/{soil}/{source}/{stage}/design_check.csv",
    params:
        soil=lambda w: dem_context(soil_cfg(w.soil)) if w.source == "dem" else None,
        stage=lambda w: stage_cfg(w.soil, w.stage),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/{source}/{stage}/design.log",
    benchmark:
        "benchmarks/workflow/{soil}/{source}/{stage}/design.tsv"
    script:
        "../scripts/design.py"
