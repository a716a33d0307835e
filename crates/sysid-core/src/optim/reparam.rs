//! A problem seen through a (possibly nonlinear) change of parameters.
//!
//! A grey-box model has a few physical parameters `p`; the residual provider it reuses (the
//! state-space predictor, say) is written in many "inner" parameters `theta` (the entries of
//! the system matrices). With a map `theta = phi(p)` and its Jacobian `M = dphi/dp` (q x p),
//! the chain rule gives the problem in `p`:
//!
//! ```text
//! J_p = J_theta M,   g_p = M^T g_theta,   H_p = M^T H_theta M
//! ```
//!
//! so the inner provider's blockwise accumulation over samples is used unchanged and only a
//! q x q matrix is transformed per iteration.

use super::{Evaluation, Problem};
use crate::error::{Result, SysidError};
use faer::Mat;

/// A map from the outer parameters `p` to the inner parameters `theta`.
pub trait ParameterMap {
    /// `theta = phi(p)`, and `M = dphi/dp` (q x p) when `jacobian` is `true`.
    fn map(&mut self, p: &[f64], jacobian: bool) -> Result<(Vec<f64>, Option<Mat<f64>>)>;
}

/// `inner` seen in the parameters of `map` (see the module documentation).
pub struct Reparameterized<'a> {
    inner: &'a mut dyn Problem,
    map: &'a mut dyn ParameterMap,
    n: usize,
    last: Option<(Vec<f64>, Vec<f64>)>,
}

impl<'a> Reparameterized<'a> {
    /// The problem in `n` outer parameters.
    pub fn new(inner: &'a mut dyn Problem, map: &'a mut dyn ParameterMap, n: usize) -> Self {
        Reparameterized {
            inner,
            map,
            n,
            last: None,
        }
    }

    /// `phi(p)` (cached for the last point).
    pub fn inner_theta(&mut self, p: &[f64]) -> Result<Vec<f64>> {
        if let Some((lp, th)) = &self.last {
            if lp.as_slice() == p {
                return Ok(th.clone());
            }
        }
        let (th, _) = self.map.map(p, false)?;
        self.check(&th, None)?;
        self.last = Some((p.to_vec(), th.clone()));
        Ok(th)
    }

    fn check(&self, th: &[f64], m: Option<&Mat<f64>>) -> Result<()> {
        let q = self.inner.n_params();
        if th.len() != q {
            return Err(SysidError::numerical(
                "parameter map",
                format!(
                    "returned {} inner parameters, the problem has {q}",
                    th.len()
                ),
            ));
        }
        if let Some(m) = m {
            if m.nrows() != q || m.ncols() != self.n {
                return Err(SysidError::numerical(
                    "parameter map",
                    format!(
                        "returned a {}x{} Jacobian, expected {q}x{}",
                        m.nrows(),
                        m.ncols(),
                        self.n
                    ),
                ));
            }
        }
        Ok(())
    }

    fn with_jacobian(&mut self, p: &[f64]) -> Result<(Vec<f64>, Mat<f64>)> {
        let (th, m) = self.map.map(p, true)?;
        let m = m.ok_or_else(|| {
            SysidError::numerical("parameter map", "no Jacobian returned when asked for one")
        })?;
        self.check(&th, Some(&m))?;
        self.last = Some((p.to_vec(), th.clone()));
        Ok((th, m))
    }

    fn transform(ev: Evaluation, m: &Mat<f64>) -> Evaluation {
        let q = m.nrows();
        let n = m.ncols();
        let gradient = (0..n)
            .map(|j| (0..q).map(|i| m[(i, j)] * ev.gradient[i]).sum())
            .collect();
        let gauss_newton = if ev.gauss_newton.nrows() == q {
            let hm = &ev.gauss_newton * m;
            let mut h = m.transpose() * &hm;
            for i in 0..n {
                for j in 0..i {
                    let v = 0.5 * (h[(i, j)] + h[(j, i)]);
                    h[(i, j)] = v;
                    h[(j, i)] = v;
                }
            }
            h
        } else {
            Mat::zeros(0, 0)
        };
        Evaluation {
            cost: ev.cost,
            gradient,
            gauss_newton,
        }
    }
}

impl Problem for Reparameterized<'_> {
    fn n_params(&self) -> usize {
        self.n
    }

    fn evaluate(&mut self, p: &[f64], jacobian: bool) -> Result<Evaluation> {
        if !jacobian {
            let th = self.inner_theta(p)?;
            if th.iter().any(|v| !v.is_finite()) {
                return Ok(Evaluation::cost_only(f64::INFINITY));
            }
            return self.inner.evaluate(&th, false);
        }
        let (th, m) = self.with_jacobian(p)?;
        if th.iter().any(|v| !v.is_finite()) || m.as_ref().has_nan() {
            return Err(SysidError::numerical(
                "parameter map",
                "the system matrices or their derivatives are not finite at the current \
                 parameters; bound the parameters or start elsewhere",
            ));
        }
        let ev = self.inner.evaluate(&th, true)?;
        Ok(Self::transform(ev, &m))
    }

    fn admissible(&mut self, p: &[f64]) -> bool {
        match self.inner_theta(p) {
            Ok(th) => th.iter().all(|v| v.is_finite()) && self.inner.admissible(&th),
            Err(_) => false,
        }
    }

    fn accepted(&mut self, p: &[f64]) -> Result<bool> {
        let th = self.inner_theta(p)?;
        self.inner.accepted(&th)
    }

    fn criterion(&self) -> Option<f64> {
        self.inner.criterion()
    }

    fn n_residuals(&self) -> Option<usize> {
        self.inner.n_residuals()
    }

    fn gradient_only(&mut self, p: &[f64]) -> Result<Option<Evaluation>> {
        let (th, m) = self.with_jacobian(p)?;
        match self.inner.gradient_only(&th)? {
            Some(ev) => Ok(Some(Self::transform(ev, &m))),
            None => Ok(None),
        }
    }
}
