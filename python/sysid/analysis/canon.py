"""Canonical state-space forms (MATLAB's ``canon``): modal and companion.

* ``"modal"``: ``A`` real block diagonal, a ``1 x 1`` block per real pole and a ``2 x 2`` block
  ``[[sigma, omega], [-omega, sigma]]`` per complex pair ``sigma +- j omega`` (the state basis
  of the eigenvectors' real and imaginary parts): the modes decoupled, each read off ``A``.
  It needs ``A`` diagonalisable: repeated poles with dependent eigenvectors have no modal form.
* ``"companion"``: from the first input, ``A`` has ones on its subdiagonal and the
  characteristic polynomial's coefficients ``-a_n .. -a_1`` in its last column, ``B = e_1``
  (the state basis of the controllability matrix ``[b, A b, .., A^(n-1) b]``): needs the states
  reachable from that input, and is badly conditioned beyond a few states, as MATLAB warns.

The transformation is the package's convention (:func:`sysid.balanced_truncation`):
``info["T"]`` with ``x = T x_new`` and ``info["T_inv"]`` with ``x_new = T_inv x`` (MATLAB's
``T``). ``K`` and the initial state move with the states; the input-output map, the noise
model and the poles are unchanged.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError, NumericalError
from ..models.carried import carry_basis
from ..models.statespace import StateSpaceModel

__all__ = ["canon", "real_modal_basis"]

_FORMS = ("modal", "companion")


def real_modal_basis(A: Any, max_cond: float = 1e10) -> tuple[np.ndarray, np.ndarray] | None:
    """``(T, poles)``: columns the real eigenvectors and the real and imaginary parts of one
    eigenvector of each complex pair, so that ``T^-1 A T`` is the real modal form, with the
    pole of each new state; ``None`` when the eigenvectors are (nearly) dependent
    (``cond(T) > max_cond``).

    Examples
    --------
    >>> import numpy as np
    >>> T, p = real_modal_basis([[0.5, 1.0], [-1.0, 0.5]])
    >>> np.round(np.linalg.solve(T, np.array([[0.5, 1.0], [-1.0, 0.5]]) @ T), 12).tolist()
    [[0.5, 1.0], [-1.0, 0.5]]
    """
    A = np.asarray(A, dtype=float)
    lam, V = np.linalg.eig(A)
    cols: list[np.ndarray] = []
    poles: list[complex] = []
    used = np.zeros(lam.size, bool)
    for k in range(lam.size):
        if used[k]:
            continue
        if lam[k].imag == 0:
            cols.append(V[:, k].real)
            poles.append(complex(lam[k].real, 0.0))
            used[k] = True
            continue
        partner = [j for j in range(lam.size) if not used[j] and j != k
                   and np.isclose(lam[j], np.conj(lam[k]), rtol=1e-10, atol=1e-12)]
        if not partner:
            return None
        j = partner[0]
        top = k if lam[k].imag > 0 else j  # the pole sigma + j omega, omega > 0
        cols += [V[:, top].real, V[:, top].imag]
        poles += [complex(lam[top]), complex(lam[top])]
        used[[k, j]] = True
    T = np.column_stack(cols) if cols else np.zeros((0, 0))
    if len(poles) != A.shape[0] or (T.size and np.linalg.cond(T) > max_cond):
        return None
    return T, np.asarray(poles)


def _companion_basis(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    n = A.shape[0]
    W = np.empty((n, n))
    v = b.copy()
    for k in range(n):
        W[:, k] = v
        v = A @ v
    s = np.linalg.svd(W, compute_uv=False) if n else np.zeros(0)
    if n and (s[-1] <= s[0] * n * np.finfo(float).eps * 1e3 or not np.all(np.isfinite(s))):
        raise DataError(
            "the companion form needs every state reachable from the first input, and the "
            f"controllability matrix of this model has rank below {n}: remove the "
            "unreachable states first (sysid.minreal(model)), or use form='modal'")
    return W


def canon(model: Any, form: str = "modal") -> StateSpaceModel:
    """The model in a canonical state basis (MATLAB's ``canon(sys, type)``).

    Parameters
    ----------
    model : StateSpaceModel, ContinuousStateSpace or a model with ``to_statespace()``
    form : {"modal", "companion"}
        See the module docstring.

    Returns
    -------
    StateSpaceModel
        The same input-output and noise map in the new basis; ``info["T"]`` (``x = T
        x_new``), ``info["T_inv"]`` (``x_new = T_inv x``, MATLAB's ``T``) and
        ``info["canonical_form"]``. The parameter uncertainty follows, each draw in the same
        basis ``T`` (:func:`sysid.models.carried.carry_basis`).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.5, 0.2, 0.0], [-0.6, 0.7, 0.1], [0.0, 0.0, 0.3]],
    ...                           [[1.0], [0.0], [1.0]], [[1.0, 1.0, 0.5]])
    >>> np.round(sysid.canon(m, "modal").A, 4).tolist()
    [[0.6, 0.3317, 0.0], [-0.3317, 0.6, 0.0], [0.0, 0.0, 0.3]]
    >>> c = sysid.canon(m, "companion")
    >>> np.round(c.A[:, -1], 4).tolist(), np.round(c.B.ravel(), 12).tolist()  # -a3, -a2, -a1
    ([0.141, -0.83, 1.5], [1.0, 0.0, 0.0])
    """
    if form not in _FORMS:
        raise DataError(f"form must be 'modal' or 'companion', got {form!r}")
    from ..models.continuous import ContinuousStateSpace

    m = model if isinstance(model, (StateSpaceModel, ContinuousStateSpace)) else (
        model.to_statespace() if hasattr(model, "to_statespace") else None)
    if not isinstance(m, (StateSpaceModel, ContinuousStateSpace)):
        raise DataError(f"canon needs a state-space model (or one with to_statespace()), got "
                        f"{type(model).__name__}")
    if form == "modal":
        basis = real_modal_basis(m.A)
        if basis is None:
            raise NumericalError(
                "canon(form='modal'): A has repeated poles whose eigenvectors are (nearly) "
                "dependent, so it has no modal form; use form='companion' or "
                "sysid.balanced_realization(model)")
        T = basis[0]
    else:
        if m.ninputs == 0:
            raise DataError("the companion form is built from the first input, and this "
                            "model has none: use form='modal'")
        T = _companion_basis(m.A, m.B[:, 0])
    Ti = np.linalg.inv(T)
    A, B = Ti @ m.A @ T, Ti @ m.B
    # the structure's zeros and ones exactly (round-off there is no part of the model)
    n = A.shape[0]
    if form == "modal":
        keep = np.eye(n, dtype=bool)
        poles = basis[1]
        for i in range(n - 1):
            if poles[i].imag != 0 and poles[i] == poles[i + 1] and not keep[i, i + 1] \
                    and (i == 0 or not keep[i - 1, i]):
                keep[i:i + 2, i:i + 2] = True
        A = np.where(keep, A, 0.0)
        for i in range(n - 1):  # each pair's block exactly [[s, w], [-w, s]]
            if keep[i, i + 1]:
                sig = 0.5 * (A[i, i] + A[i + 1, i + 1])
                w = 0.5 * (A[i, i + 1] - A[i + 1, i])
                A[i:i + 2, i:i + 2] = [[sig, w], [-w, sig]]
    elif n:
        A[:, :-1] = np.eye(n, n - 1, -1)
        B[:, 0] = np.eye(n)[:, 0]
    info = {k: v for k, v in dict(m.info).items() if k != "uncertainty"}
    info.update(canonical_form=form, T=T, T_inv=Ti)
    if isinstance(m, ContinuousStateSpace):
        out: Any = ContinuousStateSpace(A, B, m.C @ T, m.D, input_names=m.input_names,
                                        output_names=m.output_names, hold=m.hold, info=info)
    else:
        out = StateSpaceModel(
            A, B, m.C @ T, m.D, None if m.K is None else Ti @ m.K,
            dt=m.dt, noise_cov=m.noise_cov, x0=None if m.x0 is None else Ti @ m.x0,
            input_names=m.input_names, output_names=m.output_names, info=info)
    return carry_basis(m, out, T, Ti)
