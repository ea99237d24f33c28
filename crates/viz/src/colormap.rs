//! Colour maps for scalar fields.

/// Grey used for missing (non-finite) values.
pub const MISSING: [u8; 3] = [150, 150, 150];

/// matplotlib's viridis sampled at t = 0, 0.1, …, 1 (linear interpolation in between).
const VIRIDIS: [[u8; 3]; 11] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x24, 0x75],
    [0x41, 0x44, 0x87],
    [0x35, 0x5f, 0x8d],
    [0x2a, 0x78, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x22, 0xa8, 0x84],
    [0x44, 0xbf, 0x70],
    [0x7a, 0xd1, 0x51],
    [0xbd, 0xdf, 0x26],
    [0xfd, 0xe7, 0x25],
];

/// Viridis colour for `t` in `[0, 1]` (clamped; NaN gives [`MISSING`]).
pub fn viridis(t: f64) -> [u8; 3] {
    if t.is_nan() {
        return MISSING;
    }
    let x = t.clamp(0.0, 1.0) * 10.0;
    let i = (x.floor() as usize).min(9);
    let f = x - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mut out = [0u8; 3];
    for k in 0..3 {
        out[k] = (a[k] as f64 + f * (b[k] as f64 - a[k] as f64)).round() as u8;
    }
    out
}

/// Range `(min, max)` of the finite values, or `None` when there is none.
pub fn finite_range(values: &[f64]) -> Option<(f64, f64)> {
    let mut r: Option<(f64, f64)> = None;
    for &v in values.iter().filter(|v| v.is_finite()) {
        r = Some(match r {
            None => (v, v),
            Some((lo, hi)) => (lo.min(v), hi.max(v)),
        });
    }
    r
}

/// Per-value viridis colours, normalised by the range of the finite values; non-finite values
/// are grey ([`MISSING`]); a constant field maps to the middle of the map.
pub fn field_colors(values: &[f64]) -> Vec<[u8; 3]> {
    let Some((lo, hi)) = finite_range(values) else {
        return vec![MISSING; values.len()];
    };
    let span = hi - lo;
    values
        .iter()
        .map(|&v| {
            if !v.is_finite() {
                MISSING
            } else if span > 0.0 {
                viridis((v - lo) / span)
            } else {
                viridis(0.5)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_endpoints_and_monotone_luminance() {
        assert_eq!(viridis(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(viridis(1.0), [0xfd, 0xe7, 0x25]);
        assert_eq!(viridis(-3.0), viridis(0.0));
        assert_eq!(viridis(7.0), viridis(1.0));
        assert_eq!(viridis(f64::NAN), MISSING);
        let lum = |c: [u8; 3]| 0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64;
        let mut prev = -1.0;
        for i in 0..=100 {
            let l = lum(viridis(i as f64 / 100.0));
            assert!(l >= prev - 0.5, "luminance drops at {i}");
            prev = l;
        }
    }

    #[test]
    fn field_colors_normalise_and_mark_missing() {
        let c = field_colors(&[2.0, f64::NAN, 4.0, 3.0, f64::INFINITY]);
        assert_eq!(c[0], viridis(0.0));
        assert_eq!(c[1], MISSING);
        assert_eq!(c[2], viridis(1.0));
        assert_eq!(c[3], viridis(0.5));
        assert_eq!(c[4], MISSING);
        assert_eq!(field_colors(&[5.0, 5.0]), vec![viridis(0.5); 2]);
        assert_eq!(field_colors(&[f64::NAN]), vec![MISSING]);
        assert!(field_colors(&[]).is_empty());
    }
}
