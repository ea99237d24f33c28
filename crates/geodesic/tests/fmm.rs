//! Accuracy of the fast-marching update rules on meshes with analytic distances: the default
//! curved-front rule against the plane-wave (Kimmel-Sethian) and point-source rules. Meshes are
//! generated here (the constructions of the peers' `make_meshes.py`); a few seconds in the dev
//! profile.

use geodesic::{FastMarching, FmmUpdate, GeodesicSolver, SolveOptions, Source, TriMesh};
use glam::DVec3;
use testsupport::fields::{
    icosphere_errors, max_abs_diff, mean_abs_diff, prism_geodesic, sphere_geodesic,
};
use testsupport::shapes::{self, icosphere, uv_sphere, Diagonals};

fn solve(mesh: &TriMesh, rule: FmmUpdate, src: &[Source]) -> Vec<f64> {
    FastMarching::with_update(mesh, rule)
        .unwrap()
        .distances(src, &SolveOptions::default())
        .unwrap()
}

/// Great-circle distance on the unit sphere from vertex `src`.
fn great_circle(mesh: &TriMesh, src: u32) -> Vec<f64> {
    sphere_geodesic(mesh, mesh.position(src), 1.0)
}

/// (MAE, max error).
fn errors(d: &[f64], g: &[f64]) -> (f64, f64) {
    (mean_abs_diff(d, g), max_abs_diff(d, g))
}

#[test]
fn curved_front_is_the_default() {
    assert_eq!(FmmUpdate::default(), FmmUpdate::CurvedFront);
}

#[test]
fn uv_sphere_from_the_equator_within_two_percent() {
    // The peers' uv10k mesh (99 rings x 100 segments), source on the equator. potpourri3d's
    // fast marching (no unfolding) reaches 0.274 max error here, our point-source rule 0.042,
    // the plane-wave rule 0.029.
    let m = uv_sphere(100, 100);
    let src = 4901u32;
    assert!(m.position(src).z.abs() < 1e-12);
    let g = great_circle(&m, src);
    let (mae, max) = errors(
        &solve(&m, FmmUpdate::CurvedFront, &[Source::Vertex(src)]),
        &g,
    );
    // The issue asks for 2 %; measured 6.3e-4.
    assert!(max < 0.005, "max error {max}");
    assert!(mae < 1e-3, "MAE {mae}");
    let (mae_p, max_p) = errors(&solve(&m, FmmUpdate::PlaneWave, &[Source::Vertex(src)]), &g);
    assert!(
        max < 0.7 * max_p && mae < 0.1 * mae_p,
        "curved {mae} / {max}, plane wave {mae_p} / {max_p}"
    );
}

#[test]
fn icosphere_errors_far_below_the_plane_wave() {
    // ico4 of the peers (2,562 vertices): potpourri3d and our plane-wave rule both have MAE
    // 1.71e-2 / max 3.05e-2; the point-source rule max 4.08e-2 (it underestimates towards the
    // antipode).
    let m = icosphere(4);
    let g = great_circle(&m, 0);
    let (mae, max) = errors(&solve(&m, FmmUpdate::CurvedFront, &[Source::Vertex(0)]), &g);
    let (mae_p, max_p) = errors(&solve(&m, FmmUpdate::PlaneWave, &[Source::Vertex(0)]), &g);
    let (_, max_s) = errors(&solve(&m, FmmUpdate::PointSource, &[Source::Vertex(0)]), &g);
    assert!(
        max < 0.1 * max_p && max < 0.1 * max_s,
        "max {max} vs {max_p}, {max_s}"
    );
    assert!(mae < 0.05 * mae_p, "MAE {mae} vs {mae_p}");
}

#[test]
fn curved_front_is_exact_on_flat_meshes() {
    // On a plane (no Gaussian curvature) the carried curvature stays 1 / T and the rule is the
    // point-source one: exact from a vertex source.
    let (nx, sx, sy) = (14usize, 0.1, 0.08);
    let m = shapes::grid(nx, 11, Diagonals::Alternating, |i, j| {
        DVec3::new(i as f64 * sx, j as f64 * sy, 0.0)
    })
    .unwrap();
    let idx = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let src = idx(6, 5);
    let c = m.position(src);
    let d = solve(&m, FmmUpdate::CurvedFront, &[Source::Vertex(src)]);
    for (p, v) in m.positions().iter().zip(&d) {
        let e = (*p - c).length();
        assert!((e - v).abs() < 1e-9, "{e} vs {v}");
    }
}

#[test]
fn cylinder_unrolled_is_nearly_exact() {
    // Developable: zero Gaussian curvature inside, so the front stays a circle in the unrolled
    // plane. The polygonal cylinder is shorter around than the round one; compare with the
    // unrolled polygon (chord length per segment).
    let (na, nh, r, h) = (64usize, 48usize, 1.0, 3.0);
    let m = shapes::cylinder(r, h, na, nh);
    let d = solve(&m, FmmUpdate::CurvedFront, &[Source::Vertex(0)]);
    // Unrolled position: min(i, na - i) chords around, z up.
    let worst = max_abs_diff(&d, &prism_geodesic(&m, r, na, 0));
    assert!(worst < 1e-9, "max error {worst}");
}

#[test]
fn curved_front_converges_on_icospheres() {
    // Max error shrinks with refinement (roughly quadratically away from the antipode).
    let mut prev = f64::INFINITY;
    let curved_front = |m: &TriMesh| solve(m, FmmUpdate::CurvedFront, &[Source::Vertex(0)]);
    for (level, _, mae, _) in icosphere_errors(curved_front) {
        assert!(mae < 0.4 * prev, "level {level}: MAE {mae} after {prev}");
        prev = mae;
    }
}

/// A height function `z = f(x, y)`.
type Height = fn(f64, f64) -> f64;

/// Height field `z = f(x, y)` on an `n` x `n` grid of the unit square, alternating diagonals.
fn height_field(n: usize, f: impl Fn(f64, f64) -> f64) -> TriMesh {
    let h = 1.0 / n as f64;
    shapes::grid(n, n, Diagonals::Alternating, |i, j| {
        let (x, y) = (i as f64 * h, j as f64 * h);
        DVec3::new(x, y, f(x, y))
    })
    .unwrap()
}

#[test]
fn curved_surfaces_against_the_exact_polyhedral_distance() {
    // Open meshes with positive and negative Gaussian curvature (a bump and a saddle), with
    // boundary: the curved-front rule against the exact solver, beside the other rules.
    let bump = |x: f64, y: f64| 0.4 * (-((x - 0.5).powi(2) + (y - 0.5).powi(2)) * 12.0).exp();
    let saddle = |x: f64, y: f64| 0.8 * (x - 0.5) * (y - 0.5);
    let cases: [(&str, Height); 2] = [("bump", bump), ("saddle", saddle)];
    for (name, f) in cases {
        let m = height_field(32, f);
        let src = [Source::Vertex(3 * 33 + 4)];
        let exact = geodesic::ExactGeodesic::new(&m)
            .unwrap()
            .distances(&src, &SolveOptions::default())
            .unwrap();
        let e = |rule| errors(&solve(&m, rule, &src), &exact);
        let (c, p, w) = (
            e(FmmUpdate::CurvedFront),
            e(FmmUpdate::PointSource),
            e(FmmUpdate::PlaneWave),
        );
        println!("{name}: curved {c:?}, point {p:?}, plane {w:?}");
        assert!(c.0.is_finite() && c.1.is_finite());
        assert!(
            c.0 < p.0 && c.0 < w.0,
            "{name}: MAE curved {c:?} point {p:?} plane {w:?}"
        );
        assert!(c.1 < w.1, "{name}: max curved {c:?} plane {w:?}");
    }
}

#[test]
fn row_of_sources_on_a_plane() {
    // All vertices of the bottom row as sources: distance = y. Each source starts as a point
    // source, and the circle through two vertices reached from different sources is not the
    // front, so the point-source and curved-front rules are not exact here (the plane-wave rule
    // is); measured 0.12 h for both.
    let m = height_field(12, |_, _| 0.0);
    let src: Vec<Source> = (0..=12).map(Source::Vertex).collect();
    let h = 1.0 / 12.0;
    for (rule, tol) in [
        (FmmUpdate::PlaneWave, 1e-12),
        (FmmUpdate::PointSource, 0.15 * h),
        (FmmUpdate::CurvedFront, 0.15 * h),
    ] {
        let d = solve(&m, rule, &src);
        let e = m
            .positions()
            .iter()
            .zip(&d)
            .map(|(p, v)| (p.y - v).abs())
            .fold(0.0, f64::max);
        println!("{rule:?}: max error {e:.3e} (h = {h:.3e})");
        assert!(e < tol, "{rule:?}: {e}");
    }
}

#[test]
fn option_names_round_trip_and_bad_names_list_the_choices() {
    use geodesic::{FmmUpdate, GeodesicError, Method};
    meshcore::choice::check_choice::<Method>("mmp").unwrap();
    meshcore::choice::check_choice::<FmmUpdate>("planewave").unwrap();
    assert_eq!("FMM".parse::<Method>().unwrap(), Method::Fmm);
    match "mmp".parse::<Method>() {
        Err(GeodesicError::UnknownChoice(e)) => {
            assert_eq!(e.expected, ["exact", "fmm", "heat", "dijkstra"]);
        }
        other => panic!("{other:?}"),
    }
}
