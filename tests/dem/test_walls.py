"""Wall kinds wired into the force loop: equal forces for equivalent geometries, moving walls."""

import math
import re

import numpy as np
import pytest

from conftest import table
from soilcal.dem.engine import Simulation
from soilcal.errors import InputError

R = 5e-3
G = 9.81


def resting(add_wall, steps=6000):
    sim = Simulation(table(e=0.3, mu=0.5, E=1e8), dt_fraction=0.2)
    sim.add_particles([[0.0, 0.0, R]], R, "soil")
    add_wall(sim)
    sim.run(steps)
    return sim


@pytest.mark.parametrize("kind", ["mesh_edge", "mesh_vertex", "drum", "rectangle", "disk",
                                  "disk_back", "drum_outside"])
def test_sphere_rests_with_weight_on_each_wall_kind(kind):
    def add(sim):
        if kind == "mesh_edge":  # two triangles, sphere above the shared diagonal
            v = [[-0.1, -0.1, 0], [0.1, -0.1, 0], [0.1, 0.1, 0], [-0.1, 0.1, 0]]
            sim.add_mesh(v, [[0, 1, 2], [0, 2, 3]], "soil")
        elif kind == "mesh_vertex":  # fan of 6 triangles around the vertex under the sphere
            ang = np.linspace(0, 2 * math.pi, 7)[:-1]
            v = [[0, 0, 0]] + [[0.1 * math.cos(a), 0.1 * math.sin(a), 0] for a in ang]
            sim.add_mesh(v, [[0, 1 + k, 1 + (k + 1) % 6] for k in range(6)], "soil")
        elif kind == "drum":  # horizontal inner cylinder, sphere at its bottom
            sim.add_cylinder((0, 0, 0.05), (1, 0, 0), 0.05, 0.1, "soil", inner=True)
        elif kind == "disk_back":  # disk facing down: the sphere rests on its back side
            sim.add_disk((0, 0, 0), (0, 0, -1), 0.05, "soil")
        elif kind == "drum_outside":  # sphere on top of a drum shell, outside it
            sim.add_cylinder((0, 0, -0.05), (1, 0, 0), 0.05, 0.1, "soil", inner=True)
        elif kind == "rectangle":
            sim.add_rectangle((0, 0, 0), (0, 0, 1), (1, 0, 0), 0.05, 0.05, "soil")
        else:
            sim.add_disk((0, 0, 0), (0, 0, 1), 0.05, "soil")

    sim = resting(add)
    weight = sim.p.m[0] * G
    assert sim.wall_force[0] == pytest.approx([0, 0, -weight], abs=1e-3 * weight)
    assert abs(sim.v[0]).max() < 1e-4


def test_mesh_face_equals_plane():
    def plane(sim):
        sim.add_plane((0, 0, 0), (0, 0, 1), "soil")

    def mesh(sim):
        sim.add_box((-0.1, -0.1, -0.1), (0.1, 0.1, 0.0), "soil")

    for x0 in ([0.01, 0.02], [0.0, 0.0]):  # inside a face / on a box-face diagonal
        a = Simulation(table(e=0.5, mu=0.4, E=1e8), dt=1e-6)
        b = Simulation(table(e=0.5, mu=0.4, E=1e8), dt=1e-6)
        for sim, add in ((a, plane), (b, mesh)):
            sim.add_particles([[x0[0], x0[1], R * 0.999]], R, "soil", v=[[0.02, 0.01, -0.05]],
                              omega=[[2.0, 1.0, 0.0]])
            add(sim)
            sim.run(300)
        assert np.allclose(a.p.f, b.p.f, rtol=1e-9, atol=1e-12)
        assert np.allclose(a.x, b.x, rtol=1e-12, atol=1e-15)


def _grid(L=0.02, n=4):
    """A flat square mesh z = 0 of n x n cells, each cut along its diagonal."""
    xs = np.linspace(-L, L, n + 1)
    v = [[x, y, 0.0] for y in xs for x in xs]
    t = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            t += [[a, a + 1, a + n + 2], [a, a + n + 2, a + n + 1]]
    return v, t


def _hertz_wall_force(mats, r, delta):
    """Hertz force of a sphere pressed delta into a flat wall of its own material."""
    m = mats.materials[0]
    estar = m.youngs / (2 * (1 - m.poisson**2))
    return 4 / 3 * estar * math.sqrt(r) * delta**1.5


@pytest.mark.parametrize("xy", [(0.0, 1e-9), (1e-9, 0.0), (0.0, 0.0), (0.005, 0.0),
                                (0.003, 0.001)])
def test_a_sphere_over_a_mesh_vertex_or_edge_is_one_contact(xy):
    """A sphere 1e-9 m beside a vertex of a flat mesh touched it through three triangles (a
    vertex, an edge and the diagonal edge each counted), pushed with three times the Hertz
    force of the plane."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    sim = Simulation(mats, gravity=(0, 0, 0))
    v, t = _grid()
    sim.add_mesh(v, t, "soil")
    delta = 0.01 * R
    sim.add_particles([[xy[0], xy[1], R - delta]], R, "soil")
    f, _ = sim.compute_forces()
    assert f[0] == pytest.approx([0, 0, _hertz_wall_force(mats, R, delta)], rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("y", [-0.0099, -0.005, 0.0, 0.0099])
def test_a_sphere_on_a_convex_box_edge_is_one_contact(y):
    """Beside a box's edge, near its end, the triangles that meet the edge only at its end
    vertex added vertex contacts: 1.97 times the Hertz force of the edge at y = +-0.0099."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    sim = Simulation(mats, gravity=(0, 0, 0))
    sim.add_box((-0.01, -0.01, -0.01), (0.01, 0.01, 0.0), "soil")
    delta = 0.01 * R
    d = (R - delta) / math.sqrt(2)  # centre at 45 deg beyond the edge x = 0.01, z = 0
    sim.add_particles([[0.01 + d, y, d]], R, "soil")
    f, _ = sim.compute_forces()
    fn = _hertz_wall_force(mats, R, delta)
    assert f[0] == pytest.approx([fn / math.sqrt(2), 0, fn / math.sqrt(2)], rel=1e-9, abs=1e-12)


def test_spheres_over_vertices_and_edges_of_a_turned_mesh_feel_the_plane():
    """On a flat mesh turned out of the axes (round-off in every closest point), spheres
    pressed 1 % of their radius at vertices, on edges and 1e-9 m beside them feel the plane's
    Hertz force: 13 of these 225 felt two or three contacts."""
    from soilcal.dem.geometry import rotation_matrix

    r, delta = 1e-3, 1e-5
    mats = table(e=0.5, mu=0.2, E=1e8)
    rot = rotation_matrix(np.array([0.3, 0.5, 0.8]) / math.sqrt(0.98), 0.7)
    shift = np.array([0.01, -0.02, 0.03])
    v, t = _grid(L=0.04, n=16)  # 5 mm cells
    n = rot @ np.array([0, 0, 1.0])
    rng = np.random.default_rng(1)
    on = lambda q: round(q / 0.005) * 0.005  # noqa: E731 - the grid line nearest q
    pts = []
    for i, x in enumerate(np.linspace(-0.035, 0.035, 15)):
        for j, y in enumerate(np.linspace(-0.035, 0.035, 15)):
            q = [(on(x), on(y)), (on(x) + rng.uniform(-1e-3, 1e-3), on(y)),
                 (x + rng.uniform(-1e-9, 1e-9), on(y) + rng.uniform(-1e-9, 1e-9))][(i + j) % 3]
            pts.append(rot @ np.array([q[0], q[1], 0.0]) + shift + n * (r - delta))
    sim = Simulation(mats, gravity=(0, 0, 0))
    sim.add_mesh(np.array(v) @ rot.T + shift, t, "soil")
    sim.add_particles(np.array(pts), r, "soil")
    f, _ = sim.compute_forces()
    f = f[sim.index(np.arange(len(pts)))]
    fn = _hertz_wall_force(mats, r, delta)
    assert np.abs(f - fn * n).max() < 1e-9 * fn


def test_a_ledge_of_the_same_mesh_pushes_a_sphere_resting_on_its_floor():
    """A floor and a low ledge (0.3 R high) in one mesh: a sphere on the floor against the
    ledge's top edge is pushed by the floor and by the edge, as when they are two meshes.
    The edge contact was dropped because the same mesh had a face contact (the floor), so
    the sphere felt the floor alone and would pass into the ledge."""
    r = 2e-3
    h = 0.3 * r
    mats = table(e=0.5, mu=0.2, E=1e8)
    v = [[-0.02, -0.02, 0], [0.01, -0.02, 0], [0.01, 0.02, 0], [-0.02, 0.02, 0],
         [0.01, -0.02, h], [0.01, 0.02, h], [0.03, -0.02, h], [0.03, 0.02, h]]
    t = [[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2], [4, 6, 7], [4, 7, 5]]
    x = np.array([0.01 - 0.5 * r, 0, 0.999 * r])
    sim = Simulation(mats, gravity=(0, 0, 0))
    sim.add_mesh(v, t, "soil")
    sim.add_particles([x], r, "soil")
    f, _ = sim.compute_forces()
    floor = _hertz_wall_force(mats, r, 0.001 * r) * np.array([0, 0, 1.0])
    d = x - np.array([0.01, 0, h])  # from the ledge's edge to the centre
    dist = np.linalg.norm(d)
    edge = _hertz_wall_force(mats, r, r - dist) * d / dist
    assert f[0] == pytest.approx(floor + edge, rel=1e-9, abs=1e-12)


def _tile(x0, x1, h=0.02):
    """A flat rectangle x0 <= x <= x1, |y| <= h in z = 0, facing up, as a two-triangle mesh."""
    return [[x0, -h, 0], [x1, -h, 0], [x1, h, 0], [x0, h, 0]], [[0, 1, 2], [0, 2, 3]]


_FLOORS = {  # floors z = 0 made of several walls that meet or overlap
    "two_meshes": lambda s: (s.add_mesh(*_tile(-0.02, 0.0), "soil"),
                             s.add_mesh(*_tile(0.0, 0.02), "soil")),
    "two_boxes": lambda s: (s.add_box((-0.02, -0.02, -0.01), (0.0, 0.02, 0.0), "soil"),
                            s.add_box((0.0, -0.02, -0.01), (0.02, 0.02, 0.0), "soil")),
    "plane_then_mesh": lambda s: (s.add_plane((0, 0, 0), (0, 0, 1), "soil"),
                                  s.add_mesh(*_tile(-0.02, 0.0), "soil")),
    "mesh_then_plane": lambda s: (s.add_mesh(*_tile(0.0, 0.02), "soil"),
                                  s.add_plane((0, 0, 0), (0, 0, 1), "soil")),
    "rectangle_and_mesh": lambda s: (s.add_rectangle((0.01, 0, 0), (0, 0, 1), (1, 0, 0), 0.01,
                                                     0.02, "soil"),
                                     s.add_mesh(*_tile(-0.02, 0.0), "soil")),
}


@pytest.mark.parametrize("floor", sorted(_FLOORS))
@pytest.mark.parametrize("x", [0.0, 1e-9, -1e-9, 3e-4, -3e-4])
def test_a_sphere_on_a_floor_of_several_walls_is_one_contact(floor, x):
    """A floor of two STL tiles (two walls), of two boxes side by side, or a mesh lying on a
    plane or a rectangle is one surface: a sphere on the seam, or on the mesh over the plane,
    was pushed by both walls with twice the Hertz force of the plane (x = +-3e-4 m: the
    neighbour's edge touches within sqrt(2 R delta) = 0.71 mm of the seam)."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    sim = Simulation(mats, gravity=(0, 0, 0))
    _FLOORS[floor](sim)
    delta = 0.01 * R
    sim.add_particles([[x, 0.0, R - delta]], R, "soil")
    f, _ = sim.compute_forces()
    assert f[0] == pytest.approx([0, 0, _hertz_wall_force(mats, R, delta)], rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("x", [0.0, 3e-4, -3e-4])
@pytest.mark.parametrize("gap, step", [(1e-8, 0.0), (5e-7, 0.0), (-5e-7, 0.0), (0.0, 1e-7),
                                       (0.0, 1e-9)])
def test_tiles_a_rounding_error_apart_are_one_contact(gap, step, x):
    """Two mesh tiles meeting with a gap (or overlap) of up to 5e-7 m or a step of up to
    1e-7 m, as CAD exports leave them, are one surface: a sphere on the seam was pushed 2.0
    times, near it 1.74 times the Hertz force of one plane (the points were compared within
    1e-9 R).  Over the raised tile the force is that of its overlap delta + step."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    sim = Simulation(mats, gravity=(0, 0, 0))
    v, t = _tile(-0.02, -0.5 * gap)
    sim.add_mesh(v, t, "soil")
    v, t = _tile(0.5 * gap, 0.02)
    sim.add_mesh([[a, b, step] for a, b, _ in v], t, "soil")
    delta = 0.01 * R
    sim.add_particles([[x, 0.0, R - delta]], R, "soil")
    f, _ = sim.compute_forces()
    d = delta + step if x >= 0 else delta  # at x = 0 the raised edge is the closer
    assert f[0][2] == pytest.approx(_hertz_wall_force(mats, R, d), rel=3e-3)
    assert abs(f[0][0]) < 1e-3 * f[0][2] and f[0][1] == 0.0


@pytest.mark.parametrize("x", [0.0, 1e-4, 3e-4, -3e-4])
@pytest.mark.parametrize("noise", [2e-9, 1e-8, -5e-7])
def test_unwelded_patches_of_one_mesh_are_one_contact(noise, x):
    """One mesh (one STL file, one wall) of two patches whose seam vertices are not shared:
    patch B's copies of the seam corners lie ``noise`` off patch A's (float32 rounding of a
    CAD export, 1.9e-9 m at 0.02 m, or a slight overlap).  A sphere pressed delta = 0.01 R
    into the plate on or beside the seam was pushed by both patches: 2.0 times the Hertz force
    of the plate on the seam, 1.97 at 0.1 mm, 1.74 at 0.3 mm; it is one surface, as the same
    two patches welded or loaded as two walls."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    sim = Simulation(mats, gravity=(0, 0, 0))
    va, ta = _tile(-0.02, 0.0)
    vb, tb = _tile(noise, 0.02)
    sim.add_mesh(np.vstack([va, vb]), np.vstack([ta, np.asarray(tb) + len(va)]), "soil")
    delta = 0.01 * R
    sim.add_particles([[x, 0.0, R - delta]], R, "soil")
    f, _ = sim.compute_forces()
    fh = _hertz_wall_force(mats, R, delta)
    assert f[0][2] == pytest.approx(fh, rel=1e-6)
    # on the seam the normal may come from either side's edge: tilted by at most noise / R
    assert abs(f[0][0]) <= 2 * abs(noise) / R * fh and f[0][1] == 0.0


@pytest.mark.parametrize("x, y", [(0.0, 0.0), (0.002, 0.001), (0.01, 0.0)])
def test_an_stl_tile_on_a_plane_is_one_contact(x, y):
    """An STL tile (float32 vertices) lying on a plane at z = -0.3 m is 1.2e-8 m off it: the
    sphere was pushed 2.0 times the Hertz force of the plane everywhere over the tile (on its
    diagonal, over its face, beside it).  The tile counts over its face with its own overlap,
    1.19e-8 m less: 0.99964 of the plane's force at 0.01 R."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    sim = Simulation(mats, gravity=(0, 0, 0))
    z0 = -0.3
    sim.add_plane((0, 0, z0), (0, 0, 1), "soil")
    v, t = _tile(-0.005, 0.005)
    sim.add_mesh(np.array([[a, b, z0] for a, b, _ in v], dtype=np.float32), t, "soil")
    delta = 0.01 * R
    sim.add_particles([[x, y, z0 + R - delta]], R, "soil")
    f, _ = sim.compute_forces()
    assert f[0][2] == pytest.approx(_hertz_wall_force(mats, R, delta), rel=1e-3)


@pytest.mark.parametrize("kind, floor_kind", [("rectangle", "plane"), ("disk", "plane"), ("rectangle", "mesh"),
                                              ("rectangle", "rectangle")])
@pytest.mark.parametrize("moving_first", [True, False])
def test_a_belt_set_into_a_floor_carries_a_sphere_whichever_wall_came_first(kind, floor_kind, moving_first):
    """A belt (rectangle) or a turntable-like disk moving at u, lying in a fixed floor plane:
    a sphere resting on it rolls at 2/7 u once it stops sliding (a sphere on a plane moving
    at u: friction takes v from 0 to 2/7 u).  With the plane added first the plane counted
    the contact and the sphere stayed at rest."""
    u = 0.1
    sim = Simulation(table(e=0.5, mu=0.3, E=1e8), dt=2e-6)

    def moving():
        if kind == "rectangle":
            sim.add_rectangle((0, 0, 0), (0, 0, 1), (1, 0, 0), 0.05, 0.02, "soil",
                              velocity=(u, 0, 0))
        else:
            sim.add_disk((0, 0, 0), (0, 0, 1), 0.05, "soil", velocity=(u, 0, 0))

    def floor():
        if floor_kind == "plane":
            sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
        elif floor_kind == "rectangle":
            sim.add_rectangle((0, 0, 0), (0, 0, 1), (1, 0, 0), 0.2, 0.2, "soil")
        else:
            v, t = _grid(L=0.2, n=4)
            sim.add_mesh(v, t, "soil")

    (moving(), floor()) if moving_first else (floor(), moving())
    sim.add_particles([[0.0, 0.0, 0.9999 * R]], R, "soil")
    sim.run(10000)  # 0.02 s; sliding ends after 2/7 u / (mu g) = 0.0097 s
    assert sim.v[0][0] == pytest.approx(2 / 7 * u, rel=1e-3)


@pytest.mark.parametrize("y", [0.0, 0.005])
def test_a_convex_edge_made_of_two_walls_is_one_contact(y):
    """A blade's top and its side as two meshes meeting at a convex 90 deg edge: a sphere
    45 deg beyond the edge was pushed by both edges, with twice the Hertz force of the edge;
    in the concave corner of a floor and a wall of two walls it still feels both."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    top = [[-0.02, -0.02, 0], [0, -0.02, 0], [0, 0.02, 0], [-0.02, 0.02, 0]]
    side = [[0, -0.02, 0], [0, -0.02, -0.02], [0, 0.02, -0.02], [0, 0.02, 0]]
    delta = 0.01 * R
    fn = _hertz_wall_force(mats, R, delta)
    d = (R - delta) / math.sqrt(2)
    for x, expected in (([d, y, d], [fn / math.sqrt(2), 0, fn / math.sqrt(2)]),
                        ([-(R - delta), y, -(R - delta)], [-fn, 0, -fn])):
        sim = Simulation(mats, gravity=(0, 0, 0))
        sim.add_mesh(top, [[0, 1, 2], [0, 2, 3]], "soil")
        sim.add_mesh(side, [[0, 1, 2], [0, 2, 3]], "soil")
        sim.add_particles([x], R, "soil")
        f, _ = sim.compute_forces()
        assert f[0] == pytest.approx(expected, rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("floor", ["two_meshes", "mesh_then_plane"])
def test_oblique_impact_across_the_seam_of_two_walls_equals_the_plane(floor):
    """A sphere that hits a floor of two walls beside their seam and slides across it
    rebounds as from one plane: the contact and its tangential spring pass from one wall
    to the other, and the walls together carry the plane's reaction."""
    out = []
    for add in (lambda s: s.add_plane((0, 0, 0), (0, 0, 1), "soil"), _FLOORS[floor]):
        sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0), dt=1e-6)
        add(sim)
        # in contact for 0.74 ms, sliding over the seam x = 0 after 0.28 ms
        sim.add_particles([[-1.5e-4, 0, R + 1e-6]], R, "soil", v=[[0.6, 0, -0.2]])
        sim.run(400)  # still in contact, past the seam: both walls have held it
        out.append((sim.wall_force.sum(axis=0), sim.p.f[0].copy()))
        sim.run(1000)
        out.append((sim.v[0].copy(), sim.omega[0].copy()))
    assert out[0][1][2] > 0.0 and out[0][1][0] < 0.0  # pressed and rubbed mid-way
    for a, b in zip(out[:2], out[2:]):
        assert b[0] == pytest.approx(a[0], rel=1e-9, abs=1e-12)
        assert b[1] == pytest.approx(a[1], rel=1e-9, abs=1e-12)


def test_oblique_impact_on_a_mesh_vertex_equals_the_plane():
    """A sphere sliding off a mesh vertex along an edge during an oblique impact rebounds as
    from a plane (a 2 mm sphere rebounded at 0.450 of its normal speed instead of 0.493: a
    vertex contact beside the edge's)."""
    out = []
    for mesh in (False, True):
        sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0))
        if mesh:
            v, t = _grid()
            sim.add_mesh(v, t, "soil")
        else:
            sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
        sim.add_particles([[0, 0, R + 1e-6]], R, "soil", v=[[0.6, 0, -0.2]])
        sim.run(3000)
        out.append((sim.v[0].copy(), sim.omega[0].copy()))
    assert out[1][0] == pytest.approx(out[0][0], rel=1e-9, abs=1e-12)
    assert out[1][1] == pytest.approx(out[0][1], rel=1e-9, abs=1e-12)


def test_a_sphere_hanging_from_a_moving_mesh_crosses_its_triangles_as_under_a_plane():
    """A JKR contact passes from triangle to triangle with its history: a sphere hanging
    with 0.95 of its pull-off force as weight (its neck in tension, overlap < 0) under a
    ceiling mesh moving sideways rolls at 2/7 of the ceiling's speed, as under a plane. The
    triangle it moved onto started without the neck, so the edge of the one it left held it
    alone: after 1.25 s it was 0.40 mm ahead of the sphere under the plane and 0.14 mm
    aside."""
    r, rho, g, u = 2e-3, 2600.0, 9.81, 0.02
    m = rho * 4 / 3 * math.pi * r**3
    gamma = m * g / (0.95 * 1.5 * math.pi * r)  # pull-off 1.5 pi gamma R (EDEM convention)
    out = []
    for mesh in (False, True):
        sim = Simulation(table(e=0.2, mu=0.5, gamma=gamma, E=1e7, rho=rho), gravity=(0, 0, 0),
                         contact_model=dict(cohesion="jkr"))
        if mesh:
            v, t = _grid(L=0.05, n=20)
            w = sim.add_mesh(v, t, "soil")
        else:
            w = sim.add_plane((0, 0, 0), (0, 0, -1), "soil")
        sim.add_particles([[0.001, 0.0013, -0.9999 * r]], r, "soil")
        sim.run(10000)
        for k in range(1, 11):  # the weight put on slowly: the neck does not tear
            sim.gravity[:] = (0, 0, -g * k / 10)
            sim.run(3000)
        sim.set_wall_motion(w, velocity=(u, 0, 0))
        sim.run(30000)  # the sphere moves 18 mm along the ceiling, over 4 of its cells
        out.append((sim.x[0].copy(), sim.v[0].copy()))
    assert out[0][0][2] == pytest.approx(-r, rel=1e-3)  # still hanging
    assert out[0][1][0] == pytest.approx(2 / 7 * u, rel=1e-3)
    assert out[1][0] == pytest.approx(out[0][0], rel=1e-8)
    assert out[1][1] == pytest.approx(out[0][1], rel=1e-6, abs=1e-12)


def test_a_jkr_neck_under_a_ceiling_of_two_walls_crosses_their_seam_as_under_a_plane():
    """A sphere hanging with 0.95 of its pull-off force as weight under a ceiling of two mesh
    tiles moving sideways rolls at 2/7 of the ceiling's speed, as under a plane, while its
    contact passes the seam.  The tile it moved onto started without the neck, so the edge
    of the one it left held it alone: after 0.21 s it was 0.22 mm ahead of the sphere under
    the plane."""
    r, rho, g, u = 2e-3, 2600.0, 9.81, 0.02
    m = rho * 4 / 3 * math.pi * r**3
    gamma = m * g / (0.95 * 1.5 * math.pi * r)  # pull-off 1.5 pi gamma R (EDEM convention)
    out = []
    for tiles in (False, "meshes", "rectangle_to_mesh"):
        sim = Simulation(table(e=0.2, mu=0.5, gamma=gamma, E=1e7, rho=rho), gravity=(0, 0, 0),
                         contact_model=dict(cohesion="jkr"))
        if tiles == "meshes":  # facing down, seam at x = 0 (the sphere starts under the second)
            ws = [sim.add_mesh([[a, -0.05, 0], [a, 0.05, 0], [b, 0.05, 0], [b, -0.05, 0]],
                               [[0, 1, 2], [0, 2, 3]], "soil") for a, b in ((-0.05, 0), (0, 0.05))]
        elif tiles:  # from under a rectangle onto a mesh: the rectangle's edge, reported as
            # its face, held the neck alone (v_x 5.88e-3 m/s, 3 % above the plane's)
            ws = [sim.add_mesh([[-0.05, -0.05, 0], [-0.05, 0.05, 0], [0, 0.05, 0], [0, -0.05, 0]],
                               [[0, 1, 2], [0, 2, 3]], "soil"),
                  sim.add_rectangle((0.025, 0, 0), (0, 0, -1), (1, 0, 0), 0.025, 0.05, "soil")]
        else:
            ws = [sim.add_plane((0, 0, 0), (0, 0, -1), "soil")]
        sim.add_particles([[0.001, 0.0013, -0.9999 * r]], r, "soil")
        sim.run(10000)
        for k in range(1, 11):  # the weight put on slowly: the neck does not tear
            sim.gravity[:] = (0, 0, -g * k / 10)
            sim.run(3000)
        for w in ws:
            sim.set_wall_motion(w, velocity=(u, 0, 0))
        sim.run(6000)  # the sphere moves 3 mm back along the ceiling, over the seam
        out.append((sim.x[0].copy(), sim.v[0].copy(), sim.wall_force.sum(axis=0)))
    seam = u * 6000 * sim.dt  # where the seam is now
    assert out[0][1][0] == pytest.approx(2 / 7 * u, rel=1e-3)
    for tiled in out[1:]:
        assert tiled[0][0] < seam - 1e-3 and tiled[2][2] < 0.0  # past it, still hanging
        for a, b in zip(out[0], tiled):
            assert b == pytest.approx(a, rel=1e-8, abs=1e-12)


def test_moving_plane_lifts_particle_and_reports_force():
    sim = Simulation(table(e=0.3, mu=0.5, E=1e8), dt_fraction=0.2)
    sim.add_particles([[0.0, 0.0, R]], R, "soil")
    w = sim.add_plane((0, 0, 0), (0, 0, 1), "soil", velocity=(0, 0, 0.01))
    sim.run(20000)
    t = sim.step * sim.dt
    # the sphere rides on the plane: its height follows the plane, force balances weight
    assert sim.x[0, 2] == pytest.approx(R + 0.01 * t, abs=0.02 * R)
    assert sim.v[0, 2] == pytest.approx(0.01, rel=0.01)
    assert sim.wall_force[w, 2] == pytest.approx(-sim.p.m[0] * G, rel=0.01)
    assert sim.prim_par[0, 2] == pytest.approx(0.01 * t, rel=1e-9)


def test_rotating_drum_carries_particle_and_torque_balances():
    # sphere at the bottom of a drum turning about x: friction drags it up the wall until
    # it rolls back; the torque the wall feels about the axis is -F_t * (drum radius)
    Rd = 0.05
    sim = Simulation(table(e=0.3, mu=0.8, mur=0.0, E=1e8), dt_fraction=0.2)
    sim.add_particles([[0.0, 0.0, R]], R, "soil")
    w = sim.add_cylinder((0, 0, Rd), (1, 0, 0), Rd, 0.05, "soil", inner=True,
                         omega=(1.0, 0, 0))
    sim.run(5000)
    # angular momentum balance about the drum axis (quasi-steady): wall torque about axis
    # equals minus the moment of the contact force about the axis
    f = sim.wall_force[w]
    rel = sim.x[0] - np.array([0, 0, Rd])
    torque_expected = np.cross(rel, f) - sim.p.t[0]
    assert sim.wall_torque[w] == pytest.approx(torque_expected, abs=1e-9 + 1e-6 * abs(torque_expected).max())
    assert sim.x[0, 1] != 0.0  # dragged sideways by the turning drum


def test_wall_log_of_a_continued_run():
    # the log of every run() call starts with that call: a sphere at rest on a plane presses
    # it with its weight in every logged row of a later call
    sim = resting(lambda s: s.add_plane((0, 0, 0), (0, 0, 1), "soil"))
    sim.run(1000, wall_log_every=100)
    log = sim.wall_log
    assert log.shape == (10, 1, 6)
    weight = sim.p.m[0] * G
    assert np.allclose(log[:, 0, 2], -weight, rtol=1e-3)
    assert np.allclose(log[:, 0, :2], 0.0, atol=1e-6 * weight)


@pytest.mark.parametrize("curvature", ["flat", "cylinder"])
def test_inner_cylinder_curvature_enters_the_hertz_overlap(curvature):
    """A sphere at rest at the bottom of a drum carries its weight with the Hertz overlap
    delta = (3 m g / (4 E* sqrt(R*)))^(2/3): R* = r against the flat wall, and with
    ``wall_curvature: cylinder`` R* = r R_w / (r + R_w), R_w = -2 R_drum (LAMMPS's region
    cylinder), 10/9 r here, so the overlap is (9/10)^(1/3) of the flat one."""
    r, rd = 1e-3, 5e-3
    sim = Simulation(table(e=0.3, mu=0.5, E=1e7), dt_fraction=0.2,
                     contact_model=dict(wall_curvature=curvature))
    sim.add_particles([[0.0, 0.0, -rd + r]], r, "soil")
    sim.add_cylinder((0, 0, 0), (1, 0, 0), rd, 0.01, "soil", inner=True)
    sim.run(40000)
    assert abs(sim.v[0, 2]) < 1e-7
    delta = r - (rd - math.hypot(sim.x[0, 1], sim.x[0, 2]))
    nu, e = 0.3, 1e7
    estar = e / (2 * (1 - nu**2))
    rstar = r if curvature == "flat" else r * (-2 * rd) / (r - 2 * rd)
    m = 2600.0 * 4 / 3 * math.pi * r**3
    expected = (3 * m * G / (4 * estar * math.sqrt(rstar))) ** (2 / 3)
    assert delta == pytest.approx(expected, rel=1e-6)


_L = 0.04  # a box periodic in x and y, 0 .. _L


def _periodic_sim():
    return Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0), box=(0, _L, 0, _L),
                      periodic=(True, True))


_UNSEEN = {  # walls a sphere could touch across a periodic boundary, without seeing it
    # a plate (normal +x) 1 mm inside x = L: a sphere beside x = 0 presses it across x = L
    "plate_by_boundary": lambda s: s.add_rectangle((_L - 1e-3, _L / 2, 0.01), (1, 0, 0),
                                                   (0, 1, 0), 0.01, 0.01, "soil", name="w"),
    # a floor laid from -L/2 to L/2: its half outside the box is never touched
    "floor_half_outside": lambda s: s.add_mesh(
        [[-_L / 2, 0, 0], [_L / 2, 0, 0], [_L / 2, _L, 0], [-_L / 2, _L, 0]],
        [[0, 1, 2], [0, 2, 3]], "soil", name="w"),
    # a floor tilted along x: a sphere crossing x = L lands at another height above it
    "tilted_plane": lambda s: s.add_plane((0, 0, 0), (0.1, 0, 1), "soil", name="w"),
    # a mesh bump (a box) across the boundary x = 0
    "bump_across": lambda s: s.add_box((-2e-3, 0.01, 0), (2e-3, 0.02, 2e-3), "soil", name="w"),
    # a bar ending on the boundary x = 0 beside a floor spanning the period: a sphere beside
    # x = L presses its end across the boundary (the floor spanning is no licence for the bar)
    "bar_ending_on_boundary_beside_a_floor": lambda s: (
        s.add_mesh([[0, 0, 0], [_L, 0, 0], [_L, _L, 0], [0, _L, 0]], [[0, 1, 2], [0, 2, 3]], "soil", name="floor"),
        s.add_box((0.0, 0.006, 0.02), (0.02, 0.014, 0.03), "soil", name="w")),
    # a floor mesh tilted along x, wider than the box: past x = L it is 1 mm higher than its
    # continuation from x = 0 (it was accepted as continued past both boundaries)
    "tilted_mesh_wider_than_box": lambda s: s.add_mesh(
        [[-0.01, 0, 0], [_L + 0.01, 0, 0.0015], [_L + 0.01, _L, 0.0015], [-0.01, _L, 0]],
        [[0, 1, 2], [0, 2, 3]], "soil", name="w"),
    # a plate lying in the boundary plane x = 0 (a bulkhead): its face is touched across it
    "bulkhead_on_boundary": lambda s: s.add_rectangle((0.0, _L / 2, 0.01), (1, 0, 0), (0, 1, 0), 0.005, 0.005,
                                                      "soil", name="w"),
}


@pytest.mark.parametrize("case", sorted(_UNSEEN))
def test_a_wall_a_sphere_could_touch_across_a_periodic_boundary_is_refused(case):
    """Wall contacts do not see periodic images.  A sphere beside x = 0 whose image across
    x = L presses the plate 1 mm inside x = L by delta = 0.01 R felt no force (Hertz: 4/3 E*
    sqrt(R) delta^1.5 on the image), and a floor laid half outside the box let a sphere over
    its missing half fall through: such set-ups are refused, naming the wall."""
    sim = _periodic_sim()
    _UNSEEN[case](sim)
    sim.add_particles([[R - 0.01 * R - 1e-3, _L / 2, 0.01]], R, "soil")
    with pytest.raises(InputError, match=r"walls\.w.*periodic in x"):
        sim.compute_forces()


def test_the_image_contact_of_the_refused_plate_is_a_hertz_contact():
    """The contact the plate set-up above would miss: the same sphere at its image position
    x + L, in a box without periodic boundaries, is pushed with the Hertz force."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    sim = Simulation(mats, gravity=(0, 0, 0))
    _UNSEEN["plate_by_boundary"](sim)
    delta = 0.01 * R
    sim.add_particles([[_L - 1e-3 + R - delta, _L / 2, 0.01]], R, "soil")
    f, _ = sim.compute_forces()
    assert f[0] == pytest.approx([_hertz_wall_force(mats, R, delta), 0, 0], rel=1e-9, abs=1e-12)


_D = 0.01 * R  # the overlap pressed into the walls below
_SEEN = {  # (wall, lower corner of the periodic box, sphere centre, normal of the face)
    "floor_mesh_spanning": (lambda s: s.add_mesh(*_grid(L=_L / 2, n=4), "soil"), -_L / 2,
                            (1e-4 - _L / 2, 0.0, R - _D), (0, 0, 1)),
    "plate_wider_than_box": (lambda s: s.add_rectangle((_L / 2, _L / 2, 0.01), (0, 1, 0),
                                                       (1, 0, 0), _L, 0.01, "soil"), 0.0,
                             (1e-4, _L / 2 + R - _D, 0.01), (0, 1, 0)),
    "plate_clear": (lambda s: s.add_rectangle((_L / 2, _L / 2, 0.01), (0, 1, 0), (1, 0, 0),
                                              0.005, 0.005, "soil"), 0.0,
                    (_L / 2, _L / 2 + R - _D, 0.01), (0, 1, 0)),
    "floor_plane": (lambda s: s.add_plane((0, 0, 0), (0, 0, 1), "soil"), 0.0,
                    (1e-4, _L / 2, R - _D), (0, 0, 1)),
    # a closed solid exactly spanning the period in y (a periodic slab of a wide blade): its
    # end faces lie on the boundaries y = 0 and y = L, touched at their rims only
    "closed_box_spanning": (lambda s: s.add_box((0.018, 0.0, 0.005), (0.022, _L, 0.015), "soil"), 0.0,
                            (0.018 - R + _D, 1e-4, 0.01), (-1, 0, 0)),
}


@pytest.mark.parametrize("case", sorted(_SEEN))
def test_walls_spanning_or_clear_of_a_periodic_boundary_push_with_the_hertz_force(case):
    """A floor or plate spanning the period (or wider than it), or a wall clear of the
    boundaries, is accepted: a sphere pressed delta = 0.01 R into it beside a boundary feels
    the Hertz force of the face."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    add, lo, x, n = _SEEN[case]
    sim = Simulation(mats, gravity=(0, 0, 0), box=(lo, lo + _L, lo, lo + _L),
                     periodic=(True, True))
    add(sim)
    sim.add_particles([x], R, "soil")
    f, _ = sim.compute_forces()
    fh = _hertz_wall_force(mats, R, _D)
    assert f[0] == pytest.approx(fh * np.array(n, float), rel=1e-9, abs=1e-12)


def test_a_plate_moving_across_a_periodic_boundary_during_a_run_is_refused():
    """A plate clear of the boundaries at the start that the run carries across x = L."""
    sim = _periodic_sim()
    sim.add_rectangle((_L / 2, _L / 2, 0.01), (1, 0, 0), (0, 1, 0), 0.005, 0.005, "soil",
                      name="w", velocity=(0.1, 0, 0))
    sim.add_particles([[0.01, 0.01, 0.01]], R, "soil")
    sim.compute_forces()  # at rest in place: nothing to refuse
    sim.run(10)  # 10 steps carry it far less than to the boundary
    with pytest.raises(InputError, match=r"walls\.w.*over the run"):
        sim.run(int(0.02 / (0.1 * sim.dt)))  # 20 mm: past x = L - R


def test_a_run_that_may_stop_early_is_checked_over_its_steps():
    """run(n, ke_tol) of a plate clear of the boundaries at the start that the n steps would
    carry across x = L: judged over the n steps, as run(n) is."""
    sim = _periodic_sim()
    sim.add_rectangle((_L / 2, _L / 2, 0.01), (0, 1, 0), (1, 0, 0), 0.005, 0.005, "soil", name="w",
                      velocity=(0.5, 0, 0))
    sim.add_particles([[_L / 2, _L / 4, 0.01]], R, "soil")
    sim.compute_forces()
    steps = int(0.05 / sim.dt) + 1  # 25 mm of travel: past x = L
    with pytest.raises(InputError, match=r"walls\.w.*over the run"):
        sim.run(steps, ke_tol=1e-30, ke_every=10)


def test_a_settling_run_judges_a_moving_wall_where_it_stands():
    """run_until_settled runs up to 10 million steps but stops once settled: a paddle clear of
    the boundaries moving at 1 mm/s was refused as sweeping 10 m over that horizon."""
    sim = _periodic_sim()
    sim.add_rectangle((_L / 2, _L / 2, 0.01), (0, 1, 0), (1, 0, 0), 0.005, 0.005, "soil", name="w",
                      velocity=(1e-3, 0, 0))
    sim.add_particles([[_L / 2, _L / 4, 0.01]], R, "soil")
    assert sim.run_until_settled(ke_tol=1.0, check_every=10)


_H = 4 * R  # the height of a terrace's step


def _terrace(s):
    """One mesh spanning the period in x: a floor z = 0 for x < L/2, a riser, z = _H beyond."""
    v = [[0, 0, 0], [_L / 2, 0, 0], [_L / 2, _L, 0], [0, _L, 0],
         [_L / 2, 0, _H], [_L, 0, _H], [_L, _L, _H], [_L / 2, _L, _H]]
    s.add_mesh(v, [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7], [1, 2, 7], [1, 7, 4]], "soil",
               name="w")


@pytest.mark.parametrize("where", ["riser", "edge"])
def test_a_floor_at_another_height_at_each_end_of_the_period_is_refused(where):
    """A terraced floor spanning x = 0 .. L in one mesh, low at x = 0 and high at x = L: its
    periodic continuation steps down at x = 0.  A sphere beside x = 0 pressed delta = 0.01 R
    into that riser, or onto the edge of the high floor across the boundary, is pushed by the
    Hertz force of the overlap (computed below on the continued mesh in a box that is not
    periodic), where it felt no force at all: such a floor is refused, naming it."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    a = 0.6 * R
    x = {"riser": (R - _D, _L / 2, _H / 2), "edge": (a, _L / 2, _H + math.sqrt((R - _D) ** 2 - a**2))}[where]
    # the contact the periodic box would have: the same sphere one period on, by the mesh
    # continued by one period
    sim = Simulation(mats, gravity=(0, 0, 0))
    _terrace(sim)
    sim.add_mesh([[_L, 0, 0], [1.5 * _L, 0, 0], [1.5 * _L, _L, 0], [_L, _L, 0], [_L, 0, _H], [_L, _L, _H]],
                 [[0, 1, 2], [0, 2, 3], [0, 3, 5], [0, 5, 4]], "soil", name="next")
    sim.add_particles([[x[0] + _L, x[1], x[2]]], R, "soil")
    f, _ = sim.compute_forces()
    n = {"riser": np.array([1.0, 0, 0]), "edge": np.array([a, 0, x[2] - _H]) / (R - _D)}[where]
    assert f[0] == pytest.approx(_hertz_wall_force(mats, R, _D) * n, rel=1e-9, abs=1e-12)
    sim = _periodic_sim()
    _terrace(sim)
    sim.add_particles([x], R, "soil")
    with pytest.raises(InputError, match=r"walls\.w.*periodic in x.*at x = 0 m \(y 0 \.\. 0\.04, z 0 m\)"):
        sim.compute_forces()


def _floor_tile(s, x0, x1, y0, y1, z=0.0, name=None, mesh=True):
    if mesh:
        s.add_mesh([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]], [[0, 1, 2], [0, 2, 3]], "soil",
                   name=name)
    else:
        s.add_rectangle(((x0 + x1) / 2, (y0 + y1) / 2, z), (0, 0, 1), (1, 0, 0), (x1 - x0) / 2,
                        (y1 - y0) / 2, "soil", name=name)


@pytest.mark.parametrize("mesh", [True, False])
@pytest.mark.parametrize("x", [(1e-4, 1e-4), (0.0, _L / 2), (_L - 1e-4, _L - 1e-4), (_L / 2, _L / 2)])
def test_a_floor_of_tiles_meeting_at_both_boundaries_pushes_with_the_hertz_force(mesh, x):
    """A floor given as four tiles (STL meshes or rectangles, each its own wall) covering the
    period in x and y: a tile on a boundary meets one at the same height on the other, so the
    floor continues periodically, and a sphere pressed 0.01 R into it beside a boundary, at a
    corner of the box or on the tiles' seams feels the Hertz force of one face (it was
    refused, naming the first tile)."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, _L), periodic=(True, True))
    h = _L / 2
    for i, j in ((0, 0), (1, 0), (0, 1), (1, 1)):
        _floor_tile(sim, i * h, (i + 1) * h, j * h, (j + 1) * h, mesh=mesh)
    sim.add_particles([[x[0], x[1], R - _D]], R, "soil")
    f, _ = sim.compute_forces()
    assert f[0] == pytest.approx([0, 0, _hertz_wall_force(mats, R, _D)], rel=1e-9, abs=1e-12)


_UNMATCHED_TILES = {
    # the second tile a step higher: the floor steps at x = 0 = L
    "step": lambda s: (_floor_tile(s, 0, _L / 2, 0, _L, name="w"), _floor_tile(s, _L / 2, _L, 0, _L, z=_H)),
    # the second tile narrower in y: a gap at x = L, y > L/2
    "narrower": lambda s: (_floor_tile(s, 0, _L / 2, 0, _L, name="w"), _floor_tile(s, _L / 2, _L, 0, _L / 2)),
    # the second tile moving: it is not the same surface over the run
    "moving": lambda s: (_floor_tile(s, 0, _L / 2, 0, _L, name="w"),
                         s.add_rectangle((3 * _L / 4, _L / 2, 0), (0, 0, 1), (1, 0, 0), _L / 4, _L / 2, "soil",
                                         velocity=(0, 0.01, 0))),
}


@pytest.mark.parametrize("case", sorted(_UNMATCHED_TILES))
def test_tiles_that_do_not_meet_alike_at_both_boundaries_are_refused(case):
    sim = _periodic_sim()
    _UNMATCHED_TILES[case](sim)
    sim.add_particles([[1e-4, _L / 4, R - _D]], R, "soil")
    with pytest.raises(InputError, match=r"walls\.w.*periodic in x"):
        sim.compute_forces()


def test_a_floor_spanning_the_period_exactly_may_not_slide_along_it():
    """A floor mesh from x = 0 to L moving along x at 0.1 m/s (a belt) leaves x = 0 .. v t
    bare: a frictionless sphere resting on it at x = 2 mm fell through it (z 3.5 mm, 1.5 mm
    below its resting height, after 5 mm of travel).  Refused over the run; a belt wider than
    the box by its travel plus the largest radius is accepted."""
    def run(x0, x1, steps):
        sim = Simulation(table(e=0.5, mu=0.0, E=1e8), box=(0, _L, 0, _L), periodic=(True, True))
        sim.add_mesh([[x0, 0, 0], [x1, 0, 0], [x1, _L, 0], [x0, _L, 0]], [[0, 1, 2], [0, 2, 3]], "soil",
                     name="w", velocity=(0.1, 0, 0))
        sim.add_particles([[2e-3, _L / 2, R]], R, "soil")
        sim.compute_forces()
        sim.run(steps(sim.dt))
        return sim

    with pytest.raises(InputError, match=r"walls\.w.*over the run"):
        run(0.0, _L, lambda dt: int(0.05 / dt))
    sim = run(-0.011, _L + 0.011, lambda dt: int(0.05 / dt))  # 5 mm of travel, 11 mm wider
    assert sim.x[0, 2] > R - 0.01 * R


def test_a_settling_run_stops_where_a_moving_wall_would_need_its_image():
    """run_until_settled of a sphere that never settles (it coasts along y without gravity)
    beside a paddle moving along x at 0.5 m/s: the paddle's edge, 25 mm from x = 0, may come
    to x = L - R = 35 mm (within 2e-4 R), which it does after (0.01 + 2e-4 R) / (0.5 dt)
    steps; the run stops there, refused, where it carried the paddle through the boundary
    for all of max_steps (to x = 0.3 m)."""
    sim = _periodic_sim()
    sim.add_rectangle((_L / 2, _L / 2, 0.01), (0, 1, 0), (1, 0, 0), 0.005, 0.005, "soil", name="w",
                      velocity=(0.5, 0, 0))
    sim.add_particles([[_L / 2, _L / 4, 0.03]], R, "soil", v=[(0, 0.1, 0)])
    with pytest.raises(InputError, match=r"walls\.w.*not settled after"):
        sim.run_until_settled(1e-30, check_every=10, max_steps=20000)
    assert sim.step == math.floor((0.01 + 2e-4 * R) / (0.5 * sim.dt))


@pytest.mark.parametrize("axis, refused", [((0, 0, 5.0), True), ((0, 5.0, 0), False)])
def test_a_blade_spanning_a_slab_may_turn_only_about_the_periodic_axis(axis, refused):
    """A closed blade (a box mesh) exactly as wide as a slab periodic in y, turning at 5 rad/s
    about its centre: about y its ends stay on the boundaries, and a sphere pressed 0.01 R
    into its face beside y = L feels the Hertz force along the normal; about z its ends swing off the
    boundaries (a sphere beside one boundary would miss the end across it), and it was
    accepted, its sweep counted as reaching past both boundaries."""
    from soilcal.dem.geometry import box_mesh

    mats = table(e=0.5, mu=0.3, E=1e8)
    sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, _L), periodic=(False, True))
    v, t = box_mesh(np.array([0.015, 0.0, 0.0]), np.array([0.018, _L, 0.03]))
    sim.add_mesh(v, t, "soil", name="w", omega=axis, centre=(0.0165, _L / 2, 0.015))
    sim.add_particles([[0.015 - R + _D, _L - 1e-4, 0.015]], R, "soil")
    if refused:
        with pytest.raises(InputError, match=r"walls\.w.*periodic in y.*over the run"):
            sim.run(10)
    else:
        f, _ = sim.compute_forces()
        # along the normal the Hertz force (the face slides past the sphere along z: a
        # tangential force besides)
        assert f[0][:2] == pytest.approx([-_hertz_wall_force(mats, R, _D), 0], rel=1e-9, abs=1e-12)
        sim.run(10)


def test_a_closed_rod_with_disk_caps_on_the_boundaries_pushes_with_the_hertz_force():
    """A cylinder rod (radius 10 mm) along x spanning the period, closed by disks lying on
    x = 0 and x = L: its caps are met at their rims only, and a sphere pressed 0.01 R into
    the rod's top beside x = 0 feels the Hertz force.  It was refused (the caps' centres
    were looked for inside the straight pieces of the section only, never its circles)."""
    from soilcal.dem.walls import CYLINDER, DISK

    mats = table(e=0.5, mu=0.3, E=1e8)
    yc, zc, a = 0.05, 0.05, 0.01
    sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, 0.1), periodic=(True, False))
    sim.add_wall("rod", "soil", [
        (CYLINDER, np.array([_L / 2, yc, zc, 1, 0, 0, a, _L / 2, 0.0]), 0b1, 0b10),
        (DISK, np.array([0, yc, zc, 1, 0, 0, a]), 0b1, 0b10),
        (DISK, np.array([_L, yc, zc, 1, 0, 0, a]), 0b1, 0b10)])
    sim.add_particles([[1e-3, yc, zc + a + R - _D]], R, "soil")
    f, _ = sim.compute_forces()
    assert f[0] == pytest.approx([0, 0, _hertz_wall_force(mats, R, _D)], rel=1e-9, abs=1e-12)


def _curved_floor(n, zf, shift=0.0):
    """A floor mesh over 0 .. _L (x) by 0 .. _L (y) of n x n cells, height zf(y), float32
    rounded as read from a file, shifted by ``shift`` along x."""
    xs = np.linspace(0, _L, n + 1)
    X, Y = np.meshgrid(xs, xs)
    v = np.column_stack([X.ravel(), Y.ravel(), zf(Y.ravel())]).astype(np.float32).astype(float)
    v[:, 0] += shift
    t = [[j * (n + 1) + i, j * (n + 1) + i + 1, j * (n + 1) + i + n + 2] for j in range(n) for i in range(n)]
    t += [[j * (n + 1) + i, j * (n + 1) + i + n + 2, j * (n + 1) + i + n + 1] for j in range(n) for i in range(n)]
    return v, np.array(t)


_CURVED = {  # a cross-profile across y, running along x, and where the sphere sits
    "sine_2mm": (lambda y: 2e-3 * np.sin(2 * np.pi * y / _L), _L / 4, 2e-3),
    "sine_5mm": (lambda y: 5e-3 * np.sin(2 * np.pi * y / _L), _L / 4, 5e-3),
    "parabola": (lambda y: 0.5 * (y - _L / 2) ** 2, _L / 2, 0.0),
}


@pytest.mark.parametrize("n", [30, 60, 100])
@pytest.mark.parametrize("profile", sorted(_CURVED))
def test_a_floor_curved_across_the_periodic_axis_is_accepted_at_every_resolution(profile, n):
    """A faceted floor whose height varies across y only runs along x: the sections at
    x = 0 and x = L are the same at any mesh resolution, and a sphere beside x = 0 feels the
    force of the same floor made non-periodic (copies shifted by +-L).  It was refused at
    some resolutions only (z = 2 mm sin(2 pi y / L) at 60 and 100 cells, 5 mm at 100, the
    parabola at 30 and 60): nearly collinear pieces were merged greedily into lines, differently at
    x = 0 (cut along mesh edges) and inside."""
    zf, y, z = _CURVED[profile]
    mats = table(e=0.5, mu=0.3, E=1e8)
    x = [1e-4, y, z + R - _D]
    forces = []
    for periodic in (True, False):
        sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, _L), periodic=(periodic, False))
        for k, s in enumerate((0.0,) if periodic else (0.0, -_L, _L)):
            sim.add_mesh(*_curved_floor(n, zf, s), "soil", name=f"floor{k}")
        sim.add_particles([x], R, "soil")
        forces.append(sim.compute_forces()[0][0])
    assert forces[1][2] > 0.1 * _hertz_wall_force(mats, R, _D)
    assert forces[0] == pytest.approx(forces[1], rel=1e-9, abs=1e-12)


def _tri(a, b, c):
    from soilcal.dem.walls import TRIANGLE

    return (TRIANGLE, np.concatenate([a, b, c]).astype(float), 0b111, 0)


def _square_tube(h, yc=0.05, zc=0.05):
    """Four faces (two triangles each) of a square tube of half side h along x, 0 .. _L."""
    p = lambda x, y, z: np.array([x, yc + y, zc + z])
    cs = [(-h, -h), (h, -h), (h, h), (-h, h)]
    out = []
    for i in range(4):
        (y0, z0), (y1, z1) = cs[i], cs[(i + 1) % 4]
        out += [_tri(p(0, y0, z0), p(_L, y0, z0), p(_L, y1, z1)),
                _tri(p(0, y0, z0), p(_L, y1, z1), p(0, y1, z1))]
    return out


def _end_square(h, yc=0.05, zc=0.05):
    q = lambda y, z: np.array([0.0, yc + y, zc + z])
    return [_tri(q(-h, -h), q(h, -h), q(h, h)), _tri(q(-h, -h), q(h, h), q(-h, h))]


def _u_channel_with_end():
    y0, y1, hh = 0.03, 0.07, 0.04
    p = lambda x, y, z: np.array([x, y, z])
    out = []
    for (ya, za), (yb, zb) in (((y0, hh), (y0, 0)), ((y0, 0), (y1, 0)), ((y1, 0), (y1, hh))):
        out += [_tri(p(0, ya, za), p(_L, ya, za), p(_L, yb, zb)),
                _tri(p(0, ya, za), p(_L, yb, zb), p(0, yb, zb))]
    return out + [_tri(p(0, y0, 0), p(0, y1, 0), p(0, y1, hh)),
                  _tri(p(0, y0, 0), p(0, y1, hh), p(0, y0, hh))]


def _floor_with_bulkhead():
    from soilcal.dem.walls import RECTANGLE

    rect = lambda c, n, u, a, b: (RECTANGLE, np.concatenate([c, n, u, [a, b]]).astype(float), 0b1, 0b110)
    return [rect((_L / 2, 0.05, 0), (0, 0, 1), (1, 0, 0), _L / 2, 0.05),
            rect((0, 0.05, -2.5e-3), (1, 0, 0), (0, 1, 0), 0.05, 17.5e-3)]


def _shifted(prims, s):
    from soilcal.dem.walls import TRIANGLE

    out = []
    for kind, v, pts, dirs in prims:
        v = v.copy()
        v[[0, 3, 6] if kind == TRIANGLE else [0]] += s
        out.append((kind, v, pts, dirs))
    return out


_END_FACES_MET = {  # walls spanning the period with an end face at x = 0, a sphere beside x = L
    # an open U channel (y 0.03 .. 0.07, z 0 .. 0.04) and an end plate across it: the
    # channel's section encloses nothing
    "u_channel_end_plate": (_u_channel_with_end, (_L - R + _D, 0.05, 0.02)),
    # a floor and a bulkhead (z -20 .. 15 mm) whose centre lies below the floor
    "floor_bulkhead": (_floor_with_bulkhead, (_L - R + _D, 0.05, 7e-3)),
    # a square tube (+-10 mm) and a bulkhead of two triangles (+-25 mm) whose centres lie
    # inside the tube
    "tube_wider_bulkhead": (lambda: _square_tube(0.01) + _end_square(0.025),
                            (_L - R + _D, 0.05 + 0.017, 0.05)),
}


@pytest.mark.parametrize("case", sorted(_END_FACES_MET))
def test_an_end_face_reaching_outside_a_closed_outline_of_the_section_is_refused(case):
    """An end face on the boundary x = 0 is met at its rim only when every corner lies
    inside or on a closed outline of the section of the faces along x there.  In these
    set-ups a sphere beside x = L presses the end face across the boundary: the set-up made
    non-periodic (the wall copied at +-L) pushes it with the Hertz force of an overlap
    0.01 R, and the periodic run gave 0 (its centre, or the centres of its triangles, lay
    inside the section by a ray count that also counted open outlines): it is refused,
    naming the wall and the corner outside."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    build, x = _END_FACES_MET[case]
    sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, 0.1))
    sim.add_wall("w", "soil", build() + _shifted(build(), _L) + _shifted(build(), -_L))
    sim.add_particles([x], R, "soil")
    f, _ = sim.compute_forces()
    assert np.linalg.norm(f[0]) == pytest.approx(_hertz_wall_force(mats, R, _D), rel=1e-9)
    sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, 0.1), periodic=(True, False))
    sim.add_wall("w", "soil", build())
    sim.add_particles([x], R, "soil")
    with pytest.raises(InputError, match=r"walls\.w.*end face on the boundary x = 0 m with a "
                                         r"corner at \(y, z\) = .* outside every closed outline"):
        sim.compute_forces()


def test_a_tube_closed_by_end_faces_on_its_section_pushes_with_the_hertz_force():
    """The square tube closed by end squares exactly its section (corners on the closed
    outline) stays accepted: a sphere pressed 0.01 R into its top beside x = L feels the
    Hertz force."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, 0.1), periodic=(True, False))
    sim.add_wall("w", "soil", _square_tube(0.01) + _end_square(0.01))
    sim.add_particles([[_L - R / 2, 0.05, 0.06 + R - _D]], R, "soil")
    f, _ = sim.compute_forces()
    assert f[0] == pytest.approx([0, 0, _hertz_wall_force(mats, R, _D)], rel=1e-9, abs=1e-12)


def test_spheres_inside_a_closed_solid_spanning_the_period_are_refused():
    """A closed bin (a box mesh, 0 .. L along x) spanning the period with spheres inside,
    0.99 R from its end walls: made non-periodic (the bin copied at +-L) each sphere is
    pushed by its end wall with the Hertz force of an overlap 0.01 R; periodic, each got
    three times that (5.4945 N), the two spheres touching across x = 0 through the end
    walls.  The end walls are met at more than their rims: the set-up is refused, naming
    the bin and a sphere inside it."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    x = [(0.99 * R, _L / 2, 0.015), (_L - 0.99 * R, _L / 2, 0.015)]
    sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, _L))
    for k, s in enumerate((0.0, -_L, _L)):
        sim.add_box((s, 0.0, 0.0), (s + _L, _L, 0.03), "soil", name=f"bin{k}")
    sim.add_particles(x, R, "soil")
    f, _ = sim.compute_forces()
    fh = _hertz_wall_force(mats, R, 0.01 * R)
    assert f.ravel() == pytest.approx([fh, 0, 0, -fh, 0, 0], rel=1e-9, abs=1e-12)
    sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, _L), periodic=(True, False))
    sim.add_box((0.0, 0.0, 0.0), (_L, _L, 0.03), "soil", name="bin")
    sim.add_particles(x, R, "soil")
    with pytest.raises(InputError, match=r"walls\.bin.*2 sphere\(s\) inside the end faces on "
                                         r"the boundary"):
        sim.compute_forces()


def test_points_inside_closed_outlines_are_found_in_chunks():
    # an L-shaped outline (the unit square less its upper right quarter) and a circle of radius
    # 0.1 about (2, 2): inside by the shapes' inequalities, tested in chunks of a few points
    # and with the points outside both bounding boxes never tested
    from soilcal.dem.engine import _inside_many

    corners = np.array([(0, 0), (1, 0), (1, 0.5), (0.5, 0.5), (0.5, 1), (0, 1)], float)
    loops = np.stack([corners, np.roll(corners, -1, axis=0)], axis=1)
    circ = np.array([[2.0, 2.0, 0.1]])
    rng = np.random.default_rng(3)
    pts = rng.uniform(-0.5, 2.5, size=(5000, 2))
    x, y = pts[:, 0], pts[:, 1]
    in_l = (x > 0) & (x < 1) & (y > 0) & (y < 1) & ~((x > 0.5) & (y > 0.5))
    in_c = np.hypot(x - 2.0, y - 2.0) < 0.1
    for block in (7, 500_000):
        got = _inside_many(pts, loops, circ, block=block)
        assert np.array_equal(got, in_l | in_c)
    assert not _inside_many(pts, np.zeros((0, 2, 2)), np.zeros((0, 3))).any()


def _quad(a, b, c, d):
    return [[a, b, c], [a, c, d]]


def _prism(section, x0, x1):
    """The faces along x of a prism over ``section`` (a closed polygon of (y, z) corners)
    from x0 to x1, and its two end faces (fans from the first corner)."""
    out = []
    for (ya, za), (yb, zb) in zip(section, section[1:] + section[:1]):
        out += _quad((x0, ya, za), (x1, ya, za), (x1, yb, zb), (x0, yb, zb))
    for x in (x0, x1):
        out += [[(x, *section[0]), (x, *section[i]), (x, *section[i + 1])]
                for i in range(1, len(section) - 1)]
    return out


_Y0, _Y1, _H = 0.025, 0.035, 0.01  # a ridge across y, standing on z = 0


def _floor(x0, x1):
    return _quad((x0, 0, 0), (x1, 0, 0), (x1, 0.06, 0), (x0, 0.06, 0))


_ON_FLOOR = {  # one wall: floor faces and a closed solid along x between x0 and x1
    # a closed box standing on a floor sheet: its bottom face lies on the floor
    "box_on_floor": lambda x0, x1: _floor(x0, x1) + _prism(
        [(_Y0, 0), (_Y1, 0), (_Y1, _H), (_Y0, _H)], x0, x1),
    # the box sunk 2 mm through the floor sheet
    "box_through_floor": lambda x0, x1: _floor(x0, x1) + _prism(
        [(_Y0, -0.002), (_Y1, -0.002), (_Y1, _H), (_Y0, _H)], x0, x1),
    # a closed floor slab 4 mm thick with the box on its top face: two solids sharing a face
    "box_on_slab": lambda x0, x1: _prism([(0, -0.004), (0.06, -0.004), (0.06, 0), (0, 0)], x0, x1)
    + _prism([(_Y0, 0), (_Y1, 0), (_Y1, _H), (_Y0, _H)], x0, x1),
}


def _stl_wall(sim, name, tris, tmp_path):
    """``tris`` written to a binary STL file (float32 corners) and read back as one wall."""
    from soilcal.dem.stl import read_stl, write_stl

    tri = np.array(tris, float)
    path = tmp_path / f"{name}.stl"
    write_stl(path, tri.reshape(-1, 3), np.arange(tri.shape[0] * 3).reshape(-1, 3))
    sim.add_mesh(*read_stl(path), "soil", name=name)


@pytest.mark.parametrize("x", [(1e-4, 0.01, R - _D), (_L - 1e-4, 0.01, R - _D),
                               (1e-4, _Y0 - R + _D, 0.006), (_L - 1e-4, 0.03, _H + R - _D)])
@pytest.mark.parametrize("case", sorted(_ON_FLOOR))
def test_a_solid_standing_on_a_floor_of_the_same_wall_pushes_with_the_hertz_force(case, x, tmp_path):
    """A box along x spanning the period on a floor, all in one STL file: its end faces on
    x = 0 and x = L lie inside the closed outline the box's faces cut there, and a sphere
    pressed 0.01 R into the floor, a side of the box or its top beside either boundary feels
    the Hertz force, as with the wall copied at +-L.  It was refused (the outline was looked
    for among whole pieces joined end to end; the floor, open at both ends, was dropped with
    the box's bottom lying on it, and so was the box)."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    forces = []
    for periodic in (True, False):
        sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, 0.06), periodic=(periodic, False))
        for k, s in enumerate((0.0,) if periodic else (0.0, -_L, _L)):
            _stl_wall(sim, f"bin{k}", _ON_FLOOR[case](s, s + _L), tmp_path)
        sim.add_particles([x], R, "soil")
        forces.append(sim.compute_forces()[0][0].copy())
    # float32 corners (0.025 is read as 0.025000000373): a face 4e-10 m off its place changes
    # the force of the 5e-5 m overlap by 1.1e-5
    assert np.linalg.norm(forces[0]) == pytest.approx(_hertz_wall_force(mats, R, _D), rel=1e-4)
    assert forces[0] == pytest.approx(forces[1], rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("case,x", [("box_on_floor", (0.02, 0.03, 0.005)),
                                    ("box_on_slab", (0.02, 0.03, 0.005)),
                                    ("box_on_slab", (0.02, 0.026, -0.0015)),
                                    ("box_through_floor", (0.02, 0.03, -0.001))])
def test_a_sphere_inside_a_solid_standing_on_a_floor_is_refused(case, x, tmp_path):
    """A sphere (radius 1 mm) inside the box or inside the slab it stands on: it meets the
    end faces on the boundaries; the set-up is refused, naming the wall and the sphere.
    Inside the slab it would be missed by a count of crossings over both outlines at once
    (a ray from it leaves the slab into the box and leaves the box: two)."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, 0.06), periodic=(True, False))
    _stl_wall(sim, "bin", _ON_FLOOR[case](0.0, _L), tmp_path)
    sim.add_particles([x], 1e-3, "soil")
    with pytest.raises(InputError, match=r"walls\.bin.*1 sphere\(s\) inside the end faces"):
        sim.compute_forces()



def _sheet(path, x0, x1):
    """Faces along x over the open polyline ``path`` of (y, z) corners, from x0 to x1."""
    out = []
    for (ya, za), (yb, zb) in zip(path[:-1], path[1:]):
        out += _quad((x0, ya, za), (x1, ya, za), (x1, yb, zb), (x0, yb, zb))
    return out


def _duct(outer, inner, x0, x1):
    """A hollow duct along x: the faces of the outer and inner prisms and ring end faces."""
    out = _sheet(outer + outer[:1], x0, x1) + _sheet(inner[::-1] + inner[-1:], x0, x1)
    for x in (x0, x1):
        for i in range(len(outer)):
            j = (i + 1) % len(outer)
            out += _quad((x, *outer[i]), (x, *outer[j]), (x, *inner[j]), (x, *inner[i]))
    return out


_RIDGE = [(_Y0, 0), (_Y1, 0), (_Y1, _H), (_Y0, _H)]
_OUTER = [(0.01, 0.0), (0.05, 0.0), (0.05, 0.04), (0.01, 0.04)]
_INNER = [(0.015, 0.005), (0.045, 0.005), (0.045, 0.035), (0.015, 0.035)]
_ARCH = [(0.005 + 0.01 * (1 - math.cos(t)), 0.01 * math.sin(t))
         for t in np.linspace(0.0, math.pi, 13)]
_HOLLOW = {  # one wall with open space inside its closed outlines, and a point there
    # a hollow square duct: a sphere on the floor of its cavity (the ring end faces
    # on x = 0 and L leave the cavity open)
    "duct_cavity": (lambda x0, x1: _duct(_OUTER, _INNER, x0, x1), (0.03, 0.005)),
    # a floor, an arch sheet over it (a tunnel, no end faces) and a closed ridge beside it:
    # a sphere on the floor in the tunnel
    "tunnel_beside_ridge": (lambda x0, x1: _floor(x0, x1) + _sheet(_ARCH, x0, x1)
                            + _prism(_RIDGE, x0, x1), (0.015, 0.0)),
    # a channel sealed by floor, side and lid sheets with a closed ridge on its floor: a
    # sphere on the floor beside the ridge
    "sealed_channel_with_ridge": (lambda x0, x1: _floor(x0, x1) + _sheet(
        [(0, 0), (0, 0.04), (0.06, 0.04), (0.06, 0)], x0, x1) + _prism(_RIDGE, x0, x1),
        (0.01, 0.0)),
}


@pytest.mark.parametrize("x", [1e-4, _L / 2, _L - 1e-4])
@pytest.mark.parametrize("case", sorted(_HOLLOW))
def test_a_sphere_in_open_space_inside_closed_outlines_pushes_with_the_hertz_force(case, x,
                                                                                   tmp_path):
    """A sphere pressed 0.01 R onto a floor in open space that closed outlines of the section
    surround (a duct's cavity, a tunnel or sealed channel beside a closed ridge, all one STL
    file): it meets no end face on the boundaries, only faces along x, and feels the Hertz
    force of its overlap, as with the wall copied at +-L.  It was refused as inside a closed
    solid (a sphere inside any closed outline of the section was taken to be in a solid)."""
    build, (y, z) = _HOLLOW[case]
    mats = table(e=0.5, mu=0.3, E=1e8)
    forces = []
    for periodic in (True, False):
        sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, 0.06), periodic=(periodic, False))
        for k, s in enumerate((0.0,) if periodic else (0.0, -_L, _L)):
            _stl_wall(sim, f"bin{k}", build(s, s + _L), tmp_path)
        sim.add_particles([(x, y, z + R - _D)], R, "soil")
        forces.append(sim.compute_forces()[0][0].copy())
    assert np.linalg.norm(forces[0]) == pytest.approx(_hertz_wall_force(mats, R, _D), rel=1e-4)
    assert forces[0] == pytest.approx(forces[1], rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("case,x", [("duct_wall", (0.02, 0.03, 0.0025)),
                                    ("nested_boxes", (0.02, 0.03, 0.0025))])
def test_a_sphere_inside_the_material_of_a_hollow_or_nested_solid_is_refused(case, x, tmp_path):
    """A sphere (radius 1 mm) inside the wall of a hollow duct, or inside a closed box between
    it and a second closed box within it (its end faces cover both): it meets the end faces
    on the boundaries; the set-up is refused, naming the wall and the sphere."""
    tris = (_duct(_OUTER, _INNER, 0.0, _L) if case == "duct_wall"
            else _prism(_OUTER, 0.0, _L) + _prism(_INNER, 0.0, _L))
    mats = table(e=0.5, mu=0.3, E=1e8)
    sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, 0.06), periodic=(True, False))
    _stl_wall(sim, "bin", tris, tmp_path)
    sim.add_particles([x], 1e-3, "soil")
    with pytest.raises(InputError, match=r"walls\.bin.*1 sphere\(s\) inside the end faces"):
        sim.compute_forces()


def test_closed_outlines_of_solids_sharing_faces_and_standing_on_lines():
    """The closed outlines of a unit square standing on a line (y = 0, x -1 .. 2) beside a
    square of side 0.5 sharing the unit square's right side in part, and a triangle crossing
    the line: points inside each found by the shapes' inequalities; the line, open at its
    ends, encloses nothing."""
    from soilcal.dem.engine import _closed_outline, _inside_many

    def ring(*c):
        c = np.array(c, float)
        return np.stack([c, np.roll(c, -1, axis=0)], axis=1)

    seg = np.concatenate([np.array([[[-1.0, 0.0], [2.0, 0.0]]]),
                          ring((0, 0), (1, 0), (1, 1), (0, 1))[1:],  # bottom on the line
                          ring((1, 0.25), (1.5, 0.25), (1.5, 0.75), (1, 0.75))[:3],
                          ring((-0.8, -0.5), (-0.2, -0.5), (-0.5, 0.5))])
    loops, face = _closed_outline(seg, 1e-9)
    rng = np.random.default_rng(5)
    pts = rng.uniform(-1.2, 2.2, size=(20000, 2))
    x, y = pts[:, 0], pts[:, 1]
    inside = (((x > 0) & (x < 1) & (y > 0) & (y < 1))
              | ((x > 1) & (x < 1.5) & (y > 0.25) & (y < 0.75))
              | ((y > -0.5) & (y < 0.5 - np.abs(x + 0.5) / 0.3)))
    # keep away from the edges, where the ray count and the inequalities may differ by a rounding
    far = np.min(np.abs([x, x - 1, x - 1.5, y, y - 1, y - 0.25, y - 0.75, y + 0.5,
                          y - 0.5 + np.abs(x + 0.5) / 0.3]), axis=0) > 1e-6
    got = _inside_many(pts, loops, np.zeros((0, 3)), face=face)
    assert np.array_equal(got[far], inside[far])
    line = np.array([[[-1.0, 0.0], [2.0, 0.0]], [[0.5, 0.0], [0.5, 1.0]]])
    assert _closed_outline(line, 1e-9)[0].shape[0] == 0


def test_pieces_whose_boxes_overlap_are_paired_once_in_any_chunks():
    from soilcal.dem.engine import _box_pairs

    rng = np.random.default_rng(8)
    seg = rng.uniform(0, 1, size=(300, 2, 2)) * [1.0, 1.0] * rng.uniform(0.05, 1, (300, 1, 1))
    lo, hi = seg.min(axis=1) - 1e-3, seg.max(axis=1) + 1e-3
    i, j = np.triu_indices(300, 1)
    want = {(a, b) for a, b, ok in zip(i, j, np.all((lo[i] <= hi[j]) & (lo[j] <= hi[i]), axis=1))
            if ok}
    for chunk in (7, 1_000_000):
        got = [tuple(sorted(p)) for a, b in _box_pairs(seg, 1e-3, chunk) for p in zip(a, b)]
        assert len(got) == len(set(got)) and set(got) == {(int(a), int(b)) for a, b in want}


def _tilted(kind, tilt):
    """A plane (z = 0 at x = L/2) or a rod (radius 10 mm, axis through (L/2, 0.05, 0.05))
    along x tilted by ``tilt`` rad towards +z, and the signed distance of a point from it."""
    a = np.array([math.cos(tilt), 0.0, math.sin(tilt)])
    if kind == "plane":
        n = np.array([-math.sin(tilt), 0.0, math.cos(tilt)])
        return (lambda s: s.add_plane((_L / 2, 0, 0), n, "soil", name="w"),
                lambda x: float(np.dot(np.asarray(x) - [_L / 2, 0, 0], n)))
    p = np.array([_L / 2, 0.05, 0.05])
    return (lambda s: s.add_cylinder(p, a, 0.01, _L / 2, "soil", inner=False, name="w"),
            lambda x: float(np.linalg.norm(np.cross(np.asarray(x) - p, a))) - 0.01)


def test_a_plane_rising_over_the_period_is_judged_against_the_smallest_radius():
    """Spheres of radii 1.5 and 4.5 mm beside a plane tilted by 1.5e-5 rad along x in a box
    periodic in x (L = 0.04 m): it rises 0.6 um over the period, under 2e-4 of the largest
    radius (0.9 um) but twice 2e-4 of the smallest (0.3 um); a small sphere pressed 0.01 R
    (15 um) into it lands 0.6 um deeper or shallower after crossing the boundary, 4 % of its
    overlap, 6 % of its Hertz force.  It was accepted; it is refused, naming the plane.  Level,
    it is accepted."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    for tilt, refused in ((1.5e-5, True), (0.0, False)):
        sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, 0.1), periodic=(True, False))
        sim.add_plane((_L / 2, 0, 0), (-math.sin(tilt), 0, math.cos(tilt)), "soil", name="w")
        sim.add_particles([(_L - 1e-4, 0.02, 0.99 * 1.5e-3)], 1.5e-3, "soil")
        sim.add_particles([(_L / 2, 0.07, 0.99 * 4.5e-3)], 4.5e-3, "soil")
        if refused:
            with pytest.raises(InputError, match=r"walls\.w.*rise over the period"):
                sim.compute_forces()
        else:
            f = np.linalg.norm(sim.compute_forces()[0][0])
            assert f == pytest.approx(_hertz_wall_force(mats, 1.5e-3, 1.5e-5), rel=1e-6)


@pytest.mark.parametrize("kind", ["mesh", "rectangle"])
def test_a_flat_face_rising_over_the_period_is_judged_as_a_plane_is(kind):
    """A floor of two triangles or a rectangle, wider than the period, tilted by 1.5e-5 rad
    along x in a box periodic in x (L = 0.04 m), with spheres of radii 1.5 and 4.5 mm: it rises
    0.6 um over the period, twice 2e-4 of the smallest radius (0.3 um), the limit a plane is
    held to.  A small sphere pressed 0.01 R (15 um) into it just inside x = L felt the Hertz
    force of that overlap, and after crossing the boundary at the same height 0.941 of it (a
    bare slope under 2e-4 counted as none, the sections 0.6 um apart within 2e-4 of the largest
    radius).  It is refused, naming the wall; level, it is accepted with the Hertz force on
    both sides."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    r = 1.5e-3
    for tilt, refused in ((1.5e-5, True), (0.0, False)):
        s, c = math.sin(tilt), math.cos(tilt)
        for x in (_L - 1e-4, 1e-4):
            sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, 0.1), periodic=(True, False))
            if kind == "mesh":
                zf = [(xx - _L / 2) * math.tan(tilt) for xx in (-0.01, _L + 0.01)]
                sim.add_mesh([[-0.01, -0.05, zf[0]], [_L + 0.01, -0.05, zf[1]],
                              [_L + 0.01, 0.15, zf[1]], [-0.01, 0.15, zf[0]]],
                             [[0, 1, 2], [0, 2, 3]], "soil", name="w")
            else:
                sim.add_rectangle((_L / 2, 0.05, 0), (-s, 0, c), (c, 0, s), (_L / 2 + 0.01) / c,
                                  0.1, "soil", name="w")
            sim.add_particles([(x, 0.05, 0.99 * r)], r, "soil")
            sim.add_particles([(_L / 2, 0.07, 0.05)], 4.5e-3, "soil")
            if refused:
                with pytest.raises(InputError, match=r"walls\.w.*rising over the period"):
                    sim.compute_forces()
            else:
                f = np.linalg.norm(sim.compute_forces()[0][0])
                assert f == pytest.approx(_hertz_wall_force(mats, r, 0.01 * r), rel=1e-9)


def test_a_level_float32_stl_floor_tilted_across_the_periodic_axis_is_accepted(tmp_path):
    """A floor z = -0.1 + y tan 0.3 (true n_x = 0) of irregular 2 mm triangles over a 0.2 m
    period in x (a strip 2 cm wide), written as binary STL and read back: float32 rounding of each vertex (7 nm at
    |z| = 0.1 m) tilts the faces by up to ~8e-6 along x, a "rise" over the period of 1.7 um,
    beyond the 0.3 um limit, so the floor was refused though both boundary sections agree to
    float32 rounding.  That rounding is forgiven: the floor is accepted and a 1.5 mm sphere
    pressed 0.01 R into it feels the Hertz force on both sides of the boundary."""
    from scipy.spatial import Delaunay

    from soilcal.dem.stl import read_stl, write_stl

    mats = table(e=0.5, mu=0.3, E=1e8)
    L, W, h, a, r = 0.2, 0.02, 2e-3, 0.3, 1.5e-3
    rng = np.random.default_rng(1)
    X, Y = np.meshgrid(np.linspace(-0.01, L + 0.01, 111), np.linspace(0, W, 11), indexing="ij")
    X, Y = X.ravel(), Y.ravel()
    inner = (X > X.min()) & (X < X.max()) & (Y > 0) & (Y < W)
    X[inner] += h * rng.uniform(-0.3, 0.3, inner.sum())
    Y[inner] += h * rng.uniform(-0.3, 0.3, inner.sum())
    write_stl(tmp_path / "floor.stl", np.c_[X, Y, -0.1 + Y * math.tan(a)], Delaunay(np.c_[X, Y]).simplices)
    v, t = read_stl(tmp_path / "floor.stl")
    n = np.array([0.0, -math.sin(a), math.cos(a)])
    for x in (L - 1e-4, 1e-4):
        sim = Simulation(mats, gravity=(0, 0, 0), box=(0, L, 0, W), periodic=(True, False))
        sim.add_mesh(v, t, "soil", name="floor")
        y = W / 2
        sim.add_particles([np.array([x, y, -0.1 + y * math.tan(a)]) + 0.99 * r * n], r, "soil")
        f = np.linalg.norm(sim.compute_forces()[0][0])
        assert f == pytest.approx(_hertz_wall_force(mats, r, 0.01 * r), rel=2e-3)


@pytest.mark.parametrize("stone_first", [False, True])
def test_a_floor_of_small_faces_rising_over_the_period_beside_a_large_stone_is_refused(
        stone_first):
    """A floor z = 0.1 + 1.5e-5 x of 2 mm right triangles over a 0.2 m period in x rises 3 um
    over the period, 10 times the limit 2e-4 R_min = 0.3 um (R_min = 1.5 mm): a sphere pressed
    0.01 R = 15 um into it just inside x = L lands 3 um shallower after crossing the boundary
    (Hertz: (12/15)^1.5, 28 % less force).  Each face's own tilt is below what float32
    rounding of its vertices could give (1.8e-5 at z = 0.1 m), so the faces were forgiven,
    and with a 20 mm stone in the box the sections at both ends were compared within
    2e-4 R_max = 4 um: the floor was accepted.  The step between the two ends is judged
    against R_min as a plane's rise is: refused, naming the wall, also when the small spheres
    are added after a run with the stone alone (the wall's answer was kept from that run,
    when R_min was the stone's 20 mm).  Level, it is accepted, and a sphere pressed 0.01 R
    into it just inside x = L and one at the same height just past x = 0 (the first wrapped
    across the boundary) both feel the Hertz force of that overlap."""
    L, W, h, r = 0.2, 0.02, 2e-3, 1.5e-3
    nx, ny = int(round((L + 0.02) / h)) + 1, int(round(W / h)) + 1
    X, Y = np.meshgrid(np.linspace(-0.01, L + 0.01, nx), np.linspace(0, W, ny), indexing="ij")
    i = np.arange(nx * ny).reshape(nx, ny)
    a, b, c, d = i[:-1, :-1].ravel(), i[1:, :-1].ravel(), i[1:, 1:].ravel(), i[:-1, 1:].ravel()
    tri = np.r_[np.c_[a, b, c], np.c_[a, c, d]]
    mats = table(e=0.5, mu=0.3, E=1e8)
    for slope in (1.5e-5, 0.0):
        sim = Simulation(mats, gravity=(0, 0, 0), box=(0, L, 0, W), periodic=(True, False))
        v = np.c_[X.ravel(), Y.ravel(), 0.1 + slope * X.ravel()]
        # rising, as a binary STL stores it (float32): each face's tilt within its rounding
        sim.add_mesh(v.astype(np.float32) if slope else v, tri, "soil", name="floor")
        sim.add_particles([(L / 2, W / 2, 0.15)], 0.02, "soil")
        if stone_first:
            sim.compute_forces()
        z = 0.1 + slope * L + 0.99 * r
        sim.add_particles([(L - 1e-4, 0.005, z), (1e-4, 0.015, z)], r, "soil")
        if slope:
            with pytest.raises(InputError, match=r"walls\.floor.*one period away.*a step") as err:
                sim.compute_forces()
            # the limit printed is the one the text names: 2e-4 R_min = 3e-7 m (4 float32
            # ulps of coordinates up to 0.21 m, 8 x 2^-24 x 0.21 m = 1e-7 m, are smaller)
            m = re.search(r"within (\S+) m \(max\(2e-4 R_min = (\S+) m, 4 ulps of the "
                          r"coordinates as stored = (\S+) m\)", str(err.value))
            assert m is not None, str(err.value)
            assert float(m[1]) == float(m[2]) == pytest.approx(2e-4 * r, rel=1e-3)
            assert float(m[3]) == pytest.approx(8 * 2.0 ** -24 * (L + 0.01), rel=5e-3)
        else:
            f = np.linalg.norm(sim.compute_forces()[0][sim.p.r == r], axis=1)
            assert f == pytest.approx([_hertz_wall_force(mats, r, 0.01 * r)] * 2, rel=1e-6)


def test_the_refusal_of_a_mesh_names_the_face_tilted_along_the_periodic_axis():
    """A level floor (triangles 0 and 2) over a 0.04 m period in x and, between them in the
    mesh, triangle 1: a wedge z = 0.025 x on the boundary x = 0 (unit normal (-0.025, 0, 1) /
    sqrt(1 + 0.025^2), a rise of 0.025 L = 1 mm over the period).  The refusal named the wall
    only; it names the triangle, its normal and its rise."""
    L = 0.04
    v = [[-0.004, 0, 0], [L + 0.004, 0, 0], [L + 0.004, 0.02, 0], [-0.004, 0.02, 0],
         [0, 0.004, 0], [0.004, 0.004, 1e-4], [0, 0.008, 0]]
    sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0), box=(0, L, 0, 0.02),
                     periodic=(True, False))
    sim.add_mesh(v, [[0, 1, 2], [4, 5, 6], [0, 2, 3]], "soil", name="floor")
    sim.add_particles([(L / 2, 0.01, 2e-3)], 1e-3, "soil")
    with pytest.raises(InputError, match=r"walls\.floor") as err:
        sim.compute_forces()
    m = re.search(r"face (\d+) of its (\d+) as added \(triangle, normal \(([^)]*)\), rising (\S+) m over "
                  r"the period\)", str(err.value))
    assert m is not None, str(err.value)
    assert (int(m[1]), int(m[2])) == (1, 3)
    n = np.abs([float(c) for c in m[3].split(",")])
    assert n == pytest.approx(np.array([0.025, 0.0, 1.0]) / math.hypot(1, 0.025), abs=1e-6)
    assert float(m[4]) == pytest.approx(0.025 * L, rel=1e-3)


def test_the_refusal_of_an_stl_mesh_names_the_facet_of_the_file(tmp_path):
    """The mesh above written as an STL file whose first facet is a sliver (three corners on
    one line, as CAD exports write): read_stl leaves it out, so the wedge, the file's facet 2
    of 4, is triangle 1 of the 3 read.  Read with facets=True and added with them, the
    refusal names facet 2 of the file (it named only "face 1 of its 3")."""
    from soilcal.dem.stl import read_stl, write_stl

    L = 0.04
    v = np.array([[-0.004, 0, 0], [L + 0.004, 0, 0], [L + 0.004, 0.02, 0], [-0.004, 0.02, 0],
                  [0, 0.004, 0], [0.004, 0.004, 1e-4], [0, 0.008, 0],
                  [0.01, 0.01, 0], [0.02, 0.01, 0], [0.03, 0.01, 0]])
    path = tmp_path / "floor.stl"
    write_stl(path, v, np.array([[7, 8, 9], [0, 1, 2], [4, 5, 6], [0, 2, 3]]))
    V, T, facets = read_stl(path, facets=True)
    assert facets.tolist() == [1, 2, 3]
    sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0), box=(0, L, 0, 0.02),
                     periodic=(True, False))
    sim.add_mesh(V, T, "soil", name="floor", facets=facets)
    sim.add_particles([(L / 2, 0.01, 2e-3)], 1e-3, "soil")
    with pytest.raises(InputError, match=r"walls\.floor") as err:
        sim.compute_forces()
    m = re.search(r"facet (\d+) of its STL file, face (\d+) of its (\d+) as added \(triangle, "
                  r"normal \(([^)]*)\), rising (\S+) m", str(err.value))
    assert m is not None, str(err.value)
    assert (int(m[1]), int(m[2]), int(m[3])) == (2, 1, 3)
    assert float(m[5]) == pytest.approx(0.025 * L, rel=1e-3)
    with pytest.raises(InputError, match=r"walls\.mesh\.facets"):
        sim.add_mesh(V, T, "soil", facets=[0, 1])


@pytest.mark.parametrize("kind", ["plane", "rod"])
def test_a_wall_tilted_along_the_periodic_axis_by_a_step_a_contact_feels_is_refused(kind):
    """A plane or a rod along x tilted by 1.5e-4 rad in a box periodic in x (L = 0.04 m)
    rises 6 um over the period: a sphere (R = 5 mm) pressed 0.01 R into it just inside x = L
    and, after crossing the boundary at the same height, just inside x = 0 felt 2.00 N and
    then 1.67 N (the Hertz forces of overlaps 3 um more and less than 0.01 R).  Both were
    accepted (a tilt under 2e-4 counted as none, the rod's section taken at its axis point);
    they are refused, naming the wall.  Tilted by 1e-5 rad (a rise of 0.4 um, under 2e-4 R =
    1 um) each is accepted and pushes with the Hertz force of its own overlap there."""
    mats = table(e=0.5, mu=0.3, E=1e8)
    z = (0.0 if kind == "plane" else 0.06) + R - _D
    for tilt, refused in ((1.5e-4, True), (1e-5, False)):
        add, dist = _tilted(kind, tilt)
        for x in ((_L - 1e-4, 0.05, z), (1e-4, 0.05, z)):
            sim = Simulation(mats, gravity=(0, 0, 0), box=(0, _L, 0, 0.1), periodic=(True, False))
            add(sim)
            sim.add_particles([x], R, "soil")
            if refused:
                with pytest.raises(InputError, match=r"walls\.w.*periodic in x"):
                    sim.compute_forces()
            else:
                f = np.linalg.norm(sim.compute_forces()[0][0])
                assert f == pytest.approx(_hertz_wall_force(mats, R, R - dist(x)), rel=1e-6)


def _far_floor(rise):
    """A floor z = 0.1 + rise (x - 100) / 0.2 over x = 100 .. 100.2 m, y = 0 .. 0.02 m."""
    X, Y = np.meshgrid(np.linspace(100.0, 100.2, 3), [0.0, 0.02])
    v = np.c_[X.ravel(), Y.ravel(), 0.1 + rise * (X.ravel() - 100.0) / 0.2]
    return v, np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]])


def _far_sim():
    sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0), box=(100.0, 100.2, 0, 0.02),
                     periodic=(True, False))
    sim.add_particles([(100.1, 0.01, 0.101)], 1e-3, "soil")
    return sim


@pytest.mark.parametrize("how", ["array", "ascii", "binary"])
def test_a_floor_far_from_the_origin_is_forgiven_the_rounding_of_its_storage_only(how, tmp_path):
    """A floor over x = 100 .. 100.2 m rising 20 um over the period: a sphere of R = 1 mm
    crossing the boundary lands 20 um deeper or shallower (its 0.01 R overlap doubled or
    gone), 100 times the limit 2e-4 R_min = 0.2 um.  Four float32 ulps at x = 100 m are
    8 x 2^-24 x 100 m = 48 um, which was forgiven whatever the mesh was stored in: the floor
    was accepted.  Given as float64 arrays, or as an ASCII STL whose numbers carry 17
    digits, it is refused; written as binary STL (float32 vertices: 100.1 m is stored 3.1 um
    off, so a face's rise of 20 um is within the rounding) it is accepted."""
    from soilcal.dem.stl import write_stl

    v, t = _far_floor(20e-6)
    sim = _far_sim()
    if how == "array":
        sim.add_mesh(v, t, "soil", name="floor")
    else:
        write_stl(tmp_path / "f.stl", v, t, binary=how == "binary")
        sim.add_stl(tmp_path / "f.stl", "soil", name="floor")
    if how == "binary":
        sim.compute_forces()
    else:
        with pytest.raises(InputError, match=r"walls\.floor.*rising 2(\.\d*)?e-05 m over the period"):
            sim.compute_forces()
    # level, it is accepted whichever way it was given
    sim = _far_sim()
    sim.add_mesh(*_far_floor(0.0), "soil", name="floor")
    sim.compute_forces()


def test_read_stl_gives_vertices_the_type_their_file_stored_them_in(tmp_path):
    """Binary STL: float32 vertices (scaled in float32, so add_mesh forgives them float32's
    rounding, 2^-24 |x|); ASCII: its numbers taken as written, float64 whatever format wrote
    them (%e, %f, integers), scaled or not."""
    from soilcal.dem.stl import read_stl, write_stl

    v = np.array([[100.0, 0.0, 0.1], [100.2, 0.0, 0.1], [100.0, 0.02, 0.1]])
    t = np.array([[0, 1, 2]])
    write_stl(tmp_path / "b.stl", v, t)
    vb = read_stl(tmp_path / "b.stl")[0]
    assert vb.dtype == np.float32
    assert np.array_equal(np.unique(vb, axis=0), np.unique(v.astype(np.float32), axis=0))
    vm = read_stl(tmp_path / "b.stl", scale=1e-3)[0]
    assert vm.dtype == np.float32
    assert vm.astype(float) == pytest.approx(1e-3 * vb.astype(float), rel=1e-7)
    for fmt in ("{:.6e}", "{:.4f}", "{!r}"):
        lines = ["solid s", "facet normal 0 0 1", "outer loop"]
        lines += ["vertex " + " ".join(fmt.format(float(c)) for c in p) for p in v]
        lines += ["endloop", "endfacet", "endsolid s"]
        (tmp_path / "a.stl").write_text("\n".join(lines) + "\n")
        for scale in (1.0, 1e-3):
            va = read_stl(tmp_path / "a.stl", scale=scale)[0]
            assert va.dtype == np.float64
            assert np.unique(va, axis=0) == pytest.approx(np.unique(scale * v, axis=0), rel=1e-6)


@pytest.mark.parametrize("rise, accepted", [(40e-6, True), (60e-6, False)])
def test_a_welded_binary_stl_is_forgiven_float32_rounding_of_its_kept_corners(rise, accepted,
                                                                               tmp_path):
    """The floor over x = 100 .. 100.2 m written as a binary STL soup whose later copies of
    each corner lie up to 10 um off in x and y (as CAD exports write them), welded with
    weld_tol = 0.1 mm into its 6 corners: a face may rise over the period by 4 float32
    ulps of its largest coordinate, 8 x 2^-24 x 100.2 m = 47.8 um.  Rising 40 um it is
    accepted, 60 um refused."""
    from soilcal.dem.stl import read_stl, write_stl

    v, t = _far_floor(rise)
    soup = v[t].reshape(-1, 3)
    later = np.zeros(len(soup), dtype=bool)
    later[[k for k in range(len(soup)) if t.ravel()[k] in t.ravel()[:k]]] = True
    soup[later, :2] += np.random.default_rng(3).uniform(-1e-5, 1e-5, (int(later.sum()), 2))
    write_stl(tmp_path / "f.stl", soup, np.arange(len(soup)).reshape(-1, 3))
    assert len(read_stl(tmp_path / "f.stl")[0]) == 12  # the copies apart: 6 + 6
    assert len(read_stl(tmp_path / "f.stl", weld_tol=1e-4)[0]) == 6
    sim = _far_sim()
    sim.add_stl(tmp_path / "f.stl", "soil", name="floor", weld_tol=1e-4)
    if accepted:
        sim.compute_forces()
    else:
        # its end sections a step of 60 um apart, more than 8 x 2^-24 x 100.2 m
        with pytest.raises(InputError, match=r"walls\.floor.*within 4\.78e-05 m"):
            sim.compute_forces()


def test_a_welded_binary_stl_stores_the_float32_rounding_of_each_faces_kept_corners(tmp_path):
    """The rule pinned: a face of a binary STL keeps, as its rounding, float32's unit
    roundoff 2^-24 |x| of the largest coordinate among its corners as stored, and where
    copies of a corner were welded (weld_tol) the kept one is the first in the file, so it is
    the first copy's coordinate that counts, not the largest over the copies.  A level
    floor z = 0.5 m over x = 100 .. 100.25 m in two columns (x = 100, 100.125, 100.25), y = 0
    .. 0.25 m, all numbers exact in float32; every later copy of a corner lies 2^-14 m (61
    um, exact in float32 there) further in x, welded with weld_tol = 0.1 mm.  The first
    column's faces keep 2^-24 x 100.125 m, the second's 2^-24 x 100.25 m (the copies' 2^-24 x
    (x + 2^-14) would be larger by 2^-38 m)."""
    from soilcal.dem.stl import write_stl

    xs, shift = np.array([100.0, 100.125, 100.25]), 2.0 ** -14
    X, Y = np.meshgrid(xs, [0.0, 0.25])
    v = np.c_[X.ravel(), Y.ravel(), np.full(6, 0.5)]
    t = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]])
    soup = v[t].reshape(-1, 3)
    later = np.array([t.ravel()[k] in t.ravel()[:k] for k in range(t.size)])
    soup[later, 0] += shift
    assert np.array_equal(soup.astype(np.float32).astype(float), soup)  # as the file holds it
    write_stl(tmp_path / "f.stl", soup, np.arange(len(soup)).reshape(-1, 3))
    sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0))
    sim.add_particles([(100.1, 0.1, 0.6)], 1e-3, "soil")
    w = sim.add_stl(tmp_path / "f.stl", "soil", name="floor", weld_tol=1e-4)
    assert sim.walls.names[w] == "floor"
    # each face its facet of the file (all four have area); its kept corners: the first copies
    kept = 2.0 ** -24 * np.array([100.125, 100.125, 100.25, 100.25])
    assert np.array_equal(sim._mesh_rounding[w], kept)


def _slab_floor(rise, L=0.1, W=0.02):
    """Two triangles z = rise x / L over x = 0 .. L, y = 0 .. W (a floor rising ``rise``
    over a period L along x)."""
    v = np.array([[0, 0, 0], [L, 0, rise], [L, W, rise], [0, W, 0]], float)
    return v, np.array([[0, 1, 2], [0, 2, 3]])


def _slab_sim(L=0.1, W=0.02, periodic=(True, True)):
    sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0), box=(0, L, 0, W),
                     periodic=periodic)
    sim.add_particles([(L / 2, W / 2, 0.002)], 1e-3, "soil")
    return sim


def test_a_coarsely_stored_mesh_loosens_no_other_walls_periodic_checks():
    """A plate across x (normal along x) at x = 0.98 mm in a box periodic in x, 20 um within
    the largest radius (1 mm) of the boundary x = 0: a sphere at x = 0.09999 m meets the
    plate's image 0.99 mm away, an overlap of 10 um (0.01 R) that wall contacts do not see,
    so the plate is refused.  A block in the middle of the box stored as float32 at z = 100 m (2^-24 x 100 m
    = 6e-6 m per vertex, eight of which, 4.8e-5 m, were once the tolerance of every face)
    let the plate count as clear of the boundary: its rounding is its own faces'."""
    from soilcal.dem.geometry import box_mesh

    pv = np.array([[9.8e-4, 0, 0], [9.8e-4, 0.02, 0], [9.8e-4, 0.02, 0.01], [9.8e-4, 0, 0.01]])
    bv, bt = box_mesh((0.04, 0.005, 100.0), (0.06, 0.015, 100.01))
    for block in (True, False):
        sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0), box=(0, 0.1, 0, 0.02),
                         periodic=(True, False))
        sim.add_particles([(0.09999, 0.01, 0.005)], 1e-3, "soil")
        sim.add_mesh(pv, [[0, 1, 2], [0, 2, 3]], "soil", name="plate")
        if block:
            sim.add_mesh(np.asarray(bv, np.float32), np.asarray(bt), "soil", name="block")
        with pytest.raises(InputError, match=r"walls\.plate") as e:
            sim.compute_forces()
        if not block:
            # the plate's faces cross the axis: named as such, not as a rise of 1e6 m
            assert "at 90 degrees to the x axis" in str(e.value)
            assert "rising" not in str(e.value)


def test_a_walls_own_rounding_never_makes_it_clear_of_a_periodic_boundary():
    """The same plate at x = 0.98 mm, itself stored as float32 at z = 100 m (a rounding of
    6e-6 m per vertex, 4.8e-5 m for 4 ulps): it counted as clear of the boundary within its
    own rounding and was accepted, while a sphere at x = 0.09999 m overlaps its image by
    10 um (0.01 R).  Whether a wall is clear is judged to float64's rounding of the box only."""
    pv = np.array([[9.8e-4, 0, 99.995], [9.8e-4, 0.02, 99.995], [9.8e-4, 0.02, 100.005],
                   [9.8e-4, 0, 100.005]], np.float32)
    sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0), box=(0, 0.1, 0, 0.02),
                     periodic=(True, False))
    sim.add_particles([(0.09999, 0.01, 100.0)], 1e-3, "soil")
    sim.add_mesh(pv, [[0, 1, 2], [0, 2, 3]], "soil", name="plate")
    with pytest.raises(InputError, match=r"walls\.plate"):
        sim.compute_forces()


@pytest.mark.parametrize("rounding", [1e-4, 5e-4])
def test_a_declared_rounding_forgives_no_more_than_the_periodic_step(rounding):
    """A floor rising 5 mm over a 0.1 m period (R = 1 mm) and a plate across x 0.5 mm inside
    x = 0 were accepted when added with rounding=5e-4 (the plate also with 1e-4): 8 x the
    rounding was forgiven as a rise and as clearance.  A rounding whose 4 ulps exceed the
    2e-4 R_min step the periodic checks allow is refused, naming the field; one within it
    keeps a level floor accepted."""
    floor = np.array([[0, 0, 0], [0.1, 0, 0.005], [0.1, 0.02, 0.005], [0, 0.02, 0]])
    plate = np.array([[5e-4, 0, 0], [5e-4, 0.02, 0], [5e-4, 0.02, 0.01], [5e-4, 0, 0.01]])
    for v, x in ((floor, (0.0995, 0.01, 0.0059)), (plate, (0.0995, 0.01, 0.005))):
        sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0),
                         box=(0, 0.1, 0, 0.02), periodic=(True, False))
        sim.add_particles([x], 1e-3, "soil")
        sim.add_mesh(v, [[0, 1, 2], [0, 2, 3]], "soil", name="w", rounding=rounding)
        with pytest.raises(InputError, match=r"walls\.w\.rounding.*at most 2\.5e-5 R_min"):
            sim.compute_forces()
    level = floor * [1, 1, 0]
    sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0), box=(0, 0.1, 0, 0.02),
                     periodic=(True, False))
    sim.add_particles([(0.0995, 0.01, 0.0009)], 1e-3, "soil")
    sim.add_mesh(level, [[0, 1, 2], [0, 2, 3]], "soil", name="w", rounding=2e-8)
    sim.compute_forces()


def test_a_refused_rise_names_the_remedy_for_a_float32_mesh_made_float64():
    """A mesh face refused for its rise over the period tells how a binary STL's float32
    allowance is kept (a float32 mesh moved with float64 numbers is judged as float64)."""
    floor = np.array([[0, 0, 0], [0.1, 0, 0.005], [0.1, 0.02, 0.005], [0, 0.02, 0]])
    sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0), box=(0, 0.1, 0, 0.02),
                     periodic=(True, False))
    sim.add_particles([(0.0995, 0.01, 0.0059)], 1e-3, "soil")
    sim.add_mesh(floor, [[0, 1, 2], [0, 2, 3]], "soil", name="w")
    with pytest.raises(InputError, match=r"walls\.w.*astype\(np\.float32\).*add_stl"
                                         r"\(scale=\).*rounding="):
        sim.compute_forces()


def test_grouped_walls_are_held_to_the_strictest_of_their_own_limits():
    """A floor (float64) whose section at x = 0.1 m stands 20 um above the one at x = 0
    (R = 1 mm: a sphere crossing the boundary lands 20 um deeper, twice its 0.01 R overlap)
    is refused alone.  With an unrelated ridge stored as float32 at z = 100 m (4 ulps: 4.8e-5
    m) beside it, the two were re-checked as one surface within the ridge's limit and the
    floor accepted; the group is now held to each wall's own, the floor's."""
    from soilcal.dem.geometry import box_mesh

    step = 2e-5
    fv = np.array([[0, 0, 0], [0.05, 0, 0], [0.05, 0.01, 0], [0, 0.01, 0],
                   [0.05, 0, step], [0.1, 0, step], [0.1, 0.01, step], [0.05, 0.01, step]])
    bv, bt = box_mesh((0.0, 0.015, 100.0), (0.1, 0.02, 100.01))
    for ridge in (False, True):
        sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0), dt=1e-6,
                         box=(0, 0.1, 0, 0.02), periodic=(True, False))
        sim.add_particles([(0.0999, 0.005, step + 0.0009)], 1e-3, "soil")
        sim.add_mesh(fv, [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]], "soil", name="floor")
        if ridge:
            sim.add_mesh(np.asarray(bv, np.float32), np.asarray(bt), "soil", name="ridge")
        with pytest.raises(InputError, match=r"walls\.floor.*not those one period away"):
            sim.compute_forces()


@pytest.mark.parametrize("rise", [1e-3, 2e-5])
def test_an_ascii_stl_is_taken_as_written_not_as_rounded_to_its_shortest_number(rise, tmp_path):
    """A floor rising 1 mm (or 20 um) over a 0.1 m period, R = 1 mm: a sphere crossing the
    boundary lands that much deeper, 5 (0.1) times its 0.01 R overlap.  Written by
    write_stl(binary=False) (repr: '0.1', '0.001', '2e-05') its numbers were taken as rounded
    to their last digit (up to 0.05 m) and the floor was accepted by add_stl; as arrays it
    was refused.  Now it is refused both ways; a level floor written so is accepted, and a
    rounding the user declares (rounding=) that would forgive the rise (8 x rounding beyond
    the 2e-4 R_min step allowed) is refused, naming the field."""
    from soilcal.dem.stl import write_stl

    write_stl(tmp_path / "f.stl", *_slab_floor(rise), binary=False)
    sim = _slab_sim()
    sim.add_stl(tmp_path / "f.stl", "soil", name="floor")
    with pytest.raises(InputError, match=r"walls\.floor.*rising"):
        sim.compute_forces()
    write_stl(tmp_path / "g.stl", *_slab_floor(0.0), binary=False)
    sim = _slab_sim()
    sim.add_stl(tmp_path / "g.stl", "soil", name="floor")
    sim.compute_forces()
    # declared: stored to within `rise`, far beyond the step a sphere of 1 mm tolerates
    sim = _slab_sim()
    sim.add_stl(tmp_path / "f.stl", "soil", name="floor", rounding=rise)
    with pytest.raises(InputError, match=r"walls\.floor\.rounding"):
        sim.compute_forces()


def test_an_integer_millimetre_ascii_stl_rising_3_mm_is_refused(tmp_path):
    """A CAD floor written in whole millimetres, 400 x 40 mm at z = 100 mm, read with
    scale=1e-3 into a box periodic over 0.4 m: z = 103 mm at x = 400 mm is a rise of 3 mm over
    the period (a 1 mm sphere crossing lands 3 mm deep), refused; it was forgiven as
    rounding of 0.5 mm (the integers' last digit).  z = 100 everywhere is accepted."""
    for top, ok in (("100", True), ("103", False)):
        P = [("0", "0", "100"), ("400", "0", top), ("400", "40", top), ("0", "40", "100")]
        lines = ["solid floor"]
        for tri in ((0, 1, 2), (0, 2, 3)):
            lines += ["facet normal 0 0 1", "outer loop"]
            lines += ["vertex " + " ".join(P[k]) for k in tri] + ["endloop", "endfacet"]
        (tmp_path / "f.stl").write_text("\n".join(lines + ["endsolid floor"]) + "\n")
        sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0), box=(0, 0.4, 0, 0.04),
                         periodic=(True, True))
        sim.add_particles([(0.2, 0.02, 0.102)], 1e-3, "soil")
        sim.add_stl(tmp_path / "f.stl", "soil", scale=1e-3, name="floor")
        if ok:
            sim.compute_forces()
        else:
            with pytest.raises(InputError, match=r"walls\.floor.*rising 0\.003 m"):
                sim.compute_forces()


def test_a_millimetre_binary_stl_read_and_scaled_keeps_float32s_allowance(tmp_path):
    """A level floor (along x) of 4 mm triangles with jittered corners at z = 100 mm + 0.1 y,
    written as binary STL in millimetres: float32 rounds each corner by up to 2^-24 |x|,
    tilting small faces by a few 1e-6.  Read with read_stl(scale=1e-3) (or read and then
    multiplied by 1e-3) and given to add_mesh it was refused for that noise (a rise of
    4.6e-7 m against 2e-7 m: float64 arrays were judged as float64); read_stl now returns a
    binary file's float32 numbers, scaled in float32, and the floor is accepted as add_stl
    accepts it.  The same floor rising 20 um over the period is refused all ways."""
    from soilcal.dem.stl import read_stl, write_stl

    rng = np.random.default_rng(1)
    xs, ys = np.arange(0, 400.001, 4.0), np.arange(0, 40.001, 4.0)
    X, Y = (a.copy() for a in np.meshgrid(xs, ys))
    inner = (X > 0) & (X < 400) & (Y > 0) & (Y < 40)
    X[inner] += rng.uniform(-1, 1, inner.sum())
    Y[inner] += rng.uniform(-1, 1, inner.sum())
    nx, ny = len(xs), len(ys)
    t = np.array([[j * nx + i, j * nx + i + 1, j * nx + i + nx + 1] for j in range(ny - 1)
                  for i in range(nx - 1)] + [[j * nx + i, j * nx + i + nx + 1, j * nx + i + nx]
                                             for j in range(ny - 1) for i in range(nx - 1)])
    for rise_mm, ok in ((0.0, True), (0.02, False)):
        v = np.c_[X.ravel(), Y.ravel(), 100.0 + 0.1 * Y.ravel() + rise_mm * X.ravel() / 400]
        write_stl(tmp_path / "f.stl", v, t, binary=True)
        for how in ("scale", "times", "add_stl"):
            sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0),
                             box=(0, 0.4, 0, 0.04), periodic=(True, False))
            sim.add_particles([(0.2, 0.02, 0.2)], 1e-3, "soil")
            if how == "scale":
                sim.add_mesh(*read_stl(tmp_path / "f.stl", scale=1e-3), "soil", name="floor")
            elif how == "times":
                vv, tt = read_stl(tmp_path / "f.stl")
                sim.add_mesh(vv * 1e-3, tt, "soil", name="floor")
            else:
                sim.add_stl(tmp_path / "f.stl", "soil", scale=1e-3, name="floor")
            if ok:
                sim.compute_forces()
            else:
                with pytest.raises(InputError, match=r"walls\.floor"):
                    sim.compute_forces()


@pytest.mark.parametrize("rise", [2.0 ** -15, 3.0e-5])
def test_float64_vertices_are_judged_as_float64_whatever_numbers_they_hold(rise):
    """A floor over x = 100 .. 100.25 m rising ~30 um over the period (R = 1 mm: 30 times
    the 2e-4 R_min limit): as float64 arrays it is refused whether or not its numbers happen
    to be float32 numbers (2^-15 is one; it was accepted with float32's 48 um allowance);
    as float32 arrays (a binary STL's storage, 100 m rounded by up to 6 um) it is within
    float32's allowance and accepted."""
    v = np.array([[100, 0, 0.0], [100.25, 0, rise], [100.25, 0.03125, rise],
                  [100, 0.03125, 0.0]], float)
    for dtype in (np.float64, np.float32):
        sim = Simulation(table(e=0.5, mu=0.3, E=1e8), gravity=(0, 0, 0),
                         box=(100, 100.25, 0, 0.03125), periodic=(True, True))
        sim.add_particles([(100.1, 0.015, 1e-3)], 1e-3, "soil")
        sim.add_mesh(v.astype(dtype), [[0, 1, 2], [0, 2, 3]], "soil", name="floor")
        if dtype == np.float32:
            sim.compute_forces()
        else:
            with pytest.raises(InputError, match=r"walls\.floor.*rising"):
                sim.compute_forces()


def test_add_stl_refuses_facets_it_sets_itself(tmp_path):
    """add_stl numbers refused faces by the file's facets itself: a facets= passed on to
    add_mesh raised a TypeError (a duplicate argument); it is refused by name."""
    from soilcal.dem.stl import write_stl

    write_stl(tmp_path / "f.stl", *_slab_floor(0.0))
    sim = _slab_sim()
    with pytest.raises(InputError, match=r"f\.stl.*facets"):
        sim.add_stl(tmp_path / "f.stl", "soil", facets=[0, 1])



@pytest.mark.parametrize("bad", [[1e-9, 1e-9], -1e-9, float("nan"), "1e-9", True])
def test_a_mesh_rounding_that_is_not_one_distance_per_vertex_is_refused(bad):
    sim = _far_sim()
    v, t = _far_floor(0.0)
    with pytest.raises(InputError, match=r"walls\.mesh\.rounding.*one distance >= 0"):
        sim.add_mesh(v, t, "soil", rounding=bad)


def test_an_end_face_bridging_the_gap_between_two_bars_on_the_boundary_is_refused():
    """Two bars along x spanning the period (y 0.01 .. 0.02 and 0.03 .. 0.04 m, z 0 .. 0.01
    m), their end faces on x = 0 and x = L, and on each boundary one more end triangle with
    corners (y, z) = (0.01, 0), (0.04, 0), (0.04, 0.002) m: each corner lies on a bar's
    outline, but the triangle spans the open gap y 0.02 .. 0.03 between them.  A 1 mm sphere
    in that gap beside x = 0, touching nothing of the periodic bars, was pushed by that face
    (8.3 N along x).  The face is refused, naming the point (0.025, 0) of its edge outside
    both outlines; without the bridging triangles the bars are accepted and the sphere feels
    nothing."""
    L = 0.1

    def bar(y0, y1, z0=0.0, z1=0.01):
        out = []
        for (ya, za), (yb, zb) in (((y0, z0), (y1, z0)), ((y1, z0), (y1, z1)),
                                   ((y1, z1), (y0, z1)), ((y0, z1), (y0, z0))):
            out += _quad([0, ya, za], [L, ya, za], [L, yb, zb], [0, yb, zb])
        return out

    for bridge in (True, False):
        tris = bar(0.01, 0.02) + bar(0.03, 0.04)
        for x in (0.0, L):
            tris += _quad([x, 0.01, 0], [x, 0.02, 0], [x, 0.02, 0.01], [x, 0.01, 0.01])
            tris += _quad([x, 0.03, 0], [x, 0.04, 0], [x, 0.04, 0.01], [x, 0.03, 0.01])
            if bridge:
                tris += [[[x, 0.01, 0.0], [x, 0.04, 0.0], [x, 0.04, 0.002]]]
        tris = np.array(tris, float)
        sim = Simulation(table(E=1e8), gravity=(0, 0, 0), box=(0, L, 0, 0.05),
                         periodic=(True, False))
        sim.add_particles([[0.0005, 0.025, 0.0015]], 1e-3, "soil")
        sim.add_mesh(tris.reshape(-1, 3), np.arange(tris.shape[0] * 3).reshape(-1, 3), "soil",
                     name="bars")
        if bridge:
            with pytest.raises(InputError, match=r"walls\.bars.*an edge \(bridging open space.*"
                               r"\(y, z\) = \(0\.025, 0\) m"):
                sim.compute_forces()
        else:
            assert np.all(sim.compute_forces()[0][0] == 0)
