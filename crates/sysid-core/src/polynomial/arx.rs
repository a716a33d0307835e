//! Least-squares ARX from one streaming compression of the lagged data.

use faer::{Mat, MatRef};

use crate::error::{check_io, Result, SysidError};
use crate::linalg::QrAccumulator;

/// The compressed summary of one or more records: the triangular factor of the matrix whose
/// row `t` holds lags `0..=max_lag` of every input then every output.
#[derive(Debug, Clone)]
pub struct ArxCompressor {
    n_inputs: usize,
    n_outputs: usize,
    max_lag: usize,
    acc: QrAccumulator,
}

/// Orders of a (MIMO) ARX structure: `na` (outputs x outputs), `nb` and `nk`
/// (outputs x inputs), row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct ArxOrders {
    /// `na[i][k]`: lags of output k in the equation of output i.
    pub na: Vec<Vec<usize>>,
    /// `nb[i][j]`: number of coefficients of input j in the equation of output i.
    pub nb: Vec<Vec<usize>>,
    /// `nk[i][j]`: delay of input j in the equation of output i.
    pub nk: Vec<Vec<usize>>,
}

/// One output's least-squares solution.
#[derive(Debug, Clone)]
pub struct ArxFit {
    /// `A` coefficients: `a[k]` holds `a_1..a_na` of output k in this equation.
    pub a: Vec<Vec<f64>>,
    /// `B` coefficients per input, `b_0..b_{nb-1}` (applied to `u_j(t-nk)...`).
    pub b: Vec<Vec<f64>>,
    /// Regression parameters in the order `[-a (per output), b (per input)]`... stored as
    /// `[a..., b...]` with the signs of the polynomials.
    pub theta: Vec<f64>,
    /// Mean squared residual (loss function V).
    pub loss: f64,
    /// `(Phi^T Phi)^-1` (without regularisation in the inverse: with regularisation,
    /// `(Phi^T Phi + lambda M^T M)^-1`), for the covariance `loss * this`.
    pub unscaled_cov: Mat<f64>,
    /// Rows of the regression.
    pub n_rows: usize,
}

impl ArxCompressor {
    /// A compressor for `n_inputs` inputs and `n_outputs` outputs with lags up to `max_lag`.
    ///
    /// ```
    /// use faer::Mat;
    /// use sysid_core::polynomial::arx::{ArxCompressor, ArxOrders};
    /// let n = 200;
    /// let u = Mat::from_fn(n, 1, |t, _| ((t * 7919) % 13) as f64 - 6.0);
    /// let mut y = Mat::<f64>::zeros(n, 1);
    /// for t in 1..n { y[(t, 0)] = 0.5 * y[(t - 1, 0)] + u[(t - 1, 0)]; }
    /// let mut c = ArxCompressor::new(1, 1, 2).unwrap();
    /// c.push(u.as_ref(), y.as_ref()).unwrap();
    /// let orders = ArxOrders { na: vec![vec![1]], nb: vec![vec![1]], nk: vec![vec![1]] };
    /// let fit = c.solve_output(0, &orders, 0.0, None).unwrap();
    /// assert!((fit.a[0][0] + 0.5).abs() < 1e-10 && (fit.b[0][0] - 1.0).abs() < 1e-10);
    /// ```
    pub fn new(n_inputs: usize, n_outputs: usize, max_lag: usize) -> Result<Self> {
        if n_outputs == 0 {
            return Err(SysidError::invalid(
                "y",
                "needs at least one output channel",
            ));
        }
        if max_lag == 0 {
            return Err(SysidError::invalid("max_lag", "must be at least 1"));
        }
        let k = n_inputs
            .checked_add(n_outputs)
            .and_then(|d| max_lag.checked_add(1).and_then(|l| d.checked_mul(l)))
            .unwrap_or(usize::MAX);
        if k > 4000 {
            return Err(SysidError::invalid(
                "orders",
                format!("{k} lagged columns is too many; lower the orders or delays"),
            ));
        }
        Ok(Self {
            n_inputs,
            n_outputs,
            max_lag,
            acc: QrAccumulator::new(k, 256.max(k)),
        })
    }

    /// Column of channel `c` (inputs first, then outputs) at lag `lag`.
    fn col(&self, channel: usize, lag: usize) -> usize {
        channel * (self.max_lag + 1) + lag
    }

    /// Adds one experiment (rows `max_lag..N`).
    pub fn push(&mut self, u: MatRef<'_, f64>, y: MatRef<'_, f64>) -> Result<()> {
        check_io("u, y", u, y, self.n_inputs, self.n_outputs)?;
        let n = y.nrows();
        if n <= self.max_lag {
            return Err(SysidError::InsufficientData {
                context: format!("an ARX regression with lags up to {}", self.max_lag),
                needed: self.max_lag + 1,
                got: n,
                fix: "use a longer record or smaller orders and delays",
            });
        }
        let k = self.acc.k();
        let mut row = vec![0.0; k];
        for t in self.max_lag..n {
            if t % 4096 == 0 {
                crate::interrupt::check()?; // Ctrl-C
            }
            for j in 0..self.n_inputs {
                for lag in 0..=self.max_lag {
                    row[self.col(j, lag)] = u[(t - lag, j)];
                }
            }
            for i in 0..self.n_outputs {
                for lag in 0..=self.max_lag {
                    row[self.col(self.n_inputs + i, lag)] = y[(t - lag, i)];
                }
            }
            self.acc.push_row(&row);
        }
        Ok(())
    }

    /// Rows pushed so far.
    pub fn n_rows(&self) -> usize {
        self.acc.n_rows()
    }

    /// The triangular factor (flushes pending rows).
    pub fn factor(&self) -> Mat<f64> {
        self.acc.clone().finish()
    }

    /// Columns of the factor that output `i`'s regression of `orders` selects, and its target
    /// column; checks the orders and that there are more rows than parameters.
    fn columns(&self, i: usize, orders: &ArxOrders) -> Result<(Vec<usize>, usize)> {
        let (ny, nu) = (self.n_outputs, self.n_inputs);
        if i >= ny {
            return Err(SysidError::invalid(
                "output",
                format!("output {i} does not exist; the data have {ny} output(s)"),
            ));
        }
        if orders.na.len() != ny
            || orders.nb.len() != ny
            || orders.nk.len() != ny
            || orders.na.iter().any(|r| r.len() != ny)
            || orders.nb.iter().any(|r| r.len() != nu)
            || orders.nk.iter().any(|r| r.len() != nu)
        {
            return Err(SysidError::invalid(
                "orders",
                format!("na must be {ny} x {ny}, nb and nk {ny} x {nu}"),
            ));
        }
        let mut cols = Vec::new();
        for k in 0..ny {
            let na = orders.na[i][k];
            if na > self.max_lag {
                return Err(SysidError::invalid(
                    "na",
                    format!("{na} exceeds max_lag {}", self.max_lag),
                ));
            }
            for lag in 1..=na {
                cols.push(self.col(nu + k, lag));
            }
        }
        for j in 0..nu {
            let (nb, nk) = (orders.nb[i][j], orders.nk[i][j]);
            if nb > 0 && nk + nb - 1 > self.max_lag {
                return Err(SysidError::invalid(
                    "nb, nk",
                    format!(
                        "nk + nb - 1 = {} exceeds max_lag {}",
                        nk + nb - 1,
                        self.max_lag
                    ),
                ));
            }
            for lag in nk..nk + nb {
                cols.push(self.col(j, lag));
            }
        }
        let p = cols.len();
        let nrows = self.acc.n_rows();
        if nrows < p + 1 {
            return Err(SysidError::InsufficientData {
                context: format!("an ARX fit with {p} parameters"),
                needed: p + 1,
                got: nrows,
                fix: "use a longer record or smaller orders",
            });
        }
        Ok((cols, self.col(nu + i, 0)))
    }

    /// The compressed regression of output `i` of `orders`: the upper-triangular
    /// `(p + 1) x (p + 1)` factor `[[R11, r], [0, rho]]` of `[Phi_i  y_i]` (`p` parameters in
    /// the order of [`ArxFit::theta`], regressor signs: `y(t - lag)` columns, so the `A`
    /// coefficients are `-theta_a`). `R11^T R11 = Phi^T Phi`, `R11^T r = Phi^T y` and
    /// `|r|^2 + rho^2 = y^T y`: everything a regularised fit or a marginal likelihood needs,
    /// of a size independent of the record length.
    ///
    /// ```
    /// use faer::Mat;
    /// use sysid_core::polynomial::arx::{ArxCompressor, ArxOrders};
    /// let n = 100;
    /// let u = Mat::from_fn(n, 1, |t, _| ((t * 7919) % 13) as f64 - 6.0);
    /// let y = Mat::from_fn(n, 1, |t, _| if t > 0 { 2.0 * u[(t - 1, 0)] } else { 0.0 });
    /// let mut c = ArxCompressor::new(1, 1, 1).unwrap();
    /// c.push(u.as_ref(), y.as_ref()).unwrap();
    /// let o = ArxOrders { na: vec![vec![0]], nb: vec![vec![1]], nk: vec![vec![1]] };
    /// let s = c.output_summary(c.factor().as_ref(), 0, &o).unwrap();
    /// assert!((s[(0, 1)] / s[(0, 0)] - 2.0).abs() < 1e-12 && s[(1, 1)].abs() < 1e-9);
    /// ```
    pub fn output_summary(
        &self,
        r: MatRef<'_, f64>,
        i: usize,
        orders: &ArxOrders,
    ) -> Result<Mat<f64>> {
        let (cols, target) = self.columns(i, orders)?;
        let p = cols.len();
        let k = r.nrows();
        let s = Mat::from_fn(k, p + 1, |row, c| {
            r[(row, if c < p { cols[c] } else { target })]
        });
        let rs = crate::linalg::thin_r_seq(s.as_ref());
        Ok(Mat::from_fn(p + 1, p + 1, |a, b| {
            if a <= b && a < rs.nrows() {
                rs[(a, b)]
            } else {
                0.0
            }
        }))
    }

    /// Least squares for output `i` of `orders`, with optional regularisation
    /// `lambda * |M theta|^2` (`M = None`: the identity, i.e. ridge).
    pub fn solve_output(
        &self,
        i: usize,
        orders: &ArxOrders,
        lambda: f64,
        m: Option<MatRef<'_, f64>>,
    ) -> Result<ArxFit> {
        let r = self.factor();
        self.solve_with_factor(r.as_ref(), i, orders, lambda, m)
    }

    /// As [`Self::solve_output`] on an already finished factor (for order searches).
    pub fn solve_with_factor(
        &self,
        r: MatRef<'_, f64>,
        i: usize,
        orders: &ArxOrders,
        lambda: f64,
        m: Option<MatRef<'_, f64>>,
    ) -> Result<ArxFit> {
        let (ny, nu) = (self.n_outputs, self.n_inputs);
        let (cols, target) = self.columns(i, orders)?;
        let p = cols.len();
        let nrows = self.acc.n_rows();
        let k = r.nrows();
        let extra = if lambda > 0.0 {
            m.map_or(p, |m| m.nrows())
        } else {
            0
        };
        if let Some(m) = m {
            if m.ncols() != p {
                return Err(SysidError::ShapeMismatch {
                    what: "regularisation factor".into(),
                    expected: format!("(q, {p})"),
                    got: format!("({}, {})", m.nrows(), m.ncols()),
                });
            }
        }
        let sl = lambda.max(0.0).sqrt();
        let mut s = Mat::<f64>::zeros(k + extra, p + 1);
        for (c, &src) in cols.iter().enumerate() {
            for row in 0..k {
                s[(row, c)] = r[(row, src)];
            }
        }
        for row in 0..k {
            s[(row, p)] = r[(row, target)];
        }
        if extra > 0 {
            for a in 0..extra {
                for c in 0..p {
                    s[(k + a, c)] = match m {
                        Some(m) => sl * m[(a, c)],
                        None => {
                            if a == c {
                                sl
                            } else {
                                0.0
                            }
                        }
                    };
                }
            }
        }
        let rs = crate::linalg::thin_r_seq(s.as_ref());
        // Rank check of the regression.
        let dmax = (0..p).map(|d| rs[(d, d)].abs()).fold(0.0, f64::max);
        for d in 0..p {
            if rs[(d, d)].abs().is_nan() || rs[(d, d)].abs() <= 1e-12 * dmax || dmax == 0.0 {
                return Err(SysidError::RegressorRank {
                    estimator: "arx",
                    rank: d,
                    columns: p,
                    tol: 1e-12,
                    fix: "use lower orders (na, nb), drop constant or duplicated input \
                          channels, or a richer input (white noise, PRBS, multisine)",
                });
            }
        }
        // Back substitution R11 theta = r12.
        let mut theta = vec![0.0; p];
        for d in (0..p).rev() {
            let mut v = rs[(d, p)];
            for e in d + 1..p {
                v -= rs[(d, e)] * theta[e];
            }
            theta[d] = v / rs[(d, d)];
        }
        // (R11^T R11)^-1 = R11^-1 R11^-T.
        let mut rinv = Mat::<f64>::zeros(p, p);
        for c in 0..p {
            for d in (0..=c).rev() {
                let mut v = if d == c { 1.0 } else { 0.0 };
                for e in d + 1..=c {
                    v -= rs[(d, e)] * rinv[(e, c)];
                }
                rinv[(d, c)] = v / rs[(d, d)];
            }
        }
        let unscaled_cov = &rinv * rinv.transpose();
        // Residual sum of squares: recompute without the penalty rows' contribution.
        let mut rss = rs[(p, p)] * rs[(p, p)];
        if extra > 0 {
            // rs[p,p]^2 = |y - Phi theta|^2 + lambda |M theta|^2.
            let mut pen = 0.0;
            for a in 0..extra {
                let mut v = 0.0;
                for c in 0..p {
                    v += s[(k + a, c)] * theta[c];
                }
                pen += v * v;
            }
            rss = (rss - pen).max(0.0);
        }
        // Polynomial signs: A y = B u  =>  y(t) = -a y(t-k) + b u.
        let mut a = Vec::with_capacity(ny);
        let mut idx = 0;
        let mut poly_theta = theta.clone();
        for kk in 0..ny {
            let na = orders.na[i][kk];
            let coeffs: Vec<f64> = theta[idx..idx + na].iter().map(|v| -v).collect();
            for q in idx..idx + na {
                poly_theta[q] = -theta[q];
            }
            idx += na;
            a.push(coeffs);
        }
        let mut b = Vec::with_capacity(nu);
        for j in 0..nu {
            let nb = orders.nb[i][j];
            b.push(theta[idx..idx + nb].to_vec());
            idx += nb;
        }
        // Covariance of the polynomial coefficients: flip signs of the `a` rows/cols.
        let na_tot: usize = orders.na[i].iter().sum();
        let mut cov = unscaled_cov;
        for q in 0..p {
            for w in 0..p {
                if (q < na_tot) != (w < na_tot) {
                    cov[(q, w)] = -cov[(q, w)];
                }
            }
        }
        Ok(ArxFit {
            a,
            b,
            theta: poly_theta,
            loss: rss / nrows as f64,
            unscaled_cov: cov,
            n_rows: nrows,
        })
    }

    /// Loss (mean squared residual, all outputs summed) of every SISO-pattern structure
    /// `na in na_range, nb in nb_range, nk in nk_range` (same orders for all channels), from the
    /// one compression: rows `[na, nb, nk, loss, n_params]`. Structures whose regression is
    /// rank deficient (over-parameterised for noise-free data) are left out of the table.
    pub fn arxstruc(
        &self,
        na_range: &[usize],
        nb_range: &[usize],
        nk_range: &[usize],
    ) -> Result<Vec<[f64; 5]>> {
        let r = self.factor();
        let (ny, nu) = (self.n_outputs, self.n_inputs);
        let mut out = Vec::new();
        for &na in na_range {
            for &nb in nb_range {
                for &nk in nk_range {
                    crate::interrupt::check()?;
                    if na + nb == 0 || (nb > 0 && nk + nb - 1 > self.max_lag) || na > self.max_lag {
                        continue;
                    }
                    let orders = ArxOrders {
                        na: (0..ny)
                            .map(|i| (0..ny).map(|k| if i == k { na } else { 0 }).collect())
                            .collect(),
                        nb: vec![vec![nb; nu]; ny],
                        nk: vec![vec![nk; nu]; ny],
                    };
                    let mut loss = 0.0;
                    let mut deficient = false;
                    for i in 0..ny {
                        match self.solve_with_factor(r.as_ref(), i, &orders, 0.0, None) {
                            Ok(f) => loss += f.loss,
                            Err(SysidError::RegressorRank { .. }) => deficient = true,
                            Err(e) => return Err(e),
                        }
                    }
                    if deficient {
                        continue;
                    }
                    let np = ny * (na + nu * nb);
                    out.push([na as f64, nb as f64, nk as f64, loss, np as f64]);
                }
            }
        }
        Ok(out)
    }
}
