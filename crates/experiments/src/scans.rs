//! Scan sets for the experiments: faces sampled from the ICT model (`facemodel`), scanned by
//! the virtual range scanner (`rangescan`) under given settings, cleaned by `scanprep` (crop
//! around the nose tip), with the ground-truth landmarks the scanner projected (unseen ones
//! marked with the reason) and the landmarks `landmarks::detect` finds on the cleaned scan.
//!
//! Deterministic: the faces' weights come from one seeded stream drawn in order, every scan
//! has its own seed derived from the set's seed and the face's index, and faces are processed
//! in parallel (rayon) but collected in input order.

use anyhow::Result;
use facemodel::FaceModel;
use indicatif::ProgressBar;
use landmarks::{DetectOptions, GenericModel, LandmarkName, VisibleLandmarks};
use meshcore::{DVec3, TriMesh};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rangescan::Visibility;
use rayon::prelude::*;
use scanprep::{CleanOptions, Crop, Input};
use std::time::{Duration, Instant};

pub use rangescan::{scan_seed, ScanSettings};

/// One face to scan: its weights in the ICT model, the scanner settings and the scan's seed.
#[derive(Debug, Clone)]
pub struct FaceSpec {
    /// Name used in reports (`id03-e1-yaw30`, ...).
    pub name: String,
    /// Identity index in the set.
    pub identity: usize,
    /// Identity weights.
    pub identity_weights: Vec<f64>,
    /// Expression weights (empty: neutral).
    pub expression_weights: Vec<f64>,
    /// Scanner settings.
    pub settings: ScanSettings,
    /// Seed of the scanner's artifacts.
    pub seed: u64,
}

/// Weights of `identities` x `expressions` faces drawn from one stream of `seed`
/// ([`FaceModel::random_faces`]: expression 0 of each identity neutral), as `(identity
/// weights, expression weights per face)`.
pub fn sample_weights(
    model: &FaceModel,
    identities: usize,
    expressions: usize,
    seed: u64,
) -> Vec<(Vec<f64>, Vec<Vec<f64>>)> {
    model.random_faces(
        &mut ChaCha8Rng::seed_from_u64(seed),
        identities,
        expressions,
    )
}

/// Makes the [`FaceSpec`]s of one sampled set ([`sample_weights`]), numbering their scan seeds
/// ([`scan_seed`]) in the order they are made, from 1.
#[derive(Debug)]
pub struct SpecMaker {
    weights: Vec<(Vec<f64>, Vec<Vec<f64>>)>,
    seed: u64,
    made: u64,
}

impl SpecMaker {
    /// The weights of `identities` x `expressions` faces of the set with seed `seed`.
    pub fn new(model: &FaceModel, identities: usize, expressions: usize, seed: u64) -> Self {
        Self {
            weights: sample_weights(model, identities, expressions, seed),
            seed,
            made: 0,
        }
    }

    /// Expression `expression` of `identity` at `settings`, named `idII-eE` and `tag`, with the
    /// set's next scan seed.
    pub fn spec(
        &mut self,
        identity: usize,
        expression: usize,
        settings: ScanSettings,
        tag: &str,
    ) -> FaceSpec {
        self.made += 1;
        FaceSpec {
            name: format!("id{identity:02}-e{expression}{tag}"),
            identity,
            identity_weights: self.weights[identity].0.clone(),
            expression_weights: self.weights[identity].1[expression].clone(),
            settings,
            seed: scan_seed(self.seed, self.made),
        }
    }

    /// The scan benchmark's gallery and probes: per identity its neutral face at `base`, then
    /// per identity and other expression a probe under a random yaw and noise drawn from the
    /// set's own stream ([`ScanSettings::random_probe`]).
    pub fn gallery_and_probes(&mut self, base: ScanSettings) -> (Vec<FaceSpec>, Vec<FaceSpec>) {
        let (identities, expressions) = (
            self.weights.len(),
            self.weights.first().map_or(0, |w| w.1.len()),
        );
        let gallery = (0..identities).map(|i| self.spec(i, 0, base, "")).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(scan_seed(self.seed, u64::MAX));
        let mut probes = Vec::new();
        for i in 0..identities {
            for e in 1..expressions {
                let st = base.random_probe(&mut rng);
                let tag = format!("-yaw{}-noise{}", st.yaw_deg, st.noise_mm);
                probes.push(self.spec(i, e, st, &tag));
            }
        }
        (gallery, probes)
    }
}

/// A ground-truth landmark on the cleaned scan.
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    /// The true point in the scan frame (mm).
    pub position: DVec3,
    /// What the scanner saw at the point.
    pub scanner: Visibility,
    /// The nearest vertex of the cleaned scan and its distance (mm) when it is within
    /// [`MAX_SNAP_MM`] (the point is on the cleaned scan, whatever the scanner saw at its exact
    /// position: a corner tucked under the eyelid counts, a filled hole too); otherwise why not.
    pub vertex: Result<(u32, f64), String>,
}

/// A ground-truth landmark farther than this (mm) from every vertex of the cleaned scan
/// (occluded, outside the grid, removed by the cleaning or the crop) is not on the scan.
pub const MAX_SNAP_MM: f64 = 3.0;

/// Wall time of each step of one face.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepTimes {
    /// Sampling the face and scanning it.
    pub scan: Duration,
    /// `scanprep::clean` (with the decimation, if any).
    pub clean: Duration,
    /// Landmark detection (`landmarks::detect`) on the cleaned scan.
    pub detect: Duration,
}

/// One scanned, cleaned face.
#[derive(Debug, Clone)]
pub struct ScannedFace {
    /// Valid samples of the raw scan.
    pub valid_samples: usize,
    /// The cleaned scan (mm, scan frame).
    pub mesh: TriMesh,
    /// Ground truth, in [`LandmarkName::ALL`] order.
    pub truth: [Truth; 5],
    /// Landmarks detected on the cleaned scan (`landmarks::detect_visible`: those the scanner
    /// did not see are reported unseen), or the detector's error message.
    pub detected: Result<VisibleLandmarks, String>,
    /// Step times.
    pub times: StepTimes,
}

impl ScannedFace {
    /// The ground-truth vertex of landmark `n`, or why it is not on the cleaned scan.
    pub fn truth_vertex(&self, n: LandmarkName) -> Result<u32, String> {
        self.truth[n as usize]
            .vertex
            .as_ref()
            .map(|x| x.0)
            .map_err(|e| format!("ground-truth {n}: {e}"))
    }

    /// Ground-truth vertices of the outer eye corners and the nose tip, or why one is missing.
    pub fn truth_vertices(&self) -> Result<[u32; 3], String> {
        let [r, q, nose] = REFERENCE_LANDMARKS;
        Ok([
            self.truth_vertex(r)?,
            self.truth_vertex(q)?,
            self.truth_vertex(nose)?,
        ])
    }
}

/// The landmarks the descriptors take their poles from: the outer eye corners and the nose tip.
pub const REFERENCE_LANDMARKS: [LandmarkName; 3] = [
    LandmarkName::OuterEyeRight,
    LandmarkName::OuterEyeLeft,
    LandmarkName::NoseTip,
];

/// Distance (mm) of each detected reference landmark ([`REFERENCE_LANDMARKS`]) from its
/// ground truth `truth` (the scanner's landmarks, in [`LandmarkName::ALL`] order), or, for one
/// the detector reports unseen, why, with how far from its ground truth the fitted face
/// predicts it.
pub fn detection_errors(
    truth: &[rangescan::ScannedLandmark],
    found: &VisibleLandmarks,
) -> [Result<f64, String>; 3] {
    REFERENCE_LANDMARKS.map(|n| {
        let truth = truth[n as usize].position;
        match found.get(n) {
            Ok(l) => Ok((l.position - truth).length()),
            Err(u) => {
                let off = (found.predicted[n as usize] - truth).length();
                Err(format!(
                    "{}: {u}; the fitted face predicts it {off:.2} mm from its ground truth",
                    n.key()
                ))
            }
        }
    })
}

/// The direction toward the scanner in the frame of every scan `rangescan` writes.
pub use facematch::GRID_SCANNER as SCANNER_SIDE;

/// Options of [`scan_faces`].
#[derive(Debug, Clone)]
pub struct ScanSetOptions {
    /// How every scan is cleaned (mm); its crop sphere, when set, is centred on each scan's
    /// true nose tip (the centre given here is not used).
    pub clean: CleanOptions,
    /// Detection options for every cleaned scan (their `mesh_units_per_model_unit` is replaced
    /// by the one recognised from the scan, `landmarks::mesh_units_per_model_unit`); `None`:
    /// no detection.
    pub detect: Option<DetectOptions>,
    /// Taubin smoothing iterations of a copy of the cleaned scan that detection runs on (the
    /// landmarks keep their vertices and are placed on the scan itself); 0: detection on the
    /// scan.
    pub detect_smoothing: usize,
}

impl Default for ScanSetOptions {
    fn default() -> Self {
        Self {
            clean: CleanOptions {
                crop: Some(Crop::around(DVec3::ZERO)),
                ..CleanOptions::default()
            },
            detect: Some(DetectOptions {
                toward_viewer: Some(SCANNER_SIDE),
                ..DetectOptions::default()
            }),
            detect_smoothing: 0,
        }
    }
}

/// The scanner settings and the crop as command-line options (shared by the tasks that scan).
#[derive(Debug, Clone, clap::Args)]
pub struct ScanArgs {
    /// Sample pitch of the scans, mm.
    #[arg(long, default_value_t = 0.5)]
    pub scan_pitch: f64,
    /// Depth noise of the scans (standard deviation), mm; 0 switches it off.
    #[arg(long, default_value_t = 0.1)]
    pub scan_noise: f64,
    /// Depth quantisation step of the scans, mm; 0 switches it off.
    #[arg(long, default_value_t = 0.0)]
    pub scan_quantisation: f64,
    /// Scans without holes and grazing dropouts.
    #[arg(long)]
    pub no_holes: bool,
    /// Scans without spikes and outliers.
    #[arg(long)]
    pub no_spikes: bool,
    /// Head yaw of the scans, degrees.
    #[arg(long, default_value_t = 0.0)]
    pub scan_yaw: f64,
    /// Crop radius around the nose tip, mm.
    #[arg(long, default_value_t = scanprep::DEFAULT_CROP_RADIUS_MM)]
    pub crop_radius: f64,
}

impl ScanArgs {
    /// The settings these options give.
    pub fn settings(&self) -> ScanSettings {
        ScanSettings {
            pitch_mm: self.scan_pitch,
            noise_mm: self.scan_noise,
            quantisation_mm: self.scan_quantisation,
            spikes: !self.no_spikes,
            holes: !self.no_holes,
            yaw_deg: self.scan_yaw,
            pitch_deg: 0.0,
        }
    }
}

/// Samples, scans, cleans and (optionally) detects every face, in parallel, in input order.
/// A face whose sampling, scan or cleaning fails is `Err` with the face's name and the error.
pub fn scan_faces(
    model: &FaceModel,
    generic: &GenericModel,
    specs: &[FaceSpec],
    options: &ScanSetOptions,
    progress: &ProgressBar,
) -> Vec<Result<ScannedFace, String>> {
    specs
        .par_iter()
        .map(|s| {
            let r = scan_face(model, generic, s, options).map_err(|e| format!("{}: {e:#}", s.name));
            progress.inc(1);
            r
        })
        .collect()
}

/// [`scan_faces`] for one face: [`scan_raw`], then [`clean_scan`].
pub fn scan_face(
    model: &FaceModel,
    generic: &GenericModel,
    spec: &FaceSpec,
    options: &ScanSetOptions,
) -> Result<ScannedFace> {
    let (scan, t_scan) = scan_raw(model, spec)?;
    clean_scan(&scan, t_scan, generic, options)
}

/// Samples the face of `spec` and scans it (the raw grid with the projected ground-truth
/// landmarks, in [`LandmarkName::ALL`] order), with the time it took.
pub fn scan_raw(model: &FaceModel, spec: &FaceSpec) -> Result<(rangescan::Scan, Duration)> {
    let t0 = Instant::now();
    let face = model.sample(&spec.identity_weights, &spec.expression_weights)?;
    let truth_cm = model.landmark_positions(&face)?;
    let marks: Vec<(String, DVec3)> = LandmarkName::ALL
        .iter()
        .zip(truth_cm)
        .map(|(n, p)| (n.lm3_label().to_string(), p))
        .collect();
    // The model's units (cm where they are not recognised).
    let units = model
        .units()
        .parse()
        .unwrap_or(meshcore::units::Units::Centimetre);
    let options = spec.settings.options(units.mm_per_unit(), spec.seed);
    let scan = rangescan::scan_with_landmarks(&face, &marks, &options)?;
    Ok((scan, t0.elapsed()))
}

/// Cleans a raw scan ([`scan_raw`]; its crop around the *true* nose tip), snaps its ground truth
/// to the cleaned scan and detects the landmarks on it; `t_scan` is the scan's own time.
pub fn clean_scan(
    scan: &rangescan::Scan,
    t_scan: Duration,
    generic: &GenericModel,
    options: &ScanSetOptions,
) -> Result<ScannedFace> {
    let t1 = Instant::now();
    let nose = scan.landmarks[LandmarkName::NoseTip as usize].position;
    let cleaned = scanprep::clean(
        Input::Grid(&scan.grid),
        &CleanOptions {
            crop: options.clean.crop.map(|c| Crop { centre: nose, ..c }),
            ..options.clean.clone()
        },
    )?;
    let t2 = Instant::now();
    let mesh = cleaned.mesh;
    let truth: Vec<Truth> = scan
        .landmarks
        .iter()
        .map(|l| Truth {
            position: l.position,
            scanner: l.visibility,
            vertex: match facematch::nearest_vertex(&mesh, l.position) {
                Some((v, d)) if d <= MAX_SNAP_MM => Ok((v, d)),
                Some((_, d)) => Err(format!(
                    "{} and {d:.1} mm from the cleaned surface",
                    l.visibility
                )),
                None => Err("the cleaned scan is empty".into()),
            },
        })
        .collect();
    let truth: [Truth; 5] = truth
        .try_into()
        .map_err(|_| anyhow::anyhow!("the scanner returned another number of landmarks"))?;
    let detected = match &options.detect {
        // The detector's reason, not facematch's wording of it.
        Some(o) => facematch::detect_landmarks(&mesh, generic, o, options.detect_smoothing)
            .map_err(|e| match e {
                facematch::MatchError::NoFace(why) => why,
                e => e.to_string(),
            }),
        None => Err("not run".into()),
    };
    let t3 = Instant::now();
    Ok(ScannedFace {
        valid_samples: scan.n_valid(),
        mesh,
        truth,
        detected,
        times: StepTimes {
            scan: t_scan,
            clean: t2 - t1,
            detect: t3 - t2,
        },
    })
}
