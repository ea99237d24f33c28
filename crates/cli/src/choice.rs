//! Command-line options that name a choice: every such argument parses through the option
//! enum's `FromStr` (the [`meshcore::Choice`] names), so the command line accepts exactly the
//! names the libraries and the Python bindings accept, `--help` lists them, and a bad name gets
//! the library's message listing the valid ones.

use clap::builder::{PossibleValue, TypedValueParser};
use meshcore::Choice;
use std::ffi::OsStr;
use std::marker::PhantomData;
use std::path::Path;

/// A clap value parser for the [`Choice`] `T` (use as `value_parser = choice::<T>()`).
#[derive(Debug)]
pub struct ChoiceParser<T>(PhantomData<fn() -> T>);

impl<T> Clone for ChoiceParser<T> {
    fn clone(&self) -> Self {
        ChoiceParser(PhantomData)
    }
}

/// The value parser of the [`Choice`] `T`.
pub fn choice<T>() -> ChoiceParser<T> {
    ChoiceParser(PhantomData)
}

impl<T> TypedValueParser for ChoiceParser<T>
where
    T: Choice + std::str::FromStr + Clone + Send + Sync + 'static,
    T::Err: std::fmt::Display,
{
    type Value = T;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<T, clap::Error> {
        let shown = arg.map_or_else(|| "value".to_string(), |a| a.to_string());
        let s = value.to_string_lossy();
        s.parse::<T>().map_err(|e| {
            cmd.clone().error(
                clap::error::ErrorKind::InvalidValue,
                format!("{shown}: {e}"),
            )
        })
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(T::ALL.iter().map(|v| {
            PossibleValue::new(v.name()).aliases(v.aliases().iter().copied())
        })))
    }
}

/// The [`Choice`] `T` named by the extension of `path` (e.g. the output format of a command),
/// with an error naming the file and listing the extensions.
pub fn from_extension<T>(path: &Path) -> anyhow::Result<T>
where
    T: Choice,
{
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    T::from_name(ext).map_err(|e| {
        anyhow::anyhow!(
            "{}: unknown {} extension {ext:?}; expected one of: {}",
            path.display(),
            e.what,
            e.expected
                .iter()
                .map(|n| format!(".{n}"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    })
}
