//! Closed-form distance of two keyed point sets: pair the points by key, centre, solve the
//! rotation exactly (Kabsch or Horn), optionally with robust (IRLS) weights and a residual
//! gate.

use glam::{DAffine3, DMat3, DVec3};
use serde::Serialize;

use crate::error::{ShapeDistError, Which};
use crate::points::{check_spread, outer, validate};
use meshcore::linalg::{horn_rotation, kabsch_rotation};

meshcore::choice! {
    /// Closed-form solver for the rotation.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
    pub enum RotationMethod: "rotation solver", ShapeDistError {
        /// SVD of the 3x3 correlation matrix with the reflection guard.
        #[default]
        Kabsch = "kabsch",
        /// Horn's unit quaternion (largest eigenvector of a 4x4 symmetric matrix).
        Horn = "horn",
    }
}

/// Robust loss for iteratively reweighted least squares on the pair residuals.
///
/// The parameter is in units of the robust residual scale `sigma = 1.4826 * median(r_i)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum RobustLoss {
    /// Huber: weight 1 up to `k sigma`, then `k sigma / r` (1.345 is the usual choice).
    Huber(f64),
    /// Tukey's biweight: `(1 - (r / (c sigma))^2)^2` below `c sigma`, 0 above (usual 4.685).
    Tukey(f64),
}

/// Options of [`keyed_distance`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct KeyedOptions {
    /// Rotation solver.
    pub method: RotationMethod,
    /// Robust reweighting of the pairs (None = plain least squares).
    pub robust: Option<RobustLoss>,
    /// Number of IRLS re-fits when `robust` is set.
    pub irls_iterations: usize,
    /// Residual gate (absolute length, same unit as the points): after alignment, pairs whose
    /// residual `|a - R b|` exceeds it are dropped and the fit is repeated until stable. A
    /// gate of about `0.3 * D` (D = distance between the reference points) is the method
    /// notes' choice.
    pub gate: Option<f64>,
}

impl Default for KeyedOptions {
    fn default() -> Self {
        Self {
            method: RotationMethod::Kabsch,
            robust: None,
            irls_iterations: 5,
            gate: None,
        }
    }
}

/// Pairs of indices `(index in A, index in B)` sharing a key, in increasing key order.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Pairing {
    /// The pairs.
    pub pairs: Vec<(usize, usize)>,
    /// Points of A dropped because their key occurs more than once in A.
    pub ambiguous_a: usize,
    /// Points of B dropped because their key occurs more than once in B.
    pub ambiguous_b: usize,
}

/// `(key, index)` for every key, sorted by key then index: an LSD radix sort on bytes (stable,
/// so equal keys keep index order), skipping the byte positions where all keys agree (packed
/// descriptor keys use few of their 64 bits). Already sorted input is detected in one pass.
fn sort_by_key_then_index(keys: &[u64]) -> Vec<(u64, usize)> {
    let mut v: Vec<(u64, usize)> = keys.iter().copied().zip(0..).collect();
    if v.windows(2).all(|w| w[0].0 <= w[1].0) || v.len() < 64 {
        if v.len() < 64 {
            v.sort_unstable();
        }
        return v;
    }
    let (or, and) = keys
        .iter()
        .fold((0u64, u64::MAX), |(o, a), &k| (o | k, a & k));
    let varying = or ^ and;
    let mut tmp = vec![(0u64, 0usize); v.len()];
    for byte in 0..8 {
        let shift = 8 * byte;
        if (varying >> shift) & 0xff == 0 {
            continue;
        }
        let mut count = [0usize; 257];
        for &(k, _) in &v {
            count[((k >> shift) & 0xff) as usize + 1] += 1;
        }
        for d in 0..256 {
            count[d + 1] += count[d];
        }
        for &e in &v {
            let d = ((e.0 >> shift) & 0xff) as usize;
            tmp[count[d]] = e;
            count[d] += 1;
        }
        std::mem::swap(&mut v, &mut tmp);
    }
    v
}

/// Pairs two key lists: keys present exactly once in each list form a pair; keys repeated
/// within a list are ambiguous and dropped.
pub fn pair_by_keys(keys_a: &[u64], keys_b: &[u64]) -> Pairing {
    fn unique_sorted(keys: &[u64]) -> (Vec<(u64, usize)>, usize) {
        let v = sort_by_key_then_index(keys);
        let mut out = Vec::with_capacity(v.len());
        let mut dropped = 0;
        let mut i = 0;
        while i < v.len() {
            let mut j = i + 1;
            while j < v.len() && v[j].0 == v[i].0 {
                j += 1;
            }
            if j - i == 1 {
                out.push(v[i]);
            } else {
                dropped += j - i;
            }
            i = j;
        }
        (out, dropped)
    }
    let (ua, ambiguous_a) = unique_sorted(keys_a);
    let (ub, ambiguous_b) = unique_sorted(keys_b);
    let mut pairs = Vec::with_capacity(ua.len().min(ub.len()));
    let (mut i, mut j) = (0, 0);
    while i < ua.len() && j < ub.len() {
        match ua[i].0.cmp(&ub[j].0) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                pairs.push((ua[i].1, ub[j].1));
                i += 1;
                j += 1;
            }
        }
    }
    Pairing {
        pairs,
        ambiguous_a,
        ambiguous_b,
    }
}

/// Optimal rotation between paired rows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Alignment {
    /// Rotation `R` mapping centred B onto centred A (`a - c_a ~ R (b - c_b)`).
    pub rotation: DMat3,
    /// (Weighted) centroid of the paired points of A.
    pub centroid_a: DVec3,
    /// (Weighted) centroid of the paired points of B.
    pub centroid_b: DVec3,
    /// Normalised distance `sqrt(sum w |a - R b|^2 / (sum w |a|^2 + sum w |b|^2))`, centred
    /// points, in [0, 1].
    pub distance: f64,
    /// Root mean square residual `sqrt(sum w |a - R b|^2 / sum w)` (unnormalised).
    pub rmse: f64,
}

/// Least-squares rotation (about the centroids) between paired points `a[i] <-> b[i]`, with
/// optional non-negative weights.
///
/// Errors: empty or unequal inputs, non-finite values, collinear or coincident points (the
/// rotation is then undefined).
pub fn align_pairs(
    a: &[DVec3],
    b: &[DVec3],
    weights: Option<&[f64]>,
    method: RotationMethod,
) -> Result<Alignment, ShapeDistError> {
    validate(a, Which::A)?;
    validate(b, Which::B)?;
    if a.len() != b.len() {
        return Err(ShapeDistError::InvalidOption(format!(
            "paired sets differ in size ({} and {})",
            a.len(),
            b.len()
        )));
    }
    let n_pos = match weights {
        Some(w) => {
            if w.len() != a.len() || w.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                return Err(ShapeDistError::InvalidOption(
                    "weights must be finite, non-negative, one per pair".into(),
                ));
            }
            w.iter().filter(|&&x| x > 0.0).count()
        }
        None => a.len(),
    };
    if n_pos < 3 {
        return Err(ShapeDistError::TooFewPairs {
            found: n_pos,
            needed: 3,
            detail: "pairs with a positive weight".into(),
        });
    }
    let w = |i: usize| weights.map_or(1.0, |w| w[i]);
    let wsum: f64 = (0..a.len()).map(w).sum();
    let ca = (0..a.len()).map(|i| a[i] * w(i)).sum::<DVec3>() / wsum;
    let cb = (0..b.len()).map(|i| b[i] * w(i)).sum::<DVec3>() / wsum;
    // Degeneracy is judged on the (positively weighted) centred points.
    let sel = |pts: &[DVec3], c: DVec3| -> Vec<DVec3> {
        (0..pts.len())
            .filter(|&i| w(i) > 0.0)
            .map(|i| (pts[i] - c) * w(i).sqrt())
            .collect()
    };
    check_spread(&sel(a, ca), Which::A)?;
    check_spread(&sel(b, cb), Which::B)?;
    let mut k = DMat3::ZERO;
    let (mut na, mut nb) = (0.0, 0.0);
    for i in 0..a.len() {
        let (pa, pb, wi) = (a[i] - ca, b[i] - cb, w(i));
        k += outer(pa * wi, pb);
        na += wi * pa.length_squared();
        nb += wi * pb.length_squared();
    }
    let rotation = match method {
        RotationMethod::Kabsch => kabsch_rotation(k).0,
        RotationMethod::Horn => horn_rotation(k).0,
    };
    let ss: f64 = (0..a.len())
        .map(|i| w(i) * ((a[i] - ca) - rotation * (b[i] - cb)).length_squared())
        .sum();
    let den = na + nb;
    let distance = if den > 0.0 {
        (ss / den).sqrt().min(1.0)
    } else {
        0.0
    };
    Ok(Alignment {
        rotation,
        centroid_a: ca,
        centroid_b: cb,
        distance,
        rmse: (ss / wsum).sqrt(),
    })
}

/// Result of [`keyed_distance`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct KeyedDistance {
    /// Normalised L2 distance in [0, 1] over the pairs used (weighted when robust).
    pub distance: f64,
    /// Rigid motion mapping B onto A: `a ~ motion * b`, with `motion.matrix3` the rotation
    /// about the centroids and `motion.translation = c_a - R c_b`.
    pub motion: DAffine3,
    /// Keys present exactly once in both sets.
    pub shared_keys: usize,
    /// Pairs used in the final fit (after the residual gate).
    pub pairs_used: usize,
    /// `shared_keys / |A|`.
    pub share_a: f64,
    /// `shared_keys / |B|`.
    pub share_b: f64,
    /// Points of A with a repeated key (dropped).
    pub ambiguous_a: usize,
    /// Points of B with a repeated key (dropped).
    pub ambiguous_b: usize,
    /// Pairs rejected by the residual gate.
    pub gated: usize,
    /// Unweighted RMS residual over the pairs used (same unit as the points).
    pub rmse: f64,
    /// Largest residual over the pairs used.
    pub max_residual: f64,
}

/// Normalised L2 distance between two keyed point sets (closed form, see
/// `docs/shape-distance.md`): pairs by key, centres, finds the optimal rotation.
///
/// `d = min_R ||A - R B||_F / sqrt(||A||_F^2 + ||B||_F^2)` over the paired, centred points.
pub fn keyed_distance(
    keys_a: &[u64],
    a: &[DVec3],
    keys_b: &[u64],
    b: &[DVec3],
    opts: &KeyedOptions,
) -> Result<KeyedDistance, ShapeDistError> {
    for (which, k, p) in [(Which::A, keys_a, a), (Which::B, keys_b, b)] {
        if k.len() != p.len() {
            return Err(ShapeDistError::LengthMismatch {
                which,
                keys: k.len(),
                points: p.len(),
            });
        }
        validate(p, which)?;
    }
    if let Some(g) = opts.gate {
        if !(g.is_finite() && g > 0.0) {
            return Err(ShapeDistError::InvalidOption(format!(
                "residual gate must be positive and finite, got {g}"
            )));
        }
    }
    if let Some(RobustLoss::Huber(p) | RobustLoss::Tukey(p)) = opts.robust {
        if !(p.is_finite() && p > 0.0) {
            return Err(ShapeDistError::InvalidOption(format!(
                "robust loss parameter must be positive and finite, got {p}"
            )));
        }
    }
    let pairing = pair_by_keys(keys_a, keys_b);
    let shared = pairing.pairs.len();
    if shared < 3 {
        return Err(ShapeDistError::TooFewPairs {
            found: shared,
            needed: 3,
            detail: format!(
                "{} and {} points, {} and {} dropped as ambiguous",
                a.len(),
                b.len(),
                pairing.ambiguous_a,
                pairing.ambiguous_b
            ),
        });
    }
    let mut pairs = pairing.pairs.clone();
    let mut gated = 0;
    let (align, weights) = loop {
        let pa: Vec<DVec3> = pairs.iter().map(|&(i, _)| a[i]).collect();
        let pb: Vec<DVec3> = pairs.iter().map(|&(_, j)| b[j]).collect();
        let (al, w) = fit(&pa, &pb, opts)?;
        let Some(gate) = opts.gate else {
            break (al, w);
        };
        let keep: Vec<bool> = pa
            .iter()
            .zip(&pb)
            .map(|(&x, &y)| residual(&al, x, y) <= gate)
            .collect();
        let n_keep = keep.iter().filter(|&&k| k).count();
        if n_keep == pairs.len() {
            break (al, w);
        }
        if n_keep < 3 {
            return Err(ShapeDistError::TooFewPairs {
                found: n_keep,
                needed: 3,
                detail: format!("{shared} shared keys, residual gate {gate} rejects the rest"),
            });
        }
        gated += pairs.len() - n_keep;
        pairs = pairs
            .iter()
            .zip(&keep)
            .filter(|(_, &k)| k)
            .map(|(&p, _)| p)
            .collect();
    };
    let _ = weights;
    let res: Vec<f64> = pairs
        .iter()
        .map(|&(i, j)| residual(&align, a[i], b[j]))
        .collect();
    let rmse = (res.iter().map(|r| r * r).sum::<f64>() / res.len() as f64).sqrt();
    Ok(KeyedDistance {
        distance: align.distance,
        motion: DAffine3::from_mat3_translation(
            align.rotation,
            align.centroid_a - align.rotation * align.centroid_b,
        ),
        shared_keys: shared,
        pairs_used: pairs.len(),
        share_a: shared as f64 / a.len() as f64,
        share_b: shared as f64 / b.len() as f64,
        ambiguous_a: pairing.ambiguous_a,
        ambiguous_b: pairing.ambiguous_b,
        gated,
        rmse,
        max_residual: res.iter().fold(0.0, |m: f64, &r| m.max(r)),
    })
}

fn residual(al: &Alignment, a: DVec3, b: DVec3) -> f64 {
    ((a - al.centroid_a) - al.rotation * (b - al.centroid_b)).length()
}

/// Plain or IRLS fit of paired points.
fn fit(
    a: &[DVec3],
    b: &[DVec3],
    opts: &KeyedOptions,
) -> Result<(Alignment, Option<Vec<f64>>), ShapeDistError> {
    let mut al = align_pairs(a, b, None, opts.method)?;
    let Some(loss) = opts.robust else {
        return Ok((al, None));
    };
    let mut w = vec![1.0; a.len()];
    for _ in 0..opts.irls_iterations {
        let r: Vec<f64> = a
            .iter()
            .zip(b)
            .map(|(&x, &y)| residual(&al, x, y))
            .collect();
        let mut sorted = r.clone();
        sorted.sort_unstable_by(f64::total_cmp);
        let med = sorted[sorted.len() / 2];
        let scale = r.iter().fold(0.0f64, |m, &x| m.max(x));
        let sigma = (1.4826 * med).max(scale * 1e-9);
        if sigma == 0.0 {
            break; // perfect fit
        }
        for (wi, &ri) in w.iter_mut().zip(&r) {
            *wi = match loss {
                RobustLoss::Huber(k) => {
                    if ri <= k * sigma {
                        1.0
                    } else {
                        k * sigma / ri
                    }
                }
                RobustLoss::Tukey(c) => {
                    let u = ri / (c * sigma);
                    if u < 1.0 {
                        (1.0 - u * u).powi(2)
                    } else {
                        0.0
                    }
                }
            };
        }
        al = align_pairs(a, b, Some(&w), opts.method)?;
    }
    Ok((al, Some(w)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn radix_pairing_sort_equals_a_comparison_sort() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for (n, bits) in [
            (10usize, 57u32),
            (100, 12),
            (5000, 40),
            (5000, 57),
            (3000, 3),
        ] {
            let keys: Vec<u64> = (0..n)
                .map(|_| (rng.random::<u64>() >> (64 - bits)) << 7)
                .collect();
            let mut want: Vec<(u64, usize)> = keys.iter().copied().zip(0..).collect();
            want.sort();
            assert_eq!(sort_by_key_then_index(&keys), want, "n {n}, bits {bits}");
            let sorted: Vec<u64> = want.iter().map(|e| e.0).collect();
            assert_eq!(
                sort_by_key_then_index(&sorted),
                sorted.iter().copied().zip(0..).collect::<Vec<_>>()
            );
        }
    }
}
