//! The few settings that vary between the scans of a benchmark (pitch, noise, quantisation,
//! the structured-light artifacts switched on or off, head pose), the [`ScanOptions`] they
//! give, and the seeds of the scans of a set.

use crate::{Artifacts, DepthNoise, HeadPose, Quantisation, ScanOptions};

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
    fn scan_seeds_differ_and_repeat() {
        assert_eq!(scan_seed(7, 3), scan_seed(7, 3));
        let mut v: Vec<u64> = (0..1000).map(|i| scan_seed(7, i)).collect();
        v.extend((0..1000).map(|i| scan_seed(8, i)));
        v.sort_unstable();
        v.dedup();
        assert_eq!(v.len(), 2000);
    }
}
