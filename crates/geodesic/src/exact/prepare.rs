//! Preparation of the exact solver (once per mesh): half-edge structure, per-half-edge frames,
//! dropped faces, cut non-manifold edges, pseudo-source flags.

use super::*;

impl ExactGeodesic {
    /// Prepares the solver: half-edge structure, frames, pseudo-source flags.
    ///
    /// Never fails on a valid [`TriMesh`]; degenerate and non-manifold parts are handled as
    /// described in the module documentation and listed in [`ExactGeodesic::report`].
    pub fn new(mesh: &TriMesh) -> Result<Self, GeodesicError> {
        let positions = mesh.positions().to_vec();
        let tris = mesh.triangles().to_vec();
        let n = positions.len();
        let m = tris.len();
        let nh = 3 * m;
        let min_edge = 1e-12 * mesh.bbox().diagonal();
        let mut report = ExactMeshReport::default();
        let mut live = vec![true; m];
        for (f, t) in tris.iter().enumerate() {
            let bad = t[0] == t[1]
                || t[1] == t[2]
                || t[0] == t[2]
                || (0..3).any(|k| {
                    (positions[t[k] as usize] - positions[t[(k + 1) % 3] as usize]).length()
                        <= min_edge
                });
            if bad {
                live[f] = false;
                report.dropped_faces.push(f as u32);
            }
        }
        // Twins by sorting undirected edge keys.
        let mut keys: Vec<(u64, u32)> = Vec::with_capacity(nh);
        for (f, t) in tris.iter().enumerate() {
            if !live[f] {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let key = ((a.min(b) as u64) << 32) | a.max(b) as u64;
                keys.push((key, (3 * f + k) as u32));
            }
        }
        keys.sort_unstable();
        let mut twin = vec![NONE; nh];
        let tail = |h: u32| tris[(h / 3) as usize][(h % 3) as usize];
        let mut i = 0;
        while i < keys.len() {
            let mut j = i + 1;
            while j < keys.len() && keys[j].0 == keys[i].0 {
                j += 1;
            }
            match j - i {
                1 => {}
                2 => {
                    let (h1, h2) = (keys[i].1, keys[i + 1].1);
                    let rev = if tail(h1) == tail(h2) {
                        report.inconsistent_edges += 1;
                        REV
                    } else {
                        0
                    };
                    twin[h1 as usize] = h2 | rev;
                    twin[h2 as usize] = h1 | rev;
                }
                _ => report.cut_edges += 1,
            }
            i = j;
        }
        // Frames.
        let mut geom = vec![HeGeom::default(); nh];
        let mut angle = vec![0.0f64; n];
        let mut boundary = vec![false; n];
        let mut deg = vec![0u32; n + 1];
        for (f, t) in tris.iter().enumerate() {
            if !live[f] {
                continue;
            }
            for k in 0..3 {
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let (pa, pb, pc) = (
                    positions[a as usize],
                    positions[b as usize],
                    positions[c as usize],
                );
                let ab = pb - pa;
                let ac = pc - pa;
                let bc = pc - pb;
                let l = ab.length();
                let cx = ac.dot(ab) / l;
                let cy = ab.cross(ac).length() / l;
                let lac = ac.length();
                let lbc = bc.length();
                geom[3 * f + k] = HeGeom {
                    l,
                    cx,
                    cy,
                    lac,
                    lbc,
                };
                // Corner angle at a.
                angle[a as usize] += ab.cross(ac).length().atan2(ab.dot(ac));
                if twin[3 * f + k] == NONE {
                    boundary[a as usize] = true;
                    boundary[b as usize] = true;
                }
                deg[c as usize + 1] += 1;
            }
        }
        for v in 0..n {
            deg[v + 1] += deg[v];
        }
        let mut fill = deg.clone();
        let mut vopp = vec![0u32; deg[n] as usize];
        for (f, t) in tris.iter().enumerate() {
            if !live[f] {
                continue;
            }
            for k in 0..3 {
                let c = t[(k + 2) % 3] as usize;
                vopp[fill[c] as usize] = (3 * f + k) as u32;
                fill[c] += 1;
            }
        }
        let two_pi = 2.0 * std::f64::consts::PI;
        let mut pseudo: Vec<bool> = (0..n)
            .map(|v| boundary[v] || angle[v] > two_pi - 1e-5)
            .collect();
        // Non-manifold vertices: faces around v not connected through edges at v.
        let mut seen: Vec<u32> = Vec::new();
        let mut stack: Vec<u32> = Vec::new();
        for v in 0..n {
            let opp = &vopp[deg[v] as usize..deg[v + 1] as usize];
            if opp.len() <= 1 {
                continue;
            }
            seen.clear();
            stack.clear();
            seen.push(opp[0] / 3);
            stack.push(opp[0]);
            while let Some(g) = stack.pop() {
                // The two half-edges of face(g) at v: next(g) and prev(g).
                for h in [next(g), prev(g)] {
                    let t = twin[h as usize];
                    if t == NONE {
                        continue;
                    }
                    let f2 = (t & IDX) / 3;
                    if !seen.contains(&f2) {
                        seen.push(f2);
                        if let Some(&g2) = opp.iter().find(|&&g2| g2 / 3 == f2) {
                            stack.push(g2);
                        }
                    }
                }
            }
            if seen.len() < opp.len() {
                pseudo[v] = true;
                report.non_manifold_vertices.push(v as u32);
            }
        }
        report.pseudo_sources = pseudo.iter().filter(|&&p| p).count();
        Ok(Self {
            positions,
            tris,
            live,
            twin,
            geom,
            vopp_off: deg,
            vopp,
            pseudo,
            report,
        })
    }
}
