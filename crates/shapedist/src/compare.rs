//! One comparison of two keyed point sets in a chosen [`Mode`], with its options as flat
//! settings: what `bipolar distance`, `bipolar matrix` and the Python `distance` functions
//! share (they differ only in how the settings are spelt and the sets are read).

use glam::{DMat3, DVec3};
use serde_json::json;

use crate::{
    icp_distance, keyed_distance, GlobalOptions, IcpDistance, IcpOptions, IcpVariant,
    KeyedDistance, KeyedOptions, PrepareOptions, PreparedSet, RobustLoss, RotationMethod,
    ShapeDistError, Which,
};

meshcore::choice! {
    /// How two point sets are compared.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub enum Mode: "comparison mode", ShapeDistError {
        /// Points paired by key, closed-form rotation: normalised L2 distance
        /// ([`keyed_distance`]).
        #[default]
        Keys = "keys",
        /// Global ICP without keys: normalised mean closest-point distance after alignment.
        Icp = "icp",
        /// Global ICP without keys: normalised symmetric Hausdorff distance after alignment.
        Hausdorff = "hausdorff",
    }
}

impl Mode {
    /// What the distance of this mode is normalised by, in words.
    pub fn normalisation(self) -> &'static str {
        match self {
            Mode::Keys => {
                "min_R ||A - R B||_F / sqrt(||A||_F^2 + ||B||_F^2), centred, paired by key"
            }
            Mode::Icp => {
                "symmetric mean closest-point distance / (rho_A + rho_B), after global ICP"
            }
            Mode::Hausdorff => "symmetric Hausdorff distance / (rho_A + rho_B), after global ICP",
        }
    }
}

meshcore::choice! {
    /// Robust weights of the keyed fit by name, with the usual tuning constants.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum RobustWeights: "robust loss", ShapeDistError {
        /// [`RobustLoss::Huber`] with k = 1.345 robust sigmas.
        Huber = "huber",
        /// [`RobustLoss::Tukey`] with c = 4.685 robust sigmas.
        Tukey = "tukey",
    }
}

impl RobustWeights {
    /// The loss with its usual tuning constant.
    pub fn loss(self) -> RobustLoss {
        match self {
            RobustWeights::Huber => RobustLoss::Huber(1.345),
            RobustWeights::Tukey => RobustLoss::Tukey(4.685),
        }
    }
}

/// Settings of [`compare`]: the mode and the options of its method, as flat values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompareOptions {
    /// Comparison mode.
    pub mode: Mode,
    /// Keys mode: closed-form rotation solver.
    pub solver: RotationMethod,
    /// Keys mode: robust IRLS weights (None = plain least squares).
    pub robust: Option<RobustWeights>,
    /// Keys mode: drop pairs whose residual after alignment exceeds this length.
    pub gate: Option<f64>,
    /// ICP modes: error variant of the refinement.
    pub variant: IcpVariant,
    /// ICP modes: fraction of the worst pairs rejected at each iteration.
    pub trim: f64,
    /// ICP modes: maximum refinement iterations on all points (at least 1 is run).
    pub iterations: usize,
    /// ICP modes: multi-start global search (false: plain ICP from the identity).
    pub global_search: bool,
}

impl Default for CompareOptions {
    fn default() -> Self {
        Self {
            mode: Mode::Keys,
            solver: RotationMethod::Kabsch,
            robust: None,
            gate: None,
            variant: IcpVariant::PointToPoint,
            trim: 0.0,
            iterations: 100,
            global_search: true,
        }
    }
}

impl CompareOptions {
    /// Options of [`keyed_distance`] (5 IRLS re-fits when robust).
    pub fn keyed(&self) -> KeyedOptions {
        KeyedOptions {
            method: self.solver,
            robust: self.robust.map(RobustWeights::loss),
            irls_iterations: 5,
            gate: self.gate,
        }
    }

    /// Options of [`icp_distance`].
    pub fn global(&self) -> GlobalOptions {
        GlobalOptions {
            grid: self.global_search,
            refine: IcpOptions {
                variant: self.variant,
                max_iterations: self.iterations.max(1),
                trim: self.trim,
                ..IcpOptions::default()
            },
            ..GlobalOptions::default()
        }
    }
}

/// A point set as [`compare`] sees it: the keyed points (paired by key in the keys mode) and
/// all points (the ICP modes), prepared once when it is compared several times.
#[derive(Debug)]
pub struct ComparedSet {
    /// Packed keys of the points kept for the keyed comparison.
    pub keys: Vec<u64>,
    /// Positions of those points.
    pub key_points: Vec<DVec3>,
    /// All positions.
    pub points: Vec<DVec3>,
    prepared: Option<PreparedSet>,
}

impl ComparedSet {
    /// A set from its keyed points and all its points (not prepared).
    pub fn new(keys: Vec<u64>, key_points: Vec<DVec3>, points: Vec<DVec3>) -> Self {
        Self {
            keys,
            key_points,
            points,
            prepared: None,
        }
    }

    /// Prepares the set once for the ICP modes (nothing to do in the keys mode); `which`
    /// names it in errors.
    pub fn prepare(&mut self, mode: Mode, which: Which) -> Result<(), ShapeDistError> {
        if mode != Mode::Keys && self.prepared.is_none() {
            self.prepared = Some(PreparedSet::new(
                &self.points,
                &PrepareOptions::default(),
                which,
            )?);
        }
        Ok(())
    }
}

/// The result of [`compare`]: the result of the mode's method.
#[derive(Debug, Clone, PartialEq)]
pub enum Comparison {
    /// [`Mode::Keys`].
    Keys(KeyedDistance),
    /// [`Mode::Icp`] or [`Mode::Hausdorff`] (same alignment, other statistic).
    Icp(Mode, IcpDistance),
}

impl Comparison {
    /// The mode compared in.
    pub fn mode(&self) -> Mode {
        match self {
            Comparison::Keys(_) => Mode::Keys,
            Comparison::Icp(m, _) => *m,
        }
    }

    /// The normalised distance in [0, 1].
    pub fn distance(&self) -> f64 {
        match self {
            Comparison::Keys(r) => r.distance,
            Comparison::Icp(Mode::Icp, r) => r.stats.mean_normalised,
            Comparison::Icp(_, r) => r.stats.hausdorff_normalised,
        }
    }

    /// The details as a JSON object: mode, distance, rotation (rows) and translation of the
    /// motion mapping `b` onto `a`, the method's counts and residuals, and the point counts of
    /// `a` and `b` (the sets compared).
    pub fn details(&self, a: &ComparedSet, b: &ComparedSet) -> serde_json::Value {
        let mut v = match self {
            Comparison::Keys(r) => json!({
                "shared_keys": r.shared_keys,
                "pairs_used": r.pairs_used,
                "share_a": r.share_a,
                "share_b": r.share_b,
                "keyed_points_a": a.keys.len(),
                "keyed_points_b": b.keys.len(),
                "repeated_keys_a": r.ambiguous_a,
                "repeated_keys_b": r.ambiguous_b,
                "gated": r.gated,
                "rmse": r.rmse,
                "max_residual": r.max_residual,
            }),
            Comparison::Icp(_, r) => json!({
                "mean_normalised": r.stats.mean_normalised,
                "hausdorff_normalised": r.stats.hausdorff_normalised,
                "rms_normalised": r.stats.rms_normalised,
                "mean": r.stats.mean,
                "hausdorff": r.stats.hausdorff,
                "rms": r.stats.rms,
                "iterations": r.iterations,
                "converged": r.converged,
                "starts": r.starts,
                "rmse": r.rmse,
            }),
        };
        let motion = match self {
            Comparison::Keys(r) => r.motion,
            Comparison::Icp(_, r) => r.motion,
        };
        let common = json!({
            "mode": self.mode().to_string(),
            "distance": self.distance(),
            "rotation": rows(motion.matrix3),
            "translation": motion.translation.to_array(),
            "points_a": a.points.len(),
            "points_b": b.points.len(),
        });
        if let (Some(o), serde_json::Value::Object(c)) = (v.as_object_mut(), common) {
            o.extend(c);
        }
        v
    }
}

/// The rows of a rotation matrix.
fn rows(r: DMat3) -> [[f64; 3]; 3] {
    let t = r.transpose();
    [
        t.x_axis.to_array(),
        t.y_axis.to_array(),
        t.z_axis.to_array(),
    ]
}

/// Compares `b` with `a` in the mode of `o` (the ICP modes use the sets' preparation, or
/// prepare them here).
pub fn compare(
    a: &ComparedSet,
    b: &ComparedSet,
    o: &CompareOptions,
) -> Result<Comparison, ShapeDistError> {
    if o.mode == Mode::Keys {
        let r = keyed_distance(&a.keys, &a.key_points, &b.keys, &b.key_points, &o.keyed())?;
        return Ok(Comparison::Keys(r));
    }
    let owned;
    let (pa, pb) = match (&a.prepared, &b.prepared) {
        (Some(x), Some(y)) => (x, y),
        _ => {
            let po = PrepareOptions::default();
            owned = (
                PreparedSet::new(&a.points, &po, Which::A)?,
                PreparedSet::new(&b.points, &po, Which::B)?,
            );
            (&owned.0, &owned.1)
        }
    };
    Ok(Comparison::Icp(o.mode, icp_distance(pa, pb, &o.global())?))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud(n: usize, scale: f64) -> Vec<DVec3> {
        (0..n)
            .map(|i| {
                let t = i as f64 * 0.7;
                DVec3::new(
                    t.cos() * scale,
                    t.sin() * 2.0 * scale,
                    (0.3 * t).sin() * scale,
                )
            })
            .collect()
    }

    fn set(points: Vec<DVec3>) -> ComparedSet {
        let keys = (0..points.len() as u64).collect();
        ComparedSet::new(keys, points.clone(), points)
    }

    #[test]
    fn names_round_trip() {
        meshcore::choice::check_choice::<Mode>("chamfer").unwrap();
        meshcore::choice::check_choice::<RobustWeights>("cauchy").unwrap();
    }

    #[test]
    fn each_mode_gives_its_method_distance() {
        let a = set(cloud(60, 1.0));
        let b = set(cloud(60, 1.2));
        let keys = compare(&a, &b, &CompareOptions::default()).unwrap();
        let direct = keyed_distance(
            &a.keys,
            &a.key_points,
            &b.keys,
            &b.key_points,
            &Default::default(),
        )
        .unwrap();
        assert_eq!(keys.distance(), direct.distance);
        assert!(keys.distance() > 0.0);
        for mode in [Mode::Icp, Mode::Hausdorff] {
            let o = CompareOptions {
                mode,
                ..CompareOptions::default()
            };
            let (mut pa, mut pb) = (set(cloud(60, 1.0)), set(cloud(60, 1.2)));
            pa.prepare(mode, Which::A).unwrap();
            pb.prepare(mode, Which::B).unwrap();
            let fresh = compare(&a, &b, &o).unwrap();
            let prepared = compare(&pa, &pb, &o).unwrap();
            assert_eq!(fresh, prepared);
            assert_eq!(fresh.mode(), mode);
            let d = fresh.details(&a, &b);
            assert_eq!(d["mode"], mode.to_string());
            assert_eq!(d["distance"], fresh.distance());
            assert_eq!(d["points_b"], 60);
        }
    }

    #[test]
    fn robust_names_map_to_losses() {
        let o = CompareOptions {
            robust: Some("tukey".parse().unwrap()),
            ..CompareOptions::default()
        };
        assert_eq!(o.keyed().robust, Some(RobustLoss::Tukey(4.685)));
        assert_eq!(o.global().refine.max_iterations, 100);
    }
}
