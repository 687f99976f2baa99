"""Per-soil photo manifest ``resources/images/<soil>/manifest.yaml`` and its measurement.

Fields per photo: ``file``, ``kind`` (pile | drum | furrow), ``view``, ``group`` (photos
averaged into one value), ``scale_length_mm`` (physical length of the scale reference), for
furrows ``beam_datum_mm``, and for drum frames the options of :mod:`soilcal.imaging.drum`
(``level``, ``roll_deg``, ``chord_fraction``, ``rim_margin``, ``drum_centre_px``,
``drum_radius_px``).  Only these user-known fields and the pixels are read; the renderer's
``*.truth.json`` sidecars are never opened here.
"""

from __future__ import annotations

from collections import OrderedDict
from pathlib import Path

from soilcal.errors import InputError

KINDS = ("pile", "drum", "furrow")


def read_manifest(path):
    import yaml

    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise InputError(path, "manifest", "a readable YAML file", str(exc)) from None
    if not isinstance(data, dict) or not isinstance(data.get("photos"), list) or not data["photos"]:
        raise InputError(path, "photos", "a non-empty list of photo entries", None)
    for i, p in enumerate(data["photos"]):
        if not isinstance(p, dict) or "file" not in p:
            raise InputError(path, f"photos[{i}].file", "a file name", p)
        if p.get("kind") not in KINDS:
            raise InputError(path, f"photos[{i}].kind", f"one of {KINDS}", p.get("kind"))
        if not (path.parent / str(p["file"])).is_file():
            raise InputError(path, f"photos[{i}].file", f"an existing image file in {path.parent}", p["file"])
        if p["kind"] == "drum":
            from soilcal.imaging.drum import frame_options

            frame_options(p, path, prefix=f"photos[{i}].")
        p.setdefault("group", p["kind"])
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


def measure_manifest(path, figdir=None, threshold="otsu"):
    """Measure every group of the manifest; returns {group: result dict}."""
    from soilcal.imaging import drum, figures, measure

    path = Path(path)
    data = read_manifest(path)
    groups: OrderedDict[str, list] = OrderedDict()
    for p in data["photos"]:
        groups.setdefault(p["group"], []).append(p)
    out = OrderedDict()
    for g, entries in groups.items():
        kind = entries[0]["kind"]
        files = [path.parent / e["file"] for e in entries]
        keep = figdir is not None
        if kind == "pile":
            summary, res = measure.measure_piles(files, threshold, keep_stages=keep)
            summary["views"] = [e.get("view") for e in entries]
        elif kind == "drum":
            summary, res = drum.measure_drum(files, threshold, keep_stages=keep,
                                             options=[drum.frame_options(e, path) for e in entries])
        else:
            e = entries[0]
            r = measure.measure_furrow(files[0], e.get("scale_length_mm"), e.get("beam_datum_mm", 0.0),
                                       int(e.get("degree", 9)), threshold, keep_stages=keep)
            summary, res = r.as_dict(), [r]
        summary["kind"] = kind
        out[g] = summary
        if keep:
            for r in res:
                stem = Path(figdir) / Path(r.path).stem
                (figures.furrow_figure if kind == "furrow" else figures.angle_figure)(r, stem)
    return out
