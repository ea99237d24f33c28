//! Separation figures and finite-value reductions of distance matrices and rows.

use crate::report::f4;
use facemodel::Face;

/// Separation figures of a distance matrix.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sep {
    pub max_same: f64,
    pub min_diff: f64,
    pub row_max_same: f64,
    pub row_min_diff: f64,
}

impl Sep {
    pub(crate) fn of(m: &[Vec<f64>], faces: &[Face], test: usize) -> Self {
        let mut s = Sep {
            max_same: 0.0,
            min_diff: f64::INFINITY,
            row_max_same: 0.0,
            row_min_diff: f64::INFINITY,
        };
        for i in 0..faces.len() {
            for j in i + 1..faces.len() {
                let v = m[i][j];
                if faces[i].person == faces[j].person {
                    s.max_same = s.max_same.max(v);
                    if i == test || j == test {
                        s.row_max_same = s.row_max_same.max(v);
                    }
                } else {
                    s.min_diff = s.min_diff.min(v);
                    if i == test || j == test {
                        s.row_min_diff = s.row_min_diff.min(v);
                    }
                }
            }
        }
        s
    }
    pub(crate) fn ratio(&self) -> f64 {
        self.min_diff / self.max_same
    }
    pub(crate) fn row_ratio(&self) -> f64 {
        self.row_min_diff / self.row_max_same
    }
    pub(crate) fn verdict(&self) -> &'static str {
        if self.ratio() > 1.0 {
            "separated"
        } else {
            "NOT separated"
        }
    }
    pub(crate) fn row_verdict(&self) -> &'static str {
        if self.row_ratio() > 1.0 {
            "separated"
        } else {
            "NOT separated"
        }
    }
}

/// A column of the separation tables: its header and its cell for a [`Sep`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum SepColumn {
    MaxSame,
    MinDiff,
    Ratio,
    Verdict,
    RowMaxSame,
    RowMinDiff,
    RowRatio,
    RowVerdict,
}

impl SepColumn {
    /// Every column, in table order.
    pub(super) const ALL: [SepColumn; 8] = [
        SepColumn::MaxSame,
        SepColumn::MinDiff,
        SepColumn::Ratio,
        SepColumn::Verdict,
        SepColumn::RowMaxSame,
        SepColumn::RowMinDiff,
        SepColumn::RowRatio,
        SepColumn::RowVerdict,
    ];

    /// The column header.
    pub(super) fn header(self) -> &'static str {
        match self {
            SepColumn::MaxSame => "max same",
            SepColumn::MinDiff => "min different",
            SepColumn::Ratio => "ratio",
            SepColumn::Verdict => "whole matrix",
            SepColumn::RowMaxSame => "test row: max same",
            SepColumn::RowMinDiff => "test row: min different",
            SepColumn::RowRatio => "test-row ratio",
            SepColumn::RowVerdict => "test row",
        }
    }

    /// The cell of `s` (distances with 4 decimals, ratios with 3).
    pub(super) fn cell(self, s: &Sep) -> String {
        match self {
            SepColumn::MaxSame => f4(s.max_same),
            SepColumn::MinDiff => f4(s.min_diff),
            SepColumn::Ratio => format!("{:.3}", s.ratio()),
            SepColumn::Verdict => s.verdict().into(),
            SepColumn::RowMaxSame => f4(s.row_max_same),
            SepColumn::RowMinDiff => f4(s.row_min_diff),
            SepColumn::RowRatio => format!("{:.3}", s.row_ratio()),
            SepColumn::RowVerdict => s.row_verdict().into(),
        }
    }
}

/// The finite values of `v`, in order.
pub(crate) fn finite(v: &[f64]) -> Vec<f64> {
    v.iter().copied().filter(|x| x.is_finite()).collect()
}
/// Mean of the finite values (NaN if none).
pub(crate) fn mean(v: &[f64]) -> f64 {
    let f = finite(v);
    if f.is_empty() {
        f64::NAN
    } else {
        f.iter().sum::<f64>() / f.len() as f64
    }
}
/// Max of the finite values (NaN if none).
pub(crate) fn max(v: &[f64]) -> f64 {
    finite(v).into_iter().reduce(f64::max).unwrap_or(f64::NAN)
}
/// Min of the finite values (NaN if none).
pub(crate) fn min(v: &[f64]) -> f64 {
    finite(v).into_iter().reduce(f64::min).unwrap_or(f64::NAN)
}

pub(crate) fn matrix_rows(faces: &[Face], m: &[Vec<f64>]) -> Vec<Vec<String>> {
    faces
        .iter()
        .zip(m)
        .map(|(f, row)| {
            std::iter::once(f.name.clone())
                .chain(row.iter().map(|v| format!("{v:.6}")))
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separation_figures() {
        let mk = |name: &str| Face {
            name: name.into(),
            person: name.split('_').next().unwrap().into(),
            expression: String::new(),
            mesh: crate::walk::tests::plane(1, 0.0, 0),
            landmarks: facemodel::FaceLandmarks::ground_truth(),
        };
        let faces = vec![mk("a_n"), mk("a_x"), mk("b_n"), mk("c_n")];
        let m = vec![
            vec![0.0, 0.1, 0.3, 0.2],
            vec![0.1, 0.0, 0.05, 0.4],
            vec![0.3, 0.05, 0.0, 0.5],
            vec![0.2, 0.4, 0.5, 0.0],
        ];
        let s = Sep::of(&m, &faces, 0);
        assert_eq!((s.max_same, s.min_diff), (0.1, 0.05));
        assert_eq!((s.row_max_same, s.row_min_diff), (0.1, 0.2));
        assert!((s.row_ratio() - 2.0).abs() < 1e-12 && s.verdict() == "NOT separated");
    }
}
