//! Bosphorus `.bnt` range grids (layout in `docs/algorithms.md` section 4.1 of the shared
//! specification) and their triangulation.

use crate::{IoError, LoadedMesh};
use meshcore::{DVec3, TriMesh};
use std::path::Path;

/// A range grid as stored in a `.bnt` file, with rows in image order (row 0 at the top; the
/// file stores the bottom row first and the reader flips it).
#[derive(Debug, Clone, PartialEq)]
pub struct BntGrid {
    /// Number of rows.
    pub nrows: usize,
    /// Number of columns.
    pub ncols: usize,
    /// Background sentinel (`-1e9` in the Bosphorus data).
    pub zmin: f64,
    /// Name of the texture image the (u, v) coordinates refer to.
    pub image_file: String,
    /// Per sample (index `row * ncols + col`): x, y, z in mm.
    pub xyz: Vec<DVec3>,
    /// Per sample: normalised texture coordinates (u, v).
    pub uv: Vec<[f64; 2]>,
}

impl BntGrid {
    /// Whether sample `i` is a measurement (not background: no coordinate equals `zmin`).
    pub fn is_valid(&self, i: usize) -> bool {
        let p = self.xyz[i];
        p.x != self.zmin && p.y != self.zmin && p.z != self.zmin
    }

    /// Checks that the grid can be written as a `.bnt` file the reader accepts: 1 to 65535 rows
    /// and columns, one `xyz` and one `uv` entry per sample, an image name of at most 65535
    /// bytes, finite coordinates and a finite `zmin` (background samples hold `zmin` itself).
    pub fn check_writable(&self) -> Result<(), String> {
        let max = u16::MAX as usize;
        if self.nrows == 0 || self.ncols == 0 || self.nrows > max || self.ncols > max {
            return Err(format!(
                "grid is {} x {}; a .bnt grid has 1 to {max} rows and columns",
                self.nrows, self.ncols
            ));
        }
        let n = self.nrows * self.ncols;
        if self.xyz.len() != n || self.uv.len() != n {
            return Err(format!(
                "{} xyz and {} uv entries for {} x {} = {n} samples",
                self.xyz.len(),
                self.uv.len(),
                self.nrows,
                self.ncols
            ));
        }
        if 5 * n > u32::MAX as usize {
            return Err(format!("{n} samples do not fit the 32-bit data length"));
        }
        if self.image_file.len() > max {
            return Err(format!(
                "image name of {} bytes; at most {max}",
                self.image_file.len()
            ));
        }
        if !self.zmin.is_finite() {
            return Err(format!(
                "background sentinel zmin = {} is not finite",
                self.zmin
            ));
        }
        if let Some(i) = (0..n).find(|&i| !self.xyz[i].is_finite()) {
            return Err(format!(
                "sample {i} (row {}, column {}) has a non-finite coordinate {:?}; background samples hold zmin = {}",
                i / self.ncols,
                i % self.ncols,
                self.xyz[i].to_array(),
                self.zmin
            ));
        }
        if let Some(i) = (0..n).find(|&i| !self.uv[i].iter().all(|c| c.is_finite())) {
            return Err(format!(
                "sample {i} has a non-finite texture coordinate {:?}",
                self.uv[i]
            ));
        }
        Ok(())
    }

    /// Serialises the grid in the `.bnt` layout (bottom row first) without checks; see
    /// [`write_bnt_to_bytes`] for the checked writer.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(&(self.nrows as u16).to_le_bytes());
        out.extend_from_slice(&(self.ncols as u16).to_le_bytes());
        out.extend_from_slice(&self.zmin.to_le_bytes());
        out.extend_from_slice(&(self.image_file.len() as u16).to_le_bytes());
        out.extend_from_slice(self.image_file.as_bytes());
        let n = self.nrows * self.ncols;
        out.extend_from_slice(&((n * 5) as u32).to_le_bytes());
        for block in 0..5 {
            for fr in 0..self.nrows {
                let r = self.nrows - 1 - fr;
                for c in 0..self.ncols {
                    let i = r * self.ncols + c;
                    let v = match block {
                        0 => self.xyz[i].x,
                        1 => self.xyz[i].y,
                        2 => self.xyz[i].z,
                        3 => self.uv[i][0],
                        _ => self.uv[i][1],
                    };
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
        out
    }
}

/// Options of the grid triangulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BntOptions {
    /// Triangles whose longest edge exceeds `max_edge_factor * s` are dropped, where `s` is the
    /// grid spacing: the median 3D length of the horizontal and vertical edges between valid
    /// neighbouring samples. Default 4 (about 3 mm on Bosphorus scans, whose spacing is
    /// ~0.77 mm): such triangles bridge depth jumps (nose sides, hair, occluders). A cell
    /// diagonal is ~1.41 s, so regular triangles are never dropped.
    pub max_edge_factor: f64,
    /// Keep only the largest connected component (by vertex count). Default true.
    pub largest_component_only: bool,
}

impl Default for BntOptions {
    fn default() -> Self {
        Self {
            max_edge_factor: 4.0,
            largest_component_only: true,
        }
    }
}

struct Reader<'a> {
    b: &'a [u8],
    off: usize,
    file: &'a str,
}

impl Reader<'_> {
    fn take(&mut self, n: usize, what: &str) -> Result<&[u8], IoError> {
        if self.b.len() - self.off < n {
            return Err(IoError::byte(
                self.file,
                self.off,
                format!(
                    "file ends while reading {what} ({n} bytes needed, {} left)",
                    self.b.len() - self.off
                ),
            ));
        }
        let s = &self.b[self.off..self.off + n];
        self.off += n;
        Ok(s)
    }
    fn u16(&mut self, what: &str) -> Result<u16, IoError> {
        let s = self.take(2, what)?;
        Ok(u16::from_le_bytes([s[0], s[1]]))
    }
    fn u32(&mut self, what: &str) -> Result<u32, IoError> {
        let s = self.take(4, what)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
    fn f64(&mut self, what: &str) -> Result<f64, IoError> {
        let s = self.take(8, what)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(s);
        Ok(f64::from_le_bytes(a))
    }
}

/// Parses the bytes of a `.bnt` file into a grid.
pub(crate) fn parse_bnt_grid(bytes: &[u8], file: &str) -> Result<BntGrid, IoError> {
    let mut r = Reader {
        b: bytes,
        off: 0,
        file,
    };
    let nrows = r.u16("nrows")? as usize;
    let ncols = r.u16("ncols")? as usize;
    let zmin = r.f64("zmin")?;
    let len = r.u16("image name length")? as usize;
    let name = String::from_utf8_lossy(r.take(len, "image name")?).into_owned();
    let len_off = r.off;
    let len2 = r.u32("data length")? as usize;
    let n = nrows * ncols;
    if n == 0 {
        return Err(IoError::byte(
            file,
            0,
            format!("empty grid ({nrows} x {ncols})"),
        ));
    }
    if len2 != 5 * n {
        return Err(IoError::byte(
            file,
            len_off,
            format!(
                "data length {len2} is not 5 x {nrows} x {ncols} = {}",
                5 * n
            ),
        ));
    }
    let left = bytes.len() - r.off;
    if left < 8 * len2 {
        return Err(IoError::byte(file, r.off, format!("header claims {len2} doubles ({} bytes) but only {left} bytes remain (truncated file)", 8 * len2)));
    }
    if left > 8 * len2 {
        return Err(IoError::byte(
            file,
            r.off + 8 * len2,
            format!(
                "{} unexpected bytes after the {len2} doubles the header declares",
                left - 8 * len2
            ),
        ));
    }
    let data_off = r.off;
    let val = |block: usize, i: usize| {
        let o = data_off + 8 * (block * n + i);
        let mut a = [0u8; 8];
        a.copy_from_slice(&bytes[o..o + 8]);
        (f64::from_le_bytes(a), o)
    };
    let mut xyz = vec![DVec3::ZERO; n];
    let mut uv = vec![[0.0; 2]; n];
    for fi in 0..n {
        let (fr, c) = (fi / ncols, fi % ncols);
        let i = (nrows - 1 - fr) * ncols + c;
        let (x, ox) = val(0, fi);
        let (y, oy) = val(1, fi);
        let (z, oz) = val(2, fi);
        for (v, o) in [(x, ox), (y, oy), (z, oz)] {
            if !v.is_finite() {
                return Err(IoError::byte(
                    file,
                    o,
                    format!("non-finite coordinate {v} in sample {fi}"),
                ));
            }
        }
        xyz[i] = DVec3::new(x, y, z);
        uv[i] = [val(3, fi).0, val(4, fi).0];
    }
    Ok(BntGrid {
        nrows,
        ncols,
        zmin,
        image_file: name,
        xyz,
        uv,
    })
}

/// Reads a `.bnt` file into a grid.
pub fn read_bnt_grid(path: impl AsRef<Path>) -> Result<BntGrid, IoError> {
    crate::read_parsed(path.as_ref(), parse_bnt_grid)
}

/// Reads a `.bnt` file and triangulates it (see [`bnt_grid_to_mesh`]).
pub fn read_bnt(path: impl AsRef<Path>, options: &BntOptions) -> Result<LoadedMesh, IoError> {
    crate::read_parsed(path.as_ref(), |bytes, name| {
        read_bnt_bytes(bytes, name, options)
    })
}

pub(crate) fn read_bnt_bytes(
    bytes: &[u8],
    file: &str,
    options: &BntOptions,
) -> Result<LoadedMesh, IoError> {
    let grid = parse_bnt_grid(bytes, file)?;
    grid_mesh(&grid, options, file)
}

/// Triangulates a range grid: two triangles per 2x2 cell of valid samples (split along the
/// shorter 3D diagonal; one triangle when exactly three corners are valid), triangles with an
/// edge longer than `max_edge_factor` grid spacings dropped, largest component kept (optional),
/// unreferenced samples dropped, faces oriented so that the mean normal has positive z (towards
/// the scanner). [`LoadedMesh::grid_index`] gives each vertex's sample `row * ncols + col`.
pub fn bnt_grid_to_mesh(grid: &BntGrid, options: &BntOptions) -> Result<LoadedMesh, IoError> {
    grid_mesh(grid, options, "<grid>")
}

fn grid_mesh(g: &BntGrid, o: &BntOptions, file: &str) -> Result<LoadedMesh, IoError> {
    let (nr, nc) = (g.nrows, g.ncols);
    if g.xyz.len() != nr * nc {
        return Err(IoError::invalid(
            file,
            format!("grid has {} samples for {nr} x {nc}", g.xyz.len()),
        ));
    }
    let valid: Vec<bool> = (0..nr * nc).map(|i| g.is_valid(i)).collect();
    // Grid spacing: median length of edges between 4-neighbours that are both valid.
    let mut lens = Vec::new();
    for r in 0..nr {
        for c in 0..nc {
            let i = r * nc + c;
            if !valid[i] {
                continue;
            }
            if c + 1 < nc && valid[i + 1] {
                lens.push((g.xyz[i] - g.xyz[i + 1]).length());
            }
            if r + 1 < nr && valid[i + nc] {
                lens.push((g.xyz[i] - g.xyz[i + nc]).length());
            }
        }
    }
    if lens.is_empty() {
        return Err(IoError::whole(
            file,
            "range grid has no two adjacent valid samples: empty mesh",
        ));
    }
    let mid = lens.len() / 2;
    let spacing = *lens.select_nth_unstable_by(mid, f64::total_cmp).1;
    let tau = o.max_edge_factor * spacing;
    let p = &g.xyz;
    let longest = |t: [usize; 3]| {
        (p[t[0]] - p[t[1]])
            .length()
            .max((p[t[1]] - p[t[2]]).length())
            .max((p[t[2]] - p[t[0]]).length())
    };
    let mut tris: Vec<[usize; 3]> = Vec::new();
    let mut dropped = 0usize;
    for r in 0..nr.saturating_sub(1) {
        for c in 0..nc.saturating_sub(1) {
            let a = r * nc + c;
            let b = a + 1;
            let cc = a + nc;
            let d = cc + 1;
            let cand: Vec<[usize; 3]> = match (valid[a], valid[b], valid[cc], valid[d]) {
                (true, true, true, true) => {
                    if (p[a] - p[d]).length() < (p[b] - p[cc]).length() {
                        vec![[a, cc, d], [a, d, b]]
                    } else {
                        vec![[a, cc, b], [cc, d, b]]
                    }
                }
                (true, true, true, false) => vec![[a, cc, b]],
                (false, true, true, true) => vec![[cc, d, b]],
                (true, false, true, true) => vec![[a, cc, d]],
                (true, true, false, true) => vec![[a, d, b]],
                _ => vec![],
            };
            for t in cand {
                if longest(t) <= tau {
                    tris.push(t);
                } else {
                    dropped += 1;
                }
            }
        }
    }
    if tris.is_empty() {
        return Err(IoError::whole(
            file,
            "range grid gives no triangle (all cells background or across depth jumps)",
        ));
    }
    // Components by union-find over samples.
    let mut parent: Vec<usize> = (0..nr * nc).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for t in &tris {
        for k in 1..3 {
            let (ra, rb) = (find(&mut parent, t[0]), find(&mut parent, t[k]));
            if ra != rb {
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    let mut used = vec![false; nr * nc];
    for t in &tris {
        for &v in t {
            used[v] = true;
        }
    }
    let mut size = vec![0usize; nr * nc];
    for (v, &u) in used.iter().enumerate() {
        if u {
            let root = find(&mut parent, v);
            size[root] += 1;
        }
    }
    let n_comp = size.iter().filter(|&&s| s > 0).count();
    // Largest component; ties go to the smallest root (deterministic).
    let best = (0..nr * nc)
        .max_by_key(|&v| (size[v], std::cmp::Reverse(v)))
        .unwrap_or(0);
    let mut removed_small = 0usize;
    if o.largest_component_only && n_comp > 1 {
        let before = tris.len();
        tris.retain(|t| find(&mut parent, t[0]) == best);
        removed_small = before - tris.len();
    }
    let mut new_index = vec![u32::MAX; nr * nc];
    let mut grid_index = Vec::new();
    let mut pos = Vec::new();
    let mut out = Vec::with_capacity(tris.len());
    // Vertices numbered in grid order (stable, independent of triangle order).
    let mut keep = vec![false; nr * nc];
    for t in &tris {
        for &v in t {
            keep[v] = true;
        }
    }
    for (v, &k) in keep.iter().enumerate() {
        if k {
            new_index[v] = pos.len() as u32;
            pos.push(p[v]);
            grid_index.push(v as u32);
        }
    }
    for t in &tris {
        out.push(t.map(|v| new_index[v]));
    }
    let mut mean = DVec3::ZERO;
    for t in &out {
        let [a, b, c] = t.map(|v| pos[v as usize]);
        mean += (b - a).cross(c - a);
    }
    if mean.z < 0.0 {
        for t in &mut out {
            t.swap(1, 2);
        }
    }
    let mesh = TriMesh::new(pos, out).map_err(|e| IoError::mesh(file, e))?;
    let mut lm = LoadedMesh::new(mesh);
    lm.grid_index = Some(grid_index);
    lm.warnings.push(format!(
        "range grid {nr} x {nc}: spacing {spacing:.4}, {dropped} triangle(s) longer than {tau:.4} dropped, {n_comp} component(s){}",
        if removed_small > 0 { format!(", {removed_small} triangle(s) outside the largest dropped") } else { String::new() }
    ));
    Ok(lm)
}

/// Serialises a grid into the bytes of a `.bnt` file (layout of `docs/algorithms.md` section
/// 4.1: little endian, rows stored bottom row first) after [`BntGrid::check_writable`]; the
/// reader gives the same grid back, bit for bit.
pub fn write_bnt_to_bytes(grid: &BntGrid) -> Result<Vec<u8>, IoError> {
    grid.check_writable()
        .map_err(|e| IoError::invalid("<memory>", e))?;
    Ok(grid.to_bytes())
}

/// Writes a grid as a `.bnt` file (see [`write_bnt_to_bytes`]).
pub fn write_bnt(path: impl AsRef<Path>, grid: &BntGrid) -> Result<(), IoError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    grid.check_writable()
        .map_err(|e| IoError::invalid(&name, e))?;
    std::fs::write(path, grid.to_bytes()).map_err(|e| IoError::io("write", path, e))
}

/// Parses the bytes of a `.bnt` file into a grid (`file` names it in errors).
pub fn read_bnt_grid_from_bytes(bytes: &[u8], file: &str) -> Result<BntGrid, IoError> {
    parse_bnt_grid(bytes, file)
}
