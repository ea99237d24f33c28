use super::{run, Args};

#[test]
fn detect_only_writes_one_row_per_scan_and_stops() {
    let model = testsupport::require_shared!(testsupport::MODEL);
    let out = std::env::temp_dir().join(format!("bipolar-detect-only-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let (model, dir) = (model.display().to_string(), out.display().to_string());
    let args = |extra: &[&str]| {
        let base = [
            "recognition",
            "--scans",
            "--identities",
            "2",
            "--expressions",
            "2",
            "--no-sweeps",
            "--detect-only",
            "--model",
            &model,
            "--out",
            &dir,
        ];
        crate::parse_args::<Args>(&[&base[..], extra].concat())
    };
    run(args(&[])).unwrap();
    let text = std::fs::read_to_string(out.join("detection.csv")).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    // Two gallery scans, then two probes, in order; nothing described or compared.
    let names: Vec<&str> = rows.iter().map(|r| r[0]).collect();
    assert_eq!(names[..2], ["id00-e0", "id01-e0"], "{text}");
    assert_eq!(rows.len(), 4, "{text}");
    assert!(names[2].starts_with("id00-e1-yaw") && names[3].starts_with("id01-e1-yaw"));
    // The frontal gallery scans: found, every landmark within 5 mm of its ground truth.
    for r in &rows[..2] {
        assert_eq!(r[3], "found", "{text}");
        for e in &r[4..7] {
            let e: f64 = e.parse().unwrap();
            assert!((0.0..5.0).contains(&e), "{text}");
        }
    }
    // The report: the yaw table and its two figures; nothing of a full run.
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("landmarks found on") && md.contains("| yaw bin"),
        "{md}"
    );
    for f in ["detection-error-yaw.svg", "detection-placed-yaw.svg"] {
        assert!(out.join(f).exists(), "{f}");
    }
    assert!(!out.join("probes.csv").exists() && !out.join("summary.json").exists());
    // `--only-identities 1`: identity 1's scans alone, with the whole run's seeds, yaws and
    // noises (the same rows byte for byte).
    let only = args(&["--only-identities", "1"]);
    run(only.clone()).unwrap();
    let again = std::fs::read_to_string(out.join("detection.csv")).unwrap();
    let id1: Vec<&str> = text.lines().filter(|l| l.starts_with("id01")).collect();
    let got: Vec<&str> = again.lines().skip(1).collect();
    assert_eq!(got, id1);
    // An identity the run does not have is an error naming it.
    let e = run(Args {
        only_identities: vec![2],
        ..only
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("--only-identities 2"), "{e}");
    // So is a probe name the run does not have.
    let e = run(args(&["--only-probes", "id05"]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("no probe left") && e.contains("id05"), "{e}");
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn runs_need_two_identities_and_two_expressions() {
    let parse = |extra: &[&str]| crate::parse_args::<Args>(&[&["recognition"], extra].concat());
    assert_eq!(parse(&[]).sizes((16, 3)).unwrap(), (16, 3));
    assert_eq!(
        parse(&["--identities", "4"]).sizes((50, 6)).unwrap(),
        (4, 6)
    );
    for bad in [["--identities", "1"], ["--expressions", "1"]] {
        let e = parse(&bad).sizes((16, 3)).unwrap_err().to_string();
        assert!(e.contains("at least 2 identities and 2 expressions"), "{e}");
    }
}
