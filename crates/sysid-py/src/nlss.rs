//! Bindings of `sysid_core::nlss`: PNLSS monomials, simulation and estimation, and the
//! neural state-space training.
//!
//! A structure crosses the boundary as a dict ([`PnlssStructure`], [`DecoupledStructure`],
//! [`NeuralStructure`]); PNLSS monomials as lists of variable indices into `z = [x; u]`.

use crate::convert::{mat_to_numpy, slice_to_numpy};
use crate::errors::IntoPy;
use crate::search::{run, search_items};
use faer::Mat;
use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::nlss::neural::{self, EpochReport, NeuralSs, Segment, TrainOptions};
use sysid_core::nlss::{self, Decoupled, Monomials, Pnlss, PnlssData, Terms};
use sysid_core::optim::{Flow, Iteration, Options, Solution};
use sysid_core::SysidError;

type Terms2 = Vec<Vec<usize>>;
type Pair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);
type Owned = Vec<(Vec<f64>, Vec<f64>, usize)>;
pub(crate) type Records<'a> = [(PyReadonlyArray2<'a, f64>, PyReadonlyArray2<'a, f64>, usize)];

pub(crate) fn slice<'a>(
    a: &'a PyReadonlyArray2<'_, f64>,
    name: &'static str,
) -> PyResult<&'a [f64]> {
    a.as_slice().map_err(|_| {
        crate::errors::to_py(SysidError::InvalidArgument {
            name,
            reason: "must be a C-contiguous float64 array".into(),
        })
    })
}

type Range = Option<(Vec<f64>, Vec<f64>)>;

/// A PNLSS structure, from a dict with `nx`, `nu`, `ny`, `zeta` and `eta` (the monomials
/// as index lists into `z = [x; u]`) and optionally `range = (lo, hi)`, which clamps the
/// monomials' arguments, and `stable`, whose fits keep the linear part's `A` stable.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct PnlssStructure {
    nx: usize,
    nu: usize,
    ny: usize,
    zeta: Terms2,
    eta: Terms2,
    #[pyo3(default)]
    range: Range,
    #[pyo3(default)]
    stable: bool,
}

impl PnlssStructure {
    fn model(self) -> PyResult<Pnlss> {
        let (nx, nu) = (self.nx, self.nu);
        let mut m = Pnlss::new(
            nx,
            nu,
            self.ny,
            Monomials::from_terms(nx, nu, self.zeta).py()?,
            Monomials::from_terms(nx, nu, self.eta).py()?,
        );
        m.stable_linear = self.stable;
        with_range(m, self.range, Pnlss::with_range)
    }
}

/// A decoupled PNLSS structure, from a dict with `dims = (nx, nu, ny)`, `branches`,
/// `degrees` and optionally `range = (lo, hi)`, which clamps the branch arguments, and
/// `stable` (as a PNLSS structure's).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct DecoupledStructure {
    dims: (usize, usize, usize),
    branches: usize,
    degrees: Vec<usize>,
    #[pyo3(default)]
    range: Range,
    #[pyo3(default)]
    stable: bool,
}

impl DecoupledStructure {
    fn model(self) -> PyResult<Decoupled> {
        let (nx, nu, ny) = self.dims;
        let mut m = Decoupled::new(nx, nu, ny, self.branches, self.degrees).py()?;
        m.stable_linear = self.stable;
        with_range(m, self.range, Decoupled::with_range)
    }
}

/// `m` with its arguments' box, when one is given.
fn with_range<M>(
    m: M,
    range: Range,
    set: impl FnOnce(M, Vec<f64>, Vec<f64>) -> sysid_core::Result<M>,
) -> PyResult<M> {
    match range {
        Some((lo, hi)) => Ok(set(m, lo, hi).py()?),
        None => Ok(m),
    }
}

/// Either polynomial structure (a dict of one or the other).
#[derive(FromPyObject)]
pub enum Structure {
    /// Coupled monomials.
    Pnlss(PnlssStructure),
    /// Univariate branches.
    Decoupled(DecoupledStructure),
}

/// A polynomial state-space model of either kind.
pub(crate) enum Model {
    Pnlss(Pnlss),
    Decoupled(Decoupled),
}

impl Structure {
    pub(crate) fn model(self) -> PyResult<Model> {
        Ok(match self {
            Structure::Pnlss(s) => Model::Pnlss(s.model()?),
            Structure::Decoupled(s) => Model::Decoupled(s.model()?),
        })
    }
}

impl Model {
    fn simulate(
        &self,
        theta: &[f64],
        u: &[f64],
        x0: Option<&[f64]>,
    ) -> sysid_core::Result<(Vec<f64>, Vec<f64>)> {
        match self {
            Model::Pnlss(m) => m.simulate(theta, u, x0),
            Model::Decoupled(m) => m.simulate(theta, u, x0),
        }
    }

    fn estimate(
        &self,
        data: &[PnlssData<'_>],
        theta0: &[f64],
        options: &Options,
        observer: &mut dyn FnMut(&Iteration) -> Flow,
    ) -> sysid_core::Result<Solution> {
        match self {
            Model::Pnlss(m) => nlss::estimate(m, data, theta0, options, observer),
            Model::Decoupled(m) => nlss::estimate_decoupled(m, data, theta0, options, observer),
        }
    }
}

/// The monomials (index lists into `z = [x; u]`) of the given degrees in the variables
/// `terms` selects ("full", "states" or "inputs").
#[pyfunction]
pub fn pnlss_monomials(nx: usize, nu: usize, terms: &str, degrees: Vec<usize>) -> PyResult<Terms2> {
    let t: Terms = terms.parse().py()?;
    Ok(Monomials::new(nx, nu, t, &degrees).py()?.terms().to_vec())
}

/// Simulated outputs and states (row-major `(N, ny)` and `(N, nx)` flattened) from `x0`, of
/// a PNLSS or decoupled PNLSS structure.
#[pyfunction]
#[pyo3(signature = (structure, theta, u, x0=None))]
pub fn pnlss_simulate<'py>(
    py: Python<'py>,
    structure: Structure,
    theta: Vec<f64>,
    u: PyReadonlyArray2<'_, f64>,
    x0: Option<Vec<f64>>,
) -> PyResult<Pair<'py>> {
    let m = structure.model()?;
    let us = slice(&u, "u")?;
    let (y, x) = py.detach(|| m.simulate(&theta, us, x0.as_deref())).py()?;
    Ok((slice_to_numpy(py, &y), slice_to_numpy(py, &x)))
}

/// Simulation-error fit of a PNLSS or decoupled PNLSS structure from `theta0`; records are
/// `(u, y, skip)`. Returns a dict with the optimiser's report and `theta`; with
/// `iterates=True` also `iterates`, the point of every iteration (one row each, in order).
#[pyfunction]
#[pyo3(signature = (structure, records, theta0, max_iter=100, tol=1e-8, fixed=None, progress=None, iterates=false, significance=0.0))]
#[allow(clippy::too_many_arguments)]
pub fn pnlss_estimate<'py>(
    py: Python<'py>,
    structure: Structure,
    records: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>, usize)>,
    theta0: PyReadonlyArray1<'_, f64>,
    max_iter: usize,
    tol: f64,
    fixed: Option<Vec<bool>>,
    progress: Option<Py<PyAny>>,
    iterates: bool,
    significance: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let m = structure.model()?;
    let data = records_data(&records)?;
    let th0 = crate::convert::vec1(&theta0);
    let mut opts = fit_options(max_iter, tol);
    opts.fixed = fixed;
    opts.significance = significance;
    let mut kept = Vec::new();
    let sol = run(py, &progress, |obs| {
        m.estimate(&data, &th0, &opts, &mut keeping(obs, iterates, &mut kept))
    })?;
    fit_dict(py, &sol, iterates.then_some(kept))
}

/// `obs`, also appending the point of every iteration to `kept` when `keep`.
pub(crate) fn keeping<'a>(
    obs: &'a mut dyn FnMut(&Iteration) -> Flow,
    keep: bool,
    kept: &'a mut Vec<f64>,
) -> impl FnMut(&Iteration) -> Flow + 'a {
    move |it: &Iteration| {
        if keep {
            kept.extend_from_slice(it.theta);
        }
        obs(it)
    }
}

/// The dict a simulation-error fit returns: the optimiser's report, `theta`, and the kept
/// iterates (`iterations x p`) when given.
pub(crate) fn fit_dict<'py>(
    py: Python<'py>,
    sol: &Solution,
    kept: Option<Vec<f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    search_items(&d, py, sol)?;
    d.set_item("theta", slice_to_numpy(py, &sol.theta))?;
    if let Some(k) = kept {
        let p = sol.theta.len();
        let rows = k.len().checked_div(p).unwrap_or(0);
        d.set_item(
            "iterates",
            mat_to_numpy(py, &Mat::from_fn(rows, p, |i, j| k[i * p + j])),
        )?;
    }
    Ok(d)
}

/// The records `(u, y, skip)` as the core reads them.
pub(crate) fn records_data<'a>(records: &'a Records<'_>) -> PyResult<Vec<PnlssData<'a>>> {
    records
        .iter()
        .map(|(u, y, skip)| {
            Ok(PnlssData {
                u: slice(u, "u")?,
                y: slice(y, "y")?,
                skip: *skip,
            })
        })
        .collect()
}

/// The optimiser's options of a simulation-error fit.
pub(crate) fn fit_options(max_iter: usize, tol: f64) -> Options {
    let mut opts = Options::default();
    opts.max_iter = max_iter;
    opts.tol_cost = tol;
    opts.tol_step = tol;
    opts.tol_gradient = tol * tol;
    // statistical convergence, as pem's searches (problems that count their residuals)
    opts.tol_statistical = 1e-2;
    opts
}

/// Registers the functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(pnlss_monomials, m)?)?;
    m.add_function(wrap_pyfunction!(pnlss_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(pnlss_estimate, m)?)?;
    register_neural(m)
}

/// A neural state-space structure, from a dict with `dims = (nx, nu, ny)`, the hidden
/// widths `f_hidden`, `g_hidden` (`None`: no output network) and `h_hidden` (the encoder),
/// and the encoder's `lags`.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct NeuralStructure {
    dims: (usize, usize, usize),
    f_hidden: Vec<usize>,
    #[pyo3(default)]
    g_hidden: Option<Vec<usize>>,
    h_hidden: Vec<usize>,
    lags: usize,
}

impl NeuralStructure {
    fn model(&self) -> NeuralSs {
        let (nx, nu, ny) = self.dims;
        NeuralSs::new(
            nx,
            nu,
            ny,
            &self.f_hidden,
            self.g_hidden.as_deref(),
            &self.h_hidden,
            self.lags,
        )
    }
}

/// Neural state-space simulation from `x0` (row-major `(N, ny)` flattened).
#[pyfunction]
pub fn neural_ss_simulate<'py>(
    py: Python<'py>,
    structure: NeuralStructure,
    params: PyReadonlyArray1<'_, f64>,
    u: PyReadonlyArray2<'_, f64>,
    x0: Vec<f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = structure.model();
    let p = crate::convert::vec1(&params);
    let us = slice(&u, "u")?;
    let y = py.detach(|| m.simulate(&p, us, &x0)).py()?;
    Ok(slice_to_numpy(py, &y))
}

/// The encoder's state at sample `t` of a record.
#[pyfunction]
pub fn neural_ss_encode<'py>(
    py: Python<'py>,
    structure: NeuralStructure,
    params: PyReadonlyArray1<'_, f64>,
    u: PyReadonlyArray2<'_, f64>,
    y: PyReadonlyArray2<'_, f64>,
    t: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = structure.model();
    let p = crate::convert::vec1(&params);
    let x = m.encode(&p, slice(&u, "u")?, slice(&y, "y")?, t).py()?;
    Ok(slice_to_numpy(py, &x))
}

/// Trains from `params0`; `train` and `val` are `(u, y, at)` records. `progress(epoch,
/// validation, train)` after every epoch (`False` stops); `rates`: each parameter's step
/// size as a fraction of `learning_rate`; `penalty`: each parameter's weight in the L2
/// penalty toward `params0`. Returns a dict.
#[pyfunction]
#[pyo3(signature = (structure, params0, train, val, epochs=200, batch=16, horizon=100, learning_rate=1e-3, patience=20, seed=0, progress=None, rates=None, penalty=None))]
#[allow(clippy::too_many_arguments)]
pub fn neural_ss_train<'py>(
    py: Python<'py>,
    structure: NeuralStructure,
    params0: PyReadonlyArray1<'_, f64>,
    train: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>, usize)>,
    val: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>, usize)>,
    epochs: usize,
    batch: usize,
    horizon: usize,
    learning_rate: f64,
    patience: usize,
    seed: u64,
    progress: Option<Py<PyAny>>,
    rates: Option<PyReadonlyArray1<'_, f64>>,
    penalty: Option<PyReadonlyArray1<'_, f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = structure.model();
    let seg = |v: &Records<'_>| -> PyResult<Owned> {
        v.iter()
            .map(|(u, y, at)| Ok((slice(u, "u")?.to_vec(), slice(y, "y")?.to_vec(), *at)))
            .collect()
    };
    let (tr, va) = (seg(&train)?, seg(&val)?);
    let p0 = crate::convert::vec1(&params0);
    let mut opts = TrainOptions::default();
    opts.epochs = epochs;
    opts.batch = batch.max(1);
    opts.horizon = horizon;
    opts.learning_rate = learning_rate;
    opts.patience = patience;
    opts.seed = seed;
    opts.rates = rates.map(|r| crate::convert::vec1(&r)).unwrap_or_default();
    opts.penalty = penalty
        .map(|r| crate::convert::vec1(&r))
        .unwrap_or_default();
    let mut slot: Option<PyErr> = None;
    let res = crate::search::watch(py, || {
        let ts: Vec<Segment<'_>> = tr
            .iter()
            .map(|(u, y, at)| Segment { u, y, at: *at })
            .collect();
        let vs: Vec<Segment<'_>> = va
            .iter()
            .map(|(u, y, at)| Segment { u, y, at: *at })
            .collect();
        neural::train(&m, &p0, &ts, &vs, &opts, &mut |r: &EpochReport| {
            Python::attach(|py| {
                let out = match &progress {
                    Some(cb) => cb
                        .call1(py, (r.epoch, r.validation, r.train))
                        .map(|v| v.bind(py).is(&*pyo3::types::PyBool::new(py, false))),
                    None => Ok(false),
                };
                match out {
                    Ok(true) => Flow::Stop,
                    Ok(false) => Flow::Continue,
                    Err(e) => {
                        slot.get_or_insert(e);
                        Flow::Stop
                    }
                }
            })
        })
    });
    let r = crate::search::finish(res, slot)?;
    let d = PyDict::new(py);
    d.set_item("params", slice_to_numpy(py, &r.params))?;
    d.set_item("validation", r.validation)?;
    d.set_item("train", r.train)?;
    d.set_item("best_epoch", r.best_epoch)?;
    d.set_item("stop", r.stop)?;
    d.set_item("diverged", r.diverged)?;
    Ok(d)
}

/// Parameter count of a neural state-space structure.
#[pyfunction]
pub fn neural_ss_n_params(structure: NeuralStructure) -> usize {
    structure.model().n_params()
}

/// Registers the neural state-space functions.
pub fn register_neural(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(neural_ss_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(neural_ss_encode, m)?)?;
    m.add_function(wrap_pyfunction!(neural_ss_train, m)?)?;
    m.add_function(wrap_pyfunction!(neural_ss_n_params, m)?)?;
    Ok(())
}
