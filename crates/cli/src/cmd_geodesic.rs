//! `bipolar geodesic`: a geodesic distance field from source vertices or surface points.
//!
//! Writes one distance per vertex, in vertex order, in a format chosen by the extension of
//! `--out`: `.txt` (one value per line), `.csv` (header `vertex,distance`), `.npy` (float64,
//! shape `(n,)`) or `.ply` (the mesh with a `double distance` vertex property). Unreachable
//! vertices (other components, beyond `--max-distance`) get `inf`.

use crate::choice::{choice, from_extension};
use crate::refpoint::{RefArgs, Resolver};
use anyhow::Context;
use geodesic::{Method, SolveOptions, Source};
use meshcore::TriMesh;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `bipolar geodesic`.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("src").required(true).multiple(true).args(["source", "source_point"])))]
pub struct Args {
    /// Input mesh (OBJ, PLY, STL, OFF, glTF/GLB, BNT).
    pub mesh: PathBuf,
    /// Source: a vertex index (0-based), `X,Y,Z` (snapped to the nearest surface point, within
    /// --snap-tolerance) or a landmark name (from --landmarks, or detected); repeat for several.
    #[arg(long = "source", value_name = "REF", allow_hyphen_values = true)]
    pub source: Vec<String>,
    /// Source point `X,Y,Z` (read like --source); repeat for several.
    #[arg(
        long = "source-point",
        value_name = "X,Y,Z",
        allow_hyphen_values = true
    )]
    pub source_point: Vec<String>,
    /// How sources are read (landmark file, snapping tolerance).
    #[command(flatten)]
    pub refs: RefArgs,
    /// Method: exact (polyhedral), fmm (fast marching), heat (heat method) or dijkstra (edges).
    #[arg(long, default_value = "exact", value_parser = choice::<Method>())]
    pub method: Method,
    /// Stop at this distance; farther vertices get `inf`.
    #[arg(long = "max-distance", value_name = "D")]
    pub max_distance: Option<f64>,
    /// Output file: `.txt`, `.csv`, `.npy` or `.ply`.
    #[arg(long)]
    pub out: PathBuf,
}

meshcore::choice! {
    /// Output formats.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum OutFormat: "distance file", meshcore::UnknownChoice {
        Txt = "txt",
        Csv = "csv",
        Npy = "npy",
        Ply = "ply",
    }
}

fn out_format(path: &Path) -> anyhow::Result<OutFormat> {
    from_extension(path)
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let fmt = out_format(&args.out)?;
    let loaded = crate::load::mesh(&args.mesh)?;
    let mesh = loaded.mesh;
    let resolver = Resolver::new(&mesh, &args.mesh, &args.refs)?;
    let mut sources: Vec<Source> = Vec::new();
    for s in &args.source {
        sources.push(resolver.resolve(s, "--source")?.source);
    }
    for s in &args.source_point {
        sources.push(resolver.resolve(s, "--source-point")?.source);
    }
    let t0 = Instant::now();
    let solver = geodesic::new_solver(&mesh, args.method)
        .with_context(|| format!("preparing the {} solver", args.method.name()))?;
    let t1 = Instant::now();
    let dist = solver
        .distances(
            &sources,
            &SolveOptions {
                max_distance: args.max_distance,
            },
        )
        .context("computing distances")?;
    let t2 = Instant::now();
    write_field(&args.out, fmt, &mesh, &dist)?;
    let finite: Vec<f64> = dist.iter().copied().filter(|d| d.is_finite()).collect();
    let max = finite.iter().copied().fold(0.0, f64::max);
    eprintln!(
        "{}: {} vertices, {} reached, max distance {:.6}; setup {:.3} s, solve {:.3} s -> {}",
        solver.method().name(),
        solver.n_vertices(),
        finite.len(),
        max,
        (t1 - t0).as_secs_f64(),
        (t2 - t1).as_secs_f64(),
        args.out.display()
    );
    Ok(())
}

fn write_field(path: &Path, fmt: OutFormat, mesh: &TriMesh, dist: &[f64]) -> anyhow::Result<()> {
    let ctx = || format!("writing {}", path.display());
    match fmt {
        OutFormat::Txt | OutFormat::Csv => {
            let mut s = String::with_capacity(dist.len() * 20);
            if fmt == OutFormat::Csv {
                s.push_str("vertex,distance\n");
            }
            for (v, d) in dist.iter().enumerate() {
                if fmt == OutFormat::Csv {
                    s.push_str(&format!("{v},{d}\n"));
                } else {
                    s.push_str(&format!("{d}\n"));
                }
            }
            std::fs::write(path, s).with_context(ctx)?;
        }
        OutFormat::Npy => {
            let mut f = std::io::BufWriter::new(std::fs::File::create(path).with_context(ctx)?);
            f.write_all(&npy_f64(dist)).with_context(ctx)?;
            f.flush().with_context(ctx)?;
        }
        OutFormat::Ply => {
            let field = mesh_io::ScalarField {
                name: "distance".into(),
                values: dist.to_vec(),
                ty: mesh_io::ScalarType::F64,
            };
            mesh_io::write_ply(
                path,
                mesh,
                &mesh_io::PlyWriteOptions {
                    scalars: std::slice::from_ref(&field),
                    ..Default::default()
                },
            )
            .with_context(ctx)?;
        }
    }
    Ok(())
}

/// A 1-D little-endian float64 `.npy` file (format version 1.0).
fn npy_f64(values: &[f64]) -> Vec<u8> {
    let mut header = format!(
        "{{'descr': '<f8', 'fortran_order': False, 'shape': ({},), }}",
        values.len()
    );
    // Magic (6) + version (2) + header length (2) + header + '\n' must be a multiple of 64.
    let total = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - total % 64) % 64));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + 8 * values.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_header_is_aligned() {
        let b = npy_f64(&[1.0, 2.5]);
        let hl = u16::from_le_bytes([b[8], b[9]]) as usize;
        assert_eq!((10 + hl) % 64, 0);
        assert_eq!(b.len(), 10 + hl + 16);
        assert_eq!(
            f64::from_le_bytes(b[10 + hl..18 + hl].try_into().unwrap()),
            1.0
        );
    }

    #[test]
    fn output_formats() {
        assert!(out_format(Path::new("a.xyz")).is_err());
        assert_eq!(out_format(Path::new("a.NPY")).unwrap(), OutFormat::Npy);
    }
}
