"""The whole DEM calibration from an empty results/ with `snakemake --cores N`: its wall time,
the time of every rule from Snakemake's benchmark files, whether a second run has nothing to
do, and whether a run killed midway recomputes only its unfinished jobs.

The workflow (Snakefile, workflow/, config/, resources/, envs/) is copied into a fresh work
directory, so the repository's own results/ are never touched; ``--soils`` restricts the copy's
config to some soils.  Rows go to ``benchmarks/results/calibration.csv`` (one per rule and run)
and ``calibration_runs.csv`` (one per workflow run); ``calibration.md`` is the page.

    python benchmarks/calibration.py                       # the five soils, 2 cores
    python benchmarks/calibration.py --kill-after 300      # also: kill at 300 s, unlock, restart
    python benchmarks/calibration.py --soils cinnamon-soil --kill-after 60
    python benchmarks/calibration.py --report-only
    python benchmarks/calibration.py --surfaces-of /tmp/run   # surfaces of a directory that ran
    python benchmarks/calibration.py --breakdown-of /tmp/run  # its jobs per soil and rule

The breakdown (``calibration_soils.csv``) splits a run's job time by soil and rule and adds
the DEM work the jobs' logs name (every scenario run prints its particles, steps and wall time,
:func:`soilcal.chain.sources.run_point`): particle-steps, and the rate the runs reached, which
tell whether a soil costs much because it simulates much or because its runs are slow.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import resource
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import yaml
from _report import commit, read_rows, write_page, write_rows

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OUT = HERE / "results"
RULE_FIELDS = ["utc", "commit", "run_id", "rule", "jobs", "sum_s", "mean_s", "max_s", "max_rss_mb"]
RUN_FIELDS = ["utc", "commit", "run_id", "soils", "cores", "kind", "elapsed_s", "jobs_done", "rc",
              "run_cpu_s", "other_cpu_s", "note"]
SURFACE_FIELDS = ["utc", "commit", "run_id", "soil", "stage", "response", "points", "centre_points", "seed_sd",
                  "centre_sd", "largest_effect", "largest_effect_factor", "effect_over_centre_sd", "model_p",
                  "lack_of_fit_p"]
BREAKDOWN_FIELDS = ["utc", "commit", "run_id", "soil", "rule", "jobs", "sum_s", "dem_runs", "dem_wall_s",
                    "particle_steps"]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]
#: the line every DEM scenario run of a job writes to its log (soilcal.chain.sources.run_point)
RUN_LINE = re.compile(r"^(\S+) (\S+) \((\w+)\): (\d+) particles, (\d+) steps, ([\d.]+) s on \d+ thread",
                      flags=re.M)


def copy_workflow(dest: Path, soils: list[str] | None) -> Path:
    if dest.exists():
        shutil.rmtree(dest)
    dest.mkdir(parents=True)
    for f in ("Snakefile",):
        shutil.copy(ROOT / f, dest / f)
    for d in ("workflow", "config", "resources", "envs", "profiles"):
        shutil.copytree(ROOT / d, dest / d, symlinks=False)
    if soils:
        cfg = yaml.safe_load((dest / "config/config.yaml").read_text())
        cfg["soils"] = soils
        (dest / "config/config.yaml").write_text(yaml.safe_dump(cfg))
    return dest


def rule_of(path: Path) -> str:
    """The rule a benchmark file belongs to, from its place under benchmarks/workflow/."""
    parts = path.parts
    if "loop" in parts and "runs" in parts:
        return "loop_point"
    if "runs" in parts:
        return "dem_point"
    if "refine" in parts:
        return "refine_point"
    if "verify" in parts:
        return "verify_point"
    if "tools" in parts:
        return "tool_point"
    stem = path.stem
    if stem.startswith("figures_"):
        return "figures"
    return {"responses": "dem_responses"}.get(stem, stem)


def rule_times(workdir: Path) -> pd.DataFrame:
    """One row per job's benchmark file: its path under ``benchmarks/workflow/`` (``rel``), soil
    (the path's first folder; none for ``dem_kernels``), rule, wall time ``s`` and ``max_rss``."""
    bench = workdir / "benchmarks/workflow"
    rows = []
    for p in sorted(bench.rglob("*.tsv")):
        df = pd.read_csv(p, sep="\t")
        if len(df):
            rel = p.relative_to(bench)
            rows.append({"rel": rel, "soil": rel.parts[0] if len(rel.parts) > 1 else "", "rule": rule_of(rel),
                         "s": float(df["s"].iloc[-1]),
                         "max_rss": float(pd.to_numeric(df["max_rss"], errors="coerce").iloc[-1])})
    return pd.DataFrame(rows, columns=["rel", "soil", "rule", "s", "max_rss"])


def breakdown_rows(workdir: Path, rt: pd.DataFrame | None = None) -> list[dict]:
    """Per soil and rule: the jobs, the sum of their benchmark-file wall times (``rt``, the
    run's :func:`rule_times`), and the DEM runs their logs name (``logs/<the benchmark file's
    path>.log``) with those runs' wall time and particle-steps (particles x steps, summed).  A
    job whose log names no run (a fit, a figure, the photo pipeline) adds to ``sum_s`` only;
    ``dem_kernels`` has no soil."""
    rt = rule_times(workdir) if rt is None else rt
    out = []
    for (soil, rule), g in rt.groupby(["soil", "rule"], sort=True):
        runs = [m for rel in g["rel"] for m in RUN_LINE.finditer(_text(workdir / "logs" / rel.with_suffix(".log")))]
        out.append(dict(soil=soil, rule=rule, jobs=len(g), sum_s=round(float(g["s"].sum()), 1), dem_runs=len(runs),
                        dem_wall_s=round(sum((float(m.group(6)) for m in runs), 0.0), 1),
                        particle_steps=sum(int(m.group(4)) * int(m.group(5)) for m in runs)))
    return out


def _text(path: Path) -> str:
    return path.read_text(errors="replace") if path.is_file() else ""


def add_breakdown(workdir: Path, utc: str, run_id: str, rev: str, rt: pd.DataFrame | None = None) -> None:
    rows = [dict(r, utc=utc, commit=rev, run_id=run_id) for r in breakdown_rows(workdir, rt)]
    write_rows(OUT / "calibration_soils.csv", read_rows(OUT / "calibration_soils.csv", BREAKDOWN_FIELDS) + rows,
               BREAKDOWN_FIELDS)


def machine_busy_s() -> float:
    """CPU seconds the whole machine has spent busy (every CPU; /proc/stat, Linux)."""
    try:
        f = [int(v) for v in Path("/proc/stat").read_text().split("\n")[0].split()[1:]]
    except (OSError, ValueError):
        return float("nan")
    user, nice, system, idle, iowait, irq, softirq, steal = (f + [0] * 8)[:8]
    return (user + nice + system + irq + softirq + steal) / os.sysconf("SC_CLK_TCK")


def children_cpu_s() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def snakemake(workdir: Path, cores: int, *extra, timeout=None, load=None):
    """Run Snakemake in ``workdir``; ``load`` (a dict) receives the CPU seconds of the run's
    process tree (``run_cpu_s``) and of everything else on the machine meanwhile
    (``other_cpu_s``): a run that shared the machine says so."""
    t0 = time.perf_counter()
    busy0, own0 = machine_busy_s(), children_cpu_s()
    # the package of this checkout, whose commit the rows name, whatever soilcal the environment
    # has installed (an editable install of another checkout would run that one's code)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src")] + [
        x for x in os.environ.get("PYTHONPATH", "").split(os.pathsep) if x]))
    p = subprocess.Popen(SNAKEMAKE + ["--cores", str(cores), *extra], cwd=workdir, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, start_new_session=True, env=env)
    killed = False
    try:
        out, _ = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, _ = p.communicate()
        killed = True
    if load is not None:
        own = children_cpu_s() - own0
        load.update(run_cpu_s=round(own, 1), other_cpu_s=round(max(0.0, machine_busy_s() - busy0 - own), 1))
    return p.returncode, time.perf_counter() - t0, out, killed


def surface_rows(workdir: Path) -> list[dict]:
    """Per soil, response-surface stage (a design with centre points) and response: the seed
    scatter beside the factors' effects, and the full quadratic's model and lack-of-fit tests.

    seed_sd: the replicate SD of single seeds pooled over the design points that ran several
    (``sd`` and ``n`` of the run files, :func:`soilcal.doe.adaptive.pooled_sd`; empty with one
    seed per point); centre_sd: the square root of the ANOVA's pure-error mean square, the SD
    of the centre points' responses (each the mean of its point's seeds) in a Box-Behnken
    design; largest_effect: the largest change of the full quadratic's linear term over its
    factor's range (2 |b_i| in coded units) and its factor.  A surface whose largest effect is
    not several centre SDs cannot tell the factors from the seeds."""
    from soilcal.doe.adaptive import pooled_sd

    nan = float("nan")
    rows = []
    for anova_csv in sorted((workdir / "results").glob("*/dem/*/anova.csv")):
        d = anova_csv.parent
        design = pd.read_csv(d / "design.csv")
        coded = [c for c in design.columns if c != "run" and not c.endswith("_actual")]
        n_centre = int((design[coded] == 0).all(axis=1).sum())
        if not n_centre:  # a screening design: no centre points, no lack-of-fit test
            continue
        anova = pd.read_csv(anova_csv)
        anova = anova[anova["model"] == "full"]
        coef = pd.read_csv(d / "coefficients.csv")
        runs = [pd.read_csv(f) for f in sorted((d / "runs").glob("*.csv"))]
        runs = pd.concat(runs, ignore_index=True) if runs else pd.DataFrame(columns=["response", "sd", "n", "commit"])
        for rid in anova["response"].unique():
            a = anova[anova["response"] == rid].set_index("source")
            c = coef[(coef["response"] == rid) & (coef["model"] == "full")].set_index("term")["coded"]
            lin = {f: 2 * abs(float(c[f])) for f in coded if f in c.index}
            big = max(lin, key=lin.get) if lin else ""
            r = runs[runs["response"] == rid]
            seed_sd = pooled_sd(pd.DataFrame({f"{rid}_n": pd.to_numeric(r["n"], errors="coerce").fillna(0),
                                              f"{rid}_sd": pd.to_numeric(r["sd"], errors="coerce")}), rid)
            centre_sd = float(a.loc["Pure Error", "mean_sq"]) ** 0.5 if "Pure Error" in a.index else nan
            effect = lin.get(big, nan)
            made = r["commit"].astype(str).unique()
            rows.append(dict(commit=made[0][:7] if len(made) == 1 else "", soil=d.parent.parent.name,
                             stage=d.name, response=rid, points=len(design), centre_points=n_centre,
                             seed_sd=round(seed_sd, 3) if seed_sd is not None else nan,
                             centre_sd=round(centre_sd, 3), largest_effect=round(effect, 3),
                             largest_effect_factor=big,
                             effect_over_centre_sd=round(effect / centre_sd, 2) if centre_sd > 0 else nan,
                             model_p=float(a.loc["Model", "p"]) if "Model" in a.index else nan,
                             lack_of_fit_p=float(a.loc["Lack of Fit", "p"]) if "Lack of Fit" in a.index else nan))
    return rows


def add_surfaces(workdir: Path, utc: str, run_id: str) -> None:
    """Append the surfaces of a run's work directory to ``calibration_surfaces.csv`` (the commit
    of each row is the one its DEM runs name)."""
    rows = [dict(r, utc=utc, run_id=run_id) for r in surface_rows(workdir)]
    write_rows(OUT / "calibration_surfaces.csv",
               read_rows(OUT / "calibration_surfaces.csv", SURFACE_FIELDS) + rows, SURFACE_FIELDS)


def jobs_done(log: str) -> int:
    return len(re.findall(r"^Finished jobid: \d+ \(Rule: (?!all\))", log, flags=re.M))


def planned(workdir: Path, cores: int) -> int:
    rc, _, out, _ = snakemake(workdir, cores, "-n")
    m = re.search(r"^total\s+(\d+)", out, flags=re.M)
    return int(m.group(1)) if m else 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--soils", nargs="*", default=None)
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--workdir", default="/tmp/soilcal-calibration-bench")
    ap.add_argument("--kill-after", type=float, default=None,
                    help="also run a second copy, kill it after this many seconds, restart it")
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--surfaces-of", metavar="WORKDIR", default=None,
                    help="only add the response-surface rows of a workflow directory that has run")
    ap.add_argument("--breakdown-of", metavar="WORKDIR", default=None,
                    help="only add the per-soil breakdown of a workflow directory that has run")
    ap.add_argument("--run-id", default=None, help="with --breakdown-of: the run's id in calibration.csv")
    args = ap.parse_args(argv)
    OUT.mkdir(exist_ok=True)
    rev = commit()
    utc = time.strftime("%Y-%m-%d %H:%M", time.gmtime())
    run_id = time.strftime("%Y%m%dT%H%M%S", time.gmtime())
    if args.surfaces_of:
        wd = Path(args.surfaces_of)
        if not (wd / "results").is_dir():
            sys.exit(f"--surfaces-of {wd}: expected a workflow directory with results/, found none")
        add_surfaces(wd, utc, f"{run_id} ({wd.name})")
    elif args.breakdown_of:
        wd = Path(args.breakdown_of)
        if not (wd / "benchmarks/workflow").is_dir():
            sys.exit(f"--breakdown-of {wd}: expected a workflow directory with benchmarks/workflow/, found none")
        made = sorted({str(c)[:7] for f in (wd / "results").glob("*/dem/*/runs/*.csv")
                       for c in pd.read_csv(f, usecols=["commit"])["commit"].dropna().unique()})
        add_breakdown(wd, utc, args.run_id or f"{run_id} ({wd.name})", "+".join(made))
    elif not args.report_only:
        soils = args.soils
        wd = copy_workflow(Path(args.workdir), soils)
        label = " ".join(soils or yaml.safe_load((ROOT / "config/config.yaml").read_text())["soils"])
        load = {}
        rc, el, log, _ = snakemake(wd, args.cores, load=load)
        (wd / "calibration.log").write_text(log)
        runs = [dict(utc=utc, commit=rev, run_id=run_id, soils=label, cores=args.cores, kind="from empty results/",
                     elapsed_s=round(el, 1), jobs_done=jobs_done(log), rc=rc, note="", **load)]
        left = planned(wd, args.cores) if rc == 0 else -1
        runs.append(dict(utc=utc, commit=rev, run_id=run_id, soils=label, cores=args.cores, kind="second run (dry)",
                         elapsed_s="", jobs_done=left, rc=0, note="jobs a second run would do"))
        rt = rule_times(wd)
        rules = []
        for rule, g in rt.groupby("rule"):
            rules.append(dict(utc=utc, commit=rev, run_id=run_id, rule=rule, jobs=len(g), sum_s=round(g["s"].sum(), 1),
                              mean_s=round(g["s"].mean(), 2), max_s=round(g["s"].max(), 1),
                              max_rss_mb=round(g["max_rss"].max(), 0)))
        if args.kill_after:
            wk = copy_workflow(Path(args.workdir + "-kill"), soils)
            rc1, el1, log1, killed = snakemake(wk, args.cores, timeout=args.kill_after)
            (wk / "killed.log").write_text(log1)
            done1 = jobs_done(log1)
            # a SIGKILL leaves Snakemake's lock behind: unlock, then the same command again
            snakemake(wk, args.cores, "--unlock")
            rc2, el2, log2, _ = snakemake(wk, args.cores, "--rerun-incomplete")
            (wk / "restart.log").write_text(log2)
            done2 = jobs_done(log2)
            total = runs[0]["jobs_done"]
            runs.append(dict(utc=utc, commit=rev, run_id=run_id, soils=label, cores=args.cores,
                             kind=f"killed (SIGKILL) after {args.kill_after:g} s", elapsed_s=round(el1, 1),
                             jobs_done=done1, rc=rc1, note="killed" if killed else "finished before the kill"))
            runs.append(dict(utc=utc, commit=rev, run_id=run_id, soils=label, cores=args.cores,
                             kind="restart of the killed run", elapsed_s=round(el2, 1), jobs_done=done2, rc=rc2,
                             note=f"{done1} + {done2} = {done1 + done2} jobs against {total} in one run"))
        if (wd / "results/summary.csv").is_file() and not soils:  # the page's table: every soil
            summ = pd.read_csv(wd / "results/summary.csv")
            summ.insert(0, "commit", rev)
            summ.insert(0, "utc", utc)
            summ.to_csv(OUT / "calibration_summary.csv", index=False)
        add_surfaces(wd, utc, run_id)
        add_breakdown(wd, utc, run_id, rev, rt)
        write_rows(OUT / "calibration_runs.csv", read_rows(OUT / "calibration_runs.csv", RUN_FIELDS) + runs,
                   RUN_FIELDS)
        write_rows(OUT / "calibration.csv", read_rows(OUT / "calibration.csv", RULE_FIELDS) + rules, RULE_FIELDS)
    report(OUT / "calibration.md", argv if argv is not None else sys.argv[1:])
    return 0


def report(md_path: Path, argv) -> None:
    runs = read_rows(OUT / "calibration_runs.csv", RUN_FIELDS)
    rules = read_rows(OUT / "calibration.csv", RULE_FIELDS)
    md = ["# The DEM calibration of every soil, from an empty results/", "",
          f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs, Python {platform.python_version()}.  "
          f"Last command: `python benchmarks/calibration.py {' '.join(argv)}`.  Rows: `calibration_runs.csv`, "
          "`calibration.csv` (utc and commit per row).", "",
          "Workflow runs (a fresh copy of Snakefile, workflow/, config/, resources/ per run; elapsed is the "
          "wall-clock time of `snakemake --cores N`; run CPU min: the CPU time of the run's processes; "
          "other CPU min: what every other process on the machine used meanwhile (from /proc/stat; recorded "
          "from 2026-11-27 18:50 UTC on, empty before): a run beside other work is slower than the "
          "machine allows):", "",
          "| utc | commit | soils | cores | run | elapsed min | jobs | rc | run CPU min | other CPU min | note |",
          "|---|---|---|---:|---|---:|---:|---:|---:|---:|---|"]

    def minutes(v):
        return f"{float(v) / 60:.1f}" if v not in ("", None) else ""
    for r in runs:
        md.append(f"| {r['utc']} | {r['commit']} | {r['soils']} | {r['cores']} | {r['kind']} | "
                  f"{minutes(r['elapsed_s'])} | {r['jobs_done']} | {r['rc']} | {minutes(r['run_cpu_s'])} | "
                  f"{minutes(r['other_cpu_s'])} | {r['note']} |")
    soils_of = {r["run_id"]: r["soils"] for r in runs if "run_id" in r}
    latest = {}
    for r in rules:  # the last run of every set of soils
        latest[soils_of.get(r["run_id"], "")] = r["run_id"]
    for soils, run_id in latest.items():
        sel = [r for r in rules if r["run_id"] == run_id]
        tot = sum(float(r["sum_s"]) for r in sel)
        md += ["", f"Time per rule, run {run_id} ({soils}; from the jobs' benchmark files: each job's own wall "
               "time while the other job ran beside it; the sum is CPU-side work, not elapsed time):", "",
               "| rule | jobs | sum s | share | mean s | max s | max RSS MB |", "|---|---:|---:|---:|---:|---:|---:|"]
        for r in sorted(sel, key=lambda r: -float(r["sum_s"])):
            md.append(f"| {r['rule']} | {r['jobs']} | {r['sum_s']} | {100 * float(r['sum_s']) / tot:.0f} % | "
                      f"{r['mean_s']} | {r['max_s']} | {r['max_rss_mb']} |")
    parts = read_rows(OUT / "calibration_soils.csv", BREAKDOWN_FIELDS)
    if parts:
        rid = parts[-1]["run_id"]
        sel = [r for r in parts if r["run_id"] == rid]
        tot = sum(float(r["sum_s"]) for r in sel)
        soils = sorted({r["soil"] for r in sel}, key=lambda s: (s == "", s))
        md += ["", f"Where the time went, run {rid} ({sel[0]['commit']}; `calibration_soils.csv`, "
               "`--breakdown-of`): each soil's jobs (benchmark-file wall times, the other job beside "
               "them) and the DEM runs their logs name: the runs' own wall time, their particle-steps, and "
               "the rate (particle-steps per second of run wall time); DEM rules are the jobs that run "
               "scenarios (design points, verification, second round, tools, the loop):", "",
               "| soil | jobs | job s | share | DEM jobs | DEM job s | runs | run s | particle-steps (1e9) | "
               "M particle-steps/s | largest rule |",
               "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
        for soil in soils:
            rs = [r for r in sel if r["soil"] == soil]
            dem = [r for r in rs if int(r["dem_runs"]) > 0]
            job_s = sum(float(r["sum_s"]) for r in rs)
            run_s = sum(float(r["dem_wall_s"]) for r in rs)
            ps = sum(int(r["particle_steps"]) for r in rs)
            big = max(rs, key=lambda r: float(r["sum_s"]))
            md.append(f"| {soil or '(kernels, summary)'} | {sum(int(r['jobs']) for r in rs)} | {job_s:.0f} | "
                      f"{100 * job_s / tot:.0f} % | {sum(int(r['jobs']) for r in dem)} | "
                      f"{sum(float(r['sum_s']) for r in dem):.0f} | {sum(int(r['dem_runs']) for r in rs)} | "
                      f"{run_s:.0f} | {ps / 1e9:.2f} | {ps / run_s / 1e6 if run_s else float('nan'):.2f} | "
                      f"{big['rule']} ({float(big['sum_s']):.0f} s) |")
    surfaces = read_rows(OUT / "calibration_surfaces.csv", SURFACE_FIELDS)
    last = {}
    for r in surfaces:  # the last run of every soil
        last[r["soil"]] = r["run_id"]
    sel = [r for r in surfaces if last[r["soil"]] == r["run_id"]]
    if sel:
        md += ["", "Response surfaces of the last run of every soil (`calibration_surfaces.csv`): the seed "
               "scatter beside the factors' effects (seed SD: single seeds' SD pooled over the points that ran "
               "several; centre SD: the SD of the centre points, the lack-of-fit test's pure error; largest "
               "effect: 2 |b| of the full quadratic's largest linear term, coded), the full quadratic's model "
               "and lack-of-fit p:", "",
               "| soil | stage | response | commit | points | centre | seed SD | centre SD | largest effect | "
               "effect / centre SD | model p | lack of fit p |",
               "|---|---|---|---|---:|---:|---:|---:|---|---:|---:|---:|"]

        def g(x, fmt):
            return "" if x in ("", None) or pd.isna(float(x)) else format(float(x), fmt)
        for r in sel:
            md.append(f"| {r['soil']} | {r['stage']} | {r['response']} | {r['commit']} | {r['points']} | "
                      f"{r['centre_points']} | {g(r['seed_sd'], '.2f')} | {g(r['centre_sd'], '.2f')} | "
                      f"{g(r['largest_effect'], '.2f')} ({r['largest_effect_factor']}) | "
                      f"{g(r['effect_over_centre_sd'], '.1f')} | {g(r['model_p'], '.3g')} | "
                      f"{g(r['lack_of_fit_p'], '.3g')} |")
    summ = OUT / "calibration_summary.csv"
    if summ.is_file():
        df = pd.read_csv(summ)
        md += ["", f"Verification at the calibrated sets in the run of {df['utc'].iloc[0]} UTC ({df['commit'].iloc[0]}; "
               "`results/summary.csv` of that run, copied to `calibration_summary.csv`): target (photo or measured), "
               "mean and SD of the verification seeds, signed relative error, and the response surface's prediction "
               "at the calibrated set minus the target:", "",
               "| soil | stage | case | response | target | source | mean | SD | n | error % | within 2 % | "
               "surface - target | status |", "|---|---|---|---|---:|---|---:|---:|---:|---:|---|---:|---|"]
        for r in df.to_dict("records"):
            def f(x, d=2):
                return "" if pd.isna(x) else f"{float(x):.{d}f}"
            md.append(f"| {r['soil']} | {r['stage']} | {r['case']} | {r['response']} | {f(r['target'])} | "
                      f"{'' if pd.isna(r['target_source']) else r['target_source']} | {f(r['simulated_mean'])} | "
                      f"{f(r['simulated_sd'])} | {r['n']} | {f(r['relative_error_percent'], 1)} | {r['within_2_percent']} | "
                      f"{f(r['predicted_minus_target'])} | {str(r['status']).replace('|', '/')} |")
    write_page(md_path, md)


if __name__ == "__main__":
    sys.exit(main())
