"""The soils' `measurements` blocks: measured tool/process tests as data, one condition per row."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest
import yaml

from soilcal.config.load import load_soil, read_yaml
from soilcal.config.measurements import Condition, conditions, unit_of
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]
SOILS = sorted(p.stem for p in (ROOT / "config" / "soils").glob("*.yaml"))


def _shipped(soil):
    return load_soil(ROOT / "config" / "soils" / f"{soil}.yaml", ROOT / "resources")


@pytest.mark.parametrize("soil", SOILS)
def test_shipped_soils_load_with_their_measurements(soil):
    conds = conditions(_shipped(soil))
    assert all(isinstance(c, Condition) for c in conds)
    assert conds
    if soil == "xinjiang-vineyard":
        # the three layers' measured static and dynamic angles (angles_measured.csv, as printed)
        # against the middle layer's calibrated set, the layer depth (the layer's bottom, m)
        # the one declared quantity: each table's rows run one simulation
        assert [(c.measurement, c.scenario, c.case) for c in conds] == (
            [("static_angles", "repose", "middle")] * 3 + [("dynamic_angles", "drum", "middle")] * 3)
        assert [c.quantities["layer_depth"] for c in conds] == pytest.approx([0.2, 0.4, 0.6] * 2, rel=1e-12)
        assert all(c.note for c in conds)  # simulated alike, said


def test_each_measured_table_is_read_once_at_load_and_its_conditions_kept(monkeypatch):
    import types

    import soilcal.config.load as load

    reads = []
    real = load.read_table
    monkeypatch.setattr(load, "read_table", lambda p, *a: reads.append(Path(p).name) or real(p, *a))
    soil = _shipped("cinnamon-soil")
    tables = [e["table"] for e in soil.data["measurements"].values()]
    assert sorted(n for n in reads if n in tables) == sorted(tables)  # once each
    reads.clear()
    conds = conditions(soil)
    assert reads == [] and len(conds) == 4
    # the same conditions as the tables read anew (a soil the loader did not make)
    fresh = types.SimpleNamespace(path=soil.path, data=soil.data, resources_root=soil.resources_root)
    assert conditions(fresh) == conds and sorted(reads) == sorted(tables)


def test_cinnamon_one_condition_per_plate():
    conds = conditions(_shipped("cinnamon-soil"))
    table = pd.read_csv(ROOT / "resources/measurements/cinnamon-soil/cutting_resistance.csv")
    assert len(conds) == 4 == len(table)
    for c, directrix in zip(conds, table["directrix"]):
        assert c.scenario == "bulldozing"
        assert c.setup["name"] == f"plate-{directrix}" and c.setup["shape"] == directrix
        assert c.label == f"directrix={directrix}"
        assert (c.covariate, c.covariate_value) == ("directrix", directrix)
        assert (c.stage, c.case, c.preset, c.replicates) == ("bbd", "stacking_angle", "quick", 3)
        assert [r["measure"] for r in c.responses] == ["horizontal_force_N", "vertical_force_N"]
        assert all(r["unit"] == "N" and r["measured"] is not None for r in c.responses)
    assert [c.row for c in conds] == [1, 2, 3, 4]
    assert conds[0].responses[0]["measured"] == pytest.approx(321.10)
    assert conds[3].responses[1]["measured"] == pytest.approx(10.40)


def test_black_soil_flatness_and_power_by_rotor_speed():
    conds = conditions(_shipped("black-soil"))
    flat = [c for c in conds if c.measurement == "surface_flatness"]
    power = [c for c in conds if c.measurement == "tillage_power"]
    speeds = [150, 200, 250, 300, 350]
    assert [c.setup["name"] for c in flat] == [f"rpm-{n}" for n in speeds]
    assert [c.setup["rpm"] for c in flat] == [float(n) for n in speeds]
    assert [c.covariate_value for c in flat] == [str(n) for n in speeds]
    assert all((c.stage, c.case) == ("soil-65mn", "accumulation_angle_65mn") for c in conds)
    last = flat[-1].responses[0]
    assert (last["measure"], last["unit"]) == ("flatness_mm", "mm")
    assert (last["measured"], last["paper_simulated"], last["paper_difference"]) == (102.1, 105.3, 3.2)
    assert [c.setup["name"] for c in power] == [f"rpm-{n}" for n in speeds]
    for c in power:
        (r,) = c.responses
        assert r["measure"] == "power_kW" and r["measured"] is None and r["note"]
        assert 0 < r["paper_difference"] < 0.5
    # the soil's simulation.params (particle density) come with every condition
    assert all(c.params["soil_density"] == 1560 for c in conds)


def test_guangxi_compression_one_case_per_moisture():
    conds = conditions(_shipped("guangxi-cohesive"))
    assert len(conds) == 3
    assert [c.case for c in conds] == ["mc05", "mc10", "mc15"]
    assert [c.label for c in conds] == ["moisture_content=5", "moisture_content=10", "moisture_content=15"]
    assert all(c.scenario == "compression" and c.setup["name"] == "guangxi-cohesive" for c in conds)
    assert all(c.responses[0]["measured"] is None and "Table 13" in c.responses[0]["note"] for c in conds)


def test_yangtze_traction_single_condition():
    (c,) = conditions(_shipped("yangtze-clay-loam"))
    assert (c.scenario, c.setup["name"], c.covariate, c.label) == ("furrow", "yangtze-opener", "", "row 1")
    (r,) = c.responses
    assert (r["measure"], r["measured"], r["paper_simulated"]) == ("traction_N", 1303.07, 1167.30)


def test_unit_suffixes():
    assert unit_of("horizontal_force_N") == "N"
    assert unit_of("power_kW") == "kW"
    assert unit_of("flatness_mm") == "mm"
    assert unit_of("stress_10_kpa") == "kPa"
    assert unit_of("area_difference_dm2") == "dm^2"
    assert unit_of("angle_deg") == "deg"
    assert unit_of("height_m") == "m"
    assert unit_of("strain_end") == "-"


# --- bad inputs, each in a copy of one soil -------------------------------------------------


def _workspace(tmp_path, soil):
    (tmp_path / "config" / "soils").mkdir(parents=True)
    shutil.copy(ROOT / f"config/soils/{soil}.yaml", tmp_path / f"config/soils/{soil}.yaml")
    for kind in ("published", "measurements", "images"):
        if (ROOT / "resources" / kind / soil).is_dir():
            shutil.copytree(ROOT / "resources" / kind / soil, tmp_path / "resources" / kind / soil)
    return tmp_path


@pytest.fixture
def cinnamon(tmp_path):
    return _workspace(tmp_path, "cinnamon-soil")


@pytest.fixture
def black(tmp_path):
    return _workspace(tmp_path, "black-soil")


@pytest.fixture
def guangxi(tmp_path):
    return _workspace(tmp_path, "guangxi-cohesive")


def _yaml(ws: Path, soil: str) -> Path:
    return ws / f"config/soils/{soil}.yaml"


def _table(ws: Path, soil: str, name: str) -> Path:
    return ws / "resources/measurements" / soil / name


def _edit(ws: Path, soil: str, fn) -> Path:
    p = _yaml(ws, soil)
    d = read_yaml(p)
    fn(d)
    p.write_text(yaml.safe_dump(d, sort_keys=False, allow_unicode=True))
    return p


def _fails(ws: Path, soil: str, where: str) -> str:
    """Loading fails with a message starting '<file>: <field>: expected'."""
    with pytest.raises(InputError) as e:
        load_soil(_yaml(ws, soil), ws / "resources")
    msg = str(e.value)
    assert f"{where}: expected" in msg, msg
    assert "\n" not in msg
    return msg


def _entry(d, mid="cutting_resistance"):
    return d["measurements"][mid]


def test_workspace_copy_loads(cinnamon):
    s = load_soil(_yaml(cinnamon, "cinnamon-soil"), cinnamon / "resources")
    assert len(conditions(s)) == 4


def test_unknown_covariate_column(cinnamon):
    def fn(d):
        covs = _entry(d)["covariates"]
        covs["directriks"] = covs.pop("directrix")

    p = _edit(cinnamon, "cinnamon-soil", fn)
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.covariates.directriks")
    assert "a column of cutting_resistance.csv" in msg


def test_empty_measured_value_cell(cinnamon):
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["horizontal_measured_N"] = df["horizontal_measured_N"].astype(object)
    df.loc[1, "horizontal_measured_N"] = None
    df.to_csv(t, index=False)
    msg = _fails(cinnamon, "cinnamon-soil", f"{t}: row 2, column horizontal_measured_N")
    assert "value: null" in msg


def test_empty_covariate_cell(cinnamon):
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df.loc[2, "directrix"] = None
    df.to_csv(t, index=False)
    _fails(cinnamon, "cinnamon-soil", f"{t}: row 3, column directrix")


def test_unit_mismatch(cinnamon):
    # a length for a force: no conversion, an error naming the field and the units it takes
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["responses"][1].update(unit="mm"))
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.responses[1].unit")
    assert "expected N (the unit of vertical_force_N" in msg and "'mm'" in msg
    assert "cutting_resistance.csv" in msg and "N, kN, mN" in msg


def test_a_table_in_kN_is_read_in_N(cinnamon):
    """The plates' forces tabled in kN (0.3211 kN = 321.1 N): the conditions hold them in N, the
    unit the DEM gives horizontal_force_N in, and say so."""
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t).rename(columns={"horizontal_measured_N": "horizontal_measured_kN"})
    df["horizontal_measured_kN"] = [0.3211, 0.2521, 0.1545, 0.3048]
    df.to_csv(t, index=False)
    p = _edit(cinnamon, "cinnamon-soil",
              lambda d: _entry(d)["responses"][0].update(unit="kN", value="horizontal_measured_kN"))
    conds = conditions(load_soil(p, cinnamon / "resources"))
    h = [next(r for r in c.responses if r["measure"] == "horizontal_force_N") for c in conds]
    assert [r["measured"] for r in h] == pytest.approx([321.1, 252.1, 154.5, 304.8])
    assert {r["unit"] for r in h} == {"N"}
    assert "gives kN, converted to N (x 1000)" in h[0]["note"]
    # the other force stays as tabled
    v = [next(r for r in c.responses if r["measure"] == "vertical_force_N") for c in conds]
    assert [r["measured"] for r in v] == pytest.approx([48.80, 13.98, 15.50, 10.40]) and v[0]["note"] == ""


def test_a_column_named_in_another_unit_than_the_response_s_is_refused(cinnamon):
    """Draughts tabled in kN under a column draught_kN, the response left at unit: N: read as N
    they were 1000 times too small (0.3211 N).  Refused naming the response's unit and the
    column; declared unit: kN, they load in N."""
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t).rename(columns={"horizontal_measured_N": "draught_kN"})
    df["draught_kN"] = [0.3211, 0.2521, 0.1545, 0.3048]
    df.to_csv(t, index=False)
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(value="draught_kN"))
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.responses[0].unit")
    assert "column draught_kN (value) says is kN" in msg and "got 'N'" in msg
    # declared kN, it loads in N
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(unit="kN"))
    conds = conditions(load_soil(p, cinnamon / "resources"))
    assert [c.responses[0]["measured"] for c in conds] == pytest.approx([321.1, 252.1, 154.5, 304.8])


@pytest.mark.parametrize("col", ["draught_kn", "Draught (KN)", "draught kN", "draught, kN", "draught_kN_mean",
                                 "draught [kN]", "draught/kN", "Draught..kN.", "draught.kN", "draught_kN.1"])
def test_a_kn_column_is_refused_under_unit_n_however_written(cinnamon, col):
    """A unit is a word of the column's name anywhere (between _, spaces, commas, brackets,
    after a /, between the dots of R's names: read.csv turns Draught (kN) into Draught..kN.;
    pandas names a second draught_kN draught_kN.1), matched without its case where that names
    one unit (kn, KN: kN): each of these loaded 0.3211 kN as 0.3211 N."""
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t).rename(columns={"horizontal_measured_N": col})
    df[col] = [0.3211, 0.2521, 0.1545, 0.3048]
    df.to_csv(t, index=False)
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(value=col))
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.responses[0].unit")
    assert f"column {col} (value) says is kN" in msg


def test_a_one_letter_last_word_of_a_column_s_name_is_its_unit(cinnamon):
    """horizontal_measured_N, the tables' own naming: its last word N is the unit of its cells.
    Under unit: kN the draughts 321.1 were read as 321100 N without a word (a one-letter word
    was a unit only in brackets); now refused naming N, and under unit: N they load as tabled."""
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(unit="kN"))
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.responses[0].unit")
    assert "column horizontal_measured_N (value) says is N" in msg and "got 'kN'" in msg
    assert "rename the column, e.g. horizontal_measured_N (kN)" in msg
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(unit="N"))
    conds = conditions(load_soil(p, cinnamon / "resources"))
    t = pd.read_csv(_table(cinnamon, "cinnamon-soil", "cutting_resistance.csv"))
    assert [c.responses[0]["measured"] for c in conds] == pytest.approx(list(t["horizontal_measured_N"]))


def test_a_one_letter_word_beside_another_unit_is_no_unit(black):
    """Sd_m (mm): the name's unit is the bracketed mm, its m a word (measured); Sd_m, ending in
    m, is metres: under unit mm refused, asking for a name such as Sd_m (mm), with which the
    flatness loads as tabled."""
    t = _table(black, "black-soil", "surface_flatness.csv")
    df = pd.read_csv(t).rename(columns={"Sd_measured_mm": "Sd_m", "Sd_simulated_mm": "Sd_s (mm)"})
    df.to_csv(t, index=False)
    p = _edit(black, "black-soil", lambda d: _entry(d, "surface_flatness")["responses"][0].update(
        value="Sd_m", paper_simulated="Sd_s (mm)"))
    msg = _fails(black, "black-soil", f"{p}: measurements.surface_flatness.responses[0].unit")
    assert "column Sd_m (value) says is m" in msg and "e.g. Sd_m (mm)" in msg
    df.rename(columns={"Sd_m": "Sd_m (mm)"}).to_csv(t, index=False)
    p = _edit(black, "black-soil", lambda d: _entry(d, "surface_flatness")["responses"][0].update(
        value="Sd_m (mm)"))
    flat = [c for c in conditions(load_soil(p, black / "resources")) if c.measurement == "surface_flatness"]
    assert [c.responses[0]["measured"] for c in flat] == pytest.approx(list(df["Sd_m"]))
    assert [c.responses[0]["paper_simulated"] for c in flat] == pytest.approx(list(df["Sd_s (mm)"]))


@pytest.mark.parametrize("col", ["draught_N_mean", "F_N_sd", "draught N mean"])
def test_a_one_letter_unit_inside_a_column_s_name_is_its_unit(cinnamon, col):
    """draught_N_mean under unit: kN: the draughts 321.1 N were read as 321100 N without a word
    (a one-letter word was a unit only as the name's last word).  A one-letter word after the
    first is the unit where the name gives no other: refused naming N; under unit: N they
    load as tabled."""
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t).rename(columns={"horizontal_measured_N": col})
    df.to_csv(t, index=False)
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(value=col, unit="kN"))
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.responses[0].unit")
    assert f"column {col} (value) says is N" in msg and "got 'kN'" in msg and f"e.g. {col} (kN)" in msg
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(unit="N"))
    conds = conditions(load_soil(p, cinnamon / "resources"))
    assert [c.responses[0]["measured"] for c in conds] == pytest.approx(list(df[col]))


@pytest.mark.parametrize("name, unit", [
    ("speed (m s-1)", "m/s"), ("speed [m.s-1]", "m/s"), ("speed (m·s⁻¹)", "m/s"), ("speed (m s^-1)", "m/s"),
    ("speed_m_per_s", "m/s"), ("v (km h-1)", "km/h"), ("density (g cm-3)", "g/cm^3"), ("bd (g.cm-3)", "g/cm^3"),
    ("density (Mg m-3)", "t/m^3"), ("Bulk density (Mg/m3)", "t/m^3"), ("density_kg_m3", "kg/m^3"),
    ("rotor (min-1)", "r/min"), ("w (g g-1)", "g/g"), ("A (cm²)", "cm^2"), ("torque..N.m.", "N m"),
    ("draught (N m-1)", "N/m"), ("draught_N_per_m", "N/m"), ("time (s)", None), ("mass (g)", None)])
def test_compound_units_in_a_column_s_name(name, unit):
    """Units written SI style with exponents (m s-1, g cm-3, Mg m-3: a megagram is a tonne) or a
    / are read whole; a quotient no table knows (a draught per width, N m-1) is given as
    written, so that it is seen as no N, and s or g alone are units of no table."""
    from soilcal.config.measurements import name_units

    assert name_units(name) == ([unit] if unit else [])


def test_a_lone_hyphen_in_a_column_s_name_is_no_unit(guangxi):
    """Moisture - %, declared unit: %: the hyphen was read as the dimensionless unit '-' and the
    column refused as 'the column's name says are in -'.  A word of punctuation only is no unit
    outside brackets; w (-) still is dimensionless."""
    from soilcal.config.measurements import name_units

    t = _table(guangxi, "guangxi-cohesive", "compression.csv")
    pd.read_csv(t).rename(columns={"moisture_content": "Moisture - %"}).to_csv(t, index=False)

    def rename(d):
        cov = _entry(d, "compression")["covariates"]
        cov["Moisture - %"] = cov.pop("moisture_content")
    p = _edit(guangxi, "guangxi-cohesive", rename)
    conds = [c for c in conditions(load_soil(p, guangxi / "resources")) if c.measurement == "compression"]
    assert [c.case for c in conds] == ["mc05", "mc10", "mc15"]
    assert name_units("Moisture - %") == ["%"] and name_units("w (-)") == ["-"] and name_units("a - b") == []


@pytest.mark.parametrize("col", ["horizontal_mn", "horizontal_N_mn", "horizontal_MN_x", "horizontal_nm"])
def test_two_letters_in_another_case_are_no_unit(cinnamon, col):
    """mn (a mean, as R's headers write it), MN (meganewtons), nm (nanometres) were all matched
    without case as mN or N m: horizontal_mn under unit: N was refused as mN.  A spelling of two
    letters is matched with its case (or as kn, KN for kN): the draughts load as tabled."""
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t).rename(columns={"horizontal_measured_N": col})
    df.to_csv(t, index=False)
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(value=col))
    conds = conditions(load_soil(p, cinnamon / "resources"))
    assert [c.responses[0]["measured"] for c in conds] == pytest.approx(list(df[col]))


def test_a_flatness_in_cm_and_a_strain_in_percent_are_converted():
    from soilcal.config.measurements import unit_factor

    assert unit_factor("cm", "flatness_mm") == pytest.approx(10.0)
    assert unit_factor("m", "flatness_mm") == pytest.approx(1000.0)
    assert unit_factor("%", "recovered_strain") == pytest.approx(0.01)
    assert unit_factor("MPa", "stress_10_kpa") == pytest.approx(1000.0)
    assert unit_factor("Nm", "torque_Nm") == 1.0 and unit_factor("m^2", "area_difference_dm2") == pytest.approx(100.0)
    assert unit_factor("N", "flatness_mm") is None and unit_factor("%", "angle_deg") is None


def test_covariate_value_not_in_map(black):
    t = _table(black, "black-soil", "surface_flatness.csv")
    df = pd.read_csv(t)
    df.loc[4, "rotor_speed_rpm"] = 400
    df.to_csv(t, index=False)
    msg = _fails(black, "black-soil", f"{t}: row 5, column rotor_speed_rpm")
    assert "measurements.surface_flatness.covariates.rotor_speed_rpm.setup" in msg and "400" in msg


def test_case_map_names_an_unknown_case(guangxi):
    p = _edit(guangxi, "guangxi-cohesive",
              lambda d: _entry(d, "compression")["covariates"]["moisture_content"]["case"].update({"15": "mc17"}))
    _fails(guangxi, "guangxi-cohesive", f"{p}: measurements.compression.covariates.moisture_content.case.15")


def test_setup_key_that_does_not_exist(cinnamon):
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d).update(set={"depht": 0.05}))
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.set.depht")
    assert "depth" in msg


def test_set_covariate_key_that_does_not_exist(cinnamon):
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["depth_mm"] = 30
    df.to_csv(t, index=False)
    p = _edit(cinnamon, "cinnamon-soil",
              lambda d: _entry(d)["covariates"].update(depth_mm={"set": "cut_depth", "scale": 0.001}))
    _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.covariates.depth_mm.set")


def test_set_and_param_covariates(cinnamon):
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["depth_mm"] = [30, 35, 40, 45]
    df["bulk_density"] = [1.3, 1.35, 1.4, 1.45]
    df.to_csv(t, index=False)

    def fn(d):
        _entry(d)["covariates"].update(depth_mm={"set": "depth", "scale": 0.001},
                                       bulk_density={"param": "soil_density", "scale": 1000})

    _edit(cinnamon, "cinnamon-soil", fn)
    conds = conditions(load_soil(_yaml(cinnamon, "cinnamon-soil"), cinnamon / "resources"))
    assert [c.setup["depth"] for c in conds] == pytest.approx([0.03, 0.035, 0.04, 0.045])
    assert [c.params["soil_density"] for c in conds] == pytest.approx([1300, 1350, 1400, 1450])
    assert conds[1].label == "directrix=parabola, depth_mm=35, bulk_density=1.35"
    assert conds[1].covariate == "directrix"


def test_value_the_scenario_refuses_names_row_and_column(cinnamon):
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["depth_mm"] = [30, 30, 500, 30]  # row 3 deeper than the bin
    df.to_csv(t, index=False)
    _edit(cinnamon, "cinnamon-soil",
          lambda d: _entry(d)["covariates"].update(depth_mm={"set": "depth", "scale": 0.001}))
    msg = _fails(cinnamon, "cinnamon-soil", f"{t}: row 3, column depth_mm")
    assert "cutting depth" in msg and "got 500" in msg


def test_param_that_is_not_a_dem_parameter(cinnamon):
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["bulk_density"] = 1394
    df.to_csv(t, index=False)
    p = _edit(cinnamon, "cinnamon-soil",
              lambda d: _entry(d)["covariates"].update(bulk_density={"param": "bulk_density"}))
    _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.covariates.bulk_density.param")


def test_unknown_measure(cinnamon):
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(measure="draft_force_N"))
    msg = _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.responses[0].measure")
    assert "horizontal_force_N" in msg


def test_unknown_scenario_and_setup(cinnamon):
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d).update(setup="plate-zigzag"))
    _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.setup")
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d).update(scenario="bulldozer"))
    _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.scenario")


def test_setup_map_names_an_unknown_setup(cinnamon):
    p = _edit(cinnamon, "cinnamon-soil",
              lambda d: _entry(d)["covariates"]["directrix"]["setup"].update(arc="plate-circle"))
    _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.covariates.directrix.setup.arc")


def test_missing_table_file(cinnamon):
    _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv").unlink()
    msg = _fails(cinnamon, "cinnamon-soil",
                 f"{_yaml(cinnamon, 'cinnamon-soil')}: measurements.cutting_resistance.table")
    assert "no such file" in msg


def test_table_without_rows(cinnamon):
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    t.write_text(t.read_text().splitlines()[0] + "\n")
    _fails(cinnamon, "cinnamon-soil", f"{t}: rows")


def test_undeclared_extra_column(cinnamon):
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    df = pd.read_csv(t)
    df["speed_m_s"] = 0.16
    df.to_csv(t, index=False)
    msg = _fails(cinnamon, "cinnamon-soil", f"{t}: column speed_m_s")
    assert "ignore_columns" in msg


def test_source_column_must_be_declared(cinnamon):
    t = _table(cinnamon, "cinnamon-soil", "cutting_resistance.csv")
    _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d).pop("ignore_columns"))
    _fails(cinnamon, "cinnamon-soil", f"{t}: column source")


def test_calibrated_stage_needs_an_optimise_block(cinnamon):
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["calibrated"].update(stage="pb"))
    _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.calibrated.stage")


def test_calibrated_case_must_be_a_case_of_the_stage(cinnamon):
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["calibrated"].update(case="angle"))
    _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.calibrated.case")


def test_calibrated_case_needed_without_a_case_covariate(cinnamon):
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["calibrated"].pop("case"))
    _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.calibrated.case")


def test_unprinted_value_needs_a_note(cinnamon):
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["responses"][1].update(value=None))
    _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.responses[1].note")


def test_covariate_needs_exactly_one_form(cinnamon):
    p = _edit(cinnamon, "cinnamon-soil",
              lambda d: _entry(d)["covariates"]["plate"].update(set="depth"))
    _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.covariates.plate")


def test_schema_refuses_unknown_field_and_bad_id(cinnamon):
    p = _edit(cinnamon, "cinnamon-soil", lambda d: _entry(d)["responses"][0].update(valeu="x"))
    _fails(cinnamon, "cinnamon-soil", f"{p}: measurements.cutting_resistance.responses[0].valeu")
    shutil.copy(ROOT / "config/soils/cinnamon-soil.yaml", p)
    p = _edit(cinnamon, "cinnamon-soil", lambda d: d["measurements"].update({"Bad-Id": d["measurements"]["cutting_resistance"]}))
    _fails(cinnamon, "cinnamon-soil", f"{p}: measurements")
