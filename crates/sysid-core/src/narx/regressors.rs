//! Lagged variables of NARX / NARMAX models over one or several (MIMO) experiments.

use faer::MatRef;

use crate::error::{check_finite, Result, SysidError};

/// Which signal a lagged variable reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Signal {
    /// A measured (or simulated) output.
    Output,
    /// An input.
    Input,
    /// A residual (NARMAX noise term).
    Noise,
}

/// One lagged variable `signal_channel(t - lag)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LagVar {
    /// The signal.
    pub signal: Signal,
    /// Its channel.
    pub channel: usize,
    /// The lag (0 only for inputs with `nk = 0`).
    pub lag: usize,
}

/// The lagged variables shared by every output's equation: for each output `k` the lags
/// `1..=na[k]`, for each input `j` the lags `nk[j]..nk[j]+nb[j]-1`, for each output `k` the
/// residual lags `1..=ne[k]`, in this order.
#[derive(Debug, Clone, PartialEq)]
pub struct LagSpec {
    /// Number of inputs.
    pub n_inputs: usize,
    /// Number of outputs.
    pub n_outputs: usize,
    /// The variables, in order.
    pub vars: Vec<LagVar>,
    /// The largest lag: rows `t >= max_lag` of every experiment enter the regression.
    pub max_lag: usize,
}

/// One experiment: inputs `(N, m)`, outputs `(N, p)`, and for NARMAX the residuals `(N, p)`.
#[derive(Debug, Clone, Copy)]
pub struct Record<'a> {
    /// Inputs.
    pub u: MatRef<'a, f64>,
    /// Outputs.
    pub y: MatRef<'a, f64>,
    /// Residuals (needed when the spec has noise lags).
    pub e: Option<MatRef<'a, f64>>,
}

impl LagSpec {
    /// The variables of `na` (per output), `nb`, `nk` (per input) and `ne` (per output).
    ///
    /// ```
    /// use sysid_core::narx::regressors::LagSpec;
    /// let s = LagSpec::new(1, 1, &[2], &[1], &[1], &[0]).unwrap();
    /// assert_eq!(s.names(), vec!["y0(t-1)", "y0(t-2)", "u0(t-1)"]);
    /// ```
    pub fn new(
        n_inputs: usize,
        n_outputs: usize,
        na: &[usize],
        nb: &[usize],
        nk: &[usize],
        ne: &[usize],
    ) -> Result<Self> {
        if n_outputs == 0 {
            return Err(SysidError::invalid(
                "y",
                "needs at least one output channel",
            ));
        }
        if na.len() != n_outputs || ne.len() != n_outputs {
            return Err(SysidError::invalid(
                "na, ne",
                format!("need one entry per output ({n_outputs})"),
            ));
        }
        if nb.len() != n_inputs || nk.len() != n_inputs {
            return Err(SysidError::invalid(
                "nb, nk",
                format!("need one entry per input ({n_inputs})"),
            ));
        }
        let mut vars = Vec::new();
        for (k, &n) in na.iter().enumerate() {
            vars.extend((1..=n).map(|lag| LagVar {
                signal: Signal::Output,
                channel: k,
                lag,
            }));
        }
        for j in 0..n_inputs {
            vars.extend((nk[j]..nk[j] + nb[j]).map(|lag| LagVar {
                signal: Signal::Input,
                channel: j,
                lag,
            }));
        }
        for (k, &n) in ne.iter().enumerate() {
            vars.extend((1..=n).map(|lag| LagVar {
                signal: Signal::Noise,
                channel: k,
                lag,
            }));
        }
        if vars.is_empty() {
            return Err(SysidError::invalid(
                "orders",
                "no lagged variable: give na or nb greater than zero",
            ));
        }
        let max_lag = vars.iter().map(|v| v.lag).max().unwrap_or(0).max(1);
        Ok(Self {
            n_inputs,
            n_outputs,
            vars,
            max_lag,
        })
    }

    /// Number of lagged variables.
    pub fn n_vars(&self) -> usize {
        self.vars.len()
    }

    /// Whether residual lags (NARMAX) are present.
    pub fn has_noise(&self) -> bool {
        self.vars.iter().any(|v| v.signal == Signal::Noise)
    }

    /// Readable names `y0(t-1)`, `u1(t-2)`, `e0(t-1)`.
    pub fn names(&self) -> Vec<String> {
        self.vars
            .iter()
            .map(|v| {
                let s = match v.signal {
                    Signal::Output => "y",
                    Signal::Input => "u",
                    Signal::Noise => "e",
                };
                if v.lag == 0 {
                    format!("{s}{}(t)", v.channel)
                } else {
                    format!("{s}{}(t-{})", v.channel, v.lag)
                }
            })
            .collect()
    }

    /// Fills `x` with the variables at time `t >= max_lag`, reading signals through `get`.
    #[inline]
    pub fn fill_with(&self, t: usize, x: &mut [f64], get: impl Fn(Signal, usize, usize) -> f64) {
        for (xv, v) in x.iter_mut().zip(&self.vars) {
            *xv = get(v.signal, v.channel, t - v.lag);
        }
    }

    /// Checks shapes and finiteness of the records; returns the number of regression rows.
    pub fn check_records(&self, records: &[Record<'_>]) -> Result<usize> {
        if records.is_empty() {
            return Err(SysidError::invalid(
                "experiments",
                "needs at least one (u, y) record",
            ));
        }
        let mut rows = 0;
        for r in records {
            let n = r.y.nrows();
            if r.y.ncols() != self.n_outputs
                || r.u.ncols() != self.n_inputs
                || (self.n_inputs > 0 && r.u.nrows() != n)
            {
                return Err(SysidError::ShapeMismatch {
                    what: "u, y".into(),
                    expected: format!("(N, {}) and (N, {})", self.n_inputs, self.n_outputs),
                    got: format!(
                        "({}, {}) and ({}, {})",
                        r.u.nrows(),
                        r.u.ncols(),
                        n,
                        r.y.ncols()
                    ),
                });
            }
            check_finite("u", r.u)?;
            check_finite("y", r.y)?;
            if self.has_noise() {
                match r.e {
                    Some(e) if e.nrows() == n && e.ncols() == self.n_outputs => {
                        check_finite("e", e)?
                    }
                    _ => {
                        return Err(SysidError::invalid(
                            "e",
                            "noise lags need the residuals (N, n_outputs) of every experiment",
                        ))
                    }
                }
            }
            if n <= self.max_lag {
                return Err(SysidError::InsufficientData {
                    context: format!("a NARX regression with lags up to {}", self.max_lag),
                    needed: self.max_lag + 1,
                    got: n,
                    fix: "use a longer record or smaller lags",
                });
            }
            rows += n - self.max_lag;
        }
        Ok(rows)
    }

    /// Fills the column-major block `x` (`len x n_vars`) with rows `t0..t0+len` of a record.
    pub(crate) fn fill_block(&self, r: &Record<'_>, t0: usize, len: usize, x: &mut [f64]) {
        for (c, v) in self.vars.iter().enumerate() {
            let col = &mut x[c * len..(c + 1) * len];
            let src = match v.signal {
                Signal::Output => r.y,
                Signal::Input => r.u,
                Signal::Noise => r.e.expect("checked by check_records"),
            };
            for (i, xv) in col.iter_mut().enumerate() {
                *xv = src[(t0 + i - v.lag, v.channel)];
            }
        }
    }
}
