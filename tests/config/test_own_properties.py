"""A soil of one's own (no citation) gives its measured properties and materials in their
units: a value outside the physical range once converted (a bulk density 1.52 declared in
kg/m^3, a moisture content 15 declared as a fraction) is refused at load naming the field, the
range and the unit that would take it in; a cited soil's printed values are kept as printed
(the published replay's errata judge them)."""

from __future__ import annotations

import pytest
import yaml

from soilcal.config import load_soil
from soilcal.errors import InputError
from test_minimal_soil import _write


def _load(tmp_path, **extra):
    path = _write(tmp_path)
    d = yaml.safe_load(path.read_text())
    d.update(extra)
    path.write_text(yaml.safe_dump(d))
    return load_soil(path, tmp_path / "resources")


def _refused(tmp_path, field, **extra):
    with pytest.raises(InputError) as e:
        _load(tmp_path, **extra)
    assert f": {field}: expected " in str(e.value)
    return str(e.value)


@pytest.mark.parametrize("prop, key, expected", [
    ({"bulk_density": {"value": 1.52, "unit": "kg/m^3"}}, "value",
     "a bulk density of 50 to 3000 kg/m^3 (in g/cm^3? declare unit: g/cm^3), got 1.52"),
    ({"bulk_density": {"values": [1.35, 1520], "unit": "g/cm^3"}}, "values[1]",
     "(1520 g/cm^3 is 1.52e+06 kg/m^3: in kg/m^3? declare unit: kg/m^3)"),
    ({"dry_density": {"low": 1.2, "high": 1.6, "unit": "kg/m^3"}}, "low", "a dry density of 50 to 3000 kg/m^3"),
    ({"moisture_content": {"value": 15, "unit": "fraction"}}, "value",
     "a moisture content of 0 to 500 % (15 fraction is 1500 %: in %? declare unit: %)"),
    ({"poisson_ratio": {"value": 30, "unit": "-"}}, "value", "a Poisson ratio of 0 to 0.5, got 30"),
])
def test_an_own_soil_s_property_outside_its_range_is_refused(tmp_path, prop, key, expected):
    """Before, each of these loaded without a word (the soil runs no published replay whose
    errata would judge them, and the DEM takes none of them)."""
    name = next(iter(prop))
    msg = _refused(tmp_path, f"properties.{name}.{key}", properties=prop)
    assert expected in msg


def test_an_own_soil_s_material_density_and_unknown_units_are_refused(tmp_path):
    msg = _refused(tmp_path, "materials.steel.density.value",
                   materials={"steel": {"density": {"value": 7.85, "unit": "kg/m^3"}}})
    assert "a density of 50 to 20000 kg/m^3 (in g/cm^3? declare unit: g/cm^3)" in msg
    # a unit weight is no density
    msg = _refused(tmp_path, "properties.bulk_density.unit", properties={"bulk_density": {"value": 15, "unit": "kN/m^3"}})
    assert "kg/m^3, g/cm^3, t/m^3" in msg and "got 'kN/m^3'" in msg


@pytest.mark.parametrize("q", [{"value": 1.52, "unit": "g/cm^3"}, {"value": 1.52, "unit": "Mg m-3"},
                               {"value": 1520, "unit": "kg/m3"}, {"value": 1.52, "unit": "t/m^3"},
                               {"value": 95, "unit": "lb/ft^3"}])  # 1521.7 kg/m^3
def test_an_own_soil_s_density_in_any_density_unit_loads(tmp_path, q):
    soil = _load(tmp_path, properties={"bulk_density": q, "moisture_content": {"value": 0.15, "unit": "-"}},
                 materials={"steel": {"density": {"value": 7850, "unit": "kg/m^3"}}})
    assert soil.data["properties"]["bulk_density"] == q


def test_a_cited_soil_s_printed_property_is_kept_as_printed(tmp_path):
    """A paper's misprint (a bulk density 1.52 printed in kg/m^3) is the paper's: kept, the
    published replay's errata report it."""
    soil = _load(tmp_path, citation={"title": "A paper"}, properties={"bulk_density": {"value": 1.52, "unit": "kg/m^3"}})
    assert soil.data["properties"]["bulk_density"]["value"] == 1.52


@pytest.mark.parametrize("prop", [
    {"bulk_density": {"value": 0.08, "unit": "g/cm^3"}},  # sphagnum peat at the surface
    {"moisture_content": {"value": 350, "unit": "%"}},  # a peat, gravimetric
    {"moisture_content": {"value": 1.2, "unit": "g/g"}},  # an andisol
    {"relative_density": {"value": 65, "unit": "%"}},  # of a sand, no mass density
    {"dry_density_ratio": {"value": 0.95, "unit": "-"}},
    {"root_length_density": {"value": 1.2, "unit": "cm/cm^3"}},
    {"bulk_density": {"value": 1.45, "unit": "kg/dm^3"}},
    {"bulk_density": {"value": 1.45, "unit": "g/ml"}},
    {"particle_density": {"value": 2.65, "unit": "Mg m^-3"}},
    {"shear_modulus": {"value": 1, "unit": "MN/m2"}},
    {"shear_modulus": {"value": 1e6, "unit": "N/m^2"}},
    {"youngs_modulus": {"value": 1e6, "unit": "N m-2"}},
    {"poisson_ratio": {"value": 0.3, "unit": "1"}},
    {"poisson_ratio": {"value": 0.3, "unit": "dimensionless"}}])
def test_a_real_own_soil_property_in_an_si_unit_loads(tmp_path, prop):
    """Each was refused: a peat's 80 kg/m^3 and 350 % (real: peat holds several times its dry
    mass of water) lay outside ranges of 100 kg/m^3 and 100 %; any key with density in it was
    taken as a mass density (relative_density 65 % refused as no density unit); N/m^2, MN/m2,
    kg/dm^3, g/ml, a Poisson ratio in 1 were no units of the range."""
    soil = _load(tmp_path, properties=prop)
    assert soil.data["properties"] == prop


@pytest.mark.parametrize("prop, field, expected", [
    ({"bulk_density": {"value": 18, "unit": "kN/m^3"}}, "properties.bulk_density.unit", "kg/m^3, g/cm^3"),
    ({"bulk_density": {"value": 1.5, "unit": "x1000 kg/m3"}}, "properties.bulk_density.unit", "kg/m^3, g/cm^3"),
    ({"shear_modulus": {"value": 1, "unit": "MN/m^3"}}, "properties.shear_modulus.unit", "Pa, kPa, MPa"),
    ({"moisture_content": {"value": 25, "unit": "vol %"}}, "properties.moisture_content.unit", "gravimetric"),
    ({"moisture_content": {"value": 600, "unit": "%"}}, "properties.moisture_content.value", "0 to 500 %"),
    ({"bulk_density": {"value": 40, "unit": "kg/m^3"}}, "properties.bulk_density.value", "50 to 3000 kg/m^3")])
def test_a_wrong_quantity_s_unit_or_an_unreal_value_is_still_refused(tmp_path, prop, field, expected):
    """A unit weight (kN/m^3) is no density, a modulus per length no pressure."""
    assert expected in _refused(tmp_path, field, properties=prop)


def test_the_load_check_and_the_errata_judge_by_one_table():
    """The published soils' errata and the load check of an own soil read one table of ranges and
    one conversion: a bulk density of 0.04 g/cm^3 (40 kg/m^3) is out of both, 0.08 in both, and
    an errata-judged density in g cm-3 or Mg m-3 is converted as at load (2.65 Mg/m^3 = 2650)."""
    from soilcal.chain.errata import Errata, plausibility

    def errata(prop):
        e = Errata()
        plausibility(e, {"properties": prop, "materials": {}, "stages": [], "parameters": {}})
        return e.rows

    assert errata({"bulk_density": {"value": 0.04, "unit": "g/cm^3"}})
    assert not errata({"bulk_density": {"value": 0.08, "unit": "g/cm^3"}})
    assert not errata({"particle_density": {"value": 2.65, "unit": "Mg m-3"}})
    assert errata({"particle_density": {"value": 0.265, "unit": "t/m^3"}})


@pytest.mark.parametrize("prop", [
    {"surface_energy": {"value": 72, "unit": "mN/m"}},  # water's surface tension, 0.072 J/m^2
    {"surface_energy": {"value": 0.072, "unit": "N/m"}},
    {"bulk_density": {"value": 1450, "unit": "Kg/m3"}},
    {"bulk_density": {"value": 1450, "unit": "KG/M3"}},
    {"bulk_density": {"value": 1.45, "unit": "G/CM3"}},
    {"moisture_content": {"value": 0.15, "unit": "g g-1"}},
    {"moisture_content": {"value": 0.15, "unit": "kg kg-1"}},
    {"moisture_content": {"value": 15, "unit": "pct"}}])
def test_an_own_soil_property_in_a_unit_the_tables_take_loads(tmp_path, prop):
    """Each was refused as no unit of its quantity: mN/m was missing from the symbols, a density
    in capitals was matched with its case only, and the own-property check read moisture by
    another conversion than soil_moisture and the tables (g g-1, kg kg-1, pct refused)."""
    soil = _load(tmp_path, properties=prop)
    assert soil.data["properties"] == prop


def test_an_out_of_range_moisture_in_g_per_g_is_refused_and_judged():
    """6 g g-1 is 600 %, over a gravimetric moisture's 500 %: the load check refused the unit,
    the errata skipped the value (no factor)."""
    from soilcal.chain.errata import Errata, plausibility
    from soilcal.config.quantities import si_factor

    def errata(prop):
        e = Errata()
        plausibility(e, {"properties": prop, "materials": {}, "stages": [], "parameters": {}})
        return e.rows

    assert errata({"moisture_content": {"value": 6, "unit": "g g-1"}})
    assert not errata({"moisture_content": {"value": 0.15, "unit": "kg kg-1"}})
    assert si_factor("mN/m", "J/m^2") == pytest.approx(1e-3) and si_factor("MG/M3", "kg/m^3") is None
