//! End-to-end tests of the one reference-point parser: `describe --ref-a`, `render --ref-a`
//! and `geodesic --source` read vertex ids, `X,Y,Z` within a snapping tolerance of the surface
//! (farther is an error naming the distance and the tolerance) and landmark names from
//! `--landmarks FILE`.

use std::path::Path;

mod common;
use common::{arg as s, bipolar, sphere_obj};

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
        let e = &o.stderr;
        assert!(!o.ok, "{e}");
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
        let fixed = [
            "describe",
            s(&obj),
            "--ref-a",
            "0,0,1.01",
            "--ref-b",
            "1.01,0,0",
            "--method",
            "dijkstra",
            "--levels",
            "5",
            "--out",
            s(&csv),
        ];
        bipolar(&[&fixed[..], extra].concat())
    };
    let e = run(&[]).success().stderr;
    assert!(e.contains("--ref-a: \"0,0,1.01\" snapped to face"), "{e}");
    let e = run(&["--snap-tolerance", "0.001"]).failure();
    assert!(e.contains("farther than the tolerance"), "{e}");
    run(&["--snap-tolerance", "-1"]).failure();
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
    let (lm3, a_csv, b_csv, r_svg) = (s(&lm3), d("a.csv"), d("b.csv"), d("r.svg"));
    let (g1, g2, g3) = (d("g1.txt"), d("g2.txt"), d("g3.txt"));
    // describe: the file's names give the same descriptor as the coordinates; geodesic: a
    // landmark source equals the same point given as coordinates. (names, coordinates, the
    // common arguments, the two outputs).
    type Case<'a> = (&'a [&'a str], &'a [&'a str], &'a [&'a str], [&'a Path; 2]);
    let pairs: [Case; 2] = [
        (
            &[
                "--landmarks",
                lm3,
                "--ref-a",
                "outer-eye-right",
                "--ref-b",
                "outer-eye-left",
            ],
            &["--ref-a", "0,0,1.01", "--ref-b", "1.01,0,0"],
            &["describe", s(&obj), "--method", "dijkstra", "--levels", "5"],
            [&a_csv, &b_csv],
        ),
        (
            &["--landmarks", lm3, "--source", "outer-eye-right"],
            &["--source-point", "0,0,1.01"],
            &["geodesic", s(&obj), "--method", "dijkstra"],
            [&g1, &g2],
        ),
    ];
    let mut texts = Vec::new();
    for (names, coords, common, outs) in pairs {
        let [by_name, by_coords] = [(names, outs[0]), (coords, outs[1])].map(|(refs, out)| {
            bipolar(&[common, refs, &["--out", s(out)]].concat()).success();
            std::fs::read_to_string(out).unwrap()
        });
        assert_eq!(by_name, by_coords, "{common:?}");
        texts.push(by_name);
    }
    assert!(texts[0].lines().count() > 5, "{}", texts[0]);
    assert_eq!(texts[1].lines().count(), 642);
    // render: the names place both markers and curves.
    bipolar(&[
        "render",
        s(&obj),
        "--landmarks",
        lm3,
        "--ref-a",
        "outer-eye-right",
        "--ref-b",
        "Outer left eye corner",
        "--curves",
        "3",
        "--method",
        "dijkstra",
        "--out",
        s(&r_svg),
    ])
    .success();
    let svg = std::fs::read_to_string(&r_svg).unwrap();
    assert!(
        svg.contains("#d72828") && svg.contains("#1e5adc"),
        "both curve colours"
    );
    // A name the file lacks is an error listing the file's labels.
    let e = bipolar(&[
        "geodesic",
        s(&obj),
        "--landmarks",
        lm3,
        "--source",
        "nose-tip",
        "--out",
        s(&g3),
    ])
    .failure();
    assert!(e.contains("Outer left eye corner"), "{e}");
}

#[test]
fn bad_option_names_list_the_valid_ones() {
    let dir = tempfile::tempdir().unwrap();
    let obj = sphere_obj(dir.path());
    let cases: [(&[&str], &str); 2] = [
        (
            &[
                "geodesic",
                s(&obj),
                "--source",
                "0",
                "--method",
                "mmp",
                "--out",
                "x.txt",
            ],
            "unknown geodesic method \"mmp\"; expected one of: exact, fmm, heat, dijkstra",
        ),
        (
            &[
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
            ],
            "filter, isoangle, all",
        ),
    ];
    for (args, needle) in cases {
        let e = bipolar(args).failure();
        assert!(e.contains(needle), "{args:?}: {e}");
    }
}
