"""The adaptive design (``simulation.design: adaptive``) on a soil's DEM jobs.

One design per optimisation case of each optimised stage the DEM source runs: the space is the
stage's factors over their screening ranges, or their own ranges in the soil config (``low`` ..
``high``; :func:`stage_for`, ``simulation.adaptive.ranges``; a range the soil declares under
``simulation.search_ranges`` serves the recipe's second round only and is recorded in the
stage's ``derivation.text`` as not used by the adaptive design), the stage's fixed
values stay fixed (and, for a stage fixed from an earlier one, ``fixed_from``, at that stage's
adaptive result), and the targets are the case's target goals with the values of
``results/<soil>/dem/targets.csv`` (photo or measurement).  :mod:`soilcal.doe.adaptive` decides
each iteration; this module turns its decisions into files and DEM point specs:

* ``step/<it>.json`` - iteration ``it``: status, message, the runs it asks for (point, kind,
  seed, levels), the surrogates' leave-one-out scores, the best candidate, the consistent
  region (each factor's spread, and a sample of up to 256 of its candidates, ``consistent``)
  and the last verification (written by the workflow's checkpoint ``adaptive_step``);
* ``runs/<it>/<k>.csv`` - run ``k`` of iteration ``it``: one DEM job, one seed, the
  :func:`soilcal.chain.sources.run_point` rows;
* ``runs.csv``, ``surrogates.csv``, ``region.csv``, ``result.json`` - the case's whole design
  once it has stopped;
* per stage ``optimum.csv`` (the verified set, or the best candidate, as the ``calibrated``
  row, in the recipe's columns) and ``identifiability.csv`` (the consistent region), and per
  soil ``verification.csv`` from the verified point's own runs, all under
  ``results/<soil>/dem/adaptive/`` with the recipe's file names;
* ``figures/``: the verification bars and per case its progress, the error of its best
  verified set against the runs spent (:func:`progress_frame`) and its proposals over the
  consistent region per iteration (:func:`figure_files`).

The cases of a stage share their runs (``simulation.adaptive.share_runs``, default true): the
step of case c at iteration k reads, besides its own, the step records and runs of its sibling
cases' iterations before k (:func:`shared_runs`), so the cases advance in lockstep and only the
first runs the start (:mod:`soilcal.doe.adaptive`, "Cases that share their runs").

Settings: the soil's ``simulation.adaptive`` block (:data:`soilcal.doe.adaptive.DEFAULTS`;
``tolerance_pct`` default 2 %, ``tolerances`` per response), the soil's ``seed``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from soilcal.chain.targets import goal_has_value
from soilcal.config.tables import read_table
from soilcal.doe import adaptive as ad
from soilcal.doe.designs import actual_to_coded
from soilcal.errors import InputError

ROOT = "adaptive"


def settings_block(soil_data: dict) -> dict:
    return dict((soil_data.get("simulation") or {}).get("adaptive") or {})


def _why_not(soil_data: dict, case: dict) -> str:
    """Why the adaptive design cannot run a case ('' when it can): it needs a target value for
    every response it aims at (a printed value or a photo group in the soil's ``targets``), and
    for every response to be minimised or maximised an absolute tolerance
    (``simulation.adaptive.tolerances.<response>.abs``)."""
    tols = settings_block(soil_data).get("tolerances") or {}
    for rid, g in case["goals"].items():
        if g.get("goal") in ad.OPTIMISED_GOALS:
            if (tols.get(rid) or {}).get("abs") is None:
                return (f"{rid}: goal {g.get('goal')} needs an absolute tolerance, "
                        f"simulation.adaptive.tolerances.{rid}.abs (how much worse than the best is acceptable)")
            continue
        if g.get("goal") != "target":
            return f"{rid}: goal {g.get('goal')} is neither a target nor minimize / maximize"
        if not goal_has_value(soil_data, g):
            return f"{rid}: target {g.get('target')} has no value and no photo group"
    return ""


def adaptive_cases(soil_data: dict, stage_ids) -> list[tuple[str, str]]:
    """(stage, case) of every optimisation case of the stages ``stage_ids`` the design can run
    (:func:`excluded_cases` lists the others with the reason)."""
    return [(st["id"], c["id"]) for st in soil_data["stages"] if st["id"] in stage_ids
            for c in (st.get("optimise") or {}).get("cases", []) if not _why_not(soil_data, c)]


def excluded_cases(soil_data: dict, stage_ids) -> list[dict]:
    return [{"stage": st["id"], "case": c["id"], "why": _why_not(soil_data, c)}
            for st in soil_data["stages"] if st["id"] in stage_ids
            for c in (st.get("optimise") or {}).get("cases", []) if _why_not(soil_data, c)]


def _case(stage: dict, case_id: str) -> dict:
    for c in (stage.get("optimise") or {}).get("cases", []):
        if c["id"] == case_id:
            return c
    raise InputError(stage.get("id"), "optimise.cases", f"a case {case_id!r}", case_id)


#: where the design's factor ranges come from (``simulation.adaptive.ranges``)
RANGES = ("screening", "stage")


def ranges_setting(soil_data: dict) -> str:
    r = settings_block(soil_data).get("ranges", "screening")
    if r not in RANGES:
        raise InputError(soil_data.get("name", "<soil>"), "simulation.adaptive.ranges", f"one of {RANGES}", r)
    return r


def screening_of(soil_data: dict, stage_id: str) -> dict | None:
    """The Plackett-Burman screening stage a stage descends from through its ``from_stage``
    links (None when it has none)."""
    from soilcal.chain.derive import _stage

    seen = set()
    cur = _stage(soil_data, stage_id)
    while cur.get("from_stage") and cur["id"] not in seen:
        seen.add(cur["id"])
        cur = _stage(soil_data, cur["from_stage"])
        if cur["kind"] == "plackett_burman":
            return cur
    return None


@dataclass(frozen=True)
class SearchRange:
    """The range (``low`` .. ``high``, the parameter's unit) a factor may be searched over, and
    where it comes from: ``field`` is ``stages.<screening>.factors.<symbol>`` (``kind``
    ``screening``) or ``simulation.search_ranges.<parameter>`` (``kind`` ``declared``)."""

    low: float
    high: float
    field: str
    kind: str

    def text(self) -> str:
        """``declared search range 0..10 (simulation.search_ranges.G)``: the values this range
        holds (the caller's, after any widening to a stage's bounds) and their field."""
        what = "screening range" if self.kind == "screening" else "declared search range"
        return f"{what} {self.low:g}..{self.high:g} ({self.field})"


def declared_range(soil_data: dict, parameter) -> SearchRange | None:
    """The range the soil declares ``parameter`` may be searched over
    (``simulation.search_ranges.<parameter>``, checked as the soil loads:
    :func:`soilcal.config.load.check_search_ranges`), or None."""
    entry = ((soil_data.get("simulation") or {}).get("search_ranges") or {}).get(parameter)
    if not entry:
        return None
    return SearchRange(float(entry["low"]), float(entry["high"]), f"simulation.search_ranges.{parameter}", "declared")


def screening_range(soil_data: dict, stage_id: str, parameter) -> SearchRange | None:
    """The range (``kind`` ``screening``, ``low`` <= ``high``) of the first factor of the
    Plackett-Burman screening stage ``stage_id`` descends from (:func:`screening_of`) that
    varies ``parameter`` between a low and a high level, or None: what
    :func:`second_round_range` and :func:`adaptive_range` take from the screening."""
    screening = screening_of(soil_data, stage_id)
    for sym, f in ((screening or {}).get("factors") or {}).items():
        if f.get("parameter") == parameter and f.get("low") is not None and f.get("high") is not None:
            lo, hi = sorted((float(f["low"]), float(f["high"])))
            return SearchRange(lo, hi, f"stages.{screening['id']}.factors.{sym}", "screening")
    return None


def second_round_range(soil_data: dict, stage_id: str, parameter, screening: bool = True) -> SearchRange | None:
    """The range a factor of stage ``stage_id`` setting ``parameter`` may be searched over past
    the stage's own levels by the second calibration round of ``design: recipe``
    (:func:`soilcal.chain.stage.screening_ranges`): the range the soil declares
    (:func:`declared_range`, the user's explicit choice) wherever it is declared; else, where
    ``screening`` (a stage derived from the simulated path), the range of the Plackett-Burman
    screening the stage descends from (:func:`screening_range`) where it varies the parameter;
    else None.  The adaptive design does not read declared ranges (:func:`adaptive_range`)."""
    declared = declared_range(soil_data, parameter)
    if declared is not None:
        return declared
    return screening_range(soil_data, stage_id, parameter) if screening else None


def adaptive_range(soil_data: dict, stage_id: str, parameter) -> SearchRange | None:
    """The range ``design: adaptive`` gives ``parameter`` in stage ``stage_id``: that of the
    Plackett-Burman screening the stage descends from (:func:`screening_range`), or None where
    the stage keeps its own range (``simulation.adaptive.ranges: stage``, no screening the stage
    descends from (:func:`screening_of`), or a screening that does not vary the parameter
    between a low and a high level).  A range declared under ``simulation.search_ranges`` does
    not enter: it serves the recipe's second round (:func:`second_round_range`).  The one rule
    :func:`stage_for` and the start-up checks of the adaptive design follow."""
    if ranges_setting(soil_data) != "screening":
        return None
    return screening_range(soil_data, stage_id, parameter)


def _screening_ranges(soil_data: dict, st: dict) -> tuple[list[str], dict]:
    """Widen the factors of ``st`` in place to the range :func:`adaptive_range` gives their
    parameter; returns the factors widened ("A (0.08-0.14 -> 0.05-0.2)") and, per symbol taking
    a range, ``{"low", "high", "from"}`` (the field it comes from)."""
    moved, used = [], {}
    for sym, f in st["factors"].items():
        found = adaptive_range(soil_data, st["id"], f.get("parameter"))
        if found is None:
            continue
        lo, hi = found.low, found.high
        used[sym] = {"low": lo, "high": hi, "from": found.field}
        if f.get("low") is None or f.get("high") is None:
            # a stage whose levels the recipe derives (no levels of its own): the screening's
            moved.append(f"{sym} (no levels -> {lo:g}-{hi:g})")
        elif (lo, hi) != (float(f["low"]), float(f["high"])):
            moved.append(f"{sym} ({f['low']:g}-{f['high']:g} -> {lo:g}-{hi:g})")
        f["low"], f["high"] = lo, hi
        if "centre" in f:
            f["centre"] = (lo + hi) / 2
    return moved, used


def stage_for(soil_data: dict, stage_id: str, upstream_optimum: pd.DataFrame | None = None) -> dict:
    """The stage the design runs on: the config stage as the DEM source writes it, its fixed
    values completed from the upstream stage's adaptive optimum where it has ``fixed_from``.

    Its factors' ranges (``simulation.adaptive.ranges``): ``screening`` (default) widens each
    factor to the range the stage's own Plackett-Burman screening (:func:`screening_of`) gave
    its parameter, where the stage has one: the screening says which factors matter and over
    what range the user expects them, while a Box-Behnken stage's narrower printed levels were
    centred by the paper's steepest ascent on its own engine's responses, which another
    engine need not share; ``stage`` keeps the stage's printed ranges.  A range the soil
    declares under ``simulation.search_ranges`` is not used (it serves the recipe's second
    round) and ``derivation.text`` says so.  ``derivation.ranges`` records, per factor taking a
    screening range, its ``low``, ``high`` and the field it comes ``from``.  The non-significant
    factors stay at the stage's fixed values either way."""
    from soilcal.chain.derive import _dem_base, _stage, apply_own_fixed, dependencies, fix_from_optimum

    config_stage = _stage(soil_data, stage_id)
    st = _dem_base(config_stage)
    text = "the factor ranges in the soil config (design: adaptive)"
    screening = screening_of(soil_data, stage_id) if ranges_setting(soil_data) == "screening" else None
    moved, used = _screening_ranges(soil_data, st) if screening is not None else ([], {})
    if screening is not None:
        text = (f"the ranges of screening stage {screening['id']} (design: adaptive, ranges: screening"
                + (f"; widened: {', '.join(moved)})" if moved else ")"))
    unused = [f"{s} {r.low:g}-{r.high:g}" for s, f in st["factors"].items()
              if (r := declared_range(soil_data, f.get("parameter"))) is not None]
    if unused:
        text += (f"; declared ranges not used by the adaptive design (simulation.search_ranges, for the "
                 f"recipe's second round): {', '.join(unused)}")
    st["derivation"] = {"kind": "adaptive", "text": text}
    if used:
        st["derivation"]["ranges"] = used
    # every fixed value with its origin (derivation.fixed), as the DEM source's stages record it
    apply_own_fixed(st, config_stage, {}, {}, set(), soil_data)
    deps = dependencies(dict(soil_data, simulation={**(soil_data.get("simulation") or {}), "design": "printed"}),
                        stage_id)
    if "fixed_from" in deps:
        if upstream_optimum is None:
            raise InputError(stage_id, "fixed_from", f"the adaptive optimum of stage {deps['fixed_from']}", None)
        up = _dem_base(_stage(soil_data, deps["fixed_from"]))
        st = fix_from_optimum(st, up, upstream_optimum, (config_stage.get("fixed_from") or {}).get("case"),
                              soil_data.get("parameters"))
    return st


def problem_for(soil_data: dict, stage: dict, case_id: str, targets: dict, source: str = "") -> ad.Problem:
    """The design's problem for one case: free factors and ranges, fixed values, targets."""
    where = source or f"{soil_data.get('name', '<soil>')}: stage {stage['id']} case {case_id}"
    factors = []
    for sym, f in stage["factors"].items():
        if "low" not in f or "high" not in f:
            raise InputError(where, f"stages.{stage['id']}.factors.{sym}", "a range (low, high)",
                             sorted(f))
        factors.append(ad.Factor(sym, float(f["low"]), float(f["high"])))
    block = settings_block(soil_data)
    default_pct = float(block.get("tolerance_pct", ad.DEFAULTS["tolerance_pct"]))
    per = block.get("tolerances") or {}
    tgts = []
    for rid, goal in _case(stage, case_id)["goals"].items():
        if goal.get("goal") in ad.OPTIMISED_GOALS:
            tol = (per.get(rid) or {}).get("abs")
            if tol is None:
                raise InputError(where, f"simulation.adaptive.tolerances.{rid}.abs",
                                 f"an absolute tolerance for the goal {goal['goal']}", "missing")
            tgts.append(ad.Target(rid, float("nan"), tol=float(tol), goal=goal["goal"]))
            continue
        if goal.get("goal") != "target":
            raise InputError(where, f"optimise.cases.{case_id}.goals.{rid}", "a goal target, minimize or maximize",
                             goal.get("goal"))
        if goal.get("value") is not None:
            value = float(goal["value"])
        else:
            t = targets.get(goal["target"]) or {}
            value = t.get("value")
            if value is None or not np.isfinite(float(value)):
                raise InputError(where, f"targets.{goal['target']}", "a target value (photo or measurement)",
                                 t.get("source", "not available"))
            value = float(value)
        tol = per.get(rid, {})
        tgts.append(ad.Target(rid, value, tol=tol.get("abs"), tol_pct=tol.get("pct", default_pct)))
    return ad.Problem(factors, tgts, fixed=dict(stage.get("fixed") or {}), source=where)


def settings_for(soil_data: dict, stage_id: str | None = None, case_id: str | None = None) -> ad.Settings:
    """The design's settings; with the stage and case of a stage whose cases share their runs
    (:func:`shares_runs`), that case's own seed stream (:func:`soilcal.doe.adaptive.case_settings`)."""
    block = settings_block(soil_data)
    block.pop("tolerances", None)
    block.pop("ranges", None)  # read by stage_for
    block.pop("share_runs", None)  # read by shares_runs
    s = ad.Settings.from_mapping(block, seed=int(soil_data.get("seed", 0)),
                                 source=f"{soil_data.get('name', '<soil>')}: simulation")
    if stage_id is not None and case_id is not None and shares_runs(soil_data):
        s = ad.case_settings(s, case_index(soil_data, stage_id, case_id))
    return s


def adaptive_stage_ids(soil_data: dict) -> list[str]:
    """The stages the adaptive design runs: the optimised stages the DEM source runs with at
    least one case it can run (:func:`adaptive_cases`)."""
    from soilcal.chain.derive import optimised_dem_stage_ids

    return [sid for sid in optimised_dem_stage_ids(soil_data) if adaptive_cases(soil_data, [sid])]


def start_runs(settings: ad.Settings, d: int) -> int:
    """DEM runs of the start over ``d`` free factors: the centre with ``centre_replicates``
    seeds and ``n_start - 1`` Halton points, one seed each (:func:`soilcal.doe.adaptive.step`)."""
    n = settings.n_start or 2 * d + 1
    return settings.centre_replicates + n - 1


def check_settings(soil_path, soil_data: dict) -> ad.Settings:
    """Start-up check of a soil's ``simulation.adaptive`` block for ``design: adaptive``; every
    error names the soil file and ``simulation.adaptive.<key>``.

    Besides each setting's own range (:meth:`soilcal.doe.adaptive.Settings.from_mapping`):
    ``tolerances`` name responses of the stages the design runs, each with exactly one of
    ``pct`` or ``abs``; and the ``budget`` of a case (the runs it may spend, the start
    included: the design stops once its own runs reach it) holds the start and one
    verification, budget >= centre_replicates + n_start - 1 + verify_seeds for every stage the
    design runs (n_start default 2 d + 1 over the stage's d factors), and ``batch`` is no
    larger than what the budget leaves after the start (a larger batch can never be proposed
    whole)."""
    where = "simulation.adaptive"
    block = settings_block(soil_data)
    if not isinstance((soil_data.get("simulation") or {}).get("adaptive") or {}, dict):
        raise InputError(soil_path, where, "a mapping of settings", soil_data["simulation"]["adaptive"])
    if block.get("ranges", "screening") not in RANGES:
        raise InputError(soil_path, f"{where}.ranges", f"one of {', '.join(RANGES)}", block["ranges"])
    if not isinstance(block.get("share_runs", True), bool):
        raise InputError(soil_path, f"{where}.share_runs", "true or false", block["share_runs"])
    pct = block.get("tolerance_pct", ad.DEFAULTS["tolerance_pct"])
    if isinstance(pct, bool) or not isinstance(pct, (int, float)) or not (np.isfinite(pct) and pct > 0):
        raise InputError(soil_path, f"{where}.tolerance_pct", "a percentage > 0", pct)
    rest = {k: v for k, v in block.items() if k not in ("tolerances", "ranges", "share_runs")}
    try:
        settings = ad.Settings.from_mapping(rest, seed=int(soil_data.get("seed", 0)), source=str(soil_path))
    except InputError as exc:
        fld = exc.field[len("adaptive."):] if exc.field.startswith("adaptive.") else exc.field
        raise InputError(soil_path, f"{where}.{fld}", exc.expected, exc.got) from None
    stages = adaptive_stage_ids(soil_data)
    by_id = {st["id"]: st for st in soil_data["stages"]}
    rids = list(dict.fromkeys(r["id"] for sid in stages for r in by_id[sid]["responses"]))
    tols = block.get("tolerances")
    if tols is not None and not isinstance(tols, dict):
        raise InputError(soil_path, f"{where}.tolerances", "a mapping response -> {pct: ..} or {abs: ..}", tols)
    for rid, tol in (tols or {}).items():
        if rid not in rids:
            raise InputError(soil_path, f"{where}.tolerances.{rid}", "a response of a stage the adaptive design runs ("
                             + (", ".join(rids) if rids else "none") + ")", rid)
        given = sorted(set(tol or {}) & {"pct", "abs"}) if isinstance(tol, dict) else []
        if not isinstance(tol, dict) or len(given) != 1 or len(tol) != 1:
            raise InputError(soil_path, f"{where}.tolerances.{rid}",
                             "exactly one of {pct: percent of the target} or {abs: value in the response's unit}",
                             tol)
        v = tol[given[0]]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not (np.isfinite(v) and v > 0):
            raise InputError(soil_path, f"{where}.tolerances.{rid}.{given[0]}", "a number > 0", v)
    for sid in stages:
        d = len(by_id[sid]["factors"])
        start = start_runs(settings, d)
        n_start = settings.n_start or 2 * d + 1
        how = (f"the start of stage {sid!r} ({settings.centre_replicates} seeds at the centre and {n_start - 1} "
               f"Halton points{'' if settings.n_start else f', n_start = 2 d + 1 for its {d} factors'}: {start} runs)")
        need = start + settings.verify_seeds
        if settings.budget < need:
            raise InputError(soil_path, f"{where}.budget",
                             f"at least {need} runs: {how} and one verification (verify_seeds = {settings.verify_seeds})",
                             settings.budget)
        if settings.batch > settings.budget - start:
            raise InputError(soil_path, f"{where}.batch",
                             f"at most {settings.budget - start}, the runs of the budget ({settings.budget}) left after "
                             + how, settings.batch)
    return settings


def shares_runs(soil_data: dict) -> bool:
    """Whether the cases of a stage share their runs (``simulation.adaptive.share_runs``,
    default true; :mod:`soilcal.doe.adaptive`, "Cases that share their runs")."""
    v = settings_block(soil_data).get("share_runs", True)
    if not isinstance(v, bool):
        raise InputError(soil_data.get("name", "<soil>"), "simulation.adaptive.share_runs", "true or false", v)
    return v


def case_index(soil_data: dict, stage_id: str, case_id: str) -> int:
    """The position of a case among its stage's cases the design runs."""
    ids = [c for _, c in adaptive_cases(soil_data, [stage_id])]
    if case_id not in ids:
        raise InputError(f"{soil_data.get('name', '<soil>')}: stage {stage_id}", "optimise.cases",
                         f"a case the adaptive design runs ({', '.join(ids)})", case_id)
    return ids.index(case_id)


def sibling_cases(soil_data: dict, stage_id: str, case_id: str) -> list[str]:
    """The other cases of the stage whose runs this case shares (none when sharing is off)."""
    if not shares_runs(soil_data):
        return []
    return [c for _, c in adaptive_cases(soil_data, [stage_id]) if c != case_id]


# --------------------------------------------------------------------------- runs on disk

def read_runs(problem: ad.Problem, steps: list[dict], run_paths) -> pd.DataFrame:
    """The design's run table from its step records and run files ``runs/<it>/<k>.csv``."""
    files = {}
    for p in run_paths:
        p = Path(p)
        try:
            key = (int(p.parent.name), int(p.stem))
        except ValueError:
            raise InputError(p, "<file name>", "runs/<iteration>/<run>.csv", str(p)) from None
        df = read_table(p)
        missing = [c for c in ("response", "status", "value") if c not in df.columns]
        if missing:
            raise InputError(p, missing[0], "a DEM run table (soilcal.chain.sources.run_point)", "missing column")
        files[key] = df
    rows = []
    for step in steps:
        it = int(step["iteration"])
        for k, r in enumerate(step["runs"]):
            if (it, k) not in files:
                raise InputError(f"runs/{it}", f"run {k}", "a run file for every run of the iteration", "missing")
            df = files[(it, k)]
            row = {"iteration": it, "kind": r["kind"], "point": int(r["point"]), "seed": int(r["seed"]),
                   **{s: float(r["levels"][s]) for s in problem.names}}
            for rid in problem.responses:
                sel = df[(df["response"] == rid) & (df["status"].astype(str) == "ok")]
                row[rid] = float(sel["value"].iloc[0]) if len(sel) else np.nan
            rows.append(row)
    return pd.DataFrame(rows, columns=[*ad.RUN_KEYS, *problem.names, *problem.responses]) if rows \
        else ad.empty_runs(problem)


def _records(df: pd.DataFrame) -> list[dict]:
    return json.loads(df.to_json(orient="records")) if df is not None and len(df) else []


def _plain(obj):
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, np.ndarray)):
        return [_plain(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        return None if not np.isfinite(obj) else float(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def step_record(problem: ad.Problem, settings: ad.Settings, st: ad.Step) -> dict:
    runs = [{"iteration": int(r["iteration"]), "kind": r["kind"], "point": int(r["point"]),
             "seed": int(r["seed"]), "levels": {s: float(r[s]) for s in problem.names}}
            for _, r in st.runs.iterrows()]
    best = None
    if st.best:
        best = {"p": st.best["p"], "levels": dict(zip(problem.names, map(float, st.best["actual"]))),
                "predicted": st.best["predicted"], "predicted_sd": st.best["predicted_sd"],
                "closest": bool(st.best.get("closest", False))}
    return _plain({"iteration": st.iteration, "status": st.status, "message": st.message, "runs": runs,
                   "surrogates": _records(st.surrogates), "best": best, "region": _records(st.region),
                   "verified": st.verified,
                   "problem": {"factors": {f.name: [f.low, f.high] for f in problem.factors},
                               "fixed": problem.fixed,
                               # a minimised (maximised) response's value: its best level as decided
                               "targets": {t.response: {"value": t.value, "tolerance": t.tolerance, "goal": t.goal}
                                           for t in (st.problem or problem).targets}},
                   "searched": st.searched,
                   # a sample of the consistent region (P > 1/2) as this iteration saw it, for the
                   # figure of the proposals over it; one row of factor levels per candidate
                   "consistent": [[float(f"{v:.6g}") for v in row] for row in
                                  (st.consistent if st.consistent is not None else [])],
                   "settings": {k: getattr(settings, k) for k in settings.__dataclass_fields__}})


def _case_of(path) -> str:
    """The case directory a step record or run file of ``<case>/step/<it>.json`` or
    ``<case>/runs/<it>/<k>.csv`` lies in."""
    p = Path(path)
    return p.parent.parent.name if p.parent.name == "step" else p.parent.parent.parent.name


def shared_runs(soil_data: dict, stage: dict, targets: dict, step_paths, run_paths) -> pd.DataFrame | None:
    """The runs of the sibling cases (their step records and run files, any iterations), one
    frame with a ``case`` column, or None when there are none."""
    steps: dict[str, list] = {}
    runs: dict[str, list] = {}
    for p in step_paths:
        steps.setdefault(_case_of(p), []).append(json.loads(Path(p).read_text()))
    for p in run_paths:
        runs.setdefault(_case_of(p), []).append(p)
    frames = []
    for case, recs in steps.items():
        recs.sort(key=lambda d: d["iteration"])
        df = read_runs(problem_for(soil_data, stage, case, targets), recs, runs.get(case, []))
        if len(df):
            frames.append(df.assign(case=case))
    return pd.concat(frames, ignore_index=True) if frames else None


def write_step(soil_data: dict, stage: dict, case_id: str, targets: dict, iteration: int,
               step_paths, run_paths, out, shared_step_paths=(), shared_run_paths=()) -> dict:
    """Decide iteration ``iteration`` from the earlier steps and their runs (and, where the
    stage's cases share their runs, the sibling cases' steps and runs); write its record."""
    from soilcal.atomic import write_text

    problem = problem_for(soil_data, stage, case_id, targets)
    settings = settings_for(soil_data, stage["id"], case_id)
    steps = [json.loads(Path(p).read_text()) for p in step_paths]
    steps.sort(key=lambda d: d["iteration"])
    if [d["iteration"] for d in steps] != list(range(iteration)):
        raise InputError(out, "iteration", f"the records of iterations 0..{iteration - 1}",
                         [d["iteration"] for d in steps])
    runs = read_runs(problem, steps, run_paths)
    sharing = shares_runs(soil_data)
    shared = shared_runs(soil_data, stage, targets, shared_step_paths, shared_run_paths) if sharing else None
    st = ad.step(problem, runs, settings, iteration, shared=shared,
                 wait_for_start=sharing and case_index(soil_data, stage["id"], case_id) > 0)
    rec = step_record(problem, settings, st)
    write_text(out, json.dumps(rec, indent=1) + "\n")
    return rec


def point_spec(soil, stage: dict, case_id: str, step: dict, k: int) -> dict:
    """The DEM job of run ``k`` of an iteration record: the point's levels, one seed, every
    response the case aims at."""
    from soilcal.chain.sources import point_spec as spec

    r = step["runs"][k]
    rids = list(_case(stage, case_id)["goals"])
    out = spec(soil, stage, r["levels"], run=int(r["point"]), seed=int(r["seed"]), replicates=1, responses=rids)
    return dict(out, case=case_id, iteration=int(step["iteration"]), kind=r["kind"])


# --------------------------------------------------------------------------- results

def write_case(soil_data: dict, stage: dict, case_id: str, targets: dict, step_paths, run_paths,
               out_runs, out_surrogates, out_region, out_result, out_verification_runs) -> dict:
    """The stopped design of one case: its runs, the surrogates of each iteration, the
    consistent region, the final record and the DEM rows of its last verified point."""
    from soilcal.atomic import write_text
    from soilcal.chain.files import write_csv

    problem = problem_for(soil_data, stage, case_id, targets)
    steps = sorted((json.loads(Path(p).read_text()) for p in step_paths), key=lambda d: d["iteration"])
    final = steps[-1]
    if final["status"] == "continue":
        raise InputError(step_paths[-1], "status", "a stopped design (the last iteration's record)", "continue")
    runs = read_runs(problem, steps[:-1], run_paths)
    write_csv(runs, out_runs)
    sur = pd.DataFrame([dict(iteration=d["iteration"], **s) for d in steps for s in d["surrogates"]])
    write_csv(sur, out_surrogates)
    write_csv(pd.DataFrame(final["region"]), out_region)
    result = {"stage": stage["id"], "case": case_id, "status": final["status"], "message": final["message"],
              "runs": int(len(runs)), "iterations": int(final["iteration"]), "best": final["best"],
              "verified": final["verified"], "problem": final["problem"], "settings": final["settings"]}
    write_text(out_result, json.dumps(_plain(result), indent=1) + "\n")
    ver = []
    if final["verified"]:
        pid = int(final["verified"]["point"])
        where = {(int(d["iteration"]), k): r for d in steps for k, r in enumerate(d["runs"])}
        for p in run_paths:
            p = Path(p)
            r = where.get((int(p.parent.name), int(p.stem)))
            if r and r["kind"] == "verification" and int(r["point"]) == pid:
                ver.append(pd.read_csv(p))
    write_csv(pd.concat(ver, ignore_index=True) if ver else pd.DataFrame(columns=["response", "status"]),
              out_verification_runs)
    return result


def optimum_frame(stage: dict, results: list[dict]) -> pd.DataFrame:
    """``optimum.csv`` in the recipe's columns: per case the verified set (``calibrated``; its
    responses the verified means); when none was verified within tolerance, the best verified
    point (measured: its verification runs are the ones verification.csv compares it with; its
    responses empty, as there is no surface prediction at it), or,
    with no verification at all, the best candidate (its responses the surrogate's predictions),
    with the reason in ``note``."""
    syms = list(stage["factors"])
    rows = []
    for res in results:
        f = res["problem"]["factors"]
        src = None
        if res["verified"] and res["verified"]["met"]:
            src, levels = "verified", res["verified"]["levels"]
        elif res["verified"]:
            # a measured answer, not the surrogate's unrun best guess: the point verification.csv
            # compares with its own runs
            src, levels = "verified point", res["verified"]["levels"]
        elif res["best"]:
            src, levels = "best candidate", res["best"]["levels"]
        row = {"case": res["case"], "method": "adaptive", "solution": 1}
        if src is None:
            rows.append(row | {"calibrated": False, "status": res["status"], "note": res["message"]})
            continue
        for s in syms:
            row[f"{s}_coded"] = float(actual_to_coded(np.array([levels[s]]), [f[s][0]], [f[s][1]])[0])
            row[s] = levels[s]
        for rid, v in ((res["best"] or {}).get("predicted") or {}).items():
            row[rid] = v if src == "best candidate" else np.nan
        if src == "verified":
            for rid, v in res["verified"]["responses"].items():
                row[rid] = v["mean"]
        elif src == "verified point":
            # no surface prediction there (verification.csv reads these columns as one; the
            # point's verified means are its own rows there)
            for rid in res["verified"]["responses"]:
                row[rid] = np.nan
        row.update(calibrated=True, status=res["status"], runs=res["runs"],
                   note=("verified within tolerance" if src == "verified" else
                         "the best verified point (its verified means in verification.csv), not within tolerance; "
                         "the surrogate's "
                         f"best candidate, not run, is named here: {res['message']}" if src == "verified point" else
                         ("closest reachable point (no point is plausibly within tolerance), "
                          if res["best"].get("closest") else "best candidate, ")
                         + f"not verified within tolerance: {res['message']}"))
        rows.append(row)
    return pd.DataFrame(rows)


def region_frame(results: list[dict], regions: list[pd.DataFrame]) -> pd.DataFrame:
    """``identifiability.csv``: per case and factor, the consistent region's spread."""
    frames = []
    for res, reg in zip(results, regions):
        if reg is None or not len(reg):
            continue
        r = reg.copy()
        r.insert(0, "case", res["case"])
        r["spread"] = r["max"] - r["min"]
        r["spread_coded"] = r["spread"] / ((r["high"] - r["low"]) / 2)
        r["note"] = ["at bound: the consistent region reaches the " + ad.near_a_bound(lo, hi, f_lo, f_hi)
                     + " bound of the box, which holds it there, not the data: the consistent set may go on beyond it"
                     if pin == "at bound" else
                     "" if pin else "spread over more than half its range: the data do not pin it down"
                     for pin, lo, hi, f_lo, f_hi in zip(r["pinned"], r["min"], r["max"], r["low"], r["high"])]
        frames.append(r)
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(
        columns=["case", "factor", "candidates", "min", "max", "spread", "spread_coded", "pinned", "note"])


def write_stage(soil_data: dict, stage: dict, result_paths, region_paths, out_stage, out_optimum,
                out_identifiability) -> pd.DataFrame:
    from soilcal.atomic import write_text
    from soilcal.chain.files import write_csv

    results = [json.loads(Path(p).read_text()) for p in result_paths]
    regions = [pd.read_csv(p) if Path(p).stat().st_size > 1 else None for p in region_paths]
    write_text(out_stage, json.dumps(_plain(stage), indent=1) + "\n")
    opt = optimum_frame(stage, results)
    write_csv(opt, out_optimum)
    write_csv(region_frame(results, regions), out_identifiability)
    return opt


def write_verification(soil_data: dict, stage_dirs: dict[str, str], targets_csv, result_paths,
                       verification_run_paths, out) -> pd.DataFrame:
    """``verification.csv`` in the recipe's columns, from each case's verified point (its own
    verification runs: the seeds the design verified it with); ``verification_run_paths``
    are the cases' ``verification_runs.csv`` beside their ``result.json``."""
    from soilcal.chain.files import read_stage, read_targets, write_csv
    from soilcal.chain.verify import VERIFICATION_COLUMNS, verification_frame

    targets = read_targets(targets_csv)
    results = {(r["stage"], r["case"]): r for r in (json.loads(Path(p).read_text()) for p in result_paths)}
    runs: dict[tuple[str, str], list[pd.DataFrame]] = {}
    for p in verification_run_paths:
        p = Path(p)
        df = pd.read_csv(p)
        if len(df):
            runs[(p.parent.parent.name, p.parent.name)] = [df]
    frames = []
    for sid, d in stage_dirs.items():
        stage = read_stage(Path(d) / "stage.json")
        opt = pd.read_csv(Path(d) / "optimum.csv")
        case_runs = {case: fr for (s, case), fr in runs.items() if s == sid}
        cases = [c for c in (stage.get("optimise") or {}).get("cases", []) if (sid, c["id"]) in results]
        frames.append(verification_frame(soil_data, dict(stage, optimise={**stage["optimise"], "cases": cases}),
                                         opt, targets, case_runs))
    df = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=VERIFICATION_COLUMNS)
    for i, row in df.iterrows():
        res = results[(row["stage"], row["case"])]
        if row["n"] > 0:  # simulated (status ok, or some seeds failed)
            df.at[i, "note"] = "; ".join(x for x in (f"adaptive: {res['status']} after {res['runs']} runs",
                                                      str(row["note"])) if x and x != "nan")
        else:
            df.at[i, "status"] = f"not verified: {res['status']}"
            df.at[i, "note"] = res["message"]
    write_csv(df, out)
    return df


# --------------------------------------------------------------------------- file-level entry points
# (what the workflow's scripts call: paths in, files out)

def _inputs(soil_data, stage_id, targets_csv, upstream_csv):
    from soilcal.chain.files import read_targets

    up = pd.read_csv(upstream_csv) if upstream_csv else None
    return stage_for(soil_data, stage_id, up), read_targets(targets_csv)


def step_files(soil_data: dict, stage_id: str, case_id: str, iteration: int, targets_csv, step_paths,
               run_paths, out, upstream_csv=None, shared_step_paths=(), shared_run_paths=()) -> dict:
    stage, targets = _inputs(soil_data, stage_id, targets_csv, upstream_csv)
    return write_step(soil_data, stage, case_id, targets, iteration, step_paths, run_paths, out,
                      shared_step_paths, shared_run_paths)


def case_files(soil_data: dict, stage_id: str, case_id: str, targets_csv, step_paths, run_paths, outputs,
               upstream_csv=None) -> dict:
    """``outputs``: runs, surrogates, region, result, verification_runs paths."""
    stage, targets = _inputs(soil_data, stage_id, targets_csv, upstream_csv)
    return write_case(soil_data, stage, case_id, targets, step_paths, run_paths, *outputs)


def stage_files(soil_data: dict, stage_id: str, result_paths, region_paths, outputs, upstream_csv=None):
    """``outputs``: stage.json, optimum.csv, identifiability.csv paths."""
    up = pd.read_csv(upstream_csv) if upstream_csv else None
    return write_stage(soil_data, stage_for(soil_data, stage_id, up), result_paths, region_paths, *outputs)


def stage_log_lines(stage_json) -> list[str]:
    """The lines the stage job's log gives on the stage's fixed values: each with its origin
    (``fixed: ...``), and a warning for each that lies outside its screening range
    (``warning: ...``, :func:`soilcal.chain.derive.apply_own_fixed`)."""
    rec = (json.loads(Path(stage_json).read_text()).get("derivation") or {}).get("fixed") or {}
    return ([f"fixed: {k} = {r['value']:g}: {r['origin']}" for k, r in rec.items()]
            + [f"warning: {r['warning']}" for r in rec.values() if r.get("warning")])


SUMMARY_COLUMNS = ["soil", "stage", "case", "response", "goal", "target", "best_level", "tolerance", "method", "runs",
                   "iterations",
                   "verified_mean", "verified_sd", "verified_n", "verification_rel_error_pct",
                   "within_tolerance", "stopped_because", "message"]


def summary_frame(soil: str, results: list[dict], excluded: list[dict] = ()) -> pd.DataFrame:
    """One row per case and response: how the design stopped, after how many runs, and the
    verified relative error; a case the design cannot run is a row saying why."""
    rows = [{"soil": soil, "stage": e["stage"], "case": e["case"], "method": "adaptive", "runs": 0,
             "stopped_because": "not run", "message": e["why"]} for e in excluded]
    for r in results:
        ver = (r.get("verified") or {}).get("responses") or {}
        for rid, t in r["problem"]["targets"].items():
            v = ver.get(rid, {})
            # a minimised (maximised) response has no target: the best level it was held to, and
            # no relative error (records written before the design left it empty carry one)
            aimed = t.get("goal", "target") == "target"
            rows.append({"soil": soil, "stage": r["stage"], "case": r["case"], "response": rid,
                         "goal": t.get("goal", "target"), "target": t["value"] if aimed else None,
                         "best_level": None if aimed else t["value"], "tolerance": t["tolerance"],
                         "method": "adaptive", "runs": r["runs"], "iterations": r["iterations"],
                         "verified_mean": v.get("mean"), "verified_sd": v.get("sd"), "verified_n": v.get("n"),
                         "verification_rel_error_pct": v.get("error_pct") if aimed else None,
                         "within_tolerance": v.get("within"), "stopped_because": r["status"],
                         "message": r["message"]})
    return pd.DataFrame(rows, columns=SUMMARY_COLUMNS)


def verification_files(soil: str, soil_data: dict, stage_dirs: dict[str, str], targets_csv, result_paths,
                       verification_run_paths, out, out_summary) -> pd.DataFrame:
    from soilcal.chain.files import write_csv

    from soilcal.chain.derive import dem_stage_ids

    df = write_verification(soil_data, stage_dirs, targets_csv, result_paths, verification_run_paths, out)
    results = [json.loads(Path(p).read_text()) for p in result_paths]
    write_csv(summary_frame(soil, results, excluded_cases(soil_data, dem_stage_ids(soil_data))), out_summary)
    return df


#: one point of the error of the best verified set against the runs spent
#: (:func:`progress_frame`; :func:`soilcal.plots.adaptive.error_against_runs`)
PROGRESS_COLUMNS = ["stage", "case", "method", "iteration", "runs", "response", "goal", "target", "tolerance",
                    "verified_mean", "verified_n", "error_pct", "within"]


def progress_frame(result: dict, steps: list[dict]) -> pd.DataFrame:
    """The best verified set of a case after every iteration against the runs spent before it
    (its own runs): one row per iteration that had a verified set and per response.  A step
    record's ``verified`` is decided from the runs of the iterations before it, so the runs
    column counts those."""
    rows, spent = [], 0
    for rec in sorted(steps, key=lambda r: r["iteration"]):
        ver = rec.get("verified") or {}
        targets = (rec.get("problem") or {}).get("targets") or {}
        for rid, v in (ver.get("responses") or {}).items():
            t = targets.get(rid, {})
            rows.append({"stage": result["stage"], "case": result["case"], "method": "adaptive",
                         "iteration": int(rec["iteration"]), "runs": spent, "response": rid,
                         "goal": v.get("goal", "target"), "target": v.get("target"),
                         "tolerance": v.get("tolerance", t.get("tolerance")), "verified_mean": v.get("mean"),
                         "verified_n": v.get("n"), "error_pct": v.get("error_pct"), "within": v.get("within")})
        spent += len(rec.get("runs") or [])
    return pd.DataFrame(rows, columns=PROGRESS_COLUMNS)


def case_steps(case_dir) -> tuple[dict, list[dict]]:
    """A stopped case's ``result.json`` and its ``step/<it>.json`` records, in order."""
    d = Path(case_dir)
    res = json.loads((d / "result.json").read_text())
    steps = sorted((json.loads(p.read_text()) for p in (d / "step").glob("*.json")), key=lambda r: r["iteration"])
    return res, steps


def figure_files(soil: str, verification_csv, case_dirs, out_dir) -> list[Path]:
    """The verification bars of the soil's adaptive sets and, per case, its progress, the error
    of its best verified set against the runs spent and its proposals over the consistent
    region."""
    from soilcal import plots
    from soilcal.plots.adaptive import adaptive_progress, error_against_runs, proposals_over_region

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = plots.verification_bars(pd.read_csv(verification_csv), out_dir / "verification",
                                    title=f"{soil}: verification at the adaptive sets")
    for d in map(Path, case_dirs):
        res, steps = case_steps(d)
        runs = pd.read_csv(d / "runs.csv")
        best = [(r["iteration"], r["best"]["p"]) for r in steps if r.get("best")]
        tag = f"{res['stage']}_{res['case']}"
        paths += adaptive_progress(runs, res, best, out_dir / f"progress_{tag}")
        prog = progress_frame(res, steps)
        if len(prog):
            paths += error_against_runs(prog, out_dir / f"error_{tag}",
                                        title=f"{soil} {res['stage']} / {res['case']}: best verified set "
                                              f"against runs ({res['status']})")
        paths += proposals_over_region(steps, runs, out_dir / f"region_{tag}")
    return paths


__all__ = ["PROGRESS_COLUMNS", "case_steps", "progress_frame", "case_index", "shares_runs", "shared_runs", "sibling_cases", "SUMMARY_COLUMNS", "figure_files", "adaptive_cases", "excluded_cases", "case_files", "stage_files", "step_files", "summary_frame", "verification_files", "optimum_frame", "point_spec", "problem_for", "read_runs", "settings_for",
           "stage_for", "step_record", "write_case", "write_stage", "write_step", "write_verification"]
