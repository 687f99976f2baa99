"""Start-up checks of a soil beyond its schema: each bad setting stops the config check (and the
workflow's start-up, which loads the soils the same way) with one line naming the soil file and
the field, before any job runs."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

from soilcal.config import load_soil
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]


def copy_soil(tmp: Path, soil: str = "cinnamon-soil") -> Path:
    """A shipped soil's YAML and its resources under ``tmp``; returns the YAML path."""
    (tmp / "config/soils").mkdir(parents=True, exist_ok=True)
    dst = tmp / "config/soils" / f"{soil}.yaml"
    shutil.copy(ROOT / "config/soils" / f"{soil}.yaml", dst)
    for kind in ("published", "measurements", "images", "geometry"):
        src = ROOT / "resources" / kind / soil
        if src.is_dir():
            shutil.copytree(src, tmp / "resources" / kind / soil)
    return dst


def edit(path: Path, fn) -> Path:
    data = yaml.safe_load(path.read_text())
    fn(data)
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def refused(path: Path, tmp: Path) -> InputError:
    with pytest.raises(InputError) as exc:
        load_soil(path, tmp / "resources")
    return exc.value


# ------------------------------------------------------------------ densities


@pytest.mark.parametrize("rho", [175.7567, 1394.0, 7850.0, 19300.0])
def test_densities_of_soils_and_tool_materials_pass(rho):
    from soilcal.dem.scenarios.base import DemParams

    assert DemParams.from_mapping({"soil_density": rho, "steel_density": rho}).steel_density == rho


def test_a_density_typed_in_g_per_cm3_is_refused(tmp_path):
    p = edit(copy_soil(tmp_path), lambda d: d["simulation"].update(params={"soil_density": 1.394}))
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == "simulation.params.soil_density" and e.got == 1.394
    assert "[100, 25000] kg/m^3" in e.expected


# ------------------------------------------------------------------ loop.fold_by


def test_fold_by_names_a_covariate_column_of_the_measured_tables(tmp_path):
    p = copy_soil(tmp_path)
    columns = sorted(yaml.safe_load(p.read_text())["measurements"]["cutting_resistance"]["covariates"])
    edit(p, lambda d: d.update(loop={"fold_by": columns[0]}))
    load_soil(p, tmp_path / "resources")
    edit(p, lambda d: d.update(loop={"fold_by": "test_day"}))
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == "loop.fold_by" and e.got == "test_day"
    assert e.expected == f"a covariate column of the soil's measured tables ({', '.join(columns)})"


# ------------------------------------------------------------------ simulation.screening


def _pb_factor_count(p: Path) -> int:
    d = yaml.safe_load(p.read_text())
    return len(next(s for s in d["stages"] if s["kind"] == "plackett_burman")["factors"])


def test_screening_min_factors_above_max_factors_is_refused(tmp_path):
    p = edit(copy_soil(tmp_path), lambda d: d["simulation"].update(screening={"min_factors": 4, "max_factors": 3}))
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == "simulation.screening.min_factors" and e.got == 4
    assert "max_factors (3)" in e.expected
    # max_factors below the default min_factors names max_factors, the key the file gives
    edit(p, lambda d: d["simulation"].update(screening={"max_factors": 2}))
    e = refused(p, tmp_path)
    assert e.field == "simulation.screening.max_factors" and e.got == 2


def test_screening_min_factors_above_the_screenings_factor_count_is_refused(tmp_path):
    p = copy_soil(tmp_path)
    k = _pb_factor_count(p)
    edit(p, lambda d: d["simulation"].update(screening={"min_factors": k}))
    load_soil(p, tmp_path / "resources")  # every screened factor on the path: allowed
    edit(p, lambda d: d["simulation"].update(screening={"min_factors": k + 1}))
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == "simulation.screening.min_factors" and e.got == k + 1
    assert e.expected.startswith(f"an integer <= {k}, the factor count of screening stage 'pb'")
    # a path run on the printed levels selects nothing: the count does not matter
    edit(p, lambda d: d["simulation"].update(design="printed"))
    load_soil(p, tmp_path / "resources")
