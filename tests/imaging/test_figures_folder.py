"""Figures are written as <photo name>.png and .pdf: a figures folder that is the folder of any
photo of the call is refused before anything is measured or written (a PNG photo there, the one
measured or another of the same name, would be replaced by a figure)."""

from __future__ import annotations

import os

import pytest
import yaml

from test_user_photos import _u8, heap_photo


def _refused(main, capsys, argv, photo, option="--figures"):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert str(photo) in err and option in err and "other than the photo's own" in err, err


def test_figures_into_the_photos_own_folder_never_replace_a_png_photo(tmp_path, capsys):
    # before: exit 0, heap.png overwritten by its five-panel figure (the photo lost)
    from soilcal.cli import main

    photo = tmp_path / "heap.png"
    _u8(heap_photo()).save(photo)
    data = photo.read_bytes()
    _refused(main, capsys, ["image", "pile", str(photo), "--figures", str(tmp_path)], photo)
    assert photo.read_bytes() == data
    # another folder: the figure is written, the photo untouched
    assert main(["image", "pile", str(photo), "--figures", str(tmp_path / "figs")]) == 0
    assert (tmp_path / "figs" / "heap.png").is_file() and photo.read_bytes() == data


def test_a_jpg_photos_figure_never_replaces_a_png_photo_beside_it(tmp_path, capsys, monkeypatch):
    # before: heap.jpg's figure written as heap.png over the photo heap.png beside it (silently
    # with heap.jpg alone; with both photos given, heap.png was replaced, then refused)
    from soilcal.cli import main

    jpg, png = tmp_path / "heap.jpg", tmp_path / "heap.png"
    _u8(heap_photo()).save(jpg, quality=95)
    _u8(heap_photo(left=30, right=33, seed=3)).save(png)
    data = png.read_bytes()
    _refused(main, capsys, ["image", "pile", str(jpg), str(png), "--figures", str(tmp_path)], jpg)
    _refused(main, capsys, ["image", "pile", str(jpg), "--figures", str(tmp_path)], jpg)
    # the same folder spelled otherwise: relative, through a symlink
    link = tmp_path.parent / (tmp_path.name + "_link")
    os.symlink(tmp_path, link)
    monkeypatch.chdir(tmp_path)
    _refused(main, capsys, ["image", "pile", "heap.jpg", "--figures", str(link)], "heap.jpg")
    _refused(main, capsys, ["image", "pile", str(link / "heap.jpg"), "--figures", "."], link / "heap.jpg")
    assert png.read_bytes() == data and not (tmp_path / "heap.pdf").exists()


def test_a_manifests_figures_folder_that_is_its_photos_folder_is_refused(tmp_path, capsys):
    from soilcal.cli import main
    from soilcal.errors import InputError
    from soilcal.imaging.manifest import measure_manifest

    _u8(heap_photo()).save(tmp_path / "a.jpg", quality=95)
    _u8(heap_photo(left=30, right=33, seed=3)).save(tmp_path / "a.png")
    data = (tmp_path / "a.png").read_bytes()
    m = tmp_path / "manifest.yaml"
    m.write_text(yaml.safe_dump({"photos": [{"file": "a.jpg", "kind": "pile", "group": "heap"}]}))
    _refused(main, capsys, ["image", "soil", str(m), "--figures", str(tmp_path)], tmp_path / "a.jpg")
    _refused(main, capsys, ["image", "soil", str(m), "--figures", str(tmp_path / "figs"), "--refusals",
                            str(tmp_path)], tmp_path / "a.jpg", "--refusals")
    with pytest.raises(InputError) as e:
        measure_manifest(m, figdir=tmp_path)
    assert e.value.field == "figures folder"
    assert (tmp_path / "a.png").read_bytes() == data and not (tmp_path / "figs").exists()


def test_photos_named_with_dots_get_a_figure_each(tmp_path):
    # heap.v1.png and heap.v2.png have the stems heap.v1 and heap.v2; their figures were both
    # written as heap.png / heap.pdf (Path.with_suffix took .v1 and .v2 for extensions), the
    # second replacing the first
    import matplotlib.pyplot as plt

    from soilcal.imaging.figures import _save

    for stem in ("heap.v1", "heap.v2"):
        _save(plt.figure(), tmp_path / stem)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["heap.v1.pdf", "heap.v1.png", "heap.v2.pdf",
                                                          "heap.v2.png"]
