//! Opt-in repairs. Nothing in the workspace repairs a mesh unless the user asks.

use crate::{MeshError, TriMesh};
use glam::DVec3;
use std::collections::HashMap;

/// What a repair changed.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RepairReport {
    /// Vertices merged into an earlier duplicate.
    pub welded_vertices: usize,
    /// Faces removed as degenerate (repeated vertex or near-zero area).
    pub removed_faces: usize,
    /// Vertices removed because no face used them any more.
    pub removed_vertices: usize,
}

/// Merges vertices closer than `tol` (absolute; e.g. `1e-9 * bbox diagonal`), keeping the first
/// occurrence, then drops faces that became degenerate and unused vertices.
pub fn weld_vertices(mesh: &TriMesh, tol: f64) -> Result<(TriMesh, RepairReport), MeshError> {
    let tol = tol.max(0.0);
    let inv = if tol > 0.0 { 1.0 / tol } else { 0.0 };
    let key = |p: DVec3| -> (i64, i64, i64) {
        if tol > 0.0 {
            (
                (p.x * inv).floor() as i64,
                (p.y * inv).floor() as i64,
                (p.z * inv).floor() as i64,
            )
        } else {
            (
                p.x.to_bits() as i64,
                p.y.to_bits() as i64,
                p.z.to_bits() as i64,
            )
        }
    };
    let mut grid: HashMap<(i64, i64, i64), Vec<u32>> = HashMap::new();
    let mut remap = vec![0u32; mesh.n_vertices()];
    let mut report = RepairReport::default();
    for (i, &p) in mesh.positions().iter().enumerate() {
        let k = key(p);
        let mut found = None;
        if tol > 0.0 {
            'outer: for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        if let Some(list) = grid.get(&(k.0 + dx, k.1 + dy, k.2 + dz)) {
                            for &j in list {
                                if (mesh.positions()[j as usize] - p).length() <= tol {
                                    found = Some(j);
                                    break 'outer;
                                }
                            }
                        }
                    }
                }
            }
        } else if let Some(list) = grid.get(&k) {
            found = list.first().copied();
        }
        match found {
            Some(j) => {
                remap[i] = j;
                report.welded_vertices += 1;
            }
            None => {
                remap[i] = i as u32;
                grid.entry(k).or_default().push(i as u32);
            }
        }
    }
    let tris: Vec<[u32; 3]> = mesh
        .triangles()
        .iter()
        .map(|t| {
            [
                remap[t[0] as usize],
                remap[t[1] as usize],
                remap[t[2] as usize],
            ]
        })
        .collect();
    let (m, r) = compact(mesh.positions(), tris, 0.0)?;
    report.removed_faces = r.removed_faces;
    report.removed_vertices = r.removed_vertices;
    Ok((m, report))
}

/// Removes faces with a repeated vertex or area `<= rel_tol * bbox_diagonal^2`, then unused
/// vertices.
pub fn remove_degenerate_faces(
    mesh: &TriMesh,
    rel_tol: f64,
) -> Result<(TriMesh, RepairReport), MeshError> {
    let d = mesh.bbox().diagonal();
    compact(mesh.positions(), mesh.triangles().to_vec(), rel_tol * d * d)
}

fn compact(
    positions: &[DVec3],
    tris: Vec<[u32; 3]>,
    area_thr: f64,
) -> Result<(TriMesh, RepairReport), MeshError> {
    let n_before = tris.len();
    let kept: Vec<[u32; 3]> = tris
        .into_iter()
        .filter(|t| {
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return false;
            }
            let [a, b, c] = t.map(|v| positions[v as usize]);
            0.5 * (b - a).cross(c - a).length() > area_thr
        })
        .collect();
    let mut new_index = vec![u32::MAX; positions.len()];
    let mut pos = Vec::new();
    let mut out = Vec::with_capacity(kept.len());
    for t in &kept {
        let mut nt = [0u32; 3];
        for k in 0..3 {
            let v = t[k] as usize;
            if new_index[v] == u32::MAX {
                new_index[v] = pos.len() as u32;
                pos.push(positions[v]);
            }
            nt[k] = new_index[v];
        }
        out.push(nt);
    }
    let report = RepairReport {
        welded_vertices: 0,
        removed_faces: n_before - out.len(),
        removed_vertices: positions.len() - pos.len(),
    };
    Ok((TriMesh::new(pos, out)?, report))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weld_and_drop() {
        // Two triangles written as separate soups (STL style) sharing an edge, plus a sliver.
        let p = vec![
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::X,
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::Y + DVec3::splat(1e-13),
        ];
        let m = TriMesh::new(p, vec![[0, 1, 2], [3, 4, 5], [0, 0, 1]]).unwrap();
        let (w, r) = weld_vertices(&m, 1e-9).unwrap();
        assert_eq!(w.n_vertices(), 4);
        assert_eq!(w.n_faces(), 2);
        assert_eq!(r.welded_vertices, 2);
        assert_eq!(r.removed_faces, 1);
        let (d, r) = remove_degenerate_faces(&m, 1e-12).unwrap();
        assert_eq!(d.n_faces(), 2);
        assert_eq!(r.removed_faces, 1);
    }
}
