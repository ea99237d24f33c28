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
