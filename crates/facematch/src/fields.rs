//! The landmark fields the descriptions of a face read, each solved no farther than needed.

use crate::{FaceFields, MatchOptions, Poles};
use geodesic::{GeodesicSolver, SolveOptions, Source};
use meshcore::TriMesh;

/// The fields [`crate::describe`] and the template views read: the outer eye corners' as
/// [`crate::face_fields`] solves them (cut off at `options.field_cutoff` times the corners'
/// straight distance), the nose tip's cut off just past what the side pairs read. A side pair's
/// descriptor reads its fields up to its D (levels up to N at step D / N) plus an edge, and D is
/// at most the farther corner's distance to the nose tip on the corners' fields; with `search`,
/// a moved corner's pair reads up to four search radii farther. So every value a description
/// reads is the one [`crate::face_fields`] gives (an exact solve gives the same value at a
/// vertex within any cut-off beyond it), at about half the nose tip field's cost on a face
/// scan. The corners are solved first (in parallel), then the nose tip; its cut-off is the
/// corners' when neither corner's field reaches the nose tip.
pub fn description_fields(
    mesh: &TriMesh,
    solver: &dyn GeodesicSolver,
    poles: Poles,
    options: &MatchOptions,
    search: bool,
) -> Result<FaceFields, String> {
    if poles.lost.is_none() && poles.r == poles.q {
        return Err(format!(
            "the two outer eye corners are the same vertex {}",
            poles.r
        ));
    }
    let [pr, pq, _] = poles.positions(mesh);
    let corners_cut = options.field_cutoff * (pq - pr).length();
    let field = |v: u32, lost: bool, cut: f64| {
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
    };
    let lost_right = poles.lost.map(|l| l.right);
    let (r, q) = rayon::join(
        || field(poles.r, lost_right == Some(true), corners_cut),
        || field(poles.q, lost_right == Some(false), corners_cut),
    );
    let ((ur, tr), (uq, tq)) = (r?, q?);
    let reach = [&ur, &uq]
        .iter()
        .filter_map(|u| u.get(poles.nose as usize).copied())
        .filter(|d| d.is_finite())
        .reduce(f64::max);
    let nose_cut = match reach {
        None => corners_cut,
        Some(d) => {
            let extra = match (search, &options.search) {
                (true, Some(s)) => 4.0 * s.radius_mm,
                _ => 0.0,
            };
            let cut = d * (1.0 + 1e-6) + mesh.longest_edge() * (1.0 + 1e-9) + extra;
            cut.min(corners_cut)
        }
    };
    let (un, tn) = field(poles.nose, false, nose_cut)?;
    let d = match poles.lost {
        Some(_) => f64::NAN,
        None => 0.5 * (ur[poles.q as usize] + uq[poles.r as usize]),
    };
    Ok(FaceFields {
        ur,
        uq,
        un,
        d,
        secs: [tr, tq, tn],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::describe::tests::{left_lost, plane_face};
    use crate::{describe_with_fields, face_fields};
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
