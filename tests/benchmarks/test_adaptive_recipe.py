"""The adaptive benchmark's recipe rows count the DEM runs a recipe spent: design points and
local-design points times their replicates, verification and second-round seeds that ran, not
the 'not run' rows a case without a calibrated set writes; a case's row is the round it ends
with (``final``); the commit is the one the runs name."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
import yaml


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("adaptive.py", "adaptive_bench")


def _seed(path: Path, status: str, commit: str | None = "303e2e901320", replicates: int = 1):
    path.parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame([{"status": status, "commit": commit, "replicates": replicates}]).to_csv(path, index=False)


def _workdir(tmp_path: Path, commit2="303e2e901320") -> Path:
    soil = "s"
    d = tmp_path / "results" / soil / "dem"
    for k in range(5):  # five design points of two replicates each: 10 runs
        p = d / "bbd" / "runs" / f"{k}.csv"
        p.parent.mkdir(parents=True, exist_ok=True)
        # a response of its own count (1) listed first: the point ran the most of them, 2 seeds
        pd.DataFrame([{"status": "ok", "commit": "303e2e901320", "replicates": 1},
                      {"status": "ok", "commit": "303e2e901320", "replicates": 2}]).to_csv(p, index=False)
    for k in range(4):
        _seed(d / "verify/quick/bbd/a" / f"{k}.csv", "ok")  # 4 seeds ran
        _seed(d / "verify/quick/bbd/b" / f"{k}.csv", "not run", None)  # no calibrated set: 0 ran
    _seed(d / "verify/quick/bbd/a/4.csv", "failed", commit2)  # a failed seed ran
    _seed(d / "refine/bbd/a/0.csv", "ok")
    for k in range(3):  # the local design at the first set: 3 points of 2 seeds each ran
        _seed(d / "local/bbd/a" / f"{k}.csv", "ok", replicates=2)
    pd.DataFrame([
        {"stage": "bbd", "case": "a", "round": 1, "response": "r", "simulated_mean": 30.0, "simulated_sd": 1.0,
         "relative_error_percent": 1.0, "within_2_percent": True, "status": "ok", "final": True},
        # a second round that did not do better: the case ends with the first
        {"stage": "bbd", "case": "a", "round": 2, "response": "r", "simulated_mean": 33.0, "simulated_sd": 1.0,
         "relative_error_percent": 11.0, "within_2_percent": False, "status": "ok", "final": False},
        {"stage": "bbd", "case": "b", "round": 1, "response": "r", "simulated_mean": float("nan"),
         "simulated_sd": float("nan"), "relative_error_percent": float("nan"), "within_2_percent": False,
         "status": "not run: no calibrated set", "final": True}]).to_csv(d / "verification.csv", index=False)
    cfg = tmp_path / "config/soils"
    cfg.mkdir(parents=True)
    (cfg / f"{soil}.yaml").write_text(yaml.safe_dump({"stages": [{"id": "bbd", "optimise": {"cases": [
        {"id": "a", "goals": {"r": {"goal": "target"}}}, {"id": "b", "goals": {"r": {"goal": "target"}}}]}}]}))
    return tmp_path


def test_not_run_seeds_are_not_counted(bench, tmp_path):
    rows = bench.recipe_rows(_workdir(tmp_path), "s")
    assert [r["runs"] for r in rows] == [10 + 5 + 3 * 2 + 1] * 2
    assert rows[0]["stopped_because"] == "recipe complete" and rows[1]["stopped_because"].startswith("not run")
    assert rows[0]["verified_mean"] == 30.0 and rows[0]["note"].endswith("round 1")  # the final round
    assert bench.recipe_commit(tmp_path, "s") == "303e2e9"


def test_runs_of_two_commits_are_refused(bench, tmp_path):
    with pytest.raises(SystemExit, match="2 commits"):
        bench.recipe_commit(_workdir(tmp_path, commit2="aaaaaaa0000"), "s")
