//! Neural state-space models: small multilayer maps around a linear part,
//!
//! ```text
//! x(t+1) = A x + B u + f(x, u),      y = C x + D u + g(x, u),      x(t0) = h(phi(t0))
//! ```
//!
//! with `f`, `g` tanh networks and `h` an encoder of the past `phi(t) = [y(t-1..t-L),
//! u(t-1..t-L)]` (a linear map plus a network). Training minimises the mean squared
//! simulation error over short sections (truncated simulation, each starting at the
//! encoder's state) with Adam; gradients by back-propagation through the section (reverse
//! mode over time). The epoch with the lowest validation error is kept, and training stops
//! when it has not improved for `patience` epochs.

mod mlp;
mod train;

pub use mlp::Mlp;
#[cfg(test)]
pub(crate) use train::penalty;
pub use train::{train, EpochReport, Segment, TrainOptions, TrainResult};

use crate::error::{Result, SysidError};

/// The structure of a neural state-space model; parameters `[A, B, C, D, f, g, h]`.
///
/// ```
/// use sysid_core::nlss::neural::{Mlp, NeuralSs};
/// let m = NeuralSs::new(1, 1, 1, &[4], None, &[], 2);
/// let mut p = vec![0.0; m.n_params()];
/// p[0] = 0.5; p[1] = 1.0; p[2] = 1.0; // A, B, C; the networks output zero
/// let y = m.simulate(&p, &[1.0, 1.0, 0.0], &[0.0]).unwrap();
/// assert_eq!(y, vec![0.0, 1.0, 1.5]);
/// ```
#[derive(Debug, Clone)]
pub struct NeuralSs {
    /// States.
    pub nx: usize,
    /// Inputs.
    pub nu: usize,
    /// Outputs.
    pub ny: usize,
    /// State network `[x; u] -> nx`.
    pub f: Mlp,
    /// Output network `[x; u] -> ny`, if any.
    pub g: Option<Mlp>,
    /// Encoder `phi -> nx` (with a linear skip term).
    pub h: Mlp,
    /// Lags of the encoder.
    pub lags: usize,
    /// A state beyond this in absolute value has diverged.
    pub bound: f64,
}

impl NeuralSs {
    /// Hidden widths of `f`, of `g` (`None`: no output network) and of the encoder.
    pub fn new(
        nx: usize,
        nu: usize,
        ny: usize,
        f_hidden: &[usize],
        g_hidden: Option<&[usize]>,
        h_hidden: &[usize],
        lags: usize,
    ) -> Self {
        let sizes = |i: usize, h: &[usize], o: usize| {
            let mut s = vec![i];
            s.extend_from_slice(h);
            s.push(o);
            s
        };
        NeuralSs {
            nx,
            nu,
            ny,
            f: Mlp::new(sizes(nx + nu, f_hidden, nx), false),
            g: g_hidden.map(|h| Mlp::new(sizes(nx + nu, h, ny), false)),
            h: Mlp::new(sizes(lags * (nu + ny), h_hidden, nx), true),
            lags,
            bound: 1e6,
        }
    }

    /// Offsets of `[B, C, D, f, g, h, end]`.
    pub(crate) fn offsets(&self) -> [usize; 7] {
        let (n, m, l) = (self.nx, self.nu, self.ny);
        let b = n * n;
        let c = b + n * m;
        let d = c + l * n;
        let f = d + l * m;
        let g = f + self.f.n_params();
        let h = g + self.g.as_ref().map_or(0, |g| g.n_params());
        [b, c, d, f, g, h, h + self.h.n_params()]
    }

    /// Number of parameters.
    pub fn n_params(&self) -> usize {
        self.offsets()[6]
    }

    /// Checks a parameter vector's length.
    pub fn check(&self, p: &[f64]) -> Result<()> {
        if p.len() != self.n_params() {
            return Err(SysidError::invalid(
                "params",
                format!("needs {} values, got {}", self.n_params(), p.len()),
            ));
        }
        Ok(())
    }

    /// The encoder's input at time `t` (`t >= lags`) of a record.
    pub(crate) fn phi(&self, u: &[f64], y: &[f64], t: usize, out: &mut [f64]) {
        let (m, l, lg) = (self.nu, self.ny, self.lags);
        for k in 0..lg {
            out[k * l..(k + 1) * l].copy_from_slice(&y[(t - 1 - k) * l..(t - k) * l]);
        }
        for k in 0..lg {
            let o = lg * l + k * m;
            out[o..o + m].copy_from_slice(&u[(t - 1 - k) * m..(t - k) * m]);
        }
    }

    /// The encoder's state estimate at `t` from the record's past.
    pub fn encode(&self, p: &[f64], u: &[f64], y: &[f64], t: usize) -> Result<Vec<f64>> {
        self.check(p)?;
        if t < self.lags || t * self.ny > y.len() || t * self.nu > u.len() {
            return Err(SysidError::invalid(
                "t",
                format!("the encoder needs {} past samples before t", self.lags),
            ));
        }
        let o = self.offsets();
        let mut phi = vec![0.0; self.h.n_in()];
        self.phi(u, y, t, &mut phi);
        let mut acts = vec![0.0; self.h.n_acts()];
        let a = self.h.forward(&p[o[5]..o[6]], &phi, &mut acts);
        Ok(acts[a..a + self.nx].to_vec())
    }

    /// One step: output into `y`, next state into `xn`; `false` when it diverged.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn step(
        &self,
        p: &[f64],
        x: &[f64],
        u: &[f64],
        y: &mut [f64],
        xn: &mut [f64],
        z: &mut [f64],
        af: &mut [f64],
        ag: &mut [f64],
    ) -> bool {
        let o = self.offsets();
        let (n, m) = (self.nx, self.nu);
        z[..n].copy_from_slice(x);
        z[n..].copy_from_slice(u);
        let fo = self.f.forward(&p[o[3]..o[4]], z, af);
        let go = self.g.as_ref().map(|g| g.forward(&p[o[4]..o[5]], z, ag));
        for (i, yi) in y.iter_mut().enumerate() {
            let mut v = go.map_or(0.0, |go| ag[go + i]);
            for j in 0..n {
                v += p[o[1] + i * n + j] * x[j];
            }
            for j in 0..m {
                v += p[o[2] + i * m + j] * u[j];
            }
            *yi = v;
        }
        let mut ok = true;
        for i in 0..n {
            let mut v = af[fo + i];
            for j in 0..n {
                v += p[i * n + j] * x[j];
            }
            for j in 0..m {
                v += p[o[0] + i * m + j] * u[j];
            }
            ok &= v.is_finite() && v.abs() <= self.bound;
            xn[i] = v;
        }
        ok
    }

    /// Simulated outputs (`N x ny` row-major) from `x0`; an error when the state diverges.
    pub fn simulate(&self, p: &[f64], u: &[f64], x0: &[f64]) -> Result<Vec<f64>> {
        self.check(p)?;
        if x0.len() != self.nx || u.len() % self.nu.max(1) != 0 {
            return Err(SysidError::invalid(
                "x0/u",
                format!(
                    "x0 needs {} values and u a multiple of {} inputs",
                    self.nx, self.nu
                ),
            ));
        }
        let n = u.len() / self.nu.max(1);
        let (nx, nu, ny) = (self.nx, self.nu, self.ny);
        let mut y = vec![0.0; n * ny];
        let (mut x, mut xn) = (x0.to_vec(), vec![0.0; nx]);
        let mut z = vec![0.0; nx + nu];
        let mut af = vec![0.0; self.f.n_acts()];
        let mut ag = vec![0.0; self.g.as_ref().map_or(0, |g| g.n_acts())];
        for t in 0..n {
            let ok = self.step(
                p,
                &x,
                &u[t * nu..(t + 1) * nu],
                &mut y[t * ny..(t + 1) * ny],
                &mut xn,
                &mut z,
                &mut af,
                &mut ag,
            );
            if !ok && t + 1 < n {
                return Err(SysidError::numerical(
                    "neural state-space simulation",
                    format!(
                        "the state diverged at sample {}; the input leaves the range the \
                             model was trained on",
                        t + 1
                    ),
                ));
            }
            std::mem::swap(&mut x, &mut xn);
        }
        Ok(y)
    }
}
