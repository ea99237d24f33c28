//! A probe against a template: the distance by each pole pair and the score, with what was
//! used and what was fallen back on.

use crate::{probe_direction, Description, KeyedSet, MatchOptions, Pair, Template};

/// Which description of the template a comparison used.
#[derive(Debug, Clone, PartialEq)]
pub enum ViewUse {
    /// View matching is off.
    Off,
    /// The probe's scanner, carried into the template's frame, is within the minimum angle
    /// (`angle_deg`) of the template's own: its own description.
    Own {
        /// The angle between the two scanner directions (degrees).
        angle_deg: f64,
    },
    /// The template's view nearest the probe's direction.
    Matched {
        /// The view's turn (degrees).
        yaw_deg: f64,
        /// The angle between the two scanner directions (degrees).
        angle_deg: f64,
        /// The angle between the probe's direction and the view's (degrees).
        off_deg: f64,
    },
    /// A view was wanted but could not be used: the template's own description instead.
    Fallback {
        /// Why.
        reason: String,
    },
}

impl ViewUse {
    /// The view used in a word or two: `off`, `own`, `view +15` (the matched view's turn) or
    /// `own (fallback)`.
    pub fn label(&self) -> String {
        match self {
            ViewUse::Off => "off".into(),
            ViewUse::Own { .. } => "own".into(),
            ViewUse::Matched { yaw_deg, .. } => format!("view {yaw_deg:+}"),
            ViewUse::Fallback { .. } => "own (fallback)".into(),
        }
    }
}

/// What one pair's distance used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairUse {
    /// The distance (NaN when none could be computed).
    pub distance: f64,
    /// The template's own descriptor stood in for a view's that failed.
    pub view_fallback: bool,
    /// The probe's own descriptor failed: the distance is the least over its moved ones.
    pub probe_own_failed: bool,
    /// The probe's moved descriptors compared (the reference-point search).
    pub moved: usize,
    /// The probe's moved descriptors that failed and are left out.
    pub moved_failed: usize,
}

/// The result of [`compare`].
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// The score (lower is more alike; NaN when no pair gave a distance).
    pub score: f64,
    /// Per pair (indexed by [`Pair`]'s discriminant).
    pub pairs: [PairUse; 3],
    /// The probe's own pair.
    pub probe_pair: Pair,
    /// The pair whose distance is the score's least (with `least_pair`), else the probe's own.
    pub scored_by: Option<Pair>,
    /// Which description of the template was used.
    pub view: ViewUse,
}

impl Comparison {
    /// The decision of verification: the same person when the score is a number at or below
    /// `options.verify_threshold`.
    pub fn same_person(&self, options: &MatchOptions) -> bool {
        self.score.is_finite() && self.score <= options.verify_threshold
    }

    /// The kinds of the substitutions this comparison made, one per [`Comparison::fallbacks`]
    /// sentence without its numbers and reasons (`view matching: own description`,
    /// `corners: view failed`, `left-nose: probe's own failed`, `corners: moved left out`), for
    /// counting.
    pub fn fallback_kinds(&self) -> Vec<String> {
        self.substitutions().into_iter().map(|(k, _)| k).collect()
    }

    /// The substitutions this comparison made, as sentences (empty when none).
    pub fn fallbacks(&self) -> Vec<String> {
        self.substitutions().into_iter().map(|(_, s)| s).collect()
    }

    /// Each substitution as its kind and its sentence.
    fn substitutions(&self) -> Vec<(String, String)> {
        let mut out = Vec::new();
        if let ViewUse::Fallback { reason } = &self.view {
            out.push((
                "view matching: own description".to_string(),
                format!("view matching: the template's own description ({reason})"),
            ));
        }
        for (p, u) in Pair::ALL.iter().zip(&self.pairs) {
            let name = p.name();
            if u.view_fallback {
                out.push((
                    format!("{name}: view failed"),
                    format!("{name}: the template's view failed, its own descriptor used"),
                ));
            }
            if u.probe_own_failed {
                out.push((
                    format!("{name}: probe's own failed"),
                    format!(
                        "{name}: the probe's own descriptor failed, the least of its {} moved ones used",
                        u.moved
                    ),
                ));
            }
            if u.moved_failed > 0 {
                out.push((
                    format!("{name}: moved left out"),
                    format!(
                        "{name}: {} of the search's moved descriptors failed and were left out ({} used)",
                        u.moved_failed, u.moved
                    ),
                ));
            }
        }
        out
    }
}

/// With `least`: `(1 - second)` x the least of the distances by each pair `d` + `second` x the
/// second least (NaN ones skipped; the least alone when only one is a number, or when
/// `second` is 0; NaN when none is); else the one of the probe's pair `own`. Also the pair the
/// least came from.
pub fn pair_score(d: [f64; 3], own: Pair, least: bool, second: f64) -> (f64, Option<Pair>) {
    if !least {
        return (d[own as usize], (!d[own as usize].is_nan()).then_some(own));
    }
    let mut f: Vec<(f64, Pair)> = d
        .into_iter()
        .zip(Pair::ALL)
        .filter(|x| !x.0.is_nan())
        .collect();
    f.sort_by(|a, b| a.0.total_cmp(&b.0));
    match f[..] {
        [] => (f64::NAN, None),
        [(a, p)] => (a, Some(p)),
        [(a, p), ..] if second == 0.0 => (a, Some(p)),
        [(a, p), (b, _), ..] => ((1.0 - second) * a + second * b, Some(p)),
    }
}

/// The template's descriptors a probe is compared with: the view nearest the probe's scanner
/// direction, or its own.
fn choose_view<'a>(
    probe: &Description,
    template: &'a Template,
    options: &MatchOptions,
) -> (Option<&'a [Result<KeyedSet, String>; 3]>, ViewUse) {
    let Some(v) = &options.view else {
        return (None, ViewUse::Off);
    };
    let t = &template.description;
    let Some(toward) = probe_direction(&probe.landmarks, probe.scanner, &t.landmarks) else {
        let reason = "the probe's landmarks do not fit the template's".to_string();
        return (None, ViewUse::Fallback { reason });
    };
    let angle_deg = toward.angle_between(t.scanner).to_degrees();
    if angle_deg < v.min_angle_deg {
        return (None, ViewUse::Own { angle_deg });
    }
    let nearest = template
        .views
        .iter()
        .map(|w| (w, toward.angle_between(w.toward).to_degrees()))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    match nearest {
        None => (
            None,
            ViewUse::Fallback {
                reason: "the template has no views".into(),
            },
        ),
        Some((w, off_deg)) => match &w.sets {
            Ok(sets) => (
                Some(sets),
                ViewUse::Matched {
                    yaw_deg: w.yaw_deg,
                    angle_deg,
                    off_deg,
                },
            ),
            Err(e) => (
                None,
                ViewUse::Fallback {
                    reason: format!("its view at {} degrees failed: {e}", w.yaw_deg),
                },
            ),
        },
    }
}

/// Compares a probe's description with a template: per pair the least of the probe's own and
/// moved descriptors' distances ([`bipolar::least_searched_distance`]) to the template's
/// descriptor (its view nearest the probe's scanner direction with view matching; its own
/// where the view's failed), and the score ([`pair_score`]). Nothing is substituted unseen:
/// [`Comparison`] says what was used.
pub fn compare(probe: &Description, template: &Template, options: &MatchOptions) -> Comparison {
    let (view_sets, view) = choose_view(probe, template, options);
    let gate = options.gate_mm;
    let dist = |a: &KeyedSet, b: &KeyedSet| a.distance(b, gate);
    let pairs = Pair::ALL.map(|p| {
        let i = p as usize;
        let mut u = PairUse {
            distance: f64::NAN,
            view_fallback: false,
            probe_own_failed: false,
            moved: probe.moved[i].len(),
            moved_failed: probe.moved_failed[i],
        };
        let Ok(own) = &template.description.sets[i] else {
            return u;
        };
        let yb = match view_sets.map(|s| &s[i]) {
            Some(Ok(s)) => s,
            Some(Err(_)) => {
                u.view_fallback = true;
                own
            }
            None => own,
        };
        let (xa, moved) = match (&probe.sets[i], probe.moved[i].split_first()) {
            (Ok(xa), _) => (xa, &probe.moved[i][..]),
            (Err(_), Some((first, rest))) => {
                u.probe_own_failed = true;
                (first, rest)
            }
            (Err(_), None) => return u,
        };
        u.distance = bipolar::least_searched_distance(xa, moved, yb, &[], dist).unwrap_or(f64::NAN);
        u
    });
    let (score, scored_by) = pair_score(
        pairs.map(|u| u.distance),
        probe.pair,
        options.least_pair,
        options.second_weight,
    );
    Comparison {
        score,
        pairs,
        probe_pair: probe.pair,
        scored_by,
        view,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_score_is_the_least_pair_or_the_own_one() {
        let n = f64::NAN;
        assert_eq!(
            pair_score([0.3, 0.1, n], Pair::Corners, true, 0.0),
            (0.1, Some(Pair::RightNose))
        );
        let (s, p) = pair_score([0.3, 0.1, 0.2], Pair::Corners, true, 0.25);
        assert!((s - (0.75 * 0.1 + 0.25 * 0.2)).abs() < 1e-15);
        assert_eq!(p, Some(Pair::RightNose));
        assert_eq!(
            pair_score([0.3, 0.1, 0.2], Pair::Corners, false, 0.0),
            (0.3, Some(Pair::Corners))
        );
        assert!(pair_score([n, n, n], Pair::Corners, true, 0.0).0.is_nan());
        assert_eq!(
            pair_score([n, 0.4, n], Pair::Corners, true, 0.5),
            (0.4, Some(Pair::RightNose))
        );
    }

    #[test]
    fn every_fallback_has_a_sentence_and_a_kind() {
        let used = |view_fallback, probe_own_failed| PairUse {
            distance: 0.1,
            view_fallback,
            probe_own_failed,
            moved: 48,
            moved_failed: 0,
        };
        let c = Comparison {
            score: 0.1,
            pairs: [used(true, false), used(false, false), used(true, true)],
            probe_pair: Pair::Corners,
            scored_by: Some(Pair::Corners),
            view: ViewUse::Fallback {
                reason: "the template has no views".into(),
            },
        };
        assert_eq!(
            c.fallback_kinds(),
            [
                "view matching: own description",
                "corners: view failed",
                "left-nose: view failed",
                "left-nose: probe's own failed"
            ]
        );
        let s = c.fallbacks();
        assert_eq!(s.len(), 4);
        assert!(s[0].contains("the template has no views"), "{s:?}");
        assert!(s[3].contains("48 moved ones"), "{s:?}");
        let none = Comparison {
            pairs: [used(false, false); 3],
            view: ViewUse::Off,
            ..c
        };
        assert!(none.fallbacks().is_empty() && none.fallback_kinds().is_empty());
        // Moved descriptors of the search that failed are left out, and said.
        let mut short = none.clone();
        short.pairs[1].moved_failed = 5;
        assert_eq!(short.fallback_kinds(), ["right-nose: moved left out"]);
        assert!(
            short.fallbacks()[0].contains("5 of the search's moved descriptors failed"),
            "{:?}",
            short.fallbacks()
        );
    }
}
