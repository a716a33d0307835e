//! Simulation and Kalman prediction: the O(N) loops besides compression.
//!
//! Simulation: `x(t+1) = A x(t) + B u(t)`, `y(t) = C x(t) + D u(t)`.
//!
//! One-step prediction with the innovation-form gain K (the steady-state Kalman predictor):
//! `x̂(t+1|t) = A x̂(t|t-1) + B u(t) + K (y(t) - C x̂(t|t-1) - D u(t))`.
//! The k-step-ahead prediction `ŷ(t|t-k)` runs the predictor up to time `t-k+1` and then the
//! model without correction for the remaining `k-1` steps; `horizon = 1` is the one-step
//! predictor. Both are linear in N; the small matrices are kept row-major in flat buffers.

use crate::error::{check_finite, Result, SysidError};
use crate::model::StateSpace;
use faer::{Mat, MatRef};

struct Dense {
    n: usize,
    m: usize,
    l: usize,
    a: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
    d: Vec<f64>,
}

fn flat(m: MatRef<'_, f64>) -> Vec<f64> {
    let mut v = Vec::with_capacity(m.nrows() * m.ncols());
    for i in 0..m.nrows() {
        for j in 0..m.ncols() {
            v.push(m[(i, j)]);
        }
    }
    v
}

impl Dense {
    fn new(sys: &StateSpace) -> Self {
        Self {
            n: sys.n_states(),
            m: sys.n_inputs(),
            l: sys.n_outputs(),
            a: flat(sys.a.as_ref()),
            b: flat(sys.b.as_ref()),
            c: flat(sys.c.as_ref()),
            d: flat(sys.d.as_ref()),
        }
    }

    /// y = C x + D u
    #[inline]
    fn output(&self, x: &[f64], u: &[f64], y: &mut [f64]) {
        for i in 0..self.l {
            let mut s = 0.0;
            let cr = &self.c[i * self.n..(i + 1) * self.n];
            for j in 0..self.n {
                s += cr[j] * x[j];
            }
            let dr = &self.d[i * self.m..(i + 1) * self.m];
            for j in 0..self.m {
                s += dr[j] * u[j];
            }
            y[i] = s;
        }
    }

    /// xn = A x + B u
    #[inline]
    fn step(&self, x: &[f64], u: &[f64], xn: &mut [f64]) {
        for i in 0..self.n {
            let mut s = 0.0;
            let ar = &self.a[i * self.n..(i + 1) * self.n];
            for j in 0..self.n {
                s += ar[j] * x[j];
            }
            let br = &self.b[i * self.m..(i + 1) * self.m];
            for j in 0..self.m {
                s += br[j] * u[j];
            }
            xn[i] = s;
        }
    }
}

fn check_inputs(sys: &StateSpace, u: MatRef<'_, f64>, x0: Option<&[f64]>) -> Result<()> {
    if u.ncols() != sys.n_inputs() {
        return Err(SysidError::ShapeMismatch {
            what: "u".into(),
            expected: format!("(samples, {})", sys.n_inputs()),
            got: format!("({}, {})", u.nrows(), u.ncols()),
        });
    }
    if let Some(x0) = x0 {
        if x0.len() != sys.n_states() {
            return Err(SysidError::ShapeMismatch {
                what: "x0".into(),
                expected: format!("({},)", sys.n_states()),
                got: format!("({},)", x0.len()),
            });
        }
        if let Some(i) = x0.iter().position(|v| !v.is_finite()) {
            return Err(SysidError::NonFinite {
                what: "x0",
                sample: i,
                channel: 0,
            });
        }
    }
    check_finite("u", u)
}

/// Simulates the model from the initial state `x0` (zero when `None`); returns `(N, l)`.
///
/// ```
/// use faer::mat;
/// use sysid_core::{StateSpace, simulate::simulate};
/// let sys = StateSpace::new(mat![[0.5]], mat![[1.0]], mat![[1.0]], mat![[0.0]]).unwrap();
/// let u = mat![[1.0], [0.0], [0.0]];
/// let y = simulate(&sys, u.as_ref(), None).unwrap();
/// assert_eq!((y[(0, 0)], y[(1, 0)], y[(2, 0)]), (0.0, 1.0, 0.5));
/// ```
pub fn simulate(sys: &StateSpace, u: MatRef<'_, f64>, x0: Option<&[f64]>) -> Result<Mat<f64>> {
    check_inputs(sys, u, x0)?;
    let dense = Dense::new(sys);
    let (n, m, l) = (dense.n, dense.m, dense.l);
    let len = u.nrows();
    let mut y = Mat::<f64>::zeros(len, l);
    let mut x = x0.map(|v| v.to_vec()).unwrap_or_else(|| vec![0.0; n]);
    let mut xn = vec![0.0; n];
    let mut ut = vec![0.0; m];
    let mut yt = vec![0.0; l];
    for t in 0..len {
        for j in 0..m {
            ut[j] = u[(t, j)];
        }
        dense.output(&x, &ut, &mut yt);
        for i in 0..l {
            y[(t, i)] = yt[i];
        }
        dense.step(&x, &ut, &mut xn);
        std::mem::swap(&mut x, &mut xn);
    }
    check_finite("simulated output (the model diverged)", y.as_ref()).map_err(|_| {
        SysidError::numerical(
            "simulate",
            "the simulated output overflowed; the model is unstable over this record length",
        )
    })?;
    Ok(y)
}

/// `horizon`-step-ahead predictions `ŷ(t|t-horizon)` of the innovation-form model with gain
/// `k` (n x l); returns `(N, l)`. For `t < horizon` the prediction starts from `x0`.
///
/// ```
/// use faer::mat;
/// use sysid_core::{StateSpace, simulate::predict};
/// let sys = StateSpace::new(mat![[0.9]], mat![[1.0]], mat![[1.0]], mat![[0.0]]).unwrap();
/// let k = mat![[0.9]];  // deadbeat observer: x̂(t+1) = u(t) + 0.9 y(t)
/// let u = mat![[0.0], [0.0], [0.0]];
/// let y = mat![[1.0], [0.9], [0.81]];
/// let yh = predict(&sys, k.as_ref(), u.as_ref(), y.as_ref(), None, 1).unwrap();
/// assert!((yh[(2, 0)] - 0.81).abs() < 1e-15);
/// ```
pub fn predict(
    sys: &StateSpace,
    k: MatRef<'_, f64>,
    u: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    x0: Option<&[f64]>,
    horizon: usize,
) -> Result<Mat<f64>> {
    check_inputs(sys, u, x0)?;
    let dense = Dense::new(sys);
    let (n, m, l) = (dense.n, dense.m, dense.l);
    if horizon == 0 {
        return Err(SysidError::invalid(
            "horizon",
            "the prediction horizon must be >= 1",
        ));
    }
    if k.nrows() != n || k.ncols() != l {
        return Err(SysidError::ShapeMismatch {
            what: "K".into(),
            expected: format!("({n}, {l})"),
            got: format!("({}, {})", k.nrows(), k.ncols()),
        });
    }
    if y.ncols() != l || y.nrows() != u.nrows() {
        return Err(SysidError::ShapeMismatch {
            what: "y".into(),
            expected: format!("({}, {l})", u.nrows()),
            got: format!("({}, {})", y.nrows(), y.ncols()),
        });
    }
    check_finite("y", y)?;
    let kf = flat(k);
    let len = u.nrows();
    // one-step predicted states x̂(t|t-1), t = 0..len
    let mut states = vec![0.0; (len + 1) * n];
    if let Some(x0) = x0 {
        states[..n].copy_from_slice(x0);
    }
    let mut ut = vec![0.0; m];
    let mut yt = vec![0.0; l];
    let mut e = vec![0.0; l];
    let mut xn = vec![0.0; n];
    for t in 0..len {
        for j in 0..m {
            ut[j] = u[(t, j)];
        }
        let (cur, next) = states.split_at_mut((t + 1) * n);
        let x = &cur[t * n..];
        dense.output(x, &ut, &mut yt);
        for i in 0..l {
            e[i] = y[(t, i)] - yt[i];
        }
        dense.step(x, &ut, &mut xn);
        for i in 0..n {
            let mut s = xn[i];
            for j in 0..l {
                s += kf[i * l + j] * e[j];
            }
            next[i] = s;
        }
    }
    let mut out = Mat::<f64>::zeros(len, l);
    let mut x = vec![0.0; n];
    for t in 0..len {
        // start from x̂(s|s-1), s = t - horizon + 1, and run open loop to t
        let s = (t + 1).saturating_sub(horizon);
        x.copy_from_slice(&states[s * n..(s + 1) * n]);
        for tau in s..t {
            for j in 0..m {
                ut[j] = u[(tau, j)];
            }
            dense.step(&x, &ut, &mut xn);
            std::mem::swap(&mut x, &mut xn);
        }
        for j in 0..m {
            ut[j] = u[(t, j)];
        }
        dense.output(&x, &ut, &mut yt);
        for i in 0..l {
            out[(t, i)] = yt[i];
        }
    }
    check_finite("prediction", out.as_ref()).map_err(|_| {
        SysidError::numerical(
            "predict",
            "the prediction overflowed; the predictor A - K C is unstable",
        )
    })?;
    Ok(out)
}
