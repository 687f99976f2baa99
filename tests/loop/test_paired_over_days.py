"""The paired test of the held-out error where the folds are test days
(``soilcal.loop.select.paired_p``): over four days or more the conditions' gains are tested,
their mean against the larger of the between-day and within-day mean squares (the conditions
of a day share its fit, so the between-day one can be the larger); over fewer days, over the
days.  The expected values are the t statistics and mean squares worked by hand from the
constructed errors."""

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


def _days(day_mean=DAY_MEAN, pattern=PATTERN):
    per = len(pattern)
    d = (day_mean[:, None] + pattern[None, :]).ravel()  # conditions, day by day
    ref_held = np.full(d.size, REF)
    held = REF - d  # the model's held-out error (all positive here)
    folds = sl.Folds([np.arange(per * k, per * k + per) for k in range(len(day_mean))],
                     units=[np.array([i]) for i in range(d.size)])
    rms = lambda e: np.array([math.sqrt(np.mean(e[f] ** 2)) if np.all(np.isfinite(e[f])) else math.nan  # noqa: E731
                              for f in folds.held_out])
    return rms(ref_held), rms(held), ref_held, held, folds


def test_days_as_alike_as_chance_are_tested_over_the_conditions_with_the_within_mean_square():
    # day means 0.06, 0.03, 0.07, 0.04 (mean 0.05): MS between = 5 x (0.01^2 + 0.02^2 + 0.02^2
    # + 0.01^2) / 3 = 0.005 / 3; MS within = 4 x 0.04 / 16 = 0.01, the larger: t = 0.05 /
    # sqrt(0.01 / 20) = sqrt(5) on 16 df
    p = sl.paired_p(*_days(np.array([0.06, 0.03, 0.07, 0.04])))
    assert (p.test, p.variance, p.df) == ("conditions", "within", 16)
    assert math.isclose(p.ms_between, 0.005 / 3, rel_tol=1e-9) and math.isclose(p.ms_within, 0.01, rel_tol=1e-9)
    assert math.isclose(p.p, stats.t.sf(math.sqrt(5), 16), rel_tol=1e-9) and p.p < 0.05


def test_days_that_differ_more_than_their_conditions_take_the_between_mean_square():
    # day means 0.10, -0.01, 0.07, 0.04: MS between = 5 x (0.05^2 + 0.06^2 + 0.02^2 + 0.01^2) / 3
    # = 0.011 > MS within 0.01: t = 0.05 / sqrt(0.011 / 20) on 3 df, not significant, where the
    # within mean square alone (t = sqrt(5), 16 df) would have passed it
    p = sl.paired_p(*_days())
    assert (p.test, p.variance, p.df) == ("conditions", "between", 3)
    assert math.isclose(p.ms_between, 0.011, rel_tol=1e-9)
    assert math.isclose(p.p, stats.t.sf(0.05 / math.sqrt(0.011 / 20), 3), rel_tol=1e-9) and p.p > 0.05
    # the pattern 10 % larger: MS within = 1.21 x 0.01 = 0.0121 > 0.011, so the within one is taken
    q = sl.paired_p(*_days(pattern=1.1 * PATTERN))
    assert (q.test, q.variance, q.df) == ("conditions", "within", 16)
    assert math.isclose(q.p, stats.t.sf(0.05 / math.sqrt(0.0121 / 20), 16), rel_tol=1e-9)


def test_fewer_than_four_days_keep_the_test_over_the_days():
    # the first three days of the four: the test is over their RMS errors, 2 df
    ref_rms, fold_rms, ref_held, held, folds = _days(DAY_MEAN[:3])
    p = sl.paired_p(ref_rms, fold_rms, ref_held, held, folds)
    assert (p.test, p.df) == ("folds", 2) and sl.MIN_POOLED_FOLDS == 4
    assert p.p == stats.ttest_rel(ref_rms, fold_rms, alternative="greater").pvalue
    # two days of five conditions: over the two days, 1 df
    ref_rms, fold_rms, ref_held, held, folds = _days(DAY_MEAN[:2])
    p = sl.paired_p(ref_rms, fold_rms, ref_held, held, folds)
    assert (p.test, p.df) == ("folds", 1)
    assert p.p == stats.ttest_rel(ref_rms, fold_rms, alternative="greater").pvalue


def test_a_condition_without_a_finite_error_is_left_out_of_the_conditions():
    ref_rms, fold_rms, ref_held, held, folds = _days()
    held = held.copy()
    held[3] = math.nan  # day 1's fourth condition could not be predicted
    p = sl.paired_p(ref_rms, fold_rms, ref_held, held, folds)
    # the mean squares by their definitions over the 19 others (day 1 holds four)
    d = (REF - np.delete(held, 3))
    g = np.repeat(np.arange(4), 5)[np.arange(20) != 3]
    m = d.mean()
    msb = sum((g == j).sum() * (d[g == j].mean() - m) ** 2 for j in range(4)) / 3
    msw = sum(((d[g == j] - d[g == j].mean()) ** 2).sum() for j in range(4)) / 15
    assert math.isclose(p.ms_within, msw, rel_tol=1e-9) and math.isclose(p.ms_between, msb, rel_tol=1e-9)
    df = 3 if msb >= msw else 15
    assert p.df == df and math.isclose(p.p, stats.t.sf(m / math.sqrt(max(msb, msw) / 19), df), rel_tol=1e-9)


def test_folds_of_single_conditions_are_tested_as_before():
    ref_rms, fold_rms, ref_held, held, folds = _days()
    single = sl.Folds([np.array([i]) for i in range(20)])
    p = sl.paired_p(np.abs(ref_held), np.abs(held), ref_held, held, single)
    assert (p.test, p.df) == ("folds", 19)
    assert p.p == stats.ttest_rel(np.abs(ref_held), np.abs(held), alternative="greater").pvalue
