"""The stage the DEM source runs, derived from earlier DEM results (soilcal.chain.derive).

No DEM run here: screening effects, path responses and optima are frames built by hand.
Every expected number is either reasoned out next to the assertion or a printed value the
soil config quotes (cinnamon soil: Qiu et al. 2022, Tables 2, 5, 6 and Sec. 3.3.2; vineyard
soil: Conclusions (1); black soil: Sec. 3.1.2).
"""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from soilcal.chain.derive import (
    bbd_from_path,
    dem_stage,
    dem_stage_ids,
    dependencies,
    fix_from_optimum,
    path_from_screening,
    response_targets,
)
from soilcal.config.load import load_soil
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]

# Cinnamon soil, Table 5 (config stage `steepest`): the printed climbing path, 6 steps.
TABLE5 = {
    "A": [0.05, 0.08, 0.11, 0.14, 0.17, 0.2],   # X3 soil-soil rolling friction, 0.05..0.2
    "B": [0.1, 0.24, 0.38, 0.52, 0.66, 0.8],    # X7 JKR surface energy, 0.1..0.8
    "C": [0.3, 0.42, 0.54, 0.66, 0.78, 0.9],    # X5 soil-steel static friction, 0.3..0.9
}
# Cinnamon soil, Table 6 (config stage `bbd`): steps 2, 3, 4 of Table 5 as low, centre, high.
TABLE6 = {"A": (0.08, 0.11, 0.14), "B": (0.24, 0.38, 0.52), "C": (0.42, 0.54, 0.66)}
# Sec. 3.3.2: insignificant factors at their intermediate levels (centres of Table 2's ranges):
# X1 (0.15 + 0.75)/2, X2 (0.2 + 0.92)/2, X4 (0.2 + 0.7)/2, X6 (0.05 + 0.2)/2.
INTERMEDIATE = {"soil_soil_restitution": 0.45, "soil_soil_static_friction": 0.56,
                "soil_steel_restitution": 0.45, "soil_steel_rolling_friction": 0.125}
CINNAMON_TARGET = 27.69  # Sec. 2.4, measured stacking angle


def _soil(name: str) -> dict:
    return copy.deepcopy(load_soil(ROOT / "config" / "soils" / f"{name}.yaml", ROOT / "resources").data)


@pytest.fixture(scope="module")
def soils():
    return {n: _soil(n) for n in ("cinnamon-soil", "xinjiang-vineyard", "guangxi-cohesive", "black-soil",
                                  "yangtze-clay-loam")}


def _targets(soil_data: dict) -> dict:
    """The chain's target dict as files.read_targets gives it: printed values, None when lost."""
    return {tid: {"value": t.get("value"), "source": "printed"} for tid, t in soil_data["targets"].items()}


def _stage(soil_data: dict, sid: str) -> dict:
    return next(s for s in soil_data["stages"] if s["id"] == sid)


def _effects(p: dict[str, float], b: dict[str, float], response: str = "stacking_angle") -> pd.DataFrame:
    """A screening-effects frame as rsm.screening_effects + a response column lays it out."""
    rows = [{"response": response, "term": t, "effect": 2 * b[t], "coefficient": b[t], "sum_sq": 12 * b[t] ** 2,
             "contribution_percent": np.nan, "F": np.nan, "p": p[t], "rank": 0} for t in p]
    return pd.DataFrame(rows)


# X3, X5, X7 significant (p < 0.05), positive; the other four clearly not.
P_SIG = {"X1": 0.45, "X2": 0.34, "X3": 0.001, "X4": 0.22, "X5": 0.03, "X6": 0.88, "X7": 0.01}
B_SIG = {"X1": 0.5, "X2": -0.7, "X3": 4.0, "X4": 0.9, "X5": 1.5, "X6": 0.1, "X7": 2.0}


# --------------------------------------------------------------------------- targets of a path


def test_response_targets_own_target_and_layer_mean(soils):
    cin, vin = soils["cinnamon-soil"], soils["xinjiang-vineyard"]
    got = response_targets(cin, ["stacking_angle"], _targets(cin))
    assert got == {"stacking_angle": {"value": pytest.approx(27.69), "from": ["stacking_angle"]}}

    got = response_targets(vin, ["static_angle", "dynamic_angle", "no_such_response"], _targets(vin))
    # no target has the id static_angle: the mean of the three layer targets its cases aim at
    assert got["static_angle"]["value"] == pytest.approx((30.82 + 32.35 + 33.77) / 3, abs=1e-12)
    assert got["static_angle"]["from"] == ["static_angle_upper", "static_angle_middle", "static_angle_lower"]
    assert got["dynamic_angle"]["value"] == pytest.approx((42.7 + 43.91 + 45.7) / 3, abs=1e-12)
    assert "no_such_response" not in got


def test_response_targets_skip_lost_targets_and_take_inline_values(soils):
    gx = soils["guangxi-cohesive"]
    # angle_mc05 and angle_mc15 are lost (value null): the mean of mc00, mc10, mc20
    got = response_targets(gx, ["angle_of_repose"], _targets(gx))
    assert got["angle_of_repose"]["value"] == pytest.approx((30.83 + 31.97 + 37.13) / 3, abs=1e-12)
    assert got["angle_of_repose"]["from"] == ["angle_mc00", "angle_mc10", "angle_mc20"]

    soil = {"stages": [{"id": "s", "optimise": {"cases": [
        {"id": "c1", "goals": {"y": {"goal": "target", "value": 10.0}, "z": {"goal": "maximize"}}},
        {"id": "c2", "goals": {"y": {"goal": "target", "target": "t"}}}]}}]}
    got = response_targets(soil, ["y", "z"], {"t": {"value": 14.0}})
    assert got == {"y": {"value": pytest.approx(12.0), "from": ["c1 (value)", "t"]}}
    # a NaN own target does not count: the cases' targets are used
    got = response_targets(soil, ["y"], {"y": {"value": float("nan")}, "t": {"value": 14.0}})
    assert got["y"]["value"] == pytest.approx(12.0)


# --------------------------------------------------------------------------- which stages run


def test_dem_stage_ids_and_dependencies_of_the_shipped_soils(soils):
    gx, cin, black = soils["guangxi-cohesive"], soils["cinnamon-soil"], soils["black-soil"]
    assert dem_stage_ids(gx) == ["bbd"]            # simulation.stages: [bbd]
    assert dependencies(gx, "bbd") == {}

    assert dem_stage_ids(cin) == ["pb", "steepest", "bbd"]
    assert dependencies(cin, "pb") == {}
    assert dependencies(cin, "steepest") == {"from": "pb"}
    assert dependencies(cin, "bbd") == {"from": "steepest"}

    assert dem_stage_ids(black) == ["soil-soil", "soil-65mn"]
    assert dependencies(black, "soil-soil") == {}
    assert dependencies(black, "soil-65mn") == {"fixed_from": "soil-soil"}

    printed = copy.deepcopy(cin)
    printed["simulation"]["design"] = "printed"
    assert dependencies(printed, "bbd") == {}

    with pytest.raises(InputError, match="nope"):
        dependencies(cin, "nope")


# --------------------------------------------------------------------------- path from a screening


def _cinnamon_path(soils, mean: float, p=P_SIG, b=B_SIG):
    cin = soils["cinnamon-soil"]
    responses = pd.DataFrame({"stacking_angle": [mean - 1.0, mean + 1.0, mean - 0.5, mean + 0.5]})
    return path_from_screening(cin, "steepest", _stage(cin, "pb"), _effects(p, b), responses, _targets(cin))


def test_path_ascends_over_the_screening_ranges_below_the_target(soils):
    st = _cinnamon_path(soils, mean=25.0)  # 25 < 27.69: every positive effect climbs
    # the config's path stage names the parameters A, B, C: the paper's symbols are kept
    assert list(st["factors"]) == ["A", "B", "C"]  # rank order of p: X3, X7, X5
    assert {s: f["screening_symbol"] for s, f in st["factors"].items()} == {"A": "X3", "B": "X7", "C": "X5"}
    assert {s: f["parameter"] for s, f in st["factors"].items()} == {
        "A": "soil_soil_rolling_friction", "B": "jkr_surface_energy", "C": "soil_steel_static_friction"}
    # exactly the printed Table 5 (6 levels over each screening range, 12 significant digits)
    for s, levels in TABLE5.items():
        assert st["factors"][s]["levels"] == levels
    assert _stage(soils["cinnamon-soil"], "steepest")["factors"]["A"]["levels"] == TABLE5["A"]
    # the four other PB factors at the centres of their ranges = the printed intermediate levels
    assert set(st["fixed"]) == set(INTERMEDIATE)
    for k, v in INTERMEDIATE.items():
        assert st["fixed"][k] == pytest.approx(v, abs=1e-12)
        assert st["fixed"][k] == pytest.approx(_stage(soils["cinnamon-soil"], "steepest")["fixed"][k], abs=1e-12)
    assert st["path_targets"] == {"stacking_angle": {"value": pytest.approx(CINNAMON_TARGET),
                                                     "from": ["stacking_angle"]}}
    assert st["source"] == "dem" and st["table"] == "responses.csv" and st["table_coding"] == "actual"
    assert "chosen_step" not in st and "printed" not in st
    d = st["derivation"]
    assert d["kind"] == "screening" and d["from_stage"] == "pb" and d["rule"] == "range"
    # direction d_j = (t - b0)/t^2 * b_j > 0 for the three positive effects
    assert all(v > 0 for v in d["direction"].values())
    assert d["paper_factors"]["A"] == "soil_soil_rolling_friction"


def test_path_descends_above_the_target(soils):
    st = _cinnamon_path(soils, mean=30.0)  # 30 > 27.69: (t - b0) < 0, the path walks high -> low
    for s, levels in TABLE5.items():
        assert st["factors"][s]["levels"] == levels[::-1]
    assert all(v < 0 for v in st["derivation"]["direction"].values())


def test_path_with_the_printed_table4_p_values_tops_up_to_three_factors(soils):
    # Table 4 (quoted in the config errata): only X3 (p 0.0018) is below 0.05; X7 (0.0753) and
    # X5 (0.0775) are the next two by p and are added because a Box-Behnken design needs three.
    p = {"X1": 0.4523, "X2": 0.3391, "X3": 0.0018, "X4": 0.2222, "X5": 0.0775, "X6": 0.8759, "X7": 0.0753}
    b = {k: 1.0 for k in p}
    st = _cinnamon_path(soils, mean=25.0, p=p, b=b)
    assert {s: f["screening_symbol"] for s, f in st["factors"].items()} == {"A": "X3", "B": "X7", "C": "X5"}
    sel = pd.DataFrame(st["derivation"]["selection"]).set_index("term")
    assert bool(sel.loc["X3", "significant"]) and not bool(sel.loc["X7", "significant"])
    assert sel["selected"].sum() == 3


def test_path_factor_outside_the_paper_stage_keeps_its_screening_symbol(soils):
    # X1 (soil-soil restitution) significant instead of X5: the paper's path has no symbol for it
    p = dict(P_SIG, X1=0.002, X5=0.6)
    st = _cinnamon_path(soils, mean=25.0, p=p)
    assert list(st["factors"]) == ["A", "X1", "B"]  # rank order of p: X3, X1, X7
    assert st["factors"]["X1"]["parameter"] == "soil_soil_restitution"
    assert st["factors"]["X1"]["levels"] == [0.15, 0.27, 0.39, 0.51, 0.63, 0.75]  # 0.15..0.75, step 0.12
    # X5 is now held at the centre of its range (0.3 + 0.9)/2
    assert st["fixed"]["soil_steel_static_friction"] == pytest.approx(0.6, abs=1e-12)
    assert "soil_soil_restitution" not in st["fixed"]


def test_path_needs_a_target(soils):
    cin = copy.deepcopy(soils["cinnamon-soil"])
    with pytest.raises(InputError, match="stages.steepest.responses"):
        path_from_screening(cin, "steepest", _stage(cin, "pb"), _effects(P_SIG, B_SIG),
                            pd.DataFrame({"stacking_angle": [25.0]}), {})


# --------------------------------------------------------------------------- Box-Behnken from a path


def _path_responses(values) -> pd.DataFrame:
    return pd.DataFrame({"step": np.arange(1, len(values) + 1), "stacking_angle": values})


def test_bbd_centred_on_the_step_closest_to_the_target(soils):
    cin = soils["cinnamon-soil"]
    path = _cinnamon_path(soils, mean=25.0)
    path["id"] = "steepest"
    # |y - 27.69|: 5.69, 3.19, 0.19, 1.31, 3.31, 5.31 -> step 3 (responses shuffled: sorted by step)
    resp = _path_responses([22.0, 24.5, 27.5, 29.0, 31.0, 33.0]).iloc[[3, 0, 5, 2, 1, 4]]
    st = bbd_from_path(cin, "bbd", path, resp)
    for s, (lo, c, hi) in TABLE6.items():
        f = st["factors"][s]
        assert (f["low"], f["centre"], f["high"]) == pytest.approx((lo, c, hi), abs=1e-12)
        cfg = _stage(cin, "bbd")["factors"][s]
        assert (f["low"], f["centre"], f["high"]) == pytest.approx((cfg["low"], cfg["centre"], cfg["high"]),
                                                                  abs=1e-12)
        assert f["parameter"] == cfg["parameter"]
    assert st["derivation"]["chosen_step"] == 3 and st["derivation"]["from_stage"] == "steepest"
    assert st["runs"] == 2 * 3 * 2 + 5 == 17  # 12 edge midpoints + 5 centre points, as printed
    assert st["fixed"] == path["fixed"]
    # the printed optimum is on the same parameters (A, B, C): kept as printed (Sec. 3.4)
    case = st["optimise"]["cases"][0]
    assert case["printed_optimum"] == {"A": 0.08, "B": 0.37, "C": 0.64}
    assert st["table"] == "responses.csv" and st["table_coding"] == "actual" and "printed" not in st


def test_bbd_centre_follows_the_trend_of_a_noisy_path(soils):
    """One run per step: a line 45, 41, 37, 33, 29, 25 deg crossing the target 27.69 between
    steps 5 and 6, with step 2's seed landing on 27.7 by chance (the fitted line then runs at
    28.49 deg at step 5 and 25.63 at step 6).  The fitted rule (default of
    a derived path) centres on the step the line puts closest; the papers' rule on the lucky
    run."""
    cin = copy.deepcopy(soils["cinnamon-soil"])
    y = 49.0 - 4.0 * np.arange(1, 7)
    y[1] = 27.7
    path = _cinnamon_path(soils, mean=25.0)
    path["id"] = "steepest"
    assert path["path_choice"] == "fitted"
    st = bbd_from_path(cin, "bbd", path, _path_responses(list(y)))
    # OLS with step 2 off its line by delta: fitted_s = line_s + delta (1/6 + (2 - 3.5)(s - 3.5) / 17.5)
    delta = 27.7 - 41.0
    s = np.arange(1, 7)
    fitted = 49.0 - 4.0 * s + delta * (1 / 6 + (2 - 3.5) * (s - 3.5) / 17.5)
    assert st["derivation"]["chosen_step"] == int(np.argmin(np.abs(fitted - 27.69))) + 1 == 5
    assert st["derivation"]["choice"] == "fitted"
    trend = st["derivation"]["trend"]["stacking_angle"]
    assert trend["degree"] == 1 and trend["n"] == 6
    # the lucky run leaves the line's slope short of significance (its OLS t-test, scipy's
    # linregress: p = 0.099): the derivation says so beside the choice
    p_slope = stats.linregress(s, y).pvalue
    assert 0.05 < p_slope < 0.1
    assert f"p = {p_slope:.2g}" in st["derivation"]["cautions"]["stacking_angle"]
    assert "no significant slope" in st["derivation"]["text"]
    json.dumps(st)  # stage.json: no NaN, no numpy types
    clean = bbd_from_path(cin, "bbd", path, _path_responses(list(49.0 - 4.0 * s + 0.1 * (-1.0) ** s)))
    assert clean["derivation"]["cautions"] == {}
    # the papers' rule, asked for in the soil's simulation block
    cin["simulation"]["path"] = {"choose": "closest"}
    path = path_from_screening(cin, "steepest", _stage(cin, "pb"), _effects(P_SIG, B_SIG),
                               pd.DataFrame({"stacking_angle": [24.0, 26.0, 24.5, 25.5]}), _targets(cin))
    path["id"] = "steepest"
    assert path["path_choice"] == "closest"
    st = bbd_from_path(cin, "bbd", path, _path_responses(list(y)))
    assert st["derivation"]["chosen_step"] == 2 and st["derivation"]["trend"] == {}


def test_steepest_optimum_marks_the_step_the_bbd_is_centred_on(soils):
    """optimum.csv of a derived path chooses as the Box-Behnken derivation does, with the
    trend's values beside the runs."""
    from soilcal.chain.stage import _steepest_frame

    y = 49.0 - 4.0 * np.arange(1, 7)
    y[1] = 27.7
    path = _cinnamon_path(soils, mean=25.0)
    table = pd.DataFrame({"step": np.arange(1, 7), "stacking_angle": y})
    for s, f in path["factors"].items():
        table[s] = f["levels"]
    f = _steepest_frame(path, table, {})
    assert int(f.loc[f["chosen"], "step"].iloc[0]) == 5 and f["fitted"].notna().all()
    f = _steepest_frame({**path, "path_choice": "closest"}, table, {})
    assert int(f.loc[f["chosen"], "step"].iloc[0]) == 2 and f["fitted"].isna().all()


def test_bbd_drops_a_printed_optimum_on_other_parameters(soils):
    cin = soils["cinnamon-soil"]
    path = {"id": "steepest", "kind": "steepest_ascent",
            "factors": {"A": {"parameter": "soil_soil_rolling_friction", "levels": TABLE5["A"]},
                        "B": {"parameter": "jkr_surface_energy", "levels": TABLE5["B"]},
                        "X6": {"parameter": "soil_steel_rolling_friction",
                               "levels": [0.05, 0.08, 0.11, 0.14, 0.17, 0.2]}},
            "fixed": {"soil_steel_static_friction": 0.6},
            "path_targets": {"stacking_angle": {"value": CINNAMON_TARGET}}}
    st = bbd_from_path(cin, "bbd", path, _path_responses([22.0, 27.7, 29.0, 30.0, 31.0, 33.0]))
    # step 2 (|27.7 - 27.69| = 0.01): A 0.05/0.08/0.11
    assert (st["factors"]["A"]["low"], st["factors"]["A"]["centre"], st["factors"]["A"]["high"]) == \
        pytest.approx((0.05, 0.08, 0.11), abs=1e-12)
    assert "printed_optimum" not in st["optimise"]["cases"][0]
    # the path's fixed value carries on; the stage's own fixed values hold for what it does not
    # vary; its fixed soil-steel rolling friction is a factor here (X6), so it is not used, and said so
    assert st["fixed"] == {"soil_steel_static_friction": 0.6, "soil_soil_restitution": 0.45,
                           "soil_soil_static_friction": 0.56, "soil_steel_restitution": 0.45}
    assert set(st["derivation"]["fixed_not_used"]) == {"soil_steel_rolling_friction"}


def test_bbd_at_the_first_step_mirrors_and_shifts_inside_the_physical_range(soils):
    cin = soils["cinnamon-soil"]
    path = _cinnamon_path(soils, mean=25.0)
    path["id"] = "steepest"
    # step 1 closest: low mirrored 2*0.05 - 0.08 = 0.02 for A (>= 0, no shift);
    # B: 2*0.1 - 0.24 = -0.04 < 0 -> the triple is shifted by +0.04: 0, 0.14, 0.28
    st = bbd_from_path(cin, "bbd", path, _path_responses([27.6, 30.0, 31.0, 32.0, 33.0, 34.0]))
    a, b = st["factors"]["A"], st["factors"]["B"]
    assert (a["low"], a["centre"], a["high"]) == pytest.approx((0.02, 0.05, 0.08), abs=1e-12)
    assert (b["low"], b["centre"], b["high"]) == pytest.approx((0.0, 0.14, 0.28), abs=1e-12)


def test_bbd_bounds_a_surface_energy_in_the_unit_its_levels_are_written_in(soils):
    """The JKR surface energy's physical range is [0, 1000] J/m^2; a soil that writes it in
    mJ/m^2 has levels up to 1e6.  A path at 800, 1200 and 1600 mJ/m^2 (0.8-1.6 J/m^2) centred
    on 1200: the Box-Behnken levels are the path's, not shifted below 1000 mJ/m^2 as if it
    were J/m^2."""
    cin = copy.deepcopy(soils["cinnamon-soil"])
    cin["parameters"]["jkr_surface_energy"]["unit"] = "mJ/m^2"
    path = {"id": "steepest", "kind": "steepest_ascent",
            "factors": {"A": {"parameter": "soil_soil_rolling_friction", "levels": [0.05, 0.08, 0.11]},
                        "B": {"parameter": "jkr_surface_energy", "levels": [800.0, 1200.0, 1600.0]},
                        "C": {"parameter": "soil_steel_static_friction", "levels": [0.3, 0.42, 0.54]}},
            "fixed": {}, "path_targets": {"stacking_angle": {"value": CINNAMON_TARGET}}}
    st = bbd_from_path(cin, "bbd", path, _path_responses([20.0, 27.7, 35.0]))
    b = st["factors"]["B"]
    assert st["derivation"]["chosen_step"] == 2
    assert (b["low"], b["centre"], b["high"]) == pytest.approx((800.0, 1200.0, 1600.0), abs=1e-9)


def _plastic_path(cin: dict) -> dict:
    cin["parameters"]["lam"] = {"name": "soil-soil contact plasticity ratio", "unit": "-", "pair": "soil-soil",
                                "kind": "plasticity"}
    return {"id": "steepest", "kind": "steepest_ascent",
            "factors": {"A": {"parameter": "soil_soil_rolling_friction", "levels": [0.05, 0.08, 0.11]},
                        "B": {"parameter": "jkr_surface_energy", "levels": [0.24, 0.38, 0.52]},
                        "C": {"parameter": "lam", "levels": [0.8, 0.9, 0.96]}},
            "fixed": {}, "path_targets": {"stacking_angle": {"value": CINNAMON_TARGET}}}


def test_bbd_keeps_every_dem_parameter_inside_its_physical_range(soils):
    """The Box-Behnken levels stay inside the range the DEM runs accept for every parameter
    kind, a contact plasticity ratio's [0, 1) too.  A path whose last step (0.96) is closest to
    the target mirrors the high level to 2 * 0.96 - 0.9 = 1.02, beyond 1: the triple 0.9 / 0.96
    / 1.02 is shifted down as a whole until its high lies just inside 1, by 0.02 and the open
    end's margin (1e-9 of the range 1): 0.88 / 0.94 / 1 - 1e-9."""
    cin = copy.deepcopy(soils["cinnamon-soil"])
    path = _plastic_path(cin)
    st = bbd_from_path(cin, "bbd", path, _path_responses([20.0, 24.0, 27.7]))
    assert st["derivation"]["chosen_step"] == 3
    c = st["factors"]["C"]
    assert (c["low"], c["centre"], c["high"]) == pytest.approx((0.88, 0.94, 1.0), abs=1e-8)
    assert c["high"] == pytest.approx(1.0 - 1e-9, abs=1e-12) and c["high"] < 1.0


def test_bbd_bounds_refuse_a_unit_without_a_factor_to_si(soils):
    """A level's physical range is converted to the unit its parameter is written in; a unit
    the DEM does not know (mN/m for a surface energy) is refused naming it, not taken as SI."""
    cin = copy.deepcopy(soils["cinnamon-soil"])
    cin["parameters"]["jkr_surface_energy"]["unit"] = "mN/m"
    path = _plastic_path(cin)
    with pytest.raises(InputError) as e:
        bbd_from_path(cin, "bbd", path, _path_responses([20.0, 24.0, 27.7]))
    assert (e.value.field, e.value.got) == ("parameters.jkr_surface_energy.unit", "mN/m")


# --------------------------------------------------------------------------- dem_stage


def test_dem_stage_printed_design_returns_the_config_levels(soils):
    cin = copy.deepcopy(soils["cinnamon-soil"])
    cin["simulation"]["design"] = "printed"
    for sid in ("steepest", "bbd"):
        st = dem_stage(cin, sid, _targets(cin))
        assert st["factors"] == _stage(cin, sid)["factors"]
        assert st["fixed"] == _stage(cin, sid)["fixed"]
        assert st["derivation"]["kind"] == "config" and "printed" in st["derivation"]["text"]
        assert st["source"] == "dem" and "printed" not in st


def test_dem_stage_notes_an_upstream_stage_that_is_not_simulated(soils):
    cin = copy.deepcopy(soils["cinnamon-soil"])
    cin["simulation"]["stages"] = ["bbd"]
    st = dem_stage(cin, "bbd", _targets(cin))
    assert st["factors"] == _stage(cin, "bbd")["factors"]
    assert "stage steepest is not simulated" in st["derivation"]["text"]


def test_dem_stage_recipe_derives_from_upstream(soils):
    cin = soils["cinnamon-soil"]
    pb = dem_stage(cin, "pb", _targets(cin))
    resp = pd.DataFrame({"stacking_angle": [24.0, 26.0]})
    st = dem_stage(cin, "steepest", _targets(cin),
                   {"from": {"stage": pb, "effects": _effects(P_SIG, B_SIG), "responses": resp}})
    assert {s: f["levels"] for s, f in st["factors"].items()} == TABLE5
    st["id"] = "steepest"
    bbd = dem_stage(cin, "bbd", _targets(cin),
                    {"from": {"stage": st, "responses": _path_responses([22.0, 24.5, 27.5, 29.0, 31.0, 33.0])}})
    assert {s: (f["low"], f["centre"], f["high"]) for s, f in bbd["factors"].items()} == \
        {s: pytest.approx(v, abs=1e-12) for s, v in TABLE6.items()}
    with pytest.raises(InputError, match="from_stage"):
        dem_stage(cin, "bbd", _targets(cin), {"from": {"stage": pb, "responses": resp, "effects": None}})


# --------------------------------------------------------------------------- fixed from an optimum


def _black_optimum():
    # the calibrated set of stage 1 (calibrated True) beside a desirability solution
    return pd.DataFrame({
        "case": ["accumulation_angle", "accumulation_angle"],
        "method": ["desirability", "near_optimal"],
        "x1": [0.9, 0.52], "x2": [0.9, 0.41], "x3": [0.9, 0.72], "x4": [0.9, 0.19],
        "calibrated": [False, True],
    })


def test_fix_from_optimum_replaces_exactly_the_upstream_parameters(soils):
    black = soils["black-soil"]
    upstream = dem_stage(black, "soil-soil", _targets(black))
    st = copy.deepcopy(_stage(black, "soil-65mn"))
    st["fixed"]["other_parameter"] = 1.23  # not a stage-1 parameter: left as it is
    out = fix_from_optimum(st, upstream, _black_optimum(), "accumulation_angle")
    assert out["fixed"] == {"soil_soil_surface_energy": 0.52, "soil_soil_restitution": 0.41,
                            "soil_soil_static_friction": 0.72, "soil_soil_rolling_friction": 0.19,
                            "other_parameter": 1.23}
    ff = out["derivation"]["fixed_from"]
    assert ff["stage"] == "soil-soil" and ff["case"] == "accumulation_angle"
    # the paper's values were its printed stage-1 optimum (Sec. 3.1.2: 0.46, 0.51, 0.65, 0.13)
    assert ff["paper"] == {"soil_soil_surface_energy": 0.46, "soil_soil_restitution": 0.51,
                           "soil_soil_static_friction": 0.65, "soil_soil_rolling_friction": 0.13}
    assert set(ff["values"]) == set(ff["paper"])


def test_dem_stage_black_soil_stage2_fixes_the_dem_stage1_optimum(soils):
    black = soils["black-soil"]
    upstream = dem_stage(black, "soil-soil", _targets(black))
    st = dem_stage(black, "soil-65mn", _targets(black),
                   {"fixed_from": {"stage": upstream, "optimum": _black_optimum()}})
    assert st["fixed"] == {"soil_soil_surface_energy": 0.52, "soil_soil_restitution": 0.41,
                           "soil_soil_static_friction": 0.72, "soil_soil_rolling_friction": 0.19}
    assert st["factors"] == _stage(black, "soil-65mn")["factors"]
    # no calibrated set of the upstream case: refused, naming the case
    opt = _black_optimum().assign(calibrated=False)
    with pytest.raises(InputError, match="case accumulation_angle"):
        dem_stage(black, "soil-65mn", _targets(black), {"fixed_from": {"stage": upstream, "optimum": opt}})


# --------------------------------------------------------------------------- choosing the path step


def test_steepest_frame_uses_the_path_targets():
    from soilcal.chain.stage import _steepest_frame

    stage = {"kind": "steepest_ascent", "factors": {"A": {}}, "chosen_step": 3,
             "responses": [{"id": "y1"}, {"id": "y2"}],
             "path_targets": {"y1": {"value": 30.0}, "y2": {"value": 40.0}}}
    table = pd.DataFrame({"step": [1, 2, 3], "A": [0.1, 0.2, 0.3], "y1": [27.0, 30.0, 33.0],
                          "y2": [40.0, 43.0, 36.0]})
    # the path targets win over a target with the response's id
    f = _steepest_frame(stage, table, {"y1": {"value": 100.0}})
    y1 = f[f["response"] == "y1"]
    assert list(y1["target"]) == [30.0] * 3
    assert list(y1["relative_error_percent"]) == pytest.approx([10.0, 0.0, 10.0])
    assert list(y1["chosen"]) == [False, True, False]
    assert list(f.loc[f["response"] == "y2", "chosen"]) == [True, False, False]
    # combined 100 sqrt(mean e^2): step 1 (-0.1, 0) 7.07 %, step 2 (0, 0.075) 5.30 %, step 3 (0.1, -0.1) 10 %
    a = f[f["response"] == "all"]
    assert list(a["relative_error_percent"]) == pytest.approx(
        [100 * np.sqrt(0.01 / 2), 100 * np.sqrt(0.075 ** 2 / 2), 10.0])
    assert list(a["chosen"]) == [False, True, False]
    assert list(a["printed_choice"]) == [False, False, True]


def test_bbd_after_a_path_on_config_levels(soils):
    # simulation.stages without pb: the DEM runs the printed Table 5 path, then derives the BBD
    # from its own path responses.  |y - 27.69| is smallest at step 3 -> Table 6.
    cin = copy.deepcopy(soils["cinnamon-soil"])
    cin["simulation"]["stages"] = ["steepest", "bbd"]
    assert dependencies(cin, "steepest") == {} and dependencies(cin, "bbd") == {"from": "steepest"}
    path = dem_stage(cin, "steepest", _targets(cin))
    st = dem_stage(cin, "bbd", _targets(cin),
                   {"from": {"stage": path, "responses": _path_responses([22.0, 24.5, 27.5, 29.0, 31.0, 33.0])}})
    assert {s: (f["low"], f["centre"], f["high"]) for s, f in st["factors"].items()} == \
        {s: pytest.approx(v, abs=1e-12) for s, v in TABLE6.items()}


def _refuse_constant(name):
    raise ValueError(f"{name} is not JSON")


def test_stage_json_of_a_path_with_failed_steps_is_strict_json(soils, tmp_path):
    """Steps 4 and 5 of the path failed (no response): their errors are unknown, written as
    null, never as the bare NaN that strict JSON readers refuse."""
    from soilcal.chain.files import read_stage, write_json, write_stage

    cin = soils["cinnamon-soil"]
    path = _cinnamon_path(soils, mean=25.0)
    path["id"] = "steepest"
    st = bbd_from_path(cin, "bbd", path, _path_responses([22.0, 24.5, 27.5, np.nan, np.nan, 33.0]))
    steps = st["derivation"]["steps"]
    assert any(isinstance(v, float) and not np.isfinite(v) for r in steps for v in r.values())
    out = write_stage(st, tmp_path / "stage.json")
    text = out.read_text()
    back = json.loads(text, parse_constant=_refuse_constant)
    assert back == read_stage(out)
    failed = [r for r in back["derivation"]["steps"] if r["step"] in (4, 5)]
    assert len(failed) >= 2 and all(r["stacking_angle"] is None for r in failed)
    # the shared writer: infinities and NumPy NaN too, at any depth
    write_json({"a": [np.float64(np.inf), -np.inf, {"b": np.nan}], "c": np.float32(1.5), "d": (1, np.nan)},
               tmp_path / "x.json")
    assert json.loads((tmp_path / "x.json").read_text(), parse_constant=_refuse_constant) == \
        {"a": [None, None, {"b": None}], "c": 1.5, "d": [1, None]}
