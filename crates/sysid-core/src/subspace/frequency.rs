//! Frequency-domain subspace identification from frequency-response data (McKelvey, Akçay &
//! Ljung 1996).
//!
//! With `z_k = e^{j ω_k}` (ω in rad/sample) and `G_k = D + C (z_k I - A)^{-1} B`, the data
//! equation `Y = Γ_q X + T_q U` holds for
//!
//! ```text
//!   Y[:, k] = [G_k; z_k G_k; ...; z_k^{q-1} G_k],   U[:, k] = [I; z_k I; ...; z_k^{q-1} I],
//!   X[:, k] = (z_k I - A)^{-1} B,
//! ```
//!
//! so the column space of `Y` with `U` projected out is that of `Γ_q`. Real and imaginary
//! parts side by side make every matrix real (the conjugate frequencies are implied); the
//! projection is the LQ factorisation of `[U; Y]`, the SVD of its `Y` block gives `Γ_q`, A and
//! C follow by shift invariance, and B, D by linear least squares on `G_k`. Each frequency
//! may carry a weight. Exact data of an order-n system give it exactly when `q > n` and at
//! least `n + 1` distinct frequencies are given (fewer when the system has more inputs).

use super::order::largest_log_gap;
use super::system::shift_invariance;
use crate::error::{Result, SysidError};
use crate::linalg::{lq_lower, pinv};
use crate::model::StateSpace;
use faer::{Mat, MatRef};

/// The direct term `D` of a frequency-domain fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Feedthrough {
    /// `D = 0`, a strictly proper model (the default of every sysid state-space estimator).
    #[default]
    Zero,
    /// `D` estimated jointly with `B`.
    Estimate,
    /// `G(-1) = 0`, i.e. `D = C (I + A)^{-1} B`: the continuous-time model Tustin's map gives
    /// back has no direct term (its response at infinite frequency is that at `z = -1`).
    ZeroAtNyquist,
}

impl Feedthrough {
    /// Parses `"zero"`, `"estimate"` or `"zero-at-nyquist"`.
    ///
    /// ```
    /// use sysid_core::subspace::frequency::Feedthrough;
    /// assert_eq!(Feedthrough::parse("estimate").unwrap(), Feedthrough::Estimate);
    /// assert!(Feedthrough::parse("yes").is_err());
    /// ```
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "zero" => Ok(Self::Zero),
            "estimate" => Ok(Self::Estimate),
            "zero-at-nyquist" => Ok(Self::ZeroAtNyquist),
            _ => Err(SysidError::invalid(
                "feedthrough",
                "must be 'zero', 'estimate' or 'zero-at-nyquist'",
            )),
        }
    }

    /// `C (I + A)^{-1}` when `D` is tied to `B` by `G(-1) = 0`, else `None`.
    fn nyquist_gain(self, a: MatRef<'_, f64>, c: MatRef<'_, f64>) -> Result<Option<Mat<f64>>> {
        if self != Self::ZeroAtNyquist {
            return Ok(None);
        }
        let n = a.nrows();
        let ipa = Mat::from_fn(n, n, |i, j| a[(i, j)] + if i == j { 1.0 } else { 0.0 });
        Ok(Some(c * pinv(ipa.as_ref(), 1e-14)?))
    }

    /// `D` from the fitted `B` (and the estimated `D` when it is free).
    fn direct_term(self, nyq: Option<&Mat<f64>>, b: &Mat<f64>, free: Mat<f64>) -> Mat<f64> {
        match (self, nyq) {
            (Self::Estimate, _) => free,
            (_, Some(g)) => g * b,
            _ => Mat::zeros(free.nrows(), free.ncols()),
        }
    }
}

/// Result of [`identify_frd`].
#[derive(Debug, Clone)]
pub struct FrdIdentified {
    /// The discrete-time model.
    pub sys: StateSpace,
    /// Singular values of the projected data, largest first.
    pub singular_values: Vec<f64>,
}

/// Identifies `(A, B, C, D)` of `order` (or the largest log gap when `None`) from `G_k`
/// (real and imaginary parts, each `l x m`) at `omega` (rad/sample) with horizon `q`; `D`
/// as `feedthrough` says.
pub fn identify_frd(
    omega: &[f64],
    g_re: &[MatRef<'_, f64>],
    g_im: &[MatRef<'_, f64>],
    weights: Option<&[f64]>,
    order: Option<usize>,
    q: usize,
    feedthrough: Feedthrough,
) -> Result<FrdIdentified> {
    let nf = omega.len();
    if nf == 0 || g_re.len() != nf || g_im.len() != nf {
        return Err(SysidError::invalid(
            "frequency data",
            "omega, the real and the imaginary parts need the same, non-zero length",
        ));
    }
    let (l, m) = (g_re[0].nrows(), g_re[0].ncols());
    if l == 0 || m == 0 {
        return Err(SysidError::invalid(
            "frequency data",
            "needs inputs and outputs",
        ));
    }
    if q < 2 {
        return Err(SysidError::invalid("horizon", "must be >= 2"));
    }
    let w: Vec<f64> = match weights {
        Some(w) if w.len() == nf => w.to_vec(),
        Some(_) => return Err(SysidError::invalid("weights", "one weight per frequency")),
        None => vec![1.0; nf],
    };
    for k in 0..nf {
        if !omega[k].is_finite() || !w[k].is_finite() || w[k] < 0.0 {
            return Err(SysidError::invalid(
                "frequency data",
                "frequencies and weights must be finite, weights non-negative",
            ));
        }
        crate::error::check_finite("response (real part)", g_re[k])?;
        crate::error::check_finite("response (imaginary part)", g_im[k])?;
    }
    // [U; Y], real and imaginary parts of each frequency's m columns side by side
    let rows_u = q * m;
    let rows = q * (m + l);
    let mut z = Mat::<f64>::zeros(rows, 2 * nf * m);
    for k in 0..nf {
        for i in 0..q {
            let (c, s) = ((i as f64 * omega[k]).cos(), (i as f64 * omega[k]).sin());
            for j in 0..m {
                let (cr, ci) = (2 * k * m + j, (2 * k + 1) * m + j);
                z[(i * m + j, cr)] = w[k] * c;
                z[(i * m + j, ci)] = w[k] * s;
                for r in 0..l {
                    let (gr, gi) = (g_re[k][(r, j)], g_im[k][(r, j)]);
                    z[(rows_u + i * l + r, cr)] = w[k] * (c * gr - s * gi);
                    z[(rows_u + i * l + r, ci)] = w[k] * (c * gi + s * gr);
                }
            }
        }
    }
    let (u_sv, sv, rank) = output_subspace(
        z.as_ref(),
        rows_u,
        q * l,
        "the response carries nothing beyond a constant; is it zero?",
    )?;
    let max = ((q - 1) * l).min(rank).min(2 * nf * m);
    let (_, a, c) = order_and_ac(u_sv.as_ref(), &sv, order, max, q, l)?;
    let (b, d) = fit_bd(omega, g_re, g_im, &w, a.as_ref(), c.as_ref(), feedthrough)?;
    let sys = StateSpace::new(a, b, c, d).map_err(|_| {
        SysidError::numerical(
            "system matrices",
            "non-finite estimates; lower the order or check the frequency data",
        )
    })?;
    Ok(FrdIdentified {
        sys,
        singular_values: sv,
    })
}

/// Identifies `(A, B, C, D)` from the DFTs of one record's input and output, `U_k` (rows
/// of `u_re`, `u_im`: `nf x m`) and `Y_k` (`nf x l`) at `omega` (rad/sample), with
/// `Y_k = G(z_k) U_k + C (z_k I - A)^{-1} z_k x_t` where the transient `x_t` (the initial
/// minus the final state, scaled as the DFT) is estimated with B and D when `transient` is
/// set (McKelvey, Akçay & Ljung 1996, the input/output spectra form); `D` as `feedthrough`
/// says. Exact for noise-free records, periodic or not.
#[allow(clippy::too_many_arguments)]
pub fn identify_spectra(
    omega: &[f64],
    u_re: MatRef<'_, f64>,
    u_im: MatRef<'_, f64>,
    y_re: MatRef<'_, f64>,
    y_im: MatRef<'_, f64>,
    weights: Option<&[f64]>,
    order: Option<usize>,
    q: usize,
    transient: bool,
    feedthrough: Feedthrough,
) -> Result<FrdIdentified> {
    let nf = omega.len();
    let (m, l) = (u_re.ncols(), y_re.ncols());
    if nf == 0
        || u_re.nrows() != nf
        || u_im.nrows() != nf
        || y_re.nrows() != nf
        || y_im.nrows() != nf
        || u_im.ncols() != m
        || y_im.ncols() != l
    {
        return Err(SysidError::invalid(
            "spectra",
            "omega and the input/output DFTs need the same number of frequencies",
        ));
    }
    if l == 0 || m == 0 || q < 2 {
        return Err(SysidError::invalid(
            "spectra",
            "needs inputs, outputs and a horizon >= 2",
        ));
    }
    let w: Vec<f64> = match weights {
        Some(w) if w.len() == nf => w.to_vec(),
        Some(_) => return Err(SysidError::invalid("weights", "one weight per frequency")),
        None => vec![1.0; nf],
    };
    for x in [u_re, u_im, y_re, y_im] {
        crate::error::check_finite("spectra", x)?;
    }
    // the transient acts as one more input with DFT z_k (an impulse into the state)
    let mt = m + usize::from(transient);
    let rows_u = q * mt;
    let mut z = Mat::<f64>::zeros(q * (mt + l), 2 * nf);
    for k in 0..nf {
        for i in 0..q {
            let (c, s) = ((i as f64 * omega[k]).cos(), (i as f64 * omega[k]).sin());
            for j in 0..m {
                let (a, b) = (u_re[(k, j)], u_im[(k, j)]);
                z[(i * mt + j, 2 * k)] = w[k] * (c * a - s * b);
                z[(i * mt + j, 2 * k + 1)] = w[k] * (c * b + s * a);
            }
            if transient {
                let ang = (i + 1) as f64 * omega[k];
                z[(i * mt + m, 2 * k)] = w[k] * ang.cos();
                z[(i * mt + m, 2 * k + 1)] = w[k] * ang.sin();
            }
            for r in 0..l {
                let (a, b) = (y_re[(k, r)], y_im[(k, r)]);
                z[(rows_u + i * l + r, 2 * k)] = w[k] * (c * a - s * b);
                z[(rows_u + i * l + r, 2 * k + 1)] = w[k] * (c * b + s * a);
            }
        }
    }
    let (u_sv, sv, rank) = output_subspace(
        z.as_ref(),
        rows_u,
        q * l,
        "the output spectra carry nothing beyond the input's; are the outputs zero?",
    )?;
    let max = ((q - 1) * l).min(rank);
    let (n, a, c) = order_and_ac(u_sv.as_ref(), &sv, order, max, q, l)?;
    // B, D (and the transient) by least squares: unknowns vec(B), vec(D) when free, x_t
    let nd = if feedthrough == Feedthrough::Estimate {
        l * m
    } else {
        0
    };
    let nt = n * m + nd + if transient { n } else { 0 };
    let nyq = feedthrough.nyquist_gain(a.as_ref(), c.as_ref())?;
    let mut design = Mat::<f64>::zeros(2 * l * nf, nt);
    let mut rhs = Mat::<f64>::zeros(2 * l * nf, 1);
    for k in 0..nf {
        let (co, si) = (omega[k].cos(), omega[k].sin());
        let (fr, fi) = resolvent(a.as_ref(), c.as_ref(), co, si)?;
        // D tied to B (G(-1) = 0): the B columns carry F_k + C (I + A)^{-1}
        let tied = nyq.as_ref().map(|g| &fr + g);
        let fb = tied.as_ref().unwrap_or(&fr);
        for r in 0..l {
            let (re_row, im_row) = (2 * l * k + r, 2 * l * k + l + r);
            for i in 0..m {
                let (ur, ui) = (u_re[(k, i)], u_im[(k, i)]);
                for p in 0..n {
                    let col = i * n + p; // B[p, i], column-major
                    design[(re_row, col)] = w[k] * (fb[(r, p)] * ur - fi[(r, p)] * ui);
                    design[(im_row, col)] = w[k] * (fb[(r, p)] * ui + fi[(r, p)] * ur);
                }
                if nd > 0 {
                    let col = n * m + i * l + r; // D[r, i]
                    design[(re_row, col)] = w[k] * ur;
                    design[(im_row, col)] = w[k] * ui;
                }
            }
            if transient {
                for p in 0..n {
                    let col = n * m + nd + p; // F_k z_k x_t
                    design[(re_row, col)] = w[k] * (fr[(r, p)] * co - fi[(r, p)] * si);
                    design[(im_row, col)] = w[k] * (fr[(r, p)] * si + fi[(r, p)] * co);
                }
            }
            rhs[(re_row, 0)] = w[k] * y_re[(k, r)];
            rhs[(im_row, 0)] = w[k] * y_im[(k, r)];
        }
    }
    let th = pinv(design.as_ref(), 1e-13)? * &rhs;
    let b = Mat::from_fn(n, m, |p, i| th[(i * n + p, 0)]);
    let free = Mat::from_fn(l, m, |r, i| {
        if nd > 0 {
            th[(n * m + i * l + r, 0)]
        } else {
            0.0
        }
    });
    let d = feedthrough.direct_term(nyq.as_ref(), &b, free);
    let sys = StateSpace::new(a, b, c, d).map_err(|_| {
        SysidError::numerical(
            "system matrices",
            "non-finite estimates; lower the order or check the spectra",
        )
    })?;
    Ok(FrdIdentified {
        sys,
        singular_values: sv,
    })
}

/// `C (z I - A)^{-1}` at `z = co + j si`, real and imaginary parts.
/// The order (given, or the largest gap of the log singular values up to `max`) and `A`, `C`
/// by shift invariance of the first `n` left singular vectors `u` scaled by `sqrt(sv)`.
fn order_and_ac(
    u: MatRef<'_, f64>,
    sv: &[f64],
    order: Option<usize>,
    max: usize,
    q: usize,
    l: usize,
) -> Result<(usize, Mat<f64>, Mat<f64>)> {
    let n = order.unwrap_or_else(|| largest_log_gap(sv, max));
    if n == 0 || n > max {
        return Err(SysidError::OrderTooLarge {
            order: n,
            max,
            future: q,
            outputs: l,
        });
    }
    let mut gamma = u.subcols(0, n).to_owned();
    for j in 0..n {
        let s = sv[j].sqrt();
        for i in 0..gamma.nrows() {
            gamma[(i, j)] *= s;
        }
    }
    let (a, c, _) = shift_invariance(gamma.as_ref(), l, false)?;
    Ok((n, a, c))
}

fn resolvent(
    a: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    co: f64,
    si: f64,
) -> Result<(Mat<f64>, Mat<f64>)> {
    let n = a.nrows();
    let mut big = Mat::<f64>::zeros(2 * n, 2 * n);
    for i in 0..n {
        for j in 0..n {
            big[(i, j)] = -a[(i, j)];
            big[(n + i, n + j)] = -a[(i, j)];
        }
        big[(i, i)] += co;
        big[(n + i, n + i)] += co;
        big[(i, n + i)] = -si;
        big[(n + i, i)] = si;
    }
    let inv = pinv(big.as_ref(), 1e-14)?;
    Ok((
        c * inv.as_ref().submatrix(0, 0, n, n),
        c * inv.as_ref().submatrix(n, 0, n, n),
    ))
}

/// B and D minimising `Σ_k w_k^2 |G_k - D - C (z_k I - A)^{-1} B|^2`, column by column,
/// with `D` free, zero or tied to `B` as `feedthrough` says.
fn fit_bd(
    omega: &[f64],
    g_re: &[MatRef<'_, f64>],
    g_im: &[MatRef<'_, f64>],
    w: &[f64],
    a: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    feedthrough: Feedthrough,
) -> Result<(Mat<f64>, Mat<f64>)> {
    let (n, l, m, nf) = (a.nrows(), c.nrows(), g_re[0].ncols(), omega.len());
    let nd = if feedthrough == Feedthrough::Estimate {
        l
    } else {
        0
    };
    let nyq = feedthrough.nyquist_gain(a, c)?;
    // F_k = C (z_k I - A)^{-1} in real form from [[cI - A, -sI], [sI, cI - A]]
    let mut design = Mat::<f64>::zeros(2 * l * nf, n + nd);
    for k in 0..nf {
        let (co, si) = (omega[k].cos(), omega[k].sin());
        let mut big = Mat::<f64>::zeros(2 * n, 2 * n);
        for i in 0..n {
            for j in 0..n {
                let v = -a[(i, j)];
                big[(i, j)] = v;
                big[(n + i, n + j)] = v;
            }
            big[(i, i)] += co;
            big[(n + i, n + i)] += co;
            big[(i, n + i)] = -si;
            big[(n + i, i)] = si;
        }
        let inv = pinv(big.as_ref(), 1e-14)?;
        let xr = inv.as_ref().submatrix(0, 0, n, n);
        let xi = inv.as_ref().submatrix(n, 0, n, n);
        let fr = match &nyq {
            Some(g) => c * xr + g,
            None => c * xr,
        };
        let fi = c * xi;
        for r in 0..l {
            for j in 0..n {
                design[(2 * l * k + r, j)] = w[k] * fr[(r, j)];
                design[(2 * l * k + l + r, j)] = w[k] * fi[(r, j)];
            }
            if nd > 0 {
                design[(2 * l * k + r, n + r)] = w[k];
            }
        }
    }
    let dp = pinv(design.as_ref(), 1e-13)?;
    let mut b = Mat::<f64>::zeros(n, m);
    let mut d = Mat::<f64>::zeros(l, m);
    for j in 0..m {
        let mut rhs = Mat::<f64>::zeros(2 * l * nf, 1);
        for k in 0..nf {
            for r in 0..l {
                rhs[(2 * l * k + r, 0)] = w[k] * g_re[k][(r, j)];
                rhs[(2 * l * k + l + r, 0)] = w[k] * g_im[k][(r, j)];
            }
        }
        let th = &dp * &rhs;
        for i in 0..n {
            b[(i, j)] = th[(i, 0)];
        }
        for r in 0..nd {
            d[(r, j)] = th[(n + r, 0)];
        }
    }
    let d = feedthrough.direct_term(nyq.as_ref(), &b, d);
    Ok((b, d))
}

/// The LQ factor of the stacked data `z`, its output block (rows after the first `rows_u`,
/// `rows` of them) projected off the inputs, and that block's left singular vectors,
/// singular values and numerical rank (relative tolerance 1e-12); `empty` is the error when
/// the block is zero.
fn output_subspace(
    z: MatRef<'_, f64>,
    rows_u: usize,
    rows: usize,
    empty: &str,
) -> Result<(Mat<f64>, Vec<f64>, usize)> {
    let lfac = lq_lower(z);
    let l22 = lfac.as_ref().submatrix(rows_u, rows_u, rows, rows);
    let (sv, u) = crate::linalg::svd_left_seq("frequency-domain SVD", l22)?;
    let smax = sv.first().copied().unwrap_or(0.0);
    if !smax.is_finite() || smax <= 0.0 {
        return Err(SysidError::numerical(
            "frequency-domain SVD",
            empty.to_string(),
        ));
    }
    let rank = sv.iter().filter(|&&x| x > 1e-12 * smax).count();
    Ok((u, sv, rank))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_frequency_response_gives_the_system() {
        // 3rd-order, 2 outputs, 1 input
        let a = faer::mat![[0.7, 0.3, 0.0], [-0.3, 0.7, 0.0], [0.0, 0.0, -0.5]];
        let b = faer::mat![[1.0], [0.0], [0.5]];
        let c = faer::mat![[1.0, 0.0, 1.0], [0.0, 1.0, 0.2]];
        let d = faer::mat![[0.1], [0.0]];
        let omega: Vec<f64> = (0..40).map(|k| 0.05 + 3.0 * k as f64 / 40.0).collect();
        let resp =
            |a: MatRef<'_, f64>, b: MatRef<'_, f64>, c: MatRef<'_, f64>, d: MatRef<'_, f64>| {
                omega
                    .iter()
                    .map(|&om| fit_bd_response(a, b, c, d, om))
                    .collect::<Vec<_>>()
            };
        let g = resp(a.as_ref(), b.as_ref(), c.as_ref(), d.as_ref());
        let re: Vec<MatRef<'_, f64>> = g.iter().map(|x| x.0.as_ref()).collect();
        let im: Vec<MatRef<'_, f64>> = g.iter().map(|x| x.1.as_ref()).collect();
        let id = identify_frd(&omega, &re, &im, None, None, 6, Feedthrough::Estimate).unwrap();
        assert_eq!(id.sys.a.nrows(), 3);
        let g2 = resp(
            id.sys.a.as_ref(),
            id.sys.b.as_ref(),
            id.sys.c.as_ref(),
            id.sys.d.as_ref(),
        );
        for (x, y) in g.iter().zip(g2.iter()) {
            assert!((&x.0 - &y.0).norm_max() < 1e-9 && (&x.1 - &y.1).norm_max() < 1e-9);
        }
    }

    #[test]
    fn direct_term_zero_or_tied_to_b_is_exact() {
        let a = faer::mat![[0.7, 0.3], [-0.3, 0.7]];
        let b = faer::mat![[1.0], [0.5]];
        let c = faer::mat![[1.0, 0.2]];
        let ipa = faer::mat![[1.7, 0.3], [-0.3, 1.7]];
        let tied = &c * pinv(ipa.as_ref(), 1e-14).unwrap() * &b;
        let omega: Vec<f64> = (0..30).map(|k| 0.05 + 3.0 * k as f64 / 30.0).collect();
        for (mode, d) in [
            (Feedthrough::Zero, faer::mat![[0.0]]),
            (Feedthrough::ZeroAtNyquist, tied),
        ] {
            let g: Vec<_> = omega
                .iter()
                .map(|&om| fit_bd_response(a.as_ref(), b.as_ref(), c.as_ref(), d.as_ref(), om))
                .collect();
            let re: Vec<MatRef<'_, f64>> = g.iter().map(|x| x.0.as_ref()).collect();
            let im: Vec<MatRef<'_, f64>> = g.iter().map(|x| x.1.as_ref()).collect();
            let id = identify_frd(&omega, &re, &im, None, Some(2), 5, mode).unwrap();
            assert!(
                (&id.sys.d - &d).norm_max() < 1e-9,
                "{mode:?}: D = {:?}",
                id.sys.d
            );
            for (k, &om) in omega.iter().enumerate() {
                let s = &id.sys;
                let (r, i) =
                    fit_bd_response(s.a.as_ref(), s.b.as_ref(), s.c.as_ref(), s.d.as_ref(), om);
                assert!((&r - &g[k].0).norm_max() < 1e-9 && (&i - &g[k].1).norm_max() < 1e-9);
            }
        }
    }

    /// G(e^{jω}) in real and imaginary parts, through the real 2n x 2n system.
    fn fit_bd_response(
        a: MatRef<'_, f64>,
        b: MatRef<'_, f64>,
        c: MatRef<'_, f64>,
        d: MatRef<'_, f64>,
        om: f64,
    ) -> (Mat<f64>, Mat<f64>) {
        let n = a.nrows();
        let (co, si) = (om.cos(), om.sin());
        let mut big = Mat::<f64>::zeros(2 * n, 2 * n);
        for i in 0..n {
            for j in 0..n {
                big[(i, j)] = -a[(i, j)];
                big[(n + i, n + j)] = -a[(i, j)];
            }
            big[(i, i)] += co;
            big[(n + i, n + i)] += co;
            big[(i, n + i)] = -si;
            big[(n + i, i)] = si;
        }
        let inv = pinv(big.as_ref(), 1e-14).unwrap();
        let xr = inv.as_ref().submatrix(0, 0, n, n) * b;
        let xi = inv.as_ref().submatrix(n, 0, n, n) * b;
        (c * &xr + d, c * &xi)
    }
}
