"""Tool passes the run could not finish are refused before the bin is settled: a tool
pushing the soil faster than its stiffness carries (the bed's overlaps would pass the
run's max_overlap whatever the time step), and a pass of more steps than MAX_PASS_STEPS."""

import math

import numpy as np
import pytest

from soilcal.dem.scenarios import bulldozing, furrow, rotary, soilbin
from soilcal.dem.scenarios.base import DemParams, merge_setup
from soilcal.errors import InputError


def _chain_peak(n, k_wall, dt=4e-3):
    """Largest pair overlap of n touching undamped Hertz spheres (m = 1, F = delta^1.5)
    pushed by a wall at speed 1 (wall law k_wall delta^1.5), velocity Verlet."""
    x = np.zeros(n)
    v = np.zeros(n)
    f = np.zeros(n)
    xw = 0.0
    peak = 0.0
    for _ in range(int(2 * n / dt)):
        v += 0.5 * dt * f
        x += dt * v
        xw += dt
        d = np.maximum(x[:-1] - x[1:], 0.0)
        peak = max(peak, d.max())
        fp = d ** 1.5
        f = np.zeros(n)
        f[0] = k_wall * max(xw - x[0], 0.0) ** 1.5
        f[:-1] -= fp
        f[1:] += fp
        v += 0.5 * dt * f
    return peak


def test_chain_constant_is_the_peak_of_a_pushed_hertz_chain():
    """CHAIN_PEAK (units (m v^2/k)^(2/5)) bounds the chain of 60 spheres from above by at
    most 3 % (it still grows slowly with the chain's length), whatever the wall's stiffness."""
    for k_wall in (1.0, 2.0 * math.sqrt(2.0)):
        p = _chain_peak(60, k_wall)
        assert p <= soilbin.CHAIN_PEAK <= 1.03 * p, (k_wall, p)


def _params():
    return DemParams()


def _analytic_limit(p: DemParams, max_overlap: float) -> float:
    # delta/r = C (m v^2 / k)^(2/5) / r, m = 4/3 pi r^3 rho, k = 4/3 E* sqrt(r / 2)
    e = 2.0 * p.soil_shear_modulus * (1.0 + p.soil_poisson)
    estar = e / (2.0 * (1.0 - p.soil_poisson ** 2))
    r = 0.007
    m = 4.0 / 3.0 * math.pi * r ** 3 * p.soil_density
    k = 4.0 / 3.0 * estar * math.sqrt(r / 2.0)
    # C (m v^2 / k)^0.4 = max_overlap r
    return math.sqrt((max_overlap * r / soilbin.CHAIN_PEAK) ** 2.5 * k / m)


def test_bulldozing_at_30_kmh_is_refused_naming_speed_and_limit(monkeypatch):
    p = _params()
    setup = merge_setup(bulldozing.setups(), "plate-line", {"speed": 30 / 3.6}, "<t>")
    # refused before any settling
    monkeypatch.setattr(bulldozing, "settled_bin", lambda *a, **k: pytest.fail("settled"))
    with pytest.raises(InputError, match="setup.speed") as e:
        bulldozing.run(setup, p, "quick", use_cache=False)
    vmax = _analytic_limit(p, 0.5)
    assert 6.0 < vmax < 6.4  # the quick bed ran at 6 m/s and failed at 8.33 m/s
    assert f"<= {vmax:.3g} m/s" in str(e.value)
    # just below the limit it is accepted
    ok = merge_setup(bulldozing.setups(), "plate-line", {"speed": 0.99 * vmax}, "<t>")
    bulldozing.validate(ok, "quick", "<t>", params=p)


def test_tool_speed_in_the_wrong_unit_is_refused_with_its_step_count(monkeypatch):
    p = _params()
    setup = merge_setup(bulldozing.setups(), "plate-line", {"speed": 0.001 / 3.6}, "<t>")
    monkeypatch.setattr(bulldozing, "settled_bin", lambda *a, **k: pytest.fail("settled"))
    s = bulldozing._settings(setup, "quick")
    s["cohesion_scale"] = soilbin.reference_cohesion(
        bulldozing._bin(s), bulldozing._bin(bulldozing._settings(bulldozing._setup("line"),
                                                                 "paper")), setup, "<t>")
    dt = soilbin.tool_time_step(bulldozing._bin(s), p)
    steps = math.ceil(0.2 / (0.001 / 3.6) / dt)
    with pytest.raises(InputError, match="setup.speed") as e:
        bulldozing.run(setup, p, "quick", use_cache=False)
    assert f"{steps:,} steps" in str(e.value)
    r = merge_setup(rotary.setups(), "rpm-150", {"forward_speed": 0.001 / 3.6}, "<t>")
    with pytest.raises(InputError, match="setup.forward_speed"):
        rotary.validate(r, "quick", "<t>", params=p)
    f = merge_setup(furrow.setups(), "yangtze-opener", {"speed": 0.001 / 3.6}, "<t>")
    with pytest.raises(InputError, match="setup.speed"):
        furrow.validate(f, "quick", "<t>", params=p)


def test_a_pass_whose_travel_follows_from_its_duration_names_the_duration():
    # at the paper preset the plate travels its speed times setup.duration: the step count is
    # the duration over the time step whatever the speed, so a pass too long is the duration's
    p = _params()
    setup = merge_setup(bulldozing.setups(), "plate-line", {"speed": 0.02, "duration": 30.0, "bin_length": 2.0},
                        "<t>")
    s = bulldozing._settings(setup, "paper")
    s["cohesion_scale"] = soilbin.reference_cohesion(
        bulldozing._bin(s), bulldozing._bin(bulldozing._settings(bulldozing._setup("line"), "paper")), setup, "<t>")
    dt = soilbin.tool_time_step(bulldozing._bin(s), p)
    assert 30.0 / dt > soilbin.MAX_PASS_STEPS  # the case is one the rule refuses
    with pytest.raises(InputError, match="setup.duration") as e:
        bulldozing.validate(setup, "paper", "<t>", params=p)
    assert f"a duration <= {soilbin.MAX_PASS_STEPS * dt:.4g} s" in str(e.value)
