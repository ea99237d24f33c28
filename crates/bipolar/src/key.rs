//! Keys of descriptor points (specification §2.6).

use serde::{Deserialize, Serialize};

/// The key of a descriptor point: which reference pair, which levels, which side.
///
/// * `a`, `b`: indices of the reference pair (`a < b`) in the list of reference points;
/// * `i`: level of the field of reference `a` (`U_a = i * step`);
/// * `j`: level of the field of reference `b` for [`crate::SelectionRule::Filter`] and
///   [`crate::SelectionRule::All`], or the angle level `k` (`|cos| = alpha * k / K`) for
///   [`crate::SelectionRule::IsoAngle`];
/// * `side`: sign of `<n, grad U_a x grad U_b>` (which side of the a-b geodesic), `+1` or `-1`;
/// * `sign`: sign of `cos` for the iso-angle rule (`0` for `k = 0`), `0` for the other rules.
///
/// Keys order lexicographically in field order; [`Key::pack`] preserves that order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Key {
    /// Index of the first reference point of the pair.
    pub a: u8,
    /// Index of the second reference point of the pair.
    pub b: u8,
    /// Level of the first field.
    pub i: u32,
    /// Level of the second field (filter rule) or angle level (iso-angle rule).
    pub j: u32,
    /// Side of the reference geodesic: `+1` or `-1`.
    pub side: i8,
    /// Sign of the cosine (iso-angle rule), `0` otherwise.
    pub sign: i8,
}

impl Key {
    /// Largest level index that [`Key::pack`] stores without loss (22 bits).
    pub const MAX_LEVEL: u32 = (1 << 22) - 1;

    /// Packs the key into a `u64`: `a` (8 bits), `b` (8), `i` (22), `j` (22), `side` (2),
    /// `sign` (2), most significant first.
    ///
    /// Injective (and order preserving) for keys with `i, j <= Key::MAX_LEVEL` and `side`,
    /// `sign` in `{-1, 0, 1}`, which is every key the descriptor produces (it refuses more
    /// levels). Values outside are masked / clamped by sign.
    pub fn pack(&self) -> u64 {
        fn enc(s: i8) -> u64 {
            (s.signum() + 1) as u64
        }
        ((self.a as u64) << 56)
            | ((self.b as u64) << 48)
            | (((self.i & Self::MAX_LEVEL) as u64) << 26)
            | (((self.j & Self::MAX_LEVEL) as u64) << 4)
            | (enc(self.side) << 2)
            | enc(self.sign)
    }

    /// Inverse of [`Key::pack`].
    pub fn unpack(p: u64) -> Key {
        let dec = |v: u64| (v & 3) as i8 - 1;
        Key {
            a: (p >> 56) as u8,
            b: (p >> 48) as u8,
            i: ((p >> 26) as u32) & Self::MAX_LEVEL,
            j: ((p >> 4) as u32) & Self::MAX_LEVEL,
            side: dec(p >> 2),
            sign: dec(p),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn key() -> impl Strategy<Value = Key> {
        (
            any::<u8>(),
            any::<u8>(),
            0..=Key::MAX_LEVEL,
            0..=Key::MAX_LEVEL,
            -1i8..=1,
            -1i8..=1,
        )
            .prop_map(|(a, b, i, j, side, sign)| Key {
                a,
                b,
                i,
                j,
                side,
                sign,
            })
    }

    proptest! {
        #[test]
        fn pack_roundtrips_and_preserves_order(k1 in key(), k2 in key()) {
            prop_assert_eq!(Key::unpack(k1.pack()), k1);
            prop_assert_eq!(k1.pack().cmp(&k2.pack()), k1.cmp(&k2));
            prop_assert_eq!(k1.pack() == k2.pack(), k1 == k2);
        }
    }

    #[test]
    fn extreme_keys_differ() {
        let k = Key {
            a: 255,
            b: 255,
            i: Key::MAX_LEVEL,
            j: Key::MAX_LEVEL,
            side: 1,
            sign: 1,
        };
        let mut k2 = k;
        k2.sign = -1;
        assert_ne!(k.pack(), k2.pack());
        assert_eq!(Key::unpack(k.pack()), k);
    }
}
