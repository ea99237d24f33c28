//! Flying pixels: the depth between a silhouette's surface and its background that
//! time-of-flight and stereo depth cameras return beside the silhouette.

use crate::ScanError;
use mesh_io::BntGrid;
use meshcore::DVec3;
use rand::Rng;

/// Flying pixels of [`add_flying_pixels`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlyingPixels {
    /// Probability that a background sample beside a measurement becomes a flying pixel (0 to
    /// 1).
    pub rate: f64,
    /// Least depth behind its measured neighbour, mm.
    pub min_behind_mm: f64,
    /// Largest depth behind its measured neighbour, mm (`min_behind_mm <= max_behind_mm`).
    pub max_behind_mm: f64,
}

impl Default for FlyingPixels {
    /// Half of the silhouette's background neighbours, 5 to 60 mm behind.
    fn default() -> Self {
        Self {
            rate: 0.5,
            min_behind_mm: 5.0,
            max_behind_mm: 60.0,
        }
    }
}

/// Adds flying pixels to a range grid in mm seen from `+z` (the grids of [`crate::scan`]):
/// each background sample with a measured 4-neighbour (the first of right, left, below,
/// above) becomes, with probability `options.rate`, a measurement one grid step from that
/// neighbour across the grid and `U(min_behind_mm, max_behind_mm)` farther from the scanner.
/// The grid's steps are the mean differences of neighbouring measurements. Draws from `rng`
/// (per candidate sample, row-major: one uniform for the rate, and the depth for a flying
/// pixel), so the same stream gives the same pixels. Returns how many were added; errors on
/// options out of range or a grid whose sample count is not `nrows * ncols`.
pub fn add_flying_pixels<R: Rng>(
    grid: &mut BntGrid,
    options: &FlyingPixels,
    rng: &mut R,
) -> Result<usize, ScanError> {
    let FlyingPixels {
        rate,
        min_behind_mm: lo,
        max_behind_mm: hi,
    } = *options;
    if !(0.0..=1.0).contains(&rate) {
        return Err(ScanError::InvalidOption(format!(
            "flying pixel rate {rate} (expected 0 to 1)"
        )));
    }
    if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo < hi) {
        return Err(ScanError::InvalidOption(format!(
            "flying pixel depths {lo} to {hi} mm (expected 0 <= min < max, finite)"
        )));
    }
    let (nr, nc) = (grid.nrows, grid.ncols);
    if grid.xyz.len() != nr * nc {
        return Err(ScanError::InvalidOption(format!(
            "a grid of {nr} x {nc} samples holds {} points",
            grid.xyz.len()
        )));
    }
    if nr == 0 || nc == 0 {
        return Ok(0);
    }
    // The grid's steps along a column and along a row, from neighbouring measurements.
    let step = |dr: usize, dc: usize| -> DVec3 {
        let (mut s, mut n) = (DVec3::ZERO, 0);
        for r in 0..nr - dr {
            for c in 0..nc - dc {
                let (i, j) = (r * nc + c, (r + dr) * nc + c + dc);
                if grid.is_valid(i) && grid.is_valid(j) {
                    s += grid.xyz[j] - grid.xyz[i];
                    n += 1;
                }
            }
        }
        let v = s / n.max(1) as f64;
        DVec3::new(v.x, v.y, 0.0)
    };
    let (down, right) = (step(1, 0), step(0, 1));
    let valid: Vec<bool> = (0..nr * nc).map(|i| grid.is_valid(i)).collect();
    let mut added = 0;
    for r in 0..nr {
        for c in 0..nc {
            let i = r * nc + c;
            if valid[i] {
                continue;
            }
            let nb = [(0isize, 1isize), (0, -1), (1, 0), (-1, 0)]
                .into_iter()
                .find_map(|(a, b)| {
                    let (rr, cc) = (r as isize + a, c as isize + b);
                    (rr >= 0 && cc >= 0 && (rr as usize) < nr && (cc as usize) < nc)
                        .then(|| (rr as usize * nc + cc as usize, a, b))
                        .filter(|(j, _, _)| valid[*j])
                });
            let Some((j, a, b)) = nb else { continue };
            if rng.random::<f64>() >= rate {
                continue;
            }
            let p = grid.xyz[j] - down * a as f64 - right * b as f64;
            grid.xyz[i] = DVec3::new(p.x, p.y, p.z - rng.random_range(lo..hi));
            added += 1;
        }
    }
    Ok(added)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// A 6 x 6 grid of 2 mm pitch at depth 100 with a measured 2 x 2 block in the middle.
    fn grid() -> BntGrid {
        let (nr, nc, zmin) = (6, 6, crate::BACKGROUND);
        let xyz = (0..nr * nc)
            .map(|i| {
                let (r, c) = (i / nc, i % nc);
                if (2..4).contains(&r) && (2..4).contains(&c) {
                    DVec3::new(2.0 * c as f64, -2.0 * r as f64, 100.0)
                } else {
                    DVec3::splat(zmin)
                }
            })
            .collect();
        BntGrid {
            nrows: nr,
            ncols: nc,
            zmin,
            image_file: String::new(),
            xyz,
            uv: vec![[0.0, 0.0]; nr * nc],
        }
    }

    #[test]
    fn puts_pixels_beside_the_silhouette_behind_it() {
        let mut g = grid();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let all = FlyingPixels {
            rate: 1.0,
            ..FlyingPixels::default()
        };
        // The 8 background samples that share an edge with the block.
        assert_eq!(add_flying_pixels(&mut g, &all, &mut rng).unwrap(), 8);
        let valid: Vec<usize> = (0..36).filter(|&i| g.is_valid(i)).collect();
        assert_eq!(valid.len(), 12);
        for i in valid {
            let (r, c) = (i / 6, i % 6);
            let p = g.xyz[i];
            // On the grid's lattice, 5 to 60 mm behind the block's depth.
            assert!((p.x - 2.0 * c as f64).abs() < 1e-9 && (p.y + 2.0 * r as f64).abs() < 1e-9);
            assert!(p.z == 100.0 || (40.0..=95.0).contains(&p.z), "{p}");
        }
        let mut none = grid();
        let off = FlyingPixels {
            rate: 0.0,
            ..FlyingPixels::default()
        };
        assert_eq!(add_flying_pixels(&mut none, &off, &mut rng).unwrap(), 0);
        let bad = FlyingPixels {
            rate: 1.5,
            ..FlyingPixels::default()
        };
        assert!(add_flying_pixels(&mut none, &bad, &mut rng).is_err());
    }
}
