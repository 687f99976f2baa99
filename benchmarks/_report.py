"""Shared helpers of the benchmark scripts: commit id, CSV rows kept across runs, the notes
below a results page's marker (hand-written, kept when the table is regenerated)."""

from __future__ import annotations

import csv
import os
from contextlib import contextmanager
import subprocess
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
NOTES = "<!-- notes: kept when the table is regenerated -->"


def corpus_args(doc, n, argv, extra=None):
    """Arguments of a photo-corpus benchmark: --n photos, --seed of the corpus, --out folder,
    --jobs photos measured at a time (processes); ``extra(parser)`` adds a benchmark's own."""
    import argparse

    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--n", type=int, default=n)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=str(HERE / "results"))
    ap.add_argument("--jobs", type=int, default=1)
    if extra is not None:
        extra(ap)
    return ap.parse_args(argv)


def _corpus_one(task):
    """One photo of :func:`corpus_rows`: render, measure, time (a worker process's unit)."""
    import time

    from soilcal.errors import InputError

    k, p, write, truth_row, measured_row, tmp, stem = task
    path, truth = write(p, tmp, f"{stem}{k:04d}")
    row = dict(photo=k, **truth_row(truth))
    t0 = time.perf_counter()
    try:
        row.update(measured_row(path, truth))
    except InputError as e:
        row["refusal"] = str(e).split(": ", 1)[-1].replace("|", "/")
    row["seconds"] = round(time.perf_counter() - t0, 2)
    Path(path).unlink(missing_ok=True)
    return row


def corpus_rows(params, write, truth_row, measured_row, stem="photo", jobs=1):
    """Render every parameter set of a photo corpus (``write(params, folder, name)`` -> (path,
    truth)) into a temporary folder and measure it: one row per photo with ``photo``, the
    truth's fields (``truth_row(truth)``), the measured fields (``measured_row(path, truth)``)
    or the refusal (the InputError's text after the file name) and the seconds the measurement
    took, in photo order; ``jobs`` photos at a time (forked processes: the three callables must
    be module-level functions).  Returns (rows, wall seconds)."""
    import multiprocessing
    import time
    from concurrent.futures import ProcessPoolExecutor

    t_all = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        tasks = [(k, p, write, truth_row, measured_row, tmp, stem) for k, p in enumerate(params)]
        if jobs <= 1:
            rows = [_corpus_one(t) for t in tasks]
        else:
            with ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("fork")) as ex:
                rows = list(ex.map(_corpus_one, tasks))
    return rows, time.perf_counter() - t_all


def run_header(script, argv, what: str) -> str:
    """The first line of a results page: machine, commit, time, the command
    (``python benchmarks/<script> <argv>``) and ``what`` in brackets after it (its wall time)."""
    import platform
    import time

    return (f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs, Python {platform.python_version()}; "
            f"commit {commit()}, {time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC; "
            f"`python benchmarks/{script} {' '.join(str(a) for a in argv)}` ({what})")


def corpus_header(script, argv, n, seed, wall):
    """The first line of a photo-corpus page: machine, commit, time, command, photos, wall time."""
    return run_header(script, argv, f"{n} photos, seed {seed}, {wall:.0f} s") + "."


def percentile_text(a, p, digits):
    """The ``p``-th percentile of ``a`` with ``digits`` decimals, "" for an empty array."""
    import numpy as np

    return f"{np.percentile(a, p):.{digits}f}" if len(a) else ""


def confidence_table(rows, key, tight, loose, pct, digits, header):
    """Markdown table of a photo-corpus run's accuracy (|``key``| of each measured row) for all
    measured photos and by confidence: count, share of all photos, shares within ``tight`` and
    ``loose``, count above ``loose``, median, ``pct``-th percentile and largest error;
    ``header`` the table's first line."""
    import numpy as np

    n = len(rows)
    meas = [r for r in rows if r.get(key, "") != ""]
    table = [header, "|---|---|---|---|---|---|---|---|---|"]
    for label, sel in (("measured", meas), ("measured, confidence ok", [r for r in meas if r["confidence"] == "ok"]),
                       ("measured, confidence low", [r for r in meas if r["confidence"] == "low"])):
        e = np.array([abs(r[key]) for r in sel])
        table.append(f"| {label} | {len(sel)} | {len(sel) / n:.1%} | {np.mean(e <= tight) if e.size else 0:.1%} | "
                     f"{np.mean(e <= loose) if e.size else 0:.1%} | {int(np.sum(e > loose))} | "
                     f"{percentile_text(e, 50, digits)} | {percentile_text(e, pct, digits)} | "
                     f"{percentile_text(e, 100, digits)} |")
    return table


def refusal_line(rows, n_measured):
    """"Refused: k of n (share): <count> x <reason>; ..." of a photo-corpus run."""
    from collections import Counter

    n = len(rows)
    refusals = Counter(r["refusal"] for r in rows if r.get("refusal"))
    return (f"Refused: {n - n_measured} of {n} ({(n - n_measured) / n:.1%}): "
            + ("; ".join(f"{c} x {m}" for m, c in refusals.most_common()) or "none") + ".")


def seed_list(text: str) -> list[int]:
    """Seeds from a command-line list: ``0-5``, ``0,2,4`` or both (``0-2,7``)."""
    out = []
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        a, _, b = part.partition("-")
        out += list(range(int(a), int(b) + 1)) if b else [int(a)]
    return out


def run_cases(one, cases, rev, csv_path, fields, keyof, jobs, show=()):
    """Run ``one(*case, rev)`` for every case, ``jobs`` processes at a time, each result a row
    replacing the kept row of the same ``keyof``; the CSV is rewritten after every row (a
    stopped run keeps what it finished).  Returns every row, kept and new."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    rows = {keyof(r): r for r in read_rows(csv_path, fields)}
    # fresh interpreters: a forked child of a process whose Numba kernels already ran on
    # GNU OpenMP threads aborts
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=max(1, jobs), mp_context=ctx) as ex:
        for r in ex.map(one, *zip(*cases), [rev] * len(cases)):
            rows[keyof(r)] = r
            print({k: r[k] for k in show} if show else r, flush=True)
            write_rows(csv_path, list(rows.values()), fields)
    return list(rows.values())


def commit() -> str:
    """Short id of the checked-out commit, with ``+dirty`` when tracked files outside
    ``benchmarks/results`` differ from it ('' outside a git checkout)."""
    try:
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=HERE,
                             capture_output=True, text=True, check=True).stdout.strip()
        # results tables rewritten by a sweep do not make the code dirty
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--",
                                ":/", ":(top,exclude)benchmarks/results"],
                               cwd=HERE, capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return ""
    return rev + ("+dirty" if dirty.strip() else "")


def read_rows(path: Path, fields) -> list[dict]:
    """Earlier rows of a results table (columns they lack are left empty)."""
    if not path.exists():
        return []
    with open(path, newline="") as fh:
        return [{k: r.get(k, "") for k in fields} for r in csv.DictReader(fh)]


@contextmanager
def _replacing(path):
    """A text file to write in place of ``path``: written to a temporary file beside it,
    given the mode of a newly created file (tempfile makes it 0600) and moved into place,
    so an interrupted write leaves the previous file whole."""
    path = Path(path)
    with tempfile.NamedTemporaryFile("w", newline="", dir=path.parent, prefix=path.name,
                                     suffix=".tmp", delete=False) as fh:
        yield fh
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(fh.name, 0o666 & ~umask)
    os.replace(fh.name, path)


def write_rows(path: Path, rows, fields) -> None:
    """Write the table atomically (:func:`_replacing`)."""
    with _replacing(path) as fh:
        w = csv.DictWriter(fh, fieldnames=list(fields), extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


def spread_and_correlation(printed, simulated):
    """(printed spread, simulated spread, Pearson correlation) over the pairs where both are
    finite: spreads as max - min ('' when no pair), the correlation as text ('' for fewer
    than three pairs or a constant side)."""
    import numpy as np

    p = np.asarray(printed, dtype=float)
    s = np.asarray(simulated, dtype=float)
    good = np.isfinite(p) & np.isfinite(s)
    p, s = p[good], s[good]
    if not len(p):
        return "", "", ""
    corr = f"{np.corrcoef(p, s)[0, 1]:.2f}" if len(p) > 2 and p.std() > 0 and s.std() > 0 else ""
    return f"{np.ptp(p):.2f}", f"{np.ptp(s):.2f}", corr


def runs_table(rows, fields) -> list[str]:
    """Markdown lines of a table with one row per run, every field a column."""
    return ["| " + " | ".join(fields) + " |", "|" + "---|" * len(fields),
            *("| " + " | ".join(str(r.get(k, "")) for k in fields) + " |" for r in rows)]


def write_page(md_path: Path, lines) -> None:
    """Write a results page: ``lines``, then the notes kept below its marker; atomically,
    like :func:`write_rows`."""
    md_path = Path(md_path)
    text = "\n".join(list(lines) + ["", kept_notes(md_path)]) + "\n"
    with _replacing(md_path) as fh:
        fh.write(text)


def write_rows_page(md_path: Path, lines, rows_file: str) -> None:
    """A results page ending with the line that names its rows file: written
    (:func:`write_page`) and printed."""
    lines = list(lines) + ["", f"Rows: `{rows_file}`."]
    write_page(md_path, lines)
    print("\n".join(lines))


def kept_notes(md_path: Path) -> str:
    """The marker line and the notes below it, to end a regenerated page with."""
    notes = ""
    if md_path.exists() and NOTES in md_path.read_text():
        notes = md_path.read_text().split(NOTES, 1)[1]
    return NOTES + notes.rstrip("\n")


def seed_and_ranges(seed, groups, fmt=".3f") -> list[str]:
    """Cells of a convergence summary row: the number of seeds, their mean and sample SD,
    then for each group of values over one factor's levels its range (max - min) and, in
    brackets, the range over the seed SD.  ``seed`` and ``groups`` hold finite values."""
    import numpy as np

    sd = float(np.std(seed, ddof=1))
    cells = [str(len(seed)), f"{np.mean(seed):{fmt}}", f"{sd:{fmt}}"]
    for v in groups:
        if len(v) < 2:
            cells.append("")
            continue
        rng = float(np.ptp(v))
        cells.append(f"{rng:{fmt}} ({rng / sd:.1f})" if sd > 0 else f"{rng:{fmt}}")
    return cells
