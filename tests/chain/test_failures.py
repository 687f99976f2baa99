"""A DEM point that blows up is a failed point with its reason, not a failed workflow; the
regression then refuses to fit when too few points are left, naming them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from soilcal.chain import sources
from soilcal.chain.stage import fit_stage
from soilcal.config.load import load_soil
from soilcal.errors import InputError, SimulationError

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture()
def cinnamon():
    return load_soil(ROOT / "config/soils/cinnamon-soil.yaml", ROOT / "resources")


def test_a_blow_up_is_written_as_a_failed_point(monkeypatch, tmp_path, cinnamon):
    import soilcal.dem.scenarios.base as base

    def boom(*a, **k):
        raise SimulationError("step 812: particle 17 moved 3.2 radii in one step (time step too large?)")

    monkeypatch.setattr(base, "run_replicates", boom)
    stage = cinnamon.stage("bbd")
    spec = sources.point_spec(cinnamon, stage, {"A": 0.11, "B": 0.38, "C": 0.54}, run=4, seed=7)
    df = sources.run_point(spec, tmp_path / "4.csv", threads=1)
    back = pd.read_csv(tmp_path / "4.csv")
    assert list(back["status"]) == ["failed"] and np.isnan(back["value"].iloc[0])
    assert "SimulationError: step 812: particle 17" in back["error"].iloc[0]
    assert int(back["seed"].iloc[0]) == 7 and back["f:A"].iloc[0] == 0.11
    assert list(df.columns[: len(sources.RUN_COLUMNS)]) == sources.RUN_COLUMNS


def test_too_few_points_left_refuses_the_fit_naming_them(cinnamon):
    """17-run Box-Behnken, 10 quadratic terms: with 8 failed points only 9 remain, fewer
    than the 10 terms plus one residual degree of freedom."""
    from soilcal.doe.designs import box_behnken, coded_to_actual

    stage = dict(cinnamon.stage("bbd"), table_coding="actual", table="responses.csv")
    stage.pop("printed", None)
    coded = box_behnken(3, 5)
    lo = [stage["factors"][s]["low"] for s in "ABC"]
    hi = [stage["factors"][s]["high"] for s in "ABC"]
    act = coded_to_actual(coded, lo, hi)
    table = pd.DataFrame(act, columns=list("ABC"))
    table.insert(0, "run", np.arange(1, 18))
    table["stacking_angle"] = 27.0 + coded[:, 0] + 0.5 * coded[:, 1] ** 2
    table["error"] = ""
    failed = [2, 3, 5, 7, 11, 13, 14, 16]
    table.loc[table["run"].isin(failed), "stacking_angle"] = np.nan
    table.loc[table["run"] == 11, "error"] = "stacking_angle: SimulationError: blow-up at step 40"
    with pytest.raises(InputError) as err:
        fit_stage(stage, table)
    msg = str(err.value)
    assert "at least 11 design points" in msg and "got '9; without a response:" in msg
    assert "run 11: stacking_angle: SimulationError: blow-up at step 40" in msg
    assert "run 2: no response" in msg
    # one point fewer failed: 10 points, still no residual degree of freedom for 10 terms
    table.loc[table["run"] == 2, "stacking_angle"] = 27.0
    with pytest.raises(InputError):
        fit_stage(stage, table)
    table.loc[table["run"] == 3, "stacking_angle"] = 27.0
    fits = fit_stage(stage, table)
    assert fits[0].full.df_resid == 1
