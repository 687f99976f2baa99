"""A ``case`` or ``setup`` map key quoted in the YAML is the number it writes.

The guangxi cohesive soil's compression table holds the moistures 5, 10 and 15 (read as
numbers); its case map is written with quoted keys.  A key quoted with its decimals
(``"5.0"``, as a spreadsheet prints it) is the same moisture: before, the table's first row was
refused with 'expected a value mapped under ....case (5.0, 10.0, 15.0), got 5.0'."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
import yaml

from soilcal.config.load import load_soil, read_yaml
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]
SOIL = "guangxi-cohesive"


@pytest.fixture(scope="module")
def parsed():
    return read_yaml(ROOT / f"config/soils/{SOIL}.yaml")


def _load(tmp_path, data):
    p = tmp_path / f"{SOIL}.yaml"
    p.write_text(yaml.safe_dump(data, sort_keys=False))
    return load_soil(p, ROOT / "resources")


def test_quoted_keys_with_decimals_map_the_numeric_cells(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    cv = d["measurements"]["compression"]["covariates"]["moisture_content"]
    cv["case"] = {"5.0": "mc05", "10.00": "mc10", "15.0": "mc15"}
    soil = _load(tmp_path, d)
    from soilcal.config.measurements import conditions

    got = {c.quantities["moisture_content"]: c.case for c in conditions(soil)}
    assert got == {5.0: "mc05", 10.0: "mc10", 15.0: "mc15"}


def test_two_keys_of_one_value_are_refused(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    cv = d["measurements"]["compression"]["covariates"]["moisture_content"]
    cv["case"] = {"5": "mc05", "5.0": "mc10", "10": "mc10", "15": "mc15"}
    with pytest.raises(InputError) as ei:
        _load(tmp_path, d)
    e = ei.value
    assert e.field == "measurements.compression.covariates.moisture_content.case.5.0" and e.got == "5.0"
    assert "'5' is the same value" in e.expected
