"""The funnel benchmark splits a run's steps into its phases from hand-made traces: the load's
fill, the cover's withdrawal, the discharge up to the first trace with no sphere left in the
funnel, and the heap's rest after it."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[2] / "benchmarks"


@pytest.fixture(scope="module")
def reach():
    sys.path.insert(0, str(BENCH))
    try:
        spec = importlib.util.spec_from_file_location("funnel_reach_bench", BENCH / "funnel_reach.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        yield mod
    finally:
        sys.path.remove(str(BENCH))


def _run(trace, steps=10_000, fill=1_000, heap=8_600):
    # 10,000 steps: 1,000 fill, 400 cover, 8,600 heap (which starts at step 1,400)
    return {"tag": "t", "levels": {"A": 0.3, "B": 0.5, "G": 0.02}, "seed": 7, "n": 100, "steps": steps,
            "dt": 1e-4, "cpu_s": 20.0,
            "phases": [{"key": "fill_steps", "steps": fill, "cpu": 2.0}, {"key": "heap_steps", "steps": heap, "cpu": 17.0}],
            "trace": trace,
            "responses": {"angle_image_deg": 33.0, "angle_deg": 32.0, "settled": 1, "settle_time_s": 0.86}}


def test_phases_split_at_the_first_trace_with_an_empty_funnel(reach):
    trace = [{"step": 5_400, "retained": 50, "image": 30.0}, {"step": 9_400, "retained": 0, "image": 34.5},
             {"step": 10_000, "retained": 0, "image": 33.0}]
    row = reach.row_of(_run(trace), "abc")
    assert (row["fill_steps"], row["cover_steps"]) == (1_000, 400)
    assert row["discharge_steps"] == 9_400 - 1_400
    assert row["rest_steps"] == 10_000 - 9_400
    assert row["discharge_end_s"] == pytest.approx(0.94)
    assert row["heap_end_s"] == pytest.approx(1.0)
    assert row["angle_image_at_discharge_end_deg"] == 34.5


def test_a_run_whose_funnel_never_empties_is_all_discharge(reach):
    row = reach.row_of(_run([{"step": 10_000, "retained": 3}]), "abc")
    assert (row["discharge_steps"], row["rest_steps"]) == (8_600, 0)
    assert row["angle_image_at_discharge_end_deg"] == ""
