"""Arithmetic of frequency-response data: sums, series (matrix) products, inverses and
feedback of :class:`sysid.FRD` objects, one frequency at a time.

:class:`FRDAlgebra` is the part of :class:`sysid.FRD` that combines responses. The other
operand can be an FRD on the same frequency grid, a model with ``freqresp(omega)`` (evaluated
on the FRD's grid, taken as exact), a scalar or a constant gain matrix. ``G1 * G2`` is the
series connection *G1 after G2* (MATLAB's ``G1*G2``): the matrix product
``G1(w) @ G2(w)`` at each frequency. The result is on this FRD's grid, in its units (or the
other FRD's), with the sample time the operands agree on (none when two FRDs differ; a
model's is not checked: it is evaluated at the grid's frequencies in rad/s as it stands).

Uncertainty is carried to first order: the complex errors of the entries of an operand are
taken as independent and circular (``E|dG|^2 = std^2``, ``E dG^2 = 0``, as :class:`sysid.FRD`
defines its std). Each operation (including ``/``, :meth:`FRDAlgebra.inv` and
:meth:`FRDAlgebra.feedback`) is linearised as one step, which holds while the std is small
against the responses (for an inverse: against the smallest singular value).

Two operands are taken as **independent** of each other, except when they are the same
response: the same FRD object, or two FRDs on the very same ``response`` and ``std`` arrays
(a shallow copy). Then the two errors are one and the same (fully correlated) and the std
comes from the full derivative of the operation in that response: ``G - G`` and ``G / G``
have std 0, ``G + G`` twice G's, ``G * G`` (one output and one input) ``2 |G| std``,
``G @ G`` ``dG G + G dG`` and ``G.feedback(G)`` ``S dG Si + sign T dG T``. Any other pair is
independent, also two separately built FRDs holding equal numbers (``sysid.FRD(G.omega,
G.response, std=G.std)`` copies them) and a response with a part or a result of itself
(``G[0, 0] * G``, ``(G + H) - H``): for those the std is wrong, as it is for feedback around
a loop that shares a measurement.

Only a std per entry is kept. After one operation on a MIMO response the errors of its
entries are correlated; a further operation takes them as independent again, so the std of
a chain of MIMO operations is an approximation (for one output and one input it is
first-order exact as long as no operand enters it twice other than as the same object).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError, ShapeError

__all__ = ["FRDAlgebra", "check_grid"]


def check_grid(a: Any, b: Any, fix: str) -> None:
    """Refuse two FRDs on different frequency grids, naming the grids and ``fix``."""
    if b.omega.shape != a.omega.shape or not np.allclose(b.omega, a.omega):
        raise DataError(
            f"the two FRDs are on different frequency grids ({b.omega.size} frequencies "
            f"{b.omega.min():.4g}..{b.omega.max():.4g} rad/s, this one {a.omega.size} in "
            f"{a.omega.min():.4g}..{a.omega.max():.4g}); {fix}")


_GRID_FIX = ("estimate both on one grid (spa's omega=, the same nperseg / lines), or resample "
             "one onto the other's grid first: sysid.FRD.from_model(b, a.omega) interpolates b "
             "linearly between its frequencies (without its std)")


def _sandwich(left: np.ndarray | None, var: np.ndarray, right: np.ndarray | None) -> np.ndarray:
    """First-order variance of ``L @ dX @ R`` per frequency for independent circular entries
    of ``dX`` with variances ``var``: ``|L|^2 @ var @ |R|^2`` (``None``: the identity)."""
    out = var
    if left is not None:
        out = np.abs(left) ** 2 @ out
    if right is not None:
        out = out @ np.abs(right) ** 2
    return out


def _sandwiches(terms: list[tuple[np.ndarray | None, np.ndarray | None]],
                var: np.ndarray) -> np.ndarray:
    """First-order variance of ``sum_t L_t @ dX @ R_t`` per frequency (one error ``dX`` entering
    several times, its entries independent and circular with variances ``var``): the
    coefficient of ``dX[p, q]`` in entry ``(i, j)`` is ``sum_t L_t[i, p] R_t[q, j]``."""
    nf, n_p, n_q = var.shape
    coef: Any = 0.0
    for left, right in terms:
        lt = np.broadcast_to(np.eye(n_p), (nf, n_p, n_p)) if left is None else left
        rt = np.broadcast_to(np.eye(n_q), (nf, n_q, n_q)) if right is None else right
        coef = coef + np.einsum("fip,fqj->fijpq", lt, rt)
    return np.einsum("fijpq,fpq->fij", np.abs(coef) ** 2, var)


def _same_array(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    """``a`` and ``b`` are the same array, or the same view of one buffer."""
    if a is None or b is None:
        return a is b
    return a is b or (a.shape == b.shape and a.strides == b.strides and a.dtype == b.dtype
                      and a.__array_interface__["data"][0] == b.__array_interface__["data"][0])


def _shared_var(x: Any, y: Any) -> np.ndarray | None:
    """The variance of the one error of two operands carrying the same uncertain response
    (fully correlated: the same FRD, or FRDs on the same response and std arrays), or
    ``None`` when they are not that (independent, or exact)."""
    if x is None or y is None or x.std is None:
        return None
    same = x is y or (_same_array(x.response, y.response) and _same_array(x.std, y.std)
                      and _same_array(x.omega, y.omega))
    return x.std ** 2 if same else None


class _Operand:
    """The other side of an operation, on this FRD's grid: response ``(n_freq, a, b)`` (or a
    scalar), its variance (``None``: exact) and what it says about channels and time."""

    def __init__(self, g: np.ndarray, var: np.ndarray | None, *, scalar: bool = False,
                 inputs: Any = None, outputs: Any = None, dt: float | None = None,
                 units: str | None = None, frd: Any = None) -> None:
        self.g, self.var, self.scalar = g, var, scalar
        self.inputs, self.outputs, self.dt, self.units, self.frd = inputs, outputs, dt, units, frd


class FRDAlgebra:
    """Operators of :class:`sysid.FRD`: ``+``, ``-``, ``*`` (also ``@``), ``/``, unary ``-``,
    :meth:`inv` and :meth:`feedback` (see the module docstring for the operands and the
    independence assumption of the propagated std)."""

    omega: np.ndarray
    response: np.ndarray
    std: np.ndarray | None
    coherence: np.ndarray | None
    confidence: float
    dof: float | None
    dt: float | None
    units: str | None
    input_names: list[str]
    output_names: list[str]
    method: str
    info: dict[str, Any]

    def _new(self, response: Any, *, units: str | None, **kw: Any) -> Any:
        raise NotImplementedError  # FRD: a new FRD on this grid

    # numpy arrays and numpy scalars on the left give way to __radd__, __rmul__, ...
    __array_ufunc__ = None

    # -- operands --------------------------------------------------------------------------

    def _operand(self, other: Any) -> _Operand | None:
        """``other`` on this grid, or ``None`` when it is nothing an FRD combines with."""
        if isinstance(other, FRDAlgebra):
            check_grid(self, other, _GRID_FIX)
            return _Operand(other.response, None if other.std is None else other.std ** 2,
                            inputs=other.input_names, outputs=other.output_names,
                            dt=other.dt, units=other.units, frd=other)
        if hasattr(other, "freqresp") and hasattr(other, "ninputs"):
            g = np.asarray(other.freqresp(self.omega), dtype=complex)
            if g.ndim != 3 or g.shape[0] != self.omega.size:
                raise ShapeError(f"the model's freqresp gave shape {g.shape}, not "
                                 f"({self.omega.size}, n_outputs, n_inputs)")
            return _Operand(g, None, inputs=getattr(other, "input_names", None),
                            outputs=getattr(other, "output_names", None))
        if isinstance(other, (str, bytes)):
            return None
        try:
            k = np.asarray(other, dtype=complex)
        except (TypeError, ValueError):
            return None
        if k.ndim == 0:
            return _Operand(k, None, scalar=True)
        if k.ndim != 2:
            raise ShapeError(f"a gain is a scalar or a constant (n_outputs, n_inputs) matrix, "
                             f"got shape {k.shape}; wrap a response per frequency in an FRD "
                             "first (sysid.FRD(frd.omega, response))")
        if not np.isfinite(k).all():
            raise DataError("the gain must be finite")
        return _Operand(np.broadcast_to(k, (self.omega.size, *k.shape)), None)

    def _derive(self, g: np.ndarray, var: np.ndarray | None, other: _Operand | None, *,
                inputs: Any = None, outputs: Any = None, coherence: Any = None,
                both_uncertain: bool = False) -> Any:
        """A new FRD on this grid with response ``g`` and std ``sqrt(var)``."""
        mine = self.std is not None
        theirs = other is not None and other.var is not None
        # the band level and dof of the one uncertain operand; dof is dropped (large-sample
        # limit) when two uncertain responses mix
        src = self if mine or not theirs else other.frd  # type: ignore[union-attr]
        dts = {d for d in (self.dt, None if other is None else other.dt) if d is not None}
        if var is not None and not np.isfinite(var).all():
            raise DataError("the propagated std is not finite (a response near a singular "
                            "matrix at some frequency)")
        return self._new(
            g, std=None if var is None else np.sqrt(var), coherence=coherence,
            confidence=src.confidence,
            dof=None if both_uncertain or var is None else src.dof,
            dt=dts.pop() if len(dts) == 1 else None, input_names=inputs, output_names=outputs,
            units=self.units or (None if other is None else other.units),
        )

    # -- sums --------------------------------------------------------------------------------

    def _sum(self, other: Any, sign: float, reflected: bool) -> Any:
        o = self._operand(other)
        if o is None:
            return NotImplemented
        b = np.broadcast_to(o.g, self.response.shape) if o.scalar else o.g
        if b.shape != self.response.shape:
            raise ShapeError(f"adding responses of shapes {self.response.shape[1:]} and "
                             f"{b.shape[1:]} (outputs x inputs): they must be the same")
        g = (b - self.response) if reflected and sign < 0 else self.response + sign * b
        if (v := _shared_var(self, o.frd)) is not None:  # G + G, G - G: one error, 1 + sign times
            return self._derive(g, (1.0 + sign) ** 2 * v, o, inputs=self.input_names,
                                outputs=self.output_names)
        variances = [v for v in (None if self.std is None else self.std ** 2, o.var)
                     if v is not None]
        var = sum(variances) if variances else None
        return self._derive(g, var, o, inputs=self.input_names, outputs=self.output_names,
                            both_uncertain=len(variances) == 2)

    def __add__(self, other: Any) -> Any:
        """Parallel connection ``G + other`` at each frequency.

        ``other`` is an FRD on the same grid, a model (evaluated on this grid), a scalar
        (added to every entry) or a constant matrix of the same shape. The std of independent
        operands adds in variance, ``sqrt(std_a^2 + std_b^2)``; other FRDs are taken as
        independent of G, except G itself (the same object or arrays): ``G + G`` has twice
        G's std and ``G - G`` std 0.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> a = sysid.FRD([1.0, 2.0], [1.0, 2.0], std=[0.3, 0.3])
        >>> b = sysid.FRD([1.0, 2.0], [1j, 1j], std=[0.4, 0.4])
        >>> (a + b).response[:, 0, 0], (a + b).std[:, 0, 0]
        (array([1.+1.j, 2.+1.j]), array([0.5, 0.5]))
        """
        return self._sum(other, 1.0, False)

    def __radd__(self, other: Any) -> Any:
        return self._sum(other, 1.0, True)

    def __sub__(self, other: Any) -> Any:
        """``G - other`` (see :meth:`__add__`; the variances of independent operands add here
        too, ``G - G`` has std 0).

        Examples
        --------
        >>> import sysid
        >>> (sysid.FRD([1.0, 2.0], [3.0, 4.0]) - 1).response[:, 0, 0]
        array([2.+0.j, 3.+0.j])
        """
        return self._sum(other, -1.0, False)

    def __rsub__(self, other: Any) -> Any:
        return self._sum(other, -1.0, True)

    def __neg__(self) -> Any:
        """``-G``: the response negated; std and coherence are unchanged.

        Examples
        --------
        >>> import sysid
        >>> (-sysid.FRD([1.0], [2.0 + 1.0j])).response[0, 0, 0]
        np.complex128(-2-1j)
        """
        return self._derive(-self.response, None if self.std is None else self.std ** 2, None,
                            inputs=self.input_names, outputs=self.output_names,
                            coherence=self.coherence)

    def __pos__(self) -> Any:
        return self

    # -- products ----------------------------------------------------------------------------

    def _product(self, left: _Operand, right: _Operand, me_left: bool) -> Any:
        a, va, b, vb = left.g, left.var, right.g, right.var
        other = right if me_left else left
        if left.scalar or right.scalar:  # a gain: scale, keep the FRD's channels
            k, frd = (left, right) if left.scalar else (right, left)
            g = k.g * frd.g
            var = None if frd.var is None else np.abs(k.g) ** 2 * frd.var
            return self._derive(g, var, other, inputs=self.input_names,
                                outputs=self.output_names,
                                coherence=self.coherence if k.g != 0 else None)
        if a.shape[2] != b.shape[1]:
            raise ShapeError(
                f"series connection {a.shape[1]}x{a.shape[2]} * {b.shape[1]}x{b.shape[2]} "
                f"(outputs x inputs): the left one's {a.shape[2]} input(s) must match the right "
                f"one's {b.shape[1]} output(s) (G1 * G2 is G1 after G2)")
        g = a @ b
        if (v := _shared_var(left.frd, right.frd)) is not None:  # G @ G: dG G + G dG
            return self._derive(g, _sandwiches([(None, b), (a, None)], v), other,
                                inputs=right.inputs, outputs=left.outputs)
        terms = [t for t in (None if va is None else _sandwich(None, va, b),
                             None if vb is None else _sandwich(a, vb, None)) if t is not None]
        return self._derive(g, sum(terms) if terms else None, other, inputs=right.inputs,
                            outputs=left.outputs, both_uncertain=len(terms) == 2)

    def _me(self) -> _Operand:
        return _Operand(self.response, None if self.std is None else self.std ** 2,
                        inputs=self.input_names, outputs=self.output_names, dt=self.dt,
                        units=self.units, frd=self)

    def __mul__(self, other: Any) -> Any:
        """Series connection ``G * other``: *G after other*, the matrix product
        ``G(w) @ other(w)`` at each frequency (MATLAB's ``G*other``).

        ``other`` is an FRD on the same grid, a model (evaluated on this grid), a scalar or a
        constant gain matrix. The result has G's outputs and other's inputs. For independent
        operands the std is first order: ``var = |G|^2 @ std_o^2 + std_G^2 @ |o|^2`` (for one
        pair, ``|G|^2 std_o^2 + |o|^2 std_G^2``); a scalar gain scales the std exactly. Other
        FRDs are taken as independent of G, except G itself (the same object or arrays):
        ``G * G`` is carried with ``d(G G) = dG G + G dG`` (one pair: std ``2 |G| std_G``).
        ``@`` is the same operation.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> g1 = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
        >>> g2 = sysid.StateSpaceModel([[0.2]], [[1.0]], [[2.0]])
        >>> w = np.linspace(0.1, 3.0, 5)
        >>> p = sysid.FRD.from_model(g1, w) * sysid.FRD.from_model(g2, w)
        >>> bool(np.allclose(p.response, g1.freqresp(w) * g2.freqresp(w)))
        True
        """
        o = self._operand(other)
        if o is None:
            return NotImplemented
        return self._product(self._me(), o, True)

    def __rmul__(self, other: Any) -> Any:
        o = self._operand(other)
        if o is None:
            return NotImplemented
        return self._product(o, self._me(), False)

    __matmul__ = __mul__
    __rmatmul__ = __rmul__

    def _quotient(self, left: _Operand, right: _Operand, me_left: bool) -> Any:
        """``left * inv(right)``, its std from ``d(L R^-1) = dL R^-1 - Q dR R^-1`` (one step:
        the entries of ``inv(right)`` are correlated, a product with them would not be)."""
        gi = _inverse_operand(right).g
        if not left.scalar and left.g.shape[2] != gi.shape[1]:
            raise ShapeError(f"{left.g.shape[1]}x{left.g.shape[2]} / {gi.shape[1]}x"
                             f"{gi.shape[2]} (outputs x inputs): the left one needs as many "
                             "inputs as the right one has outputs")
        q = left.g * gi if left.scalar else left.g @ gi
        if (v := _shared_var(left.frd, right.frd)) is not None:  # G / G: dG G^-1 - Q dG G^-1
            return self._derive(q, _sandwiches([(None, gi), (-q, gi)], v),
                                right if me_left else left, inputs=right.outputs,
                                outputs=left.outputs)
        terms = []
        if left.var is not None:
            terms.append(_sandwich(None, left.var, gi))
        if right.var is not None:
            terms.append(_sandwich(q, right.var, gi))
        outputs = right.inputs if left.scalar else left.outputs
        return self._derive(q, sum(terms) if terms else None, right if me_left else left,
                            inputs=right.outputs, outputs=outputs,
                            both_uncertain=len(terms) == 2)

    def __truediv__(self, other: Any) -> Any:
        """``G / other`` is ``G * inv(other)`` (MATLAB's ``G/other``); by a scalar it divides.
        The std is first order in one step, ``d(G o^-1) = dG o^-1 - G o^-1 do o^-1``, with
        ``dG`` and ``do`` independent unless ``other`` is G itself (the same object or arrays):
        ``G / G`` has std 0.

        Examples
        --------
        >>> import sysid
        >>> (sysid.FRD([1.0, 2.0], [2.0, 4.0]) / 2).response[:, 0, 0]
        array([1.+0.j, 2.+0.j])
        """
        o = self._operand(other)
        if o is None:
            return NotImplemented
        if o.scalar:
            if o.g == 0:
                raise DataError("division of an FRD by zero")
            return self._product(self._me(), _Operand(1.0 / o.g, None, scalar=True), True)
        return self._quotient(self._me(), o, True)

    def __rtruediv__(self, other: Any) -> Any:
        o = self._operand(other)
        if o is None:
            return NotImplemented
        return self._quotient(o, self._me(), False)

    # -- inverse and feedback ----------------------------------------------------------------

    def inv(self) -> Any:
        """The inverse response ``G(w)^{-1}`` of a square FRD (MATLAB's ``inv``).

        The std is carried to first order, ``dG^{-1} = -G^{-1} dG G^{-1}``:
        ``var = |G^{-1}|^2 @ std^2 @ |G^{-1}|^2`` (for one pair ``std / |G|^2``), with the
        entries' errors independent. It is only good while ``std`` is small against the
        smallest singular value of ``G``; the coherence is dropped.

        Examples
        --------
        >>> import sysid
        >>> g = sysid.FRD([1.0, 2.0], [2.0, 4j], std=[0.2, 0.4]).inv()
        >>> g.response[:, 0, 0], g.std[:, 0, 0]
        (array([0.5+0.j  , 0. -0.25j]), array([0.05 , 0.025]))
        """
        o = _inverse_operand(self._me())
        return self._derive(o.g, o.var, None, inputs=self.output_names,
                            outputs=self.input_names)

    def feedback(self, K: Any = 1.0, sign: float = -1.0) -> Any:
        """The closed loop of ``G`` (forward path) with ``K`` in the feedback path:
        ``(I - sign G K)^{-1} G`` (MATLAB's ``feedback(G, K)``; ``sign=-1`` is negative
        feedback).

        ``K`` is an FRD on the same grid, a model (evaluated on this grid), a scalar or a
        constant matrix, with as many outputs as G has inputs and as many inputs as G has
        outputs. The std is carried to first order for independent G and K: with
        ``S = (I - sign G K)^{-1}`` and ``Si = (I - sign K G)^{-1}``, the error is
        ``S dG Si + sign T dK T`` (``T`` the closed loop). An FRD K is taken as independent
        of G unless it is G itself (the same object or arrays), when ``dK = dG`` and the two
        terms add before the variance is taken. The coherence is dropped.

        Examples
        --------
        >>> import sysid
        >>> t = sysid.FRD([1.0, 2.0], [1.0, 3.0]).feedback(1.0)
        >>> t.response[:, 0, 0]
        array([0.5 +0.j, 0.75+0.j])
        """
        if sign not in (-1, 1):
            raise DataError(f"sign is -1 (negative feedback) or +1 (positive), got {sign}")
        o = self._operand(K)
        if o is None:
            raise DataError(f"feedback needs an FRD, a model with freqresp, a scalar or a "
                            f"matrix, got {type(K).__name__}")
        G = self.response
        l, m = G.shape[1:]
        if o.scalar and l != m:
            raise ShapeError(f"a scalar K closes a square loop; G is {l}x{m}: give K as a "
                             f"{m}x{l} matrix")
        k = np.broadcast_to(o.g * np.eye(m), (G.shape[0], m, l)) if o.scalar else o.g
        if k.shape[1:] != (m, l):
            raise ShapeError(f"K must be {m}x{l} (outputs x inputs: as many outputs as G has "
                             f"inputs and inputs as G has outputs), got "
                             f"{k.shape[1]}x{k.shape[2]}")
        S = _solve_inv(np.eye(l) - sign * G @ k, "I - sign G K")
        Si = _solve_inv(np.eye(m) - sign * k @ G, "I - sign K G")
        T = S @ G
        if (v := _shared_var(self, o.frd)) is not None:  # feedback(G, G): dK = dG
            return self._derive(T, _sandwiches([(S, Si), (sign * T, T)], v), o,
                                inputs=self.input_names, outputs=self.output_names)
        terms = []
        if self.std is not None:
            terms.append(_sandwich(S, self.std ** 2, Si))
        if o.var is not None:  # a scalar or matrix gain is exact
            terms.append(_sandwich(T, o.var, T))
        return self._derive(T, sum(terms) if terms else None, o, inputs=self.input_names,
                            outputs=self.output_names, both_uncertain=len(terms) == 2)


def _solve_inv(M: np.ndarray, what: str) -> np.ndarray:
    try:
        return np.linalg.inv(M)
    except np.linalg.LinAlgError:
        bad = [k for k in range(M.shape[0]) if np.linalg.matrix_rank(M[k]) < M.shape[1]]
        raise DataError(f"{what} is singular at {len(bad)} frequency index(es) {bad[:5]}: "
                        "no inverse there") from None


def _inverse_operand(o: _Operand) -> _Operand:
    """``o`` inverted per frequency, with the first-order variance of the inverse."""
    g = o.g
    if g.ndim != 3 or g.shape[1] != g.shape[2]:
        raise ShapeError(f"only a square response has an inverse, this one is "
                         f"{g.shape[1]}x{g.shape[2]} (outputs x inputs)")
    gi = _solve_inv(g, "the response")
    var = None if o.var is None else _sandwich(gi, o.var, gi)
    return _Operand(gi, var, inputs=o.outputs, outputs=o.inputs, dt=o.dt, units=o.units,
                    frd=o.frd)
