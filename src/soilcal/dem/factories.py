"""Particle factories: size distributions, random insertion, rate insertion, lattices.

Size distributions
------------------
* :class:`UniformRadius` -- radii uniform *by number* on ``[r_min, r_max]``;
  mean particle volume ``(4/3) pi E[r^3]``, ``E[r^3] = (b^4 - a^4) / (4 (b - a))``.
* :class:`PSD` -- a particle-size distribution given as mass fractions
  ``f_k`` of bins ``[a_k, b_k]`` of radius (a sieve analysis) or of discrete
  sizes (``a_k = b_k``).  Within a bin the *mass* is taken as uniformly
  distributed over radius, so the number density is ``p(r) ~ r^-3``:
  sampling by inverse CDF,
  ``r = (a^-2 - u (a^-2 - b^-2))^(-1/2)``, ``u ~ U(0, 1)``.
  The number of particles per unit mass of bin k (solid density rho) is
  ``n_k = 3 (a^-2 - b^-2) / (8 pi rho (b - a))`` (``3 / (4 pi rho a^3)`` for a
  discrete size), so the number fractions are ``nu_k = f_k n_k / sum f_j n_j``
  and the mean particle volume is
  ``E[v] = sum_k nu_k (4/3) pi (b - a) / Z_k``, ``Z_k = (a^-2 - b^-2) / 2``.
  A count request allocates ``N nu_k`` particles to bin k by the largest
  remainder method; a mass request fills every bin to ``M f_k`` (the last
  particle of a bin is kept if that brings the bin mass closer to its
  target), so small samples honour the PSD without sampling noise.
* Coarse graining: scaling all radii by ``s`` keeps the PSD shape; a bulk
  volume ``V`` at solid fraction ``phi`` then holds
  ``N = phi V / (s^3 E[v])`` particles, so the smallest scale that keeps
  ``N <= N_max`` is ``s = max(1, (phi V / (N_max E[v]))^(1/3))``
  (:func:`coarse_graining_scale`; Radl et al. 2011, "Parcel-based approach for
  the simulation of gas-particle flows", and Bierwisch et al. 2009, J. Mech.
  Phys. Solids 57:10-31, for the similarity argument).

Random insertion
----------------
Random sequential addition (RSA): candidate centres are drawn uniformly in
the part of the region where the sphere lies entirely inside (a frustum,
:class:`ConeRegion`: drawn in its enclosing cylinder, those outside the cone
rejected), and accepted
when no existing or already placed sphere overlaps (``|x_i - x_j| >= r_i +
r_j``), the check running over the 27 cells of a uniform grid of cell size
``>= r_new,max + r_max``.  Spheres are placed largest first.  RSA of equal
spheres saturates at a solid fraction of 0.3841 (Zhang & Torquato 2013,
Phys. Rev. E 88, 053312), so requests above ``max_fraction`` (default 0.35)
of the region volume are refused up front with :class:`InputError`; a
request that still fails (``max_attempts`` rejected candidates for one
sphere) raises the same error.  Denser beds are made by letting inserted
particles settle under gravity, or with :func:`lattice_fill`.

Random numbers come only from the ``numpy.random.Generator`` passed in or
built from ``seed``: candidate uniforms are drawn in blocks by numpy and
consumed by the compiled kernel, so results are deterministic for a seed.

Lattices
--------
Simple cubic sites ``a (i, j, k)``; hexagonal close packed (ABAB stacking)
``a (i + ((j + k) mod 2)/2, (sqrt(3)/2)(j + (k mod 2)/3), sqrt(6)/3 k)``, both
with nearest-neighbour distance ``a``.  A jitter of every coordinate within
``+-j``, ``j = jitter (a - 2 r_max) / (2 sqrt(3))``, moves a centre by at most
``(a - 2 r_max)/2`` so no two spheres can overlap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from soilcal.dem.state import check_memory
from soilcal.errors import InputError

RSA_SATURATION = 0.3841  # Zhang & Torquato (2013), equal spheres in 3-D


def _rng(rng=None, seed=None):
    if rng is not None:
        return rng
    if seed is None:
        raise ValueError("give a numpy Generator (rng=) or a seed (seed=); runs must be seeded")
    return np.random.default_rng(seed)


# ---------------------------------------------------------------------------
# regions
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class BoxRegion:
    """Axis-aligned box ``[lo, hi]``."""

    lo: tuple
    hi: tuple

    def __post_init__(self):
        lo = np.asarray(self.lo, dtype=np.float64)
        hi = np.asarray(self.hi, dtype=np.float64)
        if lo.shape != (3,) or hi.shape != (3,) or np.any(hi <= lo):
            raise ValueError(f"box region needs lo < hi, got {self.lo}, {self.hi}")

    @property
    def volume(self):
        return float(np.prod(np.subtract(self.hi, self.lo)))

    def min_extent(self):
        return float(np.min(np.subtract(self.hi, self.lo)))

    def bbox(self):
        return np.asarray(self.lo, np.float64), np.asarray(self.hi, np.float64)

    def contains(self, x, r):
        """True where a sphere of radius r at x lies entirely inside."""
        x = np.atleast_2d(x)
        r = np.asarray(r, dtype=np.float64).reshape(-1, 1)
        return np.all((x - r >= np.asarray(self.lo) - 1e-12)
                      & (x + r <= np.asarray(self.hi) + 1e-12), axis=1)

    def kernel_params(self):
        p = np.zeros(16)
        p[0:3] = self.lo
        p[3:6] = self.hi
        return 0, p

    def local_frame(self):
        """(origin, rows = local unit axes, local lo, local hi)."""
        return (np.zeros(3), np.eye(3), np.asarray(self.lo, np.float64),
                np.asarray(self.hi, np.float64))


def _axial(region, x, r):
    """Axial coordinate and distance from the axis of points x in an axisymmetric region,
    with the radii r as a flat array."""
    x = np.atleast_2d(x)
    d = region._frame[0]
    w = x - np.asarray(region.axis_point, dtype=np.float64)
    z = w @ d
    rho = np.linalg.norm(w - z[:, None] * d, axis=1)
    return z, rho, np.asarray(r, dtype=np.float64).reshape(-1)


@dataclass(frozen=True)
class CylinderRegion:
    """Solid cylinder of ``radius`` between axial coordinates ``z0 < z1``
    measured from ``axis_point`` along ``axis_dir``."""

    radius: float
    z0: float
    z1: float
    axis_point: tuple = (0.0, 0.0, 0.0)
    axis_dir: tuple = (0.0, 0.0, 1.0)
    _frame: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if self.radius <= 0 or self.z1 <= self.z0:
            raise ValueError("cylinder region needs radius > 0 and z1 > z0")
        d = np.asarray(self.axis_dir, dtype=np.float64)
        d = d / np.linalg.norm(d)
        a = np.array([1.0, 0, 0]) if abs(d[0]) < 0.9 else np.array([0, 1.0, 0])
        e1 = np.cross(d, a)
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(d, e1)
        object.__setattr__(self, "_frame", (d, e1, e2))

    @property
    def volume(self):
        return math.pi * self.radius**2 * (self.z1 - self.z0)

    def min_extent(self):
        return min(2 * self.radius, self.z1 - self.z0)

    def bbox(self):
        d = self._frame[0]
        a = np.asarray(self.axis_point, dtype=np.float64)
        c0, c1 = a + self.z0 * d, a + self.z1 * d
        ext = self.radius * np.sqrt(np.clip(1 - d**2, 0, 1))
        return np.minimum(c0, c1) - ext, np.maximum(c0, c1) + ext

    def contains(self, x, r):
        z, rho, r = _axial(self, x, r)
        return ((z - r >= self.z0 - 1e-12) & (z + r <= self.z1 + 1e-12)
                & (rho + r <= self.radius + 1e-12))

    def kernel_params(self):
        d, e1, e2 = self._frame
        p = np.zeros(16)
        p[0:3] = self.axis_point
        p[3:6] = d
        p[6:9] = e1
        p[9:12] = e2
        p[12], p[13], p[14] = self.radius, self.z0, self.z1
        return 1, p

    def local_frame(self):
        d, e1, e2 = self._frame
        R = self.radius
        return (np.asarray(self.axis_point, np.float64), np.vstack([e1, e2, d]),
                np.array([-R, -R, self.z0]), np.array([R, R, self.z1]))


@dataclass(frozen=True)
class ConeRegion:
    """Solid frustum (truncated cone) between axial coordinates ``z0 < z1`` measured from
    ``axis_point`` along ``axis_dir``, of radius ``radius0`` at ``z0`` and ``radius1`` at
    ``z1`` (a funnel's inside).

    A sphere of radius r at axial coordinate z and distance rho from the axis lies inside
    when ``z - r >= z0``, ``z + r <= z1`` and its distance to the cone's side,
    ``(R(z) - rho) cos(alpha)`` with ``R(z)`` the radius at z and ``tan(alpha) =
    (radius1 - radius0) / (z1 - z0)`` the half-angle, is at least r.  Random insertion
    draws candidates in the enclosing cylinder and rejects those outside.
    """

    radius0: float
    radius1: float
    z0: float
    z1: float
    axis_point: tuple = (0.0, 0.0, 0.0)
    axis_dir: tuple = (0.0, 0.0, 1.0)
    _frame: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if self.radius0 <= 0 or self.radius1 <= 0 or self.z1 <= self.z0:
            raise ValueError("cone region needs radii > 0 and z1 > z0")
        object.__setattr__(self, "_frame", self._cyl._frame)

    @property
    def _cos(self):
        return 1.0 / math.hypot(1.0, (self.radius1 - self.radius0) / (self.z1 - self.z0))

    @property
    def _cyl(self):
        return CylinderRegion(max(self.radius0, self.radius1), self.z0, self.z1,
                              self.axis_point, self.axis_dir)

    @property
    def volume(self):
        a, b = self.radius0, self.radius1
        return math.pi * (self.z1 - self.z0) / 3.0 * (a * a + a * b + b * b)

    def min_extent(self):
        return min(2 * min(self.radius0, self.radius1), self.z1 - self.z0)

    def bbox(self):
        return self._cyl.bbox()

    def radius_at(self, z):
        return self.radius0 + (self.radius1 - self.radius0) * (np.asarray(z) - self.z0) / (
            self.z1 - self.z0)

    def contains(self, x, r):
        z, rho, r = _axial(self, x, r)
        return ((z - r >= self.z0 - 1e-12) & (z + r <= self.z1 + 1e-12)
                & ((self.radius_at(z) - rho) * self._cos >= r - 1e-12))

    def kernel_params(self):
        _, p16 = self._cyl.kernel_params()
        p = np.zeros(18)
        p[:16] = p16
        p[15], p[16], p[17] = self.radius0, self.radius1, self._cos
        return 2, p

    def local_frame(self):
        return self._cyl.local_frame()


# ---------------------------------------------------------------------------
# size distributions
# ---------------------------------------------------------------------------


def _sphere_volume(r):
    return 4.0 / 3.0 * np.pi * np.asarray(r, dtype=np.float64) ** 3


@dataclass(frozen=True)
class UniformRadius:
    """Radii uniform by number on ``[r_min, r_max]``."""

    r_min: float
    r_max: float

    def __post_init__(self):
        if not (0 < self.r_min <= self.r_max):
            raise ValueError(f"need 0 < r_min <= r_max, got {self.r_min}, {self.r_max}")

    @classmethod
    def splitting(cls, volume: float, n: int, spread: float = 0.1) -> "UniformRadius":
        """Radii uniform on [(1 - spread) r, (1 + spread) r] with the mean sphere volume
        ``volume / n``: ``n`` spheres of this distribution fill ``volume`` on average
        (<r^3> = r^3 ((1 + s)^4 - (1 - s)^4) / (8 s), 1.01 r^3 at s = 0.1)."""
        if not (isinstance(n, (int, np.integer)) and n >= 1):
            raise ValueError(f"need a whole number of spheres n >= 1, got {n!r}")
        if not (volume > 0 and 0 <= spread < 1):
            raise ValueError(f"need volume > 0 and 0 <= spread < 1, got {volume}, {spread}")
        unit = cls.about(1.0, spread).mean_volume()  # at r = 1 m
        return cls.about((volume / (n * unit)) ** (1.0 / 3.0), spread)

    @classmethod
    def about(cls, r: float, spread: float = 0.1) -> "UniformRadius":
        """Radii uniform on [(1 - spread) r, (1 + spread) r]."""
        return cls((1.0 - spread) * float(r), (1.0 + spread) * float(r))

    @property
    def r_mid(self) -> float:
        return 0.5 * (self.r_min + self.r_max)

    def mean_volume(self):
        a, b = self.r_min, self.r_max
        er3 = a**3 if a == b else (b**4 - a**4) / (4 * (b - a))
        return 4.0 / 3.0 * math.pi * er3

    def sample(self, n, rng):
        return rng.uniform(self.r_min, self.r_max, int(n)) if self.r_max > self.r_min \
            else np.full(int(n), self.r_min)

    sample_iid = sample

    def sample_mass(self, mass, density, rng):
        out, m = [], 0.0
        while m < mass:
            r = self.sample(1, rng)[0]
            mr = density * 4.0 / 3.0 * math.pi * r**3
            if m + mr > mass and (m + mr - mass) > (mass - m):
                break
            out.append(r)
            m += mr
        return np.array(out)

    def scaled(self, s):
        return UniformRadius(self.r_min * s, self.r_max * s)


@dataclass(frozen=True)
class PSD:
    """Mass-fraction size distribution over radius bins ``[lower_k, upper_k]``
    (``lower_k == upper_k`` for discrete sizes)."""

    lower: tuple
    upper: tuple
    mass_fraction: tuple

    def __post_init__(self):
        a = np.asarray(self.lower, np.float64)
        b = np.asarray(self.upper, np.float64)
        f = np.asarray(self.mass_fraction, np.float64)
        if not (a.shape == b.shape == f.shape and a.ndim == 1 and a.size > 0):
            raise ValueError("lower, upper and mass_fraction must be equal-length 1-D")
        if np.any(a <= 0) or np.any(b < a):
            raise ValueError("bins need 0 < lower <= upper")
        if np.any(f < 0) or not math.isclose(f.sum(), 1.0, abs_tol=1e-9):
            raise ValueError("mass fractions must be >= 0 and sum to 1")

    # -- constructors -------------------------------------------------------
    @classmethod
    def from_mass_percent(cls, sizes, percent, diameter=True, source=None, field="psd",
                          tolerance=1.0):
        """PSD from a table of mass percentages.

        ``sizes`` are bin edges (``len(percent) + 1`` increasing values) or
        discrete sizes (``len(percent)`` values); diameters unless
        ``diameter=False``.  Percentages must sum to 100 within ``tolerance``
        and are renormalised to fractions.  Errors name ``source`` and
        ``field``.
        """
        s = np.asarray(sizes, dtype=np.float64).reshape(-1)
        p = np.asarray(percent, dtype=np.float64).reshape(-1)
        k = 0.5 if diameter else 1.0
        if p.size == 0 or np.any(~np.isfinite(p)) or np.any(p < 0):
            raise InputError(source, f"{field}.percent", "non-negative mass percentages",
                             list(p))
        if abs(p.sum() - 100.0) > tolerance:
            raise InputError(source, f"{field}.percent",
                             f"mass percentages summing to 100 (+-{tolerance})", float(p.sum()))
        if np.any(~np.isfinite(s)) or np.any(s <= 0):
            raise InputError(source, f"{field}.sizes", "positive finite sizes (a lowest "
                             "bin starting at 0 needs a finite lower size)", list(s))
        if s.size == p.size + 1:
            if np.any(np.diff(s) <= 0):
                raise InputError(source, f"{field}.sizes", "strictly increasing bin edges",
                                 list(s))
            lo, hi = s[:-1] * k, s[1:] * k
        elif s.size == p.size:
            lo = hi = s * k
        else:
            raise InputError(source, f"{field}.sizes", f"{p.size + 1} bin edges or {p.size} "
                             "discrete sizes", f"{s.size} values")
        keep = p > 0
        f = p[keep] / p[keep].sum()
        return cls(tuple(lo[keep]), tuple(hi[keep]), tuple(f))

    @classmethod
    def from_number_fractions(cls, radii, fractions):
        """Discrete radii with *number* fractions converted to mass fractions
        ``f_k ~ nu_k r_k^3``."""
        r = np.asarray(radii, np.float64)
        nu = np.asarray(fractions, np.float64)
        m = nu * r**3
        return cls(tuple(r), tuple(r), tuple(m / m.sum()))

    # -- properties ---------------------------------------------------------
    @property
    def r_min(self):
        return float(np.min(self.lower))

    @property
    def r_max(self):
        return float(np.max(self.upper))

    def _bins(self):
        return (np.asarray(self.lower, np.float64), np.asarray(self.upper, np.float64),
                np.asarray(self.mass_fraction, np.float64))

    def _bin_mean_volume(self):
        a, b, _ = self._bins()
        disc = b <= a * (1 + 1e-12)
        z = np.where(disc, 1.0, 0.5 * (a**-2.0 - b**-2.0))
        ev = np.where(disc, _sphere_volume(a), 4.0 / 3.0 * np.pi * (b - a) / z)
        return ev

    def number_fractions(self):
        """Number fractions ``nu_k`` of the bins."""
        _, _, f = self._bins()
        w = f / self._bin_mean_volume()  # particles per unit solid volume of bin
        return w / w.sum()

    def mean_volume(self):
        return float(np.sum(self.number_fractions() * self._bin_mean_volume()))

    def _draw_in_bin(self, k, n, rng):
        a, b, _ = self._bins()
        u = rng.random(int(n))
        if b[k] <= a[k] * (1 + 1e-12):
            return np.full(int(n), a[k])
        ia, ib = a[k] ** -2.0, b[k] ** -2.0
        return (ia - u * (ia - ib)) ** -0.5

    # -- sampling -----------------------------------------------------------
    def sample(self, n, rng):
        """``n`` radii, bin counts by largest remainder of ``n nu_k``, shuffled."""
        n = int(n)
        nu = self.number_fractions()
        exact = n * nu
        cnt = np.floor(exact).astype(np.int64)
        rem = n - cnt.sum()
        if rem > 0:
            order = np.argsort(-(exact - cnt), kind="stable")
            cnt[order[:rem]] += 1
        out = np.concatenate([self._draw_in_bin(k, c, rng) for k, c in enumerate(cnt)])
        return rng.permutation(out)

    def sample_iid(self, n, rng):
        """``n`` independent radii (bin chosen with probability ``nu_k``)."""
        n = int(n)
        nu = self.number_fractions()
        ks = rng.choice(len(nu), size=n, p=nu)
        out = np.empty(n)
        for k in range(len(nu)):
            sel = ks == k
            out[sel] = self._draw_in_bin(k, int(sel.sum()), rng)
        return out

    def sample_mass(self, mass, density, rng):
        """Radii whose total mass approximates ``mass`` with every bin filled
        to ``mass * f_k`` (closest stop), shuffled."""
        _, _, f = self._bins()
        ev = self._bin_mean_volume()
        out = []
        for k in range(len(f)):
            target = mass * f[k]
            if target <= 0:
                continue
            got = []
            m = 0.0
            while True:
                guess = max(8, int(1.2 * (target - m) / (density * ev[k])) + 8)
                for r in self._draw_in_bin(k, guess, rng):
                    mr = density * 4.0 / 3.0 * math.pi * r**3
                    if m + mr > target:
                        if (m + mr - target) <= (target - m):
                            got.append(r)
                            m += mr
                        break
                    got.append(r)
                    m += mr
                else:
                    continue
                break
            out.append(np.asarray(got))
        return rng.permutation(np.concatenate(out)) if out else np.zeros(0)

    def scaled(self, s):
        """Coarse-grained PSD: all radii multiplied by ``s`` (same fractions)."""
        return PSD(tuple(np.multiply(self.lower, s)), tuple(np.multiply(self.upper, s)),
                   self.mass_fraction)


def coarse_graining_scale(dist, bulk_volume, solid_fraction, n_max):
    """Smallest radius scale ``s >= 1`` such that a bulk volume at the given
    solid fraction holds at most ``n_max`` particles of ``dist`` scaled by s:
    ``s = max(1, (phi V / (N_max E[v]))^(1/3))``."""
    if not (0 < solid_fraction < 1) or bulk_volume <= 0 or n_max < 1:
        raise ValueError("need 0 < solid_fraction < 1, bulk_volume > 0, n_max >= 1")
    s = (solid_fraction * bulk_volume / (n_max * dist.mean_volume())) ** (1.0 / 3.0)
    return max(1.0, s)


# ---------------------------------------------------------------------------
# random sequential addition kernel
# ---------------------------------------------------------------------------


@njit(cache=True)
def _candidate(kind, prm, r, u0, u1, u2):
    """A candidate centre and whether the sphere lies inside the region (kind 0 box, 1
    cylinder: always; 2 frustum: drawn in the enclosing cylinder, rejected outside)."""
    if kind == 0:
        x = prm[0] + r + u0 * (prm[3] - prm[0] - 2.0 * r)
        y = prm[1] + r + u1 * (prm[4] - prm[1] - 2.0 * r)
        z = prm[2] + r + u2 * (prm[5] - prm[2] - 2.0 * r)
        return x, y, z, True
    rho = (prm[12] - r) * math.sqrt(u0)
    th = 2.0 * math.pi * u1
    zz = prm[13] + r + u2 * (prm[14] - prm[13] - 2.0 * r)
    c, s = rho * math.cos(th), rho * math.sin(th)
    x = prm[0] + zz * prm[3] + c * prm[6] + s * prm[9]
    y = prm[1] + zz * prm[4] + c * prm[7] + s * prm[10]
    z = prm[2] + zz * prm[5] + c * prm[8] + s * prm[11]
    inside = True
    if kind == 2:
        rz = prm[15] + (prm[16] - prm[15]) * (zz - prm[13]) / (prm[14] - prm[13])
        inside = (rz - rho) * prm[17] >= r
    return x, y, z, inside


@njit(cache=True)
def _cell_of(x, y, z, glo, h, dims):
    i = int((x - glo[0]) / h)
    j = int((y - glo[1]) / h)
    k = int((z - glo[2]) / h)
    i = min(max(i, 0), dims[0] - 1)
    j = min(max(j, 0), dims[1] - 1)
    k = min(max(k, 0), dims[2] - 1)
    return i, j, k


@njit(cache=True)
def _grid_insert(idx, x, y, z, glo, h, dims, head, nxt):
    i, j, k = _cell_of(x, y, z, glo, h, dims)
    c = (i * dims[1] + j) * dims[2] + k
    nxt[idx] = head[c]
    head[c] = idx


@njit(cache=True)
def _rsa_kernel(radii, i_start, att_start, kind, prm, pos, rad, n_stored, glo, h, dims,
                head, nxt, uni, u_start, max_attempts):
    """Place radii[i_start:] one by one.  ``pos``/``rad`` hold the
    ``n_stored`` spheres already in the grid; placed spheres are appended.

    Returns (next particle, attempts spent on it, next uniform row, n_stored,
    status) with status 0 done, 1 uniforms exhausted, 2 max_attempts hit."""
    ub = u_start
    att = att_start
    for i in range(i_start, radii.shape[0]):
        r = radii[i]
        while True:
            if att >= max_attempts:
                return i, att, ub, n_stored, 2
            if ub >= uni.shape[0]:
                return i, att, ub, n_stored, 1
            x, y, z, inside = _candidate(kind, prm, r, uni[ub, 0], uni[ub, 1], uni[ub, 2])
            ub += 1
            att += 1
            if not inside:
                continue
            ci, cj, ck = _cell_of(x, y, z, glo, h, dims)
            ok = True
            for a in range(max(ci - 1, 0), min(ci + 2, dims[0])):
                for b in range(max(cj - 1, 0), min(cj + 2, dims[1])):
                    for c in range(max(ck - 1, 0), min(ck + 2, dims[2])):
                        q = head[(a * dims[1] + b) * dims[2] + c]
                        while q >= 0:
                            dx = x - pos[q, 0]
                            dy = y - pos[q, 1]
                            dz = z - pos[q, 2]
                            s = r + rad[q]
                            if dx * dx + dy * dy + dz * dz < s * s:
                                ok = False
                                break
                            q = nxt[q]
                        if not ok:
                            break
                    if not ok:
                        break
                if not ok:
                    break
            if ok:
                pos[n_stored, 0] = x
                pos[n_stored, 1] = y
                pos[n_stored, 2] = z
                rad[n_stored] = r
                _grid_insert(n_stored, x, y, z, glo, h, dims, head, nxt)
                n_stored += 1
                att = 0
                break
    return radii.shape[0], 0, ub, n_stored, 0


class _RSA:
    """Grid state for random sequential addition into one region."""

    def __init__(self, region, r_new_max, existing_positions, existing_radii, capacity_new,
                 max_cells=4_000_000):
        lo, hi = region.bbox()
        ex = (np.zeros((0, 3)) if existing_positions is None
              else np.asarray(existing_positions, np.float64).reshape(-1, 3))
        er = (np.zeros(0) if existing_radii is None
              else np.asarray(existing_radii, np.float64).reshape(-1))
        if ex.shape[0] != er.shape[0]:
            raise ValueError("existing positions and radii differ in length")
        r_ex_max = float(er.max()) if er.size else 0.0
        margin = r_new_max + r_ex_max
        glo, ghi = lo - margin, hi + margin
        if ex.shape[0]:
            near = np.all((ex >= glo) & (ex <= ghi), axis=1)
            ex, er = ex[near], er[near]
        h = max(2.0 * r_new_max, r_new_max + r_ex_max)
        ext = ghi - glo
        total = ex.shape[0] + capacity_new
        cap_cells = max(64, min(max_cells, 8 * total))
        while np.prod(np.maximum(1, np.ceil(ext / h))) > cap_cells:
            h *= 1.25
        self.glo = glo
        self.h = float(h)
        self.dims = np.maximum(1, np.ceil(ext / h)).astype(np.int64)
        self.head = np.full(int(np.prod(self.dims)), -1, dtype=np.int64)
        self.pos = np.empty((total, 3))
        self.rad = np.empty(total)
        self.nxt = np.full(total, -1, dtype=np.int64)
        self.n = ex.shape[0]
        self.n_existing = ex.shape[0]
        self.pos[: self.n] = ex
        self.rad[: self.n] = er
        for q in range(self.n):
            _grid_insert(q, ex[q, 0], ex[q, 1], ex[q, 2], self.glo, self.h, self.dims,
                         self.head, self.nxt)
        self.kind, self.prm = region.kernel_params()

    def place(self, radii, rng, max_attempts, block=None):
        """Place ``radii`` in order; stop at the first sphere that fails.
        Returns the number placed."""
        radii = np.ascontiguousarray(radii, dtype=np.float64)
        n0 = self.n
        i, att = 0, 0
        block = block or max(1024, 4 * radii.size)
        while i < radii.size:
            uni = rng.random((block, 3))
            i, att, _, self.n, status = _rsa_kernel(
                radii, i, att, self.kind, self.prm, self.pos, self.rad, self.n, self.glo,
                self.h, self.dims, self.head, self.nxt, uni, 0, max_attempts)
            if status == 2:
                break
        return self.n - n0

    def new(self, start):
        return self.pos[start:self.n].copy(), self.rad[start:self.n].copy()


def _check_fit(region, radii, max_fraction, source, field):
    if radii.size == 0:
        return
    if 2.0 * radii.max() >= region.min_extent():
        raise InputError(source, field, f"particle diameters below the region's smallest "
                         f"extent {region.min_extent():.6g}", f"{2 * radii.max():.6g}")
    phi = float(_sphere_volume(radii).sum() / region.volume)
    if phi > max_fraction:
        raise InputError(source, field, f"a solid volume fraction of the region <= "
                         f"{max_fraction} for random insertion (RSA saturates at "
                         f"{RSA_SATURATION}); use a larger region, fewer particles, or "
                         f"lattice_fill", f"{phi:.4f} ({radii.size} particles)")


def insert_random(region, dist, n=None, mass=None, density=None, rng=None, seed=None,
                  existing_positions=None, existing_radii=None, max_attempts=20000,
                  max_fraction=0.35, source=None, field="insertion"):
    """Random non-overlapping spheres in ``region`` (RSA), count ``n`` or total
    ``mass`` (needs ``density``), also avoiding existing spheres.

    Returns ``(positions float64[N, 3], radii float64[N])`` in placement
    order (largest first).  Impossible requests raise InputError naming
    ``source``/``field``."""
    rng = _rng(rng, seed)
    if (n is None) == (mass is None):
        raise InputError(source, field, "exactly one of a particle count or a total mass",
                         {"n": n, "mass": mass})
    if n is not None:
        if int(n) < 0:
            raise InputError(source, f"{field}.n", "a non-negative particle count", n)
        check_memory(int(n), source, f"{field}.n")
        radii = dist.sample(int(n), rng)
    else:
        if density is None or density <= 0 or mass < 0:
            raise InputError(source, f"{field}.mass", "mass >= 0 with a positive density",
                             {"mass": mass, "density": density})
        check_memory(float(mass) / (float(density) * dist.mean_volume()), source,
                     f"{field}.mass")
        radii = dist.sample_mass(float(mass), float(density), rng)
    radii = np.sort(radii)[::-1].copy()
    _check_fit(region, radii, max_fraction, source, field)
    if radii.size == 0:
        return np.zeros((0, 3)), radii
    rsa = _RSA(region, float(radii.max()), existing_positions, existing_radii, radii.size)
    start = rsa.n
    placed = rsa.place(radii, rng, max_attempts)
    if placed < radii.size:
        raise InputError(source, field, f"room for {radii.size} non-overlapping particles "
                         f"(random insertion gave up after {max_attempts} rejected "
                         "positions for one particle)", f"only {placed} placed")
    return rsa.new(start)


class RateInserter:
    """Insert particles at a rate (particles/s, or kg/s with ``density``) into a
    region, never overlapping particles already there.

    Number rate: by time ``t`` a total of ``floor(rate (t - t_start))``
    particles are due.  Mass rate: the next particle (radius drawn in advance)
    is due while ``inserted mass + m_next / 2 <= rate (t - t_start)``, so the
    inserted mass tracks the target within half a particle.  Particles that
    find no room stay pending (``pending``) and are retried first on the
    next call.  Insertion stops at ``t_end``.
    """

    def __init__(self, region, dist, rate, basis="number", density=None, seed=None, rng=None,
                 t_start=0.0, t_end=math.inf, max_attempts=2000, source=None, field="inlet"):
        if basis not in ("number", "mass"):
            raise InputError(source, f"{field}.basis", "'number' or 'mass'", basis)
        if not rate > 0:
            raise InputError(source, f"{field}.rate", "a positive rate", rate)
        if basis == "mass" and not (density and density > 0):
            raise InputError(source, f"{field}.density", "a positive particle density for a "
                             "mass rate", density)
        r_big = dist.r_max
        if 2 * r_big >= region.min_extent():
            raise InputError(source, field, "particle diameters below the region's smallest "
                             f"extent {region.min_extent():.6g}", f"{2 * r_big:.6g}")
        self.region, self.dist, self.rate, self.basis = region, dist, float(rate), basis
        self.density = density
        self.rng = _rng(rng, seed)
        self.t_start, self.t_end = float(t_start), float(t_end)
        self.max_attempts = int(max_attempts)
        self.inserted = 0
        self.inserted_mass = 0.0
        self._queue = np.zeros(0)
        self._pending = 0

    def _target(self, t):
        return self.rate * max(0.0, min(t, self.t_end) - self.t_start)

    def _ensure(self, k):
        if self._queue.size < k:
            more = self.dist.sample_iid(max(k - self._queue.size, 64), self.rng)
            self._queue = np.concatenate([self._queue, more])

    def _mass(self, r):
        return self.density * 4.0 / 3.0 * math.pi * np.asarray(r) ** 3

    def due(self, t):
        """How many particles should be inserted now to meet the rate at ``t``
        (including pending ones)."""
        if self.basis == "number":
            return max(0, int(math.floor(self._target(t) + 1e-9)) - self.inserted)
        target = self._target(t)
        k, m = 0, self.inserted_mass
        while True:
            self._ensure(k + 1)
            mk = float(self._mass(self._queue[k]))
            if m + 0.5 * mk > target:
                return k
            m += mk
            k += 1

    @property
    def pending(self):
        """Particles due at the last call that found no room."""
        return self._pending

    def insert(self, t, existing_positions=None, existing_radii=None):
        """Positions and radii of the particles to add at time ``t``."""
        k = self.due(t)
        if k == 0:
            self._pending = 0
            return np.zeros((0, 3)), np.zeros(0)
        self._ensure(k)
        radii = self._queue[:k]
        rsa = _RSA(self.region, float(radii.max()), existing_positions, existing_radii, k)
        start = rsa.n
        placed = rsa.place(radii, self.rng, self.max_attempts)
        pos, rad = rsa.new(start)
        self._queue = self._queue[placed:]
        self.inserted += placed
        self.inserted_mass += float(self._mass(rad).sum()) if self.basis == "mass" else 0.0
        self._pending = k - placed
        return pos, rad


# ---------------------------------------------------------------------------
# lattices
# ---------------------------------------------------------------------------


def lattice_fill(region, radius=None, dist=None, kind="hcp", spacing=None, jitter=0.0, n=None,
                 rng=None, seed=None, source=None, field="lattice"):
    """Fill ``region`` with spheres on a simple cubic (``"sc"``) or hexagonal
    close-packed (``"hcp"``) lattice.

    Give a single ``radius`` or a size distribution ``dist`` (sites sized for
    ``dist.r_max``).  ``spacing`` (nearest-neighbour distance) defaults to
    ``2.02 r_max`` and must be >= ``2 r_max``; ``jitter`` in [0, 1] moves
    centres randomly within the free gap.  With ``n`` only the ``n`` sites
    lowest along the region's third local axis (z, or the cylinder axis) are
    kept.  Returns ``(positions, radii)``.
    """
    if (radius is None) == (dist is None):
        raise InputError(source, field, "either a radius or a size distribution", None)
    r_max = float(radius) if radius is not None else float(dist.r_max)
    if r_max <= 0:
        raise InputError(source, f"{field}.radius", "a positive radius", r_max)
    a = 2.02 * r_max if spacing is None else float(spacing)
    if a < 2 * r_max:
        raise InputError(source, f"{field}.spacing", f">= 2 r_max = {2 * r_max:.6g}", a)
    if not 0 <= jitter <= 1:
        raise InputError(source, f"{field}.jitter", "a fraction in [0, 1]", jitter)
    if kind not in ("sc", "hcp"):
        raise InputError(source, f"{field}.kind", "'sc' or 'hcp'", kind)
    if jitter > 0 or dist is not None:
        rng = _rng(rng, seed)
    j = jitter * (a - 2 * r_max) / (2 * math.sqrt(3.0))
    origin, axes, llo, lhi = region.local_frame()
    if kind == "sc":
        steps = np.array([a, a, a])
    else:
        steps = np.array([a, a * math.sqrt(3) / 2, a * math.sqrt(6) / 3])
    nk = np.floor((lhi - llo) / steps).astype(int) + 2
    check_memory(float(np.prod(nk.astype(float))), source, field)  # lattice sites tried
    i, jj, k = np.meshgrid(np.arange(nk[0]), np.arange(nk[1]), np.arange(nk[2]), indexing="ij")
    i, jj, k = i.ravel(), jj.ravel(), k.ravel()
    if kind == "sc":
        loc = np.column_stack([i * a, jj * a, k * a]).astype(np.float64)
    else:
        loc = np.column_stack([a * (i + ((jj + k) % 2) / 2.0),
                               a * math.sqrt(3) / 2 * (jj + (k % 2) / 3.0),
                               a * math.sqrt(6) / 3 * k])
    loc = loc + llo + r_max + j * math.sqrt(3)
    x = origin + loc @ axes
    inside = region.contains(x, np.full(len(x), r_max + j * math.sqrt(3)))
    x, loc = x[inside], loc[inside]
    order = np.lexsort((loc[:, 0], loc[:, 1], loc[:, 2]))
    x = x[order]
    if n is not None:
        if n > len(x):
            raise InputError(source, f"{field}.n", f"at most {len(x)} lattice sites in the "
                             "region", n)
        x = x[: int(n)]
    if j > 0:
        x = x + rng.uniform(-j, j, x.shape)
    radii = np.full(len(x), r_max) if dist is None else dist.sample(len(x), rng)
    return x, radii
