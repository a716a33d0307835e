//! The predictor's half of geodesic acceleration ([`crate::optim::Options::geodesic`]):
//! `J(theta)^T W r_vv`, the Jacobian at `theta` times the prediction errors' second
//! directional derivative along a step `v`.
//!
//! `r_vv` comes from second differences of the errors, centred where `theta - h v` is
//! admissible,
//!
//! ```text
//! r_vv ~ (e(theta + h v) - 2 e(theta) + e(theta - h v)) / h^2,
//! ```
//!
//! one-sided (`e(theta + 2 h v) - 2 e(theta + h v) + e(theta)`) otherwise. `J^T W x` for
//! substituted residuals `x` is the gradient pass of the evaluation itself (the sensitivity
//! recursion at `theta`, which does not depend on the residuals) with `W x` in place of
//! `W e`: two predictor passes and one gradient pass, no Gauss-Newton matrix.

use super::options::stable_enough;
use super::predictor::{Filter, Predictor};
use crate::error::Result;

impl Predictor<'_> {
    /// The prediction errors at `theta`, every sample in experiment order, `l` per sample.
    pub(super) fn residuals(&self, th: &[f64]) -> Vec<f64> {
        let mut f = Filter::new(self.unpack(th), self.rinv.clone());
        let mut out = Vec::with_capacity(self.n_samples * self.l);
        for (ex, (u, y)) in self.exps.iter().enumerate() {
            f.restart(ex);
            for t in 0..y.nrows() {
                f.errors(*u, *y, t);
                out.extend_from_slice(&f.e);
                f.advance(*u, *y, t);
            }
        }
        out
    }

    /// Whether the structured gradient pass (the one that takes substituted residuals)
    /// applies.
    fn has_gradient_pass(&self) -> bool {
        self.structured && self.col_lo == 0 && self.n > 0
    }

    /// `J(theta)^T W (c e(theta) + x)`, with `x` (`l` per sample, experiment order) in the
    /// units of the errors: the gradient pass with substituted residuals. `None` where the
    /// structured pass does not apply.
    pub(super) fn gradient_with_residuals(
        &mut self,
        th: &[f64],
        c: f64,
        x: Vec<f64>,
    ) -> Result<Option<Vec<f64>>> {
        if !self.has_gradient_pass() || x.len() != self.n_samples * self.l {
            return Ok(None);
        }
        self.substitute = Some((c, x));
        let ev = match self.modal.then(|| self.modal_at(th)).flatten() {
            Some(md) => self.evaluate_modal(th, true, &md),
            None => self.evaluate_structured(th, true),
        };
        self.substitute = None;
        Ok(Some(ev?.gradient))
    }

    /// Admissible, without counting a refusal as a hit of the stability bound (these points
    /// are probes, not trial steps).
    fn probe_admissible(&self, th: &[f64]) -> bool {
        let pm = self.unpack(th);
        stable_enough(
            pm.a.as_ref(),
            pm.k.as_ref(),
            pm.c.as_ref(),
            self.enforce_stability,
        )
    }

    /// `J(theta)^T W r_vv` along `v` by second differences with step `h v` (module doc);
    /// `None` when the pass does not apply or the difference points are inadmissible.
    pub(super) fn second_difference_gradient(
        &mut self,
        th: &[f64],
        v: &[f64],
        h: f64,
    ) -> Result<Option<Vec<f64>>> {
        if !self.has_gradient_pass() || v.len() != th.len() || h.is_nan() || h <= 0.0 {
            return Ok(None);
        }
        let at = |s: f64| -> Vec<f64> { th.iter().zip(v).map(|(t, d)| t + s * h * d).collect() };
        let plus = at(1.0);
        if !self.probe_admissible(&plus) {
            return Ok(None);
        }
        let h2 = h * h;
        let minus = at(-1.0);
        let (c, x) = if self.probe_admissible(&minus) {
            let (rp, rm) = (self.residuals(&plus), self.residuals(&minus));
            let x = rp.iter().zip(&rm).map(|(a, b)| (a + b) / h2).collect();
            (-2.0 / h2, x)
        } else {
            let plus2 = at(2.0);
            if !self.probe_admissible(&plus2) {
                return Ok(None);
            }
            let (rp, rp2) = (self.residuals(&plus), self.residuals(&plus2));
            let x = rp2
                .iter()
                .zip(&rp)
                .map(|(b, a)| (b - 2.0 * a) / h2)
                .collect();
            (1.0 / h2, x)
        };
        self.gradient_with_residuals(th, c, x)
    }
}
