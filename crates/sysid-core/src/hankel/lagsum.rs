//! Lagged sums of a block of samples: `C += X^T Xw`, read straight from the samples.
//!
//! `x` holds samples row-major (`d` channels per row). Row `t` of the overlapping Hankel
//! view `Xw` is the contiguous slice `x[t d .. t d + w d]` (samples `t .. t + w` side by
//! side), so `C[i, c] = sum_t x[t d + i] x[t d + c]` (`i < d`, `c < w d`) gathers every
//! lagged product `x_t x_{t+tau}^T` in the block `tau` of columns `tau d .. (tau + 1) d`.
//!
//! A general GEMM would pack `Xw` (a `w`-fold copy of the data) and tile for large square
//! products; here the output has only `d` rows, so the kernel keeps an `MR x NR` tile of
//! `C` in registers, reads `MR` broadcasts and `NR / 4` unaligned vectors of `x` per sample
//! and runs `MR NR / 4` fused multiply-adds, for a run of samples short enough to stay in
//! the L1 cache, then adds the tile to `C`. Every entry of `C` sums over `t` in the same
//! fixed order (runs in order, `t` in order inside a run) whatever the tile, so the result
//! is a function of `(x, n, d, w)` and the instruction set only.

/// Samples per run: the rows a run touches (`run + w` rows of `d` doubles) should stay in
/// the L1 data cache while every tile sweeps them.
fn run_rows(d: usize, w: usize) -> usize {
    const L1_BYTES: usize = 24 << 10;
    let row = d.max(1) * std::mem::size_of::<f64>();
    (L1_BYTES / row).saturating_sub(w).clamp(64, 1024)
}

/// Register tile shape `(MR, NV)` (`MR` rows, `NR = 4 NV` columns) for `d` channels.
///
/// AVX2 has 16 vector registers: `MR NV` accumulators, `NV` loads and one broadcast must
/// fit (6 x 8 and 4 x 8 do; 4 x 12 and 3 x 16 spill and run at half speed). Rows split into
/// tiles of equal height when they can (d = 16: four 4 x 8 tiles). Measured with
/// `cargo run --release -p sysid-core --example lagsum_rate`.
fn tile_shape(d: usize) -> (usize, usize) {
    match d {
        1 => (1, 4),
        2 => (2, 4),
        3 => (3, 3),
        4 => (4, 2),
        5 => (5, 2),
        _ if d % 4 == 0 && d % 6 != 0 => (4, 2),
        _ => (6, 2),
    }
}

/// `out += X^T Xw` for `n` samples of `d` channels and a window of `w` samples.
///
/// `x` holds at least `(n + w - 1) d` values: rows `t < n` of the Hankel view read
/// `x[t d .. t d + w d]` (the caller pads with zeros when the lags past the end of the block
/// must count as zero). `out` is `d x (w d)` row-major: `out[i * w d + c] += sum_{t<n}
/// x[t d + i] x[t d + c]`. The summation order depends only on `(n, d, w)` and on whether
/// the CPU has AVX2 and FMA (x86-64), so results are reproducible run to run.
///
/// # Panics
/// If `x` or `out` is shorter than stated.
///
/// ```
/// use sysid_core::hankel::lag_sums;
/// // two channels, window 2: three samples then one row of zero padding
/// let x = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 0.0, 0.0];
/// let mut c = vec![0.0; 2 * 4];
/// lag_sums(&x, 3, 2, 2, &mut c);
/// // c[0][0] = 1*1 + 3*3 + 5*5; c[1][2] = sum_t y_t u_{t+1} = 2*3 + 4*5 + 6*0
/// assert_eq!(c[0], 35.0);
/// assert_eq!(c[4 + 2], 26.0);
/// ```
pub fn lag_sums(x: &[f64], n: usize, d: usize, w: usize, out: &mut [f64]) {
    let wd = w * d;
    assert!(out.len() >= d * wd, "lag_sums: out holds d * w * d values");
    if n == 0 || d == 0 || w == 0 {
        return;
    }
    assert!(
        x.len() >= (n + w - 1) * d,
        "lag_sums: x holds (n + w - 1) d values"
    );
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU has AVX2 and FMA (checked just above); the lengths of x and
            // out were checked against n, d, w, which is what avx2::lag_sums reads/writes.
            unsafe { avx2::lag_sums(x, n, d, w, out) };
            return;
        }
    }
    portable::lag_sums(x, n, d, w, out);
}

/// Drives the tiles: runs of samples, then row tiles, then column tiles.
/// `tile(mr, nv, t0, t1, i0, c0)` adds the sums over `t0 <= t < t1` for rows `i0 .. i0 + mr`
/// and columns `c0 .. c0 + 4 nv`; `nv = 0` stands for the remainder columns `c0 .. w d`
/// (fewer than 4) of every row.
#[inline(always)]
fn drive(
    n: usize,
    d: usize,
    w: usize,
    mut tile: impl FnMut(usize, usize, usize, usize, usize, usize),
) {
    let wd = w * d;
    let (mr0, nv0) = tile_shape(d);
    let run = run_rows(d, w);
    let vec_cols = wd / 4 * 4;
    let mut t0 = 0;
    while t0 < n {
        let t1 = (t0 + run).min(n);
        let mut i0 = 0;
        while i0 < d {
            let mr = mr0.min(d - i0);
            let mut c0 = 0;
            while c0 < vec_cols {
                let nv = nv0.min((vec_cols - c0) / 4);
                tile(mr, nv, t0, t1, i0, c0);
                c0 += 4 * nv;
            }
            i0 += mr;
        }
        if vec_cols < wd {
            tile(d, 0, t0, t1, 0, vec_cols);
        }
        t0 = t1;
    }
}

/// Every register-tile shape (rows x groups of 4 columns) the drivers use, handed to the
/// dispatching macro `$go` of each kernel (one list for the AVX2 and the portable tiles).
macro_rules! tile_shapes {
    ($go:ident) => {
        $go!(1, 1; 1, 2; 1, 3; 1, 4;
            2, 1; 2, 2; 2, 3; 2, 4;
            3, 1; 3, 2; 3, 3; 3, 4;
            4, 1; 4, 2; 4, 3; 4, 4;
            5, 1; 5, 2; 5, 3; 5, 4;
            6, 1; 6, 2; 6, 3; 6, 4)
    };
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    /// [`super::lag_sums`] with AVX2 and FMA.
    ///
    /// # Safety
    /// The CPU supports AVX2 and FMA; `x.len() >= (n + w - 1) d`, `out.len() >= d w d`,
    /// `n, d, w >= 1`.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn lag_sums(x: &[f64], n: usize, d: usize, w: usize, out: &mut [f64]) {
        let wd = w * d;
        let xp = x.as_ptr();
        let op = out.as_mut_ptr();
        super::drive(
            n,
            d,
            w,
            // SAFETY: the CPU has AVX2 and FMA (caller's contract); t < n, i0 + mr <= d and
            // c0 + 4 nv <= w d (or c < w d for the remainder), so every read is below
            // (n - 1) d + w d <= x.len() and writes stay in row i < d, column c < w d of out.
            |mr, nv, t0, t1, i0, c0| unsafe {
                if nv == 0 {
                    rest(xp, d, wd, t0, t1, c0, op)
                } else {
                    dispatch(mr, nv, xp, d, t0, t1, i0, c0, op, wd)
                }
            },
        );
    }

    /// The columns `c0..wd` that do not fill a vector, one at a time.
    ///
    /// # Safety
    /// AVX2 and FMA available; `x` readable below `(t1 - 1) d + wd`, `out` writable below
    /// `d wd`.
    #[target_feature(enable = "avx2,fma")]
    unsafe fn rest(
        x: *const f64,
        d: usize,
        wd: usize,
        t0: usize,
        t1: usize,
        c0: usize,
        out: *mut f64,
    ) {
        for i in 0..d {
            for c in c0..wd {
                let mut s = 0.0f64;
                for t in t0..t1 {
                    s = (*x.add(t * d + i)).mul_add(*x.add(t * d + c), s);
                }
                *out.add(i * wd + c) += s;
            }
        }
    }

    /// Calls the `(mr, nv)` instance of [`tile`].
    ///
    /// # Safety
    /// As [`tile`].
    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn dispatch(
        mr: usize,
        nv: usize,
        x: *const f64,
        d: usize,
        t0: usize,
        t1: usize,
        i0: usize,
        c0: usize,
        out: *mut f64,
        ldo: usize,
    ) {
        macro_rules! go {
            ($($mr:literal, $nv:literal);*) => {
                match (mr, nv) {
                    $(($mr, $nv) => tile::<$mr, $nv>(x, d, t0, t1, i0, c0, out, ldo),)*
                    _ => unreachable!("tile shape {mr}x{nv}"),
                }
            };
        }
        tile_shapes!(go)
    }

    /// `out[i0 + r, c0 + 4 v + k] += sum_{t0 <= t < t1} x[t d + i0 + r] x[t d + c0 + 4 v + k]`
    /// for `r < MR`, `v < NV`, `k < 4`, accumulated in registers.
    ///
    /// # Safety
    /// AVX2 and FMA available; `x` readable at `t d + i0 + r` and `t d + c0 + 4 NV - 1` for
    /// `t0 <= t < t1`; `out` writable at `(i0 + r) ldo + c0 + 4 NV - 1`.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn tile<const MR: usize, const NV: usize>(
        x: *const f64,
        d: usize,
        t0: usize,
        t1: usize,
        i0: usize,
        c0: usize,
        out: *mut f64,
        ldo: usize,
    ) {
        let mut acc = [[_mm256_setzero_pd(); NV]; MR];
        let mut p = x.add(t0 * d);
        for _ in t0..t1 {
            let mut b = [_mm256_setzero_pd(); NV];
            for (v, bv) in b.iter_mut().enumerate() {
                *bv = _mm256_loadu_pd(p.add(c0 + 4 * v));
            }
            for (r, row) in acc.iter_mut().enumerate() {
                let a = _mm256_broadcast_sd(&*p.add(i0 + r));
                for (av, bv) in row.iter_mut().zip(&b) {
                    *av = _mm256_fmadd_pd(a, *bv, *av);
                }
            }
            p = p.add(d);
        }
        for (r, row) in acc.iter().enumerate() {
            for (v, av) in row.iter().enumerate() {
                let o = out.add((i0 + r) * ldo + c0 + 4 * v);
                _mm256_storeu_pd(o, _mm256_add_pd(_mm256_loadu_pd(o), *av));
            }
        }
    }
}

/// Any CPU: the same tiles in plain arithmetic (which the compiler may vectorise).
pub(super) mod portable {
    /// [`super::lag_sums`] on any CPU.
    pub(in crate::hankel) fn lag_sums(x: &[f64], n: usize, d: usize, w: usize, out: &mut [f64]) {
        let wd = w * d;
        super::drive(n, d, w, |mr, nv, t0, t1, i0, c0| {
            if nv == 0 {
                for i in 0..d {
                    for c in c0..wd {
                        let mut s = 0.0f64;
                        for t in t0..t1 {
                            s += x[t * d + i] * x[t * d + c];
                        }
                        out[i * wd + c] += s;
                    }
                }
                return;
            }
            macro_rules! go {
                    ($($mr:literal, $nv:literal);*) => {
                        match (mr, nv) {
                            $(($mr, $nv) => tile::<$mr, {4 * $nv}>(x, d, t0, t1, i0, c0, out, wd),)*
                            _ => unreachable!("tile shape {mr}x{nv}"),
                        }
                    };
                }
            tile_shapes!(go)
        });
    }

    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn tile<const MR: usize, const NR: usize>(
        x: &[f64],
        d: usize,
        t0: usize,
        t1: usize,
        i0: usize,
        c0: usize,
        out: &mut [f64],
        ldo: usize,
    ) {
        let mut acc = [[0.0f64; NR]; MR];
        for t in t0..t1 {
            let row = &x[t * d..];
            let b: &[f64; NR] = row[c0..c0 + NR].try_into().unwrap();
            let a: &[f64; MR] = row[i0..i0 + MR].try_into().unwrap();
            for (accr, ar) in acc.iter_mut().zip(a) {
                for (s, bv) in accr.iter_mut().zip(b) {
                    *s += ar * bv;
                }
            }
        }
        for (r, accr) in acc.iter().enumerate() {
            let o = &mut out[(i0 + r) * ldo + c0..(i0 + r) * ldo + c0 + NR];
            for (ov, s) in o.iter_mut().zip(accr) {
                *ov += s;
            }
        }
    }
}
