"""The soil's optional `loop` block and the `soilcal loop` command line: every bad value stops
with one line naming the field."""

from __future__ import annotations

import pytest

from soilcal.cli import main
from soilcal.errors import InputError
from soilcal.loop import core
from soilcal.loop.effects import EFFECTS


def test_defaults_are_every_effect_matched_at_five_levels():
    s = core.settings_from({})
    assert s.effects == list(EFFECTS) and s.candidates == "matched" and s.design_points == 5
    assert s.alpha == 0.05 and s.max_effects == 2 and s.fold_by is None and s.bootstrap == 200
    assert s.surrogate == "pooled"


def test_a_full_block_is_read():
    s = core.settings_from({"loop": {"alpha": 0.01, "effects": ["rate_friction"], "candidates": "all",
                                     "bounds": {"rate_friction": {"beta": [0, 0.5]}}, "reference": {"tool_speed": 2},
                                     "design_points": 4, "fold_by": "day", "max_effects": 1,
                                     "bootstrap": 0, "surrogate": "rows"}})
    assert s.alpha == 0.01 and s.effects == ["rate_friction"] and s.candidates == "all"
    assert s.effect_bounds("rate_friction") == {"beta": (0.0, 0.5)}
    assert s.reference == {"tool_speed": 2.0} and s.design_points == 4 and s.max_effects == 1 and s.bootstrap == 0
    assert s.surrogate == "rows"


@pytest.mark.parametrize("block, field", [
    ({"alpha": 1.5}, "loop.alpha"),
    ({"effects": ["stones"]}, "loop.effects[0]"),
    ({"candidates": "some"}, "loop.candidates"),
    ({"bounds": {"nope": {}}}, "loop.bounds.nope"),
    ({"bounds": {"rate_friction": {"gamma": [0, 1]}}}, "loop.bounds.rate_friction.gamma"),
    ({"bounds": {"rate_friction": {"beta": [1, 0]}}}, "loop.bounds.rate_friction.beta"),
    ({"bounds": {"rate_friction": [0, 0.2]}}, "loop.bounds.rate_friction"),
    ({"bounds": {"rate_friction": 0.2}}, "loop.bounds.rate_friction"),
    ({"bounds": {"rate_friction": None}}, "loop.bounds.rate_friction"),
    ({"bounds": [0, 0.2]}, "loop.bounds"),
    ({"bounds": {"rate_friction": {"beta": [0, float("inf")]}}}, "loop.bounds.rate_friction.beta"),
    ({"bounds": {"moisture_cohesion": {"c_w": [float("-inf"), 0.1]}}}, "loop.bounds.moisture_cohesion.c_w"),
    ({"bounds": {"rate_friction": {"beta": [False, True]}}}, "loop.bounds.rate_friction.beta"),
    ({"bounds": {"plastic_contact": {"lambda_p": [0.0, 0.99]}}}, "loop.bounds.plastic_contact.lambda_p"),
    ({"bounds": {"plastic_contact": {"lambda_p": [-0.1, 0.5]}}}, "loop.bounds.plastic_contact.lambda_p"),
    ({"effects": ["rate_friction", "tool_adhesion", "rate_friction"]}, "loop.effects[2]"),
    ({"reference": {"tool": 1.0}}, "loop.reference.tool"),
    ({"reference": {"tool_speed": "fast"}}, "loop.reference.tool_speed"),
    ({"design_points": 2}, "loop.design_points"),
    ({"max_effects": 0}, "loop.max_effects"),
    ({"bootstrap": 10}, "loop.bootstrap"),
    ({"bootstrap": True}, "loop.bootstrap"),
    ({"surrogate": "gp"}, "loop.surrogate"),
    ({"unknown": 1}, "loop.unknown"),
])
def test_bad_settings_name_the_field(block, field):
    with pytest.raises(InputError) as exc:
        core.settings_from({"loop": block}, "soil.yaml")
    assert exc.value.field == field
    assert "soil.yaml" in str(exc.value)


def test_bounds_given_as_a_list_say_the_form_a_bound_takes():
    with pytest.raises(InputError) as exc:
        core.settings_from({"loop": {"bounds": {"rate_friction": [0, 0.2]}}}, "soil.yaml")
    assert exc.value.expected.startswith("a mapping parameter -> [low, high]")
    assert "beta: [-0.3, 0.6]" in exc.value.expected  # the effect's parameter and library bounds


def test_bounds_must_lie_in_the_range_the_library_states_and_else_be_finite():
    # plastic_contact clamps its ratio to [0, 0.95]: its whole range is a valid bound
    s = core.settings_from({"loop": {"bounds": {"plastic_contact": {"lambda_p": [0.0, 0.95]}}}})
    assert s.effect_bounds("plastic_contact") == {"lambda_p": (0.0, 0.95)}
    with pytest.raises(InputError, match=r"within \[0, 0\.95\]"):
        core.settings_from({"loop": {"bounds": {"plastic_contact": {"lambda_p": [0.0, 0.96]}}}})
    # an effect that states no range takes any finite interval
    s = core.settings_from({"loop": {"bounds": {"rate_friction": {"beta": [-5.0, 40.0]}}}})
    assert s.effect_bounds("rate_friction") == {"beta": (-5.0, 40.0)}
    assert all(set(e.ranges) <= set(e.params) for e in EFFECTS.values())


def test_design_holds_the_switched_off_value_and_the_bounds():
    s = core.Settings()
    from soilcal.loop.select import theta_design

    d = theta_design(EFFECTS["rate_friction"], s.effect_bounds("rate_friction"), 3)
    assert [t["beta"] for t in d] == [-0.3, 0.0, 0.15, 0.6]


@pytest.mark.parametrize("argv, text", [
    (["loop", "synthesize", "config/soils/cinnamon-soil.yaml", "--measurement", "cutting_resistance",
      "--effect", "rate_friction:beta", "--out", "x.csv"], "--effect"),
    (["loop", "synthesize", "config/soils/cinnamon-soil.yaml", "--measurement", "nope", "--out", "x.csv"],
     "measurements"),
    (["loop", "synthesize", "config/soils/cinnamon-soil.yaml", "--measurement", "cutting_resistance",
      "--effect", "gravity:g=1", "--out", "x.csv"], "one of moisture_cohesion"),
])
def test_the_command_line_refuses_bad_arguments_with_exit_2(argv, text, capsys, monkeypatch, tmp_path):
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    monkeypatch.chdir(root)
    argv = [a if a != "x.csv" else str(tmp_path / "x.csv") for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("soilcal: error:") and text in err
    assert not (tmp_path / "x.csv").exists()
