//! Decimation to a target edge length by shortest-edge collapse with midpoint placement.

use crate::mesh::compact;
use crate::ScanPrepError;
use meshcore::TriMesh;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// What [`decimate`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DecimationReport {
    /// The target edge length (mm).
    pub target_edge: f64,
    /// Vertices before.
    pub vertices_before: usize,
    /// Vertices after.
    pub vertices_after: usize,
    /// Mean edge length before.
    pub mean_edge_before: f64,
    /// Mean edge length after.
    pub mean_edge_after: f64,
    /// Edges collapsed.
    pub collapses: usize,
}

/// Edges shorter than this times the target are collapsed (Botsch and Kobbelt's remeshing
/// bounds: 4/5 and 4/3 of the target).
pub const COLLAPSE_BELOW: f64 = 0.8;
/// A collapse that would make an edge longer than this times the target is not done.
pub const MAX_NEW_EDGE: f64 = 4.0 / 3.0;

/// A collapse candidate in the min-heap: (length, a, b, version of a, version of b) packed so
/// that integer order is the order of the tuple (a length is never negative, and for those
/// `f64::to_bits` orders as `f64::total_cmp`).
type Cand = Reverse<(u64, u64, u64)>;

fn cand(len: f64, a: u32, b: u32, va: u32, vb: u32) -> Cand {
    let pack = |x: u32, y: u32| (u64::from(x) << 32) | u64::from(y);
    Reverse((len.to_bits(), pack(a, b), pack(va, vb)))
}

/// Collapses edges, shortest first, while an edge is shorter than `COLLAPSE_BELOW * target`;
/// the surviving vertex goes to the edge midpoint, or stays on the boundary when one end is a
/// boundary vertex. A collapse is skipped when it would break the link condition (the mesh
/// stays manifold where it was), pinch a boundary (an interior edge between two boundary
/// vertices), turn a face by more than 60 degrees, or make an edge longer than
/// `MAX_NEW_EDGE * target`. Midpoints lie inside a convex surface: on a sphere of radius `R`
/// vertices sink by about the sagitta `target^2 / (8 R)` of a target edge. Deterministic: ties in length go to the smaller vertex ids. Only
/// coarsens: a mesh whose edges are already long enough comes back unchanged.
pub fn decimate(mesh: &TriMesh, target: f64) -> Result<(TriMesh, DecimationReport), ScanPrepError> {
    if !(target.is_finite() && target > 0.0) {
        return Err(ScanPrepError::InvalidOption(format!(
            "target edge length {target} (expected > 0)"
        )));
    }
    let n = mesh.n_vertices();
    let mut pos = mesh.positions().to_vec();
    let mut tris = mesh.triangles().to_vec();
    let mut face_alive = vec![true; tris.len()];
    let mut vf: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (f, t) in tris.iter().enumerate() {
        for &v in t {
            if !vf[v as usize].contains(&(f as u32)) {
                vf[v as usize].push(f as u32);
            }
        }
    }
    let mut vert_alive = vec![true; n];
    let mut version = vec![0u32; n];
    let lo = COLLAPSE_BELOW * target;
    let hi = MAX_NEW_EDGE * target;
    // Each short edge once (an edge of two faces would be a second, identical candidate).
    let mut first: Vec<Cand> = Vec::new();
    for t in &tris {
        for k in 0..3 {
            let (a, b) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
            let len = (pos[a as usize] - pos[b as usize]).length();
            if a != b && len < lo {
                first.push(cand(len, a, b, 0, 0));
            }
        }
    }
    first.sort_unstable();
    first.dedup();
    let mut heap = BinaryHeap::from(first);
    let before_mean = mesh.mean_edge_length();
    let mut collapses = 0usize;
    // Scratch lists reused by every candidate: the faces on the edge, the two rings.
    let (mut ef, mut ra, mut rb) = (Vec::new(), Vec::new(), Vec::new());
    while let Some(Reverse((_, ab, vab))) = heap.pop() {
        let (a, b) = ((ab >> 32) as u32, ab as u32);
        if !vert_alive[a as usize]
            || !vert_alive[b as usize]
            || version[a as usize] != (vab >> 32) as u32
            || version[b as usize] != vab as u32
        {
            continue;
        }
        ef.clear();
        ef.extend(
            vf[a as usize]
                .iter()
                .copied()
                .filter(|&f| tris[f as usize].contains(&b)),
        );
        if ef.is_empty() || ef.len() > 2 {
            continue;
        }
        let ba = star(a, &vf, &tris, &mut ra);
        let bb = star(b, &vf, &tris, &mut rb);
        let common = ra.iter().filter(|w| rb.binary_search(w).is_ok()).count();
        if common != ef.len() {
            continue;
        }
        if ef.len() == 2 && ba && bb {
            continue;
        }
        let target_pos = match (ba, bb) {
            (true, false) => pos[a as usize],
            (false, true) => pos[b as usize],
            _ => 0.5 * (pos[a as usize] + pos[b as usize]),
        };
        if ra
            .iter()
            .chain(rb.iter())
            .any(|&w| w != a && w != b && (pos[w as usize] - target_pos).length() > hi)
        {
            continue;
        }
        let mut ok = true;
        for &f in vf[a as usize].iter().chain(vf[b as usize].iter()) {
            let t = tris[f as usize];
            if t.contains(&a) && t.contains(&b) {
                continue;
            }
            let q = t.map(|v| pos[v as usize]);
            let n0 = (q[1] - q[0]).cross(q[2] - q[0]);
            let q1 = t.map(|v| {
                if v == a || v == b {
                    target_pos
                } else {
                    pos[v as usize]
                }
            });
            let n1 = (q1[1] - q1[0]).cross(q1[2] - q1[0]);
            if n1.length_squared() <= 1e-24 * n0.length_squared().max(1e-300)
                || n0.dot(n1) <= 0.5 * n0.length() * n1.length()
            {
                ok = false;
                break;
            }
        }
        if !ok {
            continue;
        }
        // Collapse b into a.
        pos[a as usize] = target_pos;
        for &f in &ef {
            face_alive[f as usize] = false;
        }
        let fb = std::mem::take(&mut vf[b as usize]);
        for f in fb {
            if !face_alive[f as usize] {
                continue;
            }
            for v in tris[f as usize].iter_mut() {
                if *v == b {
                    *v = a;
                }
            }
            vf[a as usize].push(f);
        }
        for w in ra.iter().chain(rb.iter()) {
            vf[*w as usize].retain(|&f| face_alive[f as usize]);
        }
        vf[a as usize].retain(|&f| face_alive[f as usize]);
        vf[a as usize].sort_unstable();
        vf[a as usize].dedup();
        vert_alive[b as usize] = false;
        version[a as usize] += 1;
        collapses += 1;
        star(a, &vf, &tris, &mut ra);
        for &w in &ra {
            let len = (pos[w as usize] - pos[a as usize]).length();
            if len < lo {
                let (x, y) = (a.min(w), a.max(w));
                heap.push(cand(len, x, y, version[x as usize], version[y as usize]));
            }
        }
    }
    let kept: Vec<[u32; 3]> = tris
        .iter()
        .zip(&face_alive)
        .filter(|(_, &al)| al)
        .map(|(t, _)| *t)
        .collect();
    let (out, _) = compact(&pos, kept, "decimation")?;
    let report = DecimationReport {
        target_edge: target,
        vertices_before: n,
        vertices_after: out.n_vertices(),
        mean_edge_before: before_mean,
        mean_edge_after: out.mean_edge_length(),
        collapses,
    };
    Ok((out, report))
}

/// The ring of `v` (its neighbours in its faces `vf[v]`, sorted, once each) into `ring`, and
/// whether `v` is on a boundary: some neighbour shares other than two of those faces with it.
fn star(v: u32, vf: &[Vec<u32>], tris: &[[u32; 3]], ring: &mut Vec<u32>) -> bool {
    ring.clear();
    for &f in &vf[v as usize] {
        let t = tris[f as usize];
        // Each neighbour once per face: the face counts once for that edge.
        for (k, &w) in t.iter().enumerate() {
            if w != v && !t[..k].contains(&w) {
                ring.push(w);
            }
        }
    }
    ring.sort_unstable();
    let mut boundary = false;
    let mut i = 0;
    let mut out = 0;
    while i < ring.len() {
        let w = ring[i];
        let mut j = i + 1;
        while j < ring.len() && ring[j] == w {
            j += 1;
        }
        boundary |= j - i != 2;
        ring[out] = w;
        out += 1;
        i = j;
    }
    ring.truncate(out);
    boundary
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshcore::shapes;

    #[test]
    fn a_sphere_reaches_the_target_and_stays_on_the_sphere() {
        let s = shapes::icosphere(5);
        let r = 50.0;
        let m = TriMesh::new(
            s.positions().iter().map(|p| *p * r).collect(),
            s.triangles().to_vec(),
        )
        .unwrap();
        let before = m.mean_edge_length();
        let target = 4.0 * before;
        let (d, rep) = decimate(&m, target).unwrap();
        assert!(rep.vertices_after < m.n_vertices() / 8, "{rep:?}");
        let e = d.mean_edge_length();
        assert!(e > 0.7 * target && e < 1.4 * target, "{e} vs {target}");
        let worst = d
            .positions()
            .iter()
            .map(|p| (p.length() - r).abs())
            .fold(0.0f64, f64::max);
        // Midpoints of chords sink: no more than twice the sagitta t^2 / (8 R) of a target edge.
        assert!(worst < target * target / (4.0 * r), "{worst}");
        let topo = meshcore::Topology::new(&d);
        assert!(topo.is_oriented_manifold());
        assert_eq!(topo.boundary_loops().len(), 0);
        assert_eq!(topo.n_components(), 1);
        // Deterministic, and a no-op below the current edge length.
        assert_eq!(decimate(&m, target).unwrap().0, d);
        assert_eq!(decimate(&m, 0.1 * before).unwrap().0, m);
        assert!(decimate(&m, f64::NAN).is_err());
    }
}
