"""Units read by the one table of unit symbols (quantities.UNIT_SYMBOLS) and its one parser
(quantities.unit_powers).  The truth of each number is the unit's definition: a millipascal
is 1e-3 Pa; the inch 0.0254 m, the foot 0.3048 m, the pound 0.45359237 kg and the
pound-force 0.45359237 kg x 9.80665 m/s^2 (exact by definition); a mile per hour
1609.344 m / 3600 s; a rotational frequency in s-1 is in revolutions per second (ISO 80000-3)."""
import sys
from pathlib import Path

import pandas as pd
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from test_measurements import _edit, _entry, _table, _yaml, cinnamon  # noqa: E402,F401

from soilcal.config.load import load_soil  # noqa: E402
from soilcal.config.measurements import conditions, name_units, unit_factor, whole_unit  # noqa: E402
from soilcal.config.quantities import quantity_factor, si_factor  # noqa: E402
from soilcal.errors import InputError  # noqa: E402

LBF = 0.45359237 * 9.80665
PSI = LBF / 0.0254 ** 2


def test_a_millipascal_is_no_megapascal():
    """mPa was read as MPa: a stress of 5 mPa loaded as 5 MPa, 1e9 times too large.  A
    millipascal is no soil's stress either: refused (a viscosity's mPa s is no stress)."""
    assert whole_unit("mPa") == "mPa" and name_units("stress (mPa)") == ["mPa"]
    assert unit_factor("mPa", "stress_10_kpa") is None and si_factor("mPa", "Pa") is None
    assert name_units("viscosity_mPa_s") == ["mPa s"] and unit_factor("mPa s", "stress_10_kpa") is None
    # MPa in capitals or in one case, as printed tables write it, stays MPa
    for u in ("MPa", "mpa", "MPA", "Mpa"):
        assert si_factor(u, "Pa") == 1e6 and unit_factor(u, "stress_10_kpa") == pytest.approx(1e3)


@pytest.mark.parametrize("col", ["rotor (s-1)", "rotor_s-1", "rotor (1/s)", "rotor (s⁻¹)"])
def test_a_rotation_rate_per_second_is_in_revolutions(col):
    """rotor (s-1) gave 1/s, refused as no unit of rotor_speed; (1/s) gave no unit at all."""
    assert name_units(col) == ["r/s"]
    assert quantity_factor("rotor_speed", "s-1") == 60.0 and quantity_factor("rotor_speed", "1/min") == 1.0


def test_imperial_units_convert_by_their_definitions():
    assert quantity_factor("working_depth", "in") == pytest.approx(0.0254)
    assert quantity_factor("layer_depth", "ft") == pytest.approx(0.3048)
    assert quantity_factor("tool_speed", "mph") == pytest.approx(1609.344 / 3600)
    assert quantity_factor("tool_speed", "ft/s") == pytest.approx(0.3048)
    assert quantity_factor("bulk_density", "lb/ft3") == pytest.approx(0.45359237 / 0.3048 ** 3)
    assert unit_factor("lbf", "horizontal_force_N") == pytest.approx(LBF)
    assert unit_factor("in", "flatness_mm") == pytest.approx(25.4)
    assert unit_factor("psi", "stress_10_kpa") == pytest.approx(PSI / 1e3)
    assert si_factor("psi", "Pa") == pytest.approx(PSI, rel=1e-11)
    assert si_factor("lb/ft^3", "kg/m^3") == pytest.approx(0.45359237 / 0.3048 ** 3, rel=1e-11)
    assert si_factor("lbf/in^2", "Pa") == pytest.approx(PSI, rel=1e-11)


@pytest.mark.parametrize("col, units", [("depth_in", ["in"]), ("depth (in)", ["in"]), ("speed (mph)", ["mph"]),
                                        ("draught_lbf", ["lbf"]), ("pressure_psi", ["psi"]), ("depth_ft", ["ft"]),
                                        ("depth in mm", ["mm"]), ("psi (kPa)", ["kPa"]), ("draught_kN_in", ["kN"])])
def test_imperial_units_in_column_names(col, units):
    """in and psi are words too: a unit in brackets or as the name's last word, where the
    name gives no other unit."""
    assert name_units(col) == units


def _covariate(ws, col, unit, quantity, vals):
    t = _table(ws, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df[col] = list(vals)
    df.to_csv(t, index=False)
    _edit(ws, "cinnamon-soil", lambda d: _entry(d)["covariates"].update(
        {col: {"ignore": True, "quantity": quantity, "unit": unit}}))
    return [c.quantities[quantity] for c in conditions(load_soil(_yaml(ws, "cinnamon-soil"), ws / "resources"))]


def test_a_depth_named_in_inches_is_refused_in_metres_and_converted_in_inches(cinnamon):
    """depth_in under unit: m loaded 4 inches as 4 m without a word."""
    with pytest.raises(InputError) as e:
        _covariate(cinnamon, "depth_in", "m", "working_depth", [4.0] * 4)
    assert e.value.field.endswith("covariates.depth_in.unit") and "in" in e.value.expected
    assert _covariate(cinnamon, "depth_in", "in", "working_depth", [4.0] * 4) == pytest.approx([0.1016] * 4)


def test_a_moisture_fraction_above_one_loads_and_one_above_five_is_refused_clearly(cinnamon):
    """A peat's 1.5 g/g (150 % of the dry mass) was refused as "1.5 reads as a percentage";
    it loads where the soil says it is that wet.  40 g/g (4000 %) is past any soil's (500 %)
    and is refused saying what it would be."""
    _edit(cinnamon, "cinnamon-soil", lambda d: d["properties"].update(
        moisture_content={"value": 120.0, "unit": "%"}))
    assert _covariate(cinnamon, "w (g/g)", "g/g", "moisture_content",
                      [1.2, 0.9, 1.5, 1.1]) == pytest.approx([120.0, 90.0, 150.0, 110.0])
    with pytest.raises(InputError) as e:
        _covariate(cinnamon, "w (g/g)", "g/g", "moisture_content", [20, 30, 15, 40])
    assert "cutting_resistance.csv" in str(e.value.path) and e.value.field == "column w (g/g)"
    assert "4000 %" in e.value.expected and "500 %" in e.value.expected and 'unit: "%"' in e.value.expected
