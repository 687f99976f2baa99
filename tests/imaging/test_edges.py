"""The photo measurement's Canny edges and circle Hough transform (:mod:`soilcal.imaging.edges`)
give scikit-image's numbers to the last bit: the same edge maps and accumulators as
``skimage.feature.canny`` and ``skimage.transform.hough_circle``, whatever the image."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi
from skimage import draw, feature, transform

from soilcal.imaging import edges


def _scene(shape, seed):
    """A smooth random grey image with a few steps in it: edges of every strength."""
    rng = np.random.default_rng(seed)
    img = ndi.gaussian_filter(rng.random(shape), 3.0)
    rr, cc = np.mgrid[0:shape[0], 0:shape[1]]
    img += 0.3 * (rr > shape[0] * rng.uniform(0.3, 0.7)) + 0.2 * ((cc - shape[1] / 2) ** 2 + rr ** 2 < shape[1] ** 2 / 9)
    return img / img.max()


@pytest.mark.parametrize("kw", [{"sigma": 1.5}, {"sigma": 2.0, "low_threshold": 0.02, "high_threshold": 0.05},
                                {"sigma": 1.0, "low_threshold": 0.05}, {}])
def test_canny_is_scikit_images(kw):
    # more shapes than the division images kept, each met twice (the second from the cache,
    # unless pushed out meanwhile), a constant image (no edge at all) and a grey one of 8 bits
    # (left to scikit-image)
    shapes = [(60, 80), (61, 80), (60, 81), (47, 33), (90, 120), (60, 80), (47, 33)]
    for k, shape in enumerate(shapes):
        img = _scene(shape, k)
        got, want = edges.canny(img, **kw), feature.canny(img, **kw)
        assert got.dtype == want.dtype and np.array_equal(got, want), (shape, kw)
    flat = np.full((40, 50), 0.5)
    assert np.array_equal(edges.canny(flat, **kw), feature.canny(flat, **kw)) and not edges.canny(flat, **kw).any()
    grey8 = (_scene((50, 70), 9) * 255).astype(np.uint8)
    assert np.array_equal(edges.canny(grey8, **kw), feature.canny(grey8, **kw))


def test_canny_keeps_a_few_division_images_and_leaves_them_unchanged():
    for k in range(edges._BLEED_KEPT + 3):
        edges.canny(_scene((30 + k, 40), k), sigma=1.5)
    assert len(edges._bleed) == edges._BLEED_KEPT
    bleed, _ = edges._bleed_over((30, 40), 1.5)
    assert not bleed.flags.writeable
    with pytest.raises(ValueError):
        edges.canny(_scene((30, 40), 0), sigma=1.5, low_threshold=0.3, high_threshold=0.2)


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
