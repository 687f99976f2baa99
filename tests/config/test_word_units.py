"""Unit symbols in a column's name that are words too (in, ft, psi), in any case or spelling,
pandas' duplicate suffix, and the millipascal.  Each number is the unit's definition (the
inch 0.0254 m, the foot 0.3048 m, the pound 0.45359237 kg, the pound-force 0.45359237 kg x
9.80665 m/s^2, the psi a pound-force per square inch)."""
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from test_measurements import cinnamon  # noqa: E402,F401
from test_one_unit_table import _covariate  # noqa: E402

from soilcal.config.measurements import _check_response_column_units, name_units, unit_factor  # noqa: E402
from soilcal.config.quantities import quantity_factor, si_factor  # noqa: E402
from soilcal.errors import InputError  # noqa: E402

LBF = 0.45359237 * 9.80665
PSI = LBF / 0.0254 ** 2


@pytest.mark.parametrize("col, units", [("depth_in.1", ["in"]), ("pressure_psi.1", ["psi"]), ("Depth..in..1", ["in"]),
                                        ("draught_kN.1", ["kN"])])
def test_pandas_duplicate_suffix_is_no_part_of_the_name(col, units):
    """depth_in.1 (pandas' second depth_in) and R's Depth..in..1 gave no unit."""
    assert name_units(col) == units


def test_a_duplicate_inch_column_under_metres_is_refused(cinnamon):
    """depth_in.1 of 4.0 under unit: m loaded as 4 m."""
    with pytest.raises(InputError) as e:
        _covariate(cinnamon, "depth_in.1", "m", "working_depth", [4.0] * 4)
    assert e.value.field.endswith("covariates.depth_in.1.unit")


@pytest.mark.parametrize("col, units", [
    ("ft_id", []), ("plot_ft", []), ("tool_ft_2", []), ("draught_ft_N", ["N"]), ("depth_ft", ["ft"]),
    ("plot_width_ft", ["ft"]), ("moisture_in", []), ("w_in", []), ("gain_in", []), ("N_in", []), ("depth.in", []),
    ("depth (in) [mm]", ["mm"]), ("depth (in)", ["in"]), ("Layer.depth..in.", ["in"]),
    ("PSI (kPa)", ["kPa"]), ("suction PSI", []), ("cone_index_PSI", ["psi"]), ("pressure_psi", ["psi"]),
    ("stress_psi_mean", ["psi"]), ("depth_in_sd", ["in"]), ("psi_mean", []), ("gain_in_max", [])])
def test_units_that_are_words_are_units_only_behind_a_word_of_their_kind(col, units):
    """ft anywhere (ft_id, tool_ft_2) gave ft; draught_ft_N was refused as two lengths... in as
    a last word (gain_in, N_in) gave inches; PSI in capitals escaped the guard."""
    assert name_units(col) == units


def test_one_case_rule_for_properties_units_and_names():
    """si_factor("PSI", "Pa") was None where unit_factor read it as psi."""
    assert si_factor("PSI", "Pa") == pytest.approx(PSI, rel=1e-11)
    assert unit_factor("PSI", "stress_10_kpa") == pytest.approx(PSI / 1e3)
    assert si_factor("MPA", "Pa") == 1e6 and unit_factor("MPA", "stress_10_kpa") == pytest.approx(1e3)
    assert si_factor("KN/M2", "Pa") == 1e3 and unit_factor("KN", "horizontal_force_N") == 1e3
    assert unit_factor("mN", "horizontal_force_N") == pytest.approx(1e-3)


def test_a_stress_in_millipascals_is_refused_asking_for_mpa():
    """unit: mPa for a stress read 5 as 5e-3 Pa, 1e9 below a MPa: no soil's stress."""
    assert unit_factor("mPa", "stress_10_kpa") is None and si_factor("mPa", "Pa") is None
    r = {"measure": "stress_10_kpa", "unit": "kPa", "value": "cone index (mPa)"}
    with pytest.raises(InputError) as e:
        _check_response_column_units(Path("s.yaml"), "responses[0]", r, Path("t.csv"))
    assert "did you mean MPa" in e.value.expected and e.value.got == "cone index (mPa)"
    assert name_units("viscosity_mPa_s") == ["mPa s"]


@pytest.mark.parametrize("col, unit", [("draught (lb)", "lbf"), ("draught_lbs", "lbf"), ("depth (inches)", "in"),
                                       ("depth_inch", "in"), ("depth (in.)", "in"), ("depth_feet", "ft"),
                                       ("density (pcf)", "lb/ft^3")])
def test_imperial_spellings_of_us_papers(col, unit):
    assert name_units(col) == [unit]


def test_imperial_spellings_convert_by_their_definitions():
    assert unit_factor("lb", "horizontal_force_N") == pytest.approx(LBF)
    assert unit_factor("lbs", "horizontal_force_N") == pytest.approx(LBF)
    assert quantity_factor("working_depth", "inches") == pytest.approx(0.0254)
    assert quantity_factor("bulk_density", "pcf") == pytest.approx(0.45359237 / 0.3048 ** 3)
