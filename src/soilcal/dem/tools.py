"""Soil-engaging tool geometry generated from the papers' printed dimensions.

Every builder returns an indexed triangle mesh ``(vertices float64[nv, 3] in m,
triangles int64[nt, 3])`` in the *tool frame*: the tool travels along ``+x``, ``z`` is up,
``y`` is lateral, and the lowest working point of the tool is at ``z = 0`` (so placing a
tool at working depth ``d`` below a soil surface at height ``h`` is a translation by
``h - d`` in z).  Tool surfaces are zero-thickness open sheets (the engine's triangle walls
are two-sided), kept coarse (tens to ~150 triangles) because every particle tests every
wall triangle at each neighbour-list rebuild.

The three tools
---------------
1. **Moldboard-style ridge and furrow opener** (Yangtze clay loam, Zeng et al.,
   Agriculture 2023, 13, 648).  Printed: working depth 200 mm and speed 0.72 m/s
   (Sec. 2.1.2, Sec. 2.2.4); "upper and lower wings" whose intersection line is flush with
   the ground (Sec. 2.1.2, Figure 1c); the measured furrow contour F(x) of Eq. (3) turns
   over at x = +223.8 mm (its right-hand maximum, F = 129.6 mm); on the left it has no
   maximum and keeps rising (F(-223.8) = 128.6 mm, F(-300) = 1706 mm), so the opener is
   made symmetric about the right-hand turning point.  The drawing (Figure 1c) prints no
   dimension, so the opener is a symmetric double moldboard whose rear section follows an
   assumed theoretical furrow (Figure 2): bottom half-width ``b0`` = 50 mm (assumption),
   half-width 225 mm at the ground line (the right-hand turning point of Eq. 3, used on
   both sides), an upper wing ``h_up`` = 100 mm above the ground widening to 300 mm
   (assumption), body length ``L`` = 450 mm (assumption).  Each
   wing is the surface::

       y(u, z) = w(z) (u + u^2) / 2,   x = -L u,   u in [0, 1]

   with ``w(z)`` piecewise linear through the rear section points, so the wing meets the
   soil at ``atan(w / (2 L))`` at the share point and turns it out at
   ``atan(3 w / (2 L))`` at the rear (a concave moldboard).  A flat sole joins the two
   lower wing edges and a flat cover the two upper ones, so the body is closed except at
   the rear (soil spilling over the upper wings would otherwise fall into the converging
   wedge and be pushed along, a resistance that grows without bound).

2. **Bulldozing plates** (cinnamon soil, Qiu et al., Agriculture 2022, 12, 1082,
   Sec. 4.2.1, Figure 7, Table 9).  Printed: plate height x breadth 150 x 300 mm, straight
   cutting-edge segment S = 20 mm, cutting angle delta = 55 deg for the three curved
   directrices, skew (chord) angle epsilon = 78 deg for all, front roll angles
   beta_k = 72.4 (arc), 80.2 (parabola), 69.4 deg (bionic), the ruled (straight) plate set
   at the 78 deg skew angle.  Depth 30 mm, speed 0.16 m/s (Sec. 4.2.1).  The directrix is
   drawn in the (x, z) plane with the cutting edge at the origin and the face looking
   towards +x; its tangent angle ``theta`` is measured from the horizontal ``-x`` axis
   (the cutting angle is the tangent angle at the edge).  The chord from the cutting edge
   to the top edge makes the skew angle, so the top edge lies at
   ``(-H / tan(epsilon), H)``; the front roll angle is the tangent angle at the top edge
   measured on the other side, ``beta_k = 180 deg - theta_top``.

   * line: the straight segment from the edge to the top (delta = epsilon = 78 deg);
   * arc: the edge segment then the circular arc tangent to it at P1 = S (cos, sin) delta
     through the top point P2; a circle's end tangents are symmetric about its chord, so
     ``theta_top = 2 phi - delta`` with ``phi`` the angle of P2 - P1.  With the printed
     numbers this gives beta_k = 72.4 deg, the value of Table 9 (a check of this reading
     of Figure 7 and Table 9, tested);
   * parabola: the quadratic Bezier curve (a parabolic arc) from P1 to P2 whose end
     tangents are delta and ``180 - beta_k`` (control point at the intersection of the two
     tangent lines);
   * bionic curve: the vole claw-toe contour of Figure 8 is not printed as data; it is
     replaced by a curve of linearly varying curvature (an Euler-spiral arc,
     ``theta(s) = delta + c1 s/Ls + c2 (s/Ls)^2``) from P1 with tangent delta to P2 with
     tangent ``180 - beta_k``; ``c1, Ls`` solve the two position conditions (assumption:
     "variable curvature" of Sec. 4.2.1 taken as linear in arc length).

   Table 9 prints a clearance angle alpha = 20 deg and a shovel point closed angle
   beta = 30 deg for the three curved plates (arc, parabola, bionic) and 30 deg / 48 deg
   for the straight-line plate (the text of Sec. 4.2.1 gives 20 deg and 48 deg).  These
   angles shape the back of the cutting edge, which the soil in front of the plate does not
   touch, so they are not used: the plate is modelled as its soil-engaging face only.

3. **Rotary tiller blade set** (black soil, Qi et al., Sustainability 2025, 17, 8126,
   Sec. 2.1 (2), Table 1): 1GKN-160 tiller, working width 1.6 m, 36 IT225 curved blades,
   18 bent left and 18 bent right, installed symmetrically.  The paper prints no blade
   drawing.  IT225 is the GB/T 5669 designation whose number is the rotary radius
   R = 225 mm.  Simplified blade (assumptions): a flat side part in the plane normal to
   the shaft from the holder radius ``r_hub`` = 100 mm, width ``w`` = 50 mm, whose outer
   edge (the bend line) is inclined by ``2 dr`` over the width (dr = 15 mm), and a flat bent
   part swept from the bend line by ``c`` = 30 mm radially and ``b`` = 50 mm sideways, so its
   outermost corner reaches R.  The bent part's normal
   ``(w s b, 2 dr s b, -w c)`` in the (radial, tangential, axial) frame has a tangential
   component: the bent part faces the direction of rotation and pushes the soil slice it
   cuts.  Arrangement (assumption): 12 flanges at 1.6 m / 12 spacing, 3 blades per flange
   120 deg apart, phase advanced 10 deg per flange (a helix, 36 distinct phases), bend side
   alternating so that 18 blades bend each way.  The shaft lies along ``y`` through the
   origin; blades at the canonical phase point down (-z) and, for rotation
   ``omega = +|omega| e_y`` (down-cut, the rotor turning like the tractor wheels), move
   towards -x at the bottom.

STL files
---------
:func:`write_all` writes every tool as a binary STL under
``resources/geometry/<soil>/<tool>.stl`` (``python -m soilcal.dem.tools [--out DIR]``);
:func:`mesh_report` checks a mesh: watertight (every directed edge once and its reverse
once), or an open surface whose edges are each shared by at most two triangles with
consistent winding and no degenerate triangle.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from soilcal.dem.geometry import extrude_curve, is_watertight, merge_meshes, rotation_matrix
from soilcal.dem.stl import write_stl
from soilcal.errors import InputError

# ---------------------------------------------------------------------------
# printed dimensions (SI)
# ---------------------------------------------------------------------------

# Yangtze clay loam ridge/furrow opener (Zeng et al. 2023)
OPENER = dict(
    depth=0.200,          # Sec. 2.1.2 / 2.2.4: depth of soil entry 200 mm
    half_width=0.225,     # Eq. (3): F(x) turns over at x = +223.8 mm (rounded; both sides)
    bottom_half_width=0.05,  # assumption (Figure 2 prints no dimension)
    upper_height=0.10,    # assumption: upper wing above the ground line
    upper_half_width=0.30,  # assumption
    length=0.45,          # assumption
)

# Cinnamon soil bulldozing plates (Qiu et al. 2022, Sec. 4.2.1, Table 9)
PLATE = dict(
    height=0.150,         # Sec. 4.2.1: height x breadth 150 x 300 mm
    breadth=0.300,
    edge_length=0.020,    # Sec. 4.2.1: cutting edge straight segment S = 20 mm
    cutting_angle=55.0,   # Table 9, delta (curved directrices)
    skew_angle=78.0,      # Table 9, epsilon; ruled plate cut at 78 deg (Sec. 4.2.1)
)
FRONT_ROLL = {"arc": 72.4, "parabola": 80.2, "bionic": 69.4}  # Table 9, beta_k (deg)
# Table 9 also prints clearance / shovel point closed angles of 20 / 30 deg (arc, parabola,
# bionic) and 30 / 48 deg (straight line); they shape the back of the edge and are not
# modelled (module notes)
SHAPES = ("line", "arc", "parabola", "bionic")

# Black soil rotary tiller (Qi et al. 2025, Table 1, Sec. 2.1 (2)); blade shape assumed
ROTOR = dict(
    radius=0.225,         # IT225: rotary radius 225 mm (GB/T 5669 designation)
    hub_radius=0.100,     # assumption
    blade_width=0.050,    # assumption
    bend_incline=0.015,   # assumption (dr)
    bend_radial=0.030,    # assumption (c)
    bend_axial=0.050,     # assumption (b)
    working_width=1.6,    # Table 1: working width 160 cm
    n_blades=36,          # Table 1 / Sec. 2.1 (2)
    n_flanges=12,         # assumption (36 = 12 x 3)
    blades_per_flange=3,  # assumption
    phase_step_deg=10.0,  # assumption: helix, 36 distinct phases
)


def _pos(value, source, field, what="> 0"):
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(source, field, f"a number {what}", value) from None
    if not (math.isfinite(x) and x > 0):
        raise InputError(source, field, f"a number {what}", value)
    return x


# ---------------------------------------------------------------------------
# mesh checks
# ---------------------------------------------------------------------------


def mesh_report(vertices, triangles) -> dict:
    """Topology summary: watertight, boundary/non-manifold edge counts, winding, areas."""
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    a = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    area = 0.5 * np.linalg.norm(a, axis=1)
    und = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    _, counts = np.unique(und, axis=0, return_counts=True)
    directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    _, dcounts = np.unique(directed, axis=0, return_counts=True)
    return dict(
        n_vertices=int(len(v)), n_triangles=int(len(t)),
        watertight=bool(is_watertight(t)),
        boundary_edges=int(np.sum(counts == 1)),
        nonmanifold_edges=int(np.sum(counts > 2)),
        consistent_winding=bool(np.all(dcounts == 1)),
        min_triangle_area=float(area.min()), area=float(area.sum()),
        bbox_lo=v.min(axis=0).tolist(), bbox_hi=v.max(axis=0).tolist(),
    )


def check_open_surface(vertices, triangles, name="mesh"):
    """Raise ValueError unless the mesh is a valid open surface (or watertight)."""
    rep = mesh_report(vertices, triangles)
    if rep["nonmanifold_edges"] or not rep["consistent_winding"] or rep["min_triangle_area"] <= 0:
        raise ValueError(f"{name}: not a valid surface: {rep}")
    return rep


# ---------------------------------------------------------------------------
# 1. ridge and furrow opener
# ---------------------------------------------------------------------------


def opener_section(z, depth, bottom_half_width, half_width, upper_height, upper_half_width):
    """Rear half-width w(z) of the opener: linear from the bottom (z = 0) to the ground
    line (z = depth) and on to the top of the upper wing."""
    return np.interp(z, [0.0, depth, depth + upper_height],
                     [bottom_half_width, half_width, upper_half_width])


def furrow_opener(depth=OPENER["depth"], half_width=OPENER["half_width"],
                  bottom_half_width=OPENER["bottom_half_width"],
                  upper_height=OPENER["upper_height"],
                  upper_half_width=OPENER["upper_half_width"], length=OPENER["length"],
                  n_length=6, n_height=5, source="<furrow_opener>"):
    """Symmetric double-moldboard ridge/furrow opener (see module docstring); share point
    at the origin, body towards -x; open at the rear, ``4 n_length n_height +
    2 (2 n_length - 1)`` triangles."""
    depth = _pos(depth, source, "depth")
    half_width = _pos(half_width, source, "half_width")
    b0 = _pos(bottom_half_width, source, "bottom_half_width")
    hu = _pos(upper_height, source, "upper_height")
    wu = _pos(upper_half_width, source, "upper_half_width")
    length = _pos(length, source, "length")
    if not b0 < half_width <= wu:
        raise InputError(source, "half_width",
                         "bottom_half_width < half_width <= upper_half_width",
                         (b0, half_width, wu))
    u = np.linspace(0.0, 1.0, int(n_length) + 1)
    nz_low = max(1, int(round(n_height * depth / (depth + hu))))
    zs = np.concatenate([np.linspace(0.0, depth, nz_low + 1),
                         np.linspace(depth, depth + hu, int(n_height) - nz_low + 1)[1:]])
    w = opener_section(zs, depth, b0, half_width, hu, wu)
    shape = 0.5 * (u + u * u)
    U, Z = np.meshgrid(u, zs, indexing="ij")
    Wg = np.broadcast_to(w, U.shape)
    Sg = np.broadcast_to(shape[:, None], U.shape)
    x = -length * U
    right = np.column_stack([x.ravel(), (Wg * Sg).ravel(), Z.ravel()])
    left = right * np.array([1.0, -1.0, 1.0])
    ni, nj = U.shape
    from soilcal.dem.geometry import _grid_triangles

    tri = _grid_triangles(ni, nj)
    # the two wings share the leading edge (u = 0, y = 0): weld it
    nr = len(right)
    verts = np.concatenate([right, left])
    tl = tri[:, ::-1] + nr  # mirrored wing: reverse winding
    lead = np.arange(nj)  # u = 0 row of the right wing (index i*nj + j, i = 0)
    remap = np.arange(2 * nr)
    remap[nr + lead] = lead
    tl = remap[tl]
    # sole: strip between the bottom edges (z = 0) of the two wings
    rb = np.arange(ni) * nj            # right wing, j = 0
    lb = remap[nr + np.arange(ni) * nj]  # left wing, j = 0 (first one welded)
    sole = []
    for i in range(ni - 1):
        if i == 0:
            sole.append((rb[0], lb[1], rb[1]))
        else:
            sole.append((rb[i], lb[i], lb[i + 1]))
            sole.append((rb[i], lb[i + 1], rb[i + 1]))
    # cover: the same strip between the top edges of the wings, wound the other way, so
    # that soil spilling over the upper wings cannot fall into the wedge and be pushed along
    rt = np.arange(ni) * nj + (nj - 1)
    lt = remap[nr + np.arange(ni) * nj + (nj - 1)]
    cover = []
    for i in range(ni - 1):
        if i == 0:
            cover.append((rt[0], rt[1], lt[1]))
        else:
            cover.append((rt[i], lt[i + 1], lt[i]))
            cover.append((rt[i], rt[i + 1], lt[i + 1]))
    tris = np.concatenate([tri, tl, np.array(sole, dtype=np.int64),
                           np.array(cover, dtype=np.int64)])
    used = np.unique(tris)
    new = -np.ones(len(verts), dtype=np.int64)
    new[used] = np.arange(len(used))
    return verts[used], new[tris]


# ---------------------------------------------------------------------------
# 2. bulldozing plates
# ---------------------------------------------------------------------------


def _direction(theta):
    """Unit tangent of the directrix at tangent angle theta (rad, from the -x axis)."""
    return np.array([-np.cos(theta), np.sin(theta)])


def directrix_ends(height=PLATE["height"], edge_length=PLATE["edge_length"],
                   cutting_angle=PLATE["cutting_angle"], skew_angle=PLATE["skew_angle"]):
    """P1 (end of the straight cutting-edge segment) and P2 (top edge), (x, z) in m."""
    d = math.radians(cutting_angle)
    e = math.radians(skew_angle)
    p1 = edge_length * _direction(d)
    p2 = np.array([-height / math.tan(e), height])
    return p1, p2


def arc_front_roll_angle(**kw) -> float:
    """Front roll angle beta_k (deg) implied by a circular arc directrix (theta_top =
    2 phi - delta, beta_k = 180 - theta_top)."""
    p1, p2 = directrix_ends(**kw)
    c = p2 - p1
    phi = math.atan2(c[1], -c[0])
    d = math.radians(kw.get("cutting_angle", PLATE["cutting_angle"]))
    return 180.0 - math.degrees(2.0 * phi - d)


def _spiral_points(p1, theta0, c1, c2, ls, t):
    """Points of theta(s) = theta0 + c1 tau + c2 tau^2 (tau = s/ls) at tau = t (numerical
    integration of the unit tangent by Gauss-Legendre on each sub-interval)."""
    gx, gw = np.polynomial.legendre.leggauss(12)
    out = [np.asarray(p1, dtype=float)]
    for a, b in zip(t[:-1], t[1:]):
        tau = 0.5 * (b - a) * gx + 0.5 * (a + b)
        th = theta0 + c1 * tau + c2 * tau * tau
        dx = ls * 0.5 * (b - a) * np.sum(gw * -np.cos(th))
        dz = ls * 0.5 * (b - a) * np.sum(gw * np.sin(th))
        out.append(out[-1] + np.array([dx, dz]))
    return np.array(out)


def directrix(shape, n=16, height=PLATE["height"], edge_length=PLATE["edge_length"],
              cutting_angle=PLATE["cutting_angle"], skew_angle=PLATE["skew_angle"],
              front_roll_angle=None, source="<directrix>"):
    """Directrix points (x, z) in m from the cutting edge (0, 0) to the top edge, ``n``
    segments on the curved part (module docstring for each shape)."""
    if shape not in SHAPES:
        raise InputError(source, "shape", f"one of {', '.join(SHAPES)}", shape)
    height = _pos(height, source, "height")
    edge_length = _pos(edge_length, source, "edge_length")
    if not 0 < cutting_angle < 180 or not 0 < skew_angle < 180:
        raise InputError(source, "cutting_angle/skew_angle", "angles in (0, 180) deg",
                         (cutting_angle, skew_angle))
    n = int(n)
    if shape == "line":
        p2 = np.array([-height / math.tan(math.radians(skew_angle)), height])
        return np.outer(np.linspace(0.0, 1.0, n + 1), p2)
    p1, p2 = directrix_ends(height, edge_length, cutting_angle, skew_angle)
    if p1[1] >= height:
        raise InputError(source, "edge_length", "a cutting-edge segment below the plate "
                         "height", edge_length)
    th0 = math.radians(cutting_angle)
    chord = p2 - p1
    phi = math.atan2(chord[1], -chord[0])
    if shape == "arc":
        dth = 2.0 * (phi - th0)
        if abs(dth) < 1e-12:
            curve = np.outer(np.linspace(0, 1, n + 1), chord) + p1
        else:
            rho = np.linalg.norm(chord) / (2.0 * math.sin(0.5 * dth))
            th = th0 + np.linspace(0.0, dth, n + 1)
            curve = p1 + rho * np.column_stack([-(np.sin(th) - math.sin(th0)),
                                                 (math.cos(th0) - np.cos(th))])
        return np.vstack([[0.0, 0.0], curve])
    bk = FRONT_ROLL[shape] if front_roll_angle is None else float(front_roll_angle)
    th1 = math.radians(180.0 - bk)
    if shape == "parabola":
        d0, d1 = _direction(th0), _direction(th1)
        # p1 + a d0 = p2 - b d1
        a, b = np.linalg.solve(np.column_stack([d0, d1]), chord)
        if not (a > 0 and b > 0):
            raise InputError(source, "front_roll_angle", "end tangents that meet ahead of "
                             "both ends (a convex parabolic directrix)", bk)
        ctrl = p1 + a * d0
        s = np.linspace(0.0, 1.0, n + 1)[:, None]
        curve = (1 - s) ** 2 * p1 + 2 * s * (1 - s) * ctrl + s ** 2 * p2
        return np.vstack([[0.0, 0.0], curve])
    c1, ls = _bionic_solve(p1, p2, th0, th1, height, bk, source)
    curve = _spiral_points(p1, th0, c1, th1 - th0 - c1, ls, np.linspace(0.0, 1.0, n + 1))
    return np.vstack([[0.0, 0.0], curve])


def _bionic_solve(p1, p2, th0, th1, height, bk, source):
    """c1, ls of theta(tau) = th0 + c1 tau + (th1 - th0 - c1) tau^2 reaching p2."""
    # here, not at module import: scipy.optimize costs every DEM job that builds no such tool ~0.5 s
    from scipy.optimize import fsolve

    def resid(z):
        c1, ls = z
        end = _spiral_points(p1, th0, c1, th1 - th0 - c1, ls, np.array([0.0, 1.0]))[-1]
        return (end - p2) / height

    z0 = np.array([th1 - th0, np.linalg.norm(p2 - p1)])
    sol, info, ier, msg = fsolve(resid, z0, full_output=True, xtol=1e-12)
    if ier != 1 or np.max(np.abs(resid(sol))) > 1e-9 or sol[1] <= 0:
        raise InputError(source, "front_roll_angle", "a reachable top tangent for the "
                         "variable-curvature directrix", bk)
    return float(sol[0]), float(sol[1])


def bionic_coefficients(front_roll_angle=FRONT_ROLL["bionic"], height=PLATE["height"],
                        edge_length=PLATE["edge_length"], cutting_angle=PLATE["cutting_angle"],
                        skew_angle=PLATE["skew_angle"]):
    """(c1, c2, ls) of the bionic directrix theta(tau) = delta + c1 tau + c2 tau^2 (rad, m);
    the curvature d theta / ds = (c1 + 2 c2 tau) / ls varies linearly along the curve."""
    p1, p2 = directrix_ends(height, edge_length, cutting_angle, skew_angle)
    th0 = math.radians(cutting_angle)
    th1 = math.radians(180.0 - front_roll_angle)
    c1, ls = _bionic_solve(p1, p2, th0, th1, height, front_roll_angle, "<bionic>")
    return c1, th1 - th0 - c1, ls


def bulldozing_plate(shape, breadth=PLATE["breadth"], n=16, source="<bulldozing_plate>",
                     **kw):
    """Plate surface: the directrix swept along y (straight generatrix, parallel
    translation, Sec. 4.2.1) over ``breadth`` centred on y = 0; cutting edge on the x = 0,
    z = 0 line; ``2 (m - 1)`` triangles for ``m`` directrix points."""
    breadth = _pos(breadth, source, "breadth")
    pts = directrix(shape, n=n, source=source, **kw)
    # drop the duplicate point where the edge segment meets a 0-length start
    keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-12])
    pts = pts[keep]
    return extrude_curve(pts, (0.0, 1.0, 0.0), breadth, n_along=1,
                         origin=(0.0, -0.5 * breadth, 0.0))


def tangent_angles(points):
    """Tangent angle (deg, from the -x axis) of each segment of an (x, z) polyline."""
    d = np.diff(np.asarray(points, dtype=float), axis=0)
    return np.degrees(np.arctan2(d[:, 1], -d[:, 0]))


# ---------------------------------------------------------------------------
# 3. rotary tiller blades
# ---------------------------------------------------------------------------


def rotary_blade(side=1, radius=ROTOR["radius"], hub_radius=ROTOR["hub_radius"],
                 width=ROTOR["blade_width"], bend_incline=ROTOR["bend_incline"],
                 bend_radial=ROTOR["bend_radial"], bend_axial=ROTOR["bend_axial"],
                 phase_deg=0.0, y0=0.0, source="<rotary_blade>"):
    """One simplified IT-series blade (module docstring), 4 triangles, at phase
    ``phase_deg`` (rotation about +y from pointing down) and axial position ``y0``; ``side``
    +1 bends towards +y, -1 towards -y."""
    radius = _pos(radius, source, "radius")
    rb = radius - bend_radial - bend_incline  # bend-line radius at mid-width
    if not 0 < hub_radius < rb - bend_incline:
        raise InputError(source, "hub_radius", f"0 < hub_radius < {rb - bend_incline:.4g} m "
                         "(inside the bend line)", hub_radius)
    if side not in (1, -1):
        raise InputError(source, "side", "+1 or -1", side)
    er, et, ey = np.array([0.0, 0.0, -1.0]), np.array([-1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    h = 0.5 * width

    def p(r, t, y):
        return r * er + t * et + y * ey

    a = p(rb + bend_incline, -h, 0.0)   # bend line, trailing end
    bb = p(rb - bend_incline, h, 0.0)   # bend line, leading end
    s0 = p(hub_radius, -h, 0.0)
    s1 = p(hub_radius, h, 0.0)
    u = bend_radial * er + side * bend_axial * ey
    verts = np.array([s0, s1, bb, a, bb + u, a + u])
    tris = np.array([[0, 1, 2], [0, 2, 3], [3, 2, 4], [3, 4, 5]], dtype=np.int64)
    rot = rotation_matrix(np.array([0.0, 1.0, 0.0]), math.radians(phase_deg))
    verts = verts @ rot.T + np.array([0.0, y0, 0.0])
    return verts, tris


def rotor_layout(n_flanges=ROTOR["n_flanges"], blades_per_flange=ROTOR["blades_per_flange"],
                 width=ROTOR["working_width"], phase_step_deg=ROTOR["phase_step_deg"]):
    """(phase_deg, y0, side) of every blade: flanges at the centres of ``n_flanges`` equal
    strips of ``width`` (centred on y = 0), blades ``360/blades_per_flange`` apart, the
    helix advancing ``phase_step_deg`` per flange, bend sides alternating."""
    sp = width / n_flanges
    out = []
    k = 0
    for f in range(int(n_flanges)):
        y0 = -0.5 * width + (f + 0.5) * sp
        for j in range(int(blades_per_flange)):
            side = 1 if (f + j) % 2 == 0 else -1
            out.append((f * phase_step_deg + j * 360.0 / blades_per_flange, y0, side))
            k += 1
    return out


def rotary_blade_set(n_flanges=ROTOR["n_flanges"], blades_per_flange=ROTOR["blades_per_flange"],
                     width=ROTOR["working_width"], phase_step_deg=ROTOR["phase_step_deg"],
                     source="<rotary_blade_set>", **blade):
    """Mesh of the whole blade set (4 triangles per blade), shaft along y through 0."""
    parts = [rotary_blade(side=s, phase_deg=ph, y0=y0, source=source, **blade)
             for ph, y0, s in rotor_layout(n_flanges, blades_per_flange, width, phase_step_deg)]
    return merge_meshes(*parts)


# ---------------------------------------------------------------------------
# files
# ---------------------------------------------------------------------------


def tool_meshes() -> dict:
    """{relative STL path: (vertices, triangles)} of every tool at the papers' sizes."""
    out = {"yangtze-clay-loam/furrow_opener.stl": furrow_opener()}
    for s in SHAPES:
        out[f"cinnamon-soil/bulldozing_plate_{s}.stl"] = bulldozing_plate(s)
    out["black-soil/rotary_blade_set.stl"] = rotary_blade_set()
    out["black-soil/rotary_blade.stl"] = rotary_blade()
    return out


def default_geometry_dir() -> Path:
    return Path(__file__).resolve().parents[3] / "resources" / "geometry"


def write_all(out_dir=None) -> list[Path]:
    """Write every tool as binary STL (metres) under ``out_dir``; returns the paths."""
    out_dir = Path(out_dir) if out_dir is not None else default_geometry_dir()
    paths = []
    for rel, (v, t) in tool_meshes().items():
        check_open_surface(v, t, rel)
        p = out_dir / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        write_stl(p, v, t, binary=True, name=Path(rel).stem)
        paths.append(p)
    return paths


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m soilcal.dem.tools",
                                 description="(re)generate the tool STL files")
    ap.add_argument("--out", default=None, help="output folder (default resources/geometry)")
    args = ap.parse_args(argv)
    for p in write_all(args.out):
        from soilcal.dem.stl import read_stl

        v, t = read_stl(p)
        rep = mesh_report(v, t)
        print(f"{p}: {rep['n_triangles']} triangles, watertight={rep['watertight']}, "
              f"boundary edges={rep['boundary_edges']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
