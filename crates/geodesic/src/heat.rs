use crate::{GeodesicError, GeodesicSolver, Method, SolveOptions, Source, TriMesh};

/// Heat method (not implemented yet).
#[derive(Debug, Clone)]
pub struct HeatMethod {
    n: usize,
}

impl HeatMethod {
    /// Prepares the solver for `mesh` (currently always an error: not implemented yet).
    pub fn new(mesh: &TriMesh) -> Result<Self, GeodesicError> {
        let _ = Self {
            n: mesh.n_vertices(),
        };
        Err(GeodesicError::NotImplemented("heat"))
    }
}

impl GeodesicSolver for HeatMethod {
    fn method(&self) -> Method {
        Method::Heat
    }
    fn n_vertices(&self) -> usize {
        self.n
    }
    fn distances(&self, _s: &[Source], _o: &SolveOptions) -> Result<Vec<f64>, GeodesicError> {
        Err(GeodesicError::NotImplemented("heat"))
    }
}
