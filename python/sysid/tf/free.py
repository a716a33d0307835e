""":func:`sysid.tfest`'s search free of the stability bound on time records: where it starts.

With ``enforce_stability=True`` (the default) the fit is kept stable, and a search free of
the bound decides whether the data insist on an unstable model (:func:`.refine.free_test`);
with ``False`` the free search's model is returned. From the stable fit alone the free search
stops at once wherever that fit is a minimum of the free criterion too: on 7 of 100
records of an unstable plant (the warning audit's ``unstable`` scenario, a real pole at
``z`` = 1.01-1.03) it did not move, and the stable model was returned without a word (on 6
more it moved, but not to the plant's pole). The
free search therefore also starts from the output's least-squares ARX fit, whose ``A`` is
not held stable (:func:`.starts.arx_pairs`, as :func:`sysid.oe`'s test does), when that fit
has a mode that grows over the record.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..errors import DataError
from .refine import PairStructure, free_search, refine

__all__ = ["arx_start", "free_fit", "reflected", "unstable_uncertainty"]


def reflected(pair: PairStructure, q: np.ndarray) -> np.ndarray:
    """A pair's parameters ``[a_1.., b..]`` with the unstable poles of
    ``s^n + a_1 s^(n-1) + ...`` mirrored into the left half-plane (``s -> -conj(s)``; the
    numerator kept).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.tf.free import reflected
    >>> from sysid.tf.refine import PairStructure
    >>> pr = PairStructure(lambda p: (p[1:], np.concatenate([[1.0], p[:1]])), np.zeros(2),
    ...                    np.zeros(2, bool), np.full(2, -np.inf), np.full(2, np.inf))
    >>> reflected(pr, np.array([-0.5, 2.0])).tolist()
    [0.5, 2.0]
    """
    num, den = pair.coef(np.asarray(q, float))
    r = np.roots(den)
    r = np.where(r.real > 0, -np.conj(r), r)
    return np.concatenate([np.real(np.poly(r))[1:], num])


def arx_start(res: dict[str, Any], pairs: list[PairStructure],
              exps: list[tuple[np.ndarray, np.ndarray]], dt: float, npo: np.ndarray,
              nze: np.ndarray, hold: str) -> list[PairStructure] | None:
    """The pairs of one output (the structures ``pairs``, the delays where the search
    ``res`` ended) started at its least-squares ARX fit (:func:`.starts.arx_pairs`); ``None``
    when that fit has no growing mode or fails.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.tf.free import arx_start
    >>> from sysid.tf.refine import PairStructure
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(400)
    >>> y = sysid.TransferFunction([1.0], [1.0, -0.02]).simulate(u, dt=1.0)[:, 0]
    >>> pr = PairStructure(lambda p: (p[1:], np.concatenate([[1.0], p[:1]])),
    ...                    np.array([0.5, 1.0]), np.zeros(2, bool), np.full(2, -np.inf),
    ...                    np.full(2, np.inf))
    >>> got = arx_start({"delays": [0.0]}, [pr], [(u[:, None], y)], 1.0, np.array([1]),
    ...                 np.array([0]), "zoh")
    >>> np.round(got[0].p0, 3).tolist()
    [-0.02, 1.0]
    """
    from .starts import arx_pairs

    got = arx_pairs(exps, dt, np.ravel(npo), np.ravel(nze), list(res["delays"]), hold)
    if got is None:
        return None
    return [PairStructure(pr.coef, np.concatenate([a[1:], b]), pr.fixed, pr.lower, pr.upper,
                          t, pr.delay_free, pr.delay_max, pr.names)
            for pr, (a, b, t) in zip(pairs, got)]


def free_fit(res: dict[str, Any], pairs: list[PairStructure],
             exps: list[tuple[np.ndarray, np.ndarray]], dt: float, npo: np.ndarray,
             nze: np.ndarray, hold: str, x0_mode: str, max_iter: int, tol: float
             ) -> tuple[dict[str, Any], list[Any]] | None:
    """``enforce_stability=False``: the search free of the bound from the stable fit ``res``
    and from the ARX start (:func:`arx_start`), the lower criterion kept with its warnings
    (held back: the caller raises them); ``None`` when neither lowers ``res``'s.

    Examples
    --------
    >>> import numpy as np, sysid, warnings
    >>> from sysid.tf.free import free_fit
    >>> from sysid.tf.refine import PairStructure, refine
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(400)
    >>> y = sysid.TransferFunction([1.0], [1.0, -0.02]).simulate(u, dt=1.0)[:, 0]
    >>> y = y + 0.1 * rng.standard_normal(400)
    >>> pr = PairStructure(lambda p: (p[1:], np.concatenate([[1.0], p[:1]])),
    ...                    np.array([0.5, 1.0]), np.zeros(2, bool), np.full(2, -np.inf),
    ...                    np.full(2, np.inf), names=["a1", "b0"])
    >>> exps = [(u[:, None], y)]
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     held = refine([pr], exps, 1.0, "zoh")  # kept stable
    >>> got, said = free_fit(held, [pr], exps, 1.0, np.array([1]), np.array([0]), "zoh",
    ...                      "zero", 50, 1e-10)
    >>> round(float(got["p"][0][0]), 3)  # a1: the pole at s = 0.02
    -0.02
    """
    best = None
    arx = arx_start(res, pairs, exps, dt, npo, nze, hold)
    for start in [None] + ([arx] if arx is not None else []):
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            try:
                got = free_search(res, pairs, exps, dt, hold, x0_mode, max_iter, tol) \
                    if start is None else refine(start, exps, dt, hold, x0_mode=x0_mode,
                                                 max_iter=max_iter, tol=tol, stable=False)
            except (DataError, ArithmeticError):
                got = None
        if got is None:
            continue
        c = got["cost_history"][-1]
        if c < res["cost_history"][-1] and (best is None or c < best[0]["cost_history"][-1]):
            best = (got, list(said))
    return best


#: singular values of the column-scaled Jacobian kept, relative to the largest: where the
#: columns are the exact sensitivities (simulated filters, rounding of about 1e-14 of the
#: growing samples) and where a column is a central difference (relative step ``_STEP``,
#: accurate to about 1e-10 of a column)
_SV_EXACT, _SV_DIFF, _STEP = 1e-12, 1e-8, 1e-5
#: the search's rank test on the singular values (its 1e-10 is on their squares)
_RANK = 1e-5
FIX = "Lower n_zeros, fix the delay or use more informative data"


def unstable_uncertainty(res: dict[str, Any], said: list[Any], pairs: list[PairStructure],
                         exps: list[tuple[np.ndarray, np.ndarray]], dt: float, hold: str,
                         x0_mode: str) -> list[Any]:
    """The covariance of an unstable fit ``res`` of one output, from the simulation-error
    criterion it minimised, with a rank test the growth of its sensitivities does not
    defeat; returns ``said`` (the search's warnings) without the
    :class:`~sysid.IdentifiabilityWarning` of the search's own rank test, ``res`` updated in
    place (a stable fit: both as they are).

    That test drops the directions whose Gauss-Newton eigenvalue is below 1e-10 of the
    largest (after Jacobi scaling). The sensitivities of an unstable model grow with its
    mode, so the record's last samples dominate that matrix and its eigenvalues span
    about ``exp(2 sigma T)``: on 600 samples of a plant with a pole at ``z`` = 1.02 they
    spanned 2e-13, and every parameter was named as one the data cannot determine (its
    standard deviation inf), where 30 noise realisations put the four parameters' spread
    within 10 % of the covariance computed here. With white output errors the criterion is
    the likelihood of the model from rest, unstable or not, so its Gauss-Newton covariance
    stands. It is formed from the singular values of the column-scaled Jacobian (never
    squared): the sensitivities to the coefficients are the responses of the filters
    ``-s^k B / A^2`` and ``s^k / A`` (sampled with the data's hold and delay: sampling is
    linear in the transfer function), exact; a delay's, and every column when the initial
    state was estimated (fitted again in each), by central differences. The rank test is
    the search's (1e-10 on the eigenvalues, 1e-5 on the singular values) loosened by the
    spread the mode adds, ``exp(-sigma T)``, down to the accuracy of the columns (1e-12 of
    the largest singular value, 1e-8 with a difference): a direction below the loosened
    test is named by the IdentifiabilityWarning, as before; one below the columns' accuracy
    only keeps an infinite standard deviation, and an
    :class:`~sysid.models.uncertainty.UncertaintyWarning` says why (the growth of the mode)
    instead of claiming that the data do not determine it. A fit held at the bound (a mode
    that grows by less than ``1 / PERSISTENT_DECAY`` over the record) keeps the search's
    covariance and warnings. On the first 40 records of the warning audit's ``unstable``
    scenario with ``enforce_stability=False``: the IdentifiabilityWarning on 32 of 37
    unstable fits before; now on 2 of 40 (low-pass inputs; one fit has a pole at
    ``s`` = -15 with ``dt`` = 1, far beyond the band the input excites) and this
    UncertaintyWarning on 1.

    Examples
    --------
    >>> import numpy as np, sysid, warnings
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(600)
    >>> g = sysid.TransferFunction([0.5, 0.3], np.poly([1.02, 0.7]), dt=1.0)
    >>> y = g.simulate(u)[:, 0]
    >>> d = sysid.IOData(u, y + 0.05 * y[:200].std() * rng.standard_normal(600), dt=1.0)
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", sysid.StabilityWarning)
    ...     G = sysid.tfest(d, 2, 1, enforce_stability=False)
    >>> bool(np.all(np.isfinite(G.parameters.std)))
    True
    """
    from ..greybox.greybox import IdentifiabilityWarning
    from ..pem.boundary import grows

    growth = max((float(np.max(np.roots(pr.coef(q)[1]).real)) for pr, q in zip(pairs, res["p"])
                  if pr.coef(q)[1].size > 1), default=-np.inf)
    longest = max(len(y) for _, y in exps)
    span = longest * dt
    if not grows([growth], longest, dt):
        return said  # no mode grows over the record: the search's own rank test stands
    names = [nm for pr in pairs for nm in pr.names] + [
        f"{pairs[j].names[0].split(':')[0]}:iodelay" if pairs[j].names else f"iodelay{j}"
        for j in res["delay_index"]]
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            J, exact = _jacobian(res, pairs, exps, dt, hold, x0_mode)
    except (DataError, ArithmeticError, ValueError, np.linalg.LinAlgError):
        return said
    if not np.all(np.isfinite(J)):
        return said
    D = np.linalg.norm(J, axis=0)
    D = np.where(D > 0, D, 1.0)
    _, S, Vt = np.linalg.svd(J / D, full_matrices=False)
    # the search's test (1e-10 on eigenvalues: _RANK on singular values), loosened by the
    # spread the growing mode adds over the record, down to the columns' accuracy
    floor = max(_RANK * np.exp(-growth * span), _SV_EXACT if exact else _SV_DIFF)
    keep = S > floor * S[0]
    F = Vt[keep].T / S[keep] / D[:, None]
    res["covariance"] = float(res["noise_variance"]) * (F @ F.T)
    kept = [w for w in said if not (issubclass(w.category, IdentifiabilityWarning) and str(
        w.message).startswith("the data cannot determine these parameters separately"))]
    res["unidentifiable"] = []
    if keep.all():
        return kept
    from ..models.uncertainty import UncertaintyWarning
    from .refine import _unidentifiable

    with warnings.catch_warnings(record=True) as again:
        warnings.simplefilter("always")
        if floor > (_SV_EXACT if exact else _SV_DIFF):  # the test decided: a true warning
            res["unidentifiable"] = _unidentifiable((Vt[~keep] / D).T, names, FIX)
            return kept + list(again)
        weak = sorted({int(i) for v in Vt[~keep] / D for i in
                       np.flatnonzero(np.abs(v) >= 1e-3 * np.max(np.abs(v)))})
        res["unidentifiable"] = weak
        warnings.warn(
            f"the standard deviations of {', '.join(names[i] for i in weak)} are not computed "
            f"(reported as inf): the model is unstable (a pole at real part {growth:.3g}), so "
            f"its sensitivities grow by a factor of about {np.exp(growth * span):.2g} over "
            f"the record and {int((~keep).sum())} direction(s) of the Jacobian fall below the "
            "precision it is computed to, so whether the data determine them cannot be told "
            "from it (a Monte Carlo run, or sysid.ssest's prediction focus, gives a spread)",
            UncertaintyWarning, stacklevel=2)
    return kept + list(again)


def _jacobian(res: dict[str, Any], pairs: list[PairStructure],
              exps: list[tuple[np.ndarray, np.ndarray]], dt: float, hold: str,
              x0_mode: str) -> tuple[np.ndarray, bool]:
    """The Jacobian of one output's simulation (all records stacked) in ``res``'s parameters
    ``[p of each pair..., estimated delays...]``, and whether every column is exact."""
    from .model import TransferFunction

    sizes = [len(q) for q in res["p"]]
    v0 = np.concatenate([np.concatenate(res["p"]), [res["delays"][j]
                                                   for j in res["delay_index"]]])
    cols: list[np.ndarray] = []
    if x0_mode != "estimate":
        o = 0
        for j, (pr, k) in enumerate(zip(pairs, sizes)):
            num, den = pr.coef(v0[o:o + k])
            base = np.zeros(k)
            for c in range(k):  # d(num, den)/dp_c from the parameterisation (linear here)
                e = base.copy()
                e[c] = 1.0
                dn, dd = pr.coef(v0[o:o + k] + e)
                dn, dd = np.asarray(dn) - num, np.asarray(dd) - den
                # d(B/A) = (dB A - B dA) / A^2
                top = np.polysub(np.polymul(dn, den), np.polymul(num, dd))
                g = TransferFunction(top, np.polymul(den, den), iodelay=res["delays"][j],
                                     hold=hold)
                cols.append(np.concatenate([g.simulate(u[:, j], dt=dt, hold=hold)[:, 0]
                                            for u, _ in exps]))
            o += k
    exact = x0_mode != "estimate" and not res["delay_index"]

    def sim(v: np.ndarray) -> np.ndarray:
        nums, dens, taus, o = [], [], list(res["delays"]), 0
        for pr, k in zip(pairs, sizes):
            num, den = pr.coef(v[o:o + k])
            nums.append(num)
            dens.append(den)
            o += k
        for j in res["delay_index"]:
            taus[j] = max(float(v[o]), 0.0)
            o += 1
        g = TransferFunction([nums], [dens], iodelay=[taus], hold=hold)
        out = []
        for u, y in exps:
            s = g.simulate(u, dt=dt, hold=hold)
            if x0_mode == "estimate":
                from ..pem.sandwich import free_response, with_fitted_state

                Ad, _, Cd = g.sampled_taps(dt, hold)[:3]
                s = with_fitted_state(s, y[:, None], free_response(Ad, Cd, len(y)))
            out.append(np.asarray(s, float)[:, 0])
        return np.concatenate(out)

    for c in range(len(cols), v0.size):  # central differences for the rest
        h = _STEP * max(abs(v0[c]), 1e-3)
        e = np.zeros(v0.size)
        e[c] = h
        cols.append((sim(v0 + e) - sim(v0 - e)) / (2 * h))
    return np.column_stack(cols), exact
