"""Whether the data insist on an unstable ``F`` where the search of ``oe``, ``bj`` or
``polyest`` keeps every ``F`` stable, and whether an unstable plant's growth went into the
noise model ``C / D`` instead (issue 26: a stable model unless the data insist, and then a
StabilityWarning that names the pole and the option)."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import user_stacklevel
from ..errors import DataError, NumericalError, StabilityWarning
from .model import PolynomialModel

__all__ = ["warn_growing_noise", "warn_insisting_f"]

# a noise model whose disturbance grows more than this many times over the record: no drift
# of a stable plant does (a root on the bound, a random walk, stays near 1)
NOISE_GROWTH = 10.0


def warn_insisting_f(m: PolynomialModel, exps: list[Any], rs: list[dict[str, Any]],
                      na: list[int], nb: list[list[int]], nc: list[int], nd: list[int],
                      nf: list[list[int]], nk: list[list[int]], iters: int,
                      method: str = "oe") -> bool:
    """The search keeps every ``F`` stable: from each output's fit, the search again with
    ``F`` free to leave the unit circle, and a :class:`~sysid.StabilityWarning` when the data
    insist on an unstable ``F`` (:func:`sysid.pem.boundary.insists`, 1 %), naming the pole
    and what fits it (``method``, ``oe``, ``bj`` or ``polyest``, itself keeps ``F`` stable);
    True if it warned. From a minimum inside the stability region the free search stops at
    once; an unstable plant's record (a real pole at 1.01-1.03) left ``oe``'s stable fit
    silent in 48 of 100 runs, and ``bj``'s and ``polyest``'s in 6 of the first 10."""
    from ..pem.boundary import grows, insists, warn_insisted

    found = []
    longest = max(len(y) for _, y in exps)
    for i, r in enumerate(rs):
        if not any(nf[i]) or r.get("stop") == "cancelled":
            continue
        runs = []
        arx = _arx_start(exps, i, na[i], nb[i], nc[i], nd[i], nf[i], nk[i], longest)
        for start in (r["theta"], arx):
            if start is None:
                continue
            try:
                runs.append(_sysid.polynomial_free_search(
                    [(np.ascontiguousarray(y[:, i]), u) for u, y in exps], na[i], nb[i],
                    nc[i], nd[i], nf[i], nk[i], list(map(float, start)),
                    initial_condition=r["initial_condition"], max_iter=max(iters, 1)))
            except (DataError, NumericalError):
                continue
        if not runs or not np.isfinite(runs[0]["kept_cost"]):
            continue
        # the stable fit against the better free search: from it (which stops at once at a
        # minimum inside the region) and from the unconstrained least-squares ARX fit
        free = min(runs, key=lambda x: x["cost"] if np.isfinite(x["cost"]) else np.inf)
        lr, yes = insists(runs[0]["kept_cost"], free["cost"], sum(len(y) for _, y in exps))
        if not yes:
            continue
        th = np.asarray(free["theta"], float)
        at = na[i] + sum(nb[i]) + nc[i] + nd[i]
        for j, n in enumerate(nf[i]):
            roots = np.roots(np.concatenate([[1.0], th[at:at + n]])) if n else np.zeros(0)
            at += n
            # a mode growing less than 1 / PERSISTENT_DECAY over the record is one on the
            # bound (an integrating plant: the held pole's own warning names it)
            if grows(roots, longest):
                found.append((lr, f"{m.output_names[i]} <- {m.input_names[j]}",
                              complex(roots[np.argmax(np.abs(roots))])))
    if not found:
        return False
    lr, pair, pole = max(found, key=lambda x: x[0])
    warn_insisted(f"the {method} model's F", pair, pole, float(m.dt), lr,
                  f"{method} keeps F stable: sysid.ssest(data, order) (prediction focus, "
                  f"whose default returns the unstable model when the data insist) or "
                  f"arx/armax (whose A is not held stable) fit it")
    m.info["insisting"] = [{"pair": p, "pole": z, "statistic": v} for v, p, z in found]
    return True


def warn_growing_noise(m: PolynomialModel, d: list[np.ndarray], method: str,
                       longest: int) -> bool:
    """A :class:`~sysid.StabilityWarning` when ``F`` is stable but the noise model is not:
    ``D`` (``bj``, ``polyest``) of an output has a root whose mode grows more than
    ``NOISE_GROWTH`` times over the ``longest`` experiment. The record's growing mode then
    sits in the disturbance model ``C / D``, which the predictor cancels (``D / C``), so the
    prediction errors are white and the free search over ``F``
    (:func:`warn_insisting_f`) does not insist, while the simulation ``B / F`` misses the
    growth. On the warning audit's unstable plants (a real pole at 1.01-1.03, 800 samples)
    ``bj(data, n, 1, 1, n, 1)`` put that pole in ``D`` in 40 of 40 runs and said nothing in
    10. No ``D`` root grew tenfold on the clean and closed-loop records; of the shipped real
    ones only ball and beam's (24-fold, an unstable plant the free search already names).
    True if it warned.

    Examples
    --------
    >>> import warnings, numpy as np, sysid
    >>> from sysid.polynomial.stability import warn_growing_noise
    >>> m = sysid.PolynomialModel([[[]]], [[[0.5]]], [[1]], 1.0, c=[[0.3]], d=[[-1.02]],
    ...                           f=[[[-0.5]]])
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_growing_noise(m, [np.array([-1.02])], "bj", 800)
    True
    >>> w[0].category.__name__, "noise model" in str(w[0].message)
    ('StabilityWarning', True)
    """
    worst: tuple[float, str, complex] | None = None
    for i, di in enumerate(d):
        di = np.asarray(di, float)
        if not di.size or not np.all(np.isfinite(di)):
            continue
        roots = np.roots(np.concatenate([[1.0], di]))
        z = complex(roots[np.argmax(np.abs(roots))])
        growth = float(np.exp(min(longest * np.log(max(abs(z), 1e-300)), 700.0)))
        if growth > NOISE_GROWTH and (worst is None or growth > worst[0]):
            worst = (growth, m.output_names[i], z)
    if worst is None:
        return False
    growth, out, z = worst
    warnings.warn(
        f"the {method} model's F is stable, but its noise model is not: D of {out} has a root "
        f"at z = {z:.4g} (modulus {abs(z):.4g}), whose mode grows {growth:.3g}-fold over the "
        f"record. The record's growing mode went into the disturbance model C/D, which the "
        f"predictor cancels, and the simulation B/F does not follow it. If the plant is "
        f"unstable, sysid.ssest(data, order) (prediction focus) or arx/armax (whose A is not "
        f"held stable) fit it; if not, look for a drift or an offset left in the data "
        f"(sysid.detrend(data, 'linear') removes both)", StabilityWarning,
        stacklevel=user_stacklevel())
    m.info["growing_noise"] = {"output": out, "root": z, "growth": growth}
    return True


def _arx_start(exps: list[Any], i: int, na: int, nb: list[int], nc: int, nd: int,
               nf: list[int], nk: list[int], longest: int) -> np.ndarray | None:
    """Output ``i``'s parameters (``[a, b, c, d, f]``) from its least-squares ARX fit, whose
    ``A`` is not held stable: ``F`` of every input its ``A`` (truncated or padded to ``nf``),
    ``B`` its ``B``, ``C`` and ``D`` zero. A second start for the free search, which from a
    stable minimum alone stops at once; None when the fit cannot be made or its ``A`` has
    no mode that grows over the ``longest`` experiment (then it starts inside the region the
    first search covers)."""
    from ..pem.boundary import grows

    n = max(nf)
    try:
        fit = _sysid.arx_fit([(np.ascontiguousarray(u, float),
                               np.ascontiguousarray(y[:, [i]], float)) for u, y in exps],
                             [[n]], [list(nb)], [list(nk)], 0.0, None)[0]
    except Exception:  # noqa: BLE001 - no second start
        return None
    a = np.asarray(fit["a"][0], float)
    roots = np.roots(np.concatenate([[1.0], a])) if n else np.zeros(0)
    if not grows(roots, longest):
        return None
    f = [np.concatenate([a, np.zeros(max(k - n, 0))])[:k] for k in nf]
    b = [np.asarray(x, float) for x in fit["b"]]
    parts = [np.zeros(na)] + b + [np.zeros(nc), np.zeros(nd)] + f
    return np.concatenate(parts)
