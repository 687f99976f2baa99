"""The generator of measured tables with a hidden effect (soilcal.loop.synthesize) and the
checks of what ``soilcal loop synthesize`` / ``loop run`` take on the command line."""

from __future__ import annotations

import numpy as np
import pytest

from soilcal.errors import InputError
from soilcal.loop import cli
from soilcal.loop import standin as S
from soilcal.loop import synthesize as sy
from soilcal.loop.residuals import observations


def _conds():
    return S.conditions(S.grid(0, 6))


def test_without_a_reference_the_hidden_effect_acts_about_the_mean_of_the_rows():
    conds = _conds()
    off = sy.synthesize(conds, S.base_params, S.simulate, {}, None, {}, noise=0.0, seed=0)
    on = sy.synthesize(conds, S.base_params, S.simulate, {"rate_friction": {"beta": 0.2}}, None, {}, noise=0.0, seed=0)
    speeds = observations(conds)["q:tool_speed"].to_numpy(float)
    v0 = speeds.mean()
    assert on["reference:tool_speed"].to_numpy() == pytest.approx(np.full(len(on), v0))
    # the effect moves the force with ln(v / v0): up above the mean speed, down below it
    ratio = (on["truth_simulated"] / off["truth_simulated"]).to_numpy()
    lv = np.log(speeds / v0)
    far = np.abs(lv) > 0.1
    assert far.sum() >= 2 and (np.sign(ratio[far] - 1) == np.sign(lv[far])).all()


def test_a_declared_reference_is_kept_and_a_command_line_one_must_be_carried():
    conds = _conds()
    assert sy.default_reference(conds, {"tool_speed": 1.5})["tool_speed"] == 1.5
    assert "moisture_content" not in sy.default_reference(conds, {"moisture_content": 12.0})
    with pytest.raises(InputError, match="reference.moisture_content: expected a numeric quantity of the measured"):
        sy.default_reference(conds, {"moisture_content": 12.0}, "--reference", strict=True)
    with pytest.raises(InputError, match="loop.reference.tool_speed: expected a positive number in m/s"):
        sy.default_reference(conds, {"tool_speed": -1.0}, "--reference", strict=True)
    with pytest.raises(InputError, match="loop.reference.speed_kmh: expected a numeric quantity"):
        sy.default_reference(conds, {"speed_kmh": 4.0}, "--reference", strict=True)


def test_an_effect_or_disturbance_needs_known_parameters_and_a_periodic_one_its_wavelength():
    conds = _conds()
    with pytest.raises(InputError, match="effect.rate_friction: expected a value of its parameters"):
        sy.check_hidden({"rate_friction": {}})
    with pytest.raises(InputError, match=r"disturbance.stones: expected a parameter of the disturbance \(fraction"):
        sy.check_disturbances({"stones": {"amplitude": 0.5}}, conds)
    with pytest.raises(InputError, match="disturbance.periodic.wavelength: expected a value in"):
        sy.check_disturbances({"periodic": {"amplitude": 0.2}}, conds)
    full = sy.check_disturbances({"stones": {"fraction": 0.5}}, conds)
    assert full == {"stones": {"fraction": 0.5, "low": 0.1, "high": 0.3}}
    with pytest.raises(InputError, match="repeats: expected at least one measured repeat"):
        sy.synthesize(conds, S.base_params, S.simulate, {}, None, {}, seeds=())


def test_a_name_given_twice_on_the_command_line_is_refused():
    assert cli._named(["stones:fraction=0.2", "day_offset:sd=0.1"], "--disturbance") == {
        "stones": {"fraction": 0.2}, "day_offset": {"sd": 0.1}}
    with pytest.raises(InputError, match="--disturbance: expected each name once"):
        cli._named(["stones:fraction=0.2", "stones:low=0.2"], "--disturbance")


@pytest.mark.parametrize("given, field, words", [
    # a share of rows above 1, a rise range upside down, an amplitude that turns the factor
    # 1 + a sin negative, a wavelength of 0 (a division by zero before), a negative SD
    ({"stones": {"fraction": 2.0}}, "disturbance.stones.fraction", "a share of the rows in [0, 1]"),
    ({"stones": {"low": 0.3, "high": 0.1}}, "disturbance.stones.high", "a relative rise >= low"),
    ({"periodic": {"amplitude": 1.5, "wavelength": 3.0}}, "disturbance.periodic.amplitude", "in [0, 1)"),
    ({"periodic": {"wavelength": 0.0}}, "disturbance.periodic.wavelength", "a wavelength > 0 in m along"),
    ({"day_offset": {"sd": -0.1}}, "disturbance.day_offset.sd", "a relative SD >= 0"),
])
def test_a_disturbance_outside_its_range_is_refused_naming_the_parameter(given, field, words):
    with pytest.raises(InputError) as exc:
        sy.check_disturbances(given, _conds(), "--disturbance")
    assert str(exc.value).startswith(f"--disturbance: {field}: expected ") and words in str(exc.value)


@pytest.mark.parametrize("argv, field, expected, got", [
    (["--reference", "tool_speed=fast"], "--reference", "QUANTITY=NUMBER", "'tool_speed=fast'"),
    (["--param", "soil_density"], "--param", "NAME=NUMBER", "'soil_density'"),
    (["--noise", "-0.02"], "--noise", "a relative SD >= 0", "-0.02"),
])
def test_the_command_line_values_are_refused_as_typed(tmp_path, monkeypatch, capsys, argv, field, expected, got):
    from soilcal.cli import main

    from test_user_tables import _counting_simulator, user_soil

    soil, res = user_soil(tmp_path)
    calls = []
    monkeypatch.setattr(cli, "dem_simulator", _counting_simulator(calls))
    code = main(["loop", "synthesize", str(soil), "--resources", str(res), "--measurement", "small4", *argv,
                 "--out", str(tmp_path / "o.csv")])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith(f"soilcal: error: <command line>: {field}: expected {expected}") and err[0].endswith(
        f"got {got}"), err[0]
    assert not (tmp_path / "o.csv").exists() and calls == []


def test_a_table_written_without_scatter_has_blank_sds_and_its_values_in_full(tmp_path, monkeypatch):
    # a simulator without seed scatter (10 N + the table row, from 1) and --noise 0: every SD is 0,
    # which a measured table may not state (the value would be exact); the written table
    # leaves those cells blank, loads again as the soil's own table, and keeps the values
    import pandas as pd

    from soilcal.cli import main
    from soilcal.config.load import load_soil

    from test_user_tables import _counting_simulator, user_soil

    soil, res = user_soil(tmp_path)
    monkeypatch.setattr(cli, "dem_simulator", _counting_simulator([]))
    out = tmp_path / "bin.csv"
    assert main(["loop", "synthesize", str(soil), "--resources", str(res), "--measurement", "bin_forces",
                 "--noise", "0", "--out", str(out)]) == 0
    df = pd.read_csv(out)
    assert df["draft_sd_N"].isna().all()
    target = next((res / "measurements").glob("*/bin_forces.csv"))
    rows = pd.read_csv(target)
    assert list(df["draft_N"]) == [10.0 + r for r in range(1, len(rows) + 1)]  # rows numbered from 1
    out.replace(target)
    load_soil(soil, res)  # the written table is a valid measured table of the soil


@pytest.mark.parametrize("hidden, field, words", [
    # no finite number (it was blamed on a table row), or outside the physical range the
    # library states (plastic_contact lambda_p in [0, 0.95], soilcal.loop.effects)
    ({"rate_friction": {"beta": float("nan")}}, "effect.rate_friction.beta", "a finite number (-)"),
    ({"rate_friction": {"beta": float("inf")}}, "effect.rate_friction.beta", "a finite number (-)"),
    ({"plastic_contact": {"lambda_p": 1.2}}, "effect.plastic_contact.lambda_p", "a finite number from 0 to 0.95, its physical range (-)"),
])
def test_a_hidden_effect_parameter_that_is_no_number_or_unphysical_is_refused_naming_it(hidden, field, words):
    with pytest.raises(InputError) as exc:
        sy.check_hidden(hidden, "--effect")
    assert str(exc.value).startswith(f"--effect: {field}: expected {words}")
    with pytest.raises(InputError):
        sy.synthesize(_conds(), S.base_params, S.simulate, hidden, None, {}, noise=0.0, seed=0)


def test_a_hidden_effect_driven_to_a_physical_limit_is_refused_naming_the_row():
    # f = 1 + g (d / d0 - 1) with g -5 is below 0.1 at the deeper rows (d / d0 > 1.18): the
    # density and stiffness stop at their floor instead of following g; an adhesion of -1 J/m^2
    # on a soil-steel surface energy of 0 (the stand-in's) stays 0 on every row
    conds = _conds()
    ref = sy.default_reference(conds, None)
    with pytest.raises(InputError) as exc:
        sy.check_acts({"depth_compaction": {"g": -5.0}}, {}, conds, S.base_params, ref, "--effect")
    assert str(exc.value).startswith("--effect: effect.depth_compaction.g: expected a value at which depth_compaction "
                                     "follows its formula")
    assert "to a physical limit" in str(exc.value)
    with pytest.raises(InputError) as exc:
        sy.check_acts({"tool_adhesion": {"gamma_a": -1.0}}, {}, conds, S.base_params, ref, "--effect")
    assert "held at its physical limit" in str(exc.value)
    # within the formula's reach both act
    sy.check_acts({"depth_compaction": {"g": 0.4}, "tool_adhesion": {"gamma_a": 1.0}}, {}, conds, S.base_params,
                  ref, "--effect")


def test_the_truth_records_the_hidden_effect_and_the_disturbance_with_their_parameters():
    conds = _conds()
    table = sy.synthesize(conds, S.base_params, S.simulate, {"rate_friction": {"beta": 0.2}}, None,
                          {"stones": {"fraction": 0.5}}, noise=0.0, seed=0)
    assert (table["hidden:rate_friction.beta"] == 0.2).all()
    assert (table["disturbance:stones.fraction"] == 0.5).all()
    # the defaults filled in are recorded too (synthesize.DISTURBANCES)
    assert (table["disturbance:stones.low"] == 0.1).all() and (table["disturbance:stones.high"] == 0.3).all()
