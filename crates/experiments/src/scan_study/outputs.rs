//! The study's outputs: `scans.csv`, `pairs.csv`, `ambiguity.csv`, `ratios.csv`, the
//! histograms and `report.md`.

use super::acquisition::Setting;
use super::distances::methods;
use super::variants::VARIANTS;
use super::{quantiles, Args, Described, Relation, ScanPair, ScanResult};
use crate::report::{joined, write_csv};
use anyhow::{Context, Result};
use facemodel::Face;
use std::fmt::Write as _;
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

/// A method's separation: its name and min(other person) / max(same face) over all pairs, the
/// scans only and the neutral rescans.
type Ratio = (String, f64, f64, f64);

impl Study<'_> {
    /// Writes every output into `out`; `t0`: the run's start (the report gives the wall time).
    pub(super) fn write(&self, t0: Instant) -> Result<()> {
        self.write_scans_csv()?;
        self.write_pairs_csv()?;
        let mut md = self.report_head();
        let ratios = self.distances_section(&mut md)?;
        self.same_face_section(&mut md);
        self.ambiguity_section(&mut md)?;
        self.fallbacks_section(&mut md);
        write_ratios_csv(self.out, &ratios)?;
        let _ = writeln!(
            md,
            "\nRun time: {:.0} s wall (release, 2 cores shared). Per-scan details: `scans.csv`.",
            t0.elapsed().as_secs_f64()
        );
        std::fs::write(self.out.join("report.md"), md)?;
        Ok(())
    }

    /// `scans.csv`: per scan its status, size, D, landmark offsets, each variant's points and
    /// ambiguous keys, the single pole's points, the time and the notes.
    fn write_scans_csv(&self) -> Result<()> {
        let Study {
            faces,
            sets,
            scans,
            out,
            ..
        } = *self;
        // Per-scan table (the variant names have commas: `write_csv` quotes them).
        let mut header: Vec<String> = [
            "face",
            "setting",
            "status",
            "vertices",
            "mean_edge_mm",
            "D_mm",
            "lm_offset_r_mm",
            "lm_offset_q_mm",
            "lm_offset_nose_mm",
        ]
        .map(String::from)
        .to_vec();
        for v in &VARIANTS {
            header.extend([
                format!("points {}", v.name),
                format!("ambiguous {}", v.name),
            ]);
        }
        header.extend(["points_polar", "seconds", "notes"].map(String::from));
        let mut rows = Vec::new();
        for s in scans {
            let mut row = vec![faces[s.face].name.clone(), sets[s.setting].name.to_string()];
            match &s.status {
                Ok(d) => {
                    row.push("ok".into());
                    row.push(d.vertices.to_string());
                    row.extend(
                        [
                            d.mean_edge_mm,
                            d.d_mm,
                            d.landmark_offsets_mm[0],
                            d.landmark_offsets_mm[1],
                            d.landmark_offsets_mm[2],
                        ]
                        .map(|x| format!("{x:.4}")),
                    );
                    for b in &d.bip {
                        row.extend([
                            n_points(b).to_string(),
                            format!("{:.4}", ambiguous_fraction(b)),
                        ]);
                    }
                    row.extend([
                        d.polar.points.len().to_string(),
                        format!("{:.2}", d.seconds),
                        d.notes.join("; "),
                    ]);
                }
                Err(e) => row.push(e.clone()),
            }
            rows.push(row);
        }
        write_csv(
            &out.join("scans.csv"),
            &header.iter().map(String::as_str).collect::<Vec<_>>(),
            &rows,
        )?;
        Ok(())
    }

    /// `pairs.csv`: every pair compared with its relation and distances.
    fn write_pairs_csv(&self) -> Result<()> {
        let Study {
            args,
            faces,
            sets,
            scans,
            pairs,
            out,
        } = *self;
        let mut header: Vec<String> = ["face_a", "setting_a", "face_b", "setting_b", "relation"]
            .map(String::from)
            .to_vec();
        header.extend(methods(args).into_iter().map(String::from));
        let rows: Vec<Vec<String>> = pairs
            .iter()
            .map(|p| {
                let (a, b) = (&scans[p.a], &scans[p.b]);
                let mut row = vec![
                    faces[a.face].name.clone(),
                    sets[a.setting].name.to_string(),
                    faces[b.face].name.clone(),
                    sets[b.setting].name.to_string(),
                    p.rel.name().to_string(),
                ];
                row.extend(p.d.iter().map(|x| format!("{x:.6}")));
                row
            })
            .collect();
        write_csv(
            &out.join("pairs.csv"),
            &header.iter().map(String::as_str).collect::<Vec<_>>(),
            &rows,
        )?;

        Ok(())
    }

    /// The report's title, what was run, the usable scans and the refused descriptors.
    fn report_head(&self) -> String {
        let Study {
            args,
            faces,
            sets,
            scans,
            pairs,
            ..
        } = *self;
        let mut md = String::new();
        let _ = writeln!(md, "# Scan study: the descriptor on range scans\n");
        let _ = writeln!(
        md,
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
         of the two distances.\n",
        faces.len(),
        args.set
            .faces
            .as_ref()
            .map_or("paper-set".to_string(), |p| p.display().to_string()),
        sets.len(),
        joined(sets, ", ", |s| s.name.to_string()),
        args.landmark_tolerance_mm,
        args.set.res.levels,
        args.set.res.sectors,
        args.icp_points
    );
        let _ = writeln!(
            md,
            "Pairs compared ({} of them, `--pairs {}`): {}\n",
            pairs.len(),
            args.pairs,
            if args.pairs == "all" {
                "every pair of usable scans."
            } else {
                "every two acquisitions of one face, and every two faces within one setting \
             (pairs of other persons across settings are left out)."
            }
        );
        let failed: Vec<String> = scans
            .iter()
            .filter_map(|s| {
                s.status
                    .as_ref()
                    .err()
                    .map(|e| format!("{} / {}: {e}", faces[s.face].name, sets[s.setting].name))
            })
            .collect();
        let _ = writeln!(
            md,
            "Usable scans: {} of {}.{}\n",
            scans.len() - failed.len(),
            scans.len(),
            if failed.is_empty() {
                String::new()
            } else {
                format!(" Unusable: {}.", failed.join("; "))
            }
        );
        let notes: Vec<String> = scans
            .iter()
            .filter_map(|s| s.status.as_ref().ok().map(|d| (s, d)))
            .flat_map(|(s, d)| {
                d.notes
                    .iter()
                    .map(move |n| format!("{} / {}: {n}", faces[s.face].name, sets[s.setting].name))
            })
            .collect();
        if !notes.is_empty() {
            let _ = writeln!(md, "Descriptors refused: {}.\n", notes.join("; "));
        }

        md
    }

    /// The distances section (and the histograms): per method the distributions and the
    /// ratios, which it returns.
    fn distances_section(&self, md: &mut String) -> Result<Vec<Ratio>> {
        let Study {
            args,
            faces,
            sets,
            scans,
            pairs,
            out,
        } = *self;
        // Distances.
        let _ = writeln!(md, "## Distances\n");
        let _ = writeln!(
        md,
        "The ratio min(other person) / max(same face) over all pairs; over the scans only (no face mesh); and over the neutral rescans: same-face pairs of the neutral faces scanned at other pitch, noise or pose (no face mesh, no depth quantisation) against the other persons in those settings.\n"
    );
        let _ = writeln!(
        md,
        "| method | same face: min / median / max (n) | same person | other person | min(other) / max(same face) | scans only | neutral rescans |"
    );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|");
        let is_mesh = |p: &ScanPair| {
            sets[scans[p.a].setting].scan.is_none() || sets[scans[p.b].setting].scan.is_none()
        };
        // The case: two scans of one neutral face at other pitch, noise or pose (no face
        // mesh, no depth quantisation), against the other persons in the same settings.
        let rescan = |p: &ScanPair| {
            [p.a, p.b].iter().all(|&i| {
                sets[scans[i].setting]
                    .scan
                    .is_some_and(|s| s.quant_mm.is_none())
            }) && (p.rel != Relation::SameFace || faces[scans[p.a].face].expression == "neutral")
        };
        let mut ratios = Vec::new();
        for (m, name) in methods(args).iter().enumerate() {
            let subset = |rel: Relation, keep: &dyn Fn(&ScanPair) -> bool| -> Vec<f64> {
                pairs
                    .iter()
                    .filter(|p| p.rel == rel && keep(p))
                    .map(|p| p.d[m])
                    .collect()
            };
            let of = |rel: Relation, scans_only: bool| -> Vec<f64> {
                subset(rel, &|p| !(scans_only && is_mesh(p)))
            };
            let fmt = |v: &[f64]| {
                let (lo, med, hi, n) = quantiles(v);
                format!("{lo:.4} / {med:.4} / {hi:.4} ({n})")
            };
            let ratio = |scans_only: bool| {
                let (_, _, same_max, _) = quantiles(&of(Relation::SameFace, scans_only));
                let (other_min, _, _, _) = quantiles(&of(Relation::Other, scans_only));
                other_min / same_max
            };
            let (r_all, r_scans) = (ratio(false), ratio(true));
            let r_rescans = {
                let (_, _, same_max, _) = quantiles(&subset(Relation::SameFace, &rescan));
                let (other_min, _, _, _) = quantiles(&subset(Relation::Other, &rescan));
                other_min / same_max
            };
            ratios.push((name.to_string(), r_all, r_scans, r_rescans));
            let _ = writeln!(
                md,
                "| {name} | {} | {} | {} | **{r_all:.3}** | {r_scans:.3} | {r_rescans:.3} |",
                fmt(&of(Relation::SameFace, false)),
                fmt(&of(Relation::SamePerson, false)),
                fmt(&of(Relation::Other, false)),
            );
            let series: Vec<(String, Vec<f64>)> =
                [Relation::SameFace, Relation::SamePerson, Relation::Other]
                    .iter()
                    .map(|&r| (r.name().to_string(), of(r, false)))
                    .filter(|(_, v)| v.iter().any(|x| x.is_finite()))
                    .collect();
            if !series.is_empty() {
                let file = format!(
                    "hist_{}.svg",
                    name.replace([' ', '(', ')'], "_")
                        .replace("__", "_")
                        .trim_end_matches('_')
                );
                viz::histogram(
                    out.join(&file),
                    &format!("{name}: distances between scans"),
                    "distance",
                    &series,
                    40,
                )
                .with_context(|| format!("histogram {file}"))?;
            }
        }
        let _ = writeln!(
        md,
        "\nRatio above 1: every two scans of one face are closer than any two persons (\"scans \
         only\" leaves out the pairs with the mesh itself). Histograms: `hist_*.svg`. All pairs: \
         `pairs.csv`.\n"
    );

        Ok(ratios)
    }

    /// Same-face distance by setting against the reference setting.
    fn same_face_section(&self, md: &mut String) {
        let Study {
            args,
            sets,
            scans,
            pairs,
            ..
        } = *self;
        // Same-face distance by setting pair against the reference setting.
        let _ = writeln!(
            md,
            "## Same face: each setting against the first, median over faces\n"
        );
        let _ = writeln!(md, "| setting | {} |", methods(args).join(" | "));
        let _ = writeln!(md, "|---|{}", "---|".repeat(methods(args).len()));
        for (si, s) in sets.iter().enumerate().skip(1) {
            let row: Vec<String> = (0..methods(args).len())
                .map(|m| {
                    let v: Vec<f64> = pairs
                        .iter()
                        .filter(|p| {
                            p.rel == Relation::SameFace && {
                                let (x, y) = (scans[p.a].setting, scans[p.b].setting);
                                (x == 0 && y == si) || (x == si && y == 0)
                            }
                        })
                        .map(|p| p.d[m])
                        .collect();
                    format!("{:.4}", quantiles(&v).1)
                })
                .collect();
            let _ = writeln!(
                md,
                "| {} vs {} | {} |",
                s.name,
                sets[0].name,
                row.join(" | ")
            );
        }
    }

    /// The ambiguous keys per setting, also as `ambiguity.csv`.
    fn ambiguity_section(&self, md: &mut String) -> Result<()> {
        let Study {
            sets, scans, out, ..
        } = *self;
        // Ambiguity per setting.
        let _ = writeln!(md, "\n## Ambiguous keys per setting\n");
        let _ = writeln!(
        md,
        "Fraction of descriptor points whose key occurs at two places on the scan (never paired), \
         median and max over the faces; points per descriptor (median).\n"
    );
        let _ = writeln!(
            md,
            "| setting | mean edge mm | {} | polar points |",
            joined(&VARIANTS, " | ", |v| format!(
                "{}: ambiguous median / max (points)",
                v.name
            ))
        );
        let _ = writeln!(md, "|---|---|{}---|", "---|".repeat(VARIANTS.len()));
        let mut header = vec!["setting".to_string()];
        for v in &VARIANTS {
            header.extend([
                format!("ambiguous median {}", v.name),
                format!("ambiguous max {}", v.name),
            ]);
        }
        let mut rows = Vec::new();
        for (si, s) in sets.iter().enumerate() {
            let ds: Vec<&Described> = scans
                .iter()
                .filter(|x| x.setting == si)
                .filter_map(|x| x.status.as_ref().ok())
                .collect();
            let col =
                |f: &dyn Fn(&Described) -> f64| -> Vec<f64> { ds.iter().map(|d| f(d)).collect() };
            let (_, edge, _, _) = quantiles(&col(&|d| d.mean_edge_mm));
            let (_, pp, _, _) = quantiles(&col(&|d| d.polar.points.len() as f64));
            let mut cells = Vec::new();
            let mut row = vec![s.name.to_string()];
            for k in 0..VARIANTS.len() {
                let (_, med, max, _) = quantiles(&col(&|d| ambiguous_fraction(&d.bip[k])));
                let (_, pts, _, _) = quantiles(&col(&|d| n_points(&d.bip[k]) as f64));
                cells.push(format!(
                    "{:.1} % / {:.1} % ({pts:.0})",
                    100.0 * med,
                    100.0 * max
                ));
                row.extend([format!("{med:.4}"), format!("{max:.4}")]);
            }
            rows.push(row);
            let _ = writeln!(
                md,
                "| {} | {edge:.2} | {} | {pp:.0} |",
                s.name,
                cells.join(" | ")
            );
        }
        write_csv(
            &out.join("ambiguity.csv"),
            &header.iter().map(String::as_str).collect::<Vec<_>>(),
            &rows,
        )?;
        Ok(())
    }

    /// The fallbacks the `facematch` comparisons took, counted by kind.
    fn fallbacks_section(&self, md: &mut String) {
        let mut counts: Vec<(String, usize)> = Vec::new();
        for k in self.pairs.iter().flat_map(|p| &p.fallbacks) {
            match counts.iter_mut().find(|(c, _)| c == k) {
                Some((_, n)) => *n += 1,
                None => counts.push((k.clone(), 1)),
            }
        }
        counts.sort();
        let _ = writeln!(md, "\n## Fallbacks of the three-pole-pair comparisons\n");
        let _ = writeln!(
            md,
            "The view-matched and the searched distances compare each pair of scans twice, each scan \
             the probe once (`facematch::compare`); what a comparison substituted \
             (`Comparison::fallback_kinds`), counted over the {} pairs' comparisons{}",
            self.pairs.len(),
            if counts.is_empty() { ": none." } else { ":\n" }
        );
        for (k, n) in &counts {
            let _ = writeln!(md, "- {k}: {n}");
        }
    }
}

/// `ratios.csv`: each method's three ratios.
fn write_ratios_csv(out: &Path, ratios: &[Ratio]) -> Result<()> {
    let rows: Vec<Vec<String>> = ratios
        .iter()
        .map(|(n, a, s, r)| {
            vec![
                n.to_string(),
                format!("{a:.4}"),
                format!("{s:.4}"),
                format!("{r:.4}"),
            ]
        })
        .collect();
    write_csv(
        &out.join("ratios.csv"),
        &[
            "method",
            "ratio_all_pairs",
            "ratio_scans_only",
            "ratio_neutral_rescans",
        ],
        &rows,
    )?;
    Ok(())
}
