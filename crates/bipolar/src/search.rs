//! Candidate reference points for a reference-point search.
//!
//! The descriptor takes its two fields from the reference points, so a few millimetres of
//! error in a detected eye corner move the whole descriptor (on range scans, a corner 4 mm off
//! tripled the distance to the same face). A search describes a face from several placements
//! of each reference around the given one and keeps, per comparison, the least distance.
//! [`reference_candidates`] gives those placements, [`SearchedPole`] them with their fields,
//! [`moved_pairs`] the pole pairs two searched poles make, [`describe_searched`] the
//! descriptors of them all for two reference points, and [`least_searched_distance`] the
//! distance of two faces so described.

use crate::{BipolarError, Descriptor, DescriptorOptions, Fields};
use geodesic::{GeodesicSolver, SolveOptions, Source};
use meshcore::{DVec3, Surface, TriMesh};

/// A pole of a reference-point search: its candidate vertices ([`reference_candidates`], the
/// given place first) and the geodesic distance field from each (`None` where its solve
/// failed). The default has no candidate, so it makes no pair.
#[derive(Debug, Clone, Default)]
pub struct SearchedPole {
    /// Candidate vertices, the given one first.
    pub vertices: Vec<u32>,
    /// The field from each candidate, in the same order.
    pub fields: Vec<Option<Vec<f64>>>,
}

impl SearchedPole {
    /// The candidates of the reference vertex `v` (as [`reference_candidates`] with `toward`,
    /// `radius` and `directions`) with their fields: `given`, the field from `v`, is taken as
    /// it is, the moved candidates' are solved by `solver` with `opts` (a cut-off keeps the
    /// solves short), in parallel. Errors are those of [`reference_candidates`]; a failed solve
    /// leaves that candidate's field `None`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        mesh: &TriMesh,
        solver: &dyn GeodesicSolver,
        v: u32,
        toward: DVec3,
        given: &[f64],
        radius: f64,
        directions: usize,
        opts: &SolveOptions,
    ) -> Result<Self, BipolarError> {
        let vertices = reference_candidates(mesh, v, toward, radius, directions)?;
        // The moved candidates' fields in one parallel batch; should any fail, each is solved
        // on its own, so that only the failed ones are `None`.
        let sets: Vec<Vec<Source>> = vertices
            .iter()
            .filter(|&&w| w != v)
            .map(|&w| vec![Source::Vertex(w)])
            .collect();
        let mut solved = match solver.distances_many(&sets, opts) {
            Ok(f) => f.into_iter().map(Some).collect::<Vec<_>>(),
            Err(_) => sets
                .iter()
                .map(|set| solver.distances(set, opts).ok())
                .collect(),
        }
        .into_iter();
        let fields = vertices
            .iter()
            .map(|&w| {
                if w == v {
                    Some(given.to_vec())
                } else {
                    solved.next().flatten()
                }
            })
            .collect();
        Ok(Self { vertices, fields })
    }
}

/// A pole pair of a reference-point search: its two vertices, their fields and their
/// reference distance `d`.
#[derive(Debug, Clone, Copy)]
pub struct MovedPair<'a> {
    /// The first pole's vertex.
    pub r: u32,
    /// The second pole's vertex.
    pub q: u32,
    /// The field from `r`.
    pub ur: &'a [f64],
    /// The field from `q`.
    pub uq: &'a [f64],
    /// The mean of each field at the other pole.
    pub d: f64,
}

/// The pole pairs of two searched poles with at least one moved: every candidate of `a` with
/// every candidate of `b` but the two given ones together, `a`'s candidates in the outer loop.
/// Pairs with a failed field, or whose `d` is not positive and finite (the poles not connected
/// within the fields' cut-off), are left out.
pub fn moved_pairs<'a>(
    a: &'a SearchedPole,
    b: &'a SearchedPole,
) -> impl Iterator<Item = MovedPair<'a>> + 'a {
    let pairs = a
        .vertices
        .iter()
        .zip(&a.fields)
        .enumerate()
        .flat_map(move |(i, (&r, ur))| {
            b.vertices
                .iter()
                .zip(&b.fields)
                .enumerate()
                .map(move |(j, (&q, uq))| (i, j, r, ur, q, uq))
        });
    pairs.filter_map(|(i, j, r, ur, q, uq)| {
        if i == 0 && j == 0 {
            return None;
        }
        let (ur, uq) = (ur.as_deref()?, uq.as_deref()?);
        let d = 0.5 * (ur.get(q as usize)? + uq.get(r as usize)?);
        (d.is_finite() && d > 0.0).then_some(MovedPair { r, q, ur, uq, d })
    })
}

/// The distance of two faces described with a reference-point search: the least of the
/// distance of their own descriptors (`a`, `b`) and of each side's moved descriptors
/// (`a_moved`, `b_moved`: from [`describe_searched`], its first one left out) against the other
/// side's own. Moved against moved is not compared: that would move the two sides' references
/// at once and give both faces twice the freedom. Symmetric when `dist` is. Either list may
/// be empty (a one-sided search: a probe searched against a gallery described once).
///
/// A distance that fails or is NaN is skipped; when every one does, the error (or NaN) of the
/// own descriptors' distance is returned.
pub fn least_searched_distance<T, E>(
    a: &T,
    a_moved: &[T],
    b: &T,
    b_moved: &[T],
    mut dist: impl FnMut(&T, &T) -> Result<f64, E>,
) -> Result<f64, E> {
    let own = dist(a, b);
    let moved = a_moved
        .iter()
        .map(|m| (m, b))
        .chain(b_moved.iter().map(|m| (a, m)));
    let mut least = f64::NAN;
    for (x, y) in moved {
        if let Ok(v) = dist(x, y) {
            least = least.min(v);
        }
    }
    match own {
        Ok(v) => Ok(v.min(least)),
        Err(_) if !least.is_nan() => Ok(least),
        Err(e) => Err(e),
    }
}

/// The descriptors of a reference-point search around two reference points: their own
/// descriptor ([`crate::describe`] with `solver`) first, then one per moved pole pair
/// ([`moved_pairs`] of the two references' [`SearchedPole`]s: each reference at its vertex, a
/// surface point at the nearest corner of its face, with `directions` candidates at `radius`,
/// the first toward the other reference), all with `opts`. A comparison's distance is then
/// the least over them. Moved pairs whose descriptor fails (no points, ...) are left out. The
/// fields of the moved poles are solved without a cut-off (two plus one per moved candidate).
///
/// Errors: not exactly two references; those of [`crate::describe`] for the own descriptor; a
/// reference off the mesh; those of [`reference_candidates`] (radius, directions).
pub fn describe_searched(
    surface: &Surface,
    solver: &dyn GeodesicSolver,
    references: &[Source],
    radius: f64,
    directions: usize,
    opts: &DescriptorOptions,
) -> Result<Vec<Descriptor>, BipolarError> {
    if references.len() != 2 {
        return Err(BipolarError::ReferenceCount(references.len()));
    }
    let own = crate::describe(surface, Fields::Solve { solver, references }, opts)?;
    let mesh = surface.mesh();
    let vertex = |s: &Source| match s {
        Source::Vertex(v) => mesh.try_position(*v).map(|_| *v),
        Source::Point(p) => mesh.nearest_corner(p),
    };
    let (a, b) = (vertex(&references[0])?, vertex(&references[1])?);
    let whole = SolveOptions::default();
    let pole = |v: u32, toward: u32| -> Result<SearchedPole, BipolarError> {
        let given = solver.distances(&[Source::Vertex(v)], &whole)?;
        let toward = mesh.position(toward);
        SearchedPole::new(mesh, solver, v, toward, &given, radius, directions, &whole)
    };
    let (pa, pb) = (pole(a, b)?, pole(b, a)?);
    let mut out = vec![own];
    for m in moved_pairs(&pa, &pb) {
        let fields = [m.ur.to_vec(), m.uq.to_vec()];
        let references = [Source::Vertex(m.r), Source::Vertex(m.q)];
        let fields = Fields::Precomputed {
            fields: &fields,
            references: Some(&references),
        };
        if let Ok(d) = crate::describe(surface, fields, opts) {
            out.push(d);
        }
    }
    Ok(out)
}

/// Vertices around the reference vertex `v` for a reference-point search: `v` first, then,
/// for each of `directions` directions evenly spread in `v`'s tangent plane (the first toward
/// `toward`, usually the other reference), the vertex nearest to the point at `radius` from
/// `v` (mesh units) in that direction; repeated vertices are listed once.
///
/// Deterministic, and follows rigid motions of the mesh with `toward` (the tangent frame is
/// built from the vertex normal and `toward`). Errors: `v` out of range, a radius that is not
/// positive and finite, no direction, or a `toward` on the normal through `v` (no tangent
/// direction toward it).
pub fn reference_candidates(
    mesh: &TriMesh,
    v: u32,
    toward: DVec3,
    radius: f64,
    directions: usize,
) -> Result<Vec<u32>, BipolarError> {
    let p = mesh.try_position(v)?;
    if !(radius.is_finite() && radius > 0.0) {
        return Err(BipolarError::InvalidOption(format!(
            "reference search radius must be positive and finite, got {radius}"
        )));
    }
    if directions == 0 {
        return Err(BipolarError::InvalidOption(
            "reference search needs at least one direction".into(),
        ));
    }
    let n = vertex_normal(mesh, v);
    let d = toward - p;
    let e1 = (d - n * d.dot(n)).try_normalize().ok_or_else(|| {
        BipolarError::InvalidOption(format!(
            "reference search: {toward} gives no tangent direction at vertex {v}"
        ))
    })?;
    let e2 = n.cross(e1);
    let mut out = vec![v];
    for k in 0..directions {
        let a = k as f64 * std::f64::consts::TAU / directions as f64;
        let target = p + radius * (a.cos() * e1 + a.sin() * e2);
        let w = nearest_vertex(mesh, target);
        if !out.contains(&w) {
            out.push(w);
        }
    }
    Ok(out)
}

/// Area-weighted unit normal at `v` (the sum of its faces' cross products); `+z` for an
/// isolated vertex.
fn vertex_normal(mesh: &TriMesh, v: u32) -> DVec3 {
    let mut n = DVec3::ZERO;
    for t in mesh.triangles().iter().filter(|t| t.contains(&v)) {
        let [a, b, c] = t.map(|i| mesh.position(i));
        n += (b - a).cross(c - a);
    }
    n.try_normalize().unwrap_or(DVec3::Z)
}

/// The vertex nearest to `p` (lowest index on ties).
fn nearest_vertex(mesh: &TriMesh, p: DVec3) -> u32 {
    let mut best = (f64::INFINITY, 0u32);
    for (i, q) in mesh.positions().iter().enumerate() {
        let d2 = (*q - p).length_squared();
        if d2 < best.0 {
            best = (d2, i as u32);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshcore::{DAffine3, DQuat};

    /// A square grid of `n x n` vertices spaced `h` in the plane z = 0 (vertex `(i, j)` has id
    /// `j n + i`).
    fn grid(n: usize, h: f64) -> TriMesh {
        meshcore::shapes::grid(
            n - 1,
            n - 1,
            meshcore::shapes::Diagonals::Uniform,
            |i, j| DVec3::new(i as f64 * h, j as f64 * h, 0.0),
        )
        .unwrap()
    }

    #[test]
    fn candidates_ring_the_reference_at_the_radius() {
        let (n, h) = (41, 0.25);
        let m = grid(n, h);
        let v = (20 * n + 20) as u32;
        let c = reference_candidates(&m, v, DVec3::new(10.0, 5.0, 0.0), 2.0, 6).unwrap();
        assert_eq!(c[0], v);
        assert_eq!(c.len(), 7, "{c:?}");
        let p = m.position(v);
        for (k, &w) in c[1..].iter().enumerate() {
            let q = m.position(w) - p;
            // On the radius within half a grid diagonal, in its direction.
            assert!((q.length() - 2.0).abs() < 0.5 * h * 2f64.sqrt(), "{k}: {q}");
            let a = q.y.atan2(q.x) - std::f64::consts::FRAC_PI_2 * (k as f64 * 4.0 / 6.0);
            assert!(a.sin().abs() < 0.2, "{k}: direction {q}");
        }
        // The first direction points toward `toward` (+x here).
        assert!(m.position(c[1]).x > p.x + 1.8);
    }

    #[test]
    fn candidates_follow_a_rigid_motion() {
        let m = grid(41, 0.25);
        let v = 20 * 41 + 20;
        let toward = DVec3::new(9.0, 1.0, 0.0);
        let t = DAffine3::from_rotation_translation(
            DQuat::from_axis_angle(DVec3::new(1.0, -2.0, 0.5).normalize(), 0.8),
            DVec3::new(3.0, -1.0, 7.0),
        );
        let base = reference_candidates(&m, v, toward, 1.5, 8).unwrap();
        let moved = reference_candidates(&m.transformed(&t), v, t.transform_point3(toward), 1.5, 8)
            .unwrap();
        assert_eq!(base, moved);
    }

    #[test]
    fn searched_poles_pair_every_placement_but_the_given_one() {
        let (n, h) = (41, 0.25);
        let m = grid(n, h);
        let solver = geodesic::new_solver(&m, geodesic::Method::Exact).unwrap();
        let opts = SolveOptions::default();
        let (v, w) = ((20 * n + 12) as u32, (20 * n + 28) as u32);
        let field = |x: u32| solver.distances(&[Source::Vertex(x)], &opts).unwrap();
        // The given field is taken as it is (a marker value shows it is not solved again).
        let mut given = field(v);
        given[0] = 123.0;
        let a = SearchedPole::new(&m, solver.as_ref(), v, m.position(w), &given, 1.0, 6, &opts)
            .unwrap();
        let b = SearchedPole::new(
            &m,
            solver.as_ref(),
            w,
            m.position(v),
            &field(w),
            1.0,
            6,
            &opts,
        )
        .unwrap();
        assert_eq!(
            a.vertices,
            reference_candidates(&m, v, m.position(w), 1.0, 6).unwrap()
        );
        assert_eq!(a.fields[0].as_deref(), Some(given.as_slice()));
        for (&x, u) in a.vertices.iter().zip(&a.fields).skip(1) {
            assert_eq!(u.as_deref(), Some(field(x).as_slice()));
        }
        let pairs: Vec<MovedPair<'_>> = moved_pairs(&a, &b).collect();
        assert_eq!(pairs.len(), a.vertices.len() * b.vertices.len() - 1);
        assert_eq!((pairs[0].r, pairs[0].q), (a.vertices[0], b.vertices[1]));
        for p in &pairs {
            // On a plane the exact geodesic distance is the straight one.
            let straight = (m.position(p.r) - m.position(p.q)).length();
            assert!((p.d - straight).abs() < 1e-9, "{} {}", p.d, straight);
            assert_eq!(p.ur[p.q as usize], field(p.r)[p.q as usize]);
        }
        // A failed candidate field leaves out its pairs; a pole without candidates makes none.
        let mut broken = a.clone();
        broken.fields[2] = None;
        assert_eq!(
            moved_pairs(&broken, &b).count(),
            pairs.len() - b.vertices.len()
        );
        assert_eq!(moved_pairs(&SearchedPole::default(), &b).count(), 0);
        // Poles not connected within the cut-off give no pair.
        let short = SolveOptions {
            max_distance: Some(1.5),
        };
        let c = SearchedPole::new(
            &m,
            solver.as_ref(),
            v,
            m.position(w),
            &given,
            1.0,
            6,
            &short,
        )
        .unwrap();
        let far = SearchedPole::new(
            &m,
            solver.as_ref(),
            w,
            m.position(v),
            &given,
            1.0,
            6,
            &short,
        )
        .unwrap();
        assert_eq!(moved_pairs(&c, &far).count(), 0);
    }

    /// A curved, asymmetric height field on a 1-unit grid (on a plane every placement gives the
    /// same scale-free descriptor).
    fn bumpy(n: usize) -> TriMesh {
        let h = 0.5 * (n - 1) as f64;
        meshcore::shapes::grid(
            n - 1,
            n - 1,
            meshcore::shapes::Diagonals::Uniform,
            |i, j| {
                let (x, y) = (i as f64 - h, j as f64 - h);
                DVec3::new(
                    x,
                    y,
                    0.02 * x * x + 0.01 * x * y + 0.03 * y * y + 2e-4 * x * x * x,
                )
            },
        )
        .unwrap()
    }

    #[test]
    fn the_search_describes_the_references_then_each_moved_pair() {
        let n = 41;
        let m = bumpy(n);
        let surface = Surface::new(m.clone());
        let solver = geodesic::new_solver(&m, geodesic::Method::Exact).unwrap();
        let (v, w) = ((20 * n + 10) as u32, (20 * n + 30) as u32);
        let opts = DescriptorOptions {
            max_level: Some(10),
            ..DescriptorOptions::default()
        };
        let refs = [Source::Vertex(v), Source::Vertex(w)];
        let all = describe_searched(&surface, solver.as_ref(), &refs, 2.0, 6, &opts).unwrap();
        let own = crate::describe(
            &surface,
            Fields::Solve {
                solver: solver.as_ref(),
                references: &refs,
            },
            &opts,
        )
        .unwrap();
        assert_eq!(all[0].points, own.points);
        assert!(all.len() > 40 && all.len() <= 49, "{}", all.len());
        // The first moved pair keeps `v` and moves `w` toward `v`; its descriptor is the one
        // described from those two vertices directly (cut fields read the same values).
        let cw = reference_candidates(&m, w, m.position(v), 2.0, 6).unwrap();
        let moved = crate::describe(
            &surface,
            Fields::Solve {
                solver: solver.as_ref(),
                references: &[Source::Vertex(v), Source::Vertex(cw[1])],
            },
            &opts,
        )
        .unwrap();
        assert_eq!(all[1].references, moved.references);
        assert_eq!(all[1].points.len(), moved.points.len());
        for (a, b) in all[1].points.iter().zip(&moved.points) {
            assert_eq!(a.key, b.key);
            assert!((a.position - b.position).length() < 1e-9);
        }
        // Every descriptor differs from the own one: each moved pair has other references.
        assert!(all[1..].iter().all(|d| d.references != own.references));
        // A surface point searches from the nearest corner of its face.
        let face = (0..m.n_faces() as u32)
            .find(|&f| m.triangles()[f as usize].contains(&v))
            .unwrap();
        let k = m.triangles()[face as usize]
            .iter()
            .position(|&c| c == v)
            .unwrap();
        let mut bary = [0.1; 3];
        bary[k] = 0.8;
        let point = Source::Point(meshcore::SurfacePoint::new(face, DVec3::from(bary)));
        let from_point =
            describe_searched(&surface, solver.as_ref(), &[point, refs[1]], 2.0, 6, &opts).unwrap();
        assert_eq!(from_point.len(), all.len());
        assert_eq!(from_point[1].references, all[1].references);
        // Errors: not two references, a bad radius, a reference off the mesh.
        let three = [refs[0], refs[1], Source::Vertex(0)];
        assert!(matches!(
            describe_searched(&surface, solver.as_ref(), &three, 2.0, 6, &opts),
            Err(BipolarError::ReferenceCount(3))
        ));
        assert!(matches!(
            describe_searched(&surface, solver.as_ref(), &refs, 0.0, 6, &opts),
            Err(BipolarError::InvalidOption(_))
        ));
        let off = [refs[0], Source::Vertex(10_000)];
        assert!(describe_searched(&surface, solver.as_ref(), &off, 2.0, 6, &opts).is_err());
    }

    #[test]
    fn the_searched_distance_is_the_least_over_own_and_one_side_moved() {
        // Descriptors stand in as numbers; the distance is their difference, and 100 + x fails.
        let dist = |x: &f64, y: &f64| -> Result<f64, String> {
            if *x >= 100.0 || *y >= 100.0 {
                Err(format!("{x} or {y} failed"))
            } else {
                Ok((x - y).abs())
            }
        };
        let least =
            |a: f64, am: &[f64], b: f64, bm: &[f64]| least_searched_distance(&a, am, &b, bm, dist);
        assert_eq!(least(0.0, &[], 5.0, &[]), Ok(5.0));
        // Each side's moved ones against the other's own: 4 - 5 and 0 - 2.
        assert_eq!(least(0.0, &[4.0, -3.0], 5.0, &[]), Ok(1.0));
        assert_eq!(least(0.0, &[], 5.0, &[2.0, 9.0]), Ok(2.0));
        // Symmetric; moved against moved (4 against 4.5: 0.5) is never compared.
        assert_eq!(least(0.0, &[4.0], 5.0, &[4.5]), Ok(1.0));
        assert_eq!(least(5.0, &[4.5], 0.0, &[4.0]), Ok(1.0));
        assert_eq!(least(0.0, &[3.0], 9.0, &[3.5]), Ok(3.5));
        // Failed distances are skipped; the own pair's error when every one fails.
        assert_eq!(least(0.0, &[100.0, 4.0], 5.0, &[]), Ok(1.0));
        assert_eq!(least(100.0, &[4.0], 5.0, &[]), Ok(1.0));
        assert_eq!(
            least(100.0, &[101.0], 5.0, &[]),
            Err("100 or 5 failed".to_string())
        );
        // NaN distances are skipped too.
        let nan = |x: &f64, y: &f64| -> Result<f64, ()> {
            Ok(if *x < 0.0 { f64::NAN } else { (x - y).abs() })
        };
        assert_eq!(
            least_searched_distance(&0.0, &[-1.0], &5.0, &[], nan),
            Ok(5.0)
        );
        assert!(least_searched_distance(&-1.0, &[], &5.0, &[], nan)
            .unwrap()
            .is_nan());
    }

    #[test]
    fn bad_requests_are_errors() {
        let m = grid(5, 1.0);
        let far = DVec3::new(10.0, 0.0, 0.0);
        assert!(matches!(
            reference_candidates(&m, 99, far, 1.0, 6),
            Err(BipolarError::Mesh(_))
        ));
        for r in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                reference_candidates(&m, 12, far, r, 6),
                Err(BipolarError::InvalidOption(_))
            ));
        }
        assert!(matches!(
            reference_candidates(&m, 12, far, 1.0, 0),
            Err(BipolarError::InvalidOption(_))
        ));
        // Straight above the vertex: no tangent direction.
        let above = m.position(12) + DVec3::Z;
        assert!(matches!(
            reference_candidates(&m, 12, above, 1.0, 6),
            Err(BipolarError::InvalidOption(_))
        ));
    }
}
