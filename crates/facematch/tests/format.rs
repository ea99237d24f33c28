//! The template format: the committed fixture, round trips, and the errors of bad files.

use facematch::{fixture::small_template, Gallery, MatchError, MatchOptions, Template};
use std::path::Path;

fn fixture_bytes() -> Vec<u8> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/facematch/small.bpt");
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn the_committed_fixture_reads_as_the_template_it_was_made_from() {
    let bytes = fixture_bytes();
    let t = Template::from_bytes(&bytes, "small.bpt").unwrap();
    assert_eq!(t, small_template());
    // Written again: the same bytes.
    assert_eq!(t.to_bytes(), bytes);
}

#[test]
fn a_gallery_file_round_trips_bit_identically() {
    let a = small_template();
    let mut b = small_template();
    b.identity = "id08".into();
    let bytes = Template::gallery_bytes(&[a.clone(), b.clone()]);
    let back = Template::many_from_bytes(&bytes, "g.bpg").unwrap();
    assert_eq!(back, vec![a, b]);
    assert_eq!(Template::gallery_bytes(&back), bytes);
}

#[test]
fn bad_files_are_named_errors() {
    let bytes = fixture_bytes();
    let err = |b: &[u8]| Template::from_bytes(b, "x.bpt").unwrap_err().to_string();
    assert!(
        err(b"hello world").contains("not a template file"),
        "{}",
        err(b"hello")
    );
    let mut v2 = bytes.clone();
    v2[8] = 2;
    assert!(err(&v2).contains("format version 2; this build reads version 1"));
    let cut = &bytes[..bytes.len() - 5];
    assert!(err(cut).contains("truncated"), "{}", err(cut));
    let mut long = bytes.clone();
    long.push(0);
    assert!(err(&long).contains("1 bytes after the end"));
}

#[test]
fn a_gallery_needs_templates_made_with_its_settings() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let e = Gallery::open(&empty, &MatchOptions::default()).unwrap_err();
    assert!(matches!(e, MatchError::EmptyGallery(_)), "{e}");
    // The fixture was made with other settings than the defaults: the error shows both.
    let f = dir.path().join("small.bpt");
    std::fs::write(&f, fixture_bytes()).unwrap();
    let e = Gallery::open(dir.path(), &MatchOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("template: method=exact levels=10\n"), "{e}");
    assert!(
        e.contains(&MatchOptions::default().template_settings()),
        "{e}"
    );
}
