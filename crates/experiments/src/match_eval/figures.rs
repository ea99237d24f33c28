//! The figures of one set at one gate: rank-1, equal error rate, the ratio of the nearest
//! other person to the farthest same person, the fallbacks, and one row per comparison.

use super::sets::{Processed, Spec};
use crate::report::f4;
use facematch::{Comparison, Gallery, MatchOptions, Template};

/// Figures of one set at one gate.
#[derive(Debug, Default, Clone)]
pub(super) struct Figures {
    pub probes: usize,
    /// Gallery scans that could not be enrolled.
    pub not_enrolled: usize,
    pub identified: usize,
    pub no_score: usize,
    pub eer: f64,
    /// min(impostor) / max(genuine) over every scored comparison.
    pub ratio: f64,
    pub genuine: Vec<f64>,
    pub impostor: Vec<f64>,
    /// Comparisons with at least one fallback, and the fallbacks by kind.
    pub with_fallback: usize,
    pub fallbacks: std::collections::BTreeMap<String, usize>,
    pub comparisons: usize,
    /// Per comparison: probe, template, same person, score, the pair that scored, the view
    /// used, the fallbacks.
    pub rows: Vec<Vec<String>>,
}

/// The columns of [`Figures::rows`] (`scores-SET.csv`).
pub(super) const SCORE_COLUMNS: [&str; 7] = [
    "probe",
    "template",
    "same person",
    "score",
    "scored by",
    "view",
    "fallbacks",
];

/// A view use in a word or two (the kind, and the matched view's turn).
fn view_label(v: &facematch::ViewUse) -> String {
    match v {
        facematch::ViewUse::Off => "off".into(),
        facematch::ViewUse::Own { .. } => "own".into(),
        facematch::ViewUse::Matched { yaw_deg, .. } => format!("view {yaw_deg:+}"),
        facematch::ViewUse::Fallback { .. } => "own (fallback)".into(),
    }
}

/// The figures of one set (`p`, with its probe specs) under options `o`: every probe
/// compared with every template, rank-1, EER, the score ratio and the fallbacks.
pub(super) fn figures(p: &Processed, probes: &[Spec], o: &MatchOptions) -> Figures {
    let templates: Vec<Template> = p.templates.iter().flatten().cloned().collect();
    let gallery = Gallery { templates };
    let mut f = Figures {
        probes: p.probes.len(),
        not_enrolled: p.templates.iter().filter(|t| t.is_err()).count(),
        ..Figures::default()
    };
    for (d, spec) in p.probes.iter().zip(probes) {
        let id = spec.identity;
        let Ok(d) = d else {
            f.no_score += 1;
            continue;
        };
        let cs: Vec<Comparison> = gallery.compare_all(d, o);
        for c in &cs {
            f.comparisons += 1;
            let fb = c.fallbacks();
            if !fb.is_empty() {
                f.with_fallback += 1;
            }
            for k in c.fallback_kinds() {
                *f.fallbacks.entry(k).or_default() += 1;
            }
        }
        // A comparison without a score counts as refused: infinitely far.
        for (t, c) in gallery.templates.iter().zip(&cs) {
            let score = if c.score.is_finite() {
                c.score
            } else {
                f64::INFINITY
            };
            let same = t.identity == id.to_string();
            if same {
                f.genuine.push(score);
            } else {
                f.impostor.push(score);
            }
            f.rows.push(vec![
                spec.name.clone(),
                t.source.clone(),
                same.to_string(),
                f4(c.score),
                c.scored_by.map_or("", |p| p.name()).to_string(),
                view_label(&c.view),
                c.fallback_kinds().join("; "),
            ]);
        }
        let ranking = facematch::rank(&gallery.templates, cs);
        match ranking.first() {
            Some(r) if r.score.is_finite() && r.identity == id.to_string() => f.identified += 1,
            Some(r) if r.score.is_finite() => {}
            _ => f.no_score += 1,
        }
    }
    f.eer = facematch::metrics::eer(&f.genuine, &f.impostor).rate;
    let max_g = f.genuine.iter().copied().fold(f64::NAN, f64::max);
    let min_i = f.impostor.iter().copied().fold(f64::NAN, f64::min);
    f.ratio = min_i / max_g;
    f
}

/// Share of the probes identified at rank 1.
pub(super) fn rank1(f: &Figures) -> f64 {
    f.identified as f64 / f.probes.max(1) as f64
}

/// The residual gate of a `--gates` value (0: none).
pub(super) fn gate_of(g: f64) -> Option<f64> {
    (g > 0.0).then_some(g)
}

/// A `--gates` value in the tables.
pub(super) fn gate_label(g: f64) -> String {
    match gate_of(g) {
        Some(g) => format!("{g} mm"),
        None => "none".into(),
    }
}
