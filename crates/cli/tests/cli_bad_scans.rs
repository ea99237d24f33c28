//! Bad scans end to end: a scan of something that is not a face, the back of a head, a scan
//! that is 90 % holes, a landmark file naming a point outside the scan. Each is an error that
//! names the problem (exit status 1, no panic).

use std::path::{Path, PathBuf};
use testsupport::paper_face;

mod common;

/// Runs the CLI: (success, stdout, stderr).
fn bipolar(args: &[&str]) -> (bool, String, String) {
    let r = common::bipolar(args);
    (r.ok, r.stdout, r.stderr)
}

/// Fails cleanly: not successful, exit code 1 (anyhow), no panic message, `word` in stderr.
fn fails_with<S: AsRef<std::ffi::OsStr> + std::fmt::Debug>(args: &[S], word: &str) -> String {
    eprintln!("bipolar {args:?}");
    testsupport::cli::run(env!("CARGO_BIN_EXE_bipolar"), args).error_naming(word)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `bipolar scan MESH --out BNT OPTS...`, which must succeed.
fn scan(mesh: &Path, bnt: &Path, opts: &[&str]) {
    let (ok, _, err) = bipolar(&[&["scan", s(mesh), "--out", s(bnt)], opts].concat());
    assert!(ok, "{err}");
}

/// The arguments of `bipolar describe INPUT OPTS... --ref-a outer-eye-right --ref-b
/// outer-eye-left --out DIR/d.csv`.
fn describe_eyes(input: &Path, dir: &Path, opts: &[&str]) -> Vec<String> {
    let out = dir.join("d.csv");
    [
        &["describe", s(input)],
        opts,
        &["--ref-a", "outer-eye-right"],
    ]
    .concat()
    .into_iter()
    .chain(["--ref-b", "outer-eye-left", "--out", s(&out)])
    .map(str::to_string)
    .collect()
}

/// A closed box of `w x h x d` mm (12 triangles) as OBJ: an object of face size that is no face.
fn box_obj(dir: &Path, w: f64, h: f64, d: f64) -> PathBuf {
    let mut text = String::new();
    for i in 0..8 {
        let x = if i & 1 == 0 { -w / 2.0 } else { w / 2.0 };
        let y = if i & 2 == 0 { -h / 2.0 } else { h / 2.0 };
        let z = if i & 4 == 0 { -d / 2.0 } else { d / 2.0 };
        text += &format!("v {x} {y} {z}\n");
    }
    for f in [
        [1, 3, 4, 2],
        [5, 6, 8, 7],
        [1, 2, 6, 5],
        [3, 7, 8, 4],
        [1, 5, 7, 3],
        [2, 4, 8, 6],
    ] {
        text += &format!(
            "f {} {} {}\nf {} {} {}\n",
            f[0], f[1], f[2], f[0], f[2], f[3]
        );
    }
    let p = dir.join("box.obj");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn a_scan_of_a_box_has_no_landmarks() {
    let dir = tempfile::tempdir().unwrap();
    let obj = box_obj(dir.path(), 160.0, 200.0, 120.0);
    let bnt = dir.path().join("box.bnt");
    scan(&obj, &bnt, &["--pitch", "1", "--yaw", "30"]);
    // Cleaning works (it is a surface of face size)...
    let clean = dir.path().join("box.ply");
    let (ok, _, err) = bipolar(&["clean", s(&bnt), s(&clean)]);
    assert!(ok, "{err}");
    // ...but there is no face on it.
    fails_with(&["landmarks", s(&clean)], "landmarks not found");
    fails_with(&describe_eyes(&bnt, dir.path(), &[]), "landmarks not found");
}

#[test]
fn the_back_of_a_head_has_no_landmarks() {
    let Some(face) = paper_face("id2_neutral.obj") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let bnt = dir.path().join("back.bnt");
    // Turned by 180 degrees: the scanner sees the inside of the face shell from behind.
    scan(&face, &bnt, &["--yaw", "180", "--pitch", "0.8"]);
    fails_with(&["landmarks", s(&bnt)], "landmarks not found");
}

/// A frontal grid of a 60 mm cap at 1 mm pitch, `keep(row, col)` samples valid.
fn cap_grid(keep: impl Fn(usize, usize) -> bool) -> mesh_io::BntGrid {
    let n = 161;
    let zmin = -1e9;
    let mut xyz = Vec::new();
    let mut uv = Vec::new();
    for r in 0..n {
        for c in 0..n {
            let (x, y) = (c as f64 - 80.0, 80.0 - r as f64);
            let rr = x * x + y * y;
            uv.push([c as f64 / n as f64, r as f64 / n as f64]);
            if rr < 80.0 * 80.0 && keep(r, c) {
                xyz.push(meshcore::DVec3::new(x, y, (120.0f64 * 120.0 - rr).sqrt()));
            } else {
                xyz.push(meshcore::DVec3::splat(zmin));
            }
        }
    }
    mesh_io::BntGrid {
        nrows: n,
        ncols: n,
        zmin,
        image_file: String::new(),
        xyz,
        uv,
    }
}

#[test]
fn a_scan_that_is_ninety_percent_holes_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let bnt = dir.path().join("holes.bnt");
    // One sample in ten survives, scattered (every 10th in a diagonal pattern), inside a full
    // silhouette.
    let grid = cap_grid(|r, c| (r * 3 + c) % 10 == 0 || r == 0 || c == 0);
    mesh_io::write_bnt(&bnt, &grid).unwrap();
    let err = fails_with(
        &["clean", s(&bnt), s(&dir.path().join("out.ply"))],
        "mostly holes",
    );
    assert!(err.contains("%"), "{err}");
    // The landmarks verb reads the grid without cleaning: the triangulation finds nothing to
    // join, and says so.
    fails_with(&["landmarks", s(&bnt)], "no two adjacent valid samples");
}

#[test]
fn a_landmark_file_naming_a_point_outside_the_scan_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let bnt = dir.path().join("cap.bnt");
    mesh_io::write_bnt(&bnt, &cap_grid(|_, _| true)).unwrap();
    let lm3 = dir.path().join("far.lm3");
    // The right corner on the cap, the left one 500 mm in front of it.
    let on = (120.0f64 * 120.0 - 20.0 * 20.0).sqrt();
    std::fs::write(
        &lm3,
        format!(
            "2 landmarks:\nOuter right eye corner\n-20 0 {on}\nOuter left eye corner\n20 0 {}\n",
            on + 500.0
        ),
    )
    .unwrap();
    let err = fails_with(
        &describe_eyes(&bnt, dir.path(), &["--landmarks", s(&lm3)]),
        "from the surface, farther than the tolerance",
    );
    assert!(err.contains("--ref-b"), "{err}");
}
