"""A scale card standing on the plate beside a heap's foot: a line from one of the card's
edges to the plate's edge beyond the other foot carries the heap as the plate's edge does, and
the photo does not say which is the plate.  Drawn heaps of known flanks (32 and 35 deg, plate
edge between rows 215 and 216 of 300): a result is either the drawn flanks, "ok", or "low"
with both lines named and the plate line to give by hand; never other flanks, "ok"."""

from __future__ import annotations

import json

import numpy as np
import pytest

from soilcal.imaging import measure

from test_plate_line_given import PLATE_EDGE, card_on_plate
from test_user_photos import _u8, heap_photo


def _card(side, width, height, style, h=300, w=400):
    """heap_photo with a card ``width`` x ``height`` px standing on the plate 4 px from the
    frame's ``side`` edge: plain white, or checked black and white in 10 px squares."""
    img = heap_photo(h=h, w=w)
    rr, cc = np.mgrid[0:h, 0:w]
    prow = 0.72 * h
    c0 = 4 if side == "left" else w - 4 - width
    m = (cc >= c0) & (cc < c0 + width) & (rr >= prow - height) & (rr < prow)
    if style == "white":
        img[m] = 0.95
    else:
        img[m] = np.where((((cc - c0) // 10 + (rr - int(prow - height)) // 10) % 2 == 0)[m], 0.05, 0.95)[:, None]
    return np.clip(img, 0.0, 1.0)


def _rows_at_ends(text):
    """The rows of the lines [[c, r], [c, r]] named in a message."""
    import re

    return [[float(r) for r in re.findall(r"\[\d+\.?\d*, (\d+\.?\d*)\]", m)]
            for m in re.findall(r"\[\[[^\]]*\], \[[^\]]*\]\]", text)]


@pytest.mark.parametrize("side,width,height,style", [
    ("left", 40, 30, "checker"),    # before: 33.64 / 33.27 deg, "ok"
    ("left", 60, 30, "checker"),    # before: 35.60 / 31.53 deg, "ok"
    ("left", 100, 30, "white"),     # before: 31.37 / 35.54 deg, "ok"
    ("right", 100, 60, "checker"),  # before: 31.50 / 35.77 deg, "ok"
])
def test_a_card_on_the_plate_gives_the_drawn_flanks_or_says_the_plate_is_ambiguous(tmp_path, side, width,
                                                                                   height, style):
    p = tmp_path / "card.png"
    _u8(_card(side, width, height, style)).save(p)
    r = measure.measure_pile(p)
    right = abs(r.left_deg - 32.0) <= 0.5 and abs(r.right_deg - 35.0) <= 0.5
    assert right or r.confidence == "low", (r.left_deg, r.right_deg, r.confidence)
    if r.confidence == "low":
        msg = r.plate_ambiguous
        assert str(p) in msg and "plate_line_px" in msg and "--plate-line-px" in msg, msg
        # both lines named, each by its two points in the photo's pixels
        assert len(_rows_at_ends(msg)) == 2, msg
        assert r.as_dict()["plate_ambiguous"] == msg


@pytest.mark.parametrize("img", [
    pytest.param(lambda: heap_photo(), id="plain"),
    # a white card 60 x 30 px on the plate's left end: a chord from its top edge to the plate's
    # edge carries the heap too, but meets edges beside it along less of the columns
    pytest.param(lambda: _card("left", 60, 30, "white"), id="white-card"),
])
def test_a_plate_line_better_supported_than_every_other_is_not_ambiguous(tmp_path, img):
    p = tmp_path / "heap.png"
    _u8(img()).save(p)
    r = measure.measure_pile(p)
    assert r.confidence == "ok" and r.plate_ambiguous == "", r.plate_ambiguous
    assert abs(r.left_deg - 32.0) <= 0.5 and abs(r.right_deg - 35.0) <= 0.5


def test_cli_pile_measures_on_the_plate_line_given(tmp_path, capsys):
    # the card photo whose plate the search cannot be trusted with, its plate edge given
    from soilcal.cli import main

    p = tmp_path / "card.png"
    _u8(card_on_plate()).save(p)
    assert main(["image", "pile", str(p), "--plate-line-px", "10", str(PLATE_EDGE), "390", str(PLATE_EDGE)]) == 0
    r = json.loads(capsys.readouterr().out)["photos"][0]
    assert abs(r["left_deg"] - 32.0) <= 0.4 and abs(r["right_deg"] - 35.0) <= 0.4, r
    assert r["plate_line"] == "command line" and r["plate_line_px"] == [[10.0, PLATE_EDGE], [390.0, PLATE_EDGE]]


@pytest.mark.parametrize("args,why", [
    (["195", "215.5", "205", "216.5"], "at least 115 px apart"),     # 1 px over 10 px: 5.7 deg
    (["10", "120", "390", "700"], "within 45 deg of horizontal"),
    (["10", "215.5", "390", "315.5"], "inside the photo's 400 x 300 pixels"),
])
def test_cli_pile_refuses_a_plate_line_as_the_manifest_does(tmp_path, capsys, args, why):
    from soilcal.cli import main

    p = tmp_path / "plain.png"
    _u8(heap_photo()).save(p)
    assert main(["image", "pile", str(p), "--plate-line-px", *args]) == 2
    err = capsys.readouterr().err
    assert "--plate-line-px" in err and "plain.png" in err and why in err, err


def test_cli_pile_wants_one_plate_line_per_photo(tmp_path, capsys):
    from soilcal.cli import main

    p = tmp_path / "plain.png"
    _u8(heap_photo()).save(p)
    assert main(["image", "pile", str(p), str(p), "--plate-line-px", "10", "215.5", "390", "215.5"]) == 2
    err = capsys.readouterr().err
    assert "--plate-line-px" in err and "one plate line per photo" in err and "2 photos" in err, err


def test_cli_pile_refusal_on_the_line_given_names_it(tmp_path, capsys):
    # a line across the wall above the heap: no heap stands on it
    from soilcal.cli import main

    p = tmp_path / "plain.png"
    _u8(heap_photo()).save(p)
    assert main(["image", "pile", str(p), "--plate-line-px", "10", "120.5", "390", "120.5",
                 "--refusals", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "plain.png" in err and "--plate-line-px 10 120.5 390 120.5" in err, err


def _result_on(slope, intercept, feet, left, right):
    """A heap measured on the plate line ``slope``, ``intercept`` with its feet at columns
    ``feet`` (flank lines (u0, v0, du, dv) crossing the plate row at u0 in a level frame)."""
    return measure.PileResult("heap.png", (left + right) / 2, left, right, 1.0, 0.0,
                              geometry=(slope, intercept, (feet[0], 0.0, 1.0, 1.0), (feet[1], 0.0, 1.0, 1.0),
                                        100.0))


def test_a_line_with_no_columns_beside_the_heap_is_not_judged_a_tie(monkeypatch):
    # a heap spanning the frame (feet 3 px from either edge of 400): fewer than 10 columns
    # beside it on either side, for the line measured on and for a second line tilted 2 deg
    # that reads the flanks 3 deg differently, "ok"; nothing beside the heap says either line
    # is the plate, so the second one is no evidence against the first
    edges = np.zeros((300, 400), bool)
    res = _result_on(0.0, 215.5, (3.0, 396.0), 32.0, 35.0)
    tilted = float(np.tan(np.radians(2.0)))
    other = _result_on(tilted, 212.0, (3.0, 396.0), 35.0, 32.0)
    monkeypatch.setattr(measure, "_on_plate_lines", lambda *a, **k: other)
    assert measure._plate_alternative("heap.png", None, None, None, [(tilted, 212.0)], res, "auto", "otsu",
                                      edges) is None
    assert measure._edge_beside(edges, res) is None and measure._edge_beside(edges, other) is None
    # where the second line does meet edges beside the heap, the first line having none to show,
    # it is flagged
    other = _result_on(tilted, 212.0, (150.0, 250.0), 35.0, 32.0)
    rows = np.round(tilted * np.arange(400) + 212.0).astype(int)
    edges[rows, np.arange(400)] = True
    res = _result_on(0.0, 215.5, (3.0, 396.0), 32.0, 35.0)
    monkeypatch.setattr(measure, "_on_plate_lines", lambda *a, **k: other)
    assert measure._plate_alternative("heap.png", None, None, None, [(tilted, 212.0)], res, "auto", "otsu",
                                      edges) is not None


def test_cli_pile_plate_line_wording_is_the_command_lines(tmp_path, capsys):
    # a refused --plate-line-px shows its example as typed on the command line, and counts
    # are worded in the singular for one
    from soilcal.cli import main

    p = tmp_path / "plain.png"
    _u8(heap_photo()).save(p)
    assert main(["image", "pile", str(p), "--plate-line-px", "10", "120", "390", "700"]) == 2
    err = capsys.readouterr().err
    assert "e.g. --plate-line-px 40 612.5 1580 618" in err and "[[40, 612.5]" not in err, err
    assert main(["image", "pile", str(p), "--plate-line-px", "10", "215.5", "390", "215.5",
                 "--plate-line-px", "10", "215.5", "390", "215.5"]) == 2
    err = capsys.readouterr().err
    assert "(1 photo;" in err and "2 lines" in err, err


def test_lines_the_search_refused_are_not_measured_again(monkeypatch):
    # the search refused line 1 with every cue: the ambiguity check measures only line 2
    res = _result_on(0.0, 215.5, (150.0, 250.0), 32.0, 35.0)
    tilted = float(np.tan(np.radians(2.0)))
    seen = []

    def measured(path, rgb, lum, grays, lines, n, *a, **k):
        seen.append(n)
        raise InputError(path, "image", "a heap", "none")

    from soilcal.errors import InputError
    monkeypatch.setattr(measure, "_on_plate_lines", measured)
    edges = np.zeros((300, 400), bool)
    assert measure._plate_alternative("heap.png", None, None, None, [(tilted, 150.0), (-tilted, 220.0)], res,
                                      "auto", "otsu", edges, {1}) is None
    assert seen == [2]
