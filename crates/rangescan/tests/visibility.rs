//! `visible_faces` against analytic occlusion and incidence: a plate hovering over a plane casts
//! an exact shadow along the viewing direction, a sphere shows the faces within the incidence
//! limit, and the mask follows rigid motions and renumbering.

use meshcore::{shapes, DMat3, DVec3, TriMesh};
use rangescan::{visible_faces, ScanError};

/// Plane z = 0 over [0, 20]^2 (1 mm cells, jittered interior) plus a plate at z = `HEIGHT` over
/// [8, 12]^2; the plate's faces come after the plane's.
fn plate_over_plane() -> (TriMesh, usize) {
    let plane = shapes::grid_plane(20, 1.0, 0.0, 0.5, 4, |_| false);
    let plate = shapes::grid_plane(4, 1.0, 8.0, 0.0, 0, |_| false);
    let n = plane.n_vertices() as u32;
    let mut pos = plane.positions().to_vec();
    pos.extend(plate.positions().iter().map(|p| *p + DVec3::Z * HEIGHT));
    let mut tris = plane.triangles().to_vec();
    tris.extend(plate.triangles().iter().map(|t| t.map(|v| v + n)));
    (TriMesh::new(pos, tris).unwrap(), plane.n_faces())
}

const HEIGHT: f64 = 5.0;
const PITCH: f64 = 0.25;

/// Signed distance (positive outside) of the shadow of plane point `p` to the plate's footprint
/// along `toward`: the ray from `p` toward the viewer meets z = HEIGHT at `p + t toward`.
fn shadow_outside(p: DVec3, toward: DVec3) -> f64 {
    let q = p + toward * (HEIGHT / toward.z);
    let dx = (q.x - 10.0).abs() - 2.0;
    let dy = (q.y - 10.0).abs() - 2.0;
    dx.max(dy)
}

/// Checks the mask of the plane's faces against the analytic shadow, away from its edge by
/// `margin`; returns how many faces were decided (so a test sees that both kinds occur).
fn check_shadow(mesh: &TriMesh, plane_faces: usize, toward: DVec3, seen: &[bool]) -> [usize; 2] {
    let margin = 2.0 * PITCH;
    let mut n = [0; 2];
    for (f, t) in mesh.triangles()[..plane_faces].iter().enumerate() {
        let out = t.map(|v| shadow_outside(mesh.position(v), toward.normalize()));
        if out.iter().all(|&o| o > margin) {
            assert!(seen[f], "plane face {f} is outside the shadow but not seen");
            n[0] += 1;
        } else if out.iter().any(|&o| o < -margin) {
            assert!(!seen[f], "plane face {f} is in the plate's shadow but seen");
            n[1] += 1;
        }
    }
    n
}

#[test]
fn a_plate_hides_its_shadow_on_the_plane() {
    let (mesh, plane_faces) = plate_over_plane();
    for toward in [
        DVec3::Z,
        DVec3::new(0.5, 0.0, 1.0),
        DVec3::new(-0.3, 0.6, 1.0),
    ] {
        let seen = visible_faces(&mesh, toward, PITCH, 89.0).unwrap();
        let [lit, hidden] = check_shadow(&mesh, plane_faces, toward, &seen);
        assert!(
            lit > 500 && hidden > 10,
            "{toward:?}: {lit} lit, {hidden} hidden"
        );
        assert!(
            seen[plane_faces..].iter().all(|&s| s),
            "the plate is in front of everything"
        );
    }
}

#[test]
fn back_faces_and_grazing_faces_are_not_seen() {
    let (mesh, _) = plate_over_plane();
    assert!(visible_faces(&mesh, -DVec3::Z, PITCH, 90.0)
        .unwrap()
        .iter()
        .all(|&s| !s));
    // Tilted by 60 degrees: seen within a 70 degree limit (shadow aside), none within 50.
    let tilted = DVec3::new(60f64.to_radians().sin(), 0.0, 60f64.to_radians().cos());
    let wide = visible_faces(&mesh, tilted, PITCH, 70.0).unwrap();
    assert!(wide.iter().filter(|&&s| s).count() > mesh.n_faces() / 2);
    assert!(visible_faces(&mesh, tilted, PITCH, 50.0)
        .unwrap()
        .iter()
        .all(|&s| !s));
}

#[test]
fn a_sphere_shows_the_faces_within_the_incidence_limit() {
    let s = shapes::icosphere(4);
    let mesh = TriMesh::new(
        s.positions().iter().map(|p| *p * 30.0).collect(),
        s.triangles().to_vec(),
    )
    .unwrap();
    let toward = DVec3::new(0.2, -0.4, 1.0).normalize();
    for limit in [30.0, 60.0, 85.0] {
        let seen = visible_faces(&mesh, toward, 0.5, limit).unwrap();
        let mut n = 0;
        for (f, t) in mesh.triangles().iter().enumerate() {
            let [a, b, c] = t.map(|v| mesh.position(v));
            let angle = (b - a).cross(c - a).angle_between(toward).to_degrees();
            // A convex surface hides nothing from itself: the incidence alone decides.
            if (angle - limit).abs() > 1e-9 {
                assert_eq!(seen[f], angle < limit, "face {f} at {angle:.3} degrees");
            }
            n += usize::from(seen[f]);
        }
        assert!(n > 0, "limit {limit}: nothing seen");
    }
}

#[test]
fn the_mask_follows_rigid_motions_and_renumbering() {
    let (mesh, plane_faces) = plate_over_plane();
    let toward = DVec3::new(0.5, 0.0, 1.0);
    let rot =
        DMat3::from_rotation_x(0.7) * DMat3::from_rotation_y(-1.1) * DMat3::from_rotation_z(0.4);
    let moved = TriMesh::new(
        mesh.positions()
            .iter()
            .map(|p| rot * *p + DVec3::new(3.0, -40.0, 7.0))
            .collect(),
        mesh.triangles().to_vec(),
    )
    .unwrap();
    let seen = visible_faces(&moved, rot * toward, PITCH, 89.0).unwrap();
    // The moved scene has the shadow of the original one (the analytic check in the frame of
    // the original mesh, whose faces are in the same order).
    let [lit, hidden] = check_shadow(&mesh, plane_faces, toward, &seen);
    assert!(lit > 500 && hidden > 10);
    // Renumbered vertices (`renumbered` lists the faces in reverse order).
    let (renum, _) = testsupport::renumbered(&mesh);
    let mut seen = visible_faces(&renum, toward, PITCH, 89.0).unwrap();
    seen.reverse();
    let [lit, hidden] = check_shadow(&mesh, plane_faces, toward, &seen);
    assert!(lit > 500 && hidden > 10);
}

#[test]
fn bad_requests_are_errors_naming_them() {
    let (mesh, _) = plate_over_plane();
    let bad = |toward: DVec3, pitch: f64, deg: f64, what: &str| match visible_faces(
        &mesh, toward, pitch, deg,
    ) {
        Err(ScanError::InvalidOption(m)) => assert!(m.contains(what), "{m}"),
        other => panic!("{what}: {other:?}"),
    };
    bad(DVec3::ZERO, PITCH, 60.0, "viewing direction");
    bad(
        DVec3::new(f64::NAN, 0.0, 1.0),
        PITCH,
        60.0,
        "viewing direction",
    );
    bad(DVec3::Z, 0.0, 60.0, "pitch");
    bad(DVec3::Z, f64::NAN, 60.0, "pitch");
    bad(DVec3::Z, PITCH, 95.0, "incidence");
    bad(DVec3::Z, PITCH, f64::NAN, "incidence");
    assert!(matches!(
        visible_faces(&mesh, DVec3::Z, 1e-6, 60.0),
        Err(ScanError::GridTooLarge(_))
    ));
}
