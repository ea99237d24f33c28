//! Isoline extraction against analytic oracles (specification §6) and structural invariants.

use glam::DVec3;
use levelcurves::{isolines, isolines_uniform, uniform_level_range, uniform_levels, Isoline};
use meshcore::shapes::{grid_plane, icosphere};
use meshcore::{Topology, TriMesh};
use proptest::prelude::*;
use std::collections::HashSet;

fn field(mesh: &TriMesh, f: impl Fn(DVec3) -> f64) -> Vec<f64> {
    mesh.positions().iter().map(|&p| f(p)).collect()
}

/// Structural checks every extraction must pass.
fn check_structure(mesh: &TriMesh, topo: &Topology, u: &[f64], c: f64, pieces: &[Isoline]) {
    let diag = mesh.bbox().diagonal();
    for iso in pieces {
        let n = iso.points.len();
        assert_eq!(iso.edge_of.len(), n);
        assert_eq!(iso.t_of.len(), n);
        assert_eq!(iso.face_of.len(), if iso.closed { n } else { n - 1 });
        for k in 0..n {
            let p = iso.points[k];
            assert!(p.is_finite());
            let (lo, hi) = iso.edge_of[k];
            assert!(lo < hi);
            let t = iso.t_of[k];
            assert!((0.0..=1.0).contains(&t));
            let q = mesh.position(lo) + t * (mesh.position(hi) - mesh.position(lo));
            assert!((p - q).length() <= 1e-12 * diag);
            // Field interpolated at the point equals the level.
            let val = u[lo as usize] + t * (u[hi as usize] - u[lo as usize]);
            assert!(
                (val - c).abs() <= 1e-9 * (1.0 + c.abs()),
                "value {val} vs level {c}"
            );
            // One end above, one below.
            assert_ne!(u[lo as usize] >= c, u[hi as usize] >= c);
        }
        for j in 0..iso.face_of.len() {
            let f = iso.face_of[j] as usize;
            let tri = mesh.triangles()[f];
            // The point lies on the face: its edge is a side of the face, or (after removal of
            // duplicates at a vertex exactly at the level) it sits on the face geometrically.
            let on_face = |k: usize| {
                let e = iso.edge_of[k];
                let [a, b, c] = mesh.face_corners(f as u32);
                let p = iso.points[k];
                (tri.contains(&e.0) && tri.contains(&e.1)) || {
                    let w = meshcore::closest_point_on_triangle(p, a, b, c);
                    (w.x * a + w.y * b + w.z * c - p).length() <= 1e-12 * diag
                }
            };
            assert!(on_face(j), "segment {j} start not on face {f}");
            assert!(on_face((j + 1) % n), "segment {j} end not on face {f}");
            let (a, b) = iso.segment(j);
            assert!(
                (b - a).length() > 1e-12 * diag,
                "consecutive duplicate points"
            );
        }
        if !iso.closed {
            // Open pieces end on boundary edges (or next to skipped faces).
            for &k in &[0, n - 1] {
                let (lo, hi) = iso.edge_of[k];
                let e = topo.edges().iter().find(|e| e.v == [lo, hi]).unwrap();
                let usable = |f: u32| {
                    f != meshcore::NO_FACE
                        && mesh.triangles()[f as usize]
                            .iter()
                            .all(|&v| u[v as usize].is_finite())
                };
                let n_usable = e.faces.iter().filter(|&&f| usable(f)).count();
                assert!(
                    e.n_faces == 1 || n_usable < 2,
                    "open end on an interior edge"
                );
            }
        }
    }
}

/// Signed area of a closed polygon projected on the xy plane.
fn signed_area_xy(p: &[DVec3]) -> f64 {
    (0..p.len())
        .map(|i| {
            let a = p[i];
            let b = p[(i + 1) % p.len()];
            a.x * b.y - b.x * a.y
        })
        .sum::<f64>()
        / 2.0
}

#[test]
fn plane_circles_are_closed_ccw_loops() {
    let mesh = grid_plane(40, 0.05, -1.0, 0.3, 7, |_| false);
    let topo = Topology::new(&mesh);
    let c0 = DVec3::new(0.03, -0.02, 0.0);
    let u = field(&mesh, |p| (p - c0).length());
    let levels = [0.2, 0.45, 0.7];
    let all = isolines(&mesh, &topo, &u, &levels).unwrap();
    for (li, pieces) in all.iter().enumerate() {
        check_structure(&mesh, &topo, &u, levels[li], pieces);
        assert_eq!(pieces.len(), 1, "level {}", levels[li]);
        let iso = &pieces[0];
        assert!(iso.closed);
        assert_eq!(iso.level_index, li);
        let r = levels[li];
        for p in &iso.points {
            // Chord error of the PL interpolant: O(h^2 / r).
            assert!(((*p - c0).length() - r).abs() < 0.05 * 0.05 / r);
        }
        // Higher values on the right of the direction of travel, normal +z: counter-clockwise.
        let area = signed_area_xy(&iso.points.iter().map(|p| *p - c0).collect::<Vec<_>>());
        assert!(area > 0.0);
        let expected = std::f64::consts::PI * r * r;
        assert!(
            (area - expected).abs() < 0.02 * expected,
            "area {area} vs {expected}"
        );
        assert!((iso.length() - 2.0 * std::f64::consts::PI * r).abs() < 0.02 * r);
    }
}

#[test]
fn plane_arc_ends_on_border() {
    let mesh = grid_plane(20, 0.1, -1.0, 0.25, 3, |_| false);
    let topo = Topology::new(&mesh);
    let corner = DVec3::new(-1.0, -1.0, 0.0);
    let u = field(&mesh, |p| (p - corner).length());
    let all = isolines(&mesh, &topo, &u, &[1.0]).unwrap();
    check_structure(&mesh, &topo, &u, 1.0, &all[0]);
    assert_eq!(all[0].len(), 1);
    let iso = &all[0][0];
    assert!(!iso.closed);
    // Counter-clockwise around the corner: starts near the x axis, ends near the y axis.
    let first = iso.points[0];
    let last = *iso.points.last().unwrap();
    assert!((first.y + 1.0).abs() < 1e-12, "first {first}");
    assert!((last.x + 1.0).abs() < 1e-12, "last {last}");
}

#[test]
fn sphere_levels_are_single_closed_loops() {
    let mesh = icosphere(3);
    let topo = Topology::new(&mesh);
    let pole = DVec3::Z;
    let u = field(&mesh, |p| p.normalize().dot(pole).clamp(-1.0, 1.0).acos());
    let levels: Vec<f64> = (1..10).map(|i| i as f64 * 0.3).collect();
    let all = isolines(&mesh, &topo, &u, &levels).unwrap();
    for (li, pieces) in all.iter().enumerate() {
        check_structure(&mesh, &topo, &u, levels[li], pieces);
        assert_eq!(pieces.len(), 1, "level {}", levels[li]);
        assert!(pieces[0].closed);
        // Orientation: with outward normals, travel along n x grad U; grad U points away from
        // the pole, so seen from outside the pole the loop turns counter-clockwise about +z
        // ... i.e. its "area vector" about the z axis has the sign of +z.
        let p = &pieces[0].points;
        let mut a = DVec3::ZERO;
        for i in 0..p.len() {
            a += p[i].cross(p[(i + 1) % p.len()]);
        }
        assert!(a.z > 0.0, "level {}: {a}", levels[li]);
        let z = levels[li].cos();
        for q in p {
            assert!((q.z - z).abs() < 0.02, "{} vs {z}", q.z);
        }
    }
}

#[test]
fn hole_splits_isolines_without_bridging() {
    let mesh = grid_plane(30, 2.0 / 30.0, -1.0, 0.2, 11, |c| c.length() < 0.35);
    let topo = Topology::new(&mesh);
    assert_eq!(topo.boundary_loops().len(), 2);
    // Linear field: the isoline is exact, x = c.
    let u = field(&mesh, |p| p.x);
    let all = isolines(&mesh, &topo, &u, &[0.0, 0.1, 0.6]).unwrap();
    for (li, &c) in [0.0, 0.1, 0.6].iter().enumerate() {
        let pieces = &all[li];
        check_structure(&mesh, &topo, &u, c, pieces);
        for iso in pieces {
            assert!(!iso.closed);
            for p in &iso.points {
                assert!((p.x - c).abs() < 1e-12);
            }
            // Orientation: grad U = +x, normal +z, travel along z x x = +y.
            assert!(iso.points.last().unwrap().y > iso.points[0].y);
            // Never across the hole.
            for j in 0..iso.n_segments() {
                let (a, b) = iso.segment(j);
                assert!((a - b).length() < 0.2);
            }
        }
        let expected = if c.abs() < 0.3 { 2 } else { 1 };
        assert_eq!(pieces.len(), expected, "level {c}");
    }
}

#[test]
fn exact_level_vertices_give_clean_curves() {
    // Integer grid, integer field values, integer levels: many vertices exactly on the level.
    let mesh = grid_plane(10, 1.0, 0.0, 0.0, 0, |_| false);
    let topo = Topology::new(&mesh);
    let u = field(&mesh, |p| (p.x + p.y).round());
    let levels: Vec<f64> = (0..=20).map(|i| i as f64).collect();
    let all = isolines(&mesh, &topo, &u, &levels).unwrap();
    for (li, pieces) in all.iter().enumerate() {
        let c = levels[li];
        check_structure(&mesh, &topo, &u, c, pieces);
        if c == 0.0 {
            // Everything is >= 0: nothing is crossed.
            assert!(pieces.is_empty());
            continue;
        }
        assert_eq!(pieces.len(), 1, "level {c}");
        for p in &pieces[0].points {
            assert!((p.x + p.y - c).abs() < 1e-12);
        }
    }
    // Chebyshev-like field with plateaus exactly at levels.
    let u2 = field(&mesh, |p| (p.x - 5.0).abs().max((p.y - 5.0).abs()));
    let all = isolines(&mesh, &topo, &u2, &[1.0, 2.0, 3.0]).unwrap();
    for (li, pieces) in all.iter().enumerate() {
        check_structure(&mesh, &topo, &u2, [1.0, 2.0, 3.0][li], pieces);
        assert_eq!(pieces.len(), 1);
        assert!(pieces[0].closed);
    }
}

#[test]
fn non_finite_values_are_skipped_like_holes() {
    let mesh = grid_plane(20, 0.1, -1.0, 0.0, 0, |_| false);
    let topo = Topology::new(&mesh);
    let mut u = field(&mesh, |p| p.x);
    // Unreachable band along y in [-0.05, 0.05].
    for (v, p) in mesh.positions().iter().enumerate() {
        if p.y.abs() < 0.05 {
            u[v] = if v % 2 == 0 { f64::INFINITY } else { f64::NAN };
        }
    }
    let all = isolines(&mesh, &topo, &u, &[0.25]).unwrap();
    check_structure(&mesh, &topo, &u, 0.25, &all[0]);
    assert_eq!(all[0].len(), 2);
    for iso in &all[0] {
        assert!(!iso.closed);
        assert!(iso
            .points
            .iter()
            .all(|p| p.is_finite() && (p.x - 0.25).abs() < 1e-12));
    }
}

#[test]
fn errors_are_reported() {
    let mesh = grid_plane(2, 1.0, 0.0, 0.0, 0, |_| false);
    let topo = Topology::new(&mesh);
    assert!(matches!(
        isolines(&mesh, &topo, &[0.0; 3], &[0.5]),
        Err(levelcurves::LevelCurveError::FieldLength {
            expected: 9,
            got: 3
        })
    ));
    let u = vec![0.0; 9];
    assert!(matches!(
        isolines(&mesh, &topo, &u, &[0.5, f64::NAN]),
        Err(levelcurves::LevelCurveError::NonFiniteLevel { index: 1, .. })
    ));
    assert!(isolines_uniform(&mesh, &topo, &u, 0.0, 3).is_err());
    let other = grid_plane(3, 1.0, 0.0, 0.0, 0, |_| false);
    assert!(isolines(&other, &topo, &[0.0; 16], &[0.5]).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn uniform_range_matches_brute_force(min in -5.0f64..5.0, span in 0.0f64..3.0, step in 0.05f64..1.0) {
        let max = min + span;
        let r = uniform_level_range(min, max, step, 200);
        let brute: Vec<u32> = (1..=200u32).filter(|&i| min < i as f64 * step && i as f64 * step <= max).collect();
        prop_assert_eq!(r.collect::<Vec<_>>(), brute);
    }

    #[test]
    fn random_fields_give_consistent_isolines(
        seed in 0u64..1000,
        a in -1.0f64..1.0, b in -1.0f64..1.0, q in 0.0f64..2.0,
        quant in prop::bool::ANY,
    ) {
        let mesh = grid_plane(12, 1.0 / 12.0, 0.0, 0.4, seed, |c| (c - DVec3::new(0.5, 0.5, 0.0)).length() < 0.15);
        let topo = Topology::new(&mesh);
        let u = field(&mesh, |p| {
            let v = a * p.x + b * p.y + q * (p.x * p.x - p.y * p.y + p.x * p.y);
            if quant { (v * 8.0).round() / 8.0 } else { v }
        });
        let step = 0.125;
        let lo = u.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = u.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let levels: Vec<f64> = ((lo / step).floor() as i64..=(hi / step).ceil() as i64).map(|i| i as f64 * step).collect();
        let all = isolines(&mesh, &topo, &u, &levels).unwrap();
        for (li, pieces) in all.iter().enumerate() {
            let c = levels[li];
            check_structure(&mesh, &topo, &u, c, pieces);
            // Every crossed edge of the mesh appears exactly once (before duplicate removal a
            // vertex at the level is shared, so count edges, not points, only when no vertex
            // is exactly at the level).
            if !u.contains(&c) {
                let mut seen = HashSet::new();
                for iso in pieces {
                    for e in &iso.edge_of {
                        prop_assert!(seen.insert(*e), "edge {:?} twice", e);
                    }
                }
                let crossed: HashSet<(u32, u32)> = topo.edges().iter()
                    .filter(|e| (u[e.v[0] as usize] >= c) != (u[e.v[1] as usize] >= c))
                    .map(|e| (e.v[0], e.v[1])).collect();
                prop_assert_eq!(seen, crossed);
            }
            // Orientation: every segment agrees with n x grad U (normal +z).
            for iso in pieces {
                let mut agree = 0i32;
                for j in 0..iso.n_segments() {
                    let f = iso.face_of[j];
                    let tri = mesh.triangles()[f as usize];
                    let g = levelcurves::face_gradient(mesh.face_corners(f), tri.map(|v| u[v as usize]));
                    let (p0, p1) = iso.segment(j);
                    let s = (p1 - p0).dot(DVec3::Z.cross(g));
                    if s > 0.0 { agree += 1 } else if s < 0.0 { agree -= 1 }
                }
                prop_assert!(agree >= 0);
                prop_assert_eq!(agree as usize, iso.n_segments());
            }
        }
        // The uniform variant gives the same curves for the positive levels.
        let npos = (hi / step).floor().max(0.0) as u32;
        let uni = isolines_uniform(&mesh, &topo, &u, step, npos).unwrap();
        let lv = uniform_levels(step, npos).unwrap();
        let direct = isolines(&mesh, &topo, &u, &lv).unwrap();
        prop_assert_eq!(uni, direct);
    }
}

#[test]
fn gradient_formula_reproduces_differences() {
    let p = [
        DVec3::new(0.1, 0.2, 0.3),
        DVec3::new(1.2, -0.3, 0.5),
        DVec3::new(-0.2, 0.9, 1.1),
    ];
    let u = [0.3, -1.2, 2.5];
    let g = levelcurves::face_gradient(p, u);
    assert!((g.dot(p[1] - p[0]) - (u[1] - u[0])).abs() < 1e-12);
    assert!((g.dot(p[2] - p[0]) - (u[2] - u[0])).abs() < 1e-12);
    assert!(g.dot((p[1] - p[0]).cross(p[2] - p[0])).abs() < 1e-12);
    assert_eq!(
        levelcurves::face_gradient([p[0], p[0], p[1]], u),
        DVec3::ZERO
    );
}
