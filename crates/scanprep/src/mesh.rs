//! Steps on a triangle mesh (mm): spikes, small components, hole filling, cropping, smoothing.

use crate::{Hole, ScanPrepError};
use meshcore::{DVec3, Topology, TriMesh, VertexAdjacency};

/// Rebuilds a mesh from positions and the triangles kept, dropping the vertices no triangle
/// uses (the others keep their order). Returns the mesh and, per old vertex, its new index
/// (`u32::MAX` if dropped). An error when no triangle is left.
pub fn compact(
    pos: &[DVec3],
    tris: Vec<[u32; 3]>,
    what: &str,
) -> Result<(TriMesh, Vec<u32>), ScanPrepError> {
    if tris.is_empty() {
        return Err(ScanPrepError::NothingLeft(what.to_string()));
    }
    let mut used = vec![false; pos.len()];
    for t in &tris {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut map = vec![u32::MAX; pos.len()];
    let mut out = Vec::new();
    for (v, &u) in used.iter().enumerate() {
        if u {
            map[v] = out.len() as u32;
            out.push(pos[v]);
        }
    }
    let tris = tris.iter().map(|t| t.map(|v| map[v as usize])).collect();
    Ok((TriMesh::new(out, tris)?, map))
}

/// Removes the connected components with fewer than `min_ratio` times the vertices of the
/// largest one (`min_ratio = 1` keeps the largest alone, plus any as large; ties are kept).
/// Returns the mesh, the number of components and of vertices removed.
pub fn remove_small_components(
    mesh: &TriMesh,
    min_ratio: f64,
) -> Result<(TriMesh, usize, usize), ScanPrepError> {
    if !(min_ratio.is_finite() && (0.0..=1.0).contains(&min_ratio)) {
        return Err(ScanPrepError::InvalidOption(format!(
            "min component ratio {min_ratio} (expected 0 to 1)"
        )));
    }
    let topo = Topology::new(mesh);
    let comps = topo.components();
    let largest = comps.iter().map(Vec::len).max().unwrap_or(0);
    let keep_comp: Vec<bool> = comps
        .iter()
        .map(|c| c.len() as f64 >= min_ratio * largest as f64)
        .collect();
    let removed_c = keep_comp.iter().filter(|&&k| !k).count();
    if removed_c == 0 {
        return Ok((mesh.clone(), 0, 0));
    }
    let removed_v: usize = comps
        .iter()
        .zip(&keep_comp)
        .filter(|(_, &k)| !k)
        .map(|(c, _)| c.len())
        .sum();
    let tris = mesh
        .triangles()
        .iter()
        .filter(|t| keep_comp[topo.vertex_component()[t[0] as usize] as usize])
        .copied()
        .collect();
    let (m, _) = compact(mesh.positions(), tris, "removing small components")?;
    Ok((m, removed_c, removed_v))
}

/// Vertices on a boundary edge (an edge with exactly one face) or a non-manifold one.
pub(crate) fn boundary_vertices(mesh: &TriMesh, topo: &Topology) -> Vec<bool> {
    let mut b = vec![false; mesh.n_vertices()];
    for e in topo.edges() {
        if e.n_faces != 2 {
            b[e.v[0] as usize] = true;
            b[e.v[1] as usize] = true;
        }
    }
    b
}

/// Removes spike vertices of a mesh (with their faces): a vertex is a spike when its distance
/// to the mean of its neighbours exceeds `factor` times the mean length of the edges among
/// those neighbours (the ring around it). On a smooth surface that distance is about `h^2 k`
/// (edge length `h`, curvature `k`), and half an edge at a boundary; a spike sticks out by
/// its height. Decisions are taken on the input mesh. Returns the mesh and the count removed.
pub fn remove_mesh_spikes(mesh: &TriMesh, factor: f64) -> Result<(TriMesh, usize), ScanPrepError> {
    if !(factor.is_finite() && factor > 0.0) {
        return Err(ScanPrepError::InvalidOption(format!(
            "mesh spike factor {factor} (expected > 0)"
        )));
    }
    let p = mesh.positions();
    let nb = VertexAdjacency::new(mesh);
    let mut spike = vec![false; p.len()];
    for (v, l) in nb.iter().enumerate() {
        if l.len() < 3 {
            continue;
        }
        let mean = l.iter().map(|&w| p[w as usize]).sum::<DVec3>() / l.len() as f64;
        // Mean length of the ring edges: edges between two neighbours of v.
        let (mut sum, mut cnt) = (0.0, 0usize);
        for &a in l {
            for &b in nb.neighbours(a) {
                if b > a && l.binary_search(&b).is_ok() {
                    sum += (p[a as usize] - p[b as usize]).length();
                    cnt += 1;
                }
            }
        }
        if cnt == 0 {
            continue;
        }
        if (p[v] - mean).length() > factor * sum / cnt as f64 {
            spike[v] = true;
        }
    }
    let n = spike.iter().filter(|&&s| s).count();
    if n == 0 {
        return Ok((mesh.clone(), 0));
    }
    let tris = mesh
        .triangles()
        .iter()
        .filter(|t| t.iter().all(|&v| !spike[v as usize]))
        .copied()
        .collect();
    let (m, _) = compact(p, tris, "removing mesh spikes")?;
    Ok((m, n))
}

/// A hole's boundary loop (vertex ids, in its faces' winding) and its record.
type LoopHole = (Vec<u32>, Hole);

/// The topology of a mesh and its holes: the boundary loops other than the outer boundary of
/// each component (the loop of largest perimeter in it; a closed component has none), each with
/// its [`Hole`] record (`filled` false). The diameter of a loop is the largest distance between
/// two of its vertices. An error when `max_diameter_mm`, the size of the holes to close, is not
/// a finite value >= 0.
fn holes(mesh: &TriMesh, max_diameter_mm: f64) -> Result<(Topology, Vec<LoopHole>), ScanPrepError> {
    if !(max_diameter_mm.is_finite() && max_diameter_mm >= 0.0) {
        return Err(ScanPrepError::InvalidOption(format!(
            "max hole diameter {max_diameter_mm} mm (expected a finite value >= 0)"
        )));
    }
    let topo = Topology::new(mesh);
    let p = mesh.positions();
    // Outer loop per component: the longest perimeter (ties to the first listed).
    let mut outer: std::collections::BTreeMap<u32, (f64, usize)> = Default::default();
    for (k, l) in topo.boundary_loops().iter().enumerate() {
        let Some(&v0) = l.first() else { continue };
        let c = topo.vertex_component()[v0 as usize];
        let per = mesh.ring_length(l);
        let e = outer.entry(c).or_insert((per, k));
        if per > e.0 {
            *e = (per, k);
        }
    }
    let outer_ids: std::collections::BTreeSet<usize> = outer.values().map(|&(_, k)| k).collect();
    let mut out = Vec::new();
    for (k, l) in topo.boundary_loops().iter().enumerate() {
        if outer_ids.contains(&k) || l.len() < 3 {
            continue;
        }
        let pts: Vec<DVec3> = l.iter().map(|&v| p[v as usize]).collect();
        let diameter_mm = if pts.len() <= 4000 {
            let mut d = 0.0f64;
            for i in 0..pts.len() {
                for j in i + 1..pts.len() {
                    d = d.max((pts[i] - pts[j]).length());
                }
            }
            d
        } else {
            meshcore::Aabb::from_points(&pts).map_or(0.0, |b| b.diagonal())
        };
        let centre = pts.iter().sum::<DVec3>() / pts.len() as f64;
        out.push((
            l.clone(),
            Hole {
                size: l.len(),
                diameter_mm,
                centre,
                filled: false,
            },
        ));
    }
    Ok((topo, out))
}

/// Fills the holes of a mesh up to `max_diameter_mm` and reports every hole.
///
/// Holes are the boundary loops other than the outer boundary of each component (the loop of
/// largest perimeter in it; a closed component has none). The diameter of a loop is the largest
/// distance between two of its vertices. A hole is closed by a fan around a new vertex at the
/// mean of the loop's vertices; on a curved surface that vertex lies off the surface by about
/// `d^2 / (8 R)` (diameter `d`, radius of curvature `R`), which the optional smoothing evens out.
pub fn fill_mesh_holes(
    mesh: &TriMesh,
    max_diameter_mm: f64,
) -> Result<(TriMesh, Vec<Hole>), ScanPrepError> {
    let (_, loops) = holes(mesh, max_diameter_mm)?;
    let mut pos = mesh.positions().to_vec();
    let mut tris = mesh.triangles().to_vec();
    let mut found = Vec::new();
    for (l, mut hole) in loops {
        if hole.diameter_mm <= max_diameter_mm {
            let c = pos.len() as u32;
            pos.push(hole.centre);
            // The loop follows its faces' winding; the fan runs the other way along each edge.
            for i in 0..l.len() {
                let (a, b) = (l[i], l[(i + 1) % l.len()]);
                tris.push([b, a, c]);
            }
            hole.filled = true;
        }
        found.push(hole);
    }
    if found.iter().all(|h| !h.filled) {
        return Ok((mesh.clone(), found));
    }
    Ok((TriMesh::new(pos, tris)?, found))
}

/// Closes the small holes of a mesh *without new vertices*: each hole up to `max_diameter_mm`
/// (holes as in [`fill_mesh_holes`]) is split into simple cycles where its loop passes a vertex
/// twice (a bow-tie), and each cycle is triangulated from its own vertices by clipping, again
/// and again, the ear whose new edge is the shortest. Every hole is reported; one is left open
/// (`filled` false) when it is larger, or when some ear cannot be cut without an edge the mesh
/// already has (which would make it non-manifold).
///
/// This is what a range grid's triangulation needs after its long-edge rule: with depth noise,
/// two neighbouring samples can differ by more than the rule allows, and the cells around them
/// are dropped although no sample is missing. Closing the gap re-forms those cells from the
/// samples that are there, so vertices (and a grid index) are unchanged.
pub fn close_mesh_gaps(
    mesh: &TriMesh,
    max_diameter_mm: f64,
) -> Result<(TriMesh, Vec<Hole>), ScanPrepError> {
    let (topo, loops) = holes(mesh, max_diameter_mm)?;
    let p = mesh.positions();
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    // The edges a new edge could coincide with: those around the vertices of the holes to close.
    let mut edges: std::collections::HashSet<(u32, u32)> = Default::default();
    for (l, hole) in &loops {
        if hole.diameter_mm <= max_diameter_mm {
            for &v in l {
                for &f in topo.vertex_faces(v) {
                    let t = mesh.triangles()[f as usize];
                    edges.extend([key(t[0], t[1]), key(t[1], t[2]), key(t[2], t[0])]);
                }
            }
        }
    }
    let mut tris = mesh.triangles().to_vec();
    let mut found = Vec::new();
    for (l, mut hole) in loops {
        if hole.diameter_mm <= max_diameter_mm {
            // A loop through a bow-tie vertex visits it twice: each simple cycle is its own
            // polygon.
            let mut new_tris = Vec::new();
            let mut new_edges = Vec::new();
            let cycles = simple_cycles(&l);
            let closed = !cycles.is_empty()
                && cycles
                    .into_iter()
                    .all(|ring| clip_ears(ring, p, &mut edges, &mut new_edges, &mut new_tris, key));
            if closed {
                tris.extend(new_tris);
                hole.filled = true;
            } else {
                for e in new_edges {
                    edges.remove(&e);
                }
            }
        }
        found.push(hole);
    }
    if found.iter().all(|h| !h.filled) {
        return Ok((mesh.clone(), found));
    }
    Ok((TriMesh::new(p.to_vec(), tris)?, found))
}

/// The simple cycles of a closed vertex walk, in its order: where a vertex comes back, the part
/// of the walk since its first visit is cut off as a cycle. Cycles of fewer than 3 vertices
/// (an edge walked both ways) are dropped.
fn simple_cycles(walk: &[u32]) -> Vec<Vec<u32>> {
    let mut cycles = Vec::new();
    let mut stack: Vec<u32> = Vec::new();
    for &v in walk {
        if let Some(i) = stack.iter().position(|&u| u == v) {
            let mut cycle = vec![v];
            cycle.extend(stack.split_off(i + 1));
            cycles.push(cycle);
        } else {
            stack.push(v);
        }
    }
    cycles.push(stack);
    cycles.retain(|c| c.len() >= 3);
    cycles
}

/// Triangulates the simple polygon `ring` (in its faces' winding) by clipping, again and again,
/// the ear whose new edge is the shortest, never one whose new edge is in `edges`. Appends the
/// triangles (running the other way along the ring) to `tris` and the new edges to `edges` and
/// `added`; false when some ear could not be cut.
fn clip_ears(
    mut ring: Vec<u32>,
    p: &[DVec3],
    edges: &mut std::collections::HashSet<(u32, u32)>,
    added: &mut Vec<(u32, u32)>,
    tris: &mut Vec<[u32; 3]>,
    key: impl Fn(u32, u32) -> (u32, u32),
) -> bool {
    while ring.len() > 3 {
        let n = ring.len();
        let ear = |i: usize| (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
        let best = (0..n)
            .filter(|&i| {
                !edges.contains(&{
                    let (a, _, c) = ear(i);
                    key(a, c)
                })
            })
            .map(|i| {
                let (a, _, c) = ear(i);
                (p[a as usize].distance(p[c as usize]), i)
            })
            .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        let Some((_, i)) = best else { return false };
        let (a, b, c) = ear(i);
        tris.push([c, b, a]);
        edges.insert(key(a, c));
        added.push(key(a, c));
        ring.remove(i);
    }
    tris.push([ring[2], ring[1], ring[0]]);
    true
}

/// For each vertex of `after`, a mesh made from `before` by steps that only drop vertices
/// and keep the rest in order ([`crop_sphere`], [`remove_small_components`]), its index in
/// `before` (positions matched bit for bit); `None` when `after` is not such a subset.
pub fn surviving_vertices(before: &TriMesh, after: &TriMesh) -> Option<Vec<u32>> {
    let mut out = Vec::with_capacity(after.n_vertices());
    let mut k = 0usize;
    for p in after.positions() {
        while k < before.n_vertices() && before.positions()[k] != *p {
            k += 1;
        }
        if k == before.n_vertices() {
            return None;
        }
        out.push(k as u32);
        k += 1;
    }
    Some(out)
}

/// Keeps the faces whose three vertices lie within `radius` of `centre` (then drops unused
/// vertices). Returns the mesh and the number of vertices removed; an error when nothing is
/// left or the centre or radius is not finite.
pub fn crop_sphere(
    mesh: &TriMesh,
    centre: DVec3,
    radius: f64,
) -> Result<(TriMesh, usize), ScanPrepError> {
    if !(centre.is_finite() && radius.is_finite() && radius > 0.0) {
        return Err(ScanPrepError::InvalidOption(format!(
            "crop sphere centre {:?}, radius {radius} (expected finite, radius > 0)",
            centre.to_array()
        )));
    }
    let p = mesh.positions();
    let r2 = radius * radius;
    let inside: Vec<bool> = p.iter().map(|q| q.distance_squared(centre) <= r2).collect();
    let tris: Vec<[u32; 3]> = mesh
        .triangles()
        .iter()
        .filter(|t| t.iter().all(|&v| inside[v as usize]))
        .copied()
        .collect();
    let (m, _) = compact(
        p,
        tris,
        &format!(
            "cropping to {radius} mm around ({:.3}, {:.3}, {:.3}): no face inside the sphere",
            centre.x, centre.y, centre.z
        ),
    )?;
    let removed = mesh.n_vertices() - m.n_vertices();
    Ok((m, removed))
}

/// Taubin's λ|μ smoothing (λ = 0.5, μ = -0.53, uniform weights), `iterations` pairs of steps;
/// boundary and non-manifold vertices stay fixed. Removes noise with little shrinkage.
pub fn taubin_smooth(mesh: &TriMesh, iterations: usize) -> Result<TriMesh, ScanPrepError> {
    const LAMBDA: f64 = 0.5;
    const MU: f64 = -0.53;
    if iterations == 0 {
        return Ok(mesh.clone());
    }
    let topo = Topology::new(mesh);
    let fixed = boundary_vertices(mesh, &topo);
    let nb = VertexAdjacency::new(mesh);
    let mut p = mesh.positions().to_vec();
    let mut next = p.clone();
    for _ in 0..iterations {
        for f in [LAMBDA, MU] {
            for (v, l) in nb.iter().enumerate() {
                if fixed[v] || l.is_empty() {
                    next[v] = p[v];
                    continue;
                }
                let mean = l.iter().map(|&w| p[w as usize]).sum::<DVec3>() / l.len() as f64;
                next[v] = p[v] + f * (mean - p[v]);
            }
            std::mem::swap(&mut p, &mut next);
        }
    }
    Ok(TriMesh::new(p, mesh.triangles().to_vec())?)
}

/// The vertices a scanner saw at an incidence of at most `max_incidence_deg`: those whose normal
/// makes at most that angle with `toward_scanner`, the direction from the surface to the
/// scanner (+z for a range grid in the scanner's frame, as `.bnt` files and `rangescan` give
/// them). Beyond about 60 degrees a scanner's depth noise runs nearly along the surface and its
/// samples thin out, so what lies there is measured least well; leaving it out of a descriptor
/// is the choice this mask offers. Normals are area-weighted and averaged twice over each
/// vertex's one-ring, so that depth noise does not tip single vertices across the limit.
/// An error when the direction is zero or not finite, or the angle is not within [0, 180].
pub fn incidence_mask(
    mesh: &TriMesh,
    toward_scanner: DVec3,
    max_incidence_deg: f64,
) -> Result<Vec<bool>, ScanPrepError> {
    let mut masks = incidence_masks(mesh, &[toward_scanner], max_incidence_deg)?;
    Ok(masks.pop().unwrap_or_default())
}

/// [`incidence_mask`] for each of the directions `towards`, with the smoothed normals computed
/// once: the masks are those of one call per direction. An error when a direction is zero or
/// not finite, or the angle is not within [0, 180].
pub fn incidence_masks(
    mesh: &TriMesh,
    towards: &[DVec3],
    max_incidence_deg: f64,
) -> Result<Vec<Vec<bool>>, ScanPrepError> {
    let mut dirs = Vec::with_capacity(towards.len());
    for t in towards {
        let d = t.normalize_or_zero();
        if !(d.is_finite() && d != DVec3::ZERO) {
            return Err(ScanPrepError::InvalidOption(format!(
                "scanner direction {t:?} (expected a finite, non-zero vector)"
            )));
        }
        dirs.push(d);
    }
    if !(0.0..=180.0).contains(&max_incidence_deg) {
        return Err(ScanPrepError::InvalidOption(format!(
            "max incidence {max_incidence_deg} degrees (expected 0 to 180)"
        )));
    }
    let adj = VertexAdjacency::new(mesh);
    let mut n = mesh.vertex_normals();
    for _ in 0..2 {
        n = adj
            .iter()
            .enumerate()
            .map(|(v, ring)| {
                ring.iter()
                    .fold(n[v], |s, &u| s + n[u as usize])
                    .normalize_or_zero()
            })
            .collect();
    }
    let c = max_incidence_deg.to_radians().cos();
    Ok(dirs
        .iter()
        .map(|d| {
            n.iter()
                .map(|n| *n != DVec3::ZERO && n.dot(*d) >= c)
                .collect()
        })
        .collect())
}
