"""The funnel benchmark splits a run's steps into its phases from hand-made traces: the load's
fill, the cover's withdrawal, the discharge up to the first trace with no sphere left in the
funnel, and the heap's rest after it."""

from __future__ import annotations

import math

import pytest


@pytest.fixture(scope="module")
def reach(load_benchmark):
    return load_benchmark("funnel_reach.py", "funnel_reach_bench")


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


class _Decay:
    """A stand-in for the engine's settle: kinetic energy exp(-step / 1000) J, checked as
    ``run_loop`` checks it (every ``ke_every``-th step of the global step count)."""

    def __init__(self, step0):
        self.step = step0

    def kinetic_energy(self):
        return math.exp(-self.step / 1000.0)

    def run(self, n, ke_tol, ke_every):
        for i in range(1, n + 1):
            self.step += 1
            if ke_every > 0 and self.step % ke_every == 0 and self.kinetic_energy() < ke_tol:
                return i
        return n


def _settle(reach, max_steps, ke_rest):
    sim, rows = _Decay(100), []

    def observe():
        rows.append({"step": sim.step})
        return rows[-1]

    done, ok, ship = reach.settle_traced(sim, max_steps, math.exp(-5.1), ke_rest, 200, 1_000, observe)
    return sim, rows, done, ok, ship


def test_the_plain_stop_is_the_first_check_below_the_tolerance(reach):
    # exp(-s/1000) < exp(-5.1) from s > 5,100: the first check (every 200th step) is at 5,200
    sim, rows, done, ok, ship = _settle(reach, 20_000, math.exp(-5.1))
    assert (sim.step, done, ok) == (5_200, 5_100, True)
    assert ship is rows[-1] and ship["step"] == 5_200
    assert [r["step"] for r in rows] == [1_100, 2_100, 3_100, 4_100, 5_100, 5_200]


def test_a_lower_rest_goes_on_from_the_plain_stop(reach):
    # below exp(-8.1) from s > 8,100: first check at 8,200; the plain stop (5,200) is recorded
    sim, rows, done, ok, ship = _settle(reach, 20_000, math.exp(-8.1))
    assert (sim.step, done, ok) == (8_200, 8_100, True)
    assert ship["step"] == 5_200
    assert [r["step"] for r in rows][5:] == [5_200, 6_200, 7_200, 8_200]


def test_a_lower_rest_not_met_within_the_bound_is_unsettled(reach):
    sim, rows, done, ok, ship = _settle(reach, 7_000, math.exp(-8.1))
    assert (sim.step, done, ok) == (7_100, 7_000, False)
    assert ship["step"] == 5_200 and rows[-1]["step"] == 7_100


def test_rows_record_the_rest_the_rolling_model_and_the_plain_stop(reach):
    trace = [{"step": 9_400, "retained": 0, "image": 34.5, "v_rms": 0.0031}]
    run = _run(trace) | {"rest_speed": 0.001, "rolling": "bounded",
                         "shipped_stop": {"step": 8_000, "image": 36.25, "v_rms": 0.0049}}
    row = reach.row_of(run, "abc")
    assert (row["rolling"], row["rest_mm_s"]) == ("bounded", 1.0)
    assert (row["shipped_stop_step"], row["angle_image_at_shipped_stop_deg"]) == (8_000, 36.25)
    assert (row["v_rms_end_mm_s"], row["retained_end"]) == (3.1, 0)


def test_rows_of_runs_before_the_rest_was_recorded_stopped_at_the_plain_rest(reach):
    row = reach.row_of(_run([{"step": 10_000, "retained": 0, "image": 33.0, "v_rms": 0.0049}]), "abc")
    assert (row["rolling"], row["rest_mm_s"]) == ("constant_torque", 5.0)
    assert (row["shipped_stop_step"], row["angle_image_at_shipped_stop_deg"]) == (10_000, 33.0)
    unsettled = _run([{"step": 10_000, "retained": 0}])
    unsettled["responses"]["settled"] = 0
    assert reach.row_of(unsettled, "abc")["angle_image_at_shipped_stop_deg"] == ""


def test_the_script_runs_its_own_heap_stop_not_the_soils_read_time(reach):
    """The soil reads its heap at ``read_time`` after the release, which bypasses the rest check
    the script's trace hooks into: the script's setup drops it, for the rest rule and for
    --until alike, and keeps the rest speed it is given."""
    from soilcal.chain.sources import point_spec
    from soilcal.config.load import load_soil

    soil = load_soil(reach.ROOT / "config/soils/guangxi-cohesive.yaml", resources_root=reach.ROOT / "resources")
    st = next(s for s in soil.data["stages"] if s["id"] == "bbd")
    shipped = point_spec(soil, st, {"A": 0.33, "B": 0.488, "G": 0.06}, 0, 1, replicates=1,
                         responses=["angle_of_repose"])["responses"]["angle_of_repose"]["setup"]
    assert shipped["read_time"] is not None  # what the script must not run with
    for kw, rest in (({}, 0.005), ({"rest": 0.001}, 0.001), ({"until": 6.0}, 0.0)):
        mod, setup, params, r = reach.point_setup(0.33, 0.488, 0.06, 1, **kw)
        assert setup["read_time"] is None and r == rest
        mod.validate(setup, "quick", "t", params)


def test_until_counts_from_the_release_as_read_time_does(reach):
    # dt 1e-4 s, the cover starts to move at step 3,000: 6 s after it is step 63,000; at the
    # heap's start (step 4,000) 59,000 steps remain, at 63,000 or later none
    assert reach.until_steps(6.0, 1e-4, 4_000, 3_000) == 63_000 - 4_000
    assert reach.until_steps(6.0, 1e-4, 63_000, 3_000) == 0
    assert reach.until_steps(6.0, 1e-4, 70_000, 3_000) == 0
