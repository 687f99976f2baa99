# Verification of the DEM calibration: every optimisation case at its calibrated set with
# several seeds apart from the design seeds, more where the first ones leave a miss within their
# scatter and the soil allows more (checkpoint verify_seeds; one job per case and seed; also at the paper preset
# for the responses listed under simulation.verification.paper), the papers' tool and
# process tests declared in the soil's `measurements` block (one job per distinct measured
# condition: a tiller speed whose flatness and power are tabled apart is one job),
# and the calibrated parameters beside the paper's.  Where the first verification misses a
# target and its mean differs significantly from the surface's prediction, a second round
# verifies the bias-corrected set (checkpoint refine, one job per case and seed; where the bias
# is significant, after a local design at the first set that learns the DEM's slope there,
# checkpoint local_design, one job per point); the tool tests,
# a later stage fixing a stage's parameters and the calibrated-vs-paper table use the set the
# soil ends with (checkpoint final_set: the better verified round).


rule verify_point:
    input:
        optimum=lambda w: optimum_of(w.soil, w.stage),
        kernels=ancient(DEM_KERNELS),
        same=verify_same_input,
    output:
        "results/{soil}/dem/verify/{preset}/{stage}/{case}/{rep}.csv",
    params:
        spec=verify_spec,
    threads: lambda w: dem_threads(w.soil)
    resources:
        mem_mb=dem_mem_mb(verify_spec),
        runtime=dem_runtime(verify_spec),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/verify/{preset}/{stage}/{case}/{rep}.log",
    benchmark:
        "benchmarks/workflow/{soil}/dem/verify/{preset}/{stage}/{case}/{rep}.tsv"
    script:
        "../scripts/verify_point.py"


checkpoint verify_seeds:
    # the second verification stage (a soil whose simulation.verification.max_replicates exceeds
    # its replicates): how many seeds each case of the stage takes, from its first stage's runs
    input:
        stage="results/{soil}/dem/{stage}/stage.json",
        targets="results/{soil}/dem/targets.csv",
        optimum=lambda w: optimum_of(w.soil, w.stage),
        runs=stage_first_runs,
    output:
        report("results/{soil}/dem/{stage}/verify_seeds.csv", caption="../report/verify_seeds.rst",
               category="{soil}", subcategory="dem verification"),
    params:
        soil=verification_soil,
        preset=lambda w: sim_cfg(w.soil).get("preset", "quick"),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/{stage}/verify_seeds.log",
    script:
        "../scripts/verify_seeds.py"


checkpoint local_design:
    # the local design at the first set of every case the second round would move because of a
    # bias (soilcal.chain.local): its runs learn the DEM's slope there
    input:
        stage="results/{soil}/dem/{stage}/stage.json",
        responses="results/{soil}/dem/{stage}/responses.csv",
        targets="results/{soil}/dem/targets.csv",
        optimum=lambda w: optimum_of(w.soil, w.stage),
        runs=stage_verify_runs,
    output:
        "results/{soil}/dem/{stage}/local.csv",
    params:
        soil=lambda w: dem_context(soil_cfg(w.soil), search_ranges=True),
        half_width=lambda w: local_half_width(w.soil),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/{stage}/local.log",
    script:
        "../scripts/local_design.py"


rule local_point:
    input:
        local=lambda w: ancient(local_of(w.soil, w.stage)),
        kernels=ancient(DEM_KERNELS),
    output:
        "results/{soil}/dem/local/{stage}/{case}/{rep}.csv",
    params:
        spec=local_spec,
    threads: lambda w: dem_threads(w.soil)
    resources:
        mem_mb=dem_mem_mb(local_spec),
        runtime=dem_runtime(local_spec),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/local/{stage}/{case}/{rep}.log",
    benchmark:
        "benchmarks/workflow/{soil}/dem/local/{stage}/{case}/{rep}.tsv"
    script:
        "../scripts/verify_point.py"


checkpoint refine:
    input:
        stage="results/{soil}/dem/{stage}/stage.json",
        responses="results/{soil}/dem/{stage}/responses.csv",
        targets="results/{soil}/dem/targets.csv",
        optimum=lambda w: optimum_of(w.soil, w.stage),
        runs=stage_verify_runs,
        local=local_files,
        local_runs=stage_local_runs,
    output:
        report("results/{soil}/dem/{stage}/refined.csv", caption="../report/refined.rst", category="{soil}",
               subcategory="dem verification"),
    params:
        # the screening or declared search ranges a second-round set may move into past the
        # Box-Behnken box (the config without its documentation: editing a note re-runs nothing)
        soil=lambda w: dem_context(soil_cfg(w.soil), search_ranges=True),
        half_width=lambda w: local_half_width(w.soil),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/{stage}/refine.log",
    script:
        "../scripts/refine.py"


rule refine_point:
    input:
        refined=lambda w: ancient(refined_of(w.soil, w.stage)),
        kernels=ancient(DEM_KERNELS),
    output:
        "results/{soil}/dem/refine/{stage}/{case}/{rep}.csv",
    params:
        spec=refine_spec,
    threads: lambda w: dem_threads(w.soil)
    resources:
        mem_mb=dem_mem_mb(refine_spec),
        runtime=dem_runtime(refine_spec),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/refine/{stage}/{case}/{rep}.log",
    benchmark:
        "benchmarks/workflow/{soil}/dem/refine/{stage}/{case}/{rep}.tsv"
    script:
        "../scripts/verify_point.py"


checkpoint final_set:
    input:
        stage="results/{soil}/dem/{stage}/stage.json",
        targets="results/{soil}/dem/targets.csv",
        optimum=lambda w: optimum_of(w.soil, w.stage),
        refined=lambda w: refined_of(w.soil, w.stage),
        runs=stage_verify_runs,
        refined_runs=stage_refined_runs,
    output:
        "results/{soil}/dem/{stage}/final.csv",
    params:
        # as the verification rule's: final.csv takes the round verification.csv marks final
        soil=verification_soil,
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/{stage}/final.log",
    script:
        "../scripts/final.py"


rule verification:
    input:
        calibration=calibration_files,
        targets="results/{soil}/dem/targets.csv",
        runs=verify_runs,
        refined=lambda w: list(refined_files(w).values()),
        refined_runs=refined_runs,
        seeds=verify_seed_files,
    output:
        report("results/{soil}/dem/verification.csv", caption="../report/verification.rst", category="{soil}",
               subcategory="dem verification"),
    params:
        soil=verification_soil,
        stages=lambda w: optimised_stages(w.soil),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/verification.log",
    script:
        "../scripts/verification.py"


rule tool_point:
    input:
        optima=tool_optima,
        kernels=ancient(DEM_KERNELS),
    output:
        "results/{soil}/dem/tools/{key}.csv",
    params:
        job=tool_spec,
    threads: lambda w: dem_threads(w.soil)
    resources:
        mem_mb=dem_mem_mb(tool_spec),
        runtime=dem_runtime(tool_spec),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/tools/{key}.log",
    benchmark:
        "benchmarks/workflow/{soil}/dem/tools/{key}.tsv"
    script:
        "../scripts/tool_point.py"


rule tool_verification:
    input:
        runs=tool_runs,
        # the sets the run map (params) is read from
        optima=tool_optima,
    output:
        report("results/{soil}/dem/tool_verification.csv", caption="../report/tools.rst", category="{soil}",
               subcategory="dem tool tests"),
    params:
        soil_path=lambda w: str(SOILS[w.soil].path),
        resources_root=RES,
        runs=after_checkpoints(tool_run_map),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/tool_verification.log",
    script:
        "../scripts/tool_verification.py"


rule calibrated_vs_paper:
    input:
        calibration=lambda w: calibration_files(w, ("stage.json", "optimum.csv", "identifiability.csv")),
        final=lambda w: list(final_files(w).values()),
    output:
        report("results/{soil}/dem/calibrated_vs_paper.csv", caption="../report/calibrated_vs_paper.rst",
               category="{soil}", subcategory="dem verification"),
    params:
        soil=lambda w: without_search_ranges(soil_cfg(w.soil)),
        stages=lambda w: optimised_stages(w.soil),
        set_file=lambda w: set_file(w.soil),
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/dem/calibrated_vs_paper.log",
    script:
        "../scripts/calibrated_vs_paper.py"
