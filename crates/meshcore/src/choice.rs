//! Option enums that parse by name.
//!
//! Every option enum of the workspace (a geodesic method, a tangent method, a spline
//! parametrisation, ...) implements [`Choice`] through the [`choice!`](crate::choice!) macro,
//! which also gives it `FromStr` (failing with the owning crate's error, converted from
//! [`UnknownChoice`]) and `Display` (its name). Command lines, the Python bindings and the
//! experiments all parse options through these, so a name is spelt the same way everywhere
//! and a bad name always lists the valid ones.

use std::fmt;

/// An enum whose values are chosen by name.
pub trait Choice: Sized + Copy + 'static {
    /// What is chosen, for messages (e.g. `"geodesic method"`).
    const WHAT: &'static str;
    /// Every value, in the order the names are listed.
    const ALL: &'static [Self];
    /// The canonical name of this value (what `Display` prints and `FromStr` reads).
    fn name(self) -> &'static str;
    /// Further accepted spellings of this value (none by default).
    fn aliases(self) -> &'static [&'static str] {
        &[]
    }
    /// The canonical names of every value, in [`Choice::ALL`] order.
    fn names() -> Vec<&'static str> {
        Self::ALL.iter().map(|v| v.name()).collect()
    }
    /// The value whose name or alias equals `s` (surrounding whitespace ignored, ASCII case
    /// ignored), or an [`UnknownChoice`] listing the valid names.
    fn from_name(s: &str) -> Result<Self, UnknownChoice> {
        let t = s.trim();
        Self::ALL
            .iter()
            .copied()
            .find(|v| {
                v.name().eq_ignore_ascii_case(t)
                    || v.aliases().iter().any(|a| a.eq_ignore_ascii_case(t))
            })
            .ok_or_else(|| UnknownChoice {
                what: Self::WHAT,
                got: s.to_string(),
                expected: Self::names(),
            })
    }
}

/// A name that is none of the values of a [`Choice`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnknownChoice {
    /// What was being chosen (e.g. `"geodesic method"`).
    pub what: &'static str,
    /// The name given.
    pub got: String,
    /// The valid names.
    pub expected: Vec<&'static str>,
}

impl fmt::Display for UnknownChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown {} {:?}; expected one of: {}",
            self.what,
            self.got,
            self.expected.join(", ")
        )
    }
}

impl std::error::Error for UnknownChoice {}

/// Implements [`Choice`], `FromStr` and `Display` for a fieldless enum.
///
/// Two forms: for an enum declared elsewhere, `choice!(Enum, "what", Error { Variant = "name",
/// ... })`; or the enum declared in the macro, each variant written once with its name (its
/// attributes and doc comments kept):
///
/// ```
/// #[derive(Debug)]
/// pub struct MyError(meshcore::UnknownChoice);
/// impl From<meshcore::UnknownChoice> for MyError {
///     fn from(e: meshcore::UnknownChoice) -> Self { MyError(e) }
/// }
/// meshcore::choice! {
///     /// How a surface is shaded.
///     #[derive(Debug, Clone, Copy, PartialEq, Default)]
///     pub enum Shade: "shading", MyError {
///         /// One colour per face.
///         #[default]
///         Flat = "flat",
///         /// Interpolated normals.
///         Smooth = "smooth" | "gouraud",
///     }
/// }
/// assert_eq!("gouraud".parse::<Shade>().unwrap(), Shade::Smooth);
/// assert_eq!(Shade::default().to_string(), "flat");
/// ```
///
/// The first form:
///
/// ```
/// #[derive(Debug, Clone, Copy, PartialEq)]
/// enum Shade { Flat, Smooth }
/// #[derive(Debug)]
/// pub struct MyError(meshcore::UnknownChoice);
/// impl From<meshcore::UnknownChoice> for MyError {
///     fn from(e: meshcore::UnknownChoice) -> Self { MyError(e) }
/// }
/// meshcore::choice!(Shade, "shading", MyError {
///     Flat = "flat",
///     Smooth = "smooth" | "gouraud",
/// });
/// assert_eq!("gouraud".parse::<Shade>().unwrap(), Shade::Smooth);
/// assert_eq!(Shade::Flat.to_string(), "flat");
/// assert!("phong".parse::<Shade>().is_err());
/// ```
#[macro_export]
macro_rules! choice {
    ($ty:ident, $what:literal, $err:ty { $($variant:ident = $name:literal $(| $alias:literal)*),+ $(,)? }) => {
        impl $crate::Choice for $ty {
            const WHAT: &'static str = $what;
            const ALL: &'static [Self] = &[$($ty::$variant),+];
            fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name),+
                }
            }
            fn aliases(self) -> &'static [&'static str] {
                match self {
                    $($ty::$variant => &[$($alias),*]),+
                }
            }
        }
        impl ::std::str::FromStr for $ty {
            type Err = $err;
            fn from_str(s: &str) -> ::std::result::Result<Self, Self::Err> {
                <$ty as $crate::Choice>::from_name(s).map_err(<$err>::from)
            }
        }
        impl ::std::fmt::Display for $ty {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str($crate::Choice::name(*self))
            }
        }
    };
    (
        $(#[$meta:meta])*
        $vis:vis enum $ty:ident : $what:literal, $err:ty {
            $($(#[$vmeta:meta])* $variant:ident = $name:literal $(| $alias:literal)*),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        $vis enum $ty {
            $($(#[$vmeta])* $variant),+
        }
        $crate::choice!($ty, $what, $err { $($variant = $name $(| $alias)*),+ });
    };
}

/// Checks that every value of `T` round-trips through its name and aliases, that names are
/// unique, and that `bad` is rejected with an [`UnknownChoice`] listing every name. For the
/// tests of the crates that declare choices; returns a description of the first failure.
pub fn check_choice<T>(bad: &str) -> Result<(), String>
where
    T: Choice + PartialEq + fmt::Debug + std::str::FromStr + fmt::Display,
    T::Err: fmt::Display,
{
    let names = T::names();
    for (i, n) in names.iter().enumerate() {
        if names[..i].iter().any(|m| m.eq_ignore_ascii_case(n)) {
            return Err(format!("{}: name {n:?} appears twice", T::WHAT));
        }
    }
    for &v in T::ALL {
        let shown = v.to_string();
        if shown != v.name() {
            return Err(format!("{v:?} displays as {shown:?}, not {:?}", v.name()));
        }
        for s in std::iter::once(v.name()).chain(v.aliases().iter().copied()) {
            match s.parse::<T>() {
                Ok(back) if back == v => {}
                Ok(back) => return Err(format!("{s:?} parses to {back:?}, not {v:?}")),
                Err(e) => return Err(format!("{s:?} does not parse: {e}")),
            }
        }
    }
    let e = match T::from_name(bad) {
        Ok(v) => return Err(format!("{bad:?} parses to {v:?}")),
        Err(e) => e,
    };
    if e.expected != names || e.got != bad || e.what != T::WHAT {
        return Err(format!("wrong UnknownChoice for {bad:?}: {e:?}"));
    }
    let msg = match bad.parse::<T>() {
        Ok(v) => return Err(format!("{bad:?} parses to {v:?}")),
        Err(e) => e.to_string(),
    };
    if let Some(n) = names.iter().find(|n| !msg.contains(*n)) {
        return Err(format!("the error for {bad:?} does not list {n:?}: {msg}"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::Diagonals;

    #[test]
    fn diagonals_round_trip_and_reject() {
        check_choice::<Diagonals>("zigzag").unwrap();
        let e = "zigzag".parse::<Diagonals>().unwrap_err().to_string();
        assert!(e.contains("zigzag") && e.contains("expected one of"), "{e}");
    }
}
