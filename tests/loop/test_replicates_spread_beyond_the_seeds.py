"""Stones within replicates in a table without an SD column.  Each condition's replicate rows
(test days) are judged against their own scatter (:func:`soilcal.loop.diagnose.replicate_residuals`),
so a stone met in some replicates and not in others widens exactly the scatter the rows' mean is
judged against: the rows read as within their uncertainty, or as a uniform bias.  What is true
is that the replicates spread beyond the DEM's seed scatter, which a uniform bias (moving every
replicate alike) does not cause: the verdict and ``loop_summary.csv`` say so.

Construction (the stand-in blade, 1 % relative seed scatter, 8 conditions x 3 days, one force):
each row the mean of 3 repeats of the model with 2 % instrument noise, so a right model's
replicates scatter sqrt(1^2 + 2^2) / sqrt(3) = 1.3 % about their mean; stones raise 30 % of the
rows, drawn at random, by 20-30 %: a relative variance 0.3 x 0.7 x 0.25^2 beside it, 11.5 %
(9 times the seed scatter); a uniform 10 % offset adds none."""

from __future__ import annotations

from dataclasses import replace

import pytest

from soilcal.loop import core
from soilcal.loop import standin as S
from soilcal.loop import synthesize as sy

REF = {"tool_speed": 1.75, "working_depth": 0.1}


def _no_sd_campaign(disturbances, seed):
    grid = [dict(g, day=f"d{j}") for g in S.grid(seed, 8) for j in range(3)]
    conds = S.conditions(grid, measures=("horizontal_force_N",))
    table = sy.synthesize(conds, S.base_params, S.simulate, {}, REF, disturbances, noise=0.02, seed=seed)
    conds = [replace(c, responses=tuple(dict(r, measured_sd=None, n=None) for r in c.responses))
             for c in sy.with_measured(conds, table)]
    return core.run_inprocess("bin", conds, S.base_params, S.simulate, core.Settings(reference=REF, bootstrap=0))


@pytest.mark.parametrize("seed", [5, 1])
def test_stones_within_replicates_are_said_to_spread_beyond_the_seeds(seed):
    out = _no_sd_campaign({"stones": {"fraction": 0.3, "low": 0.2, "high": 0.3}}, seed)
    v = out.verdict
    assert "the replicate rows (no measured SD) scatter" in v, v
    pct = float(v.split("the replicate rows (no measured SD) scatter ")[1].split(" %")[0])
    ratio = float(v.split("about their conditions' means, ")[1].split(" times")[0])
    assert 6.0 < pct < 20.0 and ratio > 4.0, (pct, ratio)  # 11.5 % and 9 by construction
    assert "throughout, a uniform bias" not in v, v
    method = str(out.summary.iloc[0]["nuisance_method"])
    assert "the uniform bias" not in method, method
    assert "the replicate rows (no measured SD) scatter" in str(out.summary.iloc[0]["verdict"])


def test_a_uniform_offset_of_the_same_replicates_is_still_a_uniform_bias():
    out = _no_sd_campaign({"stones": {"fraction": 1.0, "low": 0.1, "high": 0.1}}, 3)
    assert "the replicate rows (no measured SD) scatter" not in out.verdict, out.verdict
    assert "% above the model throughout, a uniform bias" in out.verdict, out.verdict
