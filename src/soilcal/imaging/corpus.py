"""Seeded stress corpora: photos as users take them, each with its analytic truth.

:func:`drum_frames` mixes photos of a drum on its stand (:func:`render.render_drum`: colour
JPEG, base plate, camera roll up to 3 deg) and drum testers' exports
(:func:`render.render_tester_frame`: grey 8/16-bit PNG/TIFF/BMP, cropped to the drum, off
centre or running past the border, rim rings, drums on a plain surround of any grey, frames
inside a larger drum, averaged soft
interfaces, S-shaped surfaces rising to either side, inverted polarity, haze of flying
particles, dust specks, illumination gradients, noise).  Every parameter is drawn from
``numpy.random.default_rng(seed)`` and returned with the frame.
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
