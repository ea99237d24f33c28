"""The virtual range scanner and scan preparation from Python."""

import numpy as np
import pytest

import bipolar
from bipolar import errors


@pytest.fixture(scope="module")
def ball():
    # A face-sized sphere: radius 80 mm, given in cm (so the units must be recognised).
    s = bipolar.icosphere(4)
    return bipolar.Mesh(s.vertices * 8.0, s.triangles)


def test_a_frontal_scan_lies_on_the_sphere_in_mm(ball):
    mesh, info = bipolar.scan(ball, pitch=1.0)
    assert info["input_units"] == "cm"
    assert info["valid_samples"] > 10_000
    r = np.linalg.norm(mesh.vertices, axis=1)
    # Orthographic samples of the front half of the sphere, in mm; the icosphere's flat
    # triangles lie inside the sphere by at most ~0.1 % of the radius at this subdivision.
    assert np.all(r <= 80.0 + 1e-6) and np.all(r > 79.0)
    assert mesh.grid_index is not None and len(mesh.grid_index) == mesh.n_vertices


def test_the_same_seed_gives_the_same_scan_and_artifacts_change_it(ball):
    a, _ = bipolar.scan(ball, pitch=1.0, artifacts="structured-light", seed=3)
    b, _ = bipolar.scan(ball, pitch=1.0, artifacts="structured-light", seed=3)
    c, _ = bipolar.scan(ball, pitch=1.0, artifacts="none", seed=3)
    np.testing.assert_array_equal(a.vertices, b.vertices)
    assert a.n_vertices != c.n_vertices or not np.array_equal(a.vertices, c.vertices)


def test_clean_crops_around_the_centre_and_reports_units(ball):
    noisy, _ = bipolar.scan(ball, pitch=1.0, artifacts="structured-light", seed=1)
    centre = np.array([0.0, 0.0, 80.0])
    out, report = bipolar.clean(noisy, crop_center=centre, crop_radius=50.0)
    assert report["units"] == "mm"
    assert report["output_vertices"] == out.n_vertices > 1000
    assert np.all(np.linalg.norm(out.vertices - centre, axis=1) <= 50.0 + 1e-9)
    assert isinstance(report["summary"], list) and report["summary"]


def test_bad_input_is_a_clear_error(ball):
    with pytest.raises(errors.InputError, match="artifacts"):
        bipolar.scan(ball, artifacts="laser")
    with pytest.raises(errors.InputError, match="unit"):
        bipolar.scan(ball, units="furlong")
    with pytest.raises(errors.InputError):
        bipolar.scan(ball, pitch=-1.0)
    with pytest.raises(errors.InputError, match="units"):
        bipolar.clean(bipolar.icosphere(2))  # 3.5 units across: no face in any unit


def test_visible_faces_are_the_front_within_the_incidence_limit(ball):
    toward = np.array([0.3, -0.2, 1.0])
    seen = bipolar.visible_faces(ball, toward, max_incidence=60.0)
    assert seen.dtype == np.bool_ and seen.shape == (ball.triangles.shape[0],)
    # A convex ball hides nothing from itself: the faces' incidence alone decides.
    v = ball.vertices[ball.triangles]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    cos = n @ (toward / np.linalg.norm(toward)) / np.linalg.norm(n, axis=1)
    decided = np.abs(cos - np.cos(np.radians(60.0))) > 1e-9
    np.testing.assert_array_equal(seen[decided], (cos >= np.cos(np.radians(60.0)))[decided])


def test_a_turned_scan_hides_the_far_side_of_a_bump():
    # A plane with a tall bump seen from 60 degrees: part of the plane behind the bump is hidden.
    g = bipolar.grid_plane(40, 1.0)
    x, y = g.vertices[:, 0] - 20.0, g.vertices[:, 1] - 20.0
    z = 15.0 * np.exp(-(x**2 + y**2) / 8.0)
    mesh = bipolar.Mesh(np.column_stack([g.vertices[:, 0], g.vertices[:, 1], z]), g.triangles)
    toward = np.array([np.sin(np.radians(60.0)), 0.0, np.cos(np.radians(60.0))])
    seen = bipolar.visible_faces(mesh, toward, max_incidence=89.0)
    cen = mesh.vertices[mesh.triangles].mean(axis=1)
    behind = (cen[:, 0] < 14.0) & (cen[:, 0] > 8.0) & (np.abs(cen[:, 1] - 20.0) < 1.0)
    front = cen[:, 0] > 30.0
    assert not seen[behind].any()
    assert seen[front].all()


def test_visible_faces_rejects_a_bad_direction(ball):
    with pytest.raises(errors.InputError, match="viewing direction"):
        bipolar.visible_faces(ball, [0.0, 0.0, 0.0])
    with pytest.raises(errors.InputError, match="incidence"):
        bipolar.visible_faces(ball, [0.0, 0.0, 1.0], max_incidence=120.0)
