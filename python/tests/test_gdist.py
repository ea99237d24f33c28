"""bipolar.gdist beyond tvb-gdist's own suite (which scripts/test-python runs unmodified)."""

import numpy as np
import pytest
import scipy.sparse

import bipolar
from bipolar import errors
from bipolar import gdist


@pytest.fixture(scope="module")
def grid():
    m = bipolar.grid_plane(12, 0.1, 0.0, 0.2, 5)
    return m.vertices, m.triangles.astype(np.int32)


def test_compute_gdist_matches_straight_lines(grid):
    v, t = grid
    d = gdist.compute_gdist(v, t, np.array([3], dtype=np.int32))
    np.testing.assert_allclose(d, np.linalg.norm(v - v[3], axis=1), atol=1e-12)
    assert d.dtype == np.float64
    sub = gdist.compute_gdist(v, t, np.array([3], np.int32), np.array([0, 7], np.int32))
    np.testing.assert_array_equal(sub, d[[0, 7]])
    default = gdist.compute_gdist(v, t)
    np.testing.assert_array_equal(default, gdist.compute_gdist(v, t, np.array([0], np.int32)))
    cut = gdist.compute_gdist(v, t, np.array([3], np.int32), max_distance=0.3)
    assert np.all(np.isinf(cut[d > 0.3 + 1e-12])) and np.array_equal(cut[d <= 0.3], d[d <= 0.3])


def test_one_indexed_equals_zero_indexed(grid):
    v, t = grid
    a = gdist.compute_gdist(v, t, np.array([4], np.int32), np.array([9], np.int32))
    b = gdist.compute_gdist(
        v, t + 1, np.array([5], np.int32), np.array([10], np.int32), is_one_indexed=True
    )
    assert a == b


def test_local_matrix_is_sparse_and_symmetric(grid):
    v, t = grid
    m = gdist.local_gdist_matrix(v, t, 0.35)
    assert type(m) is scipy.sparse.csc_matrix and m.shape == (len(v), len(v))
    assert m.max() <= 0.35
    dense = m.toarray()
    np.testing.assert_allclose(dense, dense.T, atol=1e-12)
    row = gdist.compute_gdist(v, t, np.array([11], np.int32))
    keep = (row > 0) & (row <= 0.35)
    np.testing.assert_array_equal(dense[11, keep], row[keep])
    assert np.all(dense[11, ~keep] == 0)


def test_selected_points(grid):
    v, t = grid
    pts = np.array([2, 30, 77], dtype=np.int32)
    m = gdist.distance_matrix_of_selected_points(v, t, pts)
    assert type(m) is scipy.sparse.csc_matrix and m.nnz == 6
    np.testing.assert_allclose(m[2, 30], np.linalg.norm(v[2] - v[30]), atol=1e-12)


def test_bad_input_is_a_clear_error(grid):
    v, t = grid
    with pytest.raises(errors.IndexOutOfRangeError, match="source_indices"):
        gdist.compute_gdist(v, t, np.array([len(v)], np.int32))
    with pytest.raises(IndexError, match="target_indices"):
        gdist.compute_gdist(v, t, np.array([0], np.int32), np.array([-1], np.int32))
    with pytest.raises(TypeError):
        gdist.compute_gdist(v, t.astype(np.float64))
    with pytest.raises(ValueError):
        gdist.compute_gdist(v[:, :2], t)
    with pytest.raises(ValueError, match="max_distance"):
        gdist.local_gdist_matrix(v, t, -1.0)
    with pytest.raises(IndexError):
        gdist.compute_gdist(v, t, is_one_indexed=True)  # index 0 in 1-indexed triangles
