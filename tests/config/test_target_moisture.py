"""A target recorded at a moisture content the soil does not declare is refused.

The soil's ``properties.moisture_content`` says at which moistures the soil was prepared and
measured; a target (``targets.<id>.moisture_content``) or a measured table's moisture column
that chooses the calibrated case (``covariates.<col>.case``) at another moisture is a
measurement of another soil state.  Before, both were accepted without a word: the target's
moisture was only copied into targets.csv, and rows at one moisture were simulated with the
parameters calibrated at another.  Each test edits the parsed guangxi cohesive soil (moistures
0, 5, 10, 15, 20 %) and loads it through the loader, as ``soilcal config check`` does."""

from __future__ import annotations

import copy

import pytest
import yaml

from soil_copies import ROOT, load_copy, read_shipped
from soilcal.config.load import load_soil, read_yaml
from soilcal.errors import InputError

SOIL = "guangxi-cohesive"


@pytest.fixture(scope="module")
def parsed():
    return read_shipped(SOIL)


def test_the_shipped_moistures_load(tmp_path, parsed):
    load_copy(tmp_path, SOIL, copy.deepcopy(parsed))


def test_a_target_at_a_moisture_the_soil_does_not_declare_is_refused(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    d["targets"]["angle_mc10"]["moisture_content"] = 12.5  # declared: 0, 5, 10, 15, 20 %
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    e = ei.value
    assert e.field == "targets.angle_mc10.moisture_content" and e.got == 12.5
    assert "0, 5, 10, 15, 20 %" in e.expected and str(e.path).endswith(f"{SOIL}.yaml")


def test_a_target_moisture_is_accepted_once_the_soil_declares_it(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    # angle_mc00 (no measured table maps to its case): only the soil's moistures decide
    d["targets"]["angle_mc00"]["moisture_content"] = 12.5
    d["properties"]["moisture_content"]["values"].append(12.5)
    load_copy(tmp_path, SOIL, d)
    # a declared range holds every moisture inside it
    d["properties"]["moisture_content"] = {"low": 0, "high": 20, "unit": "%"}
    load_copy(tmp_path, SOIL, d)


def test_a_target_moisture_without_any_declared_moisture_is_refused(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    del d["properties"]["moisture_content"]
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    assert ei.value.field.endswith(".moisture_content") and ei.value.field.startswith("targets.")


def test_a_moisture_column_mapped_to_a_case_at_another_moisture_is_refused(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    # rows at 5 % would take the parameters calibrated to the 10 % target (angle_mc10)
    d["measurements"]["compression"]["covariates"]["moisture_content"]["case"] = {"5": "mc10", "10": "mc10",
                                                                                   "15": "mc15"}
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    e = ei.value
    assert e.field == "measurements.compression.covariates.moisture_content.case.5"
    assert "targets.angle_mc10.moisture_content = 10 %" in e.expected


def test_a_moisture_column_in_another_unit_maps_to_the_same_moisture(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    cv = d["measurements"]["compression"]["covariates"]["moisture_content"]
    cv["case"] = {"0.05": "mc05", "0.1": "mc10", "0.15": "mc15"}
    cv["unit"] = "fraction"
    # the table's column is in % (5, 10, 15): the rows no longer find their key, which the
    # table check names; the map itself is consistent with the targets
    from soilcal.config.measurements import _check_case_moisture

    st = next(s for s in d["stages"] if s["id"] == "bbd")
    _check_case_moisture("x.yaml", d, st, "measurements.compression.covariates.moisture_content", cv)


def test_a_soil_moisture_unit_soilcal_does_not_know_is_refused_naming_the_unit(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    # a volumetric water content is another quantity: it cannot be compared with the targets' %
    d["properties"]["moisture_content"]["unit"] = "vol%"  # values 0, 5, 10, 15, 20 given
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    e = ei.value
    assert e.field == "properties.moisture_content.unit" and e.got == "vol%"
    assert "'vol%' is not one of them" in e.expected
    for unit in ("%", "percent", "wt%", "g/100g", "fraction", "g/g", "kg/kg"):
        assert unit in e.expected


def test_grams_per_hundred_grams_is_a_percentage(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    d["properties"]["moisture_content"]["unit"] = "g/100g"  # 10 g of water per 100 g: 10 %
    load_copy(tmp_path, SOIL, d)


@pytest.mark.parametrize("soil", ["black-soil", "cinnamon-soil", "yangtze-clay-loam"])
def test_an_unknown_moisture_unit_loads_where_nothing_compares_with_it(tmp_path, soil):
    # these soils have measured tables but no moisture target, case or column: the soil's
    # moisture is only described, so its unit is not judged
    d = read_yaml(ROOT / f"config/soils/{soil}.yaml")
    d.setdefault("properties", {})["moisture_content"] = {"value": 17.2, "unit": "vol%"}
    p = tmp_path / f"{soil}.yaml"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    load_soil(p, ROOT / "resources")


def test_a_case_moisture_the_soil_does_not_declare_names_the_fix(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    for tid in ("angle_mc00", "angle_mc05", "angle_mc10", "angle_mc15", "angle_mc20"):
        d["targets"][tid].pop("moisture_content")
    d["measurements"]["compression"]["covariates"]["moisture_content"]["case"] = {"5": "mc05", "12": "mc10",
                                                                                "15": "mc15"}
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    e = ei.value
    assert e.field == "measurements.compression.covariates.moisture_content.case.12"
    assert "add it to properties.moisture_content.values" in e.expected


def test_a_target_moisture_the_soil_does_not_declare_names_the_fix(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    d["targets"]["angle_mc10"]["moisture_content"] = 10.2
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    assert "add it to properties.moisture_content.values" in ei.value.expected


def _declared_range_case(parsed, keys):
    """The compression table's moisture map (keys in %) against a soil declaring only the
    range 0.07-0.29 as a fraction, its targets giving no moisture of their own."""
    from soilcal.config.measurements import _check_case_moisture

    d = copy.deepcopy(parsed)
    for t in d["targets"].values():
        t.pop("moisture_content", None)
    d["properties"]["moisture_content"] = {"low": 0.07, "high": 0.29, "unit": "fraction"}
    cv = {"case": dict(zip(keys, ("mc05", "mc10", "mc15"))), "quantity": "moisture_content", "unit": "%"}
    st = next(s for s in d["stages"] if s["id"] == "bbd")
    _check_case_moisture("x.yaml", d, st, "measurements.compression.covariates.moisture_content", cv)


def test_the_ends_of_a_fraction_range_hold_the_same_moisture_in_percent(parsed):
    # 7 % and 29 % are the ends of 0.07-0.29 written in %; in floating point 0.07 * 100 is
    # 7.000000000000001 and 0.29 * 100 is 28.999999999999996, which refused both ends
    _declared_range_case(parsed, ("7", "10", "29"))


def test_a_moisture_just_outside_a_fraction_range_is_refused(parsed):
    with pytest.raises(InputError) as ei:
        _declared_range_case(parsed, ("6.9", "10", "29"))
    assert ei.value.field == "measurements.compression.covariates.moisture_content.case.6.9"
    assert "0.07-0.29 fraction" in ei.value.expected


@pytest.mark.parametrize("unit", ["percent", "wt%", "% w/w", "g/100g", "Percent"])
def test_a_moisture_column_takes_the_percent_units_the_soil_moisture_takes(tmp_path, parsed, unit):
    # the compression table holds 5, 10, 15 (%): every spelling of a percentage reads them as
    # 5, 10, 15 %, as properties.moisture_content takes them; before, only "%" was accepted
    from soilcal.config.measurements import conditions

    d = copy.deepcopy(parsed)
    d["measurements"]["compression"]["covariates"]["moisture_content"]["unit"] = unit
    got = sorted((c.quantities["moisture_content"], c.case) for c in conditions(load_copy(tmp_path, SOIL, d)))
    assert got == [(5.0, "mc05"), (10.0, "mc10"), (15.0, "mc15")]


def test_a_moisture_column_in_a_volumetric_unit_is_refused_naming_the_units(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    d["measurements"]["compression"]["covariates"]["moisture_content"]["unit"] = "vol%"
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    e = ei.value
    assert e.field == "measurements.compression.covariates.moisture_content.unit" and e.got == "vol%"
    assert "wt%" in e.expected and "g/g" in e.expected


@pytest.mark.parametrize("given, missing", [("low", "high"), ("high", "low")])
def test_a_range_end_without_the_other_is_refused(tmp_path, parsed, given, missing):
    # a lone high beside the declared values declared no range and passed unread before
    d = copy.deepcopy(parsed)
    d["properties"]["moisture_content"][given] = 12
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    e = ei.value
    assert e.field == f"properties.moisture_content.{missing}"
    assert f"{missing} with {given}" in e.expected and "12" in str(e.got)


def test_a_one_sided_bound_is_refused_saying_where_it_goes(tmp_path, parsed):
    # a soil sieved below 2 mm has an upper bound and no range: the refusal names the form
    # that holds it (the entry's note, with its value if one was measured)
    d = copy.deepcopy(parsed)
    d["properties"]["particle_size"] = {"high": 2, "unit": "mm"}
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    e = ei.value
    assert e.field == "properties.particle_size.low" and e.got == "high 2 alone"
    assert "one-sided bound" in e.expected and "note" in e.expected and "value" in e.expected
    d["properties"]["particle_size"] = {"value": None, "unit": "mm", "note": "sieved below 2 mm"}
    load_copy(tmp_path, SOIL, d)
