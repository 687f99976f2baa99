"""The Snakemake workflow end to end on a copy of the repository's config and data."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]
SOILS = ["cinnamon-soil", "yangtze-clay-loam"]


def _copy(tmp: Path) -> Path:
    shutil.copy(ROOT / "Snakefile", tmp / "Snakefile")
    shutil.copytree(ROOT / "envs", tmp / "envs")
    for item in ("workflow", "config"):
        shutil.copytree(ROOT / item, tmp / item, symlinks=True)
    # the schema symlink points into the package; resolve it for the copy
    link = tmp / "workflow/schemas/soil.schema.yaml"
    if link.is_symlink():
        link.unlink()
        shutil.copy(ROOT / "src/soilcal/config/soil.schema.yaml", link)
    for soil in SOILS:
        for kind in ("published", "images"):
            if (ROOT / "resources" / kind / soil).is_dir():
                shutil.copytree(ROOT / "resources" / kind / soil, tmp / "resources" / kind / soil)
    cfg = yaml.safe_load((tmp / "config/config.yaml").read_text())
    cfg["soils"] = SOILS
    (tmp / "config/config.yaml").write_text(yaml.safe_dump(cfg))
    return tmp


def _run(tmp: Path, *args, check=True):
    p = subprocess.run(SNAKEMAKE + list(args), cwd=tmp, capture_output=True, text=True)
    if check and p.returncode != 0:
        raise AssertionError(p.stdout[-3000:] + p.stderr[-3000:])
    return p


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


def _planned_jobs(tmp: Path) -> list[str]:
    out = _run(tmp, "-n", "--cores", "2").stdout
    return re.findall(r"^\s+output: (.+)$", out, flags=re.M)


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


def test_bad_soil_file_stops_before_any_job(tmp_path):
    if not all((ROOT / "config/soils" / f"{s}.yaml").is_file() for s in SOILS):
        pytest.skip("soil entries not present")
    tmp = _copy(tmp_path)
    p = tmp / "config/soils/cinnamon-soil.yaml"
    p.write_text(p.read_text().replace("center_points: 5", "centre_points: 5"))
    r = _run(tmp, "--cores", "2", check=False)
    assert r.returncode != 0
    assert "cinnamon-soil.yaml: stages[2].centre_points" in r.stdout + r.stderr
    assert not (tmp / "results").exists()
