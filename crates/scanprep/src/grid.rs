//! Steps on a range grid ([`BntGrid`], mm): checks, spike and outlier removal, hole filling.
//!
//! The grid is a height field seen from the scanner (`+z` towards it): depth is the `z`
//! coordinate, neighbours are the samples of the same window of rows and columns.

use crate::{Hole, ScanPrepError};
use mesh_io::BntGrid;
use meshcore::DVec3;

/// Coordinates of a measured sample larger than this (mm, absolute) are not measurements but
/// sentinel values that miss the background rule (10 km).
pub const MAX_COORDINATE_MM: f64 = 1e7;

/// What [`check_grid`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridCheck {
    /// Samples in the grid.
    pub samples: usize,
    /// Valid samples (measurements).
    pub valid: usize,
    /// Valid samples over the samples inside the scanned silhouette (a sample is inside when
    /// valid samples lie on both sides of it in its row and in its column), in `[0, 1]`.
    pub coverage: f64,
    /// Grid spacing: median 3D distance between valid 4-neighbours (mm); `None` when no two
    /// valid samples are neighbours.
    pub spacing: Option<f64>,
}

/// Checks a grid: one sample per cell, finite sentinel and coordinates (a NaN is an error, not
/// background), no sentinel-like value outside the background rule (`|coordinate| >
/// MAX_COORDINATE_MM` in a valid sample), at least one valid sample and a coverage of at least
/// `min_coverage`.
pub fn check_grid(grid: &BntGrid, min_coverage: f64) -> Result<GridCheck, ScanPrepError> {
    let n = grid.nrows.saturating_mul(grid.ncols);
    if grid.xyz.len() != n || grid.uv.len() != n {
        return Err(ScanPrepError::InvalidInput(format!(
            "grid of {} x {} with {} xyz and {} uv entries",
            grid.nrows,
            grid.ncols,
            grid.xyz.len(),
            grid.uv.len()
        )));
    }
    if !grid.zmin.is_finite() {
        return Err(ScanPrepError::InvalidInput(format!(
            "background sentinel zmin = {} is not finite",
            grid.zmin
        )));
    }
    let nc = grid.ncols.max(1);
    for (i, p) in grid.xyz.iter().enumerate() {
        if !p.is_finite() {
            return Err(ScanPrepError::NonFinite {
                row: i / nc,
                col: i % nc,
            });
        }
        if grid.is_valid(i) && p.abs().max_element() > MAX_COORDINATE_MM {
            return Err(ScanPrepError::SentinelLike {
                row: i / nc,
                col: i % nc,
                value: p.abs().max_element(),
                zmin: grid.zmin,
            });
        }
    }
    let (_, _, valid) = valid_mask(grid);
    let n_valid = valid.iter().filter(|&&v| v).count();
    if n_valid == 0 {
        return Err(ScanPrepError::Empty(
            "the range grid has no valid sample".into(),
        ));
    }
    let inside = silhouette(&valid, grid.nrows, grid.ncols);
    let n_inside = inside.iter().filter(|&&v| v).count().max(1);
    let coverage = n_valid as f64 / n_inside as f64;
    if coverage < min_coverage {
        return Err(ScanPrepError::MostlyHoles {
            coverage,
            min: min_coverage,
        });
    }
    Ok(GridCheck {
        samples: n,
        valid: n_valid,
        coverage,
        spacing: grid_spacing(grid),
    })
}

/// Samples between valid samples in both their row and their column (valid ones included).
fn silhouette(valid: &[bool], nr: usize, nc: usize) -> Vec<bool> {
    let mut row_span = vec![(usize::MAX, 0usize); nr];
    let mut col_span = vec![(usize::MAX, 0usize); nc];
    for r in 0..nr {
        for c in 0..nc {
            if valid[r * nc + c] {
                row_span[r] = (row_span[r].0.min(c), row_span[r].1.max(c));
                col_span[c] = (col_span[c].0.min(r), col_span[c].1.max(r));
            }
        }
    }
    let mut out = vec![false; nr * nc];
    for r in 0..nr {
        for c in 0..nc {
            let (a, b) = row_span[r];
            let (u, w) = col_span[c];
            out[r * nc + c] = a <= c && c <= b && u <= r && r <= w;
        }
    }
    out
}

/// The grid's rows, columns and per-sample validity (row-major).
fn valid_mask(grid: &BntGrid) -> (usize, usize, Vec<bool>) {
    let valid = (0..grid.nrows * grid.ncols)
        .map(|i| grid.is_valid(i))
        .collect();
    (grid.nrows, grid.ncols, valid)
}

/// Median 3D distance between valid 4-neighbouring samples; `None` when there is no such pair.
pub fn grid_spacing(grid: &BntGrid) -> Option<f64> {
    let (nr, nc) = (grid.nrows, grid.ncols);
    let mut lens = Vec::new();
    for r in 0..nr {
        for c in 0..nc {
            let i = r * nc + c;
            if !grid.is_valid(i) {
                continue;
            }
            if c + 1 < nc && grid.is_valid(i + 1) {
                lens.push((grid.xyz[i] - grid.xyz[i + 1]).length());
            }
            if r + 1 < nr && grid.is_valid(i + nc) {
                lens.push((grid.xyz[i] - grid.xyz[i + nc]).length());
            }
        }
    }
    if lens.is_empty() {
        return None;
    }
    let mid = lens.len() / 2;
    Some(*lens.select_nth_unstable_by(mid, f64::total_cmp).1)
}

/// Options of [`remove_grid_spikes`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpikeOptions {
    /// Half width of the square window of neighbours (2: a 5 x 5 window).
    pub window_radius: usize,
    /// A sample is a spike when its depth differs from the predicted depth by more than
    /// `threshold_spacings` grid spacings and more than `mad_factor` robust standard
    /// deviations of the prediction. The prediction is the median, over the pairs of opposite
    /// valid neighbours in the window, of the pair's mean depth (exact on a plane, whatever
    /// its slope; one spike spoils one pair); the spread is 1.4826 times the median absolute
    /// deviation of those means. Samples with fewer than 3 such pairs are kept. Default 3.
    pub threshold_spacings: f64,
    /// See `threshold_spacings`; the spread term keeps strongly curved parts seen at a slant
    /// (the rim of a sphere, the sides of the nose) where they are. Default 4.
    pub mad_factor: f64,
    /// A valid sample with fewer valid neighbours in its window is an isolated outlier and
    /// removed. Default 4.
    pub min_neighbours: usize,
}

impl Default for SpikeOptions {
    fn default() -> Self {
        Self {
            window_radius: 2,
            threshold_spacings: 3.0,
            mad_factor: 4.0,
            min_neighbours: 4,
        }
    }
}

/// What [`remove_grid_spikes`] removed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SpikeCounts {
    /// Samples whose depth jumped away from their neighbours'.
    pub spikes: usize,
    /// Samples with too few valid neighbours (stray outliers in the background).
    pub isolated: usize,
}

/// Turns spikes and isolated outliers into background (see [`SpikeOptions`]). Every decision
/// is taken on the input grid (removals do not influence each other), so the result does not
/// depend on the sample order. A grid without two neighbouring valid samples has no spacing:
/// only isolated samples are removed then.
pub fn remove_grid_spikes(
    grid: &mut BntGrid,
    o: &SpikeOptions,
) -> Result<SpikeCounts, ScanPrepError> {
    if o.window_radius == 0 || o.window_radius > 50 {
        return Err(ScanPrepError::InvalidOption(format!(
            "spike window radius {} (expected 1 to 50)",
            o.window_radius
        )));
    }
    for (name, v) in [
        ("spike threshold_spacings", o.threshold_spacings),
        ("spike mad_factor", o.mad_factor),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(ScanPrepError::InvalidOption(format!(
                "{name} = {v} (expected a finite value >= 0)"
            )));
        }
    }
    let (nr, nc, valid) = valid_mask(grid);
    let n = nr * nc;
    let thr = grid_spacing(grid).map(|s| o.threshold_spacings * s);
    let w = o.window_radius as isize;
    let at = |r: usize, c: usize, dr: isize, dc: isize| -> Option<usize> {
        let (rr, cc) = (r as isize + dr, c as isize + dc);
        (rr >= 0 && cc >= 0 && rr < nr as isize && cc < nc as isize)
            .then(|| rr as usize * nc + cc as usize)
    };
    let mut remove = vec![0u8; n];
    let mut zs: Vec<f64> = Vec::with_capacity((2 * o.window_radius + 1).pow(2));
    for r in 0..nr {
        for c in 0..nc {
            let i = r * nc + c;
            if !valid[i] {
                continue;
            }
            // Neighbour count, and the mean depth of each pair of valid opposite neighbours
            // (exact at the centre of a plane, a curvature term off it).
            let mut count = 0usize;
            zs.clear();
            for dr in -w..=w {
                for dc in -w..=w {
                    if dr == 0 && dc == 0 {
                        continue;
                    }
                    let Some(j) = at(r, c, dr, dc) else { continue };
                    if !valid[j] {
                        continue;
                    }
                    count += 1;
                    // Each pair once: the half-window with dr > 0, or dr == 0 and dc > 0.
                    if dr > 0 || (dr == 0 && dc > 0) {
                        if let Some(k) = at(r, c, -dr, -dc) {
                            if valid[k] {
                                zs.push(0.5 * (grid.xyz[j].z + grid.xyz[k].z));
                            }
                        }
                    }
                }
            }
            if count < o.min_neighbours {
                remove[i] = 2;
                continue;
            }
            let Some(thr) = thr else { continue };
            if zs.len() < MIN_PAIRS {
                continue;
            }
            let med = median(&mut zs);
            for z in zs.iter_mut() {
                *z = (*z - med).abs();
            }
            let mad = 1.4826 * median(&mut zs);
            if (grid.xyz[i].z - med).abs() > thr.max(o.mad_factor * mad) {
                remove[i] = 1;
            }
        }
    }
    let mut counts = SpikeCounts::default();
    let bg = DVec3::splat(grid.zmin);
    for (i, &k) in remove.iter().enumerate() {
        match k {
            1 => counts.spikes += 1,
            2 => counts.isolated += 1,
            _ => continue,
        }
        grid.xyz[i] = bg;
    }
    Ok(counts)
}

/// Fewer pairs of opposite valid neighbours than this: no spike decision (the sample is kept).
const MIN_PAIRS: usize = 3;

/// Median of a non-empty slice (reorders it; upper median for even lengths).
fn median(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Valid samples within this many rows and columns of a hole support its fit.
const SUPPORT_RING: usize = 3;

/// Fills the holes of a grid whose diameter is at most `max_diameter_mm`, and reports every
/// hole (filled or not), in order of their first sample.
///
/// A hole is a 4-connected set of invalid samples that does not reach the edge of the grid
/// (background around the object always does). Its diameter is the largest distance between
/// two samples of its rim (the valid 4-neighbours of its samples). A filled sample gets `x`, `y` and `(u, v)` from
/// an affine fit in `(column, row)` and `z` from a quadratic fit in `(x, y)`, both least
/// squares over the valid samples within 3 rows and columns of the hole (exact on planes and
/// quadrics seen as height fields). A hole with fewer than 12 supporting samples is left and
/// reported as not filled.
pub fn fill_grid_holes(
    grid: &mut BntGrid,
    max_diameter_mm: f64,
) -> Result<Vec<Hole>, ScanPrepError> {
    if !(max_diameter_mm.is_finite() && max_diameter_mm >= 0.0) {
        return Err(ScanPrepError::InvalidOption(format!(
            "max hole diameter {max_diameter_mm} mm (expected a finite value >= 0)"
        )));
    }
    let (nr, nc, valid) = valid_mask(grid);
    let n = nr * nc;
    let mut label = vec![u32::MAX; n];
    let mut holes = Vec::new();
    let mut stack = Vec::new();
    for start in 0..n {
        if valid[start] || label[start] != u32::MAX {
            continue;
        }
        let id = holes.len() as u32;
        let mut members = Vec::new();
        let mut touches_edge = false;
        label[start] = id;
        stack.push(start);
        while let Some(i) = stack.pop() {
            members.push(i);
            let (r, c) = (i / nc, i % nc);
            if r == 0 || c == 0 || r + 1 == nr || c + 1 == nc {
                touches_edge = true;
            }
            let mut visit = |j: usize| {
                if !valid[j] && label[j] == u32::MAX {
                    label[j] = id;
                    stack.push(j);
                }
            };
            if r > 0 {
                visit(i - nc);
            }
            if r + 1 < nr {
                visit(i + nc);
            }
            if c > 0 {
                visit(i - 1);
            }
            if c + 1 < nc {
                visit(i + 1);
            }
        }
        holes.push((members, touches_edge));
    }
    let mut out = Vec::new();
    for (mut members, touches_edge) in holes {
        if touches_edge {
            continue;
        }
        members.sort_unstable();
        let (mut r0, mut r1, mut c0, mut c1) = (usize::MAX, 0, usize::MAX, 0);
        for &i in &members {
            r0 = r0.min(i / nc);
            r1 = r1.max(i / nc);
            c0 = c0.min(i % nc);
            c1 = c1.max(i % nc);
        }
        // Centre: mean of the valid 4-neighbours of the hole (its rim).
        let mut rim = Vec::new();
        for &i in &members {
            // Not on the grid edge (the hole does not touch it), so all four exist.
            for j in [i - nc, i + nc, i - 1, i + 1] {
                if valid[j] {
                    rim.push(j);
                }
            }
        }
        rim.sort_unstable();
        rim.dedup();
        let rim: Vec<DVec3> = rim.iter().map(|&j| grid.xyz[j]).collect();
        let centre = rim.iter().sum::<DVec3>() / rim.len().max(1) as f64;
        let diameter = rim_diameter(&rim);
        let mut hole = Hole {
            size: members.len(),
            diameter_mm: diameter,
            centre,
            filled: false,
        };
        if diameter <= max_diameter_mm {
            let support = support_of(&valid, nr, nc, &members, (r0, r1, c0, c1));
            if support.len() >= 12 {
                hole.filled = fill_one(grid, &members, &support);
            }
        }
        out.push(hole);
    }
    Ok(out)
}

/// Largest distance between two rim samples (the bounding-box diagonal for rims of more than
/// 3000 samples, to bound the cost).
fn rim_diameter(rim: &[DVec3]) -> f64 {
    if rim.len() > 3000 {
        return meshcore::Aabb::from_points(rim).map_or(0.0, |b| b.diagonal());
    }
    let mut d2 = 0.0f64;
    for (k, a) in rim.iter().enumerate() {
        for b in &rim[k + 1..] {
            d2 = d2.max(a.distance_squared(*b));
        }
    }
    d2.sqrt()
}

/// Valid samples within [`SUPPORT_RING`] rows and columns of a hole sample (in grid order).
fn support_of(
    valid: &[bool],
    nr: usize,
    nc: usize,
    members: &[usize],
    (r0, r1, c0, c1): (usize, usize, usize, usize),
) -> Vec<usize> {
    let (sr0, sr1) = (
        r0.saturating_sub(SUPPORT_RING),
        (r1 + SUPPORT_RING).min(nr - 1),
    );
    let (sc0, sc1) = (
        c0.saturating_sub(SUPPORT_RING),
        (c1 + SUPPORT_RING).min(nc - 1),
    );
    let (h, w) = (sr1 - sr0 + 1, sc1 - sc0 + 1);
    let mut near = vec![false; h * w];
    for &i in members {
        let (r, c) = (i / nc, i % nc);
        for rr in r.saturating_sub(SUPPORT_RING).max(sr0)..=(r + SUPPORT_RING).min(sr1) {
            for cc in c.saturating_sub(SUPPORT_RING).max(sc0)..=(c + SUPPORT_RING).min(sc1) {
                near[(rr - sr0) * w + (cc - sc0)] = true;
            }
        }
    }
    let mut out = Vec::new();
    for rr in sr0..=sr1 {
        for cc in sc0..=sc1 {
            let i = rr * nc + cc;
            if valid[i] && near[(rr - sr0) * w + (cc - sc0)] {
                out.push(i);
            }
        }
    }
    out
}

/// Fits and writes the hole samples; false (grid untouched) when a fit is singular or gives a
/// non-finite value.
fn fill_one(grid: &mut BntGrid, members: &[usize], support: &[usize]) -> bool {
    let nc = grid.ncols;
    let rc = |i: usize| ((i % nc) as f64, (i / nc) as f64);
    // Centre the parameters for conditioning.
    let (mc, mr) = support.iter().fold((0.0, 0.0), |(a, b), &i| {
        let (c, r) = rc(i);
        (a + c, b + r)
    });
    let (mc, mr) = (mc / support.len() as f64, mr / support.len() as f64);
    let affine_rows: Vec<[f64; 3]> = support
        .iter()
        .map(|&i| {
            let (c, r) = rc(i);
            [1.0, c - mc, r - mr]
        })
        .collect();
    let targets = |f: &dyn Fn(usize) -> f64| support.iter().map(|&i| f(i)).collect::<Vec<_>>();
    let fx = least_squares::<3>(&affine_rows, &targets(&|i| grid.xyz[i].x));
    let fy = least_squares::<3>(&affine_rows, &targets(&|i| grid.xyz[i].y));
    let fu = least_squares::<3>(&affine_rows, &targets(&|i| grid.uv[i][0]));
    let fv = least_squares::<3>(&affine_rows, &targets(&|i| grid.uv[i][1]));
    let (Some(fx), Some(fy), Some(fu), Some(fv)) = (fx, fy, fu, fv) else {
        return false;
    };
    let (mx, my) = (centre_of(grid, support, 0), centre_of(grid, support, 1));
    let scale = support
        .iter()
        .map(|&i| (grid.xyz[i].x - mx).abs().max((grid.xyz[i].y - my).abs()))
        .fold(0.0f64, f64::max)
        .max(1e-12);
    let quad = |x: f64, y: f64| {
        let (a, b) = ((x - mx) / scale, (y - my) / scale);
        [1.0, a, b, a * a, a * b, b * b]
    };
    let quad_rows: Vec<[f64; 6]> = support
        .iter()
        .map(|&i| quad(grid.xyz[i].x, grid.xyz[i].y))
        .collect();
    let Some(fz) = least_squares::<6>(&quad_rows, &targets(&|i| grid.xyz[i].z)) else {
        return false;
    };
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut new = Vec::with_capacity(members.len());
    for &i in members {
        let (c, r) = rc(i);
        let a = [1.0, c - mc, r - mr];
        let x = dot(&a, &fx);
        let y = dot(&a, &fy);
        let z = dot(&quad(x, y), &fz);
        let p = DVec3::new(x, y, z);
        let uv = [dot(&a, &fu), dot(&a, &fv)];
        if !p.is_finite()
            || p.abs().max_element() > MAX_COORDINATE_MM
            || !uv[0].is_finite()
            || !uv[1].is_finite()
        {
            return false;
        }
        if p.x == grid.zmin || p.y == grid.zmin || p.z == grid.zmin {
            return false;
        }
        new.push((i, p, uv));
    }
    for (i, p, uv) in new {
        grid.xyz[i] = p;
        grid.uv[i] = uv;
    }
    true
}

fn centre_of(grid: &BntGrid, support: &[usize], axis: usize) -> f64 {
    support.iter().map(|&i| grid.xyz[i][axis]).sum::<f64>() / support.len() as f64
}

/// Least squares `min |A c - t|` by the normal equations with partial pivoting; `None` when
/// they are (numerically) singular.
pub(crate) fn least_squares<const K: usize>(rows: &[[f64; K]], t: &[f64]) -> Option<[f64; K]> {
    let mut m = [[0.0; K]; K];
    let mut rhs = [0.0; K];
    for (a, &y) in rows.iter().zip(t) {
        for i in 0..K {
            rhs[i] += a[i] * y;
            for j in 0..K {
                m[i][j] += a[i] * a[j];
            }
        }
    }
    let norm = (0..K).map(|i| m[i][i].abs()).fold(0.0f64, f64::max);
    if norm == 0.0 || !norm.is_finite() {
        return None;
    }
    for col in 0..K {
        let piv = (col..K).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        if m[piv][col].abs() <= 1e-12 * norm {
            return None;
        }
        m.swap(col, piv);
        rhs.swap(col, piv);
        let pivot_row = m[col];
        for r in col + 1..K {
            let f = m[r][col] / pivot_row[col];
            for (x, p) in m[r][col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= f * p;
            }
            rhs[r] -= f * rhs[col];
        }
    }
    let mut x = [0.0; K];
    for i in (0..K).rev() {
        let s: f64 = (i + 1..K).map(|j| m[i][j] * x[j]).sum();
        x[i] = (rhs[i] - s) / m[i][i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn least_squares_recovers_a_quadratic() {
        let f = |a: f64, b: f64| 1.0 + 2.0 * a - b + 0.5 * a * a + 0.25 * a * b - 3.0 * b * b;
        let mut rows = Vec::new();
        let mut t = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                let (a, b) = (i as f64 * 0.3 - 0.6, j as f64 * 0.2 - 0.4);
                rows.push([1.0, a, b, a * a, a * b, b * b]);
                t.push(f(a, b));
            }
        }
        let c = least_squares::<6>(&rows, &t).unwrap();
        for (got, want) in c.iter().zip([1.0, 2.0, -1.0, 0.5, 0.25, -3.0]) {
            assert!((got - want).abs() < 1e-9, "{c:?}");
        }
        // Collinear samples: singular.
        let rows: Vec<[f64; 3]> = (0..5).map(|i| [1.0, i as f64, i as f64]).collect();
        assert!(least_squares::<3>(&rows, &[0.0; 5]).is_none());
    }
}
