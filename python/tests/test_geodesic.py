import sys
import threading

import numpy as np
import pytest

import bipolar
from bipolar import errors

METHODS = ["exact", "fmm", "heat", "dijkstra"]


@pytest.fixture(scope="module")
def flat():
    return bipolar.grid_plane(30, 0.1, 0.0, 0.3, 7)


@pytest.mark.parametrize("method", METHODS)
def test_every_method_on_a_flat_grid(flat, method):
    s = bipolar.GeodesicSolver(flat, method)
    assert s.method == method and s.n_vertices == flat.n_vertices
    d = s.distances(0)
    assert d.shape == (flat.n_vertices,) and d.dtype == np.float64
    euclid = np.linalg.norm(flat.vertices - flat.vertices[0], axis=1)
    if method == "exact":
        # On a flat (convex) grid the exact geodesic distance is the straight line.
        np.testing.assert_allclose(d, euclid, rtol=1e-12, atol=1e-12)
    elif method == "dijkstra":
        assert np.all(d >= euclid - 1e-12)
    else:
        assert np.max(np.abs(d - euclid)) < 0.05 * euclid.max()


def test_exact_on_the_sphere_converges_to_the_great_circle():
    m = bipolar.icosphere(4)
    d = bipolar.GeodesicSolver(m, "exact").distances(0)
    u = m.vertices / np.linalg.norm(m.vertices, axis=1, keepdims=True)
    g = np.arccos(np.clip(u @ u[0], -1, 1))
    # The polyhedron lies inside the sphere: an O(h^2) gap, not solver error.
    assert np.max(np.abs(d - g)) < 3e-3
    assert np.all(d <= g + 1e-12)


def test_surface_point_source_at_a_vertex_equals_the_vertex_source(flat):
    s = bipolar.GeodesicSolver(flat, "exact")
    t = flat.triangles
    f = int(np.flatnonzero((t == 50).any(axis=1))[0])
    bary = np.zeros((1, 3))
    bary[0, list(t[f]).index(50)] = 1.0
    dp = s.distances(faces=[f], bary=bary)
    dv = s.distances(50)
    np.testing.assert_allclose(dp, dv, rtol=1e-12, atol=1e-12)
    # Mid-face source: exact distance is the straight line on the flat grid.
    b = np.array([[0.2, 0.3, 0.5]])
    p = flat.surface_positions([f], b)[0]
    d = s.distances(faces=[f], bary=b)
    np.testing.assert_allclose(d, np.linalg.norm(flat.vertices - p, axis=1), atol=1e-12)


def test_several_sources_take_the_minimum(flat):
    s = bipolar.GeodesicSolver(flat, "exact")
    d = s.distances(np.array([0, 400]))
    np.testing.assert_array_equal(d, np.minimum(s.distances(0), s.distances(400)))


@pytest.mark.parametrize("method", METHODS)
def test_cutoff_keeps_values_within_it(flat, method):
    s = bipolar.GeodesicSolver(flat, method)
    full = s.distances(10)
    cut = s.distances(10, max_distance=1.0)
    inside = full <= 1.0
    np.testing.assert_array_equal(cut[inside], full[inside])
    assert np.all(np.isinf(cut[full > 1.0 + 1e-9]))


def test_distances_many_equals_one_by_one(flat):
    s = bipolar.GeodesicSolver(flat, "exact")
    many = s.distances_many([0, [5, 9], 200], threads=2)
    assert many.shape == (3, flat.n_vertices)
    np.testing.assert_array_equal(many[0], s.distances(0))
    np.testing.assert_array_equal(many[1], s.distances([5, 9]))
    np.testing.assert_array_equal(many[2], s.distances(200))


def test_sparse_distances_are_the_finite_nonzero_entries(flat):
    s = bipolar.GeodesicSolver(flat, "exact")
    indptr, indices, data = s.sparse_distances([3, 7], max_distance=0.5)
    for r, v in enumerate([3, 7]):
        full = s.distances(v)
        keep = np.flatnonzero((full > 0) & (full <= 0.5))
        np.testing.assert_array_equal(indices[indptr[r] : indptr[r + 1]], keep)
        np.testing.assert_array_equal(data[indptr[r] : indptr[r + 1]], full[keep])


def progress_during(call):
    """Iterations a Python thread completes while ``call()`` runs in this thread.

    Each iteration needs the GIL and gives it up between iterations (a short wait), and the
    switch interval is raised far beyond the test's length, so the interpreter never takes the
    GIL from the thread holding it: the counter advances only while ``call`` has released the
    GIL itself. No clock is compared: a call that holds the GIL throughout gives exactly 0.
    """
    count = [0]
    stop = threading.Event()

    def counter():
        while not stop.wait(0.0001):
            count[0] += 1

    old = sys.getswitchinterval()
    sys.setswitchinterval(1000.0)
    th = threading.Thread(target=counter)
    try:
        th.start()
        before = count[0]
        call()
        after = count[0]
    finally:
        stop.set()
        th.join()
        sys.setswitchinterval(old)
    return after - before


def test_the_gil_is_released_while_solving():
    m = bipolar.icosphere(6)
    s = bipolar.GeodesicSolver(m, "exact")
    # The control: Python work holds the GIL, and the counter cannot move.
    assert progress_during(lambda: sum(range(3_000_000))) == 0
    # The solve (about a second on ico6) lets the counter run while it works.
    assert progress_during(lambda: s.distances(0)) > 0


def test_bad_sources_and_options(flat):
    s = bipolar.GeodesicSolver(flat, "exact")
    n = flat.n_vertices
    with pytest.raises(errors.IndexOutOfRangeError, match=f"source vertex {n} does not exist"):
        s.distances(n)
    with pytest.raises(IndexError, match="not a valid index"):
        s.distances(-1)
    with pytest.raises(TypeError, match="integers"):
        s.distances(np.array([1.0]))
    with pytest.raises(errors.InputError, match="no source"):
        s.distances(np.zeros(0, dtype=np.int64))
    with pytest.raises(errors.InputError, match="invalid max_distance"):
        s.distances(0, max_distance=float("nan"))
    with pytest.raises(errors.InputError, match="invalid max_distance"):
        s.distances(0, max_distance=-1.0)
    with pytest.raises(errors.InputError, match="together"):
        s.distances(faces=[0])
    with pytest.raises(errors.IndexOutOfRangeError):
        s.distances(faces=[10**6], bary=[[1.0, 0.0, 0.0]])
    with pytest.raises(errors.InputError, match="barycentric"):
        s.distances(faces=[0], bary=[[np.nan, 0.5, 0.5]])
    with pytest.raises(errors.InputError, match="unknown geodesic method"):
        bipolar.GeodesicSolver(flat, "magic")
    with pytest.raises(errors.InputError, match="threads"):
        s.distances_many([0], threads=0)
