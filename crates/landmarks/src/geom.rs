//! The surface index of the detector (nearest vertex queries with a point-to-surface
//! approximation), the fit score of a template pose, and point-to-plane ICP onto the index.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use meshcore::{DAffine3, DMat3, DQuat, DVec3};
use shapedist::{
    icp_to_target, Convergence, Damping, IcpLoopOptions, IcpVariant, Match, PointTarget,
    ShapeDistError,
};

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
    /// Whether each vertex is on a rim of unobserved surface (see
    /// [`crate::DetectOptions::toward_viewer`]); all `false` from [`SurfaceIndex::new`].
    pub unseen_rim: Vec<bool>,
    /// Cells of space where every point is far from the surface ([`SurfaceIndex::mark_far`]);
    /// `None` until marked.
    pub(crate) far: Option<FarGrid>,
}

/// A grid of cubic cells over the vertices' bounding box that knows where space is far from
/// every vertex: a point in a cell not marked `near` is farther than `bound` (plus each
/// vertex's reach) from every vertex, so its approximate squared distance to the surface
/// ([`SurfaceIndex::query`]) is at least `bound^2`. Points outside the grid are far too.
#[derive(Debug, Clone)]
pub(crate) struct FarGrid {
    origin: DVec3,
    cell: f64,
    dims: [usize; 3],
    near: Vec<bool>,
    bound: f64,
}

impl FarGrid {
    /// Marks every cell within `bound + reach` (Chebyshev cell distance, one cell of margin) of
    /// a vertex; `None` when the bound or the positions are not finite or the grid would be
    /// larger than about a million cells.
    fn new(pos: &[DVec3], reach: &[f64], bound: f64) -> Option<Self> {
        if !(bound.is_finite() && bound > 0.0) || pos.is_empty() {
            return None;
        }
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in pos {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        // Most vertices share a common dilation; a vertex with a longer reach (a spike, a long
        // border edge) is dilated on its own.
        let mut sorted: Vec<f64> = reach.to_vec();
        sorted.sort_by(f64::total_cmp);
        let common_reach = sorted[sorted.len() / 2] * 4.0;
        let max_reach = sorted.last().copied().unwrap_or(0.0);
        if !(lo.is_finite() && hi.is_finite() && max_reach.is_finite()) {
            return None;
        }
        let cell = 0.25 * (bound + common_reach);
        let cells_of = |r: f64| ((bound + r) / cell).ceil() as usize + 1;
        let k = cells_of(common_reach);
        let pad = cells_of(max_reach) + 1;
        let origin = lo - DVec3::splat(pad as f64 * cell);
        let ext = (hi - origin) / cell;
        let dims = [
            ext.x as usize + pad + 2,
            ext.y as usize + pad + 2,
            ext.z as usize + pad + 2,
        ];
        let total = dims[0].checked_mul(dims[1])?.checked_mul(dims[2])?;
        if total > 1 << 20 {
            return None;
        }
        let index = |c: [usize; 3]| (c[2] * dims[1] + c[1]) * dims[0] + c[0];
        let cell_of = |p: DVec3| {
            let c = (p - origin) / cell;
            [c.x as usize, c.y as usize, c.z as usize]
        };
        let mut occupied = vec![false; total];
        let mut near = vec![false; total];
        for (p, &r) in pos.iter().zip(reach) {
            let c = cell_of(*p);
            if r <= common_reach {
                occupied[index(c)] = true;
                continue;
            }
            let m = cells_of(r);
            for z in c[2] - m..=c[2] + m {
                for y in c[1] - m..=c[1] + m {
                    for x in c[0] - m..=c[0] + m {
                        near[index([x, y, z])] = true;
                    }
                }
            }
        }
        // The cube of half-side k around every occupied cell: one running-window pass per axis.
        let strides = [1, dims[0], dims[0] * dims[1]];
        let mut buf = occupied;
        for axis in 0..3 {
            let n = dims[axis];
            let stride = strides[axis];
            let mut out = vec![false; total];
            let lines = total / n;
            for line in 0..lines {
                // The start of the `line`-th run along `axis`.
                let below = line % stride;
                let above = line / stride;
                let start = above * stride * n + below;
                let mut count = 0usize;
                // Window [i - k, i + k]: prime it with [0, k).
                for i in 0..k.min(n) {
                    count += usize::from(buf[start + i * stride]);
                }
                for i in 0..n {
                    if i + k < n {
                        count += usize::from(buf[start + (i + k) * stride]);
                    }
                    if i > k {
                        count -= usize::from(buf[start + (i - k - 1) * stride]);
                    }
                    out[start + i * stride] = count > 0;
                }
            }
            buf = out;
        }
        for (n, b) in near.iter_mut().zip(&buf) {
            *n |= *b;
        }
        Some(Self {
            origin,
            cell,
            dims,
            near,
            bound,
        })
    }

    /// Whether `q` is certainly farther than the grid's bound (plus reach) from every vertex.
    fn is_far(&self, q: DVec3) -> bool {
        let c = (q - self.origin) / self.cell;
        if !(c.x >= 0.0 && c.y >= 0.0 && c.z >= 0.0) {
            return true;
        }
        let (x, y, z) = (c.x as usize, c.y as usize, c.z as usize);
        if x >= self.dims[0] || y >= self.dims[1] || z >= self.dims[2] {
            return true;
        }
        !self.near[(z * self.dims[1] + y) * self.dims[0] + x]
    }
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
        let unseen_rim = vec![false; pos.len()];
        let pts: Vec<[f64; 3]> = pos.iter().map(|p| p.to_array()).collect();
        let tree = ImmutableKdTree::new_from_slice(&pts);
        Self {
            tree,
            pos,
            nrm,
            reach,
            unseen_rim,
            far: None,
        }
    }

    /// Marks the space farther than `bound` from the surface, so that [`SurfaceIndex::near`]
    /// answers queries there without a tree search (a query far from a dense mesh is the
    /// tree's slowest). Nothing is marked when the grid would be too large.
    pub fn mark_far(&mut self, bound: f64) {
        self.far = self.far_grid(bound);
    }

    /// The marks of [`SurfaceIndex::mark_far`], to be stored in `far` later (built while the
    /// index is shared).
    pub(crate) fn far_grid(&self, bound: f64) -> Option<FarGrid> {
        FarGrid::new(&self.pos, &self.reach, bound)
    }

    /// [`SurfaceIndex::query`] for a point that may be within `tau` of the surface; `None`
    /// when the point is certainly not (its approximate squared distance is at least `tau^2`
    /// and it is farther than `tau` plus its reach from every vertex), known without a tree
    /// search when `tau` is at most the bound given to [`SurfaceIndex::mark_far`].
    pub fn near(&self, q: DVec3, tau: f64) -> Option<Hit> {
        match &self.far {
            Some(f) if tau <= f.bound && f.is_far(q) => None,
            _ => Some(self.query(q)),
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
        // A point certainly beyond `tau` is an outlier whatever its nearest vertex.
        let inlier = idx.near(q, tau).filter(|h| {
            h.d2 < tau2 && idx.nrm[h.vertex as usize].dot(t.transform_vector3(*n)) > min_dot
        });
        if let Some(h) = inlier {
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

/// The detector's ICP target: partners are the nearest vertices ([`SurfaceIndex::query`]),
/// with the approximate point-to-surface squared distance and the vertex normals.
impl PointTarget for SurfaceIndex {
    fn partner(&self, q: DVec3, _normals: bool) -> Result<Match, ShapeDistError> {
        let h = self.query(q);
        let v = h.vertex as usize;
        Ok(Match {
            d2: h.d2,
            point: self.pos[v],
            normal: self.nrm[v],
        })
    }
}

/// The options of the detector's ICP: point-to-plane with translation, pairs closer than
/// `tau` whose normals agree (`dot > min_dot`), no trimming, damping `1e-9` times the mean
/// diagonal entry (plus `1e-300`), at least 6 pairs, stop when a step rotates by less than
/// `1e-7` rad and moves by less than `1e-7 (1 + |t|)`; no re-orthonormalisation per step.
pub fn icp_options(iterations: usize, tau: f64, min_dot: f64) -> IcpLoopOptions {
    IcpLoopOptions {
        variant: IcpVariant::PointToPlane,
        max_iterations: iterations,
        translation: true,
        max_distance: Some(tau),
        min_normal_dot: Some(min_dot),
        damping: Damping {
            factor: 1e-9,
            mean: true,
            floor: 1e-300,
            rel_pivot: 1e-13,
        },
        min_step_angle: 1e-15,
        orthonormalise_steps: false,
        convergence: Convergence::StepSize {
            angle: 1e-7,
            translation: 1e-7,
        },
        min_pairs: 6,
        evaluate_final: false,
        ..IcpLoopOptions::default()
    }
}

/// Point-to-plane ICP of template points (with normals) onto the surface, starting from `t0`
/// ([`shapedist::icp_to_target`] with [`icp_options`]); inliers as in [`score`]. Returns the
/// refined motion with its rotation re-orthonormalised (through a unit quaternion); `t0` when
/// there are no iterations or the options are invalid (a NaN `tau` or `min_dot`).
pub fn icp(
    idx: &SurfaceIndex,
    pts: &[(DVec3, DVec3)],
    t0: &DAffine3,
    iterations: usize,
    tau: f64,
    min_dot: f64,
) -> DAffine3 {
    let (src, nrm): (Vec<DVec3>, Vec<DVec3>) = pts.iter().copied().unzip();
    let t = if iterations == 0 {
        *t0
    } else {
        icp_to_target(
            idx,
            &src,
            Some(&nrm),
            *t0,
            &icp_options(iterations, tau, min_dot),
        )
        .map_or(*t0, |r| r.motion)
    };
    // Re-orthonormalise the rotation (accumulated round-off).
    let q = DQuat::from_mat3(&t.matrix3).normalize();
    DAffine3::from_mat3_translation(DMat3::from_quat(q), t.translation)
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshcore::linalg::rigid_inverse;
    use proptest::prelude::*;

    fn ellipsoid() -> meshcore::TriMesh {
        let (pos, tri) = meshcore::shapes::icosphere(3).into_parts();
        let pos = pos
            .into_iter()
            .map(|p| p * DVec3::new(3.0, 2.0, 1.2))
            .collect();
        meshcore::TriMesh::new(pos, tri).unwrap()
    }

    /// Every point the far grid calls far is farther than the bound plus its reach from every
    /// vertex (so `near` is `None` only where `query` would give `d2 >= tau^2`), and the grid
    /// does call far most of the space well away from the surface.
    #[test]
    fn far_cells_are_far_from_every_vertex() {
        let mesh = ellipsoid();
        let mut idx = crate::detect::surface_index(&mesh);
        // One vertex with a long reach (as a spike's) gets its own, wider dilation.
        idx.reach[0] = 0.8;
        let bound = 0.3;
        idx.mark_far(bound);
        let (mut far, mut total) = (0, 0);
        for i in 0..40 {
            for j in 0..40 {
                for k in 0..20 {
                    let q = DVec3::new(
                        -4.5 + 9.0 * i as f64 / 39.0,
                        -3.5 + 7.0 * j as f64 / 39.0,
                        -2.5 + 5.0 * k as f64 / 19.0,
                    );
                    total += 1;
                    for tau in [bound, 0.5 * bound] {
                        match idx.near(q, tau) {
                            None => {
                                far += usize::from(tau == bound);
                                for (v, p) in idx.pos.iter().enumerate() {
                                    let gap = (*p - q).length() - idx.reach[v];
                                    assert!(gap > bound, "{q:?} is {gap} from vertex {v}");
                                }
                                assert!(idx.query(q).d2 >= tau * tau);
                            }
                            Some(h) => assert_eq!(h.vertex, idx.query(q).vertex),
                        }
                    }
                    // Beyond the bound the grid says nothing: the tree answers.
                    assert!(idx.near(q, 2.0 * bound).is_some());
                }
            }
        }
        assert!(far > total / 3, "{far} of {total} points called far");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(12))]

        #[test]
        fn a_rigid_copy_of_the_surface_is_recovered(
            ax in (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64),
            deg in 0.0..8.0f64,
            t in (-0.1..0.1f64, -0.1..0.1f64, -0.1..0.1f64),
        ) {
            let mesh = ellipsoid();
            let idx = crate::detect::surface_index(&mesh);
            let axis = DVec3::new(ax.0, ax.1, ax.2 + 2.0);
            let m = DAffine3::from_mat3_translation(
                meshcore::linalg::axis_angle(axis, deg.to_radians()),
                DVec3::new(t.0, t.1, t.2),
            );
            // Template = the vertices with their normals moved by m^-1: ICP must find m.
            let inv = rigid_inverse(&m);
            let pts: Vec<(DVec3, DVec3)> = idx
                .pos
                .iter()
                .zip(&idx.nrm)
                .step_by(2)
                .map(|(p, n)| (inv.transform_point3(*p), inv.transform_vector3(*n)))
                .collect();
            let got = icp(&idx, &pts, &DAffine3::IDENTITY, 60, 1.0, 0.3);
            let da = meshcore::linalg::rotation_angle_between(got.matrix3, m.matrix3);
            let dt = (got.translation - m.translation).length();
            prop_assert!(da < 1e-6 && dt < 1e-6, "{da} {dt}");
            prop_assert!((got.matrix3.determinant() - 1.0).abs() < 1e-12);
        }
    }
}
