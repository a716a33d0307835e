"""Orthogonal decomposition: separate deterministic and stochastic submodels.

Picci & Katayama (1996), Katayama & Picci (1999) and Chiuso & Picci (2004) split the output
into the component in the space of the inputs (past and future) and its orthogonal
complement,

``y(t) = y_d(t) + y_s(t)``,  ``y_d(t) = E[y(t) | u(.)]``,

which, without feedback (the input uncorrelated with the noise), are the outputs of two
*decoupled* models: the deterministic ``y_d = G(q) u`` (states ``x_d``) and the stochastic
``y_s = H(q) e`` (states ``x_s``), each with its own order (seed 002, eq. 4.6):

``[x_d; x_s](t+1) = diag(A_d, A_s) [x_d; x_s](t) + [B_d; 0] u(t) + [0; K_s] e(t)``,
``y(t) = [C_d  C_s] [x_d; x_s](t) + D_d u(t) + e(t)``.

The joint innovation model needs order ``n_d + n_s`` too but mixes the two dynamics; the
decoupled one shows which poles belong to the plant and which to the disturbance.

The steps reuse the subspace engine: the deterministic submodel comes from PI-MOESP (past
inputs as instruments: the future outputs projected on the input space, so any additive
noise independent of the input drops out), with ``B_d, D_d`` and the initial state then fitted
by least squares on the data; the stochastic submodel from stochastic subspace
identification (output-only CVA by default) of the residual ``y - y_d``, the estimate of the
orthogonal complement.
"""

from __future__ import annotations

from typing import Any, Union

import numpy as np

from .. import _sysid
from .._checks import as_int
from .._display import HTMLResult
from ..data.iodata import IOData, require_record
from ..errors import DataError
from ..models.statespace import StateSpaceModel
from .feedthrough import check_feedthrough

__all__ = ["OrthogonalDecomposition", "orthogonal_decomposition", "svc_order"]

Order = Union[int, str]


class OrthogonalDecomposition(HTMLResult):
    """Deterministic and stochastic submodels of :func:`orthogonal_decomposition`.

    Attributes
    ----------
    deterministic : StateSpaceModel
        ``y_d = G(q) u``: order ``n_d``, no noise model.
    stochastic : StateSpaceModel
        ``y_s = H(q) e``: no inputs, ``K_s`` and the innovation covariance.
    combined : StateSpaceModel
        The block-diagonal innovation model of order ``n_d + n_s`` (same input-output
        behaviour and noise model as the two together).
    residual : IOData
        The stochastic component ``y - y_d`` (outputs only).
    singular_values : dict
        ``{"deterministic": ..., "stochastic": ...}`` for the order choices.
    """

    def __init__(self, deterministic: StateSpaceModel, stochastic: StateSpaceModel,
                 residual: IOData, singular_values: dict[str, np.ndarray]) -> None:
        self.deterministic = deterministic
        self.stochastic = stochastic
        self.residual = residual
        self.singular_values = singular_values
        nd, ns = deterministic.nstates, stochastic.nstates
        m, l = deterministic.ninputs, deterministic.noutputs
        A = np.zeros((nd + ns, nd + ns))
        A[:nd, :nd], A[nd:, nd:] = deterministic.A, stochastic.A
        B = np.vstack([deterministic.B, np.zeros((ns, m))])
        K = np.vstack([np.zeros((nd, l)), stochastic.K])
        C = np.hstack([deterministic.C, stochastic.C])
        self.combined = StateSpaceModel(
            A, B, C, deterministic.D, K, dt=deterministic.dt, noise_cov=stochastic.noise_cov,
            input_names=deterministic.input_names, output_names=deterministic.output_names,
            info={"method": "orthogonal-decomposition", "order": nd + ns,
                  "order_det": nd, "order_stoch": ns},
        )

    def __repr__(self) -> str:
        return (f"OrthogonalDecomposition(deterministic order {self.deterministic.nstates}, "
                f"stochastic order {self.stochastic.nstates}, "
                f"{self.deterministic.ninputs} input(s), {self.deterministic.noutputs} "
                "output(s))")

    def summary(self) -> str:
        """Poles of both submodels (with frequency and damping) and the noise variance."""
        lines = [repr(self)]
        for name, model in (("deterministic", self.deterministic),
                            ("stochastic", self.stochastic)):
            lines.append(f"{name} poles:")
            for p in np.sort_complex(model.poles()):
                s = np.log(p.astype(complex)) / model.dt
                wn = abs(s)
                z = -s.real / wn if wn > 0 else 1.0
                lines.append(f"  {p.real:+.4f}{p.imag:+.4f}j  |p| = {abs(p):.4f}  "
                             f"wn = {wn:.4g} rad/s  zeta = {z:.3f}")
        if self.stochastic.noise_cov is not None:
            lines.append("innovation covariance: "
                         + np.array2string(self.stochastic.noise_cov, precision=4))
        return "\n".join(lines)

    def to_pandas(self) -> Any:
        """One row per pole: ``submodel``, ``real``, ``imag``, ``abs``."""
        import pandas as pd

        rows = []
        for name, model in (("deterministic", self.deterministic),
                            ("stochastic", self.stochastic)):
            for p in np.sort_complex(model.poles()):
                rows.append({"submodel": name, "real": p.real, "imag": p.imag,
                             "abs": abs(p)})
        return pd.DataFrame(rows)

    def disturbance_spectrum(self, omega: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """``(omega, Phi)``: the model's disturbance spectrum ``H Σ H^*`` (one-sided density,
        units^2/Hz as :func:`sysid.spectra`), ``Phi`` of shape ``(n_freq, l, l)``."""
        st = self.stochastic
        if omega is None:
            omega = np.linspace(0.0, np.pi / st.dt, 512)
        omega = np.asarray(omega, dtype=float)
        l = st.noutputs
        H = StateSpaceModel(st.A, st.K, st.C, np.eye(l), dt=st.dt).freqresp(omega)
        sigma = st.noise_cov if st.noise_cov is not None else np.eye(l)
        phi = 2.0 * st.dt * np.einsum("fab,bc,fdc->fad", H, sigma, H.conj())
        return omega, phi

    def plot_disturbance_spectrum(self, ax: Any = None, *, nperseg: int | None = None) -> Any:
        """Disturbance spectrum of the stochastic submodel with the Welch estimate of the
        residual ``y - y_d`` (as in the robot thesis, seed 002); log-log, one line per output."""
        from ..nonparametric.spectra import spectra
        from ..plot import _pyplot

        plt = _pyplot()
        if ax is None:
            _, ax = plt.subplots()
        est = spectra(self.residual, nperseg=nperseg)
        omega, phi = self.disturbance_spectrum(est.omega[1:])
        for i, name in enumerate(self.residual.output_names):
            line = ax.loglog(est.omega[1:], est.psd(name)[1:], alpha=0.5,
                             label=f"{name}: residual (Welch)")[0]
            ax.loglog(omega, phi[:, i, i].real, color=line.get_color(),
                      label=f"{name}: stochastic submodel")
        ax.set_xlabel("frequency (rad/s)")
        ax.set_ylabel("power spectral density")
        ax.set_title("Disturbance spectrum")
        ax.legend()
        return ax

    def plot(self, ax: Any = None) -> Any:
        """Same as :meth:`plot_disturbance_spectrum`."""
        return self.plot_disturbance_spectrum(ax)


def svc_order(canonical: np.ndarray, max_order: int, n_samples: int, n_outputs: int) -> int:
    """Order minimising Bauer's singular-value criterion for CVA,
    ``SVC(n) = s_{n+1}^2 + log(N) 2 n l / N`` (Bauer 2001), ``n >= 1``; consistent, unlike the
    largest log gap, when the canonical correlations beyond the order only decay slowly.

    Examples
    --------
    >>> from sysid.subspace.orthogonal import svc_order
    >>> svc_order(np.array([0.9, 0.3, 0.1, 0.01, 0.009, 0.008]), 5, 10_000, 1)
    3
    """
    s = np.asarray(canonical, dtype=float)
    top = min(int(max_order), s.size)
    pen = np.log(n_samples) * 2.0 * n_outputs / n_samples
    crit = [(s[n] ** 2 if n < s.size else 0.0) + pen * n for n in range(1, top + 1)]
    return int(np.argmin(crit)) + 1


def orthogonal_decomposition(
    data: IOData | tuple[Any, Any],
    order_det: Order = "auto",
    order_stoch: Order = "auto",
    *,
    horizon: int | None = None,
    horizon_stoch: int | None = None,
    feedthrough: bool | str = False,
    stoch_method: str = "cva",
) -> OrthogonalDecomposition:
    """Deterministic and stochastic submodels, each with its own order (Picci & Katayama).

    Requires open-loop data (the input uncorrelated with the noise; see
    :func:`sysid.check_feedback`).

    Parameters
    ----------
    data : IOData or (u, y)
        With at least one input.
    order_det, order_stoch : int or "auto"
        Orders of the deterministic and stochastic submodels. ``"auto"``: the largest gap of
        the log singular values for the deterministic step, Bauer's SVC criterion on the
        canonical correlations (:func:`svc_order`) for the stochastic step with CVA.
    horizon : int, optional
        Horizon of the deterministic step (default :func:`sysid.default_horizon`).
    horizon_stoch : int, optional
        Horizon of the stochastic step (default: as ``horizon``).
    feedthrough : bool or "auto"
        Estimate ``D_d``. Default ``False`` (``D_d = 0``, as every sysid state-space
        estimator); ``"auto"``: decided from the data
        (:func:`sysid.subspace.feedthrough.choose_feedthrough`).
    stoch_method : str
        Weighting of the stochastic step (``"cva"`` or ``"moesp"``).

    Returns
    -------
    OrthogonalDecomposition

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> n = 5000
    >>> u = rng.standard_normal(n)
    >>> plant = sysid.StateSpaceModel([[0.6]], [[1.0]], [[1.0]])
    >>> noise = sysid.StateSpaceModel([[-0.8]], [[1.0]], [[0.5]], [[1.0]])
    >>> y = plant.simulate(u) + noise.simulate(0.3 * rng.standard_normal(n))
    >>> od = sysid.orthogonal_decomposition(sysid.IOData(u=u, y=y), 1, 1, horizon=8)
    >>> bool(abs(od.deterministic.poles()[0] - 0.6) < 0.02)
    True
    >>> bool(abs(od.stochastic.poles()[0] + 0.8) < 0.05)
    True
    """
    from .estimator import SubspaceEstimator

    data = require_record(data, "orthogonal_decomposition")
    if data.n_inputs == 0:
        raise DataError("the orthogonal decomposition needs at least one input; for "
                        "output-only data use SubspaceEstimator on the outputs alone")
    det_est = SubspaceEstimator(data, horizon, method="pi-moesp")
    det = det_est.fit(order_det, feedthrough=check_feedthrough(feedthrough), kalman=False)
    feedthrough = bool(det.info["settings"]["feedthrough"])
    A, C = det.A, det.C
    residuals = []
    for u, y in data.experiments:
        # B, D and x0 by least squares on each record: y - y_d is then the residual of the
        # orthogonal projection of y on the (filtered) inputs
        B, D, (x0,) = _sysid.estimate_bd_x0_records(A, C, [u], [y], feedthrough)
        yd = StateSpaceModel(A, B, C, D).simulate(u, x0=x0)
        residuals.append(y - yd)
    if data.n_experiments == 1:
        det = StateSpaceModel(A, B, C, D, dt=data.dt, input_names=data.input_names,
                              output_names=data.output_names, info=det.info)
    residual = IOData(
        y=residuals if data.n_experiments > 1 else residuals[0],
        dt=data.dt, output_names=data.output_names,
    )
    hs = as_int(horizon_stoch, "horizon_stoch", 2) if horizon_stoch is not None else det_est.past
    sto_est = SubspaceEstimator(residual, hs, method=stoch_method)
    if isinstance(order_stoch, str) and order_stoch == "auto" and sto_est.method == "cva":
        order_stoch = svc_order(sto_est.singular_values, sto_est.max_order,
                                sto_est.factor.n_columns, data.n_outputs)
    sto = sto_est.fit(order_stoch, feedthrough=False, kalman=True)
    stochastic = StateSpaceModel(sto.A, np.zeros((sto.nstates, 0)), sto.C, None, sto.K,
                                 dt=data.dt, noise_cov=sto.noise_cov,
                                 output_names=data.output_names, info=sto.info)
    return OrthogonalDecomposition(
        det, stochastic, residual,
        {"deterministic": det_est.singular_values_for("pi-moesp"),
         "stochastic": sto_est.singular_values},
    )
