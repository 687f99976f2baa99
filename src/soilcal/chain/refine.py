"""The second calibration round: a bias-corrected set where the first verification missed.

For every optimisation case of a stage, :func:`refine_frame` compares the verification seeds
at the calibrated set x0 (``optimum.csv``, ``calibrated = True``) with the targets.  A case is
refined when a target is missed by more than 2 % and the verification mean differs from the
response surface's prediction at x0 by more than two standard errors of that difference (the
seeds' mean's and the surface's prediction's, :meth:`soilcal.rsm.model.RSMFit.predict_se`,
together) for at least one targeted response
(:func:`soilcal.optimise.correction.significant_bias`); the new set is the smallest
move from x0 at which the bias-corrected surfaces meet every target
(:func:`soilcal.optimise.correction.corrected_set`); where a local design at x0 has run
(:mod:`soilcal.chain.local`, the workflow's default for such a case), the surfaces are corrected
to the DEM's level and slope there instead of shifted, and the move stays within its trust
region (:func:`_local_row`).  The workflow verifies the new set with fresh
seeds (``seed + seed_offset + max_replicates + k``, after every seed the first round may take;
as many as the first round ended with for the case).  Where the corrected surfaces cannot meet every
target inside the design region, the region is moved, as response-surface practice moves it
towards a target outside it (Myers, Montgomery & Anderson-Cook, Response Surface Methodology,
ch. 5-6): the search reaches past the box (``design: recipe``; ``printed`` keeps the box, to be
compared point by point with the paper), in each factor whose parameter the soil declares a
search range for (``simulation.search_ranges``, wherever declared), or else that the design
descends from a wider simulated screening range of (:func:`soilcal.chain.stage.screening_ranges`:
a Box-Behnken centred on a path step, whose Plackett-Burman screening spans more), by at most
:data:`BEYOND_HALF_WIDTHS` box half-widths and never past that range; a factor with no wider
range stays in the box.  Such
a row has ``region = beyond`` and its note says in which factors and how far; the DEM
verification of it with fresh seeds judges it (the verification rows say where it missed by
more than the first round).  Where the corrected surfaces cannot meet every target in that
region either (two targets pulling apart, as a layer's static and dynamic angles can), their
least-squares compromise is verified instead if it promises a worst relative error at least
:data:`COMPROMISE_GAIN` percentage points below theirs at x0 (a compromise past the box only
where it promises that much more than the best inside it).  Every other case keeps x0, and its
row says why (met, scatter only, no target, nothing better within reach).

``refined.csv`` has one row per case with ``calibrated = True`` on the set the soil ends
with, in the columns of ``optimum.csv`` (factor levels coded and actual, predicted responses,
corrected where refined), so the tool tests and ``calibrated_vs_paper`` read the final set
the same way they read an optimum; plus ``round`` (1 = x0 kept, 2 = bias-corrected),
``refined``, ``bias_<response>``, ``surface_change_se_<response>`` (round 2: the standard error
of the surface's change from x0 to the new set, :meth:`soilcal.rsm.model.RSMFit.change_se`),
``move_coded``, ``region`` (``inside`` the Box-Behnken box or ``beyond`` it), ``note`` and
``search_ranges`` (each factor's range past the box, as used after widening to the box, and
where it comes from: the declared ``simulation.search_ranges`` entry or the screening's factor;
a declared range ``design: printed`` does not use is named as not used; the same on every row
of a stage, and on ``final.csv``'s).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from soilcal.errors import InputError

TOLERANCE_PERCENT = 2.0
#: a compromise set is verified when the corrected surfaces promise a worst relative error at
#: least this many percentage points below theirs at the first set (half the 2 % tolerance)
COMPROMISE_GAIN = 1.0
#: how far past a bound of the design box (in box half-widths, coded units) the second round may
#: move a factor that was screened over a wider range: the surfaces were fitted inside the box
#: and a quadratic's error grows quickly outside it, so one half-width, which in the recipe's
#: design (a Box-Behnken whose low and high are the path steps either side of its centre) is the
#: next path step.  The path's DEM runs saw the responses there only along the path line (every
#: factor at that step's levels at once), not at the other factors' levels of the set, so past
#: the box the surface is extrapolated and only the verification with fresh seeds judges it
BEYOND_HALF_WIDTHS = 1.0


def refine_settings(soil_data: dict) -> bool:
    """Whether the soil runs the second round (``simulation.verification.refine``, default on)."""
    v = (soil_data.get("simulation") or {}).get("verification") or {}
    return bool(v.get("refine", True))


def set_file(soil_data) -> str:
    """The file of a DEM stage holding the set a soil ends with, which its tool jobs, a later
    stage fixing its parameters and ``calibrated_vs_paper`` read: ``final.csv``
    (:func:`final_frame`) where the soil runs the second verification round
    (:func:`refine_settings`, the default), else ``optimum.csv``."""
    return "final.csv" if refine_settings(soil_data) else "optimum.csv"


def refined_cases(refined: pd.DataFrame) -> list[str]:
    """The case ids a ``refined.csv`` frame moves to a second-round set."""
    return refined.loc[refined["refined"].astype(str).str.lower() == "true", "case"].astype(str).tolist()


def _stats(runs: pd.DataFrame, rid):
    if runs.empty:
        return np.nan, np.nan, 0
    ok = runs[(runs["response"] == rid) & (runs["status"].astype(str) == "ok")]
    vals = pd.to_numeric(ok["value"], errors="coerce").to_numpy(float)
    vals = vals[np.isfinite(vals)]
    n = int(vals.size)
    return (float(vals.mean()) if n else np.nan, float(vals.std(ddof=1)) if n > 1 else np.nan, n)


def _unbiased_miss(stage: dict, cal: pd.DataFrame, tgt: dict, stats: dict, pred: dict, missed) -> str:
    """Why a case that missed keeps its set though no response shows a bias, per missed
    response: seed scatter only where the miss is within two standard errors of the mean
    (sd / sqrt(n)); where it is larger the surface's own prediction misses and the seeds agree
    with it (a limit of the design region where the set has factors on its bounds,
    :func:`soilcal.chain.stage.factors_on_bounds`); with fewer than two seeds there is no
    standard error to tell."""
    from soilcal.chain.stage import factors_on_bounds
    from soilcal.chain.verify import region_limit, seed_scatter

    parts = []
    bounds = factors_on_bounds(stage, cal.iloc[0])  # the set's, the same for every response
    for r in missed:
        m, sd, n = stats[r]
        t, p = tgt[r], pred[r]
        sem, scatter = seed_scatter(m, sd, n, t)
        if scatter is None:
            parts.append(f"{r}: {n} verification seed{'' if n == 1 else 's'}, no standard error: seed scatter "
                         "and bias cannot be told apart")
            continue
        two_se = 2.0 * sem
        if scatter:
            parts.append(f"{r}: the miss {m - t:+.3g} is within two standard errors ({two_se:.3g}) of the mean "
                         f"of {n} seeds (seed scatter)")
            continue
        where = region_limit(bounds, ": the surface does not reach the target there")
        parts.append(f"{r}: the miss {m - t:+.3g} is more than seed scatter (two standard errors {two_se:.3g} of "
                     f"{n} seeds): the surface itself predicts {p:.4g} at this set, {p - t:+.3g} from the "
                     f"target{where}")
    return ("missed, but the verification means differ from the surface's prediction by no more than two "
            "standard errors of the seeds' mean and the surface's prediction together (no bias to correct); "
            + "; ".join(parts))


def _kept(case_id, cal: pd.DataFrame, note: str, columns) -> dict:
    row = {c: cal[c].iloc[0] for c in columns if c in cal.columns} if len(cal) else {}
    return row | {"case": case_id, "round": 1, "refined": False, "calibrated": bool(len(cal)),
                  "move_coded": 0.0, "region": "inside", "note": note}


def search_region(stage: dict, wider: dict | None) -> tuple[np.ndarray, np.ndarray]:
    """Coded lower and upper bounds of the second round's search past the box: each factor's
    screening or declared range ``wider[symbol] = (low, high, origin)`` (actual units,
    :func:`soilcal.chain.stage.screening_ranges`) cut to :data:`BEYOND_HALF_WIDTHS` past the
    box; [-1, 1] for a factor without one."""
    from soilcal.chain.stage import bounds

    syms, low, high = bounds(stage)
    centre, half = (low + high) / 2.0, (high - low) / 2.0
    lo, hi = np.full(len(syms), -1.0), np.full(len(syms), 1.0)
    for j, s in enumerate(syms):
        if s in (wider or {}):
            a, b = ((float(v) - centre[j]) / half[j] for v in wider[s][:2])
            lo[j] = min(-1.0, max(a, -1.0 - BEYOND_HALF_WIDTHS))
            hi[j] = max(1.0, min(b, 1.0 + BEYOND_HALF_WIDTHS))
    return lo, hi


def beyond_text(stage: dict, x, wider: dict | None) -> str:
    """Which factors of the coded set ``x`` lie outside the box and how far, as text (empty
    when none does)."""
    from soilcal.chain.stage import bounds

    syms, low, high = bounds(stage)
    centre, half = (low + high) / 2.0, (high - low) / 2.0
    parts = []
    for j, s in enumerate(syms):
        xj = float(x[j])
        if abs(xj) <= 1.0 + 1e-9:
            continue
        side, b = ("low", low[j]) if xj < 0 else ("high", high[j])
        parts.append(f"{s} = {centre[j] + xj * half[j]:.4g} ({abs(xj) - 1.0:.2f} half-widths past its {side} bound "
                     f"{b:g}, inside its {wider[s][2]})")
    return "; ".join(parts)


def search_ranges_text(stage: dict, wider: dict | None, unused=()) -> str:
    """The ``search_ranges`` column of ``refined.csv``: each factor's range past the box and
    where it comes from, or that every factor stays in the box; ``unused``: the declared ranges
    the stage's second round does not use (:func:`soilcal.chain.stage.unused_search_ranges`),
    named as such."""
    from soilcal.chain.stage import bounds

    syms = bounds(stage)[0]
    parts = [f"{s}: {wider[s][2]}" for s in syms if s in (wider or {})]
    if parts:
        text = "; ".join(parts)
    elif unused:
        text = "none: every factor stays in the design box (design: printed, compared point by point with the paper)"
    else:
        text = ("none: every factor stays in the design box (no simulated screening and no simulation.search_ranges "
                "entry gives a wider range)")
    return text + ("; not used: " + "; ".join(unused) if unused else "")


def _local_row(stage, cid, cal, syms, centre, half, x0, tgt, stats, models, frames, local, h, lo_w, hi_w,
               wider, columns) -> dict:
    """The second round of a case with a local design at x0 (:mod:`soilcal.chain.local`):
    the surfaces corrected to first order there by the DEM's plane through the local runs and
    the first round's seeds, the smallest move within the trust region meeting every target,
    or the compromise there where it promises :data:`COMPROMISE_GAIN` points less worst error."""
    from soilcal.chain import local as lc
    from soilcal.optimise.correction import Shifted, corrected_set

    corrected, said, bias, cov = {}, [], {}, {}
    for r in tgt:
        pl = lc.plane(frames, local, r, syms, centre, half, x0)
        s0 = float(models[r].predict(x0[None, :])[0])
        if pl is None:  # too few runs measured: the constant shift of the surface, as without a design
            b = stats[r][0] - s0
            corrected[r], bias[r], cov[r] = Shifted(models[r], b), b, None
            said.append(f"{r}: too few local runs measured for a plane; the surface shifted by {b:+.3g}")
            continue
        level, g, cg, n, sd = pl["level"], pl["slope"], pl["cov"], pl["runs"], pl["sd"]
        gs = lc.gradient(models[r], x0)
        corrected[r] = lc.FirstOrder(models[r], level - s0, g - gs, x0)
        bias[r], cov[r] = level - s0, cg
        tiny = 1e-9 * max(1.0, float(np.max(np.abs(np.r_[g, gs]))))  # rounding, said as 0

        def num(v):
            return f"{(v if abs(v) > tiny else 0.0):+.3g}"
        slopes = ", ".join(f"{sy} {num(a)} (se {math.sqrt(max(v, 0.0)):.2g}; surface {num(b)})"
                           for sy, a, v, b in zip(syms, g, np.diag(cg), gs))
        said.append(f"{r}: level {level:.4g} at the first set (its seeds' mean; surface {s0:.4g}), slope per coded "
                    f"unit {slopes}, the first set standing {pl['curvature']:+.3g} (se {pl['curvature_se']:.2g}) off "
                    f"the design's plane there, from {n} runs of {pl['seeds']} seeds (residual SD of one seed "
                    f"{sd:.3g})")
    lo_t, hi_t = np.maximum(lo_w, x0 - lc.TRUST * h), np.minimum(hi_w, x0 + lc.TRUST * h)
    res = corrected_set(corrected, tgt, {}, x0, lower=lo_t, upper=hi_t)
    x = res["x_coded"]

    def worst(xc):
        return max(abs(float(corrected[r].predict(xc[None, :])[0]) - t) / abs(t) * 100 for r, t in tgt.items())
    n_local = len(local)  # one run file per point
    lead = (f"local design at the first set ({n_local} points at +- {h:g} coded, each with a design point's "
            f"seeds, with the first round's seeds there): " + "; ".join(said) + "; the surface corrected to the "
            "DEM's level and slope there (first-order model management)")
    trust = f"within the trust region (+- {lc.TRUST * h:g} coded about the first set, inside the search region)"
    w0, w1 = worst(x0), worst(x)
    if not res["success"] and w1 > w0 - COMPROMISE_GAIN:
        return _kept(cid, cal, f"{lead}: it reaches no set meeting every target {trust} (its least-squares "
                     f"compromise: worst error {w1:.2g} % against {w0:.2g} % at the first set)", columns) | {
            f"bias_{r}": b for r, b in bias.items()} | {"local_points": n_local}
    row = {"case": cid, "round": 2, "refined": True, "calibrated": True}
    row.update({f"{s}_coded": float(x[j]) for j, s in enumerate(syms)})
    row.update({s: float(centre[j] + x[j] * half[j]) for j, s in enumerate(syms)})
    for r, m in models.items():
        row[r] = float((corrected[r] if r in corrected else m).predict(x[None, :])[0])
    row.update({f"bias_{r}": b for r, b in bias.items()})
    dx = x - x0
    # the corrected surface's change from x0 is the plane's to first order: its slope's error
    row.update({f"surface_change_se_{r}": (float(math.sqrt(max(dx @ cov[r] @ dx, 0.0))) if cov.get(r) is not None
                                           else models[r].change_se(x0, x)) for r in tgt})
    row["move_coded"] = res["move"]
    past = beyond_text(stage, x, wider)
    row["region"] = "beyond" if past else "inside"
    row["note"] = (f"{lead}; " + (f"smallest move (coded {res['move']:.3f}) {trust} at which the corrected surface "
                                  "meets every target" if res["success"] else
                                  f"compromise {trust}: worst error {w1:.2g} % against {w0:.2g} % at the first set")
                   + (f"; beyond the design region: {past}" if past else ""))
    row["local_points"] = n_local
    return row


def refine_frame(stage: dict, table: pd.DataFrame, targets: dict, optimum: pd.DataFrame,
                 runs: dict[str, list[pd.DataFrame]], wider: dict | None = None, unused=(),
                 local: dict[str, list[pd.DataFrame]] | None = None, half_width: float | None = None) -> pd.DataFrame:
    """``refined.csv`` of one stage (module docstring).  ``table``: the stage's responses
    (design points), ``runs``: case id -> the first round's verification frames at the soil's
    own preset, ``wider``: symbol -> (low, high, origin), the range each factor may be searched over
    (:func:`soilcal.chain.stage.screening_ranges`; none: every factor stays in the box),
    ``unused``: the declared ranges it does not use (:func:`search_ranges_text`); ``local``:
    case id -> the run frames of its local design at the first set (:mod:`soilcal.chain.local`,
    of half-width ``half_width``), which a biased case's move then follows instead of the
    constantly shifted surface."""
    from soilcal.chain.stage import bounds, calibrated_rows, fit_stage, goal_values
    from soilcal.optimise import desirability_optimise
    from soilcal.optimise.correction import Shifted, corrected_set, significant_bias

    opt = stage.get("optimise") or {}
    syms, low, high = bounds(stage)
    centre, half = (low + high) / 2.0, (high - low) / 2.0
    lo_w, hi_w = search_region(stage, wider)
    can_leave = bool(np.any(lo_w < -1.0) or np.any(hi_w > 1.0))
    fits = None
    rows = []
    for case in opt.get("cases", []):
        cid = case["id"]
        cal = calibrated_rows(optimum, cid)
        goals = goal_values(case["goals"], targets)
        aimed = {r: float(g["value"]) for r, g in goals.items()
                 if g.get("goal") == "target" and g.get("value") is not None}
        # a target of 0 has no relative band to miss (the verification gives it no error either)
        tgt = {r: v for r, v in aimed.items() if math.isfinite(v) and v != 0.0}
        columns = [f"{s}_coded" for s in syms] + list(syms) + list(goals)
        if not len(cal):
            rows.append(_kept(cid, cal, "no calibrated set (see optimum.csv)", columns))
            continue
        if not tgt:
            rows.append(_kept(cid, cal, "no target value to correct towards" + (
                f" (a target of 0 has no {TOLERANCE_PERCENT:g} % band: {', '.join(aimed)})" if aimed else ""),
                columns))
            continue
        frames = runs.get(cid, [])
        done = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
        stats = {r: _stats(done, r) for r in tgt}
        pred = {r: float(cal[r].iloc[0]) for r in tgt}
        missed = [r for r, (m, _, n) in stats.items()
                  if n and abs(m - tgt[r]) / abs(tgt[r]) * 100 > TOLERANCE_PERCENT]
        if not any(n for _, _, n in stats.values()):
            rows.append(_kept(cid, cal, "no verification run succeeded", columns))
            continue
        if not missed:
            rows.append(_kept(cid, cal, "the first round meets every target within 2 %", columns))
            continue
        if fits is None:
            fits = {sf.response: (sf.reduced if opt.get("model", "reduced") == "reduced" else sf.full)
                    for sf in fit_stage(stage, table)}
        x0 = np.array([(float(cal[s].iloc[0]) - centre[j]) / half[j] for j, s in enumerate(syms)])
        # the bias against the seeds' and the surface's standard errors together
        bias = {r: significant_bias(m, sd, n, pred[r], fits[r].predict_se(x0) if r in fits else 0.0)
                for r, (m, sd, n) in stats.items()}
        unbiased = ""
        if not any(bias.values()):
            from soilcal.chain.verify import seed_scatter

            unbiased = _unbiased_miss(stage, cal, tgt, stats, pred, missed)
            # the surface itself misses beyond seed scatter: only a move past the box can help
            if not (can_leave and any(seed_scatter(*stats[r], tgt[r])[1] is False for r in missed)):
                rows.append(_kept(cid, cal, unbiased, columns))
                continue
        models = {r: fits[r] for r in goals if r in fits}
        if local and local.get(cid) and half_width and any(bias.values()):
            rows.append(_local_row(stage, cid, cal, syms, centre, half, x0, tgt, stats, models, frames, local[cid],
                                   half_width, lo_w, hi_w, wider, columns))
            continue
        try:
            sols = desirability_optimise({r: Shifted(m, bias.get(r, 0.0)) for r, m in models.items()},
                                         goals, n_solutions=5, seed=0)
            starts = sols[[f"{s}_coded" for s in syms]].to_numpy(float)
        except InputError:
            starts = np.empty((0, len(syms)))
        res = corrected_set({r: models[r] for r in tgt}, tgt, bias, x0, starts=starts)
        btxt = ", ".join(f"{r} {b:+.3g}" for r, b in bias.items() if b)

        def worst(xc):
            return max(abs(float(models[r].predict(xc[None, :])[0]) + bias.get(r, 0.0) - t) / abs(t) * 100
                       for r, t in tgt.items())
        inside_text = ""
        if not res["success"] and can_leave:
            # move the region: the same search past the box, within the screening ranges and the
            # trust region; its compromise only where it promises COMPROMISE_GAIN more than the box's
            out = corrected_set({r: models[r] for r in tgt}, tgt, bias, x0,
                                starts=[*starts, res["x_coded"]], lower=lo_w, upper=hi_w)
            if out["success"] or worst(out["x_coded"]) <= worst(res["x_coded"]) - COMPROMISE_GAIN:
                inside_text = (f"inside the design region the {'corrected ' if btxt else ''}surface reaches no set "
                               "meeting every target; its compromise there: worst error "
                               f"{worst(res['x_coded']):.2g} %")
                res = out
        x = res["x_coded"]
        past = beyond_text(stage, x, wider)
        if unbiased and not (past and (res["success"] or worst(x) <= worst(x0) - COMPROMISE_GAIN)):
            rows.append(_kept(cid, cal, unbiased, columns))
            continue
        lead = (f"bias {btxt}: the corrected surface" if btxt else
                "no bias (the verification means agree with the surface at the first set): the surface itself")
        if not res["success"]:
            # the corrected surfaces' least-squares compromise, if it promises a worst relative
            # error lower by COMPROMISE_GAIN percentage points than the corrected surfaces at x0
            w0, w1 = worst(x0), worst(x)
            region = ("inside the design region" if not can_leave else
                      "inside the design region or past it where a factor may leave it (" + ", ".join(
                          f"{sy} coded {a:.3g} to {b:.3g}" for sy, a, b in zip(syms, lo_w, hi_w)
                          if a < -1.0 or b > 1.0)
                      + f": at most {BEYOND_HALF_WIDTHS:g} box half-width past a bound and within its search "
                      "range, column search_ranges)")
            why = (f"{lead} does not reach every target {region} "
                   f"(its least-squares compromise: worst error {w1:.2g} % against {w0:.2g} % at the first set)")
            if w1 > w0 - COMPROMISE_GAIN:
                rows.append(_kept(cid, cal, why, columns) | {f"bias_{r}": b for r, b in bias.items()})
                continue
        row = {"case": cid, "round": 2, "refined": True, "calibrated": True}
        for j, s in enumerate(syms):
            row[f"{s}_coded"] = float(x[j])
        for j, s in enumerate(syms):
            row[s] = float(centre[j] + x[j] * half[j])
        for r, m in models.items():
            row[r] = float(m.predict(x[None, :])[0]) + bias.get(r, 0.0)
        row.update({f"bias_{r}": b for r, b in bias.items()})
        # how well the surface knows its own change between the two sets (the verification
        # compares it with the DEM's, soilcal.chain.verify.round_change)
        row.update({f"surface_change_se_{r}": m.change_se(x0, x) for r, m in models.items()})
        row["move_coded"] = res["move"]
        row["region"] = "beyond" if past else "inside"
        if res["success"]:
            note = ((f"bias-corrected: verification mean minus surface at the first set {btxt}" if btxt else
                     "no bias (the verification means agree with the surface at the first set)")
                    + f"; smallest move (coded {res['move']:.3f}) at which the "
                    f"{'corrected ' if btxt else ''}surface meets every target")
        else:
            note = ("bias-corrected compromise: " if btxt else "compromise: ") + why
        if past:
            note += (f"; extrapolated beyond the design region ({inside_text}): {past}; the surfaces were "
                     "fitted inside the box only, so the verification at this set judges it")
        row["note"] = note
        rows.append(row)
    out = pd.DataFrame(rows)
    lead = ["case", "round", "refined", "calibrated"]
    if not len(out):
        return pd.DataFrame(columns=lead + ["note", "search_ranges"])
    out["search_ranges"] = search_ranges_text(stage, wider, unused)
    return out[lead + [c for c in out.columns if c not in lead]]


def runs_by_case(paths, stage_id: str) -> dict[str, list[pd.DataFrame]]:
    """Run files ``.../<stage>/<case>/<k>.csv`` of one stage, read and grouped by case id
    (files of other stages are left out)."""
    from pathlib import Path

    got: dict[str, list[pd.DataFrame]] = {}
    for p in map(Path, paths):
        if p.parent.parent.name == stage_id:
            got.setdefault(p.parent.name, []).append(pd.read_csv(p))
    return got


def _refined_from_files(stage_json, responses_csv, targets_csv, optimum_csv, run_paths, soil_data,
                        local_paths=(), half_width=None):
    from pathlib import Path

    from soilcal.chain.files import read_stage, read_targets
    from soilcal.chain.stage import screening_ranges, unused_search_ranges
    from soilcal.config.tables import read_table

    stage = read_stage(stage_json)
    runs = runs_by_case(run_paths, stage["id"])
    wider = screening_ranges(soil_data, stage) if soil_data else {}
    unused = unused_search_ranges(soil_data, stage) if soil_data else []
    optimum = pd.read_csv(optimum_csv)
    local = runs_by_case(local_paths, stage["id"]) if local_paths else None
    df = refine_frame(stage, read_table(Path(responses_csv)), read_targets(targets_csv), optimum, runs,
                      wider, unused, local, half_width)
    return stage, optimum, wider, df


def write_refined(stage_json, responses_csv, targets_csv, optimum_csv, run_paths, out,
                  soil_data: dict | None = None, local_paths=(), half_width: float | None = None,
                  local_csv=None) -> pd.DataFrame:
    """``refined.csv`` of one stage from its files and the first round's verification runs
    ``verify/<preset>/<stage>/<case>/<k>.csv`` (the soil's own preset only); ``soil_data``
    (the soil config) gives the screening or declared ranges the second round may move into
    (:func:`soilcal.chain.stage.screening_ranges`); ``local_paths``: the runs of the local
    designs ``local/<stage>/<case>/<point>.csv`` (:mod:`soilcal.chain.local`) of the stage's
    ``local_csv`` (``<stage>/local.csv``, required with ``half_width``; every point's run must be
    among ``local_paths``, else InputError)."""
    from pathlib import Path

    from soilcal.chain.files import write_csv

    if half_width is not None:
        # the local design's points and runs must all be in: a refine job that Snakemake ran
        # before its checkpoint's output was known would silently fall back to the constant shift
        if not local_csv:
            raise InputError(str(out), "input.local", "the stage's local.csv (checkpoint local_design) where the soil "
                             "runs local designs (simulation.verification.local); target it, or run without "
                             "forcing refine", "none given")
        pts = pd.read_csv(local_csv)
        want = {str(Path(local_csv).parent.parent / "local" / Path(local_csv).parent.name / str(c) / f"{int(k)}.csv")
                for c, k in zip(pts["case"], pts["point"])}
        have = {str(Path(p)) for p in local_paths}
        if want - have:
            raise InputError(str(out), "input.local_runs", f"the runs of every point of {local_csv}",
                             f"missing {sorted(want - have)[0]}")
    df = _refined_from_files(stage_json, responses_csv, targets_csv, optimum_csv, run_paths, soil_data,
                             local_paths, half_width)[3]
    write_csv(df, out)
    return df


def write_local(stage_json, responses_csv, targets_csv, optimum_csv, run_paths, out,
                soil_data: dict | None = None, half_width: float | None = None) -> pd.DataFrame:
    """``local.csv`` of one stage (:func:`soilcal.chain.local.local_frame`): the local design
    of every case the second round would move because of a bias, from the same files as
    :func:`write_refined` (before any local run)."""
    from soilcal.chain.files import write_csv
    from soilcal.chain.local import local_frame

    stage, optimum, wider, refined = _refined_from_files(stage_json, responses_csv, targets_csv, optimum_csv,
                                                         run_paths, soil_data)
    df = local_frame(stage, refined, optimum, half_width, wider)
    write_csv(df, out)
    return df


def final_frame(soil_data: dict, stage: dict, optimum: pd.DataFrame, targets: dict,
                runs: dict[str, list[pd.DataFrame]], refined: pd.DataFrame,
                refined_runs: dict[str, list[pd.DataFrame]]) -> pd.DataFrame:
    """``final.csv`` of one stage: the set each case ends with, in the columns of
    ``refined.csv``.  A case moved to a second-round set keeps its ``refined.csv`` row where the
    verification of both rounds (``runs``: case id -> first-round frames at the soil's preset,
    the one the second round runs at, ``refined_runs``: the second round's) makes the second round final
    (:func:`soilcal.chain.verify.better_round`, the rule of ``verification.csv``'s ``final``);
    otherwise its row is the first round's calibrated set of ``optimum.csv`` with
    ``round = 1``, ``refined = False`` and a note saying why.  Other cases are their
    ``refined.csv`` rows."""
    from soilcal.chain.stage import bounds, calibrated_rows, goal_values
    from soilcal.chain.verify import better_round, verification_frame

    v = verification_frame(soil_data, stage, optimum, targets, runs, refined, refined_runs)
    moved = set(refined_cases(refined))
    syms = bounds(stage)[0]
    rows = []
    for case in (stage.get("optimise") or {}).get("cases", []):
        cid = str(case["id"])
        ref = refined[refined["case"].astype(str) == cid]
        mine = v[v["case"].astype(str) == cid]
        keep, why = (better_round(mine[mine["round"] == 1].to_dict("records"),
                                  mine[mine["round"] == 2].to_dict("records")) if cid in moved else (True, ""))
        if keep:
            rows += ref.to_dict("records")
            continue
        columns = [f"{s}_coded" for s in syms] + list(syms) + list(goal_values(case["goals"], targets))
        row = _kept(cid, calibrated_rows(optimum, cid), f"second round at {_levels_text(ref, syms)} not kept: {why}",
                    columns)
        if "search_ranges" in ref.columns:
            row["search_ranges"] = ref["search_ranges"].iloc[0]
        rows.append(row)
    return pd.DataFrame(rows, columns=list(refined.columns))


def _levels_text(ref: pd.DataFrame, syms) -> str:
    return ", ".join(f"{s} = {float(ref[s].iloc[0]):.4g}" for s in syms if s in ref.columns) if len(ref) else "?"


def write_final(soil_data: dict, stage_json, targets_csv, optimum_csv, refined_csv, run_paths, refined_run_paths,
                out) -> pd.DataFrame:
    """``final.csv`` of one stage (:func:`final_frame`) from its files, its first-round
    verification runs ``verify/<preset>/<stage>/<case>/<k>.csv`` (the soil's preset) and its
    second-round runs ``refine/<stage>/<case>/<k>.csv``."""
    from soilcal.chain.files import read_stage, read_targets, write_csv

    stage = read_stage(stage_json)
    df = final_frame(soil_data, stage, pd.read_csv(optimum_csv), read_targets(targets_csv),
                     runs_by_case(run_paths, stage["id"]), pd.read_csv(refined_csv),
                     runs_by_case(refined_run_paths, stage["id"]))
    write_csv(df, out)
    return df
