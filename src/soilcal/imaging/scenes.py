"""Scene list of the rendered photo set, with the printed value behind every angle/profile.

The five source papers print no usable photographs, so ``resources/images/<soil>/`` is filled
by :mod:`soilcal.imaging.render` from the scenes below.  Each angle is the *measured* value the
paper prints, copied as printed; where a paper prints no measured value the scene says so in
``label`` and uses the value that *is* printed (never an invented "measured" angle).

=====================  =============================  ==========================================
soil                   value rendered                 source (as printed)
=====================  =============================  ==========================================
cinnamon-soil          27.69 deg stacking angle       002 (Qiu et al. 2022), Sec. 2.4 / Concl.:
                                                      "average value of soil stacking angle
                                                      was 27.69 deg" (cylinder lifting, 10 runs)
black-soil, soil-soil  left 35.07, right 35.37 deg;   001 (Qi et al. 2025), Sec. 3.1.2, Eqs. (6),
                       final 35.2 deg                 (7): y = 0.7021x + 741.1382,
                                                      y = 0.7103x + 221.4673; four directions
black-soil, soil-steel left 32.68, right 33.03 deg;   001, Sec. 3.2.2, Eqs. (9), (10)
                       final 32.9 deg
xinjiang-vineyard      static 30.82 / 32.35 / 33.77   003, Conclusions (1) and Sec. 2 (drum:
                       dynamic 42.7 / 43.91 / 45.7    "42.7, 43.91 and 45.7 deg"), upper / middle /
                       (upper / middle / lower layer) lower layer; drum 7 r/min, 25 % fill
guangxi-cohesive       31.3, 31.97, 32.2 deg          004 (Wei et al.), Sec. 3.6, Table 12 text:
                       (SIMULATED, 10 % moisture)     simulated angle of repose vs particle mass.
                                                      Table 1 (measured angle per moisture) and
                                                      Eq. (3) are lost in the extraction, so no
                                                      measured angle per moisture is rendered.
yangtze-clay-loam      furrow profile F(x), Eq. (3)   000 (Zeng et al. 2023), Eq. (3), 9th-degree
                       over x in [-220, 220] mm       polynomial; span not printed (see below)
=====================  =============================  ==========================================

Black soil, four directions: the paper prints the left/right boundary angles of one view
(Eqs. 6-7 / 9-10) and the four-direction mean.  The four heap sectors are therefore W = left,
E = right (printed) and N = S = the printed mean (the two other directions are not printed); the
four side views S, E, N, W each show two sectors.

Errata noted while encoding (values rendered as printed, the contradiction recorded here):
* 001 Eq. (9) slope 0.6409 gives atan = 32.66 deg, printed 32.68 deg; Eq. (10) slope 0.6095
  gives 31.36 deg, printed 33.03 deg.  The printed angles are rendered.
* 004 Table 1 (measured angle of repose per moisture) is missing from the extracted text.

Yangtze furrow: the coefficients of Eq. (3) are printed unambiguously (x and F in mm).  The
integration limits a, b of Eq. (4) are not printed.  F has its right-hand local maximum at
x = 223.8 mm and is nearly level at x = -220 mm, so the span [-220, 220] mm is used; the area
between F and the chord of its end points is then 31 624 mm^2 (3.16 dm^2), consistent with the
printed area difference 0.30 dm^2 being a 9.15 % relative error (0.30 / 0.0915 = 3.28 dm^2).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

SOILS = ("yangtze-clay-loam", "black-soil", "cinnamon-soil", "xinjiang-vineyard", "guangxi-cohesive")

# 000, Eq. (3): F(x), highest power first, x and F in mm.
FURROW_F_COEFFS = (
    -5.04e-19, -1.96e-17, 5.65e-14, 2.12e-12, -2.05e-9,
    -9.65e-8, 2.97e-5, 4.41e-3, -0.27, 7.28,
)
FURROW_SPAN_MM = (-220.0, 220.0)


def furrow_profile(x_mm: np.ndarray) -> np.ndarray:
    """Eq. (3) of 000: furrow contour height F(x) in mm (x in mm)."""
    return np.polyval(FURROW_F_COEFFS, np.asarray(x_mm, dtype=float))


def furrow_chord_area(a: float = FURROW_SPAN_MM[0], b: float = FURROW_SPAN_MM[1],
                      coeffs=FURROW_F_COEFFS) -> float:
    """Analytic area (mm^2) between the chord F(a)-F(b) and F(x) on [a, b]; F the polynomial
    of ``coeffs`` (mm, highest power first; default the shipped furrow's)."""
    p = np.poly1d(coeffs)
    P = p.integ()
    return float(0.5 * (p(a) + p(b)) * (b - a) - (P(b) - P(a)))


def polyline_chord_area(xs, zs) -> float:
    """Area (mm^2) between the chord joining the first and last points of a profile given as a
    polyline (``xs`` increasing, mm) and the polyline itself: exact for straight pieces."""
    xs, zs = np.asarray(xs, dtype=float), np.asarray(zs, dtype=float)
    return float(0.5 * (zs[0] + zs[-1]) * (xs[-1] - xs[0]) - np.trapezoid(zs, xs))


@dataclass(frozen=True)
class Scene:
    """One photo (or one drum sequence) to render."""

    soil: str
    name: str
    kind: str  # "pile", "drum" or "furrow"
    left_deg: float = float("nan")
    right_deg: float = float("nan")
    front_deg: float = float("nan")
    back_deg: float = float("nan")
    view: str = "S"
    group: str = ""  # photos averaged together (one measured value)
    target_deg: float = float("nan")  # the printed value the group reproduces
    source: str = ""
    label: str = "measured"  # "measured" or "simulated" (as printed)
    frames: int = 0  # drum sequences
    substrate: str = "steel"  # pile base plate material
    extra: dict = field(default_factory=dict)


def _cone(soil, name, angle, group, source, label="measured", **kw) -> Scene:
    return Scene(soil=soil, name=name, kind="pile", left_deg=angle, right_deg=angle,
                 front_deg=angle, back_deg=angle, group=group, target_deg=angle, source=source,
                 label=label, **kw)


def _four_views(soil, group, w, e, mean, source, substrate):
    """Heap with sectors W, E (printed left/right) and N = S = printed mean; views S, E, N, W."""
    sector = {"W": w, "E": e, "N": mean, "S": mean}
    # seen from direction d, the left flank is the sector 90 deg clockwise of d (looking at it)
    left_of = {"S": "W", "E": "S", "N": "E", "W": "N"}
    right_of = {"S": "E", "E": "N", "N": "W", "W": "S"}
    opposite = {"S": "N", "N": "S", "E": "W", "W": "E"}
    out = []
    for v in ("S", "E", "N", "W"):
        out.append(Scene(soil=soil, name=f"{group}_{v}", kind="pile",
                         left_deg=sector[left_of[v]], right_deg=sector[right_of[v]],
                         front_deg=sector[v], back_deg=sector[opposite[v]], view=v,
                         group=group, target_deg=mean, source=source, substrate=substrate))
    return out


SCENES: dict[str, list[Scene]] = {
    "cinnamon-soil": [
        _cone("cinnamon-soil", f"stacking_{i}", 27.69, "stacking",
              "002 Sec. 2.4: mean of 10 cylinder-lifting photos, 27.69 deg")
        for i in (1, 2)
    ],
    "black-soil": (
        _four_views("black-soil", "soil_soil", 35.07, 35.37, 35.2,
                    "001 Sec. 3.1.2, Eqs. (6)-(7): 35.07 / 35.37 deg, final 35.2 deg", "soil")
        + _four_views("black-soil", "soil_steel", 32.68, 33.03, 32.9,
                      "001 Sec. 3.2.2, Eqs. (9)-(10): 32.68 / 33.03 deg, final 32.9 deg", "steel")
    ),
    "xinjiang-vineyard": [
        s
        for layer, st, dy in (("upper", 30.82, 42.7), ("middle", 32.35, 43.91), ("lower", 33.77, 45.7))
        for s in (
            _cone("xinjiang-vineyard", f"static_{layer}", st, f"static_{layer}",
                  f"003 Concl. (1): static angle {layer} layer {st} deg (cylinder lift)"),
            Scene(soil="xinjiang-vineyard", name=f"drum_{layer}", kind="drum", group=f"dynamic_{layer}",
                  target_deg=dy, left_deg=dy, right_deg=dy, frames=4,
                  source=f"003 Sec. 2 / Concl. (1): dynamic angle {layer} layer {dy} deg (drum 7 r/min, 25 % fill)",
                  extra={"fill": 0.25}),
        )
    ],
    "guangxi-cohesive": [
        _cone("guangxi-cohesive", f"sim10_{tag}", a, f"sim10_{tag}",
              f"004 Sec. 3.6 (Table 12 text): SIMULATED angle {a} deg at 10 % moisture; "
              "measured angles per moisture (Table 1) not printed in the extracted text",
              label="simulated")
        for tag, a in (("low", 31.3), ("mid", 31.97), ("high", 32.2))
    ],
    "yangtze-clay-loam": [
        Scene(soil="yangtze-clay-loam", name="furrow", kind="furrow", group="furrow",
              source="000 Eq. (3): 9th-degree polynomial F(x), span [-220, 220] mm (limits not printed)",
              extra={"span_mm": list(FURROW_SPAN_MM), "area_mm2": furrow_chord_area()}),
    ],
}
# 004 Table 12 text: "fluctuates from 31.3 deg to 32.2 deg" (0.1 -> 0.3 kg) and "stabilizes
# between 31.3 deg and 31.97 deg" for >= 0.15 kg; which mass gives which value is only partly
# stated, so the three printed values are rendered as "low", "mid", "high", not per mass.


def scenes_for(soil: str) -> list[Scene]:
    from soilcal.errors import InputError

    if soil not in SCENES:
        raise InputError(None, "soil", f"one of {sorted(SCENES)}", soil)
    return SCENES[soil]
