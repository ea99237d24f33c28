//! Sparse Cholesky factors for the heat method: faer computes the fill-reducing ordering and the
//! numerical factorisation (supernodal or simplicial, whichever faer picks); the factor is then
//! copied out (exact zeros, e.g. of faer's relaxed supernodes, dropped), regrouped into
//! fundamental supernodes (row indices stored once per supernode, values as small dense blocks)
//! and solved with the hand-written triangular solves below.
//!
//! Why not faer's own `solve_in_place`: at 10^3-10^5 vertices most supernodes have a few
//! columns, and per solve faer dispatches a dense kernel per supernode, allocates its workspace
//! and copies the right-hand side through the permutation twice; profiled on a 10k-vertex
//! sphere this was ~75 % of the per-solve time. The loops here allocate nothing, work in the
//! permuted numbering directly (the caller keeps its per-solve arrays in it), and skip every
//! column whose forward value is zero (a point source starts deep in the elimination tree).
//! The solves are sequential and deterministic (fixed summation order).

use crate::GeodesicError;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::Side;

/// Sparsity pattern (lower triangle, original vertex numbering) shared by several matrices:
/// sorted once, then filled with each matrix's values (duplicates summed; explicit zeros stay
/// structural entries, so all the matrices share one symbolic analysis).
pub(crate) struct Pattern {
    symbolic: SymbolicSparseColMat<u32>,
    argsort: Argsort<u32>,
}

impl Pattern {
    /// The pattern of the `n` x `n` matrix with entries at `idx`.
    pub(crate) fn new(n: usize, idx: &[Pair<u32, u32>]) -> Result<Self, GeodesicError> {
        let (symbolic, argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, idx)
            .map_err(|e| GeodesicError::Numerical(format!("building the sparse pattern: {e:?}")))?;
        Ok(Self { symbolic, argsort })
    }

    /// The matrix with value `vals[k]` at entry `idx[k]` of [`Pattern::new`].
    pub(crate) fn matrix(
        &self,
        vals: &[f64],
        what: &str,
    ) -> Result<SparseColMat<u32, f64>, GeodesicError> {
        SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, vals)
            .map_err(|e| GeodesicError::Numerical(format!("building the {what} matrix: {e:?}")))
    }
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

/// Lower Cholesky factor `L` of `P A Pᵀ` (`P` the permutation of the symbolic analysis).
pub(crate) struct Factor {
    /// Diagonal of `L`.
    diag: Vec<f64>,
    /// Off-diagonal part, by supernodes.
    blocks: Blocks,
}

/// `L` in compressed columns (off-diagonal entries only), the intermediate form between faer's
/// factor and [`Blocks`].
struct Csc {
    diag: Vec<f64>,
    /// Off-diagonal entries of column `j` are `col_ptr[j]..col_ptr[j + 1]`.
    col_ptr: Vec<usize>,
    row_idx: Vec<u32>,
    val: Vec<f64>,
}

/// The factor grouped into fundamental supernodes (consecutive columns `c0..c1` whose
/// off-diagonal rows are the rest of the block plus one shared list of rows below it): the
/// row indices are stored once per supernode and the values as small dense blocks, which
/// halves the index traffic of the solves and lets the inner loops vectorise.
#[derive(Default)]
struct Blocks {
    /// First column of each supernode, plus `n` at the end.
    begin: Vec<u32>,
    /// Rows below supernode `s`: `pat[pat_ptr[s]..pat_ptr[s + 1]]` (ascending).
    pat_ptr: Vec<usize>,
    pat: Vec<u32>,
    /// Strictly lower triangle of the diagonal block, packed by columns.
    tri_ptr: Vec<usize>,
    tri: Vec<f64>,
    /// Rows of `pat` times the block's columns, row-major.
    rect_ptr: Vec<usize>,
    rect: Vec<f64>,
}

impl Blocks {
    fn from_csc(csc: &Csc) -> Self {
        let (col_ptr, row_idx, val) = (&csc.col_ptr, &csc.row_idx, &csc.val);
        let n = csc.diag.len();
        // Columns sorted by row.
        let mut rows: Vec<u32> = Vec::with_capacity(row_idx.len());
        let mut vals: Vec<f64> = Vec::with_capacity(val.len());
        let mut tmp: Vec<(u32, f64)> = Vec::new();
        for j in 0..n {
            let r = col_ptr[j]..col_ptr[j + 1];
            if row_idx[r.clone()].is_sorted() {
                rows.extend_from_slice(&row_idx[r.clone()]);
                vals.extend_from_slice(&val[r]);
                continue;
            }
            tmp.clear();
            tmp.extend(
                row_idx[r.clone()]
                    .iter()
                    .copied()
                    .zip(val[r].iter().copied()),
            );
            tmp.sort_unstable_by_key(|e| e.0);
            rows.extend(tmp.iter().map(|e| e.0));
            vals.extend(tmp.iter().map(|e| e.1));
        }
        let col = |j: usize| col_ptr[j]..col_ptr[j + 1];
        let mut b = Blocks {
            begin: vec![0],
            pat_ptr: vec![0],
            tri_ptr: vec![0],
            rect_ptr: vec![0],
            ..Default::default()
        };
        let mut c0 = 0;
        while c0 < n {
            let mut c1 = c0 + 1;
            while c1 < n {
                let (prev, next) = (&rows[col(c1 - 1)], &rows[col(c1)]);
                if prev.first() == Some(&(c1 as u32)) && &prev[1..] == next {
                    c1 += 1;
                } else {
                    break;
                }
            }
            let k = c1 - c0;
            let pat = &rows[col(c1 - 1)];
            b.pat.extend_from_slice(pat);
            for jj in 0..k {
                let v = &vals[col(c0 + jj)];
                b.tri.extend_from_slice(&v[..k - 1 - jj]);
            }
            let m = pat.len();
            let base = b.rect.len();
            b.rect.resize(base + m * k, 0.0);
            for jj in 0..k {
                let v = &vals[col(c0 + jj)][k - 1 - jj..];
                for (r, &x) in v.iter().enumerate() {
                    b.rect[base + r * k + jj] = x;
                }
            }
            b.begin.push(c1 as u32);
            b.pat_ptr.push(b.pat.len());
            b.tri_ptr.push(b.tri.len());
            b.rect_ptr.push(b.rect.len());
            c0 = c1;
        }
        b
    }
}

/// `Σ a_i b_i` with four accumulators (fixed order: deterministic).
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for q in 0..4 {
            s[q] += x[q] * y[q];
        }
    }
    let mut t = (s[0] + s[2]) + (s[1] + s[3]);
    for (x, y) in ra.iter().zip(rb) {
        t += x * y;
    }
    t
}

impl std::fmt::Debug for Factor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Factor")
            .field("n", &self.diag.len())
            .field("supernodes", &(self.blocks.begin.len() - 1))
            .field(
                "off_diagonal_nnz",
                &(self.blocks.tri.len() + self.blocks.rect.len()),
            )
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
        let mut out = Csc {
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
        let blocks = Blocks::from_csc(&out);
        Ok(Factor {
            diag: out.diag,
            blocks,
        })
    }

    /// Solves `L Lᵀ x = b` in place (internal numbering). `b` must be zero before index
    /// `start` (pass 0 when unknown).
    pub(crate) fn solve_in_place(&self, x: &mut [f64], start: usize) {
        let b = &self.blocks;
        let ns = b.begin.len() - 1;
        debug_assert_eq!(x.len(), self.diag.len());
        // Forward: L y = b.
        for s in 0..ns {
            let (c0, c1) = (b.begin[s] as usize, b.begin[s + 1] as usize);
            if c1 <= start {
                continue;
            }
            let k = c1 - c0;
            if k == 1 {
                // Single column: a plain sparse column.
                let v = x[c0];
                if v != 0.0 {
                    let v = v / self.diag[c0];
                    x[c0] = v;
                    let r = b.pat_ptr[s]..b.pat_ptr[s + 1];
                    for (&i, &l) in b.pat[r].iter().zip(&b.rect[b.rect_ptr[s]..]) {
                        x[i as usize] -= l * v;
                    }
                }
                continue;
            }
            let (lo, hi) = x.split_at_mut(c1);
            let xt = &mut lo[c0..];
            let tri = &b.tri[b.tri_ptr[s]..b.tri_ptr[s + 1]];
            let diag = &self.diag[c0..c1];
            let mut t = 0;
            let mut any = false;
            for jj in 0..k {
                let len = k - 1 - jj;
                let v = xt[jj];
                if v == 0.0 {
                    t += len;
                    continue;
                }
                any = true;
                let v = v / diag[jj];
                xt[jj] = v;
                let (_, below) = xt.split_at_mut(jj + 1);
                for (y, &l) in below.iter_mut().zip(&tri[t..t + len]) {
                    *y -= l * v;
                }
                t += len;
            }
            if !any {
                continue;
            }
            let pat = &b.pat[b.pat_ptr[s]..b.pat_ptr[s + 1]];
            let rect = &b.rect[b.rect_ptr[s]..b.rect_ptr[s + 1]];
            for (&r, w) in pat.iter().zip(rect.chunks_exact(k)) {
                hi[r as usize - c1] -= dot(w, xt);
            }
        }
        // Backward: Lᵀ x = y.
        for s in (0..ns).rev() {
            let (c0, c1) = (b.begin[s] as usize, b.begin[s + 1] as usize);
            let k = c1 - c0;
            let pat = &b.pat[b.pat_ptr[s]..b.pat_ptr[s + 1]];
            let rect = &b.rect[b.rect_ptr[s]..b.rect_ptr[s + 1]];
            if k == 1 {
                let (mut s0, mut s1) = (0.0f64, 0.0f64);
                let (mut ci, mut cv) = (pat.chunks_exact(2), rect.chunks_exact(2));
                for (i2, v2) in (&mut ci).zip(&mut cv) {
                    s0 += v2[0] * x[i2[0] as usize];
                    s1 += v2[1] * x[i2[1] as usize];
                }
                if let ([i], [l]) = (ci.remainder(), cv.remainder()) {
                    s0 += l * x[*i as usize];
                }
                x[c0] = (x[c0] - (s0 + s1)) / self.diag[c0];
                continue;
            }
            let (lo, hi) = x.split_at_mut(c1);
            let xt = &mut lo[c0..];
            for (&r, w) in pat.iter().zip(rect.chunks_exact(k)) {
                let xr = hi[r as usize - c1];
                for (y, &l) in xt.iter_mut().zip(w) {
                    *y -= l * xr;
                }
            }
            let tri = &b.tri[b.tri_ptr[s]..b.tri_ptr[s + 1]];
            let diag = &self.diag[c0..c1];
            let mut end = tri.len();
            for jj in (0..k).rev() {
                let len = k - 1 - jj;
                let col = &tri[end - len..end];
                end -= len;
                let (head, below) = xt.split_at_mut(jj + 1);
                head[jj] = (head[jj] - dot(col, below)) / diag[jj];
            }
        }
    }
}
