//! Tests of the transfer-function kernels: the Gram matrix against a direct simulation, and
//! the frequency-domain fit recovering a known model with its delay.

use super::*;
use crate::optim::{Flow, Options};
use faer::{c64, Mat};

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
}

#[test]
fn gram_matches_direct_accumulation() {
    let mut seed = 7u64;
    let (nx, q, r, n) = (3, 2, 4, 1500);
    let ad = Mat::from_fn(
        nx,
        nx,
        |i, j| if i == j { 0.5 } else { 0.1 * lcg(&mut seed) },
    );
    let bd = Mat::from_fn(nx, q, |_, _| lcg(&mut seed));
    let cw = Mat::from_fn(r, nx, |_, _| lcg(&mut seed));
    let dw = Mat::from_fn(r, q, |_, _| lcg(&mut seed));
    let v = Mat::from_fn(n, q, |_, _| lcg(&mut seed));
    let skip = 10;
    let g = filtered_gram(
        ad.as_ref(),
        bd.as_ref(),
        cw.as_ref(),
        dw.as_ref(),
        v.as_ref(),
        skip,
    )
    .unwrap();
    let mut x = Mat::<f64>::zeros(nx, 1);
    let mut expect = Mat::<f64>::zeros(r, r);
    for t in 0..n {
        let vt = Mat::from_fn(q, 1, |k, _| v[(t, k)]);
        let w = &(&cw * &x) + &(&dw * &vt);
        if t >= skip {
            expect += &(&w * w.transpose());
        }
        x = &(&ad * &x) + &(&bd * &vt);
    }
    let err = (&g - &expect).norm_max() / expect.norm_max();
    assert!(err < 1e-13, "relative error {err}");
}

#[test]
fn gram_rejects_bad_shapes_and_nan() {
    let z = Mat::<f64>::zeros(2, 2);
    let gram = |v: &Mat<f64>| {
        filtered_gram(
            z.as_ref(),
            z.as_ref(),
            z.as_ref(),
            z.as_ref(),
            v.as_ref(),
            0,
        )
    };
    let e = gram(&Mat::<f64>::zeros(5, 1));
    assert!(e.unwrap_err().to_string().contains("bd has shape"));
    let mut v = Mat::<f64>::zeros(5, 2);
    v[(3, 1)] = f64::NAN;
    let e = gram(&v);
    assert!(e.unwrap_err().to_string().contains("sample 3"));
}

#[test]
fn frequency_fit_recovers_second_order_with_delay() {
    // G(s) = (0.5 s + 2) / (s^2 + 0.8 s + 4) e^{-0.3 s}
    let omega: Vec<f64> = (0..60).map(|k| 0.05 * 1.1f64.powi(k)).collect();
    let x: Vec<c64> = omega.iter().map(|&w| c64::new(0.0, w)).collect();
    let h: Vec<c64> = x
        .iter()
        .map(|&s| (s * 0.5 + 2.0) / (s * s + s * 0.8 + 4.0) * (-s * 0.3).exp())
        .collect();
    let model = Rational {
        x: x.clone(),
        w: x,
        lead: 2,
        den: vec![1, 0],
        num: vec![1, 0],
        stable: false,
    };
    let theta0 = [0.6, 3.5, 0.4, 1.8, 0.25];
    let fit = fit_frequency(
        &model,
        &h,
        &vec![1.0; omega.len()],
        &theta0,
        &Options::default(),
        None,
        &mut |_| Flow::Continue,
    )
    .unwrap();
    let want = [0.8, 4.0, 0.5, 2.0, 0.3];
    for (a, b) in fit.solution.theta.iter().zip(want) {
        assert!((a - b).abs() < 1e-8, "{:?}", fit.solution.theta);
    }
    let g = model.response(&fit.solution.theta);
    let err = g
        .iter()
        .zip(&h)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(err < 1e-9);
}

#[test]
fn hurwitz_test_agrees_with_the_roots() {
    use crate::polynomial::filter::{conv, is_hurwitz};
    // products of first- and second-order factors with known root locations
    let cases: [(&[f64], bool); 7] = [
        (&[1.0, 1.0], true),        // s + 1
        (&[-1.0, 1.0], false),      // s - 1
        (&[4.0, 0.1, 1.0], true),   // lightly damped pair in the left half-plane
        (&[4.0, -0.1, 1.0], false), // the pair mirrored
        (&[0.0, 1.0], false),       // s = 0
        (&[1e-9, 1.0], true),       // a slow stable pole
        (&[5.0, 0.0, 1.0], false),  // s = +-j sqrt 5
    ];
    for (c, want) in cases {
        assert_eq!(is_hurwitz(c), want, "{c:?}");
    }
    // higher degree: (s + 1)(s^2 + 0.2 s + 9)(s + 30) stable; one factor flipped, not
    let stable = conv(&conv(&[1.0, 1.0], &[9.0, 0.2, 1.0]), &[30.0, 1.0]);
    let flipped = conv(&conv(&[1.0, 1.0], &[9.0, -0.2, 1.0]), &[30.0, 1.0]);
    assert!(is_hurwitz(&stable) && !is_hurwitz(&flipped));
}

#[test]
fn enforced_stability_keeps_the_frequency_fit_stable() {
    // a lightly damped pair fitted from a start on the stable side: the free search crosses
    // into the right half-plane to fit a response with an unstable-looking phase; held
    let omega: Vec<f64> = (0..80).map(|k| 0.1 * 1.06f64.powi(k)).collect();
    let x: Vec<c64> = omega.iter().map(|&w| c64::new(0.0, w)).collect();
    // G(s) = 1 / (s^2 - 0.2 s + 4): unstable pair at 0.1 +- 2j (its response is still finite)
    let h: Vec<c64> = x
        .iter()
        .map(|&s| c64::new(1.0, 0.0) / (s * s - s * 0.2 + 4.0))
        .collect();
    let mut model = Rational {
        x: x.clone(),
        w: x,
        lead: 2,
        den: vec![1, 0],
        num: vec![0],
        stable: false,
    };
    let opts = Options {
        fixed: Some(vec![false, false, false, true]),
        ..Options::default()
    };
    let weight = vec![1.0; 80];
    let fit = |model: &Rational, theta0: &[f64]| {
        fit_frequency(model, &h, &weight, theta0, &opts, None, &mut |_| {
            Flow::Continue
        })
    };
    let theta0 = [0.5, 3.0, 1.0, 0.0];
    let free = fit(&model, &theta0).unwrap();
    assert!(
        free.solution.theta[0] < 0.0,
        "the free fit finds the unstable pair"
    );
    model.stable = true;
    let held = fit(&model, &theta0).unwrap();
    assert!(model.is_stable(&held.solution.theta));
    assert!(held.solution.cost > free.solution.cost);
    assert!(
        held.solution.cost < free.solution.history[0],
        "never worse than its start"
    );
    // an unstable start is refused, not searched from
    let bad = fit(&model, &[-0.5, 3.0, 1.0, 0.0]);
    assert!(bad.unwrap_err().to_string().contains("unstable"));
}
