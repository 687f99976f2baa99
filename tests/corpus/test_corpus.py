"""Every broken input of the corpus (tests/corpus/cases.py) stops soilcal with one clear line.

Each case is run through :func:`soilcal.cli.main` in this process; the cases marked
``subprocess`` also as ``python -m soilcal.cli`` (the exit status and output a shell sees), and
the workflow-level ones marked ``snakemake`` through a dry run of a copy of the workflow.
"""

from __future__ import annotations

import shutil
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import yaml

from corpus.cases import CASES, KINDS, ROOT
from corpus.runner import command, problems, run_in_process, run_subprocess
from wfutil import run as snakemake

SUBPROCESS = [c for c in CASES if c.subprocess]
SNAKEMAKE = [c for c in CASES if c.snakemake]


def test_corpus_covers_every_kind():
    assert len(CASES) >= 60
    assert {c.kind for c in CASES} == set(KINDS)
    assert {c.kind for c in SUBPROCESS} == set(KINDS) and len(SUBPROCESS) >= 15


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_one_clear_line_and_nothing_written(case, tmp_path):
    o = run_in_process(case, tmp_path)
    assert not problems(case, o), (problems(case, o), o.stderr, o.stdout[-2000:])


@pytest.fixture(scope="module")
def subprocess_outcomes(tmp_path_factory):
    """Every subprocess case, run four at a time."""
    jobs = {}
    for c in SUBPROCESS:
        tmp = tmp_path_factory.mktemp(c.id)
        jobs[c.id] = (c, tmp, *command(c, tmp))
    with ThreadPoolExecutor(max_workers=4) as pool:
        futures = {cid: pool.submit(run_subprocess, c, tmp, cmd, before) for cid, (c, tmp, cmd, before) in jobs.items()}
        return {cid: f.result() for cid, f in futures.items()}


@pytest.mark.parametrize("case", SUBPROCESS, ids=lambda c: c.id)
def test_command_exits_2_with_one_line_and_no_traceback(case, subprocess_outcomes):
    o = subprocess_outcomes[case.id]
    assert o.code == 2
    assert "Traceback" not in o.stderr + o.stdout
    assert not problems(case, o), (problems(case, o), o.stderr, o.stdout[-2000:])


def _workflow_copy(tmp: Path) -> None:
    """The workflow (Snakefile, rules, scripts, schemas, profiles) beside a case's inputs."""
    shutil.copy(ROOT / "Snakefile", tmp / "Snakefile")
    for item in ("workflow", "profiles", "envs"):
        shutil.copytree(ROOT / item, tmp / item)  # the schema symlink is followed into a copy
    cfg = tmp / "config/config.yaml"
    if not cfg.is_file():
        soils = sorted(p.stem for p in (tmp / "config/soils").glob("*.yaml"))
        cfg.write_text(yaml.safe_dump({"soils": soils, "soil_dir": "config/soils", "resources": "resources"}))


@pytest.mark.parametrize("case", SNAKEMAKE, ids=lambda c: c.id)
def test_workflow_dry_run_stops_with_the_same_line(case, tmp_path):
    case.build(tmp_path)
    _workflow_copy(tmp_path)
    r = snakemake(tmp_path, "-n", "--cores", "1", check=False)
    text = r.stdout + r.stderr
    assert r.returncode == 2
    lines = [ln for ln in text.splitlines() if f"{case.file}: {case.field}: expected " in ln]
    assert len(lines) == 1 and lines[0].startswith("soilcal: error: ") and case.expected in lines[0], text[-3000:]
    assert "Traceback" not in text and 'File "' not in text
    assert not (tmp_path / "results").exists()
