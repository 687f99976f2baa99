"""A response's own seed count per design point (``simulation.responses.<id>.replicates``):
the vineyard's cheap, noisy heap averaged over more seeds than its costly drum at the same
points.  No DEM run: ``run_replicates`` is replaced by a stand-in returning known values."""

from __future__ import annotations

import copy
from types import SimpleNamespace

import numpy as np
import pytest
from soil_copies import load_copy, read_shipped

from soilcal.chain.sources import design_replicates, point_seeds, point_spec, replicates_of, seed_stride, simulate
from soilcal.errors import InputError

LEVELS = {"B": 0.63, "D": 0.08, "F": 0.56, "H": 0.14}


@pytest.fixture(scope="module")
def shipped():
    return read_shipped("xinjiang-vineyard")


def _plain(data: dict) -> dict:
    """The soil without any response's own count."""
    data = copy.deepcopy(data)
    for rs in data["simulation"]["responses"].values():
        rs.pop("replicates", None)
    return data


def _with_heap_seeds(data: dict, k: int = 4, block: int | None = None) -> dict:
    data = _plain(data)
    data["simulation"]["responses"]["static_angle"]["replicates"] = k
    if block is not None:
        data["simulation"]["replicates"] = block
    else:
        data["simulation"].pop("replicates", None)
    return data


def test_counts_and_seed_stride(shipped):
    data = _with_heap_seeds(shipped, 4)
    assert design_replicates(data) == 1
    assert design_replicates(data, "static_angle") == 4
    assert design_replicates(data, "dynamic_angle") == 1
    # the points' first seeds lie the most seeds of any response apart, so no draw repeats
    assert seed_stride(data) == 4
    pts = [(1, {}), (2, {}), (3, {})]
    seeds = point_seeds(pts, 100, seed_stride(data))
    assert seeds == {1: 100, 2: 104, 3: 108}
    # a block count above every response's own sets the stride
    assert seed_stride(_with_heap_seeds(shipped, 2, block=3)) == 3
    plain = _plain(shipped)
    assert seed_stride(plain) == design_replicates(plain) == design_replicates(plain, "static_angle")


def test_point_spec_carries_a_responses_own_count_only_where_it_differs(tmp_path, shipped):
    soil = load_copy(tmp_path, "xinjiang-vineyard", _with_heap_seeds(shipped, 4))
    spec = point_spec(soil, soil.stage("bbd"), LEVELS, run=1, seed=3)
    assert spec["replicates"] == 1
    assert spec["responses"]["static_angle"]["replicates"] == 4
    assert "replicates" not in spec["responses"]["dynamic_angle"]
    assert (replicates_of(spec, "static_angle"), replicates_of(spec, "dynamic_angle")) == (4, 1)
    # a verification seed is one seed per job whatever the design's counts
    one = point_spec(soil, soil.stage("bbd"), LEVELS, run=1, seed=3, replicates=1)
    assert all("replicates" not in rs for rs in one["responses"].values())
    # a soil without its own counts: the job's params have no such key (its jobs do not re-run)
    plain = load_copy(tmp_path, "xinjiang-vineyard", _plain(shipped))
    spec = point_spec(plain, plain.stage("bbd"), LEVELS, run=1, seed=3)
    assert all("replicates" not in rs for rs in spec["responses"].values())


def test_simulate_runs_each_response_its_own_seeds(tmp_path, shipped, monkeypatch):
    from soilcal.dem.scenarios import base

    calls = []

    def fake_run(module, setup, params, seed, replicates, **kw):
        calls.append((module.NAME, seed, replicates))
        # run i of a call reads 30 + 2 i (static) and 45 + i (drum)
        per = [{"angle_deg": 30.0 + 2 * i, "angle_avalanche_deg": 45.0 + i} for i in range(replicates)]
        return SimpleNamespace(n_particles=10, steps=5, wall_s=0.0, per_run=per, responses=per[0])

    monkeypatch.setattr(base, "run_replicates", fake_run)
    soil = load_copy(tmp_path, "xinjiang-vineyard", _with_heap_seeds(shipped, 4))
    df = simulate(point_spec(soil, soil.stage("bbd"), LEVELS, run=1, seed=104), rev="test").set_index("response")
    assert sorted(calls) == [("drum", 104, 1), ("repose", 104, 4)]
    s, d = df.loc["static_angle"], df.loc["dynamic_angle"]
    # the heap: mean of 30, 32, 34, 36 and its SD (ddof 1) sqrt(20 / 3)
    assert (s["replicates"], s["seeds"], s["n"]) == (4, "104 105 106 107", 4)
    assert s["value"] == pytest.approx(33.0) and s["sd"] == pytest.approx(np.sqrt(20.0 / 3.0))
    assert (d["replicates"], d["seeds"], d["n"], d["value"]) == (1, "104", 1, 45.0)
    assert np.isnan(d["sd"])


def test_cost_counts_each_responses_own_seeds(tmp_path, shipped):
    from soilcal.dem import cost

    soil = load_copy(tmp_path, "xinjiang-vineyard", _with_heap_seeds(shipped, 4))
    spec = point_spec(soil, soil.stage("bbd"), LEVELS, run=1, seed=3)
    heap, drum = spec["responses"]["static_angle"], spec["responses"]["dynamic_angle"]
    one = cost.estimate("repose", heap["setup"], spec["params"], "quick")
    two = cost.estimate("drum", drum["setup"], spec["params"], "quick")
    got = cost.estimate_spec(spec)
    assert got.runs == 5
    assert got.particle_steps == pytest.approx(4 * one.particle_steps + two.particle_steps)


@pytest.mark.parametrize("bad", [0, 1.5, "four"])
def test_a_bad_count_is_refused_naming_the_field(tmp_path, shipped, bad):
    data = _plain(shipped)
    data["simulation"]["responses"]["static_angle"]["replicates"] = bad
    with pytest.raises(InputError, match=r"simulation\.responses\.static_angle\.replicates"):
        load_copy(tmp_path, "xinjiang-vineyard", data)


def test_simulation_csv_says_where_a_responses_count_comes_from(tmp_path, shipped):
    from soilcal.chain.provenance import simulation_setup

    rows = simulation_setup(load_copy(tmp_path, "xinjiang-vineyard", _with_heap_seeds(shipped, 4))).set_index("item")
    row = rows.loc["simulation.responses.static_angle.replicates"]
    assert (str(row["value"]), row["origin"]) == ("4", "soil")
    assert "simulation.responses.dynamic_angle.replicates" not in rows.index
    plain = simulation_setup(load_copy(tmp_path, "xinjiang-vineyard", _plain(shipped))).set_index("item")
    assert not any(i.endswith(".replicates") and i.startswith("simulation.responses.") for i in plain.index)
