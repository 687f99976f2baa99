"""The paired test of the held-out error where the folds are test days: over four days it has
three degrees of freedom, and a gain that is the same on every day but scatters from
condition to condition (a DEM's seed scatter) did not pass it; where the days' differences do
not differ (one-way ANOVA), the test is over the conditions (``soilcal.loop.select.paired_p``).
The expected values are the t statistics worked by hand from the constructed errors."""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from soilcal.loop import select as sl

#: the within-day pattern of a condition's gain (reference |error| - model |error|), and each
#: day's mean gain: 4 days x 5 conditions
PATTERN = np.array([0.1, -0.1, 0.1, -0.1, 0.0])
DAY_MEAN = np.array([0.10, -0.01, 0.07, 0.04])
REF = 1.0  # the reference's held-out relative error of every condition


def _days(day_mean=DAY_MEAN):
    d = (day_mean[:, None] + PATTERN[None, :]).ravel()  # 20 conditions, day by day
    ref_held = np.full(d.size, REF)
    held = REF - d  # the model's held-out error (all positive here)
    folds = sl.Folds(np.arange(5 * k, 5 * k + 5) for k in range(len(day_mean)))
    folds.units = [np.array([i]) for i in range(d.size)]
    rms = lambda e: np.array([math.sqrt(np.mean(e[f] ** 2)) for f in folds])  # noqa: E731
    return rms(ref_held), rms(held), ref_held, held, folds


def test_a_gain_alike_on_every_day_is_tested_over_the_conditions():
    ref_rms, fold_rms, ref_held, held, folds = _days()
    # by hand: gains d = day mean + pattern; mean 0.05; squares about the mean: 0.04 per day
    # from the pattern + 5 x (0.05^2 + 0.06^2 + 0.02^2 + 0.01^2) = 0.033 from the day means
    n, ss = 20, 4 * 0.04 + 5 * (0.05 ** 2 + 0.06 ** 2 + 0.02 ** 2 + 0.01 ** 2)
    t_conditions = 0.05 / math.sqrt(ss / (n - 1) / n)
    assert math.isclose(t_conditions, 2.2184, rel_tol=1e-4)
    # the days differ by no more than chance: F = MS between / MS within = (0.033 / 3) / (0.16 / 16) = 1.1
    f_days = stats.f_oneway(*[ref_held[f] - held[f] for f in folds])
    assert math.isclose(f_days.statistic, 1.1, rel_tol=1e-9) and f_days.pvalue > sl.POOL_ALPHA
    p = sl.paired_p(ref_rms, fold_rms, ref_held, held, folds)
    assert math.isclose(p, stats.t.sf(t_conditions, n - 1), rel_tol=1e-9)
    assert p < 0.05
    # over the four days' RMS errors alone (three degrees of freedom) the same gain is not
    # significant: the test the loop made before
    over_days = stats.ttest_rel(ref_rms, fold_rms, alternative="greater").pvalue
    assert over_days > 0.05


def test_days_that_differ_keep_the_test_over_the_days():
    # one day carries the whole gain (a day's offset followed through a covariate): the
    # conditions are not independent draws, and the test stays over the four days
    day_mean = np.array([0.6, 0.0, 0.0, 0.0])
    ref_rms, fold_rms, ref_held, held, folds = _days(day_mean)
    # by hand: mean gain 0.15; MS between = 5 x (0.45^2 + 3 x 0.15^2) / 3 = 0.45, MS within 0.16 / 16 = 0.01
    f_days = stats.f_oneway(*[ref_held[f] - held[f] for f in folds])
    assert math.isclose(f_days.statistic, 45.0, rel_tol=1e-9) and f_days.pvalue < sl.POOL_ALPHA
    p = sl.paired_p(ref_rms, fold_rms, ref_held, held, folds)
    assert p == stats.ttest_rel(ref_rms, fold_rms, alternative="greater").pvalue
    assert p > 0.05
    # over the conditions it would have passed
    assert stats.ttest_1samp(ref_held - held, 0.0, alternative="greater").pvalue < 0.05


def test_folds_of_single_conditions_are_tested_as_before():
    ref_rms, fold_rms, ref_held, held, folds = _days()
    single = sl.Folds(np.array([i]) for i in range(20))
    p = sl.paired_p(np.abs(ref_held), np.abs(held), ref_held, held, single)
    assert p == stats.ttest_rel(np.abs(ref_held), np.abs(held), alternative="greater").pvalue
