"""``tfest`` from frequency-response data: Sanathanan-Koerner iterations, then weighted
nonlinear least squares.

For each output/input pair with measured ``H_k = H(omega_k)`` and weights ``W_k``:

1. Sanathanan-Koerner (1963): with the previous denominator ``D_{i-1}`` fixed, the error
   ``W (N - H D) / D_{i-1}`` is linear in the coefficients; a few weighted linear
   least-squares solves (frequency scaled by the geometric mean of the grid for conditioning)
   converge to a good start. A known delay is removed from ``H`` first; ``"auto"`` delays are
   chosen from a grid by the fitted cost.
2. The exact weighted cost ``1/2 sum |W (N/D e^{-j omega tau} - H)|^2`` is minimised on the
   shared Gauss-Newton search (Rust core, :func:`sysid._sysid.tf_fit_frequency`) with the
   delay free or fixed.

The covariance is ``c s (J^T W J)^-1`` with the residual scale ``s = 2 V / (n_residuals -
rank)`` (``sysid_core::optim::residual_scale``, the one rule of ``pem``'s and ``greyest``'s
frequency paths). With an FRD's std, weighted as there (``W = sqrt(2)/std``: each real part
carries half the variance), ``s`` is about 1 when the std is exact and the model right,
about ``(P-1)/(P-2)`` when the std was estimated from ``P`` periods, larger when the model
does not explain the lines. Unweighted, ``s`` is the residual variance of one real part.
``info["residual_scale"]`` holds it per pair. What the scale cannot see: with weights
``1/std_hat`` estimated from ``P`` periods the estimate itself is noisier (the weights fit
the lines whose noise happened to look small too closely), asymptotically in the number of
lines by ``c = (P-2)/(P-3)`` in variance (sample maximum likelihood,
:func:`sysid.pem.periodic.sample_variance_factor`; ``info["sample_variance_factor"]``; 1 for
an FRD whose std is given, a warning and 1 with 3 periods or fewer, where no finite variance
exists). Monte Carlo (a 2nd-order pair, 32 lines, 400 runs; the tfest periodic
uncertainty tests): sample std / predicted std 0.89-0.91 with 4 periods
(1.26-1.29 without ``c``), 1.01-1.05 with 8 (1.10-1.15), 1.02-1.05 with 16. With few lines
carrying the information (8-16 lines for 4 parameters) and 4 periods the std is conservative
by 10-15 %.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import PERSISTENT_DECAY, user_stacklevel
from ..errors import DataError, StabilityWarning
from ..models.paramtable import ParameterTable
from ..models.uncertainty import ParameterUncertainty
from .model import TransferFunction
from .options import blockdiag, delays, pole_zero_orders, progress_callback

__all__ = ["tfest_frd", "sanathanan_koerner", "fit_lines", "record_lines", "warn_held",
           "warn_insisting"]


def sanathanan_koerner(x: np.ndarray, h: np.ndarray, w: np.ndarray, den_pow: list[int],
                       lead: int, num_pow: list[int], iters: int = 20
                       ) -> tuple[np.ndarray, np.ndarray]:
    """``(a, b)`` of ``N/D`` (powers as in the Rust fit) by Sanathanan-Koerner iterations.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.tf.frequency import sanathanan_koerner
    >>> s = 1j * np.logspace(-1, 1, 30)
    >>> a, b = sanathanan_koerner(s, 2 / (s + 3), np.ones(30), [0], 1, [0])
    >>> np.round(a, 8), np.round(b, 8)
    (array([3.]), array([2.]))
    """
    prev = np.ones(x.size, dtype=complex)
    a = np.zeros(len(den_pow))
    b = np.zeros(len(num_pow))
    for _ in range(iters):
        sc = w / np.abs(prev)
        cols = [-h * x ** p for p in den_pow] + [x ** q for q in num_pow]
        M = np.column_stack(cols) * sc[:, None] if cols else np.zeros((x.size, 0))
        rhs = h * x ** lead * sc
        Mr = np.vstack([M.real, M.imag])
        rr = np.concatenate([rhs.real, rhs.imag])
        norms = np.linalg.norm(Mr, axis=0)
        norms[norms == 0] = 1.0
        th = np.linalg.lstsq(Mr / norms, rr, rcond=None)[0] / norms
        a_new, b_new = th[:len(den_pow)], th[len(den_pow):]
        prev = x ** lead + sum(ai * x ** p for ai, p in zip(a_new, den_pow))
        done = np.allclose(a_new, a, rtol=1e-12, atol=0) and np.allclose(b_new, b, rtol=1e-12,
                                                                          atol=0)
        a, b = a_new, b_new
        if done:
            break
    return a, b


def _reflect(a: np.ndarray, cont: bool) -> np.ndarray:
    """Denominator coefficients ``a`` (after the leading 1: descending powers of ``s``, or
    ascending powers of ``z^-1``) with every unstable root reflected into the stable region
    (``s -> -conj(s)``, ``z -> 1 / conj(z)``; roots on the boundary moved 1 % of their
    modulus inside, a root at ``s = 0`` to ``-1e-6`` of the scaled frequency)."""
    r = np.roots(np.concatenate([[1.0], a]))
    if cont:
        inside = np.maximum(np.maximum(np.abs(r.real), 1e-2 * np.abs(r)), 1e-6)
        r = np.where(r.real >= 0, -inside + 1j * r.imag, r)
    else:
        big = np.abs(r) >= 1
        r = np.where(big, 0.99 / np.conj(np.where(big, r, 1.0)), r)
    return np.real(np.poly(r))[1:]


def _is_stable(a: np.ndarray, cont: bool) -> bool:
    """Every root of the denominator ``[1, a]`` (as :func:`_reflect` reads it) stable."""
    r = np.roots(np.concatenate([[1.0], np.asarray(a, float)]))
    return bool(np.all(r.real < 0) if cont else np.all(np.abs(r) < 1))


def _fit_pair(omega: np.ndarray, h: np.ndarray, wgt: np.ndarray, n: int, m: int, dt: float,
              tau0: float, free: bool, max_iter: int, tol: float, cb: Any,
              stable: bool = False, max_delay: float | None = None,
              lag0: int = 1) -> dict[str, Any]:
    cont = not dt
    if cont:
        w0 = float(np.exp(np.mean(np.log(omega[omega > 0])))) if np.any(omega > 0) else 1.0
        x = 1j * omega / w0
        lead, den_pow, num_pow = n, list(range(n - 1, -1, -1)), list(range(m, -1, -1))
    else:
        w0 = 1.0
        x = np.exp(-1j * omega * dt)
        lead, den_pow = 0, list(range(1, n + 1))
    wvar = 1j * omega if cont else np.zeros(omega.size, complex)
    best = free_best = None
    upper = np.inf if max_delay is None else float(max_delay)
    for tau in (_delay_grid(omega, h, dt, max_delay) if free else [tau0]):
        if not cont:  # a delay of whole samples: the numerator's lag, one sample more (as
            # MATLAB, no feedthrough; lag0 = 0 with one), searched over the grid when "auto"
            lag = lag0 + int(round(tau))
            num_pow = list(range(lag, lag + m + 1))
        hd = h * np.exp(wvar * tau)
        a, b = sanathanan_koerner(x, hd, wgt, den_pow, lead, num_pow)
        a = np.asarray(a, float)
        starts = [(a, stable)]
        if stable and n and not _is_stable(a, cont):
            # the reflected start keeps every step stable; the free search from the start
            # itself may leave the unstable region on its own and end lower (a stable end
            # of it is as valid a fit), so both run and the lower stable one is kept
            starts = [(_reflect(a, cont), True), (a, False)]
        for a0, bound in starts:
            th0 = list(a0) + list(b) + [(tau if cont else 0.0) * w0]
            res = _sysid.tf_fit_frequency(
                (x.real.copy(), x.imag.copy()),
                ((wvar / w0).real.copy(), (wvar / w0).imag.copy()),
                (h.real.copy(), h.imag.copy()), list(map(float, wgt)), lead, den_pow,
                num_pow, list(map(float, th0)),
                fixed=[False] * (n + m + 1) + [not (free and cont)],
                lower=[-np.inf] * (n + m + 1) + [0.0],
                upper=[np.inf] * (n + m + 1) + [upper * w0 if cont else np.inf],
                noise_variance=None, max_iter=max_iter, tol=tol, progress=cb, stable=bound)
            res["delay_samples"] = 0 if cont else int(round(tau))
            if stable and not bound:
                if free_best is None or res["cost"] < free_best["cost"]:
                    free_best = res
                if not _is_stable(np.asarray(res["theta"])[:n], cont):
                    continue
            if best is None or res["cost"] < best["cost"]:
                best = res
    assert best is not None
    if free_best is not None and free_best is not best:  # for "the data insist"
        a_free = np.asarray(free_best["theta"])[:n]
        r = np.roots(np.concatenate([[1.0], a_free])) * (w0 if cont else 1.0)
        best["free"] = {"cost": float(free_best["cost"]),
                        "pole": complex(r[np.argmax(r.real if cont else np.abs(r))])}
    # back from the scaled frequency: s = w0 s'
    k = n + m + 1
    scale = np.ones(k + 1)
    if cont:
        scale[:n] = [w0 ** (i + 1) for i in range(n)]
        scale[n:k] = [w0 ** (n + i - m) for i in range(m + 1)]
        scale[k] = 1.0 / w0
    best["theta"] = np.asarray(best["theta"]) * scale
    best["covariance"] = np.asarray(best["covariance"]) * np.outer(scale, scale)
    return best


def _delay_grid(omega: np.ndarray, h: np.ndarray, dt: float,
                max_delay: float | None = None) -> list[float]:
    """Starting delays of the search: eight periods of the highest line in 17 steps
    (continuous, seconds), or every whole sample up to 16 (discrete, where each is fitted
    and the best kept: a delay of samples is no continuous parameter); at most
    ``max_delay``."""
    wmax = float(np.max(omega))
    top = 2.0 * np.pi / wmax * 8 if wmax > 0 else 0.0
    if dt:
        top = 16.0 if max_delay is None else float(max_delay) / dt
        return [float(k) for k in range(int(np.floor(top + 1e-9)) + 1)]
    if max_delay is not None:
        top = min(top, float(max_delay))
    return list(np.linspace(0.0, top, 17)) if top > 0 else [0.0]


def record_lines(data: Any, periods: Any, transient: Any) -> tuple[Any, dict[str, Any]]:
    """The excited lines of periodic data for :func:`fit_lines`, and what was found of the
    periodicity (:func:`sysid.pem.periodic.resolve_periods`; no lines when ``"auto"`` finds
    no usable period). The std of noise-free lines is floored as in ``pem``'s lines."""
    from ..models.frd import FRD
    from ..pem.periodic import line_weights, resolve_periods

    frd, periodicity = resolve_periods(data, periods, transient)
    if frd is None:
        return None, periodicity
    return FRD(frd.omega, frd.response, std=np.sqrt(2.0 / line_weights(frd)), dt=frd.dt,
               dof=frd.dof, input_names=frd.input_names, output_names=frd.output_names,
               method=frd.method, info=frd.info), periodicity


def tfest_frd(frd: Any, n_poles: Any, n_zeros: Any, *, iodelay: Any, dt: Any,
              max_iter: int, tol: float, progress: Any, stable: bool = False,
              max_delay: float | None = None, feedthrough: bool = False) -> TransferFunction:
    """The FRD branch of :func:`sysid.tfest` (see the module documentation)."""
    l, m = frd.n_outputs, frd.n_inputs
    npo, nze = pole_zero_orders(n_poles, n_zeros, l, m)
    given, auto = delays(iodelay, l, m)
    dtv = 0.0 if dt is None else float(dt)
    if dtv and (frd.dt is None or abs(dtv - float(frd.dt)) > 1e-9 * dtv):
        raise DataError(f"a discrete model needs the FRD's sample time: the FRD has dt="
                        f"{frd.dt}, dt={dt} was given")
    insisting: list[dict[str, Any]] = []
    nums, dens, dl, names, thetas, covs, scales, factor = fit_lines(
        frd, npo, nze, given, auto, dtv, max_iter, tol, progress, stable=stable,
        insisting=insisting, max_delay=max_delay, lag0=0 if feedthrough else 1)
    G = _assemble(frd, nums, dens, dl, dtv, names, thetas, covs, auto,
                  lag0=0 if feedthrough else 1)
    G.info["residual_scale"] = scales
    G.info["sample_variance_factor"] = factor
    if stable and not warn_insisting(insisting, "tfest", dtv):
        warn_held(G, frd.omega, dtv)
    if insisting:
        G.info["insisting"] = insisting
    return G


INSIST = 0.01  # the free fit's cost below this share of the stable one's: the data insist


def _grows(p: complex, omega: np.ndarray, dtv: float) -> bool:
    """The mode of pole ``p`` grows by more than ``1 / PERSISTENT_DECAY`` over the longest
    period ``omega`` resolves: clearly unstable, not a pole on the boundary (an integrator,
    which :func:`warn_held` names)."""
    pos = omega[omega > 0]
    horizon = 2 * np.pi / float(np.min(pos)) if pos.size else 1.0
    growth = abs(p) ** (horizon / dtv) if dtv else np.exp(min(p.real * horizon, 700.0))
    return bool(growth * PERSISTENT_DECAY > 1.0)


def warn_insisting(insisting: list[dict[str, Any]], who: str, dtv: float,
                   free: str = "pass enforce_stability=False") -> bool:
    """A :class:`~sysid.StabilityWarning` naming the pairs whose free fit, unstable, has a
    weighted cost below ``INSIST`` (1 %) of the stable model's (errors ten times smaller):
    the frequency response of an unstable plant (measured in closed loop) looks so, and the
    stable model misses it; True if it warned. ``insisting`` as :func:`fit_lines` fills it;
    ``free`` says how to fit the unstable model instead.

    Examples
    --------
    >>> import warnings
    >>> from sysid.tf.frequency import warn_insisting
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     said = warn_insisting([{"pair": "y<-u", "cost": 12.0, "free_cost": 1e-9,
    ...                             "pole": 0.3 + 0j}], "tfest", 0.0)
    >>> said, "s = 0.3" in str(w[0].message)
    (True, True)
    """
    if not insisting:
        return False
    worst = min(insisting, key=lambda d: d["free_cost"] / max(d["cost"], 1e-300))
    p = worst["pole"]
    where = f"z = {p:.4g} (modulus {abs(p):.4g})" if dtv else f"s = {p:.3g}"
    pairs = ", ".join(d["pair"] for d in insisting)
    which = f": for {worst['pair']}, the" if len(insisting) > 1 else ": the"
    warnings.warn(
        f"the data insist on an unstable {who} model for {pairs}{which} "
        f"free fit, with a pole at {where}, has {worst['free_cost'] / worst['cost']:.2g} of "
        "the stable model's weighted cost (its errors over ten times smaller), and the "
        "stable model returned misses the response there. If the plant is unstable (its "
        f"response measured in closed loop), {free}; if not, the "
        "response is poorly measured at some frequencies or needs another structure (more "
        "poles or zeros, a delay)", StabilityWarning, stacklevel=user_stacklevel())
    return True


def warn_held(G: TransferFunction, omega: np.ndarray, dtv: float, who: str = "tfest",
              free: str = "enforce_stability=False shows it") -> bool:
    """A :class:`~sysid.StabilityWarning` when a pole of the stable fit ``G`` (a
    :class:`~sysid.TransferFunction`, or anything with its ``den``, ``output_names`` and
    ``input_names``) sits on the stability boundary: its mode keeps more than
    ``PERSISTENT_DECAY`` over the longest period the frequencies ``omega`` resolve
    (``2 pi / min(omega)``), so the static gain is not determined by them; True if it
    warned. ``who`` names the estimator, ``free`` how to see the free fit.

    Examples
    --------
    >>> import numpy as np, warnings, sysid
    >>> from sysid.tf.frequency import warn_held
    >>> G = sysid.TransferFunction([1.0], [1.0, 1e-9])
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     said = warn_held(G, np.logspace(-2, 1, 20), 0.0)
    >>> said, "stability boundary" in str(w[0].message)
    (True, True)
    """
    pos = omega[omega > 0]
    if not pos.size:
        return False
    horizon = 2 * np.pi / float(np.min(pos))
    worst: tuple[float, complex, str] | None = None
    for i, row in enumerate(G.den):
        for j, a in enumerate(row):
            r = np.roots(np.asarray(a, float))
            r = r[np.isfinite(r)]
            if not r.size:
                continue
            kept = (np.abs(r) ** (horizon / dtv) if dtv else
                    np.exp(np.minimum(r.real, 0.0) * horizon))
            k = int(np.argmax(kept))
            if kept[k] > PERSISTENT_DECAY and (worst is None or kept[k] > worst[0]):
                worst = (float(kept[k]), complex(r[k]),
                         f"{G.output_names[i]}<-{G.input_names[j]}")
    if worst is None:
        return False
    kept, p, pair = worst
    where = f"z = {p:.6g} (modulus 1 - {1 - abs(p):.2g})" if dtv else f"s = {p:.3g}"
    freq = abs(np.angle(p)) / dtv if dtv else abs(p.imag)
    if freq * horizon < 2 * np.pi:
        what = ("so the static gain and the step response's final value are not determined. "
                "If the plant integrates, that is what the model shows; if not")
    else:
        what = (f"an undamped oscillation of period {2 * np.pi / freq:.3g} time units: "
                "a resonance the data cannot damp or an order above what they support; "
                "unless the plant is undamped")
    warnings.warn(
        f"{who}'s model ({pair}) has a pole at {where}, on the stability boundary: the "
        f"search keeps the poles stable and the data held this one "
        f"there; its mode keeps {100 * kept:.0f} % over the longest period the frequencies "
        f"resolve ({horizon:.3g} time units), {what}, the free fit puts the pole in the "
        f"unstable region ({free}): try other numbers of poles and "
        "zeros, a delay (iodelay='auto'), or leave out poorly measured lowest frequencies",
        StabilityWarning, stacklevel=user_stacklevel())
    return True


def fit_lines(frd: Any, npo: np.ndarray, nze: np.ndarray, given: np.ndarray, auto: bool,
              dtv: float, max_iter: int, tol: float, progress: Any, who: str = "tfest",
              stable: bool = False, insisting: list[dict[str, Any]] | None = None,
              max_delay: float | None = None, lag0: int = 1
              ) -> tuple[list[Any], list[Any], np.ndarray, list[str], list[np.ndarray],
                         list[np.ndarray], np.ndarray, float]:
    """The weighted fit of every pair of ``frd`` (``npo`` poles, ``nze + 1`` numerator
    coefficients; a discrete pair lags ``1 + given`` samples): per output the numerators and
    denominators, the delays, and per pair the parameter names, values
    ``[a_1.., b_0.., delay]`` and covariance (scaled by the residual scale and, for a
    :func:`sysid.bla`, the sample-variance factor, see the module notes), and the residual
    scales ``(l, m)``, and the factor (internal: :func:`tfest_frd`, and
    :func:`sysid.tfest`/:func:`sysid.oe` on periodic data; ``who`` names the caller in
    warnings; ``stable``: every denominator kept stable, from a reflected start;
    ``insisting``: a list that receives, per pair, what the free search reached where the
    data insist on an unstable model, see :func:`warn_insisting`)."""
    from ..pem.periodic import line_weights, sample_variance_factor

    l, m = frd.n_outputs, frd.n_inputs
    omega = frd.omega
    k_par = int(np.max(npo + nze + 2))
    if omega.size * 2 < k_par:
        raise DataError(f"the FRD has {omega.size} frequencies, too few for {k_par} "
                        "parameters: measure more frequencies or lower n_poles")
    if frd.std is not None:
        if np.any(frd.std < 0):
            raise DataError("the FRD's std has negative entries: give the measured std (>= 0), "
                            "or remove it for an unweighted fit")
        # sqrt(2)/std: pem's and greyest's weights (a zero std, the noise-free line of a BLA,
        # floored at 1e-6 of the median std; all zero: equal weights)
        weights = np.sqrt(line_weights(frd))
        factor = sample_variance_factor(frd, who)
    else:
        weights, factor = np.ones(frd.response.shape), 1.0
    cb, close = progress_callback(progress, max_iter)
    nums, dens, names, thetas, covs = [], [], [], [], []
    dl, scales = np.zeros((l, m)), np.zeros((l, m))
    try:
        for i in range(l):
            rn, rd = [], []
            for j in range(m):
                n, z = int(npo[i, j]), int(nze[i, j])
                r = _fit_pair(omega, frd.response[:, i, j], weights[:, i, j], n, z, dtv,
                              float(given[i, j]), auto, max_iter, tol, cb, stable,
                              max_delay, lag0)
                th = r["theta"]
                if dtv:  # the delay of whole samples the pair was fitted with
                    th[-1] = float(r["delay_samples"])
                free = r.get("free")
                if (insisting is not None and free and free["cost"] < INSIST * r["cost"]
                        and _grows(free["pole"], omega, dtv)):
                    insisting.append({"pair": f"{frd.output_names[i]}<-{frd.input_names[j]}",
                                      "cost": float(r["cost"]), "free_cost": free["cost"],
                                      "pole": free["pole"]})
                rd.append(np.concatenate([[1.0], th[:n]]))
                rn.append(th[n:n + z + 1])
                dl[i, j] = th[-1]
                scales[i, j] = float(r["noise_variance"])
                pre = f"{frd.output_names[i]}<-{frd.input_names[j]}:"
                names += [f"{pre}a{k + 1}" for k in range(n)] + \
                    [f"{pre}b{k}" for k in range(z + 1)] + [f"{pre}iodelay"]
                thetas.append(th)
                covs.append(factor * r["covariance"])
            nums.append(rn)
            dens.append(rd)
    finally:
        close()
    return nums, dens, dl, names, thetas, covs, scales, factor


def _assemble(frd: Any, nums: list[Any], dens: list[Any], dl: np.ndarray, dtv: float,
              names: list[str], thetas: list[np.ndarray], covs: list[np.ndarray],
              auto: bool, lag0: int = 1) -> TransferFunction:
    if dtv:  # z^-1 polynomials (numerator after its one-sample lag) -> descending powers
        # of z; the delay stays the model's iodelay in samples (as from time-domain data)
        pairs = [[descending(b, a, lag0) for b, a in zip(rn, rd)]
                 for rn, rd in zip(nums, dens)]
        nums = [[p[0] for p in r] for r in pairs]
        dens = [[p[1] for p in r] for r in pairs]
        dl = np.round(dl)
    info = {"method": "tfest (frequency response: Sanathanan-Koerner + weighted NLS)",
            "n_frequencies": int(frd.omega.size), "weighting": "1/std" if frd.std is not None
            else "none", "n_delays_estimated": int(dl.size) if auto else 0}
    G = TransferFunction(nums, dens, dt=dtv, iodelay=dl, input_names=frd.input_names,
                         output_names=frd.output_names, info=info)
    theta = np.concatenate(thetas)
    fixed = np.array([n.endswith("iodelay") and not auto for n in names])
    P = blockdiag(covs)
    G.parameters = ParameterTable(names, theta, np.sqrt(np.clip(np.diag(P), 0, None)), fixed)
    l, m = G.noutputs, G.ninputs
    n_den, o = [], 0
    for th in thetas:
        n_den.append(sum(":a" in x for x in names[o:o + th.size]))
        o += th.size

    def build(t: np.ndarray) -> TransferFunction:
        o, rn, rd, dd = 0, [], [], np.zeros((l, m))
        for i in range(l):
            nn, ddn = [], []
            for j in range(m):
                k = thetas[i * m + j].size
                q = t[o:o + k]
                n = n_den[i * m + j]
                a, b = np.concatenate([[1.0], q[:n]]), q[n:k - 1]
                if dtv:
                    b, a = descending(b, a, lag0)
                ddn.append(a)
                nn.append(b)
                dd[i, j] = max(q[-1], 0.0)
                o += k
            rn.append(nn)
            rd.append(ddn)
        return TransferFunction(rn, rd, dt=dtv, iodelay=np.round(dd) if dtv else dd,
                                input_names=G.input_names, output_names=G.output_names)

    G.uncertainty = ParameterUncertainty(theta, P, build, names=names)
    return G


def descending(b: np.ndarray, a: np.ndarray, lag0: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """A discrete pair ``z^-lag0 B(z^-1) / A(z^-1)`` (``lag0`` 1, or 0 with feedthrough) as
    numerator and denominator in descending powers of ``z`` (of equal length)."""
    b = np.concatenate([np.zeros(lag0), b])
    k = max(a.size, b.size)
    return np.pad(b, (0, k - b.size)), np.pad(a, (0, k - a.size))
