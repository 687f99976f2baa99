"""Measurements on synthetic particle states with known answers: analytic heaps (rounded top,
concave toe), a tilted drum free surface, the avalanche angle of a sawtooth, stress = force /
area."""

import math

import numpy as np
import pytest

from soilcal.dem import measure
from soilcal.errors import InputError


def heap(alpha_deg, R=0.06, r=0.002, cap=0.25, toe=0.85, seed=0, centre=(0.0, 0.0), skew=None):
    """Spheres filling a heap h(rho): cone of slope alpha with a parabolic cap tangent to it
    at rho_c = cap R and an exponential toe h_t exp(-(rho - rho_t) tan(alpha) / h_t) from
    rho_t = toe R (continuous in value and slope).  Columns of spheres on a jittered square
    grid of pitch 2r; the top sphere of each column touches the surface.  ``skew`` gives
    per-direction slopes (alpha varies with azimuth as alpha + skew cos(phi))."""
    rng = np.random.default_rng(seed)
    g = np.arange(-1.4 * R, 1.4 * R, 2 * r)
    X, Y = np.meshgrid(g, g)
    X = X + rng.uniform(-0.2 * r, 0.2 * r, X.shape)
    Y = Y + rng.uniform(-0.2 * r, 0.2 * r, Y.shape)
    rho = np.hypot(X, Y)
    phi = np.arctan2(Y, X)
    a = np.radians(alpha_deg + (skew * np.cos(phi) if skew else 0.0))
    t = np.tan(a)
    rc, rt = cap * R, toe * R
    H0 = R * t
    ht = (R - rt) * t
    cone = (R - rho) * t
    capv = H0 - rc * t / 2 - t * rho**2 / (2 * rc)
    toev = ht * np.exp(-(rho - rt) * t / ht)
    h = np.where(rho < rc, capv, np.where(rho > rt, toev, cone))
    return columns(X + centre[0], Y + centre[1], h, r)


def columns(X, Y, h, r):
    """Columns of spheres of radius r at (X, Y) under the surface h, the top sphere of each
    touching it (none where h < r / 2)."""
    pts = []
    for xx, yy, hh in zip(X.ravel(), Y.ravel(), h.ravel()):
        if hh < 0.5 * r:
            continue
        zt = hh - r
        zs = np.arange(zt, r * 0.99, -2 * r) if zt > r else np.array([max(zt, 0.5 * r)])
        pts += [(xx, yy, z) for z in zs]
    x = np.array(pts)
    return x, np.full(len(x), r)


@pytest.mark.parametrize("alpha", [22.0, 30.0, 38.0])
@pytest.mark.parametrize("method, tol, spread", [
    ("repose_angle_bins", 0.3, 0.5),
    # the probe's surface is the heap's offset by one radius: the same flank slope
    ("repose_angle_surface", 0.1, 0.2),
])
def test_the_flank_angle_of_an_analytic_heap_is_recovered(alpha, method, tol, spread):
    x, r = heap(alpha)
    res = getattr(measure, method)(x, r, 0.0)
    # the rounded top and the toe are excluded: the flank slope is recovered
    assert res["angle_deg"] == pytest.approx(alpha, abs=tol)
    assert len(res["per_direction_deg"]) == 8
    assert res["spread_deg"] < spread


def test_radial_bins_average_directions_and_find_the_axis():
    # slopes alpha + 4 cos(phi): the eight sector fits average back to alpha (cos sums to 0)
    x, r = heap(30.0, skew=4.0, centre=(0.02, -0.01))
    res = measure.repose_angle_bins(x, r, 0.0)
    assert res["centre"][0] == pytest.approx(0.02, abs=0.004)
    assert res["centre"][1] == pytest.approx(-0.01, abs=0.004)
    per = np.array(res["per_direction_deg"])
    assert per[0] > per[4] + 5.0  # +x side steeper than -x side
    assert res["angle_deg"] == pytest.approx(30.0, abs=0.6)


def test_radial_bins_ignore_the_plate_offset():
    x, r = heap(30.0)
    x[:, 2] += 0.1
    assert measure.repose_angle_bins(x, r, 0.1)["angle_deg"] == pytest.approx(30.0, abs=0.3)


def test_too_small_pile_is_refused():
    x = np.array([[0.0, 0.0, 0.002]] * 5)
    with pytest.raises(InputError, match="particles"):
        measure.repose_angle_bins(x, 0.002)


def test_surface_scan_follows_per_direction_slopes():
    # slopes alpha + 4 cos(phi): the +x sector is steeper than the -x sector by about 8 deg
    x, r = heap(30.0, skew=4.0, centre=(0.02, -0.01))
    res = measure.repose_angle_surface(x, r, 0.0)
    per = np.array(res["per_direction_deg"])
    assert per[0] - per[4] == pytest.approx(8.0, abs=1.5)
    assert res["angle_deg"] == pytest.approx(30.0, abs=0.6)


def test_surface_height_map_of_one_sphere():
    # bare caps (probe 0): H = z + sqrt(r^2 - d^2) over the disc, the plate elsewhere
    x = np.array([[0.0, 0.0, 0.01]] * 10)
    X, Y, H = measure.surface_height_map(x, 0.004, 0.0, cell=0.0005, probe=0.0)
    d2 = X**2 + Y**2
    inside = d2 < 0.004**2
    assert H[inside] == pytest.approx(0.01 + np.sqrt(0.004**2 - d2[inside]), abs=1e-12)
    assert np.all(H[~inside] == 0.0)
    # a probe of radius p rides on the sphere inflated by p: its lowest point at the apex
    # is z + r, and it reaches the plate only beyond the inflated disc
    _, _, Hp = measure.surface_height_map(x, 0.004, 0.0, cell=0.0005, probe=0.002)
    assert Hp.max() == pytest.approx(0.014, abs=2e-5)


def test_surface_scan_refuses_a_bad_grid():
    x, r = heap(30.0, R=0.03)
    with pytest.raises(InputError, match="cell"):
        measure.repose_angle_surface(x, r, 0.0, cell=0.0)
    with pytest.raises(InputError, match="probe"):
        measure.repose_angle_surface(x, r, 0.0, probe=-1.0)


@pytest.mark.parametrize("alpha", [25.0, 35.0])
def test_side_silhouette_through_the_photo_pipeline(alpha, tmp_path):
    x, r = heap(alpha, R=0.05)
    res = measure.repose_angle_image(x, r, 0.0)
    assert len(res["flanks_deg"]) == 4
    # the silhouette of discs on a straight flank is the flank offset by the radius
    assert res["angle_deg"] == pytest.approx(alpha, abs=0.6)


def elliptic_heap(A, B, H, r=0.002, cap=0.25, toe=0.85):
    """Spheres filling h = H g(s), s = sqrt((x/A)^2 + (y/B)^2): the cone 1 - s with the
    parabolic cap and exponential toe of :func:`heap`, stretched to an elliptic base.  Seen at
    azimuth theta its outline is H g(|u| / w), w = sqrt(A^2 cos^2 + B^2 sin^2) the ellipse's
    support function: a heap of flank angle atan(H / w(theta))."""
    g = np.arange(-1.4 * A, 1.4 * A, 2 * r)
    X, Y = np.meshgrid(g, g)
    s = np.hypot(X / A, Y / B)
    cone = 1.0 - s
    capv = 1.0 - cap / 2 - s**2 / (2 * cap)
    ht = 1.0 - toe
    toev = ht * np.exp(-(s - toe) / ht)
    h = H * np.where(s < cap, capv, np.where(s > toe, toev, cone))
    return columns(X, Y, h, r)


@pytest.mark.parametrize("views", [2, 8])
def test_silhouette_views_average_the_flanks_over_azimuth(views, tmp_path):
    # an elliptic heap is 30.3 deg steep seen along y and 41.2 deg along x: the views' mean is
    # the mean of atan(H / w(theta)) over their azimuths 180 k / n
    A, B, H = 0.06, 0.04, 0.035
    x, r = elliptic_heap(A, B, H)
    az = np.radians(measure.view_azimuths(views))
    expect = np.degrees(np.arctan(H / np.sqrt(A**2 * np.cos(az) ** 2 + B**2 * np.sin(az) ** 2)))
    res = measure.repose_angle_image(x, r, 0.0, views=views)
    assert len(res["flanks_deg"]) == 2 * views
    assert res["angle_deg"] == pytest.approx(expect.mean(), abs=0.6)
    per_view = np.reshape(res["flanks_deg"], (views, 2)).mean(axis=1)
    assert per_view == pytest.approx(expect, abs=0.8)


def test_two_views_are_the_x_and_y_views(tmp_path):
    x, r = heap(30.0, R=0.04, skew=5.0)
    assert measure.view_azimuths(2) == [0.0, 90.0]
    for az, axis in ((0.0, "y"), (90.0, "x")):
        a, _ = measure.render_side(x, r, 0.0, view=az)
        b, _ = measure.render_side(x, r, 0.0, view=axis)
        assert np.array_equal(a, b)
    assert (measure.repose_angle_image(x, r, 0.0, views=2)
            == measure.repose_angle_image(x, r, 0.0, views=("y", "x")))
    for bad in (0, -1, 2.0, True):
        with pytest.raises(InputError, match="image_views"):
            measure.view_azimuths(bad)


def test_a_silhouette_is_measured_in_memory_on_the_plate_row_it_was_drawn_with(tmp_path):
    from soilcal.imaging.measure import measure_pile, plate_lines

    x, r = heap(30.0, R=0.04, skew=5.0)
    rgb, _ = measure.render_side(x, r, 0.0, view=45.0, path=tmp_path / "v.png")
    same, _, row = measure._render(x, r, 0.0, 45.0)
    assert np.array_equal(rgb, same)
    # the 8-bit image in memory is the PNG read back: the same numbers to the last bit
    disk = measure_pile(tmp_path / "v.png", "otsu", False, "gray")
    mem = measure_pile("<view>", "otsu", False, "gray", image=rgb / 255.0)
    assert (mem.left_deg, mem.right_deg) == (disk.left_deg, disk.right_deg)
    # the drawn plate row lies between the last wall row and the first plate row, where the
    # photo's own plate search finds the plate's top edge (to its half-pixel edge locations)
    assert rgb[int(row - 0.5), 0, 0] > rgb[int(row + 0.5), 0, 0]
    slope, icpt = plate_lines(rgb[..., 0] / 255.0)[0]
    assert abs(slope) < 1e-3 and icpt == pytest.approx(row, abs=1.0)
    given = measure_pile("<view>", "otsu", False, "gray", image=rgb / 255.0, plate=(0.0, row))
    assert given.geometry[:2] == (0.0, row) and given.roll_deg == 0.0
    assert (given.left_deg + given.right_deg) / 2 == pytest.approx(30.0, abs=1.0)


def test_render_side_draws_the_heap_above_a_plate(tmp_path):
    x, r = heap(30.0, R=0.04)
    scale = 5000.0  # px per m, given
    img, s = measure.render_side(x, r, 0.0, view="y", px_per_m=scale, path=tmp_path / "a.png")
    assert (tmp_path / "a.png").is_file() and s == scale
    dark = img[..., 0] < 100
    rows = np.nonzero(dark.any(axis=1))[0]
    # heap height in pixels = max(z + r) * scale (orthographic)
    h_px = rows.max() - rows.min() + 1
    assert h_px == pytest.approx((x[:, 2] + r).max() * scale, abs=3)
    with pytest.raises(InputError, match="view"):
        measure.render_side(x, r, view="z")
    with pytest.raises(InputError, match="view"):
        measure.render_side(x, r, view=float("nan"))


def test_painted_discs_are_scikit_image_discs():
    """The silhouette's disc painter sets exactly the pixels of skimage.draw.disk (clipped to
    the image, nothing at or below the plate row), including discs cut by the border and
    sub-pixel discs."""
    from skimage.draw import disk

    rng = np.random.default_rng(7)
    h, w, stop = 120, 160, 90
    rows = rng.uniform(-10, h + 10, 400)
    cols = rng.uniform(-10, w + 10, 400)
    rad = np.maximum(rng.uniform(0.2, 12, 400), 0.7)
    want = np.full((h, w), 0.5)
    for rc, cc, rr in zip(rows, cols, rad):
        pr, pc = disk((rc, cc), rr, shape=want.shape)
        keep = pr < stop
        want[pr[keep], pc[keep]] = 0.1
    got = np.full((h, w), 0.5)
    measure._paint_disks(got, rows, cols, rad, 0.1, stop)
    assert np.array_equal(got, want)
    assert (got[stop:] == 0.5).all() and (got == 0.1).sum() > 1000


def drum_state(theta_deg, R=0.05, L=0.1, r=0.002, fill=0.25, seed=1):
    """Spheres filling the circular segment below a chord tilted by theta (drum axis along y)
    that holds ``fill`` of the section (A = R^2 acos(d/R) - d sqrt(R^2 - d^2))."""
    from scipy.optimize import brentq

    target = fill * math.pi * R * R
    d = brentq(lambda d: R * R * math.acos(d / R) - d * math.sqrt(R * R - d * d) - target, 0, R)
    rng = np.random.default_rng(seed)
    th = math.radians(theta_deg)
    pts = []
    # columns of spheres every 2 r across the section; the top sphere of each column touches
    # the chord z_s(u) = (u sin(theta) - d) / cos(theta), the lowest stays inside the circle
    for u in np.arange(-R + r, R - r, 2 * r) + rng.uniform(-0.1 * r, 0.1 * r):
        zs = (u * math.sin(th) - d) / math.cos(th)
        zb = -math.sqrt(max(R * R - u * u, 0.0))
        for z in np.arange(zs - r, zb + r, -2 * r):
            if math.hypot(u, z) < R - r:
                pts += [(u, y, z) for y in np.arange(r, L, 2 * r)]
    x = np.array(pts)
    return x, np.full(len(x), r)


@pytest.mark.parametrize("theta", [30.0, 42.7])
def test_drum_surface_angle_of_a_tilted_segment(theta):
    x, r = drum_state(theta)
    res = measure.drum_surface_angle(x, r, (0.0, 0.05, 0.0), (0, 1, 0))
    assert res["angle_deg"] == pytest.approx(theta, abs=0.3)


def test_drum_axis_must_be_horizontal():
    x, r = drum_state(30.0)
    with pytest.raises(InputError, match="axis_dir"):
        measure.drum_surface_angle(x, r, (0, 0.05, 0), (0, 0, 1))


def sawtooth(peaks, trough=30.0, rise_per_frame=2.1, jitter=0.0, seed=0):
    """Frame angles of a slumping drum: each cycle rises by ``rise_per_frame`` degrees per
    frame (7 r/min, 0.05 s) to its peak, from within one step above ``trough``; after the
    peak the next frame starts the next cycle (one-frame collapse), and the series ends on
    the first two frames of a next cycle (``trough`` and one step above, so that the last
    collapse shows on a frame before the last); optional uniform jitter of +-``jitter``
    degrees."""
    a = []
    for p in peaks:
        k = int(math.ceil((p - trough) / rise_per_frame))
        a += list(p - rise_per_frame * np.arange(k, 0, -1)) + [p]
    a += [trough, trough + rise_per_frame]
    a = np.array(a)
    return a + np.random.default_rng(seed).uniform(-jitter, jitter, a.size)


def test_avalanche_angle_is_the_mean_angle_before_collapse():
    """003: "the maximum angle ... before collapse occurs".  Peaks 50, 54, 47 deg on a
    sawtooth with 2 deg of frame jitter: each collapse (21, 26 and 17 deg before the
    jitter) is found, the jitter is
    not, and the angle is the mean of the three peaks (50.33 deg, within the jitter), where
    the time mean of the frames, half-way up each linear rise from the 30 deg trough, is
    about 10 deg lower."""
    a = sawtooth([50.0, 54.0, 47.0], jitter=2.0)
    res = measure.avalanche_angle(a, 10.0)
    assert res["n_avalanches"] == 3
    assert res["angle_deg"] == pytest.approx((50 + 54 + 47) / 3, abs=2.0)
    assert a.mean() < res["angle_deg"] - 8.0
    exact = measure.avalanche_angle(sawtooth([50.0, 54.0, 47.0]), 10.0)
    assert exact["peaks_deg"] == pytest.approx([50.0, 54.0, 47.0], abs=1e-12)


def test_avalanche_angle_ignores_lone_frames():
    """A bed carried up with the drum steepens by about 2.1 deg a frame, so a lone frame
    15 deg above both neighbours (a misfit surface) is no collapse; nor does a lone frame
    15 deg below both make the frame before it one.  The sawtooth's three peaks are found as
    without the outliers, the two outliers are counted, and a two-frame excursion (not a
    lone frame) still counts."""
    clean = sawtooth([50.0, 54.0, 47.0])
    a = clean.copy()
    # mid-rise of the first cycle (29 -> 50 deg) and of the second (28.8 -> 54 deg)
    up, down = 4, 17
    a[up] += 15.0
    a[down] -= 15.0
    naive = find_peaks_count(a, 10.0)
    assert naive == 5  # without the despiking each outlier adds a collapse
    res = measure.avalanche_angle(a, 10.0)
    assert res["n_spikes"] == 2 and res["n_avalanches"] == 3
    assert res["peaks_deg"] == pytest.approx([50.0, 54.0, 47.0], abs=1e-12)
    two = clean.copy()
    two[up:up + 2] += 15.0
    res2 = measure.avalanche_angle(two, 10.0)
    assert res2["n_spikes"] == 0 and clean[up + 1] + 15.0 in res2["peaks_deg"]
    b, n = measure.despike([1.0, 20.0, 2.0, -20.0, 3.0, 3.0], 10.0)
    assert n == 2 and list(b) == [1.0, 2.0, 2.0, 2.0, 3.0, 3.0]  # medians of three
    # a zig-zag of misfits (up, down, up) leaves no new lone frame behind: the first pass
    # gives 30, 30, 50, 30, 30, the second flattens the 50 it made
    b, n = measure.despike([30.0, 50.0, 20.0, 50.0, 30.0], 10.0)
    assert n == 4 and list(b) == [30.0] * 5
    with pytest.raises(InputError, match="jump"):
        measure.despike([1.0, 2.0, 3.0], 0.0)


def find_peaks_count(a, prominence):
    from scipy.signal import find_peaks

    return find_peaks(a, prominence=prominence)[0].size


def test_avalanche_angle_without_collapse_is_the_time_mean():
    """A surface flowing steadily (rolling regime): fluctuations of +-2 deg about 40 deg
    never drop by 10 deg, so no avalanche is counted and the angle is the time mean; a rise
    that ends on the last frame is not seen to collapse and is not counted either."""
    rng = np.random.default_rng(1)
    flat = 40.0 + rng.uniform(-2.0, 2.0, 60)
    res = measure.avalanche_angle(flat, 10.0)
    assert res["n_avalanches"] == 0 and res["angle_deg"] == pytest.approx(flat.mean())
    rising = np.linspace(30.0, 55.0, 12)
    assert measure.avalanche_angle(rising, 10.0)["n_avalanches"] == 0
    # a rise that peaks two frames before the end and dips by 4 deg: no collapse seen
    dip = np.concatenate([rising, [53.0, 51.0]])
    assert measure.avalanche_angle(dip, 10.0)["n_avalanches"] == 0
    # a last frame 12 deg below a rise: prominent for find_peaks, but only the last frame
    # shows the fall (it has one neighbour, so it may be a misfit): no collapse seen
    last = np.concatenate([rising, [rising[-1] - 12.0]])
    assert find_peaks_count(last, 10.0) == 1
    assert measure.avalanche_angle(last, 10.0)["n_avalanches"] == 0
    # the fall shown on the last two frames is a collapse
    fall = np.concatenate([rising, [rising[-1] - 12.0, rising[-1] - 14.0]])
    res = measure.avalanche_angle(fall, 10.0)
    assert res["n_avalanches"] == 1 and res["angle_deg"] == pytest.approx(55.0)
    two = measure.avalanche_angle([40.0, 44.0], 10.0)  # too short to see a collapse
    assert two["n_avalanches"] == 0 and two["angle_deg"] == 42.0
    with pytest.raises(InputError, match="min_drop"):
        measure.avalanche_angle(flat, 0.0)
    with pytest.raises(InputError, match="angles"):
        measure.avalanche_angle([40.0, float("nan"), 41.0], 10.0)


def test_stress_strain_is_force_over_area():
    z = np.array([0.05, 0.049, 0.045])
    f = np.array([0.0, 10.0, 100.0])
    eps, sig = measure.stress_strain(z, f, 0.0495, 0.05)
    assert eps == pytest.approx([0.0, 0.02, 0.1])
    assert sig == pytest.approx(f / (math.pi * 0.0495**2))
    assert measure.value_at(eps, sig, 0.06) == pytest.approx(
        (10 + (100 - 10) * (0.04 / 0.08)) / (math.pi * 0.0495**2))
    assert math.isnan(measure.value_at(eps, sig, 0.5))


def test_silhouette_views_the_pipeline_cannot_measure_are_left_out_and_named(tmp_path, monkeypatch):
    import soilcal.imaging.measure as im

    x, r = heap(30.0, R=0.04)
    real = im.measure_pile
    calls = []

    def failing(bad):
        def fake(path, *a, **kw):
            calls.append(path)
            if len(calls) - 1 in bad:
                raise InputError(path, "left flank", "a flank of at least 20 boundary pixels", 11)
            return real(path, *a, **kw)
        return fake

    all8 = measure.repose_angle_image(x, r, 0.0, views=8)
    assert all8["views_measured"] == 8 and all8["views_failed"] == []
    calls.clear()
    monkeypatch.setattr(im, "measure_pile", failing({1, 5, 6}))
    part = measure.repose_angle_image(x, r, 0.0, views=8)
    assert part["views_measured"] == 5 and len(part["flanks_deg"]) == 10
    assert [v for v, _ in part["views_failed"]] == [22.5, 112.5, 135.0]
    assert "at least 20 boundary pixels, got 11" in part["views_failed"][0][1]
    # the mean of the five views measured, flank by flank
    keep = [k for k in range(8) if k not in (1, 5, 6)]
    assert part["angle_deg"] == pytest.approx(np.mean([all8["flanks_deg"][2 * k + j] for k in keep for j in (0, 1)]))
    # half the views is not enough
    calls.clear()
    monkeypatch.setattr(im, "measure_pile", failing({0, 2, 4, 6}))
    with pytest.raises(InputError, match="more than half of 8 views") as e:
        measure.repose_angle_image(x, r, 0.0, views=8)
    assert e.value.field == "views" and "view 0" in str(e.value.expected)
