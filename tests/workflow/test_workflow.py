"""The Snakemake workflow end to end on a copy of the repository's config and data: the replay of
the printed tables (published source)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest

from wfutil import ROOT, copy_workflow, planned_jobs, run

SOILS = ["cinnamon-soil", "yangtze-clay-loam"]


def _copy(tmp: Path) -> Path:
    # the replay; tests/workflow/test_dem_workflow.py runs the DEM source.  The second soil's
    # furrow photo is left out: no target of that soil reads it, nor does a test here (the
    # cinnamon soil's photos are measured and read), so no job measures it
    tmp = copy_workflow(tmp, SOILS, source="published")
    shutil.rmtree(tmp / "resources/images" / SOILS[1])
    return tmp


def _run(tmp: Path, *args, check=True):
    return run(tmp, *args, check=check)


@pytest.fixture(scope="module")
def done(tmp_path_factory):
    if not all((ROOT / "config/soils" / f"{s}.yaml").is_file() for s in SOILS):
        pytest.skip("soil entries not present")
    tmp = _copy(tmp_path_factory.mktemp("wf"))
    _run(tmp, "--cores", "2")
    return tmp


def test_replay_outputs(done):
    d = done / "results/cinnamon-soil/published"
    anova = pd.read_csv(d / "bbd/anova.csv")
    assert list(anova.columns[-6:]) == ["source", "sum_sq", "df", "mean_sq", "F", "p"]
    assert {"full", "reduced"} == set(anova["model"])
    rows = set(anova[anova["model"] == "full"]["source"])
    assert {"Model", "A", "A*C", "B^2", "Residual", "Lack of Fit", "Pure Error", "Cor Total"} <= rows
    coef = pd.read_csv(d / "bbd/coefficients.csv")
    assert {"term", "coded", "actual", "model"} <= set(coef.columns)
    assert (d / "bbd/optimum.csv").is_file() and (d / "errata.csv").is_file()
    pngs = list((d / "bbd/figures/surfaces").glob("*.png"))
    assert pngs and all(p.with_suffix(".pdf").is_file() for p in pngs)
    assert list((d / "pb/figures/pareto").glob("*.png"))
    errata = pd.read_csv(d / "errata.csv")
    assert list(errata.columns) == ["where", "printed", "recomputed", "note"]
    photos = done / "results/cinnamon-soil/images/measurements.json"
    assert abs(__import__("json").loads(photos.read_text())["stacking"]["angle_deg"] - 27.69) <= 0.3


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
            "expected a complete, readable image (JPEG/PNG/TIFF)")
    assert r.returncode != 0
    assert sum(line in ln for ln in text.splitlines()) == 1, text[-3000:]
    assert "Traceback" not in text and "returned non-zero exit status 2" in text
    log = (tmp / "logs/cinnamon-soil/images/image_measure.log").read_text()
    assert "ERROR soilcal: resources/images/cinnamon-soil/stacking_1.jpg: file: expected" in log
    assert "Traceback" not in log
    assert not (tmp / out).exists() and not (tmp / "results/cinnamon-soil/images/figures").exists()


def _planned_jobs(tmp: Path) -> list[str]:
    return planned_jobs(tmp)


def test_editing_one_soil_reruns_only_that_soil(done):
    assert _planned_jobs(done) == []
    p = done / "config/soils/cinnamon-soil.yaml"
    text = p.read_text()
    p.write_text(text.replace("seed: 1082", "seed: 1083"))
    try:
        planned = _planned_jobs(done)
        assert planned, "changing the seed must re-run the optimisation"
        assert all("results/cinnamon-soil/" in o for o in planned), planned
    finally:
        p.write_text(text)


def test_lint_is_clean(done):
    p = _run(done, "--lint", check=False)
    assert p.returncode == 0, p.stdout + p.stderr



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
