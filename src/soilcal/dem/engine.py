"""Python front end of the DEM engine: :class:`Simulation`.

Example::

    mats = MaterialTable()
    soil = mats.add(Material("soil", density=2600, youngs=2.6e7, poisson=0.3))
    mats.set_pair("soil", "soil", restitution=0.5, friction=0.5, rolling_friction=0.1)
    sim = Simulation(mats, dt=2e-5, box=(0, 0.05, 0, 0.05), periodic=(True, True),
                     contact_model=dict(rolling="constant_torque"))
    sim.add_particles(x, r, "soil")
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    sim.run(20000)

The time step is checked against the Rayleigh time and, with JKR, the zero-load JKR
stiffness (materials.py) and the contact model is
composed by name (contact.py).  All arrays are structure-of-arrays numpy float64 and stay
owned by the object between calls to :meth:`Simulation.run`.

Storage order: every ``sort_every`` steps (default 1000, 0 = never; an attribute that may
change between runs), at the next build of the neighbour lists, and at the first build
after particles were added, the particle rows are re-sorted in memory into neighbour-cell
order, as LAMMPS does (``atom_modify sort``):
a random insertion otherwise scatters the partners of every list row over the whole
state, and each contact then reads cold cache lines.  Row i of ``x``, ``v``, ... is
therefore not the i-th particle added after a run: ``p.id`` holds each row's insertion id
(the ids :meth:`Simulation.add_particles` returned) and :meth:`Simulation.index` maps ids
to rows.  Contact histories follow their pairs through the sort.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from soilcal.dem import _kernel_cache as kc
from soilcal.dem import integrator as itg
from soilcal.dem.contact import H_SIZE, hist_width, jkr_separation, model_codes
from soilcal.dem.materials import DAMPING_DT_SAFETY, P_ESTAR, P_W, MaterialTable
from soilcal.dem.neighbour import GROUPS_MAX, SCRATCH_LEN, SGROUP_LEN
from soilcal.dem.state import ParticleState
from soilcal.dem.stl import without_area
from soilcal.dem.walls import CONE, CYLINDER, DISK, NPAR, PLANE, RECTANGLE, TRIANGLE, WallSet
from soilcal.errors import InputError, SimulationError


def _rows(source, field, value, n, what) -> np.ndarray:
    """``value`` as an (n, 3) array of finite numbers (one row is repeated n times; n None:
    any number of rows); InputError naming ``field`` otherwise."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(source, field, f"{what}: rows of three numbers", value) from None
    if a.ndim == 1 and a.size == 3:
        a = a.reshape(1, 3)
    if a.ndim != 2 or a.shape[1] != 3 or (n is not None and a.shape[0] not in (1, n)):
        rows = "rows" if n is None else f"one row or {n} rows"
        raise InputError(source, field, f"{what}: {rows} of three numbers",
                         f"an array of shape {a.shape}")
    if not np.all(np.isfinite(a)):
        k = int(np.flatnonzero(~np.all(np.isfinite(a), axis=1))[0])
        raise InputError(source, field, f"{what}: finite numbers",
                         f"row {k}: {tuple(float(q) for q in a[k])}")
    return a if n is None or a.shape[0] == n else np.repeat(a, n, axis=0)


def _vector(source, field, value, size=3) -> np.ndarray:
    """``value`` as ``size`` finite numbers; InputError naming ``field`` otherwise."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        a = None
    if a is None or a.size != size or not np.all(np.isfinite(a)):
        raise InputError(source, field, f"{size} finite numbers", value)
    return a.reshape(size).copy()


def _flags(source, field, value, n) -> np.ndarray:
    """``value`` (one boolean, or one per particle) as n booleans; InputError naming
    ``field`` otherwise (a list taken as one truth value would fix every particle)."""
    a = np.asarray(value, dtype=object)
    if a.ndim > 1 or a.size not in (1, n) or not all(
            isinstance(q, (bool, np.bool_)) for q in a.reshape(-1)):
        raise InputError(source, field, f"true or false, or one of them per particle ({n})",
                         value)
    return np.broadcast_to(a.reshape(-1).astype(np.bool_), (n,)).copy()


def _number(source, field, value, expected, ok) -> float:
    """``value`` as a finite float for which ``ok`` holds; InputError naming ``field``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(source, field, expected, value)
    x = float(value)
    if not (math.isfinite(x) and ok(x)):
        raise InputError(source, field, expected, value)
    return x


def _rise(nq, period):
    """How far a flat face whose unit normal has component ``nq`` along a periodic axis rises
    over the period (array or number): a sphere crossing the boundary lands that much deeper
    in it or farther from it.  Every flat primitive (plane, rectangle, triangle) is judged by
    this against the same limit in :meth:`Simulation._check_periodic_walls`."""
    nq = np.minimum(np.abs(nq), 1.0)
    with np.errstate(divide="ignore"):
        return np.where(nq < 1.0, period * nq / np.sqrt(1.0 - nq * nq), np.inf)


def _extent_along(kind, par, q, eps, period, eps_p):
    """``(lo, hi, parallel)``: the extent of a bounded primitive other than a triangle (those
    are taken at once in :meth:`Simulation._check_periodic_walls`) along axis q, and whether
    its surface runs along q (a flat face rising over the ``period`` by at most ``eps_p``,
    :func:`_rise`, a cylinder
    whose section across q is its circle within ``eps``: radius r, tilt t from q, the
    ellipse's long half-axis r / cos t at most eps longer; how far its section moves along
    q is judged by the sections, :class:`_Sections`)."""
    n = par[3:6]
    side = math.sqrt(max(0.0, 1.0 - float(n[q]) ** 2))
    if kind == RECTANGLE:
        v = np.cross(n, par[6:9])
        h = abs(par[6 + q]) * par[9] + abs(v[q]) * par[10]
        return float(par[q] - h), float(par[q] + h), bool(_rise(n[q], period) <= eps_p)
    if kind == DISK:
        return float(par[q] - par[6] * side), float(par[q] + par[6] * side), False
    if kind == CYLINDER:
        h = abs(n[q]) * par[7] + par[6] * side
        return (float(par[q] - h), float(par[q] + h),
                abs(n[q]) > 0 and par[6] * (1.0 / abs(n[q]) - 1.0) <= eps)
    # CONE: the end circles at z0 (radius r0) and z1 (r1)
    e0, e1 = par[q] + par[8] * n[q], par[q] + par[9] * n[q]
    return (float(min(e0 - par[6] * side, e1 - par[7] * side)),
            float(max(e0 + par[6] * side, e1 + par[7] * side)), False)


# ------------------------------------------------------------------ periodic sections
_ACROSS = ((1, 2), (2, 0))  # the coordinates across periodic axis x (y, z) and y (z, x)


def _flat_pieces(kinds, par, q):
    """The flat-along-q primitives ``par`` (rows of kinds ``kinds``) as triangles
    [n, 3, 3] (a rectangle as two) with the row each came from, and cylinders about q as
    circles [m, 3] (the axis across q where it crosses q = 0, radius), how far the axis
    moves across q per unit along q [m, 2], and their extents along q [m, 2]."""
    tri, trow, circ, crow, cext, slope = [], [], [], [], [], []
    for i, (kind, p) in enumerate(zip(kinds, par)):
        if kind == TRIANGLE:
            tri.append(p[:9].reshape(3, 3))
            trow += [i]
        elif kind == RECTANGLE:
            c, n, u = p[0:3], p[3:6], p[6:9]
            du, dv = u * p[9], np.cross(n, u) * p[10]
            k = [c - du - dv, c + du - dv, c + du + dv, c - du + dv]
            tri += [np.array([k[0], k[1], k[2]]), np.array([k[0], k[2], k[3]])]
            trow += [i, i]
        elif kind == CYLINDER:
            a0, a1 = _ACROSS[q]
            k = np.array([p[3 + a0], p[3 + a1]]) / p[3 + q]
            circ.append([p[a0] - k[0] * p[q], p[a1] - k[1] * p[q], p[6]])
            slope.append(k)
            h = abs(p[3 + q]) * p[7] + p[6] * math.sqrt(max(0.0, 1.0 - p[3 + q] ** 2))
            cext.append([p[q] - h, p[q] + h])
            crow.append(i)
    return (np.array(tri).reshape(-1, 3, 3), np.array(trow, dtype=np.int64),
            np.array(circ).reshape(-1, 3), np.array(slope).reshape(-1, 2),
            np.array(crow, dtype=np.int64), np.array(cext).reshape(-1, 2))


def _section_lines(tri, q, c, eps):
    """Where the plane q = c cuts triangles ``tri`` lying along q (their normals across
    q): one segment [k, 2, 2] in the coordinates across q per triangle reaching c (within
    ``eps``; a triangle ending less than ``eps`` short of c is cut at its end), with the
    index of its triangle."""
    s = tri[:, :, q]
    smin, smax = s.min(axis=1), s.max(axis=1)
    use = np.flatnonzero((smin <= c + eps) & (smax >= c - eps))
    if use.size == 0:
        return np.zeros((0, 2, 2)), use
    t, s = tri[use], s[use]
    cc = np.clip(c, smin[use], smax[use])
    p = t[:, :, list(_ACROSS[q])]
    pts, ok = [], []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        ds = s[:, j] - s[:, i]
        with np.errstate(divide="ignore", invalid="ignore"):
            w = (cc - s[:, i]) / ds
        cut = (ds != 0) & (w >= 0) & (w <= 1)
        w = np.where(cut, w, 0.0)
        on = (ds == 0) & (s[:, i] == cc)  # an edge lying in the plane
        pts += [p[:, i] + w[:, None] * (p[:, j] - p[:, i]), p[:, i], p[:, j]]
        ok += [cut, on, on]
    pts, ok = np.stack(pts, axis=1), np.stack(ok, axis=1)
    # the cut of a triangle along q is a segment along the line (its plane) x (q axis)
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    eq = np.zeros(3)
    eq[q] = 1.0
    d = np.cross(eq, n)[:, list(_ACROSS[q])]
    d /= np.linalg.norm(d, axis=1)[:, None]
    h = np.einsum("kij,kj->ki", pts, d)
    i0 = np.argmin(np.where(ok, h, np.inf), axis=1)
    i1 = np.argmax(np.where(ok, h, -np.inf), axis=1)
    k = np.arange(use.size)
    seg = np.stack([pts[k, i0], pts[k, i1]], axis=1)
    return seg, use


def _covered(x, y, tol) -> bool:
    """Whether every point of the segments ``x`` [k, 2, 2] lies within ``tol`` of a segment
    of ``y`` [m, 2, 2]: along each segment of x, the points within tol of one segment of y
    (the convex capsule about it) form one interval, and those intervals must cover the
    whole segment.  Points and pieces of x shorter than tol (a corner touching the plane)
    are left out.  No segments are joined first, so how finely a surface is meshed does not
    change the answer."""
    if x.shape[0]:
        x = x[np.linalg.norm(x[:, 1] - x[:, 0], axis=1) > tol]
    if x.shape[0] == 0:
        return True
    if y.shape[0] == 0:
        return False
    a, e = y[:, 0], y[:, 1] - y[:, 0]
    ln = np.linalg.norm(e, axis=1)
    u = e / np.where(ln > 0, ln, 1.0)[:, None]
    nrm = np.stack([-u[:, 1], u[:, 0]], axis=1)
    t2 = tol * tol
    for k0 in range(0, x.shape[0], 256):
        p0 = x[k0:k0 + 256, 0]
        d = x[k0:k0 + 256, 1] - p0
        dd = np.einsum("ij,ij->i", d, d)[:, None]
        starts, ends = [], []
        for c in (y[:, 0], y[:, 1]):  # the discs about y's ends: |p0 + t d - c| <= tol
            w = p0[:, None, :] - c[None]
            bb = np.einsum("kij,kj->ki", w, d)
            disc = bb * bb - dd * (np.einsum("kij,kij->ki", w, w) - t2)
            r = np.sqrt(np.maximum(disc, 0.0))
            ok = disc >= 0
            starts.append(np.where(ok, (-bb - r) / dd, np.inf))
            ends.append(np.where(ok, (-bb + r) / dd, -np.inf))
        # the band beside y: |n.(p - a)| <= tol and 0 <= u.(p - a) <= |e|
        w = p0[:, None, :] - a[None]
        s0, s1 = np.full(w.shape[:2], -np.inf), np.full(w.shape[:2], np.inf)
        for dirn, lo_, hi_ in ((nrm, -tol, tol), (u, 0.0, ln)):
            al = np.einsum("kij,ij->ki", w, dirn)
            be = d @ dirn.T
            flat = np.abs(be) <= 1e-300
            with np.errstate(divide="ignore", invalid="ignore"):
                ta, tb = (lo_ - al) / be, (hi_ - al) / be
            lo_t = np.where(flat, np.where((al >= lo_) & (al <= hi_), -np.inf, np.inf),
                            np.minimum(ta, tb))
            hi_t = np.where(flat, np.where((al >= lo_) & (al <= hi_), np.inf, -np.inf),
                            np.maximum(ta, tb))
            s0, s1 = np.maximum(s0, lo_t), np.minimum(s1, hi_t)
        band = ln[None, :] > 0
        starts.append(np.where(band, s0, np.inf))
        ends.append(np.where(band, s1, -np.inf))
        st, en = np.concatenate(starts, axis=1), np.concatenate(ends, axis=1)
        use = (en >= st) & (en >= 0) & (st <= 1)
        st = np.where(use, np.maximum(st, 0.0), np.inf)
        en = np.where(use, np.minimum(en, 1.0), -np.inf)
        order = np.argsort(st, axis=1)
        st, en = np.take_along_axis(st, order, 1), np.take_along_axis(en, order, 1)
        reach = np.maximum.accumulate(en, axis=1)
        gap = (st[:, 1:] > reach[:, :-1] + 1e-12) & (reach[:, :-1] < 1.0)
        if np.any(st[:, 0] > 0) or np.any(gap) or np.any(reach[:, -1] < 1.0):
            return False
    return True


class _Sections:
    """Sections across axis q of the flat primitives of a set of walls, by material:
    ``at(c)`` maps each material to (segments, circles) where the plane q = c cuts
    them; ``same(s1, s2)`` compares two sections within ``tol``."""

    def __init__(self, kinds, par, mats, q, eps, tol, windows):
        self.q, self.eps, self.tol = q, eps, tol
        tri, trow, circ, slope, crow, cext = _flat_pieces(kinds, par, q)
        # the pieces reaching the windows along q where sections are taken
        s = tri[:, :, q]
        t = np.zeros(trow.size, dtype=bool)
        c = np.zeros(crow.size, dtype=bool)
        for a, b in windows:
            t |= (s.min(axis=1) <= b + eps) & (s.max(axis=1) >= a - eps)
            c |= (cext[:, 0] <= b + eps) & (cext[:, 1] >= a - eps)
        self.tri, self.circ, self.slope, self.cext = tri[t], circ[c], slope[c], cext[c]
        self.tmat, self.cmat = mats[trow[t]], mats[crow[c]]

    def breaks(self):
        """The coordinates along q where a section may change: corners, cylinder ends."""
        return np.concatenate([self.tri[:, :, self.q].ravel(), self.cext.ravel()])

    def at(self, c):
        out = {}
        seg, it = _section_lines(self.tri, self.q, c, self.eps)
        ic = np.flatnonzero((self.cext[:, 0] <= c + self.eps) & (self.cext[:, 1] >= c - self.eps))
        circ = self.circ[ic].copy()  # where the axes cross the plane q = c
        circ[:, :2] += self.slope[ic] * c
        for m in set(self.tmat[it].tolist()) | set(self.cmat[ic].tolist()):
            out[m] = (seg[self.tmat[it] == m], circ[self.cmat[ic] == m])
        return out

    def describe(self, s) -> str:
        """Where a section lies across q, in words."""
        pts = [v[0].reshape(-1, 2) for v in s.values()]
        pts += [np.concatenate([v[1][:, :2] - v[1][:, 2:], v[1][:, :2] + v[1][:, 2:]])
                for v in s.values()]
        pts = np.concatenate(pts) if pts else np.zeros((0, 2))
        if pts.shape[0] == 0:
            return "no face"
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        return ", ".join(f"{'xyz'[k]} {a:.6g}" + (f" .. {b:.6g}" if b - a > self.tol else "")
                         for k, a, b in zip(_ACROSS[self.q], lo, hi)) + " m"

    def same(self, s1, s2, tol=None) -> bool:
        """Whether sections ``s1`` and ``s2`` agree within ``tol`` (default: the one given)."""
        tol = self.tol if tol is None else tol
        if set(s1) != set(s2):
            return False
        for m in s1:
            (l1, c1), (l2, c2) = s1[m], s2[m]
            if not (_covered(l1, l2, tol) and _covered(l2, l1, tol)):
                return False
            for x, y in ((c1, c2), (c2, c1)):
                if x.shape[0] and (y.shape[0] == 0 or not np.all(
                        (np.abs(x[:, None, :] - y[None]).max(axis=2) <= tol).any(axis=1))):
                    return False
        return True

def _seg_dist(p, seg):
    """Distances [k, m] from points ``p`` [k, 2] to segments ``seg`` [m, 2, 2]."""
    a, d = seg[:, 0], seg[:, 1] - seg[:, 0]
    dd = np.einsum("ij,ij->i", d, d)
    w = p[:, None, :] - a[None]
    t = np.clip(np.einsum("kij,ij->ki", w, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    return np.linalg.norm(w - t[:, :, None] * d[None], axis=2)


def _box_pairs(seg, tol, chunk: int = 1_000_000):
    """The pairs (i, j), i != j once, of pieces ``seg`` [k, 2, 2] whose bounding boxes grown
    by ``tol`` overlap, in lists of at most about ``chunk`` (pieces sorted by their lower x,
    each paired with the ones starting before it ends)."""
    lo = seg.min(axis=1) - tol
    hi = seg.max(axis=1) + tol
    order = np.argsort(lo[:, 0], kind="stable")
    end = np.searchsorted(lo[order, 0], hi[order, 0], side="right")
    cnt = np.maximum(end - np.arange(1, order.size + 1), 0)
    start = 0
    while start < order.size:
        stop = start + 1 + int(np.searchsorted(np.cumsum(cnt[start:]), chunk))
        c = cnt[start:stop]
        rows = np.repeat(np.arange(start, min(stop, order.size)), c)
        first = np.repeat(np.cumsum(c) - c, c)
        cols = rows + 1 + np.arange(rows.size) - first
        i, j = order[rows], order[cols]
        ok = (lo[i, 1] <= hi[j, 1]) & (lo[j, 1] <= hi[i, 1])
        yield i[ok], j[ok]
        start = stop


def _node(seg, tol):
    """The planar graph of the pieces ``seg`` [k, 2, 2] (each longer than ``tol``): every
    piece split where an end of another lies on it (within tol; a solid standing on a
    floor meets it there) and where two cross, the split points within tol of each other
    joined into one vertex (the mean of them).  Returns the vertices [v, 2] and the edges
    [e, 2] between distinct vertices, each once (the same edge cut from two faces, a box's
    bottom lying on the floor)."""
    # here, not at module import: scipy.sparse and scipy.spatial cost every run without a mesh ~0.4 s
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    a, d = seg[:, 0], seg[:, 1] - seg[:, 0]
    ln = np.linalg.norm(d, axis=1)
    u = d / ln[:, None]
    k = seg.shape[0]
    rows, cuts = [np.arange(k), np.arange(k)], [np.zeros(k), np.ones(k)]
    for i, j in _box_pairs(seg, tol):
        for p, q in ((i, j), (j, i)):
            for e in (0, 1):  # an end of q on p, away from p's own ends
                w = seg[q, e] - a[p]
                t = np.einsum("ij,ij->i", w, u[p])
                on = ((np.abs(w[:, 0] * u[p, 1] - w[:, 1] * u[p, 0]) <= tol) & (t > tol)
                      & (t < ln[p] - tol))
                rows.append(p[on])
                cuts.append(t[on] / ln[p[on]])
        # crossings inside both: a_i + s d_i = a_j + r d_j, 0 < s, r < 1
        den = d[i, 0] * d[j, 1] - d[i, 1] * d[j, 0]
        g = a[j] - a[i]
        x = np.abs(den) > 1e-12 * ln[i] * ln[j]
        den = np.where(x, den, 1.0)
        s = (g[:, 0] * d[j, 1] - g[:, 1] * d[j, 0]) / den
        r = (g[:, 0] * d[i, 1] - g[:, 1] * d[i, 0]) / den
        x &= (s > 0) & (s < 1) & (r > 0) & (r < 1)
        rows += [i[x], j[x]]
        cuts += [s[x], r[x]]
    rows, cuts = np.concatenate(rows), np.concatenate(cuts)
    order = np.lexsort((cuts, rows))
    rows, cuts = rows[order], cuts[order]
    pts = a[rows] + cuts[:, None] * d[rows]
    # join the points within tol (connected components of the pairs closer than tol)
    pairs = cKDTree(pts).query_pairs(tol, output_type="ndarray")
    n = pts.shape[0]
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    nv, lab = connected_components(graph, directed=False)
    cnt = np.bincount(lab, minlength=nv)
    verts = np.stack([np.bincount(lab, pts[:, j], nv) for j in range(2)], axis=1) / cnt[:, None]
    # consecutive points along one piece are its edges
    same = rows[1:] == rows[:-1]
    e = np.stack([lab[:-1][same], lab[1:][same]], axis=1)
    e = np.sort(e[e[:, 0] != e[:, 1]], axis=1)
    return verts, np.unique(e, axis=0).reshape(-1, 2)


def _closed_outline(seg, tol):
    """The closed outlines of the pieces ``seg`` [k, 2, 2]: the bounded faces of the planar
    graph they form (:func:`_node`), found by walking round each face (at every vertex the
    next edge clockwise from the one arrived by), each as its boundary pieces ``loops``
    [m, 2, 2] with the number of its face ``face`` [m] (ascending).  Pieces no longer than
    tol are left out; a piece with an open end (a floor, a U channel, a fin) bounds no face
    or lies inside one (walked there and back, it is left out), so only closed outlines
    remain, also where a solid stands on a floor of the same wall, or two solids share a
    face (a solid with a ridge on it); faces no wider than about tol (area <= tol x half
    the perimeter) are left out."""
    none = (np.zeros((0, 2, 2)), np.zeros(0, dtype=np.int64))
    if seg.shape[0]:
        seg = seg[np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1) > tol]
    if seg.shape[0] == 0:
        return none
    verts, edges = _node(seg, tol)
    if edges.shape[0] == 0:
        return none
    # half-edges 2e (u -> v) and 2e + 1 (v -> u); at each vertex in counter-clockwise order
    org = edges.reshape(-1)
    dst = edges[:, ::-1].reshape(-1)
    dv = verts[dst] - verts[org]
    ang = np.arctan2(dv[:, 1], dv[:, 0])
    ring = np.lexsort((ang, org))
    pos = np.empty_like(ring)
    pos[ring] = np.arange(ring.size)
    first = np.searchsorted(org[ring], np.arange(verts.shape[0]))
    deg = np.bincount(org, minlength=verts.shape[0])
    # the face on the left of half-edge h continues at its end v with the outgoing edge
    # just clockwise of the one back (h ^ 1)
    tw = np.arange(org.size) ^ 1
    v = org[tw]
    nxt = ring[first[v] + (pos[tw] - first[v] - 1) % deg[v]]
    seen = np.zeros(org.size, dtype=bool)
    loops, face = [], []
    for h0 in range(org.size):
        if seen[h0]:
            continue
        cyc = [h0]
        seen[h0] = True
        h = nxt[h0]
        while h != h0:
            cyc.append(h)
            seen[h] = True
            h = nxt[h]
        cyc = np.array(cyc)
        p0, p1 = verts[org[cyc]], verts[dst[cyc]]
        area = 0.5 * float(np.sum(p0[:, 0] * p1[:, 1] - p1[:, 0] * p0[:, 1]))
        if area <= 0.5 * tol * float(np.linalg.norm(p1 - p0, axis=1).sum()):
            continue  # the outside of a group of pieces, or a sliver
        keep = ~np.isin(cyc ^ 1, cyc)  # an edge walked there and back bounds nothing
        loops.append(np.stack([p0[keep], p1[keep]], axis=1))
        face.append(np.full(int(keep.sum()), len(face)))
    if not loops:
        return none
    return np.concatenate(loops), np.concatenate(face)


def _inside_caps(pts, caps, tol, block: int = 500_000) -> np.ndarray:
    """Which points ``pts`` [n, 2] lie inside or on one of the convex polygons ``caps`` (a
    list of corner arrays [m, 2] in either order: end faces seen along the periodic axis, a
    triangle, a rectangle, a disk's 32 rim points); polygons no wider than about ``tol``
    (area <= tol x half the perimeter, a sliver of a fan) are left out.  Only the points in
    a polygon's group's bounding box are tested, in chunks of at most ``block`` point x
    polygon pairs."""
    out = np.zeros(pts.shape[0], dtype=bool)
    for m in sorted({c.shape[0] for c in caps}):
        P = np.array([c for c in caps if c.shape[0] == m], dtype=float)
        e = np.roll(P, -1, axis=1) - P
        area = 0.5 * np.sum(P[..., 0] * np.roll(P, -1, axis=1)[..., 1]
                            - np.roll(P, -1, axis=1)[..., 0] * P[..., 1], axis=1)
        big = np.abs(area) > 0.5 * tol * np.linalg.norm(e, axis=2).sum(axis=1)
        P, e, sgn = P[big], e[big], np.sign(area[big])
        if P.shape[0] == 0:
            continue
        lo, hi = P.min(axis=(0, 1)), P.max(axis=(0, 1))
        idx = np.flatnonzero(~out & np.all((pts >= lo) & (pts <= hi), axis=1))
        step = max(1, block // (P.shape[0] * m))
        for a in range(0, idx.size, step):
            sel = idx[a:a + step]
            d = pts[sel, None, None, :] - P[None]
            cr = (e[None, ..., 0] * d[..., 1] - e[None, ..., 1] * d[..., 0]) * sgn[None, :, None]
            out[sel] |= np.all(cr >= 0.0, axis=2).any(axis=1)
    return out


def _edge_outside(poly, loops, face, circ, tol):
    """A point of the edges of the polygon ``poly`` [m, 2] (closed) outside every closed
    outline (:func:`_enclosed`), or None: each edge is cut where it crosses a piece of
    ``loops`` or a circle of ``circ``, and the middle of each part tested (an end face whose
    corners lie in two solids bridges the open space between them)."""
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        d = b - a
        ts = [0.0, 1.0]
        if loops.shape[0]:
            e0, e = loops[:, 0], loops[:, 1] - loops[:, 0]
            den = d[0] * e[:, 1] - d[1] * e[:, 0]
            g = e0 - a
            ok = np.abs(den) > 1e-300
            den = np.where(ok, den, 1.0)
            t = (g[:, 0] * e[:, 1] - g[:, 1] * e[:, 0]) / den
            u = (g[:, 0] * d[1] - g[:, 1] * d[0]) / den
            ts += t[ok & (t > 0) & (t < 1) & (u >= 0) & (u <= 1)].tolist()
        for cx, cy, r in circ:
            w = a - (cx, cy)
            qa, qb, qc = d @ d, 2 * (w @ d), w @ w - r * r
            disc = qb * qb - 4 * qa * qc
            if qa > 0 and disc > 0:
                ts += [t for t in ((-qb - disc ** 0.5) / (2 * qa), (-qb + disc ** 0.5) / (2 * qa))
                       if 0 < t < 1]
        ts = np.unique(ts)
        for m in 0.5 * (ts[1:] + ts[:-1]):
            pt = a + m * d
            if not _enclosed(pt, loops, face, circ, tol):
                return pt
    return None


def _enclosed(p, loops, face, circ, tol) -> bool:
    """Whether point ``p`` (2) lies inside or on (within ``tol``) a closed outline of
    ``loops`` [k, 2, 2] (those of one face ``face`` [k] crossing a ray from p an odd number
    of times) or a circle of ``circ`` [m, 3] (centre, radius)."""
    if circ.shape[0] and np.any(np.hypot(*(circ[:, :2] - p).T) <= circ[:, 2] + tol):
        return True
    if loops.shape[0] == 0:
        return False
    if np.any(_seg_dist(p[None], loops) <= tol):
        return True
    return bool(_inside_many(p[None], loops, np.zeros((0, 3)), face=face)[0])


def _inside_many(pts, loops, circ, block: int = 500_000, face=None) -> np.ndarray:
    """Which points ``pts`` [n, 2] lie inside a closed outline of ``loops`` [k, 2, 2] (the
    pieces of one face, ``face`` [k] ascending, all one face when None, crossing a ray from
    the point an odd number of times) or a circle of ``circ`` [m, 3].  Only the points in
    the outlines' and circles' bounding box are tested, in chunks of at most ``block`` point
    x piece pairs: a finely faceted round outline (2048 pieces) beside 20,000 spheres took
    7.6 s and 3.7 GB in one go."""
    out = np.zeros(pts.shape[0], dtype=bool)
    if not (loops.shape[0] or circ.shape[0]) or not pts.shape[0]:
        return out
    if face is None:
        face = np.zeros(loops.shape[0], dtype=np.int64)
    starts = np.flatnonzero(np.r_[True, face[1:] != face[:-1]]) if loops.shape[0] else None
    lo = np.min(np.concatenate([loops.reshape(-1, 2), circ[:, :2] - circ[:, 2:3]]), axis=0)
    hi = np.max(np.concatenate([loops.reshape(-1, 2), circ[:, :2] + circ[:, 2:3]]), axis=0)
    idx = np.flatnonzero(np.all((pts >= lo) & (pts <= hi), axis=1))
    r = np.array([math.cos(0.3183), math.sin(0.3183)])  # a ray along no mesh line
    step = max(1, block // max(1, loops.shape[0], circ.shape[0]))
    for a in range(0, idx.size, step):
        sel = idx[a:a + step]
        q = pts[sel]
        hit = np.zeros(sel.size, dtype=bool)
        if circ.shape[0]:
            hit |= (np.hypot(q[:, None, 0] - circ[None, :, 0], q[:, None, 1] - circ[None, :, 1])
                    < circ[None, :, 2]).any(axis=1)
        if loops.shape[0]:
            e0, e1 = loops[None, :, 0] - q[:, None], loops[None, :, 1] - q[:, None]
            c0, c1 = r[0] * e0[..., 1] - r[1] * e0[..., 0], r[0] * e1[..., 1] - r[1] * e1[..., 0]
            cross = (c0 > 0) != (c1 > 0)  # the ends on the two sides of the ray's line
            w = np.where(cross, c0 / np.where(cross, c0 - c1, 1.0), 0.0)
            along = (e0 + w[..., None] * (e1 - e0)) @ r
            n = np.add.reduceat((cross & (along > 0)).astype(np.int64), starts, axis=1)
            hit |= (n % 2 == 1).any(axis=1)
        out[sel] = hit
    return out


def _face_corners(kind, p):
    """The corners [n, 3] of an end face: a triangle's three, a rectangle's four, 32 points
    round a disk's rim."""
    if kind == TRIANGLE:
        return p[:9].reshape(3, 3)
    c, n = p[0:3], p[3:6]
    if kind == RECTANGLE:
        du, dv = p[6:9] * p[9], np.cross(n, p[6:9]) * p[10]
        return np.array([c - du - dv, c + du - dv, c + du + dv, c - du + dv])
    e1 = np.cross(n, np.eye(3)[int(np.argmin(np.abs(n)))])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    th = np.linspace(0.0, 2 * math.pi, 32, endpoint=False)
    return c + p[6] * (np.cos(th)[:, None] * e1 + np.sin(th)[:, None] * e2)


def _surface_steps(kind, wall, par, vel, omega, centre, reach, dt) -> np.ndarray:
    """How far the surface of each wall primitive moves in one step ``dt`` [m] (0 for a wall
    at rest): its wall's velocity ``vel`` (its normal part for a plane) plus its spin
    ``omega`` (less the part about a plane's normal or a cylinder's, cone's or disk's axis,
    which leaves the surface in place, while that part still carries an axis off the wall's
    ``centre`` round it) times the wall's ``reach``; all primitives at once (an STL floor
    has tens of thousands)."""
    v, om = vel[wall], omega[wall]
    speed = np.sqrt(np.einsum("ij,ij->i", v, v))
    spin = np.sqrt(np.einsum("ij,ij->i", om, om))
    ax = np.isin(kind, (PLANE, CYLINDER, CONE, DISK))
    if ax.any():
        a = par[ax, 3:6]
        along = np.einsum("ij,ij->i", om[ax], a)[:, None] * a
        spin[ax] = np.linalg.norm(om[ax] - along, axis=1)
        plane = kind[ax] == PLANE
        carried = np.linalg.norm(np.cross(along, par[ax, 0:3] - centre[wall[ax]]), axis=1)
        speed[ax] = np.where(plane, np.abs(np.einsum("ij,ij->i", v[ax], a)), speed[ax] + carried)
    still = ~(np.any(v != 0, axis=1) | np.any(om != 0, axis=1))
    return np.where(still, 0.0, (speed + spin * reach[wall]) * dt)


class Simulation:
    """Spheres, walls and a contact model advanced by velocity Verlet in compiled loops."""

    def __init__(self, materials: MaterialTable, dt: float | None = None,
                 dt_fraction: float = 0.2, gravity=(0.0, 0.0, -9.81), box=None,
                 periodic=(False, False), contact_model: dict | None = None,
                 skin: float | None = None, coarse_grain: float = 1.0,
                 max_overlap: float = 0.05, sort_every: int = 1000, source: str = "<input>"):
        self.source = source
        self.materials = materials
        if contact_model is not None and not isinstance(contact_model, dict):
            raise InputError(source, "contact_model",
                             "a mapping of model names (normal, damping, tangential, rolling, "
                             "cohesion, conventions, ...)", contact_model)
        self.codes, self.w_factor = model_codes(**(contact_model or {}), source=source)
        self.damping_eta = (contact_model or {}).get("damping_eta")
        if dt is not None:
            dt = _number(source, "dt", dt, "a time step > 0 s", lambda d: d > 0)
        self.dt_user = dt
        self.dt_fraction = _number(source, "dt_fraction", dt_fraction,
                                   "a fraction of the Rayleigh time in (0, 1]",
                                   lambda f: 0.0 < f <= 1.0)
        self.gravity = _vector(source, "gravity", gravity)
        if (not isinstance(periodic, (tuple, list, np.ndarray)) or len(periodic) != 2
                or not all(isinstance(q, (bool, np.bool_)) for q in periodic)):
            raise InputError(source, "periodic",
                             "two booleans (periodic in x, periodic in y; z is never periodic)",
                             periodic)
        self.periodic = np.array([bool(periodic[0]), bool(periodic[1])], dtype=np.bool_)
        if box is None:
            if self.periodic.any():
                raise InputError(source, "box", "(xlo, xhi, ylo, yhi) for periodic boundaries", None)
            box = (0.0, 1.0, 0.0, 1.0)
        self.box = _vector(source, "box", box, 4)
        if self.box[1] <= self.box[0] or self.box[3] <= self.box[2]:
            raise InputError(source, "box", "xlo < xhi and ylo < yhi", tuple(box))
        if skin is not None:
            skin = _number(source, "skin", skin, "a neighbour skin > 0 m", lambda d: d > 0)
        self.skin_user = skin
        self.coarse_grain = _number(source, "coarse_grain", coarse_grain, "a size factor > 0",
                                    lambda c: c > 0)
        self.max_overlap = _number(source, "max_overlap", max_overlap,
                                   "the largest overlap a run accepts, as a fraction of a "
                                   "radius in (0, 1]", lambda c: 0 < c <= 1)
        if (isinstance(sort_every, bool) or not isinstance(sort_every, (int, np.integer))
                or sort_every < 0):
            raise InputError(source, "sort_every",
                             "a whole number of steps >= 0 between spatial sorts (0: never)",
                             sort_every)
        self.sort_every = int(sort_every)
        self.p = ParticleState()
        self.walls = WallSet()
        self._warr = self.walls.arrays()
        self.step = 0
        self._need_forces = True
        self._npair_per = 8  # initial pair capacity per particle (grows on demand)
        self._npair = 0
        self._kw = 4
        self._lists = None
        self._cells = np.zeros(1024, dtype=np.int64)
        self._wcells = np.zeros(1024, dtype=np.int64)
        self._wbins = np.zeros(1024, dtype=np.int64)
        self.wall_force = np.zeros((0, 3))
        self.wall_torque = np.zeros((0, 3))
        self.wall_log = np.zeros((0, 0, 6))
        self._pair = None
        self.dt = None
        # wall travel since the list build, pair-list builds, wall-list builds, steps since
        # the last spatial sort (inf: sort at the first build), pair passes over every listed
        # pair (integrator.run_loop, "Near list"; the others visit the near list only)
        self._fstate = np.array([0.0, 0.0, 0.0, math.inf, 0.0])

    # ------------------------------------------------------------------ building
    def add_particles(self, x, r, material, v=None, omega=None, fixed=False, lock_rotation=False):
        """Add spheres (radii multiplied by the coarse-graining factor); returns their
        insertion ids (rows until the first spatial sort; :meth:`index`)."""
        k = self.materials.index(material)
        x = _rows(self.source, "particles.x", x, None, "positions [m]")
        n = x.shape[0]
        try:
            r = np.asarray(r, dtype=np.float64)
        except (TypeError, ValueError):
            raise InputError(self.source, "particles.radius", "radii > 0 m", r) from None
        if r.size not in (1, n) or r.ndim > 1:
            raise InputError(self.source, "particles.radius",
                             f"one radius or one per particle ({n})", f"{r.size} radii")
        r = r * self.coarse_grain
        if np.any(~np.isfinite(r)) or np.any(r <= 0):
            bad = r[~(np.isfinite(r) & (r > 0))]
            raise InputError(self.source, "particles.radius", "radii > 0 m",
                             float(bad[0] / self.coarse_grain))
        v = None if v is None else _rows(self.source, "particles.v", v, n, "velocities [m/s]")
        fixed = _flags(self.source, "particles.fixed", fixed, n)
        lock_rotation = _flags(self.source, "particles.lock_rotation", lock_rotation, n)
        omega = (None if omega is None
                 else _rows(self.source, "particles.omega", omega, n, "angular velocities [rad/s]"))
        ids = self.p.append(x, r, self.materials.materials[k].density, k, v, omega, fixed,
                            lock_rotation)
        self._fstate[3] = math.inf  # new particles sit at the end: sort at the next build
        self._invalidate()
        return ids

    def add_wall(self, name, material, primitives, velocity=(0, 0, 0), omega=(0, 0, 0),
                 centre=(0, 0, 0)) -> int:
        """Add a rigid wall made of primitives [(kind, values, point_rows, dir_rows), ...]."""
        k = self.materials.index(material)
        velocity = _vector(self.source, "walls.velocity", velocity)
        omega = _vector(self.source, "walls.omega", omega)
        centre = _vector(self.source, "walls.centre", centre)
        ws = self.walls
        # keep moved primitives: rebuild the python lists from the current arrays
        a = self._warr
        ws.par = [row.copy() for row in a["prim_par"]]
        ws.centre = [row.copy() for row in a["wall_centre"]]
        wid = ws.new_wall(name, velocity, omega, centre)
        for kind, values, pts, dirs in primitives:
            ws.add_prim(wid, kind, k, values, pts, dirs)
        self._warr = ws.arrays()
        self.wall_force = np.zeros((len(ws.names), 3))
        self.wall_torque = np.zeros((len(ws.names), 3))
        self._invalidate()
        return wid

    def add_plane(self, point, normal, material, name=None, velocity=(0, 0, 0),
                  omega=(0, 0, 0), centre=None) -> int:
        """Infinite plane through ``point``; particles live on the side of ``normal``."""
        nrm = _vector(self.source, "walls.plane.normal", normal)
        ln = float(np.linalg.norm(nrm))
        if not ln > 0:
            raise InputError(self.source, "walls.plane.normal", "a non-zero vector", tuple(nrm))
        pt = _vector(self.source, "walls.plane.point", point)
        vals = np.concatenate([pt, nrm / ln])
        return self.add_wall(name or f"plane{len(self.walls.names)}", material,
                             [(PLANE, vals, 0b1, 0b10)], velocity, omega,
                             pt if centre is None else centre)

    def _unit(self, v, field):
        v = _vector(self.source, field, v)
        ln = float(np.linalg.norm(v))
        if not ln > 0:
            raise InputError(self.source, field, "a non-zero vector", tuple(v))
        return v / ln

    def add_cylinder(self, axis_point, axis_dir, radius, half_length, material, inner=True,
                     name=None, velocity=(0, 0, 0), omega=(0, 0, 0), centre=None) -> int:
        """Cylindrical shell about an axis (inner=True: particles inside, e.g. a drum)."""
        radius = _number(self.source, "walls.cylinder.radius", radius, "a radius > 0 m",
                         lambda q: q > 0)
        half_length = _number(self.source, "walls.cylinder.half_length", half_length,
                              "a half length > 0 m", lambda q: q > 0)
        a = _vector(self.source, "walls.cylinder.axis_point", axis_point)
        vals = np.concatenate([a, self._unit(axis_dir, "walls.cylinder.axis_dir"),
                               [radius, half_length, 1.0 if inner else 0.0]])
        return self.add_wall(name or f"cylinder{len(self.walls.names)}", material,
                             [(CYLINDER, vals, 0b1, 0b10)], velocity, omega,
                             a if centre is None else centre)

    def add_cone(self, axis_point, axis_dir, r0, r1, z0, z1, material, inner=True, name=None,
                 velocity=(0, 0, 0), omega=(0, 0, 0), centre=None) -> int:
        """Cone frustum shell: radius r0 at axial coordinate z0 to r1 at z1 (z1 > z0)."""
        r0, r1 = (_number(self.source, f"walls.cone.{nm}", q, "a radius >= 0 m",
                          lambda c: c >= 0) for nm, q in (("r0", r0), ("r1", r1)))
        z0, z1 = (_number(self.source, f"walls.cone.{nm}", q, "an axial coordinate [m]",
                          lambda c: True) for nm, q in (("z0", z0), ("z1", z1)))
        if not z1 > z0 or max(r0, r1) <= 0:
            raise InputError(self.source, "walls.cone", "z1 > z0, radii >= 0, one > 0",
                             (r0, r1, z0, z1))
        a = _vector(self.source, "walls.cone.axis_point", axis_point)
        vals = np.concatenate([a, self._unit(axis_dir, "walls.cone.axis_dir"),
                               [r0, r1, z0, z1, 1.0 if inner else 0.0]])
        return self.add_wall(name or f"cone{len(self.walls.names)}", material,
                             [(CONE, vals, 0b1, 0b10)], velocity, omega,
                             a if centre is None else centre)

    def add_rectangle(self, centre, normal, u_axis, half_u, half_v, material, name=None,
                      velocity=(0, 0, 0), omega=(0, 0, 0)) -> int:
        """Bounded plane (e.g. a tool blade): centre, normal, in-plane u axis, half sizes."""
        c = _vector(self.source, "walls.rectangle.centre", centre)
        for nm, h in (("half_u", half_u), ("half_v", half_v)):
            _number(self.source, f"walls.rectangle.{nm}", h, "a half size > 0 m", lambda q: q > 0)
        nrm = self._unit(normal, "walls.rectangle.normal")
        u = _vector(self.source, "walls.rectangle.u_axis", u_axis)
        u = self._unit(u - np.dot(u, nrm) * nrm, "walls.rectangle.u_axis")
        vals = np.concatenate([c, nrm, u, [half_u, half_v]])
        return self.add_wall(name or f"rectangle{len(self.walls.names)}", material,
                             [(RECTANGLE, vals, 0b1, 0b110)], velocity, omega, c)

    def add_disk(self, centre, normal, radius, material, name=None, velocity=(0, 0, 0),
                 omega=(0, 0, 0)) -> int:
        c = _vector(self.source, "walls.disk.centre", centre)
        _number(self.source, "walls.disk.radius", radius, "a radius > 0 m", lambda q: q > 0)
        vals = np.concatenate([c, self._unit(normal, "walls.disk.normal"), [radius]])
        return self.add_wall(name or f"disk{len(self.walls.names)}", material,
                             [(DISK, vals, 0b1, 0b10)], velocity, omega, c)

    def add_mesh(self, vertices, triangles, material, name=None, velocity=(0, 0, 0),
                 omega=(0, 0, 0), centre=None, facets=None, rounding=None) -> int:
        """Triangle mesh wall (boxes, STL tools); one primitive per triangle.  ``omega``
        turns it about ``centre``, by default the mean of its vertices (the axis of a drum,
        the middle of a box; give the shaft of a paddle or blade explicitly).  ``facets``:
        each triangle's facet index in its STL file (``read_stl(path, facets=True)``, which
        leaves out facets without area), by which a refused face is named.  ``rounding``:
        how far each vertex [nv] (or all, one number) may lie from where it was drawn, as
        it was stored [m] (a CAD export rounded to 0.01 mm: 5e-6); by default the unit
        roundoff of the vertices' own type: float32 (2^-24 |x|: a binary STL as
        ``read_stl`` returns it, scaled or not) or float64 (any other array, whatever its
        numbers; a float32 array moved with float64 numbers is float64), of each vertex's
        largest coordinate as given: where ``read_stl(weld_tol=)`` merged copies of a corner,
        the copy it kept (the first in the file), not the largest of the copies (how far the
        copies lay apart is ``weld_tol``'s, stated separately).  Each face takes the largest
        of its three corners'.  The checks of a periodic box forgive a face that much tilt,
        no more, and only that face; there a declared rounding may be at most 2.5e-5 R_min
        (its 8 x within the 2e-4 R_min step allowed), and none makes a wall count as clear
        of a boundary."""
        raw = vertices
        v = _rows(self.source, "walls.mesh.vertices", vertices, None, "vertices [m]")
        t = np.asarray(triangles)
        if (t.ndim != 2 or t.shape[1] != 3 or t.size == 0 or not np.issubdtype(t.dtype, np.integer)
                or t.min() < 0 or t.max() >= len(v)):
            raise InputError(self.source, "walls.mesh.triangles",
                             f"rows of three whole vertex indices in [0, {len(v)})",
                             f"an array of shape {t.shape} and type {t.dtype}")
        t = t.astype(np.int64)
        rows = v[t].reshape(-1, 9)
        # a triangle without area (collinear or repeated corners) has no normal to push along
        flat = np.flatnonzero(without_area(rows.reshape(-1, 3, 3)))
        if flat.size:
            k = int(flat[0])
            raise InputError(self.source, f"walls.mesh.triangles[{k}]",
                             "a triangle with area (three corners not on one line)",
                             f"corners {t[k].tolist()} at {rows[k].reshape(3, 3).tolist()}")
        if facets is not None:
            fa = np.asarray(facets)
            if (fa.shape != (len(t),) or not np.issubdtype(fa.dtype, np.integer)
                    or (fa.size and fa.min() < 0)):
                raise InputError(self.source, "walls.mesh.facets",
                                 f"one whole facet index >= 0 per triangle ({len(t)})",
                                 f"an array of shape {fa.shape} and type {fa.dtype}")
        if rounding is None:
            # the vertices' own type: float32 (a binary STL's, as read_stl returns it), else
            # float64 (a float64 array is judged as one, whatever numbers it holds)
            kind = np.asarray(raw).dtype
            ftype = np.dtype(np.float32) if kind == np.float32 else np.dtype(np.float64)
            # the unit roundoff: |fl(x) - x| <= eps / 2 |x|
            rd = 0.5 * float(np.finfo(ftype).eps) * np.abs(v).max(axis=1)
        else:
            rd = np.asarray(rounding, dtype=float) if np.ndim(rounding) else np.full(
                len(v), float(rounding) if isinstance(rounding, (int, float, np.number))
                and not isinstance(rounding, bool) else np.nan)
            if rd.shape != (len(v),) or not np.all(np.isfinite(rd)) or np.any(rd < 0):
                raise InputError(self.source, "walls.mesh.rounding",
                                 f"one distance >= 0 [m] per vertex ({len(v)}) or one for all",
                                 f"{rounding!r}" if np.ndim(rounding) == 0 else
                                 f"an array of shape {np.shape(rounding)}")
        c = v.mean(axis=0) if centre is None else centre
        w = self.add_wall(name or f"mesh{len(self.walls.names)}", material,
                          [(TRIANGLE, row, 0b111, 0) for row in rows], velocity, omega, c)
        if facets is not None:
            self.__dict__.setdefault("_mesh_facets", {})[w] = fa.astype(np.int64)
        # each face's: the largest of its corners'
        self.__dict__.setdefault("_mesh_rounding", {})[w] = rd[t].max(axis=1)
        if rounding is not None:
            self.__dict__.setdefault("_mesh_declared", {})[w] = rd
        return w

    def add_stl(self, path, material, scale=1.0, weld_tol=0.0, rounding=None, **kw) -> int:
        """An STL file as a mesh wall (:func:`soilcal.dem.stl.read_stl`, then
        :meth:`add_mesh` with its facets, by which a refused face is named, and the rounding
        the file stored its vertices with: float32's in a binary file (2^-24 |x| of the
        coordinates kept, a welded corner's first copy in the file: the copies' distance is
        ``weld_tol``'s, not a rounding), an ASCII file's numbers as written, or ``rounding``
        [m, after ``scale``] where given, as an ASCII export rounded to 0.01 mm has it: 5e-6,
        half of it, also with ``scale=1e-3``); ``kw``: the other arguments of
        :meth:`add_mesh` (name, velocity, omega, centre)."""
        from soilcal.dem.stl import read_stl

        if "facets" in kw:
            raise InputError(path, "facets", "no facets= to add_stl (it numbers a refused "
                             "face by its facet in the file itself)", kw["facets"])
        # read_stl returns a binary file's vertices as float32 and an ASCII file's as
        # float64: add_mesh takes the unit roundoff of that type as the file's own rounding
        v, t, fa = read_stl(path, scale=scale, weld_tol=weld_tol, facets=True)
        return self.add_mesh(v, t, material, facets=fa, rounding=rounding, **kw)

    def _check_declared_rounding(self, q):
        """A rounding given to add_mesh or add_stl (rounding=) is forgiven by a periodic
        box's checks only up to the step they allow: its 4 ulps (8 x rounding) at most
        2e-4 R_min, else a declared rounding would forgive steps and rises that change
        contacts (a floor rising 5 mm accepted for rounding=5e-4)."""
        r_min = float(self.p.r.min())
        for w, rd in self.__dict__.get("_mesh_declared", {}).items():
            if rd.size and 8.0 * float(rd.max()) > 2e-4 * r_min:
                name = self.walls.names[w]
                raise InputError(
                    self.source, f"walls.{name}.rounding",
                    f"in a box periodic in {('x', 'y')[q]}: a rounding [m] of at most "
                    f"2.5e-5 R_min = {2.5e-5 * r_min:.3g} m (its 4 ulps, 8 x rounding, within "
                    f"the 2e-4 R_min step the periodic checks allow; a coarser one would "
                    f"forgive steps that change contacts)",
                    f"{float(rd.max()):.3g} m")

    def _rounding(self) -> np.ndarray:
        """How far each primitive's stored coordinates may lie from where they were drawn
        [m]: a mesh face's as add_mesh recorded it, else the float64 unit roundoff of its
        largest number."""
        wa = self._warr
        par = wa["prim_par"]
        out = (0.5 * float(np.finfo(np.float64).eps) * np.abs(par).max(axis=1) if par.size
               else np.zeros(0))
        for w, rd in self.__dict__.get("_mesh_rounding", {}).items():
            k = np.flatnonzero(wa["prim_wall"] == w)
            if k.size == rd.size:
                out[k] = rd
        return out

    def add_box(self, lo, hi, material, name=None, velocity=(0, 0, 0), omega=(0, 0, 0)) -> int:
        """Closed box surface as a triangle mesh (particles outside or inside)."""
        from soilcal.dem.geometry import box_mesh

        lo = _vector(self.source, "walls.box.lo", lo)
        hi = _vector(self.source, "walls.box.hi", hi)
        if not np.all(lo < hi):
            raise InputError(self.source, "walls.box", "corners lo < hi in x, y and z",
                             f"lo {lo.tolist()}, hi {hi.tolist()}")
        v, t = box_mesh(lo, hi)
        return self.add_mesh(v, t, material, name or f"box{len(self.walls.names)}", velocity,
                             omega)

    def set_wall_motion(self, wall, velocity=None, omega=None):
        """Set a wall's translation velocity [m/s] and angular velocity [rad/s] about its
        centre (``wall``: the id ``add_*`` returned, or the wall's name)."""
        names = self.walls.names
        if isinstance(wall, str) and wall in names:
            wall = names.index(wall)
        if (isinstance(wall, bool) or not isinstance(wall, (int, np.integer))
                or not 0 <= wall < len(names)):
            raise InputError(self.source, "wall", f"a wall id in [0, {len(names)}) or one of "
                             f"the wall names {names}", wall)
        if velocity is not None:
            self._warr["wall_vel"][wall] = _vector(self.source, "walls.velocity", velocity)
        if omega is not None:
            self._warr["wall_omega"][wall] = _vector(self.source, "walls.omega", omega)

    def _invalidate(self):
        self._need_forces = True
        self._pair = None

    # ------------------------------------------------------------------ checks
    def _prepare(self):
        p = self.p
        if p.n == 0:
            raise InputError(self.source, "particles", "at least one particle", 0)
        self._pair = self.materials.table(self.w_factor, self.damping_eta)
        rmin = {}
        for k in np.unique(p.mat):
            rmin[int(k)] = float(p.r[p.mat == k].min())
        self.rayleigh = self.materials.rayleigh_dt(rmin)
        self.jkr_dt = (self.materials.jkr_dt(rmin, self._pair) if self.codes[4] == 1
                       else math.inf)
        self._check_weight()
        self.damping_dt = self.materials.damping_dt(rmin, self._pair, self.max_overlap,
                                                    wall_materials=set(self.walls.mat))
        dt = self.dt_user if self.dt_user is not None else min(
            self.dt_fraction * self.rayleigh, self.jkr_dt, DAMPING_DT_SAFETY * self.damping_dt)
        if not (dt > 0 and math.isfinite(dt)):
            raise InputError(self.source, "dt", "a time step > 0 s", dt)
        if dt > self.rayleigh:
            raise InputError(self.source, "dt",
                             f"a time step <= the Rayleigh time {self.rayleigh:.4g} s "
                             f"(stable bound; 20-40 % of it is usual)", dt)
        if dt > self.jkr_dt * (1 + 1e-12):
            raise InputError(self.source, "dt",
                             f"a time step <= the JKR bound {self.jkr_dt:.4g} s "
                             f"(0.17 sqrt(m / (2 E* a_0)), materials.py)", dt)
        if dt > self.damping_dt * (1 + 1e-12):
            raise InputError(self.source, "dt",
                             f"a time step <= the damped-contact bound {self.damping_dt:.4g} s "
                             f"(tangential and normal modes at {100 * self.max_overlap:g} % "
                             f"overlap, materials.py)", dt)
        self.dt = float(dt)
        rmax = float(p.r.max())
        # JKR separation range
        extra = 0.0
        if self.codes[4] == 1:
            pr = self._pair
            for a in range(pr.shape[0]):
                for b in range(pr.shape[1]):
                    if pr[a, b, P_W] > 0:
                        extra = max(extra, -jkr_separation(rmax, pr[a, b, P_ESTAR], pr[a, b, P_W]))
        self.extra = extra * 1.01
        self.skin = float(self.skin_user) if self.skin_user is not None else 0.2 * rmax
        if self.skin <= 0:
            raise InputError(self.source, "skin", "a neighbour skin > 0 m", self.skin)
        cell = 2 * rmax + self.skin + self.extra
        for q, nm in ((0, "x"), (1, "y")):
            if self.periodic[q] and (self.box[2 * q + 1] - self.box[2 * q]) < 2 * cell:
                raise InputError(self.source, f"box.{nm}",
                                 f"a periodic length >= {2 * cell:.4g} m (two neighbour cells)",
                                 float(self.box[2 * q + 1] - self.box[2 * q]))
        n = p.n
        if self._lists is None or self._lists["start_a"].shape[0] != n + 1:
            self._alloc_lists(n, self._npair_per * n, self._kw)

    def _alloc_lists(self, n, npair, kw, old=None):
        """Pair buffers for ``npair`` pairs (CSR half lists), wall lists of width ``kw``;
        with ``old``, the current lists are carried over."""
        if npair > np.iinfo(np.int32).max:  # the near list's slot indices are int32 (below)
            raise SimulationError(
                f"{n:,} spheres need {npair:,} pair-list slots, more than the near list's "
                f"int32 slot indices hold ({np.iinfo(np.int32).max:,}); fewer spheres or a "
                f"narrower size distribution")
        L = {}
        for s in ("a", "b"):
            L["start_" + s] = np.zeros(n + 1, dtype=np.int64)
            L["nbr_" + s] = np.full(npair, -1, dtype=np.int64)
            L["hist_" + s] = np.zeros((npair, hist_width(self.codes)))
            L["act_" + s] = np.zeros(npair, dtype=np.int8)
            L["wnbr_" + s] = np.full((kw, n), -1, dtype=np.int64)  # wnbr[k, i]: slot k of i
            L["wcnt_" + s] = np.zeros(n, dtype=np.int64)
            # wall history rows k * n + i (slot k of particle i): a slot's rows of every
            # particle lie together, so a run whose particles touch few walls reads a short
            # stretch of this array whatever the width kw grew to
            L["whist_" + s] = np.zeros((n * kw, H_SIZE))
        L["sorder"] = np.zeros(n, dtype=np.int64)  # particles grouped by slab group
        L["sgroup"] = np.zeros(SGROUP_LEN, dtype=np.int64)  # group offsets, last: groups
        L["sscratch"] = np.zeros(SCRATCH_LEN, dtype=np.int64)  # work space of the build
        # partners found by the build's count pass (work space, neighbour.build_lists: one
        # per pair in an even bed, up to NBLK_GROUPS per pair in an uneven one)
        nh = npair if old is None else max(npair, old["hits"].shape[0])
        L["hits"] = np.zeros(nh, dtype=np.int32)
        L["wslot"] = np.zeros((kw, n, 6))  # wslot[k, i]: slot k of particle i
        L["xr"] = np.zeros((n, 4))
        L["vw"] = np.zeros((n, 8))
        L["perm"] = np.zeros(n, dtype=np.int64)  # spatial sort: new row -> old row
        L["pbuf"] = np.zeros((n, 8))
        L["ibuf"] = np.zeros(n, dtype=np.int64)
        # near list of the pair pass (integrator.run_loop): slots of each row, their count,
        # the displacements when it was written.  A slot index is below npair, and int32
        # holds up to 2^31 - 1 slots, whose pair lists alone would take over 170 GB (two
        # buffers of partner, history and flag, over 80 bytes a slot); a larger list is
        # refused at the top rather than wrapped
        L["near"] = np.zeros(npair, dtype=np.int32)
        L["ncnt"] = np.zeros(n, dtype=np.int64)
        L["dref"] = np.zeros((n, 3))
        if old is not None:
            npo = int(old["start_a"][-1])
            kwo = old["wnbr_a"].shape[0]
            L["start_a"][:] = old["start_a"]
            L["nbr_a"][:npo] = old["nbr_a"][:npo]
            L["hist_a"][:npo] = old["hist_a"][:npo]
            L["act_a"][:npo] = old["act_a"][:npo]
            L["wnbr_a"][:kwo] = old["wnbr_a"]
            L["wcnt_a"][:] = old["wcnt_a"]
            L["whist_a"].reshape(kw, n, H_SIZE)[:kwo] = old["whist_a"].reshape(kwo, n, H_SIZE)
            L["xr"][:] = old["xr"]
            L["vw"][:] = old["vw"]
            L["sorder"][:] = old["sorder"]
            L["sgroup"][:] = old["sgroup"]
        self._lists = L
        self._npair, self._kw = npair, kw

    # ------------------------------------------------------------------ running
    def run(self, steps: int, ke_tol: float = -1.0, ke_every: int = 0,
            wall_log_every: int = 0) -> int:
        """Advance ``steps`` steps (stop early when settled if ke_tol >= 0); returns steps done.

        Raises SimulationError on blow-up (non-finite state or overlap above max_overlap of a
        particle's radius), naming the step and the particle (its insertion id); InputError
        when the state the run starts from already overlaps beyond max_overlap or is not
        finite (spheres placed into one another or into a wall), before any step.
        """
        if (isinstance(steps, bool) or not isinstance(steps, (int, float, np.integer, np.floating))
                or not (math.isfinite(steps) and steps >= 0 and float(steps) == int(steps))):
            raise InputError(self.source, "steps", "a whole number of steps >= 0", steps)
        steps = int(steps)
        self._wrap_periodic()
        if self._pair is None or self._need_forces:
            self._prepare()
        p, wa = self.p, self._warr
        nw = wa["wall_vel"].shape[0]
        nlog = steps // wall_log_every if wall_log_every > 0 else 0
        self.wall_log = np.zeros((nlog, nw, 6))
        lo = p.x.min(axis=0) - p.r.max()
        hi = p.x.max(axis=0) + p.r.max()
        # a wall point that can touch a particle lies within the particles' box (grown by
        # half of it, for the particles' own motion) and on the wall's own extent
        reach = np.array([min(1.5 * float(np.linalg.norm(np.maximum(abs(lo - c), abs(hi - c)))),
                              e) for c, e in zip(wa["wall_centre"], self._wall_extent())])
        # run_until_settled has no known length (its cap is 10 million steps): it runs as far as
        # its moving walls stay acceptable (below) and is refused there if not settled; any
        # other run is judged over the steps it is given
        limit = steps
        if getattr(self, "_open_ended", False):
            limit = self._periodic_steps(steps)
        else:
            self._check_periodic_walls(steps)
        if steps > 0:
            self._check_wall_steps(reach)
        status = np.zeros(5, dtype=np.int64)
        threads = numba.get_num_threads()
        if p.n < itg.PARALLEL_MIN:
            numba.set_num_threads(1)
        try:
            done = self._run(limit, ke_tol, ke_every, wall_log_every, reach, status)
        finally:
            numba.set_num_threads(threads)
        if done == limit < steps and not self.kinetic_energy() < ke_tol:
            try:
                self._check_periodic_walls(limit + 1)
            except InputError as exc:
                raise InputError(
                    exc.path, exc.field, exc.expected,
                    f"not settled after {limit} steps ({limit * self.dt:.4g} s), where a moving "
                    f"wall reaches the end of the path it may take: {exc.got}") from None
        return done

    def _wrap_periodic(self):
        """Bring the positions on a periodic axis into the box, lo + (x - lo) mod L, before a
        run: the kernels' minimum image and their wrap after each drift move a sphere by one
        period at most, so a sphere given (or set) more than one period outside the box would
        miss its neighbours there, passing through them without a force.  A sphere moved
        makes the run start by building its lists and evaluating its forces anew."""
        x = self.p.x
        for q in range(2):
            if not self.periodic[q] or not len(x):
                continue
            lo, hi = float(self.box[2 * q]), float(self.box[2 * q + 1])
            c = x[:, q]
            out = ~((c >= lo) & (c < hi)) & np.isfinite(c)
            if out.any():
                w = lo + np.mod(c[out] - lo, hi - lo)
                c[out] = np.where(w < hi, w, lo)  # a remainder rounded up to L is 0
                self._need_forces = True

    def _periodic_steps(self, steps) -> int:
        """The most steps up to ``steps`` over which the walls pass
        :meth:`_check_periodic_walls` (raising its error if they fail where they stand): the
        extent a wall sweeps grows with the steps, so the steps that pass are those below a
        limit, found by bisection."""
        self._check_periodic_walls(0)
        wa = self._warr
        if not self.periodic.any() or not (np.any(wa["wall_vel"] != 0)
                                           or np.any(wa["wall_omega"] != 0)):
            return steps
        try:
            self._check_periodic_walls(steps)
            return steps
        except InputError:
            pass
        ok, bad = 0, steps
        while bad - ok > 1:
            mid = (ok + bad) // 2
            try:
                self._check_periodic_walls(mid)
                ok = mid
            except InputError:
                bad = mid
        return ok

    def _run(self, steps, ke_tol, ke_every, wall_log_every, reach, status):
        p, wa = self.p, self._warr
        total = 0
        resume_mid = False
        step0 = self.step
        kc.wait_for_compile()  # a compile under way (soilcal scenario compile) caches run_loop
        while True:
            L = self._lists
            done = itg.run_loop(
                steps - total, self.step, resume_mid,
                self._need_forces, float(ke_tol), int(ke_every), self.max_overlap,
                int(wall_log_every), step0, p.x, p.v, p.omega, p.f, p.t, p.r, p.m, p.inv_m, p.inv_i,
                p.mat, p.disp, p.ovr, p.peak, p.mroll, p.id, L["xr"], L["vw"], self.gravity, self.box,
                self.periodic, self.dt, self.skin, self.extra, self._pair, self.codes,
                self.sort_every, L["perm"], L["pbuf"], L["ibuf"], self._cells,
                self._cidx(), self._cof(), self._cpos_arr, self._wcells, self._wbins, self._glob(),
                L["start_a"], L["nbr_a"], L["hist_a"], L["act_a"], L["start_b"], L["nbr_b"],
                L["hist_b"], L["act_b"], min(numba.get_num_threads(), GROUPS_MAX),
                L["sorder"], L["sgroup"], L["sscratch"], L["hits"], L["near"], L["ncnt"],
                L["dref"], L["wnbr_a"], L["wcnt_a"], L["whist_a"], L["wnbr_b"], L["wcnt_b"],
                L["whist_b"], L["wslot"], wa["prim_kind"], wa["prim_wall"], wa["prim_mat"],
                wa["prim_par"], wa["prim_pts"], wa["prim_dirs"], wa["wall_vel"],
                wa["wall_omega"], wa["wall_centre"], self.wall_force, self.wall_torque, reach,
                self.wall_log, self._fstate, status)
            total += done
            self.step = step0 + total
            code = int(status[0])
            if code in (itg.NEED_PAIRS, itg.NEED_KW, itg.NEED_CELLS, itg.NEED_WBINS,
                        itg.NEED_HITS):
                if status[4] == 1:
                    self._need_forces = False
                    resume_mid = True
                need = int(status[3])
                if code == itg.NEED_CELLS:
                    self._cells = np.zeros(2 * need, dtype=np.int64)
                    self._wcells = np.zeros(2 * need, dtype=np.int64)
                elif code == itg.NEED_WBINS:
                    self._wbins = np.zeros(2 * need, dtype=np.int64)
                elif code == itg.NEED_HITS:
                    self._lists["hits"] = np.zeros(int(1.25 * need) + 64, dtype=np.int32)
                elif code == itg.NEED_PAIRS:
                    self._alloc_lists(p.n, int(1.25 * need) + 64, self._kw, self._lists)
                else:
                    self._alloc_lists(p.n, self._npair, need + 2, self._lists)
                continue
            self._need_forces = False
            if code == itg.BLOWUP and int(status[3]) in (3, 4):
                self._need_forces = True
                raise self._initial_state_error(int(status[2]), int(status[3]) == 3)
            if code == itg.BLOWUP:
                i = int(status[2])
                why = ("overlap above %g %% of its radius" % (100 * self.max_overlap)
                       if status[3] == 1 else "non-finite velocity")
                step = int(status[1])
                raise SimulationError(
                    f"step {step}: particle {int(p.id[i])}: {why} "
                    f"(radius {p.r[i]:.4g} m, dt {self.dt:.4g} s, t {step * self.dt:.4g} s); reduce the "
                    f"time step or check the stiffness (a shorter step that fails at the same time t "
                    f"points to a load the stiffness cannot carry, not to the step)")
            return total

    def _check_weight(self) -> None:
        """InputError when the weight of a sphere alone presses it deeper into a wall of the
        run than ``max_overlap`` of its radius: the Hertz overlap of a sphere resting on a
        flat face, delta = (3 m g / (4 E* sqrt(R)))^(2/3), is delta / R = (pi rho g R /
        E*)^(2/3), largest for the largest sphere of each material (a softer wall, a weaker
        contact law or a larger sphere only adds to it); such a run would stop at the first
        sphere that comes to rest on the wall."""
        g = float(np.linalg.norm(self.gravity))
        if g == 0.0 or not self.walls.mat:
            return
        p = self.p
        for k in np.unique(p.mat):
            mat = self.materials.materials[int(k)]
            if not np.any((p.mat == k) & (p.inv_m > 0)):
                continue
            rmax = float(p.r[(p.mat == k) & (p.inv_m > 0)].max())
            for wm in sorted(set(self.walls.mat)):
                estar = float(self._pair[int(k), wm, P_ESTAR])
                frac = (math.pi * mat.density * g * rmax / estar) ** (2.0 / 3.0)
                if frac > self.max_overlap:
                    wall = self.materials.materials[wm].name
                    need = math.pi * mat.density * g * rmax / self.max_overlap ** 1.5
                    raise InputError(
                        self.source, f"materials.{mat.name}",
                        f"a material stiff enough to carry a sphere's own weight on a "
                        f"'{wall}' wall within max_overlap = {100 * self.max_overlap:g} % of "
                        f"its radius (Hertz: E* >= pi rho g R / max_overlap^1.5 = "
                        f"{need:.4g} Pa for the largest sphere, R = {rmax:.4g} m), or a larger "
                        f"max_overlap",
                        f"E* = {estar:.4g} Pa: a resting sphere would overlap the wall by "
                        f"{100 * frac:.3g} % of its radius")

    def _check_periodic_walls(self, steps) -> None:
        """InputError naming the wall that a sphere could touch across a periodic boundary:
        wall contacts do not see periodic images (walls.py), so a wall within reach R_max (the
        largest radius) of a boundary x = lo or hi is accepted only where its surface there
        runs along x and continues periodically (:meth:`_periodic_fault`: the planes x = lo
        and x = hi cut it in the same section, a floor, a plate across the slab or wider than
        it, a closed solid whose caps lie on the boundaries inside a closed outline of that
        section, with no sphere centre inside its end faces); walls moving together (floor
        tiles) that fail alone are judged as one surface.  Otherwise a sphere beside one
        boundary would miss the contacts across it, or, outside the box, every contact.  A
        plane must be parallel to the periodic axes, rising over a period by at most
        max(2e-4 R_min, 4 ulps of its coordinates as stored: float32 for a binary STL, the
        last digit of an ASCII one, float64 for arrays and analytic walls) (R_min the smallest radius, whose contacts
        a step changes most).  A moving wall is checked over the
        ``steps`` of the run: its extent swept by its velocity, its sections over the planes
        its motion along x carries past, and the sphere of its reach about its centre when it
        turns about any axis but x."""
        wa = self._warr
        if not self.periodic.any() or wa["prim_kind"].shape[0] == 0:
            return
        rho = float(self.p.r.max())
        span = steps * self.dt
        names = ("x", "y")
        for q in range(2):
            if not self.periodic[q]:
                continue
            lo, hi = float(self.box[2 * q]), float(self.box[2 * q + 1])
            # 4 ulps of the coordinates as they were stored (8 unit roundoffs: a binary STL's
            # float32, an ASCII STL's last digit, float64 arrays and analytic walls)
            # per primitive: each face is judged with its own rounding (a coarsely stored
            # mesh elsewhere in the box loosens no other wall's checks)
            res = self._rounding()
            self._check_declared_rounding(q)
            # whether a wall is clear of the boundaries (within reach of a sphere beside one)
            # is judged to float64's rounding of the box's numbers only: no wall's stored
            # rounding makes it count as clear
            eps_c = 4.0 * float(np.finfo(np.float64).eps) * max(abs(lo), abs(hi))
            eps_all = np.maximum(max(2e-4 * rho, eps_c), 8.0 * res)
            # the largest rise over the period of a flat face along q (plane, rectangle,
            # triangle alike): 2e-4 of the smallest radius, whose contacts a step changes
            # most, or 4 ulps of the face's own coordinates as stored, per primitive
            eps_p = np.maximum(2e-4 * float(self.p.r.min()), 8.0 * res)
            nw = wa["wall_vel"].shape[0]
            a_w, b_w = np.full(nw, np.inf), np.full(nw, -np.inf)
            bad = np.zeros(nw, dtype=bool)  # a primitive near a boundary that is not parallel
            has = np.zeros(nw, dtype=bool)  # a bounded primitive
            kinds, walls_of, par_all = wa["prim_kind"], wa["prim_wall"], wa["prim_par"]
            planes = np.flatnonzero(kinds == PLANE)
            for k in planes:
                # how far the plane rises across the period: a sphere crossing the boundary
                # lands that much deeper in it or farther from it (a 6 um step changes an
                # overlap of 0.01 R = 50 um by 12 % at R = 5 mm, its Hertz force by 16 %)
                par = par_all[k]
                rise = float(_rise(par[3 + q], hi - lo))
                if rise > eps_p[k]:
                    name = self.walls.names[walls_of[k]]
                    raise InputError(
                        self.source, f"walls.{name}",
                        f"a plane parallel to {names[q]} in a box periodic in {names[q]}, its "
                        f"rise over the period ({hi - lo:.6g} m) within {eps_p[k]:.3g} m "
                        f"(max(2e-4 R_min, 4 ulps of its coordinates as stored, float64); a "
                        f"sphere crossing the "
                        f"boundary would land deeper in it or farther from it; wall contacts "
                        f"do not see periodic images)",
                        f"normal {par[3:6].tolist()}: a rise of {rise:.4g} m")
            ks = np.flatnonzero(kinds != PLANE)
            if ks.size == 0:
                continue
            # each bounded primitive's extent along q and whether its surface is unchanged along
            # q: triangles (a mesh's thousands) at once, the few other primitives one by one
            a, b = np.empty(ks.size), np.empty(ks.size)
            flat = np.zeros(ks.size, dtype=bool)
            # a flat face's unit normal and rise over the period (named when it is refused)
            unit, rises = np.full((ks.size, 3), np.nan), np.full(ks.size, np.nan)
            tri = kinds[ks] == TRIANGLE
            if tri.any():
                par = par_all[ks[tri]]
                c = par[:, [q, 3 + q, 6 + q]]
                n = np.cross(par[:, 3:6] - par[:, 0:3], par[:, 6:9] - par[:, 0:3])
                a[tri], b[tri] = c.min(axis=1), c.max(axis=1)
                nn = np.linalg.norm(n, axis=1)
                with np.errstate(invalid="ignore", divide="ignore"):
                    nq = np.nan_to_num(np.abs(n[:, q]) / nn, nan=1.0)
                    # the slope a float32 mesh (binary STL) cannot resolve: each vertex is
                    # rounded by half an ulp of its largest coordinate, which tilts a face
                    # by up to (rounding) x (its two edges) / (twice its area); 4 half-ulps
                    # of that are forgiven before the rise is taken (a level floor of 2 mm
                    # triangles at z = 0.1 m reads back with slopes of ~3e-6, 1 um over a
                    # 0.4 m period), at most 1e-3 (a face across the axis stays one)
                    ulp = 2.0 * res[ks[tri]]  # as stored: float32, ASCII digits, float64
                    edges = (np.linalg.norm(par[:, 3:6] - par[:, 0:3], axis=1)
                             + np.linalg.norm(par[:, 6:9] - par[:, 0:3], axis=1))
                    noise = np.nan_to_num(np.minimum(2.0 * ulp * edges / nn, 1e-3), nan=0.0)
                    unit[tri] = n / nn[:, None]
                rises[tri] = _rise(np.maximum(nq - noise, 0.0), hi - lo)
                flat[tri] = rises[tri] <= eps_p[ks[tri]]
            eps = eps_all[ks]  # each bounded primitive's
            for i in np.flatnonzero(~tri):
                a[i], b[i], flat[i] = _extent_along(kinds[ks[i]], par_all[ks[i]], q,
                                                    float(eps[i]), hi - lo,
                                                    float(eps_p[ks[i]]))
                if kinds[ks[i]] == RECTANGLE:
                    unit[i] = par_all[ks[i], 3:6]
                    rises[i] = _rise(par_all[ks[i], 3 + q], hi - lo)
            # an end face lying on a boundary, across the axis (the cap of a closed solid
            # exactly spanning the period): a sphere meets it at its rim only, where the faces
            # along the axis have it
            cap = (b - a <= eps) & ((np.abs(a - lo) <= eps) | (np.abs(b - hi) <= eps))
            w = walls_of[ks]
            om, vq = wa["wall_omega"][w], wa["wall_vel"][w][:, q]
            turn = np.any(np.delete(om, q, axis=1) != 0, axis=1)
            if turn.any():
                # a wall turning about any axis but q: the sphere of its reach about its centre
                ext = self._wall_extent()
                c = wa["wall_centre"][w[turn]][:, q]
                a[turn], b[turn], flat[turn] = c - ext[w[turn]], c + ext[w[turn]], False
            moves = vq != 0
            a = np.where(moves, np.minimum(a, a + vq * span), a)
            b = np.where(moves, np.maximum(b, b + vq * span), b)
            has[w] = True
            np.minimum.at(a_w, w, a)
            np.maximum.at(b_w, w, b)
            # within reach of a sphere in the box beside a boundary (farther out, unreachable)
            near = (((a < lo + rho - eps_c) & (b > lo - rho + eps_c))
                    | ((a < hi + rho - eps_c) & (b > hi - rho + eps_c)))
            off = near & ~flat & ~(cap & ~turn & ~moves)
            bad[w[off]] = True
            w_of, off_of, turn_of = w, off, turn  # per primitive in ks (w is reused below)
            # a flat face (triangle, rectangle) at rest turning about nothing but q: its rise
            flat_kind = ((kinds[ks] == TRIANGLE) | (kinds[ks] == RECTANGLE)) & ~turn
            tilted = np.zeros(nw, dtype=bool)
            # (steeper than 45 degrees it crosses the axis: named so by _face_at_fault)
            tilted[w[off & flat_kind & (rises <= hi - lo)]] = True
            cap &= ~turn & ~moves  # a cap of a wall at rest, met at its rim (below)
            for w in range(nw):
                if not has[w]:
                    continue
                A, B = a_w[w], b_w[w]
                if A >= lo + rho - eps_c and B <= hi - rho + eps_c:
                    continue  # clear of both boundaries
                why = ("a face within the largest radius of a boundary that does not run "
                       f"along {names[q]}" + (f" (a flat face rising over the period by more "
                       f"than {eps_p[ks[w_of == w]].min():.3g} m, max(2e-4 R_min, 4 ulps of "
                       f"its coordinates as stored), as a plane would; vertices are judged "
                       f"as float64 unless given as float32: a binary STL moved or scaled with "
                       f"float64 numbers loses float32's allowance, keep them float32 "
                       f"(.astype(np.float32)), read it with add_stl(scale=) or give add_mesh "
                       f"rounding=)" if tilted[w] else "")
                       + f", {self._face_at_fault(q, w, ks, w_of, off_of, turn_of, unit, rises)}"
                       if bad[w] else None)
                if why is None:
                    why = self._periodic_fault(q, [w], ks, flat, cap, rho, eps_all, res,
                                               span)
                if why is not None and not bad[w]:
                    # tiles: the walls moving with this one, judged as one surface
                    mates = [g for g in range(nw) if has[g] and not bad[g]
                             and not (a_w[g] >= lo + rho - eps_c
                                      and b_w[g] <= hi - rho + eps_c)
                             and np.array_equal(wa["wall_vel"][g], wa["wall_vel"][w])
                             and np.array_equal(wa["wall_omega"][g], wa["wall_omega"][w])
                             and (not np.any(wa["wall_omega"][w] != 0)
                                  or np.array_equal(wa["wall_centre"][g], wa["wall_centre"][w]))]
                    if len(mates) > 1 and self._periodic_fault(q, mates, ks, flat, cap, rho,
                                                               eps_all, res, span) is None:
                        continue
                if why is None:
                    continue
                name = self.walls.names[w]
                ax = names[q]
                moving = " over the run" if np.any(wa["wall_vel"][w] != 0) or np.any(
                    wa["wall_omega"][w] != 0) else ""
                raise InputError(
                    self.source, f"walls.{name}",
                    f"in a box periodic in {ax} ({lo:.6g} .. {hi:.6g} m; wall contacts do not "
                    f"see periodic images): a wall kept {rho:.4g} m (the largest radius) "
                    f"inside the boundaries, or one whose surface within that of each boundary "
                    f"runs along {ax} and is cut by the planes {ax} = {lo:.6g} and {hi:.6g} m in "
                    f"the same section (a floor, a plate across the slab, a wider plate, a "
                    f"closed solid with its end faces on the boundaries; walls moving together, "
                    f"such as floor tiles, are taken as one surface), past a boundary that "
                    f"section or nothing",
                    f"a wall reaching {ax} = {A:.6g} .. {B:.6g} m{moving}: {why}; a sphere "
                    f"beside one boundary would miss the surface across it")

    def _face_at_fault(self, q, w, ks, w_of, off, turn, unit, rises) -> str:
        """The first face of wall ``w`` refused near a periodic boundary, in words: its index
        among the wall's faces (a mesh's triangle index, as add_mesh was given them), its
        kind, and for a flat face its unit normal and rise over the period (after forgiving
        the tilt the stored rounding of a triangle's vertices gives it)."""
        kinds, walls_of = self._warr["prim_kind"], self._warr["prim_wall"]
        j = int(np.flatnonzero(off & (w_of == w))[0])
        k = int(ks[j])
        face = int(np.count_nonzero(walls_of[:k] == w))
        kind = {TRIANGLE: "triangle", RECTANGLE: "rectangle", DISK: "disk",
                CYLINDER: "cylinder", CONE: "cone"}.get(int(kinds[k]), "face")
        ax = ("x", "y")[q]
        if turn[j]:
            how = f"turning about an axis other than {ax}"
        elif np.isfinite(rises[j]) and rises[j] <= float(self.box[2 * q + 1] - self.box[2 * q]):
            nrm = ", ".join(f"{c:.6g}" for c in unit[j])
            how = f"normal ({nrm}), rising {rises[j]:.4g} m over the period"
        elif np.all(np.isfinite(unit[j])):
            # steeper than 45 degrees: it crosses the axis rather than rising along it
            nrm = ", ".join(f"{c:.6g}" for c in unit[j])
            tilt = math.degrees(math.asin(min(1.0, abs(float(unit[j][q])))))
            how = (f"normal ({nrm}): a face at {tilt:.3g} degrees to the {ax} axis, across "
                   f"it rather than flat along the period (0 degrees)")
        else:
            how = f"its section across {ax} not the same all along it"
        n_faces = int(np.count_nonzero(walls_of == w))
        fac = self.__dict__.get("_mesh_facets", {}).get(w)
        if fac is not None:
            return (f"facet {int(fac[face])} of its STL file, face {face} of its {n_faces} "
                    f"as added ({kind}, {how})")
        return f"face {face} of its {n_faces} as added ({kind}, {how})"

    def _periodic_fault(self, q, walls, ks, flat, cap, rho, eps_all, res, span):
        """None when the surface of ``walls`` (moving together) continues periodically across
        axis q over a run of ``span`` seconds, else what breaks it.  In the walls' own frame
        at the start (a shift s = v_q span along q sweeps the planes the spheres meet), the
        spheres in the box within the largest radius rho of a boundary meet the faces between
        q = lo - max(s, 0) and lo + rho - min(s, 0) (and at hi likewise), and the plane q = c
        cuts all of them in one section, the one at q = lo: where their faces run along q
        (their normals across q, the primitives that are not were refused) and the sections
        at both ends agree, a sphere's closest point on the periodic continuation is on the
        faces in the box, so the contacts it misses across the boundary are ones it has.
        Past a boundary (within rho) the section is that one or empty (a plate wider than
        the slab, a floor ending on the boundary).  A section changes only at a corner or a
        cylinder's end along q: it is taken there and halfway between.  An end face lying on
        a boundary (the cap of a closed solid spanning the period) is met at its rim only when
        every corner of it (32 points round a disk's rim) and every point of its edges
        (:func:`_edge_outside`) lies inside or on a closed outline
        of the section there (:func:`_closed_outline`: the bounded faces of the planar graph
        of its pieces, split where they meet or cross, so a solid standing on a floor of the
        same wall or on another solid is enclosed and pieces with an open end never enclose;
        inside: an odd count of one face's pieces crossing a ray from it, or within a circle),
        and no sphere centre lies inside or on such an end face (seen along q) at the run's
        start (:meth:`_spheres_enclosed`, judged again at every run; the open space that
        closed outlines surround, a duct's cavity or a tunnel beside a ridge, is free).  Sections are compared
        per material within max(2e-4 rho, 4 ulps of the coordinates as stored), as walls.py
        joins tiles: every point of the pieces of each within that distance of a piece of
        the other (:func:`_covered`; pieces shorter than it left out), circles by centre and
        radius; the sections exactly one period apart (q = lo and hi), which a sphere crossing
        the boundary meets in turn, within max(2e-4 R_min, 4 ulps as stored), the limit of a
        flat face's rise over the period.  ``eps_all``: each primitive's tolerance of where
        it lies (its stored rounding): each wall's largest, the smallest of those among
        these walls taken (no wall's rounding loosens another's check); ``res``: each
        primitive's stored rounding (:meth:`_rounding`), as the caller took it."""
        wa = self._warr
        lo, hi = float(self.box[2 * q]), float(self.box[2 * q + 1])
        sel = np.isin(wa["prim_wall"][ks], walls)
        # walls judged together (tiles) are held to the strictest of their own limits (each
        # wall's: the largest of its faces'): a coarsely stored wall loosens no other's
        wk = wa["prim_wall"][ks]
        eps = min(float(eps_all[ks[wk == g]].max()) for g in walls if np.any(wk == g))
        prims = ks[sel & flat]
        par = wa["prim_par"][prims]
        shift = float(wa["wall_vel"][walls[0], q]) * span
        # 4 ulps of the faces' coordinates as stored (8 unit roundoffs: float32 for a
        # binary STL, the last digit of an ASCII one, float64 for arrays)
        res, pw = res[prims], wa["prim_wall"][prims]
        ulps = (8.0 * min(float(res[pw == g].max()) for g in walls if np.any(pw == g))
                if prims.size else 0.0)
        tol = max(2e-4 * rho, ulps)
        # one period on, the section a sphere crossing the boundary meets in place of the
        # one at lo: the step between them is judged as a flat face's rise over the period
        # is, within max(2e-4 R_min, 4 ulps of the coordinates as stored) (the tilt the
        # rounding gives a small face is forgiven face by face, a rise of the whole surface
        # is not)
        tol_end = max(2e-4 * float(self.p.r.min()), ulps)
        # the answer depends on R_min through tol_end: spheres added later change it
        key = (q, tuple(walls), rho, eps, tol, tol_end, shift, lo, hi, hash(par.tobytes()))
        # walls at rest keep their answer (a moving wall is elsewhere at the next run)
        still = not (np.any(wa["wall_vel"][walls] != 0) or np.any(wa["wall_omega"][walls] != 0))
        cache = self.__dict__.setdefault("_periodic_cache", {}) if still else {}
        if key in cache:
            return self._spheres_enclosed(q, *cache[key])
        sp, sn = max(shift, 0.0), min(shift, 0.0)
        sec = _Sections(wa["prim_kind"][prims], par, wa["prim_mat"][prims], q, eps, tol,
                        [(lo - rho - sp, lo + rho - sn), (hi - rho - sp, hi + rho - sn)])
        br = sec.breaks()
        ax = ("x", "y")[q]

        def samples(a, b):
            c = np.unique(np.concatenate([[a, b], br[(br > a) & (br < b)]]))
            return np.sort(np.concatenate([c, 0.5 * (c[1:] + c[:-1])]))

        ref = sec.at(lo - sp)
        why = None
        end = sec.at(hi - sp)
        if not sec.same(end, ref, min(tol, tol_end)):
            r_min = float(self.p.r.min())
            limit = (f"max(2e-4 R_min = {2e-4 * r_min:.3g} m, 4 ulps of the coordinates as "
                     f"stored = {ulps:.3g} m)" if tol_end <= tol else
                     f"max(2e-4 R_max = {2e-4 * rho:.3g} m, 4 ulps of the faces' "
                     f"coordinates as stored = {ulps:.3g} m), within which any two sections "
                     f"are compared")
            why = (f"its faces at {ax} = {hi - sp:.6g} m ({sec.describe(end)}) are not those "
                   f"one period away at {ax} = {lo - sp:.6g} m ({sec.describe(ref)}) within "
                   f"{min(tol, tol_end):.3g} m ({limit}; a sphere crossing the boundary would "
                   f"meet a step)"
                   + (", as it stands at the start, moving by "
                      f"{shift:.4g} m along {ax} over the run" if shift else ""))
        for a, b, inside in ((lo - sp, lo + rho - sn, True), (hi - rho - sp, hi - sn, True),
                             (lo - rho - sp, lo - sp, False), (hi - sn, hi + rho - sn, False)):
            if why is not None:
                break
            for c in samples(a, b):
                s = sec.at(c)
                if sec.same(s, ref) or (not inside and not s):
                    continue
                where = "past the boundary " if not inside else ""
                why = (f"its faces {where}at {ax} = {c:.6g} m ({sec.describe(s)}) are not "
                       f"those at {ax} = {lo - sp:.6g} m ({sec.describe(ref)})"
                       + (", as it stands at the start, moving by "
                          f"{shift:.4g} m along {ax} over the run" if shift else ""))
                break
            if why is not None:
                break
        shut = {}  # the closed outlines enclosing accepted caps, by boundary
        if why is None:
            # the caps on a boundary: every corner inside or on a closed outline there
            cp = ks[sel & cap]
            outline, faces = {}, {}
            for k in cp:
                cor = _face_corners(wa["prim_kind"][k], wa["prim_par"][k])
                c = lo if abs(cor[:, q].mean() - lo) <= abs(cor[:, q].mean() - hi) else hi
                if c not in outline:
                    at = list(sec.at(c).values())
                    lines = np.concatenate([v[0] for v in at]) if at else np.zeros((0, 2, 2))
                    circ = np.concatenate([v[1] for v in at]) if at else np.zeros((0, 3))
                    outline[c] = (*_closed_outline(lines, tol), circ)
                loops, face, circ = outline[c]
                poly = cor[:, list(_ACROSS[q])]
                out = [pt for pt in poly if not _enclosed(pt, loops, face, circ, tol)]
                edge = None if out else _edge_outside(poly, loops, face, circ, tol)
                if out or edge is not None:
                    yz = ", ".join(f"{v:.6g}" for v in (out[0] if out else edge))
                    across = ", ".join("xyz"[i] for i in _ACROSS[q])
                    why = (f"an end face on the boundary {ax} = {c:.6g} m with "
                           + ("a corner" if out else "a point of an edge (bridging open space "
                              "between closed outlines)")
                           + f" at ({across}) = ({yz}) m outside every closed outline of the "
                           f"section of its faces along {ax} there (a sphere meets its face)")
                    break
                faces.setdefault(c, []).append(cor[:, list(_ACROSS[q])])
            if why is None:
                # the solid a sphere would meet at these end faces is the part of the
                # section they cover (a duct's cavity, a tunnel beside a ridge are open)
                shut = {c: (f, c, tol) for c, f in faces.items()}
        shut = list(shut.values())
        cache[key] = (why, shut)
        return self._spheres_enclosed(q, why, shut)

    def _spheres_enclosed(self, q, why, shut):
        """``why``, or, when it is None, what a sphere inside a closed solid whose end faces
        were accepted on a boundary breaks: its centre (now, at the run's start) inside or on
        one of those end faces seen along q (:func:`_inside_caps`); such a sphere meets the
        end faces, and the spheres beside the other boundary across them.  Inside a closed
        outline but off the end faces (a hollow duct's cavity, a tunnel beside a closed ridge)
        a sphere meets only faces along q, which continue periodically."""
        if why is not None or not shut or self.p.x.shape[0] == 0:
            return why
        ax = ("x", "y")[q]
        pts = self.p.x[:, list(_ACROSS[q])]
        for caps, c, tol in shut:
            ins = np.flatnonzero(_inside_caps(pts, caps, tol))
            if ins.size:
                i = int(ins[0])
                across = ", ".join("xyz"[j] for j in _ACROSS[q])
                at = ", ".join(f"{v:.6g}" for v in pts[i])
                return (f"{ins.size} sphere(s) inside the end faces on the boundary "
                        f"{ax} = {c:.6g} m (sphere {i} at ({across}) = ({at}) m): "
                        f"they meet the end faces, and each other across the boundary through "
                        f"them")
        return None

    def _check_wall_steps(self, reach) -> None:
        """InputError naming the wall whose surface moves more than ``max_overlap`` of the
        smallest radius in one step: a contact it makes would start deeper than the run
        accepts (a blow-up at its first step), and a thin wall moving more than a diameter
        per step passes through a sphere without touching it.  The step of each primitive's
        surface: :func:`_surface_steps`, with ``reach`` from :meth:`run`; the first primitive
        over the limit names its wall."""
        wa = self._warr
        limit = self.max_overlap * float(self.p.r.min())
        step = _surface_steps(wa["prim_kind"], wa["prim_wall"], wa["prim_par"], wa["wall_vel"],
                              wa["wall_omega"], wa["wall_centre"], reach, self.dt)
        over = np.flatnonzero(step > limit)
        if over.size:
            k = int(over[0])
            w = int(wa["prim_wall"][k])
            v, om, step = wa["wall_vel"][w], wa["wall_omega"][w], float(step[k])
            name = self.walls.names[w]
            raise InputError(
                self.source, f"walls.{name}",
                f"a wall whose surface moves at most max_overlap = "
                f"{100 * self.max_overlap:g} % of the smallest radius ({limit:.4g} m) per "
                f"step (a contact would start deeper than the run accepts, and a thin wall "
                f"can pass through a sphere unseen): a step dt <= {self.dt * limit / step:.4g} s "
                f"at this motion, or a surface speed <= {limit / self.dt:.4g} m/s at dt = "
                f"{self.dt:.4g} s",
                f"{step / self.dt:.4g} m/s (velocity {v.tolist()} m/s, omega {om.tolist()} "
                f"rad/s): {step:.4g} m per step")

    def _initial_state_error(self, i: int, overlap: bool) -> InputError:
        """The error of a state that a run cannot start from: row ``i`` overlaps a sphere or
        a wall beyond ``max_overlap`` of its radius, or its velocity is not finite."""
        p = self.p
        pid = int(p.id[i])
        if not overlap:
            return InputError(self.source, "particles.v", "finite velocities and spins",
                              f"particle {pid}: v {p.v[i].tolist()}, omega {p.omega[i].tolist()}")
        # the sphere it overlaps most, if any (a wall otherwise)
        dx = p.x - p.x[i]
        for q in range(2):
            if self.periodic[q]:
                span = self.box[2 * q + 1] - self.box[2 * q]
                dx[:, q] -= span * np.round(dx[:, q] / span)
        d = np.linalg.norm(dx, axis=1)
        ov = p.r + p.r[i] - d
        ov[i] = -np.inf
        j = int(np.argmax(ov))
        frac = float(p.ovr[i]) if np.isfinite(p.ovr[i]) else float("nan")
        if ov[j] > 0 and ov[j] / p.r[i] >= 0.999 * frac:
            what = (f"particle {pid} overlaps particle {int(p.id[j])} by {100 * ov[j] / p.r[i]:.3g} "
                    f"% of its radius (centres {d[j]:.4g} m apart, radii {p.r[i]:.4g} and "
                    f"{p.r[j]:.4g} m)")
        elif np.isfinite(frac):
            what = f"particle {pid} overlaps a wall by {100 * frac:.3g} % of its radius"
        else:
            what = f"particle {pid}: its overlap with a wall is not a finite number (position {p.x[i].tolist()})"
        # a radius of a metre or so, placed a few millimetres from its neighbour or wall: a
        # size typed in millimetres
        units = (f"radii are in metres: a radius of {p.r[i]:g} is {p.r[i]:g} m, 1 mm is 0.001"
                 if p.r[i] >= 0.1 and (ov[j] > 0.5 * p.r[i] or frac > 0.5) else None)
        return InputError(self.source, "particles",
                          f"a starting state whose overlaps are at most max_overlap = "
                          f"{100 * self.max_overlap:g} % of a radius (separate the spheres or move "
                          f"the wall or tool placed into them, or raise max_overlap)", what,
                          note=units)

    def _cidx(self):
        if getattr(self, "_cidx_arr", None) is None or self._cidx_arr.shape[0] != self.p.n:
            self._cidx_arr = np.zeros(self.p.n, dtype=np.int64)
            self._cof_arr = np.zeros(self.p.n, dtype=np.int64)
            self._cpos_arr = np.zeros((self.p.n, 4))  # cell-sorted x, y, z, R
        return self._cidx_arr

    def _wall_extent(self):
        """Largest distance from each wall's centre to its surface (inf for planes); rigid
        motion keeps it."""
        wa = self._warr
        ext = np.zeros(wa["wall_centre"].shape[0])
        tri = wa["prim_kind"] == TRIANGLE
        if tri.any():  # a mesh's triangles at once: the farthest corner from their wall's centre
            w = wa["prim_wall"][tri]
            corners = wa["prim_par"][tri][:, :9].reshape(-1, 3, 3)
            e = np.linalg.norm(corners - wa["wall_centre"][w][:, None, :], axis=2).max(axis=1)
            np.maximum.at(ext, w, e)
        for p in np.flatnonzero(~tri):
            kind, w = wa["prim_kind"][p], wa["prim_wall"][p]
            par, c = wa["prim_par"][p], wa["wall_centre"][w]
            if kind == RECTANGLE:
                e = float(np.linalg.norm(par[0:3] - c) + math.hypot(par[9], par[10]))
            elif kind == DISK:
                e = float(np.linalg.norm(par[0:3] - c) + par[6])
            elif kind == CYLINDER:
                e = float(np.linalg.norm(par[0:3] - c) + math.hypot(par[6], par[7]))
            elif kind == CONE:
                e = float(np.linalg.norm(par[0:3] - c)
                          + math.hypot(max(par[6], par[7]), max(abs(par[8]), abs(par[9]))))
            else:
                e = math.inf
            ext[w] = max(ext[w], e)
        return ext

    def _glob(self):
        npr = self._warr["prim_kind"].shape[0]
        if getattr(self, "_glob_arr", None) is None or self._glob_arr.shape[0] != npr:
            self._glob_arr = np.zeros(npr, dtype=np.int64)
        return self._glob_arr

    def _cof(self):
        self._cidx()
        return self._cof_arr

    def compute_forces(self):
        """Evaluate forces of the current state without stepping (into p.f, p.t, wall_force),
        with the walls' and spheres' present velocities in the dashpots, as LIGGGHTS and LAMMPS
        do when a ``run`` starts (soilcal.reference.deck evaluates every phase's start so).
        The next step starts from these forces, not from the last step's (whose dashpots saw
        half-step velocities), so a run interrupted by this call differs from one that is
        not (slightly, where dashpots act); to look at the forces of a
        run without touching it, call it on a copy (``copy.deepcopy(sim)``)."""
        self._need_forces = True
        self.run(0)
        return self.p.f, self.p.t

    def run_until_settled(self, ke_tol: float, check_every: int = 100,
                          max_steps: int = 10_000_000) -> bool:
        """Run until the translational kinetic energy (J) falls below ke_tol; True if settled.
        In a periodic box the run goes as far as its moving walls stay acceptable to
        :meth:`_check_periodic_walls` (at most ``max_steps``); not settled there, it stops
        with that check's InputError, naming the wall."""
        if ke_tol < 0:
            raise InputError(self.source, "ke_tol", "a kinetic energy threshold >= 0 J", ke_tol)
        start = self.step
        self._open_ended = True
        try:
            self.run(max_steps, ke_tol=ke_tol, ke_every=check_every)
        finally:
            self._open_ended = False
        return self.step - start < max_steps or self.kinetic_energy() < ke_tol

    # ------------------------------------------------------------------ results
    def kinetic_energy(self) -> float:
        return float(itg.kinetic_translational(self.p.v, self.p.m, self.p.inv_m))

    def rotational_energy(self) -> float:
        p = self.p
        ok = p.inv_i > 0
        inertia = 0.4 * p.m * p.r**2
        return float(0.5 * np.sum(inertia[ok] * np.sum(p.omega[ok] ** 2, axis=1)))

    @property
    def n_rebuilds(self) -> int:
        """Builds of the pair lists (the wall lists are built with them)."""
        return int(self._fstate[1])

    @property
    def peak_overlap(self) -> float:
        """Largest overlap of any particle, as a fraction of its radius, over the force
        evaluations since the simulation was built or :meth:`reset_peak_overlap` was called
        (kept per row in the time loop, the maximum taken here)."""
        return float(self.p.peak.max()) if self.p.n else 0.0

    def reset_peak_overlap(self) -> None:
        self.p.peak[:] = 0.0

    @property
    def n_wall_rebuilds(self) -> int:
        """Builds of the wall lists alone (walls moved, particles did not)."""
        return int(self._fstate[2])

    def index(self, ids):
        """Rows of the particles with insertion ids ``ids`` (the rows move when the engine
        re-sorts the particles in memory, module docstring)."""
        row = np.empty(self.p.n, dtype=np.int64)
        row[self.p.id] = np.arange(self.p.n)
        ids = np.asarray(ids)
        if ids.size and (ids.min() < 0 or ids.max() >= self.p.n):
            raise InputError(self.source, "ids", f"insertion ids in [0, {self.p.n})",
                             (int(ids.min()), int(ids.max())))
        return row[ids]

    @property
    def x(self):
        return self.p.x

    @property
    def v(self):
        return self.p.v

    @property
    def omega(self):
        return self.p.omega

    @property
    def n(self):
        return self.p.n

    @property
    def prim_par(self):
        return self._warr["prim_par"]


__all__ = ["Simulation", "NPAR"]
