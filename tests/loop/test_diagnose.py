"""Residual diagnosis (soilcal.loop.diagnose): hand-built residual tables with a known structure
(a linear trend, a tool difference, an offset, excess scatter, none at all) and the tests
that must or must not find it, with Holm-corrected p-values, the ranking and the matched
quantities."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from soilcal.loop.diagnose import DIAGNOSIS_COLUMNS, detectable, diagnose, holm_adjusted, matched_quantities, ranking

# Thue-Morse signs over x = 0..7: sum s x^k = 0 for k = 0, 1, 2 (Prouhet), so a residual
# proportional to them has no mean, no linear and no quadratic relation to x = 0..7
#   k=0: 1-1-1+1-1+1+1-1 = 0
#   k=1: 0-1-2+3-4+5+6-7 = 0
#   k=2: 0-1-4+9-16+25+36-49 = 0
TM = np.array([1, -1, -1, 1, -1, 1, 1, -1], float)
X = np.arange(8, dtype=float)


def _table(r, z=None, **covs):
    n = len(r)
    d = {"measurement": ["bin"] * n, "row": list(range(1, n + 1)), "measure": ["F_N"] * n,
         "relative_residual": list(r), "standardised_residual": list(np.ones(n) if z is None else z)}
    for k, v in covs.items():
        d[f"cov:{k}"] = list(v)
    return pd.DataFrame(d)


def _row(diag, test, covariate=""):
    sel = diag[(diag["test"] == test) & (diag["covariate"] == covariate)]
    assert len(sel) == 1, (test, covariate, diag)
    return sel.iloc[0]


def _holm(p):
    """Holm step-down by hand: sort ascending, (m - i) p_(i) cumulative max, capped at 1."""
    p = np.asarray(p, float)
    m = len(p)
    order = np.argsort(p)
    adj = np.empty(m)
    run = 0.0
    for i, j in enumerate(order):
        run = max(run, min(1.0, (m - i) * p[j]))
        adj[j] = run
    return adj


def _trend_table():
    # r = 0.1 (x - 3.5) + 0.002 (-1)^x; the noise's own slope on x is
    # 0.002 sum (-1)^x (x - 3.5) / sum (x - 3.5)^2 = 0.002 * (-4) / 42 = -1.9e-4 (0.2 % of 0.1)
    noise = 0.002 * (-1.0) ** X
    r = 0.1 * (X - X.mean()) + noise
    # tool by the Thue-Morse pattern: A at x = 0, 3, 5, 6 and B at 1, 2, 4, 7, both summing to 14,
    # and (-1)^x sums to 0 in each group: no group difference at all
    tool = np.where(TM > 0, "A", "B")
    return _table(r, speed=X, tool=tool)


def test_linear_trend_is_found():
    diag = diagnose(_trend_table(), quantity_of={"speed": "tool_speed"})
    assert list(diag.columns) == DIAGNOSIS_COLUMNS
    t = _row(diag, "trend", "speed")
    assert t["significant"]
    assert t["estimate"] == pytest.approx(0.1, rel=0.05)  # per unit of x
    assert t["r2"] > 0.99
    assert t["quantity"] == "tool_speed"
    assert (t["n"], t["levels"]) == (8, 8)
    assert not _row(diag, "group", "tool")["significant"]
    assert _row(diag, "group", "tool")["statistic"] == pytest.approx(0.0, abs=1e-9)
    assert not _row(diag, "bias")["significant"]


def test_no_structure_no_significant_test():
    # r = +-0.01 in the Thue-Morse pattern: zero mean, zero correlation with x and x^2, and
    # the tool groups (x = 0..3 and 4..7: +--+ and -++-) both have mean 0
    r = 0.01 * TM
    tool = ["A"] * 4 + ["B"] * 4
    diag = diagnose(_table(r, z=TM, speed=X, tool=tool))
    assert set(diag["test"]) == {"bias", "scatter", "trend", "curvature", "group"}
    assert not diag["significant"].any(), diag
    assert _row(diag, "trend", "speed")["estimate"] == pytest.approx(0.0, abs=1e-12)
    assert _row(diag, "curvature", "speed")["estimate"] == pytest.approx(0.0, abs=1e-12)
    assert _row(diag, "bias")["estimate"] == pytest.approx(0.0, abs=1e-15)
    # z = +-1: chi-square 8 on 8 degrees of freedom
    sc = _row(diag, "scatter")
    assert sc["statistic"] == pytest.approx(8.0)
    assert sc["p"] == pytest.approx(stats.chi2.sf(8.0, 8))


def test_group_difference_is_found():
    spread = np.array([0.01, -0.01, 0.02, -0.02])
    r = np.concatenate([0.1 + spread, -0.1 + spread])
    tool = ["A"] * 4 + ["B"] * 4
    diag = diagnose(_table(r, tool=tool), quantity_of={"tool": "tool"})
    g = _row(diag, "group", "tool")
    assert g["significant"] and g["quantity"] == "tool" and g["levels"] == 2
    # grand mean 0; between SS = 8 * 0.1^2 = 0.08; within SS = 2 (1e-4 + 1e-4 + 4e-4 + 4e-4) = 0.002
    # F = (0.08 / 1) / (0.002 / 6) = 240 on (1, 6); r2 = 0.08 / 0.082; estimate sqrt(0.08 / 8) = 0.1
    assert g["statistic"] == pytest.approx(240.0)
    assert g["p"] == pytest.approx(stats.f.sf(240.0, 1, 6))
    assert g["r2"] == pytest.approx(0.08 / 0.082)
    assert g["estimate"] == pytest.approx(0.1)
    assert not _row(diag, "bias")["significant"]


def test_constant_offset_is_a_bias():
    r = 0.05 + 0.001 * TM
    diag = diagnose(_table(r, speed=X))
    b = _row(diag, "bias")
    assert b["significant"] and b["quantity"] == "bias"
    assert b["estimate"] == pytest.approx(0.05)
    # t = mean / (sd / sqrt(n)); sd (ddof 1) = 0.001 sqrt(8 / 7)
    t = 0.05 / (0.001 * np.sqrt(8 / 7) / np.sqrt(8))
    assert b["statistic"] == pytest.approx(t)
    # share of the sum of squares about zero: 0.05^2 / (0.05^2 + 0.001^2)
    assert b["r2"] == pytest.approx(0.0025 / (0.0025 + 1e-6))
    assert not _row(diag, "trend", "speed")["significant"]
    assert matched_quantities(diag) == {"bias"}


def test_scatter_beyond_the_uncertainty():
    n = 8
    z = 3.0 * TM
    diag = diagnose(_table(0.01 * TM, z=z))
    sc = _row(diag, "scatter")
    assert sc["statistic"] == pytest.approx(9.0 * n)  # sum z^2 = 8 * 9
    assert sc["p"] == pytest.approx(stats.chi2.sf(9.0 * n, n))
    assert sc["estimate"] == pytest.approx(3.0)
    assert sc["significant"]
    assert not _row(diag, "bias")["significant"]


def test_scatter_skips_rows_without_uncertainty():
    z = np.array([3.0, -3.0, 3.0, np.nan, np.nan])
    diag = diagnose(_table([0.01, -0.01, 0.01, -0.01, 0.0], z=z))
    sc = _row(diag, "scatter")
    assert sc["n"] == 3 and sc["statistic"] == pytest.approx(27.0)


@pytest.mark.parametrize("make", [
    _trend_table,
    lambda: _table(0.01 * TM, z=3 * TM, speed=X, tool=["A"] * 4 + ["B"] * 4),
    lambda: _table(0.05 + 0.001 * TM, speed=X),
])
def test_holm_adjusted_p(make):
    diag = diagnose(make())
    assert len(diag) >= 3
    assert (diag["p_adjusted"] >= diag["p"] - 1e-15).all()
    assert diag["p_adjusted"].to_numpy() == pytest.approx(_holm(diag["p"]))
    assert (diag["significant"] == (diag["p_adjusted"] < 0.05)).all()


def test_holm_by_hand_with_ties_and_the_cap():
    # m = 5, sorted 0.005, 0.01, 0.01, 0.04, 0.3: 5 x 0.005 = 0.025, 4 x 0.01 = 0.04,
    # 3 x 0.01 = 0.03 -> 0.04 (non-decreasing), 2 x 0.04 = 0.08, 1 x 0.3 = 0.3
    assert holm_adjusted([0.01, 0.04, 0.3, 0.005, 0.01]) == pytest.approx([0.04, 0.08, 0.3, 0.025, 0.04])
    assert holm_adjusted([0.7, 0.6]) == pytest.approx([1.0, 1.0])  # 2 x 0.6 = 1.2 capped at 1, 0.7 below it
    assert holm_adjusted([]).shape == (0,)


def test_the_correction_runs_no_garbage_collection(monkeypatch):
    # statsmodels' Holm collects garbage on every call: 0.1-0.3 s per diagnosis in a process
    # holding many objects (most of the time of a Monte Carlo run of the diagnosis)
    import gc

    def collect(*a):
        raise AssertionError("gc.collect called")

    diag = diagnose(_trend_table())
    monkeypatch.setattr(gc, "collect", collect)
    again = diagnose(_trend_table())
    assert again["p_adjusted"].to_numpy() == pytest.approx(diag["p_adjusted"].to_numpy())


def test_rows_without_a_residual_are_left_out():
    t = _trend_table()
    extra = t.iloc[:2].assign(relative_residual=np.nan, row=[9, 10])
    diag = diagnose(pd.concat([t, extra], ignore_index=True))
    assert (diag["n"] == 8).all()


def test_ranking_puts_the_significant_covariate_first():
    diag = diagnose(_trend_table(), quantity_of={"speed": "tool_speed"})
    rk = ranking(diag)
    assert rk.iloc[0]["covariate"] == "speed"
    assert rk.iloc[0]["significant"] and rk.iloc[0]["quantity"] == "tool_speed"
    assert not rk.set_index("covariate").loc["tool", "significant"]
    assert set(rk["covariate"]) >= {"speed", "tool", "bias"}


def test_matched_quantities():
    diag = diagnose(_trend_table(), quantity_of={"speed": "tool_speed", "tool": "tool"})
    assert matched_quantities(diag) == {"tool_speed"}
    # the same significant trend without a declared quantity matches nothing
    assert matched_quantities(diagnose(_trend_table())) == set()


def test_too_few_rows():
    diag = diagnose(_table([0.1]))
    assert len(diag) == 0
    assert len(ranking(diag)) == 0
    assert matched_quantities(diag) == set()


def test_residual_degrees_of_freedom_are_welch_satterthwaite():
    from soilcal.loop.residuals import residual_frame

    obs = pd.DataFrame([dict(measurement="m", row=1, measure="F_N", unit="N", label="a", measured=100.0,
                             measured_sd=2.0, measured_n=3),
                        dict(measurement="m", row=2, measure="F_N", unit="N", label="b", measured=100.0,
                             measured_sd=2.0, measured_n=float("nan"))])
    runs = pd.DataFrame([dict(measurement="m", row=r, measure="F_N", seed=s, value=v, status="ok")
                         for r in (1, 2) for s, v in enumerate((97.0, 100.0, 103.0))])  # seed SD 3
    res = residual_frame(obs, runs)
    # var_m = 4/3, var_s = 9/3 = 3: nu = (13/3)^2 / ((4/3)^2 / 2 + 3^2 / 2) = 18.778 / 5.3889
    assert res["residual_dof"].iloc[0] == pytest.approx((13 / 3) ** 2 / ((4 / 3) ** 2 / 2 + 9 / 2), rel=1e-12)
    # a measured SD without a repeat count is taken as known: only the seeds' term, nu = (4 + 3)^2 / (9 / 2)
    assert res["residual_dof"].iloc[1] == pytest.approx(49 / 4.5, rel=1e-12)


def test_t_residuals_mapped_to_normal_deviates_hold_the_chi_square_level():
    """Standardised residuals that are Student t on 2-4 degrees of freedom (SDs from three
    repeats and three seeds): their normal deviates make the 12-row chi-square scatter
    statistic reject at its nominal 5 %; read as unit normal, the t values reject far more
    often (heavy tails)."""
    from soilcal.loop.diagnose import normal_equivalent

    rng = np.random.default_rng(11)
    dof = rng.uniform(2.0, 4.0, (4000, 12))
    t = rng.standard_t(dof)
    u = normal_equivalent(t.ravel(), dof.ravel()).reshape(t.shape)
    assert np.all(np.sign(u) == np.sign(t)) and np.all(np.abs(u) <= np.abs(t))
    p_t = stats.chi2.sf((u ** 2).sum(axis=1), 12)
    p_normal = stats.chi2.sf((t ** 2).sum(axis=1), 12)
    assert 0.04 < np.mean(p_t < 0.05) < 0.06  # binomial SD 0.0034 over 4000 tables
    assert np.mean(p_normal < 0.05) > 0.25


def test_the_scatter_test_reads_each_row_on_its_degrees_of_freedom():
    """The scatter row of a residual table is the chi-square of the rows' normal deviates
    with the tail probabilities of t on each row's residual_dof (infinite: the value itself)."""
    z = np.array([2.5, -1.0, 0.3, 3.0])
    dof = np.array([3.0, 3.0, np.inf, 2.0])
    res = pd.DataFrame({"measurement": "m", "row": [1, 2, 3, 4], "measure": "F_N", "relative_residual": 0.01 * z,
                        "standardised_residual": z, "residual_dof": dof, "measured_sd": 1.0})
    d = diagnose(res)
    u = np.where(np.isfinite(dof), stats.norm.isf(stats.t.sf(np.abs(z), np.where(np.isfinite(dof), dof, 1.0))),
                 np.abs(z))
    chi = float(np.sum(u ** 2))
    row = d[d["test"] == "scatter"].iloc[0]
    assert row["statistic"] == pytest.approx(chi, rel=1e-12)
    assert row["p"] == pytest.approx(stats.chi2.sf(chi, 4), rel=1e-10)


def _nested_f_p(r, small, big):
    """p of the nested F-test by hand: ((SSE_s - SSE_b) / (k_b - k_s)) / (SSE_b / (n - k_b))."""
    def sse(X):
        coef, *_ = np.linalg.lstsq(X, r, rcond=None)
        return float(np.sum((r - X @ coef) ** 2))
    n, kb, ks = len(r), big.shape[1], small.shape[1]
    f = ((sse(small) - sse(big)) / (kb - ks)) / (sse(big) / (n - kb))
    return float(stats.f.sf(f, kb - ks, n - kb))


def _confounded_table():
    # 16 conditions, speed x = 0..15 run in day blocks of four (the first day the slowest):
    # the residual follows speed alone, r = 0.05 (x - 7.5) + 0.01 t(x), t the Thue-Morse signs
    # over 16 points (orthogonal to 1, x, x^2 and x^3 by Prouhet), so both the speed trend and
    # the day grouping are significant, and the day adds nothing once speed is fitted
    x = np.arange(16, dtype=float)
    t = np.array([1 - 2 * (bin(i).count("1") % 2) for i in range(16)], float)
    r = 0.05 * (x - 7.5) + 0.01 * t
    day = np.array([f"d{i // 4}" for i in range(16)])
    return _table(r, speed=x, day=day), x, day, r


def test_beyond_is_the_nested_f_test_of_the_second_covariates_terms():
    from soilcal.loop.diagnose import beyond

    d, x, day, r = _confounded_table()
    q = {"day": "day"}
    xs = (x - x.mean()) / x.std()
    one = np.ones((16, 1))
    dummies = np.column_stack([(day == lv).astype(float) for lv in ("d1", "d2", "d3")])
    quad = np.column_stack([xs, xs ** 2])
    # day beyond speed (x and x^2): three day terms added to 1, x, x^2
    p_day = beyond(d, "day", "speed", q)
    assert p_day == pytest.approx(_nested_f_p(r, np.column_stack([one, quad]), np.column_stack([one, quad, dummies])),
                                  rel=1e-9)
    # speed beyond day: x and x^2 added to the day indicators
    p_speed = beyond(d, "speed", "day", q)
    assert p_speed == pytest.approx(_nested_f_p(r, np.column_stack([one, dummies]),
                                                np.column_stack([one, dummies, quad])), rel=1e-9)
    assert p_day > 0.05 and p_speed < 1e-6
    assert np.isnan(beyond(d, "bias", "speed", q)) and np.isnan(beyond(d, "nothing", "speed", q))


def test_a_covariate_sharing_the_first_ones_structure_is_named_shared():
    from soilcal.loop.core import _follows

    d, *_ = _confounded_table()
    q = {"day": "day"}
    diag = diagnose(d, q)
    assert _row(diag, "trend", "speed")["significant"] and _row(diag, "group", "day")["significant"]
    text = _follows(ranking(diag), d, q)
    assert text.startswith("speed (r2 ")
    assert "; also day (r2 " in text and "beyond speed: p" in text and text.endswith(", shared)")
    assert _follows(ranking(diag)).count("beyond") == 0  # without the residual table: the list alone


def test_beyond_a_covariate_with_one_level_on_the_shared_rows_is_nan():
    from soilcal.loop.core import _follows
    from soilcal.loop.diagnose import beyond

    d, *_ = _confounded_table()
    d["cov:speed"] = d["cov:speed"].where(d["cov:day"] == "d0")  # speed recorded on the first day only
    # on the four rows with a speed the day has one level: speed's structure is its own there
    # (the residual is linear in speed), and the day has none beyond speed
    assert beyond(d, "speed", "day", {"day": "day"}) < 0.05
    assert np.isnan(beyond(d, "day", "speed", {"day": "day"}))
    d["cov:other"] = np.where(d["cov:day"] == "d0", np.nan, 1.0)  # never beside speed
    assert np.isnan(beyond(d, "other", "speed", {"day": "day"}))
    diag = diagnose(d, {"day": "day"})
    text = _follows(ranking(diag), d, {"day": "day"})  # no p beyond speed where it cannot be told
    assert text.startswith("speed (r2 ") and "; also day (r2 " in text and "beyond" not in text


# What the diagnosis can detect: the reported smallest bias and trend, put back into the data
# with fresh noise of the stated scatter, must be found at about the stated power (0.8); a
# binomial count over 400 draws at p = 0.8 leaves 0.74-0.86 with probability 0.998.  For the
# trend, Holm's later steps make the test a little more powerful than the alpha / tests bound
# it is computed at, hence the upper limit 0.9 there.


def _power_table(r, **covs):
    return _table(r, **covs).assign(standardised_residual=np.nan, measured=100.0, simulated_sd=6.0, simulated_n=3,
                                    measured_sd=np.nan, measured_n=np.nan)  # no SD measured: no scatter test


def test_a_trend_of_the_detectable_size_is_found_at_the_stated_power():
    sigma = 0.05
    # sigma sqrt(6/8) TM: orthogonal to 1 and x, so its standard error about the line is sigma
    base = _power_table(sigma * np.sqrt(6 / 8) * TM, speed=X)
    diag = diagnose(base)
    assert list(diag["test"]) == ["bias", "trend", "curvature"]
    det = detectable(base, diag)
    row = det[det["test"] == "trend"].iloc[0]
    assert (row["low"], row["high"], row["tests"], row["n"]) == (0.0, 7.0, 3, 8)
    assert row["scatter_percent"] == pytest.approx(5.0)
    assert row["seed_se_percent"] == pytest.approx(6.0 / np.sqrt(3))  # 6 / sqrt(3) of 100, in %
    assert np.isnan(row["measured_se_percent"])
    slope = row["detectable_percent"] / 100 / 7.0
    rng = np.random.default_rng(11)
    found = sum(bool(_row(diagnose(_power_table(slope * (X - X.mean()) + sigma * rng.standard_normal(8), speed=X)),
                          "trend", "speed")["significant"]) for _ in range(400))
    assert 0.74 <= found / 400 <= 0.9, found


def test_a_bias_of_the_detectable_size_is_found_at_the_stated_power():
    sigma = 0.05
    base = _power_table(sigma * np.sqrt(7 / 8) * TM)  # mean 0, SD sigma
    diag = diagnose(base)
    assert list(diag["test"]) == ["bias"]
    row = detectable(base, diag).iloc[0]
    assert row["scatter_percent"] == pytest.approx(5.0)
    b = row["detectable_percent"] / 100
    rng = np.random.default_rng(12)
    found = sum(bool(_row(diagnose(_power_table(b + sigma * rng.standard_normal(8))), "bias")["significant"])
                for _ in range(400))
    assert 0.74 <= found / 400 <= 0.86, found


def test_the_smallest_shift_tends_to_the_normal_sum_of_quantiles():
    from soilcal.loop.diagnose import _smallest_shift

    # a two-sided z-test at level 0.05 has power 0.8 at a shift of z_0.975 + z_0.8 = 2.8016
    # (the opposite tail adds 3e-6)
    assert _smallest_shift(10 ** 6, stats.norm.isf(0.025), 0.8) == pytest.approx(
        stats.norm.isf(0.025) + stats.norm.isf(0.2), abs=1e-4)


def test_nothing_detectable_without_tests():
    assert len(detectable(_power_table([0.1, -0.1]), diagnose(_power_table([0.1, -0.1])).iloc[0:0])) == 0


def test_a_table_without_standardised_residuals_has_no_scatter_test():
    t = _table([0.1, 0.2, -0.1, 0.0, 0.05]).drop(columns="standardised_residual").assign(measured_sd=1.0)
    assert list(diagnose(t)["test"]) == ["bias"]


def test_the_quantities_of_one_measured_test_count_once_in_the_bias_and_trend_tests():
    # eight soil-bin tests at speeds 1..8, each measuring the horizontal and the vertical force;
    # a disturbance of the test (a stone, a ridge) moves both forces alike: relative residuals
    # r_i + e_i and r_i - e_i.  The trend over the tests is the regression of their means r_i
    # on eight points (scipy's linregress), not on sixteen independent rows, which would have
    # cut its p by three quarters (here 0.21 against 0.052)
    from scipy import stats

    x = np.arange(1.0, 9.0)
    r = np.array([0.0, -0.03, 0.05, 0.0, 0.06, 0.01, 0.08, 0.02])
    e = np.array([0.01, -0.005, 0.0, 0.004, -0.01, 0.002, 0.0, 0.006])
    rows = []
    for i in range(8):
        for m, sign in (("horizontal_force_N", 1), ("vertical_force_N", -1)):
            rows.append({"measurement": "bin", "row": i + 1, "measure": m, "relative_residual": r[i] + sign * e[i],
                         "standardised_residual": np.nan, "cov:speed": x[i]})
    diag = diagnose(pd.DataFrame(rows), {"speed": "tool_speed"})
    trend = diag[diag["test"] == "trend"].iloc[0]
    assert trend["n"] == 8
    assert trend["p"] == pytest.approx(stats.linregress(x, r).pvalue, rel=1e-9)
    bias = diag[diag["test"] == "bias"].iloc[0]
    assert bias["n"] == 8 and bias["p"] == pytest.approx(stats.ttest_1samp(r, 0.0).pvalue, rel=1e-9)
    # the two forces are still compared with each other over all sixteen rows
    assert diag[(diag["test"] == "group") & (diag["covariate"] == "measure")]["n"].iloc[0] == 16


def test_a_periodic_disturbance_along_the_bin_is_found_with_its_wavelength():
    # sixteen tests at positions drawn along a 40 m bin; a ridge pattern of wavelength 8 m raises
    # and lowers the residual by 10 % (plus 0.5 % noise): neither a trend nor a curvature in the
    # position follows it, a sine of the position does
    rng = np.random.default_rng(5)
    x = np.sort(rng.uniform(0.0, 40.0, 16))
    r = 0.1 * np.sin(2 * np.pi * x / 8.0 + 0.4) + rng.normal(0.0, 0.005, 16)
    res = pd.DataFrame({"measurement": "bin", "row": np.arange(1, 17), "measure": "F_N", "relative_residual": r,
                        "standardised_residual": np.nan, "cov:position_m": x})
    diag = diagnose(res, {"position_m": "position"})
    per = diag[diag["test"] == "periodic"].iloc[0]
    assert bool(per["significant"]) and per["r2"] > 0.95
    # the scan's frequency step near 1/8 per m is 3.6 % of it
    assert per["estimate"] == pytest.approx(8.0, rel=0.04)
    assert not diag[diag["test"].isin(["trend", "curvature"])]["significant"].any()
    assert ranking(diag).iloc[0]["covariate"] == "position_m"


def test_beyond_the_measured_quantity_takes_every_row():
    # two forces per test, both following the speed (+2 % per m/s from 1 m/s), the horizontal
    # one 10 % above the vertical throughout: the force explains the residual beyond the speed
    # (a nested F-test over all 16 rows), though one value per test would leave it one level
    import pandas as pd
    from soilcal.loop import diagnose as dg

    rng = np.random.default_rng(4)
    rows = []
    for i, v in enumerate(np.linspace(1.0, 4.5, 8)):
        for m, offset in (("horizontal_force_N", 0.10), ("vertical_force_N", 0.0)):
            rows.append({"measurement": "t", "row": i, "measure": m, "cov:tool_speed": v,
                         "relative_residual": offset + 0.02 * (v - 1.0) + 0.002 * rng.standard_normal()})
    res = pd.DataFrame(rows)
    p = dg.beyond(res, "measure", "tool_speed")
    assert np.isfinite(p) and p < 1e-6, p
    assert dg.beyond(res, "tool_speed", "measure") < 1e-6


def test_scatter_alone_points_to_the_test_most_sure_of_a_structure():
    # the scatter test alone is significant; a group test of many levels explains the larger
    # share (r2 0.6 at p 0.2: the share noise gives so many parameters) and a speed trend the
    # smaller one at p 0.01: the candidates are sought through the speed
    import pandas as pd
    from soilcal.loop import diagnose as dg

    diag = pd.DataFrame([
        {"test": "scatter", "covariate": "", "quantity": "", "r2": 0.0, "p": 1e-6, "p_adjusted": 1e-6,
         "significant": True},
        {"test": "group", "covariate": "tool", "quantity": "tool_id", "r2": 0.6, "p": 0.2, "p_adjusted": 0.6,
         "significant": False},
        {"test": "trend", "covariate": "tool_speed", "quantity": "speed", "r2": 0.5, "p": 0.01, "p_adjusted": 0.06,
         "significant": False},
    ])
    assert dg.matched_quantities(diag) == {"speed"}


# --- the quantities of one measured test combined by their uncertainty (per_test) ---

QUIET, NOISY = "horizontal_force_N", "vertical_force_N"


def _two_force_table(r, sd_m, n_m, sd_s, n_s, scale):
    """A residual table of len(r[QUIET]) soil-bin tests measuring two forces: per quantity the
    relative residuals, measured and seed SDs (absolute, N), their counts and the scale (N)."""
    rows = []
    for i in range(len(r[QUIET])):
        for q in (QUIET, NOISY):
            rows.append({"measurement": "bin", "row": i + 1, "measure": q, "simulation": f"s{i}",
                         "measured": scale[q] * (1.0 + r[q][i]), "measured_sd": sd_m[q][i], "measured_n": n_m[q][i],
                         "simulated_sd": sd_s[q][i], "simulated_n": n_s[q][i], "scale": scale[q],
                         "relative_residual": r[q][i], "standardised_residual": np.nan, "cov:speed_m_s": 0.1 * (i + 1)})
    return pd.DataFrame(rows)


def test_a_tests_quantities_are_combined_by_their_inverse_variance():
    # four tests of two forces, scales 100 N and 20 N, three repeats and three seeds; each
    # quantity's relative SDs differ from row to row, so its weight comes from their pooled
    # value, sum((n - 1)(sd / scale)^2) / sum(n - 1), here the mean of (sd / scale)^2 (equal n)
    from soilcal.loop.diagnose import per_test

    scale = {QUIET: 100.0, NOISY: 20.0}
    rel_m = {QUIET: np.array([0.04, 0.06, 0.05, 0.05]), NOISY: np.array([0.30, 0.20, 0.25, 0.25])}
    rel_s = {QUIET: np.array([0.03, 0.05, 0.04, 0.04]), NOISY: np.array([0.40, 0.30, 0.35, 0.35])}
    r = {QUIET: np.array([-0.10, 0.02, 0.05, -0.01]), NOISY: np.array([0.40, -0.30, 0.10, 0.25])}
    three = {q: np.full(4, 3.0) for q in (QUIET, NOISY)}
    t = _two_force_table(r, {q: rel_m[q] * scale[q] for q in r}, three, {q: rel_s[q] * scale[q] for q in r},
                         three, scale)
    # by hand: v = (pooled (sd_m / scale)^2 / 3 + pooled (sd_s / scale)^2 / 3)
    v = {q: (np.mean(rel_m[q] ** 2) + np.mean(rel_s[q] ** 2)) / 3.0 for q in (QUIET, NOISY)}
    # horizontal: (0.0016 + 0.0036 + 0.0025 + 0.0025) / 4 = 0.00255 and (0.0009 + 0.0025 + 0.0016 + 0.0016) / 4
    # = 0.00165, so v = 0.0042 / 3 = 0.0014
    assert v[QUIET] == pytest.approx(0.0014, rel=1e-12)
    want = (r[QUIET] / v[QUIET] + r[NOISY] / v[NOISY]) / (1.0 / v[QUIET] + 1.0 / v[NOISY])
    got = per_test(t)
    assert len(got) == 4
    np.testing.assert_allclose(got["relative_residual"].to_numpy(float), want, rtol=1e-12)
    # the bias test takes those values: its estimate is their mean, its p their t-test's
    bias = _row(diagnose(t), "bias")
    assert bias["n"] == 4 and bias["estimate"] == pytest.approx(want.mean(), rel=1e-12)
    assert bias["p"] == pytest.approx(stats.ttest_1samp(want, 0.0).pvalue, rel=1e-9)
    # a row whose simulated mean rests on one seed (no seed SD of its own) takes its quantity's
    # pooled seed variance over that one seed
    sd_s, n_s = {q: rel_s[q] * scale[q] for q in r}, {q: three[q].copy() for q in r}
    sd_s[NOISY][3], n_s[NOISY][3] = np.nan, 1.0
    t1 = _two_force_table(r, {q: rel_m[q] * scale[q] for q in r}, three, sd_s, n_s, scale)
    cv_s = np.mean(rel_s[NOISY][:3] ** 2)
    v_noisy = np.mean(rel_m[NOISY] ** 2) / 3.0 + cv_s / 1.0
    v_quiet = v[QUIET]
    want3 = (r[QUIET][3] / v_quiet + r[NOISY][3] / v_noisy) / (1.0 / v_quiet + 1.0 / v_noisy)
    assert per_test(t1)["relative_residual"].iloc[3] == pytest.approx(want3, rel=1e-12)


def test_the_weighted_combination_reaches_the_least_variance_a_common_shift_allows():
    # 400 tables of 12 tests: both forces read 5 % above the model (a common relative shift);
    # the horizontal force's repeats and seeds scatter by 5 % and 7 % of it, the vertical
    # force's by 20 % and 30 %, three of each per test, every table drawing its own repeats and
    # seeds (so each row's SDs are estimated, and the weights from their pooled values).  The
    # mean of a table's combined values estimates the shift; its SD over the tables is, for
    # the inverse-variance weights, sqrt(v_min / 12) with v_min = 1 / (1 / v_h + 1 / v_v), and
    # for equal weights sqrt((v_h + v_v) / 4 / 12), 2.2 times as large
    from soilcal.loop.diagnose import per_test

    rng = np.random.default_rng(20261201)
    k, tables, shift = 12, 400, 0.05
    scale = {QUIET: 100.0, NOISY: 20.0}
    sig_m, sig_s = {QUIET: 0.05, NOISY: 0.20}, {QUIET: 0.07, NOISY: 0.30}
    v = {q: (sig_m[q] ** 2 + sig_s[q] ** 2) / 3.0 for q in (QUIET, NOISY)}
    v_min = 1.0 / (1.0 / v[QUIET] + 1.0 / v[NOISY])
    weighted, equal = [], []
    for _ in range(tables):
        r, sd_m, sd_s = {}, {}, {}
        for q in (QUIET, NOISY):
            rep = scale[q] * (1.0 + shift + sig_m[q] * rng.standard_normal((k, 3)))  # measured repeats
            seeds = scale[q] * (1.0 + sig_s[q] * rng.standard_normal((k, 3)))  # simulated seeds
            r[q] = (rep.mean(axis=1) - seeds.mean(axis=1)) / scale[q]
            sd_m[q], sd_s[q] = rep.std(axis=1, ddof=1), seeds.std(axis=1, ddof=1)
        three = {q: np.full(k, 3.0) for q in (QUIET, NOISY)}
        weighted.append(per_test(_two_force_table(r, sd_m, three, sd_s, three, scale))["relative_residual"].mean())
        equal.append(np.mean((r[QUIET] + r[NOISY]) / 2.0))
    sd_w, sd_e = np.std(weighted, ddof=1), np.std(equal, ddof=1)
    sd_min = np.sqrt(v_min / k)
    # the relative standard error of an SD from 400 normal values: 1 / sqrt(2 * 399) = 0.035
    se = 1.0 / np.sqrt(2.0 * (tables - 1))
    assert abs(sd_w / sd_min - 1.0) < 3.0 * se, (sd_w, sd_min)
    assert abs(sd_e / np.sqrt((v[QUIET] + v[NOISY]) / 4.0 / k) - 1.0) < 3.0 * se
    assert sd_w < sd_e / 1.8
    assert np.mean(weighted) == pytest.approx(shift, abs=3.0 * sd_min / np.sqrt(tables))


def test_equal_variances_give_the_plain_mean():
    # both forces scatter by the same share of their scale: the weights are equal and the
    # combined value is the plain mean of the two relative residuals (the rule before weights)
    from soilcal.loop.diagnose import per_test

    scale = {QUIET: 100.0, NOISY: 20.0}
    r = {QUIET: np.array([0.10, -0.05, 0.02]), NOISY: np.array([-0.30, 0.15, 0.07])}
    rel = np.array([0.05, 0.08, 0.06])
    sd = {q: rel * scale[q] for q in r}
    three = {q: np.full(3, 3.0) for q in r}
    got = per_test(_two_force_table(r, sd, three, sd, three, scale))["relative_residual"].to_numpy(float)
    np.testing.assert_allclose(got, (r[QUIET] + r[NOISY]) / 2.0, rtol=1e-12)


def test_unknown_variances_fall_back_to_equal_weights():
    # no measured SD and one seed for the vertical force throughout: its variance is unknown
    # (the residual table gives it no standard error), so every test takes the plain mean,
    # though the horizontal force's variance is known; and so does a table with neither force's
    from soilcal.loop.diagnose import per_test

    scale = {QUIET: 100.0, NOISY: 20.0}
    r = {QUIET: np.array([0.10, -0.05, 0.02]), NOISY: np.array([-0.30, 0.15, 0.07])}
    plain = (r[QUIET] + r[NOISY]) / 2.0
    sd_m = {QUIET: np.full(3, 5.0), NOISY: np.full(3, np.nan)}
    sd_s = {QUIET: np.full(3, 4.0), NOISY: np.full(3, np.nan)}
    n_m = {QUIET: np.full(3, 3.0), NOISY: np.full(3, np.nan)}
    n_s = {QUIET: np.full(3, 3.0), NOISY: np.full(3, 1.0)}
    got = per_test(_two_force_table(r, sd_m, n_m, sd_s, n_s, scale))["relative_residual"].to_numpy(float)
    np.testing.assert_allclose(got, plain, rtol=1e-12)
    none = {q: np.full(3, np.nan) for q in r}
    one = {q: np.full(3, 1.0) for q in r}
    got = per_test(_two_force_table(r, none, none, none, one, scale))["relative_residual"].to_numpy(float)
    np.testing.assert_allclose(got, plain, rtol=1e-12)


def test_a_quantity_without_a_measured_sd_takes_no_weight_from_its_seeds_alone():
    # horizontal force measured with a 10 % SD over three repeats and simulated with a 3 % seed
    # SD over three seeds; the vertical force has no measured SD on any row and a 5 % seed SD
    # over three seeds.  Weighted by what is known, v_h = 0.1^2 / 3 + 0.03^2 / 3 = 0.003633 and
    # v_v = 0.05^2 / 3 = 0.000833, the vertical force would take 0.81 of the weight on its seed
    # scatter alone, which understates its variance; the parts differ, so the plain mean
    from soilcal.loop.diagnose import per_test
    from soilcal.loop.residuals import relative_variances

    scale = {QUIET: 100.0, NOISY: 20.0}
    r = {QUIET: np.array([0.10, -0.05, 0.02]), NOISY: np.array([-0.30, 0.15, 0.07])}
    sd_m = {QUIET: np.full(3, 10.0), NOISY: np.full(3, np.nan)}
    sd_s = {QUIET: np.full(3, 3.0), NOISY: np.full(3, 1.0)}
    n_m = {QUIET: np.full(3, 3.0), NOISY: np.full(3, np.nan)}
    three = {q: np.full(3, 3.0) for q in r}
    t = _two_force_table(r, sd_m, n_m, sd_s, three, scale)
    v = relative_variances(t)
    # the variances themselves are those of the residual's standard error (the known parts)
    np.testing.assert_allclose(v[t["measure"] == QUIET], (0.01 + 0.0009) / 3.0, rtol=1e-12)
    np.testing.assert_allclose(v[t["measure"] == NOISY], 0.0025 / 3.0, rtol=1e-12)
    got = per_test(t)["relative_residual"].to_numpy(float)
    np.testing.assert_allclose(got, (r[QUIET] + r[NOISY]) / 2.0, rtol=1e-12)


# --- the pooled relative variances behind the weights (relative_variances) ---

def _one_quantity(rows):
    """A residual table of one measured quantity (scale 100 N) from (simulation, measured value,
    relative measured SD, n_m, relative seed SD, n_s) per row."""
    return pd.DataFrame([{"measurement": "bin", "row": i + 1, "measure": QUIET, "simulation": sim,
                          "measured": m, "measured_sd": 100.0 * rm, "measured_n": nm,
                          "simulated_sd": 100.0 * rs, "simulated_n": ns, "scale": 100.0,
                          "relative_residual": m / 100.0 - 1.0}
                         for i, (sim, m, rm, nm, rs, ns) in enumerate(rows)])


def test_the_weights_pool_a_quantitys_relative_variances_however_unequal():
    # relative measured SDs 0.02, 0.02, 0.20, 0.20 from ten repeats each, no seed SD: Bartlett's
    # test would reject one relative variance (a ratio of 100 on 9 and 9 degrees of freedom)
    # and leave each row its own, but the weights pool them all,
    # 9 (0.0004 + 0.0004 + 0.04 + 0.04) / 36 = 0.0202, over n_m 10: 0.00202 on every row
    from soilcal.loop.residuals import relative_variances

    t = _one_quantity([(f"s{i}", 100.0 + i, rm, 10.0, np.nan, 1.0) for i, rm in enumerate([0.02, 0.02, 0.20, 0.20])])
    np.testing.assert_allclose(relative_variances(t), np.full(4, 0.00202), rtol=1e-12)


def test_a_simulations_seed_sd_counts_once_however_many_rows_it_serves():
    # simulation s0 runs three replicate rows with a relative seed SD 0.10 over three seeds,
    # s1 one row with 0.40 over three seeds, no measured SD: pooled once per simulation,
    # (2 0.01 + 2 0.16) / 4 = 0.085, over n_s 3: 0.028333 on every row (counted per row it
    # would be (3 2 0.01 + 2 0.16) / 8 = 0.0475, over 3: 0.015833)
    from soilcal.loop.residuals import relative_variances

    t = _one_quantity([("s0", 101.0, np.nan, np.nan, 0.10, 3.0), ("s0", 97.0, np.nan, np.nan, 0.10, 3.0),
                       ("s0", 104.0, np.nan, np.nan, 0.10, 3.0), ("s1", 92.0, np.nan, np.nan, 0.40, 3.0)])
    np.testing.assert_allclose(relative_variances(t), np.full(4, 0.085 / 3.0), rtol=1e-12)


def test_a_row_entered_twice_counts_once_in_the_measured_pool():
    # rows 1 and 2 are one row entered twice (simulation s0, measured 105 N, relative SD 0.10
    # over three repeats), row 3 another (s1, 0.40 over three), no seed SD: pooled once,
    # (2 0.01 + 2 0.16) / 4 = 0.085, over n_m 3: 0.028333 on every row (counted twice,
    # (2 2 0.01 + 2 0.16) / 6 = 0.06, over 3: 0.02)
    from soilcal.loop.residuals import relative_variances

    t = _one_quantity([("s0", 105.0, 0.10, 3.0, np.nan, 1.0), ("s0", 105.0, 0.10, 3.0, np.nan, 1.0),
                       ("s1", 93.0, 0.40, 3.0, np.nan, 1.0)])
    np.testing.assert_allclose(relative_variances(t), np.full(3, 0.085 / 3.0), rtol=1e-12)


def test_a_row_entered_twice_counts_once_in_every_pool():
    # rows 1 and 2 are one row entered twice (s0, relative measured SD 0.10 over three repeats),
    # row 3 another (s1, 0.12 over three), row 4 (s2) has no measured SD; every row a relative
    # seed SD 0.05 over four seeds.  The measured SDs pooled once: (2 0.01 + 2 0.0144) / 4 =
    # 0.0122 (counted twice, (4 0.01 + 2 0.0144) / 6 = 0.011467).  The residual's degrees of
    # freedom use it on the rows of three repeats, 0.0122 x (100 N)^2 / 3 = 40.667 N^2; the
    # noise floor of row 4 takes it for its missing SD (one repeat) beside its own seed part
    # 0.0025 / 4: sqrt(0.0122 + 0.000625) = 0.113248; the weights as in the test above.
    from soilcal.loop.residuals import noise_floor, reference_variances, relative_variances

    t = _one_quantity([("s0", 105.0, 0.10, 3.0, 0.05, 4.0), ("s0", 105.0, 0.10, 3.0, 0.05, 4.0),
                       ("s1", 93.0, 0.12, 3.0, 0.05, 4.0), ("s2", 100.0, np.nan, np.nan, 0.05, 4.0)])
    ref_m, ref_s = reference_variances(t)
    np.testing.assert_allclose(ref_m[:3], np.full(3, 0.0122 * 1e4 / 3.0), rtol=1e-12)
    np.testing.assert_allclose(ref_s, np.full(4, 25.0 / 4.0), rtol=1e-12)
    floor, _ = noise_floor(t, rows=np.array([False, False, False, True]))
    assert floor == pytest.approx(np.sqrt(0.0122 + 0.000625), rel=1e-12)
    np.testing.assert_allclose(relative_variances(t)[:3], np.full(3, 0.0122 / 3.0 + 0.000625), rtol=1e-12)


def test_a_copied_row_shares_its_sds_sampling_error_in_the_floor_interval():
    # rows s0 (relative measured SD 0.10 over three repeats) and s1 (0.12 over three), each a
    # relative seed SD 0.05 over four seeds; s0 entered twice in its table, or copied into a
    # second one.  Three rows, so each estimate's share T of floor^2 is its term over 3: s0's
    # measured SD 2 (0.01 / 3) / 3 on 2 degrees of freedom (both copies repeat one estimate, as
    # both read s0's seeds, the same runs in either table: 2 (0.0025 / 4) / 3 on 3), s1's
    # 0.0144 / 3 / 3 on 2 and
    # 0.0025 / 4 / 3 on 3; Satterthwaite's nu as in test_noise_floor's interval by hand
    from scipy import stats

    from soilcal.loop.residuals import floor_interval, noise_floor

    share = [(2 * 0.01 / 3 / 3, 2), (2 * 0.0025 / 4 / 3, 3), (0.0144 / 3 / 3, 2), (0.0025 / 4 / 3, 3)]
    floor2 = sum(t for t, _ in share)
    quad = sum(t ** 2 / (d + 2) for t, d in share)
    nu = (floor2 ** 2 - 2 * quad) / quad
    rows = [("s0", 105.0, 0.10, 3.0, 0.05, 4.0), ("s0", 105.0, 0.10, 3.0, 0.05, 4.0),
            ("s1", 93.0, 0.12, 3.0, 0.05, 4.0)]
    same = _one_quantity(rows)
    second = same.copy()
    second.loc[1, "measurement"] = "field"  # the copy in a second table
    for t in (same, second):
        floor, _ = noise_floor(t)
        assert floor ** 2 == pytest.approx(floor2, rel=1e-12)
        lo, hi, dof = floor_interval(t)
        assert dof == pytest.approx(nu, rel=1e-12)
        assert lo == pytest.approx(math.sqrt(floor2 * nu / stats.chi2.ppf(0.975, nu)), rel=1e-12)


def test_a_pattern_at_the_shortest_resolvable_period_is_found_exactly():
    # twelve tests 0.5 m apart whose residual alternates +5 % / -5 %: the cosine at the Nyquist
    # frequency of the spacing, wavelength 2 x 0.5 m = 1.0 m, explains all of it (r2 1).  Its
    # sine is 0 at every position, so the scan keeps its cosine alone (it dropped the frequency
    # as one it could not tell from the mean); the scan stops there, at (m - 1) / 2 periods over
    # the span, as shorter periods only alias longer ones at these positions
    from soilcal.loop.diagnose import _periodic

    x = 0.5 * np.arange(12)
    r = 0.05 * np.cos(np.pi * np.arange(12))
    row = _periodic("position_m", "position", x, r, 12, float(r @ r))
    assert row["r2"] == pytest.approx(1.0, abs=1e-12)
    assert row["estimate"] == pytest.approx(1.0, rel=1e-12)
    # no permutation of the alternating signs explains more than the pattern itself
    assert row["p"] < 0.01


def test_the_verdict_names_a_periodic_structure_with_its_wavelength():
    from soilcal.loop.core import _follows

    rng = np.random.default_rng(5)
    x = np.sort(rng.uniform(0.0, 40.0, 16))
    r = 0.1 * np.sin(2 * np.pi * x / 8.0 + 0.4) + rng.normal(0.0, 0.005, 16)
    res = pd.DataFrame({"measurement": "bin", "row": np.arange(1, 17), "measure": "F_N", "relative_residual": r,
                        "standardised_residual": np.nan, "cov:position_m": x})
    diag = diagnose(res, {"position_m": "position"})
    per = diag[diag["test"] == "periodic"].iloc[0]
    text = _follows(ranking(diag))
    assert text.startswith(f"position_m periodically (a sine of wavelength {per['estimate']:.3g} in position_m's unit, "
                           f"r2 {per['r2']:.2f}, Holm p {per['p_adjusted']:.3g})"), text


def test_a_trend_common_to_two_quantities_is_tested_beside_their_offsets():
    # two tables of three tests each, one quantity each (a heap's static and a drum's dynamic
    # angle), the layer depth 20, 40, 60 cm: r = a_q + 0.002 (x - 40) + e, the quantities'
    # offsets a = -0.02 and -0.13, e = 0.001 (1, -2, 1) in each table (no mean, no slope in x).
    # By hand, least squares with an intercept per quantity: the slope 0.002 exactly, its
    # variance s^2 / Sxx with Sxx = 2 * 800 (x about each table's mean), s^2 = sum e^2 / (6 - 3);
    # the share it adds, (SSR of the offsets alone - sum e^2) / SST
    x = np.array([20.0, 40.0, 60.0] * 2)
    q = np.array(["angle_deg"] * 3 + ["angle_avalanche_deg"] * 3)
    a = np.where(q == "angle_deg", -0.02, -0.13)
    e = 0.001 * np.array([1.0, -2.0, 1.0] * 2)
    r = a + 0.002 * (x - 40.0) + e
    t = pd.DataFrame({"measurement": np.where(q == "angle_deg", "static", "dynamic"), "row": [1, 2, 3] * 2,
                      "measure": q, "relative_residual": r, "standardised_residual": 1.0, "cov:depth": x})
    diag = diagnose(t, quantity_of={"depth": "layer_depth"})
    row = _row(diag, "trend", "depth")
    s2 = float(np.sum(e ** 2)) / 3
    t_stat = 0.002 / math.sqrt(s2 / 1600.0)
    assert row["estimate"] == pytest.approx(0.002, rel=1e-9)
    assert row["statistic"] == pytest.approx(t_stat, rel=1e-9)
    assert row["p"] == pytest.approx(2 * stats.t.sf(t_stat, 3), rel=1e-6)
    sst = float(np.sum((r - r.mean()) ** 2))
    ssr0 = float(sum(np.sum((r[q == k] - r[q == k].mean()) ** 2) for k in set(q)))
    assert row["r2"] == pytest.approx((ssr0 - np.sum(e ** 2)) / sst, rel=1e-9)
    # without the offsets the quantities' difference is scatter to the trend: p 0.30 on these
    # rows (the least-squares slope is the same, the tables being alike in x)
    plain = stats.linregress(x, r)
    assert plain.slope == pytest.approx(0.002, rel=1e-9) and plain.pvalue > 0.29 > 100 * row["p"]
    # a covariate that changes only with the quantity (a speed per table) is not tested: no
    # trend is left beside the offsets
    diag = diagnose(t.assign(**{"cov:speed": np.where(q == "angle_deg", 1.0, 2.0)}))
    assert not (diag["covariate"] == "speed").any()
    # one quantity: the tests as they always were, the fit's R^2
    one = t[q == "angle_deg"].assign(row=[1, 2, 3])
    one = pd.concat([one, one.assign(row=[4, 5, 6], **{"cov:depth": [30.0, 50.0, 70.0]})], ignore_index=True)
    fit = stats.linregress(one["cov:depth"], one["relative_residual"])
    row = _row(diagnose(one), "trend", "depth")
    assert row["estimate"] == pytest.approx(fit.slope, rel=1e-9) and row["p"] == pytest.approx(fit.pvalue, rel=1e-9)
    assert row["r2"] == pytest.approx(fit.rvalue ** 2, rel=1e-9)
