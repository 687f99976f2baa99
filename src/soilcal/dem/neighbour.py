"""Verlet neighbour lists built from a cell list, with contact history remapping.

Cell list: cubic-ish cells of edge >= 2 R_max + skin + s_c (s_c: largest JKR separation
range), particles counting-sorted by cell index (x fastest).  Periodic dimensions (x, y) use
the box and the minimum-image convention, so the box must be at least two cells wide.

Verlet list: a half list, for every particle i the partners j > i with
|x_i - x_j| < R_i + R_j + skin + s_c, sorted by j, so that each pair is evaluated once (LIGGGHTS
``newton on``).  Rows are stored compactly (CSR): the partners of i are
nbr[start[i]:start[i+1]], and every per-pair array (history, touching flag, pair results) is
indexed by the same pair index, so a particle's pairs are contiguous in memory.  The
particles are also grouped into slabs of whole cells (:func:`_slabs`): the pair pass works
through the slabs in three colours, the slabs of a colour dealt to one group per thread by
their work, and adds each pair's force to both particles without races and in an order
fixed by the lists.  The lists are valid while no particle moved more than skin/2
since the build (then no pair can close the skin) and no wall moved more than skin/2.  Each
list slot owns a contact-history row (tangential spring, rolling spring, square root of the
JKR contact radius) and a touching flag; on rebuild every surviving pair copies both from
the old list (a merge of the two sorted lists), so history is never lost while two
particles stay within the cutoff.

Walls: each particle also lists the wall primitives within R_i + skin + s_c (at most KW;
wall history row k * n + i for slot k of particle i, so that the first slots of all the
particles lie together whatever width KW the lists once needed).  Unbounded
primitives (planes, cylinders, cones, rectangles, disks) are tested by every particle;
triangles are binned into the cells their bounding box, grown by the cutoff, overlaps, and
tested only by the particles of those cells.

When only walls moved by half the skin (the particles did not), :func:`build_wall_lists`
renews the wall lists alone.

The particle loops run in parallel over interleaved blocks of particles in cell order
(every thread gets blocks from the whole domain, dense and sparse alike); each particle
writes only its own rows.  The slab groups and the triangle bins are filled serially, so
their order never depends on the thread count.
"""

from __future__ import annotations

import math

from numba import njit, prange

from soilcal.dem.contact import H_A, H_DP
from soilcal.dem.walls import TRIANGLE, prim_closest


@njit(cache=True)
def _grid_dim(lo_box, hi_box, per, xmin, xmax, cell):
    if per:
        L = hi_box - lo_box
        nc = max(1, int(L / cell))
        return lo_box, L / nc, nc
    lo = xmin - 1e-9 * max(1.0, abs(xmin))
    nc = max(1, int((xmax - lo) / cell) + 1)
    return lo, cell, nc


@njit(cache=True)
def _cell_coord(x, lo, cs, nc, per):
    c = int(math.floor((x - lo) / cs))
    if per:
        c = c % nc
    else:
        c = min(max(c, 0), nc - 1)
    return c


@njit(cache=True, inline="always")
def min_image(d, periodic, half, length):
    """Minimum-image separation along one axis of a periodic box (no-op if not periodic)."""
    if periodic:
        if d > half:
            return d - length
        if d < -half:
            return d + length
    return d


@njit(cache=True)
def _range(c, nc, per):
    # neighbour cell offsets along one dimension without duplicates
    if per:
        if nc >= 3:
            return -1, 1
        if nc == 2:
            return 0, 1
        return 0, 0
    lo = -1 if c > 0 else 0
    hi = 1 if c < nc - 1 else 0
    return lo, hi


@njit(cache=True, inline="always")
def _tri_cells(prim_par, p, q, cut, lo, cs, nc, per, clamp):
    """Cell range [c0, c1] along axis q covered by triangle p grown by cut (c0 > c1: none);
    ``clamp``: a triangle beyond the grid goes to its edge cells, where the particles beyond
    it are (:func:`_grid`)."""
    mn = min(prim_par[p, q], prim_par[p, 3 + q], prim_par[p, 6 + q]) - cut
    mx = max(prim_par[p, q], prim_par[p, 3 + q], prim_par[p, 6 + q]) + cut
    c0 = int(math.floor((mn - lo) / cs))
    c1 = int(math.floor((mx - lo) / cs))
    if per:
        if c1 - c0 + 1 >= nc:
            return 0, nc - 1
        return c0, c1
    if not clamp and (c1 < 0 or c0 > nc - 1):
        return 1, 0
    return min(max(c0, 0), nc - 1), max(min(c1, nc - 1), 0)


@njit(cache=True)
def _bin_triangles(prim_kind, prim_par, cut, lo0, cs0, n0, per0, lo1, cs1, n1, per1,
                   lo2, cs2, n2, wcell_start, wcell_idx, glob, clamp):
    """Bin triangle primitives by cell (counting sort); other kinds go to ``glob``.

    Returns (n_global, status, need): status 0 ok, 5 bin buffer too short (need entries).
    """
    ncell = n0 * n1 * n2
    for c in range(ncell + 1):
        wcell_start[c] = 0
    ng = 0
    total = 0
    for sweep in range(2):
        for p in range(prim_kind.shape[0]):
            if prim_kind[p] != TRIANGLE:
                if sweep == 0:
                    glob[ng] = p
                    ng += 1
                continue
            ax, bx = _tri_cells(prim_par, p, 0, cut, lo0, cs0, n0, per0, clamp)
            ay, by = _tri_cells(prim_par, p, 1, cut, lo1, cs1, n1, per1, clamp)
            az, bz = _tri_cells(prim_par, p, 2, cut, lo2, cs2, n2, False, clamp)
            for zz in range(az, bz + 1):
                for yy0 in range(ay, by + 1):
                    yy = yy0 % n1
                    for xx0 in range(ax, bx + 1):
                        c = xx0 % n0 + n0 * (yy + n1 * zz)
                        if sweep == 0:
                            wcell_start[c + 1] += 1
                            total += 1
                        else:
                            q = wcell_start[c + 1]
                            wcell_idx[q] = p
                            wcell_start[c + 1] = q + 1
        if sweep == 0:
            if total > wcell_idx.shape[0]:
                return ng, 5, total
            for c in range(ncell):
                wcell_start[c + 1] += wcell_start[c]
            for c in range(ncell, 0, -1):
                wcell_start[c] = wcell_start[c - 1]
    return ng, 0, 0


@njit(cache=True, inline="always")
def _cell_ranges(c, n0, n1, n2, p0, p1):
    cx = c % n0
    cy = (c // n0) % n1
    cz = c // (n0 * n1)
    a0, b0 = _range(cx, n0, p0)
    a1, b1 = _range(cy, n1, p1)
    a2, b2 = _range(cz, n2, False)
    return cx, cy, cz, a0, b0, a1, b1, a2, b2


@njit(cache=True, inline="always")
def _scan(q0, q1, i, xi, yi, zi, ri, cpos, cell_idx, p0, h0, L0, p1, h1, L1, cut0, out, o0,
          lim, cnt):
    """Candidates q0..q1-1 of the cell-sorted arrays against particle i (see :func:`_row`)."""
    for q in range(q0, q1):
        j = cell_idx[q]
        if j <= i:
            continue
        ddx = min_image(xi - cpos[q, 0], p0, h0, L0)
        ddy = min_image(yi - cpos[q, 1], p1, h1, L1)
        ddz = zi - cpos[q, 2]
        cut = ri + cpos[q, 3] + cut0
        if ddx * ddx + ddy * ddy + ddz * ddz < cut * cut:
            if o0 + cnt < lim:
                out[o0 + cnt] = j
            cnt += 1
    return cnt


@njit(cache=True)
def _row(q, cpos, cell_idx, cell_of, box, periodic, cut0, cell_start, n0, n1, n2, out, o0,
         lim):
    """Partners j > i of particle i = cell_idx[q] within the cutoff, written in the order
    they are met to out[o0:lim] (those beyond lim are only counted); returns their number.

    Candidates are read from the cell-sorted copy ``cpos`` (x, y, z, R per slot of
    ``cell_idx``), so each neighbour cell is a contiguous stretch of memory; the three cells
    of a row of the stencil along x are one stretch unless the row wraps around the box."""
    L0 = box[1] - box[0]
    L1 = box[3] - box[2]
    h0 = 0.5 * L0
    h1 = 0.5 * L1
    p0 = periodic[0]
    p1 = periodic[1]
    i = cell_idx[q]
    cx, cy, cz, a0, b0, a1, b1, a2, b2 = _cell_ranges(cell_of[i], n0, n1, n2, p0, p1)
    xi, yi, zi, ri = cpos[q, 0], cpos[q, 1], cpos[q, 2], cpos[q, 3]
    cnt = 0
    for dz in range(a2, b2 + 1):
        zz = cz + dz
        for dy in range(a1, b1 + 1):
            yy = cy + dy
            if yy < 0:
                yy += n1
            elif yy >= n1:
                yy -= n1
            base = n0 * (yy + n1 * zz)
            if cx + a0 >= 0 and cx + b0 < n0:
                cnt = _scan(cell_start[base + cx + a0], cell_start[base + cx + b0 + 1], i,
                            xi, yi, zi, ri, cpos, cell_idx, p0, h0, L0, p1, h1, L1, cut0, out,
                            o0, lim, cnt)
            else:
                for dx in range(a0, b0 + 1):
                    xx = cx + dx
                    if xx < 0:
                        xx += n0
                    elif xx >= n0:
                        xx -= n0
                    cc = base + xx
                    cnt = _scan(cell_start[cc], cell_start[cc + 1], i, xi, yi, zi, ri, cpos,
                                cell_idx, p0, h0, L0, p1, h1, L1, cut0, out, o0, lim, cnt)
    return cnt


#: cells a grid may have per particle, and at least (:func:`_grid`)
CELLS_PER_PARTICLE = 128
CELLS_MIN = 1 << 16
#: the bulk of a narrowed grid leaves out at most one particle in this many at either end
BULK_TRIM = 1000
HIST_BINS = 1024  # histogram bins of :func:`_bulk_range` (in cell_start, >= 1024 long)


@njit(cache=True, inline="always")
def cell_cap(n):
    """Most cells of the grid of n particles (:func:`_grid`)."""
    return max(CELLS_MIN, CELLS_PER_PARTICLE * n)


@njit(cache=True)
def _bulk_range(x, q, k, mn, mx, hist):
    """[a, b] in [mn, mx] holding every coordinate x[:, q] but at most k below a and k
    above b: three rounds of a histogram of HIST_BINS bins (in hist) each narrowing the
    range to the bins where the k-th smallest and largest coordinates fall."""
    n = x.shape[0]
    a = mn
    b = mx
    below = 0
    above = 0
    for _ in range(3):
        w = (b - a) / HIST_BINS
        if not w > 0.0:
            break
        for h in range(HIST_BINS):
            hist[h] = 0
        for i in range(n):
            v = x[i, q]
            if v < a or v > b:
                continue
            hist[min(int((v - a) / w), HIST_BINS - 1)] += 1
        h0 = 0
        c = below
        while h0 < HIST_BINS - 1 and c + hist[h0] <= k:
            c += hist[h0]
            h0 += 1
        below = c
        h1 = HIST_BINS - 1
        c = above
        while h1 > h0 and c + hist[h1] <= k:
            c += hist[h1]
            h1 -= 1
        above = c
        a, b = a + h0 * w, min(b, a + (h1 + 1) * w)
    return a, b


@njit(cache=True)
def _grid(x, r, box, periodic, skin, extra, cell_start, cell_idx, cell_of, cpos):
    """Cell grid over the particles' bounding box, particles counting-sorted by cell
    (cell_idx; cpos holds their x, y, z, R in the same order).

    The grid has at most :func:`cell_cap` cells: a bounding box that would need more (a
    sphere that left the others far behind: thrown off a tool, falling past the floor's
    edge) is first narrowed, along each non-periodic axis, to the bulk of the particles
    (:func:`_bulk_range`: all but at most n // BULK_TRIM beyond either end, which go to
    the edge cells, and the triangles beyond the grid with them: ``clamp``), then the
    cells of the longest axis are doubled until the grid fits.  Cells at least the cutoff
    wide, with the outlying particles clamped into the edge cells, still put every pair
    within the cutoff into the same or adjacent cells (clamping keeps the cell order), so
    the lists are the same; only their cost changes.

    Returns (ok, rmax, lo0, cs0, n0, lo1, cs1, n1, lo2, cs2, n2, clamp); ok is False when
    cell_start is too short (n0 * n1 * n2 + 1 needed).
    """
    n = x.shape[0]
    rmax = 0.0
    mn0, mn1, mn2 = x[0, 0], x[0, 1], x[0, 2]
    mx0, mx1, mx2 = mn0, mn1, mn2
    for i in range(n):
        rmax = max(rmax, r[i])
        mn0 = min(mn0, x[i, 0])
        mx0 = max(mx0, x[i, 0])
        mn1 = min(mn1, x[i, 1])
        mx1 = max(mx1, x[i, 1])
        mn2 = min(mn2, x[i, 2])
        mx2 = max(mx2, x[i, 2])
    cell = 2.0 * rmax + skin + extra
    lo0, cs0, n0 = _grid_dim(box[0], box[1], periodic[0], mn0, mx0, cell)
    lo1, cs1, n1 = _grid_dim(box[2], box[3], periodic[1], mn1, mx1, cell)
    lo2, cs2, n2 = _grid_dim(0.0, 0.0, False, mn2, mx2, cell)
    cap = cell_cap(n)
    clamp = False
    if n0 * n1 * n2 > cap:
        clamp = True
        k = n // BULK_TRIM
        if not periodic[0]:
            a, b = _bulk_range(x, 0, k, mn0, mx0, cell_start)
            lo0, cs0, n0 = _grid_dim(0.0, 0.0, False, a, b, cell)
        if not periodic[1]:
            a, b = _bulk_range(x, 1, k, mn1, mx1, cell_start)
            lo1, cs1, n1 = _grid_dim(0.0, 0.0, False, a, b, cell)
        a, b = _bulk_range(x, 2, k, mn2, mx2, cell_start)
        lo2, cs2, n2 = _grid_dim(0.0, 0.0, False, a, b, cell)
        while n0 * n1 * n2 > cap:
            # double the cells of the non-periodic axis with the most
            # (an axis of one cell is never halved: a periodic axis alone above the cap ends
            # the loop with the others at one cell each)
            if not periodic[0] and n0 > 1 and n0 >= n2 and (periodic[1] or n0 >= n1):
                n0 = (n0 + 1) // 2
                cs0 *= 2.0
            elif not periodic[1] and n1 > 1 and n1 >= n2:
                n1 = (n1 + 1) // 2
                cs1 *= 2.0
            elif n2 > 1:
                n2 = (n2 + 1) // 2
                cs2 *= 2.0
            else:
                break
    ncell = n0 * n1 * n2
    if ncell + 1 > cell_start.shape[0]:
        return False, rmax, lo0, cs0, n0, lo1, cs1, n1, lo2, cs2, n2, clamp
    for c in range(ncell + 1):
        cell_start[c] = 0
    for i in range(n):
        c = (_cell_coord(x[i, 0], lo0, cs0, n0, periodic[0])
             + n0 * (_cell_coord(x[i, 1], lo1, cs1, n1, periodic[1])
                     + n1 * _cell_coord(x[i, 2], lo2, cs2, n2, False)))
        cell_of[i] = c
        cell_start[c + 1] += 1
    for c in range(ncell):
        cell_start[c + 1] += cell_start[c]
    # counting sort (stable: particles keep increasing index inside a cell)
    for c in range(ncell, 0, -1):
        cell_start[c] = cell_start[c - 1]
    for i in range(n):
        c = cell_of[i]
        q = cell_start[c + 1]
        cell_idx[q] = i
        cpos[q, 0] = x[i, 0]
        cpos[q, 1] = x[i, 1]
        cpos[q, 2] = x[i, 2]
        cpos[q, 3] = r[i]
        cell_start[c + 1] = q + 1
    return True, rmax, lo0, cs0, n0, lo1, cs1, n1, lo2, cs2, n2, clamp


@njit(cache=True, inline="always")
def tri_beyond(par, p, x, y, z, lim):
    """Whether triangle p (rows v0 v1 v2 of ``par``) lies surely at lim or farther from
    point (x, y, z): its plane does, by a margin far beyond the rounding of either distance
    (1e-9 of lim and of the point's distance from v0, for the rounding relative to the
    triangle's size, plus 1e-14 of the distances of v0 and of the point from the origin,
    some 45 units in the last place, for that of the closest point's coordinates, which
    prim_closest forms at the size of the coordinates: a millimetre triangle 1 km from the
    origin and a reach of microns).  A point's distance from a
    triangle is at least its distance from the triangle's plane, so a triangle this
    rejects is one :func:`soilcal.dem.walls.prim_closest` puts at lim or beyond too: the
    wall lists are the same, at a fraction of the cost (most triangles binned to a cell
    are the large faces of a funnel or a hopper, whose bounding boxes hold many cells
    their planes are far from).  A sliver (sine of its widest angle below 1e-3, whose
    normal is not known well) is never rejected."""
    e1x, e1y, e1z = par[p, 3] - par[p, 0], par[p, 4] - par[p, 1], par[p, 5] - par[p, 2]
    e2x, e2y, e2z = par[p, 6] - par[p, 0], par[p, 7] - par[p, 1], par[p, 8] - par[p, 2]
    nx = e1y * e2z - e1z * e2y
    ny = e1z * e2x - e1x * e2z
    nz = e1x * e2y - e1y * e2x
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    l1 = math.sqrt(e1x * e1x + e1y * e1y + e1z * e1z)
    l2 = math.sqrt(e2x * e2x + e2y * e2y + e2z * e2z)
    l3 = math.sqrt((e2x - e1x) ** 2 + (e2y - e1y) ** 2 + (e2z - e1z) ** 2)
    # 2 area = nn = product of two sides times the sine of their angle; the smallest of the
    # three sines is that of the triangle's widest angle (or of a needle's narrow one)
    if not nn > 1e-3 * max(l1 * l2, l1 * l3, l2 * l3):
        return False
    wx, wy, wz = x - par[p, 0], y - par[p, 1], z - par[p, 2]
    s = abs(wx * nx + wy * ny + wz * nz)
    w = math.sqrt(wx * wx + wy * wy + wz * wz)
    a = (math.sqrt(par[p, 0] ** 2 + par[p, 1] ** 2 + par[p, 2] ** 2)
         + math.sqrt(x * x + y * y + z * z))
    return s > (lim + 1e-9 * (lim + w) + 1e-14 * a) * nn


@njit(cache=True, inline="always")
def _wall_row(i, io, x, r, cut0, cell_of, prim_kind, prim_par, wcell_start, wcell_idx, glob,
              ng, wnbr_old, wcnt_old, whist_old, wnbr_new, wcnt_new, whist_new):
    """Wall list of particle i: unbounded primitives, then the triangles binned in its cell
    (history rows copied from row io of the old list: i itself, or the row it had before a
    spatial sort); wcnt_new[i] may exceed KW."""
    KW, n = wnbr_new.shape
    H = whist_new.shape[1]
    c = cell_of[i]
    xi, yi, zi, ri = x[i, 0], x[i, 1], x[i, 2], r[i]
    wc = 0
    nb = wcell_start[c + 1] - wcell_start[c]
    for t in range(ng + nb):
        if t < ng:
            p = glob[t]
        else:
            p = wcell_idx[wcell_start[c] + t - ng]
        if prim_kind[p] == TRIANGLE and tri_beyond(prim_par, p, xi, yi, zi, ri + cut0):
            continue
        d = prim_closest(prim_kind[p], prim_par, p, xi, yi, zi)[0]
        if d < ri + cut0:
            if wc < KW:
                wnbr_new[wc, i] = p
                row = wc * n + i
                for h in range(H):
                    whist_new[row, h] = 0.0
                for k in range(wcnt_old[io]):
                    if wnbr_old[k, io] == p:
                        for h in range(H):
                            whist_new[row, h] = whist_old[k * n + io, h]
                        break
            wc += 1
    wcnt_new[i] = wc


@njit(cache=True)
def _wall_need(wcnt_new, KW):
    wneed = 0
    for i in range(wcnt_new.shape[0]):
        if wcnt_new[i] > KW:
            wneed = max(wneed, wcnt_new[i])
            wcnt_new[i] = KW
    return wneed


@njit(cache=True)
def _grid_and_bins(x, r, box, periodic, skin, extra, cell_start, cell_idx, cell_of, cpos,
                   prim_kind, prim_par, wcell_start, wcell_idx, glob):
    """Cell grid (:func:`_grid`) and triangle bins (:func:`_bin_triangles`) of a list build.
    Returns (status, need, ng, n0, n1, n2) with the status codes of :func:`build_lists`."""
    ok, rmax, lo0, cs0, n0, lo1, cs1, n1, lo2, cs2, n2, clamp = _grid(
        x, r, box, periodic, skin, extra, cell_start, cell_idx, cell_of, cpos)
    if not ok or n0 * n1 * n2 + 1 > wcell_start.shape[0]:
        return 3, n0 * n1 * n2 + 1, 0, n0, n1, n2
    ng, code, wneed = _bin_triangles(prim_kind, prim_par, rmax + skin + extra, lo0, cs0, n0,
                                     periodic[0], lo1, cs1, n1, periodic[1], lo2, cs2, n2,
                                     wcell_start, wcell_idx, glob, clamp)
    return code, wneed, ng, n0, n1, n2


SLAB_MAX = 768  # at most this many slabs
GROUPS_MAX = 64  # at most this many slab groups per colour (threads of the pair pass)
# groups assumed when the slab axis is chosen (fixed, never the thread count: the axis sets
# the colours and so the order in which contributions are added to a particle)
BALANCE_GROUPS = 2
# work of a touching pair in units of a particle or a listed pair when the slabs are dealt
# to the threads: a contact force costs 50-60 ns, a particle's row and a pair's distance
# check about 5 ns (settle benchmark bed, N = 20,000, one thread)
TOUCH_WEIGHT = 8
SGROUP_LEN = 3 * GROUPS_MAX + 2  # group offsets (3 G + 1) and, last, G
SCRATCH_LEN = 2 * SLAB_MAX + GROUPS_MAX  # slab work, slab owner, group load
NBLK_GROUPS = 32


@njit(cache=True, inline="always")
def block_size(n):
    """Particles per block: about 64, and a whole number of blocks per group, so that every
    group (and thread) gets the same number of blocks (only the last block may be short).
    Parallel particle loops take the blocks of group c as c, c + NBLK_GROUPS, ...: every
    group samples the whole domain, so dense and sparse regions are shared evenly."""
    per_group = max(1, (n + 64 * NBLK_GROUPS - 1) // (64 * NBLK_GROUPS))
    return max(1, (n + per_group * NBLK_GROUPS - 1) // (per_group * NBLK_GROUPS))


@njit(cache=True, inline="always")
def _slab(c, axis, n0, n1, ns, nc):
    """Slab of cell c: its coordinate along ``axis`` (nc cells) mapped onto ns slabs."""
    ca = c % n0 if axis == 0 else ((c // n0) % n1 if axis == 1 else c // (n0 * n1))
    return ca * ns // nc


@njit(cache=True)
def _slab_count(axis, n0, n1, n2, p0, p1):
    """(cells along ``axis``, slabs): slabs of whole cells, a multiple of 3 along a
    periodic axis of at least 3 cells (slabs three apart then never touch across the
    boundary), at most SLAB_MAX."""
    nc = n0 if axis == 0 else (n1 if axis == 1 else n2)
    per = p0 if axis == 0 else (p1 if axis == 1 else False)
    ns = nc
    if per and nc >= 3:
        ns = 3 * (nc // 3)
    return nc, min(ns, 3 * (SLAB_MAX // 3))


@njit(cache=True)
def _slab_work(axis, nc, ns, cell_idx, cell_of, start, act, touch_weight, n0, n1, work):
    """work[s]: pair-pass work of slab s, its particles plus their listed pairs, plus
    ``touch_weight`` per pair that touched after the last step (act; 0: not counted)."""
    for s in range(ns):
        work[s] = 0
    for q in range(cell_idx.shape[0]):
        i = cell_idx[q]
        w = start[i + 1] - start[i] + 1
        if touch_weight > 0:
            for k in range(start[i], start[i + 1]):
                w += touch_weight * act[k]
        work[_slab(cell_of[i], axis, n0, n1, ns, nc)] += w


@njit(cache=True)
def _deal(work, ns, G, owner, load):
    """Deal the slabs of each colour to G groups as contiguous ranges balanced by work:
    slab s goes to the group in whose share of its colour's cumulative work the middle of
    its own work falls (owner[s]).  Each thread so keeps about one region of the domain in
    all three colours (and in its cache), and no group is off its share by more than half
    a slab's work.  Returns the summed largest group load of the three colours, the time of
    the three pair passes on G threads in units of work."""
    cost = 0
    for colour in range(3):
        total = 0
        for s in range(colour, ns, 3):
            total += work[s]
        for g in range(G):
            load[g] = 0
        pre = 0
        for s in range(colour, ns, 3):
            g = 0 if total == 0 else min(G - 1, G * (2 * pre + work[s]) // (2 * total))
            owner[s] = g
            load[g] += work[s]
            pre += work[s]
        mx = 0
        for g in range(G):
            mx = max(mx, load[g])
        cost += mx
    return cost


@njit(cache=True)
def _axis_cost(axis, cell_idx, cell_of, start, act, n0, n1, n2, p0, p1, work, owner, load):
    """Pair-pass time (:func:`_deal`) of slabs along ``axis`` on BALANCE_GROUPS threads,
    in particles plus listed pairs (touching pairs not weighted: the axis stays the one
    chosen before the weight was introduced, and with it every trajectory)."""
    nc, ns = _slab_count(axis, n0, n1, n2, p0, p1)
    _slab_work(axis, nc, ns, cell_idx, cell_of, start, act, 0, n0, n1, work)
    return _deal(work, ns, BALANCE_GROUPS, owner, load)


@njit(cache=True)
def _slabs(cell_idx, cell_of, start, act, n0, n1, n2, p0, p1, G, sorder, sgroup, scratch):
    """Slab groups for race-free force accumulation.

    The cells are cut into slabs of whole cells along one axis.  A listed pair is closer
    than one cell edge at the build, so its two particles lie in the same or adjacent slabs,
    and slabs of the same colour (s mod 3) can add forces to both particles of their rows'
    pairs in parallel.  The slabs are dealt to G groups (one per thread) as contiguous
    ranges balanced by their work (:func:`_deal`): particles plus listed pairs plus
    TOUCH_WEIGHT per pair that touched after the last step (act), since a contact costs
    about ten times a listed pair that only has its distance checked.  A bed that is dense
    at the bottom and sparse above, or whose contacts sit in one region (the first layers
    landing on the floor), so keeps both threads busy, and each thread works on one region
    of the domain.

    The axis is the one with the most cells, unless another axis balances clearly better
    (summed largest group load below 4/5 of it) for BALANCE_GROUPS groups, counting
    particles and listed pairs only (the contact weight only deals the slabs, which
    changes no trajectory).  It never
    depends on G: the axis fixes which contributions to a particle come in which colour
    pass, so the summation order, and with it the trajectory, is the same for any thread
    count; G only decides which thread runs which slab.

    sorder: particle indices grouped by (colour, group), cell order inside a group;
    sgroup[colour * G + g] .. sgroup[colour * G + g + 1]: group g of that colour;
    sgroup[SGROUP_LEN - 1] = G.  scratch: SCRATCH_LEN integers of work space.  Filled
    serially, so the order never depends on the thread count."""
    n = cell_idx.shape[0]
    work = scratch[:SLAB_MAX]
    owner = scratch[SLAB_MAX:2 * SLAB_MAX]
    load = scratch[2 * SLAB_MAX:]
    # slabs along the axis with the most cells (ties: z, then y): the most slabs to deal;
    # another axis only if it balances clearly better (a thin dense layer under sparse
    # particles: across the layer a few slabs hold all the work)
    main = 2
    if n0 > n2 and n0 >= n1:
        main = 0
    elif n1 > n2 and n1 > n0:
        main = 1
    axis = main
    best = _axis_cost(main, cell_idx, cell_of, start, act, n0, n1, n2, p0, p1, work, owner,
                      load)
    for a in range(3):
        if a != main:
            cost = _axis_cost(a, cell_idx, cell_of, start, act, n0, n1, n2, p0, p1, work,
                              owner, load)
            if 5 * cost < 4 * best:
                axis, best = a, cost
    nc, ns = _slab_count(axis, n0, n1, n2, p0, p1)
    _slab_work(axis, nc, ns, cell_idx, cell_of, start, act, TOUCH_WEIGHT, n0, n1, work)
    _deal(work, ns, G, owner, load)
    # counting sort of the particles by group k = colour * G + owner (stable: cell order)
    for k in range(SGROUP_LEN):
        sgroup[k] = 0
    for q in range(n):
        s = _slab(cell_of[cell_idx[q]], axis, n0, n1, ns, nc)
        sgroup[(s % 3) * G + owner[s] + 1] += 1
    for k in range(3 * G):
        sgroup[k + 1] += sgroup[k]
    for q in range(n):
        i = cell_idx[q]
        s = _slab(cell_of[i], axis, n0, n1, ns, nc)
        k = (s % 3) * G + owner[s]
        sorder[sgroup[k]] = i
        sgroup[k] += 1
    for k in range(3 * G, 0, -1):
        sgroup[k] = sgroup[k - 1]
    sgroup[0] = 0
    sgroup[SGROUP_LEN - 1] = G


@njit(cache=True, parallel=True)
def build_wall_lists(x, r, box, periodic, skin, extra, cell_start, cell_idx, cell_of, cpos,
                     prim_kind, prim_par, wcell_start, wcell_idx, glob,
                     wnbr_old, wcnt_old, whist_old, wnbr_new, wcnt_new, whist_new):
    """Rebuild only the wall lists (walls moved, particles did not move enough for the
    pair lists to expire).  Same status codes as :func:`build_lists`."""
    n = x.shape[0]
    if n == 0:
        return 0, 0
    code, need, ng, n0, n1, n2 = _grid_and_bins(x, r, box, periodic, skin, extra, cell_start,
                                                cell_idx, cell_of, cpos, prim_kind, prim_par,
                                                wcell_start, wcell_idx, glob)
    if code != 0:
        return code, need
    for i in prange(n):
        _wall_row(i, i, x, r, skin + extra, cell_of, prim_kind, prim_par, wcell_start,
                  wcell_idx, glob, ng, wnbr_old, wcnt_old, whist_old, wnbr_new, wcnt_new,
                  whist_new)
    wneed = _wall_need(wcnt_new, wnbr_new.shape[0])
    if wneed > 0:
        return 2, wneed
    return 0, 0


@njit(cache=True, inline="always")
def _old_slot(start_old, nbr_old, io, jo):
    """Slot of partner jo in old row io (linear scan of the short sorted row), or -1."""
    for k in range(start_old[io], start_old[io + 1]):
        j = nbr_old[k]
        if j == jo:
            return k
        if j > jo:
            break
    return -1


@njit(cache=True)
def _fill_row(q, x, r, cell_idx, cell_of, cut0, hits, h0, start_old, nbr_old, hist_old,
              act_old, start_new, nbr_new, hist_new, act_new, remap, perm, prim_kind,
              prim_par, wcell_start, wcell_idx, glob, ng, wnbr_old,
              wcnt_old, whist_old, wnbr_new, wcnt_new, whist_new):
    """Sorted row of particle i = cell_idx[q] (offsets already in start_new; its partners
    as the count pass met them in hits[h0:]), history rows and touching flags merged from
    i's old sorted row, and i's wall list.

    remap: the particles were just re-sorted (:func:`sort_particles`) and the old lists
    still use the previous rows, perm[new row] = old row.  Pair (i, j), j > i, is then found
    in the old row of min(perm[i], perm[j]); when that is j's, the pair's orientation is
    reversed and the antisymmetric history (tangential displacement and rolling moment of
    i relative to j) changes sign; sqrt(a) of JKR and the largest overlap are symmetric."""
    H = hist_new.shape[1]
    i = cell_idx[q]
    o0 = start_new[i]
    o1 = start_new[i + 1]
    # insertion into the sorted row
    for k in range(o1 - o0):
        j = hits[h0 + k]
        s = o0 + k
        while s > o0 and nbr_new[s - 1] > j:
            nbr_new[s] = nbr_new[s - 1]
            s -= 1
        nbr_new[s] = j
    io = i
    if remap:
        io = perm[i]
        for k in range(o0, o1):
            jo = perm[nbr_new[k]]
            flip = jo < io
            ko = _old_slot(start_old, nbr_old, jo, io) if flip else _old_slot(start_old, nbr_old,
                                                                              io, jo)
            if ko >= 0:
                act_new[k] = act_old[ko]
                for h in range(H):
                    v = hist_old[ko, h]
                    if flip and h != H_A and h != H_DP:
                        v = -v
                    hist_new[k, h] = v
            else:
                act_new[k] = 0
                for h in range(H):
                    hist_new[k, h] = 0.0
    else:
        ko = start_old[i]
        kend = start_old[i + 1]
        for k in range(o0, o1):
            j = nbr_new[k]
            while ko < kend and nbr_old[ko] < j:
                ko += 1
            if ko < kend and nbr_old[ko] == j:
                act_new[k] = act_old[ko]
                for h in range(H):
                    hist_new[k, h] = hist_old[ko, h]
            else:
                act_new[k] = 0
                for h in range(H):
                    hist_new[k, h] = 0.0
    _wall_row(i, io, x, r, cut0, cell_of, prim_kind, prim_par, wcell_start, wcell_idx, glob,
              ng, wnbr_old, wcnt_old, whist_old, wnbr_new, wcnt_new, whist_new)


@njit(cache=True, parallel=True)
def build_lists(x, r, box, periodic, skin, extra, cell_start, cell_idx, cell_of, cpos,
                start_old, nbr_old, hist_old, act_old, start_new, nbr_new, hist_new, act_new,
                groups, sorder, sgroup, scratch, hits, remap, perm, prim_kind, prim_par,
                wcell_start, wcell_idx, glob, wnbr_old, wcnt_old, whist_old, wnbr_new,
                wcnt_new, whist_new):
    """Rebuild the half lists (CSR), the slab groups (:func:`_slabs`, ``groups`` per
    colour: one per thread) and the wall lists into *_new.

    History rows and touching flags are copied from *_old (``remap``: the old lists use
    the rows before a spatial sort, perm[new row] = old row; :func:`_fill_row`).  ``hits``:
    work space, hits.shape[0] // NBLK_GROUPS partners per block group, in which the count
    pass keeps the partners it finds so that the fill pass need not look for them again.
    Every group has a stretch as long as the busiest group's, so ``hits`` needs
    NBLK_GROUPS times the busiest group's partners: the number of pairs where the groups
    hold as many each (a bed of even packing), up to NBLK_GROUPS times the pairs where
    a few groups hold most of them (a dense cluster among sparse spheres: 42,744 entries
    for 1,381 pairs, 31 per pair, with 1,964 spheres).
    Returns (status, need): status 0 ok, 1 pair buffers too short (need = pairs), 2 wall
    list too short (need = width), 3 cell buffer too short (need = cells), 5 triangle bins
    too short (need = entries), 7 ``hits`` too short (need = NBLK_GROUPS x the busiest
    block group's partners).
    """
    n = x.shape[0]
    P = nbr_new.shape[0]
    if n == 0:
        start_new[0] = 0
        for k in range(SGROUP_LEN):
            sgroup[k] = 0
        sgroup[SGROUP_LEN - 1] = 1
        return 0, 0
    code, need, ng, n0, n1, n2 = _grid_and_bins(x, r, box, periodic, skin, extra, cell_start,
                                                cell_idx, cell_of, cpos, prim_kind, prim_par,
                                                wcell_start, wcell_idx, glob)
    if code != 0:
        return code, need
    cut0 = skin + extra
    cap = hits.shape[0] // NBLK_GROUPS
    # pass 1: row lengths -> offsets (particles taken in cell order, in blocks: neighbouring
    # particles are processed together and their candidates stay in cache); the partners
    # of block group c are kept one row after another in hits[c * cap:(c + 1) * cap]
    bs = block_size(n)
    nblk = (n + bs - 1) // bs
    for c in prange(NBLK_GROUPS):
        h = c * cap
        for blk in range(c, nblk, NBLK_GROUPS):
            for q in range(blk * bs, min(n, blk * bs + bs)):
                cnt = _row(q, cpos, cell_idx, cell_of, box, periodic, cut0, cell_start, n0, n1,
                           n2, hits, h, (c + 1) * cap)
                start_new[cell_idx[q] + 1] = cnt
                h += cnt
    # partners of each block group (serial: a sum over the rows in the same order)
    most = 0
    for c in range(NBLK_GROUPS):
        m = 0
        for blk in range(c, nblk, NBLK_GROUPS):
            for q in range(blk * bs, min(n, blk * bs + bs)):
                m += start_new[cell_idx[q] + 1]
        most = max(most, m)
    start_new[0] = 0
    for i in range(n):
        start_new[i + 1] += start_new[i]
    if start_new[n] > P:
        return 1, start_new[n]
    if most > cap:
        return 7, most * NBLK_GROUPS
    # pass 2: sorted rows, history merged from the old sorted rows; wall lists
    for c in prange(NBLK_GROUPS):
        h = c * cap
        for blk in range(c, nblk, NBLK_GROUPS):
            for q in range(blk * bs, min(n, blk * bs + bs)):
                i = cell_idx[q]
                _fill_row(q, x, r, cell_idx, cell_of, cut0, hits, h, start_old, nbr_old,
                          hist_old, act_old, start_new, nbr_new, hist_new, act_new, remap,
                          perm, prim_kind, prim_par, wcell_start, wcell_idx, glob, ng,
                          wnbr_old, wcnt_old, whist_old, wnbr_new, wcnt_new, whist_new)
                h += start_new[i + 1] - start_new[i]
    wneed = _wall_need(wcnt_new, wnbr_new.shape[0])
    if wneed > 0:
        return 2, wneed
    _slabs(cell_idx, cell_of, start_new, act_new, n0, n1, n2, periodic[0], periodic[1],
           min(max(groups, 1), GROUPS_MAX), sorder, sgroup, scratch)
    return 0, 0


# ---------------------------------------------------------------- spatial sort
@njit(cache=True)
def _permute2(a, perm, buf, inverse):
    """Rows of a 2-D array reordered: a[q] = old a[perm[q]] (``inverse``: undone)."""
    n, w = a.shape
    for q in range(n):
        for c in range(w):
            if inverse:
                buf[perm[q], c] = a[q, c]
            else:
                buf[q, c] = a[perm[q], c]
    for q in range(n):
        for c in range(w):
            a[q, c] = buf[q, c]


@njit(cache=True)
def _permute1(a, perm, buf, inverse):
    """1-D version of :func:`_permute2` (``buf`` of a's dtype)."""
    n = a.shape[0]
    for q in range(n):
        if inverse:
            buf[perm[q]] = a[q]
        else:
            buf[q] = a[perm[q]]
    for q in range(n):
        a[q] = buf[q]


@njit(cache=True)
def sort_particles(inverse, x, v, om, f, t, r, m, inv_m, inv_i, mat, disp, ovr, pid, xr, vw,
                   box, periodic, skin, extra, cell_start, cell_idx, cell_of, cpos, perm,
                   fbuf, ibuf):
    """Spatial sort: the particle rows of every per-particle array reordered into cell order
    (x fastest, then y, then z; the order of :func:`_grid`), so that particles close in
    space are close in memory and a list row's partners share cache lines (LAMMPS
    ``atom_modify sort``).  perm[new row] = old row; ``pid`` (insertion ids) follows the
    rows.  The lists still use the old rows: the next :func:`build_lists` remaps them
    (``remap``).  ``inverse``: undo the last sort with the same perm (a build that has to
    stop for larger buffers restores the old rows).

    Returns (ok, need): ok False when cell_start is too short (need cells, nothing moved).
    """
    n = x.shape[0]
    if not inverse:
        ok, rmax, lo0, cs0, n0, lo1, cs1, n1, lo2, cs2, n2, _ = _grid(
            x, r, box, periodic, skin, extra, cell_start, cell_idx, cell_of, cpos)
        if not ok:
            return False, n0 * n1 * n2 + 1
        for q in range(n):
            perm[q] = cell_idx[q]
    _permute2(x, perm, fbuf, inverse)
    _permute2(v, perm, fbuf, inverse)
    _permute2(om, perm, fbuf, inverse)
    _permute2(f, perm, fbuf, inverse)
    _permute2(t, perm, fbuf, inverse)
    _permute2(disp, perm, fbuf, inverse)
    _permute2(xr, perm, fbuf, inverse)
    _permute2(vw, perm, fbuf, inverse)
    fb = fbuf[:, 0]
    _permute1(r, perm, fb, inverse)
    _permute1(m, perm, fb, inverse)
    _permute1(inv_m, perm, fb, inverse)
    _permute1(inv_i, perm, fb, inverse)
    _permute1(ovr, perm, fb, inverse)
    _permute1(mat, perm, ibuf, inverse)
    _permute1(pid, perm, ibuf, inverse)
    return True, 0
