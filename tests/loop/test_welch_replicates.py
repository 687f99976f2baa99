"""Replicate rows of one condition whose quantity's SDs are not pooled: each row gives its mean,
SD and number of repeats, and a replicate day may be noisier than another (another rig, fewer
repeats).  The null hypothesis of no scatter beyond the measurement is one true mean for the
condition's rows, not one true SD: their scatter is Welch's heteroscedastic ANOVA.

Construction: each row the mean and sample SD of n normal repeats of SD sd about one value, so
every condition is a true null and a test at 0.05 rejects 5 % of conditions (Welch's F
approximation: 5 % at equal SDs, up to about 8 % where a row has 2 degrees of freedom)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from soilcal.loop import residuals as rs


def _rate(n, sd, conditions=1000, seed=3):
    rng = np.random.default_rng(seed)
    n, sd = np.asarray(n), np.asarray(sd, float)
    p = np.empty(conditions)
    for i in range(conditions):
        x = [20.0 + s * rng.standard_normal(k) for k, s in zip(n, sd)]
        m = np.array([v.mean() for v in x])
        s = np.array([v.std(ddof=1) for v in x])
        p[i] = stats.chi2.sf(rs.replicate_scatter_chi(m, s ** 2 / n, 0.0, s, n), len(n) - 1)
    return float(np.mean(p < 0.05))


def test_welch_anova_is_scipys_on_the_raw_values():
    rng = np.random.default_rng(11)
    groups = [rng.normal(3.0, s, k) for s, k in ((1.0, 10), (1.0, 10), (3.0, 3), (0.5, 6))]
    m = [g.mean() for g in groups]
    sd = [g.std(ddof=1) for g in groups]
    n = [len(g) for g in groups]
    want = stats.f_oneway(*groups, equal_var=False).pvalue
    assert abs(rs.welch_anova_p(m, sd, n) - want) < 1e-10


def test_equal_sds_hold_the_level():
    # 1000 conditions: binomial SD of the rate at 5 % is 0.7 %
    assert abs(_rate((10, 10, 10), (1, 1, 1)) - 0.05) < 0.021


@pytest.mark.parametrize("n, sd", [((10, 10, 3), (1, 1, 3)), ((20, 3), (1, 4))])
def test_a_noisier_day_with_fewer_repeats_is_no_scatter(n, sd):
    """A third day of 3 repeats at 3 times the SD (or 3 at 4 times beside 20): an SD pooled
    over the condition's rows takes the noisy day's mean against the quiet days' SD, and put
    25 % and 41 % of these null conditions at p < 0.05; Welch 6.6 % and 5.5 %.  Bound: 12 %,
    over 4 binomial SDs (0.9 %) above Welch's 8 % where such a row is alone (4000 conditions)."""
    assert _rate(n, sd) < 0.12
