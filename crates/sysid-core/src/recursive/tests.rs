use super::*;
use faer::prelude::Solve;

fn noise(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
}

/// The single-input structure of orders `[na, nb, nc, nd, nf, nk]`.
fn siso(na: usize, nb: usize, nc: usize, nd: usize, nf: usize, nk: usize) -> Structure {
    Structure {
        na,
        nb: vec![nb],
        nc,
        nd,
        nf: vec![nf],
        nk: vec![nk],
    }
}

fn arx_structure() -> Structure {
    siso(2, 2, 0, 0, 0, 1)
}

/// ARX(2, 2, 1) data: y = 1.5 y1 - 0.7 y2 + u1 + 0.5 u2 + 0.1 e.
fn arx_data(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut seed = 3;
    let u: Vec<f64> = (0..n).map(|_| noise(&mut seed)).collect();
    let mut y = vec![0.0; n];
    for t in 0..n {
        let g = |k: usize, v: &Vec<f64>| if t >= k { v[t - k] } else { 0.0 };
        y[t] = 1.5 * g(1, &y) - 0.7 * g(2, &y) + g(1, &u) + 0.5 * g(2, &u) + 0.1 * noise(&mut seed);
    }
    (u, y)
}

#[test]
fn rls_equals_regularised_least_squares() {
    // with lambda = 1, theta0 = 0 and P0 = p0 I, RLS is exactly the minimiser of
    // |Y - Phi theta|^2 + |theta|^2 / p0
    let (u, y) = arx_data(300);
    let p0 = 10.0;
    let mut est = Recursive::new(
        arx_structure(),
        Method::Forgetting { lambda: 1.0 },
        None,
        Some(p0),
    )
    .unwrap();
    let mut yhat = vec![0.0; 300];
    est.run(&u, &y, &mut yhat, None, 64, &mut || false).unwrap();
    let mut g = faer::Mat::<f64>::identity(4, 4) * faer::Scale(1.0 / p0);
    let mut rhs = faer::Mat::<f64>::zeros(4, 1);
    for t in 0..300 {
        let at = |k: usize, v: &Vec<f64>| if t >= k { v[t - k] } else { 0.0 };
        let phi = [-at(1, &y), -at(2, &y), at(1, &u), at(2, &u)];
        for i in 0..4 {
            rhs[(i, 0)] += phi[i] * y[t];
            for j in 0..4 {
                g[(i, j)] += phi[i] * phi[j];
            }
        }
    }
    let th = g.full_piv_lu().solve(&rhs);
    for i in 0..4 {
        assert!(
            (est.theta()[i] - th[(i, 0)]).abs() < 1e-10,
            "{:?}",
            est.theta()
        );
    }
}

#[test]
fn step_and_run_are_bit_identical() {
    let (u, y) = arx_data(200);
    for method in [
        Method::Forgetting { lambda: 0.98 },
        Method::Kalman {
            r1: (0..49)
                .map(|i| if i % 8 == 0 { 0.01 } else { 0.0 })
                .collect(),
            r2: 0.5,
        },
        Method::NormalizedGradient {
            gamma: 0.5,
            bias: 1e-6,
        },
        Method::Gradient { gamma: 0.1 },
    ] {
        let s = siso(2, 2, 1, 1, 1, 0);
        let mut a = Recursive::new(s.clone(), method.clone(), None, None).unwrap();
        let mut b = a.clone();
        let mut ya = vec![0.0; 200];
        a.run(&u, &y, &mut ya, None, 7, &mut || false).unwrap();
        for t in 0..200 {
            let yh = b.step(&u[t..t + 1], y[t]).unwrap();
            assert_eq!(yh.to_bits(), ya[t].to_bits());
        }
        assert_eq!(a.theta(), b.theta());
        assert_eq!(a.covariance(), b.covariance());
    }
}

#[test]
fn armax_and_oe_converge() {
    let n = 20000;
    let mut seed = 11;
    let u: Vec<f64> = (0..n).map(|_| noise(&mut seed)).collect();
    let e: Vec<f64> = (0..n).map(|_| 0.3 * noise(&mut seed)).collect();
    // ARMAX: y = 0.8 y1 + u1 + e + 0.5 e1
    let mut y = vec![0.0; n];
    for t in 1..n {
        y[t] = 0.8 * y[t - 1] + u[t - 1] + e[t] + 0.5 * e[t - 1];
    }
    let s = siso(1, 1, 1, 0, 0, 1);
    let mut est = Recursive::new(s, Method::Forgetting { lambda: 1.0 }, None, None).unwrap();
    let mut yh = vec![0.0; n];
    est.run(&u, &y, &mut yh, None, 1024, &mut || false).unwrap();
    let th = est.theta();
    assert!(
        (th[0] + 0.8).abs() < 0.02 && (th[1] - 1.0).abs() < 0.02 && (th[2] - 0.5).abs() < 0.05,
        "{th:?}"
    );
    // OE: y = u1 / (1 - 0.7 q^-1) + e
    let mut x = vec![0.0; n];
    for t in 1..n {
        x[t] = 0.7 * x[t - 1] + u[t - 1];
    }
    let y: Vec<f64> = x.iter().zip(&e).map(|(a, b)| a + b).collect();
    let s = siso(0, 1, 0, 0, 1, 1);
    let mut est = Recursive::new(s, Method::Forgetting { lambda: 1.0 }, None, None).unwrap();
    est.run(&u, &y, &mut yh, None, 1024, &mut || false).unwrap();
    let th = est.theta();
    assert!(
        (th[0] - 1.0).abs() < 0.03 && (th[1] + 0.7).abs() < 0.02,
        "{th:?}"
    );
}

#[test]
fn bad_settings_are_refused() {
    assert!(Recursive::new(
        arx_structure(),
        Method::Forgetting { lambda: 1.5 },
        None,
        None
    )
    .is_err());
    assert!(Recursive::new(
        arx_structure(),
        Method::Forgetting { lambda: 1.0 },
        None,
        Some(-1.0)
    )
    .is_err());
    let mut est = Recursive::new(
        arx_structure(),
        Method::Forgetting { lambda: 1.0 },
        None,
        None,
    )
    .unwrap();
    assert!(est.step(&[f64::NAN], 1.0).is_err());
    assert!(est.step(&[1.0, 2.0], 1.0).is_err());
    assert!(est.set_theta(&[1.0]).is_err());
    let mut bad_p = vec![0.0; 16];
    bad_p[1] = 1.0;
    assert!(est.set_covariance(&bad_p).is_err());
}

#[test]
fn schur_cohn_matches_roots() {
    let mut w = vec![0.0; 4];
    assert!(stable(&[-1.5, 0.7], &mut w)); // poles 0.75 +- 0.37i
    assert!(!stable(&[-2.5, 1.0], &mut w)); // roots 2 and 0.5
    assert!(stable(&[0.5], &mut w));
    assert!(!stable(&[1.2], &mut w));
    assert!(!stable(&[0.0, 0.0, 1.01], &mut w));
    assert!(stable(&[-0.9, 0.2, 0.05], &mut w));
}

#[test]
fn delays_and_orders_are_bounded_before_sizing() {
    let s = |nb: usize, nk: usize, na: usize| Structure {
        na,
        nb: vec![nb],
        nc: 0,
        nd: 0,
        nf: vec![0],
        nk: vec![nk],
    };
    // nk = 10^12 sized a delay line of 8 TB and aborted the process
    let e = check_structure(&s(1, 1_000_000_000_000, 2))
        .unwrap_err()
        .to_string();
    assert!(e.contains("delay line") && e.contains("shift"), "{e}");
    assert!(check_structure(&s(1, usize::MAX, 2)).is_err());
    // orders whose sum overflows
    let e = check_structure(&s(1, 1, usize::MAX))
        .unwrap_err()
        .to_string();
    assert!(e.contains("more parameters than can be counted"), "{e}");
    // a long but bounded delay is fine
    assert_eq!(check_structure(&s(1, MAX_DELAY_LINE - 1, 2)).unwrap(), 3);
}

#[test]
fn start_up_forgetting_tends_to_the_factor_asked_for() {
    assert_eq!(start_up_forgetting(1.0, 0), LAMBDA_START);
    assert!(
        (start_up_forgetting(1.0, 1) - (LAMBDA_RATE * LAMBDA_START + 1.0 - LAMBDA_RATE)).abs()
            < 1e-15
    );
    assert!(1.0 - start_up_forgetting(1.0, 2000) < 1e-9);
    assert_eq!(start_up_forgetting(1.0, 20_000), 1.0);
    // a factor below the start is used from the first sample
    assert_eq!(start_up_forgetting(0.9, 0), 0.9);
    assert_eq!(start_up_forgetting(0.9, 500), 0.9);
}

#[test]
fn start_up_forgetting_only_changes_the_prediction_error_method() {
    let (u, y) = arx_data(300);
    let run = |s: Structure, on: bool| {
        let mut est = Recursive::new(s, Method::Forgetting { lambda: 1.0 }, None, None).unwrap();
        est.set_startup_forgetting(on);
        assert_eq!(est.startup_forgetting(), on);
        let mut yhat = vec![0.0; 300];
        est.run(&u, &y, &mut yhat, None, 64, &mut || false).unwrap();
        est.theta().to_vec()
    };
    // ARX: recursive least squares either way
    assert_eq!(run(arx_structure(), true), run(arx_structure(), false));
    assert_ne!(
        run(siso(0, 2, 0, 0, 2, 1), true),
        run(siso(0, 2, 0, 0, 2, 1), false)
    );
}
