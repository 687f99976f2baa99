"""Output of DEM states: VTK XML files for ParaView and compact .npz snapshots.

VTK XML formats (Kitware, "VTK File Formats", VTK User's Guide ch. 19, and
https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html):

* particles: ``UnstructuredGrid`` (.vtu), one ``VTK_VERTEX`` cell (type 1)
  per particle so that ParaView shows them directly (Glyph filter, scale by
  ``radius``).  Point data: ``radius``, ``velocity`` (3), ``angular_velocity``
  (3), ``material`` and ``id`` plus any extra arrays.
* wall meshes: ``PolyData`` (.vtp) with triangles in ``Polys``.
* time series: ``Collection`` (.pvd) of ``DataSet`` entries with
  ``timestep`` and ``file`` attributes.

Data arrays are written either as ``ascii`` or as inline ``binary``: base64 of
a little-endian UInt64 byte count followed by the raw little-endian array
(``header_type="UInt64"``, uncompressed).  Both are plain XML, readable with
``xml.etree.ElementTree`` (see :func:`read_vtk_arrays`).

The ``.npz`` snapshot holds ``positions``, ``velocities``, ``radii``,
``material``, ``time``, ``step`` and optional ``angular_velocities``, ``ids``,
and ``metadata`` (a JSON string; e.g. seed, material table, soil name).
"""

from __future__ import annotations

import base64
import json
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from soilcal.errors import InputError

_VTK_TYPES = {
    np.dtype("float32"): "Float32", np.dtype("float64"): "Float64",
    np.dtype("int8"): "Int8", np.dtype("uint8"): "UInt8",
    np.dtype("int16"): "Int16", np.dtype("uint16"): "UInt16",
    np.dtype("int32"): "Int32", np.dtype("uint32"): "UInt32",
    np.dtype("int64"): "Int64", np.dtype("uint64"): "UInt64",
}
_NP_TYPES = {v: k for k, v in _VTK_TYPES.items()}


def _data_array(name, arr, binary, ncomp=None):
    a = np.asarray(arr)
    if a.dtype == np.bool_:
        a = a.astype(np.uint8)
    if a.dtype not in _VTK_TYPES:
        a = a.astype(np.float64 if a.dtype.kind == "f" else np.int64)
    a = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<"))
    if ncomp is None:
        ncomp = 1 if a.ndim == 1 else a.shape[1]
    attrs = f'type="{_VTK_TYPES[a.dtype.newbyteorder("=")]}" Name="{name}"'
    if ncomp != 1:
        attrs += f' NumberOfComponents="{ncomp}"'
    if binary:
        raw = a.tobytes()
        payload = base64.b64encode(np.uint64(len(raw)).astype("<u8").tobytes() + raw).decode()
        return f'<DataArray {attrs} format="binary">{payload}</DataArray>'
    flat = a.reshape(-1)
    if a.dtype.kind == "f":
        body = " ".join(repr(float(x)) for x in flat)
    else:
        body = " ".join(str(int(x)) for x in flat)
    return f'<DataArray {attrs} format="ascii">{body}</DataArray>'


def _header(kind):
    return (f'<?xml version="1.0"?>\n<VTKFile type="{kind}" version="1.0" '
            f'byte_order="LittleEndian" header_type="UInt64">\n')


def _atomic_write(path, text):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)
    return path


def write_particles_vtu(path, positions, radii, velocities=None, angular_velocities=None,
                        material=None, ids=None, extra=None, binary=True):
    """Write particles as a VTK XML UnstructuredGrid of vertex cells."""
    x = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    n = x.shape[0]
    r = np.asarray(radii, dtype=np.float64).reshape(n)
    v = np.zeros((n, 3)) if velocities is None else np.asarray(velocities, np.float64).reshape(n, 3)
    w = (np.zeros((n, 3)) if angular_velocities is None
         else np.asarray(angular_velocities, np.float64).reshape(n, 3))
    m = np.zeros(n, np.int32) if material is None else np.asarray(material).astype(np.int32)
    i = np.arange(n, dtype=np.int64) if ids is None else np.asarray(ids).astype(np.int64)
    parts = [_header("UnstructuredGrid"), "<UnstructuredGrid>\n",
             f'<Piece NumberOfPoints="{n}" NumberOfCells="{n}">\n',
             '<PointData Scalars="radius" Vectors="velocity">\n']
    parts.append(_data_array("radius", r, binary) + "\n")
    parts.append(_data_array("velocity", v, binary, 3) + "\n")
    parts.append(_data_array("angular_velocity", w, binary, 3) + "\n")
    parts.append(_data_array("material", m.reshape(n), binary) + "\n")
    parts.append(_data_array("id", i.reshape(n), binary) + "\n")
    for name, arr in (extra or {}).items():
        a = np.asarray(arr)
        if a.shape[0] != n:
            raise ValueError(f"extra array {name!r} has {a.shape[0]} rows, expected {n}")
        parts.append(_data_array(name, a, binary) + "\n")
    parts.append("</PointData>\n<Points>\n")
    parts.append(_data_array("Points", x, binary, 3) + "\n</Points>\n<Cells>\n")
    parts.append(_data_array("connectivity", np.arange(n, dtype=np.int64), binary) + "\n")
    parts.append(_data_array("offsets", np.arange(1, n + 1, dtype=np.int64), binary) + "\n")
    parts.append(_data_array("types", np.ones(n, dtype=np.uint8), binary) + "\n")
    parts.append("</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")
    return _atomic_write(path, "".join(parts))


def write_mesh_vtp(path, vertices, triangles, cell_data=None, binary=True):
    """Write a triangle mesh as VTK XML PolyData."""
    v = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    nv, nt = v.shape[0], t.shape[0]
    parts = [_header("PolyData"), "<PolyData>\n",
             f'<Piece NumberOfPoints="{nv}" NumberOfVerts="0" NumberOfLines="0" '
             f'NumberOfStrips="0" NumberOfPolys="{nt}">\n']
    if cell_data:
        parts.append("<CellData>\n")
        for name, arr in cell_data.items():
            a = np.asarray(arr)
            if a.shape[0] != nt:
                raise ValueError(f"cell array {name!r} has {a.shape[0]} rows, expected {nt}")
            parts.append(_data_array(name, a, binary) + "\n")
        parts.append("</CellData>\n")
    parts.append("<Points>\n" + _data_array("Points", v, binary, 3) + "\n</Points>\n<Polys>\n")
    parts.append(_data_array("connectivity", t.reshape(-1), binary) + "\n")
    parts.append(_data_array("offsets", 3 * np.arange(1, nt + 1, dtype=np.int64), binary) + "\n")
    parts.append("</Polys>\n</Piece>\n</PolyData>\n</VTKFile>\n")
    return _atomic_write(path, "".join(parts))


def write_pvd(path, entries):
    """Write a ParaView collection: ``entries`` is a sequence of
    ``(time, file)`` or ``(time, file, part)``; file names are stored
    relative to the .pvd location."""
    path = Path(path)
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "<Collection>"]
    for e in entries:
        t, f = float(e[0]), Path(e[1])
        part = int(e[2]) if len(e) > 2 else 0
        try:
            rel = os.path.relpath(f.resolve(), path.parent.resolve())
        except ValueError:
            rel = str(f)
        lines.append(f'<DataSet timestep="{t!r}" group="" part="{part}" file="{rel}"/>')
    lines += ["</Collection>", "</VTKFile>", ""]
    return _atomic_write(path, "\n".join(lines))


def _decode_array(path, da, header_dtype):
    name = da.get("Name")
    typ = da.get("type")
    if typ not in _NP_TYPES:
        raise InputError(path, f"DataArray {name} type", f"one of {sorted(_NP_TYPES)}", typ)
    dt = _NP_TYPES[typ].newbyteorder("<")
    ncomp = int(da.get("NumberOfComponents", "1"))
    fmt = da.get("format", "ascii")
    text = (da.text or "").strip()
    if fmt == "ascii":
        a = np.array(text.split(), dtype=np.float64 if dt.kind == "f" else np.int64).astype(dt)
    elif fmt == "binary":
        raw = base64.b64decode(text)
        hs = header_dtype.itemsize
        nbytes = int(np.frombuffer(raw[:hs], dtype=header_dtype)[0])
        if len(raw) - hs != nbytes:
            raise InputError(path, f"DataArray {name}", f"{nbytes} bytes of data",
                             f"{len(raw) - hs} bytes")
        a = np.frombuffer(raw[hs:], dtype=dt).copy()
    else:
        raise InputError(path, f"DataArray {name} format", "ascii or binary", fmt)
    if ncomp != 1:
        a = a.reshape(-1, ncomp)
    return a


def read_vtk_arrays(path):
    """Parse a .vtu/.vtp written by this module (or any uncompressed inline
    VTK XML file) into ``{section/Name: array}`` using the standard library
    XML parser; also returns the Piece attributes under ``"piece"``."""
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise InputError(path, "XML", "a well-formed VTK XML file", str(exc)) from None
    if root.tag != "VTKFile":
        raise InputError(path, "root element", "VTKFile", root.tag)
    if root.get("compressor"):
        raise InputError(path, "compressor", "uncompressed data", root.get("compressor"))
    htype = root.get("header_type", "UInt32")
    hdt = _NP_TYPES[htype].newbyteorder("<")
    out = {"type": root.get("type")}
    piece = root.find(f"./{root.get('type')}/Piece")
    if piece is None:
        raise InputError(path, "Piece", f"a Piece inside {root.get('type')}", None)
    out["piece"] = dict(piece.attrib)
    for section in piece:
        for da in section.iter("DataArray"):
            out[f"{section.tag}/{da.get('Name')}"] = _decode_array(path, da, hdt)
    return out


def read_pvd(path):
    """List of ``(time, file path)`` from a .pvd collection (paths resolved
    against the .pvd directory)."""
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise InputError(path, "XML", "a well-formed .pvd collection", str(exc)) from None
    if root.get("type") != "Collection":
        raise InputError(path, "VTKFile type", "Collection", root.get("type"))
    return [(float(d.get("timestep")), path.parent / d.get("file"))
            for d in root.iter("DataSet")]


# ---------------------------------------------------------------- npz snapshots

_REQUIRED = ("positions", "velocities", "radii", "material", "time", "step", "metadata")


def write_snapshot(path, positions, velocities, radii, material, time, step, metadata=None,
                   angular_velocities=None, ids=None, compressed=True):
    """Write a compact .npz snapshot (float64 kinematics, int32 material)."""
    x = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    n = x.shape[0]
    arrays = dict(
        positions=x,
        velocities=np.asarray(velocities, dtype=np.float64).reshape(n, 3),
        radii=np.asarray(radii, dtype=np.float64).reshape(n),
        material=np.asarray(material).astype(np.int32).reshape(n),
        time=np.float64(time),
        step=np.int64(step),
        metadata=np.array(json.dumps(metadata or {}, sort_keys=True)),
    )
    if angular_velocities is not None:
        arrays["angular_velocities"] = np.asarray(angular_velocities, np.float64).reshape(n, 3)
    if ids is not None:
        arrays["ids"] = np.asarray(ids).astype(np.int64).reshape(n)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp.npz")
    (np.savez_compressed if compressed else np.savez)(tmp, **arrays)
    os.replace(tmp, path)
    return path


def read_snapshot(path):
    """Read a snapshot into a dict; ``metadata`` decoded from JSON, ``time``
    a float and ``step`` an int.  Missing or inconsistent fields raise
    InputError naming the file and the field."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (OSError, ValueError) as exc:
        raise InputError(path, "file", "a readable .npz snapshot", str(exc)) from None
    for k in _REQUIRED:
        if k not in data:
            raise InputError(path, k, "present in the snapshot", "missing")
    n = data["positions"].shape[0]
    for k, shape in (("positions", (n, 3)), ("velocities", (n, 3)), ("radii", (n,)),
                     ("material", (n,)), ("angular_velocities", (n, 3)), ("ids", (n,))):
        if k in data and data[k].shape != shape:
            raise InputError(path, k, f"shape {shape}", data[k].shape)
    try:
        data["metadata"] = json.loads(str(data["metadata"]))
    except json.JSONDecodeError as exc:
        raise InputError(path, "metadata", "a JSON string", str(exc)) from None
    data["time"] = float(data["time"])
    data["step"] = int(data["step"])
    return data
