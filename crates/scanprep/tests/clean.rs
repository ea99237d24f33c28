//! Scan preparation on planted artifacts: scans of analytic shapes from `rangescan` with
//! spikes and holes whose positions are known, crops, decimation, bad input, units.

use mesh_io::{BntGrid, BntOptions};
use meshcore::units::{detect_units, Units};
use meshcore::{shapes, DVec3, TriMesh};
use rangescan::{scan, Artifacts, HeadPose, ScanOptions, Spikes};
use scanprep::{
    check_grid, clean, clean_uncropped, close_mesh_gaps, crop_sphere, decimate, fill_grid_holes,
    fill_mesh_holes, incidence_mask, incidence_masks, remove_grid_spikes, remove_mesh_spikes,
    surviving_vertices, CleanOptions, Crop, Input, ScanPrepError, SpikeOptions,
};

/// The plane z = 5 over [0, 60]^2 mm.
fn plane() -> TriMesh {
    let g = shapes::grid_plane(30, 2.0, 0.0, 0.0, 1, |_| false);
    TriMesh::new(
        g.positions()
            .iter()
            .map(|p| DVec3::new(p.x, p.y, 5.0))
            .collect(),
        g.triangles().to_vec(),
    )
    .unwrap()
}

const R: f64 = 60.0;

/// A sphere of radius `R` mm about the origin.
fn sphere() -> TriMesh {
    let s = shapes::icosphere(6);
    TriMesh::new(
        s.positions().iter().map(|p| *p * R).collect(),
        s.triangles().to_vec(),
    )
    .unwrap()
}

fn scan_of(mesh: &TriMesh, artifacts: Artifacts) -> BntGrid {
    let o = ScanOptions {
        artifacts,
        seed: 7,
        ..ScanOptions::default()
    };
    scan(mesh, &o).unwrap().grid
}

fn spiky() -> Artifacts {
    Artifacts {
        spikes: Some(Spikes {
            fraction: 0.01,
            min_mm: 2.0,
            max_mm: 10.0,
        }),
        ..Artifacts::none()
    }
}

/// Planted spikes: those samples that differ between the clean and the spiky scan.
fn check_spikes_removed(mesh: &TriMesh, max_false: f64) {
    let clean_grid = scan_of(mesh, Artifacts::none());
    let mut g = scan_of(mesh, spiky());
    let n = g.xyz.len();
    let planted: Vec<bool> = (0..n).map(|i| g.xyz[i] != clean_grid.xyz[i]).collect();
    let n_planted = planted.iter().filter(|&&p| p).count();
    let n_valid = (0..n).filter(|&i| g.is_valid(i)).count();
    assert!(n_planted > 50, "{n_planted}");
    let before = g.clone();
    let counts = remove_grid_spikes(&mut g, &SpikeOptions::default()).unwrap();
    let mut caught = 0;
    let mut false_removed = 0;
    for (i, &planted_i) in planted.iter().enumerate() {
        if g.is_valid(i) {
            // Kept samples are unchanged.
            assert_eq!(g.xyz[i], before.xyz[i]);
        } else if before.is_valid(i) {
            if planted_i {
                caught += 1;
            } else {
                false_removed += 1;
            }
        }
    }
    assert_eq!(counts.spikes + counts.isolated, caught + false_removed);
    assert!(
        caught as f64 >= 0.97 * n_planted as f64,
        "{caught} of {n_planted} spikes removed"
    );
    assert!(
        (false_removed as f64) <= max_false * n_valid as f64,
        "{false_removed} of {n_valid} good samples removed"
    );
}

#[test]
fn spikes_on_a_plane_are_removed_and_the_rest_kept() {
    check_spikes_removed(&plane(), 0.001);
}

#[test]
fn spikes_on_a_sphere_are_removed_and_the_rest_kept() {
    // The rim, seen at grazing angles, may lose a few samples.
    check_spikes_removed(&sphere(), 0.01);
}

/// Samples of `g` within `radius` (in x, y) of `c` set to background; returns their indices.
fn punch(g: &mut BntGrid, c: (f64, f64), radius: f64) -> Vec<usize> {
    let mut out = Vec::new();
    for i in 0..g.xyz.len() {
        let p = g.xyz[i];
        if g.is_valid(i) && (p.x - c.0).hypot(p.y - c.1) <= radius {
            g.xyz[i] = DVec3::splat(g.zmin);
            out.push(i);
        }
    }
    out
}

#[test]
fn small_holes_are_filled_on_the_sphere_and_a_big_one_is_reported() {
    let orig = scan_of(&sphere(), Artifacts::none());
    let mut g = orig.clone();
    let small = [(0.0, 0.0), (20.0, 10.0), (-15.0, -25.0)];
    let mut punched = Vec::new();
    for c in small {
        punched.extend(punch(&mut g, c, 2.0));
    }
    let big = punch(&mut g, (10.0, -30.0), 12.0);
    let holes = fill_grid_holes(&mut g, 10.0).unwrap();
    assert_eq!(holes.len(), 4, "{holes:?}");
    assert_eq!(holes.iter().filter(|h| h.filled).count(), 3);
    let left: Vec<_> = holes.iter().filter(|h| !h.filled).collect();
    // The tilted surface makes the 24 mm disc (in x, y) longer on the sphere.
    let mut far = 0.0f64;
    for &i in &big {
        for &j in &big {
            far = far.max(orig.xyz[i].distance(orig.xyz[j]));
        }
    }
    assert!(far > 24.0);
    assert!(
        left[0].diameter_mm > far && left[0].diameter_mm < far + 1.5,
        "{left:?} {far}"
    );
    assert_eq!(left[0].size, big.len());
    for &i in &big {
        assert!(!g.is_valid(i));
    }
    for &i in &punched {
        let p = g.xyz[i];
        assert!(g.is_valid(i));
        // On the sphere (the icosphere is within 3e-3 mm of it), and at the sample's own grid
        // position.
        assert!((p.length() - R).abs() < 5e-3, "{p:?}: {}", p.length() - R);
        assert!((p.z - orig.xyz[i].z).abs() < 5e-3);
        assert!((p.x - orig.xyz[i].x).abs() < 1e-9 && (p.y - orig.xyz[i].y).abs() < 1e-9);
        assert!((g.uv[i][0] - orig.uv[i][0]).abs() < 1e-9);
    }
    // The rest of the grid is untouched.
    for i in 0..g.xyz.len() {
        if !punched.contains(&i) && !big.contains(&i) {
            assert_eq!(g.xyz[i], orig.xyz[i]);
        }
    }
}

#[test]
fn holes_on_a_plane_are_filled_exactly() {
    let orig = scan_of(&plane(), Artifacts::none());
    let mut g = orig.clone();
    let p = punch(&mut g, (30.0, 30.0), 4.0);
    let holes = fill_grid_holes(&mut g, 10.0).unwrap();
    assert_eq!(holes.len(), 1);
    assert!(holes[0].filled);
    for i in p {
        assert!((g.xyz[i] - orig.xyz[i]).length() < 1e-9);
    }
}

#[test]
fn mesh_holes_are_fanned_and_big_ones_left() {
    // A 40 x 40 mm plane with a 3 mm and a 14 mm square hole.
    let m = shapes::grid_plane(40, 1.0, 0.0, 0.0, 0, |c| {
        (c.x > 10.0 && c.x < 13.0 && c.y > 10.0 && c.y < 13.0)
            || (c.x > 20.0 && c.x < 30.0 && c.y > 20.0 && c.y < 30.0)
    });
    let (filled, holes) = fill_mesh_holes(&m, 6.0).unwrap();
    assert_eq!(holes.len(), 2, "{holes:?}");
    let f: Vec<_> = holes.iter().filter(|h| h.filled).collect();
    assert_eq!(f.len(), 1);
    assert!((f[0].diameter_mm - 3.0 * 2f64.sqrt()).abs() < 1e-9);
    assert_eq!(filled.n_vertices(), m.n_vertices() + 1);
    assert_eq!(filled.n_faces(), m.n_faces() + f[0].size);
    let topo = meshcore::Topology::new(&filled);
    assert_eq!(topo.boundary_loops().len(), 2);
    assert!(topo.is_oriented_manifold());
    assert!(filled.positions().iter().all(|p| p.z == 0.0));
}

#[test]
fn mesh_gaps_are_closed_from_their_own_vertices() {
    // A 40 x 40 mm plane with gaps of one cell (4 edges) and of two cells (6 edges), whose
    // vertices are all there, and a 14 mm hole.
    let m = shapes::grid_plane(40, 1.0, 0.0, 0.0, 0, |c| {
        (c.x > 10.0 && c.x < 11.0 && c.y > 10.0 && c.y < 11.0)
            || (c.x > 5.0 && c.x < 7.0 && c.y > 30.0 && c.y < 31.0)
            || (c.x > 20.0 && c.x < 30.0 && c.y > 20.0 && c.y < 30.0)
    });
    let before = meshcore::Topology::new(&m);
    assert_eq!(before.boundary_loops().len(), 4);
    let (closed, holes) = close_mesh_gaps(&m, 6.0).unwrap();
    assert_eq!(holes.len(), 3, "{holes:?}");
    let mut sizes: Vec<_> = holes.iter().filter(|h| h.filled).map(|h| h.size).collect();
    sizes.sort_unstable();
    assert_eq!(sizes, [4, 6]);
    assert!(holes.iter().any(|h| !h.filled && h.diameter_mm > 14.0));
    // No vertex added or moved; a gap of k edges takes k - 2 triangles.
    assert_eq!(closed.positions(), m.positions());
    assert_eq!(closed.n_faces(), m.n_faces() + 2 + 4);
    let topo = meshcore::Topology::new(&closed);
    assert_eq!(topo.boundary_loops().len(), 2);
    assert!(topo.is_oriented_manifold());
    // The new triangles cover the gaps with the plane's orientation: the area is back.
    let area = |t: &TriMesh| -> f64 {
        let p = t.positions();
        t.triangles()
            .iter()
            .map(|f| {
                let (a, b, c) = (p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]);
                (b - a).cross(c - a).z / 2.0
            })
            .sum()
    };
    assert!((area(&closed) - area(&m) - 3.0).abs() < 1e-9);
    // Two one-cell gaps touching at a corner: one boundary loop through that vertex twice.
    let bowtie = shapes::grid_plane(20, 1.0, 0.0, 0.0, 0, |c| {
        (c.x > 8.0 && c.x < 9.0 && c.y > 8.0 && c.y < 9.0)
            || (c.x > 9.0 && c.x < 10.0 && c.y > 9.0 && c.y < 10.0)
    });
    let (closed, holes) = close_mesh_gaps(&bowtie, 6.0).unwrap();
    assert!(holes.iter().all(|h| h.filled), "{holes:?}");
    assert_eq!(closed.n_faces(), bowtie.n_faces() + 4);
    let topo = meshcore::Topology::new(&closed);
    assert_eq!(topo.boundary_loops().len(), 1);
    assert!(topo.is_oriented_manifold());
    assert!((area(&closed) - area(&bowtie) - 2.0).abs() < 1e-9);
    // Nothing to close at a 0 mm limit; a bad limit is an error.
    assert_eq!(close_mesh_gaps(&m, 0.0).unwrap().0, m);
    assert!(close_mesh_gaps(&m, f64::NAN).is_err());
}

#[test]
fn cells_dropped_on_depth_noise_are_closed_by_clean() {
    // 1 mm of depth noise at 0.5 mm pitch: neighbouring samples differ by more than the
    // triangulation's long-edge rule allows here and there, although none is missing.
    let g = scan_of(
        &plane(),
        Artifacts {
            noise: Some(rangescan::DepthNoise { sigma_mm: 1.0 }),
            ..Artifacts::none()
        },
    );
    let o = CleanOptions {
        units: Some(Units::Millimetre),
        spikes: None,
        ..CleanOptions::default()
    };
    let open = mesh_io::bnt_grid_to_mesh(&g, &BntOptions::default()).unwrap();
    let gaps_before = meshcore::Topology::new(&open.mesh).boundary_loops().len() - 1;
    assert!(gaps_before >= 5, "{gaps_before} gaps: the test needs some");
    let c = clean(Input::Grid(&g), &o).unwrap();
    let topo = meshcore::Topology::new(&c.mesh);
    assert_eq!(topo.boundary_loops().len(), 1, "only the border is left");
    assert_eq!(c.report.gaps_closed, gaps_before);
    assert!(c
        .report
        .summary()
        .iter()
        .any(|l| l == &format!("triangulation gaps closed: {gaps_before}")));
    // The samples are the vertices, in the grid index, as before.
    let gi = c.grid_index.unwrap();
    assert_eq!(c.mesh.n_vertices(), open.mesh.n_vertices());
    for (k, &s) in gi.iter().enumerate() {
        assert_eq!(g.xyz[s as usize], c.mesh.positions()[k]);
    }
    // Without hole filling the gaps stay.
    let kept = clean(
        Input::Grid(&g),
        &CleanOptions {
            max_hole_diameter_mm: None,
            ..o
        },
    )
    .unwrap();
    assert_eq!(kept.report.gaps_closed, 0);
    assert_eq!(
        meshcore::Topology::new(&kept.mesh).boundary_loops().len(),
        gaps_before + 1
    );
}

#[test]
fn the_incidence_mask_follows_the_sphere() {
    // A sphere scanned along z: the incidence at a sample is the angle between its radius and z.
    // Depth noise tips the normals: 0.2 mm at 0.5 mm pitch by up to about 10 degrees after the
    // ring averaging.
    for (noise, tol) in [
        (None, 4.0),
        (Some(rangescan::DepthNoise { sigma_mm: 0.2 }), 10.0),
    ] {
        let g = scan_of(
            &sphere(),
            Artifacts {
                noise,
                ..Artifacts::none()
            },
        );
        let m = mesh_io::bnt_grid_to_mesh(&g, &BntOptions::default())
            .unwrap()
            .mesh;
        let mask = incidence_mask(&m, DVec3::Z, 50.0).unwrap();
        let (mut inside, mut outside) = (0, 0);
        for (p, &seen) in m.positions().iter().zip(&mask) {
            let incidence = (p.z / p.length()).acos().to_degrees();
            if incidence < 50.0 - tol {
                assert!(seen, "{incidence} degrees left out (noise {noise:?})");
                inside += 1;
            } else if incidence > 50.0 + tol {
                assert!(!seen, "{incidence} degrees kept (noise {noise:?})");
                outside += 1;
            }
        }
        assert!(inside > 1000 && outside > 1000, "{inside} {outside}");
    }
    // Seen from the other side nothing is kept; bad options are errors.
    let g = scan_of(&sphere(), Artifacts::none());
    let m = mesh_io::bnt_grid_to_mesh(&g, &BntOptions::default())
        .unwrap()
        .mesh;
    assert!(incidence_mask(&m, -DVec3::Z, 80.0)
        .unwrap()
        .iter()
        .all(|&s| !s));
    assert!(incidence_mask(&m, DVec3::ZERO, 60.0).is_err());
    assert!(incidence_mask(&m, DVec3::Z, f64::NAN).is_err());
    assert!(incidence_mask(&m, DVec3::Z, 181.0).is_err());
    // Several directions at once: each mask follows the sphere about its own direction.
    let turned = DVec3::new(30f64.to_radians().sin(), 0.0, 30f64.to_radians().cos());
    let masks = incidence_masks(&m, &[DVec3::Z, turned], 40.0).unwrap();
    assert_eq!(masks[0], incidence_mask(&m, DVec3::Z, 40.0).unwrap());
    let (mut inside, mut outside) = (0, 0);
    for (p, &seen) in m.positions().iter().zip(&masks[1]) {
        let incidence = (p.dot(turned) / p.length()).acos().to_degrees();
        if incidence < 36.0 {
            assert!(
                seen,
                "{incidence} degrees from the turned direction left out"
            );
            inside += 1;
        } else if incidence > 44.0 {
            assert!(!seen, "{incidence} degrees from the turned direction kept");
            outside += 1;
        }
    }
    assert!(inside > 1000 && outside > 1000, "{inside} {outside}");
    assert!(incidence_masks(&m, &[DVec3::Z, DVec3::ZERO], 60.0).is_err());
}

#[test]
fn a_mesh_spike_is_removed() {
    let s = sphere();
    let mut pos = s.positions().to_vec();
    pos[100] *= 1.2;
    let m = TriMesh::new(pos, s.triangles().to_vec()).unwrap();
    let (out, n) = remove_mesh_spikes(&m, 3.0).unwrap();
    assert_eq!(n, 1);
    assert_eq!(out.n_vertices(), m.n_vertices() - 1);
    assert_eq!(remove_mesh_spikes(&s, 3.0).unwrap().1, 0);
}

#[test]
fn the_crop_radius_is_honoured() {
    let g = scan_of(&sphere(), Artifacts::none());
    let centre = DVec3::new(0.0, 0.0, R);
    let c = clean(
        Input::Grid(&g),
        &CleanOptions {
            units: Some(Units::Millimetre),
            crop: Some(Crop {
                centre,
                radius_mm: 30.0,
            }),
            ..CleanOptions::default()
        },
    )
    .unwrap();
    let d = c
        .mesh
        .positions()
        .iter()
        .map(|p| p.distance(centre))
        .fold(0.0f64, f64::max);
    assert!(d <= 30.0 && d > 29.0, "{d}");
    assert!(c.report.cropped_vertices > 0);
    // Every vertex within the sphere survives (up to the rim's partial cells).
    let full = mesh_io::bnt_grid_to_mesh(&g, &BntOptions::default())
        .unwrap()
        .mesh;
    let inside = full
        .positions()
        .iter()
        .filter(|p| p.distance(centre) <= 29.0)
        .count();
    assert!(c.mesh.n_vertices() >= inside);
    assert_eq!(
        c.report.cropped_vertices,
        full.n_vertices() - c.mesh.n_vertices()
    );
    let gi = c.grid_index.unwrap();
    assert_eq!(gi.len(), c.mesh.n_vertices());
    for (k, &s) in gi.iter().enumerate() {
        assert_eq!(g.xyz[s as usize], c.mesh.positions()[k]);
    }
    // The crop keeps the surviving vertices in order: each is found in the uncropped mesh,
    // and a mesh with a moved vertex is not a subset.
    let (cut, removed) = crop_sphere(&full, full.positions()[full.n_vertices() / 2], 5.0).unwrap();
    assert!(removed > 0);
    let kept = surviving_vertices(&full, &cut).unwrap();
    assert_eq!(kept.len(), cut.n_vertices());
    assert!(kept.windows(2).all(|k| k[0] < k[1]));
    for (p, &k) in cut.positions().iter().zip(&kept) {
        assert_eq!(full.positions()[k as usize], *p);
    }
    let mut moved = cut.positions().to_vec();
    moved[0].x += 1e-3;
    let moved = TriMesh::new(moved, cut.triangles().to_vec()).unwrap();
    assert_eq!(surviving_vertices(&full, &moved), None);
    // Crop a bare mesh; nothing inside is an error.
    assert!(matches!(
        crop_sphere(&full, DVec3::splat(1e4), 1.0),
        Err(ScanPrepError::NothingLeft(_))
    ));
}

#[test]
fn an_uncropped_scan_finishes_like_clean_with_each_crop() {
    // Spikes and a decimation: every step of `clean` runs, before and after the crop.
    let g = scan_of(&sphere(), spiky());
    let o = CleanOptions {
        units: Some(Units::Millimetre),
        target_edge_mm: Some(3.0),
        ..CleanOptions::default()
    };
    let staged = clean_uncropped(Input::Grid(&g), &o).unwrap();
    assert_eq!(staged.units(), Units::Millimetre);
    let crops = [
        None,
        Some(Crop {
            centre: DVec3::new(0.0, 0.0, R),
            radius_mm: 30.0,
        }),
        Some(Crop {
            centre: DVec3::new(10.0, -5.0, R),
            radius_mm: 45.0,
        }),
    ];
    for crop in crops {
        let once = clean(Input::Grid(&g), &CleanOptions { crop, ..o.clone() }).unwrap();
        let finished = staged.finish(crop).unwrap();
        assert_eq!(finished.mesh, once.mesh, "{crop:?}");
        assert_eq!(finished.grid_index, once.grid_index);
        let mut a = finished.report.clone();
        let mut b = once.report.clone();
        (a.timings, b.timings) = (Vec::new(), Vec::new());
        assert_eq!(a, b);
        assert_eq!(crop.is_some(), finished.report.cropped_vertices > 0);
    }
    // A bad crop is the same clear error either way.
    let bad = Some(Crop {
        centre: DVec3::new(f64::NAN, 0.0, 0.0),
        radius_mm: 30.0,
    });
    assert!(matches!(
        staged.finish(bad),
        Err(ScanPrepError::InvalidOption(_))
    ));
}

#[test]
fn decimation_reaches_the_target_and_keeps_the_sphere() {
    let g = scan_of(&sphere(), Artifacts::none());
    let mesh = mesh_io::bnt_grid_to_mesh(&g, &BntOptions::default())
        .unwrap()
        .mesh;
    let (d, rep) = decimate(&mesh, 2.0).unwrap();
    assert!(rep.mean_edge_before < 0.8, "{rep:?}");
    assert!(
        rep.mean_edge_after > 1.4 && rep.mean_edge_after < 2.8,
        "{rep:?}"
    );
    assert!(rep.vertices_after * 6 < rep.vertices_before, "{rep:?}");
    let worst = d
        .positions()
        .iter()
        .map(|p| (p.length() - R).abs())
        .fold(0.0f64, f64::max);
    assert!(worst < 4.0 / (4.0 * R), "{worst}");
    let topo = meshcore::Topology::new(&d);
    assert!(topo.is_oriented_manifold());
    assert_eq!(topo.boundary_loops().len(), 1);
}

#[test]
fn bad_grids_are_clear_errors() {
    let g = scan_of(&plane(), Artifacts::none());
    let opts = CleanOptions::default();
    let valid: Vec<usize> = (0..g.xyz.len()).filter(|&i| g.is_valid(i)).collect();
    // NaN.
    let mut bad = g.clone();
    bad.xyz[valid[10]].z = f64::NAN;
    let e = clean(Input::Grid(&bad), &opts).unwrap_err();
    assert!(matches!(e, ScanPrepError::NonFinite { .. }), "{e}");
    assert!(e.to_string().contains("not finite"));
    // A sentinel other than zmin.
    let mut bad = g.clone();
    bad.xyz[valid[10]].z = -1e12;
    let e = clean(Input::Grid(&bad), &opts).unwrap_err();
    assert!(matches!(e, ScanPrepError::SentinelLike { .. }), "{e}");
    // Empty.
    let mut bad = g.clone();
    for p in &mut bad.xyz {
        *p = DVec3::splat(bad.zmin);
    }
    let e = clean(Input::Grid(&bad), &opts).unwrap_err();
    assert!(matches!(e, ScanPrepError::Empty(_)), "{e}");
    // 90 % holes (every sample but one in ten dropped, the outline kept).
    let mut bad = g.clone();
    for (k, &i) in valid.iter().enumerate() {
        let (r, c) = (i / g.ncols, i % g.ncols);
        let edge = [r, c].contains(&2) || r + 3 == g.nrows || c + 3 == g.ncols;
        if k % 10 != 0 && !edge {
            bad.xyz[i] = DVec3::splat(bad.zmin);
        }
    }
    let e = clean(Input::Grid(&bad), &opts).unwrap_err();
    assert!(matches!(e, ScanPrepError::MostlyHoles { .. }), "{e}");
    assert!(e.to_string().contains("mostly holes"), "{e}");
    // Bad options.
    let e = clean(
        Input::Grid(&g),
        &CleanOptions {
            target_edge_mm: Some(-1.0),
            units: Some(Units::Millimetre),
            ..CleanOptions::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, ScanPrepError::InvalidOption(_)), "{e}");
    // The plane alone (60 mm across, 85 mm diagonal) is a face size in mm; check_grid accepts it.
    assert!(check_grid(&g, 0.5).unwrap().coverage > 0.99);
}

#[test]
fn clean_is_deterministic_and_reports() {
    let mut a = Artifacts::structured_light();
    a.holes = None;
    let g = scan_of(&sphere(), a);
    let o = CleanOptions {
        smoothing_iterations: 2,
        target_edge_mm: Some(1.5),
        ..CleanOptions::default()
    };
    let x = clean(Input::Grid(&g), &o).unwrap();
    let mut y = clean(Input::Grid(&g), &o).unwrap();
    y.report.timings = x.report.timings.clone();
    assert_eq!(x, y);
    assert_eq!(x.report.units.used, Units::Millimetre);
    assert!(!x.report.units.overridden);
    assert!(x.report.grid_spikes.spikes > 0);
    assert!(x.report.decimation.is_some());
    let s = x.report.summary().join("\n");
    assert!(s.contains("units: mm (detected"), "{s}");
    assert!(s.contains("spikes removed"), "{s}");
}

fn ict_face() -> Option<TriMesh> {
    testsupport::paper_meshes(["id1_neutral.obj"]).map(|[m]| m)
}

#[test]
fn units_of_the_ict_face_in_mm_cm_and_m() {
    let Some(face) = ict_face() else { return };
    for u in Units::ALL {
        let f = Units::Centimetre.factor_to(u);
        let m = TriMesh::new(
            face.positions().iter().map(|p| *p * f).collect(),
            face.triangles().to_vec(),
        )
        .unwrap();
        assert_eq!(detect_units(&m).unwrap().units, u);
        let c = clean(Input::Mesh(&m), &CleanOptions::default()).unwrap();
        assert_eq!(c.report.units.used, u);
        // Output in mm: the face is 15 cm wide.
        let w = c.mesh.bbox().size().x;
        assert!((w - 149.3).abs() < 1.0, "{w}");
    }
}

#[test]
fn a_scan_of_the_ict_face_is_in_mm() {
    let Some(face) = ict_face() else { return };
    let o = ScanOptions {
        input_mm_per_unit: 10.0,
        artifacts: Artifacts::structured_light(),
        pose: HeadPose {
            yaw_deg: 20.0,
            pitch_deg: 0.0,
        },
        seed: 3,
        ..ScanOptions::default()
    };
    let s = scan(&face, &o).unwrap();
    let mesh = mesh_io::bnt_grid_to_mesh(&s.grid, &BntOptions::default())
        .unwrap()
        .mesh;
    assert_eq!(detect_units(&mesh).unwrap().units, Units::Millimetre);
    let c = clean(Input::Grid(&s.grid), &CleanOptions::default()).unwrap();
    assert_eq!(c.report.units.used, Units::Millimetre);
    assert!(
        c.report.grid_spikes.spikes >= s.stats.spikes * 9 / 10,
        "{:?}",
        c.report
    );
    assert!(c.report.holes_filled() > 0, "{:?}", c.report.holes);
}

mod no_panic {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        #[test]
        fn clean_never_panics_on_random_grids(
            nrows in 1usize..14,
            ncols in 1usize..14,
            kinds in proptest::collection::vec((0u8..10, -5.0f64..5.0), 196),
            units in 0usize..4,
            target in proptest::option::of(0.1f64..3.0),
        ) {
            let zmin = -1e9;
            let n = nrows * ncols;
            let xyz = (0..n).map(|i| {
                let (r, c) = (i / ncols, i % ncols);
                let (k, z) = kinds[i % kinds.len()];
                match k {
                    0 | 1 => DVec3::splat(zmin),
                    2 => DVec3::new(c as f64, f64::NAN, z),
                    3 => DVec3::new(c as f64 * 20.0, -(r as f64) * 20.0, z * 1e3),
                    _ => DVec3::new(c as f64 * 15.0, -(r as f64) * 15.0, z),
                }
            }).collect();
            let g = BntGrid { nrows, ncols, zmin, image_file: String::new(), xyz, uv: vec![[0.0; 2]; n] };
            let o = CleanOptions {
                units: [None, Some(Units::Millimetre), Some(Units::Centimetre), Some(Units::Metre)][units],
                target_edge_mm: target,
                smoothing_iterations: 1,
                crop: Some(Crop { centre: DVec3::ZERO, radius_mm: 100.0 }),
                ..CleanOptions::default()
            };
            let _ = clean(Input::Grid(&g), &o);
        }
    }
}
