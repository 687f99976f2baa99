"""Wall geometry for the DEM engine: closest points, rigid motion and mesh builders.

Closest-point kernels
---------------------
Every wall kernel is ``@njit(cache=True)`` and returns a tuple::

    (dist, nx, ny, nz, cx, cy, cz)

for a sphere centre ``p``: ``c`` is the closest point on the wall surface (the
contact point) and ``n`` the unit normal pointing from the wall towards ``p``;
``dist`` is the distance from ``p`` to the surface measured along ``n``.  The
engine computes the overlap of a sphere of radius ``R`` as ``R - dist``
(contact when positive), the normal force acting on the sphere along ``+n``.

* Infinite plane through ``q`` with unit normal ``m`` (signed)::

      dist = (p - q) . m ,   c = p - dist m ,   n = m

* Bounded planes (rectangle, disk): ``c`` is ``p`` projected onto the plane and
  clamped to the bounded region; on the face ``dist = |(p - c) . m|`` with ``n``
  the face normal turned towards ``p``, off the face (rim region)
  ``dist = |p - c|`` and ``n = (p - c)/|p - c|``.

* Surfaces of revolution (cylinder and cone frustum shells).  With the unit
  axis ``d`` through ``a``, write ``z = (p - a) . d`` and the radial vector
  ``r_vec = (p - a) - z d``, ``r = |r_vec|``, ``e = r_vec / r``.  A point of a
  surface of revolution at meridian coordinates ``(z_s, r_s)`` and azimuth
  offset ``phi`` from the meridian half-plane of ``p`` lies at squared distance
  ``(z - z_s)^2 + r^2 + r_s^2 - 2 r r_s cos(phi)``, minimal at ``phi = 0``: the
  3-D problem therefore reduces to the 2-D closest point of ``q = (z, r)`` on
  the meridian generator, the segment ``(z0, r0)-(z1, r1)`` (Eberly,
  "Distance to circles/cones in 3D", Geometric Tools; Ericson 2005, sec. 5.1.2
  for the point-segment projection)::

      t = clamp(((q - s0) . (s1 - s0)) / |s1 - s0|^2, 0, 1) ,  s = s0 + t (s1 - s0)

  On the shell (``0 < t < 1``) the 2-D normal of the generator is
  ``m = (-(r1 - r0), z1 - z0) / L`` (pointing to larger radius; z1 > z0), the
  distance is ``dist = |(q - s) . m|`` and ``n`` is ``m`` or ``-m``, whichever
  points to the side of ``p``; ``inner`` (particles inside a drum, tube or funnel)
  orients ``n`` for a point exactly on the shell.  For a cylinder this gives
  ``dist = R - r`` inside.

  Rectangles, disks, cylinders and cones are thin walls with two sides, like
  triangles: a sphere behind a face is pushed back towards its own side.  (A
  sphere on the front side cannot reach a negative signed distance without an
  overlap above its radius, far beyond the engine's blow-up limit, so a negative
  signed distance only ever means the back side.)  Infinite planes stay
  half-spaces: ``dist`` is signed, and a centre below the plane is pushed up.  At a rim
  (``t`` clamped to 0 or 1) the closest point is on the edge circle and
  ``dist = |q - s|``, ``n`` the unit vector from that circle point to ``p``.

* Triangle: exact closest point by Voronoi-region classification (Ericson,
  *Real-Time Collision Detection*, 2005, sec. 5.1.5, ``ClosestPtPointTriangle``).
  ``dist = |p - c|`` (unsigned), ``n = (p - c)/dist``; in the face region
  this equals the unit face normal ``(v1 - v0) x (v2 - v0)`` oriented towards
  ``p`` and is computed as such (the +face normal when ``p`` is on the face).  An 8th
  element codes the feature of ``c``: 0 face, 1 edge, 2 vertex, so that an
  engine can discard an edge or vertex contact that a neighbouring triangle
  already reports as a face contact.

Rigid motion
------------
Rotation by angle ``theta`` about unit axis ``k`` (Rodrigues' formula)::

    R = I + sin(theta) K + (1 - cos(theta)) K^2 ,   K = [k]_x

A wall moving with constant translation velocity ``v`` and angular velocity
``omega`` about a centre ``x_c`` has the exact pose
``x(t) = x_c0 + v t + R(|omega| t, omega/|omega|) (x_0 - x_c0)`` and the
material velocity at a point ``c`` is ``v + omega x (c - x_c)``.

Mesh builders
-------------
Builders return ``(vertices float64[nv, 3], triangles int64[nt, 3])`` wound so
that ``(v1 - v0) x (v2 - v0)`` points outward (away from the axis for tubes and
cones, out of the enclosed volume for closed meshes).  Surfaces of revolution
are made from a meridian profile; a profile point at radius 0 becomes a single
pole vertex, so closed profiles give watertight meshes.  The enclosed volume of
a closed mesh follows from the divergence theorem,
``V = sum_t (v0 . (v1 x v2)) / 6``; the area is ``sum_t |(v1-v0) x (v2-v0)| / 2``.
A regular n-gon tube of radius R and length L has lateral area
``2 n R sin(pi/n) L`` and a closed n-gon prism the volume ``(n/2) R^2 sin(2 pi/n) L``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_EPS = 1e-300

# ---------------------------------------------------------------------------
# small vector helpers (scalars in, scalars out; no allocation)
# ---------------------------------------------------------------------------


@njit(cache=True)
def _any_perpendicular(dx, dy, dz):
    """Unit vector perpendicular to the unit vector (dx, dy, dz)."""
    # cross with the coordinate axis least aligned with d
    ax, ay, az = abs(dx), abs(dy), abs(dz)
    if ax <= ay and ax <= az:
        # d x e_x = (0, dz, -dy)
        ux, uy, uz = 0.0, dz, -dy
    elif ay <= az:
        # d x e_y = (-dz, 0, dx)
        ux, uy, uz = -dz, 0.0, dx
    else:
        # d x e_z = (dy, -dx, 0)
        ux, uy, uz = dy, -dx, 0.0
    nrm = math.sqrt(ux * ux + uy * uy + uz * uz)
    return ux / nrm, uy / nrm, uz / nrm


# ---------------------------------------------------------------------------
# planes
# ---------------------------------------------------------------------------


@njit(cache=True)
def plane_closest(p, point, normal):
    """Infinite plane through ``point`` with unit ``normal``; dist is signed."""
    nx, ny, nz = normal[0], normal[1], normal[2]
    dist = (p[0] - point[0]) * nx + (p[1] - point[1]) * ny + (p[2] - point[2]) * nz
    return (dist, nx, ny, nz, p[0] - dist * nx, p[1] - dist * ny, p[2] - dist * nz)


@njit(cache=True)
def _rim_result(p, cx, cy, cz, fnx, fny, fnz):
    """Result for a closest point ``c`` off the face: unsigned distance."""
    dx, dy, dz = p[0] - cx, p[1] - cy, p[2] - cz
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    if d < _EPS:
        return (0.0, fnx, fny, fnz, cx, cy, cz)
    return (d, dx / d, dy / d, dz / d, cx, cy, cz)


@njit(cache=True)
def rectangle_closest(p, centre, normal, u_axis, half_u, half_v):
    """Rectangle centred at ``centre`` with unit ``normal`` and in-plane unit
    ``u_axis``; the second in-plane axis is ``normal x u_axis``.  Half sizes
    ``half_u`` and ``half_v``."""
    nx, ny, nz = normal[0], normal[1], normal[2]
    ux, uy, uz = u_axis[0], u_axis[1], u_axis[2]
    vx = ny * uz - nz * uy
    vy = nz * ux - nx * uz
    vz = nx * uy - ny * ux
    rx, ry, rz = p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]
    h = rx * nx + ry * ny + rz * nz
    a = rx * ux + ry * uy + rz * uz
    b = rx * vx + ry * vy + rz * vz
    ac = min(max(a, -half_u), half_u)
    bc = min(max(b, -half_v), half_v)
    cx = centre[0] + ac * ux + bc * vx
    cy = centre[1] + ac * uy + bc * vy
    cz = centre[2] + ac * uz + bc * vz
    if ac == a and bc == b:
        if h < 0.0:
            return (-h, -nx, -ny, -nz, cx, cy, cz)
        return (h, nx, ny, nz, cx, cy, cz)
    return _rim_result(p, cx, cy, cz, nx, ny, nz)


@njit(cache=True)
def disk_closest(p, centre, normal, radius):
    """Disk of ``radius`` centred at ``centre`` with unit ``normal``."""
    nx, ny, nz = normal[0], normal[1], normal[2]
    rx, ry, rz = p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]
    h = rx * nx + ry * ny + rz * nz
    ix, iy, iz = rx - h * nx, ry - h * ny, rz - h * nz
    rho = math.sqrt(ix * ix + iy * iy + iz * iz)
    if rho <= radius:
        if h < 0.0:
            return (-h, -nx, -ny, -nz, p[0] - h * nx, p[1] - h * ny, p[2] - h * nz)
        return (h, nx, ny, nz, p[0] - h * nx, p[1] - h * ny, p[2] - h * nz)
    s = radius / rho
    cx, cy, cz = centre[0] + s * ix, centre[1] + s * iy, centre[2] + s * iz
    return _rim_result(p, cx, cy, cz, nx, ny, nz)


# ---------------------------------------------------------------------------
# surfaces of revolution
# ---------------------------------------------------------------------------


@njit(cache=True)
def cone_closest(p, axis_point, axis_dir, r0, r1, z0, z1, inner):
    """Conical frustum shell, radius ``r0`` at axial coordinate ``z0`` to ``r1``
    at ``z1`` (``z1 > z0``, measured from ``axis_point`` along unit ``axis_dir``).
    ``inner=True``: particles are inside, the normal on the shell points
    towards the axis side.  Rim edges are handled (closest point on the edge
    circle)."""
    dx, dy, dz = axis_dir[0], axis_dir[1], axis_dir[2]
    wx, wy, wz = p[0] - axis_point[0], p[1] - axis_point[1], p[2] - axis_point[2]
    z = wx * dx + wy * dy + wz * dz
    rx, ry, rz = wx - z * dx, wy - z * dy, wz - z * dz
    r = math.sqrt(rx * rx + ry * ry + rz * rz)
    if r > 1e-14 * (1.0 + abs(z)):
        ex, ey, ez = rx / r, ry / r, rz / r
    else:
        ex, ey, ez = _any_perpendicular(dx, dy, dz)
        r = 0.0
    gz = z1 - z0
    gr = r1 - r0
    L2 = gz * gz + gr * gr
    t = ((z - z0) * gz + (r - r0) * gr) / L2
    if t < 0.0:
        t = 0.0
    elif t > 1.0:
        t = 1.0
    sz = z0 + t * gz
    sr = r0 + t * gr
    cx = axis_point[0] + sz * dx + sr * ex
    cy = axis_point[1] + sz * dy + sr * ey
    cz = axis_point[2] + sz * dz + sr * ez
    L = math.sqrt(L2)
    mz = -gr / L
    mr = gz / L
    if inner:
        mz = -mz
        mr = -mr
    if 0.0 < t < 1.0:
        dist = (z - sz) * mz + (r - sr) * mr
        if dist < 0.0:  # behind the face: the other side of the thin shell
            dist = -dist
            mz = -mz
            mr = -mr
        nx = mz * dx + mr * ex
        ny = mz * dy + mr * ey
        nz = mz * dz + mr * ez
        return (dist, nx, ny, nz, cx, cy, cz)
    return _rim_result(p, cx, cy, cz, mz * dx + mr * ex, mz * dy + mr * ey, mz * dz + mr * ez)


@njit(cache=True)
def cylinder_closest(p, axis_point, axis_dir, radius, z0, z1, inner):
    """Finite cylindrical shell of ``radius`` between axial coordinates ``z0``
    and ``z1`` (``z1 > z0``).  ``inner=True`` for particles inside (drum,
    tube): on the shell ``dist = radius - r``.  Beyond ``z0``/``z1`` the closest
    point is on the rim circle."""
    return cone_closest(p, axis_point, axis_dir, radius, radius, z0, z1, inner)


# ---------------------------------------------------------------------------
# triangles
# ---------------------------------------------------------------------------


@njit(cache=True)
def triangle_closest_local(p, v0, v1, v2):
    """Closest point on triangle (v0, v1, v2) to ``p`` (Ericson 2005, 5.1.5).

    Returns ``(dist, nx, ny, nz, cx, cy, cz, feature, local)``: ``feature`` 0
    face, 1 edge, 2 vertex; ``local`` the vertex index (0, 1, 2) for a vertex,
    the edge index k for edge (v_k, v_(k+1)%3), 0 for the face.
    """
    ax, ay, az = v0[0], v0[1], v0[2]
    abx, aby, abz = v1[0] - ax, v1[1] - ay, v1[2] - az
    acx, acy, acz = v2[0] - ax, v2[1] - ay, v2[2] - az
    apx, apy, apz = p[0] - ax, p[1] - ay, p[2] - az
    # face normal (for on-face points)
    fnx = aby * acz - abz * acy
    fny = abz * acx - abx * acz
    fnz = abx * acy - aby * acx
    fl = math.sqrt(fnx * fnx + fny * fny + fnz * fnz)
    if fl > 0.0:
        fnx /= fl
        fny /= fl
        fnz /= fl
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    feature = 0
    local = 0
    done = False
    cx, cy, cz = 0.0, 0.0, 0.0
    if d1 <= 0.0 and d2 <= 0.0:
        cx, cy, cz = ax, ay, az
        feature, local, done = 2, 0, True
    if not done:
        bpx, bpy, bpz = p[0] - v1[0], p[1] - v1[1], p[2] - v1[2]
        d3 = abx * bpx + aby * bpy + abz * bpz
        d4 = acx * bpx + acy * bpy + acz * bpz
        if d3 >= 0.0 and d4 <= d3:
            cx, cy, cz = v1[0], v1[1], v1[2]
            feature, local, done = 2, 1, True
        if not done:
            vc = d1 * d4 - d3 * d2
            if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
                v = d1 / (d1 - d3)
                cx, cy, cz = ax + v * abx, ay + v * aby, az + v * abz
                feature, local, done = 1, 0, True
            if not done:
                cpx, cpy, cpz = p[0] - v2[0], p[1] - v2[1], p[2] - v2[2]
                d5 = abx * cpx + aby * cpy + abz * cpz
                d6 = acx * cpx + acy * cpy + acz * cpz
                if d6 >= 0.0 and d5 <= d6:
                    cx, cy, cz = v2[0], v2[1], v2[2]
                    feature, local, done = 2, 2, True
                if not done:
                    vb = d5 * d2 - d1 * d6
                    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
                        w = d2 / (d2 - d6)
                        cx, cy, cz = ax + w * acx, ay + w * acy, az + w * acz
                        feature, local, done = 1, 2, True
                    if not done:
                        va = d3 * d6 - d5 * d4
                        if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
                            w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
                            cx = v1[0] + w * (v2[0] - v1[0])
                            cy = v1[1] + w * (v2[1] - v1[1])
                            cz = v1[2] + w * (v2[2] - v1[2])
                            feature, local, done = 1, 1, True
                        if not done:
                            denom = 1.0 / (va + vb + vc)
                            v = vb * denom
                            w = vc * denom
                            cx = ax + abx * v + acx * w
                            cy = ay + aby * v + acy * w
                            cz = az + abz * v + acz * w
                            feature, local = 0, 0
    if feature == 0 and fl > 0.0:
        # face region: project along the face normal (exact, no round-off
        # in the direction when p is on or very near the face)
        h = apx * fnx + apy * fny + apz * fnz
        cx, cy, cz = p[0] - h * fnx, p[1] - h * fny, p[2] - h * fnz
        if h >= 0.0:
            return (h, fnx, fny, fnz, cx, cy, cz, 0, 0)
        return (-h, -fnx, -fny, -fnz, cx, cy, cz, 0, 0)
    dx, dy, dz = p[0] - cx, p[1] - cy, p[2] - cz
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    if d < _EPS:
        return (0.0, fnx, fny, fnz, cx, cy, cz, feature, local)
    return (d, dx / d, dy / d, dz / d, cx, cy, cz, feature, local)


@njit(cache=True)
def triangle_closest(p, v0, v1, v2):
    """Closest point on a triangle: ``(dist, nx, ny, nz, cx, cy, cz, feature)``
    with feature 0 face, 1 edge, 2 vertex (Ericson 2005, 5.1.5)."""
    r = triangle_closest_local(p, v0, v1, v2)
    return (r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7])


@njit(cache=True)
def mesh_closest(p, vertices, triangles):
    """Closest triangle of a whole mesh (brute force over all triangles).

    Returns ``(dist, nx, ny, nz, cx, cy, cz, feature, tri_index)``; for
    reference and small meshes (the engine uses its neighbour search)."""
    best = 1e300
    res = (best, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0, -1)
    for t in range(triangles.shape[0]):
        r = triangle_closest(p, vertices[triangles[t, 0]], vertices[triangles[t, 1]],
                             vertices[triangles[t, 2]])
        if r[0] < best:
            best = r[0]
            res = (r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], t)
    return res


# ---------------------------------------------------------------------------
# rigid motion
# ---------------------------------------------------------------------------


@njit(cache=True)
def rotation_matrix_into(axis, angle, out):
    """Rodrigues rotation matrix about ``axis`` (normalised here) by ``angle``
    (right-hand rule) written into ``out`` (3x3)."""
    kx, ky, kz = axis[0], axis[1], axis[2]
    n = math.sqrt(kx * kx + ky * ky + kz * kz)
    if n == 0.0:
        for i in range(3):
            for j in range(3):
                out[i, j] = 1.0 if i == j else 0.0
        return
    kx /= n
    ky /= n
    kz /= n
    s = math.sin(angle)
    c1 = 1.0 - math.cos(angle)
    out[0, 0] = 1.0 - c1 * (ky * ky + kz * kz)
    out[0, 1] = -s * kz + c1 * kx * ky
    out[0, 2] = s * ky + c1 * kx * kz
    out[1, 0] = s * kz + c1 * kx * ky
    out[1, 1] = 1.0 - c1 * (kx * kx + kz * kz)
    out[1, 2] = -s * kx + c1 * ky * kz
    out[2, 0] = -s * ky + c1 * kx * kz
    out[2, 1] = s * kx + c1 * ky * kz
    out[2, 2] = 1.0 - c1 * (kx * kx + ky * ky)


@njit(cache=True)
def rotation_matrix(axis, angle):
    """Rodrigues rotation matrix (allocates a new 3x3 array)."""
    out = np.empty((3, 3))
    rotation_matrix_into(axis, angle, out)
    return out


@njit(cache=True)
def rigid_velocity(c, v_lin, omega, centre):
    """Velocity ``v + omega x (c - centre)`` of the material point ``c``."""
    rx, ry, rz = c[0] - centre[0], c[1] - centre[1], c[2] - centre[2]
    return (v_lin[0] + omega[1] * rz - omega[2] * ry,
            v_lin[1] + omega[2] * rx - omega[0] * rz,
            v_lin[2] + omega[0] * ry - omega[1] * rx)


@njit(cache=True)
def _rotate_about(vertices, centre, kx, ky, kz, angle, tx, ty, tz):
    s = math.sin(angle)
    c1 = 1.0 - math.cos(angle)
    m00 = 1.0 - c1 * (ky * ky + kz * kz)
    m01 = -s * kz + c1 * kx * ky
    m02 = s * ky + c1 * kx * kz
    m10 = s * kz + c1 * kx * ky
    m11 = 1.0 - c1 * (kx * kx + kz * kz)
    m12 = -s * kx + c1 * ky * kz
    m20 = -s * ky + c1 * kx * kz
    m21 = s * kx + c1 * ky * kz
    m22 = 1.0 - c1 * (kx * kx + ky * ky)
    cx, cy, cz = centre[0], centre[1], centre[2]
    for i in range(vertices.shape[0]):
        x = vertices[i, 0] - cx
        y = vertices[i, 1] - cy
        z = vertices[i, 2] - cz
        vertices[i, 0] = cx + tx + m00 * x + m01 * y + m02 * z
        vertices[i, 1] = cy + ty + m10 * x + m11 * y + m12 * z
        vertices[i, 2] = cz + tz + m20 * x + m21 * y + m22 * z


@njit(cache=True)
def advance_pose(vertices, centre, v_lin, omega, dt):
    """Move ``vertices`` (n, 3) and the rotation ``centre`` (3,) in place over
    ``dt`` for constant translation velocity ``v_lin`` and angular velocity
    ``omega`` (rad/s, axis through ``centre``): rotate by ``|omega| dt`` about
    ``centre`` then translate by ``v_lin dt``.  Exact for constant motion;
    no allocation."""
    w = math.sqrt(omega[0] ** 2 + omega[1] ** 2 + omega[2] ** 2)
    tx, ty, tz = v_lin[0] * dt, v_lin[1] * dt, v_lin[2] * dt
    if w > 0.0:
        _rotate_about(vertices, centre, omega[0] / w, omega[1] / w, omega[2] / w, w * dt,
                      tx, ty, tz)
    else:
        for i in range(vertices.shape[0]):
            vertices[i, 0] += tx
            vertices[i, 1] += ty
            vertices[i, 2] += tz
    centre[0] += tx
    centre[1] += ty
    centre[2] += tz


@njit(cache=True)
def pose_from_reference(ref_vertices, out_vertices, centre_ref, v_lin, omega, t):
    """Drift-free pose at time ``t``: ``out = c0 + v t + R(|omega| t)(ref - c0)``
    for constant ``v_lin`` and ``omega`` (no allocation)."""
    for i in range(ref_vertices.shape[0]):
        for k in range(3):
            out_vertices[i, k] = ref_vertices[i, k]
    w = math.sqrt(omega[0] ** 2 + omega[1] ** 2 + omega[2] ** 2)
    tx, ty, tz = v_lin[0] * t, v_lin[1] * t, v_lin[2] * t
    if w > 0.0:
        _rotate_about(out_vertices, centre_ref, omega[0] / w, omega[1] / w, omega[2] / w,
                      w * t, tx, ty, tz)
    else:
        for i in range(out_vertices.shape[0]):
            out_vertices[i, 0] += tx
            out_vertices[i, 1] += ty
            out_vertices[i, 2] += tz


# ---------------------------------------------------------------------------
# mesh analysis (numpy)
# ---------------------------------------------------------------------------


def _as_mesh(vertices, triangles):
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    t = np.ascontiguousarray(triangles, dtype=np.int64)
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"vertices must have shape (n, 3), got {v.shape}")
    if t.ndim != 2 or t.shape[1] != 3:
        raise ValueError(f"triangles must have shape (m, 3), got {t.shape}")
    return v, t


def triangle_normals(vertices, triangles, normalise=True):
    """Face normals ``(v1 - v0) x (v2 - v0)`` (unit if ``normalise``)."""
    v, t = _as_mesh(vertices, triangles)
    n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    if normalise:
        ln = np.linalg.norm(n, axis=1)
        n = n / np.where(ln > 0, ln, 1.0)[:, None]
    return n


def mesh_area(vertices, triangles):
    """Total surface area ``sum |(v1 - v0) x (v2 - v0)| / 2``."""
    return 0.5 * float(np.linalg.norm(triangle_normals(vertices, triangles, False), axis=1).sum())


def mesh_volume(vertices, triangles):
    """Signed enclosed volume ``sum v0 . (v1 x v2) / 6`` (positive for outward
    winding of a closed mesh)."""
    v, t = _as_mesh(vertices, triangles)
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def is_watertight(triangles):
    """True if every directed edge (i, j) appears exactly once and its
    reverse (j, i) exactly once: closed, edge-manifold, consistently wound."""
    t = np.asarray(triangles, dtype=np.int64)
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    uniq, counts = np.unique(e, axis=0, return_counts=True)
    if np.any(counts != 1):
        return False
    key = uniq[:, 0] * (t.max() + 1) + uniq[:, 1]
    rkey = uniq[:, 1] * (t.max() + 1) + uniq[:, 0]
    return bool(np.all(np.isin(rkey, key)))


def merge_meshes(*meshes):
    """Concatenate ``(vertices, triangles)`` pairs into one mesh."""
    vs, ts, off = [], [], 0
    for v, t in meshes:
        v, t = _as_mesh(v, t)
        vs.append(v)
        ts.append(t + off)
        off += v.shape[0]
    return np.concatenate(vs), np.concatenate(ts)


def transform_mesh(vertices, rotation=None, translation=None):
    """Return ``vertices @ rotation.T + translation`` (a new array)."""
    v = np.array(vertices, dtype=np.float64)
    if rotation is not None:
        v = v @ np.asarray(rotation, dtype=np.float64).T
    if translation is not None:
        v = v + np.asarray(translation, dtype=np.float64)
    return v


# ---------------------------------------------------------------------------
# mesh builders (numpy)
# ---------------------------------------------------------------------------


def _frame(axis_dir):
    d = np.asarray(axis_dir, dtype=np.float64)
    d = d / np.linalg.norm(d)
    e1 = np.array(_any_perpendicular(d[0], d[1], d[2]))
    e2 = np.cross(d, e1)
    return d, e1, e2


def box_mesh(lo, hi):
    """Closed box ``[lo, hi]`` as 12 outward-wound triangles on 8 vertices."""
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    if lo.shape != (3,) or hi.shape != (3,) or np.any(hi <= lo):
        raise ValueError(f"box needs lo < hi componentwise, got lo={lo}, hi={hi}")
    # vertex index bits: x = bit0, y = bit1, z = bit2
    v = np.array([[hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1],
                   hi[2] if i & 4 else lo[2]] for i in range(8)])
    quads = [(0, 2, 3, 1),  # z = lo, normal -z
             (4, 5, 7, 6),  # z = hi, +z
             (0, 1, 5, 4),  # y = lo, -y
             (2, 6, 7, 3),  # y = hi, +y
             (0, 4, 6, 2),  # x = lo, -x
             (1, 3, 7, 5)]  # x = hi, +x
    tris = []
    for a, b, c, d in quads:
        tris += [(a, b, c), (a, c, d)]
    return v, np.array(tris, dtype=np.int64)


def revolve_profile(profile, n_seg, axis_point=(0.0, 0.0, 0.0), axis_dir=(0.0, 0.0, 1.0),
                    closed=False):
    """Surface of revolution of a meridian ``profile`` of ``(r, z)`` points.

    ``n_seg`` segments around the axis; a profile point with ``r == 0``
    becomes a single pole vertex.  Triangles are wound with normal
    ``t_phi x t_profile`` (``t_phi`` the counter-clockwise azimuth about
    ``axis_dir``): a profile running up the axis at constant radius faces
    away from the axis; a closed profile listed counter-clockwise in the
    (r, z) half-plane (bottom cap outwards, side up, top cap inwards) gives an
    outward-wound watertight mesh.  ``closed=True`` also joins the last
    profile point to the first.
    """
    prof = np.asarray(profile, dtype=np.float64)
    if prof.ndim != 2 or prof.shape[1] != 2 or prof.shape[0] < 2:
        raise ValueError(f"profile must be (m >= 2, 2) of (r, z), got {prof.shape}")
    if np.any(prof[:, 0] < 0):
        raise ValueError("profile radii must be >= 0")
    n_seg = int(n_seg)
    if n_seg < 3:
        raise ValueError(f"n_seg must be >= 3, got {n_seg}")
    d, e1, e2 = _frame(axis_dir)
    a = np.asarray(axis_point, dtype=np.float64)
    phi = 2.0 * np.pi * np.arange(n_seg) / n_seg
    cs, sn = np.cos(phi), np.sin(phi)
    verts = []
    rings = []  # list of index arrays (length n_seg; poles repeat one index)
    nv = 0
    for r, z in prof:
        if r == 0.0:
            verts.append((a + z * d)[None, :])
            rings.append(np.full(n_seg, nv, dtype=np.int64))
            nv += 1
        else:
            ring = a + z * d + r * (cs[:, None] * e1 + sn[:, None] * e2)
            verts.append(ring)
            rings.append(nv + np.arange(n_seg, dtype=np.int64))
            nv += n_seg
    pairs = list(zip(range(len(rings) - 1), range(1, len(rings))))
    if closed:
        pairs.append((len(rings) - 1, 0))
    tris = []
    jn = (np.arange(n_seg) + 1) % n_seg
    for i, k in pairs:
        A = rings[i]
        B = rings[i][jn]
        C = rings[k]
        D = rings[k][jn]
        # quad a=(i,j), b=(i,j+1), c=(i+1,j), d=(i+1,j+1): tris (a,b,d), (a,d,c)
        t1 = np.stack([A, B, D], axis=1)
        t2 = np.stack([A, D, C], axis=1)
        for tt in (t1, t2):
            keep = (tt[:, 0] != tt[:, 1]) & (tt[:, 1] != tt[:, 2]) & (tt[:, 0] != tt[:, 2])
            tris.append(tt[keep])
    return np.concatenate(verts), np.concatenate(tris).astype(np.int64)


def cylinder_mesh(radius, z0, z1, n_seg=48, axis_point=(0.0, 0.0, 0.0),
                  axis_dir=(0.0, 0.0, 1.0), n_axial=1):
    """Open cylindrical tube (no caps) between axial coordinates z0 < z1,
    normals facing away from the axis."""
    if radius <= 0 or z1 <= z0:
        raise ValueError("cylinder needs radius > 0 and z1 > z0")
    zs = np.linspace(z0, z1, int(n_axial) + 1)
    prof = np.column_stack([np.full_like(zs, radius), zs])
    return revolve_profile(prof, n_seg, axis_point, axis_dir)


def cone_mesh(r0, r1, z0, z1, n_seg=48, axis_point=(0.0, 0.0, 0.0), axis_dir=(0.0, 0.0, 1.0)):
    """Open conical frustum (funnel) from radius r0 at z0 to r1 at z1 (z1 > z0),
    normals facing away from the axis."""
    if r0 < 0 or r1 < 0 or (r0 == 0 and r1 == 0) or z1 <= z0:
        raise ValueError("cone needs radii >= 0 (not both 0) and z1 > z0")
    return revolve_profile([(r0, z0), (r1, z1)], n_seg, axis_point, axis_dir)


def disk_mesh(radius, n_seg=48, centre=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0)):
    """Flat disk (triangle fan about a centre vertex) facing ``normal``."""
    if radius <= 0:
        raise ValueError("disk needs radius > 0")
    # profile from rim to pole in the plane: normal = t_phi x (-e_r) = +axis
    return revolve_profile([(radius, 0.0), (0.0, 0.0)], n_seg, centre, normal)


def drum_mesh(radius, length, n_seg=48, axis_point=(0.0, 0.0, 0.0), axis_dir=(0.0, 0.0, 1.0),
              n_axial=1):
    """Closed cylinder (tube plus end caps) from axial 0 to ``length``,
    watertight and outward-wound; particles go inside (rotating drum)."""
    if radius <= 0 or length <= 0:
        raise ValueError("drum needs radius > 0 and length > 0")
    zs = np.linspace(0.0, length, int(n_axial) + 1)
    prof = [(0.0, 0.0)] + [(radius, z) for z in zs] + [(0.0, length)]
    return revolve_profile(prof, n_seg, axis_point, axis_dir)


def plate_mesh(centre, u_axis, v_axis, width, height, n_u=1, n_v=1):
    """Flat rectangle ``width`` along ``u_axis`` x ``height`` along ``v_axis``,
    centred at ``centre``; normal ``u x v``."""
    c = np.asarray(centre, dtype=np.float64)
    u = np.asarray(u_axis, dtype=np.float64)
    u = u / np.linalg.norm(u)
    v = np.asarray(v_axis, dtype=np.float64)
    v = v - u * (u @ v)
    v = v / np.linalg.norm(v)
    s = np.linspace(-0.5 * width, 0.5 * width, int(n_u) + 1)
    t = np.linspace(-0.5 * height, 0.5 * height, int(n_v) + 1)
    S, T = np.meshgrid(s, t, indexing="ij")
    verts = c + S.reshape(-1, 1) * u + T.reshape(-1, 1) * v
    return verts, _grid_triangles(len(s), len(t))


def _grid_triangles(ni, nj):
    """Triangles of a structured (ni x nj) vertex grid, index i*nj + j, wound
    with normal (d/di) x (d/dj)."""
    i, j = np.meshgrid(np.arange(ni - 1), np.arange(nj - 1), indexing="ij")
    a = (i * nj + j).ravel()
    b = ((i + 1) * nj + j).ravel()
    c = ((i + 1) * nj + j + 1).ravel()
    d = (i * nj + j + 1).ravel()
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]).astype(np.int64)


def extrude_curve(curve, direction, length, n_along=1, origin=(0.0, 0.0, 0.0)):
    """Ruled surface swept by a directrix ``curve`` along a straight generator.

    ``curve`` is (m, 3), or (m, 2) read as (x, z) points in the plane y = 0
    (the side profile of a bulldozing blade or moldboard); vertices are
    ``origin + curve_i + s * direction_unit`` for ``s`` in
    ``linspace(0, length, n_along + 1)``.  Normal ``t_curve x direction``.
    """
    cv = np.asarray(curve, dtype=np.float64)
    if cv.ndim != 2 or cv.shape[0] < 2 or cv.shape[1] not in (2, 3):
        raise ValueError(f"curve must be (m >= 2, 2 or 3), got {cv.shape}")
    if cv.shape[1] == 2:
        cv = np.column_stack([cv[:, 0], np.zeros(len(cv)), cv[:, 1]])
    g = np.asarray(direction, dtype=np.float64)
    g = g / np.linalg.norm(g)
    if length <= 0:
        raise ValueError("extrusion length must be > 0")
    s = np.linspace(0.0, length, int(n_along) + 1)
    o = np.asarray(origin, dtype=np.float64)
    verts = (o + cv[:, None, :] + s[None, :, None] * g).reshape(-1, 3)
    return verts, _grid_triangles(cv.shape[0], s.shape[0])


# ---------------------------------------------------------------------------
# parameter-row variants for wall tables (scalars in, no allocation)
# ---------------------------------------------------------------------------
# The kernels above accept any indexable (array, array view or tuple) for
# points and directions, so an engine can pass ``(px, py, pz)`` and rows of a
# float64[P, 16] parameter table.  Row layouts:
#   plane      point(0:3) unit normal(3:6)
#   rectangle  centre(0:3) unit normal(3:6) unit u axis(6:9) half_u(9) half_v(10)
#   disk       centre(0:3) unit normal(3:6) radius(6)
#   cylinder   axis point = centre(0:3) unit axis(3:6) radius(6) half length(7)
#              inner flag(8)   (shell from -half length to +half length)
#   cone       axis point(0:3) unit axis(3:6) r0(6) r1(7) z0(8) z1(9) inner flag(10)
#   triangle   v0(0:3) v1(3:6) v2(6:9)


@njit(cache=True)
def _row3(par, k, o):
    """Three consecutive entries of a parameter row as a tuple (array views
    would cost reference counting in the inner loop)."""
    return (par[k, o], par[k, o + 1], par[k, o + 2])


@njit(cache=True)
def plane_closest_par(px, py, pz, par, k):
    return plane_closest((px, py, pz), _row3(par, k, 0), _row3(par, k, 3))


@njit(cache=True)
def rectangle_closest_par(px, py, pz, par, k):
    return rectangle_closest((px, py, pz), _row3(par, k, 0), _row3(par, k, 3), _row3(par, k, 6),
                             par[k, 9], par[k, 10])


@njit(cache=True)
def disk_closest_par(px, py, pz, par, k):
    return disk_closest((px, py, pz), _row3(par, k, 0), _row3(par, k, 3), par[k, 6])


@njit(cache=True)
def cylinder_closest_par(px, py, pz, par, k):
    h = par[k, 7]
    return cone_closest((px, py, pz), _row3(par, k, 0), _row3(par, k, 3), par[k, 6],
                        par[k, 6], -h, h, par[k, 8] != 0.0)


@njit(cache=True)
def cone_closest_par(px, py, pz, par, k):
    return cone_closest((px, py, pz), _row3(par, k, 0), _row3(par, k, 3), par[k, 6], par[k, 7],
                        par[k, 8], par[k, 9], par[k, 10] != 0.0)


@njit(cache=True)
def triangle_closest_par(px, py, pz, par, k):
    return triangle_closest((px, py, pz), _row3(par, k, 0), _row3(par, k, 3), _row3(par, k, 6))


def mesh_to_par(vertices, triangles, npar=16):
    """Triangle parameter rows ``v0(0:3) v1(3:6) v2(6:9)`` of a mesh."""
    v, t = _as_mesh(vertices, triangles)
    par = np.zeros((t.shape[0], npar))
    par[:, 0:9] = v[t].reshape(-1, 9)
    return par
