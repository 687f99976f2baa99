"""The loop's DEM jobs as the workflow plans them (soilcal.loop.files.loop_jobs) and the
surrogate's handling of failed runs and flat designs (soilcal.loop.select)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from soilcal.chain.verify import tool_key
from soilcal.loop import select as sl
from soilcal.loop import standin as S
from soilcal.loop.effects import EFFECTS
from soilcal.loop.files import loop_jobs


def _tool_job(gamma_ss=0.4):
    spec = {"soil": "s", "stage": "bbd", "run": 1, "levels": {}, "seed": 10, "replicates": 1,
            "params": dict(S.BASE, soil_soil_surface_energy=gamma_ss),
            "responses": {"horizontal_force_N": {"scenario": "bulldozing", "setup": {"name": "plate-line"},
                                                 "measure": "horizontal_force_N", "preset": "quick"}}}
    return {"measurement": "m", "row": 1, "stage": "bbd", "measures": ["horizontal_force_N"], "specs": [spec]}


def test_conditions_sharing_a_tool_job_get_their_own_effect_parameters():
    # two rows that simulate alike (same tool job) but were measured at 10 % and 20 % moisture,
    # and a third without a moisture value
    conds = S.conditions([{"working_depth": 0.1, "moisture_content": 10.0},
                          {"working_depth": 0.1, "moisture_content": 20.0},
                          {"working_depth": 0.1}], measures=("horizontal_force_N",))
    job = _tool_job()
    key = tool_key(job)
    keys = {(c.measurement, c.row): key for c in conds}
    plan = {"candidates": ["moisture_cohesion"], "reference": {"moisture_content": 15.0},
            "design": {"moisture_cohesion": [{"c_w": 0.0}, {"c_w": 0.05}]}}
    jobs, files = loop_jobs(conds, {key: job}, keys, plan, "results/s")
    at = files["moisture_cohesion"]
    # the switched-off point, and the row the effect does not reach, are the tool run itself
    assert set(at[0].values()) == {f"results/s/dem/tools/{key}.csv"}
    assert at[1]["plates/3"] == f"results/s/dem/tools/{key}.csv"
    # 0.4 + 0.05 (10 - 15) = 0.15 and 0.4 + 0.05 (20 - 15) = 0.65 J/m^2: two jobs
    k1, k2 = at[1]["plates/1"].split("/")[-1][:-4], at[1]["plates/2"].split("/")[-1][:-4]
    assert k1 != k2 and set(jobs) == {k1, k2}
    assert jobs[k1]["specs"][0]["params"]["soil_soil_surface_energy"] == pytest.approx(0.15)
    assert jobs[k2]["specs"][0]["params"]["soil_soil_surface_energy"] == pytest.approx(0.65)
    assert jobs[k1]["specs"][0]["seed"] == job["specs"][0]["seed"]


def test_plastic_contact_plans_and_runs_only_the_compression_conditions():
    from soilcal.dem.scenarios.base import DemParams
    from soilcal.loop import core

    blade = S.conditions([{"working_depth": 0.1}], measures=("horizontal_force_N",))
    comp = S.compression_conditions([{"max_strain": 0.2}], measures=("recovered_strain",))
    conds = blade + comp
    # a significant difference between a table's measured quantities: plastic_contact's signature
    diag = pd.DataFrame([{"test": "group", "covariate": "measure", "quantity": "measure", "significant": True}])
    assert "plastic_contact" not in core.candidates(diag, blade, core.Settings())
    assert "plastic_contact" in core.candidates(diag, conds, core.Settings())
    acts = {(e["measurement"], e["row"]): e["acts"] for e in core.plan(conds, ["plastic_contact"], core.Settings(), {})}
    assert acts == {("plates", 1): False, ("compression", 1): True}
    # the DEM jobs: a blade tool job, and a compression one with DemParams' full set (elastic, 0)
    bjob = _tool_job()
    cspec = {"soil": "s", "stage": "bbd", "run": 1, "levels": {}, "seed": 10, "replicates": 1,
             "params": DemParams().as_dict(),
             "responses": {"recovered_strain": {"scenario": "compression", "setup": {"name": "paper", "unload": True},
                                                "measure": "recovered_strain", "preset": "quick"}}}
    cjob = {"measurement": "compression", "row": 1, "stage": "bbd", "measures": ["recovered_strain"], "specs": [cspec]}
    # the stand-in's compression condition, as the DEM's scenario
    from dataclasses import replace

    conds = [blade[0], replace(comp[0], scenario="compression")]
    bk, ck = tool_key(bjob), tool_key(cjob)
    plan = {"candidates": ["plastic_contact"], "reference": {},
            "design": {"plastic_contact": [{"lambda_p": 0.0}, {"lambda_p": 0.45}]}}
    jobs, files = loop_jobs(conds, {bk: bjob, ck: cjob}, {("plates", 1): bk, ("compression", 1): ck}, plan, "results/s")
    at = files["plastic_contact"]
    # the blade at every point and the switched-off compression test are the tool runs themselves
    assert at[0] == {"plates/1": f"results/s/dem/tools/{bk}.csv", "compression/1": f"results/s/dem/tools/{ck}.csv"}
    assert at[1]["plates/1"] == f"results/s/dem/tools/{bk}.csv"
    # lambda_p = 0 + 0.45 = 0.45 on the compression test: one new job, nothing else changed
    (key,) = jobs
    assert at[1]["compression/1"] == f"results/s/loop/runs/{key}.csv"
    assert jobs[key]["specs"][0]["params"] == dict(DemParams().as_dict(), soil_soil_plasticity=0.45)


def _obs(n):
    return pd.DataFrame({"measurement": ["m"] * n, "row": list(range(1, n + 1)), "measure": ["F_N"] * n,
                         "measured": [100.0] * n})


def _runs(values_by_theta):
    rows = []
    for theta, values in values_by_theta.items():
        for i, v in enumerate(values, start=1):
            rows.append({"measurement": "m", "row": i, "measure": "F_N", "seed": 0, "value": v,
                         "status": "ok" if np.isfinite(v) else "failed", "t:beta": theta})
    return pd.DataFrame(rows)


def test_a_failed_run_at_a_design_point_is_interpolated_and_named():
    eff = EFFECTS["rate_friction"]
    bounds = {"beta": (-0.3, 0.6)}
    # row 1 linear in beta (100 + 100 beta); its run at beta = 0.3 failed
    runs = _runs({-0.3: [70.0, 50.0], 0.0: [100.0, 50.0], 0.3: [math.nan, 50.0], 0.6: [160.0, 50.0]})
    ed = sl.build_effect_data(_obs(2), runs, eff, bounds)
    assert ed.missing == ["m row 1 F_N"]
    assert ed.surrogate([0.3])[0] == pytest.approx(130.0)


def test_a_row_with_one_simulated_point_is_refused():
    runs = _runs({-0.3: [math.nan], 0.0: [100.0], 0.3: [math.nan], 0.6: [math.nan]})
    with pytest.raises(ValueError, match="fewer than two design points"):
        sl.build_effect_data(_obs(1), runs, EFFECTS["rate_friction"], {"beta": (-0.3, 0.6)})


def test_a_flat_design_does_not_pin_the_parameter_down():
    # the effect changes nothing: the fit stays at the switched-off value, interval unbounded
    runs = _runs({b: [90.0, 95.0, 105.0, 110.0] for b in (-0.3, 0.0, 0.3, 0.6)})
    obs = _obs(4)
    ed = sl.build_effect_data(obs, runs, EFFECTS["rate_friction"], {"beta": (-0.3, 0.6)})
    m = sl.Model([ed], np.array([90.0, 95.0, 105.0, 110.0]), obs["measured"].to_numpy(float))
    ref = sl.Model([], m.y0, m.measured)
    s = sl.score(m, ref, sl._folds(obs, None))
    assert s.theta["rate_friction.beta"] == 0.0
    assert s.ci["rate_friction.beta"] == (-math.inf, math.inf)
    assert not s.accepted


def test_aicc_counts_the_residual_variance():
    # n ln(SSE/n) + 2K + 2K(K+1)/(n-K-1) with K = 2 (one parameter + the variance), n = 6, SSE = 6
    assert sl.aicc(6.0, 6, 2) == pytest.approx(0 + 4 + 12 / 3)
    assert math.isnan(sl.aicc(1.0, 3, 2))  # undefined: n <= K + 1
