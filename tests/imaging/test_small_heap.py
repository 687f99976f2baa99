"""A heap too small in the photo for its flanks to be fitted is refused as such, naming its size
and the size needed.  A flank is fitted over the columns of its band (20-75 % of the heap's
height), at least 20: a flank rising at a deg over a heap H px high spans 0.55 H / tan(a)
columns, so the drawn 32 / 35 deg heap needs H >= 20 tan(35 deg) / 0.55 = 25.5 px."""

from __future__ import annotations

import math
import re

import pytest

from soilcal.errors import InputError
from soilcal.imaging import measure

from test_user_photos import _u8, heap_photo


def test_a_heap_too_small_is_refused_naming_its_size_and_the_size_needed(tmp_path):
    # 72 x 96 px, the heap 0.3 x 72 = 21.6 px high: its right flank spans 0.55 x 21.6 / tan(35)
    # = 17 columns.  Before, the refusal named a line above the plate ("a line through the
    # heap, an edge along 0% of the columns left of it")
    p = tmp_path / "small.png"
    _u8(heap_photo(h=72, w=96)).save(p)
    with pytest.raises(InputError) as e:
        measure.measure_pile(p)
    err = e.value
    assert err.field in ("left flank", "right flank") and "small.png" in str(err), str(err)
    assert "too small" in err.got and "take the photo closer or at a higher resolution" in err.got, err.got
    high, need = (int(v) for v in re.search(r"a heap (\d+) px high.*at least (\d+) px high", err.got).groups())
    assert abs(high - 21.6) <= 2.5, err.got
    assert abs(need - 20 * math.tan(math.radians(35)) / 0.55) <= 2.5, err.got


def test_a_heap_just_large_enough_is_measured(tmp_path):
    # 96 x 128 px, the heap 28.8 px high: its flanks span 25 and 23 columns
    p = tmp_path / "enough.png"
    _u8(heap_photo(h=96, w=128)).save(p)
    r = measure.measure_pile(p)
    assert abs(r.left_deg - 32.0) <= 0.7 and abs(r.right_deg - 35.0) <= 0.7, (r.left_deg, r.right_deg)
