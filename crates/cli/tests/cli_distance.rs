//! `bipolar distance` and `bipolar matrix` end to end on small descriptor CSV files.

use std::path::{Path, PathBuf};

const HEADER: &str = "x,y,z,a,b,i,j,side,sign,cos,ambiguous";

/// A non-symmetric smooth patch; key (0, 1, i, j, side, 0) per grid point.
fn patch() -> Vec<([f64; 3], [i64; 6])> {
    let mut out = Vec::new();
    for i in 0..14 {
        for j in 0..11 {
            let (x, y) = (i as f64 * 0.1 - 0.7, j as f64 * 0.1 - 0.5);
            let z = 0.3 * (1.0 - x * x - y * y) + 0.15 * (-(x - 0.3f64).powi(2) * 8.0).exp() * y;
            let side = if x < 0.0 { -1 } else { 1 };
            out.push(([x, y, z], [0, 1, i, j, side, 0]));
        }
    }
    out
}

fn rot(axis: [f64; 3], deg: f64, p: [f64; 3]) -> [f64; 3] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let k = [axis[0] / n, axis[1] / n, axis[2] / n];
    let (s, c) = deg.to_radians().sin_cos();
    let dot = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
    let cr = [
        k[1] * p[2] - k[2] * p[1],
        k[2] * p[0] - k[0] * p[2],
        k[0] * p[1] - k[1] * p[0],
    ];
    std::array::from_fn(|i| p[i] * c + cr[i] * s + k[i] * dot * (1.0 - c))
}

fn write(dir: &Path, name: &str, pts: &[([f64; 3], [i64; 6])], ambiguous: &[usize]) -> PathBuf {
    let mut s = String::from(HEADER);
    s.push('\n');
    for (n, (p, k)) in pts.iter().enumerate() {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},0.5,{}\n",
            p[0],
            p[1],
            p[2],
            k[0],
            k[1],
            k[2],
            k[3],
            k[4],
            k[5],
            u8::from(ambiguous.contains(&n))
        ));
    }
    let path = dir.join(name);
    std::fs::write(&path, s).unwrap();
    path
}

mod common;

/// (success, stdout, stderr) of one run of `bipolar`.
fn bipolar(args: &[&str]) -> (bool, String, String) {
    let r = common::bipolar(args);
    (r.ok, r.stdout, r.stderr)
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

#[test]
fn rotated_shuffled_copy_is_at_distance_zero_in_every_mode() {
    let dir = tempfile::tempdir().unwrap();
    let a = patch();
    let mut b: Vec<_> = a
        .iter()
        .map(|(q, k)| {
            let r = rot([0.2, -1.0, 0.4], 170.0, *q);
            ([r[0] + 5.0, r[1], r[2] - 2.0], *k)
        })
        .collect();
    b.reverse();
    let fa = write(dir.path(), "a.csv", &a, &[]);
    let fb = write(dir.path(), "b.csv", &b, &[]);
    for mode in ["keys", "icp", "hausdorff"] {
        let (ok, out, err) = bipolar(&["distance", p(&fa), p(&fb), "--mode", mode]);
        assert!(ok, "{mode}: {err}");
        let d: f64 = out.trim().parse().unwrap();
        assert!((0.0..1e-6).contains(&d), "{mode}: {d}");
    }
    let (ok, out, err) = bipolar(&["distance", p(&fa), p(&fb), "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["shared_keys"], a.len());
    assert_eq!(v["share_a"], 1.0);
    assert!(v["rotation"][2][2].as_f64().is_some());
    assert!(v["distance"].as_f64().unwrap() < 1e-9);
}

#[test]
fn ambiguous_points_are_ignored_and_a_mirror_image_is_not_a_rotation() {
    let dir = tempfile::tempdir().unwrap();
    let a = patch();
    let m: Vec<_> = a.iter().map(|(q, k)| ([-q[0], q[1], q[2]], *k)).collect();
    let fa = write(dir.path(), "a.csv", &a, &[0, 1, 2]);
    let fm = write(dir.path(), "m.csv", &m, &[]);
    let (ok, out, err) = bipolar(&["distance", p(&fa), p(&fm), "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["shared_keys"], a.len() - 3);
    assert!(v["distance"].as_f64().unwrap() > 0.05, "{out}");
}

#[test]
fn matrix_is_symmetric_with_zero_diagonal_and_heatmap_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let a = patch();
    let files: Vec<PathBuf> = (0..3)
        .map(|n| {
            let s: Vec<_> = a
                .iter()
                .map(|(q, k)| {
                    let r = rot([1.0, n as f64, 0.5], 40.0 * n as f64, *q);
                    ([r[0], r[1], r[2] * (1.0 + 0.2 * n as f64)], *k)
                })
                .collect();
            write(dir.path(), &format!("face{n}.csv"), &s, &[])
        })
        .collect();
    let out = dir.path().join("m.csv");
    let svg = dir.path().join("m.svg");
    let mut args = vec!["matrix"];
    args.extend(files.iter().map(|f| p(f)));
    args.extend(["--out", p(&out), "--heatmap", p(&svg)]);
    let (ok, _, err) = bipolar(&args);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    let rows: Vec<Vec<String>> = text
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows[0], ["label", "face0", "face1", "face2"]);
    let m: Vec<Vec<f64>> = rows[1..]
        .iter()
        .map(|r| r[1..].iter().map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(m.len(), 3);
    for (i, row) in m.iter().enumerate() {
        assert_eq!(row[i], 0.0);
        for (j, v) in row.iter().enumerate() {
            assert_eq!(*v, m[j][i]);
        }
    }
    // More z-stretch, larger distance from face0.
    assert!(m[0][1] > 1e-3 && m[0][2] > m[0][1], "{m:?}");
    let svg_text = std::fs::read_to_string(&svg).unwrap();
    assert!(svg_text.contains("<svg") && svg_text.contains("face2"));
}

#[test]
fn bad_input_fails_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let a = patch();
    let fa = write(dir.path(), "a.csv", &a, &[]);
    let few: Vec<_> = a.iter().take(2).cloned().collect();
    let ff = write(dir.path(), "few.csv", &few, &[]);
    let (ok, _, err) = bipolar(&["distance", p(&fa), p(&ff)]);
    assert!(!ok);
    assert!(err.contains("shared keys"), "{err}");
    let missing = dir.path().join("nope.csv");
    let (ok, _, err) = bipolar(&["distance", p(&fa), p(&missing)]);
    assert!(!ok);
    assert!(err.contains("nope.csv"), "{err}");
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, format!("{HEADER}\n1,2,nan_here,0,1,0,0,1,0,0.5,0\n")).unwrap();
    let (ok, _, err) = bipolar(&["distance", p(&fa), p(&bad)]);
    assert!(!ok);
    assert!(err.contains("line 2"), "{err}");
}

/// The patch with its z stretched by `1 + s`, turned by `deg` about a fixed axis.
fn stretched(s: f64, deg: f64) -> Vec<([f64; 3], [i64; 6])> {
    patch()
        .iter()
        .map(|(q, k)| {
            (
                rot([0.3, 1.0, -0.2], deg, [q[0], q[1], q[2] * (1.0 + s)]),
                *k,
            )
        })
        .collect()
}

/// The number printed by a successful `bipolar distance`.
fn distance(args: &[&str]) -> f64 {
    let (ok, out, err) = bipolar(&[&["distance"][..], args].concat());
    assert!(ok, "{err}");
    out.trim().parse().unwrap()
}

#[test]
fn searched_distances_take_the_least_over_each_sides_moved_descriptors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // a and b differ; b's moved descriptors hold a turned copy of a, so the search finds it.
    let fa = write(d, "a.csv", &stretched(0.0, 0.0), &[]);
    let fb = write(d, "b.csv", &stretched(0.4, 10.0), &[]);
    write(d, "b.search-01.csv", &stretched(0.3, 20.0), &[]);
    write(d, "b.search-02.csv", &stretched(0.0, 30.0), &[]);
    let plain = distance(&[p(&fa), p(&fb)]);
    assert!(plain > 1e-3, "{plain}");
    let searched = distance(&[p(&fa), p(&fb), "--searched"]);
    assert!(searched < 1e-9, "{searched}");
    assert!(distance(&[p(&fb), p(&fa), "--searched"]) < 1e-9);
    let (ok, out, err) = bipolar(&["distance", p(&fa), p(&fb), "--searched", "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["searched"]["b_moved"], 2);
    assert_eq!(v["searched"]["a_moved"], 0);
    assert_eq!(v["b"], "b.search-02", "{out}");
    // Moved against moved is not compared: c's moved copy equals b's first one, but the
    // searched distance of b and c stays the least of own and one-sided moved distances.
    let fc = write(d, "c.csv", &stretched(0.8, 0.0), &[]);
    write(d, "c.search-01.csv", &stretched(0.3, 20.0), &[]);
    let bc = distance(&[p(&fb), p(&fc), "--searched"]);
    let one_sided = [
        distance(&[p(&fb), p(&fc)]),
        distance(&[p(&d.join("b.search-01.csv")), p(&fc)]),
        distance(&[p(&d.join("b.search-02.csv")), p(&fc)]),
        distance(&[p(&fb), p(&d.join("c.search-01.csv"))]),
    ];
    assert_eq!(bc, one_sided.into_iter().fold(f64::INFINITY, f64::min));
    assert!(bc > 1e-3, "{bc}");

    // The matrix: listed search files fold into their own file's row; entries as `distance`.
    let out = d.join("m.csv");
    let (ok, _, err) = bipolar(&[
        "matrix",
        p(&fa),
        p(&fb),
        p(&d.join("b.search-01.csv")),
        p(&fc),
        "--searched",
        "--out",
        p(&out),
    ]);
    assert!(ok, "{err}");
    assert!(
        err.contains("3 moved descriptors beside 2 of the 3 files"),
        "{err}"
    );
    let text = std::fs::read_to_string(&out).unwrap();
    let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows[0], ["label", "a", "b", "c"]);
    let m = |i: usize, j: usize| -> f64 { rows[i + 1][j + 1].parse().unwrap() };
    assert!(m(0, 1) < 1e-9 && m(1, 0) < 1e-9, "{text}");
    assert!((m(1, 2) - bc).abs() <= 1e-12 * bc, "{text}");
    assert_eq!(m(0, 2), distance(&[p(&fa), p(&fc), "--searched"]));
    // Without --searched the listed search file is a row of its own.
    let (ok, _, err) = bipolar(&[
        "matrix",
        p(&fa),
        p(&fb),
        p(&d.join("b.search-01.csv")),
        "--out",
        p(&out),
    ]);
    assert!(ok, "{err}");
    assert!(std::fs::read_to_string(&out)
        .unwrap()
        .starts_with("label,a,b,b.search-01\n"));
    // No search files anywhere: an error naming what is missing.
    let fe = write(d, "e.csv", &stretched(0.1, 0.0), &[]);
    let (ok, _, err) = bipolar(&["distance", p(&fa), p(&fe), "--searched"]);
    assert!(!ok && err.contains("STEM.search-NN.EXT"), "{err}");
    let (ok, _, err) = bipolar(&["matrix", p(&fa), p(&fe), "--searched", "--out", p(&out)]);
    assert!(!ok && err.contains("no moved descriptors"), "{err}");
}
