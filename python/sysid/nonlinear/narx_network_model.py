"""NARX models with network nonlinearities: sigmoid network, wavelet network, tree partition
(MATLAB's ``idSigmoidNetwork``, ``idWaveletNetwork``, ``idTreePartition`` in ``nlarx``).

Output ``i`` is ``y_i(t) = F_i(z(t))`` of the standardised lagged variables
``z = (x - shift) / scale``, ``x(t) = [y(t-1) .. y(t-na), u(t-nk) .. u(t-nk-nb+1)]``:

* unit network: ``F(z) = d + l^T z + sum_k a_k g(z; p_k)`` with sigmoid units
  ``g = 1 / (1 + exp(-(w^T z + b)))`` or radial wavelets ``(nz - r^2) exp(-r^2 / 2)``,
  ``r = dil |z - c|`` (and Gaussian scaling functions ``exp(-r^2 / 2)``);
* tree partition: ``F(z) = c0_j + c_j^T z`` on the leaf ``j`` of a binary partition of the
  regressor space.

Simulation, prediction and evaluation run in Rust (``sysid-core``, ``narx/network``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _sysid
from ..errors import DataError
from ..models.protocol import ModelMixin, no_pole_std
from .narx_model import LaggedIO, channel_names, lag_names

__all__ = ["NetworkNARXModel"]

KIND_CODES = {"sigmoid": 0, "wavelet": 1, "scaling": 2}
_KIND_NAMES = {v: k for k, v in KIND_CODES.items()}


def _rust_nl(d: dict[str, Any]) -> tuple[Any, ...]:
    """One output's nonlinearity as the tuple the Rust functions take."""
    if d["type"] == "tree":
        return (np.asarray(d["var"], int).tolist(), np.asarray(d["threshold"], float).tolist(),
                np.asarray(d["left"], int).tolist(), np.asarray(d["right"], int).tolist(),
                np.asarray(d["coefs"], float).tolist())
    return ([KIND_CODES[k] for k in d["kinds"]], np.asarray(d["theta"], float).ravel().tolist(),
            np.asarray(d["linear"], float).tolist())


def from_rust_nl(t: tuple[Any, ...], nz: int) -> dict[str, Any]:
    """Inverse of :func:`_rust_nl`."""
    if len(t) == 5:
        var, thr, left, right, coefs = t
        return {"type": "tree", "var": np.asarray(var, int), "threshold": np.asarray(thr, float),
                "left": np.asarray(left, int), "right": np.asarray(right, int),
                "coefs": np.asarray(coefs, float).reshape(len(var), nz + 1)}
    kinds, theta, linear = t
    return {"type": "network", "kinds": [_KIND_NAMES[int(k)] for k in kinds],
            "theta": np.asarray(theta, float).reshape(len(kinds), nz + 1),
            "linear": np.asarray(linear, float)}


class NetworkNARXModel(LaggedIO, ModelMixin):
    """A (MIMO) NARX model whose outputs are sigmoid networks, wavelet networks or tree
    partitions of the lagged outputs and inputs (from :func:`sysid.nlarx`).

    Parameters
    ----------
    na : list of int (n_outputs)
        Output lags ``1..na[k]`` of each output.
    nb, nk : list of int (n_inputs)
        Input lags ``nk[j]..nk[j] + nb[j] - 1``.
    nonlinearities : list of dict (n_outputs)
        A unit network ``{"type": "network", "kinds": [...], "theta": (n_units, nz + 1),
        "linear": [d, l (nz), a (n_units)]}`` (kinds ``"sigmoid"``, ``"wavelet"``,
        ``"scaling"``; a sigmoid's parameters ``[w, b]``, a wavelet's ``[dilation, centre]``)
        or a tree ``{"type": "tree", "var", "threshold", "left", "right", "coefs"}`` (one
        entry per node, ``left = right = -1`` at leaves, ``coefs`` the affine model
        ``[c0, c]`` of the node's cell).
    shift, scale : array_like (nz)
        Standardisation of the lagged variables ``z = (x - shift) / scale``.
    dt : float
        Sample time.
    name : str
        The nonlinearity's name (``"sigmoidnet"``, ``"wavenet"``, ``"treepartition"``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> # y(t) = 0.5 y(t-1) + 2 sigmoid(u(t-1))
    >>> net = {"type": "network", "kinds": ["sigmoid"], "theta": [[0.0, 1.0, 0.0]],
    ...        "linear": [0.0, 0.5, 0.0, 2.0]}
    >>> m = sysid.NetworkNARXModel([1], [1], [1], [net], [0.0, 0.0], [1.0, 1.0], dt=1.0)
    >>> np.round(m.simulate(np.zeros(3)).ravel(), 6).tolist()
    [0.0, 1.0, 1.5]
    """

    def __init__(self, na: Any, nb: Any, nk: Any, nonlinearities: Any, shift: Any, scale: Any,
                 dt: float, *, name: str = "network", noise_variance: Any = None,
                 input_names: Any = None, output_names: Any = None,
                 info: dict[str, Any] | None = None) -> None:
        self.na = [int(v) for v in np.atleast_1d(na)]
        self.nb = [int(v) for v in np.atleast_1d(nb)] if np.size(nb) else []
        self.nk = [int(v) for v in np.atleast_1d(nk)] if np.size(nk) else []
        ny, nu = len(self.na), len(self.nb)
        if len(self.nk) != nu:
            raise DataError(f"nk needs {nu} entries (one per input)")
        nz = sum(self.na) + sum(self.nb)
        self.shift = np.asarray(shift, float).ravel()
        self.scale = np.asarray(scale, float).ravel()
        if self.shift.size != nz or self.scale.size != nz:
            raise DataError(f"shift and scale need one value per lagged variable ({nz})")
        nls = list(nonlinearities)
        if len(nls) != ny:
            raise DataError(f"nonlinearities needs one entry per output ({ny}), got {len(nls)}")
        self.nonlinearities = [from_rust_nl(_rust_nl(dict(d)), nz) for d in nls]
        self.dt, self.name = float(dt), str(name)
        self.noise_variance = (np.ones(ny) if noise_variance is None
                               else np.asarray(noise_variance, float).ravel())
        self.input_names = channel_names(input_names, "u", nu)
        self.output_names = channel_names(output_names, "y", ny)
        self.info: dict[str, Any] = dict(info or {})
        self.evaluate(self.shift[None, :])  # checks the parts in Rust (a DataError if wrong)

    # -- protocol ----------------------------------------------------------------------
    ninputs = property(lambda self: len(self.nb), doc="Number of inputs.")
    noutputs = property(lambda self: len(self.na), doc="Number of outputs.")

    @property
    def n_parameters(self) -> int:
        """Number of estimated parameters over all outputs (unit and linear parameters; for a
        tree the leaves' affine coefficients and the thresholds)."""
        total = 0
        for d in self.nonlinearities:
            if d["type"] == "tree":
                leaves = int(np.sum(d["left"] < 0))
                total += leaves * d["coefs"].shape[1] + (len(d["var"]) - leaves)
            else:
                total += d["theta"].size + d["linear"].size
        return total

    @property
    def max_lag(self) -> int:
        """Largest lag: the number of initial outputs a simulation needs."""
        return int(max([*self.na, *[b + k - 1 for b, k in zip(self.nb, self.nk) if b], 1]))

    @property
    def regressor_names(self) -> list[str]:
        """Names of the lagged variables, in the order of ``z``."""
        return lag_names(self.na, self.nb, self.nk, [0] * self.noutputs, self.input_names,
                         self.output_names)

    def _args(self) -> dict[str, Any]:
        return {"orders": (self.na, self.nb, self.nk), "shift": self.shift.tolist(),
                "scale": self.scale.tolist(),
                "outputs": [_rust_nl(d) for d in self.nonlinearities]}

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Free-run simulation; ``x0`` the first ``max_lag`` outputs ``(max_lag, noutputs)``
        (``None`` or ``"zero"``: zeros). Raises a :class:`~sysid.NumericalError` naming the
        sample when the simulation diverges."""
        u, y0 = self._u(u), self._y0(x0)
        return np.asarray(_sysid.narx_network_simulate(self._args(), u, np.ascontiguousarray(y0)))

    def predict(self, u: Any, y: Any = None, horizon: int = 1) -> np.ndarray:
        """``horizon``-step prediction ``yhat(t | t - horizon)`` from measured ``u``, ``y``;
        ``np.inf``: the simulation from the measured first ``max_lag`` outputs. The first
        ``max_lag`` rows repeat the measured outputs."""
        u, y, horizon = self._measured(u, y, horizon)
        if horizon is None:
            return self.simulate(u, x0=self._measured_start(y))
        return np.asarray(_sysid.narx_network_predict(self._args(), u, np.ascontiguousarray(y),
                                                      int(horizon)))

    def evaluate(self, x: Any) -> np.ndarray:
        """The nonlinearities ``F_i`` at lagged variables ``x`` ``(n, nz)`` (engineering
        units, columns in the order of :attr:`regressor_names`): ``(n, noutputs)``."""
        x = np.atleast_2d(np.asarray(x, float))
        return np.asarray(_sysid.narx_network_evaluate(self._args(), np.ascontiguousarray(x)))

    def linearize(self, at: Any = None) -> Any:
        """The linear ARX model of the first-order expansion at the lagged variables ``at``
        (default: the mean over the estimation data, ``shift``), a
        :class:`~sysid.PolynomialModel`; the slopes by central differences of
        :meth:`evaluate` (the constant term is dropped)."""
        from ..polynomial.model import PolynomialModel

        x0 = self.shift if at is None else np.asarray(at, float).ravel()
        nz, ny, nu = x0.size, self.noutputs, self.ninputs
        h = 1e-6 * self.scale
        pts = np.vstack([x0 + np.diag(h), x0 - np.diag(h)])
        v = self.evaluate(pts)
        slope = (v[:nz] - v[nz:]) / (2 * h[:, None])  # (nz, ny)
        offs = np.cumsum([0, *self.na, *self.nb])
        a = [[-slope[offs[k]:offs[k + 1], i] for k in range(ny)] for i in range(ny)]
        b = [[slope[offs[ny + j]:offs[ny + j + 1], i] for j in range(nu)] for i in range(ny)]
        return PolynomialModel(a, b, [list(self.nk)] * ny, self.dt)

    def freqresp(self, omega: Any) -> np.ndarray:
        """Frequency response of :meth:`linearize` (small-signal, at the mean operating
        point)."""
        return np.asarray(self.linearize().freqresp(omega))

    def poles(self, std: bool = False) -> np.ndarray:
        """Poles of :meth:`linearize`."""
        no_pole_std(self, std)
        return np.asarray(self.linearize().poles())

    # -- presentation ------------------------------------------------------------------
    def n_units(self, output: int = 0) -> int:
        """Units of one output's network, or leaves of its tree."""
        d = self.nonlinearities[output]
        return int(np.sum(d["left"] < 0)) if d["type"] == "tree" else len(d["kinds"])

    def to_pandas(self) -> Any:
        """One row per (output, parameter): group, index, value."""
        import pandas as pd

        rows: list[dict[str, Any]] = []
        for i, d in enumerate(self.nonlinearities):
            out = self.output_names[i]
            if d["type"] == "tree":
                for j in np.flatnonzero(d["left"] < 0):
                    rows += [{"output": out, "group": f"leaf {j}", "index": k, "value": v}
                             for k, v in enumerate(d["coefs"][j])]
                continue
            rows += [{"output": out, "group": "linear", "index": k, "value": v}
                     for k, v in enumerate(d["linear"])]
            for k, kind in enumerate(d["kinds"]):
                rows += [{"output": out, "group": f"{kind} unit {k}", "index": j, "value": v}
                         for j, v in enumerate(d["theta"][k])]
        return pd.DataFrame(rows, columns=["output", "group", "index", "value"])

    def summary(self) -> str:
        """The structure of each output's nonlinearity and how it was trained."""
        out = [repr(self), "regressors: " + ", ".join(self.regressor_names)]
        for i in range(self.noutputs):
            kind = "leaves" if self.nonlinearities[i]["type"] == "tree" else "units"
            out.append(f"output {self.output_names[i]}: {self.n_units(i)} {kind}, residual "
                       f"variance {self.noise_variance[i]:.4g}")
        for i, s in enumerate(self.info.get("search", [])):
            out.append(f"  {self.output_names[i]} search: {s.get('iterations')} iterations, "
                       f"stop: {s.get('stop')}")
        if "refine" in self.info:
            r = self.info["refine"]
            out.append(f"simulation focus: {r['iterations']} iterations, stop: {r['stop']}")
        return "\n".join(out)

    def __repr__(self) -> str:
        units = ", ".join(str(self.n_units(i)) for i in range(self.noutputs))
        return (f"NetworkNARXModel({self.name}, {self.noutputs} output(s), {self.ninputs} "
                f"input(s), units [{units}], {self.n_parameters} parameters, dt={self.dt:g})")

    def plot(self, regressor: int = 0, fig: Any = None) -> Any:
        """Each output's nonlinearity along one regressor (the others at their mean);
        returns the figure."""
        import matplotlib.pyplot as plt

        fig = fig or plt.figure(figsize=(6, 2.5 * self.noutputs))
        grid = np.linspace(-3, 3, 200) * self.scale[regressor] + self.shift[regressor]
        x = np.tile(self.shift, (grid.size, 1))
        x[:, regressor] = grid
        v = self.evaluate(x)
        for i in range(self.noutputs):
            ax = fig.add_subplot(self.noutputs, 1, i + 1)
            ax.plot(grid, v[:, i])
            ax.set_xlabel(self.regressor_names[regressor])
            ax.set_ylabel(f"F({self.output_names[i]})")
        fig.tight_layout()
        return fig

    # -- saving ------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Everything needed to rebuild the model (see :func:`sysid.save_model`)."""
        nls = []
        for d in self.nonlinearities:
            e = dict(d)
            if d["type"] == "network":
                e["kinds"] = list(d["kinds"])
            nls.append(e)
        return {"na": self.na, "nb": self.nb, "nk": self.nk, "nonlinearities": nls,
                "shift": self.shift, "scale": self.scale, "dt": self.dt, "name": self.name,
                "noise_variance": self.noise_variance, "input_names": self.input_names,
                "output_names": self.output_names, "info": self.info}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> NetworkNARXModel:
        """Inverse of :meth:`to_dict`."""
        return cls(d["na"], d["nb"], d["nk"], d["nonlinearities"], d["shift"], d["scale"],
                   float(d["dt"]), name=str(d.get("name", "network")),
                   noise_variance=d.get("noise_variance"), input_names=d.get("input_names"),
                   output_names=d.get("output_names"), info=d.get("info"))


def _register() -> None:
    from ..models.serialize import register_model

    register_model(NetworkNARXModel)


_register()
