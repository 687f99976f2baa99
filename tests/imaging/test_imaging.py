"""Image pipeline against the renderer's analytic ground truth and the printed values."""

from __future__ import annotations

import functools
import gc
import json
import shutil
import weakref
from pathlib import Path

import numpy as np
import pytest

from soilcal.errors import InputError
from soilcal.imaging import drum, measure, render, scenes
from soilcal.imaging.manifest import read_manifest

ROOT = Path(__file__).resolve().parents[2]
IMAGES = ROOT / "resources" / "images"


def _truth(photo):
    return json.loads(Path(str(photo) + ".truth.json").read_text())


def _photos(kind):
    out = []
    for soil in scenes.SOILS:
        m = read_manifest(IMAGES / soil / "manifest.yaml")
        out += [IMAGES / soil / p["file"] for p in m["photos"] if p["kind"] == kind]
    return out


# --- printed values in the scene list --------------------------------------------------------

def test_scene_values_as_printed():
    by = {s.name: s for s in scenes.SCENES["cinnamon-soil"]}
    assert by["stacking_1"].left_deg == 27.69  # 002 Sec. 2.4
    bs = {s.name: s for s in scenes.SCENES["black-soil"]}
    assert (bs["soil_soil_S"].left_deg, bs["soil_soil_S"].right_deg) == (35.07, 35.37)  # 001 Eqs. 6-7
    assert (bs["soil_steel_S"].left_deg, bs["soil_steel_S"].right_deg) == (32.68, 33.03)  # Eqs. 9-10
    vy = {s.name: s.target_deg for s in scenes.SCENES["xinjiang-vineyard"]}
    assert [vy[f"static_{k}"] for k in ("upper", "middle", "lower")] == [30.82, 32.35, 33.77]
    assert [vy[f"drum_{k}"] for k in ("upper", "middle", "lower")] == [42.7, 43.91, 45.7]
    assert all(s.label == "simulated" for s in scenes.SCENES["guangxi-cohesive"])


def test_furrow_area_consistent_with_printed_error():
    # 000: area difference 0.30 dm^2 is a 9.15 % error -> measured area about 3.28 dm^2
    area = scenes.furrow_chord_area() / 1e4
    assert abs(area - 0.30 / 0.0915) / area < 0.05


def test_black_soil_four_view_mean_is_printed_value():
    g = [s for s in scenes.SCENES["black-soil"] if s.group == "soil_soil"]
    flanks = [a for s in g for a in (s.left_deg, s.right_deg)]
    assert abs(np.mean(flanks) - 35.2) < 0.05


# --- committed rendered set: within +/-0.3 deg of the truth ---------------------------------

@functools.lru_cache(maxsize=None)
def _measured(photo):
    """measure_pile(photo) of a committed photo, measured once for the tests of this file that
    read it (the file runs on one worker)."""
    return measure.measure_pile(photo)


@pytest.mark.parametrize("photo", _photos("pile"), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_pile_angles_rendered_set(photo):
    t = _truth(photo)
    r = _measured(photo)
    assert abs(r.left_deg - t["left_deg"]) <= 0.3
    assert abs(r.right_deg - t["right_deg"]) <= 0.3
    assert abs(r.angle_deg - t["angle_deg"]) <= 0.3
    assert abs(r.roll_deg - t["roll_deg"]) <= 0.1


def test_drum_groups_rendered_set():
    frames = _photos("drum")
    groups = {}
    for f in frames:
        groups.setdefault(f.name.rsplit("_f", 1)[0], []).append(f)
    assert len(groups) == 3
    for name, fs in groups.items():
        summary, res = drum.measure_drum(fs)
        truths = [_truth(f) for f in fs]
        mean_truth = truths[0]["frame_mean_deg"]
        assert abs(np.mean([t["angle_deg"] for t in truths]) - mean_truth) < 1e-9
        assert abs(summary["angle_deg"] - mean_truth) <= 0.3, name
        assert summary["level_reference"] == "plate" and summary["drum_reference"] == "rim"
        for r, t in zip(res, truths):
            assert abs(r.angle_deg - t["angle_deg"]) <= 0.3


def test_adaptive_threshold_pile_and_drum_rejects_it():
    photo = IMAGES / "cinnamon-soil" / "stacking_1.jpg"
    t = _truth(photo)
    r = measure.measure_pile(photo, threshold="adaptive")
    assert abs(r.left_deg - t["left_deg"]) <= 0.3 and abs(r.right_deg - t["right_deg"]) <= 0.3
    frame = IMAGES / "xinjiang-vineyard" / "drum_upper_f01.jpg"
    with pytest.raises(InputError, match="threshold"):
        drum.measure_drum_frame(frame, threshold="adaptive")


def test_multiview_average_black_soil():
    # the group's summary as measure_piles makes it (pile_summary of the photos' results,
    # ok only) from the four photos measured above; measure_piles itself runs in
    # test_cli_pile_json
    m = read_manifest(IMAGES / "black-soil" / "manifest.yaml")
    files = [IMAGES / "black-soil" / p["file"] for p in m["photos"] if p["group"] == "soil_soil"]
    summary = measure.pile_summary([_measured(f) for f in files], ok_only=True)
    assert summary["n_photos"] == 4
    assert abs(summary["angle_deg"] - 35.2) <= 0.3  # printed final value, 001 Sec. 3.1.2
    assert 0 < summary["spread_deg"] < 0.5


def test_furrow_profile_and_area():
    photo = IMAGES / "yangtze-clay-loam" / "furrow.jpg"
    t = _truth(photo)
    r = measure.measure_furrow(photo, 440.0, t["beam_datum_mm"], degree=9)
    assert abs(r.area_mm2 / t["area_mm2"] - 1) < 0.02
    x = np.linspace(-200, 200, 9)
    assert np.max(np.abs(np.polyval(r.coeffs, x) - scenes.furrow_profile(x))) < 2.0
    r4 = measure.measure_furrow(photo, 440.0, t["beam_datum_mm"], degree=4)
    assert r4.degree == 4 and len(r4.coeffs) == 5


@pytest.fixture(scope="module")
def copy_beside_a_false_sidecar(tmp_path_factory):
    """cinnamon-soil's first photo copied beside a false truth sidecar and measured once, for
    the two tests that read the measurement: with the garbage collector off and a weak
    reference to each cue object the measurement makes (:func:`measure._grays`), read right
    after ``measure_pile`` returns.  Returns (result, whether each cue object was still
    alive then)."""
    folder = tmp_path_factory.mktemp("sidecar")
    shutil.copy(IMAGES / "cinnamon-soil" / "stacking_1.jpg", folder / "p.jpg")
    (folder / "p.jpg.truth.json").write_text('{"left_deg": 99}')
    made = []
    grays = measure._grays

    def kept(*a, **k):
        cues = grays(*a, **k)
        made.append(weakref.ref(cues))
        return cues

    with pytest.MonkeyPatch.context() as m:
        m.setattr(measure, "_grays", kept)
        gc.disable()
        try:
            res = measure.measure_pile(folder / "p.jpg")
            alive = [r() is not None for r in made]
        finally:
            gc.enable()
    return res, alive


def test_measurement_does_not_read_sidecar(copy_beside_a_false_sidecar):
    # the committed photo beside its true sidecar and a copy beside a false one measure alike
    res, _ = copy_beside_a_false_sidecar
    assert res.angle_deg == _measured(IMAGES / "cinnamon-soil" / "stacking_1.jpg").angle_deg


# --- harder set, rendered at test time ------------------------------------------------------

@pytest.mark.parametrize("seed", range(101, 109))
def test_hard_set_within_one_degree(tmp_path, seed, monkeypatch):
    """Strong shadows, roll up to 3 deg, dark soil on a dark background: the photo's angle
    within 1 deg; a single flank next to the cast shadow may stray further (1.5 deg).  Every
    class the measurement takes from its cache of segmented classes (several plate lines and
    checks give one cue the same threshold) is the class segmented afresh from that cue."""
    from skimage import filters

    img, t = render.render_pile(seed, 35.07, 35.37, soil="black-soil", hard=True)
    assert abs(t["roll_deg"]) <= 3
    p = render.save_photo(tmp_path / "hard.jpg", img, t)
    stale, expected = [], []
    pile_with, on_plate = measure._pile_with, measure._components_on_plate

    def checked(path, rgb, gray, cue, polarity, band, *args, **kw):
        # the class segmented afresh: open_fill of the cue below Otsu's threshold of the band
        threshold = args[2] if len(args) > 2 else kw.get("threshold")
        th = None
        if threshold == "otsu":
            th = filters.threshold_otsu(gray[band]) if kw.get("otsu") is None else kw["otsu"]
        expected.append(None if th is None else measure.open_fill(gray < th))
        try:
            return pile_with(path, rgb, gray, cue, polarity, band, *args, **kw)
        finally:
            expected.pop()

    def used(path, binary, *args, **kw):  # the class _pile_with goes on with (its first call)
        if expected and expected[-1] is not None:
            if not np.array_equal(binary, expected[-1]):
                stale.append(path)
            expected[-1] = None
        return on_plate(path, binary, *args, **kw)

    monkeypatch.setattr(measure, "_pile_with", checked)
    monkeypatch.setattr(measure, "_components_on_plate", used)
    r = measure.measure_pile(p)
    assert stale == []
    assert abs(r.angle_deg - t["angle_deg"]) <= 1.0
    assert abs(r.left_deg - t["left_deg"]) <= 1.5
    assert abs(r.right_deg - t["right_deg"]) <= 1.5


def _heap_mask(h, w, plate_row, cx, height, angle_deg):
    """Pixels (by their centres) of a heap with both flanks at ``angle_deg`` to a horizontal
    plate at ``plate_row``, its apex ``height`` px above it in column ``cx``."""
    rr, cc = np.mgrid[0:h, 0:w] + 0.5
    return (rr < plate_row) & (plate_row - rr < height - np.abs(cc - cx) * np.tan(np.radians(angle_deg)))


def test_segmented_class_cache_tells_cues_and_polarities_apart():
    """Two cues and the two polarities of one cue at the same threshold each keep their own
    class in the photo's cache of segmented classes (:class:`measure._Cues`).  A three-level
    luminance (heap A at 0.2, heap B at 0.8, the rest exactly 0.5) holds heap A (30 deg
    flanks) in its dark class and heap B (45 deg) in its light one, and neither is the rest
    (0.5 is not below 0.5, nor is 1 - 0.5); the chroma cue holds heap B dark.  All three are
    segmented at 0.5 on one plate line, in the order a cue search takes them, with one cache:
    each measures its own heap, as without the cache."""
    h, w, plate = 100, 280, 80.0
    a = _heap_mask(h, w, plate, 75.25, 36.0, 30.0)  # half base 62.4 px
    b = _heap_mask(h, w, plate, 210.25, 48.0, 45.0)  # half base 48 px; no pixel centre on a flank
    lum = np.full((h, w), 0.5)
    lum[a], lum[b] = 0.2, 0.8
    chroma = np.where(b, 0.2, 0.8)
    rgb = np.repeat(lum[..., None], 3, axis=-1)
    cues = measure._Cues({"gray": lum, "chroma": chroma})
    rr = np.arange(h)[:, None]
    band = np.broadcast_to((rr < plate - 3) & (rr > plate - 0.35 * h), (h, w))
    calls = [("gray", "dark", 30.0), ("gray", "light", 45.0), ("chroma", "dark", 45.0)]

    def angles(segmented):
        out = []
        for cue, pol, _ in calls:
            g = cues[cue] if pol == "dark" else 1.0 - cues[cue]
            r = measure._pile_with("synthetic.png", rgb, g, cue, pol, band, 0.0, plate, "otsu", False,
                                   lum=lum, otsu=0.5, segmented=segmented)
            assert r.cue == f"{cue}/{pol}"
            out.append((r.left_deg, r.right_deg))
        return np.array(out)

    cached = angles(cues.segmented)
    for (cue, pol, truth), flanks in zip(calls, cached):
        assert np.abs(flanks - truth).max() < 0.5, (cue, pol, flanks)
    assert np.array_equal(cached, angles(None)) and len(cues.segmented) == 3


def test_local_threshold_class_is_segmented_once_for_every_plate_line(monkeypatch):
    """With ``threshold="adaptive"`` a cue's class does not depend on the plate line (the local
    threshold is the cue's own, pixel by pixel): segmented once per cue and polarity in the
    photo's cache of segmented classes, and each line measures the heap (35 deg flanks) as
    with the class segmented afresh."""
    h, w = 300, 300
    lum = np.full((h, w), 0.8)
    lum[_heap_mask(h, w, 240.0, 150.25, 50.0, 35.0)] = 0.3
    lum[240:] = 0.6  # a plate darker than the wall: no wall above it darker than its surroundings
    rgb = np.repeat(lum[..., None], 3, axis=-1)
    rr = np.arange(h)[:, None]
    calls = []
    binary = measure._binary
    monkeypatch.setattr(measure, "_binary", lambda *a: calls.append(a[2]) or binary(*a))

    def angles(segmented, intercept):
        band = np.broadcast_to((rr < intercept - 3) & (rr > intercept - 0.35 * h), (h, w))
        r = measure._pile_with("synthetic.png", rgb, lum, "gray", "dark", band, 0.0, intercept, "adaptive", False,
                               lum=lum, segmented=segmented)
        return r.left_deg, r.right_deg

    cache = {}
    cached = [angles(cache, b) for b in (240.0, 239.6)]
    assert calls == ["adaptive"] and list(cache) == [("gray", "dark", "adaptive")]
    assert cached == [angles(None, b) for b in (240.0, 239.6)] and len(calls) == 3
    assert np.abs(np.array(cached) - 35.0).max() < 0.5


def test_cues_are_made_when_first_read():
    """A photo's cue images (:class:`measure._Cues` given the photo) are each channel's own
    (:func:`measure._gray`), made as the search first reads them: L*a*b* is converted once, for
    the first of its two cues, and never for a search that reads luminance and chroma only."""
    rng = np.random.default_rng(5)
    rgb = rng.random((40, 60, 3))
    made = []
    lab = measure._smoothed_lab

    def counted(x):
        made.append(1)
        return lab(x)

    lum = measure._gray(rgb)
    cues = measure._grays(rgb, measure.CUES, lum)
    orig, measure._smoothed_lab = measure._smoothed_lab, counted
    try:
        assert cues["gray"] is lum and np.array_equal(cues["chroma"], measure._gray(rgb, "chroma"))
        assert made == []
        for ch in ("lab_b", "saturation", "lab_a"):
            assert np.array_equal(cues[ch], measure._gray(rgb, ch, lab(rgb)))
        assert len(made) == 1 and sorted(cues) == sorted(measure.CUES)
    finally:
        measure._smoothed_lab = orig
    with pytest.raises(KeyError):
        cues["hue"]


def test_a_photos_cue_images_are_freed_without_the_garbage_collector():
    """A photo's cue images and what its plate lines keep (band, separabilities, levelled
    images) go with the last reference to the photo's cues: no reference cycle holds them until
    a full garbage collection (each photo of a batch would otherwise stay in memory).  The
    separabilities read are each cue's :func:`measure._eta` in the band, kept for the line."""
    rng = np.random.default_rng(3)
    rgb = rng.random((40, 60, 3))
    gc.disable()
    try:
        cues = measure._grays(rgb, measure.CUES, measure._gray(rgb))
        band, split, levelled = measure._line_cues(cues, 0.0, 35.0, (40, 60))
        assert np.array_equal(np.flatnonzero(band.any(axis=1)), np.arange(22, 32))  # 3 px to 35 % above
        for ch in measure.CUES:
            eta, t = split[ch]
            assert (eta, t) == measure._eta(cues[ch][band])
        again = measure._line_cues(cues, 0.0, 35.0, (40, 60))
        assert again[0] is band and again[2] is levelled and again[1]["lab_a"] is split["lab_a"]
        levelled["gray"] = cues["gray"].copy()
        gone = [weakref.ref(cues)] + [weakref.ref(cues[ch]) for ch in measure.CUES]
        del cues, band, split, levelled, again
        assert [r() for r in gone] == [None] * len(gone)
    finally:
        gc.enable()


def test_a_photos_cues_are_freed_when_measure_pile_returns(copy_beside_a_false_sidecar):
    """Right after ``measure_pile`` returns, with the garbage collector off, the photo's cue
    object is gone: neither the cues nor the refusals of the cues and lines tried on the way
    (whose tracebacks hold the search's frames) keep it in a reference cycle.  A batch of heap
    photos measured in one process then holds one photo's images at a time.  The photo is
    cinnamon-soil's first (a copy, :func:`copy_beside_a_false_sidecar`): cues and plate lines
    are refused before the heap is found."""
    res, alive = copy_beside_a_false_sidecar
    assert alive == [False]  # one cue object, gone
    assert res.confidence == "ok"


def test_an_unknown_channel_is_refused_before_any_search(monkeypatch):
    """``channel`` other than "auto" or a cue of :data:`measure.CUES`: one InputError naming the
    photo and the field, before the photo is read or searched."""

    def searched(*a, **k):
        raise AssertionError("searched")

    monkeypatch.setattr(measure, "read_photo_reduced", searched)
    monkeypatch.setattr(measure, "_pile_on_lines", searched)
    photo = IMAGES / "cinnamon-soil" / "stacking_1.jpg"
    for kw in ({}, {"image": np.zeros((30, 40, 3))}):
        with pytest.raises(InputError) as ei:
            measure.measure_pile(photo, channel="hue", **kw)
        assert str(ei.value) == (f"{photo}: channel: expected 'gray', 'chroma', 'lab_a', 'lab_b', "
                                  "'saturation' or 'auto', got 'hue'")
        assert ei.value.field == "channel" and ei.value.got == "hue"


def test_renderer_is_deterministic():
    a, ta = render.render_drum(7, 43.91)
    b, tb = render.render_drum(7, 43.91)
    assert ta == tb and np.array_equal(a, b)


# --- errors naming the file -----------------------------------------------------------------

def _raises_naming(path, fn=measure.measure_pile, **kw):
    with pytest.raises(InputError) as ei:
        fn(path, **kw)
    assert str(path) in str(ei.value)
    return ei.value


def test_unreadable_file(tmp_path):
    p = tmp_path / "notaphoto.jpg"
    p.write_text("this is not an image")
    assert _raises_naming(p).field == "file"


def test_truncated_jpeg(tmp_path):
    data = (IMAGES / "cinnamon-soil" / "stacking_1.jpg").read_bytes()
    p = tmp_path / "truncated.jpg"
    p.write_bytes(data[: len(data) // 2])
    assert _raises_naming(p).field == "file"


def test_blank_image(tmp_path):
    from PIL import Image

    p = tmp_path / "blank.jpg"
    Image.fromarray(np.full((900, 1200, 3), 128, np.uint8)).save(p)
    _raises_naming(p)


def test_no_heap(tmp_path):
    img, t = render.render_pile(4, 30.0, 30.0, n_heaps=0)  # plate, clutter, no heap
    p = render.save_photo(tmp_path / "noheap.jpg", img, t)
    e = _raises_naming(p)
    assert e.field == "image" and "none found" in str(e)


def test_two_heaps(tmp_path):
    img, t = render.render_pile(5, 30.0, 30.0, n_heaps=2)
    p = render.save_photo(tmp_path / "two.jpg", img, t)
    e = _raises_naming(p)
    assert "2 separate heaps" in str(e)


def test_heap_cut_by_frame(tmp_path):
    img, t = render.render_pile(6, 30.0, 30.0, cut=True)
    p = render.save_photo(tmp_path / "cut.jpg", img, t)
    e = _raises_naming(p)
    assert "cut by the image border" in str(e)


# --- CLI ------------------------------------------------------------------------------------

def test_cli_pile_json(capsys, tmp_path):
    from soilcal.cli import main

    files = [str(IMAGES / "cinnamon-soil" / f) for f in ("stacking_1.jpg", "stacking_2.jpg")]
    assert main(["image", "pile", *files, "--figures", str(tmp_path)]) == 0
    out = json.loads(capsys.readouterr().out)
    for k in ("angle_deg", "left_deg", "right_deg", "spread_deg"):
        assert k in out
    assert abs(out["angle_deg"] - 27.69) <= 0.3  # 002 printed mean
    assert (tmp_path / "stacking_1.png").is_file() and (tmp_path / "stacking_1.pdf").is_file()


def test_cli_furrow_json_uses_manifest(capsys):
    from soilcal.cli import main

    assert main(["image", "furrow", str(IMAGES / "yangtze-clay-loam" / "furrow.jpg")]) == 0
    out = json.loads(capsys.readouterr().out)
    assert abs(out["area_mm2"] / scenes.furrow_chord_area() - 1) < 0.02
    assert len(out["profile"]["x_mm"]) == len(out["profile"]["z_mm"]) > 10


def test_cli_error_names_file(capsys, tmp_path):
    from soilcal.cli import main

    p = tmp_path / "bad.jpg"
    p.write_bytes(b"\xff\xd8\xff\xe0garbage")
    assert main(["image", "drum", str(p)]) == 2
    assert str(p) in capsys.readouterr().err


@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.uint8])
def test_saturation_cue_is_hsv_saturation(dtype):
    """The saturation cue is scikit-image's HSV saturation (rgb2hsv's S), smoothed: the same
    numbers, 0 on black and grey pixels (where max = min), for float and 8-bit images."""
    from skimage import color, filters

    rng = np.random.default_rng(3)
    x = rng.random((60, 50, 3))
    x[:8] = 0.0  # black
    x[8:16] = x[8:16, :, :1]  # grey
    x = (x * 255).astype(np.uint8) if dtype == np.uint8 else x.astype(dtype)
    expected = filters.gaussian(color.rgb2hsv(x)[..., 1], 1.2)
    got = measure._gray(x, "saturation")
    assert got.dtype == expected.dtype and np.array_equal(got, expected)


def test_chroma_cue_is_its_formula():
    """The chroma cue is 1/2 - 2 (R - B) / (R + G + B + 0.05) of the smoothed image, clipped to
    [0, 1]: the same numbers as the formula with NumPy's sum over the colour axis."""
    from skimage import filters

    rng = np.random.default_rng(4)
    x = rng.random((60, 50, 3))
    x[:8] = 0.0
    for image in (x, x.astype(np.float32), (x * 255).astype(np.uint8)):
        g = filters.gaussian(image, 1.5, channel_axis=-1)
        expected = np.clip(0.5 - 2.0 * (g[..., 0] - g[..., 2]) / (g.sum(-1) + 0.05), 0, 1)
        got = measure._gray(image, "chroma")
        assert got.dtype == expected.dtype and np.array_equal(got, expected)
