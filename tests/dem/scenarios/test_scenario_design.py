"""The soils' simulation blocks: which scenario measures which design response."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

from soilcal.config.load import Soil, load_soil
from soilcal.dem.scenarios import design
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[3]
SOILS = ["black-soil", "cinnamon-soil", "guangxi-cohesive", "xinjiang-vineyard", "yangtze-clay-loam"]


def _soil(name):
    return load_soil(ROOT / f"config/soils/{name}.yaml", ROOT / "resources")


@pytest.mark.parametrize("name", SOILS)
def test_every_design_response_has_a_scenario(name):
    soil = _soil(name)
    for rid in design.response_ids(soil.data):
        spec = design.spec(soil, rid)
        assert spec.scenario in ("repose", "drum", "furrow") and spec.measure


def test_generated_box_behnken_of_a_lost_table():
    # guangxi-cohesive: Table 8 lost; 17 runs of A, B, G from the printed levels (Sec. 3.2)
    df = design.design_levels(_soil("guangxi-cohesive"), "bbd")
    assert len(df) == 17 and list(df["run"]) == list(range(1, 18))
    assert sorted(set(df["A"])) == pytest.approx([0.27, 0.33, 0.39])
    assert sorted(set(df["G"])) == pytest.approx([0.04, 0.06, 0.08])
    centre = (df["A"] == 0.33) & (df["B"] == 0.488) & (df["G"] == 0.06)
    assert centre.sum() == 5  # five centre points (Sec. 3.3)
    with pytest.raises(InputError, match=r"stages\.pb\.factors\.A"):
        design.design_levels(_soil("guangxi-cohesive"), "pb")
    with pytest.raises(InputError, match=r"stages\.steepest\.factors\.A\.levels"):
        design.design_levels(_soil("guangxi-cohesive"), "steepest")


def test_generated_screening_design_has_the_printed_run_count():
    # guangxi-cohesive Sec. 3.1: a 12-run Plackett-Burman design of 7 factors (an N-run
    # design has N - 1 columns; 7 columns alone would give the 8-run design).  The levels
    # of A..F are lost; with levels supplied every column is balanced: 6 high, 6 low.
    soil = _soil("guangxi-cohesive")
    data = copy.deepcopy(soil.data)
    pb = next(st for st in data["stages"] if st["id"] == "pb")
    for c in "ABCDEF":
        pb["factors"][c].update(low=0.1, high=0.2)
    df = design.design_levels(Soil(soil.path, data, soil.resources_root), "pb")
    assert len(df) == 12
    for c in "ABCDEFG":
        assert sorted(df[c].value_counts().to_dict().values()) == [6, 6]
    pb["runs"] = 16
    assert len(design.design_levels(Soil(soil.path, data, soil.resources_root), "pb")) == 16
    pb["runs"] = 14  # no Plackett-Burman design has 14 runs
    with pytest.raises(InputError, match=r"stages\.pb\.runs"):
        design.design_levels(Soil(soil.path, data, soil.resources_root), "pb")


def test_printed_coded_table_is_decoded():
    # cinnamon soil Table 6 (coded) -> A 0.08/0.11/0.14, B 0.24/0.38/0.52, C 0.42/0.54/0.66
    df = design.design_levels(_soil("cinnamon-soil"), "bbd")
    assert len(df) == 17 and "stacking_angle" in df
    assert sorted(set(df["A"])) == [0.08, 0.11, 0.14]
    assert sorted(set(df["B"])) == [0.24, 0.38, 0.52]
    assert sorted(set(df["C"])) == [0.42, 0.54, 0.66]


def test_parameter_precedence():
    soil = _soil("xinjiang-vineyard")
    spec = design.spec(soil, "static_angle")
    # simulation.params corrects the printed 175.7567 kg/m^3 (Table 2)
    p = design.design_params(soil, "bbd", dict(B=0.63, D=0.08, F=0.5, H=0.1), spec)
    assert p.soil_density == 1757.567 and p.soil_poisson == 0.33
    assert p.soil_soil_restitution == 0.63 and p.soil_shear_modulus == 1.0e7  # fixed, Sec. steepest
    # a factor level wins over simulation.params
    spec2 = design.SimulationSpec(**{**spec.__dict__, "params": dict(soil_soil_restitution=0.2)})
    assert design.design_params(soil, "bbd", dict(B=0.63), spec2).soil_soil_restitution == 0.63
    # a printed shear modulus is read: Yangtze clay loam 'G = 1 MP' (Sec. 2.2.4) = 1e6 Pa
    y = _soil("yangtze-clay-loam")
    assert design.design_params(y, "bbd", {}, design.spec(y, "area_difference")).soil_shear_modulus == 1.0e6


def _broken(tmp_path, edit):
    src = ROOT / "config/soils/cinnamon-soil.yaml"
    data = yaml.safe_load(src.read_text())
    edit(data["simulation"])
    out = tmp_path / "cinnamon-soil.yaml"
    out.write_text(yaml.safe_dump(data, sort_keys=False))
    return out


@pytest.mark.parametrize("edit, field", [
    (lambda s: s["responses"]["stacking_angle"].update(scenario="pile"),
     r"simulation\.responses\.stacking_angle\.scenario: expected one of"),
    (lambda s: s["responses"]["stacking_angle"].update(setup="no-such"),
     r"simulation\.responses\.stacking_angle\.setup: expected a setup of repose"),
    (lambda s: s["responses"]["stacking_angle"].update(set=dict(tube_colour=1)),
     r"simulation\.responses\.stacking_angle\.set\.tube_colour"),
    (lambda s: s["responses"]["stacking_angle"].update(set=dict(tube_diameter=-0.06)),
     r"simulation\.responses\.stacking_angle\.set\.tube_diameter"),
    (lambda s: s.update(params=dict(soil_soil_restitution=1.5)),
     r"simulation\.params\.soil_soil_restitution: expected a coefficient of restitution"),
    (lambda s: s.update(params=dict(soil_colour=1.0)), r"simulation\.params"),
    (lambda s: s["responses"].update(furrow_area={"scenario": "furrow", "setup": "yangtze-opener",
                                                  "measure": "x"}),
     r"simulation\.responses\.furrow_area: expected a response id of a stage"),
    (lambda s: s.update(replicates=0), r"simulation\.replicates"),
])
def test_bad_simulation_block_fails_at_load(tmp_path, edit, field):
    with pytest.raises(InputError, match=field):
        load_soil(_broken(tmp_path, edit), ROOT / "resources")


def test_unknown_measure_names_the_field():
    soil = _soil("cinnamon-soil")
    data = copy.deepcopy(soil.data)
    data["simulation"]["responses"]["stacking_angle"]["measure"] = "angle_of_nothing"
    bad = Soil(soil.path, data, soil.resources_root)
    with pytest.raises(InputError, match=r"simulation\.responses\.stacking_angle\.measure"):
        design.simulate_point(bad, "bbd", dict(A=0.08, B=0.24, C=0.54), "stacking_angle",
                              threads=1, seed=0)


@pytest.mark.parametrize("soil_name,rid,measure", [
    ("cinnamon-soil", "stacking_angle", "measure_errors"),     # a text diagnostic
    ("cinnamon-soil", "stacking_angle", "retained_fraction"),  # a funnel's; this is a cylinder
    ("yangtze-clay-loam", "area_difference", "bin_from_cache"),
])
def test_a_measure_that_is_not_a_result_of_the_setup_fails_at_load(soil_name, rid, measure):
    soil = _soil(soil_name)
    data = copy.deepcopy(soil.data)
    data["simulation"]["responses"][rid]["measure"] = measure
    with pytest.raises(InputError, match=rf"simulation\.responses\.{rid}\.measure"):
        design.check_block(soil.path, data)


def test_a_funnel_load_is_checked_at_the_soils_density_at_load():
    """Black soil: 0.5 kg fills 0.5 / (rho 0.6) of the 3.51 L funnel (192/50 mm, 274 mm
    high).  At the soil's 1560 kg/m^3 that is 0.53 L; at 200 kg/m^3 it is 4.2 L, which the
    funnel cannot hold, and the config check must say so (the default density, 1394 kg/m^3,
    would let it pass)."""
    soil = _soil("black-soil")
    data = copy.deepcopy(soil.data)
    design.check_block(soil.path, data)
    data["simulation"]["params"]["soil_density"] = 200.0
    with pytest.raises(InputError, match=r"accumulation_angle\.set\.load_mass: expected a load "
                                         r"that fits the funnel \(3\.51 L at 200 kg/m\^3"):
        design.check_block(soil.path, data)


@pytest.mark.slow
def test_low_restitution_corner_of_a_screening_design_runs():
    """003 Table 3 run 1 (G 10 MPa, soil-soil e 0.15, mu 1.16, H 0.3 J/m^2) through the
    100 mm cylinder lift: with the step at 30 % of the Rayleigh time the heap blew up (overlap
    above 30 % of a radius); the damped-contact cap (materials.py) lowers the step.  The heap
    here has 500 spheres (the quick preset's 1000 set down on the response): without the cap
    it still blows up (step 5613 with the soil's seed), and with it the angle was 34.4, 22.6
    and 28.0 deg with seeds 3 (the soil's), 0 and 1."""
    soil = _soil("xinjiang-vineyard")
    data = copy.deepcopy(soil.data)
    data["simulation"]["responses"]["static_angle"]["set"] = dict(n_particles=500)
    soil = Soil(soil.path, data, soil.resources_root)
    row = design.design_levels(soil, "pb").iloc[0]
    assert (row["B"], row["C"], row["H"]) == (0.15, 1.16, 0.3)
    levels = {k: row[k] for k in soil.stage("pb")["factors"]}
    value, res = design.simulate_point(soil, "pb", levels, "static_angle", threads=1)
    assert res.n_particles == 500
    assert res.responses["settled"] == 1 and np.isfinite(value) and 15 < value < 50
    assert res.setup["dt_fraction"] < 0.3


@pytest.mark.slow
def test_furrow_centre_point_does_not_jam_against_the_tank_end(tmp_path, monkeypatch):
    """Zeng et al. 2023 Table 4 run 25 (centre point; G 1 MPa): with 0.1 m of soil left
    ahead of the opener at the end of the pass, the soil pushed ahead of it jammed against
    the tank's far wall (overlap above 50 % of a radius); the quick tank keeps
    ``front_clearance`` (furrow.py) of soil ahead of the share point, so the far wall's
    load rises by a small part of the traction over the pass."""
    monkeypatch.setenv("SOILCAL_SCENARIO_CACHE", str(tmp_path))
    soil = _soil("yangtze-clay-loam")
    row = design.design_levels(soil, "bbd").iloc[24]
    assert (row["A"], row["B"], row["C"], row["D"]) == (0.45, 0.40, 0.17, 7.00)
    levels = {k: row[k] for k in soil.stage("bbd")["factors"]}
    value, res = design.simulate_point(soil, "bbd", levels, "area_difference", threads=1)
    r = res.responses
    assert np.isfinite(value) and value > 0
    assert r["traction_N"] > 0
    # the far wall (x_hi) is pushed, not pulled: its load may rise a little, not by a jam's
    # share of the traction (919 N of 1710 N with 0.4 m of clearance, furrow.py)
    assert -0.1 * r["traction_N"] < r["far_wall_rise_N"] < 0.25 * r["traction_N"]


def test_repeated_points_get_the_next_seeds():
    # cinnamon soil Table 6: 12 edge points and 5 centre points (A 0.11, B 0.38, C 0.54)
    soil = _soil("cinnamon-soil")
    df = design.design_levels(soil, "bbd")
    seeds = design.design_seeds(soil, "bbd", df)
    centre = ((df["A"] == 0.11) & (df["B"] == 0.38) & (df["C"] == 0.54)).to_numpy()
    assert centre.sum() == 5
    assert sorted(np.asarray(seeds)[centre]) == [1082, 1083, 1084, 1085, 1086]  # seed: 1082
    assert set(np.asarray(seeds)[~centre]) == {1082}
    assert design.design_seeds(soil, "bbd", df, seed=0)[:1] == [0]
    # with k replicates per point, repetition j starts at seed + j k (no shared seeds)
    s3 = np.asarray(design.design_seeds(soil, "bbd", df, replicates=3))
    assert sorted(s3[centre]) == [1082, 1085, 1088, 1091, 1094]
