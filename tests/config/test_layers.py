"""A soil's layers are declared once (``layers``) and a target's ``layer`` must be one of them.

Before, ``layer`` was a free label: the vineyard soil's upper-layer target written ``uper``
loaded without a word and targets.csv held a fourth layer, calibrated on its own."""

from __future__ import annotations

import copy

import pytest

from soil_copies import load_copy, read_shipped
from soilcal.errors import InputError

SOIL = "xinjiang-vineyard"


@pytest.fixture(scope="module")
def parsed():
    return read_shipped(SOIL)


def _refused(tmp_path, d) -> InputError:
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    assert "\n" not in str(ei.value)
    return ei.value


def test_the_shipped_layers_are_the_targets_layers(tmp_path, parsed):
    soil = load_copy(tmp_path, SOIL, copy.deepcopy(parsed))
    assert list(soil.data["layers"]) == ["upper", "middle", "lower"]
    assert {t["layer"] for t in soil.data["targets"].values()} == {"upper", "middle", "lower"}


def test_a_misspelt_layer_is_refused_naming_the_declared_ones(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    d["targets"]["static_angle_upper"]["layer"] = "uper"
    e = _refused(tmp_path, d)
    assert e.field == "targets.static_angle_upper.layer" and e.got == "uper"
    assert "upper, middle, lower" in e.expected
    assert str(e).startswith(f"{tmp_path / (SOIL + '.yaml')}: targets.static_angle_upper.layer: expected")


def test_a_layer_without_declared_layers_is_refused(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    del d["layers"]
    e = _refused(tmp_path, d)
    assert e.field.endswith(".layer") and "declares none" in e.expected and "layers:" in e.expected


def test_layers_named_without_a_description_and_targets_without_a_layer_load(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    d["layers"] = {"upper": None, "middle": None, "lower": None}
    load_copy(tmp_path, SOIL, d)
    d = copy.deepcopy(parsed)
    del d["layers"]
    for t in d["targets"].values():
        t.pop("layer")
    load_copy(tmp_path, SOIL, d)


def test_layers_as_a_list_of_names(tmp_path, parsed):
    """layers: [upper, middle, lower] was refused as 'expected a value of type object'; the
    names are all a target's layer needs."""
    d = copy.deepcopy(parsed)
    d["layers"] = ["upper", "middle", "lower"]
    load_copy(tmp_path, SOIL, d)
    d["targets"]["static_angle_upper"]["layer"] = "uper"
    e = _refused(tmp_path, d)
    assert e.field == "targets.static_angle_upper.layer" and "(upper, middle, lower)" in e.expected


@pytest.mark.parametrize("layers, field, said", [
    ({"upper": 20, "middle": 40, "lower": 60}, "layers.upper", "a bare number has no unit"),
    ({}, "layers", 'layers: {upper: "0-20 cm", middle: "20-40 cm"}'),
    ("upper", "layers", "layers: [upper, middle]"),
    (["upper", "upper"], "layers[1]", "a layer named once"),
])
def test_a_layers_form_not_taken_is_refused_showing_the_forms(tmp_path, parsed, layers, field, said):
    d = copy.deepcopy(parsed)
    d["layers"] = layers
    e = _refused(tmp_path, d)
    assert e.field == field and said in e.expected


@pytest.mark.parametrize("layers, field", [
    (["upper", "middle", "lower", 20], "layers[3]"),
    ({"upper": "0-20 cm", "middle": "20-40 cm", "lower": "40-60 cm", 20: "x"}, "layers.20"),
])
def test_a_number_as_a_layer_s_name_is_refused_in_either_form(tmp_path, parsed, layers, field):
    """A layer named by a bare number was refused in a list but loaded as a mapping's key (20: x),
    a name no target's layer (text) could give.  Both forms ask for the name quoted."""
    d = copy.deepcopy(parsed)
    d["layers"] = layers
    e = _refused(tmp_path, d)
    assert e.field == field and e.got == 20 and '(quote it, "20"' in e.expected
    d["layers"] = [str(x) for x in layers] if isinstance(layers, list) else {str(k): v for k, v in layers.items()}
    load_copy(tmp_path, SOIL, d)


@pytest.mark.parametrize("what", ["20", "0-20", " 20.5 "])
def test_a_layer_described_by_a_number_in_quotes_is_refused(tmp_path, parsed, what):
    """upper: "20" loaded though upper: 20 was refused as a bare number without a unit: the
    quotes add no unit."""
    d = copy.deepcopy(parsed)
    d["layers"] = {"upper": what, "middle": "20-40 cm", "lower": "40-60 cm"}
    e = _refused(tmp_path, d)
    assert e.field == "layers.upper" and "a bare number has no unit" in e.expected and e.got == what


@pytest.mark.parametrize("what", ["", "  "])
def test_a_layer_described_by_blank_text_is_a_layer_described_by_nothing(tmp_path, parsed, what):
    """upper: "" was refused as 'a bare number has no unit' (the pattern of a number matched
    the empty text), though it says as little as upper: (null), which loads; now both load."""
    d = copy.deepcopy(parsed)
    d["layers"] = {"upper": what, "middle": None, "lower": "40-60 cm"}
    soil = load_copy(tmp_path, SOIL, d)
    assert list(soil.data["layers"]) == ["upper", "middle", "lower"]
