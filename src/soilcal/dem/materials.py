"""Materials, per-pair contact parameter tables and the DEM time step.

Effective (pair) properties, as defined in the EDEM Theory Reference Guide (Hertz-Mindlin
with no slip) and in LIGGGHTS ``model hertz``/``tangential history``::

    1/E* = (1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j
    1/G* = (2 - nu_i)/G_i + (2 - nu_j)/G_j,        G = E / (2 (1 + nu))
    1/R* = 1/R_i + 1/R_j,  1/m* = 1/m_i + 1/m_j
    beta = ln(e) / sqrt(ln(e)^2 + pi^2)             (e: coefficient of restitution)

Rayleigh time step (EDEM guide; Li, Xu & Thornton 2005, Powder Technol. 160:219)::

    T_R = pi R sqrt(rho / G) / (0.1631 nu + 0.8766)

evaluated for the smallest particle of each material, the minimum over materials is used.
A time step above T_R is rejected as unstable (EDEM recommends 20-40 % of T_R).

JKR bound.  T_R follows from Hertz contacts, whose stiffness S_n = 2 E* a vanishes at zero
load; a JKR contact at zero load already has the contact radius
a_0 = (9 pi w R*^2 / (2 E*))^(1/3) (contact.py; about 0.12 r for the soils here), so a bed
held together by cohesion is much stiffer than a Hertz bed under its weight.  The critical
step of the central-difference scheme for a 3-D packing with rotations is
0.17 sqrt(m / k) (O'Sullivan & Bray 2004, Eng. Comput. 21:278, their 3-D result with
rotational degrees of freedom); with k = 2 E* a_0 (the larger of the normal and Mindlin
tangential stiffness there) and m the smaller mass of the pair::

    dt_JKR = 0.17 sqrt(m / (2 E* a_0))

A requested step above dt_JKR is rejected; a step from ``dt_fraction`` is capped at it
(the run records the step used).  At 30 % of T_R a JKR bed whose dt_JKR is below that step
keeps jittering at about 1 cm/s and never comes to rest.

Damping bound.  The viscoelastic damping of contact.py is a dashpot c = 2 sqrt(5/6) |beta|
sqrt(S m*) on each spring S.  For a linear oscillator of frequency w and damping ratio z,
integrated as the engine does (velocity Verlet, the damping force from the half-step
velocity), the step is stable for

    w dt < 2 (sqrt(1 + z^2) - z)                (= 2 without damping)

The stiffest damped mode of a contact is the tangential one while it sticks: the Mindlin
spring S_t = 8 G* sqrt(R* delta) acts on the relative slip of the contact point, whose
effective mass with the rotation of two solid spheres is m_t = 2/7 m* (1/m_t = 1/m* +
r_i^2/I_i + r_j^2/I_j), while the dashpot is sized with m* (EDEM, LIGGGHTS), so

    w_t = sqrt(S_t / m_t),   z_t = sqrt(5/6) |beta| sqrt(m* / m_t) = sqrt(35/12) |beta|
    w_n = sqrt(S_n / m*),    z_n = sqrt(5/6) |beta|,    S_n = 2 E* sqrt(R* delta)

Evaluated at the largest overlap a run accepts (delta = ``max_overlap`` r, the blow-up
stop), with the smallest sphere of each material, for particle-particle pairs (R* = r/2,
m* = m/2) and particle-wall pairs with the walls' materials (R* = r, m* = m; a sphere on a
stiff wall has a tangential mode 2^(1/4) times stiffer than on a sphere), the smallest step
over the modes is ``damping_dt``; the tangential mode counts only with friction (mu_s > 0).
With the ``viscous_radius`` damping (contact.py: the dashpot eta m* a, LAMMPS's
``viscoelastic``) the normal mode's ratio is z_n = eta m* a / (2 sqrt(S_n m*)), largest at the
largest contact radius, so it is taken at the same overlap.
The ``eepa`` normal law (contact.py) unloads along a spring 1/(1 - lambda_p) times stiffer
than the Hertz one it loads on, so its normal mode is taken with S_n / (1 - lambda_p) and the
Hertz damping ratio (conservative: the same dashpot on a stiffer spring damps less).
In units of the Rayleigh time it does not depend on the shear modulus or the size
(w dt ~ (delta / r)^(1/4)); at max_overlap 0.3 and Poisson 0.33 it is 0.476 (2 (sqrt(1 +
z_t^2) - z_t)) T_R: 0.32 T_R for e = 0.45, 0.21 T_R for e = 0.15.  Heavy damping
(low restitution) thus lowers the stable step: a 990-sphere heap (G 5e5 Pa, mu_s 1.16,
100 mm tube, steel tube and plate with e 0.65, mu_s 0.8) blew up above about 0.18 / 0.25 /
0.32 / 0.43 T_R for e = 0.15 / 0.3 / 0.45 / 0.75, which is 0.84 / 0.94 / 1.0 / 1.34 times
this bound (the last one set by the steel walls, which the bound overrates there).  With
friction on a steel wall, 0.7 times the bound is below 30 % of T_R even at e = 1 (0.28
T_R), so the quick step of any scenario with steel walls is set by this cap.  A requested
step above ``damping_dt`` is rejected; a step from ``dt_fraction`` is capped at
``DAMPING_DT_SAFETY`` (0.7) times it.

Stiffness scaling (Lommen, Schott & Lodewijks 2014, Particuology 12:107; shear modulus
reduced to ``G_mod`` keeps cohesion comparable, e.g. Thakur et al. 2014, Powder Technol.
254:28, via the JKR scaling of the surface energy)::

    gamma_mod = gamma (G_mod / G)^(2/5)

Coarse graining (particles scaled by factor ``s``, material properties unchanged, as in
Bierwisch et al. 2009, J. Mech. Phys. Solids 57:10) is applied to radii by
:class:`soilcal.dem.engine.Simulation`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from soilcal.errors import InputError

# Columns of the per-pair parameter table ``pair[mi, mj, :]``.
P_ESTAR, P_GSTAR, P_BETA, P_MUS, P_MUR, P_W, P_TRATIO, P_JKRK, P_JKRC, P_ETA, P_PLAS, P_NCOL = range(12)


def _num(v, name, src):
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise InputError(src, name, "a number", v) from None
    if not math.isfinite(x):
        raise InputError(src, name, "a finite number", v)
    return x


@dataclass
class Material:
    """Bulk material: density [kg/m^3], Poisson ratio and Young's E or shear G [Pa]."""

    name: str
    density: float
    poisson: float
    youngs: float | None = None
    shear: float | None = None
    source: str = "<input>"

    def __post_init__(self):
        src = self.source
        self.density = _num(self.density, f"materials.{self.name}.density", src)
        self.poisson = _num(self.poisson, f"materials.{self.name}.poisson", src)
        if self.density <= 0:
            raise InputError(src, f"materials.{self.name}.density", "> 0 kg/m^3", self.density)
        if not (-1.0 < self.poisson < 0.5):
            raise InputError(src, f"materials.{self.name}.poisson", "in (-1, 0.5)", self.poisson)
        if self.youngs is None and self.shear is None:
            raise InputError(src, f"materials.{self.name}", "youngs (E) or shear (G) modulus", None)
        if self.shear is not None:
            self.shear = _num(self.shear, f"materials.{self.name}.shear", src)
            if self.shear <= 0:
                raise InputError(src, f"materials.{self.name}.shear", "G > 0 Pa", self.shear)
            e_from_g = 2.0 * self.shear * (1.0 + self.poisson)
            if self.youngs is not None:
                self.youngs = _num(self.youngs, f"materials.{self.name}.youngs", src)
                if abs(self.youngs - e_from_g) > 1e-6 * e_from_g:
                    raise InputError(src, f"materials.{self.name}.youngs",
                                     f"consistent with G and nu (E = 2G(1+nu) = {e_from_g:g})",
                                     self.youngs)
            self.youngs = e_from_g
        else:
            self.youngs = _num(self.youngs, f"materials.{self.name}.youngs", src)
            if self.youngs <= 0:
                raise InputError(src, f"materials.{self.name}.youngs", "E > 0 Pa", self.youngs)
            self.shear = self.youngs / (2.0 * (1.0 + self.poisson))


@dataclass
class PairParams:
    """Contact parameters of one material pair."""

    restitution: float
    friction: float
    rolling_friction: float = 0.0
    surface_energy: float = 0.0  # J/m^2, meaning set by the JKR convention (contact.py)
    plasticity: float = 0.0  # contact plasticity ratio lambda_p of the ``eepa`` normal law


def restitution_beta(e: float) -> float:
    """beta = ln e / sqrt(ln^2 e + pi^2) (EDEM / LIGGGHTS damping coefficient, <= 0)."""
    le = math.log(e)
    return le / math.sqrt(le * le + math.pi * math.pi)


JKR_DT_COEFF = 0.17  # O'Sullivan & Bray 2004: 3-D, with rotation


def jkr_zero_load_radius(estar: float, w: float, rstar: float) -> float:
    """JKR contact radius at zero load, a_0 = (9 pi w R*^2 / (2 E*))^(1/3) [m]."""
    return (9.0 * math.pi * w * rstar * rstar / (2.0 * estar)) ** (1.0 / 3.0)


def jkr_critical_dt(mass: float, estar: float, w: float, rstar: float) -> float:
    """dt_JKR = 0.17 sqrt(m / (2 E* a_0)) (module docstring); inf without adhesion."""
    if w <= 0.0:
        return math.inf
    return JKR_DT_COEFF * math.sqrt(mass / (2.0 * estar * jkr_zero_load_radius(estar, w, rstar)))


#: fraction of :meth:`MaterialTable.damping_dt` a step from ``dt_fraction`` is capped at
#: (module docstring: measured blow-ups at 0.84-1.34 times the bound)
DAMPING_DT_SAFETY = 0.7
TANGENTIAL_MASS = 2.0 / 7.0  # m_t / m* for solid spheres with rotation


def damped_critical_dt(stiffness: float, mass: float, zeta: float) -> float:
    """2 (sqrt(1 + z^2) - z) / w with w = sqrt(stiffness / mass): the stable step of a
    damped oscillator under velocity Verlet with half-step-velocity damping."""
    return 2.0 * (math.sqrt(1.0 + zeta * zeta) - zeta) / math.sqrt(stiffness / mass)


def rayleigh_time(radius: float, density: float, shear: float, poisson: float) -> float:
    """T_R = pi R sqrt(rho/G) / (0.1631 nu + 0.8766)."""
    return math.pi * radius * math.sqrt(density / shear) / (0.1631 * poisson + 0.8766)


@dataclass
class MaterialTable:
    """Materials and per-pair parameters; builds the numeric table used by the kernels."""

    materials: list[Material] = field(default_factory=list)
    pairs: dict[tuple[int, int], PairParams] = field(default_factory=dict)
    shear_mod: float | None = None  # stiffness scaling: G_mod applied to every material
    source: str = "<input>"

    def add(self, mat: Material) -> int:
        if any(m.name == mat.name for m in self.materials):
            raise InputError(self.source, f"materials.{mat.name}", "a unique material name", mat.name)
        self.materials.append(mat)
        return len(self.materials) - 1

    def index(self, name_or_id) -> int:
        if isinstance(name_or_id, (int, np.integer)):
            if not 0 <= int(name_or_id) < len(self.materials):
                raise InputError(self.source, "material", f"an index < {len(self.materials)}", name_or_id)
            return int(name_or_id)
        for k, m in enumerate(self.materials):
            if m.name == name_or_id:
                return k
        raise InputError(self.source, "material", f"one of {[m.name for m in self.materials]}", name_or_id)

    def set_pair(self, a, b, restitution, friction, rolling_friction=0.0, surface_energy=0.0,
                 plasticity=0.0):
        i, j = self.index(a), self.index(b)
        na, nb = self.materials[i].name, self.materials[j].name
        f = f"interactions.{na}-{nb}"
        e = _num(restitution, f + ".restitution", self.source)
        if not (0.0 < e <= 1.0):
            raise InputError(self.source, f + ".restitution", "a coefficient of restitution in (0, 1]", e)
        mu = _num(friction, f + ".friction", self.source)
        if mu < 0:
            raise InputError(self.source, f + ".friction", "sliding friction >= 0", mu)
        mur = _num(rolling_friction, f + ".rolling_friction", self.source)
        if mur < 0:
            raise InputError(self.source, f + ".rolling_friction", "rolling friction >= 0", mur)
        g = _num(surface_energy, f + ".surface_energy", self.source)
        if g < 0:
            raise InputError(self.source, f + ".surface_energy", "surface energy >= 0 J/m^2", g)
        lp = _num(plasticity, f + ".plasticity", self.source)
        if not 0.0 <= lp < 1.0:
            raise InputError(self.source, f + ".plasticity", "a contact plasticity ratio in [0, 1)",
                             lp)
        p = PairParams(e, mu, mur, g, lp)
        self.pairs[(i, j)] = p
        self.pairs[(j, i)] = p

    def effective_shear(self, k: int) -> float:
        return self.shear_mod if self.shear_mod is not None else self.materials[k].shear

    def table(self, jkr_w_factor: float, damping_eta: float | None = None) -> np.ndarray:
        """pair[M, M, P_NCOL] float64: E*, G*, beta, mu_s, mu_r, w (work of adhesion),
        sqrt(4 G*/E*) (ratio of tangential to normal damping), (27/64) pi^2 w^2 / E*^2 (JKR
        separation: delta_c^3 = -that * R*), c = sqrt(2 pi w / E*) (JKR, see contact.py),
        eta (the ``viscous_radius`` damping coefficient, 1/(m s); 0 for the others), the
        contact plasticity ratio lambda_p (the ``eepa`` normal law, contact.py).

        ``jkr_w_factor`` converts the input surface energy to the work of adhesion w used by
        the kernel (1 for the EDEM convention, 2 for the LAMMPS convention, see contact.py).
        ``damping_eta`` is the ``viscous_radius`` coefficient (the same for every pair); with
        it the restitution's beta is not used and its column is 0.
        With stiffness scaling the surface energy is scaled by (G_mod/G)^(2/5), with G the
        harmonic mean-like pair value 1/G* of the unscaled materials.
        """
        nm = len(self.materials)
        if nm == 0:
            raise InputError(self.source, "materials", "at least one material", None)
        if self.shear_mod is not None and self.shear_mod <= 0:
            raise InputError(self.source, "shear_mod", "G_mod > 0 Pa", self.shear_mod)
        out = np.zeros((nm, nm, P_NCOL))
        for i in range(nm):
            for j in range(nm):
                if (i, j) not in self.pairs:
                    raise InputError(self.source,
                                     f"interactions.{self.materials[i].name}-{self.materials[j].name}",
                                     "contact parameters for every material pair", None)
                mi, mj = self.materials[i], self.materials[j]
                p = self.pairs[(i, j)]
                gi, gj = self.effective_shear(i), self.effective_shear(j)
                ei, ej = 2 * gi * (1 + mi.poisson), 2 * gj * (1 + mj.poisson)
                estar = 1.0 / ((1 - mi.poisson**2) / ei + (1 - mj.poisson**2) / ej)
                gstar = 1.0 / ((2 - mi.poisson) / gi + (2 - mj.poisson) / gj)
                gamma = p.surface_energy
                if self.shear_mod is not None and gamma > 0:
                    g0 = 1.0 / ((2 - mi.poisson) / mi.shear + (2 - mj.poisson) / mj.shear)
                    gamma = gamma * (gstar / g0) ** 0.4
                beta = restitution_beta(p.restitution) if damping_eta is None else 0.0
                out[i, j] = (estar, gstar, beta, p.friction,
                             p.rolling_friction, jkr_w_factor * gamma,
                             math.sqrt(4.0 * gstar / estar),
                             27.0 / 64.0 * math.pi**2 * (jkr_w_factor * gamma / estar) ** 2,
                             math.sqrt(2.0 * math.pi * jkr_w_factor * gamma / estar),
                             float(damping_eta or 0.0), p.plasticity)
        return out

    def jkr_dt(self, rmin_per_material: dict[int, float], tab: np.ndarray) -> float:
        """Smallest dt_JKR over the pairs with adhesion of the pair table ``tab`` (from
        :meth:`table`): particle-particle pairs of the materials present (R* and the mass
        from the smallest sphere of each), and particle-wall pairs with any material
        (R* = r)."""
        t = math.inf
        for a, ra in rmin_per_material.items():
            ma = self.materials[a].density * 4.0 / 3.0 * math.pi * ra**3
            for b in range(len(self.materials)):
                w = tab[a, b, P_W]
                if w <= 0.0:
                    continue
                if b in rmin_per_material:
                    rb = rmin_per_material[b]
                    mb = self.materials[b].density * 4.0 / 3.0 * math.pi * rb**3
                    rstar, m = ra * rb / (ra + rb), min(ma, mb)
                    t = min(t, jkr_critical_dt(m, tab[a, b, P_ESTAR], w, rstar))
                # the same material can also be a wall's (a steel tube, a soil plate)
                t = min(t, jkr_critical_dt(ma, tab[a, b, P_ESTAR], w, ra))
        return t

    def damping_dt(self, rmin_per_material: dict[int, float], tab: np.ndarray,
                   max_overlap: float, wall_materials=None) -> float:
        """Smallest damped-mode step (module docstring, "Damping bound") over the contacts
        of the pair table ``tab``: particle-particle pairs of each material present with
        itself and with the others (smallest spheres), particle-wall pairs with every
        material (or of ``wall_materials`` only); at the overlap ``max_overlap`` x the
        smaller radius."""
        t = math.inf
        mats = sorted(rmin_per_material)
        for a in mats:
            ra = rmin_per_material[a]
            ma = self.materials[a].density * 4.0 / 3.0 * math.pi * ra**3
            for b in range(len(self.materials)):
                walls = wall_materials is None or b in wall_materials
                cases = [(ra, ma, ra)] if walls else []  # wall of material b: R* = r, m* = m
                if b in rmin_per_material:
                    rb = rmin_per_material[b]
                    mb = self.materials[b].density * 4.0 / 3.0 * math.pi * rb**3
                    cases.append((ra * rb / (ra + rb), ma * mb / (ma + mb), min(ra, rb)))
                for rstar, mstar, r in cases:
                    root = math.sqrt(rstar * max_overlap * r)
                    # damping ratio of the normal mode: sqrt(5/6) |beta| (viscoelastic), or
                    # eta m* a / (2 sqrt(S_n m*)) (viscous_radius, contact.py) at a = root
                    z = (math.sqrt(5.0 / 6.0) * abs(tab[a, b, P_BETA])
                         + tab[a, b, P_ETA] * mstar * root
                         / (2.0 * math.sqrt(2.0 * tab[a, b, P_ESTAR] * root * mstar)))
                    # the ``eepa`` law unloads 1/(1 - lambda_p) times stiffer (contact.py)
                    t = min(t, damped_critical_dt(2.0 * tab[a, b, P_ESTAR] * root
                                                  / (1.0 - tab[a, b, P_PLAS]), mstar, z))
                    if tab[a, b, P_MUS] > 0.0:
                        t = min(t, damped_critical_dt(8.0 * tab[a, b, P_GSTAR] * root,
                                                      TANGENTIAL_MASS * mstar,
                                                      z / math.sqrt(TANGENTIAL_MASS)))
        return t

    def rayleigh_dt(self, rmin_per_material: dict[int, float]) -> float:
        """Minimum Rayleigh time over materials present (radius = smallest of each)."""
        t = math.inf
        for k, rmin in rmin_per_material.items():
            m = self.materials[k]
            t = min(t, rayleigh_time(rmin, m.density, self.effective_shear(k), m.poisson))
        return t
