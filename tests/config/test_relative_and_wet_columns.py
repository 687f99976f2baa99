"""Columns whose numbers are in another form than declared.  A moisture column declared as a
fraction of 1 holding 1, 2, 3, 4 beside a soil of 11.62 % is percentages (it loaded as 100 to
400 %, 9 to 34 times the soil's own); a response's SD column named as a coefficient of
variation (CV, %, pct, rsd) holds a relative SD and was read as an SD in N."""
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


@pytest.mark.parametrize("vals", [[1.0, 2.0, 3.0, 4.0], [0.5, 1.0, 2.0, 3.0]])
def test_percentages_declared_as_a_fraction_beside_a_dry_soil_are_refused(cinnamon, vals):
    """cinnamon soil is 11.62 % wet (config/soils/cinnamon-soil.yaml): 100 % or more of its dry
    mass is no reading of it; the message names the column and says to declare %."""
    with pytest.raises(InputError) as e:
        _covariate(cinnamon, "w", "-", "moisture_content", vals)
    assert "cutting_resistance.csv" in str(e.value.path) and e.value.field == "column w"
    assert "11.62" in e.value.expected and 'declare unit: "%" under covariates.w' in e.value.expected
    # the same cells declared as % load as they are
    assert _covariate(cinnamon, "w", "%", "moisture_content", [10.0, 11.0, 12.0, 13.0]) == [10.0, 11.0, 12.0, 13.0]


def test_percentages_under_a_fraction_near_a_dry_soil_blame_the_column(cinnamon):
    """Cells 0.3 to 0.8 under unit - beside a soil of 0.5 % are percentages (30 to 80 % would be
    100 times the soil's): the hint named the soil's property, not the column."""
    _edit(cinnamon, "cinnamon-soil", lambda d: d["properties"].update(moisture_content={"value": 0.5, "unit": "%"}))
    with pytest.raises(InputError) as e:
        _covariate(cinnamon, "w", "-", "moisture_content", [0.3, 0.5, 0.6, 0.8])
    assert "percentages under unit -" in e.value.expected
    assert "soil's properties.moisture_content a fraction" not in e.value.expected


def _sd_column(ws, col):
    t = _table(ws, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df[col] = [5.0] * len(df)
    df.to_csv(t, index=False)
    _edit(ws, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(sd=col))
    return conditions(load_soil(_yaml(ws, "cinnamon-soil"), ws / "resources"))


@pytest.mark.parametrize("col", ["horizontal (N) CV (%)", "draught_cv_pct_N", "draught_sd (% of mean) N", "CV%",
                                 "horizontal_SD_percent", "Draught.CV....", "draught_rsd", "draught_CV",
                                 "horizontal CV (%)", "horizontal_sd_%", "horizontal_cv_pct"])
def test_a_coefficient_of_variation_is_no_sd_in_newtons(cinnamon, col):
    """Each loaded as an SD of 5 N (a CV of 5 % of the 321.1 N mean is an SD of 16.1 N); a
    name that gives N too does not make a CV one."""
    with pytest.raises(InputError) as e:
        _sd_column(cinnamon, col)
    assert e.value.field.endswith(".sd") and e.value.got == col and "SD = CV / 100 x mean" in e.value.expected


@pytest.mark.parametrize("col", ["sd (N)", "horizontal_sd_N", "Draught.SD..N."])
def test_an_sd_in_newtons_still_loads(cinnamon, col):
    cs = _sd_column(cinnamon, col)
    assert cs and all(c.responses[0]["measured_sd"] == 5.0 for c in cs)
