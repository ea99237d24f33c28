//! Face matching (`facematch`): `Template`, `Gallery`, `enroll`, `verify`, as the CLI's
//! `bipolar enroll`, `identify` and `verify` do it.

use crate::convert;
use crate::errors;
use crate::mesh::PyMesh;
use facematch::{
    Comparison, Description, Gallery, MatchError, MatchOptions, Pair, Ranked, ScanInput, Template,
    ViewUse,
};
use meshcore::units::Units;
use meshcore::{DVec3, TriMesh};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// Why a scan could not be made into a template (converted to an exception with the GIL held).
enum Fail {
    Read(mesh_io::IoError),
    Match(MatchError),
}

impl From<MatchError> for Fail {
    fn from(e: MatchError) -> Self {
        Fail::Match(e)
    }
}

impl Fail {
    fn into_py(self, name: &str) -> PyErr {
        let e = match self {
            Fail::Read(e) => errors::io(e),
            Fail::Match(e) => errors::matching(e),
        };
        // The scan's name first, the class and the library's message kept.
        Python::attach(|py| {
            let msg = format!("{name}: {}", e.value(py));
            PyErr::from_type(e.get_type(py), msg)
        })
    }
}

/// A scan to prepare: a file (read when the work runs, GIL released) or an in-memory mesh.
enum Scan<'a> {
    File(PathBuf),
    Mesh {
        mesh: &'a TriMesh,
        scanner: Option<DVec3>,
    },
}

/// The direction toward the scanner of a mesh argument: `scanner` when given, else `+z` for a
/// range grid's mesh (it has a grid index), else none (facematch takes `+z` and notes it).
fn mesh_scanner(m: &PyMesh, scanner: Option<DVec3>) -> Option<DVec3> {
    scanner.or_else(|| m.loaded.grid_index.is_some().then_some(DVec3::Z))
}

fn is_bnt(p: &Path) -> bool {
    p.extension().is_some_and(|e| e.eq_ignore_ascii_case("bnt"))
}

fn is_template_file(p: &Path) -> bool {
    p.extension().is_some_and(|e| e == "bpt")
}

/// The file name of a path (its source in a template).
fn file_name(p: &Path) -> String {
    p.file_name()
        .and_then(|n| n.to_str())
        .map_or_else(|| p.display().to_string(), str::to_string)
}

impl Scan<'_> {
    /// Prepares the scan (a `.bnt` file as a range grid, other files as meshes) and makes its
    /// template (with the reference-point search when `search`).
    fn template(
        &self,
        identity: &str,
        source: &str,
        scanner: Option<DVec3>,
        units: Option<Units>,
        options: &MatchOptions,
        search: bool,
    ) -> Result<Template, Fail> {
        let make = |input: ScanInput<'_>| -> Result<Template, Fail> {
            let scan = facematch::prepare(input, options)?;
            Ok(Template::of_scan(&scan, identity, source, options, search)?)
        };
        match self {
            Scan::File(p) if is_bnt(p) => {
                let g = mesh_io::read_bnt_grid(p).map_err(Fail::Read)?;
                make(ScanInput::Grid(&g))
            }
            Scan::File(p) => {
                let m = mesh_io::read_mesh(p).map_err(Fail::Read)?;
                make(ScanInput::Mesh {
                    mesh: &m.mesh,
                    units,
                    scanner,
                })
            }
            Scan::Mesh { mesh, scanner } => make(ScanInput::Mesh {
                mesh,
                units,
                scanner: *scanner,
            }),
        }
    }
}

/// A scan argument: a `Mesh` (borrowed) or a path. A `Template` is not a scan.
fn scan_arg<'py>(obj: &Bound<'py, PyAny>) -> PyResult<(ScanHold<'py>, String)> {
    if let Ok(m) = obj.cast::<PyMesh>() {
        return Ok((ScanHold::Mesh(m.clone()), String::new()));
    }
    if let Ok(p) = obj.extract::<PathBuf>() {
        let name = file_name(&p);
        return Ok((ScanHold::File(p), name));
    }
    Err(errors::type_error(format!(
        "a scan must be a bipolar.Mesh or a path to a .bnt or mesh file, got {}",
        obj.get_type().name()?
    )))
}

/// A scan argument held while the GIL is released.
enum ScanHold<'py> {
    File(PathBuf),
    Mesh(Bound<'py, PyMesh>),
}

impl ScanHold<'_> {
    fn scan(&self, scanner: Option<DVec3>) -> Scan<'_> {
        match self {
            ScanHold::File(p) => Scan::File(p.clone()),
            ScanHold::Mesh(m) => Scan::Mesh {
                mesh: m.get().mesh(),
                scanner: mesh_scanner(m.get(), scanner),
            },
        }
    }
}

fn units_arg(units: Option<&str>) -> PyResult<Option<Units>> {
    units
        .map(|u| u.parse::<Units>().map_err(|e| errors::input(e.to_string())))
        .transpose()
}

fn scanner_arg(scanner: Option<&Bound<'_, PyAny>>) -> PyResult<Option<DVec3>> {
    scanner.map(|s| convert::point(s, "scanner")).transpose()
}

/// The options of a comparison: the defaults (the benchmark's) with the residual gate.
fn options(gate: Option<f64>) -> PyResult<MatchOptions> {
    let o = MatchOptions {
        gate_mm: gate,
        ..MatchOptions::default()
    };
    o.validate().map_err(errors::matching)?;
    Ok(o)
}

/// A face template: what a comparison needs of a face (its identity, where it came from, the
/// settings it was made with, the descriptors of its three pole pairs and of its turned views),
/// as ``bipolar enroll`` writes it (``.bpt``). Made by ``enroll`` or ``Template.from_scan``;
/// ``to_bytes`` / ``from_bytes`` and ``write`` / ``read`` give it back bit-identically.
#[pyclass(module = "bipolar._bipolar", name = "Template", frozen)]
#[derive(Debug, Clone)]
pub struct PyTemplate {
    pub t: Template,
}

#[pymethods]
impl PyTemplate {
    /// The template of one scan (a ``Mesh`` or a ``.bnt`` / mesh file): prepared (cleaned,
    /// cropped around the detected nose tip, landmarks) and described. ``probe=True`` adds the
    /// reference-point search's moved descriptors (a probe's template, as ``identify`` makes
    /// it). ``identity`` defaults to the file's stem (required for a ``Mesh``), ``source`` to
    /// the file name (or the identity). ``scanner``: the direction toward the scanner of a mesh
    /// (default ``+z``, said in ``notes``; a range grid's is ``+z``); ``units`` of a mesh
    /// (default: recognised from the face size).
    #[staticmethod]
    #[pyo3(signature = (scan, identity=None, *, probe=false, source=None, scanner=None, units=None))]
    fn from_scan(
        py: Python<'_>,
        scan: &Bound<'_, PyAny>,
        identity: Option<String>,
        probe: bool,
        source: Option<String>,
        scanner: Option<&Bound<'_, PyAny>>,
        units: Option<&str>,
    ) -> PyResult<Self> {
        let o = options(None)?;
        let (scanner, units) = (scanner_arg(scanner)?, units_arg(units)?);
        let (hold, name) = scan_arg(scan)?;
        let identity = match (identity, &hold) {
            (Some(i), _) => i,
            (None, ScanHold::File(p)) => stem(p),
            (None, ScanHold::Mesh(_)) => {
                return Err(errors::input("identity is required for a Mesh"))
            }
        };
        let source = source.unwrap_or_else(|| {
            if name.is_empty() {
                identity.clone()
            } else {
                name.clone()
            }
        });
        let s = hold.scan(scanner);
        let t = py
            .detach(|| s.template(&identity, &source, scanner, units, &o, probe))
            .map_err(|f| f.into_py(&source))?;
        Ok(Self { t })
    }

    /// The template of the bytes of a ``.bpt`` file (``name`` names them in errors).
    #[staticmethod]
    #[pyo3(signature = (data, name="<bytes>"))]
    fn from_bytes(py: Python<'_>, data: &[u8], name: &str) -> PyResult<Self> {
        let t = py
            .detach(|| Template::from_bytes(data, name))
            .map_err(errors::matching)?;
        Ok(Self { t })
    }

    /// Reads a ``.bpt`` file.
    #[staticmethod]
    fn read(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let t = py
            .detach(|| Template::read(&path))
            .map_err(errors::matching)?;
        Ok(Self { t })
    }

    /// The bytes of the template's ``.bpt`` file.
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.t.to_bytes())
    }

    /// Writes the template to a ``.bpt`` file.
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| self.t.write(&path)).map_err(errors::matching)
    }

    /// The identity (several templates may share one).
    #[getter]
    fn identity(&self) -> &str {
        &self.t.identity
    }

    /// Where the template came from (a file name).
    #[getter]
    fn source(&self) -> &str {
        &self.t.source
    }

    /// The settings it was made with, as one line (templates of other settings cannot be
    /// compared).
    #[getter]
    fn settings(&self) -> &str {
        &self.t.settings
    }

    /// What was assumed or substituted while making it.
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.t.notes.clone()
    }

    /// The face's own pole pair (``"corners"``, ``"right-nose"``, ``"left-nose"``).
    #[getter]
    fn pair(&self) -> &'static str {
        self.t.description.pair.name()
    }

    /// Whether it holds the reference-point search's moved descriptors (made as a probe).
    #[getter]
    fn searched(&self) -> bool {
        self.t.description.moved.iter().any(|m| !m.is_empty())
    }

    /// The landmarks its poles were placed at (right and left outer eye corners, nose tip),
    /// shape (3, 3), mm.
    #[getter]
    fn landmarks<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<f64>> {
        convert::points_out(py, &self.t.description.landmarks)
    }

    /// The turns (degrees) of its views (empty without view matching).
    #[getter]
    fn view_yaws(&self) -> Vec<f64> {
        self.t.views.iter().map(|v| v.yaw_deg).collect()
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyTemplate>()
            .is_ok_and(|o| o.get().t.to_bytes() == self.t.to_bytes())
    }

    fn __repr__(&self) -> String {
        format!(
            "Template(identity={:?}, source={:?}, pair={}, views={}{})",
            self.t.identity,
            self.t.source,
            self.pair(),
            self.t.views.len(),
            if self.searched() { ", searched" } else { "" }
        )
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<convert::Reduced<'py>> {
        convert::reduced(py, "_template_from_bytes", [self.to_bytes(py).into_any()])
    }
}

/// Rebuilds a pickled `Template`.
#[pyfunction]
pub fn _template_from_bytes(py: Python<'_>, data: &[u8]) -> PyResult<PyTemplate> {
    PyTemplate::from_bytes(py, data, "<pickle>")
}

/// Rebuilds a pickled `Gallery`.
#[pyfunction]
pub fn _gallery_from_bytes(py: Python<'_>, data: &[u8]) -> PyResult<PyGallery> {
    let templates = py
        .detach(|| Template::many_from_bytes(data, "<pickle>"))
        .map_err(errors::matching)?;
    Ok(PyGallery {
        g: Gallery { templates },
    })
}

fn stem(p: &Path) -> String {
    p.file_stem()
        .and_then(|n| n.to_str())
        .unwrap_or_default()
        .to_string()
}

/// Templates to identify probes against, made with this build's settings.
///
/// ``Gallery(templates)`` from a non-empty list of ``Template``; ``Gallery.open(path)`` reads a folder of
/// ``.bpt`` files (by name) or a ``.bpg`` file; ``enroll`` makes one from scans.
#[pyclass(module = "bipolar._bipolar", name = "Gallery", frozen)]
#[derive(Debug, Clone)]
pub struct PyGallery {
    pub g: Gallery,
}

/// Each template of `g` checked against the settings of `o` (`name`: where they came from).
fn check(g: &Gallery, o: &MatchOptions, name: &str) -> PyResult<()> {
    for t in &g.templates {
        t.check_settings(o, &format!("{name} {}", t.source))
            .map_err(errors::matching)?;
    }
    Ok(())
}

#[pymethods]
impl PyGallery {
    #[new]
    fn new(templates: Vec<PyRef<'_, PyTemplate>>) -> PyResult<Self> {
        let g = Gallery {
            templates: templates.iter().map(|t| t.t.clone()).collect(),
        };
        if g.templates.is_empty() {
            return Err(errors::input("a gallery needs at least one template"));
        }
        check(&g, &options(None)?, "template")?;
        Ok(Self { g })
    }

    /// The gallery at ``path``: every ``.bpt`` file of a folder (by name), or a ``.bpg`` (or
    /// single ``.bpt``) file. Templates of other settings (``TemplateSettingsError``) and a
    /// gallery without templates (``InputError``) are refused.
    #[staticmethod]
    fn open(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let o = options(None)?;
        let g = py
            .detach(|| Gallery::open(&path, &o))
            .map_err(errors::matching)?;
        Ok(Self { g })
    }

    /// Writes the gallery as one ``.bpg`` file.
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| self.g.write(&path)).map_err(errors::matching)
    }

    /// The bytes of the gallery's ``.bpg`` file.
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &Template::gallery_bytes(&self.g.templates))
    }

    /// The templates, in order.
    #[getter]
    fn templates(&self) -> Vec<PyTemplate> {
        self.g
            .templates
            .iter()
            .map(|t| PyTemplate { t: t.clone() })
            .collect()
    }

    /// The identities, sorted, each once.
    #[getter]
    fn identities(&self) -> Vec<String> {
        let mut s: Vec<String> = self
            .g
            .templates
            .iter()
            .map(|t| t.identity.clone())
            .collect();
        s.sort_unstable();
        s.dedup();
        s
    }

    /// Ranks the gallery's identities for ``probe`` by their best template's score, best
    /// (lowest) first; failed scores (NaN) last, ties by identity (as ``bipolar identify``).
    /// ``probe``: a ``Template`` (used as is), a ``.bpt`` path, or a scan (``Mesh`` or file),
    /// prepared and described with the reference-point search. Each result is a dict:
    /// ``identity``, ``template`` (its best template's source), ``score``, ``comparison``
    /// (what it used: ``probe_pair``, ``scored_by``, ``pairs`` with each pair's ``distance``,
    /// ``view`` with its ``kind`` ``"off"`` / ``"own"`` / ``"matched"`` / ``"fallback"``,
    /// ``fallbacks`` sentences) and ``notes`` (the probe's). ``top`` keeps the best ``top``;
    /// ``gate`` is the keyed distance's residual gate (mm); ``scanner`` / ``units`` of a mesh
    /// probe as in ``Template.from_scan``.
    #[pyo3(signature = (probe, *, top=None, gate=None, scanner=None, units=None))]
    fn identify<'py>(
        &self,
        py: Python<'py>,
        probe: &Bound<'py, PyAny>,
        top: Option<usize>,
        gate: Option<f64>,
        scanner: Option<&Bound<'py, PyAny>>,
        units: Option<&str>,
    ) -> PyResult<Bound<'py, PyList>> {
        let o = options(gate)?;
        let (d, notes) = probe_of(py, probe, &o, scanner_arg(scanner)?, units_arg(units)?)?;
        let mut ranking = py.detach(|| self.g.identify(&d, &o));
        if let Some(k) = top {
            ranking.truncate(k);
        }
        let out = PyList::empty(py);
        for r in &ranking {
            out.append(ranked_dict(py, r, &notes)?)?;
        }
        Ok(out)
    }

    fn __len__(&self) -> usize {
        self.g.templates.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Gallery({} templates, {} identities)",
            self.g.templates.len(),
            self.identities().len()
        )
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<convert::Reduced<'py>> {
        convert::reduced(py, "_gallery_from_bytes", [self.to_bytes(py).into_any()])
    }
}

/// A probe's description and notes: a `Template` or `.bpt` file used as is (checked against
/// the settings), or a scan prepared and described with the reference-point search.
fn probe_of(
    py: Python<'_>,
    probe: &Bound<'_, PyAny>,
    o: &MatchOptions,
    scanner: Option<DVec3>,
    units: Option<Units>,
) -> PyResult<(Description, Vec<String>)> {
    let t = template_arg(py, probe, "probe", o, scanner, units, true)?;
    Ok(t.into_probe())
}

/// A `Template` argument, a `.bpt` file read, or a scan made into a template (identity
/// `identity`, with the search when `search`). Templates are checked against the settings.
fn template_arg(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    identity: &str,
    o: &MatchOptions,
    scanner: Option<DVec3>,
    units: Option<Units>,
    search: bool,
) -> PyResult<Template> {
    if let Ok(t) = obj.cast::<PyTemplate>() {
        let t = t.get().t.clone();
        t.check_settings(o, &t.source).map_err(errors::matching)?;
        return Ok(t);
    }
    let (hold, name) = scan_arg(obj)?;
    if let ScanHold::File(p) = &hold {
        if is_template_file(p) {
            let t = py.detach(|| Template::read(p)).map_err(errors::matching)?;
            t.check_settings(o, &p.display().to_string())
                .map_err(errors::matching)?;
            return Ok(t);
        }
    }
    let source = if name.is_empty() {
        identity.to_string()
    } else {
        name
    };
    let s = hold.scan(scanner);
    py.detach(|| s.template(identity, &source, scanner, units, o, search))
        .map_err(|f| f.into_py(&source))
}

fn view_dict<'py>(py: Python<'py>, v: &ViewUse) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    match v {
        ViewUse::Off => d.set_item("kind", "off")?,
        ViewUse::Own { angle_deg } => {
            d.set_item("kind", "own")?;
            d.set_item("angle_deg", angle_deg)?;
        }
        ViewUse::Matched {
            yaw_deg,
            angle_deg,
            off_deg,
        } => {
            d.set_item("kind", "matched")?;
            d.set_item("yaw_deg", yaw_deg)?;
            d.set_item("angle_deg", angle_deg)?;
            d.set_item("off_deg", off_deg)?;
        }
        ViewUse::Fallback { reason } => {
            d.set_item("kind", "fallback")?;
            d.set_item("reason", reason)?;
        }
    }
    Ok(d)
}

fn comparison_dict<'py>(py: Python<'py>, c: &Comparison) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("probe_pair", c.probe_pair.name())?;
    d.set_item("scored_by", c.scored_by.map(Pair::name))?;
    let pairs = PyList::empty(py);
    for (p, u) in Pair::ALL.iter().zip(&c.pairs) {
        let e = PyDict::new(py);
        e.set_item("pair", p.name())?;
        e.set_item("distance", u.distance)?;
        e.set_item("moved", u.moved)?;
        e.set_item("view_fallback", u.view_fallback)?;
        e.set_item("probe_own_failed", u.probe_own_failed)?;
        e.set_item("moved_failed", u.moved_failed)?;
        pairs.append(e)?;
    }
    d.set_item("pairs", pairs)?;
    d.set_item("view", view_dict(py, &c.view)?)?;
    d.set_item("fallbacks", c.fallbacks())?;
    Ok(d)
}

fn ranked_dict<'py>(py: Python<'py>, r: &Ranked, notes: &[String]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("identity", &r.identity)?;
    d.set_item("template", &r.template)?;
    d.set_item("score", r.score)?;
    d.set_item("comparison", comparison_dict(py, &r.comparison)?)?;
    d.set_item("notes", notes.to_vec())?;
    Ok(d)
}

/// The identity of a scan: ``identities[i]``, or the first group (else the whole match) of
/// ``re.search(identity_from, file name)``, or the file's stem.
fn identities_of(
    py: Python<'_>,
    holds: &[(ScanHold<'_>, String)],
    identities: Option<Vec<String>>,
    identity_from: Option<&str>,
) -> PyResult<Vec<String>> {
    if let Some(ids) = identities {
        if identity_from.is_some() {
            return Err(errors::input("give identities or identity_from, not both"));
        }
        if ids.len() != holds.len() {
            return Err(errors::input(format!(
                "{} identities for {} scans",
                ids.len(),
                holds.len()
            )));
        }
        return Ok(ids);
    }
    let re = identity_from
        .map(|r| py.import("re")?.call_method1("compile", (r,)))
        .transpose()
        .map_err(|e| errors::input(format!("identity_from: {e}")))?;
    holds
        .iter()
        .enumerate()
        .map(|(i, (h, name))| match h {
            ScanHold::Mesh(_) => Err(errors::input(format!(
                "scan {i} is a Mesh: give identities= for in-memory meshes"
            ))),
            ScanHold::File(p) => match &re {
                None => Ok(stem(p)),
                Some(re) => {
                    let m = re.call_method1("search", (name,))?;
                    if m.is_none() {
                        return Err(errors::input(format!(
                            "identity_from {:?}: no match in {name}",
                            identity_from.unwrap_or_default()
                        )));
                    }
                    let groups: usize = re.getattr("groups")?.extract()?;
                    let g: Option<String> = m
                        .call_method1("group", (usize::from(groups > 0),))?
                        .extract()?;
                    Ok(g.unwrap_or_default())
                }
            },
        })
        .collect()
}

/// Enrols scans into a ``Gallery``: each prepared (cleaned, cropped around the detected nose
/// tip, landmarks) and made into a gallery template (no search), in parallel with the GIL
/// released, as ``bipolar enroll``. ``scans``: ``Mesh`` objects and ``.bnt`` / mesh file paths.
/// Identities: ``identities`` (one per scan; required for ``Mesh`` scans), or
/// ``identity_from``, a regular expression (Python ``re.search`` on the file name) whose first
/// group, else whole match, is the identity; default the file's stem. ``scanner``: direction
/// toward the scanner of the mesh scans (default ``+z``, said in the notes; a range grid's is
/// ``+z``); ``units`` of the mesh scans (default: recognised). A scan that fails raises its
/// exception (the first in ``scans`` order, its name first in the message); with
/// ``skip_failed=True`` it is left out with a ``RuntimeWarning`` instead (an error if none is
/// left).
#[pyfunction]
#[pyo3(signature = (scans, identities=None, *, identity_from=None, scanner=None, units=None,
                    skip_failed=false))]
pub fn enroll(
    py: Python<'_>,
    scans: &Bound<'_, PyAny>,
    identities: Option<Vec<String>>,
    identity_from: Option<&str>,
    scanner: Option<&Bound<'_, PyAny>>,
    units: Option<&str>,
    skip_failed: bool,
) -> PyResult<PyGallery> {
    let o = options(None)?;
    let (scanner, units) = (scanner_arg(scanner)?, units_arg(units)?);
    if scans.is_instance_of::<pyo3::types::PyString>() || scans.cast::<PyMesh>().is_ok() {
        return Err(errors::type_error(
            "scans must be a list of scans (Mesh objects or paths)",
        ));
    }
    let holds: Vec<(ScanHold<'_>, String)> = scans
        .try_iter()?
        .map(|s| scan_arg(&s?))
        .collect::<PyResult<_>>()?;
    let ids = identities_of(py, &holds, identities, identity_from)?;
    let sources: Vec<String> = holds
        .iter()
        .zip(&ids)
        .map(|((_, name), id)| {
            if name.is_empty() {
                id.clone()
            } else {
                name.clone()
            }
        })
        .collect();
    let work: Vec<Scan<'_>> = holds.iter().map(|(h, _)| h.scan(scanner)).collect();
    let made: Vec<Result<Template, Fail>> = py.detach(|| {
        work.par_iter()
            .zip(&ids)
            .zip(&sources)
            .map(|((s, id), src)| s.template(id, src, scanner, units, &o, false))
            .collect()
    });
    let mut templates = Vec::new();
    for (t, src) in made.into_iter().zip(&sources) {
        match t {
            Ok(t) => templates.push(t),
            Err(f) if skip_failed => {
                let e = f.into_py(src);
                let msg = format!("not enrolled: {}", e.value(py));
                PyErr::warn(
                    py,
                    &py.get_type::<pyo3::exceptions::PyRuntimeWarning>(),
                    &std::ffi::CString::new(msg).unwrap_or_default(),
                    1,
                )?;
            }
            Err(f) => return Err(f.into_py(src)),
        }
    }
    if templates.is_empty() {
        return Err(errors::input("no scan could be enrolled"));
    }
    Ok(PyGallery {
        g: Gallery { templates },
    })
}

/// Compares two faces, as ``bipolar verify``: ``a`` (the probe side: a ``Template``, a
/// ``.bpt`` path, or a scan described with the reference-point search) against ``b`` (a
/// ``Template``, a ``.bpt`` path, or a scan enrolled without search). Returns a dict:
/// ``score``, ``same`` (a finite score at or below ``threshold``), ``threshold``,
/// ``comparison`` (as in ``Gallery.identify``) and ``notes`` (both sides').
#[pyfunction]
#[pyo3(signature = (a, b, *, gate=None, scanner=None, units=None))]
pub fn verify<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    gate: Option<f64>,
    scanner: Option<&Bound<'py, PyAny>>,
    units: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let o = options(gate)?;
    let (scanner, units) = (scanner_arg(scanner)?, units_arg(units)?);
    let (probe, mut notes) = probe_of(py, a, &o, scanner, units)?;
    let other = template_arg(py, b, "b", &o, scanner, units, false)?;
    notes.extend(other.notes.iter().cloned());
    let c = py.detach(|| facematch::compare(&probe, &other, &o));
    let same = c.same_person(&o);
    let d = PyDict::new(py);
    d.set_item("score", c.score)?;
    d.set_item("same", same)?;
    d.set_item("threshold", o.verify_threshold)?;
    d.set_item("comparison", comparison_dict(py, &c)?)?;
    d.set_item("notes", notes)?;
    Ok(d)
}

/// The rankings of `Gallery.identify` over shards of one gallery (in template order), merged
/// into the ranking of the whole gallery: per identity the first best score (NaN never
/// better), then best first, NaN last, ties by identity. Used by ``bipolar.dask``.
#[pyfunction]
pub fn _merge_rankings<'py>(
    py: Python<'py>,
    shards: Vec<Vec<Bound<'py, PyDict>>>,
) -> PyResult<Bound<'py, PyList>> {
    let mut best: Vec<(String, f64, Bound<'py, PyDict>)> = Vec::new();
    for shard in shards {
        for r in shard {
            let id: String = r
                .get_item("identity")?
                .ok_or_else(|| errors::input("a ranking entry without identity"))?
                .extract()?;
            let score: f64 = r
                .get_item("score")?
                .ok_or_else(|| errors::input("a ranking entry without score"))?
                .extract()?;
            match best.iter_mut().find(|b| b.0 == id) {
                Some(b) => {
                    if !score.is_nan() && (b.1.is_nan() || score < b.1) {
                        b.1 = score;
                        b.2 = r;
                    }
                }
                None => best.push((id, score, r)),
            }
        }
    }
    best.sort_by(|a, b| {
        let key = |x: f64| (x.is_nan(), if x.is_nan() { 0.0 } else { x });
        let (ka, kb) = (key(a.1), key(b.1));
        ka.0.cmp(&kb.0)
            .then(ka.1.total_cmp(&kb.1))
            .then_with(|| a.0.cmp(&b.0))
    });
    PyList::new(py, best.into_iter().map(|b| b.2))
}

/// Registers the module's classes and functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyTemplate>()?;
    m.add_class::<PyGallery>()?;
    m.add_function(wrap_pyfunction!(enroll, m)?)?;
    m.add_function(wrap_pyfunction!(verify, m)?)?;
    m.add_function(wrap_pyfunction!(_merge_rankings, m)?)?;
    m.add_function(wrap_pyfunction!(_template_from_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(_gallery_from_bytes, m)?)?;
    Ok(())
}
