"""Canny edges of the photo measurement: the numbers of ``skimage.feature.canny`` (scikit-image
0.26, which ``pyproject.toml`` pins) with less work done for them.

scikit-image smooths the image with a Gaussian that treats the pixels beyond its border as 0 and
divides by the same Gaussian of an all-ones image (the share of each pixel's weights that falls
inside the image), which depends only on the image's shape and the sigma.  A heap photo's Canny
edges are taken four times (luminance and L*, a*, b*) at one shape and sigma, and a drum group's
frames are all of one size: that division image is computed once per shape and sigma
(:data:`_BLEED_KEPT` of them kept) instead of once per call."""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

#: the division images of :func:`canny` kept, by (shape, sigma), the latest used last
_BLEED_KEPT = 4
_bleed = OrderedDict()


def _bleed_over(shape, sigma):
    """scikit-image's Canny bleed-over image for an image of ``shape`` and ``sigma`` (the
    Gaussian, zero beyond the border, of an all-ones image, plus the float64 epsilon) and its
    eroded mask (all True but the outermost pixels): the same arrays as its ``_preprocess``
    makes without a mask, kept for the next image of that shape and sigma (the bleed-over
    read only; the mask is read only too, but scikit-image's Cython takes only writable ones)."""
    from skimage.filters import gaussian

    key = (tuple(shape), float(sigma))
    if key in _bleed:
        _bleed.move_to_end(key)
        return _bleed[key]
    ones = np.ones(shape, dtype=np.float64)
    bleed = gaussian(ones, sigma=sigma, mode="constant", cval=0.0, preserve_range=False) + np.finfo(np.float64).eps
    eroded = np.ones(shape, dtype=bool)
    eroded[:1, :] = 0
    eroded[-1:, :] = 0
    eroded[:, :1] = 0
    eroded[:, -1:] = 0
    bleed.flags.writeable = False
    _bleed[key] = bleed, eroded
    while len(_bleed) > _BLEED_KEPT:
        _bleed.popitem(last=False)
    return bleed, eroded


def canny(image, sigma=1.0, low_threshold=None, high_threshold=None):
    """``skimage.feature.canny(image, sigma, low_threshold, high_threshold)`` (no mask, the image
    zero beyond its border, thresholds in the image's units): the same edge map, the bleed-over
    division image shared by the images of one shape and sigma (module text).  An image other
    than a 2-D float64 one is left to scikit-image."""
    from scipy import ndimage as ndi
    from skimage import feature

    image = np.asarray(image)
    if image.ndim != 2 or image.dtype != np.float64:
        return feature.canny(image, sigma=sigma, low_threshold=low_threshold, high_threshold=high_threshold)
    from skimage.feature._canny_cy import _nonmaximum_suppression_bilinear
    from skimage.filters import gaussian

    # a float image's range is (-1, 1): the thresholds are divided by 1, as skimage divides them
    low_threshold = 0.1 if low_threshold is None else low_threshold / 1
    high_threshold = 0.2 if high_threshold is None else high_threshold / 1
    if high_threshold < low_threshold:
        raise ValueError("low_threshold should be lower then high_threshold")
    bleed, eroded = _bleed_over(image.shape, sigma)
    smoothed = gaussian(image, sigma=sigma, mode="constant", cval=0.0, preserve_range=False)
    smoothed /= bleed
    jsobel = ndi.sobel(smoothed, axis=1)
    isobel = ndi.sobel(smoothed, axis=0)
    magnitude = isobel * isobel
    magnitude += jsobel * jsobel
    np.sqrt(magnitude, out=magnitude)
    low_masked = _nonmaximum_suppression_bilinear(isobel, jsobel, magnitude, eroded, low_threshold)
    # hysteresis: the 8-connected runs above the low threshold that reach the high one
    low_mask = low_masked > 0
    labels, count = ndi.label(low_mask, np.ones((3, 3), bool))
    if count == 0:
        return low_mask
    high_mask = low_mask & (low_masked >= high_threshold)
    good = np.zeros((count + 1,), bool)
    good[np.unique(labels[high_mask])] = True
    return good[labels]
