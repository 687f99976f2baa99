"""A climbing path aimed at several targets (soilcal.doe.steepest: path_target, derive_path
rule "target", bbd_levels with half widths).

Every expected value is worked out by hand next to the assertion from the linear models the
test sets up: the point x* where the first-order models meet every target is the solution of a
small linear system (Montgomery, Design and Analysis of Experiments, sec. 11.2, with the
response replaced by the distance to the targets).
"""

from __future__ import annotations

import numpy as np
import pytest

from soilcal.doe.steepest import bbd_levels, derive_path, path_direction, path_target
from soilcal.errors import InputError


def test_one_response_lands_on_the_steepest_ascent_line_where_it_reaches_the_target():
    # y = 10 + 3 x1 + 4 x2, target 15: along b = (3, 4), |b|^2 = 25, x* = b * 5 / 25 = (0.6, 0.8)
    x = path_target({"y": {"x1": 3.0, "x2": 4.0}}, {"y": 10.0}, {"y": 15.0})
    assert x == pytest.approx({"x1": 0.6, "x2": 0.8}, abs=1e-12)
    # the same line as the gradient direction of path_direction (a positive multiple of it)
    d = path_direction({"y": {"x1": 3.0, "x2": 4.0}}, {"y": 10.0}, {"y": 15.0})
    assert x["x1"] / d["x1"] == pytest.approx(x["x2"] / d["x2"], rel=1e-12) and x["x1"] / d["x1"] > 0
    # above the target: the other way, x* = b * (-5) / 25
    assert path_target({"y": {"x1": 3.0, "x2": 4.0}}, {"y": 20.0}, {"y": 15.0}) == \
        pytest.approx({"x1": -0.6, "x2": -0.8}, abs=1e-12)


def test_two_responses_pulling_apart_get_a_move_the_summed_gradient_cannot_give():
    # static = 30 + 2 a + 2 b, target 32 (needs +2); dynamic = 50 + 3 a + 3 c, target 47
    # (needs -3): a raises both, b only the static angle, c only the dynamic one.
    coef = {"static": {"a": 2.0, "b": 2.0, "c": 0.0}, "dynamic": {"a": 3.0, "b": 0.0, "c": 3.0}}
    b0 = {"static": 30.0, "dynamic": 50.0}
    t = {"static": 32.0, "dynamic": 47.0}
    x = path_target(coef, b0, t)
    # exact: 2a + 2b = 2, 3a + 3c = -3; minimum norm: x in the row space, x = u (1,1,0) + v (1,0,1)
    # -> a = u + v, b = u, c = v with 2(2u + v) = 2 and 3(u + 2v) = -3: u = 1, v = -1
    # -> x* = (0, 1, -1)
    assert x == pytest.approx({"a": 0.0, "b": 1.0, "c": -1.0}, abs=1e-12)
    static = b0["static"] + sum(coef["static"][f] * x[f] for f in x)
    dynamic = b0["dynamic"] + sum(coef["dynamic"][f] * x[f] for f in x)
    assert static == pytest.approx(32.0, abs=1e-12) and dynamic == pytest.approx(47.0, abs=1e-12)
    # the summed gradient (path_direction) moves a, which raises both, and the range rule
    # walks it over its whole range: a direction aimed at both would not
    d = path_direction(coef, b0, t)
    assert d["a"] != 0.0


def test_more_responses_than_factors_is_the_relative_least_squares_point():
    # one factor, two responses y1 = 10 + x (target 11), y2 = 20 + 2 x (target 24):
    # relative rows x / 11 = 1 / 11 and 2 x / 24 = 4 / 24: least squares
    # x = (1/11 * 1/11 + 2/24 * 4/24) / ((1/11)^2 + (2/24)^2)
    x = path_target({"y1": {"a": 1.0}, "y2": {"a": 2.0}}, {"y1": 10.0, "y2": 20.0}, {"y1": 11.0, "y2": 24.0})
    expected = (1 / 121 + 8 / 576) / (1 / 121 + 4 / 576)
    assert x["a"] == pytest.approx(expected, rel=1e-12)


def test_path_target_refuses_targets_already_met():
    with pytest.raises(InputError, match="non-zero path direction"):
        path_target({"y": {"a": 1.0}}, {"y": 5.0}, {"y": 5.0})


LOW = {"a": 0.0, "b": 10.0, "c": 1.0}
HIGH = {"a": 1.0, "b": 20.0, "c": 3.0}  # half ranges 0.5, 5, 1; centres 0.5, 15, 2


def test_target_path_steps_along_the_line_through_the_point_inside_the_screening_box():
    x = {"a": 0.5, "b": -0.25, "c": 0.0}
    p = derive_path(x, LOW, HIGH, 5, rule="target")
    # base a (largest |x*|) walks its whole range in 4 steps of 0.5 coded: -1, -0.5, 0, 0.5, 1
    assert p.attrs["base"] == "a"
    assert p["a"].tolist() == pytest.approx([0.0, 0.25, 0.5, 0.75, 1.0], abs=1e-12)
    # b moves x*_b / |x*_a| = -0.5 of a's coded step: 0.5, 0.25, 0, -0.25, -0.5 -> 15 + 5 x
    assert p["b"].tolist() == pytest.approx([17.5, 16.25, 15.0, 13.75, 12.5], abs=1e-12)
    # c has no move: it stays at the centre
    assert p["c"].tolist() == pytest.approx([2.0] * 5, abs=1e-12)
    # step 4 is x* itself (a coded 0.5, b coded -0.25)
    assert (p["a"][3], p["b"][3]) == pytest.approx((0.75, 13.75), abs=1e-12)
    # every factor's box half width is the range rule's neighbour spacing: range / (n - 1)
    assert p.attrs["box_half_width"] == pytest.approx({"a": 0.25, "b": 2.5, "c": 0.5}, abs=1e-12)
    assert p.attrs["step"] == pytest.approx({"a": 0.25, "b": -1.25, "c": 0.0}, abs=1e-12)
    assert p.attrs["direction"] == {"a": 1, "b": -1, "c": 0}
    assert p.attrs["target_coded"] == x
    # a point far outside the box gives the same line, so the same path
    far = derive_path({"a": 3.0, "b": -1.5, "c": 0.0}, LOW, HIGH, 5, rule="target")
    assert far[["a", "b", "c"]].to_numpy() == pytest.approx(p[["a", "b", "c"]].to_numpy(), abs=1e-12)


def test_target_path_refuses_a_chosen_base():
    with pytest.raises(InputError, match="base/base_step"):
        derive_path({"a": 0.5, "b": -0.25, "c": 0.0}, LOW, HIGH, 5, rule="target", base="a")


def test_bbd_levels_take_the_box_half_width_around_the_chosen_step():
    p = derive_path({"a": 0.5, "b": -0.25, "c": 0.0}, LOW, HIGH, 5, rule="target")
    lv = bbd_levels(p, 3, ["a", "b", "c"], half_width=p.attrs["box_half_width"])
    # centre = step 3 = the screening centre (0.5, 15, 2); -/+ (0.25, 2.5, 0.5)
    assert (lv["a"]["low"], lv["a"]["centre"], lv["a"]["high"]) == pytest.approx((0.25, 0.5, 0.75), abs=1e-12)
    assert (lv["b"]["low"], lv["b"]["centre"], lv["b"]["high"]) == pytest.approx((12.5, 15.0, 17.5), abs=1e-12)
    # c is constant along this path, yet gets a box: the neighbours alone could not give one
    assert (lv["c"]["low"], lv["c"]["centre"], lv["c"]["high"]) == pytest.approx((1.5, 2.0, 2.5), abs=1e-12)
    with pytest.raises(InputError, match="three distinct levels"):
        bbd_levels(p, 3, ["c"])
    # the physical bounds still shift the box as a whole: at step 5 (a = 1) with a <= 1.1 the
    # box 0.75 .. 1.25 is shifted by -0.15
    lv = bbd_levels(p, 5, ["a"], bounds={"a": (0.0, 1.1)}, half_width={"a": 0.25})
    assert (lv["a"]["low"], lv["a"]["centre"], lv["a"]["high"]) == pytest.approx((0.6, 0.85, 1.1), abs=1e-12)
    with pytest.raises(InputError, match=r"half_width\[a\]"):
        bbd_levels(p, 3, ["a"], half_width={"a": 0.0})
    assert np.isfinite(lv["a"]["centre"])
