"""Polynomial (transfer-function) models in the backward shift ``q^-1``.

For output ``i``: ``A(q) y_i(t) = sum_j B_ij(q)/F_ij(q) u_j(t - nk_ij) + C_i(q)/D_i(q) e_i(t)``;
MIMO ARX models may couple outputs through a matrix polynomial ``A`` (``a[i][k]``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_2d, as_int, real_array
from .._measured import as_horizon, as_measured, predict_args
from ..errors import DataError, ShapeError
from ..models.attributes import Coefficients, SampleTime
from ..models.protocol import ModelMixin

Poly = np.ndarray


def _monic(c: Any) -> np.ndarray:
    return np.concatenate([[1.0], np.asarray(c, dtype=float).ravel()])


def _fmt(name: str, coef: np.ndarray, monic: bool, first: int = 0) -> str:
    """``name(q) = ...`` with ``coef[k]`` the coefficient of ``q^-(first + k)``."""
    if coef.size == 0:
        return f"{name}(q) = 0"
    parts = []
    for k, v in enumerate(coef, start=first):
        term = "1" if (k == 0 and monic) else f"{abs(v):.4g}" + (f" q^-{k}" if k else "")
        parts.append(("-" if v < 0 else "+", term))
    head = ("-" if parts[0][0] == "-" else "") + parts[0][1]
    return f"{name}(q) = " + head + "".join(f" {sg} {t}" for sg, t in parts[1:])


def _rest(x0: Any) -> None:
    if x0 is not None and not (isinstance(x0, str) and x0 == "zero"):
        raise DataError("polynomial models start from rest: x0 must be None or 'zero'")


def _names(names: Any, count: int, what: str) -> list[str]:
    out = [str(n) for n in names]
    if len(out) != count:
        raise DataError(f"{len(out)} {what} names given for {count} {what}s")
    return out


_LAYOUT = {"a": "outputs x outputs, a[i][k]: the lags of output k in output i's equation",
           "b": "outputs x inputs, b[i][j]: B of input j in output i's equation",
           "f": "outputs x inputs, f[i][j]: the free coefficients of the monic F_ij"}


def _coefficients(x: Any, name: str) -> np.ndarray:
    """One polynomial's coefficients as a flat float array (a number: one coefficient)."""
    return real_array(x, name).ravel()


def _is_row(x: Any) -> bool:
    return isinstance(x, (list, tuple)) or (isinstance(x, np.ndarray) and x.ndim >= 1)


def _poly_grid(x: Any, name: str, rows: int | None, cols: int | None
               ) -> list[list[np.ndarray]]:
    """``x[i][j]`` as coefficient arrays, ``rows x cols`` (``rows=None``: as many rows as
    given, then ``cols=None``: as many columns as rows, ``a``'s square; ``cols=None`` alone:
    every row as long as the first); a flat or ragged nesting raises a :class:`DataError`
    saying the layout."""
    example = {"a": "a=[[[-0.5]]]", "b": "b=[[[1.0, 0.5]]]", "f": "f=[[[-0.7]]]"}[name]
    layout = (f"{name} must be nested lists of coefficient arrays ({_LAYOUT[name]}; for one "
              f"output and one input {example})")
    if not _is_row(x) or not all(_is_row(r) for r in x):
        raise DataError(f"{layout}, got {x!r:.60}")
    grid = [[_coefficients(v, f"{name}[{i}][{j}]") for j, v in enumerate(r)]
            for i, r in enumerate(x)]
    if rows is None:
        rows = cols = len(grid)
    elif cols is None:
        cols = len(grid[0]) if grid else 0
    shape = [len(r) for r in grid]
    if len(grid) != rows or any(n != cols for n in shape):
        raise ShapeError(f"{name} has {len(grid)} row(s) of {shape} entries but should be "
                         f"{rows} x {cols} ({_LAYOUT[name]})")
    return grid


def _per_output(x: Any, name: str, ny: int) -> list[np.ndarray]:
    """``c`` or ``d``: one coefficient array per output (``None`` or ``[]``: none)."""
    if x is None or (isinstance(x, (list, tuple)) and len(x) == 0):
        return [np.zeros(0) for _ in range(ny)]
    if not _is_row(x) or len(x) != ny:
        raise ShapeError(f"{name} must hold one coefficient array per output ({ny}: "
                         f"{name}[i] the free coefficients of the monic {name.upper()}_i, e.g. "
                         f"{name}=[[0.5]] for one output), got {x!r:.60}")
    return [_coefficients(v, f"{name}[{i}]") for i, v in enumerate(x)]


def _delays(nk: Any, ny: int, nu: int) -> np.ndarray:
    """The input delays as an ``(ny, nu)`` integer array (a number: every channel's)."""
    try:
        grid = np.array(nk, dtype=object)
    except (TypeError, ValueError):
        grid = np.array(None, dtype=object)
    if grid.ndim == 0 and grid.item() is not None:
        grid = np.full((ny, nu), grid.item(), dtype=object)
    elif grid.ndim == 1 and ny == 1:
        grid = grid.reshape(1, -1)
    if grid.shape != (ny, nu):
        raise ShapeError(f"nk has shape {grid.shape} but should be ({ny}, {nu}): one delay "
                         f"per output (row) and input (column), or one number for all")
    out = np.zeros((ny, nu), dtype=int)
    for (i, j), v in np.ndenumerate(grid):
        try:
            out[i, j] = as_int(v, f"nk[{i}][{j}]", 0)
        except DataError as e:
            raise DataError(f"nk must hold delays >= 0 in whole samples (integer-valued "
                            f"floats such as 2.0 are taken): {e}") from None
    return out


def _variances(nv: Any, ny: int) -> np.ndarray:
    """The innovation variances: one per output (a number for one output) or ``ny x ny``."""
    if nv is None:
        return np.ones(ny)
    out = real_array(nv, "noise_variance")
    if out.ndim == 0 and ny == 1:
        out = out.reshape(1)
    if out.shape not in ((ny,), (ny, ny)):
        raise ShapeError(f"noise_variance has shape {out.shape} but should be ({ny},), one "
                         f"innovation variance per output (or a ({ny}, {ny}) covariance)")
    if not (np.all(np.isfinite(out)) and np.all(out >= 0)):
        raise DataError(f"noise_variance must be finite and >= 0, got {out.tolist()}")
    return out


def _trim(num: np.ndarray) -> np.ndarray:
    t = np.trim_zeros(num, "f")
    return t if t.size else np.zeros(1)


class PolynomialModel(ModelMixin):
    """A (MIMO) polynomial model; see the module docstring for the equations.

    Parameters
    ----------
    a : list of lists of arrays
        ``a[i][k]``: free coefficients ``a_1..a_na`` of output ``k`` in the equation of
        output ``i`` (the diagonal entries are the monic ``A_i`` without the leading 1).
    b, f : list of lists of arrays
        ``b[i][j]`` (``b_0..``) and ``f[i][j]`` (free coefficients of the monic ``F_ij``).
    c, d : list of arrays
        Free coefficients of the monic ``C_i`` and ``D_i``.
    nk : array_like of int, shape (n_outputs, n_inputs)
        Input delays.
    dt : float
        Sample time.
    noise_variance : array_like, optional
        Innovation variance per output.

    Examples
    --------
    >>> import numpy as np
    >>> m = PolynomialModel(a=[[np.array([-0.5])]], b=[[np.array([1.0])]], nk=[[1]], dt=1.0)
    >>> m.simulate(np.ones((3, 1))).ravel().tolist()
    [0.0, 1.0, 1.5]
    """

    #: replacing one by another drops the uncertainty (``noise_variance`` keeps it: no std
    #: result reads it); ``dt`` is checked whenever written
    a = Coefficients()
    b = Coefficients()
    c = Coefficients()
    d = Coefficients()
    f = Coefficients()
    nk = Coefficients()
    dt = SampleTime()

    def __init__(
        self,
        a: Any,
        b: Any,
        nk: Any,
        dt: float,
        *,
        c: Any = None,
        d: Any = None,
        f: Any = None,
        noise_variance: Any = None,
    ) -> None:
        self.a = _poly_grid(a, "a", None, None)
        ny = len(self.a)
        if ny == 0:
            raise DataError("a model needs at least one output: a must be nested as "
                            "a[i][k] (e.g. a=[[[-0.5]]], or a=[[[]]] for no A)")
        self.b = _poly_grid(b, "b", ny, None)
        nu = len(self.b[0])
        self.nk = _delays(nk, ny, nu)
        self.c = _per_output(c, "c", ny)
        self.d = _per_output(d, "d", ny)
        no_f = f is None or (isinstance(f, (list, tuple)) and len(f) == 0)
        self.f = ([[np.zeros(0) for _ in range(nu)] for _ in range(ny)] if no_f
                  else _poly_grid(f, "f", ny, nu))
        self.dt = dt
        self.noise_variance = _variances(noise_variance, ny)
        self.uncertainty: Any = None
        self.info: dict[str, Any] = {}
        for name, rows in (("a", self.a), ("b", self.b), ("f", self.f), ("c", [self.c]),
                           ("d", [self.d])):
            for i, row in enumerate(rows):
                for j, x in enumerate(row):
                    if not np.all(np.isfinite(x)):
                        at = f"[{j}]" if name in ("c", "d") else f"[{i}][{j}]"
                        raise DataError(f"{name}{at} has a non-finite coefficient (NaN or "
                                        f"Inf): {x}; every coefficient must be finite")

    @property
    def n_outputs(self) -> int:
        """Number of outputs."""
        return len(self.a)

    @property
    def n_inputs(self) -> int:
        """Number of inputs."""
        return len(self.b[0]) if self.b else 0

    @property
    def coupled(self) -> bool:
        """``True`` when ``A`` couples outputs (off-diagonal terms)."""
        return any(
            self.a[i][k].size
            for i in range(self.n_outputs)
            for k in range(self.n_outputs)
            if i != k
        )

    @property
    def prediction_is_simulation(self) -> bool:
        """``True`` for an output-error structure (no ``A``, ``C``, ``D``: the noise model is
        1), whose predictions at every horizon are its simulation."""
        return (self.n_inputs > 0 and not self.coupled
                and all(_monic(self.a[i][i]).size == 1 and _monic(self.c[i]).size == 1
                        and _monic(self.d[i]).size == 1 for i in range(self.n_outputs)))

    @property
    def statespace_predicts(self) -> bool:
        """``True`` when :meth:`to_statespace` exists with the noise model (every structure
        but a coupled one with ``F`` or ``D``): its predictions are this model's, and
        :func:`sysid.compare` fits their initial state."""
        if self.coupled:
            return not any(x.size for row in self.f for x in row) and not any(
                x.size for x in self.d)
        return True

    # -- the model protocol (sysid.Model) ------------------------------------------------
    ninputs = property(lambda self: self.n_inputs, doc="Number of inputs (protocol name).")
    noutputs = property(lambda self: self.n_outputs, doc="Number of outputs (protocol name).")

    @property
    def input_names(self) -> list[str]:
        """Input channel names (``u0, u1, ...`` unless set)."""
        names = getattr(self, "_input_names", None)
        return list(names) if names is not None else [f"u{j}" for j in range(self.n_inputs)]

    @input_names.setter
    def input_names(self, names: Any) -> None:
        self._input_names = None if names is None else _names(names, self.n_inputs, "input")

    @property
    def output_names(self) -> list[str]:
        """Output channel names (``y0, y1, ...`` unless set)."""
        names = getattr(self, "_output_names", None)
        return list(names) if names is not None else [f"y{i}" for i in range(self.n_outputs)]

    @output_names.setter
    def output_names(self, names: Any) -> None:
        self._output_names = None if names is None else _names(names, self.n_outputs, "output")

    @property
    def n_parameters(self) -> int:
        """Free coefficients: every entry of ``a``, ``b``, ``c``, ``d`` and ``f``.

        Examples
        --------
        >>> PolynomialModel([[[-0.5, 0.1]]], [[[1.0, 0.3]]], [[1]], 1.0, c=[[0.2]]).n_parameters
        5
        """
        count = sum(x.size for row in self.a for x in row)
        count += sum(x.size for row in self.b for x in row)
        count += sum(x.size for row in self.f for x in row)
        return int(count + sum(x.size for x in self.c) + sum(x.size for x in self.d))

    def to_dict(self) -> dict[str, Any]:
        """Coefficients, delays, sample time, names and info (see :func:`sysid.save_model`)."""
        return {"a": [list(row) for row in self.a], "b": [list(row) for row in self.b],
                "f": [list(row) for row in self.f], "c": list(self.c), "d": list(self.d),
                "nk": self.nk, "dt": self.dt, "noise_variance": self.noise_variance,
                "input_names": self.input_names, "output_names": self.output_names,
                "info": self.info}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> PolynomialModel:
        """Inverse of :meth:`to_dict`."""
        m = cls(d["a"], d["b"], d["nk"], float(d["dt"]), c=d.get("c"), d=d.get("d"),
                f=d.get("f"), noise_variance=d.get("noise_variance"))
        m.input_names, m.output_names = d.get("input_names"), d.get("output_names")
        m.info = dict(d.get("info") or {})
        return m

    def _check_u(self, u: Any) -> np.ndarray:
        """``u`` real, finite and ``(n_samples, n_inputs)`` (complex or NaN input refused)."""
        return np.ascontiguousarray(as_2d(u, "u", ncols=self.n_inputs,
                                          allow_empty=self.n_inputs == 0))

    def _deterministic(self, u: np.ndarray, i: int) -> np.ndarray:
        """``sum_j B_ij/F_ij u_j(t - nk_ij)`` (Rust filter)."""
        n = u.shape[0]
        w = np.zeros(n)
        for j in range(self.n_inputs):
            x = np.zeros(n)
            k = int(self.nk[i, j])
            if k < n:
                x[k:] = u[: n - k, j]
            w += _sysid.poly_filter(list(self.b[i][j]), list(_monic(self.f[i][j])), x)
        return w

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Noise-free output for input ``u`` (from rest), ``(n_samples, n_outputs)``.

        ``x0`` must be ``None`` or ``"zero"``: polynomial filters start from rest.
        """
        _rest(x0)
        u = self._check_u(u)
        ny = self.n_outputs
        w = np.column_stack([self._deterministic(u, i) for i in range(ny)])
        if not self.coupled:
            return np.column_stack([  # a column of w is strided: the filter takes contiguous
                _sysid.poly_filter([1.0], list(_monic(self.a[i][i])), np.ascontiguousarray(w[:, i]))
                for i in range(ny)])
        return np.asarray(_sysid.arx_matrix_filter(self._a_lists(), np.ascontiguousarray(w)))

    def _a_lists(self) -> list[list[list[float]]]:
        return [[[float(v) for v in self.a[i][k]] for k in range(self.n_outputs)]
                for i in range(self.n_outputs)]

    def residuals(self, u: Any, y: Any) -> np.ndarray:
        """One-step prediction errors ``e = D/C (A y - sum B/F u)`` (matrix ``A`` for a
        coupled MIMO ARX model)."""
        u, y = as_measured(u, y, self.n_inputs, self.n_outputs)
        if self.coupled:
            return y - self._coupled_predict(u, y, 1)
        out = []
        for i in range(self.n_outputs):
            v = _sysid.poly_filter(list(_monic(self.a[i][i])), [1.0], np.ascontiguousarray(y[:, i]))
            v = v - self._deterministic(u, i)
            out.append(_sysid.poly_filter(list(_monic(self.d[i])), list(_monic(self.c[i])), v))
        return np.column_stack(out)

    def predict(self, u: Any, y: Any = None, horizon: int = 1, x0: Any = None) -> np.ndarray:
        """``horizon``-step-ahead prediction ``yhat(t | t - horizon)``.

        With ``H_i = C_i / (A_i D_i)`` the noise filter of output ``i`` and ``h_0 = 1, h_1,
        ...`` its impulse response, ``yhat(t | t - k) = y(t) - sum_{j<k} h_j e(t - j)``,
        where ``e`` are the one-step prediction errors (:meth:`residuals`): the part of
        ``y(t)`` driven by innovations not yet seen at ``t - k`` is removed. ``k = 1``
        gives ``y - e``; as ``k`` grows the prediction tends to the simulation. A coupled
        MIMO ARX model iterates its matrix difference equation instead.

        Examples
        --------
        >>> import numpy as np
        >>> m = PolynomialModel([[[-0.5]]], [[[0.0]]], [[1]], 1.0)   # y = e / (1 - 0.5 q^-1)
        >>> m.predict(np.zeros((3, 1)), [1.0, 0.5, 0.25], horizon=2)[:, 0]
        array([0.  , 0.  , 0.25])
        """
        _rest(x0)
        h = as_horizon(horizon)  # np.inf: MATLAB's predict(..., Inf), the simulation
        u, y2 = as_measured(*predict_args(u, y), self.n_inputs, self.n_outputs)
        k = np.iinfo(np.int64).max if h is None else h
        if k >= max(y2.shape[0], 1):  # every innovation is unseen: the simulation from rest
            return np.asarray(self.simulate(u), dtype=float).reshape(u.shape[0], -1)
        if self.coupled:
            return self._coupled_predict(u, y2, k)
        e = self.residuals(u, y2)
        out = y2 - e
        if k > 1:
            for i in range(self.n_outputs):
                pulse = np.zeros(k)
                pulse[0] = 1.0
                den = np.convolve(_monic(self.a[i][i]), _monic(self.d[i]))
                h = _sysid.poly_filter(list(_monic(self.c[i])), list(den), pulse)
                # yhat = y - sum_{j<k} h_j e(t - j): remove the innovations after t - k
                out[:, i] = y2[:, i] - np.convolve(e[:, i], h)[: y2.shape[0]]
        return out

    def _coupled_predict(self, u: np.ndarray, y: np.ndarray, k: int) -> np.ndarray:
        """``yhat(t | t - k)`` of a MIMO ARX model ``sum_l A_l y(t - l) = w(t) + e(t)``.

        ``P_0 = y`` and ``P_j(t) = w(t) - sum_{l>=1} A_l P_{max(j - l, 0)}(t - l)``: the
        prediction ``j`` steps ahead uses measured outputs where they are known and
        shorter-range predictions where not (future innovations have mean zero). The
        recursion runs in Rust (``sysid_core::polynomial::filter::arx_matrix_filter``).
        """
        if y.shape != (u.shape[0], self.n_outputs):
            raise DataError(f"y has shape {y.shape} but should be ({u.shape[0]}, "
                            f"{self.n_outputs})")
        ny = y.shape[1]
        w = np.column_stack([self._deterministic(u, i) for i in range(ny)])
        return np.asarray(_sysid.arx_matrix_filter(self._a_lists(), np.ascontiguousarray(w),
                                                   np.ascontiguousarray(y), k))

    def freqresp(self, w: Any, std: bool = False) -> Any:
        """Frequency response ``(len(w), n_outputs, n_inputs)`` at ``w`` (rad/s); with
        ``std=True`` (needs :attr:`uncertainty`) the pair ``(H, sd)``, ``sd`` complex (std of
        the real and imaginary parts, first order)."""
        if std:
            from ..models.uncertainty import freqresp_std

            return freqresp_std(self, w)
        if self.coupled:  # A(q)^-1 B(q): through the exact state-space form
            return self.to_statespace().freqresp(w)
        z1 = np.exp(-1j * np.asarray(w, float) * self.dt)
        out = np.zeros((z1.size, self.n_outputs, self.n_inputs), complex)
        for i in range(self.n_outputs):
            a = np.polyval(_monic(self.a[i][i])[::-1], z1)
            for j in range(self.n_inputs):
                bb = np.polyval(self.b[i][j][::-1], z1) * z1 ** int(self.nk[i, j])
                ff = np.polyval(_monic(self.f[i][j])[::-1], z1)
                out[:, i, j] = bb / (a * ff)
        return out

    def poles(self, std: bool = False, method: str = "linear") -> Any:
        """Roots of ``A_i F_ij`` over all channels; with a coupled ``A`` (MIMO ARX) the roots
        of ``det A`` (the eigenvalues of its block companion matrix) in place of the
        ``A_i``'s. With ``std=True`` (needs :attr:`uncertainty`) the pair ``(poles, sd)`` as
        for :meth:`sysid.StateSpaceModel.poles`.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> a = [[np.array([-0.5]), np.array([0.4])], [np.array([0.0]), np.array([-0.2])]]
        >>> m = sysid.PolynomialModel(a=a, b=[[np.array([1.0])], [np.array([1.0])]],
        ...                           nk=[[1], [1]], dt=1.0)
        >>> np.sort(m.poles().real).round(6).tolist()
        [0.2, 0.5]
        """
        if std:
            from ..models.pole_uncertainty import pole_std

            return pole_std(self, method)
        r = self._pole_sets()
        return np.concatenate(r) if r else np.zeros(0)

    def _pole_sets(self) -> list[np.ndarray]:
        """The roots of each polynomial in :meth:`poles`' order: ``det A`` (coupled) or each
        ``A_i``, then each ``F_ij``."""
        r = [self._coupled_poles()] if self.coupled else []
        for i in range(self.n_outputs):
            if not self.coupled:
                r.append(np.roots(_monic(self.a[i][i])))
            for j in range(self.n_inputs):
                r.append(np.roots(_monic(self.f[i][j])))
        return r

    def pole_groups(self) -> list[int]:
        """How many of :meth:`poles` each polynomial contributes, in their order: the roots of
        different polynomials (``A_i``, ``F_ij``) are independent, so a pole only coincides
        with a root of its own polynomial (:func:`sysid.models.pole_uncertainty.pole_std`).

        Examples
        --------
        >>> import numpy as np, sysid
        >>> m = sysid.PolynomialModel(a=[[np.zeros(0)]], b=[[np.ones(1), np.ones(1)]],
        ...                           f=[[np.array([-0.5]), np.array([-0.5, 0.1])]],
        ...                           nk=[[1, 1]], dt=1.0)
        >>> m.pole_groups()
        [0, 1, 2]
        """
        return [int(r.size) for r in self._pole_sets()]

    def is_stable(self) -> bool:
        """True when every pole (:meth:`poles`: the roots of ``A F``, the measured part's, as
        MATLAB's ``isstable``) lies strictly inside the unit circle.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> m = sysid.PolynomialModel(a=[[np.array([-0.5])]], b=[[np.array([1.0])]],
        ...                           nk=[[1]], dt=1.0)
        >>> m.is_stable()
        True
        """
        p = self.poles()
        return bool(p.size == 0 or np.max(np.abs(p)) < 1.0)

    def _coupled_poles(self) -> np.ndarray:
        """Eigenvalues of the block companion matrix of ``A(q) = I + A_1 q^-1 + ...``."""
        ny = self.n_outputs
        n = max(x.size for row in self.a for x in row)
        if n == 0:
            return np.zeros(0, complex)
        M = np.zeros((n * ny, n * ny))
        for i in range(ny):
            for k in range(ny):
                c = self.a[i][k]
                for lag in range(c.size):
                    M[i, lag * ny + k] = -c[lag]
        M[ny:, :-ny] = np.eye((n - 1) * ny)
        return np.linalg.eigvals(M).astype(complex)

    def _channel_tf(self, i: int, j: int) -> tuple[np.ndarray, np.ndarray]:
        """``(num, den)`` of channel ``(i, j)`` in powers of ``z`` (equal lengths)."""
        if self.coupled:
            raise DataError("transfer functions of a coupled MIMO ARX model are not implemented")
        num = np.concatenate([np.zeros(int(self.nk[i, j])), self.b[i][j]])
        den = np.convolve(_monic(self.a[i][i]), _monic(self.f[i][j]))
        n = max(num.size, den.size)
        return np.pad(num, (0, n - num.size)), np.pad(den, (0, n - den.size))

    def zeros(self) -> np.ndarray:
        """Zeros of every ``B_ij`` (in ``z``), concatenated; for a coupled MIMO ARX model the
        transmission zeros of its state-space form."""
        if self.coupled:
            return np.asarray(self.to_statespace().zeros())
        out = [
            np.roots(self._channel_tf(i, j)[0])
            for i in range(self.n_outputs)
            for j in range(self.n_inputs)
        ]
        return np.concatenate(out) if out else np.zeros(0)

    def to_scipy(self) -> Any:
        """SciPy ``dlti`` transfer function (single input, single output)."""
        from scipy import signal

        if (self.n_outputs, self.n_inputs) != (1, 1):
            raise DataError("to_scipy: only single-input single-output models; use to_statespace")
        num, den = self._channel_tf(0, 0)
        return signal.dlti(_trim(num), den, dt=self.dt)

    def to_control(self) -> Any:
        """python-control ``TransferFunction`` (MIMO as nested lists of channels)."""
        import control

        nums = [
            [self._channel_tf(i, j)[0] for j in range(self.n_inputs)] for i in range(self.n_outputs)
        ]
        dens = [
            [self._channel_tf(i, j)[1] for j in range(self.n_inputs)] for i in range(self.n_outputs)
        ]
        return control.tf(nums, dens, self.dt)

    def _select(self, iy: list[int], iu: list[int]) -> PolynomialModel:
        """Outputs ``iy`` from inputs ``iu`` (:meth:`select`); a model whose ``A`` couples
        the outputs has no polynomial subsystem (each output's equation holds the others)."""
        from ..models.subsystem import names

        if self.coupled:
            raise DataError("this polynomial model's A couples its outputs, so no polynomial "
                            "model holds some of them alone: select from its state-space "
                            "form, model.to_statespace().select(...)")
        out = PolynomialModel(
            [[self.a[i][k] for k in iy] for i in iy], [[self.b[i][j] for j in iu] for i in iy],
            self.nk[np.ix_(iy, iu)], self.dt, c=[self.c[i] for i in iy],
            d=[self.d[i] for i in iy], f=[[self.f[i][j] for j in iu] for i in iy],
            noise_variance=self.noise_variance[iy])
        out.input_names, out.output_names = names(self.input_names, iu), names(
            self.output_names, iy)
        out.info = dict(self.info)
        return out

    def to_statespace(self) -> Any:
        """The model as a :class:`~sysid.StateSpaceModel` in innovations form, noise model
        included (MATLAB's ``idss(m)``): ARX and ARMAX structures in observer form per
        output (``K`` from ``C`` and ``A``), others as one block per input channel and a
        noise block per output; an output-error model has no ``K``. A time series is its
        noise model (``B``, ``D`` empty); a coupled MIMO ARX model (matrix ``A``) is realised
        whole. The simulation and the predictions are this model's
        (:mod:`sysid.polynomial.statespace_form`), and so is the parameter uncertainty: the
        same parameters seen through the realisation (:mod:`sysid.models.carried`).

        Examples
        --------
        >>> m = PolynomialModel([[[-0.5]]], [[]], [[]], 1.0)   # AR(1): y = e / (1 - 0.5 q^-1)
        >>> ss = m.to_statespace()
        >>> ss.poles().real, ss.K.shape, ss.B.shape
        (array([0.5]), (1, 1), (1, 0))
        """
        from ..models.carried import carry
        from .statespace_form import realize

        return carry(self, realize(self), realize)

    def __repr__(self) -> str:
        """The equations with the model's channel names (``y0``, ``u0`` or the data's); the
        polynomials are labelled by their indices in ``a``, ``b``, ``f`` (``B1`` is
        ``b[i][1]``, the input ``input_names[1]``'s; ``A01`` is ``a[0][1]``).

        Examples
        --------
        >>> import numpy as np, sysid
        >>> m = sysid.PolynomialModel([[[-0.5]]], [[[1.0]]], [[1]], 1.0)
        >>> m.input_names, m.output_names = ["flow"], ["level"]
        >>> print(m)
        PolynomialModel: 1 output(s), 1 input(s), dt=1
          level: A(q) level(t) = B0(q) flow(t-1) + e(t)
            A(q) = 1 - 0.5 q^-1
            B0(q) = 1
        """
        ys, us = self.output_names, self.input_names
        lines = [
            f"PolynomialModel: {self.n_outputs} output(s), {self.n_inputs} input(s), dt={self.dt:g}"
        ]
        for i in range(self.n_outputs):
            rhs = " + ".join(
                f"B{j}(q)/F{j}(q) {us[j]}(t-{self.nk[i, j]})"
                if self.f[i][j].size
                else f"B{j}(q) {us[j]}(t-{self.nk[i, j]})"
                for j in range(self.n_inputs)
            )
            noise = (
                "C(q)/D(q) e(t)" if self.d[i].size else ("C(q) e(t)" if self.c[i].size else "e(t)")
            )
            if self.coupled:  # row i of a matrix polynomial: A_ii alone is not its poles
                ny = self.n_outputs
                sep = "" if ny < 10 else ","
                ks = [k for k in range(ny) if k == i or self.a[i][k].size]
                lhs = " + ".join(f"A{i}{sep}{k}(q) {ys[k]}(t)" for k in ks)
                lines.append(f"  {ys[i]}: {lhs} = {rhs + ' + ' if rhs else ''}{noise}")
                lines.append(f"    ({ys[i]}'s row of A, a {ny}x{ny} matrix polynomial coupling "
                             "the outputs: the poles are those of det A(q), model.poles())")
                for k in ks:
                    lines.append("    " + (_fmt(f"A{i}{sep}{k}", _monic(self.a[i][k]), True)
                                           if k == i else
                                           _fmt(f"A{i}{sep}{k}", self.a[i][k], False, first=1)))
            else:
                lines.append(f"  {ys[i]}: A(q) {ys[i]}(t) = {rhs + ' + ' if rhs else ''}{noise}")
                lines.append("    " + _fmt("A", _monic(self.a[i][i]), True))
            for j in range(self.n_inputs):
                lines.append("    " + _fmt(f"B{j}", self.b[i][j], False))
                if self.f[i][j].size:
                    lines.append("    " + _fmt(f"F{j}", _monic(self.f[i][j]), True))
            if self.c[i].size:
                lines.append("    " + _fmt("C", _monic(self.c[i]), True))
            if self.d[i].size:
                lines.append("    " + _fmt("D", _monic(self.d[i]), True))
        return "\n".join(lines)

    # -- parameter uncertainty (sysid.models.uncertainty) ---------------------------------
    def _coefficients(self) -> list[np.ndarray]:
        """Every coefficient array, in the order a, b, c, d, f (row by row)."""
        return ([x for row in self.a for x in row] + [x for row in self.b for x in row]
                + list(self.c) + list(self.d) + [x for row in self.f for x in row])

    @property
    def std(self) -> dict[str, Any] | None:
        """Standard deviations of the coefficients, nested like ``a, b, c, d, f``; ``None``
        without :attr:`uncertainty`.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> rng = np.random.default_rng(0)
        >>> u = rng.standard_normal((500, 1))
        >>> y = np.zeros((500, 1))
        >>> for t in range(1, 500): y[t] = 0.5 * y[t - 1] + u[t - 1] + 0.1 * rng.standard_normal()
        >>> m = sysid.arx(sysid.IOData(u, y, 1.0), 1, 1, 1)
        >>> sd = m.std
        >>> bool(0.002 < sd["a"][0][0][0] < 0.01), bool(0.002 < sd["b"][0][0][0] < 0.01)
        (True, True)
        """
        if self.uncertainty is None:
            return None
        from ..models.uncertainty import complex_std

        _, sd = complex_std(self, lambda m: np.concatenate(
            [np.zeros(0)] + [np.asarray(x, float).ravel() for x in m._coefficients()]))
        it = iter(sd.tolist())

        def take(x: np.ndarray) -> np.ndarray:
            return np.array([next(it) for _ in range(np.asarray(x).size)])

        a = [[take(x) for x in row] for row in self.a]
        b = [[take(x) for x in row] for row in self.b]
        c = [take(x) for x in self.c]
        d = [take(x) for x in self.d]
        f = [[take(x) for x in row] for row in self.f]
        return {"a": a, "b": b, "c": c, "d": d, "f": f}
