"""One soil's DEM calibration through a real SLURM cluster against the same run on the local
machine: the same tables (same seeds, same numbers), and a cluster run killed midway that
resumes with the jobs it left.

Needs a running SLURM (``sudo benchmarks/slurm/single_node.sh`` starts a one-node cluster on
this machine) and ``pip install snakemake-executor-plugin-slurm``.  Two fresh copies of the
workflow are made with the tiny run of the workflow tests (``tests/wfutil.make_tiny``: the
cinnamon soil calibrated on heaps of 300 spheres and replayed from its printed tables):

1. ``snakemake --cores 2`` in the first (the local run);
2. ``snakemake --profile profiles/slurm`` in the second, killed with SIGKILL after
   ``--kill-after`` seconds (its queued SLURM jobs cancelled, as a lost login node would leave
   them), then ``--unlock`` and the same command again (the resumed run);
3. ``soilcal compare`` of the two results/ trees.

Rows go to ``benchmarks/results/slurm_runs.csv`` (one per workflow run) and
``slurm_files.csv`` (file outcomes per comparison); ``slurm.md`` is the page.

    python benchmarks/slurm.py                  # kill the cluster run after 240 s
    python benchmarks/slurm.py --kill-after 0   # no kill
    python benchmarks/slurm.py --local          # no cluster: the second run is local too

``--local`` needs no SLURM: the second run is ``snakemake --cores 2`` as well (killed and
resumed the same way), so the comparison says whether two complete runs of the same inputs
from an empty results/ give byte-identical tables; its rows go to ``reproducible_runs.csv``,
``reproducible_files.csv`` and ``reproducible.md``.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _report import commit, read_rows, runs_table, write_page, write_rows

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OUT = HERE / "results"
sys.path.insert(0, str(ROOT / "tests"))
from wfutil import TINY_SOILS, copy_workflow, make_tiny  # noqa: E402

from soilcal.chain.compare import compare_trees, same_results, summary  # noqa: E402

SNAKEMAKE = [sys.executable, "-m", "snakemake"]
#: what both comparisons run
TINY_RUN = ("The run: the tiny calibration of the workflow tests (cinnamon soil on heaps of 300 "
            "spheres through screening, path, Box-Behnken, verification, plate tests and the "
            "measured-data loop; its printed tables replayed)")
RUN_FIELDS = ["utc", "commit", "run_id", "kind", "command", "elapsed_s", "jobs_done", "rc", "note"]
FILE_FIELDS = ["utc", "commit", "run_id", "outcome", "files", "example"]


def jobs_done(log_text: str) -> int:
    return log_text.count("Finished jobid")


def timed(cmd, cwd, log: Path, kill_after: float = 0.0) -> tuple[float, int, str]:
    """Run ``cmd`` in ``cwd`` (output to ``log``); with ``kill_after`` > 0 send SIGKILL to it
    (and its children on this host) after that many seconds.  Returns (seconds, rc, output)."""
    t0 = time.perf_counter()
    with open(log, "w") as fh:
        p = subprocess.Popen(cmd, cwd=cwd, stdout=fh, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            rc = p.wait(timeout=kill_after if kill_after > 0 else None)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            rc = p.wait()
    return time.perf_counter() - t0, rc, log.read_text()


def cancel_jobs(workdir: Path) -> int:
    """Cancel the SLURM jobs a killed run left queued or running: those whose working
    directory is the run's copy."""
    out = subprocess.run(["squeue", "-h", "-o", "%i %Z"], capture_output=True, text=True).stdout
    ids = [line.split()[0] for line in out.splitlines()
           if len(line.split()) > 1 and Path(line.split()[1]).resolve() == workdir.resolve()]
    if ids:
        subprocess.run(["scancel", *ids], check=False)
    return len(ids)


def cluster_ready() -> str:
    try:
        p = subprocess.run(["sinfo", "-h", "-o", "%T"], capture_output=True, text=True, timeout=20)
    except (OSError, subprocess.SubprocessError) as exc:
        return f"sinfo failed: {exc}"
    if p.returncode != 0 or not p.stdout.strip():
        return f"no SLURM cluster answers ({p.stderr.strip() or 'no nodes'})"
    try:
        import snakemake_executor_plugin_slurm  # noqa: F401
    except ImportError:
        return "snakemake-executor-plugin-slurm is not installed"
    return ""


class Session:
    """One benchmark run: its folder, its identity (utc, commit, run id), its workflow-run rows
    (:meth:`row`) and the saving of the rows and of a comparison's file outcomes."""

    def __init__(self, workdir, prefix):
        self.base = Path(workdir or tempfile.mkdtemp(prefix=prefix))
        self.base.mkdir(parents=True, exist_ok=True)
        now = datetime.datetime.now(datetime.timezone.utc)
        self.utc, self.run_id = now.strftime("%Y-%m-%d %H:%M"), now.strftime("%Y%m%dT%H%M%S")
        self.rev = commit()
        self.env_note = f"{platform.machine()}, {os.cpu_count()} logical CPUs, Python {platform.python_version()}"
        self.runs = []

    def row(self, kind, command, sec, rc, text, note=""):
        r = dict(utc=self.utc, commit=self.rev, run_id=self.run_id, kind=kind, command=command,
                 elapsed_s=round(sec, 1), jobs_done=jobs_done(text), rc=rc, note=note)
        self.runs.append(r)
        print(r, flush=True)

    def save(self, stem, comps):
        """Append this run's rows and the comparison's outcomes to ``<stem>_runs.csv`` and
        ``<stem>_files.csv``; returns every row of both."""
        files = []
        for outcome, n in summary(comps).items():
            ex = next(c for c in comps if c.outcome == outcome)
            files.append(dict(utc=self.utc, commit=self.rev, run_id=self.run_id, outcome=outcome, files=n,
                              example=f"{ex.path} ({ex.detail})" if ex.detail else ex.path))
        OUT.mkdir(exist_ok=True)
        all_runs = read_rows(OUT / f"{stem}_runs.csv", RUN_FIELDS) + self.runs
        all_files = read_rows(OUT / f"{stem}_files.csv", FILE_FIELDS) + files
        write_rows(OUT / f"{stem}_runs.csv", all_runs, RUN_FIELDS)
        write_rows(OUT / f"{stem}_files.csv", all_files, FILE_FIELDS)
        return all_runs, all_files

    def run_killed(self, cmd, cwd, name, command, kill_after, after_kill=None):
        """``cmd`` in ``cwd`` from its start; with ``kill_after`` > 0 killed with SIGKILL after
        that many seconds (``after_kill()``: what else the kill needs, said in the row's note),
        unlocked and run again to its end.  One row per run, kinds ``name``, ``name, killed``
        and ``name, resumed``."""
        if kill_after > 0:
            sec, rc, text = timed(cmd, cwd, self.base / f"{name}_killed.log", kill_after)
            extra = after_kill() if after_kill else ""
            self.row(f"{name}, killed", command, sec, rc, text, f"SIGKILL after {kill_after:g} s{extra}")
            subprocess.run(SNAKEMAKE + ["--unlock", "--cores", "1"], cwd=cwd, capture_output=True)
            sec, rc, text = timed(cmd, cwd, self.base / f"{name}_resumed.log")
            self.row(f"{name}, resumed", f"snakemake --unlock; {command}", sec, rc, text)
        else:
            sec, rc, text = timed(cmd, cwd, self.base / f"{name}.log")
            self.row(name, command, sec, rc, text)

    def page(self, stem, title, intro, compared, all_runs, all_files):
        """``<stem>.md``: the title, the machine and ``intro``, the workflow runs and the file
        outcomes (``compared`` says what was compared)."""
        write_page(OUT / f"{stem}.md", [
            f"# {title}", "", f"Machine: {self.env_note}.  {intro}", "",
            "Workflow runs (elapsed: wall-clock seconds of the command; jobs: jobs Snakemake "
            "reports finished):", "", *runs_table(all_runs, RUN_FIELDS), "",
            f"{compared}:", "", *runs_table(all_files, FILE_FIELDS), ""])



def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kill-after", type=float, default=240.0, help="seconds before the cluster run is killed (0: no kill)")
    ap.add_argument("--workdir", default=None, help="folder for the two workflow copies (default: a new temporary one)")
    ap.add_argument("--local", action="store_true", help="second run on this machine too (no SLURM needed)")
    args = ap.parse_args(argv)
    if args.local:
        return local_twice(args)
    why = cluster_ready()
    if why:
        print(f"slurm.py: {why}; start one with `sudo benchmarks/slurm/single_node.sh`", file=sys.stderr)
        return 2
    ses = Session(args.workdir, "soilcal-slurm-")
    base, runs, row = ses.base, ses.runs, ses.row

    local = make_tiny(copy_workflow(_fresh(base / "local"), TINY_SOILS))
    sec, rc, text = timed(SNAKEMAKE + ["--cores", "2"], local, base / "local.log")
    row("local", "snakemake --cores 2", sec, rc, text)

    cluster = make_tiny(copy_workflow(_fresh(base / "slurm"), TINY_SOILS))
    cmd = SNAKEMAKE + ["--profile", "profiles/slurm"]
    ses.run_killed(cmd, cluster, "slurm", "snakemake --profile profiles/slurm", args.kill_after,
                   lambda: f"; {cancel_jobs(cluster)} SLURM jobs cancelled")
    dry = subprocess.run(SNAKEMAKE + ["-n", "--profile", "profiles/slurm"], cwd=cluster, capture_output=True,
                         text=True)
    left = "Nothing to be done" in dry.stdout + dry.stderr
    row("slurm, second run (dry)", "snakemake -n --profile profiles/slurm", 0.0, dry.returncode,
        "", "nothing to do" if left else "jobs left: " + dry.stdout[-300:].replace("\n", " "))

    comps = compare_trees(local / "results", cluster / "results")
    verdict = "same results" if same_results(comps) else "the results differ"
    print(f"{len(comps)} files compared: {verdict}", flush=True)
    all_runs, all_files = ses.save("slurm", comps)
    sinfo = subprocess.run(["sinfo", "-h", "-o", "%N %c CPUs %m MB %P"], capture_output=True, text=True).stdout.strip()
    version = subprocess.run(["sinfo", "--version"], capture_output=True, text=True).stdout.strip()
    kill = f" --kill-after {args.kill_after:g}" if args.kill_after != 240 else ""
    ses.page("slurm", "One soil's DEM calibration on a real SLURM cluster against the local run",
             f"Cluster: {version}, node `{sinfo}` (`benchmarks/slurm/single_node.sh`).  Command: "
             f"`python benchmarks/slurm.py{kill}`.  {TINY_RUN}.",
             "Local results/ against the cluster's, file by file (`soilcal compare`; execution "
             "columns: a job's wall-clock seconds and thread count, in tables of earlier versions)",
             all_runs, all_files)
    return 0 if same_results(comps) and all(r["rc"] == 0 for r in runs if r["kind"] != "slurm, killed") else 1


def local_twice(args) -> int:
    """Two complete local runs from an empty results/, the second killed and resumed when
    ``--kill-after`` > 0, compared file by file (``--local``)."""
    ses = Session(args.workdir, "soilcal-repro-")
    base, runs, row = ses.base, ses.runs, ses.row

    cmd = SNAKEMAKE + ["--cores", "2"]
    first = make_tiny(copy_workflow(_fresh(base / "first"), TINY_SOILS))
    sec, rc, text = timed(cmd, first, base / "first.log")
    row("first", "snakemake --cores 2", sec, rc, text)
    second = make_tiny(copy_workflow(_fresh(base / "second"), TINY_SOILS))
    ses.run_killed(cmd, second, "second", "snakemake --cores 2", args.kill_after)
    comps = compare_trees(first / "results", second / "results")
    identical = all(c.outcome == "identical" for c in comps)
    print(f"{len(comps)} files compared: {'byte-identical' if identical else 'not all byte-identical'}", flush=True)
    all_runs, all_files = ses.save("reproducible", comps)
    kill = f" --kill-after {args.kill_after:g}" if args.kill_after != 240 else ""
    ses.page("reproducible", "Two complete runs of the same inputs from an empty results/",
             f"Command: `python benchmarks/slurm.py --local{kill}`.  {TINY_RUN}; the second run "
             "is killed with SIGKILL and resumed after `snakemake --unlock`.",
             "The first run's results/ against the second's, file by file (`soilcal compare`; "
             "`identical` is byte for byte; figures are not compared)", all_runs, all_files)
    return 0 if identical and all(r["rc"] == 0 for r in runs if r["kind"] != "second, killed") else 1


def _fresh(path: Path) -> Path:
    import shutil

    if path.exists():
        shutil.rmtree(path)
    path.mkdir(parents=True)
    return path


if __name__ == "__main__":
    sys.exit(main())
