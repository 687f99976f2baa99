"""Measured-data loop benchmark: is the hidden effect found, its parameter recovered, the error
on held-out measurements lowered, and an effect outside the library left unexplained?

Two engines run the same cases (``soilcal.loop.synthesize`` writes the measured values with
the hidden effect, then ``soilcal.loop.core.run_inprocess`` runs the whole loop without it):

* ``standin``: the analytic Rankine blade force (``soilcal.loop.standin``), 18 conditions,
  several campaign seeds per case (seconds); for ``plastic_contact``, which acts on
  compression tests only, the stand-in's confined compression test (an affine Hertz
  packing) in a campaign of 12 tests (rod stopped at 15-30 % strain; stress at 10 % strain
  and recovered strain);
* ``dem``: soilcal's DEM, the cinnamon soil's bulldozing plates at the ``quick`` preset in a
  soil-bin campaign of ``--n`` conditions (three plates, speeds 0.1-1.0 m/s spaced evenly
  on a log scale, depths 20-40 mm, positions along a 40 m bin, four test days, moisture
  8-20 %), horizontal force,
  three DEM seeds per condition and design point, three levels per effect parameter
  (minutes per case).  A quick plate's horizontal force scatters by about 15 % from seed to
  seed, so the DEM cases' effects are larger than the stand-in's.  ``plastic_contact`` runs
  on the Guangxi cohesive soil's confined compression instead (quick, 1,000 spheres, JKR at
  the soil's simulation parameters): ``--n`` tests loaded to 6-12 % strain and unloaded,
  the recovered strain measured (its seed scatter is about 10 %; the loading stresses
  scatter several times more and are left out).

Cases: every library effect, two effects at once, a periodic disturbance along the bin,
stones, a random offset between test days, and no effect.  Written:
``benchmarks/results/loop.csv`` (one row per engine, case and campaign seed: chosen effects,
parameter error, RMS error before/after beside the noise floor the measured and seed
uncertainty alone give and the share of the explainable error removed (``rmse_floor_percent``,
``explained_percent``, as in loop_summary.csv; empty in rows written before they existed, for
which the page computes them from a DEM campaign's saved tables where those are the row's run,
:func:`floor_of`), false attribution, wall time; earlier rows kept where
not rerun: a stand-in case reruns all its seeds, a DEM case the campaign of ``--seed`` and
``--speeds``),
``loop.md``, and per DEM case and campaign its residuals, diagnosis before and after, every
model tried and the predictions with the chosen effects
(``benchmarks/results/loop_dem/<stem>_*.csv``, :func:`detail_stem`: ``<case>_*.csv``,
``<case>_campaign<seed>_*.csv`` for a campaign other than 0, and a soil-bin campaign's speed
spacing and measures where they are not the default's, ``<case>_uniform_*.csv``,
``<case>_horizontal_vertical_*.csv``; a table the run does not make, such as the diagnosis
after when nothing is chosen, is removed, not left from an earlier run of the campaign).  The
DEM campaign's seed draws its conditions (and so which speeds fall on which test day), the
measured side's noise and nothing else; one campaign is one draw of the data, so a DEM row is
an example, several campaigns a rate.

    python benchmarks/loop.py [--engines standin,dem] [--cases rate,stones] [--seeds 3] [--n 12]
    python benchmarks/loop.py --engines dem --cases moisture_cohesion --design-points 5
    python benchmarks/loop.py --engines dem --seed 1 --out /tmp/loop1    # a second campaign, elsewhere
    python benchmarks/loop.py --engines none --rows-from /tmp/loop1/loop.csv   # its rows merged here

``--design-points``: levels per effect parameter of the DEM cases (default 3, to keep a case
to minutes; the loop's own default, ``loop.design_points``, is 5); a DEM row records it
(column ``design_points``; empty in rows written before it existed).

``--speeds``: how the DEM campaign draws its tool speeds in 0.1-1.0 m/s: ``log`` (default)
uniform in ln v, so that every e-fold of speed holds as many conditions (rate_friction acts
per e-fold of speed, ``soilcal.loop.effects``; four in ten conditions fall below 0.25 m/s,
where the quick plate's force answers a change of friction most, ``loop.md``), or
``uniform`` in v (one in six below 0.25 m/s), the campaigns of the rows written before the
option existed (column ``speeds``, empty there).  Both map the same random draw, so the
other covariates of a campaign are the same under either.  A campaign of one spacing does not
replace the other's row, and the summary counts them apart (the case named with its spacing
where a case has rows of both); a uniform-speed campaign's detail tables carry the spacing in
their names (``rate+depth_uniform_*.csv``, :func:`speeds_tag`), so that the log-speed
campaign of the case keeps its own.

``--responses``: the plate measures the DEM soil-bin campaign records, of
``horizontal_force_N`` (the default, alone), ``vertical_force_N`` and ``resultant_angle_deg``
(:data:`CAMPAIGN_RESPONSES`); the runs are the same (one run per seed gives every measure of a
plate), the conditions too.  A DEM row records its campaign's measures (column ``responses``,
``+``-joined; empty in rows written before it existed, which measured the horizontal force);
a campaign of other measures does not replace the default campaign's row, its detail tables
carry the measures in their names (``rate_friction_horizontal_vertical_*.csv``), and the
summary counts it apart.  The horizontal force alone is the default because at the campaign's
line plate (0.4 m/s, 30 mm) it carries rate_friction furthest above its seed scatter: per unit
ln f, 3.6 seed SDs, against 2.1 for the vertical force and 1.8 for the resultant angle, whose
seed deviations follow the horizontal force's (correlation +0.76 and +0.57); an equal-weight
mean of the two measures' relative residuals per test would carry 2.5, the diagnosis's
inverse-variance mean (``soilcal.loop.diagnose.per_test``) 3.4 (``benchmarks/loop_rate/``,
``loop.md``'s notes).  The page's header names the files of ``--rows-from`` and
``--out`` by their names (a ``--rows-from`` file with as many of its directories as tell it from
another of the same name, ``rate/loop.csv``; a file given twice is refused), and the rows
taken from each by engine, case and campaign.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml
from _report import commit, read_rows, write_page, write_rows

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
FIELDS = ["engine", "case", "seed", "hidden", "disturbance", "chosen", "correct", "false_attribution",
          "parameter_error_percent", "rmse_before_percent", "rmse_after_percent", "rmse_floor_percent",
          "error_reduction_percent", "explained_percent", "verdict", "dem_runs", "wall_s", "commit", "design_points",
          "parameters", "ci95", "speeds", "responses"]

STANDIN_CASES = {
    "rate_friction": ({"rate_friction": {"beta": 0.2}}, {}),
    "depth_compaction": ({"depth_compaction": {"g": 0.4}}, {}),
    "tool_adhesion": ({"tool_adhesion": {"gamma_a": 2.5}}, {}),
    "moisture_cohesion": ({"moisture_cohesion": {"c_w": 0.1}}, {}),
    "plastic_contact": ({"plastic_contact": {"lambda_p": 0.4}}, {}),
    "rate+depth": ({"rate_friction": {"beta": 0.2}, "depth_compaction": {"g": 0.4}}, {}),
    "periodic": ({}, {"periodic": {"amplitude": 0.15, "wavelength": 7.0}}),
    "stones": ({}, {"stones": {"fraction": 0.3, "low": 0.1, "high": 0.3}}),
    "day_offset": ({}, {"day_offset": {"sd": 0.15}}),
    "none": ({}, {}),
}
DEM_CASES = {
    "plastic_contact": ({"plastic_contact": {"lambda_p": 0.5}}, {}),
    "rate_friction": ({"rate_friction": {"beta": 0.4}}, {}),
    "depth_compaction": ({"depth_compaction": {"g": 0.6}}, {}),
    "tool_adhesion": ({"tool_adhesion": {"gamma_a": 2.0}}, {}),
    "moisture_cohesion": ({"moisture_cohesion": {"c_w": 0.08}}, {}),
    "rate+depth": ({"rate_friction": {"beta": 0.4}, "depth_compaction": {"g": 0.6}}, {}),
    "periodic": ({}, {"periodic": {"amplitude": 0.2, "wavelength": 7.0}}),
    "stones": ({}, {"stones": {"fraction": 0.3, "low": 0.15, "high": 0.4}}),
    "day_offset": ({}, {"day_offset": {"sd": 0.2}}),
    "none": ({}, {}),
}
#: cases on a compression campaign (the others: the soil-bin campaign), on either engine
COMPRESSION_CASES = ("plastic_contact",)
DEM_REFERENCE = {"tool_speed": 0.4, "working_depth": 0.03, "moisture_content": 14.0}
DEM_SEEDS = 3  # per condition, for the measured values and for every design point


def _rounded(x, digits) -> float | str:
    """``x`` rounded, or "" where it is missing or not finite (an unknown noise floor)."""
    try:
        x = float(x)
    except (TypeError, ValueError):
        return ""
    return round(x, digits) if np.isfinite(x) else ""


def _row(engine, case, seed, hidden, dist, out, wall, runs):
    chosen = sorted(out.chosen)
    errs = []
    for name, theta in hidden.items():
        for k, v in theta.items():
            got = out.theta.get(f"{name}.{k}")
            if got is not None:
                errs.append(abs(got - v) / abs(v) * 100)
    s = out.summary.iloc[0]
    return dict(engine=engine, case=case, seed=seed, hidden=yaml.safe_dump(hidden, default_flow_style=True).strip(),
                disturbance=yaml.safe_dump(dist, default_flow_style=True).strip(), chosen="+".join(chosen),
                correct=chosen == sorted(hidden), false_attribution=bool(set(chosen) - set(hidden)),
                parameter_error_percent=round(max(errs), 1) if errs else "",
                parameters=s["parameters"] if chosen else "", ci95=s["ci95"] if chosen else "",
                rmse_before_percent=round(float(s["rmse_before_percent"]), 2),
                rmse_after_percent=round(float(s["rmse_after_percent"]), 2),
                error_reduction_percent=round(float(s["error_reduction_percent"]), 1)
                if np.isfinite(s["error_reduction_percent"]) else "",
                rmse_floor_percent=_rounded(s.get("rmse_floor_percent"), 2),
                explained_percent=_rounded(s.get("explained_percent"), 1),
                verdict=out.verdict.replace("|", "/"), dem_runs=runs, wall_s=round(wall, 1), commit=commit())


def standin_rows(cases, seeds):
    from soilcal.loop import core, standin as S, synthesize as sy

    ref = {"tool_speed": 1.75, "working_depth": 0.1, "moisture_content": 16.0}
    rows = []
    for case in cases:
        hidden, dist = STANDIN_CASES[case]
        for seed in range(seeds):
            t0 = time.perf_counter()
            if case in COMPRESSION_CASES:
                conds, cref = S.compression_conditions(S.compression_grid(seed, 12)), {}
            else:
                conds, cref = S.conditions(S.grid(seed, 18, moisture=True)), ref
            table = sy.synthesize(conds, S.base_params, S.simulate, hidden, cref, dist, noise=0.02, seed=seed + 10)
            out = core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, S.simulate,
                                     core.Settings(reference=cref))
            rows.append(_row("standin", case, seed, hidden, dist, out, time.perf_counter() - t0, 0))
            print(rows[-1]["case"], rows[-1]["chosen"], rows[-1]["verdict"][:80], flush=True)
    return rows


def _with_campaign(tmp: Path, name: str, lines: list[str], entry: dict):
    """A copy of soil ``name`` under ``tmp`` whose measurements block is one table,
    ``campaign.csv`` (``lines``), declared by ``entry``; returns its conditions."""
    from soilcal.config.load import load_soil
    from soilcal.config.measurements import conditions

    for sub in ("published", "images"):
        src = ROOT / "resources" / sub / name
        if src.is_dir():
            shutil.copytree(src, tmp / "resources" / sub / name, dirs_exist_ok=True)
    d = yaml.safe_load((ROOT / f"config/soils/{name}.yaml").read_text())
    mdir = tmp / "resources/measurements" / name
    mdir.mkdir(parents=True, exist_ok=True)
    (mdir / "campaign.csv").write_text("\n".join(lines) + "\n")
    d["measurements"] = {"campaign": dict(entry, table="campaign.csv")}
    p = tmp / f"{name}.yaml"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    return conditions(load_soil(p, tmp / "resources"))


#: the DEM campaign's speed range (m/s) and how it is spaced (``--speeds``, module docstring)
SPEED_RANGE = (0.1, 1.0)
SPEED_SPACINGS = ("log", "uniform")


def campaign_speed(rng, spacing: str) -> float:
    """One tool speed of the DEM campaign in :data:`SPEED_RANGE`: uniform in ln v (``log``) or
    in v (``uniform``), from one uniform draw of ``rng`` either way."""
    lo, hi = SPEED_RANGE
    if spacing == "log":
        return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
    if spacing == "uniform":
        return float(rng.uniform(lo, hi))
    raise ValueError(f"speed spacing {spacing!r} is not one of {', '.join(SPEED_SPACINGS)}")


#: the plate measures the DEM campaign can record (``--responses``): its table's value and SD
#: columns and the unit; the table always holds the two forces' columns, the angle's only
#: where it is measured (so that a horizontal-force campaign's table is the one it always was)
CAMPAIGN_RESPONSES = {
    "horizontal_force_N": ("horizontal_N", "horizontal_sd_N", "N"),
    "vertical_force_N": ("vertical_N", "vertical_sd_N", "N"),
    "resultant_angle_deg": ("angle_deg", "angle_sd_deg", "deg"),
}
DEFAULT_RESPONSES = ("horizontal_force_N",)


def _campaign(tmp: Path, n: int, seed: int, speeds: str = "log", responses=DEFAULT_RESPONSES):
    """A copy of the cinnamon soil whose measurements block is a soil-bin campaign of the
    bulldozing plates (module docstring; ``speeds``: their spacing, :func:`campaign_speed`;
    ``responses``: the measures of :data:`CAMPAIGN_RESPONSES` the table records); returns its
    conditions.  The measures do not change the conditions (the same random draws)."""
    unknown = [m for m in responses if m not in CAMPAIGN_RESPONSES]
    if unknown or not responses:
        raise ValueError(f"campaign responses {list(responses)!r}: expected one or more of "
                         f"{', '.join(CAMPAIGN_RESPONSES)}")
    angle = "resultant_angle_deg" in responses
    rng = np.random.default_rng(seed)
    plates = ["line", "arc", "parabola"]
    lines = ["directrix,speed_m_s,depth_mm,position_m,day,moisture_pct,horizontal_N,horizontal_sd_N,vertical_N,"
             "vertical_sd_N," + ("angle_deg,angle_sd_deg," if angle else "") + "repeats"]
    for i in range(n):
        lines.append(f"{plates[i % 3]},{campaign_speed(rng, speeds):.3f},{rng.uniform(20, 40):.1f},{rng.uniform(0, 40):.2f},"
                     f"d{i * 4 // n},{rng.uniform(8, 20):.1f},1,,1,," + ("1,," if angle else "") + "3")
    used = [c for m in responses for c in CAMPAIGN_RESPONSES[m][:2]]
    columns = [c for m in CAMPAIGN_RESPONSES if m != "resultant_angle_deg" or angle for c in CAMPAIGN_RESPONSES[m][:2]]
    return _with_campaign(tmp, "cinnamon-soil", lines, {
        "source": "synthetic soil-bin campaign (benchmarks/loop.py)",
        "scenario": "bulldozing", "setup": "plate-line",
        "covariates": {
            "directrix": {"setup": {p: f"plate-{p}" for p in plates}, "quantity": "tool"},
            "speed_m_s": {"set": "speed", "quantity": "tool_speed", "unit": "m/s"},
            "depth_mm": {"set": "depth", "scale": 0.001, "quantity": "working_depth", "unit": "mm"},
            "position_m": {"ignore": True, "quantity": "position", "unit": "m"},
            "day": {"ignore": True, "quantity": "day"},
            "moisture_pct": {"ignore": True, "quantity": "moisture_content", "unit": "%"}},
        "responses": [
            {"measure": m, "value": CAMPAIGN_RESPONSES[m][0], "sd": CAMPAIGN_RESPONSES[m][1], "n": "repeats",
             "unit": CAMPAIGN_RESPONSES[m][2]} for m in responses],
        "ignore_columns": [c for c in columns if c not in used],
        "calibrated": {"stage": "bbd", "case": "stacking_angle"}, "replicates": 2})


def _compression_campaign(tmp: Path, n: int, seed: int):
    """A copy of the Guangxi cohesive soil whose measurements block is a campaign of confined
    compression tests with unloading (module docstring); returns its conditions."""
    rng = np.random.default_rng(seed)
    lines = ["test,max_strain_pct,recovered,recovered_sd,repeats"]
    for i in range(n):
        lines.append(f"t{i + 1},{rng.uniform(6, 12):.2f},1,,3")
    name = "guangxi-cohesive"
    return _with_campaign(tmp, name, lines, {
        "source": "synthetic compression campaign (benchmarks/loop.py)",
        "scenario": "compression", "setup": name, "set": {"unload": True},
        "covariates": {"test": {"ignore": True}, "max_strain_pct": {"set": "max_strain", "scale": 0.01}},
        "responses": [{"measure": "recovered_strain", "value": "recovered", "sd": "recovered_sd", "n": "repeats",
                       "unit": "-"}],
        "calibrated": {"stage": "bbd", "case": "mc10"}, "replicates": 2})


def responses_tag(responses) -> str:
    """The suffix of a DEM campaign's detail tables for its measures: none for the default
    (:data:`DEFAULT_RESPONSES`, the names the tables always had), else ``_`` and the measures'
    short names (``_horizontal_vertical``), so that a campaign measuring more does not overwrite
    the default campaign's tables."""
    if tuple(responses) == DEFAULT_RESPONSES:
        return ""
    return "_" + "_".join(m.split("_")[0] for m in responses)


def speeds_tag(speeds) -> str:
    """The suffix of a DEM campaign's detail tables for its speed spacing (:data:`SPEED_SPACINGS`):
    none for ``log``, the default (the names the log-speed tables always had), and none for a
    campaign without speeds (``""``: a compression campaign); else ``_`` and the spacing
    (``_uniform``), so that the campaigns of the two spacings do not overwrite each other's
    tables."""
    if speeds in ("", "log"):
        return ""
    if speeds not in SPEED_SPACINGS:
        raise ValueError(f"speed spacing {speeds!r} is not one of {', '.join(SPEED_SPACINGS)}")
    return f"_{speeds}"


def detail_stem(case, seed, speeds="log", responses=DEFAULT_RESPONSES) -> str:
    """The name stem of a DEM campaign's detail tables (``loop_dem/<stem>_residuals.csv``), the
    one place the names are built, for :func:`dem_rows` writing them and every reader
    (:func:`detail_tag`, ``loop_rate/per_measure.py``, ``loop_depth/p_floor.py``): the case,
    ``_campaign<seed>`` for a campaign other than 0 (campaign 0 keeps its earlier names), then
    for a soil-bin campaign its speed spacing (:func:`speeds_tag`) and its measures
    (:func:`responses_tag`), each empty where it is the default's; a compression campaign has
    neither.  ``rate+depth``, ``rate+depth_campaign1_uniform``,
    ``rate_friction_campaign2_horizontal_vertical``."""
    stem = case if str(seed) == "0" else f"{case}_campaign{seed}"
    if case not in COMPRESSION_CASES:
        stem += speeds_tag(speeds) + responses_tag(responses)
    return stem


def dem_rows(cases, n, seed, threads, design_points=3, outdir=HERE / "results", speeds="log",
             responses=DEFAULT_RESPONSES):
    from soilcal.loop import core, synthesize as sy
    from soilcal.loop.cli import condition_params, dem_simulator

    rows = []
    counter = {"runs": 0}
    sim = dem_simulator(threads)

    def counted(cond, params, s):
        counter["runs"] += 1
        return sim(cond, params, s)

    base = condition_params({})
    settings = core.Settings(reference=DEM_REFERENCE, design_points=design_points)
    for case in cases:
        if case not in DEM_CASES:
            print(f"dem: no DEM case {case} (stand-in only)", flush=True)
            continue
        hidden, dist = DEM_CASES[case]
        with tempfile.TemporaryDirectory() as tmp:
            conds = (_compression_campaign(Path(tmp), n, seed) if case in COMPRESSION_CASES
                     else _campaign(Path(tmp), n, seed, speeds, responses))
            t0 = time.perf_counter()
            counter["runs"] = 0
            table = sy.synthesize(conds, base, counted, hidden, DEM_REFERENCE, dist, noise=0.02, seed=seed + 10,
                                  seeds=tuple(range(1000, 1000 + DEM_SEEDS)))
            out = core.run_inprocess("dem-campaign", sy.with_measured(conds, table), base, counted, settings,
                                     seeds=tuple(range(DEM_SEEDS)))
            rows.append(dict(_row("dem", case, seed, hidden, dist, out, time.perf_counter() - t0, counter["runs"]),
                             design_points=design_points, speeds="" if case in COMPRESSION_CASES else speeds,
                             responses="" if case in COMPRESSION_CASES else "+".join(responses)))
            detail = Path(outdir) / "loop_dem"
            detail.mkdir(parents=True, exist_ok=True)
            tag = detail_tag(rows[-1])
            for name, df in (("residuals", out.residuals), ("diagnosis", out.diagnosis), ("selection", out.selection),
                             ("diagnosis_after", out.diagnosis_after), ("predictions", out.predictions),
                             ("summary", out.summary)):
                path = detail / f"{tag}_{name}.csv"
                if df is not None:
                    df.to_csv(path, index=False)
                else:  # a table this run does not make: an earlier run's would contradict it
                    path.unlink(missing_ok=True)
            print(rows[-1]["case"], rows[-1]["chosen"], rows[-1]["verdict"][:100], rows[-1]["wall_s"], flush=True)
    return rows


def _speeds_text(r) -> str:
    """The campaign's speed spacing of a DEM row: its ``speeds``; a soil-bin row written before
    the column existed drew them uniformly; a compression campaign and a stand-in row have none."""
    if r["engine"] != "dem":
        return ""
    if r.get("speeds"):
        return r["speeds"]
    return "" if r["case"] in COMPRESSION_CASES else "uniform"


def _responses_text(r) -> str:
    """The measures of a DEM soil-bin row's campaign (``+``-joined): its ``responses``; a row
    written before the column existed measured the horizontal force alone; a compression
    campaign and a stand-in row have none."""
    if r["engine"] != "dem" or r["case"] in COMPRESSION_CASES:
        return ""
    return r.get("responses") or "+".join(DEFAULT_RESPONSES)


def replaced(r, new) -> bool:
    """Whether an earlier row ``r`` is replaced by one of the ``new`` rows: a stand-in case reruns
    all its seeds; a DEM case its campaign drawn with the same speed spacing and measuring the
    same quantities (a campaign of the other spacing, or of other measures, is another
    campaign, kept beside it)."""
    return any(r["engine"] == x["engine"] and r["case"] == x["case"]
               and (r["engine"] != "dem" or (str(r["seed"]) == str(x["seed"])
                                             and _speeds_text(r) == _speeds_text(x)
                                             and _responses_text(r) == _responses_text(x))) for x in new)


def source_labels(paths) -> list[str]:
    """Labels of the ``--rows-from`` files for the page's header: each file's name, with as
    many of its parent directories as tell it from the other files of the same name
    (``rate/loop.csv`` and ``none/loop.csv``, not ``loop.csv`` twice).  A file given twice
    is refused: its rows would be merged twice."""
    parts = [Path(p).resolve().parts for p in paths]
    seen = {}
    for p, a in zip(paths, parts):
        if a in seen:
            raise ValueError(f"--rows-from: {p} is given twice (as {seen[a]} and {p}); each run's rows once")
        seen[a] = p
    out = []
    for i, a in enumerate(parts):
        k = 1
        while k < len(a) and any(b[-k:] == a[-k:] for j, b in enumerate(parts) if j != i):
            k += 1
        out.append(Path(*a[-k:]).as_posix())
    return out


def _command_text(argv) -> str:
    """The command line of a run for the page's header, the files of ``--rows-from`` by
    :func:`source_labels` and ``--out`` by its name only (their directories are the run's own)."""
    args, files = list(argv), []
    for i, a in enumerate(args):  # the --rows-from files, in order, for their labels
        opt, eq, val = a.partition("=")
        if opt == "--rows-from":
            files.append(val if eq else (args[i + 1] if i + 1 < len(args) else ""))
    out, it, labels = [], iter(args), iter(source_labels([f for f in files if f]))
    for a in it:
        opt, eq, val = a.partition("=")
        if opt in ("--rows-from", "--out"):
            if not eq:
                val = next(it, "")
            if not val:
                out.append(opt)
            else:
                out += [opt, next(labels) if opt == "--rows-from" else Path(val).name]
        else:
            out.append(a)
    return " ".join(out)


def _campaign_text(r) -> str:
    """How a DEM soil-bin row's campaign was drawn and what it measured, for the page's header:
    `` (log speeds)``, with its measures where they are not the default's
    (`` (log speeds; measuring horizontal_force_N, vertical_force_N)``); empty for other rows."""
    parts = [f"{_speeds_text(r)} speeds"] if _speeds_text(r) else []
    if _responses_text(r) and _responses_text(r) != "+".join(DEFAULT_RESPONSES):
        parts.append("measuring " + _responses_text(r).replace("+", ", "))
    return f" ({'; '.join(parts)})" if parts else ""


def _merged_text(sources) -> str:
    """What a run took from other runs' tables (``--rows-from``), for the page's header: per
    file (its label, :func:`source_labels`) each row's engine, case and campaign, and a DEM
    soil-bin row's speed spacing and measures (:func:`_campaign_text`); ``sources``: (label,
    rows) pairs."""
    parts = [f"{label}: " + (", ".join(
        f"{r['engine']} {r['case']}" + (f" campaign {r['seed']}" if r["engine"] == "dem" else f" seed {r['seed']}")
        + _campaign_text(r) for r in rows) or "no rows")
        for label, rows in sources]
    return "; rows taken from other runs: " + "; ".join(parts) if parts else ""


def _theta_text(r) -> str:
    """``name = value (low to high)`` of a row's fitted parameters; empty in rows without them."""
    import json

    try:
        theta, ci = json.loads(r.get("parameters") or "{}"), json.loads(r.get("ci95") or "{}")
    except ValueError:
        return ""
    return "; ".join(f"{k} = {v:.3g}" + (f" ({ci[k][0]:.3g} to {ci[k][1]:.3g})" if k in ci else "")
                     for k, v in theta.items())


def detail_tag(r) -> str:
    """The name stem of a DEM row's detail tables (``loop_dem/<stem>_residuals.csv``), as
    :func:`dem_rows` writes them: :func:`detail_stem` of the row's case, campaign, speed spacing
    (:func:`_speeds_text`: a soil-bin row written before the column existed drew its speeds
    uniformly) and measures (:func:`_responses_text`)."""
    resp = _responses_text(r)
    return detail_stem(r["case"], r["seed"], _speeds_text(r), tuple(resp.split("+")) if resp else DEFAULT_RESPONSES)


def floor_of(r, detail: Path) -> tuple:
    """(noise floor, share of the explainable error removed), in %, of a row, "" where unknown:
    the row's own (``rmse_floor_percent``, ``explained_percent``, from
    :func:`soilcal.loop.residuals.noise_floor` and :func:`soilcal.loop.core.explained_percent`);
    for a DEM row written before those columns existed, computed from its campaign's saved
    residual table and held-out predictions (``detail``: ``loop_dem/``, :func:`detail_tag`)
    where they reproduce the row's RMS errors before and after to loop.csv's rounding (0.01 %),
    else "" (the tables are another run's: one rerun since)."""
    def text(x):  # a cell as written: None (a row without the column) and NaN are empty, 0 is 0
        x = "" if x is None else str(x)
        return "" if x == "nan" else x

    own = text(r.get("rmse_floor_percent"))
    if own or r["engine"] != "dem":
        return own, text(r.get("explained_percent"))
    tag = detail_tag(r)
    res_path, pred_path = Path(detail) / f"{tag}_residuals.csv", Path(detail) / f"{tag}_predictions.csv"
    if not res_path.exists():
        return "", ""
    import pandas as pd

    from soilcal.loop import core, residuals as rs

    u = rs.usable(pd.read_csv(res_path))
    before = u["relative_residual"].to_numpy(float)
    after = before
    if pred_path.exists():
        pred = pd.read_csv(pred_path)
        if "heldout_prediction" in pred and len(pred) == len(u):
            after = (u["measured"].to_numpy(float) - pred["heldout_prediction"].to_numpy(float)) / rs.scale_of(u)
    e = core.error_figures(u, before, after)
    b, a = e["rmse_before_percent"], e["rmse_after_percent"]
    if not np.isfinite(b):
        return "", ""
    try:
        same = abs(b - float(r["rmse_before_percent"])) <= 0.005 + 1e-9 and abs(a - float(r["rmse_after_percent"])) \
            <= 0.005 + 1e-9
    except ValueError:
        return "", ""
    if not same:
        return "", ""
    return _rounded(e["rmse_floor_percent"], 2), _rounded(e["explained_percent"], 1)


#: at most this many known values of a case are shown each, not as a median: the median of two
#: campaigns is their mean, which matches neither (0 and 112 would read 56)
FEW = 3


def _median_text(values, n, digits) -> str:
    """The rows' ``values`` that are known: each of them, smallest first, where there are at most
    :data:`FEW`, else their median with their range; with how many of the ``n`` rows they are
    where some are not; empty where none is."""
    v = sorted(float(x) for x in values if str(x) not in ("", "nan"))
    if not v:
        return ""
    if len(v) <= FEW:
        text = ", ".join(f"{x:.{digits}f}" for x in v)
    else:
        text = f"{np.median(v):.{digits}f} ({v[0]:.{digits}f} to {v[-1]:.{digits}f})"
    return text + (f" ({len(v)} of {n})" if len(v) < n else "")


def _summary(rows):
    out = ["| engine | case | campaigns | correct | false attributions | max parameter error, % | "
           "RMS error before -> after, % (median) | noise floor, % | explainable error removed, % | median wall s |", "|---|---|---|---|---|---|---|---|---|---|"]
    keys = list(dict.fromkeys((r["engine"], r["case"], _speeds_text(r), _responses_text(r)) for r in rows))
    for eng, case, speeds, resp in keys:
        g = [r for r in rows if r["engine"] == eng and r["case"] == case and _speeds_text(r) == speeds
             and _responses_text(r) == resp]
        label = []
        if any(k[:2] == (eng, case) and k[2] != speeds for k in keys):  # both spacings: say which
            label.append(f"{speeds or 'no'} speeds")
        if any(k[:2] == (eng, case) and k[3] != resp for k in keys):  # campaigns of other measures: say which
            label.append(f"measuring {resp.replace('+', ', ')}")
        if label:
            case = f"{case} ({'; '.join(label)})"
        pe = [float(r["parameter_error_percent"]) for r in g if str(r["parameter_error_percent"]) not in ("", "nan")]
        b = np.median([float(r["rmse_before_percent"]) for r in g])
        a = np.median([float(r["rmse_after_percent"]) for r in g])
        ok = sum(str(r["correct"]) == "True" for r in g)
        fa = sum(str(r["false_attribution"]) == "True" for r in g)
        floor = _median_text([r.get("rmse_floor_percent", "") for r in g], len(g), 2)
        explained = _median_text([r.get("explained_percent", "") for r in g], len(g), 0)
        worst = f"{max(pe):.1f}" if pe else ""
        out.append(f"| {eng} | {case} | {len(g)} | {ok} | {fa} | {worst} | {b:.2f} -> {a:.2f} | "
                   f"{floor} | {explained} | {np.median([float(r['wall_s']) for r in g]):.1f} |")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--engines", default="standin,dem")
    ap.add_argument("--cases", default=",".join(STANDIN_CASES))
    ap.add_argument("--seeds", type=int, default=5, help="campaign seeds per case (standin)")
    ap.add_argument("--n", type=int, default=18, help="conditions of the DEM campaign")
    ap.add_argument("--seed", type=int, default=0, help="seed of the DEM campaign")
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--design-points", type=int, default=3, help="levels per effect parameter (dem; default 3)")
    ap.add_argument("--speeds", choices=SPEED_SPACINGS, default="log",
                    help="spacing of the DEM campaign's tool speeds in 0.1-1.0 m/s (default log)")
    ap.add_argument("--responses", default=",".join(DEFAULT_RESPONSES),
                    help="plate measures the DEM soil-bin campaign records, comma-separated, of "
                         + ", ".join(CAMPAIGN_RESPONSES) + " (default: the horizontal force alone)")
    ap.add_argument("--out", default=str(HERE / "results"))
    ap.add_argument("--rows-from", action="append", default=[], metavar="CSV",
                    help="also take the rows of another run's loop.csv (a DEM campaign run in a clone)")
    args = ap.parse_args(argv)
    engines = args.engines.split(",")
    for e in engines:
        if e not in ("standin", "dem", "none"):
            ap.error(f"--engines: {e!r} is not one of standin, dem, none")
    cases = args.cases.split(",")
    for c in cases:
        if c not in STANDIN_CASES:
            ap.error(f"--cases: {c!r} is not one of {', '.join(STANDIN_CASES)}")
    responses = tuple(dict.fromkeys(args.responses.split(",")))
    for m in responses:
        if m not in CAMPAIGN_RESPONSES:
            ap.error(f"--responses: {m!r} is not one of {', '.join(CAMPAIGN_RESPONSES)}")
    try:
        labels = source_labels(args.rows_from)
    except ValueError as e:
        ap.error(str(e))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    new = []
    t0 = time.perf_counter()
    if "standin" in engines:
        new += standin_rows(cases, args.seeds)
    if "dem" in engines:
        new += dem_rows(cases, args.n, args.seed, args.threads, args.design_points, out, args.speeds, responses)
    sources = [(label, read_rows(Path(path), FIELDS)) for label, path in zip(labels, args.rows_from)]
    new += [r for _, rows in sources for r in rows]  # rows of a run elsewhere (a clone), each with its own commit

    # earlier rows read only now, so that a run of another engine in the meantime is kept
    old = [r for r in read_rows(out / "loop.csv", FIELDS) if not replaced(r, new)]
    rows = sorted(old + new, key=lambda r: (r["engine"], str(r["seed"]) if r["engine"] == "dem" else ""))
    write_rows(out / "loop.csv", rows, FIELDS)
    # the page's rows: a DEM row written before the noise floor existed gets it from its saved tables
    shown = [dict(r, **dict(zip(("rmse_floor_percent", "explained_percent"), floor_of(r, out / "loop_dem"))))
             for r in rows]
    md = ["# Measured-data loop benchmark", "",
          f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs, Python {platform.python_version()}; "
          f"commit {commit()}, {time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC; "
          f"`python benchmarks/loop.py {_command_text(sys.argv[1:] if argv is None else argv)}` ({time.perf_counter() - t0:.0f} s for the rows "
          f"of this run{_merged_text(sources)}; rows of engines and cases not run are kept from earlier runs, each with its commit)"
          + (f"; the DEM soil-bin campaign of this run measures {', '.join(responses)} (the column `measures` gives each "
             f"DEM row's)" if "dem" in engines else "") + ".", "",
          "A case's measured values come from the engine with the hidden effect (or disturbance) and 2 % noise per "
          "repeat (three repeats); the loop then runs without it.  correct: the chosen effects are exactly the "
          "hidden ones (none for a disturbance outside the library or no effect); false attribution: a library "
          "effect chosen that was not hidden.  Targets: the right effect with its parameter within 25 % and the "
          "held-out RMS error down by 70 %; no false attribution.", "",
          "Noise floor: the RMS relative error a model without any misfit would show on the same rows, "
          "sqrt(mean((sd_m^2 / n_m + sd_s^2 / n_s) / scale^2)) of each row's measured SD over its repeats and seed "
          "SD over its seeds (`soilcal.loop.residuals.noise_floor`, loop_summary.csv's `rmse_floor_percent`): no "
          "effect brings the held-out error below it except by chance.  Explainable error removed: (before^2 - "
          "after^2) / (before^2 - floor^2), empty where the error before is not above the floor's 95 % "
          "interval (`explained_percent`).  Rows written before these columns existed have none in loop.csv; for a DEM row "
          "the page computes them from its campaign's saved residual table and held-out predictions "
          "(`loop_dem/<case>[_campaign<seed>][_uniform]_residuals.csv`, `_predictions.csv`) where those reproduce the "
          "row's errors before and after to 0.01 %, and leaves them empty where they do not (the tables are another "
          "run's) or are missing.  In the summary a case's floors "
          "and explained shares are each campaign's, smallest first, where it has at most three, else their median "
          "(smallest to largest); \"(k of n)\" where only k of its n campaigns have one.  Even an exactly right "
          "effect leaves the held-out error a little above the floor (it includes the error of fitting the effect's "
          "parameter without the held-out rows), so its explained share lies a little below 100.", "",
          *_summary(shown), "", "DEM rows (verdicts in full):", "",
          "| case | campaign | chosen | parameters (95 % interval) | parameter error, % | RMS error before -> after, % "
          "| noise floor, % | explainable error removed, % | levels | speeds | measures | DEM runs | wall s | commit "
          "| verdict |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
          *(f"| {r['case']} | {r['seed']} | {r['chosen']} | {_theta_text(r)} | {r['parameter_error_percent']} | {r['rmse_before_percent']} -> "
            f"{r['rmse_after_percent']} | {r['rmse_floor_percent']} | {r['explained_percent']} | "
            f"{r.get('design_points') or 3} | {_speeds_text(r)} | "
            f"{_responses_text(r).replace('+', ', ')} | {r['dem_runs']} | {r['wall_s']} | "
            f"{r['commit']} | {r['verdict']} |"
            for r in shown if r["engine"] == "dem"),
          "", "Rows: `loop.csv`; per DEM case and campaign: `loop_dem/`.", ""]
    write_page(out / "loop.md", md)
    print("\n".join(_summary(shown)))


if __name__ == "__main__":
    main()
