//! Length units of face meshes and their detection from the size of the face.
//!
//! Face data come in millimetres (scanners, Bosphorus), centimetres (ICT FaceKit) or metres
//! (some exporters). [`detect_units`] guesses the unit from the *face size*: the robust
//! bounding-box diagonal of the largest connected component ([`face_size`]). A face with a bit
//! of forehead and chin, or a face cropped to the usual 100 mm sphere around the nose tip,
//! measures 150-400 mm; detection accepts one decade of sizes per unit:
//!
//! | size in file units | unit        | the face then measures |
//! |--------------------|-------------|------------------------|
//! | `[80, 800)`        | millimetre  | 80-800 mm              |
//! | `[8, 80)`          | centimetre  | 80-800 mm              |
//! | `[0.08, 0.8)`      | metre       | 80-800 mm              |
//!
//! Any other size (a 3 km object in metres, a 0.01 mm speck) fits no unit and is an error
//! ([`UnitsError::NoUnitFits`]), and so does a size in `[0.8, 8)` (too big for a face in metres,
//! too small in centimetres). The windows do not overlap, so a size gives at most one unit;
//! detection assumes the surface is a face (a 5 m wall in metres reads as a 50 cm
//! face in centimetres), which is why callers let the user override it.

use crate::topology::vertex_components;
use crate::TriMesh;
use std::fmt;
use std::str::FromStr;

/// Smallest face size accepted, in mm (bounding-box diagonal; see the module docs).
pub const MIN_FACE_SIZE_MM: f64 = 80.0;
/// Largest face size accepted (exclusive), in mm.
pub const MAX_FACE_SIZE_MM: f64 = 800.0;

/// Errors of unit parsing and detection.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum UnitsError {
    /// A unit name that is not `mm`, `cm` or `m` (or their long names).
    #[error("unknown length unit {0:?} (expected mm, cm or m)")]
    Unknown(String),
    /// The measured size is not finite or not positive (no surface to measure).
    #[error("cannot detect units: the surface has no measurable size ({0})")]
    NoSize(f64),
    /// The measured size fits no unit's face-size window.
    #[error(
        "cannot detect units: the surface measures {size:.4} units across (robust bounding-box diagonal of its largest component); a face measures {min}-{max} mm, i.e. {min}-{max} in mm, {cmin}-{cmax} in cm or {mmin}-{mmax} in m: this is not a face, or give the units explicitly",
        min = MIN_FACE_SIZE_MM, max = MAX_FACE_SIZE_MM,
        cmin = MIN_FACE_SIZE_MM / 10.0, cmax = MAX_FACE_SIZE_MM / 10.0,
        mmin = MIN_FACE_SIZE_MM / 1000.0, mmax = MAX_FACE_SIZE_MM / 1000.0
    )]
    NoUnitFits {
        /// The size measured, in file units.
        size: f64,
    },
}

/// A length unit of mesh coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Units {
    /// Millimetres (scanners, Bosphorus `.bnt`).
    Millimetre,
    /// Centimetres (ICT FaceKit).
    Centimetre,
    /// Metres.
    Metre,
}

impl Units {
    /// Every unit, smallest first.
    pub const ALL: [Units; 3] = [Units::Millimetre, Units::Centimetre, Units::Metre];

    /// Millimetres in one unit: 1, 10 or 1000.
    pub fn mm_per_unit(self) -> f64 {
        match self {
            Units::Millimetre => 1.0,
            Units::Centimetre => 10.0,
            Units::Metre => 1000.0,
        }
    }

    /// The factor that converts a length in `self` into `to` (`Centimetre.factor_to(Millimetre)
    /// == 10`).
    pub fn factor_to(self, to: Units) -> f64 {
        if self == to {
            1.0
        } else if self.mm_per_unit() >= to.mm_per_unit() {
            self.mm_per_unit() / to.mm_per_unit()
        } else {
            1.0 / (to.mm_per_unit() / self.mm_per_unit())
        }
    }

    /// The short name: `mm`, `cm` or `m`.
    pub fn symbol(self) -> &'static str {
        match self {
            Units::Millimetre => "mm",
            Units::Centimetre => "cm",
            Units::Metre => "m",
        }
    }

    /// The unit whose face-size window (module docs) holds `size`, a face size in file units.
    pub fn from_face_size(size: f64) -> Result<Units, UnitsError> {
        if !size.is_finite() || size <= 0.0 {
            return Err(UnitsError::NoSize(size));
        }
        Units::ALL
            .into_iter()
            .find(|u| {
                let mm = size * u.mm_per_unit();
                (MIN_FACE_SIZE_MM..MAX_FACE_SIZE_MM).contains(&mm)
            })
            .ok_or(UnitsError::NoUnitFits { size })
    }
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.symbol())
    }
}

impl FromStr for Units {
    type Err = UnitsError;

    /// Accepts `mm`, `cm`, `m` and the long names (millimetre(s), millimeter(s), ...), any
    /// case, surrounding blanks ignored.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim().to_ascii_lowercase();
        let t = t.strip_suffix('s').unwrap_or(&t);
        match t {
            "mm" | "millimetre" | "millimeter" => Ok(Units::Millimetre),
            "cm" | "centimetre" | "centimeter" => Ok(Units::Centimetre),
            "m" | "metre" | "meter" => Ok(Units::Metre),
            _ => Err(UnitsError::Unknown(s.to_string())),
        }
    }
}

/// The result of [`detect_units`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitsDetection {
    /// The detected unit.
    pub units: Units,
    /// The face size measured ([`face_size`]), in file units.
    pub size: f64,
}

/// Fraction of the points cut at each end of every axis by [`robust_diagonal`].
pub const ROBUST_TAIL: f64 = 0.005;

/// Diagonal of the box between the 0.5 % and 99.5 % quantiles of the points on each axis (so a
/// few stray points do not count); 0 for no point. Non-finite points are ignored.
pub fn robust_diagonal(points: &[crate::DVec3]) -> f64 {
    let mut sq = 0.0;
    for axis in 0..3 {
        let mut v: Vec<f64> = points
            .iter()
            .map(|p| p[axis])
            .filter(|x| x.is_finite())
            .collect();
        if v.is_empty() {
            return 0.0;
        }
        v.sort_unstable_by(f64::total_cmp);
        let k = ((v.len() as f64) * ROBUST_TAIL).floor() as usize;
        let lo = v[k.min(v.len() - 1)];
        let hi = v[v.len() - 1 - k.min(v.len() - 1)];
        sq += (hi - lo).max(0.0).powi(2);
    }
    sq.sqrt()
}

/// The face size of a mesh: [`robust_diagonal`] of the vertices of its largest connected
/// component (most vertices; ties to the component of the smallest vertex id).
pub fn face_size(mesh: &TriMesh) -> f64 {
    let (component, n) = vertex_components(mesh);
    let mut size = vec![0usize; n];
    for &c in &component {
        size[c as usize] += 1;
    }
    let best = size
        .iter()
        .enumerate()
        .max_by_key(|(i, len)| (**len, std::cmp::Reverse(*i)))
        .map(|(i, _)| i as u32);
    let pts: Vec<crate::DVec3> = best
        .map(|b| {
            component
                .iter()
                .enumerate()
                .filter(|(_, &c)| c == b)
                .map(|(v, _)| mesh.position(v as u32))
                .collect()
        })
        .unwrap_or_default();
    robust_diagonal(&pts)
}

/// Detects the unit of a face mesh from its [`face_size`] (thresholds in the module docs).
pub fn detect_units(mesh: &TriMesh) -> Result<UnitsDetection, UnitsError> {
    let size = face_size(mesh);
    Ok(UnitsDetection {
        units: Units::from_face_size(size)?,
        size,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{shapes, DVec3};

    fn scaled(m: &TriMesh, s: f64) -> TriMesh {
        TriMesh::new(
            m.positions().iter().map(|p| *p * s).collect(),
            m.triangles().to_vec(),
        )
        .unwrap()
    }

    #[test]
    fn parse_and_display_round_trip() {
        for u in Units::ALL {
            assert_eq!(u.to_string().parse::<Units>().unwrap(), u);
        }
        assert_eq!(" Millimetres ".parse::<Units>().unwrap(), Units::Millimetre);
        assert_eq!("centimeter".parse::<Units>().unwrap(), Units::Centimetre);
        assert_eq!("M".parse::<Units>().unwrap(), Units::Metre);
        assert!(matches!(
            "inch".parse::<Units>(),
            Err(UnitsError::Unknown(_))
        ));
        assert!("".parse::<Units>().is_err());
    }

    #[test]
    fn factors_are_consistent() {
        for a in Units::ALL {
            for b in Units::ALL {
                let f = a.factor_to(b);
                assert!((f - a.mm_per_unit() / b.mm_per_unit()).abs() < 1e-12 * f);
                assert!((f * b.factor_to(a) - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn windows_touch_and_do_not_overlap() {
        assert_eq!(Units::from_face_size(80.0).unwrap(), Units::Millimetre);
        assert_eq!(Units::from_face_size(79.999).unwrap(), Units::Centimetre);
        assert_eq!(Units::from_face_size(8.0).unwrap(), Units::Centimetre);
        // 0.8 to 8: a 0.8-8 m object in metres or an 8-80 mm one in centimetres.
        assert!(Units::from_face_size(7.999).is_err());
        assert!(Units::from_face_size(0.8).is_err());
        assert_eq!(Units::from_face_size(0.7999).unwrap(), Units::Metre);
        assert_eq!(Units::from_face_size(0.08).unwrap(), Units::Metre);
        assert!(Units::from_face_size(0.0799).is_err());
        assert!(Units::from_face_size(800.0).is_err());
        assert!(Units::from_face_size(f64::NAN).is_err());
        assert!(Units::from_face_size(0.0).is_err());
    }

    #[test]
    fn a_face_sized_sphere_in_each_unit() {
        // A sphere of radius 75 mm: diagonal of its box 2 * 75 * sqrt(3) = 260 mm.
        let s = shapes::icosphere(3);
        for u in Units::ALL {
            let m = scaled(&s, 75.0 / u.mm_per_unit());
            let d = detect_units(&m).unwrap();
            assert_eq!(d.units, u);
            assert!((d.size * u.mm_per_unit() - 260.0).abs() < 5.0, "{}", d.size);
        }
    }

    #[test]
    fn a_km_object_and_a_speck_are_refused() {
        let s = shapes::icosphere(2);
        for r in [3e6 / 3f64.sqrt() / 2.0, 0.01 / 2.0] {
            let e = detect_units(&scaled(&s, r)).unwrap_err();
            assert!(matches!(e, UnitsError::NoUnitFits { .. }), "{e}");
            assert!(e.to_string().contains("not a face"), "{e}");
        }
    }

    #[test]
    fn of_two_equal_components_the_first_decides() {
        // Two single triangles of three vertices each (sizes 1 and 10 mm across), the larger
        // listed second, and an unused vertex: equal counts, so the first component's size.
        let p = |x: f64, y: f64| DVec3::new(x, y, 0.0);
        let m = TriMesh::new(
            vec![
                p(0.0, 0.0),
                p(1.0, 0.0),
                p(0.0, 1.0),
                p(50.0, 0.0),
                p(60.0, 0.0),
                p(50.0, 10.0),
            ],
            vec![[0, 1, 2], [3, 4, 5]],
        )
        .unwrap();
        let (component, n) = crate::vertex_components(&m);
        assert_eq!((component, n), (vec![0, 0, 0, 1, 1, 1], 2));
        assert!(
            (face_size(&m) - 2f64.sqrt()).abs() < 1e-12,
            "{}",
            face_size(&m)
        );
        let swapped = TriMesh::new(m.positions().to_vec(), vec![[3, 4, 5], [0, 1, 2]]).unwrap();
        assert_eq!(
            face_size(&swapped),
            face_size(&m),
            "by vertex order, not face order"
        );
    }

    #[test]
    fn stray_points_and_small_components_do_not_count() {
        // A 150 mm sphere plus a tiny far-away triangle: the largest component decides.
        let s = shapes::icosphere(3);
        let mut pos: Vec<DVec3> = s.positions().iter().map(|p| *p * 75.0).collect();
        let mut tris = s.triangles().to_vec();
        let n = pos.len() as u32;
        pos.extend([
            DVec3::new(1e5, 0.0, 0.0),
            DVec3::new(1e5 + 1.0, 0.0, 0.0),
            DVec3::new(1e5, 1.0, 0.0),
        ]);
        tris.push([n, n + 1, n + 2]);
        let m = TriMesh::new(pos, tris).unwrap();
        assert_eq!(detect_units(&m).unwrap().units, Units::Millimetre);
        assert!(robust_diagonal(&[]) == 0.0);
    }
}
