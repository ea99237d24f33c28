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

use glam::{DMat3, DVec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use crate::error::{ShapeDistError, Which};
use meshcore::linalg::{axis_angle, kabsch_rotation, solve_sym, sym_eigen3};
use crate::nn::{dist2, NeighbourGraph, PointTree, GROUP};
use crate::points::{centred, check_spread, outer, principal_axes, radius, validate};

/// Below this many source points the correspondence search runs on one thread (rayon's
/// overhead dominates; the global search parallelises over starts instead).
const PAR_MIN: usize = 2048;

/// Source points per work unit. Partial sums are formed per chunk and added in chunk order,
/// whatever the number of threads, so results do not depend on the thread count.
const CHUNK: usize = 512;

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

    fn sub_graph(&self) -> &NeighbourGraph {
        &self.sub_graph
    }

    /// The exact nearest-neighbour tree of the centred points (its leaf order is the order in
    /// which ICP visits the points of a source set).
    pub fn point_tree(&self) -> &PointTree {
        &self.nn
    }
}

/// Point-to-point or point-to-plane error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub enum IcpVariant {
    /// Besl & McKay: minimise the squared distances to the closest points (closed form per
    /// iteration).
    #[default]
    PointToPoint,
    /// Chen & Medioni: minimise squared distances to the tangent planes of the target
    /// (linearised rotation per iteration); converges in far fewer iterations on surfaces.
    PointToPlane,
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
    /// Rotation mapping centred B onto centred A.
    pub rotation: DMat3,
    /// Translation after the rotation (zero unless [`IcpOptions::translation`]).
    pub translation: DVec3,
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

fn check_icp_options(o: &IcpOptions) -> Result<(), ShapeDistError> {
    if !(0.0..=0.9).contains(&o.trim) {
        return Err(ShapeDistError::InvalidOption(format!(
            "trim fraction must be in [0, 0.9], got {}",
            o.trim
        )));
    }
    if o.tolerance.is_nan() || o.tolerance < 0.0 || o.max_iterations == 0 {
        return Err(ShapeDistError::InvalidOption(
            "tolerance must be >= 0 and max_iterations >= 1".into(),
        ));
    }
    Ok(())
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
/// minimum. With `accumulate`, also returns the sums of all pairs (fused pass of the
/// untrimmed point-to-point step). The second return value counts the tree queries.
#[allow(clippy::too_many_arguments)]
#[inline]
fn correspond_chunk(
    tree: &PointTree,
    graph: Option<&NeighbourGraph>,
    tgt: &[DVec3],
    src: &[DVec3],
    r: DMat3,
    t: DVec3,
    out: &mut [(f64, u32)],
    skip: &mut [u8],
    warm: bool,
    accumulate: bool,
) -> (Sums, usize) {
    let mut s = Sums::ZERO;
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
        if accumulate {
            for k in 0..g {
                s.push(tgt[o[k].1 as usize], b[k], o[k].0);
            }
        }
    }
    (s, queries)
}

/// Correspondences of all source points (see [`correspond_chunk`]); returns the sums of all
/// pairs when `accumulate` (added chunk by chunk in order: deterministic) and the number of
/// tree queries.
#[allow(clippy::too_many_arguments)]
fn correspond(
    tree: &PointTree,
    graph: Option<&NeighbourGraph>,
    tgt: &[DVec3],
    src: &[DVec3],
    r: DMat3,
    t: DVec3,
    out: &mut [(f64, u32)],
    skip: &mut [u8],
    parallel: bool,
    warm: bool,
    accumulate: bool,
) -> (Sums, usize) {
    type Part<'a> = ((&'a mut [(f64, u32)], &'a mut [u8]), &'a [DVec3]);
    let run =
        |((o, k), s): Part<'_>| correspond_chunk(tree, graph, tgt, s, r, t, o, k, warm, accumulate);
    let add = |x: (Sums, usize), y: (Sums, usize)| (x.0.add(y.0), x.1 + y.1);
    if parallel {
        let parts: Vec<(Sums, usize)> = out
            .par_chunks_mut(CHUNK)
            .zip(skip.par_chunks_mut(CHUNK))
            .zip(src.par_chunks(CHUNK))
            .map(run)
            .collect();
        parts.into_iter().fold((Sums::ZERO, 0), add)
    } else {
        out.chunks_mut(CHUNK)
            .zip(skip.chunks_mut(CHUNK))
            .zip(src.chunks(CHUNK))
            .map(run)
            .fold((Sums::ZERO, 0), add)
    }
}

/// Squared-distance threshold keeping the `(1 - trim)` closest pairs (`inf` = keep all).
fn trim_threshold(corr: &[(f64, u32)], trim: f64, scratch: &mut Vec<f64>) -> f64 {
    if trim <= 0.0 {
        return f64::INFINITY;
    }
    let keep = ((corr.len() as f64) * (1.0 - trim)).ceil().max(3.0) as usize;
    if keep >= corr.len() {
        return f64::INFINITY;
    }
    scratch.clear();
    scratch.extend(corr.iter().map(|c| c.0));
    let (_, kth, _) = scratch.select_nth_unstable_by(keep - 1, f64::total_cmp);
    *kth
}

#[derive(Clone, Copy)]
struct Sums {
    n: f64,
    ss: f64,
    sa: DVec3,
    sb: DVec3,
    k: DMat3,
}

impl Sums {
    const ZERO: Sums = Sums {
        n: 0.0,
        ss: 0.0,
        sa: DVec3::ZERO,
        sb: DVec3::ZERO,
        k: DMat3::ZERO,
    };
    #[inline(always)]
    fn push(&mut self, a: DVec3, b: DVec3, d2: f64) {
        self.n += 1.0;
        self.ss += d2;
        self.sa += a;
        self.sb += b;
        self.k += outer(a, b);
    }
    fn add(self, o: Sums) -> Sums {
        Sums {
            n: self.n + o.n,
            ss: self.ss + o.ss,
            sa: self.sa + o.sa,
            sb: self.sb + o.sb,
            k: self.k + o.k,
        }
    }
}

/// Runs ICP of `src` (centred B, or a subsample, in any order) onto a target given by its
/// points, tree and (for point-to-plane) normals, from the initial rotation `init`.
#[allow(clippy::too_many_arguments)]
fn icp_core(
    tgt_pts: &[DVec3],
    tree: &PointTree,
    graph: Option<&NeighbourGraph>,
    normals: Option<&[DVec3]>,
    src: &[DVec3],
    init: DMat3,
    init_t: DVec3,
    o: &IcpOptions,
    parallel: bool,
) -> IcpResult {
    let parallel = parallel && src.len() >= PAR_MIN;
    let plane = o.variant == IcpVariant::PointToPlane && normals.is_some();
    // Untrimmed point-to-point: the sums of the closed-form step are accumulated in the
    // correspondence pass itself (one pass over the source per iteration).
    let fused = !plane && o.trim <= 0.0;
    let mut r = init;
    let mut t = init_t;
    let mut corr = vec![(f64::INFINITY, NONE); src.len()];
    let mut skip = vec![0u8; src.len()];
    let mut queries = 0;
    let mut scratch = Vec::new();
    let mut prev_rmse = f64::INFINITY;
    let mut rmse = f64::INFINITY;
    let mut iterations = 0;
    let mut converged = false;
    while iterations < o.max_iterations {
        let (all, nq) = correspond(
            tree,
            graph,
            tgt_pts,
            src,
            r,
            t,
            &mut corr,
            &mut skip,
            parallel,
            iterations > 0,
            fused,
        );
        queries += nq;
        iterations += 1;
        // Statistics of the kept pairs at the current pose.
        let (thr, kept) = if fused {
            (f64::INFINITY, all)
        } else {
            let thr = trim_threshold(&corr, o.trim, &mut scratch);
            (thr, kept_sums(tgt_pts, src, &corr, thr, parallel))
        };
        rmse = (kept.ss / kept.n.max(1.0)).sqrt();
        if rmse == 0.0
            || (prev_rmse.is_finite() && (prev_rmse - rmse).abs() <= o.tolerance * prev_rmse)
        {
            converged = true;
            break;
        }
        prev_rmse = rmse;
        let (nr, nt) = match (o.variant, normals) {
            (IcpVariant::PointToPlane, Some(nrm)) => {
                plane_step(tgt_pts, nrm, src, &corr, thr, r, t, o.translation)
            }
            _ => point_step(&kept, r, t, o.translation),
        };
        r = nr;
        t = nt;
    }
    if !converged {
        // Report the error at the returned pose.
        let (all, nq) = correspond(
            tree, graph, tgt_pts, src, r, t, &mut corr, &mut skip, parallel, true, fused,
        );
        queries += nq;
        let kept = if fused {
            all
        } else {
            let thr = trim_threshold(&corr, o.trim, &mut scratch);
            kept_sums(tgt_pts, src, &corr, thr, parallel)
        };
        rmse = (kept.ss / kept.n.max(1.0)).sqrt();
    }
    IcpResult {
        rotation: r,
        translation: t,
        iterations,
        rmse,
        converged,
        coarse_iterations: 0,
        pair_searches: src.len() * (iterations + usize::from(!converged)),
        tree_queries: queries,
    }
}

/// Sums over the pairs whose squared distance is at most `thr` (chunked, added in order).
fn kept_sums(tgt: &[DVec3], src: &[DVec3], corr: &[(f64, u32)], thr: f64, parallel: bool) -> Sums {
    let run = |(c, b): (&[(f64, u32)], &[DVec3])| {
        let mut s = Sums::ZERO;
        for (c, b) in c.iter().zip(b) {
            if c.0 <= thr {
                s.push(tgt[c.1 as usize], *b, c.0);
            }
        }
        s
    };
    if parallel {
        let parts: Vec<Sums> = corr
            .par_chunks(CHUNK)
            .zip(src.par_chunks(CHUNK))
            .map(run)
            .collect();
        parts.into_iter().fold(Sums::ZERO, Sums::add)
    } else {
        corr.chunks(CHUNK)
            .zip(src.chunks(CHUNK))
            .map(run)
            .fold(Sums::ZERO, Sums::add)
    }
}

/// Closed-form point-to-point update from the sums of the kept pairs (`a ~ R b (+ t)`).
fn point_step(s: &Sums, r: DMat3, t: DVec3, translation: bool) -> (DMat3, DVec3) {
    if s.n < 3.0 {
        return (r, t);
    }
    let mut k = s.k;
    if translation {
        let (ma, mb) = (s.sa / s.n, s.sb / s.n);
        k -= outer(ma, mb) * s.n;
        let (nr, _) = kabsch_rotation(k);
        (nr, ma - nr * mb)
    } else {
        (kabsch_rotation(k).0, DVec3::ZERO)
    }
}

#[allow(clippy::too_many_arguments)]
fn plane_step(
    tgt: &[DVec3],
    nrm: &[DVec3],
    src: &[DVec3],
    corr: &[(f64, u32)],
    thr: f64,
    r: DMat3,
    t: DVec3,
    translation: bool,
) -> (DMat3, DVec3) {
    // Residual (p - a).n + w.(p x n) + d.n, p = R b + t; unknowns w (and d).
    let mut ata = [[0.0; 6]; 6];
    let mut atb = [0.0; 6];
    for (c, b) in corr.iter().zip(src) {
        if c.0 > thr {
            continue;
        }
        let j = c.1 as usize;
        let (a, n) = (tgt[j], nrm[j]);
        let p = r * *b + t;
        let cr = p.cross(n);
        let row = [cr.x, cr.y, cr.z, n.x, n.y, n.z];
        let res = (p - a).dot(n);
        for u in 0..6 {
            for v in u..6 {
                ata[u][v] += row[u] * row[v];
            }
            atb[u] -= row[u] * res;
        }
    }
    for u in 0..6 {
        for v in 0..u {
            ata[u][v] = ata[v][u];
        }
    }
    let tr: f64 = (0..6).map(|i| ata[i][i]).sum();
    let reg = tr * 1e-12 + f64::MIN_POSITIVE;
    let (w, d) = if translation {
        let mut m = ata;
        (0..6).for_each(|i| m[i][i] += reg);
        match solve_sym(m, atb) {
            Some(x) => (DVec3::new(x[0], x[1], x[2]), DVec3::new(x[3], x[4], x[5])),
            None => return (r, t),
        }
    } else {
        let mut m = [[0.0; 3]; 3];
        for u in 0..3 {
            for v in 0..3 {
                m[u][v] = ata[u][v];
            }
            m[u][u] += reg;
        }
        match solve_sym(m, [atb[0], atb[1], atb[2]]) {
            Some(x) => (DVec3::new(x[0], x[1], x[2]), DVec3::ZERO),
            None => return (r, t),
        }
    };
    let dr = axis_angle(w, w.length());
    let nr = meshcore::linalg::orthonormalise(dr * r);
    let nt = if translation { dr * t + d } else { DVec3::ZERO };
    (nr, nt)
}

/// One ICP run of B onto A from the rotation `init` (about the centroids).
pub fn icp(
    a: &PreparedSet,
    b: &PreparedSet,
    init: DMat3,
    opts: &IcpOptions,
) -> Result<IcpResult, ShapeDistError> {
    check_icp_options(opts)?;
    if !init.is_finite() {
        return Err(ShapeDistError::InvalidOption(
            "initial rotation is not finite".into(),
        ));
    }
    let normals = (opts.variant == IcpVariant::PointToPlane).then(|| a.normals());
    let (mut r0, mut t0, mut coarse_it) = (init, DVec3::ZERO, 0);
    if opts.coarse_iterations > 0 {
        let c = icp_core(
            &a.sub_points,
            &a.sub_nn,
            Some(a.sub_graph()),
            None,
            b.sub_nn.leaf_order_points(),
            init,
            DVec3::ZERO,
            &IcpOptions {
                variant: IcpVariant::PointToPoint,
                max_iterations: opts.coarse_iterations,
                ..*opts
            },
            false,
        );
        (r0, t0, coarse_it) = (c.rotation, c.translation, c.iterations);
    }
    let mut res = icp_core(
        &a.points,
        &a.nn,
        Some(a.graph()),
        normals,
        b.nn.leaf_order_points(),
        r0,
        t0,
        opts,
        true,
    );
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
    check_icp_options(&opts.refine)?;
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
            (
                i,
                icp_core(
                    &a.sub_points,
                    &a.sub_nn,
                    Some(a.sub_graph()),
                    None,
                    b.sub_nn.leaf_order_points(),
                    r0,
                    DVec3::ZERO,
                    &coarse_opts,
                    false,
                ),
            )
        })
        .collect();
    coarse.sort_by(|x, y| x.1.rmse.total_cmp(&y.1.rmse).then(x.0.cmp(&y.0)));
    let best = coarse[0].1.rmse;
    let mut cands: Vec<IcpResult> = Vec::new();
    for (_, c) in &coarse {
        if cands.len() >= 2 || c.rmse > best * opts.refine_ratio.max(1.0) + 1e-300 {
            break;
        }
        if cands.iter().all(|d| {
            meshcore::linalg::rotation_angle_between(d.rotation, c.rotation) > 10f64.to_radians()
        }) {
            cands.push(*c);
        }
    }
    let mut finals = Vec::with_capacity(cands.len());
    for c in &cands {
        let (mut r, mut t) = (c.rotation, c.translation);
        if opts.plane_warmup > 0 {
            let w = icp_core(
                &a.points,
                &a.nn,
                Some(a.graph()),
                Some(a.normals()),
                b.nn.leaf_order_points(),
                r,
                t,
                &IcpOptions {
                    variant: IcpVariant::PointToPlane,
                    max_iterations: opts.plane_warmup,
                    tolerance: 1e-6,
                    ..opts.refine
                },
                true,
            );
            r = w.rotation;
            t = w.translation;
        }
        let normals = (opts.refine.variant == IcpVariant::PointToPlane).then(|| a.normals());
        finals.push(icp_core(
            &a.points,
            &a.nn,
            Some(a.graph()),
            normals,
            b.nn.leaf_order_points(),
            r,
            t,
            &opts.refine,
            true,
        ));
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

/// Closest-point statistics of two centred sets after the rotation `r` (B moved by `r`).
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

/// Evaluates [`ClosestPointStats`] for the pose `a ~ r b + t` of centred sets.
pub fn closest_point_stats(
    a: &PreparedSet,
    b: &PreparedSet,
    r: DMat3,
    t: DVec3,
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
    let (mb, sb, s2b) = dir(a, b.nn.leaf_order_points(), r, t);
    let rt = r.transpose();
    let (ma, sa, s2a) = dir(b, a.nn.leaf_order_points(), rt, -(rt * t));
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
