//! The PNLSS model: simulation and the simulation-error problem with forward sensitivities.

use super::simulation::{self, check_range, NonlinearTerms};
use super::Monomials;
use crate::error::Result;
use crate::optim::{Evaluation, Flow, Iteration, Options, Solution};
use faer::Mat;

/// Structure of a PNLSS model; the parameters are `theta = [A, B, C, D, E, F]`, each
/// row-major (`E` is `nx x zeta.len()`, `F` is `ny x eta.len()`).
///
/// ```
/// use sysid_core::nlss::{Monomials, Pnlss, Terms};
/// let zeta = Monomials::new(1, 1, Terms::States, &[2]).unwrap();
/// let model = Pnlss::new(1, 1, 1, zeta, Monomials::empty(1));
/// // x(t+1) = 0.5 x + u - 0.1 x^2, y = x
/// let theta = [0.5, 1.0, 1.0, 0.0, -0.1];
/// let (y, _) = model.simulate(&theta, &[1.0, 1.0, 0.0], None).unwrap();
/// assert_eq!(y, vec![0.0, 1.0, 1.4]);
/// ```
#[derive(Debug, Clone)]
pub struct Pnlss {
    /// States.
    pub nx: usize,
    /// Inputs.
    pub nu: usize,
    /// Outputs.
    pub ny: usize,
    /// Monomials of the state equation.
    pub zeta: Monomials,
    /// Monomials of the output equation.
    pub eta: Monomials,
    /// A simulation whose state exceeds this in absolute value has diverged.
    pub bound: f64,
    /// Lower ends of the box the monomials' arguments `z = [x; u]` are clamped to (empty:
    /// no clamping; see [`Pnlss::with_range`]).
    pub lo: Vec<f64>,
    /// Upper ends of that box.
    pub hi: Vec<f64>,
    /// Whether a fit keeps the linear part's `A` stable (see [`Pnlss::with_stable_linear`]).
    pub stable_linear: bool,
}

/// One record: inputs `u` (`N x nu` row-major), outputs `y` (`N x ny` row-major), and the
/// number of leading samples left out of the cost (the transient from the zero state).
#[derive(Debug, Clone, Copy)]
pub struct PnlssData<'a> {
    /// Inputs, row-major.
    pub u: &'a [f64],
    /// Outputs, row-major.
    pub y: &'a [f64],
    /// Leading samples not in the cost.
    pub skip: usize,
}

#[derive(Clone, Copy)]
struct Off {
    e: usize,
    f: usize,
    p: usize,
}

/// Values of one simulation step kept for the sensitivities.
pub(super) struct Work {
    o: Off,
    z: Vec<f64>,
    ze: Vec<f64>,
    et: Vec<f64>,
    /// Whether each state lies inside the box (its monomial derivatives count).
    free: Vec<bool>,
    /// `d zeta / dx` and `d eta / dx` (zero columns for clamped states).
    dze: Vec<f64>,
    det: Vec<f64>,
}

impl Pnlss {
    /// A model with the default divergence bound (1e8).
    pub fn new(nx: usize, nu: usize, ny: usize, zeta: Monomials, eta: Monomials) -> Self {
        Pnlss {
            nx,
            nu,
            ny,
            zeta,
            eta,
            bound: 1e8,
            lo: Vec::new(),
            hi: Vec::new(),
            stable_linear: false,
        }
    }

    /// The model whose fits ([`estimate`]) keep the spectral radius of the linear part's `A`
    /// below 1: a step that would leave that set is turned along its boundary or shortened.
    /// With clamped monomials ([`Pnlss::with_range`]) an unstable `A` runs away as soon as
    /// the state leaves the box, whatever the nonlinear terms do inside it.
    ///
    /// ```
    /// use sysid_core::nlss::{Monomials, Pnlss};
    /// let m = Pnlss::new(1, 1, 1, Monomials::empty(2), Monomials::empty(2)).with_stable_linear();
    /// assert!(m.stable_linear);
    /// ```
    pub fn with_stable_linear(mut self) -> Self {
        self.stable_linear = true;
        self
    }

    /// The model with the monomials evaluated at `z = [x; u]` clamped to the box
    /// `lo <= z <= hi` (one bound per state and input): outside the region the polynomial
    /// was fitted on, the nonlinear terms stay at their boundary values instead of growing
    /// without bound, so a simulation cannot diverge through them. The linear part is not
    /// clamped.
    ///
    /// ```
    /// use sysid_core::nlss::{Monomials, Pnlss, Terms};
    /// let zeta = Monomials::new(1, 1, Terms::States, &[2]).unwrap();
    /// let m = Pnlss::new(1, 1, 1, zeta, Monomials::empty(1))
    ///     .with_range(vec![-1.0, -10.0], vec![1.0, 10.0])
    ///     .unwrap();
    /// // x(t+1) = 0.5 x + u - 0.1 clamp(x, -1, 1)^2
    /// let (y, _) = m.simulate(&[0.5, 1.0, 1.0, 0.0, -0.1], &[3.0, 0.0], None).unwrap();
    /// assert_eq!(y, vec![0.0, 3.0]);
    /// let (y, _) = m.simulate(&[0.5, 1.0, 1.0, 0.0, -0.1], &[3.0, 0.0, 0.0], None).unwrap();
    /// assert!((y[2] - (1.5 - 0.1)).abs() < 1e-15);
    /// ```
    pub fn with_range(mut self, lo: Vec<f64>, hi: Vec<f64>) -> Result<Self> {
        check_range(&lo, &hi, self.nx + self.nu, "states then inputs")?;
        self.lo = lo;
        self.hi = hi;
        Ok(self)
    }

    fn off(&self) -> Off {
        let (n, m, l) = (self.nx, self.nu, self.ny);
        let e = n * n + n * m + l * n + l * m;
        let f = e + n * self.zeta.len();
        Off {
            e,
            f,
            p: f + l * self.eta.len(),
        }
    }

    /// Number of parameters.
    pub fn n_params(&self) -> usize {
        self.off().p
    }

    /// Simulated outputs (`N x ny`) and states (`N x nx`), row-major, from `x0` (zero when
    /// `None`). A diverging simulation is an error naming the sample.
    pub fn simulate(
        &self,
        theta: &[f64],
        u: &[f64],
        x0: Option<&[f64]>,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        simulation::simulate(self, theta, u, x0)
    }

    /// Sum of squares `1/2 sum r^2` over the records, its gradient and Gauss-Newton matrix
    /// (with `jacobian`); an infinite cost when a simulation diverges.
    pub fn cost(&self, theta: &[f64], data: &[PnlssData<'_>], jacobian: bool) -> Evaluation {
        simulation::cost(self, theta, data, jacobian)
    }
}

impl NonlinearTerms for Pnlss {
    type Work = Work;
    const NAME: &'static str = "pnlss";
    const SIMULATION: &'static str = "pnlss simulation";

    fn dims(&self) -> (usize, usize, usize) {
        (self.nx, self.nu, self.ny)
    }

    fn n_params(&self) -> usize {
        self.off().p
    }

    fn bound(&self) -> f64 {
        self.bound
    }

    fn stable_linear(&self) -> bool {
        self.stable_linear
    }

    fn work(&self) -> Work {
        let nx = self.nx;
        Work {
            o: self.off(),
            z: vec![0.0; nx + self.nu],
            ze: vec![0.0; self.zeta.len()],
            et: vec![0.0; self.eta.len()],
            free: vec![true; nx],
            dze: vec![0.0; self.zeta.len() * nx],
            det: vec![0.0; self.eta.len() * nx],
        }
    }

    /// `E zeta(z)` and `F eta(z)` at `z = [x; u]`, clamped to the box.
    fn add_nonlinear(
        &self,
        th: &[f64],
        x: &[f64],
        u: &[f64],
        w: &mut Work,
        y: &mut [f64],
        xn: &mut [f64],
    ) {
        let (n, o) = (self.nx, w.o);
        w.z[..n].copy_from_slice(x);
        w.z[n..].copy_from_slice(u);
        if !self.lo.is_empty() {
            for (k, v) in w.z.iter_mut().enumerate() {
                let c = v.clamp(self.lo[k], self.hi[k]);
                if k < n {
                    w.free[k] = c == *v;
                }
                *v = c;
            }
        }
        self.zeta.eval(&w.z, &mut w.ze);
        self.eta.eval(&w.z, &mut w.et);
        let (ne, nf) = (w.ze.len(), w.et.len());
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(p, q)| p * q).sum::<f64>();
        for (i, yi) in y.iter_mut().enumerate() {
            *yi += dot(&th[o.f + i * nf..o.f + (i + 1) * nf], &w.et);
        }
        for (i, v) in xn.iter_mut().enumerate() {
            *v += dot(&th[o.e + i * ne..o.e + (i + 1) * ne], &w.ze);
        }
    }

    fn prepare_jacobian(&self, w: &mut Work) {
        let nx = self.nx;
        self.zeta.dx(&w.z, &mut w.dze);
        self.eta.dx(&w.z, &mut w.det);
        for j in (0..nx).filter(|&j| !w.free[j]) {
            w.dze.iter_mut().skip(j).step_by(nx).for_each(|v| *v = 0.0);
            w.det.iter_mut().skip(j).step_by(nx).for_each(|v| *v = 0.0);
        }
    }

    /// `F deta/dx`, row `i`.
    fn add_output_slope(&self, th: &[f64], i: usize, w: &Work, ceff: &mut [f64]) {
        let (nx, nf) = (self.nx, self.eta.len());
        for k in 0..nf {
            let fk = th[w.o.f + i * nf + k];
            if fk != 0.0 {
                for j in 0..nx {
                    ceff[j] += fk * w.det[k * nx + j];
                }
            }
        }
    }

    fn add_output_direct(&self, _th: &[f64], i: usize, w: &Work, jb: &mut Mat<f64>, row: usize) {
        let nf = self.eta.len();
        for k in 0..nf {
            jb[(row, w.o.f + i * nf + k)] += w.et[k];
        }
    }

    /// `E dzeta/dx`.
    fn add_state_slope(&self, th: &[f64], w: &Work, aeff: &mut Mat<f64>) {
        let (nx, ne) = (self.nx, self.zeta.len());
        let mut row = vec![0.0; nx];
        for i in 0..nx {
            row.fill(0.0);
            for k in 0..ne {
                let e = th[w.o.e + i * ne + k];
                if e != 0.0 {
                    let dk = &w.dze[k * nx..(k + 1) * nx];
                    row.iter_mut().zip(dk).for_each(|(r, d)| *r += e * d);
                }
            }
            for j in 0..nx {
                aeff[(i, j)] += row[j];
            }
        }
    }

    fn add_state_direct(&self, _th: &[f64], _x: &[f64], w: &Work, s2: &mut Mat<f64>) {
        let ne = self.zeta.len();
        for i in 0..self.nx {
            for j in 0..ne {
                s2[(i, w.o.e + i * ne + j)] += w.ze[j];
            }
        }
    }
}

/// Fits the PNLSS parameters on the simulation error from `theta0` with the shared optimiser
/// (a step whose simulation diverges is rejected like one that raises the cost).
///
/// ```
/// use sysid_core::nlss::{estimate, Monomials, Pnlss, PnlssData, Terms};
/// use sysid_core::optim::{Flow, Options};
/// let zeta = Monomials::new(1, 1, Terms::States, &[2]).unwrap();
/// let model = Pnlss::new(1, 1, 1, zeta, Monomials::empty(1));
/// let truth = [0.5, 1.0, 1.0, 0.0, -0.1];
/// let u: Vec<f64> = (0..200).map(|t| ((t * 7919) % 13) as f64 / 13.0 - 0.5).collect();
/// let (y, _) = model.simulate(&truth, &u, None).unwrap();
/// let data = [PnlssData { u: &u, y: &y, skip: 0 }];
/// let sol = estimate(&model, &data, &[0.4, 1.0, 1.0, 0.0, 0.0], &Options::default(),
///                    &mut |_| Flow::Continue).unwrap();
/// // the state basis is free (x -> s x rescales B, C and E): compare the outputs
/// let (yh, _) = model.simulate(&sol.theta, &u, None).unwrap();
/// assert!(yh.iter().zip(&y).all(|(a, b)| (a - b).abs() < 1e-8));
/// ```
pub fn estimate(
    model: &Pnlss,
    data: &[PnlssData<'_>],
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<Solution> {
    simulation::estimate(model, data, theta0, options, observer)
}
