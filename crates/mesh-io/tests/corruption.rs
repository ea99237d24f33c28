//! Random byte corruption, truncation and insertion never panic, whatever the reader.

use mesh_io::{read_mesh_from_bytes, write_mesh_to_bytes, BntGrid, Format, LoadedMesh};
use meshcore::{DVec3, TriMesh};
use proptest::prelude::*;
use std::path::PathBuf;
use std::sync::OnceLock;

fn samples() -> &'static Vec<(Format, Vec<u8>)> {
    static S: OnceLock<Vec<(Format, Vec<u8>)>> = OnceLock::new();
    S.get_or_init(|| {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures");
        let mut v = Vec::new();
        for (name, f) in [
            ("cube.obj", Format::Obj),
            ("cube_ascii.ply", Format::Ply),
            ("tetra_be.ply", Format::Ply),
            ("tetra_le.ply", Format::Ply),
            ("tetra_ascii.stl", Format::Stl),
            ("tetra_binary.stl", Format::Stl),
            ("cube.off", Format::Off),
            ("tetra.gltf", Format::Gltf),
            ("tetra.glb", Format::Glb),
        ] {
            v.push((f, std::fs::read(dir.join(name)).unwrap()));
        }
        let tetra = TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
        .unwrap();
        let mut lm = LoadedMesh::new(tetra);
        lm.colors = Some(vec![[1, 2, 3, 4]; 4]);
        v.push((Format::Ply, write_mesh_to_bytes(&lm, Format::Ply).unwrap()));
        v.push((Format::Glb, write_mesh_to_bytes(&lm, Format::Glb).unwrap()));
        let n = 6 * 5;
        let grid = BntGrid {
            nrows: 6,
            ncols: 5,
            zmin: -1e9,
            image_file: "x.png".into(),
            xyz: (0..n)
                .map(|i| {
                    if i % 7 == 0 {
                        DVec3::splat(-1e9)
                    } else {
                        DVec3::new((i % 5) as f64, (i / 5) as f64, 0.1 * i as f64)
                    }
                })
                .collect(),
            uv: vec![[0.5, 0.5]; n],
        };
        v.push((Format::Bnt, grid.to_bytes()));
        v
    })
}

#[derive(Debug, Clone)]
enum Edit {
    Set(usize, u8),
    Truncate(usize),
    Insert(usize, Vec<u8>),
    Delete(usize, usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        4 => (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Set(i, b)),
        1 => any::<usize>().prop_map(Edit::Truncate),
        1 => (any::<usize>(), prop::collection::vec(any::<u8>(), 1..16)).prop_map(|(i, b)| Edit::Insert(i, b)),
        1 => (any::<usize>(), 1usize..16).prop_map(|(i, n)| Edit::Delete(i, n)),
    ]
}

fn apply(mut b: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        if b.is_empty() {
            break;
        }
        let n = b.len();
        match e {
            Edit::Set(i, v) => b[i % n] = *v,
            Edit::Truncate(i) => b.truncate(i % n),
            Edit::Insert(i, s) => {
                let at = i % n;
                b.splice(at..at, s.iter().copied());
            }
            Edit::Delete(i, k) => {
                let at = i % n;
                b.drain(at..(at + k).min(n));
            }
        }
    }
    b
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 600, ..ProptestConfig::default() })]

    #[test]
    fn corrupted_files_never_panic(which in any::<usize>(), edits in prop::collection::vec(edit(), 1..6)) {
        let s = samples();
        let (format, bytes) = &s[which % s.len()];
        let bad = apply(bytes.clone(), &edits);
        // Any result is fine as long as there is no panic; errors must render.
        if let Err(e) = read_mesh_from_bytes(&bad, *format) {
            prop_assert!(!e.to_string().is_empty());
        }
        // The other parsers on the same bytes.
        let _ = mesh_io::parse_lm3(&bad, "x.lm3");
        let _ = mesh_io::parse_lm2(&bad, "x.lm2");
        let _ = mesh_io::parse_npy_f32(&bad, "x.npy");
    }

    #[test]
    fn every_truncation_of_every_sample_is_an_error_or_a_mesh(cut in 0usize..10_000) {
        for (format, bytes) in samples() {
            let c = cut % (bytes.len() + 1);
            let _ = read_mesh_from_bytes(&bytes[..c], *format);
        }
    }
}

#[test]
fn binary_truncations_are_errors() {
    // For binary formats with exact sizes, every strict prefix must be rejected.
    for (format, bytes) in samples() {
        if matches!(format, Format::Bnt)
            || (matches!(format, Format::Ply) && bytes.windows(6).any(|w| w == b"binary"))
        {
            for c in 0..bytes.len() {
                assert!(
                    read_mesh_from_bytes(&bytes[..c], *format).is_err(),
                    "{format:?} prefix {c} accepted"
                );
            }
        }
    }
}

/// A glTF whose POSITION names an accessor that does not exist made the gltf crate's
/// validation panic (index out of bounds), found by the proptest above; now a clear error.
#[test]
fn gltf_with_a_dangling_accessor_is_an_error_not_a_panic() {
    let json =
        br#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":5}}]}]}"#;
    let err = read_mesh_from_bytes(json, Format::Gltf).unwrap_err();
    assert!(err.to_string().contains("invalid glTF"), "{err}");
}
