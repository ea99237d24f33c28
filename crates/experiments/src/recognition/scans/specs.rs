//! The faces of a scan run: the gallery, the probes and the sweeps' scans, each with its own
//! scan seed, and the sweeps themselves.

use super::super::Args;
use crate::scans::{FaceSpec, ScanSettings, SpecMaker};
use anyhow::{bail, Result};
use facemodel::FaceModel;

/// A sweep: a name, the values, and how a value changes the gallery's settings.
pub(super) struct Sweep {
    pub(super) name: &'static str,
    pub(super) unit: &'static str,
    pub(super) values: Vec<f64>,
    pub(super) apply: fn(ScanSettings, f64) -> ScanSettings,
}

/// The sweeps (each value rescans `--sweep-identities` faces); the gallery's default setting
/// (noise 0.1 mm, pitch 0.5 mm, yaw 0) is among the values.
pub(super) fn sweeps() -> Vec<Sweep> {
    vec![
        Sweep {
            name: "noise",
            unit: "mm",
            values: vec![0.0, 0.1, 0.3, 1.0],
            apply: |s, v| ScanSettings { noise_mm: v, ..s },
        },
        Sweep {
            name: "pitch",
            unit: "mm",
            values: vec![0.3, 0.5, 1.0],
            apply: |s, v| ScanSettings { pitch_mm: v, ..s },
        },
        Sweep {
            name: "yaw",
            unit: "degrees",
            values: vec![0.0, 20.0, 40.0, 60.0],
            apply: |s, v| ScanSettings { yaw_deg: v, ..s },
        },
    ]
}

/// The specs `keep` accepts, in order.
fn kept_specs(specs: Vec<FaceSpec>, keep: impl Fn(&FaceSpec) -> bool) -> Vec<FaceSpec> {
    specs.into_iter().filter(|s| keep(s)).collect()
}

/// The specs of a run, after `--only-identities` and `--only-probes`.
pub(super) struct Specs {
    pub(super) gallery: Vec<FaceSpec>,
    pub(super) probes: Vec<FaceSpec>,
    /// Per sweep and value, the rescanned probes.
    pub(super) sweeps: Vec<Vec<Vec<FaceSpec>>>,
    /// The whole run's first gallery face, the reference of the iso-curvature levels.
    pub(super) first_gallery: FaceSpec,
}

impl Specs {
    /// The specs of the gallery (neutral, at `base`), the main probes (random yaw and noise)
    /// and the sweeps' scans (expression 1 of the first `sweep_ids` identities at each value),
    /// numbered in that order for their scan seeds, then kept as `--only-identities` and
    /// `--only-probes` ask.
    pub(super) fn new(
        args: &Args,
        model: &FaceModel,
        identities: usize,
        expressions: usize,
        base: ScanSettings,
        sweep_defs: &[Sweep],
        sweep_ids: usize,
    ) -> Result<Specs> {
        let mut maker = SpecMaker::new(model, identities, expressions, args.seed);
        let (gallery_specs, probe_specs) = maker.gallery_and_probes(base);
        let mut sweep_specs: Vec<Vec<Vec<FaceSpec>>> = Vec::new();
        for sw in sweep_defs {
            let mut per_value = Vec::new();
            for &v in &sw.values {
                let tag = format!("-{}{v}", sw.name);
                per_value.push(
                    (0..sweep_ids)
                        .map(|i| maker.spec(i, 1, (sw.apply)(base, v), &tag))
                        .collect(),
                );
            }
            sweep_specs.push(per_value);
        }
        if let Some(&i) = args.only_identities.iter().find(|&&i| i >= identities) {
            bail!(
                "--only-identities {i}: the run has identities 0 to {}",
                identities - 1
            );
        }
        // The iso-curvature levels come from the whole run's first gallery scan.
        let first_gallery = gallery_specs[0].clone();
        // `--only-identities` and `--only-probes`: the specs keep the whole run's seeds.
        let named = |s: &FaceSpec| {
            args.only_probes.is_empty()
                || args
                    .only_probes
                    .iter()
                    .any(|p| s.name.starts_with(p.as_str()))
        };
        let of_identity = |s: &FaceSpec| {
            args.only_identities.is_empty() || args.only_identities.contains(&s.identity)
        };
        let gallery_specs = kept_specs(gallery_specs, of_identity);
        let probe_specs = kept_specs(probe_specs, |s| of_identity(s) && named(s));
        let sweep_specs: Vec<Vec<Vec<FaceSpec>>> = sweep_specs
            .into_iter()
            .map(|groups| {
                groups
                    .into_iter()
                    .map(|v| kept_specs(v, |s| of_identity(s) && named(s)))
                    .collect()
            })
            .collect();
        if probe_specs.is_empty() && sweep_specs.iter().flatten().all(Vec::is_empty) {
            bail!(
                "no probe left: --only-identities {:?}, --only-probes {:?}",
                args.only_identities,
                args.only_probes
            );
        }
        Ok(Specs {
            gallery: gallery_specs,
            probes: probe_specs,
            sweeps: sweep_specs,
            first_gallery,
        })
    }

    /// Every spec: the gallery, the probes, then the sweeps' scans.
    pub(super) fn all(&self) -> Vec<&FaceSpec> {
        self.gallery
            .iter()
            .chain(&self.probes)
            .chain(self.sweeps.iter().flatten().flatten())
            .collect()
    }
}
