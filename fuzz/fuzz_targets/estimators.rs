//! Subspace fits of any order and weighting, ARX order searches and ERA realisations on
//! fuzzed records return `Ok` or `Err`, never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sysid_core::hankel::{compress_experiments, CompressorKind, HankelLayout};
use sysid_core::polynomial::arx::ArxCompressor;
use sysid_core::realization::{era, RealizationOptions};
use sysid_core::subspace::{FitOptions, Method, Subspace, SubspaceOptions};

#[path = "common.rs"]
mod common;
use common::Bytes;

const METHODS: [&str; 5] = ["moesp", "ordinary-moesp", "pi-moesp", "n4sid", "cva"];

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let (m, l) = (b.small(2), 1 + b.small(1));
    let h = 1 + b.small(5);
    let n = b.small(120) + 2 * h;
    let (u, y) = (b.mat(n, m), b.mat(n, l));

    // subspace
    if let Ok(layout) = HankelLayout::new(m, l, h, h) {
        let exps = [(u.as_ref(), y.as_ref())];
        if let Ok(f) = compress_experiments(layout, &exps, CompressorKind::Qr { chunk_rows: None })
        {
            let method = Method::parse(METHODS[b.byte() as usize % METHODS.len()]).unwrap();
            if let Ok(s) = Subspace::new(&f, &SubspaceOptions::with_method(method)) {
                let _ = s.auto_order();
                let mut opts = FitOptions::default();
                opts.feedthrough = b.byte() % 2 == 0;
                opts.kalman = b.byte() % 2 == 0;
                opts.stable = b.byte() % 2 == 0;
                let _ = s.fit(b.size(8), &opts);
            }
        }
    }

    // ARX order search
    let lag = b.size(6);
    if let Ok(mut c) = ArxCompressor::new(m, l, lag) {
        if c.push(u.as_ref(), y.as_ref()).is_ok() {
            let r = |b: &mut Bytes| vec![b.size(4), b.size(4)];
            let (na, nb, nk) = (r(&mut b), r(&mut b), r(&mut b));
            let _ = c.arxstruc(&na, &nb, &nk);
        }
    }

    // ERA on the first samples read as Markov parameters (l x 1 each)
    let count = n.min(40);
    let markov: Vec<_> = (0..count)
        .map(|t| faer::Mat::from_fn(l, 1, |i, _| y[(t, i)]))
        .collect();
    let mut opts = RealizationOptions::default();
    opts.order = if b.byte() % 2 == 0 {
        None
    } else {
        Some(b.size(6))
    };
    opts.rows = if b.byte() % 2 == 0 {
        None
    } else {
        Some(b.size(30))
    };
    opts.cols = if b.byte() % 2 == 0 {
        None
    } else {
        Some(b.size(30))
    };
    let _ = era(&markov, &opts);
});
