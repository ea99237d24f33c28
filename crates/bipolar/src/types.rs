//! Public data types: options, points, descriptor.

use crate::Key;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// How the constant geodesic step is given.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum LevelSpec {
    /// `N` levels between the first two reference points: `step = d(r, q) / N`.
    Count(u32),
    /// An explicit step (mesh units).
    Step(f64),
}

meshcore::choice! {
    /// The tangent method (specification §2.4).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
    pub enum TangentMethod: "tangent method", crate::BipolarError {
        /// M0: exact tangent of the piecewise-linear isoline, `normalize(n_f x grad_f U)`
        /// (for the iso-angle rule: the smoothed per-vertex gradient, M0s, interpolated).
        #[default]
        Gradient = "gradient",
        /// M1, the paper's method 1: principal axis of the strip of vertices with
        /// `|U - lambda| <= epsilon` within a radius of the point.
        Strip = "strip",
        /// M2, the paper's method 2: derivative of a least-squares cubic B-spline fitted to the
        /// level-curve polyline.
        Spline = "spline",
    }
}

/// Which intersection points are kept (the two readings of the paper's rule, §2.5).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum SelectionRule {
    /// A: intersections of level `i` of the first field and level `j` of the second whose
    /// `|cos|` is within `tolerance` of an angle level `alpha k / K`. Keys `(i, j, side)`.
    Filter {
        /// Half-width of the acceptance band (e.g. `alpha / (4 K)`).
        tolerance: f64,
    },
    /// B: points along the level curves of the first field where `|cos|` equals exactly an
    /// angle level `alpha k / K`. Keys `(i, k, side, sign(cos))`. The default.
    #[default]
    IsoAngle,
    /// Every intersection of the two level families (no angle selection). Keys `(i, j, side)`.
    All,
}

meshcore::choice! {
    /// The name of a [`SelectionRule`] without its parameters (`filter`, `isoangle`, `all`), for
    /// choosing a rule by name.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
    pub enum SelectionKind: "rule", crate::BipolarError {
        /// [`SelectionRule::Filter`].
        Filter = "filter",
        /// [`SelectionRule::IsoAngle`].
        #[default]
        IsoAngle = "isoangle" | "iso-angle",
        /// [`SelectionRule::All`].
        All = "all",
    }
}

impl SelectionKind {
    /// The rule of this kind; `filter_tolerance` is the band of [`SelectionRule::Filter`]
    /// (ignored by the others).
    pub fn rule(self, filter_tolerance: f64) -> SelectionRule {
        match self {
            SelectionKind::Filter => SelectionRule::Filter {
                tolerance: filter_tolerance,
            },
            SelectionKind::IsoAngle => SelectionRule::IsoAngle,
            SelectionKind::All => SelectionRule::All,
        }
    }
}

impl SelectionRule {
    /// The kind of this rule.
    pub fn kind(&self) -> SelectionKind {
        match self {
            SelectionRule::Filter { .. } => SelectionKind::Filter,
            SelectionRule::IsoAngle => SelectionKind::IsoAngle,
            SelectionRule::All => SelectionKind::All,
        }
    }
}

meshcore::choice! {
    /// How the iso-angle rule ([`SelectionRule::IsoAngle`]) turns the opening along a level curve
    /// into points.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
    pub enum IsoCrossings: "iso-angle crossings", crate::BipolarError {
        /// One point per angle level and curve run: along each run of a level curve (a piece, cut
        /// where a tangent is undefined), the signed opening angle `psi = atan2(sin, cos)` between
        /// the two tangents (unwrapped, `sin` signed by the side) is replaced by its best monotone
        /// least-squares fit (isotonic regression, weighted by arc length; increasing or decreasing,
        /// whichever fits better), and each angle level is taken where the fit crosses it. On a
        /// smooth surface the opening is monotone along the curve and this equals
        /// [`IsoCrossings::Every`]; on noisy or faceted meshes the raw opening wiggles around a
        /// level and crosses it several times, which this rule turns into one point. The default.
        #[default]
        Monotone = "monotone",
        /// Every crossing of an angle level by the piecewise-linear opening along the curve (several
        /// per key where the opening wiggles; those keys are then ambiguous).
        Every = "every",
    }
}

meshcore::choice! {
    /// What the iso-angle rule ([`SelectionRule::IsoAngle`]) does with a key found at several
    /// places of one level curve of the first field. A level curve cut by a hole (on faces, the eye
    /// openings between the outer eye corners) comes in pieces, one on each side of the hole, whose
    /// opening ranges overlap: each piece then holds a point with the same key `(i, k, side, sign)`.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
    pub enum IsoRepeats: "iso-angle repeated keys", crate::BipolarError {
        /// Keep the place nearest the geodesic between the two references, the one with the
        /// smallest second field `U_b` (on level `i` of `U_a`, the smallest `U_a + U_b`): the piece
        /// on the side of the hole where the two fields meet directly. Only when every other place is
        /// farther by at least a quarter of the level step; otherwise all stay, flagged ambiguous.
        /// The default.
        #[default]
        Nearest = "nearest",
        /// Keep every place, flagged ambiguous (never paired by a keyed distance).
        Ambiguous = "ambiguous",
    }
}

/// Settings of the iso-angle rule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct IsoAngleOptions {
    /// Which crossings become points.
    pub crossings: IsoCrossings,
    /// Gaussian smoothing of the opening angle along the curve before the crossings are taken:
    /// standard deviation in units of the mean edge length (0: none).
    pub smoothing: f64,
    /// What happens to a key found at several places.
    #[serde(default)]
    pub repeats: IsoRepeats,
}

impl Default for IsoAngleOptions {
    fn default() -> Self {
        Self {
            crossings: IsoCrossings::Monotone,
            smoothing: 0.0,
            repeats: IsoRepeats::Nearest,
        }
    }
}

/// Settings of the strip tangent method (M1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StripOptions {
    /// Strip half-width `epsilon` in units of the mean edge length.
    pub epsilon: f64,
    /// Neighbourhood radius `rho` in units of the mean edge length.
    pub radius: f64,
    /// Minimum number of strip vertices (else fall back to M0).
    pub min_vertices: usize,
    /// Minimum ratio of the two largest covariance eigenvalues (else fall back to M0).
    pub min_ratio: f64,
}

impl Default for StripOptions {
    fn default() -> Self {
        Self {
            epsilon: 0.6,
            radius: 4.0,
            min_vertices: 5,
            min_ratio: 2.0,
        }
    }
}

/// Settings of the B-spline tangent method (M2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SplineOptions {
    /// Control-point spacing in units of the mean edge length (`None`: the bspline crate's
    /// default, 4 x the median chord of the polyline).
    pub control_spacing: Option<f64>,
    /// Dimensionless smoothing weight (P-spline penalty).
    pub smoothing: f64,
    /// Pieces with fewer points use M0 instead.
    pub min_points: usize,
}

impl Default for SplineOptions {
    fn default() -> Self {
        Self {
            control_spacing: None,
            smoothing: 1e-3,
            min_points: 8,
        }
    }
}

/// Options of the descriptor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DescriptorOptions {
    /// Geodesic step.
    pub levels: LevelSpec,
    /// Region: keep levels `1..=max_level` of both fields (`None`: as far as the fields go).
    pub max_level: Option<u32>,
    /// Region: vertices to use (`false` vertices act as holes); one entry per vertex.
    #[serde(skip)]
    pub vertex_mask: Option<Vec<bool>>,
    /// Region: leave out the band within this geodesic distance (mesh units) of the mesh
    /// boundary (holes, eye openings, a scan's border), as if it were a hole. Near a hole the
    /// fields bend around it and the level curves of two acquisitions of one surface cross in
    /// different places (docs/scans.md, "Yaw"). Holes whose boundary is shorter than twice the
    /// margin get no band. `None` keeps everything. The band is built on every call (an exact
    /// solve from the boundary); for many descriptors of one surface build it once with
    /// [`crate::boundary_band`] and leave it out through `vertex_mask`, which is the same.
    #[serde(default)]
    pub boundary_margin: Option<f64>,
    /// Number of angle levels `K` (targets `alpha k / K`, `k = 0..=K`).
    pub angles: u32,
    /// Maximum angular opening `alpha` in `(0, 1]` (below 1: `k = K` is then not a tangency).
    pub alpha: f64,
    /// Selection rule.
    pub rule: SelectionRule,
    /// Tangent method.
    pub tangent: TangentMethod,
    /// Strip method settings.
    pub strip: StripOptions,
    /// Spline method settings.
    pub spline: SplineOptions,
    /// Iso-angle rule settings.
    #[serde(default)]
    pub isoangle: IsoAngleOptions,
    /// Intersections with `|sin| < min_sin` between the level curves are dropped (their
    /// position is ill-conditioned, §2.3).
    pub min_sin: f64,
}

impl Default for DescriptorOptions {
    fn default() -> Self {
        Self {
            levels: LevelSpec::Count(10),
            max_level: None,
            vertex_mask: None,
            boundary_margin: None,
            angles: 8,
            alpha: 0.95,
            rule: SelectionRule::IsoAngle,
            tangent: TangentMethod::Gradient,
            strip: StripOptions::default(),
            spline: SplineOptions::default(),
            isoangle: IsoAngleOptions::default(),
            min_sin: 1e-3,
        }
    }
}

/// One point of the descriptor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DescriptorPoint {
    /// Position.
    pub position: DVec3,
    /// Key (§2.6).
    pub key: Key,
    /// Signed cosine of the opening between the two level curves (tangents oriented along
    /// `n x grad U`).
    pub cos: f64,
    /// Face containing the point (`u32::MAX` when read from a CSV/PLY file).
    pub face: u32,
    /// Barycentric coordinates in that face (zero when read from a CSV/PLY file).
    pub bary: DVec3,
    /// True when several points share this key (decided on all intersections before any
    /// angle selection; correspondence-based distances should ignore such points).
    pub ambiguous: bool,
}

/// Counters describing how a descriptor was built.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DescriptorStats {
    /// Level-curve intersections found (after merging duplicates on shared edges).
    pub intersections: usize,
    /// Intersections dropped as ill-conditioned (`|sin| < min_sin` or singular face).
    pub ill_conditioned: usize,
    /// Tangents for which the strip or spline method fell back to the gradient method.
    pub tangent_fallbacks: usize,
    /// Points marked ambiguous.
    pub ambiguous: usize,
    /// Degenerate faces skipped.
    pub degenerate_faces: usize,
}

/// The bipolar descriptor of a surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Descriptor {
    /// Points, sorted by key then position.
    pub points: Vec<DescriptorPoint>,
    /// Geodesic step between levels.
    pub step: f64,
    /// Highest level used.
    pub max_level: u32,
    /// Geodesic distance between the first two reference points (NaN when unknown).
    pub reference_distance: f64,
    /// Reference point positions (empty when unknown).
    pub references: Vec<DVec3>,
    /// Options used.
    pub options: DescriptorOptions,
    /// Build counters.
    pub stats: DescriptorStats,
}

impl Descriptor {
    /// Positions of the points, in point order.
    pub fn positions(&self) -> Vec<DVec3> {
        self.points.iter().map(|p| p.position).collect()
    }

    /// Packed keys ([`Key::pack`]) of the points, in point order.
    pub fn packed_keys(&self) -> Vec<u64> {
        self.points.iter().map(|p| p.key.pack()).collect()
    }

    /// Packed keys and positions of the points a keyed comparison pairs: every point, or
    /// (`keep_ambiguous` false) those not flagged ambiguous.
    pub fn keyed_points(&self, keep_ambiguous: bool) -> (Vec<u64>, Vec<DVec3>) {
        self.points
            .iter()
            .filter(|p| keep_ambiguous || !p.ambiguous)
            .map(|p| (p.key.pack(), p.position))
            .unzip()
    }

    /// An FNV-1a hash of the points' packed keys and the bit patterns of their positions, in
    /// point order: equal fingerprints mean the same points, bit for bit (a check that a change
    /// of the pipeline left a descriptor as it was).
    pub fn fingerprint(&self) -> u64 {
        let mut h = 0xcbf2_9ce4_8422_2325_u64;
        let mut eat = |x: u64| {
            for b in x.to_le_bytes() {
                h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
            }
        };
        for p in &self.points {
            eat(p.key.pack());
            for c in p.position.to_array() {
                eat(c.to_bits());
            }
        }
        h
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_fingerprint_changes_with_any_point_bit_for_bit() {
        let mesh = meshcore::shapes::icosphere(3);
        let solver = geodesic::new_solver(&mesh, geodesic::Method::Dijkstra).unwrap();
        let references = [geodesic::Source::Vertex(0), geodesic::Source::Vertex(5)];
        let d = crate::describe(
            &crate::Surface::new(mesh),
            crate::Fields::Solve {
                solver: solver.as_ref(),
                references: &references,
            },
            &crate::DescriptorOptions::default(),
        )
        .unwrap();
        assert!(d.len() > 10);
        assert_eq!(d.clone().fingerprint(), d.fingerprint());
        let mut moved = d.clone();
        let x = &mut moved.points[3].position.x;
        *x = f64::from_bits(x.to_bits() + 1);
        assert_ne!(moved.fingerprint(), d.fingerprint());
        let mut fewer = d.clone();
        fewer.points.pop();
        assert_ne!(fewer.fingerprint(), d.fingerprint());
    }
}
