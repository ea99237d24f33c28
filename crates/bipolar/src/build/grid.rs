//! The grid rule (§2.1-2.3): every intersection of level `i` of one field with level `j` of the
//! other, solved per face, merged across faces, with its tangents and the optional angle filter
//! (rule A) or none.

use super::{Ctx, PairCtx, Raw, SplineSet, Strip};
use crate::{BipolarError, DescriptorPoint, DescriptorStats, Key, SelectionRule, TangentMethod};
use glam::DVec3;
use levelcurves::uniform_level_range;

impl Ctx<'_> {
    /// Grid intersections (§2.1-2.3), tangents, ambiguity, then the filter (rule A) or none.
    /// Returns the number of intersections found.
    pub(super) fn grid_points(
        &self,
        pair: &PairCtx<'_>,
        stats: &mut DescriptorStats,
        out: &mut Vec<DescriptorPoint>,
    ) -> Result<usize, BipolarError> {
        let raws = self.grid_intersections(pair, stats);
        if raws.is_empty() {
            return Ok(0);
        }
        // Tangents.
        let cos: Vec<f64> = match self.opts.tangent {
            TangentMethod::Gradient => raws
                .iter()
                .map(|r| cos_of(pair.ga[r.face as usize], pair.gb[r.face as usize]))
                .collect(),
            TangentMethod::Strip => {
                let mut strip = Strip::new(self);
                raws.iter()
                    .map(|r| {
                        let f = r.face as usize;
                        let nf = self.mesh.face_normal(r.face);
                        // The strip tangent of one field's level curve at the point, or the
                        // tangent across the face gradient when the strip has none.
                        let mut tangent = |field: &[f64], level: u32, grad: DVec3| {
                            strip
                                .tangent(field, level as f64 * self.step, r.pos, r.face, nf, grad)
                                .unwrap_or_else(|| {
                                    stats.tangent_fallbacks += 1;
                                    nf.cross(grad).normalize_or_zero()
                                })
                        };
                        let ta = tangent(pair.fa, r.i, pair.ga[f]);
                        let tb = tangent(pair.fb, r.j, pair.gb[f]);
                        ta.dot(tb)
                    })
                    .collect()
            }
            TangentMethod::Spline => {
                let sa = SplineSet::new(self, pair.fa)?;
                let sb = SplineSet::new(self, pair.fb)?;
                raws.iter()
                    .map(|r| {
                        let f = r.face as usize;
                        let nf = self.mesh.face_normal(r.face);
                        let ta = sa
                            .tangent_at(r.i, r.face, r.pos, nf, pair.ga[f])
                            .unwrap_or_else(|| {
                                stats.tangent_fallbacks += 1;
                                nf.cross(pair.ga[f]).normalize_or_zero()
                            });
                        let tb = sb
                            .tangent_at(r.j, r.face, r.pos, nf, pair.gb[f])
                            .unwrap_or_else(|| {
                                stats.tangent_fallbacks += 1;
                                nf.cross(pair.gb[f]).normalize_or_zero()
                            });
                        ta.dot(tb)
                    })
                    .collect()
            }
        };
        // Merge duplicates (a point on an edge or at a vertex is found in every face around
        // it): average position and cos over the group (order-independent, so invariant to
        // motions and renumbering), keep the face of smallest index.
        let (raws, cos) = merge_duplicates(&raws, &cos, 1e-9 * self.diag);
        let n = raws.len();
        // Ambiguity on all intersections (before any filtering).
        let mut amb = vec![false; n];
        let mut s = 0;
        while s < n {
            let mut e = s + 1;
            while e < n && same_key(&raws[e], &raws[s]) {
                e += 1;
            }
            if e - s > 1 {
                amb[s..e].iter_mut().for_each(|x| *x = true);
            }
            s = e;
        }
        let k_max = self.opts.angles as f64;
        let alpha = self.opts.alpha;
        for (idx, r) in raws.iter().enumerate() {
            let c = cos[idx].clamp(-1.0, 1.0);
            if !c.is_finite() {
                continue;
            }
            if let SelectionRule::Filter { tolerance } = self.opts.rule {
                let ks = (c.abs() * k_max / alpha).round();
                if ks > k_max || (c.abs() - alpha * ks / k_max).abs() > tolerance {
                    continue;
                }
            }
            out.push(DescriptorPoint {
                position: r.pos,
                key: Key {
                    a: pair.a,
                    b: pair.b,
                    i: r.i,
                    j: r.j,
                    side: r.side,
                    sign: 0,
                },
                cos: c,
                face: r.face,
                bary: r.bary,
                ambiguous: amb[idx],
            });
        }
        Ok(n)
    }

    /// All intersections of the two level families, merged and sorted by key then position.
    fn grid_intersections(&self, pair: &PairCtx<'_>, stats: &mut DescriptorStats) -> Vec<Raw> {
        let tris = self.mesh.triangles();
        let m = self.max_level;
        let step = self.step;
        let min_sin = self.opts.min_sin;
        let mut raws = Vec::new();
        for (f, t) in tris.iter().enumerate() {
            let Some(r) = self.face_values(pair.fa, f) else {
                continue;
            };
            let Some(q) = self.face_values(pair.fb, f) else {
                continue;
            };
            let ir =
                uniform_level_range(r[0].min(r[1]).min(r[2]), r[0].max(r[1]).max(r[2]), step, m);
            if ir.is_empty() {
                continue;
            }
            let jr =
                uniform_level_range(q[0].min(q[1]).min(q[2]), q[0].max(q[1]).max(q[2]), step, m);
            if jr.is_empty() {
                continue;
            }
            let (r1, r2) = (r[1] - r[0], r[2] - r[0]);
            let (q1, q2) = (q[1] - q[0], q[2] - q[0]);
            let det = r1 * q2 - r2 * q1;
            let scale = (r1.abs() + r2.abs()) * (q1.abs() + q2.abs());
            let n_pairs = ir.len() * jr.len();
            if det.abs() <= 1e-12 * scale || scale == 0.0 {
                stats.ill_conditioned += n_pairs;
                continue;
            }
            // |sin| = |det| / (2A |ga| |gb|).
            let two_a = self.mesh.face_cross(f as u32).length();
            let sin = det.abs() / (two_a * pair.ga[f].length() * pair.gb[f].length());
            if sin < min_sin {
                stats.ill_conditioned += n_pairs;
                continue;
            }
            let side: i8 = if det > 0.0 { 1 } else { -1 };
            let p = [
                self.mesh.position(t[0]),
                self.mesh.position(t[1]),
                self.mesh.position(t[2]),
            ];
            for i in ir.clone() {
                let av = i as f64 * step - r[0];
                for j in jr.clone() {
                    let bv = j as f64 * step - q[0];
                    let b1 = (av * q2 - r2 * bv) / det;
                    let b2 = (r1 * bv - av * q1) / det;
                    let b0 = 1.0 - b1 - b2;
                    if b0 < -1e-10 || b1 < -1e-10 || b2 < -1e-10 {
                        continue;
                    }
                    let bc = DVec3::new(b0.max(0.0), b1.max(0.0), b2.max(0.0));
                    let bc = bc / bc.element_sum();
                    raws.push(Raw {
                        i,
                        j,
                        side,
                        face: f as u32,
                        bary: bc,
                        pos: bc.x * p[0] + bc.y * p[1] + bc.z * p[2],
                    });
                }
            }
        }
        raws.sort_by(|x, y| {
            (x.i, x.j, x.side)
                .cmp(&(y.i, y.j, y.side))
                .then(x.pos.x.total_cmp(&y.pos.x))
                .then(x.pos.y.total_cmp(&y.pos.y))
                .then(x.pos.z.total_cmp(&y.pos.z))
                .then(x.face.cmp(&y.face))
        });
        raws
    }
}

/// Groups raw intersections (sorted by key, then position) of equal key lying within `tol`
/// of each other; returns one point per group (mean position and cos, smallest face),
/// sorted by key then position.
fn merge_duplicates(raws: &[Raw], cos: &[f64], tol: f64) -> (Vec<Raw>, Vec<f64>) {
    let mut out: Vec<Raw> = Vec::with_capacity(raws.len());
    let mut out_cos = Vec::with_capacity(raws.len());
    let mut s = 0;
    while s < raws.len() {
        let mut e = s + 1;
        while e < raws.len() && same_key(&raws[e], &raws[s]) {
            e += 1;
        }
        // Greedy clustering within the key run.
        let mut group_of = vec![usize::MAX; e - s];
        let mut n_groups = 0;
        for a in 0..e - s {
            if group_of[a] != usize::MAX {
                continue;
            }
            group_of[a] = n_groups;
            let mut members = vec![a];
            let mut k = 0;
            while k < members.len() {
                let m = members[k];
                for b in 0..e - s {
                    if group_of[b] == usize::MAX
                        && (raws[s + b].pos - raws[s + m].pos).length() <= tol
                    {
                        group_of[b] = n_groups;
                        members.push(b);
                    }
                }
                k += 1;
            }
            let cnt = members.len() as f64;
            let pos = members.iter().map(|&m| raws[s + m].pos).sum::<DVec3>() / cnt;
            let mean_cos = members.iter().map(|&m| cos[s + m]).sum::<f64>() / cnt;
            let keep = members
                .iter()
                .map(|&m| raws[s + m])
                .min_by_key(|r| r.face)
                .unwrap_or(raws[s + a]);
            out.push(Raw { pos, ..keep });
            out_cos.push(mean_cos);
            n_groups += 1;
        }
        s = e;
    }
    // Re-sort by key then position (the means moved).
    let mut idx: Vec<usize> = (0..out.len()).collect();
    idx.sort_by(|&x, &y| {
        let (a, b) = (&out[x], &out[y]);
        (a.i, a.j, a.side)
            .cmp(&(b.i, b.j, b.side))
            .then(a.pos.x.total_cmp(&b.pos.x))
            .then(a.pos.y.total_cmp(&b.pos.y))
            .then(a.pos.z.total_cmp(&b.pos.z))
    });
    (
        idx.iter().map(|&i| out[i]).collect(),
        idx.iter().map(|&i| out_cos[i]).collect(),
    )
}

fn same_key(a: &Raw, b: &Raw) -> bool {
    a.i == b.i && a.j == b.j && a.side == b.side
}

fn cos_of(a: DVec3, b: DVec3) -> f64 {
    let d = a.length() * b.length();
    if d > 0.0 {
        (a.dot(b) / d).clamp(-1.0, 1.0)
    } else {
        f64::NAN
    }
}
