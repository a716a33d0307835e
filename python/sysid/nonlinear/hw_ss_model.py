"""MIMO Hammerstein-Wiener models with a state-space linear block.

``w_j = f_j(u_j)`` per input, ``x(t+1) = A x(t) + B w(t)``, ``v = C x + D w``, ``y_i = g_i(v_i)``
per output; simulation (from rest) and the estimator's sensitivities run in Rust
(``sysid-core``, ``hw/mimo.rs``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_2d, as_matrix
from .._measured import as_horizon, as_measured, predict_args
from ..errors import DataError, ShapeError
from ..models.protocol import ModelMixin
from .hw_model import (
    Nonlinearity,
    UserFunction,
    linear_with_std,
    nonlinearity_from_dict,
    uncertainty_lines,
    with_linear_uncertainty,
)

__all__ = ["HammersteinWienerSSModel"]


class HammersteinWienerSSModel(ModelMixin):
    """Hammerstein-Wiener model with per-channel static nonlinearities around a (MIMO)
    state-space linear block.

    Parameters
    ----------
    input_nls, output_nls : list of Nonlinearity
        One per input and one per output (``Nonlinearity()`` is the identity).
    A, B, C : array_like
        The linear block (``n x n``, ``n x m``, ``p x n``).
    D : array_like, optional
        Direct term ``p x m``; ``None``: no feedthrough (``D = 0``, not estimated).
    dt : float
        Sample time.
    u_offset, y_offset : array_like, optional
        The operating point (``m`` and ``p`` values): the model maps ``u - u_offset`` and
        adds ``y_offset`` to its outputs (:mod:`sysid.nonlinear.operating_point`; zero by
        default).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> sat = sysid.Saturation(); sat.params = np.array([-0.5, 0.5])
    >>> m = sysid.HammersteinWienerSSModel([sat], [sysid.Nonlinearity()], [[0.8]], [[0.5]],
    ...                                   [[1.0]], dt=1.0)
    >>> np.round(m.simulate(np.ones(4)).ravel(), 6).tolist()
    [0.0, 0.25, 0.45, 0.61]
    >>> np.round(m.poles().real, 6).tolist()
    [0.8]
    """

    def __init__(self, input_nls: Any, output_nls: Any, A: Any, B: Any, C: Any, D: Any = None,
                 dt: float = 1.0, *, noise_variance: Any = None,
                 info: dict[str, Any] | None = None, input_names: Any = None,
                 output_names: Any = None, u_offset: Any = None,
                 y_offset: Any = None) -> None:
        self.input_nls = list(input_nls)
        self.output_nls = list(output_nls)
        m_, p_ = len(self.input_nls), len(self.output_nls)
        self.u_offset = np.zeros(m_) if u_offset is None else np.broadcast_to(
            np.asarray(u_offset, float), (m_,)).copy()
        self.y_offset = np.zeros(p_) if y_offset is None else np.broadcast_to(
            np.asarray(y_offset, float), (p_,)).copy()
        if not (np.all(np.isfinite(self.u_offset)) and np.all(np.isfinite(self.y_offset))):
            raise DataError("u_offset and y_offset must be finite")
        self.A = np.atleast_2d(np.asarray(A, float))
        self.B = np.atleast_2d(np.asarray(B, float))
        self.C = np.atleast_2d(np.asarray(C, float))
        n, m, p = self.A.shape[0], len(self.input_nls), len(self.output_nls)
        self.feedthrough = D is not None
        self.D = np.zeros((p, m)) if D is None else np.atleast_2d(np.asarray(D, float))
        if (self.A.shape != (n, n) or self.B.shape != (n, m) or self.C.shape != (p, n)
                or self.D.shape != (p, m)):
            raise DataError(f"A, B, C, D must be ({n}, {n}), ({n}, {m}), ({p}, {n}), "
                            f"({p}, {m}) for {m} input and {p} output nonlinearities; got "
                            f"{self.A.shape}, {self.B.shape}, {self.C.shape}, {self.D.shape}")
        for nl in self.input_nls + self.output_nls:
            if not isinstance(nl, Nonlinearity):
                raise DataError(f"nonlinearities must be sysid nonlinearities, got {nl!r}")
        if any(isinstance(g, UserFunction) for g in self.output_nls):
            raise DataError("a UserFunction can only be an input nonlinearity")
        self.dt = float(dt)
        self.noise_variance = (np.ones(p) if noise_variance is None
                               else np.broadcast_to(np.asarray(noise_variance, float), (p,)))
        self.info: dict[str, Any] = dict(info or {})
        self.input_names = ([f"u{j}" for j in range(m)] if input_names is None
                            else [str(s) for s in input_names])
        self.output_names = ([f"y{i}" for i in range(p)] if output_names is None
                             else [str(s) for s in output_names])

    ninputs = property(lambda self: len(self.input_nls), doc="Number of inputs.")
    noutputs = property(lambda self: len(self.output_nls), doc="Number of outputs.")
    order = property(lambda self: int(self.A.shape[0]), doc="State dimension.")
    nstates = property(lambda self: int(self.A.shape[0]),
                       doc="State dimension (the linear block's).")
    #: ``simulate`` takes the linear block's initial state: :func:`sysid.compare` fits it
    #: (``x0="estimate"``), by Gauss-Newton since the output is not affine in it
    initial_state_fits = True
    statespace_is_exact = False

    @property
    def theta(self) -> np.ndarray:
        """Parameters in the estimator's order: input nonlinearities, ``A``, ``B``, ``C``,
        (``D``), output nonlinearities (matrices row-major)."""
        parts = [f.params for f in self.input_nls] + [self.A.ravel(), self.B.ravel(),
                                                      self.C.ravel()]
        if self.feedthrough:
            parts.append(self.D.ravel())
        parts += [g.params for g in self.output_nls]
        return np.concatenate([np.asarray(v, float).ravel() for v in parts])

    @property
    def n_parameters(self) -> int:
        """Number of parameters (the state-space part is not unique: similarity transforms
        leave ``n^2`` directions free), the output levels included when estimated."""
        levels = bool(dict(self.info.get("offsets") or {}).get("y_estimated"))
        return int(self.theta.size) + levels * self.noutputs

    def _level_estimated(self) -> bool:
        return bool(dict(self.info.get("offsets") or {}).get("y_estimated"))

    def _searched(self) -> np.ndarray:
        """The parameters the search estimated: ``theta``, then the outputs' levels
        ``y_offset`` when estimated (:mod:`sysid.nonlinear.hw_uncertainty`)."""
        return np.concatenate([self.theta, self.y_offset if self._level_estimated() else []])

    def _searched_names(self) -> list[str]:
        return self._names() + [f"{n}:y_offset" for n in self.output_names
                                if self._level_estimated()]

    def _names(self) -> list[str]:
        names = [f"{n}:in[{k}]" for n, f in zip(self.input_names, self.input_nls)
                 for k in range(np.size(f.params))]
        for key, mat in (("A", self.A), ("B", self.B), ("C", self.C)) + (
                (("D", self.D),) if self.feedthrough else ()):
            names += [f"{key}[{r},{c}]" for r in range(mat.shape[0]) for c in range(mat.shape[1])]
        return names + [f"{n}:out[{k}]" for n, g in zip(self.output_names, self.output_nls)
                        for k in range(np.size(g.params))]

    def _rebuilt(self, theta: Any) -> HammersteinWienerSSModel:
        """The model with the searched parameters ``theta`` (:meth:`_searched`'s order): the
        ``build`` of its uncertainty."""
        import copy

        t = np.asarray(theta, float).ravel()
        n, m, p = self.order, self.ninputs, self.noutputs
        fin, fout = copy.deepcopy(self.input_nls), copy.deepcopy(self.output_nls)
        k = 0
        for f in fin:
            f.params, k = t[k:k + np.size(f.params)], k + np.size(f.params)
        mats = []
        for r, c, on in ((n, n, True), (n, m, True), (p, n, True), (p, m, self.feedthrough)):
            mats.append(t[k:k + r * c].reshape(r, c) if on else None)
            k += r * c * on
        for g in fout:
            g.params, k = t[k:k + np.size(g.params)], k + np.size(g.params)
        return HammersteinWienerSSModel(
            fin, fout, *mats, self.dt, noise_variance=self.noise_variance,
            info={"offsets": self.info.get("offsets")}, input_names=self.input_names,
            output_names=self.output_names, u_offset=self.u_offset,
            y_offset=t[k:k + p] if self._level_estimated() else self.y_offset)

    def _from_state(self, u: Any, x0: Any) -> np.ndarray:
        """The outputs from the linear block's initial state ``x0``."""
        return self.simulate(u, x0)

    def specs(self) -> tuple[list[Any], list[Any]]:
        """The nonlinearities as the Rust functions take them."""
        return [f.spec() for f in self.input_nls], [g.spec() for g in self.output_nls]

    def _u(self, u: Any) -> np.ndarray:
        # complex, NaN or Inf, a wrong shape: an error naming u, not NaN outputs
        u = as_2d(u, "u", ncols=self.ninputs) - self.u_offset
        for j, f in enumerate(self.input_nls):
            if isinstance(f, UserFunction):
                u[:, j] = f(u[:, j])
        return np.ascontiguousarray(u)

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Noise-free outputs ``(n, noutputs)`` from rest, or from the linear block's state
        ``x0`` (``nstates`` values)."""
        fi, fo = self.specs()
        start = None if x0 is None or (isinstance(x0, str) and x0 == "zero") else \
            self._x0(x0)
        return np.asarray(_sysid.hw_mimo_simulate(fi, fo, self.order, self.feedthrough,
                                                  self.theta.tolist(), self._u(u), start)) \
            + self.y_offset

    def _x0(self, x0: Any) -> list[float]:
        x = as_matrix(np.ravel(x0) if not isinstance(x0, str) else x0, "x0", (1, None))[0]
        if x.size != self.nstates:
            raise ShapeError(f"x0 has {x.size} entries but the linear block has "
                             f"{self.nstates} states")
        return x.tolist()

    def predict(self, u: Any, y: Any = None, horizon: int = 1, x0: Any = None) -> np.ndarray:
        """The output-error predictor does not use measured outputs: equals ``simulate``
        (from ``x0``; ``u``, ``y`` and ``horizon`` are checked all the same, as every
        model's are)."""
        as_horizon(horizon)
        u, _ = as_measured(*predict_args(u, y), self.ninputs, self.noutputs)
        return self.simulate(u, x0)

    def linear(self) -> Any:
        """The linear block as a :class:`~sysid.StateSpaceModel` (with the uncertainty of
        its matrices when the model carries one)."""
        from ..models.statespace import StateSpaceModel

        return with_linear_uncertainty(self, StateSpaceModel(self.A, self.B, self.C, self.D,
                                                             dt=self.dt))

    def freqresp(self, omega: Any, std: bool = False) -> Any:
        """Frequency response of the linear block (between the nonlinearities); with
        ``std=True`` (needs ``uncertainty``) the pair ``(H, sd)`` as for
        :meth:`sysid.StateSpaceModel.freqresp`."""
        if std:
            return linear_with_std(self).freqresp(omega, std=True)
        return np.asarray(self.linear().freqresp(omega))

    def poles(self, std: bool = False) -> Any:
        """Poles of the linear block (eigenvalues of ``A``); with ``std=True`` (needs
        ``uncertainty``) the pair ``(poles, sd)`` as for :meth:`sysid.StateSpaceModel.poles`."""
        if std:
            return linear_with_std(self).poles(std=True)
        return np.linalg.eigvals(self.A).astype(complex)

    def summary(self) -> str:
        """Nonlinearities, poles and fit."""
        lines = [repr(self)]
        lines += [f"  input {n}: {f!r}" for n, f in zip(self.input_names, self.input_nls)]
        lines += [f"  output {n}: {g!r}" for n, g in zip(self.output_names, self.output_nls)]
        lines.append(f"  poles: {np.array2string(np.sort_complex(self.poles()), precision=5)}")
        lines.append(f"  operating point: u0 = {np.array2string(self.u_offset, precision=6)}, "
                     f"y0 = {np.array2string(self.y_offset, precision=6)}")
        lines.append(f"  residual variance {np.array2string(self.noise_variance, precision=4)}"
                     f", {self.info.get('iterations', '-')} iterations "
                     f"({self.info.get('stop', '-')})")
        return "\n".join(lines + uncertainty_lines(self))

    def __repr__(self) -> str:
        hin = any(type(f) is not Nonlinearity for f in self.input_nls)
        wout = any(type(g) is not Nonlinearity for g in self.output_nls)
        kind = ("Hammerstein-Wiener" if hin and wout else "Hammerstein" if hin else
                "Wiener" if wout else "linear")
        return (f"HammersteinWienerSSModel({kind}, {self.ninputs} input(s), {self.noutputs} "
                f"output(s), order {self.order}, dt={self.dt:g})")

    def to_pandas(self) -> Any:
        """Parameters as a table (with their standard deviations when the model carries an
        uncertainty: those of ``A``, ``B``, ``C`` only up to the state basis, which the data
        do not determine; the estimated output levels are the uncertainty's last rows)."""
        import pandas as pd

        out = pd.DataFrame({"parameter": self._names(), "value": self.theta})
        unc = getattr(self, "uncertainty", None)
        if unc is not None:
            out["std"] = unc.std[:self.theta.size]
        return out

    def plot(self, fig: Any = None) -> Any:
        """Every nonlinearity over the range seen in estimation; returns the figure."""
        import matplotlib.pyplot as plt

        nls = [(f, r, f"input {n}") for f, r, n in zip(
            self.input_nls, self.info.get("u_ranges", [(-1, 1)] * self.ninputs),
            self.input_names)]
        nls += [(g, r, f"output {n}") for g, r, n in zip(
            self.output_nls, self.info.get("v_ranges", [(-1, 1)] * self.noutputs),
            self.output_names)]
        fig = fig or plt.figure(figsize=(3 * len(nls), 3))
        for k, (nl, (lo, hi), name) in enumerate(nls):
            x = np.linspace(lo, hi, 200)
            ax = fig.add_subplot(1, len(nls), k + 1)
            ax.plot(x, nl(x))
            ax.set_title(name)
        fig.tight_layout()
        return fig

    def to_dict(self) -> dict[str, Any]:
        """For :func:`sysid.save_model` (not with a :class:`UserFunction`)."""
        if any(isinstance(f, UserFunction) for f in self.input_nls):
            raise DataError("a model with a UserFunction input cannot be saved")
        return {"input_nls": [f.to_dict() for f in self.input_nls],
                "output_nls": [g.to_dict() for g in self.output_nls],
                "A": self.A, "B": self.B, "C": self.C,
                "D": self.D if self.feedthrough else None, "dt": self.dt,
                "noise_variance": self.noise_variance, "info": self.info,
                "input_names": self.input_names, "output_names": self.output_names,
                "u_offset": self.u_offset, "y_offset": self.y_offset}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> HammersteinWienerSSModel:
        """Inverse of :meth:`to_dict`."""
        return cls([nonlinearity_from_dict(dict(f)) for f in d["input_nls"]],
                   [nonlinearity_from_dict(dict(g)) for g in d["output_nls"]],
                   d["A"], d["B"], d["C"], d.get("D"), float(d["dt"]),
                   noise_variance=d.get("noise_variance"), info=d.get("info"),
                   input_names=d.get("input_names"), output_names=d.get("output_names"),
                   u_offset=d.get("u_offset"), y_offset=d.get("y_offset"))
