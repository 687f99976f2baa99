"""One stage of the calibration chain: design, regression/ANOVA, optimum.

Inputs are plain data: the stage mapping (the soil config's stage for the published source,
the derived stage of :mod:`soilcal.chain.derive` for the DEM source) and the stage's response
table (the printed table, or the DEM runs gathered by :mod:`soilcal.chain.sources` in the same
layout).  Functions return pandas frames; writing files is left to the caller.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from soilcal import doe
from soilcal.errors import InputError


def stage_of(soil: dict, stage_id: str) -> dict:
    for s in soil["stages"]:
        if s["id"] == stage_id:
            return s
    raise InputError(soil.get("name", "<soil>"), "stages", f"a stage with id {stage_id!r}", stage_id)


def bounds(stage: dict) -> tuple[list[str], np.ndarray, np.ndarray]:
    syms = list(stage["factors"])
    low = np.array([float(stage["factors"][s]["low"]) for s in syms])
    high = np.array([float(stage["factors"][s]["high"]) for s in syms])
    return syms, low, high


def response_columns(stage: dict) -> dict[str, str]:
    return {r["id"]: r.get("column", r["id"]) for r in stage["responses"]}


SNAP_TOLERANCE = 0.05
"""Largest distance (coded units) of a printed actual level from its design level that is taken
as print rounding (e.g. a centre 0.175 printed as 0.17 on a 0.05..0.3 range is -0.04 coded)."""


def stage_data(stage: dict, table: pd.DataFrame, snap: bool = True) -> pd.DataFrame:
    """The printed table in coded units with one column per response id.

    With ``snap``, actual levels printed within :data:`SNAP_TOLERANCE` (coded) of a design level
    are put on that level; :func:`design_frame` compares the unsnapped values, so every such
    level still appears as a difference from the generated design in the errata.
    """
    syms, low, high = bounds(stage)
    coding = stage.get("table_coding", "coded")
    out = pd.DataFrame(index=table.index)
    for j, s in enumerate(syms):
        x = table[s].to_numpy(float)
        if coding != "coded":
            x = doe.actual_to_coded(x, low[j], high[j])
            if snap and stage["kind"] in ("plackett_burman", "box_behnken"):
                r = np.round(x)
                x = np.where(np.abs(x - r) <= SNAP_TOLERANCE, r, x)
        out[s] = x
    for rid, col in response_columns(stage).items():
        out[rid] = table[col].to_numpy(float)
    return out


def is_centre_run(stage: dict, data: pd.DataFrame) -> np.ndarray:
    """Rows of a stage's coded data (:func:`stage_data`) that are centre runs of a two-level
    screening (every factor at coded 0; ``center_points`` of the DEM source's Plackett-Burman
    design, :func:`generated_design`); all False for other stages."""
    if stage["kind"] != "plackett_burman" or not int(stage.get("center_points") or 0):
        return np.zeros(len(data), dtype=bool)
    x = data[list(stage["factors"])].to_numpy(float)
    return np.all(np.abs(x) <= SNAP_TOLERANCE, axis=1)


def analysis_data(stage: dict, table: pd.DataFrame) -> pd.DataFrame:
    """:func:`stage_data` without a screening's centre runs: the main effects come from its
    two-level runs (the centre runs measure curvature, :func:`screening_centre`)."""
    data = stage_data(stage, table)
    return data[~is_centre_run(stage, data)]


def screening_centre(stage: dict, table: pd.DataFrame) -> dict[str, dict]:
    """The centre runs of a Plackett-Burman stage against its two-level runs, per response.

    For each response with at least one centre run: ``n``, ``mean``, ``sd`` (None for one
    run) of the centre runs, ``factorial_mean`` of the two-level runs, ``curvature`` =
    factorial mean - centre mean, and its test (Montgomery, Design and Analysis of
    Experiments, sec. 6.8: SS_curv = n_F n_C (ybar_F - ybar_C)^2 / (n_F + n_C) on 1 degree of
    freedom) against the residual mean square of the main-effects model of the two-level runs
    pooled with the centre runs' pure error: ``F``, ``df_error``, ``p`` (None where no degree of
    freedom is left). Empty for a stage without centre runs.
    """
    from scipy import stats

    if stage["kind"] != "plackett_burman" or not int(stage.get("center_points") or 0):
        return {}
    data = stage_data(stage, table)
    centre = is_centre_run(stage, data)
    if not centre.any():
        return {}
    out = {}
    for rid in response_columns(stage):
        yc = data.loc[centre, rid].dropna().to_numpy(float)
        fac = data.loc[~centre].dropna(subset=[rid])
        yf = fac[rid].to_numpy(float)
        if yc.size == 0 or yf.size == 0:
            continue
        nf, nc = yf.size, yc.size
        x = np.column_stack([np.ones(nf), fac[list(stage["factors"])].to_numpy(float)])
        beta, *_ = np.linalg.lstsq(x, yf, rcond=None)
        ss_res = float(np.sum((yf - x @ beta) ** 2))
        df_res = nf - np.linalg.matrix_rank(x)
        ss_pure = float(np.sum((yc - yc.mean()) ** 2))
        df_err = df_res + nc - 1
        curv = float(yf.mean() - yc.mean())
        ss_curv = nf * nc * curv**2 / (nf + nc)
        row = {"n": int(nc), "mean": float(yc.mean()), "sd": float(yc.std(ddof=1)) if nc > 1 else None,
               "factorial_mean": float(yf.mean()), "curvature": curv, "F": None, "df_error": int(df_err), "p": None}
        if df_err > 0 and ss_res + ss_pure > 0:
            f = ss_curv / ((ss_res + ss_pure) / df_err)
            row["F"], row["p"] = float(f), float(stats.f.sf(f, 1, df_err))
        out[rid] = row
    return out


# --------------------------------------------------------------------------- design


def pb_columns(stage: dict) -> int:
    """Generator columns of a Plackett-Burman stage's design: its factors and dummies, or
    ``runs - 1`` where the stage asks for more runs than they need (an N-run design has N - 1
    columns: 12 runs of 6 factors are the 12-run design's first 6 columns, its other 5 the
    error estimate, as 5 dummies would be).  A ``runs`` that is not a multiple of 4 above the
    factors and dummies raises InputError naming the field and how to get it."""
    cols = len(stage["factors"]) + len(stage.get("dummies") or [])
    runs = stage.get("runs")
    if runs is None:
        return cols
    runs = int(runs)
    if runs % 4 or runs <= cols:
        raise InputError(f"stage {stage.get('id')}", "runs",
                         f"a multiple of 4 above the {cols} factors and dummies of the Plackett-Burman "
                         f"design ({', '.join(str(4 * (cols // 4 + 1) + 4 * i) for i in range(3))}, ...)", runs)
    return max(cols, runs - 1)


def generated_design(stage: dict) -> np.ndarray:
    """Coded design generated for the stage (pyDOE3 / Plackett-Burman generators); a
    Plackett-Burman stage has the ``runs`` it asks for (:func:`pb_columns`), its factors and
    dummies in the first columns."""
    k = len(stage["factors"])
    if stage["kind"] == "plackett_burman":
        cols = k + len(stage.get("dummies") or [])
        coded = doe.plackett_burman(pb_columns(stage))[:, :cols]
        n_centre = int(stage.get("center_points") or 0)  # the DEM source's centre runs, last
        return np.vstack([coded, np.zeros((n_centre, cols))]) if n_centre else coded
    if stage["kind"] == "box_behnken":
        return doe.box_behnken(k, int(stage.get("center_points", 0)))
    raise ValueError(stage["kind"])


def design_frame(stage: dict, table: pd.DataFrame | None) -> tuple[pd.DataFrame, dict]:
    """Generated design (coded and actual) and its comparison with the printed table.

    Returns the frame and a dict ``{"equal": bool, "only_generated": [...], "only_printed": [...],
    "columns": [...]}`` describing the comparison as sets of rows.
    """
    kind = stage["kind"]
    if kind == "steepest_ascent":
        syms = list(stage["factors"])
        n = len(stage["factors"][syms[0]].get("levels", []))
        df = pd.DataFrame({"step": np.arange(1, n + 1)})
        for s in syms:
            df[s] = stage["factors"][s].get("levels", [])
        info = {"equal": True, "only_generated": [], "only_printed": [], "columns": syms}
        if table is not None:
            diff = []
            for s in syms:
                printed = table[s].to_numpy(float)
                if not np.allclose(printed, df[s].to_numpy(float), rtol=0, atol=1e-12):
                    diff.append(s)
            info["equal"] = not diff
            info["only_printed"] = diff
        return df, info

    coded = generated_design(stage)
    syms = list(stage["factors"])
    dummies = list(stage.get("dummies", []))
    all_cols = syms + dummies
    assignment = None
    if kind == "plackett_burman" and table is not None:
        # Which generator column carries which factor is the experimenter's choice: adopt the
        # printed assignment when the printed design is the generated one with columns permuted.
        cols = [c for c in all_cols if c in table.columns]
        m = doe.match_columns(coded, table[cols].to_numpy(float), allow_sign_flip=False)
        if m.found and not m.identity:
            rest = [j for j in range(coded.shape[1]) if j not in m.columns]
            order = list(m.columns) + rest
            coded = coded[:, order]
            all_cols = cols + [c for c in all_cols if c not in cols]
            assignment = {c: int(j) + 1 for c, j in zip(all_cols, order)}
    df = pd.DataFrame({"run": np.arange(1, len(coded) + 1)})
    for j, s in enumerate(all_cols):
        df[s] = coded[:, j].astype(int)
    if all("low" in f and "high" in f for f in stage["factors"].values()):
        _, low, high = bounds(stage)
        for j, s in enumerate(syms):
            # 12 significant digits: 0.05 stays 0.05, not 0.0499999999999999 (centre - half range)
            df[f"{s}_actual"] = [float(f"{v:.12g}") for v in doe.coded_to_actual(coded[:, j], low[j], high[j])]
    info = {"equal": None, "only_generated": [], "only_printed": [], "columns": []}
    if table is not None:
        cols = [c for c in all_cols if c in table.columns]
        printed = stage_data(stage, table, snap=False)
        p = np.column_stack([printed[c] if c in syms else table[c].to_numpy(float) for c in cols])
        g = df[cols].to_numpy(float)
        cmp = doe.same_rows(g, p)
        info = {
            "generator_columns": assignment,
            "equal": bool(cmp.equal),
            "only_generated": [list(map(float, r)) for r in cmp.only_in_a],
            "only_printed": [list(map(float, r)) for r in cmp.only_in_b],
            "columns": cols,
        }
        # record which printed run each generated row is (first unused identical row)
        used: set[int] = set()
        match = []
        for row in g:
            hit = next((i for i, q in enumerate(p) if i not in used and np.allclose(row, q)), None)
            if hit is not None:
                used.add(hit)
            match.append(np.nan if hit is None else int(table["run"].iloc[hit]) if "run" in table else hit + 1)
        df["printed_run"] = match
    return df, info


def printed_design(stage: dict, table: pd.DataFrame, coding: str | None = None) -> pd.DataFrame:
    """The printed table's own design points in the layout of :func:`design_frame`.

    Steepest ascent: ``step`` and the actual levels.  Plackett-Burman / Box-Behnken: ``run``,
    the coded levels (print rounding snapped, :func:`stage_data`), ``<factor>_actual`` as
    printed (decoded when the table is printed coded) and ``printed_run``.  ``coding``: how the
    printed table's factor columns are printed (default: the stage's ``table_coding``).
    """
    syms = list(stage["factors"])
    coding = coding or stage.get("table_coding", "coded")
    stage = {**stage, "table_coding": coding}
    if stage["kind"] == "steepest_ascent":
        df = pd.DataFrame({"step": table["step"].to_numpy() if "step" in table else np.arange(1, len(table) + 1)})
        for s in syms:
            df[s] = table[s].to_numpy(float)
        return df
    _, low, high = bounds(stage)
    coded = stage_data(stage, table)
    runs = table["run"].to_numpy() if "run" in table else np.arange(1, len(table) + 1)
    df = pd.DataFrame({"run": np.arange(1, len(table) + 1)})
    for s in syms:
        df[s] = coded[s].to_numpy(float)
    for j, s in enumerate(syms):
        if coding == "coded":
            df[f"{s}_actual"] = [float(f"{v:.12g}") for v in doe.coded_to_actual(table[s].to_numpy(float),
                                                                                   low[j], high[j])]
        else:
            df[f"{s}_actual"] = table[s].to_numpy(float)
    df["printed_run"] = runs
    return df


# --------------------------------------------------------------------------- regression


@dataclass
class StageFit:
    response: str
    full: object
    reduced: object
    reduction: str
    transform: str


def _terms_of(stage: dict) -> list[str] | None:
    if stage["kind"] == "plackett_burman":
        return list(stage["factors"])
    return None  # full quadratic


def fit_stage(stage: dict, table: pd.DataFrame) -> list[StageFit]:
    """Fit every response of a PB or BBD stage: full model and reduced model."""
    from soilcal import rsm  # here, not at module import: the design jobs fit nothing

    syms, low, high = bounds(stage)
    data = analysis_data(stage, table)
    fits = []
    for rid in response_columns(stage):
        sub = data.dropna(subset=[rid])
        _enough_points(stage, table, rid, len(sub), len(syms))
        transform = stage.get("transform", {}).get(rid, "none")
        full = rsm.fit_response_surface(
            sub, syms, rid, low, high, terms=_terms_of(stage), transform=transform, data_coding="coded"
        )
        printed = stage.get("printed", {}).get(rid, {})
        if stage["kind"] == "plackett_burman":
            reduced, how = full, "none (main-effects screening model)"
        elif printed.get("reduced_drops"):
            drops = printed["reduced_drops"]
            reduced, how = rsm.drop_terms(full, drops), "as printed: removed " + ", ".join(drops)
        else:
            reduced = rsm.backward_eliminate(full, alpha_out=0.1, hierarchical=True)
            removed = [t for t in full.terms if t not in reduced.terms]
            how = "hierarchical backward elimination (alpha 0.10): removed " + (", ".join(removed) or "nothing")
        fits.append(StageFit(rid, full, reduced, how, transform))
    return fits


def _enough_points(stage: dict, table: pd.DataFrame, rid: str, n: int, k: int) -> None:
    """Refuse a fit with no residual degree of freedom, naming the points without a response."""
    p = 1 + (k if stage["kind"] == "plackett_burman" else k + k * (k - 1) // 2 + k)
    if n > p:
        return
    col = response_columns(stage)[rid]
    key = "step" if "step" in table.columns else "run"
    missing = table[table[col].isna()] if col in table.columns else table
    why = []
    for _, r in missing.iterrows():
        reason = str(r.get("error", "") or "no response")
        label = f"{key} {int(r[key])}" if key in r and pd.notna(r[key]) else "a point"
        why.append(f"{label}: {reason}")
    raise InputError(stage.get("table") or stage.get("id"), f"{rid}",
                     f"at least {p + 1} design points with a response for the {p} terms of the "
                     f"{stage['kind']} model of stage {stage.get('id')!r} and one residual degree of freedom",
                     f"{n}; without a response: " + ("; ".join(why) or "none"))


def _point_labels(table: pd.DataFrame, data: pd.DataFrame, rid: str) -> list:
    """Run numbers of the points a response's fit uses (:func:`fit_stage`), in its order."""
    idx = data.dropna(subset=[rid]).index
    if "run" in table.columns:
        return [int(v) if float(v).is_integer() else v for v in table.loc[idx, "run"]]
    return [int(i) + 1 for i in idx]


def _finite_row(row: dict, notes: list[str]) -> dict:
    """A fit.csv row with no infinite number: an undefined statistic is empty and the row's
    ``note`` says why (``notes``: the model's and the Box-Cox analysis's reasons; an infinity
    neither explains is named)."""
    out = dict(row)
    named = []
    for k, v in row.items():
        if isinstance(v, (float, np.floating)) and np.isinf(v):
            out[k] = np.nan
            named.append(k)
    explained = {"pred_R2", "PRESS"} if notes and notes[0] else set()
    if notes[1:] and notes[1]:
        explained |= {"boxcox_ci_low", "boxcox_ci_high"}
    rest = [k for k in named if k not in explained]
    if rest:
        notes = notes + [f"{', '.join(rest)} infinite (written empty)"]
    out["note"] = "; ".join(n for n in notes if n)
    return out


def regression_frames(stage: dict, table: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """anova, fit, coefficients and effects frames for a PB/BBD stage (all responses).

    fit: one row per response and model; a statistic the data leave undefined (PRESS and
    pred R2 where a point has leverage 1, a Box-Cox interval reaching past the searched
    lambda range, any other infinity) is empty and the row's ``note`` says why."""
    from soilcal import rsm  # here, not at module import: the design jobs fit nothing

    anova, fit, coef, effects = [], [], [], []
    data = analysis_data(stage, table)
    syms = list(stage["factors"])
    for sf in fit_stage(stage, table):
        models = [("full", sf.full)] if stage["kind"] == "plackett_burman" else [("full", sf.full), ("reduced", sf.reduced)]
        for label, m in models:
            a = m.anova().copy()
            a.insert(0, "model", label)
            a.insert(0, "response", sf.response)
            anova.append(a)
            st = dict(m.fit_statistics())
            y = data[sf.response].dropna().to_numpy(float)
            sugg = rsm.transform_suggestion(y)
            row = {"response": sf.response, "model": label, "transform": sf.transform, **st,
                   "max_min_ratio": sugg.get("ratio"), "transform_suggested": sugg.get("recommend"),
                   "reduction": sf.reduction if label == "reduced" else ""}
            notes = [m.statistics_note(_point_labels(table, data, sf.response))]
            try:
                bc = rsm.boxcox(m)
                row.update({"boxcox_lambda": bc.get("lambda_best"), "boxcox_ci_low": bc.get("ci_low"),
                            "boxcox_ci_high": bc.get("ci_high"), "boxcox_recommended": bc.get("recommended_transform")})
                notes.append(f"Box-Cox: {bc['ci_note']}" if bc.get("ci_note") else "")
            except (ValueError, np.linalg.LinAlgError) as exc:  # non-positive responses
                row["boxcox_recommended"] = f"n/a ({exc})"
            fit.append(_finite_row(row, notes))
            c = m.coefficients().copy()
            c.insert(0, "model", label)
            c.insert(0, "response", sf.response)
            coef.append(c)
        if stage["kind"] == "plackett_burman":
            e = rsm.screening_effects(data.dropna(subset=[sf.response]), syms, sf.response,
                                      dummies=stage.get("dummies"))
            e.insert(0, "response", sf.response)
            effects.append(e)
        else:
            e = sf.full.coefficients().copy()
            e.insert(0, "response", sf.response)
            effects.append(e)
    return {
        "anova": pd.concat(anova, ignore_index=True),
        "fit": pd.DataFrame(fit),
        "coefficients": pd.concat(coef, ignore_index=True),
        "effects": pd.concat(effects, ignore_index=True),
    }


# --------------------------------------------------------------------------- optimum


def goal_values(goals: dict, targets: dict) -> dict:
    """A case's goals with each ``target`` id replaced by its value (None where unavailable)."""
    out = {}
    for rid, g in goals.items():
        g = dict(g)
        if "target" in g:
            t = targets.get(g.pop("target"), {})
            v = t.get("value")
            g["value"] = None if v is None or not np.isfinite(float(v)) else float(v)
        out[rid] = g
    return out


def missing_targets_note(goals: dict, targets: dict) -> str:
    """Why a case cannot be optimised: "target value not available", then each target of its
    goals that has no value, with the reason its targets table gives (``note``, else
    ``source``), e.g. ``target value not available: angle_mc05 (no photo group and no printed
    value: not printed in the extracted text)``."""
    said = []
    for g in goals.values():
        tid = g.get("target")
        if g.get("goal") != "target" or not tid:
            continue
        t = targets.get(tid) or {}
        v = t.get("value")
        if v is not None and np.isfinite(float(v)):
            continue
        why = next((str(t[k]) for k in ("note", "source") if isinstance(t.get(k), str) and t[k].strip()), "")
        said.append(f"{tid} ({why})" if why else (f"{tid}" if tid in targets else f"{tid} (no such target)"))
    return "target value not available" + (": " + "; ".join(said) if said else "")


def _steepest_frame(stage: dict, table: pd.DataFrame, targets: dict) -> pd.DataFrame:
    """The step closest to the target, per response, and over all targeted responses together.

    A response's target is the stage's ``path_targets`` entry (the DEM source writes it,
    :func:`soilcal.chain.derive.response_targets`) or the target with the response's id.
    With two or more targeted responses, rows ``response = all`` carry the combined error
    sqrt(mean_r ((y_r - t_r)/t_r)^2) that chooses the path step
    (:func:`soilcal.doe.steepest.chosen_step`).  Under the stage's ``path_choice: fitted``
    (a path the DEM source derived, :mod:`soilcal.chain.derive`) the errors are those of the
    trend through the path's runs (column ``fitted``; empty under the papers' rule).
    """
    from soilcal.doe.steepest import chosen_step, path_trend

    path_targets = stage.get("path_targets") or {}
    choice = stage.get("path_choice", "closest")
    rows, tg, ys = [], {}, {}
    for rid, col in response_columns(stage).items():
        tgt = (path_targets.get(rid) or {}).get("value", targets.get(rid, {}).get("value"))
        tgt = None if tgt is None or not np.isfinite(float(tgt)) else float(tgt)
        y = table[col].to_numpy(float)
        fitted = (path_trend(table["step"].to_numpy(float), y)["fitted"] if choice == "fitted"
                  else np.full(len(y), np.nan))
        judged = fitted if choice == "fitted" else y
        err = np.abs(judged - tgt) / tgt * 100 if tgt else np.full(len(y), np.nan)
        best = int(np.nanargmin(err)) if tgt and np.isfinite(err).any() else -1
        if tgt:
            tg[rid], ys[rid] = tgt, y
        for i in range(len(y)):
            r = {"response": rid, "step": int(table["step"].iloc[i]), "value": y[i], "fitted": fitted[i],
                 "target": tgt, "relative_error_percent": err[i], "chosen": i == best,
                 "printed_choice": int(table["step"].iloc[i]) == stage.get("chosen_step")}
            for s in stage["factors"]:
                r[s] = table[s].iloc[i]
            rows.append(r)
    if len(tg) >= 2:
        path = table[["step", *stage["factors"]]].reset_index(drop=True)
        step, comb = chosen_step(path, ys, tg, rule=choice)
        for i, c in comb.iterrows():
            r = {"response": "all", "step": int(c["step"]), "value": np.nan, "fitted": np.nan, "target": np.nan,
                 "relative_error_percent": float(c["error_percent"]), "chosen": bool(c["chosen"]),
                 "printed_choice": int(c["step"]) == stage.get("chosen_step")}
            for s in stage["factors"]:
                r[s] = path[s].iloc[i]
            rows.append(r)
    return pd.DataFrame(rows)


#: optimum.csv methods whose rows come from a seeded search (their ``seed`` column is set)
SEEDED_METHODS = ("desirability", "pso", "near_optimal")


def optimum_frames(stage: dict, table: pd.DataFrame, targets: dict, seed: int) -> dict[str, pd.DataFrame]:
    """Optimal settings for every optimisation case of the stage, and how well the data pin
    each factor down.

    Steepest ascent: the step whose response is closest to the target (and the printed choice),
    :func:`_steepest_frame`.  Box-Behnken: Derringer-Suich desirability solutions (several
    distinct ones, as Design-Expert lists them); for ``method: pso`` particle-swarm solutions
    too; the printed optimum as a row with its predicted responses; and every distinct set of
    factor levels whose desirability is within 0.01 of the best (``method = near_optimal``,
    :func:`soilcal.optimise.near_optimal.near_optimal_sets`), of which the one nearest the
    design centre is the calibrated set (``calibrated = True``,
    :func:`soilcal.optimise.near_optimal.calibrated_choice`).  ``identifiability`` gives, per
    case and factor, the spread of the near-optimal sets and whether the data pin it down.
    The rows of the seeded searches carry the soil's ``seed`` (column ``seed``).
    """
    if stage["kind"] == "steepest_ascent":
        return {"optimum": _steepest_frame(stage, table, targets), "identifiability": None}

    opt = stage.get("optimise")
    if not opt:
        return {"optimum": pd.DataFrame(columns=["case", "method", "solution"]), "identifiability": None}
    # the optimisers (scipy.optimize, about half a second of imports) only for a stage that has
    # cases to optimise: a path's step is chosen without them
    from soilcal import optimise
    from soilcal.optimise.desirability import search_ends
    from soilcal.optimise.near_optimal import (NEAR_OPTIMAL_STARTS, calibrated_choice, identifiability,
                                               near_optimal_sets)

    fits = {sf.response: (sf.reduced if opt.get("model", "reduced") == "reduced" else sf.full)
            for sf in fit_stage(stage, table)}
    syms, low, high = bounds(stage)
    frames, ident = [], []
    for case in opt["cases"]:
        goals = goal_values(case["goals"], targets)
        if any(g["goal"] == "target" and g.get("value") is None for g in goals.values()):
            frames.append(pd.DataFrame([{"case": case["id"], "method": "none", "solution": "",
                                         "note": missing_targets_note(case["goals"], targets)}]))
            continue
        models = {rid: fits[rid] for rid in goals}
        # one seeded search serves both: the desirability solutions take the end points of its
        # centre and first 60 random starts (desirability_optimise's default), the near-optimal
        # sets all of them
        ends = search_ends(models, goals, n_starts=NEAR_OPTIMAL_STARTS, seed=seed)
        d = optimise.desirability_optimise(models, goals, seed=seed, n_solutions=opt.get("n_solutions", 5), ends=ends)
        d.insert(0, "method", "desirability")
        d.insert(0, "case", case["id"])
        frames.append(d)
        if opt["method"] == "pso":
            p = opt.get("pso", {})
            for rid, g in goals.items():
                model = models[rid]
                tgt = g["value"]

                def objective(x, model=model, tgt=tgt):
                    x = np.atleast_2d(x)
                    return np.abs(model.predict_actual(x) - tgt) / abs(tgt)

                res = optimise.pso_optimise(objective, np.column_stack([low, high]),
                                            particles=p.get("particles", 50),
                                            iterations=p.get("iterations", 200), repeats=p.get("repeats", 1),
                                            seed=seed)
                row = {"case": case["id"], "method": "pso", "solution": 1}
                xa = np.asarray(res["x"], float)
                xc = doe.actual_to_coded(xa, low, high)
                for j, s in enumerate(syms):
                    row[f"{s}_coded"] = xc[j]
                    row[s] = xa[j]
                row[rid] = float(model.predict_actual(xa[None, :])[0])
                row["objective"] = float(res["f"])
                frames.append(pd.DataFrame([row]))
        near = near_optimal_sets(models, goals, seed=seed, n_starts=NEAR_OPTIMAL_STARTS, ends=ends)
        if len(near):
            chosen = calibrated_choice(near)
            near = near.drop(columns=["near_optimal"])
            near.insert(0, "method", "near_optimal")
            near.insert(0, "case", case["id"])
            near["calibrated"] = near.index == chosen.name
            frames.append(near)
            idt = identifiability(near, syms, low, high)
            idt.insert(0, "case", case["id"])
            ident.append(idt)
        printed = case.get("printed_optimum")
        if printed and all(s in printed for s in syms):
            xa = np.array([printed[s] for s in syms], float)
            xc = doe.actual_to_coded(xa, low, high)
            row = {"case": case["id"], "method": "printed", "solution": "printed"}
            for j, s in enumerate(syms):
                row[f"{s}_coded"] = xc[j]
                row[s] = xa[j]
            for rid, m in models.items():
                row[rid] = float(m.predict_actual(xa[None, :])[0])
            frames.append(pd.DataFrame([row]))
    out = pd.concat(frames, ignore_index=True)
    if "calibrated" in out.columns:
        out["calibrated"] = out["calibrated"].fillna(False).astype(bool)
    _confidence_columns(out, fits, syms)
    # the soil's seed (schema default 0) on the rows of the seeded multi-start searches
    out["seed"] = pd.array([int(seed) if m in SEEDED_METHODS else None for m in out["method"]], dtype="Int64")
    return {"optimum": out,
            "identifiability": pd.concat(ident, ignore_index=True) if ident else
            pd.DataFrame(columns=["case", "factor", "n_sets", "min", "max", "spread", "spread_coded", "pinned", "note"])}


def _confidence_columns(out: pd.DataFrame, fits: dict, syms: list[str]) -> None:
    """``<response>_ci_low`` and ``_ci_high`` beside every predicted response of a row with
    factor levels: the 95 % confidence interval of the surface's mean there
    (:meth:`soilcal.rsm.model.RSMFit.confidence_actual`), so that a verification can tell a
    target the surface cannot reach from one its own uncertainty still covers."""
    if not len(out) or not all(s in out.columns for s in syms):
        return
    x = out[syms].apply(pd.to_numeric, errors="coerce").to_numpy(float)
    ok = np.all(np.isfinite(x), axis=1)
    for rid, model in fits.items():
        if rid not in out.columns:
            continue
        lo = np.full(len(out), np.nan)
        hi = np.full(len(out), np.nan)
        has = ok & out[rid].notna().to_numpy()
        if has.any():
            lo[has], hi[has] = model.confidence_actual(x[has])
        out.insert(out.columns.get_loc(rid) + 1, f"{rid}_ci_low", lo)
        out.insert(out.columns.get_loc(rid) + 2, f"{rid}_ci_high", hi)


def optimum_frame(stage: dict, table: pd.DataFrame, targets: dict, seed: int) -> pd.DataFrame:
    """The ``optimum`` frame of :func:`optimum_frames`."""
    return optimum_frames(stage, table, targets, seed)["optimum"]


def calibrated_rows(optimum: pd.DataFrame, case: str) -> pd.DataFrame:
    """The rows of ``optimum`` (an ``optimum.csv`` or ``refined.csv`` frame) marked
    ``calibrated`` for one case; empty when the frame has no such column or row."""
    sel = optimum[optimum["case"].astype(str) == str(case)]
    if "calibrated" not in sel.columns:
        return sel.iloc[0:0]
    return sel[sel["calibrated"].astype(str).str.lower() == "true"]


def factors_on_bounds(stage: dict, row) -> list[str]:
    """The factors of a set (a row of ``optimum.csv`` or ``refined.csv``: ``<factor>_coded``
    or the actual levels) that lie on a bound of the stage's design region, as text:
    ``["A at its low bound 0.3", "C at its high bound 0.6"]`` (empty when none does or the
    stage has no low and high levels)."""
    out = []
    for s, f in (stage.get("factors") or {}).items():
        if f.get("low") is None or f.get("high") is None:
            continue
        lo, hi = float(f["low"]), float(f["high"])
        if f"{s}_coded" in row and pd.notna(row[f"{s}_coded"]):
            x = float(row[f"{s}_coded"])
        elif s in row and pd.notna(row[s]):
            x = float(doe.actual_to_coded(np.array([float(row[s])]), lo, hi)[0])
        else:
            continue
        if doe.at_bound(x, "low"):
            out.append(f"{s} at its low bound {lo:g}")
        elif doe.at_bound(x, "high"):
            out.append(f"{s} at its high bound {hi:g}")
    return out


def calibrated_levels(stage: dict, optimum: pd.DataFrame, case: str | None = None) -> dict[str, float]:
    """Actual factor levels of the calibrated set of one optimisation case (the first case
    when ``case`` is None); InputError when the case has none (e.g. its target is missing)."""
    opt = stage.get("optimise") or {}
    cases = [c["id"] for c in opt.get("cases", [])]
    if case is None:
        if not cases:
            raise InputError(stage.get("id"), "optimise", "an optimisation case", None)
        case = cases[0]
    sel = calibrated_rows(optimum, case)
    if sel.empty:
        note = optimum.loc[optimum["case"].astype(str) == str(case), "note"] if "note" in optimum else []
        raise InputError(f"optimum of stage {stage.get('id')}", f"case {case}",
                         "a calibrated set of factor levels",
                         next((str(n) for n in note if isinstance(n, str)), "none"))
    row = sel.iloc[0]
    # 12 significant digits: a level on a bound stays the bound (0.2, not 0.1999999999999999)
    return {s: float(f"{float(row[s]):.12g}") for s in stage["factors"]}


def screening_ranges(soil_data: dict, stage: dict) -> dict[str, tuple[float, float, str]]:
    """``{symbol: (low, high, origin)}`` (actual units) of the range each factor of a DEM stage
    may be searched over past its own levels by the second calibration round
    (:func:`soilcal.chain.refine.search_region`), looked up by
    :func:`soilcal.chain.adaptive.second_round_range`: the range the soil declares under
    ``simulation.search_ranges`` wherever it declares one (the user's explicit choice); else, for
    a stage derived from the simulated path (``derivation.kind = "path"``, ``design: recipe``),
    the ``low`` .. ``high`` of the factor setting the same parameter in the Plackett-Burman
    screening the stage descends from; else none.  Each range is widened to the stage's own
    bounds where it is narrower; ``origin`` names the values used and where they come from
    (:meth:`SearchRange.text`).  Empty for ``design: printed`` (its second round stays in the
    Box-Behnken box, to be compared point by point with the paper; :func:`unused_search_ranges`)
    and ``design: adaptive`` (no second round; its ranges, which do not take declared ones:
    :func:`soilcal.chain.adaptive.stage_for`), and for
    a factor with neither range (its range is the stage's own)."""
    from dataclasses import replace

    from soilcal.chain.adaptive import second_round_range
    from soilcal.chain.derive import design_mode

    if design_mode(soil_data) != "recipe":
        return {}
    path = (stage.get("derivation") or {}).get("kind") == "path"
    out = {}
    for s, f in (stage.get("factors") or {}).items():
        found = second_round_range(soil_data, stage["id"], f.get("parameter"), screening=path)
        if found is None or f.get("low") is None or f.get("high") is None:
            continue
        used = replace(found, low=min(found.low, float(f["low"])), high=max(found.high, float(f["high"])))
        out[s] = (used.low, used.high, used.text())
    return out


def unused_search_ranges(soil_data: dict, stage: dict) -> list[str]:
    """The declared ranges (``simulation.search_ranges``) of a stage's factors that its second
    calibration round does not use: every one under ``design: printed``, whose second round
    stays in the Box-Behnken box (the printed design is there to compare point by point with
    the paper); ``["A: declared search range 0..10 (simulation.search_ranges.G)", ...]``."""
    from soilcal.chain.adaptive import declared_range
    from soilcal.chain.derive import design_mode

    if design_mode(soil_data) != "printed":
        return []
    out = []
    for s, f in (stage.get("factors") or {}).items():
        found = declared_range(soil_data, f.get("parameter"))
        if found is not None:
            out.append(f"{s}: {found.text()}")
    return out
