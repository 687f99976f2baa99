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


def _grey_alpha16_png(path, grey: np.ndarray, orientation: int | None = None) -> None:
    """A PNG of colour type 4 (grey + alpha) at 16 bits per sample, as a scientific camera or an
    editor writes one (PIL cannot write it): ``grey`` uint16, the alpha opaque; ``orientation``:
    an EXIF orientation in an eXIf chunk."""
    import struct
    import zlib

    h, w = grey.shape
    pix = np.stack([grey, np.full_like(grey, 65535)], axis=-1).astype(">u2").reshape(h, -1)
    raw = b"".join(b"\x00" + row.tobytes() for row in pix)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    exif = b""
    if orientation is not None:  # a big-endian TIFF header and one IFD entry: Orientation (SHORT)
        exif = chunk(b"eXIf", b"MM\x00\x2a\x00\x00\x00\x08\x00\x01" + struct.pack(">HHIHH", 0x0112, 3, 1, orientation, 0)
                     + b"\x00\x00\x00\x00")
    Path(path).write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 4, 0, 0, 0)) + exif
                           + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


@pytest.mark.parametrize("top", [65535, 4095, 3932])  # full range, a 12-bit camera's, 6 % of the range
def test_grey_alpha_16_bit_png_is_read_at_16_bits(tmp_path, top):
    # a heap of flanks 32 and 35 deg: PIL reads the grey of such a PNG at its upper 8 bits, which
    # a 12-bit camera's values fill to 16 of 256 (refused as flat), a dim one's to none (blank)
    from test_user_photos import heap_photo

    from soilcal.imaging.io import _decode

    grey = np.round(heap_photo().mean(axis=-1) * top).astype(np.uint16)
    p = tmp_path / "grey_alpha16.png"
    _grey_alpha16_png(p, grey)
    mode, g, rgb, shown, _ = _decode(p, "PNG")
    assert mode == "I;16" and shown == (400, 300) and np.array_equal(np.round(g * 65535), grey)
    r = measure.measure_pile(p)
    assert abs(r.left_deg - 32.0) <= 0.5 and abs(r.right_deg - 35.0) <= 0.5, (r.left_deg, r.right_deg)


def test_grey_alpha_16_bit_png_is_turned_as_shown(tmp_path):
    # stored sideways, its eXIf orientation 6 (shown turned 90 deg clockwise)
    from soilcal.imaging.io import _decode

    grey = (np.arange(300)[:, None] * 100 + np.arange(400)[None, :]).astype(np.uint16)
    p = tmp_path / "sideways.png"
    _grey_alpha16_png(p, np.ascontiguousarray(np.rot90(grey, 1)), orientation=6)
    mode, g, _, shown, _ = _decode(p, "PNG")
    assert shown == (400, 300) and np.array_equal(np.round(g * 65535), grey)


def test_grey_alpha_16_bit_png_is_read_with_tiles_as_plain_tuples(tmp_path, monkeypatch):
    # Pillow before 11 (pillow>=10.0 is required) keeps a decoder tile as a plain 4-tuple, not
    # the ImageFile._Tile NamedTuple: the tile is read by position, not by attribute
    from PIL import ImageFile
    from test_user_photos import heap_photo

    from soilcal.imaging.io import _decode

    monkeypatch.setattr(ImageFile, "_Tile", lambda *a: tuple(a), raising=False)
    grey = np.round(heap_photo().mean(axis=-1) * 4095).astype(np.uint16)
    p = tmp_path / "grey_alpha16.png"
    _grey_alpha16_png(p, grey)
    with Image.open(p) as im:
        assert all(type(t) is tuple for t in im.tile)
    mode, g, _, shown, _ = _decode(p, "PNG")
    assert mode == "I;16" and shown == (400, 300) and np.array_equal(np.round(g * 65535), grey)


def test_a_heic_photo_reads_as_its_jpeg_does_turned_as_shown(reference, tmp_path):
    """An iPhone's HEIC: read through pillow-heif, as its JPEG is; one stored sideways with an
    EXIF orientation (6: turn 90 deg clockwise to show it) reads as the upright photo, as a
    viewer shows it (pillow-heif applies the stored rotation and leaves the orientation 1)."""
    import pillow_heif

    pillow_heif.register_heif_opener()
    _, rgb, angle = reference
    p = tmp_path / "heap.heic"
    rgb.save(p, quality=92)
    assert Image.open(p).format == "HEIF"
    assert abs(measure.measure_pile(p).angle_deg - angle) <= 0.3
    side = rgb.transpose(Image.Transpose.ROTATE_90)  # as the sensor stored it: shown by turning it back
    exif = Image.Exif()
    exif[0x0112] = 6
    q = tmp_path / "heap_sideways.heic"
    side.save(q, quality=92, exif=exif.tobytes())
    img = read_photo(q)
    assert img.shape == (rgb.height, rgb.width, 3)
    assert abs(measure.measure_pile(q).angle_deg - angle) <= 0.3


def test_a_heic_photo_without_pillow_heif_is_refused_naming_it(reference, tmp_path, monkeypatch):
    import builtins

    import pillow_heif

    from soilcal.errors import InputError
    from soilcal.imaging import io

    pillow_heif.register_heif_opener()
    _, rgb, _ = reference
    p = tmp_path / "heap.heic"
    rgb.save(p, quality=80)
    real_import = builtins.__import__

    def no_heif(name, *args, **kwargs):
        if name == "pillow_heif":
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    io._heif_opener.cache_clear()
    monkeypatch.setattr(builtins, "__import__", no_heif)
    try:
        with pytest.raises(InputError) as e:
            read_photo(p)
    finally:
        io._heif_opener.cache_clear()  # the next photo imports pillow-heif again
    assert e.value.field == "file" and "pillow-heif" in str(e.value) and "export it as JPEG" in str(e.value)
