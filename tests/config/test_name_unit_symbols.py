"""A unit written as a symbol (%, °) inside a column's name, and a covariate's name in a unit of
its quantity other than the declared one.  The truth of each case is how the name is written:
``strain_%_total`` holds percent, ``speed (m/min)`` metres per minute."""
import sys
from pathlib import Path

import pandas as pd
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from test_measurements import _edit, _entry, _table, _yaml, cinnamon, guangxi  # noqa: E402,F401

from soilcal.config.load import load_soil  # noqa: E402
from soilcal.config.measurements import conditions, name_units  # noqa: E402
from soilcal.errors import InputError  # noqa: E402


@pytest.mark.parametrize("col, unit", [("strain_%_total", "%"), ("moisture_%_db", "%"), ("Moisture % w/w", "%"),
                                       ("MC % db", "%"), ("angle_°_paper", "deg"), ("strain_%", "%")])
def test_a_unit_symbol_inside_a_name_is_its_unit(col, unit):
    """The one-letter rule (a letter inside a name is an id unless a statistic follows) took
    % and ° too: strain_%_total, angle_°_paper and moisture_%_db gave no unit."""
    assert name_units(col) == [unit]


def _strain(ws, col, unit):
    t = _table(ws, "guangxi-cohesive", "compression.csv")
    df = pd.read_csv(t)
    df[col] = [4.0, 5.5, 7.0]
    df.to_csv(t, index=False)
    _edit(ws, "guangxi-cohesive", lambda d: d["measurements"]["compression"].update(responses=[
        {"measure": "recovered_strain", "value": col, "unit": unit}]))
    return [x["measured"] for c in conditions(load_soil(_yaml(ws, "guangxi-cohesive"), ws / "resources"))
            if c.measurement == "compression" for x in c.responses if x.get("measure") == "recovered_strain"]


def test_a_percent_strain_column_is_refused_under_a_dimensionless_unit(guangxi):
    """strain_%_total under unit: "-" loaded 4.0 % as a strain of 4 (400 %)."""
    with pytest.raises(InputError) as e:
        _strain(guangxi, "strain_%_total", "-")
    assert "strain_%_total" in str(e.value) and "%" in str(e.value)
    assert _strain(guangxi, "strain_%_total", "%") == pytest.approx([0.04, 0.055, 0.07])


def _speed(ws, col, unit):
    t = _table(ws, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df[col] = [72.0, 72.0, 72.0, 72.0]
    df.to_csv(t, index=False)
    _edit(ws, "cinnamon-soil", lambda d: _entry(d)["covariates"].update(
        {col: {"set": "speed", "quantity": "tool_speed", "unit": unit, **({"scale": 1 / 60} if unit == "m/min" else {})}}))
    return [c.quantities["tool_speed"] for c in conditions(load_soil(_yaml(ws, "cinnamon-soil"), ws / "resources"))]


@pytest.mark.parametrize("col", ["speed (m/min)", "speed (m min-1)", "speed_m_min"])
def test_a_covariate_named_in_m_per_min_is_refused_under_m_per_s(cinnamon, col):
    """speed (m/min) under unit: m/s was read as m/s: 72 m/min, 1.2 m/s, run at 72 m/s (60 times)."""
    with pytest.raises(InputError) as e:
        _speed(cinnamon, col, "m/s")
    assert e.value.field.endswith(f"covariates.{col}.unit") and "m/min" in str(e.value)


def test_a_covariate_in_m_per_min_is_converted(cinnamon):
    assert _speed(cinnamon, "speed (m/min)", "m/min") == pytest.approx([1.2] * 4)


@pytest.mark.parametrize("col", ["rotor (rev/s)", "rotor (r s-1)"])
def test_a_rotor_speed_named_per_second_is_refused_under_r_per_min(col):
    """rotor (rev/s) under unit: r/min was read as r/min, 60 times slow."""
    from soilcal.config.quantities import quantity_factor
    assert name_units(col) == ["r/s"]
    assert quantity_factor("rotor_speed", "r/s") == 60.0 and quantity_factor("rotor_speed", "r/min") == 1.0


def test_a_covariate_named_in_a_unit_of_no_quantity_it_takes_is_refused(cinnamon):
    """A name unit no unit of the declared quantity (a speed column named in s) was ignored."""
    with pytest.raises(InputError) as e:
        _speed(cinnamon, "speed (mm/min)", "m/s")
    assert "mm/min" in str(e.value) and "tool_speed" in str(e.value)


@pytest.mark.parametrize("col, unit", [("Sd_m_mean", ["m"]), ("Sd_m_mean (mm)", ["mm"]), ("Sd_m_mean_mm", ["mm"]),
                                       ("Sd_meas_mean", [])])
def test_a_one_letter_word_before_a_statistic_and_its_renames(col, unit):
    """Sd_m_mean reads m before mean as metres (the README says so); the renames its refusal
    proposes give mm or no unit."""
    assert name_units(col) == unit
