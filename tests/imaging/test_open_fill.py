"""The segmentation's speck opening and hole filling (``measure.open_fill``) against the library
operations it stands for: scikit-image's opening (reflected at the border) followed by scipy's
``binary_fill_holes``, on masks with specks, holes, objects cut by the border and holes that
reach it."""
import numpy as np
from scipy import ndimage as ndi
from skimage import morphology

from soilcal.imaging.measure import SPECK_FOOTPRINT, open_fill


def _reference(mask):
    return ndi.binary_fill_holes(morphology.opening(mask, SPECK_FOOTPRINT))


def test_open_fill_equals_opening_then_fill_holes_on_random_masks():
    rng = np.random.default_rng(20261130)
    for _ in range(200):
        h, w = rng.integers(5, 90, 2)
        field = ndi.gaussian_filter(rng.random((h, w)), rng.uniform(0.0, 3.0))
        mask = field > np.quantile(field, rng.uniform(0.2, 0.8))
        np.testing.assert_array_equal(open_fill(mask), _reference(mask))


def test_a_hole_is_filled_a_bay_open_to_the_border_is_not_and_a_speck_goes():
    mask = np.zeros((40, 60), bool)
    mask[5:30, 5:30] = True
    mask[12:20, 12:20] = False  # a hole: filled
    mask[20:40, 40:55] = True
    mask[25:40, 45:50] = False  # a bay reaching the bottom border: stays background
    mask[2, 50] = True  # a speck smaller than the footprint: opened away
    out = open_fill(mask)
    assert out[15, 15] and not out[35, 47] and not out[2, 50]
    np.testing.assert_array_equal(out, _reference(mask))
