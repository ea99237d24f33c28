//! Helpers shared by the exact-geodesic integration tests: mesh generators and a minimal OBJ
//! reader (only `v` and `f` lines; polygons are fan-split).
#![allow(dead_code)]

use geodesic::TriMesh;
use glam::DVec3;
#[allow(unused_imports)] // not every test binary that includes this module uses it
pub use meshcore::shapes::icosphere;
use std::path::PathBuf;

/// Reads the `v` and `f` lines of an OBJ file.
pub fn read_obj(path: &std::path::Path) -> Result<TriMesh, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut v = Vec::new();
    let mut f = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it
                    .take(3)
                    .map(|s| s.parse::<f64>())
                    .collect::<Result<_, _>>()
                    .map_err(|e| format!("{}:{}: {e}", path.display(), ln + 1))?;
                if c.len() != 3 {
                    return Err(format!("{}:{}: short vertex", path.display(), ln + 1));
                }
                v.push(DVec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let idx: Vec<u32> = it
                    .map(|s| {
                        let i: i64 = s
                            .split('/')
                            .next()
                            .unwrap_or("")
                            .parse()
                            .map_err(|e| format!("{}:{}: {e}", path.display(), ln + 1))?;
                        let i = if i > 0 { i - 1 } else { v.len() as i64 + i };
                        Ok(i as u32)
                    })
                    .collect::<Result<_, String>>()?;
                for k in 1..idx.len().saturating_sub(1) {
                    f.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    TriMesh::new(v, f).map_err(|e| e.to_string())
}

/// The shared data folder (`BIPOLAR_SHARED`, default `../shared` from the workspace root).
pub fn shared_dir() -> PathBuf {
    if let Ok(p) = std::env::var("BIPOLAR_SHARED") {
        return PathBuf::from(p);
    }
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared")
}

/// A planar grid of `nx` x `ny` squares of side `h` in the z = 0 plane, each split into two
/// triangles along alternating diagonals, vertices optionally jittered in the plane.
pub fn grid(nx: usize, ny: usize, h: f64, jitter: f64, seed: u64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut p = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let inner = i > 0 && j > 0 && i < nx && j < ny;
            let (dx, dy) = if inner && jitter > 0.0 {
                (
                    rng.random_range(-jitter..jitter) * h,
                    rng.random_range(-jitter..jitter) * h,
                )
            } else {
                (0.0, 0.0)
            };
            p.push(DVec3::new(i as f64 * h + dx, j as f64 * h + dy, 0.0));
        }
    }
    let idx = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut t = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            if (i + j) % 2 == 0 {
                t.push([a, b, c]);
                t.push([a, c, d]);
            } else {
                t.push([a, b, d]);
                t.push([b, c, d]);
            }
        }
    }
    (p, t)
}

/// Max relative difference `|a-b| / max(|b|, floor)` over finite entries; panics if the sets
/// of infinite entries differ.
pub fn max_rel_diff(a: &[f64], b: &[f64], floor: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    let mut m = 0.0f64;
    for (i, (&x, &y)) in a.iter().zip(b).enumerate() {
        assert_eq!(x.is_finite(), y.is_finite(), "vertex {i}: {x} vs {y}");
        if x.is_finite() {
            m = m.max((x - y).abs() / y.abs().max(floor));
        }
    }
    m
}
