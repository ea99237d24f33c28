//! `bipolar scan`: the virtual range scanner (`rangescan`): renders a mesh into a Bosphorus
//! `.bnt` range grid in mm, with the artifact model, and projects landmarks onto it.

use anyhow::{bail, Context};
use meshcore::units::{detect_units, Units};
use meshcore::DVec3;
use rangescan::{
    scan_with_landmarks, Artifacts, DepthNoise, HeadPose, Holes, Outliers, Projection,
    Quantisation, ScanOptions, Spikes,
};
use std::path::PathBuf;

/// Artifact model to start from (parts are then changed by the other options).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Preset {
    /// The exact rendering.
    None,
    /// A structured-light scanner like Bosphorus's (`rangescan::Artifacts::structured_light`):
    /// 0.1 mm noise, 0.1 % spikes of 2-10 mm, 50 outliers, dropouts from 70 to 80 degrees of
    /// incidence, 4 holes of 1-4 mm radius.
    StructuredLight,
}

/// Arguments of `bipolar scan`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh to scan (obj, ply, stl, off, gltf, glb, bnt); its units are detected from the size
    /// of the face unless `--units` is given.
    pub mesh: PathBuf,
    /// Output range grid (`.bnt`, mm).
    #[arg(long)]
    pub out: PathBuf,
    /// Units of the input mesh (mm, cm, m); default: detected.
    #[arg(long)]
    pub units: Option<Units>,
    /// Sample pitch in mm (Bosphorus: 0.3-0.8).
    #[arg(long, default_value_t = 0.5, value_name = "MM")]
    pub pitch: f64,
    /// Head rotation about the vertical axis, degrees (positive: face turns to the scanner's
    /// right).
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "DEG",
        allow_hyphen_values = true
    )]
    pub yaw: f64,
    /// Head rotation about the horizontal axis, degrees (positive: chin up).
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "DEG",
        allow_hyphen_values = true
    )]
    pub pitch_angle: f64,
    /// Pinhole camera at this distance (mm) in front of the face; default orthographic.
    #[arg(long, value_name = "MM")]
    pub pinhole: Option<f64>,
    /// Artifact model to start from.
    #[arg(long, value_enum, default_value_t = Preset::StructuredLight)]
    pub artifacts: Preset,
    /// Gaussian depth noise, standard deviation in mm (0 switches it off).
    #[arg(long, value_name = "MM")]
    pub noise: Option<f64>,
    /// Fraction of samples turned into spikes of 2-10 mm (0 switches them off).
    #[arg(long, value_name = "FRACTION")]
    pub spikes: Option<f64>,
    /// Number of random holes of 1-4 mm radius (0 switches them off).
    #[arg(long, value_name = "N")]
    pub holes: Option<usize>,
    /// Number of background outliers (0 switches them off).
    #[arg(long, value_name = "N")]
    pub outliers: Option<usize>,
    /// Depth quantisation step in mm (default none).
    #[arg(long, value_name = "MM")]
    pub quantise: Option<f64>,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Landmarks to carry onto the scan: an `.lm3` file in the mesh's units.
    #[arg(long, value_name = "FILE")]
    pub landmarks: Option<PathBuf>,
    /// A landmark given as a vertex of the mesh, `LABEL=ID` (repeatable), e.g.
    /// `--landmark-vertex "Nose tip=4857"` on an ICT face.
    #[arg(long, value_name = "LABEL=ID")]
    pub landmark_vertex: Vec<String>,
    /// Write the landmarks the scanner sees to this `.lm3` file (mm, scan frame); those it
    /// cannot see are listed in the file's notes with the reason.
    #[arg(long, value_name = "FILE")]
    pub lm3: Option<PathBuf>,
}

fn artifacts(a: &Args) -> anyhow::Result<Artifacts> {
    let mut art = match a.artifacts {
        Preset::None => Artifacts::none(),
        Preset::StructuredLight => Artifacts::structured_light(),
    };
    if let Some(s) = a.noise {
        art.noise = (s != 0.0).then_some(DepthNoise { sigma_mm: s });
    }
    if let Some(f) = a.spikes {
        art.spikes = (f != 0.0).then_some(Spikes {
            fraction: f,
            min_mm: 2.0,
            max_mm: 10.0,
        });
    }
    if let Some(n) = a.holes {
        art.holes = (n != 0).then_some(Holes {
            count: n,
            min_radius_mm: 1.0,
            max_radius_mm: 4.0,
        });
    }
    if let Some(n) = a.outliers {
        art.outliers = (n != 0).then_some(Outliers { count: n });
    }
    if let Some(q) = a.quantise {
        art.quantisation = Some(Quantisation { step_mm: q });
    }
    Ok(art)
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let loaded = crate::load::mesh(&args.mesh)?;
    let mesh = &loaded.mesh;
    let units = match args.units {
        Some(u) => {
            println!("units: {u} (given)");
            u
        }
        None => {
            let d = detect_units(mesh).with_context(|| {
                format!("units of {} (give --units mm|cm|m)", args.mesh.display())
            })?;
            println!(
                "units: {} (detected: face size {:.4} {} = {:.0} mm); scanning in mm",
                d.units,
                d.size,
                d.units,
                d.size * d.units.mm_per_unit()
            );
            d.units
        }
    };
    let mut marks: Vec<(String, DVec3)> = Vec::new();
    if let Some(p) = &args.landmarks {
        let lm = mesh_io::read_lm3(p).with_context(|| format!("cannot read {}", p.display()))?;
        marks.extend(lm.labels.into_iter().zip(lm.points));
    }
    for s in &args.landmark_vertex {
        let Some((label, id)) = s.rsplit_once('=') else {
            bail!("--landmark-vertex {s:?}: expected LABEL=ID");
        };
        let id: u32 = id
            .trim()
            .parse()
            .with_context(|| format!("--landmark-vertex {s:?}: {id:?} is not a vertex id"))?;
        let p = mesh
            .try_position(id)
            .with_context(|| format!("--landmark-vertex {s:?}"))?;
        marks.push((label.trim().to_string(), p));
    }
    if args.lm3.is_some() && marks.is_empty() {
        bail!("--lm3 needs landmarks: give --landmarks FILE.lm3 or --landmark-vertex LABEL=ID");
    }
    let opts = ScanOptions {
        input_mm_per_unit: units.mm_per_unit(),
        pitch_mm: args.pitch,
        projection: match args.pinhole {
            Some(d) => Projection::Pinhole { distance_mm: d },
            None => Projection::Orthographic,
        },
        pose: HeadPose {
            yaw_deg: args.yaw,
            pitch_deg: args.pitch_angle,
        },
        artifacts: artifacts(&args)?,
        seed: args.seed,
        ..ScanOptions::default()
    };
    let s = scan_with_landmarks(mesh, &marks, &opts).context("scanning")?;
    mesh_io::write_bnt(&args.out, &s.grid)?;
    let st = &s.stats;
    println!(
        "scan: {} x {} grid at {} mm, {} valid samples ({} rendered; dropped: {} grazing, {} in holes, {} border; {} spikes, {} outliers)",
        s.grid.nrows, s.grid.ncols, args.pitch, st.valid, st.rendered, st.grazing, st.holes,
        st.border, st.spikes, st.outliers
    );
    println!("wrote {}", args.out.display());
    for l in &s.landmarks {
        println!(
            "  {:<24} ({:.2}, {:.2}, {:.2}) mm  {}",
            l.label, l.position.x, l.position.y, l.position.z, l.visibility
        );
    }
    if let Some(p) = &args.lm3 {
        let mut lm = mesh_io::Landmarks3d::default();
        let mut notes = Vec::new();
        for l in &s.landmarks {
            if l.visibility.is_visible() {
                lm.labels.push(l.label.clone());
                lm.points.push(l.position);
            } else {
                notes.push(format!("not visible: {}: {}", l.label, l.visibility));
            }
        }
        mesh_io::write_lm3_with_notes(p, &lm, &notes)?;
        println!("wrote {}", p.display());
    }
    Ok(())
}
