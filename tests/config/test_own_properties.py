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
     "a bulk density of 100 to 3000 kg/m^3 (in g/cm^3? declare unit: g/cm^3), got 1.52"),
    ({"bulk_density": {"values": [1.35, 1520], "unit": "g/cm^3"}}, "values[1]",
     "(1520 g/cm^3 is 1.52e+06 kg/m^3: in kg/m^3? declare unit: kg/m^3)"),
    ({"dry_density": {"low": 1.2, "high": 1.6, "unit": "kg/m^3"}}, "low", "a dry density of 100 to 3000 kg/m^3"),
    ({"moisture_content": {"value": 15, "unit": "fraction"}}, "value",
     "a moisture content of 0 to 100 % (15 fraction is 1500 %: in %? declare unit: %)"),
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
    assert "a material's density of 100 to 20000 kg/m^3 (in g/cm^3? declare unit: g/cm^3)" in msg
    msg = _refused(tmp_path, "properties.bulk_density.unit", properties={"bulk_density": {"value": 1.5, "unit": "g/cc"}})
    assert "kg/m^3, g/cm^3 or t/m^3" in msg and "got 'g/cc'" in msg


@pytest.mark.parametrize("q", [{"value": 1.52, "unit": "g/cm^3"}, {"value": 1.52, "unit": "Mg m-3"},
                               {"value": 1520, "unit": "kg/m3"}, {"value": 1.52, "unit": "t/m^3"}])
def test_an_own_soil_s_density_in_any_density_unit_loads(tmp_path, q):
    soil = _load(tmp_path, properties={"bulk_density": q, "moisture_content": {"value": 0.15, "unit": "-"}},
                 materials={"steel": {"density": {"value": 7850, "unit": "kg/m^3"}}})
    assert soil.data["properties"]["bulk_density"] == q


def test_a_cited_soil_s_printed_property_is_kept_as_printed(tmp_path):
    """A paper's misprint (a bulk density 1.52 printed in kg/m^3) is the paper's: kept, the
    published replay's errata report it."""
    soil = _load(tmp_path, citation={"title": "A paper"}, properties={"bulk_density": {"value": 1.52, "unit": "kg/m^3"}})
    assert soil.data["properties"]["bulk_density"]["value"] == 1.52
