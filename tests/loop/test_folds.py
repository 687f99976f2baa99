"""The held-out folds of a table with test days: a column that identifies test days, sessions
or groups of replicates groups them, declared (``quantity: day``) or recognised by its name
(``soilcal.loop.core.fold_grouping``), and the report says which grouping was used."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from soilcal.loop import core, files
from soilcal.loop import select as sl
from soilcal.loop import standin as S
from soilcal.loop import synthesize as sy

REFERENCE = {"tool_speed": 1.75, "working_depth": 0.1, "moisture_content": 16.0}


def _moisture_per_day(seed):
    """Eighteen blade tests on six test days (three a day), the soil's moisture prepared once
    per day (drawn in 8-24 %), as a soil bin is wetted the evening before a test day."""
    rows = S.grid(seed, 18, moisture=True)
    rng = np.random.default_rng(seed + 100)
    per_day = {f"d{k}": float(rng.uniform(8, 24)) for k in range(6)}
    for r in rows:
        r["moisture_content"] = per_day[r["day"]]
    return S.conditions(rows)


def _undeclared(conds, column="day"):
    """The conditions as a table whose day column is a plain label (``ignore: true``, no
    ``quantity: day``), renamed ``column``."""
    out = []
    for c in conds:
        cov = {(column if k == "day" else k): v for k, v in c.covariates.items()}
        out.append(replace(c, covariates=cov, quantities={k: v for k, v in c.quantities.items() if k != "day"},
                           quantity_columns={k: v for k, v in c.quantity_columns.items() if k != "day"}))
    return out


@pytest.mark.parametrize("seed", [4, 5])
def test_an_offset_between_test_days_is_not_named_as_a_moisture_effect_with_an_undeclared_day_column(seed):
    # no library effect is hidden: only an offset per test day (SD 10 %) and 2 % noise.  The
    # moisture changes from day to day only, so the days' offsets follow the moisture by
    # chance; held out one test at a time, the other two tests of the day carried the day's
    # level into the fit, and moisture_cohesion was named ("explained by moisture_cohesion" for
    # these two seeds, 4 of 20 seeds in all) though the table holds no moisture effect
    conds = _moisture_per_day(seed)
    table = sy.synthesize(conds, S.base_params, S.simulate, {}, REFERENCE, {"day_offset": {"sd": 0.1}}, noise=0.02,
                          seed=seed + 10)
    out = core.run_inprocess("user", sy.with_measured(_undeclared(conds), table), S.base_params, S.simulate,
                             core.Settings(reference=REFERENCE, bootstrap=0))
    assert out.chosen == [], out.verdict
    assert out.verdict.startswith("unexplained: the residual follows day"), out.verdict
    assert "no effect of the library could be tried through it" in out.verdict
    assert "moisture_cohesion not tried: moisture_content has one value on each `day` group" in out.verdict
    assert out.fold_by == "day"
    folds = out.summary["folds"].iloc[0]
    assert folds.startswith("one fold per value of `day` (6 groups; named as a test-day"), folds
    text = files.report("user", out, [{"candidates": out.candidates, "reference": {}, "settings": {}}])
    assert "Held-out groups: one fold per value of `day` (6 groups" in text


def _frame(cols: dict, quantity_cols=None):
    n = len(next(iter(cols.values())))
    base = {"measurement": "t", "row": np.arange(1, n + 1), "measure": "f", "measured": 1.0,
            "relative_residual": 0.0, "simulation": [f"s{i}" for i in range(n)]}
    return pd.DataFrame({**base, **{f"cov:{k}": v for k, v in cols.items()}})


@pytest.mark.parametrize("name", ["day", "Day", "test day", "Test-Day", "session", "batch", "date"])
def test_a_column_named_as_a_test_day_or_session_groups_the_folds(name):
    res = _frame({name: ["a", "a", "b", "b", "c", "c"], "speed": [1, 2, 3, 4, 5, 6]})
    col, text = core.fold_grouping(core.Settings(), {}, res)
    assert col == name and "(3 groups; named as a test-day, session or replicate-group column)" in text
    # a declared group column comes before a named one, with two groups
    res2 = res.assign(**{"cov:plot": ["p1", "p1", "p1", "p2", "p2", "p2"]})
    col, text = core.fold_grouping(core.Settings(), {"plot": "group"}, res2)
    assert col == "plot" and "(2 groups; declared quantity: group)" in text
    # loop.fold_by wins over both
    col, text = core.fold_grouping(core.Settings(fold_by="speed"), {"plot": "group"}, res2)
    assert col == "speed" and "as loop.fold_by sets" in text


def test_a_single_test_day_or_no_day_column_folds_by_condition_and_says_why():
    res = _frame({"day": ["d1"] * 6, "speed": [1, 2, 3, 4, 5, 6]})
    col, text = core.fold_grouping(core.Settings(), {}, res)
    assert col is None and "`day` has one value on every usable row" in text
    # a column named like a day but declared as another quantity (a position) is no group
    res = _frame({"block": [1.0, 2.0, 3.0, 1.0, 2.0, 3.0]})
    col, text = core.fold_grouping(core.Settings(), {"block": "position"}, res)
    assert col is None and "no test-day, session or group column" in text


def test_numbered_test_days_are_tested_as_groups_not_as_a_trend():
    # six test days numbered 1-6, three tests a day, each day's level off by its own amount
    # (+8, -6, +3, -9, +5, -1 %): a group structure; read as a number, the day got a trend and
    # a curvature test (a drift over the days) and no group test, which is a different question
    from soilcal.loop.diagnose import diagnose

    level = {1: 0.08, 2: -0.06, 3: 0.03, 4: -0.09, 5: 0.05, 6: -0.01}
    days = [d for d in level for _ in range(3)]
    noise = np.tile([0.004, -0.003, -0.001], 6)
    res = pd.DataFrame({"measurement": "bin", "row": np.arange(1, 19), "measure": "f",
                        "relative_residual": [level[d] for d in days] + noise, "cov:day": days})
    diag = diagnose(res, {})
    tests = diag[diag["covariate"] == "day"]
    assert list(tests["test"]) == ["group"], tests
    assert tests["significant"].iloc[0] and tests["r2"].iloc[0] > 0.99
    # declared as a number of its own (a position along the bin), a column named day keeps its trend
    diag = diagnose(res, {"day": "position"})
    assert "trend" in set(diag[diag["covariate"] == "day"]["test"])


def test_candidates_rejected_over_few_day_groups_say_how_few_they_are():
    # twelve blade tests on three test days with a weak rate effect (beta 0.1) under 4 % noise:
    # held out a day at a time; three days are fewer than select.MIN_POOLED_FOLDS, so the paired
    # test is over the three groups, with two degrees of freedom, and the verdict says so beside
    # the rejected candidate, as does the candidate's reason
    assert sl.MIN_POOLED_FOLDS > 3
    reference = {"tool_speed": 1.75, "working_depth": 0.1}
    conds = S.conditions(S.grid(3, 12, days=3))
    table = sy.synthesize(conds, S.base_params, S.simulate, {"rate_friction": {"beta": 0.1}}, reference, {},
                          noise=0.04, seed=13)
    out = core.run_inprocess("user", sy.with_measured(conds, table), S.base_params, S.simulate,
                             core.Settings(reference=reference, bootstrap=0))
    assert out.chosen == [] and "candidates rejected" in out.verdict, out.verdict
    assert "(paired t-test over the folds, 2 df: p = " in out.verdict, out.verdict
    assert out.verdict.endswith("the rows were held out by `day`, 3 groups, and the paired test that rejected a "
                                "candidate had 2 degrees of freedom over them; it passes only a large gain (more "
                                "groups decide; loop.fold_by sets the grouping)"), out.verdict


def test_a_declared_day_column_comes_before_a_column_named_like_one_and_two_named_groups_are_none():
    res = _frame({"day": ["a", "a", "b", "b", "c", "c"], "batch": ["x", "y", "x", "y", "x", "y"]})
    # declared days (3 groups) before the named batch column (2 groups)
    col, text = core.fold_grouping(core.Settings(), {"day": "day"}, res)
    assert col == "day" and "declared quantity: day" in text
    # undeclared, the two-valued batch column is no grouping (a paired test over two folds has
    # one degree of freedom); the three-valued day column is
    col, _ = core.fold_grouping(core.Settings(), {}, res)
    assert col == "day"
    col, text = core.fold_grouping(core.Settings(), {}, res.drop(columns="cov:day"))
    assert col is None and "one fold per measured condition" in text


@pytest.mark.parametrize("name", ["group", "block", "series"])
def test_a_moisture_set_per_treatment_group_is_tried(name):
    # a true moisture effect (c_w 0.03, 2 % noise, no offset between groups), the moisture set
    # once per level of a column named `group`: the experiment's own treatment, not a test
    # session with a level of its own, so the effect is tried and named
    rows = S.grid(4, 18, moisture=True)
    rng = np.random.default_rng(104)
    per = {f"d{k}": float(rng.uniform(8, 24)) for k in range(6)}
    for r in rows:
        r["moisture_content"] = per[r["day"]]
    conds = S.conditions(rows)
    table = sy.synthesize(conds, S.base_params, S.simulate, {"moisture_cohesion": {"c_w": 0.03}}, REFERENCE, {},
                          noise=0.02, seed=14)
    out = core.run_inprocess("user", sy.with_measured(_undeclared(conds, name), table), S.base_params, S.simulate,
                             core.Settings(reference=REFERENCE, bootstrap=0))
    assert out.chosen == ["moisture_cohesion"], out.verdict
    assert out.theta["moisture_cohesion.c_w"] == pytest.approx(0.03, rel=0.25)


def test_day_folds_hold_their_conditions_as_the_units_of_the_paired_test():
    # rows 0-1: one test measured twice on day d1; row 2 another test on d1; row 3 a test on d2;
    # row 4 a test with no day, a fold of its own.  Folds by day (first seen first): d1 (rows
    # 0, 1, 2), d2 (3), the dayless test (4); the conditions within them: (0, 1), (2), (3), (4)
    obs = pd.DataFrame({"simulation": ["s1", "s1", "s2", "s3", "s4"],
                        "cov:day": ["d1", "d1", "d1", "d2", None]})
    folds = sl._folds(obs, "day")
    assert [f.tolist() for f in folds.held_out] == [[0, 1, 2], [3], [4]]
    assert [u.tolist() for u in folds.units] == [[0, 1], [2], [3], [4]]
    # by condition (no fold_by), every fold is one condition: no units
    by_condition = sl._folds(obs, None)
    assert [f.tolist() for f in by_condition.held_out] == [[0, 1], [2], [3], [4]]
    assert by_condition.units is None
