//! The measurements of section 6 on a described face set: the between-person matrices and
//! the time per comparison, the reference-point grid, the depth noise and figure 15.

use super::describe::{Ctx, Descs};
use super::figure15::{figure15, Fig15};
use crate::pipeline::{dist, error_grid, single_thread};
use crate::polar::Pole;
use crate::report::{par_map, quantile, sorted};
use crate::robustness::stats::Sep;
use crate::robustness::FacePrep;
use crate::walk::Walker;
use anyhow::{Context, Result};
use facemodel::Face;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The described face set: faces, their geodesic set-ups, walkers and base descriptors, the
/// test face, and the describing context.
pub(super) struct Set<'a> {
    /// The faces.
    pub faces: &'a [Face],
    /// Per face: solver, reference configuration, nose field.
    pub preps: &'a [FacePrep],
    /// Per face: the straightest-geodesic walker.
    pub walkers: &'a [Walker<'a>],
    /// Per face: the four descriptors.
    pub base: &'a [Descs],
    /// Index of the test face.
    pub test: usize,
    /// How descriptors and distances are made.
    pub ctx: &'a Ctx<'a>,
}

/// Cells of a measurement with the four distances of each.
type Cells<C> = (Vec<C>, Vec<[f64; 4]>);

/// The between-person comparisons: the four matrices, the median time per comparison (ms)
/// of each representation, how many comparisons were timed, and the separations.
pub(super) struct Between {
    /// Per representation, the face x face distance matrix.
    pub mats: Vec<Vec<Vec<f64>>>,
    /// Median ms per comparison of each representation.
    pub times: [f64; 4],
    /// Comparisons timed (the test face's row).
    pub n_timed: usize,
    /// Per representation, same- and other-person separation.
    pub seps: Vec<Sep>,
    /// The scale every movement is measured against: the test face's nearest other person.
    pub scale: Vec<f64>,
}

/// The 12 x 12 matrices, the time per comparison and the separations.
pub(super) fn between_persons(s: &Set<'_>) -> Result<Between> {
    let (faces, base, ctx, test) = (s.faces, s.base, s.ctx, s.test);
    let nf = faces.len();
    let pairs: Vec<(usize, usize)> = (0..nf)
        .flat_map(|i| (i + 1..nf).map(move |j| (i, j)))
        .collect();
    let cells = par_map(&pairs, "12 x 12 matrices", |&(i, j)| {
        let what = format!("{} vs {}", faces[i].name, faces[j].name);
        ctx.distances(&base[i], &base[j], &what)
    });
    let mut mats = vec![vec![vec![0.0; nf]; nf]; 4];
    for (&(i, j), (d, _)) in pairs.iter().zip(&cells) {
        for k in 0..4 {
            mats[k][i][j] = d[k];
            mats[k][j][i] = d[k];
        }
    }
    // Time per comparison: the test face's row again, one pair at a time on one thread (times
    // taken inside the parallel loop include work stolen into nested parallel waits).
    let row: Vec<usize> = (0..nf).filter(|&j| j != test).collect();
    let (row_times, _) = single_thread(|| {
        row.iter()
            .map(|&j| ctx.distances(&base[test], &base[j], "timing").1)
            .collect::<Vec<_>>()
    })?;
    // Median over the pairs: a pair preempted by other jobs on the shared machine does not
    // move it.
    let times: [f64; 4] = std::array::from_fn(|k| {
        let v: Vec<f64> = row_times.iter().map(|t| t[k].as_secs_f64() * 1e3).collect();
        quantile(&sorted(v), 0.5)
    });
    let persons: Vec<&str> = faces.iter().map(|f| f.person.as_str()).collect();
    let seps: Vec<Sep> = mats.iter().map(|m| Sep::of(m, &persons, test)).collect();
    let scale: Vec<f64> = seps.iter().map(|s| s.row_min_diff).collect();
    Ok(Between {
        mats,
        times,
        n_timed: row.len(),
        seps,
        scale,
    })
}

/// The reference-point grid: per cell `(radius % of D, direction)`, the bipolar distance with
/// the left outer eye corner moved and the other three with the nose tip moved (NaN where a
/// walk was stopped by a hole).
pub(super) fn reference_grid(s: &Set<'_>) -> Result<Cells<(f64, f64)>> {
    let grid_cells = error_grid();
    let grid = par_map(&grid_cells, "reference-point grid", |&(pct, theta)| {
        grid_cell(s, pct, theta)
    });
    let grid = grid.into_iter().collect::<Result<Vec<_>>>()?;
    Ok((grid_cells, grid))
}

/// One cell of [`reference_grid`]: the reference points moved by `pct` % of D towards
/// `theta`.
fn grid_cell(s: &Set<'_>, pct: f64, theta: f64) -> Result<[f64; 4]> {
    let (tf, tp, w, ctx) = (
        &s.faces[s.test],
        &s.preps[s.test],
        &s.walkers[s.test],
        s.ctx,
    );
    let name = format!("{} moved {pct} % at {:.0} deg", tf.name, theta.to_degrees());
    // Left outer eye corner moved: the bipolar descriptor; nose tip moved: the other three
    // (same D, the corners are not moved).
    let (refs, (sn, un), (cut_q, cut_n)) = tp.moved_cell(tf, w, (pct, theta))?;
    let moved_q = ctx.bipolar(&tf.mesh, &refs, &name);
    let moved_n = ctx.nose_descs((&tf.mesh, w), &tp.refs, &un, Pole::Point(sn), &name);
    let base = &s.base[s.test];
    let dq = dist(&base.bipolar, &moved_q).unwrap_or(f64::NAN);
    let (dn, _) = ctx.distances(base, &moved_n, &name);
    let nan_if = |cut: bool, v: f64| if cut { f64::NAN } else { v };
    Ok([
        nan_if(cut_q, dq),
        nan_if(cut_n, dn[1]),
        nan_if(cut_n, dn[2]),
        nan_if(cut_n, dn[3]),
    ])
}

/// Depth noise on the test face: per cell `(sigma mm, draw)`, the four distances between the
/// clean and the noisy face (everything recomputed on the noisy mesh). `mm` is millimetres
/// per mesh unit.
pub(super) fn depth_noise(s: &Set<'_>, mm: f64) -> Result<Cells<(f64, usize)>> {
    let (tf, ctx) = (&s.faces[s.test], s.ctx);
    let args = ctx.args;
    let noise_cells: Vec<(f64, usize)> = args
        .noise_mm
        .iter()
        .flat_map(|&s| (0..args.noise_draws).map(move |k| (s, k)))
        .collect();
    let noise = par_map(
        &noise_cells,
        "depth noise",
        |&(sigma_mm, k)| -> Result<[f64; 4]> {
            let seed =
                args.seed ^ (k as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ sigma_mm.to_bits();
            let noise = rangescan::DepthNoise { sigma_mm };
            let m = noise.along_normals(&tf.mesh, mm, &mut ChaCha8Rng::seed_from_u64(seed))?;
            let noisy_face = Face {
                mesh: m,
                ..tf.clone()
            };
            let p = FacePrep::new(&noisy_face, geodesic::Method::Exact)?;
            let wn = Walker::new(&noisy_face.mesh);
            let name = format!("{} with {sigma_mm} mm noise, draw {k}", tf.name);
            let nose = Pole::Vertex(tf.landmarks.nose_tip);
            let dsc = ctx.describe((&noisy_face.mesh, &wn), &p.refs, &p.un, nose, &name);
            Ok(ctx.distances(&s.base[s.test], &dsc, &name).0)
        },
    );
    let noise = noise.into_iter().collect::<Result<Vec<_>>>()?;
    Ok((noise_cells, noise))
}

/// Figure 15 on the test face's single pole, against the nearest other person by the
/// single-pole distance (`single_pole`: its matrix).
pub(super) fn rotated_rings(
    s: &Set<'_>,
    single_pole: &[Vec<f64>],
) -> Result<(Fig15, Vec<(u32, f64)>)> {
    let (faces, test) = (s.faces, s.test);
    let other = (0..faces.len())
        .filter(|&j| faces[j].person != faces[test].person)
        .min_by(|&a, &b| single_pole[test][a].total_cmp(&single_pole[test][b]));
    figure15(
        s.base[test]
            .polar
            .as_ref()
            .context("the test face's single-pole descriptor")?,
        other.and_then(|j| s.base[j].polar.as_ref()),
        s.ctx.args.seed,
        s.ctx.args.set.res.levels,
    )
}
