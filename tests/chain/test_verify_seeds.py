"""The second verification stage (soilcal.chain.verify.stein_seeds, seeds_frame): Stein's
two-stage rule against its closed form and t tables, and which cases take more seeds."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from soilcal.chain.sources import RUN_COLUMNS
from soilcal.chain.verify import (SEEDS_COLUMNS, case_seeds, first_stage_seeds, most_seeds, seed_note, seeds_frame,
                                  stein_seeds, two_stage, verify_settings)
from soilcal.config.load import load_soil
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]

#: two-sided 95 % t quantiles (Student's t tables: 3 df 3.182, 7 df 2.365, 1 df 12.706)
T975 = {1: 12.706, 3: 3.182, 7: 2.365}


@pytest.fixture(scope="module")
def cinnamon() -> dict:
    return copy.deepcopy(load_soil(ROOT / "config" / "soils" / "cinnamon-soil.yaml", ROOT / "resources").data)


def _soil(base: dict, **verification) -> dict:
    sim = dict(base.get("simulation") or {}, verification=verification)
    return dict(base, simulation=sim)


# --------------------------------------------------------------------------- Stein's rule


@pytest.mark.parametrize("sd, n0, d", [(1.68, 4, 0.55), (0.5, 4, 0.6), (2.0, 8, 0.3), (1.0, 2, 1.0)])
def test_stein_seeds_is_the_closed_form_with_the_tabled_t(sd, n0, d):
    # n = max(n0, ceil((t_{0.975, n0-1} sd / d)^2)); the tables' t is rounded to 3 decimals, so
    # the count may differ by one only where (t sd / d)^2 lies within that rounding of an integer
    want = max(n0, math.ceil((T975[n0 - 1] * sd / d) ** 2))
    got = stein_seeds(sd, n0, d)
    assert abs(got - want) <= 1 and got >= n0
    # e.g. the cinnamon verification's SD 1.68 over 4 seeds against its band 0.55 deg: 95 seeds
    if (sd, n0, d) == (1.68, 4, 0.55):
        assert got == 95


def test_stein_interval_is_no_wider_than_the_half_width():
    # the count it gives makes t sd0 / sqrt(n) <= d, and one seed fewer would not (above n0)
    for sd, n0, d in [(1.68, 4, 0.55), (3.0, 4, 0.7), (0.9, 8, 0.2)]:
        n = stein_seeds(sd, n0, d)
        assert T975[n0 - 1] * sd / math.sqrt(n) <= d * 1.001
        if n > n0:
            assert T975[n0 - 1] * sd / math.sqrt(n - 1) > d * 0.999


def test_stein_seeds_without_a_scatter_keeps_the_first_stage():
    assert stein_seeds(np.nan, 4, 0.5) == 4
    assert stein_seeds(1.0, 1, 0.5) == 1
    assert stein_seeds(1.0, 4, 0.0) == 4
    assert stein_seeds(0.0, 4, 0.5) == 4  # no scatter: the first stage already decides


def test_stein_coverage_by_simulation():
    # the procedure's promise, checked by drawing: with n0 = 4 first values of SD 2 and the
    # half-width 1, the final mean of n values lies within 1 of the true mean in at least 95 %
    # of 4000 repetitions (Stein 1945), whatever the true SD
    rng = np.random.default_rng(7)
    hits = 0
    for _ in range(4000):
        first = rng.normal(10.0, 2.0, 4)
        n = stein_seeds(float(first.std(ddof=1)), 4, 1.0)
        allv = np.concatenate([first, rng.normal(10.0, 2.0, n - 4)])
        hits += abs(allv.mean() - 10.0) <= 1.0
    assert hits / 4000 >= 0.95


# --------------------------------------------------------------------------- settings


def test_settings_default_to_one_stage(cinnamon):
    soil = _soil(cinnamon)
    assert verify_settings(soil)["max_replicates"] == 4
    assert (first_stage_seeds(soil), most_seeds(soil), two_stage(soil)) == (4, 4, False)
    soil = _soil(cinnamon, replicates=3, max_replicates=12)
    assert (first_stage_seeds(soil), most_seeds(soil), two_stage(soil)) == (3, 12, True)


def test_max_replicates_below_replicates_is_refused(tmp_path, cinnamon):
    import yaml

    text = (ROOT / "config" / "soils" / "cinnamon-soil.yaml").read_text()
    data = yaml.safe_load(text)
    data["simulation"]["verification"] = {"replicates": 6, "max_replicates": 5}
    path = tmp_path / "cinnamon-soil.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    with pytest.raises(InputError) as err:
        load_soil(path, ROOT / "resources")
    assert err.value.field == "simulation.verification.max_replicates"
    assert "at least simulation.verification.replicates (6)" in str(err.value.expected)


# --------------------------------------------------------------------------- which cases take more


def _runs(values, response="stacking_angle", seed0=11082):
    out = []
    for k, v in enumerate(values):
        row = {c: "" for c in RUN_COLUMNS} | {"stage": "bbd", "run": k, "response": response, "value": v,
                                              "sd": np.nan, "n": 1, "status": "ok", "error": "",
                                              "seed": seed0 + k, "preset": "quick"}
        out.append(pd.DataFrame([row], columns=RUN_COLUMNS))
    return out


def _stage():
    return {"id": "bbd", "factors": {"A": {"parameter": "soil_soil_rolling_friction"}},
            "responses": [{"id": "stacking_angle", "unit": "deg"}],
            "optimise": {"cases": [
                {"id": "near", "goals": {"stacking_angle": {"goal": "target", "target": "t30"}}},
                {"id": "far", "goals": {"stacking_angle": {"goal": "target", "target": "t30"}}},
                {"id": "met", "goals": {"stacking_angle": {"goal": "target", "target": "t30"}}},
            ]}}


OPTIMUM = pd.DataFrame({"case": ["near", "far", "met"], "method": ["desirability"] * 3, "A": [0.1, 0.1, 0.1],
                        "stacking_angle": [30.0, 30.0, 30.0], "calibrated": [True, True, True]})
TARGETS = {"t30": {"value": 30.0, "source": "config"}}


def test_a_miss_within_the_seed_scatter_takes_steins_seeds(cinnamon):
    soil = _soil(cinnamon, replicates=4, max_replicates=60)
    near = [29.0, 31.0, 28.0, 29.4]  # mean 29.35, -2.2 %; SD 1.26, two standard errors 1.26 > 0.65
    far = [33.0, 33.1, 32.9, 33.0]  # mean 33.0, +10 %, SD 0.08: decided
    met = [30.1, 29.8, 30.3, 30.0]  # within 2 %
    df = seeds_frame(soil, _stage(), OPTIMUM, TARGETS, {"near": _runs(near), "far": _runs(far), "met": _runs(met)},
                     "quick")
    assert list(df.columns) == SEEDS_COLUMNS
    rows = df.set_index("case")
    sd = float(np.std(near, ddof=1))
    want = math.ceil((T975[3] * sd / 0.6) ** 2)  # band 2 % of 30 = 0.6
    assert rows.loc["near", "undecided"] and abs(int(rows.loc["near", "stein_seeds"]) - want) <= 1
    assert int(rows.loc["near", "seeds"]) == int(rows.loc["near", "stein_seeds"]) and not rows.loc["near", "capped"]
    assert not rows.loc["far", "undecided"] and int(rows.loc["far", "seeds"]) == 4
    assert "decided" in rows.loc["far", "note"]
    assert not rows.loc["met", "undecided"] and int(rows.loc["met", "seeds"]) == 4
    assert case_seeds(df) == {"near": int(rows.loc["near", "seeds"]), "far": 4, "met": 4}


def test_the_cap_limits_the_seeds_and_is_said(cinnamon):
    soil = _soil(cinnamon, replicates=4, max_replicates=8)
    df = seeds_frame(soil, _stage(), OPTIMUM, TARGETS, {"near": _runs([29.0, 31.0, 28.0, 29.4])}, "quick")
    row = df.set_index("case").loc["near"]
    assert int(row["seeds"]) == 8 and row["capped"] and int(row["stein_seeds"]) > 8
    assert "capped at simulation.verification.max_replicates 8" in row["note"]
    note = seed_note(df[df["case"] == "near"])
    assert note.startswith("two-stage verification: the first 4 seeds left stacking_angle within seed scatter")
    assert "8 ran (capped" in note
    # a case that took no more seeds gets no note
    assert seed_note(df[df["case"] == "far"]) == ""


def test_the_design_stages_params_leave_the_verification_out(cinnamon):
    # soilcal.chain.plan.dem_context: the verification's seeds are read by the verification's
    # rules alone (verification=True), so raising them re-runs no design stage
    from soilcal.chain.plan import dem_context

    soil = _soil(cinnamon, replicates=4, max_replicates=12)
    assert "verification" not in dem_context(soil)["simulation"]
    assert dem_context(soil, verification=True)["simulation"]["verification"] == {"replicates": 4,
                                                                                  "max_replicates": 12}
    assert dem_context(soil) == dem_context(_soil(cinnamon, replicates=6))


# --------------------------------------------------------------------------- which responses run on


def _two_response_stage():
    return {"id": "bbd", "factors": {"A": {"parameter": "soil_soil_rolling_friction"}},
            "responses": [{"id": "static_angle", "unit": "deg"}, {"id": "dynamic_angle", "unit": "deg"}],
            "optimise": {"cases": [{"id": "layer", "goals": {
                "static_angle": {"goal": "target", "target": "s30"},
                "dynamic_angle": {"goal": "target", "target": "d45"}}}]}}


def test_the_second_stage_runs_only_the_undecided_responses(cinnamon):
    from soilcal.chain.verify import second_stage_responses

    soil = _soil(cinnamon, replicates=4, max_replicates=40)
    opt = pd.DataFrame({"case": ["layer"], "method": ["desirability"], "A": [0.1], "static_angle": [30.0],
                        "dynamic_angle": [45.0], "calibrated": [True]})
    targets = {"s30": {"value": 30.0, "source": "config"}, "d45": {"value": 45.0, "source": "config"}}
    runs = _runs([29.0, 31.0, 28.0, 29.4], "static_angle") + _runs([45.1, 44.8, 45.3, 45.0], "dynamic_angle")
    df = seeds_frame(soil, _two_response_stage(), opt, targets, {"layer": runs}, "quick")
    rows = df.set_index("response")
    # the static mean 29.35 misses its band (0.6) by less than two standard errors: undecided;
    # the dynamic mean 45.05 is within 2 % of 45: met
    assert rows.loc["static_angle", "undecided"] and not rows.loc["dynamic_angle", "undecided"]
    assert second_stage_responses(df, "layer") == ["static_angle"]
    # a case with nothing undecided: every response (None)
    met = _runs([30.1, 29.8, 30.3, 30.0], "static_angle") + _runs([45.1, 44.8, 45.3, 45.0], "dynamic_angle")
    assert second_stage_responses(seeds_frame(soil, _two_response_stage(), opt, targets, {"layer": met}, "quick"),
                                  "layer") is None


def test_a_verification_spec_of_some_responses_simulates_only_those():
    from soilcal.chain.verify import verification_spec
    from soilcal.config.load import load_soil as load

    soil = load(ROOT / "config" / "soils" / "xinjiang-vineyard.yaml", ROOT / "resources")
    stage = next(s for s in soil.data["stages"] if s["id"] == "bbd")
    stage = dict(stage, source="dem")
    syms = list(stage["factors"])
    opt = pd.DataFrame({"case": ["upper"], "method": ["desirability"], "calibrated": [True],
                        **{s: [float(stage["factors"][s].get("centre", 0.5 * (stage["factors"][s]["low"]
                                                                                + stage["factors"][s]["high"])))]
                           for s in syms}})
    every = verification_spec(soil, stage, opt, "upper", 5)
    assert set(every["responses"]) == {"static_angle", "dynamic_angle"}
    some = verification_spec(soil, stage, opt, "upper", 5, responses=["static_angle"])
    assert list(some["responses"]) == ["static_angle"]
    with pytest.raises(InputError, match="goals"):
        verification_spec(soil, stage, opt, "upper", 5, responses=["no_such_angle"])
    # the same seed and set: only the responses differ
    assert {k: v for k, v in some.items() if k != "responses"} == {k: v for k, v in every.items() if k != "responses"}
