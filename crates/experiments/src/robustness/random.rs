//! Figures 12, 13 and 17a: every face gets its own seeded random error (radius uniform in
//! [0, 5 %] of D, uniform direction) on q, on both corners, and on the nose tip; the matrices
//! between the perturbed descriptors.

use super::{eye_mid, Ctx, Desc, FacePrep, MethodResults};
use crate::pipeline::{field, perturb, Area, PoleRefs};
use crate::polar::{polar_descriptor, Pole};
use crate::report::par_map;
use crate::walk::Walker;
use anyhow::Result;
use bipolar::PolarDescriptor;
use geodesic::Source;
use meshcore::{DVec3, SurfacePoint};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The perturbed descriptors of one face and the radius of its one-corner error (% of D).
struct Run {
    one: Desc,
    both: Desc,
    nose: PolarDescriptor,
    one_pct: f64,
}

/// A random move of vertex `v`; a draw whose walk meets the boundary (eye opening) is redrawn
/// (up to 50 times). Returns (radius, direction, end point).
fn draw(
    rng: &mut ChaCha8Rng,
    w: &Walker<'_>,
    d: f64,
    v: u32,
    towards: DVec3,
) -> Result<(f64, f64, SurfacePoint)> {
    let mut last = None;
    for _ in 0..50 {
        let rad = rng.random_range(0.0..0.05) * d;
        let th = rng.random_range(0.0..std::f64::consts::TAU);
        let (sp, cut) = perturb(w, v, towards, rad, th)?;
        last = Some((rad, th, sp));
        if !cut {
            break;
        }
    }
    last.ok_or_else(|| anyhow::anyhow!("no perturbation drawn"))
}

fn one_face(ctx: &Ctx<'_>, prep: &FacePrep, i: usize) -> Result<Run> {
    let f = &ctx.faces[i];
    let r0 = &prep.refs;
    let w = &ctx.walkers[i];
    let s = prep.solver.as_ref();
    let lm = f.landmarks;
    let n = ctx.args.set.res.levels;
    let mut rng =
        ChaCha8Rng::seed_from_u64(ctx.args.seed ^ (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    // One corner (q).
    let (rad, th, spq) = draw(&mut rng, w, r0.d, lm.left_eye_outer, r0.r)?;
    let one = prep.with_q_moved(f, spq)?;
    let (uq, q) = (one.uq.clone(), one.q);
    let one = ctx.describe(&f.mesh, &one, n, Area::Static, || {
        format!("{} (random error on q)", f.name)
    });
    // Both corners (q as above, r moved independently).
    let (_, _, spr) = draw(&mut rng, w, r0.d, lm.right_eye_outer, r0.q)?;
    let ur = field(s, Source::Point(spr))?;
    let r = f.mesh.point_position(&spr)?;
    let d2 = 0.5 * (f.mesh.interpolate(&ur, &spq)? + f.mesh.interpolate(&uq, &spr)?);
    let both = PoleRefs::new(&f.mesh, [ur, uq], d2, [r, q, r0.nose]);
    let both = ctx.describe(&f.mesh, &both, n, Area::Static, || {
        format!("{} (random errors on r and q)", f.name)
    });
    // Nose tip, with the same radius/direction draw as the single corner.
    let (spn, _) = perturb(w, lm.nose_tip, eye_mid(r0), rad, th)?;
    let un = field(s, Source::Point(spn))?;
    let nose = polar_descriptor(w, &un, Pole::Point(spn), eye_mid(r0), &ctx.polar_opts(r0))?;
    Ok(Run {
        one,
        both,
        nose,
        one_pct: 100.0 * rad / r0.d,
    })
}

/// Fills the random-error matrices.
pub(super) fn run(ctx: &Ctx<'_>, prep: &[FacePrep], res: &mut MethodResults) -> Result<()> {
    let nf = ctx.faces.len();
    let ids: Vec<usize> = (0..nf).collect();
    let msg = format!("{}: random errors", ctx.mname());
    let runs = par_map(&ids, &msg, |&i| one_face(ctx, &prep[i], i));
    let runs = runs.into_iter().collect::<Result<Vec<Run>>>()?;
    let (mut one, mut both, mut nose) = (Vec::new(), Vec::new(), Vec::new());
    for r in runs {
        res.rand_one_pct.push(r.one_pct);
        one.push(r.one);
        both.push(r.both);
        nose.push(r.nose);
    }
    res.m_rand_one = ctx.matrix(&one, "random error on q");
    res.m_rand_both = ctx.matrix(&both, "random errors on r and q");
    res.m_rand_nose = ctx.matrix(&nose, "single pole, random error on the nose tip");
    Ok(())
}
