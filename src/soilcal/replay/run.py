"""File-level entry points of the replay: read inputs, call the stage functions, write outputs.

Used by the Snakemake adapters in ``workflow/scripts/`` and by ``soilcal replay``.
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from soilcal.config.load import read_table
from soilcal.replay import errata as errata_mod
from soilcal.replay.stage import (

    design_frame,
    fit_stage,
    optimum_frame,
    regression_frames,
    response_columns,
    stage_data,
)


def _table(path) -> pd.DataFrame | None:
    return None if path in (None, "", []) else read_table(Path(path))


def _mkdirs(*paths) -> None:
    for p in paths:
        Path(p).parent.mkdir(parents=True, exist_ok=True)


def write_design(stage: dict, table_path, out_design, out_check) -> dict:
    table = _table(table_path)
    df, info = design_frame(stage, table)
    _mkdirs(out_design, out_check)
    df.to_csv(out_design, index=False)
    rows = [{"origin": "generated", "row": json.dumps(r)} for r in info["only_generated"]]
    rows += [{"origin": "printed", "row": json.dumps(r)} for r in info["only_printed"]]
    pd.DataFrame(rows, columns=["origin", "row"]).to_csv(out_check, index=False)
    return info


def write_regression(stage: dict, table_path, out: dict) -> None:
    frames = regression_frames(stage, _table(table_path))
    for key in ("anova", "fit", "coefficients", "effects"):
        _mkdirs(out[key])
        frames[key].to_csv(out[key], index=False)


def write_optimum(stage: dict, table_path, targets: dict, seed: int, out) -> None:
    df = optimum_frame(stage, _table(table_path), targets, seed)
    _mkdirs(out)
    df.to_csv(out, index=False)


def write_figures(kind: str, stage: dict, table_path, targets: dict, outdir, parameters: dict | None = None) -> list[Path]:
    """Figures of one kind for a stage: pareto, steepest, surfaces, diagnostics.

    ``parameters`` (the soil's parameter table) gives the axis labels 'A: name (unit)'.
    """
    from soilcal import plots, rsm

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    table = _table(table_path)
    written: list[Path] = []
    if kind == "steepest":
        for rid, col in response_columns(stage).items():
            df = table.rename(columns={col: rid})
            rlab = next(f"{r['name']} ({r['unit']})" for r in stage["responses"] if r["id"] == rid)
            written += list(plots.steepest_ascent(df, list(stage["factors"]), rid,
                                                  targets.get(rid, {}).get("value"), outdir / rid,
                                                  response_label=rlab))
        return written
    data = stage_data(stage, table)
    syms = list(stage["factors"])
    labels = _labels(stage, parameters or {})
    rlabels = {r["id"]: f"{r['name']} ({r['unit']})" for r in stage["responses"]}
    for sf in fit_stage(stage, table):
        rid = sf.response
        rlab = rlabels[rid]
        if kind == "pareto":
            eff = rsm.screening_effects(data, syms, rid, dummies=stage.get("dummies"))
            written += list(plots.pareto_effects(eff, outdir / rid, response_label=rlab))
        elif kind == "diagnostics":
            model = sf.reduced
            written += list(plots.predicted_vs_actual(model, outdir / f"{rid}_predicted_vs_actual", response_label=rlab))
            written += list(plots.residual_diagnostics(model, outdir / f"{rid}_residuals", response_label=rlab))
        elif kind == "surfaces":
            model = sf.reduced
            a = model.anova()
            pairs = []
            for t in model.terms:
                if "*" in t:
                    p = a.loc[a["source"] == t, "p"]
                    if len(p) and float(p.iloc[0]) <= 0.05:
                        i, j = (syms.index(s) for s in t.split("*"))
                        pairs.append((i, j))
            if not pairs:  # no significant interaction: show the two strongest main effects
                coef = model.coefficients().set_index("term")["coded"]
                main = sorted(syms, key=lambda s: -abs(float(coef.get(s, 0.0))))[:2]
                pairs = [tuple(sorted(syms.index(s) for s in main))]
            points = data[syms].to_numpy(float)
            for i, j in pairs:
                written += list(plots.response_surface(model, i, j, stem=outdir / f"{rid}_{syms[i]}{syms[j]}",
                                                       labels=labels, design_points=points, response_label=rlab))
        else:
            raise ValueError(kind)
    return written


def _labels(stage: dict, parameters: dict) -> list[str]:
    out = []
    for sym, f in stage["factors"].items():
        p = parameters.get(f["parameter"])
        out.append(plots_label(sym, p))
    return out


def plots_label(sym: str, p: dict | None) -> str:
    from soilcal.plots import factor_label

    if not p:
        return sym
    return factor_label(sym, (p["name"], None if p["unit"] == "-" else p["unit"]))


def fitted_models(stage: dict, table: pd.DataFrame, which: str = "reduced") -> dict:
    return {sf.response: (sf.reduced if which == "reduced" else sf.full) for sf in fit_stage(stage, table)}


def write_errata(soil: dict, published_dir, stage_dirs: dict[str, str], out) -> pd.DataFrame:
    """Collect the stage outputs of one soil and write its errata table."""
    stages = {}
    for st in soil["stages"]:
        sid = st["id"]
        if st.get("table") is None:
            continue
        d = Path(stage_dirs[sid])
        table = read_table(Path(published_dir) / st["table"])
        entry = {"table": table}
        chk = d / "design_check.csv"
        if chk.is_file():
            entry["design_check"] = pd.read_csv(chk)
        for key in ("anova", "coefficients", "fit", "effects", "optimum"):
            f = d / f"{key}.csv"
            if f.is_file():
                entry[key] = pd.read_csv(f)
        if st["kind"] in ("box_behnken", "plackett_burman"):
            opt = st.get("optimise", {})
            entry["fits"] = fitted_models(st, table, opt.get("model", "reduced"))
        stages[sid] = entry
    df = errata_mod.build_errata(soil, published_dir, stages)
    _mkdirs(out)
    df.to_csv(out, index=False)
    return df


def replay_soil(soil, out_dir) -> tuple[dict[str, str], pd.DataFrame]:
    """Replay every stage of a loaded :class:`~soilcal.config.Soil` (no figures) into
    ``out_dir/<stage>/`` and write ``out_dir/errata.csv``; return the stage folders and errata."""
    out_dir = Path(out_dir)
    dirs = {}
    for st in soil.stages:
        d = out_dir / st["id"]
        dirs[st["id"]] = str(d)
        table = soil.table_path(st["id"])
        write_design(st, table, d / "design.csv", d / "design_check.csv")
        if table is None:
            continue
        if st["kind"] in ("plackett_burman", "box_behnken"):
            write_regression(st, table, {k: d / f"{k}.csv" for k in ("anova", "fit", "coefficients", "effects")})
        if st["kind"] == "steepest_ascent" or st.get("optimise"):
            write_optimum(st, table, soil.data["targets"], soil.data["seed"], d / "optimum.csv")
    errata = write_errata(soil.data, soil.published_dir(), dirs, out_dir / "errata.csv")
    return dirs, errata


__all__ = ["replay_soil", "write_design", "write_regression", "write_optimum", "write_figures", "write_errata"]
