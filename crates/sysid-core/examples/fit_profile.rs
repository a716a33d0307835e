//! One default fit (the `"auto"` compressor, PO-MOESP, order 8) on a synthetic record, for
//! profilers: `cargo build --release -p sysid-core --example fit_profile`, then
//! `RAYON_NUM_THREADS=1 valgrind --tool=callgrind target/release/examples/fit_profile 100000 3 3 20`.
//! Arguments: samples, inputs, outputs, horizon (default 100000 3 3 20), repetitions.

use faer::Mat;
use sysid_core::hankel::{compress_experiments, CompressorKind, HankelLayout};
use sysid_core::subspace::{FitOptions, Subspace, SubspaceOptions};

fn main() {
    let a: Vec<usize> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("integer arguments"))
        .collect();
    let get = |i: usize, d: usize| a.get(i).copied().unwrap_or(d);
    let (n, m, l, i, reps) = (get(0, 100_000), get(1, 3), get(2, 3), get(3, 20), get(4, 1));
    // a stable filter of white inputs plus noise (well conditioned: the correlation path)
    let mut s = 7u64;
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let u = Mat::from_fn(n, m, |_, _| next());
    let mut y = Mat::<f64>::zeros(n, l);
    let mut x = vec![0.0; 8];
    for t in 0..n {
        for c in 0..l {
            y[(t, c)] = x[c % 8] + 0.1 * next();
        }
        let mut nx = vec![0.0; 8];
        for k in 0..8 {
            nx[k] = 0.8 * x[k] - 0.1 * x[(k + 1) % 8] + u[(t, k % m)] + 0.1 * next();
        }
        x = nx;
    }
    let layout = HankelLayout::new(m, l, i, i).unwrap();
    for _ in 0..reps {
        let c0 = cpu_seconds();
        let t0 = std::time::Instant::now();
        let f = compress_experiments(
            layout,
            &[(u.as_ref(), y.as_ref())],
            CompressorKind::parse("auto", None).unwrap(),
        )
        .unwrap();
        let t1 = std::time::Instant::now();
        let c1 = cpu_seconds();
        let sub = Subspace::new(&f, &SubspaceOptions::default()).unwrap();
        let t2 = std::time::Instant::now();
        let id = sub
            .fit(8.min(sub.max_order()), &FitOptions::default())
            .unwrap();
        let t3 = std::time::Instant::now();
        let flops = 4.0 * i as f64 * ((m + l) * (m + l)) as f64 * n as f64;
        eprintln!(
            "compress cpu {:.3} s = {:.1} GFLOP/s of the lagged-sum floor",
            c1 - c0,
            flops / (c1 - c0) / 1e9
        );
        eprintln!(
            "compress {:.4} s ({:?}), weighted svd {:.4} s, fit {:.4} s; a[0,0] = {:.6}",
            (t1 - t0).as_secs_f64(),
            f.source(),
            (t2 - t1).as_secs_f64(),
            (t3 - t2).as_secs_f64(),
            id.sys.a[(0, 0)]
        );
    }
}

/// User + system CPU seconds of this process (all threads), from /proc/self/stat.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11).and_then(|v| v.parse().ok()).unwrap_or(0.0)
        + f.get(12).and_then(|v| v.parse().ok()).unwrap_or(0.0);
    ticks / 100.0
}
