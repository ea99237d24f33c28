//! The one reference-point parser of the command line (`describe --ref-a/--ref-b/--ref`,
//! `render --ref-a/--ref-b`, `geodesic --source/--source-point`).
//!
//! A reference point is written as
//! * a vertex index (`1507`);
//! * coordinates `X,Y,Z`, snapped to the nearest surface point, and an error when that point is
//!   farther from the surface than `--snap-tolerance` times the bounding-box diagonal;
//! * a landmark name (`outer-eye-right`, `Outer right eye corner`, `nose_tip`, ...): looked up in
//!   `--landmarks FILE` when given (any landmark file `mesh-io` reads; its vertex is used when
//!   it sits at the given position, otherwise the position is snapped under the same
//!   tolerance), else detected once per mesh with `landmarks::detect_seen_from` and the default
//!   model (units recognised from the face size; a `.bnt` grid seen from `+z`).

use anyhow::{bail, Context};
use geodesic::Source;
use meshcore::{DVec3, FaceLocator, TriMesh};
use std::cell::OnceCell;
use std::path::{Path, PathBuf};

/// Command-line options of the reference-point parser (flattened into the commands).
#[derive(Debug, Clone, clap::Args)]
pub struct RefArgs {
    /// Landmark file giving the reference points named by landmark (instead of detecting
    /// them): JSON written by `bipolar landmarks`, a flat `{name: [x, y, z]}` object, the ICT
    /// `landmarks.json` layout (the face named like the mesh file), or Bosphorus `.lm3`.
    #[arg(long, value_name = "FILE")]
    pub landmarks: Option<PathBuf>,
    /// Largest distance from the surface of a reference point given as X,Y,Z or by a landmark
    /// file, as a fraction of the mesh's bounding-box diagonal; farther points are an error.
    #[arg(
        long = "snap-tolerance",
        value_name = "FRACTION",
        default_value_t = 0.01
    )]
    pub snap_tolerance: f64,
}

/// A resolved reference point: its geodesic source and its position on the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefPoint {
    /// The geodesic source (a vertex or a surface point).
    pub source: Source,
    /// Its position.
    pub position: DVec3,
}

/// Resolves reference points on one mesh (the landmark file is read once, detection runs at
/// most once).
#[derive(Debug)]
pub struct Resolver<'a> {
    mesh: &'a TriMesh,
    diagonal: f64,
    fraction: f64,
    given: Option<(PathBuf, mesh_io::Landmarks3d)>,
    locator: OnceCell<FaceLocator<'a>>,
    detected: OnceCell<landmarks::VisibleLandmarks>,
    toward_scanner: Option<DVec3>,
}

/// Three comma-separated numbers, if `s` is that (finite or not).
fn coordinates(s: &str) -> Option<DVec3> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return None;
    }
    let mut c = [0.0; 3];
    for (k, p) in parts.iter().enumerate() {
        c[k] = p.parse::<f64>().ok()?;
    }
    Some(DVec3::from_array(c))
}

impl<'a> Resolver<'a> {
    /// A resolver for `mesh` (read from `mesh_path`, whose stem names the face in an ICT
    /// landmark file).
    pub fn new(mesh: &'a TriMesh, mesh_path: &Path, args: &RefArgs) -> anyhow::Result<Self> {
        let f = args.snap_tolerance;
        if !(f.is_finite() && f >= 0.0) {
            bail!("--snap-tolerance must be a finite fraction >= 0, got {f}");
        }
        let given = match &args.landmarks {
            Some(p) => {
                let face = mesh_path.file_stem().and_then(|s| s.to_str());
                let lm = mesh_io::read_landmark_file(p, face)
                    .with_context(|| format!("reading the landmark file {}", p.display()))?;
                Some((p.clone(), lm))
            }
            None => None,
        };
        Ok(Self {
            mesh,
            diagonal: mesh.bbox().diagonal(),
            fraction: f,
            given,
            locator: OnceCell::new(),
            detected: OnceCell::new(),
            toward_scanner: crate::load::toward_scanner(mesh_path),
        })
    }

    /// The largest accepted distance of a snapped point from the surface (mesh units).
    pub fn tolerance(&self) -> f64 {
        self.fraction * self.diagonal
    }

    /// The reference point written `spec`; `what` names it in messages (`--ref-a`).
    pub fn resolve(&self, spec: &str, what: &str) -> anyhow::Result<RefPoint> {
        let s = spec.trim();
        if let Ok(v) = s.parse::<u32>() {
            let position = self
                .mesh
                .try_position(v)
                .with_context(|| format!("{what}: reference vertex {v}"))?;
            return Ok(RefPoint {
                source: Source::Vertex(v),
                position,
            });
        }
        if let Some(p) = coordinates(s) {
            if !p.is_finite() {
                bail!("{what}: reference point {s:?} is not finite");
            }
            return self.snap(p, what, &format!("{s:?}"));
        }
        if let Some((file, lm)) = &self.given {
            return self.in_file(s, what, file, lm);
        }
        if let Some(name) = landmarks::LandmarkName::parse(s) {
            let found = match self.detected.get() {
                Some(d) => d,
                None => {
                    let model = landmarks::GenericModel::default_model()
                        .context("loading the default generic face model")?;
                    let d = landmarks::detect_seen_from(self.mesh, &model, self.toward_scanner)
                        .with_context(|| format!("{what}: detecting the landmark {name}"))?;
                    self.detected.get_or_init(|| d)
                }
            };
            let lm = found
                .get(name)
                .map_err(|u| anyhow::anyhow!("{what}: the landmark {name} is not found: {u}"))?;
            eprintln!(
                "{name}: detected at vertex {} (confidence {:.2})",
                lm.vertex, lm.confidence
            );
            return Ok(RefPoint {
                source: Source::Vertex(lm.vertex),
                position: self.mesh.try_position(lm.vertex)?,
            });
        }
        bail!(
            "{what}: cannot read reference point {spec:?}: expected a vertex index, X,Y,Z or a \
             landmark name (outer-eye-right, outer-eye-left, inner-eye-right, inner-eye-left, \
             nose-tip)"
        )
    }

    /// The labelled point `s` of a landmark file: labels match when they name the same
    /// landmark in any spelling ([`landmarks::LandmarkName::parse`]) or are equal ignoring
    /// case. The file's vertex is used when it exists and sits at the given position (within
    /// 1e-5 of the bounding-box diagonal); otherwise the position is snapped.
    fn in_file(
        &self,
        s: &str,
        what: &str,
        file: &Path,
        lm: &mesh_io::Landmarks3d,
    ) -> anyhow::Result<RefPoint> {
        let want = landmarks::LandmarkName::parse(s);
        let found = lm.labels.iter().position(|l| {
            let l = l.trim();
            (want.is_some() && landmarks::LandmarkName::parse(l) == want)
                || l.eq_ignore_ascii_case(s)
        });
        let Some(i) = found else {
            bail!(
                "{what}: landmark {s:?} is not in {} (it has: {})",
                file.display(),
                lm.labels.join(", ")
            );
        };
        let p = lm.points[i];
        if let Some(v) = lm.vertex(i) {
            if (v as usize) < self.mesh.n_vertices()
                && (self.mesh.position(v) - p).length() <= 1e-5 * self.diagonal
            {
                eprintln!("{s}: vertex {v} from {}", file.display());
                return Ok(RefPoint {
                    source: Source::Vertex(v),
                    position: self.mesh.position(v),
                });
            }
        }
        let r = self.snap(p, what, &format!("{s:?} of {}", file.display()))?;
        eprintln!(
            "{s}: {:?} from {} snapped to the surface",
            p.to_array(),
            file.display()
        );
        Ok(r)
    }

    /// The surface point nearest to `p`, or an error when it is farther than the tolerance.
    fn snap(&self, p: DVec3, what: &str, shown: &str) -> anyhow::Result<RefPoint> {
        let loc = self.locator.get_or_init(|| FaceLocator::new(self.mesh));
        let (sp, d) = loc
            .nearest(p)
            .with_context(|| format!("{what}: snapping {shown} to the mesh"))?;
        let tol = self.tolerance();
        if d > tol {
            bail!(
                "{what}: {shown} is {d:.6} from the surface, farther than the tolerance {tol:.6} \
                 ({} x the bounding-box diagonal {:.6}; see --snap-tolerance)",
                self.fraction,
                self.diagonal
            );
        }
        let position = self.mesh.point_position(&sp)?;
        eprintln!(
            "{what}: {shown} snapped to face {} (bary {:.6}, {:.6}, {:.6}), {d:.3e} away",
            sp.face, sp.bary.x, sp.bary.y, sp.bary.z
        );
        Ok(RefPoint {
            source: Source::Point(sp),
            position,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(f: f64) -> RefArgs {
        RefArgs {
            landmarks: None,
            snap_tolerance: f,
        }
    }

    #[test]
    fn vertices_coordinates_and_the_tolerance() {
        let mesh = meshcore::shapes::icosphere(2);
        let r = Resolver::new(&mesh, Path::new("s.obj"), &args(0.01)).unwrap();
        assert_eq!(r.resolve("3", "a").unwrap().source, Source::Vertex(3));
        assert!(r.resolve("100000", "a").is_err());
        let near = r.resolve("0, 0, 1.001", "a").unwrap();
        assert!((near.position.length() - 1.0).abs() < 0.02);
        let e = r.resolve("1e9,0,0", "--ref-a").unwrap_err().to_string();
        assert!(
            e.contains("--ref-a") && e.contains("farther than the tolerance"),
            "{e}"
        );
        assert!(r.resolve("1,2,nan", "a").is_err());
        assert!(r.resolve("1,2", "a").is_err());
        let loose = Resolver::new(&mesh, Path::new("s.obj"), &args(0.5)).unwrap();
        assert!(loose.resolve("0,0,1.5", "a").is_ok());
        assert!(Resolver::new(&mesh, Path::new("s.obj"), &args(-1.0)).is_err());
    }
}
