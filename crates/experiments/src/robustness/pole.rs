//! Figure 15: rotating some polar rings of the test face individually keeps every per-ring
//! distance ~0 while the global distance becomes large.

use super::{eye_mid, Args, FacePrep};
use crate::pipeline::dist;
use crate::polar::{polar_descriptor, PolarOptions, Pole};
use crate::report::{markers, render_face};
use crate::walk::Walker;
use anyhow::Result;
use bipolar::PolarDescriptor;
use facemodel::{Face, FaceFrame};
use geodesic::Method;
use meshcore::{DMat3, DQuat, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::path::Path;
use viz::Scene;

/// The rings rotated.
pub(crate) const ROTATED: [u32; 3] = [2, 4, 6];

/// Figure-15 numbers.
pub(super) struct Figure15 {
    /// The other person's face compared with.
    pub other: usize,
    /// Distance of each ring to its rotated copy, each with its own best rotation.
    pub per_ring: Vec<(u32, f64)>,
    /// Keyed distance between the descriptor and the one with rotated rings.
    pub global: f64,
    /// Keyed distance between the test face and `other`.
    pub reference: f64,
}

/// The polar descriptor of face `f` (pole at the nose tip, step D / `levels` with D the right
/// corner's field at the left corner) and its frame.
fn describe(
    f: &Face,
    method: Method,
    levels: u32,
    sectors: u32,
) -> Result<(PolarDescriptor, FaceFrame)> {
    let p = FacePrep::new(f, method)?;
    let d = p.refs.ur[f.landmarks.left_eye_outer as usize];
    let opts = PolarOptions {
        step: d / f64::from(levels),
        levels,
        sectors,
    };
    let (w, pole) = (Walker::new(&f.mesh), Pole::Vertex(f.landmarks.nose_tip));
    let polar = polar_descriptor(&w, &p.un, pole, eye_mid(&p.refs), &opts)?;
    Ok((polar, p.refs.frame))
}

/// `s` with rings [`ROTATED`] each rotated about its centroid by a seeded random rotation.
pub(crate) fn rotate_rings(s: &PolarDescriptor, seed: u64) -> PolarDescriptor {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut s1 = s.clone();
    for &lvl in &ROTATED {
        let idx: Vec<usize> = (0..s.points.len())
            .filter(|&k| s.points[k].key.level == lvl)
            .collect();
        if idx.is_empty() {
            continue;
        }
        let c = idx.iter().map(|&k| s.points[k].position).sum::<DVec3>() / idx.len() as f64;
        let axis = DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize_or_zero();
        let angle = rng.random_range(0.5..1.5);
        let rot = DMat3::from_quat(DQuat::from_axis_angle(
            if axis == DVec3::ZERO { DVec3::Z } else { axis },
            angle,
        ));
        for &k in &idx {
            s1.points[k].position = c + rot * (s.points[k].position - c);
        }
    }
    s1
}

/// Computes figure 15 with `method` on the test face and the first face of another person,
/// and writes its render.
pub(super) fn figure15(
    args: &Args,
    faces: &[Face],
    test: usize,
    method: Method,
    out: &Path,
) -> Result<Figure15> {
    let other = faces
        .iter()
        .position(|f| f.person != faces[test].person)
        .unwrap_or(test);
    let descs: Vec<(PolarDescriptor, FaceFrame)> = [test, other]
        .par_iter()
        .map(|&i| describe(&faces[i], method, args.set.res.levels, args.set.res.sectors))
        .collect::<Result<_>>()?;
    let (s, frame) = &descs[0];
    let s1 = rotate_rings(s, args.seed);
    let mut per_ring = Vec::new();
    for lvl in 1..=args.set.res.levels {
        let idx: Vec<usize> = (0..s.points.len())
            .filter(|&k| s.points[k].key.level == lvl)
            .collect();
        let keys: Vec<u64> = idx.iter().map(|&k| s.points[k].key.pack()).collect();
        let a: Vec<DVec3> = idx.iter().map(|&k| s.points[k].position).collect();
        let b: Vec<DVec3> = idx.iter().map(|&k| s1.points[k].position).collect();
        let d =
            shapedist::keyed_distance(&keys, &a, &keys, &b, &shapedist::KeyedOptions::default());
        per_ring.push((lvl, d.map_or(f64::NAN, |d| d.distance)));
    }
    let global = dist(s, &s1)?;
    let reference = dist(s, &descs[1].0)?;
    let moved: Vec<DVec3> = s1
        .points
        .iter()
        .filter(|p| ROTATED.contains(&p.key.level))
        .map(|p| p.position)
        .collect();
    let mut scene = Scene::new(&faces[test].mesh);
    scene.points = markers(s.positions(), [0x24, 0x71, 0xa3], 2.2);
    scene.points.extend(markers(moved, [0xc0, 0x39, 0x2b], 2.6));
    render_face(&out.join("figure15.svg"), &scene, frame.up, frame.forward)?;
    Ok(Figure15 {
        other,
        per_ring,
        global,
        reference,
    })
}
