"""design: adaptive inside the DAG, on the tiny preset, two soils in one workflow copy.

The cinnamon soil: one checkpoint per iteration, one DEM job per run, stopped and resumed
between iterations without redoing a finished run.

The cohesive soil, cases that share their runs: its three moisture cases aim three targets at
one simulated heap angle; only the first case runs the start, the others fit their surrogates to
it from their first iteration, and every case keeps its own budget, verifications and seeds.

Both soils run in one copy (one ``snakemake`` run after the cinnamon soil's first iteration, as
a run killed there leaves it): each soil's records, runs and seeds are its own (results/<soil>/),
so each soil's tests read what a copy of that soil alone would hold, and the copy builds the
kernel stamp (rule dem_kernels) once for both."""

from __future__ import annotations

import json

import pandas as pd
import pytest
import yaml

from wfutil import LIFT_SPEED, N_SPHERES, adaptive_soil, copy_workflow, planned_jobs, run

SOIL = "cinnamon-soil"
CASE = f"results/{SOIL}/dem/adaptive/bbd/stacking_angle"
#: the start (7 points, the centre twice: 8 runs) and one verification of two seeds: the least
#: budget the start-up check admits, spent at iteration 1 on verifying the best candidate
BUDGET, VERIFY_SEEDS = 10, 2
#: how the design stops once the budget is spent: the verification met the target or not
STOPPED = ("budget spent", "target met")

SHARED_SOIL = "guangxi-cohesive"
CASES = ["mc00", "mc10", "mc20"]
#: runs per case of the cohesive soil: the first case's start (2 d + 1 = 7 points, the centre
#: twice: 8 runs) and one verification of one seed, the least budget the start-up check admits,
#: so that case verifies its best candidate at iteration 1 and stops at 2; the others run one
#: proposal (and a verification where theirs is ready) at iteration 1 and stop at 2, the last
#: iteration
SHARED_BUDGET, SHARED_VERIFY_SEEDS, BATCH, ITERATIONS = 9, 1, 1, 1
#: a quarter of the funnel's 0.2 kg load, 0.05 kg, in 375 spheres: the diameter of 0.2 kg in
#: 1,500 spheres, the largest that passes the soil's check of an outlet five diameters wide;
#: these tests read the records' runs, seeds, budgets and surrogates, not the angles: every
#: start heap of this small load still reads (20-43 deg, against 42-49 deg for 0.1 kg in 750
#: spheres), at about half the DEM jobs' CPU time
SHARED_SPHERES, LOAD_MASS = 375, 0.05


@pytest.fixture(scope="module")
def wf(tmp_path_factory):
    tmp = copy_workflow(tmp_path_factory.mktemp("adaptive"), [SOIL, SHARED_SOIL])
    # the cinnamon soil's heaps lifted at the tiny run's speed, a quarter of the lift's steps:
    # these tests read the records' runs, seeds, levels and files, not the angles' values; the
    # target is the printed angle and the copy holds no photos (no job measures photos these
    # tests do not read: the target from the photos is the tiny run's test,
    # test_dem_workflow.py)
    adaptive_soil(tmp, SOIL, "stacking_angle", N_SPHERES, BUDGET, setup={"lift_speed": LIFT_SPEED}, photos=False,
                  printed_targets=True, verify_seeds=VERIFY_SEEDS)
    # the cohesive soil's photos are left out of the copy: no target of the soil reads them,
    # nor do these tests
    adaptive_soil(tmp, SHARED_SOIL, "angle_of_repose", SHARED_SPHERES, SHARED_BUDGET, setup={"load_mass": LOAD_MASS},
                  photos=False, verify_seeds=SHARED_VERIFY_SEEDS, batch=BATCH, max_iterations=ITERATIONS)
    # first only up to the cinnamon soil's decision of iteration 1 (the start's runs are done by
    # then), as a run killed after its first iteration leaves it; the cohesive soil has not
    # started then, and runs whole in the second run
    run(tmp, "--cores", "2", f"{CASE}/step/1.json", "--config", "design=adaptive")
    assert not (tmp / f"results/{SHARED_SOIL}/dem/adaptive").exists()
    first = {f.name: f.stat().st_mtime_ns for f in (tmp / CASE / "runs/0").glob("*.csv")}
    run(tmp, "--cores", "2", "--config", "design=adaptive")
    return tmp, first


@pytest.fixture(scope="module")
def left_to_do(wf):
    """The jobs a further run of the finished copy would plan (a dry run, made once for the two
    soils' tests: no test of this file changes the copy)."""
    return planned_jobs(wf[0], "--config", "design=adaptive")


def test_iterations_and_runs_follow_the_records(wf):
    tmp, _ = wf
    steps = [json.loads((tmp / CASE / f"step/{i}.json").read_text()) for i in range(3)]
    assert [s["status"] for s in steps[:2]] == ["continue", "continue"] and steps[2]["status"] in STOPPED
    assert len(steps[0]["runs"]) == 8 and len(steps[1]["runs"]) == VERIFY_SEEDS
    # the budget left after the start pays for one verification, so it is run, ready or not
    assert {r["kind"] for r in steps[1]["runs"]} == {"verification"}
    assert not (tmp / CASE / "step/3.json").exists()
    runs = pd.read_csv(tmp / CASE / "runs.csv")
    assert len(runs) == BUDGET and runs["seed"].is_unique
    # every run file is the DEM job of its record: its levels, its seed
    for s in steps[:2]:
        for k, r in enumerate(s["runs"]):
            df = pd.read_csv(tmp / CASE / f"runs/{s['iteration']}/{k}.csv")
            assert int(df["seed"].iloc[0]) == r["seed"]
            for sym, v in r["levels"].items():
                assert df[f"f:{sym}"].iloc[0] == pytest.approx(v)


def test_ranges_respected_and_fixed_parameters_unchanged(wf):
    tmp, _ = wf
    soil = yaml.safe_load((tmp / f"config/soils/{SOIL}.yaml").read_text())
    bbd = next(s for s in soil["stages"] if s["id"] == "bbd")
    pb = next(s for s in soil["stages"] if s["id"] == "pb")
    # by default (simulation.adaptive.ranges: screening) each factor spans the range its
    # parameter had in the soil's Plackett-Burman screening, not the printed Box-Behnken box
    screened = {f["parameter"]: f for f in pb["factors"].values()}
    runs = pd.read_csv(tmp / CASE / "runs.csv")
    for sym, f in bbd["factors"].items():
        box = screened[f["parameter"]]
        assert runs[sym].between(box["low"], box["high"]).all()
        assert runs[sym].min() < f["low"] or runs[sym].max() > f["high"]
    for f in (tmp / CASE / "runs").glob("*/*.csv"):
        df = pd.read_csv(f)
        for pname, v in bbd["fixed"].items():
            assert df[f"p:{pname}"].iloc[0] == pytest.approx(v)


def test_resumed_without_redoing_finished_runs(wf, left_to_do):
    tmp, first = wf
    assert len(first) == 8
    now = {f.name: f.stat().st_mtime_ns for f in (tmp / CASE / "runs/0").glob("*.csv")}
    assert now == first
    assert left_to_do == []


def test_outputs_have_the_recipe_file_names_and_say_how_it_stopped(wf):
    tmp, _ = wf
    d = tmp / f"results/{SOIL}/dem/adaptive"
    opt = pd.read_csv(d / "bbd/optimum.csv")
    assert list(opt["case"]) == ["stacking_angle"] and bool(opt["calibrated"].iloc[0])
    ver = pd.read_csv(d / "verification.csv")
    recipe_cols = ["stage", "case", "round", "response", "target", "simulated_mean", "within_2_percent", "status"]
    assert all(c in ver.columns for c in recipe_cols)
    summ = pd.read_csv(d / "summary.csv")
    assert summ["stopped_because"].iloc[0] in STOPPED and summ["runs"].iloc[0] == BUDGET
    targets = pd.read_csv(tmp / f"results/{SOIL}/dem/targets.csv").set_index("target_id")
    assert summ["target"].iloc[0] == pytest.approx(targets.loc["stacking_angle", "value"])
    assert (d / "bbd/identifiability.csv").exists()
    assert (d / "figures/verification.png").exists() and (d / "figures/progress_bbd_stacking_angle.png").exists()
    assert (d / "figures/region_bbd_stacking_angle.png").exists()
    # every step record carries its sample of the consistent region, one level per factor
    for rec in (tmp / CASE / "step").glob("*.json"):
        r = json.loads(rec.read_text())
        assert len(r["consistent"]) <= 256
        assert all(len(row) == len(r["problem"]["factors"]) for row in r["consistent"])


# ------------------------------------------------------------------ cases that share their runs
# The cohesive soil's three moisture cases, in the same copy.


@pytest.fixture(scope="module")
def shared(wf):
    return wf[0]


def case_dir(tmp, case):
    return tmp / f"results/{SHARED_SOIL}/dem/adaptive/bbd/{case}"


def steps(tmp, case):
    return sorted((json.loads(p.read_text()) for p in (case_dir(tmp, case) / "step").glob("*.json")),
                  key=lambda r: r["iteration"])


def test_only_the_first_case_runs_the_start(shared):
    first = steps(shared, "mc00")[0]
    assert first["message"].startswith("start:") and len(first["runs"]) == 8
    for c in CASES[1:]:
        s0 = steps(shared, c)[0]
        assert s0["status"] == "continue" and s0["runs"] == [] and "first case runs it" in s0["message"]


def test_every_case_fits_its_surrogate_to_the_shared_start(shared):
    # at iteration 1 the first case has its own start points, the others the same points as
    # shared evidence: every case's surrogate sees them although two of them ran nothing (a
    # heap a small run cannot read is no point)
    start = pd.read_csv(case_dir(shared, "mc00") / "runs.csv")
    start = start[start["kind"] == "start"]
    read = start.groupby("point")["angle_of_repose"].apply(lambda v: v.notna().any())
    assert len(read) == 7 and read.sum() >= 3
    for c in CASES:
        (sur,) = steps(shared, c)[1]["surrogates"]
        assert sur["points"] == int(read.sum()), (c, sur)


def test_budgets_verifications_and_seeds_are_each_cases_own(shared):
    seeds = []
    for c in CASES:
        runs = pd.read_csv(case_dir(shared, c) / "runs.csv")
        kinds = runs["kind"].value_counts().to_dict()
        if c == "mc00":  # the start, then the verification the budget leaves room for
            assert kinds == {"start": 8, "verification": SHARED_VERIFY_SEEDS} and len(runs) == SHARED_BUDGET
        else:  # no start of its own: one iteration of proposals, perhaps with a verification
            assert kinds.get("proposal") == BATCH and kinds.get("verification", 0) in (0, SHARED_VERIFY_SEEDS)
            assert set(kinds) <= {"proposal", "verification"}
        assert steps(shared, c)[-1]["status"] != "continue"
        seeds += runs["seed"].tolist()
        res = json.loads((case_dir(shared, c) / "result.json").read_text())
        assert res["runs"] == len(runs)
        if res["verified"]:
            ver = runs[runs["kind"] == "verification"]
            assert res["verified"]["point"] in set(ver["point"])
    assert len(seeds) == len(set(seeds))  # no seed repeated across the cases
    # case i draws from its own stream, seed + 100000 i (the soil's seed is the first's)
    soil_seed = yaml.safe_load((shared / f"config/soils/{SHARED_SOIL}.yaml").read_text()).get("seed", 0)
    for i, c in enumerate(CASES[1:], start=1):
        runs = pd.read_csv(case_dir(shared, c) / "runs.csv")
        if len(runs):
            assert runs["seed"].min() >= soil_seed + 100_000 * i


def test_summary_and_nothing_left_to_do(shared, left_to_do):
    summ = pd.read_csv(shared / f"results/{SHARED_SOIL}/dem/adaptive/summary.csv")
    assert set(summ.loc[summ["runs"] > 0, "case"]) <= set(CASES)
    assert left_to_do == []
