"""Rotating-drum frames: the dynamic angle of repose, by one method for photos of a drum on its
stand (003 Sec. 2) and for frames exported by drum testers (GranuDrum-style: cropped to the
drum window, 8- or 16-bit grey, time-averaged over many frames, no plate in view).

1. Grey level (:func:`soilcal.imaging.io.read_gray_reduced`): BMP/PNG/TIFF/JPEG, 8- or 16-bit
   single channel or colour (luminance), Gaussian-smoothed (sigma 1.2 px).  A frame of more than
   :data:`DRUM_WORK_PIXELS` pixels (a phone's photo) is measured reduced to that size, as a heap
   photo is; the drum's centre and radius, given or found, are in the frame's own pixels.
2. The drum (``drum_reference``):

   * ``manifest``: ``drum_centre_px`` and ``drum_radius_px`` given by the user;
   * ``rim``: the innermost of the concentric circles that a Hough transform of the Canny
     edges (thresholds relative to the frame's strongest gradients, on a copy reduced to about
     240 px) finds with edges along at least 30 % of its visible perimeter (the powder hides
     the rim where it lies against it), refined by a RANSAC circle fit through the
     full-resolution edge pixels near it;
   * ``image border``: no such circle, so the frame is cropped to the drum: centre = image
     centre, radius = half the shorter side.  A frame that shows only part of a larger drum
     and no rim needs the drum given: the central chord is the drum's.

   A rim that an ellipse fits better than the circle (:func:`window_ellipse`), of axes ratio
   below :data:`MIN_WINDOW_AXES_RATIO`, is a window seen off the drum's axis (a phone held to
   one side or above): refused, naming the ratio, as the frame tilts the surface.  Only a
   ``rim`` drum is checked: ``image border`` and ``manifest`` drums are taken as circles.

   The outer ``rim_margin`` (default 5 %) of the radius is masked, as the testers' software
   masks the drum wall.
3. Level (``level_reference``): ``manifest roll`` when the user gives ``roll_deg`` (the angle by
   which a true horizontal appears rotated counter-clockwise in the frame); ``plate`` when a long
   straight near-horizontal edge lies below the drum (base plate or table, found as for piles)
   and ``level`` is ``auto`` (default) or ``plate``; otherwise ``image axes`` (testers mount the
   camera square to the drum).  A frame with no plate edge below the drum within the plate
   search but a straight edge across it below the drum tilted beyond it
   (:func:`soilcal.imaging.measure._plate_beyond_search`) is refused naming the tilt: the
   ``roll_deg`` to give if that edge is the plate's (a camera rolled further), ``level: image``
   if it is not (a shadow, a table's edge).  With a plate found, a tilted edge is no roll.  ``level: image`` skips the plate search, ``level: plate``
   requires a plate.  The frame is rotated about the drum centre by the roll.
4. Interface: Otsu's threshold inside the masked drum separates powder from air; the powder is
   the class lying lower (its centroid below the air's: dark powder on a white backlight, or
   the converse), its largest connected region the bed, with every other region of at least 2 %
   of the drum's area whose contact with the drum wall reaches below the bed's highest wall
   contact on its side, or that lies on the bed across a cut of at most 0.05 drum radii, the
   bed growing by each region joined (a reflection band, a glare line or a bracket across the
   window cuts the bed into such pieces, two glare lines into three one above the other;
   powder held in a lifter above the surface, or a hub floating in the air, is no bed).  In every
   column the powder's top is the top of the first powder run with air above it and powder
   below (the medians over 30 px beyond it differ by at least :data:`MIN_STEP` of the bed's
   step: a thin streak of the powder's grey across the air joined to the bed, a glare line or a
   rod, is passed over), refined to the half-level crossing: the row where the grey level
   crosses the mean of those two levels, linearly interpolated (a column crossing it upwards
   twice, with 3 or more rows back below it between, is left out: a streak just above or just
   below the surface).  A time-averaged frame's soft grey ramp thus gives the
   median surface position to a fraction of a pixel, whatever its grey levels.  Columns where
   the powder reaches the masked rim are wall, not surface.
5. Angle (``angle_deg``): least-squares line v = a + b u (u along the level, as ``np.polyfit``
   fits it) through the surface points in the columns under the central ``chord_fraction``
   (default 0.6) of the surface's chord, the segment between its wall contacts (each end of the measured
   surface extended along its tangent across the masked rim to the drum circle), the window
   centred on the foot of the perpendicular from the drum centre; i.e. the slope of the free surface through the drum centre (one pass drops points
   beyond 4 robust sigma).  S-shape: ``upper_deg`` and ``lower_deg`` are such lines over the
   upper and lower thirds of the measured surface, ``s_shape_deg = angle_deg - (upper_deg +
   lower_deg) / 2`` is zero for a straight surface and positive when the middle is steeper
   than the ends (a cascading drum); ``line_rms_pct`` is the RMS distance of the whole surface
   from one straight line, in % of the drum radius.
6. A frame is refused, with one message (:data:`DRUM_EXPECTED`, what was found instead), when it
   shows no powder against air in the drum, a surface outside :data:`DRUM_ANGLE_RANGE` (a level
   boundary is a frame with no turning drum in it, e.g. a table edge) or one straying
   more than :data:`MAX_LINE_RMS_PCT` % of the radius from a line (no powder surface).
7. Confidence: a frame whose surface points stray more than :data:`MAX_ROUGHNESS_PCT` % of the
   radius (RMS, ``roughness_pct``, across the surface from its fitted line) from a local parabola
   over 0.1 radii along the surface, and whose upper or lower third's angle parts more than
   :data:`MAX_THIRD_TILT_DEG` deg from the central chord's, is "low" (``low_reason``): particles in
   flight above the upper part, crowding into powder-grey clusters traced as surface, make the
   trace jagged and tilt the line; a free surface, straight or S-shaped, is smooth at that scale,
   and clods spread along it leave the thirds as the chord.  A frame flagged low that the user has
   checked is averaged all the same with ``accept_low: true`` (``--accept-low``): its result says
   ``accepted_by_user``, its group lists it in ``accepted_low``.

The frames of one group measured "ok" are averaged, the others set aside (:func:`measure_drum`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy import ndimage as ndi
from skimage import feature, filters, measure, morphology, transform

from soilcal.errors import InputError
from soilcal.imaging.drum_options import (CHORD_FRACTION, LEVELS, OPTIONS, RIM_MARGIN,  # noqa: F401
                                          frame_options)
from soilcal.imaging.edges import hough_circle
from soilcal.imaging.io import read_gray_reduced
from soilcal.imaging.measure import (PILE_WORK_PIXELS, PLATE_MAX_ROLL_DEG, Stages, _plate_beyond_search, open_fill,
                                     plate_line_any, roll_of)
from soilcal.imaging.refusal import Tried, explained

MIN_RIM_SUPPORT = 0.3
#: the angles a measured free surface may stand at: a boundary within 3 deg of level is the
#: edge of a table, a plate or a wall in a frame with no drum in it (their edges read 0.0 to
#: 1.8 deg on the heap photos), which a turning drum's powder, even a free-flowing one at a
#: low speed (5 deg), does not show; a drum stopped after turning keeps a sloping surface, so a
#: frame cannot tell a drum at rest from a turning one
DRUM_ANGLE_RANGE = (3.0, 80.0)
#: where a frame's drum circle came from, as a refusal or a low reason names it
DRUM_SOURCE_WORDS = {"image border": "the image border: no drum rim found", "rim": "the drum rim found",
                     "manifest": "the drum as given"}
#: the most a free surface may stray from one straight line (RMS, % of the drum radius): a
#: cascading drum's S stays within a few %, a boundary that wanders further is no powder surface
MAX_LINE_RMS_PCT = 10.0
#: the least grey step across a surface point (the median of the 30 px below it minus that of the
#: 30 px above, beyond 8 px), as a fraction of the bed's step from the air's grey to the powder's:
#: a true surface has the powder below it and the air above (a step near 1)
MIN_STEP = 0.6
#: the most a measured surface may stray from a local parabola over 0.1 drum radii along it (RMS
#: distance across the surface, % of the radius, ``roughness_pct``) for the frame to be "ok"
#: whatever its thirds: drawn straight and S-shaped surfaces give 0.01 to 0.02, rendered drum frames
#: at 45 to 74 deg 0.11 to 0.13, twelve clods 6 % of the radius across along the surface 0.35 to
#: 0.59; 80 to 200 powder-grey particles in flight above the surface (a cascade's curtain), traced
#: as surface where they crowd, give 0.49 to 3.6 and tilt the angle by up to 15 deg
MAX_ROUGHNESS_PCT = 0.55
#: with the surface rougher than :data:`MAX_ROUGHNESS_PCT`, the most the upper or lower third's
#: angle may part from the central chord's (deg) for the frame to be "ok": particles in flight
#: crowding over the upper part tilt the chord away from the thirds, lumps spread evenly along the
#: surface do not
MAX_THIRD_TILT_DEG = 0.65
#: the most the free surface may stop short of the masked drum circle at either end for the frame
#: to be "ok", unless it runs out of the frame there: measured radially, (rm - |end|) / R, the
#: masked radius rm less the end's distance from the drum centre, in drum radii; the end is where
#: the traced surface stops or, past it, where a step from air down to powder along the end's line
#: stops (a bright glare band across the window stops the trace, not the surface).  A
#: bed lies against the drum wall, so its surface reaches the wall at both ends (drawn frames with
#: grains and clods on the surface, S-shaped, 20 to 75 deg, radii 60 to 220 px: 0.02 to 0.11, the
#: most in small drums and steep surfaces, where the columns next to the wall are wall); a circle
#: grossly wrong, larger than the drum or off its centre (a rim smeared by motion blur, a drum given
#: 1.3 times too large and 0.25 radii off), leaves the surface ending 0.23 to 0.38 R inside it, the
#: chord and so the central window not the drum's.  A circle a little wrong (0.1 radii off the
#: centre) leaves the surface ending within the limit and is not caught: it moves the angle by up
#: to about 1 deg
MAX_END_GAP = 0.2
#: what every frame refused for showing no measurable drum is expected to show
DRUM_EXPECTED = (f"a drum frame: powder lying in a drum, clearly darker or lighter than the air above it, its "
                 f"free surface one line at {DRUM_ANGLE_RANGE[0]:.0f} to {DRUM_ANGLE_RANGE[1]:.0f} deg")
#: a frame larger than this (pixels) is measured reduced to it, as a heap photo is: a phone's 12
#: megapixels are decoded reduced (a JPEG by 2, 4 or 8 in its decoder) and scaled to it
DRUM_WORK_PIXELS = PILE_WORK_PIXELS


@dataclass
class DrumResult:
    path: str
    angle_deg: float
    upper_deg: float
    lower_deg: float
    s_shape_deg: float
    line_rms_pct: float
    roll_deg: float
    level_reference: str
    drum_reference: str
    drum_centre_px: list
    drum_radius_px: float
    chord_fraction: float
    n_points: int
    stages: Stages | None = None
    # the measured image's size over the frame's (below 1 for a frame reduced to
    # DRUM_WORK_PIXELS); drum_centre_px and drum_radius_px are in the frame's own pixels (as
    # shown, as the options give them), n_points counts the measured image's columns
    work_scale: float = 1.0
    pixels: str = "frame"
    # RMS distance of the surface points from a local parabola over 0.1 drum radii of columns
    # (Savitzky-Golay), % of the radius: a free surface, straight or S-shaped, is smooth at that
    # scale; particles in flight traced as surface make it jagged
    roughness_pct: float = 0.0
    confidence: str = "ok"  # "low": see low_reason
    low_reason: str = ""
    # the frame flagged low and accepted by the user (option accept_low): averaged into its group,
    # listed in the group's accepted_low; confidence stays "low"
    accepted_by_user: bool = False

    def as_dict(self):
        d = asdict(self)
        d.pop("stages")
        return d


def _circle_support(edges, cx, cy, r):
    """(fraction of the circle's in-image perimeter on edge pixels, in-image fraction)."""
    h, w = edges.shape
    a = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    c, rr = cx + r * np.cos(a), cy + r * np.sin(a)
    ok = (c >= 1) & (c <= w - 2) & (rr >= 1) & (rr <= h - 2)
    if not ok.any():
        return 0.0, 0.0
    on = edges[np.round(rr[ok]).astype(int), np.round(c[ok]).astype(int)]
    return float(on.mean()), float(ok.mean())


def _edges(img, sigma=2.0):
    """Canny edges with hysteresis thresholds of 10 % and 20 % of the frame's strongest
    gradients (99.9th percentile of the smoothed Sobel magnitude), so a faint, blurred drum
    edge counts as an edge in a low-contrast frame as in a sharp one."""
    sm = filters.gaussian(img, sigma)
    g = np.hypot(ndi.sobel(sm, axis=0), ndi.sobel(sm, axis=1))
    top = float(np.percentile(g, 99.9))
    return feature.canny(img, sigma=sigma, low_threshold=0.1 * top, high_threshold=0.2 * top)


def _hspace_peaks(img, dist, top=None):
    """The peaks of one radius's Hough space as :func:`skimage.transform.hough_circle_peaks`
    finds them (skimage 0.26 ``_prominent_peaks``: local maxima over (2 ``dist`` + 1)^2 above
    half the space's maximum, strongest region first, each suppressing its neighbourhood), with
    the regions' centroids and maxima taken in one pass instead of one region object each: a
    mottled frame's noisy spaces hold hundreds of regions per radius, which took seconds.
    ``top``: the space's maximum, where the caller has it.  Returns (values, columns, rows)."""
    rows, cols = img.shape
    threshold = 0.5 * float(np.max(img) if top is None else top)
    size = 2 * dist + 1
    # the maximum filter, peaks and regions in the box of the pixels above the threshold, widened
    # by dist (or to the image's edge): every pixel of a region and every region's centroid lies in
    # that box, and the filter's (2 dist + 1)-wide windows of the box's pixels lie in the widened
    # box or end at the image's edge as they do in the whole space, so the numbers read are those
    # of the whole space's filter; ndi.label numbers the regions in raster order, the same in the box
    rr, cc = np.nonzero(img > threshold)
    if rr.size == 0:
        return np.array([]), np.array([], int), np.array([], int)
    ya, yb = max(int(rr.min()) - dist, 0), min(int(rr.max()) + dist + 1, rows)
    xa, xb = max(int(cc.min()) - dist, 0), min(int(cc.max()) + dist + 1, cols)
    sub = img[ya:yb, xa:xb]
    sub_max = ndi.maximum_filter1d(sub, size=size, axis=0, mode="constant", cval=0)
    sub_max = ndi.maximum_filter1d(sub_max, size=size, axis=1, mode="constant", cval=0)
    img_max = np.zeros_like(img)  # read only in the box, where it holds the whole space's filter
    img_max[ya:yb, xa:xb] = sub_max
    labels, n = ndi.label(sub * (sub == sub_max) > threshold, structure=np.ones((3, 3)))
    if n == 0:
        return np.array([]), np.array([], int), np.array([], int)
    r_idx, c_idx = np.nonzero(labels)
    lab = labels[r_idx, c_idx]
    r_idx, c_idx = r_idx + ya, c_idx + xa
    count = np.bincount(lab, minlength=n + 1)[1:]
    cen_r = np.round(np.bincount(lab, r_idx, minlength=n + 1)[1:] / count).astype(int)
    cen_c = np.round(np.bincount(lab, c_idx, minlength=n + 1)[1:] / count).astype(int)
    top = np.full(n + 1, -np.inf)  # each region's maximum (ndi.maximum's numbers, without its sort of
    np.maximum.at(top, lab, img_max[r_idx, c_idx])  # every label: a max is exact in any order)
    top = top[1:]
    order = sorted(range(n), key=lambda k: top[k])[::-1]  # as sorted(props)[::-1]: stable, then reversed
    vals, xs, ys = [], [], []
    for k in order:
        y, x = cen_r[k], cen_c[k]
        accum = img_max[y, x]
        if accum > threshold:
            y0, y1 = max(y - dist, 1), min(y + dist, rows - 1)  # rows 1 to rows - 1, not reflected
            x0, x1 = x - dist, x + dist
            img_max[y0:y1 + 1, max(x0, 0):min(x1, cols - 1) + 1] = 0
            if x0 < 0 or x1 >= cols:  # columns beyond a side wrap round, mirrored in rows
                for xx in [c for c in range(x0, x1 + 1) if c < 0 or c >= cols]:
                    img_max[rows - np.arange(y0, y1 + 1), xx % cols] = 0
            vals.append(accum)
            ys.append(y)
            xs.append(x)
    return np.array(vals), np.array(xs, int), np.array(ys, int)


def _circle_peaks(hspaces, radii, dist, total):
    """:func:`skimage.transform.hough_circle_peaks` (``min_xdistance = min_ydistance = dist``,
    ``total_num_peaks = total``) with its per-radius peak search done by :func:`_hspace_peaks`,
    and only for the radii whose space can hold one of the peaks kept.

    The peaks kept are the strongest ``total`` taken greedily, strongest first, each not within
    ``dist`` (in x and in y) of one kept before it (at ``dist`` 1 skimage keeps the strongest
    ``total`` without that suppression, and so does this); a peak weaker than the last one kept comes
    after every kept one in that order and changes nothing.  A radius's peaks are at most its
    space's maximum, so the spaces are searched in the order of their maxima, strongest first,
    until the peaks found keep ``total`` of which the weakest is stronger than every space not
    yet searched: the peaks of those spaces would all come after it.  The peaks found are put in
    the radii's order, as when every space is searched, before they are sorted.  Peaks of equal
    strength are left in the order NumPy's sort gives them, which depends on every peak sorted:
    where two peaks down to the weakest kept are equal, every space is searched and the peaks of
    all sorted together, as skimage does."""
    from skimage.transform.hough_transform import label_distant_points

    def kept(found):
        r, cx, cy, accum = [], [], [], []
        for i in sorted(found):
            h_p, x_p, y_p = found[i]
            r.extend((radii[i],) * len(h_p))
            cx.extend(x_p)
            cy.extend(y_p)
            accum.extend(h_p)
        r, cx, cy, accum = np.array(r), np.array(cx), np.array(cy), np.array(accum)
        s = np.argsort(accum)
        accum, cx, cy, r = accum[s][::-1], cx[s][::-1], cy[s][::-1], r[s][::-1]
        if len(accum) == 0 or dist == 1:  # skimage keeps the strongest ``total`` unsuppressed at 1
            return accum[:total], cx[:total], cy[:total], r[:total]
        keep = label_distant_points(cx, cy, dist, dist, total)
        return accum[keep], cx[keep], cy[keep], r[keep]

    tops = np.max(hspaces, axis=(1, 2)) if len(radii) else np.array([])
    order = np.argsort(-tops, kind="stable")
    found, tied = {}, False
    for j, i in enumerate(order):
        found[int(i)] = _hspace_peaks(hspaces[i], dist, tops[i])
        if tied or j + 1 == len(order):
            continue
        nxt = tops[order[j + 1]]  # the most any space not yet searched holds
        if sum(int(np.count_nonzero(v[0] > nxt)) for v in found.values()) >= total:
            out = kept(found)
            if len(out[0]) == total and out[0][-1] > nxt:
                vals = np.concatenate([v[0] for v in found.values()])
                vals = vals[vals >= out[0][-1]]
                if np.unique(vals).size == vals.size:
                    return out
                tied = True  # equal peaks down to the weakest kept: sorted among all peaks, as before
    return kept(found)


def find_drum(gray, edges=None):
    """(cx, cy, radius, reference) of the drum: its rim circle, else the image border.
    ``edges``: :func:`_edges` of ``gray``, where the caller has them already."""
    h, w = gray.shape
    f = max(1.0, min(h, w) / 240.0)
    small = transform.rescale(gray, 1.0 / f, anti_aliasing=True) if f > 1 else gray
    m = min(small.shape)
    radii = np.arange(int(0.25 * m), int(0.62 * m) + 1)
    hs = hough_circle(_edges(small), radii)
    _, xs, ys, rs = _circle_peaks(hs, radii, dist=3, total=8)
    edges = _edges(gray) if edges is None else edges
    er, ec = np.nonzero(edges)
    near_edges = morphology.dilation(edges, morphology.disk(1))
    found = []
    for x, y, r in zip(xs * f, ys * f, rs * f):
        near = np.abs(np.hypot(ec - x, er - y) - r) < 2.5 * f
        if near.sum() < 30:
            continue
        pts = np.column_stack([ec[near], er[near]]).astype(float)
        model, _ = measure.ransac(pts, measure.CircleModel, min_samples=3, residual_threshold=1.5,
                                  max_trials=200, rng=0)
        if not model:  # None (no inliers) or the library's failed estimate of the final fit
            continue
        (x1, y1), r1 = model.center, float(model.radius)
        if abs(r1 - r) > 0.1 * r or math.hypot(x1 - x, y1 - y) > 0.1 * r:
            continue  # the fit left the Hough circle: not this circle's edge
        support, visible = _circle_support(near_edges, x1, y1, r1)
        if visible >= 0.5 and support >= MIN_RIM_SUPPORT:
            found.append((support, float(x1), float(y1), r1))
    if not found:
        return (w - 1) / 2.0, (h - 1) / 2.0, min(h, w) / 2.0, "image border"
    _, bx, by, br = max(found)
    inner = [t for t in found if math.hypot(t[1] - bx, t[2] - by) < 0.05 * br]
    _, cx, cy, r = min(inner, key=lambda t: t[3])
    return cx, cy, r, "rim"


#: the least axes ratio (minor over major) of the drum window's outline in the frame: a circular
#: window seen off the drum's axis is an ellipse, which tilts a surface at 45 deg in the frame by
#: atan(1 / ratio) - 45 deg; at this ratio by 0.5 deg (0.9 reads 48.0 deg, 0.8 reads 51.3)
MIN_WINDOW_AXES_RATIO = math.tan(math.radians(45.0)) / math.tan(math.radians(45.5))


class _Ellipse(measure.EllipseModel):
    """skimage's ellipse with the Sampson distance (first-order geometric) as its residual: the
    library's exact distance solves one optimisation per point, seconds per frame."""

    def residuals(self, data):
        xc, yc, a, b, th = self.params
        x, y = data[:, 0] - xc, data[:, 1] - yc
        u, v = x * np.cos(th) + y * np.sin(th), -x * np.sin(th) + y * np.cos(th)
        return np.abs((u / a) ** 2 + (v / b) ** 2 - 1.0) / np.maximum(2.0 * np.hypot(u / a ** 2, v / b ** 2), 1e-12)


def window_ellipse(edges, cx, cy, r):
    """The drum window's outline as an ellipse in the frame's edge map ``edges``
    (:func:`_edges`), when an ellipse fits its rim better than the circle found: (axes ratio
    minor / major, minor axis direction in deg from the image's horizontal, counter-clockwise),
    else None.  RANSAC of :class:`_Ellipse` through the edge
    pixels between 0.6 r and 1.6 r from the circle's centre; the ellipse counts only with at
    least 1.5 times the edge pixels within 1.5 px of it that the best circle through them (RANSAC
    on the same pixels) has and its mean radius 0.6 to 1.6 r, wherever its centre (far off the
    axis the circle found is a smaller one inside the ellipse, off its centre).  A true circle's
    rim, or its ring's two edges, hold as many pixels on the circle as on any ellipse; so does a
    window seen slightly off the axis on a small drum (ratio 0.96 to 0.975 at R 70 to 90 px),
    which is not caught.  Not checked: a drum found from the image border, or given in the
    manifest."""
    import warnings

    er, ec = np.nonzero(edges)
    d = np.hypot(ec - cx, er - cy)
    near = (d > 0.6 * r) & (d < 1.6 * r)
    pts = np.column_stack([ec[near], er[near]]).astype(float)
    if len(pts) < 50:
        return None
    pts = pts[:: max(1, len(pts) // 4000)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the library's deprecation notices for model.params
        circle, on = measure.ransac(pts, measure.CircleModel, min_samples=3, residual_threshold=1.5,
                                    max_trials=150, rng=0)
        on_circle = int(on.sum()) if circle else 0  # circle: None or a failed estimate when no circle fits
        model, inl = measure.ransac(pts, _Ellipse, min_samples=5, residual_threshold=1.5, max_trials=150, rng=0)
        if not model:
            return None
        xc, yc, a, b, th = (float(x) for x in model.params)
    # an ellipse clearly holding more of the rim than the circle is the window wherever its centre:
    # far off the axis the circle found is a smaller one inside the ellipse, off its centre
    if inl.sum() < 1.5 * on_circle or not 0.6 * r <= math.sqrt(a * b) <= 1.6 * r:
        return None
    minor_th = th if a < b else th + math.pi / 2  # image rows point down: angles counter-clockwise negate
    return min(a, b) / max(a, b), float(-math.degrees(minor_th) % 180.0)


def _tls(u, v):
    p = np.column_stack([u, v])
    m = p.mean(axis=0)
    d = np.linalg.svd(p - m, full_matrices=False)[2][0]
    if d[0] < 0:
        d = -d
    return m, d, (p - m) @ np.array([-d[1], d[0]])


def _tls_robust(u, v):
    """Total-least-squares line; one pass drops points beyond max(4 robust sigma, 1 px)."""
    m, d, res = _tls(u, v)
    s = 1.4826 * np.median(np.abs(res - np.median(res)))
    keep = np.abs(res - np.median(res)) <= max(4.0 * s, 1.0)
    if keep.sum() >= 10 and not keep.all():
        m, d, res = _tls(u[keep], v[keep])
    return m, d


def _ols_robust(u, v):
    """Least-squares line v = a + b u (the level frame's slope, as np.polyfit gives it); one
    pass drops points beyond max(4 robust sigma, 1 px).  Returns (point, unit direction)."""
    b, a = np.polyfit(u, v, 1)
    res = v - (a + b * u)
    s = 1.4826 * np.median(np.abs(res - np.median(res)))
    keep = np.abs(res - np.median(res)) <= max(4.0 * s, 1.0)
    if keep.sum() >= 10 and not keep.all():
        b, a = np.polyfit(u[keep], v[keep], 1)
    um = float(np.mean(u))
    return np.array([um, a + b * um]), np.array([1.0, b]) / math.hypot(1.0, b)


def _angle(d, sign=1.0):
    return float(np.degrees(np.arctan2(sign * d[1], d[0])))


def _thin_cut_above(piece, main, rm):
    """Whether ``piece`` lies on ``main`` across a thin cut (a glare line or a rod along the
    window): in the median of the piece's columns the main region begins at most 0.05 drum radii
    below the piece's lowest pixel.  Powder in a lifter stands clear of the surface by air."""
    cols = np.flatnonzero(piece.any(axis=0))
    gaps = []
    for c in cols:
        bottom = np.flatnonzero(piece[:, c]).max()
        below = np.flatnonzero(main[bottom:, c])
        gaps.append(below[0] if below.size else np.inf)
    return bool(cols.size) and float(np.median(gaps)) <= 0.05 * rm


def _surface(path, p, inside, cx, cy, rm, circle_said=""):
    """Sub-pixel (column, row) points of the powder's free surface (powder high in ``p``)."""
    h, w = p.shape
    vals = p[inside]
    t = filters.threshold_otsu(vals)
    lo_m, hi_m = vals[vals < t].mean(), vals[vals >= t].mean()
    if hi_m - lo_m < 0.1:
        raise InputError(path, "image", DRUM_EXPECTED, f"no powder against air: the grey classes inside the drum "
                         f"differ by {hi_m - lo_m:.2f} of the frame's range (at least 0.10 needed)")
    binary = open_fill((p >= t) & inside)
    lab = measure.label(binary)
    sizes = np.bincount(lab.ravel())
    sizes[0] = 0
    if lab.max() == 0 or sizes.max() < 0.02 * np.pi * rm ** 2:
        raise InputError(path, "image", DRUM_EXPECTED, "no powder region in the drum")
    # the bed: the largest powder region, and every other one of at least 2 % of the drum's area
    # that lies against the drum wall (the edge of the measured disc) down to below the bed's
    # highest wall contact on its side of the drum, or that lies on the bed across a thin cut,
    # the bed growing by each piece joined until no other joins: a bright reflection band or a
    # dark bracket across the window cuts the bed into pieces that run down the wall from the
    # surface's two ends, a glare line along the window into pieces one above the other (two
    # lines into three, the top one lying on the middle one, not on the largest), while powder
    # held up in a lifter against the wall above the surface, a hub or a speck floating in the
    # air is no bed
    wall = inside & ~ndi.binary_erosion(inside, np.ones((3, 3), bool), border_value=0)
    main = int(sizes.argmax())
    powder = lab == main
    left = [int(k) for k in np.flatnonzero(sizes >= 0.02 * np.pi * rm ** 2) if k != main]
    grown = True
    while grown and left:
        grown = False
        wr, wc = np.nonzero(wall & powder)
        for k in list(left):
            kr, kc = np.nonzero(wall & (lab == k))
            if wr.size == 0 or kr.size == 0:
                continue
            side = (wc >= cx) == (kc.mean() >= cx)
            if kr.max() > (wr[side].min() if side.any() else wr.min()) or _thin_cut_above(lab == k, powder, rm):
                left.remove(k)
                powder = powder | (lab == k)
                grown = True
                break
    # the bed dilated and eroded by disks (skimage's disk(k): offsets of x^2 + y^2 <= k^2), read from
    # Euclidean distance transforms: a pixel lies within disk(k) of the bed when its distance to the
    # nearest bed pixel is at most k, and the bed's disk(k) erosion keeps the bed pixels farther than k
    # from every pixel off the bed (exact integer distances, as morphology.dilation and .erosion give them
    # with their default reflected border, which puts no pixel nearer than the image's own)
    # Both transforms read the bed's bounding box only, widened by 9 px for the first and 1 px for
    # the second (within the frame): every bed pixel lies in it, a pixel beyond the wider box is
    # more than 8 px from the bed, and a bed pixel's nearest pixel off the bed lies in the narrower
    # box (on its ring of pixels off the bed where none is nearer), so the distances read are the
    # whole frame's
    rows_on, cols_on = np.flatnonzero(powder.any(axis=1)), np.flatnonzero(powder.any(axis=0))

    def around(m):  # the bed's bounding box widened by m px, within the frame
        return np.s_[max(rows_on[0] - m, 0):rows_on[-1] + m + 1, max(cols_on[0] - m, 0):cols_on[-1] + m + 1]

    near = np.zeros_like(powder)
    near[around(9)] = ndi.distance_transform_edt(~powder[around(9)]) <= 8.0
    air = inside & ~near
    if air.sum() < 20:
        raise InputError(path, "image", DRUM_EXPECTED, (
            f"the bed filling the drum circle {circle_said}, no air above it: that circle is not the drum's "
            "window (a rim smeared by motion blur or out of focus is found wrong: give drum_centre_px and "
            "drum_radius_px, or take a sharper frame)"))
    # the powder's grey from its core 8 px from the bed's edge; a thin bed (a small drum little
    # filled) from as far inside as it has
    depth = np.zeros(powder.shape)  # each bed pixel's distance from the nearest pixel off the bed
    depth[around(1)] = ndi.distance_transform_edt(powder[around(1)])
    for k in (8, 4, 2, 1, 0):
        core = ((depth > k) if k else powder) & inside
        if core.sum() >= 20:
            break
    else:
        raise InputError(path, "image", DRUM_EXPECTED, f"{int(core.sum())} powder pixels in the drum circle "
                         f"{circle_said} (at least 20 needed): the frame shows no bed")
    air_lvl = np.median(p[air])
    pow_lvl = np.median(p[core])
    cols, rows = [], []
    for c in range(max(0, int(np.ceil(cx - rm)) + 1), min(w, int(np.floor(cx + rm)))):
        half = math.sqrt(max(rm ** 2 - (c - cx) ** 2, 0.0))
        top, bot = cy - half, cy + half
        idx = np.flatnonzero(powder[:, c])
        if idx.size == 0:
            continue
        if idx[0] <= top + 2:
            continue  # the powder reaches the rim in this column: wall, not free surface
        r0, r1 = int(np.ceil(top)) + 1, int(np.floor(bot))
        # the surface is the top of the first powder run with powder below it and air above: a
        # thin streak of the powder's class across the air (a glare line on a dark drum, a dark
        # rod in front of a light one) joined to the bed has air, not powder, below its top
        for i in idx[np.r_[True, np.diff(idx) > 1]]:
            i = int(i)
            if i >= bot - 2:
                break
            a = p[max(r0, i - 38):max(r0, i - 8), c]
            b = p[min(r1, i + 8):min(r1, i + 38), c]
            la = np.median(a) if a.size >= 4 else air_lvl
            lb = np.median(b) if b.size >= 4 else pow_lvl
            if lb - la >= MIN_STEP * (pow_lvl - air_lvl):
                break
        else:
            continue
        if i >= bot - 2:
            continue
        mid = 0.5 * (la + lb)
        s0, s1 = max(r0, i - 25), min(r1, i + 25)
        seg = p[s0:s1 + 1, c]
        up = seg >= mid
        js = np.flatnonzero(up[1:] & ~up[:-1]) + 1
        if js.size == 0:
            continue
        gap = np.flatnonzero(~up[:-2] & ~up[1:-1] & ~up[2:])
        if np.any((gap > js[0]) & (gap < js[-1])):
            continue  # two steps up with 3 or more rows between back below the half level: a streak
            # across the air just above the surface, or across the bed just below it; which is the
            # surface cannot be told in this column
        j = int(js[np.argmin(np.abs(s0 + js - i))])
        rows.append(s0 + j - 1 + (mid - seg[j - 1]) / (seg[j] - seg[j - 1]))
        cols.append(float(c))
    return np.asarray(cols), np.asarray(rows), binary, powder


def _surface_reach(p, u, v, part, end, outward, d, cx, cy, rm, R):
    """How far from the drum centre the free surface reaches past its traced ``end`` (a point;
    ``part``: the trace's points next to it, boolean over ``u, v``, drum centre at the origin, v
    up; ``outward``: the end's sign along the surface direction ``d``).  The end's line is followed
    to the masked circle ``rm``, and at each pixel along it the grey ``p`` (powder high) just below
    the line is compared with just above it, as under the traced end: the surface goes on where
    the step from air to powder is at least half the traced end's (a bright glare band across the
    window shifts both sides alike, the trace stopping at it while the bed goes on to the wall);
    the reach is the furthest such point up to which at least half the points followed are such.
    Beyond the drum's wall (a circle found or given larger than the drum, or off it) no bed lies
    under the line: the reach stops at the wall, short of that circle."""
    me, de, _ = _tls(u[part], v[part])
    de = de if de @ d * outward > 0 else -de
    nrm = np.array([-de[1], de[0]])
    nrm = nrm if nrm[1] < 0 else -nrm  # into the powder, below the surface
    off = np.arange(max(3.0, 0.02 * R), max(8.0, 0.06 * R) + 0.5)

    def step(q):  # (n, 2) points: median grey below minus above, nan where a side leaves the circle
        lo = q[:, None, :] + off[None, :, None] * nrm
        hi = q[:, None, :] - off[None, :, None] * nrm
        out = np.full(len(q), np.nan)
        ok = (np.hypot(lo[..., 0], lo[..., 1]).max(axis=1) < rm) & (np.hypot(hi[..., 0], hi[..., 1]).max(axis=1) < rm)
        for k in np.flatnonzero(ok):
            a, b = (ndi.map_coordinates(p, [cy - x[:, 1], cx + x[:, 0]], order=1) for x in (lo[k], hi[k]))
            out[k] = np.median(a) - np.median(b)
        return out

    ref = np.nanmedian(step(np.column_stack([u[part], v[part]])))
    s0 = float((end - me) @ de)
    b = float(me @ de)
    s1 = -b + math.sqrt(max(b * b - float(me @ me) + rm ** 2, 0.0))
    if not np.isfinite(ref) or ref <= 0 or s1 <= s0 + 1:
        return float(np.hypot(*end))
    q = me + np.arange(s0 + 1.0, s1)[:, None] * de
    st = step(q)
    q, st = q[np.isfinite(st)], st[np.isfinite(st)]
    good = st >= 0.5 * ref
    carried = good & (np.cumsum(good) >= 0.5 * np.arange(1, good.size + 1))
    return max(float(np.hypot(*end)), float(np.hypot(*q[np.flatnonzero(carried)[-1]])) if carried.any() else 0.0)


def measure_drum_frame(path, threshold="otsu", keep_stages=False, options=None, refusals=None) -> DrumResult:
    """Dynamic angle and S-shape of one drum frame (see the module text for the method);
    ``refusals``: a folder for the diagnostic image of a frame that cannot be measured
    (:mod:`soilcal.imaging.refusal`)."""
    tried = Tried(keep_masks=refusals is not None)
    with explained(path, refusals, tried):
        return _measure_drum_frame(path, threshold, keep_stages, options, tried)


def _measure_drum_frame(path, threshold, keep_stages, options, tried: Tried) -> DrumResult:
    if threshold != "otsu":
        raise InputError(path, "threshold", "'otsu' for drum frames", threshold)
    opts = frame_options(options, path)
    # a phone's 12 megapixels are measured at the heap photos' working size: decoded reduced by
    # a whole factor (a JPEG in its decoder), then scaled to DRUM_WORK_PIXELS
    raw, rgb, (w0, h0) = read_gray_reduced(path, DRUM_WORK_PIXELS)
    if w0 * h0 > DRUM_WORK_PIXELS:
        f = math.sqrt(DRUM_WORK_PIXELS / raw.size)
        raw = transform.rescale(raw, f, anti_aliasing=True)
        rgb = transform.rescale(rgb, f, channel_axis=-1, anti_aliasing=True)
    gray = filters.gaussian(raw, 1.2)
    tried.rgb, tried.gray = rgb, gray
    h, w = gray.shape
    sx, sy = w / w0, h / h0  # the measured image's pixels per frame pixel

    def frame_px(x, y, r):  # measured-image pixels to the frame's (pixel centres at i + 0.5)
        return (x + 0.5) / sx - 0.5, (y + 0.5) / sy - 0.5, r / math.sqrt(sx * sy)

    if opts["drum_centre_px"] is not None:
        (cx, cy), R, dref = opts["drum_centre_px"], opts["drum_radius_px"], "manifest"
        cx, cy, R = (cx + 0.5) * sx - 0.5, (cy + 0.5) * sy - 0.5, R * math.sqrt(sx * sy)
    else:
        tried.add("drum circle search")
        edges = _edges(gray)  # the rim's search and the ellipse check read the same edge map
        cx, cy, R, dref = find_drum(gray, edges)
        tried.attempts[-1].circle = (cx, cy, R)
        tried.attempts[-1].outcome = "drum at ({:.0f}, {:.0f}) px, radius {:.0f} px".format(*frame_px(cx, cy, R))
        ell = window_ellipse(edges, cx, cy, R) if dref == "rim" else None
        if ell is not None and ell[0] < MIN_WINDOW_AXES_RATIO:
            q, minor = ell
            raise InputError(path, "image", "a drum window seen square-on: its rim a circle in the frame (axes ratio at "
                             f"least {MIN_WINDOW_AXES_RATIO:.3f})",
                             f"the rim an ellipse of axes ratio {q:.3f}, its short axis at {minor:.0f} deg from the "
                             f"frame's horizontal: the camera looked at the window about "
                             f"{math.degrees(math.acos(q)):.0f} deg off the drum's axis, which tilts a surface in "
                             f"the frame by up to {math.degrees(math.atan(1.0 / q)) - 45.0:.1f} deg; take the frame "
                             "with the camera on the drum's axis")
    roll, lref = 0.0, "image axes"
    if opts["roll_deg"] is not None:
        roll, lref = opts["roll_deg"], "manifest roll"
    elif opts["level"] != "image":
        edges = feature.canny(gray, sigma=1.5)  # plate_lines' own edge map, kept for the tilted-edge search
        line = plate_line_any(path, gray, below=(cx, cy + R), required=False, edges=edges)
        # no plate below the drum within the plate search: a plate tilted beyond it (a camera
        # rolled further) would have given the image axes, and the angle off by the roll.  Only
        # then is a straight edge beyond the search looked for: with a plate found, a tilted
        # edge is a shadow or a table's edge, not a roll.  What it is cannot be told from the
        # photo, so both readings are offered
        tilted = None
        if line is None:
            found = _plate_beyond_search(edges, ndi.binary_dilation(edges, np.ones((3, 1), bool)), [],
                                         below=(cx, cy + R))
            tilted = found[0] if found else None
        if tilted is not None:
            tried.lines = [tilted]
            tilt = roll_of(tilted[0])
            raise InputError(path, "image", f"a plate edge below the drum within {PLATE_MAX_ROLL_DEG:.0f} deg of "
                             "horizontal (the plate search looks no further), or the frame's roll given",
                             f"no plate edge within {PLATE_MAX_ROLL_DEG:.0f} deg of horizontal below the drum, and a "
                             f"straight edge across the photo below it tilted {tilt:.1f} deg: if that edge is the "
                             f"plate's (the camera rolled), roll_deg: {tilt:.1f} in the manifest levels the frame; if "
                             "it is not (a shadow, a table's edge) and the camera was level, level: image")
        if line is not None:
            tried.lines = [line]
            roll, lref = roll_of(line[0]), "plate"
        elif opts["level"] == "plate":
            raise InputError(path, "level", "a straight base plate edge below the drum (level: plate)", "none found")
    g = transform.rotate(gray, -roll, center=(cx, cy), order=1, mode="edge") if roll else gray
    rm = R * (1.0 - opts["rim_margin"])
    rr, cc = np.arange(h)[:, None], np.arange(w)[None, :]  # broadcast as np.mgrid's rows, columns
    inside = (cc - cx) ** 2 + (rr - cy) ** 2 < rm ** 2
    if inside.sum() < 400:
        raise InputError(path, "image", "the drum inside the frame", "drum centre ({:.0f}, {:.0f}) px, "
                         "radius {:.0f} px".format(*frame_px(cx, cy, R)))
    # the powder is the class lying lower in the drum (its centroid below the air's)
    t = filters.threshold_otsu(g[inside])
    bright = inside & (g >= t)
    dark = inside & (g < t)
    if not bright.any() or not dark.any():
        tried.add("powder and air split in the drum (Otsu)", circle=(cx, cy, rm))
        raise InputError(path, "image", DRUM_EXPECTED, "one grey level in the drum")
    bright_powder = np.nonzero(bright)[0].mean() > np.nonzero(dark)[0].mean()  # the classes' mean rows
    tried.add("powder and air split in the drum (Otsu); the lower class is the powder",
              bright if bright_powder else dark, circle=(cx, cy, rm))
    p = g if bright_powder else 1.0 - g
    where = DRUM_SOURCE_WORDS[dref]
    said = "(centre ({:.0f}, {:.0f}) px, radius {:.0f} px, {})".format(*frame_px(cx, cy, R), where)
    cols, rows, binary, powder = _surface(path, p, inside, cx, cy, rm, said)
    if cols.size < 30:
        raise InputError(path, "image", DRUM_EXPECTED, f"a free surface across {cols.size} pixel columns "
                         "(at least 30 needed)")
    u, v = cols - cx, cy - rows  # drum centre at the origin, v up
    pts = np.column_stack([u, v])
    m, d = _tls_robust(u, v)
    sign = 1.0 if d[1] >= 0 else -1.0
    fr = opts["chord_fraction"]
    # the surface's chord joins its two wall contacts: each end (its last 10 % of the extent)
    # is extended along its own tangent line across the masked rim to the drum circle
    tt = (pts - m) @ d
    t0, t1 = tt.min(), tt.max()
    ends = []
    for part, outward in ((tt <= t0 + 0.1 * (t1 - t0), -1.0), (tt >= t1 - 0.1 * (t1 - t0), 1.0)):
        me, de = _tls(u[part], v[part])[:2]
        de = de if de @ d * outward > 0 else -de
        b = float(me @ de)  # |me + s de| = R, the root ahead of the end
        ends.append(me + (-b + math.sqrt(max(b * b - float(me @ me) + R ** 2, 0.0))) * de)
    dc = (ends[1] - ends[0]) / np.linalg.norm(ends[1] - ends[0])
    foot = ends[0] - (ends[0] @ dc) * dc  # foot of the perpendicular from the drum centre
    half = 0.5 * float(np.linalg.norm(ends[1] - ends[0]))
    sel = np.abs(u - foot[0]) <= fr * half * abs(dc[0])  # the columns under the central chord
    if sel.sum() < 20:
        raise InputError(path, "image", DRUM_EXPECTED, f"{int(sel.sum())} surface points in the central {fr:.0%} "
                         "of the chord (at least 20 needed)")
    m, d = _ols_robust(u[sel], v[sel])
    angle = abs(_angle(d))
    # S-shape: thirds of the measured surface along the line, one straight line through all of it
    tt = (np.column_stack([u, v]) - m) @ d
    t0, t1 = np.percentile(tt, [1, 99])
    third = (t1 - t0) / 3.0
    ends, end_lines = {}, []
    for name, part in (("low_t", tt < t0 + third), ("high_t", tt > t1 - third)):
        ends[name] = float("nan")
        if part.sum() >= 10:
            mk, dk = _ols_robust(u[part], v[part])
            ends[name] = sign * _angle(dk)
            end_lines.append((mk[0], mk[1], dk[0], dk[1], "upper third" if (name == "high_t") == (sign > 0)
                              else "lower third"))
    upper, lower = (ends["high_t"], ends["low_t"]) if sign > 0 else (ends["low_t"], ends["high_t"])
    ma, da, res = _tls(u, v)
    keep = np.abs(res) <= 8.0 * 1.4826 * np.median(np.abs(res)) + 2.0
    ma, da, res = _tls(u[keep], v[keep])
    rms = float(np.sqrt(np.mean(res ** 2)) / R * 100.0)
    # roughness across the surface: distances from the fitted line (its normal), sorted and
    # smoothed along it over 0.1 radii of surface (the points' spacing along the line is
    # 1 / cos of its slope per column), so a steep smooth surface reads as smooth as a shallow one
    sa, na = (pts - ma) @ da, (pts - ma) @ np.array([-da[1], da[0]])
    o = np.argsort(sa)
    step = float(np.median(np.diff(sa[o]))) or 1.0
    k = min(max(5, int(round(0.1 * R / step)) | 1), u.size if u.size % 2 else u.size - 1)  # odd
    # scipy.signal here, not at the top: importing it takes about 0.8 CPU-s, and every photo
    # measurement imports this module (manifest checks) while only drum frames need the filter
    from scipy.signal import savgol_filter

    rough = float(np.sqrt(np.mean((na[o] - savgol_filter(na[o], k, 2, mode="interp")) ** 2)) / R * 100.0)
    # a jagged trace tilts the line only where it is one-sided: particles in flight crowd over
    # the upper part, so a third's angle parts from the central chord's; lumps spread evenly
    # along the surface leave the thirds as the chord
    tilt = max((abs(x - angle) for x in (upper, lower) if np.isfinite(x)), default=0.0)
    conf, why = "ok", ""
    # the surface's two ends against the drum wall: an end short of the masked circle (radially,
    # (rm - |end|) / R), inside the frame, is a surface meeting no wall there, so the circle is not
    # the drum's; where the trace stops short, the surface's end is where the step from air down to
    # powder along the end's line stops (MAX_END_GAP)
    border = max(3.0, 0.02 * R)
    gaps = []
    for e, part, outward in ((pts[np.argmin(tt)], tt <= t0 + 0.1 * (t1 - t0), -1.0),
                             (pts[np.argmax(tt)], tt >= t1 - 0.1 * (t1 - t0), 1.0)):
        col, row = cx + e[0], cy - e[1]
        at_border = min(col, row, w - 1 - col, h - 1 - row) <= border
        gap = 0.0 if at_border else (rm - math.hypot(*e)) / R
        if gap > MAX_END_GAP and part.sum() >= 5:  # the trace may stop short of a surface going on
            gap = (rm - _surface_reach(p, u, v, part, e, outward, d, cx, cy, rm, R)) / R
        gaps.append(gap)
    if max(gaps) > MAX_END_GAP:
        conf = "low"
        why = f"the free surface ends {max(gaps):.2f} drum radii short of the drum circle {said} (at most " \
              f"{MAX_END_GAP:g}, radially): a bed lies against the drum wall, so " + (
                  "the drum_centre_px or drum_radius_px given does not match the frame's drum, and the central "
                  "chord is not the drum's; check them against the frame (the frame's pixels, as shown)"
                  if dref == "manifest" else
                  "that circle is not the drum's (a rim smeared by motion blur or out of focus is found wrong), and "
                  "the central chord is not the drum's; give drum_centre_px and drum_radius_px, or take a sharper "
                  "frame")
    if rough > MAX_ROUGHNESS_PCT and tilt > MAX_THIRD_TILT_DEG:
        conf = "low"
        why = (why + "; " if why else "") + (f"a jagged free surface tilting the line: its points {rough:.2f} % of the drum radius (RMS) across "
               f"the surface from a smooth curve over 0.1 radii, above {MAX_ROUGHNESS_PCT:g} %, and a third's angle "
               f"{tilt:.1f} deg from the central chord's, above {MAX_THIRD_TILT_DEG:g} deg (upper third {upper:.1f} "
               f"deg, lower third {lower:.1f} deg, central chord {angle:.1f} deg): particles in flight above the "
               "surface (a cascade's curtain) or lumps gathered on one part, traced as surface; take a frame where "
               "the curtain is sparse, with a shorter exposure, or the tester's time-averaged frame; if the "
               "surface truly bends so, read its angle from the frame by hand")
    if angle < DRUM_ANGLE_RANGE[0]:
        raise InputError(path, "image", DRUM_EXPECTED, f"a surface at {angle:.1f} deg ({where}): a level edge, "
                         "no turning drum in the frame")
    if angle > DRUM_ANGLE_RANGE[1]:
        raise InputError(path, "image", DRUM_EXPECTED, f"a surface at {angle:.1f} deg ({where}): steeper than "
                         f"{DRUM_ANGLE_RANGE[1]:g} deg, no powder surface in a turning drum stands so (a wall or an "
                         "edge of the drum taken for it)")
    if rms > MAX_LINE_RMS_PCT:
        raise InputError(path, "image", DRUM_EXPECTED, f"a powder boundary straying {rms:.0f} % of the drum radius "
                         f"(RMS) from a line, at most {MAX_LINE_RMS_PCT:.0f} % ({where})")
    st = None
    if keep_stages:
        st = Stages(rgb, g, binary, powder.astype(float),
                    [(m[0], m[1], d[0], d[1], f"central {fr:.0%} of the chord"), *end_lines],
                    [np.column_stack([u, v])],
                    circle=(cx, cy, rm), reference=f"level: {lref}, drum: {dref}")
    # a frame measured at its own size keeps its numbers to the last bit ((x + 0.5) - 0.5 != x)
    fcx, fcy, fR = frame_px(cx, cy, R) if (sx, sy) != (1.0, 1.0) else (cx, cy, R)
    return DrumResult(str(path), angle, upper, lower, angle - 0.5 * (upper + lower), rms, float(roll), lref, dref,
                      [float(fcx), float(fcy)], float(fR), float(fr), int(cols.size), st,
                      work_scale=float(math.sqrt(sx * sy)), roughness_pct=rough,
                      confidence=conf, low_reason=why, accepted_by_user=conf == "low" and opts["accept_low"])


def measure_drum(paths, threshold="otsu", keep_stages=False, options=None, refusals=None):
    """Frames of one group: the mean angle and S-shape measures, the angles' spread.

    ``options`` is one dict of :data:`OPTIONS` for every frame or a list with one per frame.
    """
    per = options if isinstance(options, list) else [options] * len(paths)
    res = [measure_drum_frame(p, threshold, keep_stages, o, refusals) for p, o in zip(paths, per)]
    try:
        return drum_summary(res), res
    except InputError as e:
        e.results = res  # frames flagged low only: their results, for the figures
        raise


def drum_summary(res) -> dict:
    """The mean angle and S-shape measures of the frames ``res`` (:class:`DrumResult`) measured
    with confidence "ok", the angles' spread and the references they were measured against; a
    frame flagged "low" is listed in ``set_aside`` (path, reason) and not averaged, unless the
    user accepted it (option ``accept_low``): then it is averaged and listed in ``accepted_low``
    (path, reason); ``n_frames`` counts those used, and a group with none used is refused naming
    each frame and its reason.
    ``frames`` holds every frame's result."""
    used = [r for r in res if r.confidence == "ok" or r.accepted_by_user]
    aside = [{"path": r.path, "reason": r.low_reason} for r in res if r.confidence != "ok" and not r.accepted_by_user]
    accepted = [{"path": r.path, "reason": r.low_reason} for r in res if r.confidence != "ok" and r.accepted_by_user]
    if not used:
        raise InputError(res[0].path if len(res) == 1 else "<drum frame group>", "confidence",
                         "at least one frame of the group measured with confidence ok (a frame flagged low is not "
                         "averaged into the group's angle unless the user, having checked it, gives accept_low: true "
                         "for it, or --accept-low)",
                         "; ".join(f"{a['path']}: low, {a['reason']}" for a in aside))

    def mean(key):
        return float(np.nanmean([getattr(r, key) for r in used]))

    a = np.array([r.angle_deg for r in used])
    return {"angle_deg": float(a.mean()), "spread_deg": float(a.std(ddof=1)) if a.size > 1 else 0.0,
            "n_frames": len(used), "upper_deg": mean("upper_deg"), "lower_deg": mean("lower_deg"),
            "s_shape_deg": mean("s_shape_deg"), "line_rms_pct": mean("line_rms_pct"),
            "level_reference": ", ".join(sorted({r.level_reference for r in used})),
            "drum_reference": ", ".join(sorted({r.drum_reference for r in used})),
            "frames": [r.as_dict() for r in res], "set_aside": aside, "accepted_low": accepted}
