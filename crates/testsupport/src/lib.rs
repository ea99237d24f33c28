//! Test-side support shared by the tests and benchmarks of every crate (not published).
//!
//! * **Shared data, one skip rule.** [`shared_path`] (and the [`require_shared!`] macro around
//!   it) returns a path inside the shared data folder found by [`facemodel::shared_dir`]. When
//!   the folder (or the file inside it) is absent, it writes one `SKIPPED <test>: ...` line to
//!   the process's standard error, past the test harness's capture (so `cargo test` shows it
//!   without `--nocapture`), and returns `None`; with [`REQUIRE_SHARED_ENV`] set (as CI sets
//!   it) it panics instead, naming the missing path, so that no data test passes unrun. A
//!   `BIPOLAR_SHARED` that names no folder is a user error, not a reason to skip: the test
//!   panics with the lookup's message.
//! * **Paths**: [`PAPER_SET`], [`MODEL`], [`paper_face`] (and [`paper_meshes`], read).
//! * **Meshes**: [`read_mesh`] (through `mesh-io`, the project's one reader) and the generators
//!   of [`meshcore::shapes`], re-exported as [`shapes`], plus [`jittered_grid`],
//!   [`jittered_unit_plane`] (the plane of the straightest-geodesic, single-pole and face-frame
//!   tests), [`height_field`], [`uv_sphere_y_up`] and [`renumbered`]; [`nearest_vertex`] by brute
//!   force.
//! * **Analytic distance fields** and the differences between two fields: [`fields`].
//! * **End-to-end runs** of the command-line tools: [`cli`]; the check of a crate's option
//!   names: [`check_choice_error`].
//! * **Temporary folders**: [`fresh_temp_dir`].
//! * **The independent descriptor and distance** the crates are checked against: [`oracle`].

pub mod cli;
pub mod fields;
pub mod oracle;

pub use facemodel::{MODEL, PAPER_SET};
pub use meshcore::shapes;

use facemodel::FaceModelError;
use meshcore::{DVec3, TriMesh};
use std::path::{Path, PathBuf};

/// Planar grid on [0, 1]^2 (z = 0) of `n` cells a side, uniform diagonals, interior vertices
/// jittered by up to `jitter` cells per axis (ChaCha8 seeded by `seed`; boundary kept straight).
pub fn jittered_unit_plane(n: usize, jitter: f64, seed: u64) -> TriMesh {
    jittered_grid(
        n,
        n,
        1.0 / n as f64,
        shapes::Diagonals::Uniform,
        jitter,
        seed,
    )
}

/// Planar grid of `nx x ny` square cells of side `h` from the origin (z = 0), vertex `(i, j)`
/// with id `j * (nx + 1) + i` (as [`shapes::grid`]), interior vertices jittered by up to
/// `jitter` cells per axis (ChaCha8 seeded by `seed`, two draws per interior vertex in id order
/// when `jitter > 0`; the boundary stays straight).
pub fn jittered_grid(
    nx: usize,
    ny: usize,
    h: f64,
    diagonals: shapes::Diagonals,
    jitter: f64,
    seed: u64,
) -> TriMesh {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    shapes::grid(nx, ny, diagonals, |i, j| {
        let inner = i > 0 && j > 0 && i < nx && j < ny;
        let (dx, dy) = if inner && jitter > 0.0 {
            (
                rng.random_range(-jitter..jitter) * h,
                rng.random_range(-jitter..jitter) * h,
            )
        } else {
            (0.0, 0.0)
        };
        meshcore::DVec3::new(i as f64 * h + dx, j as f64 * h + dy, 0.0)
    })
    .expect("a jittered grid is a valid mesh")
}

/// Height field `z = f(x, y)` on the square `[-half, half]^2`: [`shapes::grid`] of `n x n`
/// cells with uniform diagonals, vertex `(i, j)` at `x = -half + 2 half i / n` (and `y` alike
/// from `j`), normals up.
pub fn height_field(n: usize, half: f64, f: impl Fn(f64, f64) -> f64) -> TriMesh {
    let side = 2.0 * half;
    shapes::grid(n, n, shapes::Diagonals::Uniform, |i, j| {
        let (x, y) = (
            -half + side * i as f64 / n as f64,
            -half + side * j as f64 / n as f64,
        );
        meshcore::DVec3::new(x, y, f(x, y))
    })
    .expect("a height field of finite heights is a valid mesh")
}

/// UV sphere of radius `r` with its poles on the y axis (vertex 0 at `+r y`, the last vertex at
/// `-r y`, the rings in between at `y = r cos(theta)`), the view-friendly sphere of the render
/// tests: [`shapes::uv_sphere`] with y and z exchanged and every face reversed so that it stays
/// outward.
pub fn uv_sphere_y_up(r: f64, n_lat: usize, n_lon: usize) -> TriMesh {
    let (pos, tris) = shapes::uv_sphere(n_lat, n_lon).into_parts();
    let pos = pos
        .into_iter()
        .map(|p| meshcore::DVec3::new(r * p.x, r * p.z, r * p.y))
        .collect();
    let tris = tris.into_iter().map(|[a, b, c]| [a, c, b]).collect();
    TriMesh::new(pos, tris).expect("a reflected sphere is a valid mesh")
}

/// Environment variable that makes a missing shared data folder or file fail the test that
/// needs it instead of skipping it (any value but empty or `0`); `.ci/run` sets it.
pub const REQUIRE_SHARED_ENV: &str = "BIPOLAR_REQUIRE_SHARED";

/// Whether [`REQUIRE_SHARED_ENV`] is set to a value other than empty or `0`.
pub fn shared_required() -> bool {
    std::env::var_os(REQUIRE_SHARED_ENV).is_some_and(|v| !v.is_empty() && v != "0")
}

/// `rel` inside the shared data folder, or `None` after reporting why the caller skips:
/// `../shared not found (...)` when there is no shared folder, `<path> not found` when the
/// folder lacks `rel`. The line `SKIPPED <test>: <why> ...` goes to the process's standard
/// error directly (the harness captures `eprintln!`, not this), so `cargo test` shows every
/// skip. Panics with the reason when [`shared_required`], and when `BIPOLAR_SHARED` names no
/// folder.
pub fn shared_path(rel: impl AsRef<Path>) -> Option<PathBuf> {
    let root = match facemodel::shared_dir() {
        Ok(root) => root,
        Err(e @ FaceModelError::SharedNotFound { .. }) => {
            return skip(&format!("../shared not found ({e})"));
        }
        Err(e) => panic!("{e}"),
    };
    let p = root.join(rel);
    if p.exists() {
        Some(p)
    } else {
        skip(&format!("{} not found", p.display()))
    }
}

/// The skip of [`shared_path`]: a panic with `why` when [`shared_required`], else the
/// `SKIPPED` line on the uncaptured standard error and `None`.
fn skip<T>(why: &str) -> Option<T> {
    if shared_required() {
        panic!("{why}, and {REQUIRE_SHARED_ENV} is set: this test needs the shared data");
    }
    // The test harness names each test's thread after the test (a program's is "main").
    let thread = std::thread::current();
    let test = match thread.name() {
        Some(name) if name != "main" => format!(" {name}"),
        _ => String::new(),
    };
    // Not eprintln!: the harness captures that (shown only for a failure or with --nocapture).
    let line =
        format!("SKIPPED{test}: {why} (set {REQUIRE_SHARED_ENV}=1 to make this a failure)\n");
    let _ = std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
    None
}

/// `<shared>/faces/ict-facekit/paper-set/<name>` (e.g. `id1_neutral.obj`), under the rule of
/// [`shared_path`].
pub fn paper_face(name: &str) -> Option<PathBuf> {
    shared_path(Path::new(PAPER_SET).join(name))
}

/// The meshes of the paper-set faces `names` ([`paper_face`], read with [`read_mesh`]); `None`
/// when one is absent (the skip rule of [`shared_path`]).
pub fn paper_meshes<const N: usize>(names: [&str; N]) -> Option<[TriMesh; N]> {
    let paths = names.map(paper_face);
    if paths.iter().any(Option::is_none) {
        return None;
    }
    Some(paths.map(|p| read_mesh(p.expect("checked above"))))
}

/// The path `rel` inside the shared data folder, or a `return` from the calling function (with
/// `Default::default()`, so `()` in a test) after the skip line of [`shared_path`].
///
/// ```
/// fn paper_set_is_a_folder() {
///     let dir = testsupport::require_shared!(testsupport::PAPER_SET);
///     assert!(dir.is_dir());
/// }
/// paper_set_is_a_folder();
/// ```
#[macro_export]
macro_rules! require_shared {
    ($rel:expr) => {
        match $crate::shared_path($rel) {
            Some(p) => p,
            None => return Default::default(),
        }
    };
}

/// The faces of the paper set named in `names` (in the set's order), read with
/// `facemodel::load_face_set`; `None` without the shared data (the skip rule of
/// [`shared_path`]); panics if the set cannot be read or a name is missing.
pub fn paper_faces(names: &[&str]) -> Option<Vec<facemodel::Face>> {
    let dir = shared_path(PAPER_SET)?;
    let faces: Vec<facemodel::Face> = facemodel::load_face_set(&dir)
        .unwrap_or_else(|e| panic!("reading the paper set: {e}"))
        .into_iter()
        .filter(|f| names.contains(&f.name.as_str()))
        .collect();
    assert_eq!(faces.len(), names.len(), "paper faces {names:?}");
    Some(faces)
}

/// [`meshcore::choice::check_choice`] of `T` with the rejected name `bad`, and that parsing
/// `bad` gives the error `unknown` accepts (the crate's error for an unknown name).
#[track_caller]
pub fn check_choice_error<T>(bad: &str, unknown: impl Fn(&T::Err) -> bool)
where
    T: meshcore::Choice + PartialEq + std::fmt::Debug + std::str::FromStr + std::fmt::Display,
    T::Err: std::fmt::Display + std::fmt::Debug,
{
    meshcore::choice::check_choice::<T>(bad).unwrap_or_else(|e| panic!("{e}"));
    match bad.parse::<T>() {
        Err(e) => assert!(unknown(&e), "{bad:?}: unexpected error {e:?}"),
        Ok(v) => panic!("{bad:?} parses to {v:?}"),
    }
}

/// An empty folder `<temp>/<prefix>-<process id>-<name>` for a test's files (emptied first
/// when a previous run left it).
pub fn fresh_temp_dir(prefix: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("{prefix}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    if let Err(e) = std::fs::create_dir_all(&d) {
        panic!("creating {}: {e}", d.display());
    }
    d
}

/// Reads a mesh file with `mesh-io`; panics with the reader's message (test code).
pub fn read_mesh(path: impl AsRef<Path>) -> TriMesh {
    let path = path.as_ref();
    match mesh_io::read_mesh(path) {
        Ok(m) => m.mesh,
        Err(e) => panic!("reading {}: {e}", path.display()),
    }
}

/// The vertex of `mesh` nearest to `p` by brute force (the lowest index on ties); panics on a
/// mesh without vertices (test code).
pub fn nearest_vertex(mesh: &TriMesh, p: DVec3) -> u32 {
    (0..mesh.n_vertices() as u32)
        .min_by(|&a, &b| {
            (mesh.position(a) - p)
                .length()
                .total_cmp(&(mesh.position(b) - p).length())
        })
        .expect("a mesh with vertices")
}

/// `mesh` with its vertices renumbered by the permutation `v -> (7919 v + 13) mod n`, its faces
/// listed in reverse order and each face's corners rotated by `k mod 3` places (`k` its new
/// index): the same surface under another numbering. Returns the mesh and the permutation
/// (`perm[old] = new`); panics if the map is not a permutation (7919 shares a factor with `n`).
pub fn renumbered(mesh: &TriMesh) -> (TriMesh, Vec<u32>) {
    let n = mesh.n_vertices();
    let perm: Vec<u32> = (0..n as u64)
        .map(|v| ((v * 7919 + 13) % n as u64) as u32)
        .collect();
    let mut seen = vec![false; n];
    perm.iter().for_each(|&p| seen[p as usize] = true);
    assert!(seen.iter().all(|&s| s), "not a permutation of {n} vertices");
    let mut pos = vec![meshcore::DVec3::ZERO; n];
    for (v, &p) in perm.iter().enumerate() {
        pos[p as usize] = mesh.positions()[v];
    }
    let tris: Vec<[u32; 3]> = mesh
        .triangles()
        .iter()
        .rev()
        .enumerate()
        .map(|(k, t)| {
            let t = t.map(|v| perm[v as usize]);
            match k % 3 {
                0 => t,
                1 => [t[1], t[2], t[0]],
                _ => [t[2], t[0], t[1]],
            }
        })
        .collect();
    (
        TriMesh::new(pos, tris).expect("a renumbered valid mesh is valid"),
        perm,
    )
}
