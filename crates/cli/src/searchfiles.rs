//! The files of a reference-point search: `bipolar describe --search-radius` writes the moved
//! descriptors as `STEM.search-NN.EXT` beside its `STEM.EXT`; `bipolar distance --searched`
//! and `bipolar matrix --searched` read them back.

use std::path::{Path, PathBuf};

use anyhow::Context;

/// Where the `k`-th moved descriptor of `own` goes: `STEM.search-KK.EXT` beside it.
pub fn search_path(own: &Path, k: usize) -> PathBuf {
    let stem = own.file_stem().unwrap_or_default().to_string_lossy();
    let ext = own.extension().unwrap_or_default().to_string_lossy();
    own.with_file_name(format!("{stem}.search-{k:02}.{ext}"))
}

/// The number `k` of a search file of `own` named `STEM.search-K.EXT` (digits only), else
/// `None`.
fn search_number(own: &Path, name: &str) -> Option<usize> {
    let stem = own.file_stem()?.to_str()?;
    let ext = own.extension()?.to_str()?;
    let digits = name
        .strip_prefix(stem)?
        .strip_prefix(".search-")?
        .strip_suffix(ext)?
        .strip_suffix('.')?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// The descriptor file a search file belongs to (`STEM.search-NN.EXT` -> `STEM.EXT`, in the
/// same folder), or `None` when `path` is not named as one.
pub fn own_of(path: &Path) -> Option<PathBuf> {
    let name = path.file_name()?.to_str()?;
    let ext = path.extension()?.to_str()?;
    let (stem, _) = path.file_stem()?.to_str()?.rsplit_once(".search-")?;
    let own = path.with_file_name(format!("{stem}.{ext}"));
    search_number(&own, name).map(|_| own)
}

/// The search files beside `own` with their numbers, in the order of their numbers.
fn numbered(own: &Path) -> anyhow::Result<Vec<(usize, PathBuf)>> {
    let mut found: Vec<(usize, PathBuf)> = Vec::new();
    let dir = match own.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let entries = std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))?;
    for e in entries {
        let e = e.with_context(|| format!("listing {}", dir.display()))?;
        let name = e.file_name();
        if let Some(k) = name.to_str().and_then(|n| search_number(own, n)) {
            found.push((k, own.with_file_name(name)));
        }
    }
    found.sort();
    Ok(found)
}

/// The search files beside `own`, in the order of their numbers.
pub fn search_files(own: &Path) -> anyhow::Result<Vec<PathBuf>> {
    Ok(numbered(own)?.into_iter().map(|(_, p)| p).collect())
}

/// Removes the search files beside `own` numbered above `keep` (left by an earlier `describe`
/// with a search or a larger one, which `--searched` would otherwise read as this one's);
/// returns how many.
pub fn remove_stale(own: &Path, keep: usize) -> anyhow::Result<usize> {
    let mut n = 0;
    for (_, p) in numbered(own)?.into_iter().filter(|(k, _)| *k > keep) {
        std::fs::remove_file(&p).with_context(|| format!("removing {}", p.display()))?;
        n += 1;
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_others_are_not_search_files() {
        let own = Path::new("out/face.v2.csv");
        let s = search_path(own, 7);
        assert_eq!(s, Path::new("out/face.v2.search-07.csv"));
        assert_eq!(own_of(&s).as_deref(), Some(own));
        assert_eq!(
            own_of(Path::new("face.search-123.json")).as_deref(),
            Some(Path::new("face.json"))
        );
        for not in [
            "face.csv",
            "face.search-.csv",
            "face.search-0x.csv",
            "face.search-01",
            "face.searching-01.csv",
        ] {
            assert_eq!(own_of(Path::new(not)), None, "{not}");
        }
    }

    #[test]
    fn search_files_are_listed_in_order_and_stale_ones_removed() {
        let dir = tempfile::tempdir().unwrap();
        let own = dir.path().join("a.csv");
        for name in [
            "a.csv",
            "a.search-10.csv",
            "a.search-02.csv",
            "a.search-01.csv",
            "a.search-01.json",
            "ab.search-01.csv",
            "b.search-01.csv",
        ] {
            std::fs::write(dir.path().join(name), "").unwrap();
        }
        let names = |v: Vec<PathBuf>| -> Vec<String> {
            v.iter()
                .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
                .collect()
        };
        assert_eq!(
            names(search_files(&own).unwrap()),
            ["a.search-01.csv", "a.search-02.csv", "a.search-10.csv"]
        );
        assert_eq!(remove_stale(&own, 2).unwrap(), 1);
        assert_eq!(
            names(search_files(&own).unwrap()),
            ["a.search-01.csv", "a.search-02.csv"]
        );
        assert_eq!(remove_stale(&own, 0).unwrap(), 2);
        assert!(search_files(&own).unwrap().is_empty());
        assert!(dir.path().join("a.search-01.json").exists());
        assert!(dir.path().join("ab.search-01.csv").exists());
    }
}
