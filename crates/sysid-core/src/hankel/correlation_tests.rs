//! The correlation compressor against the explicit Gram matrix and the exact compressor.

use super::*;
use crate::linalg::lq_lower;
use crate::model::StateSpace;
use faer::Mat;

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
}

/// Random record with channel offsets and very different channel scales.
fn record(n: usize, m: usize, l: usize, seed: u64) -> (Mat<f64>, Mat<f64>) {
    let mut s = seed;
    let u = Mat::from_fn(n, m, |_, j| {
        50.0 * (j as f64 + 1.0) + 10f64.powi(j as i32) * lcg(&mut s)
    });
    let y = Mat::from_fn(n, l, |_, j| -3.0 + 10f64.powi(-(j as i32)) * lcg(&mut s));
    (u, y)
}

fn explicit_gram(layout: &HankelLayout, exps: &[(Mat<f64>, Mat<f64>)]) -> Mat<f64> {
    let k = layout.k();
    let w = layout.window();
    let mut g = Mat::<f64>::zeros(k, k);
    let mut col = vec![0.0; k];
    for (u, y) in exps {
        for t in 0..=(y.nrows() - w) {
            layout.fill_column(u.as_ref(), y.as_ref(), t, &mut col);
            for i in 0..k {
                for j in 0..k {
                    g[(i, j)] += col[i] * col[j];
                }
            }
        }
    }
    g
}

fn rel_gram_err(l: MatRef<'_, f64>, g: &Mat<f64>) -> f64 {
    let llt = l * l.transpose();
    let mut num: f64 = 0.0;
    let mut den: f64 = 0.0;
    for i in 0..g.nrows() {
        for j in 0..g.ncols() {
            num = num.max((llt[(i, j)] - g[(i, j)]).abs());
            den = den.max(g[(i, j)].abs());
        }
    }
    num / den
}

fn push_in(c: &mut impl Compressor, u: &Mat<f64>, y: &Mat<f64>, step: usize) {
    let n = y.nrows();
    let mut s = 0;
    while s < n {
        let len = step.min(n - s);
        c.push(u.as_ref().subrows(s, len), y.as_ref().subrows(s, len))
            .unwrap();
        s += len;
    }
}

fn opts(block_rows: usize, parallel: bool) -> CorrelationOptions {
    CorrelationOptions {
        block_rows,
        parallel,
        ..CorrelationOptions::default()
    }
}

#[test]
fn gram_matches_explicit_across_layouts_blocks_and_pushes() {
    for &(m, l, p, f) in &[
        (1, 1, 3, 3),
        (2, 3, 2, 4),
        (0, 2, 3, 2),
        (3, 1, 5, 5),
        (1, 2, 1, 1),
    ] {
        let layout = HankelLayout::new(m, l, p, f).unwrap();
        let a = record(403, m, l, 11 + m as u64);
        let b = record(57, m, l, 99 + l as u64);
        let g = explicit_gram(&layout, &[a.clone(), b.clone()]);
        for &block in &[1usize, 5, 64, 8192] {
            for &push in &[1usize, 13, 403] {
                let mut c = CorrelationCompressor::with_options(layout, opts(block, true));
                push_in(&mut c, &a.0, &a.1, push);
                c.end_experiment().unwrap();
                push_in(&mut c, &b.0, &b.1, push);
                let fac = c.finish().unwrap();
                assert_eq!(fac.n_columns(), 403 + 57 - 2 * (p + f - 1));
                assert_eq!(fac.n_experiments(), 2);
                let err = rel_gram_err(fac.l(), &g);
                assert!(
                    err < 1e-12,
                    "m={m} l={l} p={p} f={f} block={block} push={push} err={err:e}"
                );
                for i in 0..layout.k() {
                    for j in i + 1..layout.k() {
                        assert_eq!(fac.l()[(i, j)], 0.0);
                    }
                }
            }
        }
    }
}

fn singular_values(l: MatRef<'_, f64>) -> Vec<f64> {
    l.singular_values().unwrap()
}

/// A stable 3-state, 2-input, 2-output system with process and measurement noise.
fn noisy_system_record(n: usize, seed: u64) -> (Mat<f64>, Mat<f64>) {
    let a = faer::mat![[0.8, 0.2, 0.0], [-0.2, 0.8, 0.1], [0.0, 0.0, 0.5]];
    let b = faer::mat![[1.0, 0.0], [0.0, 1.0], [0.5, -0.5]];
    let c = faer::mat![[1.0, 0.0, 1.0], [0.0, 1.0, 0.0]];
    let d = faer::mat![[0.0, 0.0], [0.0, 0.0]];
    let sys = StateSpace::new(a, b, c, d).unwrap();
    let mut s = seed;
    let u = Mat::from_fn(n, 2, |_, _| lcg(&mut s));
    // process noise enters through extra inputs, then measurement noise is added
    let mut y = crate::simulate::simulate(&sys, u.as_ref(), None).unwrap();
    let mut x = [0.0; 3];
    for t in 0..n {
        let e = [0.1 * lcg(&mut s), 0.1 * lcg(&mut s), 0.1 * lcg(&mut s)];
        let xn = [
            0.8 * x[0] + 0.2 * x[1] + e[0],
            -0.2 * x[0] + 0.8 * x[1] + 0.1 * x[2] + e[1],
            0.5 * x[2] + e[2],
        ];
        y[(t, 0)] += x[0] + x[2] + 0.05 * lcg(&mut s);
        y[(t, 1)] += x[1] + 0.05 * lcg(&mut s);
        x = xn;
    }
    (u, y)
}

#[test]
fn fast_and_exact_agree_on_well_conditioned_data() {
    let layout = HankelLayout::new(2, 2, 6, 6).unwrap();
    let (mut u, y) = noisy_system_record(5000, 3);
    for t in 0..u.nrows() {
        u[(t, 0)] += 20.0; // an offset the centring must absorb
    }
    let mut q = QrCompressor::new(layout);
    q.push(u.as_ref(), y.as_ref()).unwrap();
    let exact = q.finish().unwrap();
    let mut c = CorrelationCompressor::new(layout);
    push_in(&mut c, &u, &y, 777);
    let fast = c.finish().unwrap();
    assert_eq!(fast.source(), FactorSource::Correlation);
    let (se, sf) = (singular_values(exact.l()), singular_values(fast.l()));
    for (a, b) in se.iter().zip(&sf) {
        assert!((a - b).abs() <= 1e-8 * a, "{a} vs {b}");
    }
    // same Gram matrix, hence the same subspace results
    let ge = exact.l() * exact.l().transpose();
    assert!(rel_gram_err(fast.l(), &ge) < 1e-13);
}

#[test]
fn result_does_not_depend_on_threads() {
    let layout = HankelLayout::new(2, 2, 4, 4).unwrap();
    let (u, y) = record(20_000, 2, 2, 5);
    let run = |parallel: bool| {
        let mut c = CorrelationCompressor::with_options(layout, opts(1000, parallel));
        push_in(&mut c, &u, &y, 7000);
        c.finish().unwrap()
    };
    let serial = run(false);
    let parallel = run(true);
    assert_eq!(serial.l(), parallel.l());
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let f = pool.install(|| run(true));
        assert_eq!(f.l(), serial.l(), "threads={threads}");
    }
}

#[test]
fn partial_sums_merge_and_survive_a_snapshot() {
    let layout = HankelLayout::new(1, 2, 3, 3).unwrap();
    let (u, y) = record(1000, 1, 2, 8);
    let (c0, s0) = CorrelationSums::center_scale(u.as_ref(), y.as_ref());
    let mut whole = CorrelationSums::new(layout, c0.clone(), s0.clone()).unwrap();
    whole.push(u.as_ref(), y.as_ref()).unwrap();
    let g = explicit_gram(&layout, &[(u.clone(), y.clone())]);
    // chunks of unequal size, summed separately and merged as a tree
    let cuts = [0, 1, 3, 250, 251, 700, 1000];
    let parts: Vec<CorrelationSums> = cuts
        .windows(2)
        .map(|w| {
            let mut s = CorrelationSums::new(layout, c0.clone(), s0.clone()).unwrap();
            let (a, n) = (w[0], w[1] - w[0]);
            s.push(u.as_ref().subrows(a, n), y.as_ref().subrows(a, n))
                .unwrap();
            CorrelationSums::from_state(s.state()).unwrap()
        })
        .collect();
    let left = parts[0].merge(&parts[1]).unwrap().merge(&parts[2]).unwrap();
    let right = parts[3].merge(&parts[4]).unwrap().merge(&parts[5]).unwrap();
    let merged = left.merge(&right).unwrap();
    assert_eq!(merged.open_samples(), 1000);
    let fm = merged.into_factor(1e-10).unwrap();
    let fw = whole.into_factor(1e-10).unwrap();
    assert_eq!(fm.n_columns(), fw.n_columns());
    assert!(rel_gram_err(fm.l(), &g) < 1e-12);
    assert!(rel_gram_err(fw.l(), &g) < 1e-12);

    // separate experiments: end each, then merge
    let mut a = CorrelationSums::new(layout, c0.clone(), s0.clone()).unwrap();
    a.push(u.as_ref().subrows(0, 400), y.as_ref().subrows(0, 400))
        .unwrap();
    let mut b = CorrelationSums::new(layout, c0.clone(), s0.clone()).unwrap();
    b.push(u.as_ref().subrows(400, 600), y.as_ref().subrows(400, 600))
        .unwrap();
    b.end_experiment().unwrap();
    assert!(matches!(
        a.merge(&b),
        Err(SysidError::IncompatibleFactors { .. })
    ));
    a.end_experiment().unwrap();
    let ab = a.merge(&b).unwrap().into_factor(1e-10).unwrap();
    assert_eq!(ab.n_experiments(), 2);
    let g2 = explicit_gram(
        &layout,
        &[
            (
                u.as_ref().subrows(0, 400).to_owned(),
                y.as_ref().subrows(0, 400).to_owned(),
            ),
            (
                u.as_ref().subrows(400, 600).to_owned(),
                y.as_ref().subrows(400, 600).to_owned(),
            ),
        ],
    );
    assert!(rel_gram_err(ab.l(), &g2) < 1e-12);

    // different shifts cannot be merged
    let other = CorrelationSums::new(layout, vec![1.0, 0.0, 0.0], s0).unwrap();
    assert!(matches!(
        a.merge(&other),
        Err(SysidError::IncompatibleFactors { .. })
    ));
}

#[test]
fn ill_conditioned_data_falls_back_and_stays_exact() {
    // noise-free data of a 2-state system: the Gram matrix is singular
    let sys = StateSpace::new(
        faer::mat![[0.7, 0.3], [-0.3, 0.7]],
        faer::mat![[1.0], [0.5]],
        faer::mat![[1.0, 0.0]],
        faer::mat![[0.0]],
    )
    .unwrap();
    let mut s = 17u64;
    let u = Mat::from_fn(3000, 1, |_, _| lcg(&mut s));
    let y = crate::simulate::simulate(&sys, u.as_ref(), None).unwrap();
    let layout = HankelLayout::new(1, 1, 5, 5).unwrap();
    let mut c = CorrelationCompressor::new(layout);
    c.push(u.as_ref(), y.as_ref()).unwrap();
    let fast = c.finish().unwrap();
    assert!(
        matches!(
            fast.source(),
            FactorSource::CorrelationIllConditioned { .. }
        ),
        "{:?}",
        fast.source()
    );
    // the flagged factor still represents the data's Gram matrix to round-off
    let g = explicit_gram(&layout, &[(u.clone(), y.clone())]);
    assert!(rel_gram_err(fast.l(), &g) < 1e-12);

    let views = [(u.as_ref(), y.as_ref())];
    let fb = compress_experiments(
        layout,
        &views,
        CompressorKind::Correlation(CorrelationOptions::default()),
    )
    .unwrap();
    assert!(matches!(fb.source(), FactorSource::QrFallback { .. }));
    let exact =
        compress_experiments(layout, &views, CompressorKind::Qr { chunk_rows: None }).unwrap();
    assert_eq!(exact.source(), FactorSource::Qr);
    assert_eq!(fb.l(), exact.l());
    let _ = lq_lower; // keep the shared helper import used in both test modules
}

#[test]
fn cholesky_failure_uses_clipped_eigendecomposition() {
    // a constant input channel: the centred Gram matrix has an exactly zero direction
    let layout = HankelLayout::new(1, 1, 2, 2).unwrap();
    let mut s = 3u64;
    let u = Mat::from_fn(500, 1, |_, _| 2.0);
    let y = Mat::from_fn(500, 1, |_, _| lcg(&mut s));
    let mut c = CorrelationCompressor::new(layout);
    c.push(u.as_ref(), y.as_ref()).unwrap();
    let f = c.finish().unwrap();
    assert!(matches!(
        f.source(),
        FactorSource::CorrelationIllConditioned { .. }
    ));
    let g = explicit_gram(&layout, &[(u, y)]);
    assert!(rel_gram_err(f.l(), &g) < 1e-12);
}

#[test]
fn rejects_bad_input() {
    let layout = HankelLayout::new(1, 1, 3, 3).unwrap();
    let (u, mut y) = record(100, 1, 1, 3);
    let mut c = CorrelationCompressor::new(layout);
    c.push(u.as_ref().subrows(0, 50), y.as_ref().subrows(0, 50))
        .unwrap();
    y[(72, 0)] = f64::NAN;
    match c.push(u.as_ref().subrows(50, 50), y.as_ref().subrows(50, 50)) {
        Err(SysidError::NonFinite {
            what: "y",
            sample: 72,
            channel: 0,
        }) => {}
        other => panic!("unexpected {other:?}"),
    }
    let (u, y) = record(9, 1, 1, 3);
    let mut c = CorrelationCompressor::new(layout);
    c.push(u.as_ref(), y.as_ref()).unwrap();
    assert!(matches!(
        c.finish(),
        Err(SysidError::InsufficientData { .. })
    ));
    let (u, y) = record(4, 1, 1, 3);
    let mut c = CorrelationCompressor::new(layout);
    c.push(u.as_ref(), y.as_ref()).unwrap();
    assert!(matches!(
        c.end_experiment(),
        Err(SysidError::InsufficientData { .. })
    ));
    assert!(matches!(
        CorrelationCompressor::new(layout).finish(),
        Err(SysidError::InsufficientData { .. })
    ));
    let (u, _) = record(50, 1, 1, 3);
    let (_, y) = record(40, 1, 1, 3);
    let mut c = CorrelationCompressor::new(layout);
    assert!(matches!(
        c.push(u.as_ref(), y.as_ref()),
        Err(SysidError::ShapeMismatch { .. })
    ));
    assert!(CorrelationSums::new(layout, vec![0.0], vec![1.0, 1.0]).is_err());
    assert!(CorrelationSums::new(layout, vec![0.0, 0.0], vec![1.0, 0.0]).is_err());
}

#[test]
fn output_only_records_match_the_explicit_gram_matrix() {
    // no inputs: the input views have no rows at all (several blocks, two pushes)
    let layout = HankelLayout::new(0, 2, 3, 3).unwrap();
    let (_, y) = record(3000, 0, 2, 5);
    let u = Mat::<f64>::zeros(0, 0);
    let opts = CorrelationOptions {
        block_rows: 256,
        ..CorrelationOptions::default()
    };
    let mut c = CorrelationCompressor::with_options(layout, opts);
    c.push(u.as_ref(), y.as_ref().subrows(0, 1700)).unwrap();
    c.push(u.as_ref(), y.as_ref().subrows(1700, 1300)).unwrap();
    let f = c.finish().unwrap();
    let g = explicit_gram(&layout, &[(Mat::zeros(3000, 0), y.clone())]);
    assert!(rel_gram_err(f.l(), &g) < 1e-12);
}

#[test]
fn the_gram_matrix_is_sized_only_when_an_experiment_with_a_window_closes() {
    // past = f = 2000 (k = 8000, a 0.5 GB Gram matrix): a generator's record of 500 or 5000
    // samples is refused at the end without sizing it
    let layout = HankelLayout::new(1, 1, 2000, 2000).unwrap();
    let (u, y) = record(5000, 1, 1, 7);
    for n in [500, 5000] {
        let (c, s) = CorrelationSums::center_scale(u.as_ref(), y.as_ref());
        let mut sums = CorrelationSums::new(layout, c, s).unwrap();
        sums.push(u.as_ref().subrows(0, n), y.as_ref().subrows(0, n))
            .unwrap();
        assert_eq!(sums.state().gram.nrows(), 0);
        let e = sums.clone().into_factor(1e-10).unwrap_err().to_string();
        assert!(e.contains(&format!("got {n}")), "{n}: {e}");
        let mut c = CorrelationCompressor::new(layout);
        c.push(u.as_ref().subrows(0, n), y.as_ref().subrows(0, n))
            .unwrap();
        assert_eq!(c.finish().unwrap_err().to_string(), e);
    }
    // a small layout: sized when the first experiment closes; an unsized snapshot, merge and
    // factor agree with the sized path
    let layout = HankelLayout::new(1, 1, 3, 2).unwrap();
    let (u, y) = record(400, 1, 1, 8);
    let (c, s) = CorrelationSums::center_scale(u.as_ref(), y.as_ref());
    let mut a = CorrelationSums::new(layout, c.clone(), s.clone()).unwrap();
    a.push(u.as_ref().subrows(0, 150), y.as_ref().subrows(0, 150))
        .unwrap();
    let open = CorrelationSums::from_state(a.state()).unwrap();
    assert_eq!(open.state().gram.nrows(), 0);
    let mut b = CorrelationSums::new(layout, c.clone(), s.clone()).unwrap();
    b.push(u.as_ref().subrows(150, 250), y.as_ref().subrows(150, 250))
        .unwrap();
    let mut closed = open.merge(&b).unwrap();
    closed.end_experiment().unwrap();
    assert_eq!(closed.state().gram.nrows(), layout.k());
    // sized + unsized in either order, and the sized snapshot, give the same factor
    let empty = CorrelationSums::new(layout, c, s).unwrap();
    let closed = CorrelationSums::from_state(closed.state()).unwrap();
    let g = explicit_gram(&layout, &[(u, y)]);
    for sums in [
        a.merge(&b).unwrap(),
        empty.merge(&closed).unwrap(),
        closed.merge(&empty).unwrap(),
    ] {
        assert!(rel_gram_err(sums.into_factor(1e-10).unwrap().l(), &g) < 1e-12);
    }
}
