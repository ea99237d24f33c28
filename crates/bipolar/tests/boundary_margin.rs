//! `DescriptorOptions::boundary_margin` and `boundary_band`: the band within a geodesic distance
//! of the mesh boundary is left out of the descriptor, as the range-scan pipeline does next to
//! holes. Oracle: on a plane with a convex hole the geodesic distance from the boundary vertices
//! is the Euclidean distance to the nearest of them.

use bipolar::synthetic::{grid_plane, icosphere};
use bipolar::{
    boundary_band, boundary_band_with, describe, BipolarError, Descriptor, DescriptorOptions,
    Fields, LevelSpec, SelectionRule, Source,
};
use glam::{DAffine3, DQuat, DVec3};
use meshcore::{Surface, Topology, TriMesh};

const HOLE: DVec3 = DVec3::new(0.0, 0.35, 0.0);
const HOLE_R: f64 = 0.25;

/// Plane grid on [-1.5, 1.5]^2 (cell 0.05, jittered) with a round hole above the segment between
/// the references, which sit at the vertices nearest to (-0.5, 0) and (0.5, 0).
fn holed_plane() -> (TriMesh, [u32; 2]) {
    let m = grid_plane(60, 0.05, -1.5, 0.3, 7, |c| (c - HOLE).length() < HOLE_R);
    let near = |p: DVec3| {
        (0..m.n_vertices() as u32)
            .min_by(|&a, &b| {
                (m.position(a) - p)
                    .length()
                    .total_cmp(&(m.position(b) - p).length())
            })
            .unwrap()
    };
    let refs = [
        near(DVec3::new(-0.5, 0.0, 0.0)),
        near(DVec3::new(0.5, 0.0, 0.0)),
    ];
    (m, refs)
}

fn options(margin: Option<f64>) -> DescriptorOptions {
    DescriptorOptions {
        levels: LevelSpec::Step(0.1),
        max_level: Some(12),
        rule: SelectionRule::All,
        boundary_margin: margin,
        ..Default::default()
    }
}

fn describe_exact(
    mesh: &TriMesh,
    refs: [u32; 2],
    opts: &DescriptorOptions,
) -> Result<Descriptor, BipolarError> {
    let solver = geodesic::new_solver(mesh, geodesic::Method::Exact).unwrap();
    describe(
        &Surface::new(mesh.clone()),
        Fields::Solve {
            solver: solver.as_ref(),
            references: &refs.map(Source::Vertex),
        },
        opts,
    )
}

/// Euclidean distance from `p` to the nearest boundary vertex of `mesh`.
fn to_boundary(mesh: &TriMesh, p: DVec3) -> f64 {
    let topo = Topology::new(mesh);
    topo.boundary_loops()
        .iter()
        .flatten()
        .map(|&v| (mesh.position(v) - p).length())
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn band_is_the_distance_to_the_boundary_on_a_plane() {
    let (mesh, _) = holed_plane();
    let margin = 0.2;
    let band = boundary_band(&Surface::new(mesh.clone()), margin).unwrap();
    let mut inside = 0;
    for (v, (&p, &in_band)) in mesh.positions().iter().zip(&band).enumerate() {
        let d = to_boundary(&mesh, p);
        if (d - margin).abs() > 1e-9 {
            assert_eq!(in_band, d < margin, "vertex {v} at {d} from the boundary");
        }
        inside += usize::from(in_band);
    }
    // The band holds the hole's ring and the outer border: neither empty nor everything.
    assert!(
        inside > 100 && inside < mesh.n_vertices() / 2,
        "{inside} band vertices"
    );
}

#[test]
fn margin_leaves_out_the_band_and_keeps_the_rest() {
    let (mesh, refs) = holed_plane();
    let h = 0.05 * 1.5;
    let margin = 0.15;
    let all = describe_exact(&mesh, refs, &options(None)).unwrap();
    let cut = describe_exact(&mesh, refs, &options(Some(margin))).unwrap();
    // Without the margin some points sit right next to the hole (the test can fail).
    let near_hole = |d: &Descriptor| {
        d.points
            .iter()
            .filter(|p| to_boundary(&mesh, p.position) < margin - h)
            .count()
    };
    assert!(
        near_hole(&all) > 0,
        "no point near the hole without the margin"
    );
    assert_eq!(near_hole(&cut), 0, "points left inside the band");
    assert!(cut.len() < all.len() && !cut.is_empty());
    // Away from the band nothing moves: every point of the full descriptor farther than the
    // margin plus a cell from the boundary is in the cut one, same key, same place.
    for p in all
        .points
        .iter()
        .filter(|p| to_boundary(&mesh, p.position) > margin + 2.0 * h)
    {
        let q = cut
            .points
            .iter()
            .find(|q| q.key == p.key && (q.position - p.position).length() < 1e-12);
        assert!(q.is_some(), "point {:?} lost", p.key);
    }
}

#[test]
fn margin_is_invariant_under_rigid_motion() {
    let (mesh, refs) = holed_plane();
    let m = DAffine3::from_rotation_translation(
        DQuat::from_euler(glam::EulerRot::XYZ, 0.4, -1.1, 2.0),
        DVec3::new(3.0, -2.0, 0.5),
    );
    let moved = mesh.transformed(&m);
    let a = describe_exact(&mesh, refs, &options(Some(0.15))).unwrap();
    let b = describe_exact(&moved, refs, &options(Some(0.15))).unwrap();
    assert_eq!(a.len(), b.len());
    for (p, q) in a.points.iter().zip(&b.points) {
        assert_eq!(p.key, q.key);
        assert!((m.transform_point3(p.position) - q.position).length() < 1e-9);
    }
}

#[test]
fn margin_changes_nothing_on_a_closed_surface() {
    let mesh = icosphere(3);
    let refs = [0, 5];
    let opts = |m| DescriptorOptions {
        levels: LevelSpec::Count(8),
        rule: SelectionRule::All,
        boundary_margin: m,
        ..Default::default()
    };
    let a = describe_exact(&mesh, refs, &opts(None)).unwrap();
    let b = describe_exact(&mesh, refs, &opts(Some(0.3))).unwrap();
    assert!(!a.is_empty());
    assert_eq!(a.points, b.points);
}

#[test]
fn bad_margins_are_errors() {
    let (mesh, refs) = holed_plane();
    for m in [f64::NAN, -0.1, f64::INFINITY] {
        let e = describe_exact(&mesh, refs, &options(Some(m))).unwrap_err();
        assert!(
            matches!(&e, BipolarError::InvalidOption(s) if s.contains("boundary margin")),
            "{e}"
        );
        assert!(boundary_band(&Surface::new(mesh.clone()), m).is_err());
    }
}

#[test]
fn margin_is_invariant_under_renumbering() {
    let (mesh, refs) = holed_plane();
    let (renum, perm) = testsupport::renumbered(&mesh);
    let a = describe_exact(&mesh, refs, &options(Some(0.15))).unwrap();
    let b = describe_exact(&renum, refs.map(|r| perm[r as usize]), &options(Some(0.15))).unwrap();
    assert_eq!(a.len(), b.len());
    for p in &a.points {
        assert!(
            b.points
                .iter()
                .any(|q| q.key == p.key && (q.position - p.position).length() < 1e-9),
            "point {:?} not found after renumbering",
            p.key
        );
    }
}

#[test]
fn pinholes_shorter_than_twice_the_margin_get_no_band() {
    let pin = DVec3::new(-0.6, -0.6, 0.0);
    let mesh = grid_plane(60, 0.05, -1.5, 0.3, 7, |c| {
        (c - HOLE).length() < HOLE_R || (c - pin).length() < 0.045
    });
    let topo = Topology::new(&mesh);
    let pinhole = topo
        .boundary_loops()
        .iter()
        .find(|l| l.iter().all(|&v| (mesh.position(v) - pin).length() < 0.2))
        .expect("the pinhole is a boundary loop")
        .clone();
    let p = mesh.ring_length(&pinhole);
    assert!(p > 0.05 && p < 0.49, "pinhole perimeter {p}");
    let surface = Surface::new(mesh.clone());
    // Margin 0.25: the pinhole (perimeter < 0.5) gets no band, the large hole does.
    let band = boundary_band(&surface, 0.25).unwrap();
    assert!(pinhole.iter().all(|&v| !band[v as usize]));
    let rim = topo
        .boundary_loops()
        .iter()
        .find(|l| {
            l.iter()
                .all(|&v| (mesh.position(v) - HOLE).length() < HOLE_R + 0.1)
        })
        .unwrap();
    assert!(rim.iter().all(|&v| band[v as usize]));
    // A margin below half the perimeter bands the pinhole too.
    let small = boundary_band(&surface, 0.4 * p).unwrap();
    assert!(pinhole.iter().all(|&v| small[v as usize]));
    // The caller's exact solver gives the same bands; another method or mesh is refused.
    let exact = geodesic::new_solver(&mesh, geodesic::Method::Exact).unwrap();
    for m in [0.25, 0.4 * p] {
        let with = boundary_band_with(&surface, exact.as_ref(), m).unwrap();
        assert_eq!(with, boundary_band(&surface, m).unwrap(), "margin {m}");
    }
    let fmm = geodesic::new_solver(&mesh, geodesic::Method::Fmm).unwrap();
    assert!(boundary_band_with(&surface, fmm.as_ref(), 0.25).is_err());
    let (other, _) = holed_plane();
    if other.n_vertices() != mesh.n_vertices() {
        let e = geodesic::new_solver(&other, geodesic::Method::Exact).unwrap();
        assert!(boundary_band_with(&surface, e.as_ref(), 0.25).is_err());
    }
}

#[test]
fn the_band_left_out_through_the_vertex_mask_gives_the_same_descriptor() {
    // What the experiments do to build the band once for many descriptors of one surface.
    let (mesh, refs) = holed_plane();
    let margin = 0.15;
    let by_margin = describe_exact(&mesh, refs, &options(Some(margin))).unwrap();
    let band = boundary_band(&Surface::new(mesh.clone()), margin).unwrap();
    let by_mask = describe_exact(
        &mesh,
        refs,
        &DescriptorOptions {
            vertex_mask: Some(band.iter().map(|b| !b).collect()),
            ..options(None)
        },
    )
    .unwrap();
    let all = describe_exact(&mesh, refs, &options(None)).unwrap();
    // The band removes points (else the comparison below would say nothing).
    assert!(by_margin.points.len() < all.points.len());
    assert_eq!(by_mask.points, by_margin.points);
}
