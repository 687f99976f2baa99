"""The one-parameter surrogate (soilcal.loop.select.Surrogate, smooth_fits): a least-squares
quadratic through the design's seed means where it follows them within the seed scatter, an
interpolant where it does not.

Expected values by construction: design means that are a line in the parameter plus a
pattern orthogonal to 1, theta and theta^2 over the design points are fitted by the
quadratic exactly as the line, so measured values on that line give back its parameter to
rounding; the lack-of-fit F and its p follow from the sums of squares the values were built
with (Montgomery, Design and Analysis of Experiments: lack of fit against pure error, here the
point x seed interaction of a two-way layout without replication)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from soilcal.loop import select as sl
from soilcal.loop.effects import EFFECTS

EFF = EFFECTS["rate_friction"]
BOUNDS = {"beta": (-0.3, 0.6)}
DESIGN = sl.theta_design(EFF, BOUNDS, 5)  # -0.3, -0.075, 0, 0.15, 0.375, 0.6
T = np.array([d["beta"] for d in DESIGN])
N, SEEDS = 12, 3
A = np.linspace(-1.0, 1.0, N)


def _orthogonal() -> np.ndarray:
    """A unit pattern over the design points orthogonal to 1, theta and theta^2."""
    B = np.column_stack([np.ones_like(T), T, T ** 2])
    r = np.array([1.0, -2.0, 0.5, 3.0, -1.0, 0.25])
    r = r - B @ np.linalg.lstsq(B, r, rcond=None)[0]
    return r / np.linalg.norm(r)


def _seed_pattern() -> np.ndarray:
    """Deviations over points x seeds with zero mean over the seeds and over the points, unit sum of squares."""
    rng = np.random.default_rng(0)
    e = rng.standard_normal((len(T), SEEDS))
    e = e - e.mean(axis=1, keepdims=True) - e.mean(axis=0, keepdims=True) + e.mean()
    return e / np.linalg.norm(e)


def _values(lof: float, scatter: float, seed_level: float = 0.0) -> np.ndarray:
    """points x rows x seeds: 100 (1 + a_i theta) + lof * pattern (sign by row) + scatter * the
    seed pattern + each seed's own level (shared by every point: common random numbers)."""
    r, e = _orthogonal(), _seed_pattern()
    V = np.empty((len(T), N, SEEDS))
    for i in range(N):
        V[:, i, :] = (100.0 * (1 + A[i] * T))[:, None] + lof * (-1) ** i * r[:, None] + scatter * e \
            + seed_level * np.array([-1.0, 0.5, 2.0])[None, :] * (i + 1)
    return V


def _runs(V: np.ndarray) -> pd.DataFrame:
    return pd.DataFrame([{"measurement": "m", "row": i + 1, "measure": "F_N", "seed": s, "value": V[d, i, s],
                          "status": "ok", "t:beta": T[d]}
                         for d in range(len(T)) for i in range(N) for s in range(SEEDS)])


def _obs(beta: float) -> pd.DataFrame:
    return pd.DataFrame({"measurement": "m", "row": np.arange(1, N + 1), "measure": "F_N",
                         "measured": 100.0 * (1 + A * beta)})


def test_lack_of_fit_p_from_the_sums_of_squares():
    lof, scatter = 0.4, 2.0
    smooth, p = sl.smooth_fits(T[:, None], _values(lof, scatter))
    # per row: lack-of-fit SS = SEEDS * lof^2 (unit pattern orthogonal to the quadratic), error
    # SS = scatter^2 (unit interaction pattern); pooled over N rows
    f = (N * SEEDS * lof ** 2 / (N * (len(T) - 3))) / (N * scatter ** 2 / (N * (len(T) - 1) * (SEEDS - 1)))
    assert p == pytest.approx(stats.f.sf(f, N * (len(T) - 3), N * (len(T) - 1) * (SEEDS - 1)), rel=1e-9)
    assert smooth == (p >= sl.LACK_OF_FIT_ALPHA)


def test_the_seeds_own_levels_do_not_count_as_scatter():
    # common random numbers: a seed's level shared by every design point cancels in the changes
    assert sl.smooth_fits(T[:, None], _values(0.4, 2.0, seed_level=50.0))[1] == pytest.approx(
        sl.smooth_fits(T[:, None], _values(0.4, 2.0))[1], rel=1e-9)


def test_within_the_scatter_the_quadratic_gives_back_the_parameter():
    # the orthogonal pattern (5 % of the force) within a seed scatter that holds it: the
    # quadratic takes the line, and measured values on the line give its beta to rounding;
    # an interpolant through the means follows the pattern and misses it
    V = _values(5.0, 40.0)
    ed = sl.build_effect_data(_obs(0.3), _runs(V), EFF, BOUNDS)
    assert ed.surrogate.smooth and ed.lack_of_fit_p >= sl.LACK_OF_FIT_ALPHA
    y0 = ed.means[list(T).index(0.0)]
    x, _ = sl.Model([ed], y0, _obs(0.3)["measured"].to_numpy(float)).fit()
    assert x[0] == pytest.approx(0.3, abs=1e-7)


def test_beyond_the_scatter_the_surrogate_interpolates():
    # the same pattern with little seed scatter: the quadratic does not follow the means, so the
    # surrogate goes through them (a response that saturates keeps its shape)
    V = _values(5.0, 0.5)
    ed = sl.build_effect_data(_obs(0.3), _runs(V), EFF, BOUNDS)
    assert not ed.surrogate.smooth and ed.lack_of_fit_p < sl.LACK_OF_FIT_ALPHA
    for d, t in enumerate(T):
        assert ed.surrogate([t]) == pytest.approx(V[d].mean(axis=1), rel=1e-12)


def test_no_smoothing_without_scatter_or_with_too_few_points():
    assert not sl.smooth_fits(T[:, None], _values(0.0, 0.0))[0]  # no scatter: nothing to smooth away
    assert not sl.smooth_fits(T[:3, None], _values(0.4, 2.0)[:3])[0]
    assert not sl.smooth_fits(T[:, None], _values(0.4, 2.0)[:, :, :1])[0]
    assert not sl.smooth_fits(T[:, None], None)[0]
