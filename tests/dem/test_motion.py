"""Incline stick/slip, rolling deceleration and rest (constant torque, EPSD, bounded), energy
and momentum, wall vs large sphere, thread independence."""

import math

import numba
import numpy as np
import pytest

from conftest import table
from soilcal.dem.bench import settle_simulation
from soilcal.dem.engine import Simulation

G = 9.81
R = 5e-3


def incline(theta_deg, mu=0.5, steps=20000):
    th = math.radians(theta_deg)
    sim = Simulation(table(e=0.3, mu=mu, E=1e8), dt_fraction=0.2,
                     gravity=(G * math.sin(th), 0.0, -G * math.cos(th)))
    sim.add_particles([[0, 0, R * 0.9999]], R, "soil", lock_rotation=True)
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    sim.run(2000)  # normal contact settles
    x0, t0 = sim.x[0, 0], sim.step * sim.dt
    v0 = sim.v[0, 0]
    sim.run(steps)
    t = sim.step * sim.dt - t0
    return sim.x[0, 0] - x0, sim.v[0, 0], v0, t


def test_block_sticks_and_slides_at_friction_angle():
    mu = 0.5
    crit = math.degrees(math.atan(mu))
    # 0.5 deg below tan(theta) = mu: sticks (creep below 1 % of the radius)
    dx, v, _, _ = incline(crit - 0.5, mu)
    assert abs(dx) < 0.01 * R and abs(v) < 1e-4
    # 0.5 deg above: slides with a = g (sin theta - mu cos theta)
    th = math.radians(crit + 0.5)
    dx, v, v0, t = incline(crit + 0.5, mu)
    a_expected = G * (math.sin(th) - mu * math.cos(th))
    assert (v - v0) / t == pytest.approx(a_expected, rel=0.02)


@pytest.mark.parametrize("model", ["constant_torque", "epsd", "bounded"])
def test_rolling_deceleration(model):
    # EPSD: once the rolling spring is fully mobilised its moment is mu_r R* F_n with
    # R* = R for a sphere on a plane, the same torque as the constant-torque model
    mur, v0 = 0.1, 0.2
    sim = Simulation(table(e=0.5, mu=0.5, mur=mur, E=1e8), dt_fraction=0.2,
                     contact_model=dict(rolling=model))
    # rolling without slip: v = omega_y R
    sim.add_particles([[0, 0, R * 0.99993]], R, "soil", v=[[v0, 0, 0]], omega=[[0, v0 / R, 0]])
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    sim.run(500)
    ts, vs = [], []
    for _ in range(40):
        sim.run(200)
        ts.append(sim.step * sim.dt)
        vs.append(sim.v[0, 0])
    slope = np.polyfit(ts, vs, 1)[0]
    # torque mu_r m g R against rolling: m a = F_t, I alpha = -F_t R - mu_r m g R, a = alpha R
    # -> a = -mu_r g / (1 + I/(m R^2)) = -5/7 mu_r g for a solid sphere
    assert vs[-1] > 0.02
    assert slope == pytest.approx(-5.0 / 7.0 * mur * G, rel=0.02)


def rolling_on_incline(model, theta_deg, mur=0.1, steps=20000):
    """A free sphere (rotation not locked) released at rest on a plane tilted by theta;
    returns (displacement down the slope, final velocity, velocity after the first 2000
    steps, angular velocity magnitudes of the last 200 steps, time since those 2000 steps,
    the simulation)."""
    th = math.radians(theta_deg)
    sim = Simulation(table(e=0.3, mu=0.9, mur=mur, E=1e8), dt_fraction=0.2,
                     gravity=(G * math.sin(th), 0.0, -G * math.cos(th)),
                     contact_model=dict(rolling=model))
    sim.add_particles([[0, 0, R * 0.9999]], R, "soil")
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    sim.run(2000)
    x0, t0, v0 = sim.x[0, 0], sim.step * sim.dt, sim.v[0, 0]
    sim.run(steps - 200)
    w = []
    for _ in range(200):
        sim.run(1)
        w.append(float(np.linalg.norm(sim.omega[0])))
    return sim.x[0, 0] - x0, sim.v[0, 0], v0, np.array(w), sim.step * sim.dt - t0, sim


def test_bounded_rolling_holds_a_sphere_below_the_rolling_angle():
    # A sphere on an incline rolls when the weight's moment about the contact point exceeds
    # the rolling resistance, m g sin(theta) R > mu_r m g cos(theta) R: tan(theta) > mu_r.
    mur = 0.1
    crit = math.degrees(math.atan(mur))
    # 0.5 deg below: at rest, the angular velocity exactly zero (the bound stops it)
    dx, v, _, w, _, sim = rolling_on_incline("bounded", crit - 0.5, mur)
    assert abs(dx) < 1e-4 * R and abs(v) < 1e-7
    assert w.max() < 1e-12
    # the plane takes the whole reaction of its one contact, the rolling torque included:
    # torque about its centre (the origin) -(x - c) x F - T with F, T on the sphere
    F = -sim.wall_force[0]
    expected = -np.cross(sim.x[0], F) - sim.p.t[0]
    assert np.allclose(sim.wall_torque[0], expected, rtol=1e-9, atol=1e-15)
    # 0.5 deg above: rolls without slip, a = 5/7 g (sin theta - mu_r cos theta)
    th = math.radians(crit + 0.5)
    dx, v, v0, _, t, _ = rolling_on_incline("bounded", crit + 0.5, mur)
    assert (v - v0) / t == pytest.approx(5.0 / 7.0 * G * (math.sin(th) - mur * math.cos(th)),
                                         rel=0.02)


def test_constant_torque_keeps_flipping_below_the_rolling_angle():
    # the same sphere with the unbounded constant torque: the torque flips with the sign of a
    # vanishing angular velocity, which therefore never settles.  One step of the full torque
    # mu_r m g cos(theta) R changes omega by 2.5 mu_r g cos(theta) dt / R (I = 0.4 m R^2);
    # the jitter reaches at least a quarter of that
    mur = 0.1
    th = math.atan(mur) - math.radians(0.5)
    _, _, _, w, _, sim = rolling_on_incline("constant_torque", math.degrees(th), mur)
    assert w.max() > 0.25 * 2.5 * mur * G * math.cos(th) * sim.dt / R


def hertz_energy(sim, estar):
    x, r = sim.x, sim.p.r
    L = sim.box[1] - sim.box[0]
    d = x[:, None, :] - x[None, :, :]
    d -= L * np.round(d / L) * np.array([1, 1, 1])
    dist = np.sqrt((d**2).sum(-1))
    rs = r[:, None] + r[None, :]
    delta = np.triu(np.clip(rs - dist, 0, None), 1)
    rstar = r[:, None] * r[None, :] / rs
    return float((8.0 / 15.0 * estar * np.sqrt(rstar) * delta**2.5).sum())


def test_energy_and_momentum_conserved(rng):
    E, nu = 1e9, 0.3
    estar = E / (2 * (1 - nu**2))
    L = 0.05
    n = 60
    sim = Simulation(table(e=1.0, mu=0.0, E=E, nu=nu), dt_fraction=0.1, gravity=(0, 0, 0),
                     box=(0, L, 0, L), periodic=(True, True))
    # x, y periodic; z confined by two frictionless elastic planes
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    sim.add_plane((0, 0, L), (0, 0, -1), "soil")
    g = np.stack(np.meshgrid(*(np.arange(4),) * 3, indexing="ij"), -1).reshape(-1, 3)[:n]
    x = (g + 0.5) * (L / 4)
    r = rng.uniform(3e-3, 4e-3, len(x))
    v = rng.normal(0, 0.3, (len(x), 3))
    sim.add_particles(x, r, "soil", v=v)
    m = sim.p.m  # the engine re-sorts the rows in place (this array too): v[sim.p.id] below

    def energy():
        # sphere-plane: same material pair, R* = r
        ez = sum(8.0 / 15.0 * estar * np.sqrt(ri) * max(0.0, ri - min(zi, L - zi)) ** 2.5
                 for ri, zi in zip(sim.p.r, sim.x[:, 2]))
        return sim.kinetic_energy() + sim.rotational_energy() + hertz_energy(sim, estar) + ez

    e0 = energy()
    p0 = (m[:, None] * sim.v).sum(0)[:2]
    sim.run(100_000)
    assert np.abs(sim.v - v[sim.p.id]).max() > 0.1  # collisions happened
    assert energy() == pytest.approx(e0, rel=0.01)
    p1 = (m[:, None] * sim.v).sum(0)[:2]
    scale = float((m[:, None] * np.abs(v[sim.p.id])).sum())
    assert np.abs(p1 - p0).max() < 1e-12 * scale


def test_plane_equals_infinitely_large_sphere():
    def build(wall):
        sim = Simulation(table(e=0.4, mu=0.4, mur=0.05, E=1e8), dt=1e-6, gravity=(0, 0, -G),
                         contact_model=dict(rolling="constant_torque"))
        sim.add_particles([[0, 0, R * 0.999]], R, "soil", v=[[0.05, 0.02, -0.1]],
                          omega=[[1.0, -3.0, 2.0]])
        if wall:
            sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
        else:
            big = 1e3
            sim.add_particles([[0, 0, -big]], big, "soil", fixed=True)
        return sim

    a, b = build(True), build(False)
    for _ in range(5):
        a.run(20)
        b.run(20)
        fa, fb = a.p.f[0], b.p.f[0]
        assert np.allclose(fa, fb, rtol=1e-4, atol=1e-6 * np.abs(fa).max())
        assert np.allclose(a.p.t[0], b.p.t[0], rtol=1e-4, atol=1e-6 * np.abs(a.p.t[0]).max())
        # the wall carries the reaction (gravity removed)
        grav = a.p.m[0] * np.array([0, 0, -G])
        assert np.allclose(a.wall_force[0], -(fa - grav), rtol=1e-12, atol=1e-15)


def test_lists_regrouped_when_more_threads_run(monkeypatch):
    # the pair pass runs one slab group per thread and colour; lists grouped for one
    # thread are regrouped as soon as a run has two, not at the next natural rebuild
    from soilcal.dem import integrator

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs two threads")
    monkeypatch.setattr(integrator, "PARALLEL_MIN", 0)
    sim = settle_simulation(3, "none", layers=4)
    try:
        numba.set_num_threads(1)
        sim.run(5)
        assert sim._lists["sgroup"][-1] == 1
        numba.set_num_threads(2)
        sim.run(1)
        assert sim._lists["sgroup"][-1] == 2
    finally:
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)


@pytest.mark.parametrize("rolling", ["constant_torque", "bounded"])
def test_one_and_two_threads_identical(monkeypatch, rolling):
    from soilcal.dem import integrator

    monkeypatch.setattr(integrator, "PARALLEL_MIN", 0)  # small system, parallel loops anyway
    out = []
    for nt in (1, 2):
        numba.set_num_threads(nt)
        sim = settle_simulation(3, "jkr", seed=7, layers=12, rolling=rolling)
        sim.run(1500)
        out.append((sim.x.copy(), sim.v.copy(), sim.omega.copy(), sim.wall_force.copy()))
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    for a, b in zip(*out):
        assert np.array_equal(a, b)
