//! What the ASCII and binary bodies share: where parsed values go, the roles of the vertex
//! properties, and the checks of colours, indices and faces.

use super::header::{Element, Prop, Ty};
use crate::{IoError, ScalarField, ScalarType};
use meshcore::DVec3;

/// Where the parsed values go.
pub(super) struct Sink {
    pub(super) pos: Vec<DVec3>,
    pub(super) colors: Vec<[u8; 4]>,
    pub(super) scalars: Vec<(usize, ScalarField)>,
    pub(super) tris: Vec<[u32; 3]>,
    pub(super) tri_at: Vec<usize>,
    pub(super) n_polygons: usize,
    /// Triangle strips decoded and the degenerate strip triangles (repeated vertex) skipped.
    pub(super) n_strips: usize,
    pub(super) n_strip_degenerate: usize,
}

/// Roles of the properties of the vertex element.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Role {
    X,
    Y,
    Z,
    Color(usize, bool),
    Scalar(usize),
    Ignore,
}

impl Role {
    /// Puts the value `v` of a vertex property with this role where it belongs: the position
    /// `p`, the colour `c` or its scalar field in `sink`.
    #[inline]
    pub(super) fn store(self, v: f64, p: &mut DVec3, c: &mut [u8; 4], sink: &mut Sink) {
        match self {
            Role::X => p.x = v,
            Role::Y => p.y = v,
            Role::Z => p.z = v,
            Role::Color(k, f) => c[k] = color_value(v, f),
            Role::Scalar(k) => sink.scalars[k].1.values.push(v),
            Role::Ignore => {}
        }
    }
}

pub(super) fn vertex_roles(
    el: &Element,
    file: &str,
) -> Result<(Vec<Role>, Vec<ScalarField>, bool), IoError> {
    let mut roles = Vec::new();
    let mut scalars = Vec::new();
    let mut has_color = false;
    for p in &el.props {
        let role = match p {
            Prop::Scalar(ty, name) => match name.as_str() {
                "x" => Role::X,
                "y" => Role::Y,
                "z" => Role::Z,
                "red" | "r" => {
                    has_color = true;
                    Role::Color(0, ty.is_float())
                }
                "green" | "g" => {
                    has_color = true;
                    Role::Color(1, ty.is_float())
                }
                "blue" | "b" => {
                    has_color = true;
                    Role::Color(2, ty.is_float())
                }
                "alpha" | "a" => Role::Color(3, ty.is_float()),
                "nx" | "ny" | "nz" => Role::Ignore,
                _ => {
                    scalars.push(ScalarField {
                        name: name.clone(),
                        values: Vec::new(),
                        ty: if *ty == Ty::F32 {
                            ScalarType::F32
                        } else {
                            ScalarType::F64
                        },
                    });
                    Role::Scalar(scalars.len() - 1)
                }
            },
            Prop::List(..) => Role::Ignore,
        };
        roles.push(role);
    }
    for (r, axis) in [(Role::X, "x"), (Role::Y, "y"), (Role::Z, "z")] {
        if !roles.contains(&r) {
            return Err(IoError::line(
                file,
                el.line,
                format!("vertex element has no '{axis}' property"),
            ));
        }
    }
    Ok((roles, scalars, has_color))
}

pub(super) fn face_list_index(el: &Element, file: &str) -> Result<usize, IoError> {
    el.props
        .iter()
        .position(|p| {
            matches!(p, Prop::List(..))
                && (p.name() == "vertex_indices" || p.name() == "vertex_index")
        })
        .or_else(|| el.props.iter().position(|p| matches!(p, Prop::List(..))))
        .ok_or_else(|| {
            IoError::line(
                file,
                el.line,
                "face element has no list property (vertex_indices)",
            )
        })
}

pub(super) fn color_value(v: f64, is_float: bool) -> u8 {
    if is_float {
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    } else {
        v.clamp(0.0, 255.0) as u8
    }
}

/// A list length read from the file; negative is an error at `at`.
pub(super) fn list_length(n: f64, file: &str, at: crate::Location) -> Result<usize, IoError> {
    if n < 0.0 {
        return Err(IoError::malformed(
            file,
            at,
            format!("negative list length {n}"),
        ));
    }
    Ok(n as usize)
}

pub(super) fn check_index(v: f64, file: &str, at: crate::Location) -> Result<u32, IoError> {
    if v < 0.0 || v.fract() != 0.0 || v > (u32::MAX - 1) as f64 {
        return Err(IoError::malformed(
            file,
            at,
            format!("invalid vertex index {v}"),
        ));
    }
    Ok(v as u32)
}

pub(super) fn push_face(
    sink: &mut Sink,
    corners: &[u32],
    file: &str,
    at: crate::Location,
    where_: usize,
) -> Result<(), IoError> {
    let polygon = crate::text::fan(corners, &mut sink.tris).ok_or_else(|| {
        IoError::malformed(
            file,
            at,
            format!("face with {} corner(s); at least 3 needed", corners.len()),
        )
    })?;
    sink.n_polygons += usize::from(polygon);
    sink.tri_at.resize(sink.tris.len(), where_);
    Ok(())
}

/// Decodes a triangle strip (a `tristrips` list: `-1` restarts a strip, the winding alternates
/// from one triangle to the next; triangles with a repeated vertex, used to join strips, are
/// skipped).
pub(super) fn push_strip(
    sink: &mut Sink,
    raw: &[f64],
    file: &str,
    at: crate::Location,
    where_: usize,
) -> Result<(), IoError> {
    let mut run: Vec<u32> = Vec::new();
    let flush = |run: &mut Vec<u32>, sink: &mut Sink| {
        if run.len() >= 3 {
            sink.n_strips += 1;
        }
        for k in 2..run.len() {
            let t = if k % 2 == 0 {
                [run[k - 2], run[k - 1], run[k]]
            } else {
                [run[k - 1], run[k - 2], run[k]]
            };
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                sink.n_strip_degenerate += 1;
            } else {
                sink.tris.push(t);
                sink.tri_at.push(where_);
            }
        }
        run.clear();
    };
    for &v in raw {
        if v == -1.0 {
            flush(&mut run, sink);
        } else {
            run.push(check_index(v, file, at)?);
        }
    }
    flush(&mut run, sink);
    Ok(())
}
