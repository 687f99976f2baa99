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
