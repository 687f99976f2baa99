"""measure.hough_peaks against scikit-image's hough_line_peaks, whose peaks it must give
unchanged (it finds them on the part of the accumulator above the threshold)."""

from __future__ import annotations

import numpy as np
import pytest
from skimage import draw, feature, transform

from soilcal.imaging import measure


def _accumulator(seed, rows=401, cols=121):
    """Background votes below the threshold everywhere, clusters of votes above it in the
    middle, beside the first and last angle bins (where the suppression wraps the angle and
    reflects the distance) and at the distance bins the reflection maps them to."""
    rng = np.random.default_rng(seed)
    hs = rng.integers(0, 40, (rows, cols)).astype(np.uint64)
    for _ in range(40):
        r = int(rng.integers(5, rows - 5))
        c = int(rng.choice([rng.integers(0, 4), rng.integers(cols - 4, cols), rng.integers(0, cols)]))
        hs[r, c] = rng.integers(60, 200)
        # its reflection across the angle wrap, a rival the suppression may remove
        hs[rows - r, cols - 1 - c] = rng.integers(60, 200)
        if rng.random() < 0.5:  # a plateau of equal votes: the rounded centroid decides
            hs[r, max(c - 1, 0)] = hs[r, c]
        elif rng.random() < 0.5:
            hs[r + 1, c] = hs[r, c]
    # two equal peaks two distance bins apart, the first in bin 0: the suppression around the
    # second leaves bin 0 alone
    hs[0, cols // 2] = hs[2, cols // 2] = 150
    hs[1, cols // 2] = 0
    return hs


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("min_distance, min_angle, num_peaks", [(4, 10, 16), (2, 10, 8), (9, 3, np.inf)])
def test_same_peaks_as_scikit_image(seed, min_distance, min_angle, num_peaks):
    hs = _accumulator(seed)
    angles = np.linspace(-0.3, 0.3, hs.shape[1])
    dists = np.linspace(-200.0, 200.0, hs.shape[0])
    for a in (hs, hs.astype(float)):
        want = transform.hough_line_peaks(a, angles, dists, min_distance=min_distance, min_angle=min_angle,
                                          threshold=50.0, num_peaks=num_peaks)
        got = measure.hough_peaks(a, angles, dists, num_peaks, min_distance, 50.0, min_angle=min_angle)
        assert len(want[0]) > 5
        for x, y in zip(want, got):
            assert np.array_equal(x, y)


def test_same_peaks_on_a_photo_s_edges():
    """A plate search's accumulator (0.05 deg steps over 15 deg either side of horizontal) of
    the Canny edges of a drawn plate, table edge and heap outline."""
    img = np.zeros((300, 400))
    img[200:, :] = 0.5
    img[240:, :] = 0.2
    rr, cc = draw.polygon([200, 120, 200], [100, 190, 300])
    img[rr, cc] = 0.8
    edges = feature.canny(img, sigma=1.5)
    thetas = np.radians(np.linspace(75.0, 105.0, 601))
    hs, ang, dist = transform.hough_line(edges, theta=thetas)
    want = transform.hough_line_peaks(hs, ang, dist, num_peaks=16, min_distance=4, threshold=0.1 * 400)
    got = measure.hough_peaks(hs, ang, dist, 16, 4, 0.1 * 400)
    assert len(want[0]) >= 3
    for x, y in zip(want, got):
        assert np.array_equal(x, y)


def test_no_votes_above_the_threshold():
    hs = np.ones((50, 20), np.uint64)
    v, a, d = measure.hough_peaks(hs, np.linspace(0, 1, 20), np.arange(50.0), 8, 4, 5.0)
    assert v.size == a.size == d.size == 0


def test_a_plateau_peak_is_placed_as_scikit_image_places_it():
    """Peaks of two equal bins, their centroids half a bin between them (rounded half to even),
    in an accumulator whose votes above the threshold begin at an odd distance and angle bin."""
    hs = np.zeros((301, 121), np.uint64)
    hs[101:103, 51] = 100  # two distance bins
    hs[201, 71:73] = 90  # two angle bins
    hs[251, 101] = 80
    angles, dists = np.linspace(-0.3, 0.3, 121), np.linspace(-150.0, 150.0, 301)
    want = transform.hough_line_peaks(hs, angles, dists, min_distance=4, threshold=50.0, num_peaks=8)
    got = measure.hough_peaks(hs, angles, dists, 8, 4, 50.0)
    assert len(want[0]) == 3
    for x, y in zip(want, got):
        assert np.array_equal(x, y)


@pytest.mark.parametrize("seed", range(4))
def test_random_accumulators_give_scikit_image_s_peaks(seed):
    """Seeded random non-negative accumulators (integer votes, floats, plateaus, sparse peaks on
    the borders, blocks of equal votes whose corners touch), thresholds equal to a bin's votes
    (0 among them) or between them, min_angle up to past the angle count."""
    rng = np.random.default_rng(seed)
    for it in range(150):
        rows, cols = int(rng.integers(3, 60)), int(rng.integers(2, 40))
        kind = it % 5
        if kind == 0:
            hs = rng.integers(0, 6, (rows, cols)).astype(np.uint64)
        elif kind == 1:
            hs = rng.random((rows, cols))
        elif kind == 2:
            hs = (rng.integers(0, 3, (rows, cols)) * rng.integers(0, 2, (rows, cols))).astype(float)
        elif kind == 3:
            hs = np.zeros((rows, cols), np.uint64)
            for _ in range(int(rng.integers(1, 8))):
                r = int(rng.choice([0, rows - 1, rng.integers(0, rows)]))
                c = int(rng.choice([0, cols - 1, rng.integers(0, cols)]))
                hs[r, c] = rng.integers(1, 5)
        else:
            hs = np.kron(rng.integers(0, 4, (rows // 3 + 1, cols // 3 + 1)),
                         np.ones((3, 3), int))[:rows, :cols].astype(np.uint64)
        md, ma = int(rng.integers(1, 8)), int(rng.integers(1, 15))
        th = float(rng.choice(np.unique(hs))) if rng.random() < 0.6 else float(rng.random() * hs.max())
        num = int(rng.integers(1, 6)) if rng.random() < 0.5 else np.inf
        angles = np.linspace(-np.pi / 2, np.pi / 2, cols, endpoint=False)
        dists = np.arange(rows) - rows // 2.0
        want = transform.hough_line_peaks(hs, angles, dists, min_distance=md, min_angle=ma, threshold=th,
                                          num_peaks=num)
        got = measure.hough_peaks(hs, angles, dists, num, md, th, min_angle=ma)
        for x, y in zip(want, got):
            assert np.array_equal(x, y), (seed, it)


def test_diagonal_neighbours_are_one_peak_and_a_zero_threshold_skips_suppressed_bins():
    hs = np.zeros((40, 30), np.uint64)
    hs[10, 10] = hs[11, 11] = 7  # touching at a corner only: one region, as scikit-image labels
    hs[30, 5] = 3
    angles, dists = np.linspace(-0.5, 0.5, 30), np.arange(40.0)
    for th in (0.0, 2.0):
        want = transform.hough_line_peaks(hs, angles, dists, min_distance=2, min_angle=2, threshold=th)
        got = measure.hough_peaks(hs, angles, dists, np.inf, 2, th, min_angle=2)
        for x, y in zip(want, got):
            assert np.array_equal(x, y)


@pytest.mark.parametrize("slope,intercept", [(0.0, 40.0), (0.0, 41.0), (0.5, 10.0), (3.0, -100.0),
                                             (-3.0, 200.0), (0.0, 61.0), (0.0, 60.0), (0.125, 30.0),
                                             (0.125, 29.0), (-0.25, 41.0), (40.0, -1000.0)])
def test_components_on_the_plate_as_when_every_row_is_labelled(slope, intercept):
    """_components_on_plate labels the rows above the plate line's lowest point only: the same
    component (or the same refusal) as labelling the whole photo, for flat, steep, exact-integer
    and out-of-frame lines."""
    from skimage import measure as skm

    h, w = 60, 80
    rng = np.random.default_rng(5)
    for b in (np.pad(np.ones((25, 25), bool), ((20, 15), (25, 30))), rng.random((h, w)) < 0.5,
              np.ones((h, w), bool)):
        rr, cols = np.arange(h)[:, None], np.arange(w)[None, :]
        plate_rows = slope * cols + intercept
        above = b & (rr < plate_rows - 1)
        lab = skm.label(above)
        touching = np.unique(lab[(rr > plate_rows - 8) & above])
        touching = touching[touching > 0]
        try:
            got = measure._components_on_plate("p", b, slope, intercept, "heap")
        except Exception as e:  # noqa: BLE001 - compared with the full-height labelling below
            got = e
        if not touching.size:
            assert isinstance(got, Exception)
        elif not isinstance(got, Exception):
            area = np.bincount(lab.ravel())
            assert np.array_equal(got, lab == touching[np.argmax(area[touching])])
