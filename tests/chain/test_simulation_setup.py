"""results/<soil>/dem/simulation.csv: every value a soil's DEM runs are set up with, and
where it comes from (the soil, a documented default, the named setup, the preset)
(soilcal.chain.provenance.simulation_setup)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from soilcal.chain.provenance import SETUP_COLUMNS, simulation_setup
from soilcal.config import load_soil
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def own(tmp_path_factory):
    """The cinnamon soil as a user's own: no seed, two replicates, its own tube, particle
    sizes and sphere radius, a verification seed offset of its own."""
    d = yaml.safe_load((ROOT / "config/soils/cinnamon-soil.yaml").read_text())
    d.pop("seed")
    d["simulation"]["replicates"] = 2
    d["simulation"]["verification"] = {"seed_offset": 500}
    d["simulation"]["responses"]["stacking_angle"]["set"] = {
        "tube_diameter": 0.08, "radius": 0.004, "paper_psd": [[0.001, 40], [0.0005, 60]]}
    p = tmp_path_factory.mktemp("own") / "cinnamon-soil.yaml"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    soil = load_soil(p, ROOT / "resources")
    return simulation_setup(soil).set_index("item")


def row(df, item):
    r = df.loc[item]
    return r["value"], r["origin"]


def test_the_block_options_say_whether_the_soil_or_the_default_set_them(own):
    assert list(own.reset_index().columns) == SETUP_COLUMNS
    assert row(own, "seed") == ("0", "default")
    assert row(own, "simulation.replicates") == ("2", "soil")
    assert row(own, "simulation.preset") == ("quick", "default")
    assert row(own, "simulation.design") == ("recipe", "default")
    assert row(own, "simulation.verification.seed_offset") == ("500", "soil")
    assert row(own, "simulation.verification.replicates") == ("4", "default")
    assert row(own, "dem.soil_density") == ("1394", "soil")
    assert row(own, "dem.steel_density") == ("7850.0", "default")
    assert "carbon steel" in own.loc["dem.steel_density", "note"]


def test_every_setup_value_names_the_soil_or_the_named_setup(own):
    base = "simulation.responses.stacking_angle"
    assert row(own, f"{base}.setup") == ("cinnamon-soil", "soil")
    assert row(own, f"{base}.setup.tube_diameter") == ("0.08", "soil")
    assert "0.06" in own.loc[f"{base}.setup.tube_diameter", "note"]  # the named setup's value it replaces
    assert json.loads(own.loc[f"{base}.setup.paper_psd", "value"]) == [[0.001, 40], [0.0005, 60]]
    assert own.loc[f"{base}.setup.paper_psd", "origin"] == "soil"
    # not replaced: the shipped soil's apparatus, said as such
    assert row(own, f"{base}.setup.lift_speed") == ("0.05", "named setup")
    assert row(own, f"{base}.setup.wall_material") == ("steel", "named setup")
    # left to the preset, with the value the quick run takes: spheres of the soil's 4 mm radius
    # filling its 80 mm tube, the engine's rolling model, the quick preset's time-step fraction
    assert own.loc[f"{base}.setup.n_particles", "origin"] == "preset"
    assert int(own.loc[f"{base}.setup.n_particles", "value"]) > 20
    assert row(own, f"{base}.setup.rolling_model") == ("constant_torque", "preset")
    assert row(own, f"{base}.setup.dt_fraction") == ("0.3", "preset")
    # the quick preset caps the shear modulus at 5e5 Pa: cinnamon's printed 3.814e6 Pa is scaled by 5e5 / 3.814e6
    assert float(own.loc[f"{base}.setup.stiffness_scale", "value"]) == pytest.approx(5e5 / 3.814e6, rel=1e-5)


def test_the_cohesion_factor_is_the_sauter_radius_ratio_of_the_soil_s_own_sizes(own):
    # spheres of radius 0.004 m +/- 10 %, uniform by number on [3.6, 4.4] mm:
    # r32 = 3/4 (b^4 - a^4) / (b^3 - a^3) = 0.75 (374.8096 - 167.9616) / (85.184 - 46.656) mm
    #     = 0.75 x 206.848 / 38.528 mm = 4.026578 mm;
    # the soil's paper_psd (1 mm 40 %, 0.5 mm 60 % by mass): r32 = 1 / (0.4 / 1 + 0.6 / 0.5) mm = 0.625 mm;
    # factor 4.026578 / 0.625 = 6.442525
    value, origin = row(own, "simulation.responses.stacking_angle.cohesion_scale[quick]")
    assert origin == "computed" and float(value) == pytest.approx(6.442525, rel=1e-6)


def _own(tmp_path, soil, edit):
    d = yaml.safe_load((ROOT / f"config/soils/{soil}.yaml").read_text())
    edit(d)
    p = tmp_path / f"{soil}.yaml"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    return simulation_setup(load_soil(p, ROOT / "resources")).set_index("item")


def test_a_soil_bin_scales_the_surface_energy_against_the_soil_s_own_particle_sizes(tmp_path):
    """A furrow tank of the soil's own 5 mm spheres whose surface energy is for 4 mm particles
    (set.paper_psd): the factor is taken against those, not against the shipped soil's 8 mm
    paper particles, and the file says so."""
    df = _own(tmp_path, "yangtze-clay-loam", lambda d: d["measurements"]["traction_resistance"].update(
        set={"particle_radius": 0.005, "paper_psd": [[0.004, 100]]}))
    where = "measurements.traction_resistance"
    # radii uniform by number on [4.5, 5.5] mm: r32 = 0.75 (915.0625 - 410.0625) / (166.375 - 91.125) mm
    # = 0.75 x 505 / 75.25 mm = 5.033223 mm; over the 4 mm of paper_psd: 1.258306
    value, origin = row(df, f"{where}.cohesion_scale[quick]")
    assert origin == "computed" and float(value) == pytest.approx(1.258306, rel=1e-6)
    assert "paper_psd" in df.loc[f"{where}.cohesion_scale[quick]", "note"]
    assert json.loads(df.loc[f"{where}.setup.paper_psd", "value"]) == [[0.004, 100]]
    assert df.loc[f"{where}.setup.paper_psd", "origin"] == "soil"
    # left out: the named setup's None, said to be the shipped soil's paper particles
    df = _own(tmp_path, "yangtze-clay-loam", lambda d: None)
    assert row(df, f"{where}.setup.paper_psd") == ("", "named setup")
    assert "paper preset's bin" in df.loc[f"{where}.setup.paper_psd", "note"]


def test_a_soil_bin_paper_psd_in_millimetres_is_refused(tmp_path):
    with pytest.raises(InputError, match=r"measurements\.traction_resistance\.set\.paper_psd: expected particle radii "
                                         r"in metres"):
        _own(tmp_path, "yangtze-clay-loam", lambda d: d["measurements"]["traction_resistance"].update(
            set={"paper_psd": [[4, 100]]}))


@pytest.mark.parametrize("soil,where", [("cinnamon-soil", "measurements.cutting_resistance"),
                                        ("cinnamon-soil", "simulation.responses.stacking_angle"),
                                        ("yangtze-clay-loam", "simulation.responses.area_difference")])
def test_scale_cohesion_false_is_taken_and_said(tmp_path, soil, where):
    """``scale_cohesion: false`` (README): the runs keep the soil's surface energies (factor 1,
    where the quick particles would otherwise scale them by a Sauter-radius ratio other than 1)."""
    def edit(d):
        block, key = where.split(".", 1) if where.startswith("measurements") else ("simulation", where.split(".", 1)[1])
        entry = d[block]
        for k in key.split("."):
            entry = entry[k]
        entry["set"] = {**(entry.get("set") or {}), "scale_cohesion": False}

    before = _own(tmp_path, soil, lambda d: None)
    assert float(before.loc[f"{where}.cohesion_scale[quick]", "value"]) != pytest.approx(1.0, rel=1e-3)
    df = _own(tmp_path, soil, edit)
    value, origin = row(df, f"{where}.cohesion_scale[quick]")
    assert (float(value), origin) == (1.0, "computed")
    assert "scale_cohesion: false" in df.loc[f"{where}.cohesion_scale[quick]", "note"]
    assert row(df, f"{where}.setup.scale_cohesion") == ("false", "soil")


def test_the_workflow_design_is_named_as_the_workflow_config_s(tmp_path):
    soil = load_soil(ROOT / "config/soils/cinnamon-soil.yaml", ROOT / "resources", design="printed")
    df = simulation_setup(soil, design_override="printed").set_index("item")
    assert row(df, "simulation.design") == ("printed", "workflow config")
    assert row(df, "seed") == ("1082", "soil")


def test_the_tool_tests_say_their_defaults(own):
    assert row(own, "measurements.cutting_resistance.replicates") == ("3", "default")
    assert row(own, "measurements.cutting_resistance.preset") == ("quick", "default")
    # its setup plate-line (the directrix column chooses the plate per row)
    assert row(own, "measurements.cutting_resistance.setup.shape") == ("line", "named setup")
    assert json.loads(own.loc["measurements.cutting_resistance.covariates", "value"]) == ["directrix"]
    assert own.loc["measurements.cutting_resistance.cohesion_scale[quick]", "origin"] == "computed"
    # the quick preset's bin, which the named setup does not hold: a periodic slab of 7 mm
    # spheres and a 0.2 m pass (bulldozing.py, PRESET_SETTINGS)
    assert row(own, "measurements.cutting_resistance.setup.travel") == ("0.2", "preset")
    assert row(own, "measurements.cutting_resistance.setup.particle_radius") == ("0.007", "preset")
    assert row(own, "measurements.cutting_resistance.setup.periodic") == ("true", "preset")


def test_a_parameter_a_stage_sets_says_the_stage_replaces_it():
    # the black soil's simulation.params give the soil-steel friction 0.55; its stage soil-65mn varies it
    soil = load_soil(ROOT / "config/soils/black-soil.yaml", ROOT / "resources")
    df = simulation_setup(soil).set_index("item")
    assert row(df, "dem.soil_steel_static_friction") == ("0.55", "soil")
    assert df.loc["dem.soil_steel_static_friction", "note"].endswith("replaced by the fixed value or factor of stage(s) "
                                                                     "soil-65mn")
    assert "replaced" not in df.loc["dem.soil_density", "note"]


def test_an_adaptive_soil_lists_its_design_s_settings_and_no_tool_tests(tmp_path):
    d = yaml.safe_load((ROOT / "config/soils/cinnamon-soil.yaml").read_text())
    d["simulation"]["design"] = "adaptive"
    d["simulation"]["adaptive"] = {"budget": 30}
    p = tmp_path / "cinnamon-soil.yaml"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    df = simulation_setup(load_soil(p, ROOT / "resources")).set_index("item")
    assert row(df, "simulation.design") == ("adaptive", "soil")
    assert row(df, "simulation.adaptive.budget") == ("30", "soil")
    assert row(df, "simulation.adaptive.verify_seeds") == ("4", "default")
    assert row(df, "measurements") == ("not run", "workflow")
    assert not any(i.startswith(("measurements.", "simulation.verification.", "simulation.path."))
                   for i in df.index)


@pytest.mark.parametrize("soil,design", [(p.stem, None) for p in sorted((ROOT / "config/soils").glob("*.yaml"))]
                         + [("cinnamon-soil", "adaptive")])
def test_the_rule_s_params_hold_everything_the_file_reads_and_no_documentation(soil, design):
    """The workflow rule takes setup_inputs(data) as its params: simulation.csv from them is the
    file from the whole soil, and an edit of the soil's citation, notes, errata, a stage's or a
    measurement's note, a property the runs do not take or (recipe) a target's value leaves them
    as they were, so it does not rerun the rule."""
    import copy

    from soilcal.chain.provenance import setup_inputs
    from soilcal.config.load import Soil

    full = load_soil(ROOT / f"config/soils/{soil}.yaml", ROOT / "resources", design=design)
    part = Soil(path=full.path, data=setup_inputs(full.data), resources_root=full.resources_root,
                defaulted=full.defaulted)
    assert simulation_setup(part, design).equals(simulation_setup(full, design))
    d = copy.deepcopy(full.data)
    d["notes"] = "edited"
    d["citation"] = {"title": "another"}
    d.setdefault("errata", []).append({"where": "x", "printed": 1, "note": "y"})
    d["stages"][0]["note"] = "edited"
    d["properties"]["moisture_content"] = {"value": 30.0, "unit": "%"}
    for m in (d.get("measurements") or {}).values():
        m["note"] = "edited"
    if design is None:
        for t in d["targets"].values():
            if t.get("value") is not None:
                t["value"] = t["value"] + 1
    assert setup_inputs(d) == setup_inputs(full.data)
    # what it reads does change them
    d["simulation"]["replicates"] = 7
    assert setup_inputs(d) != setup_inputs(full.data)
