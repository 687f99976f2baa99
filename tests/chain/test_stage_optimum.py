"""The optimisation settings of a stage's ``optimise`` block reach the search: the particle
swarm of ``method: pso`` runs with the block's particles, iterations and repeats (the best of
``repeats`` seeded swarms), and each left-out setting takes the default the schema states."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from bbd_stand_in import box_behnken_3
from soilcal import optimise
from soilcal.chain.stage import optimum_frames


def _stage(pso: dict | None) -> dict:
    opt = {"method": "pso", "model": "full", "cases": [{"id": "angle", "goals": {"angle": {"goal": "target", "value": 31.0}}}]}
    if pso is not None:
        opt["pso"] = pso
    return {"id": "bbd", "kind": "box_behnken", "center_points": 3,
            "factors": {"A": {"parameter": "a", "low": 0.1, "high": 0.3},
                        "B": {"parameter": "b", "low": 2.0, "high": 6.0},
                        "C": {"parameter": "c", "low": 0.4, "high": 0.8}},
            "responses": [{"id": "angle", "name": "Repose angle", "unit": "deg"}], "optimise": opt}


def _table() -> pd.DataFrame:
    df, x = box_behnken_3()
    a, b, c = x.T
    scatter = np.linspace(-0.2, 0.2, len(x))[np.argsort(np.arange(len(x)) * 7 % len(x))]
    df["angle"] = 30 + 1.5 * a + 0.8 * b - 1.1 * c + 0.6 * a * b + 0.9 * a * a - 0.5 * c * c + scatter
    return df


@pytest.fixture
def calls(monkeypatch):
    seen = []
    real = optimise.pso_optimise

    def recording(objective, bounds, **kw):
        seen.append(kw)
        return real(objective, bounds, **kw)

    monkeypatch.setattr(optimise, "pso_optimise", recording)
    return seen


def test_pso_runs_with_the_blocks_repeats(calls):
    out = optimum_frames(_stage({"particles": 12, "iterations": 15, "repeats": 3}), _table(), {}, seed=5)["optimum"]
    assert calls == [{"particles": 12, "iterations": 15, "repeats": 3, "seed": 5}]
    pso = out[out["method"] == "pso"]
    assert len(pso) == 1 and np.isfinite(float(pso["objective"].iloc[0]))


def test_pso_settings_left_out_take_the_documented_defaults(calls):
    optimum_frames(_stage(None), _table(), {}, seed=0)
    assert calls == [{"particles": 50, "iterations": 200, "repeats": 1, "seed": 0}]


def test_a_case_whose_target_has_no_value_is_not_optimised_and_says_which_and_why(tmp_path):
    """A case aiming at a target with no value gets one row, method ``none``, whose note names
    the target and the reason its targets table gives (the table as ``targets.csv`` holds it:
    the cohesive soil's 5 % angle was lost in the paper's extraction); the other case is
    optimised as usual."""
    from soilcal.chain.files import read_targets

    stage = _stage(None)
    stage["optimise"]["method"] = "desirability"
    stage["optimise"]["cases"] = [
        {"id": "mc05", "goals": {"angle": {"goal": "target", "target": "angle_mc05"}}},
        {"id": "mc10", "goals": {"angle": {"goal": "target", "target": "angle_mc10"}}}]
    tcsv = tmp_path / "targets.csv"
    pd.DataFrame({"target_id": ["angle_mc05", "angle_mc10"], "value": [np.nan, 31.0],
                  "source": ["not available", "measurement"],
                  "note": ["no photo group and no printed value: Table 1 lost in extraction", ""]}).to_csv(tcsv, index=False)
    out = optimum_frames(stage, _table(), read_targets(tcsv), seed=0)["optimum"]
    lost = out[out["case"] == "mc05"]
    assert list(lost["method"]) == ["none"]
    assert lost["note"].iloc[0] == ("target value not available: angle_mc05 (no photo group and no printed "
                                    "value: Table 1 lost in extraction)")
    assert (out.loc[out["case"] == "mc10", "method"] == "desirability").any()
    # a goal naming a target the table does not list says so
    stage["optimise"]["cases"] = [{"id": "x", "goals": {"angle": {"goal": "target", "target": "angle_mc99"}}}]
    out = optimum_frames(stage, _table(), read_targets(tcsv), seed=0)["optimum"]
    assert out["note"].iloc[0] == "target value not available: angle_mc99 (no such target)"
