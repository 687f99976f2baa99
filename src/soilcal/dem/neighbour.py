"""Verlet neighbour lists built from a cell list, with contact history remapping.

Cell list: cubic-ish cells of edge >= 2 R_max + skin + s_c (s_c: largest JKR separation
range), particles counting-sorted by cell index (x fastest).  Periodic dimensions (x, y) use
the box and the minimum-image convention, so the box must be at least two cells wide.

Verlet list: for every particle i the full list of partners j (both i-j and j-i are stored)
with |x_i - x_j| < R_i + R_j + skin + s_c.  The list is valid while no particle moved more
than skin/2 since the build (then no pair can close the skin) and no wall moved more than
skin/2.  Each list slot owns a contact-history row (tangential spring, rolling spring,
touching flag), keyed by partner id: on rebuild every surviving pair copies its row from the
old list, so history is never lost while two particles stay within the cutoff.

Walls: each particle also lists the wall primitives within R_i + skin + s_c.

Everything runs in parallel over particles; each particle writes only its own rows.
"""

from __future__ import annotations

import math

from numba import njit, prange

from soilcal.dem.walls import prim_closest


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


@njit(cache=True)
def build_lists(x, r, box, periodic, skin, extra, cell_start, cell_idx, cell_of,
                nbr_old, cnt_old, hist_old, nbr_new, cnt_new, hist_new,
                prim_kind, prim_par, wnbr_old, wcnt_old, whist_old, wnbr_new, wcnt_new, whist_new):
    """Rebuild particle and wall lists into *_new, copying history from *_old.

    Returns (status, need): status 0 ok, 1 particle list too short (need = required width),
    2 wall list too short, 3 cell buffer too short (need = cells).
    """
    n = x.shape[0]
    K = nbr_new.shape[1]
    KW = wnbr_new.shape[1]
    H = hist_new.shape[2]
    if n == 0:
        return 0, 0
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
    ncell = n0 * n1 * n2
    if ncell + 1 > cell_start.shape[0]:
        return 3, ncell + 1
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
        cell_idx[cell_start[c + 1]] = i
        cell_start[c + 1] += 1
    L0 = box[1] - box[0]
    L1 = box[3] - box[2]
    h0 = 0.5 * L0
    h1 = 0.5 * L1
    p0 = periodic[0]
    p1 = periodic[1]
    need = 0
    wneed = 0
    for i in prange(n):
        c = cell_of[i]
        cx = c % n0
        cy = (c // n0) % n1
        cz = c // (n0 * n1)
        xi, yi, zi, ri = x[i, 0], x[i, 1], x[i, 2], r[i]
        cnt = 0
        a0, b0 = _range(cx, n0, p0)
        a1, b1 = _range(cy, n1, p1)
        a2, b2 = _range(cz, n2, False)
        for dz in range(a2, b2 + 1):
            zz = cz + dz
            for dy in range(a1, b1 + 1):
                yy = cy + dy
                if yy < 0:
                    yy += n1
                elif yy >= n1:
                    yy -= n1
                for dx in range(a0, b0 + 1):
                    xx = cx + dx
                    if xx < 0:
                        xx += n0
                    elif xx >= n0:
                        xx -= n0
                    cc = xx + n0 * (yy + n1 * zz)
                    for q in range(cell_start[cc], cell_start[cc + 1]):
                        j = cell_idx[q]
                        if j == i:
                            continue
                        ddx = min_image(xi - x[j, 0], p0, h0, L0)
                        ddy = min_image(yi - x[j, 1], p1, h1, L1)
                        ddz = zi - x[j, 2]
                        cut = ri + r[j] + skin + extra
                        if ddx * ddx + ddy * ddy + ddz * ddz < cut * cut:
                            if cnt < K:
                                nbr_new[i, cnt] = j
                                for h in range(H):
                                    hist_new[i, cnt, h] = 0.0
                                for k in range(cnt_old[i]):
                                    if nbr_old[i, k] == j:
                                        for h in range(H):
                                            hist_new[i, cnt, h] = hist_old[i, k, h]
                                        break
                            cnt += 1
        if cnt > K:
            need = max(need, cnt)  # noqa: numba max-reduction
        cnt_new[i] = min(cnt, K)
        # walls
        wc = 0
        for p in range(prim_kind.shape[0]):
            d = prim_closest(prim_kind[p], prim_par, p, xi, yi, zi)[0]
            if d < ri + skin + extra:
                if wc < KW:
                    wnbr_new[i, wc] = p
                    for h in range(H):
                        whist_new[i, wc, h] = 0.0
                    for k in range(wcnt_old[i]):
                        if wnbr_old[i, k] == p:
                            for h in range(H):
                                whist_new[i, wc, h] = whist_old[i, k, h]
                            break
                wc += 1
        if wc > KW:
            wneed = max(wneed, wc)
        wcnt_new[i] = min(wc, KW)
    if need > 0:
        return 1, need
    if wneed > 0:
        return 2, wneed
    return 0, 0
