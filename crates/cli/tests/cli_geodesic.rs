//! End-to-end tests of `bipolar geodesic`.

use std::path::Path;

mod common;
use common::{arg, grid_obj, Run};

/// A flat `n x n` grid of unit cells in the plane z = 0 as `dir/grid.obj`.
fn unit_grid(dir: &Path, n: usize) -> std::path::PathBuf {
    grid_obj(dir, "grid.obj", n, 1.0)
}

fn geodesic(args: &[&str]) -> Run {
    common::bipolar_cmd("geodesic", args)
}

fn read_txt(p: &Path) -> Vec<f64> {
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect()
}

#[test]
fn writes_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = unit_grid(dir.path(), 8);
    let m = arg(&mesh);
    let out = |name: &str| dir.path().join(name);

    // Dijkstra from vertex 0: along the bottom row the distance is the x coordinate.
    let txt = out("d.txt");
    geodesic(&[
        m,
        "--source",
        "0",
        "--method",
        "dijkstra",
        "--out",
        arg(&txt),
    ])
    .success();
    let d = read_txt(&txt);
    assert_eq!(d.len(), 81);
    for (i, di) in d.iter().enumerate().take(9) {
        assert!((di - i as f64).abs() < 1e-12);
    }

    // Fast marching, CSV.
    let csv = out("d.csv");
    geodesic(&[m, "--source", "40", "--method", "fmm", "--out", arg(&csv)]).success();
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("vertex,distance"));
    let rows: Vec<(usize, f64)> = lines
        .map(|l| {
            let (a, b) = l.split_once(',').unwrap();
            (a.parse().unwrap(), b.parse().unwrap())
        })
        .collect();
    assert_eq!(rows.len(), 81);
    assert_eq!(rows[40], (40, 0.0));
    // Vertex 0 is at (0,0), the source (4,4): Euclidean sqrt(32).
    assert!((rows[0].1 - 32f64.sqrt()).abs() < 0.3, "{}", rows[0].1);

    // Heat method from a snapped surface point, NPY.
    let npy = out("d.npy");
    geodesic(&[
        m,
        "--source-point",
        "2.5,3.25,0.7",
        // 0.7 off the plane is 6 % of its bounding-box diagonal (default tolerance 1 %).
        "--snap-tolerance",
        "0.1",
        "--method",
        "heat",
        "--out",
        arg(&npy),
    ])
    .success();
    let bytes = std::fs::read(&npy).unwrap();
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    let hl = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + hl]).unwrap();
    assert!(
        header.contains("'<f8'") && header.contains("(81,)"),
        "{header}"
    );
    let vals: Vec<f64> = bytes[10 + hl..]
        .chunks(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(vals.len(), 81);
    // The far corner (8, 8) is at Euclidean distance |(5.5, 4.75)| from the snapped point
    // (2.5, 3.25, 0); the heat method is within about an edge length there (boundary corner).
    let far = 8 * 9 + 8;
    let e = (5.5f64 * 5.5 + 4.75 * 4.75).sqrt();
    assert!((vals[far] - e).abs() < 1.5, "{} vs {e}", vals[far]);
    assert!(vals.iter().all(|v| v.is_finite() && *v >= 0.0));

    // PLY with the field as a vertex property, with a cut-off.
    let ply = out("d.ply");
    geodesic(&[
        m,
        "--source",
        "0",
        "--method",
        "fmm",
        "--max-distance",
        "3",
        "--out",
        arg(&ply),
    ])
    .success();
    let back = mesh_io::read_mesh(&ply).unwrap();
    assert_eq!(back.mesh.n_vertices(), 81);
    let f = back
        .scalars
        .iter()
        .find(|s| s.name == "distance")
        .expect("distance property");
    assert_eq!(f.values[0], 0.0);
    assert!((f.values[2] - 2.0).abs() < 1e-12);
    assert!(f.values[80].is_infinite());
}

#[test]
fn reports_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = unit_grid(dir.path(), 2);
    let m = arg(&mesh);
    let out = dir.path().join("d.txt");
    let o = arg(&out);
    // (arguments, what the error names if anything)
    let cases: [(&[&str], &str); 6] = [
        (&[m, "--source", "99", "--method", "fmm", "--out", o], "99"),
        (
            &[m, "--source", "0", "--method", "fmm", "--out", "x.bin"],
            "extension",
        ),
        // A source is required.
        (&[m, "--method", "fmm", "--out", o], ""),
        (&[m, "--source", "0", "--method", "nope", "--out", o], ""),
        (
            &[
                m,
                "--source",
                "0",
                "--method",
                "fmm",
                "--max-distance",
                "-1",
                "--out",
                o,
            ],
            "",
        ),
        (&["/nonexistent/mesh.obj", "--source", "0", "--out", o], ""),
    ];
    for (args, needle) in cases {
        let e = geodesic(args).failure();
        assert!(e.contains(needle), "{args:?}: {e}");
    }
}
