"""Broken-input corpus: what a user sees for every case of ``tests/corpus/cases.py``.

Each case (a broken soil YAML, printed table, measured table, photo or manifest, scenario
setting, command-line argument or workflow config, built into a temporary folder from a
shipped soil) is run as the user runs it, ``python -m soilcal.cli ...`` in a subprocess, and
judged by ``tests/corpus/runner.py``: ``clear`` = exactly one ``soilcal: error:`` line naming
the file, the field and what was expected, exit status 2, no traceback, the output folder
unchanged; otherwise ``traceback``, ``accepted`` (no error: the broken input was used),
``half-written`` (outputs written beside an error), ``wrong exit status`` or ``unclear
message``.  Written: ``benchmarks/results/broken_inputs.csv`` (one row per case: case, input
kind, file, expected field, outcome, exit code, the one-line message, what was unclear) and
``broken_inputs.md`` (counts by kind and outcome; notes below its marker are kept).

``--before SRC`` also runs every case on another source tree's package (e.g. an export of an
earlier commit: ``git archive HEAD src | tar -x -C /tmp/before``) and adds its outcome, exit
code and first stderr line as ``before_outcome``, ``before_exit_code`` and ``before_message``.

    python benchmarks/broken_inputs.py [--jobs 2] [--before /tmp/before/src] [--out DIR]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from _report import commit, write_page, write_rows

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from corpus.cases import CASES, KINDS  # noqa: E402
from corpus.runner import command, outcome_label, problems, run_subprocess  # noqa: E402

FIELDS = ["case", "kind", "file", "field", "expected", "outcome", "exit_code", "message", "problems", "seconds",
          "before_outcome", "before_exit_code", "before_message"]
OUTCOMES = ("clear", "unclear message", "wrong exit status", "half-written", "accepted", "traceback")


def _run(case, src: str | None = None):
    """(outcome, exit code, message, problems, seconds) of one case in a fresh folder."""
    with tempfile.TemporaryDirectory(prefix="broken-input-") as d:
        tmp = Path(d)
        cmd, before = command(case, tmp)
        t = time.perf_counter()
        o = run_subprocess(case, tmp, cmd, before, pythonpath=src)
        seconds = time.perf_counter() - t
    probs = problems(case, o)
    return outcome_label(probs, o), o.code, o.message, "; ".join(probs), seconds


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=2, help="cases run at a time (default 2)")
    ap.add_argument("--before", metavar="SRC", help="also run every case on this source tree's package")
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        results = dict(zip([c.id for c in CASES], pool.map(_run, CASES)))
        if args.before:
            src = str(Path(args.before).resolve())
            before = dict(zip([c.id for c in CASES], pool.map(lambda c: _run(c, src), CASES)))
    rows = []
    for c in CASES:
        outcome, code, message, probs, seconds = results[c.id]
        row = {"case": c.id, "kind": c.kind, "file": c.file, "field": c.field, "expected": c.expected,
               "outcome": outcome, "exit_code": code, "message": message, "problems": probs,
               "seconds": f"{seconds:.2f}"}
        if args.before:
            row["before_outcome"], row["before_exit_code"], row["before_message"] = before[c.id][:3]
        rows.append(row)
    write_rows(out / "broken_inputs.csv", rows, FIELDS)

    counts = Counter((r["kind"], r["outcome"]) for r in rows)
    md = ["# Broken inputs: one clear line for every case", "",
          f"{len(rows)} cases of `tests/corpus/cases.py`, each run as `python -m soilcal.cli ...` in a subprocess "
          f"({args.jobs} at a time, {time.perf_counter() - started:.0f} s); commit {commit()}, "
          f"{time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC.  `clear`: exactly one `soilcal: error:` line "
          "naming the file, the field and what was expected, exit status 2, no traceback, the output folder "
          "unchanged.  Rows: `broken_inputs.csv`.", "",
          "| kind | cases | " + " | ".join(OUTCOMES) + " |", "|---|---:|" + "---:|" * len(OUTCOMES)]
    for k in KINDS:
        n = sum(1 for r in rows if r["kind"] == k)
        md.append(f"| {k} | {n} | " + " | ".join(str(counts.get((k, o), 0)) for o in OUTCOMES) + " |")
    total = Counter(r["outcome"] for r in rows)
    md.append(f"| all | {len(rows)} | " + " | ".join(str(total.get(o, 0)) for o in OUTCOMES) + " |")
    if args.before:
        was = Counter(r["before_outcome"] for r in rows)
        md += ["", f"On `{args.before}` (before): " + ", ".join(f"{was.get(o, 0)} {o}" for o in OUTCOMES) + "; "
               f"{sum(1 for r in rows if r['before_outcome'] != 'clear' and r['outcome'] == 'clear')} cases clear now "
               "that were not.", "",
               "| case | kind | before | before exit | now |", "|---|---|---|---:|---|"]
        md += [f"| {r['case']} | {r['kind']} | {r['before_outcome']} | {r['before_exit_code']} | {r['outcome']} |"
               for r in rows if r["before_outcome"] != r["outcome"]]
    bad = [r for r in rows if r["outcome"] != "clear"]
    if bad:
        md += ["", "Cases that are not clear:", "", "| case | kind | outcome | problems |", "|---|---|---|---|"]
        md += [f"| {r['case']} | {r['kind']} | {r['outcome']} | {r['problems']} |" for r in bad]
    write_page(out / "broken_inputs.md", md)
    print(f"{len(rows)} cases: " + ", ".join(f"{total.get(o, 0)} {o}" for o in OUTCOMES))
    return 0 if not bad else 1


if __name__ == "__main__":
    sys.exit(main())
