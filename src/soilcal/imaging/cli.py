"""``soilcal image ...``: measure pile, drum and furrow photos; render the photo set."""

from __future__ import annotations

import json
import sys


def _print(obj):
    json.dump(obj, sys.stdout, indent=2)
    sys.stdout.write("\n")


def _pile(args):
    from soilcal.imaging import figures, measure

    summary, res = measure.measure_piles(args.photos, args.threshold, keep_stages=bool(args.figures),
                                         channel=args.channel)
    if args.figures:
        for r in res:
            figures.angle_figure(r, f"{args.figures}/{r.path.rsplit('/', 1)[-1].rsplit('.', 1)[0]}")
    _print(summary)
    return 0


def _drum(args):
    from soilcal.imaging import figures, measure

    summary, res = measure.measure_drum(args.frames, args.threshold, keep_stages=bool(args.figures))
    if args.figures:
        for r in res:
            figures.angle_figure(r, f"{args.figures}/{r.path.rsplit('/', 1)[-1].rsplit('.', 1)[0]}")
    _print(summary)
    return 0


def _furrow(args):
    from soilcal.errors import InputError
    from soilcal.imaging import figures, manifest, measure

    length, datum = args.scale_length_mm, args.datum_mm
    if length is None:
        entry = manifest.lookup(args.photo)
        if entry is None or "scale_length_mm" not in entry:
            raise InputError(args.photo, "scale_length_mm",
                             "--scale-length-mm or a manifest.yaml entry beside the photo", None)
        length = float(entry["scale_length_mm"])
        datum = float(entry.get("beam_datum_mm", 0.0)) if datum is None else datum
    r = measure.measure_furrow(args.photo, length, datum or 0.0, args.degree, args.threshold,
                               keep_stages=bool(args.figures))
    if args.figures:
        figures.furrow_figure(r, f"{args.figures}/{r.path.rsplit('/', 1)[-1].rsplit('.', 1)[0]}")
    _print(r.as_dict())
    return 0


def _soil(args):
    from soilcal.imaging.manifest import measure_manifest

    _print(measure_manifest(args.manifest, args.figures, args.threshold))
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

    q = sub.add_parser("pile", help="heap photos (several views are averaged)")
    q.add_argument("photos", nargs="+")
    q.add_argument("--channel", choices=("auto", "gray", "chroma"), default="auto")
    common(q)
    q.set_defaults(func=_pile)
    q = sub.add_parser("drum", help="rotating-drum frames (dynamic angle, averaged)")
    q.add_argument("frames", nargs="+")
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
