"""soilcal image pile --refusals DIR: a photo's diagnostic image from an earlier run in which it
was refused (DIR/<stem>.refused.png) is gone once the photo is measured, so that no refusal is
read beside a photo this run measured; nothing else in DIR is touched."""

from __future__ import annotations

from test_user_photos import _u8, heap_photo


def test_an_earlier_runs_refusal_of_a_photo_now_measured_is_removed(tmp_path):
    # before: exit 0 with refused/heap.refused.png from the earlier run still there
    from soilcal.cli import main

    photo = tmp_path / "heap.png"
    _u8(heap_photo()).save(photo)
    refused = tmp_path / "refused"
    refused.mkdir()
    (refused / "heap.refused.png").write_bytes(b"an earlier run's diagnostic image")
    (refused / "other.refused.png").write_bytes(b"another photo's, not measured in this run")
    (refused / "notes.txt").write_text("the user's own file")
    assert main(["image", "pile", str(photo), "--refusals", str(refused)]) == 0
    assert not (refused / "heap.refused.png").exists()
    assert sorted(p.name for p in refused.iterdir()) == ["notes.txt", "other.refused.png"]


def test_two_photos_sharing_a_refusal_name_are_refused_naming_both(tmp_path, capsys):
    # before: heap.png and heap.jpg measured in one call both had refused/heap.refused.png, one
    # photo's refusal overwriting or (measured first) removing the other's
    from soilcal.cli import main

    png, jpg = tmp_path / "heap.png", tmp_path / "heap.jpg"
    _u8(heap_photo()).save(png)
    _u8(heap_photo()).save(jpg, quality=95)
    assert main(["image", "pile", str(png), str(jpg), "--refusals", str(tmp_path / "refused")]) == 2
    err = capsys.readouterr().err
    assert str(png) in err and str(jpg) in err and "heap.refused.png" in err, err
