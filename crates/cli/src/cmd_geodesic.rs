//! `bipolar geodesic`: a geodesic distance field from source vertices or surface points.
//!
//! Writes one distance per vertex, in vertex order, in a format chosen by the extension of
//! `--out`: `.txt` (one value per line), `.csv` (header `vertex,distance`), `.npy` (float64,
//! shape `(n,)`) or `.ply` (the mesh with a `double distance` vertex property). Unreachable
//! vertices (other components, beyond `--max-distance`) get `inf`.

use anyhow::{bail, Context};
use geodesic::{Method, SolveOptions, Source};
use meshcore::{DVec3, FaceLocator, TriMesh};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `bipolar geodesic`.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("src").required(true).multiple(true).args(["source", "source_point"])))]
pub struct Args {
    /// Input mesh (OBJ, PLY, STL, OFF, glTF/GLB, BNT).
    pub mesh: PathBuf,
    /// Source vertex index (0-based); repeat for several sources.
    #[arg(long = "source", value_name = "V")]
    pub source: Vec<u32>,
    /// Source point `X,Y,Z`, snapped to the nearest surface point; repeat for several.
    #[arg(long = "source-point", value_name = "X,Y,Z", value_parser = parse_point, allow_hyphen_values = true)]
    pub source_point: Vec<DVec3>,
    /// Method: exact (polyhedral), fmm (fast marching), heat (heat method) or dijkstra (edges).
    #[arg(long, default_value = "exact", value_parser = parse_method)]
    pub method: Method,
    /// Stop at this distance; farther vertices get `inf`.
    #[arg(long = "max-distance", value_name = "D")]
    pub max_distance: Option<f64>,
    /// Output file: `.txt`, `.csv`, `.npy` or `.ply`.
    #[arg(long)]
    pub out: PathBuf,
}

fn parse_method(s: &str) -> Result<Method, String> {
    s.parse::<Method>().map_err(|e| e.to_string())
}

fn parse_point(s: &str) -> Result<DVec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected X,Y,Z (three comma-separated numbers), got {s:?}"
        ));
    }
    let mut c = [0.0; 3];
    for (k, p) in parts.iter().enumerate() {
        c[k] = p
            .parse::<f64>()
            .map_err(|e| format!("coordinate {} of {s:?}: {e}", k + 1))?;
        if !c[k].is_finite() {
            return Err(format!("coordinate {} of {s:?} is not finite", k + 1));
        }
    }
    Ok(DVec3::from_array(c))
}

/// Output formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum OutFormat {
    Txt,
    Csv,
    Npy,
    Ply,
}

fn out_format(path: &Path) -> anyhow::Result<OutFormat> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    Ok(match ext.as_str() {
        "txt" => OutFormat::Txt,
        "csv" => OutFormat::Csv,
        "npy" => OutFormat::Npy,
        "ply" => OutFormat::Ply,
        _ => bail!(
            "unknown output extension {ext:?} of {}: expected .txt, .csv, .npy or .ply",
            path.display()
        ),
    })
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let fmt = out_format(&args.out)?;
    let loaded = mesh_io::read_mesh(&args.mesh)
        .with_context(|| format!("reading {}", args.mesh.display()))?;
    let mesh = loaded.mesh;
    let mut sources: Vec<Source> = args.source.iter().map(|&v| Source::Vertex(v)).collect();
    if !args.source_point.is_empty() {
        let loc = FaceLocator::new(&mesh);
        for p in &args.source_point {
            let (sp, d) = loc.nearest(*p)?;
            eprintln!(
                "source point ({}, {}, {}) snapped to face {} (bary {:.6}, {:.6}, {:.6}), {:.3e} away",
                p.x, p.y, p.z, sp.face, sp.bary.x, sp.bary.y, sp.bary.z, d
            );
            sources.push(Source::Point(sp));
        }
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
    fn point_parsing() {
        assert_eq!(
            parse_point("1, -2.5,3e-1").unwrap(),
            DVec3::new(1.0, -2.5, 0.3)
        );
        assert!(parse_point("1,2").is_err());
        assert!(parse_point("1,2,nan").is_err());
        assert!(out_format(Path::new("a.xyz")).is_err());
        assert_eq!(out_format(Path::new("a.NPY")).unwrap(), OutFormat::Npy);
    }
}
