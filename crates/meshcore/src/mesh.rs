use crate::MeshError;
use glam::{DAffine3, DVec3};

/// Axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub min: DVec3,
    /// Maximum corner.
    pub max: DVec3,
}

impl Aabb {
    /// Bounding box of a non-empty point set (`None` when empty).
    pub fn from_points(points: &[DVec3]) -> Option<Self> {
        let first = *points.first()?;
        let (min, max) = points
            .iter()
            .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        Some(Self { min, max })
    }

    /// Length of the diagonal: the mesh scale used for relative tolerances.
    pub fn diagonal(&self) -> f64 {
        (self.max - self.min).length()
    }

    /// Extent along each axis.
    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }

    /// Centre of the box.
    pub fn center(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }
}

/// A point on a mesh surface: a face and barycentric coordinates of its three corners.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Face index.
    pub face: u32,
    /// Barycentric coordinates (weights of the face's corners 0, 1, 2), summing to 1.
    pub bary: DVec3,
}

impl SurfacePoint {
    /// A surface point from a face and barycentric coordinates.
    pub fn new(face: u32, bary: DVec3) -> Self {
        Self { face, bary }
    }
}

/// An indexed triangle mesh with f64 positions.
///
/// Invariants (checked by [`TriMesh::new`]): at least one vertex and one triangle, every
/// coordinate finite, every index `< positions.len()`, and `positions.len() <= u32::MAX`.
/// Degenerate triangles and duplicate vertices are allowed (they are reported by
/// [`crate::Topology`] and repaired only on request with [`crate::repair`]).
#[derive(Debug, Clone, PartialEq)]
pub struct TriMesh {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Builds a mesh, validating its invariants.
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        if positions.is_empty() || triangles.is_empty() {
            return Err(MeshError::Empty {
                vertices: positions.len(),
                triangles: triangles.len(),
            });
        }
        if positions.len() > u32::MAX as usize {
            return Err(MeshError::TooManyVertices(positions.len()));
        }
        if let Some((i, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(MeshError::NonFiniteVertex {
                vertex: i,
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
        let n = positions.len();
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&bad) = tri.iter().find(|&&v| v as usize >= n) {
                return Err(MeshError::IndexOutOfRange {
                    triangle: t,
                    index: bad,
                    vertices: n,
                });
            }
        }
        Ok(Self {
            positions,
            triangles,
        })
    }

    /// Vertex positions.
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// Triangles as vertex-index triples.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn n_faces(&self) -> usize {
        self.triangles.len()
    }

    /// Consumes the mesh, returning its positions and triangles.
    pub fn into_parts(self) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        (self.positions, self.triangles)
    }

    /// Position of vertex `v` (panics if out of range; use [`TriMesh::try_position`] for user input).
    pub fn position(&self, v: u32) -> DVec3 {
        self.positions[v as usize]
    }

    /// Position of vertex `v`, or an error naming the index.
    pub fn try_position(&self, v: u32) -> Result<DVec3, MeshError> {
        self.positions
            .get(v as usize)
            .copied()
            .ok_or(MeshError::VertexOutOfRange {
                vertex: v,
                vertices: self.positions.len(),
            })
    }

    /// The three corner positions of face `f`.
    pub fn face_corners(&self, f: u32) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[f as usize];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// `(p1 - p0) x (p2 - p0)`: twice the area times the unit normal.
    pub fn face_cross(&self, f: u32) -> DVec3 {
        let [p0, p1, p2] = self.face_corners(f);
        (p1 - p0).cross(p2 - p0)
    }

    /// Unit normal of face `f` (zero for a degenerate face).
    pub fn face_normal(&self, f: u32) -> DVec3 {
        self.face_cross(f).normalize_or_zero()
    }

    /// Area of face `f`.
    pub fn face_area(&self, f: u32) -> f64 {
        0.5 * self.face_cross(f).length()
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len() as u32)
            .map(|f| self.face_area(f))
            .sum()
    }

    /// Area-weighted vertex normals (unit length; zero for isolated vertices).
    pub fn vertex_normals(&self) -> Vec<DVec3> {
        let mut n = vec![DVec3::ZERO; self.positions.len()];
        for (f, tri) in self.triangles.iter().enumerate() {
            let c = self.face_cross(f as u32);
            for &v in tri {
                n[v as usize] += c;
            }
        }
        n.iter_mut().for_each(|v| *v = v.normalize_or_zero());
        n
    }

    /// Bounding box of the vertices.
    pub fn bbox(&self) -> Aabb {
        // Non-empty by construction.
        Aabb::from_points(&self.positions).unwrap_or(Aabb {
            min: DVec3::ZERO,
            max: DVec3::ZERO,
        })
    }

    /// Mean length of the triangle edges (each interior edge counted once per incident face).
    pub fn mean_edge_length(&self) -> f64 {
        let mut sum = 0.0;
        for tri in &self.triangles {
            for k in 0..3 {
                let a = self.positions[tri[k] as usize];
                let b = self.positions[tri[(k + 1) % 3] as usize];
                sum += (a - b).length();
            }
        }
        sum / (3 * self.triangles.len()) as f64
    }

    /// Length of the closed polyline through the vertices `ring` (the last joined to the first),
    /// e.g. the perimeter of a boundary loop; 0 for fewer than two vertices.
    pub fn ring_length(&self, ring: &[u32]) -> f64 {
        if ring.len() < 2 {
            return 0.0;
        }
        (0..ring.len())
            .map(|k| (self.position(ring[k]) - self.position(ring[(k + 1) % ring.len()])).length())
            .sum()
    }

    /// Length of the longest triangle edge.
    pub fn longest_edge(&self) -> f64 {
        self.triangles
            .iter()
            .flat_map(|t| {
                let p = t.map(|v| self.positions[v as usize]);
                [
                    (p[1] - p[0]).length(),
                    (p[2] - p[1]).length(),
                    (p[0] - p[2]).length(),
                ]
            })
            .fold(0.0f64, f64::max)
    }

    /// Position of a surface point; an error if the face or the barycentric coordinates are invalid.
    pub fn point_position(&self, p: &SurfacePoint) -> Result<DVec3, MeshError> {
        self.check_surface_point(p)?;
        let [a, b, c] = self.face_corners(p.face);
        Ok(p.bary.x * a + p.bary.y * b + p.bary.z * c)
    }

    /// Value of a per-vertex field at a surface point: the barycentric (linear) interpolation of
    /// the values at its face's corners. A corner of weight exactly 0 is left out, so a
    /// non-finite value there (an unreached vertex of a distance field) does not reach a point
    /// on the opposite edge. An error if the surface point is invalid or `values` does not have
    /// one value per vertex.
    pub fn interpolate(&self, values: &[f64], p: &SurfacePoint) -> Result<f64, MeshError> {
        self.check_surface_point(p)?;
        if values.len() != self.positions.len() {
            return Err(MeshError::FieldLength {
                values: values.len(),
                vertices: self.positions.len(),
            });
        }
        let t = self.triangles[p.face as usize];
        let mut s = 0.0;
        for (k, &v) in t.iter().enumerate() {
            if p.bary[k] != 0.0 {
                s += p.bary[k] * values[v as usize];
            }
        }
        Ok(s)
    }

    /// The corner of a surface point's face with the largest barycentric weight (the first on
    /// ties): the vertex nearest to it in the face's own coordinates. An error if the surface
    /// point is invalid.
    pub fn nearest_corner(&self, p: &SurfacePoint) -> Result<u32, MeshError> {
        self.check_surface_point(p)?;
        let w = p.bary.to_array();
        let k = (1..3).fold(0, |b, i| if w[i] > w[b] { i } else { b });
        Ok(self.triangles[p.face as usize][k])
    }

    /// Validates a surface point: face in range, barycentrics finite, `>= -1e-9`, summing to 1 within 1e-9.
    pub fn check_surface_point(&self, p: &SurfacePoint) -> Result<(), MeshError> {
        if p.face as usize >= self.triangles.len() {
            return Err(MeshError::FaceOutOfRange {
                face: p.face,
                faces: self.triangles.len(),
            });
        }
        let b = p.bary;
        if !b.is_finite() || b.min_element() < -1e-9 || (b.element_sum() - 1.0).abs() > 1e-9 {
            return Err(MeshError::InvalidBarycentric(b.x, b.y, b.z));
        }
        Ok(())
    }

    /// A copy of the mesh moved by a rigid (or any affine) transform.
    pub fn transformed(&self, t: &DAffine3) -> Self {
        Self {
            positions: self
                .positions
                .iter()
                .map(|p| t.transform_point3(*p))
                .collect(),
            triangles: self.triangles.clone(),
        }
    }

    /// Triangles whose area is at most `rel_tol * bbox_diagonal^2` (or that repeat a vertex).
    pub fn degenerate_faces(&self, rel_tol: f64) -> Vec<u32> {
        let d = self.bbox().diagonal();
        let thr = rel_tol * d * d;
        self.triangles
            .iter()
            .enumerate()
            .filter(|(f, t)| {
                t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || self.face_area(*f as u32) <= thr
            })
            .map(|(f, _)| f as u32)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> TriMesh {
        TriMesh::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
        .unwrap()
    }

    #[test]
    fn ring_length_is_the_closed_perimeter() {
        let m = quad();
        assert!((m.ring_length(&[0, 1, 2, 3]) - 4.0).abs() < 1e-12);
        assert!((m.ring_length(&[0, 2]) - 2.0 * 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(m.ring_length(&[1]), 0.0);
        assert_eq!(m.ring_length(&[]), 0.0);
    }

    #[test]
    fn interpolation_is_linear_and_skips_zero_weights() {
        let m = quad();
        let x: Vec<f64> = m.positions().iter().map(|p| p.x + 2.0 * p.y).collect();
        let sp = SurfacePoint::new(1, DVec3::new(0.2, 0.3, 0.5));
        let p = m.point_position(&sp).unwrap();
        assert!((m.interpolate(&x, &sp).unwrap() - (p.x + 2.0 * p.y)).abs() < 1e-12);
        // Vertex 2 unreached: a point on the edge 0-3 (weight 0 at vertex 2) stays finite.
        let u = [1.0, 2.0, f64::INFINITY, 4.0];
        let edge = SurfacePoint::new(1, DVec3::new(0.25, 0.0, 0.75));
        assert_eq!(m.interpolate(&u, &edge).unwrap(), 0.25 * 1.0 + 0.75 * 4.0);
        assert!(m.interpolate(&u, &sp).unwrap().is_infinite());
        assert_eq!(
            m.interpolate(&u[..3], &sp),
            Err(MeshError::FieldLength {
                values: 3,
                vertices: 4
            })
        );
        let bad = SurfacePoint::new(2, DVec3::new(1.0, 0.0, 0.0));
        assert!(matches!(
            m.interpolate(&u, &bad),
            Err(MeshError::FaceOutOfRange { face: 2, faces: 2 })
        ));
    }

    #[test]
    fn the_nearest_corner_has_the_largest_weight() {
        let m = quad();
        let at = |face, w: [f64; 3]| m.nearest_corner(&SurfacePoint::new(face, DVec3::from(w)));
        assert_eq!(at(0, [0.2, 0.5, 0.3]).unwrap(), 1);
        assert_eq!(at(1, [0.1, 0.2, 0.7]).unwrap(), 3);
        assert_eq!(at(1, [1.0, 0.0, 0.0]).unwrap(), 0);
        // Ties go to the first corner.
        assert_eq!(at(1, [0.2, 0.4, 0.4]).unwrap(), 2);
        assert!(matches!(
            at(2, [1.0, 0.0, 0.0]),
            Err(MeshError::FaceOutOfRange { .. })
        ));
        assert!(at(0, [0.5, 0.5, 0.5]).is_err());
    }

    #[test]
    fn longest_edge_is_the_diagonal_of_the_unit_quad() {
        assert!((quad().longest_edge() - 2f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn rejects_bad_input() {
        assert!(matches!(
            TriMesh::new(vec![], vec![]),
            Err(MeshError::Empty { .. })
        ));
        assert!(matches!(
            TriMesh::new(vec![DVec3::new(f64::NAN, 0.0, 0.0)], vec![[0, 0, 0]]),
            Err(MeshError::NonFiniteVertex { vertex: 0, .. })
        ));
        assert!(matches!(
            TriMesh::new(vec![DVec3::ZERO; 3], vec![[0, 1, 3]]),
            Err(MeshError::IndexOutOfRange {
                triangle: 0,
                index: 3,
                ..
            })
        ));
    }

    #[test]
    fn measures() {
        let m = quad();
        assert!((m.area() - 1.0).abs() < 1e-15);
        assert!((m.face_normal(0) - DVec3::Z).length() < 1e-15);
        assert!((m.bbox().diagonal() - 2f64.sqrt()).abs() < 1e-15);
        let p = m
            .point_position(&SurfacePoint::new(0, DVec3::new(0.2, 0.3, 0.5)))
            .unwrap();
        assert!((p - DVec3::new(0.8, 0.5, 0.0)).length() < 1e-15);
        assert!(m
            .point_position(&SurfacePoint::new(2, DVec3::new(1.0, 0.0, 0.0)))
            .is_err());
        assert!(m
            .point_position(&SurfacePoint::new(0, DVec3::new(1.0, 1.0, 0.0)))
            .is_err());
        assert!(m.degenerate_faces(1e-12).is_empty());
    }
}
