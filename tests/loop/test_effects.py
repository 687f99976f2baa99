"""The effect library (soilcal.loop.effects): each mechanism's formula checked against a hand
calculation, its switch-off value, its clamps, and the library helpers (get, apply_all, bounds)."""

from __future__ import annotations

import math

import pytest

from soilcal.errors import InputError
from soilcal.loop.effects import EFFECTS, Effect, apply_all, get

E = math.e

# calibrated DEM parameters of one condition (SI); distinct values so a mix-up shows
PARAMS = dict(soil_soil_restitution=0.45, soil_soil_static_friction=0.6, soil_soil_rolling_friction=0.1,
              soil_soil_surface_energy=0.4, soil_steel_restitution=0.45, soil_steel_static_friction=0.5,
              soil_steel_rolling_friction=0.12, soil_steel_surface_energy=0.05, soil_density=2000.0,
              soil_poisson=0.3, soil_shear_modulus=1.0e6, steel_density=7850.0, steel_poisson=0.29,
              steel_shear_modulus=7.9e10)

# a condition away from the reference in every quantity an effect uses
QUANT = {"tool_speed": 2.0, "rotor_speed": 300.0, "moisture_content": 20.0, "working_depth": 0.15,
         "layer_depth": 0.3, "tool": "A"}
REF = {"tool_speed": 1.0, "rotor_speed": 250.0, "moisture_content": 15.0, "working_depth": 0.10,
       "layer_depth": 0.2}


def _unchanged_except(out: dict, changed: dict) -> None:
    """out equals PARAMS except for the keys of ``changed``, which take those values."""
    assert set(out) == set(PARAMS)
    for k, v in PARAMS.items():
        if k in changed:
            assert out[k] == pytest.approx(changed[k], rel=1e-12), k
        else:
            assert out[k] == v, k


# --- switched off -----------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_null_theta_leaves_params_unchanged(name):
    eff = EFFECTS[name]
    assert eff.apply(PARAMS, QUANT, dict(eff.null), REF) == PARAMS
    assert eff.apply(PARAMS, QUANT, {}, REF) == PARAMS  # a missing theta takes its null value


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_apply_does_not_mutate_its_input(name):
    eff = EFFECTS[name]
    params = dict(PARAMS)
    theta = {k: hi for k, (_u, (_lo, hi)) in eff.params.items()}
    eff.apply(params, QUANT, theta, REF)
    assert params == PARAMS


# --- rate_friction: mu(v) = mu_cal (1 + beta ln(v / v0)) --------------------------------------


def test_rate_friction_one_e_fold_of_tool_speed():
    v0 = 0.8
    beta = 0.2
    out = EFFECTS["rate_friction"].apply(PARAMS, {"tool_speed": E * v0}, {"beta": beta}, {"tool_speed": v0})
    # ln(e v0 / v0) = 1: mu * (1 + beta) = 0.6 * 1.2 = 0.72 and 0.5 * 1.2 = 0.6
    _unchanged_except(out, {"soil_soil_static_friction": 0.6 * 1.2, "soil_steel_static_friction": 0.5 * 1.2})


def test_rate_friction_slower_than_reference():
    # v = v0 / e**2: ln = -2, f = 1 + 0.1 * (-2) = 0.8
    out = EFFECTS["rate_friction"].apply(PARAMS, {"tool_speed": 1.5 / E ** 2}, {"beta": 0.1}, {"tool_speed": 1.5})
    _unchanged_except(out, {"soil_soil_static_friction": 0.6 * 0.8, "soil_steel_static_friction": 0.5 * 0.8})


def test_rate_friction_uses_rotor_speed_without_tool_speed():
    # the reference also has a tool speed, but the condition only a rotor speed
    out = EFFECTS["rate_friction"].apply(PARAMS, {"rotor_speed": 250.0 * E}, {"beta": 0.3},
                                         {"tool_speed": 1.0, "rotor_speed": 250.0})
    _unchanged_except(out, {"soil_soil_static_friction": 0.6 * 1.3, "soil_steel_static_friction": 0.5 * 1.3})


def test_rate_friction_without_a_speed_is_unchanged():
    out = EFFECTS["rate_friction"].apply(PARAMS, {"moisture_content": 20.0}, {"beta": 0.3}, REF)
    assert out == PARAMS


def test_rate_friction_clamped_at_zero():
    # beta ln = -0.3 * 5 = -1.5: f = -0.5, friction would be negative -> 0
    out = EFFECTS["rate_friction"].apply(PARAMS, {"tool_speed": 2.0 * E ** 5}, {"beta": -0.3}, {"tool_speed": 2.0})
    _unchanged_except(out, {"soil_soil_static_friction": 0.0, "soil_steel_static_friction": 0.0})


def test_rate_friction_clamped_at_the_upper_friction_limit():
    # f = 1 + 0.6 * 20 = 13: 0.6 * 13 = 7.8 -> 5.0 (the physical limit, base._RANGES); 0.5 * 13 = 6.5 -> 5.0
    out = EFFECTS["rate_friction"].apply(PARAMS, {"tool_speed": E ** 20}, {"beta": 0.6}, {"tool_speed": 1.0})
    _unchanged_except(out, {"soil_soil_static_friction": 5.0, "soil_steel_static_friction": 5.0})


def test_rate_friction_rises_past_a_soil_s_plausible_friction_and_the_run_takes_it():
    """A calibrated friction of 1.9 (within a soil's plausible 0-2, base.SOIL_RANGES) at four
    times the reference speed with beta 0.3: 1.9 (1 + 0.3 ln 4) = 2.6901, not held at 2 (the
    prediction would go flat in beta), and the point spec of the run takes it."""
    from soilcal.dem.scenarios.base import DemParams
    from soilcal.errors import InputError

    p = {**PARAMS, "soil_soil_static_friction": 1.9, "soil_steel_static_friction": 1.9}
    out = EFFECTS["rate_friction"].apply(p, {"tool_speed": 2.0}, {"beta": 0.3}, {"tool_speed": 0.5})
    mu = 1.9 * (1 + 0.3 * math.log(4.0))
    assert out["soil_soil_static_friction"] == pytest.approx(mu, rel=1e-12)
    assert DemParams.from_mapping(out, "<point spec>", plausible=False).soil_soil_static_friction == pytest.approx(mu)
    with pytest.raises(InputError):
        DemParams.from_mapping(out, "<typed>")


@pytest.mark.parametrize("v, v0", [(0.0, 1.0), (-1.0, 1.0), (1.0, 0.0), (1.0, -2.0)])
def test_rate_friction_refuses_non_positive_speed(v, v0):
    with pytest.raises(InputError) as e:
        EFFECTS["rate_friction"].apply(PARAMS, {"tool_speed": v}, {"beta": 0.1}, {"tool_speed": v0})
    assert "rate_friction" in str(e.value) and "positive speed" in str(e.value)


# --- moisture_cohesion: gamma_ss + c_w (w - w0), at least 0 -----------------------------------


def test_moisture_cohesion_linear_in_moisture():
    # 0.4 + 0.02 * (20 - 15) = 0.5
    out = EFFECTS["moisture_cohesion"].apply(PARAMS, {"moisture_content": 20.0}, {"c_w": 0.02},
                                             {"moisture_content": 15.0})
    _unchanged_except(out, {"soil_soil_surface_energy": 0.5})
    # drier than the reference: 0.4 + 0.03 * (11 - 15) = 0.28
    out = EFFECTS["moisture_cohesion"].apply(PARAMS, {"moisture_content": 11.0}, {"c_w": 0.03},
                                             {"moisture_content": 15.0})
    _unchanged_except(out, {"soil_soil_surface_energy": 0.28})


def test_moisture_cohesion_clamped_at_zero():
    # 0.4 - 0.1 * (25 - 15) = -0.6 -> 0
    out = EFFECTS["moisture_cohesion"].apply(PARAMS, {"moisture_content": 25.0}, {"c_w": -0.1},
                                             {"moisture_content": 15.0})
    _unchanged_except(out, {"soil_soil_surface_energy": 0.0})


def test_moisture_cohesion_without_moisture_is_unchanged():
    out = EFFECTS["moisture_cohesion"].apply(PARAMS, {"tool_speed": 2.0, "working_depth": 0.1}, {"c_w": 0.05},
                                             {"moisture_content": 15.0})
    assert out == PARAMS
    assert not EFFECTS["moisture_cohesion"].applies_to({"tool_speed": 2.0})
    assert EFFECTS["moisture_cohesion"].applies_to({"moisture_content": 20.0})


# --- depth_compaction: f = 1 + g (d / d0 - 1) >= 0.1; rho f, G f^2 -------------------------------


def test_depth_compaction_density_and_stiffness():
    # f = 1 + 0.2 * (0.15 / 0.10 - 1) = 1.1: rho = 2000 * 1.1 = 2200, G = 1e6 * 1.21 = 1.21e6
    out = EFFECTS["depth_compaction"].apply(PARAMS, {"working_depth": 0.15}, {"g": 0.2}, {"working_depth": 0.10})
    _unchanged_except(out, {"soil_density": 2200.0, "soil_shear_modulus": 1.21e6})


def test_depth_compaction_floor():
    # f = 1 - 0.3 * (1.1 / 0.1 - 1) = -2 -> 0.1: rho = 200, G = 1e6 * 0.01 = 1e4
    out = EFFECTS["depth_compaction"].apply(PARAMS, {"working_depth": 1.1}, {"g": -0.3}, {"working_depth": 0.1})
    _unchanged_except(out, {"soil_density": 200.0, "soil_shear_modulus": 1.0e4})


def test_depth_compaction_uses_layer_depth_without_working_depth():
    # f = 1 + 1.0 * (0.3 / 0.2 - 1) = 1.5: rho = 3000, G = 2.25e6
    out = EFFECTS["depth_compaction"].apply(PARAMS, {"layer_depth": 0.3}, {"g": 1.0},
                                            {"working_depth": 0.1, "layer_depth": 0.2})
    _unchanged_except(out, {"soil_density": 3000.0, "soil_shear_modulus": 2.25e6})


# --- tool_adhesion: gamma_st + gamma_a ---------------------------------------------------------


def test_tool_adhesion_adds_to_soil_steel_surface_energy_only():
    # 0.05 + 0.7 = 0.75, whatever the condition carries
    for q in ({}, QUANT):
        out = EFFECTS["tool_adhesion"].apply(PARAMS, q, {"gamma_a": 0.7}, REF)
        _unchanged_except(out, {"soil_steel_surface_energy": 0.75})
    assert EFFECTS["tool_adhesion"].applies_to({})


# --- plastic_contact: lambda_p,ss = lambda_p,cal + lambda_p in [0, 0.95], compression only ------


def test_plastic_contact_adds_to_the_calibrated_ratio():
    eff = EFFECTS["plastic_contact"]
    # a parameter set without soil_soil_plasticity is elastic: 0 + 0.3 = 0.3
    out = eff.apply(PARAMS, {}, {"lambda_p": 0.3}, {}, "compression")
    assert out == dict(PARAMS, soil_soil_plasticity=0.3)
    # a calibrated ratio 0.2: 0.2 + 0.35 = 0.55, nothing else changed, whatever the quantities
    cal = dict(PARAMS, soil_soil_plasticity=0.2)
    for q in ({}, QUANT):
        out = eff.apply(cal, q, {"lambda_p": 0.35}, REF, "standin_compression")
        assert set(out) == set(cal)
        assert out["soil_soil_plasticity"] == pytest.approx(0.55, rel=1e-12)
        assert {k: v for k, v in out.items() if k != "soil_soil_plasticity"} == PARAMS


def test_plastic_contact_clamped_to_its_range():
    eff = EFFECTS["plastic_contact"]
    # 0.6 + 0.9 = 1.5 -> 0.95 (the DEM's law needs lambda_p < 1)
    out = eff.apply(dict(PARAMS, soil_soil_plasticity=0.6), {}, {"lambda_p": 0.9}, {}, "compression")
    assert out["soil_soil_plasticity"] == 0.95
    # 0.2 - 0.5 = -0.3 -> 0 (a value below the default bounds, given directly)
    out = eff.apply(dict(PARAMS, soil_soil_plasticity=0.2), {}, {"lambda_p": -0.5}, {}, "compression")
    assert out["soil_soil_plasticity"] == 0.0


def test_plastic_contact_switched_off_adds_no_parameter():
    # lambda_p = 0 on a set without soil_soil_plasticity: the set as it was (same DEM run)
    eff = EFFECTS["plastic_contact"]
    assert eff.apply(PARAMS, {}, {"lambda_p": 0.0}, {}, "compression") == PARAMS


@pytest.mark.parametrize("scenario", ["bulldozing", "repose", "standin", None])
def test_plastic_contact_does_not_act_on_other_scenarios(scenario):
    eff = EFFECTS["plastic_contact"]
    assert eff.scenarios == ("compression", "standin_compression")
    assert eff.apply(PARAMS, QUANT, {"lambda_p": 0.5}, REF, scenario) == PARAMS
    assert not eff.applies_to(QUANT, scenario)
    assert not eff.applies_to({}, scenario)


def test_plastic_contact_acts_on_every_compression_condition():
    eff = EFFECTS["plastic_contact"]
    for scenario in ("compression", "standin_compression"):
        assert eff.applies_to({}, scenario)
        assert eff.applies_to(QUANT, scenario)


def test_unrestricted_effects_act_in_every_scenario():
    for scenario in ("compression", "bulldozing", None):
        assert EFFECTS["moisture_cohesion"].applies_to({"moisture_content": 20.0}, scenario)
        assert not EFFECTS["moisture_cohesion"].applies_to({"tool_speed": 2.0}, scenario)
        assert EFFECTS["tool_adhesion"].applies_to({}, scenario)
    # 0.05 + 0.7 = 0.75 on a compression condition too
    out = EFFECTS["tool_adhesion"].apply(PARAMS, {}, {"gamma_a": 0.7}, REF, "compression")
    _unchanged_except(out, {"soil_steel_surface_energy": 0.75})


def test_apply_all_passes_the_scenario():
    effects = {"tool_adhesion": {"gamma_a": 0.7}, "plastic_contact": {"lambda_p": 0.4}}
    # a blade: adhesion only (0.05 + 0.7); a compression test: both (0 + 0.4)
    assert apply_all(effects, PARAMS, {}, {}, "bulldozing") == dict(PARAMS, soil_steel_surface_energy=0.75)
    out = apply_all(effects, PARAMS, {}, {}, "compression")
    assert out == dict(PARAMS, soil_steel_surface_energy=0.75, soil_soil_plasticity=0.4)


# --- library helpers ---------------------------------------------------------------------------


def test_apply_all_equals_one_after_another():
    effects = {"rate_friction": {"beta": 0.2}, "moisture_cohesion": {"c_w": 0.02}}
    q = {"tool_speed": E, "moisture_content": 20.0}
    ref = {"tool_speed": 1.0, "moisture_content": 15.0}
    both = apply_all(effects, PARAMS, q, ref)
    step = EFFECTS["rate_friction"].apply(PARAMS, q, {"beta": 0.2}, ref)
    step = EFFECTS["moisture_cohesion"].apply(step, q, {"c_w": 0.02}, ref)
    assert both == step
    # and by hand: friction * 1.2, cohesion 0.4 + 0.02 * 5 = 0.5
    _unchanged_except(both, {"soil_soil_static_friction": 0.72, "soil_steel_static_friction": 0.6,
                             "soil_soil_surface_energy": 0.5})
    assert apply_all({}, PARAMS, q, ref) == PARAMS


def test_get_known_and_unknown():
    assert get("rate_friction") is EFFECTS["rate_friction"]
    with pytest.raises(InputError) as e:
        get("nope")
    msg = str(e.value)
    assert "'nope'" in msg
    for name in EFFECTS:
        assert name in msg


def test_bounds_override_replaces_only_that_parameter():
    eff = Effect(name="two", title="two-parameter effect", params={"a": ("-", (0, 1)), "b": ("m", (-2, 2))},
                 null={"a": 0.0, "b": 0.0}, signature=("bias",), needs=(), formula="", source="")
    assert eff.bounds() == {"a": (0.0, 1.0), "b": (-2.0, 2.0)}
    assert eff.bounds({"b": (-1, 0.5)}) == {"a": (0.0, 1.0), "b": (-1.0, 0.5)}
    assert eff.bounds() == {"a": (0.0, 1.0), "b": (-2.0, 2.0)}  # the defaults are not changed
    assert EFFECTS["rate_friction"].bounds({"beta": (0, 0.2)}) == {"beta": (0.0, 0.2)}
    assert EFFECTS["rate_friction"].bounds() == {"beta": (-0.3, 0.6)}
