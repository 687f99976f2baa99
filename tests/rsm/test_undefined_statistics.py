"""Statistics the data leave undefined are written empty with the reason, never as inf.

A Box-Behnken design of three factors and three centre points whose run 2 (A = -1, B = +1,
C = 0) gave no response: the full quadratic's A*B term then rests on one point alone, which
the model passes through whatever its response (leverage 1), so that point has no
leave-one-out prediction and PRESS and pred R2 are undefined.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import optimize, stats

from soilcal import doe, rsm
from soilcal.chain.stage import regression_frames

SCATTER = np.array([0.1, -0.2, 0.15, -0.05, 0.3, -0.1, 0.2, 0.05, -0.15, 0.1, 0.02, -0.3, 0.12, -0.08, 0.04])


def _table(missing=(2,)) -> pd.DataFrame:
    x = doe.box_behnken(3, 3)
    df = pd.DataFrame(x.astype(int), columns=list("ABC"))
    df.insert(0, "run", np.arange(1, len(df) + 1))
    a, b, c = x.T
    y = 30 + a + 2 * b - c + 0.5 * a * b + a * a + SCATTER
    df["angle"] = y
    df.loc[df["run"].isin(missing), "angle"] = np.nan
    return df


STAGE = {"id": "bbd", "kind": "box_behnken", "center_points": 3, "table_coding": "coded",
         "factors": {s: {"parameter": s.lower(), "low": -1.0, "high": 1.0} for s in "ABC"},
         "responses": [{"id": "angle"}]}


def _fit(table: pd.DataFrame):
    d = table.dropna(subset=["angle"])
    return rsm.fit_response_surface(d, list("ABC"), "angle", [-1] * 3, [1] * 3, data_coding="coded")


def test_a_point_of_leverage_one_is_the_one_the_model_passes_through_whatever_its_response():
    t = _table()
    fit = _fit(t)
    pos = list(fit.leverage_one)
    assert len(pos) >= 1
    # leverage 1 <=> the point's residual is zero whatever its response: move each response by
    # 10 and refit
    d = t.dropna(subset=["angle"]).reset_index(drop=True)
    through = []
    for i in range(len(d)):
        moved = d.copy()
        moved.loc[i, "angle"] += 10.0
        if abs(_fit(moved).residuals[i]) < 1e-8:
            through.append(i)
    assert pos == through
    stats = fit.fit_statistics()
    assert np.isnan(stats["PRESS"]) and np.isnan(stats["pred_R2"])
    runs = [int(d["run"][i]) for i in pos]
    note = fit.statistics_note(list(d["run"]))
    assert note.startswith(f"point {runs[0]} has leverage 1") and "PRESS and pred R2 undefined" in note
    # the full design: no such point, PRESS the leave-one-out sum, no note
    full = _fit(_table(missing=()))
    assert not full.leverage_one.size and np.isfinite(full.press) and full.statistics_note() == ""


def test_fit_csv_has_no_infinity_and_says_why_a_statistic_is_empty():
    t = _table()
    fit = regression_frames(STAGE, t)["fit"]
    numeric = fit.select_dtypes("number").to_numpy(float)
    assert not np.isinf(numeric).any()
    full = fit[fit["model"] == "full"].iloc[0]
    run = int(t.dropna(subset=["angle"])["run"].iloc[int(_fit(t).leverage_one[0])])
    assert np.isnan(full["PRESS"]) and np.isnan(full["pred_R2"])
    assert f"point {run} has leverage 1" in full["note"]
    # every point present: nothing undefined for the model
    whole = regression_frames(STAGE, _table(missing=()))["fit"]
    assert np.isfinite(whole["PRESS"]).all()
    assert not whole["note"].str.contains("leverage").any()


def _two_level(table: pd.DataFrame, c: float) -> pd.DataFrame:
    """The table's observed responses replaced by c and 1/c alternately (as many of each)."""
    t = table.copy()
    seen = t["angle"].notna()
    t.loc[seen, "angle"] = np.where(np.arange(int(seen.sum())) % 2 == 0, c, 1.0 / c)
    return t


def _two_level_half_width(L: float, nu: int, alpha: float = 0.05) -> float:
    """Box-Cox interval half-width for a response taking c and 1/c equally often, L = ln c.

    The geometric mean is 1, so every transform of the response is a + b(lambda) * indicator
    with b(lambda) = 2 sinh(lambda L) / lambda: SS_E(lambda) = b(lambda)^2 * SS_E of the
    indicator, least at lambda = 0 (b = 2L), and SS_E <= SS*(1 + t^2/nu) exactly where
    sinh(lambda L) / (lambda L) <= sqrt(1 + t^2/nu), i.e. |lambda| <= u / L.
    """
    k = np.sqrt(1.0 + stats.t.ppf(1 - alpha / 2, nu) ** 2 / nu)
    return optimize.brentq(lambda u: np.sinh(u) / u - k, 1e-9, 50.0) / L


def test_box_cox_of_a_two_level_response_has_the_analytic_optimum_and_interval():
    x = np.arange(8.0)
    X = np.column_stack([np.ones(8), x])
    L = 2.0
    y = np.exp(L * np.array([1, -1, -1, 1, 1, -1, -1, 1.0]))
    bc = rsm.boxcox(X, y)
    w = _two_level_half_width(L, nu=8 - 2)
    assert 0.5 < w < 1.0  # inside the searched range: both ends finite
    assert bc["lambda_best"] == pytest.approx(0.0, abs=1e-4)
    assert bc["ci_low"] == pytest.approx(-w, abs=1e-6) and bc["ci_high"] == pytest.approx(w, abs=1e-6)
    assert bc["ci_note"] == ""
    # 0.5, 0 and -0.5 lie inside, 1 does not: the standard lambda nearest the best, ln
    assert bc["recommended_transform"] == "ln"


@pytest.mark.parametrize("make_y, lam", [
    (lambda x: (3.0 + x) ** 2, 0.5),   # sqrt(y) exactly linear in x
    (lambda x: np.exp(0.3 * x), 0.0),  # ln(y) exactly linear in x
    (lambda x: 1.0 / (2.0 + x), -1.0),  # 1/y exactly linear in x
])
def test_box_cox_finds_the_power_that_makes_the_response_exactly_linear(make_y, lam):
    x = np.arange(8.0)
    X = np.column_stack([np.ones(8), x])
    bc = rsm.boxcox(X, make_y(x))
    assert bc["lambda_best"] == pytest.approx(lam, abs=1e-3)


def test_fit_csv_leaves_an_open_box_cox_end_empty_and_names_it():
    """Responses 1.1 and 1/1.1: the interval is |lambda| <= u / ln 1.1, over 3 for every
    model the stage fits, so it covers the searched range -3 to 3 at both ends."""
    c = 1.1
    fit = regression_frames(STAGE, _two_level(_table(), c))["fit"]
    assert list(fit["model"]) == ["full", "reduced"]
    # the narrowest of these intervals is the one of most residual df, 13 of 14 runs
    assert _two_level_half_width(np.log(c), nu=13) > 3.0
    for _, r in fit.iterrows():
        assert r["boxcox_lambda"] == pytest.approx(0.0, abs=1e-3)
        assert pd.isna(r["boxcox_ci_low"]) and pd.isna(r["boxcox_ci_high"])
        assert ("Box-Cox: the 95 % interval of lambda covers the whole searched range -3 to 3"
                in r["note"])
    assert not np.isinf(fit.select_dtypes("number").to_numpy(float)).any()


@pytest.mark.parametrize("lams, expected", [
    (np.linspace(0.9, 1.1, 21), "covers the whole searched range 0.9 to 1.1"),
])
def test_box_cox_interval_beyond_the_searched_range_is_named(lams, expected):
    """On a narrow lambda grid around 1 the 95 % interval of a well-fitted positive response
    reaches past both ends."""
    fit = _fit(_table(missing=()))
    bc = rsm.boxcox(fit, lambdas=lams)
    assert np.isinf(bc["ci_low"]) and np.isinf(bc["ci_high"])
    assert expected in bc["ci_note"]


def test_centre_points_printed_alike_leave_the_lack_of_fit_untested_and_say_why():
    """Three centre points with one printed response (a table rounded to 0.1): the pure error
    is 0, so the lack of fit's F (its mean square over the pure error's) is undefined; the sums
    of squares still partition the residual."""
    t = _table(missing=())
    centre = (t[list("ABC")] == 0).all(axis=1)
    t.loc[centre, "angle"] = 30.0
    tab = _fit(t).anova().set_index("source")
    assert tab.loc["Pure Error", "sum_sq"] == 0.0 and tab.loc["Pure Error", "df"] == 2
    assert tab.loc["Lack of Fit", "sum_sq"] == pytest.approx(tab.loc["Residual", "sum_sq"])
    assert np.isnan(tab.loc["Lack of Fit", "F"]) and np.isnan(tab.loc["Lack of Fit", "p"])
    fit = regression_frames(STAGE, t)["fit"]
    assert fit["note"].str.contains("identical responses: no pure error").all()


def test_six_centre_points_printed_alike_leave_the_lack_of_fit_untested_though_their_mean_rounds():
    """Six centre points printed 35.2: their mean is not exactly 35.2 in floating point, so the
    pure error's sum of squares is a rounding remainder, not 0; still no replicate scatter, so
    the lack of fit has no F and no p, and fit.csv's note says why."""
    x = doe.box_behnken(3, 6)
    t = pd.DataFrame(x.astype(int), columns=list("ABC"))
    t.insert(0, "run", np.arange(1, len(t) + 1))
    a, b, c = x.T
    t["angle"] = 30 + a + 2 * b - c + 0.5 * a * b + a * a + np.resize(SCATTER, len(t))
    centre = (t[list("ABC")] == 0).all(axis=1)
    assert centre.sum() == 6
    t.loc[centre, "angle"] = 35.2
    fit = _fit(t)
    assert fit.pure_error_negligible()
    tab = fit.anova().set_index("source")
    assert tab.loc["Pure Error", "df"] == 5
    assert tab.loc["Pure Error", "sum_sq"] == pytest.approx(0.0, abs=1e-20)
    assert np.isnan(tab.loc["Lack of Fit", "F"]) and np.isnan(tab.loc["Lack of Fit", "p"])
    assert "identical responses: no pure error" in fit.statistics_note()
    stage = dict(STAGE, center_points=6)
    assert regression_frames(stage, t)["fit"]["note"].str.contains("identical responses: no pure error").all()
    # one centre point moved by 0.1: pure error, an F and a p
    t.loc[centre[centre].index[0], "angle"] = 35.3
    moved = _fit(t)
    assert not moved.pure_error_negligible()
    assert np.isfinite(moved.anova().set_index("source").loc["Lack of Fit", "F"])
