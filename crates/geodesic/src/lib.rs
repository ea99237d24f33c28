//! Geodesic distance fields on triangle meshes.
//!
//! Every method sits behind one narrow trait, [`GeodesicSolver`]: a solver is prepared once per
//! mesh (it owns what it needs, so it is `'static` and can be shared across threads), then asked
//! for distance fields from one or several [`Source`]s.
//!
//! | method | type | what it computes |
//! |---|---|---|
//! | [`Method::Exact`] | [`ExactGeodesic`] | exact polyhedral distance (window propagation) |
//! | [`Method::Fmm`] | [`FastMarching`] | fast marching (Kimmel-Sethian) with obtuse-angle unfolding; by default each update models a curved front whose curvature is carried along characteristics ([`FmmUpdate::CurvedFront`]) |
//! | [`Method::Heat`] | [`HeatMethod`] | heat method with reused sparse Cholesky factorisations; smooth, approximate |
//! | [`Method::Dijkstra`] | [`Dijkstra`] | shortest paths along mesh edges (the paper's baseline; overestimates) |
//!
//! Many sources at once (one field each) run in parallel with [`distances_many`]
//! ([`GeodesicSolver::distances_many`]); the exact solver reuses its per-solve buffers across
//! them ([`ExactWorkspace`]).
//!
//! Straightest geodesics (walk a length in a tangent direction, unfolding across edges) are in
//! [`straightest`] ([`Walker`]).
//!
//! Unreachable vertices (other components, or beyond the cut-off) get `f64::INFINITY`.

mod dijkstra;
mod error;
mod exact;
mod fmm;
mod heat;
mod solver;
pub mod straightest;

pub use dijkstra::Dijkstra;
pub use error::GeodesicError;
pub use exact::{ExactGeodesic, ExactMeshReport, ExactSchedule, ExactWorkspace};
#[doc(hidden)]
pub use fmm::trace_curved_front;
pub use fmm::{FastMarching, FmmUpdate};
pub use heat::HeatMethod;
pub use meshcore::{SurfacePoint, TriMesh};
pub use straightest::{Walk, WalkSegment, Walker};

/// Where a distance field starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Source {
    /// A mesh vertex.
    Vertex(u32),
    /// An arbitrary surface point (face + barycentric coordinates).
    Point(SurfacePoint),
}

/// Options of one solve.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolveOptions {
    /// Stop propagating past this distance; vertices farther away get `f64::INFINITY`.
    /// Methods that cannot stop early (heat) compute everything and then apply the cut-off.
    pub max_distance: Option<f64>,
}

impl SolveOptions {
    /// The validated cut-off: `max_distance`, or `+inf` without one. A NaN or non-positive
    /// cut-off is [`GeodesicError::InvalidCutoff`]. Every solver checks its options here.
    pub fn cutoff(&self) -> Result<f64, GeodesicError> {
        match self.max_distance {
            Some(c) if c.is_nan() || c <= 0.0 => Err(GeodesicError::InvalidCutoff(c)),
            Some(c) => Ok(c),
            None => Ok(f64::INFINITY),
        }
    }
}

meshcore::choice! {
    /// The available methods.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum Method: "geodesic method", GeodesicError {
        /// Exact polyhedral distance (window propagation).
        Exact = "exact",
        /// Fast marching on triangulated domains (Kimmel-Sethian) with obtuse-angle unfolding.
        Fmm = "fmm",
        /// Heat method (Crane et al.) with a reusable sparse Cholesky factorisation.
        Heat = "heat",
        /// Dijkstra on mesh edges.
        Dijkstra = "dijkstra",
    }
}

impl Method {
    /// Short lowercase name, as used on the command line ([`meshcore::Choice::name`]).
    pub fn name(self) -> &'static str {
        meshcore::Choice::name(self)
    }
}

/// A geodesic distance solver prepared for one mesh: [`ExactGeodesic`], [`FastMarching`],
/// [`HeatMethod`] or [`Dijkstra`].
pub trait GeodesicSolver: Send + Sync + std::fmt::Debug {
    /// Which method this is.
    fn method(&self) -> Method;
    /// Number of vertices of the mesh the solver was prepared for.
    fn n_vertices(&self) -> usize;
    /// Distance from the nearest of `sources` to every vertex, in vertex order.
    fn distances(&self, sources: &[Source], opts: &SolveOptions)
        -> Result<Vec<f64>, GeodesicError>;
    /// One distance field per entry of `sources` (in input order), each equal to
    /// [`GeodesicSolver::distances`] of that entry; computed in parallel (rayon), and by the
    /// exact solver with per-thread reused buffers ([`ExactGeodesic::distances_many`]). The
    /// first error in input order is returned.
    fn distances_many(
        &self,
        sources: &[Vec<Source>],
        opts: &SolveOptions,
    ) -> Result<Vec<Vec<f64>>, GeodesicError> {
        use rayon::prelude::*;
        let out: Vec<_> = sources
            .par_iter()
            .map(|s| self.distances(s, opts))
            .collect();
        out.into_iter().collect()
    }
}

/// Prepares a solver of the given method for `mesh`.
pub fn new_solver(
    mesh: &TriMesh,
    method: Method,
) -> Result<Box<dyn GeodesicSolver>, GeodesicError> {
    Ok(match method {
        Method::Exact => Box::new(ExactGeodesic::new(mesh)?),
        Method::Fmm => Box::new(FastMarching::new(mesh)?),
        Method::Heat => Box::new(HeatMethod::new(mesh)?),
        Method::Dijkstra => Box::new(Dijkstra::new(mesh)?),
    })
}

/// The method a solver can be prepared with on `mesh` when `requested` is asked for:
/// `requested` itself or, for [`Method::Exact`] when it cannot be prepared, [`Method::Fmm`],
/// then [`Method::Heat`]. Returns the method used (`None`: none could be prepared) and each
/// method tried before it that could not be, with its error.
pub fn usable_method(
    mesh: &TriMesh,
    requested: Method,
) -> (Option<Method>, Vec<(Method, GeodesicError)>) {
    let chain = match requested {
        Method::Exact => vec![Method::Exact, Method::Fmm, Method::Heat],
        other => vec![other],
    };
    let mut failed = Vec::new();
    for m in chain {
        match new_solver(mesh, m) {
            Ok(_) => return (Some(m), failed),
            Err(e) => failed.push((m, e)),
        }
    }
    (None, failed)
}

/// One distance field per entry of `sources`, computed in parallel (rayon) with the same solver
/// and options: [`GeodesicSolver::distances_many`]. Equivalent to calling
/// [`GeodesicSolver::distances`] for each entry in turn; the first error (in input order) is
/// returned.
pub fn distances_many(
    solver: &dyn GeodesicSolver,
    sources: &[Vec<Source>],
    opts: &SolveOptions,
) -> Result<Vec<Vec<f64>>, GeodesicError> {
    solver.distances_many(sources, opts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_usable_method_is_the_requested_one_where_it_can_be_prepared() {
        let sphere = meshcore::shapes::icosphere(1);
        for m in [Method::Exact, Method::Fmm, Method::Heat, Method::Dijkstra] {
            let (used, failed) = usable_method(&sphere, m);
            assert_eq!(used, Some(m));
            assert!(failed.is_empty());
        }
        // A degenerate mesh (one point): whatever is used, the methods tried before it are
        // named in order, and the exact request never goes past heat.
        let point = TriMesh::new(vec![meshcore::DVec3::ZERO; 3], vec![[0, 1, 2]]).unwrap();
        let (used, failed) = usable_method(&point, Method::Exact);
        let chain = [Method::Exact, Method::Fmm, Method::Heat];
        let tried: Vec<Method> = failed.iter().map(|f| f.0).chain(used).collect();
        assert_eq!(tried, chain[..tried.len()]);
    }
}
