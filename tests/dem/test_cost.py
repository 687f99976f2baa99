"""The cost model of a DEM job (soilcal.dem.cost) against the runs it sizes."""

import math
import time

import numpy as np
import pytest

from soilcal.dem import cost
from soilcal.dem.engine import Simulation
from soilcal.dem.factories import PSD, BoxRegion, UniformRadius, lattice_fill
from soilcal.dem.geometry import cone_mesh, disk_mesh
from soilcal.dem.scenarios import bulldozing, compression, drum, repose, rotary, soilbin
from soilcal.dem.scenarios.base import (DemParams, build_materials, contact_model,
                                        make_simulation, merge_setup, paper_cohesion)
from soilcal.dem.state import BYTES_PER_PARTICLE
from soilcal.errors import InputError

BLACK = DemParams(soil_density=1560.0)


def _counting(monkeypatch):
    """Record the spheres of every simulation a run builds, in the order they first step."""
    seen = []
    orig = Simulation.run

    def run(self, steps, *a, **k):
        done = orig(self, steps, *a, **k)
        if done and not hasattr(self, "_cost_test"):
            self._cost_test = True
            seen.append((int(self.n), float(self.dt)))
        return done

    monkeypatch.setattr(Simulation, "run", run)
    return seen


def test_unknown_scenario_is_named():
    with pytest.raises(InputError) as err:
        cost.estimate("sandpit", {}, None, "quick")
    assert "sandpit" in str(err.value) and "repose" in str(err.value)


def test_refused_setup_is_an_error_not_a_number():
    bad = merge_setup(repose.setups(), "cinnamon-soil", {"tube_diameter": 0.5}, "t")
    with pytest.raises(InputError, match="tube_diameter"):
        cost.estimate("repose", bad, None, "quick")


@pytest.mark.parametrize("preset", ["quick", "paper"])
def test_counts_are_the_scenarios_own_sizing(preset):
    for name, setup in repose.setups().items():
        c = cost.estimate("repose", setup, BLACK, preset)
        assert c.n_particles == c.peak_particles == repose.sizing(setup, preset, BLACK)["n"], name
    s = drum.setups()["xinjiang-vineyard"]
    assert cost.estimate("drum", s, None, preset).n_particles == drum.sizing(s, preset)["n"]
    s = compression.setups()["guangxi-cohesive"]
    assert cost.estimate("compression", s, None, preset).n_particles == \
        compression.sizing(s, preset, DemParams())["n"]


def test_lattice_and_random_fill_counts_are_exact():
    rng = np.random.default_rng(0)
    for lo, hi, r_max in [((0, 0, 0), (0.45, 0.07, 0.078), 0.0077),
                          ((0.0, 0.0, 0.0), (0.3, 0.2, 0.1), 0.0031)]:
        x, _ = lattice_fill(BoxRegion(lo, hi), dist=UniformRadius(0.9 * r_max / 1.1, r_max),
                            kind="hcp", jitter=0.5, rng=rng)
        assert cost.lattice_sites(lo, hi, r_max) == len(x)
    psd = PSD.from_mass_percent((0.012, 0.008, 0.004), (8.85, 8.2, 82.95))
    vol = 0.3 * 0.05 * 0.04 * 0.2
    assert cost.psd_fill_count(psd, vol) == len(psd.sample_mass(vol, 1.0, rng))


SMALL = [
    ("repose", "black-soil-stage2", {"load_mass": 0.06, "max_settle_time": 1.0}, BLACK),
    # read past the settle bound: the heap's phase runs to read_time, longer than max_settle_time
    ("repose", "black-soil-stage2", {"load_mass": 0.06, "max_settle_time": 0.2, "read_time": 0.5}, BLACK),
    ("repose", "cinnamon-soil", {"n_particles": 200, "max_settle_time": 1.0}, DemParams()),
    ("drum", "xinjiang-vineyard", {"n_particles": 200, "spin_time": 0.6, "transient_time": 0.3,
                                   "max_settle_time": 0.5}, DemParams(soil_density=1757.567)),
]


@pytest.mark.parametrize("scenario,name,over,params", SMALL, ids=[s[1] + ("-read" if "read_time" in s[2] else "") for s in SMALL])
def test_estimate_bounds_a_small_bench_top_run(scenario, name, over, params, monkeypatch):
    mod = {"repose": repose, "drum": drum}[scenario]
    setup = merge_setup(mod.setups(), name, over, "t")
    est = cost.estimate(scenario, setup, params, "quick")
    seen = _counting(monkeypatch)
    res = mod.run(setup, params, "quick", seed=0, threads=1)
    assert est.n_particles == res.n_particles == seen[0][0]
    assert est.steps >= res.steps
    assert est.sim_time_s >= res.sim_time_s
    # the estimate's step is for the smallest radius the run can draw: at most the run's,
    # within the spread of the smallest drawn radius
    assert est.dt_s <= res.setup["dt"] <= 1.02 * est.dt_s
    assert est.particle_steps >= res.n_particles * res.steps


def test_estimate_of_a_soil_bin_run(monkeypatch, tmp_path):
    monkeypatch.setenv("SOILCAL_SCENARIO_CACHE", str(tmp_path))
    setup = merge_setup(bulldozing.setups(), "plate-line", {}, "t")
    params = bulldozing.paper_params()
    est = cost.estimate("bulldozing", setup, params, "quick")
    seen = _counting(monkeypatch)
    res = bulldozing.run(setup, params, "quick", seed=0, threads=1, use_cache=False)
    fill, *_, tool = seen
    assert est.peak_particles == fill[0]  # the lattice fill, counted exactly
    assert est.n_particles == pytest.approx(res.n_particles, rel=0.05)  # after trim and trench
    assert est.steps >= res.steps  # settling (both phases) and the pass
    assert est.phases[-1].sim_time_s >= res.sim_time_s  # the pass alone
    assert est.dt_s == pytest.approx(tool[1], rel=1e-12)


def _engine_dt(sim):
    sim.run(0)  # the engine picks its step at the first (zero-step) run
    return sim.dt


def test_dt_is_the_engines_step_of_the_run_simulation():
    # repose funnel, quick: the run's simulation with its walls, its smallest sphere
    setup = repose.setups()["black-soil-stage2"]
    sz = repose.sizing(setup, "quick", BLACK)
    coh = paper_cohesion(setup, sz["dist"])
    sim, _ = make_simulation(BLACK, setup, "quick", "t", cohesion=coh, skin=0.6 * sz["r_max"])
    fv, ft = cone_mesh(0.025, 0.096, 0.1, 0.374, 24)
    sim.add_mesh(fv, ft, "steel")
    cv, ct = disk_mesh(0.03, 24, centre=(0, 0, 0.1))
    sim.add_mesh(cv, ct, "steel")
    sim.add_plane((0, 0, 0), (0, 0, 1), "steel")
    r = np.array([sz["dist"].r_min, sz["dist"].r_max])
    sim.add_particles([[0, 0, 0.2], [0, 0, 0.25]], r, "soil")
    assert cost.estimate("repose", setup, BLACK, "quick").dt_s == pytest.approx(_engine_dt(sim),
                                                                             rel=1e-12)
    # paper preset, discrete sizes: the smallest size is drawn, the steps are equal
    setup = drum.setups()["xinjiang-vineyard"]
    sz = drum.sizing(setup, "paper")
    sim, _ = make_simulation(DemParams(), setup, "paper", "t",
                             cohesion=paper_cohesion(setup, sz["dist"]))
    sim.add_cylinder((0, 0.05, 0), (0, 1, 0), 0.05, 0.05, "steel", inner=True)
    sim.add_disk((0, 0, 0), (0, 1, 0), 0.05, "steel")
    sim.add_particles([[0, 0.05, 0.0], [0.02, 0.05, 0.0]], [0.00125, 0.005], "soil")
    assert cost.estimate("drum", setup, None, "paper").dt_s == pytest.approx(_engine_dt(sim),
                                                                          rel=1e-12)


@pytest.mark.parametrize("scenario,name", [("bulldozing", "plate-line"), ("rotary", "rpm-250"),
                                           ("furrow", "yangtze-opener")])
def test_dt_of_a_soil_bin_tool_pass(scenario, name):
    from soilcal.dem.scenarios import get

    mod = get(scenario)
    params = mod.paper_params()
    setup = merge_setup(mod.setups(), name, {}, "t")
    s, spec = cost.soil_bin(scenario, setup, "quick")
    # the tool pass's simulation, the engine choosing the step: soil walls, the steel tool
    mats = build_materials(params, spec.stiffness_scale, "t", spec.cohesion_scale)
    sim = Simulation(mats, dt_fraction=spec.dt_fraction, contact_model=contact_model(params),
                     max_overlap=spec.max_overlap, box=(0, spec.length, 0, spec.width),
                     periodic=(False, spec.periodic_y))
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    sim.add_plane((0, 0, 1), (0, 0, -1), "steel")
    sim.add_particles([[0.1, 0.05 * spec.width, 0.3]], [spec.r_min], "soil")
    dt = _engine_dt(sim)
    if scenario == "rotary":
        omega = 2 * np.pi * s["rpm"] / 60
        dt = min(dt, 0.1 * spec.r_min / (omega * s["radius"] + s["forward_speed"]))
    assert cost.estimate(scenario, setup, params, "quick").phases[2].dt_s == \
        pytest.approx(dt, rel=1e-12)


def test_memory_and_runtime_grow_with_the_particle_count():
    costs = [cost.estimate("repose", merge_setup(repose.setups(), "cinnamon-soil",
                                                 {"n_particles": n}, "t"), None, "quick")
             for n in (200, 1000, 5000)]
    assert [c.n_particles for c in costs] == [200, 1000, 5000]
    for a, b in zip(costs, costs[1:]):
        assert b.mem_mb > a.mem_mb
        assert b.particle_steps > a.particle_steps
        assert b.wall_s() > a.wall_s()
        assert b.runtime_min() >= a.runtime_min()
    big = cost.estimate("repose", "cinnamon-soil", None, "paper")
    assert big.mem_mb > costs[-1].mem_mb and big.runtime_min() > costs[-1].runtime_min()
    assert big.wall_s(threads=4) < big.wall_s(threads=1)
    assert costs[0].wall_s(threads=4) == costs[0].wall_s(threads=1)  # serial below 1024


def test_bytes_per_particle_is_the_engines_count():
    assert cost.bytes_per_particle(reallocation=False) == BYTES_PER_PARTICLE
    assert cost.bytes_per_particle() > 1.8 * BYTES_PER_PARTICLE


def test_spec_runs_each_scenario_setup_once_times_replicates():
    rep = dict(repose.setups()["cinnamon-soil"], name="cinnamon-soil")
    dr = dict(drum.setups()["xinjiang-vineyard"], name="xinjiang-vineyard")
    spec = {"soil": "s", "stage": "bbd", "run": 1, "replicates": 2,
            "params": DemParams().as_dict(),
            "responses": {"a": {"scenario": "repose", "setup": rep, "preset": "quick"},
                          "b": {"scenario": "repose", "setup": dict(rep), "preset": "quick"},
                          "c": {"scenario": "drum", "setup": dr, "preset": "quick"}}}
    one = cost.estimate("repose", rep, None, "quick")
    two = cost.estimate("drum", dr, None, "quick")
    got = cost.estimate_spec(spec)
    assert got.runs == 4
    assert got.particle_steps == pytest.approx(2 * (one.particle_steps + two.particle_steps))
    assert got.mem_mb == max(one.mem_mb, two.mem_mb)
    assert got.wall_s() == pytest.approx(cost.STARTUP_S + 4 * cost.RUN_OVERHEAD_S + 2 * (
        one.wall_s() - cost.STARTUP_S - cost.RUN_OVERHEAD_S
        + two.wall_s() - cost.STARTUP_S - cost.RUN_OVERHEAD_S))
    job = {"specs": [dict(spec, replicates=1), dict(spec, replicates=1)]}
    assert cost.estimate_job(job).particle_steps == pytest.approx(got.particle_steps)
    assert cost.estimate_job({"not_run": "no calibrated set"}) is None


def test_estimates_are_fast():
    setups = [("repose", "guangxi-cohesive"), ("furrow", "yangtze-opener"),
              ("rotary", "rpm-250"), ("compression", "guangxi-cohesive")]
    for sc, name in setups:  # imports done
        cost.estimate(sc, name, None, "paper")
    t = time.perf_counter()
    for sc, name in setups:
        for preset in ("quick", "paper"):
            cost.estimate(sc, name, None, preset)
    assert (time.perf_counter() - t) / (2 * len(setups)) < 0.05
    # a paper-preset job far beyond one machine is sized all the same, without allocating
    big = cost.estimate("rotary", "rpm-250", rotary.paper_params(), "paper")
    assert big.peak_particles > 10_000_000 and big.mem_mb > 100_000
    assert soilbin.FILL_FACTOR > 1


def test_a_point_whose_loop_effect_takes_friction_past_two_is_costed():
    # a rate effect on a calibrated friction of 1.9 (beta 0.2, 7 m/s against 1.75 m/s) gives
    # 1.9 (1 + 0.2 ln 4) = 2.427, past a soil's plausible 2 (base.SOIL_RANGES) but physical: the
    # job's memory and runtime are estimated while the workflow plans it, as the run takes it
    mu = 1.9 * (1 + 0.2 * math.log(4.0))
    c = cost.estimate("repose", "cinnamon-soil", {"soil_soil_static_friction": mu}, "quick")
    assert c.n_particles > 0
