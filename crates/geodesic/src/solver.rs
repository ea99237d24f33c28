//! What the four methods share: the one [`GeodesicSolver`] implementation (option checks and
//! the cut-off), the validation of sources into seeds and the priority-queue entry of the
//! vertex-ordered solvers.

use crate::{GeodesicError, GeodesicSolver, Method, SolveOptions, Source};
use glam::DVec3;
use std::cmp::Ordering;

/// One method's solve. Every type implementing it is a [`GeodesicSolver`] through the blanket
/// implementation below, which validates the options and sets every distance beyond the cut-off
/// to `+inf`, so a method only computes its field.
pub trait Field: Send + Sync + std::fmt::Debug {
    /// Which method this is.
    const METHOD: Method;
    /// The vertex positions of the mesh the solver was prepared for.
    fn positions(&self) -> &[DVec3];
    /// Distances from `sources`; the method may stop propagating past `cut` (a validated
    /// cut-off, `+inf` without one), values beyond it are discarded by the caller.
    fn field(&self, sources: &[Source], cut: f64) -> Result<Vec<f64>, GeodesicError>;
    /// [`Field::field`] for each source set, in parallel (rayon); a method may share work
    /// between the sets as long as each result equals its own [`Field::field`]. The first
    /// error in input order is returned.
    fn fields(&self, sets: &[Vec<Source>], cut: f64) -> Result<Vec<Vec<f64>>, GeodesicError> {
        use rayon::prelude::*;
        let out: Vec<_> = sets.par_iter().map(|s| self.field(s, cut)).collect();
        out.into_iter().collect()
    }
}

impl<T: Field> GeodesicSolver for T {
    fn method(&self) -> Method {
        T::METHOD
    }
    fn n_vertices(&self) -> usize {
        self.positions().len()
    }
    fn distances(
        &self,
        sources: &[Source],
        opts: &SolveOptions,
    ) -> Result<Vec<f64>, GeodesicError> {
        let cut = opts.cutoff()?;
        let mut dist = self.field(sources, cut)?;
        if cut.is_finite() {
            dist.iter_mut()
                .filter(|d| **d > cut)
                .for_each(|d| *d = f64::INFINITY);
        }
        Ok(dist)
    }
    fn distances_many(
        &self,
        sources: &[Vec<Source>],
        opts: &SolveOptions,
    ) -> Result<Vec<Vec<f64>>, GeodesicError> {
        let cut = opts.cutoff()?;
        let mut out = self.fields(sources, cut)?;
        if cut.is_finite() {
            out.iter_mut()
                .flatten()
                .filter(|d| **d > cut)
                .for_each(|d| {
                    *d = f64::INFINITY;
                });
        }
        Ok(out)
    }
}

/// Validates sources and turns them into (vertex, initial distance) seeds.
pub(crate) fn seeds(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    sources: &[Source],
) -> Result<Vec<(u32, f64)>, GeodesicError> {
    if sources.is_empty() {
        return Err(GeodesicError::NoSource);
    }
    let mut out = Vec::new();
    for s in sources {
        match *s {
            Source::Vertex(v) => {
                if v as usize >= positions.len() {
                    return Err(GeodesicError::SourceOutOfRange {
                        vertex: v,
                        vertices: positions.len(),
                    });
                }
                out.push((v, 0.0));
            }
            Source::Point(sp) => {
                let tri =
                    triangles
                        .get(sp.face as usize)
                        .ok_or(meshcore::MeshError::FaceOutOfRange {
                            face: sp.face,
                            faces: triangles.len(),
                        })?;
                let b = sp.bary;
                if !b.is_finite() || b.min_element() < -1e-9 || (b.element_sum() - 1.0).abs() > 1e-9
                {
                    return Err(meshcore::MeshError::InvalidBarycentric(b.x, b.y, b.z).into());
                }
                let p = b.x * positions[tri[0] as usize]
                    + b.y * positions[tri[1] as usize]
                    + b.z * positions[tri[2] as usize];
                for &v in tri {
                    out.push((v, (positions[v as usize] - p).length()));
                }
            }
        }
    }
    Ok(out)
}

/// Priority-queue entry `(distance, vertex)` of a max-heap that pops the smallest distance
/// first, ties to the smallest vertex id (the deterministic order of every solver).
#[derive(Debug, PartialEq)]
pub(crate) struct Item(pub f64, pub u32);
impl Eq for Item {}
impl Ord for Item {
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then_with(|| o.1.cmp(&self.1))
    }
}
impl PartialOrd for Item {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
