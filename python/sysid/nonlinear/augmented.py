"""Basis-function input augmentation: a linear model on the inputs and chosen static functions
of them (``[u, f_1(u), f_2(u), ...]``), identified with the subspace or ARX engines
(:func:`sysid.augmented_fit`).

The linear machinery stays unchanged: the augmented record is an ordinary :class:`IOData`
with more input channels, and the model applies the same functions before simulating.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .._checks import as_2d
from ..errors import DataError
from ..models.protocol import ModelMixin, no_pole_std

__all__ = ["augment_inputs", "AugmentedInputModel"]

NAMED: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "square": lambda u: u ** 2,
    "cube": lambda u: u ** 3,
    "abs": np.abs,
    "signed_square": lambda u: np.sign(u) * u ** 2,
    "tanh": np.tanh,
}


def _functions(functions: Sequence[Any]) -> list[tuple[str, Callable[[np.ndarray], Any]]]:
    if isinstance(functions, str) or callable(functions):
        functions = [functions]  # one function named or given alone
    if not isinstance(functions, (list, tuple)):
        raise DataError(f"functions must be a list of names or callables (e.g. ['square', "
                        f"'cube']), got {type(functions).__name__} {functions!r}")
    out = []
    for f in functions:
        if isinstance(f, str):
            if f not in NAMED:
                raise DataError(f"unknown basis function {f!r}; use one of {sorted(NAMED)} or a "
                                "callable")
            out.append((f, NAMED[f]))
        elif callable(f):
            out.append((getattr(f, "__name__", "f"), f))
        else:
            raise DataError(f"basis functions must be names or callables, got {f!r}")
    if not out:
        raise DataError("give at least one basis function")
    return out


def _augment(u: np.ndarray, fns: list[tuple[str, Callable[[np.ndarray], Any]]]) -> np.ndarray:
    cols = [u]
    for name, f in fns:
        v = np.asarray(f(u))
        if np.iscomplexobj(v):
            raise DataError(f"basis function {name} returned complex values: sysid does not "
                            "drop imaginary parts; return np.real(...) of them if the real part "
                            "is what you mean")
        v = v.astype(float, copy=False)
        if v.shape != u.shape:
            raise DataError(f"basis function {name} must return an array of the input's "
                            f"shape {u.shape}, got {v.shape}")
        if not np.all(np.isfinite(v)):
            bad = np.argwhere(~np.isfinite(v))[0]
            raise DataError(f"basis function {name} returned a non-finite value (at sample "
                            f"{bad[0]}, channel {bad[1]}, input {u[tuple(bad)]:g}): it must be "
                            "finite over the input's range")
        cols.append(v)
    return np.hstack(cols)


def augment_inputs(data: Any, functions: Sequence[Any]) -> Any:
    """The record with inputs ``[u, f_1(u), ...]`` (each function applied to every input).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(np.array([[1.0], [-2.0]]), np.zeros((2, 1)), 1.0)
    >>> sysid.augment_inputs(d, ["square"]).u.tolist()
    [[1.0, 1.0], [-2.0, 4.0]]
    """
    from ..data.iodata import IOData

    fns = _functions(functions)
    exps = data.experiments
    names = list(data.input_names)
    new_names = names + [f"{n}:{fname}" for fname, _ in fns for n in names]
    us = [_augment(np.asarray(u, float), fns) for u, _ in exps]
    ys = [np.asarray(y, float) for _, y in exps]
    return IOData(us if len(us) > 1 else us[0], ys if len(ys) > 1 else ys[0], data.dt,
                  input_names=new_names, output_names=list(data.output_names))


class AugmentedInputModel(ModelMixin):
    """A linear model driven by ``[u, f_1(u), ...]``; ``simulate(u)`` applies the functions.

    Parameters
    ----------
    linear : sysid.Model
        The linear model on the augmented inputs.
    functions : sequence of str or callable
        The basis functions (names: ``square``, ``cube``, ``abs``, ``signed_square``,
        ``tanh``).
    ninputs : int
        Number of original inputs.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> lin = sysid.StateSpaceModel([[0.5]], [[1.0, 0.5]], [[1.0]])
    >>> m = sysid.AugmentedInputModel(lin, ["square"], 1)
    >>> m.simulate(np.full(3, 2.0)).ravel().tolist()
    [0.0, 4.0, 6.0]
    """

    def __init__(self, linear: Any, functions: Sequence[Any], ninputs: int) -> None:
        self.linear, self.functions = linear, list(functions)
        self._fns = _functions(self.functions)
        self.ninputs = int(ninputs)
        if linear.ninputs != self.ninputs * (1 + len(self._fns)):
            raise DataError(f"the linear model has {linear.ninputs} inputs but {self.ninputs} "
                            f"input(s) with {len(self._fns)} function(s) give "
                            f"{self.ninputs * (1 + len(self._fns))}")
        self.noutputs, self.dt = linear.noutputs, linear.dt
        self.input_names = list(linear.input_names)[: self.ninputs]
        self.output_names = list(linear.output_names)
        self.info: dict[str, Any] = {"method": "augmented", "functions": [
            f if isinstance(f, str) else getattr(f, "__name__", "f") for f in self.functions],
            "linear": dict(getattr(linear, "info", {}) or {})}

    @property
    def n_parameters(self) -> int:
        """Free parameters of the linear model."""
        return int(self.linear.n_parameters)

    def _u(self, u: Any) -> np.ndarray:
        # complex, NaN or Inf, a wrong shape: an error naming u
        return _augment(as_2d(u, "u", ncols=self.ninputs), self._fns)

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Output of the linear model for the augmented inputs."""
        ua = self._u(u)
        return np.asarray(self.linear.simulate(ua) if x0 is None
                          else self.linear.simulate(ua, x0=x0))

    def predict(self, u: Any, y: Any = None, horizon: int = 1) -> np.ndarray:
        """The linear model's prediction for the augmented inputs."""
        from .._measured import predict_args

        u, y = predict_args(u, y)
        return np.asarray(self.linear.predict(self._u(u), y, horizon))

    def freqresp(self, omega: Any) -> np.ndarray:
        """Response of the linear model from the original (un-augmented) inputs."""
        return np.asarray(self.linear.freqresp(omega))[:, :, : self.ninputs]

    def poles(self, std: bool = False) -> np.ndarray:
        """Poles of the linear model."""
        no_pole_std(self, std)
        return np.asarray(self.linear.poles())

    def to_dict(self) -> dict[str, Any]:
        """The linear model (its family and body, uncertainty included), the functions' names
        and the number of inputs, for :func:`sysid.save_model`; functions given as callables
        cannot be written (a :class:`~sysid.DataError` says so).

        Examples
        --------
        >>> import os, tempfile, numpy as np, sysid
        >>> lin = sysid.StateSpaceModel([[0.5]], [[1.0, 0.5]], [[1.0]])
        >>> path = os.path.join(tempfile.mkdtemp(), "m.json")
        >>> sysid.AugmentedInputModel(lin, ["square"], 1).save(path)
        >>> sysid.load_model(path).simulate(np.full(3, 2.0)).ravel().tolist()
        [0.0, 4.0, 6.0]
        """
        from ..models.serialize import family_name
        from ..models.uncertainty_io import body_with_uncertainty

        given = [n for f, (n, _) in zip(self.functions, self._fns) if not isinstance(f, str)]
        if given:
            raise DataError(f"AugmentedInputModel cannot be saved with basis functions given as "
                            f"callables ({', '.join(given)}): a file holds "
                            f"names only ({', '.join(sorted(NAMED))}); save its linear model "
                            f"(model.linear.save(path)) and rebuild it with your functions")
        return {"linear_family": family_name(self.linear),
                "linear": body_with_uncertainty(self.linear),
                "functions": list(self.functions), "ninputs": self.ninputs}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> AugmentedInputModel:
        """Inverse of :meth:`to_dict`."""
        from ..models.serialize import REGISTRY, family_class
        from ..models.uncertainty_io import model_from_body

        linear = model_from_body(family_class(str(d["linear_family"])), d["linear"], REGISTRY)
        return cls(linear, [str(f) for f in d["functions"]], int(d["ninputs"]))

    def __repr__(self) -> str:
        return f"AugmentedInputModel({self.info['functions']}, {self.linear!r})"


def _register() -> None:
    from ..models.serialize import register_model

    register_model(AugmentedInputModel)


_register()
