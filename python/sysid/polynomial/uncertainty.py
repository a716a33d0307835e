"""Parameter uncertainty of the polynomial models: one :class:`ParameterUncertainty` over
every output's coefficients, in the order of the estimators' parameter vectors (shared by the
time-domain estimators, the frequency-domain ``oe`` and ``ar``/``arma``)."""

from __future__ import annotations

from typing import Any

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
    blocks = [np.atleast_2d(np.asarray(c, float)) for c in covs if np.size(c)]
    P = block_diag(*blocks)
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

    model.uncertainty = ParameterUncertainty(theta, P, build, names=names, method=method,
                                             blocks=[b.shape[0] for b in blocks])


def output_blocks(model: PolynomialModel, kind: str = "pem") -> list[tuple[list[int], list[int]]]:
    """Per output, the indices of its parameters in :func:`attach_uncertainty`'s vector and
    the output itself: the blocks of a fit searched one output at a time."""
    refs = _refs(model, kind)
    blocks: list[tuple[list[int], list[int]]] = [([], [i]) for i in range(model.n_outputs)]
    o = 0
    for ref in refs:
        n = _get(model, ref).size
        blocks[ref[1]][0].extend(range(o, o + n))
        o += n
    return blocks


def defer_coloured(model: PolynomialModel, experiments: list[tuple[np.ndarray, np.ndarray]],
                   sim: Any = None) -> None:
    """An output-error fit's uncertainty for coloured errors: its Gauss-Newton covariance
    becomes the sandwich of :mod:`sysid.pem.sandwich` when first used (per output, on the
    errors that the search minimised: of the simulation from rest on every record, or on one
    record ``sim(model)``'s when given, with the initial states estimated:
    :func:`sysid.polynomial.initial.simulator`);
    ``info["covariance"]`` says which covariance the model carries (as ``pem``'s
    ``info["pem"]["covariance"]``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy.signal import lfilter
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(800)
    >>> v = lfilter([1.0], [1.0, -0.9], 0.1 * rng.standard_normal(800))
    >>> y = lfilter([0.0, 0.5], [1.0, -0.8], u) + v
    >>> m = sysid.oe(sysid.IOData(u, y, 1.0), 1, 1, 1)     # calls defer_coloured
    >>> m.info["covariance"].startswith("gauss-newton until first used")
    True
    >>> sd = m.std                                         # the first use forms it
    >>> m.info["covariance"].startswith("sandwich for coloured simulation errors")
    True
    """
    from ..pem.sandwich import DeferredSandwich, sandwich_covariance

    base = getattr(model, "uncertainty", None)
    if not isinstance(base, ParameterUncertainty):
        return
    records = [(np.asarray(u, float), np.asarray(y, float)) for u, y in experiments]
    ys = [y.reshape(len(y), -1) for _, y in records]
    info = model.info
    info["covariance"] = ("gauss-newton until first used, then the sandwich for coloured "
                          "simulation errors")
    blocks = output_blocks(model)

    def form() -> tuple[ParameterUncertainty | None, str]:
        if sim is not None:  # one record, its initial states estimated
            return sandwich_covariance(base, lambda m: [sim(m)], ys, blocks=blocks)
        return sandwich_covariance(base, lambda m: [m.simulate(u) for u, _ in records], ys,
                                   blocks=blocks)

    def then(note: str) -> None:
        info["covariance"] = note
    model.uncertainty = DeferredSandwich(base, form, then)
