"""Bad parameters fail before the run with a clear message; blow-ups name step and particle."""

import math
import re

import numpy as np
import pytest

from conftest import table
from soilcal.dem.engine import Simulation
from soilcal.dem.materials import Material, MaterialTable
from soilcal.errors import InputError, SimulationError


@pytest.mark.parametrize("e", [0.0, -0.2, 1.5])
def test_restitution_out_of_range(e):
    with pytest.raises(InputError, match=r"restitution: expected a coefficient of restitution in \(0, 1\]"):
        table(e=e)


def test_negative_friction():
    with pytest.raises(InputError, match=r"\.friction: expected sliding friction >= 0"):
        table(mu=-0.1)
    with pytest.raises(InputError, match=r"rolling_friction: expected rolling friction >= 0"):
        table(mur=-0.01)


@pytest.mark.parametrize("kw", [dict(shear=0.0), dict(shear=-1e6), dict(youngs=0.0)])
def test_non_positive_modulus(kw):
    with pytest.raises(InputError, match=r"materials\.soil\.(shear|youngs): expected (G|E) > 0 Pa"):
        Material("soil", 2600, 0.3, **kw)


def test_time_step_above_rayleigh_bound():
    sim = Simulation(table(E=1e8), dt=1e-3)
    sim.add_particles([[0, 0, 0.01]], 2e-3, "soil")
    with pytest.raises(InputError, match=r"dt: expected a time step <= the Rayleigh time"):
        sim.run(10)
    assert sim.step == 0


def test_unknown_contact_model_name():
    with pytest.raises(InputError, match=r"contact_model\.rolling: expected one of"):
        Simulation(table(), contact_model=dict(rolling="type_b"))


def test_missing_pair_parameters():
    mats = MaterialTable()
    mats.add(Material("soil", 2600, 0.3, youngs=1e8))
    mats.add(Material("steel", 7800, 0.3, youngs=2e11))
    mats.set_pair("soil", "soil", 0.5, 0.5)
    sim = Simulation(mats)
    sim.add_particles([[0, 0, 0.01]], 2e-3, "soil")
    sim.add_plane((0, 0, 0), (0, 0, 1), "steel")
    with pytest.raises(InputError, match=r"interactions\.soil-steel: expected contact parameters"):
        sim.run(1)


def test_blow_up_names_step_and_particle():
    # a fast sphere hitting a soft floor: Hertz overlap ~ 40 % of the radius
    sim = Simulation(table(E=1e6), dt_fraction=0.2, gravity=(0, 0, 0))
    sim.add_particles([[0, 0, 0.05], [0.0, 0.0, 2.1e-3]], 2e-3, "soil",
                      v=[[0, 0, 0], [0, 0, -5.0]])
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    with pytest.raises(SimulationError, match=r"step \d+: particle 1: overlap above 5 % of its radius") as err:
        sim.run(10000)
    assert 0 < sim.step < 10000
    # the simulated time of the blow-up: its step times the time step, as the message gives both
    m = re.search(r"step (\d+):.*dt ([0-9.e+-]+) s, t ([0-9.e+-]+) s\)", str(err.value))
    assert m and float(m.group(3)) == pytest.approx(int(m.group(1)) * float(m.group(2)), rel=1e-3)


def _two(dist, max_overlap=0.05, **kw):
    sim = Simulation(table(), dt=1e-6, gravity=(0, 0, 0), max_overlap=max_overlap, **kw)
    sim.add_particles([[0, 0, 0], [0, 0, dist]], 1e-3, "soil")
    return sim


@pytest.mark.parametrize("dist,pct", [(1e-3, "100"), (0.0, "200"), (1.9e-3, "10")])
def test_initial_overlap_is_named_before_any_step(dist, pct):
    """Spheres placed overlapping beyond max_overlap (2 r - d over r) are an input error of the
    starting state, naming both spheres, not a blow-up of step 1 that asks for a shorter
    step; the coincident pair (no normal) is caught the same way."""
    sim = _two(dist)
    with pytest.raises(InputError) as exc:
        sim.run(10)
    assert exc.value.field == "particles" and sim.step == 0
    assert "max_overlap = 5 %" in exc.value.expected
    assert re.search(rf"particle [01] overlaps particle [01] by {pct} % of its radius", exc.value.got)
    # within the limit (4 %) it runs, and the pair pushes apart
    sim = _two(1.96e-3)
    assert sim.run(10) == 10 and sim.x[sim.index([1])[0], 2] > 1.96e-3


def test_sphere_through_a_wall_at_the_start_is_named():
    sim = Simulation(table(), dt=1e-6, gravity=(0, 0, 0))
    sim.add_particles([[0, 0, -0.5e-3]], 1e-3, "soil")
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    with pytest.raises(InputError, match=r"particle 0 overlaps a wall by 150 % of its radius"):
        sim.run(1)
    assert sim.step == 0


@pytest.mark.parametrize("kw,field", [
    (dict(x=[[0, 0, float("nan")]]), "particles.x"),
    (dict(x=[[0, 0]]), "particles.x"),
    (dict(x="origin"), "particles.x"),
    (dict(x=[[0, 0, 0], [0, 0, 0.01]], r=[1e-3, 1e-3, 1e-3]), "particles.radius"),
    (dict(r=float("inf")), "particles.radius"),
    (dict(x=[[0, 0, 0], [0, 0, 0.01]], v=[[0, 0, 1], [0, 0, 1], [0, 0, 1]]), "particles.v"),
    (dict(v=[[0, 0, float("inf")]]), "particles.v"),
    (dict(omega=[1.0, 2.0]), "particles.omega"),
])
def test_bad_particle_inputs_are_named(kw, field):
    args = dict(x=[[0, 0, 0.01]], r=1e-3, v=None, omega=None) | kw
    sim = Simulation(table(), dt=1e-6)
    with pytest.raises(InputError) as exc:
        sim.add_particles(args["x"], args["r"], "soil", v=args["v"], omega=args["omega"])
    assert exc.value.field == field and sim.n == 0


def test_one_velocity_row_is_every_particles():
    sim = Simulation(table(), dt=1e-6)
    sim.add_particles([[0, 0, 0.01], [0, 0, 0.02]], 1e-3, "soil", v=[0, 0, -1])
    assert sim.v.tolist() == [[0, 0, -1], [0, 0, -1]]


@pytest.mark.parametrize("kw,field", [
    (dict(gravity=(0, -9.81)), "gravity"),
    (dict(gravity=(0, 0, float("nan"))), "gravity"),
    (dict(box=(0, 1, 0)), "box"),
    (dict(max_overlap=-0.1), "max_overlap"),
    (dict(max_overlap="5 %"), "max_overlap"),
    (dict(coarse_grain="2"), "coarse_grain"),
    (dict(dt="1e-6"), "dt"),
    (dict(dt=0.0), "dt"),
    (dict(skin=float("nan")), "skin"),
    (dict(dt_fraction="0.2"), "dt_fraction"),
    (dict(contact_model=["hertz"]), "contact_model"),
    (dict(contact_model=dict(conventions=["lammps"])), "contact_model.conventions"),
    (dict(contact_model=dict(conventions={"conventions": "lammps"})), "contact_model.conventions"),
    (dict(contact_model=dict(rolling=["constant_torque"])), "contact_model.rolling"),
])
def test_bad_simulation_arguments_are_named(kw, field):
    with pytest.raises(InputError) as exc:
        Simulation(table(), **kw)
    assert exc.value.field == field


def test_misspelt_model_entry_lists_every_entry():
    """A misspelt model entry is not taken for a convention: the error lists the model's own
    entries (rolling, cohesion, ...) with the conventions."""
    with pytest.raises(InputError) as exc:
        Simulation(table(), contact_model=dict(rollin="constant_torque"))
    assert exc.value.field == "contact_model.rollin"
    for key in ("rolling", "cohesion", "damping_eta", "conventions", "rolling_lever"):
        assert f"'{key}'" in exc.value.expected


def test_yaml_boolean_for_on_off_gets_a_hint():
    with pytest.raises(InputError, match=r"tangential_damping: expected one of \['off', 'on'\], "
                                         r"got False \(YAML reads unquoted on/off"):
        Simulation(table(), contact_model=dict(tangential_damping=False))


@pytest.mark.parametrize("add,field", [
    (lambda s: s.add_disk((0, 0, 0), (0, 0, 1), -0.01, "soil"), "walls.disk.radius"),
    (lambda s: s.add_rectangle((0, 0, 0), (0, 0, 1), (1, 0, 0), 0.01, 0.0, "soil"),
     "walls.rectangle.half_v"),
    (lambda s: s.add_plane((0, 0, float("nan")), (0, 0, 1), "soil"), "walls.plane.point"),
    (lambda s: s.add_plane((0, 0, 0), (0, 0), "soil"), "walls.plane.normal"),
    (lambda s: s.add_mesh([[0, 0, float("inf")], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], "soil"),
     "walls.mesh.vertices"),
])
def test_bad_walls_are_named(add, field):
    sim = Simulation(table(), dt=1e-6)
    with pytest.raises(InputError) as exc:
        add(sim)
    assert exc.value.field == field and not sim.walls.names


@pytest.mark.parametrize("corners", [[[0, 0, 0], [1, 0, 0], [2, 0, 0]],      # on one line
                                     [[0, 0, 0], [1, 0, 0], [1, 0, 0]]])     # two corners one point
def test_a_mesh_triangle_without_area_is_named(corners):
    sim = Simulation(table(), dt=1e-6)
    v = [[0, 0, 0], [1, 0, 0], [0, 1, 0]] + corners
    with pytest.raises(InputError) as exc:
        sim.add_mesh(v, [[0, 1, 2], [3, 4, 5]], "soil")
    assert exc.value.field == "walls.mesh.triangles[1]" and not sim.walls.names


def test_stl_facets_without_area_are_left_out():
    from soilcal.dem.stl import weld

    good = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    sliver = [[0, 0, 0], [0.5, 0, 0], [1, 0, 0]]  # three corners on one line
    v, t = weld(np.array([good, sliver], float))
    assert t.shape == (1, 3) and sorted(map(tuple, v[t[0]].tolist())) == sorted(map(tuple, good))


@pytest.mark.parametrize("steps", [10.5, -1, float("nan"), "10", True])
def test_a_step_count_that_is_not_a_whole_number_is_named(steps):
    sim = _two(3e-3)
    with pytest.raises(InputError) as exc:
        sim.run(steps)
    assert exc.value.field == "steps" and sim.step == 0


def test_a_whole_step_count_given_as_a_float_runs():
    sim = _two(3e-3)
    assert sim.run(1e1) == 10 and sim.step == 10


@pytest.mark.parametrize("add,field", [
    (lambda s: s.add_rectangle((0, 0, 0), (0, 0, 1), (1, 0), 0.01, 0.01, "soil"), "walls.rectangle.u_axis"),
    (lambda s: s.add_cylinder((0, 0), (0, 0, 1), 0.1, 0.1, "soil"), "walls.cylinder.axis_point"),
    (lambda s: s.add_cone((0, 0, float("nan")), (0, 0, 1), 0.1, 0.05, 0.0, 0.1, "soil"), "walls.cone.axis_point"),
    (lambda s: s.add_plane((0, 0, 0), (0, 0, 1), "soil", velocity=(1, 0)), "walls.velocity"),
    (lambda s: s.add_plane((0, 0, 0), (0, 0, 1), "soil", omega=(0, 0, float("inf"))), "walls.omega"),
    (lambda s: s.add_mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1]], "soil"), "walls.mesh.triangles"),
    (lambda s: s.add_mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0.0, 1.5, 2.0]], "soil"), "walls.mesh.triangles"),
])
def test_bad_wall_geometry_and_motion_are_named(add, field):
    sim = Simulation(table(), dt=1e-6)
    with pytest.raises(InputError) as exc:
        add(sim)
    assert exc.value.field == field and not sim.walls.names


def test_a_wall_moving_further_per_step_than_the_overlap_limit_is_named():
    """A thin plate at 500 m/s moves 5 mm per 10 us step, 2.5 diameters of the 1 mm sphere
    in its way: it passed through the sphere and left it at rest.  The run is refused
    before its first step, naming the wall, the step and the surface speed it allows
    (max_overlap r_min / dt = 0.05 x 1 mm / 10 us = 5 m/s)."""

    def sim_with(**wall):
        sim = Simulation(table(E=1e7), dt=1e-5, gravity=(0, 0, 0))
        sim.add_particles([[0.0, 0, 0]], 1e-3, "soil")
        return sim, sim.add_rectangle((-0.0011, 0, 0), (1, 0, 0), (0, 1, 0), 0.01, 0.01,
                                      "soil", name="blade", **wall)

    sim, _ = sim_with(velocity=(500.0, 0, 0))
    with pytest.raises(InputError, match="walls.blade") as e:
        sim.run(10)
    assert "surface speed <= 5 m/s" in str(e.value) and "dt <= 1e-07 s" in str(e.value)
    assert sim.step == 0
    # a drum spinning about its own axis and a floor spinning about its normal leave their
    # surfaces in place: not refused, however fast
    sim = Simulation(table(E=1e7), dt=1e-5, gravity=(0, 0, -9.81))
    sim.add_particles([[0.0, 0, -0.049]], 1e-3, "soil")
    sim.add_cylinder((0, -0.01, 0), (0, 1, 0), 0.05, 0.01, "soil", omega=(0, 2000.0, 0),
                     centre=(0, 0.5, 0))
    sim.add_plane((0, 0, -0.05), (0, 0, 1), "soil", omega=(0, 0, 3000.0))
    sim.run(10)


def _reference_surface_step(kind, par, v, om, c, reach, dt):
    """One primitive's surface step, directly: a plane moves by its normal velocity and
    turns by the spin about axes in its plane; a cylinder, cone or disk turns by the spin
    across its axis, and the spin about its axis carries the axis point round the wall
    centre; any other surface moves at |v| + |omega| reach."""
    from soilcal.dem.walls import CONE, CYLINDER, DISK, PLANE

    if not (any(q != 0 for q in v) or any(q != 0 for q in om)):
        return 0.0
    norm = lambda a: math.sqrt(sum(q * q for q in a))
    if kind in (PLANE, CYLINDER, CONE, DISK):
        a = par[3:6]
        oa = sum(om[i] * a[i] for i in range(3))
        across = [om[i] - oa * a[i] for i in range(3)]
        if kind == PLANE:
            speed = abs(sum(v[i] * a[i] for i in range(3)))
        else:
            r = [par[i] - c[i] for i in range(3)]
            carried = [oa * (a[1] * r[2] - a[2] * r[1]), oa * (a[2] * r[0] - a[0] * r[2]),
                       oa * (a[0] * r[1] - a[1] * r[0])]
            speed = norm(v) + norm(carried)
        return (speed + norm(across) * reach) * dt
    return (norm(v) + norm(om) * reach) * dt


def test_wall_steps_of_many_primitives_match_the_step_of_each():
    """The surface step of every primitive (an STL floor has 80,000; checking them one by
    one took 2 s per run) equals the direct step of each, for random walls of every kind,
    at rest, sliding, turning or both, and the wall refused is the first one over the
    limit."""
    from soilcal.dem.engine import _surface_steps
    from soilcal.dem.walls import CONE, CYLINDER, DISK, PLANE, RECTANGLE, TRIANGLE

    rng = np.random.default_rng(11)
    unit = lambda: (lambda a: a / np.linalg.norm(a))(rng.normal(size=3))
    sim = Simulation(table(E=1e7), dt=1e-5, gravity=(0, 0, 0))
    sim.add_particles([[0.0, 0, 0]], 1e-3, "soil")
    for w in range(48):
        k, motion = w % 6, (w // 6) % 4  # kind; at rest, sliding, turning, both
        vel = rng.normal(size=3) * 0.5 if motion in (1, 3) else np.zeros(3)
        om = rng.normal(size=3) * 20.0 if motion in (2, 3) else np.zeros(3)
        pt, n = rng.normal(size=3) * 0.1, unit()
        if w // 6 == 6:  # turning about z, normal or axis along z: the surface stays in place
            om, n = np.array([0.0, 0.0, 30.0]), np.array([0.0, 0.0, 1.0])
        kw = dict(name=f"w{w}", velocity=vel, omega=om)
        if k == 0:
            sim.add_plane(pt, n, "soil", centre=rng.normal(size=3) * 0.1, **kw)
        elif k == 1:
            sim.add_cylinder(pt, n, 0.05, 0.02, "soil", centre=rng.normal(size=3) * 0.1, **kw)
        elif k == 2:
            sim.add_cone(pt, n, 0.01, 0.03, -0.01, 0.02, "soil", centre=rng.normal(size=3) * 0.1, **kw)
        elif k == 3:
            sim.add_disk(pt, n, 0.02, "soil", **kw)
        elif k == 4:
            sim.add_rectangle(pt, n, unit(), 0.02, 0.01, "soil", **kw)
        else:
            v = rng.normal(size=(30, 3)) * 0.05
            t = np.array([[i, (i + 1) % 30, (i + 7) % 30] for i in range(30)])
            sim.add_mesh(v, t, "soil", **kw)
    wa = sim._warr
    assert set(wa["prim_kind"].tolist()) == {PLANE, CYLINDER, CONE, DISK, RECTANGLE, TRIANGLE}
    reach = rng.uniform(0.01, 0.2, size=wa["wall_vel"].shape[0])
    got = _surface_steps(wa["prim_kind"], wa["prim_wall"], wa["prim_par"], wa["wall_vel"],
                         wa["wall_omega"], wa["wall_centre"], reach, 1e-5)
    want = np.array([_reference_surface_step(
        int(kd), wa["prim_par"][k].tolist(), wa["wall_vel"][w].tolist(),
        wa["wall_omega"][w].tolist(), wa["wall_centre"][w].tolist(), float(reach[w]), 1e-5)
        for k, (kd, w) in enumerate(zip(wa["prim_kind"], wa["prim_wall"]))])
    assert np.count_nonzero(want == 0) > 50 and np.count_nonzero(want) > 100
    assert got == pytest.approx(want, rel=1e-12, abs=0.0)
    # the wall refused at each overlap limit is the one of the first primitive over it
    sim._prepare()
    for limit in np.quantile(want[want > 0], [0.1, 0.5, 0.9, 0.999]):
        sim.max_overlap = limit / 1e-3
        first = int(np.flatnonzero(want > limit)[0])
        with pytest.raises(InputError) as e:
            sim._check_wall_steps(reach)
        assert e.value.field == f"walls.w{wa['prim_wall'][first]}"
    sim.max_overlap = 1.01 * want.max() / 1e-3
    sim._check_wall_steps(reach)

def test_a_material_too_soft_to_carry_its_weight_is_named_before_the_run():
    """A 1 cm sphere of 10 kPa on a floor of its material: Hertz's resting overlap
    (3 m g / (4 E* sqrt(R)))^(2/3) is 27.6 % of its radius, over max_overlap (5 %).  The
    run stopped at its second step with an overlap blow-up whose advice was to shorten
    the step; it is refused before any step, naming the material and the E* it needs
    (pi rho g R / 0.05^1.5); a stiffer one runs."""
    E, nu, rho, R, g = 1e4, 0.3, 2600.0, 0.01, 9.81
    estar = E / (2 * (1 - nu**2))
    m = 4 / 3 * np.pi * R**3 * rho
    assert (3 * m * g / (4 * estar * np.sqrt(R))) ** (2 / 3) / R > 0.27

    def sim_of(youngs):
        sim = Simulation(table(E=youngs, nu=nu, rho=rho), gravity=(0, 0, -g))
        sim.add_particles([[0, 0, R]], R, "soil")
        sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
        return sim

    sim = sim_of(E)
    with pytest.raises(InputError, match="materials.soil") as e:
        sim.run(2000)
    assert f"{np.pi * rho * g * R / 0.05 ** 1.5:.4g} Pa" in str(e.value)
    assert sim.step == 0
    sim_of(1e6).run(10)


@pytest.mark.parametrize("periodic", [True, (True,), (True, False, True), "no", (1, 0),
                                      ("yes", "no")])
def test_periodic_flags_other_than_two_booleans_are_named(periodic):
    """periodic=True failed with a TypeError, (True,) with an IndexError; a third flag (z)
    was dropped without a word, and the string "no" made both axes periodic."""
    with pytest.raises(InputError) as exc:
        Simulation(table(), box=(0, 1, 0, 1), periodic=periodic)
    assert exc.value.field == "periodic" and "two booleans" in exc.value.expected


@pytest.mark.parametrize("value", [2.0, 1.5])
def test_an_overlap_limit_beyond_a_radius_is_named(value):
    """max_overlap is a fraction of a radius: 2 (centres inside each other) was taken."""
    with pytest.raises(InputError) as exc:
        Simulation(table(), max_overlap=value)
    assert exc.value.field == "max_overlap" and "(0, 1]" in exc.value.expected


def test_fixed_and_locked_rotation_per_particle():
    """fixed=[True, False] was taken as one truth value and fixed both spheres: the free one
    now falls at g, the fixed one stays; lock_rotation likewise per particle."""
    sim = Simulation(table(), dt=1e-6)
    sim.add_particles([[0, 0, 0.01], [0.01, 0, 0.01]], 1e-3, "soil", fixed=[True, False],
                      omega=[0, 0, 1.0])
    sim.add_particles([[0.03, 0, 0.01], [0.05, 0, 0.01]], 1e-3, "soil",
                      lock_rotation=np.array([False, True]), omega=[0, 0, 1.0])
    sim.run(1000)
    t = 1000 * 1e-6
    v = sim.v[sim.index([0, 1, 2, 3]), 2]
    assert v == pytest.approx([0.0, -9.81 * t, -9.81 * t, -9.81 * t], rel=1e-12)
    assert sim.p.inv_m[sim.index([0, 1])].tolist()[0] == 0.0
    assert (sim.p.inv_i[sim.index([0, 1, 2, 3])] == 0).tolist() == [True, False, False, True]


@pytest.mark.parametrize("kw,field", [(dict(fixed=[True, False, True]), "particles.fixed"),
                                      (dict(fixed="yes"), "particles.fixed"),
                                      (dict(lock_rotation=[1, 0]), "particles.lock_rotation")])
def test_bad_particle_flags_are_named(kw, field):
    sim = Simulation(table(), dt=1e-6)
    with pytest.raises(InputError) as exc:
        sim.add_particles([[0, 0, 0.01], [0.01, 0, 0.01]], 1e-3, "soil", **kw)
    assert exc.value.field == field and sim.n == 0


@pytest.mark.parametrize("add,field", [
    (lambda s: s.add_cylinder((0, 0, 0), (0, 0, 1), "0.1", 0.1, "soil"), "walls.cylinder.radius"),
    (lambda s: s.add_cylinder((0, 0, 0), (0, 0, 1), 0.1, float("inf"), "soil"),
     "walls.cylinder.half_length"),
    (lambda s: s.add_cone((0, 0, 0), (0, 0, 1), float("nan"), 0.1, 0.0, 1.0, "soil"),
     "walls.cone.r0"),
    (lambda s: s.add_cone((0, 0, 0), (0, 0, 1), 0.1, 0.1, 0.0, float("nan"), "soil"),
     "walls.cone.z1"),
    (lambda s: s.add_box((0, 0, 0), (-1, 1, 1), "soil"), "walls.box"),
    (lambda s: s.add_box((0, 0, 0), (1, 1, 0), "soil"), "walls.box"),
    (lambda s: s.add_box((0, 0), (1, 1, 1), "soil"), "walls.box.lo"),
])
def test_bad_cylinder_cone_and_box_sizes_are_named(add, field):
    """A cone radius NaN was accepted (min/max pass over NaN), a cylinder radius given as
    text failed with a TypeError, a box upside down with a ValueError naming no field."""
    sim = Simulation(table(), dt=1e-6)
    with pytest.raises(InputError) as exc:
        add(sim)
    assert exc.value.field == field and not sim.walls.names


@pytest.mark.parametrize("wall,kw,field", [(3, dict(velocity=(0, 0, 1)), "wall"),
                                           (True, dict(velocity=(0, 0, 1)), "wall"),
                                           ("lid", dict(velocity=(0, 0, 1)), "wall"),
                                           (0, dict(velocity=(0, 1)), "walls.velocity"),
                                           (0, dict(omega=(0, 0, float("nan"))), "walls.omega")])
def test_bad_wall_motion_changes_are_named(wall, kw, field):
    """set_wall_motion on a wall that does not exist failed with an IndexError; a velocity of
    two numbers with a numpy broadcast error."""
    sim = Simulation(table(), dt=1e-6)
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil", name="floor")
    with pytest.raises(InputError) as exc:
        sim.set_wall_motion(wall, **kw)
    assert exc.value.field == field
    assert sim._warr["wall_vel"].tolist() == [[0, 0, 0]]


def test_wall_motion_by_name():
    sim = Simulation(table(), dt=1e-6)
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil", name="floor")
    sim.set_wall_motion("floor", velocity=(0.1, 0, 0))
    assert sim._warr["wall_vel"].tolist() == [[0.1, 0, 0]]


@pytest.mark.parametrize("wall", [True, False])
def test_a_radius_typed_in_millimetres_is_named_with_its_unit(wall):
    """A radius of 1 meant as 1 mm, with the positions in metres: the start overlaps a wall or
    the neighbour by most of a radius, and the error says radii are in metres."""
    sim = Simulation(table(E=1e8))
    if wall:
        sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
        sim.add_particles([[0, 0, 0.001]], 1.0, "soil")
    else:
        sim.add_particles([[0, 0, 0.001], [0.003, 0, 0.001]], 1.0, "soil")
    with pytest.raises(InputError) as exc:
        sim.run(10)
    assert exc.value.field == "particles"
    assert exc.value.note == "radii are in metres: a radius of 1 is 1 m, 1 mm is 0.001"


def test_a_metre_sphere_placed_right_gets_no_unit_note():
    sim = Simulation(table(E=1e8))
    sim.add_particles([[0, 0, 0], [1.9, 0, 0]], 1.0, "soil")
    with pytest.raises(InputError) as exc:
        sim.run(10)
    assert exc.value.note is None  # 10 % overlap: a placement, not a unit
