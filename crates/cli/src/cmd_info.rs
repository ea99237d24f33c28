//! `bipolar info`: statistics and checks of a mesh.

use meshcore::Topology;
use std::path::PathBuf;

/// Arguments of `bipolar info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file (obj, ply, stl, off, gltf, glb, bnt).
    pub mesh: PathBuf,
    /// Print a JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let loaded = crate::load::mesh(&args.mesh)?;
    let report = info_json(&loaded, &args.mesh.display().to_string());
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_text(&report);
    }
    Ok(())
}

/// All statistics as a JSON value (also the source of the text output).
pub fn info_json(loaded: &mesh_io::LoadedMesh, file: &str) -> serde_json::Value {
    let m = &loaded.mesh;
    let topo = Topology::new(m);
    let bb = m.bbox();
    let mut loops: Vec<usize> = topo.boundary_loops().iter().map(Vec::len).collect();
    loops.sort_unstable_by(|a, b| b.cmp(a));
    serde_json::json!({
        "file": file,
        "vertices": m.n_vertices(),
        "faces": m.n_faces(),
        "edges": topo.edges().len(),
        "bbox": {"min": [bb.min.x, bb.min.y, bb.min.z], "max": [bb.max.x, bb.max.y, bb.max.z], "diagonal": bb.diagonal()},
        "area": m.area(),
        "mean_edge_length": m.mean_edge_length(),
        "components": topo.n_components(),
        "isolated_vertices": topo.isolated_vertices(),
        "boundary_loops": loops.len(),
        "boundary_loop_lengths": loops,
        "non_manifold_edges": topo.non_manifold_edges().len(),
        "non_manifold_vertices": topo.non_manifold_vertices().len(),
        "orientation_conflicts": topo.inconsistent_edges().len(),
        "degenerate_faces": mesh_io::count_degenerate_faces(m),
        "duplicate_vertices": mesh_io::count_duplicate_vertices(m),
        "has_colors": loaded.colors.is_some(),
        "scalars": loaded.scalars.iter().map(|s| s.name.clone()).collect::<Vec<_>>(),
        "warnings": loaded.warnings,
    })
}

fn print_text(r: &serde_json::Value) {
    let g = |k: &str| r[k].to_string();
    println!(
        "file:                  {}",
        r["file"].as_str().unwrap_or("")
    );
    println!("vertices:              {}", g("vertices"));
    println!("faces:                 {}", g("faces"));
    println!("edges:                 {}", g("edges"));
    let bb = &r["bbox"];
    println!("bbox min:              {}", bb["min"]);
    println!("bbox max:              {}", bb["max"]);
    println!("bbox diagonal:         {}", bb["diagonal"]);
    println!("area:                  {}", g("area"));
    println!("mean edge length:      {}", g("mean_edge_length"));
    println!("components:            {}", g("components"));
    println!("isolated vertices:     {}", g("isolated_vertices"));
    println!(
        "boundary loops:        {} (lengths in edges: {})",
        g("boundary_loops"),
        r["boundary_loop_lengths"]
    );
    println!("non-manifold edges:    {}", g("non_manifold_edges"));
    println!("non-manifold vertices: {}", g("non_manifold_vertices"));
    println!("orientation conflicts: {}", g("orientation_conflicts"));
    println!("degenerate faces:      {}", g("degenerate_faces"));
    println!("duplicate vertices:    {}", g("duplicate_vertices"));
    if let Some(w) = r["warnings"].as_array() {
        for w in w {
            println!("warning: {}", w.as_str().unwrap_or(""));
        }
    }
}
