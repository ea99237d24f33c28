//! B-spline tangents (M2, the paper's method 2).

use super::Ctx;
use crate::BipolarError;
use glam::DVec3;
use levelcurves::{isolines_uniform, Isoline};
use std::collections::HashMap;

/// A fitted piece: the spline and the parameter of each polyline point.
type PieceFit = (bspline::BSpline3, Vec<f64>);

/// B-spline fits of the level-curve pieces of one field (M2).
pub(super) struct SplineSet {
    /// Per level (index `i - 1`), per piece: the spline and the parameter of each polyline
    /// point (None when the piece is too short or the fit failed).
    fits: Vec<Vec<Option<PieceFit>>>,
    levels: Vec<Vec<Isoline>>,
    /// (level index, face) -> (piece, segment).
    seg_of: HashMap<(u32, u32), (u32, u32)>,
}

impl SplineSet {
    pub(super) fn new(ctx: &Ctx<'_>, field: &[f64]) -> Result<Self, BipolarError> {
        let levels = isolines_uniform(ctx.mesh, ctx.topo, field, ctx.step, ctx.max_level)?;
        Self::from_levels(ctx, &levels)
    }

    pub(super) fn from_levels(
        ctx: &Ctx<'_>,
        levels: &[Vec<Isoline>],
    ) -> Result<Self, BipolarError> {
        let so = &ctx.opts.spline;
        let mut seg_of = HashMap::new();
        let mut fits = Vec::with_capacity(levels.len());
        let tol = 1e-9 * ctx.diag;
        for (li, pieces) in levels.iter().enumerate() {
            let mut row = Vec::with_capacity(pieces.len());
            for (pi, iso) in pieces.iter().enumerate() {
                for (s, &f) in iso.face_of.iter().enumerate() {
                    seg_of.insert((li as u32, f), (pi as u32, s as u32));
                }
                let (pts, kept) = bspline::dedup_consecutive(&iso.points, tol, iso.closed);
                if pts.len() < so.min_points.max(bspline::DEGREE + 1) {
                    row.push(None);
                    continue;
                }
                let opts = bspline::FitOptions {
                    closed: iso.closed,
                    control_spacing: so.control_spacing.map(|c| c * ctx.mel),
                    smoothing: so.smoothing,
                    ..bspline::FitOptions::default()
                };
                match bspline::BSpline3::fit(&pts, &opts) {
                    Ok(sp) => {
                        let mut par = vec![0.0; iso.points.len()];
                        let mut kk = 0;
                        for (o, p) in par.iter_mut().enumerate() {
                            while kk + 1 < kept.len() && kept[kk + 1] <= o {
                                kk += 1;
                            }
                            *p = sp.params()[kk];
                        }
                        row.push(Some((sp, par)));
                    }
                    Err(_) => row.push(None),
                }
            }
            fits.push(row);
        }
        Ok(Self {
            fits,
            levels: levels.to_vec(),
            seg_of,
        })
    }

    fn orient(d: DVec3, nrm: DVec3, grad: DVec3) -> Option<DVec3> {
        let t = (d - d.dot(nrm) * nrm).normalize_or_zero();
        if t == DVec3::ZERO {
            return None;
        }
        Some(if t.dot(nrm.cross(grad)) < 0.0 { -t } else { t })
    }

    /// Tangent at an intersection point `p` in `face` on level `level` (1-based).
    pub(super) fn tangent_at(
        &self,
        level: u32,
        face: u32,
        p: DVec3,
        nrm: DVec3,
        grad: DVec3,
    ) -> Option<DVec3> {
        let li = level.checked_sub(1)?;
        let &(pi, s) = self.seg_of.get(&(li, face))?;
        let (sp, par) = self.fits[li as usize][pi as usize].as_ref()?;
        let iso = &self.levels[li as usize][pi as usize];
        let s = s as usize;
        let (a, b) = iso.segment(s);
        let ab = b - a;
        let phi = if ab.length_squared() > 0.0 {
            ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let u0 = par[s];
        let u1 = if s + 1 < par.len() {
            par[s + 1]
        } else {
            1.0 // closing segment of a closed curve
        };
        let u = sp.closest_param_from(p, u0 + phi * (u1 - u0));
        Self::orient(sp.derivative(u), nrm, grad)
    }

    /// Tangent at polyline point `k` of piece `pi` of level index `li`.
    pub(super) fn tangent_at_point(
        &self,
        li: usize,
        pi: usize,
        k: usize,
        nrm: DVec3,
        grad: DVec3,
    ) -> Option<DVec3> {
        let (sp, par) = self.fits[li][pi].as_ref()?;
        Self::orient(sp.derivative(par[k]), nrm, grad)
    }
}
