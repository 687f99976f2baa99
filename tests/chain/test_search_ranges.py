"""A soil's declared search ranges (``simulation.search_ranges``): the one lookup of the range a
factor may be searched over (soilcal.chain.adaptive.search_range: the screening's where a
simulated screening gives one, else the declared, else none), its use by the second calibration
round (soilcal.chain.stage.screening_ranges, soilcal.chain.refine) and by the adaptive design,
and its checks as the soil loads (soilcal.config.load.check_search_ranges).

The second-round tests use the stand-in of test_refine: responses exactly y = 30 + 2 A (A coded,
actual 0.5 + 0.5 A), so the corrected surface is 30 + b + 2 A and the set meeting a target T is
A = (T - 30 - b) / 2."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
import yaml

from soilcal.chain.adaptive import screening_factor, search_range, stage_for
from soilcal.chain.refine import refine_frame
from soilcal.chain.stage import screening_ranges
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


def test_the_lookup_takes_the_screening_else_the_declared_range_else_none():
    soil = _soil()
    got = search_range(soil, "bbd", "gamma")
    assert (got.low, got.high, got.kind, got.field) == (0.0, 5.0, "screening", "stages.pb.factors.X1")
    # the screening does not count (a stage not derived from a simulated path): the declared range
    got = search_range(soil, "bbd", "gamma", screening=False)
    assert (got.low, got.high, got.kind, got.field) == (0.0, 10.0, "declared", "simulation.search_ranges.gamma")
    got = search_range(soil, "bbd", "e")  # not screened: declared
    assert (got.low, got.high, got.field) == (0.1, 0.9, "simulation.search_ranges.e")
    assert search_range(soil, "bbd", "mu", screening=False) is None  # neither
    assert search_range(soil, "bbd", "mu").field == "stages.pb.factors.X2"


def test_the_second_round_takes_a_path_stages_screening_and_a_printed_stages_declared_range():
    soil = _soil()
    derived = {**soil["stages"][2], "derivation": {"kind": "path"}}
    assert {s: r[:2] for s, r in screening_ranges(soil, derived).items()} == \
        {"A": (0.0, 5.0), "B": (0.2, 1.0), "C": (0.1, 0.9)}
    printed = {**soil["stages"][2], "derivation": {"kind": "config"}}
    ranges = screening_ranges(soil, printed)
    assert {s: r[:2] for s, r in ranges.items()} == {"A": (0.0, 10.0), "C": (0.1, 0.9)}
    assert ranges["A"][2] == "declared search range 0..10 (simulation.search_ranges.gamma)"
    assert screening_ranges(_soil("printed"), derived)["A"][:2] == (0.0, 10.0)
    assert screening_ranges(_soil("adaptive"), derived) == {}


def test_the_adaptive_design_takes_the_same_lookup_and_records_where_each_range_comes_from():
    soil = _soil("adaptive")
    assert screening_factor(soil, "bbd", "e").field == "simulation.search_ranges.e"
    st = stage_for(soil, "bbd")
    assert {s: (f["low"], f["high"]) for s, f in st["factors"].items()} == \
        {"A": (0.0, 5.0), "B": (0.2, 1.0), "C": (0.1, 0.9)}
    assert st["derivation"]["ranges"]["C"] == {"low": 0.1, "high": 0.9, "from": "simulation.search_ranges.e"}
    assert st["derivation"]["ranges"]["A"]["from"] == "stages.pb.factors.X1"
    assert "declared ranges (simulation.search_ranges): C 0.1-0.9" in st["derivation"]["text"]
    # ranges: stage keeps the stage's own, declared or not
    soil["simulation"]["adaptive"] = {"ranges": "stage"}
    assert screening_factor(soil, "bbd", "e") is None
    assert stage_for(soil, "bbd")["factors"]["C"]["low"] == 0.3


# ------------------------------------------------------------------ the second round


def _energy_stage():
    """The stand-in stage with A a JKR surface energy (box 0..1 J/m^2)."""
    st = _stage()
    st["factors"]["A"]["parameter"] = "jkr_surface_energy"
    st["derivation"] = {"kind": "config"}  # run on its printed levels
    return st


def _declared(low, high):
    return {"simulation": {"search_ranges": {"jkr_surface_energy": {"low": low, "high": high}}}}


def _refined(soil):
    # x0 A coded 0.5 (actual 0.75, surface 31), four seeds averaging 28.5: bias -2.5, so the
    # corrected surface 27.5 + 2 A meets the target 31 at A = 1.75 (actual 1.375), 0.75
    # half-widths past the high bound 1
    stage = _energy_stage()
    opt = OPTIMUM[OPTIMUM["case"] == "biased"]
    runs = {"biased": _runs([28.4, 28.6, 28.5, 28.5])}
    df = refine_frame(stage, _table(), {"y": {"value": 31.0}, "lost": {"value": None}}, opt, runs,
                      screening_ranges(soil, stage))
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


def test_without_a_declared_range_the_set_stays_in_the_box():
    # the compromise on the box's bound: A = 1, y = 29.5
    r = _refined({})
    assert r["region"] == "inside" and r["A_coded"] == pytest.approx(1.0, abs=1e-4)
    assert r["search_ranges"].startswith("none: every factor stays in the design box")


# ------------------------------------------------------------------ checks as the soil loads


def _load(tmp_path, ranges):
    data = yaml.safe_load((ROOT / "config/soils/guangxi-cohesive.yaml").read_text(encoding="utf-8"))
    data["simulation"]["search_ranges"] = ranges
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


@pytest.mark.parametrize("ranges, field, expected", [
    ({"soil_soil_restitution": {"low": 0.3, "high": 0.5, "source": "x"}},
     "simulation.search_ranges.soil_soil_restitution.low", "at most 0.27, the low level of stages.bbd.factors.A"),
    ({"jkr_surface_energy": {"low": 0, "high": 5, "source": "x"}},
     "simulation.search_ranges.jkr_surface_energy.high", "at least 10, the high level of stages.pb.factors.G"),
    ({"soil_soil_restitution": {"low": 0, "high": 0.5, "source": "x"}},
     "simulation.search_ranges.soil_soil_restitution.low", "a coefficient of restitution in (0, 1]"),
    ({"soil_soil_restitution": {"low": 0.1, "high": 1.2, "source": "x"}},
     "simulation.search_ranges.soil_soil_restitution.high", "a coefficient of restitution in (0, 1]"),
    ({"soil_soil_static_friction": {"low": -0.1, "high": 1, "source": "x"}},
     "simulation.search_ranges.soil_soil_static_friction.low", "a friction coefficient >= 0"),
    ({"jkr_surface_energy": {"low": -1, "high": 10, "source": "x"}},
     "simulation.search_ranges.jkr_surface_energy.low", "a surface energy >= 0"),
    ({"soil_soil_static_friction": {"low": 1, "high": 0.3, "source": "x"}},
     "simulation.search_ranges.soil_soil_static_friction.low", "a finite number below high (0.3)"),
    ({"shear_energy": {"low": 0, "high": 1, "source": "x"}},
     "simulation.search_ranges.shear_energy", "a parameter id listed under parameters"),
])
def test_a_bad_declared_range_is_refused_naming_file_field_and_what_was_expected(tmp_path, ranges, field, expected):
    with pytest.raises(InputError) as exc:
        _load(tmp_path, ranges)
    assert exc.value.field == field and expected in exc.value.expected
    assert exc.value.path == str(tmp_path / "guangxi-cohesive.yaml")


def test_a_declared_range_needs_its_source(tmp_path):
    with pytest.raises(InputError) as exc:
        _load(tmp_path, {"jkr_surface_energy": {"low": 0, "high": 10}})
    assert "search_ranges" in exc.value.field


def test_a_wider_declared_range_loads(tmp_path):
    soil = _load(tmp_path, {"jkr_surface_energy": {"low": 0, "high": 25, "source": "GEMM range, Sec. 3.1"},
                            "soil_soil_static_friction": {"low": 0.2, "high": 1.0, "source": "a choice"}})
    assert screening_ranges(soil.data, {**soil.stage("bbd"), "derivation": {"kind": "config"}})["B"][:2] == (0.2, 1.0)
