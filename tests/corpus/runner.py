"""Running a broken-input case (:mod:`corpus.cases`) and judging what the user saw.

``run_in_process`` calls :func:`soilcal.cli.main` in this process (its stdout and stderr
captured), ``run_subprocess`` runs ``python -m soilcal.cli`` (the exit status the shell sees),
``run_snakemake`` a dry run of a copy of the workflow.  ``problems`` lists everything that
makes the outcome unclear: not exactly one ``soilcal: error:`` line, the file, field or
expectation not named, a traceback, an exit status other than 2, a changed output folder.
"""

from __future__ import annotations

import contextlib
import io
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from corpus.cases import ROOT, Case

PREFIX = "soilcal: error: "


@dataclass
class Outcome:
    code: int | None
    stdout: str
    stderr: str
    before: dict
    after: dict

    @property
    def lines(self) -> list[str]:
        return [ln for ln in self.stderr.splitlines() if ln.strip()]

    @property
    def message(self) -> str:
        """The error line (the first stderr line when there is not exactly one)."""
        lines = self.lines
        return lines[0] if lines else ""


def listing(folder: Path) -> dict:
    """Every file under ``folder`` with its size and modification time (empty if absent)."""
    if not folder.exists():
        return {}
    out = {}
    for p in sorted(folder.rglob("*")):
        st = p.stat()
        out[str(p.relative_to(folder))] = (p.is_dir(), 0 if p.is_dir() else st.st_size, st.st_mtime_ns)
    return out


def run_in_process(case: Case, tmp: Path) -> Outcome:
    from soilcal.cli import main

    argv = case.build(tmp)
    before = listing(tmp / case.out)
    out, err = io.StringIO(), io.StringIO()
    cwd = os.getcwd()
    os.chdir(tmp)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exc:
                code = exc.code
    finally:
        os.chdir(cwd)
    return Outcome(code, out.getvalue(), err.getvalue(), before, listing(tmp / case.out))


def command(case: Case, tmp: Path) -> tuple[list[str], dict]:
    """(command line, before-listing) of a case whose inputs are built under ``tmp``."""
    argv = case.build(tmp)
    return [sys.executable, "-m", "soilcal.cli", *argv], listing(tmp / case.out)


def run_subprocess(case: Case, tmp: Path, cmd=None, before=None, timeout=300, pythonpath: str | None = None) -> Outcome:
    """``python -m soilcal.cli`` on a case (built now unless ``cmd`` is given); ``pythonpath``
    puts another source tree's package first."""
    if cmd is None:
        cmd, before = command(case, tmp)
    env = dict(os.environ)
    env.setdefault("NUMBA_CACHE_DIR", str(ROOT / ".numba_cache"))
    if pythonpath:
        env["PYTHONPATH"] = pythonpath + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    p = subprocess.run(cmd, cwd=tmp, capture_output=True, text=True, env=env, timeout=timeout)
    return Outcome(p.returncode, p.stdout, p.stderr, before, listing(tmp / case.out))


def problems(case: Case, o: Outcome, exit_code: int | None = 2) -> list[str]:
    """What is unclear about a case's outcome (empty: one clear line, status 2, nothing written)."""
    out = []
    if exit_code is not None and o.code != exit_code:
        out.append(f"exit status {o.code}, not {exit_code}")
    if "Traceback" in o.stderr or "Traceback" in o.stdout:
        out.append("a traceback")
    lines = o.lines
    if len(lines) != 1:
        out.append(f"{len(lines)} lines on stderr, not one")
    line = o.message
    if not line.startswith(PREFIX):
        out.append("no 'soilcal: error:' line")
    if case.file not in line:
        out.append(f"file {case.file!r} not named")
    if f"{case.field}: expected " not in line:
        out.append(f"field {case.field!r} not named")
    elif case.expected not in line.split(f"{case.field}: expected ", 1)[1]:
        out.append(f"expected {case.expected!r} not said")
    if o.after != o.before:
        added = sorted(set(o.after) - set(o.before))
        out.append("output folder changed" + (f" ({', '.join(added[:3])})" if added else ""))
    return out


def outcome_label(probs: list[str], o: Outcome | None = None) -> str:
    """One word for a case's outcome: clear, traceback, accepted (no error at all: the broken
    input was used), half-written, wrong exit status or unclear message."""
    if not probs:
        return "clear"
    if any("traceback" in p for p in probs):
        return "traceback"
    if o is not None and o.code == 0 and not o.message.startswith(PREFIX):
        return "accepted"
    if any("output folder" in p for p in probs):
        return "half-written"
    if any("exit status" in p for p in probs):
        return "wrong exit status"
    return "unclear message"
