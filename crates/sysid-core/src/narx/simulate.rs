//! Free-run simulation, k-step prediction and one-step residuals of NARX / NARMAX models.

use faer::{Mat, MatRef};

use super::basis::{Basis, Term};
use super::regressors::{LagSpec, Signal};
use super::run::{self, Outputs};
use crate::error::{check_io, Result, SysidError};

/// One output's equation `y_i(t) = sum_k coefs[k] terms[k](x(t))`.
#[derive(Debug, Clone, PartialEq)]
pub struct Equation {
    /// The terms.
    pub terms: Vec<Term>,
    /// Their coefficients.
    pub coefs: Vec<f64>,
}

/// A NARX / NARMAX model: lagged variables, basis and one equation per output.
#[derive(Debug, Clone)]
pub struct NarxModel {
    /// The lagged variables.
    pub spec: LagSpec,
    /// The basis (for RBF parameters).
    pub basis: Basis,
    /// One equation per output.
    pub equations: Vec<Equation>,
}

/// Evaluates custom regressor `c` at its arguments (the lagged outputs and inputs listed in
/// [`LagSpec::custom`], in that order).
pub type CustomFn<'a> = dyn FnMut(usize, &[f64]) -> Result<f64> + 'a;

fn no_custom(_: usize, _: &[f64]) -> Result<f64> {
    Err(SysidError::invalid(
        "custom",
        "the model has custom regressors: simulate it with their functions",
    ))
}

impl NarxModel {
    /// Checks the parts and builds the model.
    pub fn new(spec: LagSpec, basis: Basis, equations: Vec<Equation>) -> Result<Self> {
        basis.check(spec.n_lagged())?;
        if equations.len() != spec.n_outputs {
            return Err(SysidError::invalid(
                "equations",
                format!("needs one equation per output ({})", spec.n_outputs),
            ));
        }
        for e in &equations {
            if e.terms.len() != e.coefs.len() {
                return Err(SysidError::invalid(
                    "coefs",
                    "needs one coefficient per term",
                ));
            }
            for t in &e.terms {
                let ok = match (t, &basis) {
                    (Term::Monomial(v), _) => v.iter().all(|&i| i < spec.n_lagged()),
                    (Term::Custom(v), _) => (spec.n_lagged()..spec.n_vars()).contains(v),
                    (Term::Rbf(c), Basis::Rbf(r)) => *c < r.centres.nrows(),
                    (Term::Rbf(_), Basis::Polynomial { .. }) => false,
                };
                if !ok {
                    return Err(SysidError::invalid(
                        "terms",
                        format!("term {t:?} does not fit the lagged variables or the basis"),
                    ));
                }
            }
            if e.coefs.iter().any(|c| !c.is_finite()) {
                return Err(SysidError::invalid("coefs", "non-finite coefficient"));
            }
        }
        Ok(Self {
            spec,
            basis,
            equations,
        })
    }

    /// Whether custom regressor `c` appears in some equation.
    fn uses_custom(&self, c: usize) -> bool {
        let v = self.spec.n_lagged() + c;
        self.equations
            .iter()
            .any(|e| e.terms.contains(&Term::Custom(v)))
    }

    /// Values at time `t` of the custom regressors in use (others zero), arguments read
    /// through `get`.
    fn custom_values(
        &self,
        t: usize,
        used: &[bool],
        get: &impl Fn(Signal, usize, usize) -> f64,
        f: &mut CustomFn<'_>,
        vals: &mut [f64],
    ) -> Result<()> {
        let mut args = Vec::new();
        for (c, a) in self.spec.custom.iter().enumerate() {
            if !used[c] {
                continue;
            }
            args.clear();
            args.extend(a.iter().map(|v| get(v.signal, v.channel, t - v.lag)));
            let v = f(c, &args)?;
            if !v.is_finite() {
                return Err(SysidError::numerical(
                    "custom regressor",
                    format!(
                        "custom regressor {c} returned {v} at sample {t} (arguments {args:?}); \
                         make the function finite over the range of the signals"
                    ),
                ));
            }
            vals[c] = v;
        }
        Ok(())
    }

    #[inline]
    fn output(&self, i: usize, x: &[f64]) -> f64 {
        let e = &self.equations[i];
        e.terms
            .iter()
            .zip(&e.coefs)
            .map(|(t, c)| c * self.basis.eval(t, x))
            .sum()
    }

    /// Free-run simulation from `n = u.nrows()` inputs: the first `max_lag` outputs are
    /// `y0` (`max_lag x n_outputs`, for example the measured ones), later ones are simulated
    /// (noise terms are zero). Fails, naming the sample, when the output blows up.
    pub fn simulate(&self, u: MatRef<'_, f64>, y0: MatRef<'_, f64>) -> Result<Mat<f64>> {
        self.simulate_with(u, y0, &mut no_custom)
    }

    /// [`Self::simulate`] of a model with custom regressors, evaluated by `custom` at every
    /// sample from the simulated outputs and the inputs.
    pub fn simulate_with(
        &self,
        u: MatRef<'_, f64>,
        y0: MatRef<'_, f64>,
        custom: &mut CustomFn<'_>,
    ) -> Result<Mat<f64>> {
        run::free_run(
            &mut WithCustom::new(self, custom),
            u,
            y0,
            "use fewer terms, a lower degree, or inputs within the range of the estimation data",
        )
    }

    /// One-step residuals `e(t) = y(t) - yhat(t | t-1)` (computed recursively for the noise
    /// terms; zero for `t < max_lag`).
    pub fn residuals(&self, u: MatRef<'_, f64>, y: MatRef<'_, f64>) -> Result<Mat<f64>> {
        let p = self.predict(u, y, 1)?;
        Ok(Mat::from_fn(y.nrows(), y.ncols(), |t, i| {
            y[(t, i)] - p[(t, i)]
        }))
    }

    /// `horizon`-step prediction `yhat(t | t - horizon)`: measured outputs up to
    /// `t - horizon`, simulated after; residual terms from the one-step residuals up to
    /// `t - horizon`, zero after. Rows `t < max_lag` repeat the measured output.
    pub fn predict(
        &self,
        u: MatRef<'_, f64>,
        y: MatRef<'_, f64>,
        horizon: usize,
    ) -> Result<Mat<f64>> {
        self.predict_with(u, y, horizon, &mut no_custom)
    }

    /// [`Self::predict`] of a model with custom regressors, evaluated by `custom`.
    pub fn predict_with(
        &self,
        u: MatRef<'_, f64>,
        y: MatRef<'_, f64>,
        horizon: usize,
        custom: &mut CustomFn<'_>,
    ) -> Result<Mat<f64>> {
        let (n, ny, lag) = (y.nrows(), self.spec.n_outputs, self.spec.max_lag);
        check_io("u, y", u, y, self.spec.n_inputs, ny)?;
        if horizon == 0 {
            return Err(SysidError::invalid("horizon", "must be at least 1"));
        }
        let noise = self.spec.has_noise();
        let used: Vec<bool> = (0..self.spec.n_custom())
            .map(|c| self.uses_custom(c))
            .collect();
        let mut cv = vec![0.0; used.len()];
        let measured = |s: Signal, ch: usize, tt: usize| match s {
            Signal::Output => y[(tt, ch)],
            Signal::Input => u[(tt, ch)],
            Signal::Noise | Signal::Custom => 0.0,
        };
        // one-step residuals first (only needed for noise terms)
        let mut e = Mat::<f64>::zeros(n, ny);
        let mut x = vec![0.0; self.spec.n_vars()];
        if noise {
            for t in lag..n {
                self.custom_values(t, &used, &measured, custom, &mut cv)?;
                {
                    let er = e.as_ref();
                    self.spec.fill_with(t, &mut x, |s, ch, tt| match s {
                        Signal::Output => y[(tt, ch)],
                        Signal::Input => u[(tt, ch)],
                        Signal::Noise => er[(tt, ch)],
                        Signal::Custom => cv[ch],
                    });
                }
                for i in 0..ny {
                    e[(t, i)] = y[(t, i)] - self.output(i, &x);
                }
            }
        }
        let mut out = Mat::<f64>::zeros(n, ny);
        for t in 0..n.min(lag) {
            for i in 0..ny {
                out[(t, i)] = y[(t, i)];
            }
        }
        if horizon == 1 {
            for t in lag..n {
                for i in 0..ny {
                    out[(t, i)] = y[(t, i)] - e[(t, i)];
                }
                if !noise {
                    self.custom_values(t, &used, &measured, custom, &mut cv)?;
                    self.spec.fill_with(t, &mut x, |s, ch, tt| match s {
                        Signal::Custom => cv[ch],
                        _ => measured(s, ch, tt),
                    });
                    for i in 0..ny {
                        out[(t, i)] = self.output(i, &x);
                    }
                }
            }
            return Ok(out);
        }
        let e = noise.then_some(e.as_ref());
        run::k_step(&mut WithCustom::new(self, custom), u, y, e, horizon)
    }
}

/// A NARX model with the functions of its custom regressors: how its outputs at one sample
/// follow from the lagged values.
struct WithCustom<'m, 'f, 'c> {
    model: &'m NarxModel,
    custom: &'f mut CustomFn<'c>,
    used: Vec<bool>,
    cv: Vec<f64>,
    x: Vec<f64>,
}

impl<'m, 'f, 'c> WithCustom<'m, 'f, 'c> {
    fn new(model: &'m NarxModel, custom: &'f mut CustomFn<'c>) -> Self {
        let used: Vec<bool> = (0..model.spec.n_custom())
            .map(|c| model.uses_custom(c))
            .collect();
        WithCustom {
            model,
            custom,
            cv: vec![0.0; used.len()],
            used,
            x: vec![0.0; model.spec.n_vars()],
        }
    }
}

impl Outputs for WithCustom<'_, '_, '_> {
    fn spec(&self) -> &LagSpec {
        &self.model.spec
    }

    fn outputs(
        &mut self,
        t: usize,
        get: impl Fn(Signal, usize, usize) -> f64,
        out: &mut [f64],
    ) -> Result<()> {
        let m = self.model;
        m.custom_values(t, &self.used, &get, self.custom, &mut self.cv)?;
        let cv = &self.cv;
        m.spec.fill_with(t, &mut self.x, |s, ch, tt| match s {
            Signal::Custom => cv[ch],
            _ => get(s, ch, tt),
        });
        for (i, o) in out.iter_mut().enumerate() {
            *o = m.output(i, &self.x);
        }
        Ok(())
    }
}
