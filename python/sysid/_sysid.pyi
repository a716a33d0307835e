"""Type stubs of the compiled core (``sysid._sysid``); see the Python wrappers for docs.

A core error raises its ``sysid.errors`` class with the attributes ``kind`` (the core
variant's name), ``problem`` and ``remedy`` (see :class:`sysid.errors.SysidError`)."""

from typing import Any, Callable, TypedDict, final

import numpy as np
import numpy.typing as npt

__version__: str
__all__ = [
    "narx_frols",
    "narx_fit",
    "narx_simulate",
    "narx_predict",
    "hw_estimate",
    "hw_simulate",
    "hw_mimo_estimate",
    "hw_mimo_simulate",
    "AUTO_MIN_RELATIVE_PIVOT",
    "channel_stats",
    "arx_fit",
    "iv4",
    "ivx",
    "arx_struc",
    "arx_summary",
    "arx_matrix_filter",
    "arx_marginal_likelihood",
    "arx_regularized_solve",
    "poly_filter",
    "polynomial_pem",
    "polynomial_free_search",
    "stability_insists",
    "polynomial_residuals",
    "initial_condition_name",
    "__version__",
    "HankelFactor",
    "compress",
    "simulate",
    "predict",
    "kalman_gain",
    "fitted_errors",
    "StreamingCompressor",
    "CorrelationSums",
    "feedback_regressions",
    "excitation_order",
    "Subspace",
    "ClosedLoopSubspace",
    "RecursiveFactor",
    "RecursiveEstimator",
    "frd_subspace",
    "spectra_subspace",
    "estimate_bd_x0_records",
    "realize",
    "fir",
    "okid",
    "solve_discrete_lyapunov",
    "gramians",
    "hankel_singular_values",
    "balanced_truncation",
    "modal_analysis",
    "pem_refine",
    "greybox_linear",
    "greybox_frequency",
    "greybox_ode",
    "greybox_ode_simulate",
    "greybox_ode_jacobian",
    "expm_frechet",
    # issue 27 (branch tfproc): transfer functions
    "tf_filtered_gram",
    "tf_fit_frequency",
    # issue 26 (branch pem)
    "pem_criterion",
    "pem_frequency_refine",
    # issue 29 (branch nlss)
    "pnlss_monomials",
    "pnlss_simulate",
    "pnlss_estimate",
    "neural_ss_n_params",
    "neural_ss_simulate",
    "neural_ss_encode",
    "neural_ss_train",
    # issue 27 (branch nlnet): network nonlinearities of nlarx
    "narx_network_fit",
    "narx_tree_fit",
    "narx_network_refine",
    "narx_network_simulate",
    "narx_network_predict",
    "narx_network_evaluate",
    # issue 29 (branch nlss2): decoupled PNLSS
    # issue 31 (branch rules): option names, stabilisation, lagged products from the core
    "option_name",
    "reflect_unstable_poles",
    "lagged_products",
    # issue 29 (branch pnlss): frequency-weighted PNLSS
    "pnlss_estimate_weighted",
]

_Array = npt.NDArray[np.float64]
# an ODE model's (nx, p, free_p, x0, free_x0, typical)
_OdeStructure = tuple[
    int, list[float], list[int], list[list[float]], list[tuple[int, int]], list[float]
]

@final
class HankelFactor:
    """Triangular factor L (k x k, H H^T = L L^T) of a block-Hankel data matrix."""

    @property
    def l(self) -> _Array: ...
    @property
    def n_columns(self) -> int: ...
    @property
    def n_experiments(self) -> int: ...
    @property
    def n_inputs(self) -> int: ...
    @property
    def n_outputs(self) -> int: ...
    @property
    def past(self) -> int: ...
    @property
    def future(self) -> int: ...
    @property
    def source(self) -> str: ...
    @property
    def relative_pivot(self) -> float | None: ...
    def merge(self, other: HankelFactor) -> HankelFactor: ...
    def channel_rms(self) -> tuple[list[float], list[float]]: ...
    def scaled(self, input_scale: list[float], output_scale: list[float]) -> HankelFactor: ...
    @staticmethod
    def from_parts(
        n_inputs: int,
        n_outputs: int,
        past: int,
        future: int,
        l: _Array,
        n_columns: int,
        n_experiments: int,
        source: str = "qr",
        relative_pivot: float | None = None,
    ) -> HankelFactor: ...
    def __reduce__(self) -> Any: ...

AUTO_MIN_RELATIVE_PIVOT: float

def compress(
    experiments: list[tuple[_Array, _Array]],
    past: int,
    future: int,
    chunk_rows: int | None = None,
    compressor: str = "auto",
) -> HankelFactor: ...

def channel_stats(parts: list[_Array]) -> tuple[_Array, _Array, _Array]: ...

def feedback_regressions(
    factor: HankelFactor, rtol: float = 1e-9
) -> tuple[_Array, _Array, int, int, _Array]: ...

def excitation_order(factor: HankelFactor, needed: int, tol: float = 1e-9) -> int: ...

@final
class Subspace:
    def __new__(cls, factor: HankelFactor, method: str) -> Subspace: ...
    @property
    def singular_values(self) -> _Array: ...
    @property
    def max_order(self) -> int: ...
    def auto_order(self) -> int: ...
    def fit(
        self, order: int, feedthrough: bool, kalman: bool, stable: bool, matrices: str = "shift"
    ) -> dict[str, Any]: ...

@final
class ClosedLoopSubspace:
    def __new__(
        cls,
        factor: HankelFactor,
        method: str,
        regularization: str = "none",
        ridge: float = 1e-3,
        feedthrough: bool = False,
    ) -> ClosedLoopSubspace: ...
    @property
    def singular_values(self) -> _Array: ...
    @property
    def max_order(self) -> int: ...
    def auto_order(self) -> int: ...
    def fit(self, order: int) -> dict[str, Any]: ...

@final
class RecursiveFactor:
    def __new__(
        cls, n_inputs: int, n_outputs: int, past: int, future: int, forgetting: float = 1.0
    ) -> RecursiveFactor: ...
    def update(self, u: _Array, y: _Array) -> None: ...
    def factor(self) -> HankelFactor: ...
    @property
    def n_columns(self) -> int: ...
    @property
    def effective_columns(self) -> float: ...

def frd_subspace(
    omega: _Array,
    g_re: _Array,
    g_im: _Array,
    n_outputs: int,
    horizon: int,
    order: int | None = None,
    weights: _Array | None = None,
    feedthrough: str = "zero",
) -> dict[str, Any]: ...
def spectra_subspace(
    omega: _Array,
    u_re: _Array,
    u_im: _Array,
    y_re: _Array,
    y_im: _Array,
    horizon: int,
    order: int | None = None,
    weights: _Array | None = None,
    transient: bool = True,
    feedthrough: str = "zero",
) -> dict[str, Any]: ...
def estimate_bd_x0_records(
    a: _Array, c: _Array, us: list[_Array], ys: list[_Array], feedthrough: bool
) -> tuple[_Array, _Array, list[_Array]]: ...
def simulate(
    a: _Array, b: _Array, c: _Array, d: _Array, u: _Array, x0: _Array | None = None
) -> _Array: ...
def predict(
    a: _Array,
    b: _Array,
    c: _Array,
    d: _Array,
    k: _Array,
    u: _Array,
    y: _Array,
    x0: _Array | None = None,
    horizon: int = 1,
) -> _Array: ...
def kalman_gain(
    a: _Array, c: _Array, q: _Array, r: _Array, s: _Array
) -> tuple[_Array, _Array, _Array]: ...
def fitted_errors(
    a: _Array,
    c: _Array,
    y: _Array,
    ys: _Array,
    trend: bool = False,
    prior: _Array | None = None,
) -> _Array | None: ...

# -- realisation, Markov parameters, balancing, modal analysis (crates/sysid-py/src/realization.rs)
def realize(
    method: str,
    markov: _Array,
    noutputs: int,
    order: int | None = None,
    rows: int | None = None,
    cols: int | None = None,
    rank_tol: float = 1e-8,
    max_order: int | None = None,
) -> dict[str, Any]: ...
def fir(
    experiments: list[tuple[_Array, _Array]],
    length: int,
    feedthrough: bool = False,
    regularization: str = "tc",
    hyper: tuple[float, float] | None = None,
) -> dict[str, Any]: ...
def okid(
    experiments: list[tuple[_Array, _Array]],
    observer_order: int,
    count: int,
    feedthrough: bool = False,
    check_direct: bool = False,
) -> dict[str, Any]: ...
def solve_discrete_lyapunov(a: _Array, q: _Array) -> _Array: ...
def gramians(a: _Array, b: _Array, c: _Array, d: _Array) -> tuple[_Array, _Array]: ...
def hankel_singular_values(a: _Array, b: _Array, c: _Array, d: _Array) -> _Array: ...
def balanced_truncation(
    a: _Array, b: _Array, c: _Array, d: _Array, order: int | None = None
) -> dict[str, Any]: ...
def modal_analysis(a: _Array, c: _Array, dt: float) -> dict[str, Any]: ...

@final
class StreamingCompressor:
    def __new__(
        cls,
        n_inputs: int,
        n_outputs: int,
        past: int,
        future: int,
        compressor: str = "qr",
        chunk_rows: int | None = None,
        longest: int | None = None,
    ) -> StreamingCompressor: ...
    def push(self, u: _Array, y: _Array) -> None: ...
    def end_experiment(self) -> None: ...
    def finish(self) -> HankelFactor: ...
    @property
    def samples(self) -> int: ...
    @property
    def compressor(self) -> str: ...

@final
class CorrelationSums:
    def __new__(
        cls,
        n_inputs: int,
        n_outputs: int,
        past: int,
        future: int,
        center: _Array,
        scale: _Array,
        longest: int | None = None,
    ) -> CorrelationSums: ...
    @staticmethod
    def center_scale(u: _Array, y: _Array) -> tuple[_Array, _Array]: ...
    def push(self, u: _Array, y: _Array) -> None: ...
    def end_experiment(self) -> None: ...
    def merge(self, other: CorrelationSums) -> CorrelationSums: ...
    def to_factor(self, min_relative_pivot: float = 1e-10) -> HankelFactor: ...
    @property
    def n_columns(self) -> int: ...
    @property
    def n_experiments(self) -> int: ...
    @property
    def open_samples(self) -> int: ...
    def __reduce__(self) -> Any: ...

def pem_refine(
    a: _Array,
    b: _Array,
    c: _Array,
    d: _Array,
    k: _Array | None,
    experiments: list[tuple[_Array, _Array]],
    *,
    focus: str = "prediction",
    estimate_d: bool = False,
    estimate_k: bool = True,
    x0: list[Any] | None = None,
    reweight: bool = True,
    local_coordinates: bool = True,
    enforce_stability: bool | None = None,
    max_iter: int = 50,
    tol_cost: float = 1e-6,
    tol_step: float = 1e-9,
    tol_gradient: float = 1e-9,
    reg_lambda: float = 0.0,
    reg_r: _Array | None = None,
    reg_nominal: _Array | None = None,
    progress: Any = None,
    geodesic: bool = False,
) -> dict[str, Any]: ...
def pem_frequency_refine(
    a: _Array,
    b: _Array,
    c: _Array,
    d: _Array,
    omega: _Array,
    re: _Array,
    im: _Array,
    weight: _Array,
    *,
    estimate_d: bool = False,
    modal_chart: bool = True,
    max_iter: int = 50,
    tol_cost: float = 1e-6,
    progress: Any = None,
) -> dict[str, Any]: ...
# grey-box models (issue 12)
def greybox_linear(
    dims: tuple[int, int, int],
    experiments: list[tuple[_Array, _Array]],
    structure: Any,
    p0: list[float],
    *,
    focus: str = "prediction",
    with_k: bool = False,
    reweight: bool = True,
    x0_params: list[int] = ...,
    search: dict[str, Any] | None = None,
    progress: Any = None,
    unbounded: bool = False,
) -> dict[str, Any]: ...
def stability_insists(
    kept: float, free: float, n: int, l: int = 1, det: bool = False
) -> tuple[float, bool]: ...
def greybox_frequency(
    dims: tuple[int, int, int],
    omega: _Array,
    re: _Array,
    im: _Array,
    weight: _Array,
    structure: Any,
    p0: list[float],
    *,
    search: dict[str, Any] | None = None,
    progress: Any = None,
) -> dict[str, Any]: ...
def greybox_ode(
    f: Any,
    h: Any,
    experiments: list[tuple[_Array, _Array]],
    structure: _OdeStructure,
    dt: float,
    *,
    reweight: bool = True,
    integration: dict[str, Any] | None = None,
    jacobian: dict[str, Any] | None = None,
    search: dict[str, Any] | None = None,
    progress: Any = None,
) -> dict[str, Any]: ...
def greybox_ode_simulate(
    f: Any,
    h: Any,
    u: _Array,
    nx: int,
    p: list[float],
    x0: list[float],
    dt: float,
    *,
    integration: dict[str, Any] | None = None,
) -> _Array: ...
def greybox_ode_jacobian(
    f: Any,
    h: Any,
    inputs: list[_Array],
    structure: _OdeStructure,
    dt: float,
    *,
    integration: dict[str, Any] | None = None,
    jacobian: dict[str, Any] | None = None,
) -> tuple[_Array, _Array]: ...
def expm_frechet(x: _Array, dirs: list[_Array]) -> tuple[_Array, list[_Array]]: ...

# polynomial models (issue 13)
def arx_fit(
    experiments: list[tuple[_Array, _Array]],
    na: list[list[int]],
    nb: list[list[int]],
    nk: list[list[int]],
    lam: float = 0.0,
    reg_factor: _Array | None = None,
) -> list[dict[str, Any]]: ...
def arx_struc(
    experiments: list[tuple[_Array, _Array]],
    na_range: list[int],
    nb_range: list[int],
    nk_range: list[int],
) -> _Array: ...
def arx_summary(
    experiments: list[tuple[_Array, _Array]],
    na: list[list[int]],
    nb: list[list[int]],
    nk: list[list[int]],
) -> list[tuple[_Array, int]]: ...
def arx_matrix_filter(
    a: list[list[list[float]]],
    w: _Array,
    y: _Array | None = None,
    horizon: int = 1,
) -> _Array: ...
def arx_marginal_likelihood(
    summary: _Array,
    n_rows: int,
    prior: _Array,
    dprior: list[_Array],
    sigma2: float,
    gradient: bool = True,
) -> tuple[float, list[float], float]: ...
def arx_regularized_solve(
    summary: _Array, prior: _Array, lam: float
) -> tuple[_Array, _Array, float]: ...
def poly_filter(b: list[float], a: list[float], x: _Array) -> _Array: ...
def polynomial_pem(
    experiments: list[tuple[_Array, _Array]],
    na: int,
    nb: list[int],
    nc: int,
    nd: int,
    nf: list[int],
    nk: list[int],
    theta0: list[float] | None = None,
    max_iter: int = 100,
    tol: float = 1e-9,
    progress: Callable[..., Any] | None = None,
    initial_condition: str = "zero",
) -> dict[str, Any]: ...
def polynomial_residuals(
    experiments: list[tuple[_Array, _Array]],
    na: int,
    nb: list[int],
    nc: int,
    nd: int,
    nf: list[int],
    nk: list[int],
    theta: list[float] | _Array,
    initial_condition: str = "zero",
) -> tuple[_Array, list[dict[str, Any]]]: ...
def polynomial_free_search(
    experiments: list[tuple[_Array, _Array]],
    na: int,
    nb: list[int],
    nc: int,
    nd: int,
    nf: list[int],
    nk: list[int],
    theta: list[float],
    initial_condition: str = "zero",
    max_iter: int = 100,
    tol: float = 1e-9,
) -> dict[str, Any]: ...
def initial_condition_name(name: str) -> str: ...
def iv4(
    experiments: list[tuple[_Array, _Array, _Array | None]],
    na: list[list[int]],
    nb: list[list[int]],
    nk: list[list[int]],
) -> list[dict[str, Any]]: ...
def ivx(
    experiments: list[tuple[_Array, _Array, _Array | None]],
    x: list[_Array],
    na: list[list[int]],
    nb: list[list[int]],
    nk: list[list[int]],
) -> list[dict[str, Any]]: ...
# nonlinear models (issue 14)
_Orders = tuple[list[int], list[int], list[int], list[int]]
_Rbf = tuple[_Array, _Array, _Array, _Array]

class _NarxStructure(TypedDict, total=False):
    """The model structure the narx_* functions share (only ``orders`` is required)."""

    orders: _Orders
    degree: int | None
    rbf: _Rbf | None
    custom_args: list[list[tuple[int, int, int]]]

_Equations = list[tuple[list[list[int]], list[float]]]
def narx_frols(
    experiments: list[tuple[_Array, _Array, _Array | None]],
    structure: _NarxStructure,
    max_terms: int,
    forced: list[list[list[int]]],
    err_tol: float = 1e-10,
    block_rows: int = 0,
    custom_values: list[_Array] = ...,
) -> tuple[list[dict[str, Any]], int]: ...
def narx_fit(
    experiments: list[tuple[_Array, _Array, _Array | None]],
    structure: _NarxStructure,
    terms: list[list[list[int]]],
    custom_values: list[_Array] = ...,
) -> list[_Array]: ...
def narx_simulate(
    structure: _NarxStructure,
    equations: _Equations,
    u: _Array,
    y0: _Array,
    custom_fns: list[Callable[..., float]] = ...,
) -> _Array: ...
def narx_predict(
    structure: _NarxStructure,
    equations: _Equations,
    u: _Array,
    y: _Array,
    horizon: int,
    custom_fns: list[Callable[..., float]] = ...,
) -> _Array: ...
# hw_estimate / hw_mimo_estimate: theta, cost, history, iterations, stop, noise_variance and
# covariance (the model parameters' marginal Gauss-Newton one; None where not finite)
def hw_estimate(
    records: list[tuple[_Array, _Array]],
    input: tuple[str, int, list[float]],
    output: tuple[str, int, list[float]],
    nb: int,
    nf: int,
    nk: int,
    theta0: list[float],
    max_iter: int = 100,
    tol: float = 1e-10,
    progress: Callable[..., Any] | None = None,
    offset: bool = False,
    initial_state: bool = False,
) -> dict[str, Any]: ...
def hw_simulate(
    input: tuple[str, int, list[float]],
    output: tuple[str, int, list[float]],
    nb: int,
    nf: int,
    nk: int,
    theta: list[float],
    u: _Array,
) -> tuple[_Array, _Array, _Array]: ...
def hw_mimo_estimate(
    records: list[tuple[_Array, _Array]],
    inputs: list[tuple[str, int, list[float]]],
    outputs: list[tuple[str, int, list[float]]],
    order: int,
    feedthrough: bool,
    theta0: list[float],
    max_iter: int = 100,
    tol: float = 1e-10,
    progress: Callable[..., Any] | None = None,
    offsets: bool = False,
    initial_state: bool = False,
) -> dict[str, Any]: ...
def hw_mimo_simulate(
    inputs: list[tuple[str, int, list[float]]],
    outputs: list[tuple[str, int, list[float]]],
    order: int,
    feedthrough: bool,
    theta: list[float],
    u: _Array,
    x0: list[float] | None = None,
) -> _Array: ...

# issue 27 (branch tfproc): transfer functions
def tf_filtered_gram(
    ad: _Array, bd: _Array, cw: _Array, dw: _Array, v: _Array, skip: int = 0
) -> _Array: ...
def tf_fit_frequency(
    x: tuple[_Array, _Array],
    w: tuple[_Array, _Array],
    h: tuple[_Array, _Array],
    weight: list[float],
    lead: int,
    den: list[int],
    num: list[int],
    theta0: list[float],
    *,
    fixed: list[bool] | None = None,
    lower: list[float] | None = None,
    upper: list[float] | None = None,
    noise_variance: float | None = None,
    max_iter: int = 100,
    tol: float = 1e-10,
    progress: Callable[..., Any] | None = None,
    stable: bool = False,
) -> dict[str, Any]: ...
# issue 26 (branch pem): the cheap criterion of a model
def pem_criterion(
    a: _Array,
    b: _Array,
    c: _Array,
    d: _Array,
    k: _Array | None,
    experiments: list[tuple[_Array, _Array]],
    *,
    focus: str = "prediction",
    estimate_d: bool = False,
    estimate_k: bool = True,
    x0: list[Any] | None = None,
    reweight: bool = True,
    enforce_stability: bool | None = None,
) -> float: ...
# issue 29 (branch nlss): PNLSS and neural state space
def pnlss_monomials(nx: int, nu: int, terms: str, degrees: list[int]) -> list[list[int]]: ...
_Range = tuple[list[float], list[float]]
_Records = list[tuple[_Array, _Array, int]]

class _PnlssStructure(TypedDict, total=False):
    """A PNLSS structure (all but ``range`` required)."""

    nx: int
    nu: int
    ny: int
    zeta: list[list[int]]
    eta: list[list[int]]
    range: _Range | None

class _DecoupledStructure(TypedDict, total=False):
    """A decoupled PNLSS structure (all but ``range`` required)."""

    dims: tuple[int, int, int]
    branches: int
    degrees: list[int]
    range: _Range | None

_PolyStructure = _PnlssStructure | _DecoupledStructure

def pnlss_simulate(
    structure: _PolyStructure, theta: list[float], u: _Array, x0: list[float] | None = None
) -> tuple[_Array, _Array]: ...
def pnlss_estimate(
    structure: _PolyStructure,
    records: _Records,
    theta0: _Array,
    max_iter: int = 100,
    tol: float = 1e-8,
    fixed: list[bool] | None = None,
    progress: Callable[..., Any] | None = None,
    iterates: bool = False,
    significance: float = 0.0,
) -> dict[str, Any]: ...
def pnlss_estimate_weighted(
    structure: _PolyStructure,
    records: _Records,
    weights: list[tuple[int, list[int], list[float]]],
    theta0: _Array,
    max_iter: int = 100,
    tol: float = 1e-8,
    progress: Callable[..., Any] | None = None,
    iterates: bool = False,
) -> dict[str, Any]: ...

class _NeuralStructure(TypedDict, total=False):
    """A neural state-space structure (all but ``g_hidden`` required)."""

    dims: tuple[int, int, int]
    f_hidden: list[int]
    g_hidden: list[int] | None
    h_hidden: list[int]
    lags: int

def neural_ss_simulate(
    structure: _NeuralStructure, params: _Array, u: _Array, x0: list[float]
) -> _Array: ...
def neural_ss_encode(
    structure: _NeuralStructure, params: _Array, u: _Array, y: _Array, t: int
) -> _Array: ...
def neural_ss_train(
    structure: _NeuralStructure,
    params0: _Array,
    train: _Records,
    val: _Records,
    epochs: int = 200,
    batch: int = 16,
    horizon: int = 100,
    learning_rate: float = 1e-3,
    patience: int = 20,
    seed: int = 0,
    progress: Callable[..., Any] | None = None,
    rates: _Array | None = None,
    penalty: _Array | None = None,
) -> dict[str, Any]: ...
def neural_ss_n_params(structure: _NeuralStructure) -> int: ...
# issue 27 (branch tsonline): online estimators
@final
class RecursiveEstimator:
    def __new__(
        cls,
        na: int,
        nb: list[int],
        nc: int,
        nd: int,
        nf: list[int],
        nk: list[int],
        method: str = "forgetting",
        forgetting: float = 1.0,
        process_noise: _Array | None = None,
        noise_variance: float = 1.0,
        gain: float = 1.0,
        bias: float = ...,
        theta0: _Array | None = None,
        p0: float = 1e4,
        startup_forgetting: bool = True,
    ) -> RecursiveEstimator: ...
    def step(self, u: list[float], y: float) -> float: ...
    def run(
        self, u: _Array, y: _Array, store_parameters: bool = False
    ) -> tuple[_Array, _Array | None]: ...
    @property
    def parameters(self) -> _Array: ...
    def set_parameters(self, theta: _Array) -> None: ...
    @property
    def covariance(self) -> _Array: ...
    def set_covariance(self, p: _Array) -> None: ...
    @property
    def regressor(self) -> _Array: ...
    @property
    def samples(self) -> int: ...
    @property
    def rejected(self) -> int: ...
    @property
    def n_parameters(self) -> int: ...
    def reset_history(self) -> None: ...
    def copy(self) -> RecursiveEstimator: ...

# issue 27 (branch nlnet): network nonlinearities of nlarx
_Nl = tuple[Any, ...]
_Orders3 = tuple[list[int], list[int], list[int]]

class _NetworkStructure(TypedDict, total=False):
    """The structure the narx_network_* functions share (``outputs`` absent while fitting)."""

    orders: _Orders3
    shift: list[float]
    scale: list[float]
    outputs: list[_Nl]

def narx_network_fit(
    experiments: list[tuple[_Array, _Array]],
    structure: _NetworkStructure,
    output: int,
    kinds: list[int],
    theta0: list[float],
    max_iter: int = 100,
    tol: float = 1e-7,
    progress: Callable[..., Any] | None = None,
    bounds: _Range | None = None,
) -> tuple[_Nl, dict[str, Any]]: ...
def narx_tree_fit(
    experiments: list[tuple[_Array, _Array]],
    structure: _NetworkStructure,
    output: int,
    max_leaves: int = 16,
    min_leaf: int = 0,
) -> tuple[_Nl, dict[str, Any]]: ...
def narx_network_refine(
    experiments: list[tuple[_Array, _Array]],
    structure: _NetworkStructure,
    max_iter: int = 100,
    tol: float = 1e-7,
    progress: Callable[..., Any] | None = None,
    bounds: _Range | None = None,
) -> tuple[list[_Nl], dict[str, Any]]: ...
def narx_network_simulate(structure: _NetworkStructure, u: _Array, y0: _Array) -> _Array: ...
def narx_network_predict(
    structure: _NetworkStructure, u: _Array, y: _Array, horizon: int
) -> _Array: ...
def narx_network_evaluate(structure: _NetworkStructure, x: _Array) -> _Array: ...
# issue 31 (branch rules): option names, stabilisation, lagged products from the core
def option_name(option: str, value: str) -> str: ...
def reflect_unstable_poles(a: _Array, shrink: float = 0.99) -> _Array: ...
def lagged_products(parts: list[_Array], max_lag: int) -> _Array: ...
