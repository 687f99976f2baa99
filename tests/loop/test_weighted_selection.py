"""Weighted least squares through the effect selection (soilcal.loop.select.row_weights,
Model.fit, cross_validate, score, forward): each row's squared relative error weighs 1 / v, v
the variance of its relative residual ((sd_m^2 / n_m + sd_s^2 / n_s) / scale^2, the relative
SDs pooled per measured quantity), the weights' mean 1; every row alike where a variance is
unknown, the variances hold different parts, or they are equal.

Expected values: a linear stand-in in which one measured test reports two quantities (a
plate's horizontal and vertical force) whose relative error is r_i - t g_i, with known
relative variances v_H and v_V (the vertical's about twelve times the horizontal's, as on the
DEM plate, whose vertical force scatters about three times as much from seed to seed).  The
weighted least-squares estimate is then t = sum(w g r) / sum(w g^2), the plain one
sum(g r) / sum(g^2) (Draper & Smith, Applied Regression Analysis, 3rd ed., 1998, Sec. 9.2),
their variances 1 / sum(g^2 / v) (the least of any linear unbiased estimate, Gauss-Markov) and
sum(g^2 v) / (sum g^2)^2; a sample SD over M tables has (M - 1) s^2 / sigma^2 chi-square on
M - 1 degrees of freedom."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from soilcal.loop import select as sl

N = 12  # measured conditions, each one test of two quantities
X = np.linspace(-1.0, 1.0, N)  # the covariate the effect follows
SCALE = 100.0
# relative measured SD (over 3 repeats) and relative seed SD (over 3 seeds) of each quantity
REL = {"horizontal_force_N": (0.02, 0.10), "vertical_force_N": (0.10, 0.34)}
NM = NS = 3
TRUE = 0.3
BOUNDS = {"t": (-2.0, 2.0)}


class _Trend:
    name = "trend"
    null = {"t": 0.0}

    def theta_names(self):
        return ("t",)


def _variances(rel=REL) -> np.ndarray:
    """Per row (every quantity's N rows in turn) its relative variance from the formula, by hand."""
    return np.concatenate([np.full(N, sm ** 2 / NM + ss ** 2 / NS) for sm, ss in rel.values()])


def _g(rel=REL) -> np.ndarray:
    """Per row the relative change per unit t: both forces follow the covariate alike."""
    return np.tile(X, len(rel))


def _obs(rng, rel=REL, with_sd=True) -> pd.DataFrame:
    """A measured table: per condition its two quantities (one simulation), measured
    100 (1 + t g + eps), eps normal with the row's variance; the calibrated model 100."""
    v, g = _variances(rel), _g(rel)
    measured = SCALE * (1.0 + TRUE * g + np.sqrt(v) * rng.standard_normal(len(v)))
    out = pd.DataFrame({"measurement": "campaign", "row": np.tile(np.arange(1, N + 1), len(rel)),
                        "measure": np.repeat(list(rel), N), "simulation": np.tile([f"s{i}" for i in range(N)], len(rel)),
                        "cov:x": np.tile(X, len(rel)), "measured": measured, "scale": SCALE,
                        "simulated_mean": SCALE})
    if with_sd:
        out["measured_sd"] = np.repeat([SCALE * sm for sm, _ in rel.values()], N)
        out["measured_n"] = NM
        out["simulated_sd"] = np.repeat([SCALE * ss for _, ss in rel.values()], N)
        out["simulated_n"] = NS
    return out


def _effect(rel=REL) -> sl.EffectData:
    """The trend's surrogate: 100 (1 + t g) at each row, through its design points."""
    eff = _Trend()
    ts = np.array([[-2.0], [0.0], [2.0]])
    means = np.array([SCALE * (1.0 + t * _g(rel)) for t in ts[:, 0]])
    return sl.EffectData(eff, BOUNDS, sl.Surrogate(eff, BOUNDS, ts, means), [{"t": t} for t in ts[:, 0]])


def _closed_form(obs, w) -> float:
    r = obs["measured"].to_numpy(float) / SCALE - 1.0
    g = _g()
    return float(np.sum(w * g * r) / np.sum(w * g * g))


def _fit(obs, ed, weights) -> float:
    y0 = np.full(len(obs), SCALE)
    return float(sl.Model([ed], y0, obs["measured"].to_numpy(float), np.full(len(obs), SCALE), weights=weights).fit()[0][0])


def test_the_weights_are_the_inverse_relative_variances_with_mean_one():
    obs = _obs(np.random.default_rng(0))
    w = 1.0 / _variances()
    np.testing.assert_allclose(sl.row_weights(obs), w / w.mean(), rtol=1e-12)
    assert sl.row_weights(obs).mean() == pytest.approx(1.0, rel=1e-14)


def test_the_weighted_fit_is_the_closed_form_weighted_least_squares_estimate():
    obs, ed = _obs(np.random.default_rng(1)), _effect()
    v = _variances()
    wls, ols = _closed_form(obs, 1.0 / v), _closed_form(obs, np.ones(len(v)))
    assert abs(wls - ols) > 0.02  # the table tells the two apart
    assert _fit(obs, ed, sl.row_weights(obs)) == pytest.approx(wls, abs=1e-6)
    assert _fit(obs, ed, None) == pytest.approx(ols, abs=1e-6)
    # forward builds its models with the rows' weights: its first step's fit is the weighted one
    sel = sl.forward(obs, np.full(len(obs), SCALE), {"trend": ed})
    assert sel.steps[0][2].theta["trend.t"] == pytest.approx(wls, abs=1e-6)
    plain = sl.forward(_obs(np.random.default_rng(1), with_sd=False), np.full(len(obs), SCALE), {"trend": ed})
    assert plain.steps[0][2].theta["trend.t"] == pytest.approx(ols, abs=1e-6)


def test_the_weighted_parameter_has_the_least_variance_over_seeded_tables():
    # M tables: the SD of each estimate against its analytic value, within the two-sided 99.9 %
    # band of a sample SD on M - 1 degrees of freedom
    M = 300
    rng = np.random.default_rng(2)
    ed = _effect()
    v, g = _variances(), _g()
    sd_wls = math.sqrt(1.0 / np.sum(g * g / v))
    sd_ols = math.sqrt(np.sum(g * g * v)) / np.sum(g * g)
    assert sd_ols / sd_wls > 1.5  # the stand-in's noisy quantity costs the plain fit that much
    weighted, plain = [], []
    w = None
    for _ in range(M):
        obs = _obs(rng)
        w = sl.row_weights(obs) if w is None else w  # the same SD columns in every table
        weighted.append(_fit(obs, ed, w))
        plain.append(_fit(obs, ed, None))
    lo, hi = (math.sqrt(stats.chi2.ppf(q, M - 1) / (M - 1)) for q in (0.0005, 0.9995))
    s_w, s_p = np.std(weighted, ddof=1), np.std(plain, ddof=1)
    assert lo * sd_wls <= s_w <= hi * sd_wls
    assert lo * sd_ols <= s_p <= hi * sd_ols
    assert s_w < s_p
    # both unbiased: the means within 3.3 standard errors of the true value
    assert abs(np.mean(weighted) - TRUE) < 3.3 * sd_wls / math.sqrt(M)
    assert abs(np.mean(plain) - TRUE) < 3.3 * sd_ols / math.sqrt(M)


def _same_selection(a: sl.Selection, b: sl.Selection):
    assert a.chosen == b.chosen and len(a.steps) == len(b.steps)
    for (sa, na, x), (sb, nb, y) in zip(a.steps, b.steps):
        assert (sa, na) == (sb, nb)
        assert x.theta == y.theta and x.ci == y.ci
        np.testing.assert_array_equal(x.fold_rms, y.fold_rms)
        np.testing.assert_array_equal(x.heldout_errors, y.heldout_errors)
        assert (x.aicc, x.ref_aicc, x.accepted, x.reason) == (y.aicc, y.ref_aicc, y.accepted, y.reason)
        assert x.p == y.p or (math.isnan(x.p) and math.isnan(y.p))
        assert x.heldout_weights is None and y.heldout_weights is None


@pytest.mark.parametrize("case", ["equal", "unknown", "parts"])
def test_equal_or_unknown_variances_give_exactly_the_unweighted_selection(case):
    rel = REL
    if case == "equal":  # the two quantities equally noisy: every row weighs alike
        rel = {"horizontal_force_N": (0.05, 0.2), "vertical_force_N": (0.05, 0.2)}
    obs = _obs(np.random.default_rng(3), rel)
    if case == "unknown":  # the vertical force without a measured SD and on one seed: its variance unknown
        vertical = obs["measure"] == "vertical_force_N"
        obs.loc[vertical, ["measured_sd", "simulated_sd"]] = np.nan
        obs.loc[vertical, "simulated_n"] = 1
    if case == "parts":  # the vertical force without a measured SD: its seed scatter alone
        obs.loc[obs["measure"] == "vertical_force_N", "measured_sd"] = np.nan
    assert sl.row_weights(obs) is None
    ed = _effect(rel)
    with_sd = sl.forward(obs, np.full(len(obs), SCALE), {"trend": ed})
    bare = obs.drop(columns=["measured_sd", "measured_n", "simulated_sd", "simulated_n"])
    _same_selection(with_sd, sl.forward(bare, np.full(len(obs), SCALE), {"trend": ed}))


def test_the_held_out_errors_aicc_and_acceptance_are_weighted():
    obs, ed = _obs(np.random.default_rng(4)), _effect()
    w = sl.row_weights(obs)
    y0, m, sc = np.full(len(obs), SCALE), obs["measured"].to_numpy(float), np.full(len(obs), SCALE)
    model, ref = sl.Model([ed], y0, m, sc, weights=w), sl.Model([], y0, m, sc, weights=w)
    folds = sl._folds(obs, None)
    s = sl.score(model, ref, folds)
    fold_rms, held = sl.cross_validate(model, folds)
    for j, f in enumerate(folds.held_out):  # each fold's RMS weighted by its rows' weights
        assert fold_rms[j] == pytest.approx(math.sqrt(np.sum(w[f] * held[f] ** 2) / np.sum(w[f])), rel=1e-12)
    e, er = s.heldout_errors, s.ref_heldout_errors  # the plain held-out relative errors, as reported
    assert s.rmse() == pytest.approx(math.sqrt(np.mean(e ** 2)), rel=1e-12)
    assert s.weighted_rmse() == pytest.approx(math.sqrt(np.sum(w * e ** 2) / np.sum(w)), rel=1e-12)
    assert s.weighted_rmse(True) == pytest.approx(math.sqrt(np.sum(w * er ** 2) / np.sum(w)), rel=1e-12)
    assert sl.lowers_heldout(s) == (s.weighted_rmse() <= 0.9 * s.weighted_rmse(True))
    # AICc of the weighted SSE: n ln(SSE_w / n) + 2K + 2K(K + 1) / (n - K - 1), K = 2
    n, sse = len(obs), float(np.sum(w * s.fitted_errors ** 2))
    assert s.aicc == pytest.approx(n * math.log(sse / n) + 4 + 12 / (n - 3), rel=1e-12)
    sse_r = float(np.sum(w * (m / SCALE - 1.0) ** 2))
    assert s.ref_aicc == pytest.approx(n * math.log(sse_r / n) + 2 + 4 / (n - 2), rel=1e-12)


def test_the_weighted_sum_of_squares_of_replicate_groups():
    # group a: weighted mean (0.1 * 1 + 0.3 * 3) / 4 = 0.25 at its mean weight 2; group b: -0.2 at 2
    e, w = np.array([0.1, 0.3, -0.2]), np.array([1.0, 3.0, 2.0])
    assert sl.sse_of(e, np.array(["a", "a", "b"]), w) == (pytest.approx(2 * 0.25 ** 2 + 2 * 0.2 ** 2, rel=1e-14), 2)
    assert sl.sse_of(e, None, w) == (pytest.approx(0.01 + 0.27 + 0.08, rel=1e-14), 3)


def test_a_model_and_a_reference_of_different_weights_are_not_compared():
    obs, ed = _obs(np.random.default_rng(5)), _effect()
    y0, m, sc = np.full(len(obs), SCALE), obs["measured"].to_numpy(float), np.full(len(obs), SCALE)
    with pytest.raises(ValueError, match="weigh the rows differently"):
        sl.score(sl.Model([ed], y0, m, sc, weights=sl.row_weights(obs)), sl.Model([], y0, m, sc),
                 sl._folds(obs, None))


def test_the_bootstrap_refits_with_the_weights():
    # seeds without scatter and measured values without error: every draw is the table itself,
    # so the interval is the weighted fit's value (the closed form), not the plain one
    obs = _obs(np.random.default_rng(6))
    runs = pd.DataFrame([{"measurement": m, "row": r, "measure": q, "seed": s, "value": SCALE * (1.0 + t * g),
                          "status": "ok", "t:t": t}
                         for t in (-2.0, 0.0, 2.0) for m, r, q, g in zip(obs["measurement"], obs["row"], obs["measure"], _g())
                         for s in range(3)])
    ed = sl.build_effect_data(obs, runs, _Trend(), BOUNDS)
    y0, m, sc = np.full(len(obs), SCALE), obs["measured"].to_numpy(float), np.full(len(obs), SCALE)
    wls, ols = _closed_form(obs, 1.0 / _variances()), _closed_form(obs, np.ones(len(obs)))
    for weights, expected in ((sl.row_weights(obs), wls), (None, ols)):
        lo, hi = sl.bootstrap_ci([ed], y0, m, np.zeros(len(obs)), 40, scale=sc, weights=weights)["trend.t"]
        assert lo == pytest.approx(expected, abs=1e-6) and hi == pytest.approx(expected, abs=1e-6)


def test_the_summary_gives_the_weighted_held_out_errors_beside_the_plain_ones():
    from soilcal.loop import core

    obs = _obs(np.random.default_rng(7))
    before = obs["measured"].to_numpy(float) / SCALE - 1.0
    after = 0.5 * before
    w = 1.0 / _variances()
    e = core.error_figures(obs, before, after)
    assert e["rmse_before_percent"] == pytest.approx(100 * math.sqrt(np.mean(before ** 2)), rel=1e-12)
    assert e["weighted_rmse_before_percent"] == pytest.approx(100 * math.sqrt(np.sum(w * before ** 2) / np.sum(w)),
                                                              rel=1e-12)
    assert e["weighted_rmse_after_percent"] == pytest.approx(50 * math.sqrt(np.sum(w * before ** 2) / np.sum(w)),
                                                             rel=1e-12)
    alike = _obs(np.random.default_rng(7), {"horizontal_force_N": (0.05, 0.2), "vertical_force_N": (0.05, 0.2)})
    assert math.isnan(core.error_figures(alike, before, after)["weighted_rmse_before_percent"])


# The verdict's words: where the rows weigh differently a clause quotes the weighted held-out RMS
# errors its decision used, and where they weigh alike it reads as it always has.  Two held-out
# rows, the model's relative errors 0.1 and 0.5, its reference's 0.3 and 0.4, weights 1.9 and
# 0.1 (mean 1), by hand: plain RMS sqrt(0.26 / 2) = 36.06 % against sqrt(0.25 / 2) = 35.36 %,
# the model no lower; weighted sqrt(0.044 / 2) = 14.83 % against sqrt(0.187 / 2) = 30.58 %, the
# model lower by more than 10 %.  The plain clauses' expected words are the clauses as written
# before the weights.
W2 = np.array([1.9, 0.1])


def _held(weights, e=(0.1, 0.5), er=(0.3, 0.4), names=("trend.t",), **kw) -> sl.Score:
    e, er = np.asarray(e, float), np.asarray(er, float)
    fields = dict(names=list(names), theta={n: 0.1 for n in names}, ci={}, fold_rms=np.abs(e),
                  ref_fold_rms=np.abs(er), heldout_errors=e, ref_heldout_errors=er, fitted_errors=e, aicc=-10.0,
                  ref_aicc=-8.0, p=0.2, accepted=False, reason="", heldout_weights=weights)
    fields.update(kw)
    return sl.Score(**fields)


def test_the_held_out_words_and_numbers_are_those_the_decision_used():
    from soilcal.loop import core

    assert core._heldout(_held(W2)) == ("weighted held-out RMS", pytest.approx(100 * math.sqrt(0.022), rel=1e-12),
                                        pytest.approx(100 * math.sqrt(0.0935), rel=1e-12))
    assert core._heldout(_held(None)) == ("held-out RMS", pytest.approx(100 * math.sqrt(0.13), rel=1e-12),
                                          pytest.approx(100 * math.sqrt(0.125), rel=1e-12))
    assert sl.lowers_heldout(_held(W2)) and not sl.lowers_heldout(_held(None))


def test_a_uniform_bias_fitting_as_well_is_worded_from_the_errors_compared():
    from soilcal.loop import core

    # weighted, the bias (30.58 %) is above the effect (14.83 %): "nearly as well"; plain, 35.36 %
    # is below 36.06 %: "as well or better", which the weighted selection did not find
    assert core._bias_fits_as_well(_held(W2), 0.05, 1) == (
        "; a uniform bias fits the held-out rows nearly as well (the measured values 5.0 % above the model "
        "throughout: weighted held-out RMS 30.58 % against 14.83 % with the effect, paired p 0.2), so these rows "
        "cannot tell it from a bias no mechanism carries")
    assert core._bias_fits_as_well(_held(None), -0.05, 2) == (
        "; a uniform bias fits the held-out rows as well or better (the measured values 5.0 % below the model "
        "throughout: held-out RMS 35.36 % against 36.06 % with the effects, paired p 0.2), so these rows "
        "cannot tell them from a bias no mechanism carries")


def test_an_unscored_model_is_named_on_the_errors_that_named_it():
    from soilcal.loop import core

    u = pd.DataFrame({"simulation": ["s0", "s1"], "measure": "horizontal_force_N"})
    names = ("trend.t", "uniform_scale.s")

    def clause(s):
        return core._unscored(sl.Selection([], [("1", ["trend", "uniform_scale"], s)], None), u)

    text = clause(_held(W2, names=names, aicc=math.nan))
    assert text.startswith("; trend+uniform_scale (weighted held-out RMS 14.83 % against 30.58 %, paired p 0.2 >= "
                           "0.05, which does not decide either) could not be scored: on 2 observations"), text
    assert clause(_held(None, names=names, aicc=math.nan)) == ""  # plain, the model is no lower: not named
    # rows alike, a model 10 % lower: the words as before
    assert clause(_held(None, e=(0.1, 0.1), names=names, aicc=math.nan)).startswith(
        "; trend+uniform_scale (held-out RMS 10.00 % against 35.36 %, paired p 0.2 >= 0.05, which does not decide "
        "either) could not be scored: on 2 observations")


def test_an_effect_not_separated_is_named_on_the_errors_that_named_it():
    from soilcal.loop import core

    def clause(g):
        return core._not_separated(sl.Selection([], [("gate", ["trend"], g)], None, forward_chosen=["trend"]), 0.05)

    reason = "without trend, held-out error not significantly lower"
    assert clause(_held(W2, reason=reason)).startswith(
        "; trend was not separated from the model: with it the weighted held-out RMS error is 14.83 % against "
        "30.58 %, AICc -10.0 against -8.0, paired p 0.2 over 2 held-out groups (alpha 0.05)")
    assert clause(_held(None, reason=reason)) == ""
    assert clause(_held(None, e=(0.1, 0.1), reason=reason)).startswith(
        "; trend was not separated from the model: with it the held-out RMS error is 10.00 % against 35.36 %, "
        "AICc -10.0 against -8.0, paired p 0.2 over 2 held-out groups (alpha 0.05)")


@pytest.mark.parametrize("weights,said", [(W2, "weighted held-out RMS 14.83 % against 30.58 %"),
                                          (None, "held-out RMS 36.06 % against 35.36 %")])
def test_the_comparisons_beside_and_against_a_uniform_scale_quote_the_errors_compared(weights, said):
    from soilcal.loop import core

    # beside the scale, too few observations for the AICc, the paired test not passed
    b = _held(weights, names=("trend.t", "uniform_scale.s"), aicc=math.nan, reason="AICc undefined")
    uniform = _held(None, e=(0.1, 0.1), accepted=True, p=0.01)
    sel = sl.Selection(["trend"], [], None, uniform=uniform, beside_uniform=b, judged=["trend"])
    assert core._beside_clause(sel, 0.05).endswith(
        f"beside it it does not lower the held-out error significantly ({said}, paired p 0.2)")
    # judged against the scale alone, which the effect beats: that comparison's errors
    sel = sl.Selection(["trend"], [], None, uniform=_held(weights, accepted=True, p=0.01),
                       beside_uniform=_held(W2, e=(0.1, 0.1), aicc=math.nan, p=0.01, reason="AICc undefined"),
                       judged=["trend"])
    assert f"which it beats ({said}, paired p 0.01); " in core._judged_alone(sel, 0.05)


def test_selection_csv_gives_the_weighted_held_out_errors_beside_the_plain_ones(tmp_path):
    from soilcal.chain.files import write_csv
    from soilcal.loop import core

    w = 1.0 / _variances()  # by hand; their mean does not change a weighted RMS
    rows = []
    for obs in (_obs(np.random.default_rng(8)), _obs(np.random.default_rng(8), with_sd=False)):
        y0, m, sc = np.full(len(obs), SCALE), obs["measured"].to_numpy(float), np.full(len(obs), SCALE)
        weights = sl.row_weights(obs)
        s = sl.score(sl.Model([_effect()], y0, m, sc, weights=weights), sl.Model([], y0, m, sc, weights=weights),
                     sl._folds(obs, None))
        row = core._selection_row("1", s, ["trend"])
        e, er = s.heldout_errors, s.ref_heldout_errors
        assert row["heldout_rmse_percent"] == pytest.approx(100 * math.sqrt(np.mean(e ** 2)), rel=1e-12)
        assert row["reference_heldout_rmse_percent"] == pytest.approx(100 * math.sqrt(np.mean(er ** 2)), rel=1e-12)
        if weights is not None:
            assert row["weighted_heldout_rmse_percent"] == pytest.approx(
                100 * math.sqrt(np.sum(w * e ** 2) / np.sum(w)), rel=1e-12)
            assert row["reference_weighted_heldout_rmse_percent"] == pytest.approx(
                100 * math.sqrt(np.sum(w * er ** 2) / np.sum(w)), rel=1e-12)
            assert abs(row["weighted_heldout_rmse_percent"] - row["heldout_rmse_percent"]) > 0.1
        rows.append(row)
    # beside the plain columns; every row alike (the table without SD columns): the cells empty
    write_csv(pd.DataFrame(rows, columns=core.SELECTION_COLUMNS), tmp_path / "selection.csv")
    back = pd.read_csv(tmp_path / "selection.csv")
    assert list(back.columns[4:8]) == ["heldout_rmse_percent", "reference_heldout_rmse_percent",
                                       "weighted_heldout_rmse_percent", "reference_weighted_heldout_rmse_percent"]
    assert back.loc[0, ["weighted_heldout_rmse_percent", "reference_weighted_heldout_rmse_percent"]].notna().all()
    assert back.loc[1, ["weighted_heldout_rmse_percent", "reference_weighted_heldout_rmse_percent"]].isna().all()
