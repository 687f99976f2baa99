"""Comparing two results trees (soilcal.chain.compare, ``soilcal compare``)."""

from __future__ import annotations

import subprocess
import sys

from soilcal.chain.compare import (DIFFERS, IDENTICAL, ONLY_A, ONLY_B, VOLATILE_ONLY, compare_trees,
                                   same_results)


def _write(root, rel, text):
    p = root / rel
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(text)


def _pair(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    for r in (a, b):
        _write(r, "s/dem/pb/design.csv", "run,A\n1,0.1\n2,0.2\n")
        _write(r, "s/dem/targets.json", '{"x": 1}')
        _write(r, "s/logs/x.csv", f"t\n{r.name}\n")  # logs are timings, never compared
        _write(r, "s/fig.png", r.name)  # figures are not compared
    return a, b


def test_identical_trees(tmp_path):
    a, b = _pair(tmp_path)
    comps = compare_trees(a, b)
    assert [c.path for c in comps] == ["s/dem/pb/design.csv", "s/dem/targets.json"]
    assert all(c.outcome == IDENTICAL for c in comps) and same_results(comps)


def test_wall_clock_columns_are_the_only_allowed_difference(tmp_path):
    a, b = _pair(tmp_path)
    _write(a, "s/dem/pb/runs/1.csv", "response,value,wall_s\nangle,31.25,12.5\n")
    _write(b, "s/dem/pb/runs/1.csv", "response,value,wall_s\nangle,31.25,13.75\n")
    comps = {c.path: c for c in compare_trees(a, b)}
    c = comps["s/dem/pb/runs/1.csv"]
    assert c.outcome == VOLATILE_ONLY and c.detail == "wall_s"
    assert same_results(comps.values())


def test_a_changed_number_is_named_by_column_and_row(tmp_path):
    a, b = _pair(tmp_path)
    _write(a, "s/dem/pb/runs/1.csv", "response,value,wall_s\nangle,31.25,12.5\nother,2,1\n")
    _write(b, "s/dem/pb/runs/1.csv", "response,value,wall_s\nangle,31.25,12.5\nother,2.0,1\n")
    c = {c.path: c for c in compare_trees(a, b)}["s/dem/pb/runs/1.csv"]
    # "2" and "2.0" print differently: a difference, read as text
    assert c.outcome == DIFFERS and c.detail == "column value, row 2: 2 vs 2.0"
    _write(b, "s/dem/targets.json", '{"x": 2}')
    _write(b, "s/extra.md", "# x")
    _write(a, "s/gone.csv", "a\n1\n")
    comps = {c.path: c.outcome for c in compare_trees(a, b)}
    assert comps["s/dem/targets.json"] == DIFFERS
    assert comps["s/extra.md"] == ONLY_B and comps["s/gone.csv"] == ONLY_A
    assert not same_results([c for c in compare_trees(a, b)])


def test_cli_exit_codes(tmp_path):
    a, b = _pair(tmp_path)
    cmd = [sys.executable, "-m", "soilcal.cli", "compare"]
    ok = subprocess.run(cmd + [str(a), str(b)], capture_output=True, text=True)
    assert ok.returncode == 0 and "same results" in ok.stdout
    _write(b, "s/dem/pb/design.csv", "run,A\n1,0.1\n2,0.3\n")
    bad = subprocess.run(cmd + [str(a), str(b)], capture_output=True, text=True)
    assert bad.returncode == 1 and "differs: s/dem/pb/design.csv (column A, row 2: 0.2 vs 0.3)" in bad.stdout
    missing = subprocess.run(cmd + [str(a), str(tmp_path / "nope")], capture_output=True, text=True)
    assert missing.returncode == 2 and "Traceback" not in missing.stderr and "nope" in missing.stderr
