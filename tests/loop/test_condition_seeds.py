"""Each measured condition is simulated on seeds of its own (soilcal.config.measurements.condition_seed).

A soil-bin test runs in a bed prepared for it and a compression test in a fresh fill, so the
simulated mean of one condition must scatter independently of the others': the loop's bias
test (a one-sample t-test over the conditions) and its scatter test take the conditions as
independent.  With one seed list for every condition the runs of a seed share its settled bed
(cached by seed), and that bed's error moves every condition alike.  The tests check the seeds
themselves, that the DEM simulator of the loop and the workflow's tool jobs use them, and, on
a simulator whose runs share a bed per seed, that the shared seeds make a bias out of nothing
at several times the test's level while a condition's own seeds keep it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
from scipy import stats

from soilcal.config.measurements import SEED_BLOCK, Condition, condition_seed
from soilcal.loop import diagnose as dg
from soilcal.loop import residuals as rs
from soilcal.loop import synthesize as sy


def _cond(row, speed, depth, measurement="bin"):
    q = {"tool_speed": speed, "working_depth": depth}
    return Condition(measurement=measurement, row=row, label=f"row {row}", covariate="", covariate_value="",
                     scenario="bulldozing", setup={"shape": "line", "speed": speed, "depth": depth}, params={},
                     stage="bbd", case="c", preset="quick", replicates=3,
                     responses=({"measure": "horizontal_force_N", "unit": "N", "measured": None,
                                 "measured_sd": None, "n": None},),
                     covariates=dict(q), quantities=dict(q), quantity_columns={k: k for k in q})


def test_each_condition_has_seeds_of_its_own_and_a_test_tabled_twice_shares_them():
    a, b = _cond(1, 0.2, 0.025), _cond(2, 0.8, 0.035)
    sa, sb = [condition_seed(a, k) for k in range(3)], [condition_seed(b, k) for k in range(3)]
    assert not set(sa) & set(sb)
    # the k-th seed of a condition: k plus its block, as given
    assert [s % SEED_BLOCK for s in sa] == [0, 1, 2] and len({s - k for k, s in enumerate(sa)}) == 1
    assert condition_seed(a, 1000) - condition_seed(a, 0) == 1000
    # the same simulation in another row, table or under another label: one test, one set of seeds
    again = replace(a, row=7, measurement="other", label="repeat", quantities={**a.quantities, "day": "d2"})
    assert [condition_seed(again, k) for k in range(3)] == sa
    # a different parameter or preset is another simulation
    assert condition_seed(replace(a, params={"soil_density": 1500.0}), 0) != sa[0]
    assert condition_seed(replace(a, preset="paper"), 0) != sa[0]


def test_the_loop_dem_simulator_runs_each_condition_on_its_own_seed(monkeypatch):
    from soilcal.chain import sources
    from soilcal.loop.cli import dem_simulator

    seen = []

    def fake(spec, threads=None, restart_dir=None):
        seen.append(spec["seed"])
        return pd.DataFrame([{"measure": m, "value": 1.0, "status": "ok"} for m in spec["responses"]])

    monkeypatch.setattr(sources, "simulate", fake)
    sim = dem_simulator(1)
    a, b = _cond(1, 0.2, 0.025), _cond(2, 0.8, 0.035)
    for c in (a, b):
        for k in (0, 1):
            assert sim(c, {}, k) == {"horizontal_force_N": 1.0}
    assert seen == [condition_seed(a, 0), condition_seed(a, 1), condition_seed(b, 0), condition_seed(b, 1)]


def test_the_workflow_tool_jobs_give_each_condition_its_own_seeds(monkeypatch):
    from pathlib import Path

    from soilcal.chain import stage as stage_mod
    from soilcal.chain.verify import tool_key, tool_point, verify_settings
    from soilcal.config.load import load_soil
    from soilcal.config.measurements import conditions

    root = Path(__file__).resolve().parents[2]
    soil = load_soil(root / "config/soils/cinnamon-soil.yaml", root / "resources")
    stage = soil.stage("bbd")
    levels = {s: 0.5 * (f["low"] + f["high"]) for s, f in stage["factors"].items()}
    monkeypatch.setattr(stage_mod, "calibrated_levels", lambda st, opt, case=None: dict(levels))
    conds = conditions(soil)
    assert len(conds) == 4  # the four plates
    base = int(soil.data["seed"]) + int(verify_settings(soil.data)["seed_offset"])
    jobs = [tool_point(soil, c, stage, pd.DataFrame()) for c in conds]
    seeds = [[s["seed"] for s in j["specs"]] for j in jobs]
    assert seeds == [[condition_seed(c, base + k) for k in range(c.replicates)] for c in conds]
    assert len({s for row in seeds for s in row}) == sum(c.replicates for c in conds)
    assert len({tool_key(j) for j in jobs}) == 4
    # a plate tabled twice (another row of the same simulation) is one job
    twin = tool_point(soil, replace(conds[0], row=99, label="again"), stage, pd.DataFrame())
    assert tool_key(twin) == tool_key(jobs[0])


def _bed_simulator(share):
    """Runs of a soil bin whose settled bed is drawn from the seed alone (``share`` of the
    log-variance, as the cached bed of the DEM plate) and whose pass adds its own scatter:
    10 % per run in all, no dependence on the parameters (a model without any misfit)."""
    sd = 0.10

    def simulate(cond, params, seed):
        bed = np.random.default_rng([int(seed), 1]).normal()
        own = np.random.default_rng([int(seed), 2, int(cond.row)]).normal()
        z = np.sqrt(share) * bed + np.sqrt(1 - share) * own
        return {"horizontal_force_N": 50.0 * (1 + 2 * cond.quantities["working_depth"]) * np.exp(sd * z)}

    return simulate


def _bias_p(conds, simulate, own_seeds: bool, table_seed: int) -> float:
    seed_of = (lambda c, k: condition_seed(c, k)) if own_seeds else (lambda c, k: k)
    table = sy.synthesize(conds, lambda c: {}, lambda c, p, s: simulate(c, p, seed_of(c, s)), {}, {}, {},
                          noise=0.02, seed=table_seed, seeds=(1000 + 10 * table_seed, 1001 + 10 * table_seed,
                                                              1002 + 10 * table_seed))
    measured = sy.with_measured(conds, table)
    runs = pd.DataFrame([{"measurement": c.measurement, "row": c.row, "measure": "horizontal_force_N", "seed": k,
                          "value": simulate(c, {}, seed_of(c, k))["horizontal_force_N"], "status": "ok"}
                         for c in measured for k in range(3)])
    res = rs.residual_frame(rs.observations(measured), runs)
    diag = dg.diagnose(res, {"tool_speed": "tool_speed", "working_depth": "working_depth"}, 0.05)
    return float(diag.loc[diag["test"] == "bias", "p"].iloc[0])


def test_a_bed_shared_by_every_condition_makes_a_bias_and_own_seeds_keep_the_level():
    # 12 soil-bin conditions, three measured repeats and three seeds each, no misfit; 30 % of
    # the runs' log-variance the bed's (the DEM plate's correlations over 30 seeds: 0.12-0.48).
    # Shared seeds: the beds' common error, SD sqrt(2 * 0.3 / 3) * 10 % = 4.5 %, against the
    # conditions' own error of about 7 % / sqrt(12) = 2 % in the t-test: the bias test rejects in
    # about P(|Z| > 0.9) = 0.37 of the tables; with a condition's own seeds at its level, 0.05.
    rng = np.random.default_rng(5)
    tables = 120
    p_shared, p_own = [], []
    for t in range(tables):
        conds = [_cond(i + 1, float(rng.uniform(0.1, 1.0)), float(rng.uniform(0.02, 0.04))) for i in range(12)]
        sim = _bed_simulator(0.3)
        p_shared.append(_bias_p(conds, sim, False, t))
        p_own.append(_bias_p(conds, sim, True, t))
    shared = int(np.sum(np.array(p_shared) < 0.05))
    own = int(np.sum(np.array(p_own) < 0.05))
    # own seeds: within the two-sided 99 % binomial interval of the level; shared: beyond it
    lo, hi = stats.binom.ppf([0.005, 0.995], tables, 0.05)
    assert lo <= own <= hi, (own, shared)
    assert shared > hi and shared >= 0.2 * tables, (own, shared)
