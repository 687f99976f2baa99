"""Seeded stress corpora: photos as users take them, each with its analytic truth.

:func:`drum_frames` mixes photos of a drum on its stand (:func:`render.render_drum`: colour
JPEG, base plate, camera roll up to 3 deg) and drum testers' exports
(:func:`render.render_tester_frame`: grey 8/16-bit PNG/TIFF/BMP, cropped to the drum, off
centre or running past the border, rim rings, drums on a plain surround of any grey, frames
inside a larger drum, averaged soft
interfaces, S-shaped surfaces rising to either side, inverted polarity, haze of flying
particles, dust specks, illumination gradients, noise).  :func:`pile_photo_params`: heap
photos; :func:`furrow_photo_params`: furrow cross-sections in front of a profile board.  Every
parameter is drawn from ``numpy.random.default_rng(seed)`` and returned with the photo.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from soilcal.imaging import render


def drum_frame_params(n, seed=0):
    """Parameter sets of ``n`` stress frames (one in four a stand photo)."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        fs = int(rng.integers(0, 2 ** 31 - 1))
        angle = float(rng.uniform(20.0, 55.0))
        if k % 4 == 0:
            out.append({"kind": "stand", "seed": fs, "angle_deg": angle, "fill": float(rng.uniform(0.2, 0.4)),
                        "hard": bool(rng.random() < 0.3), "roll_deg": float(rng.uniform(-3.0, 3.0))})
            continue
        h = int(rng.integers(400, 900))
        window = str(rng.choice(["crop", "crop", "rim", "plain", "inside"]))
        off = rng.uniform(-0.05, 0.05, 2) * h if window == "crop" else np.zeros(2)
        bits = int(rng.choice([8, 16]))
        out.append({"kind": "tester", "seed": fs, "angle_deg": angle * float(rng.choice([-1.0, 1.0])),
                    "fill": float(rng.uniform(0.2, 0.6)),
                    "s_amp": float(rng.uniform(0.0, 0.12)) if rng.random() < 0.6 else 0.0,
                    "size": [h, int(h * rng.uniform(1.0, 1.4))], "window": window,
                    "offset_px": [float(off[0]), float(off[1])], "blur_px": float(rng.uniform(0.0, 6.0)),
                    "jitter_px": float(rng.uniform(0.0, 8.0)), "powder_dark": bool(rng.random() < 0.8),
                    "noise": float(rng.uniform(0.002, 0.03)),
                    "haze": float(rng.uniform(0.0, 0.3)) if rng.random() < 0.3 else 0.0,
                    "specks": int(rng.integers(0, 6)), "gradient": float(rng.uniform(0.0, 0.3)),
                    "surround": float(rng.uniform(0.05, 0.85)) if window in ("crop", "plain") else None, "bits": bits,
                    "suffix": str(rng.choice([".png", ".tif"] + ([".bmp"] if bits == 8 else [])))})
    return out


def write_drum_frame(params, outdir, name):
    """Render one parameter set into ``outdir``; returns (path, truth) with truth["angle_deg"]
    the magnitude of the true central slope relative to the level."""
    outdir = Path(outdir)
    p = dict(params)
    if p.pop("kind") == "stand":
        img, truth = render.render_drum(p["seed"], p["angle_deg"], fill=p["fill"], hard=p["hard"],
                                        roll_deg=p["roll_deg"])
        path = render.save_photo(outdir / f"{name}.jpg", img, truth)
    else:
        bits, suffix = p.pop("bits"), p.pop("suffix")
        img, truth = render.render_tester_frame(p.pop("seed"), p.pop("angle_deg"), **p)
        path = render.save_frame(outdir / f"{name}{suffix}", img, bits)
    truth = dict(truth, angle_deg=abs(truth["angle_deg"]))
    return path, truth


def _hsv(rng, s_range, v_range):
    from skimage.color import hsv2rgb

    return hsv2rgb(np.array([[[rng.uniform(0, 1), rng.uniform(*s_range), rng.uniform(*v_range)]]]))[0, 0].tolist()


SOIL_TONES = [(0.60, 0.45, 0.31), (0.25, 0.21, 0.18), (0.62, 0.55, 0.45), (0.55, 0.34, 0.24), (0.45, 0.36, 0.28),
              (0.42, 0.40, 0.38), (0.70, 0.50, 0.35)]
PLATE_TINTS = [(0.97, 0.99, 1.0), (1.0, 0.82, 0.6), (1.0, 1.0, 1.0), (0.9, 0.95, 1.0)]


def pile_photo_params(n, seed=0):
    """Parameter sets of ``n`` stress heap photos: flanks 20-50 deg (left and right up to 8 deg
    apart), walls of any hue and brightness (plain or cluttered, gradients, texture), cast
    shadows at any offset, blur and darkness, plates thin or thick, light or dark, with or
    without a highlight, tables of any colour, camera roll up to 5 deg, heaps off centre,
    under- and over-exposure, blur, noise, JPEG quality 60-95."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        left = float(rng.uniform(20.0, 50.0))
        right = float(np.clip(left + rng.uniform(-8.0, 8.0), 20.0, 50.0))
        tone = np.array(SOIL_TONES[int(rng.integers(len(SOIL_TONES)))]) * rng.uniform(0.85, 1.15)
        style = {"wall_rgb": _hsv(rng, (0.0, 0.6), (0.15, 0.95)), "clutter": bool(rng.random() < 0.5),
                 "wall_gradient": rng.uniform(-0.4, 0.4, 2).tolist(),
                 "wall_texture": float(rng.uniform(0.0, 0.15)) if rng.random() < 0.4 else 0.0,
                 "soil_rgb": np.clip(tone, 0, 1).tolist(),
                 "shadow": {"dx_mm": float(rng.uniform(-30, 30)), "dy_mm": float(rng.uniform(0, 15)),
                            "blur_px": float(rng.uniform(1.0, 15.0)), "darkness": float(rng.uniform(0.0, 0.6))},
                 "plate": {"thick_mm": float(rng.uniform(2.0, 12.0)), "grey": float(rng.uniform(0.2, 0.9)),
                           "rgb": list(PLATE_TINTS[int(rng.integers(len(PLATE_TINTS)))]),
                           "highlight": bool(rng.random() < 0.5)},
                 "table_rgb": _hsv(rng, (0.0, 0.7), (0.1, 0.8)),
                 "offset_frac": float(rng.uniform(-0.15, 0.15)), "scale_bar": bool(rng.random() < 0.7),
                 "exposure": float(rng.uniform(0.6, 1.4)), "noise": float(rng.uniform(0.005, 0.03)),
                 "blur_px": float(rng.uniform(0.5, 2.5))}
        out.append({"seed": int(rng.integers(0, 2 ** 31 - 1)), "left_deg": left, "right_deg": right,
                    "roll_deg": float(rng.uniform(-5.0, 5.0)), "quality": int(rng.integers(60, 96)), "style": style})
    return out


def write_pile_photo(params, outdir, name):
    """Render one heap parameter set as a JPEG (with its truth sidecar); returns (path, truth)."""
    img, truth = render.render_pile(params["seed"], params["left_deg"], params["right_deg"],
                                    roll_deg=params["roll_deg"], style=params["style"])
    truth = dict(truth, style=params["style"], quality=params["quality"])
    path = render.save_photo(Path(outdir) / f"{name}.jpg", img, truth, quality=params["quality"])
    return path, truth


def _furrow_coeffs(rng, a, b, datum):
    """A furrow profile F(x) (mm) on [a, b] as polynomial coefficients (highest power first):
    a trough 60-150 mm deep of any width, asymmetry and bottom shape (V to flat), with or without
    ridges of thrown soil at its rims, as a degree-8 polynomial (what a user's degree-9 fit can
    represent exactly, so that the corpus tests the photo, not the fit), below the beam.  The
    polynomial is fitted over the span grown by 15 % at each end, so that the span's ends lie
    inside the fit and carry no end swing of the polynomial (a surface the meter's ends rest
    on, not a cliff)."""
    x = np.linspace(a - 0.15 * (b - a), b + 0.15 * (b - a), 801)
    u = (x - a) / (b - a)
    on = (x >= a) & (x <= b)
    for _ in range(100):
        bottom = rng.uniform(0.0, 30.0)
        top = bottom + rng.uniform(60.0, min(150.0, datum - 30.0 - bottom))  # 60-150 mm deep
        c = rng.uniform(0.35, 0.65)
        wl, wr = rng.uniform(0.15, 0.4, 2)
        pw = rng.uniform(1.6, 4.0)
        w = np.where(u < c, wl, wr)
        f = top - (top - bottom) * np.exp(-(np.abs(u - c) / w) ** pw)
        for rim, amp in ((c - 1.2 * wl, rng.uniform(0, 25.0)), (c + 1.2 * wr, rng.uniform(0, 25.0))):
            f += amp * np.exp(-((u - rim) / 0.07) ** 2) if rng.random() < 0.5 else 0.0
        poly = np.polynomial.Polynomial.fit(x, f, 8)
        fit = poly(x[on])
        if fit.max() <= datum - 15.0 and fit.min() >= -20.0:
            return poly.convert().coef[::-1].tolist()
    raise RuntimeError("no furrow profile below the beam in 100 draws")


#: furrow shapes of :func:`furrow_photo_params` ``shapes="opener"``
OPENER_SHAPES = ("trapezoid", "v", "rounded", "trough")


def _opener_profile(rng, a, b, datum):
    """A furrow as an opener leaves it, F(x) (mm) as polygon vertices ``[xs, zs]`` on [a, b]:
    a flat surface (tilted up to 10 mm across the span) broken by a trapezoid, a V, a rounded
    (parabolic) trough or the corpus's smooth trough itself (not fitted by any polynomial), 60-150 mm
    deep, 35-70 % of the span wide, anywhere within it with at least 8 % of flat surface at each
    end, with or without a low ridge of thrown soil beside each rim; the corners stay corners."""
    shape = OPENER_SHAPES[int(rng.integers(len(OPENER_SHAPES)))]
    L = b - a
    bottom = rng.uniform(0.0, 30.0)  # as the smooth troughs: the profile's zero near the bottom,
    depth = rng.uniform(60.0, min(150.0, datum - 50.0 - bottom))  # the surface, tilt and ridges below the beam
    top = bottom + depth
    width = rng.uniform(0.35, 0.70) * L
    left = a + rng.uniform(0.08 * L, 0.92 * L - width)
    right = left + width
    tilt = rng.uniform(-10.0, 10.0)
    x = np.linspace(a, b, int(round(L)) * 2 + 1)  # vertices every half millimetre
    u = (x - left) / width  # 0..1 across the furrow
    inside = (u > 0) & (u < 1)
    if shape == "trapezoid":
        floor_share = rng.uniform(0.2, 0.6)  # the flat bottom's share of the top width
        wall = (1 - floor_share) / 2
        d = np.clip(np.minimum(u, 1 - u) / wall, 0, 1)
    elif shape == "v":
        c = rng.uniform(0.35, 0.65)
        d = np.where(u < c, u / c, (1 - u) / (1 - c))
    elif shape == "rounded":
        d = 1 - (2 * u - 1) ** 2
    else:
        c, pw = rng.uniform(0.4, 0.6), rng.uniform(1.6, 4.0)
        w = np.where(u < c, c, 1 - c) / 2.2
        d = np.exp(-(np.abs(u - c) / w) ** pw) - np.exp(-(np.where(u < c, c, 1 - c) / w) ** pw)
        d = d / d.max()
    f = top + tilt * (x - a) / L - depth * np.where(inside, np.clip(d, 0, 1), 0.0)
    for rim in (left, right):
        if rng.random() < 0.5:
            f += rng.uniform(3.0, 15.0) * np.exp(-((x - rim) / rng.uniform(10.0, 25.0)) ** 2) * (~inside)
    return shape, [x.tolist(), f.tolist()]


def furrow_photo_params(n, seed=0, shapes="polynomial"):
    """Parameter sets of ``n`` stress furrow photos: troughs of any depth, width and shape
    (:func:`_furrow_coeffs`), meter spans of 300-500 mm with the beam 150-250 mm above the
    profile's zero, boards of any light colour with or without a grid, beam shadows cast on the
    board, soils light to dark with shading down the face, walls of any colour around the
    board, camera roll up to 5 deg, under- and over-exposure, blur, noise, JPEG quality 60-95.
    ``shapes="opener"`` draws the furrows as openers leave them instead (:func:`_opener_profile`:
    flat surface, trapezoid, V, rounded or smooth trough with corners), the rest alike."""
    if shapes not in ("polynomial", "opener"):
        raise ValueError(f"shapes: expected 'polynomial' or 'opener', got {shapes!r}")
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        half = float(rng.uniform(150.0, 250.0))
        a, b = -half, half
        s = render.W * 0.85 / (b - a + 60)
        room = (render.MARGIN + 0.80 * render.H - render.MARGIN) / s  # mm above F = 0 in the frame
        beam_mm = float(rng.uniform(8.0, 20.0))
        datum = float(rng.uniform(150.0, min(250.0, room - beam_mm - 25.0)))
        tone = np.array(SOIL_TONES[int(rng.integers(len(SOIL_TONES)))]) * rng.uniform(0.8, 1.2)
        grid = bool(rng.random() < 0.7)
        style = {"board_rgb": _hsv(rng, (0.0, 0.3), (0.6, 0.97)),
                 "grid_mm": float(rng.choice([10.0, 20.0, 50.0])) if grid else 0.0,
                 "grid_rgb": _hsv(rng, (0.0, 0.6), (0.3, 0.75)),
                 "board_gradient": rng.uniform(-0.3, 0.3, 2).tolist(),
                 "soil_rgb": np.clip(tone, 0, 1).tolist(), "soil_shading": float(rng.uniform(0.0, 0.4)),
                 "beam_rgb": (np.ones(3) * rng.uniform(0.02, 0.3)).tolist(), "beam_mm": beam_mm,
                 "beam_shadow": {"dx_mm": float(rng.uniform(-15, 15)), "dy_mm": float(rng.uniform(5, 30)),
                                 "blur_px": float(rng.uniform(1.0, 10.0)),
                                 "darkness": float(rng.uniform(0.0, 0.5)) if rng.random() < 0.6 else 0.0},
                 "wall_rgb": _hsv(rng, (0.0, 0.6), (0.15, 0.95)), "clutter": bool(rng.random() < 0.5),
                 "exposure": float(rng.uniform(0.6, 1.4)), "noise": float(rng.uniform(0.005, 0.03)),
                 "blur_px": float(rng.uniform(0.5, 2.5))}
        row = {"seed": int(rng.integers(0, 2 ** 31 - 1)), "span_mm": [a, b], "beam_datum_mm": datum}
        if shapes == "opener":
            row["shape"], row["profile"] = _opener_profile(rng, a, b, datum)
            row["coeffs"] = None
        else:
            row["coeffs"] = _furrow_coeffs(rng, a, b, datum)
        row.update({"roll_deg": float(rng.uniform(-5.0, 5.0)), "quality": int(rng.integers(60, 96)), "style": style})
        out.append(row)
    return out


def write_furrow_photo(params, outdir, name):
    """Render one furrow parameter set as a JPEG (with its truth sidecar); returns (path, truth),
    truth with the meter's ``scale_length_mm`` (its span) and ``area_mm2``."""
    a, b = params["span_mm"]
    img, truth = render.render_furrow(params["seed"], params["coeffs"], (a, b), params["beam_datum_mm"],
                                      roll_deg=params["roll_deg"], style=params["style"],
                                      profile=params.get("profile"))
    truth = dict(truth, scale_length_mm=b - a, style=params["style"], quality=params["quality"])
    if "shape" in params:
        truth["shape"] = params["shape"]
    path = render.save_photo(Path(outdir) / f"{name}.jpg", img, truth, quality=params["quality"])
    return path, truth
