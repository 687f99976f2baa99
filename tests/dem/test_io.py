"""VTK XML, .pvd, .npz and STL round trips, parsed back independently."""

import base64
import json
import math
import struct
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from soilcal.dem import geometry as g
from soilcal.dem import io
from soilcal.dem.stl import read_stl, read_stl_soup, write_stl
from soilcal.errors import InputError


def _particles(n=7, seed=1):
    rng = np.random.default_rng(seed)
    return (rng.normal(size=(n, 3)), rng.uniform(1e-3, 2e-3, n), rng.normal(size=(n, 3)),
            rng.normal(size=(n, 3)), rng.integers(0, 3, n), np.arange(100, 100 + n))


@pytest.mark.parametrize("binary", [False, True])
def test_vtu_round_trip(tmp_path, binary):
    x, r, v, w, m, ids = _particles()
    f = io.write_particles_vtu(tmp_path / "p.vtu", x, r, v, w, m, ids,
                               extra={"speed": np.linalg.norm(v, axis=1)}, binary=binary)
    root = ET.parse(f).getroot()
    assert root.get("type") == "UnstructuredGrid"
    piece = root.find("UnstructuredGrid/Piece")
    assert piece.get("NumberOfPoints") == "7" and piece.get("NumberOfCells") == "7"
    d = io.read_vtk_arrays(f)
    assert np.array_equal(d["Points/Points"], x)
    assert np.array_equal(d["PointData/radius"], r)
    assert np.array_equal(d["PointData/velocity"], v)
    assert np.array_equal(d["PointData/angular_velocity"], w)
    assert np.array_equal(d["PointData/material"], m)
    assert np.array_equal(d["PointData/id"], ids)
    assert np.array_equal(d["Cells/types"], np.ones(7))  # VTK_VERTEX
    assert np.array_equal(d["Cells/offsets"], np.arange(1, 8))


def test_vtu_binary_layout_is_uint64_count_then_data(tmp_path):
    # decode by hand: base64( uint64 little-endian byte count + float64 data )
    f = io.write_particles_vtu(tmp_path / "p.vtu", np.zeros((2, 3)), [0.5, 0.25])
    da = [e for e in ET.parse(f).getroot().iter("DataArray") if e.get("Name") == "radius"][0]
    raw = base64.b64decode(da.text)
    assert struct.unpack("<Q", raw[:8])[0] == 16
    assert struct.unpack("<2d", raw[8:]) == (0.5, 0.25)


def test_vtp_and_pvd(tmp_path):
    v, t = g.box_mesh([0, 0, 0], [1, 1, 1])
    f = io.write_mesh_vtp(tmp_path / "walls" / "box.vtp", v, t, cell_data={"wall": np.zeros(12)})
    d = io.read_vtk_arrays(f)
    assert d["piece"]["NumberOfPolys"] == "12" and d["piece"]["NumberOfPoints"] == "8"
    assert np.array_equal(d["Polys/connectivity"].reshape(-1, 3), t)
    assert np.array_equal(d["Polys/offsets"], 3 * np.arange(1, 13))
    files = [io.write_particles_vtu(tmp_path / f"p_{k}.vtu", np.zeros((1, 3)), [1.0])
             for k in range(3)]
    pvd = io.write_pvd(tmp_path / "run.pvd", [(0.01 * k, fk) for k, fk in enumerate(files)])
    ds = list(ET.parse(pvd).getroot().iter("DataSet"))
    assert [d.get("file") for d in ds] == ["p_0.vtu", "p_1.vtu", "p_2.vtu"]
    series = io.read_pvd(pvd)
    assert [t for t, _ in series] == [0.0, 0.01, 0.02]
    assert all(p.exists() for _, p in series)


def test_optional_vtk_reader(tmp_path):
    vtk = pytest.importorskip("vtk")
    x, r, v, w, m, ids = _particles()
    f = io.write_particles_vtu(tmp_path / "p.vtu", x, r, v, w, m, ids)
    rd = vtk.vtkXMLUnstructuredGridReader()
    rd.SetFileName(str(f))
    rd.Update()
    assert rd.GetOutput().GetNumberOfPoints() == 7


def test_snapshot_round_trip_and_validation(tmp_path):
    x, r, v, w, m, ids = _particles(11)
    meta = {"seed": 42, "soil": "cinnamon", "E": 7.9e10}
    f = io.write_snapshot(tmp_path / "s.npz", x, v, r, m, 0.125, 2500, meta,
                          angular_velocities=w, ids=ids)
    d = io.read_snapshot(f)
    assert np.array_equal(d["positions"], x) and np.array_equal(d["radii"], r)
    assert np.array_equal(d["material"], m) and np.array_equal(d["ids"], ids)
    assert d["time"] == 0.125 and d["step"] == 2500 and d["metadata"] == meta
    bad = tmp_path / "bad.npz"
    np.savez(bad, positions=x, velocities=v, radii=r, material=m, time=0.0, step=0)
    with pytest.raises(InputError, match="bad.npz: metadata"):
        io.read_snapshot(bad)
    np.savez(bad, positions=x, velocities=v, radii=r[:3], material=m, time=0.0, step=0,
             metadata=np.array(json.dumps({})))
    with pytest.raises(InputError, match="radii"):
        io.read_snapshot(bad)


# ---------------------------------------------------------------- STL


@pytest.mark.parametrize("binary", [True, False])
def test_stl_round_trip(tmp_path, binary):
    v, t = g.drum_mesh(0.2, 0.1, n_seg=24)
    f = tmp_path / "drum.stl"
    write_stl(f, v, t, binary=binary)
    if binary:
        assert f.stat().st_size == 84 + 50 * len(t)
    v2, t2 = read_stl(f)
    assert len(v2) == len(v) and len(t2) == len(t)
    assert g.is_watertight(t2)  # welding restores connectivity
    # same set of triangles (compare sorted triangle centroids)
    # float32 storage in binary STL; ASCII keeps every digit
    tol = 1e-7 if binary else 0.0
    c1 = v[t].mean(1)
    c2 = v2[t2].mean(1)
    o1 = np.lexsort(np.round(c1, 5).T)
    o2 = np.lexsort(np.round(c2, 5).T)
    assert np.allclose(c1[o1], c2[o2], rtol=0, atol=tol)
    assert g.mesh_volume(v2, t2) == pytest.approx(g.mesh_volume(v, t), rel=1e-6)
    v3, _ = read_stl(f, scale=1e-3)
    assert np.abs(v3).max() == pytest.approx(0.2e-3, rel=1e-6)


def test_stl_weld_merges_corners_closer_than_the_tolerance_wherever_they_lie(tmp_path):
    """A square plate of two facets exported with float noise on the copies of the shared
    corners: the copies 2e-12 m apart straddle x = 0.5e-6 m, a line of the rounding grid of
    weld_tol = 1e-6 m, and were kept as two vertices (5 vertices, the seam open); the plate has
    4 corners and its two facets share an edge."""
    e = 1e-12
    a = [0.5e-6 - e, 0.0, 0.0]  # the shared corner (0.5e-6, 0, 0) as exported by facet 1
    b = [0.5e-6 + e, 0.0, 0.0]  # ... and by facet 2
    c, d = [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]
    soup = np.array([[a, [1.0, 0.0, 0.0], c], [b, c, d]])
    f = tmp_path / "plate.stl"
    facets = ["facet normal 0 0 1\nouter loop\n"
              + "".join("vertex %r %r %r\n" % tuple(map(float, q)) for q in tri)
              + "endloop\nendfacet\n" for tri in soup]
    f.write_text("solid plate\n" + "".join(facets) + "endsolid plate\n")
    v, t = read_stl(f, weld_tol=1e-6)
    assert len(v) == 4 and len(t) == 2
    shared = set(t[0].tolist()) & set(t[1].tolist())
    assert len(shared) == 2  # the diagonal edge, one edge of both facets
    v0, _ = read_stl(f)  # exact welding keeps the noisy copies apart
    assert len(v0) == 5
    with pytest.raises(InputError, match="weld_tol"):
        read_stl(f, weld_tol=-1e-6)


def test_stl_weld_refuses_a_tolerance_that_chains_a_fine_mesh_together(tmp_path):
    """A strip 10 mm long with corners every 0.5 mm, welded with weld_tol = 0.6 mm: each corner
    lies within the tolerance of the next, so merging by chains collapsed each row of corners
    into its first, up to 10 mm away, and the strip vanished (1 of 41 facets kept).  Refused,
    naming weld_tol; a tolerance below the edges welds nothing away."""
    xs = np.arange(21) * 0.5e-3
    tris = []
    for x0, x1 in zip(xs[:-1], xs[1:]):
        tris += [[[x0, 0, 0], [x1, 0, 0], [x1, 5e-3, 0]], [[x0, 0, 0], [x1, 5e-3, 0], [x0, 5e-3, 0]]]
    f = tmp_path / "strip.stl"
    f.write_text("solid s\n" + "".join("facet normal 0 0 1\nouter loop\n" + "".join(
        "vertex %r %r %r\n" % tuple(map(float, q)) for q in tri) + "endloop\nendfacet\n" for tri in tris)
        + "endsolid s\n")
    with pytest.raises(InputError, match="weld_tol"):
        read_stl(f, weld_tol=0.6e-3)
    v, t = read_stl(f, weld_tol=0.1e-3)
    assert len(v) == 42 and len(t) == 40


def test_stl_weld_judges_a_chain_across_its_whole_length():
    """Five corners 0.95 weld_tol apart in a row, centred on the first: each is within 1.9
    weld_tol of the first, but the row is 3.8 weld_tol long; refused as a chain."""
    from soilcal.dem.stl import weld

    tol = 1e-3
    xs = [0.0, -0.95e-3, 0.95e-3, -1.9e-3, 1.9e-3]
    soup = np.array([[[x, 0, 0], [x + 0.1 * (i + 1), 1.0, 0], [x - 0.1 * (i + 1), 1.0, 1.0]]
                     for i, x in enumerate(xs)])
    with pytest.raises(ValueError, match="weld_tol"):
        weld(soup, tol)


def test_stl_truncated_and_invalid(tmp_path):
    v, t = g.box_mesh([0, 0, 0], [1, 1, 1])
    f = tmp_path / "box.stl"
    write_stl(f, v, t)
    data = f.read_bytes()
    (tmp_path / "cut.stl").write_bytes(data[:-20])
    with pytest.raises(InputError, match=r"cut\.stl: file size"):
        read_stl(tmp_path / "cut.stl")
    write_stl(f, v, t, binary=False)
    text = f.read_text()
    (tmp_path / "cut2.stl").write_text(text[: len(text) // 2])
    with pytest.raises(InputError, match=r"cut2\.stl"):
        read_stl(tmp_path / "cut2.stl")
    (tmp_path / "bad.stl").write_text(text.replace("vertex 1.0", "vertex abc", 1))
    with pytest.raises(InputError, match=r"bad\.stl: facet"):
        read_stl(tmp_path / "bad.stl")
    (tmp_path / "tiny.stl").write_bytes(b"abc")
    with pytest.raises(InputError, match=r"tiny\.stl"):
        read_stl(tmp_path / "tiny.stl")
    with pytest.raises(InputError, match=r"missing\.stl"):
        read_stl(tmp_path / "missing.stl")


def test_binary_stl_whose_header_says_solid(tmp_path):
    # a binary file may begin with "solid"; size 84 + 50 n decides
    v, t = g.box_mesh([0, 0, 0], [2, 1, 1])
    f = tmp_path / "b.stl"
    write_stl(f, v, t, binary=True)
    data = bytearray(f.read_bytes())
    data[:5] = b"solid"
    f.write_bytes(bytes(data))
    soup = read_stl_soup(f)
    assert soup.shape == (12, 3, 3)
    vv, tt = read_stl(f)
    assert g.mesh_volume(vv, tt) == pytest.approx(2.0)
    assert math.isclose(g.mesh_area(vv, tt), 10.0)
