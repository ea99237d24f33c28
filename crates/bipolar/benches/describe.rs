//! Descriptor construction time (geodesics excluded) on a paper-set face (6,706 vertices,
//! 30 levels) and on an icosphere. The face comes from the shared data folder (found by
//! `testsupport`); without it only the sphere is measured.

// criterion_group! generates an undocumented function.
#![allow(missing_docs)]

use bipolar::{DescriptorOptions, LevelSpec, SelectionRule, Source, TangentMethod};
use criterion::{criterion_group, criterion_main, Criterion};
use meshcore::{Surface, TriMesh};

/// A paper-set face (through the shared-data rule of `testsupport`) and its outer eye
/// corners in the ICT FaceKit topology.
fn face() -> Option<(TriMesh, [Source; 2])> {
    let path = testsupport::paper_face("id1_neutral.obj")?;
    Some((
        testsupport::read_mesh(path),
        [Source::Vertex(1507), Source::Vertex(3721)],
    ))
}

fn fields(mesh: &TriMesh, refs: &[Source]) -> (Vec<Vec<f64>>, &'static str) {
    let (solver, name) = match geodesic::new_solver(mesh, geodesic::Method::Exact) {
        Ok(s) => (s, "exact"),
        Err(_) => (
            geodesic::new_solver(mesh, geodesic::Method::Dijkstra).unwrap(),
            "dijkstra",
        ),
    };
    let f = refs
        .iter()
        .map(|r| {
            solver
                .distances(&[*r], &geodesic::SolveOptions::default())
                .unwrap()
        })
        .collect();
    (f, name)
}

fn bench(c: &mut Criterion) {
    let mut cases: Vec<(String, TriMesh, [Source; 2], u32)> = Vec::new();
    match face() {
        Some((m, r)) => cases.push(("face".into(), m, r, 30)),
        None => eprintln!("paper-set face not found; benchmarking the sphere only"),
    }
    let ico = testsupport::shapes::icosphere(5);
    cases.push((
        "ico5".into(),
        ico,
        [Source::Vertex(0), Source::Vertex(5000)],
        30,
    ));
    for (name, mesh, refs, n) in &cases {
        let surface = Surface::new(mesh.clone());
        let (f, solver) = fields(mesh, refs);
        eprintln!(
            "{name}: {} vertices, fields from the {solver} solver",
            mesh.n_vertices()
        );
        let mut g = c.benchmark_group(format!("describe_{name}"));
        g.sample_size(20);
        for (label, rule, tangent) in [
            (
                "gradient_isoangle",
                SelectionRule::IsoAngle,
                TangentMethod::Gradient,
            ),
            (
                "gradient_filter",
                SelectionRule::Filter {
                    tolerance: 0.95 / 32.0,
                },
                TangentMethod::Gradient,
            ),
            ("gradient_all", SelectionRule::All, TangentMethod::Gradient),
            (
                "strip_filter",
                SelectionRule::Filter {
                    tolerance: 0.95 / 32.0,
                },
                TangentMethod::Strip,
            ),
            (
                "spline_filter",
                SelectionRule::Filter {
                    tolerance: 0.95 / 32.0,
                },
                TangentMethod::Spline,
            ),
            (
                "spline_isoangle",
                SelectionRule::IsoAngle,
                TangentMethod::Spline,
            ),
        ] {
            let opts = DescriptorOptions {
                levels: LevelSpec::Count(*n),
                max_level: Some(*n),
                rule,
                tangent,
                ..DescriptorOptions::default()
            };
            let run = || {
                let fields = bipolar::Fields::Precomputed {
                    fields: &f,
                    references: Some(refs),
                };
                bipolar::describe(&surface, fields, &opts).unwrap()
            };
            let d = run();
            eprintln!(
                "  {label}: {} points from {} intersections",
                d.len(),
                d.stats.intersections
            );
            g.bench_function(label, |b| b.iter(run));
        }
        g.finish();
    }
}

/// The whole `describe` (what `bipolar describe` computes): exact geodesic fields (cut off just
/// past the region when `max_level` is set) plus the descriptor; with and without the solver's
/// preparation.
fn bench_whole(c: &mut Criterion) {
    let Some((mesh, refs)) = face() else {
        eprintln!("paper-set face not found; skipping the whole-describe bench");
        return;
    };
    let mut g = c.benchmark_group("whole_describe_face_exact");
    g.sample_size(10);
    let surface = Surface::new(mesh.clone());
    for (label, max_level) in [("region_30_of_30", Some(30)), ("whole_face", None)] {
        let opts = DescriptorOptions {
            levels: LevelSpec::Count(30),
            max_level,
            ..DescriptorOptions::default()
        };
        let describe = |solver: &dyn geodesic::GeodesicSolver| {
            let fields = bipolar::Fields::Solve {
                solver,
                references: &refs,
            };
            bipolar::describe(&surface, fields, &opts).unwrap()
        };
        let exact = || geodesic::new_solver(&mesh, geodesic::Method::Exact).unwrap();
        let solver = exact();
        let d = describe(solver.as_ref());
        eprintln!("  {label}: {} points", d.len());
        g.bench_function(format!("{label}_solver_prepared"), |b| {
            b.iter(|| describe(solver.as_ref()))
        });
        g.bench_function(format!("{label}_with_solver_setup"), |b| {
            b.iter(|| describe(exact().as_ref()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench, bench_whole);
criterion_main!(benches);
