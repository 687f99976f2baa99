"""Compare two results trees table by table: is a calibration reproducible?

Two runs of the same workflow on the same inputs (two machines, a local run and a cluster
run, a run and its restart after a kill) must give the same tables.  Every ``.csv``, ``.json``
and ``.md`` file under the two roots is compared:

* byte for byte first (``identical``);
* where the bytes differ, a CSV is read and compared again without the execution columns
  (:data:`VOLATILE_COLUMNS`: the seconds a job took, whose values no two runs share, and the
  Numba thread count it ran on, which changes no number); equal that way it is
  ``identical apart from execution columns`` (the column names are listed).  Tables written
  by this version carry no such column (timings are in the logs and benchmark files), so its
  runs compare ``identical``; the columns are still recognised in trees of earlier versions;
* otherwise it ``differs``, with the first differing column and row.

A file in one tree only is ``only in A`` / ``only in B``.  Figures (PNG, SVG, PDF) carry
renderer metadata and are not compared; logs and Snakemake's benchmark files hold timings
and are skipped (:data:`SKIP_DIRS`).
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

#: Columns recording how a job ran, not what it computed: its wall-clock seconds (the DEM run
#: tables, their aggregates, the summary) and its Numba thread count.
VOLATILE_COLUMNS = ("wall_s", "dem_wall_s", "threads")
#: Compared file kinds.
SUFFIXES = (".csv", ".json", ".md")
#: Folders whose files are timings or logs, not results.
SKIP_DIRS = ("logs", "benchmarks", ".snakemake")

IDENTICAL = "identical"
VOLATILE_ONLY = "identical apart from execution columns"
DIFFERS = "differs"
ONLY_A = "only in A"
ONLY_B = "only in B"


@dataclass(frozen=True)
class FileComparison:
    path: str
    outcome: str
    detail: str = ""


def _files(root: Path) -> set[str]:
    out = set()
    for p in root.rglob("*"):
        if p.is_file() and p.suffix in SUFFIXES:
            rel = p.relative_to(root)
            if not any(part in SKIP_DIRS for part in rel.parts[:-1]):
                out.add(rel.as_posix())
    return out


def _first_difference(a: pd.DataFrame, b: pd.DataFrame) -> str:
    if list(a.columns) != list(b.columns):
        return f"columns {list(a.columns)} vs {list(b.columns)}"
    if len(a) != len(b):
        return f"{len(a)} rows vs {len(b)}"
    for c in a.columns:
        ca, cb = a[c].astype(str).to_numpy(), b[c].astype(str).to_numpy()
        bad = (ca != cb).nonzero()[0]
        if len(bad):
            i = int(bad[0])
            return f"column {c}, row {i + 1}: {ca[i]} vs {cb[i]}"
    return ""


def compare_file(a: Path, b: Path, rel: str = "") -> FileComparison:
    """Outcome of one file present in both trees (module docstring)."""
    rel = rel or a.name
    ba, bb = a.read_bytes(), b.read_bytes()
    if ba == bb:
        return FileComparison(rel, IDENTICAL)
    if a.suffix != ".csv":
        return FileComparison(rel, DIFFERS, "contents differ")
    # read every cell as text: a number printed differently is a difference
    da = pd.read_csv(io.BytesIO(ba), dtype=str, keep_default_na=False)
    db = pd.read_csv(io.BytesIO(bb), dtype=str, keep_default_na=False)
    vol = [c for c in VOLATILE_COLUMNS if c in da.columns and c in db.columns]
    diff = _first_difference(da.drop(columns=vol), db.drop(columns=vol))
    if diff or not vol:
        return FileComparison(rel, DIFFERS, diff or "contents differ")
    # name the execution columns whose values differ
    changed = [c for c in vol if len(da) != len(db) or (da[c].to_numpy() != db[c].to_numpy()).any()]
    return FileComparison(rel, VOLATILE_ONLY, ", ".join(changed))


def compare_trees(a, b) -> list[FileComparison]:
    """One :class:`FileComparison` per compared file of the two trees, sorted by path."""
    a, b = Path(a), Path(b)
    fa, fb = _files(a), _files(b)
    out = []
    for rel in sorted(fa | fb):
        if rel not in fb:
            out.append(FileComparison(rel, ONLY_A))
        elif rel not in fa:
            out.append(FileComparison(rel, ONLY_B))
        else:
            out.append(compare_file(a / rel, b / rel, rel))
    return out


def same_results(comparisons) -> bool:
    """True when every file is identical or differs only in its execution columns."""
    return all(c.outcome in (IDENTICAL, VOLATILE_ONLY) for c in comparisons)


def summary(comparisons) -> dict[str, int]:
    """Count of files per outcome."""
    out: dict[str, int] = {}
    for c in comparisons:
        out[c.outcome] = out.get(c.outcome, 0) + 1
    return out
