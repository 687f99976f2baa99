"""Errata: every place where a recomputation disagrees with a printed number.

A printed number is taken at its printed precision: ``24.15`` stands for the interval
[24.145, 24.155], ``0.0002`` for [0.00015, 0.00025], ``<0.0001`` for [0, 0.0001]. A recomputed
value *agrees* when it lies in that interval (plus a relative 1e-9 for floating point). Printed
tables are also checked against themselves with interval arithmetic: mean square = SS/df,
F = MS/MS_residual, p = P(F_{df, df_res} > F), Model SS = sum of the term SS (for an
orthogonal design), Cor Total = Model + Residual. Nothing is tuned to make a disagreement vanish:
each one becomes a row ``where, printed, recomputed, note``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from soilcal.config.quantities import PLAUSIBLE, plausible_kind, quantity_factor, si_factor
from soilcal.errors import InputError
from soilcal.rsm.printed import parse_printed as rsm_parse_printed

COLUMNS = ["where", "printed", "recomputed", "note"]


@dataclass(frozen=True)
class Printed:
    """A printed number with the interval its rounding stands for."""

    text: str
    value: float
    lo: float
    hi: float

    def contains(self, x: float, rel: float = 1e-9) -> bool:
        if x is None or not np.isfinite(x):
            return False
        eps = rel * max(1.0, abs(x))
        return self.lo - eps <= x <= self.hi + eps

    def overlaps(self, lo: float, hi: float) -> bool:
        eps = 1e-9 * max(1.0, abs(lo), abs(hi))
        return not (hi < self.lo - eps or lo > self.hi + eps)


def parse_printed(text) -> Printed | None:
    """Interval a printed number stands for (via :func:`soilcal.rsm.printed.parse_printed`);
    ``None`` for an empty cell or text that is no number."""
    if text is None or (isinstance(text, float) and math.isnan(text)):
        return None
    s = str(text).strip()
    if s in ("", "-", "nan"):
        return None
    try:
        op, value, decimals = rsm_parse_printed(s)
    except InputError:
        return None
    half = 0.5 * 10.0 ** (-decimals)
    if op in ("<", "<="):
        return Printed(s, value, -math.inf if value <= 0 else 0.0, value)
    if op in (">", ">="):
        return Printed(s, value, value, math.inf)
    return Printed(s, value, value - half, value + half)


def _fmt(x) -> str:
    if x is None:
        return ""
    if isinstance(x, str):
        return x
    if not np.isfinite(x):
        return str(x)
    return f"{x:.6g}"


def _norm(s: str) -> str:
    return re.sub(r"\s+", " ", str(s).strip().lower()).replace("cor. total", "cor total")


class Errata:
    def __init__(self):
        self.rows: list[dict] = []

    def add(self, where, printed, recomputed, note):
        self.rows.append({"where": where, "printed": _fmt(printed), "recomputed": _fmt(recomputed), "note": note})

    def check(self, where, printed_text, recomputed, note="recomputed value outside the printed precision"):
        p = parse_printed(printed_text)
        if p is None or recomputed is None or (isinstance(recomputed, float) and math.isnan(recomputed)):
            return
        if not p.contains(float(recomputed)):
            self.add(where, p.text, float(recomputed), note)

    def frame(self) -> pd.DataFrame:
        return pd.DataFrame(self.rows, columns=COLUMNS)


# ------------------------------------------------------------------ printed-table consistency


def anova_self_consistency(err: Errata, where: str, printed: pd.DataFrame, orthogonal: bool = False) -> None:
    """Check a printed ANOVA table against itself with interval arithmetic.

    ``orthogonal`` adds the check Model SS = sum of term SS, which holds for two-level
    (Plackett-Burman, factorial) main-effects models but not for the correlated square terms of a
    Box-Behnken model.
    """
    rows = {_norm(r["source"]): r for _, r in printed.iterrows()}
    res = rows.get("residual")
    ms_res = parse_printed(res["mean_sq"]) if res is not None else None
    df_res = parse_printed(res["df"]).value if res is not None and parse_printed(res["df"]) else None
    if res is not None and ms_res is None:
        ss, d = parse_printed(res["sum_sq"]), parse_printed(res["df"])
        if ss and d and d.value > 0:
            ms_res = Printed("", ss.value / d.value, ss.lo / d.value, ss.hi / d.value)
    for key, r in rows.items():
        ss, d, ms, f, p = (parse_printed(r.get(c)) for c in ("sum_sq", "df", "mean_sq", "F", "p"))
        src = r["source"]
        if ss and d and ms and d.value > 0 and not ms.overlaps(ss.lo / d.value, ss.hi / d.value):
            err.add(f"{where} / {src} / mean_sq", ms.text, ss.value / d.value, "printed mean square is not SS/df")
        if key in ("lack of fit",):
            pe = rows.get("pure error")
            pe_ms = None
            if pe is not None:
                pe_ss, pe_df = parse_printed(pe["sum_sq"]), parse_printed(pe["df"])
                if pe_ss and pe_df:
                    pe_ms = Printed("", pe_ss.value / pe_df.value, pe_ss.lo / pe_df.value, pe_ss.hi / pe_df.value)
            denom, d2 = pe_ms, (parse_printed(pe["df"]).value if pe is not None and parse_printed(pe["df"]) else None)
        else:
            denom, d2 = ms_res, df_res
        if key in ("residual", "pure error", "cor total") or denom is None or d2 is None:
            continue
        num = ms if ms else (Printed("", ss.value / d.value, ss.lo / d.value, ss.hi / d.value) if ss and d else None)
        if num is None or d is None:
            continue
        f_lo = num.lo / denom.hi if denom.hi > 0 else math.inf
        f_hi = num.hi / denom.lo if denom.lo > 0 else math.inf
        if f and not f.overlaps(f_lo, f_hi):
            err.add(f"{where} / {src} / F", f.text, num.value / denom.value, "printed F is not MS/MS_error of the same table")
        if p and d.value > 0:
            fl, fh = (f.lo, f.hi) if f else (f_lo, f_hi)
            p_hi = stats.f.sf(max(fl, 0.0), d.value, d2)
            p_lo = stats.f.sf(fh, d.value, d2) if np.isfinite(fh) else 0.0
            if not p.overlaps(p_lo, p_hi):
                fv = f.value if f else num.value / denom.value
                err.add(f"{where} / {src} / p", p.text, float(stats.f.sf(fv, d.value, d2)),
                        f"printed p is not P(F({d.value:g},{d2:g}) > F) for the printed F")
    model, total = rows.get("model"), rows.get("cor total")
    if model is not None and res is not None and total is not None:
        pm, pr, pt = parse_printed(model["sum_sq"]), parse_printed(res["sum_sq"]), parse_printed(total["sum_sq"])
        if pm and pr and pt and not pt.overlaps(pm.lo + pr.lo, pm.hi + pr.hi):
            err.add(f"{where} / Cor Total / sum_sq", pt.text, pm.value + pr.value, "Cor Total is not Model + Residual")
        dm, dr, dt = (parse_printed(x["df"]) for x in (model, res, total))
        if dm and dr and dt and abs(dm.value + dr.value - dt.value) > 1e-9:
            err.add(f"{where} / Cor Total / df", dt.text, dm.value + dr.value, "total df is not model df + residual df")
    if orthogonal and model is not None:
        terms = [r for k, r in rows.items() if k not in ("model", "residual", "lack of fit", "pure error", "cor total")]
        ivs = [parse_printed(r["sum_sq"]) for r in terms]
        pm = parse_printed(model["sum_sq"])
        if pm and ivs and all(ivs):
            lo, hi = sum(i.lo for i in ivs), sum(i.hi for i in ivs)
            if not pm.overlaps(lo, hi):
                err.add(f"{where} / Model / sum_sq", pm.text, sum(i.value for i in ivs),
                        "Model SS is not the sum of the printed term SS (orthogonal design)")


# ------------------------------------------------------------------ recomputation vs print


def compare_anova(err: Errata, where: str, printed: pd.DataFrame, recomputed: pd.DataFrame) -> None:
    rec = {_norm(r["source"]): r for _, r in recomputed.iterrows()}
    for _, r in printed.iterrows():
        key = _norm(r["source"])
        if key not in rec:
            err.add(f"{where} / {r['source']}", r["source"], "", "printed row has no counterpart in the recomputed model")
            continue
        for col in ("sum_sq", "df", "mean_sq", "F", "p"):
            if col in r.index:
                err.check(f"{where} / {r['source']} / {col}", r[col], rec[key].get(col))


def compare_coefficients(err: Errata, where: str, printed: pd.DataFrame, recomputed: pd.DataFrame) -> None:
    for model, grp in printed.groupby("model"):
        rec = recomputed[recomputed["model"] == model]
        recd = {str(t): row for t, row in zip(rec["term"], rec.to_dict("records"))}
        for _, r in grp.iterrows():
            term = str(r["term"])
            if term not in recd:
                err.add(f"{where} / {model} / {term}", r.get("coded"), "", "printed term not in the recomputed model")
                continue
            for col in ("coded", "actual"):
                if col in r.index:
                    err.check(f"{where} / {model} / {term} / {col}", r[col], recd[term].get(col))


def compare_fit(err: Errata, where: str, printed: dict, recomputed: dict) -> None:
    for k, v in printed.items():
        if k == "source" or k not in recomputed:
            continue
        err.check(f"{where} / {k}", str(v), recomputed[k])


def compare_effects(err: Errata, where: str, printed: pd.DataFrame, recomputed: pd.DataFrame) -> None:
    rec = {str(t): r for t, r in zip(recomputed["term"], recomputed.to_dict("records"))}
    for _, r in printed.iterrows():
        t = str(r["source"])
        if t not in rec:
            continue
        for col in printed.columns:
            if col in ("source", "significance") or col not in rec[t]:
                continue
            err.check(f"{where} / {t} / {col}", r[col], rec[t][col])


def compare_steepest(err: Errata, where: str, table: pd.DataFrame, response: str, target: float | None,
                     chosen_printed: int | None, chosen_recomputed: int | None) -> None:
    if target and "relative_error_percent" in table.columns:
        for _, r in table.iterrows():
            rec = abs(float(r[response]) - target) / target * 100
            err.check(f"{where} / step {int(r['step'])} / relative error %", r["relative_error_percent"], rec,
                      f"printed relative error does not follow from the printed {response} and target {target}")
    if chosen_printed is not None and chosen_recomputed is not None and chosen_printed != chosen_recomputed:
        err.add(f"{where} / chosen step", chosen_printed, chosen_recomputed,
                "the step closest to the target in the printed responses is not the printed choice")


def duplicated_sequences(err: Errata, tables: dict[str, tuple[str, pd.DataFrame, list[str]]], min_len: int = 4) -> None:
    """Flag response columns of one table that repeat a run of values from another table."""
    seqs = []
    for sid, (where, df, cols) in tables.items():
        for c in cols:
            if c in df.columns:
                seqs.append((sid, where, c, df[c].to_numpy(float)))
    for i, (sa, wa, ca, a) in enumerate(seqs):
        for sb, wb, cb, b in seqs[i + 1:]:
            if sa == sb:
                continue
            n = _longest_common_run(a, b)
            if n >= min_len:
                err.add(f"{wa} / {ca} vs {wb} / {cb}", f"{n} consecutive equal values", "",
                        "printed responses repeat another table's values verbatim (copied column?)")


def _longest_common_run(a: np.ndarray, b: np.ndarray) -> int:
    best = 0
    for i in range(len(a)):
        for j in range(len(b)):
            k = 0
            while i + k < len(a) and j + k < len(b) and a[i + k] == b[j + k]:
                k += 1
            best = max(best, k)
    return best


# ------------------------------------------------------------------ physical plausibility

def plausibility(err: Errata, soil: dict) -> None:
    # the ranges of PLAUSIBLE, the one table of physical ranges, shared with the check of a soil
    # of one's own at load
    def check(where, name, q):
        kind = plausible_kind(name, where.startswith("materials."))
        if kind is None:
            return
        lo, hi, si_unit = PLAUSIBLE[kind]
        declared = [q.get("value")] + list(q.get("values", [])) + [q.get("low"), q.get("high")]
        if kind == "moisture_content":
            # every declared value and range end, a lone low or high too, in % by the factor of
            # its unit (quantities.quantity_factor, as the tables read it); a unit without a factor is judged where a
            # moisture is compared with it, a value without a unit is taken as printed, in %
            f = 1.0 if q.get("unit") is None else quantity_factor("moisture_content", q.get("unit"))
        else:
            f = si_factor(str(q.get("unit", "")), si_unit)
        if f is None:
            return
        for v in (v for v in declared if v is not None):
            x = float(v) * f
            if not lo <= x <= hi:
                err.add(f"{where} ({q.get('source', '')})", f"{v} {q.get('unit', '')}", f"{x:.4g} {si_unit}",
                        f"physically implausible {kind.replace('_', ' ')} (expected {lo:g}..{hi:g} {si_unit})")

    for k, q in soil.get("properties", {}).items():
        if isinstance(q, dict) and "bins" not in q:
            check(f"properties.{k}", k, q)
    for m, props in soil.get("materials", {}).items():
        for k, q in props.items():
            check(f"materials.{m}.{k}", k, q)
    for st in soil["stages"]:
        for sym, f in st["factors"].items():
            kind = soil["parameters"][f["parameter"]].get("kind")
            if kind in PLAUSIBLE and kind != "shear_modulus":
                q = {"low": f.get("low"), "high": f.get("high"), "values": f.get("levels", []),
                     "unit": soil["parameters"][f["parameter"]]["unit"], "source": st.get("source", "")}
                check(f"stages.{st['id']}.factors.{sym}", kind, q)


def optimum_check(err: Errata, where: str, model, syms: list[str], printed: dict, target: float,
                  response: str) -> None:
    """Does the printed optimum, within its printed rounding, reach the target on the recomputed model?"""
    ivs = [parse_printed(str(printed[s])) for s in syms]
    if not all(ivs):
        return
    grid = np.array(np.meshgrid(*[np.linspace(i.lo, i.hi, 5) for i in ivs])).reshape(len(syms), -1).T
    pred = model.predict_actual(grid)
    lo, hi = float(np.min(pred)), float(np.max(pred))
    centre = float(model.predict_actual(np.array([[i.value for i in ivs]]))[0])
    tp = parse_printed(str(target))
    if tp is not None and not tp.overlaps(lo, hi):
        err.add(f"{where} / predicted {response} at the printed optimum", f"target {target}", centre,
                f"the printed optimum does not reach the target on the recomputed model (range over its rounding {lo:.4g}..{hi:.4g})")


# ------------------------------------------------------------------ whole soil


def build_errata(soil: dict, published_dir, stages: dict[str, dict]) -> pd.DataFrame:
    """All errata of one soil.

    ``stages`` maps a stage id to its replay outputs: ``table`` (printed table), ``design_check``
    (frame of unmatched design rows), and for regression stages ``anova``, ``coefficients``,
    ``fit``, ``effects``, ``fits`` (the fitted models by response), and ``optimum``.
    """
    from pathlib import Path

    published_dir = Path(published_dir)
    err = Errata()
    plausibility(err, soil)
    targets = soil.get("targets", {})
    dup_tables = {}
    for st in soil["stages"]:
        sid = st["id"]
        out = stages.get(sid)
        src = st.get("source", sid)
        if out is None or out.get("table") is None:
            continue
        table = out["table"]
        dup_tables[sid] = (f"{src} ({sid})", table, [r.get("column", r["id"]) for r in st["responses"]])
        chk = out.get("design_check")
        if chk is not None and len(chk):
            printed_rows = chk[chk["origin"] == "printed"]["row"].tolist()
            generated_rows = chk[chk["origin"] == "generated"]["row"].tolist()
            err.add(f"{src} / design ({sid})", "; ".join(printed_rows), "; ".join(generated_rows),
                    "printed design differs from the generated design as a set of rows")
        if st["kind"] == "steepest_ascent":
            opt = out.get("optimum")
            for r in st["responses"]:
                rid = r["id"]
                tgt = targets.get(rid, {}).get("value")
                rec = None
                if opt is not None and len(opt):
                    sel = opt[(opt["response"] == rid) & (opt["chosen"].astype(bool))]
                    rec = int(sel["step"].iloc[0]) if len(sel) else None
                compare_steepest(err, f"{src} ({sid})", table, r.get("column", rid), tgt, st.get("chosen_step"), rec)
            continue
        for rid, pr in st.get("printed", {}).items():
            w = f"{pr.get('source', src)} ({sid}, {rid})"
            anova = out["anova"][out["anova"]["response"] == rid]
            for label, key in (("full", "anova_full"), ("reduced", "anova_reduced")):
                if key in pr:
                    printed = pd.read_csv(published_dir / pr[key], dtype=str, keep_default_na=False)
                    wl = f"{w} / ANOVA {label}"
                    anova_self_consistency(err, wl + " (printed table)", printed)
                    compare_anova(err, wl, printed, anova[anova["model"] == label])
            if "effects" in pr:
                printed = pd.read_csv(published_dir / pr["effects"], dtype=str, keep_default_na=False)
                eff = out["effects"][out["effects"]["response"] == rid]
                if {"sum_sq", "df", "F"} <= set(printed.columns):
                    anova_self_consistency(err, f"{w} / screening ANOVA (printed table)", printed, orthogonal=True)
                compare_effects(err, f"{w} / screening", printed, eff)
                a = anova[anova["model"] == "full"]
                if {"sum_sq", "df"} <= set(printed.columns):
                    compare_anova(err, f"{w} / screening ANOVA", printed, a)
            if "coefficients" in pr:
                printed = pd.read_csv(published_dir / pr["coefficients"], dtype=str, keep_default_na=False)
                coef = out["coefficients"][out["coefficients"]["response"] == rid]
                compare_coefficients(err, f"{w} / equation", printed, coef)
            fit = out["fit"]
            for label, key in (("full", "fit_full"), ("reduced", "fit_reduced")):
                if key in pr:
                    rec = fit[(fit["response"] == rid) & (fit["model"] == label)]
                    if len(rec):
                        compare_fit(err, f"{pr[key].get('source', w)} ({sid}, {rid}) / fit {label}", pr[key], rec.iloc[0].to_dict())
        opt = st.get("optimise")
        fits = out.get("fits", {})
        if opt:
            syms = list(st["factors"])
            for case in opt["cases"]:
                printed = case.get("printed_optimum")
                if not printed or not all(s in printed for s in syms):
                    continue
                for rid, g in case["goals"].items():
                    if g["goal"] != "target" or rid not in fits:
                        continue
                    tgt = g.get("value")
                    if tgt is None and "target" in g:
                        tgt = targets.get(g["target"], {}).get("value")
                    if tgt is None:
                        continue
                    optimum_check(err, f"{case.get('source', src)} ({sid}, case {case['id']})", fits[rid], syms,
                                  printed, tgt, rid)
    duplicated_sequences(err, dup_tables)
    for e in soil.get("errata", []):
        err.add(e["where"], e["printed"], e.get("recomputed") or "", "found while encoding: " + e["note"])
    return err.frame()
