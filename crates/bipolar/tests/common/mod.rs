//! What the descriptor tests share: the fields from the outer eye corners and the static area of
//! paper-set faces, and the options of the iso-angle rule.

#![allow(dead_code)] // every test binary uses a part

use bipolar::{DescriptorOptions, IsoAngleOptions, LevelSpec, SelectionRule};
use facemodel::{face_frame, static_mask, Face};
use geodesic::{new_solver, Method, SolveOptions, Source};

/// The experiments' setting on a paper-set face: the fields `U_r`, `U_q` from the right and left
/// outer eye corners (solved with `method`), `D` (the mean of the two corner-to-corner
/// distances) and the static-area mask at `D`.
pub struct CornerFields {
    pub ur: Vec<f64>,
    pub uq: Vec<f64>,
    pub d: f64,
    pub mask: Vec<bool>,
}

pub fn corner_fields(face: &Face, method: Method) -> CornerFields {
    let (m, lm) = (&face.mesh, face.landmarks);
    let solver = new_solver(m, method).unwrap();
    let field = |v: u32| {
        solver
            .distances(&[Source::Vertex(v)], &SolveOptions::default())
            .unwrap()
    };
    let (ur, uq) = (field(lm.right_eye_outer), field(lm.left_eye_outer));
    let d = 0.5 * (ur[lm.left_eye_outer as usize] + uq[lm.right_eye_outer as usize]);
    let (r, q, nose) = (
        m.position(lm.right_eye_outer),
        m.position(lm.left_eye_outer),
        m.position(lm.nose_tip),
    );
    let mask = static_mask(m, &ur, &uq, d, &face_frame(m, r, q, nose), nose);
    CornerFields { ur, uq, d, mask }
}

/// The iso-angle rule with `isoangle` on the levels `levels`, up to level `max_level` of both
/// fields.
pub fn iso_angle(
    levels: LevelSpec,
    max_level: u32,
    isoangle: IsoAngleOptions,
) -> DescriptorOptions {
    DescriptorOptions {
        levels,
        max_level: Some(max_level),
        rule: SelectionRule::IsoAngle,
        isoangle,
        ..DescriptorOptions::default()
    }
}
