//! Windows (intervals of an edge with an unfolded virtual source) and the sound pairwise trim.

/// Relative tolerance of strict domination: a window part is removed only when it is beaten by
/// more than `TAU` relative.
pub(crate) const TAU: f64 = 1e-12;

/// An interval `[b0, b1]` of a half-edge with a virtual source `(sx, sy)` (`sy <= 0`) in that
/// half-edge's frame and an additive distance `sigma`: `D(x) = sigma + |(sx, sy) - (x, 0)|`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Window {
    /// Start of the interval along the half-edge.
    pub b0: f64,
    /// End of the interval.
    pub b1: f64,
    /// Distance already travelled when reaching the virtual source.
    pub sigma: f64,
    /// Virtual source, x coordinate.
    pub sx: f64,
    /// Virtual source, y coordinate (`<= 0`: behind the edge).
    pub sy: f64,
    /// Record index in path-tracing mode (`u32::MAX` otherwise).
    pub id: u32,
}

impl Window {
    /// The distance function at `x` on the edge.
    #[inline]
    pub fn dist(&self, x: f64) -> f64 {
        let dx = x - self.sx;
        self.sigma + (dx * dx + self.sy * self.sy).sqrt()
    }

    /// Minimum of the distance function over the interval.
    #[inline]
    pub fn min_dist(&self) -> f64 {
        let x = self.sx.clamp(self.b0, self.b1);
        self.dist(x)
    }

    /// Marks the window as removed.
    #[inline]
    pub fn kill(&mut self) {
        self.b0 = f64::INFINITY;
        self.b1 = f64::NEG_INFINITY;
    }

    /// True if the window was removed.
    #[inline]
    pub fn is_dead(&self) -> bool {
        // Dead when b0 > b1 or either end is NaN.
        !matches!(
            self.b0.partial_cmp(&self.b1),
            Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
        )
    }

    /// Size of the window's distance function (`|sigma| + |source|`), the reference of the
    /// relative tolerances in [`pair_trim`].
    #[inline]
    pub fn scale(&self) -> f64 {
        self.sigma.abs() + (self.sx * self.sx + self.sy * self.sy).sqrt()
    }

    /// An upper bound of [`Window::scale`] without a square root (`|source|` bounded by its L1
    /// norm, times `1 + 1e-15` to cover rounding): a tolerance test against the scale that
    /// fails with this bound fails with the scale too, so the scale is only computed when a
    /// test could pass.
    #[inline]
    fn scale_bound(&self) -> f64 {
        (self.sigma.abs() + self.sx.abs() + self.sy.abs()) * (1.0 + 1e-15)
    }
}

/// Success counters of [`pair_trim`]'s bounding shortcut, which only pays off when it often
/// decides (about 30 % of the overlapping pairs on a paper-set face, 0.4 % on an icosphere):
/// while it decides less than 1 pair in 8 it is only tried on 1 call in 32. This changes only
/// the speed, never a result (the shortcut's outcome equals the exact path's).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct BoundStats {
    calls: u32,
    tries: u32,
    hits: u32,
}

impl BoundStats {
    #[inline]
    fn enabled(&mut self) -> bool {
        self.calls = self.calls.wrapping_add(1);
        self.hits.saturating_mul(8) >= self.tries || self.calls % 32 == 0
    }
}

/// Outcome of [`pair_trim`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Trim {
    /// The first window is removed.
    FirstDead,
    /// The second window is removed (dominated or merged into the first).
    SecondDead,
    /// Both survive (possibly shortened).
    Both,
}

/// True when the sigmas of the two windows count as equal: they differ by at most `1e-14`
/// times the larger [`Window::scale`]. Equal sigmas (every window of one source without
/// pseudo-sources) need no scale.
#[inline]
fn equal_sigmas(w1: &Window, w2: &Window) -> bool {
    let ad = (w2.sigma - w1.sigma).abs();
    ad == 0.0
        || (ad <= 1e-14 * w1.scale_bound().max(w2.scale_bound())
            && ad <= 1e-14 * w1.scale().max(w2.scale()))
}

/// `|S1|^2 - |S2|^2` written to avoid cancellation, with `u = sx1 - sx2`.
#[inline]
fn source_norm_gap(w1: &Window, w2: &Window, u: f64) -> f64 {
    u * (w1.sx + w2.sx) + (w1.sy - w2.sy) * (w1.sy + w2.sy)
}

/// Real roots of `D1(x) = D2(x)` (a superset: squaring may add spurious ones), written into
/// `out`; returns how many. With [`equal_sigmas`] the root is the perpendicular bisector's.
fn equal_distance_roots(w1: &Window, w2: &Window, out: &mut [f64; 2]) -> usize {
    let delta = w2.sigma - w1.sigma;
    let u = w1.sx - w2.sx;
    let k = source_norm_gap(w1, w2, u);
    if equal_sigmas(w1, w2) {
        // Perpendicular bisector of the two sources.
        if u != 0.0 {
            out[0] = k / (2.0 * u);
            return 1;
        }
        return 0;
    }
    let b = -2.0 * u;
    let a0 = k - delta * delta;
    let d2 = 4.0 * delta * delta;
    let qa = b * b - d2;
    let qb = 2.0 * b * a0 + 2.0 * d2 * w2.sx;
    let qc = a0 * a0 - d2 * (w2.sx * w2.sx + w2.sy * w2.sy);
    if qa == 0.0 {
        if qb != 0.0 {
            out[0] = -qc / qb;
            return 1;
        }
        return 0;
    }
    let mut disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        if disc > -1e-10 * qb * qb {
            disc = 0.0;
        } else {
            return 0;
        }
    }
    let q = -0.5 * (qb + qb.signum() * disc.sqrt());
    let mut n = 0;
    if q != 0.0 {
        out[n] = q / qa;
        n += 1;
        out[n] = qc / q;
        n += 1;
    } else {
        // qb == 0 and disc == 0: double root at 0.
        out[n] = 0.0;
        n += 1;
    }
    n
}

/// Sound pairwise trim of two windows of the same half-edge (same frame).
///
/// A part of a window is removed only when the other window is strictly shorter there (by more
/// than [`TAU`] relative); windows are never split in the middle. Identical distance functions
/// whose intervals overlap or touch (functions within `1e-12` times `w1`'s [`Window::scale`])
/// are merged into `w1`. `bs` steers the bounding shortcut (speed only).
#[inline(always)]
pub(crate) fn pair_trim(w1: &mut Window, w2: &mut Window, bs: &mut BoundStats) -> Trim {
    let l = w1.b0.max(w2.b0);
    let r = w1.b1.min(w2.b1);
    if r < l {
        return Trim::Both;
    }
    let ds = (w1.sigma - w2.sigma).abs();
    let ub = 1e-12 * w1.scale_bound();
    if ds <= ub
        && (w1.sx - w2.sx).abs() <= ub
        && (w1.sy - w2.sy).abs() <= ub
        && {
            let s = 1e-12 * w1.scale();
            ds <= s && (w1.sx - w2.sx).abs() <= s && (w1.sy - w2.sy).abs() <= s
        }
        && w2.b0 <= w1.b1
        && w1.b0 <= w2.b1
        && w1.id == u32::MAX
    {
        w1.b0 = w1.b0.min(w2.b0);
        w1.b1 = w1.b1.max(w2.b1);
        w2.kill();
        return Trim::SecondDead;
    }
    if r <= l {
        return Trim::Both;
    }
    // Bounding check: when one window's minimum over the overlap exceeds the other's maximum
    // by a margin, every midpoint test below would say that it loses the whole overlap; the
    // outcome is then fixed (same result as the exact path, without roots or midpoints).
    if bs.enabled() {
        bs.tries = bs.tries.saturating_add(1);
        if let Some(out) = dominated_on_overlap(w1, w2, l, r) {
            bs.hits = bs.hits.saturating_add(1);
            return out;
        }
    }
    exact_trim(w1, w2, l, r)
}

/// The exact path of [`pair_trim`] on the overlap `[l, r]` (`l < r`): equal-distance roots,
/// a midpoint test per segment, then the ends are moved past the lost segments. Equal sigmas
/// take [`bisector_trim`] (the same operations unrolled for at most one root).
#[inline]
fn exact_trim(w1: &mut Window, w2: &mut Window, l: f64, r: f64) -> Trim {
    if equal_sigmas(w1, w2) {
        bisector_trim(w1, w2, l, r)
    } else {
        general_trim(w1, w2, l, r)
    }
}

/// The midpoint test of [`general_trim`] at `m`: (`w1` loses, `w2` loses).
#[inline]
fn lose_at(w1: &Window, w2: &Window, m: f64) -> (bool, bool) {
    let d1 = w1.dist(m);
    let d2 = w2.dist(m);
    let tol = TAU * d1.max(d2);
    (d1 > d2 + tol, d2 > d1 + tol)
}

/// [`general_trim`] for [`equal_sigmas`]: the only breakpoint is the bisector's root `x` (the
/// same floating-point operations, so the same result, without solving a quadratic).
#[inline]
fn bisector_trim(w1: &mut Window, w2: &mut Window, l: f64, r: f64) -> Trim {
    let u = w1.sx - w2.sx;
    let x = if u != 0.0 {
        source_norm_gap(w1, w2, u) / (2.0 * u)
    } else {
        f64::NAN
    };
    if x > l && x < r {
        trim_segments(w1, w2, [l, x, r])
    } else {
        trim_segments(w1, w2, [l, r])
    }
}

/// The exact path for any sigmas: roots, midpoint tests per segment, ends moved.
fn general_trim(w1: &mut Window, w2: &mut Window, l: f64, r: f64) -> Trim {
    let mut roots = [0.0; 2];
    let nr = equal_distance_roots(w1, w2, &mut roots);
    // Breakpoints l < p1 < p2 < r.
    let mut pts = [l, 0.0, 0.0, r];
    let mut np = 1;
    let mut rs = [roots[0], roots[1]];
    if nr == 2 && rs[1] < rs[0] {
        rs.swap(0, 1);
    }
    for &x in &rs[..nr] {
        if x > pts[np - 1] && x < r {
            pts[np] = x;
            np += 1;
        }
    }
    match np {
        1 => trim_segments(w1, w2, [l, r]),
        2 => trim_segments(w1, w2, [l, pts[1], r]),
        _ => trim_segments(w1, w2, [l, pts[1], pts[2], r]),
    }
}

/// The end of the exact path on the segments between the breakpoints `pts` (`P - 1 <= 3`
/// segments, the overlap `[pts[0], pts[P - 1]]`): a midpoint test per segment; a window that
/// lies inside the overlap and loses every segment dies, otherwise its ends move past the
/// lost segments. A fixed `P` lets the loops unroll.
#[inline(always)]
fn trim_segments<const P: usize>(w1: &mut Window, w2: &mut Window, pts: [f64; P]) -> Trim {
    let (l, r) = (pts[0], pts[P - 1]);
    let mut lose1 = [false; P];
    let mut lose2 = [false; P];
    for i in 0..P - 1 {
        (lose1[i], lose2[i]) = lose_at(w1, w2, 0.5 * (pts[i] + pts[i + 1]));
    }
    let all1 = lose1[..P - 1].iter().all(|&b| b);
    let all2 = lose2[..P - 1].iter().all(|&b| b);
    if all1 && w1.b0 >= l && w1.b1 <= r {
        w1.kill();
        return Trim::FirstDead;
    }
    if all2 && w2.b0 >= l && w2.b1 <= r {
        w2.kill();
        return Trim::SecondDead;
    }
    trim_ends(w1, &pts, &lose1);
    trim_ends(w2, &pts, &lose2);
    Trim::Both
}

/// Minimum of `w`'s distance over `[l, r]` (at the foot of the source, clamped).
#[inline]
fn min_on(w: &Window, l: f64, r: f64) -> f64 {
    let dx = (l - w.sx).max(w.sx - r).max(0.0);
    w.sigma + (dx * dx + w.sy * w.sy).sqrt()
}

/// Maximum of `w`'s distance over `[l, r]` (at the end farther from the source: convexity).
#[inline]
fn max_on(w: &Window, l: f64, r: f64) -> f64 {
    let dx = (l - w.sx).abs().max((r - w.sx).abs());
    w.sigma + (dx * dx + w.sy * w.sy).sqrt()
}

/// Margin of [`dominated_on_overlap`]: `4 TAU` relative, far above the rounding of the
/// distance evaluations (a few ulps), so that `min(D1) (1 - 4 TAU) > max(D2)` implies
/// `D1(m) > D2(m) + TAU max(D1(m), D2(m))` as computed at every midpoint `m` of `[l, r]`.
const BOUND_MARGIN: f64 = 1.0 - 4.0 * TAU;

/// The result of [`pair_trim`]'s exact path when one window loses the whole overlap `[l, r]`
/// (`l < r`) by the bound `min(D_loser) (1 - 4 TAU) > max(D_winner)`, or `None` if the bound
/// decides nothing. Mirrors the exact path: the loser dies when its interval lies inside the
/// overlap, otherwise its ends lying in the overlap move to the overlap's other end.
#[inline]
fn dominated_on_overlap(w1: &mut Window, w2: &mut Window, l: f64, r: f64) -> Option<Trim> {
    loses_overlap(w1, w2, l, r, Trim::FirstDead)
        .or_else(|| loses_overlap(w2, w1, l, r, Trim::SecondDead))
}

/// One side of [`dominated_on_overlap`]: if `loser` loses `[l, r]` to `winner` by the bound, it
/// dies (`dead`) or is trimmed ([`Trim::Both`]).
#[inline]
fn loses_overlap(loser: &mut Window, winner: &Window, l: f64, r: f64, dead: Trim) -> Option<Trim> {
    if min_on(loser, l, r) * BOUND_MARGIN > max_on(winner, l, r) {
        if loser.b0 >= l && loser.b1 <= r {
            loser.kill();
            return Some(dead);
        }
        lose_overlap(loser, l, r);
        return Some(Trim::Both);
    }
    None
}

/// [`trim_ends`] when every segment of `[l, r]` is lost (and `w` is not inside `[l, r]`).
#[inline]
fn lose_overlap(w: &mut Window, l: f64, r: f64) {
    let (b0, b1) = (w.b0, w.b1);
    if b0 >= l {
        w.b0 = r;
    }
    if b1 <= r {
        w.b1 = l;
    }
    if w.b0 > w.b1 {
        w.kill();
    }
}

/// Moves the ends of `w` that lie at the overlap's ends `pts[0]` (or `pts[P - 1]`) past the
/// lost segments touching them.
#[inline(always)]
fn trim_ends<const P: usize>(w: &mut Window, pts: &[f64; P], lose: &[bool; P]) {
    let nseg = P - 1;
    let (b0, b1) = (w.b0, w.b1);
    if b0 >= pts[0] {
        let mut i = 0;
        while i < nseg && lose[i] {
            i += 1;
        }
        if i > 0 {
            w.b0 = pts[i];
        }
    }
    if b1 <= pts[nseg] {
        let mut j = nseg;
        while j > 0 && lose[j - 1] {
            j -= 1;
        }
        if j < nseg {
            w.b1 = pts[j];
        }
    }
    if w.b0 > w.b1 {
        w.kill();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn win(b0: f64, b1: f64, sigma: f64, sx: f64, sy: f64) -> Window {
        Window {
            b0,
            b1,
            sigma,
            sx,
            sy,
            id: u32::MAX,
        }
    }

    fn trim(a: &mut Window, b: &mut Window) -> Trim {
        pair_trim(a, b, &mut BoundStats::default())
    }

    /// After a trim, every point of the original union is still served (within tolerance) by
    /// a surviving window at no more than the original lower envelope.
    fn check_sound(a: Window, b: Window, rng: &mut ChaCha8Rng) {
        let (mut x, mut y) = (a, b);
        let out = pair_trim(&mut x, &mut y, &mut BoundStats::default());
        match out {
            Trim::FirstDead => assert!(x.is_dead()),
            Trim::SecondDead => assert!(y.is_dead()),
            Trim::Both => {}
        }
        let lo = a.b0.min(b.b0);
        let hi = a.b1.max(b.b1);
        for _ in 0..64 {
            let t = rng.random_range(lo..=hi);
            let mut env = f64::INFINITY;
            for w in [&a, &b] {
                if t >= w.b0 && t <= w.b1 {
                    env = env.min(w.dist(t));
                }
            }
            if !env.is_finite() {
                continue;
            }
            let mut got = f64::INFINITY;
            for w in [&x, &y] {
                if !w.is_dead() && t >= w.b0 - 1e-12 && t <= w.b1 + 1e-12 {
                    got = got.min(w.dist(t));
                }
            }
            assert!(
                got <= env * (1.0 + 1e-9) + 1e-12,
                "unsound trim at {t}: env {env}, got {got}; {a:?} {b:?} -> {x:?} {y:?}"
            );
        }
    }

    #[test]
    fn random_pairs_are_trimmed_soundly() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for i in 0..20000 {
            let l = 1.0;
            let mk = |rng: &mut ChaCha8Rng, eq_sigma: bool| {
                let b0: f64 = rng.random_range(0.0..l);
                let b1: f64 = rng.random_range(b0..=l);
                let sigma = if eq_sigma {
                    0.0
                } else {
                    rng.random_range(0.0..3.0)
                };
                win(
                    b0,
                    b1,
                    sigma,
                    rng.random_range(-3.0..4.0),
                    -rng.random_range(1e-3..3.0),
                )
            };
            let eq = i % 3 == 0;
            let a = mk(&mut rng, eq);
            let b = mk(&mut rng, eq);
            check_sound(a, b, &mut rng);
        }
    }

    /// A random interval `[b0, b1]` of `[0, 1]`.
    fn ends(rng: &mut ChaCha8Rng) -> (f64, f64) {
        let b0: f64 = rng.random_range(0.0..1.0);
        (b0, rng.random_range(b0..=1.0))
    }

    /// Two ways of trimming the pair `(a, b)` gave the same outcome and the same surviving
    /// intervals, bit for bit.
    fn assert_same_outcome(
        (a, b): (Window, Window),
        (fast, x1, y1): (Trim, Window, Window),
        (slow, x2, y2): (Trim, Window, Window),
    ) {
        assert_eq!(fast, slow, "{a:?} {b:?}");
        for (p, q) in [(x1, x2), (y1, y2)] {
            assert_eq!(p.is_dead(), q.is_dead(), "{a:?} {b:?}");
            if !p.is_dead() {
                assert_eq!(
                    (p.b0.to_bits(), p.b1.to_bits()),
                    (q.b0.to_bits(), q.b1.to_bits()),
                    "{a:?} {b:?}"
                );
            }
        }
    }

    /// The bounding shortcut gives exactly the exact path's result whenever it decides.
    #[test]
    fn bound_shortcut_matches_exact_path() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut decided = 0;
        for _ in 0..20000 {
            let mk = |rng: &mut ChaCha8Rng| {
                let (b0, b1) = ends(rng);
                win(
                    b0,
                    b1,
                    rng.random_range(0.0..2.0),
                    rng.random_range(-3.0..4.0),
                    -rng.random_range(1e-3..3.0),
                )
            };
            let (a, b) = (mk(&mut rng), mk(&mut rng));
            let (l, r) = (a.b0.max(b.b0), a.b1.min(b.b1));
            if r <= l {
                continue;
            }
            let (mut x1, mut y1) = (a, b);
            let Some(fast) = dominated_on_overlap(&mut x1, &mut y1, l, r) else {
                continue;
            };
            decided += 1;
            let (mut x2, mut y2) = (a, b);
            let slow = exact_trim(&mut x2, &mut y2, l, r);
            assert_same_outcome((a, b), (fast, x1, y1), (slow, x2, y2));
        }
        assert!(decided > 1000, "the shortcut decided only {decided} pairs");
    }

    /// The unrolled bisector path gives bit for bit the general path's result on pairs with
    /// equal (or nearly equal) sigmas, touching, nested and shared ends included.
    #[test]
    fn bisector_path_matches_general_path() {
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        let mut split = 0;
        for i in 0..40000 {
            let sigma = if i % 2 == 0 {
                0.0
            } else {
                rng.random_range(0.0..3.0)
            };
            let (p0, p1) = ends(&mut rng);
            let (mut q0, mut q1) = ends(&mut rng);
            match i % 5 {
                0 => q0 = p0,
                1 => q1 = p1,
                2 => (q0, q1) = (p0, p1),
                _ => {}
            }
            let sx = rng.random_range(-3.0..4.0);
            let a = win(p0, p1, sigma, sx, -rng.random_range(1e-3..3.0));
            // Nearly equal sources too (the bisector root then falls anywhere).
            let sx2 = if i % 7 == 0 {
                sx + rng.random_range(-1e-9..1e-9)
            } else {
                rng.random_range(-3.0..4.0)
            };
            let sigma2 = if i % 11 == 0 {
                sigma * (1.0 + 1e-16)
            } else {
                sigma
            };
            let b = win(q0, q1, sigma2, sx2, -rng.random_range(1e-3..3.0));
            let (l, r) = (a.b0.max(b.b0), a.b1.min(b.b1));
            if r <= l || !equal_sigmas(&a, &b) {
                continue;
            }
            let (mut x1, mut y1) = (a, b);
            let fast = bisector_trim(&mut x1, &mut y1, l, r);
            let (mut x2, mut y2) = (a, b);
            let slow = general_trim(&mut x2, &mut y2, l, r);
            assert_same_outcome((a, b), (fast, x1, y1), (slow, x2, y2));
            if fast == Trim::Both && (x1.b1 < a.b1 || y1.b0 > b.b0) {
                split += 1;
            }
        }
        assert!(split > 1000, "only {split} pairs were trimmed at the root");
    }

    #[test]
    fn linear_branch_equal_sigma() {
        // Two sources with equal sigma: the bisector x = 0.5 splits the edge.
        let mut a = win(0.0, 1.0, 0.0, 0.0, -1.0);
        let mut b = win(0.0, 1.0, 0.0, 1.0, -1.0);
        assert_eq!(trim(&mut a, &mut b), Trim::Both);
        assert!((a.b1 - 0.5).abs() < 1e-12, "{a:?}");
        assert!((b.b0 - 0.5).abs() < 1e-12, "{b:?}");
        assert_eq!(a.b0, 0.0);
        assert_eq!(b.b1, 1.0);
    }

    #[test]
    fn hyperbola_branch() {
        // sigma differs by 0.2: root where sqrt(x^2+1) = 0.2 + sqrt((x-1)^2+1).
        let mut a = win(0.0, 1.0, 0.0, 0.0, -1.0);
        let mut b = win(0.0, 1.0, 0.2, 1.0, -1.0);
        assert_eq!(trim(&mut a, &mut b), Trim::Both);
        let x = a.b1;
        let f = |x: f64| (x * x + 1.0).sqrt() - 0.2 - ((x - 1.0) * (x - 1.0) + 1.0).sqrt();
        assert!(f(x).abs() < 1e-12, "root {x}: {}", f(x));
        assert!((b.b0 - x).abs() < 1e-15);
    }

    #[test]
    fn dominated_window_dies_and_duplicates_merge() {
        let mut a = win(0.2, 0.8, 0.0, 0.5, -1.0);
        let mut b = win(0.0, 1.0, 0.0, 0.5, -0.5);
        assert_eq!(trim(&mut a, &mut b), Trim::FirstDead);
        assert!(a.is_dead());
        let mut a = win(0.0, 0.5, 1.0, 0.3, -0.4);
        let mut b = win(0.5, 0.9, 1.0, 0.3, -0.4);
        assert_eq!(trim(&mut a, &mut b), Trim::SecondDead);
        assert_eq!((a.b0, a.b1), (0.0, 0.9));
        // Disjoint windows are left alone.
        let mut a = win(0.0, 0.4, 0.0, 0.0, -1.0);
        let mut b = win(0.5, 0.9, 5.0, 0.3, -0.4);
        assert_eq!(trim(&mut a, &mut b), Trim::Both);
        assert_eq!((a.b0, a.b1, b.b0, b.b1), (0.0, 0.4, 0.5, 0.9));
    }
}
