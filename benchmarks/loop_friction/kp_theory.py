"""Coulomb's passive earth-pressure coefficient for the quick line plate, against the wall
friction delta = atan(mu_st) capped at phi (past it the soil would shear beside the wall
rather than slide on it) and the soil's friction angle phi.

The line plate's face is a plane at the skew angle epsilon = 78 deg to the horizontal, its
top 12 deg behind the vertical through the cutting edge (``soilcal.dem.tools``, Table 9 of
Qiu et al. 2022), so the soil pushed ahead of it overhangs the face: wall inclination
theta = 12 deg, level soil (alpha = 0).  Coulomb (1776) in the form of Das, Principles of
Geotechnical Engineering (Coulomb's passive pressure, inclined wall and backfill):

    Kp = cos^2(phi + theta) / (cos^2 theta cos(delta - theta)
         (1 - sqrt(sin(phi + delta) sin(phi + alpha) / (cos(delta - theta) cos(alpha - theta))))^2)

with theta positive when the soil overhangs the face (checked by the trial wedge); the passive force per width
1/2 gamma H^2 Kp acts at delta to the face's normal, its horizontal part Kp cos(delta - theta).
The trial-wedge minimum over plane slip surfaces (:func:`kh_wedge`) checks the closed
form.  Rankine: tan^2(45 + phi/2) (vertical wall, delta = 0).

    python benchmarks/loop_friction/kp_theory.py
"""
import math

import numpy as np
from scipy.optimize import minimize_scalar


def kp_h(phi, delta, theta):
    """Horizontal passive coefficient (degrees in): Das's closed form, horizontal part."""
    p, d, t = map(math.radians, (phi, delta, theta))
    root = math.sqrt(math.sin(p + d) * math.sin(p) / (math.cos(d - t) * math.cos(t)))
    kp = math.cos(p + t) ** 2 / (math.cos(t) ** 2 * math.cos(d - t) * (1 - root) ** 2)
    return kp * math.cos(d - t)


def kh_wedge(phi, delta, theta):
    """The same by the trial wedge: face of unit height leaning theta back under the soil, plane
    slip surface at rho to the horizontal; wedge weight 1/2 (cot rho + tan theta); the least
    horizontal thrust over rho, times 2."""
    p, d, t = map(math.radians, (phi, delta, theta))

    def fx(rho):  # no passive failure on a plane where the denominator is not positive
        den = math.sin(t - d) + math.cos(d - t) / math.tan(rho + p)
        return 0.5 * (1 / math.tan(rho) + math.tan(t)) * math.cos(d - t) / den if den > 0 else math.inf

    grid = np.radians(np.linspace(0.5, 89.5 - phi, 20001))
    i = int(np.argmin([fx(r) for r in grid]))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    r = minimize_scalar(fx, bounds=(lo, hi), method="bounded", options={"xatol": 1e-12})
    return 2 * r.fun


if __name__ == "__main__":
    phi = 27.6  # the cinnamon soil's printed stacking angle, deg
    print("theta  mu_st  delta   Kp_h closed  Kp_h wedge")
    res = {}
    for theta in (0.0, 12.0):
        for mu in (0.243, 0.54):
            d = min(math.degrees(math.atan(mu)), phi)
            res[theta, mu] = kp_h(phi, d, theta)
            print(f"{theta:5.1f} {mu:6.3f} {d:6.2f} {res[theta, mu]:11.3f} {kh_wedge(phi, d, theta):11.3f}")
        print(f"theta {theta:.0f} deg: mu_st 0.243 against 0.54 (delta = phi): "
              f"{100 * (res[theta, 0.243] / res[theta, 0.54] - 1):+.1f} %")
    print(f"Rankine Kp: {math.tan(math.radians(45 + phi / 2)) ** 2:.3f}")
