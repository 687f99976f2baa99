"""design: adaptive inside the DAG, on the tiny preset: one checkpoint per iteration, one DEM
job per run, stopped and resumed between iterations without redoing a finished run."""

from __future__ import annotations

import json

import pandas as pd
import pytest
import yaml

from wfutil import LIFT_SPEED, N_SPHERES, adaptive_copy, planned_jobs, run

SOIL = "cinnamon-soil"
CASE = f"results/{SOIL}/dem/adaptive/bbd/stacking_angle"
#: the start (7 points, the centre twice: 8 runs) and one verification of two seeds: the least
#: budget the start-up check admits, spent at iteration 1 on verifying the best candidate
BUDGET, VERIFY_SEEDS = 10, 2
#: how the design stops once the budget is spent: the verification met the target or not
STOPPED = ("budget spent", "target met")


@pytest.fixture(scope="module")
def wf(tmp_path_factory):
    # the heaps lifted at the tiny run's speed, a quarter of the lift's steps: these tests read
    # the records' runs, seeds, levels and files, not the angles' values; the target is the
    # printed angle and the copy holds no photos (no job measures photos these tests do not
    # read: the target from the photos is the tiny run's test, test_dem_workflow.py)
    tmp = adaptive_copy(tmp_path_factory.mktemp("adaptive"), SOIL, "stacking_angle", N_SPHERES, BUDGET,
                        setup={"lift_speed": LIFT_SPEED}, photos=False, printed_targets=True,
                        verify_seeds=VERIFY_SEEDS)
    # first only up to the decision of iteration 1 (the start's runs are done by then), as a
    # run killed after its first iteration leaves it
    run(tmp, "--cores", "2", f"{CASE}/step/1.json", "--config", "design=adaptive")
    first = {f.name: f.stat().st_mtime_ns for f in (tmp / CASE / "runs/0").glob("*.csv")}
    run(tmp, "--cores", "2", "--config", "design=adaptive")
    return tmp, first


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


def test_resumed_without_redoing_finished_runs(wf):
    tmp, first = wf
    assert len(first) == 8
    now = {f.name: f.stat().st_mtime_ns for f in (tmp / CASE / "runs/0").glob("*.csv")}
    assert now == first
    assert planned_jobs(tmp, "--config", "design=adaptive") == []


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
