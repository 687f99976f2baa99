"""A heap photo reads the same in every colour mode a camera or an editor may save it in: CMYK,
palette, with alpha, grey, and 16-bit grey (scaled by its bit depth, not clipped to 8 bits)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from soilcal.imaging import measure
from soilcal.imaging.io import read_photo

PILE = Path(__file__).resolve().parents[2] / "resources/images/cinnamon-soil/stacking_1.jpg"


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    d = tmp_path_factory.mktemp("modes")
    with Image.open(PILE) as im:
        rgb = im.resize((im.width // 2, im.height // 2), Image.LANCZOS)
    rgb.save(d / "rgb.png")
    return d, rgb, measure.measure_pile(d / "rgb.png").angle_deg


def _sixteen_bit(rgb: Image.Image) -> Image.Image:
    grey = np.asarray(rgb.convert("L"), dtype=np.uint16) * 257
    return Image.fromarray(grey)  # mode I;16


@pytest.mark.parametrize("name,make", [
    ("cmyk.jpg", lambda im: im.convert("CMYK")),
    ("palette.png", lambda im: im.convert("P")),
    ("alpha.png", lambda im: im.convert("RGBA")),
    ("grey.png", lambda im: im.convert("L")),
    ("grey_alpha.png", lambda im: im.convert("LA")),
    ("grey16.png", _sixteen_bit),
    ("grey16.tif", _sixteen_bit),
])
def test_colour_mode_measures_like_rgb(reference, name, make):
    d, rgb, angle = reference
    p = d / name
    make(rgb).save(p)
    img = read_photo(p)
    assert img.shape == (rgb.height, rgb.width, 3) and 0.0 <= img.min() and img.max() <= 1.0
    assert abs(measure.measure_pile(p).angle_deg - angle) <= 0.3


def test_sixteen_bit_photo_is_not_clipped(reference):
    d, rgb, _ = reference
    p = d / "dark16.png"
    # a 12-bit camera in a 16-bit container: every value below 4096
    Image.fromarray((np.asarray(rgb.convert("L"), dtype=np.uint16) * 16)).save(p)
    img = read_photo(p)
    assert img.std() > 0.1  # stretched over its range, not read as black or white


def test_edge_median_is_numpys_median():
    """The top-edge refinement's median (a sort of a few pixels, not NumPy's call) gives
    NumPy's number: odd and even lengths, ties, signed zeros, NaN, empty."""
    import warnings

    rng = np.random.default_rng(3)
    cases = [rng.random(n) for n in (1, 2, 5, 6, 12) for _ in range(200)]
    cases += [np.round(rng.random(6) * 4) / 4 for _ in range(200)]  # ties
    cases += [np.array([0.0, -0.0, 0.0, -0.0, 1.0, -1.0]), np.array([1.0, np.nan, 0.5])]
    for a in cases:
        assert np.array_equal(np.float64(measure._median(a)), np.median(a), equal_nan=True), a
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert np.isnan(measure._median(np.array([])))
