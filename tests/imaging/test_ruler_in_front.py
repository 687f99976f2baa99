"""A ruler lying askew on the plate in front of the heap (a scale in the photo, as users put
one): its top edge hides the heap's foot and the plate's edge behind it, so the heap stands on
the ruler's edge alone and its flanks read turned by the ruler's tilt.  The plate's edge runs on
across the photo beyond the ruler's ends: the photo has two level references at the heap's
foot and does not say which is level, so the result is flagged "low" with both lines, the
flanks on each, and the way out (the plate line given by hand).  Drawn heaps of known flanks:
32 deg left, 35 deg right on a plate edge at row 216 (test_user_photos.heap_photo)."""

from __future__ import annotations

import numpy as np
import pytest

from soilcal.imaging import measure

from test_user_photos import _u8, heap_photo

PLATE_ROW = 216.0  # 0.72 h of heap_photo's 300 rows


def ruler_photo(tilt, below, length, h=300, w=400):
    """heap_photo with a white ruler 14 px high, ticks every 8 px, ``length`` px long centred on
    the heap, its top edge ``below`` px under the plate's edge at the middle column (negative:
    above it, hiding the heap's foot) and turned ``tilt`` deg (positive: rising to the right)."""
    img = heap_photo(h=h, w=w)
    rr, cc = np.mgrid[0:h, 0:w].astype(float)
    along = cc - 0.5 * w
    top = PLATE_ROW + below - np.tan(np.radians(tilt)) * along
    m = (rr >= top) & (rr < top + 14) & (np.abs(along) <= length / 2)
    img[m] = (0.92, 0.92, 0.9)
    tick = (np.mod(np.round(along), 8) == 0) & (rr < top + np.where(np.mod(np.round(along), 40) == 0, 10, 5))
    img[m & tick] = 0.1
    return np.clip(img, 0.0, 1.0)


@pytest.mark.parametrize("tilt,below,length,plate_seen", [
    # before: 35.94 / 30.86 deg, "ok" (the ruler's edge, 4 deg off, taken for the plate); the
    # plate's edge runs on beyond the ruler's ends and is the line named beside it
    (-4, 6, 240, True),
    # before: 30.51 / 36.48 deg, "ok"; the ruler spans 90 % of the width, hiding the plate's edge
    # nearly everywhere: the line named beside it is the ruler's lower edge
    (2, -4, 360, False),
])
def test_an_askew_ruler_before_the_heap_is_right_or_flagged(tmp_path, tilt, below, length, plate_seen):
    p = tmp_path / "ruler.png"
    _u8(ruler_photo(tilt, below, length)).save(p)
    r = measure.measure_pile(p)
    right = abs(r.left_deg - 32.0) <= 0.5 and abs(r.right_deg - 35.0) <= 0.5
    assert right or r.confidence == "low", (r.left_deg, r.right_deg, r.confidence)
    assert not right, "drawn to hide the plate's edge at the heap: read on the ruler"
    msg = r.plate_ambiguous
    assert str(p) in msg and "plate_line_px" in msg and "--plate-line-px" in msg, msg
    if plate_seen:
        # the flanks on the other line, the plate's edge: those drawn
        on_other = [float(v) for v in msg.split("flanks ")[2].split(" deg")[0].split(" / ")]
        assert abs(on_other[0] - 32.0) <= 0.5 and abs(on_other[1] - 35.0) <= 0.5, msg
    # on the plate's edge given by hand, the drawn flanks, "ok"
    g = measure.measure_pile(p, plate_px=((10.0, PLATE_ROW - 0.5), (390.0, PLATE_ROW - 0.5)))
    assert abs(g.left_deg - 32.0) <= 0.5 and abs(g.right_deg - 35.0) <= 0.5 and g.confidence == "ok"


def test_a_level_ruler_before_the_heap_is_no_rival():
    # parallel to the plate's edge it turns no flank: measured as drawn, "ok", nothing flagged
    r = measure.measure_pile("level_ruler.png", image=ruler_photo(0, 6, 240))
    assert abs(r.left_deg - 32.0) <= 0.5 and abs(r.right_deg - 35.0) <= 0.5, (r.left_deg, r.right_deg)
    assert r.confidence == "ok" and r.plate_ambiguous == ""
