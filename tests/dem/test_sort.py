"""Spatial sort of the particle rows (LAMMPS ``atom_modify sort``): the rows move, the
physics does not.

The invariants: a particle's trajectory, looked up by insertion id, is the same whether or
not the engine re-sorts the rows (a single contact has nothing to re-order in its force sum,
so two-body runs agree to round-off); contact histories follow their pairs, with the sign of
the antisymmetric parts reversed when the sort reverses a pair; a build that has to stop for
larger buffers after a sort restores the old rows exactly.
"""

import math

import numpy as np
import pytest

from conftest import table
from soilcal.dem.engine import Simulation
from soilcal.errors import InputError

R = 2e-3


def sphere_on_sphere(rolling="constant_torque", cohesion="none", normal="hertz"):
    """A free sphere (insertion id 0) launched across the top of a fixed one (id 1) below
    it, with a skin so small that the lists are rebuilt every few steps while they touch.
    A fixed spectator far below (id 2) anchors the cell grid so that a cell boundary lies
    between the two: the sort puts the lower sphere's row first."""
    mats = table(e=0.5, mu=0.5, mur=0.1, gamma=0.2 if cohesion == "jkr" else 0.0, E=1e7,
                 plasticity=0.5 if normal == "eepa" else 0.0)
    sim = Simulation(mats, dt_fraction=0.2, gravity=(0, 0, -9.81), skin=2e-6, sort_every=0,
                     contact_model=dict(normal=normal, rolling=rolling, cohesion=cohesion))
    sim.add_particles([[0.0, 0.0, 2 * R - 1e-6]], R, "soil", v=[[0.03, 0.0, 0.0]])
    sim.add_particles([[0.0, 0.0, 0.0]], R, "soil", fixed=True)
    cell = 2 * R + 2e-6  # cell edge 2 R_max + skin (+ the JKR range, far below R here)
    sim.add_particles([[0.0, 0.0, -2.5 * cell]], R, "soil", fixed=True)
    return sim


@pytest.mark.parametrize("rolling,cohesion,normal", [
    ("constant_torque", "none", "hertz"), ("epsd", "none", "hertz"),
    ("constant_torque", "jkr", "hertz"), ("constant_torque", "none", "eepa")])
def test_history_follows_a_pair_whose_rows_are_swapped(rolling, cohesion, normal):
    # sorting is switched on (every build) once the spheres touch, so that the first sort
    # finds a contact history to carry over
    runs = {}
    for every in (0, 1):
        sim = sphere_on_sphere(rolling, cohesion, normal)
        xs, fx = [], []
        for chunk in range(40):
            if chunk == 4:
                sim.sort_every = every
            sim.run(50)
            k = sim.index([0, 1, 2])
            xs.append(sim.x[k].copy())
            fx.append(sim.p.f[k[1]].copy())  # contact force on the fixed sphere
        runs[every] = (np.array(xs), np.array(fx), sim)
    x0, f0, s0 = runs[0]
    x1, f1, s1 = runs[1]
    # the sort put the lower sphere first: the pair's orientation was reversed
    assert list(s1.p.id) == [2, 1, 0] and list(s0.p.id) == [0, 1, 2]
    assert s1.n_rebuilds > 50  # sorted at every one of these builds
    # the spheres touched with a horizontal force of the order of the weight's share
    assert np.abs(f0[:, 0]).max() > 0.05 * np.abs(f0[:, 2]).max()
    assert np.allclose(x1, x0, rtol=0, atol=1e-12)
    assert np.allclose(f1, f0, rtol=1e-9, atol=1e-12 * np.abs(f0).max())


def random_box(seed=3, n=400, sort_every=1000):
    rng = np.random.default_rng(seed)
    sim = Simulation(table(e=0.4, mu=0.5, mur=0.1, gamma=0.1, E=1e7), dt_fraction=0.2,
                     box=(0.0, 0.03, 0.0, 0.03), periodic=(True, True), sort_every=sort_every,
                     max_overlap=0.2,
                     contact_model=dict(rolling="constant_torque", cohesion="jkr"))
    x = np.column_stack([rng.uniform(0, 0.03, n), rng.uniform(0, 0.03, n),
                         rng.uniform(0.002, 0.06, n)])
    r = rng.uniform(0.8 * R, R, n)
    keep = [0]
    for i in range(1, n):  # no initial overlaps
        dd = x[keep] - x[i]
        dd[:, :2] -= 0.03 * np.round(dd[:, :2] / 0.03)  # periodic images
        d = np.linalg.norm(dd, axis=1)
        if (d > r[keep] + r[i]).all():
            keep.append(i)
    sim.add_particles(x[keep], r[keep], "soil")
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    return sim


def test_rows_in_cell_order_after_the_first_build():
    sim = random_box()
    z_before = sim.x[:, 2].copy()
    assert not np.all(np.diff(z_before) >= 0)  # inserted in random order
    sim.run(0)
    cell = 2 * sim.p.r.max() + sim.skin + sim.extra
    layer = np.floor((sim.x[:, 2] - sim.x[:, 2].min()) / cell)
    assert np.all(np.diff(layer) >= 0)  # z-major cell order
    assert sorted(sim.p.id) == list(range(sim.n))
    assert np.array_equal(sim.x[:, 2], z_before[sim.p.id])


def test_retry_after_a_short_buffer_restores_the_rows():
    # a falling bed with contacts (and their history); then a sort is made due and, in one
    # of two identical runs, the pair buffers are cut to the pairs listed now: the sorted
    # build lists more and stops for room, the rows go back to the lists' order, and the
    # retry sorts again.  The two runs must be the same
    out = []
    for cut in (True, False):
        sim = random_box()
        sim.run(1500)
        sim._fstate[3] = math.inf
        npair = sim._npair
        if cut:
            npair = int(sim._lists["start_a"][-1])
            sim._alloc_lists(sim.n, npair, sim._kw, sim._lists)
        while math.isinf(sim._fstate[3]):  # step by step up to the sorted build
            sim.run(1)
        if cut:
            assert sim._npair > npair  # that build stopped for room, then sorted again
        sim.run(1500)
        k = sim.index(np.arange(sim.n))
        out.append((sim.x[k].copy(), sim.v[k].copy(), sim.omega[k].copy()))
    for a, b in zip(*out):
        assert np.array_equal(a, b)


def test_sorted_and_unsorted_settle_to_the_same_bed():
    # many-body runs add contributions in another order once sorted: trajectories part at
    # round-off and then chaotically, but the bed is the same granular state
    beds = []
    for every in (0, 200):
        sim = random_box(seed=5, sort_every=every)
        sim.run(20000)
        beds.append(((sim.x[:, 2] + sim.p.r).max(), sim.kinetic_energy(), sim.n))
    (h0, e0, n0), (h1, e1, n1) = beds
    assert n0 == n1
    assert abs(h1 - h0) < 2 * R
    assert max(e0, e1) < 1e-6


def test_index_maps_ids_to_rows_and_rejects_unknown_ids():
    sim = random_box(n=60)
    sim.run(0)
    rows = sim.index(np.arange(sim.n))
    assert np.array_equal(sim.p.id[rows], np.arange(sim.n))
    with pytest.raises(InputError, match=r"ids: expected insertion ids in \[0, "):
        sim.index([sim.n])
    with pytest.raises(InputError, match="sort_every: expected a whole number of steps"):
        Simulation(table(), sort_every=-1)
    with pytest.raises(InputError, match="sort_every"):
        Simulation(table(), sort_every=2.5)
    assert math.isfinite(sim.x.sum())


def test_bytes_per_particle_matches_the_engine_allocation():
    # BYTES_PER_PARTICLE (state.py, the memory guard) is counted by hand from the engine's
    # arrays: it must equal the per-particle arrays a fresh simulation really holds (pair
    # lists at their initial 8 slots, 4 wall slots, tangential + JKR history)
    from soilcal.dem.state import BYTES_PER_PARTICLE

    sim = random_box(n=200)
    sim.run(0)
    n = sim.n
    assert sim._npair == 8 * n and sim._kw == 4
    per = [a for a in vars(sim.p).values() if isinstance(a, np.ndarray)]
    # (the wall lists are slot-major: wnbr (4, n), wslot (4, n, 6), whist 4 n rows)
    per += [a for a in sim._lists.values()
            if a.shape[0] in (n, n + 1, 8 * n, 4 * n) or a.shape[:2] == (4, n)]
    per += [sim._cidx_arr, sim._cof_arr, sim._cpos_arr]
    total = sum(a.nbytes for a in per) - 2 * 8  # the two row-offset arrays hold n + 1
    assert total == n * BYTES_PER_PARTICLE
