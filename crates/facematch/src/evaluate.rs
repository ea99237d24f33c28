//! A gallery measured against probes of known identity: every probe compared with every
//! template, the probes identified at rank 1, the genuine and impostor scores with their equal
//! error rate, the ratio of the nearest other person to the farthest same person, and the
//! fallbacks the comparisons took, counted by kind.

use crate::{Comparison, Description, Gallery, MatchOptions};
use std::collections::BTreeMap;

/// How many comparisons took a fallback, and the fallbacks by kind
/// ([`Comparison::fallback_kinds`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FallbackCount {
    /// Comparisons counted.
    pub comparisons: usize,
    /// Comparisons with at least one fallback.
    pub with_fallback: usize,
    /// Fallbacks by kind, in the kinds' order.
    pub by_kind: BTreeMap<String, usize>,
}

impl FallbackCount {
    /// Counts one comparison by the kinds of its fallbacks (none: a comparison without).
    pub fn add(&mut self, kinds: &[String]) {
        self.comparisons += 1;
        self.with_fallback += usize::from(!kinds.is_empty());
        for k in kinds {
            *self.by_kind.entry(k.clone()).or_default() += 1;
        }
    }

    /// `kind: count` per kind.
    pub fn kinds(&self) -> Vec<String> {
        self.by_kind
            .iter()
            .map(|(k, n)| format!("{k}: {n}"))
            .collect()
    }

    /// `W of N WHAT took a fallback`, then the kinds in brackets when there are any.
    pub fn sentence(&self, what: &str) -> String {
        let kinds = self.kinds();
        let mut s = format!(
            "{} of {} {what} took a fallback",
            self.with_fallback, self.comparisons
        );
        if !kinds.is_empty() {
            s += &format!(" ({})", kinds.join("; "));
        }
        s
    }
}

/// What [`evaluate`] measured.
#[derive(Debug, Clone, Default)]
pub struct Evaluation {
    /// Probes given.
    pub probes: usize,
    /// Probes whose best-ranked identity ([`crate::rank`]) has a score and is their own.
    pub identified: usize,
    /// Probes without a description, or whose best-ranked identity has no score.
    pub no_score: usize,
    /// Scores of the probes against templates of their own identity (a comparison without a
    /// score counts as infinitely far).
    pub genuine: Vec<f64>,
    /// Scores against templates of other identities (likewise).
    pub impostor: Vec<f64>,
    /// Equal error rate of `genuine` against `impostor` ([`crate::metrics::eer`]).
    pub eer: f64,
    /// min(impostor) / max(genuine) (NaN when either side is empty).
    pub ratio: f64,
    /// The fallbacks of every comparison.
    pub fallbacks: FallbackCount,
    /// Per probe, its comparisons with the templates in gallery order (empty for a probe
    /// without a description).
    pub comparisons: Vec<Vec<Comparison>>,
}

impl Evaluation {
    /// Share of the probes identified at rank 1 (0 without probes).
    pub fn rank1(&self) -> f64 {
        self.identified as f64 / self.probes.max(1) as f64
    }
}

/// Every probe (its identity, its description or `None` where it has none) compared with every
/// template of `gallery` under `options` ([`Gallery::compare_all`]), and the figures of
/// [`Evaluation`].
pub fn evaluate(
    gallery: &Gallery,
    probes: &[(&str, Option<&Description>)],
    options: &MatchOptions,
) -> Evaluation {
    let mut e = Evaluation {
        probes: probes.len(),
        ..Evaluation::default()
    };
    for &(identity, d) in probes {
        let Some(d) = d else {
            e.no_score += 1;
            e.comparisons.push(Vec::new());
            continue;
        };
        let cs = gallery.compare_all(d, options);
        for (t, c) in gallery.templates.iter().zip(&cs) {
            e.fallbacks.add(&c.fallback_kinds());
            let score = crate::metrics::worst_if_failed(c.score);
            if t.identity == identity {
                e.genuine.push(score);
            } else {
                e.impostor.push(score);
            }
        }
        match crate::rank(&gallery.templates, cs.clone()).first() {
            Some(r) if r.score.is_finite() && r.identity == identity => e.identified += 1,
            Some(r) if r.score.is_finite() => {}
            _ => e.no_score += 1,
        }
        e.comparisons.push(cs);
    }
    e.eer = crate::metrics::eer(&e.genuine, &e.impostor).rate;
    let max_genuine = e.genuine.iter().copied().fold(f64::NAN, f64::max);
    let min_impostor = e.impostor.iter().copied().fold(f64::NAN, f64::min);
    e.ratio = min_impostor / max_genuine;
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fallbacks_are_counted_per_comparison_and_by_kind() {
        let mut f = FallbackCount::default();
        assert_eq!(
            f.sentence("comparisons"),
            "0 of 0 comparisons took a fallback"
        );
        f.add(&[]);
        f.add(&["b".to_string(), "a".to_string()]);
        f.add(&["a".to_string()]);
        assert_eq!((f.comparisons, f.with_fallback), (3, 2));
        assert_eq!(f.kinds(), ["a: 2", "b: 1"]);
        assert_eq!(
            f.sentence("bipolar comparisons"),
            "2 of 3 bipolar comparisons took a fallback (a: 2; b: 1)"
        );
    }

    #[test]
    fn an_empty_gallery_identifies_nobody_and_a_probe_without_description_has_no_score() {
        let e = evaluate(
            &Gallery::default(),
            &[("1", None)],
            &MatchOptions::default(),
        );
        assert_eq!((e.probes, e.identified, e.no_score), (1, 0, 1));
        assert_eq!(e.comparisons, [Vec::<Comparison>::new()]);
        assert!(e.ratio.is_nan() && e.rank1() == 0.0);
        assert_eq!(e.fallbacks, FallbackCount::default());
    }

    #[test]
    fn a_probe_is_identified_by_its_own_template_and_its_scores_are_split_by_identity() {
        let own = crate::fixture::small_template();
        let mut other = own.clone();
        other.identity = "id08".into();
        for s in other.description.sets.iter_mut().flatten() {
            for p in &mut s.points {
                p.x *= 1.5;
            }
        }
        let gallery = Gallery {
            templates: vec![other, own.clone()],
        };
        let probe = own.description.clone();
        let e = evaluate(
            &gallery,
            &[("id07", Some(&probe)), ("id09", None)],
            &MatchOptions::default(),
        );
        assert_eq!((e.probes, e.identified, e.no_score), (2, 1, 1));
        assert_eq!((e.genuine.len(), e.impostor.len()), (1, 1));
        assert!(
            e.genuine[0] < e.impostor[0],
            "{:?} {:?}",
            e.genuine,
            e.impostor
        );
        assert_eq!(e.ratio, e.impostor[0] / e.genuine[0]);
        assert_eq!(e.comparisons[0].len(), 2);
        assert_eq!(e.fallbacks.comparisons, 2);
        assert_eq!(e.rank1(), 0.5);
        let c = &e.comparisons[0][1];
        assert_eq!(c.view, crate::ViewUse::Own { angle_deg: 0.0 });
        assert_eq!(c.view.label(), "own");
        let matched = crate::ViewUse::Matched {
            yaw_deg: -15.0,
            angle_deg: 20.0,
            off_deg: 5.0,
        };
        assert_eq!(matched.label(), "view -15");
    }
}
