//! The weighted SVD of each method, computed on the factor L alone.
//!
//! Everything here runs on the calling thread: the matrices have a few hundred rows at most,
//! and faer's global (rayon) parallelism costs more in thread wake-ups than it saves.

use super::Method;
use crate::error::{Result, SysidError};
use crate::hankel::{Block, HankelFactor};
use crate::linalg::{lq_lower, mul_seq, pinv, svd_left_seq, svd_seq};
use faer::{Mat, MatRef};

/// Singular values and the basis that yields the extended observability matrix.
#[derive(Debug, Clone)]
pub struct Weighted {
    /// Singular values, largest first.
    pub singular_values: Vec<f64>,
    /// `W1^{-1} U` (f l x q): `Γ_f = basis[:, :n] diag(sqrt(s[:n]))`.
    pub basis: Mat<f64>,
    /// Numerical rank of the weighted matrix (relative tolerance 1e-12).
    pub rank: usize,
}

/// Copies the given row ranges of `l` (all columns) into one matrix.
fn stack_rows(l: MatRef<'_, f64>, ranges: &[(usize, usize)]) -> Mat<f64> {
    let rows: usize = ranges.iter().map(|r| r.1).sum();
    let mut out = Mat::<f64>::zeros(rows, l.ncols());
    let mut at = 0;
    for &(s, n) in ranges {
        out.as_mut().subrows_mut(at, n).copy_from(l.subrows(s, n));
        at += n;
    }
    out
}

/// Errors when the future inputs are not of full row rank (constant, collinear or too
/// narrow-band inputs for the horizon).
pub fn check_excitation(factor: &HankelFactor, rtol: f64) -> Result<()> {
    let lay = factor.layout();
    let (s, n) = lay.block(Block::UFuture);
    if n == 0 {
        return Ok(());
    }
    let l11 = factor.l().submatrix(s, s, n, n);
    // L11 is lower triangular: when ||L11||_F ||L11^{-1}||_F < 1 / rtol every singular value
    // passes the cut (s_min / s_max >= 1 / that bound) and the SVD is not needed
    if super::checks::well_conditioned(l11.transpose(), rtol) {
        return Ok(());
    }
    let (sv, _, _) = svd_seq("excitation check (SVD)", l11, false, false)?;
    let smax = sv[0];
    let rank = sv.iter().filter(|&&x| x > rtol * smax && x > 0.0).count();
    if rank < n {
        return Err(SysidError::NotPersistentlyExciting {
            rank,
            rows: n,
            tol: rtol,
        });
    }
    Ok(())
}

/// Computes the weighted matrix of `method` and its SVD.
pub fn weighted_svd(factor: &HankelFactor, method: Method) -> Result<Weighted> {
    let lay = factor.layout();
    let l = factor.l();
    let uf = lay.block(Block::UFuture);
    let up = lay.block(Block::UPast);
    let yp = lay.block(Block::YPast);
    let yf = lay.block(Block::YFuture);
    let (wp_s, wp_n) = (up.0, up.1 + yp.1);
    let mut transform: Option<Mat<f64>> = None;
    let m: Mat<f64> = match method {
        Method::Moesp => l.submatrix(yf.0, wp_s, yf.1, wp_n).to_owned(),
        Method::N4sid => {
            // O = L32 L22^+ [L21 L22]
            let l32 = l.submatrix(yf.0, wp_s, yf.1, wp_n);
            let l22 = l.submatrix(wp_s, wp_s, wp_n, wp_n);
            let l2 = l.submatrix(wp_s, 0, wp_n, uf.1 + wp_n);
            mul_seq(mul_seq(l32, pinv(l22, 1e-12)?.as_ref()).as_ref(), l2)
        }
        Method::Cva => {
            let y_perp = l.submatrix(yf.0, wp_s, yf.1, wp_n + yf.1);
            let t = lq_lower(y_perp);
            let l32 = l.submatrix(yf.0, wp_s, yf.1, wp_n);
            let dmax = (0..t.nrows()).map(|i| t[(i, i)].abs()).fold(0.0, f64::max);
            let dmin = (0..t.nrows())
                .map(|i| t[(i, i)].abs())
                .fold(f64::INFINITY, f64::min);
            let w = if dmin > 1e-10 * dmax {
                let mut w = l32.to_owned();
                faer::linalg::triangular_solve::solve_lower_triangular_in_place(
                    t.as_ref(),
                    w.as_mut(),
                    faer::Par::Seq,
                );
                w
            } else {
                // noise-free or redundant outputs: Y_f Π Y_f^T is singular; whiten on its
                // range only (truncated pseudo-inverse), where L32 lives too
                mul_seq(pinv(t.as_ref(), 1e-10)?.as_ref(), l32)
            };
            transform = Some(t);
            w
        }
        Method::OrdinaryMoesp => {
            let lp = lq_lower(stack_rows(l, &[uf, yf]).as_ref());
            lp.submatrix(uf.1, uf.1, yf.1, yf.1).to_owned()
        }
        Method::PiMoesp => {
            let lp = lq_lower(stack_rows(l, &[uf, up, yf]).as_ref());
            lp.submatrix(uf.1 + up.1, uf.1, yf.1, up.1).to_owned()
        }
    };
    if m.ncols() == 0 {
        return Err(SysidError::invalid(
            "method",
            "this weighting needs past inputs (PI-MOESP) but the data have no inputs",
        ));
    }
    // the left singular vectors only (the right ones are never used)
    let (s, u) = svd_left_seq("weighted SVD", m.as_ref())?;
    let smax = s.first().copied().unwrap_or(0.0);
    if smax.is_nan() || smax <= 0.0 || !smax.is_finite() {
        return Err(SysidError::numerical(
            "weighted SVD",
            "the projected output data are zero: the outputs carry no information about the \
             past (constant or zero outputs?)",
        ));
    }
    let rank = s.iter().filter(|&&x| x > 1e-12 * smax).count();
    let basis = match transform {
        Some(t) => mul_seq(t.as_ref(), u.as_ref()),
        None => u,
    };
    Ok(Weighted {
        singular_values: s,
        basis,
        rank,
    })
}
