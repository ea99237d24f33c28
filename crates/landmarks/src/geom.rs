//! Small geometric helpers: symmetric eigen-decomposition, weighted Kabsch/Horn fit, nearest
//! vertex queries with a point-to-surface approximation, point-to-plane ICP.

#![allow(clippy::needless_range_loop)] // Dense small linear algebra reads best with indices.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use meshcore::{DMat3, DQuat, DVec3};

/// A rigid motion `x -> r x + t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rigid {
    /// Rotation.
    pub r: DMat3,
    /// Translation.
    pub t: DVec3,
}

impl Rigid {
    /// The identity motion.
    pub const IDENTITY: Self = Self {
        r: DMat3::IDENTITY,
        t: DVec3::ZERO,
    };

    /// Applies the motion to a point.
    pub fn apply(&self, p: DVec3) -> DVec3 {
        self.r * p + self.t
    }

    /// Applies the rotation to a vector.
    pub fn rotate(&self, v: DVec3) -> DVec3 {
        self.r * v
    }

    /// `self` after `other`: `x -> self(other(x))`.
    pub fn compose(&self, other: &Rigid) -> Rigid {
        Rigid {
            r: self.r * other.r,
            t: self.r * other.t + self.t,
        }
    }

    /// The inverse motion.
    pub fn inverse(&self) -> Rigid {
        let rt = self.r.transpose();
        Rigid {
            r: rt,
            t: -(rt * self.t),
        }
    }
}

/// Jacobi eigen-decomposition of a symmetric 4x4 matrix: eigenvalues and eigenvectors (columns).
fn jacobi4(mut a: [[f64; 4]; 4]) -> ([f64; 4], [[f64; 4]; 4]) {
    let mut v = [[0.0; 4]; 4];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _sweep in 0..50 {
        let mut off = 0.0;
        for i in 0..4 {
            for j in i + 1..4 {
                off += a[i][j] * a[i][j];
            }
        }
        let diag: f64 = (0..4).map(|i| a[i][i] * a[i][i]).sum();
        if off <= 1e-30 * diag.max(1e-300) {
            break;
        }
        for p in 0..4 {
            for q in p + 1..4 {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..4 {
                    let akp = a[k][p];
                    let akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for k in 0..4 {
                    let apk = a[p][k];
                    let aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in v.iter_mut() {
                    let vkp = row[p];
                    let vkq = row[q];
                    row[p] = c * vkp - s * vkq;
                    row[q] = s * vkp + c * vkq;
                }
            }
        }
    }
    ([a[0][0], a[1][1], a[2][2], a[3][3]], v)
}

/// Least-squares rigid motion (proper rotation) mapping `src[i]` onto `dst[i]` with weights
/// (Horn's quaternion method). `None` for fewer than one pair or non-positive total weight.
pub fn kabsch(src: &[DVec3], dst: &[DVec3], w: Option<&[f64]>) -> Option<Rigid> {
    let n = src.len().min(dst.len());
    if n == 0 {
        return None;
    }
    let wt = |i: usize| w.map_or(1.0, |w| w[i]);
    let sw: f64 = (0..n).map(wt).sum();
    if sw <= 0.0 || !sw.is_finite() {
        return None;
    }
    let cs = (0..n).map(|i| src[i] * wt(i)).sum::<DVec3>() / sw;
    let cd = (0..n).map(|i| dst[i] * wt(i)).sum::<DVec3>() / sw;
    let mut s = [[0.0; 3]; 3];
    for i in 0..n {
        let a = src[i] - cs;
        let b = dst[i] - cd;
        let (a, b) = (a.to_array(), b.to_array());
        for (j, row) in s.iter_mut().enumerate() {
            for (k, x) in row.iter_mut().enumerate() {
                *x += wt(i) * a[j] * b[k];
            }
        }
    }
    let [[sxx, sxy, sxz], [syx, syy, syz], [szx, szy, szz]] = s;
    let m = [
        [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
        [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
        [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
        [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
    ];
    let (vals, vecs) = jacobi4(m);
    let best = (0..4).max_by(|&a, &b| vals[a].total_cmp(&vals[b]))?;
    let q = DQuat::from_xyzw(vecs[1][best], vecs[2][best], vecs[3][best], vecs[0][best]);
    if !q.is_finite() || q.length() < 1e-12 {
        return None;
    }
    let r = DMat3::from_quat(q.normalize());
    Some(Rigid { r, t: cd - r * cs })
}

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
    t: &Rigid,
    tau: f64,
    min_dot: f64,
) -> FitScore {
    let tau2 = tau * tau;
    let mut cost = 0.0;
    let mut inl = 0usize;
    let mut sse = 0.0;
    for (p, n) in pts {
        let q = t.apply(*p);
        let h = idx.query(q);
        let ok = h.d2 < tau2 && idx.nrm[h.vertex as usize].dot(t.rotate(*n)) > min_dot;
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
    t0: &Rigid,
    iterations: usize,
    tau: f64,
    min_dot: f64,
) -> Rigid {
    let mut t = *t0;
    let tau2 = tau * tau;
    for _ in 0..iterations {
        let mut ata = [[0.0; 6]; 6];
        let mut atb = [0.0; 6];
        let mut count = 0;
        for (p, n) in pts {
            let q = t.apply(*p);
            let h = idx.query(q);
            let vn = idx.nrm[h.vertex as usize];
            if h.d2 >= tau2 || vn.dot(t.rotate(*n)) <= min_dot {
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
        let Some(x) = crate::curvature::solve_dense(ata, atb) else {
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
        let step = Rigid { r: dr, t: dt };
        t = step.compose(&t);
        if angle < 1e-7 && dt.length() < 1e-7 * (1.0 + t.t.length()) {
            break;
        }
    }
    // Re-orthonormalise the rotation (accumulated round-off).
    let q = DQuat::from_mat3(&t.r).normalize();
    Rigid {
        r: DMat3::from_quat(q),
        t: t.t,
    }
}
