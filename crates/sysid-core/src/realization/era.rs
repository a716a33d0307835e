//! The Eigensystem Realisation Algorithm (Juang and Pappa 1985) with its modal accuracy
//! indicators.
//!
//! ERA realises `A = S_n^{-1/2} U_n^T H_1 V_n S_n^{-1/2}`, `B`, `C` from the SVD of a block-Hankel
//! matrix of any shape (block rows r, block columns s), for any number of inputs and outputs.
//! In the modal basis `A = Psi Lambda Psi^{-1}` each mode i is then judged by two numbers in
//! [0, 1]:
//!
//! - modal amplitude coherence (MAC): the identified modal input history
//!   `q_i = [b_i, lambda_i b_i, ..., lambda_i^{s-1} b_i]` (with `b_i` row i of `Psi^{-1} B`)
//!   against the one the data imply, row i of `Psi^{-1} S_n^{1/2} V_n^T`; near 1 for a mode
//!   that the whole record supports, low for a noise mode;
//! - modal phase collinearity (MPC): how close the mode shape `C psi_i` is to a real vector
//!   times a complex scalar (the points `(Re, Im)` of its entries on one line through the
//!   origin), `((mu_1 - mu_2) / (mu_1 + mu_2))^2` with `mu` the eigenvalues of the 2x2 matrix
//!   of sums of products of real and imaginary parts. 1 for a normal (proportionally damped)
//!   mode and always 1 with a single output.

use super::modal::eigen_decomposition;
use super::{
    a_from_shift, auto_order, block_hankel, check_markov, check_order, factors, hankel_size,
    hankel_svd, Realization, RealizationOptions,
};
use crate::error::Result;
use crate::model::StateSpace;
use faer::{c64, Mat};

/// ERA's model with the Hankel singular values and per-mode accuracy indicators.
#[derive(Debug, Clone)]
pub struct EraResult {
    /// The realised model and the singular values of `H_0`.
    pub realization: Realization,
    /// Eigenvalues of A (discrete-time poles), in the order of the indicators.
    pub eigenvalues: Vec<c64>,
    /// Modal amplitude coherence of each eigenvalue, in [0, 1]; NaN when A is defective
    /// (repeated poles without a full set of eigenvectors: no modes to judge).
    pub mac: Vec<f64>,
    /// Modal phase collinearity of each eigenvalue's mode shape, in [0, 1]; NaN as `mac`.
    pub mpc: Vec<f64>,
}

/// ERA on the Markov parameters `h_0 = D, h_1, ...` (each `l x m`).
///
/// The order is `opts.order` or chosen from the Hankel singular values: the numerical rank
/// on noise-free Markov parameters, the count above the noise floor on noisy ones
/// ([`RealizationOptions::order`]).
///
/// ```
/// use faer::mat;
/// use sysid_core::StateSpace;
/// use sysid_core::realization::{era, RealizationOptions};
/// let sys = StateSpace::new(mat![[0.9, 0.3], [-0.3, 0.9]], mat![[1.0], [0.5]],
///                           mat![[1.0, 0.0], [0.3, 1.0]], mat![[0.0], [0.0]]).unwrap();
/// let e = era(&sys.markov(30), &RealizationOptions::default()).unwrap();
/// assert_eq!(e.realization.model.n_states(), 2);
/// assert!(e.mac.iter().all(|&x| (x - 1.0).abs() < 1e-9));
/// ```
pub fn era(markov: &[Mat<f64>], opts: &RealizationOptions) -> Result<EraResult> {
    let (l, m) = check_markov(markov)?;
    let (r, s) = hankel_size(markov.len(), opts.rows, opts.cols)?;
    let h0 = block_hankel(markov, r, s, 0);
    let svd = hankel_svd(h0.as_ref())?;
    let n = opts
        .order
        .unwrap_or_else(|| auto_order(&svd.s, (r * l, s * m), opts, svd.s.len() - 1));
    check_order(n, &svd.s, r, s, l, m)?;
    let (o, ctr) = factors(&svd, n);
    let h1 = block_hankel(markov, r, s, 1);
    let a = a_from_shift(&svd, h1.as_ref(), n);
    let b = ctr.subcols(0, m).to_owned();
    let c = o.subrows(0, l).to_owned();
    let model = StateSpace::new(a, b, c, markov[0].clone())?;
    let realization = Realization {
        model,
        singular_values: svd.s,
        rows: r,
        cols: s,
    };
    let Ok(eig) = eigen_decomposition(realization.model.a.as_ref()) else {
        // a defective A (repeated poles without a full set of eigenvectors): the model stands,
        // its modal indicators are not defined (NaN; the caller says so)
        let eigenvalues = crate::linalg::eigenvalues(realization.model.a.as_ref())?
            .into_iter()
            .map(|(re, im)| c64::new(re, im))
            .collect();
        return Ok(EraResult {
            realization,
            eigenvalues,
            mac: vec![f64::NAN; n],
            mpc: vec![f64::NAN; n],
        });
    };
    let model = &realization.model;
    let ctr_c = Mat::from_fn(n, s * m, |i, j| c64::new(ctr[(i, j)], 0.0));
    let qbar = &eig.inverse * &ctr_c; // data-implied modal input histories
    let c_c = Mat::from_fn(l, n, |i, j| c64::new(model.c[(i, j)], 0.0));
    let shapes = &c_c * &eig.vectors;
    let mut mac = Vec::with_capacity(n);
    let mut mpc = Vec::with_capacity(n);
    for i in 0..n {
        let lam = eig.values[i];
        let mut pw = c64::new(1.0, 0.0);
        let (mut dot, mut nq, mut nqb) = (c64::new(0.0, 0.0), 0.0, 0.0);
        for k in 0..s {
            for j in 0..m {
                let q = pw * qbar[(i, j)];
                let qb = qbar[(i, k * m + j)];
                dot += qb * q.conj();
                nq += q.norm_sqr();
                nqb += qb.norm_sqr();
            }
            pw *= lam;
        }
        let denom = (nq * nqb).sqrt();
        mac.push(if denom > 0.0 {
            (dot.norm() / denom).min(1.0)
        } else {
            0.0
        });
        mpc.push(phase_collinearity((0..l).map(|k| shapes[(k, i)])));
    }
    Ok(EraResult {
        realization,
        eigenvalues: eig.values,
        mac,
        mpc,
    })
}

/// Modal phase collinearity of a complex mode shape (see the module documentation).
pub(crate) fn phase_collinearity(shape: impl Iterator<Item = c64>) -> f64 {
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for z in shape {
        sxx += z.re * z.re;
        syy += z.im * z.im;
        sxy += z.re * z.im;
    }
    let tr = sxx + syy;
    if tr <= 0.0 {
        return 0.0;
    }
    // eigenvalues of [[sxx, sxy], [sxy, syy]]: mu1 - mu2 = sqrt((sxx - syy)^2 + 4 sxy^2)
    let diff = ((sxx - syy).powi(2) + 4.0 * sxy * sxy).sqrt();
    (diff / tr).powi(2).min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::realization::testing::{markov_distance, pole_distance, random_system};
    use rand::{rngs::StdRng, SeedableRng};
    use rand_distr::{Distribution, Normal};

    #[test]
    fn exact_markov_parameters_any_hankel_shape() {
        for (seed, (n, m, l, r, s)) in [
            (2, 1, 1, 10, 10),
            (4, 2, 3, 5, 12),
            (6, 3, 2, 12, 4),
            (8, 2, 2, 20, 20),
        ]
        .iter()
        .enumerate()
        {
            let sys = random_system(*n, *m, *l, 0.95, 100 + seed as u64);
            let h = sys.markov(r + s + 1);
            let opts = RealizationOptions {
                rows: Some(*r),
                cols: Some(*s),
                ..Default::default()
            };
            let e = era(&h, &opts).unwrap();
            assert_eq!(e.realization.model.n_states(), *n, "case {seed}");
            assert!(
                pole_distance(&e.realization.model, &sys) < 1e-9,
                "case {seed}"
            );
            assert!(
                markov_distance(&e.realization.model, &sys, 60) < 1e-9,
                "case {seed}"
            );
            assert!(e.mac.iter().all(|&x| x > 1.0 - 1e-9));
            assert!(e.mpc.iter().all(|&x| (0.0..=1.0).contains(&x)));
        }
    }

    #[test]
    fn noise_modes_have_low_amplitude_coherence() {
        let sys = random_system(2, 1, 1, 0.9, 5);
        let mut h = sys.markov(61);
        let mut rng = StdRng::seed_from_u64(2);
        let noise = Normal::new(0.0, 1e-3).unwrap();
        for hk in h.iter_mut().skip(1) {
            hk[(0, 0)] += noise.sample(&mut rng);
        }
        let e = era(&h, &RealizationOptions::with_order(6)).unwrap();
        let mut macs: Vec<(f64, f64)> = e
            .eigenvalues
            .iter()
            .zip(&e.mac)
            .map(|(z, &mac)| (z.norm(), mac))
            .collect();
        macs.sort_by(|a, b| b.1.partial_cmp(&a.1).unwrap());
        // the two true poles come first with MAC near one; the others are clearly lower
        assert!(macs[1].1 > 0.99, "{macs:?}");
        assert!(macs[2].1 < 0.95, "{macs:?}");
    }

    #[test]
    fn collinearity_of_real_and_rotating_shapes() {
        let real = [c64::new(1.0, 1.0), c64::new(-2.0, -2.0), c64::new(0.5, 0.5)];
        assert!((phase_collinearity(real.into_iter()) - 1.0).abs() < 1e-12);
        let circ = [c64::new(1.0, 0.0), c64::new(0.0, 1.0)];
        assert!(phase_collinearity(circ.into_iter()) < 1e-12);
    }

    #[test]
    fn era_of_a_defective_system_returns_the_model_without_modal_indicators() {
        // a pole of multiplicity 5 with one eigenvector (a Jordan block): ERA realises it
        // (its Markov parameters to 1e-9), but the eigenvectors of the realised A are
        // parallel to working precision: MAC and MPC, which need them, are NaN (the
        // realisation raised before)
        let n = 5;
        let a = Mat::from_fn(n, n, |i, j| match j as i64 - i as i64 {
            0 => 0.5,
            1 => 1.0,
            _ => 0.0,
        });
        let b = Mat::from_fn(n, 1, |i, _| if i + 1 == n { 1.0 } else { 0.0 });
        let c = Mat::from_fn(1, n, |_, j| if j == 0 { 1.0 } else { 0.0 });
        let sys = crate::StateSpace::new(a, b, c, Mat::zeros(1, 1)).unwrap();
        let e = era(&sys.markov(40), &RealizationOptions::with_order(n)).unwrap();
        assert_eq!(e.realization.model.n_states(), n);
        assert!(
            e.mac.iter().chain(&e.mpc).all(|x| x.is_nan()),
            "{:?}",
            e.mac
        );
        assert_eq!(e.eigenvalues.len(), n);
        let (h, h0) = (e.realization.model.markov(20), sys.markov(20));
        for k in 0..20 {
            assert!((h[k][(0, 0)] - h0[k][(0, 0)]).abs() < 1e-9 * (1.0 + h0[k][(0, 0)].abs()));
        }
    }
}
