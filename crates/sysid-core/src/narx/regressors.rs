//! Lagged variables of NARX / NARMAX models over one or several (MIMO) experiments.

use faer::MatRef;

use crate::error::{check_finite, check_io, Result, SysidError};

/// Which signal a lagged variable reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Signal {
    /// A measured (or simulated) output.
    Output,
    /// An input.
    Input,
    /// A residual (NARMAX noise term).
    Noise,
    /// The value of a user-supplied (custom) regressor at time `t` (always lag 0): read from
    /// the record's precomputed columns when estimating, computed by a callback from its
    /// arguments when simulating.
    Custom,
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
/// residual lags `1..=ne[k]`, in this order; then, after [`LagSpec::with_custom`], one
/// [`Signal::Custom`] variable per user-supplied regressor.
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
    /// Arguments (lagged outputs and inputs) of each custom regressor.
    pub custom: Vec<Vec<LagVar>>,
}

/// One experiment: inputs `(N, m)`, outputs `(N, p)`, for NARMAX the residuals `(N, p)`,
/// and with custom regressors their values `(N, n_custom)` (row `t`: the value at time `t`;
/// rows before the largest lag are not read).
#[derive(Debug, Clone, Copy)]
pub struct Record<'a> {
    /// Inputs.
    pub u: MatRef<'a, f64>,
    /// Outputs.
    pub y: MatRef<'a, f64>,
    /// Residuals (needed when the spec has noise lags).
    pub e: Option<MatRef<'a, f64>>,
    /// Values of the custom regressors (needed when the spec has some).
    pub c: Option<MatRef<'a, f64>>,
}

impl<'a> Record<'a> {
    /// A record of inputs and outputs only.
    pub fn new(u: MatRef<'a, f64>, y: MatRef<'a, f64>) -> Self {
        Self {
            u,
            y,
            e: None,
            c: None,
        }
    }
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
            custom: Vec::new(),
        })
    }

    /// Adds user-supplied regressors: `args[c]` lists the lagged outputs (lag >= 1) and
    /// inputs of regressor `c`. Each becomes one [`Signal::Custom`] variable after the lagged
    /// ones (a candidate term of its own, never multiplied with others); the largest lag
    /// grows to cover the arguments.
    ///
    /// ```
    /// use sysid_core::narx::regressors::{LagSpec, LagVar, Signal};
    /// let arg = |signal, lag| LagVar { signal, channel: 0, lag };
    /// let s = LagSpec::new(1, 1, &[1], &[1], &[1], &[0]).unwrap()
    ///     .with_custom(vec![vec![arg(Signal::Output, 1), arg(Signal::Input, 3)]]).unwrap();
    /// assert_eq!((s.n_vars(), s.n_lagged(), s.max_lag), (3, 2, 3));
    /// ```
    pub fn with_custom(mut self, args: Vec<Vec<LagVar>>) -> Result<Self> {
        if !self.custom.is_empty() {
            return Err(SysidError::invalid(
                "custom",
                "custom regressors are already set",
            ));
        }
        for (c, a) in args.iter().enumerate() {
            for v in a {
                let ok = match v.signal {
                    Signal::Output => v.channel < self.n_outputs && v.lag >= 1,
                    Signal::Input => v.channel < self.n_inputs,
                    Signal::Noise | Signal::Custom => false,
                };
                if !ok {
                    return Err(SysidError::invalid(
                        "custom",
                        format!(
                            "argument {v:?} of custom regressor {c} is not a lagged output \
                             (lag >= 1) or input of this model"
                        ),
                    ));
                }
                self.max_lag = self.max_lag.max(v.lag);
            }
            self.vars.push(LagVar {
                signal: Signal::Custom,
                channel: c,
                lag: 0,
            });
        }
        self.custom = args;
        Ok(self)
    }

    /// Number of variables (lagged ones and custom regressors).
    pub fn n_vars(&self) -> usize {
        self.vars.len()
    }

    /// Number of lagged variables (the ones monomials and radial basis functions use).
    pub fn n_lagged(&self) -> usize {
        self.vars.len() - self.custom.len()
    }

    /// Number of custom regressors.
    pub fn n_custom(&self) -> usize {
        self.custom.len()
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
                    Signal::Custom => return format!("custom{}", v.channel),
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
            check_io("u, y", r.u, r.y, self.n_inputs, self.n_outputs)?;
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
            if !self.custom.is_empty() {
                match r.c {
                    Some(c) if c.nrows() == n && c.ncols() == self.custom.len() => {
                        let tail = c.subrows(self.max_lag.min(n), n - self.max_lag.min(n));
                        check_finite("custom regressor values", tail)?
                    }
                    _ => {
                        return Err(SysidError::invalid(
                            "custom",
                            format!(
                                "custom regressors need their values (N, {}) for every \
                                 experiment",
                                self.custom.len()
                            ),
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
                Signal::Custom => r.c.expect("checked by check_records"),
            };
            for (i, xv) in col.iter_mut().enumerate() {
                *xv = src[(t0 + i - v.lag, v.channel)];
            }
        }
    }
}
