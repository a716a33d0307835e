use faer::Mat;

use super::model::{NetworkNarx, Nonlinearity, UnitNetwork};
use super::simfocus::SimFocus;
use super::tree::{fit_tree, TreeOptions};
use super::units::UnitKind;
use super::varpro::VarPro;
use crate::narx::regressors::{LagSpec, Record};
use crate::optim::{Flow, Options, Problem};

fn input(n: usize, seed: u64) -> Mat<f64> {
    let mut s = seed;
    Mat::from_fn(n, 1, |_, _| {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    })
}

fn spec() -> LagSpec {
    LagSpec::new(1, 1, &[2], &[2], &[1], &[0]).unwrap()
}

fn net(kind: UnitKind) -> UnitNetwork {
    UnitNetwork {
        kinds: vec![kind, kind],
        theta: vec![0.8, -0.3, 0.5, 0.2, 0.1, 0.9, 0.3, -0.6, 1.1, -0.2],
        linear: vec![0.1, 0.5, -0.2, 0.7, 0.3, 0.6, -0.4],
    }
}

fn simulated(kind: UnitKind, n: usize) -> (Mat<f64>, Mat<f64>, NetworkNarx) {
    let m = NetworkNarx::new(
        spec(),
        vec![0.0; 4],
        vec![1.0; 4],
        vec![Nonlinearity::Network(net(kind))],
    )
    .unwrap();
    let u = input(n, 3);
    let y = m
        .simulate(u.as_ref(), Mat::<f64>::zeros(2, 1).as_ref())
        .unwrap();
    (u, y, m)
}

/// Central difference `(f(x + h e_j) - f(x - h e_j)) / 2h`, `h = 1e-6`.
fn central(x: &[f64], j: usize, mut f: impl FnMut(&[f64]) -> f64) -> f64 {
    let h = 1e-6;
    let (mut a, mut b) = (x.to_vec(), x.to_vec());
    a[j] += h;
    b[j] -= h;
    (f(&a) - f(&b)) / (2.0 * h)
}

/// The gradient of a problem's cost at `th` against central differences.
fn check_gradient(pr: &mut impl Problem, th: &[f64]) {
    let g = pr.evaluate(th, true).unwrap().gradient;
    for j in 0..th.len() {
        let fd = central(th, j, |a| pr.evaluate(a, false).unwrap().cost);
        assert!(
            (fd - g[j]).abs() < 1e-6 * (1.0 + fd.abs()),
            "{j}: {fd} vs {}",
            g[j]
        );
    }
}

#[test]
fn unit_gradients_match_finite_differences() {
    let z = [0.3, -0.7, 0.2];
    for kind in [UnitKind::Sigmoid, UnitKind::Wavelet, UnitKind::Scaling] {
        let p = [0.9, 0.4, -0.5, 0.1];
        let (mut dp, mut dz) = ([0.0; 4], [0.0; 3]);
        kind.value_grad(&p, &z, Some(&mut dp), Some(&mut dz));
        for j in 0..4 {
            let fd = central(&p, j, |a| kind.value(a, &z));
            assert!(
                (fd - dp[j]).abs() < 1e-8,
                "{kind:?} p{j}: {fd} vs {}",
                dp[j]
            );
        }
        for j in 0..3 {
            let fd = central(&z, j, |a| kind.value(&p, a));
            assert!(
                (fd - dz[j]).abs() < 1e-8,
                "{kind:?} z{j}: {fd} vs {}",
                dz[j]
            );
        }
    }
}

#[test]
fn varpro_gradient_matches_finite_differences() {
    for kind in [UnitKind::Sigmoid, UnitKind::Wavelet] {
        let (u, mut y, _) = simulated(kind, 300);
        let noise = input(300, 11);
        for t in 0..300 {
            y[(t, 0)] += 0.05 * noise[(t, 0)];
        }
        let sp = spec();
        let recs = [Record::new(u.as_ref(), y.as_ref())];
        let (sh, sc) = (vec![0.0; 4], vec![1.0; 4]);
        let mut pr = VarPro::new(&sp, &sh, &sc, &recs, 0, vec![kind, kind]).unwrap();
        let th: Vec<f64> = net(kind).theta.iter().map(|v| v * 1.1 + 0.05).collect();
        check_gradient(&mut pr, &th);
    }
}

#[test]
fn simulation_jacobian_matches_finite_differences() {
    let (u, y, m) = simulated(UnitKind::Sigmoid, 200);
    let mut m2 = m.clone();
    if let Nonlinearity::Network(n) = &mut m2.outputs[0] {
        n.linear[1] += 0.05;
        n.theta[0] -= 0.1;
    }
    let recs = [Record::new(u.as_ref(), y.as_ref())];
    let mut pr = SimFocus::new(m2, &recs).unwrap();
    let th = pr.params();
    check_gradient(&mut pr, &th);
    // at the truth the simulation error vanishes
    let mut pr = SimFocus::new(m, &recs).unwrap();
    let th = pr.params();
    assert!(pr.evaluate(&th, false).unwrap().cost < 1e-25);
}

#[test]
fn sigmoid_network_recovered_from_a_nearby_start() {
    let (u, y, m) = simulated(UnitKind::Sigmoid, 600);
    let sp = spec();
    let recs = [Record::new(u.as_ref(), y.as_ref())];
    let (sh, sc) = (vec![0.0; 4], vec![1.0; 4]);
    let th0: Vec<f64> = net(UnitKind::Sigmoid)
        .theta
        .iter()
        .map(|v| v + 0.05)
        .collect();
    let opts = Options {
        max_iter: 200,
        ..Default::default()
    };
    let (fit, sol) = super::fit_prediction(
        &sp,
        &sh,
        &sc,
        &recs,
        0,
        vec![UnitKind::Sigmoid; 2],
        &th0,
        &opts,
        &mut |_| Flow::Continue,
    )
    .unwrap();
    assert!(sol.cost < 1e-22, "cost {}", sol.cost);
    let Nonlinearity::Network(truth) = &m.outputs[0] else {
        unreachable!()
    };
    for (a, b) in fit
        .theta
        .iter()
        .zip(&truth.theta)
        .chain(fit.linear.iter().zip(&truth.linear))
    {
        assert!((a - b).abs() < 1e-7, "{a} vs {b}");
    }
}

#[test]
fn tree_recovers_a_piecewise_affine_arx_system() {
    let n = 800;
    let u = input(n, 5);
    let mut y = Mat::<f64>::zeros(n, 1);
    for t in 1..n {
        let (yp, up) = (y[(t - 1, 0)], u[(t - 1, 0)]);
        y[(t, 0)] = if yp <= 0.1 {
            0.5 * yp + up + 0.2
        } else {
            -0.3 * yp + 0.5 * up - 0.1
        };
    }
    let sp = LagSpec::new(1, 1, &[1], &[1], &[1], &[0]).unwrap();
    let recs = [Record::new(u.as_ref(), y.as_ref())];
    let fit = fit_tree(
        &sp,
        &[0.0, 0.0],
        &[1.0, 1.0],
        &recs,
        0,
        &TreeOptions::default(),
        &mut || false,
    )
    .unwrap();
    let tree = &fit.tree;
    assert_eq!(tree.nodes.len(), 3, "{:?} {:?}", fit.rss, fit.stop);
    assert_eq!(tree.nodes[0].var, 0);
    let (l, r) = tree.nodes[0].children.unwrap();
    for (c, e) in tree.nodes[l].coefs.iter().zip([0.2, 0.5, 1.0]) {
        assert!((c - e).abs() < 1e-10);
    }
    for (c, e) in tree.nodes[r].coefs.iter().zip([-0.1, -0.3, 0.5]) {
        assert!((c - e).abs() < 1e-10);
    }
    assert!(fit.rss.last().unwrap() < &1e-20);
}
