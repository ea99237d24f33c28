//! The descriptions of one acquired scan: the study's bipolar variants on the snapped
//! landmarks' fields, the three pole pairs by `facematch` (with the reference-point search when
//! asked), the single pole and the ICP probe points.

use super::acquisition::{acquire, snap, Setting};
use super::variants::{LEAST, VARIANTS};
use super::Args;
use crate::pipeline::{kept_vertices, Area, PoleRefs};
use crate::polar::{polar_descriptor, PolarOptions, Pole};
use anyhow::{bail, Result};
use facemodel::Face;
use geodesic::{GeodesicSolver, Method, SolveOptions, Source};
use meshcore::{DVec3, FaceLocator, SurfacePoint, TriMesh};
use std::time::Instant;

/// Everything described on one scan.
pub(super) struct Described {
    pub(super) vertices: usize,
    pub(super) mean_edge_mm: f64,
    pub(super) d_mm: f64,
    pub(super) landmark_offsets_mm: [f64; 3],
    /// One descriptor per entry of [`VARIANTS`] (`None`: refused, the reason in `notes`). A
    /// variant described like an earlier one holds that one's descriptor: the three-pole-pair
    /// variants hold the corners' descriptor of the same options on the snapped landmarks (its
    /// points and ambiguous keys are what `scans.csv` and `ambiguity.csv` give for them; their
    /// distances come from [`Described::matched`]).
    pub(super) bip: Vec<Option<bipolar::Descriptor>>,
    /// The three pole pairs as `facematch` describes them, or why they could not be.
    pub(super) matched: Result<Matched, String>,
    pub(super) polar: bipolar::PolarDescriptor,
    pub(super) notes: Vec<String>,
    pub(super) icp_probe: Vec<DVec3>,
    /// The snapped landmarks (r, q, nose tip).
    pub(super) landmarks: [DVec3; 3],
    pub(super) mesh: TriMesh,
    pub(super) seconds: f64,
}

/// A scan described by `facematch` ([`facematch::describe_with_fields`] with
/// [`super::matching`]'s options): what the [`LEAST`] variant, its view-matched and its
/// searched distances compare.
pub(super) struct Matched {
    /// The landmarks at the vertices nearest their snapped places.
    pub(super) poles: facematch::Poles,
    /// The scan as a template: its three pairs' descriptors without the search (views are
    /// added per comparison, from the other scan's direction).
    pub(super) template: facematch::Template,
    /// The scan as a probe with the reference-point search (`None` without `--ref-search-mm`:
    /// the template's description is the probe).
    pub(super) searched: Option<facematch::Description>,
}

/// Acquires `face` by `setting` and describes it ([`describe_mesh`]).
pub(super) fn describe_scan(face: &Face, setting: &Setting, args: &Args) -> Result<Described> {
    let t0 = Instant::now();
    let (mesh, lms, hidden) = acquire(face, setting, args.smooth)?;
    let mut d = describe_mesh(mesh, &lms, &hidden, args)?;
    d.seconds = t0.elapsed().as_secs_f64();
    Ok(d)
}

/// The references of the snapped landmarks `sp` at `pos` (the outer eye corners' fields, D,
/// the frame) and the nose tip's field. The static area lies within D of both corners and
/// the polar rays reach D from the nose tip; D is about 1.2 times the straight distance between
/// the corners. The fields are cut off past that (values within the cut are exact); a cut that
/// turns out too short is an error, never a silently smaller region.
fn landmark_fields(
    mesh: &TriMesh,
    solver: &dyn GeodesicSolver,
    sp: &[SurfacePoint; 3],
    pos: &[DVec3; 3],
) -> Result<(PoleRefs, Vec<f64>)> {
    let max_edge = mesh.longest_edge();
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
    let d = 0.5 * (mesh.interpolate(&ur, &sp[1])? + mesh.interpolate(&uq, &sp[0])?);
    if !(d.is_finite() && d > 0.0) {
        bail!("the corners are not connected within the cut-off {cut:.1} mm (D = {d})");
    }
    if d + 2.0 * max_edge > cut {
        bail!("D = {d:.1} mm exceeds the fields' cut-off {cut:.1} mm");
    }
    Ok((PoleRefs::new(mesh, [ur, uq], d, *pos), un))
}

/// The descriptions of an acquired mesh (mm) with landmarks `lms` (r, q, nose; `hidden`: those
/// the scanner did not see, for the notes).
pub(super) fn describe_mesh(
    mesh: TriMesh,
    lms: &[DVec3; 3],
    hidden: &[String],
    args: &Args,
) -> Result<Described> {
    let t0 = Instant::now();
    let loc = FaceLocator::new(&mesh);
    let (sp, off) = snap(&loc, lms, args.landmark_tolerance_mm)?;
    let pos = sp.map(|s| mesh.point_position(&s).unwrap_or(DVec3::NAN));
    let solver = geodesic::new_solver(&mesh, Method::Exact)?;
    let (refs, un) = landmark_fields(&mesh, solver.as_ref(), &sp, &pos)?;
    let mut notes: Vec<String> = hidden
        .iter()
        .map(|h| format!("landmark {h}, snapped to the cleaned surface"))
        .collect();
    let surface = bipolar::Surface::new(mesh.clone());
    let bip = variant_descriptors(&surface, &refs, args, &mut notes);
    let matched = matched_description(&surface, solver.as_ref(), &sp, args);
    if let Err(e) = &matched {
        notes.push(format!("{}: {e}", VARIANTS[LEAST].name));
    }
    let polar_opts = PolarOptions {
        step: refs.d / f64::from(args.set.res.levels),
        levels: args.set.res.levels,
        sectors: args.set.res.sectors,
    };
    let polar = polar_descriptor(
        &geodesic::straightest::Walker::new(&mesh),
        &un,
        Pole::Point(sp[2]),
        0.5 * (pos[0] + pos[1]),
        &polar_opts,
    )?;
    let mask = refs.static_area(&mesh);
    let inside: Vec<DVec3> = (0..mesh.n_vertices())
        .filter(|&v| mask[v])
        .map(|v| mesh.position(v as u32))
        .collect();
    let stride = (inside.len() / args.icp_points.max(3)).max(1);
    let icp_probe = inside.iter().step_by(stride).copied().collect();
    Ok(Described {
        vertices: mesh.n_vertices(),
        mean_edge_mm: mesh.mean_edge_length(),
        d_mm: refs.d,
        landmark_offsets_mm: off,
        bip,
        matched,
        polar,
        notes,
        icp_probe,
        landmarks: pos,
        seconds: t0.elapsed().as_secs_f64(),
        mesh,
    })
}

/// The vertices variant `k` describes (`None`: all): those seen within its incidence limit from
/// the scanner and outside its band along the boundary (built once per margin, in `bands`).
fn variant_mask(
    surface: &bipolar::Surface,
    k: usize,
    bands: &mut Vec<(f64, Result<Vec<bool>, String>)>,
) -> Result<Option<Vec<bool>>, String> {
    let v = &VARIANTS[k];
    let mesh = surface.mesh();
    let seen = v
        .max_incidence_deg
        .map(|deg| facematch::seen_within(mesh, crate::scans::SCANNER_SIDE, None, deg))
        .transpose()
        .map_err(|e| format!("{}: {e}", v.name))?;
    let Some(m) = v.margin_mm else {
        return Ok(seen);
    };
    let i = bands.iter().position(|(b, _)| *b == m).unwrap_or_else(|| {
        let kept = match kept_vertices(surface, None, None, Some(m)) {
            Ok(Some(kept)) => Ok(kept),
            Ok(None) => Err("no band mask".to_string()),
            Err(e) => Err(e.to_string()),
        };
        bands.push((m, kept));
        bands.len() - 1
    });
    match &bands[i].1 {
        Ok(band) => Ok(Some(match seen {
            Some(s) => s.iter().zip(band).map(|(&s, &b)| s && b).collect(),
            None => band.clone(),
        })),
        Err(e) => Err(format!("{}: {e}", v.name)),
    }
}

/// The corners' descriptor of each entry of [`VARIANTS`] on the snapped landmarks' references
/// `refs` (static area, the variant's rule and vertex mask; the band along the holes built once per
/// margin and left out through the vertex mask, `pipeline::kept_vertices`). A variant described
/// like an earlier one (another distance rule over the same descriptors) takes that one's
/// descriptor. Refusals are `None`, their reasons pushed on `notes`.
fn variant_descriptors(
    surface: &bipolar::Surface,
    refs: &PoleRefs,
    args: &Args,
    notes: &mut Vec<String>,
) -> Vec<Option<bipolar::Descriptor>> {
    let levels = args.set.res.levels;
    let mut bip: Vec<Option<bipolar::Descriptor>> = Vec::new();
    let mut bands = Vec::new();
    for (k, v) in VARIANTS.iter().enumerate() {
        if let Some(j) = (0..k).find(|&j| VARIANTS[j].same_description(v)) {
            bip.push(bip[j].clone());
            continue;
        }
        let seen = match variant_mask(surface, k, &mut bands) {
            Ok(seen) => seen,
            Err(e) => {
                notes.push(e);
                bip.push(None);
                continue;
            }
        };
        match refs.descriptor(surface, levels, Area::Static, seen.as_deref(), v.options()) {
            Ok(d) => bip.push(Some(d)),
            Err(e) => {
                notes.push(format!("{}: {e}", v.name));
                bip.push(None);
            }
        }
    }
    bip
}

/// The scan described by `facematch` ([`Matched`]): the snapped landmarks at their faces'
/// nearest corners, their fields ([`facematch::face_fields`]) and the three pole pairs
/// ([`facematch::describe_with_fields`], the scanner along +z); with `--ref-search-mm` also the
/// search's moved descriptors (the probe; the template leaves them out).
fn matched_description(
    surface: &bipolar::Surface,
    solver: &dyn GeodesicSolver,
    sp: &[SurfacePoint; 3],
    args: &Args,
) -> Result<Matched, String> {
    let mesh = surface.mesh();
    let v = sp
        .iter()
        .map(|s| mesh.nearest_corner(s).map_err(|e| e.to_string()))
        .collect::<Result<Vec<u32>, String>>()?;
    let poles = facematch::Poles::new(v[0], v[1], v[2]);
    let o = super::matching(args);
    let f = facematch::face_fields(mesh, solver, poles, o.field_cutoff)?;
    let describe = |search: bool| {
        let side = crate::scans::SCANNER_SIDE;
        facematch::describe_with_fields(surface, solver, &f, poles, side, None, &o, search)
            .map_err(|e| e.to_string())
    };
    let searched = describe(o.search.is_some())?;
    // The template is the probe without the search's moved descriptors.
    let own = facematch::Description {
        moved: Default::default(),
        moved_failed: [0; 3],
        ..searched.clone()
    };
    let searched = o.search.is_some().then_some(searched);
    let template = facematch::Template {
        identity: String::new(),
        source: String::new(),
        settings: o.template_settings(),
        description: own,
        views: Vec::new(),
        notes: Vec::new(),
    };
    Ok(Matched {
        poles,
        template,
        searched,
    })
}
