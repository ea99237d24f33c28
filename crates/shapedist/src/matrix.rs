//! Pairwise distance matrices (parallel, symmetric, zero diagonal), their CSV form, and how
//! a matrix separates groups ([`Separation`]).

use std::io::Write;

use rayon::prelude::*;

/// A pair whose distance could not be computed.
#[derive(Debug, Clone, PartialEq)]
pub struct PairError<E> {
    /// Row index.
    pub i: usize,
    /// Column index.
    pub j: usize,
    /// The underlying error.
    pub error: E,
}

impl<E: std::fmt::Display> std::fmt::Display for PairError<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "pair ({}, {}): {}", self.i, self.j, self.error)
    }
}

impl<E: std::fmt::Debug + std::fmt::Display> std::error::Error for PairError<E> {}

/// Computes `f(items[i], items[j])` for every `i < j` in parallel and returns the full
/// symmetric matrix with a zero diagonal. The first failing pair (in row-major order) is
/// reported.
pub fn pairwise_matrix<T, E, F>(items: &[T], f: F) -> Result<Vec<Vec<f64>>, PairError<E>>
where
    T: Sync,
    E: Send,
    F: Fn(&T, &T) -> Result<f64, E> + Sync,
{
    let n = items.len();
    let pairs: Vec<(usize, usize)> = (0..n)
        .flat_map(|i| ((i + 1)..n).map(move |j| (i, j)))
        .collect();
    let vals: Vec<Result<f64, PairError<E>>> = pairs
        .par_iter()
        .map(|&(i, j)| f(&items[i], &items[j]).map_err(|error| PairError { i, j, error }))
        .collect();
    let mut m = vec![vec![0.0; n]; n];
    for (&(i, j), v) in pairs.iter().zip(vals) {
        let v = v?;
        m[i][j] = v;
        m[j][i] = v;
    }
    Ok(m)
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Writes a labelled square matrix as CSV: a header `label,<labels...>`, then one row per
/// label. Values are written with full precision (shortest round-trip form).
pub fn write_matrix_csv<W: Write>(
    mut w: W,
    labels: &[String],
    matrix: &[Vec<f64>],
) -> std::io::Result<()> {
    write!(w, "label")?;
    for l in labels {
        write!(w, ",{}", csv_field(l))?;
    }
    writeln!(w)?;
    for (l, row) in labels.iter().zip(matrix) {
        write!(w, "{}", csv_field(l))?;
        for v in row {
            write!(w, ",{v}")?;
        }
        writeln!(w)?;
    }
    Ok(())
}

/// How a symmetric distance matrix separates groups (e.g. the faces of one person): the
/// largest distance within a group, the smallest between groups, and the same restricted to
/// the pairs of one `focus` item. NaN distances are ignored; an empty set leaves its
/// value at `0` (largest) or `+inf` (smallest).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Separation {
    /// Largest distance between two items of one group.
    pub max_same: f64,
    /// Smallest distance between items of different groups.
    pub min_diff: f64,
    /// Largest distance between the focus item and another of its group.
    pub row_max_same: f64,
    /// Smallest distance between the focus item and an item of another group.
    pub row_min_diff: f64,
}

impl Separation {
    /// The separation of the square matrix `m` by `groups` (one per row; items beyond the
    /// shorter of the two are ignored), with the pairs of item `focus` also on their own.
    pub fn of<G: PartialEq>(m: &[Vec<f64>], groups: &[G], focus: usize) -> Self {
        let mut s = Separation {
            max_same: 0.0,
            min_diff: f64::INFINITY,
            row_max_same: 0.0,
            row_min_diff: f64::INFINITY,
        };
        let n = groups.len().min(m.len());
        for i in 0..n {
            for j in i + 1..n.min(m[i].len()) {
                let (v, row) = (m[i][j], i == focus || j == focus);
                if groups[i] == groups[j] {
                    s.max_same = s.max_same.max(v);
                    if row {
                        s.row_max_same = s.row_max_same.max(v);
                    }
                } else {
                    s.min_diff = s.min_diff.min(v);
                    if row {
                        s.row_min_diff = s.row_min_diff.min(v);
                    }
                }
            }
        }
        s
    }

    /// `min_diff / max_same`: above 1 when every pair within a group is closer than every
    /// pair across groups.
    pub fn ratio(&self) -> f64 {
        self.min_diff / self.max_same
    }

    /// `row_min_diff / row_max_same`: [`Separation::ratio`] of the focus item's pairs.
    pub fn row_ratio(&self) -> f64 {
        self.row_min_diff / self.row_max_same
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separation_of_groups_and_of_the_focus_row() {
        let groups = ["a", "a", "b", "c"];
        let m = vec![
            vec![0.0, 0.1, 0.3, 0.2],
            vec![0.1, 0.0, 0.05, 0.4],
            vec![0.3, 0.05, 0.0, 0.5],
            vec![0.2, 0.4, 0.5, 0.0],
        ];
        let s = Separation::of(&m, &groups, 0);
        assert_eq!((s.max_same, s.min_diff), (0.1, 0.05));
        assert_eq!((s.row_max_same, s.row_min_diff), (0.1, 0.2));
        assert!((s.row_ratio() - 2.0).abs() < 1e-12 && s.ratio() < 1.0);
        // NaN cells are ignored.
        let mut m2 = m.clone();
        (m2[1][2], m2[2][1]) = (f64::NAN, f64::NAN);
        assert_eq!(Separation::of(&m2, &groups, 0).min_diff, 0.2);
    }

    #[test]
    fn matrix_is_symmetric_with_zero_diagonal_and_reports_failures() {
        let xs = [1.0f64, 4.0, 9.0, 2.5];
        let m = pairwise_matrix(&xs, |a, b| Ok::<f64, ()>((a - b).abs())).unwrap();
        for i in 0..4 {
            assert_eq!(m[i][i], 0.0);
            for j in 0..4 {
                assert_eq!(m[i][j], m[j][i]);
                if i != j {
                    assert_eq!(m[i][j], (xs[i] - xs[j]).abs());
                }
            }
        }
        let e = pairwise_matrix(&xs, |a, b| {
            if *a == 9.0 || *b == 9.0 {
                Err("nine")
            } else {
                Ok(0.0)
            }
        })
        .unwrap_err();
        assert_eq!((e.i, e.j, e.error), (0, 2, "nine"));
    }

    #[test]
    fn csv_round_trips_values_and_quotes_labels() {
        let labels = vec!["a".to_string(), "b,c".to_string()];
        let m = vec![vec![0.0, 0.1 + 0.2], vec![0.1 + 0.2, 0.0]];
        let mut out = Vec::new();
        write_matrix_csv(&mut out, &labels, &m).unwrap();
        let s = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = s.lines().collect();
        assert_eq!(lines[0], "label,a,\"b,c\"");
        let v: f64 = lines[1].split(',').nth(2).unwrap().parse().unwrap();
        assert_eq!(v, 0.1 + 0.2);
    }
}
