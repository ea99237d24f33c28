//! `describe`: the bipolar descriptor of a mesh with every option of `bipolar describe`.

use crate::convert;
use crate::descriptor::PyDescriptor;
use crate::errors;
use crate::geodesic::{PyGeodesicSolver, SolverChoice};
use crate::mesh::mesh_arg;
use bipolar::{DescriptorOptions, LevelSpec, Source};
use glam::DVec3;
use meshcore::{FaceLocator, TriMesh};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString, PyTuple};
use std::time::{Duration, Instant};

/// Labelled landmark positions given by the caller: a path (lm3 / JSON, read by
/// `mesh_io::read_landmark_file`) or a dict `{label: (x, y, z)}`.
pub(crate) fn given_landmarks(obj: &Bound<'_, PyAny>) -> PyResult<Vec<(String, DVec3)>> {
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut out = Vec::new();
        for (k, v) in d.iter() {
            let label: String = k
                .extract()
                .map_err(|_| errors::type_error("landmark labels must be str"))?;
            let p = convert::point(&v, &format!("landmarks[{label:?}]"))?;
            out.push((label, p));
        }
        return Ok(out);
    }
    let p = convert::path(obj, "landmarks")?;
    let lm = mesh_io::read_landmark_file(&p, None).map_err(errors::io)?;
    Ok(lm.labels.into_iter().zip(lm.points).collect())
}

fn snap(mesh: &TriMesh, p: DVec3, what: &str) -> PyResult<Source> {
    if !p.is_finite() {
        return Err(errors::input(format!(
            "{what}: {:?} is not finite",
            p.to_array()
        )));
    }
    let (sp, d) = FaceLocator::new(mesh).nearest(p).map_err(errors::mesh)?;
    // As the CLI's default `--snap-tolerance`: 1 % of the bounding-box diagonal.
    let tol = 0.01 * mesh.bbox().diagonal();
    if d > tol {
        return Err(errors::input(format!(
            "{what}: {:?} is {d:.6} from the surface, farther than the tolerance {tol:.6} (1 % of \
             the bounding-box diagonal); give a point on the surface",
            p.to_array()
        )));
    }
    Ok(Source::Point(sp))
}

/// Resolves reference points as `bipolar describe` does: a vertex index; an `(x, y, z)` point
/// snapped to the nearest surface point; a landmark name looked up in `given` (any spelling
/// `landmarks::LandmarkName::parse` knows, or equal ignoring case) or, without `given`,
/// detected with `landmarks::detect_seen_from` and the default model (once for all names; units
/// from the face size, seen from `toward_viewer` when given, as a range grid is from `+z`).
pub(crate) fn references(
    py: Python<'_>,
    mesh: &TriMesh,
    toward_viewer: Option<DVec3>,
    specs: &[(String, Bound<'_, PyAny>)],
    given: Option<&[(String, DVec3)]>,
    in_library: &mut Duration,
) -> PyResult<Vec<Source>> {
    let mut detected: Option<landmarks::VisibleLandmarks> = None;
    let mut out = Vec::with_capacity(specs.len());
    for (what, spec) in specs {
        if spec.is_instance_of::<PyString>() {
            let s: String = spec.extract()?;
            let s = s.trim().to_string();
            let want = landmarks::LandmarkName::parse(&s);
            if let Some(g) = given {
                let found = g.iter().find(|(l, _)| {
                    let l = l.trim();
                    (want.is_some() && landmarks::LandmarkName::parse(l) == want)
                        || l.eq_ignore_ascii_case(&s)
                });
                let Some((_, p)) = found else {
                    let labels: Vec<&str> = g.iter().map(|(l, _)| l.as_str()).collect();
                    return Err(errors::input(format!(
                        "{what}: landmark {s:?} is not among the given landmarks ({})",
                        labels.join(", ")
                    )));
                };
                let t = Instant::now();
                out.push(snap(mesh, *p, what)?);
                *in_library += t.elapsed();
                continue;
            }
            let Some(name) = want else {
                return Err(errors::input(format!(
                    "{what}: {s:?} is not a landmark name (outer-eye-right, outer-eye-left, \
                     inner-eye-right, inner-eye-left, nose-tip); give a vertex index or (x, y, z)"
                )));
            };
            if detected.is_none() {
                let t = Instant::now();
                let model = landmarks::GenericModel::default_model().map_err(errors::landmarks)?;
                let lm = py
                    .detach(|| landmarks::detect_seen_from(mesh, &model, toward_viewer))
                    .map_err(errors::landmarks)?;
                *in_library += t.elapsed();
                detected = Some(lm);
            }
            if let Some(lm) = &detected {
                let l = lm.get(name).map_err(|u| {
                    errors::landmarks(landmarks::LandmarkError::NotFound {
                        reason: format!("{what}: the landmark {name} is not found: {u}"),
                        best_score: lm.confidence,
                    })
                })?;
                out.push(Source::Vertex(l.vertex));
            }
            continue;
        }
        if let Ok(v) = spec.extract::<i64>() {
            let n = mesh.n_vertices();
            if v < 0 || v as u64 >= n as u64 {
                return Err(errors::index(format!(
                    "{what}: reference vertex {v} does not exist (the mesh has {n} vertices)"
                )));
            }
            out.push(Source::Vertex(v as u32));
            continue;
        }
        let p = convert::point(spec, what)?;
        let t = Instant::now();
        out.push(snap(mesh, p, what)?);
        *in_library += t.elapsed();
    }
    Ok(out)
}

/// The bipolar descriptor of a mesh (the options of ``bipolar describe``).
///
/// ``mesh``: a ``Mesh`` or a path. References ``ref_a``, ``ref_b`` and further ``refs``: a
/// vertex index, an ``(x, y, z)`` point (snapped to the nearest surface point) or a landmark
/// name (``"outer-eye-right"``, ...), looked up in ``landmarks`` (a ``.lm3`` / JSON path or a
/// ``{label: (x, y, z)}`` dict; positions are snapped) or, without it, detected automatically.
/// ``levels`` (default 10) or ``step``; ``max_level`` limits the region (fields cut off);
/// ``angles`` K, ``alpha``; ``rule`` ``"isoangle"`` | ``"filter"`` (``tolerance``, default
/// ``alpha / (4 K)``) | ``"all"``; ``tangent`` ``"gradient"`` | ``"strip"`` | ``"spline"``;
/// geodesic ``method`` ``"exact"`` | ``"fmm"`` | ``"heat"`` | ``"dijkstra"``, or a prepared
/// ``solver`` for this mesh (then ``method`` is ignored). ``boundary_margin`` leaves out the band
/// within that geodesic distance (mesh units) of the mesh boundary: holes, eye openings, a
/// scan's border. ``max_incidence`` (degrees) leaves out what a range scanner looking along -z
/// saw at a larger incidence (a scan in its own frame, as ``read_bnt`` and ``scan`` give it).
/// ``search_radius`` (mesh units) turns on the reference-point search: the result is then a
/// list, the references' own descriptor first, then one per pair of the two references moved
/// by that distance in ``search_directions`` directions of their tangent planes (each
/// reference at its vertex or the nearest corner of its face; the first direction toward the
/// other reference; up to 48 more), all with the same options; compare a probe by the least
/// distance over its list (``bipolar::describe_searched``). The GIL is released while it runs.
#[pyfunction]
#[pyo3(signature = (mesh, ref_a, ref_b, *, refs=None, levels=None, step=None, max_level=None,
                    angles=8, alpha=0.95, rule="isoangle", tolerance=None, tangent="gradient",
                    method="exact", landmarks=None, solver=None, boundary_margin=None,
                    max_incidence=None, search_radius=None, search_directions=6))]
#[allow(clippy::too_many_arguments)]
pub fn describe<'py>(
    py: Python<'py>,
    mesh: &Bound<'_, PyAny>,
    ref_a: &Bound<'_, PyAny>,
    ref_b: &Bound<'_, PyAny>,
    refs: Option<&Bound<'_, PyAny>>,
    levels: Option<u32>,
    step: Option<f64>,
    max_level: Option<u32>,
    angles: u32,
    alpha: f64,
    rule: &str,
    tolerance: Option<f64>,
    tangent: &str,
    method: &str,
    landmarks: Option<&Bound<'_, PyAny>>,
    solver: Option<&Bound<'_, PyGeodesicSolver>>,
    boundary_margin: Option<f64>,
    max_incidence: Option<f64>,
    search_radius: Option<f64>,
    search_directions: usize,
) -> PyResult<Bound<'py, PyAny>> {
    // The options of `bipolar describe` (same defaults and rules).
    let levels = match (levels, step) {
        (Some(_), Some(_)) => return Err(errors::input("give levels or step, not both")),
        (_, Some(s)) => LevelSpec::Step(s),
        (Some(n), None) => LevelSpec::Count(n),
        (None, None) => LevelSpec::Count(10),
    };
    let rule = rule
        .parse::<bipolar::SelectionKind>()
        .map_err(errors::descriptor)?
        .rule(tolerance.unwrap_or(alpha / (4.0 * angles.max(1) as f64)));
    let opts = DescriptorOptions {
        levels,
        max_level,
        angles,
        alpha,
        rule,
        tangent: tangent.parse().map_err(errors::descriptor)?,
        boundary_margin,
        ..DescriptorOptions::default()
    };
    let m = mesh_arg(mesh)?;
    let mesh = m.mesh();
    let opts = match max_incidence {
        Some(deg) => DescriptorOptions {
            vertex_mask: Some(
                scanprep::incidence_mask(mesh, DVec3::Z, deg).map_err(errors::scanprep)?,
            ),
            ..opts
        },
        None => opts,
    };
    let given = landmarks.map(given_landmarks).transpose()?;
    let mut specs = vec![
        ("ref_a".to_string(), ref_a.clone()),
        ("ref_b".to_string(), ref_b.clone()),
    ];
    if let Some(r) = refs {
        let items = r
            .try_iter()
            .map_err(|_| errors::type_error("refs must be a sequence of reference points"))?;
        for (k, item) in items.enumerate() {
            specs.push((format!("refs[{k}]"), item?));
        }
    }
    let mut in_library = Duration::ZERO;
    let sources = references(
        py,
        mesh,
        m.toward_scanner(),
        &specs,
        given.as_deref(),
        &mut in_library,
    )?;
    let choice = SolverChoice::of(method, solver)?;
    let (d, t) = py.detach(|| {
        let t = Instant::now();
        let d = choice.run(mesh, |solver| {
            let surface = bipolar::Surface::new(mesh.clone());
            match search_radius {
                Some(r) => bipolar::describe_searched(
                    &surface,
                    solver,
                    &sources,
                    r,
                    search_directions,
                    &opts,
                ),
                None => {
                    let fields = bipolar::Fields::Solve {
                        solver,
                        references: &sources,
                    };
                    bipolar::describe(&surface, fields, &opts).map(|d| vec![d])
                }
            }
        });
        (d, t.elapsed())
    });
    in_library += t;
    LIBRARY_SECONDS.set(in_library.as_secs_f64());
    let mut all = d
        .map_err(errors::descriptor)?
        .into_iter()
        .map(|d| PyDescriptor { d });
    match search_radius {
        Some(_) => Ok(pyo3::types::PyList::new(py, all)?.into_any()),
        None => {
            let own = all.next();
            let own = own.ok_or_else(|| errors::input("the descriptor could not be built"))?;
            Ok(Bound::new(py, own)?.into_any())
        }
    }
}

thread_local! {
    /// Seconds the last `describe` on this thread spent inside library calls.
    static LIBRARY_SECONDS: std::cell::Cell<f64> = const { std::cell::Cell::new(0.0) };
}

/// ``describe`` (same arguments) returning ``(descriptor, seconds spent inside the library
/// calls)``: the time the Rust crates took (references, solver preparation, descriptor), for
/// measuring the binding's own overhead (python/benchmarks).
#[pyfunction]
#[pyo3(signature = (*args, **kwargs))]
pub fn _describe_profiled<'py>(
    py: Python<'py>,
    args: &Bound<'py, PyTuple>,
    kwargs: Option<&Bound<'py, PyDict>>,
) -> PyResult<(Bound<'py, PyAny>, f64)> {
    let d = wrap_pyfunction!(describe, py)?.call(args, kwargs)?;
    Ok((d, LIBRARY_SECONDS.get()))
}
