//! Bindings of `sysid_core::narx`: FROLS term selection, least-squares fit of chosen terms,
//! free-run simulation and k-step prediction of NARX / NARMAX models.
//!
//! Terms cross the boundary as lists of ints: a monomial is its sorted variable indices
//! (empty: the constant), radial basis function `c` is `[-1 - c]`, custom regressor `c`
//! is `[-1, c]` (the variable after the lagged ones, so the code does not depend on them).
//!
//! Custom regressors cross as their arguments, `(kind, channel, lag)` with kind 0 for an
//! output and 1 for an input; their values as one `(N, n_custom)` array per experiment
//! (estimation) or as Python callables of the argument values (simulation, prediction).

use crate::convert::{mat_to_numpy, slice_to_numpy, view, view_nd};
use crate::errors::IntoPy;
use faer::{Mat, MatRef};
use numpy::{PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::cell::RefCell;
use sysid_core::narx::basis::{Basis, Candidates, RbfBasis, Term};
use sysid_core::narx::frols::{self, FrolsOptions};
use sysid_core::narx::regressors::{LagSpec, LagVar, Record, Signal};
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

type CustomArgs = Vec<Vec<(u8, usize, usize)>>;

fn spec(
    nu: usize,
    ny: usize,
    orders: &(Vec<usize>, Vec<usize>, Vec<usize>, Vec<usize>),
    custom: &CustomArgs,
) -> PyResult<LagSpec> {
    let sp = LagSpec::new(nu, ny, &orders.0, &orders.1, &orders.2, &orders.3).py()?;
    if custom.is_empty() {
        return Ok(sp);
    }
    let args = custom
        .iter()
        .map(|a| {
            a.iter()
                .map(|&(kind, channel, lag)| LagVar {
                    signal: if kind == 0 {
                        Signal::Output
                    } else {
                        Signal::Input
                    },
                    channel,
                    lag,
                })
                .collect()
        })
        .collect();
    sp.with_custom(args).py()
}

fn encode(t: &Term, n_lagged: usize) -> Vec<i64> {
    match t {
        Term::Monomial(v) => v.iter().map(|&i| i as i64).collect(),
        Term::Rbf(c) => vec![-1 - *c as i64],
        Term::Custom(v) => vec![-1, (*v - n_lagged) as i64],
    }
}

fn decode(v: &[i64], n_lagged: usize) -> Term {
    match v {
        [-1, c] => Term::Custom(n_lagged + (*c).max(0) as usize),
        [c] if *c < 0 => Term::Rbf((-1 - c) as usize),
        _ => Term::Monomial(v.iter().map(|&i| i.max(0) as usize).collect()),
    }
}

type Views<'a> = (MatRef<'a, f64>, MatRef<'a, f64>, Option<MatRef<'a, f64>>);

/// The structure's basis and lag specification for the experiments' channel counts.
fn built(experiments: &Experiments<'_>, structure: Structure<'_>) -> PyResult<(Basis, LagSpec)> {
    let (nu, ny) = experiments
        .first()
        .map(|(u, y, _)| (u.as_array().ncols(), y.as_array().ncols()))
        .unwrap_or((0, 1));
    structure.build(nu, ny)
}

/// Views of every experiment's `(u, y, e)`, no copies.
fn experiment_views<'a>(experiments: &'a Experiments<'_>) -> Vec<Views<'a>> {
    experiments
        .iter()
        .map(|(u, y, e)| {
            (
                view_nd(u.as_array()),
                view_nd(y.as_array()),
                e.as_ref().map(|e| view_nd(e.as_array())),
            )
        })
        .collect()
}

fn records<'a>(views: &'a [Views<'a>], custom: &'a [MatRef<'a, f64>]) -> Vec<Record<'a>> {
    views
        .iter()
        .enumerate()
        .map(|(i, (u, y, e))| Record {
            u: *u,
            y: *y,
            e: *e,
            c: custom.get(i).copied(),
        })
        .collect()
}

type Orders = (Vec<usize>, Vec<usize>, Vec<usize>, Vec<usize>);

/// The model structure every NARX call shares, from a dict with `orders` (na, nb, nk, ne),
/// `degree` or `rbf` (the basis) and `custom_args` (missing keys take the defaults).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct Structure<'py> {
    orders: Orders,
    #[pyo3(default)]
    degree: Option<usize>,
    #[pyo3(default)]
    rbf: Option<Rbf<'py>>,
    #[pyo3(default)]
    custom_args: CustomArgs,
}

impl Structure<'_> {
    /// The basis and the regressor spec for `nu` inputs and `ny` outputs.
    fn build(self, nu: usize, ny: usize) -> PyResult<(Basis, LagSpec)> {
        let b = basis(self.degree, self.rbf)?;
        let sp = spec(nu, ny, &self.orders, &self.custom_args)?;
        Ok((b, sp))
    }
}

/// FROLS selection for every output, then the streaming QR factor of `[chosen terms, y_i]`.
/// Returns, per output, a dict with `terms` (encoded), `err`, `rss`, `r`, `n_rows`, and the
/// number of candidates.
#[pyfunction]
#[pyo3(signature = (experiments, structure, max_terms, forced, err_tol=1e-10, block_rows=0, custom_values=vec![]))]
#[allow(clippy::too_many_arguments)]
pub fn narx_frols<'py>(
    py: Python<'py>,
    experiments: Experiments<'_>,
    structure: Structure<'_>,
    max_terms: usize,
    forced: Vec<Vec<Vec<i64>>>,
    err_tol: f64,
    block_rows: usize,
    custom_values: Vec<PyReadonlyArray2<'_, f64>>,
) -> PyResult<(Vec<Bound<'py, PyDict>>, usize)> {
    let (b, sp) = built(&experiments, structure)?;
    let cviews: Vec<MatRef<'_, f64>> = custom_values.iter().map(view).collect();
    let views = experiment_views(&experiments);
    let (sels, rs, terms, m) = crate::search::detach(py, || -> sysid_core::Result<_> {
        let cands = Candidates::with_custom(&b, sp.n_lagged(), sp.n_custom())?;
        let index =
            |t: &Vec<i64>| -> sysid_core::Result<usize> {
                let t = decode(t, sp.n_lagged());
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
        let recs = records(&views, &cviews);
        let sels = frols::frols(&sp, &cands, &recs, &forced_idx, &opts)?;
        let chosen: Vec<Vec<usize>> = sels.iter().map(|s| s.terms.clone()).collect();
        let rs = frols::fit(&sp, &cands, &recs, &chosen)?;
        let terms: Vec<Vec<Vec<i64>>> = chosen
            .iter()
            .map(|c| {
                c.iter()
                    .map(|&k| encode(&cands.terms[k], sp.n_lagged()))
                    .collect()
            })
            .collect();
        Ok((sels, rs, terms, cands.len()))
    })?;
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
#[pyo3(signature = (experiments, structure, terms, custom_values=vec![]))]
pub fn narx_fit<'py>(
    py: Python<'py>,
    experiments: Experiments<'_>,
    structure: Structure<'_>,
    terms: Vec<Vec<Vec<i64>>>,
    custom_values: Vec<PyReadonlyArray2<'_, f64>>,
) -> PyResult<Vec<Bound<'py, PyArray2<f64>>>> {
    let (b, sp) = built(&experiments, structure)?;
    let cviews: Vec<MatRef<'_, f64>> = custom_values.iter().map(view).collect();
    let views = experiment_views(&experiments);
    let rs = crate::search::detach(py, || -> sysid_core::Result<Vec<Mat<f64>>> {
        let ts: Vec<Vec<Term>> = terms
            .iter()
            .map(|t| t.iter().map(|v| decode(v, sp.n_lagged())).collect())
            .collect();
        frols::fit_terms(&sp, &b, &records(&views, &cviews), &ts)
    })?;
    Ok(rs.iter().map(|r| mat_to_numpy(py, r)).collect())
}

fn model(
    nu: usize,
    ny: usize,
    structure: Structure<'_>,
    equations: Vec<(Vec<Vec<i64>>, Vec<f64>)>,
) -> PyResult<NarxModel> {
    let (b, sp) = structure.build(nu, ny)?;
    let eqs = equations
        .into_iter()
        .map(|(t, c)| Equation {
            terms: t.iter().map(|v| decode(v, sp.n_lagged())).collect(),
            coefs: c,
        })
        .collect();
    NarxModel::new(sp, b, eqs).py()
}

/// Runs `run` with a callback evaluating custom regressor `c` by the Python callable
/// `fns[c]` (called with the argument values as floats; must return a float). A Python
/// exception from a callable is raised as is.
fn custom_error(reason: String) -> SysidError {
    SysidError::InvalidArgument {
        name: "custom",
        reason,
    }
}

fn with_custom<T>(
    py: Python<'_>,
    fns: &[Py<PyAny>],
    run: impl FnOnce(&mut sysid_core::narx::simulate::CustomFn<'_>) -> sysid_core::Result<T> + Send,
) -> PyResult<T>
where
    T: Send,
{
    if fns.is_empty() {
        let mut none = |_: usize, _: &[f64]| -> sysid_core::Result<f64> {
            Err(custom_error(
                "the model has custom regressors: pass their functions".into(),
            ))
        };
        return crate::search::detach(py, || run(&mut none));
    }
    let failure: RefCell<Option<PyErr>> = RefCell::new(None);
    let mut call = |c: usize, args: &[f64]| -> sysid_core::Result<f64> {
        let f = fns
            .get(c)
            .ok_or_else(|| custom_error(format!("no function for custom regressor {c}")))?;
        let r = f
            .bind(py)
            .call1(pyo3::types::PyTuple::new(py, args).map_err(|e| custom_error(e.to_string()))?)
            .and_then(|v| v.extract::<f64>());
        r.map_err(|e| {
            let msg = format!("custom regressor {c} failed: {e}");
            *failure.borrow_mut() = Some(e);
            custom_error(msg)
        })
    };
    let out = run(&mut call);
    if let Some(e) = failure.into_inner() {
        return Err(e);
    }
    out.py()
}

/// Free-run simulation; `y0` holds the first `max_lag` outputs; `custom_fns` evaluate the
/// custom regressors (arguments `custom_args`).
#[pyfunction]
#[pyo3(signature = (structure, equations, u, y0, custom_fns=vec![]))]
pub fn narx_simulate<'py>(
    py: Python<'py>,
    structure: Structure<'_>,
    equations: Vec<(Vec<Vec<i64>>, Vec<f64>)>,
    u: PyReadonlyArray2<'_, f64>,
    y0: PyReadonlyArray2<'_, f64>,
    custom_fns: Vec<Py<PyAny>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (uv, yv) = (view(&u), view(&y0));
    let m = model(uv.ncols(), yv.ncols(), structure, equations)?;
    let y = with_custom(py, &custom_fns, |f| m.simulate_with(uv, yv, f))?;
    Ok(mat_to_numpy(py, &y))
}

/// `horizon`-step prediction from measured `u`, `y`.
#[pyfunction]
#[pyo3(signature = (structure, equations, u, y, horizon, custom_fns=vec![]))]
pub fn narx_predict<'py>(
    py: Python<'py>,
    structure: Structure<'_>,
    equations: Vec<(Vec<Vec<i64>>, Vec<f64>)>,
    u: PyReadonlyArray2<'_, f64>,
    y: PyReadonlyArray2<'_, f64>,
    horizon: usize,
    custom_fns: Vec<Py<PyAny>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (uv, yv) = (view(&u), view(&y));
    let m = model(uv.ncols(), yv.ncols(), structure, equations)?;
    let p = with_custom(py, &custom_fns, |f| m.predict_with(uv, yv, horizon, f))?;
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
