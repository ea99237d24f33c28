import pickle
from pathlib import Path

import numpy as np
import pytest

import bipolar
from bipolar import errors


def tetra():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    t = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return v, t


def test_mesh_roundtrips_arrays():
    v, t = tetra()
    m = bipolar.Mesh(v, t)
    assert m.n_vertices == 4 and m.n_faces == 4 and len(m) == 4
    np.testing.assert_array_equal(m.vertices, v)
    np.testing.assert_array_equal(m.triangles, t)
    assert m.vertices.dtype == np.float64 and m.triangles.dtype == np.uint32
    assert m.area() == pytest.approx(1.5 + np.sqrt(3) / 2)
    assert m.warnings == []


def test_icosphere_counts_and_radius():
    for k, n in [(0, 12), (2, 162), (4, 2562)]:
        m = bipolar.icosphere(k)
        assert m.n_vertices == n
        np.testing.assert_allclose(np.linalg.norm(m.vertices, axis=1), 1.0, rtol=1e-12)


@pytest.mark.parametrize("fmt", ["obj", "ply", "off", "glb"])
def test_write_read_roundtrip_keeps_the_mesh(tmp_path, fmt):
    m = bipolar.icosphere(2)
    p = tmp_path / f"m.{fmt}"
    bipolar.write_mesh(p, m)
    r = bipolar.read_mesh(p)
    np.testing.assert_array_equal(r.triangles, m.triangles)
    # glb stores f32 positions; the text formats and PLY (double) are exact.
    tol = 1e-7 if fmt == "glb" else 0
    np.testing.assert_allclose(r.vertices, m.vertices, atol=tol, rtol=0)
    r2 = bipolar.read_mesh_bytes(m.to_bytes(fmt), fmt)
    np.testing.assert_allclose(r2.vertices, r.vertices, atol=tol, rtol=0)


def test_stl_roundtrip_keeps_every_triangle(tmp_path):
    m = bipolar.icosphere(1)
    p = tmp_path / "m.stl"
    bipolar.write_mesh(p, m)
    r = bipolar.read_mesh(p)
    assert r.n_faces == m.n_faces
    # STL stores f32 corners per triangle.
    np.testing.assert_allclose(
        r.vertices[r.triangles], m.vertices[m.triangles], atol=1e-7, rtol=0
    )


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_ply_extras_roundtrip(tmp_path, encoding):
    m = bipolar.icosphere(1)
    n = m.n_vertices
    colors = (np.arange(n * 3).reshape(n, 3) % 256).astype(np.uint8)
    field = np.linspace(0.0, 1.0, n)
    m2 = m.with_extras(colors=colors, scalars={"dist": field})
    p = tmp_path / "m.ply"
    bipolar.write_ply(p, m2, encoding)
    r = bipolar.read_mesh(p)
    np.testing.assert_array_equal(r.colors[:, :3], colors)
    np.testing.assert_array_equal(r.colors[:, 3], 255)
    np.testing.assert_array_equal(r.scalars["dist"], field)
    np.testing.assert_array_equal(r.vertices, m.vertices)


def test_pickle_keeps_mesh_and_extras():
    m = bipolar.icosphere(1).with_extras(scalars={"s": np.arange(42.0)})
    r = pickle.loads(pickle.dumps(m))
    np.testing.assert_array_equal(r.vertices, m.vertices)
    np.testing.assert_array_equal(r.triangles, m.triangles)
    np.testing.assert_array_equal(r.scalars["s"], np.arange(42.0))


def test_weld_merges_duplicates():
    v, t = tetra()
    v2 = np.vstack([v, v[:1]])
    t2 = t.copy()
    t2[0, 0] = 4
    m = bipolar.Mesh(v2, t2)
    assert any("duplicate" in w for w in m.warnings)
    w, summary = m.weld()
    assert summary["welded_vertices"] == 1 and w.n_vertices == 4


def test_nearest_and_surface_positions():
    m = bipolar.icosphere(3)
    q = np.array([[0.0, 0.0, 2.0], [0.3, -0.2, 0.1]])
    faces, bary, dist = m.nearest(q)
    p = m.surface_positions(faces, bary)
    np.testing.assert_allclose(np.linalg.norm(p - q, axis=1), dist, rtol=1e-12)
    assert dist[0] == pytest.approx(1.0, abs=1e-2)


def test_landmark_files_roundtrip(tmp_path):
    lm = {"Nose tip": [1.0, 2.0, 3.5], "Outer left eye corner": [-4.25, 0.5, 1.0]}
    p = tmp_path / "a.lm3"
    bipolar.write_lm3(p, lm)
    r = bipolar.read_landmarks(p)
    assert set(r) == set(lm)
    for k in lm:
        np.testing.assert_array_equal(r[k], lm[k])


def test_lm2_reads_2d_landmarks():
    fixtures = Path(__file__).resolve().parents[2] / "fixtures"
    r = bipolar.read_lm2(fixtures / "sample.lm2")
    assert list(r) == ["Nose tip", "Chin middle"]
    np.testing.assert_array_equal(r["Nose tip"], [120.5, 200.0])
    np.testing.assert_array_equal(r["Chin middle"], [118.0, 330.25])
    assert r["Nose tip"].dtype == np.float64
    with pytest.raises(errors.FileError):
        bipolar.read_lm2(fixtures / "missing.lm2")


# --- bad input: a clear exception, never a crash --------------------------------------------


def test_wrong_dtypes_are_type_errors():
    v, t = tetra()
    with pytest.raises(errors.InputTypeError, match="triangles must be an array of integers"):
        bipolar.Mesh(v, t.astype(np.float64))
    with pytest.raises(TypeError, match="vertices must be an array of real numbers"):
        bipolar.Mesh(v.astype(np.complex128), t)
    with pytest.raises(TypeError):
        bipolar.Mesh(np.array([["a", "b", "c"]]), t)
    with pytest.raises(TypeError):
        bipolar.Mesh(v, object())
    with pytest.raises(ValueError):  # ragged lists
        bipolar.Mesh([[0, 0, 0], [1, 0]], t)


def test_wrong_shapes_and_empty_arrays():
    v, t = tetra()
    with pytest.raises(errors.InputError, match=r"vertices must have shape \(n, 3\), got \(4, 2\)"):
        bipolar.Mesh(v[:, :2], t)
    with pytest.raises(errors.InputError, match=r"triangles must have shape \(m, 3\)"):
        bipolar.Mesh(v, t.ravel())
    with pytest.raises(ValueError, match="empty mesh"):
        bipolar.Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int32))
    with pytest.raises(ValueError, match="empty mesh"):
        bipolar.Mesh(v, np.zeros((0, 3), dtype=np.int32))


def test_indices_out_of_range_and_negative():
    v, t = tetra()
    t2 = t.copy()
    t2[2, 1] = 7
    with pytest.raises(errors.IndexOutOfRangeError, match="refers to vertex 7"):
        bipolar.Mesh(v, t2)
    t2[2, 1] = -1
    with pytest.raises(IndexError, match=r"triangles\[2, 1\] = -1"):
        bipolar.Mesh(v, t2)
    big = np.array([[0, 1, 2**40]], dtype=np.uint64)
    with pytest.raises(ValueError):
        bipolar.Mesh(v, big)


def test_nan_and_inf_vertices():
    v, t = tetra()
    v[2, 1] = np.nan
    with pytest.raises(errors.InputError, match="vertex 2 has a non-finite coordinate"):
        bipolar.Mesh(v, t)
    v[2, 1] = np.inf
    with pytest.raises(ValueError):
        bipolar.Mesh(v, t)


def test_non_contiguous_arrays_read_through_strides():
    v, t = tetra()
    vf = np.asfortranarray(v)
    big = np.zeros((4, 6))
    big[:, ::2] = v
    strided = big[:, ::2]
    assert not strided.flags.c_contiguous
    tt = np.asfortranarray(t)[:, :]
    for vv, ttt in [(vf, t), (strided, tt), (v[::-1][::-1], t[:, [0, 1, 2]])]:
        m = bipolar.Mesh(vv, ttt)
        np.testing.assert_array_equal(m.vertices, v)
        np.testing.assert_array_equal(m.triangles, t)


def test_unaligned_arrays_are_read_correctly():
    # Arrays rebuilt from pickle-5 buffers (as Dask sends them) can be unaligned.
    v, t = tetra()
    buf = bytearray(v.nbytes + 1)
    uv = np.frombuffer(buf, dtype=np.float64, count=v.size, offset=1).reshape(4, 3)
    assert not uv.flags.aligned
    uv[...] = v
    tb = bytearray(t.astype(np.int64).nbytes + 1)
    ut = np.frombuffer(tb, dtype=np.int64, count=t.size, offset=1).reshape(4, 3)
    ut[...] = t
    m = bipolar.Mesh(uv, ut)
    np.testing.assert_array_equal(m.vertices, v)
    np.testing.assert_array_equal(m.triangles, t)


def test_file_errors():
    with pytest.raises(errors.FileError):
        bipolar.read_mesh("/nonexistent/m.obj")
    with pytest.raises(OSError):
        bipolar.read_mesh("/nonexistent/m.obj")
    with pytest.raises(errors.FileFormatError, match="unknown mesh format"):
        bipolar.read_mesh("m.xyz")
    with pytest.raises(errors.FileFormatError):
        bipolar.read_mesh_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\n", "ply")
    with pytest.raises(errors.FileFormatError):
        bipolar.read_mesh_bytes(b"\x00" * 10, "glb")
    with pytest.raises(TypeError):
        bipolar.read_mesh(12)
