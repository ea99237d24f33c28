//! Comparison with an exact peer (tvb-gdist / pygeodesic output), run by hand in release:
//!
//! ```text
//! EXACT_PEER_MESH=mesh.obj EXACT_PEER_REF=dist.txt EXACT_PEER_SOURCE=0 \
//!     cargo test --release -p geodesic --test exact_peer -- --ignored --nocapture
//! ```
//!
//! `EXACT_PEER_REF` holds one distance per line in vertex order. Several comparisons can be
//! given at once, separated by `;` in each variable.

mod exact_util;

use geodesic::{ExactGeodesic, GeodesicSolver, SolveOptions, Source};
use std::time::Instant;

#[test]
#[ignore = "needs peer output files; run by hand (see the file header)"]
fn compare_with_peer() {
    let (Ok(meshes), Ok(refs), Ok(srcs)) = (
        std::env::var("EXACT_PEER_MESH"),
        std::env::var("EXACT_PEER_REF"),
        std::env::var("EXACT_PEER_SOURCE"),
    ) else {
        println!("skipped: EXACT_PEER_MESH / EXACT_PEER_REF / EXACT_PEER_SOURCE not set");
        return;
    };
    let tol: f64 = std::env::var("EXACT_PEER_TOL")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1e-9);
    let mut worst = 0.0f64;
    for ((mesh, rf), src) in meshes.split(';').zip(refs.split(';')).zip(srcs.split(';')) {
        let m = exact_util::read_obj(std::path::Path::new(mesh)).unwrap();
        let src: u32 = src.trim().parse().unwrap();
        let reference: Vec<f64> = std::fs::read_to_string(rf)
            .unwrap()
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| l.trim().parse::<f64>().unwrap())
            .collect();
        let t0 = Instant::now();
        let solver = ExactGeodesic::new(&m).unwrap();
        let t1 = Instant::now();
        let (d, props) = solver
            .distances_with_stats(&[Source::Vertex(src)], &SolveOptions::default())
            .unwrap();
        let t2 = Instant::now();
        let _ = solver.n_vertices();
        let floor = 1e-12 * m.bbox().diagonal();
        let rel = exact_util::max_rel_diff(&d, &reference, floor);
        let (mut imax, mut vmax) = (0, 0.0);
        for i in 0..d.len() {
            let r = (d[i] - reference[i]).abs() / reference[i].abs().max(floor);
            if r > vmax {
                vmax = r;
                imax = i;
            }
        }
        println!(
            "{mesh} src {src}: nV {} setup {:.4} s solve {:.4} s propagations {props} max rel diff {rel:.3e} (vertex {imax}: ours {} peer {})",
            m.n_vertices(),
            (t1 - t0).as_secs_f64(),
            (t2 - t1).as_secs_f64(),
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
