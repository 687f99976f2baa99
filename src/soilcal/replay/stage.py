"""One stage of a replay: design, regression/ANOVA, optimum.

Inputs are plain data: the soil mapping (as loaded from YAML), the stage id and the printed
table. Functions return pandas frames; writing files is left to the caller.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from soilcal import doe, rsm
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


# --------------------------------------------------------------------------- design


def generated_design(stage: dict) -> np.ndarray:
    """Coded design generated for the stage (pyDOE3 / Plackett-Burman generators)."""
    k = len(stage["factors"])
    if stage["kind"] == "plackett_burman":
        return doe.plackett_burman(k + len(stage.get("dummies", [])))
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
            df[f"{s}_actual"] = doe.coded_to_actual(coded[:, j], low[j], high[j])
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
    syms, low, high = bounds(stage)
    data = stage_data(stage, table)
    fits = []
    for rid in response_columns(stage):
        sub = data.dropna(subset=[rid])
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


def regression_frames(stage: dict, table: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """anova, fit, coefficients and effects frames for a PB/BBD stage (all responses)."""
    anova, fit, coef, effects = [], [], [], []
    data = stage_data(stage, table)
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
            try:
                bc = rsm.boxcox(m)
                row.update({"boxcox_lambda": bc.get("lambda_best"), "boxcox_ci_low": bc.get("ci_low"),
                            "boxcox_ci_high": bc.get("ci_high"), "boxcox_recommended": bc.get("recommended_transform")})
            except (ValueError, np.linalg.LinAlgError) as exc:  # non-positive responses
                row["boxcox_recommended"] = f"n/a ({exc})"
            fit.append(row)
            c = m.coefficients().copy()
            c.insert(0, "model", label)
            c.insert(0, "response", sf.response)
            coef.append(c)
        if stage["kind"] == "plackett_burman":
            e = rsm.screening_effects(data, syms, sf.response, dummies=stage.get("dummies"))
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


def _goal_values(goals: dict, targets: dict) -> dict:
    out = {}
    for rid, g in goals.items():
        g = dict(g)
        if "target" in g:
            t = targets[g.pop("target")]
            g["value"] = t.get("value")
        out[rid] = g
    return out


def optimum_frame(stage: dict, table: pd.DataFrame, targets: dict, seed: int) -> pd.DataFrame:
    """Optimal settings for every optimisation case of the stage.

    Steepest ascent: the step whose response is closest to the target (and the printed choice).
    Box-Behnken: Derringer-Suich desirability solutions (several distinct ones, as Design-Expert
    lists them) and, for ``method: pso``, particle-swarm solutions too; the printed optimum is
    added as a row with its predicted responses.
    """
    from soilcal import optimise

    if stage["kind"] == "steepest_ascent":
        rows = []
        for rid, col in response_columns(stage).items():
            tgt = targets.get(rid, {}).get("value")
            y = table[col].to_numpy(float)
            err = np.abs(y - tgt) / tgt * 100 if tgt else np.full(len(y), np.nan)
            best = int(np.nanargmin(err)) if tgt else -1
            for i in range(len(y)):
                r = {"response": rid, "step": int(table["step"].iloc[i]), "value": y[i], "target": tgt,
                     "relative_error_percent": err[i], "chosen": i == best,
                     "printed_choice": int(table["step"].iloc[i]) == stage.get("chosen_step")}
                for s in stage["factors"]:
                    r[s] = table[s].iloc[i]
                rows.append(r)
        return pd.DataFrame(rows)

    opt = stage.get("optimise")
    if not opt:
        return pd.DataFrame(columns=["case", "method", "solution"])
    fits = {sf.response: (sf.reduced if opt.get("model", "reduced") == "reduced" else sf.full)
            for sf in fit_stage(stage, table)}
    syms, low, high = bounds(stage)
    frames = []
    for case in opt["cases"]:
        goals = _goal_values(case["goals"], targets)
        if any(g["goal"] == "target" and g.get("value") is None for g in goals.values()):
            frames.append(pd.DataFrame([{"case": case["id"], "method": "none", "solution": "",
                                         "note": "target value not printed"}]))
            continue
        models = {rid: fits[rid] for rid in goals}
        d = optimise.desirability_optimise(models, goals, seed=seed, n_solutions=opt.get("n_solutions", 5))
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
                                            iterations=p.get("iterations", 200), seed=seed)
                row = {"case": case["id"], "method": "pso", "solution": 1}
                xa = np.asarray(res["x"], float)
                xc = doe.actual_to_coded(xa, low, high)
                for j, s in enumerate(syms):
                    row[f"{s}_coded"] = xc[j]
                    row[s] = xa[j]
                row[rid] = float(model.predict_actual(xa[None, :])[0])
                row["objective"] = float(res["f"])
                frames.append(pd.DataFrame([row]))
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
    return pd.concat(frames, ignore_index=True)
