# Targets and optimisation: the value each target has for a source (printed, or measured on the
# soil's photos for the DEM source), desirability (several distinct solutions, the near-optimal
# sets and the calibrated one), PSO where the paper used it, and the step closest to the target
# on a steepest-ascent path.  A checkpoint: the verification and tool-test jobs take the
# calibrated set as their params, so a new optimum re-runs exactly the jobs whose set changed.


rule targets:
    input:
        images=lambda w: [f"results/{w.soil}/images/measurements.json"]
        if w.source == "dem" and any(t.get("image") for t in soil_cfg(w.soil)["targets"].values())
        else [],
    output:
        "results/{soil}/{source}/targets.csv",
    params:
        # citation: whether the soil has a paper to have printed values (its text changes nothing here)
        # properties.moisture_content: the unit a target's moisture is written in (targets.csv),
        # without its documentation (editing a note re-runs nothing)
        soil=lambda w: {"targets": soil_cfg(w.soil)["targets"], "citation": bool(soil_cfg(w.soil).get("citation")),
                        "properties": moisture_property(w.soil)},
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/{source}/targets.log",
    script:
        "../scripts/targets.py"


checkpoint optimum:
    input:
        stage="results/{soil}/{source}/{stage}/stage.json",
        responses="results/{soil}/{source}/{stage}/responses.csv",
        targets="results/{soil}/{source}/targets.csv",
    output:
        optimum="results/{soil}/{source}/{stage}/optimum.csv",
        identifiability=report("results/{soil}/{source}/{stage}/identifiability.csv",
                               caption="../report/identifiability.rst", category="{soil}",
                               subcategory="{source} {stage}"),
    params:
        seed=lambda w: soil_cfg(w.soil)["seed"],
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/{source}/{stage}/optimum.log",
    benchmark:
        "benchmarks/workflow/{soil}/{source}/{stage}/optimum.tsv"
    script:
        "../scripts/optimum.py"
