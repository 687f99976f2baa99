# The measured-data loop (soilcal.loop): the calibrated model's residual against every measured
# condition of the soil's `measurements` block (the tool runs are the calibrated prediction),
# the structure in it, and the candidate effects of the library that act through that
# structure, each simulated at a small design of its parameters (one DEM job per design point
# and measured condition, with the tool runs' seeds), then fitted, scored on held-out
# measurements and chosen or rejected.  A second round (checkpoint loop_more) fits the effects
# that the residual left by the first round's model matches, and runs more levels of an effect
# whose scenario stopped measuring past some level (soilcal.loop.select.narrowing).


checkpoint loop_diagnose:
    input:
        runs=tool_runs,
        # the sets the run files (params) are read from
        optima=tool_optima,
    output:
        residuals=report("results/{soil}/loop/residuals.csv", caption="../report/loop_residuals.rst",
                         category="{soil}", subcategory="measured-data loop"),
        diagnosis=report("results/{soil}/loop/diagnosis.csv", caption="../report/loop_diagnosis.rst",
                         category="{soil}", subcategory="measured-data loop"),
        ranking="results/{soil}/loop/ranking.csv",
        plan="results/{soil}/loop/plan.json",
        figures=report(directory("results/{soil}/loop/figures/residuals"), patterns=["{name}.png"],
                       caption="../report/loop_figures.rst", category="{soil}", subcategory="measured-data loop"),
    params:
        soil_path=lambda w: str(SOILS[w.soil].path),
        resources_root=RES,
        files=after_checkpoints(tool_file_map),
        loop=lambda w: soil_cfg(w.soil).get("loop") or {},
        measurements=lambda w: soil_cfg(w.soil).get("measurements") or {},
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/loop/diagnose.log",
    script:
        "../scripts/loop_diagnose.py"


rule loop_point:
    input:
        optima=tool_optima,
        plan=lambda w: ancient(loop_plan_file(w.soil)),
        kernels=ancient(DEM_KERNELS),
    output:
        "results/{soil}/loop/runs/{key}.csv",
    params:
        job=loop_spec,
    threads: lambda w: dem_threads(w.soil)
    resources:
        mem_mb=dem_mem_mb(loop_spec),
        runtime=dem_runtime(loop_spec),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/loop/runs/{key}.log",
    benchmark:
        "benchmarks/workflow/{soil}/loop/runs/{key}.tsv"
    script:
        "../scripts/tool_point.py"


checkpoint loop_more:
    input:
        optima=tool_optima,
        plan=lambda w: loop_plan_file(w.soil),
        runs=loop_first_runs,
    output:
        "results/{soil}/loop/plan_more.json",
    params:
        soil_path=lambda w: str(SOILS[w.soil].path),
        resources_root=RES,
        effect_files=loop_first_files,
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/loop/more.log",
    script:
        "../scripts/loop_more.py"


rule loop_select:
    input:
        optima=tool_optima,
        plan=lambda w: loop_plan_file(w.soil),
        more=lambda w: loop_more_file(w.soil),
        runs=loop_runs,
    output:
        selection=report("results/{soil}/loop/selection.csv", caption="../report/loop_selection.rst",
                         category="{soil}", subcategory="measured-data loop"),
        predictions="results/{soil}/loop/predictions.csv",
        summary=report("results/{soil}/loop/loop_summary.csv", caption="../report/loop_summary.rst",
                       category="{soil}", subcategory="measured-data loop"),
        report="results/{soil}/loop/report.md",
        detectable="results/{soil}/loop/detectable.csv",
        figures=report(directory("results/{soil}/loop/figures/after"), patterns=["{name}.png"],
                       caption="../report/loop_figures.rst", category="{soil}", subcategory="measured-data loop"),
    params:
        soil_path=lambda w: str(SOILS[w.soil].path),
        resources_root=RES,
        effect_files=loop_effect_files,
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/loop/select.log",
    script:
        "../scripts/loop_select.py"
