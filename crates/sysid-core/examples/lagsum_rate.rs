//! GFLOP/s of the lagged sums `C = X^T Xw` (d x w d, 2 w d^2 n flops) on one thread:
//! the dedicated kernel (`sysid_core::hankel::lag_sums`) against faer's general matmul on
//! the same overlapping Hankel view. Best of several repeats (robust on a shared machine).
//!
//! Then the whole correlation compressor (default block size) at 3 x 3 (N = 10^5) and
//! 8 x 8 (N = 10^6), horizon 20, on one thread and on the rayon pool, with the rate of its
//! lagged sums (`2 w d^2 N` flops over the total time).
//!
//! `cargo run --release -p sysid-core --example lagsum_rate [n]`

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};
use std::time::Instant;
use sysid_core::hankel::{
    lag_sums, Compressor, CorrelationCompressor, CorrelationOptions, CorrelationSums, HankelLayout,
};

/// Process CPU time in seconds (Linux), wall time elsewhere.
fn cpu_now() -> f64 {
    #[cfg(target_os = "linux")]
    {
        #[repr(C)]
        struct Timespec {
            sec: i64,
            nsec: i64,
        }
        extern "C" {
            fn clock_gettime(clock: i32, tp: *mut Timespec) -> i32;
        }
        const CLOCK_PROCESS_CPUTIME_ID: i32 = 2;
        let mut ts = Timespec { sec: 0, nsec: 0 };
        // SAFETY: clock_gettime writes one timespec (two 64-bit fields on 64-bit Linux).
        if unsafe { clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &mut ts) } == 0 {
            return ts.sec as f64 + ts.nsec as f64 * 1e-9;
        }
    }
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64()
}

/// Best (wall, CPU) seconds over `reps` runs.
fn best<F: FnMut()>(reps: usize, mut f: F) -> (f64, f64) {
    (0..reps)
        .map(|_| {
            let (t, c) = (Instant::now(), cpu_now());
            f();
            (t.elapsed().as_secs_f64(), cpu_now() - c)
        })
        .fold((f64::INFINITY, f64::INFINITY), |a, b| {
            (a.0.min(b.0), a.1.min(b.1))
        })
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(4096);
    let w = 40;
    println!("n = {n} samples per block, w = {w}, best CPU time of 30 (one thread)");
    // `--big` (second argument): only the 8 x 8 compressor on one thread, for profiling
    let big_only = std::env::args().nth(2).as_deref() == Some("--big");
    // `--small`: only the 3 x 3 compressor on one thread
    let small_only = std::env::args().nth(2).as_deref() == Some("--small");
    for &d in if big_only || small_only {
        &[][..]
    } else {
        &[1usize, 2, 6, 16][..]
    } {
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
        let (_, tk) = best(30, || {
            out.iter_mut().for_each(|v| *v = 0.0);
            lag_sums(&x, n, d, w, &mut out);
        });
        let mut lag = Mat::<f64>::zeros(d, wd);
        let (_, tf) = best(30, || {
            // SAFETY: rows t < n of the Hankel view read x[t d .. t d + w d] <= x.len()
            let (xt, xw) = unsafe {
                (
                    MatRef::from_raw_parts(x.as_ptr(), n, d, d as isize, 1),
                    MatRef::from_raw_parts(x.as_ptr(), n, wd, d as isize, 1),
                )
            };
            matmul(
                lag.as_mut(),
                Accum::Replace,
                xt.transpose(),
                xw,
                1.0,
                Par::Seq,
            );
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
    for &(m, l, big_n, reps) in &[
        (3usize, 3usize, 100_000usize, 20usize),
        (8, 8, 1_000_000, 3),
    ] {
        let d = m + l;
        let mut s = 5u64;
        let mut next = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let u = Mat::from_fn(big_n, m, |_, _| next());
        let y = Mat::from_fn(big_n, l, |_, _| next());
        let layout = HankelLayout::new(m, l, 20, 20).unwrap();
        let flops = 2.0 * (40 * d * d * big_n) as f64;
        let (_, cs) = best(reps, || {
            std::hint::black_box(CorrelationSums::center_scale(u.as_ref(), y.as_ref()));
        });
        println!("center_scale {m}x{m} N={big_n}: CPU {:8.2} ms", cs * 1e3);
        let (cen, sca) = CorrelationSums::center_scale(u.as_ref(), y.as_ref());
        let mut pushed = None;
        let (_, tp) = best(reps, || {
            let mut c = CorrelationSums::new(layout, cen.clone(), sca.clone()).unwrap();
            c.set_blocking(0, false);
            c.push(u.as_ref(), y.as_ref()).unwrap();
            pushed = Some(c);
        });
        let (_, tf) = best(reps, || {
            let c = pushed.clone().unwrap();
            std::hint::black_box(c.into_factor(1e-10).unwrap());
        });
        println!(
            "sums {m}x{m} N={big_n}: push CPU {:8.2} ms, into_factor CPU {:8.2} ms",
            tp * 1e3,
            tf * 1e3
        );
        if (big_only && d != 16) || (small_only && d != 6) {
            continue;
        }
        for parallel in if big_only || small_only {
            &[false][..]
        } else {
            &[false, true][..]
        } {
            let parallel = *parallel;
            let mut o = CorrelationOptions::default();
            o.parallel = parallel;
            // third argument: block rows (0: automatic)
            o.block_rows = std::env::args()
                .nth(3)
                .and_then(|s| s.parse().ok())
                .unwrap_or(0);
            let (t, cpu) = best(reps, || {
                let mut c = CorrelationCompressor::with_options(layout, o);
                c.push(u.as_ref(), y.as_ref()).unwrap();
                std::hint::black_box(c.finish().unwrap());
            });
            println!(
                "compress {m}x{m} N={big_n} parallel={parallel}: wall {:8.2} ms, CPU {:8.2} ms; \
                 lagged sums at {:5.1} GFLOP/s of CPU",
                t * 1e3,
                cpu * 1e3,
                flops / cpu * 1e-9
            );
        }
    }
}
