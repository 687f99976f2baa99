"""Closest-point kernels, rigid motion and mesh builders against analytic geometry."""

import math

import numpy as np
import pytest

from soilcal.dem import geometry as g

O = np.zeros(3)
EZ = np.array([0.0, 0.0, 1.0])


def arr(*x):
    return np.array(x, dtype=np.float64)


# ---------------------------------------------------------------- planes


def test_plane_signed_distance_and_contact_point():
    r = g.plane_closest(arr(1.0, 2.0, 0.7), arr(0.0, 0.0, 0.2), EZ)
    assert r[0] == pytest.approx(0.5)
    assert r[1:4] == (0.0, 0.0, 1.0)
    assert r[4:] == pytest.approx((1.0, 2.0, 0.2))
    assert g.plane_closest(arr(0, 0, -0.3), O, EZ)[0] == pytest.approx(-0.3)


def test_rectangle_face_and_rim():
    # 2 x 1 rectangle in the z = 0 plane, u along x
    c, n, u = O, EZ, arr(1, 0, 0)
    r = g.rectangle_closest(arr(0.5, 0.2, 0.3), c, n, u, 1.0, 0.5)
    assert r[0] == pytest.approx(0.3) and r[4:] == pytest.approx((0.5, 0.2, 0.0))
    # beyond the x = 1 edge: closest point on the edge, distance hypot(0.4, 0.3)
    r = g.rectangle_closest(arr(1.4, 0.1, 0.3), c, n, u, 1.0, 0.5)
    assert r[0] == pytest.approx(0.5)
    assert r[4:] == pytest.approx((1.0, 0.1, 0.0))
    assert r[1:4] == pytest.approx((0.8, 0.0, 0.6))


def test_disk_and_rectangle_back_side():
    # thin walls have two sides: below a disk or rectangle facing +z the distance is
    # positive and the normal points down, towards the point
    r = g.disk_closest(arr(0.3, 0.4, -0.1), O, EZ, 1.0)
    assert r[0] == pytest.approx(0.1) and r[1:4] == pytest.approx((0, 0, -1))
    assert r[4:7] == pytest.approx((0.3, 0.4, 0.0))
    r = g.rectangle_closest(arr(0.5, 0.2, -0.3), O, EZ, arr(1, 0, 0), 1.0, 0.5)
    assert r[0] == pytest.approx(0.3) and r[1:4] == pytest.approx((0, 0, -1))


def test_disk_face_and_rim():
    r = g.disk_closest(arr(0.3, 0.4, 0.1), O, EZ, 1.0)
    assert r[0] == pytest.approx(0.1)
    # point at radial distance 2, height 1: rim point at radius 1, distance sqrt(2)
    r = g.disk_closest(arr(0.0, 2.0, 1.0), O, EZ, 1.0)
    assert r[0] == pytest.approx(math.sqrt(2.0))
    assert r[4:] == pytest.approx((0.0, 1.0, 0.0))


# ---------------------------------------------------------------- cylinder / cone


@pytest.mark.parametrize("r", [0.0, 0.3, 0.9])
def test_point_inside_drum_distance_is_R_minus_r(r):
    R = 1.2
    ap = arr(0.5, -0.5, 0.1)
    d = arr(1.0, 1.0, 0.0) / math.sqrt(2.0)
    perp = arr(0, 0, 1.0)
    p = ap + 0.4 * d + r * perp
    res = g.cylinder_closest(p, ap, d, R, 0.0, 1.0, True)
    assert res[0] == pytest.approx(R - r)
    n = np.array(res[1:4])
    c = np.array(res[4:7])
    assert np.linalg.norm(n) == pytest.approx(1.0)
    assert np.allclose(c + res[0] * n, p)  # p = c + dist * n
    assert np.linalg.norm(c - ap - 0.4 * d) == pytest.approx(R)  # c on the shell
    if r > 0:
        assert n == pytest.approx(-perp)  # inward normal


def test_cylinder_outer_and_penetration_sign():
    res = g.cylinder_closest(arr(1.5, 0, 0.5), O, EZ, 1.0, 0.0, 1.0, False)
    assert res[0] == pytest.approx(0.5) and res[1:4] == pytest.approx((1, 0, 0))
    # a shell has two sides: a centre outside an inner (drum) wall is 0.1 from it, pushed out
    res = g.cylinder_closest(arr(1.1, 0, 0.5), O, EZ, 1.0, 0.0, 1.0, True)
    assert res[0] == pytest.approx(0.1) and res[1:4] == pytest.approx((1, 0, 0))
    assert res[4:7] == pytest.approx((1.0, 0.0, 0.5))


def test_cylinder_rim_edge():
    # beyond z1 = 1 at radius 0.5: closest is the rim circle point (0, 1, 1)
    res = g.cylinder_closest(arr(0.0, 0.5, 1.5), O, EZ, 1.0, 0.0, 1.0, True)
    assert res[0] == pytest.approx(math.sqrt(0.5))
    assert res[4:7] == pytest.approx((0.0, 1.0, 1.0))
    assert res[1:4] == pytest.approx((0.0, -math.sqrt(0.5), math.sqrt(0.5)))


def test_cone_distance_vs_hand_geometry():
    # funnel: radius 1 at z = 0 to 2 at z = 1 (half-angle 45 deg). A point at
    # z = 0.5 and r = 1.2 sits 1.5 - 1.2 = 0.3 inside the wall measured
    # horizontally, i.e. 0.3 cos(45 deg) normal to it; foot at z = 0.35, r = 1.35.
    p = arr(1.2, 0.0, 0.5)
    res = g.cone_closest(p, O, EZ, 1.0, 2.0, 0.0, 1.0, True)
    assert res[0] == pytest.approx(0.3 / math.sqrt(2.0))
    assert res[4:7] == pytest.approx((1.35, 0.0, 0.35))
    assert res[1:4] == pytest.approx((-1 / math.sqrt(2), 0.0, 1 / math.sqrt(2)))
    # same point, outer orientation: same distance and normal (two-sided shell)
    out = g.cone_closest(p, O, EZ, 1.0, 2.0, 0.0, 1.0, False)
    assert out[0] == pytest.approx(0.3 / math.sqrt(2.0))
    assert out[1:4] == pytest.approx(res[1:4])
    # below the small rim: closest is the rim circle (r = 1, z = 0)
    res = g.cone_closest(arr(0.0, 0.5, -0.5), O, EZ, 1.0, 2.0, 0.0, 1.0, True)
    assert res[0] == pytest.approx(math.sqrt(0.5))
    assert res[4:7] == pytest.approx((0.0, 1.0, 0.0))


def test_cone_matches_brute_force_on_tessellation():
    rng = np.random.default_rng(3)
    v, t = g.cone_mesh(0.3, 1.0, -0.2, 0.9, n_seg=720, axis_dir=arr(0.2, 0.1, 1.0),
                       axis_point=arr(0.1, 0.0, 0.0))
    d = arr(0.2, 0.1, 1.0)
    d /= np.linalg.norm(d)
    for _ in range(20):
        p = rng.uniform(-1.2, 1.2, 3)
        res = g.cone_closest(p, arr(0.1, 0.0, 0.0), d, 0.3, 1.0, -0.2, 0.9, True)
        ref = g.mesh_closest(p, v, t)
        # fine tessellation: chord error R (1 - cos(pi/720)) < 1e-5
        assert abs(res[0]) == pytest.approx(ref[0], abs=2e-5)


# ---------------------------------------------------------------- triangle

V0, V1, V2 = arr(0, 0, 0), arr(1, 0, 0), arr(0, 1, 0)


@pytest.mark.parametrize(
    "p, c, feature, local",
    [
        ((0.2, 0.3, 0.5), (0.2, 0.3, 0.0), 0, 0),      # above the face
        ((-1.0, -1.0, 1.0), (0.0, 0.0, 0.0), 2, 0),    # vertex v0 region
        ((2.0, -1.0, 0.0), (1.0, 0.0, 0.0), 2, 1),     # vertex v1 region
        ((-0.5, 3.0, 0.0), (0.0, 1.0, 0.0), 2, 2),     # vertex v2 region
        ((0.5, -1.0, 0.5), (0.5, 0.0, 0.0), 1, 0),     # edge v0-v1
        ((1.0, 1.0, 0.0), (0.5, 0.5, 0.0), 1, 1),      # edge v1-v2
        ((-0.7, 0.4, -0.2), (0.0, 0.4, 0.0), 1, 2),    # edge v2-v0
    ],
)
def test_triangle_voronoi_regions(p, c, feature, local):
    p = np.array(p, dtype=float)
    res = g.triangle_closest_local(p, V0, V1, V2)
    assert res[4:7] == pytest.approx(c)
    assert res[0] == pytest.approx(np.linalg.norm(p - np.array(c)))
    assert res[7] == feature and res[8] == local
    assert g.triangle_closest(p, V0, V1, V2)[7] == feature


def test_triangle_on_face_uses_face_normal():
    res = g.triangle_closest(arr(0.2, 0.2, 0.0), V0, V1, V2)
    assert res[0] == 0.0 and res[1:4] == (0.0, 0.0, 1.0)
    res = g.triangle_closest(arr(0.2, 0.2, -0.4), V0, V1, V2)
    assert res[0] == pytest.approx(0.4) and res[1:4] == pytest.approx((0, 0, -1))


def test_triangle_against_dense_barycentric_sampling():
    rng = np.random.default_rng(7)
    a, b, c = rng.normal(size=(3, 3))
    m = 400
    u, w = np.meshgrid(np.linspace(0, 1, m), np.linspace(0, 1, m))
    keep = u + w <= 1
    pts = a + u[keep, None] * (b - a) + w[keep, None] * (c - a)
    h = max(np.linalg.norm(b - a), np.linalg.norm(c - a)) / (m - 1)
    for _ in range(25):
        p = rng.normal(size=3) * 2
        res = g.triangle_closest(p, a, b, c)
        ref = np.min(np.linalg.norm(pts - p, axis=1))
        assert res[0] <= ref + 1e-12
        assert res[0] >= ref - 2 * h


# ---------------------------------------------------------------- rigid motion


def test_rodrigues_rotation():
    R = g.rotation_matrix(arr(0, 0, 2.0), math.pi / 2)
    assert R @ arr(1, 0, 0) == pytest.approx([0, 1, 0])
    axis = arr(1, 2, 3)
    R = g.rotation_matrix(axis, 0.7)
    assert R @ R.T == pytest.approx(np.eye(3))
    assert np.linalg.det(R) == pytest.approx(1.0)
    assert R @ axis == pytest.approx(axis)  # axis is invariant
    # rotation angle from the trace: tr R = 1 + 2 cos(theta)
    assert math.acos((np.trace(R) - 1) / 2) == pytest.approx(0.7)


def test_rigid_velocity():
    v = g.rigid_velocity(arr(2, 0, 0), arr(0, 0, 1.0), arr(0, 0, 3.0), arr(1, 0, 0))
    # omega x r = (0,0,3) x (1,0,0) = (0,3,0)
    assert v == pytest.approx((0.0, 3.0, 1.0))


def test_advance_pose_matches_exact_motion():
    omega = arr(0, 0, 2.0)
    vlin = arr(0, 0, 1.0)
    ref = np.array([[2.0, 0, 0], [1.0, 1.0, 0.5]])
    verts = ref.copy()
    centre = arr(1.0, 0, 0)
    t_end = math.pi / 4  # quarter turn at 2 rad/s
    n = 1000
    for _ in range(n):
        g.advance_pose(verts, centre, vlin, omega, t_end / n)
    # point (2,0,0) rotates a quarter turn about (1,0,0) to (1,1,0), rises v t
    assert verts[0] == pytest.approx([1.0, 1.0, t_end], abs=1e-12)
    assert verts[1] == pytest.approx([0.0, 0.0, 0.5 + t_end], abs=1e-12)
    assert centre == pytest.approx([1.0, 0.0, t_end])
    out = np.empty_like(ref)
    g.pose_from_reference(ref, out, arr(1.0, 0, 0), vlin, omega, t_end)
    assert out == pytest.approx(verts, abs=1e-12)


# ---------------------------------------------------------------- meshes


def test_box_mesh_volume_area_exact_and_watertight():
    v, t = g.box_mesh([0.1, -0.2, 0.0], [0.4, 0.3, 0.7])
    assert g.mesh_volume(v, t) == pytest.approx(0.3 * 0.5 * 0.7, rel=1e-14)
    assert g.mesh_area(v, t) == pytest.approx(2 * (0.3 * 0.5 + 0.3 * 0.7 + 0.5 * 0.7))
    assert g.is_watertight(t)
    # outward: every face normal points away from the box centre
    n = g.triangle_normals(v, t)
    cen = v[t].mean(axis=1) - np.array([0.25, 0.05, 0.35])
    assert np.all(np.einsum("ij,ij->i", n, cen) > 0)


@pytest.mark.parametrize("n", [12, 48, 200])
def test_tube_area_within_discretisation_bound(n):
    R, L = 0.25, 0.6
    v, t = g.cylinder_mesh(R, 0.0, L, n_seg=n, n_axial=3)
    A = g.mesh_area(v, t)
    exact = 2 * math.pi * R * L
    assert A == pytest.approx(2 * n * R * math.sin(math.pi / n) * L, rel=1e-12)
    # 1 - sin(x)/x <= x^2/6 with x = pi/n
    assert 0 < (exact - A) / exact <= (math.pi / n) ** 2 / 6
    assert not g.is_watertight(t)  # open tube
    # normals point away from the axis
    nrm = g.triangle_normals(v, t)
    cen = v[t].mean(axis=1)
    assert np.all(np.einsum("ij,ij->i", nrm[:, :2], cen[:, :2]) > 0)


def test_drum_volume_and_watertight():
    R, L, n = 0.5, 0.3, 64
    v, t = g.drum_mesh(R, L, n_seg=n, axis_dir=(1.0, 0.0, 0.0))
    assert g.is_watertight(t)
    assert g.mesh_volume(v, t) == pytest.approx(0.5 * n * R**2 * math.sin(2 * math.pi / n) * L)
    exact = math.pi * R**2 * L
    assert 0 < (exact - g.mesh_volume(v, t)) / exact <= (2 * math.pi / n) ** 2 / 6


def test_cone_mesh_area_exact_for_facets():
    r0, r1, h, n = 0.05, 0.2, 0.3, 36
    v, t = g.cone_mesh(r0, r1, 0.0, h, n_seg=n)
    c = math.cos(math.pi / n)
    facet = n * (r0 + r1) * math.sin(math.pi / n) * math.sqrt(h**2 + ((r1 - r0) * c) ** 2)
    assert g.mesh_area(v, t) == pytest.approx(facet, rel=1e-12)
    analytic = math.pi * (r0 + r1) * math.hypot(h, r1 - r0)
    assert g.mesh_area(v, t) == pytest.approx(analytic, rel=0.01)


def test_disk_and_plate_and_extrusion():
    v, t = g.disk_mesh(0.5, n_seg=32, normal=(0, 1.0, 0))
    assert g.mesh_area(v, t) == pytest.approx(0.5 * 32 * 0.25 * math.sin(2 * math.pi / 32))
    assert np.allclose(g.triangle_normals(v, t), [0, 1, 0])
    v, t = g.plate_mesh((0, 0, 0), (1, 0, 0), (0, 0, 1), 0.4, 0.2, 4, 3)
    assert g.mesh_area(v, t) == pytest.approx(0.08)
    assert np.allclose(g.triangle_normals(v, t), [0, -1, 0])
    # circular-arc moldboard profile of radius 0.3 over 90 degrees, width 0.5
    th = np.linspace(0, math.pi / 2, 200)
    curve = np.column_stack([0.3 * np.sin(th), 0.3 * (1 - np.cos(th))])
    v, t = g.extrude_curve(curve, (0, 1, 0), 0.5, n_along=2)
    arc = 0.3 * math.pi / 2
    assert g.mesh_area(v, t) == pytest.approx(arc * 0.5, rel=1e-5)


def test_revolve_sphere_volume_and_watertight():
    R, m = 1.0, 90
    th = np.linspace(-math.pi / 2, math.pi / 2, m)
    prof = np.column_stack([R * np.cos(th), R * np.sin(th)])
    prof[0, 0] = prof[-1, 0] = 0.0
    v, t = g.revolve_profile(prof, 180)
    assert g.is_watertight(t)
    assert g.mesh_volume(v, t) == pytest.approx(4 / 3 * math.pi, rel=2e-3)


def test_parameter_row_variants_agree_with_array_kernels():
    rng = np.random.default_rng(0)
    par = np.zeros((6, 16))
    d = arr(0.3, -0.2, 1.0)
    d /= np.linalg.norm(d)
    u = np.cross(d, arr(1, 0, 0))
    u /= np.linalg.norm(u)
    par[0, 0:6] = [0.1, 0.2, 0.3, *d]
    par[1, 0:11] = [0.0, 0.0, 0.1, *d, *u, 0.4, 0.2]
    par[2, 0:7] = [0.0, 0.1, 0.0, *d, 0.3]
    par[3, 0:9] = [0.1, 0.0, 0.0, *d, 0.5, 0.4, 1.0]
    par[4, 0:11] = [0.0, 0.0, 0.0, *d, 0.2, 0.6, -0.3, 0.5, 1.0]
    par[5, 0:9] = rng.normal(size=9)
    for _ in range(10):
        p = rng.normal(size=3) * 0.5
        a = p[0], p[1], p[2]
        assert g.plane_closest_par(*a, par, 0) == pytest.approx(
            g.plane_closest(p, par[0, 0:3], d))
        assert g.rectangle_closest_par(*a, par, 1) == pytest.approx(
            g.rectangle_closest(p, par[1, 0:3], d, u, 0.4, 0.2))
        assert g.disk_closest_par(*a, par, 2) == pytest.approx(
            g.disk_closest(p, par[2, 0:3], d, 0.3))
        assert g.cylinder_closest_par(*a, par, 3) == pytest.approx(
            g.cylinder_closest(p, par[3, 0:3], d, 0.5, -0.4, 0.4, True))
        assert g.cone_closest_par(*a, par, 4) == pytest.approx(
            g.cone_closest(p, par[4, 0:3], d, 0.2, 0.6, -0.3, 0.5, True))
        assert g.triangle_closest_par(*a, par, 5) == pytest.approx(
            g.triangle_closest(p, par[5, 0:3], par[5, 3:6], par[5, 6:9]))
    v, t = g.box_mesh([0, 0, 0], [1, 1, 1])
    mp = g.mesh_to_par(v, t)
    assert mp.shape == (12, 16) and np.array_equal(mp[3, 0:3], v[t[3, 0]])
