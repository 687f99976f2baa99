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
