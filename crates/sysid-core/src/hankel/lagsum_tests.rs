//! The lagged-sum kernel against a naive triple loop.

use super::lag_sums;
use super::lagsum::portable;

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
}

fn naive(x: &[f64], n: usize, d: usize, w: usize, out: &mut [f64]) {
    let wd = w * d;
    for i in 0..d {
        for c in 0..wd {
            let mut s = 0.0;
            for t in 0..n {
                s += x[t * d + i] * x[t * d + c];
            }
            out[i * wd + c] += s;
        }
    }
}

/// Max |a - b| over max |b| (with |x| sums as scale: the terms have random signs).
fn rel_err(a: &[f64], b: &[f64], scale: f64) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max)
        / scale
}

type Kernel = fn(&[f64], usize, usize, usize, &mut [f64]);

fn check(kernel: Kernel, name: &str) {
    let mut seed = 7u64;
    for &d in &[1usize, 2, 3, 4, 5, 6, 7, 8, 11, 16, 17] {
        for &w in &[1usize, 2, 3, 5, 13, 40] {
            for &n in &[0usize, 1, 2, 3, 5, 6, 7, 12, 39, 64, 65, 301, 1500] {
                let wd = w * d;
                // not padded with zeros: the kernel must read x[(n..n + w - 1) d] as given
                let x: Vec<f64> = (0..(n + w - 1) * d).map(|_| lcg(&mut seed)).collect();
                let init: Vec<f64> = (0..d * wd).map(|_| lcg(&mut seed)).collect();
                let mut want = init.clone();
                naive(&x, n, d, w, &mut want);
                let mut got = init.clone();
                kernel(&x, n, d, w, &mut got);
                // each sum has n terms of size <= 1/4: scale the error by that
                let scale = 1.0 + n as f64 / 4.0;
                let e = rel_err(&got, &want, scale);
                assert!(e < 1e-14, "{name}: d={d} w={w} n={n}: error {e:e}");
                // a longer x (slack after the Hankel view) changes nothing
                let mut xl = x.clone();
                xl.extend((0..5).map(|_| 1e300));
                let mut again = init.clone();
                kernel(&xl, n, d, w, &mut again);
                assert_eq!(again, got, "{name}: d={d} w={w} n={n}: reads past the view");
            }
        }
    }
}

#[test]
fn lag_sums_match_naive_loop() {
    check(lag_sums, "dispatched");
}

#[test]
fn portable_lag_sums_match_naive_loop() {
    check(portable::lag_sums, "portable");
}

#[test]
fn lag_sums_are_reproducible_and_use_only_the_view() {
    let (n, d, w) = (2000, 6, 40);
    let mut seed = 3u64;
    let x: Vec<f64> = (0..(n + w - 1) * d).map(|_| lcg(&mut seed)).collect();
    let mut a = vec![0.0; d * w * d];
    let mut b = vec![0.0; d * w * d];
    lag_sums(&x, n, d, w, &mut a);
    lag_sums(&x, n, d, w, &mut b);
    assert_eq!(a, b);
    // out longer than d w d: the extra entries stay untouched
    let mut c = vec![-1.0; d * w * d + 3];
    lag_sums(&x, n, d, w, &mut c);
    assert_eq!(&c[d * w * d..], &[-1.0; 3]);
}
