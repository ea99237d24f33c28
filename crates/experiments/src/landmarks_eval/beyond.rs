//! Test faces the ICT model cannot make, and things that are not faces: the faces of
//! `landmarks-eval --beyond`. Every face is made from the ICT model (read at run time) by a
//! seeded, regenerable recipe; errors are measured against the model's landmark vertices,
//! carried through the recipe.
//!
//! * [`Kind::StrongExpression`]: expressions at 1.5-2 times full strength, or two recipes mixed.
//! * [`Kind::Warp`]: a smooth random non-rigid warp of 2-6 mm (eyes wider or narrower, brows
//!   higher, nose longer, one side only), on top of a random expression.
//! * [`Kind::Remesh`]: the face subdivided and decimated to 1-5 mm edges (another topology).
//! * [`Kind::DepthCamera`]: a consumer-depth-camera-like range scan (2-5 mm pitch, depth
//!   quantised to 1-4 mm, 1 mm noise, flying pixels at the silhouette), cleaned by `scanprep`.
//! * [`non_faces`]: a sphere, a noisy plane, the back of a head (an ellipsoid cap) and a face
//!   seen from behind (normals inverted).

use anyhow::Result;
use facemodel::FaceModel;
use mesh_io::BntGrid;
use meshcore::{DAffine3, DQuat, DVec3, TriMesh};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rangescan::{
    Artifacts, DepthNoise, GrazingDropout, HeadPose, Holes, Quantisation, ScanOptions,
};

/// A kind of face outside the ICT model's span.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Expressions at 1.5-2x full strength, or two recipes mixed.
    StrongExpression,
    /// A smooth random non-rigid warp of 2-6 mm.
    Warp,
    /// Another topology: subdivided and decimated to 1-5 mm edges.
    Remesh,
    /// A consumer depth camera's scan.
    DepthCamera,
}

impl Kind {
    /// Every kind, in table order.
    pub const ALL: [Kind; 4] = [
        Kind::StrongExpression,
        Kind::Warp,
        Kind::Remesh,
        Kind::DepthCamera,
    ];

    /// Its name in tables and file names.
    pub fn name(self) -> &'static str {
        match self {
            Kind::StrongExpression => "strong-expression",
            Kind::Warp => "warp",
            Kind::Remesh => "remesh",
            Kind::DepthCamera => "depth-camera",
        }
    }
}

/// A generated test face, in mm.
#[derive(Debug, Clone)]
pub struct BeyondFace {
    /// The face's name, `KIND-NNN` (kind, then a three-digit number).
    pub name: String,
    /// The face (mm).
    pub mesh: TriMesh,
    /// Per landmark (`LandmarkName::ALL` order) the true position, or why it is not on the
    /// surface (a scan that did not see it).
    pub truth: [Result<DVec3, String>; 5],
    /// The direction toward the scanner for a scan.
    pub toward_viewer: Option<DVec3>,
    /// What the recipe did (expression, warp size, edge length, scanner settings).
    pub label: String,
}

/// Millimetres per ICT model unit.
fn mm_per_unit(ict: &FaceModel) -> f64 {
    match ict.units() {
        "mm" => 1.0,
        "m" => 1000.0,
        _ => 10.0,
    }
}

/// Seed of face `index` of `kind` in the stream of `seed`.
fn face_seed(seed: u64, kind: Kind, index: usize) -> u64 {
    let k = Kind::ALL.iter().position(|&x| x == kind).unwrap_or(0) as u64;
    (seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x6265_796f_6e64_0000)
        .wrapping_add(k << 40)
        .wrapping_add(index as u64)
}

/// Face `index` of `kind` in the stream of `seed` (the same face for the same arguments).
pub fn make(ict: &FaceModel, kind: Kind, index: usize, seed: u64) -> Result<BeyondFace> {
    let mut rng = ChaCha8Rng::seed_from_u64(face_seed(seed, kind, index));
    let s = mm_per_unit(ict);
    let name = format!("{}-{index:03}", kind.name());
    let id = ict.random_identity(&mut rng);
    let (ex, ex_label) = match kind {
        Kind::StrongExpression => strong_expression(ict, &mut rng)?,
        _ => (
            ict.random_expression(&mut rng),
            String::from("random expression"),
        ),
    };
    let face = ict.sample(&id, &ex)?;
    let truth = ict.landmark_positions(&face)?;
    let face = face.transformed(&DAffine3::from_scale(DVec3::splat(s)));
    let truth = truth.map(|p| p * s);
    let ok = |t: [DVec3; 5]| t.map(Ok);
    let motion = facemodel::random_rigid_motion(&mut rng, 100.0);
    match kind {
        Kind::StrongExpression => Ok(BeyondFace {
            name,
            mesh: face.transformed(&motion),
            truth: ok(truth.map(|p| motion.transform_point3(p))),
            toward_viewer: None,
            label: ex_label,
        }),
        Kind::Warp => {
            let (mesh, ids_truth, label) = warp(&face, &truth, ict, &mut rng)?;
            Ok(BeyondFace {
                name,
                mesh: mesh.transformed(&motion),
                truth: ok(ids_truth.map(|p| motion.transform_point3(p))),
                toward_viewer: None,
                label,
            })
        }
        Kind::Remesh => {
            let edge = rng.random_range(1.0..5.0);
            let mesh = remesh(&face, edge)?;
            let label = format!(
                "edges {edge:.2} mm asked, mean {:.2} mm, {} vertices",
                mesh.mean_edge_length(),
                mesh.n_vertices()
            );
            Ok(BeyondFace {
                name,
                mesh: mesh.transformed(&motion),
                truth: ok(truth.map(|p| motion.transform_point3(p))),
                toward_viewer: None,
                label,
            })
        }
        Kind::DepthCamera => depth_camera(name, &face, &truth, &mut rng),
    }
}

/// Expression weights beyond the model's span: a random recipe at 1.5-2x its full strength, or
/// (half of the time) two random recipes at 0.7-1.2 each, added.
fn strong_expression(ict: &FaceModel, rng: &mut ChaCha8Rng) -> Result<(Vec<f64>, String)> {
    let recipes: Vec<String> = ict.recipe_names().map(str::to_owned).collect();
    anyhow::ensure!(
        !recipes.is_empty(),
        "the ICT model has no expression recipes"
    );
    let pick = |rng: &mut ChaCha8Rng| recipes[rng.random_range(0..recipes.len())].clone();
    if rng.random::<f64>() < 0.5 {
        let (r, k) = (pick(rng), rng.random_range(1.5..2.0));
        Ok((ict.recipe_weights(&r, k)?, format!("{r} x{k:.2}")))
    } else {
        let (a, b) = (pick(rng), pick(rng));
        let (ka, kb) = (rng.random_range(0.7..1.2), rng.random_range(0.7..1.2));
        let wa = ict.recipe_weights(&a, ka)?;
        let wb = ict.recipe_weights(&b, kb)?;
        let w = wa.iter().zip(&wb).map(|(x, y)| x + y).collect();
        Ok((w, format!("{a} x{ka:.2} + {b} x{kb:.2}")))
    }
}

/// A face frame from the five landmarks: origin at the nose tip, `x` from the right to the left
/// outer eye corner, `y` up, `z` out of the face.
fn frame(truth: &[DVec3; 5]) -> (DVec3, [DVec3; 3]) {
    let x = (truth[3] - truth[0]).normalize();
    let eyes = (truth[0] + truth[1] + truth[2] + truth[3]) / 4.0;
    let up = eyes - truth[4];
    let y = (up - x * up.dot(x)).normalize();
    (truth[4], [x, y, x.cross(y)])
}

/// A Gaussian bump of the displacement field: centre, width and displacement at the centre.
struct Bump {
    centre: DVec3,
    sigma: f64,
    shift: DVec3,
}

/// Warps `face` (mm) by a sum of 3-5 smooth Gaussian bumps scaled to a largest displacement of
/// 2-6 mm: outer eye corners moved out or in (eyes wider or narrower), brows up, the nose
/// longer, random bumps; each on one side only half of the time (asymmetric faces). Returns
/// the warped mesh, its landmark vertices' positions and a label.
fn warp(
    face: &TriMesh,
    truth: &[DVec3; 5],
    ict: &FaceModel,
    rng: &mut ChaCha8Rng,
) -> Result<(TriMesh, [DVec3; 5], String)> {
    let (o, [x, y, z]) = frame(truth);
    let d = (truth[2] - truth[1]).length(); // inner-eye distance, about 33 mm
    let mut bumps = Vec::new();
    let mut what = Vec::new();
    for _ in 0..rng.random_range(3..=5) {
        // The subject's right (-1) or left (+1) side, or both.
        let sides: Vec<f64> = match rng.random_range(0..3) {
            0 => vec![-1.0],
            1 => vec![1.0],
            _ => vec![-1.0, 1.0],
        };
        let amp = rng.random_range(0.5..1.0);
        let outer = |s: f64| if s < 0.0 { truth[0] } else { truth[3] };
        let brow = |s: f64| {
            let eye = if s < 0.0 {
                truth[0] + truth[1]
            } else {
                truth[2] + truth[3]
            };
            eye / 2.0 + y * 0.45 * d
        };
        let kind = rng.random_range(0..5);
        let label = [
            "eyes wider",
            "eyes narrower",
            "brows higher",
            "nose longer",
            "random bump",
        ][kind];
        match kind {
            0..=2 => {
                for &s in &sides {
                    let (centre, shift, sigma) = match kind {
                        0 => (outer(s), x * s, 0.4 * d),
                        1 => (outer(s), -x * s, 0.4 * d),
                        _ => (brow(s), y, 0.5 * d),
                    };
                    bumps.push(Bump {
                        centre,
                        sigma,
                        shift: shift * amp,
                    });
                }
                let side = match sides.as_slice() {
                    [s] if *s < 0.0 => " (right side)",
                    [_] => " (left side)",
                    _ => "",
                };
                what.push(format!("{label}{side}"));
            }
            3 => {
                bumps.push(Bump {
                    centre: o,
                    sigma: 0.6 * d,
                    shift: (z * 0.8 - y * 0.6) * amp,
                });
                what.push(label.to_string());
            }
            _ => {
                let centre =
                    o + x * rng.random_range(-1.6..1.6) * d + y * rng.random_range(-1.0..1.8) * d;
                let dir = DVec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
                .normalize_or_zero();
                bumps.push(Bump {
                    centre,
                    sigma: 0.5 * d,
                    shift: dir * amp,
                });
                what.push(label.to_string());
            }
        }
    }
    let field = |p: DVec3| -> DVec3 {
        bumps
            .iter()
            .map(|b| b.shift * (-(p - b.centre).length_squared() / (2.0 * b.sigma * b.sigma)).exp())
            .sum()
    };
    let raw: Vec<DVec3> = face.positions().iter().map(|&p| field(p)).collect();
    let largest = raw.iter().map(|v| v.length()).fold(0.0, f64::max);
    anyhow::ensure!(largest > 0.0, "the warp moved nothing");
    let target = rng.random_range(2.0..6.0);
    let k = target / largest;
    let pos: Vec<DVec3> = face
        .positions()
        .iter()
        .zip(&raw)
        .map(|(p, v)| *p + *v * k)
        .collect();
    let mesh = TriMesh::new(pos, face.triangles().to_vec())?;
    let moved = ict.landmark_positions(&mesh)?;
    Ok((
        mesh,
        moved,
        format!("warp {target:.1} mm: {}", what.join(", ")),
    ))
}

/// One step of midpoint subdivision (every triangle into four; the surface is unchanged).
fn subdivide(m: &TriMesh) -> Result<TriMesh> {
    let mut pos = m.positions().to_vec();
    let mut mid = std::collections::HashMap::new();
    let mut at = |a: u32, b: u32, pos: &mut Vec<DVec3>| -> u32 {
        let key = (a.min(b), a.max(b));
        *mid.entry(key).or_insert_with(|| {
            pos.push((pos[a as usize] + pos[b as usize]) / 2.0);
            (pos.len() - 1) as u32
        })
    };
    let mut tri = Vec::with_capacity(4 * m.n_faces());
    for t in m.triangles() {
        let [a, b, c] = *t;
        let (ab, bc, ca) = (at(a, b, &mut pos), at(b, c, &mut pos), at(c, a, &mut pos));
        tri.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    Ok(TriMesh::new(pos, tri)?)
}

/// The face on another topology with edges of about `edge` mm: subdivided until its edges are
/// shorter than the collapse bound, then decimated by shortest-edge collapse
/// ([`scanprep::decimate`]).
pub fn remesh(face: &TriMesh, edge: f64) -> Result<TriMesh> {
    let mut m = subdivide(face)?;
    while m.mean_edge_length() > 0.5 * edge {
        m = subdivide(&m)?;
    }
    Ok(scanprep::decimate(&m, edge)?.0)
}

/// Flying pixels: background samples beside the silhouette (4-neighbours of a measurement)
/// that, with probability `rate`, hold a depth between the surface's and the background's (5-60
/// mm behind their neighbour), as time-of-flight and stereo cameras return them.
pub fn add_flying_pixels(grid: &mut BntGrid, rate: f64, rng: &mut ChaCha8Rng) -> usize {
    let (nr, nc) = (grid.nrows, grid.ncols);
    // The grid's steps along a column and along a row, from neighbouring measurements.
    let step = |dr: usize, dc: usize| -> DVec3 {
        let (mut s, mut n) = (DVec3::ZERO, 0);
        for r in 0..nr - dr {
            for c in 0..nc - dc {
                let (i, j) = (r * nc + c, (r + dr) * nc + c + dc);
                if grid.is_valid(i) && grid.is_valid(j) {
                    s += grid.xyz[j] - grid.xyz[i];
                    n += 1;
                }
            }
        }
        let v = s / n.max(1) as f64;
        DVec3::new(v.x, v.y, 0.0)
    };
    let (down, right) = (step(1, 0), step(0, 1));
    let valid: Vec<bool> = (0..nr * nc).map(|i| grid.is_valid(i)).collect();
    let mut added = 0;
    for r in 0..nr {
        for c in 0..nc {
            let i = r * nc + c;
            if valid[i] {
                continue;
            }
            let nb = [(0isize, 1isize), (0, -1), (1, 0), (-1, 0)]
                .into_iter()
                .find_map(|(a, b)| {
                    let (rr, cc) = (r as isize + a, c as isize + b);
                    (rr >= 0 && cc >= 0 && (rr as usize) < nr && (cc as usize) < nc)
                        .then(|| (rr as usize * nc + cc as usize, a, b))
                        .filter(|(j, _, _)| valid[*j])
                });
            let Some((j, a, b)) = nb else { continue };
            if rng.random::<f64>() >= rate {
                continue;
            }
            let p = grid.xyz[j] - down * a as f64 - right * b as f64;
            grid.xyz[i] = DVec3::new(p.x, p.y, p.z - rng.random_range(5.0..60.0));
            added += 1;
        }
    }
    added
}

/// A consumer depth camera's scan of `face` (mm): head yaw up to 20 degrees, 2-5 mm pitch,
/// depth quantised to 1-4 mm, 1 mm noise, dropouts at grazing angles, a few holes, flying
/// pixels at the silhouette; cleaned by `scanprep` (crop around the nose tip). The truth is
/// the scanner's projection of the landmarks, on the cleaned scan within
/// [`crate::scans::MAX_SNAP_MM`] or not on it.
fn depth_camera(
    name: String,
    face: &TriMesh,
    truth: &[DVec3; 5],
    rng: &mut ChaCha8Rng,
) -> Result<BeyondFace> {
    let pitch = rng.random_range(2.0..5.0);
    let step = rng.random_range(1.0..4.0);
    let yaw = rng.random_range(-20.0..20.0);
    let marks: Vec<(String, DVec3)> = landmarks::LandmarkName::ALL
        .iter()
        .zip(truth)
        .map(|(n, p)| (n.lm3_label().to_string(), *p))
        .collect();
    let mut scan = rangescan::scan_with_landmarks(
        face,
        &marks,
        &ScanOptions {
            input_mm_per_unit: 1.0,
            pitch_mm: pitch,
            pose: HeadPose {
                yaw_deg: yaw,
                pitch_deg: 0.0,
            },
            artifacts: Artifacts {
                noise: Some(DepthNoise { sigma_mm: 1.0 }),
                quantisation: Some(Quantisation { step_mm: step }),
                grazing: Some(GrazingDropout {
                    start_deg: 65.0,
                    full_deg: 80.0,
                }),
                holes: Some(Holes {
                    count: 2,
                    min_radius_mm: 2.0,
                    max_radius_mm: 6.0,
                }),
                ..Artifacts::none()
            },
            seed: rng.random(),
            ..ScanOptions::default()
        },
    )?;
    let flying = add_flying_pixels(&mut scan.grid, 0.5, rng);
    let nose = scan.landmarks[landmarks::LandmarkName::NoseTip as usize].position;
    let cleaned = scanprep::clean(
        scanprep::Input::Grid(&scan.grid),
        &scanprep::CleanOptions {
            crop: Some(scanprep::Crop::around(nose)),
            ..scanprep::CleanOptions::default()
        },
    )?;
    let mesh = cleaned.mesh;
    let truth = std::array::from_fn(|k| {
        let l = &scan.landmarks[k];
        match facematch::nearest_vertex(&mesh, l.position) {
            Some((_, d)) if d <= crate::scans::MAX_SNAP_MM => Ok(l.position),
            Some((_, d)) => Err(format!(
                "{} and {d:.1} mm from the cleaned surface",
                l.visibility
            )),
            None => Err("the cleaned scan is empty".into()),
        }
    });
    Ok(BeyondFace {
        name,
        label: format!(
            "pitch {pitch:.2} mm, quantisation {step:.2} mm, noise 1 mm, yaw {yaw:.1}, {flying} flying pixels, {} vertices",
            mesh.n_vertices()
        ),
        mesh,
        truth,
        toward_viewer: Some(crate::scans::SCANNER_SIDE),
    })
}

/// Things that are not faces, in mm, with a name: a sphere of radius 80, a plane with 1 mm
/// noise, the back of a head (an ellipsoid cap 150 x 190 x 60 mm) and a face seen from behind
/// (the ICT face of `seed` with its normals inverted), each under a random rigid motion.
pub fn non_faces(ict: &FaceModel, seed: u64) -> Result<Vec<(String, TriMesh)>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x6e6f_6e66_6163_6500);
    let s = mm_per_unit(ict);
    let sphere =
        meshcore::shapes::uv_sphere(60, 120).transformed(&DAffine3::from_scale(DVec3::splat(80.0)));
    let plane = meshcore::shapes::grid(
        100,
        100,
        meshcore::shapes::Diagonals::Alternating,
        |i, j| DVec3::new(2.0 * i as f64, 2.0 * j as f64, 0.0),
    )?;
    let noisy: Vec<DVec3> = plane
        .positions()
        .iter()
        .map(|p| *p + DVec3::Z * facemodel::standard_normal(&mut rng))
        .collect();
    let plane = TriMesh::new(noisy, plane.triangles().to_vec())?;
    let back = meshcore::shapes::grid(90, 90, meshcore::shapes::Diagonals::Alternating, |i, j| {
        let (u, v) = (i as f64 / 90.0 * 2.0 - 1.0, j as f64 / 90.0 * 2.0 - 1.0);
        let (a, b) = (75.0 * u, 95.0 * v);
        let r2 = (u * u + v * v).min(1.0);
        DVec3::new(a, b, 60.0 * (1.0 - r2).sqrt())
    })?;
    let id = ict.random_identity(&mut rng);
    let face = ict
        .sample(&id, &[])?
        .transformed(&DAffine3::from_scale(DVec3::splat(s)));
    let behind = TriMesh::new(
        face.positions().to_vec(),
        face.triangles()
            .iter()
            .map(|t| [t[0], t[2], t[1]])
            .collect(),
    )?;
    let mut out = Vec::new();
    for (name, m) in [
        ("sphere r=80 mm", sphere),
        ("plane with 1 mm noise", plane),
        ("back of a head (ellipsoid cap)", back),
        ("face seen from behind", behind),
    ] {
        let t = DAffine3::from_rotation_translation(
            DQuat::from_axis_angle(
                DVec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    1.0,
                )
                .normalize(),
                rng.random_range(0.0..std::f64::consts::TAU),
            ),
            DVec3::ZERO,
        );
        out.push((name.to_string(), m.transformed(&t)));
    }
    Ok(out)
}
