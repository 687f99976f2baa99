"""Particle state as a structure of arrays (float64, contiguous).

Spheres: position x[N,3], velocity v[N,3], angular velocity omega[N,3], radius r[N], mass
m[N] = 4/3 pi r^3 rho, moment of inertia I = 2/5 m r^2 (solid sphere), inverse mass and
inverse inertia (0 for fixed particles or locked rotation), material id mat[N], insertion id
id[N] (0, 1, ... in the order the particles were added).

The engine re-sorts the rows in memory by neighbour cell (``Simulation(sort_every=...)``), so
row i is not particle i after a run: ``id`` follows every row, and ``Simulation.index`` maps
insertion ids to rows.
"""

from __future__ import annotations

import math
import os

import numpy as np

from soilcal.errors import InputError


class ParticleState:
    """Growable SoA container of sphere states."""

    def __init__(self):
        self.x = np.zeros((0, 3))
        self.v = np.zeros((0, 3))
        self.omega = np.zeros((0, 3))
        self.f = np.zeros((0, 3))
        self.t = np.zeros((0, 3))
        self.r = np.zeros(0)
        self.m = np.zeros(0)
        self.inv_m = np.zeros(0)
        self.inv_i = np.zeros(0)
        self.mat = np.zeros(0, dtype=np.int64)
        self.id = np.zeros(0, dtype=np.int64)
        self.disp = np.zeros((0, 3))
        self.ovr = np.zeros(0)
        # largest ovr of a row over the run; rows are re-sorted without it, so only its
        # maximum over all rows is meaningful
        self.peak = np.zeros(0)
        self.mroll = np.zeros(0)

    @property
    def n(self) -> int:
        return self.r.shape[0]

    def append(self, x, r, density, mat, v=None, omega=None, fixed=False, lock_rotation=False):
        x = np.ascontiguousarray(np.asarray(x, dtype=np.float64).reshape(-1, 3))
        k = x.shape[0]
        r = np.broadcast_to(np.asarray(r, dtype=np.float64), (k,)).copy()
        v = np.zeros((k, 3)) if v is None else np.broadcast_to(np.asarray(v, float), (k, 3))
        om = np.zeros((k, 3)) if omega is None else np.broadcast_to(np.asarray(omega, float), (k, 3))
        m = 4.0 / 3.0 * math.pi * r**3 * density
        # fixed, lock_rotation: one flag or one per particle
        fixed = np.broadcast_to(np.asarray(fixed, dtype=np.bool_), (k,))
        still = fixed | np.broadcast_to(np.asarray(lock_rotation, dtype=np.bool_), (k,))
        inv_m = np.where(fixed, 0.0, 1.0 / m)
        inv_i = np.where(still, 0.0, 1.0 / (0.4 * m * r**2))
        cat = np.concatenate
        self.x = np.ascontiguousarray(cat([self.x, x]))
        self.v = np.ascontiguousarray(cat([self.v, v]))
        self.omega = np.ascontiguousarray(cat([self.omega, om]))
        self.f = np.zeros((self.n + k, 3))
        self.t = np.zeros((self.n + k, 3))
        self.r = cat([self.r, r])
        self.m = cat([self.m, m])
        self.inv_m = cat([self.inv_m, inv_m])
        self.inv_i = cat([self.inv_i, inv_i])
        self.mat = cat([self.mat, np.full(k, mat, dtype=np.int64)])
        self.id = cat([self.id, np.arange(self.n - k, self.n, dtype=np.int64)])
        self.disp = np.zeros((self.n, 3))
        self.ovr = np.zeros(self.n)
        self.peak = cat([self.peak, np.zeros(k)])  # the run's peak survives an append
        self.mroll = np.zeros(self.n)
        return np.arange(self.n - k, self.n)


# ---------------------------------------------------------------- memory
# Engine bytes per sphere (Simulation and its lists, engine.py ``_alloc_lists``), float64 and
# int64 unless noted:
#   state: x, v, omega, f, t, disp (3 each), r, m, 1/m, 1/I, largest overlap (step and
#   run), rolling resistance (``bounded``), material, id
STATE_BYTES = 8 * (6 * 3 + 9)
#   two list buffers, each: row offset; 8 pair slots (partner, 4 history columns, int8
#   touching flag); 4 wall slots (primitive, 9 history columns) and a wall count
LIST_BYTES = 2 * (8 + 8 * (8 + 4 * 8 + 1) + 4 * (8 + 9 * 8) + 8)
#   wall reactions (4 x 6), packed rows (4 + 8), sort work space (1 + 8 + 1), slab order,
#   cell index, cell of, cell-sorted copy (4), near-list count and displacements (1 + 3);
#   partners of the build's count pass (int32, one per pair slot: so in a bed whose block
#   groups hold as many pairs each; a bed of uneven density needs up to NBLK_GROUPS = 32 per
#   pair, neighbour.build_lists); the near list (int32, one per pair slot)
WORK_BYTES = 8 * (4 * 6 + 4 + 8 + 1 + 8 + 1 + 1 + 1 + 1 + 4 + 1 + 3) + 4 * 8 + 4 * 8
BYTES_PER_PARTICLE = STATE_BYTES + LIST_BYTES + WORK_BYTES


def available_memory() -> int:
    """Bytes of memory available to a new allocation on this machine (Linux MemAvailable;
    elsewhere the physical memory)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 1 << 62


def check_memory(n, source, field, hint=""):
    """Refuse, before anything is allocated, a particle count whose engine state
    (BYTES_PER_PARTICLE each, pair lists at their initial 8 slots per sphere) would not fit
    in the memory available here."""
    need = float(n) * BYTES_PER_PARTICLE
    avail = available_memory()
    if need > avail:
        raise InputError(source, field,
                         f"a particle count whose engine state fits in the memory available "
                         f"here ({avail / 1e9:.3g} GB at about {BYTES_PER_PARTICLE} bytes per "
                         f"sphere; fewer or larger spheres){hint}",
                         f"{int(n):,} spheres (about {need / 1e9:.3g} GB)")
