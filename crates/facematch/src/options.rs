//! The options of face matching and their defaults: the one place where they are written.

use crate::MatchError;
use geodesic::Method;
use scanprep::CleanOptions;

/// How a scan is prepared ([`crate::prepare`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PrepareOptions {
    /// Cleaning (spikes, holes, small components, units, decimation). Its `crop` is not used:
    /// the crop is [`PrepareOptions::crop_radius_mm`] around the detected nose tip.
    pub clean: CleanOptions,
    /// Radius (mm) of the crop around the detected nose tip (`None`: no crop, one cleaning).
    pub crop_radius_mm: Option<f64>,
    /// How the crop is made: the first cleaned (decimated) scan cropped, the first detection's
    /// landmarks kept (true); or the input's cleaning finished again with the crop and the
    /// landmarks detected again on it (false).
    pub crop_keeps_detection: bool,
    /// Taubin smoothing iterations of a copy of the cleaned scan that detection runs on (the
    /// landmarks keep their vertices and are placed on the scan itself); 0: on the scan.
    pub detect_smoothing: usize,
    /// Detection options (the units factor is recognised from the scan, the viewer direction is
    /// the scanner's).
    pub detect: landmarks::DetectOptions,
}

/// The default target edge length (mm) the cleaned scans are decimated to: the scan
/// benchmark's (docs/scans.md).
pub const DEFAULT_EDGE_MM: f64 = 1.5;

impl Default for PrepareOptions {
    fn default() -> Self {
        Self {
            clean: CleanOptions {
                crop: None,
                target_edge_mm: Some(DEFAULT_EDGE_MM),
                ..CleanOptions::default()
            },
            crop_radius_mm: Some(scanprep::DEFAULT_CROP_RADIUS_MM),
            crop_keeps_detection: false,
            detect_smoothing: 0,
            detect: landmarks::DetectOptions::default(),
        }
    }
}

/// The probe's reference-point search ([`bipolar::SearchedPole`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchOptions {
    /// How far each pole is moved (mm). 2 mm raised the detected rank-1 from 0.656 to 0.750 on
    /// 16 identities and from 0.550 to 0.690 on 50 (docs/scans.md, "Reference-point search").
    pub radius_mm: f64,
    /// Directions in each pole's tangent plane.
    pub directions: usize,
    /// Move the poles of all three pairs (true) or only the probe's own pair's.
    pub all_pairs: bool,
}

impl Default for SearchOptions {
    fn default() -> Self {
        Self {
            radius_mm: 2.0,
            directions: 6,
            all_pairs: true,
        }
    }
}

/// View matching: a gallery face described again on the part of it a scanner turned toward
/// the probe's direction would measure, so that both sides miss the same surface. A template
/// holds these descriptions for a fixed set of turned directions (computed once, at
/// enrolment); a comparison takes the one nearest the probe's direction.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewOptions {
    /// Below this angle (degrees) between the probe's scanner direction (carried into the
    /// template's frame) and the template's own, the template's own description is used.
    pub min_angle_deg: f64,
    /// The turns (degrees, about the face's vertical axis) of the template's views; each is
    /// taken to both sides. Two views (25 alone) were measured and not taken: a quarter of
    /// the views' enrolment cost, better on match-eval's tuning set, but 5 (ground truth) and
    /// 2 (detected) probes fewer identified on the 50-identity scan benchmark
    /// (docs/matching.md, "Two views, measured and not taken").
    pub yaws_deg: Vec<f64>,
    /// Incidence (degrees) beyond which a view loses its faces: the middle of the
    /// structured-light scanner model's grazing dropouts (70-80 degrees).
    pub incidence_deg: f64,
    /// Sample spacing (mm) of the view's z-buffer: the scans' pitch.
    pub pitch_mm: f64,
}

impl Default for ViewOptions {
    fn default() -> Self {
        Self {
            min_angle_deg: 10.0,
            yaws_deg: vec![15.0, 25.0, 35.0, 45.0],
            incidence_deg: 75.0,
            pitch_mm: 0.5,
        }
    }
}

/// Everything face matching can be told, with the scan benchmark's defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct MatchOptions {
    /// How scans are prepared.
    pub prepare: PrepareOptions,
    /// Geodesic method.
    pub method: Method,
    /// Levels N between the two poles (step D / N, static area up to level N).
    pub levels: u32,
    /// The fields are cut off at this factor times the outer eye corners' distance.
    pub field_cutoff: f64,
    /// Band (mm) along the holes and the border left out (docs/scans.md, "Yaw").
    pub boundary_margin_mm: Option<f64>,
    /// Parts seen at more than this incidence (degrees) from the scanner left out (chosen on
    /// scan-study: docs/scans.md, "Grazing incidence").
    pub max_incidence_deg: Option<f64>,
    /// A probe turned from its scanner by more than this (degrees, eye line against the
    /// scanner direction), or with a lost outer corner, takes its nearer corner's side pair as
    /// its own pair (`None`: always the corners, and no lost corners).
    pub side_pair_deg: Option<f64>,
    /// The score is the least distance over the three pairs (else the probe's own pair's).
    pub least_pair: bool,
    /// With `least_pair`: the weight of the second least pair distance (0: the least alone).
    pub second_weight: f64,
    /// The probe's reference-point search (`None`: off).
    pub search: Option<SearchOptions>,
    /// View matching (`None`: off).
    pub view: Option<ViewOptions>,
    /// An outer eye corner the detector reports unseen is placed at the vertex nearest the
    /// fitted face's prediction, when within `snap_mm`, instead of being lost.
    pub predicted_corners: bool,
    /// A landmark farther than this (mm) from every vertex is not on the surface.
    pub snap_mm: f64,
    /// Residual rule of the keyed distance: pairs of points whose residual after the
    /// alignment exceeds this (mm) are dropped and the fit repeated (`None`: every pair).
    pub gate_mm: Option<f64>,
    /// `bipolar verify`'s threshold: scores at or below it are the same person.
    pub verify_threshold: f64,
}

/// The verification threshold (see [`MatchOptions::verify_threshold`]): the equal-error
/// threshold of `cargo xtask match-eval`'s tuning set (0.0256 at its default seed, 16
/// identities, 32 probes); its held-out set's error rates at it are in docs/matching.md.
pub const VERIFY_THRESHOLD: f64 = 0.026;

impl Default for MatchOptions {
    fn default() -> Self {
        Self {
            prepare: PrepareOptions::default(),
            method: Method::Exact,
            levels: 10,
            field_cutoff: 1.4,
            boundary_margin_mm: Some(6.0),
            max_incidence_deg: Some(60.0),
            side_pair_deg: Some(30.0),
            least_pair: true,
            second_weight: 0.0,
            search: Some(SearchOptions::default()),
            view: Some(ViewOptions::default()),
            predicted_corners: false,
            snap_mm: 3.0,
            gate_mm: None,
            verify_threshold: VERIFY_THRESHOLD,
        }
    }
}

impl MatchOptions {
    /// Checks every option; the error names the first one out of range.
    pub fn validate(&self) -> Result<(), MatchError> {
        let bad = |what: String| Err(MatchError::InvalidOption(what));
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if self.levels == 0 {
            return bad("levels 0 (at least 1)".into());
        }
        if !(positive(self.field_cutoff) && self.field_cutoff >= 1.0) {
            return bad(format!("field cut-off {} (at least 1)", self.field_cutoff));
        }
        for (name, v) in [
            ("boundary margin (mm)", self.boundary_margin_mm),
            ("max incidence (degrees)", self.max_incidence_deg),
            ("side pair angle (degrees)", self.side_pair_deg),
            ("gate (mm)", self.gate_mm),
            ("crop radius (mm)", self.prepare.crop_radius_mm),
        ] {
            if let Some(x) = v {
                if !positive(x) {
                    return bad(format!(
                        "{name} {x} (must be positive; leave it out for none)"
                    ));
                }
            }
        }
        if !(0.0..=1.0).contains(&self.second_weight) {
            return bad(format!(
                "second pair weight {} (must be in [0, 1])",
                self.second_weight
            ));
        }
        if let Some(s) = &self.search {
            if !positive(s.radius_mm) || s.directions == 0 {
                return bad(format!(
                    "search radius {} mm with {} directions (a positive radius and at least one direction)",
                    s.radius_mm, s.directions
                ));
            }
        }
        if let Some(v) = &self.view {
            let angles_ok = v.min_angle_deg.is_finite()
                && v.min_angle_deg >= 0.0
                && positive(v.incidence_deg)
                && v.yaws_deg.iter().all(|y| positive(*y) && *y < 90.0);
            if !(angles_ok && positive(v.pitch_mm)) {
                return bad(format!(
                    "view matching {v:?} (angles in (0, 90) degrees, a positive pitch)"
                ));
            }
        }
        if !positive(self.snap_mm) {
            return bad(format!(
                "snap distance {} mm (must be positive)",
                self.snap_mm
            ));
        }
        if !self.verify_threshold.is_finite() {
            return bad(format!("verify threshold {}", self.verify_threshold));
        }
        Ok(())
    }

    /// The settings a template depends on (preparation, description, views), as one line:
    /// templates made with other settings cannot be compared with these
    /// ([`MatchError::Settings`]). The probe's search, the score's rule, the gate and the
    /// verification threshold act at comparison time and are not part of it.
    pub fn template_settings(&self) -> String {
        let p = &self.prepare;
        format!(
            "method={} levels={} cutoff={} margin={:?} incidence={:?} side_pair={:?} predicted_corners={} snap={} view={:?} crop={:?}{} detect_smoothing={} clean={:?} detect={:?}",
            self.method.name(),
            self.levels,
            self.field_cutoff,
            self.boundary_margin_mm,
            self.max_incidence_deg,
            self.side_pair_deg,
            self.predicted_corners,
            self.snap_mm,
            self.view,
            p.crop_radius_mm,
            if p.crop_keeps_detection { " (of the first cleaning, its landmarks kept)" } else { "" },
            p.detect_smoothing,
            CleanOptions { crop: None, ..p.clean.clone() },
            p.detect,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_are_named() {
        assert!(MatchOptions::default().validate().is_ok());
        let o = MatchOptions {
            gate_mm: Some(-1.0),
            ..MatchOptions::default()
        };
        assert!(o
            .validate()
            .unwrap_err()
            .to_string()
            .contains("gate (mm) -1"));
        let o = MatchOptions {
            second_weight: 2.0,
            ..MatchOptions::default()
        };
        assert!(o
            .validate()
            .unwrap_err()
            .to_string()
            .contains("second pair weight 2"));
    }

    #[test]
    fn template_settings_follow_the_description_options_only() {
        let a = MatchOptions::default();
        let b = MatchOptions {
            gate_mm: Some(10.0),
            search: None,
            ..a.clone()
        };
        assert_eq!(a.template_settings(), b.template_settings());
        let c = MatchOptions {
            levels: 12,
            ..a.clone()
        };
        assert_ne!(a.template_settings(), c.template_settings());
    }
}
