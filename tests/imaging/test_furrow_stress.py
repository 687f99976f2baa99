"""Furrow photos as users take them: boards of any colour, with or without a grid, the beam's
shadow on the board, light or dark soils, camera roll up to 5 deg.  The truth is the chord
area of the renderer's profile over the meter's span (analytic, from its polynomial)."""

from __future__ import annotations

import numpy as np
import pytest

from soilcal.errors import InputError
from soilcal.imaging import corpus, measure


def _measure(path, truth):
    return measure.measure_furrow(path, truth["scale_length_mm"], truth["beam_datum_mm"])


@pytest.fixture(scope="module")
def subset(tmp_path_factory):
    """The first 6 photos of the seeded furrow corpus (path, truth), written once for this file."""
    folder = tmp_path_factory.mktemp("furrows")
    return [corpus.write_furrow_photo(params, folder, f"f{k}")
            for k, params in enumerate(corpus.furrow_photo_params(6, seed=0))]


def test_stress_subset_within_two_percent(subset):
    """The first 6 photos of the seeded furrow corpus: every area within 2 % of the truth, the
    scale from the beam's ends within 0.3 %, the roll within 0.1 deg."""
    for k, (path, truth) in enumerate(subset):
        r = _measure(path, truth)
        assert abs(r.area_mm2 / truth["area_mm2"] - 1) <= 0.02, (k, r.area_mm2, truth["area_mm2"])
        assert abs(r.px_per_mm / truth["px_per_mm"] - 1) <= 0.003, k
        assert abs(r.roll_deg - truth["roll_deg"]) <= 0.1, k
        assert r.confidence == "ok", k


def test_light_soil_below_a_dark_board_with_the_beams_shadow(tmp_path):
    """Polarity and shadow: a soil lighter than a grey board, a dark shadow of the beam just
    below it, no grid, the camera rolled 4.5 deg."""
    p = corpus.furrow_photo_params(1, seed=3)[0]
    p = dict(p, roll_deg=4.5, style=dict(p["style"], board_rgb=[0.45, 0.45, 0.47], grid_mm=0.0,
                                          soil_rgb=[0.85, 0.72, 0.55], soil_shading=0.1,
                                          beam_rgb=[0.05, 0.05, 0.05],
                                          beam_shadow={"dx_mm": 10.0, "dy_mm": 8.0, "blur_px": 3.0,
                                                       "darkness": 0.5}))
    path, truth = corpus.write_furrow_photo(p, tmp_path, "light")
    r = _measure(path, truth)
    assert abs(r.area_mm2 / truth["area_mm2"] - 1) <= 0.02
    assert abs(r.roll_deg - 4.5) <= 0.1


def test_corpus_is_seeded():
    a, b = corpus.furrow_photo_params(3, seed=5), corpus.furrow_photo_params(3, seed=5)
    assert a == b and a != corpus.furrow_photo_params(3, seed=6)
    for p in a:  # the profile stays below the beam over the span
        x = np.linspace(*p["span_mm"], 201)
        assert np.polyval(p["coeffs"], x).max() < p["beam_datum_mm"]


@pytest.mark.parametrize("case, field_text", [
    ("no beam", "a profile-meter beam"),
    ("soil like the board", "soil below the profile-meter beam distinct from the board"),
])
def test_a_photo_it_cannot_read_is_refused_naming_what_is_missing(tmp_path, case, field_text):
    p = corpus.furrow_photo_params(1, seed=1)[0]
    board = [0.8, 0.78, 0.7]
    style = dict(p["style"], board_rgb=board, grid_mm=0.0, board_gradient=[0.0, 0.0], beam_shadow=None)
    if case == "no beam":
        style["beam_rgb"] = board
    else:
        style.update(soil_rgb=board, soil_shading=0.0)
    path, truth = corpus.write_furrow_photo(dict(p, style=style), tmp_path, "bad")
    with pytest.raises(InputError) as e:
        _measure(path, truth)
    assert str(path) in str(e.value) and field_text in str(e.value)


@pytest.mark.parametrize("zoom", [0.5, 2.0])
def test_the_same_photo_at_another_resolution_gives_the_same_area(tmp_path, subset, zoom):
    """A user's camera may give a quarter or four times the pixels: the scale comes from the
    beam in pixels, the area in mm^2 stays within 2 % of the truth."""
    from PIL import Image

    path, truth = subset[5]
    im = Image.open(path)
    big = tmp_path / f"zoom{zoom}.jpg"
    im.resize((int(im.width * zoom), int(im.height * zoom)), Image.BILINEAR).save(big, quality=92)
    r = _measure(big, truth)
    assert abs(r.area_mm2 / truth["area_mm2"] - 1) <= 0.02
    assert abs(r.px_per_mm / (zoom * truth["px_per_mm"]) - 1) <= 0.005


def test_a_profile_whose_end_is_not_found_is_flagged(tmp_path):
    """Photo 256 of the seeded corpus: the soil rises into the beam's dark shadow at the left
    end of the span, whose last 38 mm get no boundary point; the chord's end height is then
    extrapolated over the gap (by the line through the last 10 mm of points before it, from
    which the polynomial's end height departs) and the area is off by more than 2 %: flagged
    low."""
    path, truth = corpus.write_furrow_photo(corpus.furrow_photo_params(257, seed=0)[256], tmp_path, "f256")
    r = _measure(path, truth)
    assert abs(r.area_mm2 / truth["area_mm2"] - 1) > 0.02
    assert r.end_gap_mm > measure.FURROW_LOW_IF["end_gap_above"] * truth["scale_length_mm"]
    assert r.confidence == "low"


@pytest.mark.parametrize("roll", [18.0, -25.0])
def test_furrow_photo_rolled_beyond_the_beam_search_names_the_roll(tmp_path, roll):
    # a furrow photo taken with the camera rolled 18 or 25 deg: the beam search (15 deg) finds
    # no beam, and the refusal said only "none found"; it names the beam-like bar's tilt and the
    # turn that levels the photo, and the photo turned so is measured (chord area within 2 %)
    import re

    from PIL import Image

    from soilcal.imaging import render
    from soilcal.imaging.scenes import FURROW_F_COEFFS

    img, truth = render.render_furrow(7, FURROW_F_COEFFS, (-200.0, 200.0), roll_deg=roll)
    p = render.save_photo(tmp_path / "rolled.jpg", img, truth, quality=90)
    with pytest.raises(InputError) as e:
        measure.measure_furrow(p, 400.0, truth["beam_datum_mm"])
    assert (e.value.path, e.value.field) == (str(p), "image")
    said = re.search(r"tilted (-?[0-9.]+) deg: .*rotate the photo ([0-9]+) deg (clockwise|counter-clockwise) to level it",
                     e.value.got)
    assert said and abs(float(said[1]) - roll) <= 0.5, e.value.got
    turn = float(said[2]) * (-1.0 if said[3] == "clockwise" else 1.0)  # PIL turns counter-clockwise
    q = tmp_path / "levelled.png"
    Image.open(p).rotate(turn, resample=Image.Resampling.BILINEAR, expand=True, fillcolor=(128, 128, 128)).save(q)
    r = measure.measure_furrow(q, 400.0, truth["beam_datum_mm"])
    assert abs(r.area_mm2 / truth["area_mm2"] - 1) <= 0.02, (r.area_mm2, truth["area_mm2"])


def test_opener_corpus_truth_is_the_polygons_exact_chord_area():
    """A furrow drawn as a polygon (an opener's trapezoid in a flat surface): the truth is the
    trapezoid's area, (top + bottom) / 2 * depth, the chord lying on the flat surface."""
    from soilcal.imaging import render

    xs = [-200.0, -90.0, -40.0, 40.0, 90.0, 200.0]
    zs = [120.0, 120.0, 20.0, 20.0, 120.0, 120.0]
    _, truth = render.render_furrow(7, None, (-200.0, 200.0), 180.0, profile=[xs, zs], roll_deg=0.0)
    assert truth["area_mm2"] == pytest.approx((180.0 + 80.0) / 2 * 100.0, rel=1e-12)
    # a tilted surface: the chord joins the ends, the trapezoid below it keeps its area
    tilt = [z + 10.0 * (x + 200.0) / 400.0 for x, z in zip(xs, zs)]
    _, truth = render.render_furrow(7, None, (-200.0, 200.0), 180.0, profile=[xs, tilt], roll_deg=0.0)
    assert truth["area_mm2"] == pytest.approx(13000.0, rel=1e-12)


def test_opener_corpus_is_seeded_and_draws_every_shape():
    a = corpus.furrow_photo_params(24, seed=2, shapes="opener")
    assert a == corpus.furrow_photo_params(24, seed=2, shapes="opener")
    assert {p["shape"] for p in a} == set(corpus.OPENER_SHAPES)
    for p in a:
        xs, zs = map(np.asarray, p["profile"])
        lo, hi = p["span_mm"]
        assert xs[0] <= lo and xs[-1] >= hi and np.all(np.diff(xs) > 0)
        assert zs.max() < p["beam_datum_mm"] - 15.0 and zs.min() > -20.0
        assert p["coeffs"] is None
    with pytest.raises(ValueError):
        corpus.furrow_photo_params(1, shapes="spline")


def test_a_grid_line_beside_a_beam_with_its_shadow_merged_is_no_edge_of_it(tmp_path):
    """Photo 133 of the opener corpus: the beam's shadow (13 mm below it, half as dark) merges
    with it into one dark bar, and a line of the board's grid runs parallel to it well below
    (the camera rolled 4.1 deg).  The grid line's step is sharper than the shadow's blurred
    lower edge: taken for the bar's lower edge, it put the beam's core onto the board and its
    ends onto vertical grid lines (the scale 15.2 % short, the area +38.9 %, confidence ok).
    Looked for within a few pixels of the bar, the lower edge is the shadow's; the scale is
    then within 2.5 % (what is left: the shadow's end reaches past the beam's)."""
    p = corpus.furrow_photo_params(134, seed=0, shapes="opener")[133]
    path, truth = corpus.write_furrow_photo(p, tmp_path, "o133")
    r = _measure(path, truth)
    assert abs(r.px_per_mm / truth["px_per_mm"] - 1) < 0.025
    assert abs(r.area_mm2 / truth["area_mm2"] - 1) < 0.10
