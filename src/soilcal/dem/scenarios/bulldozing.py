"""Bulldozing-plate cutting resistance in a soil bin (cinnamon soil, four directrix shapes).

Source: Qiu et al., Agriculture 2022, 12, 1082, Sec. 4 (``config/soils/cinnamon-soil.yaml``).

Test (Sec. 4.2.1-4.2.2): plates 150 x 300 mm (height x breadth) with the four directrices of
Table 9 (line, arc, parabola, bionic curve; geometry :func:`soilcal.dem.tools.bulldozing_plate`)
advance at 0.16 m/s, 30 mm deep, through a simulated bin of 1 x 0.6 x 0.2 m for 4.5 s.
Soil particle sizes 3, 2 and 1 mm (mass 8.85, 8.2, 82.95 %, Sec. 3.1).

Forces (Sec. 4.2.1, Figure 10b): the horizontal resistance ``Fx = -F_x`` and the vertical
force ``Fy = F_z`` of the soil on the plate (F: force of the particles on the plate; the
soil resists the motion, so Fx > 0; the paper's vertical resistance is reported as a
magnitude, the signed value is given here with + up), each as the mean and sample SD over
the stable stage (``stable_from`` of the pass to its end).  The resultant
``F = sqrt(Fx^2 + Fy^2)`` and its angle to the horizontal ``theta = atan(Fy / Fx)``
(Figure 10b) are reported too.  Measured soil-bin means (Sec. 4.3,
``resources/measurements/cinnamon-soil/cutting_resistance.csv``): horizontal 304.80 (line),
321.10 (arc), 252.10 (parabola), 154.50 N (bionic); vertical 10.40, 48.80, 13.98, 15.50 N.

Presets: ``paper`` is the paper's bin and pass with the full plate between side walls and
the printed size distribution (Sec. 3.1): particle sizes 3, 2 and 1 mm with mass percentages
8.85, 8.2 and 82.95 %, read as diameters (assumption: the paper does not say whether the
sizes are diameters or radii), i.e. radii 1.5, 1.0 and 0.5 mm
(:class:`soilcal.dem.factories.PSD`, fields ``psd_sizes`` and ``psd_mass_percent``; a
setup that gives its own ``particle_radius`` and ``radius_spread`` runs those uniform radii
instead, and one that gives its own ``psd_sizes`` and ``psd_mass_percent`` runs that
distribution under either preset, :data:`SIZE_KEYS`).  ``quick`` cuts a
periodic slab of width ``slab_width`` (70 mm) out of the bin across the plate: the plate
spans the slab (no plate ends, so no side spill), the bed is 60 mm deep (twice the cut),
particles of 7 mm radius (0.9-1.1), the paper's shear modulus unscaled, 30 % of the
Rayleigh step and a 0.2 m pass; forces are scaled to the printed breadth by ``breadth /
slab_width`` (plane-strain reading of the cut).  The convergence study
(``benchmarks/results/convergence/convergence_tools.md``) shows the effect of each choice:
with the modulus scaled by 0.1 (and the surface energy by 0.1^0.4,
:func:`soilcal.dem.scenarios.base.build_materials`) the line plate's horizontal force fell
from 40.8 to 30.9 N (means of five seeds, SDs 2.2 and 1.9 N; the scaled rows are in
convergence_tools_replaced.csv), while a run at the unscaled
modulus takes about 2 s on one thread, so the quick preset does not scale it; 0.85 and 0.7
times the radius gave 46.8 and 42.7 N against 38.3-44.3 N over the five seeds.
"""

from __future__ import annotations

import csv
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from soilcal.dem import tools
from soilcal.dem.factories import PSD
from soilcal.dem.scenarios.base import (PRESETS, DemParams, Result, check, stable_mean,
                                        threads_used)
from soilcal.dem.scenarios.soilbin import (COHESION_KEYS, BinSpec, apply_preset, check_pass,
                                           psd_field, reference_cohesion, settled_bin, tool_pass,
                                           tool_time_step, validate_bin)

NAME = "bulldozing"
#: writes and reads restart files (soilcal.dem.restart)
RESTARTABLE = True
#: every response a run reports (``Result.responses``)
RESPONSES = (
    "horizontal_force_N", "horizontal_force_sd_N", "vertical_force_N", "vertical_force_sd_N",
    "resultant_force_N", "resultant_angle_deg", "horizontal_measured_N", "vertical_measured_N",
    "horizontal_error_percent", "force_scale", "peak_overlap", "bin_from_cache",
)
#: the responses a soil's ``simulation`` block may measure (numbers a design point yields)
MEASURES = (
    "horizontal_force_N", "vertical_force_N", "resultant_force_N", "resultant_angle_deg",
)
MEASURED = (Path(__file__).resolve().parents[4] / "resources" / "measurements"
            / "cinnamon-soil" / "cutting_resistance.csv")


#: the bin's spheres: uniform radii (``particle_radius`` and ``radius_spread``) or a
#: mass-fraction size distribution (``psd_sizes``, diameters in m, and ``psd_mass_percent``);
#: None in a named setup means the preset's (``PRESET_SETTINGS``), a soil's ``set:`` gives
#: its own, one kind or the other
RADIUS_KEYS = ("particle_radius", "radius_spread")
PSD_KEYS = ("psd_sizes", "psd_mass_percent")
SIZE_KEYS = dict.fromkeys(RADIUS_KEYS + PSD_KEYS)


def _setup(shape):
    return dict(
        shape=shape,               # Table 9 directrix (line: the ruled surface plate)
        depth=0.030,               # Sec. 4.2.1/4.2.2: tillage depth 30 mm
        speed=0.16,                # Sec. 4.2.1/4.2.2: 0.16 m/s
        duration=4.5,              # Sec. 4.2.2: 4.5 s at constant speed
        bin_length=1.0,            # Sec. 4.2.2: simulated bin 1 x 0.6 x 0.2 m
        bin_width=0.6,
        bin_height=0.2,
        plate_height=tools.PLATE["height"],    # Sec. 4.2.1: 150 mm
        plate_breadth=tools.PLATE["breadth"],  # Sec. 4.2.1: 300 mm
        stable_from=0.5,           # stable stage: second half of the pass
        **SIZE_KEYS,               # the preset's spheres unless the soil sets its own
        **COHESION_KEYS,           # surface energy for the paper preset's particles (base.py)
    )


def setups() -> dict:
    return {f"plate-{s}": _setup(s) for s in ("line", "arc", "parabola", "bionic")}


# Sec. 3.1: model particle sizes 3, 2, 1 mm (read as diameters, assumption) with mass
# percentages 8.85, 8.2, 82.95 %
PAPER_PSD_SIZES = (0.003, 0.002, 0.001)
PAPER_PSD_MASS_PERCENT = (8.85, 8.2, 82.95)

PRESET_SETTINGS = {
    "quick": dict(periodic=True, slab_width=0.07, bin_length=0.45, bin_height=0.06,
                  particle_radius=0.007, radius_spread=0.1, stiffness_scale=1.0,
                  dt_fraction=0.3, travel=0.2, settle_time=0.2, psd_sizes=None,
                  psd_mass_percent=None),
    "paper": dict(periodic=False, slab_width=None, bin_length=None, bin_height=None,
                  particle_radius=None, radius_spread=None, stiffness_scale=1.0,
                  dt_fraction=0.2, travel=None, settle_time=1.0,
                  psd_sizes=PAPER_PSD_SIZES, psd_mass_percent=PAPER_PSD_MASS_PERCENT),
}
START = 0.1  # m: cutting edge's start position from the bin's x = 0 end


def paper_params() -> DemParams:
    """Cinnamon soil at the paper's optimum (Sec. 3.3.4): rolling 0.08, JKR 0.37 J/m^2,
    soil-steel static friction 0.64; other values as in the base defaults (same paper)."""
    return DemParams.from_mapping(dict(soil_soil_rolling_friction=0.08,
                                       soil_soil_surface_energy=0.37,
                                       soil_steel_static_friction=0.64),
                                  "<bulldozing.paper_params>")


def measured() -> dict:
    with open(MEASURED, newline="") as fh:
        return {r["directrix"]: (float(r["horizontal_measured_N"]),
                                 float(r["vertical_measured_N"])) for r in csv.DictReader(fh)}


def _given_travel(setup, preset) -> bool:
    """Whether the pass's travel is set (the setup, its named setup or the preset), not the
    speed times the duration."""
    return apply_preset(setup, _setup(setup.get("shape")), PRESET_SETTINGS[preset]).get("travel") is not None


def _settings(setup, preset, source="<bulldozing>"):
    s = apply_preset(setup, _setup(setup.get("shape")), PRESET_SETTINGS[preset])
    radii = [k for k in RADIUS_KEYS if setup.get(k) is not None]
    dist = [k for k in PSD_KEYS if setup.get(k) is not None]
    if radii and dist:
        check(False, source, f"setup.{radii[0]}", "either uniform radii (particle_radius, "
              "radius_spread) or a size distribution (psd_sizes, psd_mass_percent), not both",
              {k: setup[k] for k in radii + dist})
    # a soil gives one kind of sphere size whole: half of one would run beside the preset's
    # other half (a soil's sizes at the paper's mass fractions), so it is refused, naming the
    # key the soil gave
    for given, kind in ((radii, RADIUS_KEYS), (dist, PSD_KEYS)):
        if given and len(given) < len(kind):
            other = next(k for k in kind if k not in given)
            check(False, source, f"setup.{given[0]}", f"setup.{other} beside it (a soil's own sphere sizes "
                  f"are given whole: {' and '.join(kind)})", setup[given[0]])
    if radii:
        # the soil's own uniform radii take the place of the preset's size distribution
        s["psd_sizes"] = s["psd_mass_percent"] = None
    if dist:
        # the soil's own size distribution takes the place of the preset's uniform radii
        s["particle_radius"] = s["radius_spread"] = None
    if s.get("travel") is None:
        s["travel"] = s["speed"] * s["duration"]
    if not s.get("periodic"):
        s["slab_width"] = s["bin_width"]
    return s


def size_distribution(s, source="<bulldozing>"):
    """The run's :class:`soilcal.dem.factories.PSD` (mass percentages of diameters
    ``psd_sizes``), or None when ``psd_mass_percent`` is None (uniform radii)."""
    if s.get("psd_mass_percent") is None:
        return None
    sizes = s.get("psd_sizes")
    check(isinstance(sizes, (list, tuple)) and len(sizes) > 0, source, "setup.psd_sizes",
          "a list of particle diameters (m)", sizes)
    pct = s["psd_mass_percent"]
    check(isinstance(pct, (list, tuple)) and len(pct) > 0, source, "setup.psd_mass_percent",
          "a list of mass percentages", pct)
    return PSD.from_mass_percent(sizes, pct, diameter=True, source=source, field="setup.psd")


def _radii(s, source="<bulldozing>"):
    """(nominal radius, spread, BinSpec.psd) of the run's particles."""
    psd = size_distribution(s, source)
    if psd is None:
        return s.get("particle_radius"), s.get("radius_spread"), None
    r_nom = (3.0 * psd.mean_volume() / (4.0 * math.pi)) ** (1.0 / 3.0)
    return r_nom, 0.0, psd_field(psd)


def _num(s, k, source):
    v = s.get(k)
    check(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0,
          source, f"setup.{k}", "a number > 0", v)
    return v


def validate(setup: dict, preset: str = "quick", source: str = "<bulldozing>",
             params=None) -> dict:
    """Bad settings raise InputError before the run; with ``params``, also a pass the run
    could not finish (:func:`soilcal.dem.scenarios.soilbin.check_pass`).  Returns the run's
    settings, with the surface-energy factor ``cohesion_scale``
    (:func:`soilcal.dem.scenarios.soilbin.reference_cohesion`)."""
    check(preset in PRESETS, source, "preset", f"one of {PRESETS}", preset)
    check(setup.get("shape") in tools.SHAPES, source, "setup.shape",
          f"one of {', '.join(tools.SHAPES)} (Table 9)", setup.get("shape"))
    s = _settings(setup, preset, source)
    for k in ("depth", "speed", "duration", "bin_length", "bin_width", "bin_height",
              "plate_height", "plate_breadth", "travel", "slab_width"):
        _num(s, k, source)
    check(s["depth"] < s["bin_height"], source, "setup.depth",
          f"a cutting depth below the soil height of the bin ({s['bin_height']} m)", s["depth"])
    check(s["depth"] < s["plate_height"], source, "setup.depth",
          f"a cutting depth below the plate height ({s['plate_height']} m)", s["depth"])
    r_nom, spread, _ = _radii(s, source)
    _num(dict(particle_radius=r_nom), "particle_radius", source)
    check(isinstance(spread, (int, float)) and not isinstance(spread, bool)
          and 0.0 <= spread < 1.0, source, "setup.radius_spread", "a radius spread in [0, 1)",
          spread)
    spec = _bin(s, source)
    r_max = spec.r_max
    check(s["depth"] >= 2.0 * r_max, source, "setup.depth",
          f">= 2 r_max = {2.0 * r_max:.4g} m (a cut at least one largest particle diameter "
          "deep)", s["depth"])
    if not s["periodic"]:
        check(s["plate_breadth"] + 4 * r_max <= s["bin_width"], source,
              "setup.bin_width", f"wider than the plate ({s['plate_breadth']} m)",
              s["bin_width"])
    need = START + s["travel"] + 0.05
    check(need <= s["bin_length"], source, "setup.bin_length",
          f">= start + pass + margin = {need:.3g} m", s["bin_length"])
    check(0.0 <= s["stable_from"] < 1.0, source, "setup.stable_from",
          "a fraction of the pass in [0, 1)", s["stable_from"])
    # directrix itself (raises InputError naming the field if the angles cannot be met)
    tools.directrix(s["shape"], height=s["plate_height"], source=source)
    validate_bin(spec, source, "setup")
    s["cohesion_scale"] = reference_cohesion(spec, _bin(_settings(_setup(s["shape"]), "paper"), source),
                                             setup, source)
    spec = replace(spec, cohesion_scale=s["cohesion_scale"])
    if params is not None:
        check_pass(spec, params, source, "setup.speed", s["speed"], s["travel"],
                   tool_time_step(spec, params),
                   duration_field=None if _given_travel(setup, preset) else "setup.duration")
    return s


def _bin(s, source="<bulldozing>") -> BinSpec:
    radius, spread, psd = _radii(s, source)
    return BinSpec(length=s["bin_length"], width=s["slab_width"], height=s["bin_height"],
                   radius=radius, spread=spread,
                   periodic_y=bool(s["periodic"]), settle_time=s["settle_time"],
                   stiffness_scale=s["stiffness_scale"], dt_fraction=s["dt_fraction"],
                   psd=psd, cohesion_scale=s.get("cohesion_scale", 1.0))


def run(setup: dict, params: DemParams, preset: str = "quick", seed: int = 0, threads=None,
        vtk_dir=None, source: str = "<bulldozing>", use_cache: bool = True, restart=None) -> Result:
    """One plate pass (module docstring).  ``restart``: a :class:`soilcal.dem.restart.Restart`
    that the run resumes from and writes every few minutes (phases ``bin_0``, ``bin_1``,
    ``pass``: :func:`soilcal.dem.scenarios.soilbin.tool_pass`); the numbers are those of an
    uninterrupted run."""
    from soilcal.dem import restart as rst

    s = validate(setup, preset, source, params=params)
    nthreads = threads_used(threads)
    prog = rst.Progress(restart)
    prog.resume()
    spec = _bin(s, source)
    bed = settled_bin(spec, params, preset, seed, source, use_cache, progress=prog)
    pad = 2.0 * spec.r_max
    breadth = s["slab_width"] + 2 * pad if s["periodic"] else s["plate_breadth"]
    v, t = tools.bulldozing_plate(s["shape"], breadth=breadth, height=s["plate_height"],
                                  source=source)
    z_tool = bed["surface"] - s["depth"]
    v = v + np.array([START, 0.5 * s["slab_width"], z_tool])
    lo, hi = v.min(axis=0), v.max(axis=0)

    def trench(x, r):
        return ((x[:, 0] >= lo[0] - pad) & (x[:, 0] <= hi[0] + pad) & (x[:, 2] >= lo[2] - pad)
                & (np.abs(x[:, 1] - 0.5 * s["slab_width"]) <= 0.5 * breadth + pad))

    duration = s["travel"] / s["speed"]

    def pose(tt):
        return v + np.array([s["speed"] * tt, 0, 0]), t

    out = tool_pass(spec, params, preset, seed, source, v, t, (s["speed"], 0.0, 0.0), duration,
                    trench, vtk_dir=vtk_dir, stem=f"bulldozing_{s['shape']}",
                    use_cache=use_cache, tool_pose=pose, log_dt=0.01, bed=bed, progress=prog)
    prog.finish()
    scale = s["plate_breadth"] / s["slab_width"] if s["periodic"] else 1.0
    tt, f = out["t"], out["force"] * scale
    ts = s["stable_from"] * duration
    fx, fx_sd = stable_mean(tt, -f[:, 0], ts)
    fz, fz_sd = stable_mean(tt, f[:, 2], ts)
    meas = measured().get(s["shape"], (float("nan"), float("nan")))
    resp = dict(horizontal_force_N=fx, horizontal_force_sd_N=fx_sd,
                vertical_force_N=fz, vertical_force_sd_N=fz_sd,
                resultant_force_N=math.hypot(fx, fz),
                resultant_angle_deg=math.degrees(math.atan2(abs(fz), fx)),
                horizontal_measured_N=meas[0], vertical_measured_N=meas[1],
                horizontal_error_percent=100.0 * (fx - meas[0]) / meas[0],
                force_scale=scale, peak_overlap=float(out["peak_overlap"]),
                bin_from_cache=bool(out["from_cache"]))
    return Result(scenario=NAME, preset=preset, seed=int(seed), n_particles=out["n"],
                  steps=int(out["steps"] + out["settle_steps"]),
                  sim_time_s=out["steps"] * out["dt"], wall_s=prog.wall_s,
                  threads=nthreads, params=params.as_dict(), setup=dict(s), responses=resp,
                  series=dict(t=tt, horizontal_N=-f[:, 0], vertical_N=f[:, 2]))
