//! Analytic distance fields, the oracles the tests compare computed geodesic fields with, and
//! the differences between two fields that the comparisons bound.

use meshcore::{DVec3, TriMesh};
use std::f64::consts::{PI, TAU};

/// Euclidean distance from `c` to every vertex: the geodesic distance on a convex planar
/// domain (and a lower bound elsewhere).
pub fn euclidean(mesh: &TriMesh, c: DVec3) -> Vec<f64> {
    mesh.positions().iter().map(|p| (*p - c).length()).collect()
}

/// Great-circle distance on the sphere of radius `radius` centred at the origin from the
/// direction of `c` to the direction of every vertex (vertices are projected on the sphere).
pub fn sphere_geodesic(mesh: &TriMesh, c: DVec3, radius: f64) -> Vec<f64> {
    let c = c.normalize();
    mesh.positions()
        .iter()
        .map(|p| radius * p.normalize().dot(c).clamp(-1.0, 1.0).acos())
        .collect()
}

/// Geodesic distance on the round cylinder of radius `r` about the z axis from `s` to every
/// vertex: `sqrt((r * angle)^2 + dz^2)`, the angle between the two around the axis taken the
/// short way (in `[0, pi]`).
pub fn cylinder_geodesic(mesh: &TriMesh, r: f64, s: DVec3) -> Vec<f64> {
    let a0 = s.y.atan2(s.x);
    mesh.positions()
        .iter()
        .map(|p| {
            let mut a = (p.y.atan2(p.x) - a0).abs();
            if a > PI {
                a = TAU - a;
            }
            ((r * a).powi(2) + (p.z - s.z).powi(2)).sqrt()
        })
        .collect()
}

/// Geodesic distance on the open prism `meshcore::shapes::cylinder(r, _, na, _)` from vertex
/// `src` to every vertex. The prism is developable: unrolled it is a flat strip on which
/// consecutive vertices of a ring lie one chord `2 r sin(pi / na)` apart, so the distance is
/// the Euclidean one in the strip, the shorter way around.
pub fn prism_geodesic(mesh: &TriMesh, r: f64, na: usize, src: u32) -> Vec<f64> {
    let chord = 2.0 * r * (PI / na as f64).sin();
    let (si, sz) = (src as usize % na, mesh.position(src).z);
    mesh.positions()
        .iter()
        .enumerate()
        .map(|(v, p)| {
            let di = (v % na).abs_diff(si);
            let k = di.min(na - di) as f64;
            ((k * chord).powi(2) + (p.z - sz).powi(2)).sqrt()
        })
        .collect()
}

/// Largest `|a[i] - b[i]|` (0 for empty fields).
pub fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Mean of `|a[i] - b[i]|` over the length of `a`.
pub fn mean_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f64>() / a.len() as f64
}

/// Largest relative error `|got[i] - want[i]| / want[i]` over the entries with
/// `want[i] > min_want` (away from the source, where a relative error means something).
pub fn max_rel_err(got: &[f64], want: &[f64], min_want: f64) -> f64 {
    got.iter()
        .zip(want)
        .filter(|(_, w)| **w > min_want)
        .map(|(g, w)| (g - w).abs() / w)
        .fold(0.0, f64::max)
}

/// Largest relative difference `|a[i] - b[i]| / max(|b[i]|, floor)` over the finite entries;
/// panics (naming the vertex) when `a` and `b` differ in length or in which entries are
/// infinite.
pub fn max_rel_diff(a: &[f64], b: &[f64], floor: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    let mut m = 0.0f64;
    for (i, (&x, &y)) in a.iter().zip(b).enumerate() {
        assert_eq!(x.is_finite(), y.is_finite(), "vertex {i}: {x} vs {y}");
        if x.is_finite() {
            m = m.max((x - y).abs() / y.abs().max(floor));
        }
    }
    m
}

/// Panics, naming the first vertex and `what`, unless every `got[v]` is within
/// `rel * max(|want[v]|, 1)` of `want[v]` (relative for distances above 1, absolute below) and
/// the fields have the same length.
#[track_caller]
pub fn assert_close(got: &[f64], want: &[f64], rel: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: field lengths");
    for (v, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= rel * w.abs().max(1.0),
            "{what}: vertex {v}: {g} vs {w}"
        );
    }
}

/// A refinement study on the unit icosphere: for levels 2, 3 and 4, `(level, mean edge length,
/// mean absolute error, max absolute error)` of `field(mesh)` (the distance from vertex 0)
/// against the great-circle distance [`sphere_geodesic`].
pub fn icosphere_errors(field: impl Fn(&TriMesh) -> Vec<f64>) -> Vec<(u32, f64, f64, f64)> {
    (2..=4)
        .map(|level| {
            let m = meshcore::shapes::icosphere(level);
            let g = sphere_geodesic(&m, m.position(0), 1.0);
            let d = field(&m);
            let h = m.mean_edge_length();
            (level, h, mean_abs_diff(&d, &g), max_abs_diff(&d, &g))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshcore::shapes::{cylinder, grid_plane, icosphere};

    #[test]
    fn fields_vanish_at_the_source_and_match_known_values() {
        let g = grid_plane(4, 0.5, 0.0, 0.0, 0, |_| false);
        let d = euclidean(&g, DVec3::ZERO);
        assert_eq!(d[0], 0.0);
        assert!((d[g.n_vertices() - 1] - 8f64.sqrt()).abs() < 1e-15);

        let s = icosphere(2);
        let d = sphere_geodesic(&s, s.position(0), 2.0);
        assert_eq!(d[0], 0.0);
        let far = (0..s.n_vertices())
            .min_by(|&a, &b| {
                let da = s.position(a as u32).dot(s.position(0));
                da.total_cmp(&s.position(b as u32).dot(s.position(0)))
            })
            .unwrap();
        assert!((d[far] - 2.0 * PI).abs() < 1e-9, "antipode {}", d[far]);

        let c = cylinder(1.0, 2.0, 8, 2);
        let round = cylinder_geodesic(&c, 1.0, c.position(0));
        let flat = prism_geodesic(&c, 1.0, 8, 0);
        // Vertex 4 is half way round the bottom ring; vertex 8 is straight above vertex 0.
        assert!((round[4] - PI).abs() < 1e-12);
        assert!((flat[4] - 4.0 * 2.0 * (PI / 8.0).sin()).abs() < 1e-12);
        assert!((round[8] - 1.0).abs() < 1e-12 && (flat[8] - 1.0).abs() < 1e-12);
        // The polygon is shorter around than the circle.
        assert!(flat[4] < round[4]);
    }
}
