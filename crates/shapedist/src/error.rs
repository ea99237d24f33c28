use thiserror::Error;

/// Which of the two inputs of a comparison a problem refers to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Which {
    /// The first set (`A`, the target, kept fixed).
    A,
    /// The second set (`B`, the source, rotated onto `A`).
    B,
}

impl std::fmt::Display for Which {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Which::A => "A",
            Which::B => "B",
        })
    }
}

/// Everything that can go wrong when comparing two point sets.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ShapeDistError {
    /// A point set has no points.
    #[error("point set {0} is empty")]
    Empty(Which),
    /// A coordinate is NaN or infinite.
    #[error("point set {which}: point {index} has a non-finite coordinate")]
    NonFinite {
        /// The offending set.
        which: Which,
        /// Index of the point in that set.
        index: usize,
    },
    /// Keys and points of a keyed set have different lengths.
    #[error("point set {which}: {keys} keys but {points} points")]
    LengthMismatch {
        /// The offending set.
        which: Which,
        /// Number of keys.
        keys: usize,
        /// Number of points.
        points: usize,
    },
    /// Fewer usable correspondences than the rotation needs.
    #[error("only {found} usable shared keys (at least {needed} needed; {detail})")]
    TooFewPairs {
        /// Pairs available.
        found: usize,
        /// Pairs required.
        needed: usize,
        /// Why pairs were lost (ambiguous keys, residual gate, ...).
        detail: String,
    },
    /// The points are (numerically) collinear or coincident, so the rotation is undefined.
    #[error("point set {which} is degenerate ({detail}): the rotation is undefined")]
    Degenerate {
        /// The offending set.
        which: Which,
        /// What is degenerate.
        detail: String,
    },
    /// Two matrices of different sizes, or a matrix input with fewer than one set.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// An option name that is none of the valid names (they are listed).
    #[error(transparent)]
    UnknownChoice(#[from] meshcore::UnknownChoice),
    /// A mesh target of ICP failed to answer a query (for example a non-finite moved point).
    #[error("ICP target: {0}")]
    Mesh(#[from] meshcore::MeshError),
}
