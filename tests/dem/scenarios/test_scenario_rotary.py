"""Rotary tillage scenario: Eqs. (3)-(4) flatness, shaft power sign, validation, a run."""

import math

import numpy as np
import pytest

from soilcal.dem.engine import Simulation
from soilcal.dem.scenarios import rotary
from soilcal.dem.scenarios.base import DemParams, build_materials, stable_mean
from soilcal.errors import InputError


def test_flatness_is_sample_sd():
    d_mean, sd = rotary.flatness([1.0, 2.0, 3.0, 4.0, 5.0])
    assert d_mean == 3.0 and sd == pytest.approx(math.sqrt(2.5))
    rng = np.random.default_rng(3)
    d = rng.normal(100.0, 7.0, 200000)
    assert rotary.flatness(d)[1] == pytest.approx(7.0, rel=0.01)


def test_surface_heights_of_a_flat_layer():
    r = 0.01
    gx, gy = np.meshgrid(np.arange(0, 0.6, 2 * r), np.arange(0, 0.2, 2 * r), indexing="ij")
    x = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, 0.05)])
    h = rotary.surface_heights(x, np.full(len(x), r), np.array([0.2, 0.3, 0.4]),
                               np.full(3, 0.1), 0.0)
    # sample points on sphere centres (lateral half-width 0): heights are the sphere tops
    assert h == pytest.approx(0.06)
    _, sd = rotary.flatness(h)
    assert sd == pytest.approx(0.0, abs=1e-12)


def _stepped_layers(heights, r=0.01, block=0.1, width=0.2):
    """Flat layers of spheres (centres at the given heights), one per x-block of length
    ``block``; returns positions, radii and the block centres."""
    xs = []
    for k, h in enumerate(heights):
        gx, gy = np.meshgrid(np.arange(k * block + r, (k + 1) * block, 2 * r),
                             np.arange(r, width, 2 * r), indexing="ij")
        xs.append(np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, h)]))
    x = np.vstack(xs)
    centres = (np.arange(len(heights)) + 0.5) * block
    return x, np.full(len(x), r), centres


def test_flatness_of_a_stepped_surface_through_the_measurement():
    # five blocks whose surface (sphere tops) lies at known heights: Sd of Eqs. (3)-(4) is
    # the sample SD of those heights, 10 mm steps -> sqrt(250) mm
    r = 0.01
    tops_mm = np.array([40.0, 50.0, 60.0, 70.0, 80.0])
    x, rad, c = _stepped_layers(tops_mm / 1e3 - r, r)
    # points on sphere centres in x and y (lateral samples 2 r apart hit centres too)
    px = np.round(c / (2 * r) - 0.5) * 2 * r + r
    h = rotary.surface_heights(x, rad, px, np.full(len(px), 0.1 + r), 8 * r)
    d_mean, sd = rotary.flatness(1e3 * h)
    assert d_mean == pytest.approx(60.0, abs=1e-9)
    assert sd == pytest.approx(math.sqrt(250.0), abs=1e-9)


def test_empty_flatness_points_are_left_out():
    r = 0.01
    tops_mm = np.array([40.0, 50.0, 60.0])
    x, rad, c = _stepped_layers(tops_mm / 1e3 - r, r)
    px = np.append(np.round(c / (2 * r) - 0.5) * 2 * r + r, 0.9)  # 0.9 m: no particle
    h = rotary.surface_heights(x, rad, px, np.full(len(px), 0.1 + r), 0.0)
    assert np.isnan(h[-1]) and np.all(np.isfinite(h[:-1]))
    # the empty point is not the floor (0 m): Sd is that of the three covered points
    assert rotary.flatness(1e3 * h) == pytest.approx((50.0, 10.0), abs=1e-9)
    m, sd, empty = rotary.flatness_or_nan(1e3 * h)
    assert (m, sd, empty) == pytest.approx((50.0, 10.0, 1), abs=1e-9)
    # every point empty: the flatness fails clearly, or is NaN with the count flagged
    h0 = rotary.surface_heights(x, rad, np.array([0.8, 0.9]), np.full(2, 0.1), 0.0)
    with pytest.raises(ValueError, match="at least two points"):
        rotary.flatness(h0)
    m, sd, empty = rotary.flatness_or_nan(h0)
    assert math.isnan(m) and math.isnan(sd) and empty == 2


def test_flatness_points_avoid_the_starting_trench():
    R, th = 0.225, 0.25
    # long pass: behind the final rotor position, outside the trench
    assert rotary.flatness_region(0.1, 1.0, R, th) == pytest.approx((0.1 + th, 0.1 + 1.0 - R))
    # short pass: from the trench's front edge to the front of the final footprint
    assert rotary.flatness_region(0.1, 0.15, R, th) == pytest.approx((0.1 + th, 0.1 + 0.15 + R))
    s = rotary._settings(rotary.setups()["rpm-250"], "quick")
    spec = rotary._bin(s)
    x0, R = s["radius"] + 0.05, s["radius"]
    xa, xb = rotary.flatness_region(x0, s["travel"], R, rotary._trench_half(s, spec))
    # no point inside the dug circle's footprint |x - x0| <= R + 2 r_max
    assert xa - x0 >= R + 2 * spec.r_max - 1e-12 and xb > xa


def test_pass_too_short_for_the_rotor_fails_on_travel():
    s = dict(rotary.setups()["rpm-250"], travel=0.05, overrides=["travel"])
    with pytest.raises(InputError, match="setup.travel"):
        rotary.validate(s, "quick", "test")


def test_stable_mean_of_a_ramp_then_plateau():
    t = np.linspace(0, 2, 2001)
    y = np.where(t < 1, 100 * t, 100 + np.sin(40 * np.pi * t))
    m, sd = stable_mean(t, y, 1.0)
    assert m == pytest.approx(100.0, abs=0.01)
    # 1001 samples, 50 per period: sum of sin^2 = 500 over n - 1 = 1000 (sample SD)
    assert sd == pytest.approx(math.sqrt(500 / 1000), rel=1e-9)


def test_power_of_a_rotating_disk_against_known_friction_torque():
    """A particle held against a stop slides on a disk turning at omega: the disk feels the
    torque -mu m g rho about its axis, so the shaft power is mu m g rho omega."""
    # the stop is of "soil" with zero soil-soil friction, so it carries no weight
    p = DemParams(soil_steel_static_friction=0.4, soil_steel_rolling_friction=0.0,
                  soil_soil_static_friction=0.0, soil_soil_rolling_friction=0.0,
                  soil_soil_surface_energy=0.0, soil_steel_surface_energy=0.0,
                  soil_density=2000.0, soil_shear_modulus=5e6)
    mats = build_materials(p)
    sim = Simulation(mats, dt=2e-5, contact_model=dict(rolling="constant_torque"),
                     max_overlap=0.2)
    r, rho, omega = 0.01, 0.05, 3.0
    sim.add_particles([[rho, 0.0, r * 0.999]], [r], "soil", lock_rotation=True)
    disk = sim.add_disk((0, 0, 0), (0, 0, 1), 0.1, "steel", omega=(0, 0, omega))
    sim.add_plane((0, r, 0), (0, -1, 0), "soil")  # stop ahead of the disk's motion (+y)
    sim.run(6000, wall_log_every=100)
    tz = sim.wall_log[-20:, disk, 5]
    m = 2000.0 * 4 / 3 * math.pi * r**3
    expect = 0.4 * m * 9.81 * rho * omega
    power = rotary.shaft_power(tz, omega)
    assert power.mean() == pytest.approx(expect, rel=0.03)
    assert np.all(tz < 0)  # the soil's torque opposes the rotation


@pytest.mark.parametrize("field,value,match", [
    ("rpm", 0.0, "setup.rpm"),
    ("rpm", -250.0, "setup.rpm"),
    ("forward_speed", 0.0, "setup.forward_speed"),
    ("depth", 0.2, "setup.depth"),     # holders would enter the soil / deeper than the bin
    ("hood_clearance", 0.0, "setup.hood_clearance"),
    ("hood_clearance", -0.05, "setup.hood_clearance"),
])
def test_impossible_settings(field, value, match):
    s = dict(rotary.setups()["rpm-250"])
    s[field] = value
    with pytest.raises(InputError, match=match):
        rotary.validate(s, "quick", "test")
    with pytest.raises(InputError, match=match):
        rotary.run(s, rotary.paper_params(), "quick", use_cache=False)


@pytest.mark.slow
def test_quick_run_positive_power(tmp_path, monkeypatch):
    """The quick preset on a 0.15 m pass (the preset's is 0.3 m; both are shorter than the
    rotor diameter plus 0.1 m, so the flatness points lie between the trench and the rotor's
    final footprint either way): over seeds 0-2 the 0.15 m pass gave 2.0-3.0 kW and no empty
    flatness point."""
    monkeypatch.setenv("SOILCAL_SCENARIO_CACHE", str(tmp_path))
    setup = dict(rotary.setups()["rpm-250"], travel=0.15, overrides=["travel"])
    res = rotary.run(setup, rotary.paper_params(), "quick", seed=0, threads=1)
    r = res.responses
    assert res.setup["travel"] == 0.15
    assert all(math.isfinite(r[k]) for k in ("power_kW", "flatness_mm", "draft_N"))
    assert r["power_kW"] > 0   # the shaft drives the blades against the soil
    assert r["flatness_empty_points"] == 0  # every flatness point lies on soil
    assert len(res.series["flatness_points_mm"]) == 5
