"""Drop-in replacement for tvb-gdist (``import bipolar.gdist as gdist``).

Same functions, arguments, defaults, dtypes and return types as tvb-gdist 2.x, computed with
bipolar's exact polyhedral geodesics (the VTP-S window propagation of the Rust ``geodesic``
crate, which matches the MMP code tvb-gdist wraps to about 1e-14 relative):

* ``compute_gdist(vertices, triangles, source_indices=None, target_indices=None,
  max_distance=GEODESIC_INF, is_one_indexed=False)`` -> float64 array, one value per target;
* ``local_gdist_matrix(vertices, triangles, max_distance=GEODESIC_INF, is_one_indexed=False)``
  -> ``scipy.sparse.csc_matrix`` (N, N);
* ``distance_matrix_of_selected_points(vertices, triangles, points, max_distance=GEODESIC_INF,
  is_one_indexed=False)`` -> ``scipy.sparse.csc_matrix`` (N, N).

Differences: any real dtype is accepted for ``vertices`` and any integer dtype for the index
arrays (tvb-gdist requires float64 and int32); bad input raises ``bipolar.InputError`` (a
``ValueError``) naming the problem instead of crashing; ``local_gdist_matrix`` computes its rows
in parallel. Distances beyond ``max_distance`` are ``inf`` in ``compute_gdist`` (as in
tvb-gdist) and absent from the sparse matrices.
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from . import _bipolar
from .errors import IndexOutOfRangeError, InputError

__all__ = [
    "GEODESIC_INF",
    "compute_gdist",
    "distance_matrix_of_selected_points",
    "local_gdist_matrix",
]

#: tvb-gdist's "no limit" value of ``max_distance``.
GEODESIC_INF = 1e100


def _solver(vertices: Any, triangles: Any, is_one_indexed: bool) -> _bipolar.GeodesicSolver:
    tri = np.asarray(triangles)
    if is_one_indexed:
        if tri.dtype.kind not in "iu":
            raise _type_error("triangles", tri)
        tri = tri.astype(np.int64) - 1
    mesh = _bipolar.Mesh(vertices, tri)
    return _bipolar.GeodesicSolver(mesh, "exact")


def _type_error(what: str, a: np.ndarray) -> Exception:
    from .errors import InputTypeError

    return InputTypeError(f"{what} must be an array of integers, got dtype {a.dtype}")


def _indices(x: Any, what: str, n: int, is_one_indexed: bool) -> np.ndarray:
    a = np.asarray(x)
    if a.dtype.kind not in "iu":
        raise _type_error(what, a)
    a = a.astype(np.int64).ravel()
    if is_one_indexed:
        a = a - 1
    bad = (a < 0) | (a >= n)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        shown = int(a[k]) + (1 if is_one_indexed else 0)
        raise IndexOutOfRangeError(
            f"{what}[{k}] = {shown} is out of range (the mesh has {n} vertices"
            + (", indices from 1)" if is_one_indexed else ")")
        )
    return a


def _cutoff(max_distance: float) -> Optional[float]:
    m = float(max_distance)
    if np.isnan(m) or m <= 0:
        raise InputError(f"max_distance must be positive, got {max_distance}")
    return None if m >= GEODESIC_INF else m


def compute_gdist(
    vertices: Any,
    triangles: Any,
    source_indices: Any = None,
    target_indices: Any = None,
    max_distance: float = GEODESIC_INF,
    is_one_indexed: bool = False,
) -> np.ndarray:
    """Geodesic distance from the nearest source vertex to each target vertex.

    ``vertices`` (N, 3), ``triangles`` (M, 3); ``source_indices`` default ``[0]``;
    ``target_indices`` default: every vertex. Returns float64 (len(targets),); ``inf`` for
    targets farther than ``max_distance`` or unreachable.
    """
    solver = _solver(vertices, triangles, is_one_indexed)
    n = solver.n_vertices
    src = (
        np.zeros(1, dtype=np.int64)
        if source_indices is None
        else _indices(source_indices, "source_indices", n, is_one_indexed)
    )
    d = solver.distances(src, max_distance=_cutoff(max_distance))
    if target_indices is None:
        return d
    tgt = _indices(target_indices, "target_indices", n, is_one_indexed)
    return d[tgt]


def local_gdist_matrix(
    vertices: Any,
    triangles: Any,
    max_distance: float = GEODESIC_INF,
    is_one_indexed: bool = False,
) -> Any:
    """Sparse (N, N) matrix of the geodesic distances from every vertex to the vertices within
    ``max_distance`` of it (``scipy.sparse.csc_matrix``, float64; zero distances not stored).
    Row k holds the distances from vertex k."""
    import scipy.sparse

    solver = _solver(vertices, triangles, is_one_indexed)
    n = solver.n_vertices
    indptr, indices, data = solver.sparse_distances(
        np.arange(n, dtype=np.int64), max_distance=_cutoff(max_distance)
    )
    return scipy.sparse.csr_matrix((data, indices, indptr), shape=(n, n)).tocsc()


def distance_matrix_of_selected_points(
    vertices: Any,
    triangles: Any,
    points: Any,
    max_distance: float = GEODESIC_INF,
    is_one_indexed: bool = False,
) -> Any:
    """Sparse (N, N) matrix of the pairwise geodesic distances among the vertices ``points``
    (both (i, j) and (j, i) stored; ``inf`` beyond ``max_distance``), ``scipy.sparse.csc_matrix``."""
    import scipy.sparse

    solver = _solver(vertices, triangles, is_one_indexed)
    n = solver.n_vertices
    pts = _indices(points, "points", n, is_one_indexed)
    cut = _cutoff(max_distance)
    rows, cols, vals = [], [], []
    # Fields 64 sources at a time (in parallel), so memory stays 64 x N whatever len(points).
    for start in range(0, max(len(pts) - 1, 0), 64):
        chunk = pts[start : min(start + 64, len(pts) - 1)]
        fields = solver.distances_many([[int(p)] for p in chunk], max_distance=cut)
        for k, p in enumerate(chunk):
            tgt = pts[start + k + 1 :]
            d = fields[k, tgt]
            rows.extend([np.full(len(tgt), p), tgt])
            cols.extend([tgt, np.full(len(tgt), p)])
            vals.extend([d, d])
    r = np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)
    c = np.concatenate(cols) if cols else np.zeros(0, dtype=np.int64)
    v = np.concatenate(vals) if vals else np.zeros(0)
    return scipy.sparse.csc_matrix((v, (r, c)), shape=(n, n))
