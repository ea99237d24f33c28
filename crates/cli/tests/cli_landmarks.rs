//! End-to-end tests of `bipolar landmarks`.

use std::process::Command;

fn bipolar(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_bipolar"))
        .arg("landmarks")
        .args(args)
        .output()
        .unwrap()
}

use testsupport::paper_face;

#[test]
fn detects_on_a_paper_face_and_writes_json_and_lm3() {
    let Some(mesh) = paper_face("id2_neutral.obj") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("lm.json");
    let lm3 = dir.path().join("lm.lm3");
    let out = bipolar(&[
        mesh.to_str().unwrap(),
        "--out",
        json.to_str().unwrap(),
        "--lm3",
        lm3.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
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
    let obj = dir.path().join("plane.obj");
    let mut s = String::new();
    for j in 0..=20 {
        for i in 0..=20 {
            s.push_str(&format!("v {} {} 0\n", i as f64 * 0.5, j as f64 * 0.5));
        }
    }
    for j in 0..20 {
        for i in 0..20 {
            let a = j * 21 + i + 1;
            s.push_str(&format!(
                "f {} {} {}\nf {} {} {}\n",
                a,
                a + 1,
                a + 22,
                a,
                a + 22,
                a + 21
            ));
        }
    }
    std::fs::write(&obj, s).unwrap();
    let out = bipolar(&[obj.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("not found") && err.contains("score"), "{err}");
}

#[test]
fn a_face_in_millimetres_needs_no_scale_flag() {
    let Some(mesh) = paper_face("id2_neutral.obj") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
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
    let out = bipolar(&[mm.to_str().unwrap(), "--out", json.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("units mm"), "{stdout}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let x = v["landmarks"]["outer_eye_right"]["position"][0]
        .as_f64()
        .unwrap();
    assert!((x + 44.0).abs() < 6.0, "outer_eye_right x = {x} mm");
    // An explicit --scale still wins: 1 (the model's cm) on a face in mm finds no face.
    let out = bipolar(&[mm.to_str().unwrap(), "--scale", "1"]);
    assert!(!out.status.success());
}
