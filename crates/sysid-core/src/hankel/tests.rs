use super::*;
use crate::linalg::lq_lower;
use faer::Mat;

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
}

fn record(n: usize, m: usize, l: usize, seed: u64) -> (Mat<f64>, Mat<f64>) {
    let mut s = seed;
    let u = Mat::from_fn(n, m, |_, _| lcg(&mut s));
    let y = Mat::from_fn(n, l, |_, _| lcg(&mut s));
    (u, y)
}

fn explicit_h(layout: &HankelLayout, exps: &[(Mat<f64>, Mat<f64>)]) -> Mat<f64> {
    let w = layout.window();
    let cols: usize = exps.iter().map(|(_, y)| y.nrows() + 1 - w).sum();
    let mut h = Mat::<f64>::zeros(layout.k(), cols);
    let mut col = vec![0.0; layout.k()];
    let mut j = 0;
    for (u, y) in exps {
        for t in 0..=(y.nrows() - w) {
            layout.fill_column(u.as_ref(), y.as_ref(), t, &mut col);
            for (i, v) in col.iter().enumerate() {
                h[(i, j)] = *v;
            }
            j += 1;
        }
    }
    h
}

fn max_abs_diff(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
    let mut d: f64 = 0.0;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            d = d.max((a[(i, j)] - b[(i, j)]).abs());
        }
    }
    d
}

#[test]
fn streaming_matches_explicit_lq_across_chunk_sizes() {
    for &(m, l, p, f) in &[(1, 1, 3, 3), (2, 3, 2, 4), (0, 2, 3, 2), (3, 1, 5, 5)] {
        let layout = HankelLayout::new(m, l, p, f).unwrap();
        let (u, y) = record(301, m, l, 7 + m as u64);
        let h = explicit_h(&layout, &[(u.clone(), y.clone())]);
        let l_ref = lq_lower(h.as_ref());
        for &chunk_rows in &[1usize, 7, 64, 1000] {
            for &push in &[1usize, 13, 301] {
                let mut c = QrCompressor::with_chunk_rows(layout, chunk_rows);
                let mut s = 0;
                while s < 301 {
                    let n = push.min(301 - s);
                    c.push(u.as_ref().subrows(s, n), y.as_ref().subrows(s, n))
                        .unwrap();
                    s += n;
                }
                let fac = c.finish().unwrap();
                assert_eq!(fac.n_columns(), 301 - p - f + 1);
                let scale = l_ref.norm_max();
                let err = max_abs_diff(fac.l(), l_ref.as_ref());
                assert!(
                    err < 1e-12 * scale * 100.0,
                    "m={m} l={l} chunk={chunk_rows} push={push} err={err}"
                );
            }
        }
    }
}

#[test]
fn experiments_do_not_share_columns_and_merge_equals_joint() {
    let layout = HankelLayout::new(2, 2, 3, 3).unwrap();
    let a = record(120, 2, 2, 1);
    let b = record(90, 2, 2, 2);
    let h = explicit_h(&layout, &[a.clone(), b.clone()]);
    let l_ref = lq_lower(h.as_ref());

    let mut joint = QrCompressor::with_chunk_rows(layout, 10);
    joint.push(a.0.as_ref(), a.1.as_ref()).unwrap();
    joint.end_experiment().unwrap();
    joint.push(b.0.as_ref(), b.1.as_ref()).unwrap();
    let fj = joint.finish().unwrap();
    assert_eq!(fj.n_experiments(), 2);
    assert!(max_abs_diff(fj.l(), l_ref.as_ref()) < 1e-11);

    let mut ca = QrCompressor::new(layout);
    ca.push(a.0.as_ref(), a.1.as_ref()).unwrap();
    let mut cb = QrCompressor::new(layout);
    cb.push(b.0.as_ref(), b.1.as_ref()).unwrap();
    let merged = ca.finish().unwrap().merge(&cb.finish().unwrap()).unwrap();
    assert_eq!(merged.n_columns(), fj.n_columns());
    assert!(max_abs_diff(merged.l(), fj.l()) < 1e-11);
}

#[test]
fn rejects_bad_input() {
    let layout = HankelLayout::new(1, 1, 3, 3).unwrap();
    let (u, mut y) = record(100, 1, 1, 3);
    y[(42, 0)] = f64::NAN;
    let mut c = QrCompressor::new(layout);
    match c.push(u.as_ref(), y.as_ref()) {
        Err(SysidError::NonFinite {
            what: "y",
            sample: 42,
            channel: 0,
        }) => {}
        other => panic!("unexpected {other:?}"),
    }
    let (u, y) = record(5, 1, 1, 3);
    let mut c = QrCompressor::new(layout);
    c.push(u.as_ref(), y.as_ref()).unwrap();
    assert!(matches!(
        c.finish(),
        Err(SysidError::InsufficientData { .. })
    ));
    let (u, _) = record(50, 1, 1, 3);
    let (_, y) = record(40, 1, 1, 3);
    let mut c = QrCompressor::new(layout);
    assert!(matches!(
        c.push(u.as_ref(), y.as_ref()),
        Err(SysidError::ShapeMismatch { .. })
    ));
}

#[test]
fn factor_is_bit_identical_for_any_thread_count_and_chunking() {
    let layout = HankelLayout::new(3, 3, 8, 8).unwrap();
    let (u, y) = record(6000, 3, 3, 17);
    // small blocks (8 * 40 windows) so that a push holds many of them
    let run = |parallel: bool, cut: usize| {
        let mut c = QrCompressor::with_chunk_rows(layout, 40);
        c.set_parallel(parallel);
        let mut s = 0;
        while s < 6000 {
            let e = (s + cut).min(6000);
            c.push(u.as_ref().subrows(s, e - s), y.as_ref().subrows(s, e - s))
                .unwrap();
            s = e;
        }
        c.finish().unwrap()
    };
    let serial = run(false, 6000);
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let f = pool.install(|| run(true, 6000));
        assert_eq!(f.l(), serial.l(), "threads={threads}");
    }
    for cut in [1, 333, 2500] {
        assert_eq!(run(true, cut).l(), serial.l(), "pushes of {cut} samples");
    }
    // and it is the factor of the data matrix
    let l_ref = lq_lower(explicit_h(&layout, &[(u.clone(), y.clone())]).as_ref());
    let scale = l_ref.norm_max();
    assert!(max_abs_diff(serial.l(), l_ref.as_ref()) < 1e-12 * scale);
}

#[test]
fn a_known_record_length_is_checked_before_the_compressor_is_sized() {
    // past = 2000 on 500 samples: compress_stream peaked at 4.9 GB with "qr" before
    // finish() said the record was too short
    let layout = HankelLayout::new(1, 1, 2000, 2000).unwrap();
    for name in ["qr", "auto", "correlation"] {
        let kind = CompressorKind::parse(name, None).unwrap();
        let e = kind
            .check_stream(&layout, Some(500))
            .unwrap_err()
            .to_string();
        assert!(e.contains("horizon <= 250"), "{name}: {e}");
        assert!(kind.check_stream(&layout, Some(4000)).is_ok());
        assert!(kind.check_stream(&layout, None).is_ok());
    }
}
