"""Measured values no soil can have, and columns named in another quantity's unit: a negative
moisture content, one wetter than the soil's dry mass where the soil says it is 11.62 % wet, a
fraction of 1 typed among percentages, and a response column whose name gives a unit of
another quantity than its measure's.  Each is refused at load naming the table or the soil
file, the column and what was expected; the neighbouring readings that are real still load."""
import sys
from pathlib import Path

import pandas as pd
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from test_measurements import _edit, _entry, _table, _yaml, cinnamon  # noqa: E402,F401
from test_one_unit_table import _covariate  # noqa: E402

from soilcal.config.load import load_soil  # noqa: E402
from soilcal.config.measurements import conditions  # noqa: E402
from soilcal.errors import InputError  # noqa: E402


def test_a_negative_moisture_content_is_refused_and_an_oven_dry_one_loads(cinnamon):
    with pytest.raises(InputError) as e:
        _covariate(cinnamon, "w", "%", "moisture_content", [-5.0, 10.0, 11.0, 12.0])
    assert "cutting_resistance.csv" in str(e.value.path) and "column w" in e.value.field
    assert "zero or more" in e.value.expected and e.value.got == -5.0
    # 0 % is an oven-dry soil, a real reading
    assert _covariate(cinnamon, "w", "%", "moisture_content", [0.0, 10.0, 11.0, 12.0]) == [0.0, 10.0, 11.0, 12.0]


def test_more_water_than_dry_soil_is_refused_where_the_soil_is_not_that_wet(cinnamon):
    """cinnamon soil is 11.62 % wet (config/soils/cinnamon-soil.yaml): 400 % of its dry mass,
    34 times that, is no reading of it (a peat's, which the soil would have to declare)."""
    with pytest.raises(InputError) as e:
        _covariate(cinnamon, "w", "%", "moisture_content", [400.0, 10.0, 11.0, 12.0])
    assert e.value.field == "column w" and "at most 100 %" in e.value.expected and "11.62" in e.value.expected
    # a soil that says it is that wet (a peat at 300 %) loads the same cells
    _edit(cinnamon, "cinnamon-soil", lambda d: d["properties"].update(moisture_content={"value": 300.0, "unit": "%"}))
    assert _covariate(cinnamon, "w", "%", "moisture_content",
                      [400.0, 250.0, 300.0, 350.0]) == [400.0, 250.0, 300.0, 350.0]


def test_one_fraction_typed_among_percentages_is_refused_naming_it(cinnamon):
    """0.116 beside 11.6 to 12.5 %: x 100 it falls among them (the column's median, 11.8 %, is
    the soil's own, so the median check passes it)."""
    with pytest.raises(InputError) as e:
        _covariate(cinnamon, "w", "%", "moisture_content", [0.116, 11.6, 12.0, 12.5])
    assert e.value.field == "column w" and e.value.got == 0.116 and "100 times below" in e.value.expected


def test_air_dry_tests_beside_wet_ones_load(cinnamon):
    """0.5 % beside 20 to 30 %: 1.6 decades below them, but x 100 (50 %) it falls outside
    their range: a real spread of moisture, not a unit slip."""
    assert _covariate(cinnamon, "w", "%", "moisture_content", [0.5, 20.0, 25.0, 30.0]) == [0.5, 20.0, 25.0, 30.0]


def _value_column(ws, name):
    t = _table(ws, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t).rename(columns={"horizontal_measured_N": name})
    df.to_csv(t, index=False)
    _edit(ws, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(value=name))
    return conditions(load_soil(_yaml(ws, "cinnamon-soil"), ws / "resources"))


@pytest.mark.parametrize("name", ["angle_deg", "draught (mm)", "torque (N m)"])
def test_a_force_column_named_in_a_unit_of_another_quantity_is_refused(cinnamon, name):
    """The response is a force in N (horizontal_force_N); a column whose name gives deg, mm or N m
    is another quantity's (an angle, a length, a torque), or another response's column."""
    with pytest.raises(InputError) as e:
        _value_column(cinnamon, name)
    assert "cinnamon-soil" in str(e.value.path) and e.value.field.endswith(".value") and e.value.got == name
    assert "a unit of another quantity" in e.value.expected


@pytest.mark.parametrize("name", ["horizontal_N", "draught (N)", "horizontal"])
def test_a_force_column_named_in_newtons_or_in_no_unit_loads(cinnamon, name):
    cs = _value_column(cinnamon, name)
    assert [c.responses[0]["measured"] for c in cs][:2] == [321.10, 252.10]  # resources/measurements/cinnamon-soil


def test_a_table_the_soil_file_names_nowhere_is_noted_as_not_read(cinnamon):
    """A campaign's table put beside cutting_resistance.csv and not declared was left out of
    every comparison without a word; a spreadsheet is noted as not read for its format too."""
    folder = cinnamon / "resources/measurements/cinnamon-soil"
    (folder / "draught_2026.csv").write_text("speed,draught_N\n1.0,300\n")
    (folder / "draught_2026.xlsx").write_bytes(b"PK")
    notes = load_soil(_yaml(cinnamon, "cinnamon-soil"), cinnamon / "resources").load_notes
    unread = [n for n in notes if "is named nowhere in the soil file" in n]
    assert len(unread) == 2, notes
    assert any("draught_2026.csv is named nowhere" in n and "measurements.<id>.table" in n for n in unread)
    assert any("draught_2026.xlsx is named nowhere" in n and "as CSV" in n for n in unread)
    # the declared table is not among them
    assert not any("cutting_resistance.csv" in n for n in unread)
