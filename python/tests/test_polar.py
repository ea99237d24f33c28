"""The single-pole (geodesic polar) descriptor from Python."""

import numpy as np
import pytest

import bipolar
from bipolar import errors

from conftest import rotation


@pytest.fixture(scope="module")
def plane():
    # 41 x 41 unjittered grid of spacing 0.05 centred on the origin; vertex 840 is the centre.
    return bipolar.grid_plane(41, 0.05, -1.0)


def test_plane_points_lie_on_circles_at_their_angles(plane):
    centre = int(np.argmin(np.linalg.norm(plane.vertices, axis=1)))
    p0 = plane.vertices[centre]
    d = bipolar.describe_polar(plane, centre, (p0[0] + 1.0, p0[1], p0[2]), step=0.1, levels=5, sectors=8)
    n = len(d)
    assert n == 5 * 8
    assert d.points.shape == (n, 3) and d.keys.dtype == np.uint64
    assert (d.step, d.n_levels, d.n_sectors) == (0.1, 5, 8)
    r = np.linalg.norm(d.points - p0, axis=1)
    np.testing.assert_allclose(r, 0.1 * d.levels, rtol=1e-9)
    angle = np.arctan2(d.points[:, 1] - p0[1], d.points[:, 0] - p0[0]) % (2 * np.pi)
    expected = 2 * np.pi * d.sectors / 8
    diff = np.angle(np.exp(1j * (angle - expected)))
    np.testing.assert_allclose(diff, 0.0, atol=1e-9)
    np.testing.assert_allclose(plane.surface_positions(d.faces, d.bary), d.points, atol=1e-12)
    assert {bipolar.unpack_polar_key(int(k)) for k in d.keys} == {
        (int(a), int(b)) for a, b in zip(d.levels, d.sectors)
    }


def test_rigid_copy_is_at_zero_and_a_bent_one_is_not(bump_mesh):
    towards = bump_mesh.vertices[1599]
    a = bipolar.describe_polar(bump_mesh, 820, towards, step=0.15, levels=4, sectors=12)
    r, t = rotation(7), np.array([1.0, -2.0, 0.5])
    moved = bipolar.Mesh(bump_mesh.vertices @ r.T + t, bump_mesh.triangles)
    b = bipolar.describe_polar(moved, 820, towards @ r.T + t, step=0.15, levels=4, sectors=12)
    np.testing.assert_array_equal(a.keys, b.keys)
    assert bipolar.polar_distance(a, b) < 1e-9
    v = bump_mesh.vertices.copy()
    v[:, 2] *= 1.8
    c = bipolar.describe_polar(bipolar.Mesh(v, bump_mesh.triangles), 820, towards, step=0.15, levels=4, sectors=12)
    assert bipolar.polar_distance(a, c) > 1e-3


def test_prepared_solver_gives_the_same_descriptor(bump_mesh):
    s = bipolar.GeodesicSolver(bump_mesh, "exact")
    towards = bump_mesh.vertices[1599]
    a = bipolar.describe_polar(bump_mesh, 820, towards, step=0.15, levels=3, sectors=6)
    b = bipolar.describe_polar(bump_mesh, 820, towards, step=0.15, levels=3, sectors=6, solver=s)
    np.testing.assert_array_equal(a.points, b.points)


def test_bad_input_is_a_clear_error(plane):
    with pytest.raises(errors.InputError):
        bipolar.describe_polar(plane, 840, (1.0, 0.0, 0.0), step=-0.1)
    with pytest.raises(errors.InputError):
        bipolar.describe_polar(plane, 840, (1.0, 0.0, 0.0), step=0.1, sectors=0)
    with pytest.raises(errors.IndexOutOfRangeError):
        bipolar.describe_polar(plane, 10**6, (1.0, 0.0, 0.0), step=0.1)
    with pytest.raises(errors.InputError):
        bipolar.describe_polar(plane, 840, (1.0, 0.0, 0.0), step=0.1, method="nope")
    with pytest.raises(errors.InputError):
        bipolar.unpack_polar_key(16)


def test_towards_may_be_a_point_off_the_surface(plane):
    centre = int(np.argmin(np.linalg.norm(plane.vertices, axis=1)))
    p0 = plane.vertices[centre]
    above = bipolar.describe_polar(plane, centre, (p0[0] + 1.0, p0[1], p0[2] + 5.0), step=0.1, levels=2, sectors=4)
    on = bipolar.describe_polar(plane, centre, (p0[0] + 1.0, p0[1], p0[2]), step=0.1, levels=2, sectors=4)
    # The direction is projected on the tangent plane: the same rays.
    np.testing.assert_allclose(above.points, on.points, atol=1e-12)
