//! Test meshes shared by the facecurves tests: an ellipsoid with its analytic principal
//! curvatures, and a rigidly moved, renumbered copy of a mesh.

#![allow(dead_code)]

use glam::{DAffine3, DMat3, DVec3};
use meshcore::TriMesh;
use rand::seq::SliceRandom;
use rand::SeedableRng;

/// Icosphere of `level` scaled by `axes` (semi-axes a, b, c).
pub fn ellipsoid(axes: DVec3, level: u32) -> TriMesh {
    let m = testsupport::shapes::icosphere(level);
    let p = m.positions().iter().map(|p| *p * axes).collect();
    TriMesh::new(p, m.triangles().to_vec()).unwrap()
}

/// The point of the ellipsoid on the ray from its centre through `p`.
pub fn project_to_ellipsoid(axes: DVec3, p: DVec3) -> DVec3 {
    let s = (p / axes).length();
    p / s
}

/// Analytic principal curvatures `(k1, k2)`, `k1 >= k2`, of the ellipsoid
/// `x^2/a^2 + y^2/b^2 + z^2/c^2 = 1` at its point `p` (outward normals, positive).
pub fn ellipsoid_curvatures(axes: DVec3, p: DVec3) -> (f64, f64) {
    let (a2, b2, c2) = (axes.x * axes.x, axes.y * axes.y, axes.z * axes.z);
    let s = p.x * p.x / (a2 * a2) + p.y * p.y / (b2 * b2) + p.z * p.z / (c2 * c2);
    let k = 1.0 / (a2 * b2 * c2 * s * s);
    let h = (a2 + b2 + c2 - p.length_squared()) / (2.0 * a2 * b2 * c2 * s.powf(1.5));
    let d = (h * h - k).max(0.0).sqrt();
    (h + d, h - d)
}

/// `mesh` under a rigid motion, with its vertices renumbered by a seeded permutation; returns
/// the new mesh and `perm` (old vertex `v` is new vertex `perm[v]`).
pub fn moved_and_renumbered(mesh: &TriMesh, seed: u64) -> (TriMesh, Vec<u32>) {
    let n = mesh.n_vertices();
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
    // order[new] = old; perm[old] = new.
    let mut perm = vec![0u32; n];
    for (new, &old) in order.iter().enumerate() {
        perm[old as usize] = new as u32;
    }
    let m = DAffine3::from_mat3_translation(
        DMat3::from_axis_angle(DVec3::new(-0.4, 0.7, 0.2).normalize(), 1.3),
        DVec3::new(12.0, -3.0, 5.0),
    );
    let pos = order
        .iter()
        .map(|&old| m.transform_point3(mesh.position(old)))
        .collect();
    let tris = mesh
        .triangles()
        .iter()
        .map(|t| t.map(|v| perm[v as usize]))
        .collect();
    (TriMesh::new(pos, tris).unwrap(), perm)
}
