"""Time loop: velocity Verlet for translation and rotation of spheres, all steps in one njit call.

Per step (LIGGGHTS ``fix nve/sphere`` scheme)::

    v += F/m dt/2,  omega += T/I dt/2,  x += v dt          (kick-drift, periodic wrap)
    walls move by their rigid motion;  lists rebuilt if max |dx| > skin/2
    F, T from gravity and contacts                          (three pair passes, wall pass)
    v += F/m dt/2,  omega += T/I dt/2                       (kick, fused with the wall pass)

I = 2/5 m R^2 for a solid sphere.  Fixed particles have 1/m = 1/I = 0.

Forces are evaluated in race-free parallel passes:

* the kick-drift pass, after using the previous forces, resets every particle's force to its
  weight and its torque, largest overlap and ``bounded`` rolling resistance to zero;
* three pair passes, one per slab colour: the list build groups the particles into slabs of
  whole cells (:func:`soilcal.dem.neighbour._slabs`) so that both particles of a listed pair
  lie in the same or adjacent slabs; the slabs of one colour (s mod 3) share no particle and
  are dealt to one group per thread, balanced by their work; each group evaluates its
  particles' rows (pairs j > i, once each, LIGGGHTS ``newton on``) and adds the force and
  torques to both particles directly;
* the wall pass: every particle evaluates its wall contacts and kicks.

The kick-drift pass also packs (x, y, z, R) and (v, omega, 1/m, material) per particle into
two contiguous rows, so the pair pass reads one partner's data from two cache lines.  The
order in which contributions are added to a particle is fixed by the lists and the slabs,
never by the threads, so trajectories do not depend on the thread count.  Wall reactions
are stored per (particle, wall slot) and summed per wall serially after the wall pass, so
wall force and torque are race free too.

Stop codes (status[0]): 0 finished, 1 pair buffers too short, 2 wall list too short,
3 cell buffer too short, 4 blow-up (status[1] step, status[2] particle, reason in status[3]:
1 overlap above the limit, 2 non-finite state; 3 and 4 the same in the state a run starts
from, before any step), 5 settled (status[1] steps done), 6 triangle
bins too short, 7 the list build's partner work space (``hits``) too short; for 1, 2, 3,
6 and 7 status[3] is the length needed (:func:`soilcal.dem.neighbour.build_lists`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from soilcal.dem.contact import H_MR, H_SIZE, contact_force
from soilcal.dem.neighbour import (NBLK_GROUPS, SGROUP_LEN, block_size, build_lists,
                                   build_wall_lists, min_image, sort_particles)
from soilcal.dem.walls import CYLINDER, PLANE, move_walls, prim_closest

(DONE, NEED_PAIRS, NEED_KW, NEED_CELLS, BLOWUP, SETTLED, NEED_WBINS,
 NEED_HITS) = 0, 1, 2, 3, 4, 5, 6, 7


# near list (run_loop): pairs within NEAR_SKIN x skin (+ the JKR separation range) of
# contact are checked every step, the others again once a particle has moved NEAR_MOVE x
# that far (NEAR_MOVE < 1/2: two spheres closing in on each other cannot close the gap)
NEAR_SKIN = 0.125
NEAR_MOVE = 0.49


# below this many particles a step is shorter than waking the worker threads three times
# (milliseconds when other processes hold the cores): Simulation.run runs such systems on
# one thread (results do not depend on the thread count)
PARALLEL_MIN = 1024


# contact kernels: multiply-adds fused into FMA instructions (a fixed property of the
# compiled code, so results still do not depend on the thread count); no other fast-math
# flag, since NaN and infinity must survive for the blow-up check
CONTACT_MATH = {"contract"}


@njit(cache=True, inline="always")
def _cover(i, k, nwc, p, feat, cx, cy, cz, tol, ri, xi, yi, zi, fk, wnbr, prim_kind,
           prim_wall, prim_par, wall_vel, wall_omega):
    """The wall slot whose primitive counts the contact of particle i with primitive p (its
    k-th wall slot; closest point c, feature ``feat``), or -1 when p counts it itself
    (walls.py, "One contact per touch"): the slot of another primitive q, of any wall, on
    which c lies, when q's own closest point does not lie on p (q is then strictly closer:
    the edge or vertex of a flat or convex surface next to the face or edge that holds it, or
    the edge of a triangle the sphere has moved off), or lies on p too (the same point, to
    rounding) and q's is a face where p's is not, or an edge where p's is a vertex, or the
    same feature and q ranks higher: of one wall the closer one, then the later; of two walls
    a moving wall above a fixed one, then a bounded primitive above an infinite plane, then
    the later primitive (walls.py, "Which wall counts").  ``tol``: :func:`_same_tol`, for a q
    of the same wall as for one of another (the patches of one STL file need not share their
    vertices: a seam whose two sides differ by float noise is one surface).  ``fk``: the
    slot of the particle's first face contact (-1: none), tried first (a sphere on a face: its
    neighbours' edges lie on it)."""
    kp = prim_kind[p]
    wp = prim_wall[p]
    for step in range(nwc + 1):
        kk = fk if step == 0 else step - 1
        if kk < 0 or kk == k or (step > 0 and kk == fk):
            continue
        pp = wnbr[kk, i]
        kq = prim_kind[pp]
        if abs(prim_closest(kq, prim_par, pp, cx, cy, cz)[0]) > tol:
            continue  # c is not on q
        o8 = prim_closest(kq, prim_par, pp, xi, yi, zi)
        if abs(prim_closest(kp, prim_par, p, o8[4], o8[5], o8[6])[0]) > tol:
            return kk
        if o8[7] < feat:
            return kk
        if o8[7] == feat:
            if prim_wall[pp] == wp:
                # one mesh: the closer of the two counts (the true closest point of the
                # surface, to rounding), the later one where they are as close
                dp = prim_closest(kp, prim_par, p, xi, yi, zi)[0]
                if o8[0] < dp:
                    return kk
                if o8[0] > dp:
                    continue
            mq = _moving(prim_wall[pp], wall_vel, wall_omega)
            mp = _moving(wp, wall_vel, wall_omega)
            if mq != mp:
                if mq:
                    return kk
                continue
            if kq != PLANE and kp == PLANE:
                return kk
            if (kq == PLANE) == (kp == PLANE) and pp > p:
                return kk
    return -1


@njit(cache=True, inline="always")
def _moving(w, wall_vel, wall_omega):
    """Whether wall ``w`` moves (a velocity or an angular velocity set): a belt or turntable
    lying on a fixed floor carries what rests on it, whichever was added first."""
    for d in range(3):
        if wall_vel[w, d] != 0.0 or wall_omega[w, d] != 0.0:
            return True
    return False


# two face contacts whose normals agree this closely (cos, 0.008 deg) may be one surface
# (coplanar walls); a 0.1 deg crease is two
PARALLEL_COS = 1.0 - 1e-8


@njit(cache=True, inline="always")
def _same_tol(ri, xi, yi, zi):
    """Distance within which a point counts as lying on a primitive (``_cover``): 2e-4 of the
    radius (a gap or step between two walls' surfaces that changes the overlap by far less
    than a contact's, and what CAD exports leave between tiles), or 4 float32 ulps of the
    coordinates (4 * 2^-23 |x|: STL vertices are float32) if that is more."""
    return max(2e-4 * ri, 4.8e-7 * max(abs(xi), abs(yi), abs(zi)))


@njit(cache=True, parallel=True, fastmath=CONTACT_MATH)
def pair_forces(colour, xr, vw, pair, codes, box, periodic, dt, start, nbr, hist, act,
                sorder, sgroup, f, t, ovr, mroll, near, ncnt, mode, cutn):
    """Pair pass of one colour: the slab groups of that colour in parallel (one per
    thread); each evaluates the listed pairs of its particles' rows and adds the force and
    torques to both particles (f, t; ovr: largest overlap of each particle; mroll: the
    ``bounded`` rolling resistance mu_r |F_n| c of each particle).  Slabs of one
    colour share no particle (:func:`soilcal.dem.neighbour._slabs`), so the writes never
    race.

    ``mode`` 0: every listed pair; 1: every listed pair, and the near list written: the
    slots k of row i whose pair touches or lies closer than R_i + R_j + ``cutn``, in row
    order, to near[start[i]:start[i] + ncnt[i]]; 2: the near list's pairs only
    (:func:`run_loop`, "Near list")."""
    L0 = box[1] - box[0]
    L1 = box[3] - box[2]
    h0 = 0.5 * L0
    h1 = 0.5 * L1
    p0 = periodic[0]
    p1 = periodic[1]
    G = sgroup[SGROUP_LEN - 1]
    lever_r = codes[14] == 1
    # JKR across a gap (``jkr_approach: gap``): separated listed pairs go to the contact law
    gap = codes[15] == 1 and codes[4] == 1
    for g in prange(G):
        kg = colour * G + g
        for q in range(sgroup[kg], sgroup[kg + 1]):
            i = sorder[q]
            xi, yi, zi, ri = xr[i, 0], xr[i, 1], xr[i, 2], xr[i, 3]
            fxi = 0.0
            fyi = 0.0
            fzi = 0.0
            txi = 0.0
            tyi = 0.0
            tzi = 0.0
            dmax = ovr[i]
            mri = 0.0
            k0 = start[i]
            m = k0
            for kk in range(k0, k0 + ncnt[i] if mode == 2 else start[i + 1]):
                # slot and partner as unsigned integers: indices known not to be negative
                # need no wrap-around code (Numba's for signed ones, a few instructions at
                # each of the pair's dozen array accesses)
                k = np.uint64(near[kk] if mode == 2 else kk)
                j = np.uint64(nbr[k])
                dx = min_image(xi - xr[j, 0], p0, h0, L0)
                dy = min_image(yi - xr[j, 1], p1, h1, L1)
                dz = zi - xr[j, 2]
                rj = xr[j, 3]
                rs = ri + rj
                d2 = dx * dx + dy * dy + dz * dz
                touching = act[k] != 0
                if mode == 1:
                    cn = rs + cutn
                    near[m] = k
                    m += (not d2 >= cn * cn) | touching
                if d2 >= rs * rs and not touching and not gap:
                    continue
                ims = vw[i, 6] + vw[j, 6]
                if ims == 0.0:
                    act[k] = 0
                    continue
                d = math.sqrt(d2)
                invd = 1.0 / d
                nx = dx * invd
                ny = dy * invd
                nz = dz * invd
                delta = rs - d
                ci = ri - 0.5 * delta
                cj = rj - 0.5 * delta
                # the contact point's velocity from the spins with the levers c (or the
                # radii: ``contact_lever: radius``, contact.py)
                li = ri if lever_r else ci
                lj = rj if lever_r else cj
                wxi, wyi, wzi = vw[i, 3], vw[i, 4], vw[i, 5]
                wxj, wyj, wzj = vw[j, 3], vw[j, 4], vw[j, 5]
                ax = li * wxi + lj * wxj
                ay = li * wyi + lj * wyj
                az = li * wzi + lj * wzj
                rvx = vw[i, 0] - vw[j, 0] - (ay * nz - az * ny)
                rvy = vw[i, 1] - vw[j, 1] - (az * nx - ax * nz)
                rvz = vw[i, 2] - vw[j, 2] - (ax * ny - ay * nx)
                on, fx, fy, fz, tix, tiy, tiz, tjx, tjy, tjz, mr = contact_force(
                    codes, pair, int(vw[i, 7]), int(vw[j, 7]), delta, nx, ny, nz,
                    rvx, rvy, rvz, wxi - wxj, wyi - wyj, wzi - wzj,
                    ci, cj, ri * rj / rs, 1.0 / ims, dt, touching, hist, k)
                if on:
                    act[k] = 1
                    if mr > 0.0:
                        mri += mr * ci
                        mroll[j] += mr * cj
                    fxi += fx
                    fyi += fy
                    fzi += fz
                    txi += tix
                    tyi += tiy
                    tzi += tiz
                    dmax = max(dmax, delta)
                    # Newton's third law: the opposite force on j
                    f[j, 0] -= fx
                    f[j, 1] -= fy
                    f[j, 2] -= fz
                    t[j, 0] += tjx
                    t[j, 1] += tjy
                    t[j, 2] += tjz
                    if delta > ovr[j]:
                        ovr[j] = delta
                else:
                    act[k] = 0
            f[i, 0] += fxi
            f[i, 1] += fyi
            f[i, 2] += fzi
            t[i, 0] += txi
            t[i, 1] += tyi
            t[i, 2] += tzi
            ovr[i] = dmax
            mroll[i] += mri
            if mode == 1:
                ncnt[i] = m - k0


@njit(cache=True, parallel=True, fastmath=CONTACT_MATH)
def gather(x, v, om, r, inv_m, inv_i, mat, f, t, ovr, peak, mroll, dt, kick, max_ovr, pair, codes,
           prim_kind, prim_wall, prim_mat, prim_par, wall_vel, wall_omega, wall_centre,
           wnbr, wcnt, whist, wslot):
    """Wall pass: per particle, the pair sums (f, t, ovr, mroll) + wall contacts; the
    ``bounded`` rolling torque (contact.py); then the closing kick if ``kick``.  Returns the
    number of particles with an overlap above max_ovr (of their radius) or a non-finite
    velocity.  ``peak[i]`` keeps the largest overlap of row i (of its radius) seen here."""
    n = x.shape[0]
    h = 0.5 * dt
    nbad = 0
    bounded = codes[3] == 3
    # rolling against a wall: the rotation relative to the wall's (rw = 1), or the sphere's
    # own (rw = 0; ``rolling_wall``, contact.py)
    rw = 0.0 if codes[9] == 1 else 1.0
    lever_r = codes[14] == 1  # a wall contact's lever: the radius (``contact_lever``)
    gap = codes[15] == 1 and codes[4] == 1  # JKR across a gap (``jkr_approach``)
    curved = codes[16] == 1  # an inner cylinder's curvature in R* (``wall_curvature``)
    bs = block_size(n)
    nblk = (n + bs - 1) // bs
    for c in prange(NBLK_GROUPS):
        for blk in range(c, nblk, NBLK_GROUPS):
            for i in range(blk * bs, min(n, blk * bs + bs)):
                xi, yi, zi, ri = x[i, 0], x[i, 1], x[i, 2], r[i]
                vxi, vyi, vzi = v[i, 0], v[i, 1], v[i, 2]
                wxi, wyi, wzi = om[i, 0], om[i, 1], om[i, 2]
                imi = inv_m[i]
                mi = mat[i]
                fx = f[i, 0]
                fy = f[i, 1]
                fz = f[i, 2]
                tx = t[i, 0]
                ty = t[i, 1]
                tz = t[i, 2]
                mo = ovr[i] / ri
                mres = mroll[i]
                fk = -1  # the slot of the first face contact
                nwc = wcnt[i]
                moved = False  # a contact that has touched is on an edge, vertex or rim
                # face contacts, of every wall and kind: two of them may be one (coplanar
                # faces of two walls) only if their normals are parallel; the first two
                # directions are kept, a fourth face counts as parallel (the full check)
                tol = _same_tol(ri, xi, yi, zi)
                coplanar = False
                nref = 0
                ax = ay = az = bx = by = bz = 0.0
                touched = False
                for k in range(nwc if nwc > 1 else 0):  # one primitive: nothing to share
                    p = wnbr[k, i]
                    r8 = prim_closest(prim_kind[p], prim_par, p, xi, yi, zi)
                    # kept for the force loop below (the slot's reaction is written after)
                    wslot[k, i, 0] = r8[0]
                    wslot[k, i, 1] = r8[1]
                    wslot[k, i, 2] = r8[2]
                    wslot[k, i, 3] = r8[3]
                    wslot[k, i, 4] = r8[7]
                    if r8[7] == 0 and r8[0] < ri:
                        if fk < 0:
                            fk = k
                        n1, n2, n3 = r8[1], r8[2], r8[3]
                        if nref > 0 and n1 * ax + n2 * ay + n3 * az > PARALLEL_COS:
                            coplanar = True
                        elif nref > 1 and n1 * bx + n2 * by + n3 * bz > PARALLEL_COS:
                            coplanar = True
                        elif nref > 2:
                            coplanar = True
                        elif nref == 0:
                            ax, ay, az = n1, n2, n3
                        elif nref == 1:
                            bx, by, bz = n1, n2, n3
                        nref += 1
                    if whist[k * n + i, H_SIZE - 1] != 0.0:
                        touched = True
                        if r8[7] != 0:
                            moved = True
                moved = moved or (touched and coplanar)
                # a contact that passes from one primitive to the next (over the edge or
                # vertex shared by two triangles, or from a face onto a coplanar face of
                # another wall) is one contact: its history (the tangential spring, the JKR
                # neck, ...) passes to the primitive that counts it now, if that one has none
                for _ in range(nwc if moved and imi != 0.0 else 0):
                    moved = False
                    for k in range(nwc):
                        p = wnbr[k, i]
                        row = k * n + i
                        if whist[row, H_SIZE - 1] == 0.0:
                            continue
                        r8 = prim_closest(prim_kind[p], prim_par, p, xi, yi, zi)
                        if r8[7] == 0 and not coplanar:
                            continue
                        kk = _cover(i, k, nwc, p, r8[7], r8[4], r8[5], r8[6], tol, ri, xi, yi,
                                    zi, fk, wnbr, prim_kind, prim_wall, prim_par, wall_vel, wall_omega)
                        if kk >= 0 and whist[kk * n + i, H_SIZE - 1] == 0.0:
                            for q in range(H_SIZE):
                                whist[kk * n + i, q] = whist[row, q]
                                whist[row, q] = 0.0
                            moved = True
                    if not moved:
                        break
                for k in range(nwc):
                    p = wnbr[k, i]
                    if nwc > 1:  # the closest point of the first loop: c = x - dist n
                        dist = wslot[k, i, 0]
                        nx, ny, nz = wslot[k, i, 1], wslot[k, i, 2], wslot[k, i, 3]
                        feat = int(wslot[k, i, 4])
                        cx, cy, cz = xi - dist * nx, yi - dist * ny, zi - dist * nz
                    else:
                        dist, nx, ny, nz, cx, cy, cz, feat = prim_closest(
                            prim_kind[p], prim_par, p, xi, yi, zi)
                    for q in range(6):
                        wslot[k, i, q] = 0.0
                    delta = ri - dist
                    row = k * n + i
                    touching = whist[row, H_SIZE - 1] != 0.0
                    if delta <= 0.0 and not touching and not gap:
                        continue
                    if imi == 0.0:
                        continue
                    if feat != 0 or coplanar:
                        if _cover(i, k, nwc, p, feat, cx, cy, cz, tol, ri, xi, yi, zi, fk,
                                  wnbr, prim_kind, prim_wall, prim_par, wall_vel, wall_omega) >= 0:
                            for q in range(H_SIZE):
                                whist[row, q] = 0.0
                            continue
                    w = prim_wall[p]
                    ci = ri if lever_r else ri - 0.5 * delta
                    ox, oy, oz = wall_omega[w, 0], wall_omega[w, 1], wall_omega[w, 2]
                    qx = cx - wall_centre[w, 0]
                    qy = cy - wall_centre[w, 1]
                    qz = cz - wall_centre[w, 2]
                    vwx = wall_vel[w, 0] + oy * qz - oz * qy
                    vwy = wall_vel[w, 1] + oz * qx - ox * qz
                    vwz = wall_vel[w, 2] + ox * qy - oy * qx
                    rvx = vxi - vwx - ci * (wyi * nz - wzi * ny)
                    rvy = vyi - vwy - ci * (wzi * nx - wxi * nz)
                    rvz = vzi - vwz - ci * (wxi * ny - wyi * nx)
                    rs = ri
                    if curved and prim_kind[p] == CYLINDER and prim_par[p, 8] != 0.0:
                        rc = -2.0 * prim_par[p, 6]  # LAMMPS's contact radius of the face
                        rs = ri * rc / (ri + rc)
                    on, cfx, cfy, cfz, ctx, cty, ctz, _, _, _, mr = contact_force(
                        codes, pair, mi, prim_mat[p], delta, nx, ny, nz, rvx, rvy, rvz,
                        wxi - rw * ox, wyi - rw * oy, wzi - rw * oz, ci, 0.0, rs, 1.0 / imi,
                        dt if kick else -dt, touching, whist, row)
                    # the last history slot of a wall row is its touching flag
                    whist[row, H_SIZE - 1] = 1.0 if on else 0.0
                    if on:
                        if bounded:
                            # this contact's resistance, for its share of the reaction below
                            whist[row, H_MR] = mr * ci
                            mres += mr * ci
                        fx += cfx
                        fy += cfy
                        fz += cfz
                        tx += ctx
                        ty += cty
                        tz += ctz
                        if delta > mo * ri:
                            mo = delta / ri
                        # reaction on the wall: force -F, torque about the wall centre
                        # -(x_i - c_w) x F - T_i  (conserves angular momentum exactly; the
                        # ``bounded`` rolling torque is added below, by shares)
                        px = xi - wall_centre[w, 0]
                        py = yi - wall_centre[w, 1]
                        pz = zi - wall_centre[w, 2]
                        wslot[k, i, 0] = -cfx
                        wslot[k, i, 1] = -cfy
                        wslot[k, i, 2] = -cfz
                        wslot[k, i, 3] = -(py * cfz - pz * cfy) - ctx
                        wslot[k, i, 4] = -(pz * cfx - px * cfz) - cty
                        wslot[k, i, 5] = -(px * cfy - py * cfx) - ctz
                iinv = inv_i[i]
                if bounded and mres > 0.0 and iinv > 0.0:
                    # rotation at the next force evaluation without the resistance: the
                    # closing and the next opening kick apply t h / I each (the first
                    # evaluation, without a closing kick, only the opening one)
                    hb = dt if kick else h
                    sx = wxi + tx * iinv * hb
                    sy = wyi + ty * iinv * hb
                    sz = wzi + tz * iinv * hb
                    sn = math.sqrt(sx * sx + sy * sy + sz * sz)
                    if sn > 0.0:
                        mb = min(mres, sn / (iinv * hb)) / sn
                        rx = -mb * sx
                        ry = -mb * sy
                        rz = -mb * sz
                        tx += rx
                        ty += ry
                        tz += rz
                        for k in range(nwc):
                            row = k * n + i
                            if whist[row, H_SIZE - 1] != 0.0:
                                sh = whist[row, H_MR] / mres
                                wslot[k, i, 3] -= sh * rx
                                wslot[k, i, 4] -= sh * ry
                                wslot[k, i, 5] -= sh * rz
                f[i, 0] = fx
                f[i, 1] = fy
                f[i, 2] = fz
                t[i, 0] = tx
                t[i, 1] = ty
                t[i, 2] = tz
                ovr[i] = mo
                if mo > peak[i]:
                    peak[i] = mo
                if kick:
                    a = imi * h
                    b = iinv * h
                    vxi += fx * a
                    vyi += fy * a
                    vzi += fz * a
                    v[i, 0] = vxi
                    v[i, 1] = vyi
                    v[i, 2] = vzi
                    om[i, 0] = wxi + tx * b
                    om[i, 1] = wyi + ty * b
                    om[i, 2] = wzi + tz * b
                bad = 0
                if not (mo <= max_ovr):
                    bad = 1
                if not (abs(vxi) + abs(vyi) + abs(vzi) < math.inf):
                    bad = 1
                nbad += bad
    return nbad


@njit(cache=True)
def reduce_wall_forces(wcnt, wnbr, wslot, prim_wall, wall_force, wall_torque):
    wall_force[:, :] = 0.0
    wall_torque[:, :] = 0.0
    for i in range(wcnt.shape[0]):
        for k in range(wcnt[i]):
            w = prim_wall[wnbr[k, i]]
            for q in range(3):
                wall_force[w, q] += wslot[k, i, q]
                wall_torque[w, q] += wslot[k, i, 3 + q]


@njit(cache=True, parallel=True)
def _kick_drift(x, v, om, f, t, r, m, inv_m, inv_i, mat, disp, ovr, mroll, xr, vw, gravity,
                dt, box, periodic, skin2, drift, dref, near2):
    """Opening kick and drift (if ``drift``), periodic wrap, displacement since the last
    list build; packs (x, R) and (v, omega, 1/m, material) rows for the pair pass and resets
    the force to the weight, torque, largest overlap and rolling resistance to zero.  Returns
    the number of particles that moved more than half the skin since the list build, and
    the number whose displacement since the near list was written (``dref``: disp then)
    exceeds sqrt(near2)."""
    n = x.shape[0]
    h = 0.5 * dt if drift else 0.0
    nfar = 0
    nnear = 0
    for i in prange(n):
        a = inv_m[i] * h
        b = inv_i[i] * h
        far = 0
        s2 = 0.0
        e2 = 0.0
        for q in range(3):
            v[i, q] += f[i, q] * a
            om[i, q] += t[i, q] * b
            if drift:
                dq = v[i, q] * dt
                x[i, q] += dq
                disp[i, q] += dq
            s2 += disp[i, q] * disp[i, q]
            e = disp[i, q] - dref[i, q]
            e2 += e * e
        if s2 > skin2:
            far = 1
        nnear += 1 if not e2 <= near2 else 0
        for q in range(2):
            if periodic[q]:
                lo = box[2 * q]
                L = box[2 * q + 1] - lo
                if x[i, q] < lo:
                    x[i, q] += L
                elif x[i, q] >= box[2 * q + 1]:
                    x[i, q] -= L
        for q in range(3):
            xr[i, q] = x[i, q]
            vw[i, q] = v[i, q]
            vw[i, 3 + q] = om[i, q]
        xr[i, 3] = r[i]
        vw[i, 6] = inv_m[i]
        vw[i, 7] = mat[i]
        for q in range(3):
            f[i, q] = m[i] * gravity[q]
            t[i, q] = 0.0
        ovr[i] = 0.0
        mroll[i] = 0.0
        nfar += far
    return nfar, nnear


@njit(cache=True)
def kinetic_translational(v, m, inv_m):
    e = 0.0
    for i in range(v.shape[0]):
        if inv_m[i] > 0.0:
            e += 0.5 * m[i] * (v[i, 0] ** 2 + v[i, 1] ** 2 + v[i, 2] ** 2)
    return e


@njit(cache=True)
def _blown_up(n, ovr, max_ovr, v, status, why_overlap, why_state):
    """The first particle whose overlap exceeds ``max_ovr`` of its radius or whose velocity is
    not finite: stop code BLOWUP with that particle and reason (``why_overlap`` or
    ``why_state``) in ``status``; False when there is none."""
    for i in range(n):
        if not (ovr[i] <= max_ovr):
            status[0] = BLOWUP
            status[2] = i
            status[3] = why_overlap
            return True
        if not (abs(v[i, 0]) + abs(v[i, 1]) + abs(v[i, 2]) < math.inf):
            status[0] = BLOWUP
            status[2] = i
            status[3] = why_state
            return True
    return False


@njit(cache=True)
def run_loop(nsteps, step0, resume_mid, need_forces, ke_tol, ke_every, max_ovr, wlog_every,
             log0, x, v, om, f, t, r, m, inv_m, inv_i, mat, disp, ovr, peak, mroll, pid, xr, vw,
             gravity, box, periodic, dt, skin, extra, pair, codes, sort_every, perm, fbuf, ibuf,
             cell_start, cell_idx, cell_of, cpos, wcell_start, wcell_idx, glob,
             start_a, nbr_a, hist_a, act_a, start_b, nbr_b, hist_b, act_b, groups, sorder,
             sgroup, scratch, hits, near, ncnt, dref, wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b,
             whist_b, wslot, prim_kind, prim_wall, prim_mat, prim_par, prim_pts, prim_dirs,
             wall_vel, wall_omega, wall_centre, wall_force, wall_torque, wall_reach, wlog,
             fstate, status):
    """Run up to nsteps steps; returns the number of completed steps.

    The lists live in the *_a buffers on entry and on return (a rebuild writes the other
    buffer and the two swap roles; the wall lists swap on their own when only they are
    renewed).  need_forces: compute the forces of the initial state first (fresh or
    modified system).  resume_mid: the first step's kick-drift was already done by a call
    that stopped for a buffer reallocation.  groups: slab groups per colour of the pair
    pass (the thread count).  wall_reach[w]: largest distance from wall w's
    centre at which its surface can touch a particle (a point there moves at most
    (|v_w| + |omega_w| wall_reach[w]) dt per step).  fstate[0] carries the accumulated wall
    displacement since the last list build, fstate[1] counts builds of the pair lists,
    fstate[2] builds of the wall lists alone, fstate[3] the steps since the last spatial
    sort: a pair-list build with fstate[3] >= sort_every > 0 first re-sorts the particle
    rows into cell order (:func:`soilcal.dem.neighbour.sort_particles`; perm, fbuf, ibuf:
    its work space; pid: insertion ids, which follow the rows; peak: the largest overlap of
    each row, gather); fstate[4] counts the pair passes over every listed pair (below).
    Wall force and torque go to row
    (step - log0) / wlog_every - 1 of wlog every wlog_every steps after step log0.

    Near list: of the listed pairs (R_i + R_j + skin + s_c apart at most at the build), most
    never touch before the next build, yet each is checked every step.  A pass over every
    listed pair also writes, per row, the slots of the pairs that touch or lie closer than
    R_i + R_j + s_n + s_c (s_n = NEAR_SKIN x skin) into ``near`` (``ncnt`` per row), and
    dref takes disp; the following steps' passes visit those slots only, in the same order,
    until a particle has moved more than NEAR_MOVE x s_n since (_kick_drift) or the lists
    are rebuilt.  A pair left out neither touched nor lay within s_n + s_c of contact, and
    its two spheres have since closed that gap by less than 2 NEAR_MOVE s_n < s_n: it is
    still no closer than the JKR separation range s_c (and s_c bounds the reach of the
    ``gap`` approach), so the full pass would have skipped it too, or passed it to the
    contact law only to be told it is apart, with nothing written but its touching flag,
    already 0.  The forces, their order and every history are those of the full pass.
    Every run_loop call starts with a full pass (near, ncnt and dref need not survive it).
    """
    n = x.shape[0]
    skin2 = 0.25 * skin * skin
    cutn = NEAR_SKIN * skin + extra
    near2 = (NEAR_MOVE * NEAR_SKIN * skin) ** 2
    nearok = False
    status[0] = DONE
    status[1] = step0
    status[2] = -1
    status[3] = 0
    status[4] = 0
    swapped = False
    wswapped = False
    wstep = 0.0
    for w in range(wall_vel.shape[0]):
        vv = math.sqrt(wall_vel[w, 0] ** 2 + wall_vel[w, 1] ** 2 + wall_vel[w, 2] ** 2)
        oo = math.sqrt(wall_omega[w, 0] ** 2 + wall_omega[w, 1] ** 2 + wall_omega[w, 2] ** 2)
        wstep = max(wstep, (vv + oo * wall_reach[w]) * dt)
    # lists grouped for fewer threads than now run (set_num_threads between runs) are
    # regrouped at once rather than at the next natural rebuild
    rebuild = need_forces or resume_mid or sgroup[SGROUP_LEN - 1] < groups
    wrebuild = False
    done = 0
    for s in range(-1 if need_forces else 0, nsteps):
        first = s == -1
        if first or s > 0 or not resume_mid:
            # s == -1: no motion, only the packed rows for the initial forces
            nfar, nnear = _kick_drift(x, v, om, f, t, r, m, inv_m, inv_i, mat, disp, ovr,
                                      mroll, xr, vw, gravity, dt, box, periodic, skin2,
                                      not first, dref, near2)
            if nfar > 0:
                rebuild = True
            if nnear > 0:
                nearok = False
            if wstep > 0.0 and not first:
                move_walls(dt, prim_wall, prim_par, prim_pts, prim_dirs, wall_vel,
                           wall_omega, wall_centre)
                fstate[0] += wstep
                if fstate[0] > 0.5 * skin:
                    wrebuild = True
        # current (c) and other (o) buffers
        if swapped:
            sc, nc, hc, ac, so, no, ho, ao = (start_b, nbr_b, hist_b, act_b,
                                              start_a, nbr_a, hist_a, act_a)
        else:
            sc, nc, hc, ac, so, no, ho, ao = (start_a, nbr_a, hist_a, act_a,
                                              start_b, nbr_b, hist_b, act_b)
        if wswapped:
            wnc, wcc, whc, wno, wco, who = wnbr_b, wcnt_b, whist_b, wnbr_a, wcnt_a, whist_a
        else:
            wnc, wcc, whc, wno, wco, who = wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b, whist_b
        if rebuild or wrebuild:
            if rebuild:
                remap = False
                code = 0
                if sort_every > 0 and fstate[3] >= sort_every:
                    ok, need = sort_particles(False, x, v, om, f, t, r, m, inv_m, inv_i, mat,
                                              disp, ovr, pid, xr, vw, box, periodic, skin,
                                              extra, cell_start, cell_idx, cell_of, cpos,
                                              perm, fbuf, ibuf)
                    remap = ok
                    if not ok:
                        code = 3
                if code == 0:
                    code, need = build_lists(x, r, box, periodic, skin, extra, cell_start,
                                             cell_idx, cell_of, cpos, sc, nc, hc, ac, so, no,
                                             ho, ao, groups, sorder, sgroup, scratch, hits,
                                             remap, perm, prim_kind, prim_par, wcell_start,
                                             wcell_idx, glob, wnc, wcc, whc, wno, wco, who)
                if code != 0 and remap:
                    # the old lists use the old rows: restore them for the retry
                    sort_particles(True, x, v, om, f, t, r, m, inv_m, inv_i, mat, disp, ovr,
                                   pid, xr, vw, box, periodic, skin, extra, cell_start,
                                   cell_idx, cell_of, cpos, perm, fbuf, ibuf)
                elif remap:
                    fstate[3] = 0.0
            else:
                code, need = build_wall_lists(x, r, box, periodic, skin, extra, cell_start,
                                              cell_idx, cell_of, cpos, prim_kind, prim_par,
                                              wcell_start, wcell_idx, glob,
                                              wnc, wcc, whc, wno, wco, who)
            if code != 0:
                status[0] = NEED_WBINS if code == 5 else code
                status[1] = step0 + max(s, 0)
                status[3] = need
                status[4] = 0 if first else 1
                _restore(swapped, wswapped, start_a, nbr_a, hist_a, act_a, start_b, nbr_b,
                         hist_b, act_b, wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b, whist_b)
                return done
            if rebuild:
                swapped = not swapped
                sc, nc, hc, ac = so, no, ho, ao
                disp[:, :] = 0.0
                fstate[1] += 1.0
                nearok = False
            else:
                fstate[2] += 1.0
            wswapped = not wswapped
            wnc, wcc, whc = wno, wco, who
            rebuild = False
            wrebuild = False
            fstate[0] = 0.0
        # the forces of the initial state advance no history (no time passes: LAMMPS and
        # LIGGGHTS likewise do not update their shear history in a run's setup); -dt tells
        # the contact law it is the setup of a run with step dt (contact.py)
        dth = -dt if first else dt
        mode = 2 if nearok else 1
        for colour in range(3):
            pair_forces(colour, xr, vw, pair, codes, box, periodic, dth, sc, nc, hc, ac,
                        sorder, sgroup, f, t, ovr, mroll, near, ncnt, mode, cutn)
        if mode == 1:
            dref[:, :] = disp
            nearok = True
            fstate[4] += 1.0
        nbad = gather(x, v, om, r, inv_m, inv_i, mat, f, t, ovr, peak, mroll, dt, not first, max_ovr,
                      pair, codes, prim_kind, prim_wall, prim_mat, prim_par, wall_vel,
                      wall_omega, wall_centre, wnc, wcc, whc, wslot)
        reduce_wall_forces(wcc, wnc, wslot, prim_wall, wall_force, wall_torque)
        if first:
            # the state as given already overlaps beyond the limit (or is not finite): a
            # run that is to step from it stops before its first step (reasons 3 and 4),
            # rather than reporting a blow-up of step 1; the forces of such a state alone
            # (no steps) are evaluated as they are
            if nbad > 0 and nsteps > 0 and _blown_up(n, ovr, max_ovr, v, status, 3, 4):
                break
            continue
        done = s + 1
        fstate[3] += 1.0
        status[1] = step0 + done
        if wlog_every > 0 and (step0 + done - log0) % wlog_every == 0:
            row = (step0 + done - log0) // wlog_every - 1
            if row < wlog.shape[0]:
                for w in range(wall_force.shape[0]):
                    for q in range(3):
                        wlog[row, w, q] = wall_force[w, q]
                        wlog[row, w, 3 + q] = wall_torque[w, q]
        if nbad > 0:
            _blown_up(n, ovr, max_ovr, v, status, 1, 2)
            break
        if ke_every > 0 and (step0 + done) % ke_every == 0:
            if kinetic_translational(v, m, inv_m) < ke_tol:
                status[0] = SETTLED
                break
    _restore(swapped, wswapped, start_a, nbr_a, hist_a, act_a, start_b, nbr_b, hist_b, act_b,
             wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b, whist_b)
    return done


@njit(cache=True)
def _restore(swapped, wswapped, start_a, nbr_a, hist_a, act_a, start_b, nbr_b, hist_b, act_b,
             wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b, whist_b):
    """Copy the current lists back into the *_a buffers."""
    if swapped:
        start_a[:] = start_b
        npair = start_b[start_b.shape[0] - 1]
        nbr_a[:npair] = nbr_b[:npair]
        hist_a[:npair, :] = hist_b[:npair, :]
        act_a[:npair] = act_b[:npair]
    if wswapped:
        wnbr_a[:, :] = wnbr_b
        wcnt_a[:] = wcnt_b
        whist_a[:, :] = whist_b
