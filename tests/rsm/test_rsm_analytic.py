"""Analytic checks of the response-surface code (exact polynomials, identities)."""

import numpy as np
import pandas as pd
import pytest
from statsmodels.stats.outliers_influence import OLSInfluence

from soilcal.doe import box_behnken, coded_to_actual
from soilcal.errors import InputError
from soilcal.rsm import (
    apply_transform,
    backward_eliminate,
    boxcox,
    compare_printed,
    fit_response_surface,
    inverse_transform,
    transform_suggestion,
)

LOW, HIGH = [0.05, 0.1, 0.3, 2.0], [0.2, 0.8, 0.9, 6.0]
FACTORS = ["A", "B", "C", "D"]
# exact coded polynomial
TRUE = {"Intercept": 10.0, "A": 1.5, "B": -0.7, "C": 0.3, "D": 2.0, "A*B": 0.4, "A*C": -0.25, "A*D": 0.0,
        "B*C": 0.1, "B*D": -0.6, "C*D": 0.2, "A^2": -1.1, "B^2": 0.8, "C^2": 0.05, "D^2": -0.3}


def _poly(x):
    a, b, c, d = x.T
    t = TRUE
    return (t["Intercept"] + t["A"] * a + t["B"] * b + t["C"] * c + t["D"] * d + t["A*B"] * a * b
            + t["A*C"] * a * c + t["A*D"] * a * d + t["B*C"] * b * c + t["B*D"] * b * d + t["C*D"] * c * d
            + t["A^2"] * a**2 + t["B^2"] * b**2 + t["C^2"] * c**2 + t["D^2"] * d**2)


def _data(noise=0.0, seed=0, actual=False):
    x = box_behnken(4, 5)
    y = _poly(x) + np.random.default_rng(seed).normal(0, noise, len(x))
    df = pd.DataFrame(coded_to_actual(x, LOW, HIGH) if actual else x, columns=FACTORS)
    df["y"] = y
    return df


def test_noise_free_quadratic_exact():
    for actual in (False, True):
        fit = fit_response_surface(_data(actual=actual), FACTORS, "y", LOW, HIGH,
                                   data_coding="actual" if actual else "coded")
        coef = fit.coefficients().set_index("term")["coded"]
        for t, v in TRUE.items():
            assert coef[t] == pytest.approx(v, abs=1e-10)
        assert fit.fit_statistics()["R2"] == pytest.approx(1.0, abs=1e-12)
        assert fit.n == 29 and fit.df_resid == 14


@pytest.mark.parametrize("transform", ["none", "ln"])
def test_confidence_interval_of_the_mean_by_hand(transform):
    """x0' b -+ t(0.975, n - p) sqrt(MSE x0' (X'X)^-1 x0) from the model matrix, on the
    transformed scale and back-transformed, at a point inside the design region."""
    from scipy import stats

    df = _data(noise=0.3, seed=4, actual=True)
    df["y"] = df["y"] + 20.0  # positive for the log
    fit = fit_response_surface(df, FACTORS, "y", LOW, HIGH, data_coding="actual",
                               transform=transform)
    X = fit.model_matrix
    xa = np.array([[0.1, 0.5, 0.4, 3.0]])
    # the model row of the point, written out term by term
    xc = (xa - (np.array(LOW) + HIGH) / 2) / ((np.array(HIGH) - LOW) / 2)
    a, b, c, d = xc[0]
    cols = {"Intercept": 1.0, "A": a, "B": b, "C": c, "D": d, "A*B": a * b, "A*C": a * c,
            "A*D": a * d, "B*C": b * c, "B*D": b * d, "C*D": c * d, "A^2": a * a, "B^2": b * b,
            "C^2": c * c, "D^2": d * d}
    x0 = np.array([cols[t] for t in ["Intercept", *fit.terms]])
    yhat = x0 @ fit.params
    half = stats.t.ppf(0.975, fit.df_resid) * np.sqrt(fit.mse * x0 @ np.linalg.inv(X.T @ X) @ x0)
    lo, hi = fit.confidence_actual(xa)
    inv = (lambda z: z) if transform == "none" else np.exp
    assert lo[0] == pytest.approx(inv(yhat - half), rel=1e-10)
    assert hi[0] == pytest.approx(inv(yhat + half), rel=1e-10)
    assert lo[0] < fit.predict_actual(xa)[0] < hi[0]


def test_actual_coefficients_one_factor_by_hand():
    # y = 1 + 2x + 3x^2 with x = (X - 5)/2  =>  y = 1 + (X-5) + 0.75 (X-5)^2
    X = np.array([3.0, 4.0, 5.0, 6.0, 7.0, 5.0])
    x = (X - 5) / 2
    df = pd.DataFrame({"A": X, "y": 1 + 2 * x + 3 * x**2})
    fit = fit_response_surface(df, ["A"], "y", [3.0], [7.0], data_coding="actual")
    act = fit.coefficients().set_index("term")["actual"]
    assert act["Intercept"] == pytest.approx(1 - 5 + 0.75 * 25)
    assert act["A"] == pytest.approx(1 - 0.75 * 10)
    assert act["A^2"] == pytest.approx(0.75)


def test_diagnostics_match_statsmodels_influence():
    fit = fit_response_surface(_data(noise=0.3, seed=3), FACTORS, "y", LOW, HIGH)
    infl = OLSInfluence(fit.ols)
    np.testing.assert_allclose(fit.leverage, infl.hat_matrix_diag, rtol=1e-10)
    np.testing.assert_allclose(fit.studentized_residuals, infl.resid_studentized_internal, rtol=1e-8)
    np.testing.assert_allclose(fit.externally_studentized_residuals, infl.resid_studentized_external, rtol=1e-8)
    np.testing.assert_allclose(fit.cooks_distance, infl.cooks_distance[0], rtol=1e-8)
    # PRESS identity and mean leverage p/n
    assert fit.leverage.mean() == pytest.approx(fit.p / fit.n)
    loo = []
    for i in range(fit.n):
        keep = np.arange(fit.n) != i
        beta = np.linalg.lstsq(fit.model_matrix[keep], fit.y_t[keep], rcond=None)[0]
        loo.append(fit.y_t[i] - fit.model_matrix[i] @ beta)
    assert fit.press == pytest.approx(np.sum(np.square(loo)))


def test_anova_partitions():
    fit = fit_response_surface(_data(noise=0.3, seed=4), FACTORS, "y", LOW, HIGH)
    tab = fit.anova().set_index("source")
    assert tab.loc["Model", "sum_sq"] + tab.loc["Residual", "sum_sq"] == pytest.approx(tab.loc["Cor Total", "sum_sq"])
    assert tab.loc["Lack of Fit", "sum_sq"] + tab.loc["Pure Error", "sum_sq"] == pytest.approx(tab.loc["Residual", "sum_sq"])
    assert tab.loc["Pure Error", "df"] == 4 and tab.loc["Lack of Fit", "df"] == 10
    # no replicates -> no lack-of-fit rows
    nodup = _data(noise=0.3, seed=4).iloc[:25]
    t2 = fit_response_surface(nodup, FACTORS, "y", LOW, HIGH).anova()
    assert "Pure Error" not in set(t2["source"]) and "Lack of Fit" not in set(t2["source"])


def test_backward_elimination_keeps_hierarchy():
    # y depends on A only through A*B: A has a zero coefficient but must stay
    x = box_behnken(3, 3)
    a, b, c = x.T
    y = 5 + 2 * b + 3 * a * b + np.random.default_rng(5).normal(0, 0.01, len(x))
    df = pd.DataFrame(x, columns=["A", "B", "C"])
    df["y"] = y
    full = fit_response_surface(df, ["A", "B", "C"], "y", [-1] * 3, [1] * 3)
    red = backward_eliminate(full, alpha_out=0.1, hierarchical=True)
    assert set(red.terms) == {"A", "B", "A*B"}
    assert "A" not in backward_eliminate(full, alpha_out=0.1, hierarchical=False).terms


@pytest.mark.parametrize("tr", ["sqrt", "ln", "log10", "inverse", "inverse_sqrt", ("power", 0.3), ("power", 0.0)])
def test_transform_round_trip_and_fit(tr):
    y = np.linspace(0.5, 40.0, 17)
    np.testing.assert_allclose(inverse_transform(apply_transform(y, tr), tr), y, rtol=1e-12)
    # a response that is exactly quadratic on the transformed scale is fitted exactly
    x = box_behnken(3, 5)
    yt = 3 + 0.5 * x[:, 0] - 0.2 * x[:, 1] ** 2 + 0.1 * x[:, 0] * x[:, 2]
    if tr in ("inverse", "inverse_sqrt"):
        yt = yt / 10
    yy = inverse_transform(yt, tr)
    df = pd.DataFrame(x, columns=["A", "B", "C"])
    df["y"] = yy
    fit = fit_response_surface(df, ["A", "B", "C"], "y", [-1] * 3, [1] * 3, transform=tr)
    np.testing.assert_allclose(fit.fitted, yy, rtol=1e-9)
    np.testing.assert_allclose(fit.predict(x), yy, rtol=1e-9)
    assert fit.residuals == pytest.approx(np.zeros(17), abs=1e-9)


def test_transform_suggestion_ratio_rule():
    assert transform_suggestion([2.0, 30.0])["recommend"] == "sqrt"
    s = transform_suggestion([24.2, 33.1])  # cinnamon Table 6 range
    assert s["recommend"] == "none" and s["ratio"] == pytest.approx(33.1 / 24.2)


def test_boxcox_recovers_log_and_identity():
    rng = np.random.default_rng(11)
    x = rng.uniform(-1, 1, 60)
    X = np.column_stack([np.ones(60), x])
    y_log = np.exp(1.0 + 0.8 * x + rng.normal(0, 0.05, 60))
    r = boxcox(X, y_log)
    assert r["ci_low"] < 0.0 < r["ci_high"] and r["ci_high"] < 1.0
    assert r["recommended_transform"] == "ln"
    y_lin = 20 + 5 * x + rng.normal(0, 0.3, 60)
    assert boxcox(X, y_lin)["recommended_transform"] == "none"


@pytest.mark.parametrize("printed,value,ok,dec", [
    ("24.15", 24.1517, True, 2), ("24.15", 24.1551, False, 2), ("0.0002", 0.000163, True, 4),
    ("<0.0001", 6.8e-5, True, 4), ("<0.0001", 1.2e-4, False, 4), ("2.10", 2.0963, True, 2),
    ("\u22120.88", -0.875, True, 2), ("1.42", 1.425, True, 2), ("1.43", 1.425, True, 2),
    ("0.3515", 0.35179, False, 4), ("77.98%", 77.984, True, 2), ("16", 15.6, True, 0),
])
def test_compare_printed(printed, value, ok, dec):
    assert compare_printed(printed, value) == (ok, dec)


def test_bad_inputs_raise_input_error():
    df = _data()
    with pytest.raises(InputError, match="data"):
        fit_response_surface(df, FACTORS + ["E"], "y", LOW + [0], HIGH + [1])
    with pytest.raises(InputError, match="terms"):
        fit_response_surface(df, FACTORS, "y", LOW, HIGH, terms=["A", "Z^2"])
    with pytest.raises(InputError, match="transform"):
        fit_response_surface(df, FACTORS, "y", LOW, HIGH, transform="cube")
    with pytest.raises(InputError):
        compare_printed("n.s.", 1.0)


def test_the_standard_error_of_a_change_between_two_sets():
    # y = b0 + b1 A on A coded -1, 0, 1 (two runs each): b1 = (mean(+1) - mean(-1)) / 2, its
    # variance MSE / Sxx with Sxx = sum (A - 0)^2 = 4; the change from A = -0.5 to A = 0.5 is
    # b1, so its SE is sqrt(MSE / 4); MSE = SSE / (6 - 2)
    A = np.array([-1.0, -1.0, 0.0, 0.0, 1.0, 1.0])
    y = np.array([9.0, 11.0, 19.0, 21.0, 30.0, 32.0])
    fit = fit_response_surface(pd.DataFrame({"A": A, "y": y}), ["A"], "y", [-1.0], [1.0], terms=["A"])
    b1 = (31.0 - 10.0) / 2
    sse = float(((y - (y.mean() + b1 * A)) ** 2).sum())
    assert fit.change_se([-0.5], [0.5]) == pytest.approx(np.sqrt(sse / 4 / 4))
    # the intercept cancels: a change of zero length has no error; twice the move, twice the SE
    assert fit.change_se([0.3], [0.3]) == pytest.approx(0.0, abs=1e-12)
    assert fit.change_se([-1.0], [1.0]) == pytest.approx(2 * np.sqrt(sse / 4 / 4))
    # on a log scale (delta method): the change exp(eta2) - exp(eta1), eta = b0 + b1 A, has the
    # gradient exp(eta2) [1, A2] - exp(eta1) [1, A1] in (b0, b1)
    lf = fit_response_surface(pd.DataFrame({"A": A, "y": np.exp(y / 10)}), ["A"], "y", [-1.0], [1.0],
                              terms=["A"], transform="ln")
    e1, e2 = lf.predict([[-0.5]])[0], lf.predict([[0.5]])[0]
    a = np.array([e2 - e1, 0.5 * (e2 + e1)])
    assert lf.change_se([-0.5], [0.5]) == pytest.approx(float(np.sqrt(a @ np.asarray(lf.ols.cov_params()) @ a)),
                                                        rel=1e-5)


def test_prediction_of_a_known_quadratic_at_chosen_points():
    """A noise-free fit reproduces the polynomial TRUE, so its prediction at a point is the
    polynomial's value there, worked by hand from TRUE: 10 at the centre; the sum of all
    fifteen coefficients, 12.4, at (1, 1, 1, 1); 10 - 1.5 - 1.1 = 7.4 at A = -1;
    10 + 0.75 + 0.7 - 0.2 - 0.275 + 0.8 = 11.775 at (0.5, -1, 0, 0); 10 - 2 - 0.3 = 7.7 at
    D = -1.  One point at a time (as the optimisers call it) and the five as one batch, coded
    and actual levels alike; under a ln transform the prediction is exp of the polynomial."""
    pts = np.array([[0, 0, 0, 0], [1, 1, 1, 1], [-1, 0, 0, 0], [0.5, -1, 0, 0], [0, 0, 0, -1]], dtype=float)
    want = np.array([10.0, 12.4, 7.4, 11.775, 7.7])
    for transform, back in (("none", want), ("ln", np.exp(want))):
        df = _data()
        if transform == "ln":
            df["y"] = np.exp(df["y"])
        fit = fit_response_surface(df, FACTORS, "y", LOW, HIGH, transform=transform)
        np.testing.assert_allclose(fit.predict(pts), back, rtol=1e-10)
        np.testing.assert_allclose([fit.predict(p)[0] for p in pts], back, rtol=1e-10)
        np.testing.assert_allclose(fit.predict_actual(coded_to_actual(pts, LOW, HIGH)), back, rtol=1e-10)
        np.testing.assert_allclose(fit.predict_transformed(pts), want, rtol=1e-10)


def test_prediction_of_a_reduced_and_a_one_factor_model():
    """Terms kept in another order than the full quadratic's, and a single factor (its own
    path through the model matrix): y = 3 - 2 B + 0.5 A*B + 1.5 B^2 gives 3 - 2 - 0.5 + 1.5 = 2
    at (A, B) = (-1, 1) and 3 + 1 - 0.125 + 0.375 = 4.25 at (0.5, -0.5); y = 2 + 3 x - 0.5 x^2
    gives 3.12 at x = 0.4 and -1.5 at x = -1."""
    x = box_behnken(3, 3)[:, :2]
    a, b = x.T
    df = pd.DataFrame(x, columns=["A", "B"])
    df["y"] = 3 - 2 * b + 0.5 * a * b + 1.5 * b**2
    fit = fit_response_surface(df, ["A", "B"], "y", [0, 0], [1, 1], terms=["B^2", "A*B", "B"])
    pts = np.array([[-1.0, 1.0], [0.5, -0.5]])
    np.testing.assert_allclose(fit.predict(pts), [2.0, 4.25], rtol=1e-10)
    np.testing.assert_allclose([fit.predict(p)[0] for p in pts], [2.0, 4.25], rtol=1e-10)

    x1 = np.linspace(-1, 1, 7)
    df1 = pd.DataFrame({"x": x1, "y": 2 + 3 * x1 - 0.5 * x1**2})
    fit1 = fit_response_surface(df1, ["x"], "y", [0], [1])
    np.testing.assert_allclose(fit1.predict([[0.4], [-1.0]]), [3.12, -1.5], rtol=1e-10)
    np.testing.assert_allclose(fit1.predict([0.4]), [3.12], rtol=1e-10)
