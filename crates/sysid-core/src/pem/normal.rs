//! The normal equations `J^T W J`, `J^T W r` in the predictor parameters
//! `phi = (Abar, Bbar, C, D, K, x0)` (`Abar = A - K C`, `Bbar = B - K D`) and their map back
//! to `theta = (A, B, C, D, K, x0)`.
//!
//! In `phi` the state does not depend on `C` and `D`: their Jacobian rows are `e_i (x) z(t)^T`
//! with the regressor `z = (x, u)`, so their blocks are `W (x) sum z z^T` (static-static) and
//! the gradient `-sum (W e) z^T`. The chain rule `J_theta = J_phi T` uses the sparse
//! derivative `T = dphi/dtheta` ([`Predictor::predictor_map`]).

use super::predictor::{Predictor, Unpacked};
use crate::optim::{clear_upper, gram_add};
use faer::{Accum, Mat, MatMut, MatRef, Par};

/// Sparse columns of `T = dphi/dtheta`: `(row, value)` pairs per column.
pub(super) type SparseCols = Vec<Vec<(usize, f64)>>;

/// `dst = alpha a b` on the calling thread (the small per-sample products), leaving the
/// vector registers' upper halves clear for the scalar code around it ([`clear_upper`]).
pub(super) fn product(dst: MatMut<'_, f64>, a: MatRef<'_, f64>, b: MatRef<'_, f64>, alpha: f64) {
    faer::linalg::matmul::matmul(dst, Accum::Replace, a, b, alpha, Par::Seq);
    clear_upper();
}

/// Running sums of the regressor `z = (x, u)` over the samples: `sum (W e) z^T` always, and
/// with `acc` also `sum z z^T` (lower triangle, folded in per block by [`Self::fold`]) and the
/// block of `z` rows of the current block of samples.
pub(super) struct StaticSums {
    pub gz: Mat<f64>,
    pub zz: Mat<f64>,
    pub zbuf: Mat<f64>,
    acc: bool,
}

impl StaticSums {
    pub fn new(l: usize, nz: usize, block: usize, acc: bool) -> Self {
        StaticSums {
            gz: Mat::zeros(l, nz),
            zz: Mat::zeros(nz, nz),
            zbuf: Mat::zeros(if acc { block } else { 0 }, nz),
            acc,
        }
    }

    /// Adds one sample: regressor `z`, weighted error `wz = W e`, row `row` of the block.
    pub fn add(&mut self, z: &[f64], wz: &[f64], row: usize) {
        for (j, &zj) in z.iter().enumerate() {
            for (g, &w) in self.gz.col_as_slice_mut(j).iter_mut().zip(wz) {
                *g += w * zj;
            }
        }
        if self.acc {
            for (a, &za) in z.iter().enumerate() {
                self.zbuf[(row, a)] = za;
            }
        }
    }

    /// Adds the first `rows` regressors of the block to `sum z z^T` (one product per block,
    /// not a rank-one update per sample).
    pub fn fold(&mut self, rows: usize) {
        if self.acc {
            gram_add(
                self.zz.as_mut(),
                self.zbuf.as_ref().subrows(0, rows),
                Par::Seq,
            );
        }
    }
}

impl Predictor<'_> {
    /// The parameter index of entry `(i, j)` of `[C D]` (`None` for a `D` that is fixed).
    pub(super) fn static_index(&self, i: usize, j: usize) -> Option<usize> {
        let off = self.offsets();
        if j < self.n {
            Some(off.c + i * self.n + j)
        } else {
            off.d.map(|d| d + i * self.m + (j - self.n))
        }
    }

    /// The gradient in `phi` of the static parameters: `-sum (W e) z^T`.
    pub(super) fn static_gradient(&self, gz: &Mat<f64>, g: &mut [f64]) {
        for i in 0..self.l {
            for j in 0..self.n + self.m {
                if let Some(s) = self.static_index(i, j) {
                    g[s] = -gz[(i, j)];
                }
            }
        }
    }

    /// The static-static block `W (x) sum z z^T` of `J^T W J` in `phi`, into `h`.
    pub(super) fn static_block(&self, w: &Mat<f64>, zz: &Mat<f64>, h: &mut Mat<f64>) {
        let nz = self.n + self.m;
        for i in 0..self.l {
            for j in 0..nz {
                let Some(sij) = self.static_index(i, j) else {
                    continue;
                };
                for i2 in 0..self.l {
                    for j2 in 0..nz {
                        if let Some(s2) = self.static_index(i2, j2) {
                            h[(sij, s2)] = w[(i, i2)] * zz[(j.max(j2), j.min(j2))];
                        }
                    }
                }
            }
        }
    }

    /// `T = dphi/dtheta` at the model `pm`, as sparse columns.
    pub(super) fn predictor_map(&self, pm: &Unpacked) -> SparseCols {
        let (n, m, l) = (self.n, self.m, self.l);
        let off = self.offsets();
        let mut t: SparseCols = (0..self.p).map(|c| vec![(c, 1.0)]).collect();
        for r in 0..l {
            for i in 0..n {
                let kir = pm.k[(i, r)];
                if kir == 0.0 {
                    continue;
                }
                for j in 0..n {
                    t[off.c + r * n + j].push((off.a + i * n + j, -kir));
                }
                if let Some(id) = off.d {
                    for j in 0..m {
                        t[id + r * m + j].push((off.b + i * m + j, -kir));
                    }
                }
            }
        }
        if let Some(ik) = off.k {
            for i in 0..n {
                for r in 0..l {
                    let col = &mut t[ik + i * l + r];
                    for j in 0..n {
                        if pm.c[(r, j)] != 0.0 {
                            col.push((off.a + i * n + j, -pm.c[(r, j)]));
                        }
                    }
                    for j in 0..m {
                        if pm.d[(r, j)] != 0.0 {
                            col.push((off.b + i * m + j, -pm.d[(r, j)]));
                        }
                    }
                }
            }
        }
        t
    }
}

/// `T^T g` for the sparse `T`.
pub(super) fn gradient_to_theta(tmap: &SparseCols, g: &[f64]) -> Vec<f64> {
    tmap.iter()
        .map(|col| col.iter().map(|&(r, v)| v * g[r]).sum())
        .collect()
}

/// `T^T H T` for the sparse `T` and a symmetric `H`, made exactly symmetric (in 64 x 64
/// tiles, so that the mirror reads memory in order).
pub(super) fn matrix_to_theta(tmap: &SparseCols, h: &Mat<f64>) -> Mat<f64> {
    let np = tmap.len();
    // Y = H T, column by column
    let mut y = Mat::<f64>::zeros(np, np);
    for (c, tc) in tmap.iter().enumerate() {
        let yc = y.col_as_slice_mut(c);
        for &(r, v) in tc {
            for (a, b) in yc.iter_mut().zip(h.col_as_slice(r)) {
                *a += v * b;
            }
        }
    }
    let mut hth = Mat::<f64>::zeros(np, np);
    for c2 in 0..np {
        let yc = y.col_as_slice(c2);
        let hc = hth.col_as_slice_mut(c2);
        for (c1, tc) in tmap.iter().enumerate() {
            hc[c1] = tc.iter().map(|&(r, v)| v * yc[r]).sum();
        }
    }
    drop(y);
    const TILE: usize = 64;
    for jb in (0..np).step_by(TILE) {
        for ib in (jb..np).step_by(TILE) {
            for j in jb..(jb + TILE).min(np) {
                for i in ib.max(j + 1)..(ib + TILE).min(np) {
                    let a = 0.5 * (hth[(i, j)] + hth[(j, i)]);
                    hth[(i, j)] = a;
                    hth[(j, i)] = a;
                }
            }
        }
    }
    hth
}
