# Configuration, validated before any job runs: the workflow config against its schema, then
# every soil file against the soil schema, its published tables against their designs and its
# simulation block against the DEM scenarios.  Paths and target lists of the calibration chain.
import json
import os
import sys

from soilcal.chain import adaptive, derive, refine, verify
from soilcal.chain.files import read_stage
from soilcal.config import load_workflow_config
from soilcal.errors import InputError
from soilcal.chain.plan import dem_context, soil_sources, without_search_ranges
from soilcal.chain.provenance import setup_inputs


def config_origins():
    """Where each top-level key of the config was given when not in config/config.yaml: the
    --configfile that sets it, or --config on the command line (named in a start-up error)."""
    from soilcal.config import read_yaml

    out = {}
    for f in workflow.overwrite_configfiles:
        for key in read_yaml(f) or {}:
            out[key] = os.path.relpath(f)
    for key in workflow.config_settings.config:
        out[key] = "<command line: --config>"
    return out


try:
    # the config against ../schemas/config.schema.yaml (the package's workflow schema), then every soil;
    # --config design=... (source=...) is every soil's DEM design (source), checked as such
    SOILS = load_workflow_config(config, origins=config_origins())
    SOURCES = {soil: soil_sources(s, config.get("source")) for soil, s in SOILS.items()}
except InputError as e:
    # one line naming file, field and what was expected, status 2 as the soilcal commands; no traceback
    print(f"soilcal: error: {e}", file=sys.stderr)
    sys.exit(2)
# what a soil's user should know though nothing is wrong (measured rows simulated alike), as
# soilcal config check says it
for _soil_id, _soil in SOILS.items():
    for _note in _soil.load_notes:
        print(f"soilcal: note: {_soil.path}: {_note}", file=sys.stderr)
    # a replay asked of a soil that prints no table plans its designs only: say why
    if "published" in SOURCES[_soil_id] and not any(st.get("table") for st in _soil.stages):
        print(f"soilcal: note: {_soil.path}: source published replays the printed tables (stages[].table), and "
              "no stage of this soil has one: only its designs are written; source: dem calibrates it on the DEM",
              file=sys.stderr)
RES = config.get("resources", "resources")
# every soil's photo manifest, read and checked with the soil (soilcal config check does the same)
IMAGE_MANIFESTS = {soil: s.manifest for soil, s in SOILS.items() if s.manifest is not None}

#: the stamp of the Numba kernel cache, written by rule dem_kernels before any DEM job
DEM_KERNELS = "results/cache/dem_kernels.csv"

wildcard_constraints:
    soil="|".join(SOILS),
    source="published|dem",
    stage="[a-z0-9][a-z0-9-]*",
    run=r"\d+",
    rep=r"\d+",
    row=r"\d+",
    case="[A-Za-z0-9_][A-Za-z0-9_.-]*",
    key="[0-9a-f]{12}",
    preset="quick|paper",
    it=r"\d+",

# Light rules (designs, regressions, tables, figures) run on the submitting host when a
# cluster executor sends the DEM jobs away (profiles/slurm); locally this changes nothing.
localrules:
    design, errata, image_measure, targets, optimum, figures, verification_figures, tool_figures,
    summary, regression, published_responses, dem_responses, simulation_setup, printed_comparison, refine, local_design,
    verify_seeds, final_set, verification, tool_verification, calibrated_vs_paper, loop_diagnose, loop_more, loop_select,
    adaptive_step, adaptive_case, adaptive_stage, adaptive_verification, adaptive_figures,


def soil_cfg(soil):
    return SOILS[soil].data


def stage_cfg(soil, stage):
    return SOILS[soil].stage(stage)


def stage_dir(soil, stage, source="published"):
    return f"results/{soil}/{source}/{stage}"


def printed_table(soil, stage):
    st = stage_cfg(soil, stage)
    return None if st.get("table") is None else f"{RES}/published/{soil}/{st['table']}"


def moisture_property(soil):
    """The soil's ``properties.moisture_content`` as the targets table reads it (its values,
    range and unit, :func:`soilcal.config.quantities.soil_moisture`), or nothing."""
    prop = (soil_cfg(soil).get("properties") or {}).get("moisture_content")
    if not isinstance(prop, dict):
        return {}
    return {"moisture_content": {k: prop[k] for k in ("value", "values", "low", "high", "unit") if k in prop}}


def source_stages(soil, source):
    """Stage ids a source runs: every stage with factors of its own (published: a stage leaving
    its factors to the DEM recipe has no design to replay), simulation.stages (dem)."""
    if source == "dem":
        return derive.dem_stage_ids(soil_cfg(soil))
    return [st["id"] for st in SOILS[soil].stages if st["factors"]]


def has_responses(soil, source, stage):
    return source == "dem" or printed_table(soil, stage) is not None


def stage_targets(soil, st, source="published"):
    d = stage_dir(soil, st["id"], source)
    out = [f"{d}/design.csv"]
    if not has_responses(soil, source, st["id"]):
        return out
    out.append(f"{d}/responses.csv")
    if st["kind"] in ("plackett_burman", "box_behnken"):
        out += [f"{d}/{x}.csv" for x in ("anova", "fit", "coefficients", "effects")]
        out += [f"{d}/figures/diagnostics"]
    if st["kind"] == "plackett_burman":
        out += [f"{d}/figures/pareto"]
    if st["kind"] == "box_behnken":
        out += [f"{d}/figures/surfaces"]
        if st.get("optimise"):
            out += [f"{d}/optimum.csv", f"{d}/identifiability.csv"]
    if st["kind"] == "steepest_ascent":
        out += [f"{d}/optimum.csv", f"{d}/figures/steepest"]
    if source == "dem" and derive.design_mode(soil_cfg(soil)) == "printed" and printed_table(soil, st["id"]):
        out.append(f"{d}/printed_comparison.csv")
    return out


def optimised_stages(soil):
    """The optimised stages the DEM source runs (soilcal.chain.derive.optimised_dem_stage_ids)."""
    return derive.optimised_dem_stage_ids(soil_cfg(soil))


def dem_soil_targets(soil):
    d = f"results/{soil}/dem"
    out = [f"{d}/targets.csv", f"{d}/simulation.csv", f"{d}/verification.csv", f"{d}/calibrated_vs_paper.csv",
           f"{d}/figures/verification"] + seed_files(soil) + local_targets(soil)
    if soil_cfg(soil).get("measurements"):
        out += [f"{d}/tool_verification.csv", f"{d}/figures/tools"]
        loop = f"results/{soil}/loop"
        out += [f"{loop}/loop_summary.csv", f"{loop}/report.md", f"{loop}/figures/residuals", f"{loop}/figures/after"]
    return out


def all_targets():
    out = []
    for soil, s in SOILS.items():
        for source in SOURCES[soil]:
            if source == "dem" and adaptive_on(soil):
                out += adaptive_targets(soil)
                continue
            for sid in source_stages(soil, source):
                out += stage_targets(soil, s.stage(sid), source)
        if "published" in SOURCES[soil]:
            out.append(f"results/{soil}/published/errata.csv")
        if "dem" in SOURCES[soil] and not adaptive_on(soil):
            out += dem_soil_targets(soil)
        if soil in IMAGE_MANIFESTS:
            out.append(f"results/{soil}/images/measurements.json")
    if any("dem" in v and not adaptive_on(soil) for soil, v in SOURCES.items()):
        out += ["results/summary.csv", "results/figures/summary"]
    return out


def image_photos(wildcards):
    m = IMAGE_MANIFESTS[wildcards.soil]
    base = f"{RES}/images/{wildcards.soil}"
    return [f"{base}/manifest.yaml"] + [f"{base}/{p['file']}" for p in m["photos"]]


def errata_inputs(wildcards):
    out = []
    for sid in source_stages(wildcards.soil, "published"):
        st = stage_cfg(wildcards.soil, sid)
        out += [f for f in stage_targets(wildcards.soil, st) if f.endswith(".csv")]
        if st.get("table") is not None:
            out.append(f"{stage_dir(wildcards.soil, st['id'])}/design_check.csv")
    return out


# ------------------------------------------------------------------ the DEM source


def sim_cfg(soil):
    return soil_cfg(soil).get("simulation") or {}


def dem_threads(soil):
    return int(sim_cfg(soil).get("threads", 1))


def _job_cost(w, spec_of):
    """soilcal.dem.cost of the DEM job spec_of(w); None for a job that simulates nothing, or
    while the checkpoint its spec reads is still to run (the job is planned again, with its
    size, once the checkpoint has run)."""
    from snakemake.exceptions import IncompleteCheckpointException

    from soilcal.dem.cost import estimate_job

    try:
        spec = spec_of(w)
    except IncompleteCheckpointException:
        return None
    # mem_mb and runtime of one job ask for the same estimate: made once per spec
    key = json.dumps(spec, sort_keys=True, default=str)
    if key not in _JOB_COSTS:
        _JOB_COSTS[key] = estimate_job(spec)
    return _JOB_COSTS[key]


_JOB_COSTS = {}


def dem_mem_mb(spec_of):
    """Resource callable: the soil's simulation.resources.mem_mb, else the job's own need."""

    def mem_mb(w):
        fixed = (sim_cfg(w.soil).get("resources") or {}).get("mem_mb")
        if fixed is not None:
            return int(fixed)
        cost = _job_cost(w, spec_of)
        return cost.mem_mb if cost is not None else 1000

    return mem_mb


def dem_runtime(spec_of):
    """Resource callable: minutes, the soil's simulation.resources.runtime else the job's own
    estimate, times the attempt (a job killed at its limit is retried with more time)."""

    def runtime(w, attempt):
        fixed = (sim_cfg(w.soil).get("resources") or {}).get("runtime")
        if fixed is not None:
            base = int(fixed)
        else:
            cost = _job_cost(w, spec_of)
            base = cost.runtime_min(threads=dem_threads(w.soil)) if cost is not None else 5
        return base * int(attempt)

    return runtime


def stage_priority(soil, stage):
    """1 plus the priorities of the DEM stages derived from this one: the points of a stage
    that later stages wait on run first, so that the cores are not left with one soil's long
    chain at the end."""
    later = [s for s in source_stages(soil, "dem") if stage in derive.dependencies(soil_cfg(soil), s).values()]
    return 1 + sum(stage_priority(soil, s) for s in later)


def dem_priority(w):
    return stage_priority(w.soil, w.stage)


# Every function below that reads a checkpoint's output first asks for the checkpoints that
# output is made after, in the order they run (a stage's design after the designs and sets it is
# derived from, its optimum after its design, refined.csv after the optimum, final.csv after
# refined.csv, the loop's plans after the final sets).  Snakemake puts a pending checkpoint's
# output in place of a job's input and params (a placeholder) and evaluates the job again when
# that checkpoint has run, or when an evaluation names a checkpoint it had not named before and
# that checkpoint has nothing to do.  A checkpoint that has nothing to do once an earlier one has
# run (a forced optimum writes the same optimum.csv: refine and final_set are then up to date) does
# not run, so a job still holding its placeholder is never evaluated again, and one that has to run
# (a target given with -f, or missing) runs on the placeholder.  Asked in order, a job waits on the
# first checkpoint still pending, and each evaluation after it has run names the next one.


def design_of(soil, stage):
    """design.csv of a DEM stage once its checkpoint has run, after the checkpoints of the
    stages it is derived from (derive.dependencies: the DEM stage it follows, the stage whose
    set it fixes)."""
    deps = derive.dependencies(soil_cfg(soil), stage)
    if "from" in deps:
        design_of(soil, deps["from"])
    if "fixed_from" in deps:
        set_of(soil, deps["fixed_from"])
    return checkpoints.design.get(soil=soil, source="dem", stage=stage).output.design


def dem_design(w):
    """The DEM design of a stage, once its checkpoint has run."""
    return design_of(w.soil, w.stage)


_POINTS = {}


def _points(soil, stage):
    """(stage, design points, seeds) of a DEM stage, read once per file version."""
    from soilcal.chain.sources import design_points, point_seeds, seed_stride

    import pandas as pd

    d = stage_dir(soil, stage, "dem")
    key = (soil, stage, os.path.getmtime(f"{d}/design.csv"), os.path.getmtime(f"{d}/stage.json"))
    if key not in _POINTS:
        st = read_stage(f"{d}/stage.json")
        pts = design_points(st, pd.read_csv(f"{d}/design.csv"))
        seeds = point_seeds(pts, int(soil_cfg(soil)["seed"]), seed_stride(soil_cfg(soil)))
        _POINTS[key] = (st, dict(pts), seeds)
    return _POINTS[key]


def dem_runs(w):
    dem_design(w)
    st, pts, _ = _points(w.soil, w.stage)
    return [f"{stage_dir(w.soil, w.stage, 'dem')}/runs/{r}.csv" for r in pts]


def point_spec(w):
    from soilcal.chain.sources import point_spec as spec

    dem_design(w)
    st, pts, seeds = _points(w.soil, w.stage)
    run = int(w.run)
    return spec(SOILS[w.soil], st, pts[run], run, seeds[run])


def stage_inputs(w):
    """What a stage's design is made from: the printed table (published; dem with
    design: printed), and for a derived DEM stage the DEM results it is derived from."""
    out = {}
    table = printed_table(w.soil, w.stage)
    if w.source == "published" or derive.design_mode(soil_cfg(w.soil)) == "printed":
        if table:
            out["table"] = table
    if w.source == "dem":
        out["targets"] = f"results/{w.soil}/dem/targets.csv"
        deps = derive.dependencies(soil_cfg(w.soil), w.stage)
        if "from" in deps:
            d = stage_dir(w.soil, deps["from"], "dem")
            out["from_stage"] = f"{d}/stage.json"
            out["from_responses"] = f"{d}/responses.csv"
            if stage_cfg(w.soil, deps["from"])["kind"] == "plackett_burman":
                out["from_effects"] = f"{d}/effects.csv"
        if "fixed_from" in deps:
            d = stage_dir(w.soil, deps["fixed_from"], "dem")
            out["fixed_stage"] = f"{d}/stage.json"
            # the set the upstream stage ends with (final.csv where the soil runs a second round)
            out["fixed_optimum"] = f"{d}/{set_file(w.soil)}"
    return out


def verify_presets(soil, stage, case):
    """The soil's preset, and `paper` where its verification admits one of the case's responses."""
    presets = [sim_cfg(soil).get("preset", "quick")]
    goals = next(c for c in stage_cfg(soil, stage)["optimise"]["cases"] if c["id"] == case)["goals"]
    if verify.paper_responses(SOILS[soil], list(goals)):
        presets.append("paper")
    return presets


def verify_runs(w):
    reps = verify.first_stage_seeds(soil_cfg(w.soil))
    own = sim_cfg(w.soil).get("preset", "quick")
    counts = {sid: case_seed_counts(w.soil, sid) for sid in optimised_stages(w.soil)}
    out = []
    for sid, case in verify.verification_cases(soil_cfg(w.soil), optimised_stages(w.soil)):
        for preset in verify_presets(w.soil, sid, case):
            n = counts[sid].get(case, reps) if preset == own else reps
            out += [f"results/{w.soil}/dem/verify/{preset}/{sid}/{case}/{k}.csv" for k in range(n)]
    return out


def stage_first_runs(w):
    """The first verification stage's runs of one stage at the soil's own preset
    (``replicates`` seeds per case), from which verify_seeds sizes the second stage."""
    reps = verify.first_stage_seeds(soil_cfg(w.soil))
    preset = sim_cfg(w.soil).get("preset", "quick")
    return [f"results/{w.soil}/dem/verify/{preset}/{w.stage}/{case}/{k}.csv"
            for sid, case in verify.verification_cases(soil_cfg(w.soil), [w.stage]) for k in range(reps)]


def case_seed_counts(soil, stage):
    """Each case's verification seeds at the soil's own preset once the verify_seeds
    checkpoint has sized them (a soil whose max_replicates exceeds its replicates); {} (every
    case its replicates) otherwise."""
    if not verify.two_stage(soil_cfg(soil)):
        return {}
    return verify.case_seeds(_seeds_frame(soil, stage))


def _seeds_frame(soil, stage):
    """verify_seeds.csv of a stage, read once per file version (as _calibration reads a set)."""
    import pandas as pd

    path = verify_seeds_of(soil, stage)
    key = (path, os.path.getmtime(path))
    if key not in _SEED_FRAMES:
        _SEED_FRAMES[key] = pd.read_csv(path)
    return _SEED_FRAMES[key]


_SEED_FRAMES = {}


def verify_seeds_of(soil, stage):
    """verify_seeds.csv of a stage once that checkpoint has run (after its optimum)."""
    optimum_file(soil, stage)
    return checkpoints.verify_seeds.get(soil=soil, stage=stage).output[0]


def stage_verify_runs(w):
    """The first round's verification runs of one stage at the soil's own preset (what the
    second round corrects from): both stages of it where the soil runs two."""
    reps = verify.first_stage_seeds(soil_cfg(w.soil))
    preset = sim_cfg(w.soil).get("preset", "quick")
    counts = case_seed_counts(w.soil, w.stage)
    return [f"results/{w.soil}/dem/verify/{preset}/{w.stage}/{case}/{k}.csv"
            for sid, case in verify.verification_cases(soil_cfg(w.soil), [w.stage])
            for k in range(counts.get(case, reps))]


def seed_files(soil):
    """verify_seeds.csv of every optimised stage where the soil runs a second verification
    stage, else none.  They are targets of the run (dem_soil_targets): a job whose input only
    a checkpoint's result names (the verification's seeds) keeps its output until the
    checkpoint has run, and Snakemake runs a checkpoint that no target asks for only for a job
    that must run anyway, so a soil that turns the second stage on after a finished run would
    otherwise get nothing."""
    if not verify.two_stage(soil_cfg(soil)):
        return []
    return [f"results/{soil}/dem/{s}/verify_seeds.csv" for s in optimised_stages(soil)]


def verify_seed_files(w):
    """The soil's verify_seeds.csv files (seed_files), which the verification notes."""
    return seed_files(w.soil)


def refine_on(soil):
    return refine.refine_settings(soil_cfg(soil))


def refined_of(soil, stage):
    """refined.csv of a stage once the refine checkpoint has run (after its optimum, and after
    its local design where the soil runs one)."""
    optimum_file(soil, stage)
    if local_half_width(soil) is not None:
        local_of(soil, stage)
    return checkpoints.refine.get(soil=soil, stage=stage).output[0]


def refined_files(w):
    return {s: refined_of(w.soil, s) for s in optimised_stages(w.soil)} if refine_on(w.soil) else {}


def final_of(soil, stage):
    """final.csv of a stage once the final_set checkpoint has run (after refined.csv)."""
    refined_of(soil, stage)
    return checkpoints.final_set.get(soil=soil, stage=stage).output[0]


def final_files(w):
    return {s: final_of(w.soil, s) for s in optimised_stages(w.soil)} if refine_on(w.soil) else {}


def _stage_refined_runs(soil, stage):
    """The second round's runs of one stage: its refined cases at their bias-corrected sets,
    each with as many seeds as its first round ended with."""
    reps = verify.first_stage_seeds(soil_cfg(soil))
    _, ref = _calibration(soil, stage, refined=True)
    counts = case_seed_counts(soil, stage)
    return [f"results/{soil}/dem/refine/{stage}/{case}/{k}.csv"
            for case in refine.refined_cases(ref) for k in range(counts.get(case, reps))]


def stage_refined_runs(w):
    """The second round's runs of one stage."""
    return _stage_refined_runs(w.soil, w.stage)


def refined_runs(w):
    """Second-round runs: the refined cases of every stage at their bias-corrected sets."""
    if not refine_on(w.soil):
        return []
    return [p for sid in optimised_stages(w.soil) for p in _stage_refined_runs(w.soil, sid)]


def verification_soil(w):
    """The soil config the verification and final.csv judge a round by (without its
    documentation: editing a note re-runs nothing); ``citation``: whether the soil has a paper
    whose targets and verification to set beside."""
    return dict(dem_context(soil_cfg(w.soil), verification=True), citation=bool(soil_cfg(w.soil).get("citation")))


def local_half_width(soil):
    """The local design's half-width (soilcal.chain.local.half_width), or None: no local design."""
    from soilcal.chain.local import half_width

    return half_width(soil_cfg(soil))


def local_of(soil, stage):
    """local.csv of a stage once the local_design checkpoint has run (after its optimum and the
    first round's seed counts, verify_seeds, where the soil sizes them)."""
    optimum_file(soil, stage)
    case_seed_counts(soil, stage)
    return checkpoints.local_design.get(soil=soil, stage=stage).output[0]


def local_targets(soil):
    """local.csv of every optimised stage where the soil runs local designs: targets of the run
    (dem_soil_targets), as verify_seeds.csv (seed_files), so that a finished run that turns the
    local design on plans it (refine names it only through the checkpoint)."""
    if "dem" not in SOURCES[soil] or derive.design_mode(soil_cfg(soil)) == "adaptive" or local_half_width(soil) is None:
        return []
    return [f"results/{soil}/dem/{s}/local.csv" for s in optimised_stages(soil)]


def local_files(w):
    return [local_of(w.soil, w.stage)] if local_half_width(w.soil) is not None else []


_LOCAL_POINTS = {}


def _local_points(soil, stage):
    """local.csv of a stage, read once per file version."""
    import pandas as pd

    path = local_of(soil, stage)
    stamp = (path, os.path.getmtime(path))
    if stamp not in _LOCAL_POINTS:
        _LOCAL_POINTS[stamp] = pd.read_csv(path)
    return _LOCAL_POINTS[stamp]


def stage_local_runs(w):
    """The runs of a stage's local designs (none where the soil runs no local design)."""
    if local_half_width(w.soil) is None:
        return []
    df = _local_points(w.soil, w.stage)
    return [f"results/{w.soil}/dem/local/{w.stage}/{c}/{int(p)}.csv" for c, p in zip(df["case"], df["point"])]


def local_spec(w):
    """One local point's job: its levels as the case's set, each response's seeds per design
    point, after every verification and second-round seed (soilcal.chain.local.point_seed)."""
    from soilcal.chain.local import point_optimum, point_seed

    st, opt = _calibration(w.soil, w.stage)
    one = point_optimum(opt, _local_points(w.soil, w.stage), w.case, int(w.rep))
    return verify.verification_point(SOILS[w.soil], st, one, w.case, point_seed(soil_cfg(w.soil), int(w.rep)),
                                     design_seeds=True)


def refine_spec(w):
    st, ref = _calibration(w.soil, w.stage, refined=True)
    # after every seed the first round may take (both its stages), so that no seed repeats; a
    # seed past the first stage's runs, as in the first round, only the responses its second
    # stage ran (the ones the first seeds left undecided)
    return verify.verification_point(SOILS[w.soil], st, ref, w.case, verify.most_seeds(soil_cfg(w.soil)) + int(w.rep),
                                     responses=second_stage_responses(w.soil, w.stage, w.case, int(w.rep),
                                                                      sim_cfg(w.soil).get("preset", "quick")))


_CALIBRATED = {}


def _calibration(soil, stage, final=False, refined=False):
    """(stage, optimum) of a DEM stage once its optimum checkpoint has run, read once per file
    version; with ``final`` the set the soil ends with (final.csv, the better verified round,
    where the soil runs the second round); with ``refined`` the second round's sets
    (refined.csv, what its runs simulate)."""
    import pandas as pd

    if refined and refine_on(soil):
        opt = refined_of(soil, stage)
    elif final and refine_on(soil):
        opt = final_of(soil, stage)
    else:
        opt = optimum_file(soil, stage)
    d = stage_dir(soil, stage, "dem")
    key = (soil, stage, opt, os.path.getmtime(opt), os.path.getmtime(f"{d}/stage.json"))
    if key not in _CALIBRATED:
        _CALIBRATED[key] = (read_stage(f"{d}/stage.json"), pd.read_csv(opt))
    return _CALIBRATED[key]


def optimum_file(soil, stage):
    """optimum.csv of a DEM stage once its optimum checkpoint has run (after its design)."""
    design_of(soil, stage)
    return checkpoints.optimum.get(soil=soil, source="dem", stage=stage).output.optimum


def optimum_of(soil, stage):
    return ancient(optimum_file(soil, stage))


def verify_spec(w):
    st, opt = _calibration(w.soil, w.stage)
    spec = verify.verification_point(SOILS[w.soil], st, opt, w.case, int(w.rep), w.preset,
                                     second_stage_responses(w.soil, w.stage, w.case, int(w.rep), w.preset))
    same = _same_case(w)
    return dict(spec, same_as=same) if same else spec


def second_stage_responses(soil, stage, case, rep, preset):
    """The responses a second-stage verification seed runs (verify.second_stage_responses:
    the ones the first seeds left undecided); None (all) for a first-stage seed, another
    preset, or a soil without a second stage. Only a seed past the first stage reads the
    verify_seeds checkpoint, whose job it follows."""
    if (not verify.two_stage(soil_cfg(soil)) or rep < verify.first_stage_seeds(soil_cfg(soil))
            or preset != sim_cfg(soil).get("preset", "quick")):
        return None
    return verify.second_stage_responses(_seeds_frame(soil, stage), case)


def _same_case(w):
    """The earlier case of the stage whose verification job of this seed and preset simulates
    the same (verify.same_as), or None; the stage's specs are built once per seed and preset
    (its params and its input ask for it)."""
    st, opt = _calibration(w.soil, w.stage)
    key = (w.soil, w.stage, int(w.rep), w.preset, id(st), id(opt))
    if key not in _SAME_SPECS:
        _SAME_SPECS[key] = {c: verify.verification_point(
            SOILS[w.soil], st, opt, c, int(w.rep), w.preset,
            second_stage_responses(w.soil, w.stage, c, int(w.rep), w.preset))
            for s, c in verify.verification_cases(soil_cfg(w.soil), [w.stage])}
    return verify.same_as(_SAME_SPECS[key], w.case)


_SAME_SPECS = {}


def verify_same_input(w):
    """The rows a verification job copies (verify.same_as), as its input; none otherwise."""
    same = _same_case(w)
    return [f"results/{w.soil}/dem/verify/{w.preset}/{w.stage}/{same}/{w.rep}.csv"] if same else []


def tool_jobs(soil):
    """The soil's measured conditions as DEM jobs, keyed by what they simulate
    (verify.tool_key): conditions that need the same runs share one job.  Returns
    ({key: job}, {(measurement, row): key})."""
    cals = {s: _calibration(soil, s, final=True) for s in sorted({c.stage for c in conditions(soil)})}
    stamp = (soil,) + tuple(id(v) for v in cals.values())
    if stamp not in _TOOL_JOBS:
        jobs, keys = {}, {}
        for c in conditions(soil):
            job = verify.tool_point(SOILS[soil], c, *cals[c.stage])
            key = verify.tool_key(job)
            keys[(c.measurement, c.row)] = key
            jobs[key] = verify.merge_tool_jobs(jobs[key], job) if key in jobs else job
        _TOOL_JOBS[stamp] = (jobs, keys)
    return _TOOL_JOBS[stamp]


_TOOL_JOBS = {}


def tool_spec(w):
    return tool_jobs(w.soil)[0][w.key]


def set_of(soil, stage):
    """The file holding the set a stage ends with (final.csv where the soil runs the second
    round, else optimum.csv), once its checkpoint has run."""
    return final_of(soil, stage) if refine_on(soil) else optimum_file(soil, stage)


def tool_sets(soil):
    """The sets the measured conditions are simulated at: one file per stage they name."""
    return [set_of(soil, s) for s in sorted({c.stage for c in conditions(soil)})]


def tool_optima(w):
    return [ancient(f) for f in tool_sets(w.soil)]


def set_file(soil):
    """The file of a stage holding the set the soil ends with."""
    return refine.set_file(soil_cfg(soil))


def calibration_files(w, names=("stage.json", "optimum.csv")):
    return [f"{stage_dir(w.soil, s, 'dem')}/{n}" for s in optimised_stages(w.soil) for n in names]


_CONDITIONS = {}


def conditions(soil):
    from soilcal.config.measurements import conditions as conds

    if soil not in _CONDITIONS:
        _CONDITIONS[soil] = conds(SOILS[soil])
    return _CONDITIONS[soil]


def tool_runs(w):
    return [f"results/{w.soil}/dem/tools/{k}.csv" for k in dict.fromkeys(tool_jobs(w.soil)[1].values())]


def after_checkpoints(fn):
    """A params function read through checkpoints, whose value waits for them as Snakemake's
    own placeholder (<TBD>) does for a checkpoint among a rule's inputs.  On a run over earlier
    results (a soil edited, a run resumed), Snakemake may count a checkpoint whose old output is
    on disk as done while it evaluates a job's params but not while it evaluated the inputs;
    the params then reach a later checkpoint than the inputs name, and Snakemake stops the whole
    run.  The job, whose inputs still point at a checkpoint, is evaluated again when that
    checkpoint finishes, before it can run."""
    from snakemake.common.tbdstring import TBDString
    from snakemake.exceptions import IncompleteCheckpointException

    def params(w):
        try:
            return fn(w)
        except IncompleteCheckpointException:
            return TBDString()

    params.__name__ = fn.__name__
    return params


def tool_run_map(w):
    return {f"{m}/{r}": k for (m, r), k in tool_jobs(w.soil)[1].items()}


def tool_file_map(w):
    """The calibrated runs of every measured condition: {"<measurement>/<row>": tool run file}."""
    return {f"{m}/{r}": f"results/{w.soil}/dem/tools/{k}.csv" for (m, r), k in tool_jobs(w.soil)[1].items()}


# ------------------------------------------------------------------ the measured-data loop


def loop_plan_file(soil):
    """plan.json once loop_diagnose has run (after the final sets its tool runs simulate)."""
    tool_sets(soil)
    return checkpoints.loop_diagnose.get(soil=soil).output.plan


def loop_more_file(soil):
    """plan_more.json once loop_more has run (after the first plan)."""
    loop_plan_file(soil)
    return checkpoints.loop_more.get(soil=soil).output[0]


_LOOP = {}


def _loop_round(soil, plan_path):
    """({key: job}, {effect: {point: {condition: run file}}}) of one round's plan
    (soilcal.loop.files.loop_jobs), read once per file version."""
    from soilcal.loop.files import loop_jobs

    jobs, keys = tool_jobs(soil)
    stamp = (soil, plan_path, os.path.getmtime(plan_path), id(jobs))
    if stamp not in _LOOP:
        with open(plan_path) as fh:
            plan = json.load(fh)
        _LOOP[stamp] = loop_jobs(conditions(soil), jobs, keys, plan, f"results/{soil}")
    return _LOOP[stamp]


def loop_spec(w):
    """A loop job of the first round, else of the second (whose plan exists by then)."""
    jobs = _loop_round(w.soil, loop_plan_file(w.soil))[0]
    if w.key in jobs:
        return jobs[w.key]
    return _loop_round(w.soil, loop_more_file(w.soil))[0][w.key]


def _run_files(files):
    return [p for per in files.values() for keyed in per.values() for p in keyed.values()]


def loop_first_files(w):
    return _loop_round(w.soil, loop_plan_file(w.soil))[1]


def loop_effect_files(w):
    files = dict(loop_first_files(w))
    files.update(_loop_round(w.soil, loop_more_file(w.soil))[1])
    return files


def loop_first_runs(w):
    return list(dict.fromkeys(list(tool_file_map(w).values()) + _run_files(loop_first_files(w))))


def loop_runs(w):
    return list(dict.fromkeys(list(tool_file_map(w).values()) + _run_files(loop_effect_files(w))))


# ------------------------------------------------------------------ the adaptive design


def adaptive_on(soil):
    return "dem" in SOURCES[soil] and derive.design_mode(soil_cfg(soil)) == "adaptive"


def adaptive_stages(soil):
    """The optimised DEM stages with at least one case whose goals are all targets."""
    return [s for s in optimised_stages(soil) if adaptive.adaptive_cases(soil_cfg(soil), [s])]


def adaptive_case_ids(soil, stage):
    return [c for _, c in adaptive.adaptive_cases(soil_cfg(soil), [stage])]


def adaptive_dir(soil, stage, case=None):
    d = f"results/{soil}/dem/adaptive/{stage}"
    return f"{d}/{case}" if case else d


def adaptive_targets(soil):
    out = [f"results/{soil}/dem/targets.csv", f"results/{soil}/dem/simulation.csv",
           f"results/{soil}/dem/adaptive/verification.csv",
           f"results/{soil}/dem/adaptive/summary.csv", f"results/{soil}/dem/adaptive/figures"]
    for sid in adaptive_stages(soil):
        out += [f"{adaptive_dir(soil, sid)}/{n}" for n in ("stage.json", "optimum.csv", "identifiability.csv")]
    return out


def adaptive_upstream(soil, stage):
    """The stage whose adaptive set a stage fixes (fixed_from), or None."""
    data = dict(soil_cfg(soil), simulation=dict(sim_cfg(soil), design="printed"))
    return derive.dependencies(data, stage).get("fixed_from")


def _step_file(soil, stage, case, it):
    return checkpoints.adaptive_step.get(soil=soil, stage=stage, case=case, it=str(it)).output[0]


def adaptive_step_file(soil, stage, case, it):
    """step/<it>.json of a case once its checkpoint has run, after the checkpoints it is
    decided from (adaptive_history)."""
    adaptive_history(soil, stage, case, it)
    return _step_file(soil, stage, case, it)


_STEP_RECORDS = {}


def _step_record(path):
    key = (path, os.path.getmtime(path))
    if key not in _STEP_RECORDS:
        with open(path) as fh:
            _STEP_RECORDS[key] = json.load(fh)
    return _STEP_RECORDS[key]


def adaptive_history(soil, stage, case, upto=None):
    """(iteration records, run files) of the iterations before ``upto``, or of the whole design
    (until an iteration stops it) when ``upto`` is None; each record is a checkpoint, asked for
    after those it is decided from: the upstream stage's whole designs (adaptive_upstream) and
    the iterations before it of the cases sharing its runs."""
    up = adaptive_upstream(soil, stage)
    if up:
        for c in adaptive_case_ids(soil, up):
            adaptive_history(soil, up, c)
    # the next iteration of each sibling case to ask for (None once its design has stopped)
    sibs = dict.fromkeys(adaptive.sibling_cases(soil_cfg(soil), stage, case), 0)
    steps, runs = [], []
    it = 0
    while True:
        # the siblings' iterations before this one (also before the iteration ``upto`` the caller asks for)
        for c, k in sibs.items():
            if k is not None and k < it:
                sibs[c] = k + 1 if _step_record(_step_file(soil, stage, c, k))["status"] == "continue" else None
        if upto is not None and it >= upto:
            break
        p = _step_file(soil, stage, case, it)
        rec = _step_record(p)
        steps.append(p)
        runs += [f"{adaptive_dir(soil, stage, case)}/runs/{it}/{k}.csv" for k in range(len(rec["runs"]))]
        if rec["status"] != "continue":
            break
        it += 1
    return steps, runs


def _adaptive_common(soil, stage):
    out = {"targets": f"results/{soil}/dem/targets.csv"}
    up = adaptive_upstream(soil, stage)
    if up:
        out["upstream"] = f"{adaptive_dir(soil, up)}/optimum.csv"
    return out


def adaptive_step_inputs(w):
    """The case's own earlier iterations and, where the stage's cases share their runs, the
    sibling cases' iterations before this one (every case decides iteration k from all runs of
    the iterations before k)."""
    steps, runs = adaptive_history(w.soil, w.stage, w.case, int(w.it))
    shared_steps, shared_runs = [], []
    for c in adaptive.sibling_cases(soil_cfg(w.soil), w.stage, w.case):
        st, rn = adaptive_history(w.soil, w.stage, c, int(w.it))
        shared_steps += st
        shared_runs += rn
    return dict(_adaptive_common(w.soil, w.stage), steps=steps, runs=runs, shared_steps=shared_steps,
                shared_runs=shared_runs)


def adaptive_case_inputs(w):
    steps, runs = adaptive_history(w.soil, w.stage, w.case)
    return dict(_adaptive_common(w.soil, w.stage), steps=steps, runs=runs)


def adaptive_stage_inputs(w):
    cases = adaptive_case_ids(w.soil, w.stage)
    out = {k: v for k, v in _adaptive_common(w.soil, w.stage).items() if k == "upstream"}
    out["results"] = [f"{adaptive_dir(w.soil, w.stage, c)}/result.json" for c in cases]
    out["regions"] = [f"{adaptive_dir(w.soil, w.stage, c)}/region.csv" for c in cases]
    return out


def adaptive_verification_inputs(w):
    out = {"targets": f"results/{w.soil}/dem/targets.csv", "stages": [], "results": [], "verification_runs": []}
    for sid in adaptive_stages(w.soil):
        out["stages"] += [f"{adaptive_dir(w.soil, sid)}/{n}" for n in ("stage.json", "optimum.csv")]
        for c in adaptive_case_ids(w.soil, sid):
            out["results"].append(f"{adaptive_dir(w.soil, sid, c)}/result.json")
            out["verification_runs"].append(f"{adaptive_dir(w.soil, sid, c)}/verification_runs.csv")
    return out


def adaptive_spec(w):
    """The DEM job of run ``run`` of iteration ``it`` (the iteration's record is its params)."""
    import pandas as pd

    rec = _step_record(adaptive_step_file(w.soil, w.stage, w.case, int(w.it)))
    up = adaptive_upstream(w.soil, w.stage)
    opt = pd.read_csv(f"{adaptive_dir(w.soil, up)}/optimum.csv") if up else None
    st = adaptive.stage_for(soil_cfg(w.soil), w.stage, opt)
    return adaptive.point_spec(SOILS[w.soil], st, w.case, rec, int(w.run))
