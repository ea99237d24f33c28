//! End-to-end tests of the one reference-point parser: `describe --ref-a`, `render --ref-a`
//! and `geodesic --source` read vertex ids, `X,Y,Z` within a snapping tolerance of the surface
//! (farther is an error naming the distance and the tolerance) and landmark names from
//! `--landmarks FILE`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bipolar(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bipolar"))
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A unit icosphere (3 subdivisions, 642 vertices; bounding-box diagonal about 3.46) as OBJ.
fn sphere_obj(dir: &Path) -> PathBuf {
    let mesh = bipolar::synthetic::icosphere(3);
    let mut s = String::new();
    for p in mesh.positions() {
        s.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
    }
    for t in mesh.triangles() {
        s.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    let path = dir.join("sphere.obj");
    std::fs::write(&path, s).unwrap();
    path
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn a_far_point_is_rejected_with_its_distance_in_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let (csv, svg, txt) = (
        dir.path().join("d.csv"),
        dir.path().join("r.svg"),
        dir.path().join("g.txt"),
    );
    let runs = [
        bipolar(&[
            "describe",
            s(&obj),
            "--ref-a",
            "1e9,0,0",
            "--ref-b",
            "0",
            "--method",
            "dijkstra",
            "--out",
            s(&csv),
        ]),
        bipolar(&[
            "render",
            s(&obj),
            "--ref-a",
            "1e9,0,0",
            "--ref-b",
            "0",
            "--out",
            s(&svg),
        ]),
        bipolar(&["geodesic", s(&obj), "--source", "1e9,0,0", "--out", s(&txt)]),
        bipolar(&[
            "geodesic",
            s(&obj),
            "--source-point",
            "1e9,0,0",
            "--out",
            s(&txt),
        ]),
    ];
    for o in &runs {
        let e = stderr(o);
        assert!(!o.status.success(), "{e}");
        // The distance (1e9 - 1) and the tolerance (1 % of the diagonal, 0.0346...).
        assert!(
            e.contains("999999999.") && e.contains("farther than the tolerance 0.034"),
            "{e}"
        );
    }
    assert!(!csv.exists() && !svg.exists() && !txt.exists());
}

#[test]
fn a_near_point_is_accepted_and_the_tolerance_can_be_tightened() {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let csv = dir.path().join("d.csv");
    let run = |extra: &[&str]| {
        bipolar(
            &[
                &[
                    "describe",
                    s(&obj),
                    "--ref-a",
                    "0,0,1.01",
                    "--ref-b",
                    "1.01,0,0",
                ][..],
                &["--method", "dijkstra", "--levels", "5", "--out", s(&csv)],
                extra,
            ]
            .concat(),
        )
    };
    let o = run(&[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--ref-a: \"0,0,1.01\" snapped to face"),
        "{}",
        stderr(&o)
    );
    let o = run(&["--snap-tolerance", "0.001"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("farther than the tolerance"),
        "{}",
        stderr(&o)
    );
    let o = run(&["--snap-tolerance", "-1"]);
    assert!(!o.status.success());
}

#[test]
fn landmark_names_from_a_file_work_in_describe_render_and_geodesic() {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let lm3 = dir.path().join("given.lm3");
    std::fs::write(
        &lm3,
        "# test\n\n2 landmarks:\nOuter right eye corner\n0 0 1.01\nOuter left eye corner\n1.01 0 0\n",
    )
    .unwrap();
    let d = |name: &str| dir.path().join(name);
    // describe: the file's names give the same descriptor as the coordinates.
    let common = ["--method", "dijkstra", "--levels", "5"];
    let o = bipolar(
        &[
            &["describe", s(&obj), "--landmarks", s(&lm3)][..],
            &["--ref-a", "outer-eye-right", "--ref-b", "outer-eye-left"],
            &common,
            &["--out", s(&d("a.csv"))],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = bipolar(
        &[
            &[
                "describe",
                s(&obj),
                "--ref-a",
                "0,0,1.01",
                "--ref-b",
                "1.01,0,0",
            ][..],
            &common,
            &["--out", s(&d("b.csv"))],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let a = std::fs::read_to_string(d("a.csv")).unwrap();
    assert!(a.lines().count() > 5, "{a}");
    assert_eq!(a, std::fs::read_to_string(d("b.csv")).unwrap());
    // render: the names place both markers and curves.
    let o = bipolar(&[
        "render",
        s(&obj),
        "--landmarks",
        s(&lm3),
        "--ref-a",
        "outer-eye-right",
        "--ref-b",
        "Outer left eye corner",
        "--curves",
        "3",
        "--method",
        "dijkstra",
        "--out",
        s(&d("r.svg")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let svg = std::fs::read_to_string(d("r.svg")).unwrap();
    assert!(
        svg.contains("#d72828") && svg.contains("#1e5adc"),
        "both curve colours"
    );
    // geodesic: a landmark source equals the same point given as coordinates.
    let o = bipolar(&[
        "geodesic",
        s(&obj),
        "--landmarks",
        s(&lm3),
        "--source",
        "outer-eye-right",
        "--method",
        "dijkstra",
        "--out",
        s(&d("g1.txt")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = bipolar(&[
        "geodesic",
        s(&obj),
        "--source-point",
        "0,0,1.01",
        "--method",
        "dijkstra",
        "--out",
        s(&d("g2.txt")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let g1 = std::fs::read_to_string(d("g1.txt")).unwrap();
    assert_eq!(g1.lines().count(), 642);
    assert_eq!(g1, std::fs::read_to_string(d("g2.txt")).unwrap());
    // A name the file lacks is an error listing the file's labels.
    let o = bipolar(&[
        "geodesic",
        s(&obj),
        "--landmarks",
        s(&lm3),
        "--source",
        "nose-tip",
        "--out",
        s(&d("g3.txt")),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("Outer left eye corner"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn bad_option_names_list_the_valid_ones() {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let o = bipolar(&[
        "geodesic",
        s(&obj),
        "--source",
        "0",
        "--method",
        "mmp",
        "--out",
        "x.txt",
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("unknown geodesic method \"mmp\"; expected one of: exact, fmm, heat, dijkstra"),
        "{e}"
    );
    let o = bipolar(&[
        "describe",
        s(&obj),
        "--ref-a",
        "0",
        "--ref-b",
        "5",
        "--rule",
        "band",
        "--out",
        "x.csv",
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("filter, isoangle, all"),
        "{}",
        stderr(&o)
    );
}
