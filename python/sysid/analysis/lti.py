"""Model analysis: zeros, damping, controllability, responses, time-domain conversions.

Everything here works on the small matrices of a model (no pass over data), with NumPy and
SciPy. Discrete-time models are :class:`~sysid.StateSpaceModel`; continuous-time ones are
:class:`ContinuousStateSpace`, obtained with :func:`d2c` and turned back with :func:`c2d`.

Conventions
-----------
- Frequencies of discrete poles use the continuous equivalent ``s = log(p) / dt``: natural
  frequency ``|s|``, damping ``-cos(angle(s))``, damped frequency ``|Im s| = |angle(p)| / dt``.
- ``c2d``/``d2c`` with ``method="tustin"`` use SciPy's realisation of the bilinear transform
  (``scipy.signal.cont2discrete(..., method="bilinear")``, the one python-control uses), so
  the matrices agree with both, not only the transfer functions.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_matrix, as_nonnegative
from ..errors import DataError, ShapeError
from ..models.checks import _optional, check_model, check_start
from ..models.continuous import ContinuousStateSpace, c2d, d2c
from ..models.linear import DampingTable, damping, transmission_zeros
from ..models.protocol import TimeResponse
from ..models.statespace import StateSpaceModel
from .controllability import ctrb, is_controllable, is_observable, obsv  # noqa: F401 (moved)

__all__ = [
    "ContinuousStateSpace",
    "DampingTable",
    "TimeResponse",
    "zeros",
    "damp",
    "ctrb",
    "obsv",
    "is_controllable",
    "is_observable",
    "step",
    "impulse",
    "c2d",
    "d2c",
    "to_control",
    "from_control",
    "to_scipy",
    "from_scipy",
]


# -- zeros, damping (computed in sysid.models.linear) ------------------------------------
def zeros(model: Any, tol: float = 1e-6) -> np.ndarray:
    """Transmission zeros of any model: :func:`~sysid.models.linear.transmission_zeros` of
    its state-space matrices, else its own ``zeros()`` (or that of ``to_statespace()``).

    ``[[A - z I, B], [C, D]]`` loses rank at a zero; non-square systems are squared down
    twice at random and the common zeros kept, within ``tol`` relative.

    Returns
    -------
    ndarray
        Complex zeros (discrete ``z`` or continuous ``s``), sorted by modulus.

    Examples
    --------
    >>> import sysid
    >>> m = sysid.StateSpaceModel([[0.5, 0.0], [0.0, 0.2]], [[1.0], [1.0]], [[1.0, 1.0]])
    >>> sysid.zeros(m)
    array([0.35+0.j])
    """
    tol = as_nonnegative(tol, "tol")
    if all(hasattr(model, k) for k in ("A", "B", "C", "D")):
        return transmission_zeros(model.A, model.B, model.C, model.D, tol)
    return np.asarray(_optional(model, "zeros", "zeros"))


def damp(model: Any, std: bool = False) -> DampingTable:
    """Natural frequencies (rad/s and Hz), damping ratios and time constants of the poles.

    Works on any model with ``poles()`` (or ``to_statespace()``). Discrete poles are mapped
    through ``s = log(z) / dt``; a pole at ``z = 0`` gets ``s = -inf`` (infinitely fast,
    damping 1); a continuous model (``dt == 0``) keeps its poles.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> dt = 0.01
    >>> p = np.exp(dt * (-1.0 + 10.0j))
    >>> A = [[p.real, -p.imag], [p.imag, p.real]]
    >>> table = sysid.damp(sysid.StateSpaceModel(A, [[1.0], [0.0]], [[1.0, 0.0]], dt=dt))
    >>> np.round(table.wd, 6)
    array([10., 10.])
    >>> np.round(table.zeta, 4)
    array([0.0995, 0.0995])
    """
    model = check_model(model)
    check_start(model, None, "damp", role="model")
    return damping(model, std)


# -- time responses ---------------------------------------------------------------------
def step(model: Any, n_samples: int | None = None, std: bool = False) -> TimeResponse:
    """Response to a unit step on each input (from rest) of any model: ``model.step``.

    Discrete models simulate ``n_samples`` samples (default: until the slowest pole has
    decayed to 1 %); a :class:`ContinuousStateSpace` is sampled exactly (see its
    :meth:`~ContinuousStateSpace.step`). With ``std=True`` (a model with ``uncertainty``)
    ``resp.std`` holds the first-order standard deviation of each sample, drawn as a 95 %
    band by ``resp.plot()``.

    Examples
    --------
    >>> import sysid
    >>> r = sysid.step(sysid.StateSpaceModel([[0.5]], [[0.5]], [[1.0]]), 4)
    >>> r.y[:, 0, 0]
    array([0.   , 0.5  , 0.75 , 0.875])
    """
    resp = _response(model, "step", n_samples)
    if std:
        from ..models.uncertainty import response_band

        return response_band(model, resp, step)
    return resp


def impulse(model: Any, n_samples: int | None = None, std: bool = False) -> TimeResponse:
    """Response to a unit pulse ``u(0) = 1`` on each input: the Markov parameters. With
    ``std=True`` (a model with ``uncertainty``) ``resp.std`` holds the first-order standard
    deviation of each sample, drawn as a 95 % band by ``resp.plot()`` (as :func:`step`).

    Examples
    --------
    >>> import sysid
    >>> sysid.impulse(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), 3).y[:, 0, 0]
    array([0. , 1. , 0.5])
    """
    resp = _response(model, "impulse", n_samples)
    if std:
        from ..models.uncertainty import response_band

        return response_band(model, resp, impulse)
    return resp


def _response(model: Any, kind: str, n_samples: int | None) -> TimeResponse:
    model = check_model(model)
    fn = getattr(model, kind, None)
    if fn is None:
        from ..models.protocol import sampled_response

        return sampled_response(model, kind, n_samples)
    return fn(n_samples)  # type: ignore[no-any-return]


# -- other libraries --------------------------------------------------------------------
def _control() -> Any:
    try:
        import control
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("this conversion needs python-control: pip install control") from e
    return control


def to_control(model: StateSpaceModel | ContinuousStateSpace, *, noise: bool = False) -> Any:
    """A ``control.StateSpace`` (discrete with ``dt``, or continuous).

    By default the deterministic part ``(A, B, C, D)``: ``K`` is dropped. With
    ``noise=True`` the noise-augmented system of the innovation form, inputs ``[u, e]``:
    ``x(t+1) = A x + [B K] [u; e]``, ``y = C x + [D I] [u; e]`` (the innovation channels are
    named ``e:<output>``); a model without ``K`` raises :class:`~sysid.DataError`.

    Needs python-control (optional; the examples are skipped by the doctest run, the
    conversions are tested against it in ``tests/test_analysis.py`` when it is installed).

    Examples
    --------
    >>> import sysid
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], K=[[0.3]], dt=0.1)
    >>> sysid.to_control(m).dt  # doctest: +SKIP
    0.1
    >>> sysid.to_control(m, noise=True).ninputs  # doctest: +SKIP
    2
    """
    if not isinstance(model, (StateSpaceModel, ContinuousStateSpace)):
        if hasattr(model, "statespace") or not hasattr(model, "to_statespace"):
            hint = (" (for sysid.identify's model: res.model.statespace, the model of the "
                    "deviations from its offsets)" if hasattr(model, "statespace") else "")
            raise DataError(f"to_control needs a sysid.StateSpaceModel or "
                            f"ContinuousStateSpace, got {type(model).__name__}{hint}")
        from ..models.checks import as_statespace

        model = as_statespace(model, "to_control")  # transfer functions, polynomial models
    ct = _control()
    dt = model.dt if isinstance(model, StateSpaceModel) else 0
    B, D, inputs = model.B, model.D, list(model.input_names)
    if noise:
        K = getattr(model, "K", None)
        if K is None:
            raise DataError("noise=True needs a model with a Kalman gain K (an innovation "
                            "form, e.g. fit(..., kalman=True)); this model has none")
        B = np.hstack([B, K])
        D = np.hstack([D, np.eye(model.noutputs)])
        inputs += [f"e:{n}" for n in model.output_names]
    return ct.ss(model.A, B, model.C, D, dt, inputs=inputs, outputs=list(model.output_names))


def _from_matrices(A: Any, B: Any, C: Any, D: Any, dt: Any, names: tuple[Any, Any]) -> Any:
    D = np.atleast_2d(np.asarray(D, dtype=float))
    A = np.asarray(A, dtype=float)
    A = as_matrix(A if A.size else np.zeros((0, 0)), "A", (None, None))
    n = A.shape[0]
    B = np.asarray(B, dtype=float).reshape(n, D.shape[1])
    C = np.asarray(C, dtype=float).reshape(D.shape[0], n)
    if n and not np.any(B) and not np.any(C):
        # a static gain as SciPy writes it: one state that neither input nor output touches
        A, B, C = np.zeros((0, 0)), np.zeros((0, D.shape[1])), np.zeros((D.shape[0], 0))
    if dt is None or dt is True or dt == 0:
        if dt is True:
            raise DataError("the system is discrete with an unspecified sample time; set dt")
        return ContinuousStateSpace(A, B, C, D, input_names=names[0], output_names=names[1])
    return StateSpaceModel(A, B, C, D, dt=float(dt), input_names=names[0], output_names=names[1])


def from_control(sys: Any) -> StateSpaceModel | ContinuousStateSpace:
    """Convert a ``control.StateSpace`` (or transfer function) to a sysid model.

    Examples
    --------
    >>> import control, sysid  # doctest: +SKIP
    >>> sysid.from_control(control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], 0.1))  # doctest: +SKIP
    StateSpaceModel(nstates=1, ninputs=1, noutputs=1, dt=0.1, stable, no noise model)
    """
    ct = _control()
    if not isinstance(sys, ct.StateSpace):
        sys = ct.ss(sys)
    names = (getattr(sys, "input_labels", None), getattr(sys, "output_labels", None))
    return _from_matrices(sys.A, sys.B, sys.C, sys.D, sys.dt, names)


def to_scipy(model: Any) -> Any:
    """A ``scipy.signal.StateSpace`` (with ``dt`` for a discrete model); any other model
    goes through its ``to_statespace()`` (a delayed continuous transfer function needs
    ``model.to_statespace(dt)`` first).

    Examples
    --------
    >>> import sysid
    >>> sysid.to_scipy(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1)).dt
    0.1
    """
    import scipy.signal

    from ..models.checks import as_statespace

    if not isinstance(model, (StateSpaceModel, ContinuousStateSpace)):
        model = as_statespace(model, "to_scipy")
    if model.dt:
        return scipy.signal.StateSpace(model.A, model.B, model.C, model.D, dt=model.dt)
    return scipy.signal.StateSpace(model.A, model.B, model.C, model.D)


def from_scipy(sys: Any) -> StateSpaceModel | ContinuousStateSpace:
    """Convert a ``scipy.signal`` LTI object (state space, transfer function, zpk).

    Examples
    --------
    >>> import scipy.signal, sysid
    >>> sysid.from_scipy(scipy.signal.StateSpace([[-1.0]], [[1.0]], [[1.0]], [[0.0]]))
    ContinuousStateSpace(nstates=1, ninputs=1, noutputs=1, stable)
    """
    import scipy.signal

    if not isinstance(sys, scipy.signal.lti) and not isinstance(sys, scipy.signal.dlti):
        raise ShapeError(f"expected a scipy.signal LTI object, got {type(sys).__name__}")
    ss = sys.to_ss()
    return _from_matrices(ss.A, ss.B, ss.C, ss.D, getattr(ss, "dt", None), (None, None))
