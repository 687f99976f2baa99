"""The photo measurement's Canny edges (:mod:`soilcal.imaging.edges`) give scikit-image's numbers
to the last bit: the same edge maps as ``skimage.feature.canny``, whatever the image."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi
from skimage import feature

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
