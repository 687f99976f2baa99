"""Declarations and cells of a soil's ``measurements`` block that used to be accepted and
then misread: each is refused with the file and the field (or the table row and column) named.

Each test edits a copy of a shipped soil's parsed YAML and of its measured tables and runs the
block's start-up check (:func:`soilcal.config.measurements.check_measurements`, which the
loader calls); the broken-input corpus (tests/corpus) runs some of the same inputs through
the command line."""

from __future__ import annotations

import copy
import math
import shutil
from pathlib import Path
from types import SimpleNamespace

import pandas as pd
import pytest

from soilcal.config.load import read_yaml
from soilcal.config.measurements import check_measurements, conditions
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]
SOIL = "cinnamon-soil"
CUT = "measurements.cutting_resistance"


@pytest.fixture(scope="module")
def parsed():
    return {s: read_yaml(ROOT / f"config/soils/{s}.yaml") for s in (SOIL, "black-soil")}


def _workspace(tmp_path, parsed, soil):
    shutil.copytree(ROOT / "resources/measurements" / soil, tmp_path / "resources/measurements" / soil)
    return SimpleNamespace(path=ROOT / f"config/soils/{soil}.yaml", data=copy.deepcopy(parsed[soil]),
                           resources_root=tmp_path / "resources", soil=soil)


@pytest.fixture
def cinnamon(tmp_path, parsed):
    return _workspace(tmp_path, parsed, SOIL)


@pytest.fixture
def black(tmp_path, parsed):
    return _workspace(tmp_path, parsed, "black-soil")


def _entry(ws, mid="cutting_resistance"):
    return ws.data["measurements"][mid]


def _table(ws, name="cutting_resistance.csv"):
    return ws.resources_root / "measurements" / ws.soil / name


def _column(ws, name, cells, table="cutting_resistance.csv"):
    t = _table(ws, table)
    df = pd.read_csv(t)
    df[name] = cells
    df.to_csv(t, index=False)
    return t


def _load(ws):
    return conditions(ws)


def _fails(ws, where: str) -> str:
    """The check fails with one line starting '<where>: expected'."""
    with pytest.raises(InputError) as e:
        check_measurements(ws.path, ws.data, ws.resources_root)
    msg = str(e.value)
    assert msg.startswith(f"{where}: expected"), msg
    assert "\n" not in msg
    return msg


# --- sd and n of a response -------------------------------------------------------------------


def _spread(ws, sd, n):
    """SD and repeat-count columns beside the horizontal force, declared as its sd and n."""
    _column(ws, "horizontal_sd_N", sd)
    t = _column(ws, "repeats", n)
    _entry(ws)["responses"][0].update(sd="horizontal_sd_N", n="repeats")
    return t


def test_sd_and_n_are_read(cinnamon):
    _spread(cinnamon, [5.1, 0.5, 3.0, 4.0], [3, 1, None, 5])
    got = [(c.responses[0]["measured_sd"], c.responses[0]["n"]) for c in _load(cinnamon)]
    # n = 1 beside an SD, and a blank n, are accepted (the SD is the value's own uncertainty)
    assert got == [(5.1, 3), (0.5, 1), (3.0, None), (4.0, 5)]


@pytest.mark.parametrize("bad, n", [(-2, 3), (0, 3), (0, 1)])
def test_a_negative_or_zero_sd_is_refused(cinnamon, bad, n):
    # an SD of 0, behind three repeats or as the value's own uncertainty, calls the value exact
    t = _spread(cinnamon, [5.1, bad, 3.0, 4.0], [3, n, 3, 3])
    msg = _fails(cinnamon, f"{t}: row 2, column horizontal_sd_N")
    assert "a standard deviation > 0" in msg and f"got {bad}" in msg and "blank cell" in msg


@pytest.mark.parametrize("bad", [0, -3, 2.6])
def test_n_not_a_whole_number_of_at_least_one_is_refused(cinnamon, bad):
    t = _spread(cinnamon, [5.1, 2.0, 3.0, 4.0], [3, 3, bad, 3])
    msg = _fails(cinnamon, f"{t}: row 3, column repeats")
    assert "a whole number of repeats >= 1" in msg and f"got {bad}" in msg


# --- one column, one role ---------------------------------------------------------------------


def test_sd_naming_its_own_value_column(cinnamon):
    _entry(cinnamon)["responses"][0].update(sd="horizontal_measured_N")
    msg = _fails(cinnamon, f"{cinnamon.path}: {CUT}.responses[0].sd")
    assert f"horizontal_measured_N is already the value column of {CUT}.responses[0]" in msg


def test_n_naming_the_value_column_of_another_response(cinnamon):
    _entry(cinnamon)["responses"][1].update(n="horizontal_measured_N")
    msg = _fails(cinnamon, f"{cinnamon.path}: {CUT}.responses[1].n")
    assert f"already the value column of {CUT}.responses[0]" in msg


def test_covariate_column_also_a_response_value(cinnamon):
    _entry(cinnamon)["responses"][0].update(value="plate")
    msg = _fails(cinnamon, f"{cinnamon.path}: {CUT}.responses[0].value")
    assert f"plate is already the covariate {CUT}.covariates.plate" in msg


def test_covariate_also_listed_in_ignore_columns(cinnamon):
    _entry(cinnamon)["ignore_columns"].append("plate")
    msg = _fails(cinnamon, f"{cinnamon.path}: {CUT}.ignore_columns[1]")
    assert f"plate is already the covariate {CUT}.covariates.plate" in msg


def test_one_repeat_count_column_for_every_response(cinnamon):
    _column(cinnamon, "repeats", [3, 3, 4, 3])
    for r in _entry(cinnamon)["responses"]:
        r.update(n="repeats")
    assert [[r["n"] for r in c.responses] for c in _load(cinnamon)] == [[3, 3], [3, 3], [4, 4], [3, 3]]


# --- the table's path -------------------------------------------------------------------------


@pytest.mark.parametrize("escape", ["../../outside.csv", "sub/../../cinnamon-soil-copy.csv", "ABSOLUTE"])
def test_table_outside_the_soils_measurements_folder(cinnamon, escape):
    # a real table sits at each place, so only the path itself can be what is refused
    t = _table(cinnamon)
    target = (t.parent / escape if escape != "ABSOLUTE" else cinnamon.resources_root.parent / "elsewhere.csv").resolve()
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(t.read_text())
    table = str(target) if escape == "ABSOLUTE" else escape
    _entry(cinnamon).update(table=table)
    msg = _fails(cinnamon, f"{cinnamon.path}: {CUT}.table")
    assert f"a table inside {t.parent}/" in msg and repr(table) in msg


def test_table_in_a_subfolder_is_inside(cinnamon):
    t = _table(cinnamon)
    (t.parent / "2023").mkdir()
    t.rename(t.parent / "2023" / t.name)
    _entry(cinnamon).update(table="2023/./cutting_resistance.csv")
    assert len(_load(cinnamon)) == 4


# --- the calibrated stage ---------------------------------------------------------------------


@pytest.mark.parametrize("source", ["dem", "both"])
def test_calibrated_stage_the_dem_does_not_simulate(cinnamon, source):
    cinnamon.data["source"] = source
    cinnamon.data["simulation"]["stages"] = ["pb", "steepest"]  # the entry is calibrated on bbd
    msg = _fails(cinnamon, f"{cinnamon.path}: {CUT}.calibrated.stage")
    assert msg.endswith("expected a stage the DEM simulates (simulation.stages: pb, steepest), got 'bbd'")


def test_calibrated_stage_among_the_simulated_ones(cinnamon):
    cinnamon.data["simulation"]["stages"] = ["steepest", "bbd"]
    assert {c.stage for c in _load(cinnamon)} == {"bbd"}


# --- scale against the declared unit ----------------------------------------------------------


def _speed_kmh(ws, **extra):
    """A tool-speed column in km/h that sets the bulldozing plate's speed (m/s)."""
    _column(ws, "speed_kmh", [0.576, 3.6, 7.2, 1.8])
    _entry(ws)["covariates"]["speed_kmh"] = {"set": "speed", "quantity": "tool_speed", "unit": "km/h", **extra}


def test_km_per_h_without_scale_is_refused(cinnamon):
    _speed_kmh(cinnamon)
    msg = _fails(cinnamon, f"{cinnamon.path}: {CUT}.covariates.speed_kmh.scale")
    # 1 km/h = 1/3.6 m/s
    assert msg.endswith(f"expected {1 / 3.6:.4g} (km/h to m/s, the unit of setup key speed), got 1")


@pytest.mark.parametrize("scale", [0.2778, 1 / 3.6])
def test_km_per_h_with_its_factor_runs_the_dem_in_m_per_s(cinnamon, scale):
    _speed_kmh(cinnamon, scale=scale)
    conds = _load(cinnamon)
    assert [c.setup["speed"] for c in conds] == pytest.approx([0.16, 1.0, 2.0, 0.5], rel=1e-3)
    assert [c.quantities["tool_speed"] for c in conds] == pytest.approx([0.16, 1.0, 2.0, 0.5])


def test_scale_off_by_more_than_the_tolerance_is_refused(cinnamon):
    _speed_kmh(cinnamon, scale=0.28)  # 0.8 % above 1/3.6
    _fails(cinnamon, f"{cinnamon.path}: {CUT}.covariates.speed_kmh.scale")


def test_depth_in_mm_with_a_centimetre_scale(cinnamon):
    _column(cinnamon, "depth_mm", [30, 35, 40, 45])
    _entry(cinnamon)["covariates"]["depth_mm"] = {"set": "depth", "scale": 0.01, "quantity": "working_depth",
                                                  "unit": "mm"}
    msg = _fails(cinnamon, f"{cinnamon.path}: {CUT}.covariates.depth_mm.scale")
    assert msg.endswith("expected 0.001 (mm to m, the unit of setup key depth), got 0.01")


def test_density_in_g_per_cm3_sets_a_parameter_in_kg_per_m3(cinnamon):
    _column(cinnamon, "density_g_cm3", [1.3, 1.35, 1.4, 1.45])
    _entry(cinnamon)["covariates"]["density_g_cm3"] = {"param": "soil_density", "quantity": "bulk_density",
                                                       "unit": "g/cm^3"}
    msg = _fails(cinnamon, f"{cinnamon.path}: {CUT}.covariates.density_g_cm3.scale")
    assert msg.endswith("expected 1000 (g/cm^3 to kg/m^3, the unit of DEM parameter soil_density), got 1")


def test_rotor_speed_in_rad_per_s_sets_a_key_in_r_per_min(black):
    _column(black, "omega_rad_s", [15.7, 20.9, 26.2, 31.4, 36.7], table="surface_flatness.csv")
    covs = _entry(black, "surface_flatness")["covariates"]
    for k in ("quantity", "unit"):  # the quantity is declared by the new column
        covs["rotor_speed_rpm"].pop(k, None)
    covs["omega_rad_s"] = {"set": "rpm", "quantity": "rotor_speed", "unit": "rad/s"}
    msg = _fails(black, f"{black.path}: measurements.surface_flatness.covariates.omega_rad_s.scale")
    # 1 rad/s = 60 / (2 pi) r/min
    assert msg.endswith(f"expected {60 / (2 * math.pi):.4g} (rad/s to r/min, the unit of setup key rpm), got 1")


def test_a_spreadsheet_export_with_empty_rows_after_the_data_loads_its_rows(cinnamon):
    t = _table(cinnamon)
    cols = t.read_text().splitlines()[0].count(",")
    t.write_text(t.read_text().rstrip("\n") + "\n" + ("," * cols + "\n") * 3)
    assert len(_load(cinnamon)) == 4
