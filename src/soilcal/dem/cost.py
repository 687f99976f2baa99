"""Cost of a DEM job from its own size: particles, time step, simulated time, memory, runtime.

:func:`estimate` sizes one scenario run before anything is simulated (milliseconds, no
kernel compiled, nothing allocated per particle), from the same code the run uses:

* **particle count**: the scenario's own ``sizing`` (repose, drum, compression: exact, the
  run inserts that many spheres), the incline's block builder (exact), and for the
  soil-bin scenarios (furrow, bulldozing, rotary) the bin of the run (``_settings`` and
  ``_bin`` of the scenario module, :mod:`soilcal.dem.scenarios.soilbin`): the lattice
  fill's site count, counted exactly as :func:`soilcal.dem.factories.lattice_fill` places
  them (:func:`lattice_sites`), or for a bin with a mass-fraction size distribution the
  count :meth:`~soilcal.dem.factories.PSD.sample_mass` draws for the fill's solid volume
  (exact for discrete sizes).  The bed that remains after the settled fill is trimmed to
  the fill height, and the tool's starting trench, are known only after the settling: they
  are computed from the fill volume times the settled solid fraction :data:`BED_FRACTION`
  over the mean sphere volume, as the trim would leave it, less the trench's volume at the
  same fraction (so ``n_particles`` of a soil-bin run is an estimate; ``peak_particles``,
  the lattice or random fill, is exact);
* **time step**: the rule the run applies.  Bench-top scenarios (repose, drum, compression,
  incline) build the run's :class:`~soilcal.dem.engine.Simulation` with
  :func:`~soilcal.dem.scenarios.base.make_simulation` (same materials, stiffness and
  cohesion scaling, contact model, ``dt_fraction`` and overlap guard), give it one sphere
  of the distribution's smallest radius and a plane of each wall material of the run, and
  let the engine choose its step (the Rayleigh fraction capped at the JKR and damped-contact
  bounds, materials.py).  A run draws its radii at random, so its smallest sphere is at
  least that radius and its step at least this one (equal for the papers' discrete sizes).
  Soil-bin runs use :func:`~soilcal.dem.scenarios.soilbin.soil_time_step` (settling) and
  :func:`~soilcal.dem.scenarios.soilbin.tool_time_step` (tool pass; the rotary tiller
  also caps it at a tenth of the smallest radius per step of the blade tip), which take
  the bin's nominal smallest radius, so their steps are exact;
* **simulated time**: an upper bound of one run, from each scenario's ``run``:

  - repose, funnel: 2 x ``max_settle_time`` (fill, heap) + the cover's travel
    (2.5 R_outlet + d_max) / ``cover_speed``; with ``read_time`` the heap's phase is
    ``read_time`` less the cover's travel (exact);
  - repose, cylinder: 2 x ``max_settle_time`` + the lift (insertion height + d_max) /
    ``lift_speed`` (the settled fill is no higher than the region it was inserted in;
    the run lifts by the settled fill height + d_max, or less); with ``read_time`` the
    heap's phase is at most ``read_time``;
  - drum: ``max_settle_time`` + the rotation (``spin_time``: transient + frames);
  - compression: ``max_settle_time`` + the rod's longest travel, from half a radius above
    the fill (no higher than its insertion height) down to 5 % of that height, at
    ``rod_speed`` (the run stops earlier at ``max_strain`` or on jamming);
  - incline: 0.05 s + every hold of the staircase from ``start_deg`` to ``max_deg`` (the
    run stops at the first step that moves);
  - soil-bin tools: ``settle_time`` of the bin (both settling phases; skipped when the
    settled bin is in the cache, which the bound does not assume) + the pass
    (``travel / speed``, rounded up to whole force samples), + the rotor's lift and rest
    (rotary).

  Settling phases stop earlier when the bed comes to rest.  Steps count each phase as the
  run rounds it; ``steps`` is their sum and ``particle_steps`` the sum over phases of
  spheres x steps, times the replicates (so, for a soil-bin run, not simply
  ``n_particles x steps``: the fill, the trimmed bed and the pass differ in size);
* **memory** (:attr:`Cost.mem_mb`): :data:`BASE_MB` for the Python process (interpreter,
  NumPy, pandas, Numba and the loaded kernels) plus the engine's bytes per sphere
  (:func:`bytes_per_particle`, the arrays :class:`~soilcal.dem.engine.Simulation`
  allocates, as :data:`soilcal.dem.state.BYTES_PER_PARTICLE` counts them, with the
  pair-list slots a size distribution needs, wider wall lists against triangle-mesh tools
  and room for the lists' reallocation, when old and new buffers coexist), for the largest
  number of spheres alive at once.  The count is of allocated bytes: a 94,000-sphere bin
  held 1.7 kB per sphere resident after 400 steps against 4.1 kB (4,120 B) counted here
  (``throughput.md``, case ``memory``, whose row has the 3.8 kB of an earlier count);
* **runtime** (:meth:`Cost.wall_s`, :meth:`Cost.runtime_min`): particle-steps over the
  measured engine throughput :data:`THROUGHPUT` (particle-steps per second on one
  thread), times a thread speed-up from the measured two-thread efficiency
  :data:`PARALLEL_EFFICIENCY`, plus the measured start-up of a job (:data:`STARTUP_S`)
  and a per-run overhead (:data:`RUN_OVERHEAD_S`: insertion, measurement).

A scenario this module has no model for, or a setup the scenario refuses, raises
:class:`soilcal.errors.InputError` naming it; no number is ever guessed.

:func:`estimate_spec` sizes a job of :func:`soilcal.chain.sources.point_spec` (responses
that share scenario, setup and preset run once, as :func:`soilcal.chain.sources.simulate`
runs them) and :func:`estimate_job` also the tool and verification jobs of
:mod:`soilcal.chain.verify`.  Workflow resource callables can use, e.g.::

    cost = estimate_spec(point_spec(w))
    mem_mb=cost.mem_mb, runtime=cost.runtime_min(threads=dem_threads(w.soil))
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

from soilcal.errors import InputError

# ---------------------------------------------------------------- measured constants
#: Engine throughput, particle-steps per second on one thread, conservative: below the
#: lowest rate of whole quick-preset runs (wall time of the run, insertion and measurement
#: included) in ``benchmarks/results/throughput.md`` (``benchmarks/throughput.py``, column
#: ``per_s``): 1.6e6 for the 496-sphere funnel, up to 4.4e6 for the other scenario runs of
#: 500 to 6,500 spheres, on a two-core machine shared with other jobs (load 4-7).
THROUGHPUT = 1.0e6
#: Speed-up of the second thread over the first: two threads ran settling beds of 5,000 and
#: 20,000 spheres, with and without JKR, 1.56 to 1.94 times as fast as one
#: (``benchmarks/results/settle.md``, soilcal details: wall s of threads 1 over threads 2),
#: rounded to 0.8.  The two-thread rows of ``throughput.md`` (case ``threads-bed``) ran
#: while other jobs loaded the two cores (``load_1min`` 5-7) and measure that contention,
#: not the engine.  t threads run at 1 + (t - 1) x this; beyond two threads that is an
#: extrapolation.  Runs of fewer than :data:`soilcal.dem.integrator.PARALLEL_MIN` spheres
#: run on one thread whatever the count.
PARALLEL_EFFICIENCY = 0.8
#: Time per step that does not grow with the sphere count (list checks, wall motion, the
#: Python side of each call): 16 microseconds measured on a one-sphere run (``throughput.md``,
#: case ``incline-rolling``); it matters only for runs of a few spheres over many steps.
STEP_S = 2e-5
#: Start-up of a job process: imports and loading the cached kernels, 0.9-2.0 s measured
#: (``throughput.md``, column ``startup_s``).  A job that compiles the kernels afresh (the
#: first after a change of the package's sources, :mod:`soilcal.dem._kernel_cache`) takes
#: :data:`COMPILE_S` more.
STARTUP_S = 5.0
#: Cold compilation of the engine's kernels: 110-126 s measured on the shared two-core
#: machine (a process with an empty ``NUMBA_CACHE_DIR`` running a small funnel heap).
COMPILE_S = 150.0
#: Per-run work outside the time loop (insertion, measurement, frames): at most 2.0 s
#: measured on small runs with two silhouette views (``throughput.md``: ``wall_s`` less
#: ``engine_s``; the heaps' silhouette measurement is the largest part), and a heap's
#: silhouettes now take 8 views at about 0.4 s each (``repose_seeds.md``).
RUN_OVERHEAD_S = 5.0
#: Resident memory of a DEM job process without its particles [MB]: the largest peak RSS
#: of the workflow's DEM jobs at the quick preset (``dem_point`` 548 MB,
#: ``benchmarks/results/calibration.md``; their few thousand spheres account for about
#: 20 MB of it at :func:`bytes_per_particle`).
BASE_MB = 550.0
#: Runtime requested for a job: this many times its estimated wall time, at least
#: :data:`MIN_RUNTIME_MIN` minutes, plus one cold compilation.
RUNTIME_SAFETY = 2.0
MIN_RUNTIME_MIN = 5
#: Settled solid fraction of a soil bin trimmed to its fill height (spheres x mean sphere
#: volume / (length x width x fill height)): 0.49 (bulldozing, not trimmed), 0.53 (rotary)
#: and 0.58 (furrow) measured in the quick bins (``throughput.md``, column
#: ``bed_fraction``); the largest, rounded up.
BED_FRACTION = 0.59
#: Wall-list slots per sphere next to triangle meshes (the engine starts at 4 and widens the
#: lists on demand): at most 11 measured in the quick tool passes, 30 in the funnel, whose
#: cover is a fan of 24 triangles meeting at its centre (``throughput.md``, ``wall_slots``).
TOOL_WALL_SLOTS = 12
FUNNEL_WALL_SLOTS = 32
#: Pair-list slots the engine allocates per sphere at first, and the growth factor when a
#: build needs more (engine.py ``_npair_per``, ``_alloc_lists``).
PAIR_SLOTS_MIN = 8
PAIR_GROWTH = 1.25
#: Per-sphere bytes held by the scenario outside the engine (positions and radii copies,
#: insertion and measurement arrays).
SCENARIO_BYTES = 256

BENCHTOP = ("repose", "drum", "compression", "incline")
SOIL_BIN = ("furrow", "bulldozing", "rotary")


# ---------------------------------------------------------------- result
@dataclass(frozen=True)
class Phase:
    """One stretch of a run with a fixed sphere count and time step."""

    name: str
    n_particles: int
    steps: int
    dt_s: float

    @property
    def sim_time_s(self) -> float:
        return self.steps * self.dt_s


@dataclass(frozen=True)
class Cost:
    """Size and cost of a DEM job (one scenario run times ``replicates``, or the sum of the
    runs of a job spec).

    ``n_particles``: the spheres of the run's measured phase (``Result.n_particles``);
    ``peak_particles``: the most alive at once (memory); ``dt_s``: the smallest time step;
    ``sim_time_s``: an upper bound of the simulated time of one run; ``steps``: the steps of
    one run at that bound; ``particle_steps``: spheres x steps summed over the phases, times
    ``replicates``; ``runs``: scenario runs in the job (replicates included);
    ``count``: how the particle count was obtained."""

    scenario: str
    preset: str
    n_particles: int
    peak_particles: int
    dt_s: float
    sim_time_s: float
    steps: int
    replicates: int
    particle_steps: float
    runs: int
    bytes_per_particle: int
    count: str = ""
    phases: tuple = field(default=(), repr=False)
    #: times the phases run in the job (the replicates; 1 for a combined job, whose phases
    #: already hold every run)
    repeat: int = field(default=1, repr=False)

    def wall_s(self, throughput: float | None = None, threads: int = 1) -> float:
        """Estimated wall time [s] of the job on ``threads`` threads at ``throughput``
        particle-steps per second per thread (default :data:`THROUGHPUT`): start-up, the
        runs' overhead, and every phase's steps at :data:`STEP_S` plus its particle-steps at
        the thread speed-up (one thread below the engine's parallel threshold)."""
        tp = float(throughput or THROUGHPUT)
        if not tp > 0:
            raise InputError("<cost>", "throughput", "particle-steps per second > 0", throughput)
        loop = sum(p.steps * (STEP_S + p.n_particles / (tp * speedup(threads, p.n_particles)))
                   for p in self.phases) * self.repeat
        return STARTUP_S + self.runs * RUN_OVERHEAD_S + loop

    def runtime_min(self, throughput: float | None = None, threads: int = 1,
                    safety: float = RUNTIME_SAFETY, minimum: int = MIN_RUNTIME_MIN) -> int:
        """Minutes to request: ``safety`` x :meth:`wall_s` + one cold kernel compilation
        (:data:`COMPILE_S`), at least ``minimum``."""
        t = safety * self.wall_s(throughput, threads) + COMPILE_S
        return int(max(minimum, math.ceil(t / 60.0)))

    @property
    def mem_mb(self) -> int:
        """Megabytes to request: :data:`BASE_MB` + ``peak_particles`` x
        ``bytes_per_particle`` (10^6 bytes per MB)."""
        return int(math.ceil(BASE_MB + self.peak_particles * self.bytes_per_particle / 1e6))

    def row(self) -> dict:
        return dict(scenario=self.scenario, preset=self.preset, n_particles=self.n_particles,
                    peak_particles=self.peak_particles, dt_s=self.dt_s,
                    sim_time_s=self.sim_time_s, steps=self.steps, replicates=self.replicates,
                    runs=self.runs, particle_steps=self.particle_steps, mem_mb=self.mem_mb,
                    count=self.count)


def speedup(threads: int, n_particles: int | None = None) -> float:
    """Speed-up of ``threads`` threads over one (:data:`PARALLEL_EFFICIENCY`); 1 for runs
    the engine keeps on one thread (fewer than ``PARALLEL_MIN`` spheres)."""
    from soilcal.dem.integrator import PARALLEL_MIN

    t = int(threads)
    if t < 1:
        raise InputError("<cost>", "threads", "an integer >= 1", threads)
    if n_particles is not None and n_particles < PARALLEL_MIN:
        return 1.0
    return 1.0 + (t - 1) * PARALLEL_EFFICIENCY


# ---------------------------------------------------------------- memory
def bytes_per_particle(pair_slots: float = PAIR_SLOTS_MIN, hist: int | None = None,
                       wall_slots: int = 4, reallocation: bool = True) -> int:
    """Engine bytes per sphere: the state (:data:`soilcal.dem.state.STATE_BYTES`), the two
    list buffers with ``pair_slots`` pair slots (partner, ``hist`` history columns, touching
    flag) and ``wall_slots`` wall slots (primitive, 9 history columns) each, the work arrays
    ``_alloc_lists`` allocates beside them (with the build's int32 partner work space, one
    per pair slot: the size it takes in a bed of even packing; where a few of the build's
    block groups hold most pairs, e.g. a dense cluster among sparse spheres, it grows to
    up to NBLK_GROUPS = 32 entries per pair, :func:`soilcal.dem.neighbour.build_lists`,
    which this count does not assume; and the pair pass's near list, int32, one per pair
    slot, with its count per sphere and the displacements it was written at, 1 + 3 numbers
    of 8 bytes), and the cell arrays; with ``reallocation`` the
    lists twice (old and new buffers coexist while the engine widens them), plus
    :data:`SCENARIO_BYTES`.  With the defaults and without ``reallocation`` and the
    scenario's bytes it is :data:`soilcal.dem.state.BYTES_PER_PARTICLE`."""
    from soilcal.dem.contact import H_SHORT, H_SIZE
    from soilcal.dem.state import STATE_BYTES

    h = H_SHORT if hist is None else int(hist)
    lists = (2 * (8 + pair_slots * (8 + 8 * h + 1) + wall_slots * (8 + 8 * H_SIZE) + 8)
             + 8 * (6 * wall_slots + 4 + 8 + 1 + 8 + 1 + 1 + 1 + 3) + 4 * pair_slots
             + 4 * pair_slots)
    cells = 8 * (1 + 1 + 4)
    total = STATE_BYTES + cells + lists * (2 if reallocation else 1)
    return int(math.ceil(total + (SCENARIO_BYTES if reallocation else 0)))


def pair_slots(dist, skin: float, fraction: float = 0.64) -> float:
    """Pair-list slots per sphere of a packed bed of the radius distribution ``dist``: half
    the partners j of a sphere i within r_i + r_j + skin (the list's cutoff, neighbour.py),
    ``fraction (r_i + r_j + skin)^3 / <r^3>`` on average over the number fractions
    (the excluded volume of the sphere itself is not taken off: an upper bound at a solid
    fraction up to ``fraction``), times the engine's growth factor, at least the initial
    :data:`PAIR_SLOTS_MIN`."""
    import numpy as np

    from soilcal.dem.factories import PSD

    if isinstance(dist, PSD):
        a, b = np.asarray(dist.lower, float), np.asarray(dist.upper, float)
        # three radii per bin (ends and middle) with a third of its number each
        r = np.concatenate([a, 0.5 * (a + b), b])
        w = np.tile(dist.number_fractions(), 3) / 3.0
    else:
        r = np.linspace(dist.r_min, dist.r_max, 5)
        w = np.full(5, 0.2)
    r3 = float(np.sum(w * r**3))
    pairs = np.add.outer(r, r) + float(skin)
    mean = float(np.sum(np.outer(w, w) * pairs**3))
    need = 0.5 * fraction * mean / r3
    return max(float(PAIR_SLOTS_MIN), PAIR_GROWTH * need)


# ---------------------------------------------------------------- time steps
def _benchtop_dt(params, setup: dict, preset: str, r_min: float, wall_materials,
                 cohesion: float, source: str) -> float:
    """The step the engine chooses for the run's simulation: built as the run builds it
    (:func:`~soilcal.dem.scenarios.base.make_simulation`) with one sphere of radius
    ``r_min`` and a plane of each wall material; the engine's own preparation picks the
    step (``Simulation._prepare``, the rule of materials.py), without running a step."""
    from soilcal.dem.scenarios.base import make_simulation

    sim, _ = make_simulation(params, setup, preset, source, cohesion=cohesion)
    sim.add_particles([[0.0, 0.0, 1.0]], [float(r_min)], "soil")
    for k, mat in enumerate(sorted(set(wall_materials))):
        sim.add_plane((0.0, 0.0, -float(k)), (0.0, 0.0, 1.0), mat)
    sim._prepare()
    return float(sim.dt)


def _rsteps(seconds: float, dt: float) -> int:
    """Steps of :func:`~soilcal.dem.scenarios.base.run_time` and ``settle`` (at least one)."""
    return max(1, int(round(seconds / dt)))


# ---------------------------------------------------------------- bench-top scenarios
def _repose(mod, setup, params, preset, source):
    import math as m

    sz = mod.sizing(setup, preset, params)
    coh = _paper_cohesion(setup, sz["dist"], source)
    walls = {setup["wall_material"], setup["plate_material"]}
    dt = _benchtop_dt(params, setup, preset, sz["dist"].r_min, walls, coh, source)
    dmax = 2 * sz["r_max"]
    settle = _rsteps(setup["max_settle_time"], dt)
    if setup["method"] == "cylinder":
        R = setup["tube_diameter"] / 2
        vol = sz["n"] * sz["dist"].mean_volume()
        h_ins = vol / (mod.FILL_FRACTION * m.pi * (R - sz["r_max"]) ** 2)
        lift = int(m.ceil((h_ins + dmax) / (setup["lift_speed"] * dt))) + 1
        release = ("lift", lift)
    else:
        release = ("cover", _rsteps(mod.cover_travel_time(setup, sz["r_max"]), dt))
    heap = settle
    if setup.get("read_time") is not None:
        # the heap runs to read_time after the release starts (a shorter lift leaves it more)
        heap = _rsteps(setup["read_time"], dt) - (release[1] if release[0] == "cover" else 0)
    steps = [("fill settle", settle), release, ("heap settle", max(1, heap))]
    return [(nm, sz["n"], k, dt) for nm, k in steps], sz["n"], sz["dist"], 0.6 * sz["r_max"], \
        "exact (repose.sizing)"


def _drum(mod, setup, params, preset, source):
    sz = mod.sizing(setup, preset, source)
    coh = _paper_cohesion(setup, sz["dist"], source)
    walls = {setup["wall_material"], setup["end_material"]}
    dt = _benchtop_dt(params, setup, preset, sz["dist"].r_min, walls, coh, source)
    spin, trans = mod.PRESET_TIMES[preset]
    spin = setup.get("spin_time") or spin
    trans = setup.get("transient_time") or trans
    n_fr = int(math.floor((spin - trans) / setup["frame_every"] + 1e-9)) + 1
    steps = [("settle", _rsteps(setup["max_settle_time"], dt)),
             ("transient", _rsteps(trans, dt)),
             ("frames", (n_fr - 1) * _rsteps(setup["frame_every"], dt))]
    return [(nm, sz["n"], k, dt) for nm, k in steps], sz["n"], sz["dist"], 0.5 * sz["r_max"], \
        "exact (drum.sizing)"


def _compression(mod, setup, params, preset, source):
    sz = mod.sizing(setup, preset, params)
    coh = _paper_cohesion(setup, sz["dist"], source)
    dt = _benchtop_dt(params, setup, preset, sz["dist"].r_min, {"steel"}, coh, source)
    R, rm = setup["tube_diameter"] / 2, sz["r_max"]
    h_ins = sz["n"] * sz["dist"].mean_volume() / (0.30 * math.pi * (R - rm) ** 2)
    nsub = max(1, int(round(setup["sample_dz"] / setup["rod_speed"] / dt)))
    travel = 0.95 * h_ins + 0.5 * rm
    press = nsub * int(math.ceil(travel / (setup["rod_speed"] * nsub * dt)))
    steps = [("settle", _rsteps(setup["max_settle_time"], dt)), ("press", press)]
    return [(nm, sz["n"], k, dt) for nm, k in steps], sz["n"], sz["dist"], 0.5 * rm, \
        "exact (compression.sizing)"


def _incline(mod, setup, params, preset, source):
    from soilcal.dem.factories import UniformRadius

    kind = setup["kind"]
    if kind == "sliding":
        x, _ = mod._block(setup)
        n, r = len(x), float(setup["sphere_radius"])
    else:
        n, r = 1, float(setup["ball_radius"])
    dt = _benchtop_dt(params, setup, preset, r, {setup["plate_material"]}, 1.0, source)
    step_deg, hold = mod.STEPS[(preset, kind)]
    step_deg = setup.get("step_deg") or step_deg
    hold = setup.get("hold_time") or hold
    holds = int(math.floor((setup["max_deg"] - setup["start_deg"]) / step_deg + 1e-9)) + 1
    steps = [("contact", max(1, int(0.05 / dt))), ("holds", holds * _rsteps(hold, dt))]
    return [(nm, n, k, dt) for nm, k in steps], n, UniformRadius(r, r), 0.2 * r, \
        "exact (the run's block / ball)"


def _paper_cohesion(setup, dist, source):
    from soilcal.dem.scenarios.base import paper_cohesion

    return paper_cohesion(setup, dist, source)


# ---------------------------------------------------------------- soil bins
def lattice_sites(lo, hi, r_max: float, jitter: float = 0.5) -> int:
    """Spheres :func:`soilcal.dem.factories.lattice_fill` places in the box ``[lo, hi]``
    (hexagonal close packing, spacing 2.02 r_max, ``jitter``), counted per lattice row with
    the same arithmetic instead of building every site."""
    import numpy as np

    a = 2.02 * r_max
    j = jitter * (a - 2 * r_max) / (2 * math.sqrt(3.0))
    llo, lhi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    steps = np.array([a, a * math.sqrt(3) / 2, a * math.sqrt(6) / 3])
    nk = np.floor((lhi - llo) / steps).astype(int) + 2
    rr = r_max + j * math.sqrt(3)
    sh = j * math.sqrt(3)

    def ok(v, q):  # the placed coordinate v along axis q lies inside, as BoxRegion.contains
        v = (v + llo[q]) + r_max + sh
        return (v - rr >= llo[q] - 1e-12) & (v + rr <= lhi[q] + 1e-12)

    i = np.arange(nk[0])
    jj = np.arange(nk[1])
    k = np.arange(nk[2])
    nx = [int(ok(a * (i + p / 2.0), 0).sum()) for p in (0, 1)]
    zin = ok(a * math.sqrt(6) / 3 * k, 2)
    total = 0
    for kq in (0, 1):
        nz = int(zin[k % 2 == kq].sum())
        if not nz:
            continue
        yin = ok(a * math.sqrt(3) / 2 * (jj + kq / 3.0), 1)
        row = sum(nx[(int(y) + kq) % 2] for y in jj[yin])
        total += nz * row
    return int(total)


def psd_fill_count(dist, volume: float) -> int:
    """Spheres :meth:`~soilcal.dem.factories.PSD.sample_mass` draws for a solid ``volume``
    (density 1, as :func:`soilcal.dem.scenarios.soilbin.fill_bin` asks): every bin filled to
    its share at the nearest whole sphere (exact for discrete sizes, the mean otherwise)."""
    import numpy as np

    ev = dist._bin_mean_volume()
    f = np.asarray(dist.mass_fraction, float)
    return int(sum(int(round(volume * fk / vk)) for fk, vk in zip(f, ev) if fk > 0))


def _bin_counts(spec, source):
    """(fill count, how) of a soil bin (the lattice or random fill of soilbin.fill_bin)."""
    from soilcal.dem.scenarios import soilbin

    if spec.psd is None:
        hi = (spec.length, spec.width, soilbin.FILL_FACTOR * spec.height)
        n = lattice_sites((0.0, 0.0, 0.0), hi, spec.r_max)
        return n, "fill exact (lattice sites)"
    h = soilbin.PSD_FILL_FACTOR * spec.height
    vol = soilbin.PSD_FILL_FRACTION * spec.length * spec.width * h
    return psd_fill_count(spec.dist, vol), "fill from its solid volume / mean sphere volume"


def _box_overlap(lo, hi, blo, bhi) -> float:
    v = 1.0
    for a, b, c, d in zip(lo, hi, blo, bhi):
        v *= max(0.0, min(b, d) - max(a, c))
    return v


def soil_bin(scenario: str, setup: dict, preset: str, source: str = "<cost>"):
    """``(settings, BinSpec)`` of a soil-bin scenario's run: the settings its ``validate``
    returns (the setup with the preset's discretisation and the surface-energy factor
    ``cohesion_scale``, :func:`soilcal.dem.scenarios.soilbin.reference_cohesion`) and the bin,
    as the scenario's ``run`` forms them."""
    mod = _module(scenario, source)
    if scenario not in SOIL_BIN:
        raise InputError(source, "scenario", f"a soil-bin scenario ({', '.join(SOIL_BIN)})",
                         scenario)
    s = mod.validate(setup, preset, source)
    return s, (mod._bin(s, source) if scenario == "bulldozing" else mod._bin(s))


def _soil_bin(mod, name, setup, params, preset, source):
    import numpy as np

    from soilcal.dem import tools
    from soilcal.dem.scenarios import soilbin

    s, spec = soil_bin(name, setup, preset, source)
    dt_settle = soilbin.soil_time_step(spec, params)
    dt = soilbin.tool_time_step(spec, params)
    n_fill, how = _bin_counts(spec, source)
    vmean = spec.dist.mean_volume()
    L, W, H = spec.length, spec.width, spec.height
    n_bed = min(n_fill, int(round(BED_FRACTION * L * W * H / vmean)))
    pad = 2.0 * spec.r_max
    extra = []
    if name == "furrow":
        v, _ = tools.furrow_opener(depth=s["depth"], half_width=s["opener_half_width"],
                                   bottom_half_width=s["opener_bottom_half_width"],
                                   upper_height=s["opener_upper_height"],
                                   upper_half_width=s["opener_upper_half_width"],
                                   length=s["opener_length"], source=source)
        v = v + np.array([mod.MARGIN + s["opener_length"], 0.5 * W, H - s["depth"]])
        trench = _box_overlap(v.min(axis=0) - pad, v.max(axis=0) + pad, (0, 0, 0), (L, W, H))
        duration, log_dt = s["travel"] / s["speed"], 0.005
    elif name == "bulldozing":
        breadth = s["slab_width"] + 2 * pad if s["periodic"] else s["plate_breadth"]
        v, _ = tools.bulldozing_plate(s["shape"], breadth=breadth, height=s["plate_height"],
                                      source=source)
        v = v + np.array([mod.START, 0.5 * W, H - s["depth"]])
        lo, hi = v.min(axis=0), v.max(axis=0)
        trench = _box_overlap((lo[0] - pad, 0.5 * W - 0.5 * breadth - pad, lo[2] - pad),
                              (hi[0] + pad, 0.5 * W + 0.5 * breadth + pad, math.inf),
                              (0, 0, 0), (L, W, H))
        duration, log_dt = s["travel"] / s["speed"], 0.01
    else:
        R = s["radius"]
        rc, h = R + pad, min(s["depth"] + pad, 2 * (R + pad))  # trench circle below the surface
        seg = rc * rc * math.acos((rc - h) / rc) - (rc - h) * math.sqrt(max(0.0, 2 * rc * h - h * h))
        trench = seg * W
        omega = 2.0 * math.pi * s["rpm"] / 60.0
        vf = s["forward_speed"]
        duration, log_dt = s["travel"] / vf, 0.005
        dt = min(dt, 0.1 * spec.r_min / (omega * R + vf))
        extra = [("lift", int(math.ceil(s["lift_time"] / dt))),
                 ("rest", int(math.ceil(s["rest_time"] / dt)))]
    n_pass = max(1, n_bed - int(round(BED_FRACTION * trench / vmean)))
    log_every = max(1, int(round(log_dt / dt)))
    pass_steps = int(math.ceil(duration / dt / log_every)) * log_every
    phases = [("settle (fill)", n_fill, int(math.ceil(0.7 * spec.settle_time / dt_settle)), dt_settle),
              ("settle (trimmed)", n_bed, int(math.ceil(0.3 * spec.settle_time / dt_settle)), dt_settle),
              ("tool pass", n_pass, pass_steps, dt)]
    phases += [(nm, n_pass, k, dt) for nm, k in extra]
    skin = spec.skin_fraction * spec.r_max
    how += f"; bed and pass from the fill volume x {BED_FRACTION} / mean sphere volume"
    return phases, n_pass, spec.dist, skin, how


# ---------------------------------------------------------------- public API
def _module(scenario: str, source: str):
    from soilcal.dem.scenarios import get

    mod = get(scenario, source)  # InputError listing the known scenarios
    if scenario not in BENCHTOP + SOIL_BIN:
        raise InputError(source, "scenario", "a scenario with a cost model (" +
                         ", ".join(BENCHTOP + SOIL_BIN) + ")", scenario)
    return mod


def estimate(scenario: str, setup, params=None, preset: str = "quick", replicates: int = 1,
             source: str = "<cost>") -> Cost:
    """Size and cost of ``replicates`` runs of ``scenario`` with ``setup`` (a setup dict as
    the run takes it, or the name of one of the scenario's setups), DEM parameters
    ``params`` (a :class:`~soilcal.dem.scenarios.base.DemParams` or a name -> value
    mapping; None: the defaults) and ``preset``, before anything runs (module docstring).

    Unknown scenarios, scenarios without a cost model and setups the scenario's
    ``validate`` refuses raise :class:`soilcal.errors.InputError`."""
    from soilcal.dem.scenarios.base import DemParams, check, merge_setup

    mod = _module(scenario, source)
    if isinstance(params, DemParams):
        dem = params
    else:
        # a point spec's values, checked at start-up or derived from checked ones (a loop
        # effect may take a friction past a soil's plausible 2): only their physical range here
        dem = DemParams.from_mapping(params or {}, source, plausible=False)
    if isinstance(setup, str):
        setup = merge_setup(mod.setups(), setup, None, source)
    check(isinstance(setup, dict), source, "setup", "a setup mapping or a setup name", setup)
    check(isinstance(replicates, int) and not isinstance(replicates, bool) and replicates >= 1,
          source, "replicates", "an integer >= 1", replicates)
    mod.validate(setup, preset, source, params=dem)
    if scenario == "repose":
        out = _repose(mod, setup, dem, preset, source)
    elif scenario == "drum":
        out = _drum(mod, setup, dem, preset, source)
    elif scenario == "compression":
        out = _compression(mod, setup, dem, preset, source)
    elif scenario == "incline":
        out = _incline(mod, setup, dem, preset, source)
    else:
        out = _soil_bin(mod, scenario, setup, dem, preset, source)
    raw, n_run, dist, skin, how = out
    phases = tuple(Phase(nm, int(n), int(k), float(dt)) for nm, n, k, dt in raw)
    hist = None
    if scenario in BENCHTOP:
        from soilcal.dem.contact import H_SIZE

        # the full row: the EPSD rolling spring, the plastic law's largest overlap
        hist = (H_SIZE if setup.get("rolling_model") == "epsd" or dem.soil_soil_plasticity > 0
                else None)
    slots = pair_slots(dist, skin)
    walls = TOOL_WALL_SLOTS if scenario in SOIL_BIN else (
        FUNNEL_WALL_SLOTS if scenario == "repose" and setup.get("method") == "funnel" else 4)
    bpp = bytes_per_particle(slots, hist, walls)
    steps = sum(p.steps for p in phases)
    return Cost(scenario=scenario, preset=preset, n_particles=int(n_run),
                peak_particles=max(p.n_particles for p in phases),
                dt_s=min(p.dt_s for p in phases),
                sim_time_s=sum(p.sim_time_s for p in phases), steps=int(steps),
                replicates=int(replicates),
                particle_steps=float(sum(p.n_particles * p.steps for p in phases) * replicates),
                runs=int(replicates), bytes_per_particle=bpp, count=how, phases=phases,
                repeat=int(replicates))


def combine(costs, replicates: int = 1) -> Cost:
    """One :class:`Cost` for runs done one after another in one job: sizes and times summed,
    memory of the largest run."""
    costs = list(costs)
    if not costs:
        raise InputError("<cost>", "runs", "at least one run", 0)
    if len(costs) == 1:
        return costs[0]
    big = max(costs, key=lambda c: c.peak_particles * c.bytes_per_particle)
    phases = tuple(Phase(f"{c.scenario}: {p.name}", p.n_particles, p.steps * c.repeat, p.dt_s)
                   for c in costs for p in c.phases)
    return Cost(scenario="+".join(dict.fromkeys(c.scenario for c in costs)),
                preset="+".join(dict.fromkeys(c.preset for c in costs)),
                n_particles=max(c.n_particles for c in costs),
                peak_particles=big.peak_particles, dt_s=min(c.dt_s for c in costs),
                sim_time_s=sum(c.sim_time_s for c in costs), steps=sum(c.steps for c in costs),
                replicates=int(replicates),
                particle_steps=sum(c.particle_steps for c in costs),
                runs=sum(c.runs for c in costs), bytes_per_particle=big.bytes_per_particle,
                count="; ".join(dict.fromkeys(c.count for c in costs)), phases=phases, repeat=1)


def spec_groups(spec: dict) -> list[dict]:
    """The distinct runs of a point spec: responses that share scenario, setup, preset and
    seed count run once (as :func:`soilcal.chain.sources.simulate` groups them); each with its
    ``replicates`` (the response's own, else the spec's)."""
    seen = {}
    for rid, rs in (spec.get("responses") or {}).items():
        k = int(rs.get("replicates", spec.get("replicates", 1)))
        key = json.dumps([rs["scenario"], rs["setup"], rs["preset"], k], sort_keys=True, default=str)
        seen.setdefault(key, dict(rs, replicates=k))
    return list(seen.values())


def estimate_spec(spec: dict, source: str | None = None) -> Cost:
    """:class:`Cost` of a job of :func:`soilcal.chain.sources.point_spec`: the sum over its
    distinct runs (:func:`spec_groups`), each its ``replicates`` times, with the spec's DEM
    parameters."""
    src = source or "{}/{}/run {}".format(spec.get("soil", "<spec>"), spec.get("stage", "?"),
                                          spec.get("run", "?"))
    groups = spec_groups(spec)
    if not groups:
        raise InputError(src, "responses", "at least one response to simulate", None)
    costs = [estimate(rs["scenario"], rs["setup"], spec.get("params"), rs["preset"], rs["replicates"], src)
             for rs in groups]
    return combine(costs, max(rs["replicates"] for rs in groups))


def estimate_job(job: dict) -> Cost | None:
    """:class:`Cost` of any DEM job of the workflow: a point spec (design point,
    verification replicate), a tool job of :func:`soilcal.chain.verify.tool_point` (its
    ``specs`` run one after another), or None for a job that does not simulate
    (``not_run``)."""
    if "not_run" in job:
        return None
    if "specs" in job:
        return combine([estimate_spec(s) for s in job["specs"]])
    return estimate_spec(job)


__all__ = ["BASE_MB", "BED_FRACTION", "COMPILE_S", "Cost", "PARALLEL_EFFICIENCY", "Phase",
           "RUN_OVERHEAD_S", "STARTUP_S", "STEP_S", "THROUGHPUT", "bytes_per_particle", "combine",
           "estimate", "estimate_job", "estimate_spec", "lattice_sites", "pair_slots",
           "psd_fill_count", "soil_bin", "spec_groups", "speedup"]
