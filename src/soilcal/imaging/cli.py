"""``soilcal image ...``: measure pile, drum and furrow photos; render the photo set."""

from __future__ import annotations

import sys

from soilcal.imaging import CUES, huge_pages_off
from soilcal.imaging.manifest import counted, set_aside_lines


def _print(obj):
    """``obj`` on stdout as JSON, a value not measured (NaN) as ``null``
    (:func:`soilcal.chain.files.json_text`: JSON has no NaN, and strict parsers refuse it)."""
    from soilcal.chain.files import json_text

    sys.stdout.write(json_text(obj))


def _warn_set_aside(summary, group=None):
    """On stderr, the group's lines of photos or frames set aside or accepted low
    (:func:`soilcal.imaging.manifest.set_aside_lines`)."""
    for line in set_aside_lines(summary, group):
        print(f"soilcal: warning: {line}", file=sys.stderr)


def _figure_base(folder, r):
    """Where a photo's figures go: ``folder`` and the photo's file name without its extension
    (the figure functions add theirs)."""
    from pathlib import PurePath

    return f"{folder}/{PurePath(r.path).stem}"


def _plate_lines(args):
    """The ``--plate-line-px`` lines, one per photo in the photos' order (None for each photo
    where none is given), checked as a manifest's ``plate_line_px`` is
    (:func:`soilcal.imaging.manifest.check_plate_line`)."""
    from soilcal.errors import InputError
    from soilcal.imaging.manifest import check_plate_line

    given = args.plate_line_px or []
    if not given:
        return None
    if len(given) != len(args.photos):
        raise InputError("<command line>", "--plate-line-px", f"one plate line per photo, in the photos' order "
                         f"({counted(len(args.photos), 'photo')}; several photos' lines can also be given in a manifest, "
                         f"soilcal image soil)", counted(len(given), "line"))
    return [check_plate_line("<command line>", "--plate-line-px",
                             {"kind": "pile", "file": str(photo), "plate_line_px": [q[:2], q[2:]]}, photo)
            for photo, q in zip(args.photos, given)]


def _refusals(args, photos=(), field="photos"):
    """The folder for refused photos' diagnostic images: --refusals, else the current folder.
    Each of ``photos``' diagnostic image left there by an earlier run
    (:func:`soilcal.imaging.refusal.refusal_path`) is removed first: this call writes it again
    where the photo is still refused, and one left beside a photo now measured would be taken
    for this run's refusal.  Nothing else in the folder (the current one by default) is touched.
    Two of ``photos`` whose diagnostic images would share a name (the same stem: heap.png and
    heap.jpg, or a/heap.png and b/heap.png) are refused, naming both (argument ``field``): one's
    refusal would overwrite or remove the other's."""
    from soilcal.errors import InputError
    from soilcal.imaging.refusal import refusal_path

    folder = args.refusals if args.refusals is not None else "."
    seen = {}
    for photo in photos:
        out = refusal_path(photo, folder)
        if out in seen:
            raise InputError(photo, field, f"a refusal image name of its own: {seen[out]}, given too, would write the "
                                           f"same {out} (rename one, or measure them in separate calls with "
                                           f"different --refusals)")
        seen[out] = photo
    for out in seen:
        if out.is_file() or out.is_symlink():
            out.unlink()
    return folder


def _pile(args):
    huge_pages_off()
    from soilcal.errors import InputError
    from soilcal.imaging import figures, measure

    lines = _plate_lines(args)
    figures.check_apart(args.photos, args.figures, "--figures")
    try:
        summary, res = measure.measure_piles(args.photos, args.threshold, keep_stages=bool(args.figures),
                                             channel=args.channel, refusals=_refusals(args, args.photos), plate_px=lines,
                                             plate_px_from="command line")
    except InputError as e:
        if e.field == "confidence" and args.figures:
            # no photo "ok": their figures, which the reasons point to, are written all the same
            figures.angle_figures(e.results, args.figures)
            raise InputError(e.path, e.field, e.expected, f"{e.got}; figures of every photo in {args.figures}",
                             e.note) from None
        # a photo measured on the line given: the refusal names the option and the line
        given = {str(f): q for f, q in zip(args.photos, lines or []) if q is not None}
        if e.path not in given or e.field not in ("image", "left flank", "right flank", "plate line"):
            raise
        raise InputError(e.path, e.field, e.expected, f"{e.got} on the plate line given on the command line "
                         f"--plate-line-px {' '.join(f'{v:g}' for q in given[e.path] for v in q)}", e.note) from None
    if args.figures:
        figures.angle_figures(res, args.figures)
    _warn_set_aside(summary)
    _print(summary)
    return 0


def _drum(args):
    huge_pages_off()
    from soilcal.imaging import drum, figures

    from soilcal.errors import InputError

    try:
        opts = drum.frame_options({k: getattr(args, k) for k in drum.OPTIONS}, "<command line>", prefix="--")
    except InputError as exc:  # name the option as it is typed: --chord-fraction
        raise InputError(exc.path, exc.field.replace("_", "-"), exc.expected, exc.got) from None
    figures.check_apart(args.frames, args.figures, "--figures")
    try:
        summary, res = drum.measure_drum(args.frames, args.threshold, keep_stages=bool(args.figures), options=opts,
                                         refusals=_refusals(args, args.frames, "frames"))
    except InputError as e:
        if e.field != "confidence" or not args.figures:
            raise
        # no frame "ok": their figures, which the reasons point to, are written all the same
        figures.angle_figures(e.results, args.figures)
        raise InputError(e.path, e.field, e.expected, f"{e.got}; figures of every frame in {args.figures}",
                         e.note) from None
    if args.figures:
        figures.angle_figures(res, args.figures)
    _warn_set_aside(summary)
    _print(summary)
    return 0


def _furrow(args):
    huge_pages_off()
    from soilcal.errors import InputError
    from soilcal.imaging import figures, manifest, measure

    manifest.check_degree("<command line>", "--degree", args.degree)
    if args.scale_length_mm is not None and not args.scale_length_mm > 0:
        raise InputError("<command line>", "--scale-length-mm", "a positive length of the beam in mm",
                         args.scale_length_mm)
    length, datum = args.scale_length_mm, args.datum_mm
    if length is None:
        entry = manifest.lookup(args.photo)
        if entry is None or "scale_length_mm" not in entry:
            raise InputError(args.photo, "scale_length_mm",
                             "--scale-length-mm or a manifest.yaml entry beside the photo", None)
        length = float(entry["scale_length_mm"])
        datum = float(entry.get("beam_datum_mm", 0.0)) if datum is None else datum
    figures.check_apart([args.photo], args.figures, "--figures")
    r = measure.measure_furrow(args.photo, length, datum or 0.0, args.degree, args.threshold,
                               keep_stages=bool(args.figures), refusals=_refusals(args, [args.photo]))
    if args.figures:
        figures.furrow_figure(r, _figure_base(args.figures, r))
    _print(r.as_dict())
    return 0


def _soil(args):
    huge_pages_off()
    from soilcal.imaging.manifest import measure_manifest

    # a refused group's figures go to --refusals where it was given, else with the others
    out = measure_manifest(args.manifest, args.figures, args.threshold, _refusals(args),
                           refused_figdir=args.refusals if args.refusals is not None else args.figures,
                           figdir_field="--figures",
                           refused_figdir_field="--refusals" if args.refusals is not None else "--figures")
    for group, summary in out.items():
        _warn_set_aside(summary, group)
    _print(out)
    return 0


def _render(args):
    from soilcal.imaging.render import render_soil

    print(render_soil(args.soil, args.outdir, args.seed))
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("image", help="photo measurement (pile/drum angle, furrow profile)")
    sub = p.add_subparsers(dest="command", required=True)

    def common(q):
        q.add_argument("--threshold", choices=("otsu", "adaptive"), default="otsu")
        q.add_argument("--figures", metavar="DIR", help="write original/gray/binary/contour/fit figures")
        q.add_argument("--refusals", metavar="DIR", default=None,
                       help="where a photo that cannot be measured gets its diagnostic image, "
                            "<photo stem>.refused.png (default: the current folder)")

    q = sub.add_parser("pile", help="heap photos (several views are averaged)")
    q.add_argument("photos", nargs="+")
    q.add_argument("--channel", choices=("auto",) + CUES, default="auto")
    q.add_argument("--plate-line-px", dest="plate_line_px", type=float, nargs=4, action="append",
                   metavar=("C0", "R0", "C1", "R1"),
                   help="the plate's top edge given by hand, not searched: two points (column, row) on it in the "
                        "photo's pixels as a viewer shows them, at least 115 px apart, within 45 deg of "
                        "horizontal (a manifest's plate_line_px); once per photo, in the photos' order")
    common(q)
    q.set_defaults(func=_pile)
    q = sub.add_parser("drum", help="rotating-drum frames or tester exports (dynamic angle, S-shape, averaged)")
    q.add_argument("frames", nargs="+")
    q.add_argument("--level", choices=("auto", "plate", "image"), default="auto",
                   help="level reference: a plate below the drum if found (auto), required (plate), or the image axes")
    q.add_argument("--roll-deg", dest="roll_deg", type=float,
                   help="camera roll: angle by which a true horizontal appears rotated counter-clockwise")
    q.add_argument("--chord-fraction", dest="chord_fraction", type=float, default=0.6,
                   help="central part of the drum's chord the angle is fitted over (default 0.6)")
    q.add_argument("--rim-margin", dest="rim_margin", type=float, default=0.05,
                   help="outer fraction of the drum radius masked as wall (default 0.05)")
    q.add_argument("--drum-centre-px", dest="drum_centre_px", type=float, nargs=2, metavar=("COL", "ROW"))
    q.add_argument("--drum-radius-px", dest="drum_radius_px", type=float)
    q.add_argument("--accept-low", dest="accept_low", action="store_true",
                   help="average frames flagged low all the same, once checked by eye (listed as accepted_low)")
    common(q)
    q.set_defaults(func=_drum)
    q = sub.add_parser("furrow", help="furrow cross-section: profile, polynomial, area")
    q.add_argument("photo")
    q.add_argument("--scale-length-mm", type=float, help="length of the profile-meter beam (default: manifest)")
    q.add_argument("--datum-mm", type=float, help="height of the beam's lower edge above the profile zero")
    q.add_argument("--degree", type=int, default=9)
    common(q)
    q.set_defaults(func=_furrow)
    q = sub.add_parser("soil", help="measure every photo group listed in a manifest.yaml")
    q.add_argument("manifest")
    common(q)
    q.set_defaults(func=_soil)
    q = sub.add_parser("render", help="render the documented photo set of one soil")
    q.add_argument("soil")
    q.add_argument("outdir")
    q.add_argument("--seed", type=int)
    q.set_defaults(func=_render)
