"""The Snakemake workflow on a copy of the repository's config and data, replaying the printed
tables (published source): what it refuses before any job runs, and a bad photo found by the
job that measures it.  The replay's tables and figures, an edit that re-runs one soil of two,
and the lint are read from the session's tiny run (tests/workflow/test_dem_workflow.py), which
replays the printed tables of two soils beside its DEM calibration."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from wfutil import ROOT, copy_workflow, run

SOILS = ["cinnamon-soil", "yangtze-clay-loam"]


def _copy(tmp: Path) -> Path:
    # the replay.  The second soil's furrow photo is left out: no target of that soil reads it,
    # nor does a test here (the cinnamon soil's photos are measured and read)
    tmp = copy_workflow(tmp, SOILS, source="published")
    shutil.rmtree(tmp / "resources/images" / SOILS[1])
    return tmp


def _run(tmp: Path, *args, check=True):
    return run(tmp, *args, check=check)


def test_missing_photo_is_one_clear_error(tmp_path):
    tmp = _copy(tmp_path)
    (tmp / "resources/images/cinnamon-soil/stacking_2.jpg").unlink()
    r = _run(tmp, "-n", "--cores", "2", check=False)
    assert r.returncode != 0
    assert "manifest.yaml: photos[1].file: expected an existing image file" in r.stdout + r.stderr


def test_bad_photo_found_by_a_job_is_one_line_without_traceback(tmp_path):
    # the photo exists (start-up passes) but is no image: the job that measures it finds out
    tmp = _copy(tmp_path)
    (tmp / "resources/images/cinnamon-soil/stacking_1.jpg").write_text("not a photo\n")
    out = "results/cinnamon-soil/images/measurements.json"
    r = _run(tmp, "--cores", "1", out, check=False)
    text = r.stdout + r.stderr
    line = ("soilcal: error: resources/images/cinnamon-soil/stacking_1.jpg: file: "
            "expected a complete, readable image (JPEG/PNG/TIFF/HEIC)")
    assert r.returncode != 0
    assert sum(line in ln for ln in text.splitlines()) == 1, text[-3000:]
    assert "Traceback" not in text and "returned non-zero exit status 2" in text
    log = (tmp / "logs/cinnamon-soil/images/image_measure.log").read_text()
    assert "ERROR soilcal: resources/images/cinnamon-soil/stacking_1.jpg: file: expected" in log
    assert "Traceback" not in log
    assert not (tmp / out).exists() and not (tmp / "results/cinnamon-soil/images/figures").exists()


@pytest.mark.parametrize("setting, field, expected", [
    ("soils=oops", "soils", "a value of type array"),
    ("design=adaptiv", "design", "one of recipe, printed, adaptive"),
    ("soils=[nosuch]", "soils[0]", "a soil file config/soils/nosuch.yaml"),
])
def test_a_bad_workflow_setting_is_one_line(tmp_path, setting, field, expected):
    """--config reaches the workflow schema (the package's, linked from workflow/schemas)."""
    tmp = _copy(tmp_path)
    r = _run(tmp, "-n", "--cores", "1", "--config", setting, check=False)
    text = r.stdout + r.stderr
    lines = [ln for ln in text.splitlines() if ln.startswith("soilcal: error: ")]
    assert r.returncode == 2 and len(lines) == 1, text
    assert lines[0].startswith(f"soilcal: error: <command line: --config>: {field}: expected {expected}"), lines
    assert 'File "' not in text and not (tmp / "results").exists()


def test_bad_soil_file_stops_before_any_job(tmp_path):
    if not all((ROOT / "config/soils" / f"{s}.yaml").is_file() for s in SOILS):
        pytest.skip("soil entries not present")
    tmp = _copy(tmp_path)
    p = tmp / "config/soils/cinnamon-soil.yaml"
    p.write_text(p.read_text().replace("center_points: 5", "centre_points: 5"))
    r = _run(tmp, "--cores", "2", check=False)
    assert r.returncode != 0
    text = r.stdout + r.stderr
    lines = [ln for ln in text.splitlines() if "cinnamon-soil.yaml: stages[2].centre_points" in ln]
    assert len(lines) == 1 and lines[0].startswith("soilcal: error: ") and r.returncode == 2, text
    assert "Traceback" not in text and 'File "' not in text, text
    assert not (tmp / "results").exists()
