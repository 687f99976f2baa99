"""One photo group is the measurement of one soil state.

The vineyard soil's six targets are measured on six photo groups, one per layer and test.
A target line copied for the next layer whose ``image`` is left as it was (the middle layer's
static angle on the upper layer's heaps) loaded without a word before: both layers were
calibrated to the same photos and targets.csv gave both the upper layer's angle."""

from __future__ import annotations

import copy

import pytest

from soil_copies import load_copy, read_shipped
from soilcal.errors import InputError

SOIL = "xinjiang-vineyard"


@pytest.fixture(scope="module")
def parsed():
    return read_shipped(SOIL)


def test_a_target_of_another_layer_on_the_same_photos_is_refused(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    d["targets"]["static_angle_middle"]["image"] = "static_upper"
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    e = ei.value
    assert e.field == "targets.static_angle_middle.image" and e.got == "static_upper"
    assert "targets.static_angle_upper" in e.expected and "layer upper there, middle here" in e.expected


def test_a_target_at_another_moisture_on_the_same_photos_is_refused(tmp_path, parsed):
    d = copy.deepcopy(parsed)  # moistures 8.39, 10.74, 12.40 % declared
    d["targets"]["static_angle_upper"]["moisture_content"] = 8.39
    d["targets"]["static_angle_lower"].update(image="static_upper", layer="upper", moisture_content=12.40)
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    assert ei.value.field == "targets.static_angle_lower.image"
    assert "moisture_content 8.39 there, 12.4 here" in ei.value.expected


def test_the_same_photos_for_one_state_load(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    # a second target of the upper layer, and one that gives no layer, on the upper layer's heaps
    d["targets"]["static_angle_upper_again"] = dict(d["targets"]["static_angle_upper"])
    d["targets"]["static_angle_any"] = {k: v for k, v in d["targets"]["static_angle_upper"].items() if k != "layer"}
    load_copy(tmp_path, SOIL, d)


@pytest.mark.parametrize("measure", ["left_deg", "spread_deg"])
def test_another_measure_of_the_same_photos_is_of_the_same_state(tmp_path, parsed, measure):
    # every measure of a group comes from the same photos: the middle layer's target on the
    # upper layer's heaps is refused whichever measure it takes
    d = copy.deepcopy(parsed)
    d["targets"]["static_angle_middle"].update(image="static_upper", image_measure=measure)
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    assert ei.value.field == "targets.static_angle_middle.image"
    assert "targets.static_angle_upper" in ei.value.expected and "layer upper there, middle here" in ei.value.expected


def test_a_state_given_by_a_later_target_counts(tmp_path, parsed):
    # the first target on the group gives no layer, the second the upper one: a third of the
    # middle layer is of another state than the second
    d = copy.deepcopy(parsed)
    up = d["targets"].pop("static_angle_upper")
    d["targets"] = {"static_angle_any": {k: v for k, v in up.items() if k != "layer"},
                    "static_angle_upper": up, **d["targets"]}
    d["targets"]["static_angle_middle"]["image"] = "static_upper"
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    assert ei.value.field == "targets.static_angle_middle.image"
    # named by the target that gave the layer, not the group's first target (which gives none)
    assert "targets.static_angle_upper (layer upper there, middle here)" in ei.value.expected
    assert "static_angle_any" not in ei.value.expected
