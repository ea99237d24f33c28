//! The iso-angle rule (§2.5-B): points along the level curves of the first field where the
//! opening equals an angle level exactly.

use super::{sort_points, Ctx, PairCtx, SplineSet, Strip};
use crate::{
    BipolarError, DescriptorPoint, DescriptorStats, IsoCrossings, IsoRepeats, Key, TangentMethod,
};
use glam::DVec3;
use levelcurves::isolines_uniform;
use levelcurves::Isoline;
use meshcore::SurfacePoint;
use std::f64::consts::{PI, TAU};

impl Ctx<'_> {
    /// Iso-angle points along the level curves of the first field (rule B, §2.5-B).
    /// Returns the number of points found (before nothing is filtered: all are kept).
    pub(super) fn isoangle_points(
        &self,
        pair: &PairCtx<'_>,
        stats: &mut DescriptorStats,
        out: &mut Vec<DescriptorPoint>,
    ) -> Result<usize, BipolarError> {
        let levels = isolines_uniform(self.mesh, self.topo, pair.fa, self.step, self.max_level)?;
        let vn = self.mesh.vertex_normals();
        let va = self.vertex_gradients(pair.fa, pair.ga, &vn);
        let vb = self.vertex_gradients(pair.fb, pair.gb, &vn);
        let splines = match self.opts.tangent {
            TangentMethod::Spline => Some(SplineSet::from_levels(self, &levels)?),
            _ => None,
        };
        let mut strip = match self.opts.tangent {
            TangentMethod::Strip => Some(Strip::new(self)),
            _ => None,
        };
        let k_max = self.opts.angles;
        let alpha = self.opts.alpha;
        let targets: Vec<(u32, f64, i8)> = (0..=k_max)
            .flat_map(|k| {
                let c = alpha * k as f64 / k_max as f64;
                if k == 0 {
                    vec![(0, 0.0, 0)]
                } else {
                    vec![(k, c, 1), (k, -c, -1)]
                }
            })
            .collect();
        let psi_targets = psi_targets(k_max, alpha);
        let bmax = self.max_level as f64 * self.step;
        let start = out.len();
        for (li, pieces) in levels.iter().enumerate() {
            let i = li as u32 + 1;
            let lambda = i as f64 * self.step;
            for (pi, iso) in pieces.iter().enumerate() {
                let np = iso.points.len();
                if iso.n_segments() == 0 {
                    continue;
                }
                let mut cos = vec![f64::NAN; np];
                let mut sin = vec![f64::NAN; np];
                let mut ub = vec![f64::NAN; np];
                for k in 0..np {
                    let (lo, hi) = iso.edge_of[k];
                    let t = iso.t_of[k];
                    let (lo, hi) = (lo as usize, hi as usize);
                    ub[k] = pair.fb[lo] + t * (pair.fb[hi] - pair.fb[lo]);
                    let nrm = (vn[lo] + t * (vn[hi] - vn[lo])).normalize_or_zero();
                    let ga = va[lo] + t * (va[hi] - va[lo]);
                    let gb = vb[lo] + t * (vb[hi] - vb[lo]);
                    let tb = nrm.cross(gb).normalize_or_zero();
                    // A face adjacent to this point along the curve.
                    let seg = if k < iso.n_segments() { k } else { k - 1 };
                    let face = iso.face_of[seg];
                    let ta = match self.opts.tangent {
                        TangentMethod::Gradient => Some(nrm.cross(ga).normalize_or_zero()),
                        TangentMethod::Strip => strip
                            .as_mut()
                            .and_then(|s| s.tangent(pair.fa, lambda, iso.points[k], face, nrm, ga)),
                        TangentMethod::Spline => splines
                            .as_ref()
                            .and_then(|s| s.tangent_at_point(li, pi, k, nrm, ga)),
                    };
                    let ta = ta.unwrap_or_else(|| {
                        stats.tangent_fallbacks += 1;
                        nrm.cross(ga).normalize_or_zero()
                    });
                    if ta != DVec3::ZERO && tb != DVec3::ZERO {
                        cos[k] = ta.dot(tb).clamp(-1.0, 1.0);
                        sin[k] = nrm.dot(ta.cross(tb));
                    }
                }
                if self.opts.isoangle.crossings == IsoCrossings::Monotone {
                    let run = CurveValues {
                        cos: &cos,
                        sin: &sin,
                        ub: &ub,
                    };
                    self.monotone_points(iso, &run, (pair.a, pair.b, i), &psi_targets, bmax, out);
                    continue;
                }
                for seg in 0..iso.n_segments() {
                    let k0 = seg;
                    let k1 = (seg + 1) % np;
                    let (c0, c1) = (cos[k0], cos[k1]);
                    if !(c0.is_finite() && c1.is_finite()) {
                        continue;
                    }
                    let face = iso.face_of[seg];
                    let f = face as usize;
                    let det_sign = self
                        .mesh
                        .face_normal(face)
                        .dot(pair.ga[f].cross(pair.gb[f]));
                    if det_sign == 0.0 || !det_sign.is_finite() {
                        continue;
                    }
                    let side: i8 = if det_sign > 0.0 { 1 } else { -1 };
                    for &(k, target, sign) in &targets {
                        // Samples within 1e-12 of the target count as on it ("above"), so a
                        // rounding-level change cannot create or move a crossing.
                        let snap = |c: f64| {
                            if (c - target).abs() <= 1e-12 {
                                target
                            } else {
                                c
                            }
                        };
                        let (c0, c1) = (snap(c0), snap(c1));
                        if (c0 >= target) == (c1 >= target) {
                            continue;
                        }
                        let phi = ((target - c0) / (c1 - c0)).clamp(0.0, 1.0);
                        let ubp = ub[k0] + phi * (ub[k1] - ub[k0]);
                        if !(ubp.is_finite() && ubp > 0.0 && ubp <= bmax) {
                            continue;
                        }
                        let pos = iso.points[k0] + phi * (iso.points[k1] - iso.points[k0]);
                        let bary = self.barycentric(face, pos);
                        out.push(DescriptorPoint {
                            position: pos,
                            key: Key {
                                a: pair.a,
                                b: pair.b,
                                i,
                                j: k,
                                side,
                                sign,
                            },
                            cos: target,
                            face,
                            bary,
                            ambiguous: false,
                        });
                    }
                }
            }
        }
        // Repeated keys: one key at several places (pieces of one level curve separated by a
        // hole, wiggles of the opening with every crossing).
        let mine = &mut out[start..];
        sort_points(mine);
        let n = mine.len();
        // The second field at a point ([`meshcore::TriMesh::interpolate`]: an unreached corner of zero
        // weight does not make it NaN); the points were made on this mesh, so it is valid.
        let ub_at = |p: &DescriptorPoint| {
            self.mesh
                .interpolate(pair.fb, &SurfacePoint::new(p.face, p.bary))
                .unwrap_or(f64::NAN)
        };
        let margin = 0.25 * self.step;
        let mut drop = vec![false; n];
        let mut s = 0;
        while s < n {
            let mut e = s + 1;
            while e < n && mine[e].key == mine[s].key {
                e += 1;
            }
            if e - s > 1 {
                let nearest = match self.opts.isoangle.repeats {
                    IsoRepeats::Nearest => {
                        nearest_of(&mine[s..e].iter().map(ub_at).collect::<Vec<_>>(), margin)
                    }
                    IsoRepeats::Ambiguous => None,
                };
                match nearest {
                    Some(keep) => (s..e)
                        .filter(|&q| q != s + keep)
                        .for_each(|q| drop[q] = true),
                    None => mine[s..e].iter_mut().for_each(|p| p.ambiguous = true),
                }
            }
            s = e;
        }
        let mut q = 0;
        out.retain(|_| {
            q += 1;
            q <= start || !drop[q - 1 - start]
        });
        Ok(n)
    }

    /// [`IsoCrossings::Monotone`] on one level-curve piece: per run of points with defined
    /// tangents, the unwrapped signed opening `psi` (optionally smoothed along the arc length),
    /// its best monotone fit, and one point where the fit crosses each target angle.
    fn monotone_points(
        &self,
        iso: &Isoline,
        v: &CurveValues<'_>,
        (a, b, i): (u8, u8, u32),
        targets: &[PsiTarget],
        bmax: f64,
        out: &mut Vec<DescriptorPoint>,
    ) {
        let np = iso.points.len();
        let valid: Vec<bool> = (0..np)
            .map(|k| v.cos[k].is_finite() && v.sin[k].is_finite())
            .collect();
        let raw = |k: usize| v.sin[k].atan2(v.cos[k]);
        // Walking order: an open piece from its first point; a closed one from a point without
        // tangent (runs never wrap then) or else from the point where the opening is nearest to
        // 0 (parallel tangents, no target near), back to that point. Both starts are intrinsic.
        let order: Vec<usize> = if iso.closed {
            let start = (0..np).find(|&k| !valid[k]).unwrap_or_else(|| {
                (0..np)
                    .min_by(|&x, &y| {
                        raw(x).abs().total_cmp(&raw(y).abs()).then_with(|| {
                            let (p, q) = (iso.points[x], iso.points[y]);
                            p.x.total_cmp(&q.x)
                                .then(p.y.total_cmp(&q.y))
                                .then(p.z.total_cmp(&q.z))
                        })
                    })
                    .unwrap_or(0)
            });
            (0..=np).map(|j| (start + j) % np).collect()
        } else {
            (0..np).collect()
        };
        let mut s = 0;
        while s < order.len() {
            if !valid[order[s]] {
                s += 1;
                continue;
            }
            let mut e = s + 1;
            while e < order.len() && valid[order[e]] {
                e += 1;
            }
            if e - s >= 2 {
                self.monotone_run(iso, v, &order[s..e], (a, b, i), targets, bmax, out);
            }
            s = e;
        }
    }

    /// One run of [`Ctx::monotone_points`] (`idx`: point indices in walking order; the segment
    /// from `idx[j]` to `idx[j + 1]` lies in face `iso.face_of[idx[j]]`).
    #[allow(clippy::too_many_arguments)]
    fn monotone_run(
        &self,
        iso: &Isoline,
        v: &CurveValues<'_>,
        idx: &[usize],
        (a, b, i): (u8, u8, u32),
        targets: &[PsiTarget],
        bmax: f64,
        out: &mut Vec<DescriptorPoint>,
    ) {
        let n = idx.len();
        let pts: Vec<DVec3> = idx.iter().map(|&k| iso.points[k]).collect();
        // Unwrapped opening angle.
        let mut psi = Vec::with_capacity(n);
        for (j, &k) in idx.iter().enumerate() {
            let r = v.sin[k].atan2(v.cos[k]);
            psi.push(if j == 0 {
                r
            } else {
                let prev: f64 = psi[j - 1];
                prev + wrap(r - prev)
            });
        }
        // Arc-length positions and weights (half the adjacent segments), so that the fit does
        // not depend on how densely the curve is sampled.
        let mut arc = vec![0.0; n];
        for j in 1..n {
            arc[j] = arc[j - 1] + (pts[j] - pts[j - 1]).length();
        }
        let floor = 1e-9 * self.mel.max(f64::MIN_POSITIVE);
        let w: Vec<f64> = (0..n)
            .map(|j| {
                let l = if j > 0 { arc[j] - arc[j - 1] } else { 0.0 };
                let r = if j + 1 < n { arc[j + 1] - arc[j] } else { 0.0 };
                (0.5 * (l + r)).max(floor)
            })
            .collect();
        let sigma = self.opts.isoangle.smoothing * self.mel;
        let psi = if sigma > 0.0 {
            smooth(&psi, &w, &arc, sigma)
        } else {
            psi
        };
        let inc = isotonic_increasing(&psi, &w);
        let neg: Vec<f64> = psi.iter().map(|x| -x).collect();
        let dec: Vec<f64> = isotonic_increasing(&neg, &w).iter().map(|x| -x).collect();
        let sse = |f: &[f64]| -> f64 {
            f.iter()
                .zip(&psi)
                .zip(&w)
                .map(|((f, p), w)| w * (f - p) * (f - p))
                .sum()
        };
        let (fit, increasing) = if sse(&dec) < sse(&inc) {
            (dec, false)
        } else {
            (inc, true)
        };
        let (lo, hi) = if increasing {
            (fit[0], fit[n - 1])
        } else {
            (fit[n - 1], fit[0])
        };
        for t in targets {
            let m0 = ((lo - t.psi) / TAU).ceil() as i64;
            let m1 = ((hi - t.psi) / TAU).floor() as i64;
            for m in m0..=m1 {
                let tv = t.psi + TAU * m as f64;
                // The one place where the monotone fit passes tv: below before, at or above after
                // (increasing), or the mirror image (decreasing).
                let above = |x: f64| if increasing { x >= tv } else { x < tv };
                if above(fit[0]) || !above(fit[n - 1]) {
                    continue;
                }
                let j = (1..n).find(|&j| above(fit[j])).unwrap_or(n - 1);
                let (f0, f1) = (fit[j - 1], fit[j]);
                let phi = if f1 != f0 {
                    ((tv - f0) / (f1 - f0)).clamp(0.0, 1.0)
                } else {
                    0.5
                };
                let (k0, k1) = (idx[j - 1], idx[j]);
                let ubp = v.ub[k0] + phi * (v.ub[k1] - v.ub[k0]);
                if !(ubp.is_finite() && ubp > 0.0 && ubp <= bmax) {
                    continue;
                }
                let pos = pts[j - 1] + phi * (pts[j] - pts[j - 1]);
                let face = iso.face_of[k0];
                out.push(DescriptorPoint {
                    position: pos,
                    key: Key {
                        a,
                        b,
                        i,
                        j: t.k,
                        side: t.side,
                        sign: t.sign,
                    },
                    cos: t.cos,
                    face,
                    bary: self.barycentric(face, pos),
                    ambiguous: false,
                });
            }
        }
    }

    /// Area-weighted per-vertex gradients projected on the vertex tangent planes (M0s).
    fn vertex_gradients(&self, f: &[f64], g: &[DVec3], vn: &[DVec3]) -> Vec<DVec3> {
        let mut acc = vec![DVec3::ZERO; self.mesh.n_vertices()];
        let mut w = vec![0.0; self.mesh.n_vertices()];
        let mut mag = vec![0.0; self.mesh.n_vertices()];
        for (face, t) in self.mesh.triangles().iter().enumerate() {
            if self.face_values(f, face).is_none() {
                continue;
            }
            let area = self.mesh.face_area(face as u32);
            for &v in t {
                acc[v as usize] += area * g[face];
                mag[v as usize] += area * g[face].length();
                w[v as usize] += area;
            }
        }
        acc.iter()
            .zip(&w)
            .zip(vn)
            .zip(&mag)
            .map(|(((a, &w), n), &mag)| {
                // Where the face gradients around a vertex cancel (the source of a distance
                // field, a ridge), the direction is undefined: return zero (no tangent).
                if w > 0.0 && a.length() > 0.1 * mag {
                    let m = *a / w;
                    m - m.dot(*n) * *n
                } else {
                    DVec3::ZERO
                }
            })
            .collect()
    }

    /// Barycentric coordinates of `p` (assumed in the plane of `face`), clamped to the face.
    fn barycentric(&self, face: u32, p: DVec3) -> DVec3 {
        let [a, b, c] = self.mesh.face_corners(face);
        meshcore::closest_point_on_triangle(p, a, b, c)
    }
}

/// [`IsoRepeats::Nearest`]: among the places of one key with second-field values `ub` (on one
/// level of the first field, so `ub` orders them by `U_a + U_b`, their distance from the
/// geodesic between the references), the index of the one nearest the geodesic when every other
/// is farther by at least `margin`; `None` when two are too close to tell.
fn nearest_of(ub: &[f64], margin: f64) -> Option<usize> {
    let best = (0..ub.len()).min_by(|&x, &y| ub[x].total_cmp(&ub[y]))?;
    let clear = ub.iter().enumerate().all(|(k, &u)| {
        k == best || (u.is_finite() && ub[best].is_finite() && u - ub[best] >= margin)
    });
    clear.then_some(best)
}

/// Per-point values along one level-curve piece.
struct CurveValues<'a> {
    /// Cosine of the opening (NaN where a tangent is undefined).
    cos: &'a [f64],
    /// Sine of the opening, signed by `<n, t_a x t_b>` (the side).
    sin: &'a [f64],
    /// Second field.
    ub: &'a [f64],
}

/// A target of the iso-angle rule as a signed opening angle.
#[derive(Debug, Clone, Copy)]
struct PsiTarget {
    /// `atan2(sin, cos)` in `(-pi, pi]`.
    psi: f64,
    /// Its cosine, `sign * alpha * k / K` exactly.
    cos: f64,
    k: u32,
    side: i8,
    sign: i8,
}

/// The targets `|cos| = alpha k / K` as signed angles: each `(k, sign)` on both sides (one angle
/// where the sine is 0, counted on side `+1`).
fn psi_targets(k_max: u32, alpha: f64) -> Vec<PsiTarget> {
    let mut out = Vec::new();
    for k in 0..=k_max {
        let c = alpha * k as f64 / k_max as f64;
        let signs: &[i8] = if k == 0 { &[0] } else { &[1, -1] };
        for &sign in signs {
            let cos = sign as f64 * c;
            let a = cos.clamp(-1.0, 1.0).acos();
            out.push(PsiTarget {
                psi: a,
                cos,
                k,
                side: 1,
                sign,
            });
            if a > 0.0 && a < PI {
                out.push(PsiTarget {
                    psi: -a,
                    cos,
                    k,
                    side: -1,
                    sign,
                });
            }
        }
    }
    out
}

/// `x` wrapped into `(-pi, pi]`.
fn wrap(x: f64) -> f64 {
    let y = x.rem_euclid(TAU);
    if y > PI {
        y - TAU
    } else {
        y
    }
}

/// Weighted least-squares non-decreasing fit (pool adjacent violators).
fn isotonic_increasing(y: &[f64], w: &[f64]) -> Vec<f64> {
    let mut blocks: Vec<(f64, f64, usize)> = Vec::with_capacity(y.len());
    for (&v, &wt) in y.iter().zip(w) {
        blocks.push((v, wt, 1));
        while blocks.len() > 1 {
            let (v2, w2, n2) = blocks[blocks.len() - 1];
            let (v1, w1, n1) = blocks[blocks.len() - 2];
            if v1 <= v2 {
                break;
            }
            blocks.truncate(blocks.len() - 2);
            let ws = w1 + w2;
            blocks.push(((v1 * w1 + v2 * w2) / ws, ws, n1 + n2));
        }
    }
    blocks
        .iter()
        .flat_map(|&(v, _, n)| std::iter::repeat_n(v, n))
        .collect()
}

/// Gaussian smoothing of `y` along the arc length (standard deviation `sigma`, weights `w`,
/// window 4 sigma).
fn smooth(y: &[f64], w: &[f64], arc: &[f64], sigma: f64) -> Vec<f64> {
    let n = y.len();
    let mut out = Vec::with_capacity(n);
    let mut lo = 0;
    for j in 0..n {
        while arc[j] - arc[lo] > 4.0 * sigma {
            lo += 1;
        }
        let (mut s, mut ws) = (0.0, 0.0);
        let mut l = lo;
        while l < n && arc[l] - arc[j] <= 4.0 * sigma {
            let d = (arc[l] - arc[j]) / sigma;
            let k = w[l] * (-0.5 * d * d).exp();
            s += k * y[l];
            ws += k;
            l += 1;
        }
        out.push(if ws > 0.0 { s / ws } else { y[j] });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isotonic_fit_pools_violators_and_keeps_monotone_data() {
        let w = [1.0; 5];
        assert_eq!(
            isotonic_increasing(&[1.0, 2.0, 3.0, 4.0, 5.0], &w),
            vec![1.0, 2.0, 3.0, 4.0, 5.0]
        );
        assert_eq!(
            isotonic_increasing(&[1.0, 3.0, 2.0, 4.0, 5.0], &w),
            vec![1.0, 2.5, 2.5, 4.0, 5.0]
        );
        let f = isotonic_increasing(&[3.0, 1.0, 2.0], &[1.0, 1.0, 2.0]);
        assert!(f.iter().all(|&x| (x - 2.0).abs() < 1e-15), "{f:?}");
    }

    #[test]
    fn nearest_needs_a_clear_margin() {
        assert_eq!(nearest_of(&[80.0, 76.0, 90.0], 2.5), Some(1));
        assert_eq!(nearest_of(&[76.5, 76.0], 2.5), None);
        assert_eq!(nearest_of(&[f64::NAN, 76.0], 2.5), None);
        assert_eq!(nearest_of(&[], 2.5), None);
    }

    #[test]
    fn targets_cover_both_sides_and_signs() {
        let t = psi_targets(8, 0.95);
        // k = 0: two sides; k = 1..8: two signs x two sides.
        assert_eq!(t.len(), 2 + 8 * 4);
        for x in &t {
            assert!((x.psi.cos() - x.cos).abs() < 1e-12);
            assert_eq!(x.psi.sin() > 0.0, x.side > 0);
        }
        assert!((wrap(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap(-0.5) + 0.5).abs() < 1e-15);
    }
}
