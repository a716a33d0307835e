//! Tests of the subspace engine on systems whose answer is known.

use super::*;
use crate::hankel::{Compressor, HankelLayout, QrCompressor};
use crate::simulate::simulate;
use faer::Mat;

pub(crate) struct Rng(pub(crate) u64);
impl Rng {
    pub(crate) fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    pub(crate) fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform().max(1e-300), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

/// A random stable system with poles of modulus in [0.3, 0.9] (block-diagonal, then mixed).
pub(crate) fn random_system(n: usize, m: usize, l: usize, rng: &mut Rng) -> StateSpace {
    let mut a = Mat::<f64>::zeros(n, n);
    let mut i = 0;
    while i < n {
        let r = 0.3 + 0.6 * rng.uniform();
        if i + 1 < n && rng.uniform() < 0.6 {
            let th = 0.2 + 2.5 * rng.uniform();
            a[(i, i)] = r * th.cos();
            a[(i, i + 1)] = r * th.sin();
            a[(i + 1, i)] = -r * th.sin();
            a[(i + 1, i + 1)] = r * th.cos();
            i += 2;
        } else {
            a[(i, i)] = if rng.uniform() < 0.5 { r } else { -r };
            i += 1;
        }
    }
    let t = Mat::from_fn(
        n,
        n,
        |i, j| if i == j { 1.0 } else { 0.0 } + 0.3 * rng.normal(),
    );
    let tinv = crate::linalg::pinv(t.as_ref(), 1e-14).unwrap();
    let a = &t * &a * &tinv;
    let b = Mat::from_fn(n, m, |_, _| rng.normal());
    let c = Mat::from_fn(l, n, |_, _| rng.normal());
    let d = Mat::from_fn(l, m, |_, _| rng.normal());
    StateSpace::new(a, b, c, d).unwrap()
}

fn compress(u: &Mat<f64>, y: &Mat<f64>, p: usize, f: usize) -> HankelFactor {
    let lay = HankelLayout::new(u.ncols(), y.ncols(), p, f).unwrap();
    let mut c = QrCompressor::new(lay);
    c.push(u.as_ref(), y.as_ref()).unwrap();
    c.finish().unwrap()
}

fn rel_markov_error(a: &StateSpace, b: &StateSpace, count: usize) -> f64 {
    let (ha, hb) = (a.markov(count), b.markov(count));
    let mut num: f64 = 0.0;
    let mut den: f64 = 0.0;
    for (x, y) in ha.iter().zip(hb.iter()) {
        num = num.max((x - y).norm_max());
        den = den.max(x.norm_max());
    }
    num / den
}

#[test]
fn noise_free_mimo_systems_are_recovered_for_every_method() {
    // A, B, C, D by the shift invariance and from the state sequence, with and without D
    let mut rng = Rng(11);
    for case in 0..12 {
        let n = 1 + case % 6;
        let m = 1 + case % 3;
        let l = 1 + (case / 3) % 3;
        let mut sys = random_system(n, m, l, &mut rng);
        let feedthrough = case % 2 == 0;
        if !feedthrough {
            sys.d.fill(0.0);
        }
        let len = 600;
        let u = Mat::from_fn(len, m, |_, _| rng.normal());
        let y = simulate(&sys, u.as_ref(), None).unwrap();
        let f = (n + 2).div_ceil(l) + 2;
        let fac = compress(&u, &y, f, f);
        for method in [
            Method::Moesp,
            Method::N4sid,
            Method::OrdinaryMoesp,
            Method::PiMoesp,
            Method::Cva,
        ] {
            let sub = Subspace::new(&fac, &SubspaceOptions::with_method(method)).unwrap();
            assert_eq!(
                sub.auto_order(),
                n,
                "case {case} {method:?} sv={:?}",
                sub.singular_values()
            );
            for matrices in [SystemMatrices::Shift, SystemMatrices::States] {
                let opts = FitOptions {
                    kalman: false,
                    feedthrough,
                    matrices,
                    ..FitOptions::default()
                };
                let id = sub.fit(n, &opts).unwrap();
                let err = rel_markov_error(&sys, &id.sys, 30);
                assert!(
                    err < 1e-8,
                    "case {case} n={n} m={m} l={l} {method:?} {matrices:?} D={feedthrough}: \
                     markov err {err:e}"
                );
            }
        }
    }
}

#[test]
fn order_above_the_horizon_limit_is_an_error() {
    let mut rng = Rng(3);
    let sys = random_system(2, 1, 1, &mut rng);
    let u = Mat::from_fn(300, 1, |_, _| rng.normal());
    let y = simulate(&sys, u.as_ref(), None).unwrap();
    let fac = compress(&u, &y, 4, 4);
    let sub = Subspace::new(&fac, &SubspaceOptions::default()).unwrap();
    assert!(matches!(
        sub.fit(4, &FitOptions::default()),
        Err(SysidError::OrderTooLarge { .. })
    ));
}

#[test]
fn constant_input_is_not_persistently_exciting() {
    let u = Mat::from_fn(300, 1, |_, _| 1.0);
    let y = Mat::from_fn(300, 1, |t, _| (t as f64 * 0.1).sin());
    let fac = compress(&u, &y, 4, 4);
    assert!(matches!(
        Subspace::new(&fac, &SubspaceOptions::default()),
        Err(SysidError::NotPersistentlyExciting { .. })
    ));
}

/// A slow pole (0.99) under white output noise, fitted with more states than the system
/// has: the shift-invariance estimate of A puts a pole outside the unit circle on many
/// records, the least squares on the state sequence on none.
#[test]
fn the_state_sequence_keeps_a_slow_pole_inside_the_unit_circle() {
    let a = faer::mat![[0.99, 0.0], [0.0, 0.5]];
    let b = faer::mat![[1.0], [1.0]];
    let c = faer::mat![[0.1, 1.0]];
    let sys = StateSpace::new(a, b, c, Mat::zeros(1, 1)).unwrap();
    let (mut shift_unstable, mut states_unstable) = (0, 0);
    let mut rng = Rng(5);
    for _ in 0..20 {
        let u = Mat::from_fn(1000, 1, |_, _| rng.normal());
        let mut y = simulate(&sys, u.as_ref(), None).unwrap();
        let sd = (y.col(0).iter().map(|v| v * v).sum::<f64>() / 1000.0).sqrt();
        for t in 0..1000 {
            y[(t, 0)] += 0.3 * sd * rng.normal();
        }
        let sub = Subspace::new(&compress(&u, &y, 10, 10), &SubspaceOptions::default()).unwrap();
        for (matrices, count) in [
            (SystemMatrices::Shift, &mut shift_unstable),
            (SystemMatrices::States, &mut states_unstable),
        ] {
            let opts = FitOptions {
                matrices,
                ..FitOptions::default()
            };
            let id = sub.fit(6, &opts).unwrap();
            if crate::linalg::spectral_radius(id.sys.a.as_ref()).unwrap() >= 1.0 {
                *count += 1;
            }
        }
    }
    assert!(
        shift_unstable >= 3,
        "shift: {shift_unstable} unstable of 20"
    );
    assert_eq!(
        states_unstable, 0,
        "states: {states_unstable} unstable of 20"
    );
}
