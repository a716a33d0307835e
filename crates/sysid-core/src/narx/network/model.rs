//! A NARX model whose outputs are network nonlinearities of the standardised regressors,
//! with its free-run simulation and k-step prediction.

use faer::{Mat, MatRef};

use super::units::UnitKind;
use crate::error::{check_finite, check_io, Result, SysidError};
use crate::narx::regressors::{LagSpec, Signal};
use crate::narx::run::{self, Outputs};

/// `F(z) = d + l^T z + sum_k a_k g_k(z; p_k)`: a linear term plus nonlinear units.
#[derive(Debug, Clone, PartialEq)]
pub struct UnitNetwork {
    /// The kind of each unit.
    pub kinds: Vec<UnitKind>,
    /// The unit parameters `p_1, p_2, ...` one after the other (`nz + 1` each).
    pub theta: Vec<f64>,
    /// The parameters entering linearly: `[d, l (nz), a (n_units)]`.
    pub linear: Vec<f64>,
}

impl UnitNetwork {
    /// Value at the standardised regressors `z`.
    ///
    /// ```
    /// use sysid_core::narx::network::{model::UnitNetwork, units::UnitKind};
    /// let f = UnitNetwork { kinds: vec![UnitKind::Sigmoid], theta: vec![1.0, 0.0],
    ///                       linear: vec![1.0, 2.0, 4.0] };
    /// assert_eq!(f.value(&[0.0]), 1.0 + 4.0 * 0.5);
    /// ```
    #[inline]
    pub fn value(&self, z: &[f64]) -> f64 {
        let nz = z.len();
        let mut v = self.linear[0];
        for (l, x) in self.linear[1..=nz].iter().zip(z) {
            v += l * x;
        }
        for (k, kind) in self.kinds.iter().enumerate() {
            let p = &self.theta[k * (nz + 1)..(k + 1) * (nz + 1)];
            v += self.linear[1 + nz + k] * kind.value(p, z);
        }
        v
    }

    fn check(&self, nz: usize) -> Result<()> {
        let k = self.kinds.len();
        if self.theta.len() != k * (nz + 1) || self.linear.len() != 1 + nz + k {
            return Err(SysidError::invalid(
                "network",
                format!(
                    "{k} units on {nz} regressors need {} unit parameters and {} linear ones, \
                     got {} and {}",
                    k * (nz + 1),
                    1 + nz + k,
                    self.theta.len(),
                    self.linear.len()
                ),
            ));
        }
        Ok(())
    }
}

/// One node of a binary tree partition. Internal nodes send `z` to `left` when
/// `z[var] <= threshold`; leaves hold the local affine model `coefs = [c0, c (nz)]`.
#[derive(Debug, Clone, PartialEq)]
pub struct TreeNode {
    /// The regressor the split reads (internal nodes).
    pub var: usize,
    /// The split threshold (internal nodes).
    pub threshold: f64,
    /// Indices of the two children, `None` for a leaf.
    pub children: Option<(usize, usize)>,
    /// The local affine model of the node's cell (used at leaves).
    pub coefs: Vec<f64>,
}

/// A piecewise-affine function on a binary partition of the regressor space; node 0 is
/// the root.
#[derive(Debug, Clone, PartialEq)]
pub struct TreePartition {
    /// The nodes.
    pub nodes: Vec<TreeNode>,
}

impl TreePartition {
    /// The leaf whose cell holds `z`.
    #[inline]
    pub fn leaf(&self, z: &[f64]) -> usize {
        let mut i = 0;
        while let Some((l, r)) = self.nodes[i].children {
            i = if z[self.nodes[i].var] <= self.nodes[i].threshold {
                l
            } else {
                r
            };
        }
        i
    }

    /// Value at `z`: the affine model of its leaf.
    #[inline]
    pub fn value(&self, z: &[f64]) -> f64 {
        let c = &self.nodes[self.leaf(z)].coefs;
        c[0] + c[1..].iter().zip(z).map(|(a, b)| a * b).sum::<f64>()
    }

    fn check(&self, nz: usize) -> Result<()> {
        let n = self.nodes.len();
        let ok = n > 0
            && self.nodes.iter().enumerate().all(|(i, nd)| {
                nd.coefs.len() == nz + 1
                    && nd.coefs.iter().all(|c| c.is_finite())
                    && match nd.children {
                        None => true,
                        Some((l, r)) => l > i && r > i && l < n && r < n && nd.var < nz,
                    }
            });
        if ok {
            Ok(())
        } else {
            Err(SysidError::invalid(
                "tree",
                format!(
                    "the nodes do not form a tree on {nz} regressors with {} coefficients \
                         per node",
                    nz + 1
                ),
            ))
        }
    }
}

/// The nonlinearity of one output.
#[derive(Debug, Clone, PartialEq)]
pub enum Nonlinearity {
    /// Sigmoid or wavelet network.
    Network(UnitNetwork),
    /// Tree partition.
    Tree(TreePartition),
}

impl Nonlinearity {
    /// Value at the standardised regressors `z`.
    #[inline]
    pub fn value(&self, z: &[f64]) -> f64 {
        match self {
            Nonlinearity::Network(n) => n.value(z),
            Nonlinearity::Tree(t) => t.value(z),
        }
    }
}

/// `y_i(t) = F_i((x(t) - shift) / scale)` for the lagged variables `x(t)` of `spec`.
#[derive(Debug, Clone)]
pub struct NetworkNarx {
    /// The lagged variables (no noise lags, no custom regressors).
    pub spec: LagSpec,
    /// Standardisation: shift per lagged variable.
    pub shift: Vec<f64>,
    /// Standardisation: scale per lagged variable (positive).
    pub scale: Vec<f64>,
    /// One nonlinearity per output.
    pub outputs: Vec<Nonlinearity>,
}

impl NetworkNarx {
    /// Checks the parts and builds the model.
    pub fn new(
        spec: LagSpec,
        shift: Vec<f64>,
        scale: Vec<f64>,
        outputs: Vec<Nonlinearity>,
    ) -> Result<Self> {
        let nz = spec.n_vars();
        if spec.has_noise() || spec.n_custom() > 0 {
            return Err(SysidError::invalid(
                "orders",
                "network nonlinearities take lagged outputs and inputs only (no noise lags, \
                 no custom regressors)",
            ));
        }
        if shift.len() != nz || scale.len() != nz {
            return Err(SysidError::invalid(
                "shift, scale",
                format!("need one value per regressor ({nz})"),
            ));
        }
        if scale.iter().any(|s| !(s.is_finite() && *s > 0.0))
            || shift.iter().any(|s| !s.is_finite())
        {
            return Err(SysidError::invalid("scale", "must be finite and positive"));
        }
        if outputs.len() != spec.n_outputs {
            return Err(SysidError::invalid(
                "outputs",
                format!("need one nonlinearity per output ({})", spec.n_outputs),
            ));
        }
        for o in &outputs {
            match o {
                Nonlinearity::Network(n) => {
                    n.check(nz)?;
                    if n.theta.iter().chain(&n.linear).any(|v| !v.is_finite()) {
                        return Err(SysidError::invalid("network", "non-finite parameter"));
                    }
                }
                Nonlinearity::Tree(t) => t.check(nz)?,
            }
        }
        Ok(Self {
            spec,
            shift,
            scale,
            outputs,
        })
    }

    /// Standardises `x` into `z`.
    #[inline]
    pub fn standardise(&self, x: &[f64], z: &mut [f64]) {
        for ((o, v), (s, c)) in z.iter_mut().zip(x).zip(self.shift.iter().zip(&self.scale)) {
            *o = (v - s) / c;
        }
    }

    /// The nonlinearities at given lagged variables `x` (`n x n_vars`, rows in the model's
    /// variable order, engineering units): `n x n_outputs`.
    pub fn evaluate(&self, x: MatRef<'_, f64>) -> Result<Mat<f64>> {
        let nz = self.spec.n_vars();
        if x.ncols() != nz {
            return Err(SysidError::ShapeMismatch {
                what: "regressors".into(),
                expected: format!("(n, {nz})"),
                got: format!("({}, {})", x.nrows(), x.ncols()),
            });
        }
        check_finite("regressors", x)?;
        let (mut xr, mut z) = (vec![0.0; nz], vec![0.0; nz]);
        Ok(Mat::from_fn(x.nrows(), self.outputs.len(), |t, i| {
            for (v, o) in xr.iter_mut().enumerate() {
                *o = x[(t, v)];
            }
            self.standardise(&xr, &mut z);
            self.outputs[i].value(&z)
        }))
    }

    fn step(
        &self,
        t: usize,
        get: impl Fn(Signal, usize, usize) -> f64,
        z: &mut [f64],
        out: &mut [f64],
    ) {
        let mut x = [0.0; 64];
        let nz = z.len();
        let mut heap;
        let xs: &mut [f64] = if nz <= 64 {
            &mut x[..nz]
        } else {
            heap = vec![0.0; nz];
            &mut heap
        };
        self.spec.fill_with(t, xs, get);
        self.standardise(xs, z);
        for (o, f) in out.iter_mut().zip(&self.outputs) {
            *o = f.value(z);
        }
    }

    /// Free-run simulation: the first `max_lag` outputs are `y0` (`max_lag x n_outputs`),
    /// later ones simulated. Fails, naming the sample, when the output blows up.
    pub fn simulate(&self, u: MatRef<'_, f64>, y0: MatRef<'_, f64>) -> Result<Mat<f64>> {
        run::free_run(
            &mut Stepper::new(self),
            u,
            y0,
            "use fewer units or inputs within the range of the estimation data",
        )
    }

    /// `horizon`-step prediction `yhat(t | t - horizon)`: measured outputs up to
    /// `t - horizon`, simulated after. Rows `t < max_lag` repeat the measured output.
    pub fn predict(
        &self,
        u: MatRef<'_, f64>,
        y: MatRef<'_, f64>,
        horizon: usize,
    ) -> Result<Mat<f64>> {
        check_io("u, y", u, y, self.spec.n_inputs, self.spec.n_outputs)?;
        if horizon == 0 {
            return Err(SysidError::invalid("horizon", "must be at least 1"));
        }
        run::k_step(&mut Stepper::new(self), u, y, None, horizon)
    }
}

/// A network NARX model with its standardised-regressor buffer: how its outputs at one
/// sample follow from the lagged values.
struct Stepper<'a> {
    model: &'a NetworkNarx,
    z: Vec<f64>,
}

impl<'a> Stepper<'a> {
    fn new(model: &'a NetworkNarx) -> Self {
        Stepper {
            model,
            z: vec![0.0; model.spec.n_vars()],
        }
    }
}

impl Outputs for Stepper<'_> {
    fn spec(&self) -> &LagSpec {
        &self.model.spec
    }

    fn outputs(
        &mut self,
        t: usize,
        get: impl Fn(Signal, usize, usize) -> f64,
        out: &mut [f64],
    ) -> Result<()> {
        self.model.step(t, get, &mut self.z, out);
        Ok(())
    }
}
