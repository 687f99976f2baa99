"""The reference engines' conventions (contact.py, "Conventions of the reference engines"):
each option against the torque or force written out by hand from its definition."""

import math

import numpy as np
import pytest

from conftest import table
from soilcal.dem.contact import CONVENTIONS, model_codes
from soilcal.dem.engine import Simulation
from soilcal.dem.materials import restitution_beta
from soilcal.dem.scenarios import repose
from soilcal.dem.scenarios.base import DemParams, conventions_of, make_simulation
from soilcal.errors import InputError

R = 1e-3
E, NU, RHO = 1e7, 0.3, 2600.0
ESTAR = E / (2 * (1 - NU**2))
GSTAR = E / (2 * (1 + NU)) / (2 * (2 - NU))
MASS = 4 / 3 * math.pi * R**3 * RHO
MUR, REST = 0.2, 0.5


def pair(conv, omega_i, vz=0.0, ri=R, rj=R, delta=2e-5, rolling="constant_torque", **kw):
    """Sphere i above sphere j (normal +z from j to i) with overlap delta; i moves at vz and
    spins at omega_i, j at rest.  Returns (force on i, torque on i, torque on j, R*, m*)."""
    sim = Simulation(table(e=REST, mu=0.5, mur=MUR, E=E, nu=NU), dt=1e-7, gravity=(0, 0, 0),
                     contact_model=dict(rolling=rolling, tangential="none", conventions=conv,
                                        **kw))
    sim.add_particles([[0, 0, ri + rj - delta], [0, 0, 0]], np.array([ri, rj]), "soil",
                      v=[[0, 0, vz], [0, 0, 0]])
    sim.p.omega[0] = omega_i
    f, t = sim.compute_forces()
    mi, mj = MASS * (ri / R) ** 3, MASS * (rj / R) ** 3
    return f[0].copy(), t[0].copy(), t[1].copy(), ri * rj / (ri + rj), mi * mj / (mi + mj)


def hertz(delta, rstar):
    return 4 / 3 * ESTAR * math.sqrt(rstar) * delta**1.5


def damping(delta, rstar, mstar, vn):
    """Viscoelastic normal damping force (positive repulsive) at approach speed -vn."""
    sn = 2 * ESTAR * math.sqrt(rstar * delta)
    return 2 * math.sqrt(5 / 6) * restitution_beta(REST) * math.sqrt(sn * mstar) * vn


def test_edem_rolling_torque_total_force_own_lever_full_axis():
    """EDEM: tau_i = -mu_r |F_n,tot| c_i omega_rel/|omega_rel| with c_i = R_i - delta/2, the
    torsion part kept; the partner takes -(c_j/c_i) of it."""
    delta, w = 2e-5, np.array([0.0, 3.0, 4.0])
    f, ti, tj, rstar, mstar = pair("edem", w, vz=-0.01, rj=1.5 * R, delta=delta)
    ftot = hertz(delta, rstar) + damping(delta, rstar, mstar, -0.01)
    assert f[2] == pytest.approx(ftot, rel=1e-9)
    ci, cj = R - delta / 2, 1.5 * R - delta / 2
    expected = -MUR * abs(ftot) * ci * w / np.linalg.norm(w)
    np.testing.assert_allclose(ti, expected, rtol=1e-9)
    np.testing.assert_allclose(tj, -expected * cj / ci, rtol=1e-9)


def test_liggghts_rolling_torque_elastic_force_effective_lever_no_torsion():
    """LIGGGHTS cdt (rolling_model_cdt.h): r_torque = rmu k_n delta R_eff w_rel/|w_rel| with
    its normal (torsion) part removed; -r_torque on i, +r_torque on j."""
    delta, w = 2e-5, np.array([0.0, 3.0, 4.0])
    f, ti, tj, rstar, mstar = pair("liggghts", w, vz=-0.01, rj=1.5 * R, delta=delta)
    fe = hertz(delta, rstar)
    assert f[2] == pytest.approx(fe + damping(delta, rstar, mstar, -0.01), rel=1e-9)
    wt = w - np.array([0.0, 0.0, w[2]])  # normal along z
    expected = -MUR * fe * rstar * wt / np.linalg.norm(w)
    np.testing.assert_allclose(ti, expected, rtol=1e-9, atol=1e-25)
    np.testing.assert_allclose(tj, -expected, rtol=1e-9, atol=1e-25)


@pytest.mark.parametrize("option,value", [("rolling_lever", "effective"),
                                          ("rolling_force", "elastic"),
                                          ("rolling_axis", "tangential")])
def test_each_option_alone(option, value):
    """One entry changed from EDEM's set changes only its own factor."""
    delta, w = 2e-5, np.array([0.0, 3.0, 4.0])
    _, base, _, rstar, mstar = pair("edem", w, vz=-0.01, delta=delta)
    _, ti, _, _, _ = pair("edem", w, vz=-0.01, delta=delta, **{option: value})
    ftot = hertz(delta, rstar) + damping(delta, rstar, mstar, -0.01)
    fe = hertz(delta, rstar)
    ci = R - delta / 2
    unit = w / np.linalg.norm(w)
    expected = {"rolling_lever": -MUR * ftot * rstar * unit,
                "rolling_force": -MUR * fe * ci * unit,
                "rolling_axis": -MUR * ftot * ci * np.array([0.0, unit[1], 0.0])}[option]
    np.testing.assert_allclose(ti, expected, rtol=1e-9, atol=1e-25)
    assert not np.allclose(ti, base)


def test_wall_lever():
    """Against a wall EDEM's lever is c_i = R - delta/2; LIGGGHTS 3.8 takes R_i."""
    delta, w = 2e-5, np.array([5.0, 0.0, 0.0])
    out = {}
    for conv in ("edem", "liggghts"):
        sim = Simulation(table(e=REST, mu=0.5, mur=MUR, E=E, nu=NU), dt=1e-7,
                         gravity=(0, 0, 0),
                         contact_model=dict(rolling="constant_torque", tangential="none",
                                            conventions=conv))
        sim.add_particles([[0, 0, R - delta]], R, "soil")
        sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
        sim.p.omega[0] = w
        out[conv] = sim.compute_forces()[1][0].copy()
    unit = w / np.linalg.norm(w)
    np.testing.assert_allclose(out["edem"], -MUR * hertz(delta, R) * (R - delta / 2) * unit,
                               rtol=1e-9)
    np.testing.assert_allclose(out["liggghts"], -MUR * hertz(delta, R) * R * unit, rtol=1e-9)


@pytest.mark.parametrize("mode", ["relative", "absolute"])
def test_rolling_against_a_rotating_wall(mode):
    """A sphere turning with its wall: relative to the wall it does not roll (no torque);
    by its own rotation it is resisted by mu_r F c_i, as LIGGGHTS's wall torque."""
    delta, w = 2e-5, np.array([0.0, 2.0, 0.0])
    sim = Simulation(table(e=REST, mu=0.5, mur=MUR, E=E, nu=NU), dt=1e-7, gravity=(0, 0, 0),
                     contact_model=dict(rolling="constant_torque", tangential="none",
                                        rolling_wall=mode))
    sim.add_particles([[0, 0, R - delta]], R, "soil")
    wall = sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    sim.set_wall_motion(wall, omega=w)
    sim.p.omega[0] = w
    t = sim.compute_forces()[1][0]
    expected = np.zeros(3) if mode == "relative" else \
        -MUR * hertz(delta, R) * (R - delta / 2) * w / np.linalg.norm(w)
    np.testing.assert_allclose(t, expected, rtol=1e-9, atol=1e-25)


@pytest.mark.parametrize("damped", ["on", "off"])
def test_tangential_damping_option(damped):
    """The initial state's forces of a sliding pair below the Coulomb limit: the new contact
    has no tangential displacement yet (no time has passed), so F_t is the damping force
    -2 sqrt(5/6)|beta| sqrt(S_t m*) v_t when it is on and zero when it is off."""
    delta, vt, dt = 2e-5, 1e-3, 1e-7
    sim = Simulation(table(e=REST, mu=0.5, E=E, nu=NU), dt=dt, gravity=(0, 0, 0),
                     contact_model=dict(tangential_damping=damped))
    sim.add_particles([[0, 0, 2 * R - delta], [0, 0, 0]], R, "soil", v=[[vt, 0, 0], [0, 0, 0]])
    f = sim.compute_forces()[0][0]
    rstar, mstar = R / 2, MASS / 2
    st = 8 * GSTAR * math.sqrt(rstar * delta)
    expected = 0.0
    if damped == "on":
        expected = -2 * math.sqrt(5 / 6) * abs(restitution_beta(REST)) * math.sqrt(st * mstar) * vt
    assert f[0] == pytest.approx(expected, rel=1e-9, abs=1e-30)
    # evaluating the same state again advances nothing
    assert sim.compute_forces()[0][0, 0] == pytest.approx(expected, rel=1e-12, abs=1e-30)


def test_tangential_history_after_one_step():
    """One step of the sliding pair (undamped tangential): xi = v_t(1/2) dt, with the
    half-step velocity v_t(1/2) = v_t (no tangential force acted at the start), so
    F_t = -8 G* a(1) v_t dt at the new overlap."""
    delta, vt, dt = 2e-5, 1e-3, 1e-7
    sim = Simulation(table(e=REST, mu=0.5, E=E, nu=NU), dt=dt, gravity=(0, 0, 0),
                     contact_model=dict(tangential_damping="off"))
    sim.add_particles([[0, 0, 2 * R - delta], [0, 0, 0]], R, "soil", v=[[vt, 0, 0], [0, 0, 0]])
    sim.run(1)
    rows = sim.index([0, 1])
    d = sim.x[rows[0]] - sim.x[rows[1]]
    dist = float(np.linalg.norm(d))
    a = math.sqrt(R / 2 * (2 * R - dist))
    n = d / dist
    # the relative motion of the centres in the step is vt dt along x (the normal force's
    # kick along z moves both spheres apart, not sideways)
    vrel_t = vt - vt * n[0] * n[0]
    f = sim.p.f[rows[0]]
    ft = f - np.dot(f, n) * n
    assert ft[0] == pytest.approx(-8 * GSTAR * a * vrel_t * dt, rel=1e-6)


def test_named_sets_and_single_entries():
    codes, w = model_codes(rolling="constant_torque")
    assert list(codes[5:]) == [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0] and w == 1.0
    codes, w = model_codes(rolling="constant_torque", conventions="lammps")
    assert list(codes[5:]) == [1, 1, 1, 0, 0, 1, 1, 1, 1, 1, 0, 1, 0] and w == 2.0
    codes, _ = model_codes(conventions="liggghts", rolling_force="total")
    assert list(codes[5:]) == [1, 0, 1, 0, 1, 0, 0, 0, 0, 0, 0, 0, 1]
    codes, _ = model_codes(conventions="lammps", jkr_break="displacement")
    assert list(codes[10:]) == [0, 1, 1, 1, 1, 0, 1, 0]
    codes, _ = model_codes(conventions="liggghts", epsd_form="tangent")
    assert codes[17] == 0
    codes, _ = model_codes(jkr_approach="gap")
    assert codes[15] == 1
    codes, _ = model_codes(conventions="lammps", wall_curvature="flat")
    assert codes[16] == 0
    assert set(CONVENTIONS) == {"edem", "liggghts", "lammps"}


@pytest.mark.parametrize("value,field", [
    ("ligghts", "setup.contact_conventions"),
    ({"rolling_lever": "radius"}, "setup.contact_conventions.rolling_lever"),
    ({"rolling_arm": "effective"}, "setup.contact_conventions.rolling_arm"),
    ({"conventions": "edem3"}, "setup.contact_conventions.conventions"),
    (3, "setup.contact_conventions"),
])
def test_bad_conventions_named_before_a_run(value, field):
    setup = dict(repose.setups()["cinnamon-soil"], contact_conventions=value)
    with pytest.raises(InputError) as exc:
        repose.validate(setup, "quick", "soil.yaml")
    assert exc.value.field == field and exc.value.path == "soil.yaml"


def test_setup_conventions_reach_the_engine():
    setup = dict(repose.setups()["cinnamon-soil"], n_particles=50,
                 contact_conventions={"conventions": "liggghts", "tangential_damping": "off"})
    sim, _ = make_simulation(DemParams(), setup, "quick", "t")
    assert list(sim.codes[5:]) == [1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0, 1]
    assert conventions_of(None)["conventions"] == "edem"


@pytest.mark.parametrize("approach", ["touch", "gap"])
@pytest.mark.parametrize("wall", [False, True])
def test_jkr_attraction_across_a_gap(approach, wall):
    """Surfaces that have never touched, at a gap inside the JKR separation range: no force
    (``touch``), or the JKR force of that overlap on the stable branch (``gap``, EDEM's JKR:
    the same force on approach as on separation); beyond the range, none in either."""
    gamma = 0.3
    sim = Simulation(table(e=0.5, mu=0.0, gamma=gamma, E=E), dt=1e-7, gravity=(0, 0, 0),
                     contact_model=dict(cohesion="jkr", tangential="none",
                                        jkr_approach=approach))
    if wall:
        sim.add_particles([[0, 0, R]], R, "soil")
        sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
        rstar, k = R, 0
    else:
        sim.add_particles([[0, 0, 0], [0, 0, 2 * R]], R, "soil")
        rstar, k = R / 2, 1
    w = gamma  # EDEM convention
    ac = (math.pi * w * rstar**2 / (8 * ESTAR)) ** (1 / 3)
    dc = ac * ac / rstar - math.sqrt(2 * math.pi * w * ac / ESTAR)
    a = 1.5 * ac  # a stable-branch radius whose overlap is a gap
    delta = a * a / rstar - math.sqrt(2 * math.pi * w * a / ESTAR)
    assert dc < delta < 0
    force = 4 * ESTAR * a**3 / (3 * rstar) - math.sqrt(8 * math.pi * w * ESTAR * a**3)
    for d, expected in ((delta, force if approach == "gap" else 0.0), (1.01 * dc, 0.0)):
        sim.p.x[k, 2] = (R if wall else 2 * R) - d
        fz = sim.compute_forces()[0][k, 2]
        assert fz == pytest.approx(expected, rel=1e-9, abs=1e-15)
    assert force < 0


def test_liggghts_epsd_pair_spring_is_secant_and_counts_the_setup_step():
    """LIGGGHTS rolling_model_epsd.h between spheres: r_torque = M_old + k_r w_t dt with
    k_r = 2.25 k_n mu_r^2 R*^2 and k_n = F_ne / delta = 4/3 E* a (its Hertz kn), w_t the
    relative rotation without its normal part; -r_torque on i, +r_torque on j.  A run's setup
    (compute_forces) applies the step's increment without storing it.  soilcal's own form
    (``tangent``, EDEM's set) takes S_n = 2 E* a and adds nothing at the setup."""
    delta, w = 2e-5, np.array([0.0, 3.0, 4.0])
    dt = 1e-7  # the step of pair()
    _, ti, tj, rstar, _ = pair("liggghts", w, vz=-0.01, rj=1.5 * R, delta=delta,
                               rolling="epsd")
    kn = 4 / 3 * ESTAR * math.sqrt(rstar * delta)
    kr = 2.25 * kn * MUR**2 * rstar**2
    wt = w - np.array([0.0, 0.0, w[2]])  # normal along z
    np.testing.assert_allclose(ti, -kr * wt * dt, rtol=1e-9, atol=1e-25)
    np.testing.assert_allclose(tj, kr * wt * dt, rtol=1e-9, atol=1e-25)
    _, ti, _, _, _ = pair("edem", w, vz=-0.01, rj=1.5 * R, delta=delta, rolling="epsd")
    np.testing.assert_allclose(ti, 0.0, atol=1e-25)


def _epsd_on_floor(conv, w, vz, delta=2e-5, dt=1e-7):
    sim = Simulation(table(e=REST, mu=0.5, mur=MUR, E=E, nu=NU), dt=dt, gravity=(0, 0, 0),
                     contact_model=dict(rolling="epsd", tangential="none", conventions=conv))
    sim.add_particles([[0, 0, R - delta]], R, "soil", v=[[0, 0, vz]])
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    sim.p.omega[0] = w
    return sim


def test_liggghts_epsd_wall_spring_and_limit():
    """Against a wall LIGGGHTS's epsd turns the spring by wr = omega (R - delta/2)/(R - delta)
    (surface_model_default.h) with R_eff = R, and limits it at mu_r R |F_n| with the damping
    in F_n (sidata.Fn); the setup's increment is not stored (evaluating twice gives the same
    torque)."""
    delta, dt = 2e-5, 1e-7
    w = np.array([0.0, 3.0, 4.0])
    sim = _epsd_on_floor("liggghts", w, 0.0, delta, dt)
    kn = 4 / 3 * ESTAR * math.sqrt(R * delta)
    kr = 2.25 * kn * MUR**2 * R**2
    wt = np.array([0.0, 3.0, 0.0]) * (R - delta / 2) / (R - delta)
    for _ in range(2):
        t = sim.compute_forces()[1][0].copy()
        np.testing.assert_allclose(t, -kr * wt * dt, rtol=1e-9, atol=1e-25)
    # a spin far beyond the spring's reach: the limit with the normal damping in the force
    big = np.array([0.0, 1e8, 0.0])
    sim = _epsd_on_floor("liggghts", big, -0.01, delta, dt)
    t = sim.compute_forces()[1][0]
    m = 4 / 3 * math.pi * R**3 * RHO
    fn = hertz(delta, R) + damping(delta, R, m, -0.01)
    np.testing.assert_allclose(t, [0.0, -MUR * R * fn, 0.0], rtol=1e-9, atol=1e-25)
