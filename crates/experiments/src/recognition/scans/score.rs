//! The scores of a probe group against the gallery: its figures, each probe's rank and every
//! failure.

use super::super::compare::score_set;
use super::super::describe::Described;
use super::super::metrics::{summarize, Metrics, SCORES};
use super::face::Face;
use super::SETS;
use anyhow::Result;
use facecurves::ElasticOptions;
use meshcore::{DVec3, FaceLocator};

/// Figures of a probe group against the gallery, per landmark set and score, with the times
/// per comparison (timed on pairs of this group) and per description (`ms_desc`).
pub(in super::super) fn score_group(
    gallery: &[Face],
    locators: &[[Option<FaceLocator<'_>>; 2]],
    probes: &[Face],
    elastic: &ElasticOptions,
    ms_desc: &[f64; 4],
) -> Result<Scored> {
    let gid: Vec<usize> = gallery.iter().map(|g| g.identity).collect();
    let pid: Vec<usize> = probes.iter().map(|p| p.identity).collect();
    let mut all = Vec::new();
    let mut per_probe = Vec::new();
    let mut by_pair = Vec::new();
    let mut fallbacks = Vec::new();
    for (k, set) in SETS.iter().enumerate() {
        let gal: Vec<Option<(&Described, &FaceLocator<'_>)>> = gallery
            .iter()
            .zip(locators)
            .map(|(g, l)| g.desc[k].as_ref().ok().zip(l[k].as_ref()))
            .collect();
        let pr: Vec<(Option<&Described>, &[DVec3])> = probes
            .iter()
            .map(|p| (p.desc[k].as_ref().ok(), p.pts[k].as_slice()))
            .collect();
        let (rows, pairs, ms_cmp) = score_set(&pr, &gal, elastic)?;
        all.extend(summarize(&rows, &ms_cmp, ms_desc, &pid, &gid, set));
        for (p, row) in probes.iter().zip(&rows) {
            for (j, score) in SCORES.iter().enumerate() {
                per_probe.push(probe_rank(&p.name, p.identity, set, score, &row[j], &gid));
            }
        }
        let mut count = facematch::FallbackCount::default();
        for (p, ds) in probes.iter().zip(&pairs) {
            let Ok(x) = &p.desc[k] else { continue };
            for (g, (d, fb)) in gallery.iter().zip(ds) {
                count.add(fb);
                by_pair.push(
                    [
                        p.name.clone(),
                        p.identity.to_string(),
                        set.to_string(),
                        x.bip
                            .as_ref()
                            .map_or(String::new(), |b| format!("{:?}", b.pair)),
                        g.identity.to_string(),
                    ]
                    .into_iter()
                    .chain(d.iter().map(|v| format!("{v:.6}")))
                    .chain([fb.join("; ")])
                    .collect(),
                );
            }
        }
        fallbacks.push(format!("{set}: {}", count.sentence("bipolar comparisons")));
    }
    Ok(Scored {
        metrics: all,
        per_probe,
        by_pair,
        fallbacks,
    })
}

/// What [`score_group`] gives: the figures, the lines of `probes.csv` and those of
/// `bipolar-pairs.csv`, and per landmark set the count of bipolar comparisons that took a
/// fallback ([`facematch::FallbackCount`]), by kind.
pub(in super::super) struct Scored {
    pub(in super::super) metrics: Vec<Metrics>,
    pub(super) per_probe: Vec<Vec<String>>,
    pub(super) by_pair: Vec<Vec<String>>,
    pub(in super::super) fallbacks: Vec<String>,
}

/// One line of `probes.csv`: where the probe's own identity ranks among the gallery for one
/// score ([`facematch::metrics::genuine_rank`]; empty when its genuine score failed), its
/// genuine score, and the best impostor with its score.
fn probe_rank(
    name: &str,
    identity: usize,
    set: &str,
    score: &str,
    row: &[f64],
    gallery_id: &[usize],
) -> Vec<String> {
    let r = facematch::metrics::genuine_rank(row, gallery_id, identity);
    let num = |v: f64| {
        if v.is_finite() {
            format!("{v:.6}")
        } else {
            String::new()
        }
    };
    vec![
        name.to_string(),
        identity.to_string(),
        set.to_string(),
        score.to_string(),
        r.rank.map(|r| r.to_string()).unwrap_or_default(),
        num(r.genuine),
        r.best_impostor
            .map(|(g, _)| g.to_string())
            .unwrap_or_default(),
        r.best_impostor.map(|(_, v)| num(v)).unwrap_or_default(),
    ]
}

/// Every failure of a group: (face, landmark set, what failed).
pub(super) fn failures(faces: &[Face], group: &str) -> Vec<[String; 4]> {
    let mut out = Vec::new();
    for f in faces {
        for (k, set) in SETS.iter().enumerate() {
            let what: Vec<String> = match &f.desc[k] {
                Err(e) => vec![e.clone()],
                Ok(d) => [
                    match &d.bip {
                        Ok(b) => b.sets[b.pair as usize].as_ref().err().cloned(),
                        Err(e) => Some(e.clone()),
                    }
                    .as_ref(),
                    d.facial.as_ref().err(),
                    d.iso.as_ref().err(),
                ]
                .into_iter()
                .flatten()
                .cloned()
                .collect(),
            };
            for w in what {
                out.push([group.to_string(), f.name.clone(), set.to_string(), w]);
            }
        }
    }
    out
}
