//! The study's outputs: `scans.csv`, `pairs.csv`, `ambiguity.csv`, `ratios.csv`, the
//! histograms and `report.md`.

use super::acquisition::Setting;
use super::distances::methods;
use super::variants::VARIANTS;
use super::{quantiles, Args, Described, Relation, ScanPair, ScanResult};
use crate::report::{joined, Report};
use anyhow::{Context, Result};
use facemodel::Face;
use std::path::Path;
use std::time::Instant;

/// Fraction of a descriptor's points whose key is ambiguous (NaN when refused).
fn ambiguous_fraction(d: &Option<bipolar::Descriptor>) -> f64 {
    d.as_ref().map_or(f64::NAN, |d| {
        d.points.iter().filter(|p| p.ambiguous).count() as f64 / d.points.len().max(1) as f64
    })
}

/// Number of a descriptor's points (0 when refused).
fn n_points(d: &Option<bipolar::Descriptor>) -> usize {
    d.as_ref().map_or(0, |d| d.points.len())
}

/// `x` with 4 decimals.
fn f4(x: f64) -> String {
    format!("{x:.4}")
}

/// A finished study: what its outputs are written from.
#[derive(Clone, Copy)]
pub(super) struct Study<'a> {
    pub(super) args: &'a Args,
    pub(super) faces: &'a [Face],
    pub(super) sets: &'a [Setting],
    pub(super) scans: &'a [ScanResult],
    pub(super) pairs: &'a [ScanPair],
    pub(super) out: &'a Path,
}

impl Study<'_> {
    /// Writes every output into `out`; `t0`: the run's start (the report gives the wall time).
    pub(super) fn write(&self, t0: Instant) -> Result<()> {
        let mut rep = Report::new(self.out, "Scan study: the descriptor on range scans")?;
        rep.csv("scans.csv", &self.scans_header(), &self.scan_rows())?;
        self.write_pairs_csv(&rep)?;
        self.report_head(&mut rep);
        self.distances_section(&mut rep)?;
        self.same_face_section(&mut rep);
        self.ambiguity_section(&mut rep)?;
        self.fallbacks_section(&mut rep);
        rep.para(&format!(
            "Run time: {:.0} s wall (release, 2 cores shared). Per-scan details: `scans.csv`.",
            t0.elapsed().as_secs_f64()
        ));
        rep.finish()?;
        Ok(())
    }

    /// The name of scan `i`: its face and setting.
    fn scan_name(&self, i: usize) -> [String; 2] {
        let s = &self.scans[i];
        [
            self.faces[s.face].name.clone(),
            self.sets[s.setting].name.to_string(),
        ]
    }

    /// The columns of `scans.csv` (the variant names have commas: the CSV writer quotes them).
    fn scans_header(&self) -> Vec<String> {
        let lead = [
            "face",
            "setting",
            "status",
            "vertices",
            "mean_edge_mm",
            "D_mm",
        ];
        let offsets = ["lm_offset_r_mm", "lm_offset_q_mm", "lm_offset_nose_mm"];
        let variants = VARIANTS.iter().flat_map(|v| {
            [
                format!("points {}", v.name),
                format!("ambiguous {}", v.name),
            ]
        });
        let tail = ["points_polar", "seconds", "notes"];
        let fixed = lead.iter().chain(&offsets).map(|s| s.to_string());
        fixed
            .chain(variants)
            .chain(tail.map(String::from))
            .collect()
    }

    /// Per scan its status, size, D, landmark offsets, each variant's points and ambiguous
    /// keys, the single pole's points, the time and the notes.
    fn scan_rows(&self) -> Vec<Vec<String>> {
        let row = |(i, s): (usize, &ScanResult)| {
            let mut row = self.scan_name(i).to_vec();
            let d = match &s.status {
                Ok(d) => d,
                Err(e) => {
                    row.push(e.clone());
                    return row;
                }
            };
            row.extend(["ok".into(), d.vertices.to_string()]);
            let [r, q, nose] = d.landmark_offsets_mm;
            row.extend([d.mean_edge_mm, d.d_mm, r, q, nose].map(f4));
            for b in &d.bip {
                row.extend([n_points(b).to_string(), f4(ambiguous_fraction(b))]);
            }
            let seconds = format!("{:.2}", d.seconds);
            row.extend([
                d.polar.points.len().to_string(),
                seconds,
                d.notes.join("; "),
            ]);
            row
        };
        self.scans.iter().enumerate().map(row).collect()
    }

    /// `pairs.csv`: every pair compared with its relation and distances.
    fn write_pairs_csv(&self, rep: &Report) -> Result<()> {
        let lead = ["face_a", "setting_a", "face_b", "setting_b", "relation"];
        let header: Vec<&str> = lead.into_iter().chain(methods(self.args)).collect();
        let rows: Vec<Vec<String>> = self
            .pairs
            .iter()
            .map(|p| {
                let names = [self.scan_name(p.a), self.scan_name(p.b)].concat();
                let d = p.d.iter().map(|x| format!("{x:.6}"));
                names
                    .into_iter()
                    .chain([p.rel.name().into()])
                    .chain(d)
                    .collect()
            })
            .collect();
        rep.csv("pairs.csv", &header, &rows)
    }

    /// What was run, the pairs, the usable scans and the refused descriptors.
    fn report_head(&self, rep: &mut Report) {
        let Study {
            args,
            faces,
            sets,
            scans,
            pairs,
            ..
        } = *self;
        rep.para(&format!(
            "{} faces of `{}`, {} acquisitions each: {}. Scans: `rangescan` with the structured-light \
             artifacts (0.1 % spikes, 50 outliers, grazing dropouts 70-80 degrees, 4 holes of 1-4 mm) \
             and the noise, pitch, pose, quantisation and seed of the setting; cleaned by \
             `scanprep::clean` (defaults, crop 100 mm around the projected nose tip). Reference points: \
             the scanner's projected ground-truth landmarks, snapped to the cleaned surface (at most \
             {} mm away, else the scan is listed as unusable). Exact geodesics; static area at N = {} \
             (levels <= N, `facemodel::static_mask`); single pole with {} sectors; ICP of {} \
             static-area points, symmetric mean of the two directions, RMS in mm. The three pole \
             pairs (and their view matching and search) are `facematch`'s: its poles at the vertices \
             nearest the snapped landmarks, each scan of a pair the probe once, per pair the lesser \
             of the two distances.",
            faces.len(),
            args.set.faces.as_ref().map_or("paper-set".to_string(), |p| p.display().to_string()),
            sets.len(),
            joined(sets, ", ", |s| s.name.to_string()),
            args.landmark_tolerance_mm,
            args.set.res.levels,
            args.set.res.sectors,
            args.icp_points
        ));
        let which = if args.pairs == "all" {
            "every pair of usable scans."
        } else {
            "every two acquisitions of one face, and every two faces within one setting \
             (pairs of other persons across settings are left out)."
        };
        rep.para(&format!(
            "Pairs compared ({} of them, `--pairs {}`): {which}",
            pairs.len(),
            args.pairs
        ));
        let failed: Vec<String> = (0..scans.len())
            .filter_map(|i| {
                scans[i]
                    .status
                    .as_ref()
                    .err()
                    .map(|e| format!("{}: {e}", self.scan_name(i).join(" / ")))
            })
            .collect();
        let unusable = if failed.is_empty() {
            String::new()
        } else {
            format!(" Unusable: {}.", failed.join("; "))
        };
        rep.para(&format!(
            "Usable scans: {} of {}.{unusable}",
            scans.len() - failed.len(),
            scans.len()
        ));
        let notes: Vec<String> = (0..scans.len())
            .filter_map(|i| scans[i].status.as_ref().ok().map(|d| (i, d)))
            .flat_map(|(i, d)| {
                d.notes
                    .iter()
                    .map(move |n| format!("{}: {n}", self.scan_name(i).join(" / ")))
            })
            .collect();
        if !notes.is_empty() {
            rep.para(&format!("Descriptors refused: {}.", notes.join("; ")));
        }
    }

    /// The distances of method `m` over the pairs of relation `rel` that `keep` accepts.
    fn of(&self, m: usize, rel: Relation, keep: &dyn Fn(&ScanPair) -> bool) -> Vec<f64> {
        self.pairs
            .iter()
            .filter(|p| p.rel == rel && keep(p))
            .map(|p| p.d[m])
            .collect()
    }

    /// min(other person) / max(same face) of method `m` over the pairs `keep` accepts.
    fn ratio(&self, m: usize, keep: &dyn Fn(&ScanPair) -> bool) -> f64 {
        quantiles(&self.of(m, Relation::Other, keep)).0
            / quantiles(&self.of(m, Relation::SameFace, keep)).2
    }

    /// The distances section, the histograms and `ratios.csv`: per method the distributions and
    /// the ratios over all pairs, the scans only and the neutral rescans.
    fn distances_section(&self, rep: &mut Report) -> Result<()> {
        let Study {
            faces, sets, scans, ..
        } = *self;
        rep.heading(2, "Distances");
        rep.para("The ratio min(other person) / max(same face) over all pairs; over the scans only (no face mesh); and over the neutral rescans: same-face pairs of the neutral faces scanned at other pitch, noise or pose (no face mesh, no depth quantisation) against the other persons in those settings.");
        let scanned = |i: usize| sets[scans[i].setting].scan;
        let no_mesh = |p: &ScanPair| scanned(p.a).is_some() && scanned(p.b).is_some();
        // The case: two scans of one neutral face at other pitch, noise or pose (no face
        // mesh, no depth quantisation), against the other persons in the same settings.
        let rescan = |p: &ScanPair| {
            [p.a, p.b]
                .iter()
                .all(|&i| scanned(i).is_some_and(|s| s.0.quantisation_mm == 0.0))
                && (p.rel != Relation::SameFace || faces[scans[p.a].face].expression == "neutral")
        };
        let (mut rows, mut ratios) = (Vec::new(), Vec::new());
        for (m, name) in methods(self.args).into_iter().enumerate() {
            let all = |rel| self.of(m, rel, &|_| true);
            let fmt = |v: Vec<f64>| {
                let (lo, med, hi, n) = quantiles(&v);
                format!("{lo:.4} / {med:.4} / {hi:.4} ({n})")
            };
            let r = [
                self.ratio(m, &|_| true),
                self.ratio(m, &no_mesh),
                self.ratio(m, &rescan),
            ];
            ratios.push(std::iter::once(name.to_string()).chain(r.map(f4)).collect());
            let [same, person, other] =
                [Relation::SameFace, Relation::SamePerson, Relation::Other].map(all);
            rows.push(vec![
                name.to_string(),
                fmt(same.clone()),
                fmt(person.clone()),
                fmt(other.clone()),
                format!("**{:.3}**", r[0]),
                format!("{:.3}", r[1]),
                format!("{:.3}", r[2]),
            ]);
            let series: Vec<(String, Vec<f64>)> = [
                (Relation::SameFace, same),
                (Relation::SamePerson, person),
                (Relation::Other, other),
            ]
            .into_iter()
            .map(|(r, v)| (r.name().to_string(), v))
            .filter(|(_, v)| v.iter().any(|x| x.is_finite()))
            .collect();
            if !series.is_empty() {
                let stem = name.replace([' ', '(', ')'], "_").replace("__", "_");
                let file = format!("hist_{}.svg", stem.trim_end_matches('_'));
                let title = format!("{name}: distances between scans");
                viz::histogram(rep.path(&file), &title, "distance", &series, 40)
                    .with_context(|| format!("histogram {file}"))?;
            }
        }
        let header = [
            "method",
            "same face: min / median / max (n)",
            "same person",
            "other person",
            "min(other) / max(same face)",
            "scans only",
            "neutral rescans",
        ];
        rep.table(&header, &rows);
        rep.para("Ratio above 1: every two scans of one face are closer than any two persons (\"scans \
             only\" leaves out the pairs with the mesh itself). Histograms: `hist_*.svg`. All pairs: \
             `pairs.csv`.");
        rep.csv(
            "ratios.csv",
            &[
                "method",
                "ratio_all_pairs",
                "ratio_scans_only",
                "ratio_neutral_rescans",
            ],
            &ratios,
        )
    }

    /// Same-face distance by setting against the reference setting (the first), median over
    /// faces.
    fn same_face_section(&self, rep: &mut Report) {
        let (sets, scans, names) = (self.sets, self.scans, methods(self.args));
        rep.heading(
            2,
            "Same face: each setting against the first, median over faces",
        );
        let rows: Vec<Vec<String>> = (1..sets.len())
            .map(|si| {
                let with_first = |p: &ScanPair| {
                    let (x, y) = (scans[p.a].setting, scans[p.b].setting);
                    (x == 0 && y == si) || (x == si && y == 0)
                };
                let medians = (0..names.len())
                    .map(|m| f4(quantiles(&self.of(m, Relation::SameFace, &with_first)).1));
                std::iter::once(format!("{} vs {}", sets[si].name, sets[0].name))
                    .chain(medians)
                    .collect()
            })
            .collect();
        let header: Vec<&str> = std::iter::once("setting").chain(names).collect();
        rep.table(&header, &rows);
    }

    /// The ambiguous keys per setting, also as `ambiguity.csv`.
    fn ambiguity_section(&self, rep: &mut Report) -> Result<()> {
        rep.heading(2, "Ambiguous keys per setting");
        rep.para("Fraction of descriptor points whose key occurs at two places on the scan (never paired), \
             median and max over the faces; points per descriptor (median).");
        let (mut cells, mut rows) = (Vec::new(), Vec::new());
        for (si, s) in self.sets.iter().enumerate() {
            let ds: Vec<&Described> = self
                .scans
                .iter()
                .filter(|x| x.setting == si)
                .filter_map(|x| x.status.as_ref().ok())
                .collect();
            let q = |f: &dyn Fn(&Described) -> f64| {
                quantiles(&ds.iter().map(|d| f(d)).collect::<Vec<_>>())
            };
            let mut md = vec![
                s.name.to_string(),
                format!("{:.2}", q(&|d| d.mean_edge_mm).1),
            ];
            let mut row = vec![s.name.to_string()];
            for k in 0..VARIANTS.len() {
                let (_, med, max, _) = q(&|d| ambiguous_fraction(&d.bip[k]));
                let pts = q(&|d| n_points(&d.bip[k]) as f64).1;
                md.push(format!(
                    "{:.1} % / {:.1} % ({pts:.0})",
                    100.0 * med,
                    100.0 * max
                ));
                row.extend([f4(med), f4(max)]);
            }
            md.push(format!("{:.0}", q(&|d| d.polar.points.len() as f64).1));
            cells.push(md);
            rows.push(row);
        }
        let variants = VARIANTS
            .iter()
            .map(|v| format!("{}: ambiguous median / max (points)", v.name));
        let header: Vec<String> = ["setting".to_string(), "mean edge mm".to_string()]
            .into_iter()
            .chain(variants)
            .chain(["polar points".to_string()])
            .collect();
        rep.table(&header, &cells);
        let csv_header: Vec<String> = std::iter::once("setting".to_string())
            .chain(VARIANTS.iter().flat_map(|v| {
                [
                    format!("ambiguous median {}", v.name),
                    format!("ambiguous max {}", v.name),
                ]
            }))
            .collect();
        rep.csv("ambiguity.csv", &csv_header, &rows)
    }

    /// The fallbacks the `facematch` comparisons took, counted by kind.
    fn fallbacks_section(&self, rep: &mut Report) {
        let mut counts = std::collections::BTreeMap::<&str, usize>::new();
        for k in self.pairs.iter().flat_map(|p| &p.fallbacks) {
            *counts.entry(k).or_default() += 1;
        }
        rep.heading(2, "Fallbacks of the three-pole-pair comparisons");
        rep.para(&format!(
            "The view-matched and the searched distances compare each pair of scans twice, each scan \
             the probe once (`facematch::compare`); what a comparison substituted \
             (`Comparison::fallback_kinds`), counted over the {} pairs' comparisons{}",
            self.pairs.len(),
            if counts.is_empty() { ": none." } else { ":" }
        ));
        if !counts.is_empty() {
            rep.list(
                &counts
                    .iter()
                    .map(|(k, n)| format!("{k}: {n}"))
                    .collect::<Vec<_>>(),
            );
        }
    }
}
