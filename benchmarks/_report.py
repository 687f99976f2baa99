"""Shared helpers of the benchmark scripts: commit id, CSV rows kept across runs, the notes
below a results page's marker (hand-written, kept when the table is regenerated)."""

from __future__ import annotations

import csv
import os
import subprocess
from pathlib import Path

HERE = Path(__file__).resolve().parent
NOTES = "<!-- notes: kept when the table is regenerated -->"


def commit() -> str:
    """Short id of the checked-out commit, with ``+dirty`` when tracked files differ from it
    ('' outside a git checkout)."""
    try:
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=HERE,
                             capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
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


def write_rows(path: Path, rows, fields) -> None:
    """Write the table to a temporary file beside ``path`` and move it into place, so an
    interrupted write leaves the previous table whole."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(fields), extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    os.replace(tmp, path)


def kept_notes(md_path: Path) -> str:
    """The marker line and the notes below it, to end a regenerated page with."""
    notes = ""
    if md_path.exists() and NOTES in md_path.read_text():
        notes = md_path.read_text().split(NOTES, 1)[1]
    return NOTES + notes.rstrip("\n")
