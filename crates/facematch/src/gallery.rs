//! A gallery of templates: a folder of `.bpt` files or one `.bpg` file; identification.

use crate::template::read_file;
use crate::{compare, Comparison, Description, MatchError, MatchOptions, Template};
use rayon::prelude::*;
use std::path::Path;

/// Templates to identify probes against.
#[derive(Debug, Clone, Default)]
pub struct Gallery {
    /// The templates, in file order.
    pub templates: Vec<Template>,
}

/// One identity of a ranking.
#[derive(Debug, Clone, PartialEq)]
pub struct Ranked {
    /// The identity.
    pub identity: String,
    /// Its best template's source.
    pub template: String,
    /// Its best template's score (NaN when no comparison gave one).
    pub score: f64,
    /// Its best template's comparison.
    pub comparison: Comparison,
}

impl Gallery {
    /// The gallery at `path`: every `.bpt` file of a folder (by name), or a `.bpg` (or single
    /// `.bpt`) file. Each template must have been made with `options`' settings
    /// ([`MatchError::Settings`]); a gallery with none is [`MatchError::EmptyGallery`].
    pub fn open(path: &Path, options: &MatchOptions) -> Result<Self, MatchError> {
        let mut templates = Vec::new();
        if path.is_dir() {
            let io = |source| meshcore::FileError::new("list", path, source);
            let mut files: Vec<_> = std::fs::read_dir(path)
                .map_err(io)?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "bpt"))
                .collect();
            files.sort();
            for f in files {
                let t = Template::read(&f)?;
                t.check_settings(options, &f.display().to_string())?;
                templates.push(t);
            }
        } else {
            let name = path.display().to_string();
            for t in Template::many_from_bytes(&read_file(path)?, &name)? {
                t.check_settings(options, &name)?;
                templates.push(t);
            }
        }
        if templates.is_empty() {
            return Err(MatchError::EmptyGallery(path.display().to_string()));
        }
        Ok(Self { templates })
    }

    /// Writes the gallery as one `.bpg` file.
    pub fn write(&self, path: &Path) -> Result<(), MatchError> {
        std::fs::write(path, Template::gallery_bytes(&self.templates))
            .map_err(|source| meshcore::FileError::new("write", path, source).into())
    }

    /// The probe compared with every template (in parallel, in template order).
    pub fn compare_all(&self, probe: &Description, options: &MatchOptions) -> Vec<Comparison> {
        self.templates
            .par_iter()
            .map(|t| compare(probe, t, options))
            .collect()
    }

    /// The identities ranked by their best template's score, best (lowest) first; ties and
    /// failed scores (NaN, last) ordered by identity.
    pub fn identify(&self, probe: &Description, options: &MatchOptions) -> Vec<Ranked> {
        rank(&self.templates, self.compare_all(probe, options))
    }
}

/// The identities of `templates` ranked by their best score among `comparisons` (one per
/// template, in order): lowest first, NaN last, ties by identity.
pub fn rank(templates: &[Template], comparisons: Vec<Comparison>) -> Vec<Ranked> {
    let mut best: Vec<Ranked> = Vec::new();
    for (t, c) in templates.iter().zip(comparisons) {
        let better = |r: &Ranked| !c.score.is_nan() && (r.score.is_nan() || c.score < r.score);
        match best.iter_mut().find(|r| r.identity == t.identity) {
            Some(r) if better(r) => {
                r.score = c.score;
                r.template = t.source.clone();
                r.comparison = c;
            }
            Some(_) => {}
            None => best.push(Ranked {
                identity: t.identity.clone(),
                template: t.source.clone(),
                score: c.score,
                comparison: c,
            }),
        }
    }
    best.sort_by(|a, b| {
        let key = |x: f64| (x.is_nan(), if x.is_nan() { 0.0 } else { x });
        let (ka, kb) = (key(a.score), key(b.score));
        ka.0.cmp(&kb.0)
            .then(ka.1.total_cmp(&kb.1))
            .then_with(|| a.identity.cmp(&b.identity))
    });
    best
}
