use super::compare::icp_score;
use super::metrics::{identified, mcnemar_exact, metrics};
use super::{run, Args};
use meshcore::{DVec3, FaceLocator};

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
fn eer_and_rank1_on_known_scores() {
    // 2 gallery ids, 2 probes each; probe 3 is misidentified.
    let gid = vec![0, 1];
    let pid = vec![0, 0, 1, 1];
    let s = vec![
        vec![0.1, 0.5],
        vec![0.2, 0.6],
        vec![0.7, 0.3],
        vec![0.4, 0.45],
    ];
    let (rank1, eer, roc, gm, im, f) = metrics(&s, &pid, &gid);
    assert!((rank1 - 0.75).abs() < 1e-12);
    assert!((gm - (0.1 + 0.2 + 0.3 + 0.45) / 4.0).abs() < 1e-12);
    assert!((im - (0.5 + 0.6 + 0.7 + 0.4) / 4.0).abs() < 1e-12);
    assert_eq!(f, 0);
    // Threshold 0.4: FAR 1/4, FRR 1/4 -> EER 0.25.
    assert!((eer - 0.25).abs() < 1e-12, "{eer}");
    assert_eq!(roc.first(), Some(&(0.0, 0.0)));
    assert_eq!(roc.last(), Some(&(1.0, 1.0)));
    // Perfect separation gives EER 0; NaN counts as a failure.
    let (r, e, ..) = metrics(&[vec![0.1, f64::NAN], vec![0.9, 0.2]], &[0, 1], &gid);
    assert_eq!((r, e), (1.0, 0.0));
    assert_eq!(identified(&s, &pid, &gid), [true, true, true, false]);
    // A probe whose every score failed is not identified, even of the first identity.
    assert_eq!(identified(&[vec![f64::NAN, f64::NAN]], &[0], &gid), [false]);
}

#[test]
fn the_mcnemar_p_value_is_the_two_sided_binomial_tail() {
    // 10 discordant probes split 9 : 1: 2 (1 + 10) / 1024.
    assert!((mcnemar_exact(9, 1) - 22.0 / 1024.0).abs() < 1e-15);
    assert!((mcnemar_exact(1, 9) - 22.0 / 1024.0).abs() < 1e-15);
    // 10 : 0: 2 / 1024; an even split and no discordant probe: 1.
    assert!((mcnemar_exact(10, 0) - 2.0 / 1024.0).abs() < 1e-15);
    assert_eq!(mcnemar_exact(5, 5), 1.0);
    assert_eq!(mcnemar_exact(0, 0), 1.0);
    // 6 : 2 (the figure of a 50-identity run): 2 (1 + 8 + 28) / 256.
    assert!((mcnemar_exact(6, 2) - 74.0 / 256.0).abs() < 1e-14);
    // Many probes, no underflow: 2 sum_{i <= 200} C(500, i) / 2^500 = 8.9401e-6 (exact
    // integer sum).
    let p = mcnemar_exact(300, 200);
    assert!((p / 8.940066542253267e-6 - 1.0).abs() < 1e-9, "{p}");
}

#[test]
fn icp_recovers_a_rigid_copy() {
    let m = meshcore::shapes::icosphere(2);
    let rot = meshcore::DMat3::from_quat(meshcore::DQuat::from_axis_angle(
        DVec3::new(1.0, 0.3, 0.2).normalize(),
        1.1,
    ));
    let t = DVec3::new(3.0, -2.0, 1.0);
    let probe: Vec<DVec3> = m.positions().iter().map(|p| rot * *p + t).collect();
    let lm_g = [m.position(0), m.position(5), m.position(9)];
    let lm_p = lm_g.map(|p| rot * p + t);
    let loc = FaceLocator::new(&m);
    assert!(icp_score(&probe, &lm_p, &loc, &lm_g) < 1e-9);
    // A scaled copy is not at distance 0.
    let big: Vec<DVec3> = probe.iter().map(|p| (*p - t) * 1.1 + t).collect();
    assert!(icp_score(&big, &lm_p, &loc, &lm_g) > 0.01);
}
