//! A probe's points against a target surface, started from corresponding landmarks: the
//! landmark-started trimmed ICP and its closest-point RMS, the score the recognition and scan
//! benchmarks give ICP on raw meshes.

use crate::target::{icp_to_target, Convergence, IcpLoopOptions, TrimRounding};
use crate::IcpVariant;
use glam::{DAffine3, DVec3};
use meshcore::linalg::fit_rigid;
use meshcore::FaceLocator;

/// ICP of points onto a surface as the benchmarks run it: point-to-point with translation onto
/// the closest surface points, the worst 10 % of pairs trimmed (kept count rounded down), at
/// most `max_iterations`, stop after a step when the trimmed RMS changed by at most `1e-6`
/// relative.
pub fn trimmed_icp(max_iterations: usize) -> IcpLoopOptions {
    IcpLoopOptions {
        variant: IcpVariant::PointToPoint,
        max_iterations,
        translation: true,
        trim: 0.1,
        trim_rounding: TrimRounding::Down,
        convergence: Convergence::RelativeRmseAfterStep { tolerance: 1e-6 },
        evaluate_final: false,
        ..IcpLoopOptions::default()
    }
}

/// ICP of `probe` onto the surface of `target` ([`icp_to_target`] with
/// [`trimmed_icp`]`(max_iterations)`), started from the rigid fit of `probe_lm` onto
/// `target_lm` (the same landmarks on both faces): the [`rms_to_surface`] of all probe points
/// at the final pose; NaN when the fit or a step fails.
pub fn landmark_icp_rms(
    probe: &[DVec3],
    probe_lm: &[DVec3],
    target: &FaceLocator<'_>,
    target_lm: &[DVec3],
    max_iterations: usize,
) -> f64 {
    let Some(init) = fit_rigid(probe_lm, target_lm, None) else {
        return f64::NAN;
    };
    let Ok(res) = icp_to_target(target, probe, None, init, &trimmed_icp(max_iterations)) else {
        return f64::NAN;
    };
    rms_to_surface(target, probe, &res.motion)
}

/// Root mean square distance of the `points` moved by `motion` to the surface of `target`
/// (every point counted; NaN where a query fails).
pub fn rms_to_surface(target: &FaceLocator<'_>, points: &[DVec3], motion: &DAffine3) -> f64 {
    let ss: f64 = points
        .iter()
        .map(|p| {
            target
                .nearest(motion.transform_point3(*p))
                .map_or(f64::NAN, |(_, d)| d * d)
        })
        .sum();
    (ss / points.len().max(1) as f64).sqrt()
}

/// About `n` of the points, evenly strided (every `len / max(n, 3)`-th, at least every one):
/// the probe points of [`landmark_icp_rms`].
pub fn strided_points(points: &[DVec3], n: usize) -> Vec<DVec3> {
    let stride = (points.len() / n.max(3)).max(1);
    points.iter().step_by(stride).copied().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, DQuat};

    #[test]
    fn icp_recovers_a_rigid_copy() {
        let m = meshcore::shapes::icosphere(2);
        let rot = DMat3::from_quat(DQuat::from_axis_angle(
            DVec3::new(1.0, 0.3, 0.2).normalize(),
            1.1,
        ));
        let t = DVec3::new(3.0, -2.0, 1.0);
        let probe: Vec<DVec3> = m.positions().iter().map(|p| rot * *p + t).collect();
        let lm_g = [m.position(0), m.position(5), m.position(9)];
        let lm_p = lm_g.map(|p| rot * p + t);
        let loc = FaceLocator::new(&m);
        assert!(landmark_icp_rms(&probe, &lm_p, &loc, &lm_g, 6) < 1e-9);
        // A scaled copy is not at distance 0.
        let big: Vec<DVec3> = probe.iter().map(|p| (*p - t) * 1.1 + t).collect();
        assert!(landmark_icp_rms(&big, &lm_p, &loc, &lm_g, 6) > 0.01);
        // Landmarks that cannot be fitted (another count on each side) give NaN.
        assert!(landmark_icp_rms(&probe, &lm_p, &loc, &lm_g[..2], 6).is_nan());
        assert_eq!(
            strided_points(&probe, 100).len(),
            probe.len().div_ceil(probe.len() / 100)
        );
        assert_eq!(strided_points(&probe[..2], 100).len(), 2);
    }
}
