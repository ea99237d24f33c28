//! Both curve representations of a face built around its nose tip, as the experiments
//! (`cargo xtask section6`, `cargo xtask recognition`) build and score them:
//!
//! * **facial curves**: the level curves of the geodesic distance `U_n` from the nose tip at
//!   `D / N, 2 D / N, ..., D` (`D` the geodesic distance between the outer eye corners),
//!   compared level by level with the elastic (SRVF) distance, root sum of squares;
//! * **iso-curvature curves**: the level sets of the principal curvatures in the geodesic disc
//!   `U_n <= D` around the nose tip, at levels shared by every face of an experiment (the
//!   quantiles of one reference face), compared by the normalised RMS closest-point distance
//!   after a global ICP.

use crate::{
    describe_facial_curves, describe_iso_curvature, facial_curves_distance, iso_curvature_distance,
    Aggregate, ElasticOptions, FaceCurvesError, FacialCurvesDescriptor, FacialCurvesOptions,
    IsoCurvatureDescriptor, IsoCurvatureOptions, IsoLevels,
};
use meshcore::{DMat3, Surface};
use shapedist::{IcpOptions, PrepareOptions, PreparedSet, ShapeDistError, Which};

/// Lower and upper quantile of the reference face's curvatures between which the shared
/// iso-curvature levels lie.
pub const ISO_QUANTILES: (f64, f64) = (0.05, 0.95);

/// The geodesic disc `U_n <= d` around the nose tip (one flag per vertex of the field `un`):
/// the region of the iso-curvature network.
pub fn nose_disc(un: &[f64], d: f64) -> Vec<bool> {
    un.iter().map(|&u| u <= d).collect()
}

/// The facial curves of a face: the levels `i d / n` (`i = 1..=n`) of the nose field `un`.
pub fn facial_curves(
    surface: &Surface,
    un: &[f64],
    d: f64,
    n: u32,
) -> Result<FacialCurvesDescriptor, FaceCurvesError> {
    describe_facial_curves(
        surface,
        un,
        &FacialCurvesOptions {
            step: d / f64::from(n),
            levels: n,
        },
    )
}

/// The iso-curvature network of a face in its nose disc ([`nose_disc`]) at `levels`.
pub fn iso_curves(
    surface: &Surface,
    un: &[f64],
    d: f64,
    levels: &IsoLevels,
) -> Result<IsoCurvatureDescriptor, FaceCurvesError> {
    describe_iso_curvature(
        surface,
        Some(&nose_disc(un, d)),
        &IsoCurvatureOptions {
            levels: levels.clone(),
            ..Default::default()
        },
    )
}

/// The iso-curvature levels an experiment uses for every face: `count` levels per principal
/// field, uniform between the [`ISO_QUANTILES`] of the reference face's curvatures over its
/// nose disc (explicit levels, so that every face is cut at the same curvatures).
pub fn reference_iso_levels(
    surface: &Surface,
    un: &[f64],
    d: f64,
    count: usize,
) -> Result<IsoLevels, FaceCurvesError> {
    let probe = iso_curves(
        surface,
        un,
        d,
        &IsoLevels::Quantiles {
            count,
            low: ISO_QUANTILES.0,
            high: ISO_QUANTILES.1,
        },
    )?;
    Ok(IsoLevels::Explicit {
        k1: probe.levels_k1,
        k2: probe.levels_k2,
    })
}

/// Distance of two faces by their facial curves: elastic distance (`elastic`) per shared
/// level, root sum of squares (sqrt(mesh units)).
pub fn facial_distance(
    a: &FacialCurvesDescriptor,
    b: &FacialCurvesDescriptor,
    elastic: &ElasticOptions,
) -> Result<f64, FaceCurvesError> {
    facial_curves_distance(a, b, Aggregate::RootSumSquare, elastic).map(|d| d.distance)
}

/// Distance of two iso-curvature networks: normalised RMS closest-point distance after a
/// global ICP (default options), in `[0, 1]`.
pub fn iso_distance(
    a: &IsoCurvatureDescriptor,
    b: &IsoCurvatureDescriptor,
) -> Result<f64, FaceCurvesError> {
    iso_curvature_distance(a, b, &Default::default()).map(|d| d.stats.rms_normalised)
}

/// The points of an iso-curvature network prepared for ICP (centred, search trees), as the
/// first (`Which::A`) or second set of [`iso_distance_from`]; with `max_points`, every k-th
/// point in curve order, k the smallest stride that keeps at most `max_points`.
pub fn iso_point_set(
    d: &IsoCurvatureDescriptor,
    which: Which,
    max_points: Option<usize>,
) -> Result<PreparedSet, ShapeDistError> {
    let pts = d.points();
    let stride = max_points.map_or(1, |m| pts.len().div_ceil(m.max(1)).max(1));
    let kept: Vec<_> = pts.into_iter().step_by(stride).collect();
    PreparedSet::new(&kept, &PrepareOptions::default(), which)
}

/// [`iso_distance`] with the ICP (`opts`) started from the rotation `init` (of `b` onto `a`,
/// about the centroids; e.g. from landmarks) instead of the global search, then the
/// normalised RMS closest-point distance, in `[0, 1]`.
pub fn iso_distance_from(
    a: &PreparedSet,
    b: &PreparedSet,
    init: DMat3,
    opts: &IcpOptions,
) -> Result<f64, ShapeDistError> {
    let res = shapedist::icp(a, b, init, opts)?;
    Ok(shapedist::closest_point_stats(a, b, &res.motion).rms_normalised)
}

#[cfg(test)]
mod tests {
    use super::*;
    use geodesic::{Method, SolveOptions, Source};
    use meshcore::{DMat3, DQuat, DVec3, TriMesh};

    /// An ellipsoid (icosphere scaled), moved rigidly and with reversed vertex order.
    fn ellipsoid(moved: bool) -> TriMesh {
        let m = meshcore::shapes::icosphere(4);
        let rot = DMat3::from_quat(DQuat::from_axis_angle(
            DVec3::new(0.3, 1.0, -0.2).normalize(),
            0.8,
        ));
        let n = m.n_vertices() as u32;
        let map = |i: u32| if moved { n - 1 - i } else { i };
        let mut pos = vec![DVec3::ZERO; n as usize];
        for (i, p) in m.positions().iter().enumerate() {
            let e = DVec3::new(p.x * 3.0, p.y * 2.0, p.z * 1.5);
            pos[map(i as u32) as usize] = if moved {
                rot * e + DVec3::new(1.0, -2.0, 0.5)
            } else {
                e
            };
        }
        let tri = m
            .triangles()
            .iter()
            .map(|t| [map(t[0]), map(t[1]), map(t[2])])
            .collect();
        TriMesh::new(pos, tri).unwrap()
    }

    /// The vertex at the +z end of the unmoved ellipsoid (lowest index on ties).
    fn pole_of(m: &TriMesh) -> u32 {
        let mut best = 0;
        for (i, p) in m.positions().iter().enumerate() {
            if p.z > m.position(best).z {
                best = i as u32;
            }
        }
        best
    }

    /// Surface, nose field from `pole` and D = 2.5.
    fn set_up(m: &TriMesh, pole: u32) -> (Surface, Vec<f64>, f64) {
        let solver = geodesic::new_solver(m, Method::Exact).unwrap();
        let un = solver
            .distances(&[Source::Vertex(pole)], &SolveOptions::default())
            .unwrap();
        (Surface::new(m.clone()), un, 2.5)
    }

    #[test]
    fn nose_disc_keeps_the_vertices_within_d() {
        assert_eq!(
            nose_disc(&[0.0, 1.0, 1.5, f64::INFINITY], 1.0),
            vec![true, true, false, false]
        );
    }

    #[test]
    fn a_moved_renumbered_copy_is_near_zero_for_both_curve_distances() {
        let a = ellipsoid(false);
        let b = ellipsoid(true);
        let pole = pole_of(&a);
        let (sa, ua, d) = set_up(&a, pole);
        let (sb, ub, _) = set_up(&b, b.n_vertices() as u32 - 1 - pole);
        let fa = facial_curves(&sa, &ua, d, 5).unwrap();
        let fb = facial_curves(&sb, &ub, d, 5).unwrap();
        assert_eq!(fa.curves.len(), 5);
        let lv = reference_iso_levels(&sa, &ua, d, 4).unwrap();
        let IsoLevels::Explicit { k1, k2 } = &lv else {
            panic!("levels are explicit");
        };
        assert_eq!((k1.len(), k2.len()), (4, 4));
        let ia = iso_curves(&sa, &ua, d, &lv).unwrap();
        let ib = iso_curves(&sb, &ub, d, &lv).unwrap();
        let el = ElasticOptions::default();
        let same_f = facial_distance(&fa, &fb, &el).unwrap();
        let same_i = iso_distance(&ia, &ib).unwrap();
        // Another surface: the ellipsoid stretched by 20 % along one axis.
        let (pos, tri) = a.clone().into_parts();
        let c = TriMesh::new(
            pos.into_iter()
                .map(|p| DVec3::new(p.x * 1.2, p.y, p.z))
                .collect(),
            tri,
        )
        .unwrap();
        let (sc, uc, _) = set_up(&c, pole);
        let fc = facial_curves(&sc, &uc, d, 5).unwrap();
        let ic = iso_curves(&sc, &uc, d, &lv).unwrap();
        let other_f = facial_distance(&fa, &fc, &el).unwrap();
        let other_i = iso_distance(&ia, &ic).unwrap();
        assert!(same_f < 0.05 * other_f, "{same_f} vs {other_f}");
        assert!(same_i < 0.05 * other_i, "{same_i} vs {other_i}");
        // Started from the applied rotation (b = R a + t, so b onto a is R^T), the local ICP
        // finds the copy too, and the stretched ellipsoid stays far.
        let rot = DMat3::from_quat(DQuat::from_axis_angle(
            DVec3::new(0.3, 1.0, -0.2).normalize(),
            0.8,
        ));
        let (pa, pb, pc) = (
            iso_point_set(&ia, Which::A, None).unwrap(),
            iso_point_set(&ib, Which::B, Some(1000)).unwrap(),
            iso_point_set(&ic, Which::B, Some(1000)).unwrap(),
        );
        let o = shapedist::GlobalOptions::default().refine;
        let same_l = iso_distance_from(&pa, &pb, rot.transpose(), &o).unwrap();
        let other_l = iso_distance_from(&pa, &pc, DMat3::IDENTITY, &o).unwrap();
        assert!(same_l < 0.05 * other_l, "{same_l} vs {other_l}");
    }
}
