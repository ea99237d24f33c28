//! Construction of the descriptor (specification §2).

use crate::{
    BipolarError, Descriptor, DescriptorOptions, DescriptorPoint, DescriptorStats, Key, LevelSpec,
    SelectionRule, TangentMethod,
};
use geodesic::{GeodesicSolver, SolveOptions, Source};
use glam::DVec3;
use levelcurves::{face_gradient, isolines_uniform, uniform_level_range, Isoline};
use meshcore::{Topology, TriMesh};
use std::collections::HashMap;

/// Builds the descriptor of `mesh` for the reference points `refs` (two or more; every pair
/// `a < b` contributes points whose keys carry the pair), computing one distance field per
/// reference with `solver`.
///
/// The step is `d(refs[0], refs[1]) / N` for [`LevelSpec::Count`]. Errors: see
/// [`BipolarError`] (different components, coincident references, no points, ...).
pub fn describe(
    mesh: &TriMesh,
    solver: &dyn GeodesicSolver,
    refs: &[Source],
    opts: &DescriptorOptions,
) -> Result<Descriptor, BipolarError> {
    if refs.len() < 2 || refs.len() > 256 {
        return Err(BipolarError::ReferenceCount(refs.len()));
    }
    if solver.n_vertices() != mesh.n_vertices() {
        return Err(BipolarError::InvalidOption(format!(
            "the solver was prepared for {} vertices but the mesh has {}",
            solver.n_vertices(),
            mesh.n_vertices()
        )));
    }
    let topo = Topology::new(mesh);
    check_references(mesh, &topo, refs)?;
    let fields = match opts.max_level {
        Some(m) if m > 0 => region_fields(mesh, &topo, solver, refs, opts.levels, m)?,
        _ => solve_all(solver, refs, &vec![None; refs.len()])?,
    };
    describe_fields_with_refs(mesh, &topo, &fields, Some(refs), opts)
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
        .edges
        .iter()
        .map(|e| (mesh.position(e.v[0]) - mesh.position(e.v[1])).length())
        .fold(0.0f64, f64::max)
        * (1.0 + 1e-9);
    let pos = refs
        .iter()
        .map(|r| source_position(mesh, r))
        .collect::<Result<Vec<_>, _>>()?;
    let mut comp_size = vec![0usize; topo.n_components];
    for &c in &topo.vertex_component {
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
            let comp = topo.vertex_component[source_vertex(mesh, &refs[a]) as usize] as usize;
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

/// Builds the descriptor from precomputed distance fields (one per reference point, `+inf` for
/// unreachable vertices).
///
/// Without the reference points, `d(r, q)` (for [`LevelSpec::Count`]) is estimated as
/// `min_v (U_0(v) + U_1(v))` and the reference positions as the vertices where each field is
/// smallest.
pub fn describe_fields(
    mesh: &TriMesh,
    topo: &Topology,
    fields: &[Vec<f64>],
    opts: &DescriptorOptions,
) -> Result<Descriptor, BipolarError> {
    describe_fields_with_refs(mesh, topo, fields, None, opts)
}

/// [`describe_fields`] with the reference points known (used for `d(r, q)` and the reference
/// positions, and checked for coincidence / components).
pub fn describe_fields_with_refs(
    mesh: &TriMesh,
    topo: &Topology,
    fields: &[Vec<f64>],
    refs: Option<&[Source]>,
    opts: &DescriptorOptions,
) -> Result<Descriptor, BipolarError> {
    let n = mesh.n_vertices();
    if fields.len() < 2 || fields.len() > 256 {
        return Err(BipolarError::ReferenceCount(fields.len()));
    }
    for (fi, f) in fields.iter().enumerate() {
        if f.len() != n {
            return Err(BipolarError::FieldLength {
                field: fi,
                expected: n,
                got: f.len(),
            });
        }
        if let Some((v, &value)) = f
            .iter()
            .enumerate()
            .find(|(_, x)| x.is_nan() || **x == f64::NEG_INFINITY)
        {
            return Err(BipolarError::NonFiniteField {
                field: fi,
                vertex: v,
                value,
            });
        }
    }
    check_options(opts, n)?;
    if topo.face_edges.len() != mesh.n_faces() {
        return Err(BipolarError::InvalidOption(
            "topology was built for another mesh".into(),
        ));
    }
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

    // Working fields: masked-out vertices become unreachable (+inf, faces skipped).
    let work: Vec<std::borrow::Cow<'_, [f64]>> = fields
        .iter()
        .map(|f| match &opts.vertex_mask {
            Some(mask) => std::borrow::Cow::Owned(
                f.iter()
                    .zip(mask)
                    .map(|(&x, &keep)| if keep { x } else { f64::INFINITY })
                    .collect(),
            ),
            None => std::borrow::Cow::Borrowed(f.as_slice()),
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

fn check_options(opts: &DescriptorOptions, n: usize) -> Result<(), BipolarError> {
    let bad = |m: String| Err(BipolarError::InvalidOption(m));
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

fn field_at(mesh: &TriMesh, f: &[f64], r: &Source) -> Result<f64, BipolarError> {
    Ok(match r {
        Source::Vertex(v) => {
            mesh.try_position(*v)?;
            f[*v as usize]
        }
        Source::Point(sp) => {
            mesh.check_surface_point(sp)?;
            let t = mesh.triangles()[sp.face as usize];
            let mut s = 0.0;
            for k in 0..3 {
                if sp.bary[k] != 0.0 {
                    s += sp.bary[k] * f[t[k] as usize];
                }
            }
            s
        }
    })
}

fn source_vertex(mesh: &TriMesh, r: &Source) -> u32 {
    match r {
        Source::Vertex(v) => *v,
        Source::Point(sp) => mesh.triangles()[sp.face as usize][0],
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
            let ca = topo.vertex_component[source_vertex(mesh, &refs[a]) as usize];
            let cb = topo.vertex_component[source_vertex(mesh, &refs[b]) as usize];
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

    /// Grid intersections (§2.1-2.3), tangents, ambiguity, then the filter (rule A) or none.
    /// Returns the number of intersections found.
    fn grid_points(
        &self,
        pair: &PairCtx<'_>,
        stats: &mut DescriptorStats,
        out: &mut Vec<DescriptorPoint>,
    ) -> Result<usize, BipolarError> {
        let raws = self.grid_intersections(pair, stats);
        if raws.is_empty() {
            return Ok(0);
        }
        // Tangents.
        let cos: Vec<f64> = match self.opts.tangent {
            TangentMethod::Gradient => raws
                .iter()
                .map(|r| cos_of(pair.ga[r.face as usize], pair.gb[r.face as usize]))
                .collect(),
            TangentMethod::Strip => {
                let mut strip = Strip::new(self);
                raws.iter()
                    .map(|r| {
                        let f = r.face as usize;
                        let nf = self.mesh.face_normal(r.face);
                        let ta = strip
                            .tangent(
                                pair.fa,
                                r.i as f64 * self.step,
                                r.pos,
                                r.face,
                                nf,
                                pair.ga[f],
                            )
                            .unwrap_or_else(|| {
                                stats.tangent_fallbacks += 1;
                                nf.cross(pair.ga[f]).normalize_or_zero()
                            });
                        let tb = strip
                            .tangent(
                                pair.fb,
                                r.j as f64 * self.step,
                                r.pos,
                                r.face,
                                nf,
                                pair.gb[f],
                            )
                            .unwrap_or_else(|| {
                                stats.tangent_fallbacks += 1;
                                nf.cross(pair.gb[f]).normalize_or_zero()
                            });
                        ta.dot(tb)
                    })
                    .collect()
            }
            TangentMethod::Spline => {
                let sa = SplineSet::new(self, pair.fa)?;
                let sb = SplineSet::new(self, pair.fb)?;
                raws.iter()
                    .map(|r| {
                        let f = r.face as usize;
                        let nf = self.mesh.face_normal(r.face);
                        let ta = sa
                            .tangent_at(r.i, r.face, r.pos, nf, pair.ga[f])
                            .unwrap_or_else(|| {
                                stats.tangent_fallbacks += 1;
                                nf.cross(pair.ga[f]).normalize_or_zero()
                            });
                        let tb = sb
                            .tangent_at(r.j, r.face, r.pos, nf, pair.gb[f])
                            .unwrap_or_else(|| {
                                stats.tangent_fallbacks += 1;
                                nf.cross(pair.gb[f]).normalize_or_zero()
                            });
                        ta.dot(tb)
                    })
                    .collect()
            }
        };
        // Merge duplicates (a point on an edge or at a vertex is found in every face around
        // it): average position and cos over the group (order-independent, so invariant to
        // motions and renumbering), keep the face of smallest index.
        let (raws, cos) = merge_duplicates(&raws, &cos, 1e-9 * self.diag);
        let n = raws.len();
        // Ambiguity on all intersections (before any filtering).
        let mut amb = vec![false; n];
        let mut s = 0;
        while s < n {
            let mut e = s + 1;
            while e < n && same_key(&raws[e], &raws[s]) {
                e += 1;
            }
            if e - s > 1 {
                amb[s..e].iter_mut().for_each(|x| *x = true);
            }
            s = e;
        }
        let k_max = self.opts.angles as f64;
        let alpha = self.opts.alpha;
        for (idx, r) in raws.iter().enumerate() {
            let c = cos[idx].clamp(-1.0, 1.0);
            if !c.is_finite() {
                continue;
            }
            if let SelectionRule::Filter { tolerance } = self.opts.rule {
                let ks = (c.abs() * k_max / alpha).round();
                if ks > k_max || (c.abs() - alpha * ks / k_max).abs() > tolerance {
                    continue;
                }
            }
            out.push(DescriptorPoint {
                position: r.pos,
                key: Key {
                    a: pair.a,
                    b: pair.b,
                    i: r.i,
                    j: r.j,
                    side: r.side,
                    sign: 0,
                },
                cos: c,
                face: r.face,
                bary: r.bary,
                ambiguous: amb[idx],
            });
        }
        Ok(n)
    }

    /// All intersections of the two level families, merged and sorted by key then position.
    fn grid_intersections(&self, pair: &PairCtx<'_>, stats: &mut DescriptorStats) -> Vec<Raw> {
        let tris = self.mesh.triangles();
        let m = self.max_level;
        let step = self.step;
        let min_sin = self.opts.min_sin;
        let mut raws = Vec::new();
        for (f, t) in tris.iter().enumerate() {
            let Some(r) = self.face_values(pair.fa, f) else {
                continue;
            };
            let Some(q) = self.face_values(pair.fb, f) else {
                continue;
            };
            let ir =
                uniform_level_range(r[0].min(r[1]).min(r[2]), r[0].max(r[1]).max(r[2]), step, m);
            if ir.is_empty() {
                continue;
            }
            let jr =
                uniform_level_range(q[0].min(q[1]).min(q[2]), q[0].max(q[1]).max(q[2]), step, m);
            if jr.is_empty() {
                continue;
            }
            let (r1, r2) = (r[1] - r[0], r[2] - r[0]);
            let (q1, q2) = (q[1] - q[0], q[2] - q[0]);
            let det = r1 * q2 - r2 * q1;
            let scale = (r1.abs() + r2.abs()) * (q1.abs() + q2.abs());
            let n_pairs = ir.len() * jr.len();
            if det.abs() <= 1e-12 * scale || scale == 0.0 {
                stats.ill_conditioned += n_pairs;
                continue;
            }
            // |sin| = |det| / (2A |ga| |gb|).
            let two_a = self.mesh.face_cross(f as u32).length();
            let sin = det.abs() / (two_a * pair.ga[f].length() * pair.gb[f].length());
            if sin < min_sin {
                stats.ill_conditioned += n_pairs;
                continue;
            }
            let side: i8 = if det > 0.0 { 1 } else { -1 };
            let p = [
                self.mesh.position(t[0]),
                self.mesh.position(t[1]),
                self.mesh.position(t[2]),
            ];
            for i in ir.clone() {
                let av = i as f64 * step - r[0];
                for j in jr.clone() {
                    let bv = j as f64 * step - q[0];
                    let b1 = (av * q2 - r2 * bv) / det;
                    let b2 = (r1 * bv - av * q1) / det;
                    let b0 = 1.0 - b1 - b2;
                    if b0 < -1e-10 || b1 < -1e-10 || b2 < -1e-10 {
                        continue;
                    }
                    let bc = DVec3::new(b0.max(0.0), b1.max(0.0), b2.max(0.0));
                    let bc = bc / bc.element_sum();
                    raws.push(Raw {
                        i,
                        j,
                        side,
                        face: f as u32,
                        bary: bc,
                        pos: bc.x * p[0] + bc.y * p[1] + bc.z * p[2],
                    });
                }
            }
        }
        raws.sort_by(|x, y| {
            (x.i, x.j, x.side)
                .cmp(&(y.i, y.j, y.side))
                .then(x.pos.x.total_cmp(&y.pos.x))
                .then(x.pos.y.total_cmp(&y.pos.y))
                .then(x.pos.z.total_cmp(&y.pos.z))
                .then(x.face.cmp(&y.face))
        });
        raws
    }

    /// Iso-angle points along the level curves of the first field (rule B, §2.5-B).
    /// Returns the number of points found (before nothing is filtered: all are kept).
    fn isoangle_points(
        &self,
        pair: &PairCtx<'_>,
        stats: &mut DescriptorStats,
        out: &mut Vec<DescriptorPoint>,
    ) -> Result<usize, BipolarError> {
        let levels = isolines_uniform(self.mesh, self.topo, pair.fa, self.step, self.max_level)?;
        let vn = self.mesh.vertex_normals();
        let va = self.vertex_gradients(pair.fa, pair.ga, &vn);
        let vb = self.vertex_gradients(pair.fb, pair.gb, &vn);
        let splines = match self.opts.tangent {
            TangentMethod::Spline => Some(SplineSet::from_levels(self, &levels)?),
            _ => None,
        };
        let mut strip = match self.opts.tangent {
            TangentMethod::Strip => Some(Strip::new(self)),
            _ => None,
        };
        let k_max = self.opts.angles;
        let alpha = self.opts.alpha;
        let targets: Vec<(u32, f64, i8)> = (0..=k_max)
            .flat_map(|k| {
                let c = alpha * k as f64 / k_max as f64;
                if k == 0 {
                    vec![(0, 0.0, 0)]
                } else {
                    vec![(k, c, 1), (k, -c, -1)]
                }
            })
            .collect();
        let bmax = self.max_level as f64 * self.step;
        let start = out.len();
        for (li, pieces) in levels.iter().enumerate() {
            let i = li as u32 + 1;
            let lambda = i as f64 * self.step;
            for (pi, iso) in pieces.iter().enumerate() {
                let np = iso.points.len();
                if iso.n_segments() == 0 {
                    continue;
                }
                let mut cos = vec![f64::NAN; np];
                let mut ub = vec![f64::NAN; np];
                for k in 0..np {
                    let (lo, hi) = iso.edge_of[k];
                    let t = iso.t_of[k];
                    let (lo, hi) = (lo as usize, hi as usize);
                    ub[k] = pair.fb[lo] + t * (pair.fb[hi] - pair.fb[lo]);
                    let nrm = (vn[lo] + t * (vn[hi] - vn[lo])).normalize_or_zero();
                    let ga = va[lo] + t * (va[hi] - va[lo]);
                    let gb = vb[lo] + t * (vb[hi] - vb[lo]);
                    let tb = nrm.cross(gb).normalize_or_zero();
                    // A face adjacent to this point along the curve.
                    let seg = if k < iso.n_segments() { k } else { k - 1 };
                    let face = iso.face_of[seg];
                    let ta = match self.opts.tangent {
                        TangentMethod::Gradient => Some(nrm.cross(ga).normalize_or_zero()),
                        TangentMethod::Strip => strip
                            .as_mut()
                            .and_then(|s| s.tangent(pair.fa, lambda, iso.points[k], face, nrm, ga)),
                        TangentMethod::Spline => splines
                            .as_ref()
                            .and_then(|s| s.tangent_at_point(li, pi, k, nrm, ga)),
                    };
                    let ta = ta.unwrap_or_else(|| {
                        stats.tangent_fallbacks += 1;
                        nrm.cross(ga).normalize_or_zero()
                    });
                    if ta != DVec3::ZERO && tb != DVec3::ZERO {
                        cos[k] = ta.dot(tb).clamp(-1.0, 1.0);
                    }
                }
                for seg in 0..iso.n_segments() {
                    let k0 = seg;
                    let k1 = (seg + 1) % np;
                    let (c0, c1) = (cos[k0], cos[k1]);
                    if !(c0.is_finite() && c1.is_finite()) {
                        continue;
                    }
                    let face = iso.face_of[seg];
                    let f = face as usize;
                    let det_sign = self
                        .mesh
                        .face_normal(face)
                        .dot(pair.ga[f].cross(pair.gb[f]));
                    if det_sign == 0.0 || !det_sign.is_finite() {
                        continue;
                    }
                    let side: i8 = if det_sign > 0.0 { 1 } else { -1 };
                    for &(k, target, sign) in &targets {
                        // Samples within 1e-12 of the target count as on it ("above"), so a
                        // rounding-level change cannot create or move a crossing.
                        let snap = |c: f64| {
                            if (c - target).abs() <= 1e-12 {
                                target
                            } else {
                                c
                            }
                        };
                        let (c0, c1) = (snap(c0), snap(c1));
                        if (c0 >= target) == (c1 >= target) {
                            continue;
                        }
                        let phi = ((target - c0) / (c1 - c0)).clamp(0.0, 1.0);
                        let ubp = ub[k0] + phi * (ub[k1] - ub[k0]);
                        if !(ubp.is_finite() && ubp > 0.0 && ubp <= bmax) {
                            continue;
                        }
                        let pos = iso.points[k0] + phi * (iso.points[k1] - iso.points[k0]);
                        let bary = self.barycentric(face, pos);
                        out.push(DescriptorPoint {
                            position: pos,
                            key: Key {
                                a: pair.a,
                                b: pair.b,
                                i,
                                j: k,
                                side,
                                sign,
                            },
                            cos: target,
                            face,
                            bary,
                            ambiguous: false,
                        });
                    }
                }
            }
        }
        // Ambiguity: several points with one key.
        let mine = &mut out[start..];
        sort_points(mine);
        let n = mine.len();
        let mut s = 0;
        while s < n {
            let mut e = s + 1;
            while e < n && mine[e].key == mine[s].key {
                e += 1;
            }
            if e - s > 1 {
                mine[s..e].iter_mut().for_each(|p| p.ambiguous = true);
            }
            s = e;
        }
        Ok(n)
    }

    /// Area-weighted per-vertex gradients projected on the vertex tangent planes (M0s).
    fn vertex_gradients(&self, f: &[f64], g: &[DVec3], vn: &[DVec3]) -> Vec<DVec3> {
        let mut acc = vec![DVec3::ZERO; self.mesh.n_vertices()];
        let mut w = vec![0.0; self.mesh.n_vertices()];
        let mut mag = vec![0.0; self.mesh.n_vertices()];
        for (face, t) in self.mesh.triangles().iter().enumerate() {
            if self.face_values(f, face).is_none() {
                continue;
            }
            let area = self.mesh.face_area(face as u32);
            for &v in t {
                acc[v as usize] += area * g[face];
                mag[v as usize] += area * g[face].length();
                w[v as usize] += area;
            }
        }
        acc.iter()
            .zip(&w)
            .zip(vn)
            .zip(&mag)
            .map(|(((a, &w), n), &mag)| {
                // Where the face gradients around a vertex cancel (the source of a distance
                // field, a ridge), the direction is undefined: return zero (no tangent).
                if w > 0.0 && a.length() > 0.1 * mag {
                    let m = *a / w;
                    m - m.dot(*n) * *n
                } else {
                    DVec3::ZERO
                }
            })
            .collect()
    }

    /// Barycentric coordinates of `p` (assumed in the plane of `face`), clamped to the face.
    fn barycentric(&self, face: u32, p: DVec3) -> DVec3 {
        let [a, b, c] = self.mesh.face_corners(face);
        meshcore::closest_point_on_triangle(p, a, b, c)
    }
}

/// Groups raw intersections (sorted by key, then position) of equal key lying within `tol`
/// of each other; returns one point per group (mean position and cos, smallest face),
/// sorted by key then position.
fn merge_duplicates(raws: &[Raw], cos: &[f64], tol: f64) -> (Vec<Raw>, Vec<f64>) {
    let mut out: Vec<Raw> = Vec::with_capacity(raws.len());
    let mut out_cos = Vec::with_capacity(raws.len());
    let mut s = 0;
    while s < raws.len() {
        let mut e = s + 1;
        while e < raws.len() && same_key(&raws[e], &raws[s]) {
            e += 1;
        }
        // Greedy clustering within the key run.
        let mut group_of = vec![usize::MAX; e - s];
        let mut n_groups = 0;
        for a in 0..e - s {
            if group_of[a] != usize::MAX {
                continue;
            }
            group_of[a] = n_groups;
            let mut members = vec![a];
            let mut k = 0;
            while k < members.len() {
                let m = members[k];
                for b in 0..e - s {
                    if group_of[b] == usize::MAX
                        && (raws[s + b].pos - raws[s + m].pos).length() <= tol
                    {
                        group_of[b] = n_groups;
                        members.push(b);
                    }
                }
                k += 1;
            }
            let cnt = members.len() as f64;
            let pos = members.iter().map(|&m| raws[s + m].pos).sum::<DVec3>() / cnt;
            let mean_cos = members.iter().map(|&m| cos[s + m]).sum::<f64>() / cnt;
            let keep = members
                .iter()
                .map(|&m| raws[s + m])
                .min_by_key(|r| r.face)
                .unwrap_or(raws[s + a]);
            out.push(Raw { pos, ..keep });
            out_cos.push(mean_cos);
            n_groups += 1;
        }
        s = e;
    }
    // Re-sort by key then position (the means moved).
    let mut idx: Vec<usize> = (0..out.len()).collect();
    idx.sort_by(|&x, &y| {
        let (a, b) = (&out[x], &out[y]);
        (a.i, a.j, a.side)
            .cmp(&(b.i, b.j, b.side))
            .then(a.pos.x.total_cmp(&b.pos.x))
            .then(a.pos.y.total_cmp(&b.pos.y))
            .then(a.pos.z.total_cmp(&b.pos.z))
    });
    (
        idx.iter().map(|&i| out[i]).collect(),
        idx.iter().map(|&i| out_cos[i]).collect(),
    )
}

fn same_key(a: &Raw, b: &Raw) -> bool {
    a.i == b.i && a.j == b.j && a.side == b.side
}

fn cos_of(a: DVec3, b: DVec3) -> f64 {
    let d = a.length() * b.length();
    if d > 0.0 {
        (a.dot(b) / d).clamp(-1.0, 1.0)
    } else {
        f64::NAN
    }
}

/// Strip tangents (M1): principal axis of nearby vertices close to the level.
struct Strip<'c, 'a> {
    ctx: &'c Ctx<'a>,
    offsets: Vec<u32>,
    adj: Vec<u32>,
    stamp: Vec<u32>,
    gen: u32,
    queue: Vec<u32>,
}

impl<'c, 'a> Strip<'c, 'a> {
    fn new(ctx: &'c Ctx<'a>) -> Self {
        let n = ctx.mesh.n_vertices();
        let mut deg = vec![0u32; n + 1];
        for e in &ctx.topo.edges {
            deg[e.v[0] as usize + 1] += 1;
            deg[e.v[1] as usize + 1] += 1;
        }
        for i in 0..n {
            deg[i + 1] += deg[i];
        }
        let mut fill = deg.clone();
        let mut adj = vec![0u32; deg[n] as usize];
        for e in &ctx.topo.edges {
            for (x, y) in [(e.v[0], e.v[1]), (e.v[1], e.v[0])] {
                adj[fill[x as usize] as usize] = y;
                fill[x as usize] += 1;
            }
        }
        Self {
            ctx,
            offsets: deg,
            adj,
            stamp: vec![0; n],
            gen: 0,
            queue: Vec::new(),
        }
    }

    /// Tangent of the level curve `field = level` at `p` (in `face`), projected on the plane of
    /// normal `nrm` and oriented along `nrm x grad`; `None` when the strip is too small or has
    /// no dominant direction.
    fn tangent(
        &mut self,
        field: &[f64],
        level: f64,
        p: DVec3,
        face: u32,
        nrm: DVec3,
        grad: DVec3,
    ) -> Option<DVec3> {
        let so = &self.ctx.opts.strip;
        let eps = so.epsilon * self.ctx.mel;
        let rho = so.radius * self.ctx.mel;
        let pos = self.ctx.mesh.positions();
        self.gen = self.gen.wrapping_add(1);
        if self.gen == 0 {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.gen = 1;
        }
        self.queue.clear();
        for &v in &self.ctx.mesh.triangles()[face as usize] {
            if self.stamp[v as usize] != self.gen {
                self.stamp[v as usize] = self.gen;
                self.queue.push(v);
            }
        }
        let mut pts: Vec<DVec3> = Vec::new();
        let mut head = 0;
        while head < self.queue.len() {
            let v = self.queue[head];
            head += 1;
            let x = pos[v as usize];
            if (x - p).length() > rho {
                continue;
            }
            let u = field[v as usize];
            if u.is_finite() && (u - level).abs() <= eps {
                pts.push(x);
            }
            let (a, b) = (
                self.offsets[v as usize] as usize,
                self.offsets[v as usize + 1] as usize,
            );
            for &w in &self.adj[a..b] {
                if self.stamp[w as usize] != self.gen {
                    self.stamp[w as usize] = self.gen;
                    self.queue.push(w);
                }
            }
        }
        if pts.len() < so.min_vertices.max(2) {
            return None;
        }
        let c = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
        let mut m = [[0.0; 3]; 3];
        for q in &pts {
            let d = *q - c;
            for r in 0..3 {
                for s in 0..3 {
                    m[r][s] += d[r] * d[s];
                }
            }
        }
        let (vals, vecs) = meshcore::linalg::sym_eigen3(glam::DMat3::from_cols_array_2d(&m));
        if vals[0].is_nan() || vals[0] <= 0.0 || vals[0] < so.min_ratio * vals[1].max(0.0) {
            return None;
        }
        let t = vecs[0];
        let t = (t - t.dot(nrm) * nrm).normalize_or_zero();
        if t == DVec3::ZERO {
            return None;
        }
        let reference = nrm.cross(grad);
        Some(if t.dot(reference) < 0.0 { -t } else { t })
    }
}

/// A fitted piece: the spline and the parameter of each polyline point.
type PieceFit = (bspline::BSpline3, Vec<f64>);

/// B-spline fits of the level-curve pieces of one field (M2).
struct SplineSet {
    /// Per level (index `i - 1`), per piece: the spline and the parameter of each polyline
    /// point (None when the piece is too short or the fit failed).
    fits: Vec<Vec<Option<PieceFit>>>,
    levels: Vec<Vec<Isoline>>,
    /// (level index, face) -> (piece, segment).
    seg_of: HashMap<(u32, u32), (u32, u32)>,
}

impl SplineSet {
    fn new(ctx: &Ctx<'_>, field: &[f64]) -> Result<Self, BipolarError> {
        let levels = isolines_uniform(ctx.mesh, ctx.topo, field, ctx.step, ctx.max_level)?;
        Self::from_levels(ctx, &levels)
    }

    fn from_levels(ctx: &Ctx<'_>, levels: &[Vec<Isoline>]) -> Result<Self, BipolarError> {
        let so = &ctx.opts.spline;
        let mut seg_of = HashMap::new();
        let mut fits = Vec::with_capacity(levels.len());
        let tol = 1e-9 * ctx.diag;
        for (li, pieces) in levels.iter().enumerate() {
            let mut row = Vec::with_capacity(pieces.len());
            for (pi, iso) in pieces.iter().enumerate() {
                for (s, &f) in iso.face_of.iter().enumerate() {
                    seg_of.insert((li as u32, f), (pi as u32, s as u32));
                }
                let (pts, kept) = bspline::dedup_consecutive(&iso.points, tol, iso.closed);
                if pts.len() < so.min_points.max(bspline::DEGREE + 1) {
                    row.push(None);
                    continue;
                }
                let opts = bspline::FitOptions {
                    closed: iso.closed,
                    control_spacing: so.control_spacing.map(|c| c * ctx.mel),
                    smoothing: so.smoothing,
                    ..bspline::FitOptions::default()
                };
                match bspline::BSpline3::fit(&pts, &opts) {
                    Ok(sp) => {
                        let mut par = vec![0.0; iso.points.len()];
                        let mut kk = 0;
                        for (o, p) in par.iter_mut().enumerate() {
                            while kk + 1 < kept.len() && kept[kk + 1] <= o {
                                kk += 1;
                            }
                            *p = sp.params()[kk];
                        }
                        row.push(Some((sp, par)));
                    }
                    Err(_) => row.push(None),
                }
            }
            fits.push(row);
        }
        Ok(Self {
            fits,
            levels: levels.to_vec(),
            seg_of,
        })
    }

    fn orient(d: DVec3, nrm: DVec3, grad: DVec3) -> Option<DVec3> {
        let t = (d - d.dot(nrm) * nrm).normalize_or_zero();
        if t == DVec3::ZERO {
            return None;
        }
        Some(if t.dot(nrm.cross(grad)) < 0.0 { -t } else { t })
    }

    /// Tangent at an intersection point `p` in `face` on level `level` (1-based).
    fn tangent_at(
        &self,
        level: u32,
        face: u32,
        p: DVec3,
        nrm: DVec3,
        grad: DVec3,
    ) -> Option<DVec3> {
        let li = level.checked_sub(1)?;
        let &(pi, s) = self.seg_of.get(&(li, face))?;
        let (sp, par) = self.fits[li as usize][pi as usize].as_ref()?;
        let iso = &self.levels[li as usize][pi as usize];
        let s = s as usize;
        let (a, b) = iso.segment(s);
        let ab = b - a;
        let phi = if ab.length_squared() > 0.0 {
            ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let u0 = par[s];
        let u1 = if s + 1 < par.len() {
            par[s + 1]
        } else {
            1.0 // closing segment of a closed curve
        };
        let u = sp.closest_param_from(p, u0 + phi * (u1 - u0));
        Self::orient(sp.derivative(u), nrm, grad)
    }

    /// Tangent at polyline point `k` of piece `pi` of level index `li`.
    fn tangent_at_point(
        &self,
        li: usize,
        pi: usize,
        k: usize,
        nrm: DVec3,
        grad: DVec3,
    ) -> Option<DVec3> {
        let (sp, par) = self.fits[li][pi].as_ref()?;
        Self::orient(sp.derivative(par[k]), nrm, grad)
    }
}
