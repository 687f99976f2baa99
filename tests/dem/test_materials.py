"""Pair tables, Rayleigh time step, JKR step bound, stiffness scaling and coarse graining."""

import math

import numpy as np
import pytest

from soilcal.dem.engine import Simulation
from soilcal.dem.materials import (P_BETA, P_ESTAR, P_GSTAR, P_W, Material, MaterialTable,
                                   rayleigh_time)
from soilcal.errors import InputError


def two_materials(shear_mod=None):
    mats = MaterialTable(shear_mod=shear_mod)
    mats.add(Material("soil", 2600, 0.3, youngs=2.6e7))
    mats.add(Material("steel", 7800, 0.3, shear=7.9e10))
    mats.set_pair("soil", "soil", 0.5, 0.5, 0.1, 0.3)
    mats.set_pair("soil", "steel", 0.6, 0.4, 0.05, 0.2)
    mats.set_pair("steel", "steel", 0.9, 0.2, 0.01, 0.0)
    return mats


def test_pair_table_effective_moduli():
    t = two_materials().table(1.0)
    e_soil, nu = 2.6e7, 0.3
    g_soil = e_soil / (2 * (1 + nu))
    e_steel = 2 * 7.9e10 * (1 + nu)
    estar = 1 / ((1 - nu**2) / e_soil + (1 - nu**2) / e_steel)
    gstar = 1 / ((2 - nu) / g_soil + (2 - nu) / 7.9e10)
    assert t[0, 1, P_ESTAR] == pytest.approx(estar, rel=1e-12)
    assert t[1, 0, P_GSTAR] == pytest.approx(gstar, rel=1e-12)
    le = math.log(0.6)
    assert t[0, 1, P_BETA] == pytest.approx(le / math.sqrt(le**2 + math.pi**2), rel=1e-12)
    assert t[0, 0, P_W] == 0.3 and two_materials().table(2.0)[0, 0, P_W] == 0.6


def test_stiffness_scaling_of_surface_energy():
    gmod = 1e6
    t = two_materials(shear_mod=gmod).table(1.0)
    g_soil = 2.6e7 / 2.6
    # same material pair: G*_mod / G* = G_mod / G
    assert t[0, 0, P_W] == pytest.approx(0.3 * (gmod / g_soil) ** 0.4, rel=1e-12)
    assert t[0, 0, P_GSTAR] == pytest.approx(gmod / (2 * (2 - 0.3)), rel=1e-12)


def test_rayleigh_time_and_default_step():
    # T_R = pi R sqrt(rho/G) / (0.1631 nu + 0.8766)
    g = 2.6e7 / 2.6
    tr = math.pi * 1.8e-3 * math.sqrt(2600 / g) / (0.1631 * 0.3 + 0.8766)
    assert rayleigh_time(1.8e-3, 2600, g, 0.3) == pytest.approx(tr, rel=1e-14)
    sim = Simulation(two_materials(), dt_fraction=0.3)
    sim.add_particles([[0, 0, 0.01], [0.01, 0, 0.01]], [1.8e-3, 2.2e-3], "soil")
    sim.run(1)
    assert sim.dt == pytest.approx(0.3 * tr, rel=1e-12)


def test_coarse_graining_scales_radii():
    sim = Simulation(two_materials(), coarse_grain=2.5)
    sim.add_particles([[0, 0, 0.05]], 2e-3, "soil")
    assert sim.p.r[0] == pytest.approx(5e-3)
    assert sim.p.m[0] == pytest.approx(4 / 3 * math.pi * 5e-3**3 * 2600)


def test_jkr_zero_load_radius_is_where_the_jkr_force_vanishes():
    from soilcal.dem.contact import jkr_force
    from soilcal.dem.materials import jkr_zero_load_radius

    estar, w, rstar = 7.3e5, 0.7, 1.2e-3
    a0 = jkr_zero_load_radius(estar, w, rstar)
    assert a0 == pytest.approx((9 * math.pi * w * rstar**2 / (2 * estar)) ** (1 / 3), rel=1e-14)
    # F(a) = 4 E* a^3 / (3 R*) - sqrt(8 pi w E* a^3) (JKR 1971) is zero at a0 and changes
    # sign there; the Hertz part alone is of order 4 E* a0^3 / (3 R*)
    scale = 4 * estar * a0**3 / (3 * rstar)
    assert abs(jkr_force(a0, rstar, estar, w)) < 1e-12 * scale
    assert jkr_force(1.01 * a0, rstar, estar, w) > 0 > jkr_force(0.99 * a0, rstar, estar, w)


def jkr_table(gamma):
    mats = MaterialTable()
    mats.add(Material("soil", 1394, 0.311, shear=5e5))
    mats.add(Material("steel", 7850, 0.3, shear=7.9e10))
    mats.set_pair("soil", "soil", 0.45, 0.56, 0.11, gamma)
    mats.set_pair("soil", "steel", 0.45, 0.54, 0.125, 0.0)
    mats.set_pair("steel", "steel", 0.5, 0.3)
    return mats


def test_jkr_step_bound_caps_the_default_step_and_rejects_larger_steps():
    r, gamma = 2.2e-3, 0.7
    nu, g = 0.311, 5e5
    estar = 2 * g * (1 + nu) / (2 * (1 - nu**2))
    m = 1394 * 4 / 3 * math.pi * r**3
    # the bound is set by the stiffest pair: the soil plate (R* = r) below the spheres
    # (pairs of spheres have R* = r/2, a smaller a0 and a larger bound)
    a0 = (9 * math.pi * gamma * r * r / (2 * estar)) ** (1 / 3)
    bound = 0.17 * math.sqrt(m / (2 * estar * a0))
    tr = math.pi * r * math.sqrt(1394 / g) / (0.1631 * nu + 0.8766)
    assert bound < 0.3 * tr  # the case the bound exists for
    sim = Simulation(jkr_table(gamma), dt_fraction=0.3, contact_model=dict(cohesion="jkr"))
    sim.add_particles([[0, 0, 0.01], [0.01, 0, 0.01]], r, "soil")
    sim.run(1)
    assert sim.dt == pytest.approx(bound, rel=1e-12)
    # no adhesion: the Rayleigh fraction as before (0.2: below the damped-contact cap)
    sim0 = Simulation(jkr_table(0.0), dt_fraction=0.2, contact_model=dict(cohesion="jkr"))
    sim0.add_particles([[0, 0, 0.01]], r, "soil")
    sim0.run(1)
    assert sim0.dt == pytest.approx(0.2 * tr, rel=1e-12)
    bad = Simulation(jkr_table(gamma), dt=1.05 * bound, contact_model=dict(cohesion="jkr"))
    bad.add_particles([[0, 0, 0.01]], r, "soil")
    with pytest.raises(InputError, match="JKR bound") as e:
        bad.run(1)
    assert e.value.field == "dt"


def test_cohesive_bed_comes_to_rest():
    """500 JKR spheres poured into a 60 mm steel tube (the cylinder-lifting fill at quick
    size: radii 3.3-4.0 mm, G = 5e5 Pa, gamma 1.1 J/m^2) come to rest, a mean speed below
    2 mm/s after 1.5 s.  With the step at 30 % of the Rayleigh time, above the JKR bound
    here, the same fill kept jittering at about 1 cm/s."""
    from soilcal.dem.factories import CylinderRegion, UniformRadius, insert_random

    x, r = insert_random(CylinderRegion(0.026, 0.004, 0.2), UniformRadius(3.3e-3, 4.0e-3),
                         n=500, rng=np.random.default_rng(0), source="test")
    sim = Simulation(jkr_table(1.1), dt_fraction=0.3, max_overlap=0.3,
                     contact_model=dict(cohesion="jkr", rolling="constant_torque"),
                     skin=2.4e-3)
    sim.add_particles(x, r, "soil")
    sim.add_cylinder((0, 0, 0.11), (0, 0, 1), 0.03, 0.11, "steel", inner=True)
    sim.add_plane((0, 0, 0), (0, 0, 1), "steel")
    sim.run(0)
    sim.run(int(1.5 / sim.dt))
    v = np.sqrt(2 * sim.kinetic_energy() / sim.p.m.sum())
    assert v < 2e-3


def _damped_step(k, m, z):
    # stable step of x'' + 2 z w x' + w^2 x = 0 under leapfrog with half-step damping:
    # the roots of l^2 + (h^2 + 2 z h - 2) l + (1 - 2 z h) = 0 (h = w dt) stay in the unit
    # circle while h^2 + 4 z h - 4 < 0 (Jury), i.e. h < 2 (sqrt(1 + z^2) - z)
    w = math.sqrt(k / m)
    h = -2 * z + math.sqrt(4 * z * z + 4)
    return h / w


def test_damped_contact_bound_for_low_restitution():
    """The damped-contact step bound (materials.py) from the spring and dashpot of each
    contact at max_overlap: tangential spring 8 G* sqrt(R* d) on the effective slip mass
    2/7 m*, dashpot 2 sqrt(5/6) |beta| sqrt(S m*); normal spring 2 E* sqrt(R* d) on m*."""
    r, rho, nu, g, e, ov = 3e-3, 1800.0, 0.33, 5e5, 0.15, 0.3
    mats = MaterialTable()
    mats.add(Material("soil", rho, nu, shear=g))
    mats.add(Material("steel", 7850, 0.3, shear=7.9e10))
    mats.set_pair("soil", "soil", e, 0.8, 0.0, 0.0)
    mats.set_pair("soil", "steel", 0.9, 0.0, 0.0, 0.0)  # frictionless wall: normal mode only
    mats.set_pair("steel", "steel", 0.5, 0.3)
    m = rho * 4 / 3 * math.pi * r**3
    le = math.log(e)
    beta = le / math.sqrt(le * le + math.pi**2)
    z = math.sqrt(5 / 6) * abs(beta)
    estar = 2 * g * (1 + nu) / (2 * (1 - nu**2))
    gstar = g / (2 * (2 - nu))
    d = ov * r
    rs, ms = r / 2, m / 2
    tangential = _damped_step(8 * gstar * math.sqrt(rs * d), 2 / 7 * ms, z * math.sqrt(7 / 2))
    normal = _damped_step(2 * estar * math.sqrt(rs * d), ms, z)
    assert tangential < normal
    le9 = math.log(0.9)
    z_wall = math.sqrt(5 / 6) * abs(le9 / math.sqrt(le9 * le9 + math.pi**2))
    e_wall = 1 / ((1 - nu**2) / (2 * g * (1 + nu)) + (1 - 0.3**2) / (2 * 7.9e10 * 1.3))
    wall = _damped_step(2 * e_wall * math.sqrt(r * d), m, z_wall)
    bound = min(tangential, normal, wall)
    tr = math.pi * r * math.sqrt(rho / g) / (0.1631 * nu + 0.8766)
    sim = Simulation(mats, dt_fraction=0.3, max_overlap=ov)
    sim.add_particles([[0, 0, 0.01], [0.01, 0, 0.01]], r, "soil")
    sim.add_plane((0, 0, 0), (0, 0, 1), "steel")
    sim.run(1)
    assert sim.damping_dt == pytest.approx(bound, rel=1e-12)
    assert 0.7 * bound < 0.3 * tr  # heavy damping: the cap binds
    assert sim.dt == pytest.approx(0.7 * bound, rel=1e-12)
    # in units of the Rayleigh time the bound does not depend on the modulus
    mats.materials[0].shear = 100 * g
    stiff = Simulation(mats, dt_fraction=0.3, max_overlap=ov)
    stiff.add_particles([[0, 0, 0.01]], r, "soil")
    stiff.run(1)
    assert stiff.damping_dt / stiff.rayleigh == pytest.approx(bound / tr, rel=1e-9)
    mats.materials[0].shear = g
    bad = Simulation(mats, dt=1.05 * bound, max_overlap=ov)
    bad.add_particles([[0, 0, 0.01]], r, "soil")
    with pytest.raises(InputError, match="damped-contact bound") as err:
        bad.run(1)
    assert err.value.field == "dt"


@pytest.mark.parametrize("zeta", [0.0, 0.2, 0.47, 0.9])
def test_damped_step_bound_is_the_leapfrog_stability_limit(zeta):
    """Integrate x'' = -w^2 x - 2 z w v as the engine does (kick with the force from the
    half-step velocity, drift): bounded just below damped_critical_dt, growing just above."""
    from soilcal.dem.materials import damped_critical_dt

    k, m = 4.0e3, 2.0e-4
    w = math.sqrt(k / m)
    hc = damped_critical_dt(k, m, zeta)

    def growth(dt):
        # largest |x| over the last 200 of 4000 steps over the largest of the first 200
        x, v, peaks = 1.0, 0.0, []
        for _ in range(4000):
            v += dt * (-w * w * x - 2 * zeta * w * v)
            x += dt * v
            peaks.append(abs(x))
            if abs(x) > 1e12:
                return math.inf
        return max(peaks[-200:]) / max(peaks[:200])

    assert growth(0.99 * hc) < 1.01  # undamped: sampled peaks of a steady oscillation
    assert growth(1.01 * hc) > 1e3
