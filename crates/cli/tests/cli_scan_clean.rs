//! `bipolar scan` and `bipolar clean` end to end: scan an ICT face (cm) to `.bnt`, clean it,
//! read the result back.

use std::path::PathBuf;

mod common;

/// (success, stdout, stderr) of one run of `bipolar`.
fn bipolar(args: &[&str]) -> (bool, String, String) {
    let r = common::bipolar(args);
    (r.ok, r.stdout, r.stderr)
}

#[test]
fn scan_an_ict_face_clean_it_and_read_it_back() {
    let Some((face, dir)) = common::paper_face_and_tempdir("id1_neutral.obj") else {
        return;
    };
    let bnt = dir.path().join("scan.bnt");
    let lm3 = dir.path().join("scan.lm3");
    let s = |p: &PathBuf| p.to_str().unwrap().to_string();
    let scan_args = [
        "scan",
        face.to_str().unwrap(),
        "--out",
        &s(&bnt),
        "--lm3",
        &s(&lm3),
        "--pitch",
        "0.8",
        "--yaw",
        "-10",
        "--noise",
        "0.1",
        "--spikes",
        "0.002",
        "--seed",
        "5",
        "--landmark-vertex",
        "Nose tip=4857",
        "--landmark-vertex",
        "Outer right eye corner=1507",
    ];
    let (ok, out, err) = bipolar(&scan_args);
    assert!(ok, "{err}");
    assert!(out.contains("units: cm (detected"), "{out}");
    // Deterministic under the seed.
    let first = std::fs::read(&bnt).unwrap();
    assert!(bipolar(&scan_args).0);
    assert_eq!(std::fs::read(&bnt).unwrap(), first);
    let grid = mesh_io::read_bnt_grid(&bnt).unwrap();
    assert!(grid.nrows > 100 && grid.ncols > 100);
    let lm = mesh_io::read_lm3(&lm3).unwrap();
    let nose = lm
        .get("Nose tip")
        .expect("the nose tip is visible frontally");

    let ply = dir.path().join("clean.ply");
    let centre = format!("{},{},{}", nose.x, nose.y, nose.z);
    let (ok, out, err) = bipolar(&[
        "clean",
        &s(&bnt),
        &s(&ply),
        "--crop-center",
        &centre,
        "--crop-radius",
        "80",
        "--target-edge",
        "1.5",
        "--timings",
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("units: mm (detected"), "{out}");
    assert!(out.contains("spikes removed: "), "{out}");
    assert!(out.contains("decimation to 1.500 mm"), "{out}");
    assert!(out.contains("time spikes"), "{out}");
    let m = mesh_io::read_mesh(&ply).unwrap().mesh;
    let far = m
        .positions()
        .iter()
        .map(|p| p.distance(nose))
        .fold(0.0f64, f64::max);
    assert!(far <= 80.0, "{far}");
    let e = m.mean_edge_length();
    assert!(e > 1.0 && e < 2.2, "{e}");
}

/// A frontal range grid of a spherical cap (radius 100 mm, 50 mm across at 1 mm pitch), the
/// size of a face, written as `dir/cap.bnt`: a scan that needs no shared data.
fn cap_bnt(dir: &std::path::Path) -> PathBuf {
    let (n, zmin) = (51, -1e9);
    let mut xyz = Vec::new();
    for r in 0..n {
        for c in 0..n {
            let (x, y) = (c as f64 - 25.0, 25.0 - r as f64);
            let rr = x * x + y * y;
            xyz.push(if rr < 25.0 * 25.0 {
                meshcore::DVec3::new(x, y, (100.0f64 * 100.0 - rr).sqrt())
            } else {
                meshcore::DVec3::splat(zmin)
            });
        }
    }
    let grid = mesh_io::BntGrid {
        nrows: n,
        ncols: n,
        zmin,
        image_file: String::new(),
        xyz,
        uv: vec![[0.0; 2]; n * n],
    };
    let p = dir.join("cap.bnt");
    std::fs::write(&p, grid.to_bytes()).unwrap();
    p
}

/// `bipolar clean --units` overrides the detected units; a unit, an output file or a crop
/// centre that is wrong is an error naming the problem.
#[test]
fn clean_takes_given_units_and_names_bad_arguments() {
    let dir = tempfile::tempdir().unwrap();
    let bnt = cap_bnt(dir.path());
    let ply = dir.path().join("clean.ply");
    let s = |p: &PathBuf| p.to_str().unwrap().to_string();
    let (ok, out, err) = bipolar(&["clean", &s(&bnt), &s(&ply), "--units", "mm"]);
    assert!(ok, "{err}");
    assert!(out.contains("units: mm (given"), "{out}");
    assert!(mesh_io::read_mesh(&ply).unwrap().mesh.n_vertices() > 100);
    let (ok, _, err) = bipolar(&["clean", &s(&bnt), &s(&ply), "--units", "inch"]);
    assert!(!ok);
    assert!(err.contains("unknown length unit"), "{err}");
    let (ok, _, err) = bipolar(&["clean", &s(&bnt), &s(&bnt)]);
    assert!(!ok);
    assert!(err.contains("is a mesh"), "{err}");
    let (ok, _, err) = bipolar(&["clean", &s(&bnt), &s(&ply), "--crop-center", "1,2"]);
    assert!(!ok);
    assert!(err.contains("x,y,z"), "{err}");
}

#[test]
fn scan_refuses_a_mesh_of_no_face_size() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("km.obj");
    std::fs::write(&p, "v 0 0 0\nv 3000 0 0\nv 0 3000 0\nf 1 2 3\n").unwrap();
    let out = dir.path().join("x.bnt");
    let (ok, _, err) = bipolar(&["scan", p.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("not a face"), "{err}");
    assert!(err.contains("--units"), "{err}");
}
