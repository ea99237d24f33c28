#!/usr/bin/env python3
"""Python-side benchmarks of bipolar, with the peers in the same run (docs/benchmarks.md).

    python/benchmarks/run                       # makes the bench venv, builds release, runs all
    python bench_python.py [--parts geodesic,overhead,dask] [--repeat 3] [--json out.json]

Parts:
  geodesic  exact geodesics from Python against tvb-gdist and pygeodesic (max relative
            difference, time ratio), and fast marching / heat method against potpourri3d's
            (time, error against our exact field; on the spheres also against the great-circle
            distance), on ico6, ico7 and a paper-set face. Single solves from one source
            vertex; preparation and solve timed separately where the library separates them.
  overhead  the Python overhead of a describe call: wall time of bipolar.describe against the
            time spent inside the Rust library calls of the same call (_describe_profiled).
  dask      a 2,000 x 2,000 keyed distance matrix: one process (rayon, all cores) against a
            LocalCluster of 2 worker processes x 1 thread, blocks of 250; equality checked.

Single-threaded peers (OMP/OPENBLAS threads = 1), as the shared peer scripts run them; our
solvers are single-threaded per solve too. Times are wall-clock medians of --repeat runs
(one run for the peers' ico7 exact solves, which take over a minute each).
"""

import argparse
import json
import os
import pathlib
import platform
import statistics
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import bipolar  # noqa: E402
import bipolar.gdist  # noqa: E402,F401

ROOT = pathlib.Path(__file__).resolve().parents[2]
SHARED = pathlib.Path(os.environ.get("BIPOLAR_SHARED", ROOT.parent / "shared"))
PAPER = SHARED / "faces" / "ict-facekit" / "paper-set"


def timed(fn, repeat):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times)


def fmt(s):
    if s is None:
        return "-"
    if s < 1e-3:
        return f"{s * 1e6:.0f} µs"
    if s < 1:
        return f"{s * 1e3:.1f} ms"
    return f"{s:.2f} s"


def meshes():
    out = [("ico6", bipolar.icosphere(6), 0), ("ico7", bipolar.icosphere(7), 0)]
    face = PAPER / "id1_neutral.obj"
    if face.exists():
        out.append(("face id1_neutral", bipolar.read_mesh(face), 1507))
    else:
        print(f"note: {face} absent, face rows skipped", file=sys.stderr)
    return out


def rel_diff(a, b):
    """max |a - b| / max |b| (the field's scale), and max |a - b| / b over b > 1 % of max b."""
    scale = np.max(np.abs(b))
    far = b > 0.01 * scale
    return float(np.max(np.abs(a - b)) / scale), float(np.max(np.abs(a - b)[far] / b[far]))


def bench_geodesic(repeat):
    import gdist
    import potpourri3d as pp3d
    import pygeodesic.geodesic as pyg

    rows = []
    for name, mesh, src in meshes():
        V = mesh.vertices
        F = mesh.triangles.astype(np.int32)
        peer_rep = 1 if mesh.n_vertices > 100_000 else repeat
        row = {"mesh": name, "vertices": mesh.n_vertices, "source": src}
        # ours, exact: preparation + one solve, and the solve alone on the prepared solver
        solver, t_prep = timed(lambda: bipolar.GeodesicSolver(mesh, "exact"), repeat)
        ours, t_solve = timed(lambda: solver.distances(src), repeat)
        row["exact_ours_prep"], row["exact_ours_solve"] = t_prep, t_solve
        # the drop-in module, as a tvb-gdist user calls it (builds the solver each call)
        drop, t_drop = timed(
            lambda: bipolar.gdist.compute_gdist(V, F, np.array([src], np.int32)), repeat
        )
        row["exact_ours_gdist_api"] = t_drop
        assert np.array_equal(drop, ours)
        tvb, t_tvb = timed(
            lambda: gdist.compute_gdist(V, F, source_indices=np.array([src], np.int32)), peer_rep
        )
        row["exact_tvb"] = t_tvb
        row["rel_vs_tvb"] = rel_diff(ours, np.asarray(tvb))

        def pyg_run():
            alg = pyg.PyGeodesicAlgorithmExact(V, F)
            d, _ = alg.geodesicDistances(np.array([src]), None)
            return np.asarray(d)

        pyd, t_pyg = timed(pyg_run, peer_rep)
        row["exact_pygeodesic"] = t_pyg
        row["rel_vs_pygeodesic"] = rel_diff(ours, pyd)
        analytic = None
        if name.startswith("ico"):
            u = V / np.linalg.norm(V, axis=1, keepdims=True)
            analytic = np.arccos(np.clip(u @ u[src], -1, 1))
        # fast marching and heat: ours vs potpourri3d
        for method in ["fmm", "heat"]:
            s, tp = timed(lambda: bipolar.GeodesicSolver(mesh, method), repeat)
            d, ts = timed(lambda: s.distances(src), repeat)
            row[f"{method}_ours_prep"], row[f"{method}_ours_solve"] = tp, ts
            row[f"{method}_ours_err"] = err(d, ours, analytic)
        s, tp = timed(lambda: pp3d.MeshFastMarchingDistanceSolver(V, F), repeat)
        d, ts = timed(lambda: np.asarray(s.compute_distance([[(int(src), [])]])), repeat)
        row["fmm_pp3d_prep"], row["fmm_pp3d_solve"] = tp, ts
        row["fmm_pp3d_err"] = err(d, ours, analytic)
        s, tp = timed(lambda: pp3d.MeshHeatMethodDistanceSolver(V, F, t_coef=1.0, use_robust=True), repeat)
        d, ts = timed(lambda: np.asarray(s.compute_distance(int(src))), repeat)
        row["heat_pp3d_prep"], row["heat_pp3d_solve"] = tp, ts
        row["heat_pp3d_err"] = err(d, ours, analytic)
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def err(d, exact, analytic):
    e = {"mae_vs_exact": float(np.mean(np.abs(d - exact))), "max_vs_exact": float(np.max(np.abs(d - exact)))}
    if analytic is not None:
        e["mae_vs_sphere"] = float(np.mean(np.abs(d - analytic)))
        e["max_vs_sphere"] = float(np.max(np.abs(d - analytic)))
    return e


def bench_overhead(repeat):
    face = PAPER / "id1_neutral.obj"
    if not face.exists():
        return []
    mesh = bipolar.read_mesh(face)
    rows = []
    for label, kw in [
        ("region of 30 levels", dict(levels=30, max_level=30)),
        ("whole face, 30 levels", dict(levels=30)),
    ]:
        n = max(repeat, 15)
        bipolar.describe(mesh, 1507, 3721, **kw)  # warm-up
        walls, inner, walls_p = [], [], []
        for _ in range(n):
            t0 = time.perf_counter()
            bipolar.describe(mesh, 1507, 3721, **kw)
            walls.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            _, rust = bipolar._bipolar._describe_profiled(mesh, 1507, 3721, **kw)
            walls_p.append(time.perf_counter() - t0)
            inner.append(rust)
        over = [w - r for w, r in zip(walls_p, inner)]
        row = {
            "case": label,
            "describe_wall_median": statistics.median(walls),
            "profiled_wall_median": statistics.median(walls_p),
            "rust_median": statistics.median(inner),
            "overhead_median": statistics.median(over),
            "overhead_share_median": statistics.median([o / r for o, r in zip(over, inner)]),
            "runs": n,
        }
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def gallery(n, seed=0):
    """n descriptors: the 12 paper-set faces described once (30 levels, region of 30), each
    copy moved rigidly, jittered (0.02 cm) and with 10 % of its points dropped."""
    faces = sorted(PAPER.glob("*.obj"))
    base = [bipolar.describe(f, 1507, 3721, levels=30, max_level=30) for f in faces]
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        b = base[k % len(base)]
        q, r = np.linalg.qr(rng.normal(size=(3, 3)))
        q = q * np.sign(np.diag(r))
        keep = rng.random(len(b)) > 0.1
        pts = b.points[keep] + rng.normal(scale=0.02, size=(keep.sum(), 3))
        out.append(
            bipolar.Descriptor.from_arrays(pts @ q.T + rng.normal(size=3), b.keys[keep],
                                           b.cos[keep], b.ambiguous[keep])
        )
    return out


def bench_dask(n, block):
    from distributed import Client, LocalCluster

    import bipolar.dask as bd

    descs = gallery(n)
    points = [len(d) for d in descs]
    t0 = time.perf_counter()
    single = bipolar.distance_matrix(descs)
    t_single = time.perf_counter() - t0
    t0 = time.perf_counter()
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster)
    t_start = time.perf_counter() - t0
    t0 = time.perf_counter()
    dm = bd.distance_matrix(descs, client=client, block_size=block)
    t_dask = time.perf_counter() - t0
    client.close()
    cluster.close()
    row = {
        "n": n,
        "points_per_descriptor_median": statistics.median(points),
        "pairs": n * (n - 1) // 2,
        "block_size": block,
        "tasks": (len(bd.blocks(n, block)) * (len(bd.blocks(n, block)) + 1)) // 2,
        "single_process_all_cores": t_single,
        "cluster_start": t_start,
        "dask": t_dask,
        "identical": bool(np.array_equal(dm, single)),
    }
    print(json.dumps(row), flush=True)
    return [row]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--parts", default="geodesic,overhead,dask")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--block", type=int, default=250)
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    import importlib.metadata as md

    info = {"python": platform.python_version(), "cpus": os.cpu_count(), "load": os.getloadavg()}
    for p in ["numpy", "tvb-gdist", "pygeodesic", "potpourri3d", "dask", "distributed", "bipolar"]:
        try:
            info[p] = md.version(p)
        except md.PackageNotFoundError:
            pass
    print(json.dumps(info), flush=True)
    res = {"info": info}
    parts = a.parts.split(",")
    if "geodesic" in parts:
        res["geodesic"] = bench_geodesic(a.repeat)
    if "overhead" in parts:
        res["overhead"] = bench_overhead(a.repeat)
    if "dask" in parts:
        res["dask"] = bench_dask(a.n, a.block)
    res["info"]["load_end"] = os.getloadavg()
    if a.json:
        pathlib.Path(a.json).write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
