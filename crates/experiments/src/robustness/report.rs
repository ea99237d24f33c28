//! report.md and the CSV tables of `cargo xtask robustness`; every figure is drawn by `viz`.

use super::pole::Figure15;
use super::stats::{matrix_rows, max, mean, min, Sep, SepColumn};
use super::{Args, Failures, MethodResults};
use crate::pipeline::{DescriptorRule, MethodUse, N_DIRS, RADII_PCT};
use crate::report::{f4, joined, line_plot, Report, Series};
use anyhow::Result;
use facemodel::Face;
use std::path::Path;
use std::time::Instant;
use viz::heatmap;

/// What the report is written from.
struct Input<'a> {
    args: &'a Args,
    faces: &'a [Face],
    test: usize,
    methods: &'a [MethodUse],
    results: &'a [MethodResults],
    fig15: &'a Figure15,
    labels: Vec<String>,
    names: Vec<&'a str>,
    n: u32,
}

/// One line of figures 9 and 17: over the perturbation grid `(radius %, direction, distance)`,
/// the distances at each radius reduced by `agg` (mean or max over the directions).
fn radius_series(
    label: &str,
    grid: &[(f64, f64, f64)],
    agg: fn(&[f64]) -> f64,
    dashed: bool,
) -> Series {
    Series {
        name: label.into(),
        points: RADII_PCT
            .iter()
            .map(|&p| {
                let at: Vec<f64> = grid.iter().filter(|g| g.0 == p).map(|g| g.2).collect();
                (p, agg(&at))
            })
            .collect(),
        dashed,
    }
}

/// A distance matrix of the report: the heatmap `{stem}_{method}.svg` titled `title`, its table
/// `{stem}_{method}.csv` (rows and columns labelled by face) and the figure with `caption`.
fn matrix_figure(
    rep: &mut Report,
    inp: &Input<'_>,
    m: &[Vec<f64>],
    (stem, method): (&str, &str),
    title: &str,
    caption: &str,
) -> Result<()> {
    let fname = format!("{stem}_{method}.svg");
    heatmap(rep.path(&fname), title, &inp.labels, m, "distance")?;
    let mut h = vec!["face".to_string()];
    h.extend(inp.labels.iter().cloned());
    let hh: Vec<&str> = h.iter().map(String::as_str).collect();
    rep.csv(
        &format!("{stem}_{method}.csv"),
        &hh,
        &matrix_rows(inp.faces, m),
    )?;
    rep.figure(&fname, caption);
    Ok(())
}

impl Input<'_> {
    /// A row of a separation table ([`sep_table`]): the method, the matrix's `label` and the
    /// [`Sep`] of the matrix `m`.
    fn sep_row(&self, method: &str, label: &str, m: &[Vec<f64>]) -> (String, String, Sep) {
        (
            method.to_string(),
            label.to_string(),
            Sep::of(m, self.faces, self.test),
        )
    }
}

/// A separation table (Markdown and the CSV `file`): the two `lead` columns of each row, then
/// the `cols` of its [`Sep`].
fn sep_table(
    rep: &mut Report,
    file: &str,
    lead: [&str; 2],
    rows: &[(String, String, Sep)],
    cols: &[SepColumn],
) -> Result<()> {
    let hdr: Vec<&str> = lead
        .into_iter()
        .chain(cols.iter().map(|c| c.header()))
        .collect();
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|(a, b, s)| {
            [a.clone(), b.clone()]
                .into_iter()
                .chain(cols.iter().map(|c| c.cell(s)))
                .collect()
        })
        .collect();
    rep.table(&hdr, &cells);
    rep.csv(file, &hdr, &cells)
}

/// A line plot of the report drawn into `file` and added as a figure with `caption`.
fn plot_figure(
    rep: &mut Report,
    file: &str,
    (title, x_label, y_label): (&str, &str, &str),
    series: &[Series],
    caption: &str,
) -> Result<()> {
    line_plot(&rep.path(file), title, x_label, y_label, series)?;
    rep.figure(file, caption);
    Ok(())
}

/// Writes `report.md`, the CSV tables and the figures into `out`.
#[allow(clippy::too_many_arguments)]
pub(super) fn write_report(
    args: &Args,
    faces: &[Face],
    test: usize,
    methods: &[MethodUse],
    results: &[MethodResults],
    fig15: &Figure15,
    failures: &Failures,
    out: &Path,
    t0: Instant,
) -> Result<()> {
    let inp = Input {
        args,
        faces,
        test,
        methods,
        results,
        fig15,
        labels: faces.iter().map(|f| f.name.clone()).collect(),
        names: results.iter().map(|r| r.name.as_str()).collect(),
        n: args.set.res.levels,
    };
    let mut rep = Report::new(
        out,
        "The bipolar representation on faces: the paper's sections 4-6",
    )?;
    introduction(&mut rep, &inp, failures);
    reference_distances(&mut rep, &inp)?;
    renders(&mut rep, &inp)?;
    resolution(&mut rep, &inp)?;
    robustness(&mut rep, &inp)?;
    figure11(&mut rep, &inp)?;
    random_errors(&mut rep, &inp)?;
    single_pole(&mut rep, &inp)?;
    figure15(&mut rep, &inp)?;
    exactness(&mut rep, &inp)?;
    let n_png = rep.png_twins()?;
    rep.para(&format!(
        "Total run time: {:.1} s ({n_png} figures, each as SVG and PNG).",
        t0.elapsed().as_secs_f64()
    ));
    rep.finish()?;
    Ok(())
}

/// The set-up paragraph and "What was available" (descriptor, distance, crate failures).
fn introduction(rep: &mut Report, inp: &Input<'_>, failures: &Failures) {
    let (args, faces, n) = (inp.args, inp.faces, inp.n);
    let persons: std::collections::BTreeSet<&str> =
        faces.iter().map(|f| f.person.as_str()).collect();
    rep.para(&format!(
        "Face set: {} faces ({} persons) from `{}`; test face `{}`. Reference points: the \
         ground-truth outer eye corners (vertices 1507 right = r, 3721 left = q) and the nose tip \
         (4857) for the single-pole comparison. D = geodesic distance between the corners; N = {n} \
         levels between them (step D/N) unless a figure varies N. Shape distance: keyed L2 after \
         the optimal rotation, normalised to [0, 1] (see `docs/experiments.md`). Random seed {}.",
        faces.len(),
        persons.len(),
        args.set.faces_dir().display(),
        faces[inp.test].name,
        args.seed
    ));
    let desc_note = match args.descriptor {
        DescriptorRule::CrateAll => "Descriptor: `bipolar::describe` (precomputed fields) with selection rule `All` (every intersection of level i of U_r with level j of U_q, keys (i, j, side)): the grid reading of the paper, no angle filter (method notes 4). `--descriptor crate-iso-angle` gives the iso-angle rule B instead. (The former `--descriptor local`, a second implementation inside the experiments, is gone: its agreement with the crate is now a test, `crates/bipolar/tests/oracle.rs` against `testsupport::oracle`.)",
        DescriptorRule::CrateIsoAngle => "Descriptor: `bipolar::describe` (precomputed fields) with the iso-angle rule B (K = 8, alpha = 0.95, gradient tangents), keys (i, k, side, sign).",
    };
    let (listed, too_few) = failures.summary();
    let mut notes = vec![
        desc_note.to_string(),
        format!("Crate errors: {} (each listed below with the face; its cells are NaN, blank in the plots). Distance evaluations with fewer than 3 shared keys (n/a, NaN in the CSV): {too_few}.", listed.len()),
        "Distance: `shapedist::keyed_distance` (Kabsch closed form, no residual gate) on the unambiguous keys, matrices by `shapedist::pairwise_matrix`; a key found twice on a face is never paired.".to_string(),
        "Pictures: drawn by `viz` (plots, heatmaps, mesh renders), each SVG with a PNG twin rasterised by `viz::svg_to_png`.".to_string(),
    ];
    notes.extend(listed.iter().map(|s| format!("Crate error: {s}.")));
    for m in inp.methods {
        if let Some(note) = &m.note {
            notes.push(format!("Geodesic method **{}** was requested but {note}; **{}** was used in its place, and its results are labelled `{}`.", m.requested.name(), m.used.name(), m.used.name()));
        }
    }
    rep.heading(2, "What was available");
    rep.list(&notes);
}

/// Reference distances and point counts per face.
fn reference_distances(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    // D per face.
    rep.heading(2, "Reference distances and point counts");
    let mut rows = Vec::new();
    for (i, f) in inp.faces.iter().enumerate() {
        let mut r = vec![f.name.clone()];
        for res in inp.results {
            r.push(format!("{:.3}", res.d[i]));
            r.push(format!("{} / {}", res.n_points[i].0, res.n_points[i].1));
        }
        rows.push(r);
    }
    let mut header = vec!["face".to_string()];
    for nm in &inp.names {
        header.push(format!("D ({nm}, cm)"));
        header.push(format!("points static / whole ({nm})"));
    }
    let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
    rep.table(&hdr, &rows);
    rep.csv("reference_distances.csv", &hdr, &rows)?;
    Ok(())
}

/// Section 1: the renders (figures 4, 5).
fn renders(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    let n = inp.n;
    // 1. Renders.
    rep.heading(
        2,
        "1. Level curves, descriptor points and the static area (figures 4, 5)",
    );
    rep.para("Red: level curves of U_r (right outer eye corner); blue: of U_q (left); yellow: descriptor points (levels up to 2N); green: reference points. The static area (blue tint) is the set of vertices within D of both corners and above the horizontal plane through the nose tip (`docs/experiments.md`); orange points are the descriptor restricted to it.");
    for res in inp.results {
        for nl in [5, 10, 30] {
            rep.figure(
                &format!("render_{}_levels{nl}.svg", res.name),
                &format!(
                    "{}: {nl} level curves between the corners ({})",
                    inp.faces[inp.test].name, res.name
                ),
            );
        }
        rep.figure(
            &format!("render_{}_static.svg", res.name),
            &format!(
                "static area and restricted descriptor, N = {n} ({})",
                res.name
            ),
        );
    }
    Ok(())
}

/// Section 2: distance against resolution (figure 6) and the matrices (figure 7), with the separation table.
fn resolution(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    let n = inp.n;
    // 2. Resolution sweep and matrix.
    rep.heading(
        2,
        "2. Shape distance against resolution (figure 6) and the 12 x 12 matrix (figure 7)",
    );
    for res in inp.results {
        let mut series = Vec::new();
        for j in 0..inp.faces.len() {
            if j == inp.test {
                continue;
            }
            series.push(Series {
                name: inp.faces[j].name.clone(),
                points: res
                    .sweep
                    .iter()
                    .map(|(nl, row)| (f64::from(*nl), row[j]))
                    .collect(),
                dashed: inp.faces[j].person != inp.faces[inp.test].person,
            });
        }
        plot_figure(
            rep,
            &format!("fig6_distance_vs_resolution_{}.svg", res.name),
            (
                &format!(
                    "{} vs every other face, static area ({})",
                    inp.faces[inp.test].name, res.name
                ),
                "levels N between the corners",
                "normalised shape distance",
            ),
            &series,
            &format!("distance from the inp.test face against resolution; solid: same person, dashed: other persons ({})", res.name),
        )?;
        let mut hdr = vec!["N".to_string()];
        hdr.extend(inp.faces.iter().map(|f| f.name.clone()));
        let rows: Vec<Vec<String>> = res
            .sweep
            .iter()
            .map(|(nl, row)| {
                std::iter::once(nl.to_string())
                    .chain(row.iter().map(|v| format!("{v:.6}")))
                    .collect()
            })
            .collect();
        let h: Vec<&str> = hdr.iter().map(String::as_str).collect();
        rep.csv(&format!("fig6_{}.csv", res.name), &h, &rows)?;
    }
    let mut sep_rows = Vec::new();
    for res in inp.results {
        for (label, m, file) in [
            ("static area", &res.m_static, "static"),
            ("whole face (levels up to 2N)", &res.m_whole, "whole"),
        ] {
            matrix_figure(
                rep,
                inp,
                m,
                (&format!("fig7_matrix_{file}"), &res.name),
                &format!("pairwise distances, {label}, N = {n} ({})", res.name),
                &format!("12 x 12 matrix, {label} ({})", res.name),
            )?;
            sep_rows.push(inp.sep_row(&res.name, label, m));
        }
    }
    rep.para("Separation: the largest distance between two inp.faces of the same person, the smallest between inp.faces of different persons, and their ratio (> 1 means every same-person pair is closer than every different-person pair). 'Test row' restricts this to the pairs involving the neutral inp.test face, which is what the paper's figure 6 shows.");
    sep_table(
        rep,
        "separation.csv",
        ["method", "descriptor"],
        &sep_rows,
        &SepColumn::ALL,
    )
}

/// Section 3: the perturbation grid (figures 9, 10).
fn robustness(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    let n = inp.n;
    // 3. Robustness.
    rep.heading(2, "3. Robustness to reference-point errors (figures 9-13)");
    rep.para(&format!("The left outer eye corner q of `{}` is moved along a straightest geodesic of length {}% of D, leaving at angle theta from the direction towards r (counter-clockwise about the outward normal); its distance field is recomputed from the moved surface point, D is recomputed, and the static descriptor at N = {n} is compared with the original one.", inp.faces[inp.test].name, joined(RADII_PCT, ", ", |p| format!("{p}"))));
    for res in inp.results {
        rep.para(&format!("{}: {} of {} corner walks and {} nose-tip walks met the mesh boundary (the eye opening) before the full radius; those cells are left out (blank in the plots, NaN in the CSV).", res.name, res.truncated.0, RADII_PCT.len() * N_DIRS, res.truncated.1));
        let series: Vec<Series> = RADII_PCT
            .iter()
            .map(|&p| Series {
                name: format!("radius {p}% of D"),
                points: res
                    .grid_bip
                    .iter()
                    .filter(|g| g.0 == p)
                    .map(|g| (g.1.to_degrees(), g.2))
                    .collect(),
                dashed: false,
            })
            .collect();
        let by_r = vec![
            radius_series("mean over directions", &res.grid_bip, mean, false),
            radius_series("max over directions", &res.grid_bip, max, true),
        ];
        let plots = [
            (
                "fig9_radius",
                "radius",
                "radius (% of D)",
                by_r,
                "distance against the error radius",
            ),
            (
                "fig10_grid",
                "direction",
                "direction theta (degrees from r)",
                series,
                "distance over the radius x direction grid",
            ),
        ];
        for (stem, by, x_label, s, caption) in plots {
            let name = &res.name;
            plot_figure(
                rep,
                &format!("{stem}_{name}.svg"),
                (
                    &format!("perturbed vs original, by {by} ({name})"),
                    x_label,
                    "normalised shape distance",
                ),
                &s,
                &format!("{caption} ({name})"),
            )?;
        }
        let rows: Vec<Vec<String>> = res
            .grid_bip
            .iter()
            .zip(&res.grid_pol)
            .map(|(b, p)| {
                vec![
                    format!("{}", b.0),
                    format!("{:.1}", b.1.to_degrees()),
                    format!("{:.6}", b.2),
                    format!("{:.6}", p.2),
                ]
            })
            .collect();
        rep.csv(
            &format!("fig9_10_grid_{}.csv", res.name),
            &[
                "radius_pct",
                "theta_deg",
                "bipolar_distance",
                "single_pole_distance",
            ],
            &rows,
        )?;
    }
    Ok(())
}

/// The six curves of figure 11, in the order of their values: plot label, table header, dashed.
const FIG11_CASES: [(&str, &str, bool); 6] = [
    ("(a) perturbed, mean", "a mean", false),
    ("(a) perturbed, max", "a max", true),
    ("(b) expressions, mean", "b mean", false),
    ("(b) expressions, min", "b min", true),
    ("(c) other persons, mean", "c mean", false),
    ("(c) other persons, min", "c min", true),
];

/// Figure 11: the three cases against resolution.
fn figure11(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    let results = inp.results;
    // Figure 11.
    rep.para("Figure 11, the paper's three cases against resolution: (a) perturbed vs original (the 40 grid perturbations), (b) the test face vs the same person's other expressions, (c) vs other persons. The ordering a < b < c is checked on the means and, more strictly, as max(a) < min(b) and min(b)... (strict: max a < min b, and mean b < min c).");
    let mut rows = Vec::new();
    for res in results {
        let s: Vec<Series> = FIG11_CASES
            .iter()
            .enumerate()
            .map(|(k, &(name, _, dashed))| Series {
                name: name.into(),
                points: res
                    .fig11
                    .iter()
                    .map(|(nl, v)| (f64::from(*nl), v[k]))
                    .collect(),
                dashed,
            })
            .collect();
        plot_figure(
            rep,
            &format!("fig11_three_cases_{}.svg", res.name),
            (
                &format!("three cases against resolution ({})", res.name),
                "levels N between the corners",
                "normalised shape distance",
            ),
            &s,
            &format!("the three cases of figure 11 ({})", res.name),
        )?;
        for (nl, v) in &res.fig11 {
            let mean_order = v[0] < v[2] && v[2] < v[4];
            let strict = v[1] < v[3] && v[2] < v[5];
            let mut row = vec![res.name.clone(), nl.to_string()];
            row.extend(v.iter().map(|&x| f4(x)));
            row.extend([mean_order, strict].map(|ok| if ok { "yes" } else { "NO" }.to_string()));
            rows.push(row);
        }
    }
    let h11: Vec<&str> = ["method", "N"]
        .into_iter()
        .chain(FIG11_CASES.iter().map(|c| c.1))
        .chain(["a < b < c (means)", "max a < min b and mean b < min c"])
        .collect();
    rep.table(&h11, &rows);
    rep.csv("fig11_three_cases.csv", &h11, &rows)?;
    Ok(())
}

/// Figures 12 and 13: matrices with random errors.
fn random_errors(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    let n = inp.n;
    // Figures 12-13.
    rep.para(&format!("Figures 12 and 13: every face gets its own random error (seeded), radius uniform in [0, 5%] of D and a uniform direction: on q only, then on both r and q (independent draws); the 12 x 12 matrices are computed between the perturbed descriptors (N = {n}, static area)."));
    let mut rows = Vec::new();
    for res in inp.results {
        for (label, m, file) in [
            ("error on q", &res.m_rand_one, "fig12_random_one"),
            ("errors on r and q", &res.m_rand_both, "fig13_random_both"),
        ] {
            matrix_figure(
                rep,
                inp,
                m,
                (file, &res.name),
                &format!("{label}, static area, N = {n} ({})", res.name),
                &format!("{label} ({})", res.name),
            )?;
            rows.push(inp.sep_row(&res.name, label, m));
        }
    }
    use SepColumn::*;
    sep_table(
        rep,
        "fig12_13_separation.csv",
        ["method", "errors"],
        &rows,
        &[MaxSame, MinDiff, Ratio, Verdict, RowRatio, RowVerdict],
    )
}

/// Section 4: the single pole under the same errors (figure 17).
fn single_pole(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    let n = inp.n;
    // 4. Single pole.
    rep.heading(
        2,
        "4. Single-pole representation around the nose tip (figures 15-17)",
    );
    rep.para(&format!("Geodesic polar coordinates around the nose tip: {} rays (straightest geodesics at equal angles from the direction towards the eye-corner midpoint) and N = {n} radius levels of step D/N (radius from the same solver's distance field); keys (level, sector). Under the same perturbation grid the nose tip is moved by the same geodesic distances (directions measured from the eye-midpoint direction).", inp.args.set.res.sectors));
    let mut rows = Vec::new();
    for res in inp.results {
        let series = vec![
            radius_series("bipolar (q moved), mean", &res.grid_bip, mean, false),
            radius_series("single pole (nose moved), mean", &res.grid_pol, mean, false),
            radius_series("bipolar, max", &res.grid_bip, max, true),
            radius_series("single pole, max", &res.grid_pol, max, true),
        ];
        plot_figure(
            rep,
            &format!("fig17_pole_vs_bipolar_{}.svg", res.name),
            (
                &format!(
                    "reference-point error: bipolar vs single pole ({})",
                    res.name
                ),
                "error radius (% of D)",
                "distance to the unperturbed descriptor",
            ),
            &series,
            &format!(
                "bipolar vs single pole under the same errors ({})",
                res.name
            ),
        )?;
        for (label, m, file) in [
            ("single pole, no error", &res.m_polar, "matrix_pole"),
            (
                "single pole, random error on the nose tip (fig. 17a)",
                &res.m_rand_nose,
                "fig17a_random_nose",
            ),
            ("bipolar, random error on q (fig. 17b)", &res.m_rand_one, ""),
        ] {
            if !file.is_empty() {
                let title = format!("{label} ({})", res.name);
                matrix_figure(rep, inp, m, (file, &res.name), &title, &title)?;
            }
            rows.push(inp.sep_row(&res.name, label, m));
        }
        let gb: Vec<f64> = res.grid_bip.iter().map(|g| g.2).collect();
        let gp: Vec<f64> = res.grid_pol.iter().map(|g| g.2).collect();
        rep.para(&format!("{}: over the 40 grid perturbations, bipolar mean {} (max {}), single pole mean {} (max {}); the bipolar representation is {} robust here.", res.name, f4(mean(&gb)), f4(max(&gb)), f4(mean(&gp)), f4(max(&gp)), if mean(&gb) < mean(&gp) { "more" } else { "NOT more" }));
    }
    use SepColumn::*;
    sep_table(
        rep,
        "fig17_separation.csv",
        ["method", "matrix"],
        &rows,
        &[MaxSame, MinDiff, Ratio, RowRatio],
    )
}

/// The figure-15 argument.
fn figure15(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    // Figure 15 argument.
    let Figure15 {
        other,
        per_ring,
        global,
        reference,
    } = inp.fig15;
    let (global, reference) = (*global, *reference);
    rep.para(&format!("Figure 15, on `{}` ({}): the polar rings 2, 4 and 6 are each rotated about their own centroid by a random rotation (0.5-1.5 rad). Aligning ring by ring (each ring with its own best rotation, as curve-by-curve inp.methods do) gives distances ~0 for every ring, yet the global keyed distance between the two point sets is {}, {} the distance to another person (`{}`: {}).", inp.faces[inp.test].name, inp.methods[0].used.name(), f4(global), if global > reference { "larger than" } else { "compared with" }, inp.faces[*other].name, f4(reference)));
    rep.table(
        &["ring", "per-ring distance"],
        &per_ring
            .iter()
            .map(|(l, d)| vec![l.to_string(), format!("{d:.2e}")])
            .collect::<Vec<_>>(),
    );
    rep.figure("figure15.svg", "figure 15: rings rotated individually");
    Ok(())
}

/// Section 5: what exactness changes.
fn exactness(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    // 5. Exact vs Dijkstra.
    rep.heading(2, "5. What exactness changes");
    let mut rows = Vec::new();
    for res in inp.results {
        let s = Sep::of(&res.m_static, inp.faces, inp.test);
        let gb: Vec<f64> = res.grid_bip.iter().map(|g| g.2).collect();
        rows.push(vec![
            res.name.clone(),
            format!("{:.3}", mean(&res.d)),
            format!("{:.3}", s.ratio()),
            format!("{:.3}", s.row_ratio()),
            f4(mean(&gb)),
            format!("{:.1}", res.seconds),
        ]);
    }
    rep.table(
        &[
            "method",
            "mean D (cm)",
            "static ratio (matrix)",
            "static ratio (inp.test row)",
            "mean perturbation distance",
            "seconds",
        ],
        &rows,
    );
    if inp.results.len() >= 2 {
        let (a, b) = (&inp.results[0], &inp.results[1]);
        let dd: Vec<f64> =
            a.d.iter()
                .zip(&b.d)
                .map(|(x, y)| (y - x) / x * 100.0)
                .collect();
        rep.para(&format!("D from {} exceeds D from {} by {:.2}% to {:.2}% across inp.faces (edge paths overestimate).", b.name, a.name, min(&dd), max(&dd)));
    }
    Ok(())
}
