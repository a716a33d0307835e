//! Bindings of `sysid_core::narx`: FROLS term selection, least-squares fit of chosen terms,
//! free-run simulation and k-step prediction of NARX / NARMAX models.
//!
//! Terms cross the boundary as lists of ints: a monomial is its sorted variable indices
//! (empty: the constant), radial basis function `c` is `[-1 - c]`.

use crate::convert::{mat_to_numpy, slice_to_numpy, view, view_nd};
use crate::errors::IntoPy;
use faer::{Mat, MatRef};
use numpy::{PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::narx::basis::{Basis, Candidates, RbfBasis, Term};
use sysid_core::narx::frols::{self, FrolsOptions};
use sysid_core::narx::regressors::{LagSpec, Record};
use sysid_core::narx::simulate::{Equation, NarxModel};
use sysid_core::SysidError;

type Experiments<'a> = Vec<(
    PyReadonlyArray2<'a, f64>,
    PyReadonlyArray2<'a, f64>,
    Option<PyReadonlyArray2<'a, f64>>,
)>;
type Rbf<'a> = (
    PyReadonlyArray2<'a, f64>,
    PyReadonlyArray1<'a, f64>,
    PyReadonlyArray1<'a, f64>,
    PyReadonlyArray1<'a, f64>,
);

fn basis(degree: Option<usize>, rbf: Option<Rbf<'_>>) -> PyResult<Basis> {
    match (degree, rbf) {
        (Some(d), None) => Ok(Basis::Polynomial { degree: d }),
        (None, Some((c, w, s, sc))) => Ok(Basis::Rbf(RbfBasis {
            centres: view(&c).to_owned(),
            widths: w.as_array().to_vec(),
            shift: s.as_array().to_vec(),
            scale: sc.as_array().to_vec(),
        })),
        _ => Err(crate::errors::to_py(SysidError::InvalidArgument {
            name: "basis",
            reason: "give either a polynomial degree or RBF parameters".into(),
        })),
    }
}

fn spec(
    nu: usize,
    ny: usize,
    orders: &(Vec<usize>, Vec<usize>, Vec<usize>, Vec<usize>),
) -> PyResult<LagSpec> {
    LagSpec::new(nu, ny, &orders.0, &orders.1, &orders.2, &orders.3).py()
}

fn encode(t: &Term) -> Vec<i64> {
    match t {
        Term::Monomial(v) => v.iter().map(|&i| i as i64).collect(),
        Term::Rbf(c) => vec![-1 - *c as i64],
    }
}

fn decode(v: &[i64]) -> Term {
    match v {
        [c] if *c < 0 => Term::Rbf((-1 - c) as usize),
        _ => Term::Monomial(v.iter().map(|&i| i.max(0) as usize).collect()),
    }
}

type Views<'a> = (MatRef<'a, f64>, MatRef<'a, f64>, Option<MatRef<'a, f64>>);

fn records<'a>(views: &'a [Views<'a>]) -> Vec<Record<'a>> {
    views
        .iter()
        .map(|(u, y, e)| Record {
            u: *u,
            y: *y,
            e: *e,
        })
        .collect()
}

type Orders = (Vec<usize>, Vec<usize>, Vec<usize>, Vec<usize>);

/// FROLS selection for every output, then the streaming QR factor of `[chosen terms, y_i]`.
/// Returns, per output, a dict with `terms` (encoded), `err`, `rss`, `r`, `n_rows`, and the
/// number of candidates.
#[pyfunction]
#[pyo3(signature = (experiments, orders, degree, rbf, max_terms, forced, err_tol=1e-10, block_rows=0))]
#[allow(clippy::too_many_arguments)]
pub fn narx_frols<'py>(
    py: Python<'py>,
    experiments: Experiments<'_>,
    orders: Orders,
    degree: Option<usize>,
    rbf: Option<Rbf<'_>>,
    max_terms: usize,
    forced: Vec<Vec<Vec<i64>>>,
    err_tol: f64,
    block_rows: usize,
) -> PyResult<(Vec<Bound<'py, PyDict>>, usize)> {
    let b = basis(degree, rbf)?;
    let (nu, ny) = experiments
        .first()
        .map(|(u, y, _)| (u.as_array().ncols(), y.as_array().ncols()))
        .unwrap_or((0, 1));
    let sp = spec(nu, ny, &orders)?;
    let views: Vec<_> = experiments
        .iter()
        .map(|(u, y, e)| {
            (
                view_nd(u.as_array()),
                view_nd(y.as_array()),
                e.as_ref().map(|e| view_nd(e.as_array())),
            )
        })
        .collect();
    let (sels, rs, terms, m) = py
        .detach(|| -> sysid_core::Result<_> {
            let cands = Candidates::new(&b, sp.n_vars())?;
            let index = |t: &Vec<i64>| -> sysid_core::Result<usize> {
                let t = decode(t);
                cands.terms.iter().position(|c| *c == t).ok_or_else(|| {
                    SysidError::InvalidArgument {
                        name: "forced",
                        reason: format!("{t:?} is not a candidate of this basis"),
                    }
                })
            };
            let forced_idx = forced
                .iter()
                .map(|f| f.iter().map(index).collect::<sysid_core::Result<Vec<_>>>())
                .collect::<sysid_core::Result<Vec<_>>>()?;
            let mut opts = FrolsOptions::with_max_terms(max_terms);
            opts.err_tol = err_tol;
            opts.block_rows = block_rows;
            let recs = records(&views);
            let sels = frols::frols(&sp, &cands, &recs, &forced_idx, &opts)?;
            let chosen: Vec<Vec<usize>> = sels.iter().map(|s| s.terms.clone()).collect();
            let rs = frols::fit(&sp, &cands, &recs, &chosen)?;
            let terms: Vec<Vec<Vec<i64>>> = chosen
                .iter()
                .map(|c| c.iter().map(|&k| encode(&cands.terms[k])).collect())
                .collect();
            Ok((sels, rs, terms, cands.len()))
        })
        .py()?;
    let out = sels
        .iter()
        .zip(&rs)
        .zip(&terms)
        .map(|((s, r), t)| {
            let d = PyDict::new(py);
            d.set_item("terms", t.clone())?;
            d.set_item("err", slice_to_numpy(py, &s.err))?;
            d.set_item("rss", slice_to_numpy(py, &s.rss))?;
            d.set_item("r", mat_to_numpy(py, r))?;
            d.set_item("n_rows", s.n_rows)?;
            Ok(d)
        })
        .collect::<PyResult<Vec<_>>>()?;
    Ok((out, m))
}

/// Streaming QR factor of `[terms_i, y_i]` per output for given (encoded) terms.
#[pyfunction]
pub fn narx_fit<'py>(
    py: Python<'py>,
    experiments: Experiments<'_>,
    orders: Orders,
    degree: Option<usize>,
    rbf: Option<Rbf<'_>>,
    terms: Vec<Vec<Vec<i64>>>,
) -> PyResult<Vec<Bound<'py, PyArray2<f64>>>> {
    let b = basis(degree, rbf)?;
    let (nu, ny) = experiments
        .first()
        .map(|(u, y, _)| (u.as_array().ncols(), y.as_array().ncols()))
        .unwrap_or((0, 1));
    let sp = spec(nu, ny, &orders)?;
    let views: Vec<_> = experiments
        .iter()
        .map(|(u, y, e)| {
            (
                view_nd(u.as_array()),
                view_nd(y.as_array()),
                e.as_ref().map(|e| view_nd(e.as_array())),
            )
        })
        .collect();
    let rs = py
        .detach(|| -> sysid_core::Result<Vec<Mat<f64>>> {
            let ts: Vec<Vec<Term>> = terms
                .iter()
                .map(|t| t.iter().map(|v| decode(v)).collect())
                .collect();
            frols::fit_terms(&sp, &b, &records(&views), &ts)
        })
        .py()?;
    Ok(rs.iter().map(|r| mat_to_numpy(py, r)).collect())
}

fn model(
    nu: usize,
    ny: usize,
    orders: &Orders,
    degree: Option<usize>,
    rbf: Option<Rbf<'_>>,
    equations: Vec<(Vec<Vec<i64>>, Vec<f64>)>,
) -> PyResult<NarxModel> {
    let b = basis(degree, rbf)?;
    let sp = spec(nu, ny, orders)?;
    let eqs = equations
        .into_iter()
        .map(|(t, c)| Equation {
            terms: t.iter().map(|v| decode(v)).collect(),
            coefs: c,
        })
        .collect();
    NarxModel::new(sp, b, eqs).py()
}

/// Free-run simulation; `y0` holds the first `max_lag` outputs.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn narx_simulate<'py>(
    py: Python<'py>,
    orders: Orders,
    degree: Option<usize>,
    rbf: Option<Rbf<'_>>,
    equations: Vec<(Vec<Vec<i64>>, Vec<f64>)>,
    u: PyReadonlyArray2<'_, f64>,
    y0: PyReadonlyArray2<'_, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (uv, yv) = (view(&u), view(&y0));
    let m = model(uv.ncols(), yv.ncols(), &orders, degree, rbf, equations)?;
    let y = py.detach(|| m.simulate(uv, yv)).py()?;
    Ok(mat_to_numpy(py, &y))
}

/// `horizon`-step prediction from measured `u`, `y`.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn narx_predict<'py>(
    py: Python<'py>,
    orders: Orders,
    degree: Option<usize>,
    rbf: Option<Rbf<'_>>,
    equations: Vec<(Vec<Vec<i64>>, Vec<f64>)>,
    u: PyReadonlyArray2<'_, f64>,
    y: PyReadonlyArray2<'_, f64>,
    horizon: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (uv, yv) = (view(&u), view(&y));
    let m = model(uv.ncols(), yv.ncols(), &orders, degree, rbf, equations)?;
    let p = py.detach(|| m.predict(uv, yv, horizon)).py()?;
    Ok(mat_to_numpy(py, &p))
}

/// Registers the functions of this file.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(narx_frols, m)?)?;
    m.add_function(wrap_pyfunction!(narx_fit, m)?)?;
    m.add_function(wrap_pyfunction!(narx_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(narx_predict, m)?)?;
    Ok(())
}
