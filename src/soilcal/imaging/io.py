"""Reading photos: any file PIL can decode completely; anything else is an InputError."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def read_photo(path) -> np.ndarray:
    """RGB float image in [0, 1]; unreadable, truncated or blank files raise InputError."""
    from PIL import Image, UnidentifiedImageError

    from soilcal.errors import InputError

    p = Path(path)
    if not p.is_file():
        raise InputError(p, "file", "an existing image file", "missing")
    try:
        with Image.open(p) as im:
            im.load()  # decodes fully: a truncated JPEG raises OSError here
            rgb = np.asarray(im.convert("RGB"), dtype=float) / 255.0
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as exc:
        raise InputError(p, "file", "a complete, readable image (JPEG/PNG/TIFF)", str(exc)) from None
    if rgb.ndim != 3 or min(rgb.shape[:2]) < 64:
        raise InputError(p, "file", "an image of at least 64 x 64 pixels", rgb.shape)
    if float(rgb.std()) < 0.01:
        raise InputError(p, "image", "a photo with contrast (heap against background)", "a blank image")
    return rgb


# full scale of PIL's single-channel modes; RGB-like modes go through luminance
_FULL_SCALE = {"1": 1.0, "L": 255.0, "I;16": 65535.0, "I;16L": 65535.0, "I;16B": 65535.0, "I;16N": 65535.0}


def read_gray(path):
    """(grey image in [0, 1], RGB view for figures) of any PIL-readable frame.

    Single-channel 8-bit and 16-bit frames (BMP/PNG/TIFF, PIL modes L, I;16, I) are scaled
    by their bit depth and not converted through RGB (which would clip 16-bit data); colour
    images give their luminance.  The grey range is then stretched between its 0.5 and 99.5
    percentiles, so a 12-bit camera in a 16-bit container reads like any other frame.
    """
    from PIL import Image, UnidentifiedImageError
    from skimage.color import rgb2gray

    from soilcal.errors import InputError

    p = Path(path)
    if not p.is_file():
        raise InputError(p, "file", "an existing image file", "missing")
    try:
        with Image.open(p) as im:
            im.load()
            mode, rgb = im.mode, None
            if mode in _FULL_SCALE:
                g = np.asarray(im, dtype=float) / _FULL_SCALE[mode]
            elif mode in ("I", "F"):
                g = np.asarray(im, dtype=float)
                g = g / (65535.0 if mode == "I" and g.max() <= 65535 else max(float(g.max()), 1e-12))
            else:
                rgb = np.asarray(im.convert("RGB"), dtype=float) / 255.0
                g = rgb2gray(rgb)
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as exc:
        raise InputError(p, "file", "a complete, readable image (BMP/PNG/TIFF/JPEG)", str(exc)) from None
    if g.ndim != 2 or min(g.shape) < 64:
        raise InputError(p, "file", "an image of at least 64 x 64 pixels", g.shape)
    lo, hi = np.percentile(g, [0.5, 99.5])
    if hi - lo < 0.005:
        raise InputError(p, "image", "a frame with contrast (powder against air)", "a blank image")
    g = np.clip((g - lo) / (hi - lo), 0.0, 1.0)
    return g, (rgb if rgb is not None else np.repeat(g[..., None], 3, axis=-1))
