"""The residual table (soilcal.loop.residuals): measured minus simulated mean, its relative and
standardised forms and standard error, each checked against numbers worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from soilcal.config.measurements import Condition
from soilcal.loop.residuals import RESIDUAL_COLUMNS, observations, residual_frame, simulated_stats, usable


def _cond(row, responses, covariates=None, quantities=None, measurement="bin"):
    return Condition(measurement=measurement, row=row, label=f"row {row}", covariate="", covariate_value="",
                     scenario="standin", setup={}, params={}, stage="bbd", case="c", preset="quick", replicates=3,
                     responses=tuple(dict(measure=m, unit="N", measured=v, measured_sd=sd, n=n)
                                     for m, v, sd, n in responses),
                     covariates=covariates or {}, quantities=quantities or {},
                     quantity_columns={})


def _runs(rows, measurement="bin"):
    """rows: (row, measure, seed, value, status)."""
    return pd.DataFrame([dict(measurement=measurement, row=r, measure=m, seed=s, value=v, status=st)
                         for r, m, s, v, st in rows])


def _one(res, row, measure="F_N"):
    sel = res[(res["row"] == row) & (res["measure"] == measure)]
    assert len(sel) == 1
    return sel.iloc[0]


SIMS = [(1, "F_N", 0, 90.0, "ok"), (1, "F_N", 1, 92.0, "ok"), (1, "F_N", 2, 94.0, "ok")]


def test_residual_se_and_standardised_residual_by_hand():
    conds = [_cond(1, [("F_N", 100.0, 6.0, 4)])]
    res = residual_frame(observations(conds), _runs(SIMS))
    r = _one(res, 1)
    # simulated: mean (90 + 92 + 94) / 3 = 92; sd sqrt(((-2)^2 + 0 + 2^2) / 2) = 2; n 3
    assert (r["simulated_mean"], r["simulated_sd"], r["simulated_n"]) == (pytest.approx(92.0), pytest.approx(2.0), 3)
    assert r["residual"] == pytest.approx(100.0 - 92.0)
    assert r["relative_residual"] == pytest.approx(8.0 / 100.0)
    se = math.sqrt(6.0 ** 2 / 4 + 2.0 ** 2 / 3)  # sqrt(9 + 4/3)
    assert r["residual_se"] == pytest.approx(se)
    assert r["standardised_residual"] == pytest.approx(8.0 / se)
    assert r["note"] == ""
    assert list(res.columns) == RESIDUAL_COLUMNS


def test_relative_residual_over_absolute_measured_value():
    # measured -50, simulated -40: residual -10, relative -10 / |-50| = -0.2
    conds = [_cond(1, [("F_N", -50.0, 1.0, 1)])]
    runs = _runs([(1, "F_N", 0, -40.0, "ok"), (1, "F_N", 1, -40.0, "ok")])
    r = _one(residual_frame(observations(conds), runs), 1)
    assert r["residual"] == pytest.approx(-10.0)
    assert r["relative_residual"] == pytest.approx(-0.2)
    # no seed scatter (sd 0): se = sqrt(1^2 / 1) = 1
    assert r["residual_se"] == pytest.approx(1.0)
    assert r["standardised_residual"] == pytest.approx(-10.0)


def test_missing_measured_n_counts_as_one():
    conds = [_cond(1, [("F_N", 100.0, 6.0, None)])]
    r = _one(residual_frame(observations(conds), _runs(SIMS)), 1)
    se = math.sqrt(6.0 ** 2 / 1 + 2.0 ** 2 / 3)  # sqrt(36 + 4/3)
    assert r["residual_se"] == pytest.approx(se)
    assert r["standardised_residual"] == pytest.approx(8.0 / se)


def test_failed_runs_are_ignored():
    conds = [_cond(1, [("F_N", 100.0, 6.0, 4)])]
    runs = _runs(SIMS + [(1, "F_N", 3, 1000.0, "failed"), (1, "F_N", 4, -5.0, "diverged")])
    r = _one(residual_frame(observations(conds), runs), 1)
    assert (r["simulated_mean"], r["simulated_n"]) == (pytest.approx(92.0), 3)
    assert r["residual_se"] == pytest.approx(math.sqrt(9 + 4 / 3))
    stats = simulated_stats(runs)
    assert stats["simulated_n"].tolist() == [3]


def test_row_without_measured_value_gets_nan_and_a_note():
    conds = [_cond(1, [("F_N", 100.0, 6.0, 4)]), _cond(2, [("F_N", None, None, None)])]
    runs = _runs(SIMS + [(2, "F_N", 0, 50.0, "ok"), (2, "F_N", 1, 52.0, "ok")])
    res = residual_frame(observations(conds), runs)
    r = _one(res, 2)
    assert np.isnan(r["measured"]) and np.isnan(r["residual"]) and np.isnan(r["relative_residual"])
    assert np.isnan(r["standardised_residual"])
    assert r["simulated_mean"] == pytest.approx(51.0)
    assert "no measured value" in r["note"]
    assert usable(res)["row"].tolist() == [1]


def test_notes_on_missing_uncertainty_and_missing_simulation():
    conds = [_cond(1, [("F_N", 100.0, None, None)]), _cond(2, [("F_N", 80.0, None, None)]),
             _cond(3, [("F_N", 60.0, 3.0, None)])]
    runs = _runs([(1, "F_N", 0, 95.0, "ok"),                          # one seed, no measured SD
                  (2, "F_N", 0, 78.0, "ok"), (2, "F_N", 1, 82.0, "ok")])  # row 3 never simulated
    res = residual_frame(observations(conds), runs)
    r1, r2, r3 = _one(res, 1), _one(res, 2), _one(res, 3)
    assert r1["residual"] == pytest.approx(5.0)
    assert np.isnan(r1["residual_se"]) and np.isnan(r1["standardised_residual"])
    assert "no uncertainty known" in r1["note"]
    # seeds 78, 82: mean 80, sd sqrt((4 + 4) / 1) = 2 sqrt(2), se = 2 sqrt(2) / sqrt(2) = 2; residual 0
    assert r2["residual_se"] == pytest.approx(2.0)
    assert r2["standardised_residual"] == pytest.approx(0.0)
    assert "seed scatter only" in r2["note"]
    assert r3["simulated_n"] == 0 and np.isnan(r3["residual"])
    assert "no simulated value" in r3["note"]
    assert usable(res)["row"].tolist() == [1, 2]


def test_each_measure_matched_separately():
    conds = [_cond(1, [("F_N", 100.0, None, None), ("V_N", 10.0, None, None)])]
    runs = _runs([(1, "F_N", 0, 90.0, "ok"), (1, "V_N", 0, 12.0, "ok")])
    res = residual_frame(observations(conds), runs)
    assert _one(res, 1, "F_N")["relative_residual"] == pytest.approx(10.0 / 100.0)
    assert _one(res, 1, "V_N")["relative_residual"] == pytest.approx(-2.0 / 10.0)


def test_covariates_and_quantities_carried_over():
    conds = [_cond(1, [("F_N", 100.0, 6.0, 4)], covariates={"speed_kmh": 3.6, "plate": "A"},
                   quantities={"tool_speed": 1.0, "tool": "A"}),
             _cond(2, [("F_N", 80.0, 6.0, 4)], covariates={"speed_kmh": 7.2, "plate": "B"},
                   quantities={"tool_speed": 2.0, "tool": "B"})]
    runs = _runs(SIMS + [(2, "F_N", 0, 80.0, "ok")])
    res = residual_frame(observations(conds), runs)
    for c in ("cov:speed_kmh", "cov:plate", "q:tool_speed", "q:tool"):
        assert c in res.columns
    assert res["cov:speed_kmh"].tolist() == [3.6, 7.2]
    assert res["cov:plate"].tolist() == ["A", "B"]
    assert res["q:tool_speed"].tolist() == [1.0, 2.0]
    assert res["q:tool"].tolist() == ["A", "B"]
    # key columns first, then the covariates, then the residual columns
    assert list(res.columns[:3]) == ["measurement", "row", "measure"]
    assert list(res.columns[-len(RESIDUAL_COLUMNS) + 5:]) == RESIDUAL_COLUMNS[5:]


def test_all_runs_failed():
    conds = [_cond(1, [("F_N", 100.0, 6.0, 4)])]
    res = residual_frame(observations(conds), _runs([(1, "F_N", 0, 95.0, "failed")]))
    r = _one(res, 1)
    assert r["simulated_n"] == 0 and np.isnan(r["residual"])
    assert "no simulated value" in r["note"]
    assert len(usable(res)) == 0


def test_no_runs_at_all():
    conds = [_cond(1, [("F_N", 100.0, 6.0, 4)])]
    res = residual_frame(observations(conds), pd.DataFrame(columns=["measurement", "row", "measure", "seed",
                                                                    "value", "status"]))
    r = _one(res, 1)
    assert r["simulated_n"] == 0 and np.isnan(r["residual"])
    assert "no simulated value" in r["note"]
    assert len(usable(res)) == 0


def _table(values, sims):
    conds = [_cond(i + 1, [("Fz_N", v, 1.0, 3)]) for i, v in enumerate(values)]
    runs = _runs([(i + 1, "Fz_N", s, x, "ok") for i, x in enumerate(sims) for s in (0, 1)])
    return residual_frame(observations(conds), runs)


def test_a_quantity_of_both_signs_is_relative_to_its_rms():
    # measured 3, -4, 0.5 (both signs): RMS sqrt((9 + 16 + 0.25) / 3) = sqrt(8.4167) = 2.9011;
    # simulated 2 everywhere: residuals 1, -6, -1.5, each over 2.9011
    res = _table([3.0, -4.0, 0.5], [2.0, 2.0, 2.0])
    rms = math.sqrt((9 + 16 + 0.25) / 3)
    assert res["scale"].to_numpy() == pytest.approx([rms] * 3)
    assert res["relative_residual"].to_numpy() == pytest.approx(np.array([1.0, -6.0, -1.5]) / rms)
    assert all("relative to the RMS 2.901 of Fz_N" in n for n in res["note"])


def test_a_value_near_zero_makes_its_quantity_relative_to_its_rms_and_a_wide_range_does_not():
    # 0.5 N among 40 and 60 N: below 0.02 of the RMS sqrt((0.25 + 1600 + 3600) / 3) = 41.64
    res = _table([0.5, 40.0, 60.0], [1.0, 44.0, 57.0])
    rms = math.sqrt((0.25 + 1600 + 3600) / 3)
    assert res["relative_residual"].to_numpy() == pytest.approx(np.array([-0.5, -4.0, 3.0]) / rms)
    # 5 N among 40 and 60 N (0.12 of the RMS): each row its own value
    res = _table([5.0, 40.0, 60.0], [4.0, 44.0, 57.0])
    assert res["relative_residual"].to_numpy() == pytest.approx([1 / 5, -4 / 40, 3 / 60])
    assert (res["note"] == "").all()


def test_a_measured_zero_has_no_relative_residual_alone_but_with_others_the_rms():
    res = _table([0.0], [1.0])
    assert np.isnan(res["relative_residual"].iloc[0]) and "measured value 0" in res["note"].iloc[0]
    res = _table([0.0, 10.0], [1.0, 9.0])  # RMS sqrt(100 / 2) = 7.071
    assert res["relative_residual"].to_numpy() == pytest.approx(np.array([-1.0, 1.0]) / math.sqrt(50))


def test_failed_runs_are_counted_and_noted():
    conds = [_cond(1, [("F_N", 100.0, 6.0, 4)])]
    runs = _runs(SIMS + [(1, "F_N", 3, float("nan"), "failed"), (1, "F_N", 4, 91.0, "failed")])
    r = _one(residual_frame(observations(conds), runs), 1)
    assert (r["simulated_n"], r["failed_runs"]) == (3, 2) and r["note"] == "2 runs failed"
    assert r["simulated_mean"] == pytest.approx(92.0)


def test_a_test_measured_twice_is_one_simulation_and_one_fold():
    from soilcal.loop.select import _folds

    twins = [_cond(1, [("F_N", 100.0, 6.0, 4)], quantities={"tool_speed": 1.0, "day": "d1"}),
             _cond(2, [("F_N", 104.0, 6.0, 4)], quantities={"tool_speed": 1.0, "day": "d2"}),
             _cond(3, [("F_N", 120.0, 6.0, 4)], quantities={"tool_speed": 2.0, "day": "d2"})]
    obs = observations(twins)
    assert obs["simulation"].iloc[0] == obs["simulation"].iloc[1] != obs["simulation"].iloc[2]
    folds = _folds(obs, None)
    assert [list(f) for f in folds.held_out] == [[0, 1], [2]] and folds.units is None




def test_two_quantities_of_one_measurement_are_pooled_apart():
    """A table measuring two quantities (horizontal and vertical force of one rig) in repeated
    rows at two conditions: each quantity's relative variance is pooled over its own conditions
    only, sum((n - 1) (sd / scale)^2) / sum(n - 1): F_h (1 / 10)^2 = (2 / 20)^2 = 0.01, F_v
    (2 / 10)^2 = (4 / 20)^2 = 0.04.  Keys that pandas' grouping reads as one quantity (a
    separator at which it stops reading) pool or refuse all four conditions together."""
    from soilcal.loop.diagnose import replicate_conditions
    from soilcal.loop.residuals import KEY_SEP

    rows = [(sim, q, v, scale) for sim, scale, vals in (("s0", 10.0, {"F_h": (9, 10, 11), "F_v": (8, 10, 12)}),
                                                        ("s1", 20.0, {"F_h": (18, 20, 22), "F_v": (16, 20, 24)}))
            for q, vs in vals.items() for v in vs]
    d = pd.DataFrame(rows, columns=["simulation", "measure", "measured", "scale"]).assign(
        measurement="pull", simulated_mean=15.0, simulated_sd=1.0, simulated_n=3)
    cond = replicate_conditions(d)
    assert list(cond[7]) == [f"pull{KEY_SEP}F_h", f"pull{KEY_SEP}F_v"] * 2
    np.testing.assert_allclose(cond[8], [0.01, 0.04, 0.01, 0.04], rtol=1e-12)
