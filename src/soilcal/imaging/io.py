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
