//! The modal chart: identifiable coordinates for models without a noise model.
//!
//! A model whose `A` is block diagonal with 1x1 (real pole) and 2x2 (complex pair) blocks
//! stays so when only the entries inside its blocks move. Near a model with distinct poles,
//! every nearby model is similar to one of that form, so the entries of `A` outside the
//! blocks can be held at zero without losing any model: the search then moves in
//! `sum bs^2 + n m + l n (+ l m + n)` parameters, of which only `sum bs^2` (the similarity
//! transformations that keep the blocks) are not identifiable, instead of `n^2 + ...` with
//! `n^2` not identifiable. The sensitivities of the held entries are never formed: for order
//! 20 the Gram matrix of the modal sensitivities shrinks from about `n (n + m + 1)` to about
//! `n (2 + m + 1)` carried numbers per sample.
//!
//! The chart applies when it removes at least half of the state sensitivities (those of `A`,
//! `B` and `x0`: `n^2 - sum bs^2 >= sum bs^2 + n (m + 1)`, so for orders well above the
//! number of inputs) and leaves at most `eigen_limit` free parameters (the search then solves
//! its steps in local coordinates), when the predictor matrix is `A` itself (no Kalman gain:
//! simulation focus, or prediction without a noise model), when `A` of the start has a
//! well-conditioned real modal form, and when no non-zero initial state is given. The result
//! is mapped back to the start's state basis ([`to_start_basis`]).

use super::modal::{modal_form, Modal};
use super::options::{Focus, InitialState, PemOptions, PemResult};
use super::predictor::Predictor;
use crate::model::StateSpace;
use faer::{Mat, MatRef};

/// Per state, the first state of its chart block.
pub(super) type Chart = Vec<usize>;

/// The start in its real modal basis `(T^-1 A T, T^-1 B, C T, D)`, the chart and the modal
/// form of the start's `A` (with `T`), or `None` when the chart does not apply (over
/// `experiments` experiments).
pub(super) fn modal_start(
    start: &StateSpace,
    k0: Option<MatRef<'_, f64>>,
    opts: &PemOptions,
    experiments: usize,
) -> Option<(StateSpace, Chart, Modal)> {
    let n = start.n_states();
    let no_gain = opts.focus == Focus::Simulation
        || (!opts.estimate_k && k0.is_none_or(|k| k.norm_max() == 0.0));
    let given = opts
        .x0
        .iter()
        .any(|s| matches!(s, InitialState::Given(v) if v.iter().any(|&x| x != 0.0)));
    if !opts.modal_chart || !opts.local_coordinates || !no_gain || given || n < 3 {
        return None;
    }
    let md = modal_form(start.a.as_ref())?;
    let chart: Chart = md.block.iter().map(|b| b.0).collect();
    // worth it when it removes at least half of the state sensitivities (those of A, B, x0)
    let kept = (0..n).map(|i| md.block[i].1).sum::<usize>();
    if n * n - kept < kept + n * (start.n_inputs() + 1) {
        return None;
    }
    // and only where the steps are solved in local coordinates (eigen path of the search):
    // on the large-problem path (one Cholesky solve per step) it converged to a worse point
    // on the synthetic 2 x 28 record of benches/pem_speed.py
    let (m, l) = (start.n_inputs(), start.n_outputs());
    let x0s = match opts.x0.as_slice() {
        [one] => usize::from(*one == InitialState::Estimate) * experiments,
        all => all.iter().filter(|s| **s == InitialState::Estimate).count(),
    };
    let free = kept + n * m + l * n + usize::from(opts.estimate_d) * l * m + x0s * n;
    if free > opts.optim.eigen_limit {
        return None;
    }
    let a = Mat::from_fn(n, n, |i, j| {
        if chart[i] == chart[j] {
            md.lam[(i, j)]
        } else {
            0.0
        }
    });
    let sys = StateSpace::new(a, &md.ti * &start.b, &start.c * &md.t, start.d.clone()).ok()?;
    Some((sys, chart, md))
}

/// The result of a search in the chart, expressed in the start's state basis again:
/// `A = T A' T^-1, B = T B', C = C' T^-1, K = T K', x0 = T x0'`, the parameters by the same
/// linear map `L`, their covariance `L P L^T`, the gradient and Gauss-Newton matrix by its
/// inverse `M = L^-1` (`M^T g`, `M^T H M`). `prob` gives the parameter layout.
pub(super) fn to_start_basis(prob: &Predictor<'_>, md: &Modal, mut r: PemResult) -> PemResult {
    let (t, ti) = (&md.t, &md.ti);
    // L = M^T for the pair (T^-T, T^T) (see `Predictor::modal_mt_cols`)
    let inv = Modal {
        t: ti.transpose().to_owned(),
        ti: t.transpose().to_owned(),
        lam: Mat::zeros(0, 0),
        block: Vec::new(),
    };
    let col = |v: &[f64]| Mat::from_fn(v.len(), 1, |i, _| v[i]);
    let both = |m: &Modal, x: &Mat<f64>| {
        let z = prob.modal_mt_cols(m, x);
        prob.modal_mt_cols(m, &z.transpose().to_owned())
    };
    let sys = &r.sys;
    if let Ok(s) = StateSpace::new(t * &sys.a * ti, t * &sys.b, &sys.c * ti, sys.d.clone()) {
        r.sys = s;
    }
    r.k = t * &r.k;
    for x in &mut r.x0 {
        let v = t * col(x);
        *x = v.col_as_slice(0).to_vec();
    }
    r.theta = prob
        .modal_mt_cols(&inv, &col(&r.theta))
        .col_as_slice(0)
        .to_vec();
    r.solution.theta = r.theta.clone();
    if r.solution.gradient.len() == prob.p {
        let g = prob.modal_mt_cols(md, &col(&r.solution.gradient));
        r.solution.gradient = g.col_as_slice(0).to_vec();
    }
    if r.solution.gauss_newton.nrows() == prob.p {
        r.solution.gauss_newton = symmetric(both(md, &r.solution.gauss_newton));
    }
    r.covariance.covariance = symmetric(both(&inv, &r.covariance.covariance));
    let u = &r.covariance.unidentifiable;
    if u.ncols() > 0 && u.nrows() == prob.p {
        r.covariance.unidentifiable =
            crate::linalg::thin_q_seq(prob.modal_mt_cols(&inv, u).as_ref());
    }
    r
}

/// `(h + h^T) / 2`.
fn symmetric(h: Mat<f64>) -> Mat<f64> {
    Mat::from_fn(h.nrows(), h.ncols(), |i, j| 0.5 * (h[(i, j)] + h[(j, i)]))
}

/// Eigenvector of the 2x2 block `[[p, q], [r, s]]` for the real eigenvalue `lam`, unit length.
fn real_vector(p: f64, q: f64, r: f64, s: f64, lam: f64) -> [f64; 2] {
    let (v1, v2) = ([q, lam - p], [lam - s, r]);
    let n1 = v1[0].hypot(v1[1]);
    let n2 = v2[0].hypot(v2[1]);
    let (v, nv) = if n1 >= n2 { (v1, n1) } else { (v2, n2) };
    if nv > 0.0 {
        [v[0] / nv, v[1] / nv]
    } else {
        [1.0, 0.0]
    }
}

/// The real modal form of a matrix that is block diagonal in `chart`, block by block (so
/// that `T` is block diagonal in the chart, with the states in their order), or `None` when a
/// block's eigenvectors are ill-conditioned.
pub(super) fn chart_modal(abar: MatRef<'_, f64>, chart: &Chart) -> Option<Modal> {
    let n = abar.nrows();
    let mut t = Mat::<f64>::zeros(n, n);
    let mut lam = Mat::<f64>::zeros(n, n);
    let mut block = vec![(0usize, 0usize); n];
    let mut k = 0;
    while k < n {
        if k + 1 < n && chart[k + 1] == k {
            let (p, q, r, s) = (
                abar[(k, k)],
                abar[(k, k + 1)],
                abar[(k + 1, k)],
                abar[(k + 1, k + 1)],
            );
            let (half, det) = (0.5 * (p + s), p * s - q * r);
            let disc = half * half - det;
            if disc < 0.0 {
                // A [vr vi] = [vr vi] [[re, im], [-im, re]] for the eigenvector vr + i vi
                let (re, im) = (half, (-disc).sqrt());
                let (vr, vi) = if q.abs() >= r.abs() {
                    ([q, re - p], [0.0, im])
                } else {
                    ([re - s, r], [im, 0.0])
                };
                let sc = 1.0 / (vr[0].hypot(vr[1]).hypot(vi[0].hypot(vi[1])));
                for i in 0..2 {
                    t[(k + i, k)] = vr[i] * sc;
                    t[(k + i, k + 1)] = vi[i] * sc;
                }
                lam[(k, k)] = re;
                lam[(k + 1, k + 1)] = re;
                lam[(k, k + 1)] = im;
                lam[(k + 1, k)] = -im;
                block[k] = (k, 2);
                block[k + 1] = (k, 2);
            } else {
                // two real poles inside one chart block
                let root = disc.sqrt();
                for (i, l) in [half + root, half - root].into_iter().enumerate() {
                    let v = real_vector(p, q, r, s, l);
                    t[(k, k + i)] = v[0];
                    t[(k + 1, k + i)] = v[1];
                    lam[(k + i, k + i)] = l;
                    block[k + i] = (k + i, 1);
                }
            }
            k += 2;
        } else {
            t[(k, k)] = 1.0;
            lam[(k, k)] = abar[(k, k)];
            block[k] = (k, 1);
            k += 1;
        }
    }
    let ti = crate::linalg::inverse(t.as_ref());
    let cond = t.norm_max() * ti.norm_max() * 2.0;
    if ti.has_nan() || !ti.is_all_finite() || !cond.is_finite() || cond > 1e6 {
        return None;
    }
    let mul = crate::linalg::mul;
    let check = mul(mul(ti.as_ref(), abar).as_ref(), t.as_ref()) - &lam;
    let anorm = abar.norm_max().max(1e-300);
    // NaN in the check counts as a failure
    let accurate = !check.has_nan() && check.norm_max() <= 1e-11 * anorm * cond;
    accurate.then_some(Modal { t, ti, lam, block })
}

impl Predictor<'_> {
    /// Whether entry `(row, j)` of the predictor matrix is held at zero by the chart.
    pub(super) fn held(&self, row: usize, j: usize) -> bool {
        self.chart.as_ref().is_some_and(|c| c[row] != c[j])
    }

    /// The parameters the chart holds at zero (the entries of `A` outside its blocks).
    pub(super) fn chart_mask(&self) -> Vec<bool> {
        let n = self.n;
        let off = self.offsets();
        let mut mask = vec![false; self.p];
        for i in 0..n {
            for j in 0..n {
                mask[off.a + i * n + j] = self.held(i, j);
            }
        }
        mask
    }
}
