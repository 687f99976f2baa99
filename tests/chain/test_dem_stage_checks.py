"""Start-up checks of the stages the DEM source runs (soilcal.chain.derive.check_dem_stages,
called by the soil loader through the simulation block's check) and the Plackett-Burman run
count a stage asks for.

A user's own DEM-only soil (no printed table): a 6-factor screening of 12 runs, then a
Box-Behnken design on three of its parameters.  No DEM run: only loading and designs.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from soilcal.chain.derive import check_dem_stages, dem_stage
from soilcal.chain.files import write_stage_design
from soilcal.chain.stage import generated_design
from soilcal.config.load import load_soil
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]

SOIL = {
    "name": "my-loam",
    "source": "dem",
    "seed": 7,
    "parameters": {
        "e_ss": {"name": "soil-soil restitution", "unit": "-", "pair": "soil-soil", "kind": "restitution"},
        "mu_ss": {"name": "soil-soil static friction", "unit": "-", "pair": "soil-soil", "kind": "static_friction"},
        "mur_ss": {"name": "soil-soil rolling friction", "unit": "-", "pair": "soil-soil",
                   "kind": "rolling_friction"},
        "e_st": {"name": "soil-steel restitution", "unit": "-", "pair": "soil-steel", "kind": "restitution"},
        "mu_st": {"name": "soil-steel static friction", "unit": "-", "pair": "soil-steel",
                  "kind": "static_friction"},
        "gamma": {"name": "JKR surface energy", "unit": "J/m^2", "pair": "soil-soil", "kind": "surface_energy"},
    },
    "stages": [
        {"id": "screen", "kind": "plackett_burman", "runs": 12,
         "factors": {"A": {"parameter": "e_ss", "low": 0.2, "high": 0.7},
                     "B": {"parameter": "mu_ss", "low": 0.2, "high": 0.9},
                     "C": {"parameter": "mur_ss", "low": 0.02, "high": 0.25},
                     "D": {"parameter": "e_st", "low": 0.2, "high": 0.7},
                     "E": {"parameter": "mu_st", "low": 0.3, "high": 0.9},
                     "F": {"parameter": "gamma", "low": 0.0, "high": 0.8}},
         "responses": [{"id": "repose", "name": "Repose angle", "unit": "deg"}]},
        {"id": "rsm", "kind": "box_behnken", "center_points": 3,
         "factors": {"A": {"parameter": "mu_ss", "low": 0.3, "high": 0.8},
                     "B": {"parameter": "mur_ss", "low": 0.05, "high": 0.2},
                     "C": {"parameter": "gamma", "low": 0.1, "high": 0.6}},
         "fixed": {"e_ss": 0.45, "e_st": 0.45, "mu_st": 0.6},
         "responses": [{"id": "repose", "name": "Repose angle", "unit": "deg"}],
         "optimise": {"method": "desirability",
                      "cases": [{"id": "repose", "goals": {"repose": {"goal": "target", "target": "repose"}}}]}},
    ],
    "targets": {"repose": {"value": 36.0, "unit": "deg"}},
    "simulation": {"responses": {"repose": {"scenario": "repose", "setup": "cinnamon-soil", "measure": "angle_deg",
                                            "set": {"n_particles": 300}}},
                   # the soil parameters no stage varies or fixes (soilcal.chain.provenance)
                   "params": {"soil_steel_rolling_friction": 0.1, "soil_density": 1500.0, "soil_poisson": 0.3,
                              "soil_shear_modulus": 1.0e6}},
}


def _write(tmp_path: Path, edit=None) -> Path:
    d = copy.deepcopy(SOIL)
    if edit:
        edit(d)
    p = tmp_path / "my-loam.yaml"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    return p


def _load(path: Path):
    return load_soil(path, ROOT / "resources")


def _refused(tmp_path: Path, edit) -> tuple[Path, InputError]:
    """The soil file written with ``edit`` and the InputError its loading raises."""
    p = _write(tmp_path, edit)
    with pytest.raises(InputError) as e:
        _load(p)
    return p, e.value


def _stage(d: dict, sid: str) -> dict:
    return next(s for s in d["stages"] if s["id"] == sid)


def test_the_soil_loads(tmp_path):
    soil = _load(_write(tmp_path))
    assert [s["id"] for s in soil.stages] == ["screen", "rsm"]


# --------------------------------------------------------------------------- from_stage


def _bbd_after_screen(d):
    _stage(d, "rsm")["from_stage"] = "screen"


def test_a_box_behnken_after_a_screening_is_refused_at_load_naming_the_file(tmp_path):
    p, err = _refused(tmp_path, _bbd_after_screen)
    assert err.path == str(p) and err.field == "stages.rsm.from_stage"
    assert err.got == "box_behnken after plackett_burman"
    assert "steepest ascent after a Plackett-Burman screening" in err.expected
    assert len(str(err).splitlines()) == 1


@pytest.mark.parametrize("other", [
    lambda d: d["simulation"].update(stages=["rsm"]),      # the screening is not simulated
    lambda d: d["simulation"].update(design="printed"),    # every stage on its config levels
], ids=["screening-not-simulated", "printed-levels"])
def test_a_box_behnken_after_a_screening_that_is_not_derived_from_loads(tmp_path, other):
    _load(_write(tmp_path, lambda d: (_bbd_after_screen(d), other(d))))


def test_a_design_override_to_the_recipe_is_checked_again():
    """The workflow's --config design=recipe reaches a soil after it loaded: the same check."""
    d = copy.deepcopy(SOIL)
    _bbd_after_screen(d)
    d["simulation"]["design"] = "printed"
    check_dem_stages("my-loam.yaml", d)
    d["simulation"]["design"] = "recipe"
    with pytest.raises(InputError, match="stages.rsm.from_stage"):
        check_dem_stages("my-loam.yaml", d)


# --------------------------------------------------------------------------- DEM parameters


@pytest.mark.parametrize("edit, field, got, used_by", [
    (lambda d: d["parameters"]["mu_ss"].update(pair="soil"), "parameters.mu_ss", "soil_static_friction",
     "stages.screen.factors.B.parameter"),
    (lambda d: d["parameters"]["e_ss"].update(kind="other"), "parameters.e_ss", "soil_soil_other",
     "stages.screen.factors.A.parameter"),
    # a parameter only the Box-Behnken stage fixes
    (lambda d: (d["parameters"].update(nu={"name": "Poisson ratio", "unit": "-", "pair": "soil",
                                           "kind": "poisson_ratio"}),
                _stage(d, "rsm")["fixed"].update(nu=0.3)), "parameters.nu", "soil_poisson_ratio",
     "stages.rsm.fixed.nu"),
], ids=["pair", "kind", "fixed"])
def test_a_parameter_that_sets_no_dem_parameter_is_refused_at_load(tmp_path, edit, field, got, used_by):
    p, err = _refused(tmp_path, edit)
    assert (err.path, err.field, err.got) == (str(p), field, got)
    assert err.expected.startswith("a DEM parameter (") and used_by in str(err)


def test_a_parameter_without_a_pair_names_the_factor(tmp_path):
    p, err = _refused(tmp_path, lambda d: d["parameters"]["gamma"].pop("pair"))
    assert (err.field, err.got) == ("stages.screen.factors.F.parameter", "gamma")


@pytest.mark.parametrize("edit, field", [
    (lambda d: _stage(d, "rsm")["fixed"].update(e_st=1.5), "stages.rsm.fixed.e_st"),
    (lambda d: _stage(d, "screen")["factors"]["B"].update(low=-0.1), "stages.screen.factors.B.low"),
], ids=["fixed", "level"])
def test_a_value_outside_the_physical_range_is_refused_at_load(tmp_path, edit, field):
    p, err = _refused(tmp_path, edit)
    assert (err.path, err.field) == (str(p), field)
    assert "DEM parameter soil_" in err.expected


# --------------------------------------------------------------------------- Plackett-Burman runs

# Plackett & Burman (1946): the 12-run design's printed first row; row i (i = 0..10) is that
# row shifted i places to the right, so entry (i, j) is the printed sign j - i (mod 11) places
# along; row 12 is all minus.
PB12_PRINTED = "+ + - + + + - - - + -".split()


def _pb12_first_columns(k: int) -> np.ndarray:
    g = [1.0 if c == "+" else -1.0 for c in PB12_PRINTED]
    rows = [[g[(j - i) % 11] for j in range(11)] for i in range(11)] + [[-1.0] * 11]
    return np.array(rows)[:, :k]



def test_twelve_runs_of_six_factors_are_generated_as_asked(tmp_path):
    """An N-run Plackett-Burman design has N - 1 orthogonal columns: 12 runs of 6 factors are
    the first 6 columns of the 12-run design, the design 6 factors and 5 dummies give."""
    soil = _load(_write(tmp_path))
    st = soil.stage("screen")
    x = generated_design(st)
    assert x.shape == (12, 6)
    assert np.array_equal(x.T @ x, 12 * np.eye(6))  # orthogonal two-level columns
    dummies = dict(st, dummies=["G", "H", "I", "J", "K"])
    assert np.array_equal(generated_design(dummies)[:, :6], x)
    assert np.array_equal(x, _pb12_first_columns(6))
    assert (x == 1).sum(axis=0).tolist() == [6] * 6  # balanced: six runs at each level
    # without runs: the smallest design for 6 columns, 8 runs
    assert generated_design({k: v for k, v in st.items() if k != "runs"}).shape == (8, 6)


def test_design_csv_of_the_dem_screening_has_the_runs_of_stage_json(tmp_path):
    soil = _load(_write(tmp_path))
    targets = {"repose": {"value": 36.0, "source": "measurement"}}
    tcsv = tmp_path / "targets.csv"
    pd.DataFrame([{"target_id": "repose", "value": 36.0, "unit": "deg", "source": "measurement"}]).to_csv(tcsv,
                                                                                                      index=False)
    out = {"stage": tmp_path / "stage.json", "design": tmp_path / "design.csv", "check": tmp_path / "check.csv"}
    write_stage_design("dem", soil.stage("screen"), soil.data, {"targets": tcsv}, out)
    stage = json.loads(out["stage"].read_text())
    design = pd.read_csv(out["design"])
    assert stage["runs"] == 12 == len(design)
    assert stage == dem_stage(soil.data, "screen", targets)
    # the DEM jobs run the rows of design.csv: the generated design in actual units
    lo = np.array([0.2, 0.2, 0.02, 0.2, 0.3, 0.0])
    hi = np.array([0.7, 0.9, 0.25, 0.7, 0.9, 0.8])
    actual = design[[f"{s}_actual" for s in "ABCDEF"]].to_numpy(float)
    assert np.allclose(actual, (lo + hi) / 2 + _pb12_first_columns(6) * (hi - lo) / 2, atol=1e-12)


@pytest.mark.parametrize("runs, dummies", [(10, []), (8, ["G", "H"]), (4, [])])
def test_a_run_count_no_plackett_burman_design_has_is_refused_at_load(tmp_path, runs, dummies):
    def edit(d):
        _stage(d, "screen").update(runs=runs, **({"dummies": dummies} if dummies else {}))

    p, err = _refused(tmp_path, edit)
    cols = 6 + len(dummies)
    assert (err.path, err.field, err.got) == (str(p), "stages[0].runs", runs)
    assert f"a multiple of 4 above the {cols} factors and dummies" in err.expected


# --------------------------------------------------------------------------- a path's target


def _path_between(d):
    """A steepest-ascent stage between the screening and the Box-Behnken design, derived from
    the screening (the DEM lays it out towards the target)."""
    path = {"id": "climb", "kind": "steepest_ascent", "from_stage": "screen",
            "factors": {"A": {"parameter": "mu_ss"}, "B": {"parameter": "mur_ss"}, "C": {"parameter": "gamma"}},
            "fixed": {"e_ss": 0.45, "e_st": 0.45, "mu_st": 0.6},
            "responses": [{"id": "repose", "name": "Repose angle", "unit": "deg"}]}
    d["stages"].insert(1, path)


@pytest.mark.parametrize("target, loads", [
    ({"value": 36.0, "unit": "deg"}, True),
    ({"value": None, "unit": "deg", "note": "not measured yet"}, False),   # listed, but nothing to aim at
    ({"unit": "deg"}, False),
], ids=["value", "value-null", "no-value"])
def test_a_path_whose_target_has_no_value_is_refused_at_load(tmp_path, target, loads):
    """The path's direction needs a target value (or a photo group to measure it on); without
    one the screening's DEM runs would all be spent before the path job stopped."""
    p = _write(tmp_path, lambda d: (_path_between(d), d["targets"].update(repose=target)))
    if loads:
        _load(p)
        return
    with pytest.raises(InputError) as e:
        _load(p)
    assert e.value.path == str(p) and e.value.field == "stages.climb.responses" and e.value.got == ["repose"]
    assert "a target with a value or a photo group" in e.value.expected


# --------------------------------------------------------------------------- design: adaptive on a recipe soil


def _recipe_chain(d):
    """screen -> climb -> rsm, the path and the Box-Behnken levels left to the recipe."""
    _path_between(d)
    rsm = _stage(d, "rsm")
    rsm["from_stage"] = "climb"
    rsm["factors"] = {s: {"parameter": f["parameter"]} for s, f in rsm["factors"].items()}


def test_design_adaptive_on_a_soil_whose_later_stages_have_no_levels_takes_the_screening_ranges(tmp_path):
    """With design: adaptive the screening and the path are not run, and the optimised stage's
    factors range over the screening's levels (ranges: screening): the levels the recipe would
    derive are not asked for."""
    from soilcal.chain.adaptive import stage_for

    p = _write(tmp_path, lambda d: (_recipe_chain(d), d["simulation"].update(design="adaptive")))
    soil = _load(p)
    st = stage_for(soil.data, "rsm")
    got = {s: (f["parameter"], f["low"], f["high"]) for s, f in st["factors"].items()}
    # the screening stage's own levels of these parameters (SOIL above)
    assert got == {"A": ("mu_ss", 0.2, 0.9), "B": ("mur_ss", 0.02, 0.25), "C": ("gamma", 0.0, 0.8)}


def test_design_adaptive_with_the_stage_ranges_needs_the_stage_levels(tmp_path):
    p = _write(tmp_path, lambda d: (_recipe_chain(d), d["simulation"].update(design="adaptive",
                                                                              adaptive={"ranges": "stage"})))
    with pytest.raises(InputError) as e:
        _load(p)
    assert e.value.path == str(p) and e.value.field == "stages.rsm.factors.A"
    assert e.value.expected.startswith("low and high levels to simulate the stage (or simulation.adaptive.ranges")
    # the adaptive design takes no declared range (simulation.search_ranges): no advice to declare one
    assert "search_ranges" not in e.value.expected


# --------------------------------------------------------------------------- units of a simulated response


@pytest.mark.parametrize("unit, measure, loads", [
    ("deg", "angle_deg", True),
    ("rad", "angle_deg", False),      # the DEM gives degrees; a target of 0.63 rad would be aimed at as 0.63 deg
    ("mm", "height_m", False),
    ("m", "height_m", True),
    # compared without surrounding spaces, as a target's unit is compared with its response's
    (" deg", "angle_deg", True),
    ("deg ", "angle_deg", True),
    ("rad ", "angle_deg", False),
])
def test_a_response_in_another_unit_than_its_measure_is_refused_at_load(tmp_path, unit, measure, loads):
    def edit(d):
        for st in d["stages"]:
            st["responses"][0]["unit"] = unit
        d["targets"]["repose"]["unit"] = unit
        d["simulation"]["responses"]["repose"]["measure"] = measure

    p = _write(tmp_path, edit)
    if loads:
        _load(p)
        return
    with pytest.raises(InputError) as e:
        _load(p)
    assert (e.value.path, e.value.field, e.value.got) == (str(p), "stages[0].responses[0].unit", unit)
    assert e.value.expected.startswith(f"{measure.rsplit('_', 1)[1]}, the unit of simulation.responses.repose.measure")


# --------------------------------------------------------------------------- a Box-Behnken design needs three factors


def test_a_box_behnken_stage_of_two_factors_is_refused_at_load(tmp_path):
    """The Box-Behnken design exists for three factors and more: a stage of two would stop its
    design job, with no file named."""
    def two(d):
        rsm = _stage(d, "rsm")
        rsm["factors"].pop("C")
        rsm["fixed"]["gamma"] = 0.3

    p, err = _refused(tmp_path, two)
    assert (err.path, err.field, err.got) == (str(p), "stages[1].factors", "2 (A, B)")
    assert err.expected.startswith("at least 3 factors for a Box-Behnken design")


@pytest.mark.parametrize("screening", [{"min_factors": 2}, {"min_factors": 2, "max_factors": 5}])
def test_a_path_before_a_box_behnken_design_takes_at_least_three_factors(tmp_path, screening):
    """With min_factors 2 the path keeps two factors when only two are significant, and the
    Box-Behnken design derived from it would stop after the screening's and the path's runs."""
    p, err = _refused(tmp_path, lambda d: (_recipe_chain(d), d["simulation"].update(screening=screening)))
    assert (err.path, err.field, err.got) == (str(p), "simulation.screening.min_factors", 2)
    assert "Box-Behnken stage 'rsm', which needs at least 3" in err.expected


# --------------------------------------------------------------------------- a simulated Box-Behnken centre


@pytest.mark.parametrize("centre, refused", [(0.55, False), (0.559, False), (0.562, True), (0.4, True)])
def test_a_simulated_box_behnken_centre_off_the_midpoint_is_refused(tmp_path, centre, refused):
    """Factor A of the Box-Behnken stage runs 0.3-0.8: its runs' coded 0 is 0.55 whatever
    centre says; a centre off it by more than 2 % of the range (0.01) would be dropped without a
    word, a printed rounding within it is kept."""
    p = _write(tmp_path, lambda d: _stage(d, "rsm")["factors"]["A"].update(centre=centre))
    if not refused:
        _load(p)
        return
    with pytest.raises(InputError) as e:
        _load(p)
    assert (e.value.path, e.value.field, e.value.got) == (str(p), "stages.rsm.factors.A.centre", centre)
    assert e.value.expected.startswith("the midpoint of low and high (0.55)")


def test_a_path_on_its_own_levels_with_uneven_steps_is_refused_at_load(tmp_path):
    """A steepest-ascent stage the DEM runs on the soil's own levels (no printed table): a factor
    of two steps beside factors of three would stop its design job (a table of three rows
    cannot take two values)."""
    def uneven(d):
        _path_between(d)
        d["simulation"]["design"] = "printed"
        climb = _stage(d, "climb")
        climb["factors"] = {"A": {"parameter": "mu_ss", "levels": [0.3, 0.4, 0.5]},
                            "B": {"parameter": "mur_ss", "levels": [0.05, 0.1]},
                            "C": {"parameter": "gamma", "levels": [0.1, 0.2, 0.3]}}

    p, err = _refused(tmp_path, uneven)
    assert (err.path, err.field, err.got) == (str(p), "stages.climb.factors", [2, 3])
    assert err.expected == "the same number of levels for every factor"


def test_the_adaptive_designs_stage_and_its_start_up_check_take_the_screening_range_from_one_rule(
        tmp_path, monkeypatch):
    """Which range design: adaptive takes from the screening is one rule
    (soilcal.chain.adaptive.adaptive_range) for the stage it runs and for the start-up check
    that the stage has a range: a rule that gives mu_ss 0.25-0.85 and nothing else reaches both."""
    from soilcal.chain import adaptive

    p = _write(tmp_path, lambda d: (_recipe_chain(d), d["simulation"].update(design="adaptive")))
    soil = _load(p)
    mu, e = (adaptive.adaptive_range(soil.data, "rsm", par) for par in ("mu_ss", "e_ss"))
    assert (mu.low, mu.high, mu.field) == (0.2, 0.9, "stages.screen.factors.B")  # the screening's B
    assert (e.low, e.high, e.field) == (0.2, 0.7, "stages.screen.factors.A")     # the screening's A
    assert adaptive.adaptive_range(soil.data, "screen", "mu_ss") is None         # no screening above it
    only_mu = {"mu_ss": adaptive.SearchRange(0.25, 0.85, "a rule", "declared")}
    monkeypatch.setattr(adaptive, "adaptive_range", lambda data, sid, par: only_mu.get(par))
    st = adaptive.stage_for(soil.data, "rsm")
    assert (st["factors"]["A"]["low"], st["factors"]["A"]["high"]) == (0.25, 0.85)
    assert st["factors"]["B"].get("low") is None  # mur_ss: no range from the rule
    with pytest.raises(InputError) as e:
        _load(p)
    assert (e.value.path, e.value.field) == (str(p), "stages.rsm.factors.B")


@pytest.mark.parametrize("target, aimed", [
    ({"value": 36.0, "unit": "deg"}, True),
    ({"value": None, "unit": "deg", "image": "heap"}, True),   # a photo group gives it
    ({"value": None, "unit": "deg"}, False),
], ids=["value", "photo-group", "nothing"])
def test_a_goal_has_a_value_to_aim_at_by_one_rule_for_the_path_and_the_adaptive_design(target, aimed):
    """A goal with ``value: null`` beside ``target: <id>`` (as a soil built in code may carry it)
    aims at the target: the path's start-up check and the adaptive design's case selection
    read it alike (soilcal.chain.targets.goal_has_value)."""
    from soilcal.chain.adaptive import _why_not
    from soilcal.chain.targets import goal_has_value
    from soilcal.dem.scenarios.design import _has_target

    d = copy.deepcopy(SOIL)
    d["targets"] = {"t": target}
    case = {"id": "c", "goals": {"repose": {"goal": "target", "value": None, "target": "t"}}}
    _stage(d, "rsm")["optimise"]["cases"] = [case]
    assert goal_has_value(d, case["goals"]["repose"]) is aimed
    assert _has_target(d, ["repose"]) is aimed
    assert (_why_not(d, case) == "") is aimed


@pytest.mark.parametrize("recipe_chain", [False, True], ids=["stage-levels", "recipe-levels"])
def test_design_adaptive_checks_the_screening_range_its_stage_takes(tmp_path, recipe_chain):
    """With design: adaptive (ranges: screening) the screening is not run, but the optimised
    stage that descends from it ranges mu_ss over the screening's B levels: a high of 7.0,
    beyond a sliding friction coefficient's [0, 5], is refused at load naming the screening's
    field (the stage's own levels of mu_ss, 0.3-0.8, or none, are not the ones run)."""
    def edit(d):
        if recipe_chain:
            _recipe_chain(d)
        else:
            _bbd_after_screen(d)
        d["simulation"]["design"] = "adaptive"
        _stage(d, "screen")["factors"]["B"]["high"] = 7.0

    p, err = _refused(tmp_path, edit)
    assert (err.path, err.field, err.got) == (str(p), "stages.screen.factors.B.high", 7.0)
    assert err.expected.startswith("a sliding friction coefficient in [0, 5]")
    # with ranges: stage the stage keeps its own levels (0.3-0.8), and the screening is not used;
    # neither is it by a stage that does not descend from it
    if not recipe_chain:
        _load(_write(tmp_path, lambda d: (edit(d), d["simulation"].update(adaptive={"ranges": "stage"}))))
        _load(_write(tmp_path, lambda d: (edit(d), _stage(d, "rsm").pop("from_stage"))))


def test_a_box_behnken_centre_no_run_is_decoded_from_is_not_checked(tmp_path):
    """The centre check guards the runs decoded from low and high (coded 0 at 0.55 for A's
    0.3-0.8); with design: adaptive on the stage's own ranges (ranges: stage) the runs range
    over low .. high and no design is decoded, so a centre of 0.4 is not refused; the recipe
    runs the generated design and refuses it."""
    def off(d):
        _stage(d, "rsm")["factors"]["A"]["centre"] = 0.4
        d["simulation"]["adaptive"] = {"ranges": "stage"}

    _load(_write(tmp_path, lambda d: (off(d), d["simulation"].update(design="adaptive"))))
    with pytest.raises(InputError) as e:
        _load(_write(tmp_path, off))
    assert e.value.field == "stages.rsm.factors.A.centre"


@pytest.mark.parametrize("design, refused", [("printed", False), ("recipe", True)])
def test_a_box_behnken_centre_of_a_table_printed_in_actual_units_is_checked_only_where_decoded(
        tmp_path, design, refused):
    """The black soil's soil-soil Box-Behnken table is printed in actual units: design: printed
    runs its rows as printed, so a centre of x4 off the midpoint of 0.05-0.50 (0.275) by more
    than 2 % of the range is not used and loads; the recipe decodes its generated design from
    low and high and refuses it."""
    d = yaml.safe_load((ROOT / "config/soils/black-soil.yaml").read_text())
    d["stages"][0]["factors"]["x4"]["centre"] = 0.33
    p = tmp_path / "black-soil.yaml"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    if not refused:
        load_soil(p, ROOT / "resources", design=design)
        return
    with pytest.raises(InputError) as e:
        load_soil(p, ROOT / "resources", design=design)
    assert (e.value.field, e.value.got) == ("stages.soil-soil.factors.x4.centre", 0.33)
    assert e.value.expected.startswith("the midpoint of low and high (0.275)")


def test_a_box_behnken_design_derived_from_a_path_of_two_factors_on_its_own_levels_is_refused(tmp_path):
    """The recipe derives the Box-Behnken design from the path's factors: a path the DEM runs on
    its own levels (no screening before it) over two factors would give a design of two, which
    does not exist, and stop its design job after the path's runs, naming no file."""
    def two_factor_path(d):
        _recipe_chain(d)
        climb = _stage(d, "climb")
        climb.pop("from_stage")
        climb["factors"] = {"A": {"parameter": "mu_ss", "levels": [0.3, 0.4, 0.5]},
                            "B": {"parameter": "mur_ss", "levels": [0.05, 0.1, 0.15]}}
        climb["fixed"]["gamma"] = 0.3

    p, err = _refused(tmp_path, two_factor_path)
    assert (err.path, err.field, err.got) == (str(p), "stages.climb.factors", "2 (A, B)")
    assert err.expected.startswith("at least 3 factors: Box-Behnken stage 'rsm' is derived from this path")
    from soilcal.doe.designs import BBD_MIN_FACTORS, box_behnken

    assert BBD_MIN_FACTORS == 3
    with pytest.raises(InputError):
        box_behnken(2, 3)
    # a third factor on the path: the design of three
    _load(_write(tmp_path, lambda d: (two_factor_path(d), _stage(d, "climb")["fixed"].pop("gamma"),
                                      _stage(d, "climb")["factors"].update(
                                          C={"parameter": "gamma", "levels": [0.1, 0.2, 0.3]}))))


@pytest.mark.parametrize("setting", ["recipe-path", "published-only"])
def test_uneven_path_levels_no_run_takes_load(tmp_path, setting):
    """A path's config levels with two steps for one factor and three for the others are
    refused only where the DEM runs them: a path the recipe lays out from the screening takes
    its steps from there, and a soil replayed from its printed tables (source: published) does
    not run a stage whose table is not printed."""
    def uneven(d):
        _path_between(d)
        climb = _stage(d, "climb")
        climb["factors"]["A"]["levels"] = [0.3, 0.4, 0.5]
        climb["factors"]["B"]["levels"] = [0.05, 0.1]
        climb["factors"]["C"]["levels"] = [0.1, 0.2, 0.3]
        if setting == "published-only":
            d["source"] = "published"
            d.pop("simulation")

    soil = _load(_write(tmp_path, uneven))
    assert [len(f["levels"]) for f in soil.stage("climb")["factors"].values()] == [3, 2, 3]


def test_design_adaptive_takes_the_other_parameters_where_the_readme_says(tmp_path):
    """README, the adaptive design: with the screening and the path not run, the other soil
    parameters come from the stage's fixed values, simulation.params or the printed properties
    (not the skipped stages' fixed values).  The soil density given only as
    properties.particle_density loads; given nowhere, start-up names it."""
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert ("every other soil parameter the runs use comes from the stage's `fixed` values, "
            "`simulation.params` or the printed `properties`") in readme

    def adaptive_recipe(d):
        _recipe_chain(d)
        d["simulation"]["design"] = "adaptive"
        d["simulation"]["params"].pop("soil_density")

    _load(_write(tmp_path, lambda d: (adaptive_recipe(d), d.update(
        properties={"particle_density": {"value": 2650.0, "unit": "kg/m^3"}}))))
    # in the skipped path's fixed values only: not a value the adaptive runs take
    p = _write(tmp_path, lambda d: (adaptive_recipe(d), d["parameters"].update(
        rho={"name": "particle density", "unit": "kg/m^3", "pair": "soil", "kind": "density"}),
        _stage(d, "climb")["fixed"].update(rho=2650.0)))
    with pytest.raises(InputError) as e:
        _load(p)
    assert (e.value.path, e.value.field) == (str(p), "simulation.params")
    assert "missing: soil_density (or properties.particle_density with its unit)" in e.value.expected
