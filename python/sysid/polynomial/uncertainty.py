"""Parameter uncertainty of the polynomial models: one :class:`ParameterUncertainty` over
every output's coefficients, in the order of the estimators' parameter vectors (shared by the
time-domain estimators, the frequency-domain ``oe`` and ``ar``/``arma``)."""

from __future__ import annotations

import numpy as np

from ..models.uncertainty import ParameterUncertainty
from .model import PolynomialModel


def _refs(model: PolynomialModel, kind: str) -> list[tuple[str, int, int | None]]:
    """The coefficient arrays in the order of the estimators' parameter vectors: per output,
    ARX ``[a_i1.., a_i2.., ..., b_i1.., ...]``; PEM ``[a_ii, b_i1.., c_i, d_i, f_i1..]``."""
    ny, nu = model.n_outputs, model.n_inputs
    out: list[tuple[str, int, int | None]] = []
    for i in range(ny):
        if kind == "arx":
            out += [("a", i, k) for k in range(ny)] + [("b", i, j) for j in range(nu)]
        else:
            out += [("a", i, i)] + [("b", i, j) for j in range(nu)] + [("c", i, None),
                                                                        ("d", i, None)]
            out += [("f", i, j) for j in range(nu)]
    return out


def _get(model: PolynomialModel, ref: tuple[str, int, int | None]) -> np.ndarray:
    name, i, j = ref
    arr = getattr(model, name)[i]
    return np.asarray(arr if j is None else arr[j])


def attach_uncertainty(model: PolynomialModel, covs: list[np.ndarray], kind: str,
                        method: str) -> None:
    """``model.uncertainty`` from the per-output covariances (block diagonal: the outputs'
    equations are estimated separately)."""
    import copy

    from scipy.linalg import block_diag

    refs = _refs(model, kind)
    sizes = [_get(model, r).size for r in refs]
    theta = np.concatenate([_get(model, r) for r in refs]) if refs else np.zeros(0)
    P = block_diag(*[np.atleast_2d(np.asarray(c, float)) for c in covs if np.size(c)])
    if P.shape != (theta.size, theta.size):
        return  # a covariance that does not match the coefficients is not attached
    names = [f"{r[0]}[{r[1]}]" + (f"[{r[2]}]" if r[2] is not None else "") + f"[{k}]"
             for r, n in zip(refs, sizes) for k in range(n)]
    template = copy.deepcopy(model)
    template.uncertainty = None

    def build(t: np.ndarray) -> PolynomialModel:
        m = copy.copy(template)
        m.a = [list(row) for row in template.a]
        m.b = [list(row) for row in template.b]
        m.f = [list(row) for row in template.f]
        m.c, m.d = list(template.c), list(template.d)
        o = 0
        for (name, i, j), n in zip(refs, sizes):
            piece = np.asarray(t[o:o + n], dtype=float)
            o += n
            if j is None:
                getattr(m, name)[i] = piece
            else:
                getattr(m, name)[i][j] = piece
        return m

    model.uncertainty = ParameterUncertainty(theta, P, build, names=names, method=method)
