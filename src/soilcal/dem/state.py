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

import numpy as np


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
        inv_m = np.zeros(k) if fixed else 1.0 / m
        inv_i = np.zeros(k) if (fixed or lock_rotation) else 1.0 / (0.4 * m * r**2)
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
        return np.arange(self.n - k, self.n)
