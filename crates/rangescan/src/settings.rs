//! The few settings that vary between the scans of a benchmark (pitch, noise, quantisation,
//! the structured-light artifacts switched on or off, head pose), the [`ScanOptions`] they
//! give, and the seeds of the scans of a set.

use crate::{Artifacts, DepthNoise, HeadPose, Holes, Quantisation, ScanOptions, Spikes};
use rand::Rng;

/// The scanner settings of one scan: [`Artifacts::structured_light`] with its noise and
/// quantisation given here and its spikes and holes switched on or off.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanSettings {
    /// Sample pitch, mm.
    pub pitch_mm: f64,
    /// Standard deviation of the Gaussian depth noise, mm (0: none).
    pub noise_mm: f64,
    /// Depth quantisation step, mm (0: none).
    pub quantisation_mm: f64,
    /// Spikes (0.1 % of the samples, 2-10 mm) and 50 background outliers.
    pub spikes: bool,
    /// Holes: 4 random holes of 1-4 mm radius and dropouts at grazing angles (70-80 degrees).
    pub holes: bool,
    /// Head rotation about the vertical axis, degrees (positive turns the face to the
    /// scanner's right).
    pub yaw_deg: f64,
    /// Head rotation about the horizontal axis, degrees (positive lifts the chin).
    pub pitch_deg: f64,
}

impl Default for ScanSettings {
    /// The scan benchmark's gallery scans: 0.5 mm pitch, frontal, [`Artifacts::structured_light`]
    /// as it is (0.1 mm noise, spikes and holes, no quantisation).
    fn default() -> Self {
        Self {
            pitch_mm: 0.5,
            noise_mm: 0.1,
            quantisation_mm: 0.0,
            spikes: true,
            holes: true,
            yaw_deg: 0.0,
            pitch_deg: 0.0,
        }
    }
}

impl ScanSettings {
    /// The scanner's artifact model for these settings (the parts of
    /// [`Artifacts::structured_light`] that are switched on, with the noise and quantisation
    /// given here).
    pub fn artifacts(&self) -> Artifacts {
        let sl = Artifacts::structured_light();
        Artifacts {
            noise: (self.noise_mm > 0.0).then_some(DepthNoise {
                sigma_mm: self.noise_mm,
            }),
            quantisation: (self.quantisation_mm > 0.0).then_some(Quantisation {
                step_mm: self.quantisation_mm,
            }),
            spikes: sl.spikes.filter(|_| self.spikes),
            outliers: sl.outliers.filter(|_| self.spikes),
            grazing: sl.grazing.filter(|_| self.holes),
            holes: sl.holes.filter(|_| self.holes),
            border: None,
        }
    }

    /// The options of a scan at these settings of a mesh in units of `input_mm_per_unit` mm,
    /// with the artifacts' `seed` (the other options their defaults).
    pub fn options(&self, input_mm_per_unit: f64, seed: u64) -> ScanOptions {
        ScanOptions {
            input_mm_per_unit,
            pitch_mm: self.pitch_mm,
            pose: HeadPose {
                yaw_deg: self.yaw_deg,
                pitch_deg: self.pitch_deg,
            },
            artifacts: self.artifacts(),
            seed,
            ..ScanOptions::default()
        }
    }

    /// A probe of the scan benchmark drawn from `rng`: these settings with a head yaw of 0-45
    /// whole degrees to either side and one of the [`PROBE_NOISE_MM`] noise levels.
    pub fn random_probe<R: Rng>(&self, rng: &mut R) -> ScanSettings {
        let yaw = rng.random_range(0..=45) as f64 * if rng.random::<bool>() { 1.0 } else { -1.0 };
        let noise = PROBE_NOISE_MM[rng.random_range(0..PROBE_NOISE_MM.len())];
        ScanSettings {
            yaw_deg: yaw,
            noise_mm: noise,
            ..*self
        }
    }

    /// A short label (`pitch 0.5 mm, noise 0.1 mm, holes, spikes, yaw 30`).
    pub fn label(&self) -> String {
        let mut s = format!("pitch {} mm, noise {} mm", self.pitch_mm, self.noise_mm);
        if self.quantisation_mm > 0.0 {
            s += &format!(", quantisation {} mm", self.quantisation_mm);
        }
        if self.holes {
            s += ", holes";
        }
        if self.spikes {
            s += ", spikes";
        }
        if self.yaw_deg != 0.0 {
            s += &format!(", yaw {}", self.yaw_deg);
        }
        if self.pitch_deg != 0.0 {
            s += &format!(", pitch {}", self.pitch_deg);
        }
        s
    }
}

/// The seed of scan `index` of a set with seed `seed` (SplitMix64 of both): every scan of a set
/// its own stream, the same on every run.
pub fn scan_seed(seed: u64, index: u64) -> u64 {
    let mut z = seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(index.wrapping_add(1).wrapping_mul(0xBF58_476D_1CE4_E5B9));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Depth noise levels of the scan benchmark's probes ([`ScanSettings::random_probe`]), mm.
pub const PROBE_NOISE_MM: [f64; 3] = [0.1, 0.2, 0.4];

/// A scanner unlike the benchmark's [`ScanSettings`], drawn from `rng` (one draw per scan):
/// pitch 0.4-0.8 mm, head yaw up to 20 and pitch up to 10 degrees either way, depth noise
/// 0.05-0.3 mm, spikes of 3-15 mm on 0.05-0.3 % of the samples, 2-8 holes of 1-6 mm radius
/// anywhere, the other artifacts [`Artifacts::structured_light`]'s; for a mesh in units of
/// `input_mm_per_unit` mm, with the artifacts' `seed`.
pub fn random_scanner<R: Rng>(rng: &mut R, input_mm_per_unit: f64, seed: u64) -> ScanOptions {
    let sl = Artifacts::structured_light();
    let spike_min = rng.random_range(3.0..8.0);
    let hole_min = rng.random_range(1.0..3.0);
    ScanOptions {
        input_mm_per_unit,
        pitch_mm: rng.random_range(0.4..=0.8),
        pose: HeadPose {
            yaw_deg: rng.random_range(-20.0..=20.0),
            pitch_deg: rng.random_range(-10.0..=10.0),
        },
        artifacts: Artifacts {
            noise: Some(DepthNoise {
                sigma_mm: rng.random_range(0.05..0.3),
            }),
            spikes: Some(Spikes {
                fraction: rng.random_range(0.0005..0.003),
                min_mm: spike_min,
                max_mm: rng.random_range(spike_min..=15.0),
            }),
            holes: Some(Holes {
                count: rng.random_range(2..=8),
                min_radius_mm: hole_min,
                max_radius_mm: rng.random_range(hole_min..=6.0),
            }),
            ..sl
        },
        seed,
        ..ScanOptions::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_switch_the_artifacts() {
        let mut s = ScanSettings::default();
        let a = s.artifacts();
        assert_eq!(a, Artifacts::structured_light());
        assert!(a.noise.is_some() && a.spikes.is_some() && a.holes.is_some());
        assert!(a.quantisation.is_none());
        assert_eq!(s.label(), "pitch 0.5 mm, noise 0.1 mm, holes, spikes");
        s.spikes = false;
        s.holes = false;
        s.noise_mm = 0.0;
        s.quantisation_mm = 2.0;
        s.yaw_deg = 30.0;
        let a = s.artifacts();
        assert!(a.noise.is_none() && a.spikes.is_none() && a.outliers.is_none());
        assert!(a.holes.is_none() && a.grazing.is_none());
        assert_eq!(a.quantisation.map(|q| q.step_mm), Some(2.0));
        assert!(a.validate().is_ok());
        let o = s.options(10.0, 42);
        assert_eq!(
            (o.input_mm_per_unit, o.seed, o.pose.yaw_deg),
            (10.0, 42, 30.0)
        );
        assert_eq!(o.artifacts, a);
    }

    #[test]
    fn random_probes_turn_and_add_noise_only() {
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let base = ScanSettings {
            pitch_mm: 0.7,
            ..ScanSettings::default()
        };
        let probes: Vec<ScanSettings> = (0..300).map(|_| base.random_probe(&mut rng)).collect();
        for p in &probes {
            assert!(p.yaw_deg.abs() <= 45.0 && p.yaw_deg.fract() == 0.0);
            assert!(PROBE_NOISE_MM.contains(&p.noise_mm));
            let back = ScanSettings {
                yaw_deg: 0.0,
                noise_mm: base.noise_mm,
                ..*p
            };
            assert_eq!(back, base);
        }
        // Both sides, every noise level.
        assert!(
            probes.iter().any(|p| p.yaw_deg < -20.0) && probes.iter().any(|p| p.yaw_deg > 20.0)
        );
        for n in PROBE_NOISE_MM {
            assert!(probes.iter().any(|p| p.noise_mm == n));
        }
    }

    #[test]
    fn random_scanners_stay_in_their_ranges_and_repeat() {
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let draws: Vec<ScanOptions> = (0..200)
            .map(|k| random_scanner(&mut rng, 10.0, k))
            .collect();
        for (k, o) in draws.iter().enumerate() {
            let a = &o.artifacts;
            assert!((0.4..=0.8).contains(&o.pitch_mm) && o.seed == k as u64);
            assert!(o.pose.yaw_deg.abs() <= 20.0 && o.pose.pitch_deg.abs() <= 10.0);
            let (sp, h) = (a.spikes.unwrap(), a.holes.unwrap());
            assert!(3.0 <= sp.min_mm && sp.min_mm <= sp.max_mm && sp.max_mm <= 15.0);
            assert!((2..=8).contains(&h.count) && 1.0 <= h.min_radius_mm);
            assert!(h.min_radius_mm <= h.max_radius_mm && h.max_radius_mm <= 6.0);
            assert!(a.validate().is_ok() && o.input_mm_per_unit == 10.0);
        }
        // Other yaws than the benchmark's frontal gallery, and the same draws again.
        assert!(draws.iter().any(|o| o.pose.yaw_deg.abs() > 10.0));
        let mut again = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        assert_eq!(random_scanner(&mut again, 10.0, 0), draws[0]);
    }

    #[test]
    fn scan_seeds_differ_and_repeat() {
        assert_eq!(scan_seed(7, 3), scan_seed(7, 3));
        let mut v: Vec<u64> = (0..1000).map(|i| scan_seed(7, i)).collect();
        v.extend((0..1000).map(|i| scan_seed(8, i)));
        v.sort_unstable();
        v.dedup();
        assert_eq!(v.len(), 2000);
    }
}
