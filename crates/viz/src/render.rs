//! Orthographic software rendering of a mesh with curves and points (SVG and PNG).

use crate::{colormap, VizError};
use glam::DVec3;
use meshcore::TriMesh;
use std::fmt::Write as _;

/// Largest accepted picture side in pixels.
pub const MAX_SIZE: u32 = 16384;

/// Surface colour used when the scene has no vertex colours.
const BASE_COLOR: [f64; 3] = [210.0, 205.0, 195.0];
/// Supersampling factor of the PNG rasteriser (per axis).
const SUPERSAMPLE: usize = 2;
/// Depth tolerance for curve/point visibility, relative to the scene's bounding-box diagonal.
const DEPTH_TOL_REL: f64 = 0.01;

/// An orthographic viewing direction. The picture is fitted to the scene's bounding box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Viewing direction, from the eye into the scene.
    pub dir: DVec3,
    /// Direction that appears upwards in the picture (projected on the image plane).
    pub up: DVec3,
}

impl View {
    /// A view along `dir` (eye to scene) with `up` pointing up in the picture.
    pub fn new(dir: DVec3, up: DVec3) -> Self {
        Self { dir, up }
    }

    /// Looking along −Z with +Y up: faces of the ICT model (which look towards +Z) seen from
    /// the front, +X to the right of the picture.
    pub fn front() -> Self {
        Self::new(DVec3::NEG_Z, DVec3::Y)
    }

    /// Looking along +Z with +Y up (the back of the head).
    pub fn back() -> Self {
        Self::new(DVec3::Z, DVec3::Y)
    }

    /// Eye on the +X side looking along −X, +Y up: the subject's left profile for a face
    /// looking towards +Z.
    pub fn left() -> Self {
        Self::new(DVec3::NEG_X, DVec3::Y)
    }

    /// Eye on the −X side looking along +X, +Y up: the subject's right profile.
    pub fn right() -> Self {
        Self::new(DVec3::X, DVec3::Y)
    }

    /// Eye above (+Y) looking down along −Y, with −Z up in the picture (the face, looking
    /// towards +Z, is at the bottom).
    pub fn top() -> Self {
        Self::new(DVec3::NEG_Y, DVec3::NEG_Z)
    }

    /// Parses `front`, `back`, `left`, `right`, `top` or a direction `X,Y,Z` (eye to scene; up
    /// is +Y, or −Z when the direction is nearly vertical).
    pub fn parse(s: &str) -> Result<Self, VizError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "front" => return Ok(Self::front()),
            "back" => return Ok(Self::back()),
            "left" => return Ok(Self::left()),
            "right" => return Ok(Self::right()),
            "top" => return Ok(Self::top()),
            _ => {}
        }
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let bad = || {
            VizError::InvalidView(format!(
                "`{s}`: expected front, back, left, right, top or X,Y,Z"
            ))
        };
        if parts.len() != 3 {
            return Err(bad());
        }
        let mut v = [0.0; 3];
        for (k, p) in parts.iter().enumerate() {
            v[k] = p.parse::<f64>().map_err(|_| bad())?;
        }
        let dir = DVec3::from_array(v);
        if !dir.is_finite() || dir.length() == 0.0 {
            return Err(VizError::InvalidView(format!(
                "`{s}`: the direction must be finite and non-zero"
            )));
        }
        let d = dir.normalize();
        let up = if d.y.abs() > 0.95 {
            DVec3::NEG_Z
        } else {
            DVec3::Y
        };
        Ok(Self::new(d, up))
    }

    /// Orthonormal camera basis `(right, up, forward)`. Degenerate input is repaired: a zero or
    /// non-finite direction becomes −Z, an `up` parallel to the direction is replaced by a
    /// perpendicular axis.
    pub fn basis(&self) -> (DVec3, DVec3, DVec3) {
        let f = if self.dir.is_finite() && self.dir.length() > 0.0 {
            self.dir.normalize()
        } else {
            DVec3::NEG_Z
        };
        let mut up = if self.up.is_finite() {
            self.up
        } else {
            DVec3::Y
        };
        if f.cross(up).length() <= 1e-9 * up.length().max(1e-300) {
            up = if f.cross(DVec3::Y).length() > 0.1 {
                DVec3::Y
            } else {
                DVec3::NEG_Z
            };
        }
        let r = f.cross(up).normalize();
        let u = r.cross(f);
        (r, u, f)
    }
}

/// A polyline drawn over the visible surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Polyline {
    /// Vertices. Non-finite vertices break the line.
    pub points: Vec<DVec3>,
    /// Whether the last vertex connects back to the first.
    pub closed: bool,
    /// RGB colour.
    pub color: [u8; 3],
    /// Line width in pixels.
    pub width: f64,
}

/// A point drawn as a disc with a dark outline.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// Position. Markers with a non-finite position are skipped.
    pub position: DVec3,
    /// RGB colour.
    pub color: [u8; 3],
    /// Radius in pixels.
    pub radius: f64,
}

/// What to draw: a mesh, optional per-vertex colours, polylines and points.
#[derive(Debug, Clone)]
pub struct Scene<'a> {
    /// The surface.
    pub mesh: &'a TriMesh,
    /// One colour per mesh vertex (interpolated), or `None` for a uniform light grey.
    pub vertex_colors: Option<Vec<[u8; 3]>>,
    /// Curves drawn where they are not hidden by the surface.
    pub polylines: Vec<Polyline>,
    /// Points drawn where they are not hidden by the surface.
    pub points: Vec<Marker>,
}

impl<'a> Scene<'a> {
    /// A scene with only the mesh.
    pub fn new(mesh: &'a TriMesh) -> Self {
        Self {
            mesh,
            vertex_colors: None,
            polylines: Vec::new(),
            points: Vec::new(),
        }
    }

    /// Colours the vertices by a scalar field (viridis, non-finite values grey).
    pub fn with_field(mut self, values: &[f64]) -> Self {
        self.vertex_colors = Some(colormap::field_colors(values));
        self
    }

    fn validate(&self, width: u32, height: u32) -> Result<(), VizError> {
        if width == 0 || height == 0 || width > MAX_SIZE || height > MAX_SIZE {
            return Err(VizError::InvalidSize { width, height });
        }
        if let Some(c) = &self.vertex_colors {
            if c.len() != self.mesh.n_vertices() {
                return Err(VizError::VertexColorCount {
                    expected: self.mesh.n_vertices(),
                    got: c.len(),
                });
            }
        }
        Ok(())
    }

    fn colors(&self) -> Option<&[[u8; 3]]> {
        self.vertex_colors
            .as_deref()
            .filter(|c| c.len() == self.mesh.n_vertices())
    }
}

/// Checks the picture size and the vertex colour count.
pub(crate) fn validate_scene(scene: &Scene, width: u32, height: u32) -> Result<(), VizError> {
    scene.validate(width, height)
}

/// Orthographic camera mapping world points to pixel coordinates (y down) and depth.
#[derive(Debug, Clone, Copy)]
struct Camera {
    r: DVec3,
    u: DVec3,
    f: DVec3,
    cx: f64,
    cy: f64,
    scale: f64,
    w: f64,
    h: f64,
    depth_tol: f64,
}

impl Camera {
    fn fit(scene: &Scene, view: &View, w: usize, h: usize) -> Self {
        let (r, u, f) = view.basis();
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let mut lo3 = lo;
        let mut hi3 = hi;
        let mut add = |p: DVec3| {
            if p.is_finite() {
                let q = DVec3::new(p.dot(r), p.dot(u), p.dot(f));
                lo = lo.min(q);
                hi = hi.max(q);
                lo3 = lo3.min(p);
                hi3 = hi3.max(p);
            }
        };
        for &p in scene.mesh.positions() {
            add(p);
        }
        for pl in &scene.polylines {
            for &p in &pl.points {
                add(p);
            }
        }
        for m in &scene.points {
            add(m.position);
        }
        let diag = (hi3 - lo3).length();
        let ext_x = (hi.x - lo.x).max(0.0);
        let ext_y = (hi.y - lo.y).max(0.0);
        let margin = 0.05;
        let avail_w = w as f64 * (1.0 - 2.0 * margin);
        let avail_h = h as f64 * (1.0 - 2.0 * margin);
        let mut scale = f64::INFINITY;
        if ext_x > 0.0 {
            scale = scale.min(avail_w / ext_x);
        }
        if ext_y > 0.0 {
            scale = scale.min(avail_h / ext_y);
        }
        if !scale.is_finite() {
            scale = 1.0;
        }
        Self {
            r,
            u,
            f,
            cx: 0.5 * (lo.x + hi.x),
            cy: 0.5 * (lo.y + hi.y),
            scale,
            w: w as f64,
            h: h as f64,
            depth_tol: DEPTH_TOL_REL * diag.max(f64::MIN_POSITIVE),
        }
    }

    /// (x, y) in pixels, y downwards, and depth (larger is farther).
    fn project(&self, p: DVec3) -> (f64, f64, f64) {
        let x = (p.dot(self.r) - self.cx) * self.scale + 0.5 * self.w;
        let y = 0.5 * self.h - (p.dot(self.u) - self.cy) * self.scale;
        (x, y, p.dot(self.f))
    }

    fn light(&self) -> DVec3 {
        // Towards the viewer, a little from the upper left.
        (-self.f + 0.35 * self.u - 0.25 * self.r).normalize()
    }
}

/// Colour and depth buffers.
struct Raster {
    w: usize,
    h: usize,
    color: Vec<[f64; 3]>,
    depth: Vec<f64>,
}

fn shade(n: DVec3, light: DVec3) -> f64 {
    0.3 + 0.7 * n.dot(light).max(0.0)
}

impl Raster {
    fn new(w: usize, h: usize) -> Self {
        Self {
            w,
            h,
            color: vec![[255.0; 3]; w * h],
            depth: vec![f64::INFINITY; w * h],
        }
    }

    /// Z-buffered rasterisation of the mesh; colour only when `with_color`.
    fn draw_mesh(&mut self, cam: &Camera, scene: &Scene, with_color: bool) {
        let mesh = scene.mesh;
        let proj: Vec<(f64, f64, f64)> = mesh.positions().iter().map(|&p| cam.project(p)).collect();
        let normals = if with_color {
            mesh.vertex_normals()
        } else {
            Vec::new()
        };
        let colors = scene.colors();
        let light = cam.light();
        for (fi, tri) in mesh.triangles().iter().enumerate() {
            let [a, b, c] = tri.map(|v| proj[v as usize]);
            let area = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
            if area.abs() < 1e-12 || !area.is_finite() {
                continue;
            }
            let x0 = a.0.min(b.0).min(c.0).floor().max(0.0) as usize;
            let y0 = a.1.min(b.1).min(c.1).floor().max(0.0) as usize;
            let x1 = (a.0.max(b.0).max(c.0).ceil() as i64).min(self.w as i64 - 1);
            let y1 = (a.1.max(b.1).max(c.1).ceil() as i64).min(self.h as i64 - 1);
            if x1 < 0 || y1 < 0 {
                continue;
            }
            let (x1, y1) = (x1 as usize, y1 as usize);
            let fnormal = mesh.face_normal(fi as u32);
            let back = fnormal.dot(cam.f) > 0.0;
            let inv = 1.0 / area;
            for py in y0..=y1 {
                let sy = py as f64 + 0.5;
                for px in x0..=x1 {
                    let sx = px as f64 + 0.5;
                    let w0 = ((b.0 - sx) * (c.1 - sy) - (b.1 - sy) * (c.0 - sx)) * inv;
                    let w1 = ((c.0 - sx) * (a.1 - sy) - (c.1 - sy) * (a.0 - sx)) * inv;
                    let w2 = 1.0 - w0 - w1;
                    if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                        continue;
                    }
                    let z = w0 * a.2 + w1 * b.2 + w2 * c.2;
                    let idx = py * self.w + px;
                    if z >= self.depth[idx] {
                        continue;
                    }
                    self.depth[idx] = z;
                    if !with_color {
                        continue;
                    }
                    let [ia, ib, ic] = tri.map(|v| v as usize);
                    let mut n = w0 * normals[ia] + w1 * normals[ib] + w2 * normals[ic];
                    n = n.normalize_or(fnormal);
                    if back {
                        n = -n;
                    }
                    let base = match colors {
                        Some(cs) => {
                            let mut out = [0.0; 3];
                            for (k, o) in out.iter_mut().enumerate() {
                                *o = w0 * cs[ia][k] as f64
                                    + w1 * cs[ib][k] as f64
                                    + w2 * cs[ic][k] as f64;
                            }
                            out
                        }
                        None => BASE_COLOR,
                    };
                    let mut s = shade(n, light);
                    if back {
                        s *= 0.6;
                    }
                    self.color[idx] = base.map(|v| (v * s).min(255.0));
                }
            }
        }
    }

    /// Whether a point at pixel (x, y) with depth z is in front of (or on) the surface:
    /// z ≤ max depth over the 3×3 neighbourhood + tolerance (lenient at silhouettes).
    fn visible(&self, x: f64, y: f64, z: f64, tol: f64) -> bool {
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            return false;
        }
        let px = x.floor() as i64;
        let py = y.floor() as i64;
        let mut d = f64::NEG_INFINITY;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let (qx, qy) = (px + dx, py + dy);
                let v = if qx < 0 || qy < 0 || qx >= self.w as i64 || qy >= self.h as i64 {
                    f64::INFINITY
                } else {
                    self.depth[qy as usize * self.w + qx as usize]
                };
                d = d.max(v);
            }
        }
        z <= d + tol
    }

    /// Anti-aliased disc (coverage from the distance to the rim).
    fn disc(&mut self, x: f64, y: f64, radius: f64, color: [f64; 3]) {
        let r = radius.max(0.5);
        let x0 = (x - r - 1.0).floor().max(0.0) as usize;
        let y0 = (y - r - 1.0).floor().max(0.0) as usize;
        let x1 = ((x + r + 1.0).ceil() as i64).min(self.w as i64 - 1);
        let y1 = ((y + r + 1.0).ceil() as i64).min(self.h as i64 - 1);
        if x1 < 0 || y1 < 0 {
            return;
        }
        for py in y0..=y1 as usize {
            for px in x0..=x1 as usize {
                let d = ((px as f64 + 0.5 - x).powi(2) + (py as f64 + 0.5 - y).powi(2)).sqrt();
                let cov = (r - d + 0.5).clamp(0.0, 1.0);
                if cov > 0.0 {
                    let idx = py * self.w + px;
                    let c = &mut self.color[idx];
                    for k in 0..3 {
                        c[k] = c[k] * (1.0 - cov) + color[k] * cov;
                    }
                }
            }
        }
    }
}

fn rgb(c: [u8; 3]) -> [f64; 3] {
    c.map(|v| v as f64)
}

/// Samples of a polyline in pixel space: (x, y, depth, is an input vertex); `None` marks a
/// break (non-finite vertex).
fn sample_polyline(cam: &Camera, pl: &Polyline, step: f64) -> Vec<Option<(f64, f64, f64, bool)>> {
    let mut pts: Vec<DVec3> = pl.points.clone();
    if pl.closed && pts.len() > 2 {
        pts.push(pts[0]);
    }
    let mut out = Vec::new();
    let mut prev: Option<(f64, f64, f64)> = None;
    for p in pts {
        if !p.is_finite() {
            out.push(None);
            prev = None;
            continue;
        }
        let q = cam.project(p);
        if let Some(a) = prev {
            let len = ((q.0 - a.0).powi(2) + (q.1 - a.1).powi(2)).sqrt();
            let n = ((len / step).ceil() as usize).clamp(1, 100_000);
            for k in 1..n {
                let t = k as f64 / n as f64;
                out.push(Some((
                    a.0 + t * (q.0 - a.0),
                    a.1 + t * (q.1 - a.1),
                    a.2 + t * (q.2 - a.2),
                    false,
                )));
            }
        }
        out.push(Some((q.0, q.1, q.2, true)));
        prev = Some(q);
    }
    out
}

fn draw_overlays(raster: &mut Raster, cam: &Camera, scene: &Scene, ss: f64) {
    for pl in &scene.polylines {
        let color = rgb(pl.color);
        let radius = 0.5 * pl.width.max(0.1) * ss;
        for (x, y, z, _) in sample_polyline(cam, pl, 0.5).into_iter().flatten() {
            if raster.visible(x, y, z, cam.depth_tol) {
                raster.disc(x, y, radius, color);
            }
        }
    }
    for m in &scene.points {
        if !m.position.is_finite() {
            continue;
        }
        let (x, y, z) = cam.project(m.position);
        if raster.visible(x, y, z, cam.depth_tol) {
            let r = m.radius.max(0.5) * ss;
            raster.disc(x, y, r, [30.0, 30.0, 30.0]);
            raster.disc(x, y, (r - ss).max(0.5 * ss), rgb(m.color));
        }
    }
}

/// Renders the scene into RGB8 pixels (row-major, `width × height × 3`) with the z-buffered
/// rasteriser: Lambert shading with a light near the eye, 2×2 supersampling, back faces
/// darker, polylines and points drawn where they are not behind the surface (depth tolerance
/// 1 % of the scene's bounding-box diagonal).
pub fn render_rgb(
    scene: &Scene,
    view: &View,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, VizError> {
    scene.validate(width, height)?;
    let ss = SUPERSAMPLE;
    let (w, h) = (width as usize, height as usize);
    let cam = Camera::fit(scene, view, w * ss, h * ss);
    let mut raster = Raster::new(w * ss, h * ss);
    raster.draw_mesh(&cam, scene, true);
    draw_overlays(&mut raster, &cam, scene, ss as f64);
    let mut out = Vec::with_capacity(w * h * 3);
    let norm = 1.0 / (ss * ss) as f64;
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0.0; 3];
            for sy in 0..ss {
                for sx in 0..ss {
                    let c = raster.color[(y * ss + sy) * raster.w + x * ss + sx];
                    for k in 0..3 {
                        acc[k] += c[k];
                    }
                }
            }
            for a in acc {
                out.push((a * norm).round().clamp(0.0, 255.0) as u8);
            }
        }
    }
    Ok(out)
}

/// Encodes RGB8 pixels as PNG.
pub fn encode_png(rgb: &[u8], width: u32, height: u32) -> Result<Vec<u8>, VizError> {
    let mut buf = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut buf, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc
            .write_header()
            .map_err(|e| VizError::Png(e.to_string()))?;
        writer
            .write_image_data(rgb)
            .map_err(|e| VizError::Png(e.to_string()))?;
        writer.finish().map_err(|e| VizError::Png(e.to_string()))?;
    }
    Ok(buf)
}

/// Renders the scene to PNG bytes (see [`render_rgb`]).
pub fn render_png(
    scene: &Scene,
    view: &View,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, VizError> {
    let rgb = render_rgb(scene, view, width, height)?;
    encode_png(&rgb, width, height)
}

fn hex(c: [f64; 3]) -> String {
    let b = c.map(|v| v.round().clamp(0.0, 255.0) as u8);
    format!("#{:02x}{:02x}{:02x}", b[0], b[1], b[2])
}

/// Renders the scene as SVG: front-facing triangles with flat Lambert shading sorted back to
/// front (painter's algorithm), then the visible parts of the polylines and the visible points
/// (visibility from a z-buffer at the picture's resolution, as in [`render_png`]).
///
/// Never fails: a size of 0 is raised to 1 and vertex colours of the wrong count are ignored
/// (use [`render_to_file`](crate::render_to_file) or [`render_png`] for validation).
pub fn render_svg(scene: &Scene, view: &View, width: u32, height: u32) -> String {
    let (width, height) = (width.clamp(1, MAX_SIZE), height.clamp(1, MAX_SIZE));
    let (w, h) = (width as usize, height as usize);
    let cam = Camera::fit(scene, view, w, h);
    let mut raster = Raster::new(w, h);
    raster.draw_mesh(&cam, scene, false);
    let mesh = scene.mesh;
    let colors = scene.colors();
    let light = cam.light();
    let proj: Vec<(f64, f64, f64)> = mesh.positions().iter().map(|&p| cam.project(p)).collect();
    let mut faces: Vec<(f64, usize)> = mesh
        .triangles()
        .iter()
        .enumerate()
        .filter_map(|(fi, tri)| {
            let n = mesh.face_normal(fi as u32);
            if n.dot(cam.f) >= 0.0 || n == DVec3::ZERO {
                return None; // back face or degenerate
            }
            let z = tri.iter().map(|&v| proj[v as usize].2).sum::<f64>() / 3.0;
            Some((z, fi))
        })
        .collect();
    faces.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut s = String::with_capacity(faces.len() * 90 + 1024);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}">"#
    );
    let _ = writeln!(
        s,
        r#"<rect x="0" y="0" width="{width}" height="{height}" fill="white"/>"#
    );
    let _ = writeln!(s, r#"<g stroke-width="0.6" stroke-linejoin="round">"#);
    for &(_, fi) in &faces {
        let tri = mesh.triangles()[fi];
        let base = match colors {
            Some(cs) => {
                let mut out = [0.0; 3];
                for (k, o) in out.iter_mut().enumerate() {
                    *o = tri.iter().map(|&v| cs[v as usize][k] as f64).sum::<f64>() / 3.0;
                }
                out
            }
            None => BASE_COLOR,
        };
        let sh = shade(mesh.face_normal(fi as u32), light);
        let col = hex(base.map(|v| v * sh));
        let [a, b, c] = tri.map(|v| proj[v as usize]);
        let _ = writeln!(
            s,
            r#"<polygon points="{:.2},{:.2} {:.2},{:.2} {:.2},{:.2}" fill="{col}" stroke="{col}"/>"#,
            a.0, a.1, b.0, b.1, c.0, c.1
        );
    }
    let _ = writeln!(s, "</g>");
    // Polylines: runs of visible samples; keep input vertices and run ends.
    for pl in &scene.polylines {
        let samples = sample_polyline(&cam, pl, 0.5);
        let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
        let mut cur: Vec<(f64, f64)> = Vec::new();
        let mut last_visible: Option<(f64, f64)> = None;
        for smp in samples {
            let vis = smp.filter(|&(x, y, z, _)| raster.visible(x, y, z, cam.depth_tol));
            match vis {
                Some((x, y, _, is_vertex)) => {
                    if cur.is_empty() || is_vertex {
                        cur.push((x, y));
                        last_visible = None;
                    } else {
                        last_visible = Some((x, y));
                    }
                }
                None => {
                    if let Some(p) = last_visible.take() {
                        cur.push(p);
                    }
                    if cur.len() >= 2 {
                        runs.push(std::mem::take(&mut cur));
                    }
                    cur.clear();
                }
            }
        }
        if let Some(p) = last_visible {
            cur.push(p);
        }
        if cur.len() >= 2 {
            runs.push(cur);
        }
        let col = hex(rgb(pl.color));
        for run in runs {
            let pts: Vec<String> = run.iter().map(|(x, y)| format!("{x:.2},{y:.2}")).collect();
            let _ = writeln!(
                s,
                r#"<polyline points="{}" fill="none" stroke="{col}" stroke-width="{:.2}" stroke-linecap="round" stroke-linejoin="round"/>"#,
                pts.join(" "),
                pl.width.max(0.1)
            );
        }
    }
    for m in &scene.points {
        if !m.position.is_finite() {
            continue;
        }
        let (x, y, z) = cam.project(m.position);
        if raster.visible(x, y, z, cam.depth_tol) {
            let _ = writeln!(
                s,
                r##"<circle cx="{x:.2}" cy="{y:.2}" r="{:.2}" fill="{}" stroke="#1e1e1e" stroke-width="1"/>"##,
                m.radius.max(0.5),
                hex(rgb(m.color))
            );
        }
    }
    s.push_str("</svg>\n");
    s
}
