//! `bipolar render` end to end: SVG/PNG/GLB output, field colours, level curves, descriptor
//! points, errors.

use std::fmt::Write as _;
use std::path::PathBuf;

mod common;
use common::{arg as s, bipolar};

struct Fixture {
    dir: tempfile::TempDir,
    mesh: PathBuf,
    /// The y coordinate of every vertex.
    y: Vec<f64>,
}

/// A UV sphere of radius 1 (16 bands, 32 sectors, poles on the y axis, vertex 0 the north
/// pole) as OBJ.
fn fixture() -> Fixture {
    let dir = tempfile::tempdir().unwrap();
    let sphere = testsupport::uv_sphere_y_up(1.0, 16, 32);
    let mesh = testsupport::cli::write_mesh(dir.path(), "sphere.obj", &sphere);
    let y = sphere.positions().iter().map(|p| p.y).collect();
    Fixture { dir, mesh, y }
}

#[test]
fn renders_mesh_png_and_svg() {
    let fx = fixture();
    let png = fx.dir.path().join("a.png");
    bipolar(&[
        "render",
        s(&fx.mesh),
        "--width",
        "120",
        "--height",
        "90",
        "--out",
        s(&png),
    ])
    .success();
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 120);
    assert_eq!(u32::from_be_bytes(bytes[20..24].try_into().unwrap()), 90);
    let svg = fx.dir.path().join("a.svg");
    bipolar(&["render", s(&fx.mesh), "--view", "top", "--out", s(&svg)]).success();
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
    for y in &fx.y {
        let _ = writeln!(t, "{y}");
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
    let with_field = ["render", s(&fx.mesh), "--field", s(&field)];
    bipolar(
        &[
            &with_field[..],
            &["--curves", "3", "--descriptor", s(&desc), "--out", s(&svg)],
        ]
        .concat(),
    )
    .success();
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
    let e = bipolar(&[&with_field[..], &["--out", s(&svg)]].concat()).failure();
    assert!(e.contains("values for a mesh of"));
}

#[test]
fn reference_level_curves_and_glb() {
    let fx = fixture();
    let svg = fx.dir.path().join("r.svg");
    let glb = fx.dir.path().join("r.glb");
    // Reference points at the north pole (vertex 0) and on the equator facing the viewer.
    let refs = [
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
    ];
    for out in [&svg, &glb] {
        bipolar(&[&refs[..], &["--out", s(out)]].concat()).success();
    }
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        text.contains("#d72828") && text.contains("#1e5adc"),
        "both curve colours"
    );
    assert!(
        text.matches("<circle").count() >= 2,
        "both reference markers"
    );
    let bytes = std::fs::read(&glb).unwrap();
    assert_eq!(&bytes[..4], b"glTF");
    // Errors: one reference only, unknown extension, bad view.
    bipolar(&["render", s(&fx.mesh), "--ref-a", "0", "--out", s(&svg)]).failure();
    let e = bipolar(&["render", s(&fx.mesh), "--out", "x.bmp"]).failure();
    assert!(e.contains("expected .svg, .png or .glb"));
    bipolar(&[
        "render",
        s(&fx.mesh),
        "--view",
        "sideways",
        "--out",
        s(&svg),
    ])
    .failure();
}
