//! The Bosphorus `.bnt` reader on grids synthesised by the test.

use mesh_io::{bnt_grid_to_mesh, read_mesh_from_bytes, BntGrid, BntOptions, Format};
use meshcore::{DVec3, Topology};

const ZMIN: f64 = -1e9;

/// A 40 x 50 grid (1 mm spacing): a smooth bump over rows 5..=35, cols 5..=45, background
/// elsewhere, and an island rows 15..=20, cols 20..=25 raised by 50 mm (a depth jump).
fn grid() -> BntGrid {
    let (nr, nc) = (40, 50);
    let mut xyz = vec![DVec3::splat(ZMIN); nr * nc];
    let mut uv = vec![[0.0; 2]; nr * nc];
    for r in 0..nr {
        for c in 0..nc {
            let i = r * nc + c;
            uv[i] = [c as f64 / nc as f64, r as f64 / nr as f64];
            if (5..=35).contains(&r) && (5..=45).contains(&c) {
                let (x, y) = (c as f64, -(r as f64)); // y up: image row 0 at the top
                let mut z = 10.0 - 0.002 * ((x - 25.0).powi(2) + (y + 20.0).powi(2));
                if (15..=20).contains(&r) && (20..=25).contains(&c) {
                    z += 50.0;
                }
                xyz[i] = DVec3::new(x, y, z);
            }
        }
    }
    BntGrid {
        nrows: nr,
        ncols: nc,
        zmin: ZMIN,
        image_file: "bs000_N_N_0.png".into(),
        xyz,
        uv,
    }
}

#[test]
fn grid_mesh_drops_background_jumps_and_small_components() {
    let g = grid();
    let bytes = g.to_bytes();
    let m = read_mesh_from_bytes(&bytes, Format::Bnt).unwrap();
    // 31 x 41 rectangle minus the 6 x 6 island.
    assert_eq!(m.mesh.n_vertices(), 31 * 41 - 36);
    // 30 x 40 cells, minus the 7 x 7 cells touching the island, plus one triangle in each of
    // the 4 corner cells (three main corners, split along the main diagonal).
    assert_eq!(m.mesh.n_faces(), (1200 - 49) * 2 + 4);
    let gi = m.grid_index.as_ref().unwrap();
    for (v, p) in m.mesh.positions().iter().enumerate() {
        let i = gi[v] as usize;
        assert_eq!(*p, g.xyz[i]);
        let (r, c) = (i / 50, i % 50);
        assert!(
            !((15..=20).contains(&r) && (20..=25).contains(&c)),
            "island vertex kept"
        );
    }
    let t = Topology::new(&m.mesh);
    assert_eq!(t.n_components(), 1);
    assert!(t.inconsistent_edges().is_empty());
    assert!(t.non_manifold_edges().is_empty());
    // Outer boundary and the hole left by the island.
    assert_eq!(t.boundary_loops().len(), 2);
    // Oriented towards the scanner (+z).
    let mean: DVec3 = (0..m.mesh.n_faces() as u32)
        .map(|f| m.mesh.face_cross(f))
        .sum();
    assert!(mean.z > 0.0);
}

#[test]
fn larger_threshold_keeps_the_bridges() {
    let g = grid();
    let opts = BntOptions {
        max_edge_factor: 100.0,
        ..BntOptions::default()
    };
    let m = bnt_grid_to_mesh(&g, &opts).unwrap();
    assert_eq!(m.mesh.n_vertices(), 31 * 41);
    assert_eq!(m.mesh.n_faces(), 1200 * 2);
    // Without the largest-component filter the island survives as a second component.
    let opts = BntOptions {
        max_edge_factor: 4.0,
        largest_component_only: false,
    };
    let m = bnt_grid_to_mesh(&g, &opts).unwrap();
    assert_eq!(m.mesh.n_vertices(), 31 * 41);
    assert_eq!(Topology::new(&m.mesh).n_components(), 2);
}

#[test]
fn rows_are_flipped_bottom_first_in_the_file() {
    // A 2 x 2 grid written by hand: the file stores the bottom row (y = -100) first.
    let mut b = Vec::new();
    b.extend_from_slice(&2u16.to_le_bytes());
    b.extend_from_slice(&2u16.to_le_bytes());
    b.extend_from_slice(&ZMIN.to_le_bytes());
    b.extend_from_slice(&3u16.to_le_bytes());
    b.extend_from_slice(b"a.p");
    b.extend_from_slice(&20u32.to_le_bytes());
    let x = [0.0, 1.0, 0.0, 1.0];
    let y = [-100.0, -100.0, -99.0, -99.0];
    let z = [5.0, 5.0, 5.0, 5.0];
    let u = [0.0, 0.5, 0.0, 0.5];
    let v = [0.9, 0.9, 0.1, 0.1];
    for block in [x, y, z, u, v] {
        for val in block {
            b.extend_from_slice(&f64::to_le_bytes(val));
        }
    }
    let g = mesh_io::read_bnt_grid_from_bytes(&b, "t.bnt").unwrap();
    assert_eq!(g.image_file, "a.p");
    assert_eq!(g.xyz[0], DVec3::new(0.0, -99.0, 5.0)); // image row 0 = top
    assert_eq!(g.uv[0], [0.0, 0.1]);
    assert_eq!(g.xyz[3], DVec3::new(1.0, -100.0, 5.0));
    assert_eq!(g.to_bytes(), b);
    let m = read_mesh_from_bytes(&b, Format::Bnt).unwrap();
    assert_eq!(m.mesh.n_faces(), 2);
    let n = m.mesh.face_normal(0);
    assert!(n.z > 0.99, "{n}");
}

#[test]
fn all_background_is_an_error() {
    let mut g = grid();
    g.xyz.iter_mut().for_each(|p| p.z = ZMIN);
    let e = read_mesh_from_bytes(&g.to_bytes(), Format::Bnt).unwrap_err();
    assert!(
        e.to_string().contains("no two adjacent valid samples"),
        "{e}"
    );
}

#[test]
fn writer_round_trips_through_a_file() {
    let g = grid();
    let dir = std::env::temp_dir().join(format!("bnt-write-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("scan.bnt");
    mesh_io::write_bnt(&p, &g).unwrap();
    let back = mesh_io::read_bnt_grid(&p).unwrap();
    assert_eq!(back, g);
    // The triangulated file equals the triangulated grid.
    let a = mesh_io::read_mesh(&p).unwrap();
    let b = bnt_grid_to_mesh(&g, &BntOptions::default()).unwrap();
    assert_eq!(a.mesh, b.mesh);
    assert_eq!(a.grid_index, b.grid_index);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn writer_rejects_grids_the_reader_would_not_take_back() {
    let mut g = grid();
    g.xyz[7] = DVec3::new(f64::NAN, 0.0, 0.0);
    let e = mesh_io::write_bnt_to_bytes(&g).unwrap_err().to_string();
    assert!(e.contains("sample 7") && e.contains("non-finite"), "{e}");
    let mut g = grid();
    g.uv.pop();
    let e = mesh_io::write_bnt_to_bytes(&g).unwrap_err().to_string();
    assert!(e.contains("uv entries"), "{e}");
    let mut g = grid();
    g.ncols = 70_000;
    let e = mesh_io::write_bnt_to_bytes(&g).unwrap_err().to_string();
    assert!(e.contains("1 to 65535"), "{e}");
    let mut g = grid();
    g.zmin = f64::NEG_INFINITY;
    assert!(mesh_io::write_bnt_to_bytes(&g).is_err());
}

proptest::proptest! {
    #[test]
    fn written_grids_read_back_bit_for_bit(
        nr in 1usize..6,
        nc in 1usize..6,
        seed in proptest::prelude::any::<u64>(),
        name in "[a-z_0-9.]{0,12}",
    ) {
        // Deterministic pseudo-random values (including signed zeros and background samples).
        let mut s = seed | 1;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % 20001) as f64 / 100.0 - 100.0
        };
        let n = nr * nc;
        let xyz = (0..n)
            .map(|i| if i % 3 == 1 { DVec3::splat(ZMIN) } else { DVec3::new(next(), next(), -0.0 * next()) })
            .collect();
        let uv = (0..n).map(|_| [next(), next()]).collect();
        let g = BntGrid { nrows: nr, ncols: nc, zmin: ZMIN, image_file: name, xyz, uv };
        let bytes = mesh_io::write_bnt_to_bytes(&g).unwrap();
        let back = mesh_io::read_bnt_grid_from_bytes(&bytes, "p.bnt").unwrap();
        proptest::prop_assert_eq!(&back, &g);
        // Bit for bit, signed zeros included.
        for (a, b) in back.xyz.iter().zip(&g.xyz) {
            proptest::prop_assert_eq!(a.to_array().map(f64::to_bits), b.to_array().map(f64::to_bits));
        }
        proptest::prop_assert_eq!(mesh_io::write_bnt_to_bytes(&back).unwrap(), bytes);
    }
}
