//! `bipolar convert`: convert a mesh between formats (chosen by file extension).

use std::path::PathBuf;

/// Arguments of `bipolar convert`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Input mesh (obj, ply, stl, off, gltf, glb, bnt).
    pub input: PathBuf,
    /// Output mesh (obj, ply, stl, off, glb). PLY is written binary little endian unless
    /// `--ascii` is given; per-vertex colours and scalars are kept where the format allows.
    pub output: PathBuf,
    /// Merge vertices closer than TOL (absolute, in mesh units; 0 merges exact duplicates).
    #[arg(long, value_name = "TOL")]
    pub weld: Option<f64>,
    /// Remove degenerate faces (repeated vertex or area <= 1e-12 x bbox diagonal^2).
    #[arg(long)]
    pub drop_degenerate: bool,
    /// Write PLY as ASCII text.
    #[arg(long)]
    pub ascii: bool,
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(t) = args.weld {
        anyhow::ensure!(
            t.is_finite() && t >= 0.0,
            "--weld must be a finite tolerance >= 0, got {t}"
        );
    }
    let mut m = crate::load::mesh(&args.input)?;
    for w in &m.warnings {
        eprintln!("warning: {}: {w}", args.input.display());
    }
    if let Some(t) = args.weld {
        let s = m.weld(t);
        eprintln!(
            "welded {} vertices, removed {} collapsed faces and {} unused vertices",
            s.welded_vertices, s.removed_faces, s.removed_vertices
        );
    }
    if args.drop_degenerate {
        let s = m.drop_degenerate(1e-12);
        eprintln!(
            "removed {} degenerate faces and {} unused vertices",
            s.removed_faces, s.removed_vertices
        );
    }
    let is_ply = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if args.ascii && is_ply {
        let opts = mesh_io::PlyWriteOptions {
            encoding: mesh_io::PlyEncoding::Ascii,
            colors: m.colors.as_deref(),
            scalars: &m.scalars,
        };
        mesh_io::write_ply(&args.output, &m.mesh, &opts)?;
    } else {
        anyhow::ensure!(!args.ascii, "--ascii applies to PLY output only");
        mesh_io::write_mesh(&args.output, &m)?;
    }
    eprintln!(
        "wrote {} ({} vertices, {} faces)",
        args.output.display(),
        m.mesh.n_vertices(),
        m.mesh.n_faces()
    );
    Ok(())
}
