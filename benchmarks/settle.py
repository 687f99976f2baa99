"""Settle benchmark matrix: soilcal's DEM engine and the reference engines in the same run.

Runs ``soilcal bench settle`` in a fresh process per case (so peak RSS is per case and the
thread count is set before any parallel launch): N = 5,000 and 20,000 spheres, 1 and 2
threads, without cohesion and with JKR (gamma = 0.3 J/m^2), 20,000 steps each; plus
N = 200,000 with a few steps for the memory footprint.  Compile time is excluded from wall_s
(each process warms up on a tiny case first).

For every case the reference engines run right after soilcal on the same configuration
(``benchmarks/reference.py``: identical positions and radii, same materials, floor, time step
and skin; 1 or 2 MPI ranks for 1 or 2 threads): LIGGGHTS 3.8 (``pair gran model hertz
tangential history rolling_friction cdt``; with cohesion its ``sjkr``, a simplified JKR that
is not the same law) and LAMMPS ``pair granular`` (``hertz/material`` or ``jkr``, tsuji
damping matched to soilcal's, mindlin, rolling sds).  The table reports the measured
throughput ratios soilcal / reference.  A reference whose binary is missing is skipped with a
note.

Usage: python benchmarks/settle.py [--steps 20000] [--big-steps 200] [--quick]
           [--engines soilcal,liggghts,lammps] [--out DIR] [--sanity]
       python benchmarks/settle.py --repeat K --case N:THREADS:COHESION [--case ...]
``--quick`` runs N = 5,000 with 2,000 steps only and, without ``--out``, writes to a fresh
temporary directory (never over benchmarks/results).

``--repeat K`` runs only the given cases, K times each, soilcal and the references
alternating (so a slow spell of the machine hits both), and writes ``settle_repeats.csv``
and ``settle_repeats.md``: every repeat's throughputs and ratio, and per case the median and
the range of the ratios.  One sample of a 2-thread case on a shared 2-core machine scatters
by about 10 %; the median of alternating repeats is the fairer comparison.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
OUT = HERE / "results"
sys.path.insert(0, str(HERE))

import reference  # noqa: E402  (benchmarks/reference.py)

ENGINES = ("soilcal", "liggghts", "lammps")
FIELDS = ["engine", "n", "steps", "threads", "cohesion", "wall_s", "cpu_s",
          "particle_steps_per_s", "peak_rss_mb", "rank_rss_mb", "engine_mem_mb", "list_builds",
          "skin_m", "ke_final_J", "erot_final_J", "bed_top_m", "load_avg_1min", "law"]
SOILCAL_LAW = {
    "none": "soilcal hertz + viscoelastic (beta, 2 sqrt(5/6)) + mindlin + constant_torque "
            "rolling (mu_r |F_n| R_i)",
    "jkr": "soilcal jkr (w = gamma, pull-off 1.5 pi w R*) + viscoelastic + mindlin + "
           "constant_torque rolling",
}
NAMES = {"soilcal": "soilcal", "liggghts": "LIGGGHTS", "lammps": "LAMMPS"}
SANITY_N = 450  # nx = 3: a 15 mm x 15 mm column of 50 layers, cheap to run to rest


def run_case(n, steps, threads, cohesion):
    exe = [sys.executable, "-m", "soilcal.cli", "bench", "settle", "--n", str(n), "--steps",
           str(steps), "--threads", str(threads), "--cohesion", cohesion]
    out = subprocess.run(exe, check=True, capture_output=True, text=True).stdout
    res = json.loads(out.strip().splitlines()[-1])
    res["engine"] = "soilcal"
    res["law"] = SOILCAL_LAW[cohesion]
    return res


def _fmt(v, spec):
    return "-" if v is None else format(v, spec)


def _ratio(a, b):
    if a is None or b is None or not b:
        return None
    return a / b


def write_tables(rows, notes, out: Path, quick: bool) -> None:
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "settle.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    by = {}
    cases = []
    for r in rows:
        key = (r["n"], r["steps"], r["threads"], r["cohesion"])
        if key not in by:
            by[key] = {}
            cases.append(key)
        by[key][r["engine"]] = r
    ours = [r for r in rows if r["engine"] == "soilcal"]
    lines = [
        "# DEM settle benchmark" + (" (quick run: N 5,000, 2,000 steps)" if quick else ""),
        "",
        _machine(),
        "Case: lattice of nx*nx*50 spheres (spacing 5 mm) settling on a floor, periodic x/y, "
        "Hertz-Mindlin + constant-torque rolling (mu_r 0.1), dt 2e-5 s; compile excluded.",
        "Each case runs soilcal and then the reference engines on the identical configuration "
        "(benchmarks/reference.py); threads = OpenMP-free MPI ranks for the references.",
        "Throughput = N * steps / loop wall time (references: the 'Loop time' line; set-up and "
        "file reading excluded, like soilcal's compile and first list build).",
        "load_avg_1min is the machine load when the case ended (other processes share the cores;",
        "MPI ranks busy-wait, so the 2-rank reference rows suffer most from a loaded machine).",
    ]
    versions = sorted({f"{NAMES[r['engine']]}: {r['version']} ({r.get('binary', '')})"
                       for r in rows if r.get("version")})
    if versions:
        lines.append("Reference engines: " + "; ".join(versions) + ".")
    lines += [
        "",
        "## Throughput, measured in this run",
        "",
        "| N | steps | threads | cohesion | soilcal p-steps/s | LIGGGHTS p-steps/s | "
        "soilcal / LIGGGHTS | LAMMPS p-steps/s | soilcal / LAMMPS | load |",
        "|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|",
    ]
    for key in cases:
        e = by[key]
        s = e.get("soilcal", {}).get("particle_steps_per_s")
        lg = e.get("liggghts", {}).get("particle_steps_per_s")
        lm = e.get("lammps", {}).get("particle_steps_per_s")
        loads = [r.get("load_avg_1min") for r in e.values() if r.get("load_avg_1min") is not None]
        coh = key[3] if key[3] == "none" else "jkr (LIGGGHTS: sjkr)"
        lines.append(f"| {key[0]} | {key[1]} | {key[2]} | {coh} | {_fmt(s, '.3g')} | "
                     f"{_fmt(lg, '.3g')} | {_fmt(_ratio(s, lg), '.2f')} | {_fmt(lm, '.3g')} | "
                     f"{_fmt(_ratio(s, lm), '.2f')} | "
                     f"{_fmt(max(loads) if loads else None, '.1f')} |")
    lines += [
        "",
        "## Same case? End state and memory",
        "",
        "Bed top = max(z + r) [m] and translational kinetic energy [J] after the last step; "
        "peak RSS of the whole run (references: largest rank x ranks).  After 2,000 steps the "
        "bed is still falling (equal values only confirm the identical start and gravity); the "
        f"N = {SANITY_N} rows run to rest and compare the settled beds.",
        "",
        "| N | steps | threads | cohesion | bed top soilcal | LIGGGHTS | LAMMPS | "
        "KE soilcal | LIGGGHTS | LAMMPS | RSS MB soilcal | LIGGGHTS | LAMMPS |",
        "|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for key in cases:
        e = by[key]
        cells = []
        for field, spec in (("bed_top_m", ".4f"), ("ke_final_J", ".3g"), ("peak_rss_mb", ".0f")):
            cells += [_fmt(e.get(k, {}).get(field), spec) for k in ENGINES]
        lines.append(f"| {key[0]} | {key[1]} | {key[2]} | {key[3]} | " + " | ".join(cells) + " |")
    if ours:
        lines += [
            "",
            "## soilcal details",
            "",
            "| N | steps | threads | cohesion | wall s | cpu s | particle-steps/s | peak RSS MB | "
            "list builds |",
            "|---:|---:|---:|---|---:|---:|---:|---:|---:|",
        ]
        for r in ours:
            lines.append(f"| {r['n']} | {r['steps']} | {r['threads']} | {r['cohesion']} | "
                         f"{r['wall_s']:.2f} | {r['cpu_s']:.2f} | "
                         f"{r['particle_steps_per_s']:.3g} | {r['peak_rss_mb']:.0f} | "
                         f"{r['list_builds']} |")
    laws = {}
    for r in rows:
        laws.setdefault((r["engine"], r["cohesion"]), r.get("law", ""))
    lines += ["", "## Contact laws", ""]
    for (eng, coh), law in sorted(laws.items()):
        lines.append(f"* {NAMES[eng]}, cohesion {coh}: {law}")
    lines += [
        "",
        "LIGGGHTS 3.8 has no JKR law: its `cohesion sjkr` (simplified JKR, force = k x overlap "
        "area, no neck beyond contact, no hysteresis) is a cheaper and different law; the JKR "
        "ratio against it is a cost reference only.  LAMMPS `jkr` is the same law as soilcal's "
        "(same pull-off), with `rolling sds` (spring-slider) instead of constant torque.  Details "
        "and parameter matching in benchmarks/reference.py.",
        "",
        "Target: soilcal at least as fast as LIGGGHTS on two threads, without and with "
        "JKR (ratio soilcal / LIGGGHTS >= 1 in the threads = 2 rows).",
    ]
    if not quick:
        lines += ["", "The large-N row runs only the first steps (free fall, almost no contacts): "
                  "it is there for peak memory, its throughput is not comparable with the "
                  "20,000-step rows.",
                  "soilcal's lists grow with the number of neighbour pairs (CSR half lists: partner "
                  "8 bytes, history 32 bytes (64 with the EPSD rolling spring), touching flag 1 "
                  "byte, twice for the rebuild); most of its RSS is the Python, NumPy and Numba "
                  "runtime (about 300 MB)."]
    if notes:
        lines += ["", "Notes from this run:", ""] + [f"* {n}" for n in notes]
    (out / "settle.md").write_text("\n".join(lines) + "\n")


def run_engines(case, engines, refs, notes) -> list[dict]:
    """Rows of one case (n, steps, threads, cohesion): soilcal (if chosen), then each
    reference engine; a failing reference or lost atoms become a note, not an abort."""
    n, st, threads, cohesion = case
    rows = []
    if "soilcal" in engines:
        t = time.time()
        res = run_case(*case)
        rows.append(res)
        print(json.dumps(res), f"# {time.time() - t:.0f} s incl. start-up", flush=True)
    for eng in refs:
        t = time.time()
        try:
            res = reference.run_reference(eng, n, st, threads, cohesion,
                                          timeout=max(600.0, n * st / 2e5))
        except Exception as exc:  # noqa: BLE001 - record and go on with the matrix
            msg = f"{NAMES[eng]} N={n} threads={threads} cohesion={cohesion} failed: " \
                  f"{str(exc).splitlines()[0]}"
            notes.append(msg)
            print("#", msg, flush=True)
            continue
        rows.append(res)
        print(json.dumps(res), f"# {time.time() - t:.0f} s incl. start-up", flush=True)
        if res.get("atoms_final") is not None and res["atoms_final"] != res["n"]:
            notes.append(f"{NAMES[eng]} N={n} threads={threads} cohesion={cohesion}: "
                         f"{res['n'] - res['atoms_final']} atoms lost.")
    return rows


def _machine() -> str:
    return (f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} logical "
            f"CPUs, Python {platform.python_version()}; date "
            f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}.")


def parse_case(text, ap):
    """'20000:2:jkr' -> (20000, 2, 'jkr'); a clear argparse error otherwise."""
    parts = text.split(":")
    try:
        n, threads, cohesion = int(parts[0]), int(parts[1]), parts[2]
        if len(parts) != 3 or n < 1 or threads < 1 or cohesion not in ("none", "jkr"):
            raise ValueError
    except (ValueError, IndexError):
        ap.error(f"--case {text!r}: expected N:THREADS:COHESION with N, THREADS >= 1 and "
                 "COHESION none or jkr, e.g. 20000:2:jkr")
    return n, threads, cohesion


def repeats(cases, steps, k, engines, refs, notes, out: Path) -> None:
    """Alternating repeats of a few cases; per-repeat ratios and their median (module doc)."""
    rows = []
    for ci, (n, threads, cohesion) in enumerate(cases):
        for rep in range(k):
            for res in run_engines((n, steps, threads, cohesion), engines, refs, notes):
                rows.append(dict(res, repeat=rep, case_index=ci))
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "settle_repeats.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["repeat"] + FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    ref_cols = [e for e in ("liggghts", "lammps") if e in refs]
    head = ["N", "steps", "threads", "cohesion", "repeat", "soilcal p-steps/s", "load"]
    for e in ref_cols:
        head += [f"{NAMES[e]} p-steps/s", f"soilcal / {NAMES[e]}"]
    lines = ["# DEM settle benchmark: alternating repeats", "", _machine(),
             f"Command: python benchmarks/settle.py --repeat {k} "
             + " ".join(f"--case {n}:{t}:{c}" for n, t, c in cases)
             + (f" --steps {steps}" if steps != 20000 else "") + ".",
             "Same case and throughput definition as settle.md; in every repeat soilcal runs "
             "first, then each reference engine, so the engines share the machine's state.", "",
             "| " + " | ".join(head) + " |", "|" + "---:|" * 3 + "---|" + "---:|" * (len(head) - 4)]
    summary = []
    for ci, (n, threads, cohesion) in enumerate(cases):
        ratios = {e: [] for e in ref_cols}
        for rep in range(k):
            got = {r["engine"]: r for r in rows if (r["case_index"], r["repeat"]) == (ci, rep)}
            n = got.get("soilcal", {}).get("n", n)  # the lattice rounds N to nx*nx*50
            s = got.get("soilcal", {}).get("particle_steps_per_s")
            load = got.get("soilcal", {}).get("load_avg_1min")
            cells = [str(n), str(steps), str(threads), cohesion, str(rep), _fmt(s, ".3g"),
                     _fmt(load, ".1f")]
            for e in ref_cols:
                p = got.get(e, {}).get("particle_steps_per_s")
                q = _ratio(s, p)
                if q is not None:
                    ratios[e].append(q)
                cells += [_fmt(p, ".3g"), _fmt(q, ".2f")]
            lines.append("| " + " | ".join(cells) + " |")
        for e in ref_cols:
            v = sorted(ratios[e])
            if v:
                med = statistics.median(v)
                summary.append(f"* N = {n}, {threads} thread(s), cohesion {cohesion}: soilcal / "
                               f"{NAMES[e]} median {med:.2f} over {len(v)} repeats (range "
                               f"{v[0]:.2f}-{v[-1]:.2f}).")
    lines += ["", "## Ratios", ""] + (summary or ["* no complete repeat"])
    if notes:
        lines += ["", "Notes from this run:", ""] + [f"* {x}" for x in notes]
    (out / "settle_repeats.md").write_text("\n".join(lines) + "\n")
    print(f"# wrote {out / 'settle_repeats.csv'} and {out / 'settle_repeats.md'}", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--big-n", type=int, default=200000)
    ap.add_argument("--big-steps", type=int, default=200)
    ap.add_argument("--quick", action="store_true",
                    help="N=5000 only, 2000 steps; writes to a temporary directory unless --out")
    ap.add_argument("--engines", default=",".join(ENGINES),
                    help="comma-separated subset of soilcal,liggghts,lammps")
    ap.add_argument("--out", default=None, help="output directory (default benchmarks/results)")
    ap.add_argument("--repeat", type=int, default=0,
                    help="run only the --case cases, this many times each, engines alternating; "
                         "writes settle_repeats.{csv,md}")
    ap.add_argument("--case", action="append", default=[], metavar="N:THREADS:COHESION",
                    help="with --repeat: a case such as 20000:2:jkr (repeatable)")
    ap.add_argument("--sanity", action="store_true",
                    help=f"with --quick: also run the N={SANITY_N} bed for --steps steps "
                         "(always part of the full run)")
    args = ap.parse_args(argv)
    engines = [e.strip() for e in args.engines.split(",") if e.strip()]
    bad = [e for e in engines if e not in ENGINES]
    if bad or not engines:
        ap.error(f"--engines: unknown {bad}; choose from {','.join(ENGINES)}")
    if args.out:
        out = Path(args.out)
    elif args.quick:
        out = Path(tempfile.mkdtemp(prefix="settle-quick-"))
    else:
        out = OUT
    notes = []
    refs = []
    for eng in ("liggghts", "lammps"):
        if eng not in engines:
            continue
        ok, what = reference.available(eng)
        if ok:
            refs.append(eng)
        else:
            notes.append(f"{NAMES[eng]} skipped: {what}.")
            print(f"# {NAMES[eng]} skipped: {what}", flush=True)
    if args.repeat or args.case:
        if args.repeat < 1 or not args.case or args.quick:
            ap.error("--repeat K (K >= 1) needs at least one --case and no --quick")
        cases = [parse_case(c, ap) for c in args.case]
        repeats(cases, args.steps, args.repeat, engines, refs, notes, out)
        return 0
    cases = []
    sizes = [5000] if args.quick else [5000, 20000]
    steps = 2000 if args.quick else args.steps
    for n in sizes:
        for cohesion in ("none", "jkr"):
            for threads in (1, 2):
                cases.append((n, steps, threads, cohesion))
    if not args.quick:
        cases.append((args.big_n, args.big_steps, 2, "none"))
    if args.sanity or not args.quick:
        # small bed run to the end (fallen and settling): end states comparable across engines
        for cohesion in ("none", "jkr"):
            cases.append((SANITY_N, args.steps, 1, cohesion))
    rows = []
    for case in cases:
        rows += run_engines(case, engines, refs, notes)
    write_tables(rows, notes, out, args.quick)
    print(f"# wrote {out / 'settle.csv'} and {out / 'settle.md'}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
