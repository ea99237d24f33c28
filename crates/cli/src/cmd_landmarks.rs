//! `bipolar landmarks`: automatic detection of the outer and inner eye corners and the nose tip.

use anyhow::Context;
use landmarks::{detect_visible, io, DetectOptions, GenericModel, LandmarkName};
use std::path::PathBuf;

/// Arguments of `bipolar landmarks`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file (obj, ply, stl, off, gltf, glb, bnt).
    pub mesh: PathBuf,
    /// Generic face model (JSON); default: the model shipped with the tool (trained on ICT
    /// FaceKit faces, cm).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Output JSON file of the detected landmarks.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also write the landmarks as a Bosphorus `.lm3` file.
    #[arg(long)]
    pub lm3: Option<PathBuf>,
    /// Mesh units per model unit (10 for a scan in mm with the default model in cm); by
    /// default recognised from the size of the face (mm, cm or m) and printed.
    #[arg(long)]
    pub scale: Option<f64>,
    /// Overall confidence below which detection fails (default: the library's,
    /// `landmarks::DetectOptions::default().min_confidence`, calibrated on training faces).
    #[arg(long)]
    pub min_confidence: Option<f64>,
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let loaded = crate::load::mesh(&args.mesh)?;
    let model = match &args.model {
        Some(p) => GenericModel::load(p)?,
        None => GenericModel::default_model()?,
    };
    let scale = match args.scale {
        Some(s) => s,
        None => {
            let u = meshcore::units::detect_units(&loaded.mesh)
                .with_context(|| format!("units of {}", args.mesh.display()))?;
            println!(
                "{}: units {} (recognised from the face size, {:.1} {}; override with --scale)",
                args.mesh.display(),
                u.units,
                u.size,
                u.units
            );
            landmarks::mesh_units_per_model_unit(&loaded.mesh, &model)?
        }
    };
    let opts = DetectOptions {
        mesh_units_per_model_unit: scale,
        min_confidence: args
            .min_confidence
            .unwrap_or(DetectOptions::default().min_confidence),
        toward_viewer: crate::load::toward_scanner(&args.mesh),
        ..DetectOptions::default()
    };
    // A landmark the scanner did not see is reported as not found, with the reason.
    let lm = detect_visible(&loaded.mesh, &model, &opts)
        .with_context(|| format!("landmark detection on {}", args.mesh.display()))?;
    println!(
        "{}: face found, confidence {:.2} (fit rms {:.4}, {:.0} % of the generic face matched)",
        args.mesh.display(),
        lm.confidence,
        lm.fit_rms,
        100.0 * lm.inlier_fraction
    );
    for n in LandmarkName::ALL {
        match lm.get(n) {
            Ok(l) => println!(
                "  {:<16} vertex {:>7}  ({:.4}, {:.4}, {:.4})  confidence {:.2}",
                n.key(),
                l.vertex,
                l.position.x,
                l.position.y,
                l.position.z,
                l.confidence
            ),
            Err(u) => println!("  {:<16} not found: {u}", n.key()),
        }
    }
    if let Some(p) = &args.out {
        mesh_io::write_landmarks_json(p, &io::to_json_file(&lm))?;
        println!("wrote {}", p.display());
    }
    if let Some(p) = &args.lm3 {
        let (file, notes) = io::to_lm3_file(&lm);
        mesh_io::write_lm3_with_notes(p, &file, &notes)?;
        println!("wrote {}", p.display());
    }
    Ok(())
}
