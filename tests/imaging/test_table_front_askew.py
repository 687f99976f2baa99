"""A heap on a plate narrower than the photo, set on a table top of the wall's colour whose
front edge, 12 or 20 px below the plate's top edge at the middle, is turned against it (the
plate set askew on the table, seen from a little above).  The plate's top edge shows only
along the plate's own width, against the heap in hue alone (plate and soil about equally
bright), while the table's front edge runs straight across the whole photo: the search
measures the heap on that edge, joined to it by the strip of plate between the two lines,
and the flanks read turned by the table's tilt with nothing in their fits to say so.  But the
heap's outline does not run down to that line along its flanks: it ends at the plate's top
edge, above it: along that edge the heap's soil meets the plate from foot to foot, which no
line across the heap's grain does.  Drawn: flanks 32 deg left, 35 deg right on a level plate
edge at row 216 (its middle column 200)."""

from __future__ import annotations

import numpy as np
import pytest

from soilcal.imaging import measure

from test_user_photos import _u8, heap_photo

WALL, FRONT = (0.75, 0.72, 0.65), (0.2, 0.15, 0.1)


def askew_table_photo(tilt, below, plate_w, h=300, w=400):
    """heap_photo's heap (32/35 deg, plate top at row 0.72 h) on a plate ``plate_w`` px wide; the
    table top beside it of the wall's colour, its front edge ``below`` px under the plate's top
    edge at the middle column, turned ``tilt`` deg, the table's dark front under it (and under
    the plate's 8 px thickness)."""
    img = heap_photo(h=h, w=w, wall=WALL)
    rr, cc = np.mgrid[0:h, 0:w].astype(float)
    prow = 0.72 * h
    off = np.abs(cc - w / 2) > plate_w / 2
    img[(rr >= prow) & off] = WALL
    edge = prow + below - np.tan(np.radians(tilt)) * (cc - w / 2)
    img[(rr >= edge) & ((rr >= prow + 8) | off)] = FRONT
    return np.clip(img, 0.0, 1.0)


@pytest.mark.parametrize("tilt,below", [(1.0, 12.0), (-2.0, 20.0)])
def test_a_line_below_the_heaps_foot_is_no_plate_it_stands_on(tmp_path, tilt, below):
    # before: "ok" at 30.93 / 35.89 (tilt +1, 12 px) and 33.89 / 31.65 deg (tilt -2, 20 px),
    # the flanks turned by the table's tilt
    p = tmp_path / "askew.png"
    _u8(askew_table_photo(tilt, below, 300)).save(p)
    r = measure.measure_pile(str(p))
    assert r.confidence == "low", (r.left_deg, r.right_deg)
    why = measure.low_reason(r)
    assert str(p) in why and "plate_line_px" in why and "above the line measured on" in why, why
    # the line it names is the drawn plate's top edge: level (within the half degree a plate
    # line is held to) and, under the heap's middle, on the boundary of rows 215 and 216
    s2, b2, *_ = r.stood_above
    assert abs(np.degrees(np.arctan(s2))) <= 0.5 and abs(s2 * 199.5 + b2 - 215.5) <= 1.5, (s2, b2)


def test_a_heap_standing_on_its_plate_across_the_photo_is_ok(tmp_path):
    # the plate across the whole photo, the table's front edge askew below it: measured on the
    # plate's top edge, no line above it carries the heap
    p = tmp_path / "level.png"
    _u8(askew_table_photo(1.0, 12.0, 400)).save(p)
    r = measure.measure_pile(str(p))
    assert abs(r.left_deg - 32.0) <= 0.5 and abs(r.right_deg - 35.0) <= 0.5, (r.left_deg, r.right_deg)
    assert r.confidence == "ok", measure.low_reason(r)


def moist_base_photo(tilt, band, dark, seed=3):
    """heap_photo's heap with a band of moister, darker soil along its base: the soil ``band`` px
    above the plate's top edge (row 216) at the middle column, the band's top edge turned
    ``tilt`` deg, darkened to ``dark`` of its colour.  The band's top edge crosses the heap
    from flank to flank, one step of colour along it under the heap, but ends at its flanks:
    beyond them the wall shows on both sides of it."""
    img = heap_photo(seed=seed)
    h, w = img.shape[:2]
    rr, cc = np.mgrid[0:h, 0:w].astype(float)
    prow = 0.72 * h
    top = np.maximum(prow - 0.3 * h + (w / 2 - cc) * np.tan(np.radians(32.0)),
                     prow - 0.3 * h + (cc - w / 2) * np.tan(np.radians(35.0)))
    m = (rr >= top + 1) & (rr < prow) & (rr >= prow - band - np.tan(np.radians(tilt)) * (cc - w / 2))
    img[m] *= dark
    return img


@pytest.mark.parametrize("tilt,band,dark", [(1.0, 8.0, 0.6), (0.7, 12.0, 0.6)])
def test_a_moist_band_along_the_heaps_base_is_no_plate(tmp_path, tilt, band, dark):
    # measured on the plate's top edge, right; the band's top edge, tilted, carries the heap
    # too and steps in colour along its whole foot, but ends at the heap's flanks, where no
    # plate edge does
    p = tmp_path / "moist.png"
    _u8(moist_base_photo(tilt, band, dark)).save(p)
    r = measure.measure_pile(str(p))
    assert abs(r.left_deg - 32.0) <= 0.5 and abs(r.right_deg - 35.0) <= 0.5, (r.left_deg, r.right_deg)
    assert r.confidence == "ok", measure.low_reason(r)


@pytest.mark.parametrize("scale", [0.6, 0.8])
def test_a_small_photo_of_a_level_plate_on_a_level_table_is_ok(tmp_path, scale):
    # 240 x 180 and 320 x 240 px: the plate's top edge and the table's front edge 12 px below
    # it are both level; the plate's edge, fitted from the short stretch beside the heap, may
    # come out a little tilted, but followed beside the heap on both sides it is level
    from skimage import transform

    img = askew_table_photo(0.0, 12.0, 300)
    h, w = img.shape[:2]
    small = transform.resize(img, (int(h * scale), int(w * scale)), order=1, anti_aliasing=True)
    p = tmp_path / "small.png"
    _u8(np.clip(small, 0.0, 1.0)).save(p)
    r = measure.measure_pile(str(p))
    assert abs(r.left_deg - 32.0) <= 0.5 and abs(r.right_deg - 35.0) <= 0.5, (r.left_deg, r.right_deg)
    assert r.confidence == "ok", measure.low_reason(r)
