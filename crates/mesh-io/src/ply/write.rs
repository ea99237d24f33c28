//! The PLY writer (ASCII or binary, optional colours and scalar properties).

use super::{PlyEncoding, PlyWriteOptions};
use crate::text::{push_f64, push_xyz};
use crate::{IoError, ScalarType};
use meshcore::TriMesh;

/// Serialises a PLY file.
pub(crate) fn write_ply(
    mesh: &TriMesh,
    o: &PlyWriteOptions<'_>,
    file: &str,
) -> Result<Vec<u8>, IoError> {
    let n = mesh.n_vertices();
    crate::check_extras(file, n, o.colors, o.scalars)?;
    for s in o.scalars {
        if s.name.is_empty()
            || s.name.chars().any(|c| c.is_whitespace())
            || ["x", "y", "z", "red", "green", "blue", "alpha"].contains(&s.name.as_str())
        {
            return Err(IoError::invalid(
                file,
                format!("invalid or reserved PLY property name {:?}", s.name),
            ));
        }
    }
    let fmt = match o.encoding {
        PlyEncoding::Ascii => "ascii",
        PlyEncoding::BinaryLittleEndian => "binary_little_endian",
        PlyEncoding::BinaryBigEndian => "binary_big_endian",
    };
    let mut h = format!("ply\nformat {fmt} 1.0\ncomment written by bipolar mesh-io\nelement vertex {n}\nproperty double x\nproperty double y\nproperty double z\n");
    if o.colors.is_some() {
        h.push_str(
            "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n",
        );
    }
    for s in o.scalars {
        let t = if s.ty == ScalarType::F32 {
            "float"
        } else {
            "double"
        };
        h.push_str(&format!("property {t} {}\n", s.name));
    }
    h.push_str(&format!(
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.n_faces()
    ));
    let mut out = h.into_bytes();
    match o.encoding {
        PlyEncoding::Ascii => {
            let mut s = String::with_capacity(n * 60 + mesh.n_faces() * 20);
            for (i, p) in mesh.positions().iter().enumerate() {
                push_xyz(&mut s, *p);
                if let Some(c) = o.colors {
                    s.push_str(&format!(" {} {} {} {}", c[i][0], c[i][1], c[i][2], c[i][3]));
                }
                for f in o.scalars {
                    s.push(' ');
                    match f.ty {
                        ScalarType::F32 => s.push_str(&format!("{:?}", f.values[i] as f32)),
                        ScalarType::F64 => push_f64(&mut s, f.values[i]),
                    }
                }
                s.push('\n');
            }
            for t in mesh.triangles() {
                s.push_str(&format!("3 {} {} {}\n", t[0], t[1], t[2]));
            }
            out.extend_from_slice(s.as_bytes());
        }
        PlyEncoding::BinaryLittleEndian | PlyEncoding::BinaryBigEndian => {
            let be = o.encoding == PlyEncoding::BinaryBigEndian;
            let rec = 24
                + if o.colors.is_some() { 4 } else { 0 }
                + o.scalars
                    .iter()
                    .map(|s| if s.ty == ScalarType::F32 { 4 } else { 8 })
                    .sum::<usize>();
            out.reserve(n * rec + mesh.n_faces() * 13);
            macro_rules! put {
                ($v:expr) => {
                    if be {
                        out.extend_from_slice(&$v.to_be_bytes())
                    } else {
                        out.extend_from_slice(&$v.to_le_bytes())
                    }
                };
            }
            for (i, p) in mesh.positions().iter().enumerate() {
                put!(p.x);
                put!(p.y);
                put!(p.z);
                if let Some(c) = o.colors {
                    out.extend_from_slice(&c[i]);
                }
                for f in o.scalars {
                    match f.ty {
                        ScalarType::F32 => put!(f.values[i] as f32),
                        ScalarType::F64 => put!(f.values[i]),
                    }
                }
            }
            for t in mesh.triangles() {
                out.push(3);
                for &v in t {
                    put!(v as i32);
                }
            }
        }
    }
    Ok(out)
}
