//! The surface index of the detector (nearest vertex queries with a point-to-surface
//! approximation), the fit score of a template pose, and point-to-plane ICP onto the index.

#![allow(clippy::needless_range_loop)] // Dense small linear algebra reads best with indices.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use meshcore::linalg::solve_sym_tol;
use meshcore::{DAffine3, DMat3, DQuat, DVec3};

/// Vertex positions and normals with a k-d tree, answering approximate point-to-surface distances.
#[derive(Debug)]
pub struct SurfaceIndex {
    tree: ImmutableKdTree<f64, 3>,
    /// Positions.
    pub pos: Vec<DVec3>,
    /// Unit vertex normals.
    pub nrm: Vec<DVec3>,
    /// Half the mean length of the edges at each vertex (the vertex's share of the surface).
    pub reach: Vec<f64>,
}

/// Result of a nearest query.
#[derive(Debug, Clone, Copy)]
pub struct Hit {
    /// Nearest vertex.
    pub vertex: u32,
    /// Approximate squared distance to the surface.
    pub d2: f64,
    /// Signed normal offset of the query from the vertex tangent plane.
    pub normal_offset: f64,
}

impl SurfaceIndex {
    /// Builds the index.
    pub fn new(pos: Vec<DVec3>, nrm: Vec<DVec3>, reach: Vec<f64>) -> Self {
        let pts: Vec<[f64; 3]> = pos.iter().map(|p| p.to_array()).collect();
        let tree = ImmutableKdTree::new_from_slice(&pts);
        Self {
            tree,
            pos,
            nrm,
            reach,
        }
    }

    /// Nearest vertex and the approximate squared distance from `q` to the surface: the normal
    /// offset squared plus the squared tangential excess beyond the vertex's reach (so that
    /// points beyond a border or over a hole are far).
    pub fn query(&self, q: DVec3) -> Hit {
        let nn = self.tree.nearest_one::<SquaredEuclidean>(&q.to_array());
        let v = nn.item as usize;
        let d = q - self.pos[v];
        let n = self.nrm[v];
        let dn = d.dot(n);
        let dt2 = (d.length_squared() - dn * dn).max(0.0);
        let ex = (dt2.sqrt() - self.reach[v]).max(0.0);
        Hit {
            vertex: v as u32,
            d2: dn * dn + ex * ex,
            normal_offset: dn,
        }
    }

    /// Vertices within `radius` of `q`, sorted by index.
    pub fn within(&self, q: DVec3, radius: f64) -> Vec<u32> {
        let mut v: Vec<u32> = self
            .tree
            .within_unsorted::<SquaredEuclidean>(&q.to_array(), radius * radius)
            .into_iter()
            .map(|n| n.item as u32)
            .collect();
        v.sort_unstable();
        v
    }
}

/// Outcome of aligning template points (with normals) to a surface.
#[derive(Debug, Clone, Copy)]
pub struct FitScore {
    /// Truncated mean squared distance (outliers count `tau^2`).
    pub cost: f64,
    /// Share of template points that are inliers (close and with agreeing normals).
    pub inlier_fraction: f64,
    /// Root mean square distance of the inliers.
    pub rms: f64,
}

/// Scores template points `pts` (with normals) moved by `t` against the surface: a point is an
/// inlier when its distance is below `tau` and its normal agrees with the vertex normal
/// (`dot > min_dot`).
pub fn score(
    idx: &SurfaceIndex,
    pts: &[(DVec3, DVec3)],
    t: &DAffine3,
    tau: f64,
    min_dot: f64,
) -> FitScore {
    let tau2 = tau * tau;
    let mut cost = 0.0;
    let mut inl = 0usize;
    let mut sse = 0.0;
    for (p, n) in pts {
        let q = t.transform_point3(*p);
        let h = idx.query(q);
        let ok = h.d2 < tau2 && idx.nrm[h.vertex as usize].dot(t.transform_vector3(*n)) > min_dot;
        if ok {
            cost += h.d2;
            sse += h.d2;
            inl += 1;
        } else {
            cost += tau2;
        }
    }
    let m = pts.len().max(1) as f64;
    FitScore {
        cost: cost / m,
        inlier_fraction: inl as f64 / m,
        rms: if inl > 0 {
            (sse / inl as f64).sqrt()
        } else {
            f64::INFINITY
        },
    }
}

/// Point-to-plane ICP of template points onto the surface, starting from `t0`; correspondences
/// are the nearest vertices, inliers as in [`score`]. Returns the refined motion.
pub fn icp(
    idx: &SurfaceIndex,
    pts: &[(DVec3, DVec3)],
    t0: &DAffine3,
    iterations: usize,
    tau: f64,
    min_dot: f64,
) -> DAffine3 {
    let mut t = *t0;
    let tau2 = tau * tau;
    for _ in 0..iterations {
        let mut ata = [[0.0; 6]; 6];
        let mut atb = [0.0; 6];
        let mut count = 0;
        for (p, n) in pts {
            let q = t.transform_point3(*p);
            let h = idx.query(q);
            let vn = idx.nrm[h.vertex as usize];
            if h.d2 >= tau2 || vn.dot(t.transform_vector3(*n)) <= min_dot {
                continue;
            }
            let target = idx.pos[h.vertex as usize];
            // Linearised: ((q + w x q + dt) - target) . vn = 0.
            let c = q.cross(vn);
            let row = [c.x, c.y, c.z, vn.x, vn.y, vn.z];
            let rhs = -(q - target).dot(vn);
            for i in 0..6 {
                for j in 0..6 {
                    ata[i][j] += row[i] * row[j];
                }
                atb[i] += row[i] * rhs;
            }
            count += 1;
        }
        if count < 6 {
            break;
        }
        // Light Tikhonov damping for stability on nearly flat templates.
        let tr: f64 = (0..6).map(|i| ata[i][i]).sum::<f64>() / 6.0;
        for (i, row) in ata.iter_mut().enumerate() {
            row[i] += 1e-9 * tr + 1e-300;
        }
        let Some(x) = solve_sym_tol(ata, atb, 1e-13) else {
            break;
        };
        let w = DVec3::new(x[0], x[1], x[2]);
        let dt = DVec3::new(x[3], x[4], x[5]);
        let angle = w.length();
        let dr = if angle > 1e-15 {
            DMat3::from_axis_angle(w / angle, angle)
        } else {
            DMat3::IDENTITY
        };
        t = DAffine3::from_mat3_translation(dr, dt) * t;
        if angle < 1e-7 && dt.length() < 1e-7 * (1.0 + t.translation.length()) {
            break;
        }
    }
    // Re-orthonormalise the rotation (accumulated round-off).
    let q = DQuat::from_mat3(&t.matrix3).normalize();
    DAffine3::from_mat3_translation(DMat3::from_quat(q), t.translation)
}
