//! The bipolar descriptions of a face: the three pole pairs on the static area, without the
//! boundary band and the grazing parts, and the reference-point search's moved descriptors.

use crate::area::{grid_rule, Area, PoleRefs};
use crate::{KeyedSet, MatchOptions, Pair, Poles};
use facemodel::{face_frame, FaceFrame};
use geodesic::{GeodesicSolver, SolveOptions};
use meshcore::{DVec3, Surface, TriMesh};

/// The geodesic fields of a face's landmarks, cut off at `MatchOptions::field_cutoff` times the
/// outer eye corners' distance. A lost corner has no field (an empty vector).
#[derive(Debug, Clone)]
pub struct FaceFields {
    /// From the right outer eye corner.
    pub ur: Vec<f64>,
    /// From the left outer eye corner.
    pub uq: Vec<f64>,
    /// From the nose tip.
    pub un: Vec<f64>,
    /// D: the geodesic distance between the outer eye corners (mean of the two fields' values;
    /// NaN with a lost corner).
    pub d: f64,
    /// Wall time (s) of each field's solve: right corner, left corner, nose tip (0 for a lost
    /// corner), for benchmarks that report a description's cost.
    pub secs: [f64; 3],
}

impl FaceFields {
    /// D, or why there is none (a lost corner; the corners not connected within the cut-off).
    pub fn scale(&self, poles: Poles) -> Result<f64, String> {
        if poles.lost.is_some() {
            return Err("an outer eye corner is not on the surface".into());
        }
        let d = self.d;
        if !d.is_finite() || d <= 0.0 {
            return Err(format!(
                "the geodesic distance between the outer eye corners is {d} (not reachable within 1.4 times their distance)"
            ));
        }
        Ok(d)
    }

    /// The two fields of `pair`, in the places of r and q (empty for a lost corner).
    fn of_pair(&self, pair: Pair) -> (&[f64], &[f64]) {
        match pair {
            Pair::Corners => (&self.ur, &self.uq),
            Pair::RightNose => (&self.ur, &self.un),
            Pair::LeftNose => (&self.uq, &self.un),
        }
    }
}

/// The reference fields of `pair`: the poles stand in r and q, D is their geodesic distance.
/// The frame and the nose tip stay the landmarks' own for every pair, so the static area of a
/// side pair is its lens above the nose tip's horizontal plane.
fn pair_refs(
    mesh: &TriMesh,
    f: &FaceFields,
    poles: Poles,
    pair: Pair,
    frame: FaceFrame,
) -> Result<PoleRefs, String> {
    let (ua, ub) = f.of_pair(pair);
    if ua.is_empty() || ub.is_empty() {
        return Err(format!(
            "{pair:?}: a pole has no geodesic field (an outer eye corner not on the surface)"
        ));
    }
    let (a, b) = poles.pole_vertices(pair);
    let d = match pair {
        Pair::Corners => f.scale(poles)?,
        _ => 0.5 * (ua[b as usize] + ub[a as usize]),
    };
    if !(d.is_finite() && d > 0.0) {
        return Err(format!(
            "{pair:?}: the geodesic distance between the poles is {d} (not reachable within the fields' cut-off)"
        ));
    }
    let [_, _, nose] = poles.positions(mesh);
    Ok(PoleRefs {
        ur: ua.to_vec(),
        uq: ub.to_vec(),
        d,
        r: mesh.position(a),
        q: mesh.position(b),
        nose,
        frame,
    })
}

/// The vertices the descriptors of `surface` may use: those of `seen` (all without it) outside
/// the band of `margin` along the boundary ([`bipolar::boundary_band`], solved by `solver` when
/// it is an exact solver of the surface's mesh, else by a new one). For many descriptors of
/// one surface, pass this as their vertex mask with no `boundary_margin`:
/// `DescriptorOptions::boundary_margin` builds the band again (an exact solve from the
/// boundary) on every call, and the two leave out the same vertices.
pub fn kept_vertices(
    surface: &Surface,
    solver: Option<&dyn GeodesicSolver>,
    seen: Option<Vec<bool>>,
    margin: Option<f64>,
) -> Result<Option<Vec<bool>>, bipolar::BipolarError> {
    let Some(m) = margin else {
        return Ok(seen);
    };
    let band = match solver {
        Some(s) if s.method() == geodesic::Method::Exact => {
            bipolar::boundary_band_with(surface, s, m)?
        }
        _ => bipolar::boundary_band(surface, m)?,
    };
    Ok(Some(match seen {
        Some(s) => band.iter().zip(&s).map(|(&b, &s)| !b && s).collect(),
        None => band.iter().map(|&b| !b).collect(),
    }))
}

/// The bipolar descriptions of one face.
#[derive(Debug, Clone, PartialEq)]
pub struct Description {
    /// Per [`Pair`] (indexed by its discriminant): the descriptor's keyed points, or why it
    /// could not be built.
    pub sets: [Result<KeyedSet, String>; 3],
    /// Per pair: the descriptors from the moved poles of the reference-point search (empty
    /// without a search, or for a pair not searched).
    pub moved: [Vec<KeyedSet>; 3],
    /// Per pair: moved pole pairs whose fields or descriptor failed (left out, counted).
    pub moved_failed: [usize; 3],
    /// The pair this face is compared by as a probe ([`Pair::for_probe`]).
    pub pair: Pair,
    /// The landmarks' positions: right and left outer eye corners, nose tip (a lost corner at
    /// its place).
    pub landmarks: [DVec3; 3],
    /// The lost outer corner, if any.
    pub lost: Option<crate::Lost>,
    /// The direction toward the scanner (the mesh's frame).
    pub scanner: DVec3,
}

/// [`describe_with_fields`] after solving the fields ([`crate::description_fields`]) with a new
/// solver of `options.method`.
pub fn describe(
    mesh: &TriMesh,
    poles: Poles,
    scanner: DVec3,
    options: &MatchOptions,
    search: bool,
) -> Result<Description, crate::MatchError> {
    let solver = geodesic::new_solver(mesh, options.method)?;
    let f = crate::description_fields(mesh, solver.as_ref(), poles, options, search)
        .map_err(crate::MatchError::Describe)?;
    let surface = Surface::new(mesh.clone());
    describe_with_fields(
        &surface,
        solver.as_ref(),
        &f,
        poles,
        scanner,
        None,
        options,
        search,
    )
}

/// The descriptions of a face on `surface` with its fields `f` (by `solver`, of the same mesh):
/// each pair's static descriptor on the vertices seen within `options.max_incidence_deg` from
/// `scanner` (and, when given, from `also_toward`: a view-matched cut) outside the boundary
/// band, and with `search` the reference-point search's moved descriptors. A descriptor that
/// cannot be built is kept as its error; the call fails only when the vertex mask does.
#[allow(clippy::too_many_arguments)]
pub fn describe_with_fields(
    surface: &Surface,
    solver: &dyn GeodesicSolver,
    f: &FaceFields,
    poles: Poles,
    scanner: DVec3,
    also_toward: Option<DVec3>,
    options: &MatchOptions,
    search: bool,
) -> Result<Description, crate::MatchError> {
    let mesh = surface.mesh();
    let [r, q, nose] = poles.positions(mesh);
    let frame = face_frame(mesh, r, q, nose);
    let seen = match options.max_incidence_deg {
        Some(deg) => Some(
            crate::seen_within(mesh, scanner, also_toward, deg)
                .map_err(|e| crate::MatchError::Describe(format!("incidence mask: {e}")))?,
        ),
        None => None,
    };
    let pair = Pair::for_probe(r, q, scanner, options.side_pair_deg, poles.lost);
    let kept = kept_vertices(surface, Some(solver), seen, options.boundary_margin_mm)
        .map_err(|e| crate::MatchError::Describe(format!("boundary band: {e}")))?;
    let refs = Pair::ALL.map(|p| pair_refs(mesh, f, poles, p, frame));
    let sets = Pair::ALL.map(|p| {
        let refs = refs[p as usize].as_ref().map_err(Clone::clone)?;
        refs.descriptor(
            surface,
            options.levels,
            Area::Static,
            kept.as_deref(),
            grid_rule(),
        )
        .map(|d| KeyedSet::of(&d))
        .map_err(|e| format!("bipolar descriptor: {e}"))
    });
    let (moved, moved_failed) = match (search, &options.search) {
        (true, Some(s)) => {
            let all = options.least_pair && s.all_pairs;
            let searched = Pair::ALL.map(|p| p == pair || all);
            moved_descriptors(
                surface,
                solver,
                poles,
                &refs,
                searched,
                all,
                s,
                options,
                kept.as_deref(),
            )
        }
        _ => Default::default(),
    };
    Ok(Description {
        sets,
        moved,
        moved_failed,
        pair,
        landmarks: [r, q, nose],
        lost: poles.lost,
        scanner,
    })
}

/// A searched pole's identity: the landmark (0 r, 1 q, 2 nose tip) and the bits of the point
/// its first direction points toward.
type PoleKey = (usize, [u64; 3]);

/// The moved descriptors per pair: the poles of each pair in `searched` (with reference fields
/// `refs`; a pair whose `refs` failed is left empty) moved by the search radius in its
/// directions of their tangent planes ([`bipolar::SearchedPole`], paired by
/// [`bipolar::moved_pairs`]: each pole at its place or moved, 48 pairs with 6 directions).
/// The first direction of a pole points toward the pair's other pole, or, with `shared`, the
/// same for every pair: an outer eye corner toward the other, the nose tip toward their
/// midpoint, so that each landmark's moved fields are solved once for all pairs. Moved corners
/// get the frame of their new eye line; a side pair keeps the landmarks' frame. Also the count
/// of moved pairs left out per pair (a failed candidate set, field or descriptor).
#[allow(clippy::too_many_arguments)]
fn moved_descriptors(
    surface: &Surface,
    solver: &dyn GeodesicSolver,
    poles: Poles,
    refs: &[Result<PoleRefs, String>; 3],
    searched: [bool; 3],
    shared: bool,
    s: &crate::SearchOptions,
    o: &MatchOptions,
    kept: Option<&[bool]>,
) -> ([Vec<KeyedSet>; 3], [usize; 3]) {
    let mut out: [Vec<KeyedSet>; 3] = Default::default();
    let mut failed = [0usize; 3];
    let mesh = surface.mesh();
    let search: Vec<(Pair, &PoleRefs)> = Pair::ALL
        .into_iter()
        .filter(|p| searched[*p as usize])
        .filter_map(|p| refs[p as usize].as_ref().ok().map(|r| (p, r)))
        .collect();
    let Some(span) = search
        .iter()
        .map(|(_, r)| (r.q - r.r).length())
        .reduce(f64::max)
    else {
        return (out, failed);
    };
    let rho = s.radius_mm;
    let cut = SolveOptions {
        max_distance: Some(o.field_cutoff * span + 4.0 * rho),
    };
    let lm_vertex = [poles.r, poles.q, poles.nose];
    let [pr, pq, _] = poles.positions(mesh);
    // A landmark's searched pole, by (landmark, the point its first direction points toward);
    // the given pole keeps its field, each moved one is solved. `None`: no candidates.
    let mut cache: Vec<(PoleKey, Option<bipolar::SearchedPole>)> = Vec::new();
    let mut moved = |k: usize, toward: DVec3, given: &[f64]| -> usize {
        let key = (k, toward.to_array().map(f64::to_bits));
        if let Some(i) = cache.iter().position(|(c, _)| *c == key) {
            return i;
        }
        let pole = bipolar::SearchedPole::new(
            mesh,
            solver,
            lm_vertex[k],
            toward,
            given,
            rho,
            s.directions,
            &cut,
        )
        .ok();
        cache.push((key, pole));
        cache.len() - 1
    };
    let toward = |k: usize, other: DVec3| match (shared, k) {
        (false, _) => other,
        (true, 0) => pq,
        (true, 1) => pr,
        (true, _) => 0.5 * (pr + pq),
    };
    let jobs: Vec<(Pair, &PoleRefs, usize, usize)> = search
        .into_iter()
        .map(|(pair, refs)| {
            let (ka, kb) = match pair {
                Pair::Corners => (0, 1),
                Pair::RightNose => (0, 2),
                Pair::LeftNose => (1, 2),
            };
            let ia = moved(ka, toward(ka, refs.q), &refs.ur);
            let ib = moved(kb, toward(kb, refs.r), &refs.uq);
            (pair, refs, ia, ib)
        })
        .collect();
    for (pair, refs, ia, ib) in jobs {
        let (Some(a), Some(b)) = (&cache[ia].1, &cache[ib].1) else {
            // No candidates: the pairs a full search would make are all missing.
            failed[pair as usize] += (s.directions + 1) * (s.directions + 1) - 1;
            continue;
        };
        // Every candidate of one pole with every one of the other but the given ones together.
        let expected = a.vertices.len() * b.vertices.len() - 1;
        let mut built = 0;
        for m in bipolar::moved_pairs(a, b) {
            let (pa, pb) = (mesh.position(m.r), mesh.position(m.q));
            let moved = PoleRefs {
                ur: m.ur.to_vec(),
                uq: m.uq.to_vec(),
                d: m.d,
                r: pa,
                q: pb,
                nose: refs.nose,
                frame: match pair {
                    Pair::Corners => face_frame(mesh, pa, pb, refs.nose),
                    _ => refs.frame,
                },
            };
            if let Ok(d) = moved.descriptor(surface, o.levels, Area::Static, kept, grid_rule()) {
                out[pair as usize].push(KeyedSet::of(&d));
                built += 1;
            }
        }
        failed[pair as usize] += expected.saturating_sub(built);
    }
    (out, failed)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use geodesic::{GeodesicSolver, Source};

    /// A flat sheet of `nx` x `ny` squares of 2 mm, its landmarks at the grid points `at` (r, q,
    /// nose tip), its exact solver and the landmarks' fields.
    pub(crate) fn plane_face(
        nx: usize,
        ny: usize,
        at: [(u32, u32); 3],
    ) -> (TriMesh, Poles, Box<dyn GeodesicSolver>, FaceFields) {
        let m = meshcore::shapes::grid(nx, ny, meshcore::shapes::Diagonals::Alternating, |i, j| {
            DVec3::new(2.0 * i as f64, 2.0 * j as f64, 0.0)
        })
        .unwrap();
        let [r, q, nose] = at.map(|(i, j)| j * (nx as u32 + 1) + i);
        let poles = Poles::new(r, q, nose);
        let solver = geodesic::new_solver(&m, geodesic::Method::Exact).unwrap();
        let f = crate::face_fields(&m, solver.as_ref(), poles, 1.4).unwrap();
        (m, poles, solver, f)
    }

    /// `poles` with the left outer corner lost at its place on `m` (its vertex replaced by the
    /// nose tip's).
    pub(crate) fn left_lost(poles: Poles, m: &TriMesh) -> Poles {
        let [_, q, _] = poles.positions(m);
        Poles {
            q: poles.nose,
            lost: Some(crate::Lost {
                right: false,
                position: q,
            }),
            ..poles
        }
    }

    #[test]
    fn kept_vertices_leave_out_the_band_along_the_border_and_the_unseen() {
        // A 20 x 20 sheet of 2 mm squares: a 5 mm band takes the outer two rings of vertices.
        let (m, ..) = plane_face(20, 20, [(5, 10), (15, 10), (10, 5)]);
        let surface = Surface::new(m);
        let n = surface.mesh().n_vertices();
        assert_eq!(kept_vertices(&surface, None, None, None).unwrap(), None);
        let kept = kept_vertices(&surface, None, None, Some(5.0))
            .unwrap()
            .unwrap();
        let at = |i: usize, j: usize| kept[j * 21 + i];
        assert!(!at(0, 10) && !at(2, 10) && at(3, 10) && at(10, 10) && !at(20, 20));
        // The caller's exact solver gives the same band; another method is not used for it.
        for method in [geodesic::Method::Exact, geodesic::Method::Fmm] {
            let s = geodesic::new_solver(surface.mesh(), method).unwrap();
            let by = kept_vertices(&surface, Some(s.as_ref()), None, Some(5.0)).unwrap();
            assert_eq!(by.as_deref(), Some(&kept[..]), "{method:?}");
        }
        // The seen mask is kept as it is without a margin and joined with the band's.
        let seen: Vec<bool> = (0..n).map(|v| v % 2 == 0).collect();
        let only_seen = kept_vertices(&surface, None, Some(seen.clone()), None).unwrap();
        assert_eq!(only_seen.as_deref(), Some(&seen[..]));
        let both = kept_vertices(&surface, None, Some(seen.clone()), Some(5.0))
            .unwrap()
            .unwrap();
        assert!((0..n).all(|v| both[v] == (kept[v] && seen[v])));
    }

    /// A solver that counts the fields it solves.
    #[derive(Debug)]
    struct Counting<'a>(&'a dyn GeodesicSolver, std::sync::atomic::AtomicUsize);

    impl GeodesicSolver for Counting<'_> {
        fn method(&self) -> geodesic::Method {
            self.0.method()
        }
        fn n_vertices(&self) -> usize {
            self.0.n_vertices()
        }
        fn distances(
            &self,
            sources: &[Source],
            opts: &SolveOptions,
        ) -> Result<Vec<f64>, geodesic::GeodesicError> {
            self.1.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            self.0.distances(sources, opts)
        }
    }

    /// The options of the sheet tests: 8 levels, the least over the three pairs, nothing else.
    fn sheet_options(search: Option<crate::SearchOptions>) -> MatchOptions {
        MatchOptions {
            levels: 8,
            boundary_margin_mm: None,
            max_incidence_deg: None,
            side_pair_deg: None,
            search,
            view: None,
            ..MatchOptions::default()
        }
    }

    #[test]
    fn the_search_moves_the_pairs_asked_for_and_solves_each_moved_pole_once() {
        // An 80 x 50 mm sheet; poles moved by 4 mm (distinct vertices).
        let (m, poles, exact, f) = plane_face(40, 25, [(8, 16), (32, 16), (20, 6)]);
        let surface = Surface::new(m.clone());
        let run = |all_pairs: bool| {
            let o = sheet_options(Some(crate::SearchOptions {
                radius_mm: 4.0,
                directions: 6,
                all_pairs,
            }));
            let solver = Counting(exact.as_ref(), Default::default());
            let d = describe_with_fields(&surface, &solver, &f, poles, DVec3::Z, None, &o, true)
                .unwrap();
            assert_eq!(d.moved_failed, [0; 3]);
            (d.moved.map(|v| v.len()), solver.1.into_inner())
        };
        // The probe's own pair (the corners) alone: 7 x 7 - 1 pole pairs, 6 moved fields per
        // pole.
        assert_eq!(run(false), ([48, 0, 0], 12));
        // Every pair with shared candidates: 6 moved fields per landmark, 18.
        assert_eq!(run(true), ([48; 3], 18));
        // No search: nothing moved, nothing solved.
        let solver = Counting(exact.as_ref(), Default::default());
        let d = describe_with_fields(
            &surface,
            &solver,
            &f,
            poles,
            DVec3::Z,
            None,
            &sheet_options(None),
            true,
        )
        .unwrap();
        assert!(d.moved.iter().all(Vec::is_empty));
        assert_eq!(solver.1.into_inner(), 0);
    }

    #[test]
    fn side_pairs_on_a_plane() {
        // A 100 x 60 mm sheet: geodesic distance = straight distance.
        let (m, poles, solver, f) = plane_face(50, 30, [(5, 20), (45, 20), (25, 5)]);
        let [r, q, nose] = poles.positions(&m);
        let frame = face_frame(&m, r, q, nose);
        let corners = pair_refs(&m, &f, poles, Pair::Corners, frame).unwrap();
        assert!((corners.d - 80.0).abs() < 1e-9, "{}", corners.d);
        for (pair, corner) in [(Pair::RightNose, r), (Pair::LeftNose, q)] {
            let side = pair_refs(&m, &f, poles, pair, frame).unwrap();
            assert!((side.d - (corner - nose).length()).abs() < 1e-9, "{pair:?}");
            assert_eq!((side.r, side.q, side.nose), (corner, nose, nose));
            // The frame stays the landmarks' own.
            assert_eq!(side.frame, frame);
        }
        // The left corner lost: its true place still sets the frame; only the right pair.
        let lost = left_lost(poles, &m);
        assert_eq!(lost.positions(&m), [r, q, nose]);
        let f = crate::face_fields(&m, solver.as_ref(), lost, 1.4).unwrap();
        assert!(f.uq.is_empty() && f.scale(lost).is_err());
        assert!(pair_refs(&m, &f, lost, Pair::Corners, frame).is_err());
        assert!(pair_refs(&m, &f, lost, Pair::LeftNose, frame).is_err());
        let side = pair_refs(&m, &f, lost, Pair::RightNose, frame).unwrap();
        assert!((side.d - (r - nose).length()).abs() < 1e-9);
    }
}
