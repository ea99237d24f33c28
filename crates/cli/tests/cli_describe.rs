//! End-to-end tests of `bipolar describe`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bipolar"))
}

/// Writes a unit icosphere (3 subdivisions, 642 vertices) as OBJ.
fn sphere_obj(dir: &Path) -> PathBuf {
    let mesh = bipolar::synthetic::icosphere(3);
    let mut s = String::new();
    for p in mesh.positions() {
        s.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
    }
    for t in mesh.triangles() {
        s.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    let path = dir.join("sphere.obj");
    std::fs::write(&path, s).unwrap();
    path
}

#[test]
fn describe_writes_csv_json_and_ply() {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let csv = dir.path().join("d.csv");
    let out = bin()
        .args([
            "describe",
            obj.to_str().unwrap(),
            "--ref-a",
            "0",
            "--ref-b",
            "100",
        ])
        .args([
            "--levels",
            "6",
            "--method",
            "dijkstra",
            "--rule",
            "filter",
            "--tangent",
            "strip",
        ])
        .args(["--out", csv.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
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
    let out = bin()
        .args(["describe", obj.to_str().unwrap()])
        .args(["--ref-a", "0,0,1", "--ref-b", "1,0,0", "--ref", "0,1,0"])
        .args([
            "--step",
            "0.2",
            "--max-level",
            "8",
            "--angles",
            "6",
            "--alpha",
            "0.9",
        ])
        .args([
            "--tangent",
            "spline",
            "--method",
            "dijkstra",
            "--out",
            json.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let d = bipolar::io::read_json(&json).unwrap();
    assert_eq!(d.references.len(), 3);
    assert!((d.references[0] - glam::DVec3::Z).length() < 0.05);
    assert!((d.step - 0.2).abs() < 1e-12);
    let pairs: std::collections::BTreeSet<(u8, u8)> =
        d.points.iter().map(|p| (p.key.a, p.key.b)).collect();
    assert_eq!(pairs.len(), 3);
    assert!(d.points.iter().all(|p| p.key.j <= 6 && p.key.i <= 8));

    let ply = dir.path().join("d.ply");
    let out = bin()
        .args([
            "describe",
            obj.to_str().unwrap(),
            "--ref-a",
            "0",
            "--ref-b",
            "100",
        ])
        .args(["--method", "dijkstra", "--out", ply.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::read_to_string(&ply).unwrap().starts_with("ply\n"));
}

#[test]
fn describe_reports_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let run = |args: &[&str]| {
        let out = bin()
            .args(["describe", obj.to_str().unwrap()])
            .args(args)
            .output()
            .unwrap();
        assert!(!out.status.success());
        String::from_utf8_lossy(&out.stderr).to_string()
    };
    let out = dir.path().join("x.csv");
    let o = out.to_str().unwrap();
    let e = run(&[
        "--ref-a", "0", "--ref-b", "99999", "--method", "dijkstra", "--out", o,
    ]);
    assert!(e.contains("99999"), "{e}");
    let e = run(&[
        "--ref-a", "0", "--ref-b", "a,b", "--method", "dijkstra", "--out", o,
    ]);
    assert!(e.contains("a,b"), "{e}");
    let e = run(&[
        "--ref-a", "0", "--ref-b", "0", "--method", "dijkstra", "--out", o,
    ]);
    assert!(e.contains("coincide"), "{e}");
    let e = run(&[
        "--ref-a", "0", "--ref-b", "5", "--method", "dijkstra", "--out", "x.txt",
    ]);
    assert!(e.contains(".csv"), "{e}");
    let e = run(&[
        "--ref-a",
        "0",
        "--ref-b",
        "5",
        "--tangent",
        "magic",
        "--out",
        o,
    ]);
    assert!(e.contains("magic"), "{e}");
    let e = run(&[
        "--ref-a", "0", "--ref-b", "5", "--method", "dijkstra", "--step", "50", "--out", o,
    ]);
    assert!(e.contains("no descriptor points"), "{e}");
}

#[test]
fn landmark_names_are_detected_or_fail_clearly() {
    let dir = tempfile::tempdir().unwrap();
    // A sphere is not a face: the detector must say so, not pick a point.
    let obj = sphere_obj(dir.path());
    let out = bin()
        .args(["describe", obj.to_str().unwrap()])
        .args(["--ref-a", "outer-eye-right", "--ref-b", "outer-eye-left"])
        .args(["--out", dir.path().join("s.csv").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("outer_eye_right"), "{err}");

    // On a paper-set face the detected corners are within 5 mm of the ground-truth vertices.
    let Some(face) = testsupport::paper_face("id2_neutral.obj") else {
        return;
    };
    let csv = dir.path().join("f.csv");
    let out = bin()
        .args(["describe", face.to_str().unwrap()])
        .args(["--ref-a", "outer-eye-right", "--ref-b", "outer-eye-left"])
        .args(["--levels", "5", "--out", csv.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
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
