"""A soil calibrated on the DEM sets every soil parameter its runs use
(soilcal.chain.provenance): the engine's defaults are one soil study's values, so a soil that
left one out would run with another soil's friction or cohesion."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import yaml

from soilcal.chain.provenance import GENERIC, given, soil_parameters
from soilcal.config import load_soil
from soilcal.dem.scenarios.base import DemParams
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]


def _cinnamon(tmp_path, edit, soil="cinnamon-soil"):
    d = yaml.safe_load((ROOT / f"config/soils/{soil}.yaml").read_text())
    edit(d)
    p = tmp_path / f"{soil}.yaml"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    return p


def test_the_soil_parameters_are_every_field_but_the_generic_ones():
    assert set(soil_parameters()) | set(GENERIC) == set(DemParams.names())
    assert "soil_soil_surface_energy" in soil_parameters() and "soil_density" in soil_parameters()


def test_a_missing_soil_parameter_is_named_at_start_up(tmp_path):
    p = _cinnamon(tmp_path, lambda d: d["simulation"].pop("params"))  # its density came from there
    with pytest.raises(InputError, match="simulation.params: expected a value of every soil parameter the runs of "
                                         "stage 'pb' use .* missing: soil_density"):
        load_soil(p, ROOT / "resources")


def test_a_missing_soil_property_names_the_property_that_would_give_it(tmp_path):
    """The soil's density, Poisson ratio and shear modulus may come from its printed
    properties: the error names them, so that a soil listing only its bulk density learns
    where its particle density goes."""
    def no_density(d):
        d["simulation"].pop("params")
        d["properties"].pop("poisson_ratio")

    p = _cinnamon(tmp_path, no_density)
    with pytest.raises(InputError) as e:
        load_soil(p, ROOT / "resources")
    assert e.value.expected.endswith("missing: soil_density (or properties.particle_density with its unit), "
                                     "soil_poisson (or properties.poisson_ratio with its unit)")


def test_a_derived_stage_counts_the_factors_of_the_stage_it_comes_from(tmp_path):
    # the cinnamon path and Box-Behnken stages vary fewer parameters than the screening; the
    # rest are held at the screening's intermediate levels, so they are set
    soil = load_soil(ROOT / "config/soils/cinnamon-soil.yaml", ROOT / "resources")
    pb = {soil.data["parameters"][f["parameter"]]["pair"].replace("-", "_") + "_"
          + soil.data["parameters"][f["parameter"]]["kind"] for f in soil.stage("pb")["factors"].values()}
    assert pb <= given(soil.data, "bbd")


def test_every_shipped_dem_soil_sets_its_parameters():
    for p in sorted((ROOT / "config/soils").glob("*.yaml")):
        load_soil(p, ROOT / "resources")  # raises if a simulated stage leaves a soil parameter out


def test_a_stage_parameter_maps_to_its_field_as_the_dem_jobs_map_it():
    import copy

    soil = load_soil(ROOT / "config/soils/cinnamon-soil.yaml", ROOT / "resources")
    sym, f = next(iter(soil.stage("pb")["factors"].items()))
    entry = soil.data["parameters"][f["parameter"]]
    assert f"{entry['pair'].replace('-', '_')}_{entry['kind']}" in given(soil.data, "pb")
    # a parameter without pair and kind maps to none: named, not left out silently
    data = copy.deepcopy(soil.data)
    del data["parameters"][f["parameter"]]["pair"]
    with pytest.raises(InputError) as e:
        given(data, "pb", soil_path="soil.yaml")
    assert (e.value.path, e.value.field, e.value.got) == ("soil.yaml", f"stages.pb.factors.{sym}.parameter",
                                                         f["parameter"])


def test_a_property_the_runs_take_is_checked_at_start_up(tmp_path):
    """The printed Poisson ratio, particle density and shear modulus go into every run: a unit
    without a factor to SI, or a value outside the physical range, stops the load naming the
    property, not a DEM job later."""
    p = _cinnamon(tmp_path, lambda d: d["properties"]["poisson_ratio"].update(value=31.1, unit="%"))
    with pytest.raises(InputError, match=r"properties\.poisson_ratio\.unit: expected one of -, Pa"):
        load_soil(p, ROOT / "resources")
    p = _cinnamon(tmp_path, lambda d: d["properties"]["poisson_ratio"].update(value=0.7))
    with pytest.raises(InputError, match=r"properties\.poisson_ratio\.value: expected .*soil_poisson.*got 0\.7"):
        load_soil(p, ROOT / "resources")


def test_own_particle_sizes_in_millimetres_are_refused(tmp_path):
    """paper_psd radii are metres: radii of 1 and 0.5 (mm meant) would fill the 60 mm tube
    with no particle under the paper preset and shrink the quick preset's surface energy by
    their Sauter radius without a word."""
    def psd(rows):
        return lambda d: d["simulation"]["responses"]["stacking_angle"].update(set={"paper_psd": rows})

    p = _cinnamon(tmp_path, psd([[1.0, 40], [0.5, 60]]))
    with pytest.raises(InputError, match=r"simulation\.responses\.stacking_angle\.set\.paper_psd: expected particle "
                                         r"radii in metres"):
        load_soil(p, ROOT / "resources")
    load_soil(_cinnamon(tmp_path, psd([[0.001, 40], [0.0005, 60]])), ROOT / "resources")


@pytest.mark.parametrize("size", [{"radius": 0.004}, {"n_particles": 500}])
def test_millimetre_sizes_are_refused_beside_a_radius_or_a_sphere_count(tmp_path, size):
    """A radius or a sphere count of the soil's own takes the place of paper_psd under the
    paper preset, while the quick runs still scale the surface energy by paper_psd's Sauter
    radius: the radii are checked all the same."""
    def psd(rows):
        return lambda d: d["simulation"]["responses"]["stacking_angle"].update(set={**size, "paper_psd": rows})

    with pytest.raises(InputError, match=r"stacking_angle\.set\.paper_psd: expected particle radii in metres"):
        load_soil(_cinnamon(tmp_path, psd([[1.0, 40], [0.5, 60]])), ROOT / "resources")
    load_soil(_cinnamon(tmp_path, psd([[0.001, 40], [0.0005, 60]])), ROOT / "resources")


def test_own_sizes_are_checked_with_the_soil_s_own_density(tmp_path):
    """The black soil's funnel holds a 3.1 kg load at the soil's 1560 kg/m^3 but not at the
    engine's default density: the named setup's own sizes given as the soil's (0.5 kg of 1
    and 2 mm particles, 001 Sec. 2.2.1) load, as the same file without them does."""
    # the funnel (001 Sec. 2.2.1: 192 and 50 mm across, 274 mm high) holds
    # pi 0.274 / 3 (0.096^2 + 0.096 x 0.025 + 0.025^2) m^3 = 3.512 L; 3.1 kg at a solid fraction
    # of 0.6 fills 3.1 / (0.6 x 1560) m^3 = 3.312 L of it at the soil's density, but
    # 3.1 / (0.6 x 1394) m^3 = 3.706 L at the engine's default density 1394 kg/m^3
    def edit(rho=None):
        def apply(d):
            d["simulation"]["responses"]["accumulation_angle"]["set"] = {
                "load_mass": 3.1, "paper_psd": [[0.001, 50.0], [0.002, 50.0]]}
            if rho is not None:
                d["simulation"]["params"]["soil_density"] = rho
        return apply

    load_soil(_cinnamon(tmp_path, edit(), soil="black-soil"), ROOT / "resources")
    with pytest.raises(InputError) as e:
        load_soil(_cinnamon(tmp_path, edit(1394.0), soil="black-soil"), ROOT / "resources")
    assert e.value.field == "simulation.responses.accumulation_angle.set.load_mass"
    assert "3.51 L at 1394 kg/m^3" in e.value.expected


@pytest.mark.parametrize("edit, field, got, expected", [
    # 2 MPa typed as 2 with unit Pa: below the softest soil's modulus (base.SOIL_RANGES)
    (lambda d: d["properties"]["shear_modulus"].update(value=2, unit="Pa"), "properties.shear_modulus.value", "2",
     r"a soil shear modulus in \[1e4, 5e10\] Pa"),
    # 0.05 GPa typed with unit Pa: E = 2 (1 + nu) G over the plausible G, [2e4, 1.5e11] Pa
    (lambda d: d["properties"]["youngs_modulus"].update(value=0.05, unit="Pa"), "properties.youngs_modulus.value",
     "0.05", r"a soil Young's modulus in \[20000, 1.5e\+11\] Pa"),
    # 1.6 g/cm^3 typed as 16000 kg/m^3 (a slip of ten): above any soil's particle density
    (lambda d: d["simulation"]["params"].update(soil_density=16000), "simulation.params.soil_density", "16000",
     r"a soil particle density in \[100, 4000\] kg/m\^3"),
    (lambda d: d["simulation"]["params"].update(soil_soil_static_friction=3.0),
     "simulation.params.soil_soil_static_friction", "3.0", r"a soil-soil sliding friction coefficient in \[0, 2\]"),
    (lambda d: d["simulation"]["params"].update(soil_soil_restitution=1.2),
     "simulation.params.soil_soil_restitution", "1.2", r"a coefficient of restitution in \(0, 1\]"),
    # 380 mJ/m^2 (0.38 J/m^2) typed as 380 J/m^2
    (lambda d: d["simulation"]["params"].update(soil_soil_surface_energy=380.0),
     "simulation.params.soil_soil_surface_energy", "380.0", r"a soil-soil JKR surface energy in \[0, 100\] J/m\^2"),
])
def test_a_material_property_in_another_unit_is_refused_with_its_plausible_range(tmp_path, edit, field, got, expected):
    """A unit slip in a soil's material properties stops the load before any DEM job, naming
    the file, the field, the value and the plausible range (base.SOIL_RANGES)."""
    p = _cinnamon(tmp_path, edit)
    with pytest.raises(InputError) as e:
        load_soil(p, ROOT / "resources")
    assert (Path(e.value.path), e.value.field, str(e.value.got)) == (p, field, got)
    assert re.search(expected, e.value.expected), e.value.expected
    assert str(e.value).count("\n") == 0


def test_a_setup_is_checked_at_the_density_the_soil_prints_as_a_property(tmp_path):
    """A soil giving its particle density as a printed property (1.56 g/cm^3) rather than in
    simulation.params: its 3.1 kg funnel load fills 3.1 / (0.6 x 1560) m^3 = 3.31 L of the
    3.51 L funnel and loads; at 1.30 g/cm^3 it would fill 3.97 L, and the error names that
    density, not the engine's default 1394 kg/m^3."""
    def own(rho):
        def edit(d):
            d["simulation"]["params"].pop("soil_density")
            d["properties"]["particle_density"] = {"value": rho, "unit": "g/cm^3"}
            d["simulation"]["responses"]["accumulation_angle"]["set"] = {"load_mass": 3.1}
        return edit

    load_soil(_cinnamon(tmp_path, own(1.56), soil="black-soil"), ROOT / "resources")
    with pytest.raises(InputError) as e:
        load_soil(_cinnamon(tmp_path, own(1.30), soil="black-soil"), ROOT / "resources")
    assert e.value.field == "simulation.responses.accumulation_angle.set.load_mass"
    assert "at 1300 kg/m^3" in e.value.expected


def test_a_printed_property_that_simulation_params_replaces_is_asked_only_its_physical_range(tmp_path):
    """The vineyard soil keeps its printed particle density as printed and replaces it in
    simulation.params: a print ten times too high (17575.67 kg/m^3, beyond a soil's plausible
    4000) is no run's value and loads, as a print ten times too low (175.76) does; the same value
    not replaced is refused (base.SOIL_RANGES)."""
    def misprint(d):
        d["properties"]["particle_density"]["value"] = 17575.67

    soil = load_soil(_cinnamon(tmp_path, misprint, soil="xinjiang-vineyard"), ROOT / "resources")
    # and its runs take the replacing value, as the commit of the printed one says
    from soilcal.dem.scenarios.base import stage_params

    params = soil.data["simulation"]["params"]
    for st in soil.data["stages"]:
        assert stage_params(soil, st["id"], {}, params=params).soil_density == pytest.approx(1757.567)

    def unreplaced(d):
        misprint(d)
        d["simulation"]["params"].pop("soil_density")

    with pytest.raises(InputError) as e:
        load_soil(_cinnamon(tmp_path, unreplaced, soil="xinjiang-vineyard"), ROOT / "resources")
    assert e.value.field == "properties.particle_density.value"


def test_a_printed_young_s_modulus_in_a_unit_without_a_factor_loads(tmp_path):
    """No run takes a printed Young's modulus: one in N/mm^2 loads (the errata note its unit)."""
    def edit(d):
        d["properties"]["youngs_modulus"] = {"value": 10, "unit": "N/mm^2", "source": "Sec. 2.3"}

    load_soil(_cinnamon(tmp_path, edit), ROOT / "resources")


@pytest.mark.parametrize("kind, unit, expected", [
    ("static_friction", "-", (0.0, 2.0)),          # base.SOIL_RANGES soil-soil friction [0, 2]
    ("surface_energy", "mJ/m^2", (0.0, 1.0e5)),     # [0, 100] J/m^2 in mJ/m^2
])
def test_a_derived_box_behnken_stays_within_a_soil_s_plausible_range(kind, unit, expected):
    """The levels a Box-Behnken laid around a path step may take (derive._bounds_in_config_units)
    are the ones a DEM point of the soil accepts: a path ending at friction 1.9 no longer mirrors
    a level to 2.175, which every run of the stage would refuse after the path had run."""
    from soilcal.chain.derive import _bounds_in_config_units
    from soilcal.doe.steepest import bbd_levels

    soil = {"name": "own", "parameters": {"x": {"unit": unit, "pair": "soil-soil", "kind": kind}}}
    lo, hi = _bounds_in_config_units(soil, "x")
    assert (lo, hi) == pytest.approx(expected)
    import pandas as pd
    top = 0.95 * expected[1]
    path = pd.DataFrame({"step": [1, 2, 3, 4, 5], "A": list(np.linspace(0.4 * top, top, 5))})
    lv = bbd_levels(path, 5, ["A"], {"A": (lo, hi)})
    assert lv["A"]["high"] <= hi + 1e-12
