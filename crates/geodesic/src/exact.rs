//! Exact polyhedral geodesic distance by window propagation ("VTP-S").
//!
//! A triangle-oriented, vertex-ordered window-list propagation in the style of VTP (Qin et al.
//! 2016) that only uses pruning rules which never remove a window part carrying a shortest path
//! (the vertex filter, the split at the apex's separating point, and a sorted pairwise trim of
//! the lower envelope). Vertices are ordered by `(distance, vertex id)`; see
//! `shared/docs/exact-geodesics.md` for the algorithm and the soundness argument.
//!
//! Besides the [`GeodesicSolver`](crate::GeodesicSolver) trait: [`ExactGeodesic::distances_with_stats`] (also returns
//! the number of window propagations), [`ExactGeodesic::distances_many`] (several source sets
//! in parallel with rayon, reusing per-thread buffers), [`ExactGeodesic::distances_with`] (one
//! solve reusing the buffers of an [`ExactWorkspace`]) and [`ExactGeodesic::trace_path`] (the shortest path itself, unfolded
//! back through the windows).
//!
//! Mesh handling (done once in [`ExactGeodesic::new`], reported by [`ExactGeodesic::report`]):
//! * faces repeating a vertex or having an edge shorter than `1e-12` x bbox diagonal are dropped
//!   (weld coincident vertices first with `meshcore::repair` if that matters);
//! * zero-area faces with distinct corners are kept and crossed ("pass-through");
//! * non-manifold edges (3+ faces) are cut: each incident face sees a boundary there, so paths
//!   can pass through the edge's end vertices but not across its interior;
//! * non-manifold vertices, boundary vertices and saddles (total angle > 2 pi - 1e-5) are
//!   pseudo-sources; inconsistent orientation is handled by reflecting the frames.

mod prepare;
mod solve;
mod trace;
mod window;

use crate::solver::Field;
use crate::{GeodesicError, Method, SolveOptions, Source, SurfacePoint, TriMesh};
use glam::DVec3;
use solve::{classify_point, Origin, Pred, Record, Seed, Solve};
use window::Window;

const NONE: u32 = u32::MAX;
const REV: u32 = 1 << 31;
const IDX: u32 = !REV;
/// Barycentric coordinates below this snap to zero (edge or vertex points).
const BARY_SNAP: f64 = 1e-12;

/// Geometry of a half-edge `a -> b` of face `(a, b, c)` in its frame: origin at `a`, x towards
/// `b`, +y into the face. Kept to 40 bytes (the per-window rotations are derived in
/// [`HeGeom::frame`] once per list): `process` starts with a cache miss on it.
#[derive(Debug, Clone, Copy, Default)]
struct HeGeom {
    /// |ab|.
    l: f64,
    /// Apex x.
    cx: f64,
    /// Apex y (> 0 unless the face is flat).
    cy: f64,
    /// |ac|: length of the left child edge.
    lac: f64,
    /// |bc|: length of the right child edge.
    lbc: f64,
}

/// [`HeGeom`] with the rotations into the child edges' frames.
#[derive(Debug, Clone, Copy)]
struct Frame {
    l: f64,
    cx: f64,
    cy: f64,
    lac: f64,
    lbc: f64,
    /// (cx, cy) / |ac|.
    cos_a: f64,
    sin_a: f64,
    /// (l - cx, -cy) / |bc|.
    ux: f64,
    uy: f64,
}

impl HeGeom {
    #[inline]
    fn frame(&self) -> Frame {
        Frame {
            l: self.l,
            cx: self.cx,
            cy: self.cy,
            lac: self.lac,
            lbc: self.lbc,
            cos_a: self.cx / self.lac,
            sin_a: self.cy / self.lac,
            ux: (self.l - self.cx) / self.lbc,
            uy: -self.cy / self.lbc,
        }
    }
}

/// Reusable per-solve buffers of [`ExactGeodesic`] (vertex states, window-list slots and
/// flags, queues, a pool of window lists) for [`ExactGeodesic::distances_with`]: a caller
/// solving many fields on one mesh keeps one per thread instead of allocating them per solve.
/// After a solve it holds `10 n + 5 h` bytes for a mesh of `n` vertices and `h` half-edges,
/// plus the queues, the child buffers of one list step and up to 4096 emptied window lists
/// kept for reuse.
#[derive(Debug, Default)]
pub struct ExactWorkspace {
    buf: solve::Buffers,
}

impl ExactWorkspace {
    /// An empty workspace (sized on its first solve).
    pub fn new() -> Self {
        Self::default()
    }
}

/// What [`ExactGeodesic::new`] found and repaired in the mesh.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ExactMeshReport {
    /// Faces ignored because they repeat a vertex or have a (near) zero-length edge.
    pub dropped_faces: Vec<u32>,
    /// Number of non-manifold edges (3+ faces) that were cut into boundary edges.
    pub cut_edges: usize,
    /// Vertices whose faces form several fans (treated as pseudo-sources).
    pub non_manifold_vertices: Vec<u32>,
    /// Number of interior edges whose two faces disagree on orientation (handled by reflection).
    pub inconsistent_edges: usize,
    /// Number of pseudo-source vertices (boundary, saddle or non-manifold).
    pub pseudo_sources: usize,
}

/// Exact polyhedral geodesic distance (window propagation, VTP-S).
///
/// Prepared once per mesh (half-edge structure and per-half-edge frames, about 100 bytes per
/// half-edge); each solve allocates its own state, so the solver can be shared across threads.
#[derive(Debug, Clone)]
pub struct ExactGeodesic {
    positions: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
    live: Vec<bool>,
    /// Twin half-edge index, possibly with the [`REV`] bit (same direction), or [`NONE`].
    twin: Vec<u32>,
    geom: Vec<HeGeom>,
    /// Per vertex (CSR), the half-edges opposite it in its live faces.
    vopp_off: Vec<u32>,
    vopp: Vec<u32>,
    pseudo: Vec<bool>,
    report: ExactMeshReport,
    schedule: ExactSchedule,
}

/// How one exact solve orders its work ([`ExactGeodesic::with_schedule`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum ExactSchedule {
    /// One vertex at a time, each followed by every list step it queues, on the calling thread.
    #[default]
    Serial,
    /// Vertices taken in bands of up to 32, and the queued lists processed generation by
    /// generation, each generation's list steps in parallel on the rayon pool the solve runs
    /// in (the global one, or the pool of a `ThreadPool::install`; a generation of fewer than
    /// 1024 windows on the calling thread). The field is the same bit
    /// for bit for every number of threads; it is exact like the serial one but may differ
    /// from it in the last bits (another processing order).
    Banded,
}

impl ExactGeodesic {
    /// The solver with another [`ExactSchedule`] (the default is [`ExactSchedule::Serial`]).
    pub fn with_schedule(mut self, schedule: ExactSchedule) -> Self {
        self.schedule = schedule;
        self
    }

    /// The [`ExactSchedule`] of its solves.
    pub fn schedule(&self) -> ExactSchedule {
        self.schedule
    }

    /// What was found and repaired when preparing the mesh.
    pub fn report(&self) -> &ExactMeshReport {
        &self.report
    }

    /// Distance field, also returning the number of window propagations (for benchmarks).
    pub fn distances_with_stats(
        &self,
        sources: &[Source],
        opts: &SolveOptions,
    ) -> Result<(Vec<f64>, u64), GeodesicError> {
        self.propagate(sources, opts.cutoff()?)
    }

    /// One propagation from `sources`, stopped past `cut`: the field and the number of window
    /// propagations.
    fn propagate(&self, sources: &[Source], cut: f64) -> Result<(Vec<f64>, u64), GeodesicError> {
        let mut ws = ExactWorkspace::default();
        self.propagate_in(&mut ws, sources, cut)
    }

    /// [`ExactGeodesic::propagate`] with the buffers of `ws` (left in `ws` for the next solve).
    fn propagate_in(
        &self,
        ws: &mut ExactWorkspace,
        sources: &[Source],
        cut: f64,
    ) -> Result<(Vec<f64>, u64), GeodesicError> {
        let mut s = Solve::with_buffers(self, cut, false, std::mem::take(&mut ws.buf));
        let seeded = s.seed(sources);
        if seeded.is_ok() {
            match self.schedule {
                ExactSchedule::Serial => s.run(),
                ExactSchedule::Banded => s.run_banded(),
            }
        }
        let props = s.propagations;
        let (d, buf) = s.finish_into();
        ws.buf = buf;
        seeded.map(|()| (d, props))
    }

    /// Distance field from `sources` like
    /// [`GeodesicSolver::distances`](crate::GeodesicSolver::distances) (bit-identical result),
    /// reusing the per-solve buffers of `ws` instead of allocating them: for several solves in
    /// a row on one mesh. `ws` may come from another solver (it is then resized).
    pub fn distances_with(
        &self,
        ws: &mut ExactWorkspace,
        sources: &[Source],
        opts: &SolveOptions,
    ) -> Result<Vec<f64>, GeodesicError> {
        self.propagate_in(ws, sources, opts.cutoff()?)
            .map(|(d, _)| d)
    }

    /// One distance field per source set (results in input order, each bit-identical to
    /// [`GeodesicSolver::distances`](crate::GeodesicSolver::distances) of that set), solved in
    /// parallel with rayon, each worker reusing one [`ExactWorkspace`] across its sets. All
    /// sets are validated first; the first invalid one (in input order) is the error and
    /// nothing is solved.
    pub fn distances_many(
        &self,
        source_sets: &[Vec<Source>],
        opts: &SolveOptions,
    ) -> Result<Vec<Vec<f64>>, GeodesicError> {
        self.fields_many(source_sets, opts.cutoff()?)
    }

    /// [`ExactGeodesic::distances_many`] with a validated cut-off.
    fn fields_many(
        &self,
        source_sets: &[Vec<Source>],
        cut: f64,
    ) -> Result<Vec<Vec<f64>>, GeodesicError> {
        use rayon::prelude::*;
        for set in source_sets {
            if set.is_empty() {
                return Err(GeodesicError::NoSource);
            }
            for s in set {
                Solve::classify(self, s)?;
            }
        }
        source_sets
            .par_iter()
            .map_init(ExactWorkspace::default, |ws, set| {
                self.propagate_in(ws, set, cut).map(|(d, _)| d)
            })
            .collect()
    }

    #[inline]
    fn tail(&self, h: u32) -> u32 {
        self.tris[(h / 3) as usize][(h % 3) as usize]
    }
    #[inline]
    fn head(&self, h: u32) -> u32 {
        self.tris[(h / 3) as usize][((h % 3 + 1) % 3) as usize]
    }
    #[inline]
    fn apex(&self, h: u32) -> u32 {
        self.tris[(h / 3) as usize][((h % 3 + 2) % 3) as usize]
    }
    #[inline]
    fn opp(&self, v: u32) -> &[u32] {
        &self.vopp[self.vopp_off[v as usize] as usize..self.vopp_off[v as usize + 1] as usize]
    }
}

#[inline]
fn next(h: u32) -> u32 {
    if h % 3 == 2 {
        h - 2
    } else {
        h + 1
    }
}
#[inline]
fn prev(h: u32) -> u32 {
    if h % 3 == 0 {
        h + 2
    } else {
        h - 1
    }
}

impl Field for ExactGeodesic {
    const METHOD: Method = Method::Exact;
    fn positions(&self) -> &[DVec3] {
        &self.positions
    }
    fn field(&self, sources: &[Source], cut: f64) -> Result<Vec<f64>, GeodesicError> {
        self.propagate(sources, cut).map(|(d, _)| d)
    }
    fn fields(&self, sets: &[Vec<Source>], cut: f64) -> Result<Vec<Vec<f64>>, GeodesicError> {
        self.fields_many(sets, cut)
    }
}
