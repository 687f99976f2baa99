"""The particle sizes a soil's surface energy is for hold for its tool tests too.

A soil of one's own calibrates its surface energy on its own particles
(``simulation.responses.<id>.set.paper_psd``).  A soil-bin tool test that leaves ``paper_psd``
out must scale that calibrated surface energy against the same particles, not against the
paper preset's bin of the named setup (a shipped soil's).  The factor is the ratio of Sauter
radii r32 = <r^3>/<r^2>, worked out by hand: radii uniform by number on [a, b] have
r32 = 3 (b^4 - a^4) / (4 (b^3 - a^3)); discrete radii r_k of mass fractions f_k have
r32 = 1 / sum f_k / r_k."""

from __future__ import annotations

import textwrap

import pytest
import yaml

from own_soil import bbd_soil, write_soil
from soilcal.chain.provenance import simulation_setup
from soilcal.config import load_soil
from soilcal.config.measurements import conditions
from soilcal.errors import InputError

OWN_PSD = [[0.001, 30], [0.0005, 70]]

#: the soil's blocks beside its one Box-Behnken stage (own_soil.bbd_soil)
BLOCKS = textwrap.dedent("""\
    properties:
      particle_density: {value: 2650, unit: kg/m^3}
      poisson_ratio: {value: 0.35, unit: "-"}
      shear_modulus: {value: 2.0, unit: MPa}
    simulation:
      params:
        soil_soil_restitution: 0.4
        soil_steel_restitution: 0.4
        soil_steel_static_friction: 0.5
        soil_steel_rolling_friction: 0.1
      responses:
        angle: {scenario: repose, setup: cinnamon-soil, measure: angle_deg, set: {paper_psd: [[0.001, 30], [0.0005, 70]]}}
    measurements:
      tiller:
        table: tiller.csv
        scenario: rotary
        setup: rpm-250
        set: {depth: 0.1}
        responses:
          - {measure: flatness_mm, value: flatness_mm, unit: mm}
        calibrated: {stage: bbd, case: angle}
    """)


def _soil(tmp_path, edit=None):
    d = bbd_soil("own-psd", {"rolling": (0.1, 0.3), "energy": (0.2, 0.6), "sfric": (0.4, 0.8)}, target_angle=36.0,
                 **yaml.safe_load(BLOCKS))
    if edit:
        edit(d)
    return load_soil(write_soil(tmp_path, d, {"tiller.csv": "flatness_mm\n14.0\n"}), tmp_path, source="dem")


def test_a_tool_test_takes_the_soil_s_own_particle_sizes(tmp_path):
    soil = _soil(tmp_path)
    assert [c.setup["paper_psd"] for c in conditions(soil)] == [OWN_PSD]
    df = simulation_setup(soil).set_index("item")
    where = "measurements.tiller"
    assert df.loc[f"{where}.setup.paper_psd", "origin"] == "soil"
    assert "simulation.responses.angle.set.paper_psd" in df.loc[f"{where}.setup.paper_psd", "note"]
    # the quick bin's 12 mm +- 10 % spheres: r32 = 0.75 (13.2^4 - 10.8^4) / (13.2^3 - 10.8^3) mm
    # = 1.2 x 0.75 (11^4 - 9^4) / (11^3 - 9^3) mm = 1.2 x 0.75 x 8080 / 602 mm = 12.079734 mm;
    # the soil's particles: r32 = 1 / (0.3 / 1 + 0.7 / 0.5) mm = 1 / 1.7 mm; ratio 20.535548
    # (against the shipped soil's paper bin, 1.5 mm +- 1/3, r32 = 0.75 x 15 / 7 mm: 7.516279)
    assert float(df.loc[f"{where}.cohesion_scale[quick]", "value"]) == pytest.approx(20.535548, rel=1e-6)


def test_a_tool_test_s_own_particle_sizes_stay_its_own(tmp_path):
    soil = _soil(tmp_path, lambda d: d["measurements"]["tiller"]["set"].update(paper_psd=[[0.002, 100]]))
    assert [c.setup["paper_psd"] for c in conditions(soil)] == [[[0.002, 100]]]


def test_responses_with_different_particle_sizes_leave_the_test_to_say_which(tmp_path):
    def edit(d):
        d["stages"][0]["responses"].append({"id": "angle2", "name": "Drum angle", "unit": "deg"})
        d["simulation"]["responses"]["angle2"] = {"scenario": "repose", "setup": "cinnamon-soil",
                                                  "measure": "angle_deg", "set": {"paper_psd": [[0.002, 100]]}}
    with pytest.raises(InputError) as exc:
        _soil(tmp_path, edit)
    assert exc.value.field == "measurements.tiller.set.paper_psd"
    assert "own-psd.yaml" in str(exc.value) and "different" in exc.value.expected


def test_particle_sizes_equal_in_value_are_one_set(tmp_path):
    # [[0.001, 30], ...] and [[0.001, 30.0], ...] are the same particles
    def edit(d):
        d["stages"][0]["responses"].append({"id": "angle2", "name": "Drum angle", "unit": "deg"})
        d["simulation"]["responses"]["angle2"] = {"scenario": "repose", "setup": "cinnamon-soil",
                                                  "measure": "angle_deg",
                                                  "set": {"paper_psd": [[0.001, 30.0], [0.0005, 70.0]]}}
    soil = _soil(tmp_path, edit)
    assert [c.setup["paper_psd"] for c in conditions(soil)] == [OWN_PSD]


def test_a_response_on_its_setup_s_particles_beside_own_ones_leaves_the_test_to_say_which(tmp_path):
    # the second response leaves paper_psd to its named setup (black-soil-stage1: radii 1 and
    # 2 mm, 50 % each): the soil's surface energy is calibrated on two sets of particles
    def edit(d):
        d["stages"][0]["responses"].append({"id": "angle2", "name": "Funnel angle", "unit": "deg"})
        d["simulation"]["responses"]["angle2"] = {"scenario": "repose", "setup": "black-soil-stage1",
                                                  "measure": "angle_deg"}
    with pytest.raises(InputError) as exc:
        _soil(tmp_path, edit)
    assert exc.value.field == "measurements.tiller.set.paper_psd"
    assert "angle2 (its setup's)" in exc.value.expected
