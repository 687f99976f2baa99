"""The LAMMPS ``pair granular`` terms as options (contact.py, "Conventions of the reference
engines"): each against the force written out by hand from its definition (JKR 1971, the
LAMMPS sources named in contact.py), one contact at a time."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from conftest import table
from soilcal.dem.contact import contact_force, model_codes
from soilcal.dem.engine import Simulation
from soilcal.dem.materials import (P_BETA, P_ETA, TANGENTIAL_MASS, damped_critical_dt,
                                   restitution_beta)
from soilcal.errors import InputError

R = 1e-3
E, NU, RHO = 1e7, 0.3, 2600.0
ESTAR = E / (2 * (1 - NU**2))
GSTAR = E / (2 * (1 + NU)) / (2 * (2 - NU))
MASS = 4 / 3 * math.pi * R**3 * RHO
RSTAR, MSTAR = R / 2, MASS / 2
SQ56 = math.sqrt(5 / 6)


def jkr_delta(a, rstar, w):
    return a * a / rstar - math.sqrt(2 * math.pi * w * a / ESTAR)


def jkr_force(a, rstar, w):
    return 4 * ESTAR * a**3 / (3 * rstar) - math.sqrt(8 * math.pi * w * ESTAR * a**3)


def jkr_radius(delta, rstar, w):
    """The stable-branch contact radius (a >= a_c) of overlap delta, by bisection."""
    ac = (math.pi * w * rstar**2 / (8 * ESTAR)) ** (1 / 3)
    return brentq(lambda a: jkr_delta(a, rstar, w) - delta, ac, 1e3 * ac + 10 * rstar,
                  xtol=1e-18, rtol=1e-15)


def kernel(codes, tab, delta, rv, hist, dt=1e-7, touching=True, w=(0.0, 0.0, 0.0)):
    """One contact of sphere i above sphere j (normal +z), equal radii R: the force on i."""
    out = contact_force(codes, tab, 0, 0, delta, 0.0, 0.0, 1.0, *rv, *w, R - delta / 2,
                        R - delta / 2, RSTAR, MSTAR, dt, touching, hist, 0)
    return np.array(out[1:4])


@pytest.mark.parametrize("brk", ["displacement", "force"])
def test_jkr_break_at_the_force_minimum(brk):
    """``force``: the contact breaks at the overlap of the pull-off force, delta_f =
    delta(a_f), a_f = (9 pi w R*^2 / (8 E*))^(1/3), which is LAMMPS's pull-off distance
    (3 pi^2 gamma^2 R* / (16 E*^2))^(1/3) with w = 2 gamma; ``displacement`` keeps it on the
    JKR branch down to delta_c = -3/4 (pi^2 w^2 R* / E*^2)^(1/3)."""
    gamma = 0.3
    w = 2 * gamma
    sim = Simulation(table(e=0.5, mu=0.0, gamma=gamma, E=E), dt=1e-7, gravity=(0, 0, 0),
                     contact_model=dict(cohesion="jkr", jkr_convention="lammps",
                                        tangential="none", jkr_break=brk))
    sim.add_particles([[0, 0, 0], [0, 0, 2 * R]], R, "soil")
    af = (9 * math.pi * w * RSTAR**2 / (8 * ESTAR)) ** (1 / 3)
    df = jkr_delta(af, RSTAR, w)
    assert -df == pytest.approx((3 * math.pi**2 * gamma**2 * RSTAR / (16 * ESTAR**2)) ** (1 / 3),
                                rel=1e-12)
    dc = -0.75 * (math.pi**2 * w**2 * RSTAR / ESTAR**2) ** (1 / 3)
    assert dc < 1.01 * df < 0.99 * df < 0
    pulloff = 1.5 * math.pi * w * RSTAR  # 3 pi gamma R*
    for delta in (1e-6, 0.99 * df, 1.01 * df):  # loaded, then pulled past delta_f
        sim.p.x[1, 2] = 2 * R - delta
        fz = sim.compute_forces()[0][1, 2]
        a = jkr_radius(delta, RSTAR, w)
        expected = jkr_force(a, RSTAR, w)
        if delta == 1.01 * df and brk == "force":
            expected = 0.0
        assert fz == pytest.approx(expected, rel=1e-9, abs=1e-12 * pulloff)
    if brk == "displacement":
        assert fz == pytest.approx(-pulloff, rel=1e-3)  # near the force minimum


def test_viscous_radius_damping_normal_and_tangential():
    """F_n = Hertz - eta m* a v_n and F_t = -sqrt(4 G*/E*) eta m* a v_t (no spring yet at
    the initial evaluation); the restitution is not used."""
    eta, delta, vz, vt = 4e5, 2e-5, -0.02, 3e-3
    sim = Simulation(table(e=0.5, mu=0.5, E=E), dt=1e-7, gravity=(0, 0, 0),
                     contact_model=dict(damping="viscous_radius", damping_eta=eta))
    sim.add_particles([[0, 0, 2 * R - delta], [0, 0, 0]], R, "soil",
                      v=[[vt, 0, vz], [0, 0, 0]])
    f = sim.compute_forces()[0][0]
    a = math.sqrt(RSTAR * delta)
    fn = 4 / 3 * ESTAR * a * delta - eta * MSTAR * a * vz
    assert f[2] == pytest.approx(fn, rel=1e-12)
    ft = -math.sqrt(4 * GSTAR / ESTAR) * eta * MSTAR * a * vt
    assert abs(ft) < 0.5 * fn
    assert f[0] == pytest.approx(ft, rel=1e-12)
    tab = sim._pair
    assert tab[0, 0, P_ETA] == eta and tab[0, 0, P_BETA] == 0.0


def test_viscous_radius_time_step_bound():
    """The damped-mode bound (materials.py) at max_overlap with the normal ratio
    z = eta m* a / (2 sqrt(2 E* a m*)), and the tangential mode at z / sqrt(2/7)."""
    eta, mo = 2e6, 0.3
    tab = table(e=0.5, mu=0.5, E=E)
    pair = tab.table(1.0, eta)
    a = math.sqrt(RSTAR * mo * R)
    z = eta * MSTAR * a / (2 * math.sqrt(2 * ESTAR * a * MSTAR))
    expected = min(damped_critical_dt(2 * ESTAR * a, MSTAR, z),
                   damped_critical_dt(8 * GSTAR * a, TANGENTIAL_MASS * MSTAR,
                                      z / math.sqrt(TANGENTIAL_MASS)))
    assert tab.damping_dt({0: R}, pair, mo, wall_materials=set()) == pytest.approx(expected,
                                                                                   rel=1e-12)
    assert expected < tab.damping_dt({0: R}, tab.table(1.0, 0.0), mo, wall_materials=set())


@pytest.mark.parametrize("kw,field", [(dict(damping="viscous_radius"), "damping_eta"),
                                      (dict(damping="viscous_radius", damping_eta=-1.0),
                                       "damping_eta"),
                                      (dict(damping_eta=1e5), "damping_eta"),
                                      (dict(jkr_break="strength"), "jkr_break"),
                                      (dict(contact_lever="arm"), "contact_lever")])
def test_bad_options_named(kw, field):
    with pytest.raises(InputError) as exc:
        model_codes(**kw)
    assert exc.value.field == f"contact_model.{field}"


@pytest.mark.parametrize("rule", ["total", "jkr_elastic"])
def test_coulomb_limit_of_a_jkr_contact(rule):
    """A loaded JKR contact approaching at 1 cm/s, its spring far beyond the limit: the
    sliding force is mu |F_ne + F_d + 2 F_po| (``total``) or mu |F_ne + 2 F_po| (LAMMPS)."""
    gamma, mu, delta, vn = 0.3, 0.4, 2e-6, -0.01
    w = 2 * gamma
    codes, wf = model_codes(cohesion="jkr", jkr_convention="lammps", coulomb_force=rule)
    tab = table(e=0.5, mu=mu, gamma=gamma, E=E).table(wf)
    hist = np.zeros((1, 4))
    hist[0, 0] = 1e-3
    f = kernel(codes, tab, delta, (0.0, 0.0, vn), hist)
    a = jkr_radius(delta, RSTAR, w)
    fne = jkr_force(a, RSTAR, w)
    fd = 2 * SQ56 * abs(restitution_beta(0.5)) * math.sqrt(2 * ESTAR * a * MSTAR) * -vn
    fpo2 = 3 * math.pi * w * RSTAR
    assert f[2] == pytest.approx(fne + fd, rel=1e-9)
    limit = mu * abs(fne + fpo2 + (fd if rule == "total" else 0.0))
    assert f[0] == pytest.approx(-limit, rel=1e-9)
    # a Hertz contact keeps the total force under either rule
    codes_h, _ = model_codes(coulomb_force=rule)
    hist[0, :] = 0.0
    hist[0, 0] = 1e-3
    fh = kernel(codes_h, table(e=0.5, mu=mu, E=E).table(1.0), 2e-5, (0.0, 0.0, vn), hist)
    assert fh[0] == pytest.approx(-mu * fh[2], rel=1e-12)


@pytest.mark.parametrize("slip", ["spring", "damped"])
def test_sliding_rule(slip):
    """xi = xi0 + v_t dt; ``spring``: the test on -S_t xi, the shortened spring is the force;
    ``damped``: the test on -S_t xi + F_t^d, the sum scaled to the limit and the spring
    set to its elastic part, xi = -(F_t - F_t^d) / S_t."""
    mu, delta, vt, dt = 0.3, 2e-5, 0.05, 1e-7
    codes, _ = model_codes(tangential_slip=slip)
    tab = table(e=0.5, mu=mu, E=E).table(1.0)
    xi0 = 1e-5
    hist = np.zeros((1, 4))
    hist[0, 0] = xi0
    f = kernel(codes, tab, delta, (vt, 0.0, 0.0), hist, dt=dt)
    a = math.sqrt(RSTAR * delta)
    st = 8 * GSTAR * a
    fn = 4 / 3 * ESTAR * a * delta
    ct = -2 * SQ56 * abs(restitution_beta(0.5)) * math.sqrt(2 * ESTAR * a * MSTAR) \
        * math.sqrt(4 * GSTAR / ESTAR)
    xi1 = xi0 + vt * dt
    spring, damp = -st * xi1, ct * vt
    assert abs(spring) > mu * fn and abs(spring + damp) > mu * fn  # sliding either way
    assert f[2] == pytest.approx(fn, rel=1e-12)
    assert f[0] == pytest.approx(-mu * fn, rel=1e-12)
    expected_xi = mu * fn / st if slip == "spring" else -(-mu * fn - damp) / st
    assert hist[0, 0] == pytest.approx(expected_xi, rel=1e-12)
    assert (slip == "spring") == (hist[0, 0] == pytest.approx(mu * fn / st, rel=1e-9))


@pytest.mark.parametrize("rotation", ["project", "rescale"])
def test_history_rotation(rotation):
    """A spring with a part along the normal: ``project`` drops that part, ``rescale`` turns
    the spring into the tangent plane at its full length, and leaves it alone when no time
    passes (a run's setup)."""
    delta, dt = 2e-5, 1e-7
    codes, _ = model_codes(history_rotation=rotation, tangential_damping="off")
    tab = table(e=0.5, mu=0.5, E=E).table(1.0)
    xi = (3e-7, 0.0, 1e-7)
    hist = np.zeros((1, 4))
    hist[0, :3] = xi
    kernel(codes, tab, delta, (0.0, 0.0, 0.0), hist, dt=dt)
    length = math.hypot(xi[0], xi[2]) if rotation == "rescale" else xi[0]
    np.testing.assert_allclose(hist[0, :3], [length, 0.0, 0.0], rtol=1e-12, atol=1e-24)
    hist[0, :3] = xi
    kernel(codes, tab, delta, (0.0, 0.0, 0.0), hist, dt=0.0)
    kept = xi if rotation == "rescale" else (xi[0], 0.0, 0.0)
    np.testing.assert_allclose(hist[0, :3], kept, rtol=1e-12, atol=1e-24)


@pytest.mark.parametrize("lever", ["contact_point", "radius"])
@pytest.mark.parametrize("wall", [False, True])
def test_contact_lever(lever, wall):
    """A sphere spinning at omega_y on a sphere (or a plane) below it, at rest otherwise:
    the contact point slides at -l omega_y along x with l = R - delta/2 (``contact_point``)
    or R (``radius``); the dashpot alone acts at the initial evaluation, and its torque
    has the lever R - delta/2, or R against a wall with ``radius``."""
    delta, wy = 2e-5, 3.0
    sim = Simulation(table(e=0.5, mu=0.5, E=E), dt=1e-7, gravity=(0, 0, 0),
                     contact_model=dict(contact_lever=lever))
    if wall:
        sim.add_particles([[0, 0, R - delta]], R, "soil", omega=[[0, wy, 0]])
        sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
        rstar, mstar = R, MASS
    else:
        sim.add_particles([[0, 0, 2 * R - delta], [0, 0, 0]], R, "soil",
                          omega=[[0, wy, 0], [0, 0, 0]])
        rstar, mstar = RSTAR, MSTAR
    f, t = sim.compute_forces()
    a = math.sqrt(rstar * delta)
    ct = -2 * SQ56 * abs(restitution_beta(0.5)) * math.sqrt(2 * ESTAR * a * mstar) \
        * math.sqrt(4 * GSTAR / ESTAR)
    lv = R if lever == "radius" else R - delta / 2
    ft = ct * (-lv * wy)
    assert f[0, 0] == pytest.approx(ft, rel=1e-12)
    arm = R if (wall and lever == "radius") else R - delta / 2
    # torque on i: (-arm n) x F_t with n = +z: -arm (0, 0, 1) x (ft, 0, 0) = (0, -arm ft, 0)
    assert t[0, 1] == pytest.approx(-arm * ft, rel=1e-12)
