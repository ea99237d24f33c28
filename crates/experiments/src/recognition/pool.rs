//! `cargo xtask recognition --seeds S1,S2,...`: the benchmark run once per seed (each into
//! `OUT/seed-S`), then its figures pooled probe by probe over the seeds.
//!
//! One seed's rank-1 over 100 probes has a standard error of about 3 points, as large as the
//! differences the benchmark is read for; pooling the seeds' probes narrows it. The pooled
//! rank-1 is the share of all the seeds' probes identified at rank 1, with a Wilson 95 %
//! interval; the paired comparison adds up each seed's probes that only one of two scores
//! identifies (the probes of one seed are the same for every score).

use super::metrics::{paired_table, Metrics};
use super::Args;
use crate::report::{Report, Series};
use anyhow::{bail, Context, Result};
use facematch::metrics::{discordant, mcnemar_exact, wilson95};
use std::path::{Path, PathBuf};

/// The folder of one seed's run inside the pooled run's folder.
pub(super) fn seed_dir(out: &Path, seed: u64) -> PathBuf {
    out.join(format!("seed-{seed}"))
}

/// Runs the benchmark for every seed of `args.seeds` (unless `--pool-only`) and pools them.
pub(super) fn run(args: Args) -> Result<()> {
    let out = args.io.out.out_dir(if args.scans {
        "recognition-scans"
    } else {
        "recognition"
    });
    let seeds = args.seeds.clone();
    let mut distinct = seeds.clone();
    distinct.sort_unstable();
    distinct.dedup();
    if distinct.len() != seeds.len() {
        bail!("--seeds {seeds:?}: a seed is named twice");
    }
    if !args.pool_only {
        for &seed in &seeds {
            let mut one = args.clone();
            one.seeds.clear();
            one.seed = seed;
            one.io.out.out = Some(seed_dir(&out, seed));
            eprintln!("== seed {seed}");
            super::run(one).with_context(|| format!("the run of seed {seed}"))?;
        }
    }
    let runs = seeds
        .iter()
        .map(|&s| read_run(&seed_dir(&out, s)).map(|r| (s, r)))
        .collect::<Result<Vec<_>>>()?;
    write_pooled(&out, &runs)?;
    println!("{}", out.display());
    Ok(())
}

/// What pooling reads of one score of one run's `summary.json`.
#[derive(Debug, Clone, serde::Deserialize)]
pub(super) struct RunRow {
    pub descriptor: String,
    pub landmarks: String,
    pub rank1: f64,
    /// `null` in the file when the EER could not be computed.
    pub eer: Option<f64>,
    pub identified: Vec<bool>,
}

#[derive(Debug, serde::Deserialize)]
struct Summary {
    results: Vec<RunRow>,
}

/// The scores of one run (its `summary.json`), or an error naming the folder.
pub(super) fn read_run(dir: &Path) -> Result<Vec<RunRow>> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).with_context(|| {
        format!(
            "reading {} (run that seed, or leave out --pool-only)",
            path.display()
        )
    })?;
    let s: Summary = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: not a summary with per-probe results (written by an older run?)",
            path.display()
        )
    })?;
    for r in &s.results {
        let n = r.identified.len();
        let hits = r.identified.iter().filter(|&&i| i).count();
        if n == 0 || (hits as f64 / n as f64 - r.rank1).abs() > 1e-9 {
            bail!(
                "{}: {} ({}) has {hits} of {n} probes identified but rank-1 {}",
                path.display(),
                r.descriptor,
                r.landmarks,
                r.rank1
            );
        }
    }
    Ok(s.results)
}

/// The row of one score and landmark set in a run.
fn same_score<'a>(rows: &'a [RunRow], descriptor: &str, landmarks: &str) -> Option<&'a RunRow> {
    rows.iter()
        .find(|r| r.descriptor == descriptor && r.landmarks == landmarks)
}

/// The pooled scores: per (score, landmark set) in the first run's order, the concatenated
/// per-probe identifications and the mean EER. Every run must have the same scores.
pub(super) fn pooled(runs: &[(u64, Vec<RunRow>)]) -> Result<Vec<Metrics>> {
    let Some((_, first)) = runs.first() else {
        bail!("no runs to pool");
    };
    first
        .iter()
        .map(|row| {
            let mut identified = Vec::new();
            let mut eer = 0.0;
            for (seed, rows) in runs {
                let Some(r) = same_score(rows, &row.descriptor, &row.landmarks) else {
                    bail!(
                        "seed {seed} has no {} ({}) result to pool",
                        row.descriptor,
                        row.landmarks
                    );
                };
                identified.extend(&r.identified);
                eer += r.eer.unwrap_or(f64::NAN);
            }
            let hits = identified.iter().filter(|&&i| i).count();
            Ok(Metrics {
                descriptor: row.descriptor.clone(),
                landmarks: row.landmarks.clone(),
                rank1: hits as f64 / identified.len() as f64,
                eer: eer / runs.len() as f64,
                genuine_mean: f64::NAN,
                impostor_mean: f64::NAN,
                failures: 0,
                ms_per_comparison: f64::NAN,
                ms_per_description: f64::NAN,
                roc: Vec::new(),
                identified,
            })
        })
        .collect()
}

fn write_pooled(out: &Path, runs: &[(u64, Vec<RunRow>)]) -> Result<()> {
    let pool = pooled(runs)?;
    let mut rep = Report::new(out, "Recognition benchmark pooled over seeds")?;
    let seeds: Vec<String> = runs.iter().map(|(s, _)| s.to_string()).collect();
    let probes: Vec<usize> = runs
        .iter()
        .map(|(_, rows)| rows.first().map_or(0, |r| r.identified.len()))
        .collect();
    rep.para(&format!(
        "Seeds {} (each run's report in `seed-S/`), {} probes in all ({}). Rank-1 per seed with its EER in brackets; pooled: the share of all the seeds' probes identified at rank 1, its Wilson 95 % interval, and the mean of the seeds' EERs.",
        seeds.join(", "),
        probes.iter().sum::<usize>(),
        probes.iter().map(usize::to_string).collect::<Vec<_>>().join(" + "),
    ));
    let mut rows = Vec::new();
    let mut csv = Vec::new();
    for m in &pool {
        let hits = m.identified.iter().filter(|&&i| i).count();
        let (lo, hi) = wilson95(hits, m.identified.len());
        let per_seed: Vec<&RunRow> = runs
            .iter()
            .filter_map(|(_, rows)| same_score(rows, &m.descriptor, &m.landmarks))
            .collect();
        let mut row = vec![m.descriptor.clone(), m.landmarks.clone()];
        row.extend(per_seed.iter().map(|r| {
            format!(
                "{:.3} ({})",
                r.rank1,
                r.eer.map_or("-".into(), |e| format!("{e:.3}"))
            )
        }));
        row.push(format!("**{:.3}**", m.rank1));
        row.push(format!("{lo:.3} - {hi:.3}"));
        row.push(format!("{:.3}", m.eer));
        rows.push(row);
        let mut c = vec![m.descriptor.clone(), m.landmarks.clone()];
        c.extend(per_seed.iter().map(|r| format!("{:.6}", r.rank1)));
        c.extend([
            hits.to_string(),
            m.identified.len().to_string(),
            format!("{:.6}", m.rank1),
            format!("{lo:.6}"),
            format!("{hi:.6}"),
            format!("{:.6}", m.eer),
        ]);
        csv.push(c);
    }
    let seed_cols: Vec<String> = seeds.iter().map(|s| format!("seed {s}")).collect();
    let header: Vec<&str> = ["score", "landmarks"]
        .into_iter()
        .chain(seed_cols.iter().map(String::as_str))
        .chain(["pooled rank-1", "95 % interval", "mean EER"])
        .collect();
    rep.table(&header, &rows);
    let seed_rank: Vec<String> = seeds.iter().map(|s| format!("rank-1 seed {s}")).collect();
    let csv_header: Vec<&str> = ["score", "landmarks"]
        .into_iter()
        .chain(seed_rank.iter().map(String::as_str))
        .chain([
            "identified",
            "probes",
            "pooled rank-1",
            "interval low",
            "interval high",
            "mean EER",
        ])
        .collect();
    rep.csv("pooled.csv", &csv_header, &csv)?;
    paired_table(&mut rep, &pool);
    // Rank-1 per seed, one line per score and landmark set.
    let series: Vec<Series> = pool
        .iter()
        .map(|m| {
            let mut p: Vec<(f64, f64)> = runs
                .iter()
                .filter_map(|(seed, rows)| {
                    same_score(rows, &m.descriptor, &m.landmarks).map(|r| (*seed as f64, r.rank1))
                })
                .collect();
            p.sort_by(|a, b| a.0.total_cmp(&b.0));
            m.series(p)
        })
        .collect();
    rep.plot(
        "rank1-seeds.svg",
        ("Rank-1 per seed", "seed", "rank-1"),
        &series,
        "Rank-1 of each seed's run; dashed: detected landmarks",
    )?;
    rep.png_twins()?;
    rep.finish()?;
    for m in &pool {
        let hits = m.identified.iter().filter(|&&i| i).count();
        eprintln!(
            "{:<14} {:<13} pooled rank-1 {:.3} ({hits} / {})  mean EER {:.3}",
            m.descriptor,
            m.landmarks,
            m.rank1,
            m.identified.len(),
            m.eer
        );
    }
    // The paired counts are also on stderr for bipolar against ICP.
    for b in pool.iter().filter(|m| m.descriptor == "bipolar") {
        if let Some(o) = pool
            .iter()
            .find(|o| o.descriptor == "icp_raw_mesh" && o.landmarks == b.landmarks)
        {
            let (nb, no) = discordant(&b.identified, &o.identified);
            eprintln!(
                "bipolar vs ICP ({}): only bipolar {nb}, only ICP {no}, McNemar p {:.4}",
                b.landmarks,
                mcnemar_exact(nb, no)
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(descriptor: &str, landmarks: &str, identified: &[bool], eer: f64) -> RunRow {
        RunRow {
            descriptor: descriptor.into(),
            landmarks: landmarks.into(),
            rank1: identified.iter().filter(|&&i| i).count() as f64 / identified.len() as f64,
            eer: Some(eer),
            identified: identified.to_vec(),
        }
    }

    #[test]
    fn pooling_concatenates_probes_and_averages_eers() {
        let runs = vec![
            (
                7,
                vec![
                    row("bipolar", "ground_truth", &[true, true, false], 0.1),
                    row("icp_raw_mesh", "ground_truth", &[true, false, false], 0.2),
                ],
            ),
            (
                13,
                vec![
                    // Another order of the scores in the second run.
                    row("icp_raw_mesh", "ground_truth", &[false, true], 0.4),
                    row("bipolar", "ground_truth", &[true, true], 0.3),
                ],
            ),
        ];
        let p = pooled(&runs).unwrap();
        assert_eq!(p[0].descriptor, "bipolar");
        assert_eq!(p[0].identified, [true, true, false, true, true]);
        assert!((p[0].rank1 - 0.8).abs() < 1e-12 && (p[0].eer - 0.2).abs() < 1e-12);
        assert_eq!(p[1].identified, [true, false, false, false, true]);
        // A score missing from one run is an error naming it.
        let mut short = runs.clone();
        short[1].1.pop();
        let e = pooled(&short).unwrap_err().to_string();
        assert!(e.contains("seed 13") && e.contains("bipolar"), "{e}");
        assert!(pooled(&[]).is_err());
    }

    #[test]
    fn a_run_folder_is_read_and_checked() {
        let dir = std::env::temp_dir().join(format!("bipolar-pool-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // Missing: the error names the file.
        let e = format!("{:#}", read_run(&dir).unwrap_err());
        assert!(e.contains("summary.json"), "{e}");
        let write = |rank1: f64| {
            std::fs::write(
                dir.join("summary.json"),
                format!(
                    r#"{{"seed": 7, "results": [{{"descriptor": "bipolar", "landmarks": "detected", "rank1": {rank1}, "eer": null, "identified": [true, false]}}]}}"#
                ),
            )
            .unwrap()
        };
        write(0.5);
        let rows = read_run(&dir).unwrap();
        assert_eq!(rows[0].identified, [true, false]);
        assert_eq!(rows[0].eer, None);
        // A rank-1 that its probes do not give is refused.
        write(1.0);
        assert!(format!("{:#}", read_run(&dir).unwrap_err()).contains("rank-1"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
