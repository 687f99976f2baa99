"""Neighbour lists: completeness against brute force, growth of list width, history kept
across rebuilds, settling detection."""

import numpy as np
import pytest

from conftest import table
from soilcal.dem import neighbour as nb
from soilcal.dem.engine import Simulation


def random_box(rng, n=300, L=0.04, periodic=True, skin=None):
    per = (periodic, periodic) if isinstance(periodic, bool) else periodic
    sim = Simulation(table(E=1e8), dt_fraction=0.2, gravity=(0, 0, 0), box=(0, L, 0, L),
                     periodic=per, skin=skin)
    x = rng.uniform(0, L, (n, 3))
    r = rng.uniform(0.5e-3, 2.5e-3, n)
    sim.add_particles(x, r, "soil", v=rng.normal(0, 1e-3, (n, 3)))
    return sim


@pytest.mark.parametrize("periodic", [True, False])
def test_lists_contain_every_pair_within_cutoff(rng, periodic):
    sim = random_box(rng, periodic=periodic)
    sim.run(0)
    L = sim.box[1] - sim.box[0]
    x, r = sim.x, sim.p.r
    d = x[:, None, :] - x[None, :, :]
    if periodic:
        d[..., :2] -= L * np.round(d[..., :2] / L)
    dist = np.sqrt((d**2).sum(-1))
    cut = r[:, None] + r[None, :] + sim.skin + sim.extra
    want = (dist < cut) & ~np.eye(len(r), dtype=bool)
    start, nbr = sim._lists["start_a"], sim._lists["nbr_a"]
    for i in range(len(r)):
        # half list: the partners j > i, sorted
        row = nbr[start[i]:start[i + 1]].tolist()
        assert row == sorted(j for j in np.nonzero(want[i])[0].tolist() if j > i)




def brute_half_rows(x, r, cut0, box, periodic):
    """Partners j > i of every i within r_i + r_j + cut0 (minimum image along the periodic
    axes), ascending: the half lists by the definition, all pairs looked at."""
    rows = []
    for i in range(len(r)):
        d = x[i + 1:] - x[i]
        for a in (0, 1):
            if periodic[a]:
                L = box[2 * a + 1] - box[2 * a]
                d[:, a] -= L * np.round(d[:, a] / L)
        hit = np.einsum("ij,ij->i", d, d) < (r[i] + r[i + 1:] + cut0) ** 2
        rows.append(i + 1 + np.nonzero(hit)[0])
    return rows


@pytest.mark.parametrize("periodic", [(True, True), (False, False), (True, False)])
def test_lists_equal_brute_force_row_by_row_in_order(rng, periodic):
    # 3,000 spheres (several blocks to each block group of the build), a floor and a tilted
    # meshed plate beside them: the CSR rows must be exactly the brute-force rows, in
    # ascending order, at the first build, at a rebuild that merges the old lists, and at
    # a rebuild whose partner work space was too short (the build asks for more, and the
    # lists come out the same)
    from soilcal.dem.geometry import plate_mesh

    L = 0.05
    sim = random_box(rng, n=3000, L=L, periodic=periodic)
    v, t = plate_mesh((L / 2, L / 2, 0.02), (1, 0, 0.2), (0, 1, 0), 0.03, 0.03, n_u=6, n_v=6)
    sim.add_mesh(v, t, "soil")
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    sim._kw = 16

    def check():
        lists = sim._lists
        want = brute_half_rows(sim.p.x, sim.p.r, sim.skin + sim.extra, sim.box, sim.periodic)
        start = lists["start_a"]
        assert np.array_equal(start, np.concatenate([[0], np.cumsum([len(w) for w in want])]))
        assert np.array_equal(lists["nbr_a"][:start[-1]], np.concatenate(want))
        return start[-1]

    sim.run(0)
    assert check() > 2 * sim.n
    sim.p.x[:] = rng.uniform(0, L, (sim.n, 3))
    sim.compute_forces()
    check()
    sim._lists["hits"] = np.zeros(7, np.int32)
    sim.p.x[:] = rng.uniform(0, L, (sim.n, 3))
    sim.compute_forces()
    check()
    assert sim._lists["hits"].shape[0] >= sim._lists["start_a"][-1]


def test_a_periodic_axis_alone_above_the_cap_ends_the_grid_search():
    """Ten spheres in a line along a periodic x of 200 m (1 mm spheres: more cells along x
    than the cap, one cell across y and z): no axis can be halved, and the grid is built at
    once with the periodic cells as they are; the two touching spheres meet with the Hertz
    force 4/3 E* sqrt(R*) delta^(3/2)."""
    E, nu, R, d = 1e8, 0.3, 1e-3, 2e-5
    L = 200.0
    sim = Simulation(table(E=E, nu=nu), dt=1e-6, gravity=(0, 0, 0), box=(0, L, 0, 0.01), periodic=(True, False))
    x = [[1.0 + 20.0 * k, 0.005, 0.0] for k in range(9)] + [[1.0 + 2 * R - d, 0.005, 0.0]]
    sim.add_particles(x, R, "soil")
    f, _ = sim.compute_forces()
    estar = E / (2 * (1 - nu**2))
    rows = sim.index([0, 9])
    hz = 4 / 3 * estar * np.sqrt(R / 2) * d**1.5
    assert np.allclose(f[rows[0]], [-hz, 0, 0], rtol=1e-9) and np.allclose(f[rows[1]], [hz, 0, 0], rtol=1e-9)

def slab_groups(sim, groups, act=None):
    """The slab groups of the pair pass (neighbour._slabs) for the current lists, dealt to
    ``groups`` groups per colour (the engine uses one per thread); act: touching flags of
    the listed pairs (default: the lists' own)."""
    n, L = sim.n, sim._lists
    cidx, cof = np.zeros(n, np.int64), np.zeros(n, np.int64)
    grid = nb._grid(sim.x, sim.p.r, sim.box, sim.periodic, sim.skin, sim.extra,
                    np.zeros(sim._cells.shape[0], np.int64), cidx, cof, np.zeros((n, 4)))
    sorder = np.zeros(n, np.int64)
    sgroup = np.zeros(nb.SGROUP_LEN, np.int64)
    act = L["act_a"] if act is None else act
    nb._slabs(cidx, cof, L["start_a"], act, grid[4], grid[7], grid[10], sim.periodic[0],
              sim.periodic[1], groups, sorder, sgroup, np.zeros(nb.SCRATCH_LEN, np.int64))
    assert sgroup[-1] == groups
    assert sorted(sorder.tolist()) == list(range(n))
    return [[sorder[sgroup[c * groups + g]:sgroup[c * groups + g + 1]] for g in range(groups)]
            for c in range(3)]


@pytest.mark.parametrize("groups", [1, 2, 5])
@pytest.mark.parametrize("periodic", [True, False])
def test_groups_of_one_colour_share_no_particle(rng, periodic, groups):
    # the pair pass adds each pair's force to both particles; the groups of one colour run
    # in parallel, so the particles they write (their own and all their partners) must be
    # disjoint, also across a periodic boundary
    sim = random_box(rng, n=600, periodic=periodic)
    if periodic:
        sim.p.x[:, 2] *= 0.25  # a flat layer: the slabs cut a periodic axis
    sim.run(0)
    start, nbr = sim._lists["start_a"], sim._lists["nbr_a"]
    for colour, grps in enumerate(slab_groups(sim, groups)):
        seen = {}
        for g, rows in enumerate(grps):
            touched = set(rows.tolist())
            for i in rows:
                touched.update(nbr[start[i]:start[i + 1]].tolist())
            for j in touched:
                assert seen.setdefault(j, g) == g, (colour, g, seen[j], j)


def test_groups_balance_a_bed_dense_below_and_sparse_above(rng):
    # a settling bed: 3,000 particles in the bottom 8 mm of a 60 mm periodic box, 200
    # falling ones spread over the 100 mm above.  Slabs across the height would put almost
    # all the work in the bottom slabs (one thread); the groups of each colour must share
    # the work (particles plus listed pairs) between two threads.  About 7 slabs of a
    # colour across the box are dealt whole, so a group may be off its half by half a
    # slab's work: 1 + 1/7 of the mean at most, 1.2 with the scatter of slab work
    side = 0.06
    sim = Simulation(table(E=1e8), dt_fraction=0.2, gravity=(0, 0, 0),
                     box=(0, side, 0, side), periodic=(True, True))
    x = np.concatenate([rng.uniform((0, 0, 0), (side, side, 0.008), (3000, 3)),
                        rng.uniform((0, 0, 0.01), (side, side, 0.11), (200, 3))])
    sim.add_particles(x, rng.uniform(0.8e-3, 1.2e-3, len(x)), "soil")
    sim.run(0)
    start = sim._lists["start_a"]
    for grps in slab_groups(sim, 2):
        work = [int(np.sum(start[rows + 1] - start[rows] + 1)) for rows in grps]
        assert max(work) <= 1.2 * 0.5 * sum(work), work


def test_touching_pairs_weigh_more_when_the_slabs_are_dealt(rng):
    # a layer of uniform particle and pair density whose pairs touch only in the half of
    # the box with x < L/2 (the first layers landing on a floor: contacts in one region).
    # A contact force costs about TOUCH_WEIGHT times a pair's distance check, so each colour
    # must split particles + pairs + TOUCH_WEIGHT x touching pairs evenly (within half a
    # slab's work, 1.2 of the half), which a split by particles and pairs misses
    side = 0.06
    sim = Simulation(table(E=1e8), dt_fraction=0.2, gravity=(0, 0, 0),
                     box=(0, side, 0, side), periodic=(True, True))
    sim.add_particles(rng.uniform((0, 0, 0), (side, side, 0.004), (3000, 3)),
                      rng.uniform(0.8e-3, 1.2e-3, 3000), "soil")
    sim.run(0)
    start, nbr = sim._lists["start_a"], sim._lists["nbr_a"]
    npair = int(start[sim.n])
    act = np.zeros(sim._lists["act_a"].shape[0], np.int8)
    row = np.repeat(np.arange(sim.n), np.diff(start))
    act[:npair] = (sim.x[row, 0] < side / 2) & (sim.x[nbr[:npair], 0] < side / 2)
    assert 0.4 * npair < act.sum() < 0.6 * npair

    def work(rows, weight):
        return sum(int(start[i + 1] - start[i] + 1 + weight * act[start[i]:start[i + 1]].sum())
                   for i in rows)

    for grps in slab_groups(sim, 2, act):
        w = [work(rows, nb.TOUCH_WEIGHT) for rows in grps]
        assert max(w) <= 1.2 * 0.5 * sum(w), w
    # the unweighted split of the same slabs leaves the thread with the contacts at least
    # 1.3 times its share
    worst = max(max(work(rows, nb.TOUCH_WEIGHT) for rows in grps)
                / (0.5 * sum(work(rows, nb.TOUCH_WEIGHT) for rows in grps))
                for grps in slab_groups(sim, 2, np.zeros_like(act)))
    assert worst > 1.3, worst


def test_pair_buffers_grow_without_changing_results():
    # two large spheres (r = 3 mm) embedded in a lattice of small ones (r = 0.5 mm): a large
    # sphere has about 60 partners within its cutoff; starting from a pair buffer of one
    # pair per particle forces the buffers to grow during the run
    def build(k):
        L, h = 0.015, 1.25e-3
        sim = Simulation(table(E=1e8, mu=0.5), dt_fraction=0.2, box=(0, L, 0, L),
                         periodic=(True, True))
        g = np.stack(np.meshgrid(np.arange(12), np.arange(12), np.arange(8), indexing="ij"),
                     -1).reshape(-1, 3)
        x = (g + 0.5) * h
        big = np.array([[0.004, 0.004, 0.005], [0.011, 0.011, 0.005]])
        keep = np.min(np.linalg.norm(x[:, None] - big[None], axis=-1), axis=1) > 3.6e-3
        sim.add_particles(big, 3e-3, "soil")
        sim.add_particles(x[keep], 0.5e-3, "soil")
        sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
        sim._npair_per = k
        return sim

    a, b = build(1), build(200)
    a.run(1500)
    b.run(1500)
    assert a._npair > a.n  # the small buffers had to grow
    assert np.array_equal(a.x, b.x) and np.array_equal(a.omega, b.omega)


def test_tangential_history_survives_rebuilds():
    # a sphere pressed on a fixed one and dragged sideways slowly (sticking): the Mindlin
    # spring must be identical whether the lists are rebuilt every few steps or never
    def build(skin):
        sim = Simulation(table(E=1e8, mu=0.9, e=0.5), dt=1e-6, gravity=(2.0, 0, -9.81),
                         skin=skin)
        r = 2e-3
        sim.add_particles([[0, 0, 0]], r, "soil", fixed=True)
        sim.add_particles([[0, 0, 2 * r - 2e-6]], r, "soil", v=[[1e-3, 0, 0]],
                          lock_rotation=True)
        return sim

    a, b = build(2e-8), build(1e-3)
    for _ in range(10):
        a.run(100)
        b.run(100)
    assert a.n_rebuilds > 5 and b.n_rebuilds == 1
    assert np.allclose(a.p.f, b.p.f, rtol=1e-12, atol=1e-15)
    assert abs(a.p.f[1, 0]) > 0.0


def test_run_until_settled():
    sim = Simulation(table(E=1e8, e=0.3, mu=0.5, mur=0.1), dt_fraction=0.2,
                     contact_model=dict(rolling="constant_torque"))
    sim.add_particles([[0, 0, 0.01], [0.0001, 0.0, 0.016]], 2e-3, "soil")
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    assert sim.run_until_settled(ke_tol=1e-12, check_every=50, max_steps=200_000)
    assert sim.kinetic_energy() < 1e-12
    assert sim.step % 50 == 0 and sim.step < 200_000


@pytest.mark.parametrize("periodic", [True, False])
@pytest.mark.parametrize("lift", [0.0, 0.007])
def test_wall_lists_equal_brute_force_with_binned_triangles(rng, periodic, lift):
    # a finely meshed tilted plate (800 triangles, binned by cell) at two heights, an
    # analytic plane and a cylinder (tested by every particle): the wall list of every
    # particle must hold exactly the primitives within R + skin of its centre.  Periodic in
    # y, along which the tilted plate and the cylinder run (periodic in x they would be
    # refused: a sphere crossing x = L would meet them elsewhere than their continuation)
    from soilcal.dem.geometry import plate_mesh
    from soilcal.dem.walls import prim_closest

    L = 0.04
    sim = random_box(rng, n=400, L=L, periodic=(False, True) if periodic else False)
    sim.p.x[:, 2] *= 0.5
    v, t = plate_mesh((L / 2, L / 2, 0.006 + lift), (1, 0, 0.2), (0, 1, 0), 0.05, 0.05,
                      n_u=20, n_v=20)
    sim.add_mesh(v, t, "soil")
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    sim.add_cylinder((L / 2, L / 2, 0), (0, 1, 0), 0.03, 0.05, "soil")
    sim._kw = 32
    sim.run(0)
    wa, lists = sim._warr, sim._lists
    assert wa["prim_kind"].shape[0] == 802
    total = 0
    for i in range(sim.n):
        want = set()
        for p in range(wa["prim_kind"].shape[0]):
            d = prim_closest(wa["prim_kind"][p], wa["prim_par"], p, *sim.x[i])[0]
            if d < sim.p.r[i] + sim.skin + sim.extra:
                want.add(p)
        got = set(lists["wnbr_a"][: lists["wcnt_a"][i], i].tolist())
        assert got == want
        total += sum(1 for p in want if p < 800)
    assert total > 50  # the plate is near many particles


def test_moving_mesh_renews_wall_lists_alone_and_misses_no_contact():
    # a finely meshed floor sweeps sideways and tilts under a resting layer of spheres: the
    # wall lists are renewed on their own (the particles hardly move) and at every check
    # every triangle a sphere overlaps is in that sphere's wall list
    from soilcal.dem.geometry import plate_mesh
    from soilcal.dem.walls import prim_closest

    r = 1e-3
    sim = Simulation(table(E=1e7, mu=0.5, e=0.3), dt_fraction=0.2)
    g = np.stack(np.meshgrid(np.arange(8), np.arange(8), indexing="ij"), -1).reshape(-1, 2)
    x = np.c_[(g + 0.5) * 2.2 * r - 8.8 * r, np.full(len(g), 0.999 * r)]
    sim.add_particles(x, r, "soil")
    v, t = plate_mesh((0, 0, 0), (1, 0, 0), (0, 1, 0), 0.06, 0.06, n_u=24, n_v=24)
    sim.add_mesh(v, t, "soil", velocity=(0.02, 0.0, 0.0), omega=(0.0, 0.3, 0.0),
                 centre=(0, 0, 0))
    for _ in range(10):
        sim.run(400)
        wa, lists = sim._warr, sim._lists
        for i in range(sim.n):
            got = set(lists["wnbr_a"][: lists["wcnt_a"][i], i].tolist())
            for p in range(wa["prim_kind"].shape[0]):
                if prim_closest(wa["prim_kind"][p], wa["prim_par"], p, *sim.x[i])[0] < r:
                    assert p in got
    assert sim.n_wall_rebuilds > 0
    assert sim.wall_force[0, 2] < 0.0  # the spheres press on the floor


def test_spheres_far_from_the_rest_keep_the_grid_small_and_their_contacts(rng):
    """Spheres that left the others far behind (thrown off, falling past the floor's edge)
    would stretch the cell grid over their bounding box (here 40 m x 60 m x 30 m of 5.5 mm
    cells, 10^13 cells): the grid stays within its cap, the lists still hold every pair
    within the cutoff, and the far spheres still meet each other and a far triangle with the
    Hertz force 4/3 E* sqrt(R*) delta^(3/2)."""
    E, nu, R = 1e8, 0.3, 1e-3
    sim = Simulation(table(E=E, nu=nu), dt=1e-6, gravity=(0, 0, 0))
    x = rng.uniform(0, 0.03, (400, 3))
    sim.add_particles(x, rng.uniform(0.5e-3, 2.5e-3, 400), "soil")
    d_pair, d_wall = 2e-5, 3e-5
    far = np.array([40.0, 60.0, -30.0])
    sim.add_particles([far, far + [2 * R - d_pair, 0, 0]], R, "soil")
    low = far + [0.0, 0.1, 0.0]
    sim.add_particles([low], R, "soil")
    z = low[2] - R + d_wall
    sim.add_mesh([[low[0] - 0.01, low[1] - 0.01, z], [low[0] + 0.01, low[1] - 0.01, z],
                  [low[0], low[1] + 0.01, z]], [[0, 1, 2]], "soil", name="far")
    f, _ = sim.compute_forces()
    assert sim._cells.shape[0] <= 2 * (nb.cell_cap(sim.n) + 1)
    estar = E / (2 * (1 - nu**2))
    rows = sim.index([400, 401, 402])
    hertz = lambda rs, e, d: 4 / 3 * e * np.sqrt(rs) * d**1.5  # noqa: E731
    assert np.allclose(f[rows[0]], [-hertz(R / 2, estar, d_pair), 0, 0], rtol=1e-9)
    assert np.allclose(f[rows[1]], [hertz(R / 2, estar, d_pair), 0, 0], rtol=1e-9)
    assert np.allclose(f[rows[2]], [0, 0, hertz(R, estar, d_wall)], rtol=1e-9)
    assert np.allclose(sim.wall_force[0], [0, 0, -hertz(R, estar, d_wall)], rtol=1e-9)
    # every pair within the cutoff is listed
    xs, r = sim.x, sim.p.r
    dist = np.linalg.norm(xs[:, None] - xs[None], axis=2)
    want = (dist < r[:, None] + r[None] + sim.skin + sim.extra) & ~np.eye(sim.n, dtype=bool)
    start, nbr = sim._lists["start_a"], sim._lists["nbr_a"]
    for i in range(sim.n):
        assert nbr[start[i]:start[i + 1]].tolist() == [j for j in np.nonzero(want[i])[0]
                                                       if j > i]


def test_a_triangle_is_skipped_only_where_its_plane_is_beyond_reach(rng):
    """The wall-list build skips a binned triangle whose plane lies beyond a sphere's reach
    (a point's distance from a triangle is at least that from its plane).  Drawn cases: the
    unit right triangle in z = 0, a point 0.3 above it (over the face: distance 0.3; beside
    it at (5, 5): distance sqrt(4.5^2 + 4.5^2 + 0.3^2)); then random triangles (slivers
    among them) and points, where a skipped triangle must be one the exact closest point
    puts at the reach or beyond."""
    from soilcal.dem.walls import TRIANGLE, prim_closest

    par = np.zeros((1, 16))
    par[0, :9] = [0, 0, 0, 1, 0, 0, 0, 1, 0]
    # over the face: skipped for a reach below 0.3, kept at 0.3 and above
    assert nb.tri_beyond(par, 0, 0.2, 0.2, 0.3, 0.29)
    assert not nb.tri_beyond(par, 0, 0.2, 0.2, 0.3, 0.3)
    assert not nb.tri_beyond(par, 0, 0.2, 0.2, -0.3, 0.31)
    # beside it the plane is still 0.3 away: the bound is the plane's, never more
    assert not nb.tri_beyond(par, 0, 5.0, 5.0, 0.3, 0.31)
    assert nb.tri_beyond(par, 0, 5.0, 5.0, 0.3, 0.29)
    # a sliver (widest angle's sine 1e-6) is never skipped
    par[0, :9] = [0, 0, 0, 1, 0, 0, 0.5, 1e-6, 0]
    assert not nb.tri_beyond(par, 0, 0.5, 0.0, 5.0, 1.0)
    n = 4000
    tri = rng.normal(size=(n, 9))
    tri[::4, 6:9] = tri[::4, 0:3] + (tri[::4, 3:6] - tri[::4, 0:3]) * 0.4 + 1e-5 * rng.normal(
        size=(n // 4, 3))  # slivers
    pts = rng.normal(size=(n, 3)) * 2.0
    skipped = 0
    for k in range(n):
        par = np.zeros((1, 16))
        par[0, :9] = tri[k]
        d = prim_closest(TRIANGLE, par, 0, *pts[k])[0]
        for lim in (0.5 * d, d * (1 - 1e-12), d, 1.5 * d):
            if nb.tri_beyond(par, 0, *pts[k], lim):
                skipped += 1
                assert d >= lim, (k, d, lim)
    assert skipped > n // 4  # the bound does skip (not only in the drawn cases above)


def test_a_triangle_far_from_the_origin_is_not_skipped_within_a_tiny_reach(rng):
    """The closest point of a triangle is formed at the size of its coordinates, so its
    rounding grows with the distance from the origin, not with the triangle's size: a
    millimetre triangle 100 m or 1 km away, a point microns above its plane just beside
    an edge, and a reach one unit in the last place beyond the exact closest-point
    distance must keep the triangle (the plane is nearer than the reach by construction:
    the point's distance from the triangle is at least that from its plane)."""
    from soilcal.dem.walls import TRIANGLE, prim_closest

    # a drawn case 100 m out: plane 1e-6 away, closest-point distance rounds a hair below
    par = np.zeros((1, 16))
    par[0, :9] = [99.99984669507923, 99.9999707860961, 99.99994196837494,
                  99.99977241021428, 99.99998642453347, 99.9999571533272,
                  99.99988479516935, 99.99994296689896, 99.99985635317093]
    p = (99.99984473459759, 99.99997020895451, 99.9999425817665)
    d = prim_closest(TRIANGLE, par, 0, *p)[0]
    assert not nb.tri_beyond(par, 0, *p, np.nextafter(d, np.inf))
    for origin, size, height in ((100.0, 1e-4, 1e-6), (100.0, 1e-3, 1e-6),
                                 (1e3, 1e-3, 1e-5), (1e3, 1e-3, 1e-6)):
        for _ in range(400):
            v0 = origin + rng.normal(size=3) * size
            par[0, 0:3] = v0
            par[0, 3:6] = v0 + rng.normal(size=3) * size
            par[0, 6:9] = v0 + rng.normal(size=3) * size
            a, b, c = par[0, 0:3], par[0, 3:6], par[0, 6:9]
            n = np.cross(b - a, c - a)
            n /= np.linalg.norm(n)
            out = np.cross(b - a, n)
            out /= np.linalg.norm(out)
            if out @ (c - a) > 0:
                out = -out
            for beside in (0.0, 1e-10):  # on edge a-b, or just outside it
                p = a + rng.uniform() * (b - a) + out * beside * size + n * height
                d = prim_closest(TRIANGLE, par, 0, *p)[0]
                for lim in (np.nextafter(d, np.inf), d * (1 + 1e-13)):
                    assert not nb.tri_beyond(par, 0, *p, lim), (origin, size, d, lim)
                assert nb.tri_beyond(par, 0, *p, 0.5 * d)  # the bound still skips


def _periodic_pair(k, gap, v0=0.1, R=2e-3, L=0.02, e=0.7):
    """Sphere B given k periods of the x axis away from the image of A it meets."""
    sim = Simulation(table(e=e, mu=0.0, E=1e8), dt=1e-6, gravity=(0, 0, 0), box=(0, L, 0, L),
                     periodic=(True, True), contact_model=dict(tangential="none"))
    sim.add_particles([[0.005, 0.01, 0.01]], R, "soil")
    sim.add_particles([[0.005 + 2 * R + gap + k * L, 0.01 - 3 * L, 0.01]], R, "soil",
                      v=[[-v0, 0, 0]])
    return sim


@pytest.mark.parametrize("k", [0, 3, -4, 2000])
def test_a_sphere_given_periods_outside_a_periodic_box_meets_its_partner(k):
    # positions are periodic: the head-on impact rebounds at the configured restitution
    # (0.7) wherever the sphere was given, and both spheres end inside the box
    sim = _periodic_pair(k, gap=1e-5)
    sim.run(3000)
    ia, ib = sim.index([0, 1])
    assert (sim.v[ib, 0] - sim.v[ia, 0]) / 0.1 == pytest.approx(0.7, rel=0.01)
    assert np.all((sim.x[:, :2] >= 0) & (sim.x[:, :2] < 0.02))


@pytest.mark.parametrize("k", [3, -4])
def test_a_sphere_given_into_another_periods_away_is_refused(k):
    # half a radius into A's image, k periods away: refused before any step as a sphere
    # placed into another is (the same pair inside the box is, engine.run)
    from soilcal.errors import InputError

    sim = _periodic_pair(k, gap=-1e-3)
    with pytest.raises(InputError):
        sim.run(1)
