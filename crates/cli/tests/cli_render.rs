//! `bipolar render` end to end: SVG/PNG/GLB output, field colours, level curves, descriptor
//! points, errors.

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

/// UV sphere of radius 1 as OBJ text (outward faces). Returns (text, vertex count, y of each
/// vertex).
fn sphere_obj(n_lat: usize, n_lon: usize) -> (String, Vec<[f64; 3]>) {
    let mut pos = vec![[0.0, 1.0, 0.0]];
    for i in 1..n_lat {
        let th = PI * i as f64 / n_lat as f64;
        for j in 0..n_lon {
            let ph = TAU * j as f64 / n_lon as f64;
            pos.push([th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()]);
        }
    }
    pos.push([0.0, -1.0, 0.0]);
    let south = pos.len();
    let ring = |i: usize, j: usize| 2 + (i - 1) * n_lon + j % n_lon; // 1-based
    let mut s = String::new();
    for p in &pos {
        let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
    }
    for j in 0..n_lon {
        let _ = writeln!(s, "f 1 {} {}", ring(1, j + 1), ring(1, j));
        let _ = writeln!(
            s,
            "f {south} {} {}",
            ring(n_lat - 1, j),
            ring(n_lat - 1, j + 1)
        );
    }
    for i in 1..n_lat - 1 {
        for j in 0..n_lon {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            let _ = writeln!(s, "f {a} {b} {d}");
            let _ = writeln!(s, "f {a} {d} {c}");
        }
    }
    (s, pos)
}

struct Fixture {
    dir: tempfile::TempDir,
    mesh: PathBuf,
    pos: Vec<[f64; 3]>,
}

fn fixture() -> Fixture {
    let dir = tempfile::tempdir().unwrap();
    let (obj, pos) = sphere_obj(16, 32);
    let mesh = dir.path().join("sphere.obj");
    std::fs::write(&mesh, obj).unwrap();
    Fixture { dir, mesh, pos }
}

fn bipolar(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_bipolar"))
        .args(args)
        .output()
        .expect("running bipolar")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn renders_mesh_png_and_svg() {
    let fx = fixture();
    let png = fx.dir.path().join("a.png");
    let out = bipolar(&[
        "render",
        s(&fx.mesh),
        "--width",
        "120",
        "--height",
        "90",
        "--out",
        s(&png),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 120);
    assert_eq!(u32::from_be_bytes(bytes[20..24].try_into().unwrap()), 90);
    let svg = fx.dir.path().join("a.svg");
    let out = bipolar(&["render", s(&fx.mesh), "--view", "top", "--out", s(&svg)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") && text.contains("<polygon"));
    assert!(!text.contains("<polyline"));
}

#[test]
fn field_curves_and_descriptor_points() {
    let fx = fixture();
    // Field = y: horizontal circles as level curves, visible from the front.
    let field = fx.dir.path().join("y.txt");
    let mut t = String::new();
    for p in &fx.pos {
        let _ = writeln!(t, "{}", p[1]);
    }
    std::fs::write(&field, t).unwrap();
    // Two descriptor points, one in front (z = +1, drawn), one behind (z = -1, hidden).
    let desc = fx.dir.path().join("d.csv");
    std::fs::write(
        &desc,
        "x,y,z,a,b,i,j,side,sign,cos,ambiguous\n0,0,1,0,1,1,1,1,1,0.5,0\n0,0,-1,0,1,2,2,-1,1,0.5,0\n",
    )
    .unwrap();
    let svg = fx.dir.path().join("f.svg");
    let out = bipolar(&[
        "render",
        s(&fx.mesh),
        "--field",
        s(&field),
        "--curves",
        "3",
        "--descriptor",
        s(&desc),
        "--out",
        s(&svg),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        text.matches("<polyline").count() >= 3,
        "three level circles"
    );
    assert_eq!(
        text.matches("<circle").count(),
        1,
        "only the front point is visible"
    );
    // Field of the wrong length: clear error.
    std::fs::write(&field, "1\n2\n").unwrap();
    let out = bipolar(&[
        "render",
        s(&fx.mesh),
        "--field",
        s(&field),
        "--out",
        s(&svg),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("values for a mesh of"));
}

#[test]
fn reference_level_curves_and_glb() {
    let fx = fixture();
    let svg = fx.dir.path().join("r.svg");
    // Reference points at the north pole (vertex 0) and on the equator facing the viewer.
    let out = bipolar(&[
        "render",
        s(&fx.mesh),
        "--ref-a",
        "0",
        "--ref-b",
        "0,0,1",
        "--curves",
        "4",
        "--method",
        "dijkstra",
        "--out",
        s(&svg),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        text.contains("#d72828") && text.contains("#1e5adc"),
        "both curve colours"
    );
    assert!(
        text.matches("<circle").count() >= 2,
        "both reference markers"
    );
    let glb = fx.dir.path().join("r.glb");
    let out = bipolar(&[
        "render",
        s(&fx.mesh),
        "--ref-a",
        "0",
        "--ref-b",
        "0,0,1",
        "--curves",
        "4",
        "--method",
        "dijkstra",
        "--out",
        s(&glb),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&glb).unwrap();
    assert_eq!(&bytes[..4], b"glTF");
    // Errors: one reference only, unknown extension, bad view.
    let out = bipolar(&["render", s(&fx.mesh), "--ref-a", "0", "--out", s(&svg)]);
    assert!(!out.status.success());
    let out = bipolar(&["render", s(&fx.mesh), "--out", "x.bmp"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("expected .svg, .png or .glb"));
    let out = bipolar(&[
        "render",
        s(&fx.mesh),
        "--view",
        "sideways",
        "--out",
        s(&svg),
    ]);
    assert!(!out.status.success());
}
