"""The 10 % gain an effect must bring, counted on the held-out error above the noise floor
(soilcal.loop.select.lowers_heldout, heldout_floor, Score.floor, Model.floor).

No model removes the measured and seed scatter, so where the floor is known and the
reference's held-out RMS error lies above the floor's 95 % interval, the rule compares
sqrt(rmse^2 - low^2) of the model and of its reference, ``low`` the interval's low end;
elsewhere the whole errors, as before.  Expected values by hand below."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from soilcal.loop import residuals as rs
from soilcal.loop import select as sl


def _score(rmse: float, ref: float, floor=(math.nan, math.nan), weights=None) -> sl.Score:
    """A score whose held-out errors are +-rmse and +-ref on four rows: RMS errors rmse and ref."""
    e = np.array([rmse, -rmse, rmse, -rmse])
    er = np.array([ref, -ref, ref, -ref])
    return sl.Score(names=["x.t"], theta={"x.t": 0.1}, ci={}, fold_rms=np.abs(e), ref_fold_rms=np.abs(er),
                    heldout_errors=e, ref_heldout_errors=er, fitted_errors=e, aicc=-10.0, ref_aicc=-8.0, p=0.01,
                    accepted=False, reason="", heldout_weights=weights, floor=floor)


def test_the_gain_is_counted_above_the_low_end_of_the_floor():
    # a reference at 18.24 %, the model at 16.84 %: 16.84 / 18.24 = 0.923, short of 10 %
    assert not sl.lowers_heldout(_score(0.1684, 0.1824))
    # the floor's interval 12-15 %: above its low end sqrt(0.1824^2 - 0.12^2) = 13.74 % and
    # sqrt(0.1684^2 - 0.12^2) = 11.81 %, 0.860 of it: at least 10 % lower
    s = _score(0.1684, 0.1824, (0.12, 0.15))
    assert sl.floor_counts(s)
    assert sl.above_floor(0.1824, 0.12) == pytest.approx(math.sqrt(0.1824 ** 2 - 0.0144), rel=1e-12)
    assert sl.lowers_heldout(s)
    # the reference within the floor's interval (high end 19 %): nothing above the floor to
    # count on, the whole errors as before
    assert not sl.floor_counts(_score(0.1684, 0.1824, (0.12, 0.19)))
    assert not sl.lowers_heldout(_score(0.1684, 0.1824, (0.12, 0.19)))
    # a model below the floor's low end has nothing above it: lower by all of it
    assert sl.lowers_heldout(_score(0.11, 0.1824, (0.12, 0.15)))
    # a model that removes less than 10 % above the floor stays out: 17.9 % against 18.24 %,
    # sqrt(0.179^2 - 0.0144) = 13.28 % against 13.74 %, 0.967
    assert not sl.lowers_heldout(_score(0.179, 0.1824, (0.12, 0.15)))


def test_a_floor_of_zero_is_the_rule_on_the_whole_errors():
    for rmse in (0.15, 0.16, 0.17):
        plain = rmse <= 0.9 * 0.18
        assert sl.lowers_heldout(_score(rmse, 0.18, (0.0, 0.0))) == plain == sl.lowers_heldout(_score(rmse, 0.18))


# A residual table of 12 conditions of two quantities with known relative SDs (three repeats,
# three seeds each): per row v = (sd_m^2 + sd_s^2) / 3 / scale^2, the floor sqrt(mean v).
REL = {"horizontal_force_N": (0.02, 0.10), "vertical_force_N": (0.10, 0.34)}
N = 12


def _table() -> pd.DataFrame:
    out = pd.DataFrame({"measurement": "campaign", "row": np.tile(np.arange(1, N + 1), 2),
                        "measure": np.repeat(list(REL), N), "simulation": np.tile([f"s{i}" for i in range(N)], 2),
                        "measured": 100.0, "scale": 100.0, "simulated_mean": 100.0})
    out["measured_sd"] = np.repeat([100 * m for m, _ in REL.values()], N)
    out["measured_n"] = 3
    out["simulated_sd"] = np.repeat([100 * s for _, s in REL.values()], N)
    out["simulated_n"] = 3
    return out


def test_the_floor_is_the_tables_and_weighted_as_the_held_out_error():
    obs = _table()
    v = np.repeat([(m ** 2 + s ** 2) / 3 for m, s in REL.values()], N)
    np.testing.assert_allclose(rs.floor_variances(obs), v, rtol=1e-12)
    floor, _, (lo, hi, _) = rs.noise_floor_and_interval(obs)
    assert floor == pytest.approx(math.sqrt(v.mean()), rel=1e-12)
    assert lo < floor < hi
    assert sl.heldout_floor(obs) == (pytest.approx(lo, rel=1e-12), pytest.approx(hi, rel=1e-12))
    # weighted by 1 / v (mean 1), the floor of the weighted RMS is sqrt(sum w v / sum w): the
    # harmonic mean of v, sqrt(2 / (1 / v_H + 1 / v_V)), against the plain sqrt((v_H + v_V) / 2)
    w = sl.row_weights(obs)
    assert w is not None
    vh, vv = [(m ** 2 + s ** 2) / 3 for m, s in REL.values()]
    k = math.sqrt(2 / (1 / vh + 1 / vv)) / math.sqrt((vh + vv) / 2)
    assert sl.heldout_floor(obs, w) == (pytest.approx(lo * k, rel=1e-12), pytest.approx(hi * k, rel=1e-12))


def test_a_table_without_the_floors_columns_has_none():
    obs = _table().drop(columns=["measured_sd", "measured_n", "simulated_sd", "simulated_n"])
    assert all(math.isnan(x) for x in sl.heldout_floor(obs))
    assert all(math.isnan(x) for x in sl.heldout_floor(pd.DataFrame({"measured": [1.0]})))


class _Trend:
    name = "trend"
    null = {"t": 0.0}

    def theta_names(self):
        return ("t",)


def test_the_reference_carries_its_floor_into_the_score_and_its_words():
    # measured 100 (1 + 0.15 x + 0.15 s), s = +-1 in a pattern even in x (sum x s = 0: a scatter
    # the trend cannot take), the calibrated model 100, the errors relative to 100; the trend's
    # surrogate 100 (1 + t x)
    x = np.linspace(-1.0, 1.0, N)
    s = np.array([1, -1, -1, 1, 1, -1, -1, 1, 1, -1, -1, 1], float)
    assert abs(np.sum(x * s)) < 1e-12
    measured = 100.0 * (1.0 + 0.15 * x + 0.15 * s)
    eff = _Trend()
    ts = np.array([[-2.0], [0.0], [2.0]])
    ed = sl.EffectData(eff, {"t": (-2.0, 2.0)}, sl.Surrogate(eff, {"t": (-2.0, 2.0)}, ts,
                                                               np.array([100.0 * (1.0 + t * x) for t in ts[:, 0]])),
                       [{"t": t} for t in ts[:, 0]])
    y0, scale = np.full(N, 100.0), np.full(N, 100.0)
    folds = sl.Folds([np.array([i]) for i in range(N)])

    def scored(floor):
        return sl.score(sl.Model([ed], y0, measured, scale, floor=floor),
                        sl.Model([], y0, measured, scale, base=[ed], floor=floor), folds)

    plain, counted = scored(None), scored((0.14, 0.15))
    assert all(math.isnan(f) for f in plain.floor) and counted.floor == (0.14, 0.15)
    r, rr = plain.rmse(), plain.rmse(True)
    assert counted.rmse() == r and counted.rmse(True) == rr  # the floor changes no error, only the rule
    assert rr > 0.15 and r > 0.9 * rr  # short of 10 % on the whole errors ...
    assert sl.above_floor(r, 0.14) <= 0.9 * sl.above_floor(rr, 0.14)  # ... not above the floor's low end
    assert "lower by less than 10 %" in plain.reason
    assert "lower by less than 10 %" not in counted.reason
