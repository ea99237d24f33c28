//! End-to-end tests of `bipolar landmarks`.

mod common;
use common::{arg, Run};
use std::path::{Path, PathBuf};

fn bipolar(args: &[&str]) -> Run {
    common::bipolar_cmd("landmarks", args)
}

#[test]
fn detects_on_a_paper_face_and_writes_json_and_lm3() {
    let Some((mesh, dir)) = common::paper_face_and_tempdir("id2_neutral.obj") else {
        return;
    };
    let json = dir.path().join("lm.json");
    let lm3 = dir.path().join("lm.lm3");
    let stdout = bipolar(&[arg(&mesh), "--out", arg(&json), "--lm3", arg(&lm3)])
        .success()
        .stdout;
    assert!(stdout.contains("confidence") && stdout.contains("outer_eye_right"));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // The ICT truth of this face (cm): right outer eye corner near (-4.4, 3.4, 8.6).
    let p = &v["landmarks"]["outer_eye_right"]["position"];
    let x = p[0].as_f64().unwrap();
    assert!((x + 4.4).abs() < 0.6, "outer_eye_right x = {x}");
    let text = std::fs::read_to_string(&lm3).unwrap();
    assert!(text.contains("5 landmarks:") && text.contains("Outer right eye corner"));
}

#[test]
fn not_a_face_fails_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    // A flat 20 x 20 grid of cells 0.5 wide in the plane z = 0.
    let obj = common::grid_obj(dir.path(), "plane.obj", 20, 0.5);
    let err = bipolar(&[arg(&obj)]).failure();
    assert!(err.contains("not found") && err.contains("score"), "{err}");
}

#[test]
fn a_face_in_millimetres_needs_no_scale_flag() {
    let Some((mesh, dir)) = common::paper_face_and_tempdir("id2_neutral.obj") else {
        return;
    };
    let mm = dir.path().join("face_mm.obj");
    let text: String = std::fs::read_to_string(&mesh)
        .unwrap()
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(rest) => {
                let v: Vec<String> = rest
                    .split_whitespace()
                    .map(|x| format!("{}", 10.0 * x.parse::<f64>().unwrap()))
                    .collect();
                format!("v {}\n", v.join(" "))
            }
            None => format!("{l}\n"),
        })
        .collect();
    std::fs::write(&mm, text).unwrap();
    let json = dir.path().join("lm.json");
    let stdout = bipolar(&[arg(&mm), "--out", arg(&json)]).success().stdout;
    assert!(stdout.contains("units mm"), "{stdout}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let x = v["landmarks"]["outer_eye_right"]["position"][0]
        .as_f64()
        .unwrap();
    assert!((x + 44.0).abs() < 6.0, "outer_eye_right x = {x} mm");
    // An explicit --scale still wins: 1 (the model's cm) on a face in mm finds no face.
    bipolar(&[arg(&mm), "--scale", "1"]).failure();
}

/// `bipolar scan` of `mesh` turned by `yaw` degrees (1 mm pitch, structured-light artifacts,
/// seed `seed`) into `dir/turned.bnt`.
fn scan_turned(mesh: &Path, dir: &Path, yaw: &str, seed: &str) -> PathBuf {
    let bnt = dir.join("turned.bnt");
    common::bipolar(&[
        "scan",
        arg(mesh),
        "--out",
        arg(&bnt),
        "--pitch",
        "1",
        "--yaw",
        yaw,
        "--artifacts",
        "structured-light",
        "--seed",
        seed,
    ])
    .success();
    bnt
}

#[test]
fn a_range_grid_is_read_as_seen_from_its_scanner() {
    let Some((mesh, dir)) = common::paper_face_and_tempdir("id4_neutral.obj") else {
        return;
    };
    // A head turned by 35 degrees: the scanner loses the far side around the far eye corner.
    let bnt = scan_turned(&mesh, dir.path(), "35", "7");
    // As a range grid, the missing surface is unobserved: the face is found.
    let out = bipolar(&[arg(&bnt)]).success().stdout;
    assert!(
        out.contains("face found") && out.contains("outer_eye_left"),
        "{out}"
    );
    // The same surface as a mesh file has no viewpoint: the missing surface is mismatch.
    let ply = dir.path().join("turned.ply");
    common::bipolar(&["convert", arg(&bnt), arg(&ply)]).success();
    let err = bipolar(&[arg(&ply)]).failure();
    assert!(
        err.contains("not found") && err.contains("templates"),
        "{err}"
    );
}

#[test]
fn a_landmark_the_scanner_did_not_see_is_not_found_with_its_reason() {
    let Some((mesh, dir)) = common::paper_face_and_tempdir("id6_neutral.obj") else {
        return;
    };
    // Turned by 50 degrees: the far inner eye corner hides behind the nose.
    let bnt = scan_turned(&mesh, dir.path(), "50", "3");
    let lm3 = dir.path().join("found.lm3");
    let out = bipolar(&[arg(&bnt), "--lm3", arg(&lm3)]).success().stdout;
    assert!(out.contains("face found"), "{out}");
    let unseen: Vec<&str> = out
        .lines()
        .filter(|l| l.contains("not found:"))
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert!(!unseen.is_empty(), "nothing reported unseen: {out}");
    // The .lm3 file lists the placed landmarks and names the unseen ones in its notes.
    let text = std::fs::read_to_string(&lm3).unwrap();
    assert!(text.contains("not found"), "{text}");
    // Describing from an unseen landmark is an error naming it, not a point nearby.
    let name = unseen[0].replace('_', "-");
    let err = common::bipolar(&[
        "describe",
        arg(&bnt),
        "--ref-a",
        &name,
        "--ref-b",
        "nose-tip",
        "--out",
        arg(&dir.path().join("d.json")),
    ])
    .failure();
    assert!(
        err.contains("is not found") && err.contains(unseen[0]),
        "{err}"
    );
}
