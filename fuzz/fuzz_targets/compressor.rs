//! Any layout, chunking and data given to the compressors returns `Ok` or `Err`, never
//! panics or aborts (sizes are checked before allocating).
#![no_main]

use libfuzzer_sys::fuzz_target;
use sysid_core::hankel::{compress_experiments, Compressor, CompressorKind, HankelLayout};

#[path = "common.rs"]
mod common;
use common::Bytes;

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let (m, l) = (b.size(2), b.size(2));
    let (past, future) = (b.size(6), b.size(6));
    let chunk = match b.byte() % 3 {
        0 => None,
        _ => Some(b.size(64)),
    };
    let kind_name = if b.byte() % 2 == 0 {
        "qr"
    } else {
        "correlation"
    };
    let Ok(layout) = HankelLayout::new(m, l, past, future) else {
        return;
    };
    let Ok(kind) = CompressorKind::parse(kind_name, chunk) else {
        return;
    };
    if kind.check(&layout).is_err() {
        return;
    }
    let n_exp = 1 + b.small(2);
    let mut exps = Vec::new();
    for _ in 0..n_exp {
        let n = b.small(200);
        exps.push((b.mat(n, m), b.mat(n, l)));
    }
    let views: Vec<_> = exps.iter().map(|(u, y)| (u.as_ref(), y.as_ref())).collect();
    let _ = compress_experiments(layout, &views, kind);
    // the same data streamed in uneven chunks
    let mut c = kind.build(layout);
    for (u, y) in &exps {
        let mut start = 0;
        while start < y.nrows() {
            let len = (1 + b.small(16)).min(y.nrows() - start);
            if c.push(
                u.as_ref().subrows(start, len),
                y.as_ref().subrows(start, len),
            )
            .is_err()
            {
                return;
            }
            start += len;
        }
        if c.end_experiment().is_err() {
            return;
        }
    }
    let _ = c.finish();
});
