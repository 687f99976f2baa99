"""A soil's declared search ranges (``simulation.search_ranges``): the one lookup of the range a
factor may be searched over (soilcal.chain.adaptive.second_round_range: the declared range
wherever it is declared, else the screening's, else none), its use by the second calibration round
(soilcal.chain.stage.screening_ranges, soilcal.chain.refine; design: printed keeps the box), the
adaptive design's ranges (its screening's or the stage's own: a declared range is recorded as not
used), its checks as the soil loads
(soilcal.config.load.check_search_ranges) and which rules' params carry it
(soilcal.chain.plan.dem_context, soilcal.chain.provenance.setup_inputs).

The second-round tests use the stand-in of test_refine: responses exactly y = 30 + 2 A (A coded,
actual 0.5 + 0.5 A), so the corrected surface is 30 + b + 2 A and the set meeting a target T is
A = (T - 30 - b) / 2."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
import yaml

from soilcal.chain.adaptive import adaptive_range, second_round_range, stage_for
from soilcal.chain.plan import dem_context
from soilcal.chain.provenance import setup_inputs
from soilcal.chain.refine import refine_frame
from soilcal.chain.stage import screening_ranges, unused_search_ranges
from soilcal.config.load import load_soil
from soilcal.errors import InputError
from test_refine import OPTIMUM, _runs, _stage, _table

ROOT = Path(__file__).resolve().parents[2]

# a screening of A's and B's parameters, a path, a Box-Behnken on A, B, C; the soil declares
# ranges for A's parameter (screened too) and C's (not screened)
SOIL_YAML = """
parameters:
  gamma: {name: JKR surface energy, unit: J/m^2, pair: soil-soil, kind: surface_energy}
  mu: {name: soil-soil static friction, unit: "-", pair: soil-soil, kind: static_friction}
  e: {name: soil-steel restitution, unit: "-", pair: soil-steel, kind: restitution}
stages:
  - id: pb
    kind: plackett_burman
    factors:
      X1: {parameter: gamma, low: 0, high: 5}
      X2: {parameter: mu, low: 0.2, high: 1.0}
  - {id: path, kind: steepest_ascent, from_stage: pb, factors: {}}
  - id: bbd
    kind: box_behnken
    from_stage: path
    factors:
      A: {parameter: gamma, low: 0.5, high: 1.5}
      B: {parameter: mu, low: 0.4, high: 0.6}
      C: {parameter: e, low: 0.3, high: 0.5}
    responses: [{id: angle, name: angle of repose, unit: deg}]
simulation:
  search_ranges:
    gamma: {low: 0, high: 10, source: "a test"}
    e: {low: 0.1, high: 0.9, source: "a test"}
"""


def _soil(design=None):
    soil = yaml.safe_load(SOIL_YAML)
    if design:
        soil["simulation"]["design"] = design
    return soil


def test_the_lookup_takes_the_declared_range_else_the_screening_else_none():
    soil = _soil()
    # gamma: screened over 0..5 and declared 0..10: the declaration wins, screening counted or not
    for screening in (True, False):
        got = second_round_range(soil, "bbd", "gamma", screening=screening)
        assert (got.low, got.high, got.kind, got.field) == (0.0, 10.0, "declared", "simulation.search_ranges.gamma")
    got = second_round_range(soil, "bbd", "e")  # not screened: declared
    assert (got.low, got.high, got.field) == (0.1, 0.9, "simulation.search_ranges.e")
    got = second_round_range(soil, "bbd", "mu")  # not declared: the screening's
    assert (got.low, got.high, got.kind, got.field) == (0.2, 1.0, "screening", "stages.pb.factors.X2")
    assert second_round_range(soil, "bbd", "mu", screening=False) is None  # neither


@pytest.mark.parametrize("design, stages, kind", [
    ("recipe", None, "path"),               # every stage simulated, the Box-Behnken derived from the path
    ("recipe", ["pb", "bbd"], "config"),    # the screening simulated, the Box-Behnken on its printed levels
    ("recipe", ["bbd"], "config"),          # no screening simulated
])
def test_the_second_round_takes_a_declared_range_in_every_recipe_case(design, stages, kind):
    soil = _soil(design)
    if stages:
        soil["simulation"]["stages"] = stages
    st = {**soil["stages"][2], "derivation": {"kind": kind}}
    ranges = screening_ranges(soil, st)
    assert ranges["A"] == (0.0, 10.0, "declared search range 0..10 (simulation.search_ranges.gamma)")
    assert ranges["C"][:2] == (0.1, 0.9)
    # mu, not declared: the screening's where the stage descends from the simulated path, else none
    assert ranges.get("B", (None, None))[:2] == ((0.2, 1.0) if kind == "path" else (None, None))
    assert unused_search_ranges(soil, st) == []


def test_a_printed_design_keeps_the_box_and_names_the_declared_ranges_not_used():
    soil = _soil("printed")
    st = {**soil["stages"][2], "derivation": {"kind": "config"}}
    assert screening_ranges(soil, st) == {}
    assert unused_search_ranges(soil, st) == [
        "A: declared search range 0..10 (simulation.search_ranges.gamma)",
        "C: declared search range 0.1..0.9 (simulation.search_ranges.e)"]
    assert screening_ranges(_soil("adaptive"), st) == {}


def test_a_screening_range_is_quoted_as_used_after_widening_to_the_box():
    # the screening of mu spans 0.5..1.0, the box 0.4..0.6: the second round searches 0.4..1.0
    soil = _soil()
    soil["stages"][0]["factors"]["X2"]["low"] = 0.5
    st = {**soil["stages"][2], "derivation": {"kind": "path"}}
    assert screening_ranges(soil, st)["B"] == (0.4, 1.0, "screening range 0.4..1 (stages.pb.factors.X2)")


def test_the_adaptive_design_keeps_its_screening_ranges_and_records_a_declared_range_as_not_used():
    soil = _soil("adaptive")
    # the screening's range, declared or not (gamma is declared 0..10 and screened 0..5); e is
    # declared but not screened: the stage's own 0.3..0.5
    assert adaptive_range(soil, "bbd", "gamma").field == "stages.pb.factors.X1"
    assert adaptive_range(soil, "bbd", "e") is None
    st = stage_for(soil, "bbd")
    assert {s: (f["low"], f["high"]) for s, f in st["factors"].items()} == \
        {"A": (0.0, 5.0), "B": (0.2, 1.0), "C": (0.3, 0.5)}
    assert st["derivation"]["ranges"] == {"A": {"low": 0.0, "high": 5.0, "from": "stages.pb.factors.X1"},
                                          "B": {"low": 0.2, "high": 1.0, "from": "stages.pb.factors.X2"}}
    assert "declared ranges not used by the adaptive design" in st["derivation"]["text"]
    assert "A 0-10, C 0.1-0.9" in st["derivation"]["text"]
    # ranges: stage keeps the stage's own, declared or not
    soil["simulation"]["adaptive"] = {"ranges": "stage"}
    assert adaptive_range(soil, "bbd", "e") is None and adaptive_range(soil, "bbd", "gamma") is None
    st = stage_for(soil, "bbd")
    assert {s: (f["low"], f["high"]) for s, f in st["factors"].items()} == \
        {"A": (0.5, 1.5), "B": (0.4, 0.6), "C": (0.3, 0.5)}
    assert "ranges" not in st["derivation"]
    assert "declared ranges not used by the adaptive design" in st["derivation"]["text"]


def test_the_shipped_cohesive_soil_keeps_its_box_adaptively_and_searches_g_to_10_in_the_second_round():
    # guangxi-cohesive: Box-Behnken G 0.04-0.08 J/m^2 (Sec. 3.2), screening level 0-10 J/m^2
    # printed in Sec. 3.1 and declared under simulation.search_ranges
    soil = load_soil(ROOT / "config/soils/guangxi-cohesive.yaml", resources_root=ROOT / "resources").data
    adaptive = dict(soil, simulation={**soil["simulation"], "design": "adaptive"})
    st = stage_for(adaptive, "bbd")
    assert (st["factors"]["G"]["low"], st["factors"]["G"]["high"]) == (0.04, 0.08)
    assert "G 0-10" in st["derivation"]["text"] and "not used" in st["derivation"]["text"]
    recipe = dict(soil, simulation={**soil["simulation"], "design": "recipe"})
    ranges = screening_ranges(recipe, {**st, "derivation": {"kind": "config"}})
    assert ranges == {"G": (0.0, 10.0, "declared search range 0..10 (simulation.search_ranges.jkr_surface_energy)")}


# ------------------------------------------------------------------ the second round


def _energy_stage():
    """The stand-in stage with A a JKR surface energy (box 0..1 J/m^2)."""
    st = _stage()
    st["factors"]["A"]["parameter"] = "jkr_surface_energy"
    st["derivation"] = {"kind": "config"}  # run on its printed levels
    return st


def _declared(low, high, design="recipe"):
    return {"simulation": {"design": design, "search_ranges": {"jkr_surface_energy": {"low": low, "high": high}}}}


def _refined(soil):
    # x0 A coded 0.5 (actual 0.75, surface 31), four seeds averaging 28.5: bias -2.5, so the
    # corrected surface 27.5 + 2 A meets the target 31 at A = 1.75 (actual 1.375), 0.75
    # half-widths past the high bound 1
    stage = _energy_stage()
    opt = OPTIMUM[OPTIMUM["case"] == "biased"]
    runs = {"biased": _runs([28.4, 28.6, 28.5, 28.5])}
    df = refine_frame(stage, _table(), {"y": {"value": 31.0}, "lost": {"value": None}}, opt, runs,
                      screening_ranges(soil, stage), unused_search_ranges(soil, stage))
    return df.set_index("case").loc["biased"]


def test_a_declared_range_lets_the_second_round_reach_a_target_past_the_box():
    r = _refined(_declared(0.0, 10.0))
    assert (r["round"], bool(r["refined"]), r["region"]) == (2, True, "beyond")
    assert r["A_coded"] == pytest.approx(1.75, abs=1e-5) and r["A"] == pytest.approx(1.375, abs=1e-5)
    assert r["y"] == pytest.approx(31.0, abs=1e-5) and r["bias_y"] == pytest.approx(-2.5)
    assert ("A = 1.375 (0.75 half-widths past its high bound 1, inside its declared search range 0..10 "
            "(simulation.search_ranges.jkr_surface_energy))") in r["note"]
    assert r["search_ranges"] == "A: declared search range 0..10 (simulation.search_ranges.jkr_surface_energy)"


def test_the_move_stops_at_the_declared_range():
    # declared 0..1.2 (coded -1..1.4): the compromise stops at A = 1.4, y = 27.5 + 2.8 = 30.3
    r = _refined(_declared(0.0, 1.2))
    assert r["region"] == "beyond" and r["A_coded"] == pytest.approx(1.4, abs=1e-4)
    assert r["A"] == pytest.approx(1.2, abs=1e-4) and r["y"] == pytest.approx(30.3, abs=1e-3)


def test_a_printed_design_stays_in_the_box_and_records_the_declared_range_as_not_used():
    # as without a declared range: the compromise on the box's bound, A = 1, y = 29.5
    r = _refined(_declared(0.0, 10.0, design="printed"))
    assert r["region"] == "inside" and r["A_coded"] == pytest.approx(1.0, abs=1e-4)
    assert r["y"] == pytest.approx(29.5, abs=1e-3)
    assert r["search_ranges"] == ("none: every factor stays in the design box (design: printed, compared point by "
                                  "point with the paper); not used: A: declared search range 0..10 "
                                  "(simulation.search_ranges.jkr_surface_energy)")


def test_without_a_declared_range_the_set_stays_in_the_box():
    # the compromise on the box's bound: A = 1, y = 29.5
    r = _refined({})
    assert r["region"] == "inside" and r["A_coded"] == pytest.approx(1.0, abs=1e-4)
    assert r["search_ranges"].startswith("none: every factor stays in the design box")


# ------------------------------------------------------------------ checks as the soil loads


def _load(tmp_path, ranges, design=None, parameters=None, data=None):
    if data is None:
        data = yaml.safe_load((ROOT / "config/soils/guangxi-cohesive.yaml").read_text(encoding="utf-8"))
    data["simulation"]["search_ranges"] = ranges
    if design:
        data["simulation"]["design"] = design
    data["parameters"].update(parameters or {})
    path = tmp_path / "guangxi-cohesive.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return load_soil(path, resources_root=ROOT / "resources")


def test_the_shipped_cohesive_soil_declares_the_printed_surface_energy_range():
    soil = load_soil(ROOT / "config/soils/guangxi-cohesive.yaml", resources_root=ROOT / "resources")
    declared = soil.data["simulation"]["search_ranges"]
    assert list(declared) == ["jkr_surface_energy"]  # A and B: nothing printed
    assert (declared["jkr_surface_energy"]["low"], declared["jkr_surface_energy"]["high"]) == (0, 10)  # Sec. 3.1
    st = {**soil.stage("bbd"), "derivation": {"kind": "config"}}
    assert {s: r[:2] for s, r in screening_ranges(soil.data, st).items()} == {"G": (0.0, 10.0)}


@pytest.mark.parametrize("design", ["recipe", "printed", "adaptive"])
@pytest.mark.parametrize("ranges, field, expected", [
    ({"soil_soil_restitution": {"low": 0.3, "high": 0.5, "source": "x"}},
     "simulation.search_ranges.soil_soil_restitution.low", "at most 0.27, the low level of stages.bbd.factors.A"),
    ({"jkr_surface_energy": {"low": 0, "high": 5, "source": "x"}},
     "simulation.search_ranges.jkr_surface_energy.high", "at least 10, the high level of stages.pb.factors.G"),
    # the DEM parameters' own ranges (soilcal.dem.scenarios.base, the check of every DEM run)
    ({"soil_soil_restitution": {"low": 0, "high": 0.5, "source": "x"}},
     "simulation.search_ranges.soil_soil_restitution.low", "a coefficient of restitution in (0, 1]"),
    ({"soil_soil_restitution": {"low": 0.1, "high": 1.2, "source": "x"}},
     "simulation.search_ranges.soil_soil_restitution.high", "a coefficient of restitution in (0, 1]"),
    ({"soil_soil_static_friction": {"low": -0.1, "high": 1, "source": "x"}},
     "simulation.search_ranges.soil_soil_static_friction.low", "sliding friction coefficient in [0, "),
    ({"soil_soil_static_friction": {"low": 0.2, "high": 50, "source": "x"}},
     "simulation.search_ranges.soil_soil_static_friction.high", "sliding friction coefficient in [0, "),
    ({"jkr_surface_energy": {"low": -1, "high": 10, "source": "x"}},
     "simulation.search_ranges.jkr_surface_energy.low", "JKR surface energy in [0, "),
    # mJ/m^2 typed into a J/m^2 parameter
    ({"jkr_surface_energy": {"low": 0, "high": 380, "source": "x"}},
     "simulation.search_ranges.jkr_surface_energy.high", "a soil-soil JKR surface energy in [0, 100] J/m^2"),
    ({"soil_soil_static_friction": {"low": 1, "high": 0.3, "source": "x"}},
     "simulation.search_ranges.soil_soil_static_friction.low", "a finite number below high (0.3)"),
    ({"shear_energy": {"low": 0, "high": 1, "source": "x"}},
     "simulation.search_ranges.shear_energy", "a parameter id listed under parameters"),
])
def test_a_bad_declared_range_is_refused_naming_file_field_and_what_was_expected(tmp_path, ranges, field, expected,
                                                                                  design):
    unused = {"unused_mu": {"name": "steel rolling", "unit": "-", "pair": "soil-steel", "kind": "rolling_friction"}}
    with pytest.raises(InputError) as exc:
        _load(tmp_path, ranges, design=design, parameters=unused)
    assert exc.value.field == field and expected in exc.value.expected
    assert exc.value.path == str(tmp_path / "guangxi-cohesive.yaml")
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("design", ["recipe", "printed", "adaptive"])
@pytest.mark.parametrize("pid, on_the_path, why", [
    # only screened (and fixed in the Box-Behnken)
    ("soil_steel_restitution", False,
     "stages.pb.factors.D is in a stage the DEM source does not run (simulation.stages: bbd)"),
    # set by no stage
    ("unused_mu", False, "no stage varies it"),
    # varied by the climbing stage too, whose levels are lost (Sec. 3.2, Table 7): a range there
    # would never be searched, as the stage is not simulated and has no optimisation
    ("soil_soil_rolling_friction", True,
     "stages.pb.factors.C is in a stage the DEM source does not run (simulation.stages: bbd); "
     "stages.steepest.factors.C is in a stage the DEM source does not run (simulation.stages: bbd)"),
])
def test_a_range_the_second_round_never_uses_is_refused_naming_the_stages_that_vary_it(tmp_path, pid, on_the_path,
                                                                                        why, design):
    """The second round moves the factors of the optimised stages the DEM source runs (the
    cohesive soil: bbd, with simulation.stages: [bbd]); a factor of any other stage does not
    make a declared range usable."""
    data = yaml.safe_load((ROOT / "config/soils/guangxi-cohesive.yaml").read_text(encoding="utf-8"))
    if on_the_path:
        data["stages"][1]["factors"]["C"] = {"parameter": "soil_soil_rolling_friction"}
    unused = {"unused_mu": {"name": "steel rolling", "unit": "-", "pair": "soil-steel", "kind": "rolling_friction"}}
    with pytest.raises(InputError) as exc:
        _load(tmp_path, {pid: {"low": 0.05, "high": 0.9, "source": "x"}}, design=design, parameters=unused,
              data=data)
    assert exc.value.field == f"simulation.search_ranges.{pid}"
    assert exc.value.expected == ("a parameter set by a factor of a stage the second calibration round moves (an "
                                  "optimised stage the DEM source runs: bbd)")
    assert exc.value.note == f"{why}; the range would never be used: delete the entry"
    assert exc.value.path == str(tmp_path / "guangxi-cohesive.yaml") and "\n" not in str(exc.value)


@pytest.mark.parametrize("design", ["recipe", "printed", "adaptive"])
def test_a_declared_range_of_a_soil_without_a_second_round_is_refused(tmp_path, design):
    data = yaml.safe_load((ROOT / "config/soils/guangxi-cohesive.yaml").read_text(encoding="utf-8"))
    data["simulation"]["verification"] = {"refine": False}
    with pytest.raises(InputError) as exc:
        _load(tmp_path, {"jkr_surface_energy": {"low": 0, "high": 10, "source": "Sec. 3.1"}}, design=design,
              data=data)
    assert (exc.value.path, exc.value.field) == (str(tmp_path / "guangxi-cohesive.yaml"), "simulation.search_ranges")
    assert exc.value.expected.startswith("no entry while simulation.verification.refine is false")
    assert exc.value.got == "jkr_surface_energy"
    data["simulation"]["verification"] = {"refine": True}
    _load(tmp_path, {"jkr_surface_energy": {"low": 0, "high": 10, "source": "Sec. 3.1"}}, design=design, data=data)


def test_a_factor_of_an_unoptimised_stage_does_not_make_a_declared_range_usable(tmp_path):
    """Every stage simulated (design: recipe): the Box-Behnken stage is derived from the DEM path,
    which is derived from the DEM screening, so its runs vary the screening's factors the
    screening selects; the path's own factor is no factor the second round moves, nor is it
    with design: printed, where the Box-Behnken stage runs its own factors."""
    from soilcal.config.load import check_search_ranges

    soil = _soil()
    soil["stages"][1]["factors"] = {"D": {"parameter": "e", "levels": [0.3, 0.4, 0.5]}}
    del soil["stages"][2]["factors"]["C"]
    soil["stages"][2]["optimise"] = {"method": "desirability", "cases": []}
    with pytest.raises(InputError) as exc:
        check_search_ranges(tmp_path / "soil.yaml", soil)
    assert exc.value.field == "simulation.search_ranges.e"
    assert exc.value.expected.endswith("(an optimised stage the DEM source runs: bbd, whose DEM runs vary the "
                                       "factors of stage pb (design: recipe))")
    assert exc.value.note.startswith("stages.path.factors.D is in a steepest-ascent stage without an optimise block;")
    soil["simulation"]["design"] = "printed"
    with pytest.raises(InputError) as exc:
        check_search_ranges(tmp_path / "soil.yaml", soil)
    assert exc.value.expected.endswith("(an optimised stage the DEM source runs: bbd)")
    # the screening not simulated: the path runs its own levels, and the Box-Behnken stage
    # derived from it varies the path's factors, D among them
    soil["simulation"]["design"] = "recipe"
    soil["simulation"]["stages"] = ["path", "bbd"]
    gamma = soil["simulation"]["search_ranges"].pop("gamma")  # on no path: refused
    check_search_ranges(tmp_path / "soil.yaml", soil)
    soil["simulation"]["search_ranges"]["gamma"] = gamma
    del soil["simulation"]["search_ranges"]["e"]
    del soil["simulation"]["stages"]
    check_search_ranges(tmp_path / "soil.yaml", soil)  # gamma: a factor of the screening


def test_a_box_behnken_factor_the_recipe_replaces_by_the_screenings_does_not_make_a_range_usable(tmp_path):
    """design: recipe, every stage simulated: the Box-Behnken stage's runs vary the factors the
    DEM screening selects (gamma, mu), not its config factor C (e, screened by no stage)."""
    from soilcal.config.load import check_search_ranges

    soil = _soil()
    soil["stages"][2]["optimise"] = {"method": "desirability", "cases": []}
    with pytest.raises(InputError) as exc:
        check_search_ranges(tmp_path / "soil.yaml", soil)
    assert exc.value.field == "simulation.search_ranges.e"
    assert exc.value.note == ("stages.bbd.factors.C is in a stage whose DEM runs vary the factors of stage pb "
                              "instead (design: recipe); the range would never be used: delete the entry")
    soil["simulation"]["design"] = "printed"  # the stage's own factors: C counts
    check_search_ranges(tmp_path / "soil.yaml", soil)


def _cinnamon(stages=None, ranges=None, design=None):
    data = yaml.safe_load((ROOT / "config/soils/cinnamon-soil.yaml").read_text(encoding="utf-8"))
    if stages:
        data["simulation"]["stages"] = stages
    if ranges:
        data["simulation"]["search_ranges"] = ranges
    if design:
        data["simulation"]["design"] = design
    return data


def _write(tmp_path, data):
    path = tmp_path / "cinnamon-soil.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


RESTITUTION = {"soil_steel_restitution": {"low": 0.1, "high": 0.9, "source": "a test"}}


def test_a_path_factor_counts_where_the_box_behnken_design_is_derived_from_the_path(tmp_path):
    """Cinnamon soil, its path given a fourth factor D on the soil-steel restitution (six levels
    inside the screening's 0.2-0.7, Table 2), the screening not simulated: the path runs its
    own levels and the Box-Behnken stage derived from it (design: recipe) varies A, B, C and D,
    so the second round searches D over the declared 0.1..0.9 (soilcal.chain.stage.screening_ranges)."""
    from soilcal.chain.derive import bbd_from_path, dem_stage

    data = _cinnamon(stages=["steepest", "bbd"], ranges=RESTITUTION)
    path_cfg = data["stages"][1]
    del path_cfg["fixed"]["soil_steel_restitution"], path_cfg["table"]  # Table 5 has no column D
    path_cfg["factors"]["D"] = {"parameter": "soil_steel_restitution", "levels": [0.2, 0.3, 0.4, 0.5, 0.6, 0.7]}
    soil = load_soil(_write(tmp_path, data), resources_root=ROOT / "resources").data
    path = dem_stage(soil, "steepest", {"stacking_angle": {"value": 27.69}})
    # stand-in runs of the path: the angle rises 2 deg a step, closest to 27.69 deg at step 4
    responses = pd.DataFrame({"step": range(1, 7), "stacking_angle": [22.0, 24.0, 26.0, 28.0, 30.0, 32.0]})
    bbd = bbd_from_path(soil, "bbd", path, responses)
    assert bbd["factors"]["D"]["parameter"] == "soil_steel_restitution"
    assert screening_ranges(soil, bbd)["D"] == (
        0.1, 0.9, "declared search range 0.1..0.9 (simulation.search_ranges.soil_steel_restitution)")
    # the same path with the printed design: the Box-Behnken stage runs its own A, B, C
    data["simulation"]["design"] = "printed"
    with pytest.raises(InputError) as exc:
        load_soil(_write(tmp_path, data), resources_root=ROOT / "resources")
    assert exc.value.field == "simulation.search_ranges.soil_steel_restitution"
    assert exc.value.note.startswith("stages.pb.factors.X4 is in a stage the DEM source does not run (simulation."
                                     "stages: steepest, bbd); stages.steepest.factors.D is in a steepest-ascent "
                                     "stage without an optimise block")


@pytest.mark.parametrize("design, loads", [("recipe", True), ("printed", False), ("adaptive", False)])
def test_a_screened_parameter_counts_where_the_box_behnken_design_descends_from_the_dem_screening(
        tmp_path, design, loads):
    """Cinnamon soil, every stage simulated: the recipe's Box-Behnken stage varies the factors
    its DEM screening selects, any of X1..X7 (the soil-steel restitution X4 among them, though
    the paper's path and box fix it at 0.45, Table 3); the printed and adaptive designs run the
    stage's own A, B, C."""
    path = _write(tmp_path, _cinnamon(ranges=RESTITUTION, design=design))
    if loads:
        load_soil(path, resources_root=ROOT / "resources")
        return
    with pytest.raises(InputError) as exc:
        load_soil(path, resources_root=ROOT / "resources")
    assert exc.value.note.startswith("stages.pb.factors.X4 is in a plackett-burman stage without an optimise block;")


@pytest.mark.parametrize("design", ["recipe", "printed", "adaptive"])
def test_a_box_behnken_factor_left_out_of_the_simulated_stages_does_not_make_a_range_usable(tmp_path, design):
    """Cinnamon soil with simulation.stages: [pb, steepest]: its optimised Box-Behnken stage is
    not simulated, so no stage the second round moves varies the surface energy (its factor B
    there)."""
    data = _cinnamon(stages=["pb", "steepest"], design=design)
    del data["measurements"]  # their tool runs take the Box-Behnken stage's optimum
    load_soil(_write(tmp_path, data), resources_root=ROOT / "resources")  # without the range: loads
    data["simulation"]["search_ranges"] = {"jkr_surface_energy": {"low": 0.05, "high": 2, "source": "a test"}}
    with pytest.raises(InputError) as exc:
        load_soil(_write(tmp_path, data), resources_root=ROOT / "resources")
    assert exc.value.field == "simulation.search_ranges.jkr_surface_energy"
    assert exc.value.expected.endswith("(an optimised stage the DEM source runs: none)")
    assert exc.value.note.endswith("stages.bbd.factors.B is in a stage the DEM source does not run (simulation.stages: "
                                   "pb, steepest); the range would never be used: delete the entry")
    assert exc.value.path == str(tmp_path / "cinnamon-soil.yaml") and "\n" not in str(exc.value)


def test_a_declared_range_needs_its_source(tmp_path):
    with pytest.raises(InputError) as exc:
        _load(tmp_path, {"jkr_surface_energy": {"low": 0, "high": 10}})
    assert "search_ranges" in exc.value.field


def test_a_wider_declared_range_loads(tmp_path):
    soil = _load(tmp_path, {"jkr_surface_energy": {"low": 0, "high": 25, "source": "GEMM range, Sec. 3.1"},
                            "soil_soil_static_friction": {"low": 0.2, "high": 1.0, "source": "a choice"}})
    assert screening_ranges(soil.data, {**soil.stage("bbd"), "derivation": {"kind": "config"}})["B"][:2] == (0.2, 1.0)


# ------------------------------------------------------------------ which rules read the ranges


def test_only_the_second_round_and_adaptive_rules_get_the_declared_ranges():
    soil = load_soil(ROOT / "config/soils/guangxi-cohesive.yaml", resources_root=ROOT / "resources").data
    assert "search_ranges" in soil["simulation"]
    # refine and adaptive: the ranges, without their documentation (editing a note re-runs nothing)
    kept = dem_context(soil, search_ranges=True)["simulation"]["search_ranges"]
    assert kept == {"jkr_surface_energy": {"low": 0, "high": 10}}
    # every other DEM rule, and simulation_setup: without them (editing a range re-runs none of them)
    assert "search_ranges" not in dem_context(soil)["simulation"]
    assert "search_ranges" not in setup_inputs(soil)["simulation"]
    assert dem_context(soil)["simulation"] == {k: v for k, v in dem_context(soil, search_ranges=True)["simulation"].items()
                                               if k != "search_ranges"}
    assert "search_ranges" in soil["simulation"]  # the soil config itself is left as it was
