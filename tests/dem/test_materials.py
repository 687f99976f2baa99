"""Pair tables, Rayleigh time step, stiffness scaling and coarse graining."""

import math

import pytest

from soilcal.dem.engine import Simulation
from soilcal.dem.materials import (P_BETA, P_ESTAR, P_GSTAR, P_W, Material, MaterialTable,
                                   rayleigh_time)


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
