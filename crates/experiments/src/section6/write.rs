//! The section-6 report: renders of the curve representations, the tables of each
//! measurement with every movement relative to the distance between persons, and the claims
//! of section 6 against these numbers.

use super::describe::Descs;
use super::figure15::Fig15;
use super::measure::Between;
use super::{Args, CSV_COLUMNS, REL_COLUMNS, REPS};
use crate::pipeline::RADII_PCT;
use crate::report::{f4, joined, polylines, render_face, Report};
use crate::robustness::pole::ROTATED;
use crate::robustness::stats::{max, mean, verdict};
use anyhow::Result;
use facecurves::PrincipalField;
use facemodel::{Face, FaceFrame};
use std::path::Path;
use std::time::Instant;
use viz::Scene;

/// Colour of the k1 iso-curvature curves.
const RED: [u8; 3] = [0xc0, 0x39, 0x2b];
/// Colour of the k2 iso-curvature curves.
const BLUE: [u8; 3] = [0x24, 0x71, 0xa3];
/// Colour of the facial curves.
const GREEN: [u8; 3] = [0x27, 0xae, 0x60];

/// Figure 14 style on `face` seen from the front of its landmark `frame`: the iso-curvature
/// network (k1 red, k2 blue); the facial curves (green).
pub(super) fn renders(out: &Path, face: &Face, frame: &FaceFrame, d: &Descs) -> Result<()> {
    let render = |file: &str, lines| {
        let mut scene = Scene::new(&face.mesh);
        scene.polylines = lines;
        render_face(&out.join(file), &scene, frame.up, frame.forward)
    };
    if let Some(iso) = &d.iso {
        let color = |f| if f == PrincipalField::K1 { RED } else { BLUE };
        let lines = iso
            .curves
            .iter()
            .map(|c| (c.points.clone(), c.closed, color(c.field)));
        render("iso_curvature.svg", polylines(lines, 1.4))?;
    }
    if let Some(f) = &d.facial {
        let lines = f.curves.iter().map(|c| (c.points.clone(), c.closed, GREEN));
        render("facial_curves.svg", polylines(lines, 1.6))?;
    }
    Ok(())
}

/// A table row of movements: `label`, then per representation `agg` of the distances `d` with,
/// in brackets, its value relative to `scale` (the distance between persons).
fn rel_row<'a>(
    label: String,
    d: impl Iterator<Item = &'a [f64; 4]>,
    agg: fn(&[f64]) -> f64,
    scale: &[f64],
) -> Vec<String> {
    let d: Vec<&[f64; 4]> = d.collect();
    std::iter::once(label)
        .chain((0..4).map(|k| {
            let v: Vec<f64> = d.iter().map(|x| x[k]).collect();
            let a = agg(&v);
            format!("{} ({:.2})", f4(a), a / scale[k])
        }))
        .collect()
}

/// The [`rel_row`] of the mean movement at each of `levels` (labelled by `label`): over the
/// cells whose first coordinate is that level, with their distances `d`.
fn level_rows<T: PartialEq + Copy, U>(
    levels: &[T],
    cells: &[(T, U)],
    d: &[[f64; 4]],
    label: impl Fn(T) -> String,
    scale: &[f64],
) -> Vec<Vec<String>> {
    levels
        .iter()
        .map(|&l| {
            let at = cells
                .iter()
                .zip(d)
                .filter(|(c, _)| c.0 == l)
                .map(|(_, v)| v);
            rel_row(label(l), at, mean, scale)
        })
        .collect()
}

/// CSV rows, one per cell: its two leading columns (`lead`), then its four distances.
fn cell_rows<C>(cells: &[C], d: &[[f64; 4]], lead: impl Fn(&C) -> [String; 2]) -> Vec<Vec<String>> {
    cells
        .iter()
        .zip(d)
        .map(|(c, v)| {
            lead(c)
                .into_iter()
                .chain(v.iter().map(|x| format!("{x}")))
                .collect()
        })
        .collect()
}

/// Everything the report is written from.
pub(super) struct Results<'a> {
    /// The task's arguments.
    pub args: &'a Args,
    /// The faces.
    pub faces: &'a [Face],
    /// Index of the test face.
    pub test: usize,
    /// The between-person comparisons.
    pub between: &'a Between,
    /// Reference-point grid cells `(radius % of D, direction)`.
    pub grid_cells: Vec<(f64, f64)>,
    /// The four distances per grid cell.
    pub grid: Vec<[f64; 4]>,
    /// Depth-noise cells `(sigma mm, draw)`.
    pub noise_cells: Vec<(f64, usize)>,
    /// The four distances per noise cell.
    pub noise: Vec<[f64; 4]>,
    /// Figure-15 scores.
    pub fig15: Fig15,
    /// Elastic distance of each rotated ring to its original.
    pub fig15_rings: Vec<(u32, f64)>,
    /// Millimetres per mesh unit.
    pub mm: f64,
    /// Refusals, sorted.
    pub failures: Vec<String>,
    /// Start of the run (for the total time).
    pub t_start: Instant,
}

/// Writes the report's sections into `rep` (and the CSV tables beside it).
pub(super) fn write_report(rep: &mut Report, r: &Results<'_>) -> Result<()> {
    intro(rep, r);
    between_section(rep, r)?;
    grid_section(rep, r)?;
    noise_section(rep, r)?;
    figure15_section(rep, r);
    claims_section(rep, r);
    failures_section(rep, r);
    Ok(())
}

/// The opening paragraph (set-up, distances, scales) and the two curve renders.
fn intro(rep: &mut Report, r: &Results<'_>) {
    let (args, faces, test, t_start) = (r.args, r.faces, r.test, r.t_start);
    let tf = &faces[test];
    rep.para(&format!(
        "{} faces of the paper set, test face {}; exact geodesics; N = {} (bipolar static area; \
         single pole with {} sectors, facial curves and the iso-curvature region up to D from \
         the nose tip); iso-curvature: {} levels per principal field between the 5 % and 95 % \
         quantiles of the test face. Distances: bipolar and single pole keyed L2 in [0, 1]; \
         facial curves elastic (SRVF), root sum of squares over curves, in sqrt(mesh units); \
         iso-curvature normalised RMS closest-point distance after global ICP, in [0, 1]. \
         Because the scales differ, every movement is also given relative to the distance \
         between the test face and its nearest other person (`rel.`). Seed {}. Built by \
         `cargo xtask section6` (release); total {:.0} s.",
        faces.len(),
        tf.name,
        args.set.res.levels,
        args.set.res.sectors,
        args.iso_levels,
        args.seed,
        t_start.elapsed().as_secs_f64()
    ));
    rep.figure(
        "iso_curvature.svg",
        "Iso-curvature network of the test face (k1 red, k2 blue), figure 14 style",
    );
    rep.figure(
        "facial_curves.svg",
        "Facial curves of the test face (longest piece of each level)",
    );
}

/// Between persons: separations, time per comparison and the matrices as CSV.
fn between_section(rep: &mut Report, r: &Results<'_>) -> Result<()> {
    let (faces, mats, seps, times, n_timed) = (
        r.faces,
        &r.between.mats,
        &r.between.seps,
        &r.between.times,
        r.between.n_timed,
    );
    rep.heading(2, "Between persons (12 x 12 matrices)");
    let mut rows = Vec::new();
    for k in 0..4 {
        let s = &seps[k];
        rows.push(vec![
            REPS[k].to_string(),
            f4(s.max_same),
            f4(s.min_diff),
            format!("{:.2} ({})", s.ratio(), verdict(s.ratio())),
            f4(s.row_max_same),
            f4(s.row_min_diff),
            format!("{:.2} ({})", s.row_ratio(), verdict(s.row_ratio())),
            format!("{:.3}", times[k]),
        ]);
    }
    rep.table(
        &[
            "representation",
            "max same person",
            "min other person",
            "ratio",
            "test row: max same",
            "test row: min other",
            "ratio",
            "ms per comparison",
        ],
        &rows,
    );
    for (k, m) in mats.iter().enumerate() {
        let name = format!("matrix_{}.csv", REPS[k].replace(' ', "_"));
        let labels: Vec<&str> = faces.iter().map(|f| f.name.as_str()).collect();
        rep.matrix_csv(&name, &labels, m)?;
    }
    rep.para(&format!("Times: median wall time of one comparison on one thread (a one-thread pool), over the test face's {n_timed} comparisons, on a shared machine (compare them as ratios)."));
    Ok(())
}

/// Reference-point errors: the mean movement per radius and `grid.csv`.
fn grid_section(rep: &mut Report, r: &Results<'_>) -> Result<()> {
    let (scale, grid_cells, grid) = (&r.between.scale[..], &r.grid_cells[..], &r.grid[..]);
    rep.heading(2, "Reference-point errors (the grid of figures 9-11)");
    rep.para("Bipolar: the left outer eye corner moved; single pole, facial curves and iso-curvature: the nose tip moved (the iso-curvature network depends on it only through its region). Walks stopped by a hole are left out.");
    let mut rows = level_rows(&RADII_PCT, grid_cells, grid, |p| format!("{p} %"), scale);
    rows.push(rel_row("all (max)".to_string(), grid.iter(), max, scale));
    rep.table(&[&["radius (% of D)"][..], &REL_COLUMNS].concat(), &rows);
    rep.csv(
        "grid.csv",
        &[&["radius_pct", "angle_deg"][..], &CSV_COLUMNS].concat(),
        &cell_rows(grid_cells, grid, |c| {
            [format!("{}", c.0), format!("{:.1}", c.1.to_degrees())]
        }),
    )?;
    Ok(())
}

/// Depth noise: the mean movement per standard deviation and `noise.csv`.
fn noise_section(rep: &mut Report, r: &Results<'_>) -> Result<()> {
    let (args, scale, noise_cells, noise, mm) = (
        r.args,
        &r.between.scale[..],
        &r.noise_cells[..],
        &r.noise[..],
        r.mm,
    );
    rep.heading(2, "Depth noise on the test face");
    rep.para(&format!(
        "Gaussian noise along the vertex normals ({} draws per level; the face is in units of {mm} mm); every field, curvature and descriptor recomputed on the noisy mesh, compared with the clean one.",
        args.noise_draws
    ));
    let rows = level_rows(
        &args.noise_mm,
        noise_cells,
        noise,
        |s| format!("{s} mm"),
        scale,
    );
    rep.table(&[&["sigma"][..], &REL_COLUMNS].concat(), &rows);
    rep.csv(
        "noise.csv",
        &[&["sigma_mm", "draw"][..], &CSV_COLUMNS].concat(),
        &cell_rows(noise_cells, noise, |c| {
            [format!("{}", c.0), format!("{}", c.1)]
        }),
    )?;
    Ok(())
}

/// Figure 15: the rotated rings against the other person.
fn figure15_section(rep: &mut Report, r: &Results<'_>) {
    let (fig15, fig15_rings) = (&r.fig15, &r.fig15_rings[..]);
    rep.heading(2, "Figure 15: polar rings rotated one by one");
    rep.para(&format!(
        "Rings {ROTATED:?} of the test face's single-pole descriptor each rotated about its centroid (the robustness task's construction), scored by each family of distance, against the same distance to the nearest other person's descriptor."
    ));
    let rows: Vec<Vec<String>> = fig15
        .iter()
        .map(|(n, r, o)| vec![n.to_string(), f4(*r), f4(*o), format!("{:.3}", r / o)])
        .collect();
    rep.table(
        &["distance", "rotated rings", "other person", "ratio"],
        &rows,
    );
    rep.para(&format!(
        "Elastic distance of each ring to its copy in the rotated descriptor: {}.",
        joined(fig15_rings, ", ", |(l, d)| format!("ring {l} {d:.4}"))
    ));
}

/// Each claim of section 6 against the numbers.
fn claims_section(rep: &mut Report, r: &Results<'_>) {
    let (args, scale, times, grid, noise_cells, noise, fig15) = (
        r.args,
        &r.between.scale[..],
        &r.between.times,
        &r.grid[..],
        &r.noise_cells[..],
        &r.noise[..],
        &r.fig15,
    );
    rep.heading(2, "The paper's section-6 claims against these numbers");
    let noise_rel = |k: usize| {
        let v: Vec<f64> = noise.iter().map(|d| d[k] / scale[k]).collect();
        mean(&v)
    };
    let grid_rel = |k: usize| {
        let v: Vec<f64> = grid.iter().map(|d| d[k] / scale[k]).collect();
        mean(&v)
    };
    // 6.1: at the largest noise level, does the iso-curvature network move most, and beyond
    // the distance to another person?
    let top = args.noise_mm.iter().copied().fold(f64::NAN, f64::max);
    let noise_top = |k: usize| {
        let v: Vec<f64> = noise_cells
            .iter()
            .zip(noise)
            .filter(|(c, _)| c.0 == top)
            .map(|(_, d)| d[k] / scale[k])
            .collect();
        mean(&v)
    };
    let iso_worst = (0..3).all(|k| noise_top(3) > noise_top(k));
    rep.para(&format!(
        "**6.1, iso-curvature curves are numerically fragile (successive derivatives).** Mean movement under depth noise relative to the nearest other person, over all levels: bipolar {:.2}, single pole {:.2}, facial curves {:.2}, iso-curvature {:.2}; at {top} mm: {:.2}, {:.2}, {:.2}, {:.2}. {}",
        noise_rel(0), noise_rel(1), noise_rel(2), noise_rel(3),
        noise_top(0), noise_top(1), noise_top(2), noise_top(3),
        if iso_worst && noise_top(3) >= 1.0 {
            "Supported: the iso-curvature network moves most, and farther than the distance to another person."
        } else if noise_top(3) > noise_top(0) {
            "Partly supported: the iso-curvature network moves more than the bipolar descriptor, but it is not the most fragile of the four, or it stays closer than another person."
        } else {
            "Not supported by this measure: the bipolar descriptor moves as much or more."
        }
    ));
    let per = |k: usize| times[k];
    let t_rel = per(2) / per(0).max(1e-12);
    rep.para(&format!(
        "**6.2, matching facial curves is costly (curves, then points on curves).** Time per comparison: facial curves {:.1} ms vs bipolar {:.3} ms ({t_rel:.0}x), single pole {:.3} ms, iso-curvature (ICP) {:.1} ms. {}",
        per(2), per(0), per(1), per(3),
        if t_rel > 10.0 { "Supported: an order of magnitude or more." } else if t_rel > 2.0 { "Partly supported: slower, but less than tenfold." } else { "Not supported: the elastic matching is not much slower." }
    ));
    let (kr, er) = (fig15[0].1 / fig15[0].2, fig15[1].1 / fig15[1].2);
    rep.para(&format!(
        "**6.2, a sum of per-curve distances is blind to rotations of single curves (figure 15).** Rotated rings against the other person: keyed L2 {kr:.3}, elastic sum over curves {er:.3}. {}",
        if er < 0.1 && kr > 3.0 * er { "Supported: the curve-wise distance hardly sees the rotated rings (below a tenth of the distance to another person), the keyed one sees them at least three times more." } else if er < kr { "Partly supported: the curve-wise distance sees the rotated rings less than the keyed one, but not close to zero (see the table)." } else { "Not supported: the curve-wise distance sees the rotated rings as much as the keyed one." }
    ));
    let bip_best = (1..4).all(|k| grid_rel(0) < grid_rel(k));
    rep.para(&format!(
        "**6.3 and figure 17, the bipolar representation is more robust to reference-point errors than single-pole ones.** Mean movement over the grid relative to the nearest other person: bipolar {:.2}, single pole {:.2}, facial curves {:.2}, iso-curvature {:.2} (the last depends on the nose tip only through its region). {}",
        grid_rel(0), grid_rel(1), grid_rel(2), grid_rel(3),
        if bip_best { "Supported: the bipolar descriptor moves least." } else if grid_rel(0) < grid_rel(1) { "Partly supported: the bipolar descriptor moves less than the single pole, but not less than every representation." } else { "Not supported: the single pole moves less." }
    ));
}

/// The refusals, if any.
fn failures_section(rep: &mut Report, r: &Results<'_>) {
    let failures = &r.failures[..];
    if !failures.is_empty() {
        rep.heading(2, "Crate errors");
        rep.para(&format!(
            "{} descriptors or distances refused (their cells are NaN):",
            failures.len()
        ));
        rep.list(failures);
    }
}
