//! The study's bipolar descriptor variants: the library's options by name.

/// A bipolar descriptor variant of the study: the library's options by name.
pub(super) struct Variant {
    pub(super) name: &'static str,
    /// `None`: rule `All`; else the iso-angle rule with these crossings and repeats.
    pub(super) isoangle: Option<(bipolar::IsoCrossings, bipolar::IsoRepeats)>,
    /// Band along the scan's boundary left out (mm; built once per scan by
    /// `pipeline::kept_vertices` and left out through the vertex mask, which leaves out what
    /// `DescriptorOptions::boundary_margin` would).
    pub(super) margin_mm: Option<f64>,
    /// Vertices the scanner saw at a larger incidence left out (`scanprep::incidence_mask`,
    /// degrees; the scans and the face mesh look along +z).
    pub(super) max_incidence_deg: Option<f64>,
    /// Described by `facematch` with its three pole pairs (the outer eye corners, each outer
    /// eye corner with the nose tip: the side pairs' lens above the nose tip's horizontal plane;
    /// poles at the vertices nearest the snapped landmarks): the distance is then the mean or
    /// the least ([`facematch::pair_score`]) of the three pairs' distances.
    pub(super) side_pairs: Option<PairCombine>,
}

/// How a variant with side pairs combines the distances by its three pole pairs.
#[derive(Debug, Clone, Copy)]
pub(super) enum PairCombine {
    Mean,
    Least,
}

impl Variant {
    /// The two variants build the same descriptors (they may differ in the distance rule).
    pub(super) fn same_description(&self, other: &Variant) -> bool {
        self.isoangle == other.isoangle
            && self.margin_mm == other.margin_mm
            && self.max_incidence_deg == other.max_incidence_deg
    }

    /// The library's options of the variant's selection rule (its band and incidence limit go
    /// through the vertex mask).
    pub(super) fn options(&self) -> bipolar::DescriptorOptions {
        match self.isoangle {
            None => bipolar::DescriptorOptions {
                rule: bipolar::SelectionRule::All,
                ..Default::default()
            },
            Some((crossings, repeats)) => bipolar::DescriptorOptions {
                rule: bipolar::SelectionRule::IsoAngle,
                isoangle: bipolar::IsoAngleOptions {
                    crossings,
                    repeats,
                    ..Default::default()
                },
                ..Default::default()
            },
        }
    }
}

/// The bipolar variants: the experiments' rule (`All`, grid keys) and the iso-angle rule with
/// every crossing (the first behaviour), with the monotone fit keeping repeated keys as ambiguous
/// (the second) and with the monotone fit and repeated keys resolved to the place nearest the
/// geodesic between the references (the library's default); rule `All` without the 6 mm band
/// along the holes and the border of each scan (the scans' choice in the recognition
/// benchmark), and that with the parts seen at more than 60 or 45 degrees of incidence left out
/// too; the 60-degree one also with the two side pairs (each outer eye corner with the nose
/// tip), by the mean and by the least of the three pairs' distances.
pub(super) const VARIANTS: [Variant; 9] = {
    use bipolar::{IsoCrossings::*, IsoRepeats::*};
    [
        Variant {
            name: "bipolar All",
            isoangle: None,
            margin_mm: None,
            max_incidence_deg: None,
            side_pairs: None,
        },
        Variant {
            name: "bipolar iso-angle, every crossing",
            isoangle: Some((Every, Ambiguous)),
            margin_mm: None,
            max_incidence_deg: None,
            side_pairs: None,
        },
        Variant {
            name: "bipolar iso-angle, monotone, repeats ambiguous",
            isoangle: Some((Monotone, Ambiguous)),
            margin_mm: None,
            max_incidence_deg: None,
            side_pairs: None,
        },
        Variant {
            name: "bipolar iso-angle, monotone, nearest",
            isoangle: Some((Monotone, Nearest)),
            margin_mm: None,
            max_incidence_deg: None,
            side_pairs: None,
        },
        Variant {
            name: "bipolar All, 6 mm band left out",
            isoangle: None,
            margin_mm: Some(6.0),
            max_incidence_deg: None,
            side_pairs: None,
        },
        Variant {
            name: "bipolar All, band and incidence over 60 degrees left out",
            isoangle: None,
            margin_mm: Some(6.0),
            max_incidence_deg: Some(60.0),
            side_pairs: None,
        },
        Variant {
            name: "bipolar All, band and incidence over 45 degrees left out",
            isoangle: None,
            margin_mm: Some(6.0),
            max_incidence_deg: Some(45.0),
            side_pairs: None,
        },
        Variant {
            name:
                "bipolar All, band and incidence over 60 degrees left out, three pole pairs, mean",
            isoangle: None,
            margin_mm: Some(6.0),
            max_incidence_deg: Some(60.0),
            side_pairs: Some(PairCombine::Mean),
        },
        Variant {
            name:
                "bipolar All, band and incidence over 60 degrees left out, three pole pairs, least",
            isoangle: None,
            margin_mm: Some(6.0),
            max_incidence_deg: Some(60.0),
            side_pairs: Some(PairCombine::Least),
        },
    ]
};

/// The entry of [`VARIANTS`] with the least of the three pole pairs (the recognition
/// benchmark's rule), also measured with view matching.
pub(super) const LEAST: usize = 8;
