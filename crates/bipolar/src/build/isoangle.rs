//! The iso-angle rule (§2.5-B): points along the level curves of the first field where the
//! opening equals an angle level exactly.

use super::{sort_points, Ctx, PairCtx, SplineSet, Strip};
use crate::{BipolarError, DescriptorPoint, DescriptorStats, Key, TangentMethod};
use glam::DVec3;
use levelcurves::isolines_uniform;

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
                    }
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
        // Ambiguity: several points with one key.
        let mine = &mut out[start..];
        sort_points(mine);
        let n = mine.len();
        let mut s = 0;
        while s < n {
            let mut e = s + 1;
            while e < n && mine[e].key == mine[s].key {
                e += 1;
            }
            if e - s > 1 {
                mine[s..e].iter_mut().for_each(|p| p.ambiguous = true);
            }
            s = e;
        }
        Ok(n)
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
