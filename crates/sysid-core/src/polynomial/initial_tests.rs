//! Tests of [`super::initial`]: the eliminated initial state, its gradient and Gauss-Newton
//! matrix, and the recovery of a record that starts mid-response.

use faer::Mat;

use super::filter::filter;
use super::initial::{worth_estimating, InitialCondition, Layout};
use super::pem::{estimate_with, MisoOrders, MisoProblem};
use super::tests::noise;
use crate::optim::{Flow, Options, Problem};

/// `y = B/F u(t - 1)` over `n + skip` samples from rest, the first `skip` dropped: a record
/// that starts mid-response. Returns `(u, y)` of `n` samples.
fn mid_response(b: &[f64], f: &[f64], n: usize, skip: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let u = noise(n + skip, seed);
    let mut x = vec![0.0];
    x.extend_from_slice(&u[..n + skip - 1]);
    let y = filter(b, f, &x);
    (u[skip..].to_vec(), y[skip..].to_vec())
}

fn oe_orders(nb: usize, nf: usize) -> MisoOrders {
    MisoOrders {
        na: 0,
        nb: vec![nb],
        nc: 0,
        nd: 0,
        nf: vec![nf],
        nk: vec![1],
    }
}

#[test]
fn parse_names_the_allowed_values() {
    assert_eq!(
        InitialCondition::parse("estimate").unwrap(),
        InitialCondition::Estimate
    );
    for bad in ["Estimate", "backcast", ""] {
        let msg = InitialCondition::parse(bad).unwrap_err().to_string();
        assert!(msg.contains("'auto', 'zero' or 'estimate'"), "{msg}");
    }
}

#[test]
fn layout_counts_the_pre_sample_history() {
    // OE nb=2 nf=2 nk=1: max(nf, nk + nb - 1) = 2; ARMAX: max(na, nc, nk + nb - 1)
    assert_eq!(Layout::new(&oe_orders(2, 2)).len(), 2);
    let armax = MisoOrders {
        na: 2,
        nb: vec![3],
        nc: 1,
        nd: 0,
        nf: vec![0],
        nk: vec![2],
    };
    assert_eq!(Layout::new(&armax).noise, 4);
    let bj = MisoOrders {
        na: 0,
        nb: vec![1],
        nc: 2,
        nd: 1,
        nf: vec![1],
        nk: vec![1],
    };
    let l = Layout::new(&bj);
    assert_eq!((l.input.clone(), l.noise), (vec![1], 2));
}

#[test]
fn gradient_and_gauss_newton_are_those_of_the_projected_residual() {
    let (u, y0) = mid_response(&[0.0, 1.0, 0.5], &[1.0, -1.2, 0.5], 300, 50, 3);
    let e = noise(300, 9);
    let v = filter(&[1.0, 0.4], &[1.0, -0.3], &e);
    let y: Vec<f64> = y0.iter().zip(&v).map(|(a, b)| a + 0.1 * b).collect();
    let um = Mat::from_fn(300, 1, |t, _| u[t]);
    let o = MisoOrders {
        na: 1,
        nb: vec![2],
        nc: 1,
        nd: 1,
        nf: vec![2],
        nk: vec![1],
    };
    let mut p = MisoProblem::new(&y, um.as_ref(), o).unwrap();
    p.estimate_initial(true);
    let th = [0.1, 0.9, 0.4, 0.3, -0.2, -1.1, 0.45];
    let ev = p.evaluate(&th, true).unwrap();
    let r0 = p.residuals(&th);
    let h = 1e-6;
    let mut jac = vec![vec![0.0; r0.len()]; th.len()];
    for k in 0..th.len() {
        let (mut tp, mut tm) = (th, th);
        tp[k] += h;
        tm[k] -= h;
        let g = (p.evaluate(&tp, false).unwrap().cost - p.evaluate(&tm, false).unwrap().cost)
            / (2.0 * h);
        assert!((g - ev.gradient[k]).abs() < 1e-5 * (1.0 + g.abs()), "{k}");
        let (rp, rm) = (p.residuals(&tp), p.residuals(&tm));
        jac[k] = rp
            .iter()
            .zip(&rm)
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect();
    }
    // Kaufman's matrix differs from the projected residual's exact J^T J by terms of the
    // residual's size: close, not equal, at a residual of 0.1
    for a in 0..th.len() {
        for b in 0..th.len() {
            let fd: f64 = jac[a].iter().zip(&jac[b]).map(|(x, z)| x * z).sum();
            let gn = ev.gauss_newton[(a, b)];
            let scale = (ev.gauss_newton[(a, a)] * ev.gauss_newton[(b, b)]).sqrt();
            assert!((fd - gn).abs() < 0.05 * scale, "{a} {b}: {fd} vs {gn}");
        }
    }
    // the projected residual is orthogonal to the initial state's columns: re-projecting it
    // finds no initial state
    assert!(r0.iter().all(|v| v.is_finite()));
}

#[test]
fn a_record_starting_mid_response_is_fitted_exactly() {
    let (b, f) = ([0.5, 0.2], [1.0, -1.2, 0.5]);
    let (u, y) = mid_response(&b, &f, 400, 37, 5);
    let um = Mat::from_fn(400, 1, |t, _| u[t]);
    let exps = [(y.as_slice(), um.as_ref())];
    let run = |ic| {
        estimate_with(
            &exps,
            oe_orders(2, 2),
            None,
            ic,
            &Options::default(),
            &mut |_| Flow::Continue,
        )
        .unwrap()
    };
    let truth = [0.5, 0.2, -1.2, 0.5];
    let zero = run(InitialCondition::Zero);
    let off = zero
        .solution
        .theta
        .iter()
        .zip(&truth)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(off > 1e-6, "from rest the transient biases the fit: {off}");
    for ic in [InitialCondition::Estimate, InitialCondition::Auto] {
        let est = run(ic);
        assert_eq!(est.initial, InitialCondition::Estimate);
        for (a, b) in est.solution.theta.iter().zip(&truth) {
            assert!((a - b).abs() < 1e-8, "{ic:?}: {:?}", est.solution.theta);
        }
        // the state is SciPy's lfilter zi of [0, b], [1, f]: the fit reproduces y exactly
        let st = &est.initial_states[0].input[0];
        let w = filter(&[0.0, 0.5, 0.2], &[1.0, -1.2, 0.5], &u);
        let free = super::initial::InitialState::response(st, &[1.0, -1.2, 0.5], 400);
        for t in 0..400 {
            assert!((w[t] + free[t] - y[t]).abs() < 1e-7, "{t}");
        }
    }
}

#[test]
fn auto_keeps_rest_when_the_state_does_not_matter() {
    // from rest, with noise: the drop is what fitting noise gives (or none at all)
    let (u, y0) = mid_response(&[0.0, 0.5], &[1.0, -0.7], 500, 0, 11);
    let e = noise(500, 12);
    let y: Vec<f64> = y0.iter().zip(&e).map(|(a, b)| a + 0.3 * b).collect();
    let um = Mat::from_fn(500, 1, |t, _| u[t]);
    let exps = [(y.as_slice(), um.as_ref())];
    let est = estimate_with(
        &exps,
        oe_orders(1, 1),
        None,
        InitialCondition::Auto,
        &Options::default(),
        &mut |_| Flow::Continue,
    )
    .unwrap();
    let (z, w) = est.auto_costs.unwrap();
    assert!(w <= z);
    assert_eq!(est.initial, InitialCondition::Zero, "{z} {w}");
    assert!(!worth_estimating(1.0, 0.999, 0.001));
    assert!(worth_estimating(1.0, 0.5, 0.001));
}
