//! Generated test shapes: jittered plane grids (optionally with holes), icospheres, UV
//! spheres and the triangle soup of the repair tests. Deterministic (the jitter comes from a
//! fixed-seed generator), so tests and benchmarks may pick vertices by index. Every crate's
//! tests, benches and the sphere validation use these instead of their own copies.

use crate::{MeshError, TriMesh};
use glam::DVec3;
use std::collections::HashMap;

crate::choice! {
    /// How [`grid`] splits each square of the grid into two triangles. With corners
    /// `a = (i, j)`, `b = (i + 1, j)`, `c = (i + 1, j + 1)`, `d = (i, j + 1)`:
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum Diagonals: "diagonal layout", MeshError {
        /// Every square along `a-c`: triangles `a b c` and `a c d`.
        Uniform = "uniform",
        /// Chequerboard: `a b c`, `a c d` where `i + j` is even, else along `b-d`: `a b d`, `b c d`.
        Alternating = "alternating",
    }
}

/// Grid of `nx x ny` squares, counter-clockwise in the `(i, j)` parameter plane. Vertex
/// `(i, j)`, `0 <= i <= nx`, `0 <= j <= ny`, has id `j * (nx + 1) + i` and the position
/// `position(i, j)`, called once per vertex in id order (so a seeded generator inside the
/// closure gives a deterministic mesh). Errors when a position is not finite or `nx` or `ny` is
/// zero.
pub fn grid(
    nx: usize,
    ny: usize,
    diagonals: Diagonals,
    position: impl FnMut(usize, usize) -> DVec3,
) -> Result<TriMesh, MeshError> {
    let (pos, tris) = grid_parts(nx, ny, diagonals, position);
    TriMesh::new(pos, tris)
}

/// Positions and triangles of [`grid`].
fn grid_parts(
    nx: usize,
    ny: usize,
    diagonals: Diagonals,
    mut position: impl FnMut(usize, usize) -> DVec3,
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut pos = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            pos.push(position(i, j));
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut tris = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if diagonals == Diagonals::Uniform || (i + j) % 2 == 0 {
                tris.extend([[a, b, c], [a, c, d]]);
            } else {
                tris.extend([[a, b, d], [b, c, d]]);
            }
        }
    }
    (pos, tris)
}

/// Square grid of `n x n` cells of size `h` starting at `(x0, x0)` in the plane z = 0, normals
/// +z. Interior vertices are jittered by up to `jitter * h / 2` per axis (deterministic in
/// `seed`); faces whose centroid satisfies `drop` are left out (holes).
pub fn grid_plane(
    n: usize,
    h: f64,
    x0: f64,
    jitter: f64,
    seed: u64,
    drop: impl Fn(DVec3) -> bool,
) -> TriMesh {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut rnd = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let (pos, cells) = grid_parts(n, n, Diagonals::Alternating, |i, j| {
        let interior = i > 0 && j > 0 && i < n && j < n;
        let (dx, dy) = if interior {
            (rnd() * jitter * h, rnd() * jitter * h)
        } else {
            (0.0, 0.0)
        };
        DVec3::new(x0 + i as f64 * h + dx, x0 + j as f64 * h + dy, 0.0)
    });
    let tris = cells
        .into_iter()
        .filter(|t| {
            let c = (pos[t[0] as usize] + pos[t[1] as usize] + pos[t[2] as usize]) / 3.0;
            !drop(c)
        })
        .collect();
    // Drop unused vertices so the mesh has no isolated vertices.
    compact(pos, tris)
}

fn compact(pos: Vec<DVec3>, tris: Vec<[u32; 3]>) -> TriMesh {
    let mut map = vec![u32::MAX; pos.len()];
    let mut out = Vec::new();
    let tris: Vec<[u32; 3]> = tris
        .iter()
        .map(|t| {
            t.map(|v| {
                if map[v as usize] == u32::MAX {
                    map[v as usize] = out.len() as u32;
                    out.push(pos[v as usize]);
                }
                map[v as usize]
            })
        })
        .collect();
    TriMesh::new(out, tris).expect("a generated grid is a valid mesh")
}

/// Unit icosphere with `subdivisions` levels of 4-to-1 subdivision (outward normals):
/// 12, 42, 162, 642, 2562, 10242, ... vertices.
pub fn icosphere(subdivisions: u32) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut pos: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(tris.len() * 4);
        for tri in &tris {
            let mut m = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                m[k] = *mid.entry(key).or_insert_with(|| {
                    pos.push(((pos[a as usize] + pos[b as usize]) / 2.0).normalize());
                    (pos.len() - 1) as u32
                });
            }
            next.push([tri[0], m[0], m[2]]);
            next.push([tri[1], m[1], m[0]]);
            next.push([tri[2], m[2], m[1]]);
            next.push(m);
        }
        tris = next;
    }
    TriMesh::new(pos, tris).expect("icosphere is valid")
}

/// Unit UV sphere with `n_lat` latitude bands and `n_lon` longitude sectors (poles on the z
/// axis, outward normals).
pub fn uv_sphere(n_lat: usize, n_lon: usize) -> TriMesh {
    let n_lat = n_lat.max(2);
    let n_lon = n_lon.max(3);
    let mut pos = vec![DVec3::Z];
    for i in 1..n_lat {
        let th = std::f64::consts::PI * i as f64 / n_lat as f64;
        for j in 0..n_lon {
            let ph = std::f64::consts::TAU * j as f64 / n_lon as f64;
            pos.push(DVec3::new(
                th.sin() * ph.cos(),
                th.sin() * ph.sin(),
                th.cos(),
            ));
        }
    }
    pos.push(-DVec3::Z);
    let south = (pos.len() - 1) as u32;
    let ring = |i: usize, j: usize| (1 + (i - 1) * n_lon + j % n_lon) as u32;
    let mut tris = Vec::new();
    for j in 0..n_lon {
        tris.push([0, ring(1, j), ring(1, j + 1)]);
    }
    for i in 1..n_lat - 1 {
        for j in 0..n_lon {
            tris.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
            tris.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
        }
    }
    for j in 0..n_lon {
        tris.push([ring(n_lat - 1, j), south, ring(n_lat - 1, j + 1)]);
    }
    TriMesh::new(pos, tris).expect("uv sphere is valid")
}

/// Open cylinder of radius `r` and height `h` about the z axis (`na` segments around, `nh`
/// rows of squares split along one diagonal), outward normals, bottom ring at z = 0.
pub fn cylinder(r: f64, h: f64, na: usize, nh: usize) -> TriMesh {
    let (na, nh) = (na.max(3), nh.max(1));
    let mut v = Vec::with_capacity(na * (nh + 1));
    for j in 0..=nh {
        for i in 0..na {
            let a = std::f64::consts::TAU * i as f64 / na as f64;
            v.push(DVec3::new(
                r * a.cos(),
                r * a.sin(),
                h * j as f64 / nh as f64,
            ));
        }
    }
    let idx = |i: usize, j: usize| (j * na + i % na) as u32;
    let mut f = Vec::with_capacity(2 * na * nh);
    for j in 0..nh {
        for i in 0..na {
            f.push([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)]);
            f.push([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]);
        }
    }
    TriMesh::new(v, f).expect("a generated cylinder is a valid mesh")
}

/// The unit square's two triangles written as a soup (STL style: the two vertices of the shared
/// edge written twice, so 2 duplicate vertices), plus the degenerate face `[0, 0, 1]`: 6
/// vertices, 3 faces, the input of the repair tests.
pub fn triangle_soup() -> TriMesh {
    let p = vec![
        DVec3::ZERO,
        DVec3::X,
        DVec3::Y,
        DVec3::X,
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::Y,
    ];
    TriMesh::new(p, vec![[0, 1, 2], [3, 4, 5], [0, 0, 1]]).expect("the soup is a valid mesh")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Topology;

    #[test]
    fn icosphere_counts_and_unit_radius() {
        for (level, nv) in [(0, 12), (1, 42), (2, 162), (3, 642)] {
            let m = icosphere(level);
            assert_eq!(m.n_vertices(), nv);
            assert_eq!(m.n_faces(), 20 * 4usize.pow(level));
            assert!(m
                .positions()
                .iter()
                .all(|p| (p.length() - 1.0).abs() < 1e-12));
            let t = Topology::new(&m);
            assert!(t.boundary_loops().is_empty());
            assert!(t.inconsistent_edges().is_empty());
        }
    }

    #[test]
    fn spheres_have_outward_normals() {
        for m in [icosphere(2), uv_sphere(8, 12)] {
            for f in 0..m.n_faces() as u32 {
                let [a, b, c] = m.triangles()[f as usize].map(|v| m.position(v));
                let n = (b - a).cross(c - a);
                assert!(n.dot(a + b + c) > 0.0, "face {f} points inwards");
            }
        }
    }

    #[test]
    fn cylinder_is_open_with_outward_normals() {
        let m = cylinder(1.5, 2.0, 12, 3);
        assert_eq!(m.n_vertices(), 12 * 4);
        let t = Topology::new(&m);
        assert_eq!(t.boundary_loops().len(), 2);
        for f in 0..m.n_faces() as u32 {
            let [a, b, c] = m.triangles()[f as usize].map(|v| m.position(v));
            let radial = (a + b + c) * DVec3::new(1.0, 1.0, 0.0);
            assert!(
                (b - a).cross(c - a).dot(radial) > 0.0,
                "face {f} points inwards"
            );
        }
        assert!(m
            .positions()
            .iter()
            .all(|p| ((p.x * p.x + p.y * p.y).sqrt() - 1.5).abs() < 1e-12));
    }

    #[test]
    fn uv_sphere_layout() {
        let m = uv_sphere(10, 16);
        assert_eq!(m.n_vertices(), 2 + 9 * 16);
        assert_eq!(m.position(0), DVec3::Z);
        assert_eq!(m.position((m.n_vertices() - 1) as u32), -DVec3::Z);
        assert!(Topology::new(&m).boundary_loops().is_empty());
    }

    #[test]
    fn grid_ids_positions_and_diagonals() {
        let u = grid(3, 2, Diagonals::Uniform, |i, j| {
            DVec3::new(i as f64, j as f64, 0.5 * (i * j) as f64)
        })
        .unwrap();
        assert_eq!((u.n_vertices(), u.n_faces()), (12, 12));
        assert_eq!(u.position(2 * 4 + 1), DVec3::new(1.0, 2.0, 1.0));
        // Square (1, 0): a = 1, b = 2, c = 6, d = 5.
        assert_eq!(&u.triangles()[2..4], &[[1, 2, 6], [1, 6, 5]]);
        let a = grid(3, 2, Diagonals::Alternating, |i, j| {
            DVec3::new(i as f64, j as f64, 0.0)
        })
        .unwrap();
        assert_eq!(
            &a.triangles()[0..4],
            &[[0, 1, 5], [0, 5, 4], [1, 2, 5], [2, 6, 5]]
        );
        for m in [&u, &a] {
            let t = Topology::new(m);
            assert_eq!(t.boundary_loops().len(), 1);
            assert!(t.inconsistent_edges().is_empty());
            for f in 0..m.n_faces() as u32 {
                assert!(m.face_cross(f).z > 0.0, "face {f} is not counter-clockwise");
            }
        }
        assert!(grid(1, 1, Diagonals::Uniform, |_, _| DVec3::splat(f64::NAN)).is_err());
    }

    #[test]
    fn grid_jitter_is_deterministic_and_holes_drop_faces() {
        let a = grid_plane(6, 0.5, -1.5, 0.3, 7, |_| false);
        let b = grid_plane(6, 0.5, -1.5, 0.3, 7, |_| false);
        assert_eq!(a.positions(), b.positions());
        assert_eq!(a.n_faces(), 72);
        let c = grid_plane(6, 0.5, -1.5, 0.3, 8, |_| false);
        assert_ne!(a.positions(), c.positions());
        let holed = grid_plane(6, 0.5, -1.5, 0.0, 0, |p| p.length() < 0.6);
        assert!(holed.n_faces() < 72);
        assert_eq!(Topology::new(&holed).boundary_loops().len(), 2);
    }
}
