"""The image_measure job empties logs/<soil>/images/refused before measuring: where that folder
is a symlink to a folder kept elsewhere, the target's contents go, the link and the target stay,
and no link inside it is followed out of it."""

from __future__ import annotations

import types
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "workflow" / "scripts" / "image_measure.py"


def _job(tmp_path, refusals):
    return types.SimpleNamespace(log=[str(tmp_path / "logs/image_measure.log")],
                                 output=types.SimpleNamespace(json=str(tmp_path / "out/m.json"),
                                                              figures=str(tmp_path / "out/figs")),
                                 params=types.SimpleNamespace(refusals=str(refusals),
                                                              manifest=str(tmp_path / "no_manifest.yaml"),
                                                              threshold="otsu"))


def test_a_symlinked_refusals_folder_is_emptied_not_followed_out_of(tmp_path):
    # before: shutil.rmtree on the symlink raised OSError ("Cannot call rmtree on a symbolic
    # link"), a traceback instead of the run
    kept = tmp_path / "kept"
    (kept / "sub").mkdir(parents=True)
    (kept / "a.refused.png").write_bytes(b"earlier")
    (kept / "sub" / "b.png").write_bytes(b"earlier")
    outside = tmp_path / "precious"
    outside.mkdir()
    (outside / "photo.png").write_bytes(b"photo")
    (kept / "to_outside").symlink_to(outside)
    (kept / "file_link.png").symlink_to(outside / "photo.png")
    refused = tmp_path / "logs" / "refused"
    refused.parent.mkdir(parents=True)
    refused.symlink_to(kept)
    with pytest.raises(SystemExit) as e:  # the manifest is missing: one line, exit 2, after emptying
        exec(compile(SCRIPT.read_text(), str(SCRIPT), "exec"), {"snakemake": _job(tmp_path, refused),
                                                                 "__name__": "__main__"})
    assert e.value.code == 2
    assert refused.is_symlink() and kept.is_dir() and not any(kept.iterdir()), sorted(kept.iterdir())
    assert (outside / "photo.png").read_bytes() == b"photo"


def test_an_earlier_runs_refusals_are_emptied_before_the_photos_are_measured(tmp_path):
    # logs/<soil>/images/refused holds the diagnostic images and a refused group's figures of the
    # run that refused; before: what an earlier run left there stayed beside a later run's results
    # and was taken for them (the job empties it before it reads the manifest)
    kept = tmp_path / "logs" / "refused"
    kept.mkdir(parents=True)
    for name in ("stacking_1.refused.png", "stacking_1.png", "stacking_2.png"):
        (kept / name).write_bytes(b"an earlier run's figure")
    with pytest.raises(SystemExit) as e:  # the manifest is missing: one line, exit 2, after emptying
        exec(compile(SCRIPT.read_text(), str(SCRIPT), "exec"), {"snakemake": _job(tmp_path, kept),
                                                                 "__name__": "__main__"})
    assert e.value.code == 2
    assert kept.is_dir() and not any(kept.iterdir()), sorted(p.name for p in kept.iterdir())


def test_empty_folder_refuses_a_file_and_leaves_a_missing_folder(tmp_path):
    from soilcal.errors import InputError
    from soilcal.logs import empty_folder

    empty_folder(tmp_path / "none")
    assert not (tmp_path / "none").exists()
    (tmp_path / "f").write_text("x")
    with pytest.raises(InputError) as e:
        empty_folder(tmp_path / "f", "refusals folder")
    assert e.value.field == "refusals folder" and str(tmp_path / "f") in str(e.value)
