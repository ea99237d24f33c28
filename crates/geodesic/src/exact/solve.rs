//! One solve of the exact solver: seeding, the vertex-ordered window propagation with its sound
//! pruning rules, and the resulting distances.

use super::window::{pair_trim, BoundStats, Trim, TAU};
use super::*;
use crate::solver::Item;
use std::cmp::Ordering;
use std::collections::{BinaryHeap, VecDeque};
use std::sync::Mutex;

/// How a vertex got its current distance (recorded for path tracing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Pred {
    /// Not reached.
    None,
    /// A source vertex.
    Source,
    /// Straight line from the point source with this index.
    Point(u32),
    /// Along an edge from a pseudo-source vertex.
    Vertex(u32),
    /// As the apex of a window record, via the edge point at parameter `t`.
    Window(u32, f64),
}

/// Where a recorded window came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Origin {
    /// Child of another record.
    Window(u32),
    /// Emitted by a pseudo-source (or source) vertex.
    Vertex(u32),
    /// Emitted by the point source with this index.
    Point(u32),
}

/// A window as emitted, with its half-edge and origin (path-tracing mode).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Record {
    pub h: u32,
    pub w: Window,
    pub origin: Origin,
}

/// [`Solve::flags`] bit: the half-edge is in the FIFO.
const QUEUED: u8 = 1;
/// [`Solve::flags`] bit: the half-edge's window list is not empty.
const FILLED: u8 = 2;

const OUTSIDE: u8 = 0;
const FRONT: u8 = 1;
const INSIDE: u8 = 2;

/// A validated source after barycentric snapping.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Seed {
    Vertex(u32),
    /// A point in a live face (barycentrics snapped); `skip` is the host half-edge of an edge
    /// point (no window is started on it).
    Face {
        face: u32,
        bary: [f64; 3],
        skip: u32,
    },
    /// A point on a dropped (degenerate) face: only the corners get straight-line distances.
    Degenerate {
        face: u32,
        pos: DVec3,
    },
}

/// State of one solve.
pub(crate) struct Solve<'a> {
    g: &'a ExactGeodesic,
    cut: f64,
    pub(crate) d: Vec<f64>,
    /// The per-solve arrays, reusable by the next solve ([`Solve::finish_into`]).
    b: Buffers,
    draining: bool,
    /// Pairwise trim and apex split enabled (off only in the differential tests' oracle mode,
    /// which keeps just the vertex filter).
    prune: bool,
    pub(super) propagations: u64,
    /// Path-tracing mode: every emitted window, and how each vertex got its distance.
    pub(crate) records: Option<Vec<Record>>,
    pub(crate) pred: Vec<Pred>,
    /// Point sources (position), indexed by `Pred::Point` / `Origin::Point`.
    pub(crate) points: Vec<(u32, [f64; 3], DVec3)>,
    cur_origin: Origin,
}

/// The per-solve arrays of [`Solve`] that can be reused by the next solve on the same mesh
/// (everything but the distances, which are the result): vertex states, per-half-edge list
/// slots and flags, the lists in use, queues, and a pool of emptied window lists.
#[derive(Debug, Default)]
pub(crate) struct Buffers {
    state: Vec<u8>,
    emitted: Vec<f64>,
    emit_flag: Vec<bool>,
    /// Per half-edge: 0 (no list) or 1 + the index of its window list in `held`. Four bytes
    /// per half-edge (zeroed memory when allocated) instead of a list header each: only the
    /// half-edges of the wavefront hold a list at any time.
    slot: Vec<u32>,
    /// The window lists of the half-edges that hold one; emptied entries are in `free`.
    held: Vec<Vec<Window>>,
    /// The half-edge of each entry of `held` (stale for emptied entries).
    owner: Vec<u32>,
    free: Vec<u32>,
    /// Per half-edge: [`QUEUED`] (in `fifo`) and [`FILLED`] (its list is not empty), one byte
    /// so that the queue checks do not load the list headers.
    flags: Vec<u8>,
    fifo: VecDeque<u32>,
    heap: BinaryHeap<Item>,
    pool: Vec<Vec<Window>>,
    pending_emit: Vec<u32>,
    /// Scratch of the list steps run on this thread.
    step: StepScratch,
    /// Scratch of the list steps run by rayon workers ([`Solve::run_banded`]).
    spare: Mutex<Vec<StepScratch>>,
    /// The lists of one generation of [`Solve::run_banded`].
    batch: Vec<BatchItem>,
}

impl Buffers {
    /// Puts the buffers in the state of a fresh solve on `g` (allocating them on first use or
    /// when they were sized for another mesh). The result of a solve does not depend on what
    /// the buffers held before: every array is reset to the values [`Solve::new`] starts from.
    fn reset(&mut self, g: &ExactGeodesic) {
        let n = g.positions.len();
        let nh = g.twin.len();
        self.state.clear();
        self.state.resize(n, OUTSIDE);
        self.emitted.clear();
        self.emitted.resize(n, f64::NAN);
        self.emit_flag.clear();
        self.emit_flag.extend_from_slice(&g.pseudo);
        if self.slot.len() != nh || self.flags.len() != nh {
            self.slot = vec![0; nh];
            self.flags = vec![0; nh];
        } else {
            // A finished solve leaves every slot and flag clear; a solve stopped early (an
            // error while seeding) may not.
            for (h, f) in self.flags.iter_mut().enumerate() {
                if *f != 0 {
                    *f = 0;
                    self.slot[h] = 0;
                }
            }
        }
        self.owner.clear();
        for mut l in self.held.drain(..) {
            if l.capacity() > 0 && self.pool.len() < POOL_MAX {
                l.clear();
                self.pool.push(l);
            }
        }
        self.free.clear();
        self.fifo.clear();
        self.heap.clear();
        self.pending_emit.clear();
        self.step.kids.iter_mut().for_each(Vec::clear);
        self.step.bound_stats = BoundStats::default();
        self.batch.clear();
    }
}

impl Buffers {
    /// The window list of half-edge `h`, given a slot if it has none; with `pooled`, an
    /// unallocated list takes an emptied one from the pool.
    #[inline(always)]
    fn list_of(&mut self, h: u32, pooled: bool) -> &mut Vec<Window> {
        let mut i = self.slot[h as usize];
        if i == 0 {
            i = match self.free.pop() {
                Some(i) => i,
                None => {
                    self.held.push(Vec::new());
                    self.owner.push(h);
                    self.held.len() as u32
                }
            };
            self.slot[h as usize] = i;
            self.owner[i as usize - 1] = h;
        }
        let list = &mut self.held[i as usize - 1];
        if pooled && list.capacity() == 0 {
            if let Some(v) = self.pool.pop() {
                *list = v;
            }
        }
        list
    }
}

/// Most emptied window lists kept for reuse.
const POOL_MAX: usize = 4096;

impl<'a> Solve<'a> {
    pub(crate) fn new(g: &'a ExactGeodesic, cut: f64, record: bool) -> Self {
        Self::with_buffers(g, cut, record, Buffers::default())
    }

    /// A solve that uses (and resets) `buf`; [`Solve::finish_into`] hands them back.
    pub(crate) fn with_buffers(
        g: &'a ExactGeodesic,
        cut: f64,
        record: bool,
        mut buf: Buffers,
    ) -> Self {
        buf.reset(g);
        let n = g.positions.len();
        Self {
            g,
            cut,
            d: vec![f64::INFINITY; n],
            b: buf,
            draining: false,
            prune: true,
            propagations: 0,
            records: if record { Some(Vec::new()) } else { None },
            pred: if record {
                vec![Pred::None; n]
            } else {
                Vec::new()
            },
            points: Vec::new(),
            cur_origin: Origin::Vertex(0),
        }
    }

    /// Validates and snaps one source.
    pub(crate) fn classify(g: &ExactGeodesic, s: &Source) -> Result<Seed, GeodesicError> {
        match *s {
            Source::Vertex(v) => {
                if v as usize >= g.positions.len() {
                    return Err(GeodesicError::SourceOutOfRange {
                        vertex: v,
                        vertices: g.positions.len(),
                    });
                }
                Ok(Seed::Vertex(v))
            }
            Source::Point(sp) => classify_point(g, &sp),
        }
    }

    pub(crate) fn seed(&mut self, sources: &[Source]) -> Result<(), GeodesicError> {
        if sources.is_empty() {
            return Err(GeodesicError::NoSource);
        }
        let seeds = sources
            .iter()
            .map(|s| Self::classify(self.g, s))
            .collect::<Result<Vec<_>, _>>()?;
        for s in seeds {
            match s {
                Seed::Vertex(v) => {
                    self.b.emit_flag[v as usize] = true;
                    self.relax(v, 0.0, Pred::Source);
                }
                Seed::Face { face, bary, skip } => self.seed_face_point(face, bary, skip),
                Seed::Degenerate { face, pos } => {
                    let i = self.points.len() as u32;
                    self.points.push((face, [f64::NAN; 3], pos));
                    for &v in &self.g.tris[face as usize] {
                        let dv = (self.g.positions[v as usize] - pos).length();
                        self.b.emit_flag[v as usize] = true;
                        self.relax(v, dv, Pred::Point(i));
                    }
                }
            }
        }
        Ok(())
    }

    fn seed_face_point(&mut self, face: u32, bary: [f64; 3], skip: u32) {
        let g = self.g;
        let t = g.tris[face as usize];
        let pos = bary[0] * g.positions[t[0] as usize]
            + bary[1] * g.positions[t[1] as usize]
            + bary[2] * g.positions[t[2] as usize];
        let idx = self.points.len() as u32;
        self.points.push((face, bary, pos));
        let mut faces = vec![(face, bary, skip)];
        if skip != NONE {
            let tw = g.twin[skip as usize];
            if tw != NONE {
                let h2 = tw & IDX;
                let f2 = h2 / 3;
                let t2 = g.tris[f2 as usize];
                let mut b2 = [0.0; 3];
                for k in 0..3 {
                    if let Some(j) = t.iter().position(|&v| v == t2[k]) {
                        b2[k] = bary[j];
                    }
                }
                faces.push((f2, b2, h2));
            }
        }
        self.cur_origin = Origin::Point(idx);
        for (f, b, sk) in faces {
            let tf = g.tris[f as usize];
            for k in 0..3u32 {
                let h = 3 * f + k;
                if h == sk {
                    continue;
                }
                let geo = g.geom[h as usize];
                let (k0, k1, k2) = (k as usize, ((k + 1) % 3) as usize, ((k + 2) % 3) as usize);
                let _ = k0;
                let px = b[k1] * geo.l + b[k2] * geo.cx;
                let py = b[k2] * geo.cy;
                self.emit_vertex_like(h, px, py, 0.0);
            }
            for &v in &tf {
                let dv = (g.positions[v as usize] - pos).length();
                self.relax(v, dv, Pred::Point(idx));
            }
        }
    }

    /// Starts a full-edge window on the twin of `h` from the point `(px, py)` of `h`'s frame
    /// (a point of face(h)) with distance `sigma`.
    #[inline(always)]
    fn emit_vertex_like(&mut self, h: u32, px: f64, py: f64, sigma: f64) {
        let g = self.g;
        let tw = g.twin[h as usize];
        if tw == NONE {
            return;
        }
        let th = tw & IDX;
        let geo = &g.geom[h as usize];
        let l = geo.l;
        let sx = if tw & REV != 0 { px } else { l - px };
        let sy = (-py).min(-1e-14 * l);
        let w = Window {
            b0: 0.0,
            b1: l,
            sigma,
            sx,
            sy,
            id: u32::MAX,
        };
        if w.min_dist() > self.cut {
            return;
        }
        self.add_window(th, w, self.cur_origin);
    }

    /// Gives `w` its record id (path-tracing mode: the record is written here).
    #[inline]
    fn record(&mut self, h: u32, w: &mut Window, origin: Origin) {
        if let Some(rec) = self.records.as_mut() {
            w.id = rec.len() as u32;
            rec.push(Record { h, w: *w, origin });
        }
    }

    #[inline]
    fn add_window(&mut self, h: u32, mut w: Window, origin: Origin) {
        self.record(h, &mut w, origin);
        self.append(h, std::slice::from_ref(&w));
    }

    /// Appends `ws` (already recorded) to the list of `h` and queues the list if one of its
    /// end vertices is inside (or while draining).
    #[inline]
    fn append(&mut self, h: u32, ws: &[Window]) {
        self.b.list_of(h, true).extend_from_slice(ws);
        self.filled(h);
    }

    /// [`Solve::append`] of the windows of `ws`, which it leaves empty: moved into the list
    /// of `h` without a copy when that list is empty.
    fn append_vec(&mut self, h: u32, ws: &mut Vec<Window>) {
        let list = self.b.list_of(h, false);
        if list.is_empty() {
            std::mem::swap(list, ws);
        } else {
            list.extend_from_slice(ws);
        }
        ws.clear();
        self.filled(h);
    }

    /// Marks the list of `h` filled and queues it if one of its end vertices is inside (or
    /// while draining).
    #[inline(always)]
    fn filled(&mut self, h: u32) {
        let f = &mut self.b.flags[h as usize];
        *f |= FILLED;
        if *f & QUEUED == 0 {
            let g = self.g;
            if self.draining
                || self.b.state[g.tail(h) as usize] == INSIDE
                || self.b.state[g.head(h) as usize] == INSIDE
            {
                self.b.flags[h as usize] |= QUEUED;
                self.b.fifo.push_back(h);
            }
        }
    }

    #[inline(always)]
    fn relax(&mut self, v: u32, dist: f64, pred: Pred) {
        let vi = v as usize;
        if dist < self.d[vi] {
            self.d[vi] = dist;
            if !self.pred.is_empty() {
                self.pred[vi] = pred;
            }
            if self.b.state[vi] != INSIDE {
                self.b.state[vi] = FRONT;
                self.b.heap.push(Item(dist, v));
            } else if self.b.emit_flag[vi] {
                self.b.pending_emit.push(v);
            }
        }
    }

    /// Emits the pseudo-source windows of `v` (and relaxes its neighbours along edges).
    fn emit_from_vertex(&mut self, v: u32) {
        let dv = self.d[v as usize];
        if self.b.emitted[v as usize] == dv || dv > self.cut {
            return;
        }
        self.b.emitted[v as usize] = dv;
        let g = self.g;
        self.cur_origin = Origin::Vertex(v);
        for &gh in g.opp(v) {
            let geo = g.geom[gh as usize];
            self.emit_vertex_like(gh, geo.cx, geo.cy, dv);
            self.relax(g.tail(gh), dv + geo.lac, Pred::Vertex(v));
            self.relax(g.head(gh), dv + geo.lbc, Pred::Vertex(v));
        }
    }

    fn push_list(&mut self, h: u32) {
        if self.b.flags[h as usize] == FILLED {
            self.b.flags[h as usize] = FILLED | QUEUED;
            self.b.fifo.push_back(h);
        }
    }

    fn pop_vertex(&mut self, v: u32) {
        let g = self.g;
        self.b.state[v as usize] = INSIDE;
        if self.b.emit_flag[v as usize] {
            self.emit_from_vertex(v);
        }
        for &gh in g.opp(v) {
            for h in [next(gh), prev(gh)] {
                self.push_list(h);
                let t = g.twin[h as usize];
                if t != NONE {
                    self.push_list(t & IDX);
                }
            }
            for u in [g.tail(gh), g.head(gh)] {
                if self.b.state[u as usize] == OUTSIDE {
                    self.b.state[u as usize] = FRONT;
                }
            }
            let t = g.twin[gh as usize];
            let ok = t == NONE || self.b.state[g.apex(t & IDX) as usize] != OUTSIDE;
            if ok {
                self.push_list(gh);
                if t != NONE {
                    self.push_list(t & IDX);
                }
            }
        }
    }

    pub(crate) fn run(&mut self) {
        loop {
            if let Some(v) = self.b.pending_emit.pop() {
                self.emit_from_vertex(v);
                continue;
            }
            if let Some(h) = self.b.fifo.pop_front() {
                self.b.flags[h as usize] &= !QUEUED;
                self.process(h);
                continue;
            }
            let mut popped = false;
            while let Some(&Item(dv, v)) = self.b.heap.peek() {
                if dv != self.d[v as usize] || self.b.state[v as usize] == INSIDE {
                    self.b.heap.pop();
                    continue;
                }
                if dv > self.cut {
                    break;
                }
                self.b.heap.pop();
                self.pop_vertex(v);
                popped = true;
                break;
            }
            if !popped && !self.queue_for_drain() {
                break;
            }
        }
    }

    /// Heap exhausted (or beyond the cut-off): switches to draining and queues every list
    /// still holding windows, in half-edge order; false when there is none. The lists in use
    /// are found from `held` (the non-empty entries), not by a scan of every half-edge.
    fn queue_for_drain(&mut self) -> bool {
        self.draining = true;
        let b = &mut self.b;
        let start = b.fifo.len();
        for (l, &h) in b.held.iter().zip(&b.owner) {
            if !l.is_empty() && b.flags[h as usize] == FILLED {
                b.flags[h as usize] = FILLED | QUEUED;
                b.fifo.push_back(h);
            }
        }
        b.fifo.make_contiguous()[start..].sort_unstable();
        b.fifo.len() > start
    }

    #[cfg(test)]
    pub(crate) fn finish(self) -> Vec<f64> {
        self.finish_into().0
    }

    /// The distances (beyond the cut-off: infinity) and the buffers for the next solve.
    pub(crate) fn finish_into(mut self) -> (Vec<f64>, Buffers) {
        if self.cut.is_finite() {
            for d in &mut self.d {
                if *d > self.cut {
                    *d = f64::INFINITY;
                }
            }
        }
        (self.d, self.b)
    }

    /// Takes the window list of `h` out of its slot (clearing the slot and the filled flag);
    /// `None` when the half-edge holds no windows.
    fn take_list(&mut self, h: u32) -> Option<Vec<Window>> {
        let i = std::mem::take(&mut self.b.slot[h as usize]);
        self.b.flags[h as usize] &= !FILLED;
        if i == 0 {
            return None;
        }
        self.b.free.push(i);
        let ws = std::mem::take(&mut self.b.held[i as usize - 1]);
        if ws.is_empty() {
            return None;
        }
        Some(ws)
    }

    /// The triangle step: filters the list of `h` and pushes its windows across face(h).
    fn process(&mut self, h: u32) {
        let Some(mut ws) = self.take_list(h) else {
            return;
        };
        let out = list_step(
            self.g,
            &self.d,
            self.cut,
            self.prune,
            h,
            &mut ws,
            &mut self.b.step,
        );
        self.recycle(ws);
        if let Some(out) = out {
            self.apply(&out, None);
        }
    }

    /// Applies what a list step found: relaxes its apex, then appends its children to their
    /// lists (recording them first in path-tracing mode) and empties their buffers: `kids`, or
    /// without it the children of this thread's scratch. A buffer appended to an empty list is
    /// moved into it without a copy (and replaced by that list's buffer, or for this thread's
    /// scratch by a pooled one when that has no capacity).
    #[inline(always)]
    fn apply(&mut self, out: &StepOut, mut kids: Option<&mut [Vec<Window>; 2]>) {
        if out.best < self.d[out.apex as usize] {
            self.relax(out.apex, out.best, Pred::Window(out.best_id, out.p_star));
        }
        for (side, tw) in out.order {
            let mut ks = match kids.as_deref_mut() {
                Some(k) => std::mem::take(&mut k[side]),
                None => std::mem::take(&mut self.b.step.kids[side]),
            };
            if !ks.is_empty() {
                self.propagations += ks.len() as u64;
                if self.records.is_some() {
                    for k in ks.iter_mut() {
                        let parent = k.id;
                        self.record(tw & IDX, k, Origin::Window(parent));
                    }
                }
                self.append_vec(tw & IDX, &mut ks);
                if kids.is_none() && ks.capacity() == 0 {
                    // This thread's scratch gave its buffer to an empty list: an emptied
                    // one from the pool replaces it.
                    ks = self.pooled();
                }
            }
            match kids.as_deref_mut() {
                Some(k) => k[side] = ks,
                None => self.b.step.kids[side] = ks,
            }
        }
    }

    /// The banded schedule of [`ExactSchedule::Banded`]: vertices are popped [`BAND`] at a
    /// time, and the queued lists are processed generation by generation, each generation's
    /// list steps in parallel on the current rayon pool against the distances as they were
    /// when the generation began, and then applied in queue order. A list step reads nothing
    /// its generation writes, so the field does not depend on the number of threads.
    pub(crate) fn run_banded(&mut self) {
        loop {
            if let Some(v) = self.b.pending_emit.pop() {
                self.emit_from_vertex(v);
                continue;
            }
            if !self.b.fifo.is_empty() {
                self.generation();
                continue;
            }
            let mut popped = 0;
            while let Some(&Item(dv, v)) = self.b.heap.peek() {
                if dv != self.d[v as usize] || self.b.state[v as usize] == INSIDE {
                    self.b.heap.pop();
                    continue;
                }
                if dv > self.cut || popped == BAND {
                    break;
                }
                self.b.heap.pop();
                self.pop_vertex(v);
                popped += 1;
            }
            if popped == 0 && !self.queue_for_drain() {
                break;
            }
        }
    }

    /// Processes every queued list (one generation) as described in [`Solve::run_banded`].
    fn generation(&mut self) {
        use rayon::prelude::*;
        let mut items = std::mem::take(&mut self.b.batch);
        let mut windows = 0;
        while let Some(h) = self.b.fifo.pop_front() {
            self.b.flags[h as usize] &= !QUEUED;
            if let Some(ws) = self.take_list(h) {
                windows += ws.len();
                let kids = [self.pooled(), self.pooled()];
                items.push(BatchItem {
                    h,
                    ws,
                    kids,
                    out: None,
                });
            }
        }
        let (g, d, cut, prune) = (self.g, &self.d, self.cut, self.prune);
        let run = |sc: &mut StepScratch, it: &mut BatchItem| {
            std::mem::swap(&mut sc.kids, &mut it.kids);
            it.out = list_step(g, d, cut, prune, it.h, &mut it.ws, sc);
            std::mem::swap(&mut sc.kids, &mut it.kids);
        };
        if items.len() < 2 || windows < PARALLEL_MIN || rayon::current_num_threads() < 2 {
            let mut sc = std::mem::take(&mut self.b.step);
            items.iter_mut().for_each(|it| run(&mut sc, it));
            self.b.step = sc;
        } else {
            let spare = &self.b.spare;
            items
                .par_iter_mut()
                .with_min_len(2)
                .for_each_init(|| Lease::new(spare), |l, it| run(&mut l.sc, it));
        }
        for mut it in items.drain(..) {
            if let Some(out) = it.out {
                self.apply(&out, Some(&mut it.kids));
            }
            self.recycle(it.ws);
            let [k0, k1] = it.kids;
            self.recycle(k0);
            self.recycle(k1);
        }
        self.b.batch = items;
    }

    /// An empty window list from the pool (or a new one).
    fn pooled(&mut self) -> Vec<Window> {
        self.b.pool.pop().unwrap_or_default()
    }

    fn recycle(&mut self, mut ws: Vec<Window>) {
        ws.clear();
        if ws.capacity() > 0 && self.b.pool.len() < POOL_MAX {
            self.b.pool.push(ws);
        }
    }
}

/// Most vertices [`Solve::run_banded`] pops before processing the lists they queue.
pub(crate) const BAND: usize = 32;
/// Fewest windows in the lists of a generation for [`Solve::run_banded`] to hand their steps
/// to rayon (about 50 µs of work; smaller generations are stepped on the calling thread, which
/// changes only the speed).
const PARALLEL_MIN: usize = 1024;

/// One queued list of a generation of the banded schedule: its windows, the children its step
/// emits and what else the step found.
#[derive(Debug)]
pub(crate) struct BatchItem {
    h: u32,
    ws: Vec<Window>,
    kids: [Vec<Window>; 2],
    out: Option<StepOut>,
}

/// A [`StepScratch`] taken from the spare ones for one rayon job and given back when dropped.
struct Lease<'a> {
    spare: &'a Mutex<Vec<StepScratch>>,
    sc: StepScratch,
}

impl<'a> Lease<'a> {
    fn new(spare: &'a Mutex<Vec<StepScratch>>) -> Self {
        let sc = spare
            .lock()
            .ok()
            .and_then(|mut v| v.pop())
            .unwrap_or_default();
        Self { spare, sc }
    }
}

impl Drop for Lease<'_> {
    fn drop(&mut self) {
        if let Ok(mut v) = self.spare.lock() {
            v.push(std::mem::take(&mut self.sc));
        }
    }
}

/// Scratch buffers of one list step: the rays' apex crossings, the sort's runs and merged
/// copy, the children for the left and right target list, the trim's shortcut counters
/// (which change only the speed) and the cut-off of the step's solve.
#[derive(Debug, Default)]
pub(crate) struct StepScratch {
    tcs: Vec<f64>,
    runs: Vec<u32>,
    merged: Vec<Window>,
    kids: [Vec<Window>; 2],
    bound_stats: BoundStats,
    /// The solve's cut-off (children beyond it are not emitted).
    cut: f64,
}

/// What a list step found besides its children: the apex, its best distance through the list
/// with the window (record id) and edge point it came from, and the order in which the
/// children's two target lists (side 0 left, 1 right, with their half-edges) are appended.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StepOut {
    apex: u32,
    best: f64,
    best_id: u32,
    p_star: f64,
    order: [(usize, u32); 2],
}

/// The triangle step on the windows `ws` of half-edge `h` against the vertex distances `d`:
/// the vertex filter, the sorted pairwise trim, the apex's best window and split point, and the
/// children, written into `sc.kids` (each child's `id` is its parent's, for path tracing).
/// Reads only its arguments, so list steps of one generation can run in parallel. `None`
/// when no window survives (no children).
fn list_step(
    g: &ExactGeodesic,
    d: &[f64],
    cut: f64,
    prune: bool,
    h: u32,
    ws: &mut Vec<Window>,
    sc: &mut StepScratch,
) -> Option<StepOut> {
    sc.cut = cut;
    let geo = g.geom[h as usize];
    let (a, b, c) = (g.tail(h), g.head(h), g.apex(h));
    let (da, db) = (d[a as usize], d[b as usize]);
    let l = geo.l;
    // P0: vertex filter.
    ws.retain(|w| !(vertex_beats(da + w.b1, w, w.b1) || vertex_beats(db + (l - w.b0), w, w.b0)));
    // P1: sorted lower-envelope trim (dead windows are skipped below, not removed).
    let mut alive = ws.len();
    if prune && ws.len() > 1 {
        sort_by_start(ws, &mut sc.runs, &mut sc.merged);
        let mut cur = 0;
        for j in 1..ws.len() {
            let (lo, hi) = ws.split_at_mut(j);
            match pair_trim(&mut lo[cur], &mut hi[0], &mut sc.bound_stats) {
                Trim::FirstDead => {
                    cur = j;
                    alive -= 1;
                }
                Trim::SecondDead => alive -= 1,
                Trim::Both => {
                    if hi[0].b1 > lo[cur].b1 {
                        cur = j;
                    }
                }
            }
        }
    }
    if alive == 0 {
        return None;
    }
    // P2: best window for the apex and the split point.
    let geo = geo.frame();
    let (cx, cy) = (geo.cx, geo.cy);
    let tcs = &mut sc.tcs;
    tcs.clear();
    let mut best = f64::INFINITY;
    let mut p_star = 0.0;
    let mut best_id = u32::MAX;
    let mut best_sigma = f64::INFINITY;
    for w in ws.iter() {
        if w.is_dead() {
            // Not read: dead windows emit no children.
            tcs.push(f64::NAN);
            continue;
        }
        let tc = w.sx + (-w.sy) * (cx - w.sx) / (cy - w.sy);
        tcs.push(tc);
        let t = tc.clamp(w.b0, w.b1);
        let dc = if t == tc {
            w.sigma + ((cx - w.sx) * (cx - w.sx) + (cy - w.sy) * (cy - w.sy)).sqrt()
        } else {
            w.dist(t) + ((cx - t) * (cx - t) + cy * cy).sqrt()
        };
        if dc < best || (dc == best && w.sigma < best_sigma) {
            best = dc;
            p_star = t;
            best_id = w.id;
            best_sigma = w.sigma;
        }
    }
    let out_p_star = p_star;
    // P3: split rule and propagation.
    if !prune {
        // Oracle mode: every ray goes to the side it actually exits through.
        p_star = f64::NAN;
    }
    // The children are collected per target list and appended in one step each, the list
    // that received the first child first (the order of single pushes).
    let tl_tw = g.twin[prev(h) as usize];
    let tr_tw = g.twin[next(h) as usize];
    let mut right_first = None;
    for (i, w) in ws.iter().enumerate() {
        if w.is_dead() {
            continue;
        }
        let tc = sc.tcs[i];
        if tl_tw != NONE {
            let tl = w.b1.min(tc).min(if p_star.is_nan() { tc } else { p_star });
            if tl > w.b0 {
                sc.emit_left(&geo, tl_tw, w, w.b0, tl, tl == tc);
            }
        }
        if tr_tw != NONE {
            let tr = w.b0.max(tc).max(if p_star.is_nan() { tc } else { p_star });
            if tr < w.b1 {
                sc.emit_right(&geo, tr_tw, w, tr, w.b1, tr == tc);
            }
        }
        if right_first.is_none() {
            let [l, r] = &sc.kids;
            if !(l.is_empty() && r.is_empty()) {
                right_first = Some(l.is_empty());
            }
        }
    }
    let order = if right_first == Some(true) {
        [(1, tr_tw), (0, tl_tw)]
    } else {
        [(0, tl_tw), (1, tr_tw)]
    };
    Some(StepOut {
        apex: c,
        best,
        best_id,
        p_star: out_p_star,
        order,
    })
}

impl StepScratch {
    /// Child on the left edge a -> c: frame origin a, x towards c.
    #[inline]
    fn emit_left(&mut self, geo: &Frame, tw: u32, w: &Window, t0: f64, t1: f64, apex_end: bool) {
        let (cs, sn) = (geo.cos_a, geo.sin_a);
        let ell = geo.lac;
        let sx = w.sx * cs + w.sy * sn;
        let sy = -w.sx * sn + w.sy * cs;
        // T' = (t cos, -t sin).
        let x_of = |t: f64| -> f64 { edge_crossing(sx, sy, t * cs, -t * sn, ell) };
        let x0 = if t0 <= 0.0 { 0.0 } else { x_of(t0) };
        let x1 = if apex_end { ell } else { x_of(t1) };
        self.push_child(0, tw, ell, w, sx, sy, x0, x1);
    }

    /// Child on the right edge c -> b: frame origin c, x towards b.
    #[inline]
    fn emit_right(&mut self, geo: &Frame, tw: u32, w: &Window, t0: f64, t1: f64, apex_end: bool) {
        let (ux, uy) = (geo.ux, geo.uy);
        let ell = geo.lbc;
        let (dx, dy) = (w.sx - geo.cx, w.sy - geo.cy);
        let sx = dx * ux + dy * uy;
        let sy = -dx * uy + dy * ux;
        let x_of = |t: f64| -> f64 {
            let (ex, ey) = (t - geo.cx, -geo.cy);
            edge_crossing(sx, sy, ex * ux + ey * uy, -ex * uy + ey * ux, ell)
        };
        let x0 = if apex_end { 0.0 } else { x_of(t0) };
        let x1 = if t1 >= geo.l { ell } else { x_of(t1) };
        self.push_child(1, tw, ell, w, sx, sy, x0, x1);
    }

    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn push_child(
        &mut self,
        side: usize,
        tw: u32,
        ell: f64,
        w: &Window,
        sx: f64,
        sy: f64,
        x0: f64,
        x1: f64,
    ) {
        let mut x0 = x0.clamp(0.0, ell);
        let x1 = x1.clamp(0.0, ell);
        if x0 > x1 {
            x0 = x1;
        }
        let sy = sy.min(-1e-14 * ell);
        let (b0, b1, sx) = if tw & REV != 0 {
            (ell - x1, ell - x0, ell - sx)
        } else {
            (x0, x1, sx)
        };
        let child = Window {
            b0,
            b1,
            sigma: w.sigma,
            sx,
            sy,
            id: w.id,
        };
        if self.cut.is_finite() && child.min_dist() > self.cut {
            return;
        }
        self.kids[side].push(child);
    }
}

/// The vertex filter's test `p < D(x) (1 - TAU)` (a vertex path of length `p` beats the window
/// at `x`), with the same result as evaluating it directly but usually without the square
/// root: when `p / (1 - TAU) - sigma` exceeds `|S - x|` by more than `1e-13 p` (checked by
/// squaring, far above the few ulps of rounding in either evaluation), the test is false.
#[inline]
fn vertex_beats(p: f64, w: &Window, x: f64) -> bool {
    const K: f64 = 1.0 / (1.0 - TAU);
    let dx = x - w.sx;
    let a = dx * dx + w.sy * w.sy;
    let t = p * K - w.sigma - 1e-13 * p;
    if t > 0.0 && t * t > a {
        return false;
    }
    p < w.dist(x) * (1.0 - TAU)
}

/// Stable sort of a window list by start (`total_cmp`), the order of `sort_by`: insertion sort
/// for the short lists of a solve; a long list (appended in sorted batches, so a few
/// ascending runs) by merging neighbouring runs pass by pass, taking the left run's window on
/// ties. Each pass writes into `merged`, which is then swapped with `ws` (so `ws` may come
/// back in another allocation); `runs` and `merged` are scratch buffers.
#[inline]
fn sort_by_start(ws: &mut Vec<Window>, runs: &mut Vec<u32>, merged: &mut Vec<Window>) {
    let n = ws.len();
    if n <= 24 {
        for i in 1..n {
            let mut j = i;
            while j > 0 && ws[j - 1].b0.total_cmp(&ws[j].b0) == Ordering::Greater {
                ws.swap(j - 1, j);
                j -= 1;
            }
        }
        return;
    }
    merge_runs_in_place(ws, runs, merged);
}

/// [`sort_by_start`] of a list longer than 24 windows: its ascending runs merged pass by pass
/// (kept out of line: the short lists' insertion sort stays small in `process`).
#[inline(never)]
fn merge_runs_in_place(ws: &mut Vec<Window>, runs: &mut Vec<u32>, merged: &mut Vec<Window>) {
    let n = ws.len();
    runs.clear();
    runs.push(0);
    for (i, p) in ws.windows(2).enumerate() {
        if p[0].b0.total_cmp(&p[1].b0) == Ordering::Greater {
            runs.push(i as u32 + 1);
        }
    }
    if runs.len() == 1 {
        return;
    }
    runs.push(n as u32);
    while runs.len() > 2 {
        merged.clear();
        let mut k = 0;
        let mut w = 1;
        while k + 1 < runs.len() {
            let (a, b) = (runs[k] as usize, runs[k + 1] as usize);
            if k + 2 < runs.len() {
                let c = runs[k + 2] as usize;
                merge_runs(&ws[a..b], &ws[b..c], merged);
                runs[w] = c as u32;
            } else {
                merged.extend_from_slice(&ws[a..b]);
                runs[w] = b as u32;
            }
            w += 1;
            k += 2;
        }
        runs.truncate(w);
        std::mem::swap(ws, merged);
    }
}

/// Appends the stable merge of the sorted runs `x` and `y` (by start, `total_cmp`; `x` first
/// on ties) to `out`.
#[inline]
fn merge_runs(x: &[Window], y: &[Window], out: &mut Vec<Window>) {
    let (mut i, mut j) = (0, 0);
    while i < x.len() && j < y.len() {
        if y[j].b0.total_cmp(&x[i].b0) == Ordering::Less {
            out.push(y[j]);
            j += 1;
        } else {
            out.push(x[i]);
            i += 1;
        }
    }
    out.extend_from_slice(&x[i..]);
    out.extend_from_slice(&y[j..]);
}

pub(super) fn classify_point(g: &ExactGeodesic, sp: &SurfacePoint) -> Result<Seed, GeodesicError> {
    let m = g.tris.len();
    if sp.face as usize >= m {
        return Err(meshcore::MeshError::FaceOutOfRange {
            face: sp.face,
            faces: m,
        }
        .into());
    }
    let b = sp.bary;
    if !b.is_finite() || b.min_element() < -1e-9 || (b.element_sum() - 1.0).abs() > 1e-9 {
        return Err(meshcore::MeshError::InvalidBarycentric(b.x, b.y, b.z).into());
    }
    let t = g.tris[sp.face as usize];
    if !g.live[sp.face as usize] {
        let pos = b.x * g.positions[t[0] as usize]
            + b.y * g.positions[t[1] as usize]
            + b.z * g.positions[t[2] as usize];
        return Ok(Seed::Degenerate { face: sp.face, pos });
    }
    let mut bb = [b.x.max(0.0), b.y.max(0.0), b.z.max(0.0)];
    for x in &mut bb {
        if *x < BARY_SNAP {
            *x = 0.0;
        }
    }
    let s: f64 = bb.iter().sum();
    if s <= 0.0 {
        return Err(meshcore::MeshError::InvalidBarycentric(b.x, b.y, b.z).into());
    }
    bb.iter_mut().for_each(|x| *x /= s);
    let zeros: Vec<usize> = (0..3).filter(|&k| bb[k] == 0.0).collect();
    match zeros.len() {
        0 => Ok(Seed::Face {
            face: sp.face,
            bary: bb,
            skip: NONE,
        }),
        1 => {
            // Edge point: the host half-edge is the one opposite the zero corner.
            let k = zeros[0] as u32;
            Ok(Seed::Face {
                face: sp.face,
                bary: bb,
                skip: 3 * sp.face + (k + 1) % 3,
            })
        }
        _ => {
            let k = (0..3).find(|&k| bb[k] > 0.0).unwrap_or(0);
            Ok(Seed::Vertex(t[k]))
        }
    }
}

/// Where the line from the source `(sx, sy)` through `(tx, ty)` meets the x axis of a child
/// edge's frame (the edge is `[0, ell]`), for the left and the right child edge alike; when
/// `sy - ty > -1e-15 ell` (no usable crossing), the end of the edge on the side of `tx`.
#[inline]
fn edge_crossing(sx: f64, sy: f64, tx: f64, ty: f64, ell: f64) -> f64 {
    let den = sy - ty;
    if den > -1e-15 * ell {
        if tx > sx {
            ell
        } else {
            0.0
        }
    } else {
        sx + (tx - sx) * sy / den
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Icosphere of `level` with radial jitter `amp` (relative).
    fn jittered_sphere(level: u32, amp: f64, seed: u64) -> TriMesh {
        let ico = meshcore::shapes::icosphere(level);
        let (mut v, f) = (ico.positions().to_vec(), ico.triangles().to_vec());
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        for p in &mut v {
            *p *= 1.0 + rng.random_range(-amp..=amp);
        }
        TriMesh::new(v, f).unwrap()
    }

    /// The list sort gives the order of a stable `sort_by` with `total_cmp` (ties in input
    /// order, -0 before +0, infinities), for short and long lists of few or many runs.
    #[test]
    fn sort_by_start_is_the_stable_sort() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut runs, mut merged) = (Vec::new(), Vec::new());
        for n in (0..120).chain([500, 2000]) {
            for kind in 0..5 {
                let ws: Vec<Window> = (0..n)
                    .map(|i| {
                        let b0 = match kind {
                            0 => rng.random_range(-1.0..1.0),
                            1 => f64::from(rng.random_range(0..5u32)) - 2.0,
                            2 => [0.0, -0.0, 1.0, f64::INFINITY, -f64::INFINITY][i % 5],
                            3 => (i % 17) as f64 + 0.5 * (i % 3) as f64,
                            _ => -(i as f64),
                        };
                        Window {
                            b0,
                            b1: b0,
                            sigma: 0.0,
                            sx: 0.0,
                            sy: -1.0,
                            id: i as u32,
                        }
                    })
                    .collect();
                let mut want = ws.clone();
                want.sort_by(|x, y| x.b0.total_cmp(&y.b0));
                let mut got = ws;
                sort_by_start(&mut got, &mut runs, &mut merged);
                let ids = |v: &[Window]| v.iter().map(|w| w.id).collect::<Vec<_>>();
                assert_eq!(ids(&got), ids(&want), "n {n} kind {kind}");
            }
        }
    }

    /// The pruned propagation equals the oracle mode (vertex filter only, no pairwise trim,
    /// no apex split) on small jittered spheres: the spec's most effective bug finders.
    #[test]
    fn pruning_is_sound_on_jittered_spheres() {
        let (mut total_pruned, mut total_oracle) = (0u64, 0u64);
        for (level, amp, seed) in [
            (2, 0.0, 0),
            (2, 0.005, 1),
            (2, 0.01, 2),
            (2, 0.03, 3),
            (3, 0.01, 4),
        ] {
            let m = jittered_sphere(level, amp, seed);
            let g = ExactGeodesic::new(&m).unwrap();
            for src in [0u32, 7, 100] {
                let run = |prune: bool| {
                    let mut s = Solve::new(&g, f64::INFINITY, false);
                    s.prune = prune;
                    s.seed(&[Source::Vertex(src)]).unwrap();
                    s.run();
                    (s.propagations, s.finish())
                };
                let (np, fast) = run(true);
                let (no, slow) = run(false);
                assert!(np <= no, "pruning should not add work: {np} > {no}");
                total_pruned += np;
                total_oracle += no;
                for v in 0..fast.len() {
                    assert!(
                        (fast[v] - slow[v]).abs() <= 1e-12 * slow[v].max(1.0),
                        "level {level} amp {amp} src {src} vertex {v}: {} vs {}",
                        fast[v],
                        slow[v]
                    );
                }
            }
        }
        // The oracle mode really propagates more (the rules under test were active).
        assert!(
            2 * total_pruned < total_oracle,
            "{total_pruned} vs {total_oracle}"
        );
    }
}
