use faer::Mat;

use super::arx::{ArxCompressor, ArxOrders};
use super::filter::{filter, is_stable, monic};
use super::pem::{estimate, MisoOrders, MisoProblem};
use crate::optim::{Flow, Options, Problem};

pub(super) fn noise(n: usize, seed: u64) -> Vec<f64> {
    // Uniform(-0.5, 0.5) from a 64-bit LCG, summed twice for a smoother distribution.
    let mut s = seed
        .wrapping_mul(2862933555777941757)
        .wrapping_add(3037000493);
    (0..n)
        .map(|_| {
            let mut v = 0.0;
            for _ in 0..2 {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                v += (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            }
            v
        })
        .collect()
}

fn delay(x: &[f64], nk: usize) -> Vec<f64> {
    (0..x.len())
        .map(|t| if t >= nk { x[t - nk] } else { 0.0 })
        .collect()
}

fn close(a: &[f64], b: &[f64], tol: f64) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() < tol, "{a:?} vs {b:?}");
    }
}

#[test]
fn stability_test() {
    assert!(is_stable(&[1.0, -1.5, 0.7]));
    assert!(!is_stable(&[1.0, -1.5, 1.01]));
    assert!(!is_stable(&[1.0, 0.0, 0.0, 1.0]));
    assert!(is_stable(&[1.0]));
}

#[test]
fn siso_arx_noise_free() {
    let n = 400;
    let u = noise(n, 1);
    // (1 - 1.5 q^-1 + 0.7 q^-2) y = (1 + 0.5 q^-1) u(t-2)
    let y = filter(&[1.0, 0.5], &[1.0, -1.5, 0.7], &delay(&u, 2));
    let um = Mat::from_fn(n, 1, |t, _| u[t]);
    let ym = Mat::from_fn(n, 1, |t, _| y[t]);
    let mut c = ArxCompressor::new(1, 1, 6).unwrap();
    c.push(um.as_ref(), ym.as_ref()).unwrap();
    let o = ArxOrders {
        na: vec![vec![2]],
        nb: vec![vec![2]],
        nk: vec![vec![2]],
    };
    let fit = c.solve_output(0, &o, 0.0, None).unwrap();
    close(&fit.a[0], &[-1.5, 0.7], 1e-10);
    close(&fit.b[0], &[1.0, 0.5], 1e-10);
    assert!(fit.loss < 1e-20);
    // arxstruc: the true structure has (near) zero loss, a smaller one does not.
    let table = c.arxstruc(&[1, 2], &[1, 2], &[1, 2]).unwrap();
    let best = table
        .iter()
        .find(|r| r[0] == 2.0 && r[1] == 2.0 && r[2] == 2.0)
        .unwrap();
    let small = table
        .iter()
        .find(|r| r[0] == 1.0 && r[1] == 1.0 && r[2] == 1.0)
        .unwrap();
    assert!(best[3] < 1e-20 && small[3] > 1e-3);
    // Ridge shrinks the estimate.
    let ridge = c.solve_output(0, &o, 100.0, None).unwrap();
    assert!((ridge.b[0][0] - 1.0).abs() > 1e-3);
}

#[test]
fn mimo_arx_noise_free_with_cross_terms() {
    let n = 600;
    let u1 = noise(n, 2);
    let u2 = noise(n, 3);
    let mut y1 = vec![0.0; n];
    let mut y2 = vec![0.0; n];
    for t in 2..n {
        y1[t] = 0.6 * y1[t - 1] - 0.2 * y2[t - 1] + 1.0 * u1[t - 1] + 0.3 * u2[t - 2];
        y2[t] =
            0.1 * y1[t - 1] + 0.5 * y2[t - 1] - 0.1 * y2[t - 2] + 0.7 * u2[t - 1] - 0.4 * u1[t - 1];
    }
    let um = Mat::from_fn(n, 2, |t, j| if j == 0 { u1[t] } else { u2[t] });
    let ym = Mat::from_fn(n, 2, |t, j| if j == 0 { y1[t] } else { y2[t] });
    let mut c = ArxCompressor::new(2, 2, 3).unwrap();
    // Two experiments: halves of the record, each with its own start-up rows dropped.
    c.push(um.as_ref().subrows(0, 300), ym.as_ref().subrows(0, 300))
        .unwrap();
    c.push(um.as_ref().subrows(300, 300), ym.as_ref().subrows(300, 300))
        .unwrap();
    let o = ArxOrders {
        na: vec![vec![1, 1], vec![1, 2]],
        nb: vec![vec![1, 1], vec![1, 1]],
        nk: vec![vec![1, 2], vec![1, 1]],
    };
    let f0 = c.solve_output(0, &o, 0.0, None).unwrap();
    close(&f0.a[0], &[-0.6], 1e-10);
    close(&f0.a[1], &[0.2], 1e-10);
    close(&f0.b[0], &[1.0], 1e-10);
    close(&f0.b[1], &[0.3], 1e-10);
    let f1 = c.solve_output(1, &o, 0.0, None).unwrap();
    close(&f1.a[0], &[-0.1], 1e-10);
    close(&f1.a[1], &[-0.5, 0.1], 1e-10);
    close(&f1.b[0], &[-0.4], 1e-10);
    close(&f1.b[1], &[0.7], 1e-10);
}

fn siso(nb: usize, nc: usize, nd: usize, nf: usize, na: usize, nk: usize) -> MisoOrders {
    MisoOrders {
        na,
        nb: vec![nb],
        nc,
        nd,
        nf: vec![nf],
        nk: vec![nk],
    }
}

#[test]
fn siso_oe_armax_bj_noise_free() {
    let n = 500;
    let u = noise(n, 4);
    let um = Mat::from_fn(n, 1, |t, _| u[t]);
    let obs = &mut |_: &crate::optim::Iteration| Flow::Continue;
    // OE: y = (0.5 + 0.3 q^-1)/(1 - 1.2 q^-1 + 0.5 q^-2) u(t-1)
    let y = filter(&[0.5, 0.3], &[1.0, -1.2, 0.5], &delay(&u, 1));
    let est = estimate(
        &y,
        um.as_ref(),
        siso(2, 0, 0, 2, 0, 1),
        None,
        &Options::default(),
        obs,
    )
    .unwrap();
    close(&est.solution.theta, &[0.5, 0.3, -1.2, 0.5], 1e-8);
    // ARMAX deterministic part (no noise): A y = B u.
    let y = filter(&[0.8], &[1.0, -0.7], &delay(&u, 1));
    let est = estimate(
        &y,
        um.as_ref(),
        siso(1, 1, 0, 0, 1, 1),
        None,
        &Options::default(),
        obs,
    )
    .unwrap();
    close(&est.solution.theta[..2], &[-0.7, 0.8], 1e-8);
    // BJ deterministic part.
    let y = filter(&[1.0, 0.3], &[1.0, -0.9, 0.2], &delay(&u, 2));
    let est = estimate(
        &y,
        um.as_ref(),
        siso(2, 1, 1, 2, 0, 2),
        None,
        &Options::default(),
        obs,
    )
    .unwrap();
    close(&est.solution.theta[..2], &[1.0, 0.3], 1e-8);
    close(&est.solution.theta[4..], &[-0.9, 0.2], 1e-8);
}

#[test]
fn two_by_two_oe_noise_free() {
    // Each output: y_i = B_i1/F_i1 u_1 + B_i2/F_i2 u_2 (MISO per output).
    let n = 800;
    let u1 = noise(n, 5);
    let u2 = noise(n, 6);
    let um = Mat::from_fn(n, 2, |t, j| if j == 0 { u1[t] } else { u2[t] });
    let truth = [[(1.0, -0.5), (0.4, -0.3)], [(-0.6, 0.2), (0.9, -0.7)]];
    for row in truth {
        let w1 = filter(&[row[0].0], &[1.0, row[0].1], &delay(&u1, 1));
        let w2 = filter(&[row[1].0], &[1.0, row[1].1], &delay(&u2, 1));
        let y: Vec<f64> = w1.iter().zip(&w2).map(|(a, b)| a + b).collect();
        let o = MisoOrders {
            na: 0,
            nb: vec![1, 1],
            nc: 0,
            nd: 0,
            nf: vec![1, 1],
            nk: vec![1, 1],
        };
        let est = estimate(&y, um.as_ref(), o, None, &Options::default(), &mut |_| {
            Flow::Continue
        })
        .unwrap();
        close(
            &est.solution.theta,
            &[row[0].0, row[1].0, row[0].1, row[1].1],
            1e-8,
        );
    }
}

#[test]
fn jacobian_matches_finite_differences() {
    let n = 300;
    let u = noise(n, 7);
    let e = noise(n, 8);
    let um = Mat::from_fn(n, 1, |t, _| u[t]);
    let w = filter(&[1.0, 0.5], &[1.0, -0.6], &delay(&u, 1));
    let v = filter(&[1.0, 0.4], &[1.0, -0.3], &e);
    let y: Vec<f64> = w.iter().zip(&v).map(|(a, b)| a + b).collect();
    let o = MisoOrders {
        na: 1,
        nb: vec![2],
        nc: 1,
        nd: 1,
        nf: vec![1],
        nk: vec![1],
    };
    let mut p = MisoProblem::new(&y, um.as_ref(), o).unwrap();
    let th = [0.1, 0.9, 0.4, 0.3, -0.2, -0.5];
    let ev = p.evaluate(&th, true).unwrap();
    for k in 0..th.len() {
        let h = 1e-6;
        let mut tp = th;
        tp[k] += h;
        let mut tm = th;
        tm[k] -= h;
        let g = (p.evaluate(&tp, false).unwrap().cost - p.evaluate(&tm, false).unwrap().cost)
            / (2.0 * h);
        assert!(
            (g - ev.gradient[k]).abs() < 1e-5 * (1.0 + g.abs()),
            "{k}: {g} vs {}",
            ev.gradient[k]
        );
    }
    assert!(!p.admissible(&[0.0, 0.0, 0.0, 1.2, 0.0, 0.0]));
    assert!(monic(&[0.5]) == vec![1.0, 0.5]);
}

#[test]
fn armax_with_noise_is_consistent() {
    let n = 4000;
    let u = noise(n, 9);
    let e: Vec<f64> = noise(n, 10).iter().map(|v| 0.3 * v).collect();
    let um = Mat::from_fn(n, 1, |t, _| u[t]);
    // (1 - 0.7 q^-1) y = 0.8 u(t-1) + (1 + 0.5 q^-1) e
    let mut y = vec![0.0; n];
    for t in 1..n {
        y[t] = 0.7 * y[t - 1] + 0.8 * u[t - 1] + e[t] + 0.5 * e[t - 1];
    }
    let est = estimate(
        &y,
        um.as_ref(),
        siso(1, 1, 0, 0, 1, 1),
        None,
        &Options::default(),
        &mut |_| Flow::Continue,
    )
    .unwrap();
    let th = &est.solution.theta;
    let truth = [-0.7, 0.8, 0.5];
    for k in 0..3 {
        let sd = est.covariance[(k, k)].sqrt();
        assert!(
            (th[k] - truth[k]).abs() < 4.0 * sd,
            "{k}: {} vs {} (sd {sd})",
            th[k],
            truth[k]
        );
        assert!(sd < 0.05);
    }
}

#[test]
fn iv4_noise_free_and_colored_noise() {
    let n = 3000;
    let u = noise(n, 30);
    let y0 = filter(&[1.0, 0.5], &[1.0, -1.5, 0.7], &delay(&u, 1));
    let th = super::iv::iv4(&y0, &u, 2, 2, 1, None).unwrap();
    close(&th, &[-1.5, 0.7, 1.0, 0.5], 1e-8);
    // Coloured output noise: least squares is biased, IV4 is not.
    let v = filter(&[1.0], &[1.0, -0.9], &noise(n, 31));
    let y: Vec<f64> = y0.iter().zip(&v).map(|(a, b)| a + 0.5 * b).collect();
    let th = super::iv::iv4(&y, &u, 2, 2, 1, None).unwrap();
    close(&th, &[-1.5, 0.7, 1.0, 0.5], 0.05);
    // Reference as instrument gives the same answer on open-loop data (r = u).
    let thr = super::iv::iv4(&y, &u, 2, 2, 1, Some(&u)).unwrap();
    close(&thr, &[-1.5, 0.7, 1.0, 0.5], 0.05);
}

#[test]
fn multi_experiment_cost_is_the_sum_and_recovers_noise_free() {
    // Two OE records of different lengths, each from rest: the multi-experiment problem's
    // cost, gradient and J^T J are the sums of the single-experiment ones.
    let (n1, n2) = (300, 170);
    let u1 = noise(n1, 51);
    let u2 = noise(n2, 52);
    let sim = |u: &[f64]| filter(&[0.5, 0.3], &[1.0, -1.2, 0.5], &delay(u, 1));
    let (y1, y2) = (sim(&u1), sim(&u2));
    let m1 = Mat::from_fn(n1, 1, |t, _| u1[t]);
    let m2 = Mat::from_fn(n2, 1, |t, _| u2[t]);
    let o = siso(2, 0, 0, 2, 0, 1);
    let th = [0.4, 0.2, -1.0, 0.4];
    let mut p1 = MisoProblem::new(&y1, m1.as_ref(), o.clone()).unwrap();
    let mut p2 = MisoProblem::new(&y2, m2.as_ref(), o.clone()).unwrap();
    let exps = [(&y1[..], m1.as_ref()), (&y2[..], m2.as_ref())];
    let mut pm = MisoProblem::new_multi(&exps, o.clone()).unwrap();
    let (e1, e2, em) = (
        p1.evaluate(&th, true).unwrap(),
        p2.evaluate(&th, true).unwrap(),
        pm.evaluate(&th, true).unwrap(),
    );
    assert!((em.cost - e1.cost - e2.cost).abs() < 1e-10 * em.cost);
    for a in 0..4 {
        assert!((em.gradient[a] - e1.gradient[a] - e2.gradient[a]).abs() < 1e-9);
        for b in 0..4 {
            let s = e1.gauss_newton[(a, b)] + e2.gauss_newton[(a, b)];
            assert!((em.gauss_newton[(a, b)] - s).abs() < 1e-9 * (1.0 + s.abs()));
        }
    }
    // Noise-free recovery from the two records (OE, then ARMAX and BJ structures).
    let est =
        super::pem::estimate_multi(&exps, o, None, &Options::default(), &mut |_| Flow::Continue)
            .unwrap();
    close(&est.solution.theta, &[0.5, 0.3, -1.2, 0.5], 1e-8);
    let ya = |u: &[f64]| filter(&[0.8, 0.2], &[1.0, -0.7], &delay(u, 2));
    let (ya1, ya2) = (ya(&u1), ya(&u2));
    let exps = [(&ya1[..], m1.as_ref()), (&ya2[..], m2.as_ref())];
    for o in [siso(2, 1, 0, 0, 1, 2), siso(2, 1, 1, 1, 0, 2)] {
        let est =
            super::pem::estimate_multi(&exps, o.clone(), None, &Options::default(), &mut |_| {
                Flow::Continue
            })
            .unwrap();
        let want: Vec<f64> = if o.na == 1 {
            vec![-0.7, 0.8, 0.2, 0.0]
        } else {
            vec![0.8, 0.2, 0.0, 0.0, -0.7]
        };
        let th = &est.solution.theta;
        // the noise-model parameters are not identifiable from noise-free data: compare A/B/F
        let keep: Vec<usize> = if o.na == 1 {
            vec![0, 1, 2]
        } else {
            vec![0, 1, 4]
        };
        for k in keep {
            assert!((th[k] - want[k]).abs() < 1e-8, "{o:?}: {th:?}");
        }
    }
}

#[test]
fn iv4_mimo_two_experiments_noise_free() {
    // 2 x 2 ARX with cross terms in A, two records each from rest.
    let o = ArxOrders {
        na: vec![vec![1, 1], vec![1, 1]],
        nb: vec![vec![1, 1], vec![1, 1]],
        nk: vec![vec![1, 2], vec![1, 1]],
    };
    let sim = |n: usize, s: u64| {
        // from rest: the loop below starts at t = 2, so the first inputs are zero
        let u = Mat::from_fn(n, 2, |t, j| {
            if t < 2 {
                0.0
            } else {
                noise(n, s + j as u64)[t]
            }
        });
        let mut y = Mat::<f64>::zeros(n, 2);
        for t in 2..n {
            y[(t, 0)] =
                0.6 * y[(t - 1, 0)] - 0.2 * y[(t - 1, 1)] + u[(t - 1, 0)] + 0.3 * u[(t - 2, 1)];
            y[(t, 1)] = 0.1 * y[(t - 1, 0)] + 0.5 * y[(t - 1, 1)] + 0.7 * u[(t - 1, 1)]
                - 0.4 * u[(t - 1, 0)];
        }
        (u, y)
    };
    let (ua, ya) = sim(400, 60);
    let (ub, yb) = sim(250, 70);
    let recs = [
        super::iv::IvRecord {
            u: ua.as_ref(),
            y: ya.as_ref(),
            r: None,
        },
        super::iv::IvRecord {
            u: ub.as_ref(),
            y: yb.as_ref(),
            r: None,
        },
    ];
    let fit = super::iv::iv4_multi(&recs, &o).unwrap();
    close(&fit.theta[0], &[-0.6, 0.2, 1.0, 0.3], 1e-8);
    close(&fit.theta[1], &[-0.1, -0.5, -0.4, 0.7], 1e-8);
}

#[test]
fn output_summary_reproduces_least_squares_and_sums() {
    let n = 300;
    let u = noise(n, 21);
    let e = noise(n, 22);
    let y0 = filter(&[1.0, 0.5], &[1.0, -1.2, 0.5], &delay(&u, 1));
    let y: Vec<f64> = y0.iter().zip(&e).map(|(a, b)| a + 0.1 * b).collect();
    let um = Mat::from_fn(n, 1, |t, _| u[t]);
    let ym = Mat::from_fn(n, 1, |t, _| y[t]);
    let mut c = ArxCompressor::new(1, 1, 4).unwrap();
    c.push(um.as_ref(), ym.as_ref()).unwrap();
    let o = ArxOrders {
        na: vec![vec![2]],
        nb: vec![vec![2]],
        nk: vec![vec![1]],
    };
    let r = c.factor();
    let s = c.output_summary(r.as_ref(), 0, &o).unwrap();
    let fit = c.solve_with_factor(r.as_ref(), 0, &o, 0.0, None).unwrap();
    // back substitution on the summary gives the least-squares parameters (regression signs)
    let p = 4;
    let mut th = vec![0.0; p];
    for d in (0..p).rev() {
        let mut v = s[(d, p)];
        for k in d + 1..p {
            v -= s[(d, k)] * th[k];
        }
        th[d] = v / s[(d, d)];
    }
    let poly: Vec<f64> = th
        .iter()
        .enumerate()
        .map(|(k, v)| if k < 2 { -v } else { *v })
        .collect();
    close(&poly, &fit.theta, 1e-10);
    // rho^2 / rows is the least-squares loss
    assert!((s[(p, p)].powi(2) / fit.n_rows as f64 - fit.loss).abs() < 1e-12);
    assert!(c.output_summary(r.as_ref(), 1, &o).is_err());
}

#[test]
fn matrix_filter_simulates_and_predicts_a_coupled_model() {
    use super::filter::arx_matrix_filter;
    let n = 50;
    let a = vec![
        vec![vec![-0.5], vec![0.2, 0.1]],
        vec![vec![0.1], vec![-0.3]],
    ];
    let w = Mat::from_fn(n, 2, |t, i| noise(2 * n, 31)[2 * t + i]);
    let y = arx_matrix_filter(&a, w.as_ref(), None).unwrap();
    for t in 2..n {
        let y0 = w[(t, 0)] + 0.5 * y[(t - 1, 0)] - 0.2 * y[(t - 1, 1)] - 0.1 * y[(t - 2, 1)];
        let y1 = w[(t, 1)] - 0.1 * y[(t - 1, 0)] + 0.3 * y[(t - 1, 1)];
        assert!((y[(t, 0)] - y0).abs() < 1e-13 && (y[(t, 1)] - y1).abs() < 1e-13);
    }
    // the measured record of the model itself: every horizon predicts it exactly
    for k in [1, 2, 5, 100] {
        let p = arx_matrix_filter(&a, w.as_ref(), Some((y.as_ref(), k))).unwrap();
        for t in 0..n {
            assert!((p[(t, 0)] - y[(t, 0)]).abs() < 1e-12);
        }
    }
    assert!(arx_matrix_filter(&a[..1], w.as_ref(), None).is_err());
    let short = Mat::<f64>::zeros(n - 1, 2);
    assert!(arx_matrix_filter(&a, w.as_ref(), Some((short.as_ref(), 1))).is_err());
    assert!(arx_matrix_filter(&a, w.as_ref(), Some((y.as_ref(), 0))).is_err());
}

#[test]
fn marginal_likelihood_matches_dense_and_finite_differences() {
    use super::regul::marginal_likelihood;
    // Phi (n x 2), y: dense -2 log p(y) - n log 2 pi against the summary formula.
    let n = 12;
    let e = noise(3 * n, 41);
    let phi = Mat::from_fn(n, 2, |t, j| e[2 * t + j]);
    let y = Mat::from_fn(n, 1, |t, _| e[2 * n + t] + 0.5 * phi[(t, 0)]);
    let z = Mat::from_fn(n, 3, |t, j| if j < 2 { phi[(t, j)] } else { y[(t, 0)] });
    let s = z.qr().thin_R().to_owned();
    let prior = |c: f64| Mat::from_fn(2, 2, |i, j| c * 0.7f64.powi(i.max(j) as i32 + 1));
    let sigma2 = 0.3;
    let dense = |c: f64, s2: f64| {
        let mut sig = &phi * prior(c) * phi.transpose();
        for i in 0..n {
            sig[(i, i)] += s2;
        }
        let llt = sig.llt(faer::Side::Lower).unwrap();
        let a = faer::linalg::solvers::Solve::solve(&llt, &y);
        let quad: f64 = (0..n).map(|i| y[(i, 0)] * a[(i, 0)]).sum();
        let ld: f64 = (0..n).map(|i| 2.0 * llt.L()[(i, i)].ln()).sum();
        quad + ld
    };
    let dp = prior(1.0);
    let (v, g, ds) = marginal_likelihood(
        s.as_ref(),
        n,
        prior(2.0).as_ref(),
        &[dp.as_ref()],
        sigma2,
        true,
    )
    .unwrap();
    assert!((v - dense(2.0, sigma2)).abs() < 1e-10 * v.abs().max(1.0));
    let h = 1e-6;
    let fd = (dense(2.0 + h, sigma2) - dense(2.0 - h, sigma2)) / (2.0 * h);
    assert!(
        (g[0] - fd).abs() < 1e-6 * fd.abs().max(1.0),
        "{} vs {fd}",
        g[0]
    );
    let fds = (dense(2.0, sigma2 + h) - dense(2.0, sigma2 - h)) / (2.0 * h);
    assert!(
        (ds - fds).abs() < 1e-6 * fds.abs().max(1.0),
        "{ds} vs {fds}"
    );
    let (v2, g2, _) =
        marginal_likelihood(s.as_ref(), n, prior(2.0).as_ref(), &[], sigma2, false).unwrap();
    assert!(v2 == v && g2.is_empty());
    assert!(marginal_likelihood(s.as_ref(), n, dp.as_ref(), &[], -1.0, true).is_err());
    assert!(marginal_likelihood(s.as_ref(), 2, dp.as_ref(), &[], 1.0, true).is_err());
}

#[test]
fn regularized_solve_tends_to_least_squares_and_matches_the_normal_equations() {
    use super::regul::regularized_solve;
    let n = 40;
    let e = noise(4 * n, 51);
    let z = Mat::from_fn(n, 4, |t, j| e[4 * t + j]);
    let s = z.qr().thin_R().to_owned();
    let p = 3;
    let prior = Mat::from_fn(p, p, |i, j| 0.8f64.powi(i.max(j) as i32 + 1));
    // lam -> 0: least squares R1^-1 r
    let (th0, _, rss0) = regularized_solve(s.as_ref(), prior.as_ref(), 0.0).unwrap();
    let mut ls = vec![0.0; p];
    for d in (0..p).rev() {
        let mut v = s[(d, p)];
        for k in d + 1..p {
            v -= s[(d, k)] * ls[k];
        }
        ls[d] = v / s[(d, d)];
    }
    close(&th0, &ls, 1e-10);
    assert!((rss0 - s[(p, p)].powi(2)).abs() < 1e-10);
    // lam > 0: (R1^T R1 + lam P^-1) theta = R1^T r
    let lam = 0.7;
    let (th, cov, _) = regularized_solve(s.as_ref(), prior.as_ref(), lam).unwrap();
    let r1 = s.submatrix(0, 0, p, p);
    let pinv = prior.as_ref().llt(faer::Side::Lower).unwrap();
    let pi = faer::linalg::solvers::Solve::solve(&pinv, Mat::<f64>::identity(p, p));
    let a = r1.transpose() * r1 + Mat::from_fn(p, p, |i, j| lam * pi[(i, j)]);
    let rhs = r1.transpose() * s.submatrix(0, p, p, 1);
    let thm = Mat::from_fn(p, 1, |i, _| th[i]);
    let res = &a * &thm - &rhs;
    for i in 0..p {
        assert!(res[(i, 0)].abs() < 1e-9);
    }
    // covariance = lam (R1^T R1 + lam P^-1)^-1
    let prod = &a * &cov;
    for i in 0..p {
        for j in 0..p {
            let want = if i == j { lam } else { 0.0 };
            assert!((prod[(i, j)] - want).abs() < 1e-9);
        }
    }
    assert!(regularized_solve(s.as_ref(), prior.as_ref(), -1.0).is_err());
}

#[test]
fn regularized_solve_without_penalty_is_finite_on_a_rank_deficient_regression() {
    // noise-free data from a first-order system fitted with two a and two b coefficients:
    // a column of the regression is a combination of the others (a zero singular value);
    // lam = 0 returned NaN (0 / 0) there, which arxregul's start then carried
    use super::regul::regularized_solve;
    let n = 60;
    let u = noise(n, 7);
    let mut y = vec![0.0; n];
    for t in 1..n {
        y[t] = 0.5 * y[t - 1] + u[t - 1];
    }
    // columns -y(t-1), -y(t-2), u(t-1), u(t-2), then y(t)
    let z = Mat::from_fn(n - 2, 5, |r, j| {
        let t = r + 2;
        [-y[t - 1], -y[t - 2], u[t - 1], u[t - 2], y[t]][j]
    });
    let s = z.qr().thin_R().to_owned();
    let prior = Mat::<f64>::identity(4, 4);
    let (th, cov, rss) = regularized_solve(s.as_ref(), prior.as_ref(), 0.0).unwrap();
    assert!(th.iter().chain(cov.col_as_slice(0)).all(|v| v.is_finite()) && rss.is_finite());
    // the fit is exact: the residual is round-off, and theta reproduces y(t)
    assert!(rss < 1e-18 * y.iter().map(|v| v * v).sum::<f64>());
    for t in 2..n {
        let yh = -th[0] * y[t - 1] - th[1] * y[t - 2] + th[2] * u[t - 1] + th[3] * u[t - 2];
        assert!((yh - y[t]).abs() < 1e-9);
    }
}

#[test]
fn marginal_likelihood_holds_where_the_formed_covariance_is_indefinite() {
    use super::regul::{marginal_likelihood, solve_s, spectral_s};
    // a band-limited input with many lags: nearly collinear columns, a prior far above the
    // noise variance (as the Bouc-Wen record gave at 25 lags: R1 P R1^T up to 3e12 against
    // sigma2 = 2.4e-10, every start point "not finite")
    let n = 400;
    let e = noise(2 * n, 7);
    let base: Vec<f64> = (0..n + 8)
        .map(|t| (0.05 * t as f64).sin() + 0.3 * (0.11 * t as f64).sin())
        .collect();
    let p = 8;
    let phi = Mat::from_fn(n, p, |t, j| base[t + j] + 1e-8 * e[(7 * t + 13 * j) % n]);
    let y = Mat::from_fn(n, 1, |t, _| {
        phi[(t, 0)] - 0.5 * phi[(t, 3)] + 1e-3 * e[n + t]
    });
    let z = Mat::from_fn(n, p + 1, |t, j| if j < p { phi[(t, j)] } else { y[(t, 0)] });
    let tri = z.qr().thin_R().to_owned();
    // any orthogonal compression of the rows is a summary: a rotation mixes the
    // near-null directions into every row, where round-off in R1 P R1^T is no longer small
    let q = Mat::from_fn(p, p, |i, j| e[(7 * i + 3 * j) % n])
        .qr()
        .compute_Q();
    let s = Mat::from_fn(p + 1, p + 1, |i, j| {
        if i < p {
            (0..p).map(|k| q[(i, k)] * tri[(k, j)]).sum()
        } else {
            tri[(i, j)]
        }
    });
    let prior = |c: f64| Mat::from_fn(p, p, |i, j| c * 0.9f64.powi(i.max(j) as i32 + 1));
    let (r1, r) = (s.submatrix(0, 0, p, p), s.submatrix(0, p, p, 1));
    let sigma2 = 1e-8;
    let big = prior(1e10);
    let mut formed = r1 * &big * r1.transpose();
    for i in 0..p {
        formed[(i, i)] += sigma2;
    }
    assert!(
        formed.llt(faer::Side::Lower).is_err(),
        "the case must need the fallback"
    );
    let dp = prior(1.0);
    let (v, g, _) =
        marginal_likelihood(s.as_ref(), n, big.as_ref(), &[dp.as_ref()], sigma2, true).unwrap();
    assert!(v.is_finite() && g[0].is_finite());
    // its gradient agrees with its values (one smooth function, not a patchwork; the
    // central difference itself is good to about 5e-4 here: mpmath agrees with g to 1e-6)
    let h = 1e-4 * 1e10;
    let val = |c: f64| {
        marginal_likelihood(s.as_ref(), n, prior(c).as_ref(), &[], sigma2, false)
            .unwrap()
            .0
    };
    let fd = (val(1e10 + h) - val(1e10 - h)) / (2.0 * h);
    assert!((g[0] - fd).abs() < 2e-3 * fd.abs(), "{} vs {fd}", g[0]);
    // on a well-conditioned case the spectral route equals the Cholesky route
    let small = prior(1.0);
    let chol = solve_s(r1, small.as_ref(), r, 0.5, true).unwrap();
    let spec = spectral_s(r1, small.as_ref(), r, 0.5, true).unwrap();
    assert!((chol.logdet - spec.logdet).abs() < 1e-10 * chol.logdet.abs().max(1.0));
    for i in 0..p {
        assert!((chol.a[(i, 0)] - spec.a[(i, 0)]).abs() < 1e-10 * chol.a[(i, 0)].abs().max(1.0));
        let ((cg, ct), (sg, st)) = (
            chol.gradient.as_ref().unwrap(),
            spec.gradient.as_ref().unwrap(),
        );
        assert!((ct - st).abs() < 1e-10 * ct.abs().max(1.0));
        for j in 0..p {
            assert!((cg[(i, j)] - sg[(i, j)]).abs() < 1e-10 * cg[(i, j)].abs().max(1.0));
        }
    }
}

#[test]
fn iv4_rank_loss_is_a_regressor_rank_error_that_names_iv4() {
    // a constant input cannot determine b_0..b_3: the error names the estimator and the fix,
    // not a subspace horizon (the message it gave before)
    let n = 500;
    let u = vec![1.0; n];
    let mut y = vec![0.0; n];
    for t in 1..n {
        y[t] = 0.5 * y[t - 1] + u[t - 1] + 0.1 * ((t * 7919 % 13) as f64 - 6.0);
    }
    match super::iv::iv4(&y, &u, 2, 4, 1, None) {
        Err(crate::error::SysidError::RegressorRank {
            estimator, columns, ..
        }) => assert!(estimator == "iv4" && columns == 6),
        other => panic!("expected a regressor rank error, got {other:?}"),
    }
}
