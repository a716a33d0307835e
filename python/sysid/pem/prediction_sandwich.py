"""The parameter covariance of a prediction-error fit whose noise model cannot represent
the disturbance.

A prediction-error fit of an innovations model ``y = G u + H e`` reports the Gauss-Newton
covariance ``(J^T W J)^-1``, which holds when its one-step prediction errors
``eps = H^-1 (y - G u)`` are white. When ``H`` cannot take the shape of the disturbance's
spectrum they are not, and the covariance is the sandwich of :mod:`sysid.pem.sandwich`
(Ljung, *System Identification*, 1999, eq. 9.42) with the errors' spectrum. A state-space
noise model ``H = I + C (qI - A)^-1 K`` shares its poles with ``G``: its inverse has zeros on
the plant's poles, and the errors' spectrum a notch at a lightly damped resonance, just
where the plant's parameters are learnt. An autoregressive model of the errors themselves
(the simulation-error sandwich's) cannot follow a notch that deep and narrow; here the
spectrum is ``H^-1 S_v H^-H``, the model's own (exactly known) ``H^-1`` applied to an
autoregressive model ``S_v`` of the disturbance ``v = H eps = y - G u`` (the simulation
errors from the same initial state), whose spectrum is smooth where the errors' is not. The
errors' own autoregressive model is the alternative; the one of lower BIC (the same Gaussian
likelihood of the errors: ``H`` is monic and minimum phase; BIC, as errors of a noise model
that fits are white and should stay so) is used, and white errors keep the Gauss-Newton
covariance.

On a mass-spring-damper grey box with an AR(1) output disturbance, fitted with a free
``K`` (``greyest(..., noise="estimate")``, 200 runs), the Gauss-Newton standard deviations
of the stiffness and damping were 1.80 and 1.53 times the sample ones (the errors' own
AR model: 1.57 and 1.34); this covariance gives 1.15 and 1.04, its 95 % intervals covering
94-96 % (``tests/test_greyest_kalman.py``).

A free state-space fit (:func:`sysid.pem`, :func:`sysid.ssest`, ``focus="prediction"``, the
default) has the same noise model: :func:`defer_prediction` forms this covariance when its
uncertainty is first used, along the Gauss-Newton covariance's identifiable directions. On a
second-order plant with poles ``0.95 exp(+-0.5 i)`` and an AR(1) disturbance (200 runs of
1000 samples) the Gauss-Newton std of the pole's radius and angle were 1.72 and 1.55 times
the sample ones; this covariance gives 1.02 and 0.94, covering 92-94 %
(``tests/test_ssest_prediction_coloured.py``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..models.statespace import StateSpaceModel
from ..models.uncertainty import ParameterUncertainty
from .boundary import spectral_radius
from .sandwich import MAX_ENTRIES, DeferredSandwich, _ar_fit, _weight_matrix

__all__ = ["defer_prediction", "inverse_noise_response", "prediction_errors",
           "prediction_sandwich", "state_space_sandwich"]


def inverse_noise_response(A: Any, K: Any, C: Any, nfft: int) -> np.ndarray:
    """``H^-1(e^{iw}) = I - C (e^{iw} I - (A - K C))^-1 K`` of the innovations model
    ``(A, K, C)`` on the ``rfft`` grid of ``nfft`` points, ``(nfft // 2 + 1, l, l)``.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.pem.prediction_sandwich import inverse_noise_response
    >>> h = inverse_noise_response([[0.9]], [[0.5]], [[1.0]], 8)  # (q - 0.9) / (q - 0.4)
    >>> bool(np.isclose(h[0, 0, 0], 0.1 / 0.6)), bool(np.isclose(h[-1, 0, 0], -1.9 / -1.4))
    (True, True)
    """
    A, K, C = (np.atleast_2d(np.asarray(x, float)) for x in (A, K, C))
    n, l = K.shape
    z = np.exp(2j * np.pi * np.arange(nfft // 2 + 1) / nfft)
    Ab = A - K @ C
    X = np.linalg.solve(z[:, None, None] * np.eye(n) - Ab, np.broadcast_to(K, (z.size, n, l)))
    return np.eye(l) - C @ X


def prediction_sandwich(jacobians: Sequence[np.ndarray], errors: Sequence[np.ndarray],
                        disturbances: Sequence[np.ndarray] | None, inverse_noise: Any,
                        weights: Any = None, max_order: int = 30
                        ) -> tuple[np.ndarray | None, str]:
    """The sandwich covariance ``G^+ M G^+`` of the parameters of a prediction-error fit
    (``G = J^T W J``, ``M = J^T W Sigma W J``), ``Sigma`` from the errors' spectrum.

    Parameters
    ----------
    jacobians : list of ndarray
        Per record, the Jacobian ``(N, l, r)`` of the prediction errors in the ``r``
        searched parameters.
    errors : list of ndarray
        Per record, the prediction errors ``(N, l)`` at the estimate.
    disturbances : list of ndarray or None
        Per record, ``H eps`` (the simulation errors from the same initial state); ``None``
        when the model's noise filter does not apply (an unstable plant or a predictor
        whose responses outlast the record): the errors' own AR model only.
    inverse_noise : callable or None
        ``nfft -> H^-1`` on the ``rfft`` grid (:func:`inverse_noise_response`).
    weights : ndarray, optional
        The criterion's weighting as a matrix ``T`` applied to the errors (``W = T^T T``);
        default the identity.
    max_order : int
        Highest autoregressive order (chosen by BIC, at most a tenth of the samples).

    Returns
    -------
    ndarray or None, str
        The ``(r, r)`` covariance (``None``: the errors are white, or the correction is
        too large to form; the Gauss-Newton covariance stands) and the sentence saying
        which covariance it is.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.signal import lfilter
    >>> from sysid.pem.prediction_sandwich import prediction_sandwich
    >>> rng = np.random.default_rng(0)
    >>> J = rng.standard_normal((500, 1, 1))
    >>> P, note = prediction_sandwich([J], [rng.standard_normal((500, 1))], None, None)
    >>> P is None, note                              # white errors: Gauss-Newton
    (True, 'gauss-newton: the prediction errors are white')
    >>> e = lfilter([1.0], [1.0, -0.8], rng.standard_normal(500))[:, None]
    >>> P, note = prediction_sandwich([np.cumsum(J, 0)], [e], None, None)
    >>> note.startswith("sandwich for coloured prediction errors"), P.shape
    (True, (1, 1))
    """
    Js = [np.asarray(j, float) for j in jacobians]
    es = [np.asarray(e, float) for e in errors]
    l, r = Js[0].shape[1], Js[0].shape[2]
    total = sum(e.shape[0] for e in es)
    if total * l * r > MAX_ENTRIES:
        return None, (f"gauss-newton, as for white errors: the coloured-error correction "
                      f"would hold {total * l * r:.2g} numbers (at most {MAX_ENTRIES:.0e})")
    if not all(np.all(np.isfinite(x)) for x in [*Js, *es]):
        return None, "gauss-newton, as for white errors: the errors or their Jacobian overflow"

    penalty = float(np.log(total))  # BIC: white errors (a right noise model) stay so

    def ar_models(series: Sequence[np.ndarray]) -> tuple[list[Any], float]:
        fits = [_ar_fit([s[:, k] for s in series], max_order, penalty) for k in range(l)]
        if any(v <= 0 for _, v, _ in fits):
            return fits, np.inf
        return fits, float(sum(total * np.log(v) + penalty * p for _, v, p in fits))

    own, aic_own = ar_models(es)
    through, aic_through = None, np.inf
    if disturbances is not None and inverse_noise is not None:
        vs = [np.asarray(v, float) for v in disturbances]
        if all(np.all(np.isfinite(v)) for v in vs):
            through, aic_through = ar_models(vs)
    use_through = through is not None and aic_through < aic_own
    fits = through if use_through else own
    orders = ", ".join(str(p) for _, _, p in fits)  # type: ignore[union-attr]
    if not use_through and all(p == 0 for _, _, p in own):
        return None, "gauss-newton: the prediction errors are white"
    T = _weight_matrix(weights, l)
    G = np.zeros((r, r))
    M = np.zeros((r, r))
    for J in Js:
        N = J.shape[0]
        TJ = np.einsum("kj,tjr->tkr", T, J)
        G += np.einsum("tkr,tks->rs", TJ, TJ)
        nfft = 1 << int(np.ceil(np.log2(2 * N)))
        wts = np.full(nfft // 2 + 1, 2.0)  # the rfft grid's weights on the full one
        wts[0] = wts[-1] = 1.0
        S = np.stack([v / np.abs(np.fft.rfft(np.r_[1.0, -a], nfft)) ** 2
                      for a, v, _ in fits], axis=-1)  # type: ignore[union-attr]
        if use_through:
            Hi = inverse_noise(nfft)
            phi = Hi @ np.einsum("wj,ij->wij", S, np.eye(l)) @ np.conj(np.swapaxes(Hi, 1, 2))
        else:
            phi = np.einsum("wj,ij->wij", S, np.eye(l))
        F = np.fft.rfft(TJ, nfft, axis=0)
        M += np.einsum("w,wkr,wks->rs", wts, np.conj(F), (T @ phi @ T.T) @ F).real / nfft
    Gi = np.linalg.pinv(0.5 * (G + G.T), rcond=1e-10, hermitian=True)
    P = Gi @ (0.5 * (M + M.T)) @ Gi
    if not np.all(np.isfinite(P)):
        return None, "gauss-newton, as for white errors: the correction overflows"
    what = ("the disturbance's autoregressive order " + orders + " through the model's "
            "noise filter" if use_through else "the errors' own autoregressive order " + orders)
    return 0.5 * (P + P.T), f"sandwich for coloured prediction errors ({what})"


Records = Sequence[tuple[np.ndarray, np.ndarray]]


def prediction_errors(A: Any, B: Any, C: Any, D: Any, K: Any, records: Records,
                      x0s: Sequence[Any], simulation: bool = False) -> list[np.ndarray]:
    """Per record ``(u, y)``, the one-step prediction errors ``(N, l)`` of the innovations
    model ``(A, B, C, D, K)`` (its Kalman predictor from the state ``x0s[e]``); with
    ``simulation=True`` its simulation errors ``y - G u`` from the same state (the
    disturbance ``H eps``). ``K=None``: no noise model (the two coincide).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.pem.prediction_sandwich import prediction_errors
    >>> u, y = np.zeros((3, 1)), np.array([[1.0], [0.0], [0.0]])
    >>> e = prediction_errors([[0.5]], [[1.0]], [[1.0]], [[0.0]], [[0.5]], [(u, y)], [[0.0]])
    >>> e[0][:, 0].tolist()                        # 1 / H = (q - 0.5) / q
    [1.0, -0.5, 0.0]
    """
    A, B, C, D = (np.atleast_2d(np.asarray(x, float)) for x in (A, B, C, D))
    l = C.shape[0]
    K = np.zeros((A.shape[0], l)) if K is None else np.atleast_2d(np.asarray(K, float))
    if simulation:
        ss = StateSpaceModel(A, B, C, D)
        return [np.asarray(y, float) - ss.simulate(u, x0) for (u, y), x0 in zip(records, x0s)]
    pred = StateSpaceModel(A - K @ C, np.hstack([B - K @ D, K]), C,
                           np.hstack([D, np.zeros((l, l))]))
    return [np.asarray(y, float) - pred.simulate(np.hstack([u, y]), x0)
            for (u, y), x0 in zip(records, x0s)]


def state_space_sandwich(jacobians: Sequence[np.ndarray], A: Any, B: Any, C: Any, D: Any,
                         K: Any, records: Records, x0s: Sequence[Any], weights: Any = None
                         ) -> tuple[np.ndarray | None, str]:
    """:func:`prediction_sandwich` of a state-space innovations model ``(A, B, C, D, K)``
    fitted to ``records`` (its initial states ``x0s``; ``K=None``: no noise model, the
    errors are the simulation errors): the errors and the disturbance from the model, its
    noise filter used where its impulse responses die out within the shortest record (the
    plant's poles for the disturbance, the predictor's for ``H^-1``), else the errors' own
    autoregressive model alone. ``jacobians`` as for :func:`prediction_sandwich`, in the
    searched coordinates.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.pem.prediction_sandwich import state_space_sandwich
    >>> rng = np.random.default_rng(0)
    >>> u, y = rng.standard_normal((400, 1)), rng.standard_normal((400, 1))
    >>> J = rng.standard_normal((400, 1, 2))
    >>> ss = ([[0.5]], [[0.0]], [[1.0]], [[0.0]])    # G = 0: the disturbance is y
    >>> state_space_sandwich([J], *ss, None, [(u, y)], [[0.0]])[1]   # white, H = 1
    'gauss-newton: the prediction errors are white'
    >>> P, note = state_space_sandwich([J], *ss, [[0.5]], [(u, y)], [[0.0]])
    >>> note.split(" (")[1]              # white y through the model's 1 / H = 1 - 0.5 / q
    "the disturbance's autoregressive order 0 through the model's noise filter)"
    """
    A, C = np.atleast_2d(np.asarray(A, float)), np.atleast_2d(np.asarray(C, float))
    K = np.zeros((A.shape[0], C.shape[0])) if K is None else np.atleast_2d(np.asarray(K, float))
    with np.errstate(all="ignore"):
        e_hat = prediction_errors(A, B, C, D, K, records, x0s)
        shortest = min(np.shape(y)[0] for _, y in records)
        rho = max(spectral_radius(A), spectral_radius(A - K @ C))
        usable = rho < 1.0 and rho ** shortest < 1e-3
        dist = prediction_errors(A, B, C, D, K, records, x0s, simulation=True) if usable \
            else None
    return prediction_sandwich(
        jacobians, e_hat, dist,
        (lambda nfft: inverse_noise_response(A, K, C, nfft)) if usable else None, weights)


_METHOD = "gauss-newton with coloured prediction errors (sandwich)"


def defer_prediction(out: Any, res: dict[str, Any], records: Records, est_x0: Sequence[int],
                     feedthrough: bool, estimate_k: bool, weighting: str) -> None:
    """A state-space prediction-error fit's (:func:`sysid.pem`'s, ``focus="prediction"``)
    Gauss-Newton uncertainty becoming :func:`state_space_sandwich`'s when first used, where
    its prediction errors are coloured (the noise model ``K`` cannot take the disturbance's
    shape): formed along the Gauss-Newton covariance's identifiable directions, on every
    record. ``res`` is the core's result (its parameter vector ``A, B, C``, ``D`` when
    ``feedthrough``, ``K`` when ``estimate_k``, then the initial states of the records
    ``est_x0``), ``records`` the searched (scaled) record, ``weighting`` the criterion's
    (``"noise"``: the errors weighed by the inverse of their covariance; else a plain sum
    on the scaled record). ``info["pem"]["covariance"]`` says which covariance the model
    carries.

    Examples
    --------
    >>> import numpy as np, sysid, warnings
    >>> from scipy.signal import lfilter
    >>> rng = np.random.default_rng(0)
    >>> plant = sysid.StateSpaceModel([[1.8, -0.9], [1.0, 0.0]], [[1.0], [0.0]], [[0.5, 0.3]])
    >>> u = rng.standard_normal(800)
    >>> v = lfilter([1.0], [1.0, -0.9], 0.3 * rng.standard_normal(800))
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     m = sysid.ssest(sysid.IOData(u=u, y=plant.simulate(u)[:, 0] + v), 2)
    >>> m.info["pem"]["covariance"].startswith("gauss-newton until first used")
    True
    >>> s = m.dcgain(std=True)[1]                   # the first use forms it
    >>> m.info["pem"]["covariance"].startswith("sandwich for coloured prediction errors")
    True
    """
    info = out.info["pem"]
    weights: Any = None
    if weighting == "noise":
        try:
            weights = np.linalg.inv(np.linalg.cholesky(
                np.atleast_2d(np.asarray(res["innovation_covariance"], float))))
        except np.linalg.LinAlgError:
            info["covariance"] = ("gauss-newton, as for white errors (the errors' covariance "
                                  "is singular)")
            return
    info["covariance"] = ("gauss-newton until first used, then the sandwich for coloured "
                          "prediction errors where they are coloured")
    base = out.uncertainty
    records = [(np.asarray(u, float), np.asarray(y, float)) for u, y in records]
    lens = [y.shape[0] for _, y in records]
    n, m, l = res["b"].shape[0], res["b"].shape[1], res["c"].shape[0]
    cuts = np.cumsum([n * n, n * m, l * n, l * m * feedthrough, n * l * estimate_k])
    x0_fit = [np.asarray(x, float) for x in res["x0"]]

    def unpack(theta: np.ndarray) -> tuple[Any, ...]:
        A, B, C, D, K, x0 = np.split(np.asarray(theta, float), cuts)
        x0s = list(x0_fit)
        for i, e in enumerate(est_x0):
            x0s[e] = x0[i * n:(i + 1) * n]
        return (A.reshape(n, n), B.reshape(n, m), C.reshape(l, n),
                D.reshape(l, m) if feedthrough else res["d"],
                K.reshape(n, l) if estimate_k else res.get("k"), x0s)

    def form() -> tuple[ParameterUncertainty | None, str]:
        work = ParameterUncertainty(base.theta, base.covariance, unpack, names=base.names,
                                    dof=base.dof)
        w, V = base._eigen()  # its identifiable directions, computed once
        work._eig = (w, V)
        if sum(lens) * l * w.size > MAX_ENTRIES:
            return None, (f"gauss-newton, as for white errors: the coloured-error correction "
                          f"would hold {sum(lens) * l * w.size:.2g} numbers (at most "
                          f"{MAX_ENTRIES:.0e})")
        if w.size == 0:
            return None, "gauss-newton: no identifiable direction"

        def errors(parts: tuple[Any, ...]) -> np.ndarray:
            A, B, C, D, K, x0s = parts
            return np.concatenate(prediction_errors(A, B, C, D, K, records, x0s))

        with np.errstate(all="ignore"):
            _, G = work.scaled_jacobian(errors)
        rows = np.cumsum([0, *lens]) * l
        jac = [G[s:t].reshape(-1, l, w.size) for s, t in zip(rows[:-1], rows[1:])]
        A, B, C, D, K, x0s = unpack(base.theta)
        Pz, note = state_space_sandwich(jac, A, B, C, D, K, records, x0s, weights)
        if Pz is None:
            return None, note
        Gd = V * np.sqrt(w)  # parameters = theta + Gd z, z of unit Gauss-Newton covariance
        P = Gd @ Pz @ Gd.T
        return ParameterUncertainty(base.theta, 0.5 * (P + P.T), base.build, names=base.names,
                                    method=_METHOD, undetermined=base.undetermined), note

    def then(note: str) -> None:
        info["covariance"] = note
    out.uncertainty = DeferredSandwich(base, form, then)
