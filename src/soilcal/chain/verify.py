"""Verification of a calibration: the DEM at the calibrated parameters against the targets,
the papers' tool and process tests, and the calibrated set beside the paper's.

* :func:`verification_frame` - every optimisation case and response at its calibrated set
  (``optimum.csv``, ``calibrated = True``), simulated with ``simulation.verification.replicates``
  seeds apart from the design seeds (``seed + seed_offset + k``): target, simulated mean and
  SD, signed relative error, whether the mean meets the target within 2 %, the response
  surface's prediction at the optimum (and its distance from the target) and the paper's own
  verification numbers (``printed_verification`` of the case) beside them.  A row that misses
  says why (:func:`diagnose`).  A seed whose run failed is counted (``failed_seeds``); where
  others succeeded the status says how many of the seeds failed (never ``ok``) and the note
  names them with the reason, the statistics being those of the others.
* :func:`seeds_frame` - the second verification stage (``simulation.verification.max_replicates``
  above ``replicates``): a case whose first seeds leave a missed target within their scatter
  takes as many seeds as Stein's two-stage rule asks for (:func:`stein_seeds`), up to that cap.
* :func:`tool_frame` - the soil's ``measurements`` (:mod:`soilcal.config.measurements`)
  simulated at the calibrated set of the case each row names.
* :func:`calibrated_vs_paper` - every calibrated parameter beside the paper's calibrated value.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from soilcal.errors import InputError

VERIFY_DEFAULTS = {"replicates": 4, "max_replicates": "replicates (no second stage)", "seed_offset": 10000,
                   "paper": []}
TOLERANCE_PERCENT = 2.0
SURFACE_TOLERANCE = 0.5
VERIFICATION_COLUMNS = ["stage", "case", "round", "response", "unit", "target_id", "target", "target_source", "preset", "n",
                        "seeds", "failed_seeds", "simulated_mean", "simulated_sd", "relative_error_percent",
                        "within_2_percent", "target_sd", "miss_in_target_sd", "predicted", "predicted_minus_target",
                        "particles", "paper_target", "paper_simulated", "paper_relative_error_percent", "status",
                        "final", "note"]
TOOL_COLUMNS = ["measurement", "row", "covariate", "covariate_value", "scenario", "setup", "measure", "unit",
                "preset", "stage", "case", "n", "seeds", "measured", "measured_sd", "simulated_mean",
                "simulated_sd", "relative_error_percent", "paper_simulated", "paper_relative_error_percent",
                "paper_difference", "status", "note"]


def verify_settings(soil_data: dict) -> dict:
    """The soil's ``simulation.verification`` block over :data:`VERIFY_DEFAULTS`;
    ``max_replicates`` defaults to ``replicates`` (one stage, :func:`stein_seeds`)."""
    v = {**VERIFY_DEFAULTS, **((soil_data.get("simulation") or {}).get("verification") or {})}
    if not isinstance(v["max_replicates"], int) or isinstance(v["max_replicates"], bool):
        v["max_replicates"] = int(v["replicates"])
    return v


def first_stage_seeds(soil_data: dict) -> int:
    """Seeds of a case's first verification stage (``simulation.verification.replicates``)."""
    return int(verify_settings(soil_data)["replicates"])


def most_seeds(soil_data: dict) -> int:
    """The most seeds one case's verification takes (``simulation.verification.max_replicates``,
    default its ``replicates``: no second stage); the second calibration round's seeds follow
    them (``seed + seed_offset + most_seeds + k``), so that no round reuses another's seed."""
    v = verify_settings(soil_data)
    return max(int(v["max_replicates"]), int(v["replicates"]))


def two_stage(soil_data: dict) -> bool:
    """Whether the soil's verification may add seeds to a case (:func:`seeds_frame`)."""
    return most_seeds(soil_data) > first_stage_seeds(soil_data)


def verification_cases(soil_data: dict, stage_ids) -> list[tuple[str, str]]:
    """(stage, case) of every optimisation case of the stages ``stage_ids``."""
    out = []
    for st in soil_data["stages"]:
        if st["id"] in stage_ids:
            for c in (st.get("optimise") or {}).get("cases", []):
                out.append((st["id"], c["id"]))
    return out


def _case(stage: dict, case_id: str) -> dict:
    for c in (stage.get("optimise") or {}).get("cases", []):
        if c["id"] == case_id:
            return c
    raise InputError(stage.get("id"), "optimise.cases", f"a case {case_id!r}", None)


def verification_spec(soil, stage: dict, optimum: pd.DataFrame, case_id: str, rep: int,
                      preset: str | None = None, responses=None, design_seeds: bool = False) -> dict:
    """The point spec (:func:`soilcal.chain.sources.point_spec`) of verification replicate
    ``rep`` of one case: the calibrated set, every response the case aims at, one seed; with
    ``preset`` (``paper``) only the responses :func:`paper_responses` admits, at that preset;
    with ``responses`` only those of them (a second verification stage's seed runs only the
    responses its first seeds left undecided, :func:`second_stage_responses`); with
    ``design_seeds`` each response's seeds per design point instead of one (a local design's
    point, :mod:`soilcal.chain.local`), from seed ``rep`` on."""
    from soilcal.chain.sources import point_spec
    from soilcal.chain.stage import calibrated_levels

    v = verify_settings(soil.data)
    levels = calibrated_levels(stage, optimum, case_id)
    case = _case(stage, case_id)
    seed = int(soil.data["seed"]) + int(v["seed_offset"]) + int(rep)
    rids = list(case["goals"])
    if responses is not None:
        some = [r for r in rids if r in set(responses)]
        if not some:
            raise InputError(stage.get("id"), f"optimise.cases.{case_id}.goals",
                             f"a response of the case among {list(responses)}", rids)
        rids = some
    if preset == "paper":
        rids = [r for r in rids if r in paper_responses(soil, rids)]
    spec = point_spec(soil, stage, levels, run=rep, seed=seed, replicates=None if design_seeds else 1,
                      responses=rids)
    if preset:
        for rs in spec["responses"].values():
            rs["preset"] = preset
    return spec


def paper_responses(soil, response_ids) -> list[str]:
    """The responses among ``response_ids`` also verified at the ``paper`` preset
    (``simulation.verification.paper``; none when the soil already runs at that preset)."""
    wanted = set(verify_settings(soil.data)["paper"] or [])
    if not wanted or (soil.data.get("simulation") or {}).get("preset", "quick") == "paper":
        return []
    return [r for r in response_ids if r in wanted]


def not_run_rows(stage_id: str, case: dict, reason: str) -> pd.DataFrame:
    """Rows of a verification replicate that could not run (e.g. the case has no target)."""
    from soilcal.chain.sources import RUN_COLUMNS

    rows = [{c: "" for c in RUN_COLUMNS} | {"stage": stage_id, "run": 0, "response": rid, "status": "not run",
                                              "error": reason, "value": np.nan, "n": 0}
            for rid in case["goals"]]
    return pd.DataFrame(rows, columns=RUN_COLUMNS)


def seed_scatter(mean: float, sd: float, n: int, target: float) -> tuple[float, bool | None]:
    """The standard error of a mean of ``n`` seeds of SD ``sd`` (sd / sqrt(n)) and whether the
    miss ``mean - target`` lies within two of them (seed scatter alone may explain it); NaN
    and None with fewer than two seeds or no finite SD: no scatter to judge the miss by."""
    if n < 2 or not np.isfinite(sd):
        return float("nan"), None
    sem = sd / np.sqrt(n)
    return float(sem), bool(abs(mean - target) <= 2 * sem)


#: the confidence of the interval the second verification stage sizes (:func:`stein_seeds`)
STEIN_LEVEL = 0.95
SEEDS_COLUMNS = ["stage", "case", "response", "preset", "target", "first_seeds", "n", "simulated_mean",
                 "simulated_sd", "relative_error_percent", "band", "undecided", "stein_seeds", "seeds", "capped",
                 "note"]


def stein_seeds(sd0: float, n0: int, half_width: float, level: float = STEIN_LEVEL) -> int:
    """Seeds in all that Stein's two-stage procedure asks for (Stein 1945, Ann. Math. Statist.
    16:243): from a first stage of ``n0`` values with sample SD ``sd0``,
    n = max(n0, ceil((t_{(1 + level)/2, n0 - 1} sd0 / half_width)^2)) values make the ``level``
    confidence interval of the mean, t sd0 / sqrt(n) either side of it, no wider than
    ``half_width`` whatever the true SD.  ``n0`` where the first stage has fewer than two
    values or no finite SD (nothing to size by) or ``half_width`` is not positive."""
    from scipy.stats import t as student_t

    if n0 < 2 or not np.isfinite(sd0) or not (np.isfinite(half_width) and half_width > 0):
        return int(n0)
    q = float(student_t.ppf(0.5 + level / 2.0, n0 - 1))
    return max(int(n0), int(np.ceil((q * sd0 / half_width) ** 2 - 1e-9)))


def seeds_frame(soil_data: dict, stage: dict, optimum: pd.DataFrame, targets: dict,
                runs: dict[str, list[pd.DataFrame]], preset: str) -> pd.DataFrame:
    """How many seeds each case of a stage is verified with, from its first stage's runs
    ``runs`` (case id -> its run frames, :func:`soilcal.chain.refine.runs_by_case`) at the
    soil's own ``preset``: one row per case and targeted response (:data:`SEEDS_COLUMNS`).

    A response is ``undecided`` where the mean of its first-stage seeds misses the 2 % band of
    its target by no more than two standard errors (:func:`seed_scatter`: the row's note would
    say "seed scatter", the seeds cannot tell a miss from a hit); it then asks for
    ``stein_seeds`` (:func:`stein_seeds`, the interval's half-width the band, 2 % of the target).
    ``seeds``, the case's count, is the most any of its responses asks for, at least the first
    stage's and at most ``simulation.verification.max_replicates`` (``capped`` where that cut
    it).  A case that met every target, missed one by more than its seeds scatter, or has no
    calibrated set keeps its first stage's seeds."""
    first, top = first_stage_seeds(soil_data), most_seeds(soil_data)
    rows = []
    for case in (stage.get("optimise") or {}).get("cases", []):
        frames = runs.get(case["id"], [])
        crow = [r for r in _case_rows(soil_data, stage, case, optimum, targets, frames, 1)
                if r["preset"] in (preset, "")]
        here = []
        for r in crow:
            target, n, mean, sd = float(r["target"]), int(r["n"]), r["simulated_mean"], r["simulated_sd"]
            band = TOLERANCE_PERCENT / 100 * abs(target) if np.isfinite(target) else np.nan
            missed = bool(n and np.isfinite(band) and band > 0 and not r["within_2_percent"])
            _, scatter = seed_scatter(mean, sd, n, target) if missed else (np.nan, None)
            undecided = bool(missed and scatter)
            need = stein_seeds(sd, n, band) if undecided else n
            if undecided:
                note = (f"undecided: the miss {mean - target:+.3g} is within two standard errors of the mean of "
                        f"{n} seeds; Stein's rule asks for {need} seeds in all (t quantile of {n - 1} degrees of "
                        f"freedom, SD {sd:.3g}, half-width {band:.3g}, the 2 % band)")
            elif not n:
                note = "no seed gave a value"
            elif missed and scatter is None:
                note = "missed with fewer than two seeds: no scatter to size a second stage by"
            elif missed:
                note = "missed by more than the seeds scatter: decided"
            elif np.isfinite(band):
                note = "met within 2 %"
            else:
                note = "no target value"
            here.append({"stage": stage["id"], "case": case["id"], "response": r["response"],
                         "preset": r["preset"] or preset, "target": target, "first_seeds": len(frames), "n": n,
                         "simulated_mean": mean, "simulated_sd": sd,
                         "relative_error_percent": r["relative_error_percent"], "band": band,
                         "undecided": undecided, "stein_seeds": need, "note": note})
        asked = max([h["stein_seeds"] for h in here if h["undecided"]], default=0)
        total = min(top, max(first, asked))
        for h in here:
            h["seeds"] = total
            h["capped"] = bool(asked > total)
            if h["undecided"] and asked > total:
                h["note"] += f"; capped at simulation.verification.max_replicates {top}"
        rows += here or [{"stage": stage["id"], "case": case["id"], "response": "", "preset": preset,
                          "target": np.nan, "first_seeds": len(frames), "n": 0, "simulated_mean": np.nan,
                          "simulated_sd": np.nan, "relative_error_percent": np.nan, "band": np.nan,
                          "undecided": False, "stein_seeds": 0, "seeds": first, "capped": False,
                          "note": "no targeted response"}]
    return pd.DataFrame(rows, columns=SEEDS_COLUMNS)


def case_seeds(frame: pd.DataFrame) -> dict[str, int]:
    """Each case's seed count of a :func:`seeds_frame` (``verify_seeds.csv``)."""
    return {str(c): int(g["seeds"].max()) for c, g in frame.groupby("case", sort=False)}


def second_stage_responses(frame: pd.DataFrame, case_id: str) -> list[str] | None:
    """The responses a case's second-stage seeds run (``verify_seeds.csv``, :func:`seeds_frame`):
    the ones its first seeds left undecided. A response already decided (met, or missed by
    more than its seeds scatter) gains nothing from more seeds, and where it is another
    scenario (the vineyard soil's drum beside its heap) skipping it saves most of the time.
    None (every response) where the case has no undecided response."""
    g = frame[frame["case"].astype(str) == str(case_id)]
    und = g[g["undecided"].astype(str).str.lower() == "true"]["response"].astype(str).tolist()
    return und or None


def write_seeds(soil_data: dict, stage_json, optimum_csv, targets_csv, run_paths, preset: str, out) -> pd.DataFrame:
    """``verify_seeds.csv`` of one stage (:func:`seeds_frame`) from its files and the first
    stage's verification runs ``verify/<preset>/<stage>/<case>/<k>.csv``."""
    from soilcal.chain.files import read_stage, read_targets, write_csv
    from soilcal.chain.refine import runs_by_case

    stage = read_stage(stage_json)
    df = seeds_frame(soil_data, stage, pd.read_csv(optimum_csv), read_targets(targets_csv),
                     runs_by_case(run_paths, stage["id"]), preset)
    write_csv(df, out)
    return df


def region_limit(on_bounds, otherwise: str) -> str:
    """The end of a note on a surface that misses its target: the set's factors on a bound of
    the design region (:func:`soilcal.chain.stage.factors_on_bounds`) and that the target lies
    outside it, or ``otherwise`` where none is on a bound."""
    return f"; {', '.join(on_bounds)}: the target lies outside the design region" if on_bounds else otherwise


def diagnose(mean: float, sd: float, n: int, target: float, predicted: float | None,
             ci: tuple[float, float] | None = None, replicates: int | None = None,
             model: str | None = None, on_bounds=None, target_sd: float | None = None) -> str:
    """Why a verification mean misses its target by more than 2 % (empty when it meets it).

    * the surface cannot reach the target: the prediction at the optimum is more than 0.5
      from the target (a model limit) and the 95 % confidence interval of the surface's mean
      there, ``ci`` where given, excludes the target; where the set has factors on a bound of
      the design region (``on_bounds``, :func:`soilcal.chain.stage.factors_on_bounds`) the
      note names them: the surface comes closest on the region's boundary, so the target lies
      outside the region; otherwise the limit is the surface's within the region;
    * surface scatter: the prediction misses by more than 0.5 but its confidence interval
      contains the target: the design points' own seed scatter leaves open whether the
      design region reaches it (replicates per design point would tell; with ``replicates``,
      the seeds per design point of the design, the note says how many would narrow the
      interval to +-0.5: the interval's half-width h shrinks as 1/sqrt(seeds) where the design
      points scatter by their seeds alone, so about ceil(replicates (h / 0.5)^2), a lower
      bound where the quadratic also lacks fit; ``model``, the stage's optimisation model,
      ``full`` or ``reduced``, is named, as the interval and the count are that model's: a
      full quadratic's many terms widen it where the data support fewer);
    * seed scatter: the miss is within two standard errors of the mean (sd / sqrt(n)), so
      more replicates (or larger heaps) are needed to tell; the note says how many seeds
      would make two standard errors as small as the 2 % band,
      n = ceil((2 sd / (0.02 |target|))^2), so that a user can judge whether seeds or larger
      heaps are the way;
    * surface bias: the surface predicts the target but the DEM mean differs from its
      prediction by more than two standard errors of the difference, the seeds' mean's and
      the surface's own together (the same test as the second round's,
      :func:`soilcal.optimise.correction.significant_bias`; the surface's standard error read
      from its 95 % interval ``ci`` as its half-width over 1.96, at most t_{0.975, df} / 1.96
      times the true one): the quadratic misrepresents the DEM at the optimum;
    * surface uncertainty: the surface predicts the target and the mean differs from it by
      more than the seeds explain but not by more than the surface's and the seeds' errors
      together: the design points' scatter leaves the surface too uncertain there to tell;
    * undecided: fewer than two seeds (failed seeds can leave one): no scatter to tell seed
      scatter from a surface bias.

    Whatever the reason, where the SD the soil gives with the target (``target_sd``, the
    spread of the repeated measurements the target is the mean of) is at least the miss, the
    note ends saying so: the simulated mean lies inside one SD of the measurements, the
    convention by which DEM calibrations often judge a simulated value against a measured
    range (it is not a test of the two means: the target mean's own standard error is
    smaller by the square root of its repeats).
    """
    if not np.isfinite(target) or target == 0 or not np.isfinite(mean):
        return ""
    rel = abs(mean - target) / abs(target) * 100
    if rel <= TOLERANCE_PERCENT:
        return ""
    notes = []
    if predicted is not None and np.isfinite(predicted) and abs(predicted - target) > SURFACE_TOLERANCE:
        lo, hi = ci if ci is not None else (np.nan, np.nan)
        known = np.isfinite(lo) and np.isfinite(hi)
        if known and lo <= target <= hi:
            how = ""
            if replicates:
                seeds = int(np.ceil(replicates * ((hi - lo) / 2 / SURFACE_TOLERANCE) ** 2 - 1e-9))
                how = (f": about {seeds} seeds per design point, {int(replicates)} now, would narrow the "
                       f"interval to +-{SURFACE_TOLERANCE:g} if the points scatter by their seeds alone")
            which = f" ({model} model)" if model else ""
            notes.append(f"surface scatter: the response surface{which} predicts {predicted:.2f} at its best "
                         f"set, {predicted - target:+.2f} from the target, but the 95 % confidence "
                         f"interval of its mean there, {lo:.2f} to {hi:.2f}, contains the target: the "
                         "design points' seed scatter leaves open whether the design region reaches "
                         f"it (replicates per design point would tell{how})")
        else:
            band = f" (95 % confidence interval {lo:.2f} to {hi:.2f})" if known else ""
            where = region_limit(on_bounds, ", within the design region")
            notes.append(f"model limit: the response surface predicts {predicted:.2f} at its best set, "
                         f"{predicted - target:+.2f} from the target{band}{where}")
    sem, scatter = seed_scatter(mean, sd, n, target)
    if scatter:
        band = TOLERANCE_PERCENT / 100 * abs(target)
        need = int(np.ceil((2 * sd / band) ** 2 - 1e-9))  # an exact square is not rounded up
        notes.append(f"seed scatter: the miss {mean - target:+.2f} is within two standard errors "
                     f"({2 * sem:.2f}) of the mean of {n} seeds; more seeds or larger heaps would tell "
                     f"(at this seed SD {sd:.2f}, {need} seeds would bring two standard errors within "
                     f"the {TOLERANCE_PERCENT:g} % band of +-{band:.2f})")
    elif not notes and scatter is None:
        notes.append(f"undecided: {n} seed{'s' if n != 1 else ''} gave {mean:.2f} with no scatter to judge the miss "
                     f"{mean - target:+.2f} by (it takes two seeds), so seed scatter and a surface bias cannot be "
                     "told apart; more seeds would tell")
    elif not notes and predicted is not None and np.isfinite(predicted):
        from soilcal.optimise.correction import SIGNIFICANCE, significant_bias

        lo, hi = ci if ci is not None else (np.nan, np.nan)
        pse = (hi - lo) / 2.0 / 1.96 if np.isfinite(lo) and np.isfinite(hi) else 0.0
        if significant_bias(mean, sd, n, predicted, pse):
            notes.append(f"surface bias: the surface predicts the target but {n} seeds give {mean:.2f} "
                         f"(+-{sem:.2f} standard error): the quadratic "
                         "misrepresents the DEM at the optimum (see the lack-of-fit test)")
        else:
            notes.append(f"surface uncertainty: the surface predicts {predicted:.2f} and {n} seeds give {mean:.2f} "
                         f"(+-{sem:.2f} standard error), apart by no more than {SIGNIFICANCE:g} standard errors "
                         f"of the two together (the surface's {pse:.2f}): the design points' scatter leaves the "
                         "surface too uncertain at the optimum to tell a bias (replicates per design point or more "
                         "seeds would)")
    elif not notes:
        notes.append(f"the mean of {n} seeds, {mean:.2f}, misses the target by more than the seed scatter "
                     "explains (no surface prediction at this set)")
    if target_sd is not None and np.isfinite(target_sd) and target_sd > 0 and abs(mean - target) <= target_sd:
        notes.append(f"inside the measured spread: the miss {mean - target:+.2f} is no larger than the SD "
                     f"{target_sd:.2f} of the measurements the target is the mean of")
    return "; ".join(notes)


def verification_frame(soil_data: dict, stage: dict, optimum: pd.DataFrame, targets: dict,
                       runs: dict[str, list[pd.DataFrame]], refined: pd.DataFrame | None = None,
                       refined_runs: dict[str, list[pd.DataFrame]] | None = None) -> pd.DataFrame:
    """Verification rows of one stage (module docstring); ``runs``: case id -> its replicate
    run frames.  With ``refined`` (:mod:`soilcal.chain.refine`) a case refined to a
    bias-corrected set gets second rows (``round`` 2) from ``refined_runs`` at that set."""
    from soilcal.chain.refine import refined_cases

    moved = refined_cases(refined) if refined is not None else []
    rows = []
    for case in (stage.get("optimise") or {}).get("cases", []):
        first = _case_rows(soil_data, stage, case, optimum, targets, runs.get(case["id"], []), 1)
        rows += first
        if case["id"] in moved:
            second = _case_rows(soil_data, stage, case, refined, targets, (refined_runs or {}).get(case["id"], []), 2)
            ref = refined[refined["case"].astype(str) == str(case["id"])]
            for r2 in second:
                r1 = [r for r in first if r["response"] == r2["response"] and r["preset"] == r2["preset"]]
                rid = r2["response"]
                bias = ref[f"bias_{rid}"].iloc[0] if f"bias_{rid}" in ref.columns else 0.0
                se = ref[f"surface_change_se_{rid}"].iloc[0] if f"surface_change_se_{rid}" in ref.columns else 0.0
                lp = ref["local_points"].iloc[0] if "local_points" in ref.columns and len(ref) else np.nan
                local = bool(pd.notna(lp) and float(lp) > 0)
                change = round_change(r1[0], r2, bias, se, local) if r1 and len(ref) else ""
                if change:
                    r2["note"] = "; ".join(x for x in (r2["note"], change) if x)
            _better_round(first, second)
            rows += second
    for r in rows:
        r.setdefault("final", True)
    return pd.DataFrame(rows, columns=VERIFICATION_COLUMNS)


def _measured(r: dict) -> bool:
    """Whether a verification row has a finite error (some seed gave a value)."""
    return bool(r.get("n", 0)) and np.isfinite(float(r["relative_error_percent"]))


def _miss_se(r: dict, other: dict | None) -> float:
    """The standard error (% of the target) of one verification row's relative miss: its seeds'
    sd / sqrt(n).  A row with fewer than two seeds has no sd of its own; it takes the other
    round's sd of the same response and preset (``other``; the seed scatter of one response at
    two nearby sets), still over its own n seeds.  nan where neither round has two seeds."""
    n, t = int(r["n"]), abs(float(r.get("target", np.nan)))
    sd = float(r.get("simulated_sd", np.nan)) if n > 1 else np.nan
    if not np.isfinite(sd) and other is not None and int(other.get("n", 0)) > 1:
        sd = float(other.get("simulated_sd", np.nan))
    return sd / np.sqrt(n) / t * 100 if n > 0 and np.isfinite(sd) and t > 0 else np.nan


def _worst_miss(rows: list[dict], others: list[dict]) -> tuple[float, float, str]:
    """The largest relative miss (%) over ``rows`` (all measured), its standard error
    (:func:`_miss_se`, with ``others``: the other round's rows) and its response (preset)."""
    r = max(rows, key=lambda x: abs(float(x["relative_error_percent"])))
    other = next((o for o in others if (o["response"], o["preset"]) == (r["response"], r["preset"])), None)
    return abs(float(r["relative_error_percent"])), _miss_se(r, other), f"{r['response']} ({r['preset']})"


def better_round(first: list[dict], second: list[dict]) -> tuple[bool, str]:
    """Whether a case ends with its second round's set, and why not (empty when it does).  The
    DEM runs judge the move, not the surface that proposed it, which is often extrapolated.
    The rounds are compared over the (response, preset) pairs both measured (a finite error:
    some seed gave a value), so a response the first round never measured does not count
    against the second.  The second round is final only where (a) every pair the first round
    measured, among those the second round ran, is measured in the second round too (a
    response whose seeds all failed is not met by default), and (b) its worst relative miss
    over the shared pairs is lower than the first round's by more than the combined standard
    error of the two worst-miss means, sqrt(se1^2 + se2^2); a worst miss over one seed takes
    the other round's seed sd of that response (:func:`_miss_se`), and where neither round has
    two seeds of it the two cannot be told apart.  A first round that measured none of the
    pairs the second ran leaves the second final wherever it measured one."""
    at = {(r["response"], r["preset"]) for r in second}
    same = [r for r in first if (r["response"], r["preset"]) in at]
    got2 = {(r["response"], r["preset"]) for r in second if _measured(r)}
    if not got2:
        return False, "no second-round seed gave a value: the case ends with the first round's set"
    lost = sorted({f"{r['response']} ({r['preset']})" for r in same
                   if _measured(r) and (r["response"], r["preset"]) not in got2})
    if lost:
        return False, (f"the second round has no value for {', '.join(lost)} (every seed failed), which the first "
                       "round verified: the case ends with the first round's set")
    shared = {(r["response"], r["preset"]) for r in same if _measured(r)}
    if not shared:
        return True, ""
    one = [r for r in same if (r["response"], r["preset"]) in shared]
    two = [r for r in second if (r["response"], r["preset"]) in shared]
    (w1, s1, at1), (w2, s2, at2) = _worst_miss(one, two), _worst_miss(two, one)
    margin = float(np.hypot(s1, s2))
    if not np.isfinite(margin):
        return False, (f"the second round's verified worst miss {w2:.2g} % against the first round's "
                       f"{w1:.2g} % cannot be told apart (neither round has two seeds of "
                       f"{at1 if not np.isfinite(s1) else at2} to give it a standard error): the case ends with the "
                       "first round's set")
    if w2 < w1 - margin:
        return True, ""
    return False, (f"the second round's verified worst miss {w2:.2g} % is not lower than the first round's "
                   f"{w1:.2g} % by more than their combined standard error {margin:.2g} % (worst at {at2} and "
                   f"{at1}, over the responses both rounds measured): the case ends with the first round's set")


def _better_round(first: list[dict], second: list[dict]) -> None:
    """Mark (``final``) the rows of the round whose verified set a case ends with
    (:func:`better_round`, as ``final.csv``): every row of that round, at every preset, and
    none of the other's; a second round that is not final says why in its notes."""
    keep_second, why = better_round(first, second)
    for r in first:
        r["final"] = not keep_second
    for r in second:
        r["final"] = keep_second
        if why:
            r["note"] = "; ".join(x for x in (r["note"], why) if x)


def round_change(first: dict, second: dict, bias, surface_se=0.0, local: bool = False) -> str:
    """What the move from the first set to the second round's did to one response, beside what
    the response surface promised: the DEM's change, the verification means' difference
    m2 - m1, against the surface's change between the two sets, ``second.predicted - bias -
    first.predicted`` (the second set's prediction carries the bias the round corrected by;
    without one it is the surface's own).  The two are told apart by two standard errors of
    their difference, sqrt(s1^2/n1 + s2^2/n2 + surface_se^2), the seeds' and the surface's own
    (``surface_change_se_<response>`` of ``refined.csv``, which grows with the move).  Where
    they differ by more, the surface's slope along the move is not the DEM's there, so a
    constant bias correction cannot be relied on to aim the set (where the second round missed,
    a local design at the set, more than one point near it, would learn the slope).  With
    ``local`` the second set came from the surface corrected by such a design
    (:mod:`soilcal.chain.local`), whose slope is then the one that did not hold.  Empty where
    either round has fewer than two seeds or no prediction."""
    m1, s1, n1 = first["simulated_mean"], first["simulated_sd"], first["n"]
    m2, s2, n2 = second["simulated_mean"], second["simulated_sd"], second["n"]
    p1, p2 = first["predicted"], second["predicted"]

    b, sse = _finite(bias, 0.0), _finite(surface_se, 0.0)
    vals = (m1, s1, m2, s2, p1, p2)
    if n1 < 2 or n2 < 2 or not all(np.isfinite(float(v)) for v in vals):
        return ""
    dem, surf = float(m2 - m1), float(p2 - b - p1)
    two_se = 2.0 * float(np.sqrt(s1 ** 2 / n1 + s2 ** 2 / n2 + sse ** 2))
    what = "the surface corrected by the local design" if local else "the surface"
    text = (f"from the first set the DEM changed by {dem:+.2f} where {what} promised {surf:+.2f} (two "
            f"standard errors of their difference {two_se:.2f}, seeds and surface)")
    if abs(dem - surf) <= two_se:
        return text + (": as the local plane said" if local else ": as the surface said")
    if local:
        return text + (": the local plane's slope did not hold over the move (the response bends within it, or "
                       "one seed per local point left the slope uncertain: more seeds per point or a smaller "
                       "half-width, simulation.verification.local)"
                       + (" (the target is met nonetheless)" if second.get("within_2_percent") else ""))
    if second.get("within_2_percent"):
        return text + ": the surface's slope along the move is not the DEM's here (the target is met nonetheless)"
    return (text + ": the surface's slope along the move is not the DEM's here, so shifting it by a constant "
            "cannot aim the set (a local design at this set, more than one point near it, would learn the slope)")


def _case_rows(soil_data, stage, case, optimum, targets, frames, rnd) -> list[dict]:
    from soilcal.chain.stage import calibrated_rows

    allruns = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=["response", "status"])
    cal = calibrated_rows(optimum, case["id"])
    rows = []
    for rid, goal in case["goals"].items():
        rsel = allruns[allruns["response"] == rid]
        presets = sorted({str(x) for x in rsel["preset"]} - {"", "nan"}, key=lambda x: x != "quick") \
            if "preset" in rsel.columns and len(rsel) else []
        for preset in presets or [""]:
            sel = rsel[rsel["preset"].astype(str) == preset] if preset else rsel
            row = _verification_row(stage, case, rid, goal, targets, soil_data, cal, sel, preset)
            row["round"] = rnd
            if rnd == 2 and "note" in cal.columns and row["n"] > 0:
                row["note"] = "; ".join(n for n in (str(cal["note"].iloc[0]), row["note"]) if n)
            rows.append(row)
    return rows


def _verification_row(stage, case, rid, goal, targets, soil_data, cal, sel, preset) -> dict:
    """One row of :func:`verification_frame`: one case, response and preset."""
    from soilcal.chain.sources import design_replicates
    from soilcal.chain.stage import factors_on_bounds

    tid = goal.get("target", "")
    t = targets.get(tid, {}) if tid else {}
    target = float(goal["value"]) if "value" in goal else (
        t.get("value") if t.get("value") is not None else np.nan)
    target = float(target) if target is not None else np.nan
    # the value the paper calibrated to: only a soil that cites a paper has one (a soil of one's
    # own aims at its own measurements, which are no paper's)
    paper_target = (soil_data.get("targets", {}).get(tid) or {}).get("value") if tid else goal.get("value")
    paper_target = float(paper_target) if paper_target is not None and soil_data.get("citation") else np.nan
    ok = sel[sel["status"].astype(str) == "ok"]
    vals = ok["value"].to_numpy(float) if len(ok) else np.array([])
    n = int(np.isfinite(vals).sum())
    failed, failed_note = _failed_seeds(sel)
    mean = float(np.nanmean(vals)) if n else np.nan
    sd = float(np.nanstd(vals, ddof=1)) if n > 1 else np.nan
    pred = float(cal[rid].iloc[0]) if len(cal) and rid in cal.columns else np.nan
    paper_sim = (case.get("printed_verification") or {}).get(rid)
    paper_sim = float(paper_sim) if paper_sim is not None else np.nan
    rel = (mean - target) / target * 100 if np.isfinite(target) and target != 0 and n else np.nan
    if len(cal) == 0:
        reasons = sel["error"].astype(str).unique().tolist() if len(sel) else []
        status = "not run: " + ("; ".join(r for r in reasons if r) or "no calibrated set")
    elif n == 0:
        status = ("failed: " + "; ".join(sel["error"].astype(str).unique())) if len(sel) else "not run"
    elif failed:
        status = f"{failed} of {failed + n} seeds failed"
    else:
        status = "ok"
    ci = tuple(float(cal[f"{rid}_{k}"].iloc[0]) for k in ("ci_low", "ci_high")) \
        if len(cal) and f"{rid}_ci_low" in cal.columns else None
    model = (stage.get("optimise") or {}).get("model", "reduced")
    bounds = factors_on_bounds(stage, cal.iloc[0]) if len(cal) else []
    tsd = target_scatter(t)
    note = diagnose(mean, sd, n, target, pred, ci, design_replicates(soil_data, rid), model, bounds, tsd) \
        if len(cal) and n else ""
    if len(cal) and n and goal.get("goal") != "target":
        note = f"goal {goal.get('goal')}: no target value" + (
            "; the paper's verification is beside it" if np.isfinite(paper_sim) else "")
    if n and failed:
        note = "; ".join(x for x in (failed_note + f": the statistics are of the other {n}", note) if x)
    unit = next((str(r.get("unit", "")) for r in stage.get("responses", []) if r.get("id") == rid), "")
    return {
        "stage": stage["id"], "case": case["id"], "response": rid, "unit": unit,
        "target_id": tid or goal.get("goal"),
        "target": target, "target_source": t.get("source", "config" if "value" in goal else ""),
        "preset": preset or (ok["preset"].iloc[0] if len(ok) else ""), "n": n,
        "seeds": " ".join(str(int(s)) for s in ok["seed"]) if len(ok) else "", "failed_seeds": failed,
        "simulated_mean": mean, "simulated_sd": sd, "relative_error_percent": rel,
        "within_2_percent": bool(np.isfinite(rel) and abs(rel) <= TOLERANCE_PERCENT),
        "target_sd": tsd, "miss_in_target_sd": (mean - target) / tsd
        if np.isfinite(tsd) and tsd > 0 and np.isfinite(target) and n else np.nan,
        "predicted": pred, "predicted_minus_target": pred - target if np.isfinite(target) else np.nan,
        "particles": float(pd.to_numeric(ok["particles"], errors="coerce").mean())
        if len(ok) and "particles" in ok else np.nan,
        "paper_target": paper_target, "paper_simulated": paper_sim,
        "paper_relative_error_percent": (paper_sim - paper_target) / paper_target * 100
        if np.isfinite(paper_sim) and np.isfinite(paper_target) and paper_target else np.nan,
        "status": status, "note": note}


def target_scatter(t: dict) -> float:
    """The SD the soil gives with a target's value (``targets.<id>.sd``, the spread of the
    repeated measurements it is the mean of), from its ``targets.csv`` row ``t``; NaN where it
    gives none or it is not positive.  A photo target has none: the photo group's
    ``image_spread`` is the SD of ``angle_deg`` over single flanks (a heap's left and right
    included) or frames, whatever measure the target takes, and is not the spread of repeated
    measurements of the target's value."""
    v = float("nan") if str(t.get("source", "")) == "image" else _finite(t.get("sd"), float("nan"))
    return v if v > 0 else float("nan")


def _finite(v, default: float) -> float:
    """``v`` as a finite float, else ``default`` (a CSV cell may be empty, text or NaN)."""
    try:
        v = float(v)
    except (TypeError, ValueError):
        return default
    return v if np.isfinite(v) else default


def _pinned(v):
    """An identifiability row's ``pinned`` as read back from its CSV: True, False or
    ``"at bound"`` (:func:`soilcal.optimise.near_optimal.identifiability`)."""
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    text = str(v).strip()
    if text in ("True", "False"):
        return text == "True"
    if text == "at bound":
        return text
    raise InputError("identifiability.csv", "pinned", "True, False or 'at bound'", v)


def _failed_seeds(sel: pd.DataFrame) -> tuple[int, str]:
    """(count, note) of the verification seeds of one response that ran and failed (not the
    rows of a replicate that could not run), the note naming the seeds and the reasons."""
    if not len(sel):
        return 0, ""
    st = sel["status"].astype(str)
    vals = pd.to_numeric(sel["value"], errors="coerce")
    bad = sel[((st != "ok") | vals.isna()) & ~st.str.startswith("not run")]
    if not len(bad):
        return 0, ""
    seeds = [str(int(s)) for s in pd.to_numeric(bad["seed"], errors="coerce").dropna()] if "seed" in bad else []
    reasons = [r for r in dict.fromkeys(bad["error"].astype(str)) if r and r != "nan"] if "error" in bad else []
    who = (f"seed {seeds[0]}" if len(seeds) == 1 else f"seeds {', '.join(seeds)}") if seeds else \
        f"{len(bad)} seed{'s' if len(bad) > 1 else ''}"
    return len(bad), f"{who} failed ({'; '.join(reasons) or 'no reason recorded'})"


#: ``paper_source`` of a parameter of a soil that cites no paper and prints no optimum
NO_PUBLISHED_VALUE = "no published value"


def calibrated_vs_paper(soil_data: dict, stages: dict[str, tuple[dict, pd.DataFrame, pd.DataFrame]]) -> pd.DataFrame:
    """Every calibrated parameter of every case beside the paper's calibrated value.

    ``stages``: stage id -> (DEM stage, optimum frame, identifiability frame).  A factor's
    paper value is the case's ``printed_optimum`` (the paper's symbol of the same parameter);
    a fixed parameter's is the value the config's stage fixes it at, where the soil cites a
    paper (``citation``): a soil of one's own fixes its stages at values of its own, which are
    no paper's.  A parameter without a published value has an empty ``paper`` and
    ``paper_source`` "no published value" (a soil without a citation) or "not printed" (one
    with).  ``pinned``: whether the near-optimal sets pin a factor down (True, False, ``at
    bound`` where a bound of the design region holds it rather than the data), ``fixed`` for
    a fixed parameter.  The near-optimal range and ``pinned`` come from the first round's
    near-optimal sets (``identifiability.csv``); where a case ends with its second round's set
    (``round`` 2) the ``note`` says so, and whether the value lies outside that range; a
    second-round value past the Box-Behnken box (the stage's ``low``..``high``) is ``pinned``
    "beyond the box": no bound and no near-optimal set of the design holds it there.
    """
    from soilcal.chain.stage import calibrated_rows

    params = soil_data.get("parameters", {})
    cited = bool(soil_data.get("citation"))
    rows = []
    for sid, (stage, optimum, ident) in stages.items():
        config_stage = next(s for s in soil_data["stages"] if s["id"] == sid)
        paper_sym = {f["parameter"]: s for s, f in config_stage["factors"].items()}
        for case in (stage.get("optimise") or {}).get("cases", []):
            cfg_case = next((c for c in (config_stage.get("optimise") or {}).get("cases", [])
                             if c["id"] == case["id"]), {})
            printed = cfg_case.get("printed_optimum") or {}
            cal = calibrated_rows(optimum, case["id"])
            idt = ident[ident["case"].astype(str) == case["id"]] if ident is not None and len(ident) else None
            entries = [(s, f["parameter"], "factor") for s, f in stage["factors"].items()]
            entries += [("", p, "fixed") for p in (stage.get("fixed") or {})]
            for sym, pname, role in entries:
                if role == "factor":
                    ours = float(cal[sym].iloc[0]) if len(cal) else np.nan
                else:
                    ours = float(stage["fixed"][pname])
                ps = paper_sym.get(pname)
                if ps is not None and ps in printed:
                    paper, psrc = float(printed[ps]), f"printed optimum ({ps})"
                elif cited and pname in (config_stage.get("fixed") or {}):
                    paper, psrc = float(config_stage["fixed"][pname]), "fixed in the paper's stage"
                elif cited:
                    paper, psrc = np.nan, "not printed"
                else:
                    paper, psrc = np.nan, NO_PUBLISHED_VALUE
                row = {"stage": sid, "case": case["id"],
                       "round": int(cal["round"].iloc[0]) if len(cal) and "round" in cal.columns else 1,
                       "parameter": pname, "symbol": sym, "role": role,
                       "unit": (params.get(pname) or {}).get("unit", ""), "calibrated": ours, "paper": paper,
                       "paper_source": psrc, "difference": ours - paper,
                       "relative_difference_percent": (ours - paper) / paper * 100 if paper else np.nan,
                       "pinned": "", "near_optimal_min": np.nan, "near_optimal_max": np.nan, "note": ""}
                if role == "factor" and idt is not None:
                    r = idt[idt["factor"] == sym]
                    if len(r):
                        row.update(pinned=_pinned(r["pinned"].iloc[0]), near_optimal_min=float(r["min"].iloc[0]),
                                   near_optimal_max=float(r["max"].iloc[0]))
                if role == "factor" and row["round"] == 2:
                    row.update(_second_round_factor(stage["factors"][sym], ours, row))
                if role == "fixed":
                    row["pinned"] = "fixed"
                rows.append(row)
    return pd.DataFrame(rows)


def _second_round_factor(factor: dict, value: float, row: dict) -> dict:
    """``pinned`` and ``note`` of a factor of :func:`calibrated_vs_paper` whose case ends with
    its second round's set ``value``: the near-optimal range and ``pinned`` describe the first
    round's sets; a value past the box's ``low``..``high`` is "beyond the box"."""
    lo, hi = row["near_optimal_min"], row["near_optimal_max"]
    out = {}
    notes = ["the second round's set: near_optimal_min/max and pinned describe the first round's near-optimal sets"]
    if np.isfinite(lo) and np.isfinite(hi) and np.isfinite(value) and not lo <= value <= hi:
        notes.append(f"this value lies outside their range {lo:.4g} to {hi:.4g}")
    low, high = (float(factor[k]) if factor.get(k) is not None else np.nan for k in ("low", "high"))
    tol = 1e-9 * max(abs(low), abs(high), 1.0) if np.isfinite(low) and np.isfinite(high) else 0.0
    if np.isfinite(value) and (value < low - tol or value > high + tol):
        out["pinned"] = "beyond the box"
        notes.append(f"it lies beyond the Box-Behnken box {low:.4g} to {high:.4g}, where no bound holds it")
    out["note"] = "; ".join(notes)
    return out


def tool_frame(conditions, runs: dict[tuple[str, int], pd.DataFrame]) -> pd.DataFrame:
    """Tool-verification rows: every measured condition and quantity, measured beside simulated.

    ``conditions``: :class:`soilcal.config.measurements.Condition` objects; ``runs``:
    (measurement, row) -> that condition's run rows (one per response and replicate seed).
    """
    rows = []
    for c in conditions:
        df = runs.get((c.measurement, c.row))
        for resp in c.responses:
            measure = resp["measure"]
            sel = df[df["measure"] == measure] if df is not None and len(df) else pd.DataFrame()
            ok = sel[sel["status"].astype(str) == "ok"] if len(sel) else sel
            vals = ok["value"].to_numpy(float) if len(ok) else np.array([])
            n = int(np.isfinite(vals).sum())
            mean = float(np.nanmean(vals)) if n else np.nan
            sd = float(np.nanstd(vals, ddof=1)) if n > 1 else np.nan
            measured = resp.get("measured")
            measured = float(measured) if measured is not None else np.nan
            paper = resp.get("paper_simulated")
            paper = float(paper) if paper is not None else np.nan
            if df is None:
                status = "not run"
            elif len(sel) and (sel["status"].astype(str) != "ok").all():
                status = "; ".join(sel["status"].astype(str).unique()) + ": " + \
                    "; ".join(sel["error"].astype(str).unique())
            elif n == 0:
                status = "no value: the runs measured nothing for this quantity"
            else:
                status = "ok"
            note = "; ".join(n for n in (resp.get("note") or "", getattr(c, "note", "") or "") if n)
            if not np.isfinite(measured):
                note = (note + "; " if note else "") + "measured value not printed"
            pdiff = resp.get("paper_difference")
            rows.append({
                "measurement": c.measurement, "row": c.row, "covariate": c.covariate,
                "covariate_value": c.covariate_value, "scenario": c.scenario, "setup": c.setup.get("name", ""),
                "measure": measure, "unit": resp.get("unit", ""), "preset": c.preset, "stage": c.stage,
                "case": c.case, "n": n, "seeds": " ".join(str(int(s)) for s in ok["seed"]) if len(ok) else "",
                "measured": measured, "measured_sd": resp.get("measured_sd"), "simulated_mean": mean,
                "simulated_sd": sd,
                "relative_error_percent": (mean - measured) / measured * 100 if np.isfinite(measured) and measured
                else np.nan,
                "paper_simulated": paper,
                "paper_relative_error_percent": (paper - measured) / measured * 100
                if np.isfinite(paper) and np.isfinite(measured) and measured else np.nan,
                "paper_difference": pdiff if pdiff is not None else np.nan,
                "status": status, "note": note})
    return pd.DataFrame(rows, columns=TOOL_COLUMNS)


__all__ = ["SEEDS_COLUMNS", "TOOL_COLUMNS", "VERIFICATION_COLUMNS", "calibrated_vs_paper", "case_seeds", "diagnose",
           "second_stage_responses",
           "first_stage_seeds", "most_seeds", "not_run_rows", "seeds_frame", "stein_seeds", "tool_frame", "two_stage",
           "verification_cases", "verification_frame", "verification_spec", "verify_settings"]


# --------------------------------------------------------------------------- file level


def _soil(soil_path, soil_data, resources_root="resources"):
    from pathlib import Path

    from soilcal.config.load import Soil

    return Soil(path=Path(soil_path), data=soil_data, resources_root=Path(resources_root))


def verification_point(soil, stage: dict, optimum: pd.DataFrame, case_id: str, rep: int,
                       preset: str | None = None, responses=None, design_seeds: bool = False) -> dict:
    """Everything one verification job simulates (plain data, the job's params): the spec of
    :func:`verification_spec`, or ``{"not_run": reason}`` when the case has no calibrated set
    (e.g. its target is missing)."""
    try:
        spec = verification_spec(soil, stage, optimum, case_id, rep, preset, responses, design_seeds)
    except InputError as exc:
        return {"not_run": str(exc), "stage": stage["id"], "case": case_id,
                "responses": list(_case(stage, case_id)["goals"])}
    return dict(spec, case=case_id)


def same_as(specs: dict[str, dict], case_id: str) -> str | None:
    """The first case before ``case_id`` (in the order of ``specs``: case -> the
    :func:`verification_point` of one replicate) whose job simulates exactly what
    ``case_id``'s does: the same calibrated set, responses, preset and seed.  Two targets
    that the design region cannot reach both end at the region's same corner, for example; the
    second case's job then copies the first one's rows instead of running them again."""
    def key(s):
        return None if "not_run" in s else {k: v for k, v in s.items() if k != "case"}

    mine = key(specs[case_id])
    if mine is None:
        return None
    for other, spec in specs.items():
        if other == case_id:
            return None
        if key(spec) == mine:
            return other
    return None


def run_verification_point(spec: dict, out, threads: int | None = None,
                           restart_dir=None, copy_from=None) -> pd.DataFrame:
    """Simulate one verification job (:func:`verification_point`) and write its rows
    (``restart_dir``: :func:`soilcal.chain.sources.simulate`); with ``copy_from`` (the rows
    of the job of an earlier case that simulates the same, :func:`same_as`) those rows under
    this case's name."""
    from soilcal.chain.files import write_csv
    from soilcal.chain.sources import simulate

    if copy_from is not None:
        df = pd.read_csv(copy_from, dtype=str, keep_default_na=False)  # every cell as written
        df["case"] = spec["case"]
        write_csv(df, out)
        return df
    if "not_run" in spec:
        df = not_run_rows(spec["stage"], {"goals": {r: {} for r in spec["responses"]}}, spec["not_run"])
    else:
        df = simulate({k: v for k, v in spec.items() if k != "case"}, threads=threads,
                      restart_dir=restart_dir)
    df.insert(2, "case", spec["case"])
    write_csv(df, out)
    return df


def seed_note(plan: pd.DataFrame) -> str:
    """What the second verification stage did for one case, from its rows of
    ``verify_seeds.csv`` (:func:`seeds_frame`); empty where it took no more seeds."""
    und = plan[plan["undecided"].astype(str).str.lower() == "true"]
    if und.empty or int(plan["seeds"].max()) <= int(plan["first_seeds"].max()):
        return ""
    asked, took = int(und["stein_seeds"].max()), int(plan["seeds"].max())
    return (f"two-stage verification: the first {int(plan['first_seeds'].max())} seeds left "
            f"{', '.join(und['response'].astype(str))} within seed scatter of the target; Stein's rule asked for "
            f"{asked} seeds in all, {took} ran" + (" (capped at simulation.verification.max_replicates)"
                                                   if asked > took else ""))


def write_verification(soil_data: dict, stage_ids, stage_dirs: dict[str, str], targets_csv, run_paths, out,
                       refined_paths: dict[str, str] | None = None, refined_run_paths=(),
                       seed_paths=()) -> pd.DataFrame:
    """``verification.csv`` of a soil from its replicate runs ``verify/<preset>/<stage>/<case>/<k>.csv``
    and, where the soil runs a second round, its stages' ``refined.csv`` (``refined_paths``)
    with the runs at the refined sets ``refine/<stage>/<case>/<k>.csv``; ``seed_paths``: the
    stages' ``verify_seeds.csv`` where the soil runs a second verification stage, whose first
    round rows at the soil's preset then say what it did (:func:`seed_note`)."""
    from pathlib import Path

    from soilcal.chain.files import read_stage, read_targets, write_csv
    from soilcal.chain.refine import runs_by_case

    targets = read_targets(targets_csv)
    plans = {Path(p).parent.name: pd.read_csv(p) for p in seed_paths}
    frames = []
    for sid in stage_ids:
        d = Path(stage_dirs[sid])
        stage = read_stage(d / "stage.json")
        runs = runs_by_case(run_paths, sid)
        ref = pd.read_csv(refined_paths[sid]) if refined_paths and sid in refined_paths else None
        runs2 = runs_by_case(refined_run_paths, sid)
        frame = verification_frame(soil_data, stage, pd.read_csv(d / "optimum.csv"), targets, runs, ref, runs2)
        if sid in plans and len(frame):
            for case, plan in plans[sid].groupby("case"):
                note = seed_note(plan)
                if not note:
                    continue
                at = ((frame["case"].astype(str) == str(case)) & (frame["round"] == 1)
                      & frame["preset"].astype(str).isin(set(plan["preset"].astype(str))))
                frame.loc[at, "note"] = [note + (f"; {v}" if isinstance(v, str) and v else "")
                                         for v in frame.loc[at, "note"]]
        frames.append(frame)
    df = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=VERIFICATION_COLUMNS)
    write_csv(df, out)
    return df


def tool_point(soil, cond, stage: dict, optimum: pd.DataFrame) -> dict:
    """Everything one measured condition's job simulates (plain data, the job's params): one
    point spec per replicate seed (the condition's own seed of ``seed + seed_offset + k``,
    :func:`soilcal.config.measurements.condition_seed`: each measured test a sample of its own)
    at the calibrated set of the condition's case, with the condition's setup and parameters;
    ``{"not_run": reason}`` when that case has no calibrated set."""
    from soilcal.chain.sources import point_spec
    from soilcal.chain.stage import calibrated_levels
    from soilcal.config.measurements import condition_seed

    base = {"measurement": cond.measurement, "row": cond.row, "stage": stage["id"],
            "measures": [r["measure"] for r in cond.responses]}
    try:
        levels = calibrated_levels(stage, optimum, cond.case or None)
    except InputError as exc:
        return dict(base, not_run=str(exc))
    v = verify_settings(soil.data)
    specs = []
    for k in range(int(cond.replicates)):
        seed = condition_seed(cond, int(soil.data["seed"]) + int(v["seed_offset"]) + k)
        spec = point_spec(soil, stage, levels, run=int(cond.row), seed=seed, replicates=1,
                          extra_params=dict(cond.params), responses=[])
        spec["responses"] = {r["measure"]: {"scenario": cond.scenario, "setup": dict(cond.setup),
                                            "measure": r["measure"], "preset": cond.preset}
                             for r in cond.responses}
        specs.append(spec)
    return dict(base, specs=specs)


def run_tool_point(job: dict, out, threads: int | None = None, restart_dir=None) -> pd.DataFrame:
    """Simulate one measured condition (:func:`tool_point`) and write one row per measured
    quantity and seed.  ``restart_dir``: where its runs keep their restart files, one folder
    per spec (``spec<k>``), so that a killed job resumes (:func:`soilcal.chain.sources.simulate`)."""
    from pathlib import Path

    from soilcal.chain.files import write_csv
    from soilcal.chain.sources import RUN_COLUMNS, simulate

    if "not_run" in job:
        df = pd.DataFrame([{c: "" for c in RUN_COLUMNS} | {"stage": job["stage"], "response": m, "measure": m,
                                                            "status": "not run", "error": job["not_run"],
                                                            "value": np.nan, "n": 0}
                           for m in job["measures"]], columns=RUN_COLUMNS)
    else:
        df = pd.concat([simulate(spec, threads=threads,
                                 restart_dir=None if restart_dir is None else Path(restart_dir) / f"spec{k}")
                        for k, spec in enumerate(job["specs"])], ignore_index=True)
    df.insert(2, "measurement", job["measurement"])
    write_csv(df, out)
    return df


def write_tool_verification(soil_path, resources_root, run_paths, run_map: dict, out) -> pd.DataFrame:
    """``tool_verification.csv`` of a soil from its runs ``tools/<key>.csv``; ``run_map``:
    ``"<measurement>/<row>"`` -> the key of the job that simulated that condition."""
    from pathlib import Path

    from soilcal.chain.files import write_csv
    from soilcal.config.load import load_soil
    from soilcal.config.measurements import conditions

    soil = load_soil(soil_path, resources_root)
    files = {Path(p).stem: pd.read_csv(p) for p in run_paths}
    runs = {}
    for cond_id, key in run_map.items():
        m, r = cond_id.rsplit("/", 1)
        runs[(m, int(r))] = files[key]
    df = tool_frame(conditions(soil), runs)
    write_csv(df, out)
    return df


def write_calibrated_vs_paper(soil_data: dict, stage_ids, stage_dirs: dict[str, str], out,
                              set_file: str = "optimum.csv") -> pd.DataFrame:
    """``calibrated_vs_paper.csv``: the calibrated set of each case read from ``set_file`` in
    each stage's folder (:func:`soilcal.chain.refine.set_file`: ``final.csv``, the set each
    case ends with, where the soil runs the second round)."""
    from pathlib import Path

    from soilcal.chain.files import read_stage, write_csv

    stages = {}
    for sid in stage_ids:
        d = Path(stage_dirs[sid])
        stages[sid] = (read_stage(d / "stage.json"), pd.read_csv(d / set_file),
                       pd.read_csv(d / "identifiability.csv"))
    df = calibrated_vs_paper(soil_data, stages)
    write_csv(df, out)
    return df


SUMMARY_COLUMNS = ["soil", "stage", "case", "round", "response", "target", "target_source", "simulated_mean",
                   "simulated_sd", "n", "relative_error_percent", "within_2_percent", "predicted_minus_target",
                   "paper_relative_error_percent", "status", "dem_points", "dem_failed"]


def summary_frame(verifications: dict[str, pd.DataFrame], responses: dict[str, list[pd.DataFrame]]) -> pd.DataFrame:
    """One row per soil, case, response and preset at the set the soil ends with (the rows
    marked ``final``: the better verified round, :func:`verification_frame`; a table without
    that column, the last verification round), with each soil's DEM design points (count,
    failed; their wall time is in the jobs' benchmark files)."""
    rows = []
    for soil, v in verifications.items():
        if "final" in v.columns and len(v):
            v = v[v["final"].astype(str).str.lower() != "false"]
        elif "round" in v.columns and len(v):
            key = ["stage", "case", "response", "preset"]
            last = v.groupby(key, dropna=False)["round"].transform("max")
            v = v[v["round"] == last]
        tabs = responses.get(soil, [])
        pts = sum(len(t) for t in tabs)
        failed = sum(int((t["status"] != "ok").sum()) for t in tabs if "status" in t)
        for r in v.to_dict("records"):
            rows.append({"soil": soil, **{k: r.get(k) for k in SUMMARY_COLUMNS if k in r},
                         "dem_points": pts, "dem_failed": failed})
    return pd.DataFrame(rows, columns=SUMMARY_COLUMNS)


def write_summary(soils, verification_paths, response_paths, out_table, out_figures) -> pd.DataFrame:
    from pathlib import Path

    from soilcal import plots
    from soilcal.chain.files import write_csv

    ver = {s: pd.read_csv(p) for s, p in zip(soils, verification_paths)}
    resp: dict[str, list[pd.DataFrame]] = {}
    for p in response_paths:
        soil = Path(p).parts[-4]
        resp.setdefault(soil, []).append(pd.read_csv(p))
    df = summary_frame(ver, resp)
    write_csv(df, out_table)
    Path(out_figures).mkdir(parents=True, exist_ok=True)
    plot = df[np.isfinite(pd.to_numeric(df["relative_error_percent"], errors="coerce"))]
    if len(plot):
        plots.summary_figure(plot, Path(out_figures) / "summary")
    return df


def tool_key(job: dict) -> str:
    """Identity of the DEM runs a measured condition needs: two conditions with the same
    scenario, setup, preset, parameters and seeds (a tiller speed whose flatness and power are
    tabled apart) share one job, which measures both."""
    import hashlib
    import json

    if "not_run" in job:
        ident = {"not_run": job["not_run"], "measurement": job["measurement"], "row": job["row"]}
    else:
        ident = [{"params": s["params"], "seed": s["seed"], "replicates": s["replicates"],
                  "runs": sorted({json.dumps([r["scenario"], r["setup"], r["preset"]], sort_keys=True, default=str)
                                  for r in s["responses"].values()})} for s in job["specs"]]
    return hashlib.sha1(json.dumps(ident, sort_keys=True, default=str).encode()).hexdigest()[:12]


def merge_tool_jobs(a: dict, b: dict) -> dict:
    """One job for two conditions of the same :func:`tool_key`: the union of their measures."""
    out = dict(a, measures=list(dict.fromkeys(list(a["measures"]) + list(b["measures"]))))
    if "specs" in a:
        out["specs"] = [dict(sa, responses={**sa["responses"], **sb["responses"]})
                        for sa, sb in zip(a["specs"], b["specs"])]
    return out
