//! Parse speed: a 1M-triangle binary PLY (generated here into a temporary file) read by
//! `mesh_io::read_mesh`, and by the Python `trimesh` peer on the same file in the same run
//! (`/work/venv-peers/bin/python`, or `$BIPOLAR_PEER_PYTHON`; skipped if absent). Also the
//! load time of the 12 ICT paper-set OBJ faces (skipped if the shared data is absent).

use criterion::{black_box, Criterion};
use meshcore::shapes::Diagonals;
use meshcore::{DVec3, TriMesh};
use rand::{Rng, SeedableRng};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// A 709 x 709 height-field grid: 502,681 vertices, 1,002,528 triangles.
fn big_mesh() -> TriMesh {
    let n = 709usize;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    testsupport::shapes::grid(n - 1, n - 1, Diagonals::Uniform, |c, r| {
        let (r, c) = (r as f64, c as f64);
        DVec3::new(
            c,
            r,
            0.1 * (0.05 * r).sin() * (0.03 * c).cos() + 1e-3 * rng.random::<f64>(),
        )
    })
    .expect("valid grid")
}

fn peer(path: &Path) {
    let py = std::env::var("BIPOLAR_PEER_PYTHON")
        .unwrap_or_else(|_| "/work/venv-peers/bin/python".into());
    if !Path::new(&py).exists() {
        println!("peer skipped: {py} not found");
        return;
    }
    let script = r#"
import sys, time, trimesh
p = sys.argv[1]
for process in (False, True):
    ts = []
    for _ in range(5):
        t = time.perf_counter()
        m = trimesh.load(p, process=process)
        ts.append(time.perf_counter() - t)
    ts.sort()
    print(f"trimesh {trimesh.__version__} load(process={process}): median {ts[2]*1e3:.1f} ms, min {ts[0]*1e3:.1f} ms, {len(m.vertices)} vertices, {len(m.faces)} faces")
"#;
    match std::process::Command::new(&py)
        .arg("-c")
        .arg(script)
        .arg(path)
        .output()
    {
        Ok(o) => {
            print!("{}", String::from_utf8_lossy(&o.stdout));
            if !o.status.success() {
                println!("peer failed: {}", String::from_utf8_lossy(&o.stderr));
            }
        }
        Err(e) => println!("peer skipped: {e}"),
    }
}

fn paper_set() -> Option<Vec<PathBuf>> {
    let dir = testsupport::shared_path(testsupport::PAPER_SET)?;
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .collect();
    v.sort();
    Some(v)
}

fn main() {
    let path = std::env::temp_dir().join(format!("bipolar-bench-1m-{}.ply", std::process::id()));
    let mesh = big_mesh();
    mesh_io::write_mesh(&path, &mesh_io::LoadedMesh::new(mesh)).expect("write bench file");
    let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
    println!(
        "bench file {} ({:.1} MB, binary little endian, double x y z, list uchar int)",
        path.display(),
        size as f64 / 1e6
    );
    let mut c = Criterion::default()
        .configure_from_args()
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    c.bench_function("mesh_io::read_mesh 1M-triangle binary PLY", |b| {
        b.iter(|| black_box(mesh_io::read_mesh(&path).expect("read")))
    });
    if let Some(files) = paper_set() {
        if files.len() == 12 {
            c.bench_function("mesh_io::read_mesh 12 paper-set OBJ faces", |b| {
                b.iter(|| {
                    for f in &files {
                        black_box(mesh_io::read_mesh(f).expect("read"));
                    }
                })
            });
        }
    }
    c.final_summary();
    peer(&path);
    let _ = std::fs::remove_file(&path);
}
