//! report.md and the CSV tables of `cargo xtask robustness`; every figure is drawn by `viz`.

use super::pole::Figure15;
use super::stats::{max, mean, min, Sep, SepColumn, SEP_COLUMNS};
use super::{Args, MethodResults};
use crate::pipeline::{DescriptorRule, MethodUse, N_DIRS, RADII_PCT};
use crate::report::{f4, joined, labelled_rows, Failures, Report, Series};
use anyhow::Result;
use facemodel::Face;
use std::path::Path;
use std::time::Instant;

/// What the report is written from.
struct Input<'a> {
    args: &'a Args,
    faces: &'a [Face],
    test: usize,
    methods: &'a [MethodUse],
    results: &'a [MethodResults],
    fig15: &'a Figure15,
    labels: Vec<String>,
    n: u32,
}

/// A row of a separation table: the method, the matrix's label and its [`Sep`].
type SepRow = (String, String, Sep);

/// Axis labels of the distance plots.
const DISTANCE: &str = "normalised shape distance";
const LEVELS_N: &str = "levels N between the corners";

/// One line of figures 9 and 17: over the perturbation grid `(radius %, direction, distance)`,
/// the distances at each radius reduced by `agg` (mean or max over the directions).
fn radius_series(label: &str, grid: &[(f64, f64, f64)], agg: fn(&[f64]) -> f64) -> Series {
    let at = |p: f64| {
        grid.iter()
            .filter(|g| g.0 == p)
            .map(|g| g.2)
            .collect::<Vec<_>>()
    };
    Series::new(label, RADII_PCT.iter().map(|&p| (p, agg(&at(p)))).collect())
}

/// The last value of each grid cell.
fn distances(grid: &[(f64, f64, f64)]) -> Vec<f64> {
    grid.iter().map(|g| g.2).collect()
}

impl Input<'_> {
    /// A distance matrix of the report: the heatmap `{stem}_{method}.svg` titled `title`, its
    /// table `{stem}_{method}.csv` (rows and columns labelled by face) and the figure with
    /// `caption`.
    fn matrix(
        &self,
        rep: &mut Report,
        m: &[Vec<f64>],
        stem: &str,
        title: &str,
        caption: &str,
    ) -> Result<()> {
        let fname = format!("{stem}.svg");
        viz::heatmap(rep.path(&fname), title, &self.labels, m, "distance")?;
        rep.matrix_csv(&format!("{stem}.csv"), &self.labels, m)?;
        rep.figure(&fname, caption);
        Ok(())
    }

    /// The separation of the persons by the matrix `m`, with the test face's row.
    fn sep(&self, m: &[Vec<f64>]) -> Sep {
        let persons: Vec<&str> = self.faces.iter().map(|f| f.person.as_str()).collect();
        Sep::of(m, &persons, self.test)
    }

    /// A row of a separation table ([`sep_table`]).
    fn sep_row(&self, method: &str, label: &str, m: &[Vec<f64>]) -> SepRow {
        (method.to_string(), label.to_string(), self.sep(m))
    }
}

/// A separation table (Markdown and the CSV `file`): the two `lead` columns of each row, then
/// the columns `cols` (indices into [`SEP_COLUMNS`]) of its [`Sep`].
fn sep_table(
    rep: &mut Report,
    file: &str,
    lead: [&str; 2],
    rows: &[SepRow],
    cols: &[usize],
) -> Result<()> {
    let cols: Vec<SepColumn> = cols.iter().map(|&c| SEP_COLUMNS[c]).collect();
    let header: Vec<&str> = lead.into_iter().chain(cols.iter().map(|c| c.0)).collect();
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|(a, b, s)| {
            [a.clone(), b.clone()]
                .into_iter()
                .chain(cols.iter().map(|c| (c.1)(s)))
                .collect()
        })
        .collect();
    rep.table_csv(file, &header, &cells)
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
    let labels = faces.iter().map(|f| f.name.clone()).collect();
    let n = args.set.res.levels;
    let inp = Input {
        args,
        faces,
        test,
        methods,
        results,
        fig15,
        labels,
        n,
    };
    let mut rep = Report::new(
        out,
        "The bipolar representation on faces: the paper's sections 4-6",
    )?;
    introduction(&mut rep, &inp, failures);
    reference_distances(&mut rep, &inp)?;
    renders(&mut rep, &inp);
    resolution(&mut rep, &inp)?;
    robustness(&mut rep, &inp)?;
    figure11(&mut rep, &inp)?;
    random_errors(&mut rep, &inp)?;
    single_pole(&mut rep, &inp)?;
    figure15(&mut rep, &inp);
    exactness(&mut rep, &inp);
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
    for m in inp.methods.iter().filter(|m| m.note.is_some()) {
        let (req, used) = (m.requested.name(), m.used.name());
        let note = m.note.as_deref().unwrap_or_default();
        notes.push(format!("Geodesic method **{req}** was requested but {note}; **{used}** was used in its place, and its results are labelled `{used}`."));
    }
    rep.heading(2, "What was available");
    rep.list(&notes);
}

/// Reference distances and point counts per face.
fn reference_distances(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    rep.heading(2, "Reference distances and point counts");
    let rows: Vec<Vec<String>> = (0..inp.faces.len())
        .map(|i| {
            let cells = inp.results.iter().flat_map(|res| {
                let (s, w) = res.n_points[i];
                [format!("{:.3}", res.d[i]), format!("{s} / {w}")]
            });
            std::iter::once(inp.faces[i].name.clone())
                .chain(cells)
                .collect()
        })
        .collect();
    let header: Vec<String> = std::iter::once("face".to_string())
        .chain(inp.results.iter().flat_map(|r| {
            [
                format!("D ({}, cm)", r.name),
                format!("points static / whole ({})", r.name),
            ]
        }))
        .collect();
    rep.table_csv("reference_distances.csv", &header, &rows)
}

/// Section 1: the renders (figures 4, 5).
fn renders(rep: &mut Report, inp: &Input<'_>) {
    rep.heading(
        2,
        "1. Level curves, descriptor points and the static area (figures 4, 5)",
    );
    rep.para("Red: level curves of U_r (right outer eye corner); blue: of U_q (left); yellow: descriptor points (levels up to 2N); green: reference points. The static area (blue tint) is the set of vertices within D of both corners and above the horizontal plane through the nose tip (`docs/experiments.md`); orange points are the descriptor restricted to it.");
    let test = &inp.faces[inp.test].name;
    for res in inp.results {
        let name = &res.name;
        for nl in [5, 10, 30] {
            let caption = format!("{test}: {nl} level curves between the corners ({name})");
            rep.figure(&format!("render_{name}_levels{nl}.svg"), &caption);
        }
        let caption = format!(
            "static area and restricted descriptor, N = {} ({name})",
            inp.n
        );
        rep.figure(&format!("render_{name}_static.svg"), &caption);
    }
}

/// Section 2: distance against resolution (figure 6) and the matrices (figure 7), with the
/// separation table.
fn resolution(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    let (faces, test, n) = (inp.faces, inp.test, inp.n);
    rep.heading(
        2,
        "2. Shape distance against resolution (figure 6) and the 12 x 12 matrix (figure 7)",
    );
    for res in inp.results {
        let name = &res.name;
        let series: Vec<Series> = (0..faces.len())
            .filter(|&j| j != test)
            .map(|j| {
                let points = res
                    .sweep
                    .iter()
                    .map(|(nl, row)| (f64::from(*nl), row[j]))
                    .collect();
                Series::new(&faces[j].name, points).dashed(faces[j].person != faces[test].person)
            })
            .collect();
        let title = format!(
            "{} vs every other face, static area ({name})",
            faces[test].name
        );
        let caption = format!("distance from the test face against resolution; solid: same person, dashed: other persons ({name})");
        rep.plot(
            &format!("fig6_distance_vs_resolution_{name}.svg"),
            (&title, LEVELS_N, DISTANCE),
            &series,
            &caption,
        )?;
        let header: Vec<&str> = std::iter::once("N")
            .chain(faces.iter().map(|f| f.name.as_str()))
            .collect();
        let levels: Vec<String> = res.sweep.iter().map(|(nl, _)| nl.to_string()).collect();
        let rows: Vec<Vec<f64>> = res.sweep.iter().map(|(_, row)| row.clone()).collect();
        rep.csv(
            &format!("fig6_{name}.csv"),
            &header,
            &labelled_rows(&levels, &rows),
        )?;
    }
    let mut sep_rows = Vec::new();
    for res in inp.results {
        for (label, m, file) in [
            ("static area", &res.m_static, "static"),
            ("whole face (levels up to 2N)", &res.m_whole, "whole"),
        ] {
            let title = format!("pairwise distances, {label}, N = {n} ({})", res.name);
            let caption = format!("12 x 12 matrix, {label} ({})", res.name);
            inp.matrix(
                rep,
                m,
                &format!("fig7_matrix_{file}_{}", res.name),
                &title,
                &caption,
            )?;
            sep_rows.push(inp.sep_row(&res.name, label, m));
        }
    }
    rep.para("Separation: the largest distance between two faces of the same person, the smallest between faces of different persons, and their ratio (> 1 means every same-person pair is closer than every different-person pair). 'Test row' restricts this to the pairs involving the neutral test face, which is what the paper's figure 6 shows.");
    sep_table(
        rep,
        "separation.csv",
        ["method", "descriptor"],
        &sep_rows,
        &[0, 1, 2, 3, 4, 5, 6, 7],
    )
}

/// Section 3: the perturbation grid (figures 9, 10).
fn robustness(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    rep.heading(2, "3. Robustness to reference-point errors (figures 9-13)");
    rep.para(&format!("The left outer eye corner q of `{}` is moved along a straightest geodesic of length {}% of D, leaving at angle theta from the direction towards r (counter-clockwise about the outward normal); its distance field is recomputed from the moved surface point, D is recomputed, and the static descriptor at N = {} is compared with the original one.", inp.faces[inp.test].name, joined(RADII_PCT, ", ", |p| format!("{p}")), inp.n));
    for res in inp.results {
        let name = &res.name;
        rep.para(&format!("{name}: {} of {} corner walks and {} nose-tip walks met the mesh boundary (the eye opening) before the full radius; those cells are left out (blank in the plots, NaN in the CSV).", res.truncated.0, RADII_PCT.len() * N_DIRS, res.truncated.1));
        let by_direction: Vec<Series> = RADII_PCT
            .iter()
            .map(|&p| {
                let cells = res.grid_bip.iter().filter(|g| g.0 == p);
                Series::new(
                    format!("radius {p}% of D"),
                    cells.map(|g| (g.1.to_degrees(), g.2)).collect(),
                )
            })
            .collect();
        let by_radius = vec![
            radius_series("mean over directions", &res.grid_bip, mean),
            radius_series("max over directions", &res.grid_bip, max).dashed(true),
        ];
        for (stem, by, x_label, series, caption) in [
            (
                "fig9_radius",
                "radius",
                "radius (% of D)",
                by_radius,
                "distance against the error radius",
            ),
            (
                "fig10_grid",
                "direction",
                "direction theta (degrees from r)",
                by_direction,
                "distance over the radius x direction grid",
            ),
        ] {
            let title = format!("perturbed vs original, by {by} ({name})");
            rep.plot(
                &format!("{stem}_{name}.svg"),
                (&title, x_label, DISTANCE),
                &series,
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
        let header = [
            "radius_pct",
            "theta_deg",
            "bipolar_distance",
            "single_pole_distance",
        ];
        rep.csv(&format!("fig9_10_grid_{name}.csv"), &header, &rows)?;
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
    rep.para("Figure 11, the paper's three cases against resolution: (a) perturbed vs original (the 40 grid perturbations), (b) the test face vs the same person's other expressions, (c) vs other persons. The ordering a < b < c is checked on the means and, more strictly, as max(a) < min(b) and min(b)... (strict: max a < min b, and mean b < min c).");
    let mut rows = Vec::new();
    for res in inp.results {
        let series: Vec<Series> = FIG11_CASES
            .iter()
            .enumerate()
            .map(|(k, &(name, _, dashed))| {
                let points = res
                    .fig11
                    .iter()
                    .map(|(nl, v)| (f64::from(*nl), v[k]))
                    .collect();
                Series::new(name, points).dashed(dashed)
            })
            .collect();
        let title = format!("three cases against resolution ({})", res.name);
        let caption = format!("the three cases of figure 11 ({})", res.name);
        rep.plot(
            &format!("fig11_three_cases_{}.svg", res.name),
            (&title, LEVELS_N, DISTANCE),
            &series,
            &caption,
        )?;
        for (nl, v) in &res.fig11 {
            let checks = [v[0] < v[2] && v[2] < v[4], v[1] < v[3] && v[2] < v[5]];
            let mut row = vec![res.name.clone(), nl.to_string()];
            row.extend(v.iter().map(|&x| f4(x)));
            row.extend(checks.map(|ok| if ok { "yes" } else { "NO" }.to_string()));
            rows.push(row);
        }
    }
    let header: Vec<&str> = ["method", "N"]
        .into_iter()
        .chain(FIG11_CASES.iter().map(|c| c.1))
        .chain(["a < b < c (means)", "max a < min b and mean b < min c"])
        .collect();
    rep.table_csv("fig11_three_cases.csv", &header, &rows)
}

/// Figures 12 and 13: matrices with random errors.
fn random_errors(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    let n = inp.n;
    rep.para(&format!("Figures 12 and 13: every face gets its own random error (seeded), radius uniform in [0, 5%] of D and a uniform direction: on q only, then on both r and q (independent draws); the 12 x 12 matrices are computed between the perturbed descriptors (N = {n}, static area)."));
    let mut rows = Vec::new();
    for res in inp.results {
        for (label, m, file) in [
            ("error on q", &res.m_rand_one, "fig12_random_one"),
            ("errors on r and q", &res.m_rand_both, "fig13_random_both"),
        ] {
            let title = format!("{label}, static area, N = {n} ({})", res.name);
            let caption = format!("{label} ({})", res.name);
            inp.matrix(rep, m, &format!("{file}_{}", res.name), &title, &caption)?;
            rows.push(inp.sep_row(&res.name, label, m));
        }
    }
    sep_table(
        rep,
        "fig12_13_separation.csv",
        ["method", "errors"],
        &rows,
        &[0, 1, 2, 3, 6, 7],
    )
}

/// Section 4: the single pole under the same errors (figure 17).
fn single_pole(rep: &mut Report, inp: &Input<'_>) -> Result<()> {
    rep.heading(
        2,
        "4. Single-pole representation around the nose tip (figures 15-17)",
    );
    rep.para(&format!("Geodesic polar coordinates around the nose tip: {} rays (straightest geodesics at equal angles from the direction towards the eye-corner midpoint) and N = {} radius levels of step D/N (radius from the same solver's distance field); keys (level, sector). Under the same perturbation grid the nose tip is moved by the same geodesic distances (directions measured from the eye-midpoint direction).", inp.args.set.res.sectors, inp.n));
    let mut rows = Vec::new();
    for res in inp.results {
        let name = &res.name;
        let series = vec![
            radius_series("bipolar (q moved), mean", &res.grid_bip, mean),
            radius_series("single pole (nose moved), mean", &res.grid_pol, mean),
            radius_series("bipolar, max", &res.grid_bip, max).dashed(true),
            radius_series("single pole, max", &res.grid_pol, max).dashed(true),
        ];
        let title = format!("reference-point error: bipolar vs single pole ({name})");
        let caption = format!("bipolar vs single pole under the same errors ({name})");
        let labels = (
            title.as_str(),
            "error radius (% of D)",
            "distance to the unperturbed descriptor",
        );
        rep.plot(
            &format!("fig17_pole_vs_bipolar_{name}.svg"),
            labels,
            &series,
            &caption,
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
                let title = format!("{label} ({name})");
                inp.matrix(rep, m, &format!("{file}_{name}"), &title, &title)?;
            }
            rows.push(inp.sep_row(name, label, m));
        }
        let (gb, gp) = (distances(&res.grid_bip), distances(&res.grid_pol));
        let more = if mean(&gb) < mean(&gp) {
            "more"
        } else {
            "NOT more"
        };
        rep.para(&format!("{name}: over the 40 grid perturbations, bipolar mean {} (max {}), single pole mean {} (max {}); the bipolar representation is {more} robust here.", f4(mean(&gb)), f4(max(&gb)), f4(mean(&gp)), f4(max(&gp))));
    }
    sep_table(
        rep,
        "fig17_separation.csv",
        ["method", "matrix"],
        &rows,
        &[0, 1, 2, 6],
    )
}

/// The figure-15 argument.
fn figure15(rep: &mut Report, inp: &Input<'_>) {
    let f = inp.fig15;
    let larger = if f.global > f.reference {
        "larger than"
    } else {
        "compared with"
    };
    rep.para(&format!("Figure 15, on `{}` ({}): the polar rings 2, 4 and 6 are each rotated about their own centroid by a random rotation (0.5-1.5 rad). Aligning ring by ring (each ring with its own best rotation, as curve-by-curve methods do) gives distances ~0 for every ring, yet the global keyed distance between the two point sets is {}, {larger} the distance to another person (`{}`: {}).", inp.faces[inp.test].name, inp.methods[0].used.name(), f4(f.global), inp.faces[f.other].name, f4(f.reference)));
    let rows: Vec<Vec<String>> = f
        .per_ring
        .iter()
        .map(|(l, d)| vec![l.to_string(), format!("{d:.2e}")])
        .collect();
    rep.table(&["ring", "per-ring distance"], &rows);
    rep.figure("figure15.svg", "figure 15: rings rotated individually");
}

/// Section 5: what exactness changes.
fn exactness(rep: &mut Report, inp: &Input<'_>) {
    rep.heading(2, "5. What exactness changes");
    let rows: Vec<Vec<String>> = inp
        .results
        .iter()
        .map(|res| {
            let s = inp.sep(&res.m_static);
            let (d, ratio, row) = (mean(&res.d), s.ratio(), s.row_ratio());
            let grid = f4(mean(&distances(&res.grid_bip)));
            vec![
                res.name.clone(),
                format!("{d:.3}"),
                format!("{ratio:.3}"),
                format!("{row:.3}"),
                grid,
                format!("{:.1}", res.seconds),
            ]
        })
        .collect();
    let header = [
        "method",
        "mean D (cm)",
        "static ratio (matrix)",
        "static ratio (test row)",
        "mean perturbation distance",
        "seconds",
    ];
    rep.table(&header, &rows);
    if let [a, b, ..] = inp.results {
        let dd: Vec<f64> =
            a.d.iter()
                .zip(&b.d)
                .map(|(x, y)| (y - x) / x * 100.0)
                .collect();
        rep.para(&format!("D from {} exceeds D from {} by {:.2}% to {:.2}% across faces (edge paths overestimate).", b.name, a.name, min(&dd), max(&dd)));
    }
}
