//! The skip rule of `testsupport::shared_path` seen from outside: this test binary runs its own
//! `needs_the_paper_set` test again as a child process against an empty shared folder, once
//! as a developer would (the test passes and `SKIPPED` reaches the standard error past the
//! harness's capture) and once as CI does (with `BIPOLAR_REQUIRE_SHARED=1` the test fails
//! naming the missing path).

use std::process::{Command, Output};

/// A data test: passes with the paper set, skips without it.
#[test]
fn needs_the_paper_set() {
    let dir = testsupport::require_shared!(testsupport::PAPER_SET);
    assert!(dir.is_dir(), "{}", dir.display());
}

/// `needs_the_paper_set` of this binary run alone against the empty folder `shared`, with
/// `BIPOLAR_REQUIRE_SHARED` set to `require` (removed when `None`); output captured by the
/// harness as in a plain `cargo test`.
fn child(shared: &std::path::Path, require: Option<&str>) -> Output {
    let mut c = Command::new(std::env::current_exe().expect("the test binary's path"));
    c.args(["--exact", "needs_the_paper_set", "--test-threads=1"])
        .env(facemodel::SHARED_ENV, shared)
        .env_remove(testsupport::REQUIRE_SHARED_ENV);
    if let Some(v) = require {
        c.env(testsupport::REQUIRE_SHARED_ENV, v);
    }
    c.output().expect("running the test binary")
}

#[test]
fn a_skip_is_reported_and_is_a_failure_when_the_data_is_required() {
    let empty = testsupport::fresh_temp_dir("testsupport-skip", "empty");
    let missing = empty.join(testsupport::PAPER_SET).display().to_string();

    for require in [None, Some(""), Some("0")] {
        let out = child(&empty, require);
        let (stdout, stderr) = (
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr),
        );
        assert!(out.status.success(), "{require:?}: {stdout}\n{stderr}");
        assert!(stdout.contains("1 passed"), "{require:?}: {stdout}");
        let want = format!("SKIPPED needs_the_paper_set: {missing} not found");
        assert!(stderr.contains(&want), "{require:?}: {stderr}");
        assert!(stderr.contains("BIPOLAR_REQUIRE_SHARED=1"), "{stderr}");
    }

    let out = child(&empty, Some("1"));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(!out.status.success(), "{stdout}");
    assert!(stdout.contains("1 failed"), "{stdout}");
    assert!(
        stdout.contains(&format!(
            "{missing} not found, and BIPOLAR_REQUIRE_SHARED is set"
        )),
        "{stdout}"
    );
    let _ = std::fs::remove_dir_all(&empty);
}
