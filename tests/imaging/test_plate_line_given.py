"""A heap photo's plate line given by hand in its manifest (``plate_line_px``): drawn heaps of
known flank angles, measured on the line given instead of the one the plate search finds.  The
expected values are the angles the heaps were drawn with; the line given is the plate's top
edge as drawn (row 0.72 h, between pixel rows 215 and 216 of a 300 px photo)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from PIL import Image

from soilcal.errors import InputError
from soilcal.imaging.manifest import measure_manifest, read_manifest

from test_user_photos import _u8, heap_photo

PLATE_EDGE = 215.5  # heap_photo(h=300): plate from row 216 on, its top edge between rows 215 and 216


def card_on_plate(h=300, w=400):
    """heap_photo (flanks 32 and 35 deg) with a black-and-white checked scale card 100 px wide
    and high standing on the plate at its left end: the card's foot is the plate's edge cut
    short, its squares' edges are further near-horizontal lines."""
    img = heap_photo(h=h, w=w)
    rr, cc = np.mgrid[0:h, 0:w]
    prow, c0, cw, ch = 0.72 * h, 4, 100, 100
    m = (cc >= c0) & (cc < c0 + cw) & (rr >= prow - ch) & (rr < prow)
    img[m] = np.where((((cc - c0) // 10 + (rr - int(prow - ch)) // 10) % 2 == 0)[m], 0.05, 0.95)[:, None]
    return np.clip(img, 0.0, 1.0)


def _manifest(tmp_path, entry, **photos):
    for name, img in photos.items():
        img.save(tmp_path / name) if isinstance(img, Image.Image) else _u8(img).save(tmp_path / name)
    m = tmp_path / "manifest.yaml"
    m.write_text(yaml.safe_dump({"photos": [dict({"kind": "pile", "group": "heap"}, **entry)]}))
    return m


def _photo(out):
    return out["heap"]["photos"][0]


def test_plate_line_given_measures_a_heap_beside_a_card_on_the_plate(tmp_path):
    # the plate search takes a line of the card for the plate: flanks 0.7 and 0.9 deg off, "ok"
    m = _manifest(tmp_path, {"file": "card.png", "plate_line_px": [[10, PLATE_EDGE], [390, PLATE_EDGE]]},
                  **{"card.png": card_on_plate()})
    r = _photo(measure_manifest(m))
    assert abs(r["left_deg"] - 32.0) <= 0.4 and abs(r["right_deg"] - 35.0) <= 0.4, (r["left_deg"], r["right_deg"])
    assert r["plate_line"] == "manifest" and r["plate_line_px"] == [[10.0, PLATE_EDGE], [390.0, PLATE_EDGE]]
    assert abs(r["roll_deg"]) < 1e-9


def test_plate_line_given_agrees_with_the_line_found(tmp_path):
    # a plain heap, whose plate the search finds: the line given gives the same flanks
    found = _photo(measure_manifest(_manifest(tmp_path, {"file": "plain.png"}, **{"plain.png": heap_photo()})))
    given = _photo(measure_manifest(_manifest(tmp_path, {"file": "plain.png", "plate_line_px": [[0, PLATE_EDGE],
                                                                                              [399, PLATE_EDGE]]})))
    for r in (found, given):
        assert abs(r["left_deg"] - 32.0) <= 0.5 and abs(r["right_deg"] - 35.0) <= 0.5
    assert abs(found["left_deg"] - given["left_deg"]) <= 0.2 and abs(found["right_deg"] - given["right_deg"]) <= 0.2
    assert found["plate_line"] == "found" and given["plate_line"] == "manifest"
    # the line found is reported in the photo's pixels: the drawn plate edge
    assert all(abs(row - PLATE_EDGE) <= 1.0 for _, row in found["plate_line_px"])


@pytest.mark.parametrize("tilt", [6.0, 25.0])  # within the plate search's 15 deg, and beyond it
def test_plate_line_given_on_a_rolled_phone_photo_stored_sideways(tmp_path, tilt):
    # the camera rolled (counter-clockwise) and the photo stored sideways with an EXIF
    # orientation: the line is given in the photo as shown, through the drawn plate edge turned
    # by the roll about the image centre
    h, w = 300, 400
    cx, cy = w / 2 - 0.5, h / 2 - 0.5
    t = math.radians(tilt)

    def turned(x, y):
        return [cx + (x - cx) * math.cos(t) + (y - cy) * math.sin(t), cy - (x - cx) * math.sin(t) + (y - cy) * math.cos(t)]

    exif = Image.Exif()
    exif[0x0112] = 6  # shown turned 90 deg clockwise from how it is stored
    stored = _u8(heap_photo(tilt=tilt, height=0.25)).transpose(Image.Transpose.ROTATE_90)
    p = tmp_path / "phone.jpg"
    stored.save(p, quality=92, exif=exif)
    m = _manifest(tmp_path, {"file": "phone.jpg", "plate_line_px": [turned(60, PLATE_EDGE), turned(340, PLATE_EDGE)]})
    r = _photo(measure_manifest(m))
    assert abs(r["left_deg"] - 32.0) <= 0.5 and abs(r["right_deg"] - 35.0) <= 0.5, (r["left_deg"], r["right_deg"])
    assert abs(r["roll_deg"] - tilt) <= 0.01 and r["plate_line"] == "manifest"


def test_plate_line_given_on_a_photo_measured_reduced(tmp_path):
    # 1800 x 1200 px (2.16 megapixels) is measured reduced to 2: the line given in the photo's pixels
    h, w = 1200, 1800
    img = heap_photo(h=h, w=w, noise=0.005)
    edge = 0.72 * h - 0.5
    m = _manifest(tmp_path, {"file": "big.png", "plate_line_px": [[50, edge], [1750, edge]]}, **{"big.png": img})
    r = _photo(measure_manifest(m))
    assert r["work_scale"] < 0.97
    assert abs(r["left_deg"] - 32.0) <= 0.5 and abs(r["right_deg"] - 35.0) <= 0.5, (r["left_deg"], r["right_deg"])


@pytest.mark.parametrize("line,why", [
    ([[10, 215.5]], "two points"),
    ([[10, 215.5], [390, "x"]], "two points"),
    ([[10, 215.5], [390, float("nan")]], "two points"),
    ([200, 215.5, 390, 215.5], "two points"),
    ([[200, 100], [204, 250]], "within 45 deg"),
    ([[10, 215.5], [390, 300]], "inside the photo's 400 x 300 pixels"),
    ([[-5, 215.5], [390, 215.5]], "inside the photo's 400 x 300 pixels"),
])
def test_bad_plate_line_names_manifest_photo_and_field(tmp_path, line, why):
    m = _manifest(tmp_path, {"file": "plain.png", "plate_line_px": line}, **{"plain.png": heap_photo()})
    with pytest.raises(InputError) as e:
        read_manifest(m)
    msg = str(e.value)
    assert str(m) in msg and "photos[0].plate_line_px" in msg and "plain.png" in msg and why in msg, msg


def test_plate_line_is_for_heap_photos_only(tmp_path):
    m = _manifest(tmp_path, {"file": "plain.png", "kind": "drum", "plate_line_px": [[10, 215.5], [390, 215.5]]},
                  **{"plain.png": heap_photo()})
    with pytest.raises(InputError, match=r"photos\[0\]\.plate_line_px: expected no plate line.*plain\.png, kind drum"):
        read_manifest(m)


@pytest.mark.parametrize("low_point,turn_left", [(1, 1.0), (0, -1.0)])
def test_plate_line_given_a_pixel_off_at_the_shortest_span_turns_the_flanks_by_half_a_degree(tmp_path, low_point,
                                                                                            turn_left):
    # one point clicked 1 px below the drawn plate edge, 115 px from the other: the line is
    # tilted t = atan(1 / 115) = 0.498 deg, taken as the camera's roll.  Against a line falling
    # to the right by t (the right point low) the left flank, rising to the right, reads t
    # steeper and the right flank t flatter; the left point low turns them the other way.  The
    # turn is read against the same photo measured on the level line through the same columns;
    # the mean of the two flanks stays at the drawn 33.5
    photo = heap_photo()
    level = [[30, PLATE_EDGE], [145, PLATE_EDGE]]
    tilted = [list(q) for q in level]
    tilted[low_point][1] += 1
    r0 = _photo(measure_manifest(_manifest(tmp_path, {"file": "plain.png", "plate_line_px": level},
                                           **{"plain.png": photo})))
    r = _photo(measure_manifest(_manifest(tmp_path, {"file": "plain.png", "plate_line_px": tilted})))
    t = math.degrees(math.atan(1 / 115))
    assert abs((r["left_deg"] - r0["left_deg"]) - turn_left * t) <= 0.15, (r0, r)
    assert abs((r["right_deg"] - r0["right_deg"]) + turn_left * t) <= 0.15, (r0, r)
    assert abs(r["roll_deg"] + turn_left * t) <= 1e-6, r["roll_deg"]
    assert abs(0.5 * (r["left_deg"] + r["right_deg"]) - 33.5) <= 0.3, r


@pytest.mark.parametrize("offset", [-3.0, 3.0])
def test_plate_line_given_parallel_to_the_plate_edge_measures_the_drawn_flanks(tmp_path, offset):
    # level but a few px off the drawn edge: the flanks move by hardly anything
    row = PLATE_EDGE + offset
    m = _manifest(tmp_path, {"file": "plain.png", "plate_line_px": [[20, row], [380, row]]},
                  **{"plain.png": heap_photo()})
    r = _photo(measure_manifest(m))
    assert r["confidence"] == "ok", r
    assert abs(r["left_deg"] - 32.0) <= 0.5 and abs(r["right_deg"] - 35.0) <= 0.5


def test_plate_line_points_too_close_are_refused(tmp_path):
    # 1 px off over 10 px tilts the line 5.7 deg: 37.7 and 29.1 deg were reported for 32 and 35
    for line in ([[195, PLATE_EDGE], [205, PLATE_EDGE + 1]], [[150, PLATE_EDGE], [260, PLATE_EDGE]]):
        m = _manifest(tmp_path, {"file": "plain.png", "plate_line_px": line}, **{"plain.png": heap_photo()})
        with pytest.raises(InputError, match=r"photos\[0\]\.plate_line_px: expected .*plain\.png.*at least 115 px "
                                             r"apart \(on the plate's edge or its extension\)"):
            read_manifest(m)


def test_plate_line_given_is_recorded_as_given(tmp_path):
    line = [[390, PLATE_EDGE], [10, PLATE_EDGE]]  # the right point first
    m = _manifest(tmp_path, {"file": "plain.png", "plate_line_px": line}, **{"plain.png": heap_photo()})
    assert _photo(measure_manifest(m))["plate_line_px"] == [[390.0, PLATE_EDGE], [10.0, PLATE_EDGE]]


def test_refusal_on_a_plate_line_given_names_the_manifest_field(tmp_path):
    # a line given across the wall above the heap (row 120.5 of 300): no heap stands on it
    m = _manifest(tmp_path, {"file": "plain.png", "plate_line_px": [[10, 120.5], [390, 120.5]]},
                  **{"plain.png": heap_photo()})
    with pytest.raises(InputError) as e:
        measure_manifest(m)
    msg = str(e.value)
    assert "plain.png" in msg and str(m) in msg and "photos[0].plate_line_px" in msg, msg


@pytest.mark.parametrize("option,value", [("roll_deg", 2.0), ("drum_centre_px", [200, 150])])
def test_drum_options_on_a_heap_photo_are_refused(tmp_path, option, value):
    m = _manifest(tmp_path, {"file": "plain.png", option: value}, **{"plain.png": heap_photo()})
    with pytest.raises(InputError, match=rf"photos\[0\]\.{option}: expected no {option}: it is an option of drum "
                                         r"frames \(kind drum\) only \(photo plain\.png, kind pile\)"):
        read_manifest(m)


def test_plate_line_given_where_the_photo_shows_no_plate_edge(tmp_path):
    # a plate of the wall's colour: no edge beside the heap; the line given is measured on
    img = heap_photo(plate=(0.75, 0.72, 0.65))
    m = _manifest(tmp_path, {"file": "same.png", "plate_line_px": [[20, PLATE_EDGE], [380, PLATE_EDGE]]},
                  **{"same.png": img})
    r = _photo(measure_manifest(m))
    assert abs(r["left_deg"] - 32.0) <= 0.5 and abs(r["right_deg"] - 35.0) <= 0.5, (r["left_deg"], r["right_deg"])


def _edge_row(img, cols=40):
    """Subpixel row where the mean of the first ``cols`` columns crosses halfway from the wall's
    level to the plate's (the drawn plate edge beside the heap)."""
    prof = img[..., :3].mean(axis=-1)[:, :cols].mean(axis=1)
    n = prof.size
    a, b = prof[int(0.5 * n)], prof[int(0.86 * n)]
    mid = 0.5 * (a + b)
    i = int(np.nonzero(np.diff(np.sign(prof[int(0.5 * n):int(0.86 * n)] - mid)))[0][0]) + int(0.5 * n)
    return i + (mid - prof[i]) / (prof[i + 1] - prof[i])


@pytest.mark.parametrize("name,orientation,tol", [
    ("odd.png", 1, 0.05),   # reduced by 4 after turning: 301 x 401, the last row and column partial
    ("odd.png", 3, 0.05),
    ("odd.jpg", 3, 0.4),    # decoded at half size, turned (the partial row first), reduced by 2; the
    ("odd.jpg", 8, 0.4),    # decoder's block-wise scaling moves an edge by up to a third of a px
])
def test_reduced_photo_maps_onto_the_photos_pixels(tmp_path, name, orientation, tol):
    # 1203 x 1603 px, the plate edge drawn at row 865.5 as shown: read reduced by 4, the edge
    # found in the reduced image maps back onto it (a side not divisible by 4 ends in a partial
    # pixel: the scale is 1/4, not 301/1203, which put it 0.7 px off)
    from soilcal.imaging.io import read_photo_reduced

    turn = {1: None, 3: Image.Transpose.ROTATE_180, 8: Image.Transpose.ROTATE_270}[orientation]
    img = _u8(heap_photo(h=1203, w=1603, plate_row=866, noise=0.0))
    exif = Image.Exif()
    exif[0x0112] = orientation
    p = tmp_path / name
    kw = {"quality": 95} if name.endswith("jpg") else {}
    (img if turn is None else img.transpose(turn)).save(p, exif=exif, **kw)
    rgb, shown, _, (factor, (ox, oy)) = read_photo_reduced(p, 120_000, with_depth=True, with_map=True)
    assert shown == (1603, 1203) and factor == 4 and rgb.shape[:2] == (301, 401)
    row = (_edge_row(rgb) + 0.5 - oy) * factor - 0.5
    assert abs(row - 865.5) <= tol, row


def test_found_plate_line_is_reported_in_the_photos_pixels(tmp_path, monkeypatch):
    # the same photo measured at 120000 px: the line found is reported within 1.5 px of the
    # drawn edge (1.85 px off before, by the partial pixel's scale; the rest is the search's
    # precision at a quarter of the size)
    from soilcal.imaging import measure

    monkeypatch.setattr(measure, "PILE_WORK_PIXELS", 120_000)
    p = tmp_path / "odd.png"
    _u8(heap_photo(h=1203, w=1603, plate_row=866, noise=0.005)).save(p)
    r = measure.measure_pile(p)
    assert all(abs(row - 865.5) <= 1.5 for _, row in r.plate_line_px), r.plate_line_px


NAN, INF = float("nan"), float("inf")


@pytest.mark.parametrize("given", [dict(plate=(0.0, NAN)), dict(plate=(NAN, PLATE_EDGE)), dict(plate=(INF, PLATE_EDGE)),
                                   dict(plate=(0.0,)), dict(plate_px=((10.0, PLATE_EDGE), (390.0, NAN))),
                                   dict(plate_px=((200.0, PLATE_EDGE), (200.0, PLATE_EDGE + 1.0)))])
def test_plate_line_given_by_a_caller_that_is_no_line_is_refused_naming_it(given):
    # measure_pile's plate (slope, intercept) and plate_px (two points) from a caller in Python,
    # not through a manifest: refused before the photo is measured, naming the photo, the
    # argument and the value (NaN gave an IndexError from an empty band, one column a
    # ZeroDivisionError)
    from soilcal.imaging.measure import measure_pile

    (field, value), = given.items()
    with pytest.raises(InputError) as e:
        measure_pile("heap.png", image=heap_photo(), **given)
    assert (e.value.path, e.value.field, e.value.got) == ("heap.png", field, value)
    assert ("two finite numbers" if field == "plate" else "two points [column, row]") in e.value.expected


@pytest.mark.parametrize("slope,intercept", [(0.0, NAN), (NAN, PLATE_EDGE), (INF, PLATE_EDGE)])
def test_components_on_a_plate_line_that_is_not_finite_are_refused(slope, intercept):
    # a plate candidate of infinite or NaN slope or intercept (a RANSAC line through two points
    # of one column) carries no heap: refused as such, naming the line (math.ceil raised a bare
    # ValueError, "cannot convert float NaN to integer", for each)
    from soilcal.imaging.measure import _components_on_plate

    binary = np.zeros((300, 400), bool)
    binary[150:216, 150:250] = True  # a block standing on the plate edge
    with pytest.raises(InputError) as e:
        _components_on_plate("heap.png", binary, slope, intercept, "heap")
    assert (e.value.path, e.value.field) == ("heap.png", "image") and "finite" in e.value.expected
    assert e.value.got == f"slope {slope}, intercept {intercept}"


def test_a_plate_candidate_refined_to_a_vertical_line_is_no_candidate():
    # edge pixels within 3 px of a level Hough line (row 50): five of column 10 (rows 48 to 52)
    # and one of column 150, so RANSAC's best line (residual under 1 px) is the vertical one
    # through the five: any other line through two of the six has the far pixel and at most
    # three of the column's within 1 px; it is of no finite slope (it gave slope inf,
    # intercept NaN, a plate candidate whose band above it was empty)
    from soilcal.imaging.measure import _refined_line

    er = np.array([48, 49, 50, 51, 52, 50])
    ec = np.array([10, 10, 10, 10, 10, 150])
    assert _refined_line(er, ec, 200, math.pi / 2, 50.0) is None


def test_a_photo_whose_first_plate_candidate_is_no_finite_line_is_measured_or_refused_by_name(monkeypatch):
    # the plate search's first RANSAC fit made vertical (as through pixels of one column): the
    # photo gets a measurement on its other candidates, or one refusal naming it (this gave an
    # IndexError from the candidate's empty band above the plate)
    from skimage import measure as skmeasure

    from soilcal.imaging import measure

    ransac, calls = skmeasure.ransac, []

    def first_vertical(data, model_class, *args, **kwargs):
        model, inliers = ransac(data, model_class, *args, **kwargs)
        calls.append(model_class)
        if len(calls) == 1:
            assert model_class is skmeasure.LineModelND
            model = skmeasure.LineModelND.from_estimate(np.array([[5.0, 0.0], [5.0, 10.0]]))
            assert model.direction[0] == 0.0
        return model, inliers

    monkeypatch.setattr(measure.measure, "ransac", first_vertical)
    try:
        r = measure.measure_pile("heap.png", image=heap_photo())
    except InputError as e:
        assert e.path == "heap.png" and "heap.png" in str(e)
    else:
        assert math.isfinite(r.angle_deg) and math.isfinite(r.roll_deg)
    assert len(calls) > 1


@pytest.mark.parametrize("given", [dict(plate=(0.0, 2.0)), dict(plate=(0.0, -50.0)), dict(plate=(0.0, 5000.0)),
                                   dict(plate_px=((0.0, 5000.0), (399.0, 5000.0)))])
@pytest.mark.parametrize("channel", ["auto", "gray"])
def test_a_plate_line_with_no_rows_of_the_photo_above_it_is_refused_naming_the_photo(given, channel):
    # finite plate lines at the frame's top (row 2: nothing 3 px above it) and off the photo
    # (above and below its 300 rows): no heap can stand on them, and there is no band above
    # them for a cue's threshold; refused naming the photo (they gave an IndexError from
    # Otsu's threshold of the empty band)
    from soilcal.imaging.measure import measure_pile

    with pytest.raises(InputError) as e:
        measure_pile("heap.png", image=heap_photo(), channel=channel, **given)
    assert (e.value.path, e.value.field) == ("heap.png", "image")
    assert "no rows of the photo" in e.value.got and "heap.png" in str(e.value)
