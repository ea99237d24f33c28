//! The four descriptions of a face (bipolar, single pole, facial curves, iso-curvature) and
//! their settings.

use super::{Args, Lm};
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
    /// Sectors of the single-pole descriptor.
    pub(super) sectors: u32,
    /// Iso-curvature levels shared by every face (`None`: not described).
    pub(super) iso_levels: Option<IsoLevels>,
    /// The bipolar descriptions and their comparisons (`facematch`, in mesh units): its levels
    /// N between the outer eye corners are also the single pole's and the facial curves'; its
    /// `search` is the probes' reference-point search, its `view` the gallery faces' view
    /// matching (`None`: off).
    pub(super) matching: facematch::MatchOptions,
}

impl DescribeOptions {
    /// The settings `args` give, the iso-curvature levels not yet set: facematch's defaults
    /// with the flags' values, exact geodesics for the views (the caller sets another method
    /// where it uses one), no gate. On clean meshes (`scans` false, cm) only the search is
    /// taken from the flags (its radius converted from mm), for the outer eye corners' pair.
    pub(super) fn of_args(args: &Args, scans: bool) -> Self {
        let on = |x: f64| (scans && x > 0.0).then_some(x);
        let mm_per_unit = if scans {
            1.0
        } else {
            meshcore::units::Units::Centimetre.mm_per_unit()
        };
        let matching = facematch::MatchOptions {
            method: geodesic::Method::Exact,
            levels: args.res.levels,
            boundary_margin_mm: on(args.boundary_margin),
            max_incidence_deg: on(args.max_incidence),
            side_pair_deg: (scans && !args.no_side_pair).then_some(args.side_pair),
            least_pair: scans && !(args.no_side_pair || args.own_pair_only),
            second_weight: if scans { args.pair_second } else { 0.0 },
            search: (args.ref_search > 0.0).then(|| facematch::SearchOptions {
                radius_mm: args.ref_search / mm_per_unit,
                all_pairs: scans && !args.own_pair_search,
                ..facematch::SearchOptions::default()
            }),
            view: (scans && !args.no_view_match).then(|| facematch::ViewOptions {
                min_angle_deg: args.view_match,
                ..facematch::ViewOptions::default()
            }),
            predicted_corners: scans && args.predicted_corners,
            gate_mm: None,
            ..facematch::MatchOptions::default()
        };
        Self {
            sectors: args.res.sectors,
            iso_levels: None,
            matching,
        }
    }

    /// The same settings without the reference-point search: the gallery's.
    pub(super) fn without_search(&self) -> Self {
        let mut o = self.clone();
        o.matching.search = None;
        o
    }
}

/// The iso-curvature levels of a benchmark: `count` per principal field from the reference
/// face `mesh` with landmarks `lm` ([`reference_iso_levels`] on its nose disc of radius D; the
/// fields cut off as facematch's default cuts them).
pub(super) fn iso_levels_of(
    mesh: &TriMesh,
    solver: &dyn geodesic::GeodesicSolver,
    lm: Lm,
    count: usize,
) -> Result<IsoLevels> {
    let cutoff = facematch::MatchOptions::default().field_cutoff;
    let f = facematch::face_fields(mesh, solver, lm, cutoff).map_err(|e| anyhow::anyhow!("{e}"))?;
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
    let matching = &o.matching;
    let f = facematch::face_fields(mesh, solver, lm, matching.field_cutoff)?;
    let [r, q, nose] = lm.positions(mesh);
    let (t_corners, t_nose) = (f.secs[0] + f.secs[1], f.secs[2]);
    let t = Instant::now();
    let t_surface = Instant::now();
    let surface = Surface::new(mesh.clone());
    let t_surface = t_surface.elapsed().as_secs_f64();
    let bip = facematch::describe_with_fields(
        &surface,
        solver,
        &f,
        lm,
        crate::scans::SCANNER_SIDE,
        None,
        matching,
        matching.search.is_some(),
    )
    .map_err(|e| e.to_string());
    let t_bip = t.elapsed().as_secs_f64();
    // The descriptions scaled by D need both corners.
    let scale = f.scale(lm);
    let d = scale.clone().unwrap_or(f64::NAN);
    let opts = PolarOptions {
        step: d / f64::from(matching.levels),
        levels: matching.levels,
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
        facial_curves(&surface, &f.un, d, matching.levels)
            .map_err(|e| format!("facial curves: {e}"))
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
        matching: matching.clone(),
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
