//! The Gauss-Newton products of a MIMO Hammerstein-Wiener problem formed over its
//! identifiable directions only, in the modal coordinates of `A` (the chart of the
//! prediction-error estimator, [`crate::pem`], whose modal form, similarity tangent and
//! change of basis this reuses).
//!
//! In the real modal basis of `A` (`A' = T^-1 A T = Lambda` block diagonal, `B' = T^-1 B`,
//! `C' = C T`) the simulated output does not move along the similarity orbit: `J' t = 0`
//! for every tangent `t = (Lambda E_ab - E_ab Lambda, -E_ab B', C' E_ab)`. For `a` and `b` in
//! different blocks that tangent moves, in `A'`, only entries outside the blocks (`H`), and
//! `B'`, `C'` (in `F`, the other parameters): `J_H G + J_F R = 0` with `G` (`H` x pairs)
//! invertible when no pole is shared between blocks. So `J' = J_F K`, `K = [I, -R G^-1]`,
//! and with `M` the change of basis (`phi' = M theta`):
//!
//! ```text
//! J^T J = Z^T (J_F^T J_F) Z,   J^T r = Z^T (J_F^T r),   Z = K M
//! ```
//!
//! Only the columns `F` are ever formed (the sensitivities of `n^2 - sum bs^2` entries of
//! `A` are not), and their Gram matrix costs `|F|^2` per residual instead of `p^2`. The
//! result is the Gauss-Newton matrix of the full parameterisation, to rounding, so the
//! search moves exactly as before; it only costs less.

use faer::linalg::solvers::DenseSolveCore;
use faer::Mat;

use super::MimoHwProblem;
use crate::error::Result;
use crate::optim::{Evaluation, NormalEquations};
use crate::pem::{modal_form, modal_mt_cols, similarity_tangent, Part, StateBlocks};

/// Above this `max|G| max|G^-1|` (poles of different blocks nearly equal) the expansion
/// would amplify rounding: the plain evaluation is used.
const MAX_CONDITION: f64 = 1e8;

impl MimoHwProblem<'_> {
    /// Cost, `J^T r` and `J^T J` at `theta` through the modal coordinates (see the module
    /// documentation), or `None` when `A`'s modal form is ill-conditioned or two blocks
    /// share a pole.
    pub(super) fn evaluate_modal(&self, theta: &[f64]) -> Result<Option<Evaluation>> {
        let s = &self.structure;
        let lay = s.layout();
        let (n, m, p) = (s.order, s.inputs.len(), s.outputs.len());
        let (a, b, c, _) = s.matrices(theta);
        let Some(md) = modal_form(a.as_ref()) else {
            return Ok(None);
        };
        let blk = |i: usize| md.block[i].0;
        // the modal parameters and the entries of A' outside the blocks
        let (bm, cm) = (&md.ti * &b, &c * &md.t);
        let mut th = theta.to_vec();
        let mut held = vec![false; lay.total];
        let mut pairs = Vec::new();
        for r in 0..n {
            for k in 0..n {
                let inside = blk(r) == blk(k);
                th[lay.a + r * n + k] = if inside { md.lam[(r, k)] } else { 0.0 };
                held[lay.a + r * n + k] = !inside;
                if !inside {
                    pairs.push((r, k));
                }
            }
            for j in 0..m {
                th[lay.b + r * m + j] = bm[(r, j)];
            }
        }
        for i in 0..p {
            for k in 0..n {
                th[lay.c + i * n + k] = cm[(i, k)];
            }
        }
        // the records' initial states, x0' = T^-1 x0
        let x0m: Vec<Vec<f64>> = (0..s.initial_states)
            .map(|e| {
                let x0 = s.initial_state(theta, e);
                (0..n)
                    .map(|r| (0..n).map(|k| md.ti[(r, k)] * x0[k]).sum())
                    .collect()
            })
            .collect();
        for (e, x) in x0m.iter().enumerate() {
            th[lay.x0 + e * n..lay.x0 + (e + 1) * n].copy_from_slice(x);
        }
        if th.iter().any(|v| !v.is_finite()) {
            return Ok(None);
        }
        let free: Vec<usize> = (0..lay.total).filter(|&k| !held[k]).collect();
        let mut at_free = vec![usize::MAX; lay.total];
        for (f, &k) in free.iter().enumerate() {
            at_free[k] = f;
        }
        let mut at_held = vec![usize::MAX; lay.total];
        for (h, &(r, k)) in pairs.iter().enumerate() {
            at_held[lay.a + r * n + k] = h;
        }
        // G (held x pairs) and R (free x pairs): the tangents of the pairs across blocks
        let nh = pairs.len();
        let mut g = Mat::<f64>::zeros(nh, nh);
        let mut rr = Mat::<f64>::zeros(free.len(), nh);
        similarity_tangent(&md.lam, &bm, &cm, &pairs, |col, part, idx, v| {
            let k = match part {
                Part::A => lay.a,
                Part::B => lay.b,
                Part::C => lay.c,
            } + idx;
            if held[k] {
                g[(at_held[k], col)] += v;
            } else {
                rr[(at_free[k], col)] += v;
            }
        });
        // and of the initial states: -E_pq x0' (as of B')
        for (col, &(pp, qq)) in pairs.iter().enumerate() {
            for (e, x) in x0m.iter().enumerate() {
                rr[(at_free[lay.x0 + e * n + pp], col)] -= x[qq];
            }
        }
        // K^T (p x free): identity on the free parameters, -(R G^-1)^T on the held ones
        let mut kt = Mat::<f64>::zeros(lay.total, free.len());
        for (f, &k) in free.iter().enumerate() {
            kt[(k, f)] = 1.0;
        }
        if nh > 0 {
            let gi = g.partial_piv_lu().inverse();
            let cond = g.norm_max() * gi.norm_max();
            if !gi.is_all_finite() || !cond.is_finite() || cond > MAX_CONDITION {
                return Ok(None);
            }
            let x = &rr * &gi; // free x held
            for (h, &(r, k)) in pairs.iter().enumerate() {
                for f in 0..free.len() {
                    kt[(lay.a + r * n + k, f)] = -x[(f, h)];
                }
            }
        }
        // J_F^T J_F and J_F^T r over the free columns, at the modal parameters
        let cols = s.columns(&held);
        let mut sums = NormalEquations::blocked(cols.len(), true);
        for (e, (u, y)) in self.records.iter().enumerate() {
            let x0 = x0m.get(e).map(Vec::as_slice);
            s.run(&th, *u, Some(&cols), x0, e, |t, i, yhat, jr| {
                sums.add(y[(t, i)] - yhat, Some(jr))
            })?;
        }
        let ev = sums.finish();
        // Z^T = M^T K^T
        let mut left = vec![(lay.b, m)];
        left.extend((0..s.initial_states).map(|e| (lay.x0 + e * n, 1)));
        let at = StateBlocks {
            a: lay.a,
            left,
            c: lay.c,
            rows: p,
        };
        let zt = modal_mt_cols(&md, &at, &kt);
        let gf = Mat::from_fn(free.len(), 1, |i, _| ev.gradient[i]);
        let gradient = (&zt * &gf).col_as_slice(0).to_vec();
        let hz = &ev.gauss_newton * zt.transpose();
        let h = &zt * &hz;
        let gauss_newton = Mat::from_fn(lay.total, lay.total, |i, j| 0.5 * (h[(i, j)] + h[(j, i)]));
        Ok(Some(Evaluation {
            cost: ev.cost,
            gradient,
            gauss_newton,
        }))
    }
}
