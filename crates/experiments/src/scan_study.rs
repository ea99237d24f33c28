//! `cargo xtask scan-study`: is the descriptor stable on range scans?
//!
//! The faces of the paper set (ICT, cm) are scanned by `rangescan` under several settings
//! (pitch, depth noise, head pose, 2 mm depth quantisation, seed), cleaned by `scanprep::clean`
//! (crop around the projected nose tip) and described with the experiments' reference points:
//! the scanner's ground-truth landmarks (outer eye corners, nose tip) projected onto the cleaned
//! scan. The face mesh itself, scaled to mm, is one more "scan" (the ICT sampling). Every pair
//! of scans gets four distances: bipolar with rule `All` (the experiments' rule) and with the
//! iso-angle rule, both on the static area at N levels; the single pole (`bipolar::polar`); ICP
//! of static-area points onto the other scan's surface (RMS mm, `shapedist::icp_to_target`).
//! Pairs are *same face* (two scans of one face), *same person* (id1's expressions) or *other
//! person*. The report gives the distributions, the ratio min(other) / max(same face) per
//! method and the fraction of descriptor points with ambiguous keys per setting.
//!
//! Only composes the libraries; deterministic (the scanner's seeds, rayon results collected in
//! input order).

use crate::paths::FaceSetArgs;
use crate::pipeline::{bar, dist, kept_vertices, landmark_icp_rms, restrict};
use crate::polar::{polar_descriptor, PolarOptions, Pole};
use crate::report::{joined, write_csv};
use anyhow::{bail, Context, Result};
use facemodel::{face_frame, load_face_set, static_mask, Face};
use geodesic::{Method, SolveOptions, Source};
use meshcore::{DVec3, FaceLocator, SurfacePoint, TriMesh};
use rangescan::{Artifacts, DepthNoise, HeadPose, Quantisation, ScanOptions};
use rayon::prelude::*;
use scanprep::{CleanOptions, Crop, Input};
use std::fmt::Write as _;
use std::time::Instant;

/// Arguments of `cargo xtask scan-study`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Face set, report folder (default `target/scan-study`) and descriptor resolution (static
    /// area: levels <= N).
    #[command(flatten)]
    pub set: FaceSetArgs,
    /// Only the first `n` scan settings (of the fixed list; 0 = all).
    #[arg(long, default_value_t = 0)]
    pub settings: usize,
    /// ICP probe points per scan (static-area vertices, evenly strided).
    #[arg(long, default_value_t = 200)]
    pub icp_points: usize,
    /// Which pairs of scans are compared: `study` (every pair of two acquisitions of one face,
    /// and every pair within one setting: other persons and id1's expressions are compared
    /// under equal conditions) or `all` (every pair, which for the 8 settings is 4.6k pairs,
    /// five times as many, mostly other persons across settings).
    #[arg(long, default_value = "study", value_parser = ["study", "all"])]
    pub pairs: String,
    /// Only the faces whose name contains one of these strings (comma separated; default all).
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
    /// Largest distance (mm) between a projected landmark and the cleaned scan surface; farther
    /// landmarks (occluded, in a hole, cropped) make the scan unusable.
    #[arg(long, default_value_t = 2.0)]
    pub landmark_tolerance_mm: f64,
    /// Taubin smoothing iterations of the cleaned scans (`scanprep`; 0: none).
    #[arg(long, default_value_t = 0)]
    pub smooth: usize,
    /// Radius (mm) of the reference-point search of the searched distance: each scan is also
    /// described from the poles of its three pole pairs moved by this much in 6 directions
    /// (`bipolar::SearchedPole`; 0, the default: no search and no searched distance). Measured
    /// in docs/scans.md: it does not raise the separation ratios, and it makes the run several
    /// times longer.
    #[arg(long, default_value_t = 0.0)]
    pub ref_search_mm: f64,
}

/// One way of acquiring a face.
#[derive(Debug, Clone)]
struct Setting {
    name: &'static str,
    /// `None`: the face mesh itself, scaled to mm (no scanner).
    scan: Option<ScanSpec>,
}

#[derive(Debug, Clone, Copy)]
struct ScanSpec {
    pitch_mm: f64,
    noise_mm: f64,
    quant_mm: Option<f64>,
    yaw_deg: f64,
    pitch_deg: f64,
    seed: u64,
}

fn settings() -> Vec<Setting> {
    let s = |pitch_mm, noise_mm, quant_mm, yaw_deg, pitch_deg, seed| {
        Some(ScanSpec {
            pitch_mm,
            noise_mm,
            quant_mm,
            yaw_deg,
            pitch_deg,
            seed,
        })
    };
    vec![
        Setting {
            name: "p0.75 n0.1",
            scan: s(0.75, 0.1, None, 0.0, 0.0, 1),
        },
        Setting {
            name: "p0.5 n0.1",
            scan: s(0.5, 0.1, None, 0.0, 0.0, 2),
        },
        Setting {
            name: "p1.0 n0.1",
            scan: s(1.0, 0.1, None, 0.0, 0.0, 3),
        },
        Setting {
            name: "p0.75 n0.2",
            scan: s(0.75, 0.2, None, 0.0, 0.0, 4),
        },
        Setting {
            name: "p0.75 yaw20",
            scan: s(0.75, 0.1, None, 20.0, 0.0, 5),
        },
        Setting {
            name: "p0.75 pitch10",
            scan: s(0.75, 0.1, None, 0.0, 10.0, 6),
        },
        Setting {
            name: "p0.75 q2mm",
            scan: s(0.75, 0.1, Some(2.0), 0.0, 0.0, 7),
        },
        Setting {
            name: "mesh (mm)",
            scan: None,
        },
    ]
}

/// Millimetres per unit of the paper-set meshes (cm).
const MM_PER_CM: f64 = 10.0;

/// Everything measured on one scan.
struct ScanResult {
    face: usize,
    setting: usize,
    status: Result<Described, String>,
}

struct Described {
    vertices: usize,
    mean_edge_mm: f64,
    d_mm: f64,
    landmark_offsets_mm: [f64; 3],
    /// One descriptor per entry of [`VARIANTS`] (`None`: refused, the reason in `notes`).
    bip: Vec<Option<bipolar::Descriptor>>,
    /// Per entry of [`VARIANTS`] with [`Variant::side_pairs`]: the descriptors of the right and
    /// of the left outer eye corner with the nose tip (`None` otherwise or refused).
    sides: Vec<Option<[bipolar::Descriptor; 2]>>,
    /// The [`LEAST`] variant's descriptors from moved poles, per pole pair (corners, right
    /// corner and nose tip, left corner and nose tip; empty without the search).
    searched: [Vec<bipolar::Descriptor>; 3],
    polar: bipolar::PolarDescriptor,
    notes: Vec<String>,
    icp_probe: Vec<DVec3>,
    landmarks: [DVec3; 3],
    mesh: TriMesh,
    seconds: f64,
}

/// The acquired mesh (mm) and the three ground-truth landmarks (r, q, nose) in its frame.
/// Also returns the landmarks the scanner did not see (label and why).
fn acquire(
    face: &Face,
    setting: &Setting,
    smooth: usize,
) -> Result<(TriMesh, [DVec3; 3], Vec<String>)> {
    let lm = face.landmarks;
    let truth = [lm.right_eye_outer, lm.left_eye_outer, lm.nose_tip].map(|v| face.mesh.position(v));
    let Some(spec) = setting.scan else {
        let mesh = TriMesh::new(
            face.mesh
                .positions()
                .iter()
                .map(|p| *p * MM_PER_CM)
                .collect(),
            face.mesh.triangles().to_vec(),
        )?;
        return Ok((mesh, truth.map(|p| p * MM_PER_CM), Vec::new()));
    };
    let artifacts = Artifacts {
        noise: Some(DepthNoise {
            sigma_mm: spec.noise_mm,
        }),
        quantisation: spec.quant_mm.map(|step_mm| Quantisation { step_mm }),
        ..Artifacts::structured_light()
    };
    let opts = ScanOptions {
        input_mm_per_unit: MM_PER_CM,
        pitch_mm: spec.pitch_mm,
        pose: HeadPose {
            yaw_deg: spec.yaw_deg,
            pitch_deg: spec.pitch_deg,
        },
        artifacts,
        seed: spec.seed,
        ..ScanOptions::default()
    };
    let names = ["right_eye_outer", "left_eye_outer", "nose_tip"];
    let marks: Vec<(String, DVec3)> = names
        .iter()
        .zip(truth)
        .map(|(n, p)| (n.to_string(), p))
        .collect();
    let scan = rangescan::scan_with_landmarks(&face.mesh, &marks, &opts)?;
    // A landmark the scanner hides behind other surface is unusable; one in a small hole or a
    // grazing dropout may lie on the cleaned (filled) surface, which `snap` decides.
    for m in &scan.landmarks {
        if matches!(
            m.visibility,
            rangescan::Visibility::Occluded { .. } | rangescan::Visibility::OutsideGrid
        ) {
            bail!("landmark {} {}", m.label, m.visibility);
        }
    }
    let hidden: Vec<String> = scan
        .landmarks
        .iter()
        .filter(|m| !m.visibility.is_visible())
        .map(|m| format!("{} {}", m.label, m.visibility))
        .collect();
    let pos = [0, 1, 2].map(|k| scan.landmarks[k].position);
    let cleaned = scanprep::clean(
        Input::Grid(&scan.grid),
        &CleanOptions {
            units: Some(meshcore::units::Units::Millimetre),
            crop: Some(Crop::around(pos[2])),
            smoothing_iterations: smooth,
            ..CleanOptions::default()
        },
    )?;
    Ok((cleaned.mesh, pos, hidden))
}

/// Snaps the landmarks onto the mesh; an offset above `tol_mm` is an error naming it.
fn snap(
    loc: &FaceLocator<'_>,
    lms: &[DVec3; 3],
    tol_mm: f64,
) -> Result<([SurfacePoint; 3], [f64; 3])> {
    let mut sp = [SurfacePoint::new(0, DVec3::X); 3];
    let mut off = [0.0; 3];
    for k in 0..3 {
        let (p, d) = loc.nearest(lms[k])?;
        if d > tol_mm {
            bail!(
                "landmark {} is {d:.2} mm from the cleaned surface (tolerance {tol_mm} mm)",
                ["right_eye_outer", "left_eye_outer", "nose_tip"][k]
            );
        }
        sp[k] = p;
        off[k] = d;
    }
    Ok((sp, off))
}

fn field_at(mesh: &TriMesh, u: &[f64], sp: &SurfacePoint) -> f64 {
    crate::pipeline::field_at(mesh, u, sp)
}

fn describe_scan(face: &Face, setting: &Setting, args: &Args) -> Result<Described> {
    let t0 = Instant::now();
    let (mesh, lms, hidden) = acquire(face, setting, args.smooth)?;
    let mut d = describe_mesh(mesh, &lms, &hidden, args, None)?;
    d.seconds = t0.elapsed().as_secs_f64();
    Ok(d)
}

/// The descriptions of an acquired mesh (mm) with landmarks `lms` (r, q, nose; `hidden`: those
/// the scanner did not see, for the notes). With `view` (another scanner's direction in this
/// frame: the mesh is a view-matched cut) only the least of the three pole pairs ([`LEAST`]) is
/// described, its incidence limit holds from both directions, and the single pole is left
/// empty.
fn describe_mesh(
    mesh: TriMesh,
    lms: &[DVec3; 3],
    hidden: &[String],
    args: &Args,
    view: Option<DVec3>,
) -> Result<Described> {
    let t0 = Instant::now();
    let loc = FaceLocator::new(&mesh);
    let (sp, off) = snap(&loc, lms, args.landmark_tolerance_mm)?;
    let pos = sp.map(|s| mesh.point_position(&s).unwrap_or(DVec3::NAN));
    let solver = geodesic::new_solver(&mesh, Method::Exact)?;
    // The static area lies within D of both corners and the polar rays reach D from the nose
    // tip; D is about 1.2 times the straight distance between the corners. The fields are cut
    // off past that (values within the cut are exact); a cut that turns out too short is an
    // error, never a silently smaller region.
    let max_edge = (0..mesh.n_faces() as u32)
        .flat_map(|f| {
            let [a, b, c] = mesh.face_corners(f);
            [(a - b).length(), (b - c).length(), (c - a).length()]
        })
        .fold(0.0f64, f64::max);
    let cut = 1.4 * (pos[0] - pos[1]).length() + max_edge;
    let solve = |s: SurfacePoint| -> Result<Vec<f64>> {
        Ok(solver.distances(
            &[Source::Point(s)],
            &SolveOptions {
                max_distance: Some(cut),
            },
        )?)
    };
    let ur = solve(sp[0])?;
    let uq = solve(sp[1])?;
    let un = solve(sp[2])?;
    let d = 0.5 * (field_at(&mesh, &ur, &sp[1]) + field_at(&mesh, &uq, &sp[0]));
    if !(d.is_finite() && d > 0.0) {
        bail!("the corners are not connected within the cut-off {cut:.1} mm (D = {d})");
    }
    if d + 2.0 * max_edge > cut {
        bail!("D = {d:.1} mm exceeds the fields' cut-off {cut:.1} mm");
    }
    let frame = face_frame(&mesh, pos[0], pos[1], pos[2]);
    let mut notes: Vec<String> = hidden
        .iter()
        .map(|h| format!("landmark {h}, snapped to the cleaned surface"))
        .collect();
    let mask = static_mask(&mesh, &ur, &uq, d, &frame, pos[2]);
    let surface = bipolar::Surface::new(mesh.clone());
    // The side pairs' D: each corner's geodesic distance to the nose tip.
    let d_side =
        |u: &[f64], k: usize| 0.5 * (field_at(&mesh, u, &sp[2]) + field_at(&mesh, &un, &sp[k]));
    let d_sides = [d_side(&ur, 0), d_side(&uq, 1)];
    let fields = [ur, uq];
    let mut bip = Vec::new();
    let mut sides = Vec::new();
    let mut searched: [Vec<bipolar::Descriptor>; 3] = Default::default();
    // The band along the holes, built once per margin and left out through the vertex mask
    // (`pipeline::kept_vertices`) rather than again by every descriptor.
    let mut bands: Vec<(f64, Result<Vec<bool>, String>)> = Vec::new();
    for (k, v) in VARIANTS.iter().enumerate() {
        if view.is_some() && k != LEAST {
            bip.push(None);
            sides.push(None);
            continue;
        }
        let seen = match v
            .max_incidence_deg
            .map(|deg| facematch::seen_within(&mesh, crate::scans::SCANNER_SIDE, view, deg))
        {
            Some(Err(e)) => {
                notes.push(format!("{}: {e}", v.name));
                bip.push(None);
                sides.push(None);
                continue;
            }
            seen => seen.and_then(Result::ok),
        };
        let band = v.margin_mm.map(|m| {
            let i = bands.iter().position(|(b, _)| *b == m).unwrap_or_else(|| {
                let kept = match kept_vertices(&surface, None, Some(m)) {
                    Ok(Some(kept)) => Ok(kept),
                    Ok(None) => Err("no band mask".to_string()),
                    Err(e) => Err(e.to_string()),
                };
                bands.push((m, kept));
                bands.len() - 1
            });
            bands[i].1.clone()
        });
        let seen = match band {
            Some(Err(e)) => {
                notes.push(format!("{}: {e}", v.name));
                bip.push(None);
                sides.push(None);
                continue;
            }
            band => restrict(seen, band.and_then(Result::ok).as_deref()),
        };
        let describe = |pair: [&[f64]; 2], d: f64, frame: &facemodel::FaceFrame| {
            let mask = static_mask(&mesh, pair[0], pair[1], d, frame, pos[2]);
            let opts = bipolar::DescriptorOptions {
                levels: bipolar::LevelSpec::Step(d / f64::from(args.set.res.levels)),
                max_level: Some(args.set.res.levels),
                vertex_mask: restrict(Some(mask), seen.as_deref()),
                ..v.options()
            };
            bipolar::describe(
                &surface,
                bipolar::Fields::Precomputed {
                    fields: &[pair[0].to_vec(), pair[1].to_vec()],
                    references: None,
                },
                &opts,
            )
            .map_err(|e| format!("{}: {e}", v.name))
        };
        // A variant described like an earlier one (another distance rule over the same
        // descriptors) takes that one's descriptors; its side pairs from one that has them.
        let earlier = |want_sides: bool| {
            (0..k).find(|&j| {
                view.is_none()
                    && VARIANTS[j].same_description(v)
                    && (!want_sides || VARIANTS[j].side_pairs.is_some())
            })
        };
        match earlier(false) {
            Some(j) => bip.push(bip[j].clone()),
            None => match describe([&fields[0], &fields[1]], d, &frame) {
                Ok(d) => bip.push(Some(d)),
                Err(e) => {
                    notes.push(e);
                    bip.push(None);
                }
            },
        }
        sides.push(if let (Some(_), Some(j)) = (v.side_pairs, earlier(true)) {
            sides[j].clone()
        } else if v.side_pairs.is_some() {
            let side = |k: usize| {
                let dk = d_sides[k];
                if !(dk.is_finite() && dk > 0.0) {
                    return Err(format!(
                        "{}: the corner and the nose tip are not connected within the cut-off",
                        v.name
                    ));
                }
                describe([&fields[k], &un], dk, &frame)
            };
            match (side(0), side(1)) {
                (Ok(a), Ok(b)) => Some([a, b]),
                (Err(e), _) | (_, Err(e)) => {
                    notes.push(e);
                    None
                }
            }
        } else {
            None
        });
        if k == LEAST && view.is_none() && args.ref_search_mm > 0.0 {
            // The reference-point search (as the recognition benchmark's, over all three
            // pairs): each landmark at its nearest vertex, with its candidates moved by the
            // radius, the first direction of a corner toward the other corner and of the nose
            // tip toward their midpoint, so each moved field is solved once for both its pairs.
            let rho = args.ref_search_mm;
            let moved_cut = SolveOptions {
                max_distance: Some(cut + 4.0 * rho),
            };
            let toward = [pos[1], pos[0], 0.5 * (pos[0] + pos[1])];
            let poles: Vec<bipolar::SearchedPole> = (0..3)
                .map(|k| {
                    let v = mesh.nearest_corner(&sp[k]).ok()?;
                    let given = solver.distances(&[Source::Vertex(v)], &moved_cut).ok()?;
                    bipolar::SearchedPole::new(
                        &mesh,
                        solver.as_ref(),
                        v,
                        toward[k],
                        &given,
                        rho,
                        crate::recognition::SEARCH_DIRECTIONS,
                        &moved_cut,
                    )
                    .ok()
                })
                .map(Option::unwrap_or_default)
                .collect();
            for (p, (ka, kb)) in [(0, 1), (0, 2), (1, 2)].into_iter().enumerate() {
                for m in bipolar::moved_pairs(&poles[ka], &poles[kb]) {
                    if m.d + 2.0 * max_edge > cut + 4.0 * rho {
                        continue;
                    }
                    let frame = if p == 0 {
                        face_frame(&mesh, mesh.position(m.r), mesh.position(m.q), pos[2])
                    } else {
                        frame
                    };
                    if let Ok(b) = describe([m.ur, m.uq], m.d, &frame) {
                        searched[p].push(b);
                    }
                }
            }
        }
    }
    let polar_opts = PolarOptions {
        step: d / f64::from(args.set.res.levels),
        levels: args.set.res.levels,
        sectors: args.set.res.sectors,
    };
    let polar = match view {
        Some(_) => crate::polar::empty(&polar_opts),
        None => polar_descriptor(
            &geodesic::straightest::Walker::new(&mesh),
            &un,
            Pole::Point(sp[2]),
            0.5 * (pos[0] + pos[1]),
            &polar_opts,
        )?,
    };
    let inside: Vec<DVec3> = (0..mesh.n_vertices())
        .filter(|&v| mask[v])
        .map(|v| mesh.position(v as u32))
        .collect();
    let stride = (inside.len() / args.icp_points.max(3)).max(1);
    let icp_probe = inside.iter().step_by(stride).copied().collect();
    Ok(Described {
        vertices: mesh.n_vertices(),
        mean_edge_mm: mesh.mean_edge_length(),
        d_mm: d,
        landmark_offsets_mm: off,
        bip,
        sides,
        searched,
        polar,
        notes,
        icp_probe,
        landmarks: pos,
        seconds: t0.elapsed().as_secs_f64(),
        mesh,
    })
}

/// ICP of `a`'s probe points onto `b`'s surface from the landmark alignment: RMS closest-point
/// distance (mm) over all probe points at the final pose (`pipeline::landmark_icp_rms`, at
/// most 10 iterations).
fn icp_score(a: &Described, b: &Described, b_loc: &FaceLocator<'_>) -> f64 {
    landmark_icp_rms(&a.icp_probe, &a.landmarks, b_loc, &b.landmarks, 10)
}

/// Fraction of a descriptor's points whose key is ambiguous (NaN when refused).
fn ambiguous_fraction(d: &Option<bipolar::Descriptor>) -> f64 {
    d.as_ref().map_or(f64::NAN, |d| {
        d.points.iter().filter(|p| p.ambiguous).count() as f64 / d.points.len().max(1) as f64
    })
}

fn n_points(d: &Option<bipolar::Descriptor>) -> usize {
    d.as_ref().map_or(0, |d| d.points.len())
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Relation {
    SameFace,
    SamePerson,
    Other,
}

impl Relation {
    fn name(self) -> &'static str {
        match self {
            Relation::SameFace => "same face",
            Relation::SamePerson => "same person",
            Relation::Other => "other person",
        }
    }
}

/// A bipolar descriptor variant of the study: the library's options by name.
struct Variant {
    name: &'static str,
    /// `None`: rule `All`; else the iso-angle rule with these crossings and repeats.
    isoangle: Option<(bipolar::IsoCrossings, bipolar::IsoRepeats)>,
    /// Band along the scan's boundary left out (mm; built once per scan by
    /// `pipeline::kept_vertices` and left out through the vertex mask, which leaves out what
    /// `DescriptorOptions::boundary_margin` would).
    margin_mm: Option<f64>,
    /// Vertices the scanner saw at a larger incidence left out (`scanprep::incidence_mask`,
    /// degrees; the scans and the face mesh look along +z).
    max_incidence_deg: Option<f64>,
    /// Also described by each outer eye corner with the nose tip (the recognition benchmark's
    /// side pairs: their lens above the nose tip's horizontal plane); the distance is then the
    /// mean or the least of the three pairs' distances.
    side_pairs: Option<PairCombine>,
}

/// How a variant with side pairs combines the distances by its three pole pairs.
#[derive(Debug, Clone, Copy)]
enum PairCombine {
    Mean,
    Least,
}

impl Variant {
    /// The two variants build the same descriptors (they may differ in the distance rule).
    fn same_description(&self, other: &Variant) -> bool {
        self.isoangle == other.isoangle
            && self.margin_mm == other.margin_mm
            && self.max_incidence_deg == other.max_incidence_deg
    }

    /// The library's options of the variant's selection rule (its band and incidence limit go
    /// through the vertex mask).
    fn options(&self) -> bipolar::DescriptorOptions {
        match self.isoangle {
            None => bipolar::DescriptorOptions {
                rule: bipolar::SelectionRule::All,
                ..Default::default()
            },
            Some((crossings, repeats)) => bipolar::DescriptorOptions {
                rule: bipolar::SelectionRule::IsoAngle,
                isoangle: bipolar::IsoAngleOptions {
                    crossings,
                    repeats,
                    ..Default::default()
                },
                ..Default::default()
            },
        }
    }
}

/// The bipolar variants: the experiments' rule (`All`, grid keys) and the iso-angle rule with
/// every crossing (the first behaviour), with the monotone fit keeping repeated keys as ambiguous
/// (the second) and with the monotone fit and repeated keys resolved to the place nearest the
/// geodesic between the references (the library's default); rule `All` without the 6 mm band
/// along the holes and the border of each scan (the scans' choice in the recognition
/// benchmark), and that with the parts seen at more than 60 or 45 degrees of incidence left out
/// too; the 60-degree one also with the two side pairs (each outer eye corner with the nose
/// tip), by the mean and by the least of the three pairs' distances.
const VARIANTS: [Variant; 9] = {
    use bipolar::{IsoCrossings::*, IsoRepeats::*};
    [
        Variant {
            name: "bipolar All",
            isoangle: None,
            margin_mm: None,
            max_incidence_deg: None,
            side_pairs: None,
        },
        Variant {
            name: "bipolar iso-angle, every crossing",
            isoangle: Some((Every, Ambiguous)),
            margin_mm: None,
            max_incidence_deg: None,
            side_pairs: None,
        },
        Variant {
            name: "bipolar iso-angle, monotone, repeats ambiguous",
            isoangle: Some((Monotone, Ambiguous)),
            margin_mm: None,
            max_incidence_deg: None,
            side_pairs: None,
        },
        Variant {
            name: "bipolar iso-angle, monotone, nearest",
            isoangle: Some((Monotone, Nearest)),
            margin_mm: None,
            max_incidence_deg: None,
            side_pairs: None,
        },
        Variant {
            name: "bipolar All, 6 mm band left out",
            isoangle: None,
            margin_mm: Some(6.0),
            max_incidence_deg: None,
            side_pairs: None,
        },
        Variant {
            name: "bipolar All, band and incidence over 60 degrees left out",
            isoangle: None,
            margin_mm: Some(6.0),
            max_incidence_deg: Some(60.0),
            side_pairs: None,
        },
        Variant {
            name: "bipolar All, band and incidence over 45 degrees left out",
            isoangle: None,
            margin_mm: Some(6.0),
            max_incidence_deg: Some(45.0),
            side_pairs: None,
        },
        Variant {
            name:
                "bipolar All, band and incidence over 60 degrees left out, three pole pairs, mean",
            isoangle: None,
            margin_mm: Some(6.0),
            max_incidence_deg: Some(60.0),
            side_pairs: Some(PairCombine::Mean),
        },
        Variant {
            name:
                "bipolar All, band and incidence over 60 degrees left out, three pole pairs, least",
            isoangle: None,
            margin_mm: Some(6.0),
            max_incidence_deg: Some(60.0),
            side_pairs: Some(PairCombine::Least),
        },
    ]
};

/// The entry of [`VARIANTS`] with the least of the three pole pairs (the recognition
/// benchmark's rule), also measured with view matching.
const LEAST: usize = 8;

/// Name of the view-matched distance (the [`LEAST`] variant of two scans, each cut to what the
/// other's scanner would have measured when their directions differ by at least
/// `SCAN_VIEW_MATCH_DEG`).
const VIEW_MATCHED: &str =
    "bipolar All, band and incidence over 60 degrees left out, three pole pairs, least, view-matched";

/// Name of the distance of the [`LEAST`] variant with the reference-point search
/// ([`searched_distance`]).
const SEARCHED: &str =
    "bipolar All, band and incidence over 60 degrees left out, three pole pairs, least, reference-point search";

/// Names of the distances: the bipolar variants, the view-matched one, the searched one with
/// `args.ref_search_mm` > 0, then the single pole and ICP.
fn methods(args: &Args) -> Vec<&'static str> {
    VARIANTS
        .iter()
        .map(|v| v.name)
        .chain([VIEW_MATCHED])
        .chain((args.ref_search_mm > 0.0).then_some(SEARCHED))
        .chain(["single pole", "ICP (mm)"])
        .collect()
}

/// The distance of two scans by variant `k` of [`VARIANTS`] (NaN where either has no
/// descriptor or the distance fails): the keyed distance, or with side pairs the mean or least
/// of the three pairs'.
fn variant_distance(a: &Described, b: &Described, k: usize) -> f64 {
    let kd = |x: &Option<bipolar::Descriptor>, y: &Option<bipolar::Descriptor>| match (x, y) {
        (Some(x), Some(y)) => dist(x, y).unwrap_or(f64::NAN),
        _ => f64::NAN,
    };
    let corners = kd(&a.bip[k], &b.bip[k]);
    match (VARIANTS[k].side_pairs, &a.sides[k], &b.sides[k]) {
        (None, ..) => corners,
        (Some(c), Some([ra, la]), Some([rb, lb])) => {
            let side = |x, y| dist(x, y).unwrap_or(f64::NAN);
            let all = [corners, side(ra, rb), side(la, lb)];
            match c {
                PairCombine::Mean => all.iter().sum::<f64>() / 3.0,
                PairCombine::Least => all.into_iter().fold(f64::NAN, f64::min),
            }
        }
        (Some(_), ..) => f64::NAN,
    }
}

/// The [`LEAST`] distance of two scans with view matching: each is cut to the faces the
/// other's scanner would have measured (`facematch::cut_to_view`, when the two directions differ by
/// at least `SCAN_VIEW_MATCH_DEG`) and described again; a side whose cut or any of whose three
/// descriptions fails keeps its own description.
fn view_matched_distance(a: &Described, b: &Described, args: &Args) -> f64 {
    let cut = |x: &Described, y: &Described| {
        let side = crate::scans::SCANNER_SIDE;
        let toward = facematch::probe_direction(&y.landmarks, side, &x.landmarks)?;
        if toward.angle_between(side).to_degrees() < crate::recognition::SCAN_VIEW_MATCH_DEG {
            return None;
        }
        let c = facematch::cut_to_view(&x.mesh, toward, &facematch::ViewOptions::default()).ok()?;
        describe_mesh(c.mesh, &x.landmarks, &[], args, Some(toward))
            .ok()
            .filter(|d| d.bip[LEAST].is_some() && d.sides[LEAST].is_some())
    };
    let (ca, cb) = (cut(a, b), cut(b, a));
    variant_distance(ca.as_ref().unwrap_or(a), cb.as_ref().unwrap_or(b), LEAST)
}

/// The [`LEAST`] distance with the reference-point search: per pole pair
/// `bipolar::least_searched_distance` of the two scans' own and moved descriptors
/// ([`Described::searched`]), then the least over the three pairs; NaN where either scan lacks its own
/// descriptors of the three pairs.
fn searched_distance(a: &Described, b: &Described) -> f64 {
    fn own(x: &Described) -> Option<[&bipolar::Descriptor; 3]> {
        let [r, l] = x.sides[LEAST].as_ref()?;
        Some([x.bip[LEAST].as_ref()?, r, l])
    }
    let (Some(oa), Some(ob)) = (own(a), own(b)) else {
        return f64::NAN;
    };
    (0..3)
        .map(|p| {
            bipolar::least_searched_distance(oa[p], &a.searched[p], ob[p], &b.searched[p], dist)
                .unwrap_or(f64::NAN)
        })
        .fold(f64::NAN, f64::min)
}

struct Pair {
    a: usize,
    b: usize,
    rel: Relation,
    d: Vec<f64>,
}

fn quantiles(v: &[f64]) -> (f64, f64, f64, usize) {
    let mut f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    f.sort_by(f64::total_cmp);
    if f.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN, 0);
    }
    (f[0], f[f.len() / 2], f[f.len() - 1], f.len())
}

/// Runs the study; prints the report folder on the last line.
pub fn run(args: Args) -> Result<()> {
    let t0 = Instant::now();
    let dir = args.set.faces_dir();
    let mut faces = load_face_set(&dir)?;
    if !args.only.is_empty() {
        faces.retain(|f| args.only.iter().any(|o| f.name.contains(o.as_str())));
        if faces.is_empty() {
            bail!(
                "no face of {} matches --only {:?}",
                dir.display(),
                args.only
            );
        }
    }
    let out = args.set.out.out_dir("scan-study");
    std::fs::create_dir_all(&out)?;
    let mut sets = settings();
    if args.settings > 0 {
        // Keep the mesh setting last in any case.
        let mesh = sets.pop();
        sets.truncate(args.settings);
        sets.extend(mesh);
    }
    let jobs: Vec<(usize, usize)> = (0..faces.len())
        .flat_map(|f| (0..sets.len()).map(move |s| (f, s)))
        .collect();
    eprintln!(
        "{} faces x {} settings from {}",
        faces.len(),
        sets.len(),
        dir.display()
    );
    let pb = bar(jobs.len(), "scan, clean, describe");
    let scans: Vec<ScanResult> = jobs
        .par_iter()
        .map(|&(f, s)| {
            let status = describe_scan(&faces[f], &sets[s], &args).map_err(|e| format!("{e:#}"));
            pb.inc(1);
            ScanResult {
                face: f,
                setting: s,
                status,
            }
        })
        .collect();
    pb.finish();
    eprintln!("scans described in {:.0} s", t0.elapsed().as_secs_f64());

    // Pairs of usable scans.
    let ok: Vec<(usize, &Described)> = scans
        .iter()
        .enumerate()
        .filter_map(|(i, s)| s.status.as_ref().ok().map(|d| (i, d)))
        .collect();
    let locators: Vec<FaceLocator<'_>> =
        ok.iter().map(|(_, d)| FaceLocator::new(&d.mesh)).collect();
    let all_pairs = args.pairs == "all";
    let idx_pairs: Vec<(usize, usize)> = (0..ok.len())
        .flat_map(|a| (a + 1..ok.len()).map(move |b| (a, b)))
        .filter(|&(a, b)| {
            let (x, y) = (&scans[ok[a].0], &scans[ok[b].0]);
            all_pairs || x.face == y.face || x.setting == y.setting
        })
        .collect();
    let t_pairs = Instant::now();
    let pb = bar(idx_pairs.len(), "distances");
    let pairs: Vec<Pair> = idx_pairs
        .par_iter()
        .map(|&(a, b)| {
            let (ia, da) = ok[a];
            let (ib, db) = ok[b];
            let (fa, fb) = (&faces[scans[ia].face], &faces[scans[ib].face]);
            let rel = if scans[ia].face == scans[ib].face {
                Relation::SameFace
            } else if fa.person == fb.person {
                Relation::SamePerson
            } else {
                Relation::Other
            };
            let icp = 0.5 * (icp_score(da, db, &locators[b]) + icp_score(db, da, &locators[a]));
            let mut d: Vec<f64> = (0..VARIANTS.len())
                .map(|k| variant_distance(da, db, k))
                .collect();
            d.push(view_matched_distance(da, db, &args));
            if args.ref_search_mm > 0.0 {
                d.push(searched_distance(da, db));
            }
            pb.inc(1);
            d.push(dist(&da.polar, &db.polar).unwrap_or(f64::NAN));
            d.push(icp);
            Pair {
                a: ia,
                b: ib,
                rel,
                d,
            }
        })
        .collect();
    pb.finish();
    eprintln!(
        "{} pairs compared in {:.0} s",
        pairs.len(),
        t_pairs.elapsed().as_secs_f64()
    );
    write_outputs(&args, &faces, &sets, &scans, &pairs, &out, t0)?;
    println!("{}", out.display());
    Ok(())
}

fn write_outputs(
    args: &Args,
    faces: &[Face],
    sets: &[Setting],
    scans: &[ScanResult],
    pairs: &[Pair],
    out: &std::path::Path,
    t0: Instant,
) -> Result<()> {
    // Per-scan table (the variant names have commas: `write_csv` quotes them).
    let mut header: Vec<String> = [
        "face",
        "setting",
        "status",
        "vertices",
        "mean_edge_mm",
        "D_mm",
        "lm_offset_r_mm",
        "lm_offset_q_mm",
        "lm_offset_nose_mm",
    ]
    .map(String::from)
    .to_vec();
    for v in &VARIANTS {
        header.extend([
            format!("points {}", v.name),
            format!("ambiguous {}", v.name),
        ]);
    }
    header.extend(["points_polar", "seconds", "notes"].map(String::from));
    let mut rows = Vec::new();
    for s in scans {
        let mut row = vec![faces[s.face].name.clone(), sets[s.setting].name.to_string()];
        match &s.status {
            Ok(d) => {
                row.push("ok".into());
                row.push(d.vertices.to_string());
                row.extend(
                    [
                        d.mean_edge_mm,
                        d.d_mm,
                        d.landmark_offsets_mm[0],
                        d.landmark_offsets_mm[1],
                        d.landmark_offsets_mm[2],
                    ]
                    .map(|x| format!("{x:.4}")),
                );
                for b in &d.bip {
                    row.extend([
                        n_points(b).to_string(),
                        format!("{:.4}", ambiguous_fraction(b)),
                    ]);
                }
                row.extend([
                    d.polar.points.len().to_string(),
                    format!("{:.2}", d.seconds),
                    d.notes.join("; "),
                ]);
            }
            Err(e) => row.push(e.clone()),
        }
        rows.push(row);
    }
    write_csv(
        &out.join("scans.csv"),
        &header.iter().map(String::as_str).collect::<Vec<_>>(),
        &rows,
    )?;
    let mut header: Vec<String> = ["face_a", "setting_a", "face_b", "setting_b", "relation"]
        .map(String::from)
        .to_vec();
    header.extend(methods(args).into_iter().map(String::from));
    let rows: Vec<Vec<String>> = pairs
        .iter()
        .map(|p| {
            let (a, b) = (&scans[p.a], &scans[p.b]);
            let mut row = vec![
                faces[a.face].name.clone(),
                sets[a.setting].name.to_string(),
                faces[b.face].name.clone(),
                sets[b.setting].name.to_string(),
                p.rel.name().to_string(),
            ];
            row.extend(p.d.iter().map(|x| format!("{x:.6}")));
            row
        })
        .collect();
    write_csv(
        &out.join("pairs.csv"),
        &header.iter().map(String::as_str).collect::<Vec<_>>(),
        &rows,
    )?;

    let mut md = String::new();
    let _ = writeln!(md, "# Scan study: the descriptor on range scans\n");
    let _ = writeln!(
        md,
        "{} faces of `{}`, {} acquisitions each: {}. Scans: `rangescan` with the structured-light \
         artifacts (0.1 % spikes, 50 outliers, grazing dropouts 70-80 degrees, 4 holes of 1-4 mm) \
         and the noise, pitch, pose, quantisation and seed of the setting; cleaned by \
         `scanprep::clean` (defaults, crop 100 mm around the projected nose tip). Reference points: \
         the scanner's projected ground-truth landmarks, snapped to the cleaned surface (at most \
         {} mm away, else the scan is listed as unusable). Exact geodesics; static area at N = {} \
         (levels <= N, `facemodel::static_mask`); single pole with {} sectors; ICP of {} \
         static-area points, symmetric mean of the two directions, RMS in mm.\n",
        faces.len(),
        args.set
            .faces
            .as_ref()
            .map_or("paper-set".to_string(), |p| p.display().to_string()),
        sets.len(),
        joined(sets, ", ", |s| s.name.to_string()),
        args.landmark_tolerance_mm,
        args.set.res.levels,
        args.set.res.sectors,
        args.icp_points
    );
    let _ = writeln!(
        md,
        "Pairs compared ({} of them, `--pairs {}`): {}\n",
        pairs.len(),
        args.pairs,
        if args.pairs == "all" {
            "every pair of usable scans."
        } else {
            "every two acquisitions of one face, and every two faces within one setting \
             (pairs of other persons across settings are left out)."
        }
    );
    let failed: Vec<String> = scans
        .iter()
        .filter_map(|s| {
            s.status
                .as_ref()
                .err()
                .map(|e| format!("{} / {}: {e}", faces[s.face].name, sets[s.setting].name))
        })
        .collect();
    let _ = writeln!(
        md,
        "Usable scans: {} of {}.{}\n",
        scans.len() - failed.len(),
        scans.len(),
        if failed.is_empty() {
            String::new()
        } else {
            format!(" Unusable: {}.", failed.join("; "))
        }
    );
    let notes: Vec<String> = scans
        .iter()
        .filter_map(|s| s.status.as_ref().ok().map(|d| (s, d)))
        .flat_map(|(s, d)| {
            d.notes
                .iter()
                .map(move |n| format!("{} / {}: {n}", faces[s.face].name, sets[s.setting].name))
        })
        .collect();
    if !notes.is_empty() {
        let _ = writeln!(md, "Descriptors refused: {}.\n", notes.join("; "));
    }

    // Distances.
    let _ = writeln!(md, "## Distances\n");
    let _ = writeln!(
        md,
        "The ratio min(other person) / max(same face) over all pairs; over the scans only (no face mesh); and over the neutral rescans: same-face pairs of the neutral faces scanned at other pitch, noise or pose (no face mesh, no depth quantisation) against the other persons in those settings.\n"
    );
    let _ = writeln!(
        md,
        "| method | same face: min / median / max (n) | same person | other person | min(other) / max(same face) | scans only | neutral rescans |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    let is_mesh = |p: &Pair| {
        sets[scans[p.a].setting].scan.is_none() || sets[scans[p.b].setting].scan.is_none()
    };
    // The case: two scans of one neutral face at other pitch, noise or pose (no face
    // mesh, no depth quantisation), against the other persons in the same settings.
    let rescan = |p: &Pair| {
        [p.a, p.b].iter().all(|&i| {
            sets[scans[i].setting]
                .scan
                .is_some_and(|s| s.quant_mm.is_none())
        }) && (p.rel != Relation::SameFace || faces[scans[p.a].face].expression == "neutral")
    };
    let mut ratios = Vec::new();
    for (m, name) in methods(args).iter().enumerate() {
        let subset = |rel: Relation, keep: &dyn Fn(&Pair) -> bool| -> Vec<f64> {
            pairs
                .iter()
                .filter(|p| p.rel == rel && keep(p))
                .map(|p| p.d[m])
                .collect()
        };
        let of = |rel: Relation, scans_only: bool| -> Vec<f64> {
            subset(rel, &|p| !(scans_only && is_mesh(p)))
        };
        let fmt = |v: &[f64]| {
            let (lo, med, hi, n) = quantiles(v);
            format!("{lo:.4} / {med:.4} / {hi:.4} ({n})")
        };
        let ratio = |scans_only: bool| {
            let (_, _, same_max, _) = quantiles(&of(Relation::SameFace, scans_only));
            let (other_min, _, _, _) = quantiles(&of(Relation::Other, scans_only));
            other_min / same_max
        };
        let (r_all, r_scans) = (ratio(false), ratio(true));
        let r_rescans = {
            let (_, _, same_max, _) = quantiles(&subset(Relation::SameFace, &rescan));
            let (other_min, _, _, _) = quantiles(&subset(Relation::Other, &rescan));
            other_min / same_max
        };
        ratios.push((name.to_string(), r_all, r_scans, r_rescans));
        let _ = writeln!(
            md,
            "| {name} | {} | {} | {} | **{r_all:.3}** | {r_scans:.3} | {r_rescans:.3} |",
            fmt(&of(Relation::SameFace, false)),
            fmt(&of(Relation::SamePerson, false)),
            fmt(&of(Relation::Other, false)),
        );
        let series: Vec<(String, Vec<f64>)> =
            [Relation::SameFace, Relation::SamePerson, Relation::Other]
                .iter()
                .map(|&r| (r.name().to_string(), of(r, false)))
                .filter(|(_, v)| v.iter().any(|x| x.is_finite()))
                .collect();
        if !series.is_empty() {
            let file = format!(
                "hist_{}.svg",
                name.replace([' ', '(', ')'], "_")
                    .replace("__", "_")
                    .trim_end_matches('_')
            );
            viz::histogram(
                out.join(&file),
                &format!("{name}: distances between scans"),
                "distance",
                &series,
                40,
            )
            .with_context(|| format!("histogram {file}"))?;
        }
    }
    let _ = writeln!(
        md,
        "\nRatio above 1: every two scans of one face are closer than any two persons (\"scans \
         only\" leaves out the pairs with the mesh itself). Histograms: `hist_*.svg`. All pairs: \
         `pairs.csv`.\n"
    );

    // Same-face distance by setting pair against the reference setting.
    let _ = writeln!(
        md,
        "## Same face: each setting against the first, median over faces\n"
    );
    let _ = writeln!(md, "| setting | {} |", methods(args).join(" | "));
    let _ = writeln!(md, "|---|{}", "---|".repeat(methods(args).len()));
    for (si, s) in sets.iter().enumerate().skip(1) {
        let row: Vec<String> = (0..methods(args).len())
            .map(|m| {
                let v: Vec<f64> = pairs
                    .iter()
                    .filter(|p| {
                        p.rel == Relation::SameFace && {
                            let (x, y) = (scans[p.a].setting, scans[p.b].setting);
                            (x == 0 && y == si) || (x == si && y == 0)
                        }
                    })
                    .map(|p| p.d[m])
                    .collect();
                format!("{:.4}", quantiles(&v).1)
            })
            .collect();
        let _ = writeln!(
            md,
            "| {} vs {} | {} |",
            s.name,
            sets[0].name,
            row.join(" | ")
        );
    }

    // Ambiguity per setting.
    let _ = writeln!(md, "\n## Ambiguous keys per setting\n");
    let _ = writeln!(
        md,
        "Fraction of descriptor points whose key occurs at two places on the scan (never paired), \
         median and max over the faces; points per descriptor (median).\n"
    );
    let _ = writeln!(
        md,
        "| setting | mean edge mm | {} | polar points |",
        joined(&VARIANTS, " | ", |v| format!(
            "{}: ambiguous median / max (points)",
            v.name
        ))
    );
    let _ = writeln!(md, "|---|---|{}---|", "---|".repeat(VARIANTS.len()));
    let mut header = vec!["setting".to_string()];
    for v in &VARIANTS {
        header.extend([
            format!("ambiguous median {}", v.name),
            format!("ambiguous max {}", v.name),
        ]);
    }
    let mut rows = Vec::new();
    for (si, s) in sets.iter().enumerate() {
        let ds: Vec<&Described> = scans
            .iter()
            .filter(|x| x.setting == si)
            .filter_map(|x| x.status.as_ref().ok())
            .collect();
        let col = |f: &dyn Fn(&Described) -> f64| -> Vec<f64> { ds.iter().map(|d| f(d)).collect() };
        let (_, edge, _, _) = quantiles(&col(&|d| d.mean_edge_mm));
        let (_, pp, _, _) = quantiles(&col(&|d| d.polar.points.len() as f64));
        let mut cells = Vec::new();
        let mut row = vec![s.name.to_string()];
        for k in 0..VARIANTS.len() {
            let (_, med, max, _) = quantiles(&col(&|d| ambiguous_fraction(&d.bip[k])));
            let (_, pts, _, _) = quantiles(&col(&|d| n_points(&d.bip[k]) as f64));
            cells.push(format!(
                "{:.1} % / {:.1} % ({pts:.0})",
                100.0 * med,
                100.0 * max
            ));
            row.extend([format!("{med:.4}"), format!("{max:.4}")]);
        }
        rows.push(row);
        let _ = writeln!(
            md,
            "| {} | {edge:.2} | {} | {pp:.0} |",
            s.name,
            cells.join(" | ")
        );
    }
    write_csv(
        &out.join("ambiguity.csv"),
        &header.iter().map(String::as_str).collect::<Vec<_>>(),
        &rows,
    )?;
    let rows: Vec<Vec<String>> = ratios
        .iter()
        .map(|(n, a, s, r)| {
            vec![
                n.to_string(),
                format!("{a:.4}"),
                format!("{s:.4}"),
                format!("{r:.4}"),
            ]
        })
        .collect();
    write_csv(
        &out.join("ratios.csv"),
        &[
            "method",
            "ratio_all_pairs",
            "ratio_scans_only",
            "ratio_neutral_rescans",
        ],
        &rows,
    )?;
    let _ = writeln!(
        md,
        "\nRun time: {:.0} s wall (release, 2 cores shared). Per-scan details: `scans.csv`.",
        t0.elapsed().as_secs_f64()
    );
    std::fs::write(out.join("report.md"), md)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_view_matched_variant_is_the_least_of_the_three_pairs() {
        let v = &VARIANTS[LEAST];
        assert!(matches!(v.side_pairs, Some(PairCombine::Least)));
        assert_eq!(v.max_incidence_deg, Some(60.0));
        assert!(VIEW_MATCHED.starts_with(v.name));
        assert!(SEARCHED.starts_with(v.name));
        let mut args = study_args(0.0);
        let m = methods(&args);
        assert_eq!(m.len(), VARIANTS.len() + 3);
        assert_eq!(m[VARIANTS.len()], VIEW_MATCHED);
        args.ref_search_mm = 2.0;
        let m = methods(&args);
        assert_eq!(m.len(), VARIANTS.len() + 4);
        assert_eq!(m[VARIANTS.len() + 1], SEARCHED);
    }

    fn study_args(ref_search_mm: f64) -> Args {
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            args: Args,
        }
        let mut args = <Cli as clap::Parser>::parse_from(["scan-study"]).args;
        args.ref_search_mm = ref_search_mm;
        args
    }

    #[test]
    fn the_search_finds_a_pole_moved_by_its_radius() {
        // A curved, asymmetric height field in mm on a 1 mm grid (on a plane every placement
        // gives the same scale-free descriptor); the right outer corner of `b` placed on the
        // grid vertex 2 mm toward the left one and the left corner 2 mm toward the right one
        // (so that every pair differs), where the search's first directions put candidates of
        // `a`'s.
        let z = |x: f64, y: f64| 0.006 * x * x + 0.002 * x * y + 0.004 * y * y + 5e-5 * x * x * x;
        let mesh =
            meshcore::shapes::grid(120, 100, meshcore::shapes::Diagonals::Uniform, |i, j| {
                let (x, y) = (i as f64 - 60.0, j as f64 - 50.0);
                DVec3::new(x, y, z(x, y))
            })
            .unwrap();
        let at = |x: f64, y: f64| DVec3::new(x, y, z(x, y));
        let lms = [at(-40.0, 10.0), at(40.0, 10.0), at(0.0, -25.0)];
        let mut moved = lms;
        moved[0] = at(-38.0, 10.0);
        moved[1] = at(38.0, 10.0);
        let args = study_args(2.0);
        let a = describe_mesh(mesh.clone(), &lms, &[], &args, None).unwrap();
        let b = describe_mesh(mesh, &moved, &[], &args, None).unwrap();
        assert!(
            a.searched.iter().all(|s| s.len() > 20),
            "{:?}",
            a.searched.each_ref().map(Vec::len)
        );
        let least = variant_distance(&a, &b, LEAST);
        let searched = searched_distance(&a, &b);
        assert!(least > 0.005, "{least}");
        // The candidates land on the moved corners: the same descriptor, found exactly.
        assert!(searched < 1e-6 * least, "{searched} against {least}");
        assert_eq!(searched_distance(&a, &b), searched_distance(&b, &a));
        // Without the search the scans have no moved descriptors and the two distances agree.
        let args = study_args(0.0);
        let mesh = a.mesh.clone();
        let (a0, b0) = (
            describe_mesh(mesh.clone(), &lms, &[], &args, None).unwrap(),
            describe_mesh(mesh, &moved, &[], &args, None).unwrap(),
        );
        assert!(a0.searched.iter().all(Vec::is_empty));
        assert_eq!(
            searched_distance(&a0, &b0),
            variant_distance(&a0, &b0, LEAST)
        );
    }
}
