"""STL read/write for wall meshes (tool geometries, containers).

Format (3D Systems StereoLithography interface specification, 1988/1989):

* binary: 80-byte header, uint32 little-endian triangle count ``n``, then
  ``n`` records of 50 bytes: normal (3 x float32), three vertices
  (9 x float32), uint16 attribute byte count.  The file size is therefore
  exactly ``84 + 50 n`` bytes, which is how a binary file is recognised
  (a binary header may itself start with the word ``solid``).
* ASCII: ``solid name`` / ``facet normal nx ny nz`` / ``outer loop`` /
  three ``vertex x y z`` / ``endloop`` / ``endfacet`` ... ``endsolid``.

STL stores a triangle soup; :func:`read_stl` welds vertices with identical
coordinates (exact match, or within ``weld_tol`` when given) into an indexed
mesh ``(vertices float64[nv, 3], triangles int64[nt, 3])`` and drops
triangles that collapse to a line or point after welding (vertices closer than
``weld_tol`` merge, however they fall on any grid).  Any truncated,
malformed or non-finite file raises :class:`soilcal.errors.InputError`
naming the file.  Units are whatever the file uses; scale on read if the
tool drawing is in millimetres (``scale=1e-3``).
"""

from __future__ import annotations

import math
import re
import struct
from pathlib import Path

import numpy as np

from soilcal.errors import InputError

_BIN_DTYPE = np.dtype([("normal", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")])
_FLOAT = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf)"


def write_stl(path, vertices, triangles, binary=True, name="soilcal"):
    """Write an indexed triangle mesh as STL (binary by default)."""
    path = Path(path)
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    if v.ndim != 2 or v.shape[1] != 3 or t.ndim != 2 or t.shape[1] != 3:
        raise ValueError("vertices must be (n, 3) and triangles (m, 3)")
    tri = v[t]  # (m, 3, 3)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    ln = np.linalg.norm(n, axis=1)
    n = n / np.where(ln > 0, ln, 1.0)[:, None]
    if binary:
        rec = np.zeros(len(t), dtype=_BIN_DTYPE)
        rec["normal"] = n
        rec["v"] = tri
        header = f"binary STL {name}".encode("ascii", "replace")[:80].ljust(80, b" ")
        with open(path, "wb") as f:
            f.write(header)
            f.write(struct.pack("<I", len(t)))
            f.write(rec.tobytes())
    else:
        lines = [f"solid {name}"]
        for k in range(len(t)):
            lines.append("  facet normal {:.9e} {:.9e} {:.9e}".format(*n[k]))
            lines.append("    outer loop")
            for j in range(3):
                lines.append("      vertex {!r} {!r} {!r}".format(*map(float, tri[k, j])))
            lines.append("    endloop")
            lines.append("  endfacet")
        lines.append(f"endsolid {name}")
        path.write_text("\n".join(lines) + "\n", encoding="ascii")


def _parse_ascii(path, text):
    toks = text.split()
    if not toks or toks[0].lower() != "solid":
        raise InputError(path, "STL", "binary STL of 84 + 50 n bytes or ASCII STL starting "
                         "with 'solid'", "neither")
    tris = []
    i = 1
    # skip the solid name (until the first 'facet' or 'endsolid')
    while i < len(toks) and toks[i].lower() not in ("facet", "endsolid"):
        i += 1
    num = re.compile(rf"^(?:{_FLOAT})$", re.IGNORECASE)
    ended = False
    while i < len(toks):
        w = toks[i].lower()
        if w == "endsolid":
            ended = True
            break
        if w != "facet":
            raise InputError(path, f"ASCII STL token {i}", "'facet' or 'endsolid'", toks[i])
        # facet normal a b c outer loop vertex x y z (x3) endloop endfacet = 21 tokens
        chunk = toks[i:i + 21]
        if len(chunk) < 21:
            raise InputError(path, f"facet {len(tris)}", "a complete facet", "truncated file")
        kw = [c.lower() for c in chunk]
        if (kw[1] != "normal" or kw[5] != "outer" or kw[6] != "loop" or kw[7] != "vertex"
                or kw[11] != "vertex" or kw[15] != "vertex" or kw[19] != "endloop"
                or kw[20] != "endfacet"):
            raise InputError(path, f"facet {len(tris)}",
                             "'facet normal n n n outer loop vertex x y z (x3) endloop "
                             "endfacet'", " ".join(chunk))
        vals = chunk[8:11] + chunk[12:15] + chunk[16:19]
        if not all(num.match(s) for s in vals + chunk[2:5]):
            raise InputError(path, f"facet {len(tris)} coordinates", "numbers", vals)
        tris.append([float(s) for s in vals])
        i += 21
    if not ended:
        raise InputError(path, "endsolid", "'endsolid' closing the solid", "truncated file")
    # a number is taken as written (the digits a writer leaves out say nothing of how the
    # drawing was rounded: 0.1 and 100 are exact)
    return np.array(tris, dtype=np.float64).reshape(-1, 3, 3)


def read_stl_soup(path):
    """Triangle soup ``[nt, 3, 3]`` from a binary or ASCII STL file: float32 as a binary file
    stores it, float64 from an ASCII one (its numbers are taken as written)."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(path, "file", "a readable STL file", str(exc)) from None
    if len(data) >= 84:
        (n,) = struct.unpack("<I", data[80:84])
        if len(data) == 84 + 50 * n:
            rec = np.frombuffer(data, dtype=_BIN_DTYPE, count=n, offset=84)
            tri = rec["v"].astype(np.float32)
            if not np.all(np.isfinite(tri)):
                raise InputError(path, "vertices", "finite coordinates", "NaN or inf")
            if n == 0:
                raise InputError(path, "triangle count", "at least one triangle", 0)
            return tri
    head = data[:5].lower()
    if head != b"solid":
        if len(data) >= 84:
            (n,) = struct.unpack("<I", data[80:84])
            raise InputError(path, "file size", f"84 + 50 * {n} = {84 + 50 * n} bytes for a "
                             f"binary STL of {n} triangles", f"{len(data)} bytes")
        raise InputError(path, "file size", "at least 84 bytes (binary STL header)",
                         f"{len(data)} bytes")
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        raise InputError(path, "STL", "ASCII text after 'solid' (or a binary STL of "
                         "84 + 50 n bytes)", "non-ASCII bytes") from None
    tri = _parse_ascii(path, text)
    if tri.shape[0] == 0:
        raise InputError(path, "triangle count", "at least one facet", 0)
    if not np.all(np.isfinite(tri)):
        raise InputError(path, "vertices", "finite coordinates", "NaN or inf")
    return tri


def weld(soup, weld_tol=0.0, facets=False):
    """Indexed mesh from a triangle soup; vertices within ``weld_tol`` of each other or
    identical (``weld_tol=0``) merge into the first of them (ValueError where a chain of such
    vertices would merge two more than 2 ``weld_tol`` apart: a mesh finer than ``weld_tol``),
    wherever they lie (two copies of a corner a float-noise apart are one vertex, as on no
    grid of rounding).  Facets without area (two corners merged, or three on one line, as
    CAD exports write slivers) are left out: they bound nothing.  ``facets=True`` returns
    also each kept triangle's index in the soup."""
    pts = soup.reshape(-1, 3)
    if weld_tol > 0:
        # here, not at module import: scipy.sparse and scipy.spatial cost every run without a mesh ~0.4 s
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components
        from scipy.spatial import cKDTree

        n = pts.shape[0]
        pairs = cKDTree(pts).query_pairs(float(weld_tol), output_type="ndarray")
        graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
        _, key = connected_components(graph, directed=False)
        _, first, inv = np.unique(key, return_index=True, return_inverse=True)
        # a chain of corners each within weld_tol of the next would merge corners far apart
        # (a mesh finer than weld_tol collapses): refused, not welded
        # each merged group's extent: the diagonal of the box holding its corners
        lo_g = np.full((first.size, 3), np.inf)
        hi_g = np.full((first.size, 3), -np.inf)
        np.minimum.at(lo_g, inv, pts)
        np.maximum.at(hi_g, inv, pts)
        far = np.linalg.norm(hi_g - lo_g, axis=1)
        if far.size and far.max() > 2.0 * weld_tol:
            raise ValueError(f"corners {far.max():.3g} apart would merge through a chain of corners each within "
                             f"weld_tol = {weld_tol:g} of the next: a weld_tol below the mesh's shortest edge")
    else:
        _, first, inv = np.unique(pts, axis=0, return_index=True, return_inverse=True)
    verts = pts[first]
    tris = inv.reshape(-1, 3).astype(np.int64)
    kept = np.flatnonzero(~without_area(verts[tris]))
    return (verts, tris[kept], kept) if facets else (verts, tris[kept])


def without_area(corners) -> np.ndarray:
    """Which triangles (``corners`` [n, 3, 3]) have no area: two corners in one point, or
    three on one line (twice the area under 1e-12 of the longer edge from the first corner,
    squared)."""
    c = np.asarray(corners, dtype=np.float64).reshape(-1, 3, 3)
    e1, e2 = c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]
    area2 = np.linalg.norm(np.cross(e1, e2), axis=1)
    return ~(area2 > 1e-12 * np.maximum((e1 ** 2).sum(axis=1), (e2 ** 2).sum(axis=1)))


def read_stl(path, scale=1.0, weld_tol=0.0, facets=False):
    """Read an STL file into ``(vertices [nv, 3], triangles int64[nt, 3])``, coordinates
    multiplied by ``scale``: float32 from a binary file (as it stores them, scaled in
    float32, so :meth:`soilcal.dem.engine.Simulation.add_mesh` forgives a face float32's
    rounding, also after ``v * 1e-3``), float64 from an ASCII one (its numbers taken as
    written).  Facets without area are left out (:func:`weld`), so
    triangle k need not be the file's facet k: ``facets=True`` returns also each triangle's
    facet index in the file, ``(vertices, triangles, facets int64[nt])``; give it to
    :meth:`soilcal.dem.engine.Simulation.add_mesh` (``facets=``) and a refused face is named
    by its facet in the file.  The vertices' type is their rounding: ``add_mesh`` takes
    float32's unit roundoff (2^-24 |x|) for a binary file's, float64's for an ASCII one's,
    and a periodic box forgives a face that much and no more."""
    try:
        tol = float(weld_tol)
    except (TypeError, ValueError):
        tol = math.nan
    if not (math.isfinite(tol) and tol >= 0):
        raise InputError(path, "weld_tol", "a welding distance >= 0 (0: identical corners only)",
                         weld_tol)
    soup = read_stl_soup(path)
    f32 = soup.dtype == np.float32
    # a binary file's float32 numbers scaled in float32: the result is float32 numbers, and
    # its rounding float32's (one more unit roundoff, forgiven as the file's own)
    soup = (soup * np.float32(scale)).astype(np.float64) if f32 else soup * float(scale)
    try:
        v, t, kept = weld(soup, tol, facets=True)
    except ValueError as exc:
        raise InputError(path, "weld_tol", "a welding distance below the mesh's shortest edge", f"{tol:g}: {exc}") \
            from None
    if t.shape[0] == 0:
        raise InputError(path, "triangles", "at least one non-degenerate triangle", 0)
    if f32:
        v = v.astype(np.float32)  # each vertex a corner of the soup: float32 numbers
    return (v, t, kept) if facets else (v, t)
