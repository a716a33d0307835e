use super::simulation::{self, NonlinearTerms};
use super::*;
use crate::optim::{Flow, Options};

fn signal(n: usize, m: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n * m)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        })
        .collect()
}

/// A 2-state, 1-input, 2-output model with state and output monomials of degrees 2 and 3.
fn model() -> (Pnlss, Vec<f64>) {
    let zeta = Monomials::new(2, 1, Terms::Full, &[2, 3]).unwrap();
    let eta = Monomials::new(2, 1, Terms::States, &[2]).unwrap();
    let m = Pnlss::new(2, 1, 2, zeta, eta);
    let mut th = vec![0.0; m.n_params()];
    th[..4].copy_from_slice(&[0.6, 0.3, -0.2, 0.5]);
    th[4..6].copy_from_slice(&[1.0, 0.5]);
    th[6..10].copy_from_slice(&[1.0, 0.0, 0.3, 1.0]);
    th[10..12].copy_from_slice(&[0.1, 0.0]);
    let e0 = 12;
    let c = signal(m.n_params() - e0, 1, 99);
    for (k, v) in c.iter().enumerate() {
        th[e0 + k] = 0.3 * v;
    }
    (m, th)
}

fn residuals<M: NonlinearTerms>(m: &M, th: &[f64], u: &[f64], y: &[f64], skip: usize) -> Vec<f64> {
    let yh = simulation::simulate(m, th, u, None).unwrap().0;
    let ny = y.len() / (u.len());
    y.iter()
        .zip(&yh)
        .skip(skip * ny)
        .map(|(a, b)| a - b)
        .collect()
}

#[test]
fn monomial_derivatives_match_finite_differences() {
    let mono = Monomials::new(2, 1, Terms::Full, &[2, 3]).unwrap();
    assert_eq!(mono.len(), 6 + 10);
    let z = [0.3, -0.7, 1.1];
    let mut d = vec![0.0; mono.len() * 2];
    mono.dx(&z, &mut d);
    let (mut a, mut b) = (vec![0.0; mono.len()], vec![0.0; mono.len()]);
    for j in 0..2 {
        let (mut zp, mut zm) = (z, z);
        zp[j] += 1e-6;
        zm[j] -= 1e-6;
        mono.eval(&zp, &mut a);
        mono.eval(&zm, &mut b);
        for k in 0..mono.len() {
            assert!(((a[k] - b[k]) / 2e-6 - d[k * 2 + j]).abs() < 1e-8);
        }
    }
    assert_eq!(
        Monomials::new(2, 1, Terms::Inputs, &[2, 3]).unwrap().len(),
        2
    );
    assert!(Monomials::new(2, 1, Terms::Full, &[1]).is_err());
}

#[test]
fn sensitivity_jacobian_matches_finite_differences() {
    let (m, th) = model();
    check_jacobian(&m, &th);
}

#[test]
fn clamped_sensitivity_jacobian_matches_finite_differences() {
    // the monomials' arguments clamped to a box the simulation leaves at times: the
    // clamped states contribute no monomial derivative
    let (m, th) = model();
    let (_, xs) = m.simulate(&th, &signal(60, 1, 3), None).unwrap();
    let (lo, hi): (Vec<f64>, Vec<f64>) = (0..2)
        .map(|j| {
            let v: Vec<f64> = xs.iter().skip(j).step_by(2).copied().collect();
            let (a, b) = v
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
            (a + 0.2 * (b - a), b - 0.2 * (b - a))
        })
        .chain(std::iter::once((-0.3, 0.3)))
        .unzip();
    let mc = m.clone().with_range(lo, hi).unwrap();
    let (_, xc) = mc.simulate(&th, &signal(60, 1, 3), None).unwrap();
    assert!(xc.iter().step_by(2).any(|&x| x < mc.lo[0] || x > mc.hi[0]));
    check_jacobian(&mc, &th);
    assert!(m.clone().with_range(vec![0.0; 2], vec![1.0; 2]).is_err());
    assert!(m.with_range(vec![1.0; 3], vec![0.0; 3]).is_err());
}

fn check_jacobian<M: NonlinearTerms>(m: &M, th: &[f64]) {
    let th = th.to_vec();
    let n = 60;
    let u = signal(n, 1, 3);
    let y = signal(n, 2, 4);
    let data = [PnlssData {
        u: &u,
        y: &y,
        skip: 5,
    }];
    let ev = simulation::cost(m, &th, &data, true);
    let p = m.n_params();
    let r0 = residuals(m, &th, &u, &y, 5);
    let mut jac = vec![vec![0.0; r0.len()]; p];
    for a in 0..p {
        let h = 1e-6 * (1.0 + th[a].abs());
        let (mut tp, mut tm) = (th.clone(), th.clone());
        tp[a] += h;
        tm[a] -= h;
        let (rp, rm) = (residuals(m, &tp, &u, &y, 5), residuals(m, &tm, &u, &y, 5));
        for k in 0..r0.len() {
            jac[a][k] = (rp[k] - rm[k]) / (2.0 * h);
        }
    }
    let scale = ev.gauss_newton.norm_max();
    for a in 0..p {
        let g: f64 = jac[a].iter().zip(&r0).map(|(j, r)| j * r).sum();
        assert!(
            (g - ev.gradient[a]).abs() < 1e-6 * (1.0 + g.abs()),
            "gradient {a}: {g} vs {}",
            ev.gradient[a]
        );
        for b in 0..p {
            let h: f64 = jac[a].iter().zip(&jac[b]).map(|(x, y)| x * y).sum();
            assert!(
                (h - ev.gauss_newton[(a, b)]).abs() < 1e-6 * scale,
                "H {a} {b}"
            );
        }
    }
    let c: f64 = r0.iter().map(|r| 0.5 * r * r).sum();
    assert!((c - ev.cost).abs() < 1e-12 * c);
}

/// Fits `m` from `th0`, the first `n_fixed` parameters held, to its noise-free simulation
/// from `truth` (600 samples); the solution and the largest output error.
fn refit<M: NonlinearTerms>(
    m: &M,
    truth: &[f64],
    th0: &[f64],
    n_fixed: usize,
    max_iter: usize,
) -> (crate::optim::Solution, f64) {
    let u: Vec<f64> = signal(600, 1, 11).iter().map(|v| 2.0 * v).collect();
    let (y, _) = simulation::simulate(m, truth, &u, None).unwrap();
    let data = [PnlssData {
        u: &u,
        y: &y,
        skip: 0,
    }];
    let opts = Options {
        fixed: Some((0..truth.len()).map(|k| k < n_fixed).collect()),
        max_iter,
        tol_cost: 1e-30,
        tol_gradient: 1e-30,
        tol_step: 1e-14,
        ..Default::default()
    };
    let sol = simulation::estimate(m, &data, th0, &opts, &mut |_| Flow::Continue).unwrap();
    let (yh, _) = simulation::simulate(m, &sol.theta, &u, None).unwrap();
    let err = yh
        .iter()
        .zip(&y)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    (sol, err)
}

#[test]
fn known_coefficients_recovered_from_noise_free_data() {
    let (m, truth) = model();
    // The simulation error is invariant under a change of state basis (the full monomial
    // sets span the same space in any basis), so the basis is pinned by holding the linear
    // part at its true value; the nonlinear coefficients start at zero.
    let mut th0 = truth.clone();
    th0[12..].iter_mut().for_each(|v| *v = 0.0);
    let (sol, fit) = refit(&m, &truth, &th0, 12, 200);
    let err = sol
        .theta
        .iter()
        .zip(&truth)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(fit < 1e-9, "output error {fit}");
    assert!(err < 1e-6, "parameter error {err}");
}

#[test]
fn divergence_is_reported_and_rejected() {
    let zeta = Monomials::new(1, 1, Terms::States, &[2]).unwrap();
    let m = Pnlss::new(1, 1, 1, zeta, Monomials::empty(1));
    let th = [0.5, 1.0, 1.0, 0.0, 1.0];
    let u = vec![3.0; 50];
    assert!(m.simulate(&th, &u, None).is_err());
    let y = vec![0.0; 50];
    let ev = m.cost(
        &th,
        &[PnlssData {
            u: &u,
            y: &y,
            skip: 0,
        }],
        true,
    );
    assert!(ev.cost.is_infinite());
    let e = estimate(
        &m,
        &[PnlssData {
            u: &u,
            y: &y,
            skip: 0,
        }],
        &th,
        &Options::default(),
        &mut |_| Flow::Continue,
    );
    assert!(e.is_err());
}

#[test]
fn neural_section_gradient_matches_finite_differences() {
    use super::neural::NeuralSs;
    let m = NeuralSs::new(2, 1, 2, &[5, 3], Some(&[4]), &[3], 3);
    let np = m.n_params();
    let mut p: Vec<f64> = signal(np, 1, 21).iter().map(|v| 0.6 * v).collect();
    p[..4].copy_from_slice(&[0.5, 0.1, -0.2, 0.4]);
    let u = signal(80, 1, 5);
    let y = signal(80, 2, 6);
    let mut g = vec![0.0; np];
    let l0 = m.section(&p, &u, &y, 10, 25, 0.01, &mut g).unwrap();
    let mut dummy = vec![0.0; np];
    for a in 0..np {
        let h = 1e-6;
        let (mut pp, mut pm) = (p.clone(), p.clone());
        pp[a] += h;
        pm[a] -= h;
        let lp = m.section(&pp, &u, &y, 10, 25, 0.01, &mut dummy).unwrap();
        let lm = m.section(&pm, &u, &y, 10, 25, 0.01, &mut dummy).unwrap();
        let fd = (lp - lm) / (2.0 * h);
        assert!(
            (fd - g[a]).abs() < 1e-6 * (1.0 + fd.abs()),
            "param {a}: {fd} vs {}",
            g[a]
        );
    }
    assert!(l0 > 0.0);
}

#[test]
fn neural_penalised_gradient_matches_finite_differences() {
    use super::neural::{penalty, NeuralSs};
    let m = NeuralSs::new(2, 1, 1, &[4], Some(&[3]), &[], 3);
    let np = m.n_params();
    let p: Vec<f64> = signal(np, 1, 31).iter().map(|v| 0.5 * v).collect();
    let p0: Vec<f64> = signal(np, 1, 32).iter().map(|v| 0.5 * v).collect();
    let w: Vec<f64> = (0..np).map(|i| 0.05 * (i % 3) as f64).collect();
    let (u, y) = (signal(60, 1, 7), signal(60, 1, 8));
    let crit = |q: &[f64], g: &mut [f64]| {
        m.section(q, &u, &y, 5, 30, 0.02, g).unwrap() + penalty(q, &p0, &w, g)
    };
    let mut g = vec![0.0; np];
    crit(&p, &mut g);
    let mut dummy = vec![0.0; np];
    let mut moved = 0;
    for a in 0..np {
        let h = 1e-6;
        let (mut pp, mut pm) = (p.clone(), p.clone());
        pp[a] += h;
        pm[a] -= h;
        let fd = (crit(&pp, &mut dummy) - crit(&pm, &mut dummy)) / (2.0 * h);
        assert!(
            (fd - g[a]).abs() < 1e-6 * (1.0 + fd.abs()),
            "param {a}: {fd} vs {}",
            g[a]
        );
        moved += usize::from(w[a] > 0.0);
    }
    // the penalty alone: zero at the start, its gradient w (p - p0)
    let mut g0 = vec![0.0; np];
    assert_eq!(penalty(&p0, &p0, &w, &mut g0), 0.0);
    assert!(g0.iter().all(|v| *v == 0.0) && moved > np / 2);
}

/// A 2-state, 1-input, 2-output decoupled model with 2 branches of degrees 2 and 3.
fn decoupled() -> (Decoupled, Vec<f64>) {
    let m = Decoupled::new(2, 1, 2, 2, vec![2, 3]).unwrap();
    let (_, mut th) = model();
    th.truncate(12);
    // V (2 x 3), W (2 x 2), c (2 x 2), e0 (2), f0 (2)
    th.extend([0.8, -0.4, 0.5, 0.2, 0.9, -0.6]);
    th.extend([0.3, -0.2, 0.1, 0.25]);
    th.extend([0.5, -0.4, -0.3, 0.2]);
    th.extend([0.05, -0.02, 0.1, -0.1]);
    assert_eq!(th.len(), m.n_params());
    (m, th)
}

#[test]
fn decoupled_sensitivity_jacobian_matches_finite_differences() {
    let (m, th) = decoupled();
    check_jacobian(&m, &th);
    // with the branch arguments clamped to the middle 60 % of their range
    let (_, xs) = m.simulate(&th, &signal(60, 1, 3), None).unwrap();
    let u = signal(60, 1, 3);
    let (mut lo, mut hi) = (vec![f64::MAX; 2], vec![f64::MIN; 2]);
    for t in 0..60 {
        let z = [xs[2 * t], xs[2 * t + 1], u[t]];
        for k in 0..2 {
            let s: f64 = (0..3).map(|j| th[12 + 3 * k + j] * z[j]).sum();
            lo[k] = lo[k].min(s);
            hi[k] = hi[k].max(s);
        }
    }
    let (lo, hi): (Vec<f64>, Vec<f64>) = (0..2)
        .map(|k| (lo[k] + 0.2 * (hi[k] - lo[k]), hi[k] - 0.2 * (hi[k] - lo[k])))
        .unzip();
    let mc = m.clone().with_range(lo, hi).unwrap();
    let (yc, _) = mc.simulate(&th, &u, None).unwrap();
    let (y, _) = m.simulate(&th, &u, None).unwrap();
    assert!(yc.iter().zip(&y).any(|(a, b)| (a - b).abs() > 1e-6));
    check_jacobian(&mc, &th);
    assert!(m.clone().with_range(vec![0.0], vec![1.0]).is_err());
    assert!(Decoupled::new(2, 1, 2, 0, vec![2]).is_err());
    assert!(Decoupled::new(2, 1, 2, 1, vec![1]).is_err());
}

#[test]
fn decoupled_known_model_reproduced_from_noise_free_data() {
    // The branch scales are free (W_k c_k is what matters) and so is the state basis: the
    // linear part and V are held at their true values and the simulated output compared.
    let (m, truth) = decoupled();
    let mut th0 = truth.clone();
    th0[18..22].iter_mut().for_each(|v| *v = 0.0); // W = 0: the start is linear
    th0[22..26].copy_from_slice(&[1.0, 1.0, 1.0, 1.0]);
    th0[26..].iter_mut().for_each(|v| *v = 0.0);
    let (sol, err) = refit(&m, &truth, &th0, 18, 300);
    assert!(err < 1e-9, "output error {err}");
    // the products W_ik c_kd are identified
    for i in 0..2 {
        for k in 0..2 {
            for d in 0..2 {
                let p = |t: &[f64]| t[18 + 2 * i + k] * t[22 + 2 * k + d];
                assert!((p(&sol.theta) - p(&truth)).abs() < 1e-6, "W c {i} {k} {d}");
            }
        }
    }
}

#[test]
fn a_stable_linear_part_is_kept_where_the_free_fit_leaves_it() {
    // x(t+1) = 1.02 x + u, y = x: the free fit recovers the unstable pole; held stable, the
    // fit ends inside the unit circle, below its start's cost
    let free = Pnlss::new(1, 1, 1, Monomials::empty(2), Monomials::empty(2));
    let held = free.clone().with_stable_linear();
    let u = signal(60, 1, 5);
    let (y, _) = free.simulate(&[1.02, 1.0, 1.0, 0.0], &u, None).unwrap();
    let data = [PnlssData {
        u: &u,
        y: &y,
        skip: 0,
    }];
    let start = [0.5, 1.0, 1.0, 0.0];
    let opts = Options::default();
    let f = estimate(&free, &data, &start, &opts, &mut |_| Flow::Continue).unwrap();
    assert!((f.theta[0] - 1.02).abs() < 1e-6, "{:?}", f.theta);
    let h = estimate(&held, &data, &start, &opts, &mut |_| Flow::Continue).unwrap();
    assert!(h.theta[0].abs() < 1.0 && h.theta[0] > 0.9, "{:?}", h.theta);
    assert!(h.cost <= free.cost(&start, &data, false).cost);
    // the admissible set and its margin: the spectral radius of A less 1
    let a = [0.5, 0.0, 0.0, 1.2];
    let two = Pnlss::new(2, 1, 1, Monomials::empty(3), Monomials::empty(3));
    let mut th = vec![0.0; two.n_params()];
    th[..4].copy_from_slice(&a);
    assert!(simulation::linear_admissible(&two, &th));
    assert_eq!(simulation::linear_margin(&two, &th), None);
    let two = two.with_stable_linear();
    assert!(!simulation::linear_admissible(&two, &th));
    assert!((simulation::linear_margin(&two, &th).unwrap() - 0.2).abs() < 1e-12);
}
