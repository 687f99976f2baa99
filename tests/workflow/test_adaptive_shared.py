"""design: adaptive with cases that share their runs, inside the DAG on the tiny preset: the
cohesive soil's three moisture cases aim three targets at one simulated heap angle; only the
first case runs the start, the others fit their surrogates to it from their first iteration,
and every case keeps its own budget, verifications and seeds."""

from __future__ import annotations

import json

import pandas as pd
import pytest
import yaml

from wfutil import adaptive_copy, planned_jobs, run

SOIL = "guangxi-cohesive"
CASES = ["mc00", "mc10", "mc20"]
#: runs per case: the first case's start (2 d + 1 = 7 points, the centre twice: 8 runs) and one
#: verification of one seed, the least budget the start-up check admits, so that case verifies
#: its best candidate at iteration 1 and stops at 2; the others run one proposal (and a
#: verification where theirs is ready) at iteration 1 and stop at 2, the last iteration
BUDGET, VERIFY_SEEDS, BATCH, ITERATIONS = 9, 1, 1, 1
#: a quarter of the funnel's 0.2 kg load, 0.05 kg, in 375 spheres: the diameter of 0.2 kg in
#: 1,500 spheres, the largest that passes the soil's check of an outlet five diameters wide;
#: these tests read the records' runs, seeds, budgets and surrogates, not the angles: every
#: start heap of this small load still reads (20-43 deg, against 42-49 deg for 0.1 kg in 750
#: spheres), at about half the DEM jobs' CPU time
N_SPHERES, LOAD_MASS = 375, 0.05
#: the soil's photos are left out of the copy: no target of the soil reads them, nor do these tests


@pytest.fixture(scope="module")
def wf(tmp_path_factory):
    tmp = adaptive_copy(tmp_path_factory.mktemp("adaptive_shared"), SOIL, "angle_of_repose", N_SPHERES, BUDGET,
                        setup={"load_mass": LOAD_MASS}, photos=False,
                        verify_seeds=VERIFY_SEEDS, batch=BATCH, max_iterations=ITERATIONS)
    run(tmp, "--cores", "2", "--config", "design=adaptive")
    return tmp


def case_dir(tmp, case):
    return tmp / f"results/{SOIL}/dem/adaptive/bbd/{case}"


def steps(tmp, case):
    return sorted((json.loads(p.read_text()) for p in (case_dir(tmp, case) / "step").glob("*.json")),
                  key=lambda r: r["iteration"])


def test_only_the_first_case_runs_the_start(wf):
    first = steps(wf, "mc00")[0]
    assert first["message"].startswith("start:") and len(first["runs"]) == 8
    for c in CASES[1:]:
        s0 = steps(wf, c)[0]
        assert s0["status"] == "continue" and s0["runs"] == [] and "first case runs it" in s0["message"]


def test_every_case_fits_its_surrogate_to_the_shared_start(wf):
    # at iteration 1 the first case has its own start points, the others the same points as
    # shared evidence: every case's surrogate sees them although two of them ran nothing (a
    # heap a small run cannot read is no point)
    start = pd.read_csv(case_dir(wf, "mc00") / "runs.csv")
    start = start[start["kind"] == "start"]
    read = start.groupby("point")["angle_of_repose"].apply(lambda v: v.notna().any())
    assert len(read) == 7 and read.sum() >= 3
    for c in CASES:
        (sur,) = steps(wf, c)[1]["surrogates"]
        assert sur["points"] == int(read.sum()), (c, sur)


def test_budgets_verifications_and_seeds_are_each_cases_own(wf):
    seeds = []
    for c in CASES:
        runs = pd.read_csv(case_dir(wf, c) / "runs.csv")
        kinds = runs["kind"].value_counts().to_dict()
        if c == "mc00":  # the start, then the verification the budget leaves room for
            assert kinds == {"start": 8, "verification": VERIFY_SEEDS} and len(runs) == BUDGET
        else:  # no start of its own: one iteration of proposals, perhaps with a verification
            assert kinds.get("proposal") == BATCH and kinds.get("verification", 0) in (0, VERIFY_SEEDS)
            assert set(kinds) <= {"proposal", "verification"}
        assert steps(wf, c)[-1]["status"] != "continue"
        seeds += runs["seed"].tolist()
        res = json.loads((case_dir(wf, c) / "result.json").read_text())
        assert res["runs"] == len(runs)
        if res["verified"]:
            ver = runs[runs["kind"] == "verification"]
            assert res["verified"]["point"] in set(ver["point"])
    assert len(seeds) == len(set(seeds))  # no seed repeated across the cases
    # case i draws from its own stream, seed + 100000 i (the soil's seed is the first's)
    soil_seed = yaml.safe_load((wf / f"config/soils/{SOIL}.yaml").read_text()).get("seed", 0)
    for i, c in enumerate(CASES[1:], start=1):
        runs = pd.read_csv(case_dir(wf, c) / "runs.csv")
        if len(runs):
            assert runs["seed"].min() >= soil_seed + 100_000 * i


def test_summary_and_nothing_left_to_do(wf):
    summ = pd.read_csv(wf / f"results/{SOIL}/dem/adaptive/summary.csv")
    assert set(summ.loc[summ["runs"] > 0, "case"]) <= set(CASES)
    assert planned_jobs(wf, "--config", "design=adaptive") == []
