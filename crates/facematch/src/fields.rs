//! The landmark fields the descriptions of a face read, each solved no farther than needed.

use crate::{FaceFields, MatchOptions, Poles};
use geodesic::{GeodesicSolver, SolveOptions, Source};
use meshcore::TriMesh;

/// The fields of the landmarks `poles` on `mesh` by `solver` (of `mesh`), cut off at `cutoff`
/// times the corners' straight distance, solved in parallel.
pub fn face_fields(
    mesh: &TriMesh,
    solver: &dyn GeodesicSolver,
    poles: Poles,
    cutoff: f64,
) -> Result<FaceFields, String> {
    let cut = corners_cut(mesh, poles, cutoff)?;
    let lost_right = poles.lost.map(|l| l.right);
    // The three solves are independent: on two threads when rayon has them.
    let ((r, q), n) = rayon::join(
        || {
            rayon::join(
                || field(solver, poles.r, lost_right == Some(true), cut),
                || field(solver, poles.q, lost_right == Some(false), cut),
            )
        },
        || field(solver, poles.nose, false, cut),
    );
    Ok(assemble(poles, r?, q?, n?))
}

/// The fields [`crate::describe`] and the template views read: the outer eye corners' as
/// [`face_fields`] solves them (cut off at `options.field_cutoff` times the corners' straight
/// distance), the nose tip's cut off just past what the side pairs read. A side pair's
/// descriptor reads its fields up to its D (levels up to N at step D / N) plus an edge, and D is
/// at most the farther corner's distance to the nose tip on the corners' fields; with `search`,
/// a moved corner's pair reads up to four search radii farther. So every value a description
/// reads is the one [`face_fields`] gives (an exact solve gives the same value at a vertex
/// within any cut-off beyond it), at about half the nose tip field's cost on a face scan. The
/// corners are solved first (in parallel), then the nose tip; its cut-off is the corners' when
/// neither corner's field reaches the nose tip.
pub fn description_fields(
    mesh: &TriMesh,
    solver: &dyn GeodesicSolver,
    poles: Poles,
    options: &MatchOptions,
    search: bool,
) -> Result<FaceFields, String> {
    let cut = corners_cut(mesh, poles, options.field_cutoff)?;
    let lost_right = poles.lost.map(|l| l.right);
    let (r, q) = rayon::join(
        || field(solver, poles.r, lost_right == Some(true), cut),
        || field(solver, poles.q, lost_right == Some(false), cut),
    );
    let (r, q) = (r?, q?);
    let reach = [&r.0, &q.0]
        .iter()
        .filter_map(|u| u.get(poles.nose as usize).copied())
        .filter(|d| d.is_finite())
        .reduce(f64::max);
    let nose_cut = match reach {
        None => cut,
        Some(d) => {
            let extra = match (search, &options.search) {
                (true, Some(s)) => 4.0 * s.radius_mm,
                _ => 0.0,
            };
            let c = d * (1.0 + 1e-6) + mesh.longest_edge() * (1.0 + 1e-9) + extra;
            c.min(cut)
        }
    };
    let n = field(solver, poles.nose, false, nose_cut)?;
    Ok(assemble(poles, r, q, n))
}

/// The corners' cut-off: `cutoff` times their straight distance; an error when they are one
/// vertex.
fn corners_cut(mesh: &TriMesh, poles: Poles, cutoff: f64) -> Result<f64, String> {
    if poles.lost.is_none() && poles.r == poles.q {
        return Err(format!(
            "the two outer eye corners are the same vertex {}",
            poles.r
        ));
    }
    let [pr, pq, _] = poles.positions(mesh);
    Ok(cutoff * (pq - pr).length())
}

/// The field from `v` cut off at `cut` with its solve's wall time (empty for a lost corner).
fn field(
    solver: &dyn GeodesicSolver,
    v: u32,
    lost: bool,
    cut: f64,
) -> Result<(Vec<f64>, f64), String> {
    if lost {
        return Ok((Vec::new(), 0.0));
    }
    let t = std::time::Instant::now();
    solver
        .distances(
            &[Source::Vertex(v)],
            &SolveOptions {
                max_distance: Some(cut),
            },
        )
        .map(|u| (u, t.elapsed().as_secs_f64()))
        .map_err(|e| format!("geodesic field: {e}"))
}

/// The three fields with D (NaN with a lost corner) and their times.
fn assemble(
    poles: Poles,
    (ur, tr): (Vec<f64>, f64),
    (uq, tq): (Vec<f64>, f64),
    (un, tn): (Vec<f64>, f64),
) -> FaceFields {
    let d = match poles.lost {
        Some(_) => f64::NAN,
        None => 0.5 * (ur[poles.q as usize] + uq[poles.r as usize]),
    };
    FaceFields {
        ur,
        uq,
        un,
        d,
        secs: [tr, tq, tn],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::describe::tests::{left_lost, plane_face};
    use crate::describe_with_fields;
    use meshcore::{DVec3, Surface};

    #[test]
    fn the_descriptions_are_those_of_the_whole_fields() {
        // A 100 x 60 mm sheet (2 mm squares) with its three landmarks.
        let (m, poles, _, _) = plane_face(50, 30, [(5, 20), (45, 20), (25, 5)]);
        let solver = geodesic::new_solver(&m, geodesic::Method::Exact).unwrap();
        let o = MatchOptions {
            levels: 8,
            boundary_margin_mm: None,
            max_incidence_deg: None,
            view: None,
            ..MatchOptions::default()
        };
        let surface = Surface::new(m.clone());
        for (p, search) in [(poles, false), (poles, true), (left_lost(poles, &m), false)] {
            let whole = face_fields(&m, solver.as_ref(), p, o.field_cutoff).unwrap();
            let cut = description_fields(&m, solver.as_ref(), p, &o, search).unwrap();
            assert_eq!((&cut.ur, &cut.uq), (&whole.ur, &whole.uq));
            assert!(cut.d.to_bits() == whole.d.to_bits() || cut.d.is_nan() && whole.d.is_nan());
            // The nose tip's field is cut short, and equal where it is not.
            let reached = |u: &[f64]| u.iter().filter(|x| x.is_finite()).count();
            assert!(reached(&cut.un) < reached(&whole.un), "search {search}");
            assert!(cut
                .un
                .iter()
                .zip(&whole.un)
                .all(|(a, b)| !a.is_finite() || a.to_bits() == b.to_bits()));
            let describe = |f: &FaceFields| {
                describe_with_fields(&surface, solver.as_ref(), f, p, DVec3::Z, None, &o, search)
                    .unwrap()
            };
            let (a, b) = (describe(&cut), describe(&whole));
            assert_eq!(a, b, "search {search}");
            assert!(a.sets.iter().filter(|s| s.is_ok()).count() >= 1);
            if search {
                assert!(a.moved.iter().any(|m| !m.is_empty()));
            }
        }
        // The corners on one vertex are refused, as by face_fields.
        let same = Poles {
            q: poles.r,
            ..poles
        };
        assert!(description_fields(&m, solver.as_ref(), same, &o, false).is_err());
    }
}
