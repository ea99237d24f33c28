//! The part of a mesh a range scanner would measure from a given direction: faces turned
//! toward it within an incidence limit, none of whose vertices hides behind nearer surface.

use crate::camera::Camera;
use crate::{render, Projection, ScanError, ScanOptions};
use meshcore::{DQuat, DVec3, TriMesh};

/// Which faces of `mesh` a scanner looking from `toward_viewer` (the direction from the
/// surface to the scanner, any length; orthographic rays) would measure: a face is seen when
/// its normal is within `max_incidence_deg` of that direction (so back faces never are) and
/// none of its three vertices is hidden, that is, no other triangle lies nearer to the scanner
/// along the vertex's ray by more than twice `pitch` (depth differences within two samples are
/// taken as the surface's own relief: noise and small folds at grazing angles).
///
/// Occlusion is found with a z-buffer of sample spacing `pitch` (mesh units; about a third of
/// the mesh's edge length or finer): each vertex is tested against the triangles that are
/// nearest to the scanner at the four samples around it, so a vertex whose occluder covers
/// none of those samples (the occluder's silhouette passes within one sample of it) counts as
/// seen. This is the scanner's own rendering ([`crate::scan`]) without its grid sampling: the
/// mask of the mesh itself, not a resampled copy, so that a description of what is kept
/// shares the mesh's vertices.
///
/// Errors ([`ScanError::InvalidOption`]) name a zero or non-finite direction, a pitch that is
/// not positive and finite, or an angle outside [0, 90]; a pitch too fine for the mesh's
/// extent is [`ScanError::GridTooLarge`].
pub fn visible_faces(
    mesh: &TriMesh,
    toward_viewer: DVec3,
    pitch: f64,
    max_incidence_deg: f64,
) -> Result<Vec<bool>, ScanError> {
    let d = toward_viewer.normalize_or_zero();
    if !(d.is_finite() && d != DVec3::ZERO) {
        return Err(ScanError::InvalidOption(format!(
            "viewing direction {:?} (expected a finite, non-zero vector)",
            toward_viewer.to_array()
        )));
    }
    if !(pitch.is_finite() && pitch > 0.0) {
        return Err(ScanError::InvalidOption(format!(
            "visibility pitch {pitch} (expected a positive, finite length in mesh units)"
        )));
    }
    if !(0.0..=90.0).contains(&max_incidence_deg) {
        return Err(ScanError::InvalidOption(format!(
            "max incidence {max_incidence_deg} degrees (expected 0 to 90)"
        )));
    }
    // The scanner's frame: the viewing direction becomes +z.
    let turn = DQuat::from_rotation_arc(d, DVec3::Z);
    let pos: Vec<DVec3> = mesh.positions().iter().map(|p| turn * *p).collect();
    let tris = mesh.triangles();
    let cam = Camera::fit(
        &pos,
        &ScanOptions {
            pitch_mm: pitch,
            projection: Projection::Orthographic,
            margin: 1,
            ..ScanOptions::default()
        },
    )?;
    let hits = render::render(&pos, tris, &cam);
    let tol = 2.0 * pitch;
    let seen: Vec<bool> = pos
        .iter()
        .enumerate()
        .map(|(v, &p)| {
            let (col, row) = cam.project(p);
            let cols = [col.floor(), col.ceil()];
            let rows = [row.floor(), row.ceil()];
            !rows.iter().any(|&r| {
                cols.iter().any(|&c| {
                    if !(r >= 0.0 && c >= 0.0 && r < cam.nrows as f64 && c < cam.ncols as f64) {
                        return false;
                    }
                    let Some(h) = hits[r as usize * cam.ncols + c as usize] else {
                        return false;
                    };
                    let t = tris[h.tri as usize];
                    !t.contains(&(v as u32))
                        && depth_over(t.map(|w| pos[w as usize]), p).is_some_and(|z| z > p.z + tol)
                })
            })
        })
        .collect();
    let cos_max = max_incidence_deg.to_radians().cos();
    Ok(tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|w| pos[w as usize]);
            let n = (b - a).cross(c - a).normalize_or_zero();
            n != DVec3::ZERO && n.z >= cos_max - 1e-12 && t.iter().all(|&w| seen[w as usize])
        })
        .collect())
}

/// The height `z` of triangle `[a, b, c]` above the point `(p.x, p.y)`, when that point lies in
/// the triangle's projection on the `xy` plane.
fn depth_over([a, b, c]: [DVec3; 3], p: DVec3) -> Option<f64> {
    let det = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let wb = ((p.x - a.x) * (c.y - a.y) - (p.y - a.y) * (c.x - a.x)) / det;
    let wc = ((b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)) / det;
    let wa = 1.0 - wb - wc;
    (wa >= -1e-9 && wb >= -1e-9 && wc >= -1e-9).then_some(wa * a.z + wb * b.z + wc * c.z)
}
