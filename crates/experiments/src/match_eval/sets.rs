//! The two scan sets of `match-eval` (tuning: the benchmark's scanner; held-out: another
//! one), their scanning into `.bnt` files and their passage through the public API.

use super::Args;
use crate::report::par_map;
use crate::scans::{sample_weights, scan_seed, FaceSpec, ScanSettings, SpecMaker};
use anyhow::{Context, Result};
use facematch::{prepare, Description, MatchOptions, ScanInput, Template};
use facemodel::FaceModel;
use mesh_io::BntGrid;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rangescan::ScanOptions;
use std::path::Path;

/// A scan to make: name, identity, face weights, scanner options.
pub(super) struct Spec {
    pub name: String,
    pub identity: usize,
    pub identity_weights: Vec<f64>,
    pub expression_weights: Vec<f64>,
    pub scan: ScanOptions,
}

impl Spec {
    /// The spec of a scan of the scan benchmark's sets ([`FaceSpec`], a mesh in cm).
    fn of(f: FaceSpec) -> Self {
        Spec {
            scan: f.settings.options(10.0, f.seed),
            name: f.name,
            identity: f.identity,
            identity_weights: f.identity_weights,
            expression_weights: f.expression_weights,
        }
    }
}

/// The tuning set: the scan benchmark's gallery specs (neutral, frontal) and probe specs
/// ([`SpecMaker::gallery_and_probes`] at the default settings).
pub(super) fn tuning_specs(model: &FaceModel, a: &Args) -> (Vec<Spec>, Vec<Spec>) {
    let (g, p) = SpecMaker::new(model, a.identities, a.expressions, a.seed)
        .gallery_and_probes(ScanSettings::default());
    let of = |v: Vec<FaceSpec>| v.into_iter().map(Spec::of).collect();
    (of(g), of(p))
}

/// The held-out set: per person a gallery scan and a probe scan, each from its own draw of the
/// other scanner ([`rangescan::random_scanner`]), the probe with an expression half the time.
pub(super) fn held_out_specs(model: &FaceModel, a: &Args) -> (Vec<Spec>, Vec<Spec>) {
    let weights = sample_weights(model, a.held_out, 2, a.held_out_seed);
    let mut rng = ChaCha8Rng::seed_from_u64(scan_seed(a.held_out_seed, u64::MAX));
    let mut gallery = Vec::new();
    let mut probes = Vec::new();
    for (i, (w, ex)) in weights.iter().enumerate() {
        for k in 0..2 {
            let seed = scan_seed(a.held_out_seed, (2 * i + k) as u64);
            let expression = if k == 1 && rng.random::<bool>() {
                ex[1].clone()
            } else {
                Vec::new()
            };
            let s = Spec {
                name: format!("p{i:02}-s{k}"),
                identity: i,
                identity_weights: w.clone(),
                expression_weights: expression,
                scan: rangescan::random_scanner(&mut rng, 10.0, seed),
            };
            if k == 0 {
                gallery.push(s)
            } else {
                probes.push(s)
            }
        }
    }
    (gallery, probes)
}

/// Scans every spec (in parallel, in order) and writes each grid as `dir/NAME.bnt`.
pub(super) fn scan_all(
    model: &FaceModel,
    specs: &[Spec],
    dir: &Path,
    msg: &str,
) -> Result<Vec<BntGrid>> {
    std::fs::create_dir_all(dir).with_context(|| dir.display().to_string())?;
    par_map(specs, msg, |s| {
        let face = model.sample(&s.identity_weights, &s.expression_weights)?;
        let grid = rangescan::scan(&face, &s.scan)?.grid;
        mesh_io::write_bnt(dir.join(format!("{}.bnt", s.name)), &grid)?;
        Ok(grid)
    })
    .into_iter()
    .collect()
}

/// One side of a set through the public API: templates of the gallery (`Err`: why not) and
/// the probes' descriptions with the search.
pub(super) struct Processed {
    pub templates: Vec<Result<Template, String>>,
    pub probes: Vec<Result<Description, String>>,
    /// What `facematch::prepare` assumed or substituted for each probe.
    pub probe_notes: Vec<Vec<String>>,
}

/// Enrols the gallery scans (`gallery`, their grids `grids_g`) and describes the probes' grids
/// `grids_p` (with the search), in parallel.
pub(super) fn process(
    gallery: &[Spec],
    grids_g: &[BntGrid],
    grids_p: &[BntGrid],
    o: &MatchOptions,
) -> Processed {
    let enrolled: Vec<(&Spec, &BntGrid)> = gallery.iter().zip(grids_g).collect();
    let templates = par_map(&enrolled, "enrol", |(s, g)| {
        let (identity, source) = (s.identity.to_string(), format!("{}.bnt", s.name));
        facematch::enroll(ScanInput::Grid(g), &identity, &source, o).map_err(|e| e.to_string())
    });
    let (probes, probe_notes) = par_map(grids_p, "probes", |g| {
        match prepare(ScanInput::Grid(g), o).and_then(|s| Ok((s.describe(o, true)?, s.notes))) {
            Ok((d, notes)) => (Ok(d), notes),
            Err(e) => (Err(e.to_string()), Vec::new()),
        }
    })
    .into_iter()
    .unzip();
    Processed {
        templates,
        probes,
        probe_notes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_held_out_scan_not_found_uncropped_is_found_after_the_fallback_crop_and_said() {
        let dir = testsupport::require_shared!(testsupport::MODEL);
        let a: Args = crate::parse_args(&["match-eval", "--model", dir.to_str().unwrap()]);
        let model = FaceModel::load(&dir).unwrap();
        // p08-s0, the held-out gallery scan whose uncropped scan gives no face (docs/matching.md).
        let (gallery, _) = held_out_specs(&model, &a);
        let s = &gallery[8];
        assert_eq!(s.name, "p08-s0");
        let face = model
            .sample(&s.identity_weights, &s.expression_weights)
            .unwrap();
        let grid = rangescan::scan(&face, &s.scan).unwrap().grid;
        let p = prepare(ScanInput::Grid(&grid), &MatchOptions::default()).unwrap();
        assert!(
            p.notes
                .iter()
                .any(|n| n.contains("no face found on the uncropped scan")
                    && n.contains("around the point nearest the scanner")),
            "{:?}",
            p.notes
        );
        // Without the crop (detection on the uncropped scan only) no face is found.
        let uncropped = MatchOptions {
            prepare: facematch::PrepareOptions {
                crop_radius_mm: None,
                ..MatchOptions::default().prepare
            },
            ..MatchOptions::default()
        };
        let e = prepare(ScanInput::Grid(&grid), &uncropped).unwrap_err();
        assert!(e.to_string().contains("mirror-symmetric"), "{e}");
    }
}
