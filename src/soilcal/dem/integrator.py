"""Time loop: velocity Verlet for translation and rotation of spheres, all steps in one njit call.

Per step (LIGGGHTS ``fix nve/sphere`` scheme)::

    v += F/m dt/2,  omega += T/I dt/2,  x += v dt          (kick-drift, periodic wrap)
    walls move by their rigid motion;  lists rebuilt if max |dx| > skin/2
    F, T from gravity and contacts (each particle sums its own contacts: no scatter writes)
    v += F/m dt/2,  omega += T/I dt/2                     (kick)

I = 2/5 m R^2 for a solid sphere.  Fixed particles have 1/m = 1/I = 0.  Wall reactions are
stored per (particle, wall slot) and summed per wall serially after the force loop, so the
wall force and torque are race free and independent of the thread count.

Stop codes (status[0]): 0 finished, 1 neighbour list too short, 2 wall list too short,
3 cell buffer too short, 4 blow-up (status[1] step, status[2] particle, reason in status[3]:
1 overlap above the limit, 2 non-finite state), 5 settled (status[1] steps done).
"""

from __future__ import annotations

import math

from numba import njit, prange

from soilcal.dem.contact import H_SIZE, H_TOUCH, contact_force
from soilcal.dem.neighbour import build_lists, min_image
from soilcal.dem.walls import TRIANGLE, move_walls, prim_closest

DONE, NEED_K, NEED_KW, NEED_CELLS, BLOWUP, SETTLED = 0, 1, 2, 3, 4, 5
NBLK_GROUPS = 32


@njit(cache=True, parallel=True)
def compute_forces(x, v, om, r, m, inv_m, mat, f, t, ovr, gravity, box, periodic, dt,
                   nbr, cnt, hist, pair, codes,
                   prim_kind, prim_wall, prim_mat, prim_par, wall_vel, wall_omega, wall_centre,
                   wnbr, wcnt, whist, wslot):
    n = x.shape[0]
    L0 = box[1] - box[0]
    L1 = box[3] - box[2]
    h0 = 0.5 * L0
    h1 = 0.5 * L1
    p0 = periodic[0]
    p1 = periodic[1]
    gx, gy, gz = gravity[0], gravity[1], gravity[2]
    # particles are processed in blocks of 64 dealt round-robin over NBLK_GROUPS groups, so
    # the threads share every region of the domain (balanced when contacts are unevenly
    # spread, e.g. a falling column over a settled bed); results do not depend on it
    nblk = (n + 63) // 64
    for c in prange(NBLK_GROUPS):
        for blk in range(c, nblk, NBLK_GROUPS):
            for i in range(blk * 64, min(n, blk * 64 + 64)):
                xi, yi, zi, ri = x[i, 0], x[i, 1], x[i, 2], r[i]
                vxi, vyi, vzi = v[i, 0], v[i, 1], v[i, 2]
                wxi, wyi, wzi = om[i, 0], om[i, 1], om[i, 2]
                imi = inv_m[i]
                mi = mat[i]
                fx = m[i] * gx
                fy = m[i] * gy
                fz = m[i] * gz
                tx = 0.0
                ty = 0.0
                tz = 0.0
                mo = 0.0
                for k in range(cnt[i]):
                    j = nbr[i, k]
                    dx = min_image(xi - x[j, 0], p0, h0, L0)
                    dy = min_image(yi - x[j, 1], p1, h1, L1)
                    dz = zi - x[j, 2]
                    rj = r[j]
                    rs = ri + rj
                    d2 = dx * dx + dy * dy + dz * dz
                    if d2 >= rs * rs and hist[i, k, H_TOUCH] == 0.0:
                        continue
                    ims = imi + inv_m[j]
                    if ims == 0.0:
                        continue
                    d = math.sqrt(d2)
                    invd = 1.0 / d
                    nx = dx * invd
                    ny = dy * invd
                    nz = dz * invd
                    delta = rs - d
                    ci = ri - 0.5 * delta
                    cj = rj - 0.5 * delta
                    ax = ci * wxi + cj * om[j, 0]
                    ay = ci * wyi + cj * om[j, 1]
                    az = ci * wzi + cj * om[j, 2]
                    rvx = vxi - v[j, 0] - (ay * nz - az * ny)
                    rvy = vyi - v[j, 1] - (az * nx - ax * nz)
                    rvz = vzi - v[j, 2] - (ax * ny - ay * nx)
                    act, cfx, cfy, cfz, ctx, cty, ctz = contact_force(
                        codes, pair, mi, mat[j], delta, nx, ny, nz, rvx, rvy, rvz,
                        wxi - om[j, 0], wyi - om[j, 1], wzi - om[j, 2],
                        ci, ri * rj / rs, 1.0 / ims, dt, hist, i, k)
                    if act:
                        fx += cfx
                        fy += cfy
                        fz += cfz
                        tx += ctx
                        ty += cty
                        tz += ctz
                        if delta > mo * ri:
                            mo = delta / ri
                # walls with a face contact (bit w): their edge/vertex contacts are dropped
                face_mask = 0
                nwc = wcnt[i]
                has_tri = False
                for k in range(nwc):
                    p = wnbr[i, k]
                    if prim_kind[p] == TRIANGLE:
                        has_tri = True
                        r8 = prim_closest(prim_kind[p], prim_par, p, xi, yi, zi)
                        if r8[7] == 0 and r8[0] < ri:
                            face_mask |= 1 << min(prim_wall[p], 62)
                for k in range(nwc):
                    p = wnbr[i, k]
                    for q in range(6):
                        wslot[i, k, q] = 0.0
                    dist, nx, ny, nz, cx, cy, cz, feat = prim_closest(prim_kind[p], prim_par, p,
                                                                      xi, yi, zi)
                    delta = ri - dist
                    if delta <= 0.0 and whist[i, k, H_TOUCH] == 0.0:
                        continue
                    if imi == 0.0:
                        continue
                    if has_tri and feat != 0:
                        w = prim_wall[p]
                        dup = (face_mask >> min(w, 62)) & 1 == 1
                        if not dup:
                            for kk in range(k):
                                pp = wnbr[i, kk]
                                if prim_wall[pp] != w or prim_kind[pp] != TRIANGLE:
                                    continue
                                o8 = prim_closest(prim_kind[pp], prim_par, pp, xi, yi, zi)
                                if o8[7] != 0 and o8[0] < ri:
                                    ex = o8[4] - cx
                                    ey = o8[5] - cy
                                    ez = o8[6] - cz
                                    if ex * ex + ey * ey + ez * ez < (1e-9 * ri) ** 2:
                                        dup = True
                                        break
                        if dup:
                            for q in range(H_SIZE):
                                whist[i, k, q] = 0.0
                            continue
                    w = prim_wall[p]
                    ci = ri - 0.5 * delta
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
                    act, cfx, cfy, cfz, ctx, cty, ctz = contact_force(
                        codes, pair, mi, prim_mat[p], delta, nx, ny, nz, rvx, rvy, rvz,
                        wxi - ox, wyi - oy, wzi - oz, ci, ri, 1.0 / imi, dt, whist, i, k)
                    if act:
                        fx += cfx
                        fy += cfy
                        fz += cfz
                        tx += ctx
                        ty += cty
                        tz += ctz
                        if delta > mo * ri:
                            mo = delta / ri
                        # reaction on the wall: force -F, torque about the wall centre
                        # -(x_i - c_w) x F - T_i  (conserves angular momentum exactly)
                        px = xi - wall_centre[w, 0]
                        py = yi - wall_centre[w, 1]
                        pz = zi - wall_centre[w, 2]
                        wslot[i, k, 0] = -cfx
                        wslot[i, k, 1] = -cfy
                        wslot[i, k, 2] = -cfz
                        wslot[i, k, 3] = -(py * cfz - pz * cfy) - ctx
                        wslot[i, k, 4] = -(pz * cfx - px * cfz) - cty
                        wslot[i, k, 5] = -(px * cfy - py * cfx) - ctz
                f[i, 0] = fx
                f[i, 1] = fy
                f[i, 2] = fz
                t[i, 0] = tx
                t[i, 1] = ty
                t[i, 2] = tz
                ovr[i] = mo


@njit(cache=True)
def reduce_wall_forces(wcnt, wnbr, wslot, prim_wall, wall_force, wall_torque):
    wall_force[:, :] = 0.0
    wall_torque[:, :] = 0.0
    for i in range(wcnt.shape[0]):
        for k in range(wcnt[i]):
            w = prim_wall[wnbr[i, k]]
            for q in range(3):
                wall_force[w, q] += wslot[i, k, q]
                wall_torque[w, q] += wslot[i, k, 3 + q]


@njit(cache=True, parallel=True)
def _kick_drift(x, v, om, f, t, inv_m, inv_i, disp, dt, box, periodic, skin2):
    n = x.shape[0]
    h = 0.5 * dt
    nfar = 0
    for i in prange(n):
        a = inv_m[i] * h
        b = inv_i[i] * h
        far = 0
        s2 = 0.0
        for q in range(3):
            v[i, q] += f[i, q] * a
            om[i, q] += t[i, q] * b
            dq = v[i, q] * dt
            x[i, q] += dq
            disp[i, q] += dq
            s2 += disp[i, q] * disp[i, q]
        if s2 > skin2:
            far = 1
        for q in range(2):
            if periodic[q]:
                lo = box[2 * q]
                L = box[2 * q + 1] - lo
                if x[i, q] < lo:
                    x[i, q] += L
                elif x[i, q] >= box[2 * q + 1]:
                    x[i, q] -= L
        nfar += far
    return nfar


@njit(cache=True, parallel=True)
def _kick(v, om, f, t, inv_m, inv_i, ovr, dt, max_ovr):
    n = v.shape[0]
    h = 0.5 * dt
    nbad = 0
    for i in prange(n):
        a = inv_m[i] * h
        b = inv_i[i] * h
        for q in range(3):
            v[i, q] += f[i, q] * a
            om[i, q] += t[i, q] * b
        bad = 0
        if not (ovr[i] <= max_ovr):
            bad = 1
        if not (abs(v[i, 0]) + abs(v[i, 1]) + abs(v[i, 2]) < math.inf):
            bad = 1
        nbad += bad
    return nbad


@njit(cache=True)
def kinetic_translational(v, m, inv_m):
    e = 0.0
    for i in range(v.shape[0]):
        if inv_m[i] > 0.0:
            e += 0.5 * m[i] * (v[i, 0] ** 2 + v[i, 1] ** 2 + v[i, 2] ** 2)
    return e


@njit(cache=True)
def _rebuild(swapped, x, r, box, periodic, skin, extra, cell_start, cell_idx, cell_of,
             nbr_a, cnt_a, hist_a, nbr_b, cnt_b, hist_b, prim_kind, prim_par,
             wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b, whist_b):
    if swapped:
        return build_lists(x, r, box, periodic, skin, extra, cell_start, cell_idx, cell_of,
                           nbr_b, cnt_b, hist_b, nbr_a, cnt_a, hist_a, prim_kind, prim_par,
                           wnbr_b, wcnt_b, whist_b, wnbr_a, wcnt_a, whist_a)
    return build_lists(x, r, box, periodic, skin, extra, cell_start, cell_idx, cell_of,
                       nbr_a, cnt_a, hist_a, nbr_b, cnt_b, hist_b, prim_kind, prim_par,
                       wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b, whist_b)


@njit(cache=True)
def _forces(swapped, x, v, om, r, m, inv_m, mat, f, t, ovr, gravity, box, periodic, dt,
            nbr_a, cnt_a, hist_a, nbr_b, cnt_b, hist_b, pair, codes, prim_kind, prim_wall,
            prim_mat, prim_par, wall_vel, wall_omega, wall_centre,
            wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b, whist_b, wslot, wall_force, wall_torque):
    if swapped:
        compute_forces(x, v, om, r, m, inv_m, mat, f, t, ovr, gravity, box, periodic, dt,
                       nbr_b, cnt_b, hist_b, pair, codes, prim_kind, prim_wall, prim_mat,
                       prim_par, wall_vel, wall_omega, wall_centre, wnbr_b, wcnt_b, whist_b,
                       wslot)
        reduce_wall_forces(wcnt_b, wnbr_b, wslot, prim_wall, wall_force, wall_torque)
    else:
        compute_forces(x, v, om, r, m, inv_m, mat, f, t, ovr, gravity, box, periodic, dt,
                       nbr_a, cnt_a, hist_a, pair, codes, prim_kind, prim_wall, prim_mat,
                       prim_par, wall_vel, wall_omega, wall_centre, wnbr_a, wcnt_a, whist_a,
                       wslot)
        reduce_wall_forces(wcnt_a, wnbr_a, wslot, prim_wall, wall_force, wall_torque)


@njit(cache=True)
def run_loop(nsteps, step0, resume_mid, need_forces, ke_tol, ke_every, max_ovr, wlog_every,
             x, v, om, f, t, r, m, inv_m, inv_i, mat, disp, ovr,
             gravity, box, periodic, dt, skin, extra, pair, codes,
             cell_start, cell_idx, cell_of,
             nbr_a, cnt_a, hist_a, nbr_b, cnt_b, hist_b,
             wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b, whist_b, wslot,
             prim_kind, prim_wall, prim_mat, prim_par, prim_pts, prim_dirs,
             wall_vel, wall_omega, wall_centre, wall_force, wall_torque, wall_reach, wlog,
             fstate, status):
    """Run up to nsteps steps; returns the number of completed steps.

    The lists live in the *_a buffers on entry and on return.  need_forces: compute the
    forces of the initial state first (fresh or modified system).  resume_mid: the first
    step's kick-drift was already done by a call that stopped for a list reallocation.
    fstate[0] carries the accumulated wall displacement since the last rebuild, fstate[1]
    counts list builds.
    """
    n = x.shape[0]
    skin2 = 0.25 * skin * skin
    status[0] = DONE
    status[1] = step0
    status[2] = -1
    status[3] = 0
    status[4] = 0
    swapped = False
    wstep = 0.0
    for w in range(wall_vel.shape[0]):
        vv = math.sqrt(wall_vel[w, 0] ** 2 + wall_vel[w, 1] ** 2 + wall_vel[w, 2] ** 2)
        oo = math.sqrt(wall_omega[w, 0] ** 2 + wall_omega[w, 1] ** 2 + wall_omega[w, 2] ** 2)
        wstep = max(wstep, (vv + oo * wall_reach) * dt)
    if need_forces:
        code, need = _rebuild(swapped, x, r, box, periodic, skin, extra, cell_start, cell_idx,
                              cell_of, nbr_a, cnt_a, hist_a, nbr_b, cnt_b, hist_b, prim_kind,
                              prim_par, wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b, whist_b)
        if code != 0:
            status[0] = code
            status[3] = need
            return 0
        swapped = True
        disp[:, :] = 0.0
        fstate[1] += 1.0
        fstate[0] = 0.0
        _forces(swapped, x, v, om, r, m, inv_m, mat, f, t, ovr, gravity, box, periodic, dt,
                nbr_a, cnt_a, hist_a, nbr_b, cnt_b, hist_b, pair, codes, prim_kind, prim_wall,
                prim_mat, prim_par, wall_vel, wall_omega, wall_centre,
                wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b, whist_b, wslot, wall_force, wall_torque)
    rebuild = resume_mid
    done = 0
    for s in range(nsteps):
        if s > 0 or not resume_mid:
            nfar = _kick_drift(x, v, om, f, t, inv_m, inv_i, disp, dt, box, periodic, skin2)
            if nfar > 0:
                rebuild = True
            if wstep > 0.0:
                move_walls(dt, prim_wall, prim_par, prim_pts, prim_dirs, wall_vel,
                           wall_omega, wall_centre)
                fstate[0] += wstep
                if fstate[0] > 0.5 * skin:
                    rebuild = True
        if rebuild:
            code, need = _rebuild(swapped, x, r, box, periodic, skin, extra, cell_start,
                                  cell_idx, cell_of, nbr_a, cnt_a, hist_a, nbr_b, cnt_b, hist_b,
                                  prim_kind, prim_par, wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b,
                                  whist_b)
            if code != 0:
                status[0] = code
                status[1] = step0 + s
                status[3] = need
                status[4] = 1
                if swapped:
                    _copy_lists(nbr_b, cnt_b, hist_b, nbr_a, cnt_a, hist_a,
                                wnbr_b, wcnt_b, whist_b, wnbr_a, wcnt_a, whist_a)
                return done
            swapped = not swapped
            rebuild = False
            fstate[1] += 1.0
            fstate[0] = 0.0
            disp[:, :] = 0.0
        _forces(swapped, x, v, om, r, m, inv_m, mat, f, t, ovr, gravity, box, periodic, dt,
                nbr_a, cnt_a, hist_a, nbr_b, cnt_b, hist_b, pair, codes, prim_kind, prim_wall,
                prim_mat, prim_par, wall_vel, wall_omega, wall_centre,
                wnbr_a, wcnt_a, whist_a, wnbr_b, wcnt_b, whist_b, wslot, wall_force, wall_torque)
        nbad = _kick(v, om, f, t, inv_m, inv_i, ovr, dt, max_ovr)
        done = s + 1
        status[1] = step0 + done
        if wlog_every > 0 and (step0 + done) % wlog_every == 0:
            row = (step0 + done) // wlog_every - 1
            if row < wlog.shape[0]:
                for w in range(wall_force.shape[0]):
                    for q in range(3):
                        wlog[row, w, q] = wall_force[w, q]
                        wlog[row, w, 3 + q] = wall_torque[w, q]
        if nbad > 0:
            for i in range(n):
                if not (ovr[i] <= max_ovr):
                    status[0] = BLOWUP
                    status[2] = i
                    status[3] = 1
                    break
                if not (abs(v[i, 0]) + abs(v[i, 1]) + abs(v[i, 2]) < math.inf):
                    status[0] = BLOWUP
                    status[2] = i
                    status[3] = 2
                    break
            break
        if ke_every > 0 and (step0 + done) % ke_every == 0:
            if kinetic_translational(v, m, inv_m) < ke_tol:
                status[0] = SETTLED
                break
    if swapped:
        _copy_lists(nbr_b, cnt_b, hist_b, nbr_a, cnt_a, hist_a,
                    wnbr_b, wcnt_b, whist_b, wnbr_a, wcnt_a, whist_a)
    return done


@njit(cache=True)
def _copy_lists(nbr_b, cnt_b, hist_b, nbr_a, cnt_a, hist_a,
                wnbr_b, wcnt_b, whist_b, wnbr_a, wcnt_a, whist_a):
    nbr_a[:, :] = nbr_b
    cnt_a[:] = cnt_b
    hist_a[:, :, :] = hist_b
    wnbr_a[:, :] = wnbr_b
    wcnt_a[:] = wcnt_b
    whist_a[:, :, :] = whist_b
