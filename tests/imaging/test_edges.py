"""The drum's circle Hough transform (:mod:`soilcal.imaging.edges`) gives scikit-image's
numbers to the last bit: the same accumulators as ``skimage.transform.hough_circle``,
whatever the image."""

from __future__ import annotations

import numpy as np
import pytest
from skimage import draw, transform

from soilcal.imaging import edges


@pytest.mark.parametrize("density", [0.002, 0.02, 0.15])
def test_hough_circle_is_scikit_images(density):
    # random edge maps (any nonzero pixel votes once), radii from small to larger than the
    # image, and a drawn circle: every centre's votes as scikit-image adds them
    rng = np.random.default_rng(int(density * 1000))
    img = rng.random((70, 90)) < density
    rr, cc = draw.circle_perimeter(35, 40, 22, shape=img.shape)
    img[rr, cc] = True
    weights = img * rng.integers(1, 255, img.shape)  # a grey edge map: nonzero is an edge
    for radii in (np.arange(5, 40), np.array([22]), np.arange(60, 64), np.arange(1, 4)):
        want = transform.hough_circle(weights, radii)
        got = edges.hough_circle(weights, radii)
        assert got.dtype == want.dtype and got.shape == want.shape and np.array_equal(got, want), radii


def test_hough_circle_votes_of_one_edge_pixel():
    # one edge pixel far from the border votes 1 / n at each point of each circle around it, and
    # twice that where circle_perimeter lists a point twice (the octants' shared points)
    img = np.zeros((41, 41), bool)
    img[20, 20] = True
    r = 7
    rr, cc = draw.circle_perimeter(0, 0, r)
    n = rr.size
    acc = edges.hough_circle(img, [r])[0]
    pts, times = np.unique(np.column_stack([rr + 20, cc + 20]), axis=0, return_counts=True)
    assert times.max() == 2  # some points listed twice
    for (y, x), t in zip(pts, times):
        assert acc[y, x] == (1.0 / n if t == 1 else 1.0 / n + 1.0 / n)
    assert np.count_nonzero(acc) == len(pts)


def test_hough_circle_of_no_radius_is_scikit_images():
    # no radius: an empty accumulator of the image's shape, (0, rows, columns), as scikit-image's
    img = np.zeros((30, 45), bool)
    img[10, 5:40] = True
    for radii in ([], np.array([], int)):
        want = transform.hough_circle(img, radii)
        got = edges.hough_circle(img, radii)
        assert want.shape == (0, 30, 45) and got.shape == want.shape and got.dtype == want.dtype
