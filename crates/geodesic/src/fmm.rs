use crate::{GeodesicError, GeodesicSolver, Method, SolveOptions, Source, TriMesh};

/// Fast marching (not implemented yet).
#[derive(Debug, Clone)]
pub struct FastMarching {
    n: usize,
}

impl FastMarching {
    /// Prepares the solver for `mesh` (currently always an error: not implemented yet).
    pub fn new(mesh: &TriMesh) -> Result<Self, GeodesicError> {
        let _ = Self {
            n: mesh.n_vertices(),
        };
        Err(GeodesicError::NotImplemented("fmm"))
    }
}

impl GeodesicSolver for FastMarching {
    fn method(&self) -> Method {
        Method::Fmm
    }
    fn n_vertices(&self) -> usize {
        self.n
    }
    fn distances(&self, _s: &[Source], _o: &SolveOptions) -> Result<Vec<f64>, GeodesicError> {
        Err(GeodesicError::NotImplemented("fmm"))
    }
}
