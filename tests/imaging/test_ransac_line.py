"""measure.ransac_line against scikit-image's ransac with LineModelND, whose model and inliers
it must give unchanged (the same seeded draws, the same steps)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from skimage import measure as skm

from soilcal.imaging import measure


def _points(seed):
    """Points along a line with noise, a share of outliers scattered around it, some on a
    pixel grid (edge pixels: equal residuals, ties on the inlier count), some repeated (a pair
    of equal points gives a line of no direction)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 400))
    t = rng.uniform(0, 500, n)
    ang = rng.uniform(-np.pi, np.pi)
    pts = np.column_stack([t * np.cos(ang), t * np.sin(ang)]) + rng.normal(0, rng.uniform(0.1, 2.0), (n, 2))
    out = rng.random(n) < rng.uniform(0.0, 0.7)
    pts[out] = rng.uniform(-500, 500, (int(out.sum()), 2))
    if rng.random() < 0.4:
        pts = np.round(pts)
    if rng.random() < 0.3 and n > 4:
        pts[: n // 4] = pts[0]
    return pts


@pytest.mark.parametrize("seed", range(100))
def test_same_fit_as_scikit_image(seed):
    pts = _points(seed)
    thr = [0.5, 1.0, 1.5, 3.0][seed % 4]
    trials = [1, 7, 200, 500][seed // 4 % 4]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        want, win = skm.ransac(pts, skm.LineModelND, min_samples=2, residual_threshold=thr,
                               max_trials=trials, rng=seed)
        got, gin = measure.ransac_line(pts, residual_threshold=thr, max_trials=trials, rng=seed)
    if want is None:
        assert got is None and gin is None and win is None
        return
    assert np.array_equal(win, gin)
    assert np.array_equal(want.origin, got.origin) and np.array_equal(want.direction, got.direction)


def test_same_fit_on_ties_and_early_stop():
    """A straight run of grid points with a few off it: many draws give the same inlier count
    (the sum of squared residuals decides) and the trial limit falls as the inliers grow."""
    c = np.arange(300.0)
    pts = np.column_stack([c, np.round(0.02 * c + 40.0)])
    pts[::37, 1] += 6.0
    for seed in range(20):
        want, win = skm.ransac(pts, skm.LineModelND, min_samples=2, residual_threshold=1.0, max_trials=200, rng=seed)
        got, gin = measure.ransac_line(pts, residual_threshold=1.0, max_trials=200, rng=seed)
        assert np.array_equal(win, gin)
        assert np.array_equal(want.origin, got.origin) and np.array_equal(want.direction, got.direction)


def _same(pts, thr, trials, seed):
    want, win = skm.ransac(pts, skm.LineModelND, min_samples=2, residual_threshold=thr, max_trials=trials, rng=seed)
    got, gin = measure.ransac_line(pts, residual_threshold=thr, max_trials=trials, rng=seed)
    assert np.array_equal(win, gin)
    assert np.array_equal(want.origin, got.origin) and np.array_equal(want.direction, got.direction)
    return gin


@pytest.mark.parametrize("seed", range(4))
def test_equal_count_and_sum_keeps_the_first(seed):
    """Two rows of points, the same columns 10 px apart: a line along either has as many
    inliers and the same residual sum (its own row 0 px, the other 10 px off): the first
    drawn stays, as there."""
    c = np.arange(0.0, 60.0, 3.0)
    pts = np.concatenate([np.column_stack([c, np.zeros_like(c)]), np.column_stack([c, np.full_like(c, 10.0)])])
    inl = _same(pts, 1.0, 50, seed)
    assert inl.sum() == len(c)


def test_residual_at_threshold_is_no_inlier():
    """Edge pixels on a row and a few on the row below, one trial: a line through two of the
    first row is exactly 1 px from the second, which at a threshold of 1 px is outside, as
    there (the inliers are the first row alone)."""
    c = np.arange(40.0)
    pts = np.concatenate([np.column_stack([c, np.zeros_like(c)]), np.column_stack([c[::4], np.ones(10)])])
    seeds = [s for s in range(10) if (np.random.default_rng(s).choice(len(pts), 2, replace=False) < 40).all()]
    assert len(seeds) >= 3
    for seed in seeds:
        assert _same(pts, 1.0, 1, seed).sum() == 40


def test_no_inliers_gives_no_model():
    """Residuals that are all NaN never make a trial the best: no model, as scikit-image."""
    pts = np.array([[0.0, 0.0], [np.nan, 1.0], [2.0, np.nan]])
    with pytest.warns(UserWarning, match="No inliers"):
        want = skm.ransac(pts, skm.LineModelND, min_samples=2, residual_threshold=1.0, max_trials=10, rng=0)
    with pytest.warns(UserWarning, match="No inliers"):
        got = measure.ransac_line(pts, residual_threshold=1.0, max_trials=10, rng=0)
    assert want == got == (None, None)
