"""Normal impact (restitution, Hertz contact time) and JKR force-overlap curve vs analytic."""

import math

import numpy as np
import pytest

from conftest import head_on, table
from soilcal.dem.engine import Simulation

R = 1e-3
E, NU, RHO = 1e9, 0.3, 2600.0
ESTAR = E / (2 * (1 - NU**2))
MASS = 4 / 3 * math.pi * R**3 * RHO


def impact(e, v0, dt=1e-7):
    return head_on(table(e=e, mu=0.0, E=E), v0, R, dt)


@pytest.mark.parametrize("e", [0.1, 0.3, 0.5, 0.7, 0.9])
@pytest.mark.parametrize("v0", [0.02, 0.1])
def test_restitution_matches_input(e, v0):
    ratio, _ = impact(e, v0)
    assert ratio == pytest.approx(e, rel=0.01)


@pytest.mark.parametrize("v0", [0.02, 0.1])
def test_hertz_contact_time(v0):
    ratio, tc = impact(1.0, v0, dt=1e-7)
    mstar, rstar = MASS / 2, R / 2
    t_hertz = 2.868 * (mstar**2 / (rstar * ESTAR**2 * v0)) ** 0.2  # Hertz (Johnson 1985)
    assert ratio == pytest.approx(1.0, abs=1e-4)
    assert tc == pytest.approx(t_hertz, rel=0.01)


def jkr_analytic(a, rstar, w):
    """JKR with work of adhesion w (Johnson, Kendall & Roberts 1971)."""
    delta = a * a / rstar - math.sqrt(2 * math.pi * w * a / ESTAR)
    force = 4 * ESTAR * a**3 / (3 * rstar) - math.sqrt(8 * math.pi * w * ESTAR * a**3)
    return delta, force


@pytest.mark.parametrize("convention,factor", [("edem", 1.0), ("lammps", 2.0)])
@pytest.mark.parametrize("wall", [False, True])
def test_jkr_curve_and_pulloff(convention, factor, wall):
    gamma = 0.3
    w = factor * gamma
    sim = Simulation(table(e=0.5, mu=0.0, gamma=gamma, E=E), dt=1e-7, gravity=(0, 0, 0),
                     contact_model=dict(cohesion="jkr", jkr_convention=convention,
                                        tangential="none"))
    if wall:
        sim.add_particles([[0, 0, R]], R, "soil")
        sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
        rstar = R
    else:
        sim.add_particles([[0, 0, 0], [0, 0, 2 * R]], R, "soil")
        rstar = R / 2
    pulloff = 1.5 * math.pi * w * rstar
    expected_pulloff = {"edem": 1.5, "lammps": 3.0}[convention] * math.pi * gamma * rstar
    assert pulloff == pytest.approx(expected_pulloff, rel=1e-12)
    a0 = (9 * math.pi * w * rstar**2 / (2 * ESTAR)) ** (1 / 3)
    ac = (math.pi * w * rstar**2 / (8 * ESTAR)) ** (1 / 3)
    # unloading from a = 2 a0 down to just above the separation radius a_c
    amin_force = 1e300
    for a in np.linspace(2 * a0, 1.0005 * ac, 400):
        delta, fa = jkr_analytic(a, rstar, w)
        if wall:
            sim.p.x[0, 2] = R - delta
        else:
            sim.p.x[1, 2] = 2 * R - delta
        f = sim.compute_forces()[0][0 if wall else 1, 2]
        assert f == pytest.approx(fa, abs=0.01 * max(abs(fa), pulloff))
        amin_force = min(amin_force, f)
    assert -amin_force == pytest.approx(expected_pulloff, rel=0.01)
    # beyond the separation overlap the contact breaks
    dsep, _ = jkr_analytic(ac, rstar, w)
    if wall:
        sim.p.x[0, 2] = R - 1.01 * dsep
    else:
        sim.p.x[1, 2] = 2 * R - 1.01 * dsep
    assert sim.compute_forces()[0][0 if wall else 1, 2] == 0.0
    # and does not re-form on approach until overlap is positive
    if wall:
        sim.p.x[0, 2] = R - 0.5 * dsep
    else:
        sim.p.x[1, 2] = 2 * R - 0.5 * dsep
    assert sim.compute_forces()[0][0 if wall else 1, 2] == 0.0


@pytest.mark.parametrize("warm", [0.0, 1e-4, -1e-4, 1e-2])
def test_jkr_root_inverts_the_jkr_overlap(warm):
    """The Newton root a = x^2 returns the contact radius whose analytic JKR overlap was
    given, to 1e-12 relative, from a cold start and from warm starts off by `warm`."""
    from soilcal.dem.contact import jkr_root

    gamma = 0.3
    rstar = R / 2
    c = math.sqrt(2 * math.pi * gamma / ESTAR)
    a0 = (9 * math.pi * gamma * rstar**2 / (2 * ESTAR)) ** (1 / 3)
    ac = (math.pi * gamma * rstar**2 / (8 * ESTAR)) ** (1 / 3)
    for a in np.geomspace(1.0005 * ac, 20 * a0, 60):
        delta, _ = jkr_analytic(a, rstar, gamma)
        x_prev = math.sqrt(a) * (1 + warm) if warm else 0.0
        x = jkr_root(delta, rstar, c, x_prev)
        assert x * x == pytest.approx(a, rel=1e-12)


@pytest.mark.parametrize("v0", [0.02, 0.1])
def test_peak_overlap_is_the_hertz_maximum_compression(v0):
    """Elastic head-on impact: the largest overlap is Hertz's maximum compression
    delta_max = (15 m* v0^2 / (16 E* sqrt(R*)))^(2/5) (Johnson 1985, Sec. 11.1)."""
    sim = Simulation(table(e=1.0, mu=0.0, E=E), dt=1e-7, gravity=(0, 0, 0),
                     contact_model=dict(tangential="none"))
    sim.add_particles([[0, 0, 0], [2 * R + 1e-7, 0, 0]], R, "soil",
                      v=[[v0 / 2, 0, 0], [-v0 / 2, 0, 0]])
    assert sim.peak_overlap == 0.0
    sim.run(int(4 * 2.868 * ((MASS / 2) ** 2 / (R / 2 * ESTAR**2 * v0)) ** 0.2 / 1e-7))
    mstar, rstar = MASS / 2, R / 2
    dmax = (15 * mstar * v0**2 / (16 * ESTAR * math.sqrt(rstar))) ** 0.4
    assert sim.x[1, 0] - sim.x[0, 0] > 2 * R  # separated again
    assert sim.peak_overlap * R == pytest.approx(dmax, rel=1e-3)
    peak = sim.peak_overlap
    sim.add_particles([[0, 10 * R, 0]], R, "soil")  # a new row array keeps the run's peak
    assert sim.peak_overlap == peak
    sim.reset_peak_overlap()
    sim.run(10)
    assert sim.peak_overlap == 0.0
