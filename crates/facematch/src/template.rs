//! Templates: what a comparison needs of a gallery face, built once and kept on disk.
//!
//! The file (`.bpt`, little-endian) is `BPTEMPL\0`, the format version (u32), then the
//! template: strings as a u32 byte count and UTF-8, numbers as their IEEE-754 bits, so that a
//! template reads back bit-identically. A gallery file (`.bpg`) is `BPGALRY\0`, the version,
//! the count (u32) and each template's bytes with their length (u64).

use crate::view::{describe_view, view_directions};
use crate::{
    Description, KeyedSet, Lost, MatchError, MatchOptions, Pair, Poles, PreparedScan, ViewOptions,
};
use meshcore::{DVec3, TriMesh};
use rayon::prelude::*;
use std::path::Path;

/// The version of the template format this build reads and writes.
pub const FORMAT_VERSION: u32 = 1;

const MAGIC: &[u8; 8] = b"BPTEMPL\0";
const GALLERY_MAGIC: &[u8; 8] = b"BPGALRY\0";

/// A template's view: its descriptors as a scanner turned by `yaw_deg` would have measured
/// the face.
#[derive(Debug, Clone, PartialEq)]
pub struct TemplateView {
    /// The turn (degrees, about the face's vertical axis; the sign gives the side).
    pub yaw_deg: f64,
    /// The turned scanner direction (the template's frame, unit).
    pub toward: DVec3,
    /// Per pair the descriptor, or why the view has none.
    pub sets: Result<[Result<KeyedSet, String>; 3], String>,
}

/// A gallery face ready to be compared: its identity, where it came from, the settings it was
/// made with, its descriptions and its views.
#[derive(Debug, Clone, PartialEq)]
pub struct Template {
    /// The identity (several templates may share one).
    pub identity: String,
    /// Where it came from (a file name).
    pub source: String,
    /// [`MatchOptions::template_settings`] of the options it was made with.
    pub settings: String,
    /// Its descriptions (with the reference-point search's moved ones when it was made as a
    /// probe).
    pub description: Description,
    /// Its views (empty without view matching).
    pub views: Vec<TemplateView>,
    /// What was assumed or substituted while making it.
    pub notes: Vec<String>,
}

impl Template {
    /// The template of a prepared scan: its descriptions from the detected poles (with the
    /// reference-point search when `search`: a probe's template) and, with view matching, one
    /// view per turned direction (computed in parallel).
    pub fn of_scan(
        scan: &PreparedScan,
        identity: &str,
        source: &str,
        options: &MatchOptions,
        search: bool,
    ) -> Result<Self, MatchError> {
        let poles = scan.poles(options)?;
        // The description and the views are independent: both cores stay busy.
        let (description, views) = rayon::join(
            || crate::describe(&scan.mesh, poles, scan.scanner, options, search),
            || match &options.view {
                Some(v) => views_of(&scan.mesh, poles, scan.scanner, options, v),
                None => Vec::new(),
            },
        );
        let description = description?;
        Ok(Self {
            identity: identity.to_string(),
            source: source.to_string(),
            settings: options.template_settings(),
            description,
            views,
            notes: scan.notes.clone(),
        })
    }

    /// The template as a probe: its description and its notes, with one more when it holds no
    /// reference-point search (a gallery template compared as a probe is scored without it).
    pub fn into_probe(self) -> (Description, Vec<String>) {
        let mut notes = self.notes;
        if self.description.moved.iter().all(Vec::is_empty) {
            notes.push("the probe is a template without the reference-point search".into());
        }
        (self.description, notes)
    }

    /// Checks that the template was made with `options`' settings ([`MatchError::Settings`]).
    pub fn check_settings(&self, options: &MatchOptions, file: &str) -> Result<(), MatchError> {
        let expected = options.template_settings();
        if self.settings != expected {
            return Err(MatchError::Settings {
                file: file.to_string(),
                template: self.settings.clone(),
                expected,
            });
        }
        Ok(())
    }

    /// The template's bytes (a `.bpt` file).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Writer(Vec::new());
        w.0.extend_from_slice(MAGIC);
        w.u32(FORMAT_VERSION);
        self.write_body(&mut w);
        w.0
    }

    /// A template from the bytes of a `.bpt` file (`file` names them in errors).
    pub fn from_bytes(bytes: &[u8], file: &str) -> Result<Self, MatchError> {
        let mut r = Reader::new(bytes, file);
        r.header(MAGIC, "a template")?;
        let t = Self::read_body(&mut r)?;
        r.end()?;
        Ok(t)
    }

    /// Writes the template to `path` (a `.bpt` file).
    pub fn write(&self, path: &Path) -> Result<(), MatchError> {
        std::fs::write(path, self.to_bytes())
            .map_err(|source| meshcore::FileError::new("write", path, source).into())
    }

    /// Reads a template file.
    pub fn read(path: &Path) -> Result<Self, MatchError> {
        let bytes = read_file(path)?;
        Self::from_bytes(&bytes, &path.display().to_string())
    }

    /// The bytes of a gallery file (`.bpg`) holding `templates`.
    pub fn gallery_bytes(templates: &[Template]) -> Vec<u8> {
        let mut w = Writer(Vec::new());
        w.0.extend_from_slice(GALLERY_MAGIC);
        w.u32(FORMAT_VERSION);
        w.u32(templates.len() as u32);
        for t in templates {
            let b = t.to_bytes();
            w.u64(b.len() as u64);
            w.0.extend_from_slice(&b);
        }
        w.0
    }

    /// The templates of a gallery file's bytes, or of a single template's.
    pub fn many_from_bytes(bytes: &[u8], file: &str) -> Result<Vec<Self>, MatchError> {
        if bytes.starts_with(MAGIC) {
            return Ok(vec![Self::from_bytes(bytes, file)?]);
        }
        let mut r = Reader::new(bytes, file);
        r.header(GALLERY_MAGIC, "a gallery or template")?;
        let n = r.u32()?;
        let mut out = Vec::new();
        for i in 0..n {
            let len = r.u64()? as usize;
            let b = r.take(len)?;
            out.push(Self::from_bytes(b, &format!("{file} (template {i})"))?);
        }
        r.end()?;
        Ok(out)
    }

    fn write_body(&self, w: &mut Writer) {
        w.str(&self.identity);
        w.str(&self.source);
        w.str(&self.settings);
        w.u32(self.notes.len() as u32);
        for n in &self.notes {
            w.str(n);
        }
        let d = &self.description;
        w.u8(d.pair as u8);
        for p in d.landmarks {
            w.vec3(p);
        }
        w.vec3(d.scanner);
        match d.lost {
            None => w.u8(0),
            Some(l) => {
                w.u8(1 + u8::from(l.right));
                w.vec3(l.position);
            }
        }
        for s in &d.sets {
            w.set_result(s);
        }
        for m in &d.moved {
            w.u32(m.len() as u32);
            for s in m {
                w.set(s);
            }
        }
        for f in d.moved_failed {
            w.u64(f as u64);
        }
        w.u32(self.views.len() as u32);
        for v in &self.views {
            w.f64(v.yaw_deg);
            w.vec3(v.toward);
            match &v.sets {
                Ok(sets) => {
                    w.u8(1);
                    for s in sets {
                        w.set_result(s);
                    }
                }
                Err(e) => {
                    w.u8(0);
                    w.str(e);
                }
            }
        }
    }

    fn read_body(r: &mut Reader<'_>) -> Result<Self, MatchError> {
        let identity = r.str()?;
        let source = r.str()?;
        let settings = r.str()?;
        let notes = (0..r.u32()?).map(|_| r.str()).collect::<Result<_, _>>()?;
        let pair = Pair::from_index(usize::from(r.u8()?)).ok_or_else(|| r.bad("a pole pair"))?;
        let landmarks = [r.vec3()?, r.vec3()?, r.vec3()?];
        let scanner = r.vec3()?;
        let lost = match r.u8()? {
            0 => None,
            k @ (1 | 2) => Some(Lost {
                right: k == 2,
                position: r.vec3()?,
            }),
            _ => return Err(r.bad("a lost-corner flag")),
        };
        let sets = [r.set_result()?, r.set_result()?, r.set_result()?];
        let mut moved: [Vec<KeyedSet>; 3] = Default::default();
        for m in &mut moved {
            *m = (0..r.u32()?).map(|_| r.set()).collect::<Result<_, _>>()?;
        }
        let moved_failed = [r.u64()? as usize, r.u64()? as usize, r.u64()? as usize];
        let n_views = r.u32()?;
        let mut views = Vec::new();
        for _ in 0..n_views {
            let yaw_deg = r.f64()?;
            let toward = r.vec3()?;
            let sets = match r.u8()? {
                1 => Ok([r.set_result()?, r.set_result()?, r.set_result()?]),
                0 => Err(r.str()?),
                _ => return Err(r.bad("a view flag")),
            };
            views.push(TemplateView {
                yaw_deg,
                toward,
                sets,
            });
        }
        Ok(Self {
            identity,
            source,
            settings,
            description: Description {
                sets,
                moved,
                moved_failed,
                pair,
                landmarks,
                lost,
                scanner,
            },
            views,
            notes,
        })
    }
}

/// The bytes of a file, or an error naming it.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, MatchError> {
    std::fs::read(path).map_err(|source| meshcore::FileError::new("read", path, source).into())
}

struct Writer(Vec<u8>);

impl Writer {
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn vec3(&mut self, v: DVec3) {
        for x in v.to_array() {
            self.f64(x);
        }
    }
    fn str(&mut self, s: &str) {
        self.u32(s.len() as u32);
        self.0.extend_from_slice(s.as_bytes());
    }
    fn set(&mut self, s: &KeyedSet) {
        self.u32(s.keys.len() as u32);
        for &k in &s.keys {
            self.u64(k);
        }
        for &p in &s.points {
            self.vec3(p);
        }
    }
    fn set_result(&mut self, s: &Result<KeyedSet, String>) {
        match s {
            Ok(s) => {
                self.u8(1);
                self.set(s);
            }
            Err(e) => {
                self.u8(0);
                self.str(e);
            }
        }
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    file: &'a str,
}

impl<'a> Reader<'a> {
    fn new(bytes: &'a [u8], file: &'a str) -> Self {
        Self { bytes, at: 0, file }
    }

    fn bad(&self, what: &str) -> MatchError {
        MatchError::Template {
            file: self.file.to_string(),
            what: format!("malformed at byte {}: expected {what}", self.at),
        }
    }

    fn header(&mut self, magic: &[u8; 8], what: &str) -> Result<(), MatchError> {
        if !self.bytes.starts_with(magic) {
            return Err(MatchError::Template {
                file: self.file.to_string(),
                what: format!(
                    "not {what} file (it does not start with {:?})",
                    String::from_utf8_lossy(&magic[..7])
                ),
            });
        }
        self.at = 8;
        let v = self.u32()?;
        if v != FORMAT_VERSION {
            return Err(MatchError::Template {
                file: self.file.to_string(),
                what: format!("format version {v}; this build reads version {FORMAT_VERSION} (enrol the scans again)"),
            });
        }
        Ok(())
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], MatchError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(MatchError::Template {
                file: self.file.to_string(),
                what: format!(
                    "truncated: {n} more bytes needed at byte {} of {}",
                    self.at,
                    self.bytes.len()
                ),
            });
        };
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn end(&self) -> Result<(), MatchError> {
        if self.at != self.bytes.len() {
            return Err(MatchError::Template {
                file: self.file.to_string(),
                what: format!("{} bytes after the end", self.bytes.len() - self.at),
            });
        }
        Ok(())
    }

    fn u8(&mut self) -> Result<u8, MatchError> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> Result<u32, MatchError> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    fn u64(&mut self) -> Result<u64, MatchError> {
        let b = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }
    fn f64(&mut self) -> Result<f64, MatchError> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn vec3(&mut self) -> Result<DVec3, MatchError> {
        Ok(DVec3::new(self.f64()?, self.f64()?, self.f64()?))
    }
    fn str(&mut self) -> Result<String, MatchError> {
        let n = self.u32()? as usize;
        let b = self.take(n)?;
        String::from_utf8(b.to_vec()).map_err(|_| self.bad("UTF-8 text"))
    }
    fn set(&mut self) -> Result<KeyedSet, MatchError> {
        let n = self.u32()? as usize;
        // Each point takes 32 bytes: refuse counts the file cannot hold before allocating.
        if n.saturating_mul(32) > self.bytes.len() - self.at {
            return Err(self.bad("a point count the file can hold"));
        }
        let keys = (0..n).map(|_| self.u64()).collect::<Result<_, _>>()?;
        let points = (0..n).map(|_| self.vec3()).collect::<Result<_, _>>()?;
        Ok(KeyedSet { keys, points })
    }
    fn set_result(&mut self) -> Result<Result<KeyedSet, String>, MatchError> {
        match self.u8()? {
            1 => Ok(Ok(self.set()?)),
            0 => Ok(Err(self.str()?)),
            _ => Err(self.bad("a descriptor flag")),
        }
    }
}

/// A template's views of the face `mesh` (landmarks `poles`, own scanner `scanner`): one per
/// turn of `view.yaws_deg` to either side of the scanner ([`view_directions`]), each described
/// by [`describe_view`] (in parallel, in order).
pub fn views_of(
    mesh: &TriMesh,
    poles: Poles,
    scanner: DVec3,
    options: &MatchOptions,
    view: &ViewOptions,
) -> Vec<TemplateView> {
    let [r, q, _] = poles.positions(mesh);
    view_directions(scanner, r, q, &view.yaws_deg)
        .into_par_iter()
        .map(|(yaw_deg, toward)| TemplateView {
            yaw_deg,
            toward,
            sets: describe_view(mesh, poles, scanner, toward, options, view),
        })
        .collect()
}

/// Prepares a scan ([`crate::prepare`]) and makes its gallery template (no search).
pub fn enroll(
    input: crate::ScanInput<'_>,
    identity: &str,
    source: &str,
    options: &MatchOptions,
) -> Result<Template, MatchError> {
    let scan = crate::prepare(input, options)?;
    Template::of_scan(&scan, identity, source, options, false)
}
