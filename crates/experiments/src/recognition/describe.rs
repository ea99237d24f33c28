//! The four descriptions of a face (bipolar, single pole, facial curves, iso-curvature) and
//! their settings.

use super::Lm;
use crate::polar::{self, polar_descriptor, PolarOptions, Pole};
use crate::walk::Walker;
use anyhow::{Context, Result};
use bipolar::PolarDescriptor;
use facecurves::nose::{facial_curves, iso_curves, iso_point_set, reference_iso_levels};
use facecurves::{ElasticOptions, FacialCurvesDescriptor, IsoLevels};
use meshcore::{DVec3, Surface, TriMesh};
use shapedist::{PreparedSet, Which};
use std::time::Instant;

/// Points of an iso-curvature network kept for its ICP (every k-th point in curve order).
pub(super) const ISO_POINTS: usize = 2000;

/// The elastic distance of the facial curves in the benchmark: `samples` segments per curve,
/// one start-point candidate and one rotation / reparametrisation alternation (the crate's
/// default is 100, 3 and 2: about 25 times the cost).
pub(super) fn elastic_options(samples: usize) -> ElasticOptions {
    ElasticOptions {
        samples,
        start_candidates: 1,
        iterations: 1,
        ..ElasticOptions::default()
    }
}

/// Per face and landmark set: descriptors, landmark positions and description times.
#[derive(Debug)]
pub(super) struct Described {
    /// The bipolar descriptions ([`facematch::describe_with_fields`]: the three pole pairs, the
    /// pair it is compared by as a probe, with the reference-point search a probe's moved
    /// descriptors), or why there are none.
    pub(super) bip: Result<facematch::Description, String>,
    /// The options of its comparisons ([`facematch::compare`]: least pair, second weight).
    pub(super) matching: facematch::MatchOptions,
    pub(super) pol: PolarDescriptor,
    pub(super) facial: Result<FacialCurvesDescriptor, String>,
    /// The iso-curvature network's points prepared for ICP (the network itself is not kept).
    pub(super) iso: Result<PreparedSet, String>,
    pub(super) lm_pos: [DVec3; 3],
    /// A gallery face's views and their settings, as its template stores them
    /// ([`facematch::views_of`]; `None` for probes and when view matching is off).
    pub(super) views: Option<(Vec<facematch::TemplateView>, facematch::ViewOptions)>,
    /// Wall time of each description (bipolar, single pole, facial curves, iso-curvature): the
    /// geodesic fields it needs (both corners; the nose tip) and its own build.
    pub(super) secs: [f64; 4],
}

/// Descriptor settings of the benchmark.
#[derive(Debug, Clone)]
pub(super) struct DescribeOptions {
    /// Levels N between the outer eye corners (also the facial curves: N levels up to D).
    pub(super) levels: u32,
    /// Sectors of the single-pole descriptor.
    pub(super) sectors: u32,
    /// Iso-curvature levels shared by every face (`None`: not described).
    pub(super) iso_levels: Option<IsoLevels>,
    /// Band next to the mesh boundary left out of the bipolar descriptor (mesh units).
    pub(super) boundary_margin: Option<f64>,
    /// Parts seen at more than this incidence (degrees, scanner along +z) left out of the
    /// bipolar descriptor (`scanprep::incidence_mask`).
    pub(super) max_incidence_deg: Option<f64>,
    /// Reference-point search radius (mesh units) of the probes' bipolar descriptors (`None`:
    /// one descriptor from the given corners).
    pub(super) ref_search: Option<f64>,
    /// View matching of the gallery faces (`Args::view_match`, degrees; `None`: off).
    pub(super) view_match: Option<f64>,
    /// Probes turned by more than this (degrees) are compared by the bipolar descriptor of
    /// their nearer corner and the nose tip (`Args::side_pair`; `None`: always the corners).
    pub(super) side_pair_deg: Option<f64>,
    /// The bipolar score is the least distance over the three pole pairs (the probe's own with
    /// its reference-point search); else the probe's own pair's (`Args::own_pair_only`).
    pub(super) least_pair: bool,
    /// With `least_pair`, the reference-point search moves the poles of all three pairs, not
    /// only the probe's own (the default; `Args::own_pair_search` turns it off).
    pub(super) search_all_pairs: bool,
    /// With `least_pair`, the weight of the second least pair distance in the score
    /// (`Args::pair_second`; 0: the least alone).
    pub(super) second_weight: f64,
    /// Scans: a detected outer eye corner reported unseen is placed at the vertex nearest the
    /// fitted face's prediction (within `MAX_SNAP_MM`) instead of being lost
    /// (`Args::predicted_corners`).
    pub(super) predicted_corners: bool,
}

impl DescribeOptions {
    /// The bipolar settings as `facematch` options (exact geodesics for the views; the caller
    /// sets another method where it uses one): levels, the fields' cut-off of 1.4, the band,
    /// the incidence limit, side pairs, the score's rule, the search's radius in mesh units and
    /// [`SEARCH_DIRECTIONS`], the snap distance of a carried landmark; no gate, no stored views.
    pub(super) fn matching(&self) -> facematch::MatchOptions {
        facematch::MatchOptions {
            method: geodesic::Method::Exact,
            levels: self.levels,
            field_cutoff: FIELD_CUTOFF,
            boundary_margin_mm: self.boundary_margin,
            max_incidence_deg: self.max_incidence_deg,
            side_pair_deg: self.side_pair_deg,
            least_pair: self.least_pair,
            second_weight: self.second_weight,
            search: self.ref_search.map(|r| facematch::SearchOptions {
                radius_mm: r,
                directions: SEARCH_DIRECTIONS,
                all_pairs: self.search_all_pairs,
            }),
            view: None,
            predicted_corners: self.predicted_corners,
            snap_mm: crate::scans::MAX_SNAP_MM,
            gate_mm: None,
            ..facematch::MatchOptions::default()
        }
    }
}

/// The landmarks' fields are cut off at this factor times |q - r|.
const FIELD_CUTOFF: f64 = 1.4;

/// The iso-curvature levels of a benchmark: `count` per principal field from the reference
/// face `mesh` with landmarks `lm` ([`reference_iso_levels`] on its nose disc of radius D).
pub(super) fn iso_levels_of(
    mesh: &TriMesh,
    solver: &dyn geodesic::GeodesicSolver,
    lm: Lm,
    count: usize,
) -> Result<IsoLevels> {
    let f = facematch::face_fields(mesh, solver, lm, FIELD_CUTOFF)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let d = f.scale(lm).map_err(|e| anyhow::anyhow!("{e}"))?;
    reference_iso_levels(&Surface::new(mesh.clone()), &f.un, d, count)
        .context("iso-curvature levels of the reference face")
}

/// The four descriptions of one face for one landmark set: bipolar (static area, grid
/// reading), single pole, facial curves and iso-curvature. Only the static lens (within D of
/// both corners, D ~ 1.1 |q - r|) and radii up to D from the nose tip are used: the fields are
/// cut off at 1.4 |q - r|. Errors name what failed (a descriptor the crate refuses is kept as
/// its error; an empty single-pole one is the empty set).
pub(super) fn describe_face(
    mesh: &TriMesh,
    solver: &dyn geodesic::GeodesicSolver,
    walker: &Walker<'_>,
    lm: Lm,
    o: &DescribeOptions,
) -> Result<Described, String> {
    let f = facematch::face_fields(mesh, solver, lm, FIELD_CUTOFF)?;
    let [r, q, nose] = lm.positions(mesh);
    let (t_corners, t_nose) = (f.secs[0] + f.secs[1], f.secs[2]);
    let t = Instant::now();
    let t_surface = Instant::now();
    let surface = Surface::new(mesh.clone());
    let t_surface = t_surface.elapsed().as_secs_f64();
    let matching = o.matching();
    let bip = facematch::describe_with_fields(
        &surface,
        solver,
        &f,
        lm,
        crate::scans::SCANNER_SIDE,
        None,
        &matching,
        o.ref_search.is_some(),
    )
    .map_err(|e| e.to_string());
    let t_bip = t.elapsed().as_secs_f64();
    // The descriptions scaled by D need both corners.
    let scale = f.scale(lm);
    let d = scale.clone().unwrap_or(f64::NAN);
    let opts = PolarOptions {
        step: d / f64::from(o.levels),
        levels: o.levels,
        sectors: o.sectors,
    };
    let t = Instant::now();
    let pol = match scale {
        Ok(_) => polar_descriptor(walker, &f.un, Pole::Vertex(lm.nose), 0.5 * (r + q), &opts)
            .unwrap_or_else(|_| polar::empty(&opts)),
        Err(_) => polar::empty(&opts),
    };
    let t_pol = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let facial = scale.clone().and_then(|d| {
        facial_curves(&surface, &f.un, d, o.levels).map_err(|e| format!("facial curves: {e}"))
    });
    let t_facial = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let iso = match &o.iso_levels {
        Some(l) => scale.and_then(|d| {
            iso_curves(&surface, &f.un, d, l)
                .map_err(|e| format!("iso-curvature: {e}"))
                .and_then(|c| {
                    iso_point_set(&c, Which::B, Some(ISO_POINTS))
                        .map_err(|e| format!("iso-curvature points: {e}"))
                })
        }),
        None => Err("iso-curvature: no levels".to_string()),
    };
    let t_iso = t.elapsed().as_secs_f64();
    Ok(Described {
        bip,
        matching,
        pol,
        facial,
        iso,
        lm_pos: [r, q, nose],
        views: None,
        secs: [
            t_corners + t_bip,
            t_nose + t_pol,
            t_nose + t_surface + t_facial,
            t_nose + t_surface + t_iso,
        ],
    })
}

/// Directions of the reference-point search around each pole (both recognition benchmarks).
pub(super) const SEARCH_DIRECTIONS: usize = 6;
