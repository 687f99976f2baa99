"""A group of heap photos averages only the photos measured with confidence "ok": a photo
flagged "low" (here a scale card on the plate that makes the plate line ambiguous) is listed
with its reason in the group's ``set_aside`` and left out of angle_deg, left_deg, right_deg
and spread_deg; a group with no photo "ok" is refused.  Drawn heaps of known flanks: 32 deg
left, 35 deg right (test_user_photos.heap_photo)."""

from __future__ import annotations

import json

import pytest
import yaml

from soilcal.errors import InputError
from soilcal.imaging import measure
from soilcal.imaging.manifest import measure_manifest

from test_plate_ambiguous import _card
from test_user_photos import _u8, heap_photo


def _photos(tmp_path, **imgs):
    for name, img in imgs.items():
        _u8(img).save(tmp_path / name)
    return [tmp_path / n for n in imgs]


def _group(tmp_path, names):
    m = tmp_path / "manifest.yaml"
    m.write_text(yaml.safe_dump({"photos": [{"file": n, "kind": "pile", "group": "heap"} for n in names]}))
    return m


def test_a_flagged_photo_is_set_aside_and_the_group_is_the_ok_photo(tmp_path):
    # the card photo alone measures 35.6 / 31.5 deg, flagged low; averaged in, the group's
    # left flank was 33.8 deg and its right 33.3 (drawn: 32 and 35)
    _photos(tmp_path, **{"plain.png": heap_photo(), "card.png": _card("left", 60, 30, "checker")})
    out = measure_manifest(_group(tmp_path, ["plain.png", "card.png"]))["heap"]
    assert abs(out["left_deg"] - 32.0) <= 0.5 and abs(out["right_deg"] - 35.0) <= 0.5, out
    assert out["n_photos"] == 1 and len(out["photos"]) == 2
    aside = out["set_aside"]
    assert [a["path"] for a in aside] == [str(tmp_path / "card.png")]
    assert "plate_line_px" in aside[0]["reason"] and "--plate-line-px" in aside[0]["reason"]
    ok = [p for p in out["photos"] if p["confidence"] == "ok"][0]
    assert out["left_deg"] == ok["left_deg"] and out["right_deg"] == ok["right_deg"]
    assert out["angle_deg"] == pytest.approx((ok["left_deg"] + ok["right_deg"]) / 2, abs=1e-12)


def test_a_group_of_flagged_photos_only_is_refused(tmp_path):
    _photos(tmp_path, **{"a.png": _card("left", 60, 30, "checker"), "b.png": _card("right", 100, 60, "checker")})
    m = _group(tmp_path, ["a.png", "b.png"])
    with pytest.raises(InputError) as e:
        measure_manifest(m)
    msg = str(e.value)
    assert e.value.path == str(m) and "group heap" in e.value.field, msg
    assert str(tmp_path / "a.png") in msg and str(tmp_path / "b.png") in msg and "plate_line_px" in msg, msg


def test_cli_pile_group_sets_aside_a_flagged_photo(tmp_path, capsys):
    from soilcal.cli import main

    plain, card = _photos(tmp_path, **{"plain.png": heap_photo(), "card.png": _card("left", 60, 30, "checker")})
    assert main(["image", "pile", str(plain), str(card)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert abs(out["left_deg"] - 32.0) <= 0.5 and abs(out["right_deg"] - 35.0) <= 0.5, out
    assert [a["path"] for a in out["set_aside"]] == [str(card)]


def test_rendered_silhouettes_keep_every_view():
    # pile_summary without ok_only (a DEM heap's views): every result counts, nothing set aside
    r = [measure.PileResult("a", 33.0, 32.0, 34.0, 1.0, 0.0, confidence="low"),
         measure.PileResult("b", 35.0, 34.0, 36.0, 1.0, 0.0)]
    s = measure.pile_summary(r)
    assert s["left_deg"] == 33.0 and s["n_photos"] == 2 and "set_aside" not in s


def test_cli_warns_on_stderr_of_each_photo_set_aside(tmp_path, capsys):
    # the angle on stdout is the ok photo's; stderr names the photo left out and why, for
    # soilcal image pile and soilcal image soil alike
    from soilcal.cli import main

    plain, card = _photos(tmp_path, **{"plain.png": heap_photo(), "card.png": _card("left", 60, 30, "checker")})
    assert main(["image", "pile", str(plain), str(card)]) == 0
    err = capsys.readouterr().err
    assert f"photo {card} set aside" in err and "1 photo used" in err and "plate_line_px" in err, err
    assert str(plain) not in err
    assert main(["image", "soil", str(_group(tmp_path, ["plain.png", "card.png"]))]) == 0
    err = capsys.readouterr().err
    # the group named as in the image_measure job's log, the angle named as on the accepted-low line
    assert (f"soilcal: warning: group heap: photo {card} set aside (confidence low, not averaged into "
            f"the group's angle; 1 photo used)") in err, err


def test_a_low_photo_on_a_given_plate_line_is_not_told_to_give_it(tmp_path):
    # flanks drawn 25 and 40 deg, more than 12 deg apart: "low" on the plate line given too; its
    # way out is to check the points given, not to give a plate line again
    r = measure.measure_pile("steep.png", image=heap_photo(left=25.0, right=40.0),
                             plate_px=((10.0, 215.5), (390.0, 215.5)))
    assert r.confidence == "low" and abs(r.left_deg - 25.0) <= 0.5 and abs(r.right_deg - 40.0) <= 0.5
    why = measure.low_reason(r)
    assert "more than 12 deg apart" in why and "plate line given" in why and "check those two points" in why, why
    assert "give its plate line" not in why, why


def test_a_refused_group_of_flagged_photos_still_gets_the_figures_its_reasons_name(tmp_path, capsys):
    # each reason says "read its figure, --figures" (or names two plate lines to look at): with
    # --figures the refusal writes every photo's figure, as a measured group's are written
    from soilcal.cli import main

    a, b = _photos(tmp_path, **{"a.png": _card("left", 60, 30, "checker"), "b.png": _card("right", 100, 60, "checker")})
    figs = tmp_path / "figs"
    figs.mkdir()
    assert main(["image", "pile", str(a), str(b), "--figures", str(figs)]) != 0
    err = capsys.readouterr().err
    assert "confidence" in err and f"figures of every photo in {figs}" in err, err
    assert (figs / "a.png").is_file() and (figs / "b.png").is_file()
    mfigs = tmp_path / "mfigs"
    mfigs.mkdir()
    with pytest.raises(InputError) as e:
        measure_manifest(_group(tmp_path, ["a.png", "b.png"]), figdir=mfigs)
    assert "group heap" in e.value.field and str(mfigs) in str(e.value)
    assert (mfigs / "a.png").is_file() and (mfigs / "b.png").is_file()
    # with a refusals folder (the workflow's logs/<soil>/images/refused, which outlives the failed
    # job whose outputs, the figures folder among them, are removed), the figures go there
    kept = tmp_path / "refused"
    with pytest.raises(InputError) as e:
        measure_manifest(_group(tmp_path, ["a.png", "b.png"]), figdir=tmp_path / "gone", refusals=kept)
    assert str(kept) in str(e.value) and (kept / "a.png").is_file() and (kept / "b.png").is_file()


def test_cli_soil_writes_a_refused_groups_figures_to_figures_unless_refusals_is_given(tmp_path, capsys,
                                                                                      monkeypatch):
    # soilcal image soil --figures DIR: a refused group's figures go to DIR like a measured
    # group's, not to the current folder (the default of --refusals); --refusals DIR takes them
    from soilcal.cli import main

    _photos(tmp_path, **{"a.png": _card("left", 60, 30, "checker"), "b.png": _card("right", 100, 60, "checker")})
    m = _group(tmp_path, ["a.png", "b.png"])
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    figs = tmp_path / "figs"
    assert main(["image", "soil", str(m), "--figures", str(figs)]) != 0
    err = capsys.readouterr().err
    assert f"figures of the group's photos in {figs}" in err, err
    assert (figs / "a.png").is_file() and (figs / "b.png").is_file()
    assert not (here / "a.png").exists() and not (here / "b.png").exists()
    kept = tmp_path / "kept"
    assert main(["image", "soil", str(m), "--figures", str(tmp_path / "figs2"), "--refusals", str(kept)]) != 0
    err = capsys.readouterr().err
    assert f"figures of the group's photos in {kept}" in err, err
    assert (kept / "a.png").is_file() and (kept / "b.png").is_file()
