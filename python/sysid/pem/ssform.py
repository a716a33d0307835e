"""State-space structures with fixed and free entries (MATLAB's ``ssform`` and an ``idss``'s
``Structure.A.Free``), estimated by :func:`sysid.ssest` and :func:`sysid.pem`.

A :class:`StateSpaceStructure` is a discrete model ``x(t+1) = A x + B u + K e, y = C x + D u
+ e`` whose entries are either fixed (kept at their values) or moved by a free parameter;
a parameter may move several entries (the two diagonal entries of a complex pair's block in
the modal form). The forms (``ssform(model, form)``):

* ``"free"``: every entry of ``A, B, C`` free (MATLAB's default). Over-parameterised (any
  similarity transformation gives the same model); with nothing fixed the estimators search
  it in their identifiable local coordinates, as ``pem(data, model)`` does.
* ``"canonical"``: the observability (pseudo-)canonical form (Ljung, *System
  Identification*, 2nd ed., appendix 4A): the rows ``c_i A^k`` of the observability matrix
  taken output by output in lexicographic order while independent give the observability
  indices ``nu_i``; in that basis ``C`` selects the first state of each output's block,
  each block shifts, and only the last row of each block (``c_i A^nu_i`` in the new
  coordinates) is free, with ``B`` (and ``D``, ``K``): ``l n + n m`` parameters, an
  identifiable set for almost every system of the order. Badly conditioned beyond a few
  states, as every polynomial-like form.
* ``"companion"``: :func:`sysid.canon`'s companion form from the first input: the last column
  of ``A`` (the characteristic polynomial) free, ``B``'s first column ``e_1`` fixed, its
  other columns and ``C`` free.
* ``"modal"``: :func:`sysid.canon`'s real modal form: one parameter per real pole, two per
  complex pair ``[[sigma, omega], [-omega, sigma]]`` (each tied to its entries), ``C`` free,
  ``B`` free but for one input's entries in each block, fixed to remove the block's
  scaling (and rotation): identifiable.

``free={"C": False, "A": mask}`` then frees or fixes entries (a boolean per entry, or one for
the whole matrix), as MATLAB's ``Structure.C.Free = false``: a parameter tied to several
entries is free only when all of them are.

Examples
--------
>>> import numpy as np, sysid
>>> m = sysid.StateSpaceModel([[0.5, 0.2], [-0.3, 0.7]], [[1.0], [0.5]], [[1.0, 0.0]])
>>> s = sysid.ssform(m, "canonical")
>>> s.n_free, s.free["C"].tolist()
(4, [[False, False]])
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError
from ..models.statespace import StateSpaceModel

__all__ = ["StateSpaceStructure", "ssform", "observability_form"]

MATRICES = ("A", "B", "C", "D", "K")
FORMS = ("free", "canonical", "companion", "modal")
#: an entry: (matrix, row, column, coefficient); a parameter moves its entries by value x coef
Entry = tuple[str, int, int, float]


class StateSpaceStructure:
    """A discrete state-space model with fixed and free entries (see the module docstring).

    Build one with :func:`ssform`; estimate it with ``sysid.ssest(data, structure)`` or
    ``sysid.pem(data, structure)``.

    Attributes
    ----------
    model : StateSpaceModel
        The structure at its current values.
    form : str
    names : list of str
        The free parameters (``"A_i_j"`` for entry ``A[i, j]``, or ``"sigma_i"``,
        ``"omega_i"`` for a modal pair's block starting at state ``i``).
    free : dict of ndarray
        Per matrix, the entries a free parameter moves.

    Examples
    --------
    >>> import sysid
    >>> m = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]])
    >>> sysid.ssform(m, free={"C": False})
    StateSpaceStructure(form='free', 1 states, 1 inputs, 1 outputs, 2 free parameters: A, B)
    """

    def __init__(self, model: StateSpaceModel, params: list[tuple[str, float, list[Entry]]],
                 form: str, bounds: dict[str, tuple[float, float]] | None = None) -> None:
        self.model, self.form = model, form
        self._params = params
        #: ``{name: (lower, upper)}`` of the bounded free parameters (:meth:`with_bounds`)
        self.bounds = {k: v for k, v in (bounds or {}).items() if k in self.names}

    @property
    def names(self) -> list[str]:
        """The free parameters' names (the order of :attr:`values`)."""
        return [p[0] for p in self._params]

    @property
    def values(self) -> np.ndarray:
        """The free parameters' current values (order of :attr:`names`)."""
        return np.array([p[1] for p in self._params], dtype=float)

    @property
    def n_free(self) -> int:
        """The number of free parameters."""
        return len(self._params)

    @property
    def free(self) -> dict[str, np.ndarray]:
        """Per matrix (``A``, ``B``, ``C``, ``D``, ``K``), the entries a free parameter moves."""
        mats = _matrices(self.model)
        out = {k: np.zeros(v.shape, bool) for k, v in mats.items()}
        for _, _, entries in self._params:
            for mat, i, j, _ in entries:
                out[mat][i, j] = True
        return out

    def matrices(self, theta: Any) -> dict[str, np.ndarray]:
        """``A, B, C, D, K`` at the free parameters ``theta`` (fixed entries as they are)."""
        theta = np.asarray(theta, dtype=float).ravel()
        if theta.size != self.n_free:
            raise DataError(f"the structure has {self.n_free} free parameters, got "
                            f"{theta.size} values")
        mats = {k: v.copy() for k, v in _matrices(self.model).items()}
        for t, (_, _, entries) in zip(theta, self._params):
            for mat, i, j, c in entries:
                mats[mat][i, j] = c * t
        return mats

    def derivatives(self) -> list[dict[str, np.ndarray]]:
        """Per free parameter, the (constant) derivative of every matrix."""
        shapes = {k: v.shape for k, v in _matrices(self.model).items()}
        out = []
        for _, _, entries in self._params:
            d = {k: np.zeros(s) for k, s in shapes.items()}
            for mat, i, j, c in entries:
                d[mat][i, j] = c
            out.append(d)
        return out

    def with_values(self, theta: Any, model: StateSpaceModel | None = None
                    ) -> StateSpaceStructure:
        """The same structure at other values (``model``: its matrices, when already built)."""
        if model is None:
            m = self.matrices(theta)
            model = StateSpaceModel(m["A"], m["B"], m["C"], m["D"], K=m["K"], dt=self.model.dt)
        params = [(n, float(t), e) for t, (n, _, e) in zip(np.ravel(theta), self._params)]
        return StateSpaceStructure(model, params, self.form, self.bounds)

    def read(self, model: StateSpaceModel) -> StateSpaceStructure:
        """The structure at the values of ``model``'s matrices (same form and basis)."""
        mats = _matrices(model)
        theta = [mats[e[0][0]][e[0][1], e[0][2]] / e[0][3] for _, _, e in self._params]
        return self.with_values(theta, model)

    def without_noise(self) -> StateSpaceStructure:
        """The structure with ``K`` fixed at zero (an output-error model)."""
        m = self.model
        model = StateSpaceModel(m.A, m.B, m.C, m.D, dt=m.dt)
        keep = [p for p in self._params if all(e[0] != "K" for e in p[2])]
        return StateSpaceStructure(model, keep, self.form, self.bounds)

    def with_bounds(self, minimum: dict[str, Any] | None = None,
                    maximum: dict[str, Any] | None = None) -> StateSpaceStructure:
        """The structure with bounds on free entries (MATLAB's ``Structure.A.Minimum`` and
        ``Maximum``), in its own state basis (:attr:`model`): ``{"A": array or number,
        ...}``; a parameter tied to several entries takes its first entry's bounds. The
        search stays inside; the parameter table reports an active bound.

        Examples
        --------
        >>> import sysid
        >>> s = sysid.ssform(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]))
        >>> s.with_bounds(minimum={"A": 0.0}, maximum={"A": 0.99}).bounds
        {'A_0_0': (0.0, 0.99)}
        """
        mats = _matrices(self.model)
        lims = {}
        for side, given, fill in (("minimum", minimum, -np.inf), ("maximum", maximum, np.inf)):
            lims[side] = {k: np.full(v.shape, fill) for k, v in mats.items()}
            for k, v in (given or {}).items():
                if k not in MATRICES:
                    raise DataError(f"{side} names matrices {list(MATRICES)}, got {k!r}")
                a = np.asarray(v, dtype=float)
                if a.ndim and a.shape != mats[k].shape:
                    raise DataError(f"{side}[{k!r}] has shape {a.shape}, but {k} is "
                                    f"{mats[k].shape}")
                lims[side][k] = np.broadcast_to(a, mats[k].shape).astype(float)
        bounds = dict(self.bounds)
        for name, value, entries in self._params:
            mat, i, j, c = entries[0]
            lo, hi = lims["minimum"][mat][i, j] / c, lims["maximum"][mat][i, j] / c
            lo, hi = min(lo, hi), max(lo, hi)
            if np.isfinite(lo) or np.isfinite(hi):
                if not lo <= value <= hi:
                    raise DataError(f"{name} = {value:.6g} lies outside its bounds "
                                    f"[{lo:.6g}, {hi:.6g}]: start inside them")
                bounds[name] = (float(lo), float(hi))
        return StateSpaceStructure(self.model, self._params, self.form, bounds)

    def summary(self) -> str:
        """The free entries of each matrix, as text (``x`` free, ``.`` fixed)."""
        lines = [repr(self)]
        for k, mask in self.free.items():
            if mask.size:
                lines.append(f"{k}:")
                lines += ["  " + " ".join("x" if f else "." for f in row) for row in mask]
        return "\n".join(lines)

    def __repr__(self) -> str:
        m = self.model
        which = [k for k, v in self.free.items() if v.any()]
        return (f"StateSpaceStructure(form={self.form!r}, {m.nstates} states, {m.ninputs} "
                f"inputs, {m.noutputs} outputs, {self.n_free} free parameters: "
                f"{', '.join(which) or 'none'})")


def _matrices(model: StateSpaceModel) -> dict[str, np.ndarray]:
    K = model.K if model.K is not None else np.zeros((model.nstates, model.noutputs))
    return {"A": model.A, "B": model.B, "C": model.C, "D": model.D, "K": K}


def observability_form(model: StateSpaceModel) -> tuple[StateSpaceModel, list[int]]:
    """The model in its observability (pseudo-)canonical basis and the observability indices
    ``nu_i`` (module docstring); ``x_new = T x`` with ``T`` in ``info["T_inv"]``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.5, 0.2], [-0.3, 0.7]], [[1.0], [0.5]], [[1.0, 1.0]])
    >>> c, nu = observability_form(m)
    >>> nu, np.round(c.C, 12).tolist(), np.round(c.A[0], 12).tolist()
    ([2], [[1.0, 0.0]], [0.0, 1.0])
    """
    A, C = model.A, model.C
    n, l = model.nstates, model.noutputs
    rows: list[tuple[int, int, np.ndarray]] = []  # (output, power, row)
    basis = np.zeros((0, n))
    done = [False] * l
    row_pow = C.copy()
    tol = n * np.finfo(float).eps * max(1.0, np.linalg.norm(C)) * 1e6
    for k in range(n + 1):
        for i in range(l):
            if done[i] or len(rows) == n:
                continue
            r = row_pow[i]
            resid = r - basis.T @ (basis @ r) if basis.size else r.copy()
            if np.linalg.norm(resid) <= tol * max(1.0, np.linalg.norm(r)):
                done[i] = True
                continue
            rows.append((i, k, r.copy()))
            q = resid / np.linalg.norm(resid)
            basis = np.vstack([basis, q])
        row_pow = row_pow @ A
    if len(rows) < n:
        raise DataError(f"the canonical form needs an observable model, and this one has "
                        f"only {len(rows)} observable directions of {n}: remove the "
                        "unobservable states first (sysid.minreal(model))")
    nu = [sum(1 for i, _, _ in rows if i == o) for o in range(l)]
    order = sorted(rows, key=lambda t: (t[0], t[1]))
    T = np.vstack([r for _, _, r in order])
    if np.linalg.cond(T) > 1e12:
        raise DataError("the observability canonical form of this model is too badly "
                        "conditioned to estimate in (cond(T) > 1e12): use form='modal' or "
                        "'free'")
    Ti = np.linalg.inv(T)
    A2, C2 = T @ model.A @ Ti, model.C @ Ti
    # the shift rows and C's selections are exact
    start = np.cumsum([0] + nu)[:-1]
    for o in range(l):
        for k in range(nu[o] - 1):
            A2[start[o] + k] = 0.0
            A2[start[o] + k, start[o] + k + 1] = 1.0
        if nu[o]:
            C2[o] = 0.0
            C2[o, start[o]] = 1.0
    K = None if model.K is None else T @ model.K
    out = StateSpaceModel(A2, T @ model.B, C2, model.D, K=K, dt=model.dt)
    out.info["T"], out.info["T_inv"], out.info["canonical_form"] = Ti, T, "observability"
    return out, nu


def _form_params(model: StateSpaceModel, form: str) -> tuple[StateSpaceModel, list[Any]]:
    """The model in the form's basis and the form's parameters over ``A, B, C``."""
    from ..analysis.canon import canon

    n, m, l = model.nstates, model.ninputs, model.noutputs
    single = [(f"{k}_{i}_{j}", [(k, i, j, 1.0)])
              for k, (r, c) in (("A", (n, n)), ("B", (n, m)), ("C", (l, n)))
              for i in range(r) for j in range(c)]
    if form == "free":
        return model, single
    keep: set[tuple[str, int, int]] = set()
    if form == "canonical":
        model, nu = observability_form(model)
        ends = np.cumsum(nu) - 1
        keep |= {("A", int(e), j) for o, e in enumerate(ends) if nu[o] for j in range(n)}
        keep |= {("C", o, j) for o in range(l) if not nu[o] for j in range(n)}
        keep |= {("B", i, j) for i in range(n) for j in range(m)}
    elif form == "companion":
        model = canon(model, "companion")
        keep |= {("A", i, n - 1) for i in range(n)}
        keep |= {("B", i, j) for i in range(n) for j in range(1, m)}
        keep |= {("C", i, j) for i in range(l) for j in range(n)}
    else:  # modal
        model = canon(model, "modal")
        A, B = model.A, model.B
        params, i = [], 0
        while i < n:
            pair = i + 1 < n and A[i, i + 1] != 0.0
            size = 2 if pair else 1
            blk = B[i:i + size]
            ref = int(np.argmax(np.linalg.norm(blk, axis=0)))  # the block's scale, fixed
            if pair:
                params += [(f"sigma_{i}", [("A", i, i, 1.0), ("A", i + 1, i + 1, 1.0)]),
                           (f"omega_{i}", [("A", i, i + 1, 1.0), ("A", i + 1, i, -1.0)])]
            else:
                params.append((f"A_{i}_{i}", [("A", i, i, 1.0)]))
            params += [(f"B_{r}_{j}", [("B", r, j, 1.0)]) for r in range(i, i + size)
                       for j in range(m) if j != ref]
            i += size
        params += [p for p in single if p[1][0][0] == "C"]
        return model, params
    return model, [p for p in single if p[1][0][:3] in keep]


def _mask(name: str, value: Any, shape: tuple[int, int]) -> np.ndarray:
    v = np.asarray(value)
    if v.dtype != bool and not (v.ndim == 0 and isinstance(value, (bool, np.bool_))):
        raise DataError(f"free[{name!r}] must be True, False or a boolean array of shape "
                        f"{shape}, got {value!r}")
    if v.ndim == 0:
        return np.full(shape, bool(v))
    if v.shape != shape:
        raise DataError(f"free[{name!r}] has shape {v.shape}, but {name} is {shape}: give a "
                        f"boolean per entry, or one for the whole matrix")
    return v.astype(bool)


def ssform(model: Any, form: str = "free", *, free: dict[str, Any] | None = None,
           feedthrough: bool | None = None, noise: str | None = None) -> StateSpaceStructure:
    """A state-space structure with fixed and free entries (MATLAB's ``ssform`` and
    ``Structure.<M>.Free``), to estimate with :func:`sysid.ssest` or :func:`sysid.pem`.

    Parameters
    ----------
    model : StateSpaceModel
        A discrete model: the start values and the fixed entries' values.
    form : {"free", "canonical", "companion", "modal"}
        The parameterisation (module docstring); the model is first transformed to that
        form's state basis.
    free : dict, optional
        ``{"A" | "B" | "C" | "D" | "K": bool or boolean array}``: free (``True``) or fix
        entries, after the form.
    feedthrough : bool, optional
        ``D`` free (``True``) or fixed at zero (``False``); default: free when the model has a
        non-zero ``D``.
    noise : {"estimate", "none"}, optional
        ``K`` free (from the model's, or zero) or fixed at zero (an output-error model);
        default: free when the model has a non-zero ``K``.

    Returns
    -------
    StateSpaceStructure

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.0]], [[1.0, 0.5]])
    >>> s = sysid.ssform(m, "modal")
    >>> s.names
    ['sigma_0', 'omega_0', 'C_0_0', 'C_0_1']
    """
    if not isinstance(model, StateSpaceModel):
        raise DataError(f"ssform takes a discrete sysid.StateSpaceModel (the start values), "
                        f"got {type(model).__name__}; for a continuous or physical "
                        "structure use sysid.GreyBox")
    if form not in FORMS:
        raise DataError(f"form must be one of {list(FORMS)}, got {form!r}")
    if noise not in (None, "estimate", "none"):
        raise DataError(f"noise must be 'estimate' or 'none', got {noise!r}")
    if feedthrough is not None and not isinstance(feedthrough, (bool, np.bool_)):
        raise DataError(f"feedthrough must be True or False, got {feedthrough!r}")
    free = dict(free or {})
    unknown = sorted(set(free) - set(MATRICES))
    if unknown:
        raise DataError(f"free names matrices {list(MATRICES)}, got {unknown}")
    d_free = bool(np.any(model.D != 0)) if feedthrough is None else bool(feedthrough)
    k_free = (model.K is not None and bool(np.any(model.K != 0))) if noise is None else \
        noise == "estimate"
    base, params = _form_params(model, form)
    n, m, l = base.nstates, base.ninputs, base.noutputs
    K = base.K if (k_free and base.K is not None) else np.zeros((n, l))
    D = base.D if d_free else np.zeros((l, m))
    base = StateSpaceModel(base.A, base.B, base.C, D, K=K, dt=base.dt)
    params += [(f"D_{i}_{j}", [("D", i, j, 1.0)]) for i in range(l) for j in range(m)
               if d_free]
    params += [(f"K_{i}_{j}", [("K", i, j, 1.0)]) for i in range(n) for j in range(l)
               if k_free]
    mats = _matrices(base)
    mask = {k: np.zeros(v.shape, bool) for k, v in mats.items()}
    for _, entries in params:
        for mat, i, j, _ in entries:
            mask[mat][i, j] = True
    for k, v in free.items():
        mask[k] = _mask(k, v, mats[k].shape)
    covered = {(e[0], e[1], e[2]) for _, entries in params for e in entries}
    out = [(name, float(mats[entries[0][0]][entries[0][1], entries[0][2]] / entries[0][3]),
            entries) for name, entries in params
           if all(mask[e[0]][e[1], e[2]] for e in entries)]
    out += [(f"{k}_{i}_{j}", float(mats[k][i, j]), [(k, i, j, 1.0)])
            for k in MATRICES for i, j in zip(*np.nonzero(mask[k])) if (k, i, j) not in covered]
    if not out:
        raise DataError("the structure has no free parameter: free some entries "
                        "(free={'A': True, ...})")
    return StateSpaceStructure(base, out, form)
