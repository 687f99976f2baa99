"""File-level entry points of the calibration chain: read inputs, call the stage functions,
write outputs.

Every stage of every soil goes through the same writers whatever its response source
(:mod:`soilcal.chain.sources`): ``stage.json`` (the stage that was run,
:mod:`soilcal.chain.derive`), ``design.csv``, the response table, ``anova.csv``, ``fit.csv``,
``coefficients.csv``, ``effects.csv``, ``optimum.csv``, ``identifiability.csv`` and the
figures.  Used by the Snakemake adapters in ``workflow/scripts/`` and by ``soilcal replay``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from soilcal.atomic import write_text


def _table(path) -> pd.DataFrame | None:
    from soilcal.config.tables import read_table

    return None if path in (None, "", []) else read_table(Path(path))


def write_csv(df: pd.DataFrame, path) -> Path:
    """Write a frame atomically (:func:`soilcal.atomic.write_text`): a killed job leaves no
    partial table."""
    return write_text(path, df.to_csv(index=False))


def write_json(obj, path) -> Path:
    """Write ``obj`` as JSON atomically; a NaN or infinite number (a step whose runs failed,
    an undefined statistic) is written as ``null``: the bare ``NaN`` / ``Infinity`` that
    Python's json module writes by default are not JSON, and strict readers refuse them."""
    return write_text(path, json_text(obj))


def json_text(obj) -> str:
    """``obj`` as indented JSON text, every non-finite number ``null`` (:func:`write_json`)."""
    return json.dumps(_finite(obj), indent=1, sort_keys=False, allow_nan=False, default=_json_default) + "\n"


def _finite(o):
    """``o`` with every NaN or infinite float (Python or NumPy, also pandas' missing value) as
    None, NumPy scalars as Python ones, tuples as lists, recursively."""
    if isinstance(o, dict):
        return {k: _finite(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_finite(v) for v in o]
    if isinstance(o, np.ndarray):
        return [_finite(v) for v in o.tolist()]
    if isinstance(o, (bool, np.bool_)):
        return bool(o)
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (float, np.floating)):
        return float(o) if np.isfinite(o) else None
    if o is pd.NA or o is pd.NaT:
        return None
    return o


def _json_default(o):
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return None if not np.isfinite(o) else float(o)
    if isinstance(o, (np.bool_,)):
        return bool(o)
    raise TypeError(type(o).__name__)


def read_stage(path) -> dict:
    """The stage of a ``stage.json`` written by :func:`write_stage`."""
    return json.loads(Path(path).read_text())


def write_stage(stage: dict, out) -> Path:
    return write_json(stage, out)


def write_design(stage: dict, table_path, out_design, out_check, printed: bool = False,
                 printed_coding: str | None = None) -> dict:
    """The stage's design (coded and actual) and its comparison with the printed one.

    ``printed``: the design is the printed table's own rows (the DEM source's
    ``simulation.design: printed``) rather than the generated design matched to them.
    """
    from soilcal.chain.stage import design_frame, printed_design

    table = _table(table_path)
    if printed and table is not None:
        df, info = printed_design(stage, table, printed_coding), {"equal": True, "only_generated": [], "only_printed": []}
    else:
        df, info = design_frame(stage, table)
    write_csv(df, out_design)
    rows = [{"origin": "generated", "row": json.dumps(r)} for r in info["only_generated"]]
    rows += [{"origin": "printed", "row": json.dumps(r)} for r in info["only_printed"]]
    write_csv(pd.DataFrame(rows, columns=["origin", "row"]), out_check)
    return info


def write_stage_design(source: str, config_stage: dict, soil_data: dict | None, inputs: dict,
                       outputs: dict) -> dict:
    """``stage.json``, ``design.csv`` and ``design_check.csv`` of one stage and source.

    published: the config's stage and the generated design matched to the printed table.
    dem: the stage :func:`soilcal.chain.derive.dem_stage` derives from the inputs
    (``targets``; ``from_stage``, ``from_responses``, ``from_effects``; ``fixed_stage``,
    ``fixed_optimum``), its generated design, or the printed rows with ``design: printed``.
    """
    from soilcal.chain import derive

    table = inputs.get("table")
    if source == "published":
        stage = derive.published_stage({"stages": [config_stage]}, config_stage["id"])
        info = write_design(stage, table, outputs["design"], outputs["check"])
    else:
        upstream = {}
        if "from_stage" in inputs:
            upstream["from"] = {"stage": read_stage(inputs["from_stage"]),
                                "responses": pd.read_csv(inputs["from_responses"]),
                                "effects": pd.read_csv(inputs["from_effects"]) if "from_effects" in inputs else None}
        if "fixed_stage" in inputs:
            upstream["fixed_from"] = {"stage": read_stage(inputs["fixed_stage"]),
                                      "optimum": pd.read_csv(inputs["fixed_optimum"])}
        stage = derive.dem_stage(soil_data, config_stage["id"], read_targets(inputs["targets"]), upstream)
        printed = bool(table) and derive.design_mode(soil_data) == "printed"
        info = write_design(stage, table if printed else None, outputs["design"], outputs["check"], printed=printed,
                            printed_coding=config_stage.get("table_coding",
                                                            "actual" if config_stage["kind"] == "steepest_ascent"
                                                            else "coded"))
    write_stage(stage, outputs["stage"])
    info["derivation"] = stage["derivation"]["text"]
    info["fixed"] = [f"{k} = {r['value']:g}: {r['origin']}" for k, r in (stage["derivation"].get("fixed") or {}).items()]
    info["fixed_not_used"] = [r["why"] for r in (stage["derivation"].get("fixed_not_used") or {}).values()]
    info["fixed_warnings"] = [r["warning"] for r in (stage["derivation"].get("fixed") or {}).values() if r.get("warning")]
    return info


def write_regression(stage: dict, table_path, out: dict) -> None:
    from soilcal.chain.stage import regression_frames

    frames = regression_frames(stage, _table(table_path))
    for key in ("anova", "fit", "coefficients", "effects"):
        write_csv(frames[key], out[key])


def read_targets(path) -> dict:
    """``{target_id: {"value", ...}}`` from a ``targets.csv`` (:mod:`soilcal.chain.targets`)."""
    df = pd.read_csv(path)
    out = {}
    for r in df.to_dict("records"):
        v = r.get("value")
        out[str(r["target_id"])] = {**r, "value": None if v is None or pd.isna(v) else float(v)}
    return out


def write_optimum(stage: dict, table_path, targets: dict, seed: int, out, out_identifiability=None) -> None:
    from soilcal.chain.stage import optimum_frames

    frames = optimum_frames(stage, _table(table_path), targets, seed)
    write_csv(frames["optimum"], out)
    if out_identifiability is not None:
        ident = frames["identifiability"]
        if ident is None:
            ident = pd.DataFrame(columns=["case", "factor", "n_sets", "min", "max", "spread", "spread_coded",
                                          "pinned", "note"])
        write_csv(ident, out_identifiability)


def _reference_effects(ref_stage: dict, ref_table: pd.DataFrame, rid: str, syms: list[str]) -> pd.DataFrame | None:
    """Standardized effects of the paper's printed screening table, on the DEM stage's symbols."""
    from soilcal import plots, rsm
    from soilcal.chain.stage import response_columns, stage_data

    col = response_columns(ref_stage).get(rid)
    if col is None or col not in ref_table.columns:
        return None
    data = stage_data(ref_stage, ref_table)
    eff = rsm.screening_effects(data, list(ref_stage["factors"]), rid, dummies=ref_stage.get("dummies"))
    t = plots.standardized_effects(eff, eff.attrs["residual"]["df"])
    par = {s: f["parameter"] for s, f in ref_stage["factors"].items()}
    return t[t["term"].isin([s for s in syms if s in par])]


def _same_path(stage: dict, reference: dict) -> bool:
    """The paper's path is drawn beside ours only where it is the same path: the same
    parameters at the same levels, step by step."""
    ours = {f["parameter"]: f.get("levels") for f in stage["factors"].values()}
    theirs = {f["parameter"]: f.get("levels") for f in reference["factors"].values()}
    if set(ours) != set(theirs):
        return False
    return all(a is not None and b is not None and len(a) == len(b) and np.allclose(a, b, rtol=0, atol=1e-9)
               for a, b in ((ours[k], theirs[k]) for k in ours))


def write_figures(kind: str, stage: dict, table_path, targets: dict, outdir, parameters: dict | None = None,
                  reference_stage: dict | None = None, reference_table=None) -> list[Path]:
    """Figures of one kind for a stage: pareto, steepest, surfaces, diagnostics.

    ``parameters`` (the soil's parameter table) gives the axis labels 'A: name (unit)'.
    ``reference_stage`` and ``reference_table`` (the paper's stage and printed table) overlay
    the published values where the figure has them: the paper's standardized effects on the
    Pareto chart (same symbols, same parameters), the paper's path responses on the
    steepest-ascent plot (the same path: same parameters, same levels).
    """
    from soilcal import plots
    from soilcal.chain.stage import analysis_data, fit_stage, response_columns

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    table = _table(table_path)
    ref_table = _table(reference_table)
    written: list[Path] = []
    path_targets = stage.get("path_targets") or {}
    if kind == "steepest":
        for rid, col in response_columns(stage).items():
            df = table.rename(columns={col: rid})
            rlab = next(f"{r['name']} ({r['unit']})" for r in stage["responses"] if r["id"] == rid)
            tgt = (path_targets.get(rid) or {}).get("value", targets.get(rid, {}).get("value"))
            ref = None
            if reference_stage is not None and ref_table is not None and _same_path(stage, reference_stage):
                rcol = response_columns(reference_stage).get(rid)
                if rcol in ref_table.columns and "step" in ref_table.columns:
                    ref = ref_table[["step", rcol]].rename(columns={rcol: rid})
            trend = None
            if stage.get("path_choice") == "fitted" and "step" in df.columns:
                from soilcal.doe.steepest import path_trend

                trend = path_trend(df["step"].to_numpy(float), df[rid].to_numpy(float))["fitted"]
            written += list(plots.steepest_ascent(df, list(stage["factors"]), rid, tgt, outdir / rid,
                                                  response_label=rlab, reference=ref, trend=trend))
        return written
    # the fits' package (statsmodels, about a second of imports) only where a figure fits: a
    # steepest-ascent path's figure draws its runs (and their trend) without it
    from soilcal import rsm

    data = analysis_data(stage, table)
    syms = list(stage["factors"])
    labels = _labels(stage, parameters or {})
    rlabels = {r["id"]: f"{r['name']} ({r['unit']})" for r in stage["responses"]}
    same = (reference_stage is not None and ref_table is not None
            and {s: f["parameter"] for s, f in reference_stage["factors"].items()}
            == {s: f["parameter"] for s, f in stage["factors"].items()})
    for sf in fit_stage(stage, table):
        rid = sf.response
        rlab = rlabels[rid]
        if kind == "pareto":
            eff = rsm.screening_effects(data.dropna(subset=[rid]), syms, rid, dummies=stage.get("dummies"))
            ref = _reference_effects(reference_stage, ref_table, rid, syms) if same else None
            written += list(plots.pareto_effects(eff, outdir / rid, response_label=rlab, reference=ref))
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
    from soilcal.chain.stage import fit_stage

    return {sf.response: (sf.reduced if which == "reduced" else sf.full) for sf in fit_stage(stage, table)}


def write_errata(soil: dict, published_dir, stage_dirs: dict[str, str], out) -> pd.DataFrame:
    """Collect the stage outputs of one soil and write its errata table."""
    from soilcal.chain import errata as errata_mod
    from soilcal.config.tables import read_table

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
    write_csv(df, out)
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


def restart_dir(output) -> Path:
    """Where a DEM job keeps the restart files of its runs (:mod:`soilcal.dem.restart`):
    ``restart/`` and the path of its output below ``results/`` without the suffix
    (``results/a/dem/bbd/runs/3.csv`` -> ``restart/a/dem/bbd/runs/3``); an output outside
    ``results/`` keeps its whole relative path.  Derived from the output, so that it is no
    rule parameter whose change would make Snakemake rerun the jobs."""
    p = Path(output).with_suffix("")
    parts = p.parts[1:] if p.is_absolute() else p.parts
    if "results" in parts:
        parts = parts[parts.index("results") + 1:]
    return Path("restart", *parts)
