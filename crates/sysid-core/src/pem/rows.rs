//! Every Jacobian row in `theta` directly: `dŷ/dtheta = C S + G` with `S(t) = dx/dtheta`,
//! `S(t+1) = (A - K C) S + F` (`F` the direct derivative of the right-hand side, for `C` and
//! `D` through `-K`, for `K_ij` the error `e_j` in row `i`), folded into `J^T W J` and
//! `J^T W r` block by block. `O(N l p^2)`: the reference the structured forms are tested
//! against, and the initial-state pre-step (only the columns from `col_lo` on).

use super::normal::product;
use super::predictor::{Filter, Predictor};
use crate::error::Result;
use crate::optim::Evaluation;
use crate::optim::{clear_upper, flush_tiny_mat, gram_add, mirror_lower, small_par, FLUSH_EVERY};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};

impl Predictor<'_> {
    /// The forcing `F(t)` of the sensitivities of columns `lo..p`, added to `s2`.
    fn add_forcing(&self, f: &Filter, s2: &mut Mat<f64>, u: &[f64], lo: usize) {
        let (n, m, l) = (self.n, self.m, self.l);
        let off = self.offsets();
        let pm = &f.pm;
        let mut put = |col: usize, row: usize, v: f64| {
            if col >= lo {
                s2[(row, col - lo)] += v;
            }
        };
        for i in 0..n {
            for j in 0..n {
                put(off.a + i * n + j, i, f.x[j]);
            }
            for (j, &uj) in u.iter().enumerate() {
                put(off.b + i * m + j, i, uj);
            }
            if let Some(ik) = off.k {
                for j in 0..l {
                    put(ik + i * l + j, i, f.e[j]);
                }
            }
        }
        for i in 0..l {
            for r in (0..n).filter(|&r| pm.k[(r, i)] != 0.0) {
                for j in 0..n {
                    put(off.c + i * n + j, r, -pm.k[(r, i)] * f.x[j]);
                }
                if let Some(id) = off.d {
                    for (j, &uj) in u.iter().enumerate() {
                        put(id + i * m + j, r, -pm.k[(r, i)] * uj);
                    }
                }
            }
        }
    }

    /// `G(t)`, the direct derivative of `ŷ` (for `C` and `D`), added to `cs`.
    fn add_direct(&self, f: &Filter, cs: &mut Mat<f64>, u: &[f64], lo: usize) {
        let (n, m) = (self.n, self.m);
        let off = self.offsets();
        for i in 0..self.l {
            for j in 0..n {
                let col = off.c + i * n + j;
                if col >= lo {
                    cs[(i, col - lo)] += f.x[j];
                }
            }
            if let Some(id) = off.d {
                for (j, &uj) in u.iter().enumerate() {
                    let col = id + i * m + j;
                    if col >= lo {
                        cs[(i, col - lo)] += uj;
                    }
                }
            }
        }
    }

    /// Cost, gradient and Gauss-Newton matrix from every Jacobian row (columns `col_lo..p`;
    /// the others get zero rows and columns).
    pub(super) fn evaluate_rows(&self, th: &[f64]) -> Result<Evaluation> {
        let (n, m, l, np) = (self.n, self.m, self.l, self.p);
        let mut f = Filter::new(self.unpack(th), self.rinv.clone());
        let blk = self.block;
        let lo = self.col_lo.min(np);
        let nc = np - lo;
        let mut h = Mat::<f64>::zeros(np, np);
        let mut g = Mat::<f64>::zeros(np, 1);
        let mut jb = Mat::<f64>::zeros(blk * l, nc);
        let mut rb = Mat::<f64>::zeros(blk * l, 1);
        let mut s = Mat::<f64>::zeros(n, nc);
        let mut s2 = s.clone();
        let mut cs = Mat::<f64>::zeros(l, nc);
        let par = small_par(blk * l, nc);
        let mut ut = vec![0.0; m];
        // per-sample products of a few state rows (crate::denormals), in this loop only
        let daz = crate::denormals::DenormalsAreZero::new();
        for (ex, (u, y)) in self.exps.iter().enumerate() {
            f.restart(ex);
            s.fill(0.0);
            if let Some(o) = self.x0_off[ex].filter(|&o| o >= lo) {
                for i in 0..n {
                    s[(i, o - lo + i)] = 1.0;
                }
            }
            let len = y.nrows();
            let mut row = 0usize;
            for t in 0..len {
                f.weighed_errors(*u, *y, t)?;
                for (j, v) in ut.iter_mut().enumerate() {
                    *v = u[(t, j)];
                }
                let (pm, rinv) = (&f.pm, &f.rinv);
                product(cs.as_mut(), pm.c.as_ref(), s.as_ref(), 1.0);
                self.add_direct(&f, &mut cs, &ut, lo);
                // weighted Jacobian rows: -R^-1 dŷ
                let rows = jb.as_mut().subrows_mut(row * l, l);
                product(rows, rinv.as_ref(), cs.as_ref(), -1.0);
                for i in 0..l {
                    rb[(row * l + i, 0)] = f.we[i];
                }
                row += 1;
                product(s2.as_mut(), pm.abar.as_ref(), s.as_ref(), 1.0);
                self.add_forcing(&f, &mut s2, &ut, lo);
                std::mem::swap(&mut s, &mut s2);
                if t % FLUSH_EVERY == 0 {
                    flush_tiny_mat(&mut s);
                }
                if row == blk || t + 1 == len {
                    let jr = jb.as_ref().subrows(0, row * l);
                    gram_add(h.as_mut().submatrix_mut(lo, lo, nc, nc), jr, par);
                    let gr = g.as_mut().subrows_mut(lo, nc);
                    let rr = rb.as_ref().subrows(0, row * l);
                    matmul(gr, Accum::Add, jr.transpose(), rr, 1.0, Par::Seq);
                    clear_upper();
                    row = 0;
                }
                f.advance(*u, *y, t);
            }
        }
        drop(daz);
        mirror_lower(&mut h);
        Ok(Evaluation {
            cost: f.finite_cost(),
            gradient: (0..np).map(|i| g[(i, 0)]).collect(),
            gauss_newton: h,
        })
    }
}
