//! The command line of `cargo xtask recognition` and the defaults of its flags.

use crate::paths::{ModelArgs, ResolutionArgs};
use crate::scans::ScanArgs;

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
    /// Geodesic method (clean meshes: exact falls back to fmm, then heat, if it cannot be
    /// prepared, and the report says so; scans: the method as given, no substitute).
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
    #[arg(long = "curve-samples", default_value_t = 50)]
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
    #[arg(long, default_value_t = facematch::DEFAULT_EDGE_MM)]
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
    #[arg(long, default_value_t = fm().boundary_margin_mm.unwrap_or(0.0))]
    pub boundary_margin: f64,
    /// Parts of each scan seen at more than this incidence (degrees) left out of the bipolar
    /// descriptor (`--scans`; 0 keeps everything).
    #[arg(long, default_value_t = fm().max_incidence_deg.unwrap_or(0.0))]
    pub max_incidence: f64,
    /// Reference-point search of the bipolar score (mm, 0: off; on the clean meshes the outer
    /// eye corners' pair alone, as their only pair): each probe is also
    /// described by each pole pair (the outer eye corners; each corner with the nose tip) from
    /// its two poles moved by this distance in 6 directions of their tangent planes (48 more
    /// descriptors per pair; only the probe's own pair with `--own-pair-search`), and its
    /// distance by a pair is the least over the pair's 49 descriptors.
    #[arg(long, default_value_t = fm().search.map_or(0.0, |s| s.radius_mm))]
    pub ref_search: f64,
    /// View matching of the bipolar score (`--scans`; degrees): when a probe's scanner
    /// direction, carried into a gallery face's frame by the landmark alignment, is more than
    /// this angle from the gallery scan's own, the probe is compared with the gallery face's
    /// template view nearest that direction (`facematch::views_of`: the face described on the
    /// part of it a scanner turned by 15, 25, 35 or 45 degrees to either side would see,
    /// `rangescan::visible_faces`, incidence up to 75 degrees), so that both sides miss the
    /// same surface.
    #[arg(long, default_value_t = fm().view.map_or(0.0, |v| v.min_angle_deg))]
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
    #[arg(long, default_value_t = fm().side_pair_deg.unwrap_or(0.0))]
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

/// facematch's options with their defaults: the defaults of the bipolar flags on scans, written
/// (and the choices explained) once, in `facematch::MatchOptions`.
fn fm() -> facematch::MatchOptions {
    facematch::MatchOptions::default()
}

impl Args {
    /// The identities and faces per identity, `defaults` where not given; at least 2 of each (a
    /// neutral gallery face and probes).
    pub(super) fn sizes(&self, defaults: (usize, usize)) -> anyhow::Result<(usize, usize)> {
        let identities = self.identities.unwrap_or(defaults.0);
        let expressions = self.expressions.unwrap_or(defaults.1);
        if identities < 2 || expressions < 2 {
            anyhow::bail!(
                "need at least 2 identities and 2 expressions (one neutral gallery face + probes)"
            );
        }
        Ok((identities, expressions))
    }
}
