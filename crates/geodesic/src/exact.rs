use crate::{GeodesicError, GeodesicSolver, Method, SolveOptions, Source, TriMesh};

/// Exact polyhedral geodesic distance (not implemented yet).
#[derive(Debug, Clone)]
pub struct ExactGeodesic {
    n: usize,
}

impl ExactGeodesic {
    /// Prepares the solver for `mesh` (currently always an error: not implemented yet).
    pub fn new(mesh: &TriMesh) -> Result<Self, GeodesicError> {
        let _ = Self {
            n: mesh.n_vertices(),
        };
        Err(GeodesicError::NotImplemented("exact"))
    }
}

impl GeodesicSolver for ExactGeodesic {
    fn method(&self) -> Method {
        Method::Exact
    }
    fn n_vertices(&self) -> usize {
        self.n
    }
    fn distances(&self, _s: &[Source], _o: &SolveOptions) -> Result<Vec<f64>, GeodesicError> {
        Err(GeodesicError::NotImplemented("exact"))
    }
}
