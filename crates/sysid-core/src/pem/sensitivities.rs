//! The state sensitivities `S(t) = dx(t)/dphi` of the predictor parameters that move the
//! state (`Abar, Bbar, K, x0`), run beside the predictor and folded blockwise into the normal
//! equations.
//!
//! `S(t+1) = Abar S(t) + F(t)`, with `F` the direct derivative of the right-hand side: for
//! `Abar_ij` it is `x_j(t)` in row `i`, for `Bbar_ij` `u_j(t)`, for `K_ij` `y_j(t)`; the
//! initial state's columns start at the identity. `dŷ/dphi = C S` for these, so
//! `sum S^T C^T W C S` is the dynamic block and `sum_t z_j(t) (W C S)_i(t)` the
//! static-dynamic one.
//!
//! Two forms share this loop: in the original basis ([`Predictor::evaluate_structured`], `S`
//! is `n x p_d`, its block of `J^T W J` formed from `min(l, n)` rows per sample) and in the
//! modal basis of `Abar` ([`Predictor::evaluate_modal`], each sensitivity lives in one 1x1
//! or 2x2 block: `p_e <= 2 p_d` numbers per sample and `O(N p_e^2)` for their Gram matrix).

use super::modal::Modal;
use super::normal::{gradient_to_theta, matrix_to_theta, product, StaticSums};
use super::predictor::{rows_of, Filter, Predictor, RowProduct};
use crate::denormals::DenormalsAreZero;
use crate::error::Result;
use crate::optim::{
    clear_upper, flush_tiny, flush_tiny_mat, gram_add, mirror_lower, small_par, Evaluation,
    FLUSH_EVERY,
};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Side};

/// A dynamic column of the modal form: (phi index, state row, forcing, forcing index).
#[derive(Clone, Copy, PartialEq, Eq)]
struct Dynamic {
    phi: usize,
    row: usize,
    forcing: Forcing,
    j: usize,
}

/// What drives a sensitivity column: a state, an input, an output, or only its start.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Forcing {
    State,
    Input,
    Output,
    Start,
}

impl Predictor<'_> {
    /// The dynamic columns in `phi` order (`Abar`, `Bbar`, `K`, each estimated `x0`), and per
    /// experiment the index of its first `x0` column.
    fn dynamic_columns(&self) -> (Vec<Dynamic>, Vec<Option<usize>>) {
        let (n, m, l) = (self.n, self.m, self.l);
        let off = self.offsets();
        let mut cols = Vec::new();
        let block = |base: usize, w: usize, forcing: Forcing, cols: &mut Vec<Dynamic>| {
            for row in 0..n {
                for j in 0..w {
                    cols.push(Dynamic {
                        phi: base + row * w + j,
                        row,
                        forcing,
                        j,
                    });
                }
            }
        };
        block(off.a, n, Forcing::State, &mut cols);
        block(off.b, m, Forcing::Input, &mut cols);
        if let Some(k) = off.k {
            block(k, l, Forcing::Output, &mut cols);
        }
        let mut x0_at = Vec::with_capacity(self.x0_off.len());
        for off in &self.x0_off {
            x0_at.push(off.map(|o| {
                let at = cols.len();
                block(o, 1, Forcing::Start, &mut cols);
                at
            }));
        }
        (cols, x0_at)
    }

    /// The static-dynamic block and the dynamic gradient into `h`, `g` (in `phi`), then both
    /// mapped to `theta`. `cross(i, c)` is `sum_t (W C S)_i(t) z_j(t)` for the static row
    /// `(i, j)` and dynamic column `c`; `h` already holds the dynamic block.
    #[allow(clippy::too_many_arguments)]
    fn finish(
        &self,
        f: &Filter,
        sums: &StaticSums,
        cols: &[Dynamic],
        gd: &[f64],
        mut h: Option<Mat<f64>>,
        w: &Mat<f64>,
        cross: &dyn Fn(usize, usize, usize) -> f64,
        modal: Option<&Modal>,
    ) -> Evaluation {
        let mut g = vec![0.0; self.p];
        self.static_gradient(&sums.gz, &mut g);
        for (c, d) in cols.iter().enumerate() {
            g[d.phi] = gd[c];
        }
        let tmap = self.predictor_map(&f.pm);
        let gphi = match modal {
            Some(md) => self.modal_mt(md, &g),
            None => g,
        };
        let gradient = gradient_to_theta(&tmap, &gphi);
        let Some(mut h) = h.take() else {
            return Evaluation {
                cost: f.finite_cost(),
                gradient,
                gauss_newton: Mat::zeros(0, 0),
            };
        };
        self.static_block(w, &sums.zz, &mut h);
        for i in 0..self.l {
            for j in 0..self.n + self.m {
                let Some(sij) = self.static_index(i, j) else {
                    continue;
                };
                for (c, d) in cols.iter().enumerate() {
                    let v = cross(i, j, c);
                    h[(sij, d.phi)] = v;
                    h[(d.phi, sij)] = v;
                }
            }
        }
        if let Some(md) = modal {
            // H_phi = M^T H' M = M^T (M^T H')^T (H' symmetric)
            let z = self.modal_mt_cols(md, &h);
            drop(h);
            h = self.modal_mt_cols(md, &z.transpose().to_owned());
        }
        Evaluation {
            cost: f.finite_cost(),
            gradient,
            gauss_newton: matrix_to_theta(&tmap, &h),
        }
    }

    /// Cost, `J^T W r` and `J^T W J` through the predictor parameterisation, the
    /// sensitivities in the original state basis. The dynamic block `sum S^T C^T W C S` is
    /// formed from `min(l, n)` rows per sample (`R^-1 C`, or the Cholesky factor of
    /// `C^T W C` when `l > n`). With `grad_only` the Gauss-Newton matrix is skipped (left
    /// empty): the sensitivities and the gradient cost `O(N n^2 p_d)`.
    pub(super) fn evaluate_structured(&self, th: &[f64], grad_only: bool) -> Result<Evaluation> {
        let (n, m, l) = (self.n, self.m, self.l);
        let mut f = Filter::new(self.unpack(th), self.rinv.clone());
        let blk = self.block;
        let (cols, x0_at) = self.dynamic_columns();
        let pd = cols.len();
        let nz = n + m;
        let w = f.rinv.transpose() * &f.rinv;
        let q = &f.rinv * &f.pm.c;
        let wc = &w * &f.pm.c;
        // rows whose Gram matrix is C^T W C
        let lt: Mat<f64> = match (l > n, (q.transpose() * &q).llt(Side::Lower)) {
            (true, Ok(fac)) => fac.L().transpose().to_owned(),
            _ => q.clone(),
        };
        let r = lt.nrows();
        let par = small_par(blk * r, pd);
        let acc = !grad_only;
        let hp = if acc { pd } else { 0 };
        let mut hd = Mat::<f64>::zeros(hp, hp);
        let mut gd = vec![0.0; pd];
        // row c * n + k, column j: sum_t S_kc(t) z_j(t)
        let mut cross = Mat::<f64>::zeros(if acc { n * pd } else { 0 }, nz);
        let mut sums = StaticSums::new(l, nz, blk, acc);
        let mut jb = Mat::<f64>::zeros(if acc { blk * r } else { 0 }, hp);
        // column `row`: the sample's S by columns (`vec S`, written contiguously)
        let mut sbuf = Mat::<f64>::zeros(if acc { n * pd } else { 0 }, blk);
        let mut s = Mat::<f64>::zeros(n, pd);
        let mut s2 = s.clone();
        let mut v = vec![0.0; n];
        let mut z = vec![0.0; nz];
        let mut sample = 0usize;
        // per-sample products of a few state rows: subnormal operands read as zero
        // (crate::denormals), in this loop only
        let daz = DenormalsAreZero::new();
        for (ex, (u, y)) in self.exps.iter().enumerate() {
            f.restart(ex);
            s.fill(0.0);
            if let Some(c0) = x0_at[ex] {
                for i in 0..n {
                    s[(i, c0 + i)] = 1.0;
                }
            }
            let len = y.nrows();
            let mut row = 0usize;
            for t in 0..len {
                f.weighed_errors(*u, *y, t)?;
                if let Some((c, x)) = &self.substitute {
                    f.substitute(*c, &x[sample * l..(sample + 1) * l]);
                }
                sample += 1;
                z[..n].copy_from_slice(&f.x);
                for j in 0..m {
                    z[n + j] = u[(t, j)];
                }
                sums.add(&z, &f.wz, row);
                // dynamic gradient: -S^T C^T W e
                for (k, vk) in v.iter_mut().enumerate() {
                    *vk = (0..l).map(|i| f.pm.c[(i, k)] * f.wz[i]).sum();
                }
                for (c, gc) in gd.iter_mut().enumerate() {
                    *gc -= (0..n).map(|k| s[(k, c)] * v[k]).sum::<f64>();
                }
                if acc {
                    let col = sbuf.col_as_slice_mut(row);
                    for (c, dst) in col.chunks_exact_mut(n).enumerate() {
                        dst.copy_from_slice(s.col_as_slice(c));
                    }
                    let rows = jb.as_mut().subrows_mut(row * r, r);
                    product(rows, lt.as_ref(), s.as_ref(), 1.0);
                    row += 1;
                }
                product(s2.as_mut(), f.pm.abar.as_ref(), s.as_ref(), 1.0);
                for (c, d) in cols.iter().enumerate() {
                    s2[(d.row, c)] += match d.forcing {
                        Forcing::State => f.x[d.j],
                        Forcing::Input => u[(t, d.j)],
                        Forcing::Output => y[(t, d.j)],
                        Forcing::Start => 0.0,
                    };
                }
                std::mem::swap(&mut s, &mut s2);
                if t % FLUSH_EVERY == 0 {
                    flush_tiny_mat(&mut s);
                }
                if acc && (row == blk || t + 1 == len) {
                    gram_add(hd.as_mut(), jb.as_ref().subrows(0, row * r), par);
                    let zr = sums.zbuf.as_ref().subrows(0, row);
                    let sb = sbuf.as_ref().subcols(0, row);
                    matmul(cross.as_mut(), Accum::Add, sb, zr, 1.0, par);
                    sums.fold(row);
                    clear_upper();
                    row = 0;
                }
                f.advance(*u, *y, t);
            }
        }
        drop(daz);
        let h = acc.then(|| {
            let mut h = Mat::<f64>::zeros(self.p, self.p);
            mirror_lower(&mut hd);
            for (a, da) in cols.iter().enumerate() {
                for (b, db) in cols.iter().enumerate() {
                    h[(da.phi, db.phi)] = hd[(a, b)];
                }
            }
            h
        });
        let cross_at = |i: usize, j: usize, c: usize| -> f64 {
            (0..n).map(|k| wc[(i, k)] * cross[(c * n + k, j)]).sum()
        };
        Ok(self.finish(&f, &sums, &cols, &gd, h, &w, &cross_at, None))
    }

    /// As [`Self::evaluate_structured`], with the state-moving parameters taken in the modal
    /// coordinates of `Abar` ([`Modal`]): `S` is stored compactly, its recursion costs
    /// `O(p_e)` and `sum S^T C^T W C S` comes from the Gram matrix of those numbers.
    ///
    /// A 2x2 block `[[a, b], [-b, a]]` commutes with the rotation `R = [[0, -1], [1, 0]]`,
    /// and `R e_0 = e_1`: the sensitivity of a parameter in the block's second row is `R`
    /// times that of the same parameter in its first row, to the last bit. With `halve` only
    /// first rows are carried (the Gram matrix costs a quarter).
    pub(super) fn evaluate_modal(
        &mut self,
        th: &[f64],
        grad_only: bool,
        md: &Modal,
    ) -> Result<Evaluation> {
        let (n, m, l) = (self.n, self.m, self.l);
        let mut f = Filter::new(self.unpack(th), self.rinv.clone());
        let blk = self.block;
        let cq = &f.pm.c * &md.t;
        let (cols, x0_at) = self.dynamic_columns();
        let pd = cols.len();
        let stride = |fc: Forcing| match fc {
            Forcing::State => n,
            Forcing::Input => m,
            Forcing::Output => l,
            Forcing::Start => 1,
        };
        // carried columns (with the second-row twin derived from them)
        let mut carried: Vec<(usize, Option<usize>)> = Vec::with_capacity(pd);
        for (c, d) in cols.iter().enumerate() {
            if d.forcing == Forcing::State && self.held(d.row, d.j) {
                // held at zero by the modal chart: no sensitivity (zero in `at`)
                continue;
            }
            let (b0, bs) = md.block[d.row];
            if self.halve && bs == 2 {
                if d.row == b0 + 1 {
                    continue;
                }
                carried.push((c, Some(c + stride(d.forcing))));
            } else {
                carried.push((c, None));
            }
        }
        // `at[c][q]` = (carried number, sign) of entry q of column c's sensitivity block
        let mut eoff = vec![0usize; carried.len() + 1];
        let mut at = vec![[(0usize, 0.0f64); 2]; pd];
        for (k, &(c, twin)) in carried.iter().enumerate() {
            let bs = md.block[cols[c].row].1;
            eoff[k + 1] = eoff[k] + bs;
            for (q, a) in at[c].iter_mut().take(bs).enumerate() {
                *a = (eoff[k] + q, 1.0);
            }
            if let Some(tw) = twin {
                // R s = (-s_1, s_0)
                at[tw] = [(eoff[k] + 1, -1.0), (eoff[k], 1.0)];
            }
        }
        let pe = eoff[carried.len()];
        let segs = segments(&carried, &cols, md, &eoff, n, m, l);
        let cached = match grad_only {
            true => None,
            false => self
                .gram_cache
                .take()
                .filter(|c| c.0.as_slice() == th && c.1.nrows() == pe),
        };
        // accumulate the sums (else they come from the cache, or are not needed)
        let acc = !grad_only && cached.is_none();
        let nz = n + m;
        let w = f.rinv.transpose() * &f.rinv;
        let wc = &w * &cq;
        let mq = cq.transpose() * &wc;
        let par = small_par(blk, pe);
        let hp = if acc { pe } else { 0 };
        let mut gram = Mat::<f64>::zeros(hp, hp);
        let mut cross = Mat::<f64>::zeros(if acc { nz } else { 0 }, hp);
        // the block's sensitivity rows, one column per sample (written contiguously)
        let mut vbuf = Mat::<f64>::zeros(hp, if acc { blk } else { 0 });
        let (mut v, mut z) = (vec![0.0; n], vec![0.0; nz]);
        let mut sums = StaticSums::new(l, nz, blk, acc);
        let mut gd = vec![0.0; pd];
        let (mut sc, mut sn) = (vec![0.0; pe], vec![0.0; pe]);
        // per carried number: sum_t s v (its block's first row of v), or for the second
        // number of a 2x2 block the twin's sum (or nothing without a twin)
        let mut ge = vec![0.0; pe];
        // forcing of a sample: (z, y, 0): the modal state and input, the output, no forcing
        let mut fv = vec![0.0; nz + l + 1];
        // `T^-1` by rows (block diagonal in the modal chart: its non-zero entries only)
        let ti = RowProduct::new(&rows_of(&[&md.ti]), n);
        let mut sample = 0usize;
        let daz = DenormalsAreZero::new(); // as in evaluate_structured
        for (ex, (u, y)) in self.exps.iter().enumerate() {
            f.restart(ex);
            sc.fill(0.0);
            if let Some(c0) = x0_at[ex] {
                for i in 0..n {
                    let (h, sg) = at[c0 + i][i - md.block[i].0];
                    sc[h] = sg;
                }
            }
            let len = y.nrows();
            let mut row = 0usize;
            for t in 0..len {
                f.weighed_errors(*u, *y, t)?;
                if let Some((c, x)) = &self.substitute {
                    f.substitute(*c, &x[sample * l..(sample + 1) * l]);
                }
                sample += 1;
                // modal state x' = T^-1 x, regressor z = (x', u)
                ti.apply(&f.x, &mut z[..n]);
                for j in 0..m {
                    z[n + j] = u[(t, j)];
                }
                sums.add(&z, &f.wz, row);
                for (k, vk) in v.iter_mut().enumerate() {
                    *vk = (0..l).map(|i| cq[(i, k)] * f.wz[i]).sum();
                }
                fv[..nz].copy_from_slice(&z);
                for j in 0..l {
                    fv[nz + j] = y[(t, j)];
                }
                if acc {
                    vbuf.col_as_slice_mut(row).copy_from_slice(&sc);
                    row += 1;
                }
                // the gradient sums `ge -= s v` and `S'(t+1) = Lambda S' + F`, blockwise, in
                // one pass over the segments
                for sg in &segs {
                    let (sc_s, ge_s) = (&sc[sg.o..sg.end], &mut ge[sg.o..sg.end]);
                    let sn_s = &mut sn[sg.o..sg.end];
                    let src = &sg.forcing;
                    if sg.bs == 1 {
                        let (v0, l00) = (v[sg.b0], sg.lam[0]);
                        let cols = ge_s.iter_mut().zip(sn_s.iter_mut()).zip(sc_s).zip(src);
                        for (((gv, nv), sv), &fi) in cols {
                            *gv -= sv * v0;
                            *nv = l00 * sv + fv[fi];
                        }
                    } else {
                        let (v0, v1) = (v[sg.b0], v[sg.b0 + 1]);
                        let [l00, l01, l10, l11] = sg.lam;
                        let pairs = ge_s.chunks_exact_mut(2).zip(sn_s.chunks_exact_mut(2));
                        for ((gv, nv), (sv, &fi)) in pairs.zip(sc_s.chunks_exact(2).zip(src)) {
                            let (s0, s1) = (sv[0], sv[1]);
                            gv[0] -= s0 * v0 + s1 * v1;
                            if sg.twin {
                                gv[1] -= s0 * v1 - s1 * v0;
                            }
                            // the forcing enters the block row `fq`
                            let fk = fv[fi];
                            let (a0, a1) = (l00 * s0 + l01 * s1, l10 * s0 + l11 * s1);
                            if sg.fq == 0 {
                                nv[0] = a0 + fk;
                                nv[1] = a1;
                            } else {
                                nv[0] = a0;
                                nv[1] = a1 + fk;
                            }
                        }
                    }
                }
                std::mem::swap(&mut sc, &mut sn);
                if t % FLUSH_EVERY == 0 {
                    flush_tiny(&mut sc);
                }
                if acc && (row == blk || t + 1 == len) {
                    let vr = vbuf.as_ref().subcols(0, row).transpose();
                    gram_add(gram.as_mut(), vr, par);
                    let zr = sums.zbuf.as_ref().subrows(0, row);
                    matmul(cross.as_mut(), Accum::Add, zr.transpose(), vr, 1.0, par);
                    sums.fold(row);
                    clear_upper();
                    row = 0;
                }
                f.advance(*u, *y, t);
            }
        }
        drop(daz);
        for (k, &(c, twin)) in carried.iter().enumerate() {
            gd[c] = ge[eoff[k]];
            if let Some(tw) = twin {
                gd[tw] = ge[eoff[k] + 1];
            }
        }
        if let Some(c) = cached {
            (gram, cross, sums.zz) = (c.1, c.2, c.3);
        }
        let h = (!grad_only).then(|| {
            // dynamic block, lower triangle then mirrored
            let mut h = Mat::<f64>::zeros(self.p, self.p);
            for (c2, d2) in cols.iter().enumerate() {
                let (b2, bs2) = md.block[d2.row];
                for (c, d) in cols.iter().enumerate().skip(c2) {
                    let (b0, bs) = md.block[d.row];
                    let mut a = 0.0;
                    for (qa, &(ra, sa)) in at[c].iter().take(bs).enumerate() {
                        for (qb, &(rb, sb)) in at[c2].iter().take(bs2).enumerate() {
                            let gv = gram[(ra.max(rb), ra.min(rb))];
                            a += mq[(b0 + qa, b2 + qb)] * (sa * sb * gv);
                        }
                    }
                    h[(d.phi, d2.phi)] = a;
                    h[(d2.phi, d.phi)] = a;
                }
            }
            h
        });
        let cross_at = |i: usize, j: usize, c: usize| -> f64 {
            let b0 = md.block[cols[c].row].0;
            let bs = md.block[cols[c].row].1;
            (0..bs)
                .map(|qa| {
                    let (r, sg) = at[c][qa];
                    wc[(i, b0 + qa)] * (sg * cross[(j, r)])
                })
                .sum()
        };
        let ev = self.finish(&f, &sums, &cols, &gd, h, &w, &cross_at, Some(md));
        if !grad_only {
            self.gram_cache = Some((th.to_vec(), gram, cross, sums.zz));
        }
        Ok(ev)
    }
}

/// A run of carried sensitivity numbers of one block row of one parameter block: `w`
/// columns of `bs` numbers each, contiguous in `o..end`, sharing the block `lam` (row-major
/// 2x2, or its first entry) and the row `fq` of the block their forcing enters; `forcing`
/// holds per column its index in the sample's forcing vector `(z, y, 0)`.
struct Segment {
    o: usize,
    end: usize,
    bs: usize,
    b0: usize,
    fq: usize,
    twin: bool,
    lam: [f64; 4],
    forcing: Vec<usize>,
}

/// The carried columns of [`Predictor::evaluate_modal`] grouped into [`Segment`]s.
fn segments(
    carried: &[(usize, Option<usize>)],
    cols: &[Dynamic],
    md: &Modal,
    eoff: &[usize],
    n: usize,
    m: usize,
    l: usize,
) -> Vec<Segment> {
    let mut segs: Vec<Segment> = Vec::new();
    for (k, &(c, twin)) in carried.iter().enumerate() {
        let d = cols[c];
        let (b0, bs) = md.block[d.row];
        let fi = match d.forcing {
            Forcing::State => d.j,
            Forcing::Input => n + d.j,
            Forcing::Output => n + m + d.j,
            Forcing::Start => n + m + l,
        };
        let lam = if bs == 1 {
            [md.lam[(b0, b0)], 0.0, 0.0, 0.0]
        } else {
            [
                md.lam[(b0, b0)],
                md.lam[(b0, b0 + 1)],
                md.lam[(b0 + 1, b0)],
                md.lam[(b0 + 1, b0 + 1)],
            ]
        };
        let fq = d.row - b0;
        let joins = segs.last().is_some_and(|s: &Segment| {
            s.end == eoff[k] && s.b0 == b0 && s.bs == bs && s.fq == fq && s.twin == twin.is_some()
        });
        if !joins {
            segs.push(Segment {
                o: eoff[k],
                end: eoff[k],
                bs,
                b0,
                fq,
                twin: twin.is_some(),
                lam,
                forcing: Vec::new(),
            });
        }
        let s = segs.last_mut().expect("a segment was just pushed");
        s.end += bs;
        s.forcing.push(fi);
    }
    segs
}
