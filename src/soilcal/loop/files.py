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
  held-out RMS error against its reference, plain and, where the rows weigh differently,
  weighted as the selection compared them, AICc, paired-test p, accepted, why not, which
  surrogate each effect went through and the smallest of its rows' lack-of-fit p),
  ``predictions.csv``, ``loop_summary.csv`` (error before and after on held-out
  measurements beside the noise floor the measured and seed uncertainty alone give and the
  share of the explainable error removed, the RMS errors weighted as the selection weighs the
  rows, the verdict, the chosen effects' surrogates),
  ``detectable.csv`` (the smallest bias and trends the diagnosis finds with 80 % power:
  :func:`soilcal.loop.diagnose.detectable`), ``report.md`` and ``figures/after/``.
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


def read_written(path) -> pd.DataFrame:
    """A table this module wrote (``residuals.csv``, ``diagnosis.csv``) as it was written:
    :func:`soilcal.chain.files.write_csv` writes a missing value as an empty cell, so only an
    empty cell is missing.  pandas' default missing-value words would make a covariate's cell
    ``NA``, ``N/A``, ``null`` or ``None`` (a tool so called, kept by its measured table's map)
    missing, four such tools one level; and a label quantity's column (``q:tool``, ``q:day``,
    ``q:group``) is text, as the measured table writes it (``007`` is no ``7``)."""
    from soilcal.config.quantities import QUANTITIES

    head = pd.read_csv(path, nrows=0).columns
    labels = {c: str for c in head if c.startswith("q:") and c[2:] in QUANTITIES and QUANTITIES[c[2:]] is None}
    return pd.read_csv(path, keep_default_na=False, na_values=[""], dtype=labels)


def condition_runs(conds, files: dict, theta: dict | None = None) -> pd.DataFrame:
    """Run rows of every condition from the job file that simulated it (``files``:
    ``"<measurement>/<row>"`` -> path), tagged with the condition and, for an effect's design
    point, ``t:<parameter>``."""
    frames = []
    cache = {}
    for c in conds:
        path = files.get(f"{c.measurement}/{c.row}")
        if path is None:
            continue
        if path not in cache:
            cache[path] = pd.read_csv(path)
        df = cache[path]
        measures = [r["measure"] for r in c.responses]
        keep = ["measure", "seed", "value", "status"] + ([rs.ERROR_KEY] if rs.ERROR_KEY in df.columns else [])
        sel = df[df["measure"].isin(measures)][keep].copy()
        sel.insert(0, "row", int(c.row))
        sel.insert(0, "measurement", c.measurement)
        for k, v in (theta or {}).items():
            sel[sl.T_PREFIX + k] = float(v)
        frames.append(sel)
    if not frames:
        return pd.DataFrame(columns=["measurement", "row", "measure", "seed", "value", "status"])
    return pd.concat(frames, ignore_index=True)


def diagnose_files(soil_path, resources_root, tool_files: dict, outdir) -> dict:
    """Residuals, diagnosis, ranking, plan and residual figures of a soil (module docstring)."""
    from soilcal.chain.files import write_csv, write_json
    from soilcal.config.measurements import conditions
    from soilcal.plots.loop import residual_figures

    soil = _soil(soil_path, resources_root)
    settings = core.settings_from(soil.data, soil.path)
    conds = conditions(soil)
    res = rs.residual_frame(rs.observations(conds), condition_runs(conds, tool_files))
    qcols = core.quantity_of(conds)
    core.check_fold_by(soil, conds, settings)
    diag = dg.diagnose(res, qcols, settings.alpha)
    reference = core.reference_values(res, settings)
    cands = core.candidates(diag, conds, settings) if len(rs.usable(res)) >= 3 else []
    plan = _plan(soil.name, cands, reference, settings, qcols, core.skipped(conds, settings), res)
    out = Path(outdir)
    write_csv(res, out / "residuals.csv")
    write_csv(diag, out / "diagnosis.csv")
    write_csv(dg.ranking(diag), out / "ranking.csv")
    residual_figures(res, None, out / "figures" / "residuals", title=f"{soil.name}: calibrated model")
    write_json(plan, out / "plan.json")
    return plan


def _plan(soil_name, cands, reference, settings, qcols, skipped: dict | None = None, res=None,
          designs: dict | None = None, narrowed: dict | None = None) -> dict:
    """A round's plan: its candidates and their designs (``designs``: an effect's own, else
    :func:`soilcal.loop.select.theta_design`); ``narrowed``: effect -> why its design was
    extended (:func:`soilcal.loop.core.more_designs`)."""
    fold_by, folds = core.fold_grouping(settings, qcols, res)
    designs = designs or {}
    plan = {"soil": soil_name, "candidates": cands, "skipped": dict(skipped or {}), "reference": reference,
            "design": {nm: designs.get(nm) or sl.theta_design(EFFECTS[nm], settings.effect_bounds(nm),
                                                               settings.design_points)
                       for nm in cands},
            "fold_by": fold_by, "folds": folds, "quantity_columns": qcols,
            "settings": asdict(settings)}
    if narrowed:
        plan["narrowed"] = dict(narrowed)
    return plan


def loop_job(tool_job: dict, cond, effect: str, theta: dict, reference: dict) -> dict:
    """The tool job (:func:`soilcal.chain.verify.tool_point`) that simulates condition ``cond``,
    with ``effect`` switched on at ``theta`` for that condition's quantities and scenario."""
    if "not_run" in tool_job:
        return dict(tool_job)
    specs = []
    for s in tool_job["specs"]:
        p = EFFECTS[effect].apply(dict(s["params"]), cond.quantities or {}, theta, reference, cond.scenario)
        specs.append(dict(s, params=p))
    return dict(tool_job, specs=specs, effect=effect, theta=dict(theta))


def loop_jobs(conds, tool_jobs: dict, tool_keys: dict, plan: dict, results: str) -> tuple[dict, dict]:
    """The DEM jobs of a plan's candidates: ({key: job}, {effect: {point: {"<measurement>/<row>":
    run file}}}).  One job per design point and condition, keyed by what it simulates
    (:func:`soilcal.chain.verify.tool_key`), so conditions whose parameters the effect sets
    alike share one; where the effect leaves a condition's parameters as they are (the
    switched-off point, a condition without the effect's quantity or of a scenario it does
    not act on) the file is the tool run itself (``results/<soil>/dem/tools/<key>.csv``;
    ``results`` is ``results/<soil>``)."""
    from soilcal.chain.verify import tool_key

    jobs, files = {}, {}
    for name in plan["candidates"]:
        files[name] = {}
        for j, theta in enumerate(plan["design"][name]):
            files[name][j] = {}
            for c in conds:
                key = tool_keys[(c.measurement, c.row)]
                lj = loop_job(tool_jobs[key], c, name, theta, plan["reference"])
                lk = tool_key(lj)
                if lk == key:
                    files[name][j][f"{c.measurement}/{c.row}"] = f"{results}/dem/tools/{key}.csv"
                else:
                    jobs[lk] = lj
                    files[name][j][f"{c.measurement}/{c.row}"] = f"{results}/loop/runs/{lk}.csv"
    return jobs, files


def _outcome(soil, outdir, effect_files: dict, plans: list[dict], interval: bool = True):
    """``analyse`` over the candidates of ``plans`` (the first round, and the second where
    there is one); without the chosen effects' interval (its bootstrap) where ``interval``
    is False."""
    from soilcal.config.measurements import conditions

    out = Path(outdir)
    settings = core.settings_from(soil.data, soil.path)
    conds = conditions(soil)
    res = read_written(out / "residuals.csv")
    diag = read_written(out / "diagnosis.csv")
    cands, designs = [], {}
    for plan in plans:  # a later round's design of an effect extends the earlier one's (core.more_designs)
        cands += [c for c in plan["candidates"] if c not in cands]
        designs.update(plan["design"])
    effect_runs = {}
    for nm in cands:
        frames = []
        for j, theta in enumerate(designs[nm]):
            per = effect_files[nm]
            frames.append(condition_runs(conds, per[j] if j in per else per[str(j)], theta))
        effect_runs[nm] = pd.concat(frames, ignore_index=True)
    return core.analyse(soil.name, res, diag, cands, effect_runs, settings, plans[0]["reference"],
                        plans[0]["quantity_columns"], core.skipped(conds, settings), interval=interval), conds, settings


def more_files(soil_path, resources_root, outdir, effect_files: dict, out_plan) -> dict:
    """``plan_more.json``: the second round's candidates (:func:`soilcal.loop.core.more_candidates`)
    from the first round's runs, with their designs (none: an empty list)."""
    from soilcal.chain.files import write_json

    soil = _soil(soil_path, resources_root)
    plan = json.loads((Path(outdir) / "plan.json").read_text())
    # the first round's interval is not needed to find the second round's candidates
    outcome, conds, settings = _outcome(soil, outdir, effect_files, [plan], interval=False)
    more = core.more_candidates(outcome, conds, settings) if plan["candidates"] else []
    designs = core.more_designs(outcome, settings) if more else {}
    plan_more = _plan(soil.name, more, plan["reference"], settings, plan["quantity_columns"],
                      res=read_written(Path(outdir) / "residuals.csv"), designs=designs,
                      narrowed={nm: outcome.narrowed[nm].text() for nm in designs if nm in more})
    write_json(plan_more, out_plan)
    return plan_more


def select_files(soil_path, resources_root, outdir, effect_files: dict) -> core.Outcome:
    """Selection, predictions, summary, report and figures from the diagnosis outputs in
    ``outdir`` (``plan.json``, ``plan_more.json``) and the runs: ``effect_files``: effect ->
    point -> {"<measurement>/<row>": run file} (the calibrated runs are in ``residuals.csv``)."""
    from soilcal.chain.files import write_csv
    from soilcal.plots.loop import residual_figures

    out = Path(outdir)
    soil = _soil(soil_path, resources_root)
    plans = [json.loads((out / "plan.json").read_text())]
    if (out / "plan_more.json").is_file():
        plans.append(json.loads((out / "plan_more.json").read_text()))
    outcome, _, _ = _outcome(soil, outdir, effect_files, plans)
    write_csv(outcome.selection, out / "selection.csv")
    write_csv(outcome.predictions, out / "predictions.csv")
    write_csv(outcome.summary, out / "loop_summary.csv")
    write_csv(outcome.detectable, out / "detectable.csv")
    residual_figures(outcome.residuals, outcome.predictions if outcome.chosen else None, out / "figures" / "after",
                     title=f"{soil.name}: " + (" + ".join(outcome.chosen) if outcome.chosen else "no effect chosen"))
    write_text(out / "report.md", report(soil.name, outcome, plans))
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


def _detectable_lines(det: pd.DataFrame | None) -> list[str]:
    """The report's section on what the diagnosis could have found (``detectable.csv``)."""
    if det is None or len(det) == 0:
        return []
    d = det.assign(structure=[("mean bias" if t == "bias" else f"trend over {c} {lo:.4g} to {hi:.4g}")
                              for t, c, lo, hi in zip(det["test"], det["covariate"], det["low"], det["high"])])
    r = det.iloc[0]
    return ["## What these data can detect", "",
            f"The smallest structure each test finds with probability {r['power']:.2g}, given the residual's "
            f"own scatter, at alpha / tests ({r['tests']} tests: Holm's strictest step); a trend as the change "
            "of the relative residual across the covariate's measured range (`detectable.csv`, "
            "`soilcal.loop.diagnose.detectable`).  Beside it, the median standard errors over every row of every "
            "quantity, in % of the row's scale (not those of a test's combined value, which weights its "
            f"quantities by their noise): of the simulated mean over the seeds {r['seed_se_percent']:.3g} %, "
            "of the measured value "
            + ("unknown (no SD measured)" if not np.isfinite(r["measured_se_percent"])
               else f"{r['measured_se_percent']:.3g} %")
            + ".  Where the scatter is about their combination, more seeds or repeats (whichever dominates) shrink "
            "what goes unseen as the square root of their number; where it is well above, the rows scatter for a "
            "reason neither carries.", "",
            _table(d, ["structure", "n", "scatter_percent", "detectable_percent"],
                   {"scatter_percent": "{:.3g}", "detectable_percent": "{:.3g}"}), ""]


def _constant_lines(res: pd.DataFrame | None) -> list[str]:
    """The report's sentence on the covariate columns with one value over the usable rows:
    they carry no information and are not tested."""
    if res is None or len(res) == 0:
        return []
    u = rs.usable(res)
    const = [(c[4:], u[c].dropna().iloc[0]) for c in u.columns
             if c.startswith("cov:") and u[c].notna().any() and u[c].dropna().astype(str).nunique() == 1]
    if not len(u) or not const:
        return []
    return ["Not tested, one value on every usable row (no information on the residual): "
            + ", ".join(f"{c} ({v})" for c, v in const) + ".", ""]


def _nuisance_lines(s) -> list[str]:
    """The report's section on a free uniform scale of the model fitted beside (or instead of)
    the effects (``loop_summary.csv``: ``nuisance``, ``nuisance_ci95``, ``nuisance_method``)."""
    value = json.loads(s.get("nuisance") or "{}") if isinstance(s.get("nuisance"), str) else {}
    if core.SCALE_KEY not in value:
        return []
    lo, hi = json.loads(s.get("nuisance_ci95") or "{}").get(core.SCALE_KEY, (np.nan, np.nan))
    v = float(value[core.SCALE_KEY])
    return ["## Uniform scale of the model", "",
            "| parameter | value | 95 % interval | meaning |", "|---|---|---|---|",
            f"| uniform_scale.s | {v:.4g} | {lo:.4g} to {hi:.4g} | the model's values times (1 + s): "
            f"{abs(100 * v):.1f} % {'above' if v > 0 else 'below'} throughout |", "",
            f"How: {s['nuisance_method']}.", ""]


def _floor_lines(s, o: core.Outcome) -> list[str]:
    """The report's noise floor (``loop_summary.csv``: ``rmse_floor_percent``,
    ``explained_percent``; the outcome's ``floor_note`` and ``floor_interval``): its row of the
    error table and what it means."""
    floor, before, after = (float(s[k]) for k in ("rmse_floor_percent", "rmse_before_percent", "rmse_after_percent"))
    if not np.isfinite(floor):
        return ["| the measured and seed uncertainty alone | not known | |", "",
                "The error the measured and seed uncertainty alone give (what a model without misfit would show on "
                f"these rows) is not known: {o.floor_note or 'no uncertainty is given'}.", ""]
    lo, hi, dof = o.floor_interval
    if np.isfinite(lo) and np.isfinite(dof):
        band = (f" (95 % interval {lo:.2f}-{hi:.2f} %: the SDs it comes from are estimates, on {dof:.0f} degrees of "
                "freedom)")
    elif np.isfinite(lo):
        band = " (exact: every SD it comes from is given as known)"
    else:
        band = (" (its 95 % interval is not known: an SD it comes from was estimated as 0 from its repeats or seeds, "
                "values alike, which says nothing of how large the true scatter may be)")
    text = (f"The error the measured and seed uncertainty alone give is {floor:.2f} %{band}: the RMS relative error a "
            "model without any misfit would show on these rows, sqrt(mean((sd_m^2 / n_m + sd_s^2 / n_s) / scale^2)) "
            "of each row's measured SD over its repeats and seed SD over its seeds (residuals.csv)"
            + (f"; {o.floor_note}" if o.floor_note else "") + ".  No effect can bring the held-out error below it, "
            "except by chance.")
    explained = float(s["explained_percent"])
    if o.chosen and np.isfinite(explained):
        text += (f"  The chosen effects removed {explained:.0f} % of the explainable error, "
                 f"(before^2 - after^2) / (before^2 - floor^2) = ({before:.2f}^2 - {after:.2f}^2) / "
                 f"({before:.2f}^2 - {floor:.2f}^2).")
    elif o.chosen:
        text += ("  The error before is not above the floor's 95 % interval: the explainable part is not told apart "
                 "from the floor's own uncertainty, and the share of it removed is not defined.")
    else:
        # the floor's interval covers the SDs' uncertainty only, not the scatter of an RMS error
        # over a few rows about it: no comparison of the two is a test, and none is made
        text += (f"  No effect was chosen.  Beside the floor the error before ({before:.2f} %) tests nothing: the "
                 "floor's interval covers only the uncertainty of the SDs, not the scatter of an RMS error over these "
                 "rows; whether the residual lies within the uncertainties is the diagnosis's verdict above.")
    return [f"| the measured and seed uncertainty alone | {floor:.2f} | |", "", text, ""]


def _weighted_lines(s) -> list[str]:
    """The report's weighted held-out RMS errors (``loop_summary.csv``:
    ``weighted_rmse_before_percent``, ``weighted_rmse_after_percent``), the errors the selection
    compares where the rows weigh differently; nothing where every row weighs alike."""
    before, after = (float(s.get(k, np.nan)) for k in ("weighted_rmse_before_percent", "weighted_rmse_after_percent"))
    if not np.isfinite(before):
        return []
    return [f"Weighted by the inverse variance of each row's relative residual (its measured and seed variance over "
            f"its scale squared, the relative SDs pooled per measured quantity), as the selection fits and compares "
            f"them, the RMS error is {before:.2f} % for the calibrated model and {after:.2f} % with the chosen effects "
            "(each row predicted without its group; the table above weighs every row alike).", ""]


def report(soil: str, o: core.Outcome, plans: list) -> str:
    """``report.md``: verdict, error before and after, chosen effects, diagnosis, every
    candidate, settings."""
    plan = plans[0]
    s = o.summary.iloc[0]
    lines = [f"# Measured-data loop: {soil}", "", f"**Verdict:** {o.verdict}", "",
             "## Error on held-out measurements", "",
             "Relative error (measured - simulated) / |measured| over the usable rows (over the quantity's RMS "
             "where residuals.csv's note says so); after = each row "
             "predicted with the effect parameters fitted without its group.", "",
             f"Held-out groups: {o.folds or plan.get('folds') or 'one fold per measured condition'}.", "",
             "| | RMS error, % | largest error, % |", "|---|---|---|",
             f"| calibrated model | {s['rmse_before_percent']:.2f} | {s['max_before_percent']:.2f} |",
             f"| with the chosen effects | {s['rmse_after_percent']:.2f} | {s['max_after_percent']:.2f} |",
             *_floor_lines(s, o), *_weighted_lines(s)]
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
        lines += ["", f"Interval: {s['ci95_method']}.", ""]
    lines += _nuisance_lines(s)
    lines += ["## Diagnosis of the calibrated model's residual", "",
              _table(o.diagnosis, ["test", "covariate", "quantity", "n", "estimate", "statistic", "p", "p_adjusted", "r2",
                                   "significant"]) if len(o.diagnosis) else "(no test: too few usable rows)", "",
              *_constant_lines(o.residuals),
              *_detectable_lines(o.detectable),
              "## Candidates", ""]
    if len(o.selection):
        # the weighted held-out RMS errors the selection compared, where the rows weigh differently
        weighted = (["weighted_heldout_rmse_percent", "reference_weighted_heldout_rmse_percent"]
                    if "weighted_heldout_rmse_percent" in o.selection
                    and o.selection["weighted_heldout_rmse_percent"].notna().any() else [])
        lines.append(_table(o.selection, ["step", "effects", "parameters", "heldout_rmse_percent",
                                          "reference_heldout_rmse_percent", *weighted, "aicc", "reference_aicc",
                                          "p_paired", "accepted", "reason"]))
    else:
        lines.append("No candidate effect: " + ("none of the library acts through the significant structure."
                                                 if len(o.diagnosis) and o.diagnosis["significant"].any()
                                                 else "the residual shows no significant structure."))
    for name, why in (o.skipped or {}).items():
        lines += ["", f"{name}: {why}."]
    for name, rows in (o.filled or {}).items():
        lines += ["", f"{name}: a run failed at some design point for {len(rows)} row{'s' if len(rows) > 1 else ''} "
                  f"({'; '.join(rows)}); each was filled from the row's other design points "
                  "(`soilcal.loop.select._fill_failed`)."]
    for name, nar in (o.narrowed or {}).items():
        lines += ["", f"{nar.text()} (`soilcal.loop.select.narrowing`): a run that cannot be measured there says "
                  "the measured values rule those levels out, not what the response would be."]
    extended = plans[1].get("narrowed", {}) if len(plans) > 1 else {}
    second = [c for c in plans[1]["candidates"] if c not in extended] if len(plans) > 1 else []
    lines += ["", "Candidates of the first round: " + (", ".join(plan["candidates"]) or "none")
              + "; of the second (matched by the residual the first round's model left): "
              + (", ".join(second) or "none") + "."]
    for name, why in extended.items():
        lines += ["", f"{name}: its design extended in the second round, between the levels that measured and those "
                  f"that did not (first round: {why})."]
    lines += ["", "## Settings", "", f"- reference values (where the calibrated parameters hold): "
              f"{json.dumps(plan.get('reference', {}))}", f"- settings: {json.dumps(plan.get('settings', {}))}",
              "", "Figures: `figures/residuals/` (calibrated model), `figures/after/` (with the chosen effects).", ""]
    return "\n".join(lines)
