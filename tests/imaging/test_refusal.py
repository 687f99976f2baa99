"""A photo that cannot be measured: the refusal names a diagnostic image of what was tried."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from soilcal.errors import InputError
from soilcal.imaging import drum, measure
from soilcal.imaging.refusal import Tried

ROOT = Path(__file__).resolve().parents[2]
PILE = ROOT / "resources/images/cinnamon-soil/stacking_1.jpg"


def _plate_without_heap(path: Path) -> Path:
    """A wall above a dark plate edge and a plate face: a plate, no heap."""
    rng = np.random.default_rng(3)
    img = np.zeros((300, 400, 3), float)
    img[:] = (170, 190, 170)
    img[220:232] = (60, 60, 60)
    img[232:] = (125, 120, 115)
    img += rng.normal(0, 2.0, img.shape)
    Image.fromarray(np.clip(img, 0, 255).astype(np.uint8)).save(path)
    return path


def _no_beam(path: Path) -> Path:
    rng = np.random.default_rng(4)
    img = np.clip(rng.normal(150, 20, (240, 320)), 0, 255).astype(np.uint8)
    Image.fromarray(img).convert("RGB").save(path)
    return path


def _note_png(exc: InputError) -> Path:
    m = re.search(r"\(what was tried: (.+\.refused\.png)\)$", str(exc))
    assert m, str(exc)
    return Path(m.group(1))


def test_a_refused_pile_photo_names_its_diagnostic_image(tmp_path):
    photo = _plate_without_heap(tmp_path / "no_heap.png")
    with pytest.raises(InputError) as e:
        measure.measure_pile(photo, refusals=tmp_path / "refused")
    png = _note_png(e.value)
    assert png == tmp_path / "refused" / "no_heap.refused.png" and png.is_file()
    with Image.open(png) as im:
        assert im.size[0] > 300 and im.size[1] > 200
    # the message is the refusal itself, with the image after it, on one line
    assert e.value.field == "image" and "\n" not in str(e.value)
    assert str(e.value).startswith(f"{photo}: image: expected ")


def test_every_attempt_is_recorded_with_why_it_was_turned_down(tmp_path):
    photo = _plate_without_heap(tmp_path / "no_heap.png")
    tried = Tried()
    with pytest.raises(InputError):
        measure._measure_pile(photo, "otsu", False, "auto", tried)
    assert tried.rgb is not None and tried.lines  # the plate edge was found
    assert tried.attempts, "no segmentation attempt recorded"
    for a in tried.attempts:
        assert re.match(r"line \d, \w+/(dark|light)$", a.label)
        assert a.mask is not None and a.mask.shape == tried.rgb.shape[:2]
        assert a.line is not None and a.outcome  # each says why it was turned down


def test_without_a_folder_the_refusal_is_unchanged(tmp_path):
    photo = _plate_without_heap(tmp_path / "no_heap.png")
    with pytest.raises(InputError) as e:
        measure.measure_pile(photo)
    assert "what was tried" not in str(e.value) and e.value.note is None
    assert not list(tmp_path.rglob("*.refused.png"))


def test_a_measured_photo_writes_no_diagnostic(tmp_path):
    r = measure.measure_pile(PILE, refusals=tmp_path)
    assert np.isfinite(r.angle_deg)
    assert not list(tmp_path.iterdir())


def test_an_unreadable_photo_has_nothing_to_draw(tmp_path):
    bad = tmp_path / "notes.png"
    bad.write_text("not an image")
    with pytest.raises(InputError) as e:
        measure.measure_pile(bad, refusals=tmp_path / "refused")
    assert e.value.field == "file" and "what was tried" not in str(e.value)
    assert not (tmp_path / "refused").exists()


def test_furrow_and_drum_refusals_draw_too(tmp_path):
    photo = _no_beam(tmp_path / "furrow.png")
    with pytest.raises(InputError) as e:
        measure.measure_furrow(photo, 600.0, refusals=tmp_path)
    assert "profile-meter beam" in e.value.expected and _note_png(e.value).is_file()
    # a drum frame: a drum and its circle, but one grey level inside
    img = np.full((240, 320), 230, np.uint8)
    yy, xx = np.mgrid[0:240, 0:320]
    ring = np.abs(np.hypot(xx - 160, yy - 120) - 90) < 4
    img[ring] = 20
    frame = tmp_path / "frame.png"
    Image.fromarray(img).save(frame)
    try:
        drum.measure_drum_frame(frame, refusals=tmp_path / "drum")
    except InputError as exc:
        png = _note_png(exc)
        assert png.parent == tmp_path / "drum" and png.is_file()
    else:  # pragma: no cover - the frame has no powder: it must not be measured
        pytest.fail("a drum without powder was measured")


def test_command_line_refusal_is_one_line_naming_the_image(tmp_path):
    photo = _plate_without_heap(tmp_path / "no_heap.png")
    p = subprocess.run([sys.executable, "-m", "soilcal.cli", "image", "pile", str(photo), "--refusals", "why"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert p.returncode == 2
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "what was tried: why/no_heap.refused.png" in lines[0]
    assert (tmp_path / "why" / "no_heap.refused.png").is_file()


@pytest.mark.parametrize("wall,plate", [
    ((0.75, 0.72, 0.65), (0.35, 0.35, 0.38)),  # a light wall over a dark plate
    ((0.2, 0.2, 0.22), (0.6, 0.6, 0.62)),  # a dark wall over a light plate
    ((0.8, 0.8, 0.8), (0.55, 0.45, 0.4)),  # a white wall over a brown board
])
def test_an_empty_plate_always_gets_the_same_refusal(tmp_path, wall, plate):
    # no heap: the cues segment the wall's noise into different shapes (blobs, a strip along
    # the plate), none of which is a heap; the refusal says so, the same for every photo
    from test_user_photos import _u8, heap_photo

    p = tmp_path / "empty.jpg"
    _u8(heap_photo(height=0.0, wall=wall, plate=plate, grain=0.1)).save(p, quality=90)
    with pytest.raises(InputError) as e:
        measure.measure_pile(p)
    assert (e.value.path, e.value.field, e.value.expected, e.value.got) == (
        str(p), "image", "one heap standing on the plate", "none found")
