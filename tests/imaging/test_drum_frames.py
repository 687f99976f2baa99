"""Drum frames as drum testers export them: cropped to the drum, grey, time-averaged, S-shaped,
no plate in view.  The truth is the generator's analytic surface (render_tester_frame: the
least-squares line over the central 60 % of the chord is at exactly ``angle_deg``)."""

from __future__ import annotations

import copy
import functools
import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy import ndimage as ndi

from soilcal.errors import InputError
from soilcal.imaging import drum, render
from soilcal.imaging.manifest import measure_manifest, read_manifest

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "resources" / "images" / "xinjiang-vineyard"

# (angle, s_amp, blur_px, jitter_px, fill): slow rolling to fast cascading drums
SPEEDS = [(32.0, 0.0, 1.5, 1.0, 0.30), (38.0, 0.04, 2.5, 3.0, 0.35),
          (44.0, 0.08, 3.5, 5.0, 0.40), (50.0, 0.12, 5.0, 8.0, 0.45)]


@functools.lru_cache(maxsize=None)
def _stand_photo(roll):
    """render_drum(3, 35.0, roll_deg=roll): a drum on its stand, rendered once for the tests of
    this file that use it (the file runs on one worker); the image is read-only, so no test
    alters another's input, and _stand gives each caller its own copy of the truth."""
    img, truth = render.render_drum(3, 35.0, roll_deg=roll)
    img.flags.writeable = False
    return img, truth


def _stand(roll):
    img, truth = _stand_photo(roll)
    return img, copy.deepcopy(truth)


def _frame(tmp_path, name, bits=8, **kw):
    img, truth = render.render_tester_frame(**({"seed": 3} | kw))
    return render.save_frame(tmp_path / name, img, bits=bits), truth


@pytest.mark.parametrize("window", ["crop", "rim"])
@pytest.mark.parametrize("speed", SPEEDS, ids=lambda s: f"{s[0]:.0f}deg-S{s[1]}")
def test_central_slope_within_half_degree(tmp_path, window, speed):
    angle, s_amp, blur, jitter, fill = speed
    p, truth = _frame(tmp_path, "f.png", angle_deg=angle, s_amp=s_amp, blur_px=blur, jitter_px=jitter,
                      fill=fill, window=window)
    r = drum.measure_drum_frame(p)
    assert abs(r.angle_deg - truth["angle_deg"]) <= 0.5
    assert r.level_reference == "image axes" and r.roll_deg == 0.0
    assert r.drum_reference == "rim"


@pytest.mark.parametrize("angle", [-33.0, 47.0])
def test_frame_inside_a_larger_drum(tmp_path, angle):
    # no rim in view: a straight surface is measured against the image border's circle; an
    # S-shaped one needs the drum (its central chord is the drum's), given as in the manifest
    p, truth = _frame(tmp_path, "f.png", angle_deg=angle, window="inside", blur_px=3.0)
    r = drum.measure_drum_frame(p)
    assert r.drum_reference == "image border" and abs(r.angle_deg - abs(angle)) <= 0.5
    p, truth = _frame(tmp_path, "s.png", angle_deg=angle, s_amp=0.1, window="inside", blur_px=3.0)
    r = drum.measure_drum_frame(p, options={"drum_centre_px": truth["centre_px"],
                                            "drum_radius_px": truth["radius_px"]})
    assert r.drum_reference == "manifest" and abs(r.angle_deg - abs(truth["angle_deg"])) <= 0.5


def test_rim_circle_found_where_it_is(tmp_path):
    p, truth = _frame(tmp_path, "rim.png", angle_deg=40.0, window="rim")
    r = drum.measure_drum_frame(p)
    assert r.drum_reference == "rim"
    # the rim is a 4 px wide ring from radius R outwards; the fitted circle lies in it
    assert np.hypot(*(np.array(r.drum_centre_px) - truth["centre_px"])) < 4.0
    assert truth["radius_px"] - 1.0 < r.drum_radius_px < truth["radius_px"] + 5.0


@pytest.mark.parametrize("angle", [40.0, -40.0])
def test_s_shape_measures_rise_with_the_s(tmp_path, angle):
    # a cascading surface (middle steeper than the ends) rising to the right or to the left
    s_shape, rms = [], []
    for k, s_amp in enumerate((0.0, 0.04, 0.08, 0.12)):
        p, _ = _frame(tmp_path, f"s{k}.png", angle_deg=angle, s_amp=s_amp, window="crop")
        r = drum.measure_drum_frame(p)
        s_shape.append(r.s_shape_deg)
        rms.append(r.line_rms_pct)
    assert abs(s_shape[0]) < 0.3 and rms[0] < 0.1  # a straight surface
    assert np.all(np.diff(s_shape) > 1.0) and np.all(np.diff(rms) > 0.2)


def test_straight_and_s_surface_same_central_slope_different_shape(tmp_path):
    # the S changes the ends, not the slope through the drum centre
    a = drum.measure_drum_frame(_frame(tmp_path, "a.png", angle_deg=41.0, s_amp=0.0)[0])
    b = drum.measure_drum_frame(_frame(tmp_path, "b.png", angle_deg=41.0, s_amp=0.1)[0])
    assert abs(a.angle_deg - b.angle_deg) < 0.5
    assert b.upper_deg < b.angle_deg - 2 and b.lower_deg < b.angle_deg - 2  # flatter ends


@pytest.mark.parametrize("chord_fraction", [0.4, 0.8])
def test_chord_fraction_option(tmp_path, chord_fraction):
    p, truth = _frame(tmp_path, "c.png", angle_deg=37.0, s_amp=0.08, chord_fraction=chord_fraction)
    r = drum.measure_drum_frame(p, options={"chord_fraction": chord_fraction})
    assert r.chord_fraction == chord_fraction
    assert abs(r.angle_deg - truth["angle_deg"]) <= 0.5


def test_same_answer_in_bmp_png_tiff_8_and_16_bit(tmp_path):
    img, truth = render.render_tester_frame(5, 43.0, s_amp=0.06, blur_px=4.0, jitter_px=4.0)
    files = [render.save_frame(tmp_path / "f.bmp", img, 8), render.save_frame(tmp_path / "f.png", img, 8),
             render.save_frame(tmp_path / "f16.png", img, 16), render.save_frame(tmp_path / "f.tif", img, 8),
             render.save_frame(tmp_path / "f16.tif", img, 16)]
    angles = np.array([drum.measure_drum_frame(f).angle_deg for f in files])
    assert np.all(np.abs(angles - truth["angle_deg"]) <= 0.5)
    assert np.ptp(angles[[0, 1, 3]]) < 1e-9  # the same 8-bit pixels in three containers
    assert np.ptp(angles) < 0.05  # 8 vs 16 bit: quantisation only


def test_twelve_bit_camera_in_sixteen_bit_container(tmp_path):
    from PIL import Image

    img, truth = render.render_tester_frame(6, 36.0, blur_px=3.0)
    p = tmp_path / "f12.tif"
    Image.fromarray(np.round(img * 4095).astype(np.uint16)).save(p)
    assert abs(drum.measure_drum_frame(p).angle_deg - truth["angle_deg"]) <= 0.5


@pytest.mark.parametrize("window", ["crop", "rim"])
@pytest.mark.parametrize("fill", [0.2, 0.6])
def test_bright_powder_on_dark_background(tmp_path, window, fill):
    p, truth = _frame(tmp_path, "inv.png", angle_deg=52.0, fill=fill, s_amp=0.1, blur_px=5.0,
                      powder_dark=False, window=window)
    r = drum.measure_drum_frame(p)
    assert abs(r.angle_deg - truth["angle_deg"]) <= 0.5
    # a cropped drum's edge against dark air barely shows: the image border is then the drum
    assert r.drum_reference == "rim" or (window == "crop" and r.drum_reference == "image border")


@pytest.mark.parametrize("surround,blur", [(0.8, 8.0), (0.6, 7.0)])
def test_faint_blurred_drum_edge_on_a_light_surround(tmp_path, surround, blur):
    # a drum smaller than the frame, no rim ring: its air side (0.92) meets a light surround,
    # a faint edge blurred over several pixels; the drum is still found (the image border's
    # circle would take in the surround)
    p, truth = _frame(tmp_path, "faint.png", angle_deg=28.0, fill=0.3, s_amp=0.1, blur_px=blur, noise=0.03,
                      size=(640, 700), surround=surround, window="plain")
    r = drum.measure_drum_frame(p)
    assert r.drum_reference == "rim"
    assert abs(r.drum_radius_px - truth["radius_px"]) < 0.03 * truth["radius_px"]
    assert abs(r.angle_deg - truth["angle_deg"]) <= 0.5


def test_drum_off_centre_and_past_the_border(tmp_path):
    p, truth = _frame(tmp_path, "off.png", angle_deg=50.0, fill=0.58, s_amp=0.11, blur_px=4.6, jitter_px=6.0,
                      size=(520, 700), offset_px=(-25.0, 20.0))
    r = drum.measure_drum_frame(p)
    assert abs(r.angle_deg - truth["angle_deg"]) <= 0.5
    assert abs(r.drum_radius_px - truth["radius_px"]) < 0.05 * truth["radius_px"]


@pytest.mark.parametrize("roll", [2.0, -2.5])
def test_roll_given_by_the_user(tmp_path, roll):
    # a camera rolled by `roll` shows a 40 deg surface at 40 + roll deg against the image axes
    p, _ = _frame(tmp_path, "roll.png", angle_deg=40.0 + roll, window="crop")
    plain = drum.measure_drum_frame(p)
    given = drum.measure_drum_frame(p, options={"roll_deg": roll})
    assert plain.level_reference == "image axes" and abs(plain.angle_deg - (40.0 + roll)) <= 0.5
    assert given.level_reference == "manifest roll" and given.roll_deg == roll
    assert abs(given.angle_deg - 40.0) <= 0.5


def test_drum_given_by_the_user(tmp_path):
    p, truth = _frame(tmp_path, "in.png", angle_deg=45.0, window="inside")
    r = drum.measure_drum_frame(p, options={"drum_centre_px": truth["centre_px"],
                                            "drum_radius_px": truth["radius_px"]})
    assert r.drum_reference == "manifest"
    assert abs(r.angle_deg - 45.0) <= 0.5


def test_plate_level_on_shipped_frames_and_the_roll_it_removes():
    frame = SHIPPED / "drum_middle_f04.jpg"
    truth = json.loads(Path(str(frame) + ".truth.json").read_text())
    plate = drum.measure_drum_frame(frame)
    axes = drum.measure_drum_frame(frame, options={"level": "image"})
    assert plate.level_reference == "plate" and axes.level_reference == "image axes"
    assert abs(plate.roll_deg - truth["roll_deg"]) < 0.1
    assert abs(plate.angle_deg - truth["angle_deg"]) <= 0.3
    # the roll rotates the surface: against the image axes it reads angle + roll
    assert abs(axes.angle_deg - (plate.angle_deg + truth["roll_deg"])) < 0.15


@pytest.mark.parametrize("roll", [18.0, -22.0])
def test_drum_photo_rolled_beyond_the_plate_search(tmp_path, roll):
    # a drum on its stand photographed with the camera rolled 18 or 22 deg: the plate search
    # (15 deg) found no plate and levelled the frame to the image axes, which read the 35 deg
    # surface 18 to 22 deg off; refused, naming the roll to give, which then measures it
    import re

    img, truth = _stand(roll)
    p = render.save_photo(tmp_path / "rolled.jpg", img, truth, quality=90)
    with pytest.raises(InputError) as e:
        drum.measure_drum_frame(p)
    assert (e.value.path, e.value.field) == (str(p), "image")
    given = re.search(r"if that edge is the plate's \(the camera rolled\), roll_deg: (-?[0-9.]+) in the manifest",
                      e.value.got)
    assert given and abs(float(given[1]) - roll) <= 0.2, e.value.got
    assert "level: image" in e.value.got
    r = drum.measure_drum_frame(p, options={"roll_deg": float(given[1])})
    assert r.level_reference == "manifest roll" and abs(r.angle_deg - 35.0) <= 0.3


@pytest.mark.parametrize("tilt", [20.0, -25.0])
def test_drum_photo_level_with_a_diagonal_shadow_below_the_drum(tmp_path, tilt):
    # a drum on its stand photographed with the camera level, a straight shadow edge across the
    # wall and table below the drum at 20 or -25 deg: the plate below the drum is found within
    # the plate search, so the shadow is no roll (it was refused as one, and the roll it named
    # read the 35 deg surface at 54.9 or 9.9 deg); measured on the plate
    img, truth = _stand(0.0)
    h, w = img.shape[:2]
    rr, cc = np.mgrid[0:h, 0:w]
    (cx, cy), r_ = truth["centre_px"], truth["radius_px"]  # the drum in the rendered photo
    edge = (cy + r_ + 40) + np.tan(np.radians(tilt)) * (cc - cx)
    shaded = img.astype(float)
    shaded[(rr > edge) & (np.hypot(rr - cy, cc - cx) > r_ + 25)] *= 0.6
    p = render.save_photo(tmp_path / "shadow.jpg", shaded.astype(np.uint8), truth, quality=90)
    r = drum.measure_drum_frame(p)
    assert r.level_reference == "plate" and abs(r.roll_deg) <= 0.2 and abs(r.angle_deg - 35.0) <= 0.5, r.angle_deg


def test_level_plate_required_but_absent(tmp_path):
    p, _ = _frame(tmp_path, "np.png", angle_deg=40.0)
    with pytest.raises(InputError, match="level"):
        drum.measure_drum_frame(p, options={"level": "plate"})


@pytest.mark.parametrize("entry,field", [
    ({"chord_fraction": 2}, "photos[0].chord_fraction"),
    ({"level": "horizon"}, "photos[0].level"),
    ({"roll_deg": "two"}, "photos[0].roll_deg"),
    ({"rim_margin": -0.1}, "photos[0].rim_margin"),
    ({"drum_centre_px": [10, 20]}, "photos[0].drum_radius_px"),
    ({"drum_centre_px": [10], "drum_radius_px": 50}, "photos[0].drum_centre_px"),
    ({"roll_deg": 1.0, "level": "plate"}, "photos[0].roll_deg"),
])
def test_bad_manifest_options_name_the_field(tmp_path, entry, field):
    p, _ = _frame(tmp_path, "f.png", angle_deg=40.0)
    m = tmp_path / "manifest.yaml"
    m.write_text(yaml.safe_dump({"photos": [{"file": p.name, "kind": "drum", **entry}]}))
    with pytest.raises(InputError) as e:
        read_manifest(m)
    assert e.value.field == field and str(m) in str(e.value)


def test_manifest_group_of_sixteen_bit_tester_frames(tmp_path):
    photos = []
    for k, dev in enumerate((-0.3, 0.1, 0.2)):
        img, _ = render.render_tester_frame(10 + k, 39.0 + dev, s_amp=0.05, blur_px=3.0)
        render.save_frame(tmp_path / f"f{k}.png", img, bits=16)
        photos.append({"file": f"f{k}.png", "kind": "drum", "group": "dynamic", "level": "image"})
    (tmp_path / "manifest.yaml").write_text(yaml.safe_dump({"photos": photos}))
    out = measure_manifest(tmp_path / "manifest.yaml", figdir=tmp_path / "figs")["dynamic"]
    assert out["n_frames"] == 3 and abs(out["angle_deg"] - 39.0) <= 0.5
    assert out["level_reference"] == "image axes" and out["drum_reference"] == "rim"
    assert out["s_shape_deg"] > 1.0
    assert (tmp_path / "figs" / "f0.png").is_file()


def test_cli_drum_options(tmp_path, capsys):
    from soilcal.cli import main

    p, _ = _frame(tmp_path, "f.png", angle_deg=42.0)
    assert main(["image", "drum", str(p), "--roll-deg", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["level_reference"] == "manifest roll" and abs(out["angle_deg"] - 40.0) <= 0.5
    assert main(["image", "drum", str(p), "--chord-fraction", "0"]) == 2
    assert "<command line>: --chord-fraction: expected" in capsys.readouterr().err  # the option as typed


def test_frame_without_powder(tmp_path):
    img, _ = render.render_tester_frame(1, 40.0, window="rim")
    img[:] = np.where(img > 0.5, img, 0.9)  # the powder removed, the rim too
    img[::7, ::7] = 0.1  # some texture so it is not blank
    p = render.save_frame(tmp_path / "empty.png", img)
    with pytest.raises(InputError):
        drum.measure_drum_frame(p)


def test_blank_frame(tmp_path):
    p = render.save_frame(tmp_path / "blank.png", np.full((200, 200), 0.5))
    with pytest.raises(InputError, match="blank"):
        drum.measure_drum_frame(p)


def _no_drum(path):
    """A wall above a darker table, no drum: the only boundary is level."""
    rng = np.random.default_rng(2)
    img = np.full((240, 320), 0.75)
    img[150:] = 0.3
    return render.save_frame(path, np.clip(img + 0.01 * rng.standard_normal(img.shape), 0, 1))


@pytest.mark.parametrize("case", ["no drum", "drum at rest", "no surface"])
def test_frame_without_a_turning_drum_is_refused(tmp_path, case):
    # a level boundary is no dynamic angle (a frame of something else, a drum not turning), nor
    # is a boundary that wanders over the frame: each gets the one drum-frame refusal
    if case == "no drum":
        p = _no_drum(tmp_path / "table.png")
    elif case == "drum at rest":
        p, _ = _frame(tmp_path, "rest.png", angle_deg=0.0, window="rim", size=(240, 320))
    else:
        rng = np.random.default_rng(5)
        noise = 0.5 + 0.225 * render._noise(rng, (180, 240), 10.0)
        p = render.save_frame(tmp_path / "mottled.png", np.clip(noise, 0, 1))
    with pytest.raises(InputError) as e:
        drum.measure_drum_frame(p)
    assert e.value.path == str(p) and e.value.field == "image" and e.value.expected == drum.DRUM_EXPECTED
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("angle", [5.0, 8.0])
def test_a_drum_at_a_low_dynamic_angle_is_measured(tmp_path, angle):
    # a free-flowing powder at a low speed stands at a few degrees: drawn at 5 and 8 deg, the
    # frame is a drum frame, measured within half a degree, not refused as a level edge
    p, truth = _frame(tmp_path, "low.png", angle_deg=angle, window="rim", size=(240, 320))
    r = drum.measure_drum_frame(p)
    assert abs(r.angle_deg - angle) < 0.5, r.angle_deg


def _spy_decoder(monkeypatch):
    """The sizes PIL decodes images at, as a list filled while the test runs."""
    from PIL import ImageFile

    decoded, load = [], ImageFile.ImageFile.load

    def spy(im):
        out = load(im)
        decoded.append(im.size)
        return out

    monkeypatch.setattr(ImageFile.ImageFile, "load", spy)
    return decoded


def test_large_drum_photo_is_decoded_reduced_to_the_working_size(tmp_path, monkeypatch):
    # a phone's 12 megapixel drum photo stands in here as four times the working size: the JPEG
    # is decoded at half size by its decoder, measured there at the angle drawn, and its drum
    # reported in the photo's own pixels where it was drawn
    from PIL import Image

    monkeypatch.setattr(drum, "DRUM_WORK_PIXELS", 240 * 320)
    decoded = _spy_decoder(monkeypatch)
    img, truth = render.render_tester_frame(seed=3, angle_deg=40.0, window="rim", size=(480, 640))
    p = tmp_path / "phone.jpg"
    Image.fromarray(np.round(img * 255).astype(np.uint8)).save(p, quality=92)
    r = drum.measure_drum_frame(p, keep_stages=True)
    assert decoded and max(w * h for w, h in decoded) == 240 * 320
    assert r.stages.gray.shape == (240, 320) and r.work_scale == pytest.approx(0.5)
    assert abs(r.angle_deg - truth["angle_deg"]) <= 0.5
    assert r.drum_reference == "rim"
    # the rim, a ring from radius R outwards 4 photo px (2 measured px) wide, is found in the
    # photo's pixels where it was drawn, as closely as the rim search finds it in a frame of the
    # measured size (some 3 measured px, the bed lying against the rim)
    assert np.hypot(*(np.array(r.drum_centre_px) - truth["centre_px"])) < 0.06 * truth["radius_px"]
    assert abs(r.drum_radius_px - truth["radius_px"]) < 0.03 * truth["radius_px"]


def test_drum_given_in_the_photo_pixels_of_a_reduced_photo(tmp_path, monkeypatch):
    # drum_centre_px and drum_radius_px are the photo's pixels, as the user reads them off the
    # photo; the reduced image is measured with them scaled to it
    monkeypatch.setattr(drum, "DRUM_WORK_PIXELS", 240 * 320)
    p, truth = _frame(tmp_path, "given.png", angle_deg=36.0, window="inside", size=(480, 640))
    opts = {"drum_centre_px": [319.5, 239.5], "drum_radius_px": 0.75 * float(np.hypot(480, 640)) / 2.0}
    r = drum.measure_drum_frame(p, options=opts)
    assert r.drum_reference == "manifest" and r.work_scale == pytest.approx(0.5)
    assert r.drum_centre_px == pytest.approx(opts["drum_centre_px"]) and r.drum_radius_px == pytest.approx(
        opts["drum_radius_px"])
    assert abs(r.angle_deg - truth["angle_deg"]) <= 0.5


def test_drum_circle_peaks_are_skimages(tmp_path):
    # the circle search's peaks are those of skimage's hough_circle_peaks, found without one
    # region object per candidate (a mottled frame's noisy Hough spaces hold thousands)
    from skimage import transform

    rng = np.random.default_rng(5)
    noise = np.clip(0.5 + 0.225 * render._noise(rng, (120, 160), 10.0), 0, 1)
    radii = np.arange(30, 75)
    hs = transform.hough_circle(drum._edges(noise), radii)
    for dist in (3, 2, 1):  # at 1 skimage skips the suppression between radii
        want = transform.hough_circle_peaks(hs, radii, total_num_peaks=8, min_xdistance=dist, min_ydistance=dist)
        got = drum._circle_peaks(hs, radii, dist=dist, total=8)
        assert len(want[0]) == 8
        for a, b in zip(want, got):
            np.testing.assert_array_equal(a, b)
    # spaces full of equal peaks (counts over one perimeter's pixels): the search stops short of
    # the weaker radii only where no two of the peaks down to the weakest kept are equal (a
    # reflection-band frame's kept peaks differed so, two equal peaks taken in another order)
    for seed in range(3):
        tied = np.round(np.random.default_rng(seed).gamma(2.0, 1.0, (30, 60, 80)) * 3) / 40.0
        radii = np.arange(20, 50)
        want = transform.hough_circle_peaks(tied, radii, total_num_peaks=8, min_xdistance=3, min_ydistance=3)
        for a, b in zip(want, drum._circle_peaks(tied, radii, dist=3, total=8)):
            np.testing.assert_array_equal(a, b)


def test_a_circle_fit_the_library_could_not_finish_is_passed_over(monkeypatch):
    # skimage's ransac returns a failed estimate (falsy, no centre) when the final fit through
    # the inliers fails; the rim search passes over that candidate and the window check finds no
    # ellipse, instead of reading a centre the estimate does not have
    from skimage import measure

    failed = measure.CircleModel.from_estimate(np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]))
    assert not failed and not hasattr(failed, "center")
    monkeypatch.setattr(drum.measure, "ransac", lambda pts, *a, **k: (failed, np.ones(len(pts), bool)))
    yy, xx = np.mgrid[:240, :320]
    gray = np.where(np.hypot(xx - 160, yy - 120) < 90, 0.8, 0.2)
    cx, cy, r, ref = drum.find_drum(gray)
    assert ref == "image border" and (cx, cy, r) == (159.5, 119.5, 120.0)
    assert drum.window_ellipse(drum._edges(gray), 160.0, 120.0, 90.0) is None


@pytest.mark.parametrize("roll", [0.0, 10.0, -7.0])
def test_rendered_drum_truth_gives_the_drum_in_the_photo(roll):
    # the renderer's truth places the drum in the photo (turned with the camera's roll and
    # cropped): the rim found in the photo is there, within half a pixel
    from soilcal.imaging.measure import _gray

    img, truth = _stand(roll)
    cx, cy, r_, how = drum.find_drum(_gray(img / 255.0))
    assert how == "rim"
    assert np.hypot(cx - truth["centre_px"][0], cy - truth["centre_px"][1]) <= 0.5 and abs(r_ - truth["radius_px"]) <= 0.5


def _band(img, truth, x_over_r, height, width=0.04):
    """A vertical reflection band across the frame, ``x_over_r`` drum radii right of the centre."""
    cc = np.arange(img.shape[1])[None, :]
    x0 = truth["centre_px"][0] + x_over_r * truth["radius_px"]
    return np.clip(img + height * np.exp(-((cc - x0) / (width * truth["radius_px"])) ** 2), 0.0, 1.0)


@pytest.mark.parametrize("angle", [35.0, -35.0, 50.0])
def test_bed_cut_by_a_reflection_band_is_measured_whole(tmp_path, angle):
    # a bright band on the window, over the rising half of an S-shaped surface, lifts the dark
    # powder under it above the powder/air threshold and cuts the bed in two; both pieces lie
    # on the drum wall and are the bed (only the larger was measured: its surface lies to one
    # side of the drum centre and the central slope read 1.7 to 5.2 deg low)
    img, truth = render.render_tester_frame(7, angle, fill=0.3, s_amp=0.1, size=(716, 716), window="rim", n_avg=8)
    img = _band(img, truth, 0.35 * np.sign(angle), 0.4)
    r = drum.measure_drum_frame(render.save_frame(tmp_path / "band.png", img))
    assert abs(r.angle_deg - abs(truth["angle_deg"])) < 0.5


def test_dark_hub_in_the_air_is_not_the_bed(tmp_path):
    # the drum's dark hub floats in the air above the bed: a powder-grey region off the wall.
    # A guard: measured right also when only the largest powder region was the bed
    img, truth = render.render_tester_frame(5, 38.0, fill=0.25, size=(500, 500), window="crop", n_avg=8)
    rr, cc = np.mgrid[0:500, 0:500]
    (cx, cy), R = truth["centre_px"], truth["radius_px"]
    img[np.hypot(cc - cx, rr - (cy - 0.3 * R)) < 0.2 * R] = 0.22
    r = drum.measure_drum_frame(render.save_frame(tmp_path / "hub.png", img))
    assert abs(r.angle_deg - abs(truth["angle_deg"])) < 0.5


@pytest.mark.parametrize("seed,angle,phi,span,depth,dark", [(501, 35.0, 35, 20, 0.3, True),
                                                          (509, 35.0, 25, 20, 0.3, True),
                                                          (520, 45.0, 25, 20, 0.3, False),
                                                          (531, -40.0, 35, 25, 0.2, True)])
def test_powder_held_in_a_lifter_above_the_surface_is_not_the_bed(tmp_path, seed, angle, phi, span, depth, dark):
    # powder carried up by a lifter: a pile of the powder's grey against the wall on the rising
    # side, polar angles phi..phi+span, from (1 - depth) R out to the wall, at least 10 px above the
    # surface, 2.2 to 2.9 % of the drum's area.  Taken into the bed, its top was read as the surface:
    # 35 deg refused as a boundary straying 13 % of R, or its upper half read -47.6 deg; 45 deg
    # upper half 53.4 (41.8 when only the largest region was the bed, the pile's blur touching it)
    img, truth = render.render_tester_frame(seed, angle, fill=0.3, size=(480, 480), window="rim", powder_dark=dark,
                                            n_avg=8)
    (cx, cy), R = truth["centre_px"], truth["radius_px"]
    rr, cc = np.mgrid[0:480, 0:480].astype(float)
    x, z = cc - cx, cy - rr
    th = np.radians(angle)
    above = -x * np.sin(th) + z * np.cos(th) + render.segment_fill(R, 0.3)   # px above the flat surface
    ph = np.degrees(np.arctan2(z, x))
    ph0 = phi if angle > 0 else 180 - phi - span
    pile = (np.hypot(x, z) > (1 - depth) * R) & (np.hypot(x, z) < R + 1) & (ph > ph0) & (ph < ph0 + span) & (above > 10)
    air, powder = (0.92, 0.22) if dark else (0.12, 0.78)
    img = np.clip(img + (powder - air) * ndi.gaussian_filter(pile.astype(float), 1.5), 0.0, 1.0)
    r = drum.measure_drum_frame(render.save_frame(tmp_path / "lifter.png", img))
    assert abs(r.angle_deg - abs(truth["angle_deg"])) < 0.5
    assert abs(r.upper_deg - abs(truth["angle_deg"])) < 1.0 and abs(r.s_shape_deg) < 0.5


@pytest.mark.parametrize("angle", [38.0, -38.0])
@pytest.mark.parametrize("streak,height", [("glare on a dark drum", -0.45), ("glare on a dark drum", 0.3),
                                           ("dark rod on a light drum", 0.3)])
def test_streak_across_the_air_joined_to_the_bed_is_no_surface(tmp_path, streak, height, angle):
    # a thin horizontal streak of the powder's grey class across the air, ``height`` drum radii
    # above the centre, crossing the surface: a glare line on a drum with bright powder, a dark
    # rod in front of one with dark powder.  Joined to the bed its top was taken for the surface
    # in the columns it spans: with status ok the glare read 38 deg as 33.4 and 33.6 (0.45 R
    # below the centre); 0.3 R above the centre the glare and the rod were refused as a level edge
    dark = streak.startswith("dark")
    img, truth = render.render_tester_frame(9, angle, fill=0.4, size=(480, 480), window="rim", powder_dark=dark,
                                            n_avg=8)
    (cx, cy), R = truth["centre_px"], truth["radius_px"]
    rows = np.arange(480)[:, None] - (cy - height * R)
    if dark:
        img = np.where(np.abs(rows) < 0.03 * R, 0.05, img)
    else:
        img = np.clip(img + 0.45 * np.exp(-(rows / (0.03 * R)) ** 2), 0.0, 1.0)
    r = drum.measure_drum_frame(render.save_frame(tmp_path / "streak.png", img))
    assert abs(r.angle_deg - abs(truth["angle_deg"])) < 0.5


@pytest.mark.parametrize("angle", [30.0, 35.0])
def test_bed_cut_by_two_glare_lines_is_measured_whole(tmp_path, angle):
    # two bright glare lines along the window, 0.05 and 0.3 drum radii below the centre, cut the
    # dark bed into three pieces one above the other.  The top piece (the surface's upper end)
    # lies on the middle one, not on the largest: it was left out and the upper part of the
    # surface read from the middle piece's top, the glare line (status ok: 30 deg read 27.86,
    # upper third 20.6; 35 deg read 33.2, upper third 26.5)
    img, truth = render.render_tester_frame(4, angle, fill=0.35, size=(440, 440), window="rim", n_avg=8)
    (cx, cy), R = truth["centre_px"], truth["radius_px"]
    rows = np.arange(440)[:, None].astype(float)
    for below in (0.05, 0.3):
        img = img + 0.45 * np.exp(-((rows - (cy + below * R)) / (0.015 * R)) ** 2)
    r = drum.measure_drum_frame(render.save_frame(tmp_path / "glare2.png", np.clip(img, 0.0, 1.0)))
    assert abs(r.angle_deg - abs(truth["angle_deg"])) < 0.5
    assert abs(r.upper_deg - abs(truth["angle_deg"])) < 1.5


@pytest.mark.parametrize("axis,ratio,size", [("x", 0.9, 480), ("y", 0.93, 480), ("x", 0.75, 480), ("y", 0.75, 480)])
def test_window_seen_off_the_drum_axis_is_refused(tmp_path, axis, ratio, size):
    # a phone held off the drum's axis sees the circular window as an ellipse: the frame below is
    # a square-on frame squashed by ``ratio`` across ``axis`` about the drum centre (a camera
    # turned about the vertical, or tilted about the horizontal).  A 35 deg surface read 38.0 deg
    # (x, 0.9) and 33.2 deg (y, 0.93) with status ok; now refused naming the axes ratio.  Far off
    # the axis (0.75) a smaller circle inside the ellipse was taken for the rim and the ellipse,
    # its centre off that circle's, dropped: 35 deg read 42.67 (x) and 27.70 (y), status ok
    img, truth = render.render_tester_frame(6, 35.0, fill=0.35, size=(size, size), window="rim", n_avg=8)
    (cx, cy), R = truth["centre_px"], truth["radius_px"]
    scale = np.array([1.0, 1.0 / ratio]) if axis == "x" else np.array([1.0 / ratio, 1.0])  # (row, column)
    centre = np.array([cy, cx])
    squashed = ndi.affine_transform(img, scale, offset=centre - scale * centre, order=1, mode="nearest")
    with pytest.raises(InputError, match="the rim an ellipse of axes ratio") as err:
        drum.measure_drum_frame(render.save_frame(tmp_path / "oblique.png", squashed))
    found = float(str(err.value).split("axes ratio ")[2].split(",")[0])
    assert abs(found - ratio) < 0.04  # the rim ring's inner and outer edges (0.75 found 0.779)


def _disc(img, x, y, r, grey):
    """``img[hypot(column - x, row - y) < r] = grey``, the distances taken in the disc's bounding
    box only (every pixel of the disc lies in it)."""
    r0, r1 = max(int(np.floor(y - r)), 0), min(int(np.ceil(y + r)) + 1, img.shape[0])
    c0, c1 = max(int(np.floor(x - r)), 0), min(int(np.ceil(x + r)) + 1, img.shape[1])
    if r0 < r1 and c0 < c1:
        rr, cc = np.mgrid[r0:r1, c0:c1]
        img[r0:r1, c0:c1][np.hypot(cc - x, rr - y) < r] = grey


def _particles_in_flight(img, truth, n=200, seed=0):
    """``n`` discs of the powder's grey (0.012 to 0.03 drum radii) thrown from the bed: their
    columns over the rising 60 % of the drum, their heights above the surface in that column
    exponential (mean 0.15 R, at most 0.45 R), inside 0.93 R, as a cascading drum throws grains
    into the air; the bed and its surface are untouched."""
    rng = np.random.default_rng(seed)
    (cx, cy), R = truth["centre_px"], truth["radius_px"]
    rr, cc = np.mgrid[0:img.shape[0], 0:img.shape[1]]
    inside = np.hypot(cc - cx, rr - cy) < 0.9 * R
    powder = inside & (img < 0.5 * (img[inside].min() + img[inside].max()))  # dark powder
    grey = float(np.median(img[powder]))
    side = 1.0 if truth["angle_deg"] > 0 else -1.0
    k = 0
    while k < n:
        x = cx + side * rng.uniform(-0.3, 0.9) * R
        col = powder[:, int(round(x))]
        if not col.any():
            continue
        y = np.flatnonzero(col)[0] - rng.exponential(0.15 * R)
        r = rng.uniform(0.012, 0.03) * R
        if np.flatnonzero(col)[0] - y > 0.45 * R or np.hypot(x - cx, y - cy) > 0.93 * R:
            continue
        _disc(img, x, y, r, grey)
        k += 1
    return img


@pytest.mark.parametrize("angle", [35.0, -42.0])
def test_particles_in_flight_flag_the_frame_low(tmp_path, angle):
    # 200 powder-grey particles in flight above the upper part of the surface crowd into clusters
    # that the first step from air to powder takes for the surface in their columns: these 35 and
    # 42 deg surfaces read 41.63 and 47.62 deg, status ok.  Their jagged trace (a few % of the radius from
    # a smooth curve, a straight or S-shaped surface stays within 0.05 %) flags the frame low,
    # and a group sets it aside
    img, truth = render.render_tester_frame(8, angle, fill=0.35, size=(500, 500), window="rim", n_avg=8)
    clean = render.save_frame(tmp_path / "clean.png", img)
    flying = render.save_frame(tmp_path / "flying.png", _particles_in_flight(img.copy(), truth))
    summary, (ok, low) = drum.measure_drum([clean, flying])
    assert ok.confidence == "ok" and low.confidence == "low" and "particles in flight" in low.low_reason
    assert abs(summary["angle_deg"] - abs(truth["angle_deg"])) < 0.5
    assert summary["n_frames"] == 1 and [a["path"] for a in summary["set_aside"]] == [str(flying)]
    with pytest.raises(InputError, match="flying.png: low, a jagged free surface") as err:
        drum.drum_summary([low])
    assert err.value.field == "confidence"


def test_drum_circle_inside_the_bed_is_refused_saying_so(tmp_path):
    # a circle that lies wholly inside the bed (a rim smeared by a 60 px motion blur was found so;
    # here given by hand, a third of the radius, half a radius below the centre) has no air in it:
    # it was refused as "a free surface across 0 pixel columns" with NumPy's mean-of-empty-slice
    # warnings; now one message saying the circle is not the drum's window and what to give
    import warnings

    img, truth = render.render_tester_frame(4, 35.0, fill=0.45, size=(400, 400), window="rim", n_avg=8)
    (cx, cy), R = truth["centre_px"], truth["radius_px"]
    p = render.save_frame(tmp_path / "f.png", img)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InputError, match="no air above it: that circle is not the drum's window") as err:
            drum.measure_drum_frame(p, options={"drum_centre_px": [cx, cy + 0.5 * R], "drum_radius_px": R / 3})
    assert str(p) in str(err.value) and "drum_centre_px and drum_radius_px" in str(err.value)


def test_steep_smooth_surface_is_not_flagged_jagged(tmp_path, angle=74.0):
    # the roughness is taken across the surface (from its fitted line) over 0.1 radii along it:
    # taken up the columns it grew as 1 / cos of the angle, and these rendered drum frames, read
    # within 0.07 deg, were 0.52 and 0.83 % (74 deg flagged low); across the surface 0.13 %
    img, truth = render.render_drum(1, angle)
    r = drum.measure_drum_frame(render.save_frame(tmp_path / "steep.png", img))
    assert abs(r.angle_deg - angle) < 0.2
    assert r.confidence == "ok" and r.roughness_pct < 0.3


def test_reading_photos_does_not_import_the_drum_filter():
    """The roughness filter (scipy.signal, about 0.8 CPU-s to import) is imported where a drum
    frame's roughness is taken: a photo measurement of heaps or furrows, which imports this
    module for the manifest's checks, does not pay for it."""
    import subprocess
    import sys

    code = ("import sys, soilcal.imaging.manifest, soilcal.imaging.drum, soilcal.imaging.measure; "
            "print(sorted(m for m in sys.modules if m == 'scipy.signal' or m.startswith('scipy.signal.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def _lumps(img, truth, n=12, r_frac=0.03):
    """``n`` powder-grey discs (radius ``r_frac`` drum radii) centred on the surface, evenly
    spaced over the columns the bed spans: clods lying on the surface all along it."""
    (cx, cy), R = truth["centre_px"], truth["radius_px"]
    rr, cc = np.mgrid[0:img.shape[0], 0:img.shape[1]]
    inside = np.hypot(cc - cx, rr - cy) < 0.9 * R
    powder = inside & (img < 0.5 * (img[inside].min() + img[inside].max()))  # dark powder
    grey = float(np.median(img[powder]))
    cols = np.flatnonzero(powder.any(axis=0))
    for x in np.linspace(cols[0], cols[-1], n + 2)[1:-1]:
        y = np.flatnonzero(powder[:, int(round(x))])[0]
        _disc(img, x, y, r_frac * R, grey)
    return img


@pytest.mark.parametrize("angle", [-70.0, 40.0, -45.0])
def test_clods_spread_along_the_surface_do_not_flag_the_frame(tmp_path, angle):
    # twelve clods 6 % of the radius across, evenly along the surface, leave the line where it
    # was (read within 0.2 deg) but were flagged low (roughness 0.65 to 2.7 %, taken up the
    # columns); across the surface 0.35 to 0.59 %
    img, truth = render.render_tester_frame(8, angle, fill=0.4, size=(500, 500), window="rim", n_avg=8)
    r = drum.measure_drum_frame(render.save_frame(tmp_path / "clods.png", _lumps(img, truth)))
    assert abs(r.angle_deg - abs(truth["angle_deg"])) < 0.5
    assert r.confidence == "ok", r.low_reason


def _thin_bed(R=80.0, fill=0.08, angle=35.0, w=200, h=190):
    """A sharp drawn drum (4x supersampled): air 0.9 inside, powder 0.25 below a straight surface
    cutting a segment of ``fill`` of the circle, the body 0.5 outside."""
    from scipy.optimize import brentq

    d = brentq(lambda d: (R * R * np.arccos(d / R) - d * np.sqrt(R * R - d * d)) / (np.pi * R * R) - fill,
               -R + 1e-9, R - 1e-9)  # the chord's distance below the centre for the segment's area
    ss = 4
    yy, xx = np.mgrid[0:h * ss, 0:w * ss]
    x = (xx + 0.5) / ss - 0.5 - (w - 1) / 2
    z = (h - 1) / 2 - ((yy + 0.5) / ss - 0.5)
    th = np.radians(angle)
    img = np.where(np.hypot(x, z) < R, np.where(-x * np.sin(th) + z * np.cos(th) < -d, 0.25, 0.9), 0.5)
    return img.reshape(h, ss, w, ss).mean(axis=(1, 3))


def test_thin_bed_in_a_small_drum_is_measured(tmp_path):
    # an 80 px drum filled 8 %: its bed (16 px deep at most, less inside the rim margin) has no
    # powder 8 px from its edge, and the frame was refused as "not the drum's window" though the
    # rim was found; the powder's grey is now taken from as deep in the bed as it goes
    r = drum.measure_drum_frame(render.save_frame(tmp_path / "thin.png", _thin_bed()))
    assert abs(r.angle_deg - 35.0) < 0.2 and r.drum_reference == "rim"


def test_a_refused_group_of_flagged_frames_still_gets_its_figures(tmp_path):
    # a drum group whose frames are all flagged low was refused with no figures written, though
    # a heap photo group's refusal writes them: now both the CLI and the manifest write them
    from soilcal.cli import main

    img, truth = render.render_tester_frame(8, 35.0, fill=0.35, size=(500, 500), window="rim", n_avg=8)
    p = render.save_frame(tmp_path / "flying.png", _particles_in_flight(img.copy(), truth))
    figs = tmp_path / "figs"
    figs.mkdir()
    assert main(["image", "drum", str(p), "--figures", str(figs)]) != 0
    assert (figs / "flying.png").is_file()
    (tmp_path / "m.yaml").write_text(yaml.safe_dump({"photos": [
        {"file": "flying.png", "kind": "drum", "group": "drum", "level": "image"}]}))
    mfigs = tmp_path / "mfigs"
    with pytest.raises(InputError) as e:
        measure_manifest(tmp_path / "m.yaml", figdir=mfigs)
    assert "group drum" in e.value.field and str(mfigs) in str(e.value)
    assert (mfigs / "flying.png").is_file()


def _smeared(angle=35.0, streak=30, R=200.0, w=520, h=480):
    """A drawn drum (:func:`_thin_bed`, a third full) smeared by the camera moving along the
    surface: a line kernel 2 ``streak`` + 1 px long in the surface's direction, then a 1 px
    Gaussian and 1 % noise (seeded)."""
    img = _thin_bed(R=R, fill=0.35, angle=angle, w=w, h=h)
    k = np.zeros((2 * streak + 1, 2 * streak + 1))
    ta = np.radians(angle)
    for s in np.linspace(-streak, streak, 4 * streak + 1):
        k[int(round(streak - s * np.sin(ta))), int(round(streak + s * np.cos(ta)))] += 1
    img = ndi.gaussian_filter(ndi.convolve(img, k / k.sum(), mode="nearest"), 1.0)
    return np.clip(img + 0.01 * np.random.default_rng(7).standard_normal(img.shape), 0, 1)


def test_drum_circle_found_wrong_in_a_smeared_frame_is_flagged(tmp_path):
    # the smeared rim of a 200 px drum centred at (259.5, 239.5) was found as a 273 px circle at
    # (301, 299): the surface, straight, read 34.99 deg, status ok, though the chord (and for an
    # S-shaped surface the angle) is not the drum's; its surface ends 0.23 radii short of that
    # circle (radially, where the step from air to powder stops), where a bed lies against the
    # drum wall
    r = drum.measure_drum_frame(render.save_frame(tmp_path / "smeared.png", _smeared()))
    assert r.confidence == "low" and "short of the drum circle" in r.low_reason
    assert "drum_centre_px and drum_radius_px" in r.low_reason


@pytest.mark.parametrize("angle", [30.0, -45.0])
def test_drum_given_wrong_is_flagged_and_given_right_is_not(tmp_path, angle):
    # a drum given 1.3 times too large and 0.25 radii off the centre read 29.12 and 41.59 deg for
    # these 30 and 45 deg surfaces, status ok; the surface ends 0.34 and 0.38 radii short of it.
    # The reason says the drum given does not match the frame (it advised giving the drum, given)
    R, w, h = 80.0, 184, 184
    p = render.save_frame(tmp_path / "f.png", _thin_bed(R=R, fill=0.35, angle=angle, w=w, h=h))
    c = [(w - 1) / 2, (h - 1) / 2]
    right = drum.measure_drum_frame(p, options={"drum_centre_px": c, "drum_radius_px": R})
    assert right.confidence == "ok" and abs(right.angle_deg - abs(angle)) < 0.2
    wrong = drum.measure_drum_frame(p, options={"drum_centre_px": [c[0] + 0.25 * R * np.sign(angle), c[1] + 0.1 * R],
                                                "drum_radius_px": 1.3 * R})
    assert wrong.confidence == "low" and "short of the drum circle" in wrong.low_reason
    assert "given does not match the frame's drum" in wrong.low_reason
    assert "give drum_centre_px" not in wrong.low_reason


@pytest.mark.parametrize("angle,x_over_r,width", [(35.0, 0.7, 0.08), (-35.0, -0.62, 0.06)])
def test_trace_stopped_by_a_glare_band_near_the_wall_is_not_flagged(tmp_path, angle, x_over_r, width):
    # a vertical glare band across the rising end of the surface, 0.62 to 0.7 radii from the
    # centre, stops the trace there while the bed goes on to the wall under it: the rim was found
    # right and the angle read within 0.15 deg, but the frame was flagged low, "ends 0.28 (0.35)
    # drum radii short of the drum circle ... give drum_centre_px", so a group of frames under the
    # same lamp was refused.  The surface's end is where the step from air down to powder along
    # the end's line stops, not where the trace stops
    img, truth = render.render_tester_frame(7, angle, fill=0.3, s_amp=0.1, size=(500, 500), window="rim", n_avg=8)
    r = drum.measure_drum_frame(render.save_frame(tmp_path / "band.png", _band(img, truth, x_over_r, 0.4, width)))
    assert r.drum_reference == "rim" and abs(r.angle_deg - abs(truth["angle_deg"])) < 0.5
    assert r.confidence == "ok", r.low_reason


def test_a_flagged_frame_accepted_by_the_user_is_averaged_and_said_so(tmp_path, capsys):
    # a frame flagged low could not be used even when the user had checked it: its group was
    # refused; accept_low: true (--accept-low) averages it, its result says accepted_by_user and
    # the group lists it in accepted_low, not in set_aside
    from soilcal.cli import main

    R, w, h = 80.0, 184, 184
    p = render.save_frame(tmp_path / "f.png", _thin_bed(R=R, fill=0.35, angle=40.0, w=w, h=h))
    given = {"drum_centre_px": [(w - 1) / 2 + 20.0, (h - 1) / 2 + 8.0], "drum_radius_px": 1.3 * R}
    with pytest.raises(InputError, match="accept_low"):
        drum.measure_drum([p], options=given)
    summary, (r,) = drum.measure_drum([p], options=given | {"accept_low": True})
    assert r.confidence == "low" and r.accepted_by_user and summary["n_frames"] == 1
    assert summary["set_aside"] == [] and summary["accepted_low"] == [{"path": str(p), "reason": r.low_reason}]
    assert summary["frames"][0]["accepted_by_user"] is True
    # a frame measured ok is not marked accepted
    assert not drum.measure_drum_frame(p, options={"accept_low": True}).accepted_by_user
    with pytest.raises(InputError) as err:
        drum.frame_options({"accept_low": "yes"}, "m.yaml", prefix="photos[0].")
    assert err.value.field == "photos[0].accept_low" and "true or false" in str(err.value)
    argv = ["image", "drum", str(p), "--drum-centre-px", *map(str, given["drum_centre_px"]),
            "--drum-radius-px", str(given["drum_radius_px"])]
    assert main(argv + ["--accept-low"]) == 0
    out = capsys.readouterr()
    assert json.loads(out.out)["accepted_low"][0]["path"] == str(p) and "accepted by the user" in out.err


def test_the_figure_of_a_frame_flagged_low_says_so(tmp_path, monkeypatch):
    # a frame flagged low, set aside or accepted by the user, had a figure titled by its file name
    # only, as an "ok" one's: the user checking its figure did not see the flag
    from soilcal.imaging import figures

    titles = []
    save = figures._save
    monkeypatch.setattr(figures, "_save", lambda fig, stem: (titles.append(fig.get_suptitle()), save(fig, stem))[1])
    R, w, h = 80.0, 184, 184
    p = render.save_frame(tmp_path / "f.png", _thin_bed(R=R, fill=0.35, angle=40.0, w=w, h=h))
    wrong = {"drum_centre_px": [(w - 1) / 2 + 20.0, (h - 1) / 2 + 8.0], "drum_radius_px": 1.3 * R}
    ok = drum.measure_drum_frame(p, keep_stages=True)
    low = drum.measure_drum_frame(p, keep_stages=True, options=wrong)
    accepted = drum.measure_drum_frame(p, keep_stages=True, options=wrong | {"accept_low": True})
    for name, r in (("ok", ok), ("low", low), ("accepted", accepted)):
        figures.angle_figure(r, tmp_path / "figs" / name)
    assert titles[0] == "f.png"
    assert titles[1].startswith("f.png\nconfidence low: the free surface ends") and "accepted" not in titles[1]
    assert titles[2].startswith("f.png\nconfidence low, accepted by the user (accept_low): the free surface ends")
    assert "short of the drum circle" in " ".join(titles[2].split())
    assert (tmp_path / "figs" / "accepted.png").is_file()


def _plain_drum(angle_deg, size=600, radius=230, seed=0):
    """A drum drawn plainly: dark rim, light air, brown powder below a straight free surface
    through the centre at ``angle_deg`` (rising to the right), pixel noise of SD 8."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:size, 0:size].astype(float)
    c = size / 2
    r = np.hypot(x - c, y - c)
    img = np.empty((size, size, 3))
    img[:] = (60, 60, 65)
    img[r < radius + 12] = (30, 30, 30)
    inside = r < radius
    img[inside] = (225, 225, 230)
    img[inside & (y > c - (x - c) * np.tan(np.radians(angle_deg)))] = (120, 90, 60)
    return np.clip(img + rng.normal(0, 8, img.shape), 0, 255).astype(np.uint8)


def test_a_surface_steeper_than_the_range_is_refused_as_too_steep(tmp_path):
    # 85 deg lies above the 80 deg a turning drum's powder surface reaches: the refusal says
    # it is too steep, not that it is a level edge; the same drawing at 40 deg measures 40
    from skimage import io

    io.imsave(tmp_path / "d40.png", _plain_drum(40.0), check_contrast=False)
    assert abs(drum.measure_drum_frame(tmp_path / "d40.png").angle_deg - 40.0) <= 0.5
    p = tmp_path / "steep.png"
    io.imsave(p, _plain_drum(85.0), check_contrast=False)
    with pytest.raises(InputError) as exc:
        drum.measure_drum_frame(p)
    assert "steeper than 80 deg" in str(exc.value) and "level edge" not in str(exc.value), str(exc.value)
