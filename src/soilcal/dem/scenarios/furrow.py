"""Furrow opening in a soil bin by a moldboard-style ridge and furrow opener (Yangtze clay loam).

Source: Zeng et al., Agriculture 2023, 13, 648 (``config/soils/yangtze-clay-loam.yaml``).

Test (Sec. 2.1.2, 2.2.4): the opener (geometry: :func:`soilcal.dem.tools.furrow_opener`)
moves at 0.72 m/s, 200 mm deep, through a soil tank (simulated 3000 x 1200 x 300 mm,
particles of radius 8 mm, 0.9-1.1 times, time step 20 % of the Rayleigh time).

Furrow profile (Sec. 3.1): slices perpendicular to the travel direction, 50 mm thick and
100 mm apart, six of them in the central part of the furrow; in each slice the soil surface
is the upper envelope of the particles, taken here as the highest particle top ``z + r`` in
lateral bins of one particle diameter.  Coordinates are translated so that the profile is
symmetric about the opener's centre line (``x = 0`` in the paper's notation; here the
lateral offset from the opener's centre plane) and heights are measured from the opener's
working bottom (200 mm below the undisturbed surface), the datum for which the measured
polynomial gives F(0) = 7.28 mm at the furrow bottom (assumption: the paper prints neither
the datum nor the units; mm as in the soil config).  Each slice's points within
``|x| <= x_limit`` are fitted by a polynomial Phi_i of degree ``profile_degree`` (least
squares on a scaled domain, :class:`numpy.polynomial.Polynomial`).

Area difference (Eq. 4), mm^2, reported in dm^2 as in Table 4::

    Delta S = (1/n) sum_i Delta S_i,   Delta S_i = int_a^b |Phi_i(x) - F(x)| dx

with the measured profile F of Eq. (3) (``resources/measurements/yangtze-clay-loam/
furrow_profile_polynomial.csv``).  Eq. (4) prints the signed integral; every printed Delta S
is positive and Figure 10 counts the (+) and (-) parts as enclosed area, so the response is
the enclosed (unsigned) area, computed exactly: the real roots of the polynomial
``Phi_i - F`` in (a, b) split the interval and the antiderivative is evaluated on each piece.
The signed integral is reported too (``area_difference_signed_dm2``).  Limits
``a, b = -x_limit, +x_limit`` with ``x_limit = 200 mm`` (assumption: F is fitted inside the
furrow; as encoded, F has its right-hand maximum at x = +223.8 mm, F = 129.6 mm, and falls
beyond it, while on the left it keeps rising, F(-223.8) = 128.6 mm, F(-300) = 1706 mm, so
only the right side turns over and the limits stay inside +-223.8 mm).

Traction resistance (Sec. 3.3): the opener's resistance along the travel direction,
``R = -F_x`` (F: force of the particles on the opener; soil pushes it back, so R > 0), as
the mean and sample SD over the stable working stage (``stable_from`` .. end of the pass,
as a fraction of the pass duration).  Measured 1303.07 N, simulated 1167.30 N (stable-stage
means, Sec. 3.3, ``traction_resistance.csv``).

Tank end: the soil-tank test runs over 30 m, so the soil ahead of the opener is never
confined; a short simulated tank must keep the soil the opener pushes ahead of it away from
the tank's far wall.  At the end of the pass ``front_clearance`` of undisturbed soil remains
between the share point and the far wall: 0.8 m, four working depths (at least four
depths is checked), chosen by measurement on single runs (centre levels of the Box-Behnken
design with rolling friction 0.175, seed 648, quick preset; ``far_wall_rise_N`` is the rise
of the far wall's load from the first to the last tenth of the pass; the wall at the start
end stayed within 5 N): with 0.1 m the soil bulldozed ahead of the opener jammed against the
wall and the G = 1 MPa spheres overlapped by more than half a radius in 19 of the 29
Box-Behnken points; with 0.4 m the far wall's load rose by 919 N (54 % of the 1710 N
traction); with 0.8 m by 165 N (10 % of 1593 N).  The area differences of these runs
(0.94 and 1.27 dm^2) lie within the scatter of the five centre points over seeds (0.73-1.17
dm^2, ``benchmarks/results/design_budget.md``), so they do not enter the choice.
``far_wall_rise_N`` is reported by every run.

Overlaps: the paper's soil is soft (G = 1 MPa, Sec. 2.2.4) and the relative overlap of a
Hertz contact at a given stress does not depend on the particle size (delta / R ~
(sigma / E*)^(2/3)), so the soil loaded by the opener carries large overlaps at any
resolution: in the quick tank, snapshots of the centre and high-cohesion Box-Behnken points
showed sustained overlaps of 30-54 % of a radius ahead of and under the share point, and
the floor contacts grew to 28 %.  These are load, not a numerical blow-up, so the run's
guard (``max_overlap``) is 75 % of a radius instead of the soil bin's 50 %, and the largest
overlap of the pass is reported (``peak_overlap``, a fraction of the radius): Hertz's
small-strain law is far outside its range there, in the paper's simulation as here.  The
guard is also where the damped-contact step bound is evaluated (materials.py), so it
shortens the step a little (Box-Behnken run 1: 0.509 to 0.496 ms), and it is part of the
settled bin's cache key.

Presets: ``paper`` keeps the paper's tank, 8 mm particles (0.9-1.1), 20 % Rayleigh step and
a pass of 1.7 m (what the 3 m tank leaves after the start margin, the opener and the front
clearance); ``quick`` shrinks the tank to 2.0 x 0.8 x 0.3 m with 22 mm particles (a 2.75x
coarse-graining of the 8 mm particles), a 0.7 m pass, two slices and a 6th-degree fit, so that a run
takes seconds; the convergence study (``benchmarks/convergence_tools.py``) shows what that
costs.
"""

from __future__ import annotations

import csv
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
from numpy.polynomial import Polynomial

from soilcal.dem import tools
from soilcal.dem.scenarios.base import (PRESETS, DemParams, Result, check, stable_mean,
                                        threads_used)
from soilcal.dem.scenarios.soilbin import (COHESION_KEYS, BinSpec, apply_preset, check_pass,
                                           reference_cohesion, tool_pass, tool_time_step, validate_bin)
from soilcal.errors import InputError

NAME = "furrow"
#: writes and reads restart files (soilcal.dem.restart)
RESTARTABLE = True
#: every response a run reports (``Result.responses``)
RESPONSES = (
    "area_difference_dm2", "area_difference_sd_dm2", "area_difference_signed_dm2",
    "furrow_area_dm2", "traction_N", "traction_sd_N", "vertical_force_N", "vertical_force_sd_N",
    "traction_measured_N", "peak_overlap", "far_wall_rise_N", "settled_surface_m",
    "bin_from_cache",
)
#: the responses a soil's ``simulation`` block may measure (numbers a design point yields)
MEASURES = (
    "area_difference_dm2", "area_difference_signed_dm2", "furrow_area_dm2", "traction_N",
    "vertical_force_N",
)
MEASURED = (Path(__file__).resolve().parents[4] / "resources" / "measurements"
            / "yangtze-clay-loam")


def setups() -> dict:
    return {
        "yangtze-opener": dict(
            depth=0.200,             # Sec. 2.1.2 / 2.2.4: depth of soil entry 200 mm
            speed=0.72,              # Sec. 2.1.2 / 2.2.4: 0.72 m/s (2.6 km/h)
            tank_length=3.0,         # Sec. 2.2.4: simulated tank 3000 mm
            tank_width=1.2,          # Sec. 2.2.4: 1200 mm
            tank_height=0.3,         # Sec. 2.2.4: 300 mm
            particle_radius=0.008,   # Sec. 2.2.4: 8 mm
            radius_spread=0.1,       # Sec. 2.2.4: 0.9-1.1 times the base radius
            dt_fraction=0.2,         # Sec. 2.2.4: 20 % of the Rayleigh time step
            slice_thickness=0.05,    # Sec. 3.1: slices 50 mm thick
            slice_spacing=0.10,      # Sec. 3.1: 100 mm apart
            n_slices=6,              # Sec. 3.1: six slices
            profile_degree=9,        # Eq. (3): 9th-degree polynomial
            x_limit=0.200,           # assumption: integration limits +-200 mm (Eq. 4)
            stable_from=0.5,         # stable working stage: second half of the pass
            front_clearance=0.8,     # undisturbed soil ahead of the share point at the end
                                     # of the pass: four working depths (module doc)
            max_overlap=0.75,        # blow-up guard, fraction of a radius (module doc)
            opener_length=tools.OPENER["length"],   # assumption (tools.py)
            opener_half_width=tools.OPENER["half_width"],
            opener_upper_half_width=tools.OPENER["upper_half_width"],
            opener_upper_height=tools.OPENER["upper_height"],
            opener_bottom_half_width=tools.OPENER["bottom_half_width"],
            **COHESION_KEYS,         # surface energy for the paper preset's particles (base.py)
        ),
    }


# discretisation per preset (geometry of the test stays in the setup)
PRESET_SETTINGS = {
    "quick": dict(tank_length=2.0, tank_width=0.8, tank_height=None, particle_radius=0.022,
                  travel=0.7, n_slices=2, profile_degree=6, settle_time=0.3, stiffness_scale=1.0),
    "paper": dict(tank_length=None, tank_width=None, tank_height=None, particle_radius=None,
                  travel=1.7, n_slices=None, profile_degree=None, settle_time=1.0,
                  stiffness_scale=1.0),
}
MARGIN = 0.05  # m of soil between the trench and the tank's starting end


def paper_params() -> DemParams:
    """Yangtze clay loam at the paper's optimum (Sec. 3.2.3) with its printed constants."""
    return DemParams.from_mapping(dict(
        soil_soil_restitution=0.5, soil_soil_static_friction=0.2,   # Sec. 3.2.3 optimum
        soil_soil_rolling_friction=0.05, soil_soil_surface_energy=5.0,
        soil_steel_restitution=0.3,                    # Sec. 2.2.4, from [11]
        soil_steel_static_friction=0.71,               # Table 1 mean
        soil_steel_rolling_friction=0.097,             # Table 2 mean
        soil_steel_surface_energy=0.0,                 # Hertz-Mindlin (no slip) soil-opener
        soil_density=2570.0, soil_poisson=0.38, soil_shear_modulus=1.0e6,  # Sec. 2.1.1, 2.2.4
        steel_density=7861.0, steel_poisson=0.30, steel_shear_modulus=7.9e10,  # Sec. 2.2.4
    ), "<furrow.paper_params>")


def measured_profile() -> Polynomial:
    """F(x) of Eq. (3), x and F in mm."""
    path = MEASURED / "furrow_profile_polynomial.csv"
    with open(path, newline="") as fh:
        rows = sorted((int(r["power"]), float(r["coefficient"])) for r in csv.DictReader(fh))
    return Polynomial([c for _, c in rows])


def measured_traction() -> float:
    with open(MEASURED / "traction_resistance.csv", newline="") as fh:
        return float(next(csv.DictReader(fh))["measured_N"])


def _settings(setup: dict, preset: str) -> dict:
    return apply_preset(setup, setups()["yangtze-opener"], PRESET_SETTINGS[preset])


def validate(setup: dict, preset: str = "quick", source: str = "<furrow>",
             params=None) -> dict:
    """Bad settings raise InputError before the run; with ``params``, also a pass the run
    could not finish (:func:`soilcal.dem.scenarios.soilbin.check_pass`).  Returns the run's
    settings, with the surface-energy factor ``cohesion_scale``
    (:func:`soilcal.dem.scenarios.soilbin.reference_cohesion`)."""
    check(preset in PRESETS, source, "preset", f"one of {PRESETS}", preset)
    s = _settings(setup, preset)
    for k in ("depth", "speed", "tank_length", "tank_width", "tank_height", "particle_radius",
              "slice_thickness", "slice_spacing", "x_limit", "opener_length",
              "opener_half_width", "opener_upper_half_width", "opener_upper_height",
              "opener_bottom_half_width", "travel", "dt_fraction", "front_clearance",
              "max_overlap"):
        v = s.get(k)
        check(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
              and v > 0, source, f"setup.{k}", "a number > 0", v)
    check(s["depth"] < s["tank_height"], source, "setup.depth",
          f"a working depth below the soil height of the tank ({s['tank_height']} m)", s["depth"])
    check(s["tank_height"] - s["depth"] >= 2 * s["particle_radius"], source, "setup.depth",
          "at least one particle diameter of soil under the opener", s["depth"])
    r_max = s["particle_radius"] * (1.0 + s["radius_spread"])
    check(s["depth"] >= 2.0 * r_max, source, "setup.depth",
          f">= 2 r_max = {2.0 * r_max:.4g} m (a cut at least one largest particle diameter "
          "deep)", s["depth"])
    check(2 * s["opener_upper_half_width"] + 4 * s["particle_radius"] <= s["tank_width"], source,
          "setup.tank_width", f"wider than the opener ({2 * s['opener_upper_half_width']} m) "
          "plus a particle diameter each side", s["tank_width"])
    check(s["opener_bottom_half_width"] < s["opener_half_width"] <= s["opener_upper_half_width"],
          source, "setup.opener_half_width",
          "opener_bottom_half_width < opener_half_width <= opener_upper_half_width",
          s["opener_half_width"])
    check(s["front_clearance"] >= 4 * s["depth"] - 1e-9, source, "setup.front_clearance",
          f">= four working depths ({4 * s['depth']:.3g} m) of soil ahead of the opener at the "
          "end of the pass (module docstring: the far wall takes up the pushed soil)",
          s["front_clearance"])
    need = MARGIN + s["opener_length"] + s["travel"] + s["front_clearance"]
    check(need <= s["tank_length"] + 1e-9, source, "setup.tank_length",
          f">= margin + opener length + pass + front clearance = {need:.3g} m",
          s["tank_length"])
    n = s["n_slices"]
    check(isinstance(n, int) and n >= 1, source, "setup.n_slices", "an integer >= 1", n)
    deg = s["profile_degree"]
    check(isinstance(deg, int) and 1 <= deg <= 12, source, "setup.profile_degree",
          "an integer degree in [1, 12]", deg)
    furrow_len = s["travel"] - s["opener_length"]
    span = (n - 1) * s["slice_spacing"] + s["slice_thickness"]
    check(span <= furrow_len, source, "setup.n_slices",
          f"slices spanning <= the finished furrow behind the opener ({furrow_len:.3g} m)",
          f"{n} slices spanning {span:.3g} m")
    check(s["x_limit"] <= 0.2238, source, "setup.x_limit",
          "<= 0.2238 m (F(x) of Eq. 3 turns over at x = +223.8 mm)", s["x_limit"])
    check(0.0 <= s["stable_from"] < 1.0, source, "setup.stable_from",
          "a fraction of the pass in [0, 1)", s["stable_from"])
    check(0 < s["dt_fraction"] <= 1, source, "setup.dt_fraction", "a fraction in (0, 1]",
          s["dt_fraction"])
    check(s["max_overlap"] < 1, source, "setup.max_overlap", "a fraction of a radius in (0, 1)",
          s["max_overlap"])
    spec = _bin(s)
    validate_bin(spec, source, "setup")
    s["cohesion_scale"] = reference_cohesion(spec, _bin(_settings(setups()["yangtze-opener"], "paper")),
                                             setup, source)
    if params is not None:
        spec = replace(spec, cohesion_scale=s["cohesion_scale"])
        check_pass(spec, params, source, "setup.speed", s["speed"], s["travel"],
                   tool_time_step(spec, params))
    return s


def _bin(s) -> BinSpec:
    return BinSpec(length=s["tank_length"], width=s["tank_width"], height=s["tank_height"],
                   radius=s["particle_radius"], spread=s["radius_spread"],
                   settle_time=s["settle_time"], stiffness_scale=s["stiffness_scale"],
                   dt_fraction=s["dt_fraction"], cohesion_scale=s.get("cohesion_scale", 1.0),
                   max_overlap=s["max_overlap"])


# ---------------------------------------------------------------------------
# profile analysis
# ---------------------------------------------------------------------------


def slice_profile(x, r, x_lo, x_hi, y_centre, z_datum, step, y_range):
    """Upper envelope of the particles whose spheres reach into the slice
    ``x_lo <= x <= x_hi``: at lateral sample points ``y_k`` (spacing ``step``) the height
    ``max_i z_i + sqrt(r_i^2 - (y_k - y_i)^2)`` over spheres with ``|y_k - y_i| < r_i``.
    Returns lateral offsets from ``y_centre`` and heights above ``z_datum`` (both mm);
    samples no sphere covers are left out."""
    sel = (x[:, 0] + r >= x_lo) & (x[:, 0] - r <= x_hi)
    xs, rs = x[sel], r[sel]
    yk = np.arange(y_range[0] + 0.5 * step, y_range[1], step)
    dy = yk[None, :] - xs[:, 1:2]
    h2 = rs[:, None] ** 2 - dy * dy
    top = np.where(h2 > 0, xs[:, 2:3] + np.sqrt(np.clip(h2, 0, None)), -np.inf).max(axis=0)
    ok = np.isfinite(top)
    return 1e3 * (yk[ok] - y_centre), 1e3 * (top[ok] - z_datum)


def fit_profile(y_mm, z_mm, degree, x_limit_mm) -> Polynomial:
    """Least-squares polynomial Phi(x) (mm) of the points with |x| <= x_limit."""
    sel = np.abs(y_mm) <= x_limit_mm
    if sel.sum() <= degree:
        raise ValueError(f"{int(sel.sum())} profile points for a degree-{degree} fit")
    return Polynomial.fit(y_mm[sel], z_mm[sel], degree).convert()


def area_difference(phi: Polynomial, f: Polynomial, a: float, b: float) -> tuple[float, float]:
    """(enclosed area int_a^b |phi - f|, signed int_a^b (phi - f)), exact for polynomials."""
    d = (phi - f).convert()
    anti = d.integ()
    roots = d.roots() if d.degree() > 0 else np.array([])
    cuts = np.sort(np.real(roots[np.abs(np.imag(roots)) < 1e-9 * (1 + np.abs(roots))]))
    cuts = cuts[(cuts > a) & (cuts < b)]
    edges = np.concatenate([[a], cuts, [b]])
    pieces = anti(edges[1:]) - anti(edges[:-1])
    return float(np.sum(np.abs(pieces))), float(anti(b) - anti(a))


def furrow_area(phi: Polynomial, depth_mm: float, a: float, b: float, n: int = 401) -> float:
    """Furrow cross-section (mm^2): area between the undisturbed surface, ``depth_mm``
    above the datum, and the profile ``phi`` where it lies below it, over [a, b]
    (trapezoidal rule on ``n`` points)."""
    xs = np.linspace(a, b, n)
    return float(np.trapezoid(np.clip(depth_mm - phi(xs), 0.0, None), xs))


# ---------------------------------------------------------------------------
# run
# ---------------------------------------------------------------------------


def run(setup: dict, params: DemParams, preset: str = "quick", seed: int = 0, threads=None,
        vtk_dir=None, source: str = "<furrow>", use_cache: bool = True, restart=None) -> Result:
    """One opener pass (module docstring).  ``restart``: a :class:`soilcal.dem.restart.Restart`
    that the run resumes from and writes every few minutes (phases ``bin_0``, ``bin_1``,
    ``pass``: :func:`soilcal.dem.scenarios.soilbin.tool_pass`); the numbers are those of an
    uninterrupted run."""
    from soilcal.dem import restart as rst

    s = validate(setup, preset, source, params=params)
    nthreads = threads_used(threads)
    prog = rst.Progress(restart)
    prog.resume()
    spec = _bin(s)
    v, t = tools.furrow_opener(depth=s["depth"], half_width=s["opener_half_width"],
                               bottom_half_width=s["opener_bottom_half_width"],
                               upper_height=s["opener_upper_height"],
                               upper_half_width=s["opener_upper_half_width"],
                               length=s["opener_length"], source=source)
    from soilcal.dem.scenarios.soilbin import settled_bin

    bed = settled_bin(spec, params, preset, seed, source, use_cache, progress=prog)
    surface = bed["surface"]
    yc = 0.5 * s["tank_width"]
    x_start = MARGIN + s["opener_length"]
    z_tool = surface - s["depth"]
    v = v + np.array([x_start, yc, z_tool])
    lo, hi = v.min(axis=0), v.max(axis=0)
    pad = 2.0 * spec.r_max

    def trench(x, r):
        return np.all((x >= lo - pad) & (x <= hi + pad), axis=1)

    duration = s["travel"] / s["speed"]

    def pose(tt):
        return v + np.array([s["speed"] * tt, 0, 0]), t

    out = tool_pass(spec, params, preset, seed, source, v, t, (s["speed"], 0.0, 0.0),
                    duration, trench, vtk_dir=vtk_dir, stem="furrow", use_cache=use_cache,
                    tool_pose=pose, log_dt=0.005, bed=bed, progress=prog)
    prog.finish()
    sim = out["sim"]
    tt, force = out["t"], out["force"]
    resist = -force[:, 0]
    r_mean, r_sd = stable_mean(tt, resist, s["stable_from"] * duration)
    fz_mean, fz_sd = stable_mean(tt, force[:, 2], s["stable_from"] * duration)
    # slices in the finished furrow: between the start and the opener's final rear end
    x_end_rear = x_start + s["travel"] - s["opener_length"]
    mid = 0.5 * (x_start + x_end_rear)
    n = s["n_slices"]
    centres = mid + (np.arange(n) - 0.5 * (n - 1)) * s["slice_spacing"]
    F = measured_profile()
    xl = 1e3 * s["x_limit"]
    bw = 0.5 * s["particle_radius"]
    half = 0.5 * s["tank_width"] - pad
    enclosed, signed, areas = [], [], []
    x = sim.x
    r = sim.p.r
    for c in centres:
        ym, zm = slice_profile(x, r, c - 0.5 * s["slice_thickness"],
                               c + 0.5 * s["slice_thickness"], yc, z_tool, bw,
                               (yc - half, yc + half))
        phi = fit_profile(ym, zm, s["profile_degree"], xl)
        e, sg = area_difference(phi, F, -xl, xl)
        enclosed.append(e)
        signed.append(sg)
        areas.append(furrow_area(phi, 1e3 * s["depth"], -xl, xl))
    # the far wall's load: its rise over the pass (first to last tenth) shows the soil pushed
    # ahead of the opener reaching it (the at-rest earth pressure is there from the start)
    far = out["wall_forces"][:, sim.walls.names.index("x_hi"), 0]
    tenth = 0.1 * duration
    try:
        far_rise = (stable_mean(tt, far, duration - tenth)[0]
                    - stable_mean(tt, far, 0.0, tenth)[0])
    except InputError:  # a pass too short for two samples per tenth: no diagnostic
        far_rise = float("nan")
    wall = prog.wall_s
    resp = dict(
        area_difference_dm2=float(np.mean(enclosed)) / 1e4,
        area_difference_sd_dm2=float(np.std(enclosed, ddof=1)) / 1e4 if n > 1 else 0.0,
        area_difference_signed_dm2=float(np.mean(signed)) / 1e4,
        furrow_area_dm2=float(np.mean(areas)) / 1e4,
        traction_N=r_mean, traction_sd_N=r_sd,
        vertical_force_N=fz_mean, vertical_force_sd_N=fz_sd,
        traction_measured_N=measured_traction(),
        peak_overlap=float(out["peak_overlap"]), far_wall_rise_N=float(far_rise),
        settled_surface_m=float(surface), bin_from_cache=bool(out["from_cache"]),
    )
    return Result(scenario=NAME, preset=preset, seed=int(seed), n_particles=out["n"],
                  steps=int(out["steps"] + out["settle_steps"]),
                  sim_time_s=out["steps"] * out["dt"],
                  wall_s=wall, threads=nthreads, params=params.as_dict(), setup=dict(s),
                  responses=resp, series=dict(t=tt, traction_N=resist, force=force,
                                               slice_x=centres))
