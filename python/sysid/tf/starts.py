"""A second start for :func:`sysid.tfest`'s output-error search on time records with
several inputs: the poles of a subspace model of the output, the numerators by least squares.

The default start (:func:`sysid.tf.tfest._starts`) fits each input's pair by SRIVC on what
the others leave, in turn; with several inputs those sweeps can leave one output's pairs
far from the truth, and the search from there stopped in a poor local minimum at a
degenerate point (the warning audit's clean 2 x 2 records: an IdentifiabilityWarning in
24/100 runs, the other output's pairs recovering the true poles to 1e-3). A subspace model
of the output fits every input at once, so its poles do not depend on the sweeps; the
search runs from both starts and keeps the lower criterion (:func:`sysid.tfest`).
"""

from __future__ import annotations

import warnings

import numpy as np

from .model import TransferFunction

__all__ = ["subspace_pairs"]

#: the discrete poles of the subspace model are kept within these moduli before they are
#: mapped to continuous time (the search needs a stable start; a pole at z = 0 has no
#: logarithm)
_RADIUS = (1e-3, 0.995)


def _continuous_poles(z: np.ndarray, dt: float) -> np.ndarray:
    """``log(z) / dt`` of discrete poles, stable: moduli clipped to :data:`_RADIUS` (an
    unstable pole reflected first), a pole on the negative real axis taken at its modulus
    (no real logarithm: a start, not a conversion)."""
    z = np.asarray(z, complex)
    r = np.abs(z)
    r = np.where(r >= 1.0, 1.0 / np.maximum(r, 1e-300), r)
    r = np.clip(r, *_RADIUS)
    real = np.abs(z.imag) <= 1e-9 * np.maximum(np.abs(z), 1e-300)
    ang = np.where(real, 0.0, np.angle(z))
    return (np.log(r) + 1j * ang) / dt


def _channel_poles(s: np.ndarray, weight: np.ndarray, k: int) -> np.ndarray:
    """``k`` of the poles ``s`` for a pair, the largest ``weight`` first, a complex pole
    with its conjugate (a lone real pole fills an odd count)."""
    if k >= s.size:
        return s
    order = np.argsort(-weight)
    out: list[complex] = []
    used = np.zeros(s.size, bool)
    for i in order:
        if used[i] or len(out) >= k:
            continue
        if abs(s[i].imag) > 0:
            if len(out) + 2 > k:
                continue
            gap = np.abs(s - np.conj(s[i]))
            gap[used] = np.inf
            gap[i] = np.inf
            j = int(np.argmin(gap))
            used[[i, j]] = True
            out += [s[i], s[j]]
        else:
            used[i] = True
            out.append(s[i])
    if len(out) < k:  # only pairs were left for an odd count: a real pole at a pair's decay
        rest = [x for x, u in zip(s[order], used[order]) if not u]
        out += [complex(rest[0].real)] * (k - len(out)) if rest else []
    return np.asarray(out[:k])


def _numerators(exps: list[tuple[np.ndarray, np.ndarray]], dens: list[np.ndarray],
                nze: np.ndarray, taus: list[float], dt: float, hold: str
                ) -> tuple[list[np.ndarray], float] | None:
    """The numerators of ``y = sum_j B_j / A_j u_j`` with the denominators ``dens`` and
    delays ``taus`` fixed, and the sum of squared errors: linear least squares on the
    simulated responses of ``s^k / A_j`` (the output error is linear in them)."""
    cols, sizes = [], []
    for j, (a, nz, tau) in enumerate(zip(dens, nze, taus)):
        for q in range(int(nz) + 1):
            num = np.zeros(int(nz) + 1 - q)
            num[0] = 1.0  # s^(nz - q)
            g = TransferFunction(num, a, iodelay=tau, hold=hold)
            cols.append(np.concatenate([g.simulate(u[:, j], dt=dt)[:, 0] for u, _ in exps]))
        sizes.append(int(nz) + 1)
    Phi = np.column_stack(cols)
    y = np.concatenate([y for _, y in exps])
    if not np.all(np.isfinite(Phi)):
        return None
    scale = np.maximum(np.sqrt(np.mean(Phi ** 2, axis=0)), 1e-300)
    theta = np.linalg.lstsq(Phi / scale, y, rcond=None)[0] / scale
    out, o = [], 0
    for k in sizes:
        out.append(theta[o:o + k])
        o += k
    if not all(np.all(np.isfinite(b)) for b in out):
        return None
    return out, float(np.sum((y - Phi @ theta) ** 2))


def _modes(exps: list[tuple[np.ndarray, np.ndarray]], dt: float, n: int
           ) -> tuple[np.ndarray, np.ndarray] | None:
    """Discrete poles of :func:`sysid.n4sid` of order ``n`` on one output (all inputs), and
    each mode's weight per input (``|c_k b_kj| / (1 - |z_k|)``); ``None`` when it fails."""
    from ..data.iodata import IOData
    from ..subspace.estimator import SubspaceEstimator, horizon_for_order

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            one = IOData([u for u, _ in exps], [y[:, None] for _, y in exps], dt) \
                if len(exps) > 1 else IOData(exps[0][0], exps[0][1][:, None], dt)
            ss = SubspaceEstimator(one, horizon_for_order(one, n, None), method="n4sid").fit(n)
        A, B, C = (np.asarray(x, float) for x in (ss.A, ss.B, ss.C))
        z, V = np.linalg.eig(A)
        W = np.linalg.solve(V, B)  # modal input gains
        c = (C @ V)[0]
    except Exception:  # noqa: BLE001 - no subspace start of this order
        return None
    if not (np.all(np.isfinite(z)) and np.all(np.isfinite(W))):
        return None
    weight = np.abs(c[:, None] * W) / np.maximum(1.0 - np.minimum(np.abs(z), 0.999),
                                                 1e-3)[:, None]
    return z, weight


def subspace_pairs(exps: list[tuple[np.ndarray, np.ndarray]], dt: float, npo: np.ndarray,
                   nze: np.ndarray, taus: list[float], hold: str, order: int | None = None
                   ) -> list[tuple[np.ndarray, np.ndarray, float]] | None:
    """Per input ``(a, b, delay)`` of one output (``exps``: its records, inputs x one
    output): the poles of :func:`sysid.n4sid` on the output (all inputs at once) mapped to
    continuous time (:func:`_continuous_poles`), each pair with ``npo[j]`` of them (those
    of the largest weight for input ``j``, :func:`_modes`), the delays ``taus`` and the
    numerators by least squares (:func:`_numerators`). Two subspace orders are tried (or
    ``order``): ``max(npo)`` (pairs sharing their poles, as the channels of one state-space
    plant) and ``sum(npo)`` (each pair its own poles, the structure's state dimension); the
    start with the smaller squared error is returned. ``None`` when every fit fails.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.tf.starts import subspace_pairs
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((800, 2))
    >>> g1 = sysid.TransferFunction([1.0], [1.0, 0.5])
    >>> g2 = sysid.TransferFunction([2.0], [1.0, 2.0])
    >>> y = g1.simulate(u[:, 0], dt=0.1)[:, 0] + g2.simulate(u[:, 1], dt=0.1)[:, 0]
    >>> s = subspace_pairs([(u, y)], 0.1, np.array([1, 1]), np.array([0, 0]), [0.0, 0.0],
    ...                    "zoh")
    >>> [np.round(a, 3).tolist() for a, _, _ in s]
    [[1.0, 0.5], [1.0, 2.0]]
    """
    orders = sorted({int(np.max(npo)), int(np.sum(npo))}) if order is None else [int(order)]
    best: tuple[float, list[tuple[np.ndarray, np.ndarray, float]]] | None = None
    for n in orders:
        got = _modes(exps, dt, n)
        if got is None:
            continue
        z, weight = got
        s = _continuous_poles(z, dt)
        dens = []
        for j, k in enumerate(np.ravel(npo)):
            p = _channel_poles(s, weight[:, j], int(k))
            dens.append(np.real(np.poly(p)) if p.size else np.ones(1))
        with np.errstate(all="ignore"):
            fitted = _numerators(exps, dens, np.ravel(nze), taus, dt, hold)
        if fitted is not None and (best is None or fitted[1] < best[0]):
            best = (fitted[1], [(a, b, float(t)) for a, b, t in zip(dens, fitted[0], taus)])
    return None if best is None else best[1]


def arx_pairs(exps: list[tuple[np.ndarray, np.ndarray]], dt: float, npo: np.ndarray,
              nze: np.ndarray, taus: list[float], hold: str
              ) -> list[tuple[np.ndarray, np.ndarray, float]] | None:
    """Per input ``(a, b, delay)`` of one output from its least-squares ARX fit (``na`` =
    ``max(npo)``, ``nb`` = ``na``, the delays ``taus`` in whole samples plus one), whose
    ``A`` is not held stable: its poles mapped to continuous time as they are (``log(z) /
    dt``, an unstable pole kept unstable), each pair ``npo[j]`` of them (the slowest first)
    and the numerators by least squares (:func:`_numerators`). A start for the search free
    of the stability bound, which from :func:`sysid.tfest`'s stable fit alone can stop at
    once (a minimum inside the region: 13 of 100 records of an unstable plant left silent);
    ``None`` when the fit fails or its ``A`` has no mode that grows over the longest
    experiment (it would start inside the region the stable search covers).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.tf.starts import arx_pairs
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(400)
    >>> y = sysid.TransferFunction([1.0], [1.0, -0.02]).simulate(u, dt=1.0)[:, 0]
    >>> (a, b, tau), = arx_pairs([(u[:, None], y)], 1.0, np.array([1]), np.array([0]),
    ...                          [0.0], "zoh")
    >>> np.round(a, 3).tolist(), np.round(b, 3).tolist()
    ([1.0, -0.02], [1.0])
    """
    from .. import _sysid
    from ..pem.boundary import grows

    npo, nze = np.ravel(npo), np.ravel(nze)
    n = int(np.max(npo)) if npo.size else 0
    if n == 0:
        return None
    nk = [int(np.floor(t / dt + 1e-9)) + 1 for t in taus]
    try:
        fit = _sysid.arx_fit([(np.ascontiguousarray(u, float),
                               np.ascontiguousarray(np.asarray(y, float)[:, None]))
                              for u, y in exps], [[n]], [[n] * len(taus)], [nk], 0.0, None)[0]
        z = np.roots(np.concatenate([[1.0], np.asarray(fit["a"][0], float)]))
    except Exception:  # noqa: BLE001 - no ARX start
        return None
    longest = max(len(y) for _, y in exps)
    if not grows(z, longest):
        return None
    # log(z) / dt as it is: an unstable pole stays unstable (a pole on the negative real
    # axis, which has no real logarithm, at its modulus; z = 0 at 1e-3)
    r = np.maximum(np.abs(z), 1e-3)
    real = np.abs(z.imag) <= 1e-9 * np.maximum(np.abs(z), 1e-300)
    s = (np.log(r) + 1j * np.where(real, 0.0, np.angle(z))) / dt
    dens = []
    for k in npo:
        p = _channel_poles(s, np.abs(z), int(k))
        dens.append(np.real(np.poly(p)) if p.size else np.ones(1))
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")  # the responses of an unstable start grow
        fitted = _numerators(exps, dens, nze, list(taus), dt, hold)
    if fitted is None:
        return None
    return [(a, b, float(t)) for a, b, t in zip(dens, fitted[0], taus)]
