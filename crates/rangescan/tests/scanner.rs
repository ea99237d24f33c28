//! The scanner on analytic shapes: exact grids, occlusion, noise statistics, determinism and
//! the independence of the artifact switches.

use meshcore::{shapes, DVec3, TriMesh};
use rangescan::{
    scan, scan_with_landmarks, Artifacts, Border, DepthNoise, GrazingDropout, HeadPose, Holes,
    Outliers, Projection, Quantisation, SampleStatus, Scan, ScanError, ScanOptions, Spikes,
    Visibility,
};

/// The plane z = `z` over [0, 20] x [0, 20] mm (1 mm cells, jittered interior vertices).
fn plane(z: f64) -> TriMesh {
    let g = shapes::grid_plane(20, 1.0, 0.0, 0.6, 3, |_| false);
    let pos = g
        .positions()
        .iter()
        .map(|p| DVec3::new(p.x, p.y, z))
        .collect();
    TriMesh::new(pos, g.triangles().to_vec()).unwrap()
}

/// A sphere of radius `r` about `c` (icosphere, 5 subdivisions).
fn sphere(c: DVec3, r: f64) -> TriMesh {
    let s = shapes::icosphere(5);
    let pos = s.positions().iter().map(|p| c + *p * r).collect();
    TriMesh::new(pos, s.triangles().to_vec()).unwrap()
}

/// An axis-aligned box (outward faces).
fn cuboid(lo: DVec3, hi: DVec3) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let p = |i: u32| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let pos = (0..8).map(p).collect();
    let quads = [
        [0, 2, 3, 1], // z = lo
        [4, 5, 7, 6], // z = hi
        [0, 1, 5, 4], // y = lo
        [2, 6, 7, 3], // y = hi
        [0, 4, 6, 2], // x = lo
        [1, 3, 7, 5], // x = hi
    ];
    let mut tris = Vec::new();
    for q in quads {
        tris.push([q[0], q[1], q[2]]);
        tris.push([q[0], q[2], q[3]]);
    }
    (pos, tris)
}

fn valid(s: &Scan) -> Vec<(usize, DVec3)> {
    (0..s.status.len())
        .filter(|&i| s.status[i] == SampleStatus::Valid)
        .map(|i| (i, s.grid.xyz[i]))
        .collect()
}

#[test]
fn plane_at_a_known_depth_gives_its_exact_grid() {
    let o = ScanOptions::default();
    let s = scan(&plane(5.0), &o).unwrap();
    // Samples at x, y = 0, 0.5, ..., 20 (41 x 41), two background samples of margin per side.
    assert_eq!((s.grid.nrows, s.grid.ncols), (45, 45));
    let v = valid(&s);
    assert_eq!(v.len(), 41 * 41);
    for (i, p) in v {
        let (r, c) = (i / 45, i % 45);
        assert!(
            (2..43).contains(&r) && (2..43).contains(&c),
            "sample {r} {c}"
        );
        assert_eq!(p.z, 5.0);
        assert_eq!(p.x, (c as f64 - 2.0) * 0.5);
        assert_eq!(p.y, (42.0 - r as f64) * 0.5); // row 0 at the top (largest y)
    }
    // Background samples hold the sentinel in x, y and z, as .bnt files do.
    assert!(s.grid.is_valid(2 * 45 + 2) && !s.grid.is_valid(0));
    assert_eq!(s.grid.xyz[0], DVec3::splat(rangescan::BACKGROUND));
    assert_eq!(s.stats.rendered, 41 * 41);
}

#[test]
fn pinhole_samples_lie_on_the_plane_and_on_their_rays() {
    let o = ScanOptions {
        projection: Projection::Pinhole { distance_mm: 300.0 },
        ..ScanOptions::default()
    };
    let s = scan(&plane(-7.0), &o).unwrap();
    let v = valid(&s);
    // One pixel is 0.5 mm on the plane: about 41 x 41 samples.
    assert!((1600..=1760).contains(&v.len()), "{}", v.len());
    let centre = DVec3::new(10.0, 10.0, -7.0 + 300.0);
    let mut xs: Vec<f64> = Vec::new();
    for (i, p) in &v {
        assert!((p.z + 7.0).abs() < 1e-9, "{p}");
        assert!((-1e-9..=20.0 + 1e-9).contains(&p.x) && (-1e-9..=20.0 + 1e-9).contains(&p.y));
        let (r, c) = (i / s.grid.ncols, i % s.grid.ncols);
        if r == s.grid.nrows / 2 {
            xs.push(p.x);
        }
        // Neighbouring columns on one row are one pitch apart on the plane.
        let _ = c;
        assert!((p - centre).normalize().z < 0.0);
    }
    for w in xs.windows(2) {
        assert!(((w[1] - w[0]) - 0.5).abs() < 1e-9, "{w:?}");
    }
}

#[test]
fn sphere_samples_lie_on_it_within_the_noise_put_in() {
    let c = DVec3::new(1.0, 2.0, 3.0); // cm
    let m = sphere(c, 5.0);
    let clean = ScanOptions {
        input_mm_per_unit: 10.0,
        pitch_mm: 0.5,
        ..ScanOptions::default()
    };
    let (cm, r) = (c * 10.0, 50.0);
    // Depth error along each ray against the true sphere, on samples seen within 60 degrees.
    let errors = |s: &Scan| -> Vec<f64> {
        valid(s)
            .into_iter()
            .filter_map(|(_, p)| {
                let d2 = (p.x - cm.x).powi(2) + (p.y - cm.y).powi(2);
                (d2 < (0.85 * r) * (0.85 * r)).then(|| p.z - (cm.z + (r * r - d2).sqrt()))
            })
            .collect()
    };
    let e0 = errors(&scan(&m, &clean).unwrap());
    assert!(e0.len() > 20_000, "{}", e0.len());
    // The icosphere's facets sag at most r (1 - cos(half the edge angle)) below the sphere.
    let sag = e0.iter().fold(0.0_f64, |a, e| a.max(e.abs()));
    assert!(sag < 0.03 && e0.iter().all(|e| *e <= 1e-9), "sag {sag}");
    let noisy = ScanOptions {
        artifacts: Artifacts {
            noise: Some(DepthNoise { sigma_mm: 0.2 }),
            ..Artifacts::none()
        },
        seed: 11,
        ..clean
    };
    let e1 = errors(&scan(&m, &noisy).unwrap());
    let d: Vec<f64> = e1.iter().zip(&e0).map(|(a, b)| a - b).collect();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let sd = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    assert!(mean.abs() < 0.01, "mean {mean}");
    assert!((sd - 0.2).abs() < 0.01, "sd {sd}");
    assert!(d.iter().all(|x| x.abs() < 6.0 * 0.2));
}

#[test]
fn z_buffer_hides_the_plane_behind_a_box() {
    let p = plane(0.0);
    let (bp, bt) = cuboid(DVec3::new(5.0, 5.0, 10.0), DVec3::new(15.0, 15.0, 20.0));
    let mut pos = p.positions().to_vec();
    let off = pos.len() as u32;
    pos.extend(bp);
    let mut tris = p.triangles().to_vec();
    tris.extend(bt.iter().map(|t| t.map(|v| v + off)));
    let m = TriMesh::new(pos, tris).unwrap();
    let marks = vec![
        ("behind".to_string(), DVec3::new(10.0, 10.0, 0.0)),
        ("beside".to_string(), DVec3::new(2.0, 2.0, 0.0)),
        ("on top".to_string(), DVec3::new(10.0, 10.0, 20.0)),
        ("in the air".to_string(), DVec3::new(2.0, 18.0, 6.0)),
        ("far away".to_string(), DVec3::new(200.0, 0.0, 0.0)),
    ];
    let s = scan_with_landmarks(&m, &marks, &ScanOptions::default()).unwrap();
    for (_, q) in valid(&s) {
        let inside = (5.0..=15.0).contains(&q.x) && (5.0..=15.0).contains(&q.y);
        if inside {
            assert_eq!(q.z, 20.0, "{q}");
        } else {
            assert_eq!(q.z, 0.0, "{q}");
        }
    }
    let vis: Vec<Visibility> = s.landmarks.iter().map(|l| l.visibility).collect();
    match vis[0] {
        Visibility::Occluded { in_front_mm } => assert!((in_front_mm - 20.0).abs() < 1e-9),
        v => panic!("{v:?}"),
    }
    assert_eq!(vis[1], Visibility::Visible);
    assert_eq!(vis[2], Visibility::Visible);
    assert_eq!(vis[3], Visibility::OffSurface);
    assert_eq!(vis[4], Visibility::OutsideGrid);
}

#[test]
fn head_rotation_turns_the_front_and_hides_the_back() {
    let m = sphere(DVec3::ZERO, 30.0);
    let front = vec![("front".to_string(), DVec3::new(0.0, 0.0, 30.0))];
    let turn = |yaw: f64, pitch: f64| {
        let o = ScanOptions {
            pose: HeadPose {
                yaw_deg: yaw,
                pitch_deg: pitch,
            },
            ..ScanOptions::default()
        };
        scan_with_landmarks(&m, &front, &o).unwrap().landmarks[0].clone()
    };
    let l = turn(30.0, 0.0);
    assert!((l.position - DVec3::new(15.0, 0.0, 30.0 * 0.75f64.sqrt())).length() < 1e-9);
    assert!(l.visibility.is_visible());
    let l = turn(0.0, 30.0);
    assert!((l.position - DVec3::new(0.0, 15.0, 30.0 * 0.75f64.sqrt())).length() < 1e-9);
    let l = turn(180.0, 0.0);
    match l.visibility {
        Visibility::Occluded { in_front_mm } => assert!((in_front_mm - 60.0).abs() < 0.1),
        v => panic!("{v:?}"),
    }
}

fn all_artifacts() -> Artifacts {
    Artifacts {
        quantisation: Some(Quantisation { step_mm: 1.0 }),
        border: Some(Border {
            top_mm: 3.0,
            ..Border::default()
        }),
        ..Artifacts::structured_light()
    }
}

#[test]
fn scans_are_deterministic_under_a_seed() {
    let m = sphere(DVec3::ZERO, 40.0);
    let o = ScanOptions {
        artifacts: all_artifacts(),
        seed: 5,
        ..ScanOptions::default()
    };
    let a = scan(&m, &o).unwrap();
    let b = scan(&m, &o).unwrap();
    assert_eq!(a, b);
    let bytes = mesh_io::write_bnt_to_bytes(&a.grid).unwrap();
    assert_eq!(bytes, mesh_io::write_bnt_to_bytes(&b.grid).unwrap());
    let c = scan(&m, &ScanOptions { seed: 6, ..o }).unwrap();
    assert_ne!(a.grid, c.grid);
    assert!(a.stats.spikes > 0 && a.stats.outliers == 50 && a.stats.holes > 0);
    assert!(a.stats.grazing > 0 && a.stats.border > 0);
}

/// Scans of one sphere differing only in the artifacts.
fn with(a: Artifacts) -> Scan {
    let m = sphere(DVec3::new(0.0, 0.0, 0.0), 40.0);
    scan(
        &m,
        &ScanOptions {
            artifacts: a,
            seed: 9,
            ..ScanOptions::default()
        },
    )
    .unwrap()
}

#[test]
fn each_artifact_switch_changes_only_what_it_should() {
    let base = with(Artifacts::none());
    let n = base.status.len();
    let same_status = |s: &Scan| s.status == base.status;
    let changed = |s: &Scan| {
        (0..n)
            .filter(|&i| s.grid.xyz[i] != base.grid.xyz[i])
            .count()
    };
    // Noise and quantisation keep every status and move valid samples in depth only: (depth
    // before, depth after) of each valid sample.
    let depths = |a: Artifacts| -> Vec<(f64, f64)> {
        let s = with(a);
        assert!(same_status(&s));
        valid(&base)
            .into_iter()
            .map(|(i, p)| {
                let q = s.grid.xyz[i];
                assert!(q.x == p.x && q.y == p.y, "sample {i} moved sideways");
                (p.z, q.z)
            })
            .collect()
    };
    // Noise: every valid sample moves.
    for (p, q) in depths(Artifacts {
        noise: Some(DepthNoise { sigma_mm: 0.1 }),
        ..Artifacts::none()
    }) {
        assert!(q != p);
    }
    // Quantisation: depths become multiples of the step, nothing else.
    for (p, q) in depths(Artifacts {
        quantisation: Some(Quantisation { step_mm: 2.0 }),
        ..Artifacts::none()
    }) {
        assert!((q - p).abs() <= 1.0 + 1e-12);
        assert_eq!(q, (q / 2.0).round() * 2.0);
    }
    // Spikes: only the counted samples move, by the amounts put in.
    let s = with(Artifacts {
        spikes: Some(Spikes {
            fraction: 0.01,
            min_mm: 3.0,
            max_mm: 5.0,
        }),
        ..Artifacts::none()
    });
    assert!(same_status(&s));
    assert_eq!(changed(&s), s.stats.spikes);
    let nv = base.stats.valid as f64;
    assert!((s.stats.spikes as f64 - 0.01 * nv).abs() < 4.0 * (0.01 * nv).sqrt());
    for (i, p) in valid(&base) {
        let dz = (s.grid.xyz[i].z - p.z).abs();
        assert!(dz == 0.0 || (3.0..=5.0).contains(&dz), "{dz}");
    }
    // Outliers: only background samples change, and become valid.
    let s = with(Artifacts {
        outliers: Some(Outliers { count: 40 }),
        ..Artifacts::none()
    });
    assert_eq!(s.stats.outliers, 40);
    assert_eq!(changed(&s), 40);
    for i in 0..n {
        if s.grid.xyz[i] != base.grid.xyz[i] {
            assert_eq!(base.status[i], SampleStatus::Background);
            assert_eq!(s.status[i], SampleStatus::Valid);
        }
    }
    // Dropouts, holes and border only remove samples, each with its reason.
    for (a, why) in [
        (
            Artifacts {
                grazing: Some(GrazingDropout {
                    start_deg: 60.0,
                    full_deg: 75.0,
                }),
                ..Artifacts::none()
            },
            SampleStatus::Grazing,
        ),
        (
            Artifacts {
                holes: Some(Holes {
                    count: 5,
                    min_radius_mm: 2.0,
                    max_radius_mm: 4.0,
                }),
                ..Artifacts::none()
            },
            SampleStatus::Hole,
        ),
        (
            Artifacts {
                border: Some(Border {
                    left_mm: 5.0,
                    bottom_mm: 2.0,
                    ..Border::default()
                }),
                ..Artifacts::none()
            },
            SampleStatus::Border,
        ),
    ] {
        let s = with(a);
        let mut removed = 0;
        for i in 0..n {
            if s.status[i] != base.status[i] {
                assert_eq!((base.status[i], s.status[i]), (SampleStatus::Valid, why));
                assert!(!s.grid.is_valid(i));
                removed += 1;
            } else {
                assert_eq!(s.grid.xyz[i], base.grid.xyz[i]);
            }
        }
        assert!(removed > 0, "{why:?}");
    }
    // Grazing dropouts happen only beyond the start angle: within 60 degrees of the axis the
    // sphere (radius 40) keeps every sample, x^2 + y^2 < (40 sin 60)^2.
    let s = with(Artifacts {
        grazing: Some(GrazingDropout {
            start_deg: 60.0,
            full_deg: 60.0,
        }),
        ..Artifacts::none()
    });
    for (i, p) in valid(&base) {
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        if rho < 40.0 * 60f64.to_radians().sin() - 0.5 {
            assert_eq!(s.status[i], SampleStatus::Valid);
        } else if rho > 40.0 * 60f64.to_radians().sin() + 0.5 {
            assert_eq!(s.status[i], SampleStatus::Grazing);
        }
    }
    // Streams are independent: holes do not change the noise drawn for the other samples.
    let noise = Some(DepthNoise { sigma_mm: 0.1 });
    let a = with(Artifacts {
        noise,
        ..Artifacts::none()
    });
    let b = with(Artifacts {
        noise,
        holes: Some(Holes {
            count: 5,
            min_radius_mm: 2.0,
            max_radius_mm: 4.0,
        }),
        ..Artifacts::none()
    });
    for (i, p) in valid(&b) {
        assert_eq!(p, a.grid.xyz[i]);
    }
}

#[test]
fn landmarks_in_holes_and_dropouts_are_marked() {
    let m = plane(0.0);
    let marks: Vec<(String, DVec3)> = (0..40)
        .map(|k| {
            (
                format!("p{k}"),
                DVec3::new(1.0 + (k % 8) as f64 * 2.5, 1.0 + (k / 8) as f64 * 4.0, 0.0),
            )
        })
        .collect();
    let o = ScanOptions {
        artifacts: Artifacts {
            holes: Some(Holes {
                count: 6,
                min_radius_mm: 2.0,
                max_radius_mm: 3.0,
            }),
            ..Artifacts::none()
        },
        seed: 2,
        ..ScanOptions::default()
    };
    let s = scan_with_landmarks(&m, &marks, &o).unwrap();
    let mut n_hole = 0;
    for l in &s.landmarks {
        let (r, c) = l.sample.unwrap();
        let st = s.status[r * s.grid.ncols + c];
        match l.visibility {
            Visibility::InHole => {
                assert_eq!(st, SampleStatus::Hole);
                n_hole += 1;
            }
            Visibility::Visible => assert_eq!(st, SampleStatus::Valid),
            v => panic!("{} {v:?}", l.label),
        }
    }
    assert!(n_hole > 0);
}

#[test]
fn bad_options_and_units_are_errors() {
    let m = plane(0.0);
    let d = ScanOptions::default;
    let bad = Artifacts {
        spikes: Some(Spikes {
            fraction: 0.1,
            min_mm: 5.0,
            max_mm: 1.0,
        }),
        ..Artifacts::none()
    };
    let edge_on = HeadPose {
        yaw_deg: 90.0,
        pitch_deg: 0.0,
    };
    type Expect = fn(&ScanError) -> bool;
    // (what is wrong, the options, what the error must be)
    let cases: [(&str, ScanOptions, Expect); 4] = [
        (
            "zero pitch",
            ScanOptions {
                pitch_mm: 0.0,
                ..d()
            },
            |e| matches!(e, ScanError::InvalidOption(s) if s.contains("pitch_mm")),
        ),
        // A 20 mm plane declared in metres is 20 m wide: far too many samples.
        (
            "metres",
            ScanOptions {
                input_mm_per_unit: 1000.0,
                ..d()
            },
            |e| e.to_string().contains("is the input unit right"),
        ),
        (
            "spikes with min above max",
            ScanOptions {
                artifacts: bad,
                ..d()
            },
            |e| {
                matches!(e, ScanError::InvalidOption(s)
                    if s.contains("spikes max_mm = 1") && s.contains("min_mm to"))
            },
        ),
        // Seen edge-on from the side nothing is in view.
        (
            "edge-on",
            ScanOptions {
                pose: edge_on,
                ..d()
            },
            |e| matches!(e, ScanError::NothingInView),
        ),
    ];
    for (what, o, expected) in &cases {
        let e = scan(&m, o).unwrap_err();
        assert!(expected(&e), "{what}: {e}");
    }
    let e =
        scan_with_landmarks(&m, &[("x".into(), DVec3::new(f64::NAN, 0.0, 0.0))], &d()).unwrap_err();
    assert!(matches!(e, ScanError::BadLandmark { .. }));
}

#[test]
fn scans_triangulate_through_the_bnt_reader() {
    let m = sphere(DVec3::ZERO, 40.0);
    let s = scan(
        &m,
        &ScanOptions {
            artifacts: Artifacts::structured_light(),
            seed: 1,
            ..ScanOptions::default()
        },
    )
    .unwrap();
    let bytes = mesh_io::write_bnt_to_bytes(&s.grid).unwrap();
    let back = mesh_io::read_bnt_grid_from_bytes(&bytes, "s.bnt").unwrap();
    assert_eq!(back, s.grid);
    let mesh = mesh_io::read_mesh_from_bytes(&bytes, mesh_io::Format::Bnt).unwrap();
    // The largest component holds nearly every valid sample (outliers and spikes drop out).
    let nv = mesh.mesh.n_vertices() as f64;
    assert!(
        nv > 0.95 * s.stats.valid as f64,
        "{nv} of {}",
        s.stats.valid
    );
}
