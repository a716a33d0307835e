"""User-supplied NARX regressors (MATLAB's ``customreg``): a named function of lagged signals.

A :class:`CustomRegressor` is a candidate term of :func:`sysid.nlarx` beside the polynomial or
RBF ones: FROLS chooses it (or not) by its error reduction ratio, and it enters the model
linearly, ``theta * fn(args)``. It is evaluated vectorised over whole records when estimating
and once per sample (from the simulated outputs) in free-run simulation and k-step
prediction.
"""

from __future__ import annotations

import re
from typing import Any, Callable

import numpy as np

from ..errors import DataError

__all__ = ["CustomRegressor"]

_ARG = re.compile(r"^\s*(.+?)\s*\(\s*t\s*(?:-\s*(\d+)\s*)?\)\s*$")


class CustomRegressor:
    """A named regressor ``fn(*args)`` of lagged outputs and inputs.

    Parameters
    ----------
    fn : callable
        Called with one argument per entry of ``args``: 1-D float arrays of equal length when
        estimating (return a 1-D array of that length) and floats when simulating (return a
        float). Element-wise NumPy expressions (``np.sin(u)``, ``y * np.abs(u)``) work for
        both. Values must be finite.
    args : list of str
        The lagged signals, as ``"<name>(t-<lag>)"`` or ``"<input name>(t)"``, with the names
        of the data's channels (default ``y0, y1, ...`` and ``u0, u1, ...``); outputs need a
        lag of at least 1.
    name : str, optional
        Name in term tables (default ``fn.__name__`` with the arguments).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> r = sysid.CustomRegressor(lambda y, u: y * np.abs(u), ["y0(t-1)", "u0(t-1)"],
    ...                           name="y0(t-1)*|u0(t-1)|")
    >>> r
    CustomRegressor('y0(t-1)*|u0(t-1)|', args=['y0(t-1)', 'u0(t-1)'])
    >>> r.resolve(["y0"], ["u0"])
    [(0, 0, 1), (1, 0, 1)]
    """

    def __init__(self, fn: Callable[..., Any], args: Any, name: str | None = None) -> None:
        if not callable(fn):
            raise DataError(f"fn must be callable, got {fn!r}")
        if isinstance(args, str):
            args = [args]
        self.args = [str(a) for a in args]
        if not self.args:
            raise DataError("a custom regressor needs at least one argument, e.g. ['u0(t-1)']")
        for a in self.args:
            if not _ARG.match(a):
                raise DataError(f"argument {a!r} is not of the form 'name(t-lag)' or 'name(t)'")
        self.fn = fn
        fname = getattr(fn, "__name__", "custom")
        self.name = str(name) if name is not None else (
            f"{'custom' if fname == '<lambda>' else fname}({', '.join(self.args)})")

    def resolve(self, output_names: list[str], input_names: list[str]
                ) -> list[tuple[int, int, int]]:
        """The arguments as ``(kind, channel, lag)`` (kind 0: output, 1: input)."""
        out = []
        for a in self.args:
            m = _ARG.match(a)
            assert m is not None
            sig, lag = m.group(1), int(m.group(2) or 0)
            if sig in output_names:
                if lag < 1:
                    raise DataError(f"custom regressor {self.name!r}: output argument {a!r} "
                                    "needs a lag of at least 1 (y(t) is what is predicted)")
                out.append((0, output_names.index(sig), lag))
            elif sig in input_names:
                out.append((1, input_names.index(sig), lag))
            else:
                raise DataError(f"custom regressor {self.name!r}: {sig!r} in {a!r} is neither "
                                f"an output {output_names} nor an input {input_names}")
        return out

    def max_lag(self, output_names: list[str], input_names: list[str]) -> int:
        """Largest lag of the arguments."""
        return max(lag for _, _, lag in self.resolve(output_names, input_names))

    def values(self, u: np.ndarray, y: np.ndarray, start: int, output_names: list[str],
               input_names: list[str]) -> np.ndarray:
        """The regressor at times ``start..N`` of a record (zeros before ``start``), checked:
        a 1-D finite float array of the right length, else a :class:`~sysid.DataError`."""
        n = y.shape[0]
        cols = [(y if kind == 0 else u)[start - lag:n - lag, ch]
                for kind, ch, lag in self.resolve(output_names, input_names)]
        try:
            with np.errstate(all="ignore"):
                v = np.asarray(self.fn(*cols), dtype=float)
        except DataError:
            raise
        except Exception as e:  # the user's function failed: say which one
            raise DataError(f"custom regressor {self.name!r} raised {type(e).__name__}: {e}"
                            ) from e
        if v.shape != (n - start,):
            raise DataError(f"custom regressor {self.name!r} returned shape {v.shape} for "
                            f"arguments of shape ({n - start},); it must return one value per "
                            "sample (use element-wise NumPy operations)")
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            raise DataError(f"custom regressor {self.name!r} returned {v[bad[0]]} at sample "
                            f"{start + bad[0]} ({bad.size} non-finite values); make it finite "
                            "over the range of the data")
        out = np.zeros(n)
        out[start:] = v
        return out

    def scalar(self) -> Callable[..., float]:
        """The per-sample function for simulation (floats in, a finite float out)."""
        fn, name = self.fn, self.name

        def call(*args: float) -> float:
            try:
                with np.errstate(all="ignore"):
                    v = np.asarray(fn(*args), dtype=float)
            except Exception as e:
                raise DataError(f"custom regressor {name!r} raised {type(e).__name__}: {e}"
                                ) from e
            if v.size != 1:
                raise DataError(f"custom regressor {name!r} returned shape {v.shape} for "
                                "scalar arguments; it must return one value per sample")
            out = float(v.reshape(()))
            if not np.isfinite(out):
                raise DataError(f"custom regressor {name!r} returned {out} at arguments "
                                f"{list(args)}; make it finite over the range of the signals")
            return out

        return call

    def __repr__(self) -> str:
        return f"CustomRegressor({self.name!r}, args={self.args!r})"
