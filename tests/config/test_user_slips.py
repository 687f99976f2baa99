"""Slips a user makes in a soil of their own, each stopped at start-up with one error naming the
file and the field (never a traceback, never a value silently taken another way): a parameter
in a unit of another quantity, a misspelt ``from_stage`` on a stage that leaves its factors to
the recipe, a misspelt key of a printed optimum or verification, a goal with two targets, a
printed response left blank in one run, a misspelt setup of a measured test that gives its own
particle sizes.  The soil is the cinnamon soil's config and tables, copied and changed."""

from __future__ import annotations

import copy
import shutil
from pathlib import Path

import pytest
import yaml

from soilcal.config import load_soil
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]
SOIL = "cinnamon-soil"


@pytest.fixture(scope="module")
def raw() -> dict:
    return yaml.safe_load((ROOT / "config" / "soils" / f"{SOIL}.yaml").read_text())


def _load(tmp_path: Path, data: dict, resources: Path | None = None):
    p = tmp_path / f"{SOIL}.yaml"
    p.write_text(yaml.safe_dump(data, sort_keys=False))
    return load_soil(p, resources or ROOT / "resources")


def _error(tmp_path, data, resources=None) -> InputError:
    with pytest.raises(InputError) as exc:
        _load(tmp_path, data, resources)
    return exc.value


def _stage(d: dict, sid: str) -> dict:
    return next(s for s in d["stages"] if s["id"] == sid)


def test_the_soil_loads_as_shipped(tmp_path, raw):
    assert _load(tmp_path, copy.deepcopy(raw)).name == SOIL


@pytest.mark.parametrize("unit, kind", [("mJ/m^2", "static_friction"), ("MPa", "static_friction"),
                                        ("Pa", "surface_energy"), ("kg/m^3", "surface_energy"),
                                        ("-", "surface_energy")])
def test_a_parameter_in_a_unit_of_another_quantity_is_refused(tmp_path, raw, unit, kind):
    # the unit's factor to SI would otherwise rescale the value: a friction of 0.9 in mJ/m^2
    # would run as 0.0009
    d = copy.deepcopy(raw)
    pid = "soil_soil_static_friction" if kind == "static_friction" else "jkr_surface_energy"
    d["parameters"][pid]["unit"] = unit
    e = _error(tmp_path, d)
    assert e.field == f"parameters.{pid}.unit" and e.got == unit, str(e)
    assert "a unit of soil_soil_" in e.expected


@pytest.mark.parametrize("unit", ["J/m^2", "mJ/m^2"])
def test_a_surface_energy_in_either_of_its_units_loads(tmp_path, raw, unit):
    d = copy.deepcopy(raw)
    d["parameters"]["jkr_surface_energy"]["unit"] = unit
    if unit == "mJ/m^2":  # the same energies in mJ/m^2
        for st in d["stages"]:
            for f in (st.get("factors") or {}).values():
                if f["parameter"] == "jkr_surface_energy":
                    for k in ("low", "centre", "high"):
                        if k in f:
                            f[k] = f[k] * 1000
    assert _load(tmp_path, d).name == SOIL


def test_a_misspelt_from_stage_of_a_stage_without_factors_names_from_stage(tmp_path, raw):
    d = copy.deepcopy(raw)
    st = _stage(d, "steepest")
    for key in ("factors", "table", "table_coding", "printed", "chosen_step", "fixed"):
        st.pop(key, None)
    st["from_stage"] = "pbb"
    e = _error(tmp_path, d)
    assert (e.field, e.got) == ("stages[1].from_stage", "pbb") and e.expected == "the id of an earlier stage"


def test_a_misspelt_key_of_a_printed_optimum_or_verification_is_refused(tmp_path, raw):
    d = copy.deepcopy(raw)
    case = _stage(d, "bbd")["optimise"]["cases"][0]
    case["printed_optimum"] = {"A": 0.08, "X": 0.37, "C": 0.64}
    e = _error(tmp_path, d)
    assert e.field == "stages[2].optimise.cases[0].printed_optimum.X" and e.got == "X"
    assert "A, B, C" in e.expected and "stacking_angle" in e.expected
    d = copy.deepcopy(raw)
    _stage(d, "bbd")["optimise"]["cases"][0]["printed_verification"] = {"stacking_angel": 27.62}
    e = _error(tmp_path, d)
    assert e.field == "stages[2].optimise.cases[0].printed_verification.stacking_angel"


def test_a_goal_with_a_value_and_a_target_id_is_refused(tmp_path, raw):
    d = copy.deepcopy(raw)
    case = _stage(d, "bbd")["optimise"]["cases"][0]
    rid = next(iter(case["goals"]))
    case["goals"][rid] = {"goal": "target", "target": "stacking_angle", "value": 40.0}
    e = _error(tmp_path, d)
    assert e.field == f"stages[2].optimise.cases[0].goals.{rid}" and "not both" in e.expected


@pytest.mark.parametrize("cell", ["", "n/a", "NA"])
def test_a_printed_response_left_blank_in_one_run_is_refused(tmp_path, raw, cell):
    # the fit would leave the run out without a word
    res = tmp_path / "res"
    shutil.copytree(ROOT / "resources" / "published" / SOIL, res / "published" / SOIL)
    table = res / "published" / SOIL / "bbd.csv"
    lines = table.read_text().splitlines()
    head = lines[0].split(",")
    col = head.index("stacking_angle")
    row = lines[3].split(",")
    row[col] = cell
    lines[3] = ",".join(row)
    table.write_text("\n".join(lines) + "\n")
    e = _error(tmp_path, copy.deepcopy(raw), res)
    assert str(e.path) == str(table) and e.field == "row 3, column stacking_angle", str(e)


def test_a_misspelt_setup_of_a_test_with_its_own_particle_sizes_is_one_error(tmp_path, raw):
    d = copy.deepcopy(raw)
    entry = next(iter(d["measurements"].values()))
    entry["setup"] = entry["setup"] + "-typo"
    entry.setdefault("set", {})["paper_psd"] = [[0.001, 40.0], [0.0005, 60.0]]
    e = _error(tmp_path, d)
    assert e.field.endswith(".setup") and e.got == entry["setup"], str(e)


def test_a_target_sd_of_zero_is_refused(tmp_path, raw):
    # as in a measured table: an SD of 0 calls the measured value exact
    d = copy.deepcopy(raw)
    tid = next(iter(d["targets"]))
    d["targets"][tid]["sd"] = 0
    e = _error(tmp_path, d)
    assert (e.field, e.got) == (f"targets.{tid}.sd", 0)
