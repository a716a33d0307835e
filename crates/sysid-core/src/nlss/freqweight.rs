//! The PNLSS simulation error weighted in the frequency domain, for periodic records.
//!
//! With a periodic input of period `P`, the steady-state simulation error of a record (the
//! samples after its transient, `M` whole periods) is averaged over its periods, `rbar(tau)`,
//! and its DFT taken on chosen lines `k` (typically the excited ones):
//!
//! ```text
//! R_i(k) = sum_tau rbar_i(tau) exp(-2 pi j k tau / P),   V = 1/2 sum_k sum_i w_ik |R_i(k)|^2
//! ```
//!
//! with `w_ik` typically the inverse noise variance of the measured output's averaged spectrum
//! (the classic PNLSS cost, Paduart et al. 2010). The Jacobian rows of the time-domain
//! sensitivities are averaged over the periods the same way (one `P ny x p` block, not the
//! `N x p` Jacobian) and transformed on the chosen lines, so the Gauss-Newton matrix is
//! `sum_k w Re(J_k^H J_k)`. Averaging also removes what is not periodic (noise, the end of
//! the transient) before the cost sees it.

use super::simulation::{self, NonlinearTerms};
use super::{Decoupled, Pnlss, PnlssData};
use crate::error::{Result, SysidError};
use crate::optim::{minimize, Evaluation, Flow, Iteration, Options, Problem, Solution};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// The frequency weighting of one record: its period, the DFT lines of one period in the
/// cost (`0 <= k <= P / 2`) and their weights (`lines.len() x ny`, row-major, each `>= 0`).
#[derive(Debug, Clone)]
pub struct LineWeights {
    /// Samples per period.
    pub period: usize,
    /// DFT lines of one period in the cost.
    pub lines: Vec<usize>,
    /// Weight of each line and output, row-major (`lines.len() x ny`).
    pub weights: Vec<f64>,
}

/// The DFT of one record's period on its lines (a planned FFT of the period's length) and
/// the square roots of its weights.
struct Tables {
    period: usize,
    lines: Vec<usize>,
    /// The forward FFT of length `P`, shared by the records of the same period.
    fft: Arc<dyn Fft<f64>>,
    /// `sqrt(w_ik)`, `K x ny`.
    root: Mat<f64>,
}

impl Tables {
    /// The tables of each record, planning one FFT per distinct period.
    fn all(weights: &[LineWeights], ny: usize) -> Vec<Self> {
        let mut planner = FftPlanner::new();
        weights
            .iter()
            .map(|w| Tables {
                period: w.period,
                lines: w.lines.clone(),
                fft: planner.plan_fft_forward(w.period),
                root: Mat::from_fn(w.lines.len(), ny, |a, i| w.weights[a * ny + i].sqrt()),
            })
            .collect()
    }

    /// Real and imaginary parts (`K x c`) of the DFT on the lines of the columns of `x`
    /// (`P x c`).
    fn dft(&self, x: &Mat<f64>) -> (Mat<f64>, Mat<f64>) {
        let (p, k) = (self.period, self.lines.len());
        let (mut re, mut im) = (Mat::zeros(k, x.ncols()), Mat::zeros(k, x.ncols()));
        let mut buf = vec![Complex::new(0.0, 0.0); p];
        let mut scratch = vec![Complex::new(0.0, 0.0); self.fft.get_inplace_scratch_len()];
        for c in 0..x.ncols() {
            buf.iter_mut()
                .enumerate()
                .for_each(|(t, v)| *v = Complex::new(x[(t, c)], 0.0));
            self.fft.process_with_scratch(&mut buf, &mut scratch);
            for (row, &l) in self.lines.iter().enumerate() {
                re[(row, c)] = buf[l].re;
                im[(row, c)] = buf[l].im;
            }
        }
        (re, im)
    }

    /// Adds the weighted cost of the period-averaged residuals `r` (`P ny x 1`, row
    /// `tau ny + i`) and, when `jac` is `Some` (`P ny x p`, same rows), its gradient and
    /// Gauss-Newton matrix to `ev`.
    fn add(&self, r: &Mat<f64>, jac: Option<&Mat<f64>>, ev: &mut Evaluation) {
        let (p, ny) = (self.period, self.root.ncols());
        let weigh = |m: &mut Mat<f64>, i: usize| {
            for a in 0..m.nrows() {
                let s = self.root[(a, i)];
                m.row_mut(a).iter_mut().for_each(|v| *v *= s);
            }
        };
        for i in 0..ny {
            let ri = Mat::from_fn(p, 1, |t, _| r[(t * ny + i, 0)]);
            let (mut rc, mut rs) = self.dft(&ri);
            weigh(&mut rc, i);
            weigh(&mut rs, i);
            ev.cost += 0.5
                * (0..rc.nrows())
                    .map(|a| rc[(a, 0)].powi(2) + rs[(a, 0)].powi(2))
                    .sum::<f64>();
            let Some(j) = jac else { continue };
            let ji = Mat::from_fn(p, j.ncols(), |t, a| j[(t * ny + i, a)]);
            let (mut jc, mut js) = self.dft(&ji);
            weigh(&mut jc, i);
            weigh(&mut js, i);
            for (jk, rk) in [(&jc, &rc), (&js, &rs)] {
                let h = ev.gauss_newton.as_mut();
                matmul(h, Accum::Add, jk.transpose(), jk.as_ref(), 1.0, Par::Seq);
                let g = jk.transpose() * rk;
                for a in 0..g.nrows() {
                    ev.gradient[a] -= g[(a, 0)];
                }
            }
        }
    }
}

/// Checks the weights against the records: one per record, lines within half a period,
/// finite non-negative weights, and a whole number of periods after each transient.
fn check(ny: usize, data: &[PnlssData<'_>], w: &[LineWeights]) -> Result<()> {
    if w.len() != data.len() {
        return Err(SysidError::invalid(
            "weights",
            format!("needs one per record ({}), got {}", data.len(), w.len()),
        ));
    }
    for (d, lw) in data.iter().zip(w) {
        let n = d.y.len() / ny.max(1);
        let p = lw.period;
        if p == 0 || n <= d.skip || (n - d.skip) % p != 0 {
            return Err(SysidError::invalid(
                "weights",
                format!(
                    "a record of {n} samples with a transient of {} is not a whole number of \
                     periods of {p} after it; make the transient whole periods",
                    d.skip
                ),
            ));
        }
        if lw.lines.iter().any(|&k| 2 * k > p) || lw.lines.is_empty() {
            return Err(SysidError::invalid(
                "weights",
                format!("needs at least one line, each at most half the period ({p})"),
            ));
        }
        if lw.weights.len() != lw.lines.len() * ny
            || lw.weights.iter().any(|v| !v.is_finite() || *v < 0.0)
        {
            return Err(SysidError::invalid(
                "weights",
                "needs one finite non-negative weight per line and output",
            ));
        }
    }
    Ok(())
}

/// The frequency-weighted cost (see the module documentation) of the records with their
/// tables, with its gradient and Gauss-Newton matrix when `jacobian`; an infinite cost when
/// a simulation diverges. The Jacobian rows come from the shared sensitivity recursion
/// ([`simulation::record`]), folded onto one period.
fn weighted<M: NonlinearTerms>(
    model: &M,
    theta: &[f64],
    data: &[PnlssData<'_>],
    tables: &[Tables],
    jacobian: bool,
) -> Evaluation {
    let (ny, np) = (model.dims().2, model.n_params());
    let mut ev = Evaluation::cost_only(0.0);
    if jacobian {
        ev.gradient = vec![0.0; np];
        ev.gauss_newton = Mat::zeros(np, np);
    }
    for (d, tab) in data.iter().zip(tables) {
        let rows = tab.period * ny;
        let n = d.y.len() / ny;
        let periods = ((n - d.skip) / tab.period) as f64;
        let mut r = Mat::<f64>::zeros(rows, 1);
        let mut jsum = Mat::<f64>::zeros(if jacobian { rows } else { 0 }, np);
        if jacobian {
            let mut q = 0usize;
            let mut sink = |jb: &mut Mat<f64>, rb: &Mat<f64>, nr: usize, _: &mut Evaluation| {
                for a in 0..nr {
                    let row = q % rows;
                    r[(row, 0)] += rb[(a, 0)] / periods;
                    for c in 0..np {
                        jsum[(row, c)] += jb[(a, c)] / periods;
                    }
                    q += 1;
                }
                jb.as_mut().subrows_mut(0, nr).fill(0.0);
            };
            let mut scratch = Evaluation::cost_only(0.0);
            if !simulation::record(model, theta, d, &mut scratch, true, &mut sink) {
                return Evaluation::cost_only(f64::INFINITY);
            }
        } else {
            let Ok((yh, _)) = simulation::simulate(model, theta, d.u, None) else {
                return Evaluation::cost_only(f64::INFINITY);
            };
            for (q, t) in (d.skip * ny..n * ny).enumerate() {
                r[(q % rows, 0)] += (d.y[t] - yh[t]) / periods;
            }
            if !(0..rows).all(|a| r[(a, 0)].is_finite()) {
                return Evaluation::cost_only(f64::INFINITY);
            }
        }
        tab.add(&r, jacobian.then_some(&jsum), &mut ev);
    }
    if !ev.cost.is_finite() {
        return Evaluation::cost_only(f64::INFINITY);
    }
    ev
}

struct WeightedProblem<'a, M> {
    model: &'a M,
    data: &'a [PnlssData<'a>],
    tables: Vec<Tables>,
}

impl<M: NonlinearTerms> Problem for WeightedProblem<'_, M> {
    fn n_params(&self) -> usize {
        self.model.n_params()
    }

    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation> {
        Ok(weighted(
            self.model,
            theta,
            self.data,
            &self.tables,
            jacobian,
        ))
    }

    fn admissible(&mut self, theta: &[f64]) -> bool {
        simulation::linear_admissible(self.model, theta)
    }

    fn bound_margin(&mut self, theta: &[f64]) -> Option<f64> {
        simulation::linear_margin(self.model, theta)
    }
}

/// The frequency-weighted cost of `theta` on the records (for reports and tests); infinite
/// when a simulation diverges.
pub fn weighted_cost(
    model: &Pnlss,
    data: &[PnlssData<'_>],
    weights: &[LineWeights],
    theta: &[f64],
    jacobian: bool,
) -> Result<Evaluation> {
    simulation::estimate_checks(model, data, theta)?;
    check(model.ny, data, weights)?;
    let tables = Tables::all(weights, model.ny);
    Ok(weighted(model, theta, data, &tables, jacobian))
}

/// Fits the PNLSS parameters on the frequency-weighted simulation error of periodic records
/// (see the module documentation) from `theta0` with the shared optimiser; otherwise as
/// [`super::estimate`].
///
/// ```
/// use sysid_core::nlss::{estimate_weighted, LineWeights, Monomials, Pnlss, PnlssData, Terms};
/// use sysid_core::optim::{Flow, Options};
/// let zeta = Monomials::new(1, 1, Terms::States, &[2]).unwrap();
/// let model = Pnlss::new(1, 1, 1, zeta, Monomials::empty(1));
/// let truth = [0.5, 1.0, 1.0, 0.0, -0.1];
/// // three periods of 16 samples: a sum of cosines on lines 1..=5
/// let u: Vec<f64> = (0..48)
///     .map(|t| (1..=5).map(|k| (0.4 * (2.0 * std::f64::consts::PI * (k * t) as f64 / 16.0
///         + k as f64)).cos()).sum::<f64>() * 0.3)
///     .collect();
/// let (y, _) = model.simulate(&truth, &u, None).unwrap();
/// let data = [PnlssData { u: &u, y: &y, skip: 16 }];
/// let w = [LineWeights { period: 16, lines: (0..=8).collect(), weights: vec![1.0; 9] }];
/// let sol = estimate_weighted(&model, &data, &w, &[0.4, 1.0, 1.0, 0.0, 0.0],
///                             &Options::default(), &mut |_| Flow::Continue).unwrap();
/// let (yh, _) = model.simulate(&sol.theta, &u, None).unwrap();
/// assert!(yh[16..].iter().zip(&y[16..]).all(|(a, b)| (a - b).abs() < 1e-6));
/// ```
pub fn estimate_weighted(
    model: &Pnlss,
    data: &[PnlssData<'_>],
    weights: &[LineWeights],
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<Solution> {
    fit(model, data, weights, theta0, options, observer)
}

/// [`estimate_weighted`] for a decoupled PNLSS model.
pub fn estimate_weighted_decoupled(
    model: &Decoupled,
    data: &[PnlssData<'_>],
    weights: &[LineWeights],
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<Solution> {
    fit(model, data, weights, theta0, options, observer)
}

fn fit<M: NonlinearTerms>(
    model: &M,
    data: &[PnlssData<'_>],
    weights: &[LineWeights],
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<Solution> {
    simulation::estimate_checks(model, data, theta0)?;
    let ny = model.dims().2;
    check(ny, data, weights)?;
    let tables = Tables::all(weights, ny);
    let mut prob = WeightedProblem {
        model,
        data,
        tables,
    };
    minimize(&mut prob, theta0, options, observer)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nlss::{Monomials, Terms};
    use std::f64::consts::PI;

    /// 2 states, 1 input, 2 outputs, state monomials of degrees 2-3 in states and input,
    /// output monomials of degree 2 in the states.
    fn model() -> (Pnlss, Vec<f64>) {
        let zeta = Monomials::new(2, 1, Terms::Full, &[2, 3]).unwrap();
        let eta = Monomials::new(2, 1, Terms::States, &[2]).unwrap();
        let m = Pnlss::new(2, 1, 2, zeta, eta);
        let mut th = vec![0.0; m.n_params()];
        th[..12].copy_from_slice(&[0.6, 0.3, -0.2, 0.5, 1.0, 0.5, 1.0, 0.0, 0.3, 1.0, 0.1, 0.0]);
        for (k, v) in th[12..].iter_mut().enumerate() {
            *v = 0.05 * ((k * 37 % 11) as f64 - 5.0) / 5.0;
        }
        (m, th)
    }

    /// `periods` periods of a random-phase multisine on lines 1..=lines of period `p`.
    fn multisine(p: usize, lines: usize, periods: usize) -> Vec<f64> {
        (0..p * periods)
            .map(|t| {
                (1..=lines)
                    .map(|k| {
                        (2.0 * PI * ((k * t) % p) as f64 / p as f64 + 1.7 * (k * k) as f64).cos()
                    })
                    .sum::<f64>()
                    * 0.5
                    / (lines as f64).sqrt()
            })
            .collect()
    }

    #[test]
    fn cost_is_the_weighted_dft_of_the_period_average() {
        let (m, th) = model();
        let (p, per) = (32, 3);
        let u = multisine(p, 10, per);
        let (y0, _) = m.simulate(&th, &u, None).unwrap();
        let y: Vec<f64> = y0
            .iter()
            .enumerate()
            .map(|(k, v)| v + 0.01 * ((k * 7 % 5) as f64 - 2.0))
            .collect();
        let mut th1 = th.clone();
        th1[0] += 0.01;
        let data = [PnlssData {
            u: &u,
            y: &y,
            skip: p,
        }];
        let lines: Vec<usize> = vec![0, 1, 3, 7, 16];
        let weights: Vec<f64> = (0..lines.len() * 2).map(|k| 0.5 + k as f64).collect();
        let w = [LineWeights {
            period: p,
            lines: lines.clone(),
            weights: weights.clone(),
        }];
        let ev = weighted_cost(&m, &data, &w, &th1, false).unwrap();
        let (yh, _) = m.simulate(&th1, &u, None).unwrap();
        let mut want = 0.0;
        for i in 0..2 {
            for (a, &k) in lines.iter().enumerate() {
                let (mut re, mut im) = (0.0, 0.0);
                for t in p..p * per {
                    let r = (y[t * 2 + i] - yh[t * 2 + i]) / (per - 1) as f64;
                    let ang = 2.0 * PI * (k * (t % p)) as f64 / p as f64;
                    re += r * ang.cos();
                    im -= r * ang.sin();
                }
                want += 0.5 * weights[a * 2 + i] * (re * re + im * im);
            }
        }
        assert!(
            (ev.cost - want).abs() <= 1e-12 * want,
            "{} vs {want}",
            ev.cost
        );
        let evj = weighted_cost(&m, &data, &w, &th1, true).unwrap();
        assert!((evj.cost - want).abs() <= 1e-12 * want);
    }

    #[test]
    fn fft_equals_the_direct_dft() {
        // a power of two, a composite and a prime period
        for n in [64, 24, 37] {
            let x = Mat::from_fn(n, 2, |t, c| ((t * 29 % 17 + c * 5) as f64 - 8.0) / 8.0);
            let w = [LineWeights {
                period: n,
                lines: (0..=n / 2).collect(),
                weights: vec![1.0; n / 2 + 1],
            }];
            let tab = Tables::all(&w, 1).pop().unwrap();
            let (re, im) = tab.dft(&x);
            for c in 0..2 {
                for k in 0..=n / 2 {
                    let (mut a, mut b) = (0.0, 0.0);
                    for t in 0..n {
                        let ang = 2.0 * PI * ((k * t) % n) as f64 / n as f64;
                        a += x[(t, c)] * ang.cos();
                        b -= x[(t, c)] * ang.sin();
                    }
                    assert!(
                        (re[(k, c)] - a).abs() < 1e-12 && (im[(k, c)] - b).abs() < 1e-12,
                        "period {n}, column {c}, line {k}"
                    );
                }
            }
        }
    }

    #[test]
    fn gradient_matches_finite_differences() {
        // a composite and a power-of-two period (different FFT algorithms)
        for p in [24, 32] {
            gradient_check(p);
        }
    }

    fn gradient_check(p: usize) {
        let (m, th) = model();
        let u = multisine(p, 8, 3);
        let (y, _) = m.simulate(&th, &u, None).unwrap();
        let mut th1 = th.clone();
        for (k, v) in th1.iter_mut().enumerate() {
            *v += 0.02 * ((k * 13 % 7) as f64 - 3.0) / 3.0;
        }
        let data = [PnlssData {
            u: &u,
            y: &y,
            skip: p,
        }];
        let lines: Vec<usize> = (0..=p / 2).collect();
        let w = [LineWeights {
            period: p,
            weights: (0..2 * lines.len()).map(|k| 1.0 + (k % 3) as f64).collect(),
            lines,
        }];
        let ev = weighted_cost(&m, &data, &w, &th1, true).unwrap();
        for a in 0..th1.len() {
            let h = 1e-6;
            let (mut tp, mut tm) = (th1.clone(), th1.clone());
            tp[a] += h;
            tm[a] -= h;
            let fd = (weighted_cost(&m, &data, &w, &tp, false).unwrap().cost
                - weighted_cost(&m, &data, &w, &tm, false).unwrap().cost)
                / (2.0 * h);
            let tol = 1e-5 * (1.0 + fd.abs());
            assert!(
                (ev.gradient[a] - fd).abs() < tol,
                "parameter {a}: {} vs {fd}",
                ev.gradient[a]
            );
        }
    }

    #[test]
    fn recovers_a_known_system_from_noise_free_periodic_data() {
        let (m, th) = model();
        let p = 64;
        let u = multisine(p, 20, 4);
        let (y, _) = m.simulate(&th, &u, None).unwrap();
        let mut th0 = th.clone();
        th0[12..].iter_mut().for_each(|v| *v = 0.0);
        th0[0] += 0.05;
        let data = [PnlssData {
            u: &u,
            y: &y,
            skip: p,
        }];
        let w = [LineWeights {
            period: p,
            lines: (0..=32).collect(),
            weights: vec![1.0; 66],
        }];
        let opts = Options {
            max_iter: 200,
            ..Default::default()
        };
        let sol = estimate_weighted(&m, &data, &w, &th0, &opts, &mut |_| Flow::Continue).unwrap();
        let (yh, _) = m.simulate(&sol.theta, &u, None).unwrap();
        let err = yh[2 * p..]
            .iter()
            .zip(&y[2 * p..])
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-6, "largest output error {err}");
    }

    #[test]
    fn rejects_weights_that_do_not_fit() {
        let (m, th) = model();
        let u = multisine(16, 4, 3);
        let (y, _) = m.simulate(&th, &u, None).unwrap();
        let data = [PnlssData {
            u: &u,
            y: &y,
            skip: 10,
        }];
        let w = [LineWeights {
            period: 16,
            lines: vec![1],
            weights: vec![1.0, 1.0],
        }];
        assert!(weighted_cost(&m, &data, &w, &th, false).is_err());
        let data = [PnlssData {
            u: &u,
            y: &y,
            skip: 16,
        }];
        let bad = [LineWeights {
            period: 16,
            lines: vec![9],
            weights: vec![1.0, 1.0],
        }];
        assert!(weighted_cost(&m, &data, &bad, &th, false).is_err());
        let neg = [LineWeights {
            period: 16,
            lines: vec![1],
            weights: vec![-1.0, 1.0],
        }];
        assert!(weighted_cost(&m, &data, &neg, &th, false).is_err());
        assert!(weighted_cost(&m, &data, &[], &th, false).is_err());
    }
}
