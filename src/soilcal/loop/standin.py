"""An analytic stand-in for the DEM, for the loop's tests and benchmark: the passive earth pressure on a
vertical blade (Rankine; McKyes, Soil Cutting and Tillage, 1985, Ch. 4) from the same DEM
parameters the effects change.

Horizontal force on a blade of width b at working depth d moving at speed v::

    F_h = b d (0.5 K_p rho_b g d + 2 c sqrt(K_p) + c_a + rho_b v^2)
    K_p = tan^2(45 deg + phi / 2),  phi = atan(mu_ss),
    c = gamma_ss / r,  c_a = gamma_st / r,  rho_b = 0.6 rho_particle

(Rankine passive pressure with cohesion, a tool adhesion term, and the momentum flux of the
soil accelerated to the tool speed), and the vertical force F_v = F_h mu_st.  The bulk
cohesion gamma / r is the JKR pull-off 1.5 pi gamma R* over the area per contact (~ r^2),
the scaling in soilcal.dem.scenarios.base.  Seed scatter: relative, normal, SD 1 %,
drawn from the seed alone (common random numbers across parameters, as in the DEM).
"""

from __future__ import annotations

import math

import numpy as np

from soilcal.config.measurements import Condition

G = 9.81
R = 0.005  # m, particle radius
WIDTH = {"A": 0.10, "B": 0.15, "C": 0.20}

BASE = dict(soil_soil_restitution=0.45, soil_soil_static_friction=0.6, soil_soil_rolling_friction=0.1,
            soil_soil_surface_energy=0.4, soil_steel_restitution=0.45, soil_steel_static_friction=0.5,
            soil_steel_rolling_friction=0.1, soil_steel_surface_energy=0.0, soil_density=2000.0,
            soil_poisson=0.3, soil_shear_modulus=1e6, steel_density=7850.0, steel_poisson=0.3,
            steel_shear_modulus=7.9e10)


def forces(params: dict, q: dict) -> tuple[float, float]:
    phi = math.atan(params["soil_soil_static_friction"])
    kp = math.tan(math.pi / 4 + phi / 2) ** 2
    rho = 0.6 * params["soil_density"]
    c = params["soil_soil_surface_energy"] / R
    ca = params["soil_steel_surface_energy"] / R
    b = WIDTH[q.get("tool", "A")]
    d = q["working_depth"]
    v = q.get("tool_speed", 1.0)
    fh = b * d * (0.5 * kp * rho * G * d + 2 * c * math.sqrt(kp) + ca + rho * v * v)
    return fh, fh * params["soil_steel_static_friction"]


def simulate(cond, params, seed):
    fh, fv = forces(params, cond.quantities)
    e = np.random.default_rng([seed, cond.row]).normal(0.0, 0.01, 2)
    return {"horizontal_force_N": fh * (1 + e[0]), "vertical_force_N": fv * (1 + e[1])}


def base_params(cond):
    return dict(BASE)


def conditions(rows, measures=("horizontal_force_N", "vertical_force_N")):
    """Conditions from dicts of quantities (tool, tool_speed m/s, working_depth m,
    moisture_content %, position m, day)."""
    out = []
    for i, q in enumerate(rows, start=1):
        cov = dict(q)
        qc = {k: k for k in q}
        out.append(Condition(measurement="plates", row=i, label=f"row {i}", covariate="", covariate_value="",
                             scenario="standin", setup={}, params={}, stage="bbd", case="c", preset="quick",
                             replicates=3, responses=tuple({"measure": m, "unit": "N", "measured": None,
                                                            "measured_sd": None, "n": None} for m in measures),
                             covariates=cov, quantities=dict(q), quantity_columns=qc))
    return out


def grid(seed=0, n=18, moisture=False, days=6):
    """A soil-bin campaign: three tools, speeds 0.5-3 m/s, depths 0.05-0.15 m, positions
    along a 40 m bin and test days, drawn with a seeded generator."""
    rng = np.random.default_rng(seed)
    rows = []
    for i in range(n):
        q = {"tool": "ABC"[i % 3], "tool_speed": float(rng.uniform(0.5, 3.0)),
             "working_depth": float(rng.uniform(0.05, 0.15)), "position": float(rng.uniform(0, 40)),
             "day": f"d{i * days // n}"}
        if moisture:
            q["moisture_content"] = float(rng.uniform(8, 24))
        rows.append(q)
    return rows
