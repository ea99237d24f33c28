//! The part of a bipolar descriptor a comparison reads: its unambiguous keyed points.

use meshcore::DVec3;
use shapedist::{KeyedOptions, ShapeDistError};

/// The unambiguous points of a bipolar descriptor with their packed keys
/// ([`bipolar::Descriptor::keyed_points`]): all the keyed distance uses, and what a template
/// stores.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct KeyedSet {
    /// Packed keys ([`bipolar::Key::pack`]), one per point.
    pub keys: Vec<u64>,
    /// Positions (mm, the face's frame).
    pub points: Vec<DVec3>,
}

impl KeyedSet {
    /// The unambiguous points of `d`.
    pub fn of(d: &bipolar::Descriptor) -> Self {
        let (keys, points) = d.keyed_points(false);
        Self { keys, points }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.keys.len()
    }

    /// Whether there is no point.
    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    /// The normalised keyed distance to `other` ([`shapedist::keyed_distance`]: the closed-form
    /// rigid alignment of the points sharing a key), pairs with a residual above `gate` dropped
    /// and the fit repeated (`None`: every pair). Fewer than 3 shared keys is
    /// [`ShapeDistError::TooFewPairs`].
    pub fn distance(&self, other: &KeyedSet, gate: Option<f64>) -> Result<f64, ShapeDistError> {
        shapedist::keyed_distance(
            &self.keys,
            &self.points,
            &other.keys,
            &other.points,
            &KeyedOptions {
                gate,
                ..KeyedOptions::default()
            },
        )
        .map(|k| k.distance)
    }
}
