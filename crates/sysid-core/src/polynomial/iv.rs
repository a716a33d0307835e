//! Instrumental variables: the four-stage IV4 method for (MIMO) ARX structures
//! `A(q) y = B(q) u + v` (Ljung, System Identification, 1999, sec. 15.3), over one or
//! several experiments.
//!
//! Each output's equation `y_i + sum_k A_ik y_k = sum_j B_ij u_j(t - nk_ij) + v_i` is solved
//! from `sum z(t) phi(t)^T theta = sum z(t) y_i(t)`, where `phi` holds the lagged outputs and
//! inputs and the instruments `z` the same lags of a noise-free simulated output `x` and of
//! the instrument input `r` (the input itself in open loop; the reference in closed loop, so
//! that no instrument is correlated with the noise). The four stages: (1) least squares;
//! (2) IV with `x` simulated from the stage-1 model; (3) an AR model `L_i` (order = number of
//! parameters of the equation) of the stage-2 equation error; (4) IV on the data prefiltered
//! by `L_i`, with `x` simulated from the stage-2 model. With a reference (closed loop) the
//! instruments of every stage are instead the parts of `y` and `u` explained by the
//! reference (a least-squares FIR projection on its lags), which the feedback cannot
//! correlate with the noise; stage 1 is then IV with those instruments. Sums run over the rows of every
//! experiment separately (each filtered and simulated from rest): no sample of one experiment
//! enters a regressor or instrument of another. The prefilter `L_i` of order `n` is a moving
//! average started from rest, so the first `n` filtered samples of an experiment lack the
//! samples before it: the sums of stage 4 (and of the covariance) start `n` rows later in
//! every experiment (a record that does not start at rest was otherwise fitted with a bias,
//! `5e-4` on noise-free data).

use faer::linalg::solvers::Solve;
use faer::{Mat, MatRef};

use super::arx::ArxOrders;
use super::filter::{filter, monic};
use crate::error::{check_finite, Result, SysidError};

/// One experiment for [`iv4_multi`]: inputs `u` (N x nu), outputs `y` (N x ny) and optional
/// reference `r` (N x nr, closed-loop data; given in every experiment or in none).
#[derive(Debug, Clone, Copy)]
pub struct IvRecord<'a> {
    /// Inputs (N x nu).
    pub u: MatRef<'a, f64>,
    /// Outputs (N x ny).
    pub y: MatRef<'a, f64>,
    /// Reference (N x nr) or `None` for open-loop data.
    pub r: Option<MatRef<'a, f64>>,
}

/// Result of [`iv4_multi`], one entry per output equation.
#[derive(Debug, Clone)]
pub struct Iv4Fit {
    /// `theta[i]`: `[a_i1.., a_i2.., .., b_i1.., b_i2.., ..]` (the layout of the ARX fit).
    pub theta: Vec<Vec<f64>>,
    /// Asymptotic covariance `lambda R^-1 S R^-T` of the last stage (`R = sum z phi^T`,
    /// `S = sum z z^T` of the prefiltered regressors and instruments at the estimate).
    pub covariance: Vec<Mat<f64>>,
    /// `lambda`: mean square of the prefiltered equation error at the estimate.
    pub noise_variance: Vec<f64>,
}

/// Channels of one experiment, each a vector over time.
struct Rec {
    y: Vec<Vec<f64>>,
    u: Vec<Vec<f64>>,
    r: Vec<Vec<f64>>,
}

fn columns(m: MatRef<'_, f64>) -> Vec<Vec<f64>> {
    (0..m.ncols())
        .map(|j| (0..m.nrows()).map(|t| m[(t, j)]).collect())
        .collect()
}

/// Number of parameters of equation `i`.
fn n_params(o: &ArxOrders, i: usize) -> usize {
    o.na[i].iter().sum::<usize>() + o.nb[i].iter().sum::<usize>()
}

/// First row of equation `i` whose lags all lie inside the record.
fn first_row(o: &ArxOrders, i: usize) -> usize {
    let a = o.na[i].iter().copied().max().unwrap_or(0);
    let b = o.nb[i]
        .iter()
        .zip(&o.nk[i])
        .map(|(&nb, &nk)| if nb > 0 { nk + nb - 1 } else { 0 })
        .max()
        .unwrap_or(0);
    a.max(b)
}

/// Regressor row of equation `i` at time `t`: `[-y_k(t-1..na_ik) per k, u_j(t-nk_ij-l) per j]`.
fn row(o: &ArxOrders, i: usize, y: &[Vec<f64>], u: &[Vec<f64>], t: usize, out: &mut [f64]) {
    let mut c = 0;
    for (k, &na) in o.na[i].iter().enumerate() {
        for l in 1..=na {
            out[c] = -y[k][t - l];
            c += 1;
        }
    }
    for (j, &nb) in o.nb[i].iter().enumerate() {
        for l in 0..nb {
            out[c] = u[j][t - o.nk[i][j] - l];
            c += 1;
        }
    }
}

/// Sums `R = sum z phi^T`, `v = sum z y_i`, `S = sum z z^T` and the row count of equation `i`
/// over the experiments `(y, u, x, r)`.
type Sums = (Mat<f64>, Vec<f64>, Mat<f64>, usize);

/// The first row of equation `i` whose regressors and equation error are free of the
/// start-up transient of a prefilter of order `filter_order` (a moving average started from
/// rest: its first `filter_order` outputs lack the samples before the record).
fn first_clean_row(o: &ArxOrders, i: usize, filter_order: usize) -> usize {
    first_row(o, i).saturating_add(filter_order)
}

/// The sums of equation `i`, from row [`first_clean_row`] of every experiment (signals
/// prefiltered by a filter of order `filter_order`).
fn iv_sums(o: &ArxOrders, i: usize, exps: &[[&[Vec<f64>]; 4]], filter_order: usize) -> Sums {
    let p = n_params(o, i);
    let start = first_clean_row(o, i, filter_order);
    let mut rm = vec![0.0; p * p];
    let mut sm = vec![0.0; p * p];
    let mut v = vec![0.0; p];
    let mut phi = vec![0.0; p];
    let mut z = vec![0.0; p];
    let mut rows = 0;
    for [y, u, x, r] in exps {
        for t in start..y[i].len() {
            row(o, i, y, u, t, &mut phi);
            row(o, i, x, r, t, &mut z);
            for a in 0..p {
                let za = z[a];
                for b in 0..p {
                    rm[a * p + b] += za * phi[b];
                    sm[a * p + b] += za * z[b];
                }
                v[a] += za * y[i][t];
            }
            rows += 1;
        }
    }
    (
        Mat::from_fn(p, p, |a, b| rm[a * p + b]),
        v,
        Mat::from_fn(p, p, |a, b| sm[a * p + b]),
        rows,
    )
}

/// The estimator an error names: `"iv4"` or `"ivx"` (the function the user called).
type Caller = &'static str;

fn check_rank(r: &Mat<f64>, what: Caller) -> Result<()> {
    let p = r.nrows();
    let (s, _, _) = crate::linalg::svd_seq(what, r.as_ref(), false, false)?;
    let full = s.last().is_some_and(|&l| l > 1e-12 * s[0]);
    if !full {
        let rank = s.iter().filter(|&&v| v > 1e-12 * s[0]).count();
        let fix = if what == "ivx" {
            "the instruments (the lags of x and of the inputs) do not span them: give an x \
             correlated with the outputs and not with their noise (a noise-free simulation of \
             a prior model), or use lower orders (na, nb), or sysid.iv4 / sysid.arx"
        } else {
            "the instruments (simulated or projected outputs and the inputs) do not span \
             them: use lower orders (na, nb; with several outputs and fewer inputs the \
             output lags' instruments are dependent: fit one output at a time), or \
             sysid.arx / sysid.oe"
        };
        return Err(SysidError::RegressorRank {
            estimator: what,
            rank,
            columns: p,
            tol: 1e-12,
            fix,
        });
    }
    Ok(())
}

/// Solves `R theta = v` with `R`'s rows and columns first scaled to unit norm: the rank
/// check and the solve then see the instruments' and regressors' shapes, not their units (on
/// a real ball-and-beam record the instruments simulated by the first-stage model are 10^5
/// times the inputs, and unscaled `R` looked rank-deficient at `1e-12` where the scaled one
/// is well conditioned). The solution is the same where `R` is regular.
fn solve(r: &Mat<f64>, v: &[f64], what: Caller) -> Result<Vec<f64>> {
    let p = r.nrows();
    let inv_norm = |x: f64| {
        if x > 0.0 && x.is_finite() {
            1.0 / x
        } else {
            1.0
        }
    };
    let dr: Vec<f64> = (0..p).map(|i| inv_norm(r.row(i).norm_l2())).collect();
    let rows = Mat::from_fn(p, p, |i, j| dr[i] * r[(i, j)]);
    let dc: Vec<f64> = (0..p).map(|j| inv_norm(rows.col(j).norm_l2())).collect();
    let scaled = Mat::from_fn(p, p, |i, j| rows[(i, j)] * dc[j]);
    check_rank(&scaled, what)?;
    let rhs = Mat::from_fn(p, 1, |a, _| dr[a] * v[a]);
    let sol = scaled.partial_piv_lu().solve(&rhs);
    Ok((0..p).map(|a| dc[a] * sol[(a, 0)]).collect())
}

/// Splits equation `i`'s parameters into `(a[k], b[j])`.
fn unpack(o: &ArxOrders, i: usize, th: &[f64]) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let mut c = 0;
    let mut take = |n: usize| {
        let s = th[c..c + n].to_vec();
        c += n;
        s
    };
    let a = o.na[i].iter().map(|&n| take(n)).collect();
    let b = o.nb[i].iter().map(|&n| take(n)).collect();
    (a, b)
}

/// Noise-free simulation from rest of the MIMO ARX model `theta` driven by `r`.
fn simulate(o: &ArxOrders, theta: &[Vec<f64>], r: &[Vec<f64>], n: usize) -> Vec<Vec<f64>> {
    let ny = o.na.len();
    let parts: Vec<_> = (0..ny).map(|i| unpack(o, i, &theta[i])).collect();
    let mut y = vec![vec![0.0; n]; ny];
    for t in 0..n {
        for i in 0..ny {
            let (a, b) = &parts[i];
            let mut s = 0.0;
            for (k, ak) in a.iter().enumerate() {
                for (l, c) in ak.iter().enumerate() {
                    if t > l {
                        s -= c * y[k][t - l - 1];
                    }
                }
            }
            for (j, bj) in b.iter().enumerate() {
                let nk = o.nk[i][j];
                for (l, c) in bj.iter().enumerate() {
                    if t >= nk + l {
                        s += c * r[j][t - nk - l];
                    }
                }
            }
            y[i][t] = s;
        }
    }
    y
}

/// Equation error `A_i y - B_i u` of equation `i` (zero before the record).
fn equation_error(o: &ArxOrders, i: usize, th: &[f64], y: &[Vec<f64>], u: &[Vec<f64>]) -> Vec<f64> {
    let (a, b) = unpack(o, i, th);
    let mut w = y[i].clone();
    for (k, ak) in a.iter().enumerate() {
        let mut p = vec![0.0];
        p.extend_from_slice(ak);
        let f = filter(&p, &[1.0], &y[k]);
        w.iter_mut().zip(&f).for_each(|(wt, ft)| *wt += ft);
    }
    for (j, bj) in b.iter().enumerate() {
        let mut p = vec![0.0; o.nk[i][j]];
        p.extend_from_slice(bj);
        let f = filter(&p, &[1.0], &u[j]);
        w.iter_mut().zip(&f).for_each(|(wt, ft)| *wt -= ft);
    }
    w
}

/// Monic AR polynomial of order `n` fitted to the experiments' `w` by least squares (`1` when
/// the fit is singular).
fn ar_prefilter(w: &[Vec<f64>], n: usize) -> Vec<f64> {
    if n == 0 {
        return vec![1.0];
    }
    let mut g = Mat::<f64>::zeros(n, n);
    let mut h = vec![0.0; n];
    let mut x = vec![0.0; n];
    for we in w {
        for t in n..we.len() {
            for k in 0..n {
                x[k] = -we[t - 1 - k];
            }
            for a in 0..n {
                for b in 0..n {
                    g[(a, b)] += x[a] * x[b];
                }
                h[a] += x[a] * we[t];
            }
        }
    }
    match solve(&g, &h, "iv4") {
        Ok(l) if l.iter().all(|v| v.is_finite()) => monic(&l),
        _ => vec![1.0],
    }
}

/// Instrument signals of one experiment: `(x, r)` standing in for `(y, u)`.
type Inst = (Vec<Vec<f64>>, Vec<Vec<f64>>);

/// Noise-free simulations `(x, u)` of the model from every experiment's inputs, or `None`
/// when the model is unstable (its simulation grows without bound).
fn simulated(o: &ArxOrders, theta: &[Vec<f64>], recs: &[Rec]) -> Option<Vec<Inst>> {
    let mut out = Vec::with_capacity(recs.len());
    for rec in recs {
        let n = rec.y.first().map_or(0, |c| c.len());
        let x = simulate(o, theta, &rec.u, n);
        let scale = rec
            .y
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(f64::MIN_POSITIVE);
        let big = x.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let bounded = big.is_finite() && big <= 1e6 * scale;
        if !bounded {
            return None;
        }
        out.push((x, rec.u.clone()));
    }
    Some(out)
}

/// Lags of the instrument inputs in [`projected`].
const PROJECTION_LAGS: usize = 30;

/// The parts of `y` and `u` explained by the instrument inputs `r`: the least-squares FIR
/// projection (lags `0..=PROJECTION_LAGS` of every `r_j`, pooled over the experiments) of
/// each output and input channel. Functions of `r` only, so uncorrelated with the noise even
/// under feedback, and as correlated with the regressors as a linear filter of `r` allows.
fn projected(recs: &[Rec]) -> Result<Vec<Inst>> {
    let nr = recs[0].r.len();
    let total: usize = recs.iter().map(|r| r.y[0].len()).sum();
    let lags = PROJECTION_LAGS.min(total / (4 * nr.max(1))).max(1);
    let p = nr * (lags + 1);
    let targets = recs[0].y.len() + recs[0].u.len();
    let mut g = Mat::<f64>::zeros(p, p);
    let mut h = Mat::<f64>::zeros(p, targets);
    let mut phi = vec![0.0; p];
    let lagged = |rec: &Rec, t: usize, phi: &mut [f64]| {
        for (j, rj) in rec.r.iter().enumerate() {
            for l in 0..=lags {
                phi[j * (lags + 1) + l] = if t >= l { rj[t - l] } else { 0.0 };
            }
        }
    };
    for rec in recs {
        for t in 0..rec.y[0].len() {
            lagged(rec, t, &mut phi);
            for a in 0..p {
                for b in 0..=a {
                    g[(a, b)] += phi[a] * phi[b];
                }
                for (c, ch) in rec.y.iter().chain(&rec.u).enumerate() {
                    h[(a, c)] += phi[a] * ch[t];
                }
            }
        }
    }
    for a in 0..p {
        for b in a + 1..p {
            g[(a, b)] = g[(b, a)];
        }
    }
    check_rank(&g, "iv4")?;
    let coef = g.partial_piv_lu().solve(&h);
    let ny = recs[0].y.len();
    Ok(recs
        .iter()
        .map(|rec| {
            let n = rec.y[0].len();
            let mut chans = vec![vec![0.0; n]; targets];
            for t in 0..n {
                lagged(rec, t, &mut phi);
                for (c, ch) in chans.iter_mut().enumerate() {
                    ch[t] = (0..p).map(|a| phi[a] * coef[(a, c)]).sum();
                }
            }
            let u = chans.split_off(ny);
            (chans, u)
        })
        .collect())
}

fn prefiltered(l: &[f64], chans: &[Vec<f64>]) -> Vec<Vec<f64>> {
    chans.iter().map(|c| filter(l, &[1.0], c)).collect()
}

/// One IV stage of every equation with the instruments `inst` (`None`: the regressors, that
/// is least squares), all signals prefiltered by each equation's AR model when `prefilter`.
fn stage(
    o: &ArxOrders,
    recs: &[Rec],
    inst: Option<&[Inst]>,
    prefilter: Option<&[Vec<f64>]>,
) -> Vec<Sums> {
    (0..o.na.len())
        .map(|i| {
            let l = prefilter.map_or(vec![1.0], |p| p[i].clone());
            let sigs: Vec<[Vec<Vec<f64>>; 4]> = recs
                .iter()
                .enumerate()
                .map(|(e, rec)| {
                    let (x, r) = match inst {
                        Some(z) => (&z[e].0, &z[e].1),
                        None => (&rec.y, &rec.u),
                    };
                    [
                        prefiltered(&l, &rec.y),
                        prefiltered(&l, &rec.u),
                        prefiltered(&l, x),
                        prefiltered(&l, r),
                    ]
                })
                .collect();
            let refs: Vec<[&[Vec<f64>]; 4]> = sigs
                .iter()
                .map(|s| [&s[0][..], &s[1][..], &s[2][..], &s[3][..]])
                .collect();
            iv_sums(o, i, &refs, l.len().saturating_sub(1))
        })
        .collect()
}

fn prefilters(o: &ArxOrders, theta: &[Vec<f64>], recs: &[Rec]) -> Vec<Vec<f64>> {
    (0..o.na.len())
        .map(|i| {
            let w: Vec<Vec<f64>> = recs
                .iter()
                .map(|r| equation_error(o, i, &theta[i], &r.y, &r.u))
                .collect();
            ar_prefilter(&w, n_params(o, i))
        })
        .collect()
}

fn check_orders(o: &ArxOrders, ny: usize, nu: usize) -> Result<()> {
    let ok = o.na.len() == ny
        && o.nb.len() == ny
        && o.nk.len() == ny
        && o.na.iter().all(|r| r.len() == ny)
        && o.nb.iter().all(|r| r.len() == nu)
        && o.nk.iter().all(|r| r.len() == nu);
    if !ok {
        return Err(SysidError::invalid(
            "orders",
            format!("na must be {ny} x {ny}, nb and nk {ny} x {nu} (outputs x inputs)"),
        ));
    }
    if (0..ny).any(|i| o.nb[i].iter().all(|&b| b == 0)) {
        return Err(SysidError::invalid(
            "nb",
            "iv4 needs at least one B coefficient in every output's equation",
        ));
    }
    Ok(())
}

/// The asymptotic covariance `lambda R^-1 S R^-T` of every equation from its sums at the
/// estimate, with `lambda` the mean square of the (prefiltered by `l`) equation error.
fn iv_covariance(
    orders: &ArxOrders,
    sums: &[Sums],
    theta: &[Vec<f64>],
    recs: &[Rec],
    l: &[Vec<f64>],
    what: Caller,
) -> Result<(Vec<Mat<f64>>, Vec<f64>)> {
    let ny = theta.len();
    let mut covariance = Vec::with_capacity(ny);
    let mut noise_variance = Vec::with_capacity(ny);
    for (i, (r, _, s, rows)) in sums.iter().enumerate() {
        let start = first_clean_row(orders, i, l[i].len().saturating_sub(1));
        let (mut ss, mut cnt) = (0.0, 0usize);
        for rec in recs {
            let w = equation_error(orders, i, &theta[i], &rec.y, &rec.u);
            let wf = filter(&l[i], &[1.0], &w);
            for v in wf.iter().skip(start) {
                ss += v * v;
                cnt += 1;
            }
        }
        let lam = ss / cnt.max(1) as f64;
        // R^-1 S R^-T in Gram form, (R^-1 V L^1/2)(R^-1 V L^1/2)^T with S = V L V^T: positive
        // semi-definite by construction (the product formed directly lost that on real
        // records whose R is ill-conditioned: an eigenvalue of -5e-4 times the largest)
        let (v, l) = crate::optim::symmetric_eigen(
            s,
            if what == "ivx" {
                "ivx covariance"
            } else {
                "iv4 covariance"
            },
        )?;
        let mut half = v;
        for (j, lj) in l.iter().enumerate() {
            let f = lj.max(0.0).sqrt();
            half.col_mut(j).iter_mut().for_each(|x| *x *= f);
        }
        let m = r.partial_piv_lu().solve(&half);
        let cov = &m * m.transpose() * faer::Scale(lam);
        debug_assert_eq!(*rows, cnt);
        covariance.push(cov);
        noise_variance.push(lam);
    }
    Ok((covariance, noise_variance))
}

/// The experiments checked against the orders and each other (shapes, finiteness, length
/// for the parameters), as channel vectors; `what` names the caller in the errors.
fn prepare(records: &[IvRecord<'_>], orders: &ArxOrders, what: &str) -> Result<Vec<Rec>> {
    let Some(first) = records.first() else {
        return Err(SysidError::invalid(
            "experiments",
            "needs at least one (u, y) record",
        ));
    };
    let (ny, nu) = (first.y.ncols(), first.u.ncols());
    if ny == 0 || nu == 0 {
        return Err(SysidError::invalid(
            "data",
            format!("{what} needs at least one input and one output"),
        ));
    }
    check_orders(orders, ny, nu)?;
    let mut recs = Vec::with_capacity(records.len());
    for rec in records {
        let n = rec.y.nrows();
        let bad = rec.u.nrows() != n
            || rec.u.ncols() != nu
            || rec.y.ncols() != ny
            || rec.r.map(|r| r.ncols()) != first.r.map(|r| r.ncols())
            || rec.r.is_some_and(|r| r.nrows() != n || r.ncols() == 0);
        if bad {
            return Err(SysidError::ShapeMismatch {
                what: "u, y, reference".into(),
                expected: format!(
                    "(N, {nu}), (N, {ny}) and a reference with N rows in every experiment \
                     or in none (the same number of columns in each)"
                ),
                got: format!(
                    "({}, {}), ({}, {}){}",
                    rec.u.nrows(),
                    rec.u.ncols(),
                    n,
                    rec.y.ncols(),
                    rec.r.map_or(String::new(), |r| format!(
                        ", ({}, {})",
                        r.nrows(),
                        r.ncols()
                    ))
                ),
            });
        }
        check_finite("u", rec.u)?;
        check_finite("y", rec.y)?;
        if let Some(r) = rec.r {
            check_finite("reference", r)?;
        }
        let u = columns(rec.u);
        recs.push(Rec {
            y: columns(rec.y),
            r: rec.r.map_or_else(|| u.clone(), columns),
            u,
        });
    }
    let total: usize = records.iter().map(|r| r.y.nrows()).sum();
    let pmax = (0..ny).map(|i| n_params(orders, i)).max().unwrap_or(0);
    let lag = (0..ny).map(|i| first_row(orders, i)).max().unwrap_or(0);
    let need = pmax
        .saturating_add(lag)
        .saturating_mul(4)
        .saturating_add(10);
    if total < need {
        return Err(SysidError::InsufficientData {
            context: format!("{what} with {pmax} parameters per equation (largest lag {lag})"),
            needed: need,
            got: total,
            fix: "use a longer record or smaller orders",
        });
    }
    if what == "iv4" {
        // stage 4 drops each experiment's first `lag + p` rows (the lags and the start-up of
        // the order-p prefilter): the rows left must still outnumber the parameters
        for i in 0..ny {
            let (p, skip) = (
                n_params(orders, i),
                first_clean_row(orders, i, n_params(orders, i)),
            );
            let rows: usize = records
                .iter()
                .map(|r| r.y.nrows().saturating_sub(skip))
                .sum();
            if rows <= p {
                return Err(SysidError::InsufficientData {
                    context: format!(
                        "iv4's prefiltered stage of output {i} ({p} parameters; the first {skip} \
                         samples of every experiment are its lags and the prefilter's start-up)"
                    ),
                    needed: p + 1,
                    got: rows,
                    fix: "use longer experiments (merge short ones) or smaller orders",
                });
            }
        }
    }
    Ok(recs)
}

/// IV4 estimate of a MIMO ARX structure from several experiments; with `r` in a record
/// (closed-loop data), the instruments are built from it instead of the input.
///
/// ```
/// use faer::Mat;
/// use sysid_core::polynomial::{arx::ArxOrders, iv::{iv4_multi, IvRecord}};
/// let n = 400;
/// let u = Mat::from_fn(n, 1, |t, _| ((t * 7919 % 17) as f64) - 8.0);
/// let mut y = Mat::<f64>::zeros(n, 1);
/// for t in 1..n { y[(t, 0)] = 0.5 * y[(t - 1, 0)] + u[(t - 1, 0)]; }
/// let o = ArxOrders { na: vec![vec![1]], nb: vec![vec![1]], nk: vec![vec![1]] };
/// let fit = iv4_multi(&[IvRecord { u: u.as_ref(), y: y.as_ref(), r: None }], &o).unwrap();
/// assert!((fit.theta[0][0] + 0.5).abs() < 1e-8 && (fit.theta[0][1] - 1.0).abs() < 1e-8);
/// ```
pub fn iv4_multi(records: &[IvRecord<'_>], orders: &ArxOrders) -> Result<Iv4Fit> {
    let recs = prepare(records, orders, "iv4")?;
    let solve_all = |sums: &[Sums]| -> Result<Vec<Vec<f64>>> {
        sums.iter().map(|(r, v, _, _)| solve(r, v, "iv4")).collect()
    };
    let closed_loop = records.iter().any(|r| r.r.is_some());
    // Closed loop: instruments are the parts of y and u explained by the reference (fixed
    // through the stages). Open loop: stage 1 is least squares and the instruments are
    // simulated from the previous stage's model (the projection if that model is unstable).
    let fixed = if closed_loop {
        Some(projected(&recs)?)
    } else {
        None
    };
    let instruments = |theta: &[Vec<f64>]| -> Result<Vec<Inst>> {
        match &fixed {
            Some(z) => Ok(z.clone()),
            None => match simulated(orders, theta, &recs) {
                Some(z) => Ok(z),
                None => projected(&recs),
            },
        }
    };
    // A stage's IV solve with the instruments of `theta`; where those leave the instrument
    // matrix singular (a bounded but unstable model's simulation: every lag follows its
    // growing mode, as on a real ball-and-beam record), with the projection instruments.
    let iv_stage = |theta: &[Vec<f64>], l: Option<&[Vec<f64>]>| -> Result<(Vec<Vec<f64>>, bool)> {
        let z = instruments(theta)?;
        match solve_all(&stage(orders, &recs, Some(&z), l)) {
            Err(SysidError::RegressorRank { .. }) if fixed.is_none() => {
                let z = projected(&recs)?;
                Ok((solve_all(&stage(orders, &recs, Some(&z), l))?, true))
            }
            other => Ok((other?, false)),
        }
    };
    // Stage 1: least squares (open loop) or IV with the reference instruments.
    let th1 = solve_all(&stage(orders, &recs, fixed.as_deref(), None))?;
    // Stage 2: instruments from the stage-1 model.
    let (th2, _) = iv_stage(&th1, None)?;
    // Stage 3: AR prefilters of the stage-2 equation errors.
    let l = prefilters(orders, &th2, &recs);
    // Stage 4: prefiltered IV with instruments from the stage-2 model.
    let (th4, projection) = iv_stage(&th2, Some(&l))?;
    // Covariance at the estimate: prefilter and instruments rebuilt from it (the projection
    // where stage 4 needed it).
    let l4 = prefilters(orders, &th4, &recs);
    let z4 = if projection {
        projected(&recs)?
    } else {
        instruments(&th4)?
    };
    let sums = stage(orders, &recs, Some(&z4), Some(&l4));
    let (covariance, noise_variance) = iv_covariance(orders, &sums, &th4, &recs, &l4, "iv4")?;
    Ok(Iv4Fit {
        theta: th4,
        covariance,
        noise_variance,
    })
}

/// Instrumental-variable estimate of a MIMO ARX structure with given instruments (MATLAB's
/// `ivx`): the lags of `x[e]` (N x ny, one per experiment, a signal correlated with the
/// outputs but not with their noise, for example a noise-free simulation) take the place of
/// the outputs' lags in the instruments, the inputs' (or the reference's) lags stay; one IV
/// solve per equation, no prefilter; covariance `lambda R^-1 S R^-T`.
///
/// ```
/// use faer::Mat;
/// use sysid_core::polynomial::{arx::ArxOrders, iv::{ivx_multi, IvRecord}};
/// let n = 400;
/// let u = Mat::from_fn(n, 1, |t, _| ((t * 7919 % 17) as f64) - 8.0);
/// let mut y = Mat::<f64>::zeros(n, 1);
/// for t in 1..n { y[(t, 0)] = 0.5 * y[(t - 1, 0)] + u[(t - 1, 0)]; }
/// let o = ArxOrders { na: vec![vec![1]], nb: vec![vec![1]], nk: vec![vec![1]] };
/// let rec = IvRecord { u: u.as_ref(), y: y.as_ref(), r: None };
/// let fit = ivx_multi(&[rec], &[y.as_ref()], &o).unwrap();
/// assert!((fit.theta[0][0] + 0.5).abs() < 1e-8 && (fit.theta[0][1] - 1.0).abs() < 1e-8);
/// ```
pub fn ivx_multi(
    records: &[IvRecord<'_>],
    x: &[MatRef<'_, f64>],
    orders: &ArxOrders,
) -> Result<Iv4Fit> {
    let recs = prepare(records, orders, "ivx")?;
    if x.len() != records.len()
        || x.iter()
            .zip(records)
            .any(|(xe, r)| xe.nrows() != r.y.nrows() || xe.ncols() != r.y.ncols())
    {
        return Err(SysidError::ShapeMismatch {
            what: "instruments x".into(),
            expected: "one array per experiment, shaped as its outputs (N, ny)".into(),
            got: format!("{} arrays for {} experiments", x.len(), records.len()),
        });
    }
    for xe in x {
        check_finite("x", *xe)?;
    }
    let inst: Vec<Inst> = x
        .iter()
        .zip(&recs)
        .map(|(xe, rec)| (columns(*xe), rec.r.clone()))
        .collect();
    let sums = stage(orders, &recs, Some(&inst), None);
    let theta = sums
        .iter()
        .map(|(r, v, _, _)| solve(r, v, "ivx"))
        .collect::<Result<Vec<_>>>()?;
    let ones = vec![vec![1.0]; theta.len()];
    let (covariance, noise_variance) = iv_covariance(orders, &sums, &theta, &recs, &ones, "ivx")?;
    Ok(Iv4Fit {
        theta,
        covariance,
        noise_variance,
    })
}

/// IV4 estimate `[a_1..a_na, b_0..b_{nb-1}]` of the single-input single-output
/// `A y = B u(t-nk) + v`. With `reference` (closed-loop data), the instruments are built from
/// the reference instead of the input.
///
/// ```
/// use sysid_core::polynomial::{filter::filter, iv::iv4};
/// let u: Vec<f64> = (0..400).map(|t| ((t * 7919 % 17) as f64) - 8.0).collect();
/// let mut x = vec![0.0; 400];
/// x[1..].copy_from_slice(&u[..399]);
/// let y = filter(&[1.0], &[1.0, -0.5], &x);
/// let th = iv4(&y, &u, 1, 1, 1, None).unwrap();
/// assert!((th[0] + 0.5).abs() < 1e-8 && (th[1] - 1.0).abs() < 1e-8);
/// ```
pub fn iv4(
    y: &[f64],
    u: &[f64],
    na: usize,
    nb: usize,
    nk: usize,
    reference: Option<&[f64]>,
) -> Result<Vec<f64>> {
    if u.len() != y.len() || reference.is_some_and(|r| r.len() != y.len()) {
        return Err(SysidError::invalid(
            "u",
            "u, y (and reference) need equal lengths",
        ));
    }
    let ym = MatRef::from_column_major_slice(y, y.len(), 1);
    let um = MatRef::from_column_major_slice(u, u.len(), 1);
    let rm = reference.map(|r| MatRef::from_column_major_slice(r, r.len(), 1));
    let o = ArxOrders {
        na: vec![vec![na]],
        nb: vec![vec![nb]],
        nk: vec![vec![nk]],
    };
    let fit = iv4_multi(
        &[IvRecord {
            u: um,
            y: ym,
            r: rm,
        }],
        &o,
    )?;
    Ok(fit.theta.into_iter().next().unwrap_or_default())
}

#[cfg(test)]
mod tests {
    use faer::Mat;

    use super::{iv4_multi, ivx_multi, IvRecord};
    use crate::error::SysidError;
    use crate::polynomial::arx::ArxOrders;

    /// Uniform(-0.5, 0.5) samples from a 64-bit LCG.
    fn noise(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed.wrapping_mul(2862933555777941757).wrapping_add(1);
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }

    fn close(a: &[f64], b: &[f64], tol: f64) {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() < tol, "{a:?} vs {b:?}");
        }
    }

    /// The samples `cut..` of a noise-free SISO `y = (0.1 q^-1 + 0.05 q^-2) / (1 - 1.8 q^-1
    /// + 0.85 q^-2) u` run from rest at sample 0: a record that does not start at rest.
    fn siso_mid_record(n: usize, cut: usize, seed: u64) -> (Mat<f64>, Mat<f64>) {
        let u = noise(n, seed);
        let mut y = vec![0.0; n];
        for t in 2..n {
            y[t] = 1.8 * y[t - 1] - 0.85 * y[t - 2] + 0.1 * u[t - 1] + 0.05 * u[t - 2];
        }
        (
            Mat::from_fn(n - cut, 1, |t, _| u[t + cut]),
            Mat::from_fn(n - cut, 1, |t, _| y[t + cut]),
        )
    }

    #[test]
    fn iv4_noise_free_record_not_at_rest_is_recovered_exactly() {
        // the stage-4 prefilter started from rest made the first rows' equation error
        // nonzero: a[0] was off by -4.8e-4 (least squares: 1e-16)
        let (u, y) = siso_mid_record(3200, 200, 3);
        let o = ArxOrders {
            na: vec![vec![2]],
            nb: vec![vec![2]],
            nk: vec![vec![1]],
        };
        let rec = IvRecord {
            u: u.as_ref(),
            y: y.as_ref(),
            r: None,
        };
        let fit = iv4_multi(&[rec], &o).unwrap();
        close(&fit.theta[0], &[-1.8, 0.85, 0.1, 0.05], 1e-10);
        assert!(fit.noise_variance[0] < 1e-20, "{:?}", fit.noise_variance);
    }

    #[test]
    fn iv4_mimo_experiments_not_at_rest_are_recovered_exactly() {
        // 2 x 2 ARX with a coupled A; two experiments, each cut from a longer run
        let o = ArxOrders {
            na: vec![vec![1, 1], vec![1, 1]],
            nb: vec![vec![1, 1], vec![1, 1]],
            nk: vec![vec![1, 2], vec![1, 1]],
        };
        let sim = |n: usize, cut: usize, s: u64| {
            let u: Vec<Vec<f64>> = (0..2).map(|j| noise(n, s + j)).collect();
            let mut y = vec![vec![0.0; n]; 2];
            for t in 2..n {
                y[0][t] = 0.6 * y[0][t - 1] - 0.2 * y[1][t - 1] + u[0][t - 1] + 0.3 * u[1][t - 2];
                y[1][t] =
                    0.1 * y[0][t - 1] + 0.5 * y[1][t - 1] + 0.7 * u[1][t - 1] - 0.4 * u[0][t - 1];
            }
            (
                Mat::from_fn(n - cut, 2, |t, j| u[j][t + cut]),
                Mat::from_fn(n - cut, 2, |t, j| y[j][t + cut]),
            )
        };
        let (ua, ya) = sim(900, 300, 60);
        let (ub, yb) = sim(700, 150, 70);
        let recs = [
            IvRecord {
                u: ua.as_ref(),
                y: ya.as_ref(),
                r: None,
            },
            IvRecord {
                u: ub.as_ref(),
                y: yb.as_ref(),
                r: None,
            },
        ];
        let fit = iv4_multi(&recs, &o).unwrap();
        close(&fit.theta[0], &[-0.6, 0.2, 1.0, 0.3], 1e-10);
        close(&fit.theta[1], &[-0.1, -0.5, -0.4, 0.7], 1e-10);
    }

    #[test]
    fn iv4_refuses_experiments_too_short_for_the_prefilter_start_up() {
        // ten experiments of 6 samples: 60 in all, each one's rows all lags (2) and the
        // order-4 prefilter's start-up
        let (u, y) = siso_mid_record(230, 200, 5);
        let o = ArxOrders {
            na: vec![vec![2]],
            nb: vec![vec![2]],
            nk: vec![vec![1]],
        };
        let recs: Vec<_> = (0..10)
            .map(|_| IvRecord {
                u: u.subrows(0, 6),
                y: y.subrows(0, 6),
                r: None,
            })
            .collect();
        match iv4_multi(&recs, &o) {
            Err(SysidError::InsufficientData { context, .. }) => {
                assert!(context.contains("prefilter"), "{context}")
            }
            other => panic!("expected an insufficient-data error, got {other:?}"),
        }
    }

    #[test]
    fn ivx_rank_loss_names_ivx() {
        // an instrument that is a constant cannot determine a_1: the error names ivx, the
        // function called (it said "iv4")
        let (u, y) = siso_mid_record(600, 100, 9);
        let x = Mat::from_fn(500, 1, |_, _| 1.0);
        let o = ArxOrders {
            na: vec![vec![2]],
            nb: vec![vec![2]],
            nk: vec![vec![1]],
        };
        let rec = IvRecord {
            u: u.as_ref(),
            y: y.as_ref(),
            r: None,
        };
        match ivx_multi(&[rec], &[x.as_ref()], &o) {
            Err(e @ SysidError::RegressorRank { .. }) => {
                let text = e.to_string();
                assert!(text.starts_with("ivx:") && text.contains("x"), "{text}");
            }
            other => panic!("expected a regressor rank error, got {other:?}"),
        }
    }
}
