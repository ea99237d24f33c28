import pickle

import numpy as np
import pytest

import bipolar
from bipolar import errors

from conftest import rotation


def random_set(n, seed, nkeys=None):
    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(n, 3)) * np.array([3.0, 2.0, 1.0])
    # Multiples of 16 are valid packed keys (side and sign fields zero).
    keys = rng.permutation(nkeys or 2 * n)[:n].astype(np.uint64) * np.uint64(16)
    return pts, keys


@pytest.fixture(scope="module")
def sets():
    base, keys = random_set(300, 1)
    out = []
    for k in range(6):
        r = rotation(10 + k)
        noise = np.random.default_rng(100 + k).normal(scale=0.05 * k, size=base.shape)
        out.append(bipolar.Descriptor.from_arrays((base + noise) @ r.T + k, keys))
    return out


def test_keyed_distance_of_a_rigid_copy_is_zero(sets):
    assert bipolar.distance(sets[0], sets[0]) == pytest.approx(0.0, abs=1e-12)
    det = bipolar.distance_details(sets[0], sets[1])
    assert det["mode"] == "keys" and det["shared_keys"] == 300
    assert 0.0 < det["distance"] < 0.05
    r = np.asarray(det["rotation"])
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)


def test_icp_and_hausdorff_modes(sets):
    for mode in ["icp", "hausdorff"]:
        d0 = bipolar.distance(sets[0], sets[0], mode=mode)
        assert d0 == pytest.approx(0.0, abs=1e-9)
        d = bipolar.distance(sets[0], sets[2], mode=mode, variant="point")
        assert 0.0 < d < 0.2
        det = bipolar.distance_details(sets[0], sets[2], mode=mode)
        assert det["distance"] == d and det["mode"] == mode


def test_options_object_and_keywords_agree(sets):
    o = bipolar.DistanceOptions(robust="huber", gate=1.0)
    assert bipolar.distance(sets[0], sets[3], o) == bipolar.distance(
        sets[0], sets[3], robust="huber", gate=1.0
    )
    assert pickle.loads(pickle.dumps(o)).as_dict() == o.as_dict()
    with pytest.raises(errors.InputError, match="not both"):
        bipolar.distance(sets[0], sets[1], o, mode="icp")


def test_matrix_equals_pairwise_calls(sets):
    for kw in [dict(), dict(mode="icp", iterations=30)]:
        m = bipolar.distance_matrix(sets, **kw)
        assert m.shape == (6, 6)
        np.testing.assert_array_equal(m, m.T)
        np.testing.assert_array_equal(np.diag(m), 0.0)
        for i in range(6):
            for j in range(i + 1, 6):
                assert m[i, j] == bipolar.distance(sets[i], sets[j], **kw)
        np.testing.assert_array_equal(bipolar.distance_matrix(sets, threads=1, **kw), m)
    c = bipolar.cross_distances(sets[:2], sets, threads=2)
    assert c.shape == (2, 6)
    for i in range(2):
        for j in range(6):
            assert c[i, j] == bipolar.distance(sets[i], sets[j])


def test_ambiguous_points_are_dropped_unless_kept():
    pts, keys = random_set(50, 4)
    amb = np.zeros(50, dtype=bool)
    amb[:10] = True
    a = bipolar.Descriptor.from_arrays(pts, keys, ambiguous=amb)
    moved = pts.copy()
    moved[:10] += 5.0  # only the ambiguous points differ
    b = bipolar.Descriptor.from_arrays(moved, keys, ambiguous=amb)
    assert bipolar.distance(a, b) == pytest.approx(0.0, abs=1e-12)
    assert bipolar.distance(a, b, keep_ambiguous=True) > 0.1


def test_distance_bad_input(sets):
    pts, keys = random_set(10, 2)
    with pytest.raises(errors.InputError, match="unknown mode"):
        bipolar.distance(sets[0], sets[1], mode="l1")
    with pytest.raises(errors.InputError, match="usable shared keys"):
        other = bipolar.Descriptor.from_arrays(pts, keys + np.uint64(16 * 10**6))
        bipolar.distance(sets[0], other)
    with pytest.raises(errors.InputError, match="keys has 9 entries"):
        bipolar.Descriptor.from_arrays(pts, keys[:9])
    with pytest.raises(errors.InputError, match="not finite"):
        bad = pts.copy()
        bad[3, 0] = np.nan
        bipolar.Descriptor.from_arrays(bad, keys)
    with pytest.raises(TypeError):
        bipolar.Descriptor.from_arrays(pts, keys.astype(np.float64))
    with pytest.raises(errors.InputError, match="negative"):
        bipolar.Descriptor.from_arrays(pts, -np.arange(10))
    with pytest.raises(errors.InputError, match="not a packed bipolar key"):
        bipolar.Descriptor.from_arrays(pts, np.arange(10) * 16 + 3)
    with pytest.raises(TypeError, match="not a bipolar.Descriptor"):
        bipolar.distance_matrix([sets[0], "x"])
    with pytest.raises(errors.InputError, match="empty"):
        e = bipolar.Descriptor.from_arrays(np.zeros((0, 3)), np.zeros(0, dtype=np.uint64))
        bipolar.distance(e, sets[0], mode="icp")
    with pytest.raises(TypeError):
        bipolar.distance(sets[0], 3)
