//! Preparation of the exact solver (once per mesh): half-edge structure, per-half-edge frames,
//! dropped faces, cut non-manifold edges, pseudo-source flags.

use super::*;

impl ExactGeodesic {
    /// Prepares the solver: half-edge structure, frames, pseudo-source flags.
    ///
    /// Never fails on a valid [`TriMesh`]; degenerate and non-manifold parts are handled as
    /// described in the module documentation and listed in [`ExactGeodesic::report`].
    pub fn new(mesh: &TriMesh) -> Result<Self, GeodesicError> {
        let positions = mesh.positions().to_vec();
        let tris = mesh.triangles().to_vec();
        let n = positions.len();
        let m = tris.len();
        let nh = 3 * m;
        let min_edge = 1e-12 * mesh.bbox().diagonal();
        let mut report = ExactMeshReport::default();
        let mut live = vec![true; m];
        for (f, t) in tris.iter().enumerate() {
            let bad = t[0] == t[1]
                || t[1] == t[2]
                || t[0] == t[2]
                || (0..3).any(|k| {
                    edge_at_most(
                        positions[t[k] as usize] - positions[t[(k + 1) % 3] as usize],
                        min_edge,
                    )
                });
            if bad {
                live[f] = false;
                report.dropped_faces.push(f as u32);
            }
        }
        let twin = twins(&tris, &live, n, &mut report);
        // Frames.
        let mut geom = vec![HeGeom::default(); nh];
        // Total corner angle per vertex, approximated (see `approx_atan2`).
        let mut angle = vec![0.0f64; n];
        let mut boundary = vec![false; n];
        let mut deg = vec![0u32; n + 1];
        for (f, t) in tris.iter().enumerate() {
            if !live[f] {
                continue;
            }
            let p = t.map(|v| positions[v as usize]);
            // |p[k + 1] - p[k]|: the length of half-edge k, and (the vector negated, the same
            // bits) of the other two half-edges' child edges.
            let e = [0, 1, 2].map(|k| (p[(k + 1) % 3] - p[k]).length());
            for k in 0..3 {
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let ab = p[(k + 1) % 3] - p[k];
                let ac = p[(k + 2) % 3] - p[k];
                let l = e[k];
                let cross = ab.cross(ac).length();
                let dot = ac.dot(ab);
                geom[3 * f + k] = HeGeom {
                    l,
                    cx: dot / l,
                    cy: cross / l,
                    lac: e[(k + 2) % 3],
                    lbc: e[(k + 1) % 3],
                };
                // Corner angle at a.
                angle[a as usize] += approx_atan2(cross, ab.dot(ac));
                if twin[3 * f + k] == NONE {
                    boundary[a as usize] = true;
                    boundary[b as usize] = true;
                }
                deg[c as usize + 1] += 1;
            }
        }
        for v in 0..n {
            deg[v + 1] += deg[v];
        }
        let mut fill = deg.clone();
        let mut vopp = vec![0u32; deg[n] as usize];
        for (f, t) in tris.iter().enumerate() {
            if !live[f] {
                continue;
            }
            for k in 0..3 {
                let c = t[(k + 2) % 3] as usize;
                vopp[fill[c] as usize] = (3 * f + k) as u32;
                fill[c] += 1;
            }
        }
        // Saddles: total angle above `2 pi - 1e-5`, decided on the approximate sum unless it
        // lies within the approximation's error bound of the threshold (then the corner angles
        // are summed with `atan2` in face order, as a plain per-face loop would).
        let saddle_min = 2.0 * std::f64::consts::PI - 1e-5;
        let mut pseudo: Vec<bool> = (0..n)
            .map(|v| {
                let opp = &vopp[deg[v] as usize..deg[v + 1] as usize];
                boundary[v]
                    || if angle_sum_decides(angle[v], opp.len(), saddle_min) {
                        angle[v] > saddle_min
                    } else {
                        corner_angle_sum(&positions, &tris, opp) > saddle_min
                    }
            })
            .collect();
        // Non-manifold vertices: faces around v not connected through edges at v. `mark[f]`
        // is `v + 1` once face f was reached from v's first face.
        let mut mark = vec![0u32; m];
        let mut stack: Vec<u32> = Vec::new();
        for v in 0..n {
            let opp = &vopp[deg[v] as usize..deg[v + 1] as usize];
            if opp.len() <= 1 {
                continue;
            }
            let stamp = v as u32 + 1;
            let mut reached = 1;
            stack.clear();
            mark[(opp[0] / 3) as usize] = stamp;
            stack.push(opp[0]);
            while let Some(g) = stack.pop() {
                // The two half-edges of face(g) at v: next(g) and prev(g).
                for h in [next(g), prev(g)] {
                    let t = twin[h as usize];
                    if t == NONE {
                        continue;
                    }
                    let t = t & IDX;
                    let f2 = t / 3;
                    if mark[f2 as usize] != stamp {
                        mark[f2 as usize] = stamp;
                        reached += 1;
                        // The half-edge of face f2 opposite v (t has v at one end).
                        let tf = tris[f2 as usize];
                        stack.push(if tf[(t % 3) as usize] == v as u32 {
                            next(t)
                        } else {
                            prev(t)
                        });
                    }
                }
            }
            if reached < opp.len() {
                pseudo[v] = true;
                report.non_manifold_vertices.push(v as u32);
            }
        }
        report.pseudo_sources = pseudo.iter().filter(|&&p| p).count();
        Ok(Self {
            positions,
            tris,
            live,
            twin,
            geom,
            vopp_off: deg,
            vopp,
            pseudo,
            report,
            schedule: ExactSchedule::Serial,
        })
    }
}

/// True when the edge vector `e` is at most `min_edge` long (`e.length() <= min_edge`, the
/// same decision): the square root is taken only when the squared length does not settle it
/// (squared length above `4 min_edge^2`, far beyond rounding, means longer).
#[inline]
fn edge_at_most(e: DVec3, min_edge: f64) -> bool {
    let q = e.dot(e);
    q <= 4.0 * min_edge * min_edge && q.sqrt() <= min_edge
}

/// Twin of every half-edge of the live faces (with [`REV`] when both run the same way), or
/// [`NONE`] on boundary and cut (3+ faces) edges, which are counted in `report`.
///
/// The half-edges are bucketed by their lower end vertex (a counting sort, half-edge order kept
/// within a bucket), then each bucket is ordered by the upper end: the groups of equal
/// undirected edges are those of a sort of all `(edge, half-edge)` keys, without sorting more
/// than one vertex's edges at a time.
fn twins(tris: &[[u32; 3]], live: &[bool], n: usize, report: &mut ExactMeshReport) -> Vec<u32> {
    // (lower end, upper end, half-edge) of every live half-edge, in half-edge order.
    let live_halfedges = || {
        tris.iter()
            .enumerate()
            .filter(|&(f, _)| live[f])
            .flat_map(|(f, t)| {
                [0, 1, 2].map(|k| {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    (a.min(b), a.max(b), (3 * f + k) as u32)
                })
            })
    };
    let mut start = vec![0u32; n + 1];
    for (lo, _, _) in live_halfedges() {
        start[lo as usize + 1] += 1;
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    // (upper end, half-edge) per bucket.
    let mut keys = vec![(0u32, 0u32); start[n] as usize];
    for (lo, hi, h) in live_halfedges() {
        keys[fill[lo as usize] as usize] = (hi, h);
        fill[lo as usize] += 1;
    }
    drop(fill);
    let mut twin = vec![NONE; 3 * tris.len()];
    let tail = |h: u32| tris[(h / 3) as usize][(h % 3) as usize];
    for v in 0..n {
        let bucket = &mut keys[start[v] as usize..start[v + 1] as usize];
        // Sorted by upper end: a bucket holds its half-edges in ascending order, so a stable
        // insertion sort by the upper end gives the order of `(upper end, half-edge)` (the
        // buckets are short: about 6 half-edges).
        for i in 1..bucket.len() {
            let mut j = i;
            while j > 0 && bucket[j - 1].0 > bucket[j].0 {
                bucket.swap(j - 1, j);
                j -= 1;
            }
        }
        let mut i = 0;
        while i < bucket.len() {
            let mut j = i + 1;
            while j < bucket.len() && bucket[j].0 == bucket[i].0 {
                j += 1;
            }
            match j - i {
                1 => {}
                2 => {
                    let (h1, h2) = (bucket[i].1, bucket[i + 1].1);
                    let rev = if tail(h1) == tail(h2) {
                        report.inconsistent_edges += 1;
                        REV
                    } else {
                        0
                    };
                    twin[h1 as usize] = h2 | rev;
                    twin[h2 as usize] = h1 | rev;
                }
                _ => report.cut_edges += 1,
            }
            i = j;
        }
    }
    twin
}

/// Sum of the corner angles (`atan2` of the cross product's length and the dot product of the
/// two edges) at the vertex opposite the half-edges `opp`, in their order.
fn corner_angle_sum(positions: &[DVec3], tris: &[[u32; 3]], opp: &[u32]) -> f64 {
    opp.iter().fold(0.0, |sum, &g| {
        // g = b -> c is opposite a = apex(g): the corner's edges are a -> b and a -> c.
        let t = tris[(g / 3) as usize];
        let k = (g % 3) as usize;
        let (a, b, c) = (t[(k + 2) % 3], t[k], t[(k + 1) % 3]);
        let pa = positions[a as usize];
        let ab = positions[b as usize] - pa;
        let ac = positions[c as usize] - pa;
        sum + ab.cross(ac).length().atan2(ab.dot(ac))
    })
}

/// Bound on `|approx_atan2(y, x) - y.atan2(x)|` per corner (the truncation of the series is
/// below `7e-11`, its rounding and `atan2`'s error a few ulps).
const APPROX_ATAN2_SLACK: f64 = 2e-10;

/// True when the approximate angle sum `sum` of `corners` corners is far enough from
/// `threshold` that the `atan2` sum lies on the same side: each corner adds at most
/// [`APPROX_ATAN2_SLACK`] of approximation error and, in either sum, one rounding of at most
/// an ulp of the sum (`2.3e-16 |sum|`; `1e-15 |sum|` covers both sums with room).
#[inline]
fn angle_sum_decides(sum: f64, corners: usize, threshold: f64) -> bool {
    (sum - threshold).abs() > corners as f64 * (APPROX_ATAN2_SLACK + 1e-15 * sum.abs())
}

/// The Taylor coefficients of `atan(u) / u` in `u^2`: `(-1)^k / (2k + 1)`, `k = 0..=10`.
const ATAN_SERIES: [f64; 11] = [
    1.0,
    -1.0 / 3.0,
    1.0 / 5.0,
    -1.0 / 7.0,
    1.0 / 9.0,
    -1.0 / 11.0,
    1.0 / 13.0,
    -1.0 / 15.0,
    1.0 / 17.0,
    -1.0 / 19.0,
    1.0 / 21.0,
];

/// `y.atan2(x)` within `1e-10` for finite `y >= 0` and `x`, not both zero (`NaN` when both are
/// zero, which the caller treats as undecided): the argument is reduced to `|u| <= tan(pi / 8)`
/// and `atan(u)` summed as its Taylor series up to `u^21`.
#[inline]
fn approx_atan2(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let ax = x.abs();
    let (t, swap) = if y <= ax {
        (y / ax, false)
    } else {
        (ax / y, true)
    };
    // atan(t), t in [0, 1]: around 0, or pi/4 + atan((t - 1) / (t + 1)).
    let (u, base) = if t > 0.414_213_562_373_095_1 {
        ((t - 1.0) / (t + 1.0), FRAC_PI_4)
    } else {
        (t, 0.0)
    };
    // Horner in u^2: sum of (-1)^k u^(2k) / (2k + 1), k = 0..=10.
    let u2 = u * u;
    let p = ATAN_SERIES.iter().rev().fold(0.0, |p, &c| c + u2 * p);
    let r = base + u * p;
    let r = if swap { FRAC_PI_2 - r } else { r };
    if x < 0.0 {
        PI - r
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn approx_atan2_is_within_its_bound() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut worst = 0.0f64;
        for i in 0..200_000 {
            let scale = 10f64.powi(rng.random_range(-8..8));
            let y = rng.random_range(0.0..1.0) * scale;
            let x = rng.random_range(-1.0..1.0) * scale * if i % 3 == 0 { 1e-3 } else { 1.0 };
            worst = worst.max((approx_atan2(y, x) - y.atan2(x)).abs());
        }
        for (y, x) in [(0.0, 1.0), (0.0, -1.0), (1.0, 0.0), (1.0, 1.0), (1.0, -1.0)] {
            worst = worst.max((approx_atan2(y, x) - y.atan2(x)).abs());
        }
        assert!(worst <= 1e-10, "approx_atan2 off by {worst}");
        assert!(approx_atan2(0.0, 0.0).is_nan());
    }

    /// A fan of 16 triangles around a raised centre (corner angles near `pi / 8`, where the
    /// series is least accurate) whose total angle lies within a few ulps of
    /// the saddle threshold on either side: the centre is flagged exactly as the `atan2` sum
    /// says (the approximate sum cannot tell these apart; the exact fallback must).
    #[test]
    fn saddle_flag_at_the_threshold_follows_the_atan2_sum() {
        let rim: Vec<DVec3> = (0..16)
            .map(|k| {
                let t = std::f64::consts::TAU * f64::from(k) / 16.0;
                DVec3::new(t.cos(), t.sin(), 0.0)
            })
            .collect();
        let tris: Vec<[u32; 3]> = (0..16u32).map(|k| [0, 1 + k, 1 + (k + 1) % 16]).collect();
        let fan = |h: f64| {
            let mut p = vec![DVec3::new(0.0, 0.0, h)];
            p.extend(&rim);
            p
        };
        let opp: Vec<u32> = (0..16u32).map(|f| 3 * f + 1).collect();
        let thr = 2.0 * std::f64::consts::PI - 1e-5;
        let sum = |h: f64| corner_angle_sum(&fan(h), &tris, &opp);
        // Bisection on the height: sum(lo) > thr >= sum(hi).
        let (mut lo, mut hi) = (0.0, 0.1);
        assert!(sum(lo) > thr && sum(hi) <= thr);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid == lo || mid == hi {
                break;
            }
            if sum(mid) > thr {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        for (h, saddle) in [(lo, true), (hi, false)] {
            let mesh = TriMesh::new(fan(h), tris.clone()).unwrap();
            let g = ExactGeodesic::new(&mesh).unwrap();
            assert_eq!(g.pseudo[0], saddle, "height {h}: angle sum {}", sum(h));
            assert!(g.pseudo[1..].iter().all(|&p| p), "the rim is a boundary");
        }
    }
}
