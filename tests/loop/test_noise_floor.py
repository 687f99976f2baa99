"""The noise floor of the loop's error (soilcal.loop.residuals.noise_floor, loop_summary.csv's
``rmse_floor_percent`` and ``explained_percent``): the RMS relative error a model without any
misfit would show on the rows of the before/after figure, from the measured and seed
uncertainties alone; checked against the formula worked by hand, against the RMS error of
tables of pure noise, and left empty with its reason where an uncertainty is unknown."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from soilcal.loop import core, files
from soilcal.loop import residuals as rs
from soilcal.loop import standin as S
from soilcal.loop.residuals import noise_floor, observations, residual_frame, usable

from test_residuals import _cond, _runs


def _tool(row, responses):
    # a condition of its own (its own tool): rows of one table that run different simulations
    return _cond(row, responses, covariates={"tool": f"t{row}"}, quantities={"tool": f"t{row}"})


def test_the_floor_is_the_formula_worked_by_hand():
    # three conditions of one measured force, each with its measured SD over its repeats and
    # three seeds: per row (sd_m^2 / n_m + sd_s^2 / n_s) / measured^2
    conds = [_tool(1, [("F_N", 100.0, 6.0, 4)]), _tool(2, [("F_N", 200.0, 10.0, 5)]),
             _tool(3, [("F_N", 50.0, 1.0, 2)])]
    runs = _runs([(1, "F_N", s, v, "ok") for s, v in enumerate((90.0, 92.0, 94.0))]  # sd 2
                 + [(2, "F_N", s, v, "ok") for s, v in enumerate((196.0, 200.0, 204.0))]  # sd 4
                 + [(3, "F_N", s, v, "ok") for s, v in enumerate((49.0, 50.0, 51.0))])  # sd 1
    u = usable(residual_frame(observations(conds), runs))
    rows = [6.0 ** 2 / 4 / 100.0 ** 2 + 2.0 ** 2 / 3 / 100.0 ** 2,
            10.0 ** 2 / 5 / 200.0 ** 2 + 4.0 ** 2 / 3 / 200.0 ** 2,
            1.0 ** 2 / 2 / 50.0 ** 2 + 1.0 ** 2 / 3 / 50.0 ** 2]
    floor, note = noise_floor(u)
    assert floor == pytest.approx(math.sqrt(sum(rows) / 3), rel=1e-12)
    assert note == ""
    # over the rows of the before/after figure only (the first and third)
    floor, _ = noise_floor(u, np.array([True, False, True]))
    assert floor == pytest.approx(math.sqrt((rows[0] + rows[2]) / 2), rel=1e-12)


def test_the_floor_interval_by_hand():
    # the table above: six variance estimates, each its share T of floor^2 (its term over the 3
    # rows) on its own degrees of freedom d (repeats - 1, seeds - 1); Satterthwaite's
    # nu = (sum sigma^2)^2 / sum(sigma^4 / d) with sigma^4 / d estimated by T^2 / (d + 2) and
    # (sum sigma^2)^2 by (sum T)^2 - 2 sum T^2 / (d + 2) (E T^2 = sigma^4 (d + 2) / d for a
    # sample variance on d degrees of freedom); the interval floor sqrt(nu / chi2(nu) quantiles)
    conds = [_tool(1, [("F_N", 100.0, 6.0, 4)]), _tool(2, [("F_N", 200.0, 10.0, 5)]),
             _tool(3, [("F_N", 50.0, 1.0, 2)])]
    runs = _runs([(1, "F_N", s, v, "ok") for s, v in enumerate((90.0, 92.0, 94.0))]
                 + [(2, "F_N", s, v, "ok") for s, v in enumerate((196.0, 200.0, 204.0))]
                 + [(3, "F_N", s, v, "ok") for s, v in enumerate((49.0, 50.0, 51.0))])
    u = usable(residual_frame(observations(conds), runs))
    terms = [(6.0 ** 2 / 4 / 100.0 ** 2, 3), (2.0 ** 2 / 3 / 100.0 ** 2, 2),
             (10.0 ** 2 / 5 / 200.0 ** 2, 4), (4.0 ** 2 / 3 / 200.0 ** 2, 2),
             (1.0 ** 2 / 2 / 50.0 ** 2, 1), (1.0 ** 2 / 3 / 50.0 ** 2, 2)]
    share = [(t / 3, d) for t, d in terms]
    floor2 = sum(t for t, _ in share)
    quad = sum(t ** 2 / (d + 2) for t, d in share)
    nu = (floor2 ** 2 - 2 * quad) / quad
    lo, hi, dof = rs.floor_interval(u)
    assert dof == pytest.approx(nu, rel=1e-12)
    assert lo == pytest.approx(math.sqrt(floor2 * nu / stats.chi2.ppf(0.975, nu)), rel=1e-12)
    assert hi == pytest.approx(math.sqrt(floor2 * nu / stats.chi2.ppf(0.025, nu)), rel=1e-12)
    # an SD given without a repeat count is taken as known; a seed SD of 0 from two seeds is not:
    # it says nothing of how far the true seed scatter may lie above 0
    known = [_tool(i, [("F_N", v, 2.0, None)]) for i, v in ((1, 100.0), (2, 120.0))]
    exact = usable(residual_frame(observations(known), _runs([(1, "F_N", 0, 99.0, "ok"), (2, "F_N", 0, 118.0, "ok"),
                                                             (1, "F_N", 1, 99.0, "ok"), (2, "F_N", 1, 118.0, "ok")])))
    floor, _ = noise_floor(exact)  # (seed SD 0 over two seeds: an estimate, of unknown width)
    assert floor == pytest.approx(math.sqrt((2.0 ** 2 / 100.0 ** 2 + 2.0 ** 2 / 120.0 ** 2) / 2), rel=1e-12)
    assert all(math.isnan(x) for x in rs.floor_interval(exact))
    # the same seeds scattering: the measured SDs known, the interval that of the seeds alone
    seeds = _runs([(1, "F_N", 0, 98.0, "ok"), (2, "F_N", 0, 117.0, "ok"), (1, "F_N", 1, 100.0, "ok"),
                   (2, "F_N", 1, 119.0, "ok")])
    scatter = usable(residual_frame(observations(known), seeds))
    lo, hi, dof = rs.floor_interval(scatter)
    assert lo < noise_floor(scatter)[0] < hi and 1.0 < dof < math.inf


def test_the_floor_interval_covers_the_true_floor_at_its_level():
    # 300 seeded tables of 18 conditions whose SDs are estimates: each row's measured SD from 3
    # repeats (true 4 % or 8 % of the value) and seed SD from 3 seeds (true 6 %), so each sample
    # variance is sigma^2 chi-square(2) / 2; the true floor is sqrt(mean(sigma_m^2 / 3 +
    # sigma_s^2 / 3)).  The 95 % interval covers it in a share of the tables within the binomial
    # 99.9 % band about 0.95 (the chi-square reading is an approximation: 4000 such tables gave
    # 93.5 %, 280 of 300 expected, inside the band 271-296); without the (d + 2) correction of the
    # estimated shares it covered 99.2 %, outside.
    rng = np.random.default_rng(5)
    covered, trials = 0, 300
    for _ in range(trials):
        t = rng.uniform(50.0, 500.0, 18)
        sig_m = np.where(np.arange(18) % 2, 0.04, 0.08) * t
        sig_s = 0.06 * t
        df = pd.DataFrame({"measurement": "bin", "measure": "F_N", "simulation": [f"c{i}" for i in range(18)],
                           "measured": t, "scale": t,
                           "measured_sd": sig_m * np.sqrt(rng.chisquare(2, 18) / 2), "measured_n": 3.0,
                           "simulated_sd": sig_s * np.sqrt(rng.chisquare(2, 18) / 2), "simulated_n": 3.0})
        true = math.sqrt(float(np.mean((sig_m ** 2 / 3 + sig_s ** 2 / 3) / t ** 2)))
        lo, hi, _ = rs.floor_interval(df)
        covered += lo <= true <= hi
    a, b = stats.binom.ppf([0.0005, 0.9995], trials, 0.95)
    assert a <= covered <= b, (covered, a, b)


def test_a_missing_sd_takes_its_quantity_pooled_variance():
    # the third row gives no measured SD and ran one seed (no seed SD): its measured variance is
    # the relative SD pooled over the quantity's other rows, sum((n - 1)(sd / value)^2) /
    # sum(n - 1) = (3 (6/100)^2 + 4 (10/200)^2) / 7 per repeat, one repeat; its seed variance the
    # seeds' relative SD pooled the same way, (2 (2/100)^2 + 2 (4/200)^2) / 4, over one seed
    conds = [_tool(1, [("F_N", 100.0, 6.0, 4)]), _tool(2, [("F_N", 200.0, 10.0, 5)]),
             _tool(3, [("F_N", 50.0, None, None)])]
    runs = _runs([(1, "F_N", s, v, "ok") for s, v in enumerate((90.0, 92.0, 94.0))]
                 + [(2, "F_N", s, v, "ok") for s, v in enumerate((196.0, 200.0, 204.0))]
                 + [(3, "F_N", 0, 48.0, "ok")])
    u = usable(residual_frame(observations(conds), runs))
    pooled_m = (3 * (6.0 / 100) ** 2 + 4 * (10.0 / 200) ** 2) / 7
    pooled_s = (2 * (2.0 / 100) ** 2 + 2 * (4.0 / 200) ** 2) / 4
    rows = [6.0 ** 2 / 4 / 100.0 ** 2 + 2.0 ** 2 / 3 / 100.0 ** 2,
            10.0 ** 2 / 5 / 200.0 ** 2 + 4.0 ** 2 / 3 / 200.0 ** 2,
            pooled_m / 1 + pooled_s / 1]
    floor, note = noise_floor(u)
    assert floor == pytest.approx(math.sqrt(sum(rows) / 3), rel=1e-12)
    assert "1 of the 3 rows without a measured SD of their own" in note
    assert "1 of the 3 rows with one seed took their quantity's pooled seed SD" in note


def test_replicate_rows_without_an_sd_take_their_scatter():
    # one condition measured as three rows of one repeat each, no SD: 98, 100, 105 (sample SD
    # s); the seeds 99, 100, 101 (SD 1, three of them), shared by the three rows; each row's
    # variance s^2 + 1/3 over its own measured value squared
    conds = [_cond(i, [("F_N", v, None, None)]) for i, v in ((1, 98.0), (2, 100.0), (3, 105.0))]
    runs = _runs([(r, "F_N", s, v, "ok") for r in (1, 2, 3) for s, v in enumerate((99.0, 100.0, 101.0))])
    u = usable(residual_frame(observations(conds), runs))
    assert u["simulation"].nunique() == 1  # the three rows are one measured condition
    s2 = float(np.var([98.0, 100.0, 105.0], ddof=1))
    expected = math.sqrt(np.mean([(s2 + 1.0 / 3) / m ** 2 for m in (98.0, 100.0, 105.0)]))
    floor, note = noise_floor(u)
    assert floor == pytest.approx(expected, rel=1e-12)
    assert "replicate scatter" in note


def _pure_noise(n_rows, seed, seeds_exact):
    """A residual table of ``n_rows`` conditions of one force where the model holds: each
    truth T drawn in 50-500 N, its measured mean T + N(0, sd_m^2 / n_m) with the stated sd_m
    (2 % or 4 % of T) over n_m (3 or 5) repeats, its simulated mean T exactly with seed SD 0
    (``seeds_exact``), else T + N(0, sd_s^2 / n_s) with the stated sd_s (6 % of T) over 3 seeds."""
    rng = np.random.default_rng(seed)
    t = rng.uniform(50.0, 500.0, n_rows)
    rel_m = np.where(np.arange(n_rows) % 2, 0.02, 0.04)
    n_m = np.where(np.arange(n_rows) % 3, 3.0, 5.0)
    sd_m = rel_m * t
    sd_s, n_s = (np.zeros(n_rows), np.full(n_rows, 3.0)) if seeds_exact else (0.06 * t, np.full(n_rows, 3.0))
    measured = t + rng.standard_normal(n_rows) * sd_m / np.sqrt(n_m)
    simulated = t + rng.standard_normal(n_rows) * sd_s / np.sqrt(n_s)
    df = pd.DataFrame({"measurement": "bin", "row": np.arange(n_rows), "measure": "F_N",
                       "simulation": [f"c{i}" for i in range(n_rows)], "measured": measured, "measured_sd": sd_m,
                       "measured_n": n_m, "simulated_mean": simulated, "simulated_sd": sd_s, "simulated_n": n_s})
    df["scale"] = rs.scales(df)[0]
    df["relative_residual"] = (df["measured"] - df["simulated_mean"]) / df["scale"]
    return df


@pytest.mark.parametrize("seeds_exact", [True, False], ids=["simulated-is-truth", "simulated-within-its-seeds"])
def test_pure_noise_lands_on_the_floor_within_its_chi_square_band(seeds_exact):
    # where the model holds, each row's relative residual is normal with the variance v_i its
    # floor term states (the scale |measured| moves it by a few parts in 10^4 at 2-7 % noise),
    # so mean(r^2) = sum(v_i z_i^2) / N, a weighted sum of chi-square(1) variables: after
    # Satterthwaite (1946) floor^2 chi-square(nu) / nu with nu = (sum v)^2 / sum(v^2), here
    # 280 and 393 for 400 rows.  The RMS error lies within its two-sided 99.9 % band.
    u = _pure_noise(400, 11, seeds_exact)
    floor, note = noise_floor(u)
    assert note == ""
    scale = u["scale"].to_numpy()
    v = (u["measured_sd"] ** 2 / u["measured_n"] + u["simulated_sd"] ** 2 / u["simulated_n"]).to_numpy() / scale ** 2
    nu = v.sum() ** 2 / (v ** 2).sum()
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], nu) / nu
    rms = float(np.sqrt(np.mean(u["relative_residual"] ** 2)))
    assert lo * floor ** 2 <= rms ** 2 <= hi * floor ** 2, (rms, floor, lo, hi, nu)
    if not seeds_exact:
        # the band is narrow enough to tell a floor without the seeds' part (6 % over three seeds
        # beside 2-4 % over three to five repeats): it would lie outside it
        without = float(np.sqrt(np.mean((u["measured_sd"] ** 2 / u["measured_n"]).to_numpy() / scale ** 2)))
        assert not lo * without ** 2 <= rms ** 2 <= hi * without ** 2


def test_unknown_sds_leave_the_floor_empty_with_the_reason():
    # no measured SD anywhere, one row per condition: nothing says how far a measured value
    # strays from its truth
    conds = [_tool(i, [("F_N", v, None, None)]) for i, v in ((1, 100.0), (2, 120.0), (3, 90.0))]
    runs = _runs([(r, "F_N", s, v + s, "ok") for r, v in ((1, 98.0), (2, 118.0), (3, 91.0)) for s in range(3)])
    floor, note = noise_floor(usable(residual_frame(observations(conds), runs)))
    assert math.isnan(floor)
    assert "3 of the 3 rows have no measured SD" in note
    # one seed per condition and no seed SD to pool: the seed part is unknown
    conds = [_tool(i, [("F_N", v, 2.0, 3)]) for i, v in ((1, 100.0), (2, 120.0), (3, 90.0))]
    runs = _runs([(r, "F_N", 0, v, "ok") for r, v in ((1, 98.0), (2, 118.0), (3, 91.0))])
    floor, note = noise_floor(usable(residual_frame(observations(conds), runs)))
    assert math.isnan(floor)
    assert "3 of the 3 rows have one seed" in note


REF = {"tool_speed": 1.75, "working_depth": 0.1, "moisture_content": 16.0}


def _loop(sd: bool, hidden=None):
    from soilcal.loop import synthesize as sy

    conds = S.conditions(S.grid(2, 12, moisture=True), measures=("horizontal_force_N",))
    table = sy.synthesize(conds, S.base_params, S.simulate, hidden or {}, REF, {}, noise=0.02, seed=12)
    rows = sy.with_measured(conds, table)
    if not sd:
        rows = [replace(c, responses=tuple(dict(r, measured_sd=None, n=None) for r in c.responses)) for c in rows]
    settings = core.Settings(reference=REF, bootstrap=0)
    out = core.run_inprocess("bin", rows, S.base_params, S.simulate, settings)
    plan = files._plan("bin", out.candidates, REF, settings, core.quantity_of(rows), out.skipped, out.residuals)
    return out, files.report("bin", out, [plan])


def test_the_summary_and_report_give_the_floor_and_the_share_explained():
    out, text = _loop(True, {"rate_friction": {"beta": 0.2}})
    s = out.summary.iloc[0]
    cols = list(out.summary.columns)
    assert cols == core.SUMMARY_COLUMNS
    assert cols[cols.index("rmse_after_percent") + 1] == "rmse_floor_percent"
    u = usable(out.residuals)
    assert s["rmse_floor_percent"] == pytest.approx(100 * noise_floor(u)[0], rel=1e-12)
    b, a, f = s["rmse_before_percent"], s["rmse_after_percent"], s["rmse_floor_percent"]
    assert out.chosen == ["rate_friction"] and b > f
    assert s["explained_percent"] == pytest.approx(100 * (b ** 2 - a ** 2) / (b ** 2 - f ** 2), rel=1e-12)
    assert f"| the measured and seed uncertainty alone | {f:.2f} | |" in text
    assert f"The error the measured and seed uncertainty alone give is {f:.2f} %" in text
    lo, hi, nu = rs.floor_interval(u)
    lo, hi = 100 * lo, 100 * hi
    assert lo < f < hi and out.floor_interval == (pytest.approx(lo), pytest.approx(hi), pytest.approx(nu))
    assert f"(95 % interval {lo:.2f}-{hi:.2f} %: the SDs it comes from are estimates, on {nu:.0f} degrees" in text
    assert "of the explainable error, (before^2 - after^2) / (before^2 - floor^2)" in text


def test_the_share_explained_is_empty_where_the_error_before_is_within_the_floor():
    assert math.isnan(core.explained_percent(1.2, 1.1, 1.3))
    assert math.isnan(core.explained_percent(1.3, 1.1, math.nan))
    # before 5, after 3, floor 1: (25 - 9) / (25 - 1)
    assert core.explained_percent(5.0, 3.0, 1.0) == pytest.approx(100 * 16 / 24)


def test_the_share_explained_is_empty_where_the_error_before_lies_within_the_floor_interval():
    # before 1.4 above the floor 1.3 but within its interval's upper end 1.5: (1.96 - 1.21) /
    # (1.96 - 1.69) would read 278 %, a ratio set by the floor's own uncertainty
    assert math.isnan(core.explained_percent(1.4, 1.1, 1.3, 1.5))
    assert math.isnan(core.explained_percent(1.5, 1.1, 1.3, 1.5))
    # above the interval, or the interval unknown: the share as before, (25 - 9) / (25 - 1)
    assert core.explained_percent(5.0, 3.0, 1.0, 1.2) == pytest.approx(100 * 16 / 24)
    assert core.explained_percent(5.0, 3.0, 1.0, math.nan) == pytest.approx(100 * 16 / 24)


def test_a_table_without_sd_reports_no_floor_and_why():
    out, text = _loop(False)
    s = out.summary.iloc[0]
    assert math.isnan(s["rmse_floor_percent"]) and math.isnan(s["explained_percent"])
    assert "| the measured and seed uncertainty alone | not known | |" in text
    assert ("is not known: 12 of the 12 rows have no measured SD and their measured quantity none to take one from"
            in text), text


def test_a_pooled_replicate_scatter_is_per_repeat_over_each_rows_count():
    # one quantity without any SD column: condition A measured as three rows, each the mean of 2
    # repeats (98, 100, 105), condition B as one row, the mean of 4 repeats (200).  A's rows
    # scatter as sigma^2 / 2 of the per-repeat variance sigma^2, so their sample variance s^2
    # is each A row's variance and sigma^2 is estimated by 2 s^2; B, with no replicate rows of
    # its own, takes that per-repeat variance relative to A's mean scale over its own 4 repeats:
    # 2 s^2 / mean(A)^2 / 4, as a pooled measured SD is divided by the row's count.  (Taking A's
    # row scatter s^2 as B's variance would count B as one mean of 2 repeats, twice too large.)
    conds = [_cond(i, [("F_N", v, None, 2)]) for i, v in ((1, 98.0), (2, 100.0), (3, 105.0))]
    conds.append(_tool(4, [("F_N", 200.0, None, 4)]))
    runs = _runs([(r, "F_N", s, v, "ok") for r in (1, 2, 3) for s, v in enumerate((99.0, 100.0, 101.0))]
                 + [(4, "F_N", s, v, "ok") for s, v in enumerate((196.0, 200.0, 204.0))])
    u = usable(residual_frame(observations(conds), runs))
    assert u["simulation"].nunique() == 2
    s2 = float(np.var([98.0, 100.0, 105.0], ddof=1))
    mean_a = float(np.mean([98.0, 100.0, 105.0]))
    terms = {98.0: (s2 + 1.0 / 3) / 98.0 ** 2, 100.0: (s2 + 1.0 / 3) / 100.0 ** 2, 105.0: (s2 + 1.0 / 3) / 105.0 ** 2,
             200.0: 2 * s2 / mean_a ** 2 / 4 + 16.0 / 3 / 200.0 ** 2}
    expected = math.sqrt(np.mean([terms[v] for v in u["measured"]]))
    floor, note = noise_floor(u)
    assert floor == pytest.approx(expected, rel=1e-12)
    assert "replicate scatter" in note


def test_without_an_effect_the_report_claims_no_test_of_the_error_before_against_the_floor():
    # the stand-in campaign without a hidden effect: the verdict is the diagnosis's, and the
    # floor's interval (the SDs' uncertainty alone) is not set against the error before as if
    # it were a test of misfit
    out, text = _loop(True)
    assert not out.chosen
    s = out.summary.iloc[0]
    assert f"Beside the floor the error before ({s['rmse_before_percent']:.2f} %) tests nothing" in text
    assert "floor's 95 % interval" not in text
    for word in ("above", "below", "within"):
        assert f"lies {word} the floor" not in text


def test_the_report_says_when_the_floor_interval_is_unknown():
    from types import SimpleNamespace

    s = pd.Series({"rmse_floor_percent": 1.2, "rmse_before_percent": 1.5, "rmse_after_percent": 1.5,
                   "explained_percent": 36.0})
    o = SimpleNamespace(chosen=[], floor_note="", floor_interval=(math.nan, math.nan, math.nan))
    text = " ".join(files._floor_lines(s, o))
    assert "its 95 % interval is not known: an SD it comes from was estimated as 0" in text


class _FailedFolds:
    """soilcal.loop.select as core sees it, but the chosen effects' held-out errors of some rows
    missing, as where a fold's fit fails (too few rows left to fit): those rows are not
    held-out-valid, and the errors before and after, the floor and its interval leave them out."""

    def __init__(self, rows):
        from soilcal.loop import select

        self._select, self._rows = select, rows

    def __getattr__(self, name):
        return getattr(self._select, name)

    def cross_validate(self, model, folds):
        rms, held = self._select.cross_validate(model, folds)
        held[self._rows] = np.nan
        return rms, held


def test_the_floor_and_its_interval_are_those_of_the_held_out_valid_rows(monkeypatch):
    # the stand-in campaign with rate_friction hidden, the held-out errors of its four noisiest
    # rows (largest (sd_m^2 / n_m + sd_s^2 / n_s) / measured^2, from the table) missing: the floor
    # and its interval are those of the other eight rows, and neither all twelve nor the four
    # give them
    base, _ = _loop(True, {"rate_friction": {"beta": 0.2}})
    u = usable(base.residuals)
    term = ((u["measured_sd"] ** 2 / u["measured_n"] + u["simulated_sd"] ** 2 / u["simulated_n"])
            / u["measured"] ** 2).to_numpy()
    noisy = np.argsort(term)[-4:]
    monkeypatch.setattr(core, "sl", _FailedFolds(noisy))
    out, text = _loop(True, {"rate_friction": {"beta": 0.2}})
    assert out.chosen == ["rate_friction"]
    ok = np.ones(len(u), bool)
    ok[noisy] = False
    s = out.summary.iloc[0]
    assert s["rmse_before_percent"] == pytest.approx(100 * math.sqrt(np.mean(u["relative_residual"][ok] ** 2)))
    right, everything, wrong = (100 * noise_floor(u, m)[0] for m in (ok, None, ~ok))
    assert s["rmse_floor_percent"] == pytest.approx(right, rel=1e-12)
    assert abs(right - everything) > 0.02 * right and abs(right - wrong) > 0.02 * right
    lo, hi, nu = rs.floor_interval(u, ok)
    assert out.floor_interval == (pytest.approx(100 * lo, rel=1e-12), pytest.approx(100 * hi, rel=1e-12),
                                  pytest.approx(nu, rel=1e-12))
    for m in (None, ~ok):
        assert rs.floor_interval(u, m)[2] != pytest.approx(nu, rel=1e-3)


def _one_estimate(sd_s, n_s):
    # one row whose only estimated variance is its seed SD over n_s seeds: the measured value
    # is given as exact (SD 0 without a repeat count, taken as known)
    return pd.DataFrame({"measurement": "bin", "measure": "F_N", "simulation": "c0", "measured": [100.0],
                         "scale": [100.0], "measured_sd": [0.0], "measured_n": [np.nan],
                         "simulated_sd": [sd_s], "simulated_n": [float(n_s)]})


@pytest.mark.parametrize("n_s", [3, 5])
def test_one_estimated_variance_gives_its_exact_chi_square_interval(n_s):
    # floor^2 is then one sample variance T = sigma^2 chi-square(d) / d on d = n_s - 1 degrees of
    # freedom, whose exact interval is T d / chi2(d) quantiles: Satterthwaite's nu must be d.
    # With sigma^4 / d estimated by T^2 / (d + 2), the numerator's correction
    # (sum T)^2 - 2 sum T^2 / (d + 2) = T^2 d / (d + 2) gives nu = d exactly; (sum T)^2 alone
    # would give d + 2, an interval too narrow (at d = 2 it covers sigma in
    # exp(-0.121) - exp(-2.786) = 82.4 % of tables, not 95 %).
    d = n_s - 1
    df = _one_estimate(3.0, n_s)
    floor, _ = noise_floor(df)
    assert floor == pytest.approx(3.0 / math.sqrt(n_s) / 100.0, rel=1e-12)
    lo, hi, nu = rs.floor_interval(df)
    assert nu == pytest.approx(d, rel=1e-12)
    assert lo == pytest.approx(floor * math.sqrt(d / stats.chi2.ppf(0.975, d)), rel=1e-12)
    assert hi == pytest.approx(floor * math.sqrt(d / stats.chi2.ppf(0.025, d)), rel=1e-12)

