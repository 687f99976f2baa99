"""A declared ``unit:`` is read only where its whole text is one unit, and a column's name gives
a unit only where its words are one: an id (r1, s1, t2) next to a unit word, a multiplier, a
number or another word in a ``unit:`` text is never read past.  The truth of each case is how
the text is written: "x1000 N" is a thousand newtons per cell, never a newton."""
import sys
from pathlib import Path

import pandas as pd
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from test_measurements import _edit, _entry, _table, _yaml, cinnamon  # noqa: E402,F401

from soilcal.config.load import load_soil  # noqa: E402
from soilcal.config.measurements import conditions, name_units, unit_factor  # noqa: E402
from soilcal.config.quantities import quantity_factor, soil_moisture  # noqa: E402
from soilcal.errors import InputError  # noqa: E402


@pytest.mark.parametrize("unit", ["x1000 N", "10^3 N", "1000 N", "1e3 N", "N, x1000", "N x 1000", "0.1 kN",
                                  "kN x10^-3", "N per 3 tines", "N, mean of 3"])
def test_a_force_unit_with_a_multiplier_or_words_is_no_unit(unit):
    """These loaded as N (factor 1) or kN, the one unit word picked out of the text: "x1000 N"
    cells a thousand times small, "0.1 kN" ten times large."""
    assert unit_factor(unit, "horizontal_force_N") is None


@pytest.mark.parametrize("unit, factor", [("N", 1.0), ("kN", 1e3), ("KN", 1e3), ("kn", 1e3), ("mN", 1e-3)])
def test_a_force_unit_written_alone_is_read(unit, factor):
    assert unit_factor(unit, "horizontal_force_N") == factor


@pytest.mark.parametrize("q, unit", [("working_depth", "0.1 m s-1"), ("working_depth", "m s-1 / 10"),
                                     ("working_depth", "2 m"), ("working_depth", "10^-2 m"),
                                     ("working_depth", "mm x 10"), ("working_depth", "10 cm"),
                                     ("working_depth", "m s-1"), ("tool_speed", "0.1 m s-1")])
def test_a_covariate_unit_with_a_number_or_another_quantity_is_no_unit(q, unit):
    assert quantity_factor(q, unit) is None


@pytest.mark.parametrize("unit", ["vol %", "% vol", "% v/v", "% by volume", "% wet basis", "mass %", "m3 m-3",
                                  "cm3 cm-3"])
def test_a_volumetric_or_wet_basis_moisture_is_refused(unit):
    """These loaded as gravimetric % of the dry mass (factor 1): a volumetric 25 % of a soil of
    bulk density 1.3 g/cm^3 is 19 % gravimetric, read as 25 %."""
    assert quantity_factor("moisture_content", unit) is None
    with pytest.raises(InputError) as e:
        soil_moisture("soil.yaml", {"properties": {"moisture_content": {"value": 25, "unit": unit}}})
    assert e.value.field == "properties.moisture_content.unit" and "gravimetric" in str(e.value)


@pytest.mark.parametrize("unit, factor", [("%", 1.0), ("% dry basis", 1.0), ("% of dry mass", 1.0),
                                          ("g g-1", 100.0), ("kg/kg", 100.0)])
def test_a_gravimetric_moisture_unit_is_read(unit, factor):
    assert quantity_factor("moisture_content", unit) == factor


@pytest.mark.parametrize("col, unit", [("draught_kN_r1", "kN"), ("draught_kN_s1", "kN"), ("draught_t1_kN", "kN"),
                                       ("draught_kN_t2", "kN"), ("depth_cm_r1", "cm"), ("depth_mm_s1", "mm"),
                                       ("speed_km_h_r1", "km/h"), ("depth_cm_r2", "cm"), ("depth_mm_h1", "mm")])
def test_an_id_next_to_a_unit_word_is_no_power(col, unit):
    """r1, s1, t1, t2 after or before a unit word were read as a symbol to the power 1 or 2:
    draught_kN_r1 gave no unit (a kN column loaded under unit: N, 1000 times small) and
    depth_mm_s1 gave mm/s."""
    assert name_units(col) == [unit]


@pytest.mark.parametrize("col, unit", [("draught_N_2", []), ("run_N_2", []), ("draught_N_A", []),
                                       ("draught_N_plate", []), ("tool_m_depth", []), ("run_m_3", []),
                                       ("F_N_mean", ["N"]), ("draught_N_sd", ["N"]), ("Sd_m_mm", ["mm"]),
                                       ("horizontal_measured_N", ["N"]), ("Sd_m (mm)", ["mm"])])
def test_a_one_letter_word_inside_a_name_is_a_unit_only_before_a_statistic(col, unit):
    """draught_N_2 under unit: kN was refused, its N taken as newtons though N_2 numbers a run."""
    assert name_units(col) == unit


def _response(ws, col, unit):
    t = _table(ws, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t).rename(columns={"horizontal_measured_N": col})
    df[col] = [0.3211, 0.2521, 0.1545, 0.3048]
    df.to_csv(t, index=False)
    _edit(ws, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(value=col, unit=unit))
    return conditions(load_soil(_yaml(ws, "cinnamon-soil"), ws / "resources"))


@pytest.mark.parametrize("col", ["draught_kN_r1", "draught_t1_kN", "draught_kN_per_m", "draught (N m-1)"])
def test_a_kn_or_per_width_column_is_refused_under_unit_n(cinnamon, col):
    """draught_kN_r1 and draught_kN_per_m under unit: N loaded 0.3211 kN as 0.3211 N."""
    with pytest.raises(InputError) as e:
        _response(cinnamon, col, "N")
    assert "responses[0]" in e.value.field


def test_a_numbered_n_column_loads_under_unit_kn(cinnamon):
    conds = _response(cinnamon, "draught_N_2", "kN")
    assert [c.responses[0]["measured"] for c in conds] == pytest.approx([321.1, 252.1, 154.5, 304.8])
