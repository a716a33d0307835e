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

/// The DFT of one record's period on its lines: a radix-2 FFT when the period is a power of
/// two, else cosine and sine tables (`K x P`); and the square roots of its weights.
struct Tables {
    period: usize,
    lines: Vec<usize>,
    /// `cos(2 pi k tau / P)` and `-sin(..)`, `K x P` (empty with the FFT).
    cos: Mat<f64>,
    sin: Mat<f64>,
    /// The FFT's twiddle factors `exp(-2 pi j m / P)`, `m < P / 2` (empty without).
    twiddle: Vec<(f64, f64)>,
    /// `sqrt(w_ik)`, `K x ny`.
    root: Mat<f64>,
}

impl Tables {
    fn new(w: &LineWeights, ny: usize) -> Self {
        let (p, k) = (w.period, w.lines.len());
        let fft = p.is_power_of_two() && p >= 2;
        // (k t mod P) keeps the angle small and exact for long periods
        let ang = |a: usize, t: usize| 2.0 * std::f64::consts::PI * ((a * t) % p) as f64 / p as f64;
        let (kt, pt) = if fft { (0, 0) } else { (k, p) };
        Tables {
            period: p,
            lines: w.lines.clone(),
            cos: Mat::from_fn(kt, pt, |a, t| ang(w.lines[a], t).cos()),
            sin: Mat::from_fn(kt, pt, |a, t| -ang(w.lines[a], t).sin()),
            twiddle: if fft {
                (0..p / 2)
                    .map(|m| (ang(m, 1).cos(), -ang(m, 1).sin()))
                    .collect()
            } else {
                Vec::new()
            },
            root: Mat::from_fn(k, ny, |a, i| w.weights[a * ny + i].sqrt()),
        }
    }

    /// Real and imaginary parts (`K x c`) of the DFT on the lines of the columns of `x`
    /// (`P x c`).
    fn dft(&self, x: &Mat<f64>) -> (Mat<f64>, Mat<f64>) {
        if self.twiddle.is_empty() {
            return (&self.cos * x, &self.sin * x);
        }
        let (p, k) = (self.period, self.lines.len());
        let (mut re, mut im) = (Mat::zeros(k, x.ncols()), Mat::zeros(k, x.ncols()));
        let (mut a, mut b) = (vec![0.0; p], vec![0.0; p]);
        for c in 0..x.ncols() {
            a.iter_mut().enumerate().for_each(|(t, v)| *v = x[(t, c)]);
            b.fill(0.0);
            fft(&mut a, &mut b, &self.twiddle);
            for (row, &l) in self.lines.iter().enumerate() {
                re[(row, c)] = a[l];
                im[(row, c)] = b[l];
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

/// In-place radix-2 decimation-in-time FFT of `(re, im)` (length a power of two) with the
/// twiddle factors `exp(-2 pi j m / n)`, `m < n / 2`.
fn fft(re: &mut [f64], im: &mut [f64], tw: &[(f64, f64)]) {
    let n = re.len();
    let bits = n.trailing_zeros();
    for i in 0..n {
        let j = i.reverse_bits() >> (usize::BITS - bits);
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let step = n / len;
        for start in (0..n).step_by(len) {
            for m in 0..len / 2 {
                let (wr, wi) = tw[m * step];
                let (a, b) = (start + m, start + m + len / 2);
                let (xr, xi) = (re[b] * wr - im[b] * wi, re[b] * wi + im[b] * wr);
                re[b] = re[a] - xr;
                im[b] = im[a] - xi;
                re[a] += xr;
                im[a] += xi;
            }
        }
        len *= 2;
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
    let tables: Vec<Tables> = weights.iter().map(|w| Tables::new(w, model.ny)).collect();
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
    let tables = weights.iter().map(|w| Tables::new(w, ny)).collect();
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
        let n = 64;
        let x: Vec<f64> = (0..n).map(|t| ((t * 29 % 17) as f64 - 8.0) / 8.0).collect();
        let tw: Vec<(f64, f64)> = (0..n / 2)
            .map(|m| {
                let a = 2.0 * PI * m as f64 / n as f64;
                (a.cos(), -a.sin())
            })
            .collect();
        let (mut re, mut im) = (x.clone(), vec![0.0; n]);
        fft(&mut re, &mut im, &tw);
        for k in 0..n {
            let (mut a, mut b) = (0.0, 0.0);
            for (t, v) in x.iter().enumerate() {
                let ang = 2.0 * PI * ((k * t) % n) as f64 / n as f64;
                a += v * ang.cos();
                b -= v * ang.sin();
            }
            assert!(
                (re[k] - a).abs() < 1e-12 && (im[k] - b).abs() < 1e-12,
                "line {k}"
            );
        }
    }

    #[test]
    fn gradient_matches_finite_differences() {
        // a period of 24 takes the table DFT, one of 32 the FFT
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
