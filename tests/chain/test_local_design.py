"""The local design at the first set (soilcal.chain.local) and the second round that follows
the DEM's plane through it.

The stage is that of test_refine: a Box-Behnken whose responses are exactly y = 30 + 2 A (A
coded), so the fitted surface is that line.  The "DEM" here is another line, y = 32 + 1.5 (A -
0.5): at the first set x0 (A coded 0.5, where the surface meets the target 31) it reads 32, a
bias of +1 with a slope of 1.5 where the surface has 2.  In closed form:

* the constant bias correction moves to where 30 + 2 A + 1 = 31, A = 0, where the DEM reads
  31.25 (a miss of 0.8 %);
* the first-order correction, 30 + 2 A + 1 + (1.5 - 2)(A - 0.5) = 31.25 + 1.5 A, meets 31 at
  A = -1/6, where the DEM reads 31 exactly; B and C have no slope in either, so the smallest
  move leaves them where they are.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from bbd_stand_in import box_behnken_3
from soilcal.chain import local as lc
from soilcal.chain.refine import refine_frame
from soilcal.chain.sources import RUN_COLUMNS

GOAL = {"y": {"goal": "target", "target": "y"}}
X0 = {"A": 0.75, "B": 16.5, "C": 180.0, "A_coded": 0.5, "B_coded": 0.3, "C_coded": -0.2}
TARGETS = {"y": {"value": 31.0, "source": "image"}}
CENTRE, HALF = np.array([0.5, 15.0, 200.0]), np.array([0.5, 5.0, 100.0])


def _stage():
    return {"id": "bbd", "kind": "box_behnken", "table_coding": "actual",
            "factors": {"A": {"parameter": "soil_soil_rolling_friction", "low": 0.0, "centre": 0.5, "high": 1.0},
                        "B": {"parameter": "soil_soil_static_friction", "low": 10.0, "centre": 15.0, "high": 20.0},
                        "C": {"parameter": "soil_steel_restitution", "low": 100.0, "centre": 200.0, "high": 300.0}},
            "responses": [{"id": "y", "name": "angle", "unit": "deg"}],
            "optimise": {"method": "desirability", "model": "full", "cases": [{"id": "biased", "goals": dict(GOAL)}]}}


def _table():
    X = box_behnken_3()[1]
    y = 30.0 + 2.0 * X[:, 0]
    y[-3:] += [-0.01, 0.0, 0.01]
    return pd.DataFrame({"run": np.arange(1, 16), "A": 0.5 + 0.5 * X[:, 0], "B": 15 + 5 * X[:, 1],
                         "C": 200 + 100 * X[:, 2], "y": y})


OPTIMUM = pd.DataFrame([{"case": "biased", "method": "near_optimal", **X0, "y": 31.0, "calibrated": True}])


def dem(a_coded):
    return 32.0 + 1.5 * (a_coded - 0.5)


def _run(coded, k, wobble=0.0):
    actual = CENTRE + HALF * np.asarray(coded, float)
    row = {c: "" for c in RUN_COLUMNS} | {"stage": "bbd", "run": k, "response": "y", "value": dem(coded[0]) + wobble,
                                          "sd": np.nan, "n": 1, "status": "ok", "error": "", "seed": 11000 + k,
                                          "preset": "quick"}
    row |= {f"f:{s}": float(v) for s, v in zip("ABC", actual)}
    return pd.DataFrame([row])


X0C = np.array([0.5, 0.3, -0.2])
FIRST = {"biased": [_run(X0C, k, w) for k, w in enumerate([0.01, -0.01, 0.01, -0.01])]}


def test_the_design_is_a_plackett_burman_about_the_first_set_moved_inside_the_region():
    pts = lc.design_points(X0C, 0.35, [-1, -1, -1], [1, 1, 1])
    assert pts.shape == (4, 3)  # pbdesign(3): 4 runs
    np.testing.assert_allclose(pts.mean(axis=0), X0C)
    np.testing.assert_allclose(np.abs(pts - X0C), 0.35)
    near = lc.design_points([0.9, 0.0, -1.0, 0.2], 0.35, [-1] * 4, [1] * 4)
    assert near.shape == (8, 4)  # pbdesign(4): 8 runs
    np.testing.assert_allclose(near.mean(axis=0), [0.65, 0.0, -0.65, 0.2])
    assert near.max() <= 1.0 and near.min() >= -1.0
    narrow = lc.design_points([0.0], 0.35, [-0.2], [0.2])  # a region narrower than 2 h: its own half-width
    np.testing.assert_allclose(sorted(set(narrow.ravel())), [-0.2, 0.2])


def test_the_first_order_correction_has_the_dems_level_and_slope_at_the_first_set():
    class Line:
        factors = ["A", "B"]

        def predict(self, X):
            X = np.atleast_2d(X)
            return 30.0 + 2.0 * X[:, 0] + X[:, 0] ** 2

    x0 = np.array([0.5, 0.1])
    level, slope = 32.0, np.array([1.5, -0.4])
    m = Line()
    fo = lc.FirstOrder(m, level - m.predict(x0)[0], slope - lc.gradient(m, x0), x0)
    assert fo.predict(x0)[0] == pytest.approx(level)
    np.testing.assert_allclose(lc.gradient(fo, x0), slope, atol=1e-6)
    # the surface's curvature is kept: the second difference of A^2
    h = 0.1
    e = np.array([h, 0.0])
    curv = (fo.predict(x0 + e)[0] - 2 * fo.predict(x0)[0] + fo.predict(x0 - e)[0]) / h ** 2
    assert curv == pytest.approx(2.0)


def test_without_a_local_design_the_constant_shift_moves_to_a_zero():
    r = refine_frame(_stage(), _table(), TARGETS, OPTIMUM, FIRST).set_index("case").loc["biased"]
    assert bool(r["refined"]) and r["A_coded"] == pytest.approx(0.0, abs=1e-4)
    assert dem(r["A_coded"]) == pytest.approx(31.25, abs=1e-3)  # the DEM misses there


def test_the_local_plane_aims_the_move_where_the_dem_meets_the_target():
    local = lc.local_frame(_stage(), refine_frame(_stage(), _table(), TARGETS, OPTIMUM, FIRST), OPTIMUM, 0.35)
    assert len(local) == 4 and set(local["case"]) == {"biased"}
    runs = [_run(local.loc[i, ["A_coded", "B_coded", "C_coded"]].to_numpy(float), 10 + i, 0.005 * (-1) ** i)
            for i in range(len(local))]
    r = refine_frame(_stage(), _table(), TARGETS, OPTIMUM, FIRST, local={"biased": runs},
                     half_width=0.35).set_index("case").loc["biased"]
    assert bool(r["refined"]) and r["local_points"] == 4
    assert r["A_coded"] == pytest.approx(-1.0 / 6.0, abs=0.01)
    assert (r["B_coded"], r["C_coded"]) == pytest.approx((0.3, -0.2), abs=0.01)
    assert dem(r["A_coded"]) == pytest.approx(31.0, abs=0.02)
    assert r["bias_y"] == pytest.approx(1.0, abs=0.01)
    assert "local design at the first set (4 points at +- 0.35 coded" in r["note"]
    assert "slope per coded unit A +1.4" in r["note"] or "slope per coded unit A +1.5" in r["note"]
    assert "surface +2)" in r["note"]


def test_a_move_past_the_trust_region_is_a_compromise_at_its_edge():
    # half-width 0.25: the trust region reaches A coded 0.5 - 0.5 = 0, short of -1/6
    local = lc.local_frame(_stage(), refine_frame(_stage(), _table(), TARGETS, OPTIMUM, FIRST), OPTIMUM, 0.25)
    runs = [_run(local.loc[i, ["A_coded", "B_coded", "C_coded"]].to_numpy(float), 10 + i, 0.005 * (-1) ** i)
            for i in range(len(local))]
    r = refine_frame(_stage(), _table(), TARGETS, OPTIMUM, FIRST, local={"biased": runs},
                     half_width=0.25).set_index("case").loc["biased"]
    assert bool(r["refined"]) and r["A_coded"] == pytest.approx(0.0, abs=1e-3)
    assert "compromise within the trust region (+- 0.5 coded" in r["note"]


def test_no_local_design_for_a_case_without_a_bias_or_with_the_option_off():
    met = {"biased": [_run(X0C, k, w) for k, w in enumerate([-1.01, -0.99, -1.0, -1.0])]}  # reads 31: met
    assert lc.local_frame(_stage(), refine_frame(_stage(), _table(), TARGETS, OPTIMUM, met), OPTIMUM, 0.35).empty
    assert lc.local_frame(_stage(), refine_frame(_stage(), _table(), TARGETS, OPTIMUM, FIRST), OPTIMUM, None).empty


def test_half_width_setting():
    assert lc.half_width({}) == lc.HALF_WIDTH
    assert lc.half_width({"simulation": {"verification": {"local": {"half_width": 0.2}}}}) == 0.2
    assert lc.half_width({"simulation": {"verification": {"local": False}}}) is None
    assert lc.half_width({"simulation": {"verification": {"refine": False}}}) is None
    with pytest.raises(Exception, match="half_width"):
        lc.half_width({"simulation": {"verification": {"local": {"half_width": 2}}}})


def test_a_local_point_is_the_cases_set_at_its_levels():
    local = lc.local_frame(_stage(), refine_frame(_stage(), _table(), TARGETS, OPTIMUM, FIRST), OPTIMUM, 0.35)
    one = lc.point_optimum(OPTIMUM, local, "biased", 2)
    assert len(one) == 1 and bool(one["calibrated"].iloc[0])
    assert one["A"].iloc[0] == pytest.approx(local.loc[2, "A"]) and one["B_coded"].iloc[0] == local.loc[2, "B_coded"]


def test_a_bend_within_the_design_is_estimated_apart_from_the_slope_and_the_level():
    # the DEM bends: y = 32 + 1.5 (A - 0.5) - 3 (A - 0.5)^2; the design's points, at A - 0.5 =
    # +-0.35, all stand 3 x 0.35^2 = 0.3675 below the line, the first set's seeds on it
    local = lc.local_frame(_stage(), refine_frame(_stage(), _table(), TARGETS, OPTIMUM, FIRST), OPTIMUM, 0.35)
    runs = []
    for i in range(len(local)):
        xc = local.loc[i, ["A_coded", "B_coded", "C_coded"]].to_numpy(float)
        runs.append(_run(xc, 10 + i, -3.0 * (xc[0] - 0.5) ** 2))  # (4 runs, 4 terms: no wobble left)
    pl = lc.plane(FIRST["biased"], runs, "y", "ABC", CENTRE, HALF, X0C)
    assert pl["level"] == pytest.approx(32.0, abs=1e-9)  # the seeds' mean (their wobble cancels)
    assert pl["slope"][0] == pytest.approx(1.5, abs=0.01)
    assert pl["curvature"] == pytest.approx(3 * 0.35 ** 2, abs=0.01)
    assert pl["runs"] == 8
    # too few runs of the design for the plane: None
    assert lc.plane(FIRST["biased"], runs[:3], "y", "ABC", CENTRE, HALF, X0C) is None


def test_files_the_local_design_and_the_second_round_read_and_write(tmp_path):
    """write_local writes the design of the biased case; write_refined then follows its runs,
    and refuses (InputError naming the input) to run without local.csv or with a point's run
    missing, rather than fall back to the constant shift unseen."""
    import json

    from soilcal.chain.refine import write_local, write_refined
    from soilcal.errors import InputError

    d = tmp_path / "dem"
    (d / "bbd").mkdir(parents=True)
    (d / "bbd" / "stage.json").write_text(json.dumps(_stage()))
    _table().to_csv(d / "bbd" / "responses.csv", index=False)
    OPTIMUM.to_csv(d / "bbd" / "optimum.csv", index=False)
    pd.DataFrame([{"target_id": "y", "value": 31.0, "source": "image"}]).to_csv(d / "targets.csv", index=False)
    first = []
    for k, f in enumerate(FIRST["biased"]):
        p = d / "verify" / "quick" / "bbd" / "biased" / f"{k}.csv"
        p.parent.mkdir(parents=True, exist_ok=True)
        f.to_csv(p, index=False)
        first.append(p)
    args = (d / "bbd" / "stage.json", d / "bbd" / "responses.csv", d / "targets.csv", d / "bbd" / "optimum.csv", first)
    local = write_local(*args, d / "bbd" / "local.csv", half_width=0.35)
    assert len(local) == 4
    runs = []
    for i in range(len(local)):
        p = d / "local" / "bbd" / "biased" / f"{i}.csv"
        p.parent.mkdir(parents=True, exist_ok=True)
        _run(local.loc[i, ["A_coded", "B_coded", "C_coded"]].to_numpy(float), 10 + i).to_csv(p, index=False)
        runs.append(p)
    out = write_refined(*args, d / "bbd" / "refined.csv", local_paths=runs, half_width=0.35,
                        local_csv=d / "bbd" / "local.csv")
    assert out["A_coded"].iloc[0] == pytest.approx(-1.0 / 6.0, abs=0.01)
    with pytest.raises(InputError, match="input.local"):
        write_refined(*args, d / "bbd" / "refined.csv", local_paths=runs, half_width=0.35)
    with pytest.raises(InputError, match="input.local_runs"):
        write_refined(*args, d / "bbd" / "refined.csv", local_paths=runs[:3], half_width=0.35,
                      local_csv=d / "bbd" / "local.csv")


def test_local_points_of_several_seeds_weigh_as_many_seeds():
    # every local point run twice, each row the mean of n = 4 seeds, w = 0.2 either side of the
    # DEM's line; the first set's four one-seed runs scatter by +-0.01 about 32.  Weighted by
    # seeds, the residual SD of one seed is sqrt((4 x 0.01^2 + 8 x 4 x 0.2^2) / (12 - 5)) (12
    # rows, 5 terms); unweighted it would be sqrt((4e-4 + 8 x 0.04) / 7)
    local = lc.local_frame(_stage(), refine_frame(_stage(), _table(), TARGETS, OPTIMUM, FIRST), OPTIMUM, 0.35)
    runs = []
    for i in range(len(local)):
        xc = local.loc[i, ["A_coded", "B_coded", "C_coded"]].to_numpy(float)
        for j, w in enumerate((0.2, -0.2)):
            r = _run(xc, 10 + 2 * i + j, w)
            r["n"] = 4
            runs.append(r)
    pl = lc.plane(FIRST["biased"], runs, "y", "ABC", CENTRE, HALF, X0C)
    assert pl["slope"] == pytest.approx([1.5, 0.0, 0.0], abs=1e-9)
    assert pl["level"] == pytest.approx(32.0, abs=1e-12)
    assert pl["sd"] == pytest.approx(np.sqrt((4e-4 + 8 * 4 * 0.04) / 7), rel=1e-9)
    assert (pl["runs"], pl["seeds"]) == (12, 4 + 8 * 4)


def test_local_points_start_a_design_points_seeds_apart_after_every_verification_seed():
    soil = {"seed": 3, "simulation": {"responses": {"y": {"replicates": 4}},
                                      "verification": {"replicates": 4, "max_replicates": 10}}}
    # most_seeds 10, then SEED_OFFSET, then four seeds (the heap's count) per point
    assert [lc.point_seed(soil, p) - lc.SEED_OFFSET for p in range(3)] == [10, 14, 18]
    soil["simulation"]["responses"]["y"].pop("replicates")
    assert [lc.point_seed(soil, p) - lc.SEED_OFFSET for p in range(3)] == [10, 11, 12]
