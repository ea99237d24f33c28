//! The figures of one set at one gate ([`facematch::evaluate`]: rank-1, equal error rate, the
//! ratio of the nearest other person to the farthest same person, the fallbacks) and one row
//! per comparison.

use super::sets::{Processed, Spec};
use crate::report::f4;
use facematch::{Evaluation, Gallery, MatchOptions, Template};

/// Figures of one set at one gate.
#[derive(Debug, Default, Clone)]
pub(super) struct Figures {
    /// What [`facematch::evaluate`] measured.
    pub eval: Evaluation,
    /// Gallery scans that could not be enrolled.
    pub not_enrolled: usize,
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

/// The figures of one set (`p`, with its probe specs) under options `o`: every probe
/// compared with every template.
pub(super) fn figures(p: &Processed, probes: &[Spec], o: &MatchOptions) -> Figures {
    let templates: Vec<Template> = p.templates.iter().flatten().cloned().collect();
    let gallery = Gallery { templates };
    let ids: Vec<String> = probes.iter().map(|s| s.identity.to_string()).collect();
    let labelled: Vec<(&str, Option<&facematch::Description>)> = ids
        .iter()
        .zip(&p.probes)
        .map(|(id, d)| (id.as_str(), d.as_ref().ok()))
        .collect();
    let eval = facematch::evaluate(&gallery, &labelled, o);
    let mut rows = Vec::new();
    for ((spec, id), cs) in probes.iter().zip(&ids).zip(&eval.comparisons) {
        for (t, c) in gallery.templates.iter().zip(cs) {
            rows.push(vec![
                spec.name.clone(),
                t.source.clone(),
                (t.identity == *id).to_string(),
                f4(c.score),
                c.scored_by.map_or("", |p| p.name()).to_string(),
                c.view.label(),
                c.fallback_kinds().join("; "),
            ]);
        }
    }
    Figures {
        not_enrolled: p.templates.iter().filter(|t| t.is_err()).count(),
        eval,
        rows,
    }
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
