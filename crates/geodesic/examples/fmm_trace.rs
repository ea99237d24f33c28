//! Diagnostic of the curved-front fast-marching update on a unit-sphere mesh (by default the
//! peers' `uv10k.obj` from vertex 4901): the carried front curvature against the sphere's by
//! distance, and the walk back from the worst vertex through its candidate updates.
//!
//! ```text
//! cargo run --release -p geodesic --example fmm_trace -- [MESH] [SOURCE] [START]
//! ```
//!
//! MESH defaults to `meshes/uv10k.obj` in `GEODESIC_PEERS_DIR` (default `/tmp/peers-geo`,
//! written by `make_meshes.py` of `../shared/peers/geodesic`); SOURCE to 4901; START (the
//! vertex the walk starts from) to the vertex of largest error.

use std::path::PathBuf;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mesh = args.first().map_or_else(
        || {
            let dir =
                std::env::var("GEODESIC_PEERS_DIR").unwrap_or_else(|_| "/tmp/peers-geo".into());
            PathBuf::from(dir).join("meshes").join("uv10k.obj")
        },
        PathBuf::from,
    );
    let vertex = |i: usize| {
        args.get(i).map(|s| {
            s.parse::<u32>()
                .unwrap_or_else(|e| panic!("vertex index {s:?}: {e}"))
        })
    };
    let (src, start) = (vertex(1).unwrap_or(4901), vertex(2));
    let mesh = testsupport::read_mesh(&mesh);
    match geodesic::trace_curved_front(&mesh, src, start) {
        Ok(report) => print!("{report}"),
        Err(e) => panic!("{e}"),
    }
}
