"""Deriving the climbing path and the Box-Behnken levels from our own screening results.

Every expected number below follows from the construction written next to it (designs,
formulas, the papers' printed tables), never from running the code under test.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from soilcal.doe.designs import plackett_burman
from soilcal.doe.steepest import (
    bbd_levels,
    chosen_step,
    derive_path,
    path_direction,
    path_trend,
    trend_caution,
    select_factors,
    steepest_ascent_path,
)
from soilcal.errors import InputError
from soilcal.rsm import screening_effects

TOL = 1e-12

# Qiu et al. (cinnamon soil), Table 5: climbing path, 6 steps, every factor over its range.
CIN_LOW = {"A": 0.05, "B": 0.1, "C": 0.3}
CIN_HIGH = {"A": 0.2, "B": 0.8, "C": 0.9}
CIN_TABLE5 = {
    "A": [0.05, 0.08, 0.11, 0.14, 0.17, 0.2],
    "B": [0.1, 0.24, 0.38, 0.52, 0.66, 0.8],
    "C": [0.3, 0.42, 0.54, 0.66, 0.78, 0.9],
}
# Xinjiang vineyard soil, Table 6: B descends along the path, D, F, H ascend.
VIN_LOW = {"B": 0.15, "D": 0.05, "F": 0.5, "H": 0.1}
VIN_HIGH = {"B": 0.75, "D": 0.2, "F": 0.8, "H": 0.3}
VIN_TABLE6 = {
    "B": [0.75, 0.63, 0.51, 0.39, 0.27, 0.15],
    "D": [0.05, 0.08, 0.11, 0.14, 0.17, 0.2],
    "F": [0.5, 0.56, 0.62, 0.68, 0.74, 0.8],
    "H": [0.1, 0.14, 0.18, 0.22, 0.26, 0.3],
}


def _field(exc_info) -> str:
    return exc_info.value.field


def cinnamon_path() -> pd.DataFrame:
    return derive_path({"A": 1.0, "B": 1.0, "C": 1.0}, CIN_LOW, CIN_HIGH, 6)


def vineyard_path() -> pd.DataFrame:
    return derive_path({"B": -1.0, "D": 1.0, "F": 1.0, "H": 1.0}, VIN_LOW, VIN_HIGH, 6)


# --------------------------------------------------------------------------- select_factors
def _pb_data() -> pd.DataFrame:
    """12-run PB, factors = first 3 columns, responses y and y2.

    The "noise" is a combination of unused PB columns: they are orthogonal to the intercept and
    to x1..x3, so the fitted coefficients are exactly the true ones and the residual is exactly
    the noise. noise = 0.6 x4 - 0.8 x5 gives SS_res = 12 (0.36 + 0.64) = 12 on 12 - 1 - 3 = 8 df,
    MS_res = 1.5; SS_j = N b_j^2 = 12 b_j^2, so F_j = 8 b_j^2. (A truly tiny noise would make
    b3 = 0.1 significant too, so the amplitude is what makes x3 a non-significant factor:
    F = 0.08.) y2 uses the noise 0.8 x6 + 0.6 x7, again SS_res = 12.
    """
    X = plackett_burman(11)
    x1, x2, x3 = X[:, 0], X[:, 1], X[:, 2]
    y = 30 + 3 * x1 - 2 * x2 + 0.1 * x3 + (0.6 * X[:, 3] - 0.8 * X[:, 4])
    y2 = 5 + 0.05 * x1 + 0.0 * x2 + 2.5 * x3 + (0.8 * X[:, 5] + 0.6 * X[:, 6])
    return pd.DataFrame({"x1": x1, "x2": x2, "x3": x3, "y": y, "y2": y2})


def _p(b: float) -> float:
    return float(stats.f.sf(8 * b**2, 1, 8))


def _effects(data, response):
    eff = screening_effects(data, ["x1", "x2", "x3"], response)
    return eff.assign(response=response)


def test_select_factors_synthetic_pb_adds_third_factor():
    data = _pb_data()
    eff = _effects(data, "y")
    sel = select_factors(eff)
    # p: x1 F = 72, x2 F = 32 (both << 0.05), x3 F = 0.08 (p about 0.78)
    assert sel["term"].tolist() == ["x1", "x2", "x3"]
    assert sel["rank"].tolist() == [1, 2, 3]
    np.testing.assert_allclose(sel["p_min"], [_p(3), _p(2), _p(0.1)], rtol=1e-8)
    assert sel["significant"].tolist() == [True, True, False]
    assert sel["selected"].tolist() == [True, True, True]
    np.testing.assert_allclose(sel["b_y"], [3, -2, 0.1], atol=1e-12)
    np.testing.assert_allclose(sel["p_y"], sel["p_min"])
    assert sel["reason"].iloc[0] == f"p = {_p(3):.3g} < 0.05 (y)"
    assert sel["reason"].iloc[2] == "added: a Box-Behnken design needs at least 3 factors"
    # the fit's intercept is the mean response, the path's b0
    assert eff.attrs["fit"].params[0] == pytest.approx(30.0, abs=1e-12)


def test_select_factors_max_factors_keeps_best():
    sel = select_factors(_effects(_pb_data(), "y"), min_factors=1, max_factors=1)
    assert sel.loc[sel["selected"], "term"].tolist() == ["x1"]
    assert sel["reason"].iloc[1] == "significant but beyond max_factors = 1"
    assert sel["reason"].iloc[2].startswith("not significant (p_min = ")
    # default min_factors = 3 cannot be combined with max_factors = 1
    with pytest.raises(InputError) as e:
        select_factors(_effects(_pb_data(), "y"), max_factors=1)
    assert _field(e) == "max_factors"


def test_select_factors_any_response():
    data = _pb_data()
    eff = pd.concat([_effects(data, "y"), _effects(data, "y2")], ignore_index=True)
    sel = select_factors(eff)
    # p_min: x1 F = 72 (y), x3 F = 8 * 2.5^2 = 50 (y2), x2 F = 32 (y)
    assert sel["term"].tolist() == ["x1", "x3", "x2"]
    assert sel["significant"].all() and sel["selected"].all()
    np.testing.assert_allclose(sel["p_min"], [_p(3), _p(2.5), _p(2)], rtol=1e-8)
    assert sel["reason"].iloc[1] == f"p = {_p(2.5):.3g} < 0.05 (y2)"
    np.testing.assert_allclose(sel["b_y2"], [0.05, 2.5, 0.0], atol=1e-12)
    np.testing.assert_allclose(sel["p_y"], [_p(3), _p(0.1), _p(2)], rtol=1e-8)
    assert [c for c in sel.columns if c[:2] in ("b_", "p_")] == ["p_min", "b_y", "p_y", "b_y2", "p_y2"]


def test_select_factors_ties_and_min_factors():
    eff = pd.DataFrame({
        "response": ["r"] * 4,
        "term": ["P", "Q", "R", "S"],
        "coefficient": [1.0, -3.0, 0.5, 0.5],
        "p": [0.01, 0.01, 0.2, 0.2],
    })
    sel = select_factors(eff)
    # P and Q tie on p: larger |b| (Q) first; R and S tie on p and |b|: table order
    assert sel["term"].tolist() == ["Q", "P", "R", "S"]
    assert sel["selected"].tolist() == [True, True, True, False]
    assert sel["reason"].tolist()[3] == "not significant (p_min = 0.2)"
    sel4 = select_factors(eff, min_factors=4)
    assert sel4["selected"].all()
    assert sel4["reason"].iloc[3].startswith("added: min_factors = 4")
    strict = select_factors(eff, alpha=0.005)
    assert not strict["significant"].any() and strict["selected"].sum() == 3


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"alpha": 0.0}, "alpha"),
        ({"alpha": 1.0}, "alpha"),
        ({"alpha": -0.1}, "alpha"),
        ({"min_factors": 0}, "min_factors"),
        ({"min_factors": 3, "max_factors": 2}, "max_factors"),
        ({"min_factors": 5}, "effects.term"),
    ],
)
def test_select_factors_errors(kwargs, field):
    eff = pd.DataFrame({"response": ["r"] * 4, "term": list("PQRS"), "coefficient": [1.0] * 4, "p": [0.1] * 4})
    with pytest.raises(InputError) as e:
        select_factors(eff, **kwargs)
    assert _field(e) == field


def test_select_factors_missing_columns_and_duplicates():
    eff = pd.DataFrame({"term": list("PQR"), "coefficient": [1.0] * 3, "p": [0.1] * 3})
    with pytest.raises(InputError) as e:
        select_factors(eff)
    assert _field(e) == "effects" and "response" in str(e.value)
    dup = pd.DataFrame({"response": ["r"] * 4, "term": list("PQRR"), "coefficient": [1.0] * 4, "p": [0.1] * 4})
    with pytest.raises(InputError) as e:
        select_factors(dup)
    assert _field(e) == "effects"


# --------------------------------------------------------------------------- path_direction
def test_path_direction_one_response_ascent_and_descent():
    b = {"A": 2.0, "B": -1.0, "C": 0.0}
    up = path_direction({"y": b}, {"y": 30.0}, {"y": 35.0})
    down = path_direction({"y": b}, {"y": 30.0}, {"y": 25.0})
    # d_j = (t - b0) / t^2 * b_j = positive scale * sign(t - b0) * b_j
    for f in b:
        assert up[f] == pytest.approx((35.0 - 30.0) / 35.0**2 * b[f], rel=1e-15)
        assert down[f] == pytest.approx((25.0 - 30.0) / 25.0**2 * b[f], rel=1e-15)
    assert np.sign(up["A"]) == 1 and np.sign(up["B"]) == -1 and up["C"] == 0  # ascent: along b
    assert np.sign(down["A"]) == -1 and np.sign(down["B"]) == 1  # descent: against b
    # same direction as sign(t - b0) * b: ratios are those of b
    assert up["A"] / up["B"] == pytest.approx(-2.0) and down["A"] / down["B"] == pytest.approx(-2.0)
    assert list(up) == ["A", "B", "C"]


def test_path_direction_two_responses_weighted_sum_and_gradient():
    coef = {"y1": {"A": 2.0, "B": 1.0}, "y2": {"A": 1.0, "B": -3.0}, "untargeted": {"A": 9.0, "B": 9.0}}
    b0 = {"y1": 20.0, "y2": 12.0, "untargeted": 1.0}
    t = {"y1": 25.0, "y2": 10.0}
    d = path_direction(coef, b0, t)
    # weights (t - b0)/t^2: y1 5/625 = 0.008 (pulls up), y2 -2/100 = -0.02 (pulls down)
    # d_A = 0.008*2 - 0.02*1 = -0.004; d_B = 0.008*1 - 0.02*(-3) = 0.068
    assert d["A"] == pytest.approx(-0.004, abs=1e-15)
    assert d["B"] == pytest.approx(0.068, abs=1e-15)

    # it is minus half the gradient of f(x) = sum ((y_r(x) - t_r)/t_r)^2 at the centre; f is
    # quadratic, so the central difference is exact up to round-off
    def f(x):
        return sum(((b0[r] + sum(coef[r][k] * x[k] for k in x) - t[r]) / t[r]) ** 2 for r in t)

    h = 1e-3
    for k in ("A", "B"):
        xp = {"A": 0.0, "B": 0.0}
        xm = dict(xp)
        xp[k], xm[k] = h, -h
        assert -(f(xp) - f(xm)) / (2 * h) / 2 == pytest.approx(d[k], rel=1e-6)


def test_path_direction_end_to_end_from_screening():
    eff = _effects(_pb_data(), "y")
    b = dict(zip(eff["term"], eff["coefficient"]))
    b0 = float(eff.attrs["fit"].params[0])  # 30
    d = path_direction({"y": b}, {"y": b0}, {"y": 33.0})
    # centre 30 below target 33: ascend, d = 3/33^2 * (3, -2, 0.1)
    np.testing.assert_allclose([d["x1"], d["x2"], d["x3"]], np.array([3, -2, 0.1]) * 3 / 33**2, rtol=1e-10)


@pytest.mark.parametrize(
    "coef, b0, t, field",
    [
        ({"y": {"A": 1.0}}, {"y": 1.0}, {"y": 0.0}, "targets[y]"),
        ({"y": {"A": 1.0}}, {"y": 1.0}, {}, "targets"),
        ({"y": {"A": 1.0}}, {"y": 5.0}, {"y": 5.0}, "coefficients/intercepts"),
        ({"y": {"A": 0.0, "B": 0.0}}, {"y": 1.0}, {"y": 5.0}, "coefficients/intercepts"),
        ({"y": {"A": 1.0}}, {"y": 1.0}, {"z": 5.0}, "coefficients"),
        ({"y": {"A": 1.0}}, {}, {"y": 5.0}, "intercepts"),
        ({"y": {"A": 1.0}, "z": {"B": 1.0}}, {"y": 1.0, "z": 1.0}, {"y": 5.0, "z": 5.0}, "coefficients[z]"),
    ],
)
def test_path_direction_errors(coef, b0, t, field):
    with pytest.raises(InputError) as e:
        path_direction(coef, b0, t)
    assert _field(e) == field


# --------------------------------------------------------------------------- derive_path
def test_derive_path_range_rule_reproduces_cinnamon_table5():
    # only the signs matter for the "range" rule
    for direction in ({"A": 1.0, "B": 1.0, "C": 1.0}, {"A": 0.3, "B": 5.0, "C": 0.01}):
        path = derive_path(direction, CIN_LOW, CIN_HIGH, 6)
        assert path.columns.tolist() == ["step", "A", "B", "C"]
        assert path["step"].tolist() == [1, 2, 3, 4, 5, 6]
        for f, printed in CIN_TABLE5.items():
            np.testing.assert_allclose(path[f], printed, rtol=0, atol=TOL)
        assert path.attrs["rule"] == "range"
        assert path.attrs["direction"] == {"A": 1, "B": 1, "C": 1}
        # (high - low) / (n_steps - 1): 0.15/5, 0.7/5, 0.6/5
        for f, step in {"A": 0.03, "B": 0.14, "C": 0.12}.items():
            assert path.attrs["step"][f] == pytest.approx(step, abs=TOL)


def test_derive_path_range_rule_descending_factor_vineyard_table6():
    path = vineyard_path()
    for f, printed in VIN_TABLE6.items():
        np.testing.assert_allclose(path[f], printed, rtol=0, atol=TOL)
    assert path.attrs["direction"]["B"] == -1
    assert path.attrs["step"]["B"] == pytest.approx(-0.12, abs=TOL)


def test_derive_path_zero_direction_stays_at_centre():
    path = derive_path({"A": 1.0, "B": 0.0}, {"A": 0.0, "B": 2.0}, {"A": 1.0, "B": 4.0}, 3)
    assert path["B"].tolist() == [3.0, 3.0, 3.0]
    assert path.attrs["direction"]["B"] == 0 and path.attrs["step"]["B"] == 0.0


def test_derive_path_proportional_rule():
    d = {"A": 2.0, "B": -1.0, "C": 0.5}
    low = {"A": 0.0, "B": 0.0, "C": 10.0}
    high = {"A": 10.0, "B": 1.0, "C": 20.0}  # half ranges 5, 0.5, 5; centre 5, 0.5, 15
    path = derive_path(d, low, high, 5, rule="proportional")
    # base A (largest |d|), default base step 10/4 = 2.5 actual = 0.5 coded;
    # coded steps d_j/|d_A| * 0.5: B -0.25, C 0.125 -> actual B -0.125, C 0.625
    assert path.attrs["base"] == "A"
    coded = path.attrs["coded_step"]
    assert coded["A"] == pytest.approx(0.5) and coded["B"] == pytest.approx(-0.25)
    assert coded["C"] == pytest.approx(0.125)
    # coded steps in the ratio of the coefficients
    assert coded["A"] / coded["B"] == pytest.approx(d["A"] / d["B"])
    assert coded["C"] / coded["A"] == pytest.approx(d["C"] / d["A"])
    # centred on the screening centre: step 3 of 5 is the centre, step 1 is 2 steps back
    k = np.arange(5) - 2
    np.testing.assert_allclose(path["A"], 5 + 2.5 * k, atol=TOL)  # walks exactly 0 -> 10
    np.testing.assert_allclose(path["B"], 0.5 - 0.125 * k, atol=TOL)
    np.testing.assert_allclose(path["C"], 15 + 0.625 * k, atol=TOL)
    assert path.attrs["direction"] == {"A": 1, "B": -1, "C": 1}
    # same increments as Montgomery's construction in steepest_ascent_path
    ref = steepest_ascent_path(d, low, high, base="A", base_step_actual=2.5, n_steps=1)
    for f in d:
        assert path.attrs["step"][f] == pytest.approx(ref.attrs["actual_step"][f])

    # explicit base B, 0.1 actual per step = -0.2 coded (B descends); A: 2/1 * 0.2 = 0.4 coded
    # = 2.0 actual, C: 0.5/1 * 0.2 = 0.1 coded = 0.5 actual; 4 steps centred between steps 2, 3
    pb = derive_path(d, low, high, 4, rule="proportional", base="B", base_step=0.1)
    k = np.arange(4) - 1.5
    np.testing.assert_allclose(pb["B"], 0.5 - 0.1 * k, atol=TOL)
    np.testing.assert_allclose(pb["A"], 5 + 2.0 * k, atol=TOL)
    np.testing.assert_allclose(pb["C"], 15 + 0.5 * k, atol=TOL)


@pytest.mark.parametrize(
    "args, kwargs, field",
    [
        (({"A": 1.0}, {"A": 0.0}, {"A": 1.0}, 1), {}, "n_steps"),
        (({"A": 1.0}, {"A": 0.0}, {"A": 1.0}, 3), {"rule": "diagonal"}, "rule"),
        (({"A": 1.0}, {"A": 1.0}, {"A": 1.0}, 3), {}, "low/high[A]"),
        (({"A": 1.0}, {"A": 2.0}, {"A": 1.0}, 3), {}, "low/high[A]"),
        (({"A": 1.0, "B": 1.0}, {"A": 0.0}, {"A": 1.0, "B": 1.0}, 3), {}, "low"),
        (({"A": 1.0}, {"A": 0.0}, {"A": 1.0, "B": 1.0}, 3), {}, "high"),
        (({"A": 0.0}, {"A": 0.0}, {"A": 1.0}, 3), {}, "direction"),
        (({"A": 1.0}, {"A": 0.0}, {"A": 1.0}, 3), {"rule": "proportional", "base": "Z"}, "base"),
        (({"A": 1.0, "B": 0.0}, {"A": 0.0, "B": 0.0}, {"A": 1.0, "B": 1.0}, 3),
         {"rule": "proportional", "base": "B"}, "base"),
        (({"A": 1.0}, {"A": 0.0}, {"A": 1.0}, 3), {"rule": "proportional", "base_step": 0.0}, "base_step"),
        (({"A": 1.0}, {"A": 0.0}, {"A": 1.0}, 3), {"base": "A"}, "base/base_step"),
    ],
)
def test_derive_path_errors(args, kwargs, field):
    with pytest.raises(InputError) as e:
        derive_path(*args, **kwargs)
    assert _field(e) == field


# --------------------------------------------------------------------------- chosen_step
def test_chosen_step_linear_response_crossing_target():
    path = cinnamon_path()
    s = np.arange(1, 7)
    y = 40.0 - 5.0 * s  # 35, 30, 25, 20, 15, 10: crosses 27 at s = 2.6
    best, tab = chosen_step(path, {"y": y}, {"y": 27.0})
    # |y - t|/t = 5 |s - 2.6| / 27, smallest at the integer nearest 2.6
    assert best == 3
    np.testing.assert_allclose(tab["error_y_percent"], 100 * 5 * np.abs(s - 2.6) / 27, rtol=1e-12)
    np.testing.assert_allclose(tab["error_percent"], tab["error_y_percent"])
    assert tab["chosen"].tolist() == [False, False, True, False, False, False]
    assert tab.columns.tolist() == ["step", "y", "error_y_percent", "error_percent", "chosen"]

    # step 3 failed: step 2 (distance 0.6) beats step 4 (distance 1.4)
    y_nan = y.copy()
    y_nan[2] = np.nan
    best, tab = chosen_step(path, {"y": list(y_nan)}, {"y": 27.0})
    assert best == 2 and np.isnan(tab["error_percent"].iloc[2])

    # 30 and 25 are both 2.5 from 27.5: tie -> earlier step
    assert chosen_step(path, {"y": y}, {"y": 27.5})[0] == 2


def test_chosen_step_two_responses_combined_error():
    path = derive_path({"A": 1.0}, {"A": 0.0}, {"A": 1.0}, 3)
    resp = {"y1": [10.0, 12.0, 14.0], "y2": [30.0, 20.0, 10.0], "other": [1.0, 2.0, 3.0]}
    best, tab = chosen_step(path, resp, {"y1": 12.0, "y2": 10.0})
    # relative errors: y1 (-1/6, 0, 1/6), y2 (2, 1, 0)
    e = [np.sqrt((1 / 36 + 4) / 2), np.sqrt(1 / 2), np.sqrt(1 / 36 / 2)]
    np.testing.assert_allclose(tab["error_percent"], np.array(e) * 100, rtol=1e-12)
    assert best == 3
    assert "other" in tab.columns and "error_other_percent" not in tab.columns
    # a step with one failed targeted response counts as failed
    resp["y2"] = [30.0, 20.0, np.nan]
    assert chosen_step(path, resp, {"y1": 12.0, "y2": 10.0})[0] == 2


# --------------------------------------------------------------------------- the fitted rule
STEPS = np.arange(1, 7, dtype=float)
ALT = 0.1 * np.array([1, -1, 1, -1, 1, -1])  # a small alternating scatter


def test_path_trend_of_a_line_is_its_least_squares_line():
    # y = 60 - 5 s plus the alternating scatter: the OLS line adds the scatter's projection,
    # slope sum(ALT (s - 3.5)) / sum((s - 3.5)^2) = -0.3 / 17.5, mean(ALT) = 0
    tr = path_trend(STEPS, 60 - 5 * STEPS + ALT)
    assert tr["degree"] == 1 and tr["n"] == 6
    np.testing.assert_allclose(tr["fitted"], 60 - 5 * STEPS - 0.3 / 17.5 * (STEPS - 3.5), rtol=0, atol=1e-9)
    resid = ALT + 0.3 / 17.5 * (STEPS - 3.5)
    assert tr["residual_sd"] == pytest.approx(np.sqrt(np.sum(resid ** 2) / 4), rel=1e-9)
    assert tr["p_quadratic"] > 0.05  # tested (six steps) and not kept


def test_path_trend_tests_its_slope_and_says_when_it_tells_no_step_apart():
    """The slope's p-value is the OLS t-test of the line's slope (scipy's linregress gives it
    independently); a path whose runs scatter with no slope (here one without curvature the
    test would keep) is cautioned, a clear line is not."""
    y = np.array([8.4, 36.8, 31.1, 23.9, 14.1, 14.2])
    tr = path_trend(STEPS, y)
    assert tr["degree"] == 1
    assert tr["p_slope"] == pytest.approx(stats.linregress(STEPS, y).pvalue, rel=1e-9)
    assert tr["p_slope"] > 0.05
    text = trend_caution(tr)
    assert "no significant slope" in text and f"p = {tr['p_slope']:.2g}" in text
    line = path_trend(STEPS, 60 - 5 * STEPS + ALT)
    assert line["p_slope"] == pytest.approx(stats.linregress(STEPS, 60 - 5 * STEPS + ALT).pvalue, rel=1e-9)
    assert trend_caution(line) == ""
    # a curvature kept is a trend too; a trend not fitted (two steps) is not judged
    assert trend_caution(path_trend(STEPS, 30 + 2 * (STEPS - 3.5) ** 2 + ALT)) == ""
    assert trend_caution(path_trend([1.0, 2.0], [3.0, 9.0])) == ""


def test_path_trend_keeps_a_curvature_the_runs_show():
    truth = 30 + 2 * (STEPS - 3.5) ** 2
    tr = path_trend(STEPS, truth + ALT)
    assert tr["degree"] == 2 and tr["p_quadratic"] < 0.05
    np.testing.assert_allclose(tr["fitted"], truth, atol=0.1)


def test_path_trend_failed_steps_and_short_paths():
    y = 60 - 5 * STEPS
    y[2] = np.nan
    tr = path_trend(STEPS, y)
    assert tr["n"] == 5 and np.isnan(tr["fitted"][2])
    np.testing.assert_allclose(np.delete(tr["fitted"], 2), np.delete(60 - 5 * STEPS, 2), atol=1e-9)
    # two finite steps: no trend, the runs themselves
    tr = path_trend([1.0, 2.0, 3.0], [np.nan, 5.0, 7.0])
    assert tr["degree"] is None and np.isnan(tr["residual_sd"])
    np.testing.assert_array_equal(tr["fitted"], [np.nan, 5.0, 7.0])
    # four steps: a line only (a quadratic would leave one degree of freedom)
    tr = path_trend([1.0, 2.0, 3.0, 4.0], [1.0, 4.0, 9.0, 16.0])
    assert tr["degree"] == 1 and np.isnan(tr["p_quadratic"])
    with pytest.raises(InputError) as e:
        path_trend([1.0, 2.0, 3.0], [1.0, 2.0])
    assert _field(e) == "values"


def test_fitted_rule_is_not_pulled_onto_a_lucky_step():
    """A line 55, 50, ..., 30 crossing the target 27 beyond the last step, with one run at
    step 2 landing on the target by chance (27 instead of 50)."""
    path = cinnamon_path()
    y = 60 - 5 * STEPS
    delta = 27.0 - y[1]
    y[1] = 27.0
    best, tab = chosen_step(path, {"y": y}, {"y": 27.0})
    assert best == 2  # the papers' rule takes the lucky run
    best, tab = chosen_step(path, {"y": y}, {"y": 27.0}, rule="fitted")
    # OLS with one perturbed point: fitted_s = line_s + delta (1/6 + (2 - 3.5)(s - 3.5) / 17.5)
    line = 60 - 5 * STEPS + delta * (1 / 6 + (2 - 3.5) * (STEPS - 3.5) / 17.5)
    np.testing.assert_allclose(tab["fitted_y"], line, rtol=1e-12)
    np.testing.assert_allclose(tab["error_y_percent"], np.abs(line - 27.0) / 27.0 * 100, rtol=1e-12)
    assert best == 6 and tab["chosen"].tolist() == [False] * 5 + [True]
    assert tab.columns.tolist() == ["step", "y", "fitted_y", "error_y_percent", "error_percent", "chosen"]
    # a failed run is never the centre, even where the trend passes the target
    y[5] = np.nan
    best, tab = chosen_step(path, {"y": y}, {"y": 27.0}, rule="fitted")
    assert best == 5 and np.isnan(tab["error_percent"].iloc[5])
    with pytest.raises(InputError) as e:
        chosen_step(path, {"y": y}, {"y": 27.0}, rule="nearest")
    assert _field(e) == "rule"


@pytest.mark.parametrize(
    "responses, targets, field",
    [
        ({"y": [np.nan, np.nan, np.nan]}, {"y": 1.0}, "responses"),
        ({"y": [1.0, 2.0]}, {"y": 1.0}, "responses[y]"),
        ({"y": [1.0, 2.0, 3.0]}, {"y": 0.0}, "targets[y]"),
        ({"y": [1.0, 2.0, 3.0]}, {"z": 1.0}, "targets"),
        ({"y": [1.0, 2.0, 3.0]}, {}, "targets"),
    ],
)
def test_chosen_step_errors(responses, targets, field):
    path = derive_path({"A": 1.0}, {"A": 0.0}, {"A": 1.0}, 3)
    with pytest.raises(InputError) as e:
        chosen_step(path, responses, targets)
    assert _field(e) == field


# --------------------------------------------------------------------------- bbd_levels
def test_bbd_levels_cinnamon_table6():
    lv = bbd_levels(cinnamon_path(), 3, ["A", "B", "C"])
    # "levels of no. 2, no. 3 and no. 4 were selected as low, medium and high"
    printed = {"A": (0.08, 0.11, 0.14), "B": (0.24, 0.38, 0.52), "C": (0.42, 0.54, 0.66)}
    for f, (lo, c, hi) in printed.items():
        assert lv[f]["low"] == pytest.approx(lo, abs=TOL)
        assert lv[f]["centre"] == pytest.approx(c, abs=TOL)
        assert lv[f]["high"] == pytest.approx(hi, abs=TOL)
        assert lv[f]["note"] == "low = step 2, centre = step 3, high = step 4"


def test_bbd_levels_vineyard_descending_factor():
    lv = bbd_levels(vineyard_path(), 2, ["B", "D", "F", "H"])
    # step 2 centre, steps 1 and 3 the other levels; B descends so step 1 is its high level
    printed = {"B": (0.51, 0.63, 0.75), "D": (0.05, 0.08, 0.11), "F": (0.5, 0.56, 0.62), "H": (0.1, 0.14, 0.18)}
    for f, (lo, c, hi) in printed.items():
        assert (lv[f]["low"], lv[f]["centre"], lv[f]["high"]) == pytest.approx((lo, c, hi), abs=TOL)
    assert lv["B"]["note"] == "low = step 3, centre = step 2, high = step 1"
    assert lv["D"]["note"] == "low = step 1, centre = step 2, high = step 3"


def test_bbd_levels_mirrored_at_path_ends():
    path = cinnamon_path()
    first = bbd_levels(path, 1, ["A"])["A"]
    # centre 0.05, neighbour 0.08 -> mirrored 0.05 - 0.03 = 0.02
    assert (first["low"], first["centre"], first["high"]) == pytest.approx((0.02, 0.05, 0.08), abs=TOL)
    assert "mirrored" in first["note"] and "first step" in first["note"]
    last = bbd_levels(path, 6, ["A"])["A"]
    # centre 0.2, neighbour 0.17 -> mirrored 0.2 + 0.03 = 0.23
    assert (last["low"], last["centre"], last["high"]) == pytest.approx((0.17, 0.2, 0.23), abs=TOL)
    assert "mirrored" in last["note"] and "last step" in last["note"]
    # descending factor at step 1: neighbour 0.63 is the low level, mirrored 0.87 the high
    b = bbd_levels(vineyard_path(), 1, ["B"])["B"]
    assert (b["low"], b["centre"], b["high"]) == pytest.approx((0.63, 0.75, 0.87), abs=TOL)


def test_bbd_levels_shifted_inside_bounds():
    path = cinnamon_path()
    # step 1 of B: (-0.04, 0.1, 0.24) below 0 -> shifted by +0.04 -> (0, 0.14, 0.28)
    b = bbd_levels(path, 1, ["B"], bounds={"B": (0.0, 1.0)})["B"]
    assert (b["low"], b["centre"], b["high"]) == pytest.approx((0.0, 0.14, 0.28), abs=TOL)
    assert b["low"] >= 0.0 and "shifted" in b["note"]
    # step 6 of C: (0.78, 0.9, 1.02) above 1 -> shifted by -0.02 -> (0.76, 0.88, 1.0)
    c = bbd_levels(path, 6, ["C"], bounds={"C": (None, 1.0)})["C"]
    assert (c["low"], c["centre"], c["high"]) == pytest.approx((0.76, 0.88, 1.0), abs=TOL)
    assert c["high"] <= 1.0
    # inside the bounds: untouched
    a = bbd_levels(path, 3, ["A"], bounds={"A": (0.0, 1.0)})["A"]
    assert a["centre"] == pytest.approx(0.11, abs=TOL) and "shifted" not in a["note"]


def test_bbd_levels_errors():
    path = cinnamon_path()
    # spacing 0.52 - 0.24 = 0.28 does not fit in [0.3, 0.5]
    with pytest.raises(InputError) as e:
        bbd_levels(path, 3, ["B"], bounds={"B": (0.3, 0.5)})
    assert _field(e) == "bounds[B]"
    with pytest.raises(InputError) as e:
        bbd_levels(path, 3, ["B"], bounds={"B": (1.0, 0.0)})
    assert _field(e) == "bounds[B]"
    with pytest.raises(InputError) as e:
        bbd_levels(path, 7, ["A"])
    assert _field(e) == "step"
    with pytest.raises(InputError) as e:
        bbd_levels(path, 3, ["A", "Z"])
    assert _field(e) == "factors"
    with pytest.raises(InputError) as e:
        bbd_levels(path.iloc[:1], 1, ["A"])
    assert _field(e) == "path"
    # a factor that does not move along the path has no three distinct levels
    flat = derive_path({"A": 1.0, "B": 1.0, "C": 0.0}, CIN_LOW, CIN_HIGH, 6)
    with pytest.raises(InputError) as e:
        bbd_levels(flat, 3, ["A", "B", "C"])
    assert _field(e) == "path.C"
