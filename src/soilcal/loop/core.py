"""The measured-data loop of one soil: residual -> diagnosis -> candidate effects -> refit -> verdict.

The steps, each a function of plain tables so that the workflow (one DEM job per condition
and design point, ``workflow/rules/loop.smk``) and an in-process run (:func:`run_inprocess`,
for tests, the benchmark and ``soilcal loop synthesize``) share them:

1. :func:`soilcal.loop.residuals.residual_frame`: measured beside simulated at the calibrated
   parameters;
2. :func:`soilcal.loop.diagnose.diagnose`: structure in the residual;
3. :func:`candidates`: the effects whose signature shares a quantity (or ``bias``) with a
   significant test (:func:`soilcal.loop.diagnose.matched_quantities`), and that act on at
   least one measured condition (its quantities, and its scenario where the effect names
   some; ``loop.candidates: all`` tries every effect that acts); never one whose quantities
   have one value on every measured row (:func:`skipped`);
4. :func:`plan`: each candidate's design of parameters (:func:`soilcal.loop.select.theta_design`),
   every condition simulated at every design point with the seeds of the calibrated runs;
5. :func:`analyse`: surrogates, forward selection, the verdict and the report tables;
6. :func:`more_candidates`: one second round for an effect the first one masked (the
   residual left by the first round's model matches it), and for an effect whose scenario
   stopped measuring past some level (:func:`soilcal.loop.select.narrowing`: the levels
   inside that gap, :func:`more_designs`), then :func:`analyse` again over both rounds'
   candidates.

Settings (the soil's optional ``loop`` block, every value written into the outputs)::

    loop:
      alpha: 0.05            # significance of the diagnosis (Holm) and of the paired test
      effects: [...]         # library effects considered (default: all)
      candidates: matched    # or all
      bounds: {rate_friction: {beta: [-0.3, 0.6]}}   # parameter bounds (default: the library's)
      reference: {tool_speed: 1.0}   # where the calibrated parameters hold (default: the
                                     # mean of the measured conditions)
      design_points: 5       # levels per effect parameter (plus the switched-off value)
      fold_by: null          # covariate column grouping the held-out folds (default: a test-day,
                             # session or group column, else each condition: fold_grouping)
      max_effects: 2
      bootstrap: 200         # refits of the chosen effects' 95 % interval over the seeds and
                             # the measured values (0: the fit's own interval, seeds ignored)
      surrogate: pooled      # or rows: an effect with a dose fits one shape per measured
                             # quantity shared by its rows (select.PooledSurrogate), or one per row
"""

from __future__ import annotations

import json
import math
import dataclasses
from dataclasses import dataclass

import numpy as np
import pandas as pd

from soilcal.errors import InputError
from soilcal.loop import diagnose as dg
from soilcal.loop import residuals as rs
from soilcal.loop import select as sl
from soilcal.loop.effects import EFFECTS
from soilcal.loop.settings import Settings, settings_from  # noqa: F401 (settings_from re-exported)


#: seeds per condition below which a residual within the seed scatter is not called consistent:
#: with two, the seed SD rests on one degree of freedom, and a table 50 % off can pass
MIN_SEEDS_TO_JUDGE = 3


def _at_bounds(theta: dict, effects: list) -> list[str]:
    """A sentence per fitted parameter that sits on a bound of its design (the surrogates end
    there: the data may want a value beyond it)."""
    out = []
    for e in effects:
        for j, k in enumerate(e.effect.theta_names()):
            lo, hi = float(e.surrogate.lo[j]), float(e.surrogate.hi[j])
            x = theta.get(f"{e.effect.name}.{k}")
            if x is None:
                continue
            tol = 1e-6 * (hi - lo)
            for side, b in (("lower", lo), ("upper", hi)):
                if abs(x - b) <= tol and not (side == "lower" and b == float(e.effect.null[k])):
                    out.append(f"{e.effect.name}.{k} at the {side} bound {b:g} of its design: the data may want a "
                               f"value beyond it (loop.bounds.{e.effect.name}.{k})")
    return out


def check_fold_by(soil, conds, settings, measurement=None) -> None:
    """``loop.fold_by`` names a covariate column of the conditions that run: the soil's
    loader checks it against all of its tables, but ``--measurement`` may pick one without
    it, and the held-out folds are formed only after every run (InputError naming the soil
    file, before any simulation)."""
    if not settings.fold_by:
        return
    cols = sorted({k for c in conds for k in (c.covariates or {})})
    if settings.fold_by not in cols:
        tables = sorted({c.measurement for c in conds})
        which = (f"the table --measurement {measurement} runs" if measurement else
                 "the measured tables (" + ", ".join(tables) + ")")
        raise InputError(soil.path, "loop.fold_by", f"a covariate column of {which}: "
                         + (", ".join(cols) or "none"), settings.fold_by)


def mean_reference(frame: pd.DataFrame, declared: dict) -> dict:
    """Quantity (a ``q:<quantity>`` column of ``frame``, a residual or observation table) ->
    the value at which the calibrated parameters hold: ``declared``, else the mean over the
    rows with a measured value (so the reference does not move with the simulations that
    failed; every row of a table that has none yet, one to synthesize); a quantity that one of
    those rows lacks has no reference.  Labels (tool, day)
    have none.  The one rule of the loop, ``soilcal loop run`` and ``soilcal loop synthesize``."""
    from soilcal.config.quantities import QUANTITIES

    rows = _measured_rows(frame)
    out = {}
    for c in frame.columns:
        if not c.startswith("q:") or QUANTITIES.get(c[2:]) is None:
            continue
        q = c[2:]
        if q in declared:
            out[q] = declared[q]
            continue
        x = pd.to_numeric(rows[c], errors="coerce")
        if len(x) and x.notna().all():
            out[q] = float(x.mean())
    return out


def _measured_rows(frame: pd.DataFrame) -> pd.DataFrame:
    """The rows with a measured value (every row of a table that has none yet, one to
    synthesize): those the reference is taken over and checked against."""
    if "measured" in frame.columns and len(frame):
        with_value = frame[np.isfinite(pd.to_numeric(frame["measured"], errors="coerce").to_numpy(float))]
        return with_value if len(with_value) else frame
    return frame


def check_reference(conditions, declared: dict, source, field: str = "loop.reference") -> None:
    """A declared reference (``loop.reference``, ``--reference``: SI units) of a quantity that
    varies over the measured rows (of every table given) lies within their range widened by
    its width on each side; farther out, the effects would take the calibrated parameters to
    hold where no row was measured, and a value given in the table's own unit (km/h, cm)
    rather than the SI one lands there.  InputError naming the field, the rows' range in the
    SI unit and any unit in which the value would lie among the rows.  A quantity constant
    over the rows is not checked: there is no range to judge by."""
    from soilcal.config.quantities import QUANTITIES

    if not declared:
        return
    rows = _measured_rows(rs.observations(list(conditions)))
    for q, v in declared.items():
        col = f"q:{q}"
        if QUANTITIES.get(q) is None or col not in rows.columns:
            continue
        x = pd.to_numeric(rows[col], errors="coerce").dropna().to_numpy(float)
        if not len(x):
            continue
        lo, hi = float(x.min()), float(x.max())
        span = hi - lo
        if span <= 0 or lo - span <= float(v) <= hi + span:
            continue
        si, units = QUANTITIES[q]
        read_as = [f"{float(v) * f:.4g} {si} read as {u}" for u, f in units.items()
                   if f != 1.0 and lo <= float(v) * f <= hi]
        raise InputError(source, f"{field}.{q}", f"{q} in {si} (the SI unit) within the measured rows' range widened "
                         f"by its width, {lo - span:.4g} to {hi + span:.4g} {si} (the rows span {lo:.4g} to {hi:.4g} "
                         f"{si}): the calibrated parameters would hold where nothing was measured"
                         + (f"; the value lies among the rows as {', '.join(read_as)}, a unit other than {si}"
                            if read_as else ""), v)


def reference_values(res: pd.DataFrame, settings: Settings) -> dict:
    """Quantity -> the value at which the calibrated parameters hold (:func:`mean_reference`;
    recorded in the outputs)."""
    return mean_reference(res, settings.reference)


def quantity_of(conditions) -> dict:
    out = {}
    for c in conditions:
        out.update(c.quantity_columns or {})
    return out


def per_table_quantities(conditions) -> dict:
    """Numeric quantity -> {measured table: its value}, for each quantity that has one value on
    every measured row of each table carrying it (:func:`_measured_rows`), though it may differ
    between the tables."""
    rows = _measured_rows(rs.observations(list(conditions)))
    return _one_value_per(rows, "measurement")


def _one_value_per(rows: pd.DataFrame, by, sort: bool = False) -> dict:
    """Numeric quantity -> {level of ``by`` (a column or a series to group ``rows`` by): its
    value}, for each quantity that has one value on every row of each level carrying it."""
    from soilcal.config.quantities import QUANTITIES

    out = {}
    for col in rows.columns:
        q = col[2:]
        if not col.startswith("q:") or QUANTITIES.get(q) is None:
            continue
        per = {}
        for lv, g in rows.groupby(by, sort=sort):
            x = pd.to_numeric(g[col], errors="coerce").dropna().to_numpy(float)
            if len(x) and not np.all(x == x[0]):
                per = None
                break
            if len(x):
                per[str(lv)] = float(x[0])
        if per:
            out[q] = per
    return out


def per_group_quantities(conditions, settings: Settings) -> tuple[str | None, dict]:
    """(the column grouping the held-out folds, :func:`fold_grouping`; numeric quantity ->
    {group: its value}) for each quantity that has one value within every group of that
    column, where some group holds two measured conditions at least (a grouping coarser than
    the conditions): a moisture prepared once per test day.  (None, {}) without such a
    column."""
    rows = _measured_rows(rs.observations(list(conditions)))
    col, _ = fold_grouping(settings, quantity_of(conditions), rows)
    key = f"cov:{col}" if col else None
    if key is None or key not in rows:
        return None, {}
    g = rows[rows[key].notna()]
    if not len(g) or not (g.groupby(g[key].astype(str))["simulation"].nunique() >= 2).any():
        return None, {}
    return col, {q: per for q, per in _one_value_per(g, g[key].astype(str), sort=True).items()
                 if len(set(per.values())) > 1}


def skipped(conditions, settings: Settings) -> dict:
    """Effect -> why it is not tried: every quantity it acts through that the measured rows
    carry has one value on all of them (a table at one speed), so the effect could only shift
    every row alike, which says nothing of that quantity (the bias is tested on its own); or
    one value in each table (a table at 1 m/s, another at 2 m/s), so its structure is a
    difference between the tables, which a table's own offset (another instrument, setup or
    measured quantity) makes as well; or one value in each group of the column that groups the
    held-out folds (a moisture prepared once per test day, :func:`per_group_quantities`), so
    its structure is a difference between the groups, which a day's own level makes as well;
    with ``loop.candidates: all`` too."""
    from soilcal.config.quantities import QUANTITIES

    per = per_table_quantities(conditions)
    col, per_group = per_group_quantities(conditions, settings)
    carried = {q for c in conditions for q in (c.quantities or {})}
    out = {}
    for name in settings.effects:
        eff = EFFECTS[name]
        needs = [q for q in eff.needs if q in carried]
        if not needs or not any(eff.applies_to(c.quantities or {}, c.scenario) for c in conditions):
            continue
        if not all(q in per for q in needs):
            if col and all(q in per_group for q in needs):
                out[name] = ("not tried: " + "; ".join(
                    f"{q} has one value on each `{col}` group (" + ", ".join(
                        f"{g}: {v:.4g} {QUANTITIES[q][0]}" for g, v in list(per_group[q].items())[:6])
                    + (", ..." if len(per_group[q]) > 6 else "") + ")" for q in needs)
                    + f", the held-out groups, so the effect cannot be told from an offset that varies between "
                    f"the `{col}` groups (measure two levels of it within a group to tell them apart)")
            continue
        if all(len(set(per[q].values())) == 1 for q in needs):
            out[name] = ("not tried: " + ", ".join(f"{q} is {next(iter(per[q].values())):.4g} {QUANTITIES[q][0]}"
                                                     for q in needs)
                         + " on every measured row, so the effect could only shift every row alike and carries "
                         "no information")
        else:
            out[name] = ("not tried: " + "; ".join(
                f"{q} has one value in each measured table (" + ", ".join(
                    f"{m}: {v:.4g} {QUANTITIES[q][0]}" for m, v in per[q].items()) + ")" for q in needs)
                + ", so the effect cannot be told from a difference between the tables")
    return out


def candidates(diag: pd.DataFrame, conditions, settings: Settings) -> list[str]:
    """Effects to fit (module docstring, step 3), in library order; none that :func:`skipped`
    names."""
    matched = dg.matched_quantities(diag)
    out = []
    skip = skipped(conditions, settings)
    for name in settings.effects:
        eff = EFFECTS[name]
        if name in skip or not any(eff.applies_to(c.quantities or {}, c.scenario) for c in conditions):
            continue
        if settings.candidates == "all" or matched & set(eff.signature):
            out.append(name)
    return out


def plan(conditions, names, settings: Settings, reference: dict) -> list[dict]:
    """One entry per candidate, design point and condition the effect changes: the effect,
    the point's index and parameters, the condition (measurement, row)."""
    out = []
    for name in names:
        eff = EFFECTS[name]
        for j, theta in enumerate(sl.theta_design(eff, settings.effect_bounds(name), settings.design_points)):
            for c in conditions:
                out.append({"effect": name, "point": j, "theta": theta, "measurement": c.measurement, "row": c.row,
                            "acts": eff.applies_to(c.quantities or {}, c.scenario)})
    return out


# --------------------------------------------------------------------------- analysis

SELECTION_COLUMNS = ["step", "effects", "parameters", "ci95", "heldout_rmse_percent", "reference_heldout_rmse_percent",
                     "weighted_heldout_rmse_percent", "reference_weighted_heldout_rmse_percent", "heldout_max_percent",
                     "aicc", "reference_aicc", "p_paired", "accepted", "reason", "surrogate", "lack_of_fit_p"]
SUMMARY_COLUMNS = ["soil", "rows", "usable_rows", "verdict", "effects", "parameters", "ci95", "ci95_method", "follows",
                   "rmse_before_percent", "rmse_after_percent", "rmse_floor_percent", "max_before_percent",
                   "max_after_percent", "error_reduction_percent", "explained_percent", "alpha", "reference", "folds",
                   "nuisance", "nuisance_ci95", "nuisance_method", "surrogate", "lack_of_fit_p",
                   "weighted_rmse_before_percent", "weighted_rmse_after_percent"]


#: the parameter of the free uniform scale of the model (:func:`soilcal.loop.select.scale_data`)
SCALE_KEY = "uniform_scale.s"


def _scale_fit(s) -> tuple[float, float, float]:
    """The free uniform scale's value and 95 % interval in a fit (:class:`select.Score`)."""
    lo, hi = s.ci.get(SCALE_KEY, (math.nan, math.nan))
    return s.theta[SCALE_KEY], lo, hi


def _excludes_zero(lo, hi) -> bool:
    """A finite 95 % interval that leaves out 0: a bias the data show."""
    return bool(np.isfinite(lo) and np.isfinite(hi) and (lo > 0.0 or hi < 0.0))


def _scale_beside(sel) -> bool:
    """Whether the free uniform scale fitted beside the chosen effects (``beside_uniform``, the
    test against a constant) is significant: its 95 % interval leaves out 0, so the effects
    fitted without it take up an offset of the model (a calibration's) in their parameters."""
    b = sel.beside_uniform
    return b is not None and SCALE_KEY in b.theta and _excludes_zero(*_scale_fit(b)[1:])


def _surrogates(data: dict, names) -> tuple[str, str]:
    """Which surrogate each of the effects ``names`` was fitted through
    (:meth:`soilcal.loop.select.Surrogate.kind`) and the smallest of its rows' lack-of-fit p
    (:func:`soilcal.loop.select.smooth_fits`; NaN where none could be computed, e.g. two
    parameters), as the JSON of ``selection.csv``'s and ``loop_summary.csv``'s ``surrogate``
    and ``lack_of_fit_p``; effects without simulated data (the free uniform scale) left out."""
    kind, p = {}, {}
    for nm in names:
        if nm in data:
            kind[nm] = data[nm].surrogate.kind()
            lof = np.asarray([] if data[nm].lack_of_fit_p is None else data[nm].lack_of_fit_p, float)
            finite = lof[np.isfinite(lof)]
            p[nm] = round(float(np.min(finite)), 6) if len(finite) else math.nan
    return json.dumps(kind, sort_keys=True), json.dumps(p, sort_keys=True)


def _selection_row(step, s, names=None, data=None) -> dict:
    """A row of ``selection.csv``: a model tried (:class:`soilcal.loop.select.Score`), with
    which surrogate each effect's data (``data``: effect -> EffectData) went through.  Beside
    the plain held-out RMS errors, the weighted ones the selection compared
    (:meth:`soilcal.loop.select.Score.weighted_rmse`), NaN (an empty cell) where every row
    weighs alike."""
    names = names if names is not None else list(dict.fromkeys(k.split(".")[0] for k in s.names))
    kind, p = _surrogates(data or {}, names)
    wm, wr = (100 * s.weighted_rmse(), 100 * s.weighted_rmse(True)) if s.weighted else (math.nan, math.nan)
    return {"step": step, "effects": "+".join(names), "parameters": _fmt(s.theta), "ci95": _fmt_ci(s.ci),
            "heldout_rmse_percent": 100 * s.rmse(), "reference_heldout_rmse_percent": 100 * s.rmse(True),
            "weighted_heldout_rmse_percent": wm, "reference_weighted_heldout_rmse_percent": wr,
            "heldout_max_percent": 100 * s.max_error(), "aicc": s.aicc, "reference_aicc": s.ref_aicc,
            "p_paired": s.p, "accepted": s.accepted, "reason": s.reason, "surrogate": kind, "lack_of_fit_p": p}


def _fmt(d: dict) -> str:
    return json.dumps({k: (round(v, 6) if isinstance(v, float) else v) for k, v in d.items()}, sort_keys=True)


def _fmt_ci(d: dict) -> str:
    return json.dumps({k: [round(a, 6), round(b, 6)] for k, (a, b) in d.items()}, sort_keys=True)


def _heldout(s) -> tuple[str, float, float]:
    """The held-out RMS errors a decision on a :class:`soilcal.loop.select.Score` used, for a
    sentence: (words, the model's in %, its reference's in %).  Where the rows weigh differently
    (:func:`soilcal.loop.select.row_weights`) the selection compares the weighted errors
    (:meth:`soilcal.loop.select.Score.weighted_rmse`), and the words say "weighted held-out
    RMS"; else the plain ones, "held-out RMS"."""
    if s.weighted:
        return "weighted held-out RMS", 100 * s.weighted_rmse(), 100 * s.weighted_rmse(True)
    return "held-out RMS", 100 * s.rmse(), 100 * s.rmse(True)


@dataclass
class Outcome:
    residuals: pd.DataFrame
    diagnosis: pd.DataFrame
    ranking: pd.DataFrame
    candidates: list
    selection: pd.DataFrame
    summary: pd.DataFrame
    predictions: pd.DataFrame
    verdict: str
    chosen: list
    theta: dict
    diagnosis_after: pd.DataFrame = None
    detectable: pd.DataFrame = None  # soilcal.loop.diagnose.detectable of the calibrated model's residual
    filled: dict = None  # effect -> rows whose run failed at a design point (filled from the row's other points)
    skipped: dict = None  # effect -> why it was not tried (:func:`skipped`)
    fold_by: str | None = None  # the covariate column grouping the held-out folds (:func:`fold_grouping`)
    folds: str = ""  # which grouping the held-out folds used, and why (:func:`fold_grouping`)
    effect_data: dict = None  # effect -> its select.EffectData (surrogates), for a refit with joint runs
    uniform_scale: bool = False  # whether the chosen effects were fitted beside a free uniform scale
    floor_note: str = ""  # why the noise floor is empty, or which rows took a pooled variance (:func:`noise_floor`)
    floor_interval: tuple = (math.nan, math.nan, math.nan)  # its 95 % interval and degrees of freedom
    narrowed: dict = None  # effect -> select.Narrowing: fitted over the levels at which its scenario measured


def _follows(rank: pd.DataFrame, res: pd.DataFrame | None = None, quantity_of: dict | None = None,
             alpha: float = 0.05) -> str:
    """The covariate (or the bias) that explains most of the residual, or the excess
    scatter where that alone is significant; every other significant covariate after it,
    with the p of its structure beyond the first's (:func:`soilcal.loop.diagnose.beyond`,
    where the residual table ``res`` is given): a covariate that adds nothing beyond the
    first shares its structure (a campaign whose first day ran the faster speeds)."""
    if len(rank) == 0:
        return ""
    cov = rank[rank["covariate"] != "scatter"]
    scat = rank[rank["covariate"] == "scatter"]
    if len(scat) and bool(scat["significant"].iloc[0]) and (len(cov) == 0 or not bool(cov["significant"].iloc[0])):
        text = ("no covariate: it scatters beyond the measured and seed uncertainty "
                f"(chi-square, Holm p {scat['p_adjusted'].iloc[0]:.3g})")
        if len(cov) and float(cov["r2"].iloc[0]) > 0:  # the largest share, though not significant (few rows)
            top = cov.iloc[0]
            text += (f"; the largest share, not significant: {top['covariate']} (r2 {top['r2']:.2f}, "
                     f"Holm p {top['p_adjusted']:.3g})")
        return text
    if len(cov) == 0:
        return ""
    top = cov.iloc[0]
    text = f"{top['covariate']} (r2 {top['r2']:.2f}, Holm p {top['p_adjusted']:.3g})"
    if top.get("best_test") == "periodic" and np.isfinite(float(top.get("best_estimate", np.nan))):
        # a sine along the position: its wavelength, and the share and p of that test itself
        text = (f"{top['covariate']} periodically (a sine of wavelength {float(top['best_estimate']):.3g} in "
                f"{top['covariate']}'s unit, r2 {float(top['best_r2']):.2f}, Holm p {float(top['best_p_adjusted']):.3g})")
    if not bool(top["significant"]):
        return text
    also = []
    for other in cov.iloc[1:].itertuples():
        if not bool(other.significant):
            continue
        part = f"{other.covariate} (r2 {other.r2:.2f}, Holm p {other.p_adjusted:.3g}"
        if res is not None:
            p = dg.beyond(res, other.covariate, top["covariate"], quantity_of)
            if np.isfinite(p):
                part += f"; beyond {top['covariate']}: p {p:.3g}" + (", shared" if p >= alpha else "")
        also.append(part + ")")
    return text + ("; also " + ", ".join(also) if also else "")


def _interval(u: pd.DataFrame, effects: list, final, settings: Settings, joint=None) -> tuple[dict, str]:
    """The chosen effects' 95 % intervals and how they were found: the wider of the fit's
    own interval and the bootstrap over the seeds and the measured standard errors
    (:func:`soilcal.loop.select.bootstrap_ci`; the fit's interval carries a lack of fit
    beyond the measured scatter, the bootstrap the surrogates' seed scatter); the fit's
    alone where a row has no measured SD (its value cannot be redrawn) or
    ``loop.bootstrap`` is 0; the bootstrap's alone where the fit cannot bound a parameter."""
    fit = {k: v for k, v in (final.ci or {}).items() if np.isfinite(v[0]) and np.isfinite(v[1])}
    fit_only = "fit (Jacobian): the seeds' scatter in the surrogates left out"
    if not fit:
        fit_only = "none: the fit does not pin the parameters down"
    if settings.bootstrap <= 0:
        return final.ci, fit_only + " (loop.bootstrap: 0)"
    sd = u["measured_sd"].to_numpy(float) if "measured_sd" in u else np.full(len(u), np.nan)
    if not np.isfinite(sd).all():
        return final.ci, fit_only + " (a measured row without its SD: the bootstrap cannot redraw it)"
    n_meas = u["measured_n"].to_numpy(float) if "measured_n" in u else np.full(len(u), np.nan)
    se = sd / np.sqrt(np.where(np.isfinite(n_meas) & (n_meas >= 1), n_meas, 1.0))
    # rows of one simulation (a test measured twice, a job two tables share) share a draw
    labels = (u["simulation"].astype(str).tolist() if "simulation" in u
              else [f"{m}/{r}" for m, r in zip(u["measurement"], u["row"])])
    boot = sl.bootstrap_ci(effects, u["simulated_mean"].to_numpy(float), u["measured"].to_numpy(float), se,
                           settings.bootstrap, x0=[final.theta[nm] for nm in final.names], conditions=labels,
                           scale=rs.scale_of(u), joint=joint, weights=sl.row_weights(u))
    if boot is None:
        return final.ci, fit_only + " (too few seeds per condition to resample)"
    how = (f"a bootstrap of {settings.bootstrap} refits over each simulation's seeds and the measured standard errors "
           f"(generator seed {sl.BOOTSTRAP_SEED}" + ("; the effects' interaction held at its joint runs' value"
                                                      if joint is not None else "") + ")")
    if set(fit) != set(boot):
        return boot, how + ", alone: the fit does not bound every parameter"
    ci = {nm: (min(lo, fit[nm][0]), max(hi, fit[nm][1])) for nm, (lo, hi) in boot.items()}
    return ci, "the wider of the fit's (Jacobian) interval and " + how


#: covariate column names that identify a test day, session or group of replicates: the held-out
#: folds keep the rows of one such group together, declared or not (:func:`fold_grouping`)
GROUPING_NAMES = dg.GROUPING_NAMES
#: declared quantities whose column groups the held-out folds
GROUPING_QUANTITIES = ("day", "group")
#: values a column grouping the folds by its name alone (not declared) needs
NAMED_MIN_GROUPS = 3


def grouping_reason(col: str, q: str | None) -> str | None:
    """Why covariate column ``col`` (declaring quantity ``q``, or None) identifies test days,
    sessions or groups of replicates (:func:`fold_grouping`, rule 2), or None where it does not."""
    if q in GROUPING_QUANTITIES:
        return f"declared quantity: {q}"
    if q is None and dg.grouping_name(col):
        return "named as a test-day, session or replicate-group column"
    return None


def fold_grouping(settings: Settings, quantity_cols: dict, res: pd.DataFrame | None) -> tuple[str | None, str]:
    """(covariate column grouping the held-out folds or None for each measured condition, the
    sentence saying which and why, for the report).  The rule, in order:

    1. ``loop.fold_by``, where set;
    2. else a column that identifies test days, sessions or groups of replicates: one declared
       with ``quantity: day`` or ``quantity: group``, or one whose name is in
       :data:`GROUPING_NAMES` (``day``, ``date``, ``session``, ``batch``, ...) and that
       declares no other quantity; with two values at least on the usable rows (one test day
       leaves nothing to leak between folds).  Rows measured on one day share that day's
       level (the bed's preparation, the weather, the instrument's zero): held out one
       condition at a time, an offset that varies between days leaks from the fitted rows of
       the day into the held-out one, and an effect that follows the days' levels through a
       covariate (moisture measured per day) passes a paired test it should fail.  A declared
       column comes before a named one, and a named one needs :data:`NAMED_MIN_GROUPS` values;
       of several such columns the one with the fewest groups (the coarsest) is taken;
    3. else each measured condition (rows of one simulated test held out together)."""
    u = None
    if res is not None and len(res):
        u = rs.usable(res) if "relative_residual" in res else res
    if settings.fold_by:
        n = int(u[f"cov:{settings.fold_by}"].dropna().astype(str).nunique()) if (
            u is not None and f"cov:{settings.fold_by}" in u) else 0
        return settings.fold_by, (f"one fold per value of `{settings.fold_by}` ({n} group{'s' if n != 1 else ''}), "
                                  "as loop.fold_by sets")
    cols = [c[4:] for c in (u.columns if u is not None else []) if c.startswith("cov:")]
    found = []
    for j, col in enumerate(cols):
        q = (quantity_cols or {}).get(col)
        why = grouping_reason(col, q)
        if why is None:
            continue
        n = int(u[f"cov:{col}"].dropna().astype(str).nunique())
        found.append((q is None, n, j, col, why))
    # a declared column with two groups at least, else a column grouping by its name alone with
    # NAMED_MIN_GROUPS (a name is a weaker sign than a declaration, and two folds leave the
    # paired test one degree of freedom)
    many = [f for f in found if f[1] >= (NAMED_MIN_GROUPS if f[0] else 2)]
    if many:
        _, n, _, col, why = min(many)
        return col, (f"one fold per value of `{col}` ({n} groups; {why}): rows of one group share its level, and "
                     "are held out together (loop.fold_by sets another column)")
    one = ", ".join(f"`{col}`" for *_, col, _ in found)
    return None, ("one fold per measured condition" + (f" ({one} has one value on every usable row: nothing to "
                                                        "leak between groups)" if one else
                                                        " (no test-day, session or group column; loop.fold_by "
                                                        "names one)"))


#: a measured quantity whose median ratio to the simulated mean lies within this many decades of a
#: power of ten other than 1 (a factor within 26 % of 10, 100, 1000, ...) is said to look like a
#: value in another unit than its name's
UNIT_DECADES = 0.1


def unit_hints(u: pd.DataFrame) -> list[str]:
    """A sentence per measured quantity of a table (``u``: usable residual rows) whose measured
    values are about a power of ten (10 to 10^6, or its inverse) times the simulated ones, the
    median ratio within :data:`UNIT_DECADES` of it: a table in kN under a name in N, or in mm
    under a name in m, reads as a bias of -99.9 % that no effect of the library can explain.
    Where most of its rows have the other sign than the simulated, the sentence asks after the
    table's sign convention instead (a draught recorded as negative reads as a bias of -200 %)."""
    out = []
    if not len(u):
        return out
    for (m, q), g in u.groupby(["measurement", "measure"], sort=False):
        ratio = g["measured"].to_numpy(float) / g["simulated_mean"].to_numpy(float)
        ratio = ratio[np.isfinite(ratio) & (ratio != 0)]
        if len(ratio) and np.mean(ratio < 0) > 0.5:
            # most rows of the other sign: a sign convention, not a misfit (-200 % and below)
            out.append(f"the measured {q} of {m} has the other sign than the simulated in "
                       f"{int(np.sum(ratio < 0))} of {len(ratio)} rows (median ratio {np.median(ratio):.3g}): does the "
                       f"table count {q} with the other sign (a draught recorded as negative, the force on the tool "
                       "for the force on the soil)? give it with the simulation's sign")
            continue
        ratio = ratio[ratio > 0]
        if len(ratio) == 0:
            continue
        lg = float(np.log10(np.median(ratio)))
        k = int(round(lg))
        if k == 0 or abs(k) > 6 or abs(lg - k) > UNIT_DECADES:
            continue
        unit = str(g["unit"].iloc[0]) if "unit" in g else ""
        factor = f"{10 ** k:g}" if k > 0 else f"1/{10 ** -k:g}"
        out.append(f"the measured {q} of {m} is about {factor} times the simulated (median ratio "
                   f"{np.median(ratio):.3g}, the measured values read in {unit}): are the table's values in another "
                   "unit than the one its response declares (`unit`)?")
    return out


def rounding_step(x: float) -> float:
    """The step a recorded value was rounded to, read from its decimals: 10^-k for the fewest
    decimals k (0-12) that give it back (2 -> 1, 2.5 -> 0.1, 0.04 -> 0.01; trailing zeros of a
    whole number are not read as rounding, 1000 -> 1)."""
    for k in range(13):
        if abs(round(x, k) - x) <= 1e-9 * max(abs(x), 1e-300):
            return 10.0 ** -k
    return 0.0


def constant_hints(u: pd.DataFrame) -> list[str]:
    """A sentence per measured quantity of a table (``u``: usable residual rows) whose measured
    values are all one number over two measured conditions at least whose simulated values
    differ: a column filled down with one value, or the same cell pasted into every row, reads
    as a bias and trends of the model's own, which the verdict would otherwise explain.  The
    simulated values must differ by more than the measurement could hide: more than the
    rounding step of the recorded value (2 mm read to the millimetre holds anything from 1.5 to
    2.5 mm) and more than 4 measured SDs (the median of the rows'; +-1.96 SD about one value),
    else one value throughout is what the table would read if the model were right."""
    out = []
    if not len(u) or "simulation" not in u:
        return out
    for (m, q), g in u.groupby(["measurement", "measure"], sort=False):
        v, sim = g["measured"].to_numpy(float), g["simulated_mean"].to_numpy(float)
        if g["simulation"].astype(str).nunique() < 2 or np.unique(v).size != 1 or not np.isfinite(v[0]):
            continue
        sd = g["measured_sd"].astype(float).to_numpy() if "measured_sd" in g else np.full(len(g), np.nan)
        sd = float(np.median(sd[np.isfinite(sd)])) if np.isfinite(sd).any() else 0.0
        if np.ptp(sim) <= max(rounding_step(v[0]), 4.0 * sd, rs.EXACT * np.abs(sim).max()):
            continue
        unit = str(g["unit"].iloc[0]) if "unit" in g else ""
        out.append(f"every measured {q} of {m} is {v[0]:g}{' ' + unit if unit else ''} over its "
                   f"{g['simulation'].astype(str).nunique()} measured conditions, whose simulated values range "
                   f"{sim.min():.4g}-{sim.max():.4g}: is the column filled with one value?")
    return out


def _theta_keys(names: list) -> tuple[list[str], np.ndarray]:
    """The parameters of the effects ``names`` (``<effect>.<parameter>``, in their order) and
    their switched-off values."""
    keys = [f"{c}.{k}" for c in names for k in EFFECTS[c].theta_names()]
    null = np.array([float(EFFECTS[c].null[k]) for c in names for k in EFFECTS[c].theta_names()])
    return keys, null


def joint_interaction(u: pd.DataFrame, data: dict, names: list, joint: dict | None) -> sl.Joint | None:
    """The interaction (:class:`soilcal.loop.select.Joint`) of the chosen effects ``names`` from
    ``joint``: {"effects": their names, "theta": {"<effect>.<parameter>": value} where all were
    switched on together, "runs": those runs (measurement, row, measure, seed, value,
    status)}; None where ``joint`` is of other effects, an effect has more than one parameter
    or sits at its switched-off value there (no interaction to scale)."""
    if not joint or sorted(joint.get("effects") or []) != sorted(names) or any(data[c].surrogate.k != 1 for c in names):
        return None
    keys, null = _theta_keys(names)
    centre = np.array([float(joint["theta"][k]) for k in keys])
    if np.any(centre == null):
        return None
    stats = rs.simulated_stats(joint["runs"])
    means = u[rs.KEY].merge(stats, on=rs.KEY, how="left")["simulated_mean"].to_numpy(float)
    y0 = u["simulated_mean"].to_numpy(float)
    gap = sl.joint_gap([data[c] for c in names], y0, centre, means)
    if joint.get("base") is None:
        return sl.Joint(gap, centre, null)
    # a gap within JOINT_GAP_SE standard errors of the joint runs' change from the calibrated runs
    # (seed by seed) is their seeds' scatter, not an interaction: kept out (else, scaled towards
    # the switched-off value, one draw of a chaotic run's scatter acts as a slope beside the
    # effect's own); runs that share their random numbers (the same scatter at every parameter)
    # have a paired change without scatter and keep their gap
    se = u[rs.KEY].merge(paired_se(joint["runs"], joint["base"]), on=rs.KEY, how="left")["se"].to_numpy(float)
    return sl.Joint(np.where(np.abs(gap) > JOINT_GAP_SE * np.nan_to_num(se, nan=np.inf), gap, 0.0), centre, null)


def paired_se(runs: pd.DataFrame, base: pd.DataFrame) -> pd.DataFrame:
    """Per measured quantity (:data:`soilcal.loop.residuals.KEY`) the standard error of the mean
    change from ``base`` to ``runs`` over the seeds both ran (``se``; NaN below two seeds)."""
    cols = [*rs.KEY, "seed", "value"]
    ok = [f[cols][np.isfinite(pd.to_numeric(f["value"], errors="coerce").to_numpy(float))] for f in (runs, base)]
    d = ok[0].merge(ok[1], on=[*rs.KEY, "seed"], suffixes=("", "_base"))
    d["change"] = d["value"] - d["value_base"]
    g = d.groupby(rs.KEY)["change"]
    return (g.std(ddof=1) / np.sqrt(g.count())).rename("se").reset_index()


#: held-out groups below which the verdict of rejected candidates says how few they are
FEW_FOLDS = 5

#: rounds of joint runs at most (each at the parameters the last round fitted), and the change of
#: every parameter, as a share of its design's span, below which the fit has settled
JOINT_ROUNDS = 3
JOINT_SETTLED = 0.01
#: standard errors of the paired change a row's joint gap must exceed to count as an interaction
#: (:func:`joint_interaction`)
JOINT_GAP_SE = 2.0


def _not_separated(sel, alpha: float) -> str:
    """The verdict's clause on each effect the forward step took beside the chosen ones and the
    backward gate then dropped (:func:`soilcal.loop.select.forward`): what it gained and which
    part of the gate it failed, so that an effect the rows show but cannot separate from the
    others is named, not left out unsaid (a hidden adhesion beside a rate effect under an 8 %
    offset halved the held-out error and lowered the AICc by 54 while its paired test over six
    test days gave p 0.059)."""
    out = ""
    dropped = []
    for nm in sel.forward_chosen:
        drop = [s for step, _, s in sel.steps if step == "gate" and not s.accepted
                and s.reason.startswith(f"without {nm},")]
        # named on the same rule as a held-back one below: it lowers the held-out error by
        # MIN_IMPROVEMENT and the AICc and misses only the paired test
        if nm not in sel.chosen and drop and sl.short_of_p(drop[-1], alpha):
            dropped.append((nm, drop[-1]))
    # those the forward step tried beside a free uniform scale, which gained against the chosen
    # effects with the scale but not against them as is (the last such try of each effect), named
    # only where against the model as is they lower the held-out error by MIN_IMPROVEMENT and the
    # AICc and miss only the paired test: against the chosen effects with the scale almost any
    # effect gains where no offset is in the rows (a trend in an independent random covariate was
    # named at held-out 2.34 against 2.52 % and AICc -126.6 against -129.2)
    dropped += [(nm, g) for nm, g in dict(sel.held_back).items()
                if nm not in sel.chosen and nm not in dict(dropped) and sl.short_of_p(g, alpha)
                and {k.split(".")[0] for k in g.names} - {nm, sl._ScaleEffect.name} == set(sel.chosen)]
    for nm, g in dropped:
        beside = " beside a free uniform scale" if sl._ScaleEffect.name in {k.split(".")[0] for k in g.names} else ""
        aicc = (f", AICc {g.aicc:.1f} against {g.ref_aicc:.1f}" if np.isfinite(g.aicc) and np.isfinite(g.ref_aicc)
                else "")
        words, rm, rr = _heldout(g)
        out += (f"; {nm} was not separated from " + (" + ".join(sel.chosen) or "the model") + f"{beside}: with it the "
                f"{words} error is {rm:.2f} % against {rr:.2f} %{aicc}, "
                + (f"paired p {g.p:.2g} over {int(np.isfinite(g.fold_rms).sum())} held-out groups (alpha {alpha:g})"
                   f", so it stays out ({g.own_reason or g.reason})" if np.isfinite(g.p)
                   else g.p_text() + ", so it stays out") + ", and the "
                "parameters and any uniform scale reported are fitted without it; these rows can "
                "neither name nor rule it out (more groups decide)")
    return out


def _few_groups_clause(sel, u: pd.DataFrame, fold_by, alpha: float, judged: bool = False) -> str:
    """Where a candidate (``judged``: a judged effect beside the uniform scale) failed a paired
    test over few held-out groups (over the folds, or over the conditions with the mean's
    variance from the between-group mean square): how many groups and degrees of freedom that
    test had, which passes only a large gain, so the verdict says what would decide."""
    groups = len(sl._folds(u, fold_by).held_out) if fold_by else 0
    if sel is None or not 2 <= groups < FEW_FOLDS:
        return ""
    scores = [s for _, _, s in sel.steps] + ([sel.beside_uniform] if judged and sel.beside_uniform else [])
    few = sorted({s.test.df for s in scores
                  if s.test is not None and not s.accepted and not s.p < alpha
                  and (s.test.test == "folds" or s.test.variance == "between")})
    if not few:
        return ""
    df = few[0]
    return (f"; the rows were held out by `{fold_by}`, {groups} groups, and the paired test that "
            f"{'judged it' if judged else 'rejected a candidate'} had {df} degree{'s' if df != 1 else ''} of freedom "
            "over them; it passes only a large gain (more groups decide; loop.fold_by sets the grouping)")


def _beside_clause(sel, alpha: float) -> str:
    """Why the uniform-bias verdict finds the judged effects no more than a constant beside a
    free uniform scale (:func:`soilcal.loop.select.like_a_constant`)."""
    b, k = sel.beside_uniform, len(sel.judged)
    if not _aicc_undefined(b):
        return (f"add{'s' if k == 1 else ''} nothing beside a free uniform scale ({b.reason}; AICc "
                f"{b.aicc:.1f} against {b.ref_aicc:.1f} for the scale alone)")
    # too few rows to score them beside the scale: judged against it alone
    out = f"cannot be scored beside a free uniform scale ({b.reason})"
    if not sel.uniform.accepted:
        return out + f" and alone do{'es' if k == 1 else ''} not beat the uniform scale ({sel.uniform.reason})"
    out += f"; alone {'it beats' if k == 1 else 'they beat'} the uniform scale ({sel.uniform.p_text()}), but "
    if not (sl.lowers_heldout(b) and np.isfinite(b.p) and b.p < alpha):
        words, rm, rr = _heldout(b)
        return out + (f"beside it {'it does' if k == 1 else 'they do'} not lower the held-out error significantly "
                      f"({words} {rm:.2f} % against {rr:.2f} %, {b.p_text()})")
    return out + f"the selection's gates did not keep {'it' if k == 1 else 'them'}"


def _bias_fits_as_well(s, sv: float, k: int) -> str:
    """The verdict's clause where the ``k`` chosen effects do not beat a free uniform scale
    alone (``s``: their :class:`soilcal.loop.select.Score` against it, not accepted; ``sv``: the
    scale's value): the bias fits the held-out rows "as well or better" where its held-out RMS
    error is not above the effects', else "nearly as well", judged and quoted on the errors the
    selection compared (:func:`_heldout`: weighted where the rows weigh differently)."""
    words, rm, rr = _heldout(s)
    how = "as well or better" if s.weighted_rmse(True) <= s.weighted_rmse() else "nearly as well"
    return (f"; a uniform bias fits the held-out rows {how} (the measured values "
            f"{abs(100 * sv):.1f} % {'above' if sv > 0 else 'below'} the model throughout: {words} "
            f"{rr:.2f} % against {rm:.2f} % "
            f"with the effect{'s' if k > 1 else ''}, {s.p_text()}), "
            "so these rows cannot tell "
            + ("it" if k == 1 else "them") + " from a bias no mechanism carries")


def _judged_alone(sel, alpha: float) -> str:
    """The verdict's warning where the chosen effects were kept for beating a free uniform scale
    alone, the comparison beside it not deciding (:func:`soilcal.loop.select.rule_of_one`): a
    uniform bias beside them would sit in their parameters, and these rows cannot show it."""
    if not sl.rule_of_one(sel, alpha):
        return ""
    b, one = sel.beside_uniform, len(sel.chosen) == 1
    if _aicc_undefined(b):
        scored = "could not be scored"
    else:
        scored = (f"lower{'s' if one else ''} the held-out error, but the AICc, on the fewest observations that "
                  "define it, is decided by its small-sample term")
    words, rm, rr = _heldout(sel.uniform)
    return (f"; beside a free uniform scale {'it' if one else 'they'} {scored} ({b.reason}), "
            f"so {'it was' if one else 'they were'} judged against that scale alone, which "
            f"{'it beats' if one else 'they beat'} ({words} {rm:.2f} % "
            f"against {rr:.2f} %, {sel.uniform.p_text()}); "
            f"whether a uniform bias lies beside {'it' if one else 'them'} these rows cannot tell: "
            f"{'its parameter' if one else 'their parameters'} may hold it")


def scatter_about_scale(res: pd.DataFrame, s: float) -> tuple[float, int, float]:
    """(chi-square, degrees of freedom, p) of the residual about the model times (1 + s), the
    uniform scale s that minimises that chi-square (``s``: the verdict's fitted scale, a
    starting point; NaN gives NaN).  A uniform bias (a load cell's calibration) shifts every
    row alike and leaves the rows within their measured and seed uncertainty about it; a few
    rows far off (stones in the bin) raise the mean as much but scatter about it beyond that
    uncertainty.

    Per simulation (a measured condition, its replicate rows on other days included) and
    measured quantity, the rows with a measured SD (variance sd^2 / n each) split into the
    residual of their inverse-variance mean about the prediction, over its standard error
    sqrt(1 / sum(1 / var_m) + (1 + s)^2 sd_s^2 / n_s) (the seed part scales with the
    prediction; replicates share one simulated mean and so its seeds' error) as the unit-normal
    deviate of the same tail probability
    (:func:`soilcal.loop.diagnose.normal_equivalent`) on the Welch-Satterthwaite degrees of
    freedom of its measured and seed parts (from the variances pooled over the quantity's
    rows, :func:`soilcal.loop.residuals.reference_variances`), squared, and the chi-square of the
    replicates about their mean (sum (m_i - mean)^2 / var_m with var_m the measured variance
    pooled over the quantity's rows, read as F on its degrees of freedom and given as the
    chi-square of the same tail, one degree of freedom fewer than them), which together are the generalised chi-square of rows sharing a seed error.
    Replicate rows without an SD give the first part against their own scatter
    (:func:`soilcal.loop.diagnose.replicate_residuals`).  Table rows entered twice count once.
    The quantities one condition measures (its horizontal and vertical force) share its stone,
    its day and its repeats' noise: a condition counts once, with the mean over its quantities
    of each part (so the test errs towards a uniform bias).  The scale minimising the sum is
    fitted, so the sum is compared with chi-square on one degree of freedom fewer than the
    conditions plus the replicates' degrees of freedom.  Before, the seed part was not scaled,
    replicates were counted as independent and the scale was the selection's, not this
    chi-square's: 12 conditions 25 % high, 1 % measured noise (n 10), 5 % seed scatter over 3
    seeds, p < 0.05 in 35 % of 200 tables (mean chi-square per degree of freedom 1.70).  NaN
    where no row has a measured SD or replicates, or fewer than two conditions do."""
    from scipy import optimize, stats

    if not np.isfinite(s):
        return math.nan, 0, math.nan
    u = rs.usable(res).copy()
    if not {"measure", "measured", "simulated_mean"} <= set(u.columns) or not len(u):
        return math.nan, 0, math.nan
    if "simulation" not in u:  # each row its own simulation (:func:`soilcal.loop.residuals.residual_frame`)
        u["simulation"] = u["measurement"].astype(str) + "/" + u["row"].astype(str)
    if "simulated_sd" not in u:  # no seed scatter stated
        u["simulated_sd"], u["simulated_n"] = np.nan, 0
    sd_m = u["measured_sd"].astype(float).to_numpy() if "measured_sd" in u else np.full(len(u), np.nan)
    n_m = u["measured_n"].astype(float).fillna(1.0).clip(lower=1.0).to_numpy() if "measured_n" in u else np.ones(len(u))
    known = np.isfinite(sd_m) & (sd_m > 0) & np.isfinite(u["measured"].astype(float).to_numpy())
    # the variances the degrees of freedom are computed from, and whether they are pooled: over
    # every row, as the residual table's degrees of freedom are (a row entered twice pooled once)
    ref_m, ref_s, pool_m, pool_s = rs.reference_variances(u, flags=True)
    # the degrees of freedom of the pooled measured SD (ref_m) of each row's quantity
    pooled_dof = rs.pooled_measured_dof(u, known)  # 0 where the quantity's SDs are not pooled
    # a table row entered twice, or copied into a second table, is one condition here
    keep = rs.first_entries(u, across_tables=True)
    u = u.loc[keep]
    sd_m, n_m, known, ref_m, ref_s, pool_m, pool_s, pooled_dof = (
        np.asarray(a)[keep] for a in (sd_m, n_m, known, ref_m, ref_s, pool_m, pool_s, pooled_dof))
    groups = []  # per simulation: its quantities' (measured mean, var_m, dof_m, sim, seed var, n_s, within chi, within dof)
    for _, g in u.groupby(u["simulation"].astype(str), sort=False):
        parts = []
        kg = known[u.index.get_indexer(g.index)]
        for _, q in g[kg].groupby(g[kg]["measure"].astype(str), sort=False):
            m = q["measured"].to_numpy(float)
            at = u.index.get_indexer(q.index)
            vm = (q["measured_sd"].to_numpy(float) ** 2) / n_m[at]
            w = 1.0 / vm
            mean = float(np.sum(w * m) / np.sum(w))
            dof_m = float(np.sum(np.clip(n_m[at] - 1.0, 0.0, None))) or np.inf
            # the replicates' scatter about their mean against the measured SD pooled over the
            # quantity's rows, read as F on that SD's degrees of freedom and given as the
            # chi-square of the same tail: against each row's own SD of a few repeats, it is a
            # sum of t^2, not chi-square (6 conditions x 3 days, 2 % noise over 5 repeats, 3 %
            # seed scatter, no offset: chi-square per degree of freedom 1.30, p < 0.05 in 20 %)
            within = rs.replicate_scatter_chi(m, ref_m[at], pooled_dof[at[0]], q["measured_sd"].to_numpy(float), n_m[at])
            parts.append((mean, 1.0 / float(np.sum(w)), dof_m, float(q["simulated_mean"].iloc[0]),
                          float(q["simulated_sd"].iloc[0]), float(q["simulated_n"].iloc[0]),
                          within, len(m) - 1,
                          1.0 / float(np.sum(1.0 / ref_m[at])), float(np.mean(ref_s[at])),
                          bool(np.all(pool_m[at] & pool_s[at]))))
        rep = g[~kg]
        # the replicate rows without an SD gathered once, standardised at each scale tried
        groups.append((parts, dg.replicate_conditions(rep) if len(rep) else None, len(rep)))
    if not any(p or r for p, _, r in groups):
        return math.nan, 0, math.nan

    def chi_of(scale: float) -> tuple[float, int, int]:
        # per simulation its quantities' deviates and degrees of freedom, then every deviate's
        # unit-normal equivalent at once
        zs, dofs, rows = [], [], []
        for parts, rep, _ in groups:
            at, within, wdof = [], [], []
            for mean, var_m, dof_m, sim, sd_s, n_s, wchi, wd, rm, rs_, pooled in parts:
                var_s = (1.0 + scale) ** 2 * sd_s ** 2 / n_s if np.isfinite(sd_s) and n_s >= 1 else 0.0
                se = math.sqrt(var_m + var_s)
                if not (np.isfinite(sim) and se > 0):
                    continue
                # Welch-Satterthwaite from the variances pooled over the quantity's rows
                # (:func:`soilcal.loop.residuals.reference_variances`): from the condition's own
                # it grows where its 3 seeds happen to scatter little, exactly where the residual
                # is large; the fewer of the two parts' degrees of freedom instead takes a
                # residual as heavy-tailed as 3 seeds make it where the seed part is negligible.
                # Where a part keeps the row's own SD (not pooled: SDs not proportional to the
                # value), the fewer of the two parts' degrees of freedom, Welch-Satterthwaite's
                # from the own SDs growing with their luck (5 N +- 2 N beside 500 N +- 10 N, scaled
                # by their RMS: p < 0.05 in 9 % of right tables, the fewer 0 %)
                dof = (float(rs.satterthwaite(rm, dof_m, (1.0 + scale) ** 2 * rs_ if var_s > 0 else 0.0, n_s - 1.0))
                       if pooled else min(dof_m if var_m > 0 else np.inf, n_s - 1.0 if var_s > 0 and n_s > 1 else np.inf))
                z = (mean - sim * (1.0 + scale)) / se
                at.append(len(zs))
                zs.append(z)
                dofs.append(dof)
                within.append(wchi)
                wdof.append(wd)
            zr, dofr = dg.replicate_standardised(rep, 1.0 + scale)
            rows.append((at, len(zs), len(zr), within, wdof))
            zs += zr.tolist()
            dofs += dofr.tolist()
        ne = dg.normal_equivalent(zs, dofs)
        total, n_cond, dof_within = 0.0, 0, 0
        for at, r0, nr, within, wdof in rows:
            between = [float(ne[j]) ** 2 for j in at] + list(ne[r0:r0 + nr] ** 2)
            if between:
                total += float(np.mean(between)) + (float(np.mean(within)) if within else 0.0)
                n_cond += 1
                dof_within += int(round(np.mean(wdof))) if wdof else 0
        return total, n_cond, dof_within

    _, n_cond, dof_within = chi_of(s)
    if n_cond < 2:
        return math.nan, 0, math.nan
    lo, hi = min(-0.9, s - 1.0), max(5.0, s + 1.0)
    fit = optimize.minimize_scalar(lambda x: chi_of(x)[0], bounds=(lo, hi), method="bounded",
                                   options={"xatol": 1e-6})
    best = fit.x if chi_of(fit.x)[0] <= chi_of(s)[0] else s
    chi = chi_of(best)[0]
    k = n_cond - 1 + dof_within
    return chi, k, float(stats.chi2.sf(chi, k))


def _scatter_about_holm(res: pd.DataFrame, s: float, diag: pd.DataFrame) -> tuple[float, int, float]:
    """:func:`scatter_about_scale` with its p corrected together with the diagnosis's tests
    (Holm), one more test of that family."""
    chi, dof, p = scatter_about_scale(res, s)
    if np.isfinite(p) and len(diag):
        p = float(dg.holm_adjusted(np.append(diag["p"].fillna(1.0).to_numpy(float), p))[-1])
    return chi, dof, p


def _far_off(diag: pd.DataFrame) -> str:
    """Why rows scatter about a mean offset: the significant covariates of the diagnosis, where
    there are (a day's level), else a reason no covariate carries (stones in the bin)."""
    sig = diag[diag["significant"].astype(bool) & ~diag["test"].isin(["bias", "scatter"])] if len(diag) else diag
    names = list(dict.fromkeys(sig["covariate"].astype(str))) if len(sig) else []
    if names:
        return "their levels follow " + ", ".join(names) + " (the diagnosis)"
    return "some rows lie far off for a reason no covariate carries (stones in the bin, a disturbance)"


#: what the nuisance column adds where the replicates scatter unevenly (:func:`_replicate_spread`)
UNEVEN_SPREAD_WORDS = ("; its replicates scatter unevenly across conditions (stones, or rig noise neither one share "
                       "of the value nor one floor)")


def _replicate_spread(u: pd.DataFrame, alpha: float) -> str:
    """The verdict's note ("" for none) where replicate rows without a measured SD scatter about their
    conditions' means far more in some conditions than in others
    (:func:`soilcal.loop.diagnose.replicate_spread`, p below ``alpha``).
    Two causes give that: stones met in some replicates and not others (those rows' means are
    judged against their own scatter, so such rows read as within the uncertainty), and rig
    noise that is neither one share of the value nor one floor (an SD growing as value^1.5, or
    2 % of the reading plus a 5 N floor), which a uniform bias rides on unchanged.  The rows
    cannot tell them apart, so the note names both and withholds no verdict: a uniform 10 %
    offset on a rig of SD proportional to value^1.5 (24 conditions x 3 days) brought the note
    in 9 of 20 tables, where it had withheld the uniform bias."""
    sp = dg.replicate_spread(u)
    if sp is None or not sp["p"] < alpha:
        return ""
    return (f"; the replicate rows (no measured SD) scatter about their conditions' means unevenly: "
            f"{sp['widest_percent']:.2g} % in the widest condition, {sp['narrowest_percent']:.2g} % in the "
            f"narrowest, {sp['replicate_percent']:.2g} % pooled (Bartlett's test on {sp['dof'][0]} degrees of freedom, "
            f"p {sp['p']:.2g}), which a uniform bias does not cause but either of two things does: stones met in "
            "some replicates and not others, or rig noise that is neither one share of the value nor one floor; "
            "these rows cannot tell the two apart (a measured SD per row does), and if it is stones, a row raised "
            "far off looks within the uncertainty against that scatter")


def _aicc_undefined(s) -> bool:
    """Whether a :class:`soilcal.loop.select.Score` could not be scored for an undefined AICc
    (of the model or its reference: too few observations, :func:`soilcal.loop.select.aicc`)."""
    return math.isnan(s.aicc) or math.isnan(s.ref_aicc)


def _rejected(sel_rows: list) -> str:
    """The verdict's list of rejected candidates (``selection.csv`` rows with a reason): a try
    scored against the model held as is (step ``2, against X as is``) is told from the same
    effects scored against that model with the scale, under whose name it was listed twice."""
    return "; ".join(f"{r['effects']}"
                     + (f" ({str(r['step']).split(', ', 1)[1]})" if ", against " in str(r["step"]) else "")
                     + f": {r['reason']}" for r in sel_rows if r["reason"])


def _unscored(sel, u: pd.DataFrame, alpha: float = 0.05) -> str:
    """The verdict's clause on the models the selection could not score: too few observations
    for their parameters to define an AICc (:func:`soilcal.loop.select.aicc`), named where their
    held-out error is at least MIN_IMPROVEMENT lower, whatever their paired p (on 4 or 5
    conditions it has 3 or 4 degrees of freedom: a model 85 % lower at p 0.069 was left unsaid
    beside the effect chosen), each with its held-out errors and paired p; empty where every
    such model also failed the held-out error."""
    groups = sl.replicate_groups(u)
    seen = {}
    for step, names, s in sel.steps:
        if step == "gate" or not math.isnan(s.aicc) or s.accepted:
            continue
        if not sl.lowers_heldout(s):
            continue  # its held-out error refused it as well: the undefined AICc is not why it stayed out
        n_obs = sl.sse_of(s.fitted_errors, groups)[1]
        # with what the held-out test showed: the clause is not a sign that the rows favour the
        # model (on 4 conditions with no effect in them, 2 % noise, it was given in 10 of 40
        # tables, paired p up to 0.41)
        words, rm, rr = _heldout(s)
        held = (f"{words} {rm:.2f} % against {rr:.2f} %, "
                + (f"paired p {s.p:.2g}" + ("" if s.p < alpha else f" >= {alpha:g}, which does not decide either")
                   if np.isfinite(s.p) else s.p_text()))
        seen.setdefault((len(s.names) + 1, n_obs), {}).setdefault("+".join(names), held)
    out = ""
    for (k, n_obs), models in sorted(seen.items()):
        need = sl.aicc_needs(k)
        out += (f"; {', '.join(f'{m} ({h})' for m, h in models.items())} could not be scored: on {n_obs} "
                f"observations (measured conditions and quantities, replicates as one) the AICc of {k} estimated "
                f"parameters (the residual variance among them) is undefined; it needs {need}, {need - n_obs} more "
                "(selection.csv)")
    return out


def _design_key(runs: pd.DataFrame, effect) -> tuple:
    """The levels an effect's runs were simulated at (its design, as run)."""
    cols = [sl.T_PREFIX + k for k in effect.theta_names() if sl.T_PREFIX + k in runs.columns]
    if not cols or not len(runs):
        return ()
    return tuple(sorted({tuple(float(x) for x in t) for t in runs[cols].itertuples(index=False)}))


@dataclass
class _Rounds:
    """What the rounds of one :func:`run_inprocess` share (:func:`_analyse`; the same residual
    table, runs and settings): the selection by the tuple of candidates (their
    select.EffectData by name, those that could not be fitted with why, the Selection), each
    candidate's select.EffectData (or why it could not be fitted), and the models the
    selections scored (``select.forward``'s ``shared``).  Kept for one residual table only
    (``table``, the first one analysed): analysing another table with the same rounds is refused,
    since its candidates' fits would be those of the first table."""

    selections: dict = dataclasses.field(default_factory=dict)
    effect_data: dict = dataclasses.field(default_factory=dict)
    models: dict = dataclasses.field(default_factory=dict)
    table: object = None
    narrowed: dict = dataclasses.field(default_factory=dict)

    def check(self, res) -> None:
        """Bind the rounds to the residual table ``res`` or check they are bound to it."""
        if self.table is None:
            self.table = res
        elif self.table is not res:
            raise ValueError("the loop's rounds share their fits within one residual table; "
                             "another table was given")


def analyse(soil: str, res: pd.DataFrame, diag: pd.DataFrame, cands: list, effect_runs: dict,
            settings: Settings, reference: dict, quantity_cols: dict | None = None,
            skipped_effects: dict | None = None, joint: dict | None = None, interval: bool = True) -> Outcome:
    """Steps 5 (module docstring): ``effect_runs`` maps each candidate to its runs
    (measurement, row, measure, value, ``t:<name>``), the switched-off point included; rows of
    one simulation (the residual table's ``simulation`` key) share the bootstrap's draws;
    ``skipped_effects`` (:func:`skipped`) are named in the verdict where the structure (or
    ``loop.candidates: all``) would have tried them; ``joint``: runs with the chosen effects
    switched on together (:func:`joint_interaction`), with which two or more chosen effects
    are fitted with their interaction, else as the sum of their separate changes (the verdict
    says so); ``interval`` False: without the chosen effects' interval (its bootstrap), the
    summary's ``ci95`` left ``{}`` (:func:`_analyse`)."""
    return _analyse(soil, res, diag, cands, effect_runs, settings, reference, quantity_cols, skipped_effects,
                    joint, interval)[0]


def _analyse(soil: str, res: pd.DataFrame, diag: pd.DataFrame, cands: list, effect_runs: dict,
             settings: Settings, reference: dict, quantity_cols: dict | None, skipped_effects: dict | None,
             joint: dict | None, interval: bool, selections: _Rounds | None = None) -> tuple[Outcome, tuple | None]:
    """:func:`analyse` and, where ``interval`` is False, the chosen effects' interval left out
    of the summary (its ``ci95`` ``{}``, ``ci95_method`` only the words that follow the
    interval's own): (the outcome, what :func:`_with_interval` needs to fill it in, or None
    where there is nothing to fill in).  The interval's bootstrap refits the model
    ``loop.bootstrap`` times; :func:`run_inprocess` computes it only for the round whose
    outcome it returns.  Where the chosen effects are refitted beside a free uniform scale
    the summary gives that fit's interval, and no bootstrap is run.  ``selections``
    (:class:`_Rounds`): the candidates' surrogates and the selection over them
    (:func:`soilcal.loop.select.forward`) by the tuple of candidates, kept across the rounds
    of one :func:`run_inprocess` (the same residual table, runs and settings): ``joint``
    changes neither, only the chosen effects' fit after them, so a round with joint runs
    reuses the selection of the round before it instead of repeating it; a round with more
    candidates reuses the surrogates of those it shares with the round before and the
    models over them, fitted and cross-validated there."""
    u = rs.usable(res)
    weights = sl.row_weights(u)  # the selection's weights of the rows (None: alike), for every fit of them below
    floor = sl.heldout_floor(u, weights)  # the noise floor's interval, for every reference below (select.lowers_heldout)
    spread_note = _replicate_spread(u, settings.alpha)  # the verdict's note ("": none) and its nuisance words
    rank = dg.ranking(diag)
    follows = _follows(rank, res, quantity_cols, settings.alpha)
    sel_rows, chosen, theta, ci, ci_method = [], [], {}, {}, ""
    pred = u[["measurement", "row", "measure", "measured", "simulated_mean"]].copy()
    before = u["relative_residual"].to_numpy(float)
    after_cv = before.copy()
    n = len(u)
    structure = bool(diag["significant"].any()) if len(diag) else False
    verdict = ""
    nuisance = ({}, {}, "")  # a free uniform scale fitted beside (or instead of) the effects: value, interval, how
    provisional = []
    sel = None
    pending = None  # the interval left out (interval False): _with_interval's inputs
    data = {}
    fold_by, fold_text = fold_grouping(settings, quantity_cols, res)
    unfit = {}
    narrowed = {}  # effect -> select.Narrowing: fitted over the levels where its scenario measured
    if n >= 3 and cands:
        rounds = selections if selections is not None else _Rounds()
        rounds.check(res)
        # an effect's runs past the levels where its scenario stops measuring leave it the
        # working range (select.narrowing); keyed by its design, which a second round extends
        designs = {nm: _design_key(effect_runs[nm], EFFECTS[nm]) for nm in cands}
        sel_key = tuple((nm, designs[nm]) for nm in cands)
        if sel_key in rounds.selections:
            data, unfit, sel = rounds.selections[sel_key]
        else:
            for nm in cands:  # an effect whose runs failed at too many design points cannot be fitted
                key = (nm, designs[nm])
                if key not in rounds.effect_data:
                    if any(k[0] == nm for k in rounds.effect_data):
                        rounds.models.clear()  # the models fitted over its earlier design
                    nar = sl.narrowing(effect_runs[nm], EFFECTS[nm], settings.design_points)
                    runs_nm, bounds_nm = effect_runs[nm], settings.effect_bounds(nm)
                    if nar is not None:
                        runs_nm, bounds_nm = sl.within(runs_nm, nar), {**bounds_nm, nar.param: (nar.low, nar.high)}
                    try:
                        if nar is not None and nar.low == nar.high:
                            raise ValueError(nar.text())
                        rounds.effect_data[key] = sl.build_effect_data(u, runs_nm, EFFECTS[nm], bounds_nm,
                                                                       reference if settings.surrogate == "pooled" else None)
                    except ValueError as exc:
                        rounds.effect_data[key] = str(exc)
                    rounds.narrowed[key] = nar
                built = rounds.effect_data[key]
                if isinstance(built, str):
                    unfit[nm] = built
                else:
                    data[nm] = built
            if fold_by and f"cov:{fold_by}" not in u.columns:
                raise InputError("<soil>", "loop.fold_by", "a covariate column of the measured tables", fold_by)
            sel = sl.forward(u, u["simulated_mean"].to_numpy(float), data, fold_by, settings.alpha,
                             settings.max_effects, shared=rounds.models, floor=floor)
            rounds.selections[sel_key] = (data, unfit, sel)
        narrowed = {nm: rounds.narrowed[(nm, designs[nm])] for nm in cands
                    if rounds.narrowed.get((nm, designs[nm])) is not None}
        for nm, why in unfit.items():
            sel_rows.append({"step": 1, "effects": nm, "parameters": "{}", "ci95": "{}", "accepted": False,
                             "reason": f"not fitted: {why}"})
        for step, names, s in sel.steps:
            sel_rows.append(_selection_row(step, s, names, data))
        for step, s in (("against uniform scale", sel.uniform), ("beside uniform scale", sel.beside_uniform)):
            # (the effects judged there: the chosen, else those the forward step took)
            if s is not None:  # the chosen effects against a free uniform scale alone, and beside it
                sel_rows.append(_selection_row(step, s, data=data))
        provisional = list(sel.forward_chosen)
    # the residual the chosen effects leave (or, where the gate dropped them all, the forward
    # step's model: what it leaves may name an effect the first round masked), diagnosed once
    after, left, fitted = None, "", None
    names = (sel.chosen or provisional) if sel is not None else []
    uniform = None  # the chosen effects' fit beside a free uniform scale (Score), where a bias is left
    jt = joint_interaction(u, data, sel.chosen, joint) if sel is not None and sel.chosen else None
    if names:
        y0, meas = u["simulated_mean"].to_numpy(float), u["measured"].to_numpy(float)
        m = sl.Model([data[c] for c in names], y0, meas, rs.scale_of(u), jt, weights)
        x, _ = m.fit()
        fitted = m.predict(x)
        res_after = residual_after(res, fitted)
        after = dg.diagnose(res_after, quantity_cols, settings.alpha)
        bias_left = bool(((after["test"] == "bias") & after["significant"].astype(bool)).any())
        if sel.chosen and ((bias_left and not any("bias" in EFFECTS[c].signature for c in sel.chosen))
                           or sel.with_scale or _scale_beside(sel)):
            # a bias no chosen effect can carry pulls their parameters to make up for it, and so
            # does an offset beside an effect that carries a bias (an adhesion fitted alone under
            # an 8 % offset ran to its bound): refit them beside a free uniform scale of the
            # model (select.scale_data), and say it
            bias, sc = sl.scale_data(), rs.scale_of(u)
            ref = sl.Model([bias], y0, meas, sc, weights=weights, base=[data[c] for c in names], floor=floor)
            m = sl.Model([data[c] for c in names] + [bias], y0, meas, sc, jt, weights)
            uniform = sl.score(m, ref, sl._folds(u, fold_by), settings.alpha, groups=sl.replicate_groups(u))
            sel_rows.append(_selection_row("refit beside uniform scale", uniform, data=data))
            x = np.array([uniform.theta[k] for k in uniform.names], float)
            fitted = m.predict(x)
            res_after = residual_after(res, fitted)
            after = dg.diagnose(res_after, quantity_cols, settings.alpha)
        rest = dg.ranking(after)
        scatter_left = after[(after["test"] == "scatter") & after["significant"].astype(bool)]
        rest = rest[rest["significant"].astype(bool) & (rest["covariate"] != "scatter")]
        if len(rest) and sel.chosen:
            left = _follows(rest, res_after, quantity_cols, settings.alpha)
        elif len(scatter_left) and sel.chosen:
            # no covariate, but the rows still scatter about the chosen effects' prediction
            # beyond their measured and seed uncertainty (an offset the effect's parameter took
            # up only in part, stones): a part of the residual no effect accounted for
            left = ("no covariate but scatters beyond the measured and seed uncertainty (Holm p "
                    f"{float(scatter_left['p_adjusted'].min()):.2g})")
    if n == 0:
        measured = np.isfinite(res["measured"].astype(float)).any() if len(res) else False
        verdict = ("no simulated value to compare with: every run of the measured conditions failed or none ran"
                   if measured else "no measured value to compare with (nothing to diagnose)")
    elif bool(np.all(np.abs(before) <= rs.EXACT)):
        verdict = (f"consistent: every measured value equals the simulated mean (largest relative residual "
                   f"{float(np.max(np.abs(before))):.2g}): there is no residual to explain (is the table the "
                   "model's own values?)")
    elif n < 3:
        verdict = f"unexplained: too few measured values to decide ({n})"
    elif sel is not None and sel.judged and sl.like_a_constant(sel, settings.alpha):
        # the chosen effects (or, where the gates beside a free uniform scale dropped them all,
        # those the forward step took) add nothing beside that scale: the rows show a uniform
        # offset (an instrument's calibration), not the effects' signature
        sv, b, k = sel.uniform_s, sel.beside_uniform, len(sel.judged)
        nuisance = ({SCALE_KEY: sv}, {SCALE_KEY: sel.uniform_ci},
                    "fitted alone: the uniform bias the verdict names, the calibrated model times (1 + s)")
        beside = _beside_clause(sel, settings.alpha)
        chi, dof, p_about = _scatter_about_holm(res, sv, diag)
        where = ("the model throughout, a uniform bias (an instrument's calibration: every value times one factor); "
                 "of the library's mechanisms, ")
        if p_about < settings.alpha:  # the rows are not shifted alike: no uniform bias
            nuisance = (nuisance[0], nuisance[1], "fitted alone: the mean offset of the rows, the calibrated model "
                        "times (1 + s); they scatter about it beyond their uncertainty (no uniform bias)")
            where = (f"the model on average, but they scatter about that level beyond the measured and seed "
                     f"uncertainty (chi-square {chi:.3g} on {dof} degrees of freedom, Holm p {p_about:.2g}), so it is no "
                     "uniform bias throughout (an instrument's calibration shifts every row alike): "
                     + _far_off(diag) + "; ")
        elif spread_note:  # uneven spread: stones or the rig's noise form (noted below)
            nuisance = (nuisance[0], nuisance[1], nuisance[2] + UNEVEN_SPREAD_WORDS)
        words, rm, rr = _heldout(sel.uniform)
        verdict = (f"unexplained: the measured values are {abs(100 * sv):.1f} % {'above' if sv > 0 else 'below'} "
                   + where + " + ".join(sel.judged) + f" fit{'s' if k == 1 else ''} the rows too "
                   f"({words} {rm:.2f} % against {rr:.2f} % for "
                   f"the uniform bias alone) but {beside}: on these rows "
                   f"{'its' if k == 1 else 'their'} signature cannot be told from a constant, so the offset is "
                   "left to the uniform bias" + _few_groups_clause(sel, u, fold_by, settings.alpha, judged=True))
    elif sel is not None and sel.chosen:
        chosen = sel.chosen
        final = sel.final
        if jt is not None:  # the chosen effects with their interaction, against the calibrated model
            y0 = u["simulated_mean"].to_numpy(float)
            final = sl.score(sl.Model([data[c] for c in chosen], y0, u["measured"].to_numpy(float), rs.scale_of(u), jt,
                                      weights),
                             sl.Model([], y0, u["measured"].to_numpy(float), rs.scale_of(u), weights=weights,
                                      base=[data[c] for c in chosen], floor=floor),
                             sl._folds(u, fold_by),
                             settings.alpha, groups=sl.replicate_groups(u))
        theta = final.theta
        if uniform is None and interval:
            ci, ci_method = _interval(u, [data[c] for c in chosen], final, settings, jt)
        elif uniform is None:
            pending = (u, [data[c] for c in chosen], final, jt)
        if uniform is not None:  # (no bootstrap: its interval would not be reported)
            sv, lo, hi = _scale_fit(uniform)
            nuisance = ({SCALE_KEY: sv}, {SCALE_KEY: (lo, hi)},
                        "fitted with the chosen effects (a bias none of them carries): their prediction times (1 + s)")
            theta = {k: v for k, v in uniform.theta.items() if k != SCALE_KEY}
            ci = {k: v for k, v in uniform.ci.items() if k != SCALE_KEY}
            ci_method = ("fit (Jacobian) beside a free uniform scale of the model, which the bootstrap does not "
                         "refit: the seeds' scatter in the surrogates left out")
        pred["with_effects"] = fitted
        _, held = sl.cross_validate(m, sl._folds(u, fold_by))
        meas = u["measured"].to_numpy(float)
        pred["heldout_prediction"] = meas - held * rs.scale_of(u)
        after_cv = held
        verdict = "explained by " + " + ".join(chosen) + _parameter_words(theta, ci)
        b = sel.beside_uniform
        if uniform is None and b is not None and SCALE_KEY in b.theta:
            others = ", ".join(f"{k} {v:.4g}" for k, v in b.theta.items() if k != SCALE_KEY)
            sv, lo, hi = _scale_fit(b)
            nuisance = ({SCALE_KEY: sv}, {SCALE_KEY: (lo, hi)},
                        f"fitted beside the chosen effects ({others} there) in the test against a constant; the "
                        "parameters reported are fitted without it")
        if uniform is not None:
            sv, lo, hi = _scale_fit(uniform)
            if not (np.isfinite(lo) and np.isfinite(hi)):
                verdict += (f", fitted beside a free uniform scale of the model (s {100 * sv:+.1f} %) that these rows "
                            "do not pin down (no finite interval)")
                nuisance = (nuisance[0], nuisance[1], "fitted with the chosen effects, their prediction times "
                            "(1 + s); not pinned down: no finite interval")
            elif not _excludes_zero(lo, hi):
                # the scale fitted with them shows no bias: its interval holds 0
                verdict += (f", fitted beside a free uniform scale of the model, which shows no bias beyond the "
                            f"scatter (s {100 * sv:+.1f} %; 95 %: {100 * lo:+.1f} to {100 * hi:+.1f} %)")
                nuisance = (nuisance[0], nuisance[1], "fitted with the chosen effects, their prediction times "
                            "(1 + s); its interval holds 0: no bias shown")
            else:
                verdict += (f", beside a uniform bias that no effect of the library carries (the measured values "
                            f"{abs(100 * sv):.1f} % {'above' if sv > 0 else 'below'} the model throughout; 95 %: "
                            f"{100 * lo:+.1f} to {100 * hi:+.1f} %), fitted with them")
        if uniform is None:
            verdict += _judged_alone(sel, settings.alpha)
        if sel.uniform is not None and not sel.uniform.accepted and uniform is None:
            verdict += _bias_fits_as_well(sel.uniform, sel.uniform_s, len(chosen))
        gap = f"{100 * float(np.sqrt(np.mean((jt.gap / rs.scale_of(u)) ** 2))):.2g} % RMS" if jt is not None else ""
        at = ", ".join(f"{k} {v:.4g}" for k, v in joint["theta"].items()) if jt is not None else ""
        if jt is not None and len(chosen) == 1:  # said with the interval (summary ci95_method, report)
            ci_method += (f"; the parameter refitted with runs at {at} (they differ from the surrogate through the "
                          f"design points by {gap} there)")
        if jt is None and len(chosen) == 1:  # the workflow's selection: no runs at the fitted value
            ci_method += ("; the parameter read from the surrogate through the design points, not refitted with "
                          "runs at its fitted value, so the surrogate's error between the design points stays in "
                          "it (soilcal loop run simulates the fitted value and refits)")
        if len(chosen) > 1:
            if jt is not None:
                verdict += ("; fitted with their interaction, from runs with " + " and ".join(chosen)
                            + f" switched on together at {at} (the joint runs differ from the sum of the separate "
                            f"changes by {gap})")
            else:
                verdict += ("; fitted as the sum of each effect's separate change (first order), which leaves out "
                            "their interaction: where they interact (a friction and a density that both scale the "
                            "passive pressure) the parameters carry a bias their intervals do not cover "
                            "(soilcal loop run simulates them together and refits)")
        edge = _at_bounds(theta, [data[c] for c in chosen])
        if edge:
            verdict += "; " + "; ".join(edge)
        for c in chosen:  # its design's failed levels bound it (not loop.bounds)
            if narrowed.get(c) is not None:
                verdict += "; " + narrowed[c].text()
        verdict += _not_separated(sel, settings.alpha)
        if left:  # what the chosen effects leave: structure no effect of the library accounted for
            verdict += f"; the residual left still follows {left}, which stays unexplained"
    elif not structure:
        rms = float(np.sqrt(np.mean(before ** 2))) * 100
        judged = len(diag) and (diag["test"] == "scatter").any()
        few = int(u["simulated_n"].min()) if "simulated_n" in u and len(u) else 0
        if judged and few < MIN_SEEDS_TO_JUDGE:
            verdict = (f"unexplained: RMS error {rms:.1f} % with no significant structure, but {few} seed"
                       f"{'s' if few != 1 else ''} per condition cannot tell the seed scatter (at least "
                       f"{MIN_SEEDS_TO_JUDGE}: the measured table's `replicates`, or soilcal loop run --sim-seeds) "
                       "from a misfit (too few data to decide)")
        elif judged:
            verdict = ("consistent: no significant structure, and the residual lies within the measured and seed "
                       f"uncertainty (RMS error {rms:.1f} %)")
        else:
            # the rows may be many: what is missing is an uncertainty of the measured values
            verdict = (f"unexplained: RMS error {rms:.1f} % with no significant structure over {n} rows, and no "
                       "measured uncertainty to judge the scatter against (no measured SD given: the table's `sd` "
                       "and `n` columns, or each condition's repeats as rows of their own, give it"
                       + (f"; largest: {follows})" if follows else ")"))
        if sel_rows:
            verdict += "; no candidate effect lowered the held-out error significantly (selection.csv)"
    elif not cands and len(dg.per_condition(dg.per_test(u))) == 1:
        rows = len(dg.per_test(u))  # table rows, each measuring one or more quantities
        # how far the condition lies from the model: a free uniform scale of each measured
        # quantity's simulated values (one scale over two quantities 20 % above and 20 % below
        # the model read "7.3 % below")
        scales = []
        for q, g in u.groupby(u["measure"].astype(str), sort=True):
            sq = float(sl.Model([sl.scale_data()], g["simulated_mean"].to_numpy(float), g["measured"].to_numpy(float),
                                rs.scale_of(g), weights=sl.row_weights(g)).fit()[0][0])
            scales.append((f"{q} " if u["measure"].nunique() > 1 else "")
                          + f"{abs(100 * sq):.1f} % {'above' if sq > 0 else 'below'}")
        verdict = (f"unexplained: the residual follows {follows}; the {rows} row{'s' if rows != 1 else ''}"
                   + (f" ({n} measured values)" if n != rows else "")
                   + f" repeat{'s' if rows == 1 else ''} one measured condition, " + ", ".join(scales)
                   + " the model (a uniform scale fitted to "
                   + ("each quantity's rows" if len(scales) > 1 else "them") + "); one condition cannot tell a bias "
                   "of the model from that condition's own deviation, nor "
                   "fit an effect (measure two conditions at least)")
    elif not cands:
        sig = dg.matched_quantities(diag) if len(diag) else set()
        held = [nm for nm in (skipped_effects or {}) if sig & set(EFFECTS[nm].signature)]
        verdict = (f"unexplained: the residual follows {follows}; "
                   + ("no effect of the library could be tried through it" if held
                      else "no effect of the library acts through it"))
    else:
        rejected = _rejected(sel_rows)
        verdict = f"unexplained: the residual follows {follows}; candidates rejected ({rejected})"
        verdict += _few_groups_clause(sel, u, fold_by, settings.alpha)
    if (not nuisance[0] and n >= 3 and len(diag) and verdict.startswith("unexplained")
            and bool(((diag["test"] == "bias") & diag["significant"].astype(bool)).any())):
        # the residual follows a bias no effect explained: the uniform scale alone, its value and
        # interval, so that the report gives the offset whichever sign it has (the selection
        # fitted it where it judged effects against it)
        if sel is not None and np.isfinite(sel.uniform_s):
            sv, (lo, hi) = sel.uniform_s, sel.uniform_ci
        else:
            y0, meas, sc = u["simulated_mean"].to_numpy(float), u["measured"].to_numpy(float), rs.scale_of(u)
            alone = sl.Model([sl.scale_data()], y0, meas, sc, weights=weights)
            sv, lo, hi = _scale_fit(sl.score(alone, sl.Model([], y0, meas, sc, weights=weights, floor=floor),
                                             sl._folds(u, fold_by),
                                             settings.alpha, groups=sl.replicate_groups(u)))
        nuisance = ({SCALE_KEY: sv}, {SCALE_KEY: (lo, hi)},
                    "fitted alone: the uniform bias the residual follows, the calibrated model times (1 + s)")
        chi, dof, p_about = _scatter_about_holm(res, sv, diag)
        if p_about < settings.alpha:  # the rows are not shifted alike (stones): say so
            verdict += (f"; the measured values are {abs(100 * sv):.1f} % {'above' if sv > 0 else 'below'} the model "
                        "on average, but they scatter about that level beyond the measured and seed uncertainty "
                        f"(chi-square {chi:.3g} on {dof} degrees of freedom, Holm p {p_about:.2g}), so the bias is "
                        "no uniform one throughout (an instrument's calibration shifts every row alike): "
                        + _far_off(diag))
            nuisance = (nuisance[0], nuisance[1], "fitted alone: the mean offset of the rows, the calibrated model "
                        "times (1 + s); they scatter about it beyond their uncertainty (no uniform bias)")
        else:
            # the offset's size and sign in the verdict too, as where an effect was judged against it
            verdict += (f"; the measured values are {abs(100 * sv):.1f} % {'above' if sv > 0 else 'below'} the model "
                        + (f"throughout (95 %: {100 * lo:+.1f} to {100 * hi:+.1f} %)"
                           if np.isfinite(lo) and np.isfinite(hi) else "throughout")
                        + ", a uniform bias (an instrument's calibration) that no mechanism of the library carries")
            if spread_note:  # uneven spread: stones or the rig's noise form (noted below)
                nuisance = (nuisance[0], nuisance[1], nuisance[2] + UNEVEN_SPREAD_WORDS)
    if sel is not None:
        verdict += _unscored(sel, u, settings.alpha)
    matched = dg.matched_quantities(diag) if len(diag) else set()
    for nm, why in (skipped_effects or {}).items():  # those the structure (or candidates: all) would have tried
        if settings.candidates == "all" or matched & set(EFFECTS[nm].signature):
            verdict += f"; {nm} {why}"
    if n >= 3 and not verdict.startswith("no "):
        verdict += spread_note
    for hint in constant_hints(u) + unit_hints(u):
        verdict += f"; {hint}"
    per_test = dg.per_test(u)  # table rows; the trend tests take one value per measured condition
    tests, conds = len(per_test), len(dg.per_condition(per_test))
    if 0 < conds < 4 and not verdict.startswith("no "):
        verdict += (f"; with {tests} row{'s' if tests != 1 else ''} no trend was tested (a trend test needs 4)"
                    if conds == tests else f"; with {conds} measured condition{'s' if conds != 1 else ''} "
                    f"({tests} rows, repeats of them) no trend was tested (a trend test needs 4 conditions)")
    if n > 0 and len(res):
        measured = np.isfinite(res["measured"].astype(float).to_numpy())
        unsimulated = int((measured & ~np.isfinite(res["simulated_mean"].astype(float).to_numpy())).sum())
        if unsimulated:
            verdict += (f"; {int(measured.sum()) - unsimulated} of {int(measured.sum())} measured values have a "
                        f"simulated value: the runs of the other {unsimulated} failed (residuals.csv says why)")
    e = error_figures(u, before, after_cv)
    rb, ra, mb, ma, rf = (e[k] for k in ("rmse_before_percent", "rmse_after_percent", "max_before_percent",
                                         "max_after_percent", "rmse_floor_percent"))
    surrogate_kind, lack_of_fit_p = _surrogates(data, chosen)
    summary = pd.DataFrame([{
        "soil": soil, "rows": len(res), "usable_rows": n, "verdict": verdict, "effects": "+".join(chosen),
        "parameters": _fmt(theta), "ci95": _fmt_ci(ci), "ci95_method": ci_method, "follows": follows, "rmse_before_percent": rb,
        "rmse_after_percent": ra, "rmse_floor_percent": rf, "max_before_percent": mb, "max_after_percent": ma,
        "error_reduction_percent": (1 - ra / rb) * 100 if rb and np.isfinite(rb) and rb > 0 else math.nan,
        "explained_percent": e["explained_percent"],
        "alpha": settings.alpha, "reference": _fmt(reference), "folds": fold_text, "nuisance": _fmt(nuisance[0]),
        "nuisance_ci95": _fmt_ci(nuisance[1]), "nuisance_method": nuisance[2],
        "surrogate": surrogate_kind, "lack_of_fit_p": lack_of_fit_p,
        "weighted_rmse_before_percent": e["weighted_rmse_before_percent"],
        "weighted_rmse_after_percent": e["weighted_rmse_after_percent"]}],
        columns=SUMMARY_COLUMNS)
    out = Outcome(res, diag, rank, cands, pd.DataFrame(sel_rows, columns=SELECTION_COLUMNS), summary, pred,
                  verdict, chosen, theta, after, dg.detectable(res, diag, quantity_cols, settings.alpha),
                  {nm: list(d.missing) for nm, d in data.items() if d.missing}, dict(skipped_effects or {}),
                  fold_by, fold_text, data, uniform is not None, e["floor_note"], e["floor_interval"], narrowed)
    return out, (None if pending is None else pending + (ci_method,))


def error_figures(u: pd.DataFrame, before, after) -> dict:
    """The held-out error figures of the usable residual rows ``u`` (:func:`soilcal.loop.residuals.usable`)
    from their relative residuals ``before`` (the calibrated model's) and ``after`` (the held-out
    predictions'), over the rows where both are known, in %: ``rmse_before_percent``,
    ``rmse_after_percent``, ``max_before_percent``, ``max_after_percent``, the noise floor
    ``rmse_floor_percent`` with its ``floor_note`` and ``floor_interval`` (low, high, degrees of
    freedom; :func:`soilcal.loop.residuals.noise_floor_and_interval`) and
    ``explained_percent`` (:func:`explained_percent`); NaN where no row has both.  Beside them
    the RMS errors the selection compares, weighted by the rows' weights
    (:func:`soilcal.loop.select.row_weights`), sqrt(sum w e^2 / sum w):
    ``weighted_rmse_before_percent``, ``weighted_rmse_after_percent``, NaN where every row
    weighs alike (they would repeat the plain ones)."""
    before, after = np.asarray(before, float), np.asarray(after, float)
    ok = np.isfinite(after) & np.isfinite(before)
    rms = (lambda x: float(np.sqrt(np.mean(x[ok] ** 2))) * 100) if ok.any() else (lambda x: math.nan)
    w = sl.row_weights(u)
    wrms = ((lambda x: float(np.sqrt(np.sum(w[ok] * x[ok] ** 2) / np.sum(w[ok]))) * 100)
            if w is not None and ok.any() else (lambda x: math.nan))
    top = (lambda x: float(np.max(np.abs(x[ok]))) * 100) if ok.any() else (lambda x: math.nan)
    floor, note, (lo, hi, dof) = rs.noise_floor_and_interval(u, ok)
    rb, ra = rms(before), rms(after)
    return {"rmse_before_percent": rb, "rmse_after_percent": ra, "max_before_percent": top(before),
            "max_after_percent": top(after), "rmse_floor_percent": 100 * floor, "floor_note": note,
            "floor_interval": (100 * lo, 100 * hi, dof),
            "explained_percent": explained_percent(rb, ra, 100 * floor, 100 * hi),
            "weighted_rmse_before_percent": wrms(before), "weighted_rmse_after_percent": wrms(after)}


def explained_percent(before: float, after: float, floor: float, floor_high: float = math.nan) -> float:
    """The share of the explainable error that the chosen effects removed, in %:
    (before^2 - after^2) / (before^2 - floor^2) of the RMS errors before and after (held out)
    and of the noise floor (:func:`soilcal.loop.residuals.noise_floor`), all in the same
    unit.  The error a model without misfit would still show is the floor, so only
    before^2 - floor^2 of the mean square can be explained: 100 where the effects bring the
    held-out error down to the floor, above 100 where the rows happen to land below it, below
    0 where the error grew.  NaN where the floor is unknown or the error before is not above
    it (nothing beyond the uncertainties to explain), and where the error before lies within
    ``floor_high``, the upper end of the floor's 95 % interval
    (:func:`soilcal.loop.residuals.floor_interval`; not checked where it is NaN): the
    explainable part is then smaller than the floor's own uncertainty and the ratio's
    denominator is set by noise (a DEM campaign of two forces: 39.09 % before, 25.22 % after,
    a floor of 38.71 % with the interval 31.75-49.59 %, gave 3018 % without this rule,
    ``benchmarks/results/loop.md``)."""
    if not (np.isfinite(before) and np.isfinite(after) and np.isfinite(floor)) or before <= floor:
        return math.nan
    if np.isfinite(floor_high) and before <= floor_high:
        return math.nan
    return 100.0 * (before ** 2 - after ** 2) / (before ** 2 - floor ** 2)


def _with_interval(out: Outcome, pending: tuple | None, settings: Settings) -> Outcome:
    """``out`` (from :func:`_analyse` without its interval) with the chosen effects' interval
    (:func:`_interval`) in its summary, as :func:`analyse` gives it."""
    if pending is None:
        return out
    u, effects, final, jt, after_words = pending
    ci, ci_method = _interval(u, effects, final, settings, jt)
    summary = out.summary.copy()
    summary.loc[0, "ci95"] = _fmt_ci(ci)
    summary.loc[0, "ci95_method"] = ci_method + after_words
    verdict = out.verdict.replace(_parameter_words(out.theta, {}), _parameter_words(out.theta, ci), 1)
    summary.loc[0, "verdict"] = verdict
    return dataclasses.replace(out, summary=summary, verdict=verdict)


def _parameter_words(theta: dict, ci: dict) -> str:
    """The chosen effects' parameters for the verdict, each with its 95 % interval where it
    has a finite one: `` (rate_friction.beta 0.198, 95 %: 0.171 to 0.226)``."""
    parts = []
    for k, v in theta.items():
        lo, hi = (ci or {}).get(k, (math.nan, math.nan))
        parts.append(f"{k} {v:.3g}" + (f", 95 %: {lo:.3g} to {hi:.3g}" if np.isfinite(lo) and np.isfinite(hi) else ""))
    return f" ({'; '.join(parts)})" if parts else ""


# --------------------------------------------------------------------------- in process


def run_inprocess(soil: str, conditions, base_params, simulate, settings: Settings | None = None,
                  seeds=(0, 1, 2)) -> Outcome:
    """The whole loop in one process: ``base_params(cond)`` gives a condition's calibrated
    DEM parameters (name -> SI value), ``simulate(cond, params, seed)`` one run's measured
    quantities (measure -> value).  The calibrated runs and every design point use the same
    ``seeds``; the simulator maps them onto each condition's own DEM seeds
    (:func:`soilcal.loop.cli.dem_simulator`, :func:`soilcal.config.measurements.condition_seed`)."""
    settings = settings or Settings()
    done = {}  # a test measured twice (rows of one simulation) runs once per design point and seed

    def runs_at(effect, theta, reference, together: dict | None = None):
        rows = []
        for c in conditions:
            p = base_params(c)
            if effect:
                p = EFFECTS[effect].apply(p, c.quantities or {}, theta, reference, c.scenario)
            if together:  # several effects switched on at once (name -> theta), in library order
                from soilcal.loop.effects import apply_all

                p = apply_all(together, p, c.quantities or {}, reference, c.scenario)
            for seed in seeds:
                key = (rs.simulation_key(c), json.dumps(p, sort_keys=True), int(seed))
                if key not in done:
                    done[key] = simulate(c, p, seed)
                vals = done[key]
                for r in c.responses:
                    v = vals.get(r["measure"], math.nan)
                    ok = np.isfinite(v)
                    rows.append({"measurement": c.measurement, "row": c.row, "measure": r["measure"], "seed": seed,
                                 "value": v, "status": "ok" if ok else "failed",
                                 rs.ERROR_KEY: "" if ok else str(vals.get(rs.ERROR_KEY) or ""),
                                 **{sl.T_PREFIX + k: float(x) for k, x in (theta or {}).items()}})
        return pd.DataFrame(rows)

    obs = rs.observations(conditions)
    base = runs_at(None, None, {})
    res = rs.residual_frame(obs, base)
    qcols = quantity_of(conditions)
    diag = dg.diagnose(res, qcols, settings.alpha)
    reference = reference_values(res, settings)
    cands = candidates(diag, conditions, settings)
    effect_runs = {}

    def simulate_candidates(names, designs=None):
        for name in names:
            eff = EFFECTS[name]
            frames = []
            design = (designs or {}).get(name) or sl.theta_design(eff, settings.effect_bounds(name),
                                                                   settings.design_points)
            for th in design:
                if eff.is_null(th):  # switched off: the calibrated runs
                    frames.append(base.assign(**{sl.T_PREFIX + k: float(v) for k, v in th.items()}))
                else:
                    frames.append(runs_at(name, th, reference))
            effect_runs[name] = pd.concat(frames, ignore_index=True)

    simulate_candidates(cands)
    skip = skipped(conditions, settings)
    selections = _Rounds()  # the candidates' surrogates, models and selection, once per round's candidates
    # each round without its interval (the bootstrap), which is computed for the outcome returned alone
    out, pending = _analyse(soil, res, diag, cands, effect_runs, settings, reference, qcols, skip, None, False,
                            selections)
    more = more_candidates(out, conditions, settings)
    if more:
        # the second round, as the workflow's loop_more checkpoint
        simulate_candidates(more, more_designs(out, settings))
        cands = cands + [c for c in more if c not in cands]
        out, pending = _analyse(soil, res, diag, cands, effect_runs, settings, reference, qcols, skip, None, False,
                                selections)
    # the chosen effects simulated (together, where there are several) at the fitted parameters and
    # refitted with the difference between those runs and the model's prediction there as a
    # mixed term (select.Joint): the interaction of several effects, and the error of the
    # surrogates between their design points; repeated at the refitted values until they settle
    if not out.chosen or any(len(EFFECTS[c].params) != 1 for c in out.chosen):
        return _with_interval(out, pending, settings)
    keys, null = _theta_keys(out.chosen)
    span = np.array([float(np.subtract(*settings.effect_bounds(c)[k][::-1])) for c in out.chosen
                     for k in EFFECTS[c].theta_names()])
    u = rs.usable(res)
    y0, meas, sc = u["simulated_mean"].to_numpy(float), u["measured"].to_numpy(float), rs.scale_of(u)
    weights = sl.row_weights(u)
    effects = [out.effect_data[c] for c in out.chosen] + ([sl.scale_data()] if out.uniform_scale else [])
    x, joint = np.array([out.theta[k] for k in keys], float), None
    for _ in range(JOINT_ROUNDS):
        if np.any(x == null):
            break
        together = {c: {k: float(x[keys.index(f"{c}.{k}")]) for k in EFFECTS[c].theta_names()} for c in out.chosen}
        joint = {"effects": list(out.chosen), "theta": dict(zip(keys, map(float, x))),
                 "runs": runs_at(None, None, reference, together), "base": base}
        jt = joint_interaction(u, out.effect_data, out.chosen, joint)
        start = np.concatenate([x, [0.0]]) if out.uniform_scale else x
        new = sl.Model(effects, y0, meas, sc, jt, weights).fit(x0=start)[0][:len(keys)]
        settled = bool(np.all(np.abs(new - x) <= JOINT_SETTLED * span))
        x = new
        if settled:
            break
    if joint is None:
        return _with_interval(out, pending, settings)
    final, pending_final = _analyse(soil, res, diag, cands, effect_runs, settings, reference, qcols, skip, joint,
                                    False, selections)
    if sorted(final.chosen) == sorted(out.chosen):
        return _with_interval(final, pending_final, settings)
    return _with_interval(out, pending, settings)


def more_candidates(out: Outcome, conditions, settings: Settings) -> list[str]:
    """The second round's candidates: effects that the residual left by the first round's
    model (the chosen effects, or those the forward step added before the gate) matches, and
    that were not fitted yet (none when the model already holds ``max_effects``); and the first
    round's effects whose scenario stopped measuring past some level (:func:`more_designs`)."""
    new = []
    if out.diagnosis_after is not None and len(out.chosen) < settings.max_effects:
        new = [c for c in candidates(out.diagnosis_after, conditions, settings) if c not in out.candidates]
    return [c for c in out.candidates if (out.narrowed or {}).get(c) is not None and out.narrowed[c].gaps] + new


def more_designs(out: Outcome, settings: Settings) -> dict[str, list[dict]]:
    """The second round's design of each first-round effect whose runs stopped measuring past
    some level (:class:`soilcal.loop.select.Narrowing`): its first design, failed levels
    included (their runs are done), and the narrowing's ``gaps``, the levels between the
    working range and the failures, where the second round learns how far the scenario goes
    and the surrogate gains the points its working range lacked.  Every other candidate of
    the second round takes :func:`soilcal.loop.select.theta_design`."""
    out_d = {}
    for name, nar in (out.narrowed or {}).items():
        if nar is None or not nar.gaps:
            continue
        first = sl.theta_design(EFFECTS[name], settings.effect_bounds(name), settings.design_points)
        levels = sorted({float(t[nar.param]) for t in first} | {float(g) for g in nar.gaps})
        out_d[name] = [{nar.param: lv} for lv in levels]
    return out_d


def residual_after(res: pd.DataFrame, predicted: np.ndarray) -> pd.DataFrame:
    """The usable rows' residual table with the simulated means replaced by ``predicted``
    (the model with its effects), the seed SDs kept."""
    u = rs.usable(res).copy()
    m = u["measured"].to_numpy(float)
    u["simulated_mean"] = predicted
    u["residual"] = m - predicted
    u["relative_residual"] = (m - predicted) / rs.scale_of(u)
    u["standardised_residual"] = u["residual"] / u["residual_se"]
    return u
