//! End-to-end tests of `bipolar describe --landmarks FILE`: reference points named in a given
//! landmark file (`.lm3`, flat JSON, the ICT `landmarks.json` layout) instead of detected ones.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn describe(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bipolar"))
        .arg("describe")
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
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

/// A hand-written Bosphorus-style `.lm3` fixture: an info block, CRLF line ends, points off the
/// sphere (snapped to it by `describe`).
const LM3: &str = "# made by hand for the tests\r\n\r\n3 landmarks:\r\nOuter right eye corner\r\n0.0 0.0 1.05\r\nOuter left eye corner\r\n1.1 0.0 0.0\r\nChin middle\r\n0.0 -1.0 0.0\r\n";

#[test]
fn lm3_names_give_the_same_descriptor_as_the_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let lm3 = dir.path().join("given.lm3");
    std::fs::write(&lm3, LM3).unwrap();
    let (a, b) = (dir.path().join("a.csv"), dir.path().join("b.csv"));
    // The fixture's points are up to 0.1 off the unit sphere (2.9 % of its bounding-box
    // diagonal), beyond the default snapping tolerance of 1 %.
    let common = [
        "--method",
        "dijkstra",
        "--levels",
        "6",
        "--snap-tolerance",
        "0.05",
    ];
    let o = describe(
        &[
            &[obj.to_str().unwrap(), "--landmarks", lm3.to_str().unwrap()][..],
            &[
                "--ref-a",
                "outer-eye-right",
                "--ref-b",
                "Outer left eye corner",
            ],
            &common,
            &["--out", a.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("snapped to the surface"),
        "{}",
        stderr(&o)
    );
    let o = describe(
        &[
            &[obj.to_str().unwrap()][..],
            &["--ref-a", "0,0,1.05", "--ref-b", "1.1,0,0"],
            &common,
            &["--out", b.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (ta, tb) = (
        std::fs::read_to_string(&a).unwrap(),
        std::fs::read_to_string(&b).unwrap(),
    );
    assert!(ta.lines().count() > 10, "{ta}");
    assert_eq!(ta, tb);

    // A third label of the file works through --ref too; a flat JSON file works like the LM3.
    let json = dir.path().join("given.json");
    std::fs::write(
        &json,
        r#"{"outer_eye_right": [0.0, 0.0, 1.05], "outer_eye_left": [1.1, 0.0, 0.0]}"#,
    )
    .unwrap();
    let c = dir.path().join("c.csv");
    let o = describe(
        &[
            &[obj.to_str().unwrap(), "--landmarks", json.to_str().unwrap()][..],
            &["--ref-a", "outer-eye-right", "--ref-b", "outer-eye-left"],
            &common,
            &["--out", c.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&c).unwrap(), ta);
}

#[test]
fn missing_names_and_unreadable_files_fail_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let lm3 = dir.path().join("given.lm3");
    std::fs::write(&lm3, LM3).unwrap();
    let out = dir.path().join("x.csv");
    let run = |file: &Path, a: &str| {
        describe(&[
            obj.to_str().unwrap(),
            "--landmarks",
            file.to_str().unwrap(),
            "--ref-a",
            a,
            "--ref-b",
            "outer-eye-left",
            "--method",
            "dijkstra",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let o = run(&lm3, "nose-tip");
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("\"nose-tip\" is not in") && e.contains("Chin middle"),
        "{e}"
    );
    let o = run(&dir.path().join("absent.lm3"), "outer-eye-right");
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("reading the landmark file"),
        "{}",
        stderr(&o)
    );
    let bad = dir.path().join("bad.lm3");
    std::fs::write(&bad, "2 landmarks:\nNose tip\n1 2 x\n").unwrap();
    let o = run(&bad, "outer-eye-right");
    assert!(!o.status.success());
    assert!(stderr(&o).contains("bad.lm3: line 3"), "{}", stderr(&o));
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, "{\"outer_eye_right\": [1, 2]").unwrap();
    let o = run(&bad, "outer-eye-right");
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("not a JSON landmark file"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
}

#[test]
fn ict_landmarks_json_gives_the_ground_truth_vertices() {
    let (Some(face), Some(json)) = (
        testsupport::paper_face("id1_happiness.obj"),
        testsupport::paper_face("landmarks.json"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.csv"), dir.path().join("b.csv"));
    let common = ["--levels", "5", "--method", "dijkstra"];
    let o = describe(
        &[
            &[
                face.to_str().unwrap(),
                "--landmarks",
                json.to_str().unwrap(),
            ][..],
            &["--ref-a", "outer-eye-right", "--ref-b", "outer-eye-left"],
            &common,
            &["--out", a.to_str().unwrap()],
        ]
        .concat(),
    );
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    // The file's `vertex_ids` (right_eye_outer 1507, left_eye_outer 3721) sit at the face's
    // positions, so the vertices are used as given.
    assert!(
        e.contains("outer-eye-right: vertex 1507") && e.contains("outer-eye-left: vertex 3721"),
        "{e}"
    );
    let o = describe(
        &[
            &[face.to_str().unwrap()][..],
            &["--ref-a", "1507", "--ref-b", "3721"],
            &common,
            &["--out", b.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let ta = std::fs::read_to_string(&a).unwrap();
    assert!(ta.lines().count() > 10);
    assert_eq!(ta, std::fs::read_to_string(&b).unwrap());

    // A mesh whose name is not a face of the file fails naming the faces it has.
    let other = dir.path().join("someone.obj");
    std::fs::copy(&face, &other).unwrap();
    let o = describe(
        &[
            &[
                other.to_str().unwrap(),
                "--landmarks",
                json.to_str().unwrap(),
            ][..],
            &["--ref-a", "outer-eye-right", "--ref-b", "outer-eye-left"],
            &common,
            &["--out", a.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("no face named \"someone\"") && e.contains("id1_happiness"),
        "{e}"
    );
}
