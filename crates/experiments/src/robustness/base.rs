//! Figures 4-7: renders of the level curves, descriptor points and static area on the test
//! face; the distance against resolution; the 12 x 12 matrices at the default resolution (and
//! the single-pole matrix).

use super::{eye_mid, n_keys, Ctx, Desc, FacePrep, MethodResults, RESOLUTIONS};
use crate::pipeline::{bar, Area};
use crate::polar::{polar_descriptor, Pole};
use crate::report::{markers, polylines, render_face as render};
use anyhow::Result;
use bipolar::PolarDescriptor;
use meshcore::{DVec3, Topology, TriMesh};
use rayon::prelude::*;
use std::path::Path;
use viz::{Polyline, Scene};

/// The descriptors the later parts compare against.
pub(super) struct Base {
    /// Static-area descriptors per resolution of [`RESOLUTIONS`], per face.
    pub sweep: Vec<Vec<Desc>>,
    /// Static-area descriptors at the default resolution, per face.
    pub static_: Vec<Desc>,
    /// Single-pole descriptors, per face.
    pub polar: Vec<PolarDescriptor>,
}

const RED: [u8; 3] = [0xc0, 0x39, 0x2b];
const BLUE: [u8; 3] = [0x24, 0x71, 0xa3];
const YELLOW: [u8; 3] = [0xf1, 0xc4, 0x0f];
const GREEN: [u8; 3] = [0x27, 0xae, 0x60];
const GREY: [u8; 3] = [0xbb, 0xbb, 0xbb];
const ORANGE: [u8; 3] = [0xe6, 0x7e, 0x22];
/// Surface colour of the static area in the renders (the rest is viz's default grey).
const STATIC_TINT: [u8; 3] = [170, 200, 255];
const SURFACE: [u8; 3] = [225, 215, 205];

/// Positions of a descriptor's points (none if refused).
fn positions(d: &Desc) -> Vec<DVec3> {
    d.as_ref()
        .map(bipolar::Descriptor::positions)
        .unwrap_or_default()
}

/// Level curves of `u` at `levels` (`levelcurves`), as polylines of one colour.
fn curves(
    mesh: &TriMesh,
    topo: &Topology,
    u: &[f64],
    levels: &[f64],
    color: [u8; 3],
) -> Result<Vec<Polyline>> {
    let lines = levelcurves::isolines(mesh, topo, u, levels)?;
    Ok(polylines(
        lines
            .into_iter()
            .flatten()
            .map(|c| (c.points, c.closed, color)),
        1.1,
    ))
}

/// Figures 4 and 5 on the test face: level curves at 5, 10 and 30 levels between the corners
/// with the whole-face descriptor, and the static area with its descriptor.
pub(super) fn renders(ctx: &Ctx<'_>, prep: &[FacePrep], out: &Path) -> Result<()> {
    let (mname, n) = (ctx.mname(), ctx.args.set.res.levels);
    let f = &ctx.faces[ctx.test];
    let rf = &prep[ctx.test].refs;
    let topo = Topology::new(&f.mesh);
    for &nl in &[5u32, 10, 30] {
        let step = rf.d / f64::from(nl);
        let maxu = rf
            .ur
            .iter()
            .chain(&rf.uq)
            .copied()
            .filter(|x| x.is_finite())
            .fold(0.0, f64::max);
        let levels: Vec<f64> = (1..)
            .map(|i| f64::from(i) * step)
            .take_while(|l| *l < maxu)
            .collect();
        let desc = ctx.describe(&f.mesh, rf, nl, Area::Whole, || {
            format!("{} (whole, N = {nl})", f.name)
        });
        let mut scene = Scene::new(&f.mesh);
        scene.polylines = curves(&f.mesh, &topo, &rf.ur, &levels, RED)?;
        scene
            .polylines
            .extend(curves(&f.mesh, &topo, &rf.uq, &levels, BLUE)?);
        scene.points = markers(positions(&desc), YELLOW, if nl >= 30 { 1.3 } else { 2.6 });
        scene.points.extend(markers([rf.r, rf.q], GREEN, 5.0));
        render(
            &out.join(format!("render_{mname}_levels{nl}.svg")),
            &scene,
            rf.frame.up,
            rf.frame.forward,
        )?;
    }
    let mask = rf.static_area(&f.mesh);
    let ds = ctx.describe(&f.mesh, rf, n, Area::Static, || {
        format!("{} (static, N = {n})", f.name)
    });
    let dw = ctx.describe(&f.mesh, rf, n, Area::Whole, || {
        format!("{} (whole, N = {n})", f.name)
    });
    let mut scene = Scene::new(&f.mesh);
    scene.vertex_colors = Some(
        mask.iter()
            .map(|&m| if m { STATIC_TINT } else { SURFACE })
            .collect(),
    );
    scene.points = markers(positions(&dw), GREY, 1.6);
    scene.points.extend(markers(positions(&ds), ORANGE, 2.8));
    scene
        .points
        .extend(markers([rf.r, rf.q, rf.nose], GREEN, 5.0));
    render(
        &out.join(format!("render_{mname}_static.svg")),
        &scene,
        rf.frame.up,
        rf.frame.forward,
    )
}

/// Figures 6 and 7: the distance from the test face against resolution, the static and whole
/// matrices at the default resolution, and the single-pole matrix.
pub(super) fn run(ctx: &Ctx<'_>, prep: &[FacePrep], res: &mut MethodResults) -> Result<Base> {
    let (faces, test, n) = (ctx.faces, ctx.test, ctx.args.set.res.levels);
    let nf = faces.len();
    let describe_all = |nl: u32, area: Area, label: &'static str| -> Vec<Desc> {
        faces
            .par_iter()
            .zip(prep)
            .map(|(f, p)| {
                ctx.describe(&f.mesh, &p.refs, nl, area, || {
                    format!("{} ({label}, N = {nl})", f.name)
                })
            })
            .collect()
    };
    let pb = bar(
        RESOLUTIONS.len(),
        &format!("{}: resolution sweep", ctx.mname()),
    );
    let sweep: Vec<Vec<Desc>> = RESOLUTIONS
        .iter()
        .map(|&nl| {
            let v = describe_all(nl, Area::Static, "static");
            pb.inc(1);
            v
        })
        .collect();
    pb.finish();
    for (ds, &nl) in sweep.iter().zip(&RESOLUTIONS) {
        let row: Vec<f64> = (0..nf)
            .map(|j| {
                if j == test {
                    0.0
                } else {
                    ctx.dist(&ds[test], &ds[j], || {
                        format!(
                            "static, N = {nl}: {} vs {}",
                            faces[test].name, faces[j].name
                        )
                    })
                }
            })
            .collect();
        res.sweep.push((nl, row));
    }
    let static_ = describe_all(n, Area::Static, "static");
    let whole = describe_all(n, Area::Whole, "whole");
    res.n_points = static_
        .iter()
        .zip(&whole)
        .map(|(a, b)| (n_keys(a), n_keys(b)))
        .collect();
    res.m_static = ctx.matrix(&static_, &format!("static, N = {n}"));
    res.m_whole = ctx.matrix(&whole, &format!("whole, N = {n}"));
    let polar: Vec<PolarDescriptor> = (0..nf)
        .into_par_iter()
        .map(|i| {
            polar_descriptor(
                &ctx.walkers[i],
                &prep[i].un,
                Pole::Vertex(faces[i].landmarks.nose_tip),
                eye_mid(&prep[i].refs),
                &ctx.polar_opts(&prep[i].refs),
            )
        })
        .collect::<Result<_>>()?;
    res.m_polar = ctx.matrix(&polar, "single pole");
    Ok(Base {
        sweep,
        static_,
        polar,
    })
}
