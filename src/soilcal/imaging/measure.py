"""Angle and profile measurement from photos (scikit-image).

Pile (stacking / repose angle), as in 001 Sec. 2.2.1 and 002 Sec. 2.4: grayscale ->
threshold (global Otsu or adaptive ``threshold_local``) -> morphological opening, hole filling
-> the connected component standing on the plate -> boundary -> straight-line fit of each
flank -> angle = atan(slope).  Here the reference is the plate line itself, found by a Hough
transform of the Canny edges (lines within :data:`PLATE_MAX_ROLL_DEG` of horizontal) and refined by a RANSAC line fit, so a
rolled camera does not bias the angle: the image is rotated by the plate's tilt before the
flanks are read.  A camera rolled further is refused (:func:`_plate_beyond_search`) when a heap
stands on the tilted edge (:func:`_heap_stands_on`; a shadow's edge across the wall is no roll).  Each flank is fitted with RANSAC (``skimage.measure.ransac`` with
``LineModelND``) between 20 % and 75 % of the heap height (top cap and toe excluded):

    alpha = atan(|d_v| / |d_u|)     (d = fitted line direction in the plate frame)

Photo value = (alpha_L + alpha_R) / 2; several views are averaged over all flanks, spread =
sample standard deviation of the flank angles.

Drum (dynamic angle, 003 Sec. 2): see :mod:`soilcal.imaging.drum` (photos of a drum on its
stand and frames exported by drum testers, by one method).

Furrow (000 Sec. 2.1/3.1): the profile-meter beam (dark bar of known length L) gives the
scale s = length_px / L, the horizontal direction and the origin (beam centre, x = 0); the soil
top boundary below it gives z(x) = datum - depth, fitted with a polynomial of selectable
degree (``numpy.polynomial.Polynomial.fit``, reported as the profile); the area is the
integral over the span of (chord - z(x)) dx over the measured boundary points, the chord
joining the surface's heights at the span's ends (:func:`_direct_chord_area`); the fitted
polynomial's own chord area is reported beside it (``area_fit_mm2``).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import asdict, dataclass, field

import numpy as np
from scipy import ndimage as ndi
from skimage import color, feature, filters, measure, morphology, transform, util

from soilcal.errors import InputError
from soilcal.imaging import CHANNELS_EXPECTED, CUES
from soilcal.imaging.io import read_photo, read_photo_reduced
from soilcal.imaging.refusal import Tried, explained
from soilcal.imaging.scenes import furrow_chord_area

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
    confidence: str = "ok"  # "low": under FLANK_USED_MIN of a flank used, RMS above FLANK_RMS_MAX px,
    # flanks > 12 deg apart, the heap's level continuing past a flank's line (flank_outside_share
    # above FLANK_OUTSIDE_MAX) or further cues' flanks more than CUE_AGREEMENT_DEG away (CUE_CHECKS)
    stages: Stages | None = None
    cue_check: str = ""  # the further cue that confirms or refutes this result (cue search only), "" if none did
    cue_check_deg: float = float("nan")  # the larger of its two flanks' differences from this result
    cue_outvoted: str = ""  # a further cue that disagreed but was outvoted by cue and cue_check
    cue_outvoted_deg: float = float("nan")  # its larger flank difference from this result
    # larger flank's share of the heap-to-wall contrast still found just outside its line
    # (_outside_share; NaN where the flank's contrast is too weak to tell)
    flank_outside_share: float = float("nan")
    # flanks whose line was located again in the luminance texture ("left", "right", "left right"
    # or ""; low-confidence results only, _texture_flanks)
    texture_flanks: str = ""
    # where the plate line does not run on as an edge beside the heap (a plate hardly wider than
    # the heap, or one whose edge is faint there) and no other line gave a heap: what was found
    plate_beside: str = ""
    # the smaller flank's edge found running on along its own line below the plate line, as a
    # share of its heap-to-wall step above it (_foot_below_share; NaN where not judged): above
    # FOOT_BELOW_MAX the heap runs on below the line, which passes behind it (e.g. the edge of a
    # table top behind a plate hardly wider than the heap) and is no plate the heap stands on
    foot_below_share: float = float("nan")
    # the measured image's size over the photo's (below 1 for a photo reduced to
    # PILE_WORK_PIXELS): flank_rms_px and the plate line are in the measured image's pixels
    work_scale: float = 1.0
    # where the plate line came from: "found" by the plate search, "manifest" (the photo's
    # plate_line_px), "command line" (soilcal image pile --plate-line-px) or "given" (a
    # caller's, e.g. a rendered silhouette's)
    plate_line: str = "found"
    # two points [column, row] of the plate line in the photo's pixels as shown: the manifest's
    # as given, else the line measured on, at the measured image's first and last columns
    plate_line_px: list | None = None
    # where a second plate candidate also carries the heap, tilted against the line measured on
    # so that the flanks differ by more than PLATE_AMBIGUOUS_DEG (a line through a scale card
    # standing on the plate beside a foot, crossing the plate's edge further on): the photo, the
    # two lines and the flanks on each, and the way out (the plate line given by hand); the
    # result is then "low" (:func:`_plate_alternative`); "" where no such line was found
    plate_ambiguous: str = ""
    # (plate slope, plate intercept, left line, right line, heap height px): where the flanks
    # were fitted, for a later refinement; not reported
    geometry: tuple | None = field(default=None, repr=False)
    # (slope, intercept, left deg, right deg) of the second plate candidate that carries the
    # heap (plate_ambiguous), in the measured image's pixels; not reported
    alternative: tuple | None = field(default=None, repr=False)
    # (slope, intercept, left deg, right deg, its across share, the measured line's) of a
    # straight edge running across the photo at the heap's foot further than the line measured
    # on, tilted against it (plate_ambiguous, :func:`_level_rival`); not reported
    rival: tuple | None = field(default=None, repr=False)
    # (slope, intercept, left deg, right deg, why passed over) of a plate candidate above the
    # line measured on, at the heap's foot, that carries the heap and meets edges along its foot
    # from foot to foot, but which the search passed over (plate_ambiguous, :func:`_stood_above`);
    # not reported
    stood_above: tuple | None = field(default=None, repr=False)

    def as_dict(self):
        d = asdict(self)
        d.pop("stages")
        d.pop("geometry")
        d.pop("rival")
        d.pop("alternative")
        d.pop("stood_above")
        return d


def _smoothed_lab(rgb):
    return color.rgb2lab(filters.gaussian(rgb, 1.2, channel_axis=-1))


class _Cues(dict):
    """The cue images of one photo by channel (:func:`_gray`), and ``segmented``: each class
    segmented from them (:func:`open_fill` of a cue below a threshold) by (channel, polarity,
    threshold), kept for the photo's further plate lines and checks: two plate candidates a
    few rows apart often give the same Otsu threshold (a histogram bin's centre), so the same
    class, and the local threshold (``threshold="adaptive"``) gives every line the same one.
    With ``rgb`` (the photo) a cue of :data:`CUES` not given is made when it is first read, the
    smoothed L*a*b* image once for both of its cues: a photo whose cue searches all end at
    luminance and chroma is never converted to L*a*b*.  ``lines``: what the cue searches on a
    plate line read, by (slope, intercept) (:func:`_line_cues`)."""

    def __init__(self, *args, rgb=None, **kwargs):
        super().__init__(*args, **kwargs)
        self.segmented = {}
        self.lines = {}
        self.rgb = rgb
        self._lab = None

    def __missing__(self, channel):
        if self.rgb is None or channel not in CUES:
            raise KeyError(channel)
        lab = None
        if channel in ("lab_a", "lab_b"):
            if self._lab is None:
                self._lab = _smoothed_lab(self.rgb)
            lab = self._lab
        self[channel] = g = _gray(self.rgb, channel, lab)
        if "lab_a" in self and "lab_b" in self:
            self._lab = None  # both made: the L*a*b* image is no longer needed
        return g


def _grays(rgb, channels, lum=None):
    """The cues ``channels`` of ``rgb`` (a :class:`_Cues`, each made when first read); ``lum``
    (the "gray" channel, already computed) is reused."""
    return _Cues({"gray": lum} if lum is not None and "gray" in channels else {}, rgb=rgb)


class _Separations:
    """Each cue's separability in a plate line's band and its Otsu threshold there
    (:func:`_eta` of the cue in ``band``), by channel, each computed when first read and kept in
    ``known`` (the line's dict in ``grays.lines``, :func:`_line_cues`).  Made afresh for each
    search on the line and not kept in ``grays`` itself: a view holding ``grays`` inside it
    would make a reference cycle, and every photo's cue images would outlive its measurement
    until a full garbage collection."""

    def __init__(self, grays, band, known):
        self.grays, self.band, self.known = grays, band, known

    def __getitem__(self, channel):
        v = self.known.get(channel)
        if v is None:
            self.known[channel] = v = _eta(self.grays[channel][self.band])
        return v


def _line_cues(grays, slope, intercept, shape):
    """(band, separations, levelled) of the plate line (slope, intercept) in a photo of
    ``shape``: the rows from 35 % of the photo's height to 3 px above the line, where heap and
    wall meet; the cues' :class:`_Separations` there; and a dict of the images levelled on the
    line (:func:`_pile_with`'s ``levelled``: the luminance and each cue that finds a heap on
    it).  The band, the separabilities found and the levelled images are kept in
    ``grays.lines`` (arrays and numbers only, nothing that refers back to ``grays``) for the
    line's further searches (the plate search, the checks for a second plate line or a rival,
    which measure the heap on the same lines again) and the checks of the heap found on it
    (:func:`_judge_foot_below`, :func:`_texture_flanks`)."""
    key = (slope, intercept)
    if key not in grays.lines:
        h, w = shape
        rr, cc = np.arange(h)[:, None], np.arange(w)[None, :]
        prow = slope * cc + intercept
        band = (rr < prow - 3) & (rr > prow - 0.35 * h)
        grays.lines[key] = band, {}, {}
    band, known, levelled = grays.lines[key]
    return band, _Separations(grays, band, known), levelled


def _cue_order(split):
    """The cue search's order on a plate line (:func:`measure_pile`): luminance and chroma with
    the heap darker than the wall, the better separating one first, then every cue and polarity
    whose cue splits the band clearly (eta at least :data:`MIN_CUE_ETA`) by decreasing eta.
    Yielded in turn, the further cues' separabilities (``split``, :class:`_Separations`) read
    only once the search goes past the first two."""
    first = [(ch, "dark") for ch in sorted(("gray", "chroma"), key=lambda k: -split[k][0])]
    yield from first
    # further cues only where they split the band into two clear classes (a unimodal band gives
    # eta = 2/pi = 0.64 at best: noise, not a heap)
    yield from sorted([(ch, pol) for ch in CUES for pol in ("dark", "light")
                       if (ch, pol) not in first and split[ch][0] >= MIN_CUE_ETA], key=lambda t: -split[t[0]][0])


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
        # R + G + B added channel by channel: the numbers of rgb.sum(-1) (three terms, added
        # in order), without NumPy's reduction over an axis of three, ten times the time
        c = (rgb[..., 0] - rgb[..., 2]) / (rgb[..., 0] + rgb[..., 1] + rgb[..., 2] + 0.05)
        return np.clip(0.5 - 2.0 * c, 0, 1)
    if channel in ("lab_a", "lab_b"):
        if lab is None:
            lab = _smoothed_lab(rgb)
        return np.clip((lab[..., 1 if channel == "lab_a" else 2] + 100.0) / 200.0, 0, 1)
    if channel == "saturation":
        # rgb2hsv's S channel, (max - min) / max and 0 where max = min, computed as rgb2hsv
        # computes it (the same numbers) without the hue and value it would also compute; the
        # largest and smallest channel taken pixel by pixel of the three (the same values as
        # np.ptp and max over the colour axis, whose reductions over an axis of three take ten
        # times as long)
        rgb = util.img_as_float(rgb)
        r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
        top = np.maximum(np.maximum(r, g), b)
        delta = top - np.minimum(np.minimum(r, g), b)
        with np.errstate(invalid="ignore"):
            s = delta / top
        s[delta == 0.0] = 0.0
        return filters.gaussian(s, 1.2)
    raise InputError(None, "channel", CHANNELS_EXPECTED, channel)


#: a flank fit is good enough for an "ok" result when at least this share of its band points
#: lie on its line and their RMS distance from it is at most FLANK_RMS_MAX px
FLANK_USED_MIN = 0.6
FLANK_RMS_MAX = 2.5
MIN_CUE_ETA = 0.75
FLANK_RANGE = (10.0, 65.0)  # flank angles a heap of soil can stand at
MIN_RISE = 0.03  # the least height of a heap above the plate, as a share of the image height


def _eta(values):
    """Otsu's separability s_b^2 / s_T^2 of a sample split at its Otsu threshold, and that
    threshold: (eta, t)."""
    t = filters.threshold_otsu(values)
    lo, hi = values[values < t], values[values >= t]
    if not lo.size or not hi.size:
        return 0.0, t
    return float(lo.size * hi.size / values.size ** 2 * (hi.mean() - lo.mean()) ** 2 / (values.var() + 1e-12)), t


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


#: the opening that removes specks from a segmented class before its holes are filled
SPECK_FOOTPRINT = morphology.disk(2)
#: its pixels' offsets from its centre (row, column); it is symmetric about the centre
_SPECK_OFFSETS = tuple((int(i) - SPECK_FOOTPRINT.shape[0] // 2, int(j) - SPECK_FOOTPRINT.shape[1] // 2)
                       for i, j in np.argwhere(SPECK_FOOTPRINT))


def _reflected_min_max(mask, r, erode):
    """Binary erosion (``erode``) or dilation of ``mask`` by :data:`SPECK_FOOTPRINT` with the
    image reflected at its border by ``r`` px (``mode="symmetric"``): the AND (OR) of the
    reflected image shifted by each offset of the footprint.  The same pixels as
    ``ndi.binary_erosion`` (``binary_dilation``) of the reflected image cropped back (the
    footprint is symmetric, so the dilation's reflected footprint is itself), a few whole-array
    operations instead of a walk over every pixel's neighbourhood."""
    h, w = mask.shape
    padded = np.pad(mask, r, mode="symmetric")
    op = np.logical_and if erode else np.logical_or
    out = None
    for di, dj in _SPECK_OFFSETS:
        s = padded[r + di:r + di + h, r + dj:r + dj + w]
        out = s.copy() if out is None else op(out, s, out=out)
    return out


def open_fill(mask):
    """``mask`` opened by :data:`SPECK_FOOTPRINT` and its holes filled: the same as
    ``ndi.binary_fill_holes(morphology.opening(mask, SPECK_FOOTPRINT))`` (an opening at the
    image border reflected, as scikit-image's; a hole is a 4-connected region of background that
    does not reach the border, as scipy's), in a fraction of the time: the opening by erosion
    and dilation of the reflected image as shifted ANDs and ORs (:func:`_reflected_min_max`),
    the holes by one labelling of the background instead of a propagation from the border.
    Every candidate plate line and cue of a heap photo segments the photo once."""
    r = SPECK_FOOTPRINT.shape[0] // 2
    opened = _reflected_min_max(_reflected_min_max(np.asarray(mask, bool), r, True), r, False)
    lab, n = ndi.label(~opened)
    outside = np.zeros(n + 1, bool)
    for border in (lab[0], lab[-1], lab[:, 0], lab[:, -1]):
        outside[border] = True
    outside[0] = False  # label 0: the opened mask itself, kept
    return ~outside[lab]


def _binary(path, gray, method, classes=2):
    if method == "otsu":
        t = filters.threshold_otsu(gray) if classes == 2 else filters.threshold_multiotsu(gray, classes)[-1]
        dark = gray < t
    elif method == "adaptive":
        block = 2 * (min(gray.shape) // 4) + 1  # larger than the object, so its inside is not split
        dark = gray < filters.threshold_local(gray, block, offset=0.02)
    else:
        raise InputError(path, "threshold", "'otsu' or 'adaptive'", method)
    return open_fill(dark)


def plate_line(path, gray, binary):
    """(slope, intercept) of the plate's top edge, row = slope * col + intercept."""
    edges = feature.canny(gray, sigma=1.5)
    h, w = gray.shape
    thetas = np.radians(np.linspace(84, 96, 241))
    hs, ang, dist = transform.hough_line(edges, theta=thetas)
    _, angs, dists = hough_peaks(hs, ang, dist, num_peaks=12, min_distance=4, threshold=0.2 * w)
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
    return lev, _levelled_plate_row(mask.shape, slope, intercept), -roll


def _levelled_plate_row(shape, slope, intercept):
    """The plate line's row in an image of ``shape`` levelled on it (:func:`_level`)."""
    h, w = shape[:2]
    # plate row after rotation: the plate point under the image centre
    row_c = slope * (w / 2 - 0.5) + intercept
    ang = np.arctan(slope)
    # distance along the image vertical from centre, after rotation by -ang around the centre
    return (h / 2 - 0.5) + (row_c - (h / 2 - 0.5)) * np.cos(ang)


def _top_edge(lev, c0, c1, glev=None, llev=None):
    """Subpixel row of the object's top edge in columns c0..c1: (columns, rows), and with
    ``llev`` the rows refined in luminance as a third array.

    The first 0.5 crossing of the levelled mask gives the edge to a pixel; with the levelled
    gray image ``glev`` it is refined to the row where the gray level crosses the local
    mid-level (median of 6 px of background above and of object below), which removes the
    dependence on a global threshold.  With the levelled luminance ``llev`` as well (a cue
    other than luminance segmented the heap), the third array has, in every column whose
    luminance steps across the edge by more than :data:`LUM_EDGE_SNR` times its noise there
    (and by at least 0.03), the row refined in luminance instead, else the cue's row: a camera
    records luminance at full resolution and colour at half or less (Bayer demosaicing, JPEG
    4:2:0 subsampling in 16 px blocks), so a colour cue's edge is blurred and blocky where the
    luminance edge is sharp (:func:`_straighter` decides per flank which of the two edges is
    fitted).  All columns at once: each column's windows gathered as the rows of an array.
    """
    n = lev.shape[0]
    cs = np.arange(int(c0), int(c1))
    over = lev[:, cs] >= 0.5
    i = over.argmax(axis=0)  # the first row at or above 0.5 (0 where none is)
    keep = over[i, np.arange(cs.size)] & (i != 0)
    cs, i = cs[keep], i[keep]
    a, b = lev[i - 1, cs], lev[i, cs]
    r0 = i - 1 + (0.5 - a) / (b - a)
    r, rl = r0.copy(), r0.copy()
    if glev is not None:
        inner = np.nonzero((i >= 12) & (i < n - 12))[0]
        ii, cc = i[inner], cs[inner]

        def windows(img, lo, hi):  # img[i + lo:i + hi, c] of each inner column, as rows
            return img[ii[:, None] + np.arange(lo, hi), cc[:, None]]

        bg, fg = np.median(windows(glev, -12, -6), axis=1), np.median(windows(glev, 6, 12), axis=1)
        step = np.abs(bg - fg) > 0.03
        r[inner[step]] = _mid_crossings(windows(glev, -6, 6)[step], 0.5 * (bg + fg)[step], np.sign(bg - fg)[step],
                                        ii[step] - 6, r0[inner[step]])
        rl = r.copy()
        if llev is not None:
            above, below = windows(llev, -12, -6), windows(llev, 6, 12)
            bl, fl = np.median(above, axis=1), np.median(below, axis=1)
            noise = 1.4826 * np.median(np.abs(np.concatenate([above - bl[:, None], below - fl[:, None]], axis=1)),
                                       axis=1)
            lim = LUM_EDGE_SNR * noise
            step = np.abs(bl - fl) > np.where(lim > 0.03, lim, 0.03)  # max(0.03, lim) as Python's max
            rl[inner[step]] = _mid_crossings(windows(llev, -6, 6)[step], 0.5 * (bl + fl)[step],
                                             np.sign(bl - fl)[step], ii[step] - 6, r0[inner[step]])
    out = cs.astype(float), r
    return out + (rl,) if llev is not None else out


#: a luminance step across a heap's edge this many times its noise (robust SD of 6 px each
#: side) refines the edge in luminance when a colour cue segmented the heap (_top_edge)
LUM_EDGE_SNR = 4.0


def _mid_crossings(segs, mid, sgn, start, default):
    """:func:`_mid_crossing` (without ``near``) of each row of ``segs`` with its own ``mid``,
    ``sgn``, ``start`` and ``default``: the same numbers, all rows at once."""
    far = sgn[:, None] * (segs - mid[:, None]) <= 0
    j = far.argmax(axis=1)  # the first sample on the far side (0 where none is)
    ok = far[np.arange(j.size), j] & (j != 0)
    out = np.array(default, float)
    k, jk = np.nonzero(ok)[0], j[ok]
    prev = segs[k, jk - 1]
    out[k] = start[k] + jk - 1 + (prev - mid[k]) / (prev - segs[k, jk])
    return out


def _mid_crossing(seg, mid, sgn, start, default, near=None):
    """Position (sub-pixel, ``start`` + index in ``seg``) where ``seg`` crosses ``mid`` from the
    side of sign ``sgn`` to the other: the first sample on the far side, linearly interpolated
    from the one before (none when ``seg`` starts there), or with ``near`` (an index) the
    crossing nearest to it; ``default`` when there is none."""
    far = sgn * (seg - mid) <= 0
    if near is None:
        k = np.nonzero(far)[0]
        if not k.size or k[0] == 0:
            return default
        j = k[0]
    else:
        k = np.nonzero(~far[:-1] & far[1:])[0] + 1
        if not k.size:
            return default
        j = k[np.argmin(np.abs(k - 1 - near))]
    return start + j - 1 + (seg[j - 1] - mid) / (seg[j - 1] - seg[j])


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


#: a flank is fitted over at least this many columns (boundary points) of its band
#: (:data:`BAND` of the heap's height): a heap smaller in the photo is refused as too small
MIN_FLANK_COLUMNS = 20
#: what a photo with no heap on its plate is refused with
NONE_FOUND = "none found"
#: what a heap cut by the image border is refused with
CUT = "the whole heap inside the frame"


#: up to this many components on the plate strip have their areas counted one by one
#: (:func:`_components_on_plate`); more are counted by one pass over all the labels
_COUNT_ALONE = 8


def _components_on_plate(path, binary, slope, intercept, kind):
    h, w = binary.shape
    if not (math.isfinite(slope) and math.isfinite(intercept)):
        # measure_pile refuses a caller's line that is not finite (_check_given_plate,
        # check_plate_line) and the plate search keeps no such candidate (_refined_line), so
        # this guards direct calls only
        raise InputError(path, "image", "a plate line of finite slope and intercept (row = slope * col + "
                         "intercept)", f"slope {slope}, intercept {intercept}")
    # a column of row numbers against a row of plate rows (broadcast, not two full grids: the
    # cue search calls this for every cue on every plate line), over the rows above the plate
    # line's lowest point only (no pixel below it is above the line: labelled, counted and
    # compared, they would all be background)
    plate_rows = slope * np.arange(w)[None, :] + intercept
    top = min(h, max(1, math.ceil(float((plate_rows - 1).max()))))
    rr = np.arange(top)[:, None]
    above = binary[:top] & (rr < plate_rows - 1)
    lab = measure.label(above)
    # the components on the strip plate_rows - 8 < row < plate_rows - 1 (and row < top): its at
    # most 7 rows of each column read by index, not a mask over every row above the line; the
    # bounds are the first and last whole rows inside the open interval of the same floats
    # (row > x from floor(x) + 1 on, row < x up to ceil(x) - 1), a label > 0 is ``above``
    lo = np.clip(np.floor(plate_rows[0] - 8) + 1, 0, top).astype(np.intp)
    hi = np.clip(np.ceil(plate_rows[0] - 1), 0, top).astype(np.intp)
    strip_rows = lo[:, None] + np.arange(7)[None, :]
    on_strip = strip_rows < hi[:, None]
    touching = np.unique(lab[strip_rows[on_strip], np.nonzero(on_strip)[0]])
    touching = touching[touching > 0]
    # the areas (pixels) of the components touching the strip only, not a region object per
    # component: each counted alone where they are few, else one count of all the labels
    if touching.size <= _COUNT_ALONE:
        area = {int(t): int(np.count_nonzero(lab == t)) for t in touching}
    else:
        counts = np.bincount(lab.ravel())
        area = {int(t): int(counts[t]) for t in touching}
    cands = sorted((t for t in area if area[t] > 0.004 * h * w), key=lambda t: -area[t])
    if not cands:
        raise InputError(path, "image", f"one {kind} standing on the plate", NONE_FOUND)
    if len(cands) > 1 and area[cands[1]] > 0.25 * area[cands[0]]:
        raise InputError(path, "image", f"one {kind}", f"{len(cands)} separate {kind}s on the plate")
    comp = np.zeros((h, w), bool)
    comp[:top] = lab == cands[0]
    on = comp.any(axis=0)
    # its bounding box (rows r0 to r1, columns c0 to c1, the ends past it), as regionprops' bbox
    rows, cols = np.flatnonzero(comp.any(axis=1)), np.flatnonzero(on)
    r0, c0, r1, c1 = rows[0], cols[0], rows[-1] + 1, cols[-1] + 1
    if c0 <= 2 and c1 >= w - 2 and np.median(plate_rows[0, on] - comp[:, on].argmax(axis=0)) < MIN_RISE * h:
        # a low class running along the plate from one side of the frame to the other is a
        # strip of the plate's own edge or of the wall's noise on an empty plate, not a heap
        # (a heap wider than the frame rises from it)
        raise InputError(path, "image", f"one {kind} standing on the plate", NONE_FOUND)
    if r0 <= 2 or c0 <= 2 or c1 >= w - 2:
        cut = InputError(path, "image", f"the whole {kind} inside the frame",
                         "it is cut by the image border")
        cut.heap_beside = not (c0 <= 2 and c1 >= w - 2)  # a heap with wall beside it on one side at least
        raise cut
    return comp


def measure_pile(path, threshold="otsu", keep_stages=False, channel="auto", refusals=None, *,
                 image=None, plate=None, plate_px=None, plate_px_from="manifest") -> PileResult:
    """Left/right flank angles of one heap photo relative to the plate line.

    Plate candidates: the long near-horizontal edges below the image middle, topmost first, of
    the luminance and then of the united L*a*b* edges (a plate differing from the wall in hue
    only), at most :data:`PLATE_CANDIDATES`; the first on which a heap is found, the line running on
    beside it as an edge (:func:`_plate_beside_heap`), is the plate.  The threshold is
    Otsu's on the band of the image just above the plate (where heap and background meet).  channel "auto" tries cues in
    turn until one gives a single heap standing on the plate inside the frame: luminance and
    chroma with the heap darker than the wall (the better separating one first, Otsu's eta),
    then every cue of :data:`CUES` that splits the band into two clear classes (eta at least
    :data:`MIN_CUE_ETA`) with either polarity (a heap lighter than a dark wall, a heap
    differing in hue only) by decreasing eta; a result must look like a heap (flanks within
    :data:`FLANK_RANGE`, at least 3 % of the image high).  The cue used is reported, with a
    confidence ("low" when a flank's points stray from its line, e.g. a cast shadow joined to
    a flank; when the heap's level continues just outside a flank's line, e.g. a shaded flank
    as dark as the wall lost to it (:func:`_outside_share`, :data:`FLANK_OUTSIDE_MAX`); or
    when the further cues that also measure the heap, :data:`CUE_CHECKS` at most,
    give a flank more than :data:`CUE_AGREEMENT_DEG` away: the first credible one (a clear
    split, its own fits passing) that agrees confirms the result; one that disagrees is
    outvoted only by a next credible one that agrees: a cleanly fitted flank can still be the
    wrong edge; read such a photo before using its number).  A low-confidence result of the cue
    search has its flanks located again in the soil's grain (:func:`_texture_flanks`), which
    recovers a shaded flank lost to a wall of its brightness and colour; it stays low.  With
    ``refusals`` (a folder), a photo that cannot be measured also gets a diagnostic image of
    every attempt there (:mod:`soilcal.imaging.refusal`), named in the refusal.

    A photo of more than :data:`PILE_WORK_PIXELS` pixels is measured reduced to that size.
    ``image``: the photo as an RGB float array in [0, 1] (what :func:`read_photo` gives),
    measured instead of reading ``path``, which then only names it in messages.  ``plate``:
    the plate's top edge (slope, intercept), row = slope * col + intercept, when it is known
    (a rendered silhouette): the plate search is skipped; two finite numbers, else InputError
    (field ``plate``).  ``plate_px``: two points ((column, row), (column, row)) on the plate's
    top edge in the photo's pixels as shown (a manifest's ``plate_line_px``, checked as one:
    :func:`~soilcal.imaging.manifest.check_plate_line`, field ``plate_px``), the plate line
    measured on instead of the one the search would find (a card standing on the plate, a
    plate of the soil's colour); ``plate_line`` reports ``plate_px_from`` ("manifest", or
    "command line" for ``soilcal image pile --plate-line-px``).
    """
    if channel != "auto" and channel not in CUES:
        raise InputError(path, "channel", CHANNELS_EXPECTED, channel)
    if plate is not None:
        _check_given_plate(path, plate)
    if plate_px is not None:
        from soilcal.imaging.manifest import check_plate_line

        plate_px = check_plate_line(path, "plate_px", {"kind": "pile", "file": str(path), "plate_line_px": plate_px},
                                    path)
    tried = Tried(keep_masks=refusals is not None)
    with explained(path, refusals, tried):
        res = _measure_pile(path, threshold, keep_stages, channel, tried, image, plate, plate_px, plate_px_from)
    if channel == "auto" and res.confidence != "ok":
        res = _texture_flanks(res, tried.gray)
    if res.plate_ambiguous:
        res.confidence = "low"
    res.__dict__.pop("_levelled", None)  # the search's levelled images: not kept with the result
    return res


def _check_given_plate(path, plate):
    """A caller's ``plate`` (slope, intercept): two finite real numbers, else InputError naming it."""
    ok = (isinstance(plate, (tuple, list, np.ndarray)) and len(plate) == 2
          and all(isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)
                  and math.isfinite(v) for v in plate))
    if not ok:
        raise InputError(path, "plate", "the plate's top edge as (slope, intercept), two finite numbers, "
                         "row = slope * col + intercept", plate)


def _measure_pile(path, threshold, keep_stages, channel, tried: Tried, image=None,
                  plate=None, plate_px=None, plate_px_from="manifest") -> PileResult:
    if image is None:
        # a phone's 12 or 48 megapixels are measured at a working size (the angles do not depend
        # on it): decoded reduced by a whole factor where the format allows (a JPEG by 2, 4 or
        # 8 in its decoder), then scaled to the working size; the search then takes seconds
        # instead of minutes, and the photo is never held at full size as floats
        rgb, (w0, h0), depth, (factor, (ox, oy)) = read_photo_reduced(path, PILE_WORK_PIXELS if plate is None else None,
                                                                      with_depth=True, with_map=True)
    else:
        rgb, (h0, w0) = image, image.shape[:2]
        factor, ox, oy = 1, 0.0, 0.0
    read_w, read_h = rgb.shape[1], rgb.shape[0]
    scale = 1.0
    if plate is None and h0 * w0 > PILE_WORK_PIXELS:
        scale = math.sqrt(PILE_WORK_PIXELS / (h0 * w0))
        rgb = transform.rescale(rgb, math.sqrt(PILE_WORK_PIXELS / (rgb.shape[0] * rgb.shape[1])), channel_axis=-1,
                                anti_aliasing=True)
    # photo pixels (as shown) to the measured image's, pixel centres onto pixel centres: the
    # whole factor the photo was read reduced by (its partial pixel at the end of a side it does
    # not divide, or at the start: read_photo_reduced), then the rescale to the working size
    kx, ky = rgb.shape[1] / read_w, rgb.shape[0] / read_h

    def to_work(c, r):
        return ((c + 0.5) / factor + ox) * kx - 0.5, ((r + 0.5) / factor + oy) * ky - 0.5

    def to_photo(c, r):
        return ((c + 0.5) / kx - ox) * factor - 0.5, ((r + 0.5) / ky - oy) * factor - 0.5

    work = None
    if plate_px is not None:
        (c0, r0), (c1, r1) = (to_work(c, r) for c, r in plate_px)
        work = ((r1 - r0) / (c1 - c0), r0 - (r1 - r0) / (c1 - c0) * c0)
    res = _pile_on_lines(path, rgb, threshold, keep_stages, channel, tried, plate if work is None else work)
    if image is None:
        _check_levels_around(path, rgb, res, depth)
    res.work_scale = scale
    if plate_px is not None:
        res.plate_line, res.plate_line_px = plate_px_from, [[float(c), float(r)] for c, r in plate_px]
    else:
        slope, intercept = res.geometry[:2]
        ends = (0.0, rgb.shape[1] - 1.0)

        def in_photo(s, b):  # a line's two ends across the width, in the photo's pixels
            return [[round(v, 2) for v in to_photo(c, s * c + b)] for c in ends]

        res.plate_line = "found" if plate is None else "given"
        res.plate_line_px = in_photo(slope, intercept)
        if res.alternative is not None:
            s2, b2, left2, right2 = res.alternative
            other = in_photo(s2, b2)
            res.plate_ambiguous = (
                f"{path}: two plate lines carry the heap: the one measured on, tilted {roll_of(slope):+.2f} deg "
                f"({res.plate_line_px} in the photo's pixels; flanks {res.left_deg:.2f} / {res.right_deg:.2f} deg), "
                f"and one tilted {roll_of(s2):+.2f} deg ({other}; flanks {left2:.2f} / {right2:.2f} deg), as a "
                f"line through an object standing on the plate beside a foot (a scale card) and the plate's "
                f"edge further on is; the photo does not tell which is the plate's top edge: give it by hand, "
                f"two points on it as plate_line_px in the photo's manifest entry (or soilcal image pile "
                f"--plate-line-px C0 R0 C1 R1)")
        elif res.rival is not None:
            s2, b2, left2, right2, across2, across1 = res.rival
            other = in_photo(s2, b2)
            res.plate_ambiguous = (
                f"{path}: the line measured on as the plate's top edge, tilted {roll_of(slope):+.2f} deg "
                f"({res.plate_line_px} in the photo's pixels; flanks {res.left_deg:.2f} / {res.right_deg:.2f} deg), "
                f"runs across the photo less far (an edge along {across1:.0%} of its outer quarters) than a "
                f"second straight edge at the heap's foot tilted {roll_of(s2):+.2f} deg ({other}, {across2:.0%}; "
                f"flanks {left2:.2f} / {right2:.2f} deg on it), as the plate's edge does beyond a ruler or "
                f"strip lying askew in front of the heap's foot, and as a wall's or a shadow's edge crossing "
                f"the foot can" + _GIVE_LEVEL_LINE)
        elif res.stood_above is not None:
            s2, b2, left2, right2, why = res.stood_above
            other = in_photo(s2, b2)
            res.plate_ambiguous = (
                f"{path}: the heap stands on a straight edge tilted {roll_of(s2):+.2f} deg above the line measured "
                f"on ({other} in the photo's pixels; flanks {left2:.2f} / {right2:.2f} deg on it, which end there), "
                f"passed over as the plate's top edge ({why}); the "
                f"line measured on, tilted {roll_of(slope):+.2f} deg ({res.plate_line_px}; flanks "
                f"{res.left_deg:.2f} / {res.right_deg:.2f} deg), runs below the heap's foot, as the front edge of "
                f"a table askew under a plate narrower than the photo does" + _GIVE_LEVEL_LINE)
    return res


#: how a photo whose two candidate plate lines both carry the heap asks for the level one
_GIVE_LEVEL_LINE = ("; the photo does not tell which is level: give the plate's top edge by hand, two points on "
                    "it as plate_line_px in the photo's manifest entry (or soilcal image pile --plate-line-px "
                    "C0 R0 C1 R1)")


def _levels_around(rgb, res: PileResult, depth: int = 256) -> tuple[float, int]:
    """The grey levels the region measured spans, counted at the photo's ``depth`` (its grey
    levels: 256 at 8 bits), and the levels of the depth its own values use: the band from the
    plate line (following its tilt) up to 1.25 times the heap's height above it and a tenth of
    it (5 px at least) below, across the photo; the largest span, between the 0.5 and 99.5
    percentiles, of its luminance and of each colour channel (a heap differing from the wall in
    hue only spans its levels in a channel).  The depth its values use is, as for a 16-bit
    photo as a whole (:func:`soilcal.imaging.io._bit_depth_scaled`), the smallest of 8 bits to
    the photo's holding their :data:`~soilcal.imaging.io.DEPTH_PERCENTILE` percentile: 256 for
    any 8-bit photo."""
    from soilcal.imaging.io import DEPTH_PERCENTILE

    slope, intercept, _, _, hmax = res.geometry
    h, w = rgb.shape[:2]
    rr, cc = np.arange(h)[:, None], np.arange(w)[None, :]
    above = slope * cc + intercept - rr  # height above the plate line
    region = (above <= 1.25 * hmax) & (above >= -max(0.1 * hmax, 5.0))
    values = np.concatenate([color.rgb2gray(rgb)[region][:, None], rgb[region]], axis=1)
    lo, hi = np.percentile(values, [0.5, 99.5], axis=0)
    top = float(np.percentile(values, DEPTH_PERCENTILE)) * (depth - 1)
    used = min(depth, 2 ** max(8, int(np.ceil(np.log2(top + 1.0)))))
    return float((hi - lo).max() * (depth - 1)), used


def _check_levels_around(path, rgb, res: PileResult, depth: int = 256) -> None:
    """Refuse a heap measured in a region spanning fewer than an eighth of the grey levels its
    values use (:func:`_levels_around`; :data:`~soilcal.imaging.io.MIN_GREY_LEVELS` of 256 in
    an 8-bit photo), as a photo as a whole must (:func:`soilcal.imaging.io.read_photo_reduced`):
    the photo as a whole spans enough of them (a window, a lamp or a dark corner in view) while
    heap, plate and wall are under- or over-exposed, their edges quantisation steps (flanks 1
    deg off or more, as "ok").  ``depth``: the photo's grey levels (256 at 8 bits; a 16-bit
    photo's levels are counted at its 16 bits, where a band spanning a tenth of the range
    holds thousands of them)."""
    from soilcal.imaging.io import MIN_GREY_LEVELS

    levels, used = _levels_around(rgb, res, depth)
    need = MIN_GREY_LEVELS * used // 256
    if levels < need:
        raise InputError(path, "image", f"heap, plate and wall around the heap spanning at least {need} of "
                         f"{used} grey levels (an eighth of the range; exposed for the heap)",
                         f"{levels:.0f} levels around the heap (the photo is exposed for a brighter or darker part "
                         "of the scene)")


def _pile_on_lines(path, rgb, threshold, keep_stages, channel, tried: Tried, plate=None) -> PileResult:
    lum = _gray(rgb)
    tried.rgb, tried.gray = rgb, lum
    h, w = lum.shape
    plate_edges = None  # the edges a plate candidate must follow beside the heap
    tilted = None  # a straight edge across the photo tilted beyond the plate search
    beyond = []  # the straight edges tilted beyond the search (none looked for on a given plate)
    crossing = []  # colour edges crossing a line found at the middle column (_stood_above only)
    if plate is not None:
        lines = [(float(plate[0]), float(plate[1]))]
    else:
        ledges = feature.canny(lum, sigma=1.5)
        lines = plate_lines(lum, edges=ledges, paired=True)
        cedges = colour_edges(rgb)
        tried.edges = cedges
        # the photo's edges, each widened by a row: a plate line that runs on beside the heap
        # has one within 1 px (_plate_beside_heap, once per photo rather than per cue)
        all_edges = ledges | cedges
        plate_edges = ndi.binary_dilation(all_edges, np.ones((3, 1), bool))
        for ln in plate_lines(lum, edges=cedges, paired=True):
            if all(abs((ln[0] - o[0]) * w / 2 + ln[1] - o[1]) > 3 for o in lines):
                lines.append(ln)
            elif all(max(abs(ln[1] - o[1]), abs((ln[0] - o[0]) * (w - 1) + ln[1] - o[1])) > 3 for o in lines):
                # within 3 px of a line found at the middle column only: tilted against it and
                # crossing it there, a different edge (a plate's top edge crossed by a chord
                # across the heap), not tried in the search but a rival plate line for
                # _stood_above
                crossing.append(ln)
        beyond = _plate_beyond_search(all_edges, plate_edges, lines[:PLATE_CANDIDATES])
    tried.lines = list(lines[:PLATE_CANDIDATES])
    grays = _grays(rgb, CUES if channel == "auto" else (channel,), lum)
    if beyond:
        # the first on which a heap stands (each with the lines parallel to it just above: a
        # plate's top edge, fainter than its face's lower edge), else the one running furthest
        # across
        near = itertools.islice(((b, ln) for b in beyond for ln in _parallel_lines(all_edges, *b)), PLATE_CANDIDATES)
        tilted = next((b for b, ln in near if _heap_stands_on(path, rgb, lum, grays, ln, channel,
                                                                                 threshold, plate_edges)), None)
        standing = tilted is not None
        tilted = tilted if standing else beyond[0]  # the tilt of the edge running furthest across
        roll = roll_of(tilted[0])
        turn = level_it(roll)
        expected = (f"a plate edge within {PLATE_MAX_ROLL_DEG:.0f} deg of horizontal (the camera held within "
                    f"{PLATE_MAX_ROLL_DEG:.0f} deg of level: the plate search looks no further)")
        if standing:
            # a heap stands on the tilted edge, its flanks those of a heap in its frame: the
            # plate of a camera rolled beyond the search (a shadow's edge or a leaning ruler
            # across the wall of a level photo carries none, and the search measures that photo)
            tried.add("a straight edge across the photo, beyond the plate search, a heap standing on it",
                      line=tilted)
            raise InputError(path, "image", expected,
                             f"a straight edge across the photo, as a plate's is, tilted {roll:.1f} deg, a heap "
                             f"standing on it: {turn}, or take it again with the camera level")
        if not lines:
            raise InputError(path, "image", expected, f"none found; a straight edge across the photo is tilted "
                             f"{roll:.1f} deg, on which no heap was measured: if it is the plate's (the camera "
                             f"rolled), {turn}")
    if not lines:
        raise InputError(path, "image", "a straight base plate edge (or the plate's line given: "
                         "--plate-line-px X0 Y0 X1 Y1, a manifest's plate_line_px)", "none found")
    beside = []  # lines on which a heap was measured but which do not run on beside it
    refused = set()  # the lines every cue refused (numbered from 1)
    try:
        res = _on_plate_lines(path, rgb, lum, grays, lines[:PLATE_CANDIDATES], 1, channel, threshold, keep_stages,
                              tried, plate_edges, beside, refused)
        if plate is None:
            _judge_foot_below(res, grays)
            res.alternative = _plate_alternative(path, rgb, lum, grays, lines[:PLATE_CANDIDATES], res, channel,
                                                 threshold, plate_edges, refused)
            res.rival = _level_rival(plate_edges, lines, res, rgb)
            if res.alternative is None and res.rival is None:  # read only where neither is found
                res.stood_above = _stood_above(path, rgb, lum, grays, lines[:PLATE_CANDIDATES], beside, refused,
                                               res, channel, threshold, crossing)
        return res
    except InputError as refused:
        if not beside:
            raise _noting_tilt(refused, tilted) from None
        # no line both runs on beside the heap and gives a heap: the first line that gave one is
        # the plate (a plate hardly wider than the heap shows little edge beside it), said so
        n_line, slope, intercept, why = beside[0]
        try:
            res = _on_plate_lines(path, rgb, lum, grays, [(slope, intercept)], n_line, channel, threshold,
                                  keep_stages, tried, None, [])
        except InputError:
            raise _noting_tilt(refused, tilted) from None
        res.plate_beside = why
        _judge_foot_below(res, grays)
        res.rival = _level_rival(plate_edges, lines, res, rgb)
        return res


def _feet(geometry, w, h):
    """The photo's columns of the heap's two feet (left flank's, right flank's), where its flank
    lines meet its plate line, from a result's ``geometry`` (slope, intercept, left line, right
    line, height; the flank lines (u0, v0, du, dv) in the frame levelled on the plate line about
    the centre of the ``w`` x ``h`` photo)."""
    slope, intercept, lline, rline = geometry[:4]
    ang = math.atan(slope)
    cx, cy = w / 2 - 0.5, h / 2 - 0.5
    prow = cy + (slope * cx + intercept - cy) * math.cos(ang)
    # each flank line at height 0 (the plate row) in the levelled frame, turned back into the photo
    return [cx + (u0 - v0 / dv * du - cx) * math.cos(ang) - (prow - cy) * math.sin(ang)
            for u0, v0, du, dv in (lline, rline)]


#: a plate candidate above the line measured on is the heap's own lower outline where one step
#: of colour crosses it along at least this share of the heap's foot (:func:`_edge_under`,
#: :func:`_stood_above`)
STOOD_UNDER_MIN = 0.9


def _edge_under(rgb, res):
    """The share of the columns under the heap measured in ``res`` (between its feet, where its
    flank lines meet its plate line, less 5 % of that span at either end) across which the
    colour steps at that plate line as it does along the whole foot: per column the mean colour
    2-4 px above the line less that 2-4 px below it; the columns' median step, at least
    :data:`FACE_COLOUR_TOL` in some channel, and the share of columns whose step carries at least
    half of it along it (else 0).  About 1 for the line along which the heap's soil meets the
    plate under it (its lower outline, one step of colour from foot to foot); about 0 for a line
    across the heap's grain, which has soil on both sides, its steps scattered about none."""
    h, w = rgb.shape[:2]
    slope, intercept = res.geometry[:2]
    feet = sorted(_feet(res.geometry, w, h))
    q = 0.05 * (feet[1] - feet[0])
    cols = np.arange(w)
    cols = cols[(cols > feet[0] + q) & (cols < feet[1] - q)]
    rows = np.round(slope * cols + intercept).astype(int)
    keep = (rows - 4 >= 0) & (rows + 4 < h)
    cols, rows = cols[keep], rows[keep]
    if not len(cols):
        return 0.0
    above = np.mean([rgb[rows - k, cols, :3] for k in (2, 3, 4)], axis=0)
    below = np.mean([rgb[rows + k, cols, :3] for k in (2, 3, 4)], axis=0)
    steps = above - below
    step = np.median(steps, axis=0)
    if float(np.max(np.abs(step))) < FACE_COLOUR_TOL:
        return 0.0
    return float(np.mean(steps @ step >= 0.5 * float(step @ step)))


#: a rival plate line of :func:`_stood_above` must show its colour step beside the heap, beyond
#: each foot, along at least this share of the heap's foot (and 3 columns)
STOOD_BESIDE_MIN = 0.01
#: ... and the edge fitted there must be tilted against the line measured on by more than
#: :data:`PLATE_AMBIGUOUS_DEG` and more than this many standard deviations of its fitted tilt
STOOD_TILT_SD = 2.0
#: ... and lie within this many px of the line at both feet (edge location to a pixel)
STOOD_ON_LINE_PX = 1.5


def _edge_beside_fit(rgb, res):
    """The plate line of ``res`` followed beside the heap, beyond both its feet: (roll in deg,
    its standard deviation in deg) of the straight line fitted to where the colour steps across
    it, or None where either side has no such step.  From each foot outwards the columns
    whose colour 2-4 px above the line less that 2-4 px below carries at least half of the
    median step of the first of them (that at least :data:`FACE_COLOUR_TOL` in some channel),
    from 2 px beyond the foot (the heap's toe, rounded or blurred); the first :data:`STOOD_BESIDE_MIN` of the heap's foot (at least 3 columns) must all carry
    it, and the run is followed to its first column that does not.  In each such column the
    edge lies where the colour, projected on the step, falls from the colour above to that below
    most steeply within 6 px of the line; the straight line fitted to these must lie
    within :data:`STOOD_ON_LINE_PX` of the plate line at both feet (else the edge beside the heap
    is another, e.g. the plate's a few px below a moist band's top edge).  A plate's
    top edge (or a table's) runs on beyond the heap's feet, plate or table below, wall above; a
    band of moist soil along the heap's base, or a chord across the heap, ends at its flanks,
    with the same colour on both sides of it beyond them.  The fitted tilt rests on both sides,
    the whole width of the heap apart, not on the short stretch a line fitted by the plate
    search may have followed."""
    h, w = rgb.shape[:2]
    slope, intercept = res.geometry[:2]
    lo, hi = sorted(_feet(res.geometry, w, h))
    need = max(3, int(math.ceil(STOOD_BESIDE_MIN * (hi - lo))))
    clear = 2.0  # beyond the heap's toe, rounded or blurred
    offs = np.arange(-4, 5)
    cs, ps = [], []
    for cols in (np.arange(int(math.floor(lo - clear)), -1, -1), np.arange(int(math.ceil(hi + clear)), w)):
        rows = np.round(slope * cols + intercept).astype(int)
        inside = (rows - 6 >= 0) & (rows + 6 < h)
        n_in = len(cols) if inside.all() else int(np.argmin(inside))
        cols, rows = cols[:n_in], rows[:n_in]
        if len(cols) < need:
            return None
        prof = rgb[rows[:, None] + offs[None, :], cols[:, None], :3]  # columns x 9 rows x colour
        above, below = prof[:, :3].mean(axis=1), prof[:, -3:].mean(axis=1)
        steps = above - below
        step = np.median(steps[:need], axis=0)
        if float(np.max(np.abs(step))) < FACE_COLOUR_TOL:
            return None
        carry = steps @ step >= 0.5 * float(step @ step)
        run = len(carry) if carry.all() else int(np.argmin(carry))
        if run < need:
            return None
        # the colour projected on the step over the 13 rows about the line, high above the edge,
        # low below: the edge is where it falls most (to a tenth of a pixel by a parabola)
        on = rgb[rows[:run, None] + np.arange(-6, 7)[None, :], cols[:run, None], :3] @ step
        fall = on[:, :-1] - on[:, 1:]
        k = np.clip(np.argmax(fall, axis=1), 1, fall.shape[1] - 2)
        i = np.arange(run)
        a, b, c = fall[i, k - 1], fall[i, k], fall[i, k + 1]
        den = a - 2 * b + c
        sub = np.where(den < 0, 0.5 * (a - c) / np.where(den < 0, den, -1.0), 0.0)
        cs.append(cols[:run])
        ps.append(rows[:run] - 5.5 + k + np.clip(sub, -0.5, 0.5))
    cs, ps = np.concatenate(cs).astype(float), np.concatenate(ps)
    (s_fit, b_fit), cov = np.polyfit(cs, ps, 1, cov=True)
    # the edge found beside the heap is the line's own, not another near it (a moist band's top
    # edge a few px above the plate's: the plate's edge beside the heap)
    if max(abs((s_fit - slope) * f + b_fit - intercept) for f in (lo, hi)) > STOOD_ON_LINE_PX:
        return None
    sd = float(np.degrees(math.sqrt(max(float(cov[0, 0]), 0.0)) / (1.0 + s_fit * s_fit)))
    return roll_of(s_fit), sd


def _stood_above(path, rgb, lum, grays, lines, beside, refused, res, channel, threshold, crossing=()):
    """A plate candidate of ``lines`` above the line ``res`` was measured on, at the heap's
    foot, on which the heap stands but which the search passed over, tilted against the line
    measured on so that the flanks read more than :data:`PLATE_AMBIGUOUS_DEG` differently:
    (slope, intercept, left deg, right deg, why it was passed over) of the first such, or None.
    Passed over: tried after the line measured on (the luminance's candidates come before the
    colour edges'), or refused for running on too little beside the heap (``beside``,
    :func:`_plate_beside_heap`).  A plate narrower than the photo, set on a table top of the
    wall's colour, shows its top edge only along its own width (against the heap in hue alone
    where they are equally bright), which a heap filling most of the plate leaves little of
    beside its feet; the luminance's line below it running across the photo is then the
    table's front edge, askew against the plate, and the heap "stands" on it only through the
    strip of plate between the two: its flanks are read turned by the table's tilt.  Such a line
    has one step of colour across it along the heap's whole foot (:func:`_edge_under` at least
    :data:`STOOD_UNDER_MIN`): the heap's soil meets the plate under it there; a line across the
    heap's grain just above its foot, soil on both sides, or a chord from one foot up across
    it, has none, and is no rival; nor is a line within 3 px of the one measured on at either
    foot (the same edge fitted again, a little tilted, or one crossing it under the heap).  The
    line measured on must show such a step as well (the table's edge under the plate's strip
    does): one broken under the foot is hidden there by something lying before the heap, as
    the plate's edge is behind a ruler lying on it, whose top edge then runs along the foot
    above it and is no plate either.  "At the foot": crossing the heap's centre column above
    the line measured on by at most :data:`RIVAL_NEAR_FOOT` of the
    heap's height.  And the rival must run on beyond both feet as a plate's (or table's) edge
    does, tilted against the line measured on as fitted there (:func:`_edge_beside_fit`, by
    more than :data:`PLATE_AMBIGUOUS_DEG` and :data:`STOOD_TILT_SD` standard deviations): the
    top edge of a band of darker, moister soil along the heap's base also steps in colour from
    foot to foot, but ends at the flanks.  The photo then does not say which of the two lines
    is the plate's top edge, so the result is "low".  ``refused``: the numbers (from 1) of
    lines every cue refused in the search, which are skipped; ``crossing``: colour edges left
    out of the search as within 3 px of one of its lines at the middle column, but not at both
    ends of the width (tilted against it, crossing it there), rivals here after ``lines``."""
    slope, intercept = res.geometry[:2]
    hmax = res.geometry[4]
    h, w = lum.shape
    feet = _feet(res.geometry, w, h)
    mid = 0.5 * (feet[0] + feet[1])
    passed = {b[0]: b[3] for b in beside}
    if _edge_under(rgb, res) < STOOD_UNDER_MIN:
        return None  # the line measured on is hidden along part of the foot: something lies before it
    own = next((n for n, ln in enumerate(lines, 1) if ln[0] == slope and ln[1] == intercept), None)
    for n, (s2, b2) in enumerate(list(lines) + list(crossing), 1):
        rise = (slope - s2) * mid + intercept - b2  # how far above the measured line, at the heap's centre
        # at both feet more than 3 px above it: no second fit of the same edge, nor one crossing it
        apart = min((slope - s2) * f + intercept - b2 for f in feet) > 3.0
        if (n in refused and n not in passed) or not apart or rise > RIVAL_NEAR_FOOT * hmax or \
                abs(roll_of(slope) - roll_of(s2)) <= PLATE_AMBIGUOUS_DEG:
            continue
        try:
            other = _on_plate_lines(path, rgb, lum, grays, [(s2, b2)], n, channel, threshold, False,
                                    Tried(keep_masks=False), None, [])
        except InputError:
            continue
        if other.confidence != "ok" or _flank_difference(res, other) <= PLATE_AMBIGUOUS_DEG:
            continue
        if _edge_under(rgb, other) < STOOD_UNDER_MIN:
            continue
        fit = _edge_beside_fit(rgb, other)
        if fit is None:
            continue  # no step beside the heap beyond both feet: the line ends with the heap
        tilt, sd = fit[0] - roll_of(slope), fit[1]
        if abs(tilt) <= max(PLATE_AMBIGUOUS_DEG, STOOD_TILT_SD * sd):
            continue  # the edge beside the heap is not tilted against the line measured on beyond doubt
        if n > len(lines):
            why = (f"within 3 px at the middle column of a line of the plate search, crossing it there, and "
                   f"not tried")
        else:
            why = passed.get(n, f"line {n} of the plate search, tried after line {own} measured on, which "
                                f"carried the heap first")
        return float(s2), float(b2), other.left_deg, other.right_deg, why
    return None


#: flank difference (deg) between the heap measured on the plate line found and on a second
#: plate candidate above which the photo's plate is ambiguous (:func:`_plate_alternative`): a
#: line tilted by t against the plate turns both flanks by t, opposite ways, and a plate line
#: given by hand is held to half a degree (a point 1 px off at its shortest span)
PLATE_AMBIGUOUS_DEG = 0.5


def _plate_alternative(path, rgb, lum, grays, lines, res, channel, threshold, plate_edges, refused=()):
    """A second plate candidate of ``lines`` that carries the heap as the line ``res`` was
    measured on does, tilted against it by more than :data:`PLATE_AMBIGUOUS_DEG`, and on which
    the flanks read more than that differently: (slope, intercept, left deg, right deg) of the
    one meeting edges beside the heap along the largest share of the columns, else None.  Such a line is no chance chord: the heap stands on it with a foot, its flanks fit
    ("ok" by a cue search of their own) and it runs on beside the heap as an edge on both
    sides (:func:`_plate_beside_heap`), as the plate does; so does a line from a scale card's
    edge standing on the plate beside one foot to the plate's own edge beyond the other.  Such
    a line is no worse evidence of a plate than the line measured on where it runs on as an
    edge beside the heap along at least as large a share of the columns on either side
    (:func:`_edge_beside`): the photo then does not say which of the two is the plate, and no
    rule choosing between them is safe (the first line from the top can be either), so both
    are reported and the result is "low".  A line that meets edges beside the heap along a
    smaller share than the line measured on (a chord from a card's top edge, or from a plate
    face's lower edge, to the plate's top edge) leaves the result as it is.  Lines parallel to
    the one measured on (a plate's face, the table below a dark plate) turn no flank and are
    not judged.  A line with no side of the heap to judge (:func:`_edge_beside` None) shows no
    support beside the heap: such an alternative is not compared (a missing comparison is no
    tie), and where the line measured on has none, an alternative is flagged only where it meets
    edges beside the heap.  ``refused``: the numbers of the lines (from 1) on which the search
    measured no heap with any cue; measured alone they are refused again, so they are skipped."""
    slope = res.geometry[0]
    own = _edge_beside(plate_edges, res)
    # where the line measured on has no side to judge, any judged support beside the heap is more
    best, found = (own if own is not None else 0.0), None

    def rival(other):
        # an "ok" heap whose flanks read differently, on a line meeting edges beside it along
        # at least the share of the best so far (the first cue's heap is the one returned: the
        # further cues only confirm it or make it "low", so they are run only where it passes)
        if other.confidence != "ok" or _flank_difference(res, other) <= PLATE_AMBIGUOUS_DEG:
            return False
        share = _edge_beside(plate_edges, other)
        if share is None or (own is None and share <= 0.0):
            return False  # nothing beside the heap to compare
        return share >= best  # of several such lines, the one running on furthest beside the heap

    for n, (s2, b2) in enumerate(lines, 1):
        if n in refused or abs(math.degrees(math.atan(s2) - math.atan(slope))) <= PLATE_AMBIGUOUS_DEG:
            continue
        try:
            other = _on_plate_lines(path, rgb, lum, grays, [(s2, b2)], n, channel, threshold, False,
                                    Tried(keep_masks=False), plate_edges, [], wanted=rival)
        except InputError:
            continue
        if rival(other):
            best, found = _edge_beside(plate_edges, other), (float(s2), float(b2), other.left_deg, other.right_deg)
    return found


def _edge_beside(edges, res):
    """The smaller of the shares of the columns beside the heap measured in ``res``, left and
    right of it (more than 5 px beyond its feet, where its flank lines meet its plate line; a
    side of fewer than 10 such columns is not judged), where ``edges`` meet that plate line: 1
    for a plate's edge running on to the frame on both sides, less for a chord of two edges (a
    card's and the plate's) that meets each only near where it crosses it; None with no side judged (nothing beside the heap to judge the line by)."""
    h, w = edges.shape
    slope, intercept = res.geometry[:2]
    feet = _feet(res.geometry, w, h)
    cols = np.arange(w)
    rows = np.round(slope * cols + intercept).astype(int)
    out = []
    for beside in (cols < min(feet) - 5, cols > max(feet) + 5):
        ok = beside & (rows >= 0) & (rows < h)
        if beside.sum() >= 10:
            out.append(float(edges[rows[ok], cols[ok]].sum()) / float(beside.sum()))
    return min(out) if out else None


#: a straight edge competes with the plate line measured on as the level (:func:`_level_rival`)
#: where it crosses the heap's centre column within this share of the heap's height of it
RIVAL_NEAR_FOOT = 0.25


def _level_rival(edges, lines, res, rgb=None):
    """A straight edge of ``lines`` (the plate search's candidates) at the heap's foot that runs
    across the photo (:func:`_across`, at least :data:`ACROSS_MIN` of each outer quarter) further
    than the line ``res`` was measured on, tilted against it by more than
    :data:`PLATE_AMBIGUOUS_DEG`: (slope, intercept, left deg, right deg, its across share, the
    measured line's), the flanks re-levelled on it, or None.  A plate's top edge runs across the
    photo; a ruler or strip lying askew in front of the heap hides its foot and the plate's edge
    behind it, so the heap stands on the ruler's top edge alone, which ends with the ruler: the
    flanks were read turned by the ruler's tilt against the plate, with no second line carrying
    the heap (:func:`_plate_alternative`).  Which of the two is level the photo does not say
    (a plate's edge seen askew by perspective runs across as well), so such a result is "low".
    "At the foot": crossing the heap's centre column within :data:`RIVAL_NEAR_FOOT` of the
    heap's height of the line measured on.  Not a rival: the lower edge of the plate's front
    face under the line measured on (:func:`_face_below`, with ``rgb`` the measured image), which
    a thin face under a low heap puts within that reach, tilted by perspective, and which runs
    across further where the heap, of the face's colour, hides the plate's top edge."""
    if edges is None:
        return None
    slope, intercept = res.geometry[:2]
    hmax = res.geometry[4]
    own = _across(edges, slope, intercept)
    h, w = edges.shape
    # the heap's centre column: midway between its feet, where its flank lines meet the plate line
    feet = _feet(res.geometry, w, h)
    mid = 0.5 * (feet[0] + feet[1])
    found = None
    for s2, b2 in lines:
        turn = roll_of(slope) - roll_of(s2)  # the flanks on (s2, b2): left + turn, right - turn
        if abs(turn) <= PLATE_AMBIGUOUS_DEG or abs((s2 - slope) * mid + b2 - intercept) > RIVAL_NEAR_FOOT * hmax:
            continue
        share = _across(edges, s2, b2)
        if share >= ACROSS_MIN and share > own + 0.03 and (found is None or share > found[4]) and not (
                rgb is not None and _face_below(rgb, slope, intercept, s2, b2, feet)):
            found = (float(s2), float(b2), res.left_deg + turn, res.right_deg - turn, share, own)
    return found


#: the largest difference (any channel, of 1) between the median colour of a band under the heap
#: and the colour its two ends give there, and between the median colours of neighbouring
#: stretches of the band, for the band to be a plate's front face (:func:`_face_below`)
FACE_COLOUR_TOL = 0.05
#: stretches of equal width the band is cut into across the photo to see it run on unbroken
FACE_STRETCHES = 40


def _face_below(rgb, slope, intercept, s2, b2, feet) -> bool:
    """Whether the line (s2, b2) is the lower edge of a plate's front face under the line
    (slope, intercept) measured on: below it across the whole width, the band between them (1.5
    px in from each line) one face from end to end.  Its brightness may change along it (light
    falling off across the plate), so the band is cut into :data:`FACE_STRETCHES` stretches
    across the photo: the median colours of neighbouring stretches (those the band is wide
    enough in to give one) differ by less than
    :data:`FACE_COLOUR_TOL` in every channel (no end of an object in it), and under the heap
    (the middle half between its ``feet``) the band's median is within that of the colour
    interpolated there, column-wise, between its medians at the frame's two ends (their outer
    5 % of columns).  A ruler or strip askew before the heap is a short object: beyond its ends
    the band between its top edge and the plate's is the wall, a step of colour along the band
    and a colour at the ends other than the ruler's under the heap."""
    h, w = rgb.shape[:2]
    if not (b2 - intercept > 0 and (s2 - slope) * (w - 1) + b2 - intercept > 0):
        return False
    cols = np.arange(w)
    q = (max(feet) - min(feet)) / 4

    def band(sel, part=None):
        # part 0 / 1: the band's upper / lower half (columns where it is at least 2 px high)
        vals = []
        for c in cols[sel]:
            r0 = max(int(math.ceil(slope * c + intercept + 1.5)), 0)
            r1 = min(int(math.floor(s2 * c + b2 - 1.5)), h - 1)
            if part is not None and r1 > r0:
                rm = (r0 + r1) // 2
                r0, r1 = (r0, rm) if part == 0 else (rm + 1, r1)
            elif part is not None:
                continue
            if r1 >= r0:
                vals.append(rgb[r0:r1 + 1, c, :3])
        return np.median(np.concatenate(vals), axis=0) if vals else None

    sels = [(cols > min(feet) + q) & (cols < max(feet) - q), cols < 0.05 * w, cols >= 0.95 * w]
    xm, xl, xr = (float(cols[sel].mean()) for sel in sels)
    # the whole band, then its upper and its lower half on their own: a band on the wall behind
    # the plate (a shadow, a strip) over the plate's top edge and face has the heap's foot in its
    # upper half under the heap and the wall beside it, though the face filling its lower half
    # may make the whole band's colours agree
    for part in (None, 0, 1):
        mid, left, right = (band(sel, part) for sel in sels)
        if mid is None or left is None or right is None:
            if part is None:
                return False
            continue  # a half too thin somewhere to compare
        if float(np.max(np.abs(mid - (left + (right - left) * (xm - xl) / (xr - xl))))) >= FACE_COLOUR_TOL:
            return False
    cuts = np.linspace(0, w, FACE_STRETCHES + 1).round().astype(int)
    # a stretch at a frame's end where the band, thinning towards it, is no wider than the
    # 1.5 px left out along each line gives no colour
    stretches = [m for c0, c1 in zip(cuts[:-1], cuts[1:]) if (m := band((cols >= c0) & (cols < c1))) is not None]
    return len(stretches) >= 2 and float(np.max(np.abs(np.diff(np.array(stretches), axis=0)))) < FACE_COLOUR_TOL


def _heap_stands_on(path, rgb, lum, grays, line, channel, threshold, plate_edges) -> bool:
    """Whether a heap is measured on ``line`` (slope, intercept) as on a plate candidate (its
    foot on the line, the line running on beside it as an edge, its flanks in that frame within
    :data:`FLANK_RANGE`): a straight edge tilted beyond the plate search is the plate of a
    rolled camera only then; a shadow's edge or a leaning ruler across the wall of a level photo
    carries no heap."""
    try:
        _on_plate_lines(path, rgb, lum, grays, [line], 1, channel, threshold, False,
                        Tried(keep_masks=False), plate_edges, [])
    except InputError:
        return False
    return True


def _noting_tilt(refused: InputError, tilted) -> InputError:
    """``refused`` with a straight edge tilted beyond the plate search noted, where there is one:
    no heap was measured on it, so it may be a shadow's edge as well as a rolled plate."""
    if tilted is None or refused.field != "image":
        return refused
    roll = roll_of(tilted[0])
    return InputError(refused.path, refused.field, refused.expected,
                      f"{refused.got}; a straight edge across the photo is tilted {roll:.1f} deg, on which no heap "
                      f"was measured: if it is the plate's (the camera rolled beyond {PLATE_MAX_ROLL_DEG:.0f} deg), "
                      f"{level_it(roll)}", refused.note)


def _on_plate_lines(*args, **kwargs):
    """:func:`_search_plate_lines`, its refusal raised without the traceback of the search: the
    search's frame holds the refusals it collected (the one raised among them) and this photo's
    images, a reference cycle that would keep them alive after the measurement until a full
    garbage collection."""
    try:
        return _search_plate_lines(*args, **kwargs)
    except InputError as e:
        raise e.with_traceback(None)


def _search_plate_lines(path, rgb, lum, grays, lines, n_first, channel, threshold, keep_stages, tried, plate_edges,
                        beside, refused=None, wanted=None):
    """The heap measured on the first of ``lines`` (numbered from ``n_first``) on which a cue
    finds one (module text); a line refused only because it does not run on beside the heap
    (:func:`_plate_beside_heap`) is added to ``beside`` with the reason; ``refused``: a set
    given gets the number of each line every cue refused.  ``wanted``: a test of the first
    cue's heap (the one returned, whose geometry the further cues only confirm or make "low");
    a heap failing it is returned as the first cue measured it, unchecked by further cues (for
    a caller that would not use it whatever they found)."""
    h, w = lum.shape
    refusals = []  # every cue's refusal, the topmost line's first
    small = None  # the topmost line's refusal where its first two cues both saw a heap too small
    first = None  # the first cue's result, waiting for a second cue to cross-check it
    for n_line, (slope, intercept) in enumerate(lines, n_first):  # the plate top first; a faint one may hide behind a lower edge
        if beside and slope * w / 2 + intercept <= min(b[1] * w / 2 + b[2] for b in beside) + 3:
            # a heap stood on a line above this one already, which ran on too little beside it
            # (a plate hardly wider than the heap): a line of its grain, above its plate, is
            # no better; only a lower line can be the plate the other one was not
            continue
        band, split, levelled = _line_cues(grays, slope, intercept, (h, w))  # where heap and wall meet
        if not band.any():
            # a line at the frame's top or outside it (a plate line given off the photo): no
            # rows above it for a heap, nor a band for a cue's threshold
            tried.add(f"line {n_line}", None, (slope, intercept))
            e = InputError(path, "image", "one heap standing on the plate, inside the frame above its top edge",
                           f"no rows of the photo from 3 px to 35 % of its height above the plate line "
                           f"(row = {slope:.4g} x column + {intercept:.4g}, rows 0 to {h - 1} in the photo)")
            tried.refuse_last(e)
            refusals.append(e)
            if refused is not None:
                refused.add(n_line)
            continue
        # each channel's separability in the band, and its Otsu threshold there (a dark cue
        # segments the same channel in the same band at it: _pile_with's ``otsu``), read as the
        # search reaches the channel
        order = [(channel, "dark")] if channel != "auto" else _cue_order(split)
        checks = CUE_CHECKS
        line_refusals = []  # this line's
        dissent = None  # a credible cue that disagrees with the first, waiting for a third
        for ch, pol in order:
            if first is not None and checks == 0:
                break
            if first is not None and split[ch][0] < MIN_CUE_ETA:
                continue  # no clear split of the band: noise, neither a confirmation nor a refutation
            g = grays[ch] if pol == "dark" else 1.0 - grays[ch]
            try:
                res = _pile_with(path, rgb, g, ch, pol, band, slope, intercept, threshold,
                                 keep_stages and first is None, search=channel == "auto", tried=tried,
                                 label=f"line {n_line}, {ch}/{pol}", lum=lum, plate_edges=plate_edges,
                                 levelled=levelled, segmented=grays.segmented,
                                 otsu=split[ch][1] if channel == "auto" and pol == "dark" else None)
            except InputError as e:
                if e.field not in ("image", "left flank", "right flank", "plate line"):
                    raise
                if e.field == "plate line" and not any(b[0] == n_line for b in beside):
                    beside.append((n_line, slope, intercept, f"line {n_line}: {e.got}"))
                tried.refuse_last(e)
                # kept without its traceback: its frames hold this search's images and the
                # lists holding it, a reference cycle that would keep every photo's images
                # alive after its measurement until a full garbage collection
                e.__traceback__ = None
                refusals.append(e)
                line_refusals.append(e)
                if n_line == n_first and first is None and len(line_refusals) == 2 and all(
                        r.expected == CUT and getattr(r, "heap_beside", False) for r in line_refusals):
                    # the first two cues see a heap on the topmost line cut by the image border
                    # on one side, the wall beside it on the other: no lower line makes it whole
                    # (one slanting up across its flank would give it a foot)
                    raise line_refusals[0]
                checks -= first is not None
                continue
            if channel != "auto":
                return res
            if first is None:
                first = res
                if wanted is not None and not wanted(res):
                    return res
                continue
            checks -= 1
            if res.confidence != "ok":
                continue  # its own flank fits fail: it can neither confirm nor refute the first
            if _flank_difference(first, res) <= CUE_AGREEMENT_DEG:
                return _cross_checked(first, res, dissent)
            if dissent is not None:
                return _cross_checked(first, dissent)  # two credible cues against the first
            dissent = res  # the next credible cue decides between the two
        if first is not None:
            # no further credible cue measured a heap on this plate line: the first stands
            # alone, or against the one that disagrees
            return first if dissent is None else _cross_checked(first, dissent)
        if small is None and (len(line_refusals) >= 2 or channel != "auto") and all(
                getattr(r, "too_small", False) for r in line_refusals[:2]):
            small = line_refusals[0]
        if refused is not None:
            refused.add(n_line)
    if small is not None:
        # a heap too small for its flanks to be fitted stood on a line (two segmentations agree):
        # that, not what the lines above it were refused for, is what the photo lacks
        raise small
    raise _refusal(path, refusals, channel == "auto")


def _refusal(path, refusals, search) -> InputError:
    """The refusal of a photo on whose plate lines no cue measured a heap: the first cue's on
    the topmost line when the second cue there was turned down the same way (two segmentations
    see the same thing: as many heaps, a heap cut by the border, a shape no heap has), else
    the one refusal of a plate with no heap on it: the first two cues disagreeing is what an
    empty plate gives, each segmenting the wall's own noise into different shapes."""
    if not search or len(refusals) < 2:
        return refusals[0]

    def same(e):  # the kind of refusal, and for several heaps how many
        return e.field, e.expected, e.got if e.expected == "one heap" else None

    if same(refusals[0]) == same(refusals[1]):
        return refusals[0]
    return InputError(path, "image", "one heap standing on the plate", NONE_FOUND)


#: a heap photo larger than this (pixels) is measured reduced to it (the flank fits need no
#: more: 1630 x 1220 px, a heap some 800 px across)
PILE_WORK_PIXELS = 2_000_000

#: a cue search measures the heap with up to this many further cues after the first that
#: measures it; a further cue is credible when it splits the band clearly (eta at least
#: MIN_CUE_ETA) and its own flank fits pass.  The first credible one that agrees with the
#: first cue confirms it; when the first credible one disagrees, the next credible one decides
#: (it agrees: confirmed, the dissent recorded; it disagrees too, or none comes: "low")
CUE_CHECKS = 6
#: flank difference (deg) between two cues above which a result's confidence is "low": two
#: segmentations of one heap that disagree by more than this put one of them (the reported
#: one, or the check) more than half of it off, e.g. a flank whose shaded side or joined
#: shadow one cue takes for wall or heap
CUE_AGREEMENT_DEG = 1.0


def _flank_difference(a: PileResult, b: PileResult) -> float:
    return float(max(abs(a.left_deg - b.left_deg), abs(a.right_deg - b.right_deg)))


def _cross_checked(res: PileResult, check: PileResult, outvoted: PileResult | None = None) -> PileResult:
    """``res`` with a further cue's measurement of the same heap beside it (module constants);
    ``outvoted``: a cue that disagreed with both."""
    d = _flank_difference(res, check)
    res.cue_check, res.cue_check_deg = check.cue, d
    if outvoted is not None:
        res.cue_outvoted, res.cue_outvoted_deg = outvoted.cue, _flank_difference(res, outvoted)
    if d > CUE_AGREEMENT_DEG:
        res.confidence = "low"
    return res


def _pile_with(path, rgb, gray, cue, polarity, band, slope, intercept, threshold, keep_stages, search=True,
               tried: Tried | None = None, label: str = "", lum=None, plate_edges=None, levelled=None, otsu=None,
               segmented=None):
    """Measure with one cue: the heap is the class below Otsu's threshold of ``gray``.  In a
    cue search (``search``) the result must look like a heap; a channel chosen by the caller
    (e.g. a DEM silhouette, whatever its flanks) is measured as it is.  ``tried`` records the
    attempt (its segmented class and plate line) for a refusal's diagnostic image; ``lum``:
    the photo's luminance, in which a colour cue's edge is refined (:func:`_top_edge`);
    ``plate_edges``: the photo's edge map, in which a plate line found by the search must run
    on beside the heap (:func:`_plate_beside_heap`); ``levelled``: a dict in which the caller
    keeps the images levelled on this plate line (:func:`_level`: ``lum`` as "lum", a cue as
    (cue, polarity)) for its further cues and the checks of the heap; ``otsu``: Otsu's
    threshold of ``gray[band]`` where the caller has it already (:func:`_eta`); ``segmented``:
    a dict of the classes already segmented from the photo's cues by (cue, polarity, Otsu's
    threshold, or "adaptive" for the local threshold, which is the same on every plate line)
    (:class:`_Cues`), looked up before segmenting and added to."""
    if threshold == "otsu":
        t = filters.threshold_otsu(gray[band]) if otsu is None else otsu
        key = (cue, polarity, float(t))
    else:
        # a local threshold does not depend on the plate line (it is the cue's own, pixel by
        # pixel, over a block of half the image): one class per cue and polarity
        key = (cue, polarity, threshold)
    binary = None if segmented is None else segmented.get(key)
    if binary is None:
        binary = open_fill(gray < t) if threshold == "otsu" else _binary(path, gray, threshold)
        if segmented is not None:
            segmented[key] = binary
    if tried is not None:
        tried.add(label or f"{cue}/{polarity}", binary, (slope, intercept))
    comp = _components_on_plate(path, binary, slope, intercept, "heap")
    if plate_edges is not None:
        _plate_beside_heap(path, plate_edges, comp, slope, intercept)
    lev, prow, roll = _level(comp, slope, intercept)

    def level_once(key, img):
        # ``img`` levelled on this plate line, kept in ``levelled`` under ``key`` ("lum", or the
        # cue and its polarity) for the line's further cues and the checks of its heap
        if levelled is None:
            return _level(img, slope, intercept)[0]
        if key not in levelled:
            levelled[key] = _level(img, slope, intercept)[0]
        return levelled[key]

    glev = level_once("lum" if gray is lum else (cue, polarity), gray)
    llev = level_once("lum", lum) if lum is not None and cue != "gray" else None
    cols = np.nonzero(lev.max(axis=0) >= 0.5)[0]
    cu, rv, *rl = _top_edge(lev, cols.min(), cols.max() + 1, glev, llev)
    v = prow - rv
    hmax = np.percentile(v, 99.5)
    apex = np.median(cu[v > 0.97 * hmax])
    band = (v > BAND[0] * hmax) & (v < BAND[1] * hmax)
    lsel, rsel = band & (cu < apex), band & (cu > apex)
    vs = [v] + [prow - r for r in rl]
    cols_in = {"left flank": int(lsel.sum()), "right flank": int(rsel.sum())}
    if min(cols_in.values()) < MIN_FLANK_COLUMNS:
        # the heap is too small in the photo for a line fit of a flank: say so, with the size at
        # which both flanks would span enough columns (they grow in proportion to the heap)
        short = [k for k, n in cols_in.items() if n < MIN_FLANK_COLUMNS]
        need = hmax * MIN_FLANK_COLUMNS / max(min(cols_in.values()), 1)
        e = InputError(path, short[0], f"a heap large enough in the photo to fit its flanks: each flank over at "
                       f"least {MIN_FLANK_COLUMNS} columns between {BAND[0]:.0%} and {BAND[1]:.0%} of the "
                       f"heap's height", f"a heap {hmax:.0f} px high, its flanks over {cols_in['left flank']} and "
                       f"{cols_in['right flank']} columns ({cue}/{polarity}): too small; take the photo closer "
                       f"or at a higher resolution, so that the heap is at least {math.ceil(need)} px high")
        e.too_small = True
        raise e
    left, lline, lp = _straighter(path, cu, vs, lsel, "left flank")
    right, rline, rp = _straighter(path, cu, vs, rsel, "right flank")
    ang = np.array([left, right])
    # confidence: share of each flank's points on its line, their scatter about it
    used = min(len(lp) / max(lsel.sum(), 1), len(rp) / max(rsel.sum(), 1))
    rms = max(_line_rms(lp, lline), _line_rms(rp, rline))
    if search and (not (FLANK_RANGE[0] <= ang.min() and ang.max() <= FLANK_RANGE[1]) or hmax < MIN_RISE * lev.shape[0]):
        raise InputError(path, "image", f"a heap: flanks between {FLANK_RANGE[0]:.0f} and "
                         f"{FLANK_RANGE[1]:.0f} deg, at least 3 % of the image high",
                         f"flanks {left:.1f} and {right:.1f} deg ({rms:.1f} px from their lines), {hmax:.0f} px "
                         f"high ({cue}/{polarity})")
    shares = [_outside_share(glev, prow, line, side, BAND[0] * hmax, BAND[1] * hmax)
              for line, side in ((lline, -1.0), (rline, 1.0))]
    # the larger judged share (max() would return a NaN that comes first)
    outside = float(np.nanmax(shares)) if np.isfinite(shares).any() else float("nan")
    low = used < FLANK_USED_MIN or rms > FLANK_RMS_MAX or abs(left - right) > 12.0 or outside > FLANK_OUTSIDE_MAX
    st = None
    if keep_stages:
        st = Stages(rgb, gray, binary, lev, [lline + ("left",), rline + ("right",)], [lp, rp])
        st.plate_row = prow
    out = PileResult(str(path), float(ang.mean()), left, right, float(ang.std(ddof=1)), float(roll),
                     f"{cue}/{polarity}", float(used), float(rms), "low" if low else "ok", st,
                     flank_outside_share=float(outside),
                     geometry=(float(slope), float(intercept), lline, rline, float(hmax)))
    # the images levelled on this plate line, for the checks of this heap (_judge_foot_below,
    # _texture_flanks); not a field, so not reported, and dropped by measure_pile
    out._levelled = levelled if levelled is not None else {}
    return out


#: plate lines tried, topmost first (the luminance's, then the colour edges'): a wide textured
#: heap lines up near-horizontal edges of its grain above the plate, which are refused
PLATE_CANDIDATES = 8
#: a plate line found by the search must be an edge along at least this share of the columns
#: on either side of the heap (:func:`_plate_beside_heap`): a faint plate edge (a light plate
#: before a light wall) is one along a third of them, a line of the heap's grain along none
PLATE_BESIDE_MIN = 0.15


def _plate_beside_heap(path, edges, comp, slope, intercept):
    """Refuse a plate candidate that is no edge beside the heap ``comp`` standing on it: a
    plate's top edge runs on to either side of the heap (to the frame's border), whereas a line
    of the heap's own grain or clods (near-horizontal edges that a wide, textured heap lines up
    by chance) ends with it and cuts the heap above its foot, so the heap's lower part is lost
    and its flanks read at the line's tilt.  On either side, the share of the columns beside
    the heap (more than 5 px from it) where ``edges`` (widened by a row on either side) meet the line must
    be at least :data:`PLATE_BESIDE_MIN`; a side with fewer than 10 such columns is not judged."""
    h, w = edges.shape
    cols_heap = np.nonzero(comp.any(axis=0))[0]
    cols = np.arange(w)
    rows = np.round(slope * cols + intercept).astype(int)
    for side, beside in (("left", cols < cols_heap.min() - 5), ("right", cols > cols_heap.max() + 5)):
        if beside.sum() < 10:
            continue
        ok = beside & (rows >= 0) & (rows < h)
        share = float(edges[rows[ok], cols[ok]].sum()) / float(beside.sum())
        if share < PLATE_BESIDE_MIN:
            raise InputError(path, "plate line", "a heap standing on a plate edge that runs on beside it",
                             f"a line through the heap, an edge along {share:.0%} of the columns {side} of it")


#: strips beside a fitted flank line, in px along its normal (negative: into the heap): the
#: heap just inside, the edge's near outside, and the wall further out (_outside_share)
OUTSIDE_STRIPS = {"inside": (-8, -3), "near": (3, 8), "wall": (30, 45)}
#: a flank whose near outside strip is more than this share of the way from the wall's level
#: to the heap's is "low": the strip lies nearer the heap's level than the wall's, so the
#: edge (the mid-level crossing) is further out than the line: the fitted edge runs inside the
#: heap, e.g. a shaded flank as dark as the wall was lost to it and the flank reads steeper
FLANK_OUTSIDE_MAX = 0.5
#: the heap-to-wall step (inside strip minus wall strip, cue units 0-1) below which a flank's
#: outside share is not judged (NaN): too weak to tell a level from the noise
OUTSIDE_MIN_STEP = 0.05


def _outside_share(glev, prow, line, side, v_lo, v_hi, n=60):
    """Where the levelled cue image ``glev`` stands just outside a flank's fitted ``line``
    (u0, v0, du, dv in columns and height above the plate row ``prow``) between heights
    ``v_lo`` and ``v_hi``: (near - wall) / (inside - wall) with the medians of the
    :data:`OUTSIDE_STRIPS` (``side`` -1: the left flank, outward is towards smaller columns).
    0 when the wall begins right outside the line, 1 when the heap continues past it."""
    u0, v0, du, dv = line
    d = np.array([du, dv], float) / math.hypot(du, dv)
    if abs(d[1]) < 1e-6:
        return float("nan")
    nrm = np.array([-d[1], d[0]])
    if np.sign(nrm[0]) != np.sign(side):
        nrm = -nrm
    vs = np.linspace(v_lo, v_hi, n)
    base = np.column_stack([u0 + (vs - v0) / d[1] * d[0], vs])

    def level(lo, hi):
        pts = np.concatenate([base + k * nrm for k in range(lo, hi + 1)])
        return float(np.median(ndi.map_coordinates(glev, [prow - pts[:, 1], pts[:, 0]], order=1,
                                                   mode="nearest")))

    inside, near, wall = (level(*OUTSIDE_STRIPS[k]) for k in ("inside", "near", "wall"))
    if abs(inside - wall) < OUTSIDE_MIN_STEP:
        return float("nan")
    return (near - wall) / (inside - wall)


#: heights (px above the plate line, negative: below it) of the two bands in which a flank is
#: read (_foot_below_share): the heap's foot above the line, and the flank's line carried on
#: below it
FOOT_BANDS = {"above": (3, 12), "below": (-12, -3)}
#: columns beside a flank's line (px, outward positive) read as the heap's side and the other
#: side in the band above the line
FOOT_SIDES = {"inside": (-8, -3), "outside": (3, 8)}
#: below the line: the edge across the flank's line carried on is the step between the means
#: over FOOT_EDGE_PX (from, to) px either side of it, counted square to the line; the same step
#: FOOT_BESIDE_PX px to either side of the line is what lies beside it (an edge that does not
#: run along the flank, e.g. a plate's end, shows in both alike)
FOOT_EDGE_PX, FOOT_BESIDE_PX = (2, 4), 8
#: both flanks carrying their edge on below the plate line, along their own lines, by more than
#: this share of their step above it: the heap runs on below the line, which is no plate it
#: stands on; the result is "low"
FOOT_BELOW_MAX = 0.08


def _foot_below_share(glev, prow, line, side):
    """How far a flank's edge runs on below the plate line, whatever the colour of what lies
    beside it there: in the levelled cue image ``glev`` with the plate at row ``prow``, the
    flank's fitted ``line`` (u0, v0, du, dv; ``side`` -1 for the left flank) is carried on below
    the line (:data:`FOOT_BANDS` "below").  Each row there is read across the line, at distances
    from it counted square to it, and the rows' median taken: an edge running along the flank
    stays on the line in every row, one at another angle (a plate's end or face) is spread over
    the distances.  The share is the step across the line (means over :data:`FOOT_EDGE_PX` px either
    side) less the larger such step :data:`FOOT_BESIDE_PX` px to either side, over the
    heap-to-wall step just above the line (:data:`FOOT_BANDS` "above", :data:`FOOT_SIDES`):
    about |heap - beside| / |heap - wall| where the heap runs on below the line, about 0 or
    below where it does not.  NaN where the step above is under :data:`OUTSIDE_MIN_STEP`.  A
    heap running on below the line beside something of its own colour leaves no edge to find."""
    u0, v0, du, dv = line
    if abs(dv) < 1e-6:
        return float("nan")

    def rows(band):
        vs = np.arange(FOOT_BANDS[band][0], FOOT_BANDS[band][1] + 1, dtype=float)
        return vs, u0 + (vs - v0) / dv * du

    across = float(np.hypot(du, dv) / abs(dv))  # columns per px square to the line

    def read(vs, us, ks):
        uu = (us[:, None] + side * across * ks[None, :]).ravel()
        rr = np.repeat(prow - vs, len(ks))
        return ndi.map_coordinates(glev, [rr, uu], order=1, mode="nearest").reshape(len(vs), len(ks))

    vs, us = rows("above")
    lo, hi = FOOT_SIDES["inside"], FOOT_SIDES["outside"]
    step = float(np.median(read(vs, us, np.arange(lo[0], lo[1] + 1.0)))
                 - np.median(read(vs, us, np.arange(hi[0], hi[1] + 1.0))))
    if abs(step) < OUTSIDE_MIN_STEP:
        return float("nan")
    reach = FOOT_BESIDE_PX + FOOT_EDGE_PX[1]
    ks = np.arange(-reach, reach + 1, dtype=float)
    prof = np.median(read(*rows("below"), ks), axis=0)

    def edge(at):
        i, (a, b) = reach + at, FOOT_EDGE_PX
        return abs(prof[i - b:i - a + 1].mean() - prof[i + a:i + b + 1].mean())

    return (edge(0) - max(edge(-FOOT_BESIDE_PX), edge(FOOT_BESIDE_PX))) / abs(step)


def _judge_foot_below(res: PileResult, grays) -> None:
    """Set ``res.foot_below_share`` (the smaller flank's :func:`_foot_below_share` in the cue
    the heap was measured in) and make ``res`` "low" where both flanks run on below the plate
    line (above :data:`FOOT_BELOW_MAX`)."""
    if res.geometry is None:
        return
    slope, intercept, lline, rline, _ = res.geometry
    ch = res.cue.split("/")[0]
    # the cue image as the heap's search levelled it, where it did (a heap darker than the wall)
    glev = getattr(res, "_levelled", {}).get("lum" if ch == "gray" else (ch, "dark"))
    if glev is None:
        glev = _level(grays[ch], slope, intercept)[0]
    prow = _levelled_plate_row(glev.shape, slope, intercept)
    shares = [_foot_below_share(glev, prow, ln, side) for ln, side in ((lline, -1.0), (rline, 1.0))]
    res.foot_below_share = float(min(shares)) if np.isfinite(shares).all() else float("nan")
    if res.foot_below_share > FOOT_BELOW_MAX:
        res.confidence = "low"


def _straighter(path, u, vs, sel, label):
    """The line fit (:func:`_fit`) of the flank ``sel`` on the cue's own edge ``vs[0]``, or on
    the edge refined in luminance ``vs[1]`` (where a colour cue segmented the heap,
    :func:`_top_edge`) when that one's inliers lie clearly closer to their line (RMS below
    :data:`LUM_EDGE_STRAIGHTER` times the cue's).  A luminance edge is sharper where the
    luminance steps across the heap's outline, and follows something else where it does not
    (a textured wall of the heap's brightness, a cast shadow joined to a dark flank): then its
    line is no straighter than the cue's."""
    fits = [_fit(path, u[sel], v[sel], label) for v in vs]
    rms = [_line_rms(f[2], f[1]) for f in fits]
    return fits[1] if len(fits) > 1 and rms[1] < LUM_EDGE_STRAIGHTER * rms[0] else fits[0]


#: a flank's luminance-refined edge replaces the cue's when the RMS of its line fit is below
#: this share of the cue's (_straighter)
LUM_EDGE_STRAIGHTER = 0.8


def _line_rms(pts, line):
    u0, v0, du, dv = line
    return float(np.sqrt(np.mean(((pts[:, 0] - u0) * dv - (pts[:, 1] - v0) * du) ** 2)))


#: texture of the luminance (_texture_maps): the fine detail |L - G(L)| of a Gaussian high-pass
#: at the first scale (px), averaged by a Gaussian at the second
TEXTURE_SIGMAS = (1.0, 3.0)
#: the heap's texture level on a row is read this many px inside the cue's flank line
TEXTURE_INSIDE = (8, 30)
#: a row counts when the heap's texture exceeds the wall's by this share of the heap's
TEXTURE_MIN_CONTRAST = 0.3
#: the wall's texture level is read above the apex: from 7 averaging sigmas above it (clear of
#: the apex's own edge), over this many px upward and this many px to each side (or a quarter
#: and a half of the heap's height, where larger)
TEXTURE_WALL = (60, 100)


def _texture_maps(llev):
    """Texture energy of a levelled (smoothed) luminance image: ``absolute`` (the averaged fine detail, see
    :data:`TEXTURE_SIGMAS`) and ``relative`` (the same over the local brightness, floor 0.02):
    granular soil shows grain down to the pixel, shaded or lit, where a painted or plain wall
    shows only the camera's noise; relative to the brightness, the grain of a shaded flank is
    as strong as that of a lit one."""
    hp, av = TEXTURE_SIGMAS
    e = filters.gaussian(np.abs(llev - filters.gaussian(llev, hp)), av)
    return {"absolute": e, "relative": e / (filters.gaussian(llev, av) + 0.02)}


def _texture_edge(path, e, prow, line, side, hmax, label):
    """A flank located in the texture map ``e`` (levelled): on every row of the flank band
    (:data:`BAND`), the first place outward from :data:`TEXTURE_INSIDE` px inside the cue's
    ``line`` where the texture falls below the midpoint of the heap's (read inside the line) and
    the wall's (the median above the apex, :data:`TEXTURE_WALL`); these points fitted as a flank
    (:func:`_fit`).  Returns (angle, line, share of the points on it, their RMS px) or None
    when the map does not tell heap from wall."""
    u0, v0, du, dv = line
    if abs(dv) < 1e-9:
        return None
    h, w = e.shape
    at = lambda v: u0 + (v - v0) / dv * du  # noqa: E731 - the line's column at height v
    r1 = int(prow - hmax - 7 * TEXTURE_SIGMAS[1])
    r0 = int(r1 - max(TEXTURE_WALL[0], hmax / 4))
    half = max(TEXTURE_WALL[1], hmax / 2)
    c0, c1 = int(at(hmax) - half), int(at(hmax) + half)
    r0, c0, c1 = max(r0, 0), max(c0, 0), min(c1, w)
    if r1 - r0 < 5 or c1 - c0 < 5:
        return None
    wall = float(np.median(e[r0:r1, c0:c1]))
    reach = int(hmax / math.tan(math.radians(FLANK_RANGE[0])))  # the foot of the flattest flank
    us, vs = [], []
    for v in np.arange(BAND[0] * hmax, BAND[1] * hmax, 1.0):
        r = int(round(prow - v))
        if not 0 <= r < h:
            continue
        ul = at(v)
        ins = np.round(ul - side * np.arange(*TEXTURE_INSIDE)).astype(int)
        ins = ins[(ins >= 0) & (ins < w)]
        if ins.size < 5:
            continue
        heap = float(np.median(e[r, ins]))
        if heap - wall < TEXTURE_MIN_CONTRAST * heap:
            continue
        mid = 0.5 * (heap + wall)
        cols = np.round(ul - side * TEXTURE_INSIDE[0] + side * np.arange(reach)).astype(int)
        cols = cols[(cols >= 0) & (cols < w)]
        k = _mid_crossing(e[r, cols], mid, 1.0, 0, None)  # samples outward from cols[0]
        if k is None:
            continue
        us.append(cols[0] + side * k)
        vs.append(v)
    if len(us) < 20:
        return None
    try:
        ang, tline, pts = _fit(path, np.asarray(us), np.asarray(vs), label)
    except InputError:  # a degenerate point set: no texture line, the cue's stays
        return None
    return ang, tline, len(pts) / len(us), _line_rms(pts, tline)


def _texture_flanks(res: PileResult, lum) -> PileResult:
    """A low-confidence heap with a flank located again in the luminance's texture where the cue
    lost part of it: the failure of a shaded flank as dark as the wall behind it, which no
    colour or brightness cue separates from the wall (its line then runs inside the heap and
    reads steep).  A flank takes the texture's line when that line is fitted as well as an
    "ok" flank must be (:data:`FLANK_USED_MIN`, :data:`FLANK_RMS_MAX`; the better of the two
    maps of :func:`_texture_maps`) and is flatter than the cue's by more than
    :data:`CUE_AGREEMENT_DEG`, its foot further out: the heap goes on where the cue saw wall.
    A steeper texture line (a textured wall, a cast shadow joined to the flank) changes
    nothing.  The result stays "low" (the texture edge is blurred by its averaging scale and
    is no check of itself); ``texture_flanks`` names the flanks moved, ``flank_points_used``
    and ``flank_rms_px`` stay those of the cue's fits.  ``lum``: the smoothed luminance the
    cues were read in (:func:`_gray`)."""
    if res.geometry is None:
        return res
    slope, intercept, lline, rline, hmax = res.geometry
    llev = getattr(res, "_levelled", {}).get("lum")  # as the heap's search levelled it, where it did
    if llev is None:
        llev = _level(lum, slope, intercept)[0]
    prow = _levelled_plate_row(llev.shape, slope, intercept)
    maps = _texture_maps(llev)
    ang = {"left": res.left_deg, "right": res.right_deg}
    lines = {"left": lline, "right": rline}
    moved = []
    for name, side in (("left", -1.0), ("right", 1.0)):
        fits = [f for f in (_texture_edge(res.path, e, prow, lines[name], side, hmax, f"{name} flank")
                            for e in maps.values()) if f is not None]
        if not fits:
            continue
        a, tline, used, rms = min(fits, key=lambda f: f[3])
        if used < FLANK_USED_MIN or rms > FLANK_RMS_MAX or ang[name] - a <= CUE_AGREEMENT_DEG:
            continue
        ang[name], lines[name] = a, tline
        moved.append(name)
    if not moved:
        return res
    res.left_deg, res.right_deg = float(ang["left"]), float(ang["right"])
    pair = np.array([res.left_deg, res.right_deg])
    res.angle_deg, res.spread_deg = float(pair.mean()), float(pair.std(ddof=1))
    res.texture_flanks = " ".join(moved)
    res.geometry = (slope, intercept, lines["left"], lines["right"], hmax)
    if res.stages is not None:
        res.stages.lines = [lines["left"] + ("left",), lines["right"] + ("right",)]
    return res


def measure_piles(paths, threshold="otsu", keep_stages=False, channel="auto", refusals=None, plate_px=None,
                  plate_px_from="manifest"):
    """One group of heap photos: the mean of the flanks of its photos measured with confidence
    "ok", a photo flagged "low" set aside with its reason (:func:`pile_summary` with
    ``ok_only``; a group with no photo "ok" is refused).  ``refusals``: :func:`measure_pile`;
    ``plate_px``: one given plate line or None per photo, as :func:`measure_pile` takes it,
    ``plate_px_from`` where they came from.  The refusal of a group with no photo "ok" carries
    every photo's result as ``results`` (the callers write their figures, which its reasons name)."""
    per = plate_px if plate_px is not None else [None] * len(paths)
    res = [measure_pile(p, threshold, keep_stages, channel, refusals, plate_px=q, plate_px_from=plate_px_from)
           for p, q in zip(paths, per)]
    try:
        return pile_summary(res, ok_only=True), res
    except InputError as e:
        e.results = res  # a group of low photos only: their results, for the figures its reasons point to
        raise


def low_reason(r: PileResult) -> str:
    """Why the heap photo ``r`` (:class:`PileResult`) is "low" ("" for an "ok" one): the plate
    ambiguity (naming both lines and the plate line to give), else the flank fit, the flanks'
    difference, the heap continuing past a flank or the further cue that disagrees; the way out
    is the plate line given by hand, or for a photo measured on one given (``plate_line``
    "manifest" or "command line"), checking its two points."""
    if r.confidence == "ok":
        return ""
    if r.plate_ambiguous:
        return r.plate_ambiguous
    why = []
    if r.flank_points_used < FLANK_USED_MIN:
        why.append(f"{r.flank_points_used:.0%} of a flank's points on its line, under {FLANK_USED_MIN:.0%}")
    if r.flank_rms_px > FLANK_RMS_MAX:
        why.append(f"a flank's points {r.flank_rms_px:.1f} px from its line, above {FLANK_RMS_MAX:g} px")
    if abs(r.left_deg - r.right_deg) > 12.0:
        why.append(f"flanks {r.left_deg:.1f} and {r.right_deg:.1f} deg, more than 12 deg apart")
    if r.flank_outside_share > FLANK_OUTSIDE_MAX:
        why.append(f"{r.flank_outside_share:.0%} of the heap's contrast found past a flank's line, "
                   f"above {FLANK_OUTSIDE_MAX:.0%}")
    if r.foot_below_share > FOOT_BELOW_MAX:
        why.append(f"the heap runs on below the plate line (foot_below_share {r.foot_below_share:.2f}, above "
                   f"{FOOT_BELOW_MAX:g}: both flanks' edges carry on along their lines past it): the line "
                   f"{r.plate_line_px} passes behind the heap (a table top's or wall's edge), the plate it stands "
                   f"on is lower")
    if r.cue_check and r.cue_check_deg > CUE_AGREEMENT_DEG:
        why.append(f"the cue {r.cue_check} puts a flank {r.cue_check_deg:.1f} deg away, more than "
                   f"{CUE_AGREEMENT_DEG:g} deg")
    if not why and r.cue_outvoted:
        why.append(f"the cue {r.cue_outvoted} disagrees by {r.cue_outvoted_deg:.1f} deg and no further cue decides")
    if not why:
        why.append("its cues disagree and none decides")
    if r.plate_line in ("manifest", "command line"):
        # measured on the plate line given: giving it again is no way out
        given = "its manifest entry's plate_line_px" if r.plate_line == "manifest" else "--plate-line-px"
        return "; ".join(why) + f" on the plate line given ({given} {r.plate_line_px}; read its figure, " \
            "--figures: check those two points on the plate's top edge, or retake the photo)"
    return "; ".join(why) + " (read its figure, --figures; retake the photo, or give its plate line if the " \
        "plate was misread: plate_line_px in the manifest, --plate-line-px)"


def pile_summary(res, ok_only=False) -> dict:
    """Mean of every flank of the measured photos ``res`` (:class:`PileResult`), the mean left
    and right flank, and the flanks' sample std (``spread_deg``).  With ``ok_only`` (a group
    of photos, :func:`measure_piles`) only the photos of confidence "ok" count: each other one
    is listed in ``set_aside`` (path, reason: :func:`low_reason`), ``n_photos`` counts those
    used, and a group with none "ok" is refused naming each photo and its reason.  ``photos``
    holds every photo's result."""
    used = [r for r in res if r.confidence == "ok"] if ok_only else list(res)
    aside = [{"path": r.path, "reason": low_reason(r)} for r in res if ok_only and r.confidence != "ok"]
    if not used:
        raise InputError(res[0].path if len(res) == 1 else "<photo group>", "confidence",
                         "at least one photo of the group measured with confidence ok (a photo flagged low "
                         "is not averaged into the group's angle)",
                         "; ".join(f"{a['path']}: low, {a['reason']}" for a in aside))
    lefts = np.array([r.left_deg for r in used])
    rights = np.array([r.right_deg for r in used])
    allf = np.concatenate([lefts, rights])
    out = {
        "angle_deg": float(allf.mean()),
        "left_deg": float(lefts.mean()),
        "right_deg": float(rights.mean()),
        "spread_deg": float(allf.std(ddof=1)) if allf.size > 1 else 0.0,
        "n_photos": len(used),
        "photos": [r.as_dict() for r in res],
    }
    if ok_only:
        out["set_aside"] = aside
    return out


#: the most a plate line may be tilted in the photo (deg either way): the camera's roll the plate
#: search takes out (a hand-held phone rolls by several degrees)
PLATE_MAX_ROLL_DEG = 15.0


def roll_of(slope) -> float:
    """The camera roll (deg, counter-clockwise positive) that shows a level line at ``slope``
    (rows per column, rows down the image)."""
    return -float(np.degrees(np.arctan(slope)))


def level_it(roll) -> str:
    """What levels a photo taken with the camera rolled ``roll`` deg (:func:`roll_of`): the
    one wording of every refusal that names a roll."""
    return f"rotate the photo {abs(roll):.0f} deg {'clockwise' if roll > 0 else 'counter-clockwise'} to level it"


def hough_peaks(hspace, angles, dists, num_peaks, min_distance, threshold, min_angle=10):
    """The peaks of a straight-line Hough accumulator: the same (votes, angles, distances) as
    ``skimage.transform.hough_line_peaks(hspace, angles, dists, min_distance=min_distance,
    min_angle=min_angle, threshold=threshold, num_peaks=num_peaks)``, found by its steps
    (a maximum filter of (2 ``min_distance`` + 1) distance bins by (2 ``min_angle`` + 1)
    angle bins, the connected local maxima above ``threshold`` strongest first, each
    suppressing its neighbourhood, angles wrapping as there) on the bounding box of the bins
    above ``threshold`` instead of on the whole accumulator: a plate search's accumulator is
    thousands of distance bins by hundreds of angles, its votes above the threshold a few
    lines' worth.  Outside the box no bin is above the threshold, so no peak lies there; a
    bin's filtered maximum matters only where it is above the threshold, and then it is a bin
    inside the box that holds it (the filter's constant 0 at the box's border changes no such
    maximum); the suppression around a peak reads and writes the box only (every later peak
    lies in it).  For accumulators of non-negative votes and a given threshold, as every
    straight-line Hough transform gives (skimage's default threshold, None, is not taken)."""
    if threshold is None:
        raise ValueError("hough_peaks needs a threshold")
    rows, cols = hspace.shape
    min_angle = min(min_angle, cols)
    over = hspace > threshold
    ra, ca = np.flatnonzero(over.any(axis=1)), np.flatnonzero(over.any(axis=0))
    if not ra.size:
        return np.array([]), np.array([]), np.array([])
    r0, r1, c0, c1 = ra[0], ra[-1] + 1, ca[0], ca[-1] + 1
    img = hspace[r0:r1, c0:c1].copy()
    img_max = ndi.maximum_filter1d(img, size=2 * min_distance + 1, axis=0, mode="constant", cval=0)
    img_max = ndi.maximum_filter1d(img_max, size=2 * min_angle + 1, axis=1, mode="constant", cval=0)
    img *= img == img_max
    lab, n = measure.label(img > threshold, return_num=True)
    # the connected local maxima as regionprops gives them, by one count of the labels instead
    # of a region object each (a textured photo's accumulator holds thousands): each one's
    # maximum of img_max, strongest first (a stable sort reversed, as sorted()[::-1] of the
    # regions in label order), and its centroid in the whole accumulator's bins (the mean of
    # its bins' coordinates: sums of whole numbers, exact in any order) rounded
    flat = lab.ravel()
    at = np.flatnonzero(flat)
    labs = flat[at]
    strength = np.zeros(n + 1, img_max.dtype)
    np.maximum.at(strength, labs, img_max.ravel()[at])
    count = np.bincount(labs, minlength=n + 1)[1:]
    cy = np.bincount(labs, weights=at // img.shape[1] + r0, minlength=n + 1)[1:]
    cx = np.bincount(labs, weights=at % img.shape[1] + c0, minlength=n + 1)[1:]
    order = np.argsort(strength[1:], kind="stable")[::-1]
    coords = np.round(np.column_stack([cy / count, cx / count])[order]).astype(int)
    ys, xs = np.mgrid[-min_distance:min_distance + 1, -min_angle:min_angle + 1]
    peaks, ypk, xpk = [], [], []
    for y, x in coords.tolist():  # Python ints: the loop runs once per connected maximum
        accum = img_max[y - r0, x - c0]
        if accum > threshold:
            if x - min_angle >= 0 and x + min_angle < cols:
                # no angle wraps: the neighbourhood's bins (distance bins 1 to rows - 1, in the
                # box) are one rectangle, set to 0 as one slice (a dense photo's accumulator has
                # thousands of peaks above the threshold, each suppressing its neighbourhood)
                ya, yb = max(y - min_distance, 1, r0), min(y + min_distance + 1, rows, r1)
                xa, xb = max(x - min_angle, c0), min(x + min_angle + 1, c1)
                if ya < yb and xa < xb:
                    img_max[ya - r0:yb - r0, xa - c0:xb - c0] = 0
            else:
                yn, xn = y + ys, x + xs
                inside = (yn > 0) & (yn < rows)  # as skimage: no reflection in distance (nor its bin 0)
                yn, xn = yn[inside], xn[inside]
                low, high = xn < 0, xn >= cols  # angles wrap, the distance reflected
                yn[low], xn[low] = rows - yn[low], xn[low] + cols
                yn[high], xn[high] = rows - yn[high], xn[high] - cols
                box = (yn >= r0) & (yn < r1) & (xn >= c0) & (xn < c1)
                img_max[yn[box] - r0, xn[box] - c0] = 0
            peaks.append(accum)
            ypk.append(y)
            xpk.append(x)
    peaks, ypk, xpk = np.array(peaks), np.array(ypk), np.array(xpk)
    if num_peaks < len(peaks):
        keep = np.argsort(peaks)[::-1][:num_peaks]
        peaks, ypk, xpk = peaks[keep], ypk[keep], xpk[keep]
    if not xpk.size:
        return peaks, np.array([]), np.array([])
    return peaks, angles[xpk], dists[ypk]


def plate_lines(gray, below=None, edges=None, paired=False):
    """Long near-horizontal edges below a point, topmost first, each refined by a RANSAC line
    fit: [(slope, intercept), ...] with row = slope * col + intercept.

    ``below`` = (col, row): only lines passing below that point count (default: the image
    middle at column 0).  ``edges``: an edge map to use instead of the luminance's Canny edges.
    ``paired``: a line's support also counts the votes of the larger of its two neighbouring
    distance bins (the heap search, whose candidates must also run on beside the heap,
    :func:`_plate_beside_heap`; the drum's level keeps a line's own votes).
    """
    edges = feature.canny(gray, sigma=1.5) if edges is None else edges
    h, w = gray.shape
    col0, row0 = below if below is not None else (0.0, 0.5 * h)
    # 0.05 deg steps over +-PLATE_MAX_ROLL_DEG of horizontal
    thetas = np.radians(np.linspace(90.0 - PLATE_MAX_ROLL_DEG, 90.0 + PLATE_MAX_ROLL_DEG,
                                    int(round(40 * PLATE_MAX_ROLL_DEG)) + 1))
    hs, ang, dist = transform.hough_line(edges, theta=thetas)
    # a line's support is its own bin's votes and those of the larger of its two neighbours:
    # an edge lying on a pixel boundary comes out of Canny alternating between two rows,
    # which splits its votes between two neighbouring distance bins (a line crossing edges at
    # a slant spreads its votes over more bins and gains less)
    # (counted at the peaks only, not over the whole accumulator)
    _, angs, dists = hough_peaks(hs, ang, dist, num_peaks=16, min_distance=4, threshold=0.1 * w)

    def support(i, j):
        own = float(hs[i, j])
        if not paired:
            return own
        return own + max(float(hs[i + 1, j]) if i + 1 < hs.shape[0] else 0.0, float(hs[i - 1, j]) if i > 0 else 0.0)

    keep = [support(np.argmin(np.abs(dist - d)), np.argmin(np.abs(ang - a))) >= 0.25 * w for a, d in zip(angs, dists)]
    angs, dists = angs[keep][:8], dists[keep][:8]
    at = sorted(((a, d, (d - col0 * np.cos(a)) / np.sin(a)) for a, d in zip(angs, dists)), key=lambda t: t[2])
    er, ec = np.nonzero(edges)
    refined = (_refined_line(er, ec, w, a, d) for a, d, row in at if row > row0)
    return [ln for ln in refined if ln is not None]


def _refined_line(er, ec, w, a, d):
    """The Hough line (angle ``a``, distance ``d``) refined by a RANSAC line fit through the
    edge pixels (rows ``er``, columns ``ec``) within 3 px of it: (slope, intercept), or None
    where the fit gives no line of finite slope and intercept (fewer than two pixels near it,
    no model, or a vertical one: the best of RANSAC's lines through pixels of one column), which
    is then no plate candidate."""
    cols = np.arange(w)
    rows = (d - cols * np.cos(a)) / np.sin(a)
    near = np.abs(er - rows[ec]) < 3
    pts = np.column_stack([ec[near], er[near]]).astype(float)
    if len(pts) < 2:
        return None
    model, _ = measure.ransac(pts, measure.LineModelND, min_samples=2, residual_threshold=1.0,
                              max_trials=200, rng=0)
    if model is None or not model:
        return None
    (c0, r0), (dc, dr) = model.origin, model.direction
    if dc == 0.0:
        return None
    slope = dr / dc
    intercept = r0 - slope * c0
    return (slope, intercept) if math.isfinite(slope) and math.isfinite(intercept) else None


#: the steepest tilt (deg) at which a straight edge across the photo is looked for beyond the
#: plate search (:func:`_plate_beyond_search`): a camera rolled further is no hand-held slip
ROLL_CHECK_MAX_DEG = 45.0
#: a line runs across the photo when an edge meets it along at least this share of the columns
#: of each outer quarter of its extent in the frame (:func:`_across`)
ACROSS_MIN = 0.8


def _across(edges, slope, intercept):
    """The smaller of the shares of the columns of the first and of the last quarter of the
    line's extent in the frame (at least half the width) where ``edges`` meet it; 0 for a line
    inside the frame along less than half its width.  A plate's top edge runs across the photo
    to both sides of the heap; a flank, a line of the heap's grain or a wall's clutter does not."""
    h, w = edges.shape
    cols = np.arange(w)
    rows = np.round(slope * cols + intercept).astype(int)
    inside = (rows >= 0) & (rows < h)
    if inside.sum() < 0.5 * w:
        return 0.0
    hit = edges[rows[inside], cols[inside]]
    n = max(hit.size // 4, 1)
    return float(min(hit[:n].mean(), hit[-n:].mean()))


def _plate_beyond_search(edges, edges_wide, lines, below=None):
    """A straight edge across the photo (:func:`_across`, at least :data:`ACROSS_MIN`) tilted
    beyond the plate search's :data:`PLATE_MAX_ROLL_DEG` (up to :data:`ROLL_CHECK_MAX_DEG`) and
    running across it further than every plate candidate in ``lines`` does: the plate of a photo
    taken with the camera rolled beyond the search, whose candidates are chords of it or lines
    of the heap that gave flanks several degrees off, or none.  ``edges``: the edge map the
    candidates came from; ``edges_wide``: it widened by a row either side; ``below`` = (col,
    row): only a line passing below that point counts (a drum's plate).  Returns every such
    (slope, intercept), best first."""
    h, w = edges.shape
    t = np.arange(PLATE_MAX_ROLL_DEG + 0.1, ROLL_CHECK_MAX_DEG + 1e-9, 0.1)
    thetas = np.radians(np.concatenate([90.0 - t[::-1], 90.0 + t]))
    hs, ang, dist = transform.hough_line(edges, theta=thetas)
    _, angs, dists = hough_peaks(hs, ang, dist, num_peaks=8, min_distance=4, threshold=0.25 * w)
    if not len(angs):
        return []
    er, ec = np.nonzero(edges)
    beyond = []
    for a, d in zip(angs, dists):
        refined = _refined_line(er, ec, w, a, d)
        if refined is None:
            continue
        slope, b = refined
        if below is not None and slope * below[0] + b <= below[1]:
            continue
        if abs(np.degrees(np.arctan(slope))) > PLATE_MAX_ROLL_DEG:
            beyond.append((_across(edges_wide, slope, b), slope, b))
    return _lines_beyond(beyond, edges_wide, lines)


def _parallel_lines(edges, slope, intercept):
    """The straight edges of ``edges`` within half a degree of parallel to the line (slope, intercept)
    and from a tenth of the image height above it to 3 px below it, topmost first, the line
    itself among them: [(slope, intercept), ...] (as :func:`plate_lines` finds them, support at
    least a quarter of the width)."""
    h, w = edges.shape
    t0 = 90.0 + float(np.degrees(np.arctan(slope)))
    thetas = np.radians(np.linspace(t0 - 0.5, t0 + 0.5, 21))
    hs, ang, dist = transform.hough_line(edges, theta=thetas)
    _, angs, dists = hough_peaks(hs, ang, dist, num_peaks=16, min_distance=2, threshold=0.25 * w)
    er, ec = np.nonzero(edges)
    out = [(0.0, slope, intercept)]
    for a, d in zip(angs, dists):
        refined = _refined_line(er, ec, w, a, d)
        if refined is None:
            continue
        s_, b_ = refined
        off = (s_ - slope) * w / 2 + b_ - intercept  # rows below the line at the middle column
        if -0.1 * h <= off <= 3.0 and all(abs((s_ - o[1]) * w / 2 + b_ - o[2]) > 1.5 for o in out):
            out.append((off, s_, b_))
    return [(s_, b_) for _, s_, b_ in sorted(out)]


def _lines_beyond(beyond, edges_wide, lines):
    """Of ``beyond`` [(across score, slope, intercept), ...], the lines running across the photo
    (at least :data:`ACROSS_MIN`) further than every line of ``lines``, best first: [(slope,
    intercept), ...]."""
    best = max((_across(edges_wide, *ln) for ln in lines), default=0.0) + 0.03
    return [(slope, b) for score, slope, b in sorted(beyond, reverse=True) if score >= ACROSS_MIN and score > best]


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
    coverage: float = 1.0  # share of the span's columns with a boundary point kept in the fit
    end_gap_mm: float = 0.0  # the larger stretch at either end of the span without a point
    fit_rms_mm: float = 0.0  # RMS distance of the kept points from the fitted polynomial
    confidence: str = "ok"  # "low": FURROW_LOW_IF (the area then rests on extrapolation or a ragged boundary)
    area_fit_mm2: float = float("nan")  # the chord area of the fitted polynomial (Eq. (3)'s way)
    boundary_rms_mm: float = 0.0  # RMS of the kept points about their running median
    chord_ends_mm: list = field(default_factory=list)  # the chord's heights at the span's ends
    chord_ends_from: list = field(default_factory=list)  # "polynomial", "end line" or "line", per end

    def as_dict(self):
        return {"path": self.path, "degree": self.degree, "coeffs": self.coeffs,
                "area_mm2": self.area_mm2, "area_dm2": self.area_mm2 / 1e4,
                "confidence": self.confidence, "coverage": self.coverage, "end_gap_mm": self.end_gap_mm,
                "fit_rms_mm": self.fit_rms_mm, "area_fit_mm2": self.area_fit_mm2,
                "boundary_rms_mm": self.boundary_rms_mm, "chord_ends_mm": self.chord_ends_mm,
                "chord_ends_from": self.chord_ends_from,
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


#: the beam is sought among dark bars thinner than this share of the image height (black
#: top-hat of the luminance with a vertical line of that length)
BEAM_BAR_MAX = 0.12
#: dark lines thinner than this share of the image height (a board's grid) are no beam
BEAM_THIN = 0.006
#: the most the beam may be tilted in the photo (deg either way): the camera roll the furrow
#: measurement takes out; a beam-like bar tilted further (up to ROLL_CHECK_MAX_DEG) is named in
#: the refusal with the roll that levels it
BEAM_MAX_ROLL_DEG = 15.0
#: the least length (share of the image width) and length / thickness of a beam
BEAM_MIN_LENGTH, BEAM_MIN_ELONGATION = 0.2, 8.0
#: rows (px) of the board above the beam and of the soil at the frame's bottom that give the
#: two colours the furrow boundary separates
FURROW_SEED_ROWS = 12
#: weight of L* against a* and b* in the board/soil colour distances
FURROW_L_WEIGHT = 0.5
#: a furrow's confidence is "low" when the kept boundary points cover under 85 % of the span's
#: columns, leave more than 2 % of the span at an end without a point (the chord's end height
#: is then extrapolated), or stray from their running median by more than 1.5 mm RMS
FURROW_LOW_IF = {"coverage_below": 0.85, "end_gap_above": 0.02, "rms_mm_above": 1.5}


def _edge_peak(profile, lo, hi, sign):
    """Sub-pixel position of the strongest step of ``sign`` (+1 dark to light, -1 light to
    dark, along increasing index) of a 1-D profile in [lo, hi) (parabola through the three
    samples of the gradient around its extremum)."""
    g = np.gradient(profile) * sign
    lo, hi = max(1, int(lo)), min(len(profile) - 1, int(hi))
    if hi - lo < 3:
        return np.nan
    i = lo + int(np.argmax(g[lo:hi]))
    a, b, c = g[i - 1], g[i], g[i + 1]
    den = a - 2 * b + c
    return float(i + (0.5 * (a - c) / den if den < 0 else 0.0))


def _beam_bar(path, gray, threshold, tried):
    """The profile-meter beam: the longest and darkest dark bar (black top-hat of ``gray`` with a vertical
    line of BEAM_BAR_MAX of the image height, thresholded by ``threshold``) that is straight,
    near-horizontal (within 15 deg), at least BEAM_MIN_LENGTH of the width long, BEAM_MIN_ELONGATION
    times longer than thick and clear of the image border.  Returns its pixel rows and columns."""
    h, w = gray.shape
    k = max(15, int(round(BEAM_BAR_MAX * h)))
    bar = ndi.grey_closing(gray, size=(k, 1)) - gray
    thin = max(5, int(round(BEAM_THIN * h)))
    bar = ndi.grey_opening(bar, size=(thin, thin))  # grid lines and specks thinner than that go
    top = float(bar.max())
    if top <= 1e-6:
        raise InputError(path, "image", "a profile-meter beam (long dark bar)", "no dark bar")
    mask = _binary(path, 1.0 - bar / top, threshold)
    tried.add(f"dark bars ({threshold} on the black top-hat): the beam is sought among them", mask)
    lab = measure.label(mask)
    beams, tilted = [], []
    for p in measure.regionprops(lab):
        r0, c0, r1, c1 = p.bbox
        if r0 == 0 or c0 == 0 or r1 == h or c1 == w or p.axis_minor_length <= 0:
            continue
        if (p.axis_major_length >= BEAM_MIN_LENGTH * w
                and p.axis_major_length / p.axis_minor_length >= BEAM_MIN_ELONGATION):
            tilt = abs(abs(p.orientation) - np.pi / 2)  # from horizontal
            if tilt <= np.radians(BEAM_MAX_ROLL_DEG):
                beams.append(p)
            elif tilt <= np.radians(ROLL_CHECK_MAX_DEG):
                tilted.append(p)
    if not beams and tilted:
        # a beam-like bar tilted beyond the search: the beam of a camera rolled further
        bar_ = max(tilted, key=lambda p: p.axis_major_length)
        roll = roll_of(np.cos(bar_.orientation) / np.sin(bar_.orientation))  # major axis: (row, col) = (cos, sin)
        raise InputError(path, "image", f"a profile-meter beam (long dark bar) within {BEAM_MAX_ROLL_DEG:.0f} deg "
                         f"of horizontal (the camera held within {BEAM_MAX_ROLL_DEG:.0f} deg of level: the beam "
                         "search looks no further)",
                         f"none found; a long dark bar as the beam's is tilted {roll:.1f} deg: if it is the beam (the "
                         f"camera rolled), {level_it(roll)}, or take it again with the camera level")
    if not beams:
        raise InputError(path, "image", "a profile-meter beam (long dark bar)", "none found")
    # the longest and darkest against its surroundings (a faint grid line or board edge is not)
    beam = max(beams, key=lambda p: p.axis_major_length * float(np.median(bar[p.coords[:, 0], p.coords[:, 1]])))
    tried.attempts[-1].outcome = f"{len(beams)} beam-like bar(s); the longest and darkest is the beam"
    tried.add("beam (longest bar)", lab == beam.label)
    return beam.coords[:, 0].astype(float), beam.coords[:, 1].astype(float)


@dataclass
class _Beam:
    """The profile-meter beam in a photo: a point ``o`` on its axis and the unit vectors ``ux``
    along it and ``vx`` square to it, pointing down the image, each as (col, row); in those
    axes (px) its long edges ``top`` and ``low``, its ends ``left`` and ``right``, and its
    thickness ``thick``."""

    o: np.ndarray
    ux: np.ndarray
    vx: np.ndarray
    top: float
    low: float
    thick: float
    left: float = float("nan")
    right: float = float("nan")

    def sample(self, img, u, v):
        """``img`` resampled (bilinear) at the points ``u`` along and ``v`` across the beam:
        rows v, columns u."""
        cc = self.o[0] + u[None, :] * self.ux[0] + v[:, None] * self.vx[0]
        rr = self.o[1] + u[None, :] * self.ux[1] + v[:, None] * self.vx[1]
        return ndi.map_coordinates(img, [rr, cc], order=1, mode="nearest")


#: how far beyond the beam's dark pixels (across its axis, px) its long edges are looked for
BEAM_EDGE_MARGIN_PX = 6.0


def _beam_axis(path, gray, br, bc) -> tuple[_Beam, float]:
    """The beam's axis and long edges from its pixels (rows ``br``, columns ``bc``): first the
    straight line through their column means, then turned to the straighter of its two long
    edges (a shadow merged into one side of the bar tilts the column means, not the other
    edge); the edges are the strongest steps of the luminance across the beam (sub-pixel, mean
    over its middle 80 %) within BEAM_EDGE_MARGIN_PX of the bar's pixels.  Returns the beam and
    the axis's slope in the image."""
    cols = np.unique(bc)
    rows = np.array([br[bc == c].mean() for c in cols])
    slope, icpt = np.polyfit(cols, rows, 1)
    c_mid = 0.5 * (cols.min() + cols.max())
    o = np.array([c_mid, slope * c_mid + icpt])  # a point on the beam's axis
    thick = float(len(br)) / max(1.0, cols.max() - cols.min() + 1)
    half_len = 0.5 * (cols.max() - cols.min() + 1) * np.hypot(1.0, slope)
    u_mid = np.arange(-0.8 * half_len, 0.8 * half_len + 1)
    v_x = np.arange(-2.5 * thick - 4, 2.5 * thick + 5)
    i0 = int(np.searchsorted(v_x, 0.0))
    for refine in (True, False):
        n = np.hypot(1.0, slope)
        beam = _Beam(o, np.array([1.0, slope]) / n, np.array([-slope, 1.0]) / n, np.nan, np.nan, thick)
        cut = beam.sample(gray, u_mid, v_x)
        across = cut.mean(axis=1)
        # each long edge within the bar's own extent across the axis (and a few pixels): a
        # line of a grid running beside the beam, sharper than the blurred lower edge of a
        # shadow merged into the bar, is no edge of it
        v_bar = (bc - o[0]) * beam.vx[0] + (br - o[1]) * beam.vx[1]
        j_top = int(np.searchsorted(v_x, v_bar.min() - BEAM_EDGE_MARGIN_PX))
        j_low = int(np.searchsorted(v_x, v_bar.max() + BEAM_EDGE_MARGIN_PX, side="right"))
        beam.top = _edge_peak(across, max(0, min(j_top, i0)), i0 + 1, -1) + v_x[0]
        beam.low = _edge_peak(across, i0, min(len(v_x), max(j_low, i0 + 2)), +1) + v_x[0]
        if not (np.isfinite(beam.top) and np.isfinite(beam.low)) or beam.low - beam.top < 2:
            raise InputError(path, "image", "a profile-meter beam with two clear long edges", "none found")
        if not refine:
            break
        # the direction from the straighter of the two edges, column by column
        fits = []
        for e, sign in ((beam.top, -1), (beam.low, +1)):
            j = int(round(e - v_x[0]))
            ve = v_x[0] + np.array([_edge_peak(cut[:, i], j - 4, j + 5, sign) for i in range(cut.shape[1])])
            cf = np.polyfit(u_mid, ve, 1)
            fits.append((float(np.std(ve - np.polyval(cf, u_mid))), cf[0]))
        beta = min(fits)[1]
        slope = float(np.tan(np.arctan(slope) + np.arctan(beta)))
    return beam, slope


def _beam_ends(path, gray, beam: _Beam, br, bc) -> None:
    """Set the beam's ends: from its middle outwards, as long as its core is darker than the
    board just above it by at least half the beam's own contrast (a bar found only in part,
    where the board is darker or a grid crosses it, is followed to its real ends); each end is
    then the strongest step of the luminance along the beam within 2 thicknesses + 10 px of
    where that run stops (sub-pixel)."""
    h, w = gray.shape
    o, ux = beam.o, beam.ux
    top, low = beam.top, beam.low
    core = np.linspace(top + 0.25 * (low - top), low - 0.25 * (low - top), 5)
    ub = (bc - o[0]) * ux[0] + (br - o[1]) * ux[1]
    lim = []
    for k_, n_ in ((0, w), (1, h)):  # u where the axis stays in the frame
        if abs(ux[k_]) > 1e-9:
            lim.append(sorted(((0 - o[k_]) / ux[k_], (n_ - 1 - o[k_]) / ux[k_])))
    u_x = np.arange(np.ceil(max(l_[0] for l_ in lim)), np.floor(min(l_[1] for l_ in lim)) + 1)
    along = beam.sample(gray, u_x, core).mean(axis=0)
    above = np.median(beam.sample(gray, u_x, np.arange(top - 12, top - 3)), axis=0)
    contrast = ndi.uniform_filter1d((above - along) / np.maximum(above, 1e-3), 5)
    mid_ = (u_x >= np.percentile(ub, 20)) & (u_x <= np.percentile(ub, 80))
    inside = contrast > 0.5 * np.median(contrast[mid_])
    j_mid = int(np.searchsorted(u_x, 0.5 * (ub.min() + ub.max())))
    run = ndi.label(ndi.binary_closing(inside, np.ones(5)))[0]
    lab_mid = run[j_mid] if run[j_mid] else run[np.nonzero(run)[0][np.argmin(np.abs(np.nonzero(run)[0] - j_mid))]]
    jj = np.nonzero(run == lab_mid)[0]
    win = int(2 * beam.thick + 10)
    beam.left = _edge_peak(along, jj[0] - win, jj[0] + win, -1) + u_x[0]
    beam.right = _edge_peak(along, jj[-1] - win, jj[-1] + win + 1, +1) + u_x[0]
    length_px = beam.right - beam.left
    if not np.isfinite(length_px) or length_px < BEAM_MIN_LENGTH * w:
        raise InputError(path, "image", "a profile-meter beam with two clear ends", "none found")


def _soil_boundary(path, rgb, beam: _Beam):
    """The board-to-soil boundary below the beam, per column of the strip under its span:
    returns (u, v, z_row, split) with u the columns along the beam, v the strip's rows across
    it, z_row the boundary's row in v's units (sub-pixel; NaN where a column has no clear step)
    and split the row index of each column's board/soil split.

    Each column is split into board above and soil below at the row that best separates the
    two colours (smoothed L*a*b*, lightness at half weight: the board just above the beam, the
    soil at the frame's bottom), then refined to where the photo's own values cross half-way
    between the board just above and the soil just below."""
    h = rgb.shape[0]
    # the strip below the beam, as far down as every one of its columns stays in the frame
    u = np.arange(np.ceil(beam.left) + 1, np.floor(beam.right))
    ends = [beam.o + beam.ux * uu for uu in (u[0], u[-1])]
    v_max = min((h - 1 - e[1]) / beam.vx[1] for e in ends) - 1
    v0 = beam.top - FURROW_SEED_ROWS - 4
    if v_max - beam.low < 3 * FURROW_SEED_ROWS:
        raise InputError(path, "image", "soil below the profile-meter beam", "the beam is at the frame's bottom")
    v = np.arange(v0, v_max)
    # L*a*b* of the smoothed photo on the rows the strip's bilinear samples read only (the
    # rows of its corners' extremes and the next one), whole rows, so each pixel's conversion
    # is the one of the whole image; the rows above and below are never read
    rows = [beam.o[1] + uu * beam.ux[1] + vv * beam.vx[1] for uu in (u[0], u[-1]) for vv in (v[0], v[-1])]
    r0, r1 = max(0, math.floor(min(rows)) - 1), min(h, math.floor(max(rows)) + 3)
    smooth = filters.gaussian(rgb, 1.5, channel_axis=-1)
    lab_img = np.full_like(smooth, np.nan)  # a row outside the window would read NaN, not a colour
    lab_img[r0:r1] = color.rgb2lab(smooth[r0:r1])
    strip = np.stack([beam.sample(lab_img[..., k], u, v) for k in range(3)], axis=-1)
    board = np.median(strip[:FURROW_SEED_ROWS].reshape(-1, 3), axis=0)
    soil_c = np.median(strip[-FURROW_SEED_ROWS:].reshape(-1, 3), axis=0)
    if np.linalg.norm(board - soil_c) < 5.0:  # Delta E below 5: no visible difference
        raise InputError(path, "image", "soil below the profile-meter beam distinct from the board above it",
                         f"the same colour (Delta E {np.linalg.norm(board - soil_c):.1f})")
    # lightness counts half: a shadow on the board (the beam's, the soil's) changes it most
    wl = np.array([FURROW_L_WEIGHT, 1.0, 1.0])
    d_b = np.linalg.norm((strip - board) * wl, axis=-1)
    d_s = np.linalg.norm((strip - soil_c) * wl, axis=-1)
    score = (d_b - d_s) / (d_b + d_s + 1e-9)  # -1 board, +1 soil
    below = v > beam.low + 1
    sc = np.where(below[:, None], score, -1.0)  # nothing on or above the beam is soil
    # the row k splitting each column into board above and soil below with the least disagreement
    cost_board = np.cumsum(np.maximum(sc, 0), axis=0)  # soil-like rows labelled board
    cost_soil = np.cumsum(np.maximum(-sc, 0)[::-1], axis=0)[::-1]  # board-like rows labelled soil
    total = np.vstack([np.zeros((1, sc.shape[1])), cost_board])[:-1] + cost_soil
    k = np.argmin(total, axis=0)
    # the edge to a fraction of a pixel: where the photo's own values (linear in the light the
    # pixel saw, unlike L*a*b*) cross half-way between the board just above and the soil just
    # below, along the board-to-soil colour direction
    srgb = np.stack([beam.sample(rgb[..., q], u, v) for q in range(3)], axis=-1)
    dirn = np.median(srgb[-FURROW_SEED_ROWS:].reshape(-1, 3), axis=0) - np.median(
        srgb[:FURROW_SEED_ROWS].reshape(-1, 3), axis=0)
    proj = srgb @ (dirn / max(float(dirn @ dirn), 1e-12))
    z_row = np.full(k.shape, np.nan)
    for j, kk in enumerate(k):
        if kk < 12 or kk > len(v) - 12:
            continue
        t = proj[:, j]
        bg, fg = np.median(t[kk - 12:kk - 4]), np.median(t[kk + 4:kk + 12])
        if fg - bg < 0.2:  # no clear step at the split: no point here
            continue
        z_row[j] = _mid_crossing(t[kk - 6:kk + 6], 0.5 * (bg + fg), -1.0, v[kk - 6], np.nan, near=6)
    return u, v, z_row, k


def _profile_fit(x, z, degree):
    """The profile polynomial of ``degree`` through (x, z), refitted twice without the points
    more than 4 robust SDs (at least 1 mm) off the fit before (the area takes its own points,
    :func:`_direct_chord_area`)."""
    from scipy.stats import median_abs_deviation

    poly = np.polynomial.Polynomial.fit(x, z, degree)
    for _ in range(2):
        res = z - poly(x)
        keep = np.abs(res) <= max(4 * float(median_abs_deviation(res, scale="normal")), 1.0)
        poly = np.polynomial.Polynomial.fit(x[keep], z[keep], degree)
    return poly


def _measure_furrow(path, scale_length_mm, datum_mm, degree, threshold, keep_stages, tried: Tried):
    """Module docstring.  The beam (:func:`_beam_bar`), its axis and long edges
    (:func:`_beam_axis`; the photo is resampled along it, so that u runs along the beam and v
    down, square to it: the roll correction) and its ends (:func:`_beam_ends`) give the scale
    and the datum without a threshold; below it the soil's boundary column by column
    (:func:`_soil_boundary`), fitted with the polynomial (:func:`_profile_fit`)."""
    from soilcal.imaging.manifest import _is_number, check_degree

    if not _is_number(scale_length_mm) or scale_length_mm <= 0:
        raise InputError(path, "scale_length_mm", "a positive length of the scale reference in mm", scale_length_mm)
    if not _is_number(datum_mm):
        raise InputError(path, "beam_datum_mm", "a number (mm)", datum_mm)
    check_degree(path, "degree", degree)
    if threshold not in ("otsu", "adaptive"):
        raise InputError(path, "threshold", "'otsu' or 'adaptive'", threshold)
    rgb = read_photo(path)
    gray = _gray(rgb)
    tried.rgb, tried.gray = rgb, gray
    h, w = gray.shape
    br, bc = _beam_bar(path, gray, threshold, tried)
    beam, slope = _beam_axis(path, gray, br, bc)
    roll = roll_of(slope)
    _beam_ends(path, gray, beam, br, bc)
    s = (beam.right - beam.left) / scale_length_mm
    u_c = 0.5 * (beam.left + beam.right)
    u, v, z_row, k = _soil_boundary(path, rgb, beam)
    ok = np.isfinite(z_row) & (k > 0)
    if ok.sum() < 0.5 * len(u):
        raise InputError(path, "image", "a soil boundary below the beam in most columns of its span",
                         f"{int(ok.sum())} of {len(u)} columns")
    x = (u[ok] - u_c) / s
    z = datum_mm - (z_row[ok] - beam.low) / s
    a, b = -scale_length_mm / 2, scale_length_mm / 2
    poly = _profile_fit(x, z, degree)
    coeffs = poly.convert().coef[::-1].tolist()
    area_fit = furrow_chord_area(a, b, coeffs)
    area, keep, ends, boundary_rms, ends_from = _direct_chord_area(x, z, a, b, poly)
    x, z = x[keep], z[keep]
    # the soil found, in the photo's own pixels, for the figures (keep_stages) only: nothing
    # after this point refuses the photo, so no diagnostic image draws it, and skimage's
    # polygon fill of a vertex per column took some 40 % of the measurement's CPU
    uu = u[ok][keep]
    soil_mask = np.zeros((h, w), bool) if keep_stages else None
    if keep_stages and uu.size > 2:
        from skimage.draw import polygon

        vb = z_row[ok][keep]
        pts = [beam.o + beam.ux * a_ + beam.vx * b_ for a_, b_ in zip(uu, vb)]
        pts += [beam.o + beam.ux * uu[-1] + beam.vx * v[-1], beam.o + beam.ux * uu[0] + beam.vx * v[-1]]
        pts = np.array(pts)
        rr_, cc_ = polygon(pts[:, 1], pts[:, 0], (h, w))
        soil_mask[rr_, cc_] = True
    tried.add("soil below the beam (board and soil colours split per column)", soil_mask)
    st = None
    if keep_stages:
        st = Stages(rgb, gray, soil_mask, None, [], [np.column_stack([uu, z_row[ok][keep]])])
        st.poly = poly
        st.frame = (beam.left, beam.right, beam.low, s, datum_mm)
        st.reference = "beam axis"
    coverage = float(len(x) / max(1, len(u)))
    end_gap = float(max(x.min() - a, b - x.max(), 0.0))
    rms = float(np.sqrt(np.mean((z - poly(x)) ** 2)))
    low = (coverage < FURROW_LOW_IF["coverage_below"] or end_gap > FURROW_LOW_IF["end_gap_above"] * (b - a)
           or boundary_rms > FURROW_LOW_IF["rms_mm_above"])
    return FurrowResult(str(path), x, z, coeffs, degree, float(area), float(s), roll, st, coverage, end_gap, rms,
                        "low" if low else "ok", area_fit_mm2=float(area_fit), boundary_rms_mm=boundary_rms,
                        chord_ends_mm=[float(ends[0]), float(ends[1])], chord_ends_from=ends_from)


#: points of the running median a furrow boundary point is compared with (one per column)
FURROW_MEDIAN_POINTS = 9
#: share of the span at each end whose boundary points judge the polynomial's end height and,
#: where it does not follow them, give the chord's end height (a line)
FURROW_END_SHARE = 0.05
#: the most the boundary points at an end may stray from the polynomial (RMS, mm) for its end
#: height to be the chord's (drawn and rendered furrows: 0.1-0.6 mm where it follows them, 2.9
#: and 3.6 mm at a rounded trough's and a trapezoid's flat ends, where it swings)
FURROW_END_FIT_MM = 1.0
#: where it does (FURROW_END_FIT_MM), the polynomial's end height is still checked against a
#: line through the boundary points within this many mm of the end: a polynomial that follows
#: an end's points on the whole can bend away in its last millimetres where the furrow has
#: corners (a drawn V: 0.55 mm low at both ends; opener-shaped stress photos: up to 3 mm)
FURROW_END_LINE_MM = 10.0
#: the most the polynomial's end height may differ from that line's, beyond three standard
#: errors of the line's end height, for the polynomial's to be kept (mm)
FURROW_END_AGREE_MM = 0.3


def _direct_chord_area(x, z, a, b, poly):
    """``x`` in increasing order (one point per column along the beam).  The furrow's chord area with its profile integrated over the measured boundary points:
    (area mm^2, kept mask, (z(a), z(b)), boundary RMS mm, what gave each end height).  A point more than 4 robust SDs (at
    least 1 mm) off the running median of its FURROW_MEDIAN_POINTS neighbours (a clod, a
    speck) is dropped; the chord joins the surface heights at the span's ends: the
    polynomial's (smoothed over the whole profile, the steadiest estimate) where the kept
    points within FURROW_END_SHARE of the span of the outermost one stray from it by at most
    FURROW_END_FIT_MM RMS and its end height lies within FURROW_END_AGREE_MM (or three standard
    errors) of a line's through the points within FURROW_END_LINE_MM of the end (else that
    line's, "end line"), else a line's through the FURROW_END_SHARE points ("line"; both
    carried to the end where the points stop short of it); the area is the chord's trapezoid less the trapezoidal integral of the kept
    points closed by those end heights.  A polynomial of any degree swings at the span's ends
    where the profile has corners (a trapezoid's or a V's furrow meeting a flat surface: a
    degree-9 fit rose 10 mm at both ends of a drawn trapezoid and its chord area read 21 %
    high); the measured points do not, but a line through the few points at an end is noisier
    than the polynomial where that follows them."""
    from scipy.ndimage import median_filter
    from scipy.stats import linregress, median_abs_deviation

    from soilcal.imaging.scenes import polyline_chord_area

    med = median_filter(z, size=min(FURROW_MEDIAN_POINTS, len(z)), mode="nearest")
    r = z - med
    sc = float(median_abs_deviation(r, scale="normal"))
    keep = np.abs(r) <= max(4.0 * sc, 1.0)
    xk, zk = x[keep], z[keep]
    reach = FURROW_END_SHARE * (b - a)

    def end_line(at, sel):
        """A least-squares line's height at ``at`` through the points ``sel`` and its standard
        error (inf without residual degrees of freedom; the points' mean where they span no
        width)."""
        xs, zs = xk[sel], zk[sel]
        if len(xs) < 3 or np.ptp(xs) <= 0:
            return float(np.mean(zs)), float("inf")
        fit = linregress(xs - at, zs)
        return float(fit.intercept), float(fit.intercept_stderr)

    heights, ends_from = [], []
    for at, sel, near in ((a, xk <= xk.min() + reach, xk <= xk.min() + FURROW_END_LINE_MM),
                          (b, xk >= xk.max() - reach, xk >= xk.max() - FURROW_END_LINE_MM)):
        if float(np.sqrt(np.mean((zk[sel] - poly(xk[sel])) ** 2))) > FURROW_END_FIT_MM:
            heights.append(end_line(at, sel)[0])  # the polynomial swings over the end's points
            ends_from.append("line")
            continue
        z_line, se = end_line(at, near)
        if abs(float(poly(at)) - z_line) <= max(FURROW_END_AGREE_MM, 3.0 * se):
            heights.append(float(poly(at)))  # the polynomial follows the surface there
            ends_from.append("polynomial")
        else:
            heights.append(z_line)  # it bends away from the end's last points
            ends_from.append("end line")
    za, zb = heights
    inside = (xk > a) & (xk < b)
    area = polyline_chord_area(np.concatenate([[a], xk[inside], [b]]), np.concatenate([[za], zk[inside], [zb]]))
    rms = float(np.sqrt(np.mean(r[keep] ** 2))) if keep.any() else float("nan")
    return float(area), keep, (za, zb), rms, ends_from
