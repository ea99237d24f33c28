"""Shared fixtures: generated meshes and the shared data folder (../shared or $BIPOLAR_SHARED)."""

import os
import pathlib

import numpy as np
import pytest

import bipolar

ROOT = pathlib.Path(__file__).resolve().parents[2]


def shared_dir():
    p = os.environ.get("BIPOLAR_SHARED")
    return pathlib.Path(p) if p else ROOT.parent / "shared"


PAPER_SET = shared_dir() / "faces" / "ict-facekit" / "paper-set"


def shared_required():
    """Whether BIPOLAR_REQUIRE_SHARED (set by CI) makes missing shared data a failure."""
    return os.environ.get("BIPOLAR_REQUIRE_SHARED", "") not in ("", "0")


def paper_face(name):
    """PAPER_SET / name; without it the calling test skips, or fails when shared_required()."""
    p = PAPER_SET / name
    if not p.exists():
        if shared_required():
            pytest.fail(f"shared data absent: {p}, and BIPOLAR_REQUIRE_SHARED is set")
        pytest.skip(f"shared data absent: {p}")
    return p


@pytest.fixture(scope="session")
def face_path():
    return paper_face("id1_neutral.obj")


@pytest.fixture(scope="session")
def face(face_path):
    return bipolar.read_mesh(face_path)


def bump(n=40, h=0.05, jitter=0.3, seed=3):
    """A jittered grid bent into a smooth asymmetric bump (no symmetry, so descriptors of
    rigid copies can only match if the descriptor is invariant)."""
    g = bipolar.grid_plane(n, h, -0.5 * n * h, jitter, seed)
    v = g.vertices.copy()
    x, y = v[:, 0], v[:, 1]
    v[:, 2] = 0.4 * np.exp(-((x - 0.1) ** 2 + (y + 0.2) ** 2) / 0.3) + 0.1 * x * y
    return bipolar.Mesh(v, g.triangles)


@pytest.fixture(scope="session")
def bump_mesh():
    return bump()


def rotation(seed=1):
    rng = np.random.default_rng(seed)
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


@pytest.fixture(scope="session")
def client():
    """A Dask client on a LocalCluster of two worker processes, shared by the Dask tests."""
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()
