"""The state-space form of a NARX model: ``x(t+1) = f(x(t), u(t))``, ``y(t) = h(x(t), u(t))``.

The state is the shift register of the last ``L = max_lag`` outputs and inputs,
``x(t) = [y(t-1), ..., y(t-L), u(t-1), ..., u(t-L)]`` (each a row of all channels), and ``h``
is the NARX equations (noise terms zero), evaluated by the same Rust code as the NARX free
run, so a simulation of the state-space form is the NARX free run itself.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError
from ..models.protocol import ModelMixin, no_pole_std

__all__ = ["NARXStateSpace"]


class NARXStateSpace(ModelMixin):
    """A NARX model as a nonlinear state-space model (see :meth:`sysid.NARXModel.to_nlss`).

    Parameters
    ----------
    narx : NARXModel
        The model whose selected terms define ``h``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.NARXModel([1], [1], [1], sysid.PolynomialBasis(2), [[[0], [1], [1, 1]]],
    ...                     [[0.5, 1.0, -0.2]], dt=1.0)
    >>> ss = m.to_nlss()
    >>> ss.nstates
    2
    >>> x1, y0 = ss.step(np.zeros(2), [1.0])     # x(1) and y(0) from x(0) = 0, u(0) = 1
    >>> x1.tolist(), y0.tolist()
    ([0.0, 1.0], [0.0])
    >>> np.round(ss.simulate(np.ones(4)).ravel(), 12).tolist()
    [0.0, 0.8, 1.2, 1.4]
    """

    def __init__(self, narx: Any) -> None:
        self.narx = narx
        self.dt = narx.dt
        self.input_names, self.output_names = narx.input_names, narx.output_names
        self.info: dict[str, Any] = {"from": "NARXModel"}

    ninputs = property(lambda self: self.narx.ninputs, doc="Number of inputs.")
    noutputs = property(lambda self: self.narx.noutputs, doc="Number of outputs.")
    lags = property(lambda self: self.narx.max_lag, doc="Length L of the shift register.")
    n_parameters = property(lambda self: self.narx.n_parameters, doc="Number of terms.")

    @property
    def nstates(self) -> int:
        """State dimension ``L (noutputs + ninputs)``."""
        return self.lags * (self.noutputs + self.ninputs)

    @property
    def state_names(self) -> list[str]:
        """``y0(t-1)``, ... then ``u0(t-1)``, ..."""
        L = self.lags
        return ([f"{n}(t-{k})" for k in range(1, L + 1) for n in self.output_names]
                + [f"{n}(t-{k})" for k in range(1, L + 1) for n in self.input_names])

    def _split(self, x: Any) -> tuple[np.ndarray, np.ndarray]:
        """Past outputs and inputs, oldest first: ``(L, ny)``, ``(L, nu)``."""
        x = np.asarray(x, float).ravel()
        if x.size != self.nstates:
            raise DataError(f"the state has {self.nstates} entries ({', '.join(self.state_names)})"
                            f", got {x.size}")
        L, ny, nu = self.lags, self.noutputs, self.ninputs
        return x[:L * ny].reshape(L, ny)[::-1], x[L * ny:].reshape(L, nu)[::-1]

    def _join(self, ypast: np.ndarray, upast: np.ndarray) -> np.ndarray:
        return np.concatenate([ypast[::-1].ravel(), upast[::-1].ravel()])

    def step(self, x: Any, u: Any) -> tuple[np.ndarray, np.ndarray]:
        """``(x(t+1), y(t))`` from the state ``x(t)`` and the input ``u(t)``."""
        ypast, upast = self._split(x)
        ut = np.asarray(u, float).reshape(1, self.ninputs)
        yt = self.narx.simulate(np.vstack([upast, ut]), x0=ypast)[-1]
        return (self._join(np.vstack([ypast[1:], yt]), np.vstack([upast[1:], ut])),
                np.asarray(yt, float))

    def output(self, x: Any, u: Any) -> np.ndarray:
        """``y(t) = h(x(t), u(t))``."""
        return self.step(x, u)[1]

    def state(self, u: Any, y: Any, t: int | None = None) -> np.ndarray:
        """The state at time ``t`` (default ``L``) from measured inputs and outputs."""
        u = self.narx._u(u)
        y = np.asarray(y, float).reshape(-1, self.noutputs)
        t = self.lags if t is None else int(t)
        if not self.lags <= t <= min(len(y), len(u)):
            raise DataError(f"t must be in [{self.lags}, {min(len(y), len(u))}], got {t}")
        return self._join(y[t - self.lags:t], u[t - self.lags:t])

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Outputs ``y(0..n-1)`` from the state ``x0`` (default zero: outputs and inputs zero
        before the record); the same Rust loop as :meth:`sysid.NARXModel.simulate`."""
        u = self.narx._u(u)
        ypast, upast = self._split(np.zeros(self.nstates) if x0 is None else x0)
        full = self.narx.simulate(np.vstack([upast, u]), x0=ypast)
        return full[self.lags:]

    def predict(self, u: Any, y: Any = None, horizon: int = 1) -> np.ndarray:
        """k-step prediction: that of the NARX model."""
        return self.narx.predict(u, y, horizon)

    def freqresp(self, omega: Any) -> np.ndarray:
        """Frequency response of the NARX model's linearisation at zero."""
        return self.narx.freqresp(omega)

    def poles(self, std: bool = False) -> np.ndarray:
        """Poles of the linearisation at zero."""
        no_pole_std(self, std)
        return self.narx.poles()

    def __repr__(self) -> str:
        return (f"NARXStateSpace({self.nstates} states, {self.ninputs} input(s), "
                f"{self.noutputs} output(s), from {self.narx!r})")

    def to_dict(self) -> dict[str, Any]:
        """The NARX model it is a view of (:meth:`sysid.NARXModel.to_dict`), for
        :func:`sysid.save_model`.

        Examples
        --------
        >>> import os, tempfile, sysid
        >>> m = sysid.NARXModel([1], [1], [1], sysid.PolynomialBasis(2), [[[0], [1]]],
        ...                     [[0.5, 1.0]], dt=1.0)
        >>> path = os.path.join(tempfile.mkdtemp(), "m.json")
        >>> m.to_nlss().save(path)
        >>> sysid.load_model(path).nstates
        2
        """
        from ..models.uncertainty_io import body_with_uncertainty

        return {"narx": body_with_uncertainty(self.narx)}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> NARXStateSpace:
        """Inverse of :meth:`to_dict`."""
        from ..models.serialize import REGISTRY, family_class
        from ..models.uncertainty_io import model_from_body

        return cls(model_from_body(family_class("NARXModel"), d["narx"], REGISTRY))

    def summary(self) -> str:
        """The state and the output equations."""
        return "\n".join([repr(self), "state: " + ", ".join(self.state_names),
                          "x(t+1): shift in y(t) and u(t)", "y(t) = h(x(t), u(t)):",
                          self.narx.terms_table()])


def _register() -> None:
    from ..models.serialize import register_model

    register_model(NARXStateSpace)


_register()
