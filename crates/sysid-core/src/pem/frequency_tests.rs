//! Tests of the frequency-domain refinement (`pem::frequency`).

use super::frequency::{pem_frequency, FrequencyOptions, Lines};
use crate::error::SysidError;
use crate::model::StateSpace;
use crate::optim::Flow;
use faer::linalg::solvers::DenseSolveCore;
use faer::{c64, Mat};

/// A stable 2-input, 2-output order-4 system with two complex pole pairs, in a non-modal
/// basis.
fn truth() -> StateSpace {
    let a = Mat::from_fn(4, 4, |i, j| {
        [
            [0.5, 0.4, 0.1, 0.0],
            [-0.5, 0.6, 0.0, 0.2],
            [0.1, 0.0, -0.3, 0.7],
            [0.0, 0.1, -0.6, -0.2],
        ][i][j]
    });
    let b = Mat::from_fn(4, 2, |i, j| {
        [[1.0, 0.0], [0.3, 0.5], [0.0, 1.0], [0.4, -0.2]][i][j]
    });
    let c = Mat::from_fn(2, 4, |i, j| {
        [[1.0, 0.0, 0.5, 0.2], [0.0, 1.0, -0.3, 0.6]][i][j]
    });
    let d = Mat::from_fn(2, 2, |i, j| [[0.1, 0.0], [0.05, -0.2]][i][j]);
    StateSpace::new(a, b, c, d).unwrap()
}

/// `G(e^{j w})` by a dense complex solve, entries in row-major order.
fn response(s: &StateSpace, w: f64) -> Vec<c64> {
    let n = s.n_states();
    let z = c64::new(w.cos(), w.sin());
    let m = Mat::from_fn(n, n, |i, j| {
        (if i == j { z } else { c64::new(0.0, 0.0) }) - c64::new(s.a[(i, j)], 0.0)
    });
    let r = m.partial_piv_lu().inverse();
    let mut out = Vec::new();
    for i in 0..s.n_outputs() {
        for j in 0..s.n_inputs() {
            let mut g = c64::new(s.d[(i, j)], 0.0);
            for p in 0..n {
                for q in 0..n {
                    g += s.c[(i, p)] * r[(p, q)] * s.b[(q, j)];
                }
            }
            out.push(g);
        }
    }
    out
}

struct Data {
    omega: Vec<f64>,
    re: Mat<f64>,
    im: Mat<f64>,
    weight: Mat<f64>,
}

fn data(s: &StateSpace, k: usize) -> Data {
    let omega: Vec<f64> = (1..=k)
        .map(|i| std::f64::consts::PI * i as f64 / (k + 1) as f64)
        .collect();
    let g: Vec<Vec<c64>> = omega.iter().map(|&w| response(s, w)).collect();
    let e = s.n_outputs() * s.n_inputs();
    Data {
        re: Mat::from_fn(k, e, |i, j| g[i][j].re),
        im: Mat::from_fn(k, e, |i, j| g[i][j].im),
        weight: Mat::from_fn(k, e, |i, j| 1.0 + 0.5 * ((i + j) % 3) as f64),
        omega,
    }
}

fn lines(d: &Data) -> Lines<'_> {
    Lines {
        omega: &d.omega,
        re: d.re.as_ref(),
        im: d.im.as_ref(),
        weight: d.weight.as_ref(),
    }
}

fn perturbed(s: &StateSpace, eps: f64) -> StateSpace {
    let bump = |m: &Mat<f64>, k: f64| {
        Mat::from_fn(m.nrows(), m.ncols(), |i, j| {
            m[(i, j)] + eps * ((i * 7 + j * 3) as f64 * k).sin()
        })
    };
    StateSpace::new(
        bump(&s.a, 1.3),
        bump(&s.b, 0.7),
        bump(&s.c, 2.1),
        bump(&s.d, 0.9),
    )
    .unwrap()
}

fn cont(_: &crate::optim::Iteration) -> Flow {
    Flow::Continue
}

#[test]
fn noise_free_lines_give_the_system_to_round_off() {
    let s = truth();
    let d = data(&s, 40);
    for modal in [true, false] {
        let mut o = FrequencyOptions {
            estimate_d: true,
            modal_chart: modal,
            ..Default::default()
        };
        o.optim.max_iter = 100;
        o.optim.tol_cost = 0.0;
        let r = pem_frequency(&perturbed(&s, 0.03), &lines(&d), &o, &mut cont).unwrap();
        assert_eq!(r.modal, modal);
        for &w in &[0.05, 0.7, 2.0, 3.1] {
            let (g, h) = (response(&s, w), response(&r.sys, w));
            for (x, y) in g.iter().zip(&h) {
                assert!((x - y).norm() < 1e-10, "{modal} at {w}: {x} vs {y}");
            }
        }
        assert!(r.solution.cost < 1e-20, "cost {}", r.solution.cost);
    }
}

#[test]
fn gradient_is_the_derivative_of_the_cost() {
    // one Gauss-Newton step from a point near the optimum lowers the cost by about the
    // predicted amount only when gradient and J^T J are right: check the gradient against
    // central differences of the cost through the search's own evaluation (max_iter = 0)
    let s = truth();
    let d = data(&s, 25);
    let start = perturbed(&s, 0.05);
    let mut o = FrequencyOptions {
        estimate_d: true,
        modal_chart: false,
        ..Default::default()
    };
    o.optim.max_iter = 0;
    let r = pem_frequency(&start, &lines(&d), &o, &mut cont).unwrap();
    let g = &r.solution.gradient;
    let cost = |th: &[f64]| {
        let (n, m, l) = (4, 2, 2);
        let sys = StateSpace::new(
            Mat::from_fn(n, n, |i, j| th[i * n + j]),
            Mat::from_fn(n, m, |i, j| th[16 + i * m + j]),
            Mat::from_fn(l, n, |i, j| th[24 + i * n + j]),
            Mat::from_fn(l, m, |i, j| th[32 + i * m + j]),
        )
        .unwrap();
        let mut v = 0.0;
        for (k, &w) in d.omega.iter().enumerate() {
            for (e, gm) in response(&sys, w).iter().enumerate() {
                v +=
                    0.5 * d.weight[(k, e)] * (gm - c64::new(d.re[(k, e)], d.im[(k, e)])).norm_sqr();
            }
        }
        v
    };
    let th = r.theta.clone();
    for i in [0, 5, 15, 17, 26, 33] {
        let h = 1e-6;
        let (mut tp, mut tm) = (th.clone(), th.clone());
        tp[i] += h;
        tm[i] -= h;
        let fd = (cost(&tp) - cost(&tm)) / (2.0 * h);
        assert!(
            (fd - g[i]).abs() < 1e-6 * (1.0 + fd.abs()),
            "param {i}: {fd} vs {}",
            g[i]
        );
    }
}

#[test]
fn bad_lines_are_clear_errors() {
    let s = truth();
    let d = data(&s, 3);
    // two lines of a 2 x 2 system: 16 real residuals < 4 (2 + 2) + 4 = 20 identifiable
    // parameters
    let d2 = Data {
        omega: d.omega[..2].to_vec(),
        re: d.re.subrows(0, 2).to_owned(),
        im: d.im.subrows(0, 2).to_owned(),
        weight: d.weight.subrows(0, 2).to_owned(),
    };
    let o = FrequencyOptions {
        estimate_d: true,
        ..Default::default()
    };
    let e = pem_frequency(&s, &lines(&d2), &o, &mut cont).unwrap_err();
    assert!(matches!(e, SysidError::InsufficientData { .. }), "{e}");
    let wrong = Mat::<f64>::zeros(3, 3);
    let bad = Lines {
        re: wrong.as_ref(),
        ..lines(&d)
    };
    let e = pem_frequency(&s, &bad, &o, &mut cont).unwrap_err();
    assert!(matches!(e, SysidError::ShapeMismatch { .. }), "{e}");
    let mut neg = d.weight.clone();
    neg[(0, 0)] = -1.0;
    let bad = Lines {
        weight: neg.as_ref(),
        ..lines(&d)
    };
    assert!(pem_frequency(&s, &bad, &o, &mut cont).is_err());
}
