//! End-to-end tests of `bipolar geodesic`.

use std::path::Path;
use std::process::Command;

/// A flat 8 x 8 grid of unit cells in the plane z = 0, as OBJ text.
fn grid_obj(n: usize) -> String {
    let mut s = String::new();
    for j in 0..=n {
        for i in 0..=n {
            s.push_str(&format!("v {i} {j} 0\n"));
        }
    }
    let idx = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            s.push_str(&format!(
                "f {} {} {}\n",
                idx(i, j),
                idx(i + 1, j),
                idx(i + 1, j + 1)
            ));
            s.push_str(&format!(
                "f {} {} {}\n",
                idx(i, j),
                idx(i + 1, j + 1),
                idx(i, j + 1)
            ));
        }
    }
    s
}

fn bipolar(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_bipolar"))
        .arg("geodesic")
        .args(args)
        .output()
        .unwrap()
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
    let mesh = dir.path().join("grid.obj");
    std::fs::write(&mesh, grid_obj(8)).unwrap();
    let m = mesh.to_str().unwrap();
    let out = |name: &str| dir.path().join(name);

    // Dijkstra from vertex 0: along the bottom row the distance is the x coordinate.
    let txt = out("d.txt");
    let o = bipolar(&[
        m,
        "--source",
        "0",
        "--method",
        "dijkstra",
        "--out",
        txt.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d = read_txt(&txt);
    assert_eq!(d.len(), 81);
    for (i, di) in d.iter().enumerate().take(9) {
        assert!((di - i as f64).abs() < 1e-12);
    }

    // Fast marching, CSV.
    let csv = out("d.csv");
    let o = bipolar(&[
        m,
        "--source",
        "40",
        "--method",
        "fmm",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
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
    let o = bipolar(&[
        m,
        "--source-point",
        "2.5,3.25,0.7",
        // 0.7 off the plane is 6 % of its bounding-box diagonal (default tolerance 1 %).
        "--snap-tolerance",
        "0.1",
        "--method",
        "heat",
        "--out",
        npy.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
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
    let o = bipolar(&[
        m,
        "--source",
        "0",
        "--method",
        "fmm",
        "--max-distance",
        "3",
        "--out",
        ply.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
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
    let mesh = dir.path().join("grid.obj");
    std::fs::write(&mesh, grid_obj(2)).unwrap();
    let m = mesh.to_str().unwrap();
    let out = dir.path().join("d.txt");
    let o = out.to_str().unwrap();
    let e = bipolar(&[m, "--source", "99", "--method", "fmm", "--out", o]);
    assert!(!e.status.success());
    assert!(String::from_utf8_lossy(&e.stderr).contains("99"));
    let e = bipolar(&[m, "--source", "0", "--method", "fmm", "--out", "x.bin"]);
    assert!(!e.status.success());
    assert!(String::from_utf8_lossy(&e.stderr).contains("extension"));
    let e = bipolar(&[m, "--method", "fmm", "--out", o]);
    assert!(!e.status.success(), "a source is required");
    let e = bipolar(&[m, "--source", "0", "--method", "nope", "--out", o]);
    assert!(!e.status.success());
    let e = bipolar(&[
        m,
        "--source",
        "0",
        "--method",
        "fmm",
        "--max-distance",
        "-1",
        "--out",
        o,
    ]);
    assert!(!e.status.success());
    let e = bipolar(&["/nonexistent/mesh.obj", "--source", "0", "--out", o]);
    assert!(!e.status.success());
}
