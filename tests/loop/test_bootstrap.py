"""The chosen effect's interval (soilcal.loop.select.bootstrap_ci): the seeds of each
condition resampled with common random numbers, the measured values redrawn within their
standard error, the model refitted.

Expected values: an effect simulated without seed scatter and measured exactly leaves
nothing to resample, so the interval is the fitted value itself; a linear one-parameter
campaign with Gaussian measured values of known SE has a bootstrap distribution known in
closed form, so the interval's coverage of the true parameter (binomial over seeded
campaigns), width and centre follow from the level and the number of draws; one row of two
seeds at +-d gives draws at three known values; rows of one simulation drawn together widen
the interval by sqrt(2) over rows drawn apart."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from soilcal.loop import select as sl
from soilcal.loop.effects import EFFECTS

EFF = EFFECTS["rate_friction"]
BOUNDS = {"beta": (-0.3, 0.6)}
DESIGN = sl.theta_design(EFF, BOUNDS, 5)
N, SEEDS = 18, 3
A = np.linspace(-1.0, 1.0, N)


def _campaign(rng, true, scatter, measured_scatter=None):
    measured_scatter = scatter if measured_scatter is None else measured_scatter
    rows = []
    for d in DESIGN:
        for i in range(N):
            for s in range(SEEDS):
                v = 100.0 * (1 + A[i] * d["beta"]) * (1 + scatter * rng.standard_normal())
                rows.append({"measurement": "m", "row": i + 1, "measure": "F_N", "seed": s, "value": v, "status": "ok",
                             "t:beta": d["beta"]})
    reps = 100.0 * (1 + A * true)[:, None] * (1 + measured_scatter * rng.standard_normal((N, SEEDS)))
    obs = pd.DataFrame({"measurement": "m", "row": np.arange(1, N + 1), "measure": "F_N", "measured": reps.mean(1),
                        "measured_sd": reps.std(1, ddof=1) if measured_scatter else 0.0, "measured_n": SEEDS})
    return obs, pd.DataFrame(rows)


def _fit(obs, runs, n_boot=100):
    ed = sl.build_effect_data(obs, runs, EFF, BOUNDS)
    y0 = runs[runs["t:beta"] == 0.0].groupby("row")["value"].mean().to_numpy()
    x, _ = sl.Model([ed], y0, obs["measured"].to_numpy(float)).fit()
    se = (obs["measured_sd"] / np.sqrt(obs["measured_n"])).to_numpy(float)
    return ed, float(x[0]), sl.bootstrap_ci([ed], y0, obs["measured"].to_numpy(float), se, n_boot, x0=x)


def test_the_runs_values_are_kept_per_seed_with_the_seeds_in_order():
    obs, runs = _campaign(np.random.default_rng(0), 0.3, 0.14)
    ed = sl.build_effect_data(obs, runs, EFF, BOUNDS)
    assert ed.values.shape == (len(DESIGN), N, SEEDS)
    j = [d["beta"] for d in ed.design].index(0.15)
    sel = runs[(runs["t:beta"] == 0.15) & (runs["row"] == 4)].sort_values("seed")["value"].to_numpy()
    assert ed.values[j, 3] == pytest.approx(sel, rel=1e-15)


def test_without_scatter_the_interval_is_the_fitted_value():
    obs, runs = _campaign(np.random.default_rng(1), 0.3, 0.0)
    _, x, ci = _fit(obs, runs)
    lo, hi = ci["rate_friction.beta"]
    assert x == pytest.approx(0.3, abs=1e-6)
    assert lo == pytest.approx(x, abs=1e-9) and hi == pytest.approx(x, abs=1e-9)


def test_one_seed_or_no_refits_leave_nothing_to_resample():
    obs, runs = _campaign(np.random.default_rng(2), 0.3, 0.14)
    ed, x, _ = _fit(obs, runs)
    y0, m = np.full(N, 100.0), obs["measured"].to_numpy(float)
    assert sl.bootstrap_ci([ed], y0, m, np.zeros(N), 0) is None
    one = sl.build_effect_data(obs, runs[runs["seed"] == 0], EFF, BOUNDS)
    assert sl.bootstrap_ci([one], y0, m, np.zeros(N), 100) is None


def _percentile_interval_of_normals(b: int, level: float, reps: int = 20000):
    """numpy's percentile interval at ``level`` of ``b`` standard normal draws, over ``reps``
    sets of draws (a fixed generator, no code under test): (its coverage of an independent
    standard normal, E[Phi(q_hi) - Phi(q_lo)]; its width's mean and SD; its midpoint's SD)."""
    from scipy import stats

    z = np.random.default_rng(12345).standard_normal((reps, b))
    tail = 100 * (1 - level) / 2
    lo, hi = np.percentile(z, [tail, 100 - tail], axis=1)
    cover = float(np.mean(stats.norm.cdf(hi) - stats.norm.cdf(lo)))
    return cover, float(np.mean(hi - lo)), float(np.std(hi - lo)), float(np.std((hi + lo) / 2))


def test_the_interval_covers_the_true_parameter_at_its_level():
    # A campaign whose bootstrap distribution is known exactly: six rows a_i = -1..1, runs
    # without scatter (two seeds of equal values: nothing to resample, and the monotone cubic
    # through collinear means is the line 100 (1 + a_i beta)), measured values 100 (1 + a_i
    # beta_true) + SE z_i with their SE known, relative errors on the fixed scale 100. The fit
    # is linear least squares, beta_hat = sum a_i (m_i - 100) / (100 sum a_i^2), and each draw,
    # m_i + SE z*_i refitted, is beta_hat + sigma z* with sigma = SE / (100 sqrt(sum a_i^2)):
    # beta_hat ~ N(beta_true, sigma^2) and the draws ~ N(beta_hat, sigma^2), so the 95 %
    # percentile interval of B draws covers beta_true with the probability a percentile
    # interval of B standard normals covers an independent one (computed below from normals
    # alone: 0.87 for B = 20, below 0.95 by the percentiles' own scatter), and its width and
    # midpoint are those of that interval times sigma about beta_hat.
    # Over K = 40 seeded campaigns (each with its own bootstrap seed) the hit count is
    # Binomial(K, p_B): it must lie in its central 99 % interval (29 to 39 hits); the mean width /
    # sigma within 3.29 SD / sqrt(K) (99.9 %) of its expected value, the mean midpoint offset
    # within 3.29 SD / sqrt(K) of 0.  An interval that does not redraw the measured values
    # (width 0), or redraws them with the SE halved (coverage 0.58, P(hits >= 29) = 0.003), fails.
    from scipy import stats

    n, se, true, b, k, level = 6, 3.0, 0.2, 20, 40, 0.95
    a = np.linspace(-1.0, 1.0, n)
    sigma = se / (100.0 * np.sqrt(np.sum(a ** 2)))
    p_b, w_mean, w_sd, mid_sd = _percentile_interval_of_normals(b, level)
    runs = pd.DataFrame([{"measurement": "m", "row": i + 1, "measure": "F_N", "seed": s, "status": "ok",
                          "value": 100.0 * (1 + a[i] * d["beta"]), "t:beta": d["beta"]}
                         for d in DESIGN for i in range(n) for s in range(2)])
    rng = np.random.default_rng(20261201)
    hits, widths, mids = 0, [], []
    for c in range(k):
        m = 100.0 * (1 + a * true) + se * rng.standard_normal(n)
        obs = pd.DataFrame({"measurement": "m", "row": np.arange(1, n + 1), "measure": "F_N", "measured": m})
        ed = sl.build_effect_data(obs, runs, EFF, BOUNDS)
        y0 = ed.surrogate([0.0])
        assert y0 == pytest.approx(np.full(n, 100.0), rel=1e-12)
        x, _ = sl.Model([ed], y0, m, np.full(n, 100.0)).fit()
        beta_hat = np.sum(a * (m - 100.0)) / (100.0 * np.sum(a ** 2))
        assert x[0] == pytest.approx(beta_hat, abs=1e-7)
        lo, hi = sl.bootstrap_ci([ed], y0, m, np.full(n, se), b, seed=c, level=level, x0=x,
                                 scale=np.full(n, 100.0))["rate_friction.beta"]
        hits += lo <= true <= hi
        widths.append((hi - lo) / sigma)
        mids.append(((lo + hi) / 2 - beta_hat) / sigma)
    low, high = stats.binom.interval(0.99, k, p_b)
    assert low <= hits <= high, (hits, low, high, p_b)
    assert np.mean(widths) == pytest.approx(w_mean, abs=3.29 * w_sd / np.sqrt(k)), (np.mean(widths), w_mean)
    assert abs(np.mean(mids)) <= 3.29 * mid_sd / np.sqrt(k), np.mean(mids)


def test_runs_without_a_seed_number_are_left_out_and_rows_may_have_more_seeds():
    obs, runs = _campaign(np.random.default_rng(3), 0.3, 0.14)
    runs = runs.astype({"seed": float})
    runs.loc[(runs["row"] == 2) & (runs["seed"] == 1), "seed"] = np.nan  # one seed of row 2 unnumbered
    extra = runs[runs["row"] == 5].assign(seed=lambda d: d["seed"] + 10)  # row 5: six seeds
    ed = sl.build_effect_data(obs, pd.concat([runs, extra]), EFF, BOUNDS)
    assert ed.seeds[1] == [0, 2] and ed.seeds[4] == [0, 1, 2, 10, 11, 12] and ed.values.shape[2] == 6
    assert np.isnan(ed.values[:, 1, 2:]).all() and np.isfinite(ed.values[:, 4]).all()
    y0 = ed.surrogate([0.0])
    x, _ = sl.Model([ed], y0, obs["measured"].to_numpy(float)).fit()
    ci = sl.bootstrap_ci([ed], y0, obs["measured"].to_numpy(float), np.zeros(N), 100, x0=x)
    # the draws resample every row (the bookkeeping above) about the fit: their interval holds
    # it (whether it covers the true beta is the coverage test's, over many campaigns)
    assert ci is not None and ci["rate_friction.beta"][0] < x[0] < ci["rate_friction.beta"][1]


def test_a_row_without_its_measured_sd_keeps_the_fits_interval(monkeypatch):
    from soilcal.loop import core

    obs, runs = _campaign(np.random.default_rng(4), 0.3, 0.14)
    ed = sl.build_effect_data(obs, runs, EFF, BOUNDS)
    u = obs.assign(simulated_mean=ed.surrogate([0.0]))
    m = sl.Model([ed], u["simulated_mean"].to_numpy(float), u["measured"].to_numpy(float))
    final = sl.score(m, sl.Model([], m.y0, m.measured), sl._folds(u, None))
    boots = []
    bootstrap_ci = sl.bootstrap_ci
    monkeypatch.setattr(sl, "bootstrap_ci", lambda *a, **k: boots.append((a, k, bootstrap_ci(*a, **k))) or boots[-1][2])
    ci, how = core._interval(u, [ed], final, core.Settings())
    assert how.startswith("the wider of the fit's (Jacobian) interval and a bootstrap of 200 refits")
    # a fit that cannot bound the parameter (a rank-deficient Jacobian): the bootstrap's alone.
    # Its bootstrap is the one above (the same effects, rows, measured values and start, only
    # the fit's interval differs): the draws are not refitted again
    from dataclasses import replace

    def same(x, y):
        if isinstance(x, (list, tuple)):
            return len(x) == len(y) and all(same(p, q) for p, q in zip(x, y))
        return x is y or np.array_equal(x, y)

    def same_draws(*a, **k):
        a0, k0, ci0 = boots[0]
        assert same(list(a), list(a0)) and set(k) == set(k0) and all(same(k[n], k0[n]) for n in k)
        return ci0

    monkeypatch.setattr(sl, "bootstrap_ci", same_draws)
    unbounded = replace(final, ci={"rate_friction.beta": (-np.inf, np.inf)})
    ci, how = core._interval(u, [ed], unbounded, core.Settings())
    assert np.isfinite(ci["rate_friction.beta"]).all() and how.endswith("alone: the fit does not bound every parameter")
    lo, hi = final.ci["rate_friction.beta"]
    assert ci["rate_friction.beta"][0] <= lo and ci["rate_friction.beta"][1] >= hi
    u.loc[3, "measured_sd"] = np.nan
    ci, how = core._interval(u, [ed], final, core.Settings())
    assert ci == final.ci and "without its SD" in how
    ci, how = core._interval(u, [ed], final, core.Settings(bootstrap=0))
    assert ci == final.ci and "loop.bootstrap: 0" in how


def test_a_row_without_numbered_seeds_keeps_its_means_and_the_rest_is_resampled():
    obs, runs = _campaign(np.random.default_rng(5), 0.3, 0.14)
    runs = runs.astype({"seed": float})
    runs.loc[runs["row"] == 3, "seed"] = np.nan  # row 3's job file had no seed column
    ed = sl.build_effect_data(obs, runs, EFF, BOUNDS)
    assert ed.seeds[2] == [] and np.isfinite(ed.means[:, 2]).all()
    ci = sl.bootstrap_ci([ed], ed.surrogate([0.0]), obs["measured"].to_numpy(float), np.zeros(N), 100, x0=[0.3])
    assert ci is not None


def test_rows_of_one_simulation_share_their_draws():
    """Every row measured twice from the same runs (two tables that one job simulates).
    Drawn as one simulation per pair, the draws are those of the 18-row campaign; drawn as 36
    independent rows, the fit (the two rows of a pair alike in measured value and scale) sees
    per row the mean of two independent draws' deviations, whose spread is smaller by
    sqrt(2) (to first order in the deviations).  So the width ratio w_shared / w_apart is
    sqrt(2) in expectation, and 1 for code that ignores the shared labels.

    Threshold: each width is a 95 % percentile interval of B = 200 draws; for Gaussian draws
    its log has SD s_w = SD(width) / mean(width) = 0.066 (computed below from normals alone),
    the two intervals treated as independent, a campaign's log ratio has SD sqrt(2) s_w =
    0.094, and the mean over three campaigns sqrt(2/3) s_w = 0.054.  The mean log ratio is held
    between log 2^(1/4) and log 2^(3/4): the geometric midpoints between sqrt(2) and the ratio
    1 of shared draws ignored (or 2 of a pair's draws counted twice), each 0.173 = 3.2 SD away
    from log sqrt(2): correct code fails it, or code that ignores the labels passes it, with
    probability 7e-4.  Campaign seeds 0, 1, 2 (the first three), each the bootstrap's seed too."""
    from scipy import stats

    b = 200
    _, w_mean, w_sd, _ = _percentile_interval_of_normals(b, 0.95)
    s_mean = np.sqrt(2.0 / 3.0) * w_sd / w_mean
    assert stats.norm.sf(np.log(2.0) / 4 / s_mean) < 1e-3  # the threshold's derivation above
    logs = []
    for seed in (0, 1, 2):
        obs, runs = _campaign(np.random.default_rng(seed), 0.3, 0.14)
        twice = pd.concat([obs, obs.assign(measurement="again")], ignore_index=True)
        runs2 = pd.concat([runs, runs.assign(measurement="again")], ignore_index=True)
        ed = sl.build_effect_data(twice, runs2, EFF, BOUNDS)
        y0, m, se = ed.surrogate([0.0]), twice["measured"].to_numpy(float), np.zeros(2 * N)
        shared = sl.bootstrap_ci([ed], y0, m, se, b, seed=seed, x0=[0.3],
                                 conditions=[f"job{r}" for r in twice["row"]])
        apart = sl.bootstrap_ci([ed], y0, m, se, b, seed=seed, x0=[0.3], conditions=list(range(2 * N)))
        w = lambda ci: ci["rate_friction.beta"][1] - ci["rate_friction.beta"][0]  # noqa: E731
        logs.append(np.log(w(shared) / w(apart)))
    assert np.log(2.0) / 4 < np.mean(logs) < 3 * np.log(2.0) / 4, np.exp(logs)


def test_the_draws_centre_on_the_surrogates_means_which_count_unnumbered_runs():
    # seeded runs without scatter, 100 (1 + a beta), and one run per design point and row
    # without a seed number, 4 higher: the surrogate goes through 100 (1 + a beta) + 1 and
    # the measured values lie on it at beta = 0.3, so the fit is 0.3 exactly; the draws, with
    # nothing to resample and nothing to redraw, must each refit that same surface: the
    # interval is the point 0.3 (drawn around the seeded runs' own mean, 1 lower, it is not)
    obs, runs = _campaign(np.random.default_rng(7), 0.3, 0.0)
    runs = runs.astype({"seed": float})
    loose = runs[runs["seed"] == 0].assign(seed=np.nan, value=lambda d: d["value"] + 4.0)
    both = pd.concat([runs, loose], ignore_index=True)
    obs = obs.assign(measured=100.0 * (1 + A * 0.3) + 1.0)
    ed = sl.build_effect_data(obs, both, EFF, BOUNDS)
    j0 = [d["beta"] for d in ed.design].index(0.0)
    assert ed.means[j0] == pytest.approx(np.full(N, 101.0))
    y0 = ed.means[j0]
    x, _ = sl.Model([ed], y0, obs["measured"].to_numpy(float)).fit()
    assert x[0] == pytest.approx(0.3, abs=1e-6)
    lo, hi = sl.bootstrap_ci([ed], y0, obs["measured"].to_numpy(float), np.zeros(N), 50, x0=x)["rate_friction.beta"]
    assert lo == pytest.approx(0.3, abs=1e-6) and hi == pytest.approx(0.3, abs=1e-6)


def test_a_refit_from_an_earlier_answer_still_finds_a_lower_minimum():
    # one row measured at 100; the surrogate through the design points (monotone between
    # them) meets 100 only at beta = -0.3 and has a second, higher minimum (error 10 %) at the
    # design point 0.15: a search from 0.15 alone stays there
    design = sl.theta_design(EFF, BOUNDS, 5)
    betas = [d["beta"] for d in design]
    level = {-0.3: 100.0, -0.075: 130.0, 0.0: 125.0, 0.15: 110.0, 0.375: 130.0, 0.6: 140.0}
    assert sorted(level) == betas
    runs = pd.DataFrame([{"measurement": "m", "row": 1, "measure": "F_N", "seed": 0, "value": level[b],
                          "status": "ok", "t:beta": b} for b in betas])
    obs = pd.DataFrame({"measurement": ["m"], "row": [1], "measure": ["F_N"], "measured": [100.0]})
    ed = sl.build_effect_data(obs, runs, EFF, BOUNDS)
    x, _ = sl.Model([ed], np.array([125.0]), np.array([100.0])).fit(x0=[0.15])
    assert x[0] == pytest.approx(-0.3, abs=1e-9)


def test_the_fit_is_relative_to_the_rows_scale():
    # one row measured at -1 with the scale 10 (a quantity of both signs): the error of the
    # switched-off model (125 there) is (-1 - 125) / 10
    obs = pd.DataFrame({"measurement": ["m"], "row": [1], "measure": ["F_N"], "measured": [-1.0]})
    runs = pd.DataFrame([{"measurement": "m", "row": 1, "measure": "F_N", "seed": 0, "value": v, "status": "ok",
                          "t:beta": b} for b, v in ((-0.3, 100.0), (0.0, 125.0), (0.6, 140.0))])
    ed = sl.build_effect_data(obs, runs, EFF, BOUNDS)
    m = sl.Model([ed], np.array([125.0]), np.array([-1.0]), np.array([10.0]))
    assert m.errors(np.array([0.0])) == pytest.approx([-12.6])
    assert sl.Model([ed], np.array([125.0]), np.array([-1.0])).errors(np.array([0.0])) == pytest.approx([-126.0])


def test_one_row_two_seeds_the_interval_is_the_two_one_seed_fits_widened():
    # one row, a = 1, two seeds that sit d above and d below the design point's mean at every
    # design point: value = 100 (1 + beta) +- d, the measured value 100 (1 + 0.3) exactly
    # (no SD). A draw takes two seeds with replacement: both the first (probability 1/4), both
    # the second (1/4), or one of each (1/2); the draw's deviation from the mean, widened by
    # sqrt(n / (n - 1)) = sqrt(2), is +sqrt(2) d, -sqrt(2) d or 0, and the refit solves
    # 100 (1 + beta) + dev = 130 exactly: beta = 0.3 - dev / 100. With d = 10 / sqrt(2) the
    # draws are 0.2, 0.3 and 0.4, and 200 draws put far more than 2.5 % on each end, so the
    # 95 % percentile interval is (0.2, 0.4). Without the widening it would be
    # (0.3 -+ 0.0707); without resampling the seeds every draw refits 0.3.
    d = 10.0 / np.sqrt(2.0)
    runs = pd.DataFrame([{"measurement": "m", "row": 1, "measure": "F_N", "seed": s, "status": "ok",
                          "value": 100.0 * (1 + b["beta"]) + sign * d, "t:beta": b["beta"]}
                         for b in DESIGN for s, sign in ((0, 1.0), (1, -1.0))])
    obs = pd.DataFrame({"measurement": ["m"], "row": [1], "measure": ["F_N"], "measured": [130.0]})
    ed = sl.build_effect_data(obs, runs, EFF, BOUNDS)
    y0 = ed.surrogate([0.0])
    assert y0 == pytest.approx([100.0])
    lo, hi = sl.bootstrap_ci([ed], y0, np.array([130.0]), np.zeros(1), 200, x0=[0.3])["rate_friction.beta"]
    assert lo == pytest.approx(0.2, abs=1e-6) and hi == pytest.approx(0.4, abs=1e-6)
