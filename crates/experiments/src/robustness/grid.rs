//! Figures 9-11: the left outer eye corner (and, for the single pole, the nose tip) of the test
//! face moved by radius x direction; the distance to the unperturbed descriptor per cell, and
//! the paper's three cases against resolution.

use super::base::Base;
use super::stats::{max, mean, min};
use super::{eye_mid, Ctx, FacePrep, MethodResults, RESOLUTIONS};
use crate::pipeline::{error_grid, Area, PoleRefs};
use crate::polar::{polar_descriptor, Pole};
use crate::report::par_map;
use anyhow::Result;
use bipolar::PolarDescriptor;
use rayon::prelude::*;

/// One perturbation cell: moved-corner references, moved-pole polar descriptor, and whether
/// each walk met the boundary.
struct Cell {
    refs: PoleRefs,
    polar: PolarDescriptor,
    cut_q: bool,
    cut_nose: bool,
}

/// Moves q and the nose tip of the test face for every (radius, direction) cell.
fn perturbed(ctx: &Ctx<'_>, prep: &[FacePrep], cells: &[(f64, f64)]) -> Result<Vec<Cell>> {
    let (test, tr) = (ctx.test, &prep[ctx.test].refs);
    let w = &ctx.walkers[test];
    let msg = format!("{}: perturbation grid", ctx.mname());
    let grid = par_map(cells, &msg, |&cell| -> Result<_> {
        let (refs, (sn, un), (cut_q, cut_nose)) =
            prep[test].moved_cell(&ctx.faces[test], w, cell)?;
        let pole = Pole::Point(sn);
        let polar = polar_descriptor(w, &un, pole, eye_mid(tr), &ctx.polar_opts(tr))?;
        Ok(Cell {
            refs,
            polar,
            cut_q,
            cut_nose,
        })
    });
    grid.into_iter().collect()
}

/// Fills the perturbation grid (figures 9, 10, 17) and the three cases (figure 11).
pub(super) fn run(
    ctx: &Ctx<'_>,
    prep: &[FacePrep],
    base: &Base,
    res: &mut MethodResults,
) -> Result<()> {
    let (faces, test, n) = (ctx.faces, ctx.test, ctx.args.set.res.levels);
    let tf = &faces[test];
    let cells = error_grid();
    let grid = perturbed(ctx, prep, &cells)?;
    let cell_name = |c: &(f64, f64)| {
        format!(
            "{} (q moved {} % at {:.1} deg)",
            tf.name,
            c.0,
            c.1.to_degrees()
        )
    };
    // Walks stopped by the boundary (the eye opening) did not move the point by the radius:
    // their cells are left out (NaN) and counted.
    for (c, g) in cells.iter().zip(&grid) {
        let db = if g.cut_q {
            f64::NAN
        } else {
            let moved = ctx.describe(&tf.mesh, &g.refs, n, Area::Static, || cell_name(c));
            ctx.dist(&base.static_[test], &moved, || cell_name(c))
        };
        res.grid_bip.push((c.0, c.1, db));
        let dp = if g.cut_nose {
            f64::NAN
        } else {
            ctx.dist(&base.polar[test], &g.polar, || {
                format!(
                    "{} (nose tip moved {} % at {:.1} deg)",
                    tf.name,
                    c.0,
                    c.1.to_degrees()
                )
            })
        };
        res.grid_pol.push((c.0, c.1, dp));
    }
    res.truncated = (
        grid.iter().filter(|g| g.cut_q).count(),
        grid.iter().filter(|g| g.cut_nose).count(),
    );
    // Figure 11: the three cases against resolution.
    let same: Vec<usize> = (0..faces.len())
        .filter(|&j| j != test && faces[j].person == faces[test].person)
        .collect();
    let other: Vec<usize> = (0..faces.len())
        .filter(|&j| faces[j].person != faces[test].person)
        .collect();
    for (ds, &nl) in base.sweep.iter().zip(&RESOLUTIONS) {
        let pert: Vec<f64> = grid
            .par_iter()
            .zip(&cells)
            .filter(|(g, _)| !g.cut_q)
            .map(|(g, c)| {
                let what = || format!("{}, N = {nl}", cell_name(c));
                let moved = ctx.describe(&tf.mesh, &g.refs, nl, Area::Static, what);
                ctx.dist(&ds[test], &moved, what)
            })
            .collect();
        let to = |js: &[usize]| -> Vec<f64> {
            js.iter()
                .map(|&j| {
                    ctx.dist(&ds[test], &ds[j], || {
                        format!(
                            "static, N = {nl}: {} vs {}",
                            faces[test].name, faces[j].name
                        )
                    })
                })
                .collect()
        };
        let (e, o) = (to(&same), to(&other));
        res.fig11.push((
            nl,
            [
                mean(&pert),
                max(&pert),
                mean(&e),
                min(&e),
                mean(&o),
                min(&o),
            ],
        ));
    }
    Ok(())
}
