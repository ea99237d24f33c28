//! Construction of the descriptor (specification §2).

use crate::{
    BipolarError, Descriptor, DescriptorOptions, DescriptorPoint, DescriptorStats, Key, LevelSpec,
    SelectionRule,
};
use geodesic::{GeodesicSolver, SolveOptions, Source};
use glam::DVec3;
use levelcurves::face_gradient;
use meshcore::{Surface, Topology, TriMesh};

mod grid;
mod isoangle;
mod spline;
mod strip;

use spline::SplineSet;
use strip::Strip;

/// Where the distance fields of [`describe`] come from: one field per reference point (two to
/// 256; every pair `a < b` contributes points whose keys carry the pair).
#[derive(Debug, Clone, Copy)]
pub enum Fields<'a> {
    /// Solved by [`describe`] with `solver` (prepared for the surface's mesh). With a region
    /// limit (`max_level`) each field is cut off just past the region, which leaves every value
    /// the descriptor reads unchanged.
    Solve {
        /// The solver.
        solver: &'a dyn GeodesicSolver,
        /// The reference points.
        references: &'a [Source],
    },
    /// Precomputed fields (one per reference point, one value per vertex, `+inf` where
    /// unreachable). With the reference points, `d(r, q)` and the reference positions come from
    /// them, and they are checked for coincidence and components; without them, `d(r, q)` is
    /// estimated as `min_v (U_0(v) + U_1(v))` and each reference position as the vertex where
    /// its field is smallest.
    Precomputed {
        /// The fields.
        fields: &'a [Vec<f64>],
        /// The reference points, when known.
        references: Option<&'a [Source]>,
    },
}

/// Builds the descriptor of `surface` from the distance fields of `fields` (the one entry
/// point: a mesh and its topology come together in [`Surface`], so they cannot disagree).
///
/// The step is `d(r_0, r_1) / N` for [`LevelSpec::Count`]. Errors: see [`BipolarError`]
/// (fields or solver of the wrong size, different components, coincident references, no
/// points, ...).
pub fn describe(
    surface: &Surface,
    fields: Fields<'_>,
    opts: &DescriptorOptions,
) -> Result<Descriptor, BipolarError> {
    let (mesh, topo) = (surface.mesh(), surface.topology());
    match fields {
        Fields::Solve { solver, references } => {
            solve_and_describe(mesh, topo, solver, references, opts)
        }
        Fields::Precomputed { fields, references } => {
            describe_fields(mesh, topo, fields, references, opts)
        }
    }
}

/// The distance fields [`describe`] solves for [`Fields::Solve`]: one per reference point, in
/// parallel, each cut off just past the region when `opts.max_level` limits it (every value the
/// descriptor reads is the uncut one). `describe` with [`Fields::Precomputed`] of these fields
/// and the same references gives the same descriptor as with [`Fields::Solve`]; the split lets
/// callers time or reuse the fields.
pub fn solve_fields(
    surface: &Surface,
    solver: &dyn GeodesicSolver,
    references: &[Source],
    opts: &DescriptorOptions,
) -> Result<Vec<Vec<f64>>, BipolarError> {
    fields_for(surface.mesh(), surface.topology(), solver, references, opts)
}

/// [`solve_fields`] on a mesh and its topology.
fn fields_for(
    mesh: &TriMesh,
    topo: &Topology,
    solver: &dyn GeodesicSolver,
    refs: &[Source],
    opts: &DescriptorOptions,
) -> Result<Vec<Vec<f64>>, BipolarError> {
    check_reference_count(refs.len())?;
    if solver.n_vertices() != mesh.n_vertices() {
        return Err(BipolarError::InvalidOption(format!(
            "the solver was prepared for {} vertices but the mesh has {}",
            solver.n_vertices(),
            mesh.n_vertices()
        )));
    }
    check_references(mesh, topo, refs)?;
    match opts.max_level {
        Some(m) if m > 0 => region_fields(mesh, topo, solver, refs, opts.levels, m),
        _ => solve_all(solver, refs, &vec![None; refs.len()]),
    }
}

/// [`Fields::Solve`]: one field per reference with `solver` ([`fields_for`]), then
/// [`describe_fields`].
fn solve_and_describe(
    mesh: &TriMesh,
    topo: &Topology,
    solver: &dyn GeodesicSolver,
    refs: &[Source],
    opts: &DescriptorOptions,
) -> Result<Descriptor, BipolarError> {
    let fields = fields_for(mesh, topo, solver, refs, opts)?;
    describe_fields(mesh, topo, &fields, Some(refs), opts)
}

/// One field per reference, solved in parallel (rayon; each field is independent, so the result
/// does not depend on the thread count), with an optional cut-off each.
fn solve_all(
    solver: &dyn GeodesicSolver,
    refs: &[Source],
    cuts: &[Option<f64>],
) -> Result<Vec<Vec<f64>>, BipolarError> {
    use rayon::prelude::*;
    refs.par_iter()
        .zip(cuts)
        .map(|(r, &c)| {
            solver
                .distances(&[*r], &SolveOptions { max_distance: c })
                .map_err(BipolarError::from)
        })
        .collect()
}

/// Distance fields cut off just past the region `levels 1..=max_level`, so that the solver
/// stops early (the exact solver's cost grows with the area it covers).
///
/// Every value the descriptor reads is the uncut one: a vertex `v` next to a vertex `u` with
/// `U(u) <= L` has `U(v) <= L + |uv|`, so a cut-off at `L + longest edge` keeps exact values on
/// every edge and face a level `<= L` crosses. The cut also covers the distances between the
/// reference points (needed for the step and the checks); when a cut turns out too short
/// (the geodesic step was unknown before the first field), the field is solved again with a
/// larger one, and a field that already covers its whole component is never solved again.
fn region_fields(
    mesh: &TriMesh,
    topo: &Topology,
    solver: &dyn GeodesicSolver,
    refs: &[Source],
    levels: LevelSpec,
    max_level: u32,
) -> Result<Vec<Vec<f64>>, BipolarError> {
    let margin = topo
        .edges()
        .iter()
        .map(|e| (mesh.position(e.v[0]) - mesh.position(e.v[1])).length())
        .fold(0.0f64, f64::max)
        * (1.0 + 1e-9);
    let pos = refs
        .iter()
        .map(|r| source_position(mesh, r))
        .collect::<Result<Vec<_>, _>>()?;
    let mut comp_size = vec![0usize; topo.n_components()];
    for &c in topo.vertex_component() {
        comp_size[c as usize] += 1;
    }
    // Region radius L = max_level * step; for `Count` the step needs d(r0, r1), first guessed
    // from the straight-line distance (a lower bound) and corrected after the first field.
    let region = |d01: f64| match levels {
        LevelSpec::Count(c) => max_level as f64 * d01 / c.max(1) as f64,
        LevelSpec::Step(s) => max_level as f64 * s,
    };
    // First pass, every field at once (in parallel) with a cut from the straight-line guesses
    // (geodesic >= straight line; 1.25 covers the faces' ratio of about 1.2).
    let guess = 1.25 * (pos[0] - pos[1]).length();
    let farthest = |a: usize| {
        (0..refs.len())
            .map(|b| (pos[a] - pos[b]).length())
            .fold(0.0f64, f64::max)
    };
    let mut cuts: Vec<f64> = (0..refs.len())
        .map(|a| region(guess).max(1.25 * farthest(a)) + margin)
        .collect();
    let mut fields = solve_all(
        solver,
        refs,
        &cuts.iter().map(|&c| Some(c)).collect::<Vec<_>>(),
    )?;
    // Then check each field and solve again, larger, where the cut was too short.
    let mut d01 = None;
    for a in 0..refs.len() {
        loop {
            let f = &fields[a];
            let comp = topo.vertex_component()[source_vertex(mesh, &refs[a]) as usize] as usize;
            let whole = f.iter().filter(|x| x.is_finite()).count() >= comp_size[comp];
            let mut needed = 0.0f64;
            let mut missing = false;
            for b in refs {
                let d = field_at(mesh, f, b)?;
                if d.is_finite() {
                    needed = needed.max(d);
                } else {
                    missing = true;
                }
            }
            if a == 0 && !missing {
                d01 = Some(field_at(mesh, f, &refs[1])?);
            }
            let want = region(d01.unwrap_or(guess)).max(needed) + margin;
            if whole || (!missing && want <= cuts[a]) {
                break;
            }
            cuts[a] = if missing { cuts[a] * 2.0 } else { want * 1.05 };
            fields[a] = solver.distances(
                &[refs[a]],
                &SolveOptions {
                    max_distance: Some(cuts[a]),
                },
            )?;
        }
    }
    Ok(fields)
}

/// [`Fields::Precomputed`] (and the second half of [`Fields::Solve`]).
fn describe_fields(
    mesh: &TriMesh,
    topo: &Topology,
    fields: &[Vec<f64>],
    refs: Option<&[Source]>,
    opts: &DescriptorOptions,
) -> Result<Descriptor, BipolarError> {
    let n = mesh.n_vertices();
    check_reference_count(fields.len())?;
    for (fi, f) in fields.iter().enumerate() {
        check_field(fi, f, n)?;
    }
    check_options(opts, n)?;
    let diag = mesh.bbox().diagonal();

    // Reference positions and pairwise distances.
    let (references, d01) = match refs {
        Some(refs) => {
            if refs.len() != fields.len() {
                return Err(BipolarError::InvalidOption(format!(
                    "{} reference points for {} fields",
                    refs.len(),
                    fields.len()
                )));
            }
            check_references(mesh, topo, refs)?;
            let pos = refs
                .iter()
                .map(|r| source_position(mesh, r))
                .collect::<Result<Vec<_>, _>>()?;
            for a in 0..refs.len() {
                for b in a + 1..refs.len() {
                    let d = field_at(mesh, &fields[a], &refs[b])?;
                    if !d.is_finite() {
                        return Err(BipolarError::DifferentComponents { a, b });
                    }
                    if d <= 1e-12 * diag {
                        return Err(BipolarError::CoincidentReferences { a, b, distance: d });
                    }
                }
            }
            let d01 = field_at(mesh, &fields[0], &refs[1])?;
            (pos, d01)
        }
        None => {
            let pos: Vec<DVec3> = fields
                .iter()
                .map(|f| {
                    let v = (0..n)
                        .filter(|&v| f[v].is_finite())
                        .min_by(|&x, &y| f[x].total_cmp(&f[y]))
                        .unwrap_or(0);
                    mesh.position(v as u32)
                })
                .collect();
            for a in 0..fields.len() {
                for b in a + 1..fields.len() {
                    let d = (0..n)
                        .map(|v| fields[a][v] + fields[b][v])
                        .fold(f64::INFINITY, f64::min);
                    if !d.is_finite() {
                        return Err(BipolarError::DifferentComponents { a, b });
                    }
                    if d <= 1e-12 * diag {
                        return Err(BipolarError::CoincidentReferences { a, b, distance: d });
                    }
                }
            }
            let d01 = (0..n)
                .map(|v| fields[0][v] + fields[1][v])
                .fold(f64::INFINITY, f64::min);
            (pos, d01)
        }
    };
    let step = match opts.levels {
        LevelSpec::Count(c) => d01 / c as f64,
        LevelSpec::Step(s) => s,
    };
    if !(step.is_finite() && step > 0.0) {
        return Err(BipolarError::InvalidOption(format!(
            "geodesic step {step} (must be positive and finite)"
        )));
    }
    let max_level = match opts.max_level {
        Some(m) => m,
        None => {
            let top = fields
                .iter()
                .flat_map(|f| f.iter())
                .filter(|x| x.is_finite())
                .fold(0.0f64, |a, &b| a.max(b));
            (top / step).floor().min(u32::MAX as f64) as u32
        }
    };
    if max_level > Key::MAX_LEVEL {
        return Err(BipolarError::InvalidOption(format!(
            "{max_level} levels exceed the key capacity ({})",
            Key::MAX_LEVEL
        )));
    }
    if max_level == 0 {
        return Err(BipolarError::NoIntersections(format!(
            "no level fits in the fields (step {step:e}, max level 0)"
        )));
    }

    // Working fields: masked-out vertices (the vertex mask, the boundary band) become
    // unreachable (+inf, faces skipped).
    let band = opts
        .boundary_margin
        .map(|m| band(mesh, topo, m, None))
        .transpose()?;
    let keep = |v: usize| {
        opts.vertex_mask.as_ref().is_none_or(|m| m[v]) && band.as_ref().is_none_or(|b| !b[v])
    };
    let work: Vec<std::borrow::Cow<'_, [f64]>> = fields
        .iter()
        .map(|f| {
            if opts.vertex_mask.is_none() && band.is_none() {
                std::borrow::Cow::Borrowed(f.as_slice())
            } else {
                std::borrow::Cow::Owned(
                    f.iter()
                        .enumerate()
                        .map(|(v, &x)| if keep(v) { x } else { f64::INFINITY })
                        .collect(),
                )
            }
        })
        .collect();

    let ctx = Ctx::new(mesh, topo, opts, step, max_level);
    let grads: Vec<Vec<DVec3>> = work.iter().map(|f| ctx.face_gradients(f)).collect();
    let mut stats = DescriptorStats {
        degenerate_faces: ctx.degenerate.iter().filter(|&&d| d).count(),
        ..DescriptorStats::default()
    };
    let mut points = Vec::new();
    let mut n_intersections = 0usize;
    for a in 0..fields.len() {
        for b in a + 1..fields.len() {
            let pair = PairCtx {
                a: a as u8,
                b: b as u8,
                fa: &work[a],
                fb: &work[b],
                ga: &grads[a],
                gb: &grads[b],
            };
            match opts.rule {
                SelectionRule::Filter { .. } | SelectionRule::All => {
                    let n0 = points.len();
                    let found = ctx.grid_points(&pair, &mut stats, &mut points)?;
                    n_intersections += found;
                    let _ = n0;
                }
                SelectionRule::IsoAngle => {
                    n_intersections += ctx.isoangle_points(&pair, &mut stats, &mut points)?;
                }
            }
        }
    }
    stats.intersections = n_intersections;
    sort_points(&mut points);
    stats.ambiguous = points.iter().filter(|p| p.ambiguous).count();
    if points.is_empty() {
        let why = if n_intersections == 0 {
            format!(
                "the level curves do not intersect within levels 1..={max_level} (step {step:e})"
            )
        } else {
            format!("{n_intersections} intersections found but none passed the angle selection")
        };
        return Err(BipolarError::NoIntersections(why));
    }
    Ok(Descriptor {
        points,
        step,
        max_level,
        reference_distance: d01,
        references,
        options: opts.clone(),
        stats,
    })
}

/// Sorts points by key, then position (x, y, z).
pub(crate) fn sort_points(points: &mut [DescriptorPoint]) {
    points.sort_by(|p, q| {
        p.key
            .cmp(&q.key)
            .then(p.position.x.total_cmp(&q.position.x))
            .then(p.position.y.total_cmp(&q.position.y))
            .then(p.position.z.total_cmp(&q.position.z))
    });
}

/// Checks that field number `field` has one value per vertex of a mesh of `n` vertices, none
/// NaN or `-inf` (`+inf`, unreachable, is allowed).
pub(crate) fn check_field(field: usize, values: &[f64], n: usize) -> Result<(), BipolarError> {
    if values.len() != n {
        return Err(BipolarError::FieldLength {
            field,
            expected: n,
            got: values.len(),
        });
    }
    match values
        .iter()
        .enumerate()
        .find(|(_, x)| x.is_nan() || **x == f64::NEG_INFINITY)
    {
        Some((vertex, &value)) => Err(BipolarError::NonFiniteField {
            field,
            vertex,
            value,
        }),
        None => Ok(()),
    }
}

/// The vertices within geodesic distance `margin` (mesh units) of the boundary of `surface`
/// (exact geodesics from the boundary vertices, cut off at `margin`), one flag per vertex: the
/// band [`DescriptorOptions::boundary_margin`] leaves out. Boundary loops shorter than
/// `2 * margin` (pinholes) get no band. All `false` on a closed surface.
pub fn boundary_band(surface: &Surface, margin: f64) -> Result<Vec<bool>, BipolarError> {
    check_margin(margin)?;
    band(surface.mesh(), surface.topology(), margin, None)
}

/// [`boundary_band`] solved by `exact`, an exact solver of the surface's mesh that the caller
/// already has (one preparation fewer; the band is the same). An error when `exact` is not an
/// exact solver or is of a mesh with another number of vertices.
pub fn boundary_band_with(
    surface: &Surface,
    exact: &dyn GeodesicSolver,
    margin: f64,
) -> Result<Vec<bool>, BipolarError> {
    check_margin(margin)?;
    if exact.method() != geodesic::Method::Exact {
        return Err(BipolarError::InvalidOption(format!(
            "the boundary band needs an exact solver, not {:?}",
            exact.method()
        )));
    }
    if exact.n_vertices() != surface.mesh().n_vertices() {
        return Err(BipolarError::InvalidOption(format!(
            "a solver of {} vertices for a surface of {}",
            exact.n_vertices(),
            surface.mesh().n_vertices()
        )));
    }
    band(surface.mesh(), surface.topology(), margin, Some(exact))
}

fn check_margin(margin: f64) -> Result<(), BipolarError> {
    if margin.is_finite() && margin >= 0.0 {
        Ok(())
    } else {
        Err(BipolarError::InvalidOption(format!(
            "boundary margin {margin} (must be finite and non-negative)"
        )))
    }
}

fn band(
    mesh: &TriMesh,
    topo: &Topology,
    margin: f64,
    exact: Option<&dyn GeodesicSolver>,
) -> Result<Vec<bool>, BipolarError> {
    let n = mesh.n_vertices();
    if margin == 0.0 {
        return Ok(vec![false; n]);
    }
    // A geodesic bends around a hole by at most about half its perimeter: loops shorter than
    // twice the margin (the pinholes a noisy scan keeps) bend the fields by less than the
    // margin and get no band.
    let sources: Vec<Source> = topo
        .boundary_loops()
        .iter()
        .filter(|l| mesh.ring_length(l) >= 2.0 * margin)
        .flatten()
        .map(|&v| Source::Vertex(v))
        .collect();
    if sources.is_empty() {
        return Ok(vec![false; n]);
    }
    let own;
    let solver = match exact {
        Some(s) => s,
        None => {
            own = geodesic::new_solver(mesh, geodesic::Method::Exact)?;
            own.as_ref()
        }
    };
    let u = solver.distances(
        &sources,
        &SolveOptions {
            max_distance: Some(margin),
        },
    )?;
    Ok(u.iter().map(|&d| d < margin).collect())
}

fn check_options(opts: &DescriptorOptions, n: usize) -> Result<(), BipolarError> {
    let bad = |m: String| Err(BipolarError::InvalidOption(m));
    if let Some(m) = opts.boundary_margin {
        check_margin(m)?;
    }
    if let LevelSpec::Count(0) = opts.levels {
        return bad("the number of levels must be at least 1".into());
    }
    if !(opts.alpha > 0.0 && opts.alpha <= 1.0) {
        return bad(format!("alpha = {} (must be in (0, 1])", opts.alpha));
    }
    if opts.angles == 0 {
        return bad("the number of angle levels K must be at least 1".into());
    }
    if let SelectionRule::Filter { tolerance } = opts.rule {
        if tolerance.is_nan() || tolerance < 0.0 {
            return bad(format!("filter tolerance {tolerance} (must be >= 0)"));
        }
    }
    let sm = opts.isoangle.smoothing;
    if !(sm.is_finite() && sm >= 0.0) {
        return bad(format!(
            "iso-angle smoothing {sm} (must be finite and >= 0 mean edge lengths)"
        ));
    }
    if !(opts.min_sin >= 0.0 && opts.min_sin < 1.0) {
        return bad(format!("min_sin = {} (must be in [0, 1))", opts.min_sin));
    }
    let s = &opts.strip;
    if !(s.epsilon > 0.0 && s.radius > 0.0 && s.epsilon.is_finite() && s.radius.is_finite()) {
        return bad(format!(
            "strip epsilon {} and radius {} must be positive",
            s.epsilon, s.radius
        ));
    }
    if let Some(c) = opts.spline.control_spacing {
        if !(c > 0.0 && c.is_finite()) {
            return bad(format!("spline control spacing {c} must be positive"));
        }
    }
    if let Some(mask) = &opts.vertex_mask {
        if mask.len() != n {
            return bad(format!(
                "vertex mask has {} entries for {n} vertices",
                mask.len()
            ));
        }
    }
    Ok(())
}

fn source_position(mesh: &TriMesh, r: &Source) -> Result<DVec3, BipolarError> {
    Ok(match r {
        Source::Vertex(v) => mesh.try_position(*v)?,
        Source::Point(sp) => mesh.point_position(sp)?,
    })
}

/// The value of field `f` at reference `r`: its vertex value, or interpolated at a surface point.
fn field_at(mesh: &TriMesh, f: &[f64], r: &Source) -> Result<f64, BipolarError> {
    Ok(match r {
        Source::Vertex(v) => {
            mesh.try_position(*v)?;
            f[*v as usize]
        }
        Source::Point(sp) => mesh.interpolate(f, sp)?,
    })
}

fn source_vertex(mesh: &TriMesh, r: &Source) -> u32 {
    match r {
        Source::Vertex(v) => *v,
        Source::Point(sp) => mesh.triangles()[sp.face as usize][0],
    }
}

/// Checks that there are between 2 and 256 reference points (or fields).
fn check_reference_count(n: usize) -> Result<(), BipolarError> {
    if (2..=256).contains(&n) {
        Ok(())
    } else {
        Err(BipolarError::ReferenceCount(n))
    }
}

/// Validates reference points: in range, not on degenerate faces, same component, distinct.
fn check_references(mesh: &TriMesh, topo: &Topology, refs: &[Source]) -> Result<(), BipolarError> {
    let diag = mesh.bbox().diagonal();
    let mut pos = Vec::with_capacity(refs.len());
    for (i, r) in refs.iter().enumerate() {
        pos.push(source_position(mesh, r)?);
        if let Source::Point(sp) = r {
            if mesh.face_area(sp.face) <= 1e-14 * diag * diag {
                return Err(BipolarError::DegenerateFace {
                    reference: i,
                    face: sp.face,
                });
            }
        }
    }
    for a in 0..refs.len() {
        for b in a + 1..refs.len() {
            let ca = topo.vertex_component()[source_vertex(mesh, &refs[a]) as usize];
            let cb = topo.vertex_component()[source_vertex(mesh, &refs[b]) as usize];
            if ca != cb {
                return Err(BipolarError::DifferentComponents { a, b });
            }
            let d = (pos[a] - pos[b]).length();
            if d <= 1e-12 * diag {
                return Err(BipolarError::CoincidentReferences { a, b, distance: d });
            }
        }
    }
    Ok(())
}

struct PairCtx<'a> {
    a: u8,
    b: u8,
    fa: &'a [f64],
    fb: &'a [f64],
    ga: &'a [DVec3],
    gb: &'a [DVec3],
}

/// Shared per-mesh data.
struct Ctx<'a> {
    mesh: &'a TriMesh,
    topo: &'a Topology,
    opts: &'a DescriptorOptions,
    step: f64,
    max_level: u32,
    diag: f64,
    mel: f64,
    degenerate: Vec<bool>,
}

/// A raw grid intersection.
#[derive(Debug, Clone, Copy)]
struct Raw {
    i: u32,
    j: u32,
    side: i8,
    face: u32,
    bary: DVec3,
    pos: DVec3,
}

impl<'a> Ctx<'a> {
    fn new(
        mesh: &'a TriMesh,
        topo: &'a Topology,
        opts: &'a DescriptorOptions,
        step: f64,
        max_level: u32,
    ) -> Self {
        let diag = mesh.bbox().diagonal();
        let thr = 1e-14 * diag * diag;
        let degenerate = (0..mesh.n_faces() as u32)
            .map(|f| mesh.face_area(f) <= thr)
            .collect();
        Self {
            mesh,
            topo,
            opts,
            step,
            max_level,
            diag,
            mel: mesh.mean_edge_length(),
            degenerate,
        }
    }

    fn face_values(&self, f: &[f64], face: usize) -> Option<[f64; 3]> {
        let t = self.mesh.triangles()[face];
        let u = [f[t[0] as usize], f[t[1] as usize], f[t[2] as usize]];
        (u.iter().all(|x| x.is_finite()) && !self.degenerate[face]).then_some(u)
    }

    fn face_gradients(&self, f: &[f64]) -> Vec<DVec3> {
        (0..self.mesh.n_faces())
            .map(|face| match self.face_values(f, face) {
                Some(u) => face_gradient(self.mesh.face_corners(face as u32), u),
                None => DVec3::ZERO,
            })
            .collect()
    }
}
