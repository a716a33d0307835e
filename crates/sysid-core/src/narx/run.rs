//! The loops every NARX-type model runs, written once: free-run simulation and `k`-step
//! prediction by local simulation from every origin. A model only says how its outputs at
//! sample `t` follow from the lagged values ([`Outputs`]).

use faer::{Mat, MatRef};

use super::regressors::{LagSpec, Signal};
use crate::error::{check_finite, Result, SysidError};

/// Outputs larger than this are taken as a diverged simulation.
pub(crate) const BLOWUP: f64 = 1e150;

/// How a model's outputs at one sample follow from its lagged variables.
pub(crate) trait Outputs {
    /// The lagged variables.
    fn spec(&self) -> &LagSpec;
    /// The outputs at sample `t` into `out`, the lagged values read through
    /// `get(signal, channel, sample)`.
    fn outputs(
        &mut self,
        t: usize,
        get: impl Fn(Signal, usize, usize) -> f64,
        out: &mut [f64],
    ) -> Result<()>;
}

/// Free-run simulation from `n = u.nrows()` inputs: the first `max_lag` outputs are `y0`
/// (`max_lag x n_outputs`), later ones simulated (noise terms zero). Fails, naming the sample
/// and ending with `fix`, when the output blows up.
pub(crate) fn free_run<M: Outputs>(
    m: &mut M,
    u: MatRef<'_, f64>,
    y0: MatRef<'_, f64>,
    fix: &str,
) -> Result<Mat<f64>> {
    let spec = m.spec();
    let (n, ny, lag) = (u.nrows(), spec.n_outputs, spec.max_lag);
    if u.ncols() != spec.n_inputs {
        return Err(SysidError::ShapeMismatch {
            what: "u".into(),
            expected: format!("(N, {})", spec.n_inputs),
            got: format!("({}, {})", u.nrows(), u.ncols()),
        });
    }
    check_finite("u", u)?;
    if y0.nrows() != lag || y0.ncols() != ny {
        return Err(SysidError::ShapeMismatch {
            what: "initial outputs".into(),
            expected: format!("({lag}, {ny})"),
            got: format!("({}, {})", y0.nrows(), y0.ncols()),
        });
    }
    check_finite("initial outputs", y0)?;
    let mut y = Mat::<f64>::zeros(n, ny);
    for t in 0..n.min(lag) {
        for i in 0..ny {
            y[(t, i)] = y0[(t, i)];
        }
    }
    let mut out = vec![0.0; ny];
    for t in lag..n {
        {
            let yr = y.as_ref();
            let get = |s: Signal, ch: usize, tt: usize| match s {
                Signal::Output => yr[(tt, ch)],
                Signal::Input => u[(tt, ch)],
                Signal::Noise | Signal::Custom => 0.0,
            };
            m.outputs(t, get, &mut out)?;
        }
        for (i, &v) in out.iter().enumerate() {
            if !v.is_finite() || v.abs() >= BLOWUP {
                return Err(SysidError::numerical(
                    "free-run simulation",
                    format!(
                        "the output diverged at sample {t} (|y{i}| > 1e150): the model is \
                         unstable for this input; {fix}"
                    ),
                ));
            }
            y[(t, i)] = v;
        }
    }
    Ok(y)
}

/// `horizon`-step prediction `yhat(t | t - horizon)` by local simulation from every origin:
/// measured outputs up to `t - horizon`, simulated after; noise terms from the one-step
/// residuals `e` (none: zero) up to `t - horizon`, zero after. Rows `t < max_lag` repeat the measured
/// output. `u`, `y` and `horizon >= 1` are checked by the caller.
pub(crate) fn k_step<M: Outputs>(
    m: &mut M,
    u: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    e: Option<MatRef<'_, f64>>,
    horizon: usize,
) -> Result<Mat<f64>> {
    let (n, ny, lag) = (y.nrows(), m.spec().n_outputs, m.spec().max_lag);
    let mut out = Mat::<f64>::zeros(n, ny);
    for t in 0..n.min(lag) {
        for i in 0..ny {
            out[(t, i)] = y[(t, i)];
        }
    }
    let mut row = vec![0.0; ny];
    let mut loc = vec![0.0; horizon * ny];
    for t in lag..n {
        let origin = t as isize - horizon as isize; // last measured sample
        let first = (origin + 1).max(lag as isize) as usize;
        for s in first..=t {
            {
                let get = |sig: Signal, ch: usize, tt: usize| -> f64 {
                    let measured = (tt as isize) <= origin || tt < lag;
                    match sig {
                        Signal::Input => u[(tt, ch)],
                        Signal::Output if measured => y[(tt, ch)],
                        Signal::Output => loc[(tt - first) * ny + ch],
                        Signal::Noise if (tt as isize) <= origin => e.map_or(0.0, |e| e[(tt, ch)]),
                        Signal::Noise | Signal::Custom => 0.0,
                    }
                };
                m.outputs(s, get, &mut row)?;
            }
            for (i, &v) in row.iter().enumerate() {
                loc[(s - first) * ny + i] = if v.abs() < BLOWUP { v } else { f64::NAN };
            }
        }
        for i in 0..ny {
            let v = loc[(t - first) * ny + i];
            if !v.is_finite() {
                return Err(SysidError::numerical(
                    "k-step prediction",
                    format!("the prediction diverged at sample {t}; use a shorter horizon"),
                ));
            }
            out[(t, i)] = v;
        }
    }
    Ok(out)
}
