//! The artifact model: each part off (`None`) or sized, each with its own random stream.

use crate::camera::{Camera, Kind};
use crate::render::Hit;
use crate::{SampleStatus, ScanError, ScanStats};
use meshcore::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// Gaussian depth noise along each sample's ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthNoise {
    /// Standard deviation in mm (0 to 50).
    pub sigma_mm: f64,
}

impl DepthNoise {
    /// `mesh` with this noise along its vertex normals instead of along a scan's rays: each
    /// vertex moved by a Gaussian draw of standard deviation `sigma_mm` (`sigma_mm /
    /// mm_per_unit` in the mesh's units), the draws from `rng` in vertex order. Errors when the
    /// moved mesh is not valid (a non-finite position).
    pub fn along_normals<R: Rng>(
        &self,
        mesh: &meshcore::TriMesh,
        mm_per_unit: f64,
        rng: &mut R,
    ) -> Result<meshcore::TriMesh, meshcore::MeshError> {
        let sigma = self.sigma_mm / mm_per_unit;
        let normals = mesh.vertex_normals();
        let moved = mesh.positions().iter().zip(&normals).map(|(p, n)| {
            let z: f64 = rng.sample(StandardNormal);
            *p + *n * (sigma * z)
        });
        meshcore::TriMesh::new(moved.collect(), mesh.triangles().to_vec())
    }
}

/// Depth quantisation: the depth is rounded to a multiple of the step (consumer depth cameras
/// store depth in steps of 1-4 mm). Orthographic: the `z` coordinate; pinhole: the distance
/// from the camera plane, the sample staying on its ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quantisation {
    /// Step in mm (greater than 0, at most 100).
    pub step_mm: f64,
}

/// Spikes: valid samples displaced along their ray, towards or away from the scanner with equal
/// probability, by a uniform amount.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spikes {
    /// Probability that a valid sample becomes a spike (0 to 1).
    pub fraction: f64,
    /// Smallest displacement, mm.
    pub min_mm: f64,
    /// Largest displacement, mm.
    pub max_mm: f64,
}

/// Outliers: background samples that become measurements at a random depth within the depth
/// range of the rendered surface, widened by 20 mm on both sides (stray reflections).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outliers {
    /// Number of outliers (at most the number of background samples; at most 10^7).
    pub count: usize,
}

/// Dropouts at grazing incidence: a sample whose surface normal makes an angle `a` with its ray
/// is dropped with probability 0 below `start_deg`, 1 from `full_deg` on, linear in between.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrazingDropout {
    /// Angle where dropouts begin, degrees.
    pub start_deg: f64,
    /// Angle from which every sample is dropped, degrees (`start_deg <= full_deg <= 90`).
    pub full_deg: f64,
}

/// Random circular holes (eyebrows, eyes, hair): centres drawn uniformly among the samples of
/// the clean rendering, radii uniform in `[min_radius_mm, max_radius_mm]` (measured in the
/// grid: pixels times the pitch).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Holes {
    /// Number of holes (at most 10000).
    pub count: usize,
    /// Smallest radius, mm.
    pub min_radius_mm: f64,
    /// Largest radius, mm.
    pub max_radius_mm: f64,
}

/// A cropped border: the samples within these distances (mm, measured in the grid) of the top,
/// bottom, left and right edges of the clean rendering's bounding box are dropped.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Border {
    /// Cut from the top, mm.
    pub top_mm: f64,
    /// Cut from the bottom, mm.
    pub bottom_mm: f64,
    /// Cut from the left (smaller `x`), mm.
    pub left_mm: f64,
    /// Cut from the right, mm.
    pub right_mm: f64,
}

/// The artifact model; every part is optional.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Artifacts {
    /// Gaussian depth noise.
    pub noise: Option<DepthNoise>,
    /// Depth quantisation (applied last, after noise, spikes and outliers).
    pub quantisation: Option<Quantisation>,
    /// Spikes.
    pub spikes: Option<Spikes>,
    /// Background outliers.
    pub outliers: Option<Outliers>,
    /// Dropouts at grazing angles.
    pub grazing: Option<GrazingDropout>,
    /// Random holes.
    pub holes: Option<Holes>,
    /// Cropped border.
    pub border: Option<Border>,
}

impl Artifacts {
    /// No artifact: the exact rendering.
    pub fn none() -> Self {
        Self::default()
    }

    /// A structured-light scanner like Bosphorus's: 0.1 mm noise, one spike in a thousand
    /// samples (2-10 mm), 50 outliers, dropouts from 70 to 80 degrees of incidence and 4 holes
    /// of 1-4 mm radius; no quantisation, no border.
    pub fn structured_light() -> Self {
        Self {
            noise: Some(DepthNoise { sigma_mm: 0.1 }),
            quantisation: None,
            spikes: Some(Spikes {
                fraction: 0.001,
                min_mm: 2.0,
                max_mm: 10.0,
            }),
            outliers: Some(Outliers { count: 50 }),
            grazing: Some(GrazingDropout {
                start_deg: 70.0,
                full_deg: 80.0,
            }),
            holes: Some(Holes {
                count: 4,
                min_radius_mm: 1.0,
                max_radius_mm: 4.0,
            }),
            border: None,
        }
    }

    /// A consumer depth camera: 1 mm noise, depths quantised to `step_mm`, dropouts from 65 to
    /// 80 degrees of incidence and 2 holes of 2-6 mm radius; no spikes, outliers or border (its
    /// flying pixels at the silhouette are [`crate::add_flying_pixels`], on the grid).
    pub fn depth_camera(step_mm: f64) -> Self {
        Self {
            noise: Some(DepthNoise { sigma_mm: 1.0 }),
            quantisation: Some(Quantisation { step_mm }),
            grazing: Some(GrazingDropout {
                start_deg: 65.0,
                full_deg: 80.0,
            }),
            holes: Some(Holes {
                count: 2,
                min_radius_mm: 2.0,
                max_radius_mm: 6.0,
            }),
            ..Self::none()
        }
    }

    /// Checks every part's sizes.
    pub fn validate(&self) -> Result<(), ScanError> {
        // (what, value, lo, hi, the range as the error says it): the value must be finite and
        // in [lo, hi]; in the order they are checked.
        let mut checks: Vec<(&str, f64, f64, f64, &str)> = Vec::new();
        if let Some(n) = self.noise {
            checks.push(("noise sigma_mm", n.sigma_mm, 0.0, 50.0, "0 to 50"));
        }
        if let Some(q) = self.quantisation {
            // From the smallest positive f64: greater than 0.
            let (v, lo) = (q.step_mm, f64::from_bits(1));
            checks.push((
                "quantisation step_mm",
                v,
                lo,
                100.0,
                "greater than 0, at most 100",
            ));
        }
        if let Some(s) = self.spikes {
            let (lo, hi) = (s.min_mm, s.max_mm);
            checks.extend([
                ("spikes fraction", s.fraction, 0.0, 1.0, "0 to 1"),
                ("spikes min_mm", lo, 0.0, 1e4, "0 to 10000"),
                ("spikes max_mm", hi, lo, 1e4, "min_mm to 10000"),
            ]);
        }
        if let Some(o) = self.outliers {
            checks.push(("outliers count", o.count as f64, 0.0, 1e7, "at most 10^7"));
        }
        if let Some(g) = self.grazing {
            let (lo, hi) = (g.start_deg, g.full_deg);
            checks.extend([
                ("grazing start_deg", lo, 0.0, 90.0, "0 to 90"),
                ("grazing full_deg", hi, lo, 90.0, "start_deg to 90"),
            ]);
        }
        if let Some(h) = self.holes {
            let (lo, hi) = (h.min_radius_mm, h.max_radius_mm);
            checks.extend([
                ("holes count", h.count as f64, 0.0, 1e4, "at most 10000"),
                ("holes min_radius_mm", lo, 0.0, 1e4, "0 to 10000"),
                ("holes max_radius_mm", hi, lo, 1e4, "min_radius_mm to 10000"),
            ]);
        }
        if let Some(b) = self.border {
            for (what, v) in [
                ("border top_mm", b.top_mm),
                ("border bottom_mm", b.bottom_mm),
                ("border left_mm", b.left_mm),
                ("border right_mm", b.right_mm),
            ] {
                checks.push((what, v, 0.0, 1e5, "0 to 100000"));
            }
        }
        for (what, v, lo, hi, range) in checks {
            if !(v.is_finite() && v >= lo && v <= hi) {
                return Err(ScanError::InvalidOption(format!(
                    "{what} = {v} (expected {range})"
                )));
            }
        }
        Ok(())
    }
}

/// Random stream of each part (one ChaCha8 seed, one stream per part).
const STREAM_GRAZING: u64 = 1;
const STREAM_HOLES: u64 = 2;
const STREAM_NOISE: u64 = 3;
const STREAM_SPIKES: u64 = 4;
const STREAM_OUTLIERS: u64 = 5;

fn stream(seed: u64, s: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream(s);
    r
}

/// Applies the artifact model to the clean rendering `hits`: fills `samples` (positions of
/// valid samples) and `status`, returns the counts (`rendered` left 0).
pub(crate) fn apply(
    a: &Artifacts,
    seed: u64,
    cam: &Camera,
    hits: &[Option<Hit>],
    samples: &mut [Option<DVec3>],
    status: &mut [SampleStatus],
) -> ScanStats {
    let n = hits.len();
    let nc = cam.ncols;
    let mut stats = ScanStats::default();
    let rendered: Vec<usize> = (0..n).filter(|&i| hits[i].is_some()).collect();
    if let Some(g) = a.grazing {
        let mut rng = stream(seed, STREAM_GRAZING);
        for i in 0..n {
            let u: f64 = rng.random();
            let Some(h) = hits[i] else { continue };
            let ang = h.cos_incidence.clamp(0.0, 1.0).acos().to_degrees();
            let drop = if ang >= g.full_deg {
                true
            } else if ang > g.start_deg {
                u < (ang - g.start_deg) / (g.full_deg - g.start_deg)
            } else {
                false
            };
            if drop && status[i] == SampleStatus::Valid {
                status[i] = SampleStatus::Grazing;
                stats.grazing += 1;
            }
        }
    }
    if let Some(h) = a.holes {
        let mut rng = stream(seed, STREAM_HOLES);
        for _ in 0..h.count {
            if rendered.is_empty() {
                break;
            }
            let centre = rendered[rng.random_range(0..rendered.len())];
            let radius = if h.max_radius_mm > h.min_radius_mm {
                rng.random_range(h.min_radius_mm..=h.max_radius_mm)
            } else {
                h.min_radius_mm
            } / cam.pitch;
            let (rc, cc) = ((centre / nc) as f64, (centre % nc) as f64);
            let r_lo = (rc - radius).ceil().max(0.0) as usize;
            let r_hi = ((rc + radius).floor() as usize).min(cam.nrows - 1);
            let c_lo = (cc - radius).ceil().max(0.0) as usize;
            let c_hi = ((cc + radius).floor() as usize).min(nc - 1);
            for r in r_lo..=r_hi {
                for c in c_lo..=c_hi {
                    let (dr, dc) = (r as f64 - rc, c as f64 - cc);
                    let i = r * nc + c;
                    if dr * dr + dc * dc <= radius * radius && status[i] == SampleStatus::Valid {
                        status[i] = SampleStatus::Hole;
                        stats.holes += 1;
                    }
                }
            }
        }
    }
    if let Some(b) = a.border {
        if let Some((r0, r1, c0, c1)) = bounds(&rendered, nc) {
            let p = cam.pitch;
            let top = r0 as f64 + b.top_mm / p;
            let bottom = r1 as f64 - b.bottom_mm / p;
            let left = c0 as f64 + b.left_mm / p;
            let right = c1 as f64 - b.right_mm / p;
            for &i in &rendered {
                let (r, c) = ((i / nc) as f64, (i % nc) as f64);
                let out = r < top || r > bottom || c < left || c > right;
                if out && status[i] == SampleStatus::Valid {
                    status[i] = SampleStatus::Border;
                    stats.border += 1;
                }
            }
        }
    }
    for i in 0..n {
        samples[i] = match (status[i], hits[i]) {
            (SampleStatus::Valid, Some(h)) => Some(h.point),
            _ => None,
        };
    }
    let ray_dir = |i: usize| cam.ray((i % nc) as f64, (i / nc) as f64).1;
    if let Some(nz) = a.noise {
        let mut rng = stream(seed, STREAM_NOISE);
        for (i, sample) in samples.iter_mut().enumerate() {
            let g: f64 = rng.sample(StandardNormal);
            if let Some(p) = sample {
                *p += ray_dir(i) * (nz.sigma_mm * g);
            }
        }
    }
    if let Some(s) = a.spikes {
        let mut rng = stream(seed, STREAM_SPIKES);
        for (i, sample) in samples.iter_mut().enumerate() {
            let u: f64 = rng.random();
            let m: f64 = rng.random();
            let towards: bool = rng.random();
            if let Some(p) = sample {
                if u < s.fraction {
                    let mag = s.min_mm + m * (s.max_mm - s.min_mm);
                    *p += ray_dir(i) * if towards { -mag } else { mag };
                    stats.spikes += 1;
                }
            }
        }
    }
    if let Some(o) = a.outliers {
        let mut rng = stream(seed, STREAM_OUTLIERS);
        let background: Vec<usize> = (0..n)
            .filter(|&i| status[i] == SampleStatus::Background)
            .collect();
        let (tmin, tmax) =
            rendered
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &i| {
                    let t = hits[i].map_or(0.0, |h| h.t);
                    (a.min(t), b.max(t))
                });
        if !background.is_empty() && tmin.is_finite() {
            let (lo, hi) = ((tmin - 20.0).max(1e-3), tmax + 20.0);
            let count = o.count.min(background.len());
            let mut chosen = vec![false; background.len()];
            let mut made = 0;
            // Distinct background samples, drawn without replacement by rejection.
            while made < count {
                let k = rng.random_range(0..background.len());
                let t = rng.random_range(lo..=hi);
                if chosen[k] {
                    continue;
                }
                chosen[k] = true;
                let i = background[k];
                let (org, d) = cam.ray((i % nc) as f64, (i / nc) as f64);
                samples[i] = Some(org + d * t);
                status[i] = SampleStatus::Valid;
                made += 1;
            }
            stats.outliers = made;
        }
    }
    if let Some(q) = a.quantisation {
        let s = q.step_mm;
        for p in samples.iter_mut().flatten() {
            match cam.kind {
                Kind::Ortho { .. } => p.z = (p.z / s).round() * s,
                Kind::Pinhole { centre, .. } => {
                    let depth = centre.z - p.z;
                    let qd = (depth / s).round() * s;
                    if depth > 0.0 && qd > 0.0 {
                        *p = centre + (*p - centre) * (qd / depth);
                    }
                }
            }
        }
    }
    stats.valid = status.iter().filter(|s| **s == SampleStatus::Valid).count();
    stats
}

/// Bounding rows and columns `(r0, r1, c0, c1)` of the sample indices.
fn bounds(idx: &[usize], nc: usize) -> Option<(usize, usize, usize, usize)> {
    let mut it = idx.iter();
    let &first = it.next()?;
    let init = (first / nc, first / nc, first % nc, first % nc);
    Some(it.fold(init, |(r0, r1, c0, c1), &i| {
        let (r, c) = (i / nc, i % nc);
        (r0.min(r), r1.max(r), c0.min(c), c1.max(c))
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_along_normals_moves_a_sphere_radially_by_sigma() {
        let sphere = meshcore::shapes::icosphere(4);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let noise = DepthNoise { sigma_mm: 0.5 };
        // A unit sphere in cm: 0.5 mm is 0.05 units, along the (radial) normals.
        let moved = noise.along_normals(&sphere, 10.0, &mut rng).unwrap();
        assert_eq!(moved.triangles(), sphere.triangles());
        let dr: Vec<f64> = moved.positions().iter().map(|p| p.length() - 1.0).collect();
        let sd = (dr.iter().map(|d| d * d).sum::<f64>() / dr.len() as f64).sqrt();
        assert!((0.045..0.055).contains(&sd), "{sd}");
        for (p, q) in sphere.positions().iter().zip(moved.positions()) {
            assert!(p.cross(*q).length() < 1e-3, "moved off the normal");
        }
        // The same stream moves the same way.
        let again = noise.along_normals(&sphere, 10.0, &mut ChaCha8Rng::seed_from_u64(3));
        assert_eq!(again.unwrap().positions(), moved.positions());
    }

    #[test]
    fn a_depth_camera_quantises_and_drops_out_but_has_no_spikes() {
        let a = Artifacts::depth_camera(2.5);
        assert!(a.validate().is_ok());
        assert_eq!(a.quantisation.map(|q| q.step_mm), Some(2.5));
        assert_eq!(a.noise.map(|n| n.sigma_mm), Some(1.0));
        assert_eq!(
            a.grazing.map(|g| (g.start_deg, g.full_deg)),
            Some((65.0, 80.0))
        );
        assert_eq!(a.holes.map(|h| h.count), Some(2));
        assert!(a.spikes.is_none() && a.outliers.is_none() && a.border.is_none());
        assert!(Artifacts::depth_camera(0.0).validate().is_err());
    }
}
