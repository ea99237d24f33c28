//! The point set of the single-pole descriptor (`polar`): keys `(level, sector)` packed in a
//! `u64` and their positions, in the form `shapedist::keyed_distance` takes them.

use meshcore::DVec3;

/// Points with keys (sorted by key), and which keys are ambiguous.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KeyedPoints {
    /// Packed keys, ascending.
    pub keys: Vec<u64>,
    /// Positions.
    pub points: Vec<DVec3>,
    /// True where a key occurs at several distinct places (such keys are not paired).
    pub ambiguous: Vec<bool>,
}

impl KeyedPoints {
    /// Builds a keyed set from unsorted `(key, point)` pairs: duplicates of a key closer than
    /// `tol` are merged, farther ones make the key ambiguous.
    pub fn from_pairs(mut pairs: Vec<(u64, DVec3)>, tol: f64) -> Self {
        pairs.sort_by(|a, b| {
            a.0.cmp(&b.0)
                .then(a.1.x.total_cmp(&b.1.x))
                .then(a.1.y.total_cmp(&b.1.y))
                .then(a.1.z.total_cmp(&b.1.z))
        });
        let mut out = KeyedPoints::default();
        let mut i = 0;
        while i < pairs.len() {
            let mut j = i + 1;
            while j < pairs.len() && pairs[j].0 == pairs[i].0 {
                j += 1;
            }
            let first = pairs[i].1;
            let ambiguous = pairs[i..j].iter().any(|p| (p.1 - first).length() > tol);
            out.keys.push(pairs[i].0);
            out.points.push(first);
            out.ambiguous.push(ambiguous);
            i = j;
        }
        out
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.keys.len()
    }

    /// Unambiguous keys and points (for distances).
    pub fn unambiguous(&self) -> (Vec<u64>, Vec<DVec3>) {
        (0..self.len())
            .filter(|&i| !self.ambiguous[i])
            .map(|i| (self.keys[i], self.points[i]))
            .unzip()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn duplicates_merge_within_the_tolerance_and_are_ambiguous_beyond() {
        let p = DVec3::new(1.0, 2.0, 3.0);
        let k = KeyedPoints::from_pairs(
            vec![
                (7, p),
                (3, DVec3::ZERO),
                (7, p + DVec3::splat(1e-12)),
                (5, DVec3::X),
                (5, DVec3::Y),
            ],
            1e-9,
        );
        assert_eq!(k.keys, vec![3, 5, 7]);
        assert_eq!(k.ambiguous, vec![false, true, false]);
        let (keys, pts) = k.unambiguous();
        assert_eq!(keys, vec![3, 7]);
        assert_eq!(pts, vec![DVec3::ZERO, p]);
    }
}
