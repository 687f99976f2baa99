"""Confined (uniaxial) compression in a steel tube: axial stress-strain curve.

Apparatus and procedure (cohesive soil, 004 Sec. 3.7, Fig. 15): a steel cylinder of inner
diameter 100 mm and height 300 mm, a loading rod of diameter 99 mm, 3 kg of soil poured in
naturally, the rod pushed down at a constant 0.008 m/s by a UTM5105 testing machine; the
axial stress-strain curve after loading starts is recorded (5, 10, 15 % moisture, five
repeats each).

Simulation: tube = the engine's cylinder wall (inner side), floor = the plane z = 0, rod face
= a disc wall of the rod's radius facing down, all steel.  Spheres are placed at random in
the tube (at most 30 % solid fraction), settle (translational kinetic energy below
1/2 M v_rest^2), the rod starts half a radius above the highest sphere and moves down at
``rod_speed``; every ``sample_dz`` of travel the rod's height z_rod and the vertical force of
the particles on it, F_z, are recorded.  With h0 the rod height at the first sample with
F_z > 0 (first contact; the paper records only after loading starts)::

    sigma = F_z / (pi R_rod^2),     epsilon = (h0 - z_rod) / h0

(:func:`soilcal.dem.measure.stress_strain`).  The run stops at ``max_strain`` or, earlier,
when the largest overlap reaches ``jam_overlap`` (default 15 %) of a radius: a bed poured at
solid fraction phi0 jams near 1 - phi0 / 0.64 strain (random close packing), beyond which
spheres of the soft quick stiffness can only interpenetrate (the engine stops at 30 %).  The
stop is reported (``stop_reason``: ``max_strain`` or ``overlap``, ``strain_end``) with the
fill's solid fraction under the rod at first contact (``solid_fraction_0``); stresses at
strains beyond ``strain_end`` are NaN.

Unloading (``unload: true``; the paper's test loads only, so its setup keeps ``false``): after
the stop the rod moves back up at ``rod_speed``, sampled as on the way down, until the
particles' force on it has fallen to zero (or it is back at h0).  The strain at which the
force reaches zero (linear interpolation between the last loaded and the first free sample)
is the strain the sample keeps; ``recovered_strain`` = ``strain_end`` minus it, the elastic
rebound of the contacts.  Of the strain a bed takes, only the contacts' own compression comes
back: the rearrangement of the grains stays.  With the plastic contact law (``eepa``,
:mod:`soilcal.dem.contact`) each contact gives back only the part above its plastic overlap,
so the rebound shrinks as the plasticity ratio grows (for an affine packing of Hertz
contacts by the factor 1 - lambda_p^(2/3)).  The loading curve moves too, though less
plainly: a contact under a rising load is on its loading branch, Hertz's, but the fill
settles and the grains rearrange through plastic contacts.  On the quick Guangxi bed (1,000
spheres, JKR, to 8 % strain, seeds 1-3) lambda_p = 0.5 lowered the recovered strain from
0.0195 / 0.0235 / 0.0196 to 0.0132 / 0.0170 / 0.0130 and raised the stress at 5 % strain
from 0.127 / 0.195 / 0.066 to 0.163 / 0.314 / 0.129 kPa, whose seed scatter is several times
the recovered strain's.  A loading-unloading confined compression test is how EEPA
parameters are calibrated (Thakur et al. 2014, Powder Technol. 254:28).

Fill: N = phi m / (rho_p <v_p>) spheres for the load mass m at settled solid fraction
phi = 0.6 of the particle density.  ``quick``: the load is reduced to about 1000 spheres of
radius r_q sized for a sample about 40 mm high (radii uniform in [0.9, 1.1] r_q), shear
modulus capped at 5e5 Pa (the stress level scales with it: the convergence study shows by
how much); ``paper``: 3 kg of the paper's particle sizes (004 Sec. 2.6, taken as diameters)
and the unscaled modulus.  That is 69.7 million spheres (half of them 0.315 mm across), about
144 GB of engine state (:data:`soilcal.dem.state.BYTES_PER_PARTICLE`); the paper prints the
mass but no particle count, and its own repose runs used 0.1-0.3 kg (Sec. 2.6, 3.6).  On a
machine with less memory the run stops at the insertion, before anything is allocated,
with the count and the memory it needs; ``n_particles`` or ``radius`` in the setup give a
smaller sample of the quick height.

Responses: ``stress_5_kpa``, ``stress_10_kpa``, ``stress_20_kpa`` (stress at 5, 10, 20 %
strain, linear interpolation), ``stress_max_kpa``, ``h0_m``, ``strain_end``, ``stop_reason``,
``solid_fraction_0``, ``recovered_strain`` (NaN without unloading); series: strain, stress
(Pa), rod height and force, and with unloading the same four of the way back
(``strain_unload``, ...).
"""

from __future__ import annotations

import math

import numpy as np

from soilcal.dem import measure
from soilcal.dem.factories import CylinderRegion, UniformRadius, insert_random
from soilcal.dem.scenarios.base import (DemParams, Frames, Result, check, check_discretisation,
                                        check_preset, make_simulation, paper_cohesion, paper_psd,
                                        rng, setup_number, threads_used)

NAME = "compression"
#: writes and reads restart files (soilcal.dem.restart)
RESTARTABLE = True
#: every response a run reports (``Result.responses``)
RESPONSES = (
    "h0_m", "fill_settled", "peak_overlap", "stress_max_kpa", "strain_end", "stop_reason",
    "solid_fraction_0", "stress_5_kpa", "stress_10_kpa", "stress_20_kpa", "recovered_strain",
)
#: the responses a soil's ``simulation`` block may measure (numbers a design point yields)
MEASURES = (
    "stress_max_kpa", "strain_end", "solid_fraction_0", "stress_5_kpa", "stress_10_kpa",
    "stress_20_kpa", "recovered_strain",
)
PHI = 0.6


def setups() -> dict:
    return {
        # 004 Sec. 3.7: tube inner diameter 100 mm, height 300 mm, loading rod 99 mm,
        # 3 kg of soil, 0.008 m/s.  Sec. 2.6: particle sizes 2.5 (14 %), 1.25 (14 %),
        # 0.63 (22 %), 0.315 mm (50 %).  Final strain not printed: 30 %.
        "guangxi-cohesive": dict(tube_diameter=0.100, tube_height=0.300, rod_diameter=0.099,
                                 load_mass=3.0, rod_speed=0.008, max_strain=0.30,
                                 quick_height=0.040, sample_dz=0.0002, jam_overlap=0.15,
                                 rest_speed=0.005, max_settle_time=3.0, n_particles=None,
                                 radius=None, stiffness_scale=None, dt_fraction=None,
                                 rolling_model=None, contact_conventions=None, unload=False,
                                 scale_cohesion=True,
                                 paper_psd=[[0.00125, 14.0], [0.000625, 14.0],
                                            [0.000315, 22.0], [0.0001575, 50.0]]),
    }




def sizing(setup, preset, params: DemParams | None = None):
    d = check_preset(preset)
    rho = (params or DemParams()).soil_density
    R = setup["tube_diameter"] / 2
    r_set, n_set = setup.get("radius"), setup.get("n_particles")
    if preset == "paper" and r_set is None and n_set is None:
        dist = paper_psd(setup)
        n = int(round(setup["load_mass"] / (rho * dist.mean_volume())))
    else:
        vol = math.pi * R * R * setup["quick_height"]
        dist = (UniformRadius.splitting(PHI * vol, int(n_set or d["n_particles"]))
                if r_set is None else UniformRadius.about(r_set))
        n = int(n_set) if n_set is not None else int(round(PHI * vol / dist.mean_volume()))
    return dict(dist=dist, n=n, r_max=float(dist.r_max),
                load_mass=n * dist.mean_volume() * rho)


def validate(setup, preset="quick", source="<input>", params=None):
    """Fail before the run on impossible settings (``params``: the run's DEM parameters, for
    the soil density; the defaults when None)."""
    check_preset(preset, source)
    D = setup_number(setup, "tube_diameter", source)
    H = setup_number(setup, "tube_height", source)
    Dr = setup_number(setup, "rod_diameter", source)
    check(Dr < D, source, "setup.rod_diameter", f"a rod narrower than the tube ({D} m)", Dr)
    setup_number(setup, "load_mass", source)
    setup_number(setup, "rod_speed", source)
    e = setup_number(setup, "max_strain", source)
    check(e < 0.9, source, "setup.max_strain", "a strain in (0, 0.9)", e)
    hq = setup_number(setup, "quick_height", source)
    check(hq < H, source, "setup.quick_height", f"a sample lower than the tube ({H} m)", hq)
    setup_number(setup, "sample_dz", source)
    jam = setup_number(setup, "jam_overlap", source)
    limit = check_preset(preset, source)["max_overlap"]
    check(jam < limit, source, "setup.jam_overlap",
          f"an overlap fraction below the engine's blow-up limit {limit}", jam)
    setup_number(setup, "rest_speed", source)
    setup_number(setup, "max_settle_time", source)
    check(isinstance(setup.get("unload", False), bool), source, "setup.unload",
          "true or false (move the rod back up after the stop)", setup.get("unload"))
    check_discretisation(setup, source)
    sz = sizing(setup, preset)
    check(D >= 8 * sz["r_max"], source, "setup.tube_diameter",
          f"at least 4 particle diameters ({8 * sz['r_max']:.4g} m)", D)
    rho = (params or DemParams()).soil_density
    h_fill = sz["load_mass"] / (rho * PHI) / (math.pi * D * D / 4)
    # the particle density of the soil is not known here (the papers' densities mix bulk and
    # particle values): refuse only a load that would overflow the tube twice over
    check(h_fill < 2 * H, source, "setup.load_mass",
          f"a load whose settled height ({h_fill:.3g} m at {rho:g} kg/m^3, solid fraction "
          f"{PHI}) fits the tube ({H} m)", setup["load_mass"])


def _sample(prog, nsub: int, rod: int) -> float:
    """One sample of the rod's travel: ``nsub`` steps (resumably, a restart file when due),
    then the particles' vertical force on the rod."""
    prog.checkpoint()
    prog.advance(nsub, "sample_steps")
    prog.vars["sample_steps"] = 0
    return float(prog.sim.wall_force[rod, 2])


def run(setup, params: DemParams, preset="quick", seed=0, threads=None, vtk_dir=None,
        source="<compression>", restart=None) -> Result:
    """One compression test (module docstring).  ``restart``: a
    :class:`soilcal.dem.restart.Restart` that the run resumes from and writes every few
    minutes (phases ``settle_fill``, ``press``, ``unload``); the numbers are those of an
    uninterrupted run."""
    from soilcal.dem import restart as rst

    validate(setup, preset, source, params)
    nthreads = threads_used(threads)
    sz = sizing(setup, preset, params)
    R, H = setup["tube_diameter"] / 2, setup["tube_height"]
    Rr = setup["rod_diameter"] / 2
    coh = paper_cohesion(setup, sz["dist"], source)
    frames = Frames(vtk_dir, NAME)
    prog = rst.Progress(restart, frames)
    if not prog.resume():
        gen = rng(seed, NAME)
        sim, scale = make_simulation(params, setup, preset, source, cohesion=coh,
                                     skin=0.5 * sz["r_max"])
        sim.add_plane((0, 0, 0), (0, 0, 1), "steel", name="floor")
        vol = sz["n"] * sz["dist"].mean_volume()
        rm = sz["r_max"]
        h_ins = vol / (0.30 * math.pi * (R - rm) ** 2)
        tube_h = max(H, h_ins + 4 * rm)
        sim.add_cylinder((0, 0, tube_h / 2), (0, 0, 1), R, tube_h / 2, "steel", inner=True,
                         name="tube")
        x, r = insert_random(CylinderRegion(R - 1.001 * rm, 1.001 * rm, h_ins), sz["dist"],
                             n=sz["n"], rng=gen, max_fraction=0.35, source=source,
                             field="particles")
        order = np.argsort(x[:, 2], kind="stable")
        sim.add_particles(x[order], r[order], "soil")
        frames(sim)
        prog.begin(sim, "settle_fill", scale=scale)
    sim, st = prog.sim, prog.vars
    if prog.at("settle_fill"):
        prog.checkpoint()
        ok0, _ = prog.settle(setup["rest_speed"], setup["max_settle_time"], "fill_steps")
        top = float((sim.x[:, 2] + sim.p.r).max())
        z0 = top + 0.5 * float(sim.p.r.min())
        sim.add_disk((0, 0, z0), (0, 0, -1), Rr, "steel", name="rod",
                     velocity=(0, 0, -setup["rod_speed"]))
        frames(sim)
        sim.run(0)
        prog.next("press", fill_settled=int(ok0), top=top, z0=z0, step0=sim.step, z=z0,
                  h0=None, stop="max_strain", z_rod=[], fz=[])
    ok0, scale, top, z0 = st["fill_settled"], st["scale"], st["top"], st["z0"]
    rod = sim.walls.names.index("rod")
    nsub = max(1, int(round(setup["sample_dz"] / setup["rod_speed"] / sim.dt)))
    dz_step = setup["rod_speed"] * sim.dt
    # upper bound of the travel: the whole height above the floor
    while prog.at("press") and st["z"] > 0.05 * top:
        f = _sample(prog, nsub, rod)
        z = st["z"] = z0 - setup["rod_speed"] * (sim.step - st["step0"]) * sim.dt  # rigid translation
        st["z_rod"].append(z)
        st["fz"].append(f)
        if st["h0"] is None and f > 0:
            st["h0"] = z
        if st["h0"] is not None and (st["h0"] - z) / st["h0"] >= setup["max_strain"]:
            break
        if float(sim.p.ovr.max()) >= setup["jam_overlap"]:
            st["stop"] = "overlap"  # jammed: further travel only squeezes spheres into each other
            break
    if prog.at("press") and setup.get("unload", False):
        sim.set_wall_motion(rod, velocity=(0, 0, setup["rod_speed"]))
        prog.next("unload", step1=sim.step, z1=st["z"], z_up=[], fz_up=[])
    # upper bound of the way back: h0 (or the first contact's height)
    while prog.at("unload"):
        f = _sample(prog, nsub, rod)
        z = st["z1"] + setup["rod_speed"] * (sim.step - st["step1"]) * sim.dt
        st["z_up"].append(z)
        st["fz_up"].append(f)
        if f <= 0.0 or z >= (st["h0"] if st["h0"] is not None else top):
            break
    z_rod, fz, h0, stop = st["z_rod"], st["fz"], st["h0"], st["stop"]
    frames(sim)
    frames.close()
    prog.finish()
    z_rod, fz = np.asarray(z_rod), np.asarray(fz)
    if h0 is None:
        h0 = top
    eps, sig = measure.stress_strain(z_rod, fz, Rr, h0)
    series = dict(strain=eps, stress_pa=sig, z_rod_m=z_rod, force_n=fz)
    recovered = float("nan")
    if "z_up" in st:
        z_up, f_up = np.asarray(st["z_up"]), np.asarray(st["fz_up"])
        eps_up, sig_up = measure.stress_strain(z_up, f_up, Rr, h0)
        series.update(strain_unload=eps_up, stress_unload_pa=sig_up, z_rod_unload_m=z_up,
                      force_unload_n=f_up)
        if eps.size:
            recovered = eps[-1] - measure.unloaded_strain(eps[-1], sig[-1], eps_up, sig_up)
    resp = dict(h0_m=float(h0), fill_settled=int(ok0), peak_overlap=sim.peak_overlap,
                stress_max_kpa=float(sig.max() / 1e3) if sig.size else float("nan"),
                strain_end=float(eps[-1]) if eps.size else 0.0, stop_reason=stop,
                solid_fraction_0=float((4.0 / 3.0 * math.pi * sim.p.r**3).sum()
                                       / (math.pi * R * R * h0)),
                recovered_strain=recovered)
    for e in (0.05, 0.10, 0.20):
        resp[f"stress_{int(round(e * 100))}_kpa"] = measure.value_at(eps, sig, e) / 1e3
    setup_out = dict(setup)
    setup_out.pop("paper_psd", None)
    setup_out.update(stiffness_scale=scale, cohesion_scale=coh, dt=sim.dt,
                     dt_fraction=sim.dt / sim.rayleigh, r_max=sz["r_max"],
                     load_mass=sz["load_mass"], rod_step_m=dz_step)
    return Result(scenario=NAME, preset=preset, seed=int(seed), n_particles=int(sim.n),
                  steps=int(sim.step), sim_time_s=float(sim.step * sim.dt), wall_s=prog.wall_s,
                  threads=nthreads, params=params.as_dict(), setup=setup_out, responses=resp,
                  series=series)

