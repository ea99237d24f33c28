//! Times the reference-point search's fields on one face mesh (mm): the poles' own fields and
//! the whole search set (each pole plus the vertices nearest to it moved by RADIUS in 6
//! directions of the x-y plane, the scanner's image plane), every field cut at CUT, through
//! [`geodesic::distances_many`] (rayon over the fields; the own fields also one after
//! another, as `facematch::face_fields` solves them):
//!
//! ```text
//! cargo run --release -p geodesic --example geo_search -- MESH CUT RADIUS POLE [POLE ...]
//! ```

use geodesic::{
    distances_many, ExactGeodesic, ExactWorkspace, GeodesicSolver, SolveOptions, Source,
};
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 5 {
        eprintln!("usage: geo_search MESH CUT RADIUS POLE [POLE ...]");
        std::process::exit(2);
    }
    let mesh = testsupport::read_mesh(&a[1]);
    let cut: f64 = a[2].parse().expect("cut-off");
    let radius: f64 = a[3].parse().expect("radius");
    let poles: Vec<u32> = a[4..].iter().map(|s| s.parse().expect("pole")).collect();
    let own: Vec<Vec<Source>> = poles.iter().map(|&p| vec![Source::Vertex(p)]).collect();
    let mut all = own.clone();
    for &p in &poles {
        let c = mesh.positions()[p as usize];
        for k in 0..6 {
            let t = std::f64::consts::TAU * f64::from(k) / 6.0;
            let q = c + radius * glam::DVec3::new(t.cos(), t.sin(), 0.0);
            all.push(vec![Source::Vertex(testsupport::nearest_vertex(&mesh, q))]);
        }
    }
    let opts = SolveOptions {
        max_distance: Some(cut),
    };
    let t = Instant::now();
    let solver = ExactGeodesic::new(&mesh).expect("solver");
    let setup = t.elapsed().as_secs_f64();
    let time = |sets: &[Vec<Source>]| {
        let mut v: Vec<f64> = (0..3)
            .map(|_| {
                let t = Instant::now();
                distances_many(&solver, sets, &opts).expect("solve");
                t.elapsed().as_secs_f64()
            })
            .collect();
        v.sort_by(f64::total_cmp);
        v[1]
    };
    // The own fields one after another (as `facematch::face_fields` solves them).
    let time_seq = |sets: &[Vec<Source>]| {
        let mut v: Vec<f64> = (0..3)
            .map(|_| {
                let t = Instant::now();
                for s in sets {
                    solver.distances(s, &opts).expect("solve");
                }
                t.elapsed().as_secs_f64()
            })
            .collect();
        v.sort_by(f64::total_cmp);
        v[1]
    };
    let moved = &all[own.len()..];
    // The moved fields one after another on this thread, each solve allocating its buffers
    // or reusing one workspace; alternated 3 times, medians.
    let (mut fresh, mut reused) = (Vec::new(), Vec::new());
    let mut ws = ExactWorkspace::new();
    for _ in 0..3 {
        let t = Instant::now();
        for s in moved {
            solver.distances(s, &opts).expect("solve");
        }
        fresh.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        for s in moved {
            solver.distances_with(&mut ws, s, &opts).expect("solve");
        }
        reused.push(t.elapsed().as_secs_f64());
    }
    fresh.sort_by(f64::total_cmp);
    reused.sort_by(f64::total_cmp);
    println!(
        "moved fields one after another: {:.3} s allocating per solve, {:.3} s with a reused workspace",
        fresh[1], reused[1]
    );
    let (t_own, t_own_seq, t_moved, t_all) = (time(&own), time_seq(&own), time(moved), time(&all));
    println!(
        "setup {setup:.3} s; own fields ({}) {t_own:.3} s in parallel, {t_own_seq:.3} s one after another; \
         moved fields ({}) {t_moved:.3} s; search set with the own ({}) {t_all:.3} s \
         (moved / own in parallel {:.2}, moved / own one after another {:.2})",
        own.len(),
        moved.len(),
        all.len(),
        t_moved / t_own,
        t_moved / t_own_seq
    );
}
