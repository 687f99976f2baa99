"""Particle factories: overlap-free insertion, honoured counts/masses/PSDs,
determinism and clear errors."""

import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from soilcal.dem import factories as F
from soilcal.errors import InputError

BOX = F.BoxRegion((0.0, 0.0, 0.0), (0.06, 0.05, 0.04))
CYL = F.CylinderRegion(0.03, -0.02, 0.05, axis_point=(0.1, 0.0, 0.0), axis_dir=(1.0, 1.0, 0.0))


def min_gap(x, r):
    """min over pairs of |xi - xj| - ri - rj (inf for < 2 particles)."""
    if len(x) < 2:
        return math.inf
    pairs = cKDTree(x).query_pairs(3.5 * r.max(), output_type="ndarray")
    if len(pairs) == 0:
        return math.inf
    d = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
    return float((d - r[pairs[:, 0]] - r[pairs[:, 1]]).min())


def vol(r):
    return 4 / 3 * np.pi * np.asarray(r) ** 3


# ---------------------------------------------------------------- distributions


def test_psd_number_fractions_by_hand():
    # radius bins [0.25,0.5], [0.5,1], [1,2] mm with mass 20/50/30 %: number per
    # unit mass ~ f (a^-2 - b^-2)/(b - a) = 0.2*48, 0.5*6, 0.3*0.75 (mm units)
    psd = F.PSD.from_mass_percent([0.5e-3, 1e-3, 2e-3, 4e-3], [20, 50, 30])
    w = np.array([9.6, 3.0, 0.225])
    assert psd.number_fractions() == pytest.approx(w / w.sum())
    assert psd.r_min == 0.25e-3 and psd.r_max == 2e-3
    # discrete sizes: number fractions ~ f / r^3
    d = F.PSD.from_mass_percent([1e-3, 2e-3], [50, 50])
    assert d.number_fractions() == pytest.approx([8 / 9, 1 / 9])
    # number -> mass conversion inverts that
    back = F.PSD.from_number_fractions([0.5e-3, 1e-3], [8 / 9, 1 / 9])
    assert back.mass_fraction == pytest.approx((0.5, 0.5))


def test_mass_is_uniform_in_radius_within_a_bin():
    # mass-weighted mean radius of a bin [a, b] is (a + b)/2 under the model
    psd = F.PSD((1e-3,), (3e-3,), (1.0,))
    r = psd.sample(200_000, np.random.default_rng(0))
    assert r.min() >= 1e-3 and r.max() <= 3e-3
    assert np.average(r, weights=r**3) == pytest.approx(2e-3, rel=3e-3)
    # number-mean volume against the closed form (4/3) pi (b - a)/Z
    z = 0.5 * (1e-3**-2 - 3e-3**-2)
    assert psd.mean_volume() == pytest.approx(4 / 3 * np.pi * 2e-3 / z)
    assert vol(r).mean() == pytest.approx(psd.mean_volume(), rel=0.01)


def test_count_sample_honours_number_fractions_exactly():
    psd = F.PSD.from_mass_percent([1e-3, 2e-3, 4e-3], [30, 40, 30])
    r = psd.sample(1000, np.random.default_rng(1))
    counts = np.array([(r == 0.5e-3).sum(), (r == 1e-3).sum(), (r == 2e-3).sum()])
    nu = psd.number_fractions()
    assert counts.sum() == 1000
    assert np.all(np.abs(counts - 1000 * nu) < 1)  # largest remainder


def test_mass_sample_honours_bin_masses():
    psd = F.PSD.from_mass_percent([0.5e-3, 1e-3, 2e-3, 4e-3], [20, 50, 30])
    rho, M = 2650.0, 0.2
    r = psd.sample_mass(M, rho, np.random.default_rng(2))
    m = rho * vol(r)
    edges = [0.25e-3, 0.5e-3, 1e-3, 2e-3]
    for k, f in enumerate([0.2, 0.5, 0.3]):
        sel = (r >= edges[k]) & (r <= edges[k + 1])
        # each bin within half of its largest particle's mass of M f
        assert abs(m[sel].sum() - M * f) <= 0.5 * rho * vol(edges[k + 1])
    assert m.sum() == pytest.approx(M, rel=0.02)


def test_from_mass_percent_errors_name_field():
    with pytest.raises(InputError, match=r"soil\.yaml: psd\.percent: expected mass percentages"):
        F.PSD.from_mass_percent([1, 2, 3], [50, 30], source="soil.yaml")
    with pytest.raises(InputError, match=r"psd\.sizes"):
        F.PSD.from_mass_percent([0.0, 1e-3, 2e-3], [40, 60])
    with pytest.raises(InputError, match=r"psd\.sizes"):
        F.PSD.from_mass_percent([2e-3, 1e-3, 3e-3], [40, 60])
    with pytest.raises(InputError, match=r"psd\.sizes"):
        F.PSD.from_mass_percent([1e-3, 2e-3, 3e-3, 4e-3, 5e-3], [40, 60])


def test_coarse_graining_scale_by_hand():
    # r = 1 mm spheres, V = 1e-3 m^3, phi = 0.6 -> 0.6e-3 / 4.18879e-9 = 143239
    # particles; at most 1e5 allowed -> s = 1.432394^(1/3) = 1.127252
    d = F.UniformRadius(1e-3, 1e-3)
    s = F.coarse_graining_scale(d, 1e-3, 0.6, 100_000)
    assert s == pytest.approx(1.127252, rel=1e-5)
    assert 0.6e-3 / d.scaled(s).mean_volume() == pytest.approx(100_000)
    assert F.coarse_graining_scale(d, 1e-3, 0.6, 10**7) == 1.0


# ---------------------------------------------------------------- random insertion


@pytest.mark.parametrize("region", [BOX, CYL], ids=["box", "cylinder"])
def test_insert_count_no_overlap_inside(region):
    d = F.UniformRadius(1.0e-3, 2.0e-3)
    n = int(0.25 * region.volume / d.mean_volume())  # ~25 % solid fraction
    x, r = F.insert_random(region, d, n=n, seed=5)
    assert len(r) == n
    assert min_gap(x, r) >= -1e-12
    assert region.contains(x, r).all()
    assert r.min() >= 1.0e-3 and r.max() <= 2.0e-3


def test_cone_region_insertion_fills_the_frustum_uniformly():
    """A frustum of radius 10 mm at z = 0 and 40 mm at z = 60 mm (side slope dR/dz = 1/2),
    tilted: its volume is pi h/3 (a^2 + ab + b^2); every inserted sphere lies at least its
    radius from the side, (R(z) - rho) / sqrt(1 + 1/4), and inside the end planes; the
    centres are spread by volume: the share below mid-height is the accessible (eroded)
    frustum's share, integrated by hand."""
    a, b, h = 0.010, 0.040, 0.060
    axis_point, d = np.array([0.1, 0.0, 0.0]), np.array([0.0, 1.0, 1.0]) / math.sqrt(2)
    cone = F.ConeRegion(a, b, 0.0, h, axis_point=tuple(axis_point), axis_dir=tuple(d))
    assert cone.volume == pytest.approx(math.pi * h / 3 * (a * a + a * b + b * b), rel=1e-12)
    rr = 0.5e-3
    n = int(0.05 * cone.volume / vol(rr))
    x, r = F.insert_random(cone, F.UniformRadius(rr, rr), n=n, seed=3)
    w = x - axis_point
    z = w @ d
    rho = np.linalg.norm(w - np.outer(z, d), axis=1)
    assert len(r) == n and min_gap(x, r) >= -1e-12
    assert (z >= rr - 1e-12).all() and (z <= h - rr + 1e-12).all()
    assert ((a + z / 2 - rho) / math.sqrt(1.25) >= rr - 1e-12).all()
    zz = np.linspace(rr, h - rr, 200_001)
    area = (a + zz / 2 - rr * math.sqrt(1.25)) ** 2  # pi cancels
    low = area[zz <= h / 2].sum() / area.sum()
    assert np.mean(z <= h / 2) == pytest.approx(low, abs=0.015)
    with pytest.raises(ValueError):
        F.ConeRegion(0.01, 0.02, 0.05, 0.05)


def test_insert_mass_and_avoid_existing_particles():
    psd = F.PSD.from_mass_percent([2e-3, 3e-3, 5e-3], [60, 40])
    x0, r0 = F.insert_random(BOX, psd, n=300, seed=1)
    rho, M = 2600.0, 0.05
    x, r = F.insert_random(BOX, psd, mass=M, density=rho, seed=2,
                           existing_positions=x0, existing_radii=r0)
    assert rho * vol(r).sum() == pytest.approx(M, rel=0.03)
    X, R = np.vstack([x0, x]), np.concatenate([r0, r])
    assert min_gap(X, R) >= -1e-12


def test_insert_deterministic_with_seed():
    d = F.UniformRadius(1e-3, 1.5e-3)
    a = F.insert_random(BOX, d, n=500, seed=11)
    b = F.insert_random(BOX, d, n=500, rng=np.random.default_rng(11))
    c = F.insert_random(BOX, d, n=500, seed=12)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(a[0], c[0])


def test_impossible_requests_raise_clear_errors():
    d = F.UniformRadius(2e-3, 2e-3)
    too_many = int(0.5 * BOX.volume / d.mean_volume())  # 50 % > RSA limit
    with pytest.raises(InputError, match=r"pile\.yaml: insertion: expected a solid volume "
                       r"fraction"):
        F.insert_random(BOX, d, n=too_many, seed=0, source="pile.yaml")
    with pytest.raises(InputError, match="diameters below"):
        F.insert_random(BOX, F.UniformRadius(0.03, 0.03), n=1, seed=0)
    with pytest.raises(InputError, match="density"):
        F.insert_random(BOX, d, mass=1.0, seed=0)
    # allowed fraction but the attempts budget runs out -> same error type
    with pytest.raises(InputError, match="only"):
        F.insert_random(BOX, d, n=int(0.34 * BOX.volume / d.mean_volume()), seed=0,
                        max_attempts=5)


# ---------------------------------------------------------------- rate insertion


def test_number_rate_inserter():
    d = F.UniformRadius(1e-3, 1.5e-3)
    ins = F.RateInserter(BOX, d, rate=2500.0, seed=3, t_start=0.01)
    X, R = np.zeros((0, 3)), np.zeros(0)
    dt = 1e-3
    for k in range(1, 61):
        t = k * dt
        assert ins.due(t) == max(0, math.floor(2500.0 * (t - 0.01) + 1e-9)) - len(R)
        x, r = ins.insert(t, X, R)
        X, R = np.vstack([X, x]), np.concatenate([R, r])
    assert len(R) == math.floor(2500 * 0.05 + 1e-9) == 125
    assert ins.pending == 0
    assert min_gap(X, R) >= -1e-12 and BOX.contains(X, R).all()


def test_mass_rate_inserter_and_full_region():
    psd = F.PSD.from_mass_percent([2e-3, 4e-3], [100])
    rho = 2000.0
    ins = F.RateInserter(BOX, psd, rate=0.5, basis="mass", density=rho, seed=4)
    X, R = np.zeros((0, 3)), np.zeros(0)
    m_big = rho * vol(2e-3)
    for k in range(1, 21):
        t = k * 1e-3
        x, r = ins.insert(t, X, R)
        X, R = np.vstack([X, x]), np.concatenate([R, r])
        assert abs(rho * vol(R).sum() - 0.5 * t) <= 0.5 * m_big
    # a tiny region fills up: the rest stays pending, nothing overlaps
    small = F.BoxRegion((0, 0, 0), (0.01, 0.01, 0.01))
    full = F.RateInserter(small, F.UniformRadius(1.5e-3, 1.5e-3), rate=1e6, seed=5,
                          max_attempts=300)
    x, r = full.insert(1e-3)
    assert full.pending > 0 and len(r) + full.pending == 1000
    assert min_gap(x, r) >= -1e-12


# ---------------------------------------------------------------- lattices


def test_simple_cubic_site_count_exact():
    r, a, m = 1e-3, 2.5e-3, 4
    L = 2 * r + m * a
    box = F.BoxRegion((0, 0, 0), (L, L, L))
    x, rad = F.lattice_fill(box, radius=r, kind="sc", spacing=a)
    assert len(x) == (m + 1) ** 3
    assert min_gap(x, rad) == pytest.approx(a - 2 * r)


def test_hcp_has_twelve_neighbours_at_spacing():
    r, a = 1e-3, 2e-3
    box = F.BoxRegion((0, 0, 0), (0.02, 0.02, 0.02))
    x, rad = F.lattice_fill(box, radius=r, kind="hcp", spacing=a)
    tree = cKDTree(x)
    counts = np.array([len(c) - 1 for c in tree.query_ball_point(x, a * (1 + 1e-9))])
    assert counts.max() == 12  # close packing coordination number
    assert min_gap(x, rad) == pytest.approx(0.0, abs=1e-12)
    interior = np.all((x > 0.005) & (x < 0.015), axis=1)
    assert np.all(counts[interior] == 12)
    # close-packed layers are a sqrt(6)/3 apart
    layers = np.unique(np.round(x[:, 2] / 1e-12) * 1e-12)
    assert np.diff(layers) == pytest.approx(a * math.sqrt(6) / 3)


def test_lattice_jitter_psd_cylinder_and_count():
    psd = F.PSD.from_mass_percent([1e-3, 2e-3, 3e-3], [50, 50])
    x, r = F.lattice_fill(CYL, dist=psd, kind="hcp", jitter=1.0, seed=7)
    assert min_gap(x, r) >= -1e-12 and CYL.contains(x, r).all()
    x2, r2 = F.lattice_fill(CYL, dist=psd, kind="hcp", jitter=1.0, seed=7)
    assert np.array_equal(x, x2) and np.array_equal(r, r2)
    x3, _ = F.lattice_fill(BOX, radius=1e-3, kind="sc", n=50)
    assert len(x3) == 50 and x3[:, 2].max() <= F.lattice_fill(BOX, radius=1e-3, kind="sc")[0][
        50:, 2].min()
    with pytest.raises(InputError, match="lattice.spacing"):
        F.lattice_fill(BOX, radius=1e-3, spacing=1.5e-3)
    with pytest.raises(InputError, match="lattice.n"):
        F.lattice_fill(BOX, radius=1e-3, n=10**7)


def test_samples_beyond_the_available_memory_are_refused(monkeypatch):
    from soilcal.dem import state

    # 1.1 MB available: 600 spheres of BYTES_PER_PARTICLE (2,064 bytes) do not fit
    monkeypatch.setattr(state, "available_memory", lambda: 1_100_000)
    assert state.BYTES_PER_PARTICLE * 600 > 1_100_000 > state.BYTES_PER_PARTICLE * 500
    with pytest.raises(InputError, match=r"fill\.n: expected a particle count whose engine"):
        F.insert_random(BOX, F.UniformRadius(1e-3, 1e-3), n=600, seed=1, source="s",
                      field="fill")
    x, _ = F.insert_random(BOX, F.UniformRadius(1e-3, 1e-3), n=500, seed=1)
    assert len(x) == 500
    # by mass: 600 spheres' worth of 1 mm spheres at 1000 kg/m^3
    m1 = 1000.0 * 4.0 / 3.0 * math.pi * 1e-9
    with pytest.raises(InputError, match=r"fill\.mass: expected a particle count"):
        F.insert_random(BOX, F.UniformRadius(1e-3, 1e-3), mass=600 * m1, density=1000.0,
                      seed=1, source="s", field="fill")
    with pytest.raises(InputError, match=r"lattice: expected a particle count"):
        F.lattice_fill(F.BoxRegion((0, 0, 0), (0.1, 0.1, 0.1)), radius=1e-3, source="s")


def test_splitting_a_volume_into_n_spheres():
    """n spheres of radii uniform on [0.9, 1.1] r have mean volume 4/3 pi 1.01 r^3
    (<r^3> = r^3 (1.1^4 - 0.9^4) / 0.8), so they fill V exactly on average; a count below
    one or a volume <= 0 is refused."""
    d = F.UniformRadius.splitting(1e-4, 1000)
    r = 0.5 * (d.r_min + d.r_max)
    assert d.r_min == pytest.approx(0.9 * r) and d.r_max == pytest.approx(1.1 * r)
    assert 1000 * 4 / 3 * math.pi * 1.01 * r ** 3 == pytest.approx(1e-4, rel=1e-12)
    for n, v in ((0, 1e-4), (-5, 1e-4), (2.5, 1e-4), (10, 0.0), (10, -1.0)):
        with pytest.raises(ValueError):
            F.UniformRadius.splitting(v, n)
