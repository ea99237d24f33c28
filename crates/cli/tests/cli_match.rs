//! `bipolar enroll`, `identify` and `verify` end to end on scans made by `bipolar scan`.

mod common;

use common::bipolar_cmd;

#[test]
fn enrol_identify_and_verify_scans_of_paper_faces() {
    let Some(faces) = testsupport::paper_meshes(["id1_neutral.obj", "id2_neutral.obj"]) else {
        return;
    };
    drop(faces);
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let face = |n: &str| {
        testsupport::paper_face(n)
            .unwrap()
            .to_str()
            .unwrap()
            .to_string()
    };
    // Two neutral gallery scans (one identity each), a probe of person 1 turned by 20 degrees.
    for (src, out, yaw, seed) in [
        ("id1_neutral.obj", "id1-e0.bnt", "0", "1"),
        ("id2_neutral.obj", "id2-e0.bnt", "0", "2"),
        ("id1_happiness.obj", "probe.bnt", "20", "3"),
    ] {
        bipolar_cmd(
            "scan",
            &[&face(src), "--out", &p(out), "--yaw", yaw, "--seed", seed],
        )
        .success();
    }
    let gallery = p("gallery");
    let r = bipolar_cmd(
        "enroll",
        &[
            &p("id1-e0.bnt"),
            &p("id2-e0.bnt"),
            "--out",
            &gallery,
            "--identity-from",
            r"^(id\d+)-",
        ],
    )
    .success();
    assert!(r.stdout.contains("enrolled 2 of 2 scans"), "{}", r.stdout);
    assert!(dir.path().join("gallery/id1-e0.bpt").is_file());
    let r = bipolar_cmd(
        "identify",
        &[&p("probe.bnt"), "--gallery", &gallery, "--json"],
    )
    .success();
    let j: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    let ranking = j["ranking"].as_array().unwrap();
    assert_eq!(ranking.len(), 2);
    assert_eq!(ranking[0]["identity"], "id1", "{}", r.stdout);
    assert_eq!(ranking[0]["template"], "id1-e0.bnt");
    assert!(ranking[0]["score"].as_f64().unwrap() < ranking[1]["score"].as_f64().unwrap());
    assert_eq!(
        ranking[0]["comparison"]["view"]["kind"], "matched",
        "{}",
        r.stdout
    );
    // The ranking is the library's, as the benchmark (`cargo xtask match-eval`) computes it:
    // the same identities in the same order with the same scores.
    let o = facematch::MatchOptions::default();
    let lib_gallery = facematch::Gallery::open(std::path::Path::new(&gallery), &o).unwrap();
    let grid = mesh_io::read_bnt_grid(p("probe.bnt")).unwrap();
    let probe = facematch::prepare(facematch::ScanInput::Grid(&grid), &o)
        .unwrap()
        .describe(&o, true)
        .unwrap();
    let lib = lib_gallery.identify(&probe, &o);
    assert_eq!(lib.len(), ranking.len());
    for (l, c) in lib.iter().zip(ranking) {
        assert_eq!(c["identity"], l.identity.as_str());
        assert_eq!(c["score"].as_f64().unwrap(), l.score, "{}", l.identity);
    }
    // --top 1 and the text form.
    let r = bipolar_cmd(
        "identify",
        &[&p("probe.bnt"), "--gallery", &gallery, "--top", "1"],
    )
    .success();
    assert_eq!(r.stdout.lines().count(), 1, "{}", r.stdout);
    assert!(r.stdout.contains("id1"));
    // Verify: a scan against a template; the score on the first line.
    let r = bipolar_cmd(
        "verify",
        &[&p("probe.bnt"), &p("gallery/id1-e0.bpt"), "--json"],
    )
    .success();
    let j: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    let s = j["score"].as_f64().unwrap();
    assert_eq!(
        j["same"].as_bool().unwrap(),
        s <= j["threshold"].as_f64().unwrap()
    );
    let r = bipolar_cmd("verify", &[&p("probe.bnt"), &p("gallery/id1-e0.bpt")]).success();
    let first: f64 = r.stdout.lines().next().unwrap().parse().unwrap();
    assert!((first - s).abs() < 1e-6, "{first} vs {s}");
    // Bad input: a gallery with no templates, a probe that is not a face.
    std::fs::create_dir(dir.path().join("empty")).unwrap();
    let e = bipolar_cmd("identify", &[&p("probe.bnt"), "--gallery", &p("empty")]).failure();
    assert!(e.contains("no templates"), "{e}");
}

#[test]
fn enrolling_a_non_face_says_no_face_was_found() {
    let dir = tempfile::tempdir().unwrap();
    let sphere = common::sphere_obj(dir.path());
    let out = dir.path().join("g");
    let e = bipolar_cmd(
        "enroll",
        &[sphere.to_str().unwrap(), "--out", out.to_str().unwrap()],
    )
    .failure();
    assert!(
        e.contains("not enrolled") && e.contains("sphere.obj"),
        "{e}"
    );
}

#[test]
fn identify_ranks_the_benchmarks_own_scans_as_the_benchmark() {
    let model = testsupport::require_shared!(testsupport::MODEL);
    let dir = tempfile::tempdir().unwrap();
    let (scans, out) = (dir.path().join("scans"), dir.path().join("bench"));
    // The scan benchmark on 2 identities (a neutral frontal gallery scan each, one turned probe
    // each), writing its raw scans.
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let (model, scans_s, out_s) = (s(&model), s(&scans), s(&out));
    let args: experiments::recognition::Args = experiments::parse_args(&[
        "recognition",
        "--scans",
        "--identities",
        "2",
        "--expressions",
        "2",
        "--no-sweeps",
        "--model",
        &model,
        "--out",
        &out_s,
        "--save-scans",
        &scans_s,
    ]);
    experiments::recognition::run(args).unwrap();
    // Its bipolar distances with the detected landmarks (the path a user's scan takes): per
    // probe and gallery identity, the three pairs' distances; the score is their least.
    let text = std::fs::read_to_string(out.join("bipolar-pairs.csv")).unwrap();
    let mut bench: std::collections::BTreeMap<String, Vec<(String, f64)>> = Default::default();
    for line in text.lines().skip(1) {
        let c: Vec<&str> = line.split(',').collect();
        if c[2] != "detected" {
            continue;
        }
        let d: Vec<f64> = c[5..8].iter().map(|x| x.parse().unwrap()).collect();
        let score = d.iter().copied().fold(f64::INFINITY, f64::min);
        let gallery = format!("id{:02}", c[4].parse::<usize>().unwrap());
        bench
            .entry(c[0].to_string())
            .or_default()
            .push((gallery, score));
    }
    assert_eq!(bench.len(), 2, "{text}");
    // The same scans through the CLI.
    let gallery = s(&dir.path().join("gallery"));
    let mut enroll: Vec<String> = (0..2)
        .map(|i| s(&scans.join(format!("id{i:02}-e0.bnt"))))
        .collect();
    enroll.extend([
        "--out".into(),
        gallery.clone(),
        "--identity-from".into(),
        r"^(id\d+)-".into(),
    ]);
    let r = bipolar_cmd(
        "enroll",
        &enroll.iter().map(String::as_str).collect::<Vec<_>>(),
    )
    .success();
    assert!(r.stdout.contains("enrolled 2 of 2 scans"), "{}", r.stdout);
    for (probe, mut scores) in bench {
        let r = bipolar_cmd(
            "identify",
            &[
                &s(&scans.join(format!("{probe}.bnt"))),
                "--gallery",
                &gallery,
                "--json",
            ],
        )
        .success();
        let j: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
        let ranking = j["ranking"].as_array().unwrap();
        scores.sort_by(|a, b| a.1.total_cmp(&b.1));
        let cli: Vec<(String, f64)> = ranking
            .iter()
            .map(|x| {
                (
                    x["identity"].as_str().unwrap().to_string(),
                    x["score"].as_f64().unwrap(),
                )
            })
            .collect();
        assert_eq!(
            cli.iter().map(|x| &x.0).collect::<Vec<_>>(),
            scores.iter().map(|x| &x.0).collect::<Vec<_>>(),
            "{probe}: identify {cli:?}, the benchmark {scores:?}"
        );
        // The benchmark writes 6 decimals.
        for ((_, a), (_, b)) in cli.iter().zip(&scores) {
            assert!(
                (a - b).abs() < 1e-6,
                "{probe}: identify {cli:?}, the benchmark {scores:?}"
            );
        }
    }
}
