//! Z-buffer rasterisation of the triangles into the grid and landmark visibility.

use crate::camera::{Camera, Kind};
use crate::{SampleStatus, Visibility};
use meshcore::DVec3;

/// The nearest surface along the ray of one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Hit {
    /// Distance along the (unit) ray from its origin.
    pub t: f64,
    /// The triangle hit.
    pub tri: u32,
    /// The point hit (scan frame, mm).
    pub point: DVec3,
    /// Cosine of the angle between the ray and the triangle's normal (absolute value).
    pub cos_incidence: f64,
}

/// Rasterises every triangle of `pos` (scan frame) into the grid of `cam` and keeps, per
/// sample, the hit nearest to the camera (ties: the first triangle).
pub(crate) fn render(pos: &[DVec3], tris: &[[u32; 3]], cam: &Camera) -> Vec<Option<Hit>> {
    let (nr, nc) = (cam.nrows, cam.ncols);
    let mut hits: Vec<Option<Hit>> = vec![None; nr * nc];
    let proj: Vec<(f64, f64)> = pos.iter().map(|p| cam.project(*p)).collect();
    for (ti, t) in tris.iter().enumerate() {
        let [a, b, c] = t.map(|v| proj[v as usize]);
        let [pa, pb, pc] = t.map(|v| pos[v as usize]);
        let n = (pb - pa).cross(pc - pa);
        let nl = n.length();
        if nl == 0.0 || !nl.is_finite() {
            continue;
        }
        let n = n / nl;
        // Signed doubled area in pixel space; edge-on triangles cover no sample centre.
        let area = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
        if area.abs() < 1e-14 {
            continue;
        }
        let c_lo = a.0.min(b.0).min(c.0).ceil().max(0.0);
        let c_hi = a.0.max(b.0).max(c.0).floor().min(nc as f64 - 1.0);
        let r_lo = a.1.min(b.1).min(c.1).ceil().max(0.0);
        let r_hi = a.1.max(b.1).max(c.1).floor().min(nr as f64 - 1.0);
        if c_lo > c_hi || r_lo > r_hi {
            continue;
        }
        for r in r_lo as usize..=r_hi as usize {
            for col in c_lo as usize..=c_hi as usize {
                let (x, y) = (col as f64, r as f64);
                // Barycentric weights of b and c (pixel space).
                let wb = ((x - a.0) * (c.1 - a.1) - (y - a.1) * (c.0 - a.0)) / area;
                let wc = ((b.0 - a.0) * (y - a.1) - (b.1 - a.1) * (x - a.0)) / area;
                let wa = 1.0 - wb - wc;
                // Inclusive edges (a sample on a shared edge is tested by both triangles; the
                // z-buffer keeps one), with a relative tolerance against rounding.
                if wa < -1e-9 || wb < -1e-9 || wc < -1e-9 {
                    continue;
                }
                let (o, d) = cam.ray(x, y);
                let (t_ray, point) = match cam.kind {
                    // Orthographic projection is affine: the pixel-space weights are the 3D
                    // ones, and the ray keeps its exact x, y.
                    Kind::Ortho { .. } => {
                        let z = pa.z + wb * (pb.z - pa.z) + wc * (pc.z - pa.z);
                        (o.z - z, DVec3::new(o.x, o.y, z))
                    }
                    Kind::Pinhole { .. } => {
                        let den = n.dot(d);
                        if den == 0.0 {
                            continue;
                        }
                        let tt = n.dot(pa - o) / den;
                        (tt, o + d * tt)
                    }
                };
                if !(t_ray.is_finite() && t_ray > 0.0) {
                    continue;
                }
                let i = r * nc + col;
                if hits[i].is_none_or(|h| t_ray < h.t) {
                    hits[i] = Some(Hit {
                        t: t_ray,
                        tri: ti as u32,
                        point,
                        cos_incidence: n.dot(d).abs(),
                    });
                }
            }
        }
    }
    hits
}

/// Nearest intersection distance of the ray `o + t d` (`t > 0`) with the triangles
/// (Moller-Trumbore), or `None`.
fn cast(o: DVec3, d: DVec3, pos: &[DVec3], tris: &[[u32; 3]]) -> Option<f64> {
    let mut best: Option<f64> = None;
    for t in tris {
        let [a, b, c] = t.map(|v| pos[v as usize]);
        let e1 = b - a;
        let e2 = c - a;
        let p = d.cross(e2);
        let det = e1.dot(p);
        let scale = e1.length() * e2.length();
        if det.abs() <= 1e-14 * scale {
            continue;
        }
        let inv = 1.0 / det;
        let s = o - a;
        let u = s.dot(p) * inv;
        if !(-1e-9..=1.0 + 1e-9).contains(&u) {
            continue;
        }
        let q = s.cross(e1);
        let v = d.dot(q) * inv;
        if v < -1e-9 || u + v > 1.0 + 1e-9 {
            continue;
        }
        let tt = e2.dot(q) * inv;
        if tt > 0.0 && best.is_none_or(|b| tt < b) {
            best = Some(tt);
        }
    }
    best
}

/// A surface nearer than this (mm) along a landmark's ray hides it; a landmark farther than
/// this from the first surface along its ray is off the surface.
const OCCLUSION_TOLERANCE_MM: f64 = 1.0;

/// Where the scan-frame point `q` is on the scan: its nearest sample and its visibility.
pub(crate) fn classify_landmark(
    q: DVec3,
    pos: &[DVec3],
    tris: &[[u32; 3]],
    cam: &Camera,
    status: &[SampleStatus],
) -> (Option<(usize, usize)>, Visibility) {
    let (col, row) = cam.project(q);
    let (ci, ri) = (col.round(), row.round());
    if !(ci >= 0.0 && ri >= 0.0 && ci < cam.ncols as f64 && ri < cam.nrows as f64) {
        return (None, Visibility::OutsideGrid);
    }
    let (ri, ci) = (ri as usize, ci as usize);
    let sample = Some((ri, ci));
    // The exact ray through q.
    let (o, d) = match cam.kind {
        Kind::Ortho { zfar, .. } => (DVec3::new(q.x, q.y, zfar), DVec3::NEG_Z),
        Kind::Pinhole { centre, .. } => (centre, (q - centre).normalize()),
    };
    let tq = (q - o).dot(d);
    match cast(o, d, pos, tris) {
        Some(th) if th < tq - OCCLUSION_TOLERANCE_MM => {
            return (
                sample,
                Visibility::Occluded {
                    in_front_mm: tq - th,
                },
            )
        }
        Some(th) if th <= tq + OCCLUSION_TOLERANCE_MM => {}
        _ => return (sample, Visibility::OffSurface),
    }
    let v = match status[ri * cam.ncols + ci] {
        SampleStatus::Valid => Visibility::Visible,
        SampleStatus::Background => Visibility::OffSurface,
        SampleStatus::Grazing => Visibility::Grazing,
        SampleStatus::Hole => Visibility::InHole,
        SampleStatus::Border => Visibility::CroppedBorder,
    };
    (sample, v)
}
