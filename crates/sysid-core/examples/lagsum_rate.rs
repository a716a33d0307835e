//! GFLOP/s of the lagged sums `C = X^T Xw` (d x w d, 2 w d^2 n flops) on one thread:
//! the dedicated kernel (`sysid_core::hankel::lag_sums`) against faer's general matmul on
//! the same overlapping Hankel view. Best of several repeats (robust on a shared machine).
//!
//! `cargo run --release -p sysid-core --example lagsum_rate [n]`

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};
use std::time::Instant;
use sysid_core::hankel::lag_sums;

fn best<F: FnMut()>(reps: usize, mut f: F) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(4096);
    let w = 40;
    println!("n = {n} samples per block, w = {w}, best of 30 (one thread)");
    for &d in &[1usize, 2, 6, 16] {
        let wd = w * d;
        let mut s = 1u64;
        let x: Vec<f64> = (0..(n + w - 1) * d)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
            })
            .collect();
        let flops = 2.0 * (w * d * d * n) as f64;
        let mut out = vec![0.0; d * wd];
        let tk = best(30, || {
            out.iter_mut().for_each(|v| *v = 0.0);
            lag_sums(&x, n, d, w, &mut out);
        });
        let mut lag = Mat::<f64>::zeros(d, wd);
        let tf = best(30, || {
            // SAFETY: rows t < n of the Hankel view read x[t d .. t d + w d] <= x.len()
            let (xt, xw) = unsafe {
                (
                    MatRef::from_raw_parts(x.as_ptr(), n, d, d as isize, 1),
                    MatRef::from_raw_parts(x.as_ptr(), n, wd, d as isize, 1),
                )
            };
            matmul(lag.as_mut(), Accum::Replace, xt.transpose(), xw, 1.0, Par::Seq);
        });
        let diff = (0..d)
            .flat_map(|i| (0..wd).map(move |c| (i, c)))
            .map(|(i, c)| (lag[(i, c)] - out[i * wd + c]).abs())
            .fold(0.0, f64::max);
        println!(
            "d={d:2}: kernel {:7.3} ms {:6.1} GFLOP/s | faer matmul {:7.3} ms {:6.1} GFLOP/s | max diff {diff:.1e}",
            tk * 1e3,
            flops / tk * 1e-9,
            tf * 1e3,
            flops / tf * 1e-9
        );
    }
}
