//! Viewpoint and grid layout: the head rotation, the camera models and the mapping between
//! the scan frame (mm) and continuous pixel coordinates.

use crate::{ScanError, ScanOptions};
use meshcore::{DAffine3, DMat3, DVec3, TriMesh};

/// Camera model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// Parallel rays along `-z`; sample `(row, col)` measures the surface at
    /// `x = (c0 + col) * pitch`, `y = (r0 - row) * pitch` for integers `c0`, `r0`, so a grid
    /// sample lies on the multiples of the pitch.
    Orthographic,
    /// Rays through one centre on the `+z` side, `distance_mm` in front of the point of the
    /// (rotated) mesh nearest to the scanner, above the centre of its bounding box in `x` and
    /// `y`; the focal length makes one pixel `pitch_mm` wide on the plane through that nearest
    /// point. Structured-light face scanners work at 0.5-1.5 m.
    Pinhole {
        /// Distance of the camera centre from the front-most plane of the mesh, in mm.
        distance_mm: f64,
    },
}

/// Head rotation about the centre of the mesh's bounding box (in the scan frame: `y` up, `z`
/// towards the scanner), as in Bosphorus's rotated poses.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HeadPose {
    /// Rotation about the vertical axis, degrees; positive turns the face towards `+x` (the
    /// scanner's right, the subject's left). -180 to 180.
    pub yaw_deg: f64,
    /// Rotation about the horizontal `x` axis after the yaw, degrees; positive lifts the chin
    /// (the face looks up). -90 to 90.
    pub pitch_deg: f64,
}

impl HeadPose {
    /// The rotation matrix: pitch after yaw.
    pub fn rotation(&self) -> DMat3 {
        DMat3::from_rotation_x(-self.pitch_deg.to_radians())
            * DMat3::from_rotation_y(self.yaw_deg.to_radians())
    }
}

/// The map from input coordinates to the scan frame: scale to mm, then the head rotation about
/// the centre of the scaled bounding box.
pub(crate) fn scan_from_input(mesh: &TriMesh, o: &ScanOptions) -> DAffine3 {
    let s = o.input_mm_per_unit;
    let pivot = mesh.bbox().center() * s;
    let r = o.pose.rotation();
    DAffine3::from_translation(pivot)
        * DAffine3::from_mat3(r)
        * DAffine3::from_translation(-pivot)
        * DAffine3::from_scale(DVec3::splat(s))
}

#[derive(Debug, Clone, Copy)]
pub(crate) enum Kind {
    Ortho {
        /// Column index of `x = 0` is `-c0`: `x = (c0 + col) * pitch`.
        c0: i64,
        /// `y = (r0 - row) * pitch`.
        r0: i64,
        /// Origin height of the rays (above every vertex).
        zfar: f64,
    },
    Pinhole {
        centre: DVec3,
        /// Focal length in pixels.
        f: f64,
        /// Pixel coordinate `u = u0 + col`, `v = v0 + row` (v down).
        u0: i64,
        v0: i64,
    },
}

/// A camera with its grid.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Camera {
    pub nrows: usize,
    pub ncols: usize,
    pub pitch: f64,
    pub kind: Kind,
}

/// At most this many samples in a grid (about 320 MB of f64 samples).
const MAX_SAMPLES: usize = 40_000_000;

impl Camera {
    /// The camera of the options and the grid that holds the silhouette of `pos` (scan frame)
    /// with the options' margin.
    pub fn fit(pos: &[DVec3], o: &ScanOptions) -> Result<Self, ScanError> {
        let p = o.pitch_mm;
        let (lo, hi) = pos.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), q| (lo.min(*q), hi.max(*q)),
        );
        let m = o.margin as i64;
        let size_error = |nr: f64, nc: f64| {
            ScanError::GridTooLarge(format!(
                "the mesh spans {:.1} x {:.1} mm at {} mm per input unit; at a pitch of {p} mm that is a {nr:.0} x {nc:.0} grid (at most 65535 per side and {MAX_SAMPLES} samples): is the input unit right?",
                hi.x - lo.x,
                hi.y - lo.y,
                o.input_mm_per_unit
            ))
        };
        let check = |nr: f64, nc: f64| {
            if nr > u16::MAX as f64 || nc > u16::MAX as f64 || nr * nc > MAX_SAMPLES as f64 {
                Err(size_error(nr, nc))
            } else {
                Ok(())
            }
        };
        match o.projection {
            Projection::Orthographic => {
                let cmin = (lo.x / p).floor();
                let cmax = (hi.x / p).ceil();
                let rmin = (lo.y / p).floor();
                let rmax = (hi.y / p).ceil();
                let nc = cmax - cmin + 1.0 + 2.0 * m as f64;
                let nr = rmax - rmin + 1.0 + 2.0 * m as f64;
                check(nr, nc)?;
                Ok(Camera {
                    nrows: nr as usize,
                    ncols: nc as usize,
                    pitch: p,
                    kind: Kind::Ortho {
                        c0: cmin as i64 - m,
                        r0: rmax as i64 + m,
                        zfar: hi.z + 1.0 + (hi - lo).length(),
                    },
                })
            }
            Projection::Pinhole { distance_mm } => {
                let centre =
                    DVec3::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), hi.z + distance_mm);
                let f = distance_mm / p;
                let mut umin = f64::INFINITY;
                let mut umax = f64::NEG_INFINITY;
                let mut vmin = f64::INFINITY;
                let mut vmax = f64::NEG_INFINITY;
                for q in pos {
                    let (u, v) = pinhole_uv(centre, f, *q);
                    umin = umin.min(u);
                    umax = umax.max(u);
                    vmin = vmin.min(v);
                    vmax = vmax.max(v);
                }
                let nc = umax.ceil() - umin.floor() + 1.0 + 2.0 * m as f64;
                let nr = vmax.ceil() - vmin.floor() + 1.0 + 2.0 * m as f64;
                check(nr, nc)?;
                Ok(Camera {
                    nrows: nr as usize,
                    ncols: nc as usize,
                    pitch: p,
                    kind: Kind::Pinhole {
                        centre,
                        f,
                        u0: umin.floor() as i64 - m,
                        v0: vmin.floor() as i64 - m,
                    },
                })
            }
        }
    }

    /// Continuous `(col, row)` of a scan-frame point (pixel centres at integers).
    pub fn project(&self, q: DVec3) -> (f64, f64) {
        match self.kind {
            Kind::Ortho { c0, r0, .. } => {
                (q.x / self.pitch - c0 as f64, r0 as f64 - q.y / self.pitch)
            }
            Kind::Pinhole { centre, f, u0, v0 } => {
                let (u, v) = pinhole_uv(centre, f, q);
                (u - u0 as f64, v - v0 as f64)
            }
        }
    }

    /// Origin and unit direction of the ray of a (possibly fractional) pixel.
    pub fn ray(&self, col: f64, row: f64) -> (DVec3, DVec3) {
        match self.kind {
            Kind::Ortho { c0, r0, zfar } => (
                DVec3::new(
                    (c0 as f64 + col) * self.pitch,
                    (r0 as f64 - row) * self.pitch,
                    zfar,
                ),
                DVec3::NEG_Z,
            ),
            Kind::Pinhole { centre, f, u0, v0 } => {
                let u = u0 as f64 + col;
                let v = v0 as f64 + row;
                (centre, DVec3::new(u, -v, -f).normalize())
            }
        }
    }
}

/// Pinhole pixel coordinates (u right, v down) of `q` for a camera at `centre` looking along
/// `-z` with focal length `f` pixels. Points at or behind the camera plane map far away.
fn pinhole_uv(centre: DVec3, f: f64, q: DVec3) -> (f64, f64) {
    let d = q - centre;
    let depth = (-d.z).max(1e-9);
    (f * d.x / depth, -f * d.y / depth)
}
