"""Angle and profile measurement from photos (scikit-image).

Pile (stacking / repose angle), as in 001 Sec. 2.2.1 and 002 Sec. 2.4: grayscale ->
threshold (global Otsu or adaptive ``threshold_local``) -> morphological opening, hole filling
-> the connected component standing on the plate -> boundary -> straight-line fit of each
flank -> angle = atan(slope).  Here the reference is the plate line itself, found by a Hough
transform of the Canny edges (near-horizontal lines) and refined by a RANSAC line fit, so a
rolled camera does not bias the angle: the image is rotated by the plate's tilt before the
flanks are read.  Each flank is fitted with RANSAC (``skimage.measure.ransac`` with
``LineModelND``) between 20 % and 75 % of the heap height (top cap and toe excluded):

    alpha = atan(|d_v| / |d_u|)     (d = fitted line direction in the plate frame)

Photo value = (alpha_L + alpha_R) / 2; several views are averaged over all flanks, spread =
sample standard deviation of the flank angles.

Drum (dynamic angle, 003 Sec. 2): see :mod:`soilcal.imaging.drum` (photos of a drum on its
stand and frames exported by drum testers, by one method).

Furrow (000 Sec. 2.1/3.1): the profile-meter beam (dark bar of known length L) gives the
scale s = length_px / L, the horizontal direction and the origin (beam centre, x = 0); the soil
top boundary below it gives z(x) = datum - depth, fitted with a polynomial of selectable
degree (``numpy.polynomial.Polynomial.fit``), area = integral over the span of
(chord - z(x)) dx.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np
from scipy import ndimage as ndi
from skimage import color, feature, filters, measure, morphology, transform

from soilcal.errors import InputError
from soilcal.imaging.io import read_photo
from soilcal.imaging.refusal import Tried, explained

BAND = (0.20, 0.75)


@dataclass
class Stages:
    """Intermediate images kept for the figures."""

    rgb: np.ndarray
    gray: np.ndarray
    binary: np.ndarray
    level: np.ndarray | None = None  # levelled (roll-corrected) object mask
    lines: list = field(default_factory=list)  # (u0, v0, du, dv, label) in levelled pixel frame
    points: list = field(default_factory=list)
    plate_row: float | None = None  # row of the plate line in the levelled image
    circle: tuple | None = None  # (col, row, radius) of the masked drum
    reference: str = "levelled to plate"


@dataclass
class PileResult:
    path: str
    angle_deg: float
    left_deg: float
    right_deg: float
    spread_deg: float
    roll_deg: float
    cue: str = "gray/dark"  # segmentation channel / heap darker or lighter than the wall
    flank_points_used: float = 1.0  # smaller flank's share of band points on its fitted line
    flank_rms_px: float = 0.0  # larger flank's RMS distance of those points from the line
    confidence: str = "ok"  # "low": under 60 % of a flank used, RMS above 2.5 px, flanks > 12 deg apart
    # or a second cue's flanks more than CUE_AGREEMENT_DEG away
    stages: Stages | None = None
    cue_check: str = ""  # the second cue that measured the heap (cue search only), "" if none did
    cue_check_deg: float = float("nan")  # the larger of its two flanks' differences from this result

    def as_dict(self):
        d = asdict(self)
        d.pop("stages")
        return d


def _smoothed_lab(rgb):
    return color.rgb2lab(filters.gaussian(rgb, 1.2, channel_axis=-1))


def _grays(rgb, channels, lum=None):
    """``_gray`` of each channel; the smoothed L*a*b* image is converted once for both of its
    cues, and ``lum`` (the "gray" channel, already computed) is reused."""
    lab = _smoothed_lab(rgb) if {"lab_a", "lab_b"} <= set(channels) else None
    return {ch: lum if ch == "gray" and lum is not None else _gray(rgb, ch, lab) for ch in channels}


def _gray(rgb, channel="gray", lab=None):
    """Smoothed single channel in which soil is darker than its surroundings (``lab``: the
    smoothed L*a*b* image, where the caller has it).

    "gray": luminance (rgb2gray).  "chroma": 1 - (R - B) / (R + G + B) scaled to [0, 1], the
    hue contrast of brown soil against grey/dark backgrounds, independent of shading.
    """
    if channel == "gray":
        return filters.gaussian(color.rgb2gray(rgb), 1.2)
    if channel == "chroma":
        rgb = filters.gaussian(rgb, 1.5, channel_axis=-1)
        c = (rgb[..., 0] - rgb[..., 2]) / (rgb.sum(-1) + 0.05)
        return np.clip(0.5 - 2.0 * c, 0, 1)
    if channel in ("lab_a", "lab_b"):
        if lab is None:
            lab = _smoothed_lab(rgb)
        return np.clip((lab[..., 1 if channel == "lab_a" else 2] + 100.0) / 200.0, 0, 1)
    if channel == "saturation":
        return filters.gaussian(color.rgb2hsv(rgb)[..., 1], 1.2)
    raise InputError(None, "channel", "'gray', 'chroma' or 'auto'", channel)


CUES = ("gray", "chroma", "lab_a", "lab_b", "saturation")
MIN_CUE_ETA = 0.75
FLANK_RANGE = (10.0, 65.0)  # flank angles a heap of soil can stand at


def _eta(values):
    """Otsu's separability s_b^2 / s_T^2 of a sample split at its Otsu threshold."""
    t = filters.threshold_otsu(values)
    lo, hi = values[values < t], values[values >= t]
    if not lo.size or not hi.size:
        return 0.0
    return float(lo.size * hi.size / values.size ** 2 * (hi.mean() - lo.mean()) ** 2 / (values.var() + 1e-12))


def colour_edges(rgb, sigma=1.5):
    """Canny edges of the L*, a* and b* channels, united: a plate edge that differs from the
    wall in hue but not in brightness still shows."""
    lab = color.rgb2lab(rgb)
    out = np.zeros(rgb.shape[:2], bool)
    for k in range(3):
        ch = lab[..., k]
        lo, hi = np.percentile(ch, [1, 99])
        if hi - lo > 1e-6:
            out |= feature.canny(np.clip((ch - lo) / (hi - lo), 0, 1), sigma=sigma)
    return out


def _binary(path, gray, method, classes=2):
    if method == "otsu":
        t = filters.threshold_otsu(gray) if classes == 2 else filters.threshold_multiotsu(gray, classes)[-1]
        dark = gray < t
    elif method == "adaptive":
        block = 2 * (min(gray.shape) // 4) + 1  # larger than the object, so its inside is not split
        dark = gray < filters.threshold_local(gray, block, offset=0.02)
    else:
        raise InputError(path, "threshold", "'otsu' or 'adaptive'", method)
    dark = morphology.opening(dark, morphology.disk(2))
    return ndi.binary_fill_holes(dark)


def plate_line(path, gray, binary):
    """(slope, intercept) of the plate's top edge, row = slope * col + intercept."""
    edges = feature.canny(gray, sigma=1.5)
    h, w = gray.shape
    thetas = np.radians(np.linspace(84, 96, 241))
    hs, ang, dist = transform.hough_line(edges, theta=thetas)
    _, angs, dists = transform.hough_line_peaks(hs, ang, dist, num_peaks=12, min_distance=4,
                                                threshold=0.2 * w)
    best, best_score = None, 0
    cols = np.arange(w)
    for a, d in zip(angs, dists):
        rows = (d - cols * np.cos(a)) / np.sin(a)
        ri = np.round(rows).astype(int)
        ok = (ri > 8) & (ri < h - 8)
        above = binary[ri[ok] - 5, cols[ok]]
        below = binary[ri[ok] + 4, cols[ok]]
        score = np.sum(above & ~below)
        if score > best_score:
            best, best_score = (a, d), score
    if best is None or best_score < 0.05 * w:
        raise InputError(path, "image", "a heap standing on a straight plate edge", "no plate line with soil on it")
    a, d = best
    rows = (d - cols * np.cos(a)) / np.sin(a)
    er, ec = np.nonzero(edges)
    near = np.abs(er - rows[ec]) < 3
    pts = np.column_stack([ec[near], er[near]]).astype(float)
    model, _ = measure.ransac(pts, measure.LineModelND, min_samples=2, residual_threshold=1.0,
                              max_trials=200, rng=0)
    (c0, r0), (dc, dr) = model.origin, model.direction
    slope = dr / dc
    return slope, r0 - slope * c0


def _level(mask, slope, intercept):
    """Rotate so the plate line is horizontal; returns (levelled float mask, plate row, roll).

    roll is the camera roll, counter-clockwise positive (the plate appears rotated by it).
    """
    roll = np.degrees(np.arctan(slope))
    h, w = mask.shape
    lev = transform.rotate(np.asarray(mask, float), roll, order=1, center=(w / 2 - 0.5, h / 2 - 0.5))
    # plate row after rotation: the plate point under the image centre
    row_c = slope * (w / 2 - 0.5) + intercept
    ang = np.arctan(slope)
    # distance along the image vertical from centre, after rotation by -ang around the centre
    plate_row = (h / 2 - 0.5) + (row_c - (h / 2 - 0.5)) * np.cos(ang)
    return lev, plate_row, -roll


def _top_edge(lev, c0, c1, glev=None):
    """Subpixel row of the object's top edge in columns c0..c1.

    The first 0.5 crossing of the levelled mask gives the edge to a pixel; with the levelled
    gray image ``glev`` it is refined to the row where the gray level crosses the local
    mid-level (median of 5 px of background above and of object below), which removes the
    dependence on a global threshold.
    """
    cols, rows = [], []
    n = lev.shape[0]
    for c in range(int(c0), int(c1)):
        col = lev[:, c]
        idx = np.nonzero(col >= 0.5)[0]
        if idx.size == 0 or idx[0] == 0:
            continue
        i = idx[0]
        a, b = col[i - 1], col[i]
        r = i - 1 + (0.5 - a) / (b - a)
        if glev is not None and 12 <= i < n - 12:
            g = glev[:, c]
            bg, fg = np.median(g[i - 12:i - 6]), np.median(g[i + 6:i + 12])
            mid = 0.5 * (bg + fg)
            seg = g[i - 6:i + 6]
            if abs(bg - fg) > 0.03:
                sgn = np.sign(bg - fg)
                k = np.nonzero(sgn * (seg - mid) <= 0)[0]
                if k.size and k[0] > 0:
                    j = k[0]
                    r = i - 6 + j - 1 + (seg[j - 1] - mid) / (seg[j - 1] - seg[j])
        rows.append(r)
        cols.append(c)
    return np.asarray(cols, float), np.asarray(rows, float)


def _fit(path, u, v, label, seed=0, residual=None):
    """RANSAC line (``LineModelND``); residual threshold = max(1.5 px, 3 x robust sigma of the
    residuals about a first total-least-squares line) unless given, so a noisy edge keeps its
    full length instead of a short, locally straight piece."""
    if u.size < 20:
        raise InputError(path, label, "a flank of at least 20 boundary pixels", int(u.size))
    pts = np.column_stack([u, v])
    if residual is None:
        first = measure.LineModelND.from_estimate(pts)
        if not first:
            raise InputError(path, label, "boundary points that define a line", "a degenerate point set")
        res = first.residuals(pts)
        sigma = 1.4826 * np.median(np.abs(res - np.median(res)))
        residual = max(1.5, 3.0 * sigma)
    model, inl = measure.ransac(pts, measure.LineModelND, min_samples=2, residual_threshold=residual,
                                max_trials=500, rng=seed)
    (u0, v0), (du, dv) = model.origin, model.direction
    return float(np.degrees(np.arctan2(abs(dv), abs(du)))), (u0, v0, du, dv), pts[inl]


def _components_on_plate(path, binary, slope, intercept, kind):
    h, w = binary.shape
    rr, cc = np.mgrid[0:h, 0:w]
    plate_rows = slope * cc + intercept
    above = binary & (rr < plate_rows - 1)
    lab = measure.label(above)
    touching = np.unique(lab[(rr > plate_rows - 8) & (rr < plate_rows - 1) & above])
    touching = touching[touching > 0]
    props = {p.label: p for p in measure.regionprops(lab)}
    cands = sorted((props[t] for t in touching if props[t].area > 0.004 * h * w), key=lambda p: -p.area)
    if not cands:
        raise InputError(path, "image", f"one {kind} standing on the plate", "none found")
    if len(cands) > 1 and cands[1].area > 0.25 * cands[0].area:
        raise InputError(path, "image", f"one {kind}", f"{len(cands)} separate {kind}s on the plate")
    comp = lab == cands[0].label
    r0, c0, r1, c1 = cands[0].bbox
    if r0 <= 2 or c0 <= 2 or c1 >= w - 2:
        raise InputError(path, "image", f"the whole {kind} inside the frame", "it is cut by the image border")
    return comp


def measure_pile(path, threshold="otsu", keep_stages=False, channel="auto", refusals=None) -> PileResult:
    """Left/right flank angles of one heap photo relative to the plate line.

    Plate candidates: the long near-horizontal edges below the image middle, topmost first, of
    the luminance and then of the united L*a*b* edges (a plate differing from the wall in hue
    only), at most four; the first on which a heap is found is the plate.  The threshold is
    Otsu's on the band of the image just above the plate (where heap and background meet).  channel "auto" tries cues in
    turn until one gives a single heap standing on the plate inside the frame: luminance and
    chroma with the heap darker than the wall (the better separating one first, Otsu's eta),
    then every cue of :data:`CUES` that splits the band into two clear classes (eta at least
    :data:`MIN_CUE_ETA`) with either polarity (a heap lighter than a dark wall, a heap
    differing in hue only) by decreasing eta; a result must look like a heap (flanks within
    :data:`FLANK_RANGE`, at least 3 % of the image high).  The cue used is reported, with a
    confidence ("low" when a flank's points stray from its line, e.g. a cast shadow joined to
    a flank, or when the next cue that also measures the heap, :data:`CUE_CHECKS` at most,
    gives a flank more than :data:`CUE_AGREEMENT_DEG` away: a cleanly fitted flank can still
    be the wrong edge; read such a photo before using its number).  With ``refusals`` (a folder), a
    photo that cannot be measured also gets a diagnostic image of every attempt there
    (:mod:`soilcal.imaging.refusal`), named in the refusal.
    """
    tried = Tried(keep_masks=refusals is not None)
    with explained(path, refusals, tried):
        return _measure_pile(path, threshold, keep_stages, channel, tried)


def _measure_pile(path, threshold, keep_stages, channel, tried: Tried) -> PileResult:
    rgb = read_photo(path)
    lum = _gray(rgb)
    tried.rgb, tried.gray = rgb, lum
    h, w = lum.shape
    lines = plate_lines(lum)
    cedges = colour_edges(rgb)
    tried.edges = cedges
    for ln in plate_lines(lum, edges=cedges):
        if all(abs((ln[0] - o[0]) * w / 2 + ln[1] - o[1]) > 3 for o in lines):
            lines.append(ln)
    tried.lines = list(lines[:4])
    if not lines:
        raise InputError(path, "image", "a straight base plate edge", "none found")
    grays = _grays(rgb, CUES if channel == "auto" else (channel,), lum)
    rr, cc = np.mgrid[0:h, 0:w]
    err = None
    first = None  # the first cue's result, waiting for a second cue to cross-check it
    for n_line, (slope, intercept) in enumerate(lines[:4], 1):  # the plate top first; a faint one may hide behind a lower edge
        prow = slope * cc + intercept
        band = (rr < prow - 3) & (rr > prow - 0.35 * h)  # where heap and wall meet
        if channel != "auto":
            order = [(channel, "dark")]
        else:
            etas = {ch: _eta(g[band]) for ch, g in grays.items()}
            order = [(ch, "dark") for ch in sorted(("gray", "chroma"), key=lambda k: -etas[k])]
            # further cues only where they split the band into two clear classes (a unimodal
            # band gives eta = 2/pi = 0.64 at best: noise, not a heap)
            order += sorted([(ch, pol) for ch in CUES for pol in ("dark", "light")
                             if (ch, pol) not in order and etas[ch] >= MIN_CUE_ETA], key=lambda t: -etas[t[0]])
        checks = CUE_CHECKS
        for ch, pol in order:
            if first is not None and checks == 0:
                break
            g = grays[ch] if pol == "dark" else 1.0 - grays[ch]
            try:
                res = _pile_with(path, rgb, g, ch, pol, band, slope, intercept, threshold,
                                 keep_stages and first is None, search=channel == "auto", tried=tried,
                                 label=f"line {n_line}, {ch}/{pol}")
            except InputError as e:
                if e.field not in ("image", "left flank", "right flank"):
                    raise
                tried.refuse_last(e)
                err = err or e  # the refusal reported is the first cue's on the topmost line
                checks -= first is not None
                continue
            if channel != "auto":
                return res
            if first is None:
                first = res
                continue
            return _cross_checked(first, res)
        if first is not None:
            return first  # no second cue measured a heap on this plate line: nothing to compare
    raise err


#: a cue search measures the heap with up to this many further cues after the first that
#: measures it, and takes the first of them that does as a cross-check
CUE_CHECKS = 3
#: flank difference (deg) between two cues above which a result's confidence is "low": two
#: segmentations of one heap that disagree by more than this put one of them (the reported
#: one, or the check) more than half of it off, e.g. a flank whose shaded side or joined
#: shadow one cue takes for wall or heap
CUE_AGREEMENT_DEG = 1.0


def _cross_checked(res: PileResult, check: PileResult) -> PileResult:
    """``res`` with a second cue's measurement of the same heap beside it (module constants)."""
    d = max(abs(res.left_deg - check.left_deg), abs(res.right_deg - check.right_deg))
    res.cue_check, res.cue_check_deg = check.cue, float(d)
    if d > CUE_AGREEMENT_DEG:
        res.confidence = "low"
    return res


def _pile_with(path, rgb, gray, cue, polarity, band, slope, intercept, threshold, keep_stages, search=True,
               tried: Tried | None = None, label: str = ""):
    """Measure with one cue: the heap is the class below Otsu's threshold of ``gray``.  In a
    cue search (``search``) the result must look like a heap; a channel chosen by the caller
    (e.g. a DEM silhouette, whatever its flanks) is measured as it is.  ``tried`` records the
    attempt (its segmented class and plate line) for a refusal's diagnostic image."""
    if threshold == "otsu":
        t = filters.threshold_otsu(gray[band])
        binary = ndi.binary_fill_holes(morphology.opening(gray < t, morphology.disk(2)))
    else:
        binary = _binary(path, gray, threshold)
    if tried is not None:
        tried.add(label or f"{cue}/{polarity}", binary, (slope, intercept))
    comp = _components_on_plate(path, binary, slope, intercept, "heap")
    lev, prow, roll = _level(comp, slope, intercept)
    glev = _level(gray, slope, intercept)[0]
    cols = np.nonzero(lev.max(axis=0) >= 0.5)[0]
    cu, rv = _top_edge(lev, cols.min(), cols.max() + 1, glev)
    v = prow - rv
    hmax = np.percentile(v, 99.5)
    apex = np.median(cu[v > 0.97 * hmax])
    band = (v > BAND[0] * hmax) & (v < BAND[1] * hmax)
    lsel, rsel = band & (cu < apex), band & (cu > apex)
    left, lline, lp = _fit(path, cu[lsel], v[lsel], "left flank")
    right, rline, rp = _fit(path, cu[rsel], v[rsel], "right flank")
    ang = np.array([left, right])
    # confidence: share of each flank's points on its line, their scatter about it
    used = min(len(lp) / max(lsel.sum(), 1), len(rp) / max(rsel.sum(), 1))
    rms = max(_line_rms(lp, lline), _line_rms(rp, rline))
    if search and (not (FLANK_RANGE[0] <= ang.min() and ang.max() <= FLANK_RANGE[1]) or hmax < 0.03 * lev.shape[0]):
        raise InputError(path, "image", f"a heap: flanks between {FLANK_RANGE[0]:.0f} and "
                         f"{FLANK_RANGE[1]:.0f} deg, at least 3 % of the image high",
                         f"flanks {left:.1f} and {right:.1f} deg ({rms:.1f} px from their lines), {hmax:.0f} px "
                         f"high ({cue}/{polarity})")
    low = used < 0.6 or rms > 2.5 or abs(left - right) > 12.0
    st = None
    if keep_stages:
        st = Stages(rgb, gray, binary, lev, [lline + ("left",), rline + ("right",)], [lp, rp])
        st.plate_row = prow
    return PileResult(str(path), float(ang.mean()), left, right, float(ang.std(ddof=1)), float(roll),
                      f"{cue}/{polarity}", float(used), float(rms), "low" if low else "ok", st)


def _line_rms(pts, line):
    u0, v0, du, dv = line
    return float(np.sqrt(np.mean(((pts[:, 0] - u0) * dv - (pts[:, 1] - v0) * du) ** 2)))


def measure_piles(paths, threshold="otsu", keep_stages=False, channel="auto", refusals=None):
    """Multi-view average: mean of all flank angles, spread = their sample std (``refusals``:
    :func:`measure_pile`)."""
    res = [measure_pile(p, threshold, keep_stages, channel, refusals) for p in paths]
    lefts = np.array([r.left_deg for r in res])
    rights = np.array([r.right_deg for r in res])
    allf = np.concatenate([lefts, rights])
    summary = {
        "angle_deg": float(allf.mean()),
        "left_deg": float(lefts.mean()),
        "right_deg": float(rights.mean()),
        "spread_deg": float(allf.std(ddof=1)) if allf.size > 1 else 0.0,
        "n_photos": len(res),
        "photos": [r.as_dict() for r in res],
    }
    return summary, res


def plate_lines(gray, below=None, edges=None):
    """Long near-horizontal edges below a point, topmost first, each refined by a RANSAC line
    fit: [(slope, intercept), ...] with row = slope * col + intercept.

    ``below`` = (col, row): only lines passing below that point count (default: the image
    middle at column 0).  ``edges``: an edge map to use instead of the luminance's Canny edges.
    """
    edges = feature.canny(gray, sigma=1.5) if edges is None else edges
    h, w = gray.shape
    col0, row0 = below if below is not None else (0.0, 0.5 * h)
    thetas = np.radians(np.linspace(84, 96, 241))
    hs, ang, dist = transform.hough_line(edges, theta=thetas)
    _, angs, dists = transform.hough_line_peaks(hs, ang, dist, num_peaks=8, min_distance=4,
                                                threshold=0.25 * w)
    at = sorted(((a, d, (d - col0 * np.cos(a)) / np.sin(a)) for a, d in zip(angs, dists)), key=lambda t: t[2])
    cols = np.arange(w)
    er, ec = np.nonzero(edges)
    out = []
    for a, d, row in at:
        if row <= row0:
            continue
        rows = (d - cols * np.cos(a)) / np.sin(a)
        near = np.abs(er - rows[ec]) < 3
        pts = np.column_stack([ec[near], er[near]]).astype(float)
        model, _ = measure.ransac(pts, measure.LineModelND, min_samples=2, residual_threshold=1.0,
                                  max_trials=200, rng=0)
        (c0, r0), (dc, dr) = model.origin, model.direction
        out.append((dr / dc, r0 - dr / dc * c0))
    return out


def plate_line_any(path, gray, below=None, required=True, edges=None):
    """The topmost of :func:`plate_lines` (the plate top: the plate face and table edges lie
    below it); with ``required=False`` None when there is none."""
    lines = plate_lines(gray, below, edges)
    if not lines:
        if not required:
            return None
        raise InputError(path, "image", "a straight base plate edge", "none found")
    return lines[0]


@dataclass
class FurrowResult:
    path: str
    x_mm: np.ndarray
    z_mm: np.ndarray
    coeffs: list  # highest power first, x and z in mm
    degree: int
    area_mm2: float
    px_per_mm: float
    roll_deg: float
    stages: Stages | None = None

    def as_dict(self):
        return {"path": self.path, "degree": self.degree, "coeffs": self.coeffs,
                "area_mm2": self.area_mm2, "area_dm2": self.area_mm2 / 1e4,
                "px_per_mm": self.px_per_mm, "roll_deg": self.roll_deg,
                "profile": {"x_mm": np.round(self.x_mm[::10], 2).tolist(),
                            "z_mm": np.round(self.z_mm[::10], 2).tolist()}}


def measure_furrow(path, scale_length_mm, datum_mm=0.0, degree=9, threshold="otsu", keep_stages=False,
                   refusals=None):
    """Furrow profile in mm from the profile-meter beam (scale reference of known length);
    ``refusals``: a folder for the diagnostic image of a photo that cannot be measured."""
    tried = Tried(keep_masks=refusals is not None)
    with explained(path, refusals, tried):
        return _measure_furrow(path, scale_length_mm, datum_mm, degree, threshold, keep_stages, tried)


def _measure_furrow(path, scale_length_mm, datum_mm, degree, threshold, keep_stages, tried: Tried):
    from soilcal.imaging.manifest import _is_number, check_degree

    if not _is_number(scale_length_mm) or scale_length_mm <= 0:
        raise InputError(path, "scale_length_mm", "a positive length of the scale reference in mm", scale_length_mm)
    if not _is_number(datum_mm):
        raise InputError(path, "beam_datum_mm", "a number (mm)", datum_mm)
    check_degree(path, "degree", degree)
    rgb = read_photo(path)
    gray = _gray(rgb)
    tried.rgb, tried.gray = rgb, gray
    binary = _binary(path, gray, threshold)
    tried.add(f"dark class ({threshold}): beam and soil are sought in it", binary)
    h, w = binary.shape
    lab = measure.label(binary)
    beams = [p for p in measure.regionprops(lab)
             if p.area > 500 and p.axis_minor_length > 0 and p.axis_major_length / p.axis_minor_length > 15]
    if not beams:
        raise InputError(path, "image", "a profile-meter beam (long dark bar)", "none found")
    beam = max(beams, key=lambda p: p.axis_major_length)
    tried.attempts[-1].outcome = f"{len(beams)} beam-like bar(s); the longest is the beam"
    beam_mask = lab == beam.label
    tried.add("beam (longest bar)", beam_mask)
    br, bc = np.nonzero(beam_mask)
    # direction from a line fit through the beam pixels
    A = np.column_stack([bc, np.ones_like(bc)]).astype(float)
    slope, _ = np.linalg.lstsq(A, br.astype(float), rcond=None)[0]
    roll = -float(np.degrees(np.arctan(slope)))
    ux = np.array([1.0, slope]) / np.hypot(1.0, slope)  # (col, row) along the beam
    uz = np.array([slope, -1.0]) / np.hypot(1.0, slope)  # up
    t = bc * ux[0] + br * ux[1]
    length_px = t.max() - t.min() + 1.0
    s = length_px / scale_length_mm
    mid = (t.max() + t.min()) / 2
    vb = bc * uz[0] + br * uz[1]
    beam_lower = vb.min() - 0.5
    # soil: largest component below the beam
    others = [p for p in measure.regionprops(lab) if p.label != beam.label]
    if not others:
        raise InputError(path, "image", "the soil below the profile-meter beam (a dark region besides the beam)",
                         "none found")
    soil = lab == max(others, key=lambda p: p.area).label
    lev, _, _ = _level(soil, slope, 0.0)
    # transform beam frame into the levelled image: rotate points about the centre
    ang = np.arctan(slope)
    cy, cx = h / 2 - 0.5, w / 2 - 0.5
    def to_lev(c, r):
        dc, dr = c - cx, r - cy
        return cx + dc * np.cos(ang) + dr * np.sin(ang), cy - dc * np.sin(ang) + dr * np.cos(ang)
    lc, lr = to_lev(bc.astype(float), br.astype(float))
    c_left, c_right = lc.min() - 0.5, lc.max() + 0.5
    lower_row = lr.max() + 0.5
    cu, rv = _top_edge(lev, np.ceil(c_left), np.floor(c_right) + 1, _level(gray, slope, 0.0)[0])
    x = (cu - (c_left + c_right) / 2) / s
    z = datum_mm - (rv - lower_row) / s
    poly = np.polynomial.Polynomial.fit(x, z, degree)
    a, b = -scale_length_mm / 2, scale_length_mm / 2
    P = poly.integ()
    za, zb = poly(a), poly(b)
    area = 0.5 * (za + zb) * (b - a) - (P(b) - P(a))
    coeffs = poly.convert().coef[::-1].tolist()
    st = None
    if keep_stages:
        st = Stages(rgb, gray, binary, lev, [], [np.column_stack([cu, rv])])
        st.poly = poly
        st.frame = (c_left, c_right, lower_row, s, datum_mm)
    del beam_lower, mid, vb
    return FurrowResult(str(path), x, z, coeffs, degree, float(area), float(s), roll, st)
