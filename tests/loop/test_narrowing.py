"""An effect whose scenario stops measuring past some level of its parameter
(``soilcal.loop.select.narrowing``): soil held by a strongly adhesive tube leaves no heap to
measure.  The levels whose runs all failed, on one side of the switched-off value to the end
of the design, bound the effect's working range; the effect is fitted over it, and the second
round runs ``max(2, points - working levels)`` levels evenly inside the gap to learn how far the
scenario goes.  Isolated failures inside the range are left to the interpolation of
``_fill_failed``."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from soilcal.loop import core
from soilcal.loop import select as sl
from soilcal.loop import standin as S
from soilcal.loop import synthesize as sy
from soilcal.loop.effects import EFFECTS

REFERENCE = {"tool_speed": 1.75, "working_depth": 0.1, "moisture_content": 16.0}


def _runs(levels, fails, param="gamma_a"):
    """Two rows (A, B) with two seeds at each level; ``fails(row, level)``: the run failed."""
    rows = []
    for lv in levels:
        for m in ("A", "B"):
            for seed in (0, 1):
                bad = fails(m, lv)
                rows.append({"measurement": m, "row": 1, "measure": "angle_deg", "seed": seed,
                             "value": math.nan if bad else 30.0 + lv, "status": "failed" if bad else "ok",
                             "error": "pile too small" if bad else "", sl.T_PREFIX + param: lv})
    return pd.DataFrame(rows)


ADHESION = [0.0, 0.75, 1.5, 2.25, 3.0]


def test_a_failing_upper_tail_bounds_the_working_range_and_plans_levels_in_the_gap():
    nar = sl.narrowing(_runs(ADHESION, lambda m, lv: m == "B" and lv >= 1.5), EFFECTS["tool_adhesion"], 5)
    assert (nar.low, nar.high, nar.failed_below, nar.failed_above) == (0.0, 0.75, None, 1.5)
    # two working levels of five: three levels evenly inside 0.75..1.5
    assert nar.gaps == pytest.approx((0.9375, 1.125, 1.3125))
    assert "B row 1 angle_deg: pile too small" in nar.where
    assert nar.text().startswith("tool_adhesion.gamma_a: no run measured at or above 1.5")
    kept = sl.within(_runs(ADHESION, lambda m, lv: False), nar)
    assert sorted(kept[sl.T_PREFIX + "gamma_a"].unique()) == [0.0, 0.75]


def test_only_the_switched_off_level_measuring_plans_at_least_two_levels_below_the_first_failure():
    nar = sl.narrowing(_runs(ADHESION, lambda m, lv: lv > 0), EFFECTS["tool_adhesion"], 5)
    assert (nar.low, nar.high, nar.failed_above) == (0.0, 0.0, 0.75)
    assert nar.text().endswith("every row measured at its switched-off value 0 alone")
    assert nar.gaps == pytest.approx((0.15, 0.3, 0.45, 0.6))
    few = sl.narrowing(_runs(ADHESION, lambda m, lv: lv >= 2.25), EFFECTS["tool_adhesion"], 3)
    assert few.gaps == pytest.approx((1.75, 2.0))  # max(2, 3 - 3) levels in 1.5..2.25


def test_a_failing_lower_tail_bounds_the_range_from_below():
    levels = [-0.3, -0.075, 0.0, 0.15, 0.375, 0.6]
    nar = sl.narrowing(_runs(levels, lambda m, lv: lv <= -0.3, "beta"), EFFECTS["rate_friction"], 5)
    assert (nar.low, nar.high, nar.failed_below, nar.failed_above) == (-0.075, 0.6, -0.3, None)
    assert nar.text().startswith("rate_friction.beta: no run measured at or below -0.3")


@pytest.mark.parametrize("fails", [
    lambda m, lv: m == "B" and lv == 1.5,  # an isolated failure inside the range: interpolated instead
    lambda m, lv: lv == 0.0,               # the switched-off level itself failed
    lambda m, lv: False,                   # nothing failed
])
def test_no_narrowing_without_a_failing_tail(fails):
    assert sl.narrowing(_runs(ADHESION, fails), EFFECTS["tool_adhesion"], 5) is None


def test_an_effect_of_two_parameters_is_not_narrowed():
    class Two:  # two parameters: its failures are left to _fill_failed
        name, null = "two", {"gamma_a": 0.0, "b": 0.0}

        def theta_names(self):
            return ["gamma_a", "b"]

    runs = _runs(ADHESION, lambda m, lv: lv > 0).assign(**{sl.T_PREFIX + "b": 0.0})
    assert sl.narrowing(runs, EFFECTS["tool_adhesion"], 5) is not None
    assert sl.narrowing(runs, Two(), 5) is None


def test_the_loop_fits_an_effect_over_the_levels_its_scenario_measures_at():
    """Hidden adhesion 1.0 J/m^2 on a stand-in soil bin whose runs fail above 1.6 J/m^2 more
    than the calibrated soil-steel surface energy: the first design (0 to 3 in steps of 0.75)
    fails at 2.25 and 3, the second round's levels 1.75 and 2.0 fail too, so the effect is
    fitted over 0 to 1.5 and recovered; the verdict names the failed level."""
    conds = S.conditions(S.grid(0, 18))
    table = sy.synthesize(conds, S.base_params, S.simulate, {"tool_adhesion": {"gamma_a": 1.0}}, REFERENCE, {},
                          noise=0.02, seed=11)
    simulated = []

    def failing(c, p, seed):
        extra = p["soil_steel_surface_energy"] - S.base_params(c)["soil_steel_surface_energy"]
        simulated.append(round(extra, 9))
        out = S.simulate(c, p, seed)
        return out if extra <= 1.6 else {k: math.nan for k in out}

    out = core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, failing,
                             core.Settings(reference=REFERENCE, effects=["tool_adhesion"]))
    assert 1.75 in simulated and 2.0 in simulated  # the second round ran the gap
    nar = out.narrowed["tool_adhesion"]
    assert (nar.low, nar.high, nar.failed_above) == (0.0, 1.5, 1.75)
    assert out.chosen == ["tool_adhesion"], out.verdict
    assert out.theta["tool_adhesion.gamma_a"] == pytest.approx(1.0, rel=0.25)
    assert "tool_adhesion.gamma_a: no run measured at or above 1.75" in out.verdict
    assert out.candidates.count("tool_adhesion") == 1


def test_without_failures_the_design_is_the_first_rounds():
    conds = S.conditions(S.grid(0, 18))
    table = sy.synthesize(conds, S.base_params, S.simulate, {"tool_adhesion": {"gamma_a": 1.0}}, REFERENCE, {},
                          noise=0.02, seed=11)
    levels = set()

    def sim(c, p, seed):
        levels.add(round(p["soil_steel_surface_energy"] - S.base_params(c)["soil_steel_surface_energy"], 9))
        return S.simulate(c, p, seed)

    out = core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, sim,
                             core.Settings(reference=REFERENCE, effects=["tool_adhesion"]))
    assert not out.narrowed
    # the design's levels, and the chosen effect's fitted value (its runs at the fit, core.run_inprocess)
    fitted = {round(v, 9) for v in out.theta.values()}
    assert levels - fitted == set(ADHESION), out.verdict


def test_the_second_rounds_plan_holds_the_extended_design_and_says_why():
    from soilcal.loop.files import _plan

    settings = core.Settings(reference=REFERENCE)
    extended = [{"gamma_a": lv} for lv in (0.0, 0.15, 0.3, 0.45, 0.6, 0.75, 1.5, 2.25, 3.0)]
    plan = _plan("soil", ["tool_adhesion", "rate_friction"], REFERENCE, settings, {}, designs={"tool_adhesion": extended},
                 narrowed={"tool_adhesion": "tool_adhesion.gamma_a: no run measured at or above 0.75"})
    assert plan["design"]["tool_adhesion"] == extended
    assert plan["design"]["rate_friction"] == sl.theta_design(EFFECTS["rate_friction"], settings.effect_bounds(
        "rate_friction"), settings.design_points)
    assert plan["narrowed"] == {"tool_adhesion": "tool_adhesion.gamma_a: no run measured at or above 0.75"}
    assert "narrowed" not in _plan("soil", [], REFERENCE, settings, {})
