//! End-to-end tests of `bipolar describe --landmarks FILE`: reference points named in a given
//! landmark file (`.lm3`, flat JSON, the ICT `landmarks.json` layout) instead of detected ones.

use std::path::PathBuf;

mod common;
use common::{arg as s, sphere_obj, Run};

fn describe(args: &[&str]) -> Run {
    common::bipolar_cmd("describe", args)
}

/// Runs `describe` once per argument list (each with `common` after it and `--out` one of
/// `outs`), checks every run succeeds and returns the outputs' texts with every run's stderr.
fn describe_each(runs: &[&[&str]], common: &[&str], outs: &[PathBuf]) -> Vec<(String, String)> {
    runs.iter()
        .zip(outs)
        .map(|(args, out)| {
            let e = describe(&[*args, common, &["--out", s(out)]].concat())
                .success()
                .stderr;
            (std::fs::read_to_string(out).unwrap(), e)
        })
        .collect()
}

/// A hand-written Bosphorus-style `.lm3` fixture: an info block, CRLF line ends, points off the
/// sphere (snapped to it by `describe`).
const LM3: &str = "# made by hand for the tests\r\n\r\n3 landmarks:\r\nOuter right eye corner\r\n0.0 0.0 1.05\r\nOuter left eye corner\r\n1.1 0.0 0.0\r\nChin middle\r\n0.0 -1.0 0.0\r\n";

/// A temporary folder with the unit icosphere and [`LM3`] in it: (folder, mesh, landmarks).
fn sphere_and_lm3() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let lm3 = dir.path().join("given.lm3");
    std::fs::write(&lm3, LM3).unwrap();
    (dir, obj, lm3)
}

/// The two eye corners as the references, by name.
const EYES: [&str; 4] = ["--ref-a", "outer-eye-right", "--ref-b", "outer-eye-left"];

#[test]
fn lm3_names_give_the_same_descriptor_as_the_coordinates() {
    let (dir, obj, lm3) = sphere_and_lm3();
    // A third label of the file works through --ref too; a flat JSON file works like the LM3.
    let json = dir.path().join("given.json");
    std::fs::write(
        &json,
        r#"{"outer_eye_right": [0.0, 0.0, 1.05], "outer_eye_left": [1.1, 0.0, 0.0]}"#,
    )
    .unwrap();
    let outs = ["a.csv", "b.csv", "c.csv"].map(|n| dir.path().join(n));
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
    let runs: [&[&str]; 3] = [
        &[
            s(&obj),
            "--landmarks",
            s(&lm3),
            "--ref-a",
            "outer-eye-right",
            "--ref-b",
            "Outer left eye corner",
        ],
        &[s(&obj), "--ref-a", "0,0,1.05", "--ref-b", "1.1,0,0"],
        &[&[s(&obj), "--landmarks", s(&json)][..], &EYES].concat(),
    ];
    let got = describe_each(&runs, &common, &outs);
    assert!(got[0].1.contains("snapped to the surface"), "{}", got[0].1);
    let ta = &got[0].0;
    assert!(ta.lines().count() > 10, "{ta}");
    assert_eq!(ta, &got[1].0);
    assert_eq!(&got[2].0, ta);
}

#[test]
fn missing_names_and_unreadable_files_fail_clearly() {
    let (dir, obj, lm3) = sphere_and_lm3();
    let out = dir.path().join("x.csv");
    let bad_lm3 = dir.path().join("bad.lm3");
    std::fs::write(&bad_lm3, "2 landmarks:\nNose tip\n1 2 x\n").unwrap();
    let bad_json = dir.path().join("bad.json");
    std::fs::write(&bad_json, "{\"outer_eye_right\": [1, 2]").unwrap();
    // (landmark file, --ref-a, what the error says)
    let cases: [(PathBuf, &str, &[&str]); 4] = [
        (lm3, "nose-tip", &["\"nose-tip\" is not in", "Chin middle"]),
        (
            dir.path().join("absent.lm3"),
            "outer-eye-right",
            &["reading the landmark file"],
        ),
        (bad_lm3, "outer-eye-right", &["bad.lm3: line 3"]),
        (bad_json, "outer-eye-right", &["not a JSON landmark file"]),
    ];
    for (file, a, needles) in &cases {
        let e = describe(&[
            s(&obj),
            "--landmarks",
            s(file),
            "--ref-a",
            a,
            "--ref-b",
            "outer-eye-left",
            "--method",
            "dijkstra",
            "--out",
            s(&out),
        ])
        .failure();
        assert!(needles.iter().all(|n| e.contains(n)), "{file:?}: {e}");
    }
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
    let outs = ["a.csv", "b.csv"].map(|n| dir.path().join(n));
    let common = ["--levels", "5", "--method", "dijkstra"];
    let by_names = [&["--landmarks", s(&json)][..], &EYES].concat();
    let runs: [&[&str]; 2] = [
        &[&[s(&face)][..], &by_names].concat(),
        &[s(&face), "--ref-a", "1507", "--ref-b", "3721"],
    ];
    let got = describe_each(&runs, &common, &outs);
    // The file's `vertex_ids` (right_eye_outer 1507, left_eye_outer 3721) sit at the face's
    // positions, so the vertices are used as given.
    let e = &got[0].1;
    assert!(
        e.contains("outer-eye-right: vertex 1507") && e.contains("outer-eye-left: vertex 3721"),
        "{e}"
    );
    let ta = &got[0].0;
    assert!(ta.lines().count() > 10);
    assert_eq!(ta, &got[1].0);

    // A mesh whose name is not a face of the file fails naming the faces it has.
    let other = dir.path().join("someone.obj");
    std::fs::copy(&face, &other).unwrap();
    let e = describe(
        &[
            &[s(&other)][..],
            &by_names,
            &common,
            &["--out", s(&outs[0])],
        ]
        .concat(),
    )
    .failure();
    assert!(
        e.contains("no face named \"someone\"") && e.contains("id1_happiness"),
        "{e}"
    );
}
