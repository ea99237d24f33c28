//! The 12 ICT-FaceKit faces of the paper set and the ICT model `.npy` files (skipped when the
//! shared data folder is absent).

use meshcore::Topology;
use std::path::PathBuf;

/// Every paper-set face has 4 boundary loops (measured, and checked with an independent Python
/// script): the outer rim of the narrow face area (138 edges), the mouth (74) and the two eyes
/// (42 each).
const PAPER_SET_BOUNDARY_LOOPS: usize = 4;
const PAPER_SET_LOOP_LENGTHS: [usize; 4] = [42, 42, 74, 138];

/// Connected components (faces sharing a vertex), by an independent union-find with path
/// halving: a cross-check of `Topology::n_components` (which once over-counted on these faces
/// because its union step reused a stale root).
fn components(m: &meshcore::TriMesh) -> usize {
    let mut parent: Vec<usize> = (0..m.n_vertices()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for t in m.triangles() {
        for k in 1..3 {
            let (a, b) = (
                find(&mut parent, t[0] as usize),
                find(&mut parent, t[k] as usize),
            );
            if a != b {
                parent[a] = b;
            }
        }
    }
    (0..m.n_vertices())
        .filter(|&v| find(&mut parent, v) == v)
        .count()
}

#[test]
fn paper_set_faces_load() {
    let dir = testsupport::require_shared!(testsupport::PAPER_SET);
    let mut names: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .collect();
    names.sort();
    assert_eq!(names.len(), 12);
    let mut loop_lengths = None;
    for p in &names {
        let m = mesh_io::read_mesh(p).unwrap();
        assert_eq!(m.mesh.n_vertices(), 6706, "{}", p.display());
        let t = Topology::new(&m.mesh);
        assert_eq!(components(&m.mesh), 1, "{}", p.display());
        assert_eq!(t.n_components(), 1, "{}", p.display());
        assert_eq!(t.isolated_vertices(), 0);
        assert_eq!(
            t.boundary_loops().len(),
            PAPER_SET_BOUNDARY_LOOPS,
            "{}",
            p.display()
        );
        assert!(
            t.non_manifold_edges().is_empty() && t.inconsistent_edges().is_empty(),
            "{}",
            p.display()
        );
        let mut l: Vec<usize> = t.boundary_loops().iter().map(Vec::len).collect();
        l.sort_unstable();
        assert_eq!(l, PAPER_SET_LOOP_LENGTHS, "{}", p.display());
        // Same connectivity in every face: identical loop lengths and face counts.
        match &loop_lengths {
            None => loop_lengths = Some((l.clone(), m.mesh.n_faces())),
            Some((l0, f0)) => {
                assert_eq!(&l, l0, "{}", p.display());
                assert_eq!(m.mesh.n_faces(), *f0);
            }
        }
        println!(
            "{}: {} faces, boundary loop lengths {:?}, warnings {:?}",
            p.display(),
            m.mesh.n_faces(),
            l,
            m.warnings
        );
    }
}

#[test]
fn ict_model_npy_files() {
    let dir = testsupport::require_shared!(testsupport::MODEL);
    let neutral = mesh_io::read_mesh(dir.join("neutral.obj")).unwrap();
    for name in ["identities.npy", "expressions.npy"] {
        let (shape, v) = mesh_io::read_npy_f32(dir.join(name)).unwrap();
        assert_eq!(shape.iter().product::<usize>(), v.len(), "{name}");
        assert!(v.iter().all(|x| x.is_finite()), "{name}");
        // Blendshape arrays hold one displacement per neutral vertex coordinate.
        assert!(shape.len() >= 2, "{name}: {shape:?}");
        assert_eq!(
            shape[1..].iter().product::<usize>(),
            3 * neutral.mesh.n_vertices(),
            "{name}: {shape:?}"
        );
        println!("{name}: shape {shape:?}");
    }
}
