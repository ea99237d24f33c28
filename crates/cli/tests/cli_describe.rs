//! End-to-end tests of `bipolar describe`.

mod common;
use common::{arg, bipolar, grid_obj, sphere_obj};

#[test]
fn describe_writes_csv_json_and_ply() {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let csv = dir.path().join("d.csv");
    let ab = ["describe", arg(&obj), "--ref-a", "0", "--ref-b", "100"];
    let strip = ["--levels", "6", "--rule", "filter", "--tangent", "strip"];
    bipolar(
        &[
            &ab[..],
            &strip,
            &["--method", "dijkstra", "--out", arg(&csv)],
        ]
        .concat(),
    )
    .success();
    let d = bipolar::io::read_csv(&csv).unwrap();
    assert!(!d.is_empty());
    assert!(std::fs::read_to_string(&csv)
        .unwrap()
        .starts_with("x,y,z,a,b,i,j,side,sign,cos,ambiguous\n"));
    // Every point is on the unit sphere (up to the chord error of the mesh).
    assert!(d
        .points
        .iter()
        .all(|p| (p.position.length() - 1.0).abs() < 0.02));

    // Coordinates as references, a third reference, JSON output, spline tangents.
    let json = dir.path().join("d.json");
    bipolar(&[
        "describe",
        arg(&obj),
        "--ref-a",
        "0,0,1",
        "--ref-b",
        "1,0,0",
        "--ref",
        "0,1,0",
        "--step",
        "0.2",
        "--max-level",
        "8",
        "--angles",
        "6",
        "--alpha",
        "0.9",
        "--tangent",
        "spline",
        "--method",
        "dijkstra",
        "--out",
        arg(&json),
    ])
    .success();
    let d = bipolar::io::read_json(&json).unwrap();
    assert_eq!(d.references.len(), 3);
    assert!((d.references[0] - glam::DVec3::Z).length() < 0.05);
    assert!((d.step - 0.2).abs() < 1e-12);
    let pairs: std::collections::BTreeSet<(u8, u8)> =
        d.points.iter().map(|p| (p.key.a, p.key.b)).collect();
    assert_eq!(pairs.len(), 3);
    assert!(d.points.iter().all(|p| p.key.j <= 6 && p.key.i <= 8));

    let ply = dir.path().join("d.ply");
    bipolar(&[&ab[..], &["--method", "dijkstra", "--out", arg(&ply)]].concat()).success();
    assert!(std::fs::read_to_string(&ply).unwrap().starts_with("ply\n"));
}

#[test]
fn describe_reports_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let out = dir.path().join("x.csv");
    let o = arg(&out);
    // (arguments after the mesh, what the error names)
    let cases: [(&[&str], &str); 7] = [
        (
            &["--ref-b", "99999", "--method", "dijkstra", "--out", o],
            "99999",
        ),
        (
            &["--ref-b", "a,b", "--method", "dijkstra", "--out", o],
            "a,b",
        ),
        (
            &["--ref-b", "0", "--method", "dijkstra", "--out", o],
            "coincide",
        ),
        (
            &["--ref-b", "5", "--method", "dijkstra", "--out", "x.txt"],
            ".csv",
        ),
        (&["--ref-b", "5", "--tangent", "magic", "--out", o], "magic"),
        (
            &[
                "--ref-b", "5", "--method", "dijkstra", "--step", "50", "--out", o,
            ],
            "no descriptor points",
        ),
        (
            &[
                "--ref-b",
                "5",
                "--method",
                "dijkstra",
                "--boundary-margin=-1",
                "--out",
                o,
            ],
            "boundary margin",
        ),
    ];
    for (args, needle) in cases {
        let e = bipolar(&[&["describe", arg(&obj), "--ref-a", "0"][..], args].concat()).failure();
        assert!(e.contains(needle), "{args:?}: {e}");
    }
}

#[test]
fn landmark_names_are_detected_or_fail_clearly() {
    let dir = tempfile::tempdir().unwrap();
    // A sphere is not a face: the detector must say so, not pick a point.
    let obj = sphere_obj(dir.path());
    let s_csv = dir.path().join("s.csv");
    let eyes = ["--ref-a", "outer-eye-right", "--ref-b", "outer-eye-left"];
    let err =
        bipolar(&[&["describe", arg(&obj)][..], &eyes, &["--out", arg(&s_csv)]].concat()).failure();
    assert!(err.contains("outer_eye_right"), "{err}");

    // On a paper-set face the detected corners are within 5 mm of the ground-truth vertices.
    let Some(face) = testsupport::paper_face("id2_neutral.obj") else {
        return;
    };
    let csv = dir.path().join("f.csv");
    let levels = ["--levels", "5", "--out", arg(&csv)];
    let err = bipolar(&[&["describe", arg(&face)][..], &eyes, &levels].concat())
        .success()
        .stderr;
    assert!(std::fs::read_to_string(&csv).unwrap().lines().count() > 10);
    let mesh = mesh_io::read_mesh(&face).unwrap().mesh;
    for (name, truth) in [("outer_eye_right", 1507u32), ("outer_eye_left", 3721)] {
        let line = err.lines().find(|l| l.starts_with(name)).expect(name);
        let v: u32 = line
            .split("vertex ")
            .nth(1)
            .and_then(|r| r.split_whitespace().next())
            .and_then(|x| x.parse().ok())
            .expect(line);
        let d = (mesh.position(v) - mesh.position(truth)).length();
        assert!(
            d < 0.5,
            "{name}: detected vertex {v} is {d} cm from {truth}"
        );
    }
}

/// `describe` with rule `all` and step 2 on a 30 x 30 grid mesh (31 vertices a row), the
/// references at columns `cols` of the middle row, plus `extra` options; the descriptor read back.
fn grid_describe(
    obj: &std::path::Path,
    cols: (usize, usize),
    extra: &[&str],
    out: &std::path::Path,
) -> bipolar::Descriptor {
    let (a, b) = (
        (15 * 31 + cols.0).to_string(),
        (15 * 31 + cols.1).to_string(),
    );
    let base = ["describe", arg(obj), "--ref-a", &a, "--ref-b", &b];
    let opts = ["--step", "2", "--rule", "all", "--out", arg(out)];
    bipolar(&[&base[..], &opts, extra].concat()).success();
    bipolar::io::read_csv(out).unwrap()
}

#[test]
fn boundary_margin_leaves_out_the_band_along_the_border() {
    // A 30 x 30 grid of unit cells; references (5, 15) and (25, 15), 20 apart.
    let dir = tempfile::tempdir().unwrap();
    let obj = grid_obj(dir.path(), "grid.obj", 30, 1.0);
    let run =
        |extra: &[&str], name: &str| grid_describe(&obj, (5, 25), extra, &dir.path().join(name));
    let all = run(&[], "all.csv");
    let cut = run(&["--boundary-margin", "4"], "cut.csv");
    // Distance to the square's border [0, 30]^2.
    let border = |p: glam::DVec3| p.x.min(30.0 - p.x).min(p.y).min(30.0 - p.y);
    assert!(all.points.iter().any(|p| border(p.position) < 3.0));
    assert!(!cut.is_empty() && cut.len() < all.len());
    // Kept faces have every vertex at least 4 from the border: points at least 3 (one cell).
    assert!(cut.points.iter().all(|p| border(p.position) >= 3.0 - 1e-9));
}

#[test]
fn max_incidence_leaves_out_what_the_scanner_saw_at_grazing_angles() {
    // A sheet seen along z: flat for x <= 15, then rising at 70 degrees (incidence 70).
    let dir = tempfile::tempdir().unwrap();
    let rise = 70f64.to_radians().tan();
    let sheet =
        testsupport::shapes::grid(30, 30, testsupport::shapes::Diagonals::Uniform, |i, j| {
            let x = i as f64;
            glam::DVec3::new(x, j as f64, (x - 15.0).max(0.0) * rise)
        })
        .unwrap();
    let obj = testsupport::cli::write_mesh(dir.path(), "sheet.obj", &sheet);
    let run =
        |extra: &[&str], name: &str| grid_describe(&obj, (5, 20), extra, &dir.path().join(name));
    let all = run(&[], "all.csv");
    let seen = run(&["--max-incidence", "60"], "seen.csv");
    // Kept points lie on faces whose vertices all passed: on the flat part, up to the fold's
    // averaged normals (two rings).
    assert!(all.points.iter().any(|p| p.position.x > 18.0));
    assert!(!seen.is_empty() && seen.len() < all.len());
    assert!(seen.points.iter().all(|p| p.position.x <= 17.0 + 1e-9));
    let id = |i: usize| (15 * 31 + i).to_string();
    let err = bipolar(&[
        "describe",
        arg(&obj),
        "--ref-a",
        &id(5),
        "--ref-b",
        &id(20),
        "--max-incidence",
        "200",
        "--out",
        arg(&dir.path().join("x.csv")),
    ])
    .failure();
    assert!(err.contains("max incidence 200"), "{err}");
}

#[test]
fn describe_with_the_reference_point_search_writes_the_moved_descriptors_beside() {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let plain = dir.path().join("plain.json");
    let out = dir.path().join("d.json");
    let ab = ["describe", arg(&obj), "--ref-a", "0", "--ref-b", "100"];
    let opts = ["--levels", "6", "--method", "dijkstra"];
    bipolar(&[&ab[..], &opts, &["--out", arg(&plain)]].concat()).success();
    bipolar(
        &[
            &ab[..],
            &opts,
            &["--search-radius", "0.2", "--out", arg(&out)],
        ]
        .concat(),
    )
    .success();
    // The references' own descriptor is the one written without the search.
    assert_eq!(std::fs::read(&plain).unwrap(), std::fs::read(&out).unwrap());
    let own = bipolar::io::read_json(&out).unwrap();
    let moved: Vec<_> = (1..=48)
        .map(|k| dir.path().join(format!("d.search-{k:02}.json")))
        .take_while(|p| p.exists())
        .map(|p| bipolar::io::read_json(&p).unwrap())
        .collect();
    assert!(moved.len() > 20, "{}", moved.len());
    assert!(!dir
        .path()
        .join(format!("d.search-{:02}.json", moved.len() + 1))
        .exists());
    assert!(moved
        .iter()
        .all(|m| m.references != own.references && !m.is_empty()));
    // `distance --searched` of the own descriptor with itself is 0; of the plain one (no
    // moved files beside it) with the searched one, too.
    let r = bipolar(&["distance", arg(&plain), arg(&out), "--searched"]).success();
    assert!(
        r.stdout.trim().parse::<f64>().unwrap() < 1e-12,
        "{}",
        r.stdout
    );
    // Describing again without the search removes the moved files, which `--searched` would
    // otherwise take for this descriptor's.
    let err = bipolar(&[&ab[..], &opts, &["--out", arg(&out)]].concat())
        .success()
        .stderr;
    assert!(
        err.contains(&format!("removed {} search files", moved.len())),
        "{err}"
    );
    assert!(!dir.path().join("d.search-01.json").exists());
    // A bad radius is an error naming the option; directions need a radius.
    let err = bipolar(
        &[
            &ab[..],
            &opts,
            &["--search-radius", "0", "--out", arg(&out)],
        ]
        .concat(),
    )
    .failure();
    assert!(
        err.contains("--search-radius") && err.contains("radius"),
        "{err}"
    );
    bipolar(
        &[
            &ab[..],
            &opts,
            &["--search-directions", "3", "--out", arg(&out)],
        ]
        .concat(),
    )
    .failure();
}
