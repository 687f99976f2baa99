"""The physical quantity of a measured table's covariate (``quantity``/``unit`` in a soil's
``measurements`` block): conversion to the SI unit of QUANTITIES, and each bad declaration or
cell refused with the field (or the table row and column) named."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from soilcal.config.load import load_soil
from soilcal.config.measurements import QUANTITIES, conditions
from test_measurements import _edit, _entry, _fails, _table, _yaml, black, cinnamon  # noqa: F401 (fixtures)

CR = "measurements.cutting_resistance.covariates"
SF = "measurements.surface_flatness.covariates"



def _bare(d):
    """Strip every quantity/unit declaration from the soil, so each test starts from none
    whatever the shipped file declares."""
    for entry in (d.get("measurements") or {}).values():
        for cv in (entry.get("covariates") or {}).values():
            cv.pop("quantity", None)
            cv.pop("unit", None)
    return d


def _declare(ws, soil, fn):
    """Edit the soil from a copy without quantity declarations."""
    return _edit(ws, soil, lambda d: fn(_bare(d)))


def _load(ws, soil):
    return conditions(load_soil(_yaml(ws, soil), ws / "resources"))


def _rotor(d):
    return _entry(d, "surface_flatness")["covariates"]["rotor_speed_rpm"]


def _speed_column(ws, cells):
    """A tool-speed column ``speed_kmh`` in the cinnamon table, declared as an ignored covariate
    holding the quantity tool_speed in km/h."""
    t = _table(ws, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["speed_kmh"] = cells
    df.to_csv(t, index=False)
    _declare(ws, "cinnamon-soil",
             lambda d: _entry(d)["covariates"].update(speed_kmh={"ignore": True, "quantity": "tool_speed",
                                                                 "unit": "km/h"}))
    return t


def test_rotor_speed_in_r_per_min(black):
    _declare(black, "black-soil", lambda d: _rotor(d).update(quantity="rotor_speed", unit="r/min"))
    flat = [c for c in _load(black, "black-soil") if c.measurement == "surface_flatness"]
    assert [c.quantities for c in flat] == [{"rotor_speed": float(n)} for n in (150, 200, 250, 300, 350)]
    assert all(c.quantity_columns == {"rotor_speed_rpm": "rotor_speed"} for c in flat)
    assert flat[0].covariates == {"rotor_speed_rpm": 150.0}
    assert flat[0].setup["name"] == "rpm-150"  # the setup map still chooses the setup
    # the other entry of the soil declares no quantity
    power = [c for c in _load(black, "black-soil") if c.measurement == "tillage_power"]
    assert power and all(c.quantities == {} and c.quantity_columns == {} for c in power)


def test_rotor_speed_in_rad_per_s(black):
    # a column whose name gives no unit (rotor_speed_rpm declared rad/s is refused: the name says rpm)
    t = _table(black, "black-soil", "surface_flatness.csv")
    pd.read_csv(t).rename(columns={"rotor_speed_rpm": "rotor_speed"}).to_csv(t, index=False)

    def edit(d):
        cv = _entry(d, "surface_flatness")["covariates"]
        cv["rotor_speed"] = {**cv.pop("rotor_speed_rpm"), "quantity": "rotor_speed", "unit": "rad/s"}
    _declare(black, "black-soil", edit)
    flat = [c for c in _load(black, "black-soil") if c.measurement == "surface_flatness"]
    # 150 rad/s = 150 * 60 / (2 pi) r/min = 1432.39 r/min
    assert flat[0].quantities["rotor_speed"] == pytest.approx(150 * 60 / (2 * math.pi))


@pytest.mark.parametrize("col, cells, wrong, right, si", [
    ("speed (m s-1)", [0.16, 1.0, 2.0, 0.5], "km/h", "m/s", [0.16, 1.0, 2.0, 0.5]),
    ("speed [km.h-1]", [0.576, 3.6, 7.2, 1.8], "m/s", "km/h", [0.16, 1.0, 2.0, 0.5]),
    ("density (g cm-3)", [1.3, 1.35, 1.4, 1.45], "kg/m^3", "g/cm^3", [1300, 1350, 1400, 1450]),
    ("density (Mg m-3)", [1.3, 1.35, 1.4, 1.45], "kg/m^3", "t/m^3", [1300, 1350, 1400, 1450])])
def test_a_covariate_named_in_an_si_compound_unit(cinnamon, col, cells, wrong, right, si):
    """speed (m s-1) declared unit: km/h loaded 1 m/s as 1 km/h (0.278 m/s) without a word: the
    name's m s-1 was read as m, of no speed, and g cm-3 as no unit.  Now the name's unit is
    compared with the declared one: refused naming it; declared as the name says, the cells
    load in SI (1.3 g/cm^3 = 1300 kg/m^3, 3.6 km/h = 1 m/s)."""
    q = "bulk_density" if "density" in col else "tool_speed"
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df[col] = cells
    df.to_csv(t, index=False)
    p = _declare(cinnamon, "cinnamon-soil", lambda d: _entry(d)["covariates"].update(
        {col: {"ignore": True, "quantity": q, "unit": wrong}}))
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: {CR}.{col}.unit")
    assert f"says are in {right}" in msg and f"got '{wrong}'" in msg
    _declare(cinnamon, "cinnamon-soil", lambda d: _entry(d)["covariates"].update(
        {col: {"ignore": True, "quantity": q, "unit": right}}))
    assert [c.quantities[q] for c in _load(cinnamon, "cinnamon-soil")] == pytest.approx(si)


def test_tool_speed_in_km_per_h(cinnamon):
    _speed_column(cinnamon, [0.576, 3.6, 7.2, 1.8])
    conds = _load(cinnamon, "cinnamon-soil")
    # km/h -> m/s: divide by 3.6
    assert [c.quantities["tool_speed"] for c in conds] == pytest.approx([0.16, 1.0, 2.0, 0.5])
    assert [c.covariates["speed_kmh"] for c in conds] == pytest.approx([0.576, 3.6, 7.2, 1.8])
    assert conds[0].label == "directrix=arc"  # an ignored column changes nothing else
    assert QUANTITIES["tool_speed"][0] == "m/s"


@pytest.mark.parametrize("col, q, unit, cells, si", [
    ("speed", "tool_speed", "km h-1", [0.576, 3.6, 7.2, 1.8], [0.16, 1.0, 2.0, 0.5]),
    ("speed", "tool_speed", "m s^-1", [0.16, 1.0, 2.0, 0.5], [0.16, 1.0, 2.0, 0.5]),
    ("bd", "bulk_density", "g cm-3", [1.3, 1.35, 1.4, 1.45], [1300, 1350, 1400, 1450]),
    ("bd", "bulk_density", "Mg m-3", [1.3, 1.35, 1.4, 1.45], [1300, 1350, 1400, 1450]),
    ("w", "moisture_content", "g g-1", [0.11, 0.12, 0.115, 0.1162], [11, 12, 11.5, 11.62])])
def test_a_covariate_s_unit_written_si_style(cinnamon, col, q, unit, cells, si):
    """unit: "km h-1" (or m s^-1, g cm-3, Mg m-3, g g-1) was refused as no unit of the
    quantity though it is km/h; now it is read as that unit (3.6 km/h = 1 m/s, 1.3 g/cm^3 =
    1300 kg/m^3, 0.11 g/g = 11 %)."""
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df[col] = cells
    df.to_csv(t, index=False)
    _declare(cinnamon, "cinnamon-soil", lambda d: _entry(d)["covariates"].update(
        {col: {"ignore": True, "quantity": q, "unit": unit}}))
    assert [c.quantities[q] for c in _load(cinnamon, "cinnamon-soil")] == pytest.approx(si)


def test_moisture_content_as_a_fraction(cinnamon):
    # a moisture column tabled as mass fractions (unit "-"): 0.172 is 17.2 %
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["moisture"] = [0.05, 0.1, 0.172, 0.2]
    df.to_csv(t, index=False)
    _declare(cinnamon, "cinnamon-soil",
             lambda d: _entry(d)["covariates"].update(moisture={"ignore": True, "quantity": "moisture_content",
                                                                "unit": "-"}))
    conds = _load(cinnamon, "cinnamon-soil")
    assert [c.quantities["moisture_content"] for c in conds] == pytest.approx([5.0, 10.0, 17.2, 20.0])


def test_label_quantity_keeps_the_cell_text(cinnamon):
    _declare(cinnamon, "cinnamon-soil", lambda d: _entry(d)["covariates"]["plate"].update(quantity="tool"))
    conds = _load(cinnamon, "cinnamon-soil")
    assert [c.quantities for c in conds] == [{"tool": s} for s in ("1", "2", "3", "4")]
    assert conds[0].quantity_columns == {"plate": "tool"}


def test_label_cells_that_pandas_takes_for_missing_keep_their_text(cinnamon):
    # tools called NA, N/A, null and None: labels, not missing cells; the setup map finds them
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["plate"] = ["NA", "N/A", "null", "None"]
    df.to_csv(t, index=False)
    plates = {"NA": "plate-arc", "N/A": "plate-parabola", "null": "plate-bionic", "None": "plate-line"}

    def edit(d):
        _entry(d)["covariates"]["plate"] = {"setup": plates, "quantity": "tool"}
        _entry(d)["covariates"]["directrix"] = {"ignore": True}

    _declare(cinnamon, "cinnamon-soil", edit)
    conds = _load(cinnamon, "cinnamon-soil")
    assert [c.quantities["tool"] for c in conds] == list(plates)
    assert [c.setup["name"] for c in conds] == list(plates.values())
    # an empty label cell is still missing, and refused naming its row
    df["plate"] = ["NA", "", "null", "None"]
    df.to_csv(t, index=False)
    _fails(cinnamon, "cinnamon-soil", "row 2, column plate")


def test_a_missing_word_in_a_label_column_without_a_map_key_is_missing(cinnamon):
    """R's write.csv writes a missing day NA: days 2024-05-01, NA, 2024-05-02, NA made a day
    called "NA" holding rows 2 and 4.  A cell pandas reads as missing is a label only where the
    column's map has it for a key; here it is missing, refused naming its row, column and how
    to keep such a name."""
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["day"] = ["2024-05-01", "NA", "2024-05-02", "NA"]
    df.to_csv(t, index=False)
    _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["covariates"].update(day={"ignore": True, "quantity": "day"}))
    msg = _fails(cinnamon, "cinnamon-soil", f"{t}: row 2, column day")
    assert "'NA' is read as a missing value" in msg and '"NA": ...' in msg
    # a tool mapped under the quoted key NA stays that tool; the unmapped word beside it is missing
    df["plate"] = ["1", "NA", "2", "nan"]
    df = df.drop(columns="day")
    df.to_csv(t, index=False)

    def edit(d):
        _entry(d)["covariates"].pop("day")
        _entry(d)["covariates"]["plate"] = {"setup": {"1": "plate-arc", "NA": "plate-parabola", "2": "plate-bionic"},
                                            "quantity": "tool"}
        _entry(d)["covariates"]["directrix"] = {"ignore": True}
    _edit(cinnamon, "cinnamon-soil", edit)
    msg = _fails(cinnamon, "cinnamon-soil", f"{t}: row 4, column plate")
    assert "'nan' is read as a missing value" in msg


def test_missing_words_are_pandas_documented_list_not_its_private_module(cinnamon, monkeypatch):
    """The words a label column reads as missing are pandas' documented ``na_values`` default
    (read_csv's docs), held by soilcal: the loader must not import ``pandas._libs.parsers``, a
    private module that may move in any release.  With that module unavailable, Excel's
    ``#N/A`` for a missing day is still read as missing (refused naming row and column)."""
    import sys

    monkeypatch.setitem(sys.modules, "pandas._libs.parsers", None)  # import of it raises ImportError
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["day"] = ["2024-05-01", "#N/A", "2024-05-02", "2024-05-02"]
    df.to_csv(t, index=False)
    _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["covariates"].update(day={"ignore": True, "quantity": "day"}))
    msg = _fails(cinnamon, "cinnamon-soil", f"{t}: row 2, column day")
    assert "'#N/A' is read as a missing value" in msg


# --- bad declarations -------------------------------------------------------------------------


def test_unknown_quantity(black):
    p = _declare(black, "black-soil", lambda d: _rotor(d).update(quantity="spin", unit="r/min"))
    msg = _fails(black, "black-soil", f"{p}: {SF}.rotor_speed_rpm.quantity")
    assert "'spin'" in msg and "rotor_speed" in msg


def test_numeric_quantity_without_unit(black):
    p = _declare(black, "black-soil", lambda d: _rotor(d).update(quantity="rotor_speed"))
    msg = _fails(black, "black-soil", f"{p}: {SF}.rotor_speed_rpm.unit")
    assert "a unit of rotor_speed (r/min" in msg and ", got" not in msg


def test_wrong_unit(black):
    p = _declare(black, "black-soil", lambda d: _rotor(d).update(quantity="rotor_speed", unit="m/s"))
    msg = _fails(black, "black-soil", f"{p}: {SF}.rotor_speed_rpm.unit")
    assert "'m/s'" in msg and "a unit of rotor_speed" in msg


def test_unit_on_a_label_quantity(cinnamon):
    p = _declare(cinnamon, "cinnamon-soil",
              lambda d: _entry(d)["covariates"]["plate"].update(quantity="tool", unit="-"))
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: {CR}.plate.unit")
    assert "tool is a label" in msg


def test_unit_without_quantity(black):
    p = _declare(black, "black-soil", lambda d: _rotor(d).update(unit="r/min"))
    _fails(black, "black-soil", f"{p}: {SF}.rotor_speed_rpm.quantity")


def test_same_quantity_on_two_columns(cinnamon):
    def fn(d):
        covs = _entry(d)["covariates"]
        covs["plate"]["quantity"] = "tool"
        covs["directrix"]["quantity"] = "tool"

    p = _declare(cinnamon, "cinnamon-soil", fn)
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: {CR}")
    assert "tool is declared twice" in msg


def test_non_numeric_cell_of_a_numeric_quantity(cinnamon):
    t = _speed_column(cinnamon, [0.576, 3.6, "fast", 1.8])
    msg = _fails(cinnamon, "cinnamon-soil", f"{t}: row 3, column speed_kmh")
    assert "tool_speed in km/h" in msg and "'fast'" in msg


def test_empty_cell_of_a_quantity(cinnamon):
    t = _speed_column(cinnamon, [0.576, None, 7.2, 1.8])
    msg = _fails(cinnamon, "cinnamon-soil", f"{t}: row 2, column speed_kmh")
    assert "empty" in msg


def test_a_set_column_named_in_another_unit_needs_its_unit(cinnamon):
    """A column speed_kmh that sets the plate's speed (m/s) with no unit and no scale would run
    3.6 km/h as 3.6 m/s: refused, with the declaration it needs; scale 1 says the cells are m/s."""
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["speed_kmh"] = [0.576, 0.576, 0.576, 0.576]
    df.to_csv(t, index=False)
    p = _declare(cinnamon, "cinnamon-soil", lambda d: _entry(d)["covariates"].update(speed_kmh={"set": "speed"}))
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: {CR}.speed_kmh")
    assert "quantity: tool_speed, unit: km/h, scale: 0.2778" in msg
    _declare(cinnamon, "cinnamon-soil",
             lambda d: _entry(d)["covariates"].update(speed_kmh={"set": "speed", "scale": 0.2778}))
    assert [c.setup["speed"] for c in _load(cinnamon, "cinnamon-soil")] == pytest.approx([0.16] * 4, rel=1e-3)


@pytest.mark.parametrize("col", ["speed (km/h)", "speed [km/h]"])
def test_a_set_column_with_a_unit_in_brackets_needs_its_unit(cinnamon, col):
    """A spreadsheet's header "speed (km/h)" on a column that sets the plate's speed (m/s) with
    no unit and no scale ran 0.576 km/h as 0.576 m/s: refused as speed_kmh is; "(m/s)" loads."""
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df[col] = [0.576] * 4
    df.to_csv(t, index=False)
    p = _declare(cinnamon, "cinnamon-soil", lambda d: _entry(d)["covariates"].update({col: {"set": "speed"}}))
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: {CR}.{col}")
    assert "which the column's name says are in km/h" in msg and "scale: 0.2778" in msg
    df = df.rename(columns={col: "speed (m/s)"})
    df["speed (m/s)"] = [0.16] * 4
    df.to_csv(t, index=False)
    _declare(cinnamon, "cinnamon-soil", lambda d: (_entry(d)["covariates"].pop(col),
                                                   _entry(d)["covariates"].update({"speed (m/s)": {"set": "speed"}})))
    assert [c.setup["speed"] for c in _load(cinnamon, "cinnamon-soil")] == [0.16] * 4


@pytest.mark.parametrize("col", ["blade speed (rpm)", "blade speed (RPM)", "blade_speed_RPM", "speed (r/min)"])
def test_a_set_column_named_in_the_key_s_unit_by_another_spelling_loads(black, col):
    """The rotor's rpm is taken in r/min; a header "blade speed (rpm)" names r/min by another
    spelling (factor 1) and sets rpm 150..350 as tabled; it was refused as if rpm were another
    unit ('says are in rpm ... scale: 1')."""
    t = _table(black, "black-soil", "surface_flatness.csv")
    df = pd.read_csv(t)
    df[col] = df["rotor_speed_rpm"]
    df.to_csv(t, index=False)
    _declare(black, "black-soil", lambda d: _entry(d, "surface_flatness")["covariates"].update({col: {"set": "rpm"}}))
    flat = [c for c in _load(black, "black-soil") if c.measurement == "surface_flatness"]
    assert [c.setup["rpm"] for c in flat] == [150.0, 200.0, 250.0, 300.0, 350.0]


@pytest.mark.parametrize("col", ["blade speed (rad/s)", "blade speed (Rad/s)", "blade_speed_RAD_S"])
def test_a_set_column_in_rad_per_s_needs_its_unit_however_written(black, col):
    """rad/s is not r/min (factor 60/2pi = 9.549): "(Rad/s)" loaded 150 rad/s as 150 r/min while
    "(rad/s)" was refused; every spelling is refused alike."""
    t = _table(black, "black-soil", "surface_flatness.csv")
    df = pd.read_csv(t)
    df[col] = df["rotor_speed_rpm"]
    df.to_csv(t, index=False)
    p = _declare(black, "black-soil", lambda d: _entry(d, "surface_flatness")["covariates"].update({col: {"set": "rpm"}}))
    msg = _fails(black, "black-soil", f"{p}: {SF}.{col}")
    assert f"scale: {60 / (2 * math.pi):.4g}" in msg and "rad/s" in msg


@pytest.mark.parametrize("cv", [{"unit": "m/s"}, {"unit": "m/s", "scale": 1}])
def test_a_column_named_in_another_unit_than_its_declared_one_is_refused(cinnamon, cv):
    """"speed (km/h)" declared unit: m/s (scale 1): its 0.576 km/h ran as 0.576 m/s, header and
    declaration contradicting each other; refused naming the unit and the unit the name gives."""
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["speed (km/h)"] = [0.576] * 4
    df.to_csv(t, index=False)
    p = _declare(cinnamon, "cinnamon-soil", lambda d: _entry(d)["covariates"].update(
        {"speed (km/h)": {"set": "speed", "quantity": "tool_speed", **cv}}))
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: {CR}.speed (km/h).unit")
    assert "the column's name says are in km/h" in msg and "got 'm/s'" in msg
    # the name's unit declared, with its factor, it runs 0.576 km/h = 0.16 m/s
    _declare(cinnamon, "cinnamon-soil", lambda d: _entry(d)["covariates"].update(
        {"speed (km/h)": {"set": "speed", "quantity": "tool_speed", "unit": "km/h", "scale": 1 / 3.6}}))
    assert [c.setup["speed"] for c in _load(cinnamon, "cinnamon-soil")] == pytest.approx([0.16] * 4)


# --- rows that differ only in an ignored covariate ----------------------------------------------


def test_rows_told_when_they_differ_only_in_an_ignored_covariate(cinnamon, capsys):
    # two tools A and B on one plate geometry, the tool column ignored: one simulation serves
    # both rows, and the user is told so; tool C runs its own setup and gets no note
    import json

    from soilcal.chain.verify import tool_frame
    from soilcal.cli import main

    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t).iloc[:3]
    df["plate"] = ["A", "B", "C"]
    df["directrix"] = ["line", "line", "arc"]
    df.to_csv(t, index=False)
    _declare(cinnamon, "cinnamon-soil", lambda d: _entry(d)["covariates"].update(
        plate={"ignore": True, "quantity": "tool"}))
    soil = load_soil(_yaml(cinnamon, "cinnamon-soil"), cinnamon / "resources")
    a, b, c = conditions(soil)
    assert a.setup == b.setup and a.params == b.params and a.setup != c.setup
    assert a.note == b.note and "rows 1, 2" in a.note and "plate = A, B" in a.note and c.note == ""
    assert soil.load_notes == [a.note]
    frame = tool_frame([a, b, c], {})
    assert frame["note"].str.contains("plate = A, B", regex=False).tolist() == [True] * 4 + [False] * 2
    assert main(["config", "check", "--resources", str(cinnamon / "resources"),
                 str(_yaml(cinnamon, "cinnamon-soil"))]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["load_notes"] == [a.note]
    assert a.note in err


def test_the_load_notes_are_not_the_soil_s_own_notes(black, capsys):
    """The black soil's file has its own free-text notes:; soilcal config check's JSON said
    "notes": [] for it, as if it had none.  Its load notes are load_notes, and the JSON has no
    notes field."""
    import json

    from soilcal.cli import main

    soil = load_soil(_yaml(black, "black-soil"), black / "resources")
    assert soil.data["notes"] and soil.load_notes == []
    assert main(["config", "check", "--resources", str(black / "resources"), str(_yaml(black, "black-soil"))]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["load_notes"] == [] and "notes" not in out


def test_no_note_where_the_ignored_covariate_goes_with_a_simulated_one(cinnamon):
    # the shipped table: plate numbers 1-4 each with its own directrix, and rows at one
    # simulation that agree in every ignored covariate (repeats), get no note
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    assert all(c.note == "" for c in _load(cinnamon, "cinnamon-soil"))
    df["plate"] = [1, 1, 2, 2]
    df["directrix"] = ["line", "line", "arc", "arc"]
    df.to_csv(t, index=False)
    assert all(c.note == "" for c in _load(cinnamon, "cinnamon-soil"))


def test_a_soil_s_moisture_and_a_response_s_unit_written_si_style():
    """A soil's properties.moisture_content in "g g-1" (0.15 g/g = 15 %) was refused as a unit
    soilcal does not know; a response's unit "KN" as no unit of a force.  Both read now."""
    from soilcal.config.measurements import unit_factor
    from soilcal.config.quantities import soil_moisture

    assert soil_moisture("s.yaml", {"properties": {"moisture_content": {"value": 0.15, "unit": "g g-1"}}})[
        "factor"] == 100.0
    assert unit_factor("KN", "horizontal_force_N") == 1000.0 and unit_factor("N m-1", "horizontal_force_N") is None
