"""Heap photos as users take them: walls of any colour, plates that differ from the wall in hue
only, heaps lighter than the wall, cast shadows, roll.  The truth is the renderer's straight
flank angles relative to the plate; a result is either right or flagged (refused or low
confidence), never silently wrong by more than 1 deg."""

from __future__ import annotations

import numpy as np
import pytest

from soilcal.errors import InputError
from soilcal.imaging import corpus, measure, render

PLAIN = {"clutter": False, "wall_gradient": [0.1, -0.1], "shadow": {"dx_mm": 6.0, "dy_mm": 3.0, "blur_px": 6.0,
                                                                  "darkness": 0.2}}


def _photo(tmp_path, name, left, right, style, roll=1.0, seed=11):
    img, truth = render.render_pile(seed, left, right, roll_deg=roll, style=style)
    return render.save_photo(tmp_path / f"{name}.jpg", img, truth, quality=85), truth


@pytest.fixture(scope="module")
def stress_photo(tmp_path_factory):
    """Photo k of the seeded stress corpus (seed 0), written once for this file's tests, and
    its default measurement (measure_pile's result or its InputError), also made once."""
    folder = tmp_path_factory.mktemp("stress")
    params = corpus.pile_photo_params(197, seed=0)
    done = {}

    def photo(k):
        if k not in done:
            path, truth = corpus.write_pile_photo(params[k], folder, f"s{k:03d}")
            try:
                r = measure.measure_pile(path)
            except InputError as e:
                r = e
            done[k] = path, truth, r
        return done[k]

    return photo


def _check(r, truth):
    # the photo's value (mean of the flanks) within 0.3 deg, each flank within 0.5 deg
    assert abs(r.angle_deg - truth["angle_deg"]) <= 0.3
    assert abs(r.left_deg - truth["left_deg"]) <= 0.5
    assert abs(r.right_deg - truth["right_deg"]) <= 0.5
    assert abs(r.roll_deg - truth["roll_deg"]) <= 0.15


def test_heap_lighter_than_a_dark_wall(tmp_path):
    # rolled the other way and further than the photos below (roll 1.0)
    style = PLAIN | {"wall_rgb": [0.12, 0.12, 0.14], "soil_rgb": [0.62, 0.55, 0.45]}
    p, truth = _photo(tmp_path, "dark", 33.0, 36.0, style, roll=-4.5)
    r = measure.measure_pile(p)
    _check(r, truth)
    assert r.confidence == "ok"


def test_heap_on_a_plain_grey_green_wall(tmp_path):
    style = PLAIN | {"wall_rgb": [0.45, 0.52, 0.42], "soil_rgb": [0.55, 0.45, 0.33]}
    p, truth = _photo(tmp_path, "greygreen", 28.0, 31.0, style)
    _check(measure.measure_pile(p), truth)


def test_plate_differing_from_the_wall_in_hue_only(tmp_path):
    # a purple wall and a grey plate of about the same brightness, no chamfer highlight
    style = PLAIN | {"wall_rgb": [0.55, 0.35, 0.75], "plate": {"thick_mm": 4.0, "grey": 0.47, "highlight": False},
                     "soil_rgb": [0.60, 0.45, 0.31]}
    p, truth = _photo(tmp_path, "purple", 38.0, 41.0, style)
    _check(measure.measure_pile(p), truth)


def test_empty_plate_on_a_coloured_wall_is_refused(tmp_path):
    # no heap: every cue is tried, none may invent one
    for k, wall in enumerate(([0.45, 0.52, 0.42], [0.12, 0.12, 0.14], [0.80, 0.78, 0.74])):
        img, truth = render.render_pile(4 + k, 30.0, 30.0, n_heaps=0, style=PLAIN | {"wall_rgb": wall})
        p = render.save_photo(tmp_path / f"empty{k}.jpg", img, truth)
        with pytest.raises(InputError) as e:
            measure.measure_pile(p)
        assert str(p) in str(e.value)


def test_stress_subset_right_or_flagged(stress_photo):
    """The first 8 photos of the seeded stress corpus (the whole corpus is
    benchmarks/pile_photos.py): none silently wrong by more than 1 deg; at least 5 measured
    within 0.3 deg with confidence ok.  Six of the 8 are such heaps by construction (the
    benchmark's 500 photos are so measured in 92 %), so the test fails once two of them go
    wrong: a broad drift of 20 % of photos past 0.3 deg is caught with probability about 0.34
    here (0.8 with 16 photos); the benchmark is the check of accuracy over the corpus.  The 8
    hold both of the benchmark's ways out: a heap cut by the image border (refused) and one
    whose flank reads 6 deg off (flagged low)."""
    good = 0
    for k in range(8):
        path, truth, r = stress_photo(k)
        if isinstance(r, InputError):
            continue
        err = abs(r.angle_deg - truth["angle_deg"])
        if r.confidence == "ok":
            assert err <= 1.0, (k, err, r.cue)
            good += err <= 0.3
    assert good >= 5


def test_corpus_is_seeded():
    a = corpus.pile_photo_params(3, seed=5)
    b = corpus.pile_photo_params(3, seed=5)
    assert a == b and a != corpus.pile_photo_params(3, seed=6)
    img1, _ = render.render_pile(a[0]["seed"], a[0]["left_deg"], a[0]["right_deg"], roll_deg=a[0]["roll_deg"],
                                 style=a[0]["style"])
    img2, _ = render.render_pile(a[0]["seed"], a[0]["left_deg"], a[0]["right_deg"], roll_deg=a[0]["roll_deg"],
                                 style=a[0]["style"])
    assert np.array_equal(img1, img2)


def test_a_second_cue_flags_a_flank_the_first_one_misreads(stress_photo, monkeypatch):
    """Photo 64 of the seeded corpus: a heap of nearly the wall's hue whose right flank the
    first cue (luminance, heap lighter) reads 6 deg off its rendered 22.7 deg with a clean line
    fit (under 1 px RMS), so neither fit check sees it; the second cue disagrees and the result
    is flagged.  The flank is the shaded one, lost to a wall as dark as it: the soil's grain
    then locates it within 0.5 deg (the result stays low).  Photo 0: two cues agree within
    1 deg, confidence stays ok."""
    path, truth, r64 = stress_photo(64)
    with monkeypatch.context() as m:
        m.setattr(measure, "_texture_flanks", lambda res, lum: res)
        r = measure.measure_pile(path)
    assert abs(r.right_deg - truth["right_deg"]) > 1.0 and r.flank_rms_px < 2.5  # wrong, cleanly fitted
    assert r.cue_check and r.cue_check != r.cue and r.cue_check_deg > measure.CUE_AGREEMENT_DEG
    assert r.confidence == "low"
    r = r64
    assert r.texture_flanks == "right" and r.confidence == "low"
    assert abs(r.right_deg - truth["right_deg"]) <= 0.5 and abs(r.angle_deg - truth["angle_deg"]) <= 0.3
    path, truth, r = stress_photo(0)
    assert r.cue_check and r.cue_check_deg <= measure.CUE_AGREEMENT_DEG and r.confidence == "ok"
    assert abs(r.angle_deg - truth["angle_deg"]) <= 0.3


def test_a_third_cue_decides_between_two_that_disagree(stress_photo):
    """Photos 27 and 196 of the seeded corpus.  27: the first cue (luminance) reads both
    flanks within 0.3 deg of the rendered ones, the chroma cue reads a flank more than 1 deg
    away; the next credible cue agrees with the first, so the dissent is outvoted, recorded,
    and the result stays ok.  196: the first cue (luminance) reads the right flank 2.4 deg
    flat, the next credible cue reads it within 0.1 deg, and no third cue measures a heap to
    decide between the two: flagged low."""
    path, truth, r = stress_photo(27)
    assert abs(r.left_deg - truth["left_deg"]) <= 0.3 and abs(r.right_deg - truth["right_deg"]) <= 0.3
    assert r.cue_outvoted and r.cue_outvoted_deg > measure.CUE_AGREEMENT_DEG
    assert r.cue_check not in ("", r.cue_outvoted) and r.cue_check_deg <= measure.CUE_AGREEMENT_DEG
    assert r.confidence == "ok"
    path, truth, r = stress_photo(196)
    assert abs(r.right_deg - truth["right_deg"]) > 1.0  # the first cue's reading, refuted
    assert r.cue_check and r.cue_outvoted == ""
    assert r.cue_check_deg > measure.CUE_AGREEMENT_DEG and r.confidence == "low"


def test_a_flank_line_inside_the_heap_is_flagged_and_cannot_refute(stress_photo):
    """Photo 183 of the seeded corpus: luminance alone reads the left flank 4.6 deg steep (its
    fitted edge runs inside the heap: the strip just outside the line is still more than half
    way from the wall's level to the heap's), so that reading is low; in the cue search it is
    then no credible dissent, and the first cue, within 0.3 deg, stands confirmed and ok."""
    path, truth, r = stress_photo(183)
    g = measure.measure_pile(path, channel="gray")
    assert abs(g.left_deg - truth["left_deg"]) > 4.0
    assert g.flank_outside_share > measure.FLANK_OUTSIDE_MAX and g.confidence == "low"
    assert abs(r.left_deg - truth["left_deg"]) <= 0.3 and abs(r.right_deg - truth["right_deg"]) <= 0.3
    assert r.cue_outvoted == "" and r.cue_check and r.cue_check_deg <= measure.CUE_AGREEMENT_DEG
    assert r.flank_outside_share < 0.2 and r.confidence == "ok"


def test_a_cue_that_does_not_split_the_band_neither_confirms_nor_refutes(stress_photo):
    """Photo 56 of the seeded corpus: luminance splits the band above the plate poorly
    (Otsu's eta below MIN_CUE_ETA) and reads a flank 10 deg off; it is not taken as a
    check, the next clear cue confirms the first, which is within 0.3 deg."""
    path, truth, r = stress_photo(56)
    assert r.confidence == "ok" and r.cue_check and r.cue_check_deg <= measure.CUE_AGREEMENT_DEG
    assert r.cue_outvoted == ""
    assert abs(r.angle_deg - truth["angle_deg"]) <= 0.3


def test_a_colour_cue_edge_is_refined_in_luminance(tmp_path, monkeypatch):
    """A light heap on a dark, browner wall, saved as JPEG at quality 60 (colour subsampled in
    16 px blocks): the chroma cue segments the heap, and its blocky edge reads the shaded right
    flank flatter than rendered.  Refined in luminance (full resolution, a clear step at this
    edge) every flank is within 0.5 deg and the photo's value within 0.3 deg; with the
    luminance refinement switched off a flank of the second photo is more than 0.5 deg off
    (each of the three reads one 0.8 to 3.0 deg off so)."""
    style = PLAIN | {"wall_rgb": [0.26, 0.24, 0.22], "soil_rgb": [0.64, 0.57, 0.47], "noise": 0.01,
                     "blur_px": 1.4, "scale_bar": False,
                     "shadow": {"dx_mm": -18.0, "dy_mm": 8.0, "blur_px": 3.0, "darkness": 0.15}}
    photos = []
    for seed in (1, 2, 4):
        img, truth = render.render_pile(seed, 28.5, 26.5, roll_deg=-0.5, style=style)
        photos.append((render.save_photo(tmp_path / f"lum{seed}.jpg", img, truth, quality=60), truth))
    for p, truth in photos:
        r = measure.measure_pile(p)
        assert r.cue.startswith("chroma")
        assert abs(r.angle_deg - truth["angle_deg"]) <= 0.3
        assert abs(r.left_deg - truth["left_deg"]) <= 0.5 and abs(r.right_deg - truth["right_deg"]) <= 0.5
    monkeypatch.setattr(measure, "LUM_EDGE_SNR", np.inf)
    p, truth = photos[1]
    r = measure.measure_pile(p)
    assert max(abs(r.left_deg - truth["left_deg"]), abs(r.right_deg - truth["right_deg"])) > 0.5


def _flank_image(side, heap=0.2, wall=0.8, h=300, w=400, prow=250.0, edge=200.0):
    """A levelled cue image with one 45 deg flank meeting the plate at column ``edge``: the
    heap (darker) at heights above the plate row of at most side * (edge - u) (side -1: a
    left flank rising to the right), the wall elsewhere."""
    rows, cols = np.mgrid[0:h, 0:w].astype(float)
    return np.where(prow - rows <= side * (edge - cols), heap, wall), prow


@pytest.mark.parametrize("side", [-1.0, 1.0])
@pytest.mark.parametrize("shift, want", [(0.0, 0.0), (12.0, 1.0), (-12.0, float("nan"))])
def test_outside_share_of_a_straight_flank(side, shift, want):
    """A line on the edge has the wall right outside it (share 0); a line 12 px inside the
    heap, along its normal, has heap in its 3-8 px outside strip (share 1); a line 12 px out
    in the wall has wall in its inside strip as well: no step to judge (NaN)."""
    glev, prow = _flank_image(side)
    u0 = 200.0 - side * shift * np.sqrt(2.0)  # shift px along the normal, into the heap
    share = measure._outside_share(glev, prow, (u0, 0.0, 1.0, -side), side, 20.0, 120.0)
    if np.isnan(want):
        assert np.isnan(share)
    else:
        assert share == pytest.approx(want, abs=1e-9)


def test_outside_share_is_not_judged_on_a_weak_step():
    glev, prow = _flank_image(-1.0, heap=0.78, wall=0.8)
    assert np.isnan(measure._outside_share(glev, prow, (200.0, 0.0, 1.0, 1.0), -1.0, 20.0, 120.0))


def test_a_flank_outside_the_heap_is_flagged_when_the_other_is_not_judged(tmp_path, monkeypatch):
    """The left flank's share not judged (NaN), the right one's 0.7: the photo's share is 0.7
    and it is low (the larger judged share, whichever flank comes first)."""
    p, _ = _photo(tmp_path, "nan_first", 33.0, 36.0, PLAIN | {"wall_rgb": [0.8, 0.8, 0.78]})
    shares = iter([float("nan"), 0.7])
    monkeypatch.setattr(measure, "_outside_share", lambda *a, **k: next(shares))
    r = measure.measure_pile(p, channel="gray")
    assert r.flank_outside_share == 0.7 and r.confidence == "low"


def _texture_map(side, hmax=120.0, heap=1.0, wall=0.1, h=300, w=400, prow=250.0, edge=200.0):
    """A levelled texture map of a flat-topped heap ``hmax`` px high with one 45 deg flank
    meeting the plate at column ``edge`` (as :func:`_flank_image`), blurred by a symmetric
    Gaussian: the mid-level between heap and wall lies on the flank."""
    from skimage import filters

    rows, cols = np.mgrid[0:h, 0:w].astype(float)
    v = prow - rows
    e = np.where((v >= 0) & (v <= side * (edge - cols)) & (v <= hmax), heap, wall)
    return filters.gaussian(e, 3.0), prow


@pytest.mark.parametrize("side", [-1.0, 1.0])
def test_texture_edge_of_a_straight_flank(side):
    """The cue's line runs through the apex at 60 deg, inside the heap; the texture edge
    found outward from it is the 45 deg flank."""
    hmax = 120.0
    e, prow = _texture_map(side, hmax)
    a60 = np.radians(60.0)
    line = (200.0 - side * hmax, hmax, -side * np.cos(a60), np.sin(a60))
    ang, tline, used, rms = measure._texture_edge("map", e, prow, line, side, hmax, "flank")
    assert ang == pytest.approx(45.0, abs=0.1)
    assert used > 0.95 and rms < 0.3


def _shaded_heap(path, left=35.0, right=40.0, grain=0.06, h=600, w=800, prow=420, height=200, seed=0):
    """A grey heap photo with grain of SD ``grain`` on the heap, lit on the left (0.75) and
    shaded on the right: each row's luminance falls linearly from 0.75 at the apex column to
    the wall's 0.30 at the flank's edge, so no brightness threshold sees the flank's edge;
    plate 0.9 below, the wall with a camera noise of 0.004."""
    from skimage import io

    rng = np.random.default_rng(seed)
    rr, cc = np.mgrid[0:h, 0:w].astype(float)
    apex, v = 380.0, prow - rr
    tl, tr = np.tan(np.radians(left)), np.tan(np.radians(right))
    dr = (cc - apex) - (height - v) / tr  # < 0 inside the right flank
    heap = (v > 0) & (v <= height) & ((apex - cc) - (height - v) / tl < 0) & (dr < 0)
    f = np.clip(-dr / np.maximum((height - v) / tr, 1e-9), 0.0, 1.0)
    img = 0.30 + rng.normal(0.0, 0.004, (h, w))
    img[heap] = np.where(cc <= apex, 0.75, 0.30 + 0.45 * f)[heap] + rng.normal(0.0, grain, int(heap.sum()))
    img[(rr >= prow) & (rr < prow + 20)] = 0.9
    img[rr >= prow + 20] = 0.5
    rgb = (np.repeat(np.clip(img, 0, 1)[..., None], 3, -1) * 255).astype(np.uint8)
    io.imsave(path, rgb, check_contrast=False)
    return path


def test_a_shaded_flank_lost_to_the_wall_is_found_in_its_grain(tmp_path):
    """The brightness cue reads the shaded right flank steep (its line inside the heap, low
    confidence); the grain of the soil locates it again within 1 deg of 40, the lit flank
    stays as measured, and the result stays low.  A heap without grain keeps its steep
    flank: the texture has nothing to find."""
    r = measure.measure_pile(_shaded_heap(tmp_path / "grain.png"))
    assert r.texture_flanks == "right" and r.confidence == "low"
    assert abs(r.right_deg - 40.0) < 1.0 and abs(r.left_deg - 35.0) < 0.5
    assert r.angle_deg == pytest.approx((r.left_deg + r.right_deg) / 2)
    smooth = measure.measure_pile(_shaded_heap(tmp_path / "smooth.png", grain=0.0))
    assert smooth.texture_flanks == "" and smooth.confidence == "low" and smooth.right_deg > 50.0


@pytest.mark.parametrize("cue_deg, moved", [(30.0, False), (40.0, True), (35.5, False)])
def test_only_a_texture_line_flatter_than_the_cue_moves_a_flank(tmp_path, cue_deg, moved):
    """The lit left flank of the grained heap (35 deg) as a cue might have read it, through
    the apex: a cue line at 40 deg (inside the heap) takes the texture's 35 deg line; one at
    30 deg (out in the wall, e.g. a cast shadow joined to the flank) is left alone, and so is
    one within 1 deg of the texture's."""
    from skimage import io

    path = _shaded_heap(tmp_path / "lit.png")
    lum = measure._gray(io.imread(path) / 255.0)
    a = np.radians(cue_deg)
    lline = (380.0, 200.0, float(np.cos(a)), float(np.sin(a)))
    rline = (380.0, 200.0, -float(np.cos(np.radians(40.0))), float(np.sin(np.radians(40.0))))
    res = measure.PileResult(str(path), (cue_deg + 40.0) / 2, cue_deg, 40.0, 0.0, 0.0, cue="gray/light",
                             confidence="low", geometry=(0.0, 420.0, lline, rline, 200.0))
    out = measure._texture_flanks(res, lum)
    if moved:
        assert out.texture_flanks.startswith("left") and abs(out.left_deg - 35.0) < 0.5
        assert out.angle_deg == pytest.approx((out.left_deg + out.right_deg) / 2)
    else:
        assert "left" not in out.texture_flanks and out.left_deg == cue_deg
