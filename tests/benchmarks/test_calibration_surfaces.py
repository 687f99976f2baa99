"""The calibration benchmark's response-surface table reads a stage's files by hand-made numbers:
pooled seed SD, centre SD, the largest linear effect over its range, the ANOVA's p-values."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd
import pytest


@pytest.fixture(scope="module")
def calibration(load_benchmark):
    return load_benchmark("calibration.py", "calibration_bench")


def _stage(d: Path, centre_values, sds, ns):
    d.mkdir(parents=True)
    rows = [(1, -1, 0), (2, 1, 0), (3, 0, -1), (4, 0, 1)] + [(5 + i, 0, 0) for i in range(len(centre_values))]
    design = pd.DataFrame(rows, columns=["run", "A", "B"])
    design["A_actual"], design["B_actual"] = design["A"], design["B"]
    design.to_csv(d / "design.csv", index=False)
    y = [30.0, 34.0, 31.0, 32.0] + list(centre_values)
    pd.DataFrame({"run": design["run"], "angle": y}).to_csv(d / "responses.csv", index=False)
    # the pure error of the centre values: their variance, sum of squares over n - 1
    c = pd.Series(list(centre_values), dtype=float)
    pd.DataFrame({"response": "angle", "model": ["full"] * 4 + ["reduced"],
                  "source": ["Model", "A", "Lack of Fit", "Pure Error", "Model"],
                  "mean_sq": [9.0, 8.0, 0.5, float(((c - c.mean()) ** 2).sum() / (len(c) - 1)), 9.0],
                  "p": [0.012, 0.003, 0.41, float("nan"), 0.5]}).to_csv(d / "anova.csv", index=False)
    pd.DataFrame({"response": "angle", "model": ["full"] * 3 + ["reduced"] * 2,
                  "term": ["Intercept", "A", "B", "Intercept", "A"],
                  "coded": [32.0, 2.0, -0.5, 32.0, 9.0]}).to_csv(d / "coefficients.csv", index=False)
    (d / "runs").mkdir()
    for k, (sd, n) in enumerate(zip(sds, ns)):
        pd.DataFrame({"response": ["angle"], "sd": [sd], "n": [n], "commit": ["abcdef0123"]}).to_csv(
            d / f"runs/{k}.csv", index=False)


def test_surface_rows_from_hand_made_files(tmp_path, calibration):
    _stage(tmp_path / "results/some-soil/dem/bbd", [31.0, 33.0, 32.0], sds=[1.0, 3.0, float("nan")], ns=[2, 2, 1])
    rows = calibration.surface_rows(tmp_path)
    assert len(rows) == 1
    r = rows[0]
    assert (r["soil"], r["stage"], r["response"], r["commit"]) == ("some-soil", "bbd", "angle", "abcdef0")
    assert (r["points"], r["centre_points"]) == (7, 3)
    assert r["seed_sd"] == pytest.approx(math.sqrt((1.0 + 9.0) / 2), abs=1e-3)  # pooled, one df each
    assert r["centre_sd"] == pytest.approx(1.0)  # 31, 33, 32
    assert (r["largest_effect"], r["largest_effect_factor"]) == (4.0, "A")  # full model, 2 |2.0|
    assert r["effect_over_centre_sd"] == pytest.approx(4.0)
    assert (r["model_p"], r["lack_of_fit_p"]) == (0.012, 0.41)


def test_a_screening_stage_has_no_row(tmp_path, calibration):
    d = tmp_path / "results/some-soil/dem/pb"
    d.mkdir(parents=True)
    pd.DataFrame({"run": [1, 2], "A": [-1, 1], "A_actual": [-1, 1]}).to_csv(d / "design.csv", index=False)
    pd.DataFrame({"response": ["angle"], "model": ["full"], "source": ["Model"], "p": [0.1]}).to_csv(
        d / "anova.csv", index=False)
    assert calibration.surface_rows(tmp_path) == []


def _job(root: Path, rel: str, seconds: float, log: str | None):
    b = root / "benchmarks/workflow" / f"{rel}.tsv"
    b.parent.mkdir(parents=True, exist_ok=True)
    b.write_text("s\th:m:s\tmax_rss\n" f"{seconds}\t0:00:01\t100.0\n")
    if log is not None:
        g = root / "logs" / f"{rel}.log"
        g.parent.mkdir(parents=True, exist_ok=True)
        g.write_text(log)


def test_breakdown_sums_jobs_and_the_runs_their_logs_name(tmp_path, calibration):
    # two design points of one soil, one of them running two scenarios (a heap and a drum),
    # a fit without DEM runs, a failed run (no particles line) and the kernels' job
    _job(tmp_path, "soil-a/dem/bbd/runs/1", 10.0,
         "soil-a bbd run 1 seed 5: {}\n"
         "repose soil-a-100mm (quick): 1000 particles, 2000 steps, 4.50 s on 1 thread(s)\n"
         "drum soil-a (quick): 500 particles, 3000 steps, 3.25 s on 1 thread(s)\n")
    _job(tmp_path, "soil-a/dem/bbd/runs/2", 6.0,
         "repose soil-a-100mm (quick): failed after 1.00 s on 1 thread(s): SimulationError: blow-up\n")
    _job(tmp_path, "soil-a/dem/bbd/regression", 2.5, "fitted\n")
    _job(tmp_path, "soil-a/dem/verify/quick/bbd/c1/0", 7.0,
         "repose soil-a-100mm (quick): 1000 particles, 1000 steps, 2.00 s on 1 thread(s)\n")
    _job(tmp_path, "dem_kernels", 30.0, None)
    rows = {(r["soil"], r["rule"]): r for r in calibration.breakdown_rows(tmp_path)}
    assert set(rows) == {("soil-a", "dem_point"), ("soil-a", "regression"), ("soil-a", "verify_point"),
                         ("", "dem_kernels")}
    d = rows[("soil-a", "dem_point")]
    assert (d["jobs"], d["sum_s"], d["dem_runs"]) == (2, 16.0, 2)
    assert d["dem_wall_s"] == pytest.approx(7.75, abs=0.05)  # rounded to 0.1 s
    assert d["particle_steps"] == 1000 * 2000 + 500 * 3000
    assert (rows[("soil-a", "regression")]["dem_runs"], rows[("soil-a", "regression")]["sum_s"]) == (0, 2.5)
    assert rows[("soil-a", "verify_point")]["particle_steps"] == 1_000_000
    assert (rows[("", "dem_kernels")]["jobs"], rows[("", "dem_kernels")]["dem_runs"]) == (1, 0)
