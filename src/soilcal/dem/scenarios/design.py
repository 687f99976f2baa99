"""A soil's design points as DEM runs: which scenario measures which response.

A soil config's ``simulation`` block names, for each response of its design stages, the
physical test that measures it, the scenario setup (a named setup of the scenario with
optional ``set`` overrides, e.g. another tube diameter), the scenario response that is the
measured value, and DEM parameters the paper's printed values do not give (or give with a
unit slip the config documents)::

    simulation:
      preset: quick          # quick (default) or paper
      replicates: 1          # seeds per design point, responses averaged (base.run_replicates)
      params: {soil_density: 1757.567}
      responses:               # a response's own replicates: more seeds for a cheap, noisy one
        static_angle: {scenario: repose, setup: xinjiang-vineyard-100mm, measure: angle_deg, replicates: 4}
        dynamic_angle: {scenario: drum, setup: xinjiang-vineyard, measure: angle_avalanche_deg}

The DEM parameters of one design point are, in increasing precedence: the defaults of
:class:`~soilcal.dem.scenarios.base.DemParams`, the soil's printed properties, the block's
``params``, the stage's ``fixed`` values and the design row's factor levels (so a factor
always wins; :func:`design_params`).

:func:`design_levels` gives every run of a stage in actual units: the printed table when the
paper prints one (coded tables decoded), otherwise the design generated from the stage's
factor levels (:mod:`soilcal.doe`: Plackett-Burman or Box-Behnken columns in the order of
the config's factors, or the steepest-ascent path of ``levels``).  A Plackett-Burman design
of N runs has N - 1 columns, so a stage's ``runs`` fixes N (a 12-run screening of 7
factors); a printed or generated design whose row count differs from ``runs`` is refused.

:func:`design_seeds` gives the benchmarks' seeds (``benchmarks/design_budget.py``): every
design point with the soil's ``seed`` (common random numbers: the same packing draw at every
point, so differences between points are not seed noise), except that a repeated point (a
Box-Behnken centre point, a row equal to an earlier one) takes the next seed at each
repetition: identical runs of a deterministic engine would give a pure error of zero and void
the lack-of-fit test.  ``replicates`` adds the seeds that follow a point's seed.  The
calibration workflow draws an independent packing per point instead
(:func:`soilcal.chain.sources.point_seeds`, where the reason is given).

The rest of the block (``design``, ``stages``, ``screening``, ``path``, ``verification``,
``threads``, ``resources``) steers the calibration workflow (:mod:`soilcal.chain`) and is
checked here at start-up (:func:`check_block`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from soilcal.errors import InputError

BLOCK = "simulation"


@dataclass(frozen=True)
class SimulationSpec:
    """How one response of a soil is simulated (validated)."""

    response: str
    scenario: str
    setup: dict
    measure: str
    preset: str = "quick"
    replicates: int = 1
    params: dict = field(default_factory=dict)


def _block(soil_path, data: dict) -> dict:
    sim = data.get(BLOCK)
    if not sim:
        raise InputError(soil_path, BLOCK, "a simulation block naming the scenario of each response", None)
    return sim


def _renamed(exc: InputError, soil_path, prefix: str, field_prefix: str) -> InputError:
    """``exc`` reported against the soil file, its field ``<prefix>X`` renamed to
    ``<field_prefix>X`` (the config key the user wrote)."""
    fld = exc.field[len(prefix):] if exc.field.startswith(prefix) else exc.field
    return InputError(soil_path, field_prefix + fld, exc.expected, exc.got)


def response_ids(data: dict) -> list[str]:
    """Response ids of all stages of a soil, in config order."""
    out = []
    for st in data["stages"]:
        for r in st["responses"]:
            if r["id"] not in out:
                out.append(r["id"])
    return out


def spec_from(soil_path, data: dict, response_id: str) -> SimulationSpec:
    """The validated :class:`SimulationSpec` of one response; errors name the config field."""
    from soilcal.dem.scenarios import SCENARIOS, measures_of
    from soilcal.chain.provenance import property_base
    from soilcal.dem.scenarios.base import PRESETS, DemParams, merge_setup

    sim = _block(soil_path, data)
    where = f"{BLOCK}.responses.{response_id}"
    entry = (sim.get("responses") or {}).get(response_id)
    if entry is None:
        raise InputError(soil_path, f"{BLOCK}.responses", "an entry for the response " + repr(response_id),
                         sorted(sim.get("responses") or {}))
    name = entry["scenario"]
    if name not in SCENARIOS:
        raise InputError(soil_path, f"{where}.scenario", f"one of {', '.join(sorted(SCENARIOS))}", name)
    mod = SCENARIOS[name]
    setups = mod.setups()
    sname = entry["setup"]
    if sname not in setups:
        raise InputError(soil_path, f"{where}.setup", f"a setup of {name} ({', '.join(setups)})", sname)
    try:
        setup = merge_setup(setups, sname, dict(entry.get("set") or {}), str(soil_path))
    except InputError as exc:
        raise _renamed(exc, soil_path, "setup.", f"{where}.set.") from None
    allowed = measures_of(mod, setup)
    if entry["measure"] not in allowed:
        raise InputError(soil_path, f"{where}.measure",
                         f"a measured response of {name} with this setup ({', '.join(allowed)})",
                         entry["measure"])
    preset = sim.get("preset", "quick")
    if preset not in PRESETS:  # the schema already refuses this; kept for direct callers
        raise InputError(soil_path, f"{BLOCK}.preset", f"one of {', '.join(PRESETS)}", preset)
    params = dict(sim.get("params") or {})
    base = property_base(soil_path, data)  # the printed properties under the params, as the runs take them
    try:
        dem_params = DemParams.from_mapping(params, str(soil_path), base=base)
    except InputError as exc:
        raise _renamed(exc, soil_path, "params.", f"{BLOCK}.params.") from None
    try:
        mod.validate(setup, preset, str(soil_path), params=dem_params)
    except InputError as exc:
        raise _renamed(exc, soil_path, "setup.", f"{where}.set.") from None
    return SimulationSpec(response=response_id, scenario=name, setup=setup, measure=entry["measure"],
                          preset=preset, replicates=int(entry.get("replicates", sim.get("replicates", 1))),
                          params=params)


def check_block(soil_path, data: dict) -> None:
    """Start-up check of a soil's ``simulation`` block (called by the config loader): every
    response mapped to a scenario it can be measured with, every stage the DEM source runs
    (``stages``) known and simulable - its levels given, or derived from an earlier DEM stage
    (:mod:`soilcal.chain.derive`) - and every response of those stages simulated; the
    ``screening`` block consistent (min_factors <= max_factors, and no more than the factors of
    a Plackett-Burman screening a steepest-ascent path selects from); the chain's own checks of
    those stages follow (:func:`soilcal.chain.derive.check_dem_stages`: derivable kinds, every
    factor and fixed value a DEM parameter, Plackett-Burman runs), and every soil parameter of
    their runs set by the soil (:func:`soilcal.chain.provenance.check_parameters`)."""
    sim = data.get(BLOCK)
    if not sim:
        return
    from soilcal.config.measurements import unit_of

    rids = response_ids(data)
    for rid in sim.get("responses") or {}:
        if rid not in rids:
            raise InputError(soil_path, f"{BLOCK}.responses.{rid}",
                             "a response id of a stage (" + ", ".join(rids) + ")", rid)
        measure = spec_from(soil_path, data, rid).measure
        # the DEM gives the measure in the unit its name ends in; the stage's response (and so
        # its target) must be in that unit, or the calibration aims at a number in another one
        want = unit_of(measure)
        for i, st in enumerate(data["stages"]):
            for j, r in enumerate(st["responses"]):
                if r["id"] == rid and str(r["unit"]).strip() != want:  # as the targets' units are compared
                    raise InputError(soil_path, f"stages[{i}].responses[{j}].unit",
                                     f"{want}, the unit of {BLOCK}.responses.{rid}.measure {measure!r} (from its "
                                     "name), which the DEM runs give", r["unit"])
    for i, rid in enumerate((sim.get("verification") or {}).get("paper") or []):
        if rid not in (sim.get("responses") or {}):
            raise InputError(soil_path, f"{BLOCK}.verification.paper[{i}]",
                             "a response of simulation.responses (" + ", ".join(sim.get("responses") or {}) + ")", rid)
    ids = [s["id"] for s in data["stages"]]
    for i, sid in enumerate(sim.get("stages") or []):
        if sid not in ids:
            raise InputError(soil_path, f"{BLOCK}.stages[{i}]", "a stage id (" + ", ".join(ids) + ")", sid)
    from soilcal.chain import adaptive
    from soilcal.chain.derive import (check_dem_stages, check_own_factors, dependencies, design_mode, runs_own_levels,
                                      simulated_stage_ids)
    from soilcal.doe.designs import BBD_MIN_FACTORS

    min_factors = _check_screening(soil_path, sim)
    for sid in simulated_stage_ids(data):
        st = next(s for s in data["stages"] if s["id"] == sid)
        for r in st["responses"]:
            if r["id"] not in (sim.get("responses") or {}):
                raise InputError(soil_path, f"{BLOCK}.responses",
                                 f"an entry for the response {r['id']!r} of stage {sid!r} (or leave the stage out "
                                 f"of {BLOCK}.stages)", sorted(sim.get("responses") or {}))
        deps = dependencies(data, sid)
        check_own_factors(soil_path, data, sid)
        if "from" in deps:
            if st["kind"] == "steepest_ascent" and not _has_target(data, [r["id"] for r in st["responses"]]):
                raise InputError(soil_path, f"stages.{sid}.responses",
                                 "a target with a value or a photo group (image) for at least one response (a target id "
                                 "equal to the response id, or an optimisation case aiming at it) to lay the "
                                 "steepest-ascent path towards",
                                 [r["id"] for r in st["responses"]])
            up = next(s for s in data["stages"] if s["id"] == deps["from"])
            top = dependencies(data, up["id"]).get("from")
            if st["kind"] == "box_behnken" and up["kind"] == "steepest_ascent":
                # the path's factors are the Box-Behnken design's, which needs BBD_MIN_FACTORS
                if top is not None and min_factors < BBD_MIN_FACTORS:
                    # the path takes as few as min_factors from the screening (those found
                    # significant, when fewer are)
                    raise InputError(soil_path, f"{BLOCK}.screening.min_factors",
                                     f"at least {BBD_MIN_FACTORS}: the factors path {up['id']!r} takes from the "
                                     f"screening are those of Box-Behnken stage {sid!r}, which needs at least "
                                     f"{BBD_MIN_FACTORS}", min_factors)
                if top is None and len(up["factors"]) < BBD_MIN_FACTORS:
                    # the path runs on its own levels: its factors are the design's
                    raise InputError(soil_path, f"stages.{up['id']}.factors",
                                     f"at least {BBD_MIN_FACTORS} factors: Box-Behnken stage {sid!r} is derived "
                                     f"from this path on its factors (or give the Box-Behnken stage its levels "
                                     f"with simulation.design: printed)",
                                     f"{len(up['factors'])} ({', '.join(up['factors'])})")
            if st["kind"] == "steepest_ascent" and up["kind"] == "plackett_burman" and min_factors > len(up["factors"]):
                given = "min_factors" in (sim.get("screening") or {})
                raise InputError(soil_path, f"{BLOCK}.screening.min_factors",
                                 f"an integer <= {len(up['factors'])}, the factor count of screening stage "
                                 f"{up['id']!r} whose factors stage {sid!r} selects from"
                                 + ("" if given else " (min_factors is left at its default)"), min_factors)
            continue
        if design_mode(data) == "printed" and st.get("table"):
            continue
        for sym, f in st["factors"].items():
            where = f"stages.{sid}.factors.{sym}"
            if st["kind"] == "steepest_ascent" and not f.get("levels"):
                raise InputError(soil_path, f"{where}.levels",
                                 f"the level of every step to simulate the stage (or leave {sid!r} out of "
                                 f"{BLOCK}.stages)", None)
            if st["kind"] != "steepest_ascent" and (f.get("low") is None or f.get("high") is None) \
                    and not (design_mode(data) == "adaptive"
                             and adaptive.adaptive_range(data, sid, f.get("parameter")) is not None):
                # a range declared under simulation.search_ranges does not count: the adaptive
                # design does not use it (soilcal.chain.adaptive.adaptive_range)
                how = (f"simulation.adaptive.ranges: screening, with a screening stage {sid!r} descends from that "
                       "varies the parameter" if design_mode(data) == "adaptive"
                       else f"leave {sid!r} out of {BLOCK}.stages")
                raise InputError(soil_path, where, f"low and high levels to simulate the stage (or {how})", f)
        if st["kind"] == "steepest_ascent" and runs_own_levels(data, sid):
            path_steps(soil_path, f"stages.{sid}", st)  # the design job's rows, one per step
    check_dem_stages(soil_path, data)
    from soilcal.chain.provenance import check_parameters

    check_parameters(soil_path, data)


def _check_screening(soil_path, sim: dict) -> int:
    """``simulation.screening``: min_factors <= max_factors (either left at its default); returns
    min_factors (:data:`soilcal.chain.derive.SCREENING_DEFAULTS`)."""
    from soilcal.chain.derive import SCREENING_DEFAULTS

    scr = sim.get("screening") or {}
    lo, hi = scr.get("min_factors", SCREENING_DEFAULTS["min_factors"]), scr.get("max_factors")
    for key in ("min_factors", "max_factors"):  # the schema says so; kept for direct callers
        v = scr.get(key)
        if v is not None and (isinstance(v, bool) or not isinstance(v, int) or v < 1):
            raise InputError(soil_path, f"{BLOCK}.screening.{key}", "an integer >= 1", v)
    if hi is not None and lo > hi:
        if "min_factors" in scr:
            raise InputError(soil_path, f"{BLOCK}.screening.min_factors",
                             f"an integer <= {BLOCK}.screening.max_factors ({hi})", lo)
        raise InputError(soil_path, f"{BLOCK}.screening.max_factors",
                         f"an integer >= min_factors ({lo}, its default: what a Box-Behnken design needs)", hi)
    return lo


def _has_target(data: dict, rids) -> bool:
    """Whether a path over responses ``rids`` has a value to aim at once the photos are measured
    (:func:`soilcal.chain.derive.response_targets`): a response's own target, or a target an
    optimisation case aims it at, with a ``value`` or a photo group (``image``), or a case's
    own goal ``value``.  A target listed without either gives the path no direction."""
    from soilcal.chain.targets import goal_has_value, target_has_value

    if any(target_has_value(data, r) for r in rids):
        return True
    for st in data["stages"]:
        for case in (st.get("optimise") or {}).get("cases", []):
            for r in rids:
                g = case["goals"].get(r) or {}
                if g.get("goal") == "target" and goal_has_value(data, g):
                    return True
    return False


def path_steps(soil_path, where: str, stage: dict) -> int:
    """The number of steps of a steepest-ascent stage's ``levels`` in the soil config: as many
    for every factor that gives them (a printed table's rows, or the steps the DEM runs on the
    stage's own levels, :func:`soilcal.chain.derive.runs_own_levels`), else InputError naming
    ``<where>.factors`` (0 when no factor gives levels)."""
    lengths = sorted({len(f["levels"]) for f in stage["factors"].values() if f.get("levels")})
    if len(lengths) > 1:
        raise InputError(soil_path, f"{where}.factors", "the same number of levels for every factor", lengths)
    return lengths[0] if lengths else 0


def spec(soil, response_id: str) -> SimulationSpec:
    """:func:`spec_from` for a loaded :class:`~soilcal.config.load.Soil`."""
    return spec_from(soil.path, soil.data, response_id)


def design_levels(soil, stage_id: str) -> pd.DataFrame:
    """Every run of a stage: ``run`` (1-based), one column per factor letter in actual units,
    and the printed response columns when the paper prints the table."""
    from soilcal.doe.designs import box_behnken, coded_to_actual, plackett_burman

    stage = soil.stage(stage_id)
    letters = list(stage["factors"])
    where = f"stages.{stage_id}"
    if stage.get("table"):
        df = soil.tables[stage_id].copy()
        if stage.get("table_coding") == "coded":
            lo = [stage["factors"][c]["low"] for c in letters]
            hi = [stage["factors"][c]["high"] for c in letters]
            df[letters] = np.round(coded_to_actual(df[letters].to_numpy(float), lo, hi), 12)
        if "run" not in df.columns:
            df.insert(0, "run", np.arange(1, len(df) + 1))
        keep = ["run"] + letters + [r.get("column", r["id"]) for r in stage["responses"]]
        _check_runs(soil, stage, where, df, f"printed table {stage['table']}")
        return df[[c for c in keep if c in df.columns]].reset_index(drop=True)
    kind = stage["kind"]
    if kind == "steepest_ascent":
        levels = {}
        for c in letters:
            lv = stage["factors"][c].get("levels")
            if not lv:
                raise InputError(soil.path, f"{where}.factors.{c}.levels",
                                 "the actual value of every step (no printed table to take them from)", None)
            levels[c] = [float(v) for v in lv]
        path_steps(soil.path, where, stage)
        df = pd.DataFrame(levels)
    else:
        lo, hi = [], []
        for c in letters:
            f = stage["factors"][c]
            if f.get("low") is None or f.get("high") is None:
                raise InputError(soil.path, f"{where}.factors.{c}",
                                 "low and high levels to generate the design (the paper's table is not printed)", f)
            lo.append(float(f["low"]))
            hi.append(float(f["high"]))
        if kind == "plackett_burman":
            # an N-run design has N - 1 columns: the printed run count fixes N (a 12-run
            # screening of 7 factors is not the 8-run design 7 columns would give)
            cols = len(letters) + len(stage.get("dummies", []))
            if stage.get("runs"):
                cols = max(cols, int(stage["runs"]) - 1)
            coded = plackett_burman(cols)[:, : len(letters)]
        else:
            coded = box_behnken(len(letters), int(stage.get("center_points", 0)))
        df = pd.DataFrame(np.round(coded_to_actual(coded, lo, hi), 12), columns=letters)
    df.insert(0, "run", np.arange(1, len(df) + 1))
    _check_runs(soil, stage, where, df, "generated design")
    return df


def _check_runs(soil, stage, where, df, what):
    runs = stage.get("runs")
    if runs is not None and len(df) != int(runs):
        hint = {"plackett_burman": "; a Plackett-Burman design has a multiple of 4 runs, more "
                                   "than its factors and dummies",
                "box_behnken": "; a Box-Behnken design of k factors has 2k(k-1) runs (k = 3, 4; "
                               "pyDOE3) plus center_points"}.get(stage["kind"], "")
        raise InputError(soil.path, f"{where}.runs",
                         f"the number of rows of the {what} ({len(df)}){hint}", runs)


def design_seeds(soil, stage_id: str, rows: pd.DataFrame, seed: int | None = None,
                 replicates: int = 1) -> list[int]:
    """Seed of each row of :func:`design_levels`: the soil's ``seed`` (or ``seed``) plus
    ``replicates`` times the number of earlier rows with the same factor levels (module
    docstring), so that the replicate seeds of repeated points do not overlap."""
    base = int(soil.data["seed"]) if seed is None else int(seed)
    letters = list(soil.stage(stage_id)["factors"])
    seen: dict[tuple, int] = {}
    out = []
    for vals in rows[letters].itertuples(index=False):
        key = tuple(round(float(v), 12) for v in vals)
        out.append(base + int(replicates) * seen.get(key, 0))
        seen[key] = seen.get(key, 0) + 1
    return out


def design_params(soil, stage_id: str, levels: dict, sim: SimulationSpec, coded: bool = False):
    """DEM parameters of one design point (precedence in the module docstring)."""
    from soilcal.dem.scenarios.base import stage_params

    return stage_params(soil, stage_id, levels, coded=coded, params=sim.params,
                        params_field=f"{BLOCK}.params")


def simulate_point(soil, stage_id: str, levels: dict, response_id: str, seed: int | None = None,
                   replicates: int | None = None, threads=None, vtk_dir=None, coded: bool = False):
    """Run one design point through the scenario that measures ``response_id``.

    Returns ``(value, result)``: the measured response (the replicates' mean) and the
    scenario's :class:`~soilcal.dem.scenarios.base.Result`.  ``seed`` defaults to the soil's
    ``seed``, ``replicates`` to the block's.
    """
    from soilcal.dem.scenarios import get
    from soilcal.dem.scenarios.base import run_replicates

    sim = spec(soil, response_id)
    params = design_params(soil, stage_id, levels, sim, coded=coded)
    mod = get(sim.scenario)
    seed = int(soil.data["seed"]) if seed is None else seed
    k = sim.replicates if replicates is None else replicates
    res = run_replicates(mod, sim.setup, params, preset=sim.preset, seed=seed, replicates=k,
                         threads=threads, vtk_dir=vtk_dir, source=str(soil.path))
    if sim.measure not in res.responses:
        raise InputError(soil.path, f"{BLOCK}.responses.{response_id}.measure",
                         f"a response of {sim.scenario} ({', '.join(res.responses)})", sim.measure)
    return float(res.responses[sim.measure]), res
