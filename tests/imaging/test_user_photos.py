"""Heap photos made the way users take them, drawn here from their construction: a heap of
known flank angles (relative to the plate's top edge) on a plate, before a wall, with grain,
lighting and the file formats a phone or an editor writes.  Each expected value is the angle
the heap was drawn with."""

from __future__ import annotations

import re

import numpy as np
import pytest
from PIL import Image
from skimage import filters, transform

from soilcal.imaging import measure


def heap_photo(h=300, w=400, left=32.0, right=35.0, apex_col=None, height=0.3, plate_row=None,
               wall=(0.75, 0.72, 0.65), soil=(0.45, 0.33, 0.22), plate=(0.35, 0.35, 0.38), grain=0.15,
               tilt=0.0, noise=0.01, seed=0):
    """RGB float image: a heap whose left and right flanks rise at ``left`` and ``right`` deg
    from the plate's top edge (row ``plate_row``, default 0.72 h: on a pixel boundary when
    0.72 h is whole), the apex ``height`` h above it at column ``apex_col``; ``tilt``: the
    camera's roll (deg, counter-clockwise), applied to the whole scene."""
    rng = np.random.default_rng(seed)
    rr, cc = np.mgrid[0:h, 0:w].astype(float)
    img = np.empty((h, w, 3))
    img[:] = wall
    prow = 0.72 * h if plate_row is None else plate_row
    img[rr >= prow] = plate
    ac = 0.5 * w if apex_col is None else apex_col
    hh = height * h
    tl, tr = np.tan(np.radians(left)), np.tan(np.radians(right))
    top = np.maximum(prow - hh + (ac - cc) * tl, prow - hh + (cc - ac) * tr)
    heap = (rr >= top) & (rr < prow)
    img[heap] = soil
    img[heap] += grain * filters.gaussian(rng.normal(size=(h, w)), 1.0)[heap][:, None]
    img = filters.gaussian(img, 0.8, channel_axis=-1)
    if tilt:
        img = transform.rotate(img, tilt, mode="edge", order=1)
    return np.clip(img + rng.normal(scale=noise, size=img.shape), 0.0, 1.0)


def _u8(img):
    return Image.fromarray(np.round(img * 255).astype(np.uint8))


def _assert_flanks(r, left, right, tol=0.5):
    assert abs(r.left_deg - left) <= tol and abs(r.right_deg - right) <= tol, (r.left_deg, r.right_deg)


@pytest.mark.parametrize("orientation,stored", [
    (6, Image.Transpose.ROTATE_90),    # phone upright: shown turned 90 deg clockwise
    (8, Image.Transpose.ROTATE_270),   # phone upright the other way
    (3, Image.Transpose.ROTATE_180),   # phone upside down
])
def test_phone_photo_is_measured_as_shown(tmp_path, orientation, stored):
    # the pixels are stored in the sensor's orientation, the EXIF tag says how to show them
    p = tmp_path / f"phone{orientation}.jpg"
    exif = Image.Exif()
    exif[0x0112] = orientation
    _u8(heap_photo()).transpose(stored).save(p, quality=90, exif=exif)
    r = measure.measure_pile(p)
    _assert_flanks(r, 32.0, 35.0)
    assert abs(r.roll_deg) <= 0.2


def test_plate_edge_on_a_pixel_boundary(tmp_path):
    # the plate's top edge between rows 215 and 216: Canny marks it on either row, by the noise;
    # the heap covers two thirds of the plate's width
    p = tmp_path / "level.jpg"
    _u8(heap_photo(h=300, w=400)).save(p, quality=85)
    r = measure.measure_pile(p)
    _assert_flanks(r, 32.0, 35.0)
    assert abs(r.roll_deg) <= 0.2


def test_wide_grainy_heap_is_measured_on_its_plate(tmp_path):
    # the heap covers 83 % of the plate's width; near-horizontal runs of its grain line up
    # into edges above the plate, which must not be taken for it
    p = tmp_path / "wide.jpg"
    _u8(heap_photo(h=300, w=350, left=30.0, right=30.0, height=0.28, apex_col=200.0)).save(p, quality=85)
    r = measure.measure_pile(p)
    _assert_flanks(r, 30.0, 30.0)
    assert abs(r.roll_deg) <= 0.3  # the plate's edge is 60 px long beside the heap


def test_coarse_grained_heap_lines_up_no_false_plate(tmp_path):
    # clods and coarse grain line up into near-horizontal edges inside the heap, above its
    # foot; a line through them does not run on over the wall beside the heap
    p = tmp_path / "coarse.jpg"
    _u8(heap_photo(grain=0.35)).save(p, quality=85)
    r = measure.measure_pile(p)
    _assert_flanks(r, 32.0, 35.0)
    assert abs(r.roll_deg) <= 0.2


def test_large_photo_is_measured_at_the_working_size(tmp_path, monkeypatch):
    # a phone's 12 megapixels stand in here as four times the working size: the heap is
    # measured on the photo reduced to it, at the angles it was drawn with
    monkeypatch.setattr(measure, "PILE_WORK_PIXELS", 30_000)
    p = tmp_path / "large.jpg"
    _u8(heap_photo(h=300, w=400)).save(p, quality=90)
    r = measure.measure_pile(p, keep_stages=True)
    assert r.stages.rgb.shape[0] * r.stages.rgb.shape[1] <= 30_000
    assert r.stages.rgb.shape[1] == pytest.approx(200, abs=1)
    _assert_flanks(r, 32.0, 35.0)


@pytest.mark.parametrize("suffix", [".jpg", ".png"])
def test_large_photo_is_decoded_reduced(tmp_path, monkeypatch, suffix):
    # a phone's portrait photo four times the working size: a JPEG is decoded at half size by
    # its decoder, a PNG box-averaged before it becomes floats; neither is held at full size,
    # and both are measured as shown, at the angles drawn
    from PIL import ImageFile

    from soilcal.imaging import io

    monkeypatch.setattr(measure, "PILE_WORK_PIXELS", 30_000)
    decoded = []
    load = ImageFile.ImageFile.load

    def spy(im):
        out = load(im)
        decoded.append(im.size)
        return out

    monkeypatch.setattr(ImageFile.ImageFile, "load", spy)
    p = tmp_path / f"large{suffix}"
    exif = Image.Exif()
    exif[0x0112] = 6
    _u8(heap_photo(h=300, w=400)).transpose(Image.Transpose.ROTATE_90).save(p, exif=exif)
    rgb, shown = io.read_photo_reduced(p, 30_000)
    assert shown == (400, 300) and rgb.shape == (150, 200, 3)
    if suffix == ".jpg":
        assert decoded and max(w * h for w, h in decoded) == 150 * 200
    r = measure.measure_pile(p)
    assert r.work_scale == pytest.approx(0.5)
    _assert_flanks(r, 32.0, 35.0)


def test_a_plate_hardly_wider_than_its_heap_is_still_the_plate(tmp_path):
    """A plate that reaches only a few pixels beyond the heap's foot shows almost no edge beside
    it: no line passes the beside check, so the first line that gave a heap is the plate, and
    the result says so (plate_beside)."""
    light = (0.6, 0.6, 0.62)  # a plate lighter than the soil: its edge under the heap shows
    img = heap_photo(seed=5, plate=light)
    h, w = img.shape[:2]
    prow = 0.72 * h
    rr, cc = np.mgrid[0:h, 0:w]
    # the heap (apex 90 px above the plate at column 200) has its foot at columns 56 and 328;
    # the plate spans columns 50-334, the wall continues below it beside the plate
    clean = heap_photo(seed=5, grain=0.0, noise=0.0, plate=light)
    img[(rr >= prow) & ((cc < 50) | (cc > 334))] = clean[0, 0]
    p = tmp_path / "narrow_plate.png"
    _u8(img).save(p)
    r = measure.measure_pile(p)
    _assert_flanks(r, 32.0, 35.0)
    assert r.plate_beside.startswith("line 1: a line through the heap"), r.plate_beside
    assert abs(r.geometry[1] - prow) < 1.5  # measured on the plate's top edge


@pytest.mark.parametrize("gain,clip", [(0.5, False), (1 / 8, False), (1 / 0.3, True)])
def test_exposure_a_heap_can_be_read_at_else_refused(tmp_path, gain, clip):
    # a dim photo spanning half the grey range is measured at the angles drawn; one
    # under-exposed into an eighth of it, or over-exposed until the wall, the plate and most
    # of the heap are white, leaves too few grey levels to find the plate and flanks: refused
    from soilcal.errors import InputError

    p = tmp_path / "exposed.jpg"
    _u8(np.clip(heap_photo() * gain, 0.0, 1.0)).save(p, quality=90)
    if gain == 0.5:
        _assert_flanks(measure.measure_pile(p), 32.0, 35.0)
        return
    with pytest.raises(InputError) as e:
        measure.measure_pile(p)
    assert e.value.path == str(p) and e.value.field == "image"
    assert "at least 32 of its 256 grey levels" in e.value.expected


@pytest.mark.parametrize("gain,seed", [(1 / 6, 1), (1 / 6, 2), (1 / 12, 2), (1.0, 2)])
def test_a_heap_exposed_into_few_levels_beside_a_bright_window(tmp_path, gain, seed):
    # the heap, its plate and wall under-exposed into a sixth or a twelfth of the range while a
    # window (white) and a dark object in the top corners give the photo as a whole its 256
    # levels: the photo's own grey-level check let it through and the heap read 1.1 to 1.3 deg
    # off as "ok" (seed 2); the levels are counted around the heap, and it is refused.  Exposed
    # for the heap, the same scene is measured at the angles drawn
    from soilcal.errors import InputError

    img = heap_photo(seed=seed) * gain
    img[10:60, 20:120] = 1.0
    img[10:60, 300:380] = 0.0
    p = tmp_path / "window.jpg"
    _u8(img).save(p, quality=90)
    if gain == 1.0:
        _assert_flanks(measure.measure_pile(p), 32.0, 35.0)
        return
    with pytest.raises(InputError) as e:
        measure.measure_pile(p)
    assert (e.value.path, e.value.field) == (str(p), "image")
    assert e.value.expected.startswith("heap, plate and wall around the heap spanning at least 32 of 256 grey levels")


def png16(path, a, sbit=None):
    """A PNG of 16 bits per channel of the uint16 image ``a`` (rows x columns x 3), as libpng
    writes one: its rows filtered in turn by each of the five PNG filters (none, sub, up,
    average, Paeth), which reach back one whole 6-byte pixel (PIL cannot write such a PNG);
    ``sbit``: the significant bits per channel, written as an sBIT chunk."""
    import struct
    import zlib

    h, w, c = a.shape
    raw = a.astype(">u2").view(np.uint8).reshape(h, w * c * 2).astype(np.int32)
    bpp = 2 * c
    rows, prev = [], np.zeros(raw.shape[1], np.int32)
    for y, x in enumerate(raw):
        left = np.concatenate([np.zeros(bpp, np.int32), x[:-bpp]])
        up_left = np.concatenate([np.zeros(bpp, np.int32), prev[:-bpp]])
        p = left + prev - up_left
        paeth = np.where((abs(p - left) <= abs(p - prev)) & (abs(p - left) <= abs(p - up_left)), left,
                         np.where(abs(p - prev) <= abs(p - up_left), prev, up_left))
        pred = (0, left, prev, (left + prev) // 2, paeth)[y % 5]
        rows.append(bytes([y % 5]) + ((x - pred) % 256).astype(np.uint8).tobytes())
        prev = x

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    sig = chunk(b"sBIT", bytes([sbit] * c)) if sbit else b""
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, {3: 2, 4: 6}[c], 0, 0, 0))
                     + sig + chunk(b"IDAT", zlib.compress(b"".join(rows))) + chunk(b"IEND", b""))


def _save16(path, a):
    import tifffile

    if path.suffix == ".png":
        png16(path, a)
    else:  # as an editor exports one: deflate-compressed, with the horizontal predictor
        tifffile.imwrite(path, a, photometric="rgb", compression="zlib", predictor=True)


@pytest.mark.parametrize("suffix", [".png", ".tif"])
@pytest.mark.parametrize("bits,gain,used", [(16, 1.0, 16), (12, 1.0, 12), (16, 1 / 8, 13)])
def test_sixteen_bit_colour_photo_is_read_at_its_depth(tmp_path, suffix, bits, gain, used):
    # 16 bits per channel: full range, a 12-bit camera's values in a 16-bit file, and a dim
    # photo spanning an eighth of the range; PIL decodes the upper 8 bits only, which left
    # the 12-bit and the dim photo 7 and 14 levels (refused) and rounded the full-range one
    # to 8 bits.  Each is read at its 16 bits, scaled by the bit depth its values use, and
    # measured at the angles drawn, as its 8-bit version is
    from soilcal.imaging.io import read_photo

    img = heap_photo()
    a = np.round(img * gain * (2 ** bits - 1)).astype(np.uint16)
    p = tmp_path / f"rgb{bits}{suffix}"
    _save16(p, a)
    # the depth its values use: the depth drawn with, less 3 bits for the photo dimmed 8 times
    assert np.abs(read_photo(p) - a / (2.0 ** used - 1.0)).max() < 1e-9
    r = measure.measure_pile(p)
    _assert_flanks(r, 32.0, 35.0)
    p8 = tmp_path / "rgb8.png"
    _u8(img).save(p8)
    r8 = measure.measure_pile(p8)
    assert abs(r.left_deg - r8.left_deg) <= 0.1 and abs(r.right_deg - r8.right_deg) <= 0.1


def test_sixteen_bit_colour_photo_over_exposed_is_refused(tmp_path):
    # over-exposed until the wall, the plate and most of the heap are white: its 16 bits give it
    # no more contrast than the 8-bit photo has, refused as that one is, counting its own levels
    from soilcal.errors import InputError

    p = tmp_path / "over16.png"
    png16(p, np.round(np.clip(heap_photo() / 0.3, 0.0, 1.0) * 65535).astype(np.uint16))
    with pytest.raises(InputError) as e:
        measure.measure_pile(p)
    assert e.value.path == str(p) and e.value.field == "image"
    assert "at least 8192 of its 65536 grey levels" in e.value.expected


def test_heap_whose_foot_runs_out_of_the_frame_is_refused(tmp_path):
    # the heap's foot on one side lies beyond the image border (the flank reaches the border
    # above the plate): a line slanting up from the plate across that flank gave the heap a
    # foot, read both flanks 4 deg off as sound; the heap is cut, and said to be
    from soilcal.errors import InputError

    p = tmp_path / "cut.jpg"
    _u8(heap_photo(apex_col=110.0)).save(p, quality=90)
    with pytest.raises(InputError) as e:
        measure.measure_pile(p)
    assert (e.value.path, e.value.field, e.value.expected, e.value.got) == (
        str(p), "image", "the whole heap inside the frame", "it is cut by the image border")


@pytest.mark.parametrize("tilt", [-8.0, 12.0])
def test_a_hand_held_camera_rolled_beyond_six_degrees(tmp_path, tilt):
    # a phone held by hand rolls by several degrees: the plate line drawn tilted by 8 or 12 deg
    # is found within the plate search's range, the roll taken out, the flanks read as drawn
    p = tmp_path / "rolled.jpg"
    _u8(heap_photo(tilt=tilt)).save(p, quality=90)
    r = measure.measure_pile(p)
    _assert_flanks(r, 32.0, 35.0)
    assert abs(r.roll_deg - tilt) <= 0.2 and r.confidence == "ok"


@pytest.mark.parametrize("tilt", [16.0, 20.0, -25.0])
def test_a_camera_rolled_beyond_the_plate_search_is_refused(tmp_path, tilt):
    # the plate line drawn tilted by more than the plate search's 15 deg: its candidates were
    # chords of the plate or lines through the heap, which gave flanks 4 to 10 deg off (at 20
    # deg as "ok"), or a refusal saying nothing of the roll; refused, naming the tilt
    from soilcal.errors import InputError

    p = tmp_path / "rolled.jpg"
    _u8(heap_photo(tilt=tilt)).save(p, quality=90)
    with pytest.raises(InputError) as e:
        measure.measure_pile(p)
    assert (e.value.path, e.value.field) == (str(p), "image")
    assert e.value.expected.startswith("a plate edge within 15 deg of horizontal")
    found = re.search(r"tilted (-?[0-9.]+) deg", e.value.got)
    assert found and abs(float(found[1]) - tilt) <= 0.2, e.value.got
    assert ("clockwise" if tilt > 0 else "counter-clockwise") + " to level it" in e.value.got


def test_a_rendered_photo_rolled_beyond_the_plate_search_is_refused(tmp_path):
    # a rendered heap on its plate, before a cluttered wall, the camera rolled 16 deg: the old
    # search measured it on a line at 14.75 deg, both flanks 1 deg off, as "ok"
    from soilcal.errors import InputError
    from soilcal.imaging import render

    img, truth = render.render_pile(11, 33.0, 36.0, roll_deg=16.0)
    p = render.save_photo(tmp_path / "rolled16.jpg", img, truth, quality=85)
    with pytest.raises(InputError) as e:
        measure.measure_pile(p)
    assert e.value.path == str(p) and e.value.field == "image"
    found = re.search(r"tilted (-?[0-9.]+) deg", e.value.got)
    assert found and abs(float(found[1]) - truth["roll_deg"]) <= 0.2, e.value.got


@pytest.mark.parametrize("kind", ["ruler", "shadow"])
def test_level_photo_with_a_diagonal_edge_on_the_wall_is_measured(tmp_path, kind):
    # a level photo of a heap on a plate hardly wider than it, a ruler leaning at 20 deg or a
    # lamp's shadow edge at 20 deg across the wall behind it: a straight edge across the photo
    # beyond the plate search, but no heap stands on it (the ruler's was taken for a rolled
    # plate and refused, "rotate the photo 20 deg"); measured on the plate as drawn
    h, w = 300, 400
    rr, cc = np.mgrid[0:h, 0:w]
    prow = 0.72 * h
    light = (0.6, 0.6, 0.62)
    img = heap_photo(seed=5, plate=light)
    clean = heap_photo(seed=5, grain=0.0, noise=0.0, plate=light)
    img[(rr >= prow) & ((cc < 50) | (cc > 334))] = clean[0, 0]  # the plate ends 6 px beyond the heap's feet
    edge = 5 + np.tan(np.radians(20.0)) * cc
    top = np.maximum(prow - 90 + (200 - cc) * np.tan(np.radians(32.0)), prow - 90 + (cc - 200) * np.tan(np.radians(35.0)))
    wall = (rr < prow) & ~((rr >= top) & (rr < prow))
    if kind == "ruler":
        img[wall & (np.abs(rr - edge) < 4)] = (0.2, 0.2, 0.2)
    else:
        img[wall & (rr > edge)] *= 0.7
    p = tmp_path / f"{kind}.png"
    _u8(img).save(p)
    r = measure.measure_pile(p)
    _assert_flanks(r, 32.0, 35.0)
    assert abs(r.roll_deg) <= 0.2


def test_no_heap_found_beside_a_tilted_edge_says_what_it_could_be(tmp_path):
    # a camera rolled 40 deg: no heap is measured on the plate search's lines nor on the tilted
    # plate edge; the refusal names the tilt, conditionally (it may be a shadow's edge)
    from soilcal.errors import InputError

    p = tmp_path / "rolled40.jpg"
    _u8(heap_photo(tilt=40.0)).save(p, quality=90)
    with pytest.raises(InputError) as e:
        measure.measure_pile(p)
    assert "if it is the plate's (the camera rolled" in e.value.got, e.value.got
    assert re.search(r"tilted 40\.[0-9] deg", e.value.got), e.value.got


@pytest.mark.parametrize("hot", [4096, 65535])
def test_a_hot_pixel_does_not_set_the_bit_depth(tmp_path, hot):
    # a 12-bit camera's values in a 16-bit PNG with one hot pixel (or a glint) at 4096 or
    # 65535: the depth was that of the largest value, which scaled the photo by 8191 or 65535
    # and refused the second (32 of 8192 levels, "under-exposed"); it is read at 12 bits (the
    # hot pixel clipped) and measured as without it
    from soilcal.imaging.io import read_photo

    a = np.round(heap_photo() * 4095).astype(np.uint16)
    a[3, 3] = hot
    p = tmp_path / "hot.png"
    png16(p, a)
    img = read_photo(p)
    keep = np.ones(a.shape[:2], bool)
    keep[3, 3] = False
    assert np.abs(img[keep] - a[keep] / 4095.0).max() < 1e-9 and img[3, 3].max() == 1.0
    _assert_flanks(measure.measure_pile(p), 32.0, 35.0)


@pytest.mark.parametrize("shifted", [False, True])
def test_sixteen_bit_png_depth_from_its_sbit_chunk(tmp_path, shifted):
    # a 12-bit photo in a 16-bit PNG saying so (sBIT 12): its values as the camera gave them
    # (a dim photo whose values reach 2048 only, read by 4095, not 2047 as their spread would
    # say), or scaled to 16 bits as the PNG standard has them (read by 65535)
    from soilcal.imaging.io import read_photo

    img = heap_photo()
    a = np.round(img * (0.6 if not shifted else 1.0) * 4095).astype(np.uint16)
    if shifted:
        a = a << 4
    p = tmp_path / "sbit.png"
    png16(p, a, sbit=12)
    assert np.abs(read_photo(p) - a / (65535.0 if shifted else 4095.0)).max() < 1e-9
    _assert_flanks(measure.measure_pile(p), 32.0, 35.0)


@pytest.mark.parametrize("gain", [1 / 6, 1 / 12])
def test_sixteen_bit_photo_exposed_for_a_window_counts_its_own_levels(tmp_path, gain):
    # a 16-bit photo exposed for a bright window in view: the heap, plate and wall take a sixth
    # or a twelfth of its range, 22 or 11 of 256 levels at 8 bits (refused as an 8-bit photo
    # would be, with edges of quantisation steps), but thousands of its 65536; the levels are
    # counted at its 16 bits, an eighth of those its values there use, and it is measured
    img = heap_photo(seed=2) * gain
    img[10:60, 20:120] = 1.0
    img[10:60, 300:380] = 0.0
    p = tmp_path / "window16.png"
    png16(p, np.round(img * 65535).astype(np.uint16))
    _assert_flanks(measure.measure_pile(p), 32.0, 35.0)


def test_eight_bit_values_in_a_sixteen_bit_file_refused_for_their_contrast(tmp_path):
    # a dim photo's 8-bit values (up to 32) in a 16-bit PNG: read at its 16 bits, its values use
    # 8 of them, and it spans too few of those; the refusal says so, not that it was read at 8
    # bits
    from soilcal.errors import InputError

    p = tmp_path / "dim8in16.png"
    png16(p, np.round(heap_photo() * 255 / 8).astype(np.uint16))
    with pytest.raises(InputError) as e:
        measure.measure_pile(p)
    assert "too little brightness contrast" in e.value.got and "read at 8 bits" not in e.value.got, e.value.got


@pytest.mark.parametrize("plate", [(0.35, 0.35, 0.38), (0.1, 0.1, 0.1)])
def test_a_dark_plate_ending_just_past_the_heap_s_feet_is_the_plate(tmp_path, plate):
    # the drawn heap (32 / 35 deg) on a dark plate reaching 20 px past each foot, the wall
    # beyond the plate's ends and a table 40 px below: the plate's top line is the line the
    # heap stands on (a rule refusing a line when the heap's class goes on below it under the
    # feet, more than beside the heap, took the table's edge: 31.30 / 33.71 deg, "ok")
    h, w, prow = 300, 400, 216
    img = heap_photo(plate=plate)
    rr, cc = np.mgrid[0:h, 0:w]
    foot_l, foot_r = 200 - 90 / np.tan(np.radians(32)), 200 + 90 / np.tan(np.radians(35))
    img[(rr >= prow) & ((cc < foot_l - 20) | (cc > foot_r + 20)) & (rr < prow + 40)] = (0.75, 0.72, 0.65)
    img[rr >= prow + 40] = (0.5, 0.4, 0.3)
    p = tmp_path / "pedestal.png"
    _u8(np.clip(img, 0, 1)).save(p)
    _assert_flanks(measure.measure_pile(p), 32.0, 35.0)


@pytest.mark.parametrize("bits", [16, 12])
def test_planar_sixteen_bit_tiff_is_read_at_its_depth(tmp_path, bits):
    # a 16-bit RGB TIFF with its colour planes stored apart (planar configuration 2, as
    # scientific cameras and editors write them): PIL decoded each plane's bytes as 8-bit
    # samples and the photo read as noise without a complaint (max error 0.86 of the range);
    # it is read at its depth (12-bit values by 4095) and measured as drawn
    import tifffile

    from soilcal.imaging.io import read_photo

    a = np.round(heap_photo() * (2 ** bits - 1)).astype(np.uint16)
    p = tmp_path / "planar.tif"
    tifffile.imwrite(p, np.moveaxis(a, -1, 0), planarconfig="separate", photometric="rgb")
    assert np.abs(read_photo(p) - a / (2.0 ** bits - 1)).max() < 1e-9
    _assert_flanks(measure.measure_pile(p), 32.0, 35.0)


def test_a_photo_listed_twice_in_its_group_is_refused(tmp_path):
    # a copy-paste slip: the same file as two views of one group would weigh twice in its mean
    import numpy as np
    from skimage import io

    from soilcal.errors import InputError
    from soilcal.imaging.manifest import read_manifest

    io.imsave(tmp_path / "heap.png", np.zeros((8, 8), np.uint8), check_contrast=False)
    io.imsave(tmp_path / "other.png", np.zeros((8, 8), np.uint8), check_contrast=False)
    m = tmp_path / "manifest.yaml"
    m.write_text("photos:\n"
                 "  - {file: heap.png, kind: pile, group: s, view: S}\n"
                 "  - {file: other.png, kind: pile, group: t}\n"
                 "  - {file: heap.png, kind: pile, group: s, view: N}\n")
    with pytest.raises(InputError) as exc:
        read_manifest(m)
    e = exc.value
    assert (e.field, e.got) == ("photos[2].file", "heap.png") and "photos[0]" in e.expected, str(e)
    # in another group the same photo is no slip of this kind
    m.write_text("photos:\n  - {file: heap.png, kind: pile, group: s}\n  - {file: heap.png, kind: pile, group: t}\n")
    assert len(read_manifest(m)["photos"]) == 2


def test_the_command_line_prints_json_without_nan(capsys):
    # JSON has no NaN: a value not measured is null, so that any strict parser reads the output
    import json

    from soilcal.imaging.cli import _print

    _print({"angle_deg": 30.0, "cue_outvoted_deg": float("nan"), "rows": [1.0, float("inf")], "ok": "x"})
    out = capsys.readouterr().out
    assert "NaN" not in out and "Infinity" not in out
    assert json.loads(out, parse_constant=lambda c: pytest.fail(c)) == {
        "angle_deg": 30.0, "cue_outvoted_deg": None, "rows": [1.0, None], "ok": "x"}


def test_a_folder_given_as_a_photo_is_named_a_folder(tmp_path):
    from soilcal.errors import InputError
    from soilcal.imaging.io import read_photo

    with pytest.raises(InputError) as exc:
        read_photo(tmp_path)
    assert (exc.value.field, exc.value.got) == ("file", "a folder")
    with pytest.raises(InputError) as exc:
        read_photo(tmp_path / "nothing.png")
    assert exc.value.got == "missing"
