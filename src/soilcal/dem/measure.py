"""Responses measured on DEM particle states: repose angle, drum angle, stress-strain.

Repose angle from radial bins (vineyard-soil paper, 003, section "Simulated static/dynamic
angle of repose determination": EDEMpy measurement, a radial array of bins, the highest
particle of each bin, a least-squares line through those points, eight directions averaged)
--------------------------------------------------------------------------------------
Particles above the plate (z_top = z + r > plate_z) are split into ``n_dir`` azimuthal
sectors of width 360/n_dir deg about the pile axis (x_c, y_c) (the horizontal centroid of the
particles standing on the plate unless given).  Along each sector (or each of ``n_sub``
rays per sector; containers must stay wider than a particle, or the highest particle of a
narrow container near the axis lies below the surface and the angle is biased low) the
radial distance rho = |(x, y) - (x_c, y_c)| is cut into containers of width
``bin_width`` (default one mean diameter); each container gives its highest particle (by
centre height) and, as the paper fits "the centre-of-mass coordinates of these particles",
the point (rho_k, h_k) of that particle's centre, h_k = z - plate_z.  With the height of the
sector H = max_k h_k, the rounded top and the toe are excluded by keeping the bins with

    max(BAND[0] H, 2 <r>) < h_k < BAND[1] H     (BAND = (0.20, 0.75), as the photo measurement)

(the 2 <r> bound drops the skirt of single spheres around a low heap, whose centres stand r
above the plate; it is dropped when fewer than 3 bins remain) and lie outside the highest
container of their ray (rho_k > rho_top: containers near the axis hold few particles and
are not on the flank), and fitting h = a + b rho by least squares (``numpy.polyfit``), so
the flank angle is

    alpha = atan(-b)

The repose angle is the mean of the n_dir flank angles (a direction with fewer than three
containers or fewer than two flank bins is left out; fewer than half the directions is an
error); their sample standard deviation is reported as the spread.  ``n_sub`` must be odd, so
that the rays of a direction lie symmetrically about its centre line.

Surface scan (height map of the sphere caps)
--------------------------------------------
A third measurement reads the heap like a laser scan or a depth camera looking down: on a
square grid of pitch ``cell`` (default half a mean radius) the surface height is the highest
sphere cap above each grid point,

    H(x, y) = max_i ( z_i + sqrt(r_i^2 - (x - x_i)^2 - (y - y_i)^2) ) - plate_z

over the spheres whose disc covers the point (the plate, H = 0, where none does).  Each of
the ``n_dir`` sectors is cut into rings of width ``cell``; the sector's radial profile is the
mean H of its grid points in each ring (abscissa: their mean rho), and the flank line is
fitted to the rings outside the profile's maximum with BAND[0] H_d < h < BAND[1] H_d (H_d
the highest ring of the sector), as above.  Every grid point of a ring counts, not only the
highest sphere of a container, so the estimate does not depend on how many spheres a
container holds (the container-width bias of the radial bins) and averages the surface over
the whole sector.  The probe's surface is the heap's offset by one probe radius, so on a
straight flank it has the flank's slope (tests: analytic heaps of 22-38 deg within 0.1 deg,
where the radial bins are within 0.3 deg).  Scatter over seeds of all three estimators on
simulated heaps: ``benchmarks/repose_seeds.py``.

Side silhouette
---------------
The same pile is also rendered as an orthographic side view (each sphere a dark disc of
radius r on a light background, seen along x or along y, a grey plate whose top edge is the
plate plane) and measured by :func:`soilcal.imaging.measure.measure_pile`, the pipeline used
for photos (Otsu threshold, RANSAC flank lines between 20 and 75 % of the heap height), in
memory and on the plate row the renderer drew (a photo's plate line comes from a Hough
transform; on a rendered view it finds the same row, to its half-pixel edge locations, for
more than twice the cost of the rest of the measurement).  Two views (along x and along y) give
four flanks, averaged as the papers average both sides of each photo (002 Sec. 2.4, 003 Sec.
static angle, 001 Sec. 2.2.1 four directions); more views average more of a ragged outline.

Drum free surface (003, section "Dynamic angle of repose measurement")
--------------------------------------------------------------------
In the drum's mid-section slab |s - s_mid| <= w (s the coordinate along the drum axis),
particle centres are projected on the section plane (u horizontal, z vertical).  The u range
of the slab's particles is cut into bins of width ``bin_width``; the highest top z + r of each
bin traces the free surface.  Bins in the central fraction ``central`` of the surface chord
(default 60 %, as the photo measurement of drum frames) are fitted with z = a + b u and the
frame's dynamic angle is

    theta = atan(|b|)

Frames are averaged in time (mean and sample standard deviation).

Avalanche angle (003: "the maximum angle between the slope of the soil mass and the
horizontal plane before collapse occurs").  A drum turning slowly enough slumps: the surface
is carried up with the drum until it collapses in an avalanche, so the frame angles theta_k
(taken every ``frame_every`` seconds) form a sawtooth.  The angle before each collapse is a
peak of theta_k whose topographic prominence (scipy.signal.find_peaks: the height of the
peak above the higher of the lowest points between it and higher ground on either side: at
most the rise before it and the fall after it) is at least ``min_drop``; the
avalanche angle is the mean of those peaks.  A peak on the first or the last frame is not
seen to collapse and does not count.  A surface that flows without collapses (the rolling
regime, fluctuations below ``min_drop``) has no such peak: its steady angle, the time mean,
is reported, with ``n_avalanches`` = 0.  Frames must be close enough to resolve the rise
(at 7 r/min the drum turns 2.1 deg in 0.05 s).  A bed carried up with the drum steepens by
about that much per frame, so a lone frame that lies ``min_drop`` or more above both of its
neighbours (or as far below both) is a misfit surface, not a collapse (a collapse falls
after a build-up, so the frame before its peak is close to it).  Such a frame is replaced
by the nearer of its neighbours (the median of the three), repeatedly until none is left,
before the peaks are sought, and counted in ``n_spikes`` (:func:`despike`).  The last frame
has one neighbour, so it cannot be tested that way: a fall that only the last frame shows
is not counted as a collapse.  A two-frame excursion is not a lone frame, and a real peak
whose previous frame jitters ``min_drop`` below it is taken for one: ``min_drop`` must
exceed the frame-to-frame jitter of the fitted surface.

Stress-strain (cohesive-soil paper, 004 Sec. 3.7)
---------------------------------------------------
Axial stress of the loading rod of radius R_rod pressing down with force F_z (the particles'
reaction on the rod, upward positive) and axial strain from the rod travel::

    sigma = F_z / (pi R_rod^2),      epsilon = (h0 - z_rod) / h0

with h0 the height of the sample top (rod face at first contact) above the tube floor.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from soilcal.errors import InputError

BAND = (0.20, 0.75)


def _xr(x, r, src="<input>"):
    x = np.asarray(x, dtype=float).reshape(-1, 3)
    r = np.broadcast_to(np.asarray(r, dtype=float), (len(x),)).copy()
    if len(x) < 10:
        raise InputError(src, "particles", "at least 10 particles to measure a pile", len(x))
    return x, r


def pile_centre(x, r, plate_z=0.0, layer=None):
    """Horizontal centroid of the particles standing on the plate (bottom layer)."""
    x, r = _xr(x, r)
    layer = 2.5 * float(np.mean(r)) if layer is None else layer
    on = (x[:, 2] - r - plate_z) < layer
    on &= x[:, 2] > plate_z
    pts = x[on] if on.sum() >= 3 else x[x[:, 2] > plate_z]
    return float(pts[:, 0].mean()), float(pts[:, 1].mean())


def _direction_mean(angles, n_dir, source, expected, used) -> dict:
    """Mean and sample SD of the directions that gave a flank (NaN: left out); fewer than
    half of ``n_dir`` is an error."""
    a = np.array(angles, float)
    a = a[np.isfinite(a)]
    if a.size < (n_dir + 1) // 2:
        raise InputError(source, "pile", expected, used)
    return dict(angle_deg=float(a.mean()), spread_deg=float(a.std(ddof=1)) if a.size > 1 else 0.0,
                per_direction_deg=[float(v) for v in a])


def repose_angle_bins(x, r, plate_z=0.0, centre=None, n_dir=8, bin_width=None, band=BAND,
                      n_sub=1, source="<measurement>") -> dict:
    """Repose angle from radial bins over ``n_dir`` directions (see module docstring).

    Returns dict(angle_deg, spread_deg, per_direction_deg, height_m, centre, n_bins_used).
    """
    x, r = _xr(x, r, source)
    above = x[:, 2] > plate_z
    x, r = x[above], r[above]
    if len(x) < 10:
        raise InputError(source, "particles", "at least 10 particles above the plate", len(x))
    if centre is None:
        centre = pile_centre(x, r, plate_z)
    cx, cy = centre
    dx, dy = x[:, 0] - cx, x[:, 1] - cy
    rho = np.hypot(dx, dy)
    phi = np.mod(np.arctan2(dy, dx), 2 * np.pi)
    top = x[:, 2] + r - plate_z
    w = 2.0 * float(np.mean(r)) if bin_width is None else float(bin_width)
    if not w > 0:
        raise InputError(source, "bin_width", "a bin width > 0 m", bin_width)
    height = float(top.max())
    r_mean = float(np.mean(r))
    if int(n_sub) < 1 or int(n_sub) % 2 == 0:
        raise InputError(source, "n_sub", "an odd number of rays per direction (>= 1)", n_sub)
    top = x[:, 2] - plate_z  # centre heights: the fitted points (see module docstring)
    n_ray = n_dir * int(n_sub)
    ray = np.floor((phi + np.pi / n_ray) / (2 * np.pi / n_ray)).astype(int) % n_ray
    rb = np.floor(rho / w).astype(int)
    cell = ray * (int(rb.max()) + 1) + rb
    order = np.lexsort((-top, cell))  # per container, highest first
    first = np.ones(order.size, bool)
    first[1:] = cell[order][1:] != cell[order][:-1]
    idx = order[first]
    c_ray, c_rho, c_top = ray[idx], rho[idx], top[idx]
    c_dir = ((c_ray + n_sub // 2) // n_sub) % n_dir if n_sub > 1 else c_ray
    angles, used = [], []
    for k in range(n_dir):
        keep_k = np.zeros(idx.size, bool)
        sel = c_dir == k
        if sel.sum() < 3:  # too few containers in this direction: left out
            angles.append(float("nan"))
            used.append(int(sel.sum()))
            continue
        hd = c_top[sel].max()
        for q in np.unique(c_ray[sel]):
            s_q = c_ray == q
            rho_top = c_rho[s_q][np.argmax(c_top[s_q])]
            keep_k |= s_q & (c_rho > rho_top)
        keep = keep_k & (c_top > max(band[0] * hd, 2.0 * r_mean)) & (c_top < band[1] * hd)
        if keep.sum() < 3:  # a low heap: keep the skirt bound only
            keep = keep_k & (c_top > band[0] * hd) & (c_top < band[1] * hd)
        if keep.sum() < 2 or np.ptp(c_rho[keep]) <= 0:
            angles.append(float("nan"))
            used.append(int(keep.sum()))
            continue
        b = np.polyfit(c_rho[keep], c_top[keep], 1)[0]
        angles.append(math.degrees(math.atan(-b)))
        used.append(int(keep.sum()))
    return dict(_direction_mean(angles, n_dir, source, "flank bins in at least half of the "
                                "directions (pile too small for the bins)", used),
                height_m=height, centre=(float(cx), float(cy)), n_bins_used=used)


# ---------------------------------------------------------------- surface scan
@njit(cache=True)
def _cap_heights(x, r, lo0, lo1, cell, H):
    """H[i, j] = max over spheres of the cap height above grid point (lo + (i + 1/2) cell)."""
    n0, n1 = H.shape
    for p in range(x.shape[0]):
        px, py, pz, pr = x[p, 0], x[p, 1], x[p, 2], r[p]
        i0 = max(int(math.floor((px - pr - lo0) / cell - 0.5)), 0)
        i1 = min(int(math.ceil((px + pr - lo0) / cell - 0.5)) + 1, n0)
        j0 = max(int(math.floor((py - pr - lo1) / cell - 0.5)), 0)
        j1 = min(int(math.ceil((py + pr - lo1) / cell - 0.5)) + 1, n1)
        for i in range(i0, i1):
            dx = lo0 + (i + 0.5) * cell - px
            for j in range(j0, j1):
                dy = lo1 + (j + 0.5) * cell - py
                q = pr * pr - dx * dx - dy * dy
                if q >= 0.0:
                    h = pz + math.sqrt(q)
                    if h > H[i, j]:
                        H[i, j] = h


def surface_height_map(x, r, plate_z=0.0, cell=None, probe=None, margin=None,
                       source="<measurement>"):
    """Height above the plate of the surface traced by a probe sphere of radius ``probe``
    (default the mean particle radius) rolled over the particles, on a square grid (module
    docstring).  ``probe=0`` gives the bare sphere caps.

    Returns (X, Y, H): grid-point coordinates and heights (0 where the probe touches the plate).
    """
    x, r = _xr(x, r, source)
    probe = float(np.mean(r)) if probe is None else float(probe)
    if not probe >= 0:
        raise InputError(source, "probe", "a probe radius >= 0 m", probe)
    cell = 0.5 * float(np.mean(r)) if cell is None else float(cell)
    r = r + probe
    if not cell > 0:
        raise InputError(source, "cell", "a grid pitch > 0 m", cell)
    margin = 2.0 * cell if margin is None else float(margin)
    lo = (x[:, :2] - r[:, None]).min(axis=0) - margin
    hi = (x[:, :2] + r[:, None]).max(axis=0) + margin
    n = np.ceil((hi - lo) / cell).astype(int)
    if n.prod() > 5e7:
        raise InputError(source, "cell", "a grid of at most 5e7 points over the heap",
                         f"{cell} m ({n[0]} x {n[1]} points)")
    H = np.full((n[0], n[1]), -np.inf)
    _cap_heights(x, r, float(lo[0]), float(lo[1]), cell, H)
    # the probe's centre rides on the inflated caps; its lowest point is ``probe`` below
    H = np.maximum(H - probe - plate_z, 0.0)  # the plate where the probe reaches it
    gx = lo[0] + cell * (np.arange(n[0]) + 0.5)
    gy = lo[1] + cell * (np.arange(n[1]) + 0.5)
    X, Y = np.meshgrid(gx, gy, indexing="ij")
    return X, Y, H


def repose_angle_surface(x, r, plate_z=0.0, centre=None, n_dir=8, cell=None, probe=None,
                         band=BAND, source="<measurement>") -> dict:
    """Repose angle from the surface scan: sector profiles of the cap height map, flank line
    between ``band`` fractions of each sector's height (see module docstring).

    Returns dict(angle_deg, spread_deg, per_direction_deg, height_m, centre, n_rings_used).
    """
    x, r = _xr(x, r, source)
    above = x[:, 2] + r > plate_z
    x, r = x[above], r[above]
    if len(x) < 10:
        raise InputError(source, "particles", "at least 10 particles above the plate", len(x))
    if int(n_dir) < 1:
        raise InputError(source, "n_dir", "at least one direction", n_dir)
    if centre is None:
        centre = pile_centre(x, r, plate_z)
    cx, cy = float(centre[0]), float(centre[1])
    cell = 0.5 * float(np.mean(r)) if cell is None else float(cell)
    X, Y, H = surface_height_map(x, r, plate_z, cell, probe, source=source)
    dx, dy = (X - cx).ravel(), (Y - cy).ravel()
    h = H.ravel()
    rho = np.hypot(dx, dy)
    phi = np.mod(np.arctan2(dy, dx) + np.pi / n_dir, 2 * np.pi)
    sec = np.minimum((phi / (2 * np.pi / n_dir)).astype(int), n_dir - 1)
    ring = (rho / cell).astype(int)
    nr = int(ring.max()) + 1
    angles, used = [], []
    for k in range(n_dir):
        s = sec == k
        cnt = np.bincount(ring[s], minlength=nr)
        ok = cnt > 0
        prof = np.bincount(ring[s], weights=h[s], minlength=nr)[ok] / cnt[ok]
        rr = np.bincount(ring[s], weights=rho[s], minlength=nr)[ok] / cnt[ok]
        top = int(np.argmax(prof))
        hd = prof[top]
        keep = (np.arange(prof.size) > top) & (prof > band[0] * hd) & (prof < band[1] * hd)
        used.append(int(keep.sum()))
        if keep.sum() < 3 or not hd > 0:
            angles.append(float("nan"))
            continue
        b = np.polyfit(rr[keep], prof[keep], 1)[0]
        angles.append(math.degrees(math.atan(-b)))
    return dict(_direction_mean(angles, n_dir, source, "a flank of at least 3 rings in at "
                                "least half of the directions (pile too small for the grid)",
                                used),
                height_m=float(H.max()), centre=(cx, cy), n_rings_used=used)


# ---------------------------------------------------------------- side silhouette
@njit(cache=True)
def _paint_disks(img, rows, cols, rad, value, stop_row):
    """Set the pixels of the discs (centre rows[k], cols[k], radius rad[k]) above row
    ``stop_row`` to ``value``: the pixels of ``skimage.draw.disk`` to the last one (its
    bounding box ceil(c - R) .. floor(c + R) clipped to the image, its test
    ((i - c_r) / R)^2 + ((j - c_c) / R)^2 < 1 with the centre taken relative to the box's
    corner), without allocating per disc."""
    h, w = img.shape
    for k in range(rows.size):
        rr, cr, cc = rad[k], rows[k], cols[k]
        r0 = max(int(math.ceil(cr - rr)), 0)
        r1 = min(int(math.floor(cr + rr)), h - 1)
        c0 = max(int(math.ceil(cc - rr)), 0)
        c1 = min(int(math.floor(cc + rr)), w - 1)
        sr = cr - r0
        sc = cc - c0
        for i in range(r1 - r0 + 1):
            if i + r0 >= stop_row:
                break
            dr = (float(i) - sr) / rr
            for j in range(c1 - c0 + 1):
                dc = (float(j) - sc) / rr
                if dr * dr + dc * dc < 1.0:
                    img[i + r0, j + c0] = value


def render_side(x, r, plate_z=0.0, view="y", px_per_m=None, width_px=1000, path=None,
                background=0.93, soil=0.22, plate=0.62):
    """Orthographic side view of the particles above the plate as an 8-bit RGB image.

    ``view`` is the axis the camera looks along ("y": image columns = x, "x": columns = y), or
    the camera's azimuth in degrees: columns u = x cos(theta) + y sin(theta) (0 is "y", 90 is
    "x"; theta and theta + 180 give mirror images of one silhouette).
    Returns (image uint8[H, W, 3], px_per_m); writes a PNG when ``path`` is given.
    """
    rgb, s, _ = _render(x, r, plate_z, view, px_per_m, width_px, background, soil, plate)
    if path is not None:
        from PIL import Image

        Image.fromarray(rgb).save(path)
    return rgb, s


def _render(x, r, plate_z, view, px_per_m=None, width_px=1000, background=0.93, soil=0.22,
            plate=0.62):
    """:func:`render_side`'s image and scale, and the image row of the plate's top edge (the
    boundary between the last background row and the first plate row, at row centres)."""
    x, r = _xr(x, r)
    above = x[:, 2] + r > plate_z
    x, r = x[above], r[above]
    if view in ("x", "y"):
        u = x[:, 0 if view == "y" else 1]
    elif isinstance(view, (int, float, np.integer, np.floating)) and not isinstance(view, bool) \
            and math.isfinite(view):
        th = math.radians(float(view))
        u = x[:, 0] * math.cos(th) + x[:, 1] * math.sin(th)
    else:
        raise InputError("<render>", "view", "'x', 'y' or an azimuth in degrees", view)
    lo, hi = float((u - r).min()), float((u + r).max())
    top = float((x[:, 2] + r).max()) - plate_z
    span = hi - lo
    s = float(px_per_m) if px_per_m else 0.8 * width_px / span
    w = int(round(span * s / 0.8))
    margin_u = 0.1 * w
    plate_px = max(20, int(0.12 * top * s))
    h = int(round(top * s + 0.25 * w + plate_px + 40))
    plate_row = h - plate_px - 20
    img = np.full((h, w), background)
    img[plate_row:plate_row + plate_px, :] = plate
    img[plate_row + plate_px:, :] = 0.45
    uc = (u - lo) * s + margin_u
    vc = plate_row - (x[:, 2] - plate_z) * s
    # the plate hides what lies behind/below its top edge (rows from plate_row on)
    _paint_disks(img, vc, uc, np.maximum(r * s, 0.7), float(soil), int(plate_row))
    rgb = (np.repeat(img[..., None], 3, axis=2) * 255 + 0.5).astype(np.uint8)
    return rgb, s, plate_row - 0.5


def view_azimuths(n) -> list[float]:
    """``n`` camera azimuths spread evenly over half a turn, 180 k / n degrees (a view and the
    one opposite it see the same silhouette, mirrored): 2 gives the x and y views."""
    ok = isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n >= 1
    if not ok:
        raise InputError("<measurement>", "image_views", "a number of side views >= 1", n)
    return [180.0 * k / int(n) for k in range(int(n))]


def repose_angle_image(x, r, plate_z=0.0, views=("y", "x")) -> dict:
    """Repose angle of side silhouettes measured by :func:`soilcal.imaging.measure.measure_pile`:
    the mean of every flank of every view measured (``spread_deg``: their sample SD;
    :func:`~soilcal.imaging.measure.pile_summary`).
    ``views``: the views of :func:`render_side`, or a number n of views at the azimuths
    :func:`view_azimuths` (2: the x and y views).

    A heap of a few thousand coarse spheres has a ragged outline, so one silhouette's flank fit
    depends on which bumps it sees: more views average that out (12 cohesive 1,000-sphere
    cinnamon heaps: the seed-to-seed SD fell from 9.3 deg with 2 views to 5.0 deg with 8,
    ``benchmarks/repose_seeds.py --cases cohesive:1000 --seeds 0-11 --views 2,8``).  A view
    whose silhouette the photo pipeline cannot measure (a column of soil standing almost
    vertical shows some views a flank of a few boundary pixels) is left out and named in
    ``views_failed`` (azimuth or view, reason); the angle needs more than half of the views,
    else InputError names the first failure.

    Each view is measured in memory, as the 8-bit image a PNG of it would hold, with the
    plate's top edge the renderer drew (a levelled camera): the photo's plate search (Hough
    lines of the luminance and of the L*a*b* edges) would only find that same row again."""
    from soilcal.imaging.measure import measure_pile, pile_summary

    if not isinstance(views, (tuple, list)):
        views = view_azimuths(views)
    measured, failed = [], []
    for k, v in enumerate(views):
        rgb, _, plate_row = _render(x, r, plate_z, v)
        try:
            measured.append(measure_pile(f"<silhouette {v}>", "otsu", False, "gray",
                                         image=rgb / 255.0, plate=(0.0, plate_row)))
        except InputError as exc:
            failed.append((v, f"{exc.field}: expected {exc.expected}, got {exc.got}"))
    if 2 * len(measured) <= len(views):
        v, why = failed[0]
        raise InputError("<silhouettes>", "views",
                         f"more than half of {len(views)} views measured (view {v}: {why})",
                         f"{len(measured)} measured")
    summary = pile_summary(measured)
    return dict(angle_deg=summary["angle_deg"], spread_deg=summary["spread_deg"],
                flanks_deg=[float(a) for m in measured for a in (m.left_deg, m.right_deg)],
                views_measured=len(measured), views_failed=failed)


# ---------------------------------------------------------------- drum
def drum_surface_angle(x, r, axis_point, axis_dir=(0.0, 1.0, 0.0), slab_half=None,
                       bin_width=None, central=0.6, source="<measurement>") -> dict:
    """Free-surface angle of one drum frame in the mid-section (see module docstring).

    The drum axis must be horizontal; u is the horizontal direction normal to it.
    """
    x, r = _xr(x, r, source)
    a = np.asarray(axis_dir, float)
    a = a / np.linalg.norm(a)
    if abs(a[2]) > 1e-9:
        raise InputError(source, "axis_dir", "a horizontal drum axis", tuple(a))
    e_u = np.cross(a, [0.0, 0.0, 1.0])
    rel = x - np.asarray(axis_point, float)
    s = rel @ a
    rm = float(np.mean(r))
    half = 3.0 * rm if slab_half is None else float(slab_half)
    sel = np.abs(s) <= half
    if sel.sum() < 10:
        raise InputError(source, "slab_half", "a mid-section slab holding at least 10 particles",
                         int(sel.sum()))
    u = rel[sel] @ e_u
    top = rel[sel, 2] + r[sel]
    w = 2.0 * rm if bin_width is None else float(bin_width)
    ub = np.floor((u - u.min()) / w).astype(int)
    order = np.lexsort((-top, ub))
    first = np.ones(order.size, bool)
    first[1:] = ub[order][1:] != ub[order][:-1]
    uk, zk = u[order][first], top[order][first]
    lo, hi = uk.min(), uk.max()
    keep = (uk >= lo + 0.5 * (1 - central) * (hi - lo)) & (uk <= hi - 0.5 * (1 - central) * (hi - lo))
    if keep.sum() < 3:
        raise InputError(source, "central", "at least 3 surface bins in the central chord",
                         int(keep.sum()))
    b, c = np.polyfit(uk[keep], zk[keep], 1)
    return dict(angle_deg=float(math.degrees(math.atan(abs(b)))), slope=float(b),
                n_bins=int(keep.sum()))


def avalanche_angle(angles, min_drop, source="<measurement>") -> dict:
    """Mean angle before collapse of a drum's frame angles (module docstring).

    Returns dict(angle_deg, n_avalanches, peaks_deg, n_spikes); angle_deg is the time mean
    (of the frames as measured) when no peak has a prominence of ``min_drop`` degrees
    (always so for fewer than 3 frames, where no collapse can be seen); ``n_spikes`` lone
    frames were replaced by a neighbour before the peaks were sought."""
    from scipy.signal import find_peaks

    a = np.asarray(angles, float)
    if a.ndim != 1 or a.size < 1 or not np.all(np.isfinite(a)):
        raise InputError(source, "angles", "finite frame angles, at least one", a.size)
    if not min_drop > 0:
        raise InputError(source, "min_drop", "a collapse size > 0 deg", min_drop)
    b, n_spikes = despike(a, float(min_drop), source)
    idx, _ = find_peaks(b, prominence=float(min_drop))
    peaks = b[[i for i in idx if _fall_seen(b, i, min_drop)]]
    angle = float(peaks.mean()) if peaks.size else float(a.mean())
    return dict(angle_deg=angle, n_avalanches=int(peaks.size),
                peaks_deg=[float(v) for v in peaks], n_spikes=n_spikes)


def _fall_seen(b, i, drop) -> bool:
    """True when some frame after peak ``i``, before the series rises above the peak again
    and before the last frame, lies ``drop`` or more below it: a fall that only the last
    frame shows (one neighbour, so no lone-frame test) is not taken for a collapse."""
    higher = np.nonzero(b[i + 1:] > b[i])[0]
    end = i + 1 + (int(higher[0]) if higher.size else b.size - i - 1)
    seg = b[i + 1:min(end, b.size - 1)]
    return bool(seg.size) and float(seg.min()) <= b[i] - drop


def despike(a, jump, source="<measurement>") -> tuple[np.ndarray, int]:
    """(series, count): every interior value lying ``jump`` or more above both neighbours,
    or as far below both, replaced by the median of the three (the nearer neighbour),
    repeated until no such value is left (a zig-zag of misfits, up next to down, leaves no
    new lone frame behind); ``count`` is the number of replacements.  Two adjacent outliers
    on the same side are kept (neither lies beyond both of its neighbours), and so is a
    value on the first or the last frame (one neighbour only; :func:`avalanche_angle` does
    not count a fall that only the last frame shows).  A real peak is replaced too when the frame
    before it lies ``jump`` or more below it, i.e. when the frame jitter reaches ``jump``
    minus the rise per frame."""
    if not jump > 0:
        raise InputError(source, "jump", "an outlier size > 0", jump)
    b = np.asarray(a, float).copy()
    count = 0
    for _ in range(b.size):
        if b.size < 3:
            break
        lo = np.minimum(b[:-2], b[2:])
        hi = np.maximum(b[:-2], b[2:])
        mid = b[1:-1]
        up = mid - hi >= jump
        down = lo - mid >= jump
        if not (up.any() or down.any()):
            break
        new = np.where(up, hi, np.where(down, lo, mid))
        b[1:-1] = new
        count += int(up.sum() + down.sum())
    return b, count


def mean_sd(values) -> tuple[float, float]:
    v = np.asarray(values, float)
    return float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else 0.0


# ---------------------------------------------------------------- compression
def stress_strain(z_rod, force_z, rod_radius, h0, tube_floor=0.0):
    """(strain, stress) arrays: sigma = F_z / (pi R_rod^2), eps = (h0 - (z_rod - floor)) / h0."""
    z = np.asarray(z_rod, float)
    f = np.asarray(force_z, float)
    if not (rod_radius > 0 and h0 > 0):
        raise InputError("<measurement>", "rod_radius/h0", "positive lengths", (rod_radius, h0))
    eps = (h0 - (z - tube_floor)) / h0
    sigma = f / (math.pi * rod_radius**2)
    return eps, sigma


def unloaded_strain(eps_end, sig_end, eps_up, sig_up):
    """Strain at which the stress of an unloading path first reaches zero: linear
    interpolation between the last loaded sample (the loading's end, ``eps_end``/``sig_end``,
    then the unloading samples in order) and the first with zero or negative stress; NaN when
    the path never unloads fully."""
    e_prev, s_prev = float(eps_end), float(sig_end)
    for e, s in zip(np.asarray(eps_up, float), np.asarray(sig_up, float)):
        if s <= 0.0:
            if s_prev <= 0.0:
                return e_prev
            return e_prev + (e - e_prev) * s_prev / (s_prev - s)
        e_prev, s_prev = e, s
    return float("nan")


def value_at(x, y, x0):
    """y at x0 by linear interpolation on the increasing part of x (NaN outside the data)."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    if x.size < 2 or x0 < x.min() or x0 > x.max():
        return float("nan")
    order = np.argsort(x, kind="stable")
    return float(np.interp(x0, x[order], y[order]))
