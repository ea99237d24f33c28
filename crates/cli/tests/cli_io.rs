//! `bipolar info` and `bipolar convert` end to end.

use std::path::{Path, PathBuf};

mod common;
use common::{arg, bipolar};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(name)
}

fn info_json(path: &Path) -> serde_json::Value {
    let out = bipolar(&["info", arg(path), "--json"]).success();
    serde_json::from_str(&out.stdout).unwrap()
}

/// Two triangles as a soup (2 duplicate vertices), one degenerate face, an open strip: `name`
/// in `dir`.
fn soup(dir: &Path, name: &str) -> PathBuf {
    testsupport::cli::write_mesh(dir, name, &testsupport::shapes::triangle_soup())
}

#[test]
fn info_on_the_cube() {
    let j = info_json(&fixture("cube.obj"));
    assert_eq!(j["vertices"], 8);
    assert_eq!(j["faces"], 12);
    assert_eq!(j["edges"], 18);
    assert_eq!(j["components"], 1);
    assert_eq!(j["boundary_loops"], 0);
    assert_eq!(j["non_manifold_edges"], 0);
    assert_eq!(j["orientation_conflicts"], 0);
    assert_eq!(j["degenerate_faces"], 0);
    assert_eq!(j["duplicate_vertices"], 0);
    assert_eq!(j["bbox"]["max"], serde_json::json!([1.0, 1.0, 1.0]));
    // 12 unit edges and 6 diagonals, each in two faces: mean (12 + 6 sqrt 2) / 18.
    let mean = j["mean_edge_length"].as_f64().unwrap();
    assert!(
        (mean - (12.0 + 6.0 * 2f64.sqrt()) / 18.0).abs() < 1e-12,
        "{mean}"
    );
    let s = bipolar(&["info", arg(&fixture("cube.obj"))]).stdout;
    assert!(s.contains("vertices:              8"), "{s}");
}

#[test]
fn info_reports_defects_without_repairing() {
    let dir = tempfile::tempdir().unwrap();
    let p = soup(dir.path(), "bad.obj");
    let j = info_json(&p);
    assert_eq!(j["vertices"], 6);
    assert_eq!(j["duplicate_vertices"], 2);
    assert_eq!(j["degenerate_faces"], 1);
    assert_eq!(j["components"], 2);
    // Two open triangles; the degenerate face adds whatever meshcore makes of its edges.
    assert!(j["boundary_loops"].as_u64().unwrap() >= 2);
    assert_eq!(j["warnings"].as_array().unwrap().len(), 2);
}

#[test]
fn convert_between_formats_with_repairs() {
    let dir = tempfile::tempdir().unwrap();
    let src = soup(dir.path(), "soup.obj");
    let out = dir.path().join("clean.ply");
    bipolar(&[
        "convert",
        arg(&src),
        arg(&out),
        "--weld",
        "0",
        "--drop-degenerate",
    ])
    .success();
    let j = info_json(&out);
    assert_eq!(j["vertices"], 4);
    assert_eq!(j["faces"], 2);
    assert_eq!(j["components"], 1);
    assert_eq!(j["boundary_loops"], 1);
    assert_eq!(j["duplicate_vertices"], 0);
    // Chain through every writable format and back: the cube stays the cube.
    let mut prev = fixture("cube_ascii.ply");
    for ext in ["obj", "off", "stl", "glb", "ply"] {
        let next = dir.path().join(format!("cube.{ext}"));
        let r = bipolar(&["convert", arg(&prev), arg(&next)]);
        assert!(r.ok, "{ext}: {}", r.stderr);
        let j = info_json(&next);
        assert_eq!(j["faces"], 12, "{ext}");
        assert_eq!(j["vertices"], 8, "{ext}");
        assert_eq!(j["boundary_loops"], 0, "{ext}");
        prev = next;
    }
    // Colours survive PLY -> GLB -> PLY.
    let a = dir.path().join("c.glb");
    let b = dir.path().join("c.ply");
    bipolar(&["convert", arg(&fixture("cube_ascii.ply")), arg(&a)]).success();
    bipolar(&["convert", arg(&a), arg(&b), "--ascii"]).success();
    assert_eq!(info_json(&b)["has_colors"], true);
    let text = std::fs::read_to_string(&b).unwrap();
    assert!(text.starts_with("ply\nformat ascii"), "{text}");
}

#[test]
fn convert_bnt_to_obj() {
    let dir = tempfile::tempdir().unwrap();
    let (nr, nc) = (8usize, 9usize);
    let mut xyz = vec![meshcore::DVec3::splat(-1e9); nr * nc];
    for r in 1..7 {
        for c in 1..8 {
            xyz[r * nc + c] = meshcore::DVec3::new(c as f64, -(r as f64), 0.1 * (r * c) as f64);
        }
    }
    let g = mesh_io::BntGrid {
        nrows: nr,
        ncols: nc,
        zmin: -1e9,
        image_file: "x.png".into(),
        xyz,
        uv: vec![[0.0; 2]; nr * nc],
    };
    let src = dir.path().join("scan.bnt");
    std::fs::write(&src, g.to_bytes()).unwrap();
    let out = dir.path().join("scan.obj");
    bipolar(&["convert", arg(&src), arg(&out)]).success();
    let j = info_json(&out);
    assert_eq!(j["vertices"], 42);
    assert_eq!(j["faces"], 60);
    assert_eq!(j["boundary_loops"], 1);
}

#[test]
fn errors_name_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("broken.off");
    std::fs::write(&p, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n").unwrap();
    let e = bipolar(&["info", arg(&p)]).failure();
    assert!(
        e.contains("broken.off: line 6: vertex index 9 out of range"),
        "{e}"
    );
    let cube = fixture("cube.obj");
    let (bnt, ply) = (dir.path().join("x.bnt"), dir.path().join("x.ply"));
    bipolar(&["convert", arg(&cube), arg(&bnt)]).failure();
    bipolar(&["convert", arg(&cube), arg(&ply), "--weld", "-1"]).failure();
}
