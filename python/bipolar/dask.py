"""bipolar on a dask.distributed cluster: many files, big matrices, 1:N identification.

* :func:`describe_files` describes a list of mesh files, one task per file.
* :func:`distance_matrix` computes the N x N distance matrix in square blocks: the descriptors
  are scattered to the workers once per block, each task computes one block with the Rust
  library (``bipolar.cross_distances``, or ``bipolar.distance_matrix`` on the diagonal), and the
  blocks are assembled on the client.
* :func:`identify` ranks a gallery for each probe (1:N identification) from the P x G block
  matrix.
* :func:`identify_templates` is face identification with templates (``bipolar.Gallery``):
  the gallery cut into shards of templates, one task per probe and shard, the shards'
  rankings merged on the client into ``Gallery.identify``'s ranking of the whole gallery.

Results are identical to the single-process calls (``bipolar.describe``,
``bipolar.distance_matrix``, ``bipolar.cross_distances``, ``bipolar.Gallery.identify``): each entry is computed by the same
deterministic library function on the same inputs, whatever the block size or the number of
workers. Tasks use ``threads_per_task`` rayon threads (default 1: one task per worker thread
keeps the cores busy without oversubscription).

``client`` is a ``distributed.Client``; when omitted, the current default client
(``distributed.default_client()``) is used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _bipolar

__all__ = [
    "describe_files",
    "distance_matrix",
    "identify",
    "identify_templates",
    "rank",
    "Identification",
    "blocks",
]


def _client(client: Any) -> Any:
    if client is not None:
        return client
    from distributed import default_client

    return default_client()


def _describe_one(path: str, ref_a: Any, ref_b: Any, kwargs: dict) -> _bipolar.Descriptor:
    return _bipolar.describe(path, ref_a, ref_b, **kwargs)


def describe_files(
    paths: Sequence[Any],
    ref_a: Any,
    ref_b: Any,
    *,
    client: Any = None,
    gather: bool = True,
    **describe_kwargs: Any,
) -> List[Any]:
    """``bipolar.describe(path, ref_a, ref_b, **describe_kwargs)`` for every path, one task per
    file. Returns the descriptors in the order of ``paths`` (or their futures with
    ``gather=False``). Paths are read by the workers, so they must see the same files."""
    c = _client(client)
    futures = [
        c.submit(_describe_one, str(p), ref_a, ref_b, describe_kwargs, pure=False)
        for p in paths
    ]
    return c.gather(futures) if gather else futures


def blocks(n: int, block_size: int) -> List[Tuple[int, int]]:
    """The ``(start, stop)`` ranges that cut ``range(n)`` into blocks of ``block_size``."""
    if block_size < 1:
        raise _bipolar_input(f"block_size must be at least 1, got {block_size}")
    return [(s, min(s + block_size, n)) for s in range(0, n, block_size)]


def _bipolar_input(msg: str) -> Exception:
    from .errors import InputError

    return InputError(msg)


def _diag_block(items: list, options: Any, threads: Optional[int]) -> np.ndarray:
    return _bipolar.distance_matrix(items, options, threads=threads)


def _cross_block(rows: list, cols: list, options: Any, threads: Optional[int]) -> np.ndarray:
    return _bipolar.cross_distances(rows, cols, options, threads=threads)


def _options(options: Any, kwargs: dict) -> Any:
    if options is not None and kwargs:
        raise _bipolar_input("give either options=DistanceOptions(...) or keyword options, not both")
    return options if options is not None else _bipolar.DistanceOptions(**kwargs)


def _default_block(n: int, client: Any) -> int:
    try:
        workers = max(1, sum(client.nthreads().values()))
    except Exception:  # pragma: no cover - depends on the cluster
        workers = 1
    # About 4 block rows per worker thread, so the ~n_blocks^2 / 2 tasks balance well.
    return max(1, math.ceil(n / (4 * workers)))


def distance_matrix(
    descriptors: Sequence[_bipolar.Descriptor],
    options: Any = None,
    *,
    client: Any = None,
    block_size: Optional[int] = None,
    threads_per_task: Optional[int] = 1,
    **kwargs: Any,
) -> np.ndarray:
    """The symmetric N x N distance matrix of ``descriptors`` (zero diagonal), computed in
    blocks of ``block_size`` descriptors on the cluster; equal to
    ``bipolar.distance_matrix(descriptors, options)``. Options as ``bipolar.DistanceOptions``
    (or its keyword arguments)."""
    c = _client(client)
    opts = _options(options, kwargs)
    items = list(descriptors)
    n = len(items)
    out = np.zeros((n, n))
    if n == 0:
        return out
    bs = block_size if block_size is not None else _default_block(n, c)
    ranges = blocks(n, bs)
    scattered = [c.scatter([items[s:e]], hash=False)[0] for s, e in ranges]
    tasks = {}
    for bi, (si, ei) in enumerate(ranges):
        tasks[(bi, bi)] = c.submit(_diag_block, scattered[bi], opts, threads_per_task, pure=False)
        for bj in range(bi + 1, len(ranges)):
            tasks[(bi, bj)] = c.submit(
                _cross_block, scattered[bi], scattered[bj], opts, threads_per_task, pure=False
            )
    keys = list(tasks)
    values = c.gather([tasks[k] for k in keys])
    for (bi, bj), m in zip(keys, values):
        si, ei = ranges[bi]
        sj, ej = ranges[bj]
        out[si:ei, sj:ej] = m
        if bi != bj:
            out[sj:ej, si:ei] = m.T
    return out


@dataclass
class Identification:
    """Result of :func:`identify`.

    ``distances`` (P, G); ``ranking`` (P, G) gallery indices sorted by increasing distance
    (stable: ties keep gallery order); ``best`` (P,) = ``ranking[:, 0]``; ``best_distance`` (P,).
    With labels: ``ranks`` (P,) 1-based rank of the first gallery entry with the probe's label
    (0 when the label is absent from the gallery) and ``rank1_rate`` (share of probes whose
    best match has their label, over probes whose label is in the gallery).
    """

    distances: np.ndarray
    ranking: np.ndarray
    best: np.ndarray
    best_distance: np.ndarray
    ranks: Optional[np.ndarray] = None
    rank1_rate: Optional[float] = None


def identify(
    probes: Sequence[Union[_bipolar.Descriptor, Sequence[_bipolar.Descriptor]]],
    gallery: Sequence[_bipolar.Descriptor],
    options: Any = None,
    *,
    probe_labels: Optional[Sequence[Any]] = None,
    gallery_labels: Optional[Sequence[Any]] = None,
    client: Any = None,
    block_size: Optional[int] = None,
    threads_per_task: Optional[int] = 1,
    **kwargs: Any,
) -> Identification:
    """1:N identification: distances of every probe to every gallery descriptor, computed in
    blocks on the cluster (equal to ``bipolar.cross_distances(probes, gallery, options)``), and
    the gallery ranked for each probe. A probe may also be a list of descriptors (what
    ``bipolar.describe(..., search_radius=)`` returns): its distance to a gallery descriptor is
    then the least over the list (NaN where every one failed, or for an empty list)."""
    c = _client(client)
    opts = _options(options, kwargs)
    # Every probe's descriptors as rows, and the probe each row belongs to.
    def listed(x: Any) -> list:
        return list(x) if isinstance(x, (list, tuple)) else [x]

    per_probe = [listed(x) for x in probes]
    owner = np.array([i for i, x in enumerate(per_probe) for _ in x], dtype=np.int64)
    p_items = [d for x in per_probe for d in x]
    g_items = list(gallery)
    p, g = len(p_items), len(g_items)
    dist = np.zeros((p, g))
    if p and g:
        bs = block_size if block_size is not None else _default_block(max(p, g), c)
        pr, gr = blocks(p, bs), blocks(g, bs)
        ps = [c.scatter([p_items[s:e]], hash=False)[0] for s, e in pr]
        gs = [c.scatter([g_items[s:e]], hash=False)[0] for s, e in gr]
        tasks = [
            ((bi, bj), c.submit(_cross_block, ps[bi], gs[bj], opts, threads_per_task, pure=False))
            for bi in range(len(pr))
            for bj in range(len(gr))
        ]
        for ((bi, bj), _), m in zip(tasks, c.gather([t for _, t in tasks])):
            dist[pr[bi][0] : pr[bi][1], gr[bj][0] : gr[bj][1]] = m
    n_probes = len(per_probe)
    if len(owner) == n_probes and np.all(owner == np.arange(n_probes)):
        return rank(dist, probe_labels, gallery_labels)
    least = np.full((n_probes, g), np.nan)
    np.fmin.at(least, owner, dist)
    return rank(least, probe_labels, gallery_labels)


def rank(
    distances: np.ndarray,
    probe_labels: Optional[Sequence[Any]] = None,
    gallery_labels: Optional[Sequence[Any]] = None,
) -> Identification:
    """Ranks the gallery for each probe from a (P, G) distance matrix (see ``Identification``)."""
    d = np.asarray(distances, dtype=np.float64)
    if d.ndim != 2:
        raise _bipolar_input(f"distances must be 2-dimensional, got shape {d.shape}")
    ranking = np.argsort(d, axis=1, kind="stable")
    best = ranking[:, 0] if d.shape[1] else np.zeros(d.shape[0], dtype=np.int64)
    best_d = d[np.arange(d.shape[0]), best] if d.shape[1] else np.full(d.shape[0], np.nan)
    res = Identification(d, ranking, best, best_d)
    if probe_labels is not None and gallery_labels is not None:
        pl, gl = list(probe_labels), np.asarray(list(gallery_labels), dtype=object)
        if len(pl) != d.shape[0] or len(gl) != d.shape[1]:
            raise _bipolar_input("probe_labels and gallery_labels must match the matrix shape")
        ranks = np.zeros(len(pl), dtype=np.int64)
        for i, lab in enumerate(pl):
            hit = np.flatnonzero(gl[ranking[i]] == lab)
            ranks[i] = hit[0] + 1 if hit.size else 0
        known = ranks > 0
        res.ranks = ranks
        res.rank1_rate = float(np.mean(ranks[known] == 1)) if known.any() else float("nan")
    return res


def _probe_template(scan: Any, kwargs: dict) -> _bipolar.Template:
    return _bipolar.Template.from_scan(scan, "probe", probe=True, **kwargs)


def _identify_shard(
    probe: Any, shard: _bipolar.Gallery, gate: Optional[float]
) -> List[dict]:
    return shard.identify(probe, gate=gate)


def identify_templates(
    probes: Sequence[Any],
    gallery: Any,
    *,
    client: Any = None,
    shard_size: Optional[int] = None,
    top: Optional[int] = None,
    gate: Optional[float] = None,
    scanner: Any = None,
    units: Optional[str] = None,
) -> List[List[dict]]:
    """Face identification of each probe against a gallery of templates on the cluster: for
    every probe the ranking ``gallery.identify(probe, top=top, gate=gate)`` gives in one
    process (the same dicts, in the same order).

    ``gallery``: a ``bipolar.Gallery``, a list of ``bipolar.Template`` or a gallery path
    (opened on the client). It is cut into shards of ``shard_size`` templates (default: about
    two shards per worker thread), each scattered to the workers once; a task ranks one shard for one
    probe (``Gallery.identify``), and the client merges the shards' rankings, taking per
    identity its first best score as ``Gallery.identify`` does. ``probes``: ``Template`` objects
    (used as is) or scans (``Mesh`` objects or paths the workers can read), made into probe
    templates on the workers (``Template.from_scan(scan, "probe", probe=True, scanner=,
    units=)``), one task each. Returns one ranking (a list of dicts) per probe, in order."""
    c = _client(client)
    if isinstance(gallery, _bipolar.Gallery):
        g = gallery
    elif isinstance(gallery, (list, tuple)):
        g = _bipolar.Gallery(list(gallery))
    else:
        g = _bipolar.Gallery.open(gallery)
    templates = g.templates
    if shard_size is None:
        shard_size = _default_block(len(templates), c) * 2
    shards = [
        c.scatter(_bipolar.Gallery(templates[s:e]), hash=False)
        for s, e in blocks(len(templates), shard_size)
    ]
    kwargs = {"scanner": scanner, "units": units}
    out = []
    for p in probes:
        probe = p if isinstance(p, _bipolar.Template) else c.submit(
            _probe_template, p, kwargs, pure=False
        )
        out.append([c.submit(_identify_shard, probe, s, gate, pure=False) for s in shards])
    rankings = []
    for futures in out:
        merged = _bipolar._merge_rankings(c.gather(futures))
        rankings.append(merged if top is None else merged[:top])
    return rankings
