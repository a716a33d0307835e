#![allow(clippy::field_reassign_with_default)]
use super::*;
use crate::model::StateSpace;
use crate::optim::{Flow, Problem};
use faer::{mat, Mat};

pub(super) fn noise(n: usize, c: usize, seed: u64) -> Mat<f64> {
    let mut s = seed;
    Mat::from_fn(n, c, |_, _| {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    })
}

pub(super) fn truth() -> (StateSpace, Mat<f64>) {
    let a = mat![[0.7, 0.2, 0.0], [-0.2, 0.7, 0.1], [0.0, 0.0, -0.5]];
    let b = mat![[1.0, 0.0], [0.3, 1.0], [0.5, -0.4]];
    let c = mat![[1.0, 0.0, 0.4], [0.0, 1.0, -0.3]];
    let d = mat![[0.0, 0.0], [0.0, 0.0]];
    let k = mat![[0.3, 0.0], [0.1, 0.2], [0.0, 0.1]];
    (StateSpace::new(a, b, c, d).unwrap(), k)
}

/// [`truth`] with a non-zero `D`.
pub(super) fn truth_with_feedthrough() -> (StateSpace, Mat<f64>) {
    let (sys, k) = truth();
    let d = mat![[0.2, -0.1], [0.0, 0.3]];
    let sys = StateSpace::new(sys.a.clone(), sys.b.clone(), sys.c.clone(), d).unwrap();
    (sys, k)
}

/// Innovation-form data: x+ = A x + B u + K e, y = C x + D u + e.
pub(super) fn data(
    sys: &StateSpace,
    k: &Mat<f64>,
    u: &Mat<f64>,
    e: &Mat<f64>,
    x0: &[f64],
) -> Mat<f64> {
    let (n, l) = (sys.n_states(), sys.n_outputs());
    let mut x = Mat::from_fn(n, 1, |i, _| x0[i]);
    let mut y = Mat::zeros(u.nrows(), l);
    for t in 0..u.nrows() {
        let ut = Mat::from_fn(u.ncols(), 1, |i, _| u[(t, i)]);
        let et = Mat::from_fn(e.ncols(), 1, |i, _| e[(t, i)]);
        let yt = &sys.c * &x + &sys.d * &ut + &et;
        for i in 0..l {
            y[(t, i)] = yt[(i, 0)];
        }
        x = &sys.a * &x + &sys.b * &ut + k * &et;
    }
    y
}

pub(super) fn options(
    focus: Focus,
    d: bool,
    k: bool,
    x0: Vec<InitialState>,
    block: usize,
) -> PemOptions {
    let mut o = PemOptions::default();
    o.focus = focus;
    o.estimate_d = d;
    o.estimate_k = k;
    o.x0 = x0;
    o.block = block;
    o
}

/// The full evaluation with the paths `(structured, modal, halve)`, the defaults restored.
fn evaluate_with(
    pr: &mut Predictor,
    th: &[f64],
    paths: (bool, bool, bool),
) -> crate::optim::Evaluation {
    (pr.structured, pr.modal, pr.halve) = paths;
    let ev = pr.evaluate(th, true).unwrap();
    (pr.structured, pr.modal, pr.halve) = (true, true, true);
    ev
}

fn sorted_poles(sys: &StateSpace) -> Vec<(f64, f64)> {
    let mut p = sys.poles().unwrap();
    p.sort_by(|a, b| a.partial_cmp(b).unwrap());
    p
}

fn pole_err(a: &StateSpace, b: &StateSpace) -> f64 {
    sorted_poles(a)
        .iter()
        .zip(sorted_poles(b))
        .map(|(p, q)| (p.0 - q.0).hypot(p.1 - q.1))
        .fold(0.0, f64::max)
}

fn perturbed(sys: &StateSpace, eps: f64) -> StateSpace {
    let pa = noise(3, 3, 99);
    let pb = noise(3, 2, 98);
    let pc = noise(2, 3, 97);
    StateSpace::new(
        &sys.a + &pa * faer::Scale(eps),
        &sys.b + &pb * faer::Scale(eps),
        &sys.c + &pc * faer::Scale(eps),
        sys.d.clone(),
    )
    .unwrap()
}

fn run(
    start: &StateSpace,
    k: Option<&Mat<f64>>,
    exps: &[(&Mat<f64>, &Mat<f64>)],
    o: &PemOptions,
) -> PemResult {
    let views: Vec<_> = exps.iter().map(|(u, y)| (u.as_ref(), y.as_ref())).collect();
    pem(start, k.map(|k| k.as_ref()), &views, o, &mut |_| {
        Flow::Continue
    })
    .unwrap()
}

#[test]
fn exact_start_stays_exact() {
    let (sys, k) = truth();
    let u = noise(400, 2, 1);
    let y = data(&sys, &k, &u, &Mat::zeros(400, 2), &[0.0; 3]);
    for limit in [400, 0] {
        let mut o = PemOptions::default();
        o.optim.eigen_limit = limit;
        let r = run(&sys, Some(&k), &[(&u, &y)], &o);
        assert!(pole_err(&r.sys, &sys) < 1e-8, "{}", pole_err(&r.sys, &sys));
        let tr = r.innovation_covariance[(0, 0)] + r.innovation_covariance[(1, 1)];
        assert!(tr < 1e-24, "{tr}");
    }
}

#[test]
fn perturbed_start_converges_noise_free() {
    let (sys, k) = truth();
    let u = noise(500, 2, 2);
    let y = data(&sys, &k, &u, &Mat::zeros(500, 2), &[0.0; 3]);
    for (focus, limit) in [
        (Focus::Prediction, 400),
        (Focus::Simulation, 400),
        // the large-problem step (Cholesky, no explicit local coordinates)
        (Focus::Prediction, 0),
        (Focus::Simulation, 0),
    ] {
        let mut o = PemOptions::default();
        o.focus = focus;
        o.optim.max_iter = 100;
        o.optim.eigen_limit = limit;
        let start = perturbed(&sys, 0.05);
        assert!(pole_err(&start, &sys) > 1e-3);
        let r = run(&start, Some(&k), &[(&u, &y)], &o);
        // the large-problem step (no explicit local coordinates, damping in the full
        // Marquardt metric) creeps on noise-free prediction errors: 2e-7 after 100 iterations
        let tol = if limit == 0 { 1e-6 } else { 1e-7 };
        assert!(
            pole_err(&r.sys, &sys) < tol,
            "{focus:?} {limit}: {} {:?} {} {:?}",
            pole_err(&r.sys, &sys),
            r.solution.stop,
            r.solution.iterations,
            r.solution.history
        );
        assert!(
            r.solution
                .history
                .windows(2)
                .all(|w| w[1] <= w[0] * (1.0 + 1e-12))
                || o.reweight
        );
        assert!(r.solution.iterations >= 1);
    }
}

#[test]
fn noisy_prediction_recovers_k_and_beats_simulation_focus() {
    let (sys, k) = truth();
    let n = 3000;
    let u = noise(n, 2, 3);
    let e = noise(n, 2, 4) * faer::Scale(0.3);
    let y = data(&sys, &k, &u, &e, &[0.0; 3]);
    let start = perturbed(&sys, 0.03);
    let pr = run(
        &start,
        Some(&Mat::zeros(3, 2)),
        &[(&u, &y)],
        &PemOptions::default(),
    );
    // K estimated: predictor errors approach the innovation variance 0.09/12
    let var = 0.09 / 12.0;
    assert!((pr.innovation_covariance[(0, 0)] / var - 1.0).abs() < 0.1);
    let mut o = PemOptions::default();
    o.focus = Focus::Simulation;
    let sr = run(&start, None, &[(&u, &y)], &o);
    assert!(sr.k.norm_l2() == 0.0);
    assert!(sr.innovation_covariance[(0, 0)] > 1.1 * pr.innovation_covariance[(0, 0)]);
    assert!(pole_err(&pr.sys, &sys) < 0.05);
    // covariance: rank p - n^2 (the similarity directions are not identifiable)
    let p = pr.theta.len();
    assert_eq!(pr.covariance.rank, p - 9);
}

#[test]
fn fixed_k_stays_and_d_zero_or_free() {
    let (mut sys, k) = truth();
    sys.d = mat![[0.5, 0.0], [0.0, -0.2]];
    let u = noise(500, 2, 5);
    let y = data(&sys, &k, &u, &Mat::zeros(500, 2), &[0.0; 3]);
    let mut start = perturbed(&sys, 0.02);
    start.d = Mat::zeros(2, 2);
    let mut o = PemOptions::default();
    o.estimate_k = false;
    let kf = Mat::<f64>::zeros(3, 2);
    let fixed = run(&start, Some(&kf), &[(&u, &y)], &o);
    assert_eq!(fixed.k, kf);
    assert!(fixed.sys.d.norm_l2() == 0.0);
    o.estimate_d = true;
    o.optim.max_iter = 100;
    let free = run(&start, Some(&kf), &[(&u, &y)], &o);
    assert!((&free.sys.d - &sys.d).norm_l2() < 1e-7);
    assert!(pole_err(&free.sys, &sys) < 1e-7);
    assert!(fixed.innovation_covariance[(0, 0)] > 1e-6);
}

#[test]
fn initial_state_estimated_zero_given_and_multi_experiment() {
    let (sys, k) = truth();
    let x0 = [2.0, -1.0, 1.5];
    let u1 = noise(300, 2, 6);
    let u2 = noise(300, 2, 7);
    let y1 = data(&sys, &k, &u1, &Mat::zeros(300, 2), &x0);
    let y2 = data(&sys, &k, &u2, &Mat::zeros(300, 2), &[0.0; 3]);
    let mut o = PemOptions::default();
    o.focus = Focus::Simulation;
    o.optim.max_iter = 100;
    // exact model, x0 estimated: recovers x0 and stays exact
    let est = run(&sys, None, &[(&u1, &y1)], &o);
    for i in 0..3 {
        assert!((est.x0[0][i] - x0[i]).abs() < 1e-8);
    }
    // x0 = 0 on data with a non-zero initial state: the model must move away from the truth
    o.x0 = vec![InitialState::Zero];
    let zero = run(&sys, None, &[(&u1, &y1)], &o);
    assert!(zero.x0[0].iter().all(|&v| v == 0.0));
    assert!(pole_err(&zero.sys, &sys) > 1e-6);
    // given x0: the truth again is exact and stays
    o.x0 = vec![InitialState::Given(x0.to_vec())];
    let given = run(&sys, None, &[(&u1, &y1)], &o);
    assert!(pole_err(&given.sys, &sys) < 1e-8);
    // two experiments, one x0 each: from a perturbed start both are fitted exactly
    o.x0 = vec![InitialState::Estimate, InitialState::Zero];
    let start = perturbed(&sys, 0.03);
    let two = run(&start, None, &[(&u1, &y1), (&u2, &y2)], &o);
    assert!(
        pole_err(&two.sys, &sys) < 1e-7,
        "{}",
        pole_err(&two.sys, &sys)
    );
    assert_eq!(two.n_samples, 600);
    // x0 lives in the model's state basis: compare the free responses C A^t x0
    let free = |s: &StateSpace, x: &[f64]| {
        let mut v = Mat::from_fn(3, 1, |i, _| x[i]);
        let mut out = Vec::new();
        for _ in 0..6 {
            let yv = &s.c * &v;
            out.extend((0..2).map(|i| yv[(i, 0)]));
            v = &s.a * &v;
        }
        out
    };
    let (fa, fb) = (free(&two.sys, &two.x0[0]), free(&sys, &x0));
    assert!(fa.iter().zip(&fb).all(|(a, b)| (a - b).abs() < 1e-6));
    // a single experiment alone gives a different (noisy-free but shorter) fit path: the
    // second experiment changes the result on noisy data
    let e = noise(300, 2, 8) * faer::Scale(0.2);
    let y2n = data(&sys, &k, &u2, &e, &[0.0; 3]);
    let a = run(&start, None, &[(&u1, &y1), (&u2, &y2n)], &o);
    o.x0 = vec![InitialState::Estimate];
    let b = run(&start, None, &[(&u1, &y1)], &o);
    assert!(pole_err(&a.sys, &b.sys) > 1e-6);
}

#[test]
fn unstable_start_is_an_error_and_bad_input_is_reported() {
    let (sys, _) = truth();
    let u = noise(100, 2, 9);
    let y = noise(100, 2, 10);
    let mut bad = sys.clone();
    bad.a[(2, 2)] = 1.5;
    let mut o = PemOptions::default();
    o.focus = Focus::Simulation;
    let err = pem(&bad, None, &[(u.as_ref(), y.as_ref())], &o, &mut |_| {
        Flow::Continue
    })
    .unwrap_err()
    .to_string();
    assert!(err.contains("unstable"), "{err}");
    let y3 = noise(100, 3, 10);
    assert!(pem(&sys, None, &[(u.as_ref(), y3.as_ref())], &o, &mut |_| {
        Flow::Continue
    })
    .is_err());
}

#[test]
fn search_stays_stable_from_a_start_near_the_boundary() {
    let (sys, k) = truth();
    let u = noise(400, 2, 11);
    let e = noise(400, 2, 12) * faer::Scale(0.5);
    let y = data(&sys, &k, &u, &e, &[0.0; 3]);
    let mut start = sys.clone();
    start.a[(2, 2)] = -0.98;
    let mut o = PemOptions::default();
    o.focus = Focus::Simulation;
    let r = run(&start, None, &[(&u, &y)], &o);
    let rad = crate::linalg::spectral_radius(r.sys.a.as_ref()).unwrap();
    assert!(rad < 1.0);
}

#[test]
fn local_coordinates_and_gradient_check() {
    // analytic gradient equals finite differences of the cost
    let (sys, k) = truth();
    let u = noise(200, 2, 13);
    let e = noise(200, 2, 14) * faer::Scale(0.2);
    let y = data(&sys, &k, &u, &e, &[0.3, 0.0, -0.2]);
    let mut o = PemOptions::default();
    o.estimate_d = true;
    o.reweight = false;
    let views = [(u.as_ref(), y.as_ref())];
    let mut pr = Predictor::new(&sys, Some(k.as_ref()), &views, &o).unwrap();
    let th = pr.pack(&sys, k.as_ref(), &[vec![0.1, 0.2, 0.3]]);
    let ev = pr.evaluate(&th, true).unwrap();
    for j in 0..th.len() {
        let h = 1e-6;
        let mut tp = th.clone();
        tp[j] += h;
        let mut tm = th.clone();
        tm[j] -= h;
        let fd = (pr.evaluate(&tp, false).unwrap().cost - pr.evaluate(&tm, false).unwrap().cost)
            / (2.0 * h);
        assert!(
            (fd - ev.gradient[j]).abs() < 1e-5 * (1.0 + fd.abs()),
            "param {j}: {fd} vs {}",
            ev.gradient[j]
        );
    }
    // the basis is orthogonal to the similarity directions and has p - n^2 columns
    let q = pr.search_basis(&th, &vec![1.0; th.len()]).unwrap().unwrap();
    assert_eq!(q.ncols(), th.len() - 9);
    // the similarity directions are a null space of J^T W J and orthogonal to the gradient
    let tan = pr.orbit_tangent(&th).unwrap();
    // in the search's metric (here the Marquardt scaling, spread over orders of magnitude):
    // diag(s) T orthonormal and orthogonal to diag(s) tan, the same number of directions
    let s: Vec<f64> = (0..th.len())
        .map(|i| ev.gauss_newton[(i, i)].max(0.0).sqrt().max(1e-3) * 10f64.powi(i as i32 % 7))
        .collect();
    let qs = pr.search_basis(&th, &s).unwrap().unwrap();
    assert_eq!(qs.ncols(), q.ncols());
    let sq = Mat::from_fn(qs.nrows(), qs.ncols(), |i, j| s[i] * qs[(i, j)]);
    let st = Mat::from_fn(tan.nrows(), tan.ncols(), |i, j| s[i] * tan[(i, j)]);
    let gram = sq.transpose() * &sq;
    for a in 0..gram.nrows() {
        for b in 0..gram.ncols() {
            let e = f64::from(u8::from(a == b));
            assert!(
                (gram[(a, b)] - e).abs() < 1e-10,
                "({a}, {b}): {}",
                gram[(a, b)]
            );
        }
    }
    let cross = sq.transpose() * &st;
    assert!(
        cross.norm_max() < 1e-9 * st.norm_max(),
        "{}",
        cross.norm_max()
    );
    let ht = &ev.gauss_newton * &tan;
    let scale = ev.gauss_newton.norm_max() * tan.norm_max();
    eprintln!("H tan {} of {scale}", ht.norm_max());
    assert!(ht.norm_max() < 1e-9 * scale, "{} of {scale}", ht.norm_max());
    let gnorm = ev.gradient.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    for c in 0..tan.ncols() {
        let gt: f64 = (0..th.len()).map(|i| ev.gradient[i] * tan[(i, c)]).sum();
        assert!(gt.abs() < 1e-9 * gnorm * scale.max(1.0), "{gt}");
    }
}

/// The structured `J^T W J` (predictor parameterisation, Kronecker blocks for C and D) equals
/// the plain one that forms every Jacobian row, for every option that changes its layout.
#[test]
fn structured_gauss_newton_equals_the_plain_one() {
    let (sys, k) = truth_with_feedthrough();
    let u1 = noise(150, 2, 21);
    let u2 = noise(90, 2, 22);
    let y1 = data(
        &sys,
        &k,
        &u1,
        &(noise(150, 2, 23) * faer::Scale(0.3)),
        &[0.3, 0.0, -0.2],
    );
    let y2 = data(
        &sys,
        &k,
        &u2,
        &(noise(90, 2, 24) * faer::Scale(0.3)),
        &[0.0; 3],
    );
    let views = [(u1.as_ref(), y1.as_ref()), (u2.as_ref(), y2.as_ref())];
    for (focus, est_d, est_k, x0) in [
        (Focus::Prediction, true, true, vec![InitialState::Estimate]),
        (
            Focus::Prediction,
            false,
            true,
            vec![InitialState::Estimate, InitialState::Zero],
        ),
        (Focus::Prediction, true, false, vec![InitialState::Zero]),
        (Focus::Simulation, true, false, vec![InitialState::Estimate]),
        (
            Focus::Simulation,
            false,
            false,
            vec![InitialState::Given(vec![0.1, 0.2, 0.3])],
        ),
    ] {
        let o = options(focus, est_d, est_k, x0, 7);
        let mut pr = Predictor::new(&sys, Some(k.as_ref()), &views, &o).unwrap();
        let x0s = vec![vec![0.1, -0.2, 0.3], vec![0.05, 0.0, 0.1]];
        let th = pr.pack(&sys, k.as_ref(), &x0s);
        pr.reweight_at(&th).unwrap();
        assert!(super::modal::modal_form((&sys.a - &k * &sys.c).as_ref()).is_some());
        let fast = pr.evaluate(&th, true).unwrap();
        pr.modal = false;
        let kron = pr.evaluate(&th, true).unwrap();
        pr.structured = false;
        let plain = pr.evaluate(&th, true).unwrap();
        let dk = (&kron.gauss_newton - &plain.gauss_newton).norm_max();
        assert!(dk < 1e-11 * plain.gauss_newton.norm_max(), "{dk}");
        let scale = plain.gauss_newton.norm_max();
        let dh = (&fast.gauss_newton - &plain.gauss_newton).norm_max();
        assert!(
            dh < 1e-11 * scale,
            "{focus:?} {est_d} {est_k}: {dh} vs {scale}"
        );
        let gs = plain.gradient.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (a, b) in fast.gradient.iter().zip(&plain.gradient) {
            assert!((a - b).abs() < 1e-11 * gs, "{a} vs {b}");
        }
        assert!((fast.cost - plain.cost).abs() < 1e-12 * plain.cost);
        pr.structured = true;
        pr.modal = true;
        let chord = pr.gradient_only(&th).unwrap().unwrap();
        for (a, b) in chord.gradient.iter().zip(&fast.gradient) {
            assert!((a - b).abs() < 1e-11 * gs, "{a} vs {b}");
        }
        assert_eq!(chord.gauss_newton.nrows(), 0);
        // another weighting at the same point: the cached sums give the same matrix
        let mut th2 = th.clone();
        th2[0] += 0.01;
        pr.reweight_at(&th2).unwrap();
        let cached = pr.evaluate(&th, true).unwrap();
        let fresh = evaluate_with(&mut pr, &th, (true, false, true));
        let scale = fresh.gauss_newton.norm_max();
        let dc = (&cached.gauss_newton - &fresh.gauss_newton).norm_max();
        assert!(dc < 1e-11 * scale, "{dc} vs {scale}");
        assert!((cached.cost - fresh.cost).abs() < 1e-12 * fresh.cost);
        assert!((fast.cost - fresh.cost).abs() > 1e-9 * fresh.cost);
    }
}

/// The parallel products of the structured evaluation split the output only: the Gauss-Newton
/// matrix and gradient are bit-for-bit the same for any thread count.
#[test]
fn structured_evaluation_is_identical_for_any_thread_count() {
    let n = 6;
    let a = Mat::from_fn(n, n, |i, j| {
        if i == j {
            0.5
        } else {
            0.4 * noise(n, n, 31)[(i, j)]
        }
    });
    let b = noise(n, 2, 32);
    let c = noise(6, n, 33);
    let sys = StateSpace::new(a, b, c, Mat::zeros(6, 2)).unwrap();
    let k = noise(n, 6, 34) * faer::Scale(0.1);
    let u = noise(400, 2, 35);
    let e = noise(400, 6, 36) * faer::Scale(0.2);
    let y = data(&sys, &k, &u, &e, &[0.0; 6]);
    let views = [(u.as_ref(), y.as_ref())];
    let o = PemOptions::default();
    let mut pr = Predictor::new(&sys, Some(k.as_ref()), &views, &o).unwrap();
    let th = pr.pack(&sys, k.as_ref(), &[vec![0.0; n]]);
    pr.reweight_at(&th).unwrap();
    let mut run = |threads: usize| {
        crate::optim::dense::on_threads(threads, || pr.evaluate(&th, true).unwrap())
    };
    let serial = run(1);
    let parallel = run(2);
    assert_eq!(serial.gradient, parallel.gradient);
    assert!(serial.gauss_newton == parallel.gauss_newton);
}

/// The modal Gram matrix formed from the first rows of the complex pairs only (the second
/// row's sensitivity is a rotation of the first's) equals the one carrying both rows, and the
/// plain one, to round-off: complex pairs and real poles, with every layout option that adds
/// state-moving columns (K, several initial states). With repeated poles (a complex pair
/// twice, a real pole twice) the modal form may be refused (ill-conditioned eigenvectors):
/// then the evaluation falls back to the structured path, and either way equals the plain one.
#[test]
fn halved_modal_gram_equals_the_full_one() {
    let n = 8;
    for repeated in [false, true] {
        // in random coordinates: 0.6 +- 0.3i, 0.3 +- 0.5i (or 0.6 +- 0.3i again),
        // -0.4 and 0.5 (or 0.5 twice), -0.7 +- 0.2i
        let mut blk = Mat::<f64>::zeros(n, n);
        let second = if repeated { (0.6, 0.3) } else { (0.3, 0.5) };
        for (o, re, im) in [(0, 0.6, 0.3), (2, second.0, second.1), (6, -0.7, 0.2)] {
            blk[(o, o)] = re;
            blk[(o + 1, o + 1)] = re;
            blk[(o, o + 1)] = im;
            blk[(o + 1, o)] = -im;
        }
        blk[(4, 4)] = if repeated { 0.5 } else { -0.4 };
        blk[(5, 5)] = 0.5;
        let mut tr = noise(n, n, 41) * faer::Scale(0.5);
        for i in 0..n {
            tr[(i, i)] += 1.0;
        }
        let tri = faer::linalg::solvers::DenseSolveCore::inverse(&tr.partial_piv_lu());
        let a = &tr * &blk * &tri;
        let b = noise(n, 2, 42);
        let c = noise(3, n, 43);
        let d = noise(3, 2, 44) * faer::Scale(0.2);
        let sys = StateSpace::new(a, b, c, d).unwrap();
        let near = |re: f64, im: f64| {
            let p = sys.poles().unwrap();
            p.iter()
                .filter(|z| (z.0 - re).hypot(z.1 - im) < 1e-6)
                .count()
        };
        let twice = if repeated { 2 } else { 1 };
        assert_eq!((near(0.5, 0.0), near(0.6, 0.3)), (twice, twice));
        let modal = super::modal::modal_form(sys.a.as_ref()).is_some();
        assert!(modal || repeated);
        let kz = Mat::<f64>::zeros(n, 3);
        let u1 = noise(120, 2, 45);
        let u2 = noise(70, 2, 46);
        let e1 = noise(120, 3, 47) * faer::Scale(0.3);
        let e2 = noise(70, 3, 48) * faer::Scale(0.3);
        let y1 = data(&sys, &kz, &u1, &e1, &[0.2; 8]);
        let y2 = data(&sys, &kz, &u2, &e2, &[0.0; 8]);
        let views = [(u1.as_ref(), y1.as_ref()), (u2.as_ref(), y2.as_ref())];
        for (focus, est_k, x0) in [
            (Focus::Prediction, true, vec![InitialState::Estimate]),
            (
                Focus::Simulation,
                false,
                vec![InitialState::Estimate, InitialState::Zero],
            ),
        ] {
            let o = options(focus, true, est_k, x0, 9);
            let mut pr = Predictor::new(&sys, Some(kz.as_ref()), &views, &o).unwrap();
            let th = pr.pack(&sys, kz.as_ref(), &[vec![0.1; n], vec![-0.1; n]]);
            pr.reweight_at(&th).unwrap();
            let half = evaluate_with(&mut pr, &th, (true, true, true));
            let full = evaluate_with(&mut pr, &th, (true, true, false));
            let plain = evaluate_with(&mut pr, &th, (false, true, true));
            let scale = full.gauss_newton.norm_max();
            let dh = (&half.gauss_newton - &full.gauss_newton).norm_max();
            assert!(dh < 1e-13 * scale, "{focus:?}: {dh} vs {scale}");
            let dp = (&half.gauss_newton - &plain.gauss_newton).norm_max();
            assert!(dp < 1e-11 * scale, "{focus:?}: {dp} vs {scale}");
            let gs = full.gradient.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for ((a, b), c) in half
                .gradient
                .iter()
                .zip(&full.gradient)
                .zip(&plain.gradient)
            {
                assert!((a - b).abs() < 1e-13 * gs, "{a} vs {b}");
                assert!((a - c).abs() < 1e-11 * gs, "{a} vs {c}");
            }
            let chord = pr.gradient_only(&th).unwrap().unwrap();
            for (a, b) in chord.gradient.iter().zip(&full.gradient) {
                assert!((a - b).abs() < 1e-13 * gs, "{a} vs {b}");
            }
            assert!((half.cost - plain.cost).abs() < 1e-12 * plain.cost);
        }
    }
}

/// A model in the chart's form: a complex pair in a general 2x2 block, two real poles in one
/// 2x2 block, a real pole, a complex pair in rotation form (blocks 0-1, 2-3, 4, 5-6).
fn chart_model() -> (StateSpace, Vec<usize>) {
    let n = 7;
    let mut a = Mat::<f64>::zeros(n, n);
    for (i, j, v) in [
        (0, 0, 0.5),
        (0, 1, 0.4),
        (1, 0, -0.3),
        (1, 1, 0.6),
        (2, 2, 0.4),
        (2, 3, 0.3),
        (3, 2, 0.2),
        (3, 3, -0.2),
        (4, 4, 0.2),
        (5, 5, -0.6),
        (5, 6, 0.5),
        (6, 5, -0.5),
        (6, 6, -0.6),
    ] {
        a[(i, j)] = v;
    }
    let sys = StateSpace::new(a, noise(n, 2, 51), noise(3, n, 52), noise(3, 2, 53)).unwrap();
    (sys, vec![0, 0, 2, 2, 4, 5, 5])
}

/// In the modal chart the Gauss-Newton matrix and gradient of the parameters that move equal
/// the plain ones (every Jacobian row), the held entries of `A` get zero rows and columns,
/// and the chord gradient is the full one.
#[test]
fn modal_chart_gauss_newton_equals_the_plain_one() {
    let (sys, chart) = chart_model();
    let n = sys.n_states();
    let kz = Mat::<f64>::zeros(n, 3);
    let (u1, u2) = (noise(110, 2, 54), noise(60, 2, 55));
    let e = |rows: usize, seed: u64| noise(rows, 3, seed) * faer::Scale(0.3);
    let y1 = data(&sys, &kz, &u1, &e(110, 56), &[0.2; 7]);
    let y2 = data(&sys, &kz, &u2, &e(60, 57), &[0.0; 7]);
    let views = [(u1.as_ref(), y1.as_ref()), (u2.as_ref(), y2.as_ref())];
    for x0 in [
        vec![InitialState::Estimate],
        vec![InitialState::Estimate, InitialState::Zero],
    ] {
        let o = options(Focus::Simulation, true, false, x0, 8);
        let mut pr = Predictor::new(&sys, None, &views, &o).unwrap();
        pr.chart = Some(chart.clone());
        let th = pr.pack(&sys, kz.as_ref(), &[vec![0.1; n], vec![-0.1; n]]);
        pr.reweight_at(&th).unwrap();
        assert!(pr.modal_at(&th).is_some());
        let fast = evaluate_with(&mut pr, &th, (true, true, true));
        let plain = evaluate_with(&mut pr, &th, (false, true, true));
        let held = pr.chart_mask();
        assert_eq!(held.iter().filter(|&&h| h).count(), n * n - 4 - 4 - 1 - 4);
        let scale = plain.gauss_newton.norm_max();
        let gs = plain.gradient.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for i in 0..pr.p {
            if held[i] {
                assert_eq!(fast.gradient[i], 0.0);
                assert!((0..pr.p).all(|j| fast.gauss_newton[(i, j)] == 0.0));
                continue;
            }
            assert!((fast.gradient[i] - plain.gradient[i]).abs() < 1e-11 * gs);
            for j in (0..pr.p).filter(|&j| !held[j]) {
                let d = (fast.gauss_newton[(i, j)] - plain.gauss_newton[(i, j)]).abs();
                assert!(d < 1e-11 * scale, "({i}, {j}): {d} vs {scale}");
            }
        }
        let chord = pr.gradient_only(&th).unwrap().unwrap();
        for (a, b) in chord.gradient.iter().zip(&fast.gradient) {
            assert!((a - b).abs() < 1e-12 * gs, "{a} vs {b}");
        }
        // the orbit that keeps the blocks: 4 + 4 + 1 + 4 directions, orthogonal to the
        // gradient and null directions of the Gauss-Newton matrix
        let tan = pr.orbit_tangent(&th).unwrap();
        assert_eq!(tan.ncols(), 13);
        for col in 0..tan.ncols() {
            let v: Vec<f64> = (0..pr.p).map(|i| tan[(i, col)]).collect();
            assert!(v.iter().zip(&held).all(|(x, &h)| !h || *x == 0.0));
            let hv: f64 = (0..pr.p)
                .map(|i| {
                    (0..pr.p)
                        .map(|j| fast.gauss_newton[(i, j)] * v[j])
                        .sum::<f64>()
                        .abs()
                })
                .fold(0.0, f64::max);
            assert!(hv < 1e-10 * scale, "{hv}");
        }
        let basis = pr.local_basis(&th, &vec![1.0; th.len()]).unwrap().unwrap();
        assert_eq!(
            basis.ncols(),
            pr.p - held.iter().filter(|&&h| h).count() - 13
        );
    }
}

/// A search in the modal chart recovers a noise-free system and, on noisy data, reaches the
/// criterion of the search over every entry of `A` (the same minimum).
#[test]
fn modal_chart_search_reaches_the_full_search_minimum() {
    let (blk, _) = chart_model();
    let n = blk.n_states();
    // the same system in a random state basis
    let mut tr = noise(n, n, 61) * faer::Scale(0.5);
    for i in 0..n {
        tr[(i, i)] += 1.0;
    }
    let tri = faer::linalg::solvers::DenseSolveCore::inverse(&tr.partial_piv_lu());
    let sys = StateSpace::new(
        &tr * &blk.a * &tri,
        &tr * &blk.b,
        &blk.c * &tri,
        blk.d.clone(),
    )
    .unwrap();
    let kz = Mat::<f64>::zeros(n, 3);
    let u = noise(600, 2, 62);
    for sigma in [0.0, 0.2] {
        let y = data(
            &sys,
            &kz,
            &u,
            &(noise(600, 3, 63) * faer::Scale(sigma)),
            &[0.0; 7],
        );
        let start = perturbed_any(&sys, 0.02, 64);
        let mut costs = Vec::new();
        for on in [true, false] {
            let mut o = options(
                Focus::Simulation,
                true,
                false,
                vec![InitialState::Estimate],
                64,
            );
            o.reweight = false;
            o.modal_chart = on;
            o.optim.max_iter = 200;
            o.optim.tol_statistical = 0.0;
            o.optim.tol_cost = 1e-12;
            let r = run(&start, None, &[(&u, &y)], &o);
            if sigma == 0.0 {
                assert!(
                    pole_err(&r.sys, &sys) < 1e-7,
                    "{on}: {}",
                    pole_err(&r.sys, &sys)
                );
            }
            costs.push(r.solution.cost);
        }
        if sigma > 0.0 {
            let rel = (costs[0] - costs[1]).abs() / costs[1];
            assert!(rel < 1e-6, "{costs:?}");
        }
    }
}

fn perturbed_any(sys: &StateSpace, eps: f64, seed: u64) -> StateSpace {
    let (n, m, l) = (sys.n_states(), sys.n_inputs(), sys.n_outputs());
    StateSpace::new(
        &sys.a + &noise(n, n, seed) * faer::Scale(eps),
        &sys.b + &noise(n, m, seed + 1) * faer::Scale(eps),
        &sys.c + &noise(l, n, seed + 2) * faer::Scale(eps),
        sys.d.clone(),
    )
    .unwrap()
}

/// A defective `A` (a double pole, as procest's two real time constants reach on an
/// oscillating response) has no modal form: before, its singular eigenvector matrix was
/// inverted to inf/NaN, the norms that guard the condition skipped the NaN, and every
/// sensitivity of the fit came out NaN ("the Gauss-Newton matrix at the estimate is not
/// finite").
#[test]
fn a_defective_a_has_no_modal_form_and_finite_sensitivities() {
    // the sampled P2 model where procest's search ended: eigenvalues 0.832 twice
    let a = mat![
        [0.9850187721705859, 0.041598632923975684],
        [-0.5630741029097744, 0.6789265447884414]
    ];
    let jordan = mat![[0.8, 1.0], [0.0, 0.8]];
    for m in [&a, &jordan] {
        assert!(super::modal::modal_form(m.as_ref()).is_none());
        // nor an eigendecomposition (modal analysis says it is defective)
        assert!(crate::realization::modal::eigen_decomposition(m.as_ref()).is_err());
    }
    let sys = StateSpace::new(
        jordan.clone(),
        mat![[0.0], [1.0]],
        mat![[1.0, 0.0]],
        Mat::zeros(1, 1),
    )
    .unwrap();
    let n = 400;
    let u = Mat::<f64>::from_fn(n, 1, |t, _| if (t / 7) % 2 == 0 { 1.0 } else { -1.0 });
    let y = Mat::<f64>::from_fn(n, 1, |t, _| ((t as f64) * 0.3).sin());
    let views = vec![(u.as_ref(), y.as_ref())];
    let o = options(Focus::Simulation, false, false, vec![InitialState::Zero], 7);
    let k = Mat::<f64>::zeros(2, 1);
    let mut pr = Predictor::new(&sys, Some(k.as_ref()), &views, &o).unwrap();
    let th = pr.pack(&sys, k.as_ref(), &[vec![0.0, 0.0]]);
    let ev = pr.evaluate(&th, true).unwrap();
    assert!(ev.gauss_newton.as_ref().is_all_finite() && ev.cost.is_finite());
}

/// A record whose input stops: the simulated state and the initial state's sensitivities
/// decay to zero through the subnormal range, and are flushed to zero on the way (every
/// `FLUSH_EVERY` samples) by the cost pass and every Jacobian path alike: the costs agree
/// to the bit and the Gauss-Newton matrices as closely as on any record.
#[test]
fn a_record_whose_input_stops_gives_the_same_cost_on_every_path() {
    let (sys, k) = truth_with_feedthrough();
    let n = 4000;
    let mut u = noise(n, 2, 31);
    for t in 200..n {
        u[(t, 0)] = 0.0;
        u[(t, 1)] = 0.0;
    }
    let y = data(&sys, &k, &u, &Mat::zeros(n, 2), &[0.3, 0.0, -0.2]);
    let views = [(u.as_ref(), y.as_ref())];
    let o = options(
        Focus::Simulation,
        true,
        false,
        vec![InitialState::Estimate],
        64,
    );
    let mut pr = Predictor::new(&sys, None, &views, &o).unwrap();
    let th = pr.pack(
        &sys,
        Mat::<f64>::zeros(3, 2).as_ref(),
        &[vec![0.25, 0.05, -0.1]],
    );
    pr.reweight_at(&th).unwrap();
    let cost = pr.evaluate(&th, false).unwrap().cost;
    assert!(cost > 0.0 && cost.is_finite());
    let modal = evaluate_with(&mut pr, &th, (true, true, true));
    let structured = evaluate_with(&mut pr, &th, (true, false, false));
    let plain = evaluate_with(&mut pr, &th, (false, false, false));
    for ev in [&modal, &structured, &plain] {
        assert_eq!(ev.cost, cost);
    }
    let scale = plain.gauss_newton.norm_max();
    for ev in [&modal, &structured] {
        assert!((&ev.gauss_newton - &plain.gauss_newton).norm_max() < 1e-9 * scale);
    }
}

#[test]
fn a_search_stopped_on_a_tolerance_ends_with_its_initial_states_solved_exactly() {
    // a slow mode carrying a large initial state: a loose cost tolerance stops the joint
    // search while the states are still short of their optimum for its last parameters
    let (truth_sys, k) = truth();
    let mut a = truth_sys.a.clone();
    a[(2, 2)] = 0.995;
    let sys = StateSpace::new(
        a,
        truth_sys.b.clone(),
        truth_sys.c.clone(),
        truth_sys.d.clone(),
    )
    .unwrap();
    let u = noise(400, 2, 21);
    let e = noise(400, 2, 22) * faer::Scale(0.2);
    let y = data(&sys, &k, &u, &e, &[2.0, -1.0, 15.0]);
    let mut o = PemOptions::default();
    o.focus = Focus::Simulation;
    o.reweight = false;
    o.optim.tol_cost = 1e-3;
    let mut seen = Vec::new();
    let views = [(u.as_ref(), y.as_ref())];
    let mut a0 = sys.a.clone();
    a0[(2, 2)] = 0.98;
    let start = StateSpace::new(a0, sys.b.clone(), sys.c.clone(), sys.d.clone()).unwrap();
    let r = pem(&perturbed(&start, 0.01), None, &views, &o, &mut |it| {
        seen.push((it.iteration, it.cost));
        Flow::Continue
    })
    .unwrap();
    // the criterion of the result with its states fitted by least squares is its own cost
    let exact = criterion(&views, &r.sys, None, &o).unwrap();
    let last = *r.solution.history.last().unwrap();
    assert!(
        (last - exact).abs() <= 1e-9 * exact,
        "{last} against {exact}"
    );
    // every iteration, the states' own included, was reported and is in the history
    assert_eq!(seen.len(), r.solution.iterations);
    assert_eq!(r.solution.history.len(), r.solution.iterations + 1);
    assert!(seen.iter().enumerate().all(|(i, s)| s.0 == i + 1));
    assert!(r.solution.history.windows(2).all(|w| w[1] <= w[0]));
}
