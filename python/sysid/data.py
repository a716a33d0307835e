"""Input/output records: :class:`IOData`, the one data type every estimator accepts."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ._checks import as_2d
from .errors import DataError, ShapeError

__all__ = ["IOData"]


def _as_list(x: Any) -> list[Any] | None:
    if x is None:
        return None
    if isinstance(x, (list, tuple)):
        return list(x)
    return [x]


class IOData:
    """Measured inputs and outputs, time-first, possibly several experiments.

    Parameters
    ----------
    u : array_like or list of array_like or None
        Inputs shaped ``(n_samples, n_inputs)`` (1-D means one input). A list gives one
        array per experiment. ``None`` for output-only (time-series) data.
    y : array_like or list of array_like
        Outputs shaped ``(n_samples, n_outputs)``, one per experiment if a list.
    dt : float
        Sample time in seconds.
    input_names, output_names : sequence of str, optional
        Channel names; default ``u0, u1, ...`` and ``y0, y1, ...``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.zeros((100, 1)), y=np.ones((100, 2)), dt=0.1)
    >>> d
    IOData: 100 samples, 1 input, 2 outputs, dt = 0.1 s
    >>> d.experiments[0][1].shape
    (100, 2)
    """

    def __init__(
        self,
        u: Any = None,
        y: Any = None,
        dt: float = 1.0,
        *,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
    ) -> None:
        if y is None:
            raise DataError("y is required: IOData(u=..., y=..., dt=...)")
        ys = [as_2d(v, "y" if i == 0 else f"y[{i}]") for i, v in enumerate(_as_list(y))]
        n_out = ys[0].shape[1]
        for i, v in enumerate(ys):
            if v.shape[1] != n_out:
                raise ShapeError(f"y[{i}] has {v.shape[1]} outputs but y[0] has {n_out}")
        us_in = _as_list(u)
        if us_in is None:
            us = [np.zeros((v.shape[0], 0)) for v in ys]
        else:
            if len(us_in) != len(ys):
                raise ShapeError(
                    f"u has {len(us_in)} experiment(s) but y has {len(ys)}; give one array each"
                )
            us = [as_2d(v, "u" if i == 0 else f"u[{i}]") for i, v in enumerate(us_in)]
        n_in = us[0].shape[1]
        for i, (a, b) in enumerate(zip(us, ys)):
            if a.shape[1] != n_in:
                raise ShapeError(f"u[{i}] has {a.shape[1]} inputs but u[0] has {n_in}")
            if a.shape[0] != b.shape[0]:
                raise ShapeError(
                    f"u has {a.shape[0]} samples but y has {b.shape[0]}"
                    + (f" in experiment {i}" if len(ys) > 1 else "")
                    + "; inputs and outputs must be sampled together"
                )
        dt = float(dt)
        if not np.isfinite(dt) or dt <= 0:
            raise DataError(f"dt must be a positive number of seconds, got {dt}")
        self._u = us
        self._y = ys
        self.dt = dt
        self.input_names = self._names(input_names, n_in, "u")
        self.output_names = self._names(output_names, n_out, "y")

    @staticmethod
    def _names(names: Sequence[str] | None, n: int, prefix: str) -> list[str]:
        if names is None:
            return [f"{prefix}{i}" for i in range(n)]
        names = [str(s) for s in names]
        if len(names) != n:
            raise ShapeError(f"{len(names)} {prefix}-channel names given for {n} channel(s)")
        return names

    @property
    def experiments(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """``[(u, y), ...]``, one float64 pair per experiment, shaped (samples, channels)."""
        return list(zip(self._u, self._y))

    @property
    def u(self) -> np.ndarray:
        """Inputs of a single-experiment record, ``(n_samples, n_inputs)``."""
        return self._single(self._u, "u")

    @property
    def y(self) -> np.ndarray:
        """Outputs of a single-experiment record, ``(n_samples, n_outputs)``."""
        return self._single(self._y, "y")

    def _single(self, arrays: list[np.ndarray], name: str) -> np.ndarray:
        if len(arrays) != 1:
            raise DataError(
                f"this record has {len(arrays)} experiments; use .experiments instead of .{name}"
            )
        return arrays[0]

    @property
    def n_inputs(self) -> int:
        """Number of input channels."""
        return self._u[0].shape[1]

    @property
    def n_outputs(self) -> int:
        """Number of output channels."""
        return self._y[0].shape[1]

    @property
    def n_experiments(self) -> int:
        """Number of experiments."""
        return len(self._y)

    @property
    def n_samples(self) -> int:
        """Total number of samples over all experiments."""
        return sum(v.shape[0] for v in self._y)

    def __len__(self) -> int:
        return self.n_samples

    def __repr__(self) -> str:
        def plural(n: int, word: str) -> str:
            return f"{n} {word}" + ("" if n == 1 else "s")

        exp = f" in {self.n_experiments} experiments" if self.n_experiments > 1 else ""
        return (
            f"IOData: {plural(self.n_samples, 'sample')}{exp}, {plural(self.n_inputs, 'input')}, "
            f"{plural(self.n_outputs, 'output')}, dt = {self.dt:g} s"
        )
