"""GrainLearning's iterative Bayesian calibration driving soilcal's DEM jobs, capped at the papers'
recipe's run count: the third method of ``benchmarks/results/adaptive.csv``.

For every soil given, and every case the adaptive design runs (the optimised stages of the DEM
source, cases with a target value: :func:`soilcal.chain.adaptive.adaptive_cases`):

* the targets come from a fresh copy of the workflow (``snakemake results/<soil>/dem/targets.csv``:
  the photos measured, or the soil's measurements), the space and the fixed values from the
  soil config exactly as ``design: adaptive`` takes them (:func:`soilcal.chain.adaptive.stage_for`,
  :func:`~soilcal.chain.adaptive.problem_for`); a stage fixed from an earlier one
  (``fixed_from``) takes the set GrainLearning verified for that stage;
* the budget is the recipe's run count of the same soil in ``adaptive.csv`` (run
  ``python benchmarks/adaptive.py --soils <soil> --methods recipe`` first; the recipe's rows
  count every run of the soil's calibration), shared evenly among the soil's cases (two stages
  of the black soil, three layers of the vineyard soil), including the verification seeds:
  ``iterations`` rounds of (budget - verify_seeds) // iterations samples,
  then ``verify_seeds`` seeds at GrainLearning's estimate (the most probable sample of the last
  iteration, ``BayesianCalibration.get_most_prob_params``);
* GrainLearning (``grainlearning`` 2.0.5, its own virtual environment: it pins numpy < 2) runs
  in ``benchmarks/adaptive_gl_driver.py``; each batch of samples it asks for is run here, one
  DEM job per sample and seed (:func:`soilcal.chain.sources.point_spec` and
  :func:`~soilcal.chain.sources.simulate`, as the workflow's jobs), ``--cores`` at a time; the
  seeds run on from the soil's seed, one per run, as the adaptive design's do.

A case where GrainLearning stops with an error gets a row saying so, with the runs it spent
and no verification; the soil's other cases go on.  A case it cannot take (a goal minimize or
maximize: :func:`not_applicable`) or whose budget leaves fewer than 2d+1 samples per iteration
for d factors gets a row saying why, with no runs.  Rows (method ``grainlearning``) replace
that soil's earlier GrainLearning rows; the page
``adaptive.md`` is rewritten with every method.  Per case the runs, samples and values go to
``<workdir>/<soil>-grainlearning/gl/<stage>-<case>/``.

    python benchmarks/adaptive_gl.py --soils cinnamon-soil
    python benchmarks/adaptive_gl.py --soils cinnamon-soil --iterations 4 --glenv /tmp/glenv
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import pandas as pd
from _report import commit, read_rows, write_page, write_rows

HERE = Path(__file__).resolve().parent
OUT = HERE / "results"
DRIVER = HERE / "adaptive_gl_driver.py"
GL_VERSION = "2.0.5"
sys.path.insert(0, str(HERE))

from adaptive import FIELDS, PROGRESS_FIELDS, figures, page  # noqa: E402
from calibration import copy_workflow  # noqa: E402


def gl_python(env: Path) -> Path:
    """The Python of GrainLearning's environment, created (venv + pip) when absent."""
    py = env / "bin" / "python"
    if not py.exists():
        subprocess.run([sys.executable, "-m", "venv", str(env)], check=True)
        subprocess.run([str(py), "-m", "pip", "install", "-q", f"grainlearning=={GL_VERSION}"], check=True)
    subprocess.run([str(py), "-c", "import grainlearning"], check=True)
    return py


# --------------------------------------------------------------------------- DEM side

@functools.lru_cache(maxsize=4)
def _load(case_file: str):
    """The soil and the case (read once per worker process, not once per run)."""
    from soilcal.config.load import load_soil

    c = json.loads(Path(case_file).read_text())
    soil = load_soil(c["soil_yaml"], c["resources"])
    return soil, c


def _one(case_file: str, levels: dict, seed: int, run: int) -> pd.DataFrame:
    from soilcal.chain.sources import point_spec, simulate

    soil, c = _load(str(case_file))
    spec = point_spec(soil, c["stage"], levels, run=run, seed=seed, replicates=1, responses=c["responses"])
    return simulate(spec, threads=1)


def run_points(case_file: Path, levels: list[dict], seeds: list[int], first_run: int, cores: int) -> pd.DataFrame:
    """One DEM job per (levels, seed), ``cores`` at a time; their rows in order."""
    with ProcessPoolExecutor(max_workers=cores) as ex:
        futs = [ex.submit(_one, str(case_file), lv, s, first_run + k) for k, (lv, s) in enumerate(zip(levels, seeds))]
        return pd.concat([f.result() for f in futs], ignore_index=True)


def values(rows: pd.DataFrame, responses: list[str], n: int, first_run: int) -> np.ndarray:
    out = np.full((n, len(responses)), np.nan)
    for _, r in rows.iterrows():
        if str(r["status"]) == "ok":
            out[int(r["run"]) - first_run, responses.index(r["response"])] = float(r["value"])
    return out


def evaluate(case_file: Path, batch_file: Path, out_file: Path, cores: int) -> None:
    """The driver's batch: run it, append the rows to the case's runs.csv, write the values."""
    c = json.loads(case_file.read_text())
    b = json.loads(batch_file.read_text())
    levels = [dict(zip(b["names"], map(float, p))) for p in b["params"]]
    runs_csv = case_file.parent / "runs.csv"
    first = len(pd.read_csv(runs_csv)["run"].unique()) if runs_csv.exists() else 0
    rows = run_points(case_file, levels, b["seeds"], first, cores)
    rows.insert(0, "iteration", int(b["iteration"]))
    rows.to_csv(runs_csv, mode="a", header=not runs_csv.exists(), index=False)
    out_file.write_text(json.dumps({"values": values(rows, c["responses"], len(levels), first).tolist()}))


# --------------------------------------------------------------------------- one case

def not_applicable(problem) -> str:
    """Why GrainLearning cannot calibrate this case ('' where it can).  Its likelihood is a
    normal centred on the observations with the covariance ``sigma * obs.max()**2`` (grainlearning
    2.0.5, ``inference.SMC.get_covariance_matrices``): a goal minimize or maximize has no
    observation to centre it on, and taking 0 for one (a difference to be minimised) makes the
    covariance zero.  Such a case is an optimisation, not an inverse problem."""
    goals = sorted({t.goal for t in problem.targets if t.optimised})
    if not goals:
        return ""
    return (f"not applicable: goal {' and '.join(goals)} has no observed value, and GrainLearning's "
            "likelihood is a normal around an observation, its covariance scaled by the observation "
            "squared (an observation of 0 makes it zero)")


def not_run(soil_name: str, stage_id: str, case_id: str, problem, why: str) -> dict:
    """A case's rows when GrainLearning does not run it, with the reason and no runs spent."""
    return {"rows": [{"soil": soil_name, "stage": stage_id, "case": case_id, "target": t.response,
                      "method": "grainlearning", "runs": 0, "verification_rel_error_pct": math.nan,
                      "within_2_percent": "", "elapsed_s": "", "stopped_because": why,
                      "note": f"grainlearning {GL_VERSION}: not run"} for t in problem.targets],
            "optimum": None}


def run_case(wd: Path, soil_name: str, stage_id: str, case_id: str, targets: dict, budget: int, args,
             upstream: pd.DataFrame | None, glpy: Path) -> dict:
    from soilcal.chain import adaptive as cad
    from soilcal.config.load import load_soil

    soil_yaml, res = wd / "config" / "soils" / f"{soil_name}.yaml", wd / "resources"
    soil = load_soil(soil_yaml, res)
    stage = cad.stage_for(soil.data, stage_id, upstream)
    problem = cad.problem_for(soil.data, stage, case_id, targets)
    settings = cad.settings_for(soil.data)
    why = not_applicable(problem)
    if why:
        print(f"{soil_name} {stage_id}/{case_id}: {why}", flush=True)
        return not_run(soil_name, stage_id, case_id, problem, why)
    cdir = wd / "gl" / f"{stage_id}-{case_id}"
    cdir.mkdir(parents=True, exist_ok=True)
    for f in cdir.glob("*"):
        f.unlink()
    responses = problem.responses
    case_file = cdir / "case.json"
    case_file.write_text(json.dumps({"soil_yaml": str(soil_yaml), "resources": str(res), "stage": stage,
                                     "responses": responses}, default=float))
    samples = (budget - settings.verify_seeds) // args.iterations
    if samples < 2 * len(problem.names) + 1:
        why = (f"not run: a budget of {budget} runs (the recipe's, per case) leaves {samples} samples per iteration "
               f"for {args.iterations} iterations after {settings.verify_seeds} verification seeds (at least "
               f"{2 * len(problem.names) + 1} needed for {len(problem.names)} factors)")
        print(f"{soil_name} {stage_id}/{case_id}: {why}", flush=True)
        return not_run(soil_name, stage_id, case_id, problem, why)
    prob = {"names": problem.names, "low": [f.low for f in problem.factors], "high": [f.high for f in problem.factors],
            "responses": responses, "targets": [t.value for t in problem.targets], "samples": samples,
            "iterations": args.iterations, "seed": settings.seed, "ess_target": args.ess_target,
            "workdir": str(cdir),
            "evaluate": [sys.executable, str(Path(__file__).resolve()), "--cores", str(args.cores),
                         "--evaluate", str(case_file)]}
    (cdir / "problem.json").write_text(json.dumps(prob, indent=1))
    t0 = time.perf_counter()
    p = subprocess.run([str(glpy), str(DRIVER), str(cdir / "problem.json")], capture_output=True, text=True)
    (cdir / "driver.log").write_text(p.stdout + p.stderr)
    if p.returncode != 0:
        # GrainLearning stopped with an error: the case's row says so, with the runs it spent,
        # and the soil's other cases go on (a case fixed from this one cannot)
        lines = [ln for ln in p.stderr.strip().splitlines() if ln.strip()]
        err = next((ln for ln in reversed(lines) if "Error" in ln.split(":")[0]), lines[-1] if lines else "")
        runs_csv = cdir / "runs.csv"
        spent = len(pd.read_csv(runs_csv)["run"].unique()) if runs_csv.exists() else 0
        print(f"{soil_name} {stage_id}/{case_id}: GrainLearning exited {p.returncode} after {spent} runs "
              f"(log: {cdir / 'driver.log'}): {err}", flush=True)
        out = [{"soil": soil_name, "stage": stage_id, "case": case_id, "target": t.response, "method": "grainlearning",
                "runs": spent, "verification_rel_error_pct": math.nan, "within_2_percent": "",
                "elapsed_s": round(time.perf_counter() - t0, 1),
                "stopped_because": f"GrainLearning failed after {spent} runs: {err[:120]}",
                "note": f"grainlearning {GL_VERSION}: no estimate, nothing verified; log gl/{cdir.name}/driver.log"}
               for t in problem.targets]
        return {"rows": out, "optimum": None}
    result = json.loads((cdir / "result.json").read_text())
    runs = sum(len(h["params"]) for h in result["history"])
    best = result["most_probable"]
    first_seed = settings.seed + runs
    k = settings.verify_seeds
    ver = run_points(case_file, [best] * k, list(range(first_seed, first_seed + k)), runs, args.cores)
    ver.to_csv(cdir / "verification_runs.csv", index=False)
    vals = values(ver, responses, k, runs)
    elapsed = time.perf_counter() - t0
    out = []
    errs = {}
    for j, t in enumerate(problem.targets):
        v = vals[:, j][np.isfinite(vals[:, j])]
        mean = float(v.mean()) if v.size else math.nan
        errs[t.response] = (100.0 * (mean - t.value) / t.value, t.tolerance / abs(t.value) * 100.0, v)
    met = all(abs(e) <= tol for e, tol, _ in errs.values())
    for j, t in enumerate(problem.targets):
        e, tol, v = errs[t.response]
        out.append({"soil": soil_name, "stage": stage_id, "case": case_id, "target": t.response,
                    "method": "grainlearning", "runs": runs + k, "verification_rel_error_pct": e,
                    "within_2_percent": bool(abs(e) <= 2.0), "elapsed_s": round(elapsed, 1),
                    "stopped_because": (f"{result['iterations_run']} iterations of {samples} samples spent "
                                        f"(budget {budget}: the recipe's runs per case)"
                                        + (f"; {result['collapsed']}" if result.get("collapsed") else "")
                                        + ("; target met" if met else "")),
                    "note": f"grainlearning {GL_VERSION}: most probable sample "
                            + ", ".join(f"{n}={best[n]:.4g}" for n in problem.names)
                            + f"; {v.size} of {k} seeds {np.mean(v) if v.size else math.nan:.2f} +- "
                              f"{np.std(v, ddof=1) if v.size > 1 else math.nan:.2f}"})
    optimum = pd.DataFrame([{"case": case_id, "method": "grainlearning", "solution": 1, "calibrated": True,
                             **{n: best[n] for n in problem.names}}])
    return {"rows": out, "optimum": optimum}


def run_soil(soil: str, args, glpy: Path, recipe: dict) -> list[dict]:
    from soilcal.chain import adaptive as cad
    from soilcal.chain.derive import dem_stage_ids, dependencies
    from soilcal.chain.files import read_targets
    from soilcal.config.load import load_soil

    wd = copy_workflow(Path(args.workdir) / f"{soil}-grainlearning", [soil])
    target = f"results/{soil}/dem/targets.csv"
    p = subprocess.run([sys.executable, "-m", "snakemake", "--cores", str(args.cores), target], cwd=wd,
                       capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"{soil}: snakemake {target} exited {p.returncode}:\n{p.stderr[-2000:]}")
    targets = read_targets(wd / target)
    data = load_soil(wd / "config" / "soils" / f"{soil}.yaml", wd / "resources").data
    stages = [s for s in dem_stage_ids(data)
              if next(st for st in data["stages"] if st["id"] == s).get("optimise")]
    optima: dict[str, pd.DataFrame] = {}
    rows = []
    cases = cad.adaptive_cases(data, stages)
    for stage_id, case_id in cases:
        deps = dependencies(dict(data, simulation={**(data.get("simulation") or {}), "design": "printed"}), stage_id)
        up = optima.get(deps["fixed_from"]) if "fixed_from" in deps else None
        if "fixed_from" in deps and up is None:
            raise SystemExit(f"{soil} {stage_id}/{case_id}: fixed from stage {deps['fixed_from']}, which has no "
                             "GrainLearning estimate")
        budget = recipe.get((stage_id, case_id))
        if budget is None:
            raise SystemExit(f"{soil} {stage_id}/{case_id}: no recipe row in {OUT / 'adaptive.csv'}; run "
                             f"python benchmarks/adaptive.py --soils {soil} --methods recipe first")
        res = run_case(wd, soil, stage_id, case_id, targets, int(budget) // len(cases), args, up, glpy)
        rows += res["rows"]
        if res["optimum"] is not None:
            optima[stage_id] = pd.concat([optima[stage_id], res["optimum"]]) if stage_id in optima else res["optimum"]
        print(f"{soil} {stage_id}/{case_id}: " + "; ".join(
            f"{r['target']} {r['verification_rel_error_pct']:+.1f} %" for r in res["rows"]), flush=True)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--soils", default="cinnamon-soil")
    ap.add_argument("--iterations", type=int, default=3, help="GrainLearning iterations (default 3)")
    ap.add_argument("--ess-target", type=float, default=0.3, help="effective sample size target (default 0.3)")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--glenv", default="/tmp/soilcal-grainlearning-env")
    ap.add_argument("--workdir", default="/tmp/soilcal-adaptive-bench")
    ap.add_argument("--evaluate", nargs=3, metavar=("CASE", "BATCH", "OUT"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.evaluate:
        evaluate(*map(Path, a.evaluate), a.cores)
        return
    glpy = gl_python(Path(a.glenv))
    path = OUT / "adaptive.csv"
    rows = read_rows(path, FIELDS)
    rev = commit()
    for soil in a.soils.split(","):
        recipe = {(r["stage"], r["case"]): int(r["runs"]) for r in rows
                  if r["soil"] == soil and r["method"] == "recipe"}
        new = run_soil(soil, a, glpy, recipe)
        utc = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M")
        rows = [r for r in rows if not (r["soil"] == soil and r["method"] == "grainlearning")]
        rows += [dict(r, utc=utc, commit=rev, cores=a.cores) for r in new]
        write_rows(path, rows, FIELDS)
    figures(rows, read_rows(OUT / "adaptive_progress.csv", PROGRESS_FIELDS))
    write_page(OUT / "adaptive.md", page(rows))


if __name__ == "__main__":
    main()
