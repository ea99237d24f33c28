//! Iterative closest point without correspondences: point-to-point (the paper's definition)
//! and point-to-plane, trimmed pairs, convergence test, and a global multi-start strategy
//! against local minima.
//!
//! Convention: `A` is the target (fixed, k-d tree), `B` the source; the result `R` maps
//! centred B onto centred A (`a ~ R b`). Both sets are centred on their own centroid
//! first, so the search is over SO(3) as in the paper's `inf_h ||S1 - h S2||`
//! (optionally a translation is estimated too).

#![allow(clippy::needless_range_loop)] // index loops read best in the 6x6 normal equations

use std::num::NonZero;
use std::sync::OnceLock;

use glam::{DAffine3, DMat3, DVec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use crate::error::{ShapeDistError, Which};
use crate::nn::{dist2, NeighbourGraph, PointTree, GROUP};
use crate::points::{centred, check_spread, outer, principal_axes, radius, validate};
use crate::target::{
    icp_to_target, Convergence, IcpLoopOptions, IcpTarget, Match, TrimRounding, CHUNK, PAR_MIN,
};
use meshcore::linalg::{rigid_inverse, sym_eigen3};

/// "No point" index.
const NONE: u32 = u32::MAX;

/// A point set prepared for repeated comparisons: centred, with k-d trees (the exact
/// nearest-neighbour [`PointTree`] of the ICP loop, and kiddo's tree for the k nearest
/// neighbours of the normals), the exact neighbour graph that lets most ICP correspondences
/// skip the tree ([`NeighbourGraph`]), a random subsample (and its tree and graph) for the
/// coarse global search, and lazily estimated normals.
#[derive(Debug)]
pub struct PreparedSet {
    points: Vec<DVec3>,
    centroid: DVec3,
    radius: f64,
    tree: ImmutableKdTree<f64, 3>,
    nn: PointTree,
    graph: NeighbourGraph,
    sub_points: Vec<DVec3>,
    sub_nn: PointTree,
    sub_graph: NeighbourGraph,
    normals_k: usize,
    normals: OnceLock<Vec<DVec3>>,
}

/// Options of [`PreparedSet::new`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PrepareOptions {
    /// Size of the random subsample used by the coarse global search (all points when the set
    /// is smaller).
    pub subsample: usize,
    /// Neighbours used for PCA normals (point-to-plane ICP).
    pub normals_k: usize,
    /// Seed of the subsample.
    pub seed: u64,
}

impl Default for PrepareOptions {
    fn default() -> Self {
        Self {
            subsample: 500,
            normals_k: 12,
            seed: 0x5eed,
        }
    }
}

fn build_tree(points: &[DVec3]) -> ImmutableKdTree<f64, 3> {
    let arr: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
    ImmutableKdTree::new_from_slice(&arr)
}

impl PreparedSet {
    /// Validates (non-empty, finite, not collinear), centres, and builds the search trees.
    pub fn new(
        points: &[DVec3],
        opts: &PrepareOptions,
        which: Which,
    ) -> Result<Self, ShapeDistError> {
        validate(points, which)?;
        let (pts, c) = centred(points);
        check_spread(&pts, which)?;
        let tree = build_tree(&pts);
        let sub_points = if pts.len() <= opts.subsample.max(3) {
            pts.clone()
        } else {
            let mut idx: Vec<usize> = (0..pts.len()).collect();
            idx.shuffle(&mut ChaCha8Rng::seed_from_u64(opts.seed));
            idx.truncate(opts.subsample.max(3));
            idx.sort_unstable();
            idx.iter().map(|&i| pts[i]).collect()
        };
        let sub_nn = PointTree::new(&sub_points);
        let nn = PointTree::new(&pts);
        // Built here rather than lazily: the build runs in parallel, and a lazy cell
        // initialised from inside a rayon task (a distance matrix) could be re-entered by a
        // stolen task of the same thread.
        let graph = NeighbourGraph::new(&nn);
        let sub_graph = NeighbourGraph::new(&sub_nn);
        Ok(Self {
            radius: radius(&pts),
            nn,
            graph,
            points: pts,
            centroid: c,
            tree,
            sub_points,
            sub_nn,
            sub_graph,
            normals_k: opts.normals_k.max(3),
            normals: OnceLock::new(),
        })
    }

    /// Centred points.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// Centroid of the input points.
    pub fn centroid(&self) -> DVec3 {
        self.centroid
    }

    /// `max |p - centroid|`.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Mean squared norm of the centred points.
    pub fn mean_sq_norm(&self) -> f64 {
        self.points.iter().map(|p| p.length_squared()).sum::<f64>() / self.points.len() as f64
    }

    /// Unit normals by PCA of the `normals_k` nearest neighbours (computed on first use; the
    /// sign is arbitrary, which point-to-plane does not care about).
    pub fn normals(&self) -> &[DVec3] {
        // Sequential on purpose: a once cell initialised with rayon inside a rayon task
        // (a distance matrix) could be re-entered by a task the same thread steals.
        self.normals.get_or_init(|| {
            let k = NonZero::new(self.normals_k.min(self.points.len()).max(1))
                .unwrap_or(NonZero::<usize>::MIN);
            self.points
                .iter()
                .map(|p| {
                    let nn = self.tree.nearest_n::<SquaredEuclidean>(&p.to_array(), k);
                    let m = nn
                        .iter()
                        .map(|n| self.points[n.item as usize])
                        .sum::<DVec3>()
                        / nn.len() as f64;
                    let cov = nn.iter().fold(DMat3::ZERO, |acc, n| {
                        let d = self.points[n.item as usize] - m;
                        acc + outer(d, d)
                    });
                    let (_, axes) = sym_eigen3(cov);
                    axes[2]
                })
                .collect()
        })
    }

    /// The exact neighbour graph of the centred points (used when the set is the target of
    /// an ICP run).
    pub fn graph(&self) -> &NeighbourGraph {
        &self.graph
    }

    /// The exact nearest-neighbour tree of the centred points (its leaf order is the order in
    /// which ICP visits the points of a source set).
    pub fn point_tree(&self) -> &PointTree {
        &self.nn
    }
}

meshcore::choice! {
    /// Point-to-point or point-to-plane error.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
    pub enum IcpVariant: "ICP variant", ShapeDistError {
        /// Besl & McKay: minimise the squared distances to the closest points (closed form per
        /// iteration).
        #[default]
        PointToPoint = "point" | "point-to-point",
        /// Chen & Medioni: minimise squared distances to the tangent planes of the target
        /// (linearised rotation per iteration); converges in far fewer iterations on surfaces.
        PointToPlane = "plane" | "point-to-plane",
    }
}

/// Options of one ICP run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IcpOptions {
    /// Error variant.
    pub variant: IcpVariant,
    /// Maximum number of iterations.
    pub max_iterations: usize,
    /// Stop when the relative change of the RMS pair distance is below this.
    pub tolerance: f64,
    /// Fraction of pairs with the largest distances rejected at each iteration (trimmed ICP),
    /// in [0, 0.9].
    pub trim: f64,
    /// Also estimate a translation (the paper's distance is over rotations only: `false`).
    pub translation: bool,
    /// Coarse-to-fine schedule: when > 0, first run up to this many iterations on the
    /// random subsamples of both sets ([`PrepareOptions::subsample`]), then the
    /// `max_iterations` on all points. Far fewer points are far from their partner on the
    /// full sets, which is where exact nearest-neighbour queries are expensive.
    pub coarse_iterations: usize,
}

impl Default for IcpOptions {
    fn default() -> Self {
        Self {
            variant: IcpVariant::PointToPoint,
            max_iterations: 50,
            tolerance: 1e-6,
            trim: 0.0,
            translation: false,
            coarse_iterations: 0,
        }
    }
}

/// Result of an ICP run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IcpResult {
    /// Rigid motion mapping centred B onto centred A (`a ~ motion * b`); the translation is
    /// zero unless [`IcpOptions::translation`].
    pub motion: DAffine3,
    /// Iterations run.
    pub iterations: usize,
    /// RMS distance of the kept pairs at the final pose.
    pub rmse: f64,
    /// Whether the convergence test was met (rather than the iteration limit).
    pub converged: bool,
    /// Iterations run on the subsamples first (see [`IcpOptions::coarse_iterations`]).
    pub coarse_iterations: usize,
    /// Nearest-neighbour answers the run needed on all points (source points times
    /// correspondence passes, the final evaluation included).
    pub pair_searches: usize,
    /// How many of them needed a tree query; the others kept their partner because the point
    /// had not left its safe radius (exact: the same partner a query would find).
    pub tree_queries: usize,
}

impl IcpOptions {
    /// The options of the generic loop ([`icp_to_target`]) that run these: no gates, trim
    /// count rounded up, damping `1e-12 tr`, relative RMS convergence before the step.
    pub fn loop_options(&self) -> IcpLoopOptions {
        IcpLoopOptions {
            variant: self.variant,
            max_iterations: self.max_iterations,
            translation: self.translation,
            trim: self.trim,
            trim_rounding: TrimRounding::Up,
            convergence: Convergence::RelativeRmse {
                tolerance: self.tolerance,
            },
            ..IcpLoopOptions::default()
        }
    }
}

/// Graph moves allowed per point and iteration before falling back to a tree query.
const MAX_STEPS: usize = 8;

/// Iterations in which a point whose graph walk was not certified goes straight to the tree
/// (far from the target surface the certificate rarely holds, and the walk would be wasted).
const BACKOFF: u8 = 3;

/// Correspondence search over one chunk of source points: for each (transformed) source
/// point, the exact nearest target point `(squared distance, index)`, the lexicographic
/// minimum as [`crate::nn::nearest_brute_force`] defines it.
///
/// With `warm` (`out` holds the previous correspondences) and a target neighbour graph, a
/// point first walks the graph from its previous partner ([`NeighbourGraph::descend`]); where
/// the walk ends with a certificate, that is the exact answer without a tree query. The
/// other points are answered by the tree, in groups, seeded with the walk's end (or, without
/// a previous partner, the partner of the preceding source point: the source is in a
/// spatially coherent order). Seeds only bound the search, the result is the same exact
/// minimum. Returns the number of tree queries.
#[inline]
fn correspond_chunk(
    pass: &Pass<'_>,
    src: &[DVec3],
    out: &mut [(f64, u32)],
    skip: &mut [u8],
) -> usize {
    let Pass {
        tree,
        graph,
        tgt,
        r,
        t,
        warm,
    } = *pass;
    let mut prev = NONE;
    let mut queries = 0;
    let mut ps = [DVec3::ZERO; GROUP];
    let mut seeds = [(f64::INFINITY, NONE); GROUP];
    let mut slot = [0usize; GROUP];
    for ((o, sk), b) in out
        .chunks_mut(GROUP)
        .zip(skip.chunks_mut(GROUP))
        .zip(src.chunks(GROUP))
    {
        let g = o.len().min(b.len()).min(sk.len());
        let mut nq = 0;
        for k in 0..g {
            let p = r * b[k] + t;
            let j = if warm && o[k].1 != NONE { o[k].1 } else { prev };
            let walk = warm && o[k].1 != NONE && sk[k] == 0;
            if sk[k] > 0 {
                sk[k] -= 1;
            }
            let seed = match (graph, walk) {
                (Some(gr), true) => {
                    let (found, certain) = gr.descend(p, j, MAX_STEPS);
                    if certain {
                        o[k] = found;
                        continue;
                    }
                    sk[k] = BACKOFF;
                    found
                }
                _ if j == NONE => (f64::INFINITY, NONE),
                _ => (dist2(tgt[j as usize], p), j),
            };
            ps[nq] = p;
            seeds[nq] = seed;
            slot[nq] = k;
            nq += 1;
        }
        if nq > 0 {
            tree.nearest_group(&ps[..nq], &mut seeds[..nq]);
            for m in 0..nq {
                o[slot[m]] = seeds[m];
            }
            queries += nq;
        }
        prev = o[g - 1].1;
    }
    queries
}

/// What the chunks of one correspondence pass share: the target's tree, neighbour graph and
/// points, the source pose `(r, t)`, and whether `out` holds the previous partners.
#[derive(Clone, Copy)]
struct Pass<'a> {
    tree: &'a PointTree,
    graph: Option<&'a NeighbourGraph>,
    tgt: &'a [DVec3],
    r: DMat3,
    t: DVec3,
    warm: bool,
}

/// Correspondences of all source points (see [`correspond_chunk`]), chunk by chunk (in
/// parallel when `parallel`); returns the number of tree queries.
fn correspond(
    pass: &Pass<'_>,
    src: &[DVec3],
    out: &mut [(f64, u32)],
    skip: &mut [u8],
    parallel: bool,
) -> usize {
    type Part<'a> = ((&'a mut [(f64, u32)], &'a mut [u8]), &'a [DVec3]);
    let run = |((o, k), s): Part<'_>| correspond_chunk(pass, s, o, k);
    if parallel {
        out.par_chunks_mut(CHUNK)
            .zip(skip.par_chunks_mut(CHUNK))
            .zip(src.par_chunks(CHUNK))
            .map(run)
            .sum()
    } else {
        out.chunks_mut(CHUNK)
            .zip(skip.chunks_mut(CHUNK))
            .zip(src.chunks(CHUNK))
            .map(run)
            .sum()
    }
}

/// One point set of a [`PreparedSet`] as an ICP target: all points (with the lazily
/// estimated normals) or the subsample of the coarse search (no normals, one thread).
#[derive(Clone, Copy)]
struct SetTarget<'a> {
    set: &'a PreparedSet,
    sub: bool,
}

/// Warm-start state of a run onto a [`PreparedSet`]: the previous partners `(squared
/// distance, index)`, the graph-walk back-off counters and whether a pass has run.
#[derive(Debug)]
pub struct SetState {
    corr: Vec<(f64, u32)>,
    skip: Vec<u8>,
    warm: bool,
}

impl SetTarget<'_> {
    fn parts(&self) -> (&[DVec3], &PointTree, &NeighbourGraph) {
        if self.sub {
            (&self.set.sub_points, &self.set.sub_nn, &self.set.sub_graph)
        } else {
            (&self.set.points, &self.set.nn, &self.set.graph)
        }
    }
}

impl IcpTarget for SetTarget<'_> {
    type State = SetState;

    fn start(&self, n: usize) -> SetState {
        SetState {
            corr: vec![(f64::INFINITY, NONE); n],
            skip: vec![0; n],
            warm: false,
        }
    }

    fn has_normals(&self) -> bool {
        !self.sub
    }

    fn correspond(
        &self,
        src: &[DVec3],
        pose: &DAffine3,
        normals: bool,
        st: &mut SetState,
        out: &mut [Match],
    ) -> Result<usize, ShapeDistError> {
        let (pts, tree, graph) = self.parts();
        let parallel = !self.sub && src.len() >= PAR_MIN;
        let pass = Pass {
            tree,
            graph: Some(graph),
            tgt: pts,
            r: pose.matrix3,
            t: pose.translation,
            warm: st.warm,
        };
        let nq = correspond(&pass, src, &mut st.corr, &mut st.skip, parallel);
        st.warm = true;
        let nrm = (normals && !self.sub).then(|| self.set.normals());
        for (o, c) in out.iter_mut().zip(&st.corr) {
            let j = c.1 as usize;
            *o = Match {
                d2: c.0,
                point: pts[j],
                normal: nrm.map_or(DVec3::ZERO, |n| n[j]),
            };
        }
        Ok(nq)
    }
}

/// The centred points of the set, exact nearest points (the same answers as brute force,
/// ties to the lowest index), PCA normals ([`PreparedSet::normals`]).
impl IcpTarget for PreparedSet {
    type State = SetState;

    fn start(&self, n: usize) -> SetState {
        SetTarget {
            set: self,
            sub: false,
        }
        .start(n)
    }

    fn has_normals(&self) -> bool {
        true
    }

    fn correspond(
        &self,
        src: &[DVec3],
        pose: &DAffine3,
        normals: bool,
        st: &mut SetState,
        out: &mut [Match],
    ) -> Result<usize, ShapeDistError> {
        SetTarget {
            set: self,
            sub: false,
        }
        .correspond(src, pose, normals, st, out)
    }
}

/// Runs [`icp_to_target`] of `src` onto one set of `a` from the rotation and translation
/// `(r, t)`.
fn run_set(
    a: &PreparedSet,
    sub: bool,
    src: &[DVec3],
    r: DMat3,
    t: DVec3,
    o: &IcpOptions,
) -> Result<IcpResult, ShapeDistError> {
    icp_to_target(
        &SetTarget { set: a, sub },
        src,
        None,
        DAffine3::from_mat3_translation(r, t),
        &o.loop_options(),
    )
}

/// One ICP run of B onto A from the rotation `init` (about the centroids): [`icp_to_target`]
/// with [`IcpOptions::loop_options`], B's points in the leaf order of its tree.
pub fn icp(
    a: &PreparedSet,
    b: &PreparedSet,
    init: DMat3,
    opts: &IcpOptions,
) -> Result<IcpResult, ShapeDistError> {
    if !init.is_finite() {
        return Err(ShapeDistError::InvalidOption(
            "initial rotation is not finite".into(),
        ));
    }
    let (mut r0, mut t0, mut coarse_it) = (init, DVec3::ZERO, 0);
    if opts.coarse_iterations > 0 {
        let c = run_set(
            a,
            true,
            b.sub_nn.leaf_order_points(),
            init,
            DVec3::ZERO,
            &IcpOptions {
                variant: IcpVariant::PointToPoint,
                max_iterations: opts.coarse_iterations,
                ..*opts
            },
        )?;
        (r0, t0, coarse_it) = (c.motion.matrix3, c.motion.translation, c.iterations);
    }
    let mut res = run_set(a, false, b.nn.leaf_order_points(), r0, t0, opts)?;
    res.coarse_iterations = coarse_it;
    Ok(res)
}

/// Options of the global strategy.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GlobalOptions {
    /// Iterations of point-to-point ICP from each start on the subsamples.
    pub coarse_iterations: usize,
    /// Also start from the 24 rotations of the cube group (a uniform grid; every rotation is
    /// within 62.8 degrees of one of them) besides the 4 principal-axes alignments.
    pub grid: bool,
    /// Refine the best coarse candidates (whose subsample RMS is within this factor of the
    /// best one, at most 2 of them, distinct by more than 10 degrees) on all points.
    pub refine_ratio: f64,
    /// Point-to-plane iterations on all points before the final refinement (0 = none);
    /// brings the pose close quickly when the final variant is point-to-point.
    pub plane_warmup: usize,
    /// Options of the final refinement on all points.
    pub refine: IcpOptions,
}

impl Default for GlobalOptions {
    fn default() -> Self {
        Self {
            coarse_iterations: 30,
            grid: true,
            refine_ratio: 1.15,
            plane_warmup: 0,
            refine: IcpOptions {
                max_iterations: 100,
                ..IcpOptions::default()
            },
        }
    }
}

/// Result of [`global_icp`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GlobalResult {
    /// Final ICP result on all points.
    pub icp: IcpResult,
    /// Number of starting rotations tried on the subsamples.
    pub starts: usize,
    /// Subsample RMS of the best start.
    pub coarse_rmse: f64,
    /// Number of candidates refined on all points.
    pub refined: usize,
}

/// The 24 rotations of the cube (signed permutation matrices with determinant +1).
pub fn cube_group() -> Vec<DMat3> {
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut out = Vec::with_capacity(24);
    for p in perms {
        for s in 0..8u32 {
            let sg = |i: u32| if s >> i & 1 == 1 { -1.0 } else { 1.0 };
            let mut cols = [DVec3::ZERO; 3];
            for (row, &col) in p.iter().enumerate() {
                cols[col][row] = sg(row as u32);
            }
            let m = DMat3::from_cols(cols[0], cols[1], cols[2]);
            if m.determinant() > 0.0 {
                out.push(m);
            }
        }
    }
    out
}

/// The 4 rotations aligning the principal axes of B with those of A (the sign ambiguity of
/// the axes leaves 4 proper choices).
pub fn principal_axes_starts(a: &[DVec3], b: &[DVec3]) -> Vec<DMat3> {
    let frame = |p: &[DVec3]| {
        let (_, ax) = principal_axes(p);
        let m = DMat3::from_cols(ax[0], ax[1], ax[2]);
        if m.determinant() < 0.0 {
            DMat3::from_cols(ax[0], ax[1], -ax[2])
        } else {
            m
        }
    };
    let (fa, fb) = (frame(a), frame(b));
    [
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ]
    .iter()
    .map(|s| fa * DMat3::from_diagonal(DVec3::from_array(*s)) * fb.transpose())
    .collect()
}

/// Global ICP: point-to-point ICP from every start (principal axes and optionally the cube
/// group) on the subsamples, in parallel; the best candidates are refined on all points and
/// the lowest final RMS wins.
pub fn global_icp(
    a: &PreparedSet,
    b: &PreparedSet,
    opts: &GlobalOptions,
) -> Result<GlobalResult, ShapeDistError> {
    crate::target::check(&opts.refine.loop_options(), 0, None)?;
    let mut starts = principal_axes_starts(&a.points, &b.points);
    if opts.grid {
        starts.extend(cube_group());
    }
    let coarse_opts = IcpOptions {
        variant: IcpVariant::PointToPoint,
        max_iterations: opts.coarse_iterations.max(1),
        tolerance: 1e-4,
        trim: opts.refine.trim,
        translation: opts.refine.translation,
        coarse_iterations: 0,
    };
    let mut coarse: Vec<(usize, IcpResult)> = starts
        .par_iter()
        .enumerate()
        .map(|(i, &r0)| {
            let src = b.sub_nn.leaf_order_points();
            run_set(a, true, src, r0, DVec3::ZERO, &coarse_opts).map(|c| (i, c))
        })
        .collect::<Result<_, _>>()?;
    coarse.sort_by(|x, y| x.1.rmse.total_cmp(&y.1.rmse).then(x.0.cmp(&y.0)));
    let best = coarse[0].1.rmse;
    let mut cands: Vec<IcpResult> = Vec::new();
    for (_, c) in &coarse {
        if cands.len() >= 2 || c.rmse > best * opts.refine_ratio.max(1.0) + 1e-300 {
            break;
        }
        if cands.iter().all(|d| {
            meshcore::linalg::rotation_angle_between(d.motion.matrix3, c.motion.matrix3)
                > 10f64.to_radians()
        }) {
            cands.push(*c);
        }
    }
    let mut finals = Vec::with_capacity(cands.len());
    for c in &cands {
        let (mut r, mut t) = (c.motion.matrix3, c.motion.translation);
        let src = b.nn.leaf_order_points();
        if opts.plane_warmup > 0 {
            let warm = IcpOptions {
                variant: IcpVariant::PointToPlane,
                max_iterations: opts.plane_warmup,
                tolerance: 1e-6,
                ..opts.refine
            };
            let w = run_set(a, false, src, r, t, &warm)?;
            r = w.motion.matrix3;
            t = w.motion.translation;
        }
        finals.push(run_set(a, false, src, r, t, &opts.refine)?);
    }
    let refined = finals.len();
    let icp = finals
        .into_iter()
        .min_by(|x, y| x.rmse.total_cmp(&y.rmse))
        .ok_or_else(|| ShapeDistError::InvalidOption("no ICP candidate".into()))?;
    Ok(GlobalResult {
        icp,
        starts: starts.len(),
        coarse_rmse: best,
        refined,
    })
}

/// Closest-point statistics of two centred sets after a rigid motion of B.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ClosestPointStats {
    /// Symmetric Hausdorff distance `max(max_a min_b, max_b min_a)`.
    pub hausdorff: f64,
    /// Symmetric mean closest-point distance `(mean_b min_a + mean_a min_b) / 2`.
    pub mean: f64,
    /// Symmetric RMS closest-point distance `sqrt((mean_b min_a^2 + mean_a min_b^2) / 2)`.
    pub rms: f64,
    /// `hausdorff / (rho_A + rho_B)`, in [0, 1].
    pub hausdorff_normalised: f64,
    /// `mean / (rho_A + rho_B)`, in [0, 1].
    pub mean_normalised: f64,
    /// `rms / sqrt(mean|a|^2 + mean|b|^2)`, in [0, 1] (the closest-point analogue of the
    /// keyed L2 distance).
    pub rms_normalised: f64,
}

/// Evaluates [`ClosestPointStats`] for the pose `a ~ motion * b` of centred sets (`motion`
/// rigid).
pub fn closest_point_stats(
    a: &PreparedSet,
    b: &PreparedSet,
    motion: &DAffine3,
) -> ClosestPointStats {
    let dir = |tgt: &PreparedSet, src: &[DVec3], r: DMat3, t: DVec3| -> (f64, f64, f64) {
        // Per-chunk partial sums added in chunk order: deterministic whatever the threads.
        let parts: Vec<(f64, f64, f64)> = src
            .par_chunks(CHUNK)
            .map(|ch| {
                ch.iter().fold((0.0f64, 0.0f64, 0.0f64), |(mx, s, s2), p| {
                    let (d2, _) = tgt.nn.nearest(r * *p + t);
                    let d = d2.sqrt();
                    (mx.max(d), s + d, s2 + d2)
                })
            })
            .collect();
        parts
            .into_iter()
            .fold((0.0, 0.0, 0.0), |x, y| (x.0.max(y.0), x.1 + y.1, x.2 + y.2))
    };
    let (mb, sb, s2b) = dir(
        a,
        b.nn.leaf_order_points(),
        motion.matrix3,
        motion.translation,
    );
    let inv = rigid_inverse(motion);
    let (ma, sa, s2a) = dir(b, a.nn.leaf_order_points(), inv.matrix3, inv.translation);
    let (na, nb) = (a.points.len() as f64, b.points.len() as f64);
    let hausdorff = ma.max(mb);
    let mean = 0.5 * (sb / nb + sa / na);
    let ms = 0.5 * (s2b / nb + s2a / na);
    let rho = a.radius + b.radius;
    let norm2 = a.mean_sq_norm() + b.mean_sq_norm();
    let div = |x: f64, d: f64| {
        if d > 0.0 {
            (x / d).clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    ClosestPointStats {
        hausdorff,
        mean,
        rms: ms.sqrt(),
        hausdorff_normalised: div(hausdorff, rho),
        mean_normalised: div(mean, rho),
        rms_normalised: div(ms, norm2).sqrt(),
    }
}
