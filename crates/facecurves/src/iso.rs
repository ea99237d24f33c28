//! Iso-curvature curves (Bannour and Ghorbel; the paper's section 6.1): the network of level
//! curves of the two principal curvature fields of a surface.
//!
//! The principal curvatures `k1 >= k2` come from the workspace's one estimator,
//! [`landmarks::curvature::vertex_curvatures`] (quadric fit over a Euclidean ball, positive
//! where the surface bends away from its outward normal); each field is linear inside a face
//! and its level curves at the chosen levels ([`IsoLevels`]) are extracted by
//! [`levelcurves::isolines`]. An optional vertex mask limits the network to a region (a face's
//! central part: the fits of border vertices are one-sided).
//!
//! The curves carry no correspondence across surfaces, so two networks are compared as point
//! sets ([`iso_curvature_distance`]): a global ICP alignment and the normalised RMS
//! closest-point distance of `shapedist`.

use crate::FaceCurvesError;
use glam::DVec3;
use landmarks::curvature::{vertex_curvatures, CurvatureOptions};
use meshcore::Surface;

meshcore::choice! {
    /// Which principal curvature field a curve is a level set of.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
    pub enum PrincipalField: "principal curvature field", crate::FaceCurvesError {
        /// The maximum principal curvature `k1`.
        K1 = "k1" | "max",
        /// The minimum principal curvature `k2`.
        K2 = "k2" | "min",
    }
}

/// The curvature levels whose level sets form the network.
#[derive(Debug, Clone, PartialEq)]
pub enum IsoLevels {
    /// Given levels (1 / mesh units) of each field; use this to compare surfaces at the same
    /// levels.
    Explicit {
        /// Levels of `k1`.
        k1: Vec<f64>,
        /// Levels of `k2`.
        k2: Vec<f64>,
    },
    /// `count` levels per field, uniform strictly between the `low` and `high` quantiles of
    /// the field over the kept vertices (`0 <= low < high <= 1`):
    /// `v_low + (v_high - v_low) i / (count + 1)`, `i = 1..=count`.
    Quantiles {
        /// Levels per field (at least 1).
        count: usize,
        /// Lower quantile.
        low: f64,
        /// Upper quantile.
        high: f64,
    },
}

/// Options of [`describe_iso_curvature`].
#[derive(Debug, Clone, PartialEq)]
pub struct IsoCurvatureOptions {
    /// Radius of the curvature fits as a multiple of the mesh's mean edge length (positive).
    pub radius_edges: f64,
    /// Minimum neighbours of a curvature fit (see [`CurvatureOptions`]).
    pub min_neighbours: usize,
    /// The levels.
    pub levels: IsoLevels,
}

impl Default for IsoCurvatureOptions {
    /// Fits over 3 mean edge lengths, 6 levels per field between the 5 % and 95 % quantiles.
    fn default() -> Self {
        Self {
            radius_edges: 3.0,
            min_neighbours: 12,
            levels: IsoLevels::Quantiles {
                count: 6,
                low: 0.05,
                high: 0.95,
            },
        }
    }
}

/// One iso-curvature curve: a connected piece of a level set.
#[derive(Debug, Clone, PartialEq)]
pub struct IsoCurve {
    /// The field it is a level set of.
    pub field: PrincipalField,
    /// Index of its level in [`IsoCurvatureDescriptor::levels_k1`] or `levels_k2`.
    pub level_index: usize,
    /// The curvature value (1 / mesh units).
    pub level: f64,
    /// Ordered points on mesh edges (a closed curve does not repeat its first point).
    pub points: Vec<DVec3>,
    /// True for a closed loop.
    pub closed: bool,
}

/// The iso-curvature network of a surface.
#[derive(Debug, Clone, PartialEq)]
pub struct IsoCurvatureDescriptor {
    /// The curves: `k1` levels first, then `k2`, each in level order and in the
    /// deterministic piece order of [`levelcurves::isolines`].
    pub curves: Vec<IsoCurve>,
    /// Levels of `k1` used.
    pub levels_k1: Vec<f64>,
    /// Levels of `k2` used.
    pub levels_k2: Vec<f64>,
    /// Per-vertex `k1` (NaN outside the mask).
    pub k1: Vec<f64>,
    /// Per-vertex `k2` (NaN outside the mask).
    pub k2: Vec<f64>,
    /// Fitting radius used (mesh units).
    pub radius: f64,
}

impl IsoCurvatureDescriptor {
    /// Every curve point, in curve order (the point set compared by
    /// [`iso_curvature_distance`]).
    pub fn points(&self) -> Vec<DVec3> {
        self.curves
            .iter()
            .flat_map(|c| c.points.iter().copied())
            .collect()
    }
}

/// Value at quantile `q` (nearest rank) of the sorted finite values.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    let n = sorted.len();
    let idx = ((n - 1) as f64 * q).round() as usize;
    sorted[idx.min(n - 1)]
}

fn levels_of(field: &[f64], levels: &IsoLevels, explicit: Option<&Vec<f64>>) -> Vec<f64> {
    match (levels, explicit) {
        (_, Some(l)) => l.clone(),
        (
            IsoLevels::Quantiles {
                count, low, high, ..
            },
            None,
        ) => {
            let mut v: Vec<f64> = field.iter().copied().filter(|x| x.is_finite()).collect();
            v.sort_by(f64::total_cmp);
            if v.is_empty() {
                return Vec::new();
            }
            let (a, b) = (quantile(&v, *low), quantile(&v, *high));
            (1..=*count)
                .map(|i| a + (b - a) * i as f64 / (*count + 1) as f64)
                .collect()
        }
        (IsoLevels::Explicit { .. }, None) => Vec::new(),
    }
}

fn check_options(o: &IsoCurvatureOptions) -> Result<(), FaceCurvesError> {
    let bad = |m: String| Err(FaceCurvesError::InvalidOption(m));
    if !(o.radius_edges.is_finite() && o.radius_edges > 0.0) {
        return bad(format!(
            "curvature radius {} mean edge lengths (must be positive and finite)",
            o.radius_edges
        ));
    }
    match &o.levels {
        IsoLevels::Explicit { k1, k2 } => {
            if k1.is_empty() && k2.is_empty() {
                return bad("no curvature levels given".into());
            }
            if let Some(x) = k1.iter().chain(k2).find(|x| !x.is_finite()) {
                return bad(format!("curvature level {x} (must be finite)"));
            }
        }
        IsoLevels::Quantiles { count, low, high } => {
            if *count == 0 {
                return bad("0 curvature levels (must be at least 1)".into());
            }
            if !(0.0 <= *low && low < high && *high <= 1.0) {
                return bad(format!(
                    "curvature quantiles {low}..{high} (need 0 <= low < high <= 1)"
                ));
            }
        }
    }
    Ok(())
}

/// The principal curvature fields `(k1, k2)` of `surface` (one value per vertex, `k1 >= k2`,
/// 1 / mesh units) and the fitting radius used (`options.radius_edges` mean edge lengths):
/// the fields whose level sets [`describe_iso_curvature`] extracts.
pub fn principal_curvature_fields(
    surface: &Surface,
    options: &IsoCurvatureOptions,
) -> Result<(Vec<f64>, Vec<f64>, f64), FaceCurvesError> {
    check_options(options)?;
    let mesh = surface.mesh();
    let radius = options.radius_edges * mesh.mean_edge_length();
    if !(radius.is_finite() && radius > 0.0) {
        return Err(FaceCurvesError::InvalidOption(format!(
            "curvature radius {radius} (the mesh has no edge of positive length)"
        )));
    }
    let curv = vertex_curvatures(
        mesh,
        &CurvatureOptions {
            radius,
            min_neighbours: options.min_neighbours,
        },
    );
    Ok((
        curv.iter().map(|c| c.k1).collect(),
        curv.iter().map(|c| c.k2).collect(),
        radius,
    ))
}

/// The iso-curvature network of `surface`: principal curvatures at every vertex, then the
/// level curves of `k1` and `k2` at the levels of `options`. With `mask` (one flag per
/// vertex), only faces whose three vertices are kept carry curves and quantile levels use
/// the kept vertices only.
///
/// Errors: invalid options, a mask of the wrong length, no vertex kept, or no curve at any
/// level ([`FaceCurvesError::NoCurves`]).
pub fn describe_iso_curvature(
    surface: &Surface,
    mask: Option<&[bool]>,
    options: &IsoCurvatureOptions,
) -> Result<IsoCurvatureDescriptor, FaceCurvesError> {
    check_options(options)?;
    let mesh = surface.mesh();
    let n = mesh.n_vertices();
    if let Some(m) = mask {
        if m.len() != n {
            return Err(FaceCurvesError::VertexCount {
                what: "mask",
                expected: n,
                got: m.len(),
            });
        }
        if !m.iter().any(|&k| k) {
            return Err(FaceCurvesError::NoCurves("the mask keeps no vertex".into()));
        }
    }
    let (k1, k2, radius) = principal_curvature_fields(surface, options)?;
    let keep = |v: usize| mask.is_none_or(|m| m[v]);
    let k1: Vec<f64> = (0..n)
        .map(|v| if keep(v) { k1[v] } else { f64::NAN })
        .collect();
    let k2: Vec<f64> = (0..n)
        .map(|v| if keep(v) { k2[v] } else { f64::NAN })
        .collect();
    let (e1, e2) = match &options.levels {
        IsoLevels::Explicit { k1, k2 } => (Some(k1), Some(k2)),
        IsoLevels::Quantiles { .. } => (None, None),
    };
    let levels_k1 = levels_of(&k1, &options.levels, e1);
    let levels_k2 = levels_of(&k2, &options.levels, e2);
    let mut curves = Vec::new();
    for (field, values, levels) in [
        (PrincipalField::K1, &k1, &levels_k1),
        (PrincipalField::K2, &k2, &levels_k2),
    ] {
        if levels.is_empty() {
            continue;
        }
        let lines = levelcurves::isolines(mesh, surface.topology(), values, levels)?;
        for (li, pieces) in lines.into_iter().enumerate() {
            for p in pieces {
                curves.push(IsoCurve {
                    field,
                    level_index: li,
                    level: levels[li],
                    points: p.points,
                    closed: p.closed,
                });
            }
        }
    }
    if curves.is_empty() {
        return Err(FaceCurvesError::NoCurves(format!(
            "no level of k1 {levels_k1:?} or k2 {levels_k2:?} crosses the surface"
        )));
    }
    Ok(IsoCurvatureDescriptor {
        curves,
        levels_k1,
        levels_k2,
        k1,
        k2,
        radius,
    })
}

/// Distance of two iso-curvature networks: their points are aligned by a global ICP
/// ([`shapedist::icp_distance_points`] with `opts`) and compared by closest points. The
/// normalised RMS closest-point distance (`stats.rms_normalised`, in `[0, 1]`) is the
/// distance; the result carries the alignment and the other statistics too.
pub fn iso_curvature_distance(
    a: &IsoCurvatureDescriptor,
    b: &IsoCurvatureDescriptor,
    opts: &shapedist::GlobalOptions,
) -> Result<shapedist::IcpDistance, FaceCurvesError> {
    Ok(shapedist::icp_distance_points(
        &a.points(),
        &b.points(),
        opts,
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn choices_parse() {
        meshcore::choice::check_choice::<PrincipalField>("k3").unwrap();
    }

    #[test]
    fn quantile_levels_lie_strictly_inside() {
        let f: Vec<f64> = (0..101).map(|i| i as f64).collect();
        let l = levels_of(
            &f,
            &IsoLevels::Quantiles {
                count: 3,
                low: 0.1,
                high: 0.9,
            },
            None,
        );
        assert_eq!(l, vec![30.0, 50.0, 70.0]);
    }

    #[test]
    fn bad_options_are_named() {
        let s = Surface::new(meshcore::shapes::icosphere(1));
        let o = IsoCurvatureOptions {
            radius_edges: -1.0,
            ..Default::default()
        };
        let e = describe_iso_curvature(&s, None, &o).unwrap_err();
        assert!(e.to_string().contains("curvature radius"), "{e}");
        let o = IsoCurvatureOptions {
            levels: IsoLevels::Quantiles {
                count: 2,
                low: 0.9,
                high: 0.1,
            },
            ..Default::default()
        };
        assert!(describe_iso_curvature(&s, None, &o).is_err());
        let e = describe_iso_curvature(&s, Some(&[true; 3]), &Default::default()).unwrap_err();
        assert!(matches!(
            e,
            FaceCurvesError::VertexCount { what: "mask", .. }
        ));
    }
}
