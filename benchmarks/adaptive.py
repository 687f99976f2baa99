"""Runs spent and verified error: the papers' recipe on soilcal's DEM against ``design: adaptive``,
same engine, preset and soil seed, from an empty results/ each.

For every soil given, a fresh copy of the workflow (``benchmarks/calibration.py``'s copy) runs
``snakemake --cores N`` once with ``--config design=recipe`` and once with
``design=adaptive``.  Per case and target response one row per method:

* recipe: runs = every DEM run of the soil's stages (design points times their replicates), its
  verification seeds, its local design's points times their seeds and its second-round seeds
  (the tool tests and the measured-data loop are not part of the calibration and are not
  counted); error = the last round's verification row;
* adaptive: runs and error from ``results/<soil>/dem/adaptive/summary.csv`` (the verified point's
  mean; no error when no point was verified), and why it stopped.

Both rows also carry the goal and the verified mean and SD: for a response to minimise (the
yangtze furrow's area difference) there is no target to take an error against, and the
verified means are what the methods are compared by.

Rows go to ``benchmarks/results/adaptive.csv``
(``soil,target,method,runs,verification_rel_error_pct,stopped_because`` and context columns);
``adaptive.md`` is the page.  A (soil, method) run replaces that pair's earlier rows.

The adaptive design's best verified set after every iteration against the runs spent
(``soilcal.chain.adaptive.progress_frame`` of its step records) goes to
``adaptive_progress.csv``; per soil, stage and case, ``adaptive/<soil>_<stage>_<case>.png``
draws that curve with the other methods' verified sets as points at their run counts
(``soilcal.plots.adaptive.error_against_runs``).  ``--progress-from W`` reads the curves of
the soils given from an earlier run's workdir ``W`` (``W/<soil>-adaptive``), taking the time and
commit of that soil's adaptive rows.

    python benchmarks/adaptive.py --soils cinnamon-soil
    python benchmarks/adaptive.py --soils cinnamon-soil --methods adaptive
    python benchmarks/adaptive.py --soils yangtze-clay-loam --progress-from /tmp/soilcal-adaptive-bench
    python benchmarks/adaptive.py --soils guangxi-cohesive --recipe-from /tmp/calibration-bench
    python benchmarks/adaptive.py --soils guangxi-cohesive --methods adaptive --budget 20
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

from soilcal.chain.adaptive import PROGRESS_COLUMNS  # noqa: E402

PROGRESS_FIELDS = ["utc", "commit", "soil", *PROGRESS_COLUMNS]
FIGURES = OUT / "adaptive"

from calibration import copy_workflow  # noqa: E402


def recipe_rows(wd: Path, soil: str) -> list[dict]:
    d = wd / "results" / soil / "dem"
    runs = 0
    for f in d.glob("*/runs/*.csv"):
        df = pd.read_csv(f)
        # a point's seeds: the most any of its responses ran (a response may run its own count)
        runs += int(df["replicates"].max()) if len(df) else 0
    # a verification seed of a case without a calibrated set writes a 'not run' row: no run; a
    # local design's point runs a design point's seeds
    runs += sum(_ran(f) for f in _seed_files(d))
    ver = pd.read_csv(d / "verification.csv")
    rows = []
    goals = {(st["id"], c["id"], rid): g.get("goal", "target") for st in _stages(wd, soil)
             for c in (st.get("optimise") or {}).get("cases", []) for rid, g in c["goals"].items()}
    for (stage, case, resp), g in ver.groupby(["stage", "case", "response"], sort=False):
        # the round the case ends with (``final``; a table without it: the last round)
        fin = g[g["final"].astype(str) == "True"] if "final" in g.columns else g.iloc[:0]
        last = fin.iloc[0] if len(fin) else g[g["round"] == g["round"].max()].iloc[0]
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


def _seed_files(d: Path) -> list[Path]:
    """The one-seed run files of a soil's DEM calibration beside its design points: the
    verification seeds, the second round's seeds and the local design's points."""
    return [*d.glob("verify/*/*/*/*.csv"), *d.glob("refine/*/*/*.csv"), *d.glob("local/*/*/*.csv")]


def _ran(f: Path) -> int:
    """The seeds the run file ``f`` ran: the most any of its rows ran, none for a 'not run'
    row."""
    df = pd.read_csv(f)
    ran = df[df["status"].astype(str) != "not run"] if len(df) else df
    if not len(ran):
        return 0
    return int(pd.to_numeric(ran["replicates"], errors="coerce").fillna(1).max()) if "replicates" in ran.columns else 1


def recipe_commit(wd: Path, soil: str) -> str:
    """The commit every DEM run of a recipe workdir ran at (its run rows' ``commit``)."""
    d = wd / "results" / soil / "dem"
    found = set()
    for f in [*d.glob("*/runs/*.csv"), *_seed_files(d)]:
        found |= {str(c)[:7] for c in pd.read_csv(f).get("commit", pd.Series(dtype=str)).dropna()}
    if len(found) != 1:
        raise SystemExit(f"--recipe-from: the runs under {d} name {len(found)} commits ({sorted(found)}), not one")
    return found.pop()


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


def progress_rows(wd: Path, soil: str) -> list[dict]:
    """The adaptive design's best verified set after every iteration, per case, from the step
    records of a workdir's run (``soilcal.chain.adaptive.progress_frame``)."""
    from soilcal.chain.adaptive import case_steps, progress_frame

    rows = []
    for res_path in sorted((wd / "results" / soil / "dem" / "adaptive").glob("*/*/result.json")):
        res, steps = case_steps(res_path.parent)
        rows += [dict(r, soil=soil) for r in progress_frame(res, steps).to_dict("records")]
    return rows


def _point(r: dict) -> dict:
    """A method's final row of ``adaptive.csv`` as one point of the progress figure."""
    num = (lambda v: float(v) if str(v) not in ("", "nan", "None") else float("nan"))
    return {"method": r["method"], "runs": num(r["runs"]), "response": r["target"], "goal": r.get("goal") or "target",
            "target": float("nan"), "tolerance": float("nan"), "verified_mean": num(r.get("verified_mean", "")),
            "error_pct": num(r["verification_rel_error_pct"])}


def figures(rows: list[dict], progress: list[dict]) -> list[Path]:
    """Per soil, stage and case: the adaptive curve (or its final row where no curve was kept)
    and every other method's verified set (``adaptive/<soil>_<stage>_<case>.png``)."""
    from soilcal.plots.adaptive import error_against_runs

    out = []
    keys = dict.fromkeys((r["soil"], r["stage"], r["case"]) for r in rows)
    for soil, stage, case in keys:
        mine = [r for r in rows if (r["soil"], r["stage"], r["case"]) == (soil, stage, case)]
        curve = [p for p in progress if (p["soil"], p["stage"], p["case"]) == (soil, stage, case)]
        pts = [dict(p, method="adaptive") for p in curve]
        pts += [_point(r) for r in mine if r["method"] != "adaptive" or not curve]
        df = pd.DataFrame(pts)
        for c in ("runs", "target", "tolerance", "verified_mean", "error_pct"):
            df[c] = pd.to_numeric(df[c], errors="coerce")
        df = df[df["runs"].notna() & (df["error_pct"].notna() | df["verified_mean"].notna())]
        if df.empty:
            continue
        png, pdf = error_against_runs(df, FIGURES / f"{soil}_{stage}_{case}",
                                      title=f"{soil} {stage} / {case}: best verified set against runs, per method",
                                      band_pct=2.0)
        pdf.unlink()
        out.append(png)
    return out


def set_budget(wd: Path, soil: str, budget: int) -> None:
    """Give the adaptive design of ``soil`` in the workflow copy ``wd`` a budget of ``budget`` runs
    per case (``simulation.adaptive.budget``), the soil's other adaptive settings kept."""
    import yaml

    p = wd / "config/soils" / f"{soil}.yaml"
    d = yaml.safe_load(p.read_text())
    sim = d.setdefault("simulation", {})
    sim["adaptive"] = dict(sim.get("adaptive") or {}, budget=int(budget))
    p.write_text(yaml.safe_dump(d, sort_keys=False))


def run_method(soil: str, method: str, cores: int, workdir: Path,
               budget: int | None = None) -> tuple[list[dict], float, int]:
    wd = copy_workflow(workdir / f"{soil}-{method}", [soil])
    if budget is not None and method == "adaptive":
        set_budget(wd, soil, budget)
    t0 = time.perf_counter()
    p = subprocess.run(SNAKEMAKE + ["--cores", str(cores), "--config", f"design={method}", "source=dem"],
                       cwd=wd, capture_output=True, text=True)
    elapsed = time.perf_counter() - t0
    (workdir / f"{soil}-{method}.log").write_text(p.stdout + p.stderr)
    if p.returncode != 0:
        print(p.stderr[-3000:], file=sys.stderr)
        return [], elapsed, p.returncode
    rows = (recipe_rows if method == "recipe" else adaptive_rows)(wd, soil)
    if budget is not None and method == "adaptive":
        rows = [dict(r, note=f"{r['note']}; budget {budget} runs per case (--budget)") for r in rows]
    return rows, elapsed, 0


def page(rows: list[dict]) -> list[str]:
    lines = ["# Runs spent and verified error: the papers' recipe against the adaptive design", "",
             f"Machine: {platform.machine()}, Python {platform.python_version()}.  Rows: `adaptive.csv` "
             "(utc and commit per row).  runs: DEM runs, one per seed; error: the verified mean's signed "
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
    lines += ["", "Figures `adaptive/<soil>_<stage>_<case>.png`: per response, the error of the best verified "
              "set against the runs spent; the adaptive design as a step curve where its iterations were kept "
              "(`adaptive_progress.csv`; its own runs, a case that shares its runs counting only its own), every "
              "other method as one point at its run count (the recipe's: the runs of the soil's whole recipe)."]
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--soils", default="cinnamon-soil")
    ap.add_argument("--methods", default="recipe,adaptive")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--workdir", default="/tmp/soilcal-adaptive-bench")
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--budget", type=int, default=None,
                    help="the adaptive design's runs per case (simulation.adaptive.budget) in the workflow copy; "
                         "default: the soil's own (60 where it gives none); recorded in the rows' note")
    given = ap.add_mutually_exclusive_group()
    given.add_argument("--progress-from", default=None, help="read the adaptive curves of --soils from this workdir")
    given.add_argument("--recipe-from", default=None,
                    help="read the recipe rows of --soils from this workdir of a recipe run (benchmarks/calibration.py's "
                         "--workdir): the commit from its runs, the time from its verification.csv, no elapsed time")
    a = ap.parse_args(argv)
    path = OUT / "adaptive.csv"
    ppath = OUT / "adaptive_progress.csv"
    rows = read_rows(path, FIELDS)
    progress = read_rows(ppath, PROGRESS_FIELDS)
    if a.recipe_from:
        for soil in a.soils.split(","):
            wd = Path(a.recipe_from)
            ver = wd / "results" / soil / "dem" / "verification.csv"
            if not ver.is_file():
                raise SystemExit(f"--recipe-from: no {ver}")
            utc = datetime.fromtimestamp(ver.stat().st_mtime, timezone.utc).strftime("%Y-%m-%d %H:%M")
            rev = recipe_commit(wd, soil)
            rows = [r for r in rows if not (r["soil"] == soil and r["method"] == "recipe")]
            rows += [dict(r, utc=utc, commit=rev, elapsed_s="", cores="") for r in recipe_rows(wd, soil)]
        write_rows(path, rows, FIELDS)
    elif a.progress_from:
        for soil in a.soils.split(","):
            mine = [r for r in rows if r["soil"] == soil and r["method"] == "adaptive"]
            if not mine:
                raise SystemExit(f"--progress-from: adaptive.csv has no adaptive row of {soil}")
            new = progress_rows(Path(a.progress_from) / f"{soil}-adaptive", soil)
            if not new:
                raise SystemExit(f"--progress-from: no result.json under {a.progress_from}/{soil}-adaptive")
            progress = [p for p in progress if p["soil"] != soil]
            progress += [dict(p, utc=mine[0]["utc"], commit=mine[0]["commit"]) for p in new]
        write_rows(ppath, progress, PROGRESS_FIELDS)
    elif not a.report_only:
        rev, wd = commit(), Path(a.workdir)
        wd.mkdir(parents=True, exist_ok=True)
        for soil in a.soils.split(","):
            for method in a.methods.split(","):
                new, elapsed, rc = run_method(soil, method, a.cores, wd, a.budget)
                if rc:
                    raise SystemExit(f"{soil} {method}: snakemake exited {rc} (log in {wd})")
                utc = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M")
                rows = [r for r in rows if not (r["soil"] == soil and r["method"] == method)]
                rows += [dict(r, utc=utc, commit=rev, elapsed_s=round(elapsed, 1), cores=a.cores) for r in new]
                write_rows(path, rows, FIELDS)
                if method == "adaptive":
                    progress = [p for p in progress if p["soil"] != soil]
                    progress += [dict(p, utc=utc, commit=rev) for p in progress_rows(wd / f"{soil}-adaptive", soil)]
                    write_rows(ppath, progress, PROGRESS_FIELDS)
    figures(rows, progress)
    write_page(OUT / "adaptive.md", page(rows))


if __name__ == "__main__":
    main()
