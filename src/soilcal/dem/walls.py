"""Walls: primitive arrays, prescribed rigid motion, closest-point dispatch.

A wall is a rigid body made of one or more primitives (plane, cylinder, cone, box, triangle
mesh).  Arrays (structure of arrays, float64)::

    prim_kind[P]   kind code (PLANE, CYLINDER, CONE, BOX, TRIANGLE)
    prim_wall[P]   owning wall id
    prim_mat[P]    material id of the wall surface
    prim_par[P,16] parameters; rows of 3 at offsets 0,3,6,9,12 are points or directions as
                   flagged by prim_pts[P] (bit k: row k is a point) and prim_dirs[P]
                   (bit k: row k is a direction); the remaining scalars are not moved
    wall_vel[W,3], wall_omega[W,3], wall_centre[W,3]   prescribed motion
    wall_force[W,3], wall_torque[W,3] (about wall_centre)   reaction of the particles

Rigid motion per step dt (Rodrigues' rotation formula, rotation angle |omega| dt about the
axis omega through the wall centre c)::

    p' = c + Rot(p - c) + v dt,   d' = Rot d,   c' = c + v dt
    wall velocity at a point q: v + omega x (q - c)

Closest point: every kind returns (dist, nx, ny, nz, cx, cy, cz, feature), the signed
distance from the sphere centre to the surface along the outward unit normal n (pointing from
the wall to the sphere centre), the closest surface point c and its feature: 0 face, 1 edge,
2 vertex of a triangle; 1 where the closest point of a rectangle, disk, cylinder or cone is
clamped to its rim (2 at a rectangle's corner), 0 for planes; overlap = radius - dist.  Plane::

    dist = (p - p0) . n0,   c = p - dist n0

the other kinds are the kernels of :mod:`soilcal.dem.geometry` (formulas there).

Parameter layouts (rows of prim_par):
    PLANE      point(0:3) unit normal(3:6)
    CYLINDER   axis point(0:3) unit axis(3:6) radius(6) half length(7) inner flag(8)
    CONE       axis point(0:3) unit axis(3:6) r0(6) r1(7) z0(8) z1(9) inner flag(10)
    RECTANGLE  centre(0:3) unit normal(3:6) unit u axis(6:9) half_u(9) half_v(10)
    DISK       centre(0:3) unit normal(3:6) radius(6)
    TRIANGLE   v0(0:3) v1(3:6) v2(6:9)   (boxes and any STL surface are triangle meshes)

One contact per touch: a sphere touching a mesh at a shared edge or vertex would be reported
by every triangle sharing it, and a triangle that meets the edge or face a sphere touches only
at one vertex reports that vertex as a second, farther contact.  The same holds across walls:
a floor made of two STL tiles, a tool whose blade and shank are separate meshes, or a mesh
lying on a plane or rectangle is one surface where the walls meet or overlap.  Per particle, a
contact whose point lies on another primitive, of the same or any other wall, is ignored when
that primitive's own closest point is not on the first one (that primitive is closer and
counts the contact), and among contacts with the same point the face before the edge or rim
before the vertex or corner is kept, then within one mesh the closer one (the surface's
true closest point, to rounding), then the one of the wall that counts (below; integrator
``_cover``).  "On" means within max(2e-4 R, 4 float32 ulps of the coordinates), within one
mesh as across walls: tiles exported with a gap, an overlap or a step of up to 2e-4 R (1e-6 m
for a 5 mm radius, a change of the overlap far below a contact's), patches of one STL file
whose copies of the seam vertices differ by float noise (not welded), or an STL tile (float32
vertices) on a float64 plane are one surface.  The overlap is the counting wall's own: where
it lies that little below the other, the force is that of the overlap less the step (0.99964
of it for an STL tile 1.19e-8 m below a plane at an overlap of 0.01 R).  Face contacts are
compared only where two of them have parallel normals (within 0.008 deg; a 0.1 deg crease is
two faces).  Contacts elsewhere stay: a sphere on a floor against the edge of a ledge of the
same mesh feels both.
So a sphere over a flat or convex surface feels one contact wherever it touches, as on the
plane or the solid the surface describes, however the surface is split into walls (LIGGGHTS
de-duplicates within one mesh only: its ``fix wall/gran`` treats every mesh with its own
contact history and edge flags, so a sphere on the seam of two meshes is pushed twice).  A
contact that passes over an edge or vertex from one triangle to the next, or from a face onto
a coplanar face of another wall, stays one contact: when the primitive that counts it has no
history yet, the history of the one it leaves (tangential spring, JKR neck, rolling spring,
largest plastic overlap, touching flag) passes to it, so a JKR neck in tension (overlap < 0)
or a sticking tangential spring carries on as on a plane.  Between walls of different
materials the history is carried over as it is: the spring and the JKR neck built on one
surface act on the next with that surface's stiffness and surface energy from then on.

Which wall counts where two lie on one surface (a belt or a turntable disk flush with a floor
plane, a liner tile on a plate): a moving wall before a fixed one, then a bounded primitive
(mesh, rectangle, disk, cylinder, cone) before an infinite plane, then the one added later, as
it lies on top (a liner added to a plate).  The contact moves with the wall that counts it: a
sphere on a belt set into a floor (a plane, a mesh or a rectangle) rolls at 2/7 of the belt
speed whichever was added first.

Limits.  At a concave crease (a valley between two faces, of one wall or two) both faces count
where the sphere centre lies over both (a wedge of width ``h tan(alpha)`` for a crease of
angle alpha at centre height h), and neither face's edge counts outside it; with an overlap
above ``R (1 - cos alpha)`` the second face's contact starts, and the first one's ends, with a
force step (a 5 mm sphere, centre 0.98 R above the first face, crossing a 5.6 deg crease:
2.368 to 1.371 times the Hertz force of a 0.02 R overlap where the first face's contact
ends).  LIGGGHTS keeps such an edge active on one of the two triangles (by triangle id), so it
has one of the two steps.  Wall contacts do not see periodic images: a
sphere near a periodic boundary does not feel a wall primitive across it.  So in a periodic box
a wall keeps the largest radius clear of the periodic boundaries, or its surface within that
radius of each boundary runs along the axis and is cut by both boundary planes in the same
section (a floor, a plate across the slab or wider than it, tiles that meet alike at both
boundaries, taken together when they move together), and a plane is parallel to the periodic
axes; a run refuses any other wall by name (``Simulation._check_periodic_walls``), a moving
one over the run (LIGGGHTS copies mesh elements across periodic boundaries).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from soilcal.dem.geometry import (cone_closest_par, cylinder_closest_par, disk_closest_par,
                                  rectangle_closest_par, triangle_closest_par)

PLANE, CYLINDER, CONE, BOX, TRIANGLE, RECTANGLE, DISK = 0, 1, 2, 3, 4, 5, 6
NPAR = 16


@njit(cache=True, inline="always")
def plane_dist(px, py, pz, par, p):
    nx, ny, nz = par[p, 3], par[p, 4], par[p, 5]
    d = (px - par[p, 0]) * nx + (py - par[p, 1]) * ny + (pz - par[p, 2]) * nz
    return d, nx, ny, nz, px - d * nx, py - d * ny, pz - d * nz


@njit(cache=True)
def prim_closest(kind, par, p, px, py, pz):
    """Dispatch to the closest-point function of primitive p (row of par) of a kind."""
    if kind == PLANE:
        d, nx, ny, nz, cx, cy, cz = plane_dist(px, py, pz, par, p)
        return d, nx, ny, nz, cx, cy, cz, 0
    if kind == TRIANGLE:
        r = triangle_closest_par(px, py, pz, par, p)
        return r[0], r[1], r[2], r[3], r[4], r[5], r[6], int(r[7])
    wx, wy, wz = px - par[p, 0], py - par[p, 1], pz - par[p, 2]
    ax, ay, az = par[p, 3], par[p, 4], par[p, 5]
    feat = 0
    if kind == CYLINDER or kind == CONE:
        if kind == CYLINDER:
            r = cylinder_closest_par(px, py, pz, par, p)
            z0, z1, r0, r1 = -par[p, 7], par[p, 7], par[p, 6], par[p, 6]
        else:
            r = cone_closest_par(px, py, pz, par, p)
            z0, z1, r0, r1 = par[p, 8], par[p, 9], par[p, 6], par[p, 7]
        # the rim: the closest point clamped to an end circle (cone_closest's t outside 0..1)
        z = wx * ax + wy * ay + wz * az
        qx, qy, qz = wx - z * ax, wy - z * ay, wz - z * az
        rr = math.sqrt(qx * qx + qy * qy + qz * qz)
        t = (z - z0) * (z1 - z0) + (rr - r0) * (r1 - r0)
        if t < 0.0 or t > (z1 - z0) ** 2 + (r1 - r0) ** 2:
            feat = 1
    elif kind == RECTANGLE:
        r = rectangle_closest_par(px, py, pz, par, p)
        ux, uy, uz = par[p, 6], par[p, 7], par[p, 8]
        vx = ay * uz - az * uy
        vy = az * ux - ax * uz
        vz = ax * uy - ay * ux
        # an edge (1) or corner (2): the closest point clamped to the rim
        feat = (int(abs(wx * ux + wy * uy + wz * uz) > par[p, 9])
                + int(abs(wx * vx + wy * vy + wz * vz) > par[p, 10]))
    elif kind == DISK:
        r = disk_closest_par(px, py, pz, par, p)
        h = wx * ax + wy * ay + wz * az
        qx, qy, qz = wx - h * ax, wy - h * ay, wz - h * az
        if qx * qx + qy * qy + qz * qz > par[p, 6] * par[p, 6]:
            feat = 1
    else:
        return math.inf, 0.0, 0.0, 1.0, px, py, pz, 0
    return r[0], r[1], r[2], r[3], r[4], r[5], r[6], feat


@njit(cache=True)
def _rotate(vx, vy, vz, kx, ky, kz, c, s):
    # Rodrigues: v c + (k x v) s + k (k.v)(1 - c)
    kv = kx * vx + ky * vy + kz * vz
    return (vx * c + (ky * vz - kz * vy) * s + kx * kv * (1.0 - c),
            vy * c + (kz * vx - kx * vz) * s + ky * kv * (1.0 - c),
            vz * c + (kx * vy - ky * vx) * s + kz * kv * (1.0 - c))


@njit(cache=True)
def move_walls(dt, prim_wall, prim_par, prim_pts, prim_dirs, wall_vel, wall_omega, wall_centre):
    """Advance every primitive by its wall's rigid motion over dt."""
    nw = wall_vel.shape[0]
    for p in range(prim_par.shape[0]):
        w = prim_wall[p]
        ox, oy, oz = wall_omega[w, 0], wall_omega[w, 1], wall_omega[w, 2]
        om = math.sqrt(ox * ox + oy * oy + oz * oz)
        vx, vy, vz = wall_vel[w, 0] * dt, wall_vel[w, 1] * dt, wall_vel[w, 2] * dt
        if om == 0.0 and vx == 0.0 and vy == 0.0 and vz == 0.0:
            continue
        c = math.cos(om * dt)
        s = math.sin(om * dt)
        kx, ky, kz = 0.0, 0.0, 1.0
        if om > 0.0:
            kx, ky, kz = ox / om, oy / om, oz / om
        for row in range(5):
            b = 3 * row
            if (prim_pts[p] >> row) & 1:
                qx = prim_par[p, b] - wall_centre[w, 0]
                qy = prim_par[p, b + 1] - wall_centre[w, 1]
                qz = prim_par[p, b + 2] - wall_centre[w, 2]
                if om > 0.0:
                    qx, qy, qz = _rotate(qx, qy, qz, kx, ky, kz, c, s)
                prim_par[p, b] = wall_centre[w, 0] + qx + vx
                prim_par[p, b + 1] = wall_centre[w, 1] + qy + vy
                prim_par[p, b + 2] = wall_centre[w, 2] + qz + vz
            elif (prim_dirs[p] >> row) & 1 and om > 0.0:
                qx, qy, qz = _rotate(prim_par[p, b], prim_par[p, b + 1], prim_par[p, b + 2],
                                     kx, ky, kz, c, s)
                prim_par[p, b] = qx
                prim_par[p, b + 1] = qy
                prim_par[p, b + 2] = qz
    for w in range(nw):
        for q in range(3):
            wall_centre[w, q] += wall_vel[w, q] * dt


class WallSet:
    """Python-side container of walls and their primitives (grown by Simulation.add_wall)."""

    def __init__(self):
        self.kind: list[int] = []
        self.wall: list[int] = []
        self.mat: list[int] = []
        self.par: list[np.ndarray] = []
        self.pts: list[int] = []
        self.dirs: list[int] = []
        self.vel: list[np.ndarray] = []
        self.omega: list[np.ndarray] = []
        self.centre: list[np.ndarray] = []
        self.names: list[str] = []

    def new_wall(self, name, velocity=(0, 0, 0), omega=(0, 0, 0), centre=(0, 0, 0)) -> int:
        self.names.append(name)
        self.vel.append(np.asarray(velocity, float).reshape(3))
        self.omega.append(np.asarray(omega, float).reshape(3))
        self.centre.append(np.asarray(centre, float).reshape(3))
        return len(self.names) - 1

    def add_prim(self, wall, kind, mat, values, pts, dirs):
        row = np.zeros(NPAR)
        row[: len(values)] = values
        self.kind.append(kind)
        self.wall.append(wall)
        self.mat.append(mat)
        self.par.append(row)
        self.pts.append(pts)
        self.dirs.append(dirs)

    def arrays(self):
        npr = len(self.kind)
        nw = len(self.names)
        return dict(
            prim_kind=np.array(self.kind, dtype=np.int64).reshape(npr),
            prim_wall=np.array(self.wall, dtype=np.int64).reshape(npr),
            prim_mat=np.array(self.mat, dtype=np.int64).reshape(npr),
            prim_par=np.array(self.par, dtype=np.float64).reshape(npr, NPAR),
            prim_pts=np.array(self.pts, dtype=np.int64).reshape(npr),
            prim_dirs=np.array(self.dirs, dtype=np.int64).reshape(npr),
            wall_vel=np.array(self.vel, dtype=np.float64).reshape(nw, 3),
            wall_omega=np.array(self.omega, dtype=np.float64).reshape(nw, 3),
            wall_centre=np.array(self.centre, dtype=np.float64).reshape(nw, 3),
        )
