//! Training of [`NeuralSs`]: truncated simulation errors, back-propagation through each
//! section, Adam, the best validation epoch kept.

use super::NeuralSs;
use crate::error::{Result, SysidError};
use crate::optim::Flow;

/// Options of [`train`].
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct TrainOptions {
    /// Maximum passes over the training data.
    pub epochs: usize,
    /// Sections per gradient step.
    pub batch: usize,
    /// Samples per section.
    pub horizon: usize,
    /// Adam step size.
    pub learning_rate: f64,
    /// Stop after this many epochs without a better validation error.
    pub patience: usize,
    /// Seed of the section sampling.
    pub seed: u64,
    /// Gradients longer than this are scaled down to it.
    pub clip: f64,
    /// Step size of each parameter as a fraction of `learning_rate` (empty: all 1; `0`
    /// keeps a parameter at its start). Adam moves every parameter by about the step size
    /// whatever its gradient, so this sets the scale each parameter moves on.
    pub rates: Vec<f64>,
    /// L2 penalty toward the start, one weight per parameter (empty: none): the criterion
    /// of each step is the batch's mean squared section error plus `sum_i penalty_i (p_i -
    /// p0_i)^2 / 2` (regularisation toward a prior guess, Ljung, *System Identification*,
    /// 2nd ed., 1999, sec. 7.1; MATLAB's `nlssest` offers the same term toward zero).
    pub penalty: Vec<f64>,
}

impl Default for TrainOptions {
    fn default() -> Self {
        TrainOptions {
            epochs: 200,
            batch: 16,
            horizon: 100,
            learning_rate: 1e-3,
            patience: 20,
            seed: 0,
            clip: 10.0,
            rates: Vec::new(),
            penalty: Vec::new(),
        }
    }
}

/// Reported to the observer after every epoch.
#[derive(Debug, Clone, Copy)]
pub struct EpochReport {
    /// Epoch, from 1.
    pub epoch: usize,
    /// Mean squared section error of the epoch's training sections.
    pub train: f64,
    /// Mean squared error of the simulation from rest on the validation segments (of the
    /// training records without them).
    pub validation: f64,
}

/// The result of [`train`].
#[derive(Debug, Clone)]
pub struct TrainResult {
    /// Parameters of the best epoch (or the start, if no epoch beat it).
    pub params: Vec<f64>,
    /// Validation error at the start and after each epoch.
    pub validation: Vec<f64>,
    /// Training error of each epoch.
    pub train: Vec<f64>,
    /// Best epoch (0: the start).
    pub best_epoch: usize,
    /// Why it stopped: "patience", "epochs" or "cancelled".
    pub stop: &'static str,
    /// Sections skipped because their simulation diverged.
    pub diverged: usize,
}

/// A record: inputs and outputs row-major; training sections start in `[lags, end -
/// horizon]`; validation simulates the whole record from rest and scores it from `at` on.
#[derive(Debug, Clone, Copy)]
pub struct Segment<'a> {
    /// Inputs.
    pub u: &'a [f64],
    /// Outputs.
    pub y: &'a [f64],
    /// First scored sample (validation) or end (training, exclusive).
    pub at: usize,
}

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

impl NeuralSs {
    /// Loss `sum (yhat - y)^2 * w` of one section and its gradient (added into `grad`);
    /// `None` when the simulation diverged (nothing added).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn section(
        &self,
        p: &[f64],
        u: &[f64],
        y: &[f64],
        t0: usize,
        len: usize,
        w: f64,
        grad: &mut [f64],
    ) -> Option<f64> {
        let o = self.offsets();
        let (nx, nu, ny) = (self.nx, self.nu, self.ny);
        let (na_f, na_g) = (self.f.n_acts(), self.g.as_ref().map_or(0, |g| g.n_acts()));
        let mut phi = vec![0.0; self.h.n_in()];
        self.phi(u, y, t0, &mut phi);
        let mut ah = vec![0.0; self.h.n_acts()];
        let ho = self.h.forward(&p[o[5]..o[6]], &phi, &mut ah);
        let mut xs = vec![0.0; (len + 1) * nx];
        xs[..nx].copy_from_slice(&ah[ho..ho + nx]);
        let (mut af, mut ag) = (vec![0.0; len * na_f], vec![0.0; len * na_g]);
        let mut e = vec![0.0; len * ny];
        let mut z = vec![0.0; nx + nu];
        let mut loss = 0.0;
        for k in 0..len {
            let t = t0 + k;
            let (xk, xn) = xs.split_at_mut((k + 1) * nx);
            let ok = self.step(
                p,
                &xk[k * nx..],
                &u[t * nu..(t + 1) * nu],
                &mut e[k * ny..(k + 1) * ny],
                &mut xn[..nx],
                &mut z,
                &mut af[k * na_f..(k + 1) * na_f],
                &mut ag[k * na_g..(k + 1) * na_g],
            );
            for i in 0..ny {
                let r = e[k * ny + i] - y[t * ny + i];
                loss += w * r * r;
                e[k * ny + i] = 2.0 * w * r;
            }
            if !ok && k + 1 < len {
                return None;
            }
        }
        if !loss.is_finite() {
            return None;
        }
        // reverse sweep: lam = dL/dx(k+1)
        let mut lam = vec![0.0; nx];
        let mut lx = vec![0.0; nx + nu];
        let wmax = [&self.f, &self.h].iter().map(|m| m.n_acts()).max().unwrap()
            + self.g.as_ref().map_or(0, |g| g.n_acts());
        let mut scratch = vec![0.0; 2 * wmax];
        for k in (0..len).rev() {
            let t = t0 + k;
            let x = &xs[k * nx..(k + 1) * nx];
            let uk = &u[t * nu..(t + 1) * nu];
            let ek = &e[k * ny..(k + 1) * ny];
            lx.iter_mut().for_each(|v| *v = 0.0);
            for i in 0..ny {
                for j in 0..nx {
                    grad[o[1] + i * nx + j] += ek[i] * x[j];
                    lx[j] += p[o[1] + i * nx + j] * ek[i];
                }
                for j in 0..nu {
                    grad[o[2] + i * nu + j] += ek[i] * uk[j];
                }
            }
            if let Some(g) = &self.g {
                let (gp, _) = grad[o[4]..].split_at_mut(o[5] - o[4]);
                g.backward(
                    &p[o[4]..o[5]],
                    &ag[k * na_g..(k + 1) * na_g],
                    ek,
                    gp,
                    &mut lx,
                    &mut scratch,
                );
            }
            if k + 1 < len {
                for i in 0..nx {
                    for j in 0..nx {
                        grad[i * nx + j] += lam[i] * x[j];
                        lx[j] += p[i * nx + j] * lam[i];
                    }
                    for j in 0..nu {
                        grad[o[0] + i * nu + j] += lam[i] * uk[j];
                    }
                }
                let (gp, _) = grad[o[3]..].split_at_mut(o[4] - o[3]);
                self.f.backward(
                    &p[o[3]..o[4]],
                    &af[k * na_f..(k + 1) * na_f],
                    &lam,
                    gp,
                    &mut lx,
                    &mut scratch,
                );
            }
            lam.copy_from_slice(&lx[..nx]);
        }
        let mut gin = vec![0.0; self.h.n_in()];
        let (gp, _) = grad[o[5]..].split_at_mut(o[6] - o[5]);
        self.h
            .backward(&p[o[5]..o[6]], &ah, &lam, gp, &mut gin, &mut scratch);
        Some(loss)
    }

    /// Mean squared error of the free-run simulation from rest (`x0 = 0`, how the model is
    /// used and compared) over each whole validation record, scored from its `at` on
    /// (infinite if one diverges).
    fn validation(&self, p: &[f64], val: &[Segment<'_>]) -> f64 {
        let (mut s, mut n) = (0.0, 0usize);
        let x0 = vec![0.0; self.nx];
        for v in val {
            let ny = self.ny;
            match self.simulate(p, v.u, &x0) {
                Ok(yh) => {
                    for (a, b) in yh[v.at * ny..].iter().zip(&v.y[v.at * ny..]) {
                        s += (a - b) * (a - b);
                    }
                    n += yh.len() - v.at * ny;
                }
                Err(_) => return f64::INFINITY,
            }
        }
        if n == 0 {
            f64::INFINITY
        } else {
            s / n as f64
        }
    }
}

/// Trains from `p0` on sections of `train_data` (each `at` = end of its training part),
/// keeping the parameters with the lowest error on `val`: each record simulated from rest,
/// as the model is used, and scored from its `at` on (a held-out end: the training part
/// before it is the warm-up); without validation segments the training records' simulation
/// from rest decides. The start `p0` is a candidate too, so the result never validates
/// worse than it.
///
/// ```
/// use sysid_core::nlss::neural::{train, NeuralSs, Segment, TrainOptions};
/// use sysid_core::optim::Flow;
/// let m = NeuralSs::new(1, 1, 1, &[4], None, &[], 1);
/// let u: Vec<f64> = (0..300).map(|t| ((t * 37) % 11) as f64 / 11.0 - 0.5).collect();
/// let mut p = vec![0.0; m.n_params()];
/// p[0] = 0.5; p[1] = 1.0; p[2] = 1.0;
/// let y = m.simulate(&p, &u, &[0.0]).unwrap();
/// p[0] = 0.3;
/// let mut opts = TrainOptions::default();
/// opts.epochs = 30; opts.horizon = 20; opts.learning_rate = 1e-2;
/// let seg = [Segment { u: &u, y: &y, at: 300 }];
/// let r = train(&m, &p, &seg, &[], &opts, &mut |_| Flow::Continue).unwrap();
/// assert!(r.validation.last().unwrap() < &r.validation[0]);
/// ```
pub fn train(
    model: &NeuralSs,
    p0: &[f64],
    train_data: &[Segment<'_>],
    val: &[Segment<'_>],
    opts: &TrainOptions,
    observer: &mut dyn FnMut(&EpochReport) -> Flow,
) -> Result<TrainResult> {
    model.check(p0)?;
    let hz = opts.horizon.max(1);
    let starts: Vec<(usize, usize)> = train_data
        .iter()
        .enumerate()
        .filter(|(_, s)| s.at >= model.lags + hz)
        .map(|(i, s)| (i, s.at - hz - model.lags + 1))
        .collect();
    let total: usize = starts.iter().map(|s| s.1).sum();
    if total == 0 {
        return Err(SysidError::InsufficientData {
            context: "neural state-space training sections".into(),
            needed: model.lags + hz,
            got: train_data.iter().map(|s| s.at).max().unwrap_or(0),
            fix: "shorten the horizon or the encoder lags, or give a longer record",
        });
    }
    check_sizes(model, p0.len(), train_data, total, opts.batch)?;
    per_parameter("rates", "step-size factor", &opts.rates, p0.len())?;
    per_parameter("penalty", "weight", &opts.penalty, p0.len())?;
    let np = p0.len();
    let mut p = p0.to_vec();
    let (mut m1, mut m2) = (vec![0.0; np], vec![0.0; np]);
    let mut rng = Rng(opts.seed ^ 0x5EED);
    let score = |p: &[f64]| {
        if val.is_empty() {
            let segs: Vec<Segment<'_>> = train_data
                .iter()
                .map(|s| Segment {
                    u: &s.u[..s.at * model.nu],
                    y: &s.y[..s.at * model.ny],
                    at: 0,
                })
                .collect();
            model.validation(p, &segs)
        } else {
            model.validation(p, val)
        }
    };
    let mut best = (score(&p), p.clone(), 0usize);
    let mut res = TrainResult {
        params: Vec::new(),
        validation: vec![best.0],
        train: Vec::new(),
        best_epoch: 0,
        stop: "epochs",
        diverged: 0,
    };
    // about four passes over every sample per epoch, and at least ten steps
    let per_epoch = (4 * total.div_ceil(hz)).max(10 * opts.batch);
    let w = 1.0 / (hz * model.ny * opts.batch) as f64;
    let mut steps = 0i32;
    let (b1, b2) = (0.9f64, 0.999f64);
    let mut grad = vec![0.0; np];
    for epoch in 1..=opts.epochs {
        let (mut tl, mut tn) = (0.0, 0usize);
        let mut done = 0;
        while done < per_epoch {
            crate::interrupt::check()?;
            grad.iter_mut().for_each(|g| *g = 0.0);
            let mut used = 0;
            for _ in 0..opts.batch {
                crate::interrupt::check()?;
                let mut k = rng.below(total);
                let mut rec = 0;
                while k >= starts[rec].1 {
                    k -= starts[rec].1;
                    rec += 1;
                }
                let s = &train_data[starts[rec].0];
                let t0 = model.lags + k;
                match model.section(&p, s.u, s.y, t0, hz, w, &mut grad) {
                    Some(l) => {
                        tl += l;
                        tn += 1;
                        used += 1;
                    }
                    None => res.diverged += 1,
                }
            }
            done += opts.batch;
            if used == 0 {
                continue;
            }
            penalty(&p, p0, &opts.penalty, &mut grad);
            let norm = grad.iter().map(|g| g * g).sum::<f64>().sqrt();
            let c = if norm > opts.clip {
                opts.clip / norm
            } else {
                1.0
            };
            steps += 1;
            let (c1, c2) = (1.0 - b1.powi(steps), 1.0 - b2.powi(steps));
            for i in 0..np {
                let g = grad[i] * c;
                m1[i] = b1 * m1[i] + (1.0 - b1) * g;
                m2[i] = b2 * m2[i] + (1.0 - b2) * g * g;
                let lr = opts.learning_rate * opts.rates.get(i).copied().unwrap_or(1.0);
                p[i] -= lr * (m1[i] / c1) / ((m2[i] / c2).sqrt() + 1e-8);
            }
        }
        let v = score(&p);
        let train_mse = if tn > 0 {
            tl * opts.batch as f64 / tn as f64
        } else {
            f64::INFINITY
        };
        res.train.push(train_mse);
        res.validation.push(v);
        if v < best.0 {
            best = (v, p.clone(), epoch);
        }
        let flow = observer(&EpochReport {
            epoch,
            train: train_mse,
            validation: v,
        });
        if flow == Flow::Stop {
            res.stop = "cancelled";
            break;
        }
        if epoch - best.2 >= opts.patience {
            res.stop = "patience";
            break;
        }
    }
    res.params = best.1;
    res.best_epoch = best.2;
    Ok(res)
}

/// Refuses a per-parameter option `v` (empty: unused) that is not one finite, non-negative
/// `what` per parameter.
fn per_parameter(name: &'static str, what: &str, v: &[f64], n: usize) -> Result<()> {
    if !v.is_empty() && v.len() != n || v.iter().any(|r| !(r.is_finite() && *r >= 0.0)) {
        return Err(SysidError::invalid(
            name,
            format!(
                "needs one finite, non-negative {what} per parameter ({n}), got {}",
                v.len()
            ),
        ));
    }
    Ok(())
}

/// The L2 penalty `sum_i w_i (p_i - p0_i)^2 / 2` toward the start `p0` (weights `w`, empty:
/// none); its gradient is added into `grad`.
pub(crate) fn penalty(p: &[f64], p0: &[f64], w: &[f64], grad: &mut [f64]) -> f64 {
    let mut v = 0.0;
    for (((g, a), b), wi) in grad.iter_mut().zip(p).zip(p0).zip(w) {
        let d = a - b;
        v += 0.5 * wi * d * d;
        *g += wi * d;
    }
    v
}

/// Refuses, before anything is sized by them, a network with at least as many parameters
/// as the training records give residuals (as the other simulation-error fits do) and a
/// batch of more sections than the records hold (`sections`, each start counted once).
fn check_sizes(
    model: &NeuralSs,
    n_params: usize,
    train_data: &[Segment<'_>],
    sections: usize,
    batch: usize,
) -> Result<()> {
    let residuals: usize = train_data
        .iter()
        .map(|s| s.at.saturating_sub(model.lags).saturating_mul(model.ny))
        .fold(0, usize::saturating_add);
    if n_params >= residuals {
        return Err(SysidError::invalid(
            "hidden",
            format!(
                "the networks have {n_params} parameters but the training record gives \
                 {residuals} residuals; use smaller hidden widths, or give more data"
            ),
        ));
    }
    if batch == 0 || batch > sections {
        return Err(SysidError::invalid(
            "batch",
            format!(
                "{batch} sections per step, but the training record holds {sections} \
                 sections of the horizon; use 1 <= batch <= {sections} (or a shorter horizon)"
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 300 samples of a deterministic pseudo-random input in [-0.5, 0.5).
    fn input() -> Vec<f64> {
        (0..300)
            .map(|t| ((t * 37) % 11) as f64 / 11.0 - 0.5)
            .collect()
    }

    fn run(m: &NeuralSs, batch: usize, u: &[f64]) -> Result<TrainResult> {
        let p = vec![0.0; m.n_params()];
        let opts = TrainOptions {
            epochs: 1,
            horizon: 20,
            batch,
            ..TrainOptions::default()
        };
        let seg = [Segment {
            u,
            y: u,
            at: u.len(),
        }];
        train(m, &p, &seg, &[], &opts, &mut |_| Flow::Continue)
    }

    #[test]
    fn zero_rates_keep_parameters_and_the_start_is_kept_when_nothing_beats_it() {
        let u = input();
        let m = NeuralSs::new(1, 1, 1, &[4], None, &[], 1);
        let mut p = vec![0.0; m.n_params()];
        p[0] = 0.5;
        p[1] = 1.0;
        p[2] = 1.0;
        let y = m.simulate(&p, &u, &[0.0]).unwrap();
        let p0 = {
            let mut q = p.clone();
            q[0] = 0.3;
            q
        };
        let mut opts = TrainOptions {
            epochs: 5,
            horizon: 20,
            learning_rate: 1e-2,
            ..TrainOptions::default()
        };
        opts.rates = vec![1.0; p.len()];
        opts.rates[0] = 0.0; // A stays at 0.3
        let seg = [Segment {
            u: &u,
            y: &y,
            at: 300,
        }];
        let r = train(&m, &p0, &seg, &[], &opts, &mut |_| Flow::Continue).unwrap();
        assert_eq!(r.params[0], 0.3);
        // the true model as the start: no epoch beats it, it comes back unchanged
        opts.rates.clear();
        let r = train(&m, &p, &seg, &[], &opts, &mut |_| Flow::Continue).unwrap();
        assert_eq!(r.best_epoch, 0);
        assert_eq!(r.params, p);
        assert_eq!(r.validation[0], 0.0);
        opts.rates = vec![1.0; 3];
        assert!(train(&m, &p, &seg, &[], &opts, &mut |_| Flow::Continue).is_err());
    }

    #[test]
    fn the_penalty_keeps_the_parameters_near_the_start() {
        let u = input();
        let m = NeuralSs::new(1, 1, 1, &[4], Some(&[3]), &[], 1);
        let mut truth = vec![0.0; m.n_params()];
        truth[..3].copy_from_slice(&[0.5, 1.0, 1.0]);
        let y: Vec<f64> = m
            .simulate(&truth, &u, &[0.0])
            .unwrap()
            .iter()
            .map(|v| v + 0.3 * v * v)
            .collect();
        let mut p0 = truth.clone();
        p0[0] = 0.3;
        let off = m.offsets()[3];
        for (i, v) in p0.iter_mut().enumerate().skip(off) {
            *v = 0.1 * (((i * 7) % 5) as f64 - 2.0); // hidden units of both networks in use
        }
        let dist = |w: f64| {
            let opts = TrainOptions {
                epochs: 20,
                horizon: 20,
                learning_rate: 1e-2,
                patience: 100,
                penalty: if w > 0.0 { vec![w; p0.len()] } else { vec![] },
                ..TrainOptions::default()
            };
            let seg = [Segment {
                u: &u,
                y: &y,
                at: 300,
            }];
            let r = train(&m, &p0, &seg, &[], &opts, &mut |_| Flow::Continue).unwrap();
            let d: f64 = r
                .params
                .iter()
                .zip(&p0)
                .map(|(a, b)| (a - b) * (a - b))
                .sum();
            (d.sqrt(), r.validation[r.best_epoch])
        };
        let (free, weak, strong) = (dist(0.0), dist(1e-3), dist(10.0));
        assert!(free.0 > 0.05, "{free:?}");
        assert!(
            strong.0 < 0.2 * free.0 && weak.0 < free.0 && weak.0 > strong.0,
            "{free:?} {weak:?} {strong:?}"
        );
        assert!(free.1 <= strong.1, "{free:?} {strong:?}");
        let bad = TrainOptions {
            penalty: vec![-1.0; p0.len()],
            ..TrainOptions::default()
        };
        assert!(train(
            &m,
            &p0,
            &[Segment {
                u: &u,
                y: &y,
                at: 300
            }],
            &[],
            &bad,
            &mut |_| Flow::Continue
        )
        .is_err());
    }

    #[test]
    fn absurd_sizes_are_refused_before_training() {
        let u = input();
        let small = NeuralSs::new(1, 1, 1, &[4], None, &[], 1);
        // 300 - 20 - 1 + 1 = 280 section starts
        assert!(run(&small, 280, &u).is_ok());
        // batch = 10^9 ran without end (10^10 sections an epoch)
        let e = run(&small, 1_000_000_000, &u).unwrap_err().to_string();
        assert!(e.contains("batch") && e.contains("280 sections"), "{e}");
        assert!(run(&small, 281, &u).is_err());
        // hidden = 10^4 on 300 samples: 3 10^4 parameters for 299 residuals
        let wide = NeuralSs::new(1, 1, 1, &[10_000], None, &[], 1);
        let e = run(&wide, 16, &u).unwrap_err().to_string();
        assert!(
            e.contains("parameters but the training record gives 299 residuals"),
            "{e}"
        );
    }
}
