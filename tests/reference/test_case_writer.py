"""The LIGGGHTS input written for a soilcal case (no LIGGGHTS needed)."""

import json

import numpy as np
import pytest

from soilcal.dem.engine import Simulation
from soilcal.errors import InputError
from soilcal.reference import liggghts as L
from soilcal.reference.few import build, materials

BOUNDS = (-0.05, 0.05, -0.05, 0.05, -0.01, 0.05)


def test_case_files_carry_the_simulation(tmp_path):
    sim, phases = build("stack", "constant_torque")
    info = L.write_case(sim, tmp_path, phases, BOUNDS)
    deck = (tmp_path / "in.case").read_text()
    data = (tmp_path / "data.case").read_text().splitlines()
    # E per atom type (soil 1e7, steel 2e7 Pa), pair tables row by row (type 1-1, 1-2, 2-1, 2-2)
    assert "youngsModulus peratomtype 10000000.0 20000000.0" in deck
    assert "coefficientRestitution peratomtypepair 2 0.5 0.4 0.4 0.5" in deck
    assert "coefficientFriction peratomtypepair 2 0.5 0.6 0.6 0.3" in deck
    assert "coefficientRollingFriction peratomtypepair 2 0.1 0.15 0.15 0.0" in deck
    assert "pair_style gran model hertz tangential history rolling_friction cdt" in deck
    assert "primitive type 2 zplane 0.0" in deck  # the steel floor
    assert f"timestep {sim.dt!r}" in deck and "run 5000" in deck
    assert info["conventions_match"] and info["n"] == 3
    # atoms: id type diameter density x y z, ids = insertion ids + 1; the steel sphere is type 2
    atoms = [ln.split() for ln in data[data.index("Atoms") + 2:data.index("Velocities") - 1]]
    assert [a[:2] for a in atoms] == [["1", "1"], ["2", "2"], ["3", "1"]]
    assert float(atoms[2][2]) == pytest.approx(2 * 0.8e-3)
    assert float(atoms[1][3]) == pytest.approx(7800.0)
    assert json.loads((tmp_path / "case.json").read_text())["law"].endswith("cdt")


def test_epsd_becomes_liggghts_epsd_undamped(tmp_path):
    """soilcal's epsd (Ai et al.'s spring without the viscous term) is LIGGGHTS's
    rolling_friction epsd with coefficientRollingViscousDamping 0; the form matches with the
    liggghts conventions only."""
    sim, phases = build("stack", "epsd")
    info = L.write_case(sim, tmp_path, phases, BOUNDS)
    deck = (tmp_path / "in.case").read_text()
    assert "pair_style gran model hertz tangential history rolling_friction epsd" in deck
    assert "coefficientRollingFriction peratomtypepair 2 0.1 0.15 0.15 0.0" in deck
    assert "coefficientRollingViscousDamping peratomtypepair 2 0.0 0.0 0.0 0.0" in deck
    assert info["conventions_match"]
    sim, phases = build("stack", "epsd", conventions="edem")
    assert not L.write_case(sim, tmp_path, phases, BOUNDS)["conventions_match"]


@pytest.mark.parametrize("rolling, entry, value", [
    ("epsd", "rolling_wall", "relative"),  # the epsd spring turns with omega_i - omega_wall
    ("constant_torque", "rolling_wall", "relative"),
    ("none", "tangential_slip", "damped"),  # every case's Mindlin history
    ("none", "contact_lever", "radius"),
    ("epsd", "history_rotation", "rescale"),
])
def test_a_convention_the_law_uses_off_the_liggghts_set_is_no_match(tmp_path, rolling, entry,
                                                                      value):
    """The liggghts set with one entry changed that the case's law computes with is not
    LIGGGHTS's law: conventions_match is False (LIGGGHTS turns the epsd spring against a
    turning drum by the sphere's own rotation, so with rolling_wall: relative the few-body
    drum_turn's spins part from LIGGGHTS's by several times their size)."""
    from soilcal.dem.contact import CODE_CONVENTIONS, CONVENTION_TABLES

    sim, phases = build("drum_turn", rolling)
    assert L.write_case(sim, tmp_path, phases, BOUNDS)["conventions_match"]
    sim.codes[5 + CODE_CONVENTIONS.index(entry)] = CONVENTION_TABLES[entry][value]
    assert not L.write_case(sim, tmp_path, phases, BOUNDS)["conventions_match"]
    # LAMMPS's set with LIGGGHTS's rolling entries (its lever, force and axis are already
    # LIGGGHTS's) still has LAMMPS's tangential history
    sim, phases = build("drum_turn", rolling, conventions="lammps")
    for k, v in (("rolling_wall", "absolute"), ("epsd_form", "liggghts")):
        sim.codes[5 + CODE_CONVENTIONS.index(k)] = CONVENTION_TABLES[k][v]
    assert not L.write_case(sim, tmp_path, phases, BOUNDS)["conventions_match"]


def test_other_conventions_are_recorded_and_damping_off_passed(tmp_path):
    sim, phases = build("wall_roll", "constant_torque", conventions="edem")
    assert not L.write_case(sim, tmp_path, phases, BOUNDS)["conventions_match"]
    sim = Simulation(materials(False), dt=1e-6,
                     contact_model=dict(tangential_damping="off"))
    sim.add_particles([[0, 0, 0.01]], 1e-3, "soil")
    sim.add_plane((0, 0, 0), (0, 0, 1), "steel")
    L.write_case(sim, tmp_path, [(10, {})], BOUNDS)
    deck = (tmp_path / "in.case").read_text()
    assert "pair_style gran model hertz tangential history tangential_damping off" in deck
    assert "zplane 0.0 tangential_damping off" in deck


def test_moving_mesh_becomes_a_move_fix(tmp_path):
    sim, phases = build("mesh_drag", "none")
    L.write_case(sim, tmp_path, phases, BOUNDS)
    deck = (tmp_path / "in.case").read_text()
    assert "fix wall0 all mesh/surface file wall0.stl type 2" in deck
    assert "move/mesh mesh wall0 linear 0.01 0.002 0.0" in deck
    stl = (tmp_path / "wall0.stl").read_text()
    assert stl.count("facet normal") == 2


def test_the_plastic_normal_law_is_named(tmp_path):
    sim = Simulation(materials(False), dt=1e-6, contact_model=dict(normal="eepa"))
    sim.add_particles([[0, 0, 0.01]], 1e-3, "soil")
    with pytest.raises(InputError) as exc:
        L.write_case(sim, tmp_path, [(10, {})], BOUNDS)
    assert exc.value.field == "contact_model.normal"


@pytest.mark.parametrize("change,field", [
    (lambda s: s.add_plane((0, 0, 0), (1, 1, 0), "steel"), "walls.plane"),
    (lambda s: s.add_cylinder((0, 0, 0), (0, 0, 1), 0.05, 0.05, "steel"), "walls.cylinder"),
])
def test_walls_outside_the_translation_are_named(tmp_path, change, field):
    sim = Simulation(materials(False), dt=1e-6)
    sim.add_particles([[0, 0, 0.01]], 1e-3, "soil")
    change(sim)
    with pytest.raises(InputError, match=field):
        L.write_case(sim, tmp_path, [(10, {})], BOUNDS)


def test_phase_errors_are_named(tmp_path):
    sim, _ = build("wall_roll", "none")
    with pytest.raises(InputError, match=r"phases\[0\].steps"):
        L.write_case(sim, tmp_path, [(-1, {})], BOUNDS)
    with pytest.raises(InputError, match="phases.wall"):
        L.write_case(sim, tmp_path, [(10, {"tube": (0, 0, 1)})], BOUNDS)
    with pytest.raises(InputError, match="phases.floor"):  # LIGGGHTS planes do not move
        L.write_case(sim, tmp_path, [(10, {"floor": (0, 0, 1)})], BOUNDS)
    with pytest.raises(InputError, match="bounds"):
        L.write_case(sim, tmp_path, [(10, {})], (1, 0, 0, 1, 0, 1))


def test_dump_reader_sorts_by_id(tmp_path):
    p = tmp_path / "d.dump"
    p.write_text("ITEM: TIMESTEP\n0\nITEM: ATOMS id radius x\n2 0.1 5.0\n1 0.2 4.0\n")
    d = L.read_dump(p)
    assert list(d["id"]) == [1, 2] and list(d["x"]) == [4.0, 5.0]


def test_run_phases_moves_and_stops_walls():
    sim, phases = build("mesh_drag", "none")
    x0 = sim._warr["prim_par"][:, 0].copy()
    L.run_phases(sim, phases)
    moved = sim._warr["prim_par"][:, 0] - x0
    np.testing.assert_allclose(moved, 0.01 * 5000 * 1e-6, rtol=1e-9)
    assert not np.any(sim._warr["wall_vel"])


def test_turning_mesh_becomes_a_rotate_fix_and_every_phase_is_dumped(tmp_path):
    import math

    sim, phases = build("drum_turn", "none")
    L.write_case(sim, tmp_path, phases + [(5, {})], BOUNDS)
    deck = (tmp_path / "in.case").read_text()
    line = next(ln for ln in deck.splitlines() if "rotate" in ln)
    assert line.split("rotate", 1)[1].split() == [
        "origin", "0.0", "0.0", "0.0", "axis", "0.0", "1.0", "0.0", "period",
        repr(2 * math.pi / 2.0)]
    assert "dump phase0 all custom 1 phase0.dump" in deck
    assert "dump phase1 all custom 1 phase1.dump" in deck
    with pytest.raises(InputError, match="not both"):
        L.write_case(sim, tmp_path, [(5, {"drum": {"velocity": (0, 0, 1), "omega": (0, 1, 0)}})],
                     BOUNDS)
    with pytest.raises(InputError, match=r"phases\[0\].drum.omega"):
        L.write_case(sim, tmp_path, [(5, {"drum": {"omega": (0, "x")}})], BOUNDS)
