"""The drum-frame options a photo manifest or the command line may give (``level``,
``roll_deg``, ``chord_fraction``, ``rim_margin``, ``drum_centre_px``, ``drum_radius_px``,
``accept_low``; their meaning: :mod:`soilcal.imaging.drum`), checked without the image
libraries: every workflow start reads and checks the soils' photo manifests, and a check needs
none of what measures the frames."""

from __future__ import annotations

import math

from soilcal.errors import InputError

#: the default width of the central window along the chord, a fraction of the chord
CHORD_FRACTION = 0.6
#: the default margin kept inside the drum rim, a fraction of the drum radius
RIM_MARGIN = 0.05
#: where a frame's level is taken from (step 3 of :mod:`soilcal.imaging.drum`)
LEVELS = ("auto", "plate", "image")
_LIMITS = {"roll_deg": (-45.0, 45.0, "an angle between -45 and 45 deg"),
           "chord_fraction": (0.1, 1.0, "a fraction of the chord in [0.1, 1]"),
           "rim_margin": (0.0, 0.3, "a fraction of the drum radius in [0, 0.3]"),
           "drum_radius_px": (8.0, 1e6, "a radius of at least 8 px")}
OPTIONS = ("level", "roll_deg", "chord_fraction", "rim_margin", "drum_centre_px", "drum_radius_px", "accept_low")


def _number(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def frame_options(entry=None, where=None, prefix=""):
    """Validated drum options from a manifest entry or CLI arguments (a dict).

    Unknown values raise one InputError naming ``where`` (file) and ``prefix + key`` (field).
    """
    entry = entry or {}
    opts = {"level": "auto", "roll_deg": None, "chord_fraction": CHORD_FRACTION, "rim_margin": RIM_MARGIN,
            "drum_centre_px": None, "drum_radius_px": None, "accept_low": False}
    for k in OPTIONS:
        v = entry.get(k)
        if v is None:
            continue
        field = prefix + k
        if k == "level":
            if v not in LEVELS:
                raise InputError(where, field, f"one of {LEVELS}", v)
        elif k == "accept_low":
            if not isinstance(v, bool):
                raise InputError(where, field, "true or false (true: a frame flagged low that the user has checked "
                                 "is averaged all the same, listed as accepted_low)", v)
        elif k == "drum_centre_px":
            if not (isinstance(v, (list, tuple)) and len(v) == 2 and all(_number(x) for x in v)):
                raise InputError(where, field, "[column, row] of the drum centre in pixels", v)
            v = [float(x) for x in v]
        else:
            lo, hi, what = _LIMITS[k]
            if not _number(v) or not lo <= v <= hi:
                raise InputError(where, field, what, v)
            v = float(v)
        opts[k] = v
    if (opts["drum_centre_px"] is None) != (opts["drum_radius_px"] is None):
        raise InputError(where, prefix + ("drum_radius_px" if opts["drum_radius_px"] is None else "drum_centre_px"),
                         "drum_centre_px and drum_radius_px given together", "only one of them")
    if opts["roll_deg"] is not None and opts["level"] == "plate":
        raise InputError(where, prefix + "roll_deg", "either roll_deg or level: plate", "both")
    return opts
