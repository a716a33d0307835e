//! Criterion benches of the O(N) kernels: both compressors and simulation.
//! `cargo bench -p sysid-core --bench kernels` (a few seconds per kernel).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use faer::Mat;
use sysid_core::hankel::{Compressor, CorrelationCompressor, HankelLayout, QrCompressor};
use sysid_core::simulate::simulate;
use sysid_core::StateSpace;

fn record(n: usize, m: usize, l: usize) -> (Mat<f64>, Mat<f64>) {
    let mut s = 1u64;
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let u = Mat::from_fn(n, m, |_, _| next());
    let y = Mat::from_fn(n, l, |_, _| next());
    (u, y)
}

fn compressors(c: &mut Criterion) {
    let n = 100_000;
    let mut g = c.benchmark_group("compress");
    g.sample_size(10);
    g.throughput(Throughput::Elements(n as u64));
    for &(m, l, i) in &[(3usize, 3usize, 20usize), (8, 8, 10), (2, 2, 20)] {
        let (u, y) = record(n, m, l);
        let layout = HankelLayout::new(m, l, i, i).unwrap();
        let id = format!("m{m}_l{l}_i{i}");
        g.bench_with_input(BenchmarkId::new("correlation", &id), &(), |b, _| {
            b.iter(|| {
                let mut c = CorrelationCompressor::new(layout);
                c.push(u.as_ref(), y.as_ref()).unwrap();
                c.finish().unwrap()
            })
        });
        g.bench_with_input(BenchmarkId::new("qr", &id), &(), |b, _| {
            b.iter(|| {
                let mut c = QrCompressor::new(layout);
                c.push(u.as_ref(), y.as_ref()).unwrap();
                c.finish().unwrap()
            })
        });
    }
    g.finish();
}

fn simulation(c: &mut Criterion) {
    let n = 1_000_000;
    let nx = 8;
    let a = Mat::from_fn(nx, nx, |i, j| {
        if i == j {
            0.9
        } else if j == i + 1 {
            0.1
        } else {
            0.0
        }
    });
    let sys = StateSpace::new(
        a,
        Mat::from_fn(nx, 2, |i, j| (i + j) as f64 * 0.1),
        Mat::from_fn(2, nx, |i, j| (i * j) as f64 * 0.1),
        Mat::zeros(2, 2),
    )
    .unwrap();
    let (u, _) = record(n, 2, 1);
    let mut g = c.benchmark_group("simulate");
    g.sample_size(10);
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("n8_m2_l2", |b| {
        b.iter(|| simulate(&sys, u.as_ref(), None).unwrap())
    });
    g.finish();
}

criterion_group!(benches, compressors, simulation);
criterion_main!(benches);
