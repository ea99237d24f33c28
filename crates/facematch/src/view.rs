//! View matching: the part of a face a scanner from another direction would measure, and the
//! descriptions of a template's turned views.

use crate::{describe_with_fields, description_fields, KeyedSet, MatchOptions, Poles, ViewOptions};
use meshcore::{DQuat, DVec3, Surface, TriMesh};

/// The vertices of `mesh` seen within `max_incidence_deg` from its own scanner (`scanner`)
/// and, when given, also from another scanner's direction `toward` (both must hold).
pub fn seen_within(
    mesh: &TriMesh,
    scanner: DVec3,
    toward: Option<DVec3>,
    max_incidence_deg: f64,
) -> Result<Vec<bool>, scanprep::ScanPrepError> {
    // One set of smoothed normals for both directions.
    let dirs: Vec<DVec3> = std::iter::once(scanner).chain(toward).collect();
    let masks = scanprep::incidence_masks(mesh, &dirs, max_incidence_deg)?;
    Ok(masks
        .into_iter()
        .reduce(|a, b| a.iter().zip(&b).map(|(a, b)| *a && *b).collect())
        .unwrap_or_default())
}

/// The part of a face that a scanner from another direction would have measured.
#[derive(Debug, Clone)]
pub struct ViewCut {
    /// The faces seen from `toward` (vertices renumbered, unused ones dropped).
    pub mesh: TriMesh,
    /// New index of each vertex of the whole face (`u32::MAX`: dropped).
    pub map: Vec<u32>,
}

/// The faces of `mesh` that a scanner looking from `toward` would measure
/// ([`rangescan::visible_faces`]: z-buffer of `view.pitch_mm`, incidence up to
/// `view.incidence_deg`), or why none are left.
pub fn cut_to_view(mesh: &TriMesh, toward: DVec3, view: &ViewOptions) -> Result<ViewCut, String> {
    let seen = rangescan::visible_faces(mesh, toward, view.pitch_mm, view.incidence_deg)
        .map_err(|e| format!("visible faces: {e}"))?;
    let tris = mesh
        .triangles()
        .iter()
        .zip(&seen)
        .filter(|(_, &s)| s)
        .map(|(t, _)| *t)
        .collect();
    let (mesh, map) =
        scanprep::compact(mesh.positions(), tris, "view matching").map_err(|e| e.to_string())?;
    Ok(ViewCut { mesh, map })
}

/// The vertex of `mesh` nearest to `p` and its distance (lowest index on ties).
pub fn nearest_vertex(mesh: &TriMesh, p: DVec3) -> Option<(u32, f64)> {
    mesh.positions()
        .iter()
        .enumerate()
        .map(|(i, q)| (i as u32, (*q - p).length_squared()))
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
        .map(|(i, d2)| (i, d2.sqrt()))
}

/// A probe's scanner direction `probe_scanner` carried into a template's frame by the rigid
/// fit of the probe's landmarks `probe` onto the template's `template` (right and left outer
/// eye corners, nose tip); `None` when the fit fails.
pub fn probe_direction(
    probe: &[DVec3; 3],
    probe_scanner: DVec3,
    template: &[DVec3; 3],
) -> Option<DVec3> {
    let fit = meshcore::linalg::fit_rigid(probe, template, None)?;
    let t = (fit.matrix3 * probe_scanner).normalize_or_zero();
    (t != DVec3::ZERO).then_some(t)
}

/// The turned scanner directions of a template's views: `scanner` turned by each of `yaws`
/// (degrees) to both sides about the face's vertical axis (perpendicular to the scanner and
/// the eye line `r` to `q`), in the order +y1, -y1, +y2, -y2, ...
pub fn view_directions(scanner: DVec3, r: DVec3, q: DVec3, yaws: &[f64]) -> Vec<(f64, DVec3)> {
    let s = scanner.normalize_or_zero();
    let axis = s.cross((q - r).normalize_or_zero()).normalize_or_zero();
    if axis == DVec3::ZERO {
        return Vec::new();
    }
    yaws.iter()
        .flat_map(|&y| [y, -y])
        .map(|y| (y, DQuat::from_axis_angle(axis, y.to_radians()) * s))
        .collect()
}

/// The descriptor of each pair of the face `mesh` (landmarks `poles`, own scanner `scanner`)
/// as a scanner from `toward` would have measured it: the cut ([`cut_to_view`]), its own fields
/// and boundary band, the vertices seen within the incidence limit from both directions. A
/// landmark whose faces are all gone is placed at the nearest vertex left within
/// `options.snap_mm`. Errors say why no description could be made; a pair that fails is its
/// error.
pub fn describe_view(
    mesh: &TriMesh,
    poles: Poles,
    scanner: DVec3,
    toward: DVec3,
    options: &MatchOptions,
    view: &ViewOptions,
) -> Result<[Result<KeyedSet, String>; 3], String> {
    let ViewCut { mesh: cut, map } = cut_to_view(mesh, toward, view)?;
    let lm = poles
        .carried(mesh, &cut, &map, options.snap_mm)
        .ok_or("a landmark is not on the view")?;
    let solver = geodesic::new_solver(&cut, options.method).map_err(|e| e.to_string())?;
    let f = description_fields(&cut, solver.as_ref(), lm, options, false)?;
    let surface = Surface::new(cut);
    let d = describe_with_fields(
        &surface,
        solver.as_ref(),
        &f,
        lm,
        scanner,
        Some(toward),
        options,
        false,
    )
    .map_err(|e| e.to_string())?;
    Ok(d.sets)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::describe::tests::{left_lost, plane_face};
    use crate::Pair;

    #[test]
    fn views_turn_about_the_vertical_axis_to_both_sides() {
        let v = view_directions(DVec3::Z, -DVec3::X, DVec3::X, &[30.0]);
        assert_eq!(v.len(), 2);
        for (yaw, d) in v {
            assert!((d.length() - 1.0).abs() < 1e-12);
            assert!((d.angle_between(DVec3::Z).to_degrees() - 30.0).abs() < 1e-9);
            assert!(d.y.abs() < 1e-12, "turned about the vertical axis");
            assert_eq!(d.x.signum(), yaw.signum());
        }
        // A degenerate eye line along the scanner gives no views.
        assert!(view_directions(DVec3::Z, DVec3::ZERO, DVec3::Z, &[30.0]).is_empty());
    }

    #[test]
    fn a_probe_direction_follows_the_landmark_fit() {
        let lm = [
            DVec3::new(-5.0, 0.0, 0.0),
            DVec3::new(5.0, 0.0, 0.0),
            DVec3::new(0.0, -4.0, 2.0),
        ];
        let rot = DQuat::from_rotation_y(0.4);
        let moved = lm.map(|p| rot * p + DVec3::new(3.0, 1.0, 0.0));
        let t = probe_direction(&moved, DVec3::Z, &lm).unwrap();
        assert!((t - rot.inverse() * DVec3::Z).length() < 1e-9);
    }

    #[test]
    fn a_view_keeps_a_face_with_a_lost_corner() {
        // A 100 x 60 mm sheet (2 mm squares), seen turned 30 degrees about the vertical.
        let (m, poles, _, _) = plane_face(50, 30, [(5, 20), (45, 20), (25, 5)]);
        let o = MatchOptions {
            levels: 8,
            boundary_margin_mm: None,
            max_incidence_deg: None,
            search: None,
            view: None,
            ..MatchOptions::default()
        };
        let v = ViewOptions::default();
        let toward = DQuat::from_rotation_y(-30f64.to_radians()) * DVec3::Z;
        let whole = describe_view(&m, poles, DVec3::Z, toward, &o, &v).unwrap();
        assert!(whole.iter().all(Result::is_ok), "{whole:?}");
        // The left corner lost at its true place: the cut is the same and so is the right side
        // pair's descriptor (its frame from the lost corner's place); no other pair.
        let cut = describe_view(&m, left_lost(poles, &m), DVec3::Z, toward, &o, &v).unwrap();
        let (corners, left, right) = (
            Pair::Corners as usize,
            Pair::LeftNose as usize,
            Pair::RightNose as usize,
        );
        assert!(cut[corners].is_err() && cut[left].is_err());
        assert_eq!(cut[right], whole[right]);
        assert!(!cut[right].as_ref().unwrap().points.is_empty());
    }
}
