import pickle

import numpy as np
import pytest

import bipolar
from bipolar import errors

from conftest import bump, rotation


@pytest.fixture(scope="module")
def bump_desc(bump_mesh):
    return bipolar.describe(bump_mesh, 0, 1599, levels=12)


def test_descriptor_arrays(bump_desc, bump_mesh):
    d = bump_desc
    n = len(d)
    assert n > 50
    assert d.points.shape == (n, 3) and d.keys.shape == (n,) and d.keys.dtype == np.uint64
    assert d.cos.shape == (n,) and np.all(np.abs(d.cos) <= 1.0)
    assert d.ambiguous.dtype == np.bool_
    assert np.all(np.diff(d.keys.astype(np.float64)) >= 0)  # sorted by key
    np.testing.assert_allclose(bump_mesh.surface_positions(d.faces, d.bary), d.points, atol=1e-12)
    assert d.references.shape == (2, 3)
    np.testing.assert_array_equal(d.references[0], bump_mesh.vertices[0])
    assert d.step == pytest.approx(d.reference_distance / 12)
    assert d.options["levels"] == {"Count": 12}
    assert d.stats["intersections"] >= n
    f = d.key_fields()
    assert set(f) == {"a", "b", "i", "j", "side", "sign"}
    k0 = bipolar.pack_key(*(int(f[x][0]) for x in ["a", "b", "i", "j", "side", "sign"]))
    assert k0 == int(d.keys[0])
    assert bipolar.unpack_key(k0) == tuple(int(f[x][0]) for x in ["a", "b", "i", "j", "side", "sign"])


def test_the_descriptor_is_invariant_under_rigid_motions(bump_mesh, bump_desc):
    r = rotation(5)
    t = np.array([0.3, -2.0, 1.5])
    moved = bipolar.Mesh(bump_mesh.vertices @ r.T + t, bump_mesh.triangles)
    d2 = bipolar.describe(moved, 0, 1599, levels=12)
    np.testing.assert_array_equal(d2.keys, bump_desc.keys)
    np.testing.assert_allclose(d2.cos, bump_desc.cos, atol=1e-9)
    np.testing.assert_allclose(d2.points, bump_desc.points @ r.T + t, atol=1e-9)
    assert bipolar.distance(bump_desc, d2) < 1e-9


def test_json_pickle_and_csv_roundtrips(tmp_path, bump_desc):
    d = bump_desc
    p = tmp_path / "d.json"
    d.save(p)
    assert bipolar.read_descriptor(p) == d
    assert bipolar.Descriptor.from_json(d.to_json()) == d
    assert pickle.loads(pickle.dumps(d)) == d
    c = tmp_path / "d.csv"
    d.save(c)
    r = bipolar.read_descriptor(c)
    np.testing.assert_array_equal(r.points, d.points)
    np.testing.assert_array_equal(r.keys, d.keys)
    np.testing.assert_array_equal(r.cos, d.cos)
    assert np.isnan(r.step)
    d.save(tmp_path / "d.ply")
    assert (tmp_path / "d.ply").read_text().startswith("ply")


def test_solver_path_and_options_agree(bump_mesh, tmp_path, bump_desc):
    s = bipolar.GeodesicSolver(bump_mesh, "exact")
    assert bipolar.describe(bump_mesh, 0, 1599, levels=12, solver=s) == bump_desc
    p = tmp_path / "bump.ply"
    bipolar.write_mesh(p, bump_mesh)
    assert bipolar.describe(str(p), 0, 1599, levels=12) == bump_desc
    step = bump_desc.step
    by_step = bipolar.describe(bump_mesh, 0, 1599, step=step)
    assert by_step.step == step
    for kw in [
        dict(rule="filter"),
        dict(rule="filter", tolerance=0.01),
        dict(rule="all"),
        dict(tangent="strip"),
        dict(tangent="spline"),
        dict(method="fmm"),
        dict(method="heat"),
        dict(method="dijkstra"),
        dict(angles=4, alpha=0.8),
        dict(max_level=9),
        dict(refs=[800]),
    ]:
        d = bipolar.describe(bump_mesh, 0, 1599, levels=12, **kw)
        assert len(d) > 0, kw
    region = bipolar.describe(bump_mesh, 0, 1599, levels=12, max_level=9)
    assert region.options["max_level"] == 9
    assert bipolar.describe(bump_mesh, 0, 1599, levels=12, rule="filter").options["rule"] == {
        "Filter": {"tolerance": 0.95 / 32}
    }
    three = bipolar.describe(bump_mesh, 0, 1599, levels=12, refs=[800])
    assert set(three.key_fields()["b"]) >= {1, 2}


def test_point_references_are_snapped(bump_mesh, bump_desc):
    p = bump_mesh.vertices[0] + np.array([0.0, 0.0, 1e-3])
    d = bipolar.describe(bump_mesh, p, 1599, levels=12)
    assert len(d) > 0
    np.testing.assert_allclose(d.references[0], bump_mesh.vertices[0], atol=1e-9)
    lm = {"nose_tip": bump_mesh.vertices[0], "my point": bump_mesh.vertices[1599]}
    d2 = bipolar.describe(bump_mesh, "nose-tip", "MY POINT", levels=12, landmarks=lm)
    np.testing.assert_allclose(d2.points, bump_desc.points, atol=1e-9)


def test_boundary_margin_leaves_out_the_band_along_the_border(bump_mesh, bump_desc):
    # The bump's border is the square |x|, |y| = 1 (grid from -1 to 1).
    def border(p):
        return np.min(1.0 - np.abs(p[:, :2]), axis=1)

    cut = bipolar.describe(bump_mesh, 0, 1599, levels=12, boundary_margin=0.3)
    assert 0 < len(cut) < len(bump_desc)
    assert border(bump_desc.points).min() < 0.1
    # Geodesic distance to the border is at least the distance in the plane; kept faces have
    # every vertex 0.3 or more from it (less one cell, 0.05 plus jitter, for the points).
    assert border(cut.points).min() > 0.15
    with pytest.raises(errors.InputError, match="boundary margin"):
        bipolar.describe(bump_mesh, 0, 1599, boundary_margin=-1.0)


def test_max_incidence_leaves_out_the_steep_parts(bump_mesh):
    # Seen along z, the incidence at (x, y) is the slope angle of the bump z = f(x, y).
    def incidence(p):
        x, y = p[:, 0], p[:, 1]
        g = 0.4 * np.exp(-((x - 0.1) ** 2 + (y + 0.2) ** 2) / 0.3) / 0.3
        fx = -2.0 * (x - 0.1) * g + 0.1 * y
        fy = -2.0 * (y + 0.2) * g + 0.1 * x
        return np.degrees(np.arctan(np.hypot(fx, fy)))

    full = bipolar.describe(bump_mesh, 0, 1599, levels=12, rule="all")
    cut = bipolar.describe(bump_mesh, 0, 1599, levels=12, rule="all", max_incidence=20.0)
    assert 0 < len(cut) < len(full)
    assert incidence(full.points).max() > 30.0
    # Kept points are on faces whose (ring-averaged) vertex normals all passed.
    assert incidence(cut.points).max() < 28.0
    # The fields are the same: with rule "all" every kept point is a point of the full
    # descriptor (the iso-angle rule fits along curve runs, which the mask shortens).
    d = np.linalg.norm(cut.points[:, None, :] - full.points[None, :, :], axis=2)
    assert d.min(axis=1).max() < 1e-12
    with pytest.raises(errors.InputError, match="max incidence"):
        bipolar.describe(bump_mesh, 0, 1599, max_incidence=-5.0)


def test_describe_bad_input(bump_mesh):
    n = bump_mesh.n_vertices
    with pytest.raises(errors.InputError, match="levels or step"):
        bipolar.describe(bump_mesh, 0, 1599, levels=3, step=0.1)
    with pytest.raises(errors.InputError, match="unknown rule"):
        bipolar.describe(bump_mesh, 0, 1599, rule="best")
    with pytest.raises(errors.InputError, match="unknown tangent"):
        bipolar.describe(bump_mesh, 0, 1599, tangent="x")
    with pytest.raises(errors.IndexOutOfRangeError, match=f"reference vertex {n} does not exist"):
        bipolar.describe(bump_mesh, 0, n)
    with pytest.raises(errors.InputError, match="coincide"):
        bipolar.describe(bump_mesh, 5, 5)
    with pytest.raises(errors.InputError, match="alpha"):
        bipolar.describe(bump_mesh, 0, 1599, alpha=1.5)
    with pytest.raises(errors.InputError, match="not a landmark name"):
        bipolar.describe(bump_mesh, "left ear", 1599)
    with pytest.raises(errors.InputError, match="not finite"):
        bipolar.describe(bump_mesh, [np.nan, 0, 0], 1599)
    with pytest.raises(errors.InputError, match="farther than the tolerance"):
        bipolar.describe(bump_mesh, [1e9, 0, 0], 1599)
    with pytest.raises(errors.InputError, match="not among the given landmarks"):
        bipolar.describe(bump_mesh, "nose-tip", 1599, landmarks={"x": [0, 0, 0]})
    with pytest.raises(errors.LandmarksNotFoundError):
        bipolar.describe(bump_mesh, "nose-tip", 1599)
    with pytest.raises(errors.FileError):
        bipolar.describe("/nonexistent.obj", 0, 1)
    with pytest.raises(errors.InputError, match="solver was prepared for"):
        bipolar.describe(bump_mesh, 0, 1, solver=bipolar.GeodesicSolver(bipolar.icosphere(2)))
    # Levels i, j <= 6 of references 12 levels apart cannot meet (i + j >= 12 is needed).
    with pytest.raises(errors.NoDescriptorPointsError, match="do not intersect"):
        bipolar.describe(bump_mesh, 0, 1599, levels=12, max_level=5)


def test_the_reference_point_search_gives_the_own_descriptor_then_the_moved_ones(bump_mesh):
    a, b = 20 * 40 + 8, 20 * 40 + 32  # interior vertices of the bump's 40 x 40 grid
    own = bipolar.describe(bump_mesh, a, b, levels=8)
    found = bipolar.describe(bump_mesh, a, b, levels=8, search_radius=0.15)
    assert isinstance(found, list) and 30 < len(found) <= 49
    assert found[0] == own
    # Each moved pair has its own references, and its descriptor is the one described from
    # those two vertices with the same options.
    assert len({d.references.tobytes() for d in found}) == len(found)
    for d in (found[1], found[7], found[-1]):
        va, vb = (int(np.argmin(np.linalg.norm(bump_mesh.vertices - r, axis=1))) for r in d.references)
        direct = bipolar.describe(bump_mesh, va, vb, levels=8)
        np.testing.assert_array_equal(direct.keys, d.keys)
        np.testing.assert_allclose(direct.points, d.points, atol=1e-9)
    # Fewer directions, fewer pairs; the results pickle (for dask) like any descriptor.
    three = bipolar.describe(bump_mesh, a, b, levels=8, search_radius=0.15, search_directions=3)
    assert 1 < len(three) <= 16
    assert pickle.loads(pickle.dumps(three)) == three
    with pytest.raises(errors.InputError, match="radius"):
        bipolar.describe(bump_mesh, a, b, search_radius=0.0)
    with pytest.raises(errors.InputError, match="reference points"):
        bipolar.describe(bump_mesh, a, b, refs=[5], search_radius=0.15)


def test_searched_distance_is_the_least_over_own_and_each_sides_moved(bump_mesh):
    a, b = 20 * 40 + 8, 20 * 40 + 32
    found = bipolar.describe(bump_mesh, a, b, levels=8, search_radius=0.15)
    own = found[0]
    # A face described from one of the moved pairs: the search finds it exactly.
    va, vb = (int(np.argmin(np.linalg.norm(bump_mesh.vertices - r, axis=1))) for r in found[5].references)
    other = bipolar.describe(bump_mesh, va, vb, levels=8)
    plain = bipolar.distance(own, other)
    assert plain > 1e-4
    assert bipolar.searched_distance(found, other) < 1e-12
    assert bipolar.searched_distance(other, found) < 1e-12
    # The rule: own against own and each side's moved against the other's own, never moved
    # against moved.
    other_found = bipolar.describe(bump_mesh, va, vb, levels=8, search_radius=0.15)
    expected = min(
        [bipolar.distance(own, other_found[0])]
        + [bipolar.distance(m, other_found[0]) for m in found[1:]]
        + [bipolar.distance(own, m) for m in other_found[1:]]
    )
    assert bipolar.searched_distance(found, other_found) == pytest.approx(expected, rel=1e-12, abs=1e-15)
    # A Descriptor is a list of one; no search on either side is the plain distance.
    assert bipolar.searched_distance(own, other) == bipolar.distance(own, other)
    assert bipolar.searched_distance([own], [other], mode="icp") == pytest.approx(
        bipolar.distance(own, other, mode="icp")
    )
    with pytest.raises(errors.InputError, match="empty list"):
        bipolar.searched_distance([], other)
    with pytest.raises(TypeError, match=r"b\[1\] is not a bipolar.Descriptor"):
        bipolar.searched_distance(own, [other, 3])


def test_face_with_detected_landmarks(face_path, face):
    d = bipolar.describe(face, "outer-eye-right", "outer-eye-left", levels=30, max_level=30)
    assert len(d) > 500
    lm = bipolar.detect_landmarks(face)
    np.testing.assert_array_equal(d.references[0], lm["landmarks"]["outer_eye_right"]["position"])
