#![allow(dead_code, missing_docs)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shapedist::glam::{DMat3, DQuat, DVec3};
use shapedist::{PrepareOptions, PreparedSet, Which};

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// Uniform random rotation (Shoemake).
pub fn random_rotation(r: &mut ChaCha8Rng) -> DMat3 {
    let (u1, u2, u3): (f64, f64, f64) = (r.random(), r.random(), r.random());
    let tau = std::f64::consts::TAU;
    let q = DQuat::from_xyzw(
        (1.0 - u1).sqrt() * (tau * u2).sin(),
        (1.0 - u1).sqrt() * (tau * u2).cos(),
        u1.sqrt() * (tau * u3).sin(),
        u1.sqrt() * (tau * u3).cos(),
    );
    DMat3::from_quat(q.normalize())
}

/// Rotation by exactly `deg` degrees about a random axis.
pub fn rotation_by(r: &mut ChaCha8Rng, deg: f64) -> DMat3 {
    let axis = DVec3::new(
        r.random::<f64>() - 0.5,
        r.random::<f64>() - 0.5,
        r.random::<f64>() - 0.5,
    )
    .normalize();
    DMat3::from_axis_angle(axis, deg.to_radians())
}

/// A vector uniform in the cube of side `scale` centred at the origin (three draws).
pub fn noise(r: &mut ChaCha8Rng, scale: f64) -> DVec3 {
    DVec3::new(
        r.random::<f64>() - 0.5,
        r.random::<f64>() - 0.5,
        r.random::<f64>() - 0.5,
    ) * scale
}

/// `n` points uniform in the cube of side `scale` centred at the origin.
pub fn random_cloud(r: &mut ChaCha8Rng, n: usize, scale: f64) -> Vec<DVec3> {
    (0..n).map(|_| noise(r, scale)).collect()
}

/// `p` prepared as set `w` with the default options.
pub fn prepared(p: &[DVec3], w: Which) -> PreparedSet {
    PreparedSet::new(p, &PrepareOptions::default(), w).unwrap()
}

/// A smooth asymmetric "face-like" height field over an ellipse (as the ICP peers' patch).
pub fn patch(r: &mut ChaCha8Rng, n: usize, shape_seed: u64) -> Vec<DVec3> {
    let mut s = ChaCha8Rng::seed_from_u64(10_000 + shape_seed);
    let bumps: Vec<(f64, f64, f64, f64)> = (0..8)
        .map(|_| {
            (
                (s.random::<f64>() * 1.4 - 0.7) * 0.8,
                s.random::<f64>() * 1.4 - 0.7,
                s.random::<f64>() * 0.37 - 0.12,
                s.random::<f64>() * 0.23 + 0.12,
            )
        })
        .collect();
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let x = (r.random::<f64>() * 2.0 - 1.0) * 0.8;
        let y = r.random::<f64>() * 2.0 - 1.0;
        if (x / 0.8).powi(2) + y * y > 1.0 {
            continue;
        }
        let mut z = 0.35 * (1.0 - (x / 0.8).powi(2) - y * y);
        for &(cx, cy, a, sg) in &bumps {
            z += a * (-((x - cx).powi(2) + (y - cy).powi(2)) / (2.0 * sg * sg)).exp();
        }
        out.push(DVec3::new(x, y, z));
    }
    out
}

pub fn angle_deg(a: DMat3, b: DMat3) -> f64 {
    meshcore::linalg::rotation_angle_between(a, b).to_degrees()
}
