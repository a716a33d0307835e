//! Ho-Kalman realisation (exact Markov parameters) and Kung's SVD realisation (noisy ones).
//!
//! Both factor `H_0 = U S V^T`. Ho-Kalman takes the order as the numerical rank of `H_0` and A
//! from the shifted Hankel matrix; Kung truncates the SVD at the chosen order and takes A from
//! the shift invariance of the observability factor, `O_r[l..] = O_r[..-l] A`, by least
//! squares, which uses every block row of `H_0` and no shifted matrix.

use super::{
    a_from_shift, auto_order, block_hankel, check_markov, check_order, factors, hankel_size,
    hankel_svd, Realization, RealizationOptions,
};
use crate::error::Result;
use crate::linalg::pinv;
use crate::model::StateSpace;
use faer::Mat;

fn build(markov: &[Mat<f64>], o: &Mat<f64>, ctr: &Mat<f64>, a: Mat<f64>) -> Result<StateSpace> {
    let (l, m) = (markov[0].nrows(), markov[0].ncols());
    let n = a.nrows();
    let b = ctr.subcols(0, m).to_owned();
    let c = o.subrows(0, l).to_owned();
    let _ = n;
    StateSpace::new(a, b, c, markov[0].clone())
}

/// Ho-Kalman realisation. The order is the numerical rank of `H_0` (singular values above
/// `rank_tol` times the largest) unless `opts.order` fixes it.
///
/// ```
/// use faer::mat;
/// use sysid_core::StateSpace;
/// use sysid_core::realization::{ho_kalman, RealizationOptions};
/// let sys = StateSpace::new(mat![[0.8, 0.2], [-0.2, 0.8]], mat![[1.0], [0.0]],
///                           mat![[1.0, 1.0]], mat![[0.0]]).unwrap();
/// let r = ho_kalman(&sys.markov(12), &RealizationOptions::default()).unwrap();
/// assert_eq!(r.model.n_states(), 2);
/// let h = r.model.markov(12);
/// assert!((h[5][(0, 0)] - sys.markov(12)[5][(0, 0)]).abs() < 1e-12);
/// ```
pub fn ho_kalman(markov: &[Mat<f64>], opts: &RealizationOptions) -> Result<Realization> {
    let (l, m) = check_markov(markov)?;
    let (r, s) = hankel_size(markov.len(), opts.rows, opts.cols)?;
    let h0 = block_hankel(markov, r, s, 0);
    let svd = hankel_svd(h0.as_ref())?;
    let n = match opts.order {
        Some(n) => n,
        None => {
            let smax = svd.s[0];
            let n = svd.s.iter().filter(|&&x| x > opts.rank_tol * smax).count();
            if smax == 0.0 {
                0
            } else {
                n
            }
        }
    };
    check_order(n, &svd.s, r, s, l, m)?;
    let rank = svd
        .s
        .iter()
        .filter(|&&x| x > opts.rank_tol * svd.s[0])
        .count();
    if n > rank {
        return Err(crate::error::SysidError::invalid(
            "order",
            format!(
                "order {n} exceeds the numerical rank {rank} of the Hankel matrix (relative \
                 tolerance {:.1e}); Ho-Kalman needs exact Markov parameters: choose order <= \
                 {rank}, or use kung/era for noisy ones",
                opts.rank_tol
            ),
        ));
    }
    let (o, ctr) = factors(&svd, n);
    let h1 = block_hankel(markov, r, s, 1);
    let a = a_from_shift(&svd, h1.as_ref(), n);
    let model = build(markov, &o, &ctr, a)?;
    Ok(Realization {
        model,
        singular_values: svd.s,
        rows: r,
        cols: s,
    })
}

/// Kung's realisation: SVD truncation at `opts.order` (chosen from the singular values if
/// `None`: [`RealizationOptions::order`]), A from the
/// shift invariance of the observability factor. Needs at least two block rows.
///
/// ```
/// use faer::mat;
/// use sysid_core::StateSpace;
/// use sysid_core::realization::{kung, RealizationOptions};
/// let sys = StateSpace::new(mat![[0.9]], mat![[1.0]], mat![[0.5]], mat![[0.0]]).unwrap();
/// let r = kung(&sys.markov(10), &RealizationOptions::with_order(1)).unwrap();
/// assert!((r.model.a[(0, 0)] - 0.9).abs() < 1e-12);
/// ```
pub fn kung(markov: &[Mat<f64>], opts: &RealizationOptions) -> Result<Realization> {
    let (l, m) = check_markov(markov)?;
    let (r, s) = hankel_size(markov.len(), opts.rows, opts.cols)?;
    if r < 2 {
        return Err(crate::error::SysidError::invalid(
            "rows",
            "Kung's method needs at least 2 block rows for the shift of the observability matrix",
        ));
    }
    let h0 = block_hankel(markov, r, s, 0);
    let svd = hankel_svd(h0.as_ref())?;
    let n = opts
        .order
        .unwrap_or_else(|| auto_order(&svd.s, (r * l, s * m), opts, (r - 1) * l));
    check_order(n, &svd.s, r, s, l, m)?;
    let (o, ctr) = factors(&svd, n);
    let up = o.subrows(0, (r - 1) * l);
    let down = o.subrows(l, (r - 1) * l);
    let a = pinv(up, 1e-13)? * down;
    let model = build(markov, &o, &ctr, a)?;
    Ok(Realization {
        model,
        singular_values: svd.s,
        rows: r,
        cols: s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::realization::testing::{markov_distance, pole_distance, random_system};

    #[test]
    fn exact_markov_parameters_of_random_mimo_systems() {
        for (seed, (n, m, l)) in [(1, 1, 1), (3, 2, 2), (6, 2, 3), (7, 3, 1), (9, 1, 4)]
            .iter()
            .enumerate()
        {
            let sys = random_system(*n, *m, *l, 0.95, seed as u64 + 10);
            let h = sys.markov(2 * n + 8);
            let hk = ho_kalman(&h, &RealizationOptions::default()).unwrap();
            assert_eq!(hk.model.n_states(), *n, "Ho-Kalman order, case {seed}");
            assert!(pole_distance(&hk.model, &sys) < 1e-9);
            assert!(markov_distance(&hk.model, &sys, 40) < 1e-9);
            let kg = kung(&h, &RealizationOptions::with_order(*n)).unwrap();
            assert!(
                pole_distance(&kg.model, &sys) < 1e-9,
                "Kung poles, case {seed}"
            );
            assert!(markov_distance(&kg.model, &sys, 40) < 1e-9);
            let auto = kung(&h, &RealizationOptions::default()).unwrap();
            assert_eq!(auto.model.n_states(), *n, "Kung's gap order, case {seed}");
        }
    }

    #[test]
    fn too_few_parameters_and_bad_orders_are_errors() {
        let sys = random_system(4, 1, 1, 0.9, 3);
        let h = sys.markov(6);
        let opts = RealizationOptions {
            rows: Some(4),
            cols: Some(4),
            ..Default::default()
        };
        assert!(matches!(
            ho_kalman(&h, &opts),
            Err(crate::SysidError::InsufficientData { .. })
        ));
        let h = sys.markov(20);
        assert!(matches!(
            kung(&h, &RealizationOptions::with_order(40)),
            Err(crate::SysidError::InvalidArgument { .. })
        ));
        let mut bad = sys.markov(20);
        bad[3][(0, 0)] = f64::NAN;
        assert!(matches!(
            ho_kalman(&bad, &RealizationOptions::default()),
            Err(crate::SysidError::NonFinite { .. })
        ));
    }
}
