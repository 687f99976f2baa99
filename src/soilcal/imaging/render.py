"""Seeded photo renderer: soil heaps, rotating-drum frames and a furrow cross-section.

Geometry (world units mm, x right, y away from the camera, z up):

* Heap: height field over the plate, a cone per azimuth sector (left/right/front/back slope
  angles alpha_k, sectors of 90 deg blended over +/-6 deg at the diagonals) with a rounded top
  (parabolic cap tangent to the cone at r_c), a concave toe
  h = h_t exp(-(r - r_t) tan(alpha) / h_t) (continuous in value and slope at r_t) and
  particle-scale roughness (Gaussian-filtered noise, std ~0.3 mm).  In a horizontal side view
  with weak perspective (uniform scale s px/mm) the silhouette of each straight flank has
  exactly the slope tan(alpha) relative to the plate; the flank angle is the ground truth.
* Drum: 25 % fill; the free surface is the chord at angle theta whose circular segment holds
  the fill, A = R^2 acos(d/R) - d sqrt(R^2 - d^2); a symmetric bulge and grain noise (no
  tilt) are added.  Per-frame angles scatter around the printed mean with zero mean.
* Furrow: the soil face below z = F(x) (Eq. 3 of 000) on the profile-meter span, seen
  square-on in front of a gridded profile board; the meter beam (scale reference, known
  length = span) hangs above the furrow with its lower edge at ``beam_datum_mm``.

Shading: Lambert n.L with ambient term and multi-scale albedo texture, a cast shadow of the
heap on the back wall (silhouette shifted along the light direction, blurred), uneven
illumination (linear + radial gradient), clutter on the wall, a steel plate, a checker
scale bar, camera roll (rotation about the image centre), optical blur, sensor noise and
JPEG (quality 85).  Every random choice comes from ``numpy.random.default_rng(seed)``; the
ground truth (angles, roll, pixel scale, seed) is returned and written to a sidecar
``<photo>.truth.json`` that the measurement code never reads.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from scipy import ndimage as ndi
from skimage.transform import rotate

W, H = 1200, 900
MARGIN = 60

SOIL_COLOURS = {
    "cinnamon-soil": (0.60, 0.45, 0.31),
    "black-soil": (0.25, 0.21, 0.18),
    "xinjiang-vineyard": (0.62, 0.55, 0.45),
    "guangxi-cohesive": (0.55, 0.34, 0.24),
    "yangtze-clay-loam": (0.45, 0.36, 0.28),
}


def _noise(rng, shape, sigma):
    n = ndi.gaussian_filter(rng.standard_normal(shape), sigma)
    n /= n.std() + 1e-12
    return n


def _texture(rng, shape):
    """Multi-scale albedo texture 0.55 n_1 + 0.3 n_4 + 0.25 n_15 (n_sigma: unit-std noise
    smoothed over sigma px), drawn in that order."""
    t = _noise(rng, shape, 1.0)
    t *= 0.55
    for a, sigma in ((0.3, 4.0), (0.25, 15.0)):
        n = _noise(rng, shape, sigma)
        n *= a
        t += n
    return t


def _wall(rng, h, w, hard, avoid=None, floor_row=None, style=None):
    """Back wall with uneven light and clutter; ``avoid`` = (r0, r1, c0, c1) kept free and
    clutter hangs on the wall (ends 20 px above ``floor_row``, the plate).  ``style`` (stress
    photos) may set ``wall_rgb``, ``wall_gradient`` (relative change across the wall, (x, y)),
    ``wall_texture`` (amplitude of a mottled texture) and ``clutter`` (False: a plain wall)."""
    style = style or {}
    base = np.array([0.20, 0.19, 0.18]) if hard else np.array([0.80, 0.78, 0.74])
    if "wall_rgb" in style:
        base = np.asarray(style["wall_rgb"], float)
    base = base * (1 + 0.02 * rng.standard_normal(3))
    img = np.empty((h, w, 3))
    img[...] = base
    img *= _one_plus(0.03, _noise(rng, (h, w), 20.0))[..., None]
    rr, cc = np.arange(h)[:, None], np.arange(w)[None, :]  # broadcast as np.mgrid's rows, columns
    if "wall_gradient" in style:
        gx, gy = style["wall_gradient"]
        img *= (1 + gx * (cc / w - 0.5) + gy * (rr / h - 0.5))[..., None]
    if style.get("wall_texture"):
        img *= _one_plus(style["wall_texture"], _texture(rng, (h, w)))[..., None]
    for _ in range(int(rng.integers(6, 12)) if style.get("clutter", True) else 0):
        hh, ww = rng.integers(40, 220, size=2)
        r0, c0 = int(rng.integers(0, h - hh)), int(rng.integers(0, w - ww))
        if floor_row is not None and r0 + hh > floor_row - 20:
            continue
        if avoid is not None:
            a0, a1, b0, b1 = avoid
            if r0 < a1 and r0 + hh > a0 and c0 < b1 and c0 + ww > b0:
                continue
        col = rng.uniform(0.35, 0.95, 3) if not hard else rng.uniform(0.1, 0.35, 3)
        if rng.random() < 0.5:
            box, m = img[r0:r0 + hh, c0:c0 + ww], np.s_[...]
        else:  # the ellipse inscribed in rows r0..r0 + hh, columns c0..c0 + ww (ends included)
            box = img[r0:r0 + hh + 1, c0:c0 + ww + 1]
            br, bc = rr[r0:r0 + hh + 1], cc[:, c0:c0 + ww + 1]
            m = ((br - r0 - hh / 2) / (hh / 2)) ** 2 + ((bc - c0 - ww / 2) / (ww / 2)) ** 2 <= 1
        box[m] = col * (1 + 0.04 * rng.standard_normal())
    return ndi.gaussian_filter(img, (1.5, 1.5, 0))


def _one_plus(a, x):
    """1 + a x, computed in place in ``x``."""
    x *= a
    x += 1
    return x


def _light_field(rng, h, w, strength):
    """Uneven illumination: a linear gradient times a radial fall-off (rows and columns
    scaled by the longer side)."""
    rr, cc = np.arange(h)[:, None] / max(h, w), np.arange(w)[None, :] / max(h, w)
    g = rng.uniform(-1, 1) * (cc - 0.5) + rng.uniform(-1, 1) * (rr - 0.5)
    g = _one_plus(strength, g)
    r2 = (cc - rng.uniform(0.3, 0.7)) ** 2 + (rr - rng.uniform(0.2, 0.6)) ** 2
    r2 *= 0.35 * strength
    np.subtract(1, r2, out=r2)
    g *= r2
    return g


def _plate(img, rng, row, c0, c1, thick_px, grey=0.68, rgb=(0.97, 0.99, 1.0), highlight=True):
    """Plate seen edge-on: top edge at ``row``, brushed front face of mean ``grey`` tinted
    ``rgb`` (steel by default), a bright chamfer along the top edge if ``highlight``."""
    h = img.shape[0]
    r1 = min(h, row + thick_px)
    face = grey + 0.08 * _noise(rng, (r1 - row, c1 - c0), 0.7)[:, :] * 0.3
    face += 0.10 * np.linspace(1, -1, r1 - row)[:, None]
    img[row:r1, c0:c1] = np.clip(face, 0, 1)[..., None] * np.asarray(rgb)
    if highlight:
        img[row:row + 2, c0:c1] = 0.92  # bright chamfer highlight along the top edge


def _table(img, rng, row):
    h, w, _ = img.shape
    grain = _noise(rng, (h - row, w), (1.0, 25.0))
    img[row:] = (np.array([0.45, 0.33, 0.22]) * (1 + 0.12 * grain)[..., None])


def _scale_bar(img, row, col, s, squares=10, size_mm=10.0):
    """Checker bar, ``squares`` x 2 squares of ``size_mm``; returns its length in mm."""
    q = size_mm * s
    for i in range(squares):
        for j in range(2):
            v = 0.05 if (i + j) % 2 == 0 else 0.95
            r0, c0 = int(round(row + j * q)), int(round(col + i * q))
            img[r0:int(round(row + (j + 1) * q)), c0:int(round(col + (i + 1) * q))] = v
    return squares * size_mm


def _finish(rng, canvas, roll_deg, hard, style=None):
    """Camera: roll about the image centre, crop, blur, vignetting, noise; ``style`` may set
    ``blur_px``, ``exposure`` (a gain: under < 1 < over, clipped) and ``noise``."""
    style = style or {}
    # scikit-image's rotate of each channel alone (the same interpolation as of the three at
    # once), cropped into one array, then clipped to the canvas's range as rotate clips
    img = np.empty((H, W, canvas.shape[2]))
    for k in range(canvas.shape[2]):
        img[..., k] = rotate(canvas[..., k], roll_deg, order=1, mode="edge", clip=False)[MARGIN:MARGIN + H,
                                                                                           MARGIN:MARGIN + W]
    np.clip(img, canvas.min(), canvas.max(), out=img)
    b = style.get("blur_px", 0.8)
    img = ndi.gaussian_filter(img, (b, b, 0))
    img *= _light_field(rng, H, W, 0.15)[..., None]
    img *= style.get("exposure", 1.0)
    img += rng.normal(0, style.get("noise", 0.012 if not hard else 0.02), img.shape)
    np.clip(img, 0, 1, out=img)
    img *= 255
    img += 0.5
    return img.astype(np.uint8)


def _sector_tan(phi, right, back, left, front, blend_deg=6.0):
    """tan(alpha) for azimuth phi (rad, 0 = +x right, pi/2 = +y away); 90-deg sectors."""
    tans = np.tan(np.radians([right, back, left, front]))
    centres = np.radians([0.0, 90.0, 180.0, 270.0])
    wsum = np.zeros_like(phi)
    tsum = np.zeros_like(phi)
    for t, c in zip(tans, centres):
        d = np.abs((phi - c + np.pi) % (2 * np.pi) - np.pi)
        wk = np.clip((np.radians(45.0 + blend_deg) - d) / np.radians(2 * blend_deg), 0, 1)
        wsum += wk
        tsum += wk * t
    return tsum / wsum


def heap_height(x, y, slopes, r0, rng=None, rough=0.15):
    """Height field (mm) of the heap; ``slopes`` = (right, back, left, front) in deg."""
    r = np.hypot(x, y)
    t = _sector_tan(np.arctan2(y, x), *slopes)
    tm = np.tan(np.radians(np.mean(slopes)))
    H0 = r0 * tm
    rc = 0.22 * r0 * tm / t
    ht = 0.10 * H0
    rt = (H0 - ht) / t
    h = H0 - r * t
    cap = r < rc
    h[cap] = (H0 - t * (r ** 2 + rc ** 2) / (2 * rc))[cap]
    toe = r > rt
    h[toe] = (ht * np.exp(-(r - rt) * t / ht))[toe]
    if rng is not None and rough > 0:
        h = h + rough * _noise(rng, h.shape, 2.0) * np.clip(h / ht, 0, 1)
    h[h < 0.3] = 0.0
    return h


def render_pile(seed, left_deg, right_deg, front_deg=None, back_deg=None, soil="cinnamon-soil",
                hard=False, roll_deg=None, n_heaps=1, cut=False, style=None):
    """Render one side-view photo of a heap; returns (uint8 RGB, truth dict).

    ``style`` (stress photos, :mod:`soilcal.imaging.corpus`; None = the documented scene):
    wall keys of :func:`_wall`; ``soil_rgb``; ``shadow`` = {"dx_mm", "dy_mm", "blur_px",
    "darkness"}; ``plate`` = {"thick_mm", "grey", "rgb", "highlight"}; ``table_rgb``;
    ``offset_frac`` (heap centre shift, fraction of the width); ``scale_bar`` (False: none);
    camera keys of :func:`_finish`.
    """
    style = style or {}
    rng = np.random.default_rng(seed)
    front_deg = (left_deg + right_deg) / 2 if front_deg is None else front_deg
    back_deg = (left_deg + right_deg) / 2 if back_deg is None else back_deg
    slopes = (right_deg, back_deg, left_deg, front_deg)
    if roll_deg is None:
        roll_deg = float(rng.uniform(-3, 3) if hard else rng.uniform(-1.5, 1.5))
    s = float(rng.uniform(2.6, 3.2)) / (1.6 if n_heaps == 2 else 1.0)
    r0 = float(rng.uniform(85, 100))
    ch, cw = H + 2 * MARGIN, W + 2 * MARGIN
    row_p = int(MARGIN + rng.uniform(0.68, 0.76) * H)
    centres = [cw / 2 + rng.uniform(-50, 50) + style.get("offset_frac", 0.0) * W]
    if n_heaps == 2:
        centres = [cw / 2 - 0.25 * W, cw / 2 + 0.25 * W]
    if cut:
        centres = [MARGIN + 0.12 * W]
    if n_heaps == 0:  # an empty plate
        centres = []
    tm = np.tan(np.radians(np.mean(slopes)))
    apex_row = row_p - r0 * tm * s
    reach = int(1.6 * r0 * s)
    avoid = (int(apex_row - 80), row_p, int(min(centres, default=cw / 2) - reach - 40),
             int(max(centres, default=cw / 2) + reach + 40))
    canvas = _wall(rng, ch, cw, hard, avoid, row_p, style)
    light = np.array([-0.55, -0.55, 0.63]) * np.array([rng.uniform(0.7, 1.3), 1, 1])
    light = light / np.linalg.norm(light)
    albedo = np.array(SOIL_COLOURS.get(soil, SOIL_COLOURS["cinnamon-soil"]))
    if hard:
        albedo = np.array(SOIL_COLOURS["black-soil"]) * 0.9
    if "soil_rgb" in style:
        albedo = np.asarray(style["soil_rgb"], float)
    sil_all = np.zeros((ch, cw), bool)
    layers = []
    for cx in centres:
        c_lo = max(0, int(cx - reach))
        cols = np.arange(c_lo, min(cw, int(cx + reach)))
        xs = (cols - cx) / s
        ys = np.arange(-1.6 * r0, 1.6 * r0, 0.4)
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        h = heap_height(X, Y, slopes, r0, rng)
        gx, gy = np.gradient(h, xs, ys)
        n = np.stack([-gx, -gy, np.ones_like(h)], -1)
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        shade = 0.35 + 0.8 * np.clip(n @ light, 0, None)
        tex = 1 + 0.12 * _texture(rng, h.shape)
        sil = h.max(axis=1)
        front = np.maximum.accumulate(h[:, : len(ys) // 2 + 1], axis=1)
        # the heap's pixels lie in rows 0..row_p - 1 of its columns: the layer and its mask
        # cover that box of the canvas only
        layer = np.zeros((row_p, len(cols), 3))
        lm = np.zeros((row_p, len(cols)), bool)
        for i, c in enumerate(cols):
            top = sil[i] * s
            if top <= 0:
                continue
            rows = np.arange(int(np.ceil(row_p - top)), row_p)
            z = (row_p - rows) / s
            j = np.minimum(np.searchsorted(front[i], z), front.shape[1] - 1)
            v = shade[i, j] * tex[i, j]
            if rows.size and rows[0] < 0:
                raise ValueError(f"heap {top:.0f} px high does not fit above the plate row {row_p}")
            layer[rows, i] = v[:, None] * albedo
            lm[rows, i] = True
        box = np.s_[:row_p, c_lo:c_lo + len(cols)]
        layers.append((box, layer, lm))
        sil_all[box] |= lm
    # cast shadow on the wall, then heap(s)
    dx, dy = int(round(-light[0] / light[2] * 25 * s * 0.3)), int(round(8 * s * 0.3))
    sh = style.get("shadow", {})
    if sh:
        dx, dy = int(round(sh["dx_mm"] * s)), int(round(sh["dy_mm"] * s))
    shadow = np.roll(sil_all, (dy, dx), axis=(0, 1)).astype(float)
    shadow = ndi.gaussian_filter(shadow, sh.get("blur_px", 2.0 if hard else 7.0))
    shadow *= sh.get("darkness", 0.55 if hard else 0.25)
    canvas *= np.subtract(1, shadow, out=shadow)[..., None]
    for box, layer, lm in layers:
        canvas[box][lm] = layer[lm]
    # crumbs on the plate next to the toe: half ellipses above row_p, evaluated in their
    # bounding box (a pixel beyond it lies a pixel or more outside the ellipse)
    for _ in range(int(rng.integers(4, 10)) if centres else 0):
        side = rng.choice([-1, 1])
        cx = centres[0] + side * rng.uniform(1.15, 1.45) * r0 * s
        a, b = rng.uniform(1.0, 3.0) * s, rng.uniform(0.8, 2.0) * s
        r_lo = min(max(0, int(np.floor(row_p - b)) - 1), row_p)
        c_lo, c_hi = min(max(0, int(np.floor(cx - a)) - 1), cw), min(max(0, int(np.ceil(cx + a)) + 2), cw)
        rr, cc = np.arange(r_lo, row_p)[:, None], np.arange(c_lo, c_hi)[None, :]
        m = ((cc - cx) / a) ** 2 + ((rr - row_p) / b) ** 2 <= 1
        canvas[r_lo:row_p, c_lo:c_hi][m] = albedo * rng.uniform(0.6, 1.0)
    pl = style.get("plate", {})
    thick = int(pl.get("thick_mm", 6) * s)
    _plate(canvas, rng, row_p, 0, cw, thick, pl.get("grey", 0.68), pl.get("rgb", (0.97, 0.99, 1.0)),
           pl.get("highlight", True))
    _table(canvas, rng, row_p + thick)
    if "table_rgb" in style:
        canvas[row_p + thick:] *= (np.asarray(style["table_rgb"]) / np.array([0.45, 0.33, 0.22]))
    bar_col = int(MARGIN + rng.uniform(0.05, 0.6) * W)
    bar_len = _scale_bar(canvas, row_p + int((pl.get("thick_mm", 6) + 6) * s), bar_col, s) if style.get("scale_bar", True) else 0.0
    img = _finish(rng, canvas, roll_deg, hard, style)
    truth = {
        "kind": "pile", "seed": int(seed), "left_deg": float(left_deg), "right_deg": float(right_deg),
        "front_deg": float(front_deg), "back_deg": float(back_deg),
        "angle_deg": float((left_deg + right_deg) / 2), "roll_deg": float(roll_deg),
        "px_per_mm": s, "scale_bar_mm": bar_len, "hard": bool(hard), "n_heaps": n_heaps, "cut": cut,
    }
    return img, truth


def segment_fill(radius, fill):
    """Signed distance d of the chord below the centre whose segment holds ``fill`` of the disc
    (d < 0: the chord above the centre, fill > 1/2)."""
    from scipy.optimize import brentq

    target = fill * np.pi * radius ** 2
    return brentq(lambda d: radius ** 2 * np.arccos(d / radius) - d * np.sqrt(radius ** 2 - d ** 2) - target,
                  -radius * (1 - 1e-9), radius * (1 - 1e-9))


def render_drum(seed, angle_deg, soil="xinjiang-vineyard", fill=0.25, hard=False, roll_deg=None):
    """One front-view frame of the rotating drum; free surface at ``angle_deg``."""
    rng = np.random.default_rng(seed)
    if roll_deg is None:
        roll_deg = float(rng.uniform(-3, 3) if hard else rng.uniform(-1.5, 1.5))
    s = float(rng.uniform(2.8, 3.2))
    R = 100.0
    ch, cw = H + 2 * MARGIN, W + 2 * MARGIN
    row_p = int(MARGIN + 0.86 * H)
    cx, cz = cw / 2 + rng.uniform(-40, 40), row_p - (R + 22) * s
    canvas = _wall(rng, ch, cw, hard, (int(cz - 1.2 * R * s), row_p, int(cx - 1.2 * R * s), int(cx + 1.2 * R * s)))
    rr, cc = np.mgrid[0:ch, 0:cw]
    X, Z = (cc - cx) / s, (cz - rr) / s
    rad = np.hypot(X, Z)
    inside = rad < R
    canvas[inside] = np.array([0.88, 0.88, 0.86]) * (1 + 0.02 * _noise(rng, (ch, cw), 8.0))[inside][:, None]
    th = np.radians(angle_deg)
    d = segment_fill(R, fill)
    u = X * np.cos(th) + Z * np.sin(th)
    nrm = -X * np.sin(th) + Z * np.cos(th)
    L = np.sqrt(R ** 2 - d ** 2)
    bulge = 1.2 * np.cos(np.pi * np.clip(u / L, -1, 1) / 2) + 0.25 * _noise(rng, (1, cw * 2), 3.0)[0, np.clip((u * s + cw).astype(int), 0, 2 * cw - 1)]
    soil_m = inside & (nrm < -d + bulge)
    albedo = np.array(SOIL_COLOURS.get(soil, SOIL_COLOURS["xinjiang-vineyard"]))
    tex = 1 + 0.12 * _texture(rng, (ch, cw))
    canvas[soil_m] = (albedo * (0.85 + 0.1 * (nrm[soil_m] / R))[:, None]) * tex[soil_m][:, None]
    ring = (rad >= R) & (rad < R + 6)
    canvas[ring] = np.array([0.55, 0.56, 0.58]) * (1 + 0.2 * np.cos(np.arctan2(Z, X)[ring] * 2))[:, None]
    # stand legs and base plate
    for sgn in (-1, 1):
        leg = (np.abs(X - sgn * 0.6 * R) < 4) & (Z < -0.75 * R) & (rr < row_p)
        canvas[leg] = 0.5
    _plate(canvas, rng, row_p, 0, cw, int(6 * s))
    _table(canvas, rng, row_p + int(6 * s))
    _scale_bar(canvas, row_p + int(10 * s), int(MARGIN + 0.05 * W), s)
    img = _finish(rng, canvas, roll_deg, hard)
    # the drum's centre in the photo: turned with the canvas about its centre (counter-clockwise
    # by the roll, as skimage's rotate), then cropped by the margin
    c0, r0 = cw / 2 - 0.5, ch / 2 - 0.5
    t = np.radians(roll_deg)
    px = c0 + (cx - c0) * np.cos(t) + (cz - r0) * np.sin(t) - MARGIN
    py = r0 - (cx - c0) * np.sin(t) + (cz - r0) * np.cos(t) - MARGIN
    truth = {"kind": "drum", "seed": int(seed), "angle_deg": float(angle_deg), "roll_deg": float(roll_deg),
             "px_per_mm": s, "fill": fill, "drum_radius_mm": R, "centre_px": [float(px), float(py)],
             "radius_px": float(R * s)}
    return img, truth


def render_tester_frame(seed, angle_deg, fill=0.35, s_amp=0.0, size=(600, 640), window="crop", blur_px=2.0,
                        jitter_px=3.0, n_avg=16, powder_dark=True, noise=0.01, chord_fraction=0.6,
                        offset_px=(0.0, 0.0), haze=0.0, specks=0, gradient=0.1, surround=None):
    """A drum tester's exported frame: grey, time-averaged, no plate; ``(image in [0, 1], truth)``.

    Drum of radius R px centred in the frame (``window``: "crop" = cropped to the drum, the
    corners the dark drum body; "rim" = a thin dark rim circle on the white backlight, off
    centre; "plain" = the same drum without a rim ring, on a ``surround`` grey; "inside" = the frame lies inside a larger drum, no rim in view).  The free surface
    in the chord frame (u along the chord at ``angle_deg``, n normal, xi = u / L, L the half
    chord at fill ``fill``) is

        n(xi) = -d - sgn(angle) s_amp L (xi^3 - k xi),   k = 3 w^2 / 5,  w = ``chord_fraction``,

    a cubic S (middle steeper than the ends for s_amp > 0, whichever way the surface rises) whose cubic part is orthogonal to a
    line over |xi| <= w.  The truth ``angle_deg`` is the central slope as defined for drums: the
    least-squares line z = a + b x through the exact curve sampled uniformly in x (one point
    per image column, as a frame is read), over the columns under the central
    ``chord_fraction`` of the surface's chord (the segment between the curve's two crossings
    of the drum circle, centred on the foot of the perpendicular from the drum centre); equal to ``angle_deg`` for s_amp = 0 and
    computed from the curve otherwise (``param_angle_deg`` keeps the parameter).
    Time averaging: ``n_avg`` frames with the surface shifted normal to itself by a symmetric
    set of offsets (std ``jitter_px``, median zero), then a Gaussian blur ``blur_px``; static
    powder texture, an illumination gradient ``gradient`` across the frame and sensor noise
    ``noise``.  ``offset_px`` moves the drum from the frame centre (a cropped drum then runs
    past the border); ``haze`` is the grey of particles flying above the surface (decaying
    over 3 % of the radius), ``specks`` the number of dust specks on the window, ``surround``
    the grey outside the drum (default: the dark drum body for "crop", the backlight for "rim",
    mid grey for "plain").
    """
    rng = np.random.default_rng(seed)
    h, w = size
    if window == "crop":
        R, cx, cy = min(h, w) / 2.0 - 1.0, (w - 1) / 2.0, (h - 1) / 2.0
    elif window in ("rim", "plain"):
        R, cx, cy = 0.42 * min(h, w), (w - 1) / 2.0 + 17.0, (h - 1) / 2.0 - 9.0
    elif window == "inside":
        R, cx, cy = 0.75 * float(np.hypot(h, w)) / 2.0, (w - 1) / 2.0, (h - 1) / 2.0
    else:
        raise ValueError(f"window must be 'crop', 'rim', 'plain' or 'inside', got {window!r}")
    cx, cy = cx + offset_px[0], cy + offset_px[1]
    rr, cc = np.mgrid[0:h, 0:w].astype(float)
    x, z = cc - cx, cy - rr
    th = np.radians(angle_deg)
    u = x * np.cos(th) + z * np.sin(th)
    nrm = -x * np.sin(th) + z * np.cos(th)
    d = segment_fill(R, fill)
    L = np.sqrt(R ** 2 - d ** 2)
    xi = u / L
    k = 3.0 * chord_fraction ** 2 / 5.0
    s_signed = s_amp * (1.0 if angle_deg >= 0 else -1.0)  # cascading whichever way the surface rises
    n_s = -d - s_signed * L * (xi ** 3 - k * xi)
    half = rng.normal(0.0, 1.0, n_avg // 2)
    offs = np.concatenate([half, -half]) * jitter_px
    # cover = mean over the offsets of clip(0.5 + (n_s + o - nrm), 0, 1): a pixel more than
    # 0.5 + max |o| (and a pixel's margin for rounding) above or below the surface is 0 or 1 for
    # every offset, so its mean is exactly 0.0 or 1.0; only the band along the surface is summed,
    # offset by offset in the same order as over the whole frame
    gap = n_s - nrm
    band = np.abs(gap) < 1.5 + np.abs(offs).max() if len(offs) else np.ones(gap.shape, bool)  # none: 0 / 0
    cover = (gap > 0).astype(float)
    ns_b, nrm_b = n_s[band], nrm[band]
    acc, part = np.zeros(ns_b.size), np.empty(ns_b.size)
    for o in offs:  # acc += clip(0.5 + (n_s + o - nrm), 0, 1), in place
        np.add(ns_b, o, out=part)
        part -= nrm_b
        part += 0.5
        acc += np.clip(part, 0.0, 1.0, out=part)
    acc /= len(offs)
    cover[band] = acc
    air, powder = (0.92, 0.22) if powder_dark else (0.12, 0.78)
    tex = 1.0 + 0.06 * _noise(rng, (h, w), 2.0)
    img = air + (powder * tex - air) * cover
    if haze:
        above = np.clip(nrm - n_s, 0.0, None)
        img = img + (powder - air) * haze * np.exp(-above / (0.03 * R)) * (1.0 - cover)
    for _ in range(int(specks)):
        sr, sc, sz = rng.uniform(0, h), rng.uniform(0, w), rng.uniform(1.0, 3.0)
        img = img + (powder - air) * 0.6 * np.exp(-((rr - sr) ** 2 + (cc - sc) ** 2) / (2 * sz ** 2))
    rad = np.hypot(x, z)
    disc = np.clip(0.5 + (R - rad), 0.0, 1.0)
    if window == "crop":
        out = 0.06 if surround is None else surround
        img = out + (img - out) * disc
    elif window == "rim":
        out = air if surround is None else surround
        ring = np.clip(0.5 + (R + 4.0 - rad), 0.0, 1.0) - disc
        rim = 0.15 if powder_dark else 0.85  # a dark rim on the backlight, a bright one on a dark ground
        img = img * disc + (1.0 - disc) * out + ring * (rim - out)
    elif window == "plain":
        out = 0.5 if surround is None else surround
        img = img * disc + (1.0 - disc) * out
    img = ndi.gaussian_filter(img, blur_px) if blur_px > 0 else img
    img = img * (1.0 + gradient * (cc / w - 0.5)) + noise * rng.standard_normal((h, w))
    truth = {"kind": "drum-tester", "seed": int(seed), "param_angle_deg": float(angle_deg),
             "angle_deg": _central_slope(th, d, L, R, s_signed, k, chord_fraction), "s_amp": float(s_amp),
             "fill": float(fill), "window": window, "centre_px": [float(cx), float(cy)], "radius_px": float(R),
             "blur_px": float(blur_px), "jitter_px": float(jitter_px), "n_avg": int(n_avg),
             "chord_fraction": float(chord_fraction), "powder_dark": bool(powder_dark), "haze": float(haze),
             "specks": int(specks), "noise": float(noise), "size": [int(h), int(w)],
             "surround": None if surround is None else float(surround)}
    return np.clip(img, 0.0, 1.0), truth


def _central_slope(th, d, L, R, s_amp, k, fraction):
    """Central-chord slope (deg, signed) of the curve n(u) = -d - s_amp L (xi^3 - k xi)."""
    uu = np.linspace(-1.5 * R, 1.5 * R, 60001)
    xi = uu / L
    nn = -d - s_amp * L * (xi ** 3 - k * xi)
    x = uu * np.cos(th) - nn * np.sin(th)
    z = uu * np.sin(th) + nn * np.cos(th)
    ins = np.flatnonzero(x ** 2 + z ** 2 <= R ** 2)
    a = np.array([x[ins[0]], z[ins[0]]])
    b = np.array([x[ins[-1]], z[ins[-1]]])
    e = (b - a) / np.linalg.norm(b - a)
    foot = a - (a @ e) * e
    half = np.sqrt(R ** 2 - foot @ foot)
    win = (np.abs(x - foot[0]) <= fraction * half * abs(e[0])) & (x ** 2 + z ** 2 <= R ** 2)
    order = np.argsort(x[win])
    xs = np.linspace(x[win].min(), x[win].max(), 4001)
    zs = np.interp(xs, x[win][order], z[win][order])
    return float(np.degrees(np.arctan(np.polyfit(xs, zs, 1)[0])))


def save_frame(path, img, bits=8):
    """Write a grey frame (values in [0, 1]) as an 8- or 16-bit single-channel image; the format
    follows the suffix (BMP holds 8 bits only)."""
    from PIL import Image

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if bits == 8:
        Image.fromarray(np.round(img * 255).astype(np.uint8), mode=None).save(path)
    elif bits == 16 and path.suffix.lower() != ".bmp":
        Image.fromarray(np.round(img * 65535).astype(np.uint16)).save(path)
    else:
        raise ValueError(f"{path}: {bits}-bit frames cannot be written in this format")
    return path


def render_furrow(seed, coeffs, span_mm, beam_datum_mm=180.0, soil="yangtze-clay-loam", roll_deg=None,
                  style=None, profile=None):
    """Furrow cross-section in front of a gridded profile board, meter beam above.  The soil's
    top F(x) (mm) is the polynomial of ``coeffs`` (highest power first), or with ``profile``
    (``[xs, zs]``, xs increasing over the span) the polygon through those vertices, corners
    and flat stretches as an opener leaves them (``coeffs`` then None); the truth's area is
    that of the chord over F either way, exact.  ``style``
    (stress photos; absent: the shipped photo's look) may set ``board_rgb``, ``grid_rgb``,
    ``grid_mm`` (0: no grid), ``board_gradient`` (relative change across the board, (x, y)),
    ``soil_rgb``, ``soil_shading`` (relative darkening of the soil face from top to bottom),
    ``beam_rgb``, ``beam_mm`` (its height), ``beam_shadow`` ({dx_mm, dy_mm, blur_px,
    darkness}: the beam's shadow cast on the board), ``wall_rgb`` and ``clutter`` (the wall
    around the board), and the camera's ``blur_px``, ``exposure`` and ``noise``."""
    rng = np.random.default_rng(seed)
    if roll_deg is None:
        roll_deg = float(rng.uniform(-1.5, 1.5))
    st = style or {}
    a, b = span_mm
    s = float(W * 0.85 / (b - a + 60))
    ch, cw = H + 2 * MARGIN, W + 2 * MARGIN
    cx = cw / 2 + rng.uniform(-20, 20)
    z0_row = MARGIN + 0.80 * H  # row of F = 0
    rr, cc = np.arange(ch)[:, None], np.arange(cw)[None, :]  # broadcast as np.mgrid's rows, columns
    X, Z = (cc - cx) / s, (z0_row - rr) / s  # X a row, Z a column: the masks below broadcast to the canvas
    board = np.empty((ch, cw, 3))
    board[...] = np.array(st.get("board_rgb", [0.93, 0.93, 0.90]))
    if "board_gradient" in st:
        gx, gy = st["board_gradient"]
        board *= (1 + gx * (cc / cw - 0.5) + gy * (rr / ch - 0.5))[..., None]
    pitch = float(st.get("grid_mm", 20.0))
    if pitch > 0:
        half = pitch / 2
        grid = (np.abs(((X + 1000) % pitch) - half) > half - 0.4) | (np.abs(((Z + 1000) % pitch) - half) > half - 0.4)
        board[grid] = np.array(st.get("grid_rgb", [0.55, 0.6, 0.7]))
    board *= _one_plus(0.02, _noise(rng, (ch, cw), 10.0))[..., None]
    bh = float(st.get("beam_mm", 12.0))
    sh = st.get("beam_shadow")
    if sh and sh.get("darkness", 0) > 0:
        m = ((X >= a + sh["dx_mm"]) & (X <= b + sh["dx_mm"]) & (Z >= beam_datum_mm - sh["dy_mm"])
             & (Z < beam_datum_mm + bh - sh["dy_mm"])).astype(float)
        m = ndi.gaussian_filter(m, sh.get("blur_px", 4.0))
        board *= (1 - sh["darkness"] * m)[..., None]
    canvas = _wall(rng, ch, cw, False, None,
                   style={k: st[k] for k in ("wall_rgb", "clutter") if k in st} or None)
    on_board = (X > a - 40) & (X < b + 40) & (Z > -10) & (Z < beam_datum_mm + 60)
    canvas[on_board] = board[on_board]
    xc = np.clip(X[0], a, b)
    if profile is not None:
        px, pz = (np.asarray(v, dtype=float) for v in profile)
        prof = np.interp(xc, px, pz)
    else:
        prof = np.polyval(coeffs, xc)
    soil_m = Z < prof[None, :] + 0.3 * _noise(rng, (1, cw), 1.5)
    albedo = np.array(st.get("soil_rgb", SOIL_COLOURS.get(soil, SOIL_COLOURS["yangtze-clay-loam"])))
    face = albedo * _one_plus(0.12, _texture(rng, (ch, cw)))[soil_m][:, None]
    if st.get("soil_shading"):
        depth = np.clip((prof[None, :] - Z) / 150.0, 0, 1)[soil_m]  # 0 at the surface, 1 150 mm below
        face *= (1 - st["soil_shading"] * depth)[:, None]
    canvas[soil_m] = face
    beam = (X >= a) & (X <= b) & (Z >= beam_datum_mm) & (Z < beam_datum_mm + bh)
    canvas[beam] = np.array(st.get("beam_rgb", [0.08, 0.08, 0.09]))
    img = _finish(rng, canvas, roll_deg, False, style={k: st[k] for k in ("blur_px", "exposure", "noise")
                                                        if k in st} or None)
    from soilcal.imaging.scenes import furrow_chord_area, polyline_chord_area

    if profile is not None:
        # the polygon's exact chord area: its vertices within the span and F at both ends
        inner = (px > a) & (px < b)
        vx = np.concatenate([[a], px[inner], [b]])
        area = polyline_chord_area(vx, np.interp(vx, px, pz))
    else:
        area = furrow_chord_area(a, b, coeffs)  # the chord's area above F on [a, b]
    truth = {"kind": "furrow", "seed": int(seed), "roll_deg": float(roll_deg), "px_per_mm": s,
             "span_mm": [a, b], "beam_datum_mm": beam_datum_mm,
             "coeffs": list(coeffs) if coeffs is not None else None, "area_mm2": area}
    if profile is not None:
        truth["profile"] = [list(map(float, px)), list(map(float, pz))]
    return img, truth


def save_photo(path, img, truth, quality=85):
    """Write the JPEG and its sidecar ``<photo>.truth.json``."""
    from PIL import Image

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(img).save(path, quality=quality)
    Path(str(path) + ".truth.json").write_text(json.dumps(truth, indent=2) + "\n")
    return path


def render_soil(soil, outdir, seed=None):
    """Render every scene of ``soil`` into ``outdir`` and write ``manifest.yaml``."""
    import yaml

    from soilcal.imaging.scenes import FURROW_F_COEFFS, scenes_for

    outdir = Path(outdir)
    base = seed if seed is not None else sum(ord(ch) for ch in soil) * 101
    photos = []
    for k, sc in enumerate(scenes_for(soil)):
        sd = base + 17 * k
        if sc.kind == "pile":
            img, truth = render_pile(sd, sc.left_deg, sc.right_deg, sc.front_deg, sc.back_deg, soil=soil)
            fn = f"{sc.name}.jpg"
            save_photo(outdir / fn, img, truth | {"source": sc.source, "label": sc.label})
            photos.append({"file": fn, "kind": "pile", "view": sc.view, "group": sc.group,
                           "scale_length_mm": truth["scale_bar_mm"], "substrate": sc.substrate})
        elif sc.kind == "drum":
            frng = np.random.default_rng(sd)
            dev = frng.normal(0, 0.4, sc.frames)
            dev -= dev.mean()  # frame angles average exactly to the printed value
            for f in range(sc.frames):
                img, truth = render_drum(sd + f + 1, sc.target_deg + dev[f], soil=soil, fill=sc.extra["fill"])
                fn = f"{sc.name}_f{f + 1:02d}.jpg"
                save_photo(outdir / fn, img, truth | {"source": sc.source, "frame_mean_deg": sc.target_deg})
                photos.append({"file": fn, "kind": "drum", "view": "front", "group": sc.group,
                               "scale_length_mm": 100.0})
        else:
            img, truth = render_furrow(sd, FURROW_F_COEFFS, tuple(sc.extra["span_mm"]), soil=soil)
            fn = f"{sc.name}.jpg"
            save_photo(outdir / fn, img, truth | {"source": sc.source})
            photos.append({"file": fn, "kind": "furrow", "view": "section", "group": sc.group,
                           "scale_length_mm": float(sc.extra["span_mm"][1] - sc.extra["span_mm"][0]),
                           "beam_datum_mm": truth["beam_datum_mm"]})
    manifest = {
        "soil": soil,
        "note": ("Rendered by soilcal.imaging.render (seeded); *.truth.json sidecars hold the "
                 "ground truth and are never read by the measurement. Real photos are added "
                 "here with the same fields."),
        "photos": photos,
    }
    (outdir / "manifest.yaml").write_text(yaml.safe_dump(manifest, sort_keys=False))
    return outdir / "manifest.yaml"
