//! Sparse Cholesky factors for the heat method: faer computes the fill-reducing ordering and the
//! numerical factorisation (supernodal or simplicial, whichever faer picks), then the factor is
//! copied into plain compressed-column arrays (`u32` row indices, diagonal kept apart, exact
//! zeros dropped) and solved with the hand-written triangular solves below.
//!
//! Why not faer's own `solve_in_place`: at the mesh sizes of interest (10^4-10^5 vertices) the
//! supernodes are tiny (a few columns), and the per-supernode dense kernels, the workspace
//! allocation and the permutation copies of faer's solve cost more than the arithmetic. The
//! flat loops here are 2-4x faster per solve and allocate nothing; a right-hand side that is
//! zero up to some index (a point source) skips the columns before it and every column whose
//! forward value is still zero.

use crate::GeodesicError;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::{SparseColMat, Triplet};
use faer::Side;

/// Square sparse symmetric matrix (lower triangle, original vertex numbering) built from
/// triplets; duplicates are summed and explicit zeros are kept as structural entries, so that
/// matrices assembled from the same triplet positions share one symbolic analysis.
pub(crate) fn lower_matrix(
    n: usize,
    trip: &[Triplet<u32, u32, f64>],
    what: &str,
) -> Result<SparseColMat<u32, f64>, GeodesicError> {
    SparseColMat::<u32, f64>::try_new_from_triplets(n, n, trip)
        .map_err(|e| GeodesicError::Numerical(format!("building the {what} matrix: {e:?}")))
}

/// Fill-reducing ordering (AMD) and symbolic factorisation of the pattern of `mat`.
pub(crate) fn analyse(
    mat: &SparseColMat<u32, f64>,
) -> Result<SymbolicCholesky<u32>, GeodesicError> {
    factorize_symbolic_cholesky(
        mat.symbolic(),
        Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )
    .map_err(|e| GeodesicError::Numerical(format!("symbolic Cholesky analysis failed: {e:?}")))
}

/// The permutation of a symbolic analysis as `(forward, inverse)`: internal index `p` is
/// original vertex `forward[p]`, and original vertex `v` is internal index `inverse[v]`.
pub(crate) fn permutation(symbolic: &SymbolicCholesky<u32>) -> (Vec<u32>, Vec<u32>) {
    match symbolic.perm() {
        Some(p) => {
            let (f, i) = p.arrays();
            (f.to_vec(), i.to_vec())
        }
        None => {
            let id: Vec<u32> = (0..symbolic.nrows() as u32).collect();
            (id.clone(), id)
        }
    }
}

/// Lower Cholesky factor `L` of `P A Pᵀ` (`P` the permutation of the symbolic analysis), in
/// compressed columns.
pub(crate) struct Factor {
    /// Diagonal of `L`.
    diag: Vec<f64>,
    /// Off-diagonal entries of column `j` are `col_ptr[j]..col_ptr[j + 1]`.
    col_ptr: Vec<usize>,
    /// Row of each off-diagonal entry (always greater than its column).
    row_idx: Vec<u32>,
    /// Value of each off-diagonal entry.
    val: Vec<f64>,
}

impl std::fmt::Debug for Factor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Factor")
            .field("n", &self.diag.len())
            .field("off_diagonal_nnz", &self.val.len())
            .finish()
    }
}

impl Factor {
    /// Numerical factorisation of `mat` (same pattern as the one `symbolic` was computed for).
    pub(crate) fn new(
        symbolic: &SymbolicCholesky<u32>,
        mat: &SparseColMat<u32, f64>,
        what: &str,
    ) -> Result<Self, GeodesicError> {
        let par = faer::get_global_parallelism();
        let mut values = vec![0.0f64; symbolic.len_val()];
        let mut mem = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .map_err(|_| {
            GeodesicError::Numerical(format!("out of memory factorising the {what} matrix"))
        })?;
        symbolic
            .factorize_numeric_llt(
                &mut values,
                mat.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| {
                GeodesicError::Numerical(format!(
                    "Cholesky factorisation of the {what} matrix failed ({e:?}); \
                     the mesh probably has near-degenerate faces"
                ))
            })?;
        let n = symbolic.nrows();
        let mut out = Factor {
            diag: vec![0.0; n],
            col_ptr: Vec::with_capacity(n + 1),
            row_idx: Vec::new(),
            val: Vec::new(),
        };
        out.col_ptr.push(0);
        let bad_layout = || {
            GeodesicError::Numerical(format!(
                "unexpected layout of the Cholesky factor of the {what} matrix"
            ))
        };
        match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let (cp, ri) = (s.col_ptr(), s.row_idx());
                out.row_idx.reserve(values.len());
                out.val.reserve(values.len());
                for j in 0..n {
                    let (lo, hi) = (cp[j] as usize, cp[j + 1] as usize);
                    // faer stores the diagonal first in each column.
                    if lo >= hi || ri[lo] as usize != j {
                        return Err(bad_layout());
                    }
                    out.diag[j] = values[lo];
                    for p in lo + 1..hi {
                        if values[p] != 0.0 {
                            out.row_idx.push(ri[p]);
                            out.val.push(values[p]);
                        }
                    }
                    out.col_ptr.push(out.val.len());
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                // Supernode `k`: columns begin..end, a dense column-major block of
                // (size + pattern) rows: the lower triangle of the diagonal block, then the rows
                // listed in its pattern.
                let (begin, end) = (s.supernode_begin(), s.supernode_end());
                let (cpr, cpv, ri) = (s.col_ptr_for_row_idx(), s.col_ptr_for_val(), s.row_idx());
                for k in 0..s.n_supernodes() {
                    let (c0, c1) = (begin[k] as usize, end[k] as usize);
                    if c0 != out.col_ptr.len() - 1 || c1 <= c0 || c1 > n {
                        return Err(bad_layout());
                    }
                    let size = c1 - c0;
                    let pattern = &ri[cpr[k] as usize..cpr[k + 1] as usize];
                    let block = &values[cpv[k] as usize..cpv[k + 1] as usize];
                    let rows = size + pattern.len();
                    if block.len() != rows * size {
                        return Err(bad_layout());
                    }
                    for jj in 0..size {
                        let col = &block[jj * rows..(jj + 1) * rows];
                        out.diag[c0 + jj] = col[jj];
                        for ii in jj + 1..size {
                            if col[ii] != 0.0 {
                                out.row_idx.push((c0 + ii) as u32);
                                out.val.push(col[ii]);
                            }
                        }
                        for (&r, &x) in pattern.iter().zip(&col[size..]) {
                            if x != 0.0 {
                                out.row_idx.push(r);
                                out.val.push(x);
                            }
                        }
                        out.col_ptr.push(out.val.len());
                    }
                }
                if out.col_ptr.len() != n + 1 {
                    return Err(bad_layout());
                }
            }
        }
        if out.diag.iter().any(|d| !(d.is_finite() && *d > 0.0))
            || out.row_idx.iter().any(|&r| r as usize >= n)
        {
            return Err(bad_layout());
        }
        Ok(out)
    }

    /// Solves `L Lᵀ x = b` in place (internal numbering). `b` must be zero before index
    /// `start` (pass 0 when unknown).
    pub(crate) fn solve_in_place(&self, x: &mut [f64], start: usize) {
        let n = self.diag.len();
        debug_assert_eq!(x.len(), n);
        debug_assert!(x[..start.min(n)].iter().all(|&v| v == 0.0));
        // Forward: L y = b, column by column; columns whose value is zero change nothing.
        for j in start..n {
            let xj = x[j];
            if xj == 0.0 {
                continue;
            }
            let xj = xj / self.diag[j];
            x[j] = xj;
            let r = self.col_ptr[j]..self.col_ptr[j + 1];
            for (&i, &l) in self.row_idx[r.clone()].iter().zip(&self.val[r]) {
                x[i as usize] -= l * xj;
            }
        }
        // Backward: Lᵀ x = y, a dot product per column (two accumulators to hide latency).
        for j in (0..n).rev() {
            let r = self.col_ptr[j]..self.col_ptr[j + 1];
            let (ri, v) = (&self.row_idx[r.clone()], &self.val[r]);
            let (mut s0, mut s1) = (0.0f64, 0.0f64);
            let mut ci = ri.chunks_exact(2);
            let mut cv = v.chunks_exact(2);
            for (i2, v2) in (&mut ci).zip(&mut cv) {
                s0 += v2[0] * x[i2[0] as usize];
                s1 += v2[1] * x[i2[1] as usize];
            }
            if let ([i], [l]) = (ci.remainder(), cv.remainder()) {
                s0 += l * x[*i as usize];
            }
            x[j] = (x[j] - (s0 + s1)) / self.diag[j];
        }
    }
}
