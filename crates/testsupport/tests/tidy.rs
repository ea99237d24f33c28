//! Tidy checks over the workspace's Rust sources (ordinary tests, as rust-analyzer has): doc
//! comments say something true about their item, so none of the boilerplate written to silence
//! `missing_docs`, no issue numbers (they mean nothing to a reader of `--help` or of the API
//! docs), and no notes waiting for a change to land that outlive it.

use std::path::{Path, PathBuf};

fn workspace_root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.parent()
        .and_then(Path::parent)
        .map_or_else(|| here.to_path_buf(), Path::to_path_buf)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<PathBuf> = entries.filter_map(Result::ok).map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            if !p.ends_with("target") {
                rust_files(&p, out);
            }
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// `file:line: text` of every doc-comment line (`///`, `//!`) of the workspace's sources that
/// satisfies `pred` (given the line in lower case); this file is left out.
fn offenders(pred: impl Fn(&str) -> bool) -> Vec<String> {
    lines_where(|t| (t.starts_with("///") || t.starts_with("//!")) && pred(&t.to_lowercase()))
}

/// `file:line: text` of every code line (not a comment) of the workspace's sources that
/// satisfies `pred` (given the trimmed line), outside the files whose path ends with one of
/// `except`; this file is left out.
fn code_offenders(pred: impl Fn(&str) -> bool, except: &[&str]) -> Vec<String> {
    lines_where(|t| !t.starts_with("//") && pred(t))
        .into_iter()
        .filter(|l| {
            !except
                .iter()
                .any(|e| l.split(':').next().unwrap_or("").ends_with(e))
        })
        .collect()
}

/// Every Rust source of the workspace but this file, as (path from the root, text).
fn sources() -> Vec<(String, String)> {
    let root = workspace_root();
    let mut files = Vec::new();
    rust_files(&root.join("crates"), &mut files);
    rust_files(&root.join("xtask"), &mut files);
    assert!(
        files.len() > 50,
        "found only {} Rust files under {}",
        files.len(),
        root.display()
    );
    files
        .iter()
        .filter(|f| !f.ends_with("testsupport/tests/tidy.rs"))
        .map(|f| {
            let rel = f.strip_prefix(&root).unwrap_or(f).display().to_string();
            (rel, std::fs::read_to_string(f).unwrap_or_default())
        })
        .collect()
}

/// `file:line: text` of every line of the workspace's sources whose trimmed text satisfies
/// `pred`; this file is left out.
fn lines_where(pred: impl Fn(&str) -> bool) -> Vec<String> {
    let mut out = Vec::new();
    for (rel, text) in sources() {
        for (i, line) in text.lines().enumerate() {
            let t = line.trim_start();
            if pred(t) {
                out.push(format!("{rel}:{}: {t}", i + 1));
            }
        }
    }
    out
}

/// A whole doc comment that is one name or path in a code span and a full stop
/// ("/// `--out`."): it names its item instead of saying what it is (a formula is fine).
fn only_a_name(doc: &str) -> bool {
    let body = doc.trim();
    body.len() > 3
        && body.starts_with('`')
        && body.ends_with("`.")
        && body[1..body.len() - 2]
            .chars()
            .all(|c| c.is_alphanumeric() || matches!(c, '_' | ':' | '-'))
}

/// `file:line: text` of every one-line `///` doc comment (no doc line above or below it) whose
/// text satisfies `pred`.
fn one_line_docs(pred: impl Fn(&str) -> bool) -> Vec<String> {
    let mut out = Vec::new();
    for (rel, text) in sources() {
        let lines: Vec<&str> = text.lines().map(str::trim_start).collect();
        let doc = |i: usize| lines.get(i).is_some_and(|l| l.starts_with("///"));
        for (i, l) in lines.iter().enumerate() {
            let alone = doc(i) && !(i > 0 && doc(i - 1)) && !doc(i + 1);
            if alone && pred(&l[3..]) {
                out.push(format!("{rel}:{}: {l}", i + 1));
            }
        }
    }
    out
}

#[test]
fn no_boilerplate_doc_comments() {
    assert!(only_a_name(" `--out`.") && only_a_name(" `mesh_io::IoError`."));
    assert!(!only_a_name(" `--out` of every task.") && !only_a_name(" `sum d_i`."));
    let mut bad = offenders(|l| l.contains("see the struct doc") || l.contains("see the enum doc"));
    bad.extend(one_line_docs(only_a_name));
    assert!(
        bad.is_empty(),
        "boilerplate doc comments:\n{}",
        bad.join("\n")
    );
}

#[test]
fn no_issue_numbers_in_docs() {
    let bad = offenders(|l| {
        l.match_indices("issue ").any(|(i, m)| {
            l[i + m.len()..]
                .chars()
                .next()
                .is_some_and(|c| c.is_ascii_digit() || c == '#')
        })
    });
    assert!(
        bad.is_empty(),
        "issue numbers in doc comments (API docs, --help texts):\n{}",
        bad.join("\n")
    );
}

#[test]
fn no_until_it_lands_notes() {
    let bad =
        offenders(|l| l.contains("until") && (l.contains(" lands") || l.contains(" is merged")));
    assert!(
        bad.is_empty(),
        "stale 'until X lands' notes:\n{}",
        bad.join("\n")
    );
}

#[test]
fn os_errors_go_through_file_error() {
    let bad = code_offenders(
        |t| t.contains("std::io::Error,") && t.starts_with("source"),
        &["meshcore/src/file.rs"],
    );
    assert!(
        bad.is_empty(),
        "an error variant carrying std::io::Error itself (use meshcore::FileError):\n{}",
        bad.join("\n")
    );
}

#[test]
fn option_enums_are_declared_inside_choice() {
    let bad = code_offenders(|t| t.contains("choice!("), &["meshcore/src/choice.rs"]);
    assert!(
        bad.is_empty(),
        "choice!(Enum, ...) beside a separate enum (declare it inside choice! {{ ... }}):\n{}",
        bad.join("\n")
    );
}
