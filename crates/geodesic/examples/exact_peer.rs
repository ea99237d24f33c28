//! Comparison of the exact solver with an exact peer (tvb-gdist / pygeodesic output):
//!
//! ```text
//! EXACT_PEER_MESH=mesh.obj EXACT_PEER_REF=dist.txt EXACT_PEER_SOURCE=0 \
//!     cargo run --release -p geodesic --example exact_peer
//! ```
//!
//! `EXACT_PEER_REF` holds one distance per line in vertex order. Several comparisons can be
//! given at once, separated by `;` in each variable. A source `F<face>` is the centroid of
//! that face (compare with libigl's `exact_geodesic` face sources); `0,17,40` are several
//! sources at once. Prints one line per comparison (timings, propagations, peak RSS, the
//! largest relative difference) and panics when a difference exceeds `EXACT_PEER_TOL`
//! (default 1e-9); `EXACT_PEER_REPEAT` repeats each solve (medians printed);
//! `EXACT_PEER_SCHEDULE=banded` solves with [`ExactSchedule::Banded`] (threads:
//! `RAYON_NUM_THREADS`).

use geodesic::{ExactGeodesic, ExactSchedule, GeodesicSolver, SolveOptions, Source};
use std::time::Instant;

fn main() {
    let (Ok(meshes), Ok(refs), Ok(srcs)) = (
        std::env::var("EXACT_PEER_MESH"),
        std::env::var("EXACT_PEER_REF"),
        std::env::var("EXACT_PEER_SOURCE"),
    ) else {
        eprintln!("EXACT_PEER_MESH, EXACT_PEER_REF and EXACT_PEER_SOURCE must be set (see the source's header)");
        std::process::exit(2);
    };
    let tol: f64 = std::env::var("EXACT_PEER_TOL")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1e-9);
    let schedule = match std::env::var("EXACT_PEER_SCHEDULE").as_deref() {
        Ok("banded") => ExactSchedule::Banded,
        _ => ExactSchedule::Serial,
    };
    let mut worst = 0.0f64;
    for ((mesh, rf), src) in meshes.split(';').zip(refs.split(';')).zip(srcs.split(';')) {
        let m = testsupport::read_mesh(mesh);
        // "F<face>" means the centroid of that face (libigl's `FS` face source); several
        // sources are separated by commas.
        let src_str = src.trim().to_string();
        let sources: Vec<Source> = src_str
            .split(',')
            .map(|one| match one.strip_prefix('F') {
                Some(f) => Source::Point(geodesic::SurfacePoint::new(
                    f.parse().unwrap(),
                    glam::DVec3::splat(1.0 / 3.0),
                )),
                None => Source::Vertex(one.parse().unwrap()),
            })
            .collect();
        let src = src_str;
        let reference: Vec<f64> = std::fs::read_to_string(rf)
            .unwrap()
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| l.trim().parse::<f64>().unwrap())
            .collect();
        let repeat: usize = std::env::var("EXACT_PEER_REPEAT")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(1);
        let (mut setup, mut solve) = (Vec::new(), Vec::new());
        let mut out = None;
        for _ in 0..repeat {
            let (t0, c0) = (Instant::now(), thread_cpu());
            let solver = ExactGeodesic::new(&m).unwrap().with_schedule(schedule);
            let (t1, c1) = (Instant::now(), thread_cpu());
            let r = solver
                .distances_with_stats(&sources, &SolveOptions::default())
                .unwrap();
            let (t2, c2) = (Instant::now(), thread_cpu());
            let _ = solver.n_vertices();
            setup.push(((t1 - t0).as_secs_f64(), c1 - c0));
            solve.push(((t2 - t1).as_secs_f64(), c2 - c1));
            out = Some(r);
        }
        let (d, props) = out.unwrap();
        let med = |v: &mut Vec<(f64, f64)>| {
            let mut w: Vec<f64> = v.iter().map(|x| x.0).collect();
            let mut c: Vec<f64> = v.iter().map(|x| x.1).collect();
            w.sort_by(f64::total_cmp);
            c.sort_by(f64::total_cmp);
            (w[w.len() / 2], c[c.len() / 2])
        };
        let (sw, sc) = med(&mut setup);
        let (vw, vc) = med(&mut solve);
        let floor = 1e-12 * m.bbox().diagonal();
        let rel = testsupport::fields::max_rel_diff(&d, &reference, floor);
        let (mut imax, mut vmax) = (0, 0.0);
        for i in 0..d.len() {
            let r = (d[i] - reference[i]).abs() / reference[i].abs().max(floor);
            if r > vmax {
                vmax = r;
                imax = i;
            }
        }
        println!(
            "{mesh} src {src} ({schedule:?}): nV {} setup wall {sw:.4} s cpu {sc:.4} s | solve wall {vw:.4} s cpu {vc:.4} s (median of {repeat}) | propagations {props} | peak RSS {} MB | max rel diff {rel:.3e} (vertex {imax}: ours {} peer {})",
            m.n_vertices(),
            peak_rss_mb(),
            d[imax],
            reference[imax]
        );
        worst = worst.max(rel);
    }
    assert!(
        worst <= tol,
        "max relative difference {worst:.3e} > {tol:.0e}"
    );
}

/// CPU time of the calling thread in seconds (Linux `/proc/thread-self/schedstat`; NaN elsewhere).
fn thread_cpu() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map(|ns| ns * 1e-9)
        .unwrap_or(f64::NAN)
}

/// Peak resident set size of the process in MB (Linux `VmHWM`; 0 elsewhere).
fn peak_rss_mb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))?
                .split_whitespace()
                .nth(1)?
                .parse::<u64>()
                .ok()
        })
        .map(|kb| kb / 1024)
        .unwrap_or(0)
}
