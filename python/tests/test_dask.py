"""bipolar.dask on a LocalCluster of two worker processes: results identical to one process."""

import numpy as np
import pytest

import bipolar

distributed = pytest.importorskip("distributed")
bdask = pytest.importorskip("bipolar.dask")

from conftest import bump, rotation  # noqa: E402


@pytest.fixture(scope="module")
def mesh_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("meshes")
    paths = []
    for k in range(4):
        m = bump(n=24, seed=10 + k)
        r = rotation(k)
        m = bipolar.Mesh(m.vertices @ r.T, m.triangles)
        p = d / f"m{k}.ply"
        bipolar.write_mesh(p, m)
        paths.append(p)
    return paths


@pytest.fixture(scope="module")
def descriptors():
    rng = np.random.default_rng(0)
    base = rng.normal(size=(120, 3))
    keys = np.arange(120, dtype=np.uint64) * np.uint64(16)
    out = []
    for k in range(11):
        pts = base + rng.normal(scale=0.02 * (1 + k % 4), size=base.shape)
        keep = rng.random(120) > 0.1
        out.append(bipolar.Descriptor.from_arrays(pts[keep] @ rotation(k).T, keys[keep]))
    return out


def test_cluster_has_two_worker_processes(client):
    info = client.scheduler_info()
    assert len(info["workers"]) == 2
    pids = set(client.run(lambda: __import__("os").getpid()).values())
    assert len(pids) == 2


def test_describe_files_equals_single_process(client, mesh_files):
    got = bdask.describe_files(mesh_files, 0, 575, client=client, levels=8)
    want = [bipolar.describe(p, 0, 575, levels=8) for p in mesh_files]
    assert len(got) == 4
    for g, w in zip(got, want):
        assert g == w and len(g) > 0


@pytest.mark.parametrize("block_size", [1, 3, 4, 11, 50])
def test_block_matrix_equals_single_process(client, descriptors, block_size):
    want = bipolar.distance_matrix(descriptors)
    got = bdask.distance_matrix(descriptors, client=client, block_size=block_size)
    np.testing.assert_array_equal(got, want)


def test_block_matrix_icp_mode_and_default_blocks(client, descriptors):
    o = bipolar.DistanceOptions(mode="icp", iterations=20)
    want = bipolar.distance_matrix(descriptors[:5], o)
    np.testing.assert_array_equal(bdask.distance_matrix(descriptors[:5], o, client=client), want)
    assert bdask.distance_matrix([], client=client).shape == (0, 0)


def test_identify_ranks_the_gallery(client, descriptors):
    probes, gallery = descriptors[:4], descriptors[4:]
    labels_g = [k % 4 for k in range(4, 11)]
    res = bdask.identify(
        probes, gallery, client=client, block_size=2,
        probe_labels=[0, 1, 2, 3], gallery_labels=labels_g,
    )
    want = bipolar.cross_distances(probes, gallery)
    np.testing.assert_array_equal(res.distances, want)
    np.testing.assert_array_equal(res.ranking, np.argsort(want, axis=1, kind="stable"))
    np.testing.assert_array_equal(res.best, np.argmin(want, axis=1))
    # The rank of probe i: 1 + the gallery entries before its nearest same-label entry j
    # (closer, or as close and earlier in the gallery).
    want_ranks = []
    for i in range(4):
        j = min((g for g in range(7) if labels_g[g] == i), key=lambda g: (want[i, g], g))
        want_ranks.append(1 + sum(1 for g in range(7) if (want[i, g], g) < (want[i, j], j)))
    # All eleven descriptors are noisy copies of one point set, the noise growing with the
    # label, so every probe is nearest the least noisy entries: ranks from best to worst.
    assert want_ranks == [1, 3, 5, 7]
    np.testing.assert_array_equal(res.ranks, want_ranks)
    assert res.rank1_rate == 0.25


def test_identify_takes_the_least_over_a_probes_list(client, descriptors):
    # Probe 0 is a list of three descriptors, probe 1 a single one, probe 2 an empty list.
    lists = [descriptors[0:3], descriptors[3], []]
    gallery = descriptors[4:]
    res = bdask.identify(lists, gallery, client=client, block_size=2)
    whole = bipolar.cross_distances(descriptors[:4], gallery)
    np.testing.assert_array_equal(res.distances[0], whole[0:3].min(axis=0))
    np.testing.assert_array_equal(res.distances[1], whole[3])
    assert np.all(np.isnan(res.distances[2]))
    assert res.distances.shape == (3, len(gallery))
    np.testing.assert_array_equal(res.best[:2], np.argmin(res.distances[:2], axis=1))


def test_bad_block_size(client, descriptors):
    with pytest.raises(bipolar.InputError, match="block_size"):
        bdask.distance_matrix(descriptors, client=client, block_size=0)
