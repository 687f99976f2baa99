"""Per-soil photo manifest ``resources/images/<soil>/manifest.yaml`` and its measurement.

Fields per photo: ``file``, ``kind`` (pile | drum | furrow), ``view``, ``group`` (photos
averaged into one value), ``scale_length_mm`` (physical length of the scale reference), for
furrows ``beam_datum_mm``, and for drum frames the options of :mod:`soilcal.imaging.drum`
(``level``, ``roll_deg``, ``chord_fraction``, ``rim_margin``, ``drum_centre_px``,
``drum_radius_px``).  Only these user-known fields and the pixels are read; the renderer's
``*.truth.json`` sidecars are never opened here.

:func:`read_manifest` checks the manifest when the workflow starts: a field it does not know
(a misspelt ``scale_lenght_mm``), a missing photo, a kind other than pile, drum or furrow, a
group mixing kinds, a furrow without its beam length or with a second photo in its group, a
``degree`` outside 1-15 or a ``threshold`` other than otsu or adaptive stops it with one
line naming the manifest and the field.  Optional fields: ``substrate`` and ``note`` per
photo (documentation), ``degree`` of a furrow's profile polynomial (default 9), ``plate_line_px`` of a heap photo
(two points [column, row] on the plate's top edge, the photo's pixels as shown: the plate line
given, not searched; :func:`check_plate_line`), and at the
top ``soil``, ``note`` and ``threshold`` (default otsu).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from pathlib import Path

from soilcal.errors import InputError

KINDS = ("pile", "drum", "furrow")
THRESHOLDS = ("otsu", "adaptive")
#: manifest fields (top level, and per photo besides the drum options of soilcal.imaging.drum)
TOP_FIELDS = ("soil", "note", "photos", "threshold")
PHOTO_FIELDS = ("file", "kind", "group", "view", "scale_length_mm", "beam_datum_mm", "degree", "substrate", "note",
                "plate_line_px")
#: the steepest plate line a heap photo's ``plate_line_px`` may give (deg from the image rows)
PLATE_LINE_MAX_DEG = 45.0
#: the shortest distance (px) between a heap photo's two ``plate_line_px`` points: the line's
#: tilt is taken as the camera's roll, and a point 1 px off tilts it by atan(1 / distance), which
#: turns both flanks by as much, opposite ways: at most 0.5 deg at this distance (5.7 deg over
#: 10 px). The points may lie on the edge's extension beyond a short plate.
PLATE_LINE_MIN_SPAN_PX = 115.0
#: polynomial degrees a furrow profile may be fitted with
DEGREES = (1, 15)
#: the numbers the measurement of a photo group of each kind gives (its entry in
#: ``measurements.json``), which a target measured on the group may name (``image_measure``,
#: default ``angle_deg``): the numeric entries of :func:`soilcal.imaging.measure.pile_summary`,
#: :func:`soilcal.imaging.drum.drum_summary` and :meth:`soilcal.imaging.measure.FurrowResult.as_dict`
MEASURES = {
    "pile": ("angle_deg", "left_deg", "right_deg", "spread_deg", "n_photos"),
    "drum": ("angle_deg", "spread_deg", "n_frames", "upper_deg", "lower_deg", "s_shape_deg", "line_rms_pct"),
    "furrow": ("area_mm2", "area_dm2", "degree", "coverage", "end_gap_mm", "fit_rms_mm", "area_fit_mm2", "boundary_rms_mm", "px_per_mm", "roll_deg"),
}


def _is_number(v) -> bool:
    import math

    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def check_degree(where, field, degree) -> int:
    """A furrow profile's polynomial degree: an integer of :data:`DEGREES`."""
    lo, hi = DEGREES
    if isinstance(degree, bool) or not isinstance(degree, int) or not lo <= degree <= hi:
        raise InputError(where, field, f"an integer polynomial degree from {lo} to {hi}", degree)
    return degree


def _shown_size(photo):
    """(width, height) of ``photo`` as a viewer shows it (its EXIF orientation applied), read
    from its header; None when PIL cannot open it (the photo's own refusal comes when it is
    measured)."""
    from PIL import Image

    try:
        with Image.open(photo) as im:
            w, h = im.size
            orient = im.getexif().get(0x0112, 1)
    except Exception:  # noqa: BLE001 - the measurement names an unreadable photo
        return None
    return (h, w) if orient in (5, 6, 7, 8) else (w, h)


def check_plate_line(where, field, entry, photo):
    """A heap photo's ``plate_line_px``: two points [column, row] on the plate's top edge, in
    the photo's pixels as shown (its EXIF orientation applied), inside the photo, at least 10
    px apart across it, at least :data:`PLATE_LINE_MIN_SPAN_PX` apart and
    the line within :data:`PLATE_LINE_MAX_DEG` of the image rows.  Returns ((c0, r0), (c1,
    r1)) as floats, in the order given."""
    pts = entry["plate_line_px"]
    eg = f"{field} 40 612.5 1580 618" if field.startswith("--") else "[[40, 612.5], [1580, 618]]"  # as typed
    expected = ("two points [column, row] on the plate's top edge, in the photo's pixels as shown, "
                f"e.g. {eg} (photo {entry.get('file')})")
    if entry.get("kind") != "pile":
        raise InputError(where, field, f"no plate line: it is given for heap photos (kind pile) only "
                         f"(photo {entry.get('file')}, kind {entry.get('kind')})", pts)
    if (not isinstance(pts, (list, tuple)) or len(pts) != 2
            or not all(isinstance(q, (list, tuple)) and len(q) == 2 and all(_is_number(v) for v in q) for q in pts)):
        raise InputError(where, field, expected, pts)
    given = tuple((float(q[0]), float(q[1])) for q in pts)
    (c0, r0), (c1, r1) = sorted(given)
    if c1 - c0 < 10.0 or abs(r1 - r0) > (c1 - c0) * math.tan(math.radians(PLATE_LINE_MAX_DEG)):
        raise InputError(where, field, expected + f", at least 10 px apart across the photo and the line within "
                         f"{PLATE_LINE_MAX_DEG:.0f} deg of horizontal", pts)
    size = _shown_size(photo)
    if size is not None:
        w, h = size
        if not all(-0.5 <= c <= w - 0.5 and -0.5 <= r <= h - 0.5 for c, r in ((c0, r0), (c1, r1))):
            raise InputError(where, field, expected + f", inside the photo's {w} x {h} pixels", pts)
    if math.hypot(c1 - c0, r1 - r0) < PLATE_LINE_MIN_SPAN_PX:
        raise InputError(where, field, expected + f", at least {PLATE_LINE_MIN_SPAN_PX:.0f} px apart (on the "
                         "plate's edge or its extension): the line's tilt is taken as the camera's roll, and a "
                         f"point 1 px off tilts it by {math.degrees(math.atan(1 / PLATE_LINE_MIN_SPAN_PX)):.1f} "
                         "deg at that distance (5.7 deg over 10 px)", pts)
    return given


def read_manifest(path):
    import yaml

    from soilcal.imaging.drum_options import OPTIONS

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
        try:
            # libyaml where PyYAML has it (the same values, faster), else the pure-Python parser
            data = yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))  # noqa: S506
        except yaml.YAMLError:  # read again by the pure-Python parser, whose error the message words
            data = yaml.safe_load(text)
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise InputError(path, "manifest", "a readable YAML file", str(exc).splitlines()[0] if str(exc) else type(exc).__name__) from None
    if not isinstance(data, dict) or not isinstance(data.get("photos"), list) or not data["photos"]:
        raise InputError(path, "photos", "a non-empty list of photo entries", None)
    for k in data:
        if k not in TOP_FIELDS:
            raise InputError(path, str(k), "one of the known fields " + ", ".join(TOP_FIELDS), f"unknown field {k!r}")
    if data.get("threshold", "otsu") not in THRESHOLDS:
        raise InputError(path, "threshold", f"one of {', '.join(THRESHOLDS)}", data.get("threshold"))
    known = PHOTO_FIELDS + tuple(OPTIONS)
    kinds: dict[str, str] = {}
    listed: dict[tuple, int] = {}  # (group, photo file) -> the entry that lists it first
    for i, p in enumerate(data["photos"]):
        at = f"photos[{i}]"
        if not isinstance(p, dict) or "file" not in p:
            raise InputError(path, f"{at}.file", "a file name", p)
        for k in p:
            if k not in known:
                raise InputError(path, f"{at}.{k}", "one of the known fields " + ", ".join(known), f"unknown field {k!r}")
        if p.get("kind") not in KINDS:
            raise InputError(path, f"{at}.kind", f"one of {KINDS}", p.get("kind"))
        if not isinstance(p["file"], str) or not (path.parent / p["file"]).is_file():
            raise InputError(path, f"{at}.file", f"an existing image file in {path.parent}", p["file"])
        for k in ("group", "view"):
            if k in p and not isinstance(p[k], str):
                raise InputError(path, f"{at}.{k}", "a name (text)", p[k])
        if "scale_length_mm" in p and not (_is_number(p["scale_length_mm"]) and p["scale_length_mm"] > 0):
            raise InputError(path, f"{at}.scale_length_mm", "a positive length of the scale reference in mm",
                             p["scale_length_mm"])
        if "beam_datum_mm" in p and not _is_number(p["beam_datum_mm"]):
            raise InputError(path, f"{at}.beam_datum_mm", "a number (mm)", p["beam_datum_mm"])
        if p["kind"] == "furrow":
            if "scale_length_mm" not in p:
                raise InputError(path, f"{at}.scale_length_mm", "the length of the profile-meter beam in mm", None)
            check_degree(path, f"{at}.degree", p.get("degree", 9))
        if "plate_line_px" in p:
            check_plate_line(path, f"{at}.plate_line_px", p, path.parent / p["file"])
        if p["kind"] == "drum":
            from soilcal.imaging.drum_options import frame_options

            frame_options(p, path, prefix=f"{at}.")
        else:
            for k in OPTIONS:
                if k in p:
                    raise InputError(path, f"{at}.{k}", f"no {k}: it is an option of drum frames (kind drum) only "
                                     f"(photo {p['file']}, kind {p['kind']})", p[k])
        p.setdefault("group", p["kind"])
        # a photo listed twice in its group (a copy-paste slip) would weigh twice in its mean
        j = listed.setdefault((p["group"], (path.parent / p["file"]).resolve()), i)
        if j != i:
            raise InputError(path, f"{at}.file", f"a photo not yet in group {p['group']!r} (photos[{j}] "
                             "lists the same file: each photo counts once in its group's mean)", p["file"])
        first = kinds.setdefault(p["group"], p["kind"])
        if first != p["kind"]:
            raise InputError(path, f"{at}.kind", f"{first}, the kind of the other photos of group {p['group']!r}", p["kind"])
        if p["kind"] == "furrow" and sum(q.get("group", q.get("kind")) == p["group"] for q in data["photos"][:i]) > 0:
            raise InputError(path, f"{at}.group", f"a group of its own (a furrow group is one photo), not {p['group']!r}",
                             p["group"])
    return data


def lookup(photo):
    """Manifest entry of ``photo`` from the manifest.yaml beside it (None if absent)."""
    photo = Path(photo)
    m = photo.parent / "manifest.yaml"
    if not m.is_file():
        return None
    for p in read_manifest(m)["photos"]:
        if p["file"] == photo.name:
            return p
    return None


def counted(n, noun) -> str:
    """``n`` and the noun, plural but for one: '1 photo', '2 photos', '0 frames'."""
    return f"{n} {noun}{'' if n == 1 else 's'}"


def set_aside_lines(summary, group=None) -> list[str]:
    """The warning lines of a group's summary (:func:`soilcal.imaging.measure.pile_summary` or
    :func:`soilcal.imaging.drum.drum_summary`): one per heap photo or drum frame it set aside
    (``set_aside``) and one per frame flagged low that the user accepted (``accepted_low``,
    averaged into the group's angle all the same), each ``group NAME: `` first where a group is
    named.  ``soilcal image`` prints them on stderr and the workflow's image_measure job logs
    them: the JSON carries them too, but a group's angle from fewer photos than given, or from
    one the measurement doubted, should not pass unseen."""
    frames = "n_frames" in summary
    noun, n = ("frame", summary.get("n_frames")) if frames else ("photo", summary.get("n_photos"))
    where = f"group {group}: " if group is not None else ""
    return ([f"{where}{noun} {a['path']} set aside (confidence low, not averaged into the group's angle; "
             f"{counted(n, noun)} used): {a['reason']}" for a in summary.get("set_aside", [])]
            + [f"{where}{noun} {a['path']} flagged low and accepted by the user (accept_low), averaged into the "
               f"group's angle: {a['reason']}" for a in summary.get("accepted_low", [])])


def measure_manifest(path, figdir=None, threshold="otsu", refusals=None, refused_figdir=None,
                     figdir_field="figures folder", refused_figdir_field="refusals folder"):
    """Measure every group of the manifest; returns {group: result dict}.  ``refusals``: a
    folder for the diagnostic image of a photo that cannot be measured
    (:mod:`soilcal.imaging.refusal`).  ``refused_figdir``: where a group refused for having no
    ok photo or frame gets its figures (with ``figdir`` given); default ``refusals``, else
    ``figdir``.  A figures folder (either) that is the folder of one of the manifest's photos is
    refused before any photo is measured, naming ``figdir_field`` / ``refused_figdir_field``
    (:func:`soilcal.imaging.figures.check_apart`)."""
    from soilcal.imaging import drum, figures, huge_pages_off, measure

    huge_pages_off()

    path = Path(path)
    data = read_manifest(path)
    if figdir is not None:
        photos = [path.parent / p["file"] for p in data["photos"]]
        figures.check_apart(photos, figdir, figdir_field)
        if refused_figdir is not None:
            figures.check_apart(photos, refused_figdir, refused_figdir_field)
        elif refusals is not None:
            figures.check_apart(photos, refusals, refused_figdir_field)
    groups: OrderedDict[str, list] = OrderedDict()
    for p in data["photos"]:
        groups.setdefault(p["group"], []).append(p)

    def refused_figures(e, noun):
        """The refusal's text for a group with no ok photo or frame (``e`` from measure_piles or
        measure_drum, its ``results`` the group's measurements); with ``figdir`` given, the figures
        its reasons point to are written all the same: beside the diagnostic images of refused
        photos where there is such a folder (the workflow's outputs, figdir among them, do not
        outlive a failed job)."""
        if figdir is None:
            return e.got
        where = Path(refused_figdir if refused_figdir is not None else refusals if refusals is not None else figdir)
        where.mkdir(parents=True, exist_ok=True)
        figures.angle_figures(e.results, where)
        return f"{e.got}; figures of the group's {noun} in {where}"

    out = OrderedDict()
    figures_of = []  # written once every group is measured: a bad photo leaves no figures
    for g, entries in groups.items():
        kind = entries[0]["kind"]
        files = [path.parent / e["file"] for e in entries]
        keep = figdir is not None
        if kind == "pile":
            # the points read_manifest checked, as given
            lines = [tuple((float(c), float(r)) for c, r in e["plate_line_px"]) if "plate_line_px" in e else None
                     for e in entries]
            try:
                summary, res = measure.measure_piles(files, threshold, keep_stages=keep, refusals=refusals,
                                                     plate_px=lines)
            except InputError as e:
                if e.field == "confidence":  # no photo of the group measured "ok"
                    raise InputError(path, f"group {g} ({len(files)} photos)", e.expected,
                                     refused_figures(e, "photos")) from None
                given = {str(f): i for f, q, i in zip(files, lines, range(len(files))) if q is not None}
                if e.path not in given or e.field not in ("image", "left flank", "right flank", "plate line"):
                    raise
                at = f"photos[{data['photos'].index(entries[given[e.path]])}].plate_line_px"
                raise InputError(e.path, e.field, e.expected, f"{e.got} on the plate line given in {path} {at} "
                                 f"{entries[given[e.path]]['plate_line_px']}", e.note) from None
            summary["views"] = [e.get("view") for e in entries]
        elif kind == "drum":
            try:
                summary, res = drum.measure_drum(files, threshold, keep_stages=keep,
                                                 options=[drum.frame_options(e, path) for e in entries],
                                                 refusals=refusals)
            except InputError as e:
                if e.field != "confidence":  # no frame of the group measured "ok"
                    raise
                raise InputError(path, f"group {g} ({len(files)} frames)", e.expected,
                                 refused_figures(e, "frames")) from None
        else:
            e = entries[0]
            r = measure.measure_furrow(files[0], e.get("scale_length_mm"), e.get("beam_datum_mm", 0.0),
                                       int(e.get("degree", 9)), threshold, keep_stages=keep, refusals=refusals)
            summary, res = r.as_dict(), [r]
        summary["kind"] = kind
        out[g] = summary
        figures_of += [(kind, r) for r in res]
    if figdir is not None:
        for kind, r in figures_of:
            stem = Path(figdir) / Path(r.path).stem
            (figures.furrow_figure if kind == "furrow" else figures.angle_figure)(r, stem)
    return out
