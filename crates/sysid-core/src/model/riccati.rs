//! The discrete algebraic Riccati equation of the steady-state Kalman predictor.
//!
//! For `x(t+1) = A x + w`, `y = C x + v` with `E[w w^T] = Q`, `E[v v^T] = R`, `E[w v^T] = S`,
//! the stabilising solution P of
//!
//! ```text
//! P = A P A^T + Q - (A P C^T + S)(C P C^T + R)^{-1}(A P C^T + S)^T
//! ```
//!
//! gives the innovation-form gain `K = (A P C^T + S)(C P C^T + R)^{-1}` and the innovation
//! covariance `C P C^T + R`; `A - K C` has all eigenvalues inside the unit circle.
//!
//! The cross term is removed first (`Ā = A - S R^{-1} C`, `Q̄ = Q - S R^{-1} S^T`), then the
//! structure-preserving doubling algorithm (Chu, Fan and Lin 2005) converges quadratically to
//! the stabilising solution when one exists. The result is checked: `A - K C` stable and the
//! equation itself satisfied (relative residual `1e-9`). Covariances estimated from nearly
//! noise-free outputs, or at orders above the system's, can defeat the doubling in floating
//! point: `R` many orders below `Q` (the cross-term removal then loses to round-off the
//! positive semi-definiteness the doubling needs), states in badly scaled coordinates
//! (columns of `C` of size 100 next to 1), modes that no noise drives; it then returns no
//! stabilising gain, or a stabilising but wrong one. On such a failure the equation is solved
//! again in the state coordinates where every column of `C` has unit norm (the solution is
//! mapped back: the equation is invariant under a change of state basis): the doubling with
//! `Q` and `R` raised by `0`, `1e-12`, ... `1` times the scaled covariances' trace gives a
//! stabilising start, from which Newton's (Hewer's) iteration solves the equation as given.
//! Where Newton's iteration fails, a doubling solution with a shift of at most `1e-6` that
//! satisfies its shifted equation is returned, the shift recorded in
//! [`KalmanSolution::regularization`] (the gain is continuous in the covariances where
//! `C P C^T + R` stays positive definite). Newton's iteration can stall above the tolerance
//! when `A` has modes on or near the unit circle (its Stein solves lose digits there: an
//! unstable subspace model of 19 states on a robot-arm record stalls at relative residuals of
//! 3e-10 to 5e-9, where SciPy's Schur method reaches 6e-12); the most accurate stabilising
//! solution seen is then returned when its residual is below [`LAST_RESORT_TOL`], recorded in
//! [`KalmanSolution::residual`]. If nothing gives a stable `A - K C` that accurately,
//! [`SysidError::NoStabilizingSolution`] is returned rather than a wrong gain.

use crate::error::{Result, SysidError};
use crate::linalg::{spectral_radius, symmetrize};
use faer::linalg::solvers::Solve;
use faer::{Mat, MatRef};

/// Solution of the predictor Riccati equation.
#[derive(Debug, Clone)]
pub struct KalmanSolution {
    /// State error covariance P (n x n).
    pub p: Mat<f64>,
    /// Innovation-form (predictor) gain K (n x l).
    pub k: Mat<f64>,
    /// Innovation covariance `C P C^T + R` (l x l).
    pub innovation_cov: Mat<f64>,
    /// Doubling iterations used (plus Newton's, when they refined the solution).
    pub iterations: usize,
    /// The relative shift of `Q` and `R` (times the trace of the covariances in scaled
    /// coordinates) whose equation the returned solution satisfies; 0 for the equation as
    /// given.
    pub regularization: f64,
    /// Relative residual of the equation the solution satisfies (`|P - A P A^T - Q + K (A P
    /// C^T + S)^T|` over the larger of `|P|` and `|Q|`, entrywise maxima): at most `1e-9`
    /// unless the solvers stalled (see the module notes), never above [`LAST_RESORT_TOL`].
    pub residual: f64,
}

/// Largest relative residual of the Riccati equation accepted (`|P - A P A^T - Q + K G^T|`
/// over the larger of `|P|` and `|Q|`, entrywise maxima).
const RESIDUAL_TOL: f64 = 1e-9;

/// Relative shifts of `Q` and `R` (times the trace of the scaled covariances) tried, in
/// scaled coordinates, after a failure in the given ones: each gives a start for Newton's
/// iteration on the equation as given; a solution of a shifted equation is itself accepted
/// only for shifts up to [`MAX_KEPT_SHIFT`].
const SHIFTS: [f64; 7] = [0.0, 1e-12, 1e-10, 1e-8, 1e-6, 1e-3, 1.0];

/// The largest relative shift whose solution is returned when Newton's iteration fails.
const MAX_KEPT_SHIFT: f64 = 1e-6;

/// The largest relative residual of a stabilising solution returned when no solver reached
/// [`RESIDUAL_TOL`] (a gain this accurate predicts as well as the exact one).
pub const LAST_RESORT_TOL: f64 = 1e-6;

/// Solves the predictor DARE for (A, C, Q, R, S).
///
/// ```
/// use faer::mat;
/// use sysid_core::riccati::kalman_gain;
/// // scalar random walk observed in noise
/// let s = kalman_gain(mat![[1.0]].as_ref(), mat![[1.0]].as_ref(), mat![[1.0]].as_ref(),
///                     mat![[1.0]].as_ref(), mat![[0.0]].as_ref()).unwrap();
/// let p = (1.0 + 5f64.sqrt()) / 2.0;            // P = P + 1 - P^2 / (P + 1)
/// assert!((s.p[(0, 0)] - p).abs() < 1e-12);
/// ```
pub fn kalman_gain(
    a: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    q: MatRef<'_, f64>,
    r: MatRef<'_, f64>,
    s: MatRef<'_, f64>,
) -> Result<KalmanSolution> {
    // the most accurate stabilising solution of the equation as given, for the last resort
    let mut best: Option<KalmanSolution> = None;
    let keep = |sol: KalmanSolution, best: &mut Option<KalmanSolution>| {
        if best.as_ref().is_none_or(|b| sol.residual < b.residual) {
            *best = Some(sol);
        }
    };
    let first = match doubling(a, c, q, r, s) {
        Ok(mut sol) => match residual(a, c, q, s, &sol) {
            rel if rel <= RESIDUAL_TOL => {
                sol.residual = rel;
                return Ok(sol);
            }
            rel => {
                sol.residual = rel;
                keep(sol, &mut best);
                format!("the doubling lost its accuracy (relative residual {rel:.1e})")
            }
        },
        Err(SysidError::NoStabilizingSolution { reason }) => reason,
        Err(e) => return Err(e),
    };
    // the state basis where every column of C has unit norm: x = T^{-1} x', T = diag(d)
    let (n, l) = (a.nrows(), c.nrows());
    let cmax = (0..n).map(|j| c.col(j).norm_l2()).fold(0.0f64, f64::max);
    let d: Vec<f64> = (0..n)
        .map(|j| {
            let norm = c.col(j).norm_l2();
            if norm > 1e-12 * cmax && norm.is_finite() {
                norm
            } else {
                1.0
            }
        })
        .collect();
    let a2 = Mat::from_fn(n, n, |i, j| d[i] * a[(i, j)] / d[j]);
    let c2 = Mat::from_fn(l, n, |i, j| c[(i, j)] / d[j]);
    let q2 = Mat::from_fn(n, n, |i, j| d[i] * q[(i, j)] * d[j]);
    let s2 = Mat::from_fn(n, l, |i, j| d[i] * s[(i, j)]);
    let (a2, c2, s2) = (a2.as_ref(), c2.as_ref(), s2.as_ref());
    let back = |sol: KalmanSolution, rel: f64| KalmanSolution {
        // P = T^{-1} P' T^{-1}, K = T^{-1} K'
        p: Mat::from_fn(n, n, |i, j| sol.p[(i, j)] / (d[i] * d[j])),
        k: Mat::from_fn(n, l, |i, j| sol.k[(i, j)] / d[i]),
        innovation_cov: sol.innovation_cov,
        iterations: sol.iterations,
        regularization: rel,
        residual: sol.residual,
    };
    let trace: f64 =
        (0..n).map(|i| q2[(i, i)]).sum::<f64>() + (0..l).map(|i| r[(i, i)]).sum::<f64>();
    for rel in SHIFTS {
        if rel > 0.0 && (!trace.is_finite() || trace <= 0.0) {
            break;
        }
        let eps = rel * trace;
        let (mut q_shift, mut r_shift) = (q2.clone(), r.to_owned());
        for i in 0..n {
            q_shift[(i, i)] += eps;
        }
        for i in 0..l {
            r_shift[(i, i)] += eps;
        }
        let Ok(start) = doubling(a2, c2, q_shift.as_ref(), r_shift.as_ref(), s2) else {
            continue;
        };
        // Newton's iteration on the equation as given, from this stabilising gain
        if let Some(sol) = newton(a2, c2, q2.as_ref(), r, s2, &start) {
            if sol.residual <= RESIDUAL_TOL {
                return Ok(back(sol, 0.0));
            }
            keep(back(sol, 0.0), &mut best);
        }
        let shifted = residual(a2, c2, q_shift.as_ref(), s2, &start);
        if rel <= MAX_KEPT_SHIFT && shifted <= RESIDUAL_TOL {
            return Ok(back(
                KalmanSolution {
                    residual: shifted,
                    ..start
                },
                rel,
            ));
        }
    }
    match best {
        Some(sol) if sol.residual <= LAST_RESORT_TOL => Ok(sol),
        _ => Err(SysidError::NoStabilizingSolution { reason: first }),
    }
}

/// Relative residual of the Riccati equation at a solution: `|P - A P A^T - Q + K (A P C^T +
/// S)^T|` over the larger of `|P|` and `|Q|` (entrywise maxima); NaN counts as failed.
fn residual(
    a: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    q: MatRef<'_, f64>,
    s: MatRef<'_, f64>,
    sol: &KalmanSolution,
) -> f64 {
    let p = &sol.p;
    let apct_s = a * p * c.transpose() + s;
    let resid = a * p * a.transpose() + q - &sol.k * apct_s.transpose() - p;
    let rel = resid.norm_max() / p.norm_max().max(q.norm_max());
    if rel.is_nan() {
        f64::INFINITY
    } else {
        rel
    }
}

/// Hewer's (Newton's) iteration from a stabilising gain: `P` from the Stein equation of the
/// predictor `A - K C` driven by `[I, -K] [[Q, S], [S^T, R]] [I, -K]^T`, then the gain of that
/// `P`; every iterate is stabilising and the convergence is quadratic near the solution. Stops
/// at a tenth of [`RESIDUAL_TOL`], after 50 steps, or when 8 steps in a row gained nothing
/// (the Stein solves' accuracy floor); returns the most accurate stabilising iterate, its
/// residual recorded, or `None` when there is none.
fn newton(
    a: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    q: MatRef<'_, f64>,
    r: MatRef<'_, f64>,
    s: MatRef<'_, f64>,
    start: &KalmanSolution,
) -> Option<KalmanSolution> {
    let mut k = start.k.clone();
    let mut best: Option<KalmanSolution> = None;
    let mut stalled = 0;
    for it in 0..50 {
        let f = a - &k * c;
        let ks = &k * s.transpose();
        let mut w = q - &ks - ks.transpose() + &k * r * k.transpose();
        symmetrize(&mut w);
        let Ok(mut p) = crate::lyapunov::solve_discrete_lyapunov(f.as_ref(), w.as_ref()) else {
            break;
        };
        symmetrize(&mut p);
        let Some((k_new, innov)) = gain_of(a, c, r, s, &p) else {
            break;
        };
        k = k_new;
        let mut sol = KalmanSolution {
            p,
            k: k.clone(),
            innovation_cov: innov,
            iterations: start.iterations + it + 1,
            regularization: 0.0,
            residual: f64::INFINITY,
        };
        sol.residual = residual(a, c, q, s, &sol);
        let stable = spectral_radius((a - &sol.k * c).as_ref()).is_ok_and(|rho| rho < 1.0);
        let done = sol.residual <= 0.1 * RESIDUAL_TOL;
        if stable && best.as_ref().is_none_or(|b| sol.residual < b.residual) {
            best = Some(sol);
            stalled = 0;
        } else {
            stalled += 1;
        }
        if done || stalled >= 8 {
            break;
        }
    }
    best
}

/// The gain `K = (A P C^T + S)(C P C^T + R)^{-1}` and innovation covariance `C P C^T + R` of a
/// state error covariance `P`; `None` when the innovation covariance is not positive definite.
fn gain_of(
    a: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    r: MatRef<'_, f64>,
    s: MatRef<'_, f64>,
    p: &Mat<f64>,
) -> Option<(Mat<f64>, Mat<f64>)> {
    let cp = c * p;
    let mut innov = &cp * c.transpose() + r;
    symmetrize(&mut innov);
    let apct_s = a * cp.transpose() + s; // A P C^T + S
    let llt = innov.llt(faer::Side::Lower).ok()?;
    let k = llt.solve(apct_s.transpose()).transpose().to_owned();
    Some((k, innov))
}

/// The doubling solve of [`kalman_gain`] for the covariances as given (checked for a stable
/// `A - K C`, not for accuracy: see [`residual`]).
fn doubling(
    a: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    q: MatRef<'_, f64>,
    r: MatRef<'_, f64>,
    s: MatRef<'_, f64>,
) -> Result<KalmanSolution> {
    let n = a.nrows();
    let l = c.nrows();
    let fail = |reason: String| SysidError::NoStabilizingSolution { reason };
    let checks: [(&'static str, MatRef<'_, f64>, usize, usize); 5] = [
        ("A", a, n, n),
        ("C", c, l, n),
        ("Q", q, n, n),
        ("R", r, l, l),
        ("S", s, n, l),
    ];
    for (what, m, rows, cols) in checks {
        if m.nrows() != rows || m.ncols() != cols {
            return Err(SysidError::ShapeMismatch {
                what: what.into(),
                expected: format!("({rows}, {cols})"),
                got: format!("({}, {})", m.nrows(), m.ncols()),
            });
        }
        crate::error::check_finite(what, m)?;
    }
    let r_llt = r
        .llt(faer::Side::Lower)
        .map_err(|_| fail("the output noise covariance R is not positive definite".into()))?;
    let rinv_c = r_llt.solve(c); // R^{-1} C
    let rinv_st = r_llt.solve(s.transpose()); // R^{-1} S^T
    let abar = a - s * &rinv_c; // A - S R^{-1} C
    let mut h = q - s * &rinv_st; // Q - S R^{-1} S^T
    symmetrize(&mut h);
    let mut g = c.transpose() * &rinv_c; // C^T R^{-1} C
    symmetrize(&mut g);
    // SDA in the "control" form with F = Ā^T
    let mut ak = abar.transpose().to_owned();
    let eye = Mat::<f64>::identity(n, n);
    let mut iterations = 0;
    let mut converged = n == 0;
    for it in 0..200 {
        iterations = it + 1;
        let w = &eye + &g * &h;
        let lu = w.partial_piv_lu();
        let winv_a = lu.solve(&ak); // W^{-1} A_k
        let winv_g = lu.solve(&g); // W^{-1} G_k
        let h_new = &h + ak.transpose() * &h * &winv_a;
        let g_new = &g + &ak * &winv_g * ak.transpose();
        let a_new = &ak * &winv_a;
        let diff = (&h_new - &h).norm_l2();
        let scale = h_new.norm_l2().max(1e-300);
        h = h_new;
        g = g_new;
        symmetrize(&mut h);
        symmetrize(&mut g);
        ak = a_new;
        if !h.norm_l2().is_finite() {
            return Err(fail("the doubling iteration diverged".into()));
        }
        if diff <= 1e-14 * scale || ak.norm_l2() < 1e-300 {
            converged = true;
            break;
        }
    }
    if !converged {
        return Err(fail(format!(
            "no convergence after {iterations} doubling steps"
        )));
    }
    let p = h;
    let (k, innov) = gain_of(a, c, r, s, &p).ok_or_else(|| {
        fail("the innovation covariance C P C^T + R is not positive definite".into())
    })?;
    let rho = spectral_radius((a - &k * c).as_ref())?;
    if rho.is_nan() || rho >= 1.0 {
        return Err(fail(format!(
            "the predictor A - K C has spectral radius {rho:.6} >= 1"
        )));
    }
    Ok(KalmanSolution {
        p,
        k,
        innovation_cov: innov,
        iterations,
        regularization: 0.0,
        residual: f64::NAN, // set by the caller, which knows the equation it checks against
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::mat;

    #[test]
    fn satisfies_the_riccati_equation_with_cross_term() {
        let a = mat![[0.9, 0.2, 0.0], [-0.1, 0.7, 0.3], [0.0, 0.0, 0.5]];
        let c = mat![[1.0, 0.0, 1.0], [0.0, 1.0, 0.5]];
        let q = mat![[0.5, 0.1, 0.0], [0.1, 0.3, 0.05], [0.0, 0.05, 0.2]];
        let r = mat![[0.4, 0.1], [0.1, 0.3]];
        let s = mat![[0.05, 0.0], [0.0, 0.02], [0.01, 0.01]];
        let sol = kalman_gain(a.as_ref(), c.as_ref(), q.as_ref(), r.as_ref(), s.as_ref()).unwrap();
        let p = &sol.p;
        let apct_s = &a * p * c.transpose() + &s;
        let rhs = &a * p * a.transpose() + &q - &sol.k * apct_s.transpose();
        assert!((p - &rhs).norm_max() < 1e-12 * p.norm_max());
        assert!(spectral_radius((&a - &sol.k * &c).as_ref()).unwrap() < 1.0);
    }

    #[test]
    fn mismatched_shapes_are_errors_not_panics() {
        let a = mat![[0.5, 0.0], [0.0, 0.5]];
        let q = mat![[1.0, 0.0], [0.0, 1.0]];
        let r = mat![[1.0]];
        let s = mat![[0.0], [0.0]];
        let c_bad = mat![[1.0, 0.0, 0.0]];
        assert!(matches!(
            kalman_gain(
                a.as_ref(),
                c_bad.as_ref(),
                q.as_ref(),
                r.as_ref(),
                s.as_ref()
            ),
            Err(SysidError::ShapeMismatch { .. })
        ));
        let a_bad = mat![[0.5, 0.0]];
        let c = mat![[1.0, 0.0]];
        assert!(matches!(
            kalman_gain(
                a_bad.as_ref(),
                c.as_ref(),
                q.as_ref(),
                r.as_ref(),
                s.as_ref()
            ),
            Err(SysidError::ShapeMismatch { .. })
        ));
    }

    #[test]
    fn unstable_undetectable_mode_has_no_stabilizing_solution() {
        // an unstable mode invisible in y: no gain can stabilise A - K C
        let a = mat![[1.5, 0.0], [0.0, 0.5]];
        let c = mat![[0.0, 1.0]];
        let q = mat![[1.0, 0.0], [0.0, 1.0]];
        let r = mat![[1.0]];
        let s = mat![[0.0], [0.0]];
        assert!(matches!(
            kalman_gain(a.as_ref(), c.as_ref(), q.as_ref(), r.as_ref(), s.as_ref()),
            Err(SysidError::NoStabilizingSolution { .. })
        ));
    }
    #[test]
    fn nearly_noise_free_outputs_get_the_stabilising_gain() {
        // CVA, order 4, on the Bouc-Wen benchmark's training record: R is 1e-10 of Q and the
        // joint covariance is indefinite at round-off (-1.6e-18), so the doubling fails
        let a = mat![
            [
                0.9306465979640784,
                -0.3819413696552773,
                -0.5542205222496118,
                0.4403342241573909
            ],
            [
                -0.1670236869251183,
                0.6116857306290382,
                -0.3438039179044026,
                0.06905865408421202
            ],
            [
                0.14382615621721798,
                -0.009052044135347867,
                0.7874432682660265,
                0.2656801550934242
            ],
            [
                -0.04207278694963504,
                0.828038812602137,
                0.4173718069110444,
                0.44300734833526734
            ]
        ];
        let c = mat![[
            0.03395344402986988,
            -0.04757180495104043,
            0.07781916888418859,
            0.020522972842843993
        ]];
        let q = mat![
            [
                0.0054294285887168375,
                0.0031282198825696387,
                0.0013761188469624732,
                -0.006848774965179783
            ],
            [
                0.0031282198825696387,
                0.0018044965299045424,
                0.0007942891305034826,
                -0.0039471412153836
            ],
            [
                0.0013761188469624732,
                0.0007942891305034826,
                0.00034973255890816097,
                -0.0017366255363409696
            ],
            [
                -0.006848774965179783,
                -0.0039471412153836,
                -0.0017366255363409696,
                0.008639781331375851
            ]
        ];
        let r = mat![[2.1682512811591514e-13]];
        let s = mat![
            [-3.226226922976675e-08],
            [-1.8356315528642772e-08],
            [-8.022770371772911e-09],
            [4.057155525727533e-08]
        ];
        // the doubling alone fails (or is inaccurate) in the given basis
        let plain = doubling(a.as_ref(), c.as_ref(), q.as_ref(), r.as_ref(), s.as_ref());
        assert!(plain.map_or(true, |p| {
            residual(a.as_ref(), c.as_ref(), q.as_ref(), s.as_ref(), &p) > 1e-9
        }));
        let sol = kalman_gain(a.as_ref(), c.as_ref(), q.as_ref(), r.as_ref(), s.as_ref()).unwrap();
        assert!(spectral_radius((&a - &sol.k * &c).as_ref()).unwrap() < 1.0);
        assert!(residual(a.as_ref(), c.as_ref(), q.as_ref(), s.as_ref(), &sol) < 1e-9);
        // SciPy's solve_discrete_are (generalised Schur vectors) on the same matrices
        let scipy = [
            -13.560457743887687,
            2.869462845898852,
            12.267614999304362,
            18.382485923023673,
        ];
        for (i, want) in scipy.iter().enumerate() {
            assert!(
                (sol.k[(i, 0)] - want).abs() < 1e-6 * 20.0,
                "{} {}",
                sol.k[(i, 0)],
                want
            );
        }
    }
}
