//! `bipolar curves` and `bipolar curve-distance` end to end on ellipsoids.

use std::path::{Path, PathBuf};

mod common;

/// An ellipsoid (icosphere level 4 scaled by `axes`), rotated about z by `turn` radians, with
/// its vertices listed in reverse order when `reverse`; returns the OBJ text and the index of
/// the vertex at the top (+z).
fn ellipsoid_obj(axes: [f64; 3], turn: f64, reverse: bool) -> (String, usize) {
    let m = testsupport::shapes::icosphere(4);
    let n = m.n_vertices();
    let new = |v: usize| if reverse { n - 1 - v } else { v };
    let (s, c) = turn.sin_cos();
    let mut pos = vec![[0.0; 3]; n];
    let mut top = (f64::MIN, 0);
    for v in 0..n {
        let p = m.position(v as u32);
        let (x, y, z) = (p.x * axes[0], p.y * axes[1], p.z * axes[2]);
        pos[new(v)] = [c * x - s * y + 3.0, s * x + c * y - 1.0, z + 0.5];
        if z > top.0 {
            top = (z, new(v));
        }
    }
    let mut text = String::new();
    for p in &pos {
        text.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
    }
    for t in m.triangles() {
        let [a, b, c] = t.map(|v| new(v as usize) + 1);
        text.push_str(&format!("f {a} {b} {c}\n"));
    }
    (text, top.1)
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Runs the CLI: (success, stdout, stderr).
fn bipolar(args: &[&str]) -> (bool, String, String) {
    let r = common::bipolar(args);
    (r.ok, r.stdout, r.stderr)
}

/// Runs `bipolar curves MESH --kind KIND ARGS... --out OUT`: (success, stdout, stderr).
fn curves(mesh: &Path, kind: &str, args: &[&str], out: &Path) -> (bool, String, String) {
    let mut all = vec!["curves", mesh.to_str().unwrap(), "--kind", kind];
    all.extend_from_slice(args);
    all.extend(["--out", out.to_str().unwrap()]);
    bipolar(&all)
}

fn distance(a: &Path, b: &Path) -> f64 {
    let (ok, out, err) = bipolar(&["curve-distance", a.to_str().unwrap(), b.to_str().unwrap()]);
    assert!(ok, "{err}");
    out.trim().parse().unwrap()
}

#[test]
fn facial_and_iso_curvature_curves_are_invariant_and_discriminate() {
    let dir = tempfile::tempdir().unwrap();
    let shapes = [
        ("a.obj", ellipsoid_obj([3.0, 2.0, 1.5], 0.0, false)),
        ("moved.obj", ellipsoid_obj([3.0, 2.0, 1.5], 0.8, true)),
        ("other.obj", ellipsoid_obj([2.2, 2.0, 1.5], 0.0, false)),
    ];
    let mut facial = Vec::new();
    let mut iso = Vec::new();
    for (name, (text, top)) in &shapes {
        let mesh = write(dir.path(), name, text);
        let f = dir.path().join(format!("{name}.facial.json"));
        let nose = top.to_string();
        let (ok, _, err) = curves(
            &mesh,
            "facial",
            &["--nose", &nose, "--radius", "1.8", "--levels", "6"],
            &f,
        );
        assert!(ok, "{err}");
        assert!(err.contains("6 curves"), "{err}");
        match facecurves::io::read_json(&f).unwrap() {
            facecurves::io::CurveSet::Facial(d) => assert_eq!(d.curves.len(), 6),
            other => panic!("{other:?}"),
        }
        facial.push(f);
        let i = dir.path().join(format!("{name}.iso.json"));
        let (ok, _, err) = curves(
            &mesh,
            "iso-curvature",
            &["--k1-levels", "0.6,0.9", "--k2-levels", "0.3,0.45"],
            &i,
        );
        assert!(ok, "{err}");
        iso.push(i);
    }
    let (same, other) = (
        distance(&facial[0], &facial[1]),
        distance(&facial[0], &facial[2]),
    );
    assert!(same < 0.1 * other, "facial: moved {same}, other {other}");
    let (same, other) = (distance(&iso[0], &iso[1]), distance(&iso[0], &iso[2]));
    assert!(
        same < 1e-6 && other > 1e-3,
        "iso-curvature: moved {same}, other {other}"
    );
    // Mixed kinds are refused.
    let (ok, _, err) = bipolar(&[
        "curve-distance",
        facial[0].to_str().unwrap(),
        iso[0].to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("different curve kinds"), "{err}");
}

#[test]
fn facial_curves_need_a_radius_and_bad_kinds_are_listed() {
    let dir = tempfile::tempdir().unwrap();
    let (text, top) = ellipsoid_obj([1.0, 1.0, 1.0], 0.0, false);
    let mesh = write(dir.path(), "s.obj", &text);
    let out = dir.path().join("c.json");
    let (ok, _, err) = curves(&mesh, "facial", &["--nose", &top.to_string()], &out);
    assert!(!ok && err.contains("--radius"), "{err}");
    let (ok, _, err) = curves(&mesh, "spiral", &[], &out);
    assert!(
        !ok && err.contains("iso-curvature") && err.contains("facial"),
        "{err}"
    );
}
