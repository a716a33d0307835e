//! Dense kernels the estimators' Gauss-Newton products share: when a dense product or
//! decomposition is worth faer's thread pool, `J^T J` accumulated over blocks of Jacobian
//! rows into a lower triangle, and that triangle mirrored once at the end.

use crate::error::{Result, SysidError};
use faer::linalg::matmul::triangular::{self as tri, BlockStructure};
use faer::{Accum, Mat, MatMut, MatRef, Par};

/// The parallelism of a dense product or LU factorisation of a `rows x cols`
/// matrix, `O(rows cols^2)`: the calling thread below `2^22` multiply-adds (every iterate of
/// a small problem; waking the pool costs more than the work), rayon's pool above. Only for
/// those: they give the same bits on any number of threads (each entry's sums run in one
/// order; `tests::the_same_bits_on_any_thread_count`). faer's SVD, eigendecompositions, QR
/// and triangular solves do not (above a few hundred rows they split their work by thread:
/// the last bits move, and a search that amplifies them ends elsewhere): the crate runs them
/// on the calling thread ([`symmetric_eigen`], [`crate::linalg::svd_seq`],
/// [`crate::linalg::thin_q_seq`], and faer's own methods once
/// [`crate::linalg::reproducible_threads`] has been called).
pub(crate) fn small_par(rows: usize, cols: usize) -> Par {
    if rows.saturating_mul(cols).saturating_mul(cols) >= 1 << 22 {
        Par::rayon(0)
    } else {
        Par::Seq
    }
}

/// Eigenvectors (columns) and eigenvalues (ascending) of the symmetric `a` (its lower
/// triangle), as faer's `self_adjoint_eigen` but on the calling thread, so that the result
/// is the same on any number of threads (see [`small_par`]); `step` names the caller in the
/// error.
pub(crate) fn symmetric_eigen(a: &Mat<f64>, step: &'static str) -> Result<(Mat<f64>, Vec<f64>)> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd::{self, ComputeEigenvectors};
    let n = a.nrows();
    let par = Par::Seq;
    let mut u = Mat::<f64>::zeros(n, n);
    let mut s = faer::diag::Diag::<f64>::zeros(n);
    let scratch =
        evd::self_adjoint_evd_scratch::<f64>(n, ComputeEigenvectors::Yes, par, Default::default());
    evd::self_adjoint_evd(
        a.as_ref(),
        s.as_mut(),
        Some(u.as_mut()),
        par,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    )
    .map_err(|e| SysidError::numerical(step, format!("{e:?}")))?;
    let sv = s.column_vector();
    Ok((u, (0..n).map(|i| sv[i]).collect()))
}

/// Magnitude below which [`flush_tiny`] sets a carried number to zero: 2^52 times the
/// smallest normal double, so a value is zeroed before its decay reaches the subnormal range.
pub(crate) const TINY: f64 = f64::MIN_POSITIVE * 4_503_599_627_370_496.0;

/// Samples between two [`flush_tiny`] calls in a per-sample loop: a mode decaying faster
/// than by 1e-28 over this many samples (|pole| < 0.02) passes through the subnormal range
/// within a few samples anyway.
pub(crate) const FLUSH_EVERY: usize = 16;

/// Sets the entries of `v` smaller in magnitude than [`TINY`] (about 1e-292) to zero.
///
/// A sensitivity (or state) that is no longer forced decays geometrically: the initial
/// state's sensitivities always, every one of them over a stretch of zero input. On the way
/// to zero it passes through the subnormal numbers, and on Intel processors every
/// multiplication or product kernel that touches one takes a microcode assist (about a
/// hundred cycles): on a 2-core Xeon `pem` on the CSTR record spent 21 of its 28 ms per
/// Gauss-Newton evaluation in block products of such rows (AMD processors barely slow
/// down). The threshold is absolute: zeroing changes a sum by less than 1e-292, nothing for
/// records in any units a measurement has.
#[inline]
pub(crate) fn flush_tiny(v: &mut [f64]) {
    for x in v.iter_mut() {
        if x.abs() < TINY {
            *x = 0.0;
        }
    }
}

/// [`flush_tiny`] on every column of `m`.
#[inline]
pub(crate) fn flush_tiny_mat(m: &mut faer::Mat<f64>) {
    for j in 0..m.ncols() {
        flush_tiny(m.col_as_slice_mut(j));
    }
}

/// Zeroes the upper halves of the vector registers (`vzeroupper`) where the CPU has AVX; a
/// no-op elsewhere.
///
/// faer's matrix-product kernels (AVX2/AVX-512, chosen at run time) return with those halves
/// dirty, and this crate's scalar loops are compiled for the baseline target (legacy SSE
/// encodings): measured on this project's 2-core AMD EPYC machine, the per-sample loop of
/// `pem`'s modal evaluation ran 2.5 times slower after every 128-sample block product until
/// the halves were cleared. Call it after a dense product that a sequential per-sample loop
/// follows, and before such a loop starts.
#[inline]
pub(crate) fn clear_upper() {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU has AVX (checked above). `vzeroupper` only zeroes the upper
            // halves of the vector registers; the compiler knows the intrinsic's effect and
            // keeps no live value there across it.
            unsafe { std::arch::x86_64::_mm256_zeroupper() }
        }
    }
}

/// Adds `rows^T rows` to the lower triangle of `gram` (one block of Jacobian rows); the
/// upper triangle is left alone until [`mirror_lower`]. Leaves the vector registers'
/// upper halves clear ([`clear_upper`]).
pub(crate) fn gram_add(gram: MatMut<'_, f64>, rows: MatRef<'_, f64>, par: Par) {
    tri::matmul(
        gram,
        BlockStructure::TriangularLower,
        Accum::Add,
        rows.transpose(),
        BlockStructure::Rectangular,
        rows,
        BlockStructure::Rectangular,
        1.0,
        par,
    );
    clear_upper();
}

/// Mirrors the lower triangle of `h` into its upper one (a Gauss-Newton matrix summed in
/// its lower triangle only).
pub(crate) fn mirror_lower(h: &mut Mat<f64>) {
    for j in 0..h.ncols() {
        for i in j + 1..h.nrows() {
            h[(j, i)] = h[(i, j)];
        }
    }
}

/// `f` run inside a rayon pool of `threads` threads (tests of results that must not depend on
/// the count).
#[cfg(test)]
pub(crate) fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a rayon pool for the test")
        .install(f)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Subnormal numbers and normal ones below `TINY` become zero; `TINY` itself, larger
    /// values of either sign and NaN (which must still reach the caller's checks) stay.
    #[test]
    fn flush_tiny_zeroes_only_what_would_turn_subnormal() {
        let sub = f64::MIN_POSITIVE / 8.0;
        assert!(sub > 0.0 && !sub.is_normal());
        let mut v = [
            sub,
            -sub,
            TINY / 2.0,
            TINY,
            -TINY,
            1e-200,
            -3.0,
            f64::NAN,
            0.0,
        ];
        flush_tiny(&mut v);
        assert_eq!(&v[..7], &[0.0, 0.0, 0.0, TINY, -TINY, 1e-200, -3.0]);
        assert!(v[7].is_nan() && v[8] == 0.0);
        // a decay by 0.5 per sample, flushed every FLUSH_EVERY samples, never holds a
        // subnormal number at a flush
        let mut x = [1.0_f64];
        for t in 1..5000 {
            x[0] *= 0.5;
            if t % FLUSH_EVERY == 0 {
                flush_tiny(&mut x);
                assert!(x[0] == 0.0 || x[0].is_normal());
            }
        }
        assert_eq!(x[0], 0.0);
        let mut m = faer::Mat::from_fn(3, 2, |i, j| if i == j { sub } else { 1.0 });
        flush_tiny_mat(&mut m);
        assert_eq!((m[(0, 0)], m[(1, 1)], m[(2, 1)]), (0.0, 0.0, 1.0));
    }

    /// The products and factorisations run on rayon's pool, and the decompositions the crate
    /// runs on the calling thread, give the same bits with one thread and with two, at sizes
    /// where faer splits work by thread (its SVD, eigendecompositions, QR and triangular
    /// solves on several threads do not: found with a 2 x 28 record of order 20, whose
    /// `pem` search ended at another cost with two threads than with one). faer's own
    /// methods read its global setting, which [`crate::linalg::reproducible_threads`] sets
    /// for the whole process: not tested here, where other tests run beside this one.
    #[test]
    fn the_same_bits_on_any_thread_count() {
        use crate::linalg;
        let rnd = |r: usize, c: usize, seed: u64| {
            let mut s = seed;
            Mat::from_fn(r, c, |_, _| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
            })
        };
        let j = rnd(2400, 600, 1);
        let a = rnd(600, 600, 2);
        let run = |threads: usize| {
            on_threads(threads, || {
                let mut g = Mat::<f64>::zeros(600, 600);
                gram_add(g.as_mut(), j.as_ref(), small_par(2400, 600));
                mirror_lower(&mut g);
                let h = &g + Mat::<f64>::identity(600, 600);
                let (u, s) = symmetric_eigen(&h, "test").unwrap();
                let (sv, su, _) = linalg::svd_seq("test", a.as_ref(), true, false).unwrap();
                let ev = linalg::eigenvalues(a.as_ref()).unwrap();
                (
                    (
                        g,
                        linalg::mul(a.as_ref(), h.as_ref()),
                        linalg::inverse(a.as_ref()),
                    ),
                    (u, s, sv, su, ev),
                    (
                        linalg::thin_q_seq(j.as_ref()),
                        linalg::thin_r_seq(j.as_ref()),
                    ),
                )
            })
        };
        let (one, two) = (run(1), run(2));
        assert!(one.0 == two.0, "products or factorisations");
        assert!(one.1 == two.1, "decompositions");
        assert!(one.2 == two.2, "QR");
    }
}
