use faer::Mat;
use rand::{rngs::StdRng, Rng, SeedableRng};

use super::*;
use crate::interrupt::error_when_asked_to_stop as stop;
use crate::linalg::eigenvalues;

fn inputs(n: usize, seed: u64) -> Mat<f64> {
    let mut rng = StdRng::seed_from_u64(seed);
    Mat::from_fn(n, 2, |_, _| rng.random_range(-1.0..1.0))
}

/// Linear block with poles 0.8 and 0.5 (A in companion form), full B and C.
fn linear_block() -> Vec<f64> {
    vec![
        1.3, -0.4, 1.0, 0.0, // A
        1.0, 0.5, 0.2, -0.7, // B
        0.6, 0.3, -0.4, 0.9, // C
    ]
}

/// The 2 x 2 Hammerstein structure of several tests: saturation on input 0, a cubic
/// polynomial on input 1, a second-order linear block, no feedthrough.
fn hammerstein_2x2(offsets: bool) -> MimoHwStructure {
    MimoHwStructure {
        inputs: vec![
            Nonlinearity::Saturation,
            Nonlinearity::Polynomial { degree: 3 },
        ],
        outputs: vec![Nonlinearity::Identity, Nonlinearity::Identity],
        order: 2,
        feedthrough: false,
        offsets,
        initial_states: 0,
    }
}

/// Its true parameters (without offsets).
fn hammerstein_2x2_truth() -> Vec<f64> {
    let mut truth = vec![-0.5, 0.6, 0.3, -0.2];
    truth.extend(linear_block());
    truth
}

/// Its start: the nonlinearities near identity, the linear block perturbed by ~10 %.
fn hammerstein_2x2_start() -> Vec<f64> {
    let mut start = vec![-0.9, 0.9, 0.0, 0.0];
    start.extend(
        linear_block()
            .iter()
            .enumerate()
            .map(|(k, v)| v * (1.0 + 0.1 * ((k as f64 * 1.7).sin()))),
    );
    start
}

fn sorted_poles(s: &MimoHwStructure, th: &[f64]) -> Vec<f64> {
    let (a, _, _, _) = s.matrices(th);
    let mut p: Vec<f64> = eigenvalues(a.as_ref())
        .unwrap()
        .into_iter()
        .map(|(re, im)| {
            assert!(im.abs() < 1e-9);
            re
        })
        .collect();
    p.sort_by(|a, b| a.partial_cmp(b).unwrap());
    p
}

fn fit(s: &MimoHwStructure, truth: &[f64], start: &[f64]) -> Solution {
    let u = inputs(800, 3);
    let y = s.simulate(truth, u.as_ref()).unwrap();
    let opts = Options {
        max_iter: 200,
        ..Options::default()
    };
    estimate_mimo(s, &[(u.as_ref(), y.as_ref())], start, &opts, &mut |_| {
        Flow::Continue
    })
    .unwrap()
}

#[test]
fn gradient_matches_finite_differences() {
    let s = MimoHwStructure {
        inputs: vec![
            Nonlinearity::Saturation,
            Nonlinearity::Polynomial { degree: 3 },
        ],
        outputs: vec![
            Nonlinearity::Polynomial { degree: 2 },
            Nonlinearity::Identity,
        ],
        order: 2,
        feedthrough: true,
        offsets: true,
        initial_states: 0,
    };
    let mut th = vec![-0.613, 0.707, 0.2, -0.1];
    th.extend(linear_block());
    th.extend([0.1, -0.2, 0.05, 0.3]); // D
    th.push(0.25);
    th.extend([0.4, -1.3]); // output offsets
    let u = inputs(300, 1);
    let y = Mat::from_fn(300, 2, |t, i| ((t * (i + 3)) as f64 * 0.37).sin());
    let mut pr = MimoHwProblem {
        structure: s,
        records: vec![(u.as_ref(), y.as_ref())],
    };
    crate::optim::assert_gradient_matches_cost(&mut pr, &th, 1e-5, "");
}

/// 2 x 2 Hammerstein: saturation on input 0, cubic polynomial on input 1.
#[test]
fn hammerstein_2x2_recovered() {
    let s = hammerstein_2x2(false);
    let truth = hammerstein_2x2_truth();
    let start = hammerstein_2x2_start();
    let sol = fit(&s, &truth, &start);
    let p = sorted_poles(&s, &sol.theta);
    assert!(
        (p[0] - 0.5).abs() < 1e-6 && (p[1] - 0.8).abs() < 1e-6,
        "{p:?}"
    );
    for k in 0..4 {
        assert!(
            (sol.theta[k] - truth[k]).abs() < 1e-6,
            "{:?}",
            &sol.theta[..4]
        );
    }
    assert!(sol.cost < 1e-18, "cost {}", sol.cost);
}

/// The 2 x 2 Hammerstein record at output levels (2, -1): recovered with the offsets
/// estimated, from a start at level zero.
#[test]
fn hammerstein_2x2_with_output_levels_recovered() {
    let s = hammerstein_2x2(true);
    let mut truth = hammerstein_2x2_truth();
    truth.extend([2.0, -1.0]);
    let mut start = hammerstein_2x2_start();
    start.extend([0.0, 0.0]);
    let sol = fit(&s, &truth, &start);
    let n = sol.theta.len();
    assert!(
        (sol.theta[n - 2] - 2.0).abs() < 1e-6 && (sol.theta[n - 1] + 1.0).abs() < 1e-6,
        "{:?}",
        &sol.theta[n - 2..]
    );
    assert!(sol.cost < 1e-18, "cost {}", sol.cost);
}

/// 2 x 2 Wiener: quadratic polynomial on output 0, saturation on output 1.
#[test]
fn wiener_2x2_recovered() {
    let s = MimoHwStructure {
        inputs: vec![Nonlinearity::Identity, Nonlinearity::Identity],
        outputs: vec![
            Nonlinearity::Polynomial { degree: 2 },
            Nonlinearity::Saturation,
        ],
        order: 2,
        feedthrough: false,
        offsets: false,
        initial_states: 0,
    };
    let mut truth = linear_block();
    truth.extend([0.4, -0.5, 0.45]);
    let mut start: Vec<f64> = linear_block()
        .iter()
        .enumerate()
        .map(|(k, v)| v * (1.0 + 0.05 * ((k as f64 * 1.3).cos())))
        .collect();
    start.extend([0.0, -2.0, 2.0]);
    let sol = fit(&s, &truth, &start);
    let p = sorted_poles(&s, &sol.theta);
    assert!(
        (p[0] - 0.5).abs() < 1e-6 && (p[1] - 0.8).abs() < 1e-6,
        "{p:?}"
    );
    let nl = &sol.theta[12..];
    for (g, w) in nl.iter().zip([0.4, -0.5, 0.45]) {
        assert!((g - w).abs() < 1e-6, "{nl:?}");
    }
}

#[test]
fn bad_starts_and_shapes_are_errors() {
    let s = MimoHwStructure {
        inputs: vec![Nonlinearity::Identity, Nonlinearity::Identity],
        outputs: vec![Nonlinearity::Identity, Nonlinearity::Identity],
        order: 2,
        feedthrough: false,
        offsets: false,
        initial_states: 0,
    };
    let u = inputs(50, 2);
    let y = Mat::<f64>::zeros(50, 2);
    let mut th = linear_block();
    th[0] = 3.0; // unstable A
    let r = estimate_mimo(
        &s,
        &[(u.as_ref(), y.as_ref())],
        &th,
        &Options::default(),
        &mut |_| Flow::Continue,
    );
    assert!(format!("{:?}", r.unwrap_err()).contains("unstable"));
    let y1 = Mat::<f64>::zeros(50, 1);
    let r = estimate_mimo(
        &s,
        &[(u.as_ref(), y1.as_ref())],
        &linear_block(),
        &Options::default(),
        &mut |_| Flow::Continue,
    );
    assert!(r.is_err());
}

type Records = Vec<(Mat<f64>, Mat<f64>)>;

/// An order-3 structure with sigmoid networks in and out and feedthrough, its parameters
/// with `A` having a complex pair and a real pole (not in modal form), a record (with
/// `states`, two, their initial states estimated), and the evaluation through the modal
/// coordinates there.
fn order3(states: bool) -> (MimoHwStructure, Vec<f64>, Records, Evaluation) {
    let s = MimoHwStructure {
        inputs: vec![
            Nonlinearity::Sigmoid {
                units: 2,
                amplitude: 1.0,
            },
            Nonlinearity::Identity,
        ],
        outputs: vec![
            Nonlinearity::Sigmoid {
                units: 1,
                amplitude: 0.7,
            },
            Nonlinearity::Polynomial { degree: 2 },
        ],
        order: 3,
        feedthrough: true,
        offsets: true,
        initial_states: if states { 2 } else { 0 },
    };
    let mut th = vec![0.3, 1.1, 0.1, 0.5, 0.7, -0.2]; // input 0's network
    th.extend([0.6, -0.3, 0.1, 0.3, 0.5, -0.2, 0.1, 0.2, -0.4]); // A
    th.extend([1.0, 0.5, 0.2, -0.7, 0.4, 0.3]); // B
    th.extend([0.6, 0.3, -0.4, 0.9, 0.1, 0.5]); // C
    th.extend([0.1, -0.2, 0.05, 0.3]); // D
    th.extend([0.8, 0.9, 0.1, 0.25]); // output networks
    th.extend([0.4, -1.3]); // output offsets
    let mut recs = vec![(
        inputs(400, 5),
        Mat::from_fn(400, 2, |t, i| ((t * (i + 2)) as f64 * 0.29).cos()),
    )];
    if states {
        th.extend([0.5, -0.8, 0.3, -0.2, 0.9, 0.4]); // the two records' x(0)
        recs.push((
            inputs(250, 6),
            Mat::from_fn(250, 2, |t, i| ((t * (i + 1)) as f64 * 0.41).sin()),
        ));
    }
    assert_eq!(th.len(), s.n_params());
    let pr = MimoHwProblem {
        structure: s.clone(),
        records: recs.iter().map(|(u, y)| (u.as_ref(), y.as_ref())).collect(),
    };
    let ev = pr
        .evaluate_modal(&th)
        .unwrap()
        .expect("the modal path applies");
    (s, th, recs, ev)
}

/// The simulated outputs of every record (from its estimated initial state, if any).
fn simulate_all(s: &MimoHwStructure, th: &[f64], recs: &Records) -> Vec<Mat<f64>> {
    recs.iter()
        .enumerate()
        .map(|(e, (u, _))| {
            if s.initial_states > 0 {
                s.simulate_from(th, u.as_ref(), s.initial_state(th, e))
                    .unwrap()
            } else {
                s.simulate(th, u.as_ref()).unwrap()
            }
        })
        .collect()
}

/// The Gauss-Newton products formed in the modal coordinates over the identifiable columns
/// equal `J^T J` and `-J^T r` of a finite-difference Jacobian of the simulation over all
/// parameters (the similarity directions included; with the records' initial states, their
/// columns too).
#[test]
fn modal_gauss_newton_matches_finite_differences() {
    for states in [false, true] {
        let (s, th, recs, ev) = order3(states);
        let sim = |th: &[f64]| simulate_all(&s, th, &recs);
        let y0 = sim(&th);
        let p = th.len();
        let jac: Vec<Vec<Mat<f64>>> = (0..p)
            .map(|a| {
                let h = 1e-6;
                let (mut tp, mut tm) = (th.clone(), th.clone());
                tp[a] += h;
                tm[a] -= h;
                sim(&tp)
                    .iter()
                    .zip(sim(&tm))
                    .map(|(yp, ym)| (yp - ym) * faer::Scale(0.5 / h))
                    .collect()
            })
            .collect();
        let each = || {
            recs.iter().enumerate().flat_map(|(e, (_, y))| {
                (0..y.nrows()).flat_map(move |t| (0..2).map(move |i| (e, t, i)))
            })
        };
        let r = |e: usize, t: usize, i: usize| recs[e].1[(t, i)] - y0[e][(t, i)];
        let cost: f64 = each().map(|(e, t, i)| 0.5 * r(e, t, i).powi(2)).sum();
        assert!((ev.cost - cost).abs() < 1e-9 * cost);
        for a in 0..p {
            let want: f64 = each()
                .map(|(e, t, i)| -jac[a][e][(t, i)] * r(e, t, i))
                .sum();
            let got = ev.gradient[a];
            assert!(
                (got - want).abs() < 1e-5 * (1.0 + want.abs()),
                "states {states} g {a}: {got} vs {want}"
            );
            for b in 0..p {
                let want: f64 = each()
                    .map(|(e, t, i)| jac[a][e][(t, i)] * jac[b][e][(t, i)])
                    .sum();
                let got = ev.gauss_newton[(a, b)];
                assert!(
                    (got - want).abs() < 1e-5 * (1.0 + want.abs()),
                    "states {states} H {a},{b}: {got} vs {want}"
                );
            }
        }
    }
}

/// The modal path and the plain one (every column formed) agree to rounding.
#[test]
fn modal_gauss_newton_matches_the_plain_products() {
    for states in [false, true] {
        let (s, th, recs, ev) = order3(states);
        let cols = s.columns(&[]);
        let mut sums = NormalEquations::new(cols.len(), true);
        for (e, (u, y)) in recs.iter().enumerate() {
            let x0 = states.then(|| s.initial_state(&th, e));
            s.run(&th, u.as_ref(), Some(&cols), x0, e, |t, i, yhat, jr| {
                sums.add(y[(t, i)] - yhat, Some(jr))
            })
            .unwrap();
        }
        let plain = sums.finish();
        plain_agrees(&plain, &ev);
    }
}

fn plain_agrees(plain: &Evaluation, ev: &Evaluation) {
    let hmax = plain.gauss_newton.norm_max();
    let dh = (&ev.gauss_newton - &plain.gauss_newton).norm_max();
    assert!(dh < 1e-10 * hmax, "H differs by {dh} (max {hmax})");
    let gmax = plain.gradient.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for (a, b) in ev.gradient.iter().zip(&plain.gradient) {
        assert!((a - b).abs() < 1e-10 * gmax, "g {a} vs {b}");
    }
}

/// A pass over a long record asks whether to stop every few thousand samples: inside a scope
/// whose poll says "stop", an evaluation (and a simulation) ends with `Interrupted` instead of
/// finishing the pass (Ctrl-C took a whole pass, up to half a second, on 200 000 samples).
#[test]
fn a_pass_stops_inside_the_record_when_asked() {
    let s = MimoHwStructure {
        inputs: vec![Nonlinearity::Saturation, Nonlinearity::Identity],
        outputs: vec![Nonlinearity::Identity, Nonlinearity::Identity],
        order: 2,
        feedthrough: false,
        offsets: false,
        initial_states: 0,
    };
    let mut th = vec![-0.5, 0.5];
    th.extend(linear_block());
    let u = inputs(20_000, 5);
    let y = s.simulate(&th, u.as_ref()).unwrap();
    let mut pr = MimoHwProblem {
        structure: s.clone(),
        records: vec![(u.as_ref(), y.as_ref())],
    };
    for jacobian in [false, true] {
        let r = stop(|| pr.evaluate(&th, jacobian));
        assert_eq!(r, Some(SysidError::Interrupted), "jacobian {jacobian}");
    }
    let r = stop(|| s.simulate(&th, u.as_ref()));
    assert_eq!(r, Some(SysidError::Interrupted));
    // outside a scope nothing stops it
    assert!(pr.evaluate(&th, true).is_ok());
}

/// Two records of the 2 x 2 Hammerstein model starting from different states: with their
/// initial states estimated (from rest) the model and both states are recovered exactly;
/// from rest the fit is biased.
#[test]
fn records_starting_mid_response_are_fitted_with_their_initial_states() {
    let mut s = hammerstein_2x2(false);
    let truth = hammerstein_2x2_truth();
    let states = [[3.0, -2.0], [-1.5, 4.0]];
    let recs: Vec<(Mat<f64>, Mat<f64>)> = states
        .iter()
        .enumerate()
        .map(|(e, x0)| {
            let u = inputs(300, 11 + e as u64);
            let y = s.simulate_from(&truth, u.as_ref(), x0).unwrap();
            (u, y)
        })
        .collect();
    let refs: Vec<_> = recs.iter().map(|(u, y)| (u.as_ref(), y.as_ref())).collect();
    let mut start = hammerstein_2x2_start();
    let opts = Options {
        max_iter: 200,
        ..Options::default()
    };
    let zero = estimate_mimo(&s, &refs, &start, &opts, &mut |_| Flow::Continue).unwrap();
    assert!(zero.cost > 1e-6, "cost from rest {}", zero.cost);
    s.initial_states = 2;
    start.extend([0.0; 4]);
    let sol = estimate_mimo(&s, &refs, &start, &opts, &mut |_| Flow::Continue).unwrap();
    assert!(sol.cost < 1e-18, "cost {}", sol.cost);
    let p = sorted_poles(&s, &sol.theta);
    assert!(
        (p[0] - 0.5).abs() < 1e-8 && (p[1] - 0.8).abs() < 1e-8,
        "{p:?}"
    );
    for k in 0..4 {
        assert!(
            (sol.theta[k] - truth[k]).abs() < 1e-8,
            "{:?}",
            &sol.theta[..4]
        );
    }
    // the states in the estimate's basis: the same outputs from them
    for (e, (u, y)) in recs.iter().enumerate() {
        let x0 = s.initial_state(&sol.theta, e);
        let fit = s.simulate_from(&sol.theta, u.as_ref(), x0).unwrap();
        assert!((&fit - y).norm_max() < 1e-8 * y.norm_max());
    }
}
