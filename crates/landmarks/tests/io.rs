//! The five landmarks among the labelled points of a landmark file (read by `mesh-io`):
//! `.lm3` with CRLF and an info block, the ICT layout, and the missing-landmark error.

use landmarks::{io, LandmarkName};
use meshcore::DVec3;

const LM3: &str = "bs000_N_N_0\r\n*\r\ninfo line\r\n\r\n3 landmarks:\r\nOuter left eye corner\r\n1.5 2 -3\r\n\r\nNose tip\r\n0 0 10.25\r\nOuter right eye corner\r\n-1.5 2 -3\r\n";

#[test]
fn lm3_labels_name_the_landmarks_and_missing_ones_are_named() {
    let l = mesh_io::parse_lm3(LM3.as_bytes(), "a.lm3").unwrap();
    assert_eq!(l.labels.len(), 3);
    assert_eq!(l.labels[0], "Outer left eye corner");
    assert_eq!(l.points[1], DVec3::new(0.0, 0.0, 10.25));
    assert_eq!(
        LandmarkName::parse(&l.labels[2]),
        Some(LandmarkName::OuterEyeRight)
    );
    // Missing inner corners: select_five names the missing one.
    let e = io::select_five(&l, "a.lm3").unwrap_err().to_string();
    assert!(
        e.contains("a.lm3") && e.contains("Inner right eye corner"),
        "{e}"
    );
}

#[test]
fn ict_layout_and_kebab_names() {
    let text = r#"{"units": "cm", "faces": {"f1": {
        "right_eye_outer": [-4, 3, 8], "right_eye_inner": [-2, 3, 9],
        "left_eye_inner": [2, 3, 9], "left_eye_outer": [4, 3, 8], "nose_tip": [0, 0, 12]}}}"#;
    let m = mesh_io::parse_ict_landmarks(text.as_bytes(), "l.json").unwrap();
    let f = io::select_five(&m["f1"], "f1").unwrap();
    assert_eq!(
        f[LandmarkName::OuterEyeLeft as usize],
        DVec3::new(4.0, 3.0, 8.0)
    );
    assert_eq!(
        f[LandmarkName::NoseTip as usize],
        DVec3::new(0.0, 0.0, 12.0)
    );
    assert_eq!(
        LandmarkName::parse("outer-eye-right"),
        Some(LandmarkName::OuterEyeRight)
    );
    let broken = text.replace("\"nose_tip\": [0, 0, 12]", "\"nose_tip\": [0, 0]");
    assert!(mesh_io::parse_ict_landmarks(broken.as_bytes(), "l.json").is_err());
}
