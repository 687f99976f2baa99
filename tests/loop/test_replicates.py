"""Replicate rows: a soil-bin table that repeats each condition (three rows per speed, each
with its own measured value and no `sd`/`n` columns).  The replicates of a condition share
its simulated mean and whatever the condition carries beyond the model, so the condition is
the unit of the diagnosis; the expected rates and values follow from the constructions here
(a null without structure, a hidden rate effect of known parameter)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from soilcal.loop import core
from soilcal.loop import standin as S
from soilcal.loop.diagnose import diagnose
from soilcal.loop.effects import apply_all
from soilcal.loop.residuals import observations


def _null_table(rng, conditions=8, repeats=3, sd_condition=0.05, sd_repeat=0.03):
    """Relative residuals without structure: a deviation per condition (normal, SD
    ``sd_condition``: the bed prepared for it, the seeds' error of its simulated mean) shared
    by its ``repeats`` rows, and a deviation per row (SD ``sd_repeat``)."""
    speed = rng.uniform(0.5, 3.0, conditions)
    dev = rng.normal(0.0, sd_condition, conditions)
    rows = []
    for i in range(conditions):
        for j in range(repeats):
            rows.append({"measurement": "bin", "row": i * repeats + j + 1, "measure": "horizontal_force_N",
                         "simulation": f"s{i}", "cov:speed_ms": speed[i],
                         "relative_residual": dev[i] + rng.normal(0.0, sd_repeat)})
    d = pd.DataFrame(rows)
    return d.assign(measured=100.0 * (1.0 + d["relative_residual"]), simulated_mean=100.0)


def test_repeats_of_a_condition_do_not_make_structure_out_of_none():
    # 80 tables of 8 conditions x 3 repeats without structure: the family of bias, trend and
    # curvature tests (Holm, alpha 0.05) may flag about 5 % of them; counted as 24 independent
    # rows, the conditions' own deviations looked like a trend or a bias in about half
    rng = np.random.default_rng(11)
    flagged = 0
    for _ in range(80):
        d = diagnose(_null_table(rng), {"speed_ms": "tool_speed"})
        flagged += bool(d.loc[d["test"].isin(["bias", "trend", "curvature"]), "significant"].any())
    assert flagged / 80 <= 0.10, flagged


def test_a_condition_mean_is_one_observation_of_the_trend():
    # the same residual entered as 6 repeats of each condition (no scatter between them) or
    # once per condition: the same condition means, the same trend test
    rng = np.random.default_rng(5)
    once = _null_table(rng, conditions=8, repeats=1, sd_repeat=0.0)
    six = pd.concat([once.assign(row=once["row"] * 10 + k) for k in range(6)], ignore_index=True)
    a, b = diagnose(once, {"speed_ms": "tool_speed"}), diagnose(six, {"speed_ms": "tool_speed"})
    for test in ("bias", "trend", "curvature"):
        pa = float(a.loc[a["test"] == test, "p"].iloc[0])
        pb = float(b.loc[b["test"] == test, "p"].iloc[0])
        assert np.isclose(pa, pb, rtol=1e-9), (test, pa, pb)
        assert int(b.loc[b["test"] == test, "n"].iloc[0]) == 8


def test_a_day_that_varies_among_the_repeats_is_still_tested_on_them():
    # each of 6 conditions measured on day 1 and day 2, day 2 reading 10 % higher: the day
    # varies among a condition's repeats, so its group test compares them (12 tests, 2 levels)
    rows = []
    for i in range(6):
        for day, off in (("1", 0.0), ("2", 0.10)):
            rows.append({"measurement": "bin", "row": len(rows) + 1, "measure": "horizontal_force_N",
                         "simulation": f"s{i}", "cov:day": day, "cov:speed_ms": 0.5 + 0.5 * i,
                         "relative_residual": off + 0.01 * ((i * 7) % 3 - 1)})
    res = pd.DataFrame(rows)
    d = diagnose(res.assign(measured=100.0 * (1.0 + res["relative_residual"]), simulated_mean=100.0),
                 {"day": "day", "speed_ms": "tool_speed"})
    g = d[(d["test"] == "group") & (d["covariate"] == "day")]
    assert len(g) == 1 and int(g["n"].iloc[0]) == 12 and bool(g["significant"].iloc[0])
    t = d[(d["test"] == "trend") & (d["covariate"] == "speed_ms")]
    assert int(t["n"].iloc[0]) == 6 and not bool(t["significant"].iloc[0])


def _campaign(seed, repeats, hidden, sd_condition, sd_repeat=0.03, conditions=8):
    """Stand-in conditions at ``conditions`` speeds and depths, each entered ``repeats`` times
    with the model's value under ``hidden`` times a condition's deviation and a repeat's."""
    rng = np.random.default_rng(seed)
    base = [{"tool_speed": float(rng.uniform(0.5, 3.0)), "working_depth": float(rng.uniform(0.05, 0.15))}
            for _ in range(conditions)]
    conds = S.conditions([dict(q) for q in base for _ in range(repeats)])
    ref = core.mean_reference(observations(conds), {})
    dev = rng.normal(0.0, sd_condition, conditions)
    out = []
    for j, c in enumerate(conds):
        truth = S.forces(apply_all(hidden, S.base_params(c), c.quantities, ref, c.scenario), c.quantities)
        resp = tuple(dict(r, measured=float(t * (1 + dev[j // repeats]) * (1 + rng.normal(0.0, sd_repeat))))
                     for r, t in zip(c.responses, truth))
        out.append(replace(c, responses=resp))
    return out


def test_repeats_without_an_sd_column_are_the_measured_uncertainty():
    # 8 conditions x 3 repeats of the model's own values with 3 % noise per repeat and nothing
    # per condition: the repeats' scatter is the measured uncertainty, within which the
    # residual lies (a table of one row per condition with sd and n is judged so)
    out = core.run_inprocess("user", _campaign(3, 3, {}, sd_condition=0.0), S.base_params, S.simulate,
                             core.Settings(bootstrap=0))
    sc = out.diagnosis[out.diagnosis["test"] == "scatter"]
    assert len(sc) == 1 and int(sc["n"].iloc[0]) == 16  # 8 conditions x 2 measured forces
    assert out.verdict.startswith("consistent"), out.verdict


def test_a_rate_effect_measured_in_repeats_is_found_with_its_parameter():
    # rate_friction beta 0.2 hidden, 8 conditions x 3 repeats, 2 % per condition, 3 % per repeat
    out = core.run_inprocess("user", _campaign(1001, 3, {"rate_friction": {"beta": 0.2}}, sd_condition=0.02),
                             S.base_params, S.simulate, core.Settings(bootstrap=0))
    assert out.chosen == ["rate_friction"], out.verdict
    assert abs(out.theta["rate_friction.beta"] - 0.2) <= 0.25 * 0.2


def test_the_fit_interval_of_replicate_rows_is_that_of_their_condition_means():
    # a uniform scale s of the model (prediction 100 (1 + s)) fitted to 8 conditions x 3
    # repeats, each condition 10 % above with a deviation of its own (SD 5 %) shared by its
    # repeats (0.5 % apart): the repeats tell the condition's level, not s, so the interval is
    # that of the 8 condition means (Student t, 7 degrees of freedom), about twice as wide as
    # one that takes the 24 rows for independent observations
    from scipy import stats

    from soilcal.loop import select as sl

    rng = np.random.default_rng(7)
    dev = rng.normal(0.0, 0.05, 8)
    meas = np.array([100 * 1.1 * (1 + d + rng.normal(0.0, 0.005)) for d in dev for _ in range(3)])
    y0 = np.full(len(meas), 100.0)
    folds = sl.Folds([np.arange(3 * i, 3 * i + 3) for i in range(8)])
    m = sl.Model([sl.scale_data()], y0, meas)
    s = sl.score(m, sl.Model([], y0, meas), folds)
    lo, hi = s.ci["uniform_scale.s"]
    ratio = meas.reshape(8, 3).mean(axis=1) / 100 - 1  # each condition's own s
    tlo, thi = stats.t.interval(0.95, 7, loc=ratio.mean(), scale=stats.sem(ratio))
    assert (hi - lo) == pytest.approx(thi - tlo, rel=0.15), ((lo, hi), (tlo, thi))


def test_repeats_that_repeat_a_value_all_count_in_the_scatter_test():
    # three repeats of one force, rounded to whole newtons: 250, 250, 256 N against a
    # simulated 240 N (seed SD 3 N over 3 seeds).  Welch: mean 252, s^2 = (4 + 4 + 16) / 2 = 12,
    # se = sqrt(12 / 3 + 9 / 3) = sqrt(7), z = 12 / sqrt(7) = 4.5356; dof = 49 / (16 / 2 + 9 / 2)
    from soilcal.loop.diagnose import replicate_residuals

    d = pd.DataFrame({"simulation": ["k"] * 3, "measure": ["force"] * 3, "measured": [250.0, 250.0, 256.0],
                      "simulated_mean": [240.0] * 3, "simulated_sd": [3.0] * 3, "simulated_n": [3] * 3})
    z, dof = replicate_residuals(d)
    assert z == pytest.approx([12 / np.sqrt(7)], rel=1e-12)
    assert dof == pytest.approx([49 / (16 / 2 + 9 / 2)], rel=1e-12)


def test_three_tools_at_the_same_speeds_are_three_tests_not_repeats_of_one():
    # tools A, B, C (the stand-in's blade widths) each at 4 speeds x 2 depths, the model's own
    # values without noise: 24 conditions, each simulated with its own tool; taken as repeats of
    # 8 (the tool left out of the condition's key) B and C were run as A and read ~28 % off
    from soilcal.loop import synthesize as sy
    from soilcal.loop.residuals import simulation_key

    rows = [{"tool": t, "tool_speed": v, "working_depth": d} for t in "ABC" for v in (0.5, 1.0, 2.0, 3.0)
            for d in (0.06, 0.12)]
    conds = S.conditions(rows)
    assert len({simulation_key(c) for c in conds}) == 24
    table = sy.synthesize(conds, S.base_params, S.simulate, {}, {}, {}, noise=0.0, seed=1)
    out = core.run_inprocess("user", sy.with_measured(conds, table), S.base_params, S.simulate,
                             core.Settings(bootstrap=0))
    assert out.verdict.startswith("consistent"), out.verdict


def test_repeats_that_all_read_one_value_state_no_scatter():
    # two repeats rounded to whole newtons that read the same, 250 / 250 N against a simulated
    # 248.5 N: their sample SD is 0, no measured scatter, so no z of (250 - 248.5) / (seed SE
    # alone) flags a model 0.6 % off as scattering beyond the uncertainty
    from soilcal.loop.diagnose import replicate_residuals

    d = pd.DataFrame({"simulation": ["a", "a", "b", "b", "b"], "measure": ["force"] * 5,
                      "measured": [250.0, 250.0, 250.0, 250.0, 256.0],
                      "simulated_mean": [248.5, 248.5, 240.0, 240.0, 240.0], "simulated_sd": [0.6] * 2 + [3.0] * 3,
                      "simulated_n": [3] * 5})
    z, _ = replicate_residuals(d)
    assert z == pytest.approx([12 / np.sqrt(7)], rel=1e-12)  # only b's repeats (as the test above)


def _trend_effect(x):
    """A one-parameter effect whose change is linear in it: the prediction 100 (1 + t x) at a
    row with covariate x (a trend in x; t in [-1, 1], off at 0)."""
    from soilcal.loop import select as sl

    class Trend:
        name = "trend"
        null = {"t": 0.0}

        def theta_names(self):
            return ("t",)

    eff, bounds = Trend(), {"t": (-1.0, 1.0)}
    ts = np.array([[-1.0], [0.0], [1.0]])
    means = np.array([100.0 * (1.0 + t * x) for t in ts[:, 0]])
    return sl.EffectData(eff, bounds, sl.Surrogate(eff, bounds, ts, means), [{"t": t} for t in ts[:, 0]])


def test_replicate_rows_are_one_observation_in_the_information_criterion():
    # 8 conditions x 3 repeats with no trend: each condition deviates from the model by its own
    # 5 % (shared by its repeats, 0.5 % apart).  A trend parameter without effect lowers the
    # AICc of n = 8 condition means when n ln(SSE0/SSE1) > 3.733 (the penalty of K 1 -> 2 at
    # n = 8), i.e. when the F statistic on 1 and 6 degrees of freedom exceeds
    # 6 (exp(3.733/8) - 1) = 3.57: P = 0.108.  Taking the 24 rows for 24 observations the gain
    # is tripled against a smaller penalty (2.389 at n = 24): P(F > 0.63) = 0.46
    from scipy import stats

    from soilcal.loop import select as sl

    rng = np.random.default_rng(11)
    n_c, reps, hits, tables = 8, 3, 0, 120
    x = np.repeat(np.linspace(-0.5, 0.5, n_c), reps)
    y0 = np.full(n_c * reps, 100.0)
    obs = pd.DataFrame({"simulation": np.repeat([f"s{i}" for i in range(n_c)], reps), "measure": "F_N"})
    groups = sl.replicate_groups(obs)
    folds = sl.Folds([np.arange(reps * i, reps * i + reps) for i in range(n_c)])
    ed = _trend_effect(x)
    for _ in range(tables):
        meas = 100.0 * (1.0 + np.repeat(rng.normal(0.0, 0.05, n_c), reps) + rng.normal(0.0, 0.005, n_c * reps))
        sc = np.full(len(meas), 100.0)  # absolute errors over 100: linear least squares
        s = sl.score(sl.Model([ed], y0, meas, sc), sl.Model([], y0, meas, sc), folds, groups=groups)
        hits += s.aicc < s.ref_aicc
    expected = stats.f.sf(6 * (np.exp((sl.aicc(1, 8, 2) - sl.aicc(1, 8, 1)) / 8) - 1), 1, 6)
    assert expected == pytest.approx(0.108, abs=0.005)
    assert abs(hits / tables - expected) < 3 * np.sqrt(expected * (1 - expected) / tables), hits / tables


def test_the_information_criterion_of_replicate_rows_is_that_of_their_means():
    # the same 8 conditions given as 3 repeat rows each or as one row of their mean: the same
    # AICc for both models (errors over a fixed scale, so a condition's mean error is the error
    # of its mean)
    from soilcal.loop import select as sl

    rng = np.random.default_rng(3)
    n_c, reps = 8, 3
    xc = np.linspace(-0.5, 0.5, n_c)
    meas = 100.0 * (1.0 + 0.2 * np.repeat(xc, reps) + rng.normal(0.0, 0.03, n_c * reps))
    obs = pd.DataFrame({"simulation": np.repeat([f"s{i}" for i in range(n_c)], reps), "measure": "F_N"})
    folds = sl.Folds([np.arange(reps * i, reps * i + reps) for i in range(n_c)])
    rows = sl.score(sl.Model([_trend_effect(np.repeat(xc, reps))], np.full(n_c * reps, 100.0), meas,
                             np.full(n_c * reps, 100.0)),
                    sl.Model([], np.full(n_c * reps, 100.0), meas, np.full(n_c * reps, 100.0)), folds,
                    groups=sl.replicate_groups(obs))
    mean = meas.reshape(n_c, reps).mean(axis=1)
    one = sl.score(sl.Model([_trend_effect(xc)], np.full(n_c, 100.0), mean, np.full(n_c, 100.0)),
                   sl.Model([], np.full(n_c, 100.0), mean, np.full(n_c, 100.0)),
                   sl.Folds([np.array([i]) for i in range(n_c)]))
    assert rows.aicc == pytest.approx(one.aicc, rel=1e-6) and rows.ref_aicc == pytest.approx(one.ref_aicc, rel=1e-6)
    assert rows.theta["trend.t"] == pytest.approx(0.2, abs=0.03)
