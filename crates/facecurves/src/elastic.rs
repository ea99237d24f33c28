//! The elastic distance between two 3D curves by their square-root velocity functions
//! (Srivastava, Klassen, Joshi and Jermyn, "Shape analysis of elastic curves in Euclidean
//! spaces"; Joshi et al. for closed curves).
//!
//! A curve `beta: [0, 1] -> R^3` is represented by its SRVF `q = beta' / sqrt(|beta'|)`; the
//! elastic metric becomes the L2 metric, `||q||^2` is the length of the curve, translations
//! vanish with the derivative, a rotation acts as `R q` and a reparametrisation `gamma` as
//! `(q o gamma) sqrt(gamma')`, an isometry. The distance is
//!
//! `d(a, b) = min over R in SO(3), gamma, start point of ||q_a - R (q_b o gamma) sqrt(gamma')||`
//!
//! computed as follows:
//!
//! 1. Each curve is resampled into `samples` segments ([`Resampling`]); its SRVF is constant on
//!    each segment, `q_s = sqrt(m) dp_s / sqrt(|dp_s|)` (`m` segments), so `||q||^2` equals the
//!    polyline length exactly. With `scale`, the curves are first scaled to unit length.
//! 2. Start points (when a curve is closed): every cyclic shift of the closed curve's segments
//!    is scored by the best rotation without reparametrisation (Kabsch trace); the
//!    `start_candidates` best shifts are refined to a fraction of a segment (golden-section
//!    search on the squared distance without reparametrisation, `|q_a|^2 + |q_b|^2 - 2 trace`,
//!    the curve resampled from the new start).
//! 3. For each candidate, rotation and reparametrisation alternate `iterations` times: the
//!    reparametrisation is the dynamic-programming optimum over the piecewise-linear `gamma`
//!    through the nodes of the `m x m` grid whose pieces have slopes `b / a` with
//!    `1 <= a, b <= window` coprime, then smoothed by a moving average over `2 window + 1`
//!    nodes (the grid's slopes are quantised); the rotation is Kabsch on the SRVFs
//!    ([`meshcore::linalg::kabsch_rotation`]) for the smoothed `gamma`. Every step uses the
//!    exact integral of the piecewise-constant SRVFs (breakpoints merged), so each value
//!    considered is the exact L2 distance for its rotation and reparametrisation; the
//!    smallest is kept.
//! 4. Both directions (warping `b` onto `a` and `a` onto `b`) are computed and the smaller is
//!    returned, so the distance is symmetric.
//!
//! Without `scale` the distance is the L2 norm above (units: sqrt of length). With `scale` it
//! is the arc length on the unit sphere of SRVFs, `arccos <q_a, q_b*>`, in `[0, pi]`.

use crate::FaceCurvesError;
use glam::{DMat3, DVec3};
use meshcore::linalg::kabsch_rotation;

meshcore::choice! {
    /// How a curve is resampled before its SRVF is taken.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum Resampling: "curve resampling", crate::FaceCurvesError {
        /// Equal arc-length spacing: removes the input's parametrisation (what the face papers do
        /// with their level curves); the dynamic programming then only corrects for the shape.
        ArcLength = "arc-length" | "arclength",
        /// Equal steps of the input's own parameter (the point index, linear in between): keeps
        /// the input parametrisation, so the dynamic programming must find the reparametrisation.
        Parameter = "parameter",
    }
}

/// Options of [`elastic_distance`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElasticOptions {
    /// Segments of the resampled curves (`m`, at least 4).
    pub samples: usize,
    /// How curves are resampled.
    pub resampling: Resampling,
    /// Scale both curves to unit length first (scale invariance).
    pub scale: bool,
    /// Largest numerator or denominator of a reparametrisation slope (at least 1; 1 allows
    /// only the identity).
    pub window: usize,
    /// Start points of a closed curve refined by the dynamic programming (at least 1).
    pub start_candidates: usize,
    /// Rotation / reparametrisation alternations per start point (at least 1).
    pub iterations: usize,
}

impl Default for ElasticOptions {
    /// 100 segments by arc length, no scaling, slopes up to 3, 3 start candidates, 2
    /// alternations.
    fn default() -> Self {
        Self {
            samples: 100,
            resampling: Resampling::ArcLength,
            scale: false,
            window: 3,
            start_candidates: 3,
            iterations: 2,
        }
    }
}

impl ElasticOptions {
    fn check(&self) -> Result<(), FaceCurvesError> {
        let bad = |m: String| Err(FaceCurvesError::InvalidOption(m));
        if self.samples < 4 || self.samples > 100_000 {
            return bad(format!(
                "elastic samples {} (must be in 4..=100000)",
                self.samples
            ));
        }
        if self.window == 0 || self.window > 16 {
            return bad(format!(
                "elastic window {} (must be in 1..=16)",
                self.window
            ));
        }
        if self.start_candidates == 0 {
            return bad("elastic start_candidates 0 (must be at least 1)".into());
        }
        if self.iterations == 0 {
            return bad("elastic iterations 0 (must be at least 1)".into());
        }
        Ok(())
    }
}

/// The result of [`elastic_distance`].
#[derive(Debug, Clone, PartialEq)]
pub struct ElasticMatch {
    /// The elastic distance (L2 norm of the SRVF difference, or the arc on the unit sphere
    /// with `scale`).
    pub distance: f64,
    /// Squared L2 norm of the SRVF difference at the optimum (after scaling, if any).
    pub l2_squared: f64,
    /// Rotation applied to the warped curve (the second one unless `warped_first`).
    pub rotation: DMat3,
    /// Segments (of the resampled curve, fractional) by which the closed curve's start point
    /// was moved (0 for open curves).
    pub start_shift: f64,
    /// True when the first curve was the one warped (the other direction was better).
    pub warped_first: bool,
    /// The reparametrisation as grid nodes `(t, gamma(t))` in `[0, 1]^2`, increasing.
    pub gamma: Vec<(f64, f64)>,
}

/// A curve prepared for the SRVF: its points (scaled to unit length with `scale`), whether it
/// is closed, and the cumulative arc length at each point.
#[derive(Debug, Clone)]
struct Curve {
    points: Vec<DVec3>,
    closed: bool,
    cum: Vec<f64>,
}

/// Polyline length and cumulative arc length at each vertex (closing segment included).
fn cumulative(points: &[DVec3], closed: bool) -> Vec<f64> {
    let n = points.len();
    let segs = if closed { n } else { n - 1 };
    let mut c = Vec::with_capacity(segs + 1);
    c.push(0.0);
    for s in 0..segs {
        let l = (points[(s + 1) % n] - points[s]).length();
        c.push(c[s] + l);
    }
    c
}

/// Point at parameter `u` in `[0, segs]` of the polyline (vertex `s` at `u = s`).
fn at_param(points: &[DVec3], u: f64) -> DVec3 {
    let n = points.len();
    let s = (u.floor().max(0.0) as usize).min(n.saturating_sub(1));
    let f = u - s as f64;
    let a = points[s % n];
    if f <= 0.0 {
        return a;
    }
    let b = points[(s + 1) % n];
    a + (b - a) * f
}

impl Curve {
    fn segs(&self) -> usize {
        self.cum.len() - 1
    }

    /// Resampled into `m` segments starting `offset` segments (of the resampled curve) after
    /// the first point (closed curves only; 0 for open ones): `m` points for a closed curve,
    /// `m + 1` for an open one.
    fn resample(&self, m: usize, how: Resampling, offset: f64) -> Vec<DVec3> {
        let segs = self.segs();
        let count = if self.closed { m } else { m + 1 };
        let total = self.cum[segs];
        let wrap = |u: f64, period: f64| {
            if self.closed {
                u.rem_euclid(period)
            } else {
                u.clamp(0.0, period)
            }
        };
        (0..count)
            .map(|i| {
                let f = (i as f64 + offset) / m as f64;
                match how {
                    Resampling::Parameter => {
                        at_param(&self.points, wrap(segs as f64 * f, segs as f64))
                    }
                    Resampling::ArcLength => {
                        let target = wrap(total * f, total);
                        let s = self
                            .cum
                            .partition_point(|&c| c <= target)
                            .saturating_sub(1)
                            .min(segs - 1);
                        let len = self.cum[s + 1] - self.cum[s];
                        let t = if len > 0.0 {
                            ((target - self.cum[s]) / len).clamp(0.0, 1.0)
                        } else {
                            0.0
                        };
                        at_param(&self.points, s as f64 + t)
                    }
                }
            })
            .collect()
    }

    /// The SRVF of [`Curve::resample`]: `m` segment values.
    fn q(&self, m: usize, how: Resampling, offset: f64) -> Vec<DVec3> {
        let p = self.resample(m, how, offset);
        let sm = (m as f64).sqrt();
        let np = p.len();
        (0..m)
            .map(|s| {
                let d = p[(s + 1) % np] - p[s];
                let l = d.length();
                if l > 0.0 {
                    d * (sm / l.sqrt())
                } else {
                    DVec3::ZERO
                }
            })
            .collect()
    }
}

fn norm2(q: &[DVec3]) -> f64 {
    q.iter().map(|v| v.length_squared()).sum::<f64>() / q.len() as f64
}

fn check_curve(
    points: &[DVec3],
    closed: bool,
    which: &'static str,
) -> Result<f64, FaceCurvesError> {
    let (needed, kind) = if closed { (3, "closed") } else { (2, "open") };
    if points.len() < needed {
        return Err(FaceCurvesError::TooFewPoints {
            which,
            kind,
            needed,
            got: points.len(),
        });
    }
    if let Some(index) = points.iter().position(|p| !p.is_finite()) {
        return Err(FaceCurvesError::NonFinitePoint { which, index });
    }
    let len = *cumulative(points, closed).last().unwrap_or(&0.0);
    if !(len > 0.0 && len.is_finite()) {
        return Err(FaceCurvesError::ZeroLength { which });
    }
    Ok(len)
}

fn prepare(points: &[DVec3], closed: bool, opts: &ElasticOptions, length: f64) -> Curve {
    let points: Vec<DVec3> = if opts.scale {
        points.iter().map(|p| *p / length).collect()
    } else {
        points.to_vec()
    };
    let cum = cumulative(&points, closed);
    Curve {
        points,
        closed,
        cum,
    }
}

/// The elastic (SRVF) distance between curve `a` and curve `b` (ordered points; a closed curve
/// does not repeat its first point). Invariant to translation, rotation and
/// reparametrisation, and to scale with [`ElasticOptions::scale`]; see the module
/// documentation for the algorithm.
///
/// Errors: invalid options, a curve with too few points (2 open, 3 closed), a non-finite
/// point, or zero length.
pub fn elastic_distance(
    a: &[DVec3],
    a_closed: bool,
    b: &[DVec3],
    b_closed: bool,
    opts: &ElasticOptions,
) -> Result<ElasticMatch, FaceCurvesError> {
    opts.check()?;
    let la = check_curve(a, a_closed, "first")?;
    let lb = check_curve(b, b_closed, "second")?;
    let ca = prepare(a, a_closed, opts, la);
    let cb = prepare(b, b_closed, opts, lb);
    let ab = one_sided(&ca, &cb, opts);
    let ba = one_sided(&cb, &ca, opts);
    let (best, warped_first) = if ba.l2_squared < ab.l2_squared {
        (ba, true)
    } else {
        (ab, false)
    };
    let l2 = best.l2_squared.max(0.0);
    let distance = if opts.scale {
        // Unit-norm SRVFs: <qa, qb*> = 1 - |qa - qb*|^2 / 2.
        (1.0 - 0.5 * l2).clamp(-1.0, 1.0).acos()
    } else {
        l2.sqrt()
    };
    Ok(ElasticMatch {
        distance,
        l2_squared: l2,
        rotation: best.rotation,
        start_shift: best.start_shift,
        warped_first,
        gamma: best.gamma,
    })
}

struct OneSided {
    l2_squared: f64,
    rotation: DMat3,
    start_shift: f64,
    gamma: Vec<(f64, f64)>,
}

/// Kabsch trace of two SRVFs without warping (the larger, the better aligned).
fn trace(x: &[DVec3], y: &[DVec3]) -> f64 {
    kabsch_rotation(cross(x.iter().copied().zip(y.iter().copied()), x.len())).1
}

/// Warps (reparametrises and rotates) `y` onto `x`; the start point of whichever is closed
/// (`y` first) is searched: integer shifts scored by their Kabsch trace, the best ones refined
/// to a fraction of a segment (golden section), then rotation and reparametrisation alternate.
fn one_sided(x: &Curve, y: &Curve, opts: &ElasticOptions) -> OneSided {
    let m = opts.samples;
    let how = opts.resampling;
    let moves = slope_moves(opts.window);
    let shift_y = y.closed;
    let shift_any = x.closed || y.closed;
    let qx0 = x.q(m, how, 0.0);
    let qy0 = y.q(m, how, 0.0);
    // The SRVFs for a start offset of the shifted curve.
    let pair = |offset: f64| -> (Vec<DVec3>, Vec<DVec3>) {
        if !shift_any || offset == 0.0 {
            (qx0.clone(), qy0.clone())
        } else if shift_y {
            (qx0.clone(), y.q(m, how, offset))
        } else {
            (x.q(m, how, offset), qy0.clone())
        }
    };
    let mut candidates: Vec<(f64, usize)> = if shift_any {
        (0..m)
            .map(|p| {
                let k = cross(
                    (0..m).map(|s| {
                        if shift_y {
                            (qx0[s], qy0[(s + p) % m])
                        } else {
                            (qx0[(s + p) % m], qy0[s])
                        }
                    }),
                    m,
                );
                (kabsch_rotation(k).1, p)
            })
            .collect()
    } else {
        vec![(0.0, 0)]
    };
    // Best Kabsch traces first; ties by the smaller shift (deterministic).
    candidates.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    candidates.truncate(opts.start_candidates);
    let mut best: Option<OneSided> = None;
    let mut yr = vec![DVec3::ZERO; m];
    let mut dp = Dp::new(m);
    for &(_, p) in &candidates {
        let offset = if shift_any {
            // Scored by the squared distance without warping, not by the trace alone: a
            // fractional start resamples a polygon's corners differently, which changes the
            // resampled length, and a longer resampling raises the trace while moving away
            // (an identical coarse polygon was then found at a positive distance).
            refine_offset(p as f64, |o| {
                let (a, b) = pair(o);
                2.0 * trace(&a, &b) - norm2(&a) - norm2(&b)
            })
        } else {
            0.0
        };
        let (xs, ys) = pair(offset);
        let (nx, ny) = (norm2(&xs), norm2(&ys));
        let mut consider = |l2: f64, r: DMat3, g: &[f64]| {
            if best.as_ref().is_none_or(|b| l2 < b.l2_squared) {
                best = Some(OneSided {
                    l2_squared: l2,
                    rotation: r,
                    start_shift: offset,
                    gamma: g
                        .iter()
                        .enumerate()
                        .map(|(t, &gt)| (t as f64 / m as f64, gt / m as f64))
                        .collect(),
                });
            }
        };
        let identity: Vec<f64> = (0..=m).map(|t| t as f64).collect();
        let (mut rot, tr) = kabsch_rotation(cross(xs.iter().copied().zip(ys.iter().copied()), m));
        consider(nx + ny - 2.0 * tr, rot, &identity);
        for _ in 0..opts.iterations {
            for s in 0..m {
                yr[s] = rot * ys[s];
            }
            let (cost, path) = dp.solve(&xs, &yr, &moves);
            let g = path_to_gamma(&path, m);
            consider(cost, rot, &g);
            // Smoothed reparametrisation (moving average over the slope window): the DP's
            // slopes are quantised to b / a, which costs amplitude where the true slope lies
            // between them.
            let gs = smooth_gamma(&g, opts.window);
            let mut k = DMat3::ZERO;
            walk_gamma(&xs, &ys, &gs, |dt, qx, qy| k += outer(qx, qy) * dt);
            let (r2, tr) = kabsch_rotation(k * (1.0 / m as f64));
            consider(nx + ny - 2.0 * tr, r2, &gs);
            rot = r2;
        }
    }
    best.unwrap_or(OneSided {
        l2_squared: f64::INFINITY,
        rotation: DMat3::IDENTITY,
        start_shift: 0.0,
        gamma: Vec::new(),
    })
}

/// Golden-section search of `f` (to maximise) over `[p - 0.5, p + 0.5]`; returns the best of
/// the probes and `p` itself.
fn refine_offset(p: f64, f: impl Fn(f64) -> f64) -> f64 {
    const INV_PHI: f64 = 0.618_033_988_749_895;
    let (mut a, mut b) = (p - 0.5, p + 0.5);
    let mut c = b - INV_PHI * (b - a);
    let mut d = a + INV_PHI * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..14 {
        if fc > fd {
            b = d;
            d = c;
            fd = fc;
            c = b - INV_PHI * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + INV_PHI * (b - a);
            fd = f(d);
        }
    }
    let (x, fx) = if fc > fd { (c, fc) } else { (d, fd) };
    if fx > f(p) {
        x
    } else {
        p
    }
}

/// `gamma(t)` at the integer `t = 0..=m` of a DP path (linear along its edges).
fn path_to_gamma(path: &[(usize, usize)], m: usize) -> Vec<f64> {
    let mut g = vec![0.0; m + 1];
    for w in path.windows(2) {
        let ((k, l), (i, j)) = (w[0], w[1]);
        let slope = (j - l) as f64 / (i - k) as f64;
        for (t, gt) in g.iter_mut().enumerate().take(i + 1).skip(k) {
            *gt = l as f64 + (t - k) as f64 * slope;
        }
    }
    g[m] = m as f64;
    g
}

/// Moving average of `g` over `2 h + 1` nodes, the window shrunk at the ends so that
/// `g(0) = 0` and `g(m) = m` stay; non-decreasing like `g`.
fn smooth_gamma(g: &[f64], h: usize) -> Vec<f64> {
    let m = g.len() - 1;
    let mut out = Vec::with_capacity(m + 1);
    let mut prev = 0.0f64;
    for t in 0..=m {
        let w = h.min(t).min(m - t);
        let v = g[t - w..=t + w].iter().sum::<f64>() / (2 * w + 1) as f64;
        let v = v.max(prev);
        out.push(v);
        prev = v;
    }
    out
}

/// Like [`walk_edge`] for a reparametrisation given by real values `g[t]` at the integer `t`
/// (linear in between): calls `f(dt, x(t), sqrt(gamma') y(gamma(t)))` on every interval where
/// both are constant.
fn walk_gamma(x: &[DVec3], y: &[DVec3], g: &[f64], mut f: impl FnMut(f64, DVec3, DVec3)) {
    let m = x.len();
    for t in 0..m {
        let (g0, g1) = (g[t], g[t + 1]);
        let sigma = g1 - g0;
        if sigma <= 0.0 {
            f(1.0, x[t], DVec3::ZERO);
            continue;
        }
        let root = sigma.sqrt();
        let mut cur = g0;
        let mut seg = (g0.floor() as usize).min(m - 1);
        while cur < g1 && seg < m {
            let next = ((seg + 1) as f64).min(g1);
            if next > cur {
                f((next - cur) / sigma, x[t], y[seg] * root);
            }
            cur = next;
            seg += 1;
        }
    }
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// `sum x y^T / m` over the pairs (the cross-covariance of two SRVFs without warping).
fn cross(pairs: impl Iterator<Item = (DVec3, DVec3)>, m: usize) -> DMat3 {
    let mut k = DMat3::ZERO;
    for (a, b) in pairs {
        k += outer(a, b);
    }
    k * (1.0 / m as f64)
}

/// Slopes `(a, b)` (a steps of t, b steps of gamma) with `1 <= a, b <= window`, coprime.
fn slope_moves(window: usize) -> Vec<(usize, usize)> {
    fn gcd(a: usize, b: usize) -> usize {
        if b == 0 {
            a
        } else {
            gcd(b, a % b)
        }
    }
    let mut v = Vec::new();
    for a in 1..=window {
        for b in 1..=window {
            if gcd(a, b) == 1 {
                v.push((a, b));
            }
        }
    }
    v
}

/// Walks the edge of `gamma` from grid node `(k, l)` to `(i, j)` (linear in between) and calls
/// `f(dt, x(t), sqrt(slope) y(gamma(t)))` on each interval where both SRVFs are constant; `dt`
/// is in segment units (the integral is `sum dt * ... / m`).
fn walk_edge(
    x: &[DVec3],
    y: &[DVec3],
    k: usize,
    i: usize,
    l: usize,
    j: usize,
    mut f: impl FnMut(f64, DVec3, DVec3),
) {
    let a = (i - k) as f64;
    let b = (j - l) as f64;
    let sigma = b / a;
    let root = sigma.sqrt();
    // Breakpoints in local t (0..a): integers (x changes) and (p - l) / sigma (y changes).
    let mut t = 0.0;
    let mut sx = 0usize; // segment of x, relative to k
    let mut sy = 0usize; // segment of y, relative to l
    let (na, nb) = (i - k, j - l);
    while sx < na && sy < nb {
        let tx = (sx + 1) as f64;
        let ty = (sy + 1) as f64 / sigma;
        let next = tx.min(ty);
        let dt = next - t;
        if dt > 0.0 {
            f(dt, x[k + sx], y[l + sy] * root);
        }
        t = next;
        // Advance whichever ended (both at a common breakpoint).
        let ex = (tx - next).abs() <= 1e-12 * a;
        let ey = (ty - next).abs() <= 1e-12 * a;
        if ex {
            sx += 1;
        }
        if ey {
            sy += 1;
        }
        if !ex && !ey {
            break;
        }
    }
}

/// Dynamic programming over the reparametrisation grid, with reusable tables.
struct Dp {
    m: usize,
    cost: Vec<f64>,
    from: Vec<u8>,
}

impl Dp {
    fn new(m: usize) -> Self {
        Self {
            m,
            cost: vec![f64::INFINITY; (m + 1) * (m + 1)],
            from: vec![u8::MAX; (m + 1) * (m + 1)],
        }
    }

    /// Minimum over the grid paths from (0, 0) to (m, m) of `||x - (y o gamma) sqrt(gamma')||^2`,
    /// with the path's nodes.
    fn solve(
        &mut self,
        x: &[DVec3],
        y: &[DVec3],
        moves: &[(usize, usize)],
    ) -> (f64, Vec<(usize, usize)>) {
        let m = self.m;
        let w = m + 1;
        self.cost.iter_mut().for_each(|c| *c = f64::INFINITY);
        self.from.iter_mut().for_each(|c| *c = u8::MAX);
        self.cost[0] = 0.0;
        for i in 1..=m {
            for j in 1..=m {
                let mut best = f64::INFINITY;
                let mut arg = u8::MAX;
                for (mi, &(a, b)) in moves.iter().enumerate() {
                    if a > i || b > j {
                        continue;
                    }
                    let (k, l) = (i - a, j - b);
                    let base = self.cost[k * w + l];
                    if !base.is_finite() || base >= best {
                        continue;
                    }
                    let mut e = 0.0;
                    walk_edge(x, y, k, i, l, j, |dt, qx, qy| {
                        e += dt * (qx - qy).length_squared();
                    });
                    let c = base + e / m as f64;
                    if c < best {
                        best = c;
                        arg = mi as u8;
                    }
                }
                self.cost[i * w + j] = best;
                self.from[i * w + j] = arg;
            }
        }
        let mut path = vec![(m, m)];
        let (mut i, mut j) = (m, m);
        while i > 0 || j > 0 {
            let mi = self.from[i * w + j];
            if mi == u8::MAX {
                break;
            }
            let (a, b) = moves[mi as usize];
            i -= a;
            j -= b;
            path.push((i, j));
        }
        path.reverse();
        (self.cost[m * w + m], path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn choices_parse() {
        meshcore::choice::check_choice::<Resampling>("bogus").unwrap();
    }

    #[test]
    fn srvf_norm_is_length() {
        let pts: Vec<DVec3> = (0..7)
            .map(|i| DVec3::new(i as f64, (i * i) as f64 * 0.1, 0.0))
            .collect();
        let len = *cumulative(&pts, false).last().unwrap();
        let opts = ElasticOptions::default();
        let c = prepare(&pts, false, &opts, len);
        // Parameter resampling at 2 samples per segment keeps every vertex: |q|^2 = length.
        let q = c.q(12, Resampling::Parameter, 0.0);
        assert!(
            (norm2(&q) - len).abs() < 1e-12 * len,
            "{} vs {len}",
            norm2(&q)
        );
        // A closed square restarted half-way along a side keeps its shape.
        let sq = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        let c = prepare(&sq, true, &opts, 4.0);
        let p = c.resample(8, Resampling::ArcLength, 1.0);
        assert!(
            (p[0] - DVec3::new(0.5, 0.0, 0.0)).length() < 1e-12,
            "{:?}",
            p[0]
        );
        assert!((p[7] - DVec3::ZERO).length() < 1e-12, "{:?}", p[7]);
    }

    #[test]
    fn smoothed_gamma_keeps_the_ends_and_the_order() {
        let g = path_to_gamma(&[(0, 0), (1, 2), (3, 3), (4, 4)], 4);
        assert_eq!(g, vec![0.0, 2.0, 2.5, 3.0, 4.0]);
        let s = smooth_gamma(&g, 2);
        assert_eq!((s[0], s[4]), (0.0, 4.0));
        assert!(s.windows(2).all(|w| w[0] <= w[1]), "{s:?}");
        // The integral of |y o gamma|^2 gamma' is |y|^2 for any such gamma.
        let y = vec![DVec3::X, DVec3::Y * 2.0, DVec3::Z, DVec3::X * 3.0];
        let mut ny = 0.0;
        walk_gamma(&y, &y, &s, |dt, _, qy| ny += dt * qy.length_squared());
        assert!((ny - (1.0 + 4.0 + 1.0 + 9.0)).abs() < 1e-12, "{ny}");
    }

    #[test]
    fn walk_edge_integrates_the_whole_interval() {
        let x = vec![DVec3::X; 6];
        let y = vec![DVec3::Y; 6];
        for &(k, i, l, j) in &[(0, 3, 0, 1), (1, 2, 0, 3), (0, 2, 1, 4), (2, 5, 1, 3)] {
            let mut total = 0.0;
            let mut ny = 0.0;
            walk_edge(&x, &y, k, i, l, j, |dt, _, qy| {
                total += dt;
                ny += dt * qy.length_squared();
            });
            assert!((total - (i - k) as f64).abs() < 1e-12);
            // Reparametrisation is an isometry: the warped |y|^2 integrates to the y length.
            assert!((ny - (j - l) as f64).abs() < 1e-12);
        }
    }

    #[test]
    fn moves_are_coprime() {
        assert_eq!(slope_moves(1), vec![(1, 1)]);
        assert_eq!(slope_moves(2), vec![(1, 1), (1, 2), (2, 1)]);
        assert_eq!(slope_moves(3).len(), 7);
    }
}
