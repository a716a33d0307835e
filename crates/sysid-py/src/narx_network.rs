//! Bindings of `sysid_core::narx::network`: training of sigmoid / wavelet networks (one
//! output at a time, separable least squares) and tree partitions, refinement for
//! simulation, free-run simulation and k-step prediction.
//!
//! A nonlinearity crosses the boundary as a tuple: a unit network as
//! `(kinds, theta, linear)` (kind codes 0 sigmoid, 1 wavelet, 2 scaling), a tree partition as
//! `(var, threshold, left, right, coefs)` (per node; `left = right = -1` at leaves).

use crate::convert::{mat_to_numpy, view};
use crate::errors::IntoPy;
use crate::search::{detach, run, search_items};
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::interrupt;
use sysid_core::narx::network::model::{
    NetworkNarx, Nonlinearity, TreeNode, TreePartition, UnitNetwork,
};
use sysid_core::narx::network::tree::{fit_tree, TreeOptions};
use sysid_core::narx::network::units::UnitKind;
use sysid_core::narx::network::{fit_prediction, fit_simulation};
use sysid_core::narx::regressors::{LagSpec, Record};
use sysid_core::optim::Options;
use sysid_core::SysidError;

type Orders = (Vec<usize>, Vec<usize>, Vec<usize>);
type Experiments<'a> = Vec<(PyReadonlyArray2<'a, f64>, PyReadonlyArray2<'a, f64>)>;

/// One output's nonlinearity as it crosses the boundary.
#[derive(FromPyObject, IntoPyObject)]
pub enum NlArg {
    /// `(kinds, theta, linear)`.
    Network(Vec<i64>, Vec<f64>, Vec<f64>),
    /// `(var, threshold, left, right, coefs)`.
    Tree(Vec<usize>, Vec<f64>, Vec<i64>, Vec<i64>, Vec<Vec<f64>>),
}

fn invalid(name: &'static str, reason: impl Into<String>) -> PyErr {
    crate::errors::to_py(SysidError::InvalidArgument {
        name,
        reason: reason.into(),
    })
}

fn kinds(codes: &[i64]) -> PyResult<Vec<UnitKind>> {
    codes
        .iter()
        .map(|&k| {
            u8::try_from(k)
                .ok()
                .and_then(UnitKind::from_code)
                .ok_or_else(|| invalid("kinds", format!("unknown unit kind {k}")))
        })
        .collect()
}

fn decode(a: NlArg) -> PyResult<Nonlinearity> {
    Ok(match a {
        NlArg::Network(k, theta, linear) => Nonlinearity::Network(UnitNetwork {
            kinds: kinds(&k)?,
            theta,
            linear,
        }),
        NlArg::Tree(var, thr, left, right, coefs) => {
            let n = var.len();
            if thr.len() != n || left.len() != n || right.len() != n || coefs.len() != n {
                return Err(invalid(
                    "tree",
                    "var, threshold, left, right and coefs need one entry per node",
                ));
            }
            let nodes = (0..n)
                .map(|i| TreeNode {
                    var: var[i],
                    threshold: thr[i],
                    children: (left[i] >= 0 && right[i] >= 0)
                        .then_some((left[i] as usize, right[i] as usize)),
                    coefs: coefs[i].clone(),
                })
                .collect();
            Nonlinearity::Tree(TreePartition { nodes })
        }
    })
}

fn encode(nl: &Nonlinearity) -> NlArg {
    match nl {
        Nonlinearity::Network(n) => NlArg::Network(
            n.kinds
                .iter()
                .map(|k| match k {
                    UnitKind::Sigmoid => 0,
                    UnitKind::Wavelet => 1,
                    UnitKind::Scaling => 2,
                })
                .collect(),
            n.theta.clone(),
            n.linear.clone(),
        ),
        Nonlinearity::Tree(t) => {
            let ch = |i: usize| {
                t.nodes[i]
                    .children
                    .map(|(l, r)| (l as i64, r as i64))
                    .unwrap_or((-1, -1))
            };
            NlArg::Tree(
                t.nodes.iter().map(|n| n.var).collect(),
                t.nodes.iter().map(|n| n.threshold).collect(),
                (0..t.nodes.len()).map(|i| ch(i).0).collect(),
                (0..t.nodes.len()).map(|i| ch(i).1).collect(),
                t.nodes.iter().map(|n| n.coefs.clone()).collect(),
            )
        }
    }
}

fn spec(nu: usize, ny: usize, o: &Orders) -> PyResult<LagSpec> {
    LagSpec::new(nu, ny, &o.0, &o.1, &o.2, &vec![0; ny]).py()
}

/// What every network NARX call shares, from a dict with `orders = (na, nb, nk)`, the
/// regressors' `shift` and `scale`, and the nonlinearities `outputs` (one per output; absent
/// while they are being fitted).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct Structure {
    orders: Orders,
    shift: Vec<f64>,
    scale: Vec<f64>,
    #[pyo3(default)]
    outputs: Vec<NlArg>,
}

impl Structure {
    fn model(self) -> PyResult<NetworkNarx> {
        let nl = self
            .outputs
            .into_iter()
            .map(decode)
            .collect::<PyResult<Vec<_>>>()?;
        let o = &self.orders;
        let sp = spec(o.1.len(), o.0.len(), o)?;
        NetworkNarx::new(sp, self.shift, self.scale, nl).py()
    }
}

fn options(max_iter: usize, tol: f64, bounds: Option<(Vec<f64>, Vec<f64>)>) -> Options {
    let mut o = Options::default();
    o.max_iter = max_iter;
    o.tol_cost = tol;
    if let Some((lo, hi)) = bounds {
        o.lower = Some(lo);
        o.upper = Some(hi);
    }
    o
}

fn records<'a>(exps: &'a Experiments<'_>) -> Vec<Record<'a>> {
    exps.iter()
        .map(|(u, y)| Record::new(view(u), view(y)))
        .collect()
}

fn shape(exps: &Experiments<'_>) -> (usize, usize) {
    exps.first()
        .map(|(u, y)| (u.as_array().ncols(), y.as_array().ncols()))
        .unwrap_or((0, 1))
}

/// Trains the unit network of output `output` for one-step prediction from `theta0`.
/// Returns the network tuple and the search report (`sysid._sysid` dict items).
#[pyfunction]
#[pyo3(signature = (experiments, structure, output, kinds, theta0, max_iter=100, tol=1e-7, progress=None, bounds=None))]
#[allow(clippy::too_many_arguments)]
pub fn narx_network_fit<'py>(
    py: Python<'py>,
    experiments: Experiments<'_>,
    structure: Structure,
    output: usize,
    kinds: Vec<i64>,
    theta0: Vec<f64>,
    max_iter: usize,
    tol: f64,
    progress: Option<Py<PyAny>>,
    bounds: Option<(Vec<f64>, Vec<f64>)>,
) -> PyResult<(NlArg, Bound<'py, PyDict>)> {
    let (nu, ny) = shape(&experiments);
    let sp = spec(nu, ny, &structure.orders)?;
    let ks = self::kinds(&kinds)?;
    let recs = records(&experiments);
    let opts = options(max_iter, tol, bounds);
    let (shift, scale) = (&structure.shift, &structure.scale);
    let (net, sol) = run(py, &progress, |obs| {
        fit_prediction(&sp, shift, scale, &recs, output, ks, &theta0, &opts, obs)
    })?;
    let d = PyDict::new(py);
    search_items(&d, py, &sol)?;
    d.set_item("n_rows", sp.check_records(&recs).py()?)?;
    Ok((encode(&Nonlinearity::Network(net)), d))
}

/// Grows the tree partition of output `output`. Returns the tree tuple and a dict with
/// `rss` (after each split), `n_rows`, `stop`.
#[pyfunction]
#[pyo3(signature = (experiments, structure, output, max_leaves=16, min_leaf=0))]
pub fn narx_tree_fit<'py>(
    py: Python<'py>,
    experiments: Experiments<'_>,
    structure: Structure,
    output: usize,
    max_leaves: usize,
    min_leaf: usize,
) -> PyResult<(NlArg, Bound<'py, PyDict>)> {
    let (nu, ny) = shape(&experiments);
    let sp = spec(nu, ny, &structure.orders)?;
    let recs = records(&experiments);
    let opts = TreeOptions::new(max_leaves, min_leaf);
    let (shift, scale) = (&structure.shift, &structure.scale);
    // Ctrl-C stops growing between splits; the interrupt is raised after
    let fit = detach(py, || {
        fit_tree(
            &sp,
            shift,
            scale,
            &recs,
            output,
            &opts,
            &mut interrupt::requested,
        )
    })?;
    let d = PyDict::new(py);
    d.set_item("rss", fit.rss.clone())?;
    d.set_item("n_rows", fit.n_rows)?;
    d.set_item("stop", fit.stop)?;
    Ok((encode(&Nonlinearity::Tree(fit.tree)), d))
}

/// Refines every parameter for free-run simulation. Returns the nonlinearities and the
/// search report.
#[pyfunction]
#[pyo3(signature = (experiments, structure, max_iter=100, tol=1e-7, progress=None, bounds=None))]
pub fn narx_network_refine<'py>(
    py: Python<'py>,
    experiments: Experiments<'_>,
    structure: Structure,
    max_iter: usize,
    tol: f64,
    progress: Option<Py<PyAny>>,
    bounds: Option<(Vec<f64>, Vec<f64>)>,
) -> PyResult<(Vec<NlArg>, Bound<'py, PyDict>)> {
    let m = structure.model()?;
    let recs = records(&experiments);
    let opts = options(max_iter, tol, bounds);
    let (m, sol) = run(py, &progress, |obs| fit_simulation(m, &recs, &opts, obs))?;
    let d = PyDict::new(py);
    search_items(&d, py, &sol)?;
    Ok((m.outputs.iter().map(encode).collect(), d))
}

/// Free-run simulation from the initial outputs `y0` (`max_lag x n_outputs`).
#[pyfunction]
pub fn narx_network_simulate<'py>(
    py: Python<'py>,
    structure: Structure,
    u: PyReadonlyArray2<'_, f64>,
    y0: PyReadonlyArray2<'_, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = structure.model()?;
    let (u, y0) = (view(&u), view(&y0));
    let y = py.detach(|| m.simulate(u, y0)).py()?;
    Ok(mat_to_numpy(py, &y))
}

/// `horizon`-step prediction from measured `u`, `y`.
#[pyfunction]
pub fn narx_network_predict<'py>(
    py: Python<'py>,
    structure: Structure,
    u: PyReadonlyArray2<'_, f64>,
    y: PyReadonlyArray2<'_, f64>,
    horizon: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = structure.model()?;
    let (u, y) = (view(&u), view(&y));
    let p = py.detach(|| m.predict(u, y, horizon)).py()?;
    Ok(mat_to_numpy(py, &p))
}

/// The nonlinearities at lagged variables `x` (`n x n_vars`): `n x n_outputs`.
#[pyfunction]
pub fn narx_network_evaluate<'py>(
    py: Python<'py>,
    structure: Structure,
    x: PyReadonlyArray2<'_, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = structure.model()?;
    let x = view(&x);
    let v = py.detach(|| m.evaluate(x)).py()?;
    Ok(mat_to_numpy(py, &v))
}

/// Registers the functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(narx_network_fit, m)?)?;
    m.add_function(wrap_pyfunction!(narx_tree_fit, m)?)?;
    m.add_function(wrap_pyfunction!(narx_network_refine, m)?)?;
    m.add_function(wrap_pyfunction!(narx_network_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(narx_network_predict, m)?)?;
    m.add_function(wrap_pyfunction!(narx_network_evaluate, m)?)?;
    Ok(())
}
