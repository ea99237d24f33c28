//! Opt-in repairs. Nothing in the workspace repairs a mesh unless the user asks; this is the
//! one implementation (`mesh_io::LoadedMesh::weld` and `drop_degenerate` delegate here and
//! carry their per-vertex extras along [`Repaired::source_vertices`]).

use crate::{MeshError, TriMesh};
use glam::DVec3;
use std::collections::HashMap;

/// What a repair changed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RepairReport {
    /// Vertices merged into an earlier one.
    pub welded_vertices: usize,
    /// Faces removed (degenerate, or collapsed by welding).
    pub removed_faces: usize,
    /// Vertices removed because no face used them any more (welded vertices not counted).
    pub removed_vertices: usize,
}

/// A repaired mesh and where its vertices came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Repaired {
    /// The repaired mesh.
    pub mesh: TriMesh,
    /// For each vertex of [`Repaired::mesh`], the index of the vertex of the input mesh it is
    /// (per-vertex data of the input follow through `source_vertices.iter().map(|&v| data[v])`).
    /// Vertices keep their relative order of first use by the kept faces.
    pub source_vertices: Vec<u32>,
    /// What changed.
    pub report: RepairReport,
}

/// For each vertex, the index of the first vertex within `tol` of it (itself if none). `tol`
/// is an absolute length; `0` (or a negative or NaN value) merges exact duplicates only, with
/// `+0.0` and `-0.0` equal.
pub fn weld_map(positions: &[DVec3], tol: f64) -> Vec<u32> {
    let tol = tol.max(0.0);
    let p = positions;
    let mut remap: Vec<u32> = (0..p.len() as u32).collect();
    if tol == 0.0 {
        // Sort (coordinates, index) and give every run of equal coordinates its first index:
        // cache-friendly, unlike a hash table of half a million random probes.
        let mut keyed: Vec<([u64; 3], u32)> = p
            .iter()
            .enumerate()
            // +0.0 and -0.0 are the same point.
            .map(|(i, q)| {
                (
                    [q.x + 0.0, q.y + 0.0, q.z + 0.0].map(f64::to_bits),
                    i as u32,
                )
            })
            .collect();
        keyed.sort_unstable();
        let mut start = 0;
        while start < keyed.len() {
            let mut end = start + 1;
            while end < keyed.len() && keyed[end].0 == keyed[start].0 {
                remap[keyed[end].1 as usize] = keyed[start].1;
                end += 1;
            }
            start = end;
        }
        return remap;
    }
    let inv = 1.0 / tol;
    let cell = |q: DVec3| {
        [
            (q.x * inv).floor() as i64,
            (q.y * inv).floor() as i64,
            (q.z * inv).floor() as i64,
        ]
    };
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    for (i, &q) in p.iter().enumerate() {
        let k = cell(q);
        let mut found = None;
        'outer: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        if let Some(&j) =
                            list.iter().find(|&&j| (p[j as usize] - q).length() <= tol)
                        {
                            found = Some(j);
                            break 'outer;
                        }
                    }
                }
            }
        }
        match found {
            Some(j) => remap[i] = j,
            None => grid.entry(k).or_default().push(i as u32),
        }
    }
    remap
}

/// Merges vertices closer than `tol` (absolute length; `0` merges exact duplicates only, see
/// [`weld_map`]), keeping the first occurrence, then removes faces that collapsed and unused
/// vertices. Errors ([`MeshError::Empty`]) when no face would remain.
pub fn weld_vertices(mesh: &TriMesh, tol: f64) -> Result<Repaired, MeshError> {
    let remap = weld_map(mesh.positions(), tol);
    let welded = remap
        .iter()
        .enumerate()
        .filter(|(i, &j)| *i != j as usize)
        .count();
    let tris: Vec<[u32; 3]> = mesh
        .triangles()
        .iter()
        .map(|t| t.map(|v| remap[v as usize]))
        .collect();
    let mut r = compact(mesh.positions(), tris, 0.0)?;
    r.report.welded_vertices = welded;
    r.report.removed_vertices = r.report.removed_vertices.saturating_sub(welded);
    Ok(r)
}

/// Removes faces with a repeated vertex or an area `<= rel_tol * bbox_diagonal^2`, then unused
/// vertices. Errors ([`MeshError::Empty`]) when no face would remain.
pub fn remove_degenerate_faces(mesh: &TriMesh, rel_tol: f64) -> Result<Repaired, MeshError> {
    let d = mesh.bbox().diagonal();
    compact(mesh.positions(), mesh.triangles().to_vec(), rel_tol * d * d)
}

/// Number of vertices that exactly repeat the position of an earlier vertex.
pub fn count_duplicate_vertices(mesh: &TriMesh) -> usize {
    weld_map(mesh.positions(), 0.0)
        .iter()
        .enumerate()
        .filter(|(i, &j)| *i != j as usize)
        .count()
}

/// Faces with a repeated vertex index or zero area (exactly).
pub fn count_degenerate_faces(mesh: &TriMesh) -> usize {
    mesh.triangles()
        .iter()
        .filter(|t| {
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return true;
            }
            let [a, b, c] = t.map(|v| mesh.positions()[v as usize]);
            (b - a).cross(c - a) == DVec3::ZERO
        })
        .count()
}

fn compact(positions: &[DVec3], tris: Vec<[u32; 3]>, area_thr: f64) -> Result<Repaired, MeshError> {
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
    if kept.is_empty() {
        return Err(MeshError::Empty {
            vertices: 0,
            triangles: 0,
        });
    }
    let mut new_index = vec![u32::MAX; positions.len()];
    let mut order: Vec<u32> = Vec::new();
    let mut out = Vec::with_capacity(kept.len());
    for t in &kept {
        let mut nt = [0u32; 3];
        for k in 0..3 {
            let v = t[k] as usize;
            if new_index[v] == u32::MAX {
                new_index[v] = order.len() as u32;
                order.push(v as u32);
            }
            nt[k] = new_index[v];
        }
        out.push(nt);
    }
    let report = RepairReport {
        welded_vertices: 0,
        removed_faces: n_before - out.len(),
        removed_vertices: positions.len() - order.len(),
    };
    let pos: Vec<DVec3> = order.iter().map(|&v| positions[v as usize]).collect();
    Ok(Repaired {
        mesh: TriMesh::new(pos, out)?,
        source_vertices: order,
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weld_and_drop() {
        // Two triangles written as separate soups (STL style) sharing an edge, plus a sliver.
        let soup = crate::shapes::triangle_soup();
        let mut p = soup.positions().to_vec();
        p[5] += DVec3::splat(1e-13);
        let m = TriMesh::new(p, soup.triangles().to_vec()).unwrap();
        let w = weld_vertices(&m, 1e-9).unwrap();
        assert_eq!(w.mesh.n_vertices(), 4);
        assert_eq!(w.mesh.n_faces(), 2);
        assert_eq!(w.report.welded_vertices, 2);
        assert_eq!(w.report.removed_faces, 1);
        assert_eq!(w.report.removed_vertices, 0);
        assert_eq!(w.source_vertices, vec![0, 1, 2, 4]);
        for (new, &old) in w.source_vertices.iter().enumerate() {
            assert_eq!(w.mesh.positions()[new], m.positions()[old as usize]);
        }
        let d = remove_degenerate_faces(&m, 1e-12).unwrap();
        assert_eq!(d.mesh.n_faces(), 2);
        assert_eq!(d.report.removed_faces, 1);
        assert_eq!(d.report.removed_vertices, 0);
        assert_eq!(count_duplicate_vertices(&m), 1);
        assert_eq!(count_degenerate_faces(&m), 1);
    }

    #[test]
    fn exact_weld_merges_signed_zeros_and_refuses_to_empty() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(-0.0, 0.0, 0.0)];
        let m = TriMesh::new(p, vec![[0, 1, 2], [3, 1, 2]]).unwrap();
        assert_eq!(weld_map(m.positions(), 0.0), vec![0, 1, 2, 0]);
        let w = weld_vertices(&m, 0.0).unwrap();
        // Both faces become [0, 1, 2]: nothing collapses, the duplicate vertex goes.
        assert_eq!(w.report.welded_vertices, 1);
        assert_eq!(w.mesh.n_vertices(), 3);
        let flat =
            TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0], vec![[0, 1, 2]]).unwrap();
        assert!(matches!(
            remove_degenerate_faces(&flat, 0.0),
            Err(MeshError::Empty { .. })
        ));
    }
}
