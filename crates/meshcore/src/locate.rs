use crate::{MeshError, SurfacePoint, TriMesh};
use glam::DVec3;

/// Closest point of triangle `(a, b, c)` to `p`, as barycentric coordinates `(wa, wb, wc)`.
///
/// Region-based (Voronoi regions of vertices, edges and face); exact up to rounding, also for
/// degenerate triangles (the result then lies on the longest edge or at a vertex).
pub fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return DVec3::new(1.0, 0.0, 0.0);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return DVec3::new(0.0, 1.0, 0.0);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return DVec3::new(1.0 - v, v, 0.0);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return DVec3::new(0.0, 0.0, 1.0);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return DVec3::new(1.0 - w, 0.0, w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return DVec3::new(0.0, 1.0 - w, w);
    }
    let denom = va + vb + vc;
    if denom.abs() <= f64::MIN_POSITIVE || !denom.is_finite() {
        // Degenerate triangle: best of the three edges.
        let cands = [
            (DVec3::new(1.0, 0.0, 0.0), a),
            (DVec3::new(0.0, 1.0, 0.0), b),
            (DVec3::new(0.0, 0.0, 1.0), c),
        ];
        let mut best = cands[0].0;
        let mut bd = f64::INFINITY;
        for (w, q) in cands {
            let d = (q - p).length_squared();
            if d < bd {
                bd = d;
                best = w;
            }
        }
        return best;
    }
    let v = vb / denom;
    let w = vc / denom;
    DVec3::new(1.0 - v - w, v, w)
}

/// Nearest-surface-point queries on one mesh, accelerated by a uniform grid over face boxes.
///
/// Exact: the search visits grid shells in order of distance and stops once no unvisited cell
/// can hold a closer face. Ties are broken by the smaller face index, so results are
/// deterministic.
#[derive(Debug, Clone)]
pub struct FaceLocator<'a> {
    mesh: &'a TriMesh,
    origin: DVec3,
    cell: f64,
    dims: [usize; 3],
    /// CSR cell -> faces.
    offsets: Vec<u32>,
    faces: Vec<u32>,
}

impl<'a> FaceLocator<'a> {
    /// Builds the grid (about one face per cell).
    pub fn new(mesh: &'a TriMesh) -> Self {
        let bb = mesh.bbox();
        let size = bb
            .size()
            .max(DVec3::splat(bb.diagonal() * 1e-9 + f64::MIN_POSITIVE));
        let volume = size.x * size.y * size.z;
        let target = (mesh.n_faces() as f64).max(1.0);
        let mut cell = (volume / target).cbrt();
        // Grids of flat meshes: bound by the mean edge length so cells are never tiny or huge.
        let mel = mesh.mean_edge_length().max(bb.diagonal() * 1e-6);
        cell = cell.max(mel).max(f64::MIN_POSITIVE);
        let mut dims = [0usize; 3];
        for k in 0..3 {
            dims[k] = ((size[k] / cell).floor() as usize + 1).clamp(1, 512);
        }
        let n_cells = dims[0] * dims[1] * dims[2];
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n_cells];
        let origin = bb.min;
        let idx = |p: DVec3| -> [usize; 3] {
            let q = (p - origin) / cell;
            [
                (q.x.floor().max(0.0) as usize).min(dims[0] - 1),
                (q.y.floor().max(0.0) as usize).min(dims[1] - 1),
                (q.z.floor().max(0.0) as usize).min(dims[2] - 1),
            ]
        };
        for f in 0..mesh.n_faces() as u32 {
            let [a, b, c] = mesh.face_corners(f);
            let lo = idx(a.min(b).min(c));
            let hi = idx(a.max(b).max(c));
            for i in lo[0]..=hi[0] {
                for j in lo[1]..=hi[1] {
                    for k in lo[2]..=hi[2] {
                        lists[(k * dims[1] + j) * dims[0] + i].push(f);
                    }
                }
            }
        }
        let mut offsets = Vec::with_capacity(n_cells + 1);
        let mut faces = Vec::new();
        offsets.push(0u32);
        for l in lists {
            faces.extend_from_slice(&l);
            offsets.push(faces.len() as u32);
        }
        Self {
            mesh,
            origin,
            cell,
            dims,
            offsets,
            faces,
        }
    }

    /// The mesh this locator was built for.
    pub fn mesh(&self) -> &'a TriMesh {
        self.mesh
    }

    /// Nearest surface point to `p` and its distance.
    pub fn nearest(&self, p: DVec3) -> Result<(SurfacePoint, f64), MeshError> {
        if !p.is_finite() {
            return Err(MeshError::NonFinitePoint(p.x, p.y, p.z));
        }
        let q = (p - self.origin) / self.cell;
        let d = self.dims;
        let c = [
            (q.x.floor().max(0.0) as usize).min(d[0] - 1) as i64,
            (q.y.floor().max(0.0) as usize).min(d[1] - 1) as i64,
            (q.z.floor().max(0.0) as usize).min(d[2] - 1) as i64,
        ];
        let mut best: Option<(f64, u32, DVec3)> = None;
        let max_ring = d.iter().copied().max().unwrap_or(1) as i64 + 1;
        for ring in 0..=max_ring {
            if let Some((bd, _, _)) = best {
                // Every cell of this ring is at least (ring - 1) cells away from p along one
                // axis (also when p lies outside the grid and its home cell is clamped).
                let lower = ((ring - 1).max(0) as f64) * self.cell;
                if lower * lower > bd {
                    break;
                }
            }
            for i in (c[0] - ring)..=(c[0] + ring) {
                for j in (c[1] - ring)..=(c[1] + ring) {
                    for k in (c[2] - ring)..=(c[2] + ring) {
                        let on_shell = (i - c[0]).abs() == ring
                            || (j - c[1]).abs() == ring
                            || (k - c[2]).abs() == ring;
                        if !on_shell
                            || i < 0
                            || j < 0
                            || k < 0
                            || i >= d[0] as i64
                            || j >= d[1] as i64
                            || k >= d[2] as i64
                        {
                            continue;
                        }
                        let cell = ((k as usize) * d[1] + j as usize) * d[0] + i as usize;
                        let (s, e) = (self.offsets[cell] as usize, self.offsets[cell + 1] as usize);
                        for &f in &self.faces[s..e] {
                            let [a, b, cc] = self.mesh.face_corners(f);
                            let w = closest_point_on_triangle(p, a, b, cc);
                            let x = w.x * a + w.y * b + w.z * cc;
                            let dd = (x - p).length_squared();
                            let better = match best {
                                None => true,
                                Some((bd, bf, _)) => dd < bd || (dd == bd && f < bf),
                            };
                            if better {
                                best = Some((dd, f, w));
                            }
                        }
                    }
                }
            }
        }
        let (dd, f, w) = best.ok_or(MeshError::Empty {
            vertices: self.mesh.n_vertices(),
            triangles: self.mesh.n_faces(),
        })?;
        Ok((SurfacePoint::new(f, w), dd.sqrt()))
    }

    /// Nearest vertex of the nearest face to `p` (the corner with the largest barycentric weight).
    pub fn nearest_vertex(&self, p: DVec3) -> Result<u32, MeshError> {
        let (sp, _) = self.nearest(p)?;
        let t = self.mesh.triangles()[sp.face as usize];
        let k = if sp.bary.x >= sp.bary.y && sp.bary.x >= sp.bary.z {
            0
        } else if sp.bary.y >= sp.bary.z {
            1
        } else {
            2
        };
        Ok(t[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn brute(mesh: &TriMesh, p: DVec3) -> f64 {
        (0..mesh.n_faces() as u32)
            .map(|f| {
                let [a, b, c] = mesh.face_corners(f);
                let w = closest_point_on_triangle(p, a, b, c);
                (w.x * a + w.y * b + w.z * c - p).length()
            })
            .fold(f64::INFINITY, f64::min)
    }

    fn bumpy(n: usize) -> TriMesh {
        crate::shapes::grid(n, n, crate::shapes::Diagonals::Uniform, |i, j| {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            DVec3::new(x, y, 0.2 * (6.0 * x).sin() * (5.0 * y).cos())
        })
        .unwrap()
    }

    #[test]
    fn triangle_regions() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        assert_eq!(
            closest_point_on_triangle(DVec3::new(-1.0, -1.0, 0.0), a, b, c),
            DVec3::new(1.0, 0.0, 0.0)
        );
        let w = closest_point_on_triangle(DVec3::new(0.25, 0.25, 3.0), a, b, c);
        assert!((w - DVec3::new(0.5, 0.25, 0.25)).length() < 1e-15);
        let w = closest_point_on_triangle(DVec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((w - DVec3::new(0.0, 0.5, 0.5)).length() < 1e-15);
    }

    #[test]
    fn non_finite_query_is_an_error() {
        let m = bumpy(4);
        let loc = FaceLocator::new(&m);
        assert!(loc.nearest(DVec3::new(f64::NAN, 0.0, 0.0)).is_err());
    }

    proptest! {
        #[test]
        fn locator_matches_brute_force(x in -0.5f64..1.5, y in -0.5f64..1.5, z in -1.0f64..1.0) {
            let m = bumpy(12);
            let loc = FaceLocator::new(&m);
            let p = DVec3::new(x, y, z);
            let (sp, d) = loc.nearest(p).unwrap();
            let q = m.point_position(&sp).unwrap();
            prop_assert!(((q - p).length() - d).abs() < 1e-12);
            prop_assert!((d - brute(&m, p)).abs() < 1e-12);
        }
    }
}
