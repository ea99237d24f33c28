//! Minimal `.npy` reader: float32/float64, C order, little endian.

use crate::IoError;
use std::path::Path;

/// Reads an `.npy` array of `<f4` or `<f8` values in C order; returns the shape and the values
/// as `f32` (float64 data is rounded).
pub fn read_npy_f32(path: impl AsRef<Path>) -> Result<(Vec<usize>, Vec<f32>), IoError> {
    crate::read_parsed(path.as_ref(), parse_npy_f32)
}

fn dict_value<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let k = header.find(&format!("'{key}'"))?;
    let rest = &header[k + key.len() + 2..];
    let colon = rest.find(':')?;
    Some(rest[colon + 1..].trim_start())
}

/// Parses the bytes of an `.npy` file (see [`read_npy_f32`]).
pub fn parse_npy_f32(bytes: &[u8], file: &str) -> Result<(Vec<usize>, Vec<f32>), IoError> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(IoError::byte(
            file,
            0,
            "not an .npy file (magic \\x93NUMPY missing)",
        ));
    }
    let major = bytes[6];
    let (hlen, hstart) = match major {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 => {
            if bytes.len() < 12 {
                return Err(IoError::byte(file, 8, "truncated header"));
            }
            (
                u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
                12,
            )
        }
        v => {
            return Err(IoError::byte(
                file,
                6,
                format!("unsupported .npy version {v}"),
            ))
        }
    };
    if bytes.len() - hstart < hlen {
        return Err(IoError::byte(
            file,
            hstart,
            format!("header of {hlen} bytes runs past the end of the file"),
        ));
    }
    let header = std::str::from_utf8(&bytes[hstart..hstart + hlen])
        .map_err(|_| IoError::byte(file, hstart, "header is not text"))?;
    let descr = dict_value(header, "descr")
        .ok_or_else(|| IoError::byte(file, hstart, "header has no 'descr'"))?;
    let size = if descr.starts_with("'<f4'") {
        4
    } else if descr.starts_with("'<f8'") {
        8
    } else {
        return Err(IoError::Unsupported {
            file: file.into(),
            at: crate::Location::Byte(hstart),
            problem: format!(
                "dtype {} (only '<f4' and '<f8')",
                descr.split(',').next().unwrap_or("")
            ),
        });
    };
    let fo = dict_value(header, "fortran_order")
        .ok_or_else(|| IoError::byte(file, hstart, "header has no 'fortran_order'"))?;
    if !fo.starts_with("False") {
        return Err(IoError::Unsupported {
            file: file.into(),
            at: crate::Location::Byte(hstart),
            problem: "Fortran-order array".into(),
        });
    }
    let sh = dict_value(header, "shape")
        .ok_or_else(|| IoError::byte(file, hstart, "header has no 'shape'"))?;
    let inner = sh
        .strip_prefix('(')
        .and_then(|s| s.split(')').next())
        .ok_or_else(|| IoError::byte(file, hstart, format!("bad shape {sh:?}")))?;
    let mut shape = Vec::new();
    for t in inner.split(',').map(str::trim).filter(|t| !t.is_empty()) {
        shape.push(
            t.parse::<usize>()
                .map_err(|_| IoError::byte(file, hstart, format!("bad shape entry {t:?}")))?,
        );
    }
    let data = &bytes[hstart + hlen..];
    let count = shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    match count.and_then(|c| c.checked_mul(size)) {
        Some(nb) if nb == data.len() => {}
        _ => {
            return Err(IoError::byte(
                file,
                hstart + hlen,
                format!(
                    "shape {shape:?} of {size}-byte values does not match the {} data bytes",
                    data.len()
                ),
            ))
        }
    }
    let values = if size == 4 {
        data.chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    } else {
        data.chunks_exact(8)
            .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]) as f32)
            .collect()
    };
    Ok((shape, values))
}
