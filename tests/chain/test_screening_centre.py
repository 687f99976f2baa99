"""Centre runs of the DEM screening and the path aimed at several targets.

``simulation.screening.center_points`` adds runs at the centre of every screened range to the
DEM source's Plackett-Burman design. They do not enter the main effects; they measure the
response where the climbing path starts (which the two-level runs' mean misses where the
response curves) and test that curvature (Montgomery, Design and Analysis of Experiments,
sec. 6.8). A path aimed at several targets (the vineyard soil's static and dynamic angles)
starts from them. Every expected number is worked out by hand beside its assertion.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from soilcal.chain.derive import bbd_from_path, dem_stage, path_from_screening
from soilcal.chain.stage import (
    analysis_data,
    design_frame,
    generated_design,
    regression_frames,
    screening_centre,
)
from soilcal.config.load import load_soil

ROOT = Path(__file__).resolve().parents[2]


def _pb_stage(center_points: int = 3) -> dict:
    return {"id": "pb", "kind": "plackett_burman", "runs": 12, "table_coding": "coded",
            "factors": {"A": {"parameter": "a", "low": 0, "high": 1}, "B": {"parameter": "b", "low": 0, "high": 1},
                        "C": {"parameter": "c", "low": 0, "high": 1}},
            "responses": [{"id": "y", "name": "y", "unit": "-"}], "center_points": center_points}


def _table(stage: dict, y_centre) -> pd.DataFrame:
    """Coded design with y = 5 + 2 A exactly at the two-level runs and the given centre runs."""
    x = generated_design(stage)
    t = pd.DataFrame(x[:, :3], columns=["A", "B", "C"])
    t["y"] = 5.0 + 2.0 * t["A"]
    t.loc[len(t) - len(y_centre):, "y"] = y_centre
    return t


def test_centre_runs_are_appended_to_the_generated_design():
    st = _pb_stage(3)
    x = generated_design(st)
    # 12 two-level runs of the 11-column design (first 3 columns), then 3 rows of zeros
    assert x.shape == (15, 3)
    assert np.array_equal(x[:12], generated_design(_pb_stage(0)))
    assert np.all(x[12:] == 0.0) and set(np.unique(x[:12])) == {-1.0, 1.0}
    df, _ = design_frame({**st, "factors": {k: {**f, "low": 0.2, "high": 1.0} for k, f in st["factors"].items()}},
                         None)
    assert df["run"].tolist() == list(range(1, 16))
    assert df["A_actual"].tolist()[12:] == [0.6, 0.6, 0.6]  # the centre of 0.2 .. 1.0


def test_curvature_against_the_two_level_runs_with_its_test():
    st = _pb_stage(3)
    t = _table(st, [2.9, 3.0, 3.1])
    c = screening_centre(st, t)["y"]
    # two-level mean 5 (A balanced), centre mean 3: curvature 2
    assert c["n"] == 3 and c["mean"] == pytest.approx(3.0, abs=1e-12)
    assert c["sd"] == pytest.approx(0.1, abs=1e-12)
    assert c["factorial_mean"] == pytest.approx(5.0, abs=1e-12)
    assert c["curvature"] == pytest.approx(2.0, abs=1e-12)
    # SS_curv = 12 * 3 / 15 * 2^2 = 9.6; the main-effects model fits the two-level runs exactly
    # (SS 0 on 12 - 4 = 8 df), the centre runs' pure error SS = 0.02 on 2 df: MS = 0.02 / 10
    assert c["df_error"] == 10
    assert c["F"] == pytest.approx(9.6 / 0.002, rel=1e-9)
    assert c["p"] == pytest.approx(stats.f.sf(4800.0, 1, 10), rel=1e-6)
    # no centre runs: nothing to report
    assert screening_centre(_pb_stage(0), _table(_pb_stage(0), [])) == {}


def test_centre_runs_leave_the_effects_of_the_two_level_runs_unchanged():
    st = _pb_stage(3)
    rng = np.random.default_rng(7)
    t = _table(st, [9.0, 9.5, 10.0])
    t["y"] += rng.normal(0.0, 0.3, len(t))
    assert len(analysis_data(st, t)) == 12
    with_centre = regression_frames(st, t)["effects"].set_index("term")
    without = regression_frames(_pb_stage(0), t.iloc[:12])["effects"].set_index("term")
    pd.testing.assert_frame_equal(with_centre, without)


# --------------------------------------------------------------------------- vineyard path


def _vineyard() -> dict:
    return copy.deepcopy(load_soil(ROOT / "config" / "soils" / "xinjiang-vineyard.yaml", ROOT / "resources").data)


def _targets(soil: dict) -> dict:
    return {tid: {"value": t.get("value"), "source": "printed"} for tid, t in soil["targets"].items()}


# the printed layer targets (Conclusions (1)); the path aims at their means
STATIC_MEAN = (30.82 + 32.35 + 33.77) / 3
DYNAMIC_MEAN = (42.7 + 43.91 + 45.7) / 3
SIG = ["B", "C", "D", "H"]
# first-order models in coded units: the static angle rises with D and H, the dynamic angle
# rises with C and falls with B; A (shear modulus) lowers the static angle but is not
# significant, so it is held, at the path stage's own 10 MPa: coded -1 on 10 .. 100
COEF = {"static_angle": {"A": 1.0, "B": 0.0, "C": 0.0, "D": 2.0, "E": 0.0, "F": 0.0, "G": 0.0, "H": 2.0},
        "dynamic_angle": {"A": 0.0, "B": -3.0, "C": 3.0, "D": 0.0, "E": 0.0, "F": 0.0, "G": 0.0, "H": 0.0}}


def _effects() -> pd.DataFrame:
    rows = []
    for r, b in COEF.items():
        for t, v in b.items():
            rows.append({"response": r, "term": t, "effect": 2 * v, "coefficient": v, "sum_sq": 12 * v * v,
                         "contribution_percent": np.nan, "F": np.nan, "p": 0.001 if t in SIG else 0.5, "rank": 0})
    return pd.DataFrame(rows)


def _screening_runs(pb: dict, static_centre: float, dynamic_centre: float) -> pd.DataFrame:
    """The DEM screening's responses table (actual levels) with two-level runs whose mean is
    far from the centre runs' (curvature)."""
    df, _ = design_frame(pb, None)
    t = pd.DataFrame({s: df[f"{s}_actual"] for s in pb["factors"]})
    n = len(t)
    t["static_angle"] = 20.0
    t["dynamic_angle"] = 30.0
    t.loc[n - 3:, "static_angle"] = [static_centre - 0.5, static_centre, static_centre + 0.5]
    t.loc[n - 3:, "dynamic_angle"] = [dynamic_centre - 0.2, dynamic_centre, dynamic_centre + 0.2]
    return t


def test_vineyard_path_aims_at_both_angles_from_the_centre_runs():
    vin = _vineyard()
    assert vin["simulation"]["screening"]["center_points"] == 3
    pb = dem_stage(vin, "pb", _targets(vin))
    assert pb["center_points"] == 3 and "centre run" in pb["derivation"]["text"]
    # the static angle must rise by 2 from the path's start, the dynamic angle fall by 1.5:
    # start = centre mean + A's effect held at coded -1 (static: -1.0)
    static_centre = STATIC_MEAN - 2.0 + 1.0
    dynamic_centre = DYNAMIC_MEAN + 1.5
    runs = _screening_runs(pb, static_centre, dynamic_centre)
    st = path_from_screening(vin, "steepest", pb, _effects(), runs, _targets(vin))
    d = st["derivation"]
    assert d["rule"] == "target"  # auto: two targeted responses
    assert d["start"]["static_angle"]["from"] == "centre runs"
    assert d["start"]["static_angle"]["intercept"] == pytest.approx(STATIC_MEAN - 2.0, abs=1e-9)
    assert d["start"]["dynamic_angle"]["intercept"] == pytest.approx(DYNAMIC_MEAN + 1.5, abs=1e-9)
    assert d["held_coded"] == {"A": pytest.approx(-1.0)}
    assert d["curvature"]["dynamic_angle"]["curvature"] == pytest.approx(30.0 - dynamic_centre, abs=1e-9)
    # 2 D + 2 H = 2 and -3 B + 3 C = -1.5, minimum norm: D = H = 0.5, B = 0.25, C = -0.25
    assert d["target"]["coded"] == pytest.approx({"B": 0.25, "C": -0.25, "D": 0.5, "H": 0.5}, abs=1e-9)
    by_param = {f["parameter"]: f["levels"] for f in st["factors"].values()}
    # base D (largest move, first of D and H in the order of the effects) walks its range in
    # 6 steps of 2/5 coded: s = -1, -0.6, -0.2, 0.2, 0.6, 1; H moves as D, B half, C minus half
    lam = np.array([-1.0, -0.6, -0.2, 0.2, 0.6, 1.0])
    # D: 0.05 .. 0.15 (centre 0.1, half 0.05)
    assert by_param["soil_soil_rolling_friction"] == pytest.approx(0.1 + 0.05 * lam, abs=1e-9)
    # C: 0.2 .. 1.16 (centre 0.68, half 0.48)
    assert by_param["soil_soil_static_friction"] == pytest.approx(0.68 + 0.48 * (-0.5 * lam), abs=1e-9)
    # B: 0.15 .. 0.75 (centre 0.45, half 0.3)
    assert by_param["soil_soil_restitution"] == pytest.approx(0.45 + 0.3 * (0.5 * lam), abs=1e-9)
    # H: 0.1 .. 0.3 (centre 0.2, half 0.1)
    assert by_param["jkr_surface_energy"] == pytest.approx(0.2 + 0.1 * lam, abs=1e-9)
    # the Box-Behnken box: each factor's screening range / 5 around the chosen step
    st["id"] = "steepest"
    steps = pd.DataFrame({"step": np.arange(1, 7), "static_angle": STATIC_MEAN + np.arange(-3, 3) * 1.0,
                          "dynamic_angle": DYNAMIC_MEAN + np.arange(-2, 4) * 1.0})  # both met at step 3-4
    bbd = bbd_from_path(vin, "bbd", st, steps)
    step = bbd["derivation"]["chosen_step"]
    lv = {f["parameter"]: (f["low"], f["centre"], f["high"]) for f in bbd["factors"].values()}
    c = 0.1 + 0.05 * lam[step - 1]
    assert lv["soil_soil_rolling_friction"] == pytest.approx((c - 0.02, c, c + 0.02), abs=1e-9)
    c = 0.68 + 0.48 * (-0.5 * lam[step - 1])
    assert lv["soil_soil_static_friction"] == pytest.approx((c - 0.192, c, c + 0.192), abs=1e-9)
    assert "box half width" in bbd["derivation"]["levels"][next(iter(bbd["factors"]))]


def test_without_centre_runs_the_path_starts_from_the_two_level_mean_and_range_stays_selectable():
    vin = _vineyard()
    vin["simulation"].pop("screening")
    pb = dem_stage(vin, "pb", _targets(vin))
    assert "center_points" not in pb
    runs = _screening_runs(pb, 0.0, 0.0)
    assert len(runs) == 12
    runs["static_angle"], runs["dynamic_angle"] = 20.0, 30.0  # the two-level runs only
    st = path_from_screening(vin, "steepest", pb, _effects(), runs, _targets(vin))
    assert st["derivation"]["rule"] == "target"  # still two targets
    assert st["derivation"]["start"]["static_angle"]["from"] == "two-level runs' mean"
    assert st["derivation"]["start"]["static_angle"]["value"] == pytest.approx(20.0)
    vin["simulation"]["path"] = {"rule": "range"}
    st = path_from_screening(vin, "steepest", pb, _effects(), runs, _targets(vin))
    assert st["derivation"]["rule"] == "range" and "target" not in st["derivation"]
