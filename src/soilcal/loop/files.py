"""File-level steps of the measured-data loop, called by the workflow's adapters
(``workflow/rules/loop.smk``) and by ``soilcal loop``.

Outputs under ``results/<soil>/loop/``:

* ``residuals.csv`` (:mod:`soilcal.loop.residuals`), ``diagnosis.csv`` (every test, Holm
  corrected) and ``ranking.csv`` (covariates by the residual share they explain),
  ``plan.json`` (candidates, their designs, the reference values and the settings, all
  written out), ``figures/residuals/`` (residual against every covariate);
* ``runs/<effect>/<point>/<key>.csv``: one DEM job per candidate, design point and measured
  condition (conditions that run the same simulation share a job, as the tool tests do), with
  the seeds of the calibrated tool runs, which are the switched-off design point;
* ``selection.csv`` (every model tried: step, effects, parameters with 95 % intervals,
  held-out RMS error against its reference, AICc, paired-test p, accepted, why not),
  ``predictions.csv``, ``loop_summary.csv`` (error before and after on held-out
  measurements, the verdict), ``report.md`` and ``figures/after/``.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pandas as pd

from soilcal.atomic import write_text
from soilcal.loop import core
from soilcal.loop import diagnose as dg
from soilcal.loop import residuals as rs
from soilcal.loop import select as sl
from soilcal.loop.effects import EFFECTS


def _soil(soil_path, resources_root):
    from soilcal.config.load import load_soil

    return load_soil(soil_path, resources_root)


def condition_runs(conds, files: dict, run_map: dict, theta: dict | None = None) -> pd.DataFrame:
    """Run rows of every condition (measurement, row) from the job files its key names
    (``run_map``: ``"<measurement>/<row>"`` -> key; ``files``: key -> path), tagged with the
    condition and, for an effect's design point, ``t:<parameter>``."""
    frames = []
    cache = {}
    for c in conds:
        key = run_map.get(f"{c.measurement}/{c.row}")
        if key is None or key not in files:
            continue
        if key not in cache:
            cache[key] = pd.read_csv(files[key])
        df = cache[key]
        measures = [r["measure"] for r in c.responses]
        sel = df[df["measure"].isin(measures)][["measure", "seed", "value", "status"]].copy()
        sel.insert(0, "row", int(c.row))
        sel.insert(0, "measurement", c.measurement)
        for k, v in (theta or {}).items():
            sel[sl.T_PREFIX + k] = float(v)
        frames.append(sel)
    if not frames:
        return pd.DataFrame(columns=["measurement", "row", "measure", "seed", "value", "status"])
    return pd.concat(frames, ignore_index=True)


def diagnose_files(soil_path, resources_root, tool_files: dict, run_map: dict, outdir) -> dict:
    """Residuals, diagnosis, ranking, plan and residual figures of a soil (module docstring)."""
    from soilcal.chain.files import write_csv, write_json
    from soilcal.config.measurements import conditions
    from soilcal.plots.loop import residual_figures

    soil = _soil(soil_path, resources_root)
    settings = core.settings_from(soil.data, soil.path)
    conds = conditions(soil)
    res = rs.residual_frame(rs.observations(conds), condition_runs(conds, tool_files, run_map))
    qcols = core.quantity_of(conds)
    diag = dg.diagnose(res, qcols, settings.alpha)
    reference = core.reference_values(res, settings)
    cands = core.candidates(diag, conds, settings) if len(rs.usable(res)) >= 3 else []
    plan = {"soil": soil.name, "candidates": cands, "reference": reference,
            "design": {nm: sl.theta_design(EFFECTS[nm], settings.effect_bounds(nm), settings.design_points)
                       for nm in cands},
            "null_point": {nm: _null_index(nm, settings) for nm in cands},
            "fold_by": core.default_fold_by(settings, qcols), "quantity_columns": qcols,
            "settings": asdict(settings)}
    out = Path(outdir)
    write_csv(res, out / "residuals.csv")
    write_csv(diag, out / "diagnosis.csv")
    write_csv(dg.ranking(diag), out / "ranking.csv")
    residual_figures(res, None, out / "figures" / "residuals", title=f"{soil.name}: calibrated model")
    write_json(plan, out / "plan.json")
    return plan


def _null_index(name: str, settings: core.Settings) -> int:
    eff = EFFECTS[name]
    design = sl.theta_design(eff, settings.effect_bounds(name), settings.design_points)
    for j, th in enumerate(design):
        if all(float(th[k]) == float(eff.null[k]) for k in eff.theta_names()):
            return j
    return -1


def loop_job(tool_job: dict, conds, effect: str, theta: dict, reference: dict) -> dict:
    """A tool job (:func:`soilcal.chain.verify.tool_point`) with ``effect`` switched on at
    ``theta`` for its conditions' quantities (conditions sharing a job share their covariates)."""
    if "not_run" in tool_job:
        return dict(tool_job)
    quantities = {}
    for c in conds:
        quantities.update(c.quantities or {})
    specs = []
    for s in tool_job["specs"]:
        p = EFFECTS[effect].apply(dict(s["params"]), quantities, theta, reference)
        specs.append(dict(s, params=p))
    return dict(tool_job, specs=specs, effect=effect, theta=dict(theta))


def select_files(soil_path, resources_root, outdir, tool_files: dict, run_map: dict,
                 effect_files: dict) -> core.Outcome:
    """Selection, predictions, summary, report and figures from the diagnosis outputs in
    ``outdir`` and the runs: ``effect_files``: effect -> point -> {key: path} (the switched-
    off point's keys map to the tool runs)."""
    from soilcal.chain.files import write_csv
    from soilcal.config.measurements import conditions
    from soilcal.plots.loop import residual_figures

    out = Path(outdir)
    soil = _soil(soil_path, resources_root)
    plan = json.loads((out / "plan.json").read_text())
    settings = core.settings_from(soil.data, soil.path)
    conds = conditions(soil)
    res = pd.read_csv(out / "residuals.csv")
    diag = pd.read_csv(out / "diagnosis.csv")
    effect_runs = {}
    for nm in plan["candidates"]:
        frames = []
        for j, theta in enumerate(plan["design"][nm]):
            files = effect_files[nm][str(j)] if str(j) in effect_files[nm] else effect_files[nm][j]
            frames.append(condition_runs(conds, files, run_map, theta))
        effect_runs[nm] = pd.concat(frames, ignore_index=True)
    outcome = core.analyse(soil.name, res, diag, plan["candidates"], effect_runs, settings, plan["reference"],
                           plan["quantity_columns"])
    write_csv(outcome.selection, out / "selection.csv")
    write_csv(outcome.predictions, out / "predictions.csv")
    write_csv(outcome.summary, out / "loop_summary.csv")
    residual_figures(res, outcome.predictions if outcome.chosen else None, out / "figures" / "after",
                     title=f"{soil.name}: " + (" + ".join(outcome.chosen) if outcome.chosen else "no effect chosen"))
    write_text(out / "report.md", report(soil.name, outcome, plan))
    return outcome


def _table(df: pd.DataFrame, cols, fmt=None) -> str:
    fmt = fmt or {}
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for r in df[cols].to_dict("records"):
        cells = []
        for c in cols:
            v = r[c]
            if isinstance(v, float):
                cells.append("" if not np.isfinite(v) else (fmt.get(c, "{:.3g}").format(v)))
            else:
                cells.append(str(v).replace("|", "/"))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def report(soil: str, o: core.Outcome, plan: dict) -> str:
    """``report.md``: verdict, error before and after, chosen effects, diagnosis, every
    candidate, settings."""
    s = o.summary.iloc[0]
    lines = [f"# Measured-data loop: {soil}", "", f"**Verdict:** {o.verdict}", "",
             "## Error on held-out measurements", "",
             "Relative error (measured - simulated) / measured over the usable rows; after = each row "
             "predicted with the effect parameters fitted without its group "
             f"(groups: {plan.get('fold_by') or 'measured conditions'}).", "",
             "| | RMS error, % | largest error, % |", "|---|---|---|",
             f"| calibrated model | {s['rmse_before_percent']:.2f} | {s['max_before_percent']:.2f} |",
             f"| with the chosen effects | {s['rmse_after_percent']:.2f} | {s['max_after_percent']:.2f} |", ""]
    if o.chosen:
        ci = json.loads(s["ci95"])
        lines += ["## Chosen effects", "", "| effect | parameter | value | 95 % interval | unit | formula | source |",
                  "|---|---|---|---|---|---|---|"]
        for name in o.chosen:
            eff = EFFECTS[name]
            for k, (unit, _) in eff.params.items():
                key = f"{name}.{k}"
                lo, hi = ci.get(key, (np.nan, np.nan))
                lines.append(f"| {name} | {k} | {o.theta[key]:.4g} | {lo:.4g} to {hi:.4g} | {unit} | "
                             f"{eff.formula} | {eff.source} |")
        lines.append("")
    lines += ["## Diagnosis of the calibrated model's residual", "",
              _table(o.diagnosis, ["test", "covariate", "quantity", "n", "estimate", "statistic", "p", "p_adjusted", "r2",
                                   "significant"]) if len(o.diagnosis) else "(no test: too few usable rows)", "",
              "## Candidates", ""]
    if len(o.selection):
        lines.append(_table(o.selection, ["step", "effects", "parameters", "heldout_rmse_percent",
                                          "reference_heldout_rmse_percent", "aicc", "reference_aicc", "p_paired",
                                          "accepted", "reason"]))
    else:
        lines.append("No candidate effect: " + ("none of the library acts through the significant structure."
                                                 if len(o.diagnosis) and o.diagnosis["significant"].any()
                                                 else "the residual shows no significant structure."))
    lines += ["", "## Settings", "", f"- reference values (where the calibrated parameters hold): "
              f"{json.dumps(plan.get('reference', {}))}", f"- settings: {json.dumps(plan.get('settings', {}))}",
              "", "Figures: `figures/residuals/` (calibrated model), `figures/after/` (with the chosen effects).", ""]
    return "\n".join(lines)
