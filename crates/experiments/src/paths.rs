//! The command-line options the tasks share (`--out`, `--faces`, `--model`, the resolution) and
//! the default locations behind them.

use std::path::{Path, PathBuf};

/// The paper set in the shared data folder (`facemodel::default_paper_set`). Without a shared
/// folder the task cannot run: prints the lookup's error and exits with status 1.
pub fn default_paper_set() -> PathBuf {
    or_exit(facemodel::default_paper_set())
}

/// The ICT model folder in the shared data folder (`facemodel::default_model_dir`); exits like
/// [`default_paper_set`].
pub fn default_model_dir() -> PathBuf {
    or_exit(facemodel::default_model_dir())
}

fn or_exit(r: Result<PathBuf, facemodel::FaceModelError>) -> PathBuf {
    r.unwrap_or_else(|e| {
        eprintln!("Error: {e}");
        std::process::exit(1)
    })
}

/// Output folder `name` under the cargo target directory (`$CARGO_TARGET_DIR` if set,
/// else `<workspace>/target`).
pub fn default_out_dir(name: &str) -> PathBuf {
    let target = match std::env::var_os("CARGO_TARGET_DIR") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => workspace_root().join("target"),
    };
    target.join(name)
}

/// The workspace root: two levels above this crate's manifest (`crates/experiments`).
fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .nth(2)
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// `--out` of every task: the folder the task writes into.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct OutArgs {
    /// Output folder (default `target/<task>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

impl OutArgs {
    /// The output folder: `--out` or `target/<task>` ([`default_out_dir`]).
    pub fn out_dir(&self, task: &str) -> PathBuf {
        self.out.clone().unwrap_or_else(|| default_out_dir(task))
    }
}

/// `--faces`, `--out` and the resolution of the tasks that read a face set.
#[derive(Debug, Clone, clap::Args)]
pub struct FaceSetArgs {
    /// Folder of the face set (OBJ files + landmarks.json); default
    /// `$BIPOLAR_SHARED/faces/ict-facekit/paper-set` (BIPOLAR_SHARED defaults to `../shared`).
    #[arg(long)]
    pub faces: Option<PathBuf>,
    /// The output folder (`--out`).
    #[command(flatten)]
    pub out: OutArgs,
    /// The resolution of the descriptors (`--levels`, `--sectors`).
    #[command(flatten)]
    pub res: ResolutionArgs,
}

impl FaceSetArgs {
    /// The face-set folder: `--faces` or the shared paper set.
    pub fn faces_dir(&self) -> PathBuf {
        self.faces.clone().unwrap_or_else(default_paper_set)
    }

    /// Loads the face set and picks the test face (`id1_neutral`, else the first); prints
    /// what was loaded. Returns the faces and the test face's index.
    pub fn load(&self) -> anyhow::Result<(Vec<facemodel::Face>, usize)> {
        let dir = self.faces_dir();
        let faces = facemodel::load_face_set(&dir)?;
        let test = faces
            .iter()
            .position(|f| f.name == "id1_neutral")
            .unwrap_or(0);
        eprintln!(
            "{} faces from {}; test face {}",
            faces.len(),
            dir.display(),
            faces[test].name
        );
        Ok((faces, test))
    }
}

/// The resolution of the bipolar and single-pole descriptors.
#[derive(Debug, Clone, Copy, clap::Args)]
pub struct ResolutionArgs {
    /// Levels N between the two reference points (the bipolar step is D / N; the single-pole
    /// radius levels use the same step).
    #[arg(long, default_value_t = 10)]
    pub levels: u32,
    /// Angular sectors of the single-pole representation.
    #[arg(long, default_value_t = 16)]
    pub sectors: u32,
}

/// `--model` and `--out` of the tasks that sample faces from the ICT face model.
#[derive(Debug, Clone, clap::Args)]
pub struct ModelArgs {
    /// ICT model folder (default `$BIPOLAR_SHARED/faces/ict-facekit/model`).
    #[arg(long = "model", visible_alias = "model-dir")]
    pub model: Option<PathBuf>,
    /// The output folder (`--out`).
    #[command(flatten)]
    pub out: OutArgs,
}

impl ModelArgs {
    /// The model folder: `--model` or the shared one.
    pub fn model_dir(&self) -> PathBuf {
        self.model.clone().unwrap_or_else(default_model_dir)
    }
}
