"""Response sources of the calibration chain: the printed table, or soilcal's DEM runs.

Every stage goes through one chain (:mod:`soilcal.chain.files`: design -> responses ->
regression/ANOVA -> optimisation -> figures).  The only difference between the sources is
where the stage's response table comes from:

* **published**: the paper's printed table (``resources/published/<soil>/<table>``), as
  printed (:func:`published_responses`);
* **dem**: one DEM job per design point (:func:`point_spec` fixes everything the job
  simulates, :func:`run_point` runs it and writes ``runs/<run>.csv``), gathered by
  :func:`gather_runs` into a table with the printed table's layout - ``run`` (``step`` on a
  steepest-ascent path), the actual factor levels, one column per response - plus the seed
  scatter (``<response>_sd``, ``<response>_n``) and each point's ``status`` and ``error``.

A point's DEM parameters come from the soil config as for any scenario run
(:func:`soilcal.dem.scenarios.base.stage_params`): the stage's fixed values and the point's
factor levels over the ``simulation.params`` and the printed properties.  Every point draws
its own packing: point k of a stage (k = 0, 1, ...) runs the seeds ``seed + replicates * k``
onwards (:func:`point_seeds`).  Common random numbers (one packing draw for every point)
would make the differences between points sharper but tie the whole response surface to
that one draw: its level would be off by that draw's own deviation from the seed mean (a
cohesive quick heap's seed scatter is degrees), and the calibrated set would meet the target
for that draw only; with independent draws the regression averages the seed scatter over
all points, the residual holds it at every point alike, and the lack-of-fit test compares
like with like (the centre points' pure error is the same seed scatter).  A point whose run blows up or cannot be measured (a
heap too small for the estimator) is written with ``status = failed`` and the reason; the
regression then refuses to fit when too few points are left and names them.
"""

from __future__ import annotations

import copy
import subprocess
import time
from pathlib import Path

import numpy as np
import pandas as pd

from soilcal.errors import InputError, SimulationError

#: the columns of a DEM job's rows: what was simulated and what it gave, nothing of how long it
#: took or on how many threads (the job's log and benchmark file say that), so that two runs
#: of the same inputs write byte-identical tables
RUN_COLUMNS = ["soil", "stage", "run", "response", "scenario", "setup", "measure", "preset", "seed",
               "replicates", "seeds", "value", "sd", "n", "status", "error", "notes", "particles",
               "steps", "commit"]


def published_responses(table_path, out) -> Path:
    """The printed table is the published source's response table, byte for byte (copied
    whole or not at all)."""
    from soilcal.atomic import copy_file

    return copy_file(table_path, out)


# --------------------------------------------------------------------------- DEM points


def soil_with_stage(soil, stage: dict):
    """A copy of a loaded soil whose stage ``stage['id']`` is replaced by ``stage`` (the
    stage the DEM source derived), so the scenario helpers read its factors and fixed values."""
    from soilcal.config.load import Soil

    data = copy.deepcopy(soil.data)
    data["stages"] = [stage if s["id"] == stage["id"] else s for s in data["stages"]]
    return Soil(path=soil.path, data=data, resources_root=soil.resources_root)


def design_points(stage: dict, design: pd.DataFrame) -> list[tuple[int, dict]]:
    """``(run, {factor: actual level})`` of every design point (``step`` numbers a path)."""
    syms = list(stage["factors"])
    if stage["kind"] == "steepest_ascent":
        return [(int(r["step"]), {s: float(r[s]) for s in syms}) for _, r in design.iterrows()]
    return [(int(r["run"]), {s: float(r[f"{s}_actual"]) for s in syms}) for _, r in design.iterrows()]


def point_seeds(points: list[tuple[int, dict]], seed: int, replicates: int = 1) -> dict[int, int]:
    """First seed of each point: the soil's ``seed`` plus ``replicates`` times the point's
    position in the design, so that no two points (and no two replicates) share a packing
    draw (module docstring)."""
    return {run: int(seed) + int(replicates) * i for i, (run, _) in enumerate(points)}


def response_specs(soil, response_ids) -> dict[str, dict]:
    """Scenario, setup, measure and preset of each response (``simulation.responses``)."""
    from soilcal.dem.scenarios.design import spec

    out = {}
    for rid in response_ids:
        s = spec(soil, rid)
        out[rid] = {"scenario": s.scenario, "setup": s.setup, "measure": s.measure, "preset": s.preset}
    return out


def design_replicates(soil_data: dict, response: str | None = None) -> int:
    """Seeds per design point: the soil's ``simulation.replicates``, 1 where it gives none; for
    a ``response`` with its own ``simulation.responses.<id>.replicates`` (a cheap, noisy
    response, such as a small heap, averaged over more seeds than a costly one run beside it),
    that count."""
    sim = soil_data.get("simulation") or {}
    own = ((sim.get("responses") or {}).get(response) or {}).get("replicates") if response else None
    return int(own if own is not None else sim.get("replicates", 1))


def seed_stride(soil_data: dict) -> int:
    """Seeds between two design points' first seeds (:func:`point_seeds`): the most seeds any
    response of the soil runs per point, so that no two points share a packing draw."""
    sim = soil_data.get("simulation") or {}
    return max([design_replicates(soil_data)] + [design_replicates(soil_data, r) for r in sim.get("responses") or {}])


def point_spec(soil, stage: dict, levels: dict, run: int, seed: int, replicates: int | None = None,
               extra_params: dict | None = None, responses=None) -> dict:
    """Everything one DEM job simulates: the point's levels, its DEM parameters (SI), the
    scenario of each response, the seed and the replicate count.  Plain data (the
    workflow passes it as the job's params, so a config edit re-runs exactly the points it
    changes)."""
    from soilcal.dem.scenarios.base import stage_params

    sim = soil.data.get("simulation") or {}
    eff = soil_with_stage(soil, stage)
    params = dict(sim.get("params") or {})
    dem = stage_params(eff, stage["id"], levels, params=params, params_field="simulation.params")
    if extra_params:
        dem = dem.replace(**extra_params)
    rids = responses if responses is not None else [r["id"] for r in stage["responses"]]
    reps = int(replicates or design_replicates(soil.data))
    specs = response_specs(soil, rids)
    if replicates is None:
        # a response's own seed count where the soil gives one (written only where it differs,
        # so that the jobs of a soil without one keep their params)
        for rid, rs in specs.items():
            own = design_replicates(soil.data, rid)
            if own != reps:
                rs["replicates"] = own
    return {"soil": soil.name, "stage": stage["id"], "run": int(run),
            "levels": {k: float(v) for k, v in levels.items()},
            "seed": int(seed), "replicates": reps, "params": dem.as_dict(), "responses": specs}


def commit() -> str:
    """The git commit of the soilcal sources (``unknown`` outside a git checkout; ``+dirty``
    when the package sources differ from it)."""
    src = Path(__file__).resolve().parents[1]
    try:
        head = subprocess.run(["git", "-C", str(src), "rev-parse", "--short=12", "HEAD"], capture_output=True,
                              text=True, timeout=10)
        if head.returncode != 0:
            return "unknown"
        dirty = subprocess.run(["git", "-C", str(src), "status", "--porcelain", "--", "."], capture_output=True,
                               text=True, timeout=10)
        return head.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def replicates_of(spec: dict, rid: str) -> int:
    """Seeds a point spec runs for response ``rid``: its own ``replicates`` where
    :func:`point_spec` gave it one, else the spec's."""
    return int(spec["responses"][rid].get("replicates", spec["replicates"]))


def simulate(spec: dict, threads: int | None = None, rev: str | None = None,
             restart_dir=None) -> pd.DataFrame:
    """Run every response of a point spec; one row per response (:data:`RUN_COLUMNS`, then
    ``f:<factor>`` levels and ``p:<parameter>`` DEM parameters).  Responses measured by the same
    scenario and setup with the same seed count (:func:`replicates_of`; a plate's horizontal
    and vertical force) share one run per seed.
    ``restart_dir``: where the runs keep their restart files (one folder per scenario and
    setup; :func:`soilcal.dem.scenarios.base.run_replicates`), so that a killed job resumes."""
    from pathlib import Path

    import json

    from soilcal.dem.scenarios import get, setup_for_measures
    from soilcal.dem.scenarios.base import DemParams, run_replicates, threads_used

    nthreads = threads_used(threads)
    # the spec's values were checked at start-up or derived from checked ones (a design level
    # beyond a factor range, a loop effect switched on): only their physical range holds here
    params = DemParams.from_mapping(spec["params"], "<point spec>", plausible=False)
    rev = rev or commit()
    groups: dict[str, list[str]] = {}
    for rid, rs in spec["responses"].items():
        key = json.dumps([rs["scenario"], rs["setup"], rs["preset"], replicates_of(spec, rid)], sort_keys=True,
                         default=str)
        groups.setdefault(key, []).append(rid)
    rows = []
    for rids in groups.values():
        rs = spec["responses"][rids[0]]
        k = replicates_of(spec, rids[0])
        seeds = list(range(int(spec["seed"]), int(spec["seed"]) + k))
        base = {"soil": spec["soil"], "stage": spec["stage"], "run": spec["run"], "scenario": rs["scenario"],
                "setup": rs["setup"]["name"], "preset": rs["preset"], "seed": spec["seed"], "replicates": k,
                "seeds": " ".join(map(str, seeds)), "commit": rev}
        t0 = time.perf_counter()
        try:
            rdir = (None if restart_dir is None else
                    Path(restart_dir) / f"{rs['scenario']}-{rs['setup']['name']}-{rs['preset']}")
            mod = get(rs["scenario"])
            setup = setup_for_measures(mod, rs["setup"], [spec["responses"][rid]["measure"] for rid in rids])
            res = run_replicates(mod, setup, params, preset=rs["preset"],
                                 seed=int(spec["seed"]), replicates=k, threads=None,
                                 source=f"{spec['soil']}/{spec['stage']}/run {spec['run']}",
                                 restart_dir=rdir)
        except (SimulationError, InputError, FloatingPointError) as exc:
            err = f"{type(exc).__name__}: {exc}".replace("\n", " ")[:500]
            for rid in rids:
                rows.append(base | {"response": rid, "measure": spec["responses"][rid]["measure"], "value": np.nan,
                                    "sd": np.nan, "n": 0, "status": "failed", "error": err})
            print(f"{rs['scenario']} {rs['setup']['name']} ({rs['preset']}): failed after "
                  f"{time.perf_counter() - t0:.2f} s on {nthreads} thread(s): {err}")
            continue
        print(f"{rs['scenario']} {rs['setup']['name']} ({rs['preset']}): {res.n_particles} particles, "
              f"{res.steps} steps, {res.wall_s:.2f} s on {nthreads} thread(s)")
        notes = str(res.responses.get("measure_errors", "") or "").replace("\n", " ")[:500]
        for rid in rids:
            measure = spec["responses"][rid]["measure"]
            per = [r.get(measure) for r in res.per_run] if res.per_run else [res.responses.get(measure)]
            vals = np.array([np.nan if v is None else float(v) for v in per], float)
            ok = np.isfinite(vals)
            row = base | {"response": rid, "measure": measure,
                          "value": float(np.mean(vals[ok])) if ok.any() else np.nan,
                          "sd": float(np.std(vals[ok], ddof=1)) if ok.sum() > 1 else np.nan,
                          "n": int(ok.sum()), "particles": res.n_particles, "steps": res.steps,
                          "notes": notes}
            if ok.any():
                row.update(status="ok", error="")
            else:
                row.update(status="failed", error=f"{measure} not measured: {notes or 'NaN'}")
            rows.append(row)
    df = pd.DataFrame(rows)
    for c in RUN_COLUMNS:
        if c not in df.columns:
            df[c] = np.nan if c not in ("error", "notes") else ""
    df = df[RUN_COLUMNS]
    for key, v in spec["levels"].items():
        df[f"f:{key}"] = v
    for key, v in spec["params"].items():
        df[f"p:{key}"] = v
    return df


def run_point(spec: dict, out, threads: int | None = None, restart_dir=None) -> pd.DataFrame:
    """:func:`simulate` a point spec and write its rows atomically to ``out``."""
    from soilcal.chain.files import write_csv

    df = simulate(spec, threads=threads, restart_dir=restart_dir)
    write_csv(df, out)
    return df


# --------------------------------------------------------------------------- gathering


def gather_runs(stage: dict, design: pd.DataFrame, runs: dict[int, pd.DataFrame]) -> pd.DataFrame:
    """The DEM response table of a stage (module docstring) from its points' run rows."""
    syms = list(stage["factors"])
    key = "step" if stage["kind"] == "steepest_ascent" else "run"
    rids = [r["id"] for r in stage["responses"]]
    rows = []
    for run, levels in design_points(stage, design):
        if run not in runs:
            raise InputError(f"{stage['id']}/runs", f"run {run}", "a run file for every design point",
                             "missing")
        df = runs[run]
        row = {key: run, **levels}
        status, errors, seeds = [], [], []
        for rid in rids:
            sel = df[df["response"] == rid]
            if sel.empty:
                raise InputError(f"{stage['id']}/runs/{run}.csv", "response", f"a row for {rid}", "none")
            r = sel.iloc[0]
            ok = str(r["status"]) == "ok"
            row[rid] = float(r["value"]) if ok else np.nan
            row[f"{rid}_sd"] = float(r["sd"]) if ok and pd.notna(r["sd"]) else np.nan
            row[f"{rid}_n"] = int(r["n"]) if ok else 0
            status.append("ok" if ok else "failed")
            if not ok:
                errors.append(f"{rid}: {r['error']}")
            seeds.append(int(r["seed"]))
        row["seed"] = seeds[0]
        row["status"] = "ok" if all(s == "ok" for s in status) else "failed"
        row["error"] = "; ".join(errors)
        rows.append(row)
    cols = [key, *syms] + [c for rid in rids for c in (rid, f"{rid}_sd", f"{rid}_n")] + \
        ["seed", "status", "error"]
    return pd.DataFrame(rows, columns=cols)


def read_runs(paths) -> dict[int, pd.DataFrame]:
    """Run files ``runs/<run>.csv`` by run number."""
    out = {}
    for p in paths:
        p = Path(p)
        try:
            out[int(p.stem)] = pd.read_csv(p, keep_default_na=True)
        except ValueError:
            raise InputError(p, "<file name>", "runs/<integer>.csv", p.name) from None
    return out


def printed_comparison(stage: dict, printed_stage: dict, responses: pd.DataFrame,
                       printed_table: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """Point-by-point comparison of the DEM responses with the paper's EDEM responses at the
    same printed design points (``simulation.design: printed``): ``points`` (one row per
    point and response: printed, simulated, difference) and ``summary`` (per response: runs,
    Pearson correlation, spread of each, mean bias and RMS difference)."""
    key = "step" if stage["kind"] == "steepest_ascent" else "run"
    cols = {r["id"]: r.get("column", r["id"]) for r in printed_stage["responses"]}
    pts, summ = [], []
    for rid, col in cols.items():
        if rid not in responses.columns or col not in printed_table.columns:
            continue
        p = printed_table[col].to_numpy(float)
        s = responses[rid].to_numpy(float)
        for i in range(len(s)):
            pts.append({"response": rid, key: int(responses[key].iloc[i]), "printed": p[i], "simulated": s[i],
                        "difference": s[i] - p[i]})
        ok = np.isfinite(p) & np.isfinite(s)
        d = s[ok] - p[ok]
        corr = float(np.corrcoef(p[ok], s[ok])[0, 1]) if ok.sum() > 2 and np.std(p[ok]) > 0 and np.std(s[ok]) > 0 \
            else np.nan
        summ.append({"response": rid, "runs": int(ok.sum()), "correlation": corr,
                     "printed_spread": float(np.ptp(p[ok])) if ok.any() else np.nan,
                     "simulated_spread": float(np.ptp(s[ok])) if ok.any() else np.nan,
                     "bias": float(d.mean()) if ok.any() else np.nan,
                     "rms_difference": float(np.sqrt(np.mean(d ** 2))) if ok.any() else np.nan})
    return {"points": pd.DataFrame(pts), "summary": pd.DataFrame(summ)}


__all__ = ["RUN_COLUMNS", "design_points", "design_replicates", "gather_runs", "point_seeds", "point_spec",
           "printed_comparison", "published_responses", "read_runs", "replicates_of", "run_point", "seed_stride",
           "simulate", "soil_with_stage"]
