//! `cargo xtask recognition`: identification and verification on faces sampled from the ICT
//! face model, for the bipolar descriptor, the single-pole descriptor, ICP on the raw meshes and
//! the two curve representations of the paper's section 6 (facial curves, iso-curvature curves:
//! `experiments::curves`), each with ground-truth and with detected landmarks, with the time
//! per comparison and per description.
//!
//! N identities x M expressions are sampled (seeded); expression 0 of every identity is the
//! neutral face and forms the gallery, the M - 1 others are the probes. Every face is moved by
//! a random rigid motion, so nothing can rely on a shared frame. Scores are distances (lower =
//! more similar): rank-1 identification rate over the probes, verification EER over all
//! probe x gallery pairs, and the ROC curve. Results: `report.md`, `summary.json`, `roc.svg` (and `roc.png`),
//! CSV tables, in the output folder printed on the last line.

mod metrics;
mod pool;
mod scans;

use metrics::*;

use crate::curves::{
    facial_curves, facial_distance, iso_curves, iso_distance_from, iso_point_set,
    reference_iso_levels,
};
use crate::paths::{ModelArgs, ResolutionArgs};
use crate::pipeline::{bar, dist, resolve_methods, single_thread};
use crate::polar::{self, polar_descriptor, PolarOptions, Pole};
use crate::report::{f4, line_plot, Report, Series};
use crate::scans::ScanArgs;
use crate::walk::Walker;
use anyhow::{bail, Context, Result};
use bipolar::PolarDescriptor;
use facecurves::{ElasticOptions, FacialCurvesDescriptor, IsoLevels};
use facemodel::{random_rigid_motion, FaceModel};
use meshcore::linalg::fit_rigid;
use meshcore::{DVec3, FaceLocator, Surface, TriMesh};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use shapedist::{IcpOptions, IcpVariant, PreparedSet, Which};
use std::time::Instant;

/// Arguments of `cargo xtask recognition`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Number of sampled identities (default 50; with `--scans` 16).
    #[arg(long)]
    pub identities: Option<usize>,
    /// Faces per identity, the first neutral for the gallery (default 6; with `--scans` 3).
    #[arg(long)]
    pub expressions: Option<usize>,
    /// Seed of the sampling.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
    /// Geodesic method (exact falls back to fmm, then heat, if unavailable).
    #[arg(long, default_value = "exact")]
    pub method: String,
    /// Descriptor resolution.
    #[command(flatten)]
    pub res: ResolutionArgs,
    /// Levels per principal field of the iso-curvature network (between the 5 % and 95 %
    /// quantiles of the first gallery face's curvatures, the same levels for every face).
    #[arg(long = "iso-levels", default_value_t = 6)]
    pub iso_levels: usize,
    /// Segments each facial curve is resampled into for the elastic distance.
    #[arg(long = "curve-samples", default_value_t = CURVE_SAMPLES)]
    pub curve_samples: usize,
    /// Probe vertices used by ICP (evenly strided).
    #[arg(long, default_value_t = 100)]
    pub icp_points: usize,
    /// ICT model folder and output folder (default `target/recognition`; with `--scans`
    /// `target/recognition-scans`).
    #[command(flatten)]
    pub io: ModelArgs,
    /// Recognition on range scans (`rangescan`, cleaned by `scanprep`): neutral frontal scans
    /// (the `--scan-*` settings) as the gallery, expressions under yaw and noise as probes, and
    /// sweeps of noise, pitch and yaw.
    #[arg(long)]
    pub scans: bool,
    /// Scanner settings of the gallery (and the reference of the sweeps) with `--scans`.
    #[command(flatten)]
    pub scan: ScanArgs,
    /// Target edge length (mm) the cleaned scans are decimated to before detection and
    /// description (`--scans`; 0 keeps the scan's sampling).
    #[arg(long, default_value_t = SCAN_EDGE_MM)]
    pub scan_edge: f64,
    /// Taubin smoothing iterations of the cleaned scans, before the decimation (`--scans`; 0:
    /// none).
    #[arg(long, default_value_t = 0)]
    pub scan_smooth: usize,
    /// Taubin smoothing iterations of a copy of each cleaned scan that landmark detection runs
    /// on (`--scans`; the landmarks keep their vertices; 0: detection on the scan itself).
    #[arg(long, default_value_t = 0)]
    pub detect_smooth: usize,
    /// Identities whose probes are rescanned at every sweep setting (`--scans`).
    #[arg(long, default_value_t = 4)]
    pub sweep_identities: usize,
    /// Skip the sweeps (`--scans`).
    #[arg(long)]
    pub no_sweeps: bool,
    /// Band (mm) along the holes and the border of each cleaned scan that the bipolar
    /// descriptor leaves out (`--scans`; 0 keeps everything).
    #[arg(long, default_value_t = SCAN_BOUNDARY_MARGIN_MM)]
    pub boundary_margin: f64,
    /// Parts of each scan seen at more than this incidence (degrees) left out of the bipolar
    /// descriptor (`--scans`; 0 keeps everything).
    #[arg(long, default_value_t = SCAN_MAX_INCIDENCE_DEG)]
    pub max_incidence: f64,
    /// Reference-point search of the bipolar score (mm, 0: off; on the clean meshes the outer
    /// eye corners' pair alone, as their only pair): each probe is also
    /// described by each pole pair (the outer eye corners; each corner with the nose tip) from
    /// its two poles moved by this distance in 6 directions of their tangent planes (48 more
    /// descriptors per pair; only the probe's own pair with `--own-pair-search`), and its
    /// distance by a pair is the least over the pair's 49 descriptors.
    #[arg(long, default_value_t = SCAN_REF_SEARCH_MM)]
    pub ref_search: f64,
    /// View matching of the bipolar score (`--scans`; degrees): when a probe's scanner
    /// direction, carried into a gallery face's frame by the landmark alignment, is more than
    /// this angle from the gallery scan's own, the probe is compared with the gallery face's
    /// template view nearest that direction (`facematch::views_of`: the face described on the
    /// part of it a scanner turned by 15, 25, 35 or 45 degrees to either side would see,
    /// `rangescan::visible_faces`, incidence up to 75 degrees), so that both sides miss the
    /// same surface.
    #[arg(long, default_value_t = SCAN_VIEW_MATCH_DEG)]
    pub view_match: f64,
    /// No view matching (`--scans`): every probe is compared with the gallery face's one
    /// description.
    #[arg(long)]
    pub no_view_match: bool,
    /// Write every raw scan of the run (gallery, probes, sweeps) to this folder as `NAME.bnt`
    /// (`--scans`), for `bipolar enroll` / `identify` on the benchmark's own scans.
    #[arg(long)]
    pub save_scans: Option<std::path::PathBuf>,
    /// Side pairs of the bipolar score (`--scans`; degrees): a probe whose eye line is turned
    /// from its scanner by more than this is compared by the bipolar descriptor of its outer
    /// eye corner nearer the scanner and its nose tip (the gallery faces are described by
    /// both side pairs), not by its two corners, whose far one its scanner barely saw.
    #[arg(long, default_value_t = SCAN_SIDE_PAIR_DEG)]
    pub side_pair: f64,
    /// No side pairs (`--scans`): every probe is compared by its outer eye corners.
    #[arg(long)]
    pub no_side_pair: bool,
    /// The bipolar score of a probe is its distance by its own pole pair alone (the corners,
    /// or its side pair past `--side-pair`), not the least distance over the three pairs
    /// (`--scans`).
    #[arg(long)]
    pub own_pair_only: bool,
    /// The reference-point search (`--ref-search`) moves only the poles of the probe's own
    /// pair (`--scans`; the former default): 12 moved fields and 48 more descriptors per probe.
    /// By default, with the least over the three pairs, it moves the poles of all three: 18
    /// moved fields and 144 more descriptors.
    #[arg(long)]
    pub own_pair_search: bool,
    /// Weight of the second least pair distance in the bipolar score with the least over the
    /// three pairs (`--scans`; 0, the default: the least alone; 0.25 gives 0.75 x least + 0.25 x
    /// second least, which asks two pairs to agree).
    #[arg(long, default_value_t = 0.0)]
    pub pair_second: f64,
    /// Scan, clean and detect the landmarks of the gallery, probe and sweep scans, write
    /// `detection.csv` (per scan: the detected landmarks' errors or why detection failed) and
    /// a report of the errors and landmarks placed against the yaw, and stop, without
    /// describing or comparing (`--scans`).
    #[arg(long)]
    pub detect_only: bool,
    /// An outer eye corner the detector reports unseen is placed at the vertex nearest where
    /// the fitted face predicts it (within 3 mm of the cleaned scan) instead of being lost, so
    /// that the corners' pair and its side pair still describe the face (`--scans`; the
    /// landmark stays unseen in `detection.csv` and `landmarks.csv`).
    #[arg(long)]
    pub predicted_corners: bool,
    /// Keep only the probes (and sweep scans) whose name starts with one of these
    /// (comma-separated, e.g. `id01-e2,id27`; `--scans`), against the whole gallery: their
    /// ranks are those of the whole run.
    #[arg(long, value_delimiter = ',')]
    pub only_probes: Vec<String>,
    /// Run the benchmark once per seed (comma-separated; `--seed` is then ignored), each into
    /// `OUT/seed-S/`, and pool the runs probe by probe into `OUT/report.md` and `pooled.csv`:
    /// rank-1 over all the seeds' probes with its 95 % interval, the mean EER, the paired
    /// comparison with McNemar's test.
    #[arg(long, value_delimiter = ',')]
    pub seeds: Vec<u64>,
    /// With `--seeds`: pool the runs already in `OUT/seed-S/` without running them.
    #[arg(long, requires = "seeds")]
    pub pool_only: bool,
    /// Keep only these identities (comma-separated numbers, `--scans`): their gallery scans,
    /// probes and sweep scans, with the scan seeds, yaws and noises of the whole run, so that a
    /// run's misses can be rerun and looked at in a minute (ranks are then among these
    /// identities only).
    #[arg(long, value_delimiter = ',')]
    pub only_identities: Vec<usize>,
}

/// One sampled face.
#[derive(Debug)]
struct Sample {
    identity: usize,
    index: usize,
    mesh: TriMesh,
}

/// The reference vertices of a face (outer eye corners, nose tip; a lost corner explicit):
/// `facematch`'s, as are the pole pairs.
type Lm = facematch::Poles;

/// Default of `--scan-edge`, mm.
const SCAN_EDGE_MM: f64 = 1.5;

/// Default of `--boundary-margin`: the band next to the holes where the fields of two scans
/// disagree most (docs/scans.md, "Yaw").
const SCAN_BOUNDARY_MARGIN_MM: f64 = 6.0;

/// The default of `--max-incidence`, chosen on scan-study (60 degrees raised every same-face
/// figure and kept the other-person minimum; 45 degrees left too few shared keys on the face
/// mesh; docs/scans.md, "Grazing incidence").
const SCAN_MAX_INCIDENCE_DEG: f64 = 60.0;

/// The default of `--ref-search`: 2 mm raised bipolar with detected landmarks from 0.656 to
/// 0.750 (16 identities) and from 0.550 to 0.690 (50) and kept or raised it with ground truth;
/// 1.2 and 3 mm differ from it by one probe on 16 identities (docs/scans.md, "Reference-point
/// search").
const SCAN_REF_SEARCH_MM: f64 = 2.0;

/// The default of `--view-match` (degrees). Not tuned: below it a probe is near frontal, its
/// scanner saw what the gallery's did, and the gallery's own description is used.
pub(crate) const SCAN_VIEW_MATCH_DEG: f64 = 10.0;

/// The default of `--side-pair` (degrees), chosen on 16 identities: 25 moved one probe from
/// rank 1 to 3 and gained nothing else (docs/scans.md, "Side pairs and lost corners").
const SCAN_SIDE_PAIR_DEG: f64 = 30.0;

/// Default of `--curve-samples`.
const CURVE_SAMPLES: usize = 50;

/// Points of an iso-curvature network kept for its ICP (every k-th point in curve order).
const ISO_POINTS: usize = 2000;

/// The ICP of the iso-curvature networks, started from the landmark alignment: 10
/// point-to-point iterations on a 500-point subsample, then at most 10 on all points (the
/// other settings those of `shapedist`'s global refinement).
const ISO_ICP: IcpOptions = IcpOptions {
    variant: IcpVariant::PointToPoint,
    max_iterations: 10,
    tolerance: 1e-6,
    trim: 0.0,
    translation: false,
    coarse_iterations: 10,
};

/// The elastic distance of the facial curves in the benchmark: `samples` segments per curve,
/// one start-point candidate and one rotation / reparametrisation alternation (the crate's
/// default is 100, 3 and 2: about 25 times the cost).
fn elastic_options(samples: usize) -> ElasticOptions {
    ElasticOptions {
        samples,
        start_candidates: 1,
        iterations: 1,
        ..ElasticOptions::default()
    }
}

/// Per face and landmark set: descriptors, landmark positions and description times.
#[derive(Debug)]
struct Described {
    /// The bipolar descriptions ([`facematch::describe_with_fields`]: the three pole pairs, the
    /// pair it is compared by as a probe, with the reference-point search a probe's moved
    /// descriptors), or why there are none.
    bip: Result<facematch::Description, String>,
    /// The options of its comparisons ([`facematch::compare`]: least pair, second weight).
    matching: facematch::MatchOptions,
    pol: PolarDescriptor,
    facial: Result<FacialCurvesDescriptor, String>,
    /// The iso-curvature network's points prepared for ICP (the network itself is not kept).
    iso: Result<PreparedSet, String>,
    lm_pos: [DVec3; 3],
    /// A gallery face's views and their settings, as its template stores them
    /// ([`facematch::views_of`]; `None` for probes and when view matching is off).
    views: Option<(Vec<facematch::TemplateView>, facematch::ViewOptions)>,
    /// Wall time of each description (bipolar, single pole, facial curves, iso-curvature): the
    /// geodesic fields it needs (both corners; the nose tip) and its own build.
    secs: [f64; 4],
}

/// Descriptor settings of the benchmark.
#[derive(Debug, Clone)]
struct DescribeOptions {
    /// Levels N between the outer eye corners (also the facial curves: N levels up to D).
    levels: u32,
    /// Sectors of the single-pole descriptor.
    sectors: u32,
    /// Iso-curvature levels shared by every face (`None`: not described).
    iso_levels: Option<IsoLevels>,
    /// Band next to the mesh boundary left out of the bipolar descriptor (mesh units).
    boundary_margin: Option<f64>,
    /// Parts seen at more than this incidence (degrees, scanner along +z) left out of the
    /// bipolar descriptor (`scanprep::incidence_mask`).
    max_incidence_deg: Option<f64>,
    /// Reference-point search radius (mesh units) of the probes' bipolar descriptors (`None`:
    /// one descriptor from the given corners).
    ref_search: Option<f64>,
    /// View matching of the gallery faces (`Args::view_match`, degrees; `None`: off).
    view_match: Option<f64>,
    /// Probes turned by more than this (degrees) are compared by the bipolar descriptor of
    /// their nearer corner and the nose tip (`Args::side_pair`; `None`: always the corners).
    side_pair_deg: Option<f64>,
    /// The bipolar score is the least distance over the three pole pairs (the probe's own with
    /// its reference-point search); else the probe's own pair's (`Args::own_pair_only`).
    least_pair: bool,
    /// With `least_pair`, the reference-point search moves the poles of all three pairs, not
    /// only the probe's own (the default; `Args::own_pair_search` turns it off).
    search_all_pairs: bool,
    /// With `least_pair`, the weight of the second least pair distance in the score
    /// (`Args::pair_second`; 0: the least alone).
    second_weight: f64,
    /// Scans: a detected outer eye corner reported unseen is placed at the vertex nearest the
    /// fitted face's prediction (within `MAX_SNAP_MM`) instead of being lost
    /// (`Args::predicted_corners`).
    predicted_corners: bool,
}

impl DescribeOptions {
    /// The bipolar settings as `facematch` options (exact geodesics for the views; the caller
    /// sets another method where it uses one): levels, the fields' cut-off of 1.4, the band,
    /// the incidence limit, side pairs, the score's rule, the search's radius in mesh units and
    /// [`SEARCH_DIRECTIONS`], the snap distance of a carried landmark; no gate, no stored views.
    fn matching(&self) -> facematch::MatchOptions {
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
fn iso_levels_of(
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
fn describe_face(
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

/// Directions of the reference-point search around each pole (the recognition benchmarks and
/// scan-study).
pub(crate) const SEARCH_DIRECTIONS: usize = 6;

/// Iterations of the recognition ICP ([`crate::pipeline::trimmed_icp`]).
const ICP_ITERATIONS: usize = 6;

/// ICP of the probe points onto the gallery surface, started from the landmark alignment
/// ([`crate::pipeline::landmark_icp_rms`]); returns the RMS closest-point distance of all probe
/// points at the final pose (cm), NaN when a step fails.
fn icp_score(
    probe: &[DVec3],
    probe_lm: &[DVec3; 3],
    gallery: &FaceLocator<'_>,
    gallery_lm: &[DVec3; 3],
) -> f64 {
    crate::pipeline::landmark_icp_rms(probe, probe_lm, gallery, gallery_lm, ICP_ITERATIONS)
}

/// About `n` vertices of a probe for ICP, evenly strided.
fn icp_points(mesh: &TriMesh, n: usize) -> Vec<DVec3> {
    let stride = (mesh.n_vertices() / n.max(3)).max(1);
    mesh.positions().iter().step_by(stride).copied().collect()
}

/// A probe `x` compared with a gallery face `y` by [`facematch::compare`], as with `y`'s
/// template (view matching against its stored view nearest the probe's scanner direction; per
/// pair the least over the probe's own and moved descriptors), or `None` when a side has no
/// descriptions.
fn bipolar_compare(x: &Described, y: &Described) -> Option<facematch::Comparison> {
    let (Ok(xd), Ok(yd)) = (&x.bip, &y.bip) else {
        return None;
    };
    let template = facematch::Template {
        identity: String::new(),
        source: String::new(),
        settings: String::new(),
        description: yd.clone(),
        views: y.views.as_ref().map_or(Vec::new(), |v| v.0.clone()),
        notes: Vec::new(),
    };
    let o = facematch::MatchOptions {
        view: y.views.as_ref().map(|v| v.1.clone()),
        ..x.matching.clone()
    };
    Some(facematch::compare(xd, &template, &o))
}

/// The bipolar distance of a probe `x` to a gallery face `y` by each pole pair (NaN where a
/// side has no descriptor or the distance fails; [`bipolar_compare`]) and the kinds of the
/// fallbacks the comparison took ([`facematch::Comparison::fallback_kinds`]).
fn bipolar_pairs(x: &Described, y: &Described) -> PairDistances {
    bipolar_compare(x, y).map_or(([f64::NAN; 3], Vec::new()), |c| {
        (c.pairs.map(|u| u.distance), c.fallback_kinds())
    })
}

/// The bipolar distances of one comparison by each pole pair, and the kinds of its fallbacks.
type PairDistances = ([f64; 3], Vec<String>);

/// The bipolar score of a probe `x` from its distances by each pair `d` ([`bipolar_pairs`]):
/// [`facematch::pair_score`] with the probe's pair and its options.
fn bipolar_score(x: &Described, d: [f64; 3]) -> f64 {
    match &x.bip {
        Ok(xd) => {
            facematch::pair_score(d, xd.pair, x.matching.least_pair, x.matching.second_weight).0
        }
        Err(_) => f64::NAN,
    }
}

/// Score `k` of [`SCORES`] of a probe (its description `x` and ICP points `pts`) against a
/// gallery face (`y`, its surface `loc`); NaN when a description is missing or the score
/// fails.
fn score_one(
    k: usize,
    x: &Described,
    pts: &[DVec3],
    y: &Described,
    loc: &FaceLocator<'_>,
    elastic: &ElasticOptions,
) -> f64 {
    match k {
        0 => bipolar_score(x, bipolar_pairs(x, y).0),
        1 => dist(&x.pol, &y.pol).unwrap_or(f64::NAN),
        2 => icp_score(pts, &x.lm_pos, loc, &y.lm_pos),
        3 => match (&x.facial, &y.facial) {
            (Ok(a), Ok(b)) => facial_distance(a, b, elastic).unwrap_or(f64::NAN),
            _ => f64::NAN,
        },
        _ => match (&x.iso, &y.iso) {
            (Ok(a), Ok(b)) => fit_rigid(&x.lm_pos, &y.lm_pos, None).map_or(f64::NAN, |m| {
                iso_distance_from(b, a, m.matrix3, &ISO_ICP).unwrap_or(f64::NAN)
            }),
            _ => f64::NAN,
        },
    }
}

/// Scores of one probe against every gallery face, per score of [`SCORES`] (NaN where either
/// side has no description or the score fails).
type Row = [Vec<f64>; 5];

/// Scores of one probe (its description and ICP points) against every gallery face: bipolar,
/// single pole, ICP, facial curves (elastic distance with `elastic`) and iso-curvature (ICP of
/// the networks' points from the landmark alignment); with the bipolar distance by each pair
/// and the comparison's fallbacks ([`bipolar_pairs`]).
fn score_row(
    probe: Option<&Described>,
    pts: &[DVec3],
    gallery: &[Option<(&Described, &FaceLocator<'_>)>],
    elastic: &ElasticOptions,
) -> (Row, Vec<PairDistances>) {
    let pairs: Vec<PairDistances> = gallery
        .iter()
        .map(|g| match (probe, g) {
            (Some(x), Some((y, _))) => bipolar_pairs(x, y),
            _ => ([f64::NAN; 3], Vec::new()),
        })
        .collect();
    let row = std::array::from_fn(|k| {
        gallery
            .iter()
            .zip(&pairs)
            .map(|(g, d)| match (probe, g) {
                (Some(x), Some(_)) if k == 0 => bipolar_score(x, d.0),
                (Some(x), Some((y, loc))) => score_one(k, x, pts, y, loc, elastic),
                _ => f64::NAN,
            })
            .collect()
    });
    (row, pairs)
}

/// Faces whose descriptions are timed (single thread).
const TIMED_FACES: usize = 6;

/// Pairs timed per landmark set (single thread).
const TIMED_PAIRS: usize = 24;

/// Mean single-thread wall time (ms) of each score of [`SCORES`] over `pairs` (probe, its ICP
/// points, gallery face, its surface), run on a one-thread pool after the parallel scoring.
fn time_comparisons(
    pairs: &[(&Described, &[DVec3], &Described, &FaceLocator<'_>)],
    elastic: &ElasticOptions,
) -> Result<[f64; 5]> {
    let (ms, _) = single_thread(|| {
        std::array::from_fn(|k| {
            let t = Instant::now();
            for (x, pts, y, loc) in pairs {
                std::hint::black_box(score_one(k, x, pts, y, loc, elastic));
            }
            1e3 * t.elapsed().as_secs_f64() / pairs.len().max(1) as f64
        })
    })?;
    Ok(ms)
}

/// Up to [`TIMED_PAIRS`] probe x gallery pairs where both faces are described: probes in
/// order, each against the gallery faces in turn.
fn timed_pairs<'a>(
    probes: &[(Option<&'a Described>, &'a [DVec3])],
    gallery: &[Option<(&'a Described, &'a FaceLocator<'a>)>],
) -> Vec<(
    &'a Described,
    &'a [DVec3],
    &'a Described,
    &'a FaceLocator<'a>,
)> {
    let mut out = Vec::new();
    for (i, (p, pts)) in probes.iter().enumerate() {
        let Some(p) = p else { continue };
        let g = gallery
            .iter()
            .skip(i % gallery.len().max(1))
            .flatten()
            .next();
        if let Some((y, loc)) = g {
            out.push((*p, *pts, *y, *loc));
        }
        if out.len() == TIMED_PAIRS {
            break;
        }
    }
    out
}

/// Median single-thread wall time (ms) of each description (bipolar, single pole, facial
/// curves, iso-curvature: their fields and builds) over `faces`, described again on a
/// one-thread pool.
fn time_descriptions(
    faces: &[(&TriMesh, Lm)],
    method: geodesic::Method,
    o: &DescribeOptions,
) -> Result<[f64; 4]> {
    let (secs, _) = single_thread(|| -> Result<Vec<[f64; 4]>> {
        let mut v = Vec::new();
        for (mesh, lm) in faces {
            let solver = geodesic::new_solver(mesh, method)?;
            let walker = Walker::new(mesh);
            if let Ok(d) = describe_face(mesh, solver.as_ref(), &walker, *lm, o) {
                v.push(d.secs);
            }
        }
        Ok(v)
    })?;
    let secs = secs?;
    Ok(std::array::from_fn(|k| {
        1e3 * median(secs.iter().map(|s| s[k]).collect())
    }))
}

/// Runs the benchmark; prints the output folder on the last line.
pub fn run(args: Args) -> Result<()> {
    if !args.seeds.is_empty() {
        return pool::run(args);
    }
    let t0 = Instant::now();
    let model_dir = args.io.model_dir();
    let model = FaceModel::load(&model_dir)
        .with_context(|| format!("loading the ICT model from {}", model_dir.display()))?;
    if args.scans {
        return scans::run(&args, &model, t0);
    }
    let identities = args.identities.unwrap_or(50);
    let expressions = args.expressions.unwrap_or(6);
    if identities < 2 || expressions < 2 {
        bail!("need at least 2 identities and 2 expressions (one neutral gallery face + probes)");
    }
    let out = args.io.out.out_dir("recognition");
    let gt = Lm {
        lost: None,
        r: model.landmark_id("right_eye_outer")?,
        q: model.landmark_id("left_eye_outer")?,
        nose: model.landmark_id("nose_tip")?,
    };
    // Sampling (sequential: deterministic).
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let mut samples = Vec::new();
    for id in 0..identities {
        let w = model.random_identity(&mut rng);
        for e in 0..expressions {
            let ew = if e == 0 {
                vec![0.0; model.n_expressions()]
            } else {
                model.random_expression(&mut rng)
            };
            let mesh = model.sample(&w, &ew)?;
            let motion = random_rigid_motion(&mut rng, 5.0);
            let (pos, tri) = mesh.into_parts();
            let pos = pos
                .into_iter()
                .map(|p| motion.transform_point3(p))
                .collect();
            samples.push(Sample {
                identity: id,
                index: e,
                mesh: TriMesh::new(pos, tri)?,
            });
        }
    }
    let methods = resolve_methods(&args.method, &samples[0].mesh)?;
    let method = methods[0].used;
    let method_note = methods[0].note.clone();
    eprintln!(
        "{} faces sampled ({} identities x {}); geodesics: {}",
        samples.len(),
        identities,
        expressions,
        method.name()
    );
    // Iso-curvature levels: from the first gallery face (ground-truth landmarks).
    let iso_levels = {
        let s = &samples[0];
        let solver = geodesic::new_solver(&s.mesh, method)?;
        iso_levels_of(&s.mesh, solver.as_ref(), gt, args.iso_levels)?
    };
    let desc_opts = DescribeOptions {
        levels: args.res.levels,
        sectors: args.res.sectors,
        iso_levels: Some(iso_levels),
        boundary_margin: None,
        max_incidence_deg: None,
        ref_search: None,
        view_match: None,
        side_pair_deg: None,
        least_pair: false,
        search_all_pairs: false,
        second_weight: 0.0,
        predicted_corners: false,
    };
    // The reference-point search is the probes' (the gallery keeps its one description); its
    // radius is given in mm, the model is in cm.
    let probe_opts = DescribeOptions {
        ref_search: (args.ref_search > 0.0)
            .then(|| args.ref_search / meshcore::units::Units::Centimetre.mm_per_unit()),
        ..desc_opts.clone()
    };
    let elastic = elastic_options(args.curve_samples);
    // Landmark detection.
    let generic = landmarks::GenericModel::default_model()
        .map_err(|e| anyhow::anyhow!("landmark model: {e}"))?;
    let pb = bar(samples.len(), "detecting landmarks");
    let detected: Vec<Option<Lm>> = samples
        .par_iter()
        .map(|s| {
            let r = landmarks::detect(&s.mesh, &generic).ok().map(|l| {
                Lm::new(
                    l.outer_eye_right.vertex,
                    l.outer_eye_left.vertex,
                    l.nose_tip.vertex,
                )
            });
            pb.inc(1);
            r
        })
        .collect();
    pb.finish();
    let det_err: Vec<[f64; 3]> = samples
        .iter()
        .zip(&detected)
        .filter_map(|(s, d)| {
            d.map(|d| {
                [(gt.r, d.r), (gt.q, d.q), (gt.nose, d.nose)]
                    .map(|(a, b)| (s.mesh.position(a) - s.mesh.position(b)).length())
            })
        })
        .collect();
    // Descriptors for both landmark sets.
    let pb = bar(samples.len(), &format!("descriptors ({})", method.name()));
    let described: Vec<[Option<Described>; 2]> = samples
        .par_iter()
        .zip(&detected)
        .map(|(s, det)| -> Result<_> {
            let solver = geodesic::new_solver(&s.mesh, method)?;
            let walker = Walker::new(&s.mesh);
            let o = if s.index == 0 {
                &desc_opts
            } else {
                &probe_opts
            };
            let out = [Some(gt), *det].map(|lm| {
                lm.and_then(|lm| describe_face(&s.mesh, solver.as_ref(), &walker, lm, o).ok())
            });
            pb.inc(1);
            Ok(out)
        })
        .collect::<Result<_>>()?;
    pb.finish();
    let gallery: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].index == 0)
        .collect();
    let probes: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].index != 0)
        .collect();
    let gid: Vec<usize> = gallery.iter().map(|&g| samples[g].identity).collect();
    let pid: Vec<usize> = probes.iter().map(|&p| samples[p].identity).collect();
    let locators: Vec<FaceLocator<'_>> = gallery
        .iter()
        .map(|&g| FaceLocator::new(&samples[g].mesh))
        .collect();
    let mut all = Vec::new();
    let pb = bar(2 * probes.len(), "scoring");
    let probe_pts: Vec<Vec<DVec3>> = probes
        .iter()
        .map(|&p| icp_points(&samples[p].mesh, args.icp_points))
        .collect();
    let mut timed = Vec::new();
    for k in [0, 1] {
        let gal: Vec<Option<(&Described, &FaceLocator<'_>)>> = gallery
            .iter()
            .zip(&locators)
            .map(|(&g, l)| described[g][k].as_ref().map(|d| (d, l)))
            .collect();
        let rows: Vec<Row> = probes
            .par_iter()
            .zip(&probe_pts)
            .map(|(&p, pts)| {
                let (r, _) = score_row(described[p][k].as_ref(), pts, &gal, &elastic);
                pb.inc(1);
                r
            })
            .collect();
        let pr: Vec<(Option<&Described>, &[DVec3])> = probes
            .iter()
            .zip(&probe_pts)
            .map(|(&p, pts)| (described[p][k].as_ref(), pts.as_slice()))
            .collect();
        timed.push((rows, time_comparisons(&timed_pairs(&pr, &gal), &elastic)?));
    }
    pb.finish();
    // Description times: the first gallery faces again, one at a time on one thread.
    let first: Vec<(&TriMesh, Lm)> = gallery
        .iter()
        .take(TIMED_FACES)
        .map(|&g| (&samples[g].mesh, gt))
        .collect();
    let ms_desc = time_descriptions(&first, method, &probe_opts)?;
    for ((rows, ms_cmp), lname) in timed.iter().zip(["ground_truth", "detected"]) {
        all.extend(summarize(rows, ms_cmp, &ms_desc, &pid, &gid, lname));
    }

    // Output.
    let mut rep = Report::new(&out, "Recognition benchmark on sampled ICT faces")?;
    rep.para(&format!(
        "{} identities x {} faces (seed {}): {} gallery faces (neutral), {} probes (random expressions: with probability 1/2 a recipe at strength 0.3-1, plus random blendshapes), every face under a random rigid motion. Geodesics: {}{}. Bipolar descriptor: static area, N = {} levels between the outer eye corners (grid reading, keyed distance){}; single pole: {} sectors x {} radius levels around the nose tip; ICP: {} probe vertices onto the gallery surface, started from the 3-landmark alignment, 10 % trimmed, score = RMS closest-point distance (cm); facial curves: N = {} level curves of the nose-tip field up to D, elastic distance ({} segments per curve, one start-point candidate, one rotation / reparametrisation alternation), root sum of squares; iso-curvature: {} levels per principal field (quantiles of the first gallery face) in the geodesic disc of radius D around the nose tip, ICP of the networks' points (thinned to at most {ISO_POINTS}, every k-th point) started from the 3-landmark alignment (10 iterations on a 500-point subsample, at most 10 on all points), score = normalised RMS closest-point distance. Times, single thread (a one-thread pool, after the parallel scoring; the machine is shared, so compare them as ratios): ms per comparison is the mean over {TIMED_PAIRS} probe x gallery pairs per landmark set; ms per description the median over the first {TIMED_FACES} gallery faces (ground-truth landmarks), described as probes, of the fields a representation needs (both corners; the nose tip; the search's moved corners) plus its build.",
        identities, expressions, args.seed, gallery.len(), probes.len(), method.name(),
        method_note.as_ref().map(|n| format!(" (exact requested: {n})")).unwrap_or_default(),
        args.res.levels,
        probe_opts.ref_search.map(|r| format!(", each probe also described from its outer eye corners moved by {r} cm in {SEARCH_DIRECTIONS} directions of their tangent planes (`bipolar::SearchedPole`), its score the least distance over these 49 descriptors")).unwrap_or_default(),
        args.res.sectors, args.res.levels, icp_points(&samples[0].mesh, args.icp_points).len(),
        args.res.levels, args.curve_samples, args.iso_levels
    ));
    let n_det = detected.iter().filter(|d| d.is_some()).count();
    let mean_err =
        |k: usize| det_err.iter().map(|e| e[k]).sum::<f64>() / det_err.len().max(1) as f64;
    rep.para(&format!("Landmark detection: {n_det} of {} faces detected; mean error right corner {:.3} cm, left corner {:.3} cm, nose tip {:.3} cm.", samples.len(), mean_err(0), mean_err(1), mean_err(2)));
    results_table(&mut rep, &all, "results.csv")?;
    paired_table(&mut rep, &all);
    roc_figure(&mut rep, &all, "roc.svg", "ROC (verification)")?;
    rep.png_twins()?;
    let secs = t0.elapsed().as_secs_f64();
    rep.para(&format!("Run time: {secs:.1} s."));
    rep.finish()?;
    let fields = serde_json::json!({
        "geodesic_note": method_note,
        "landmark_detection": { "detected": n_det, "faces": samples.len(), "mean_error_cm": { "right_eye_outer": mean_err(0), "left_eye_outer": mean_err(1), "nose_tip": mean_err(2) } },
        "roc_plot": "roc.svg",
        "seconds": secs,
    });
    let sampled = [identities, expressions, gallery.len(), probes.len()];
    write_summary(&out, &args, sampled, method, fields, &all)?;
    eprintln!("{secs:.1} s wall");
    println!("{}", out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detect_only_writes_one_row_per_scan_and_stops() {
        let model = testsupport::require_shared!(testsupport::MODEL);
        let out = std::env::temp_dir().join(format!("bipolar-detect-only-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            args: Args,
        }
        let (model, dir) = (model.display().to_string(), out.display().to_string());
        let args = |extra: &[&str]| {
            let base = [
                "recognition",
                "--scans",
                "--identities",
                "2",
                "--expressions",
                "2",
                "--no-sweeps",
                "--detect-only",
                "--model",
                &model,
                "--out",
                &dir,
            ];
            <Cli as clap::Parser>::parse_from(base.iter().chain(extra)).args
        };
        run(args(&[])).unwrap();
        let text = std::fs::read_to_string(out.join("detection.csv")).unwrap();
        let rows: Vec<Vec<&str>> = text
            .lines()
            .skip(1)
            .map(|l| l.split(',').collect())
            .collect();
        // Two gallery scans, then two probes, in order; nothing described or compared.
        let names: Vec<&str> = rows.iter().map(|r| r[0]).collect();
        assert_eq!(names[..2], ["id00-e0", "id01-e0"], "{text}");
        assert_eq!(rows.len(), 4, "{text}");
        assert!(names[2].starts_with("id00-e1-yaw") && names[3].starts_with("id01-e1-yaw"));
        // The frontal gallery scans: found, every landmark within 5 mm of its ground truth.
        for r in &rows[..2] {
            assert_eq!(r[3], "found", "{text}");
            for e in &r[4..7] {
                let e: f64 = e.parse().unwrap();
                assert!((0.0..5.0).contains(&e), "{text}");
            }
        }
        // The report: the yaw table and its two figures; nothing of a full run.
        let md = std::fs::read_to_string(out.join("report.md")).unwrap();
        assert!(
            md.contains("landmarks found on") && md.contains("| yaw bin"),
            "{md}"
        );
        for f in ["detection-error-yaw.svg", "detection-placed-yaw.svg"] {
            assert!(out.join(f).exists(), "{f}");
        }
        assert!(!out.join("probes.csv").exists() && !out.join("summary.json").exists());
        // `--only-identities 1`: identity 1's scans alone, with the whole run's seeds, yaws and
        // noises (the same rows byte for byte).
        let only = args(&["--only-identities", "1"]);
        run(only.clone()).unwrap();
        let again = std::fs::read_to_string(out.join("detection.csv")).unwrap();
        let id1: Vec<&str> = text.lines().filter(|l| l.starts_with("id01")).collect();
        let got: Vec<&str> = again.lines().skip(1).collect();
        assert_eq!(got, id1);
        // An identity the run does not have is an error naming it.
        let e = run(Args {
            only_identities: vec![2],
            ..only
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("--only-identities 2"), "{e}");
        // So is a probe name the run does not have.
        let e = run(args(&["--only-probes", "id05"]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("no probe left") && e.contains("id05"), "{e}");
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn eer_and_rank1_on_known_scores() {
        // 2 gallery ids, 2 probes each; probe 3 is misidentified.
        let gid = vec![0, 1];
        let pid = vec![0, 0, 1, 1];
        let s = vec![
            vec![0.1, 0.5],
            vec![0.2, 0.6],
            vec![0.7, 0.3],
            vec![0.4, 0.45],
        ];
        let (rank1, eer, roc, gm, im, f) = metrics(&s, &pid, &gid);
        assert!((rank1 - 0.75).abs() < 1e-12);
        assert!((gm - (0.1 + 0.2 + 0.3 + 0.45) / 4.0).abs() < 1e-12);
        assert!((im - (0.5 + 0.6 + 0.7 + 0.4) / 4.0).abs() < 1e-12);
        assert_eq!(f, 0);
        // Threshold 0.4: FAR 1/4, FRR 1/4 -> EER 0.25.
        assert!((eer - 0.25).abs() < 1e-12, "{eer}");
        assert_eq!(roc.first(), Some(&(0.0, 0.0)));
        assert_eq!(roc.last(), Some(&(1.0, 1.0)));
        // Perfect separation gives EER 0; NaN counts as a failure.
        let (r, e, ..) = metrics(&[vec![0.1, f64::NAN], vec![0.9, 0.2]], &[0, 1], &gid);
        assert_eq!((r, e), (1.0, 0.0));
        assert_eq!(identified(&s, &pid, &gid), [true, true, true, false]);
        // A probe whose every score failed is not identified, even of the first identity.
        assert_eq!(identified(&[vec![f64::NAN, f64::NAN]], &[0], &gid), [false]);
    }

    #[test]
    fn the_mcnemar_p_value_is_the_two_sided_binomial_tail() {
        // 10 discordant probes split 9 : 1: 2 (1 + 10) / 1024.
        assert!((mcnemar_exact(9, 1) - 22.0 / 1024.0).abs() < 1e-15);
        assert!((mcnemar_exact(1, 9) - 22.0 / 1024.0).abs() < 1e-15);
        // 10 : 0: 2 / 1024; an even split and no discordant probe: 1.
        assert!((mcnemar_exact(10, 0) - 2.0 / 1024.0).abs() < 1e-15);
        assert_eq!(mcnemar_exact(5, 5), 1.0);
        assert_eq!(mcnemar_exact(0, 0), 1.0);
        // 6 : 2 (the figure of a 50-identity run): 2 (1 + 8 + 28) / 256.
        assert!((mcnemar_exact(6, 2) - 74.0 / 256.0).abs() < 1e-14);
        // Many probes, no underflow: 2 sum_{i <= 200} C(500, i) / 2^500 = 8.9401e-6 (exact
        // integer sum).
        let p = mcnemar_exact(300, 200);
        assert!((p / 8.940066542253267e-6 - 1.0).abs() < 1e-9, "{p}");
    }

    #[test]
    fn icp_recovers_a_rigid_copy() {
        let m = meshcore::shapes::icosphere(2);
        let rot = meshcore::DMat3::from_quat(meshcore::DQuat::from_axis_angle(
            DVec3::new(1.0, 0.3, 0.2).normalize(),
            1.1,
        ));
        let t = DVec3::new(3.0, -2.0, 1.0);
        let probe: Vec<DVec3> = m.positions().iter().map(|p| rot * *p + t).collect();
        let lm_g = [m.position(0), m.position(5), m.position(9)];
        let lm_p = lm_g.map(|p| rot * p + t);
        let loc = FaceLocator::new(&m);
        assert!(icp_score(&probe, &lm_p, &loc, &lm_g) < 1e-9);
        // A scaled copy is not at distance 0.
        let big: Vec<DVec3> = probe.iter().map(|p| (*p - t) * 1.1 + t).collect();
        assert!(icp_score(&big, &lm_p, &loc, &lm_g) > 0.01);
    }
}
