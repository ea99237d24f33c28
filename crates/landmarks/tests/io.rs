//! Landmark files: `.lm3` parsing (CRLF, info block, blank lines), writing and reading back,
//! the ICT JSON layout, and errors with line numbers.

use landmarks::{io, LandmarkName};
use meshcore::DVec3;

const LM3: &str = "bs000_N_N_0\r\n*\r\ninfo line\r\n\r\n3 landmarks:\r\nOuter left eye corner\r\n1.5 2 -3\r\n\r\nNose tip\r\n0 0 10.25\r\nOuter right eye corner\r\n-1.5 2 -3\r\n";

#[test]
fn parses_lm3_with_crlf_and_info_block() {
    let l = io::parse_lm3(LM3, "a.lm3").unwrap();
    assert_eq!(l.len(), 3);
    assert_eq!(l[0].0, "Outer left eye corner");
    assert_eq!(l[1].1, DVec3::new(0.0, 0.0, 10.25));
    assert_eq!(
        LandmarkName::parse(&l[2].0),
        Some(LandmarkName::OuterEyeRight)
    );
    // Missing inner corners: select_five names the missing one.
    let e = io::select_five(&l, "a.lm3").unwrap_err().to_string();
    assert!(e.contains("Inner right eye corner"), "{e}");
}

#[test]
fn lm3_errors_name_the_line() {
    let bad = "h\n\n2 landmarks:\nNose tip\n1 2 x\n";
    let e = io::parse_lm3(bad, "b.lm3").unwrap_err().to_string();
    assert!(e.starts_with("b.lm3:5:"), "{e}");
    let short = "h\n\n2 landmarks:\nNose tip\n1 2 3\n";
    assert!(io::parse_lm3(short, "c.lm3").is_err());
    assert!(io::parse_lm3("no count here", "d.lm3").is_err());
}

#[test]
fn ict_layout_and_kebab_names() {
    let text = r#"{"units": "cm", "faces": {"f1": {
        "right_eye_outer": [-4, 3, 8], "right_eye_inner": [-2, 3, 9],
        "left_eye_inner": [2, 3, 9], "left_eye_outer": [4, 3, 8], "nose_tip": [0, 0, 12]}}}"#;
    let m = io::parse_ict_landmarks(text, "l.json").unwrap();
    let f = m["f1"];
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
    assert!(io::parse_ict_landmarks(&broken, "l.json").is_err());
}
