"""A funnel heap read at a fixed simulated time (``read_time`` of the repose setup): the
cohesive soil's heap has no resting state under its constant-torque rolling model
(benchmarks/results/funnel_reach.md), so it is read at its paper's time after the load's
generation."""

from __future__ import annotations

import pytest

from soilcal.dem.scenarios import design
from soilcal.errors import InputError
from soil_copies import ROOT, load_copy, read_shipped

from soilcal.config.load import load_soil


def test_the_cohesive_heap_is_read_at_the_paper_s_time_after_its_generation():
    # 004 Sec. 2.6: "a total simulation duration of 10 s" including the generation of "0.2 kg"
    # at "0.05 kg/s": the heap's time after the generation is 10 s - 0.2 / 0.05 s
    total_s, mass_kg, rate_kg_s = 10.0, 0.2, 0.05
    soil = load_soil(ROOT / "config/soils/guangxi-cohesive.yaml", ROOT / "resources")
    setup = design.spec(soil, "angle_of_repose").setup
    assert setup["read_time"] == pytest.approx(total_s - mass_kg / rate_kg_s)
    # in EDEM, whose standard rolling friction is a constant torque against the rotation
    assert setup["rolling_model"] in (None, "constant_torque")


@pytest.mark.parametrize("value", [-10.0, 0.0, "10 s", float("nan")])
def test_a_bad_read_time_names_the_soil_file_and_field(tmp_path, value):
    d = read_shipped("guangxi-cohesive")
    d["simulation"]["responses"]["angle_of_repose"]["set"]["read_time"] = value
    with pytest.raises(InputError) as e:
        load_copy(tmp_path, "guangxi-cohesive", d)
    assert e.value.field == "simulation.responses.angle_of_repose.set.read_time"
    assert str(e.value.path).endswith("guangxi-cohesive.yaml") and "> 0 s after the release" in e.value.expected


def test_a_read_time_within_the_cover_s_travel_names_the_soil_file_and_field(tmp_path):
    # the cover is pulled 2.5 outlet radii + a sphere's diameter at cover_speed before the heap
    # forms: a reading within that travel is refused at start-up, not after the fill's settle
    soil = load_soil(ROOT / "config/soils/guangxi-cohesive.yaml", ROOT / "resources")
    s = design.spec(soil, "angle_of_repose").setup
    from soilcal.dem.scenarios import repose

    r_max = repose.sizing(s, "quick", None)["r_max"]
    travel = (2.5 * s["funnel_bottom_diameter"] / 2 + 2 * r_max) / s["cover_speed"]
    d = read_shipped("guangxi-cohesive")
    d["simulation"]["responses"]["angle_of_repose"]["set"]["read_time"] = 0.9 * travel
    with pytest.raises(InputError) as e:
        load_copy(tmp_path, "guangxi-cohesive", d)
    assert e.value.field == "simulation.responses.angle_of_repose.set.read_time"
    assert str(e.value.path).endswith("guangxi-cohesive.yaml") and "cover takes" in e.value.expected
