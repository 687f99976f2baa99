"""A ``case`` or ``setup`` map key quoted in the YAML is the number it writes.

The guangxi cohesive soil's compression table holds the moistures 5, 10 and 15 (read as
numbers); its case map is written with quoted keys.  A key quoted with its decimals
(``"5.0"``, as a spreadsheet prints it) is the same moisture: before, the table's first row was
refused with 'expected a value mapped under ....case (5.0, 10.0, 15.0), got 5.0'."""

from __future__ import annotations

import copy

import pytest
import yaml

from soil_copies import ROOT, load_copy, read_shipped
from soilcal.config.load import load_soil, read_yaml
from soilcal.errors import InputError

SOIL = "guangxi-cohesive"


@pytest.fixture(scope="module")
def parsed():
    return read_shipped(SOIL)


def test_quoted_keys_with_decimals_map_the_numeric_cells(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    cv = d["measurements"]["compression"]["covariates"]["moisture_content"]
    cv["case"] = {"5.0": "mc05", "10.00": "mc10", "15.0": "mc15"}
    soil = load_copy(tmp_path, SOIL, d)
    from soilcal.config.measurements import conditions

    got = {c.quantities["moisture_content"]: c.case for c in conditions(soil)}
    assert got == {5.0: "mc05", 10.0: "mc10", 15.0: "mc15"}


def test_two_keys_of_one_value_are_refused(tmp_path, parsed):
    d = copy.deepcopy(parsed)
    cv = d["measurements"]["compression"]["covariates"]["moisture_content"]
    cv["case"] = {"5": "mc05", "5.0": "mc10", "10": "mc10", "15": "mc15"}
    with pytest.raises(InputError) as ei:
        load_copy(tmp_path, SOIL, d)
    e = ei.value
    assert e.field == "measurements.compression.covariates.moisture_content.case.5.0" and e.got == "5.0"
    assert "'5' is the same value" in e.expected


# A label column's text is the label as written: tool ids "007" and "7" are two tools (the
# cinnamon soil's cutting-resistance table, its directrix column a tool label).

def _cinnamon(tmp_path, mapping, cells=("007", "7", "bionic", "line"), quantity="tool"):
    import shutil

    d = read_yaml(ROOT / "config/soils/cinnamon-soil.yaml")
    cv = d["measurements"]["cutting_resistance"]["covariates"]["directrix"]
    assert cv.get("quantity") == "tool"
    cv["setup"] = mapping
    if quantity is None:
        del cv["quantity"]
    res = tmp_path / "resources"  # the shipped resources, the cinnamon soil's tables copied
    (res / "measurements").mkdir(parents=True)
    for f in (ROOT / "resources").iterdir():
        if f.name != "measurements":
            (res / f.name).symlink_to(f)
    for f in (ROOT / "resources/measurements").iterdir():
        if f.name != "cinnamon-soil":
            (res / "measurements" / f.name).symlink_to(f)
    shutil.copytree(ROOT / "resources/measurements/cinnamon-soil", res / "measurements/cinnamon-soil")
    table = res / "measurements/cinnamon-soil/cutting_resistance.csv"
    rows = table.read_text().splitlines()
    assert rows[1].startswith("1,arc,") and rows[2].startswith("2,parabola,")
    for i, (was, cell) in enumerate(zip(("arc", "parabola", "bionic", "line"), cells), 1):
        assert f",{was}," in rows[i]
        rows[i] = rows[i].replace(f",{was},", f",{cell},")
    table.write_text("\n".join(rows) + "\n")
    p = tmp_path / "cinnamon-soil.yaml"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    return load_soil(p, res)


def test_label_keys_that_read_as_one_number_are_two_labels(tmp_path):
    from soilcal.config.measurements import conditions

    soil = _cinnamon(tmp_path, {"007": "plate-arc", "7": "plate-parabola", "bionic": "plate-bionic",
                                "line": "plate-line"})
    got = {c.row: c.setup for c in conditions(soil) if c.measurement == "cutting_resistance"}
    # the setups the unchanged table's rows 1 (arc) and 2 (parabola) run
    ref = {c.row: c.setup for c in conditions(load_soil(ROOT / "config/soils/cinnamon-soil.yaml", ROOT / "resources"))
           if c.measurement == "cutting_resistance"}
    assert ref[1] != ref[2]
    assert got[1] == ref[1] and got[2] == ref[2]


def _setups(soil):
    from soilcal.config.measurements import conditions

    return {c.row: c.setup["name"] for c in conditions(soil) if c.measurement == "cutting_resistance"}


PLATES = ("plate-arc", "plate-parabola", "plate-bionic", "plate-line")


@pytest.mark.parametrize("cells", [("007", "7", "8", "9"), ("1.10", "1.1", "2", "3")])
def test_a_label_column_of_numbers_only_keeps_each_label_as_written(tmp_path, cells):
    # every cell a number: parsed as numbers, 007 and 7 (1.10 and 1.1) were one value and
    # row 1 ran the setup mapped under the other label, plate-parabola, without a word
    soil = _cinnamon(tmp_path, dict(zip(cells, PLATES)), cells)
    assert _setups(soil) == dict(zip((1, 2, 3, 4), PLATES))


def test_a_label_cell_is_not_a_key_that_reads_as_its_number(tmp_path):
    # no quantity: cell 1 and the quoted key "1.0" are two labels; the refusal says the
    # comparison is of text and how to compare numbers instead
    with pytest.raises(InputError) as ei:
        _cinnamon(tmp_path, {"1.0": PLATES[0], "2.0": PLATES[1], "3.0": PLATES[2], "4.0": PLATES[3]},
                  ("1", "2", "3", "4"), quantity=None)
    e = ei.value
    assert e.field == "row 1, column directrix" and e.got == "1"
    assert "'1.0', '2.0'" in e.expected and "as text" in e.expected and "numeric quantity" in e.expected
    # a cell 1.000004 is not the label 1 (printed to 6 digits, it read "1" and took its key)
    with pytest.raises(InputError) as ei:
        _cinnamon(tmp_path / "b", {1: PLATES[0], 2: PLATES[1], 3: PLATES[2], 4: PLATES[3]},
                  ("1.000004", "2", "3", "4"), quantity=None)
    assert ei.value.field == "row 1, column directrix" and ei.value.got == "1.000004"
    # unquoted whole-number keys are the labels the cells write
    soil = _cinnamon(tmp_path / "c", {1: PLATES[0], 2: PLATES[1], 3: PLATES[2], 4: PLATES[3]},
                     ("1", "2", "3", "4"), quantity=None)
    assert _setups(soil) == dict(zip((1, 2, 3, 4), PLATES))


def test_a_label_left_out_of_the_map_is_refused_not_read_as_another(tmp_path):
    with pytest.raises(InputError) as ei:
        _cinnamon(tmp_path, {"007": "plate-arc", "bionic": "plate-bionic", "line": "plate-line"})
    assert "cutting_resistance.csv" in str(ei.value.path) and "directrix" in ei.value.field


def test_unquoted_keys_of_one_number_are_refused_by_the_reader(tmp_path):
    # 5 and 5.0 are one Python key: the later entry would replace the first without a word
    from soilcal.config.load import read_yaml

    p = tmp_path / "s.yaml"
    p.write_text("case:\n  5: mc05\n  5.0: mc10\n")
    with pytest.raises(InputError) as ei:
        read_yaml(p)
    assert ei.value.field == "line 3" and "first given on line 2, as '5'" in ei.value.expected
    # a quoted "5" is text, another key (a label column's "5"), read as written
    p.write_text("case:\n  '5': mc05\n  5: mc10\n")
    assert read_yaml(p) == {"case": {"5": "mc05", 5: "mc10"}}


def _guangxi_row1_moisture(tmp_path, cell):
    import shutil

    res = tmp_path / "resources"  # the shipped resources, the guangxi soil's tables copied
    (res / "measurements").mkdir(parents=True)
    for f in (ROOT / "resources").iterdir():
        if f.name != "measurements":
            (res / f.name).symlink_to(f)
    for f in (ROOT / "resources/measurements").iterdir():
        if f.name != SOIL:
            (res / "measurements" / f.name).symlink_to(f)
    shutil.copytree(ROOT / f"resources/measurements/{SOIL}", res / f"measurements/{SOIL}")
    table = res / f"measurements/{SOIL}/compression.csv"
    rows = table.read_text().splitlines()
    i = rows[0].split(",").index("moisture_content")
    r = rows[1].split(",")
    assert float(r[i]) == 5
    r[i] = cell
    rows[1] = ",".join(r)
    table.write_text("\n".join(rows) + "\n")
    p = tmp_path / f"{SOIL}.yaml"
    p.write_text(yaml.safe_dump(read_yaml(ROOT / f"config/soils/{SOIL}.yaml"), sort_keys=False))
    return load_soil(p, res)


def test_a_cell_near_a_numeric_key_is_not_that_key(tmp_path):
    # 5.000004 % is not the 5 % the case mc05 was calibrated at (relative 8e-7, beyond the 1e-9
    # a moisture is compared with); printed to 6 digits it read "5" and took the case
    with pytest.raises(InputError) as ei:
        _guangxi_row1_moisture(tmp_path, "5.000004")
    assert ei.value.field == "row 1, column moisture_content" and ei.value.got == 5.000004


def test_a_cell_that_is_the_key_written_longer_is_that_key(tmp_path):
    from soilcal.config.measurements import conditions

    soil = _guangxi_row1_moisture(tmp_path, "5.0000000001")  # relative 2e-11
    (c,) = [c for c in conditions(soil) if c.measurement == "compression" and c.row == 1]
    assert c.case == "mc05"
