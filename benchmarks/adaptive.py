"""Runs spent and verified error: the papers' recipe on soilcal's DEM against ``design: adaptive``,
same engine, preset and soil seed, from an empty results/ each.

For every soil given, a fresh copy of the workflow (``benchmarks/calibration.py``'s copy) runs
``snakemake --cores N`` once with ``--config design=recipe`` and once with
``design=adaptive``.  Per case and target response one row per method:

* recipe: runs = every DEM run of the soil's stages (design points times their replicates), its
  verification seeds and its second-round seeds (the tool tests and the measured-data loop are
  not part of the calibration and are not counted); error = the last round's verification row;
* adaptive: runs and error from ``results/<soil>/dem/adaptive/summary.csv`` (the verified point's
  mean; no error when no point was verified), and why it stopped.

Both rows also carry the goal and the verified mean and SD: for a response to minimise (the
yangtze furrow's area difference) there is no target to take an error against, and the
verified means are what the methods are compared by.

Rows go to ``benchmarks/results/adaptive.csv``
(``soil,target,method,runs,verification_rel_error_pct,stopped_because`` and context columns);
``adaptive.md`` is the page.  A (soil, method) run replaces that pair's earlier rows.

    python benchmarks/adaptive.py --soils cinnamon-soil
    python benchmarks/adaptive.py --soils cinnamon-soil --methods adaptive
    python benchmarks/adaptive.py --report-only
"""

from __future__ import annotations

import argparse
import platform
import subprocess
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

import pandas as pd
from _report import commit, read_rows, write_page, write_rows

HERE = Path(__file__).resolve().parent
OUT = HERE / "results"
FIELDS = ["utc", "commit", "soil", "stage", "case", "target", "method", "runs", "verification_rel_error_pct",
          "within_2_percent", "stopped_because", "elapsed_s", "cores", "note", "goal", "verified_mean", "verified_sd"]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]
sys.path.insert(0, str(HERE))

from calibration import copy_workflow  # noqa: E402


def recipe_rows(wd: Path, soil: str) -> list[dict]:
    d = wd / "results" / soil / "dem"
    runs = 0
    for f in d.glob("*/runs/*.csv"):
        df = pd.read_csv(f)
        runs += int(df["replicates"].iloc[0]) if len(df) else 0
    runs += len(list(d.glob("verify/*/*/*/*.csv"))) + len(list(d.glob("refine/*/*/*.csv")))
    ver = pd.read_csv(d / "verification.csv")
    rows = []
    goals = {(st["id"], c["id"], rid): g.get("goal", "target") for st in _stages(wd, soil)
             for c in (st.get("optimise") or {}).get("cases", []) for rid, g in c["goals"].items()}
    for (stage, case, resp), g in ver.groupby(["stage", "case", "response"], sort=False):
        last = g[g["round"] == g["round"].max()].iloc[0]
        goal = goals.get((stage, case, resp), "target")
        rows.append({"soil": soil, "stage": stage, "case": case, "target": resp, "method": "recipe",
                     "goal": goal, "verified_mean": last["simulated_mean"], "verified_sd": last["simulated_sd"],
                     "runs": runs, "verification_rel_error_pct": last["relative_error_percent"],
                     # no target, no band: a minimised response is compared by its verified mean
                     "within_2_percent": last["within_2_percent"] if goal == "target" else "",
                     "stopped_because": "recipe complete"
                     if str(last["status"]) == "ok" else str(last["status"])[:80],
                     "note": f"runs: the soil's whole recipe; round {int(last['round'])}"})
    return rows


def _stages(wd: Path, soil: str) -> list[dict]:
    import yaml

    return yaml.safe_load((wd / "config/soils" / f"{soil}.yaml").read_text())["stages"]


def adaptive_rows(wd: Path, soil: str) -> list[dict]:
    s = pd.read_csv(wd / "results" / soil / "dem/adaptive/summary.csv")
    return [{"soil": soil, "stage": r["stage"], "case": r["case"], "target": r["response"], "method": "adaptive",
             "goal": r.get("goal", "target"), "verified_mean": r["verified_mean"], "verified_sd": r["verified_sd"],
             "runs": int(r["runs"]), "verification_rel_error_pct": r["verification_rel_error_pct"],
             "within_2_percent": r["within_tolerance"], "stopped_because": r["stopped_because"],
             "note": "runs: this case's design" if r["stopped_because"] != "not run" else str(r["message"])[:120]}
            for _, r in s.iterrows()]


def run_method(soil: str, method: str, cores: int, workdir: Path) -> tuple[list[dict], float, int]:
    wd = copy_workflow(workdir / f"{soil}-{method}", [soil])
    t0 = time.perf_counter()
    p = subprocess.run(SNAKEMAKE + ["--cores", str(cores), "--config", f"design={method}", "source=dem"],
                       cwd=wd, capture_output=True, text=True)
    elapsed = time.perf_counter() - t0
    (workdir / f"{soil}-{method}.log").write_text(p.stdout + p.stderr)
    if p.returncode != 0:
        print(p.stderr[-3000:], file=sys.stderr)
        return [], elapsed, p.returncode
    return (recipe_rows if method == "recipe" else adaptive_rows)(wd, soil), elapsed, 0


def page(rows: list[dict]) -> list[str]:
    lines = ["# Runs spent and verified error: the papers' recipe against the adaptive design", "",
             f"Machine: {platform.machine()}, Python {platform.python_version()}.  Rows: `adaptive.csv` "
             "(utc and commit per row).  runs: DEM runs of one seed each; error: the verified mean's signed "
             "relative error, percent.", "",
             "| soil | stage | case | target | method | runs | verified | error % | within 2 % | stopped because "
             "| elapsed min |",
             "|---|---|---|---|---|---:|---|---:|---|---|---:|"]
    for r in rows:
        err = r["verification_rel_error_pct"]
        err = f"{float(err):.1f}" if str(err) not in ("", "nan", "None") else ""
        el = f"{float(r['elapsed_s']) / 60:.1f}" if str(r["elapsed_s"]) else ""
        met = r["within_2_percent"]
        met = "" if str(met) in ("", "nan", "None") else met  # no verified point
        ver = ""
        if str(r.get("verified_mean", "")) not in ("", "nan", "None"):
            sd = str(r.get("verified_sd", ""))
            ver = f"{float(r['verified_mean']):.4g}" + (f" +- {float(sd):.2g}" if sd not in ("", "nan", "None") else "")
            if str(r.get("goal", "")) in ("minimize", "maximize"):
                ver += f" ({r['goal']})"
        lines.append(f"| {r['soil']} | {r['stage']} | {r['case']} | {r['target']} | {r['method']} | {r['runs']} | "
                     f"{ver} | {err} | {met} | {r['stopped_because']} | {el} |")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--soils", default="cinnamon-soil")
    ap.add_argument("--methods", default="recipe,adaptive")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--workdir", default="/tmp/soilcal-adaptive-bench")
    ap.add_argument("--report-only", action="store_true")
    a = ap.parse_args(argv)
    path = OUT / "adaptive.csv"
    rows = read_rows(path, FIELDS)
    if not a.report_only:
        rev, wd = commit(), Path(a.workdir)
        wd.mkdir(parents=True, exist_ok=True)
        for soil in a.soils.split(","):
            for method in a.methods.split(","):
                new, elapsed, rc = run_method(soil, method, a.cores, wd)
                if rc:
                    raise SystemExit(f"{soil} {method}: snakemake exited {rc} (log in {wd})")
                utc = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M")
                rows = [r for r in rows if not (r["soil"] == soil and r["method"] == method)]
                rows += [dict(r, utc=utc, commit=rev, elapsed_s=round(elapsed, 1), cores=a.cores) for r in new]
                write_rows(path, rows, FIELDS)
    write_page(OUT / "adaptive.md", page(rows))


if __name__ == "__main__":
    main()
