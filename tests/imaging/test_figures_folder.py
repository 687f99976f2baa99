"""Figures are written as <photo name>.png: a figures folder that is the photos' own folder must
not replace a PNG photo by its figure."""

from __future__ import annotations

from test_user_photos import _u8, heap_photo


def test_figures_into_the_photos_own_folder_never_replace_a_png_photo(tmp_path, capsys):
    # before: exit 0, heap.png overwritten by its five-panel figure (the photo lost)
    from soilcal.cli import main

    photo = tmp_path / "heap.png"
    _u8(heap_photo()).save(photo)
    data = photo.read_bytes()
    assert main(["image", "pile", str(photo), "--figures", str(tmp_path)]) != 0
    err = capsys.readouterr().err
    assert str(photo) in err and "figures folder" in err and "replace the photo" in err, err
    assert photo.read_bytes() == data
    # another folder: the figure is written, the photo untouched
    assert main(["image", "pile", str(photo), "--figures", str(tmp_path / "figs")]) == 0
    assert (tmp_path / "figs" / "heap.png").is_file() and photo.read_bytes() == data
