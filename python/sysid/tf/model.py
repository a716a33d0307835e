"""The :class:`TransferFunction` model: rational ``G_ij(s) = B_ij(s) / A_ij(s) e^{-s tau_ij}``.

One rational function per output/input pair, each with its own poles and an input-output
delay (MATLAB's ``idtf`` with ``IODelay``). Continuous-time (``dt = 0``; coefficients in
descending powers of ``s``, delays in seconds) or discrete-time (descending powers of ``z``,
delays in samples, python-control's convention).

A continuous model meets sampled data with its ``hold``: the input is held constant (ZOH) or
interpolated linearly (FOH) between samples, and the model is sampled exactly, delays that
are not whole samples included (:mod:`sysid.tf.sampling`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .._checks import as_2d, as_dt
from ..errors import DataError, ShapeError
from ..greybox.delays import shift_taps
from ..models.attributes import Coefficients, SampleTime
from ..models.discretisation import require_finite_sampling
from ..models.protocol import ModelMixin, TimeResponse, continuous_grid, slowest_decay
from ..models.statespace import StateSpaceModel
from .sampling import canonical, natural_frequency, sample_pair, split_delay

__all__ = ["TransferFunction"]


def _grid(x: Any, name: str) -> list[list[np.ndarray]]:
    """A coefficient array (SISO) or nested ``[outputs][inputs]`` lists as arrays."""
    if isinstance(x, np.ndarray) and x.ndim == 1 or (
            isinstance(x, (list, tuple)) and x and isinstance(x[0], (int, float, np.number))):
        x = [[x]]
    try:
        out = [[np.atleast_1d(np.asarray(c, dtype=float)) for c in row] for row in x]
    except (TypeError, ValueError) as e:
        raise ShapeError(f"{name} must be a coefficient array or nested [output][input] lists "
                         f"of coefficient arrays ({e})") from None
    if not out or not out[0] or any(len(r) != len(out[0]) for r in out):
        raise ShapeError(f"{name} must have one coefficient array per output/input pair")
    for row in out:
        for c in row:
            if c.ndim != 1 or c.size == 0 or not np.all(np.isfinite(c)):
                raise DataError(f"{name}: every coefficient array must be 1-D, non-empty and "
                                "finite")
    return out


def _gain_at(num: np.ndarray, den: np.ndarray, x: float) -> float:
    """``num(x) / den(x)`` at ``x = 0`` (``s``) or ``x = 1`` (``z``), roots of both at ``x``
    cancelled first; an uncancelled root of ``den`` gives the signed infinity of the limit
    from above (``den(x + e) ~ c e^k``, so the sign of ``num(x) / c``)."""
    def vanishes(c: np.ndarray) -> bool:  # c(x) = 0 up to rounding of its terms
        return bool(abs(np.polyval(c, x)) <= 1e-12 * np.polyval(np.abs(c), abs(x)))

    num, den = _trim(num), _trim(den)
    while den.size > 1 and num.size > 1 and vanishes(den) and vanishes(num):
        num, den = np.polydiv(num, [1.0, -x])[0], np.polydiv(den, [1.0, -x])[0]
    if not vanishes(den):
        return float(np.polyval(num, x) / np.polyval(den, x))
    top = float(np.polyval(num, x))
    if top == 0.0:
        return 0.0  # a zero numerator: no response at all
    while den.size > 1 and vanishes(den):
        den = np.polydiv(den, [1.0, -x])[0]
    return float(np.copysign(np.inf, top * float(np.polyval(den, x))))


def _trim(c: np.ndarray) -> np.ndarray:
    nz = np.flatnonzero(c)
    return c[nz[0]:] if nz.size else np.zeros(1)


class TransferFunction(ModelMixin):
    """Transfer-function model ``y_i = sum_j B_ij / A_ij e^{-s tau_ij} u_j``.

    Parameters
    ----------
    num, den : array_like or nested lists
        Coefficients in descending powers (of ``s``, or of ``z`` when ``dt > 0``): one array
        for a single-input single-output model, else ``[output][input]`` lists of arrays.
        Each denominator is scaled to be monic.
    dt : float
        Sample time; ``0.0`` (default) for continuous time.
    iodelay : float or array_like, optional
        Input-output delays ``(noutputs, ninputs)``: seconds (continuous), whole samples
        (discrete). Default zero.
    hold : {"zoh", "foh"}
        Inter-sample behaviour of the input when a continuous model meets sampled data.
    input_names, output_names : sequence of str, optional
    info : dict, optional
        How the model was obtained.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> G = sysid.TransferFunction([2.0], [1.0, 3.0], iodelay=0.15)
    >>> G
    TransferFunction(1 output x 1 input, continuous, stable, delays 0.15)
    >>> print(G)
    y0 <- u0:  2 / (s + 3) * exp(-0.15 s)
    >>> float(abs(G.freqresp([0.0])[0, 0, 0]))
    0.6666666666666666
    >>> G.simulate(np.ones(4), dt=0.1)[:, 0].round(4)
    array([0.    , 0.    , 0.0929, 0.2416])
    """

    #: no noise model: the predictions of its state-space form, the simulation, are its
    #: own at every horizon (compare fits their initial state)
    statespace_predicts = True
    #: checked whenever written (0 or None: continuous time); a change drops the uncertainty
    dt = SampleTime(continuous=0.0)
    #: replacing one by another drops the uncertainty (``hold`` keeps it: no std result
    #: reads it)
    num = Coefficients()
    den = Coefficients()
    iodelay = Coefficients()

    def __init__(self, num: Any, den: Any, *, dt: float = 0.0, iodelay: Any = None,
                 hold: str = "zoh", input_names: Sequence[str] | None = None,
                 output_names: Sequence[str] | None = None,
                 info: dict[str, Any] | None = None) -> None:
        N, D = _grid(num, "num"), _grid(den, "den")
        if len(N) != len(D) or len(N[0]) != len(D[0]):
            raise ShapeError(f"num is {len(N)} x {len(N[0])} pairs but den is "
                             f"{len(D)} x {len(D[0])}; give one of each per output/input pair")
        self.num: list[list[np.ndarray]] = []
        self.den: list[list[np.ndarray]] = []
        for nr, dr in zip(N, D):
            rn, rd = [], []
            for n_, d_ in zip(nr, dr):
                d_ = _trim(d_)
                if d_[0] == 0:
                    raise DataError("a denominator is zero: give its coefficients")
                n_ = _trim(n_)
                if n_.size > d_.size:
                    raise DataError(f"improper transfer function (numerator degree {n_.size - 1}"
                                    f" > denominator degree {d_.size - 1}); give at most as "
                                    "many zeros as poles")
                rn.append(n_ / d_[0])
                rd.append(d_ / d_[0])
            self.num.append(rn)
            self.den.append(rd)
        dt = float(dt)
        if not np.isfinite(dt) or dt < 0:
            raise DataError(f"dt must be 0 (continuous) or a positive sample time, got {dt}")
        self.dt = dt
        l, m = len(N), len(N[0])
        delay = np.zeros((l, m)) if iodelay is None else np.broadcast_to(
            np.asarray(iodelay, dtype=float), (l, m)).copy()
        if not np.all(np.isfinite(delay)) or np.any(delay < 0):
            raise DataError("iodelay must be finite and >= 0")
        if dt > 0 and np.any(np.abs(delay - np.round(delay)) > 1e-9):
            raise DataError("a discrete transfer function's iodelay counts whole samples; "
                            "round it or use a continuous model")
        self.iodelay = np.round(delay) if dt > 0 else delay
        if hold not in ("zoh", "foh"):
            raise DataError(f"hold must be 'zoh' or 'foh', got {hold!r}")
        self.hold = hold
        self.input_names = [f"u{j}" for j in range(m)] if input_names is None else \
            [str(s) for s in input_names]
        self.output_names = [f"y{i}" for i in range(l)] if output_names is None else \
            [str(s) for s in output_names]
        if len(self.input_names) != m or len(self.output_names) != l:
            raise ShapeError(f"give {m} input name(s) and {l} output name(s)")
        self.info: dict[str, Any] = dict(info or {})
        self.uncertainty: Any = None
        self.parameters: Any = None

    ninputs = property(lambda self: len(self.num[0]), doc="Number of inputs m.")
    noutputs = property(lambda self: len(self.num), doc="Number of outputs l.")

    @property
    def nstates(self) -> int:
        """States of the realisation (sum of the denominators' degrees)."""
        return int(sum(d.size - 1 for row in self.den for d in row))

    @property
    def n_parameters(self) -> int:
        """Free coefficients: ``deg A + deg B + 1`` per pair, plus the estimated delays."""
        k = sum(n.size + d.size - 1 for rn, rd in zip(self.num, self.den)
                for n, d in zip(rn, rd))
        return int(k + int(self.info.get("n_delays_estimated", 0)))

    def pairs(self) -> list[tuple[int, int]]:
        """All ``(output, input)`` index pairs."""
        return [(i, j) for i in range(self.noutputs) for j in range(self.ninputs)]

    # -- frequency domain ---------------------------------------------------------------
    def freqresp(self, omega: Any, std: bool = False) -> Any:
        """``G(j omega)`` (or ``G(e^{j omega dt})``), shape ``(len(omega), l, m)``; with
        ``std=True`` (needs :attr:`uncertainty`) the pair ``(G, sd)``, ``sd`` complex (std of
        the real and imaginary parts, first order)."""
        if std:
            from ..models.uncertainty import freqresp_std

            return freqresp_std(self, omega)
        w = np.atleast_1d(np.asarray(omega, dtype=float))
        if w.ndim != 1 or not np.isfinite(w).all():
            raise DataError("omega must be a finite 1-D array of angular frequencies (rad/s)")
        x = np.exp(1j * w * self.dt) if self.dt > 0 else 1j * w
        out = np.empty((w.size, self.noutputs, self.ninputs), dtype=complex)
        for i, j in self.pairs():
            with np.errstate(divide="ignore", invalid="ignore"):
                g = np.polyval(self.num[i][j], x) / np.polyval(self.den[i][j], x)
            tau = self.iodelay[i, j]
            out[:, i, j] = g * (x ** -tau if self.dt > 0 else np.exp(-x * tau))
        return out

    def poles(self, std: bool = False, method: str = "linear") -> Any:
        """Roots of every denominator (``s`` or ``z``); with ``std=True`` (needs
        :attr:`uncertainty`, as ``tfest`` and ``procest`` attach) the pair ``(poles, sd)``
        as for :meth:`sysid.StateSpaceModel.poles`."""
        if std:
            from ..models.pole_uncertainty import pole_std

            return pole_std(self, method)
        p = [np.roots(d) for row in self.den for d in row]
        return np.concatenate(p).astype(complex) if p else np.zeros(0, complex)

    def pole_groups(self) -> list[int]:
        """How many of :meth:`poles` each denominator contributes, channel by channel (row
        by row): the roots of different denominators are independent, so a pole only
        coincides with a root of its own (:func:`sysid.models.pole_uncertainty.pole_std`).

        Examples
        --------
        >>> import sysid
        >>> sysid.TransferFunction([[[1.0], [2.0]]], [[[1.0, 1.0], [1.0, 3.0, 2.0]]]).pole_groups()
        [1, 2]
        """
        return [int(np.roots(d).size) for row in self.den for d in row]

    def zeros(self) -> np.ndarray:
        """Roots of the numerator (single-input single-output); transmission zeros of the
        realisation otherwise."""
        if self.ninputs == self.noutputs == 1:
            return np.roots(self.num[0][0]).astype(complex)
        return np.asarray(self.to_statespace().zeros())

    def is_stable(self) -> bool:
        """Every pole in the open left half plane (inside the unit circle when discrete)."""
        p = self.poles()
        if p.size == 0:
            return True
        return bool(np.max(np.abs(p)) < 1) if self.dt > 0 else bool(np.max(p.real) < 0)

    def dcgain(self, std: bool = False) -> Any:
        """Steady-state gain ``(l, m)``; with ``std=True`` (needs :attr:`uncertainty`) the pair
        ``(gain, std)``, first order.

        A pole at ``s = 0`` (``z = 1``) that a zero there cancels leaves a finite gain (``s /
        (s^2 + s)`` has gain 1); an integrator left over gives ``+inf`` or ``-inf``, the sign
        of the response to a positive step as it grows."""
        if std:
            from ..models.uncertainty import complex_std

            return complex_std(self, lambda m: m.dcgain())
        x = 1.0 if self.dt > 0 else 0.0
        g = np.empty((self.noutputs, self.ninputs))
        for i, j in self.pairs():
            g[i, j] = _gain_at(self.num[i][j], self.den[i][j], x)
        return g

    # -- state space and simulation --------------------------------------------------------
    def _blocks(self) -> list[tuple[int, int, tuple[np.ndarray, ...]]]:
        return [(i, j, canonical(self.den[i][j], self.num[i][j],
                                 natural_frequency(self.den[i][j]))) for i, j in self.pairs()]

    def _select(self, iy: list[int], iu: list[int]) -> TransferFunction:
        """Outputs ``iy`` from inputs ``iu`` (:meth:`select`)."""
        from ..models.subsystem import names

        return TransferFunction([[self.num[i][j] for j in iu] for i in iy],
                                [[self.den[i][j] for j in iu] for i in iy], dt=self.dt,
                                iodelay=self.iodelay[np.ix_(iy, iu)], hold=self.hold,
                                input_names=names(self.input_names, iu),
                                output_names=names(self.output_names, iy), info=self.info)

    def to_statespace(self, dt: float | None = None) -> Any:
        """An equivalent state-space model.

        A continuous model without delays gives a :class:`~sysid.ContinuousStateSpace`; with
        ``dt`` (or a discrete model) a :class:`~sysid.StateSpaceModel` sampled exactly with
        the model's hold, delays realised as extra states. The parameter uncertainty is
        carried (the same parameters seen through the realisation,
        :mod:`sysid.models.carried`).

        Examples
        --------
        >>> import sysid
        >>> sysid.TransferFunction([1.0], [1.0, 2.0]).to_statespace()
        ContinuousStateSpace(nstates=1, ninputs=1, noutputs=1, stable)
        """
        from ..models.carried import carry

        return carry(self, self._statespace(dt), lambda m: m.to_statespace(dt))

    def _statespace(self, dt: float | None) -> Any:
        """:meth:`to_statespace` without the uncertainty."""
        if self.dt > 0:
            return self._discrete_ss()
        if dt is None:
            if np.any(self.iodelay > 0):
                raise DataError("a continuous model with delays has no delay-free state-space "
                                "form: give dt for the exact sampled model")
            from ..models.continuous import ContinuousStateSpace

            A, B, C, D = self._stack([(b[0], b[1][:, None], b[2], b[3][:, None])
                                      for b in (blk for _, _, blk in self._blocks())])
            return ContinuousStateSpace(A, B, C, D, hold=self.hold, input_names=self.input_names,
                                        output_names=self.output_names, info=self.info)
        Ad, Bt, Cd, Dt, taps, _ = self.sampled_taps(float(dt))
        from ..greybox.delays import tap_states

        A, B, C, D, _ = tap_states({"A": Ad, "B": Bt, "C": Cd, "D": Dt}, taps, self.ninputs)
        return StateSpaceModel(A, B, C, D, dt=float(dt), input_names=self.input_names,
                               output_names=self.output_names, info=self.info)

    def _continuous_with_delays(self, method: str, prewarp: float | None) -> TransferFunction:
        """:func:`sysid.d2c` of a discrete model with delays (as MATLAB's ``d2c``): each
        pair's delay-free part converted, its delay of ``k`` samples kept as ``k dt``
        seconds (a continuous state-space model could not hold it; realised as states, the
        delay would be poles at ``z = 0``, which have no continuous equivalent)."""
        from ..models.continuous import d2c

        nums = [[np.zeros(1)] * self.ninputs for _ in range(self.noutputs)]
        dens = [[np.ones(1)] * self.ninputs for _ in range(self.noutputs)]
        for i, j in self.pairs():
            c = d2c(TransferFunction(self.num[i][j], self.den[i][j], dt=self.dt), method,
                    prewarp=prewarp)
            (n_,), (d_,) = statespace_polynomials(c.A, c.B, c.C, c.D)
            nums[i][j], dens[i][j] = n_[0], d_[0]
        return TransferFunction(nums, dens, iodelay=self.iodelay * self.dt,
                                hold="foh" if method == "foh" else "zoh",
                                input_names=self.input_names, output_names=self.output_names,
                                info={"method": f"d2c ({method})",
                                      "from": self.info.get("method", "TransferFunction")})

    def _stack(self, blocks: list[tuple[np.ndarray, ...]]
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Block-diagonal realisation of per-pair blocks ``(A, B(n, m), C(1, n), D(1, m))``
        whose inputs and outputs are placed by the pair."""
        l, m = self.noutputs, self.ninputs
        n = sum(b[0].shape[0] for b in blocks)
        A, B, C, D = np.zeros((n, n)), np.zeros((n, m)), np.zeros((l, n)), np.zeros((l, m))
        o = 0
        for (i, j), (a, b, c, d) in zip(self.pairs(), blocks):
            k = a.shape[0]
            A[o:o + k, o:o + k], B[o:o + k, j] = a, b[:, 0]
            C[i, o:o + k], D[i, j] = c[0], d[0, 0]
            o += k
        return A, B, C, D

    def _discrete_ss(self) -> StateSpaceModel:
        from ..greybox.delays import tap_states

        blocks = [blk for _, _, blk in self._blocks()]
        A, B, C, D = self._stack([(b[0], b[1][:, None], b[2], b[3][:, None]) for b in blocks])
        taps = [(j, int(self.iodelay[i, j])) for i, j in self.pairs()]
        keys = sorted(set(taps))
        Bt, Dt = np.zeros((A.shape[0], len(keys))), np.zeros((self.noutputs, len(keys)))
        o = 0
        for (i, j), blk, key in zip(self.pairs(), blocks, taps):
            k, c = blk[0].shape[0], keys.index(key)
            Bt[o:o + k, c] += B[o:o + k, j]
            Dt[i, c] += D[i, j]
            o += k
        Aa, Ba, Ca, Da, _ = tap_states({"A": A, "B": Bt, "C": C, "D": Dt}, keys, self.ninputs)
        return StateSpaceModel(Aa, Ba, Ca, Da, dt=self.dt, input_names=self.input_names,
                               output_names=self.output_names, info=self.info)

    def sampled_taps(self, dt: float, hold: str | None = None
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                list[tuple[int, int]], np.ndarray]:
        """The exact sampled model over input taps: ``(Ad, B_taps, C, D_taps, taps, G)``,
        ``taps`` the ``(input, shift)`` of each column and ``G`` ``(n, m)`` the state at rest
        per unit ``u(0)`` (first-order hold only)."""
        dt = as_dt(dt)
        hold = hold or self.hold
        if hold not in ("zoh", "foh"):
            raise DataError(f"hold must be 'zoh' or 'foh', got {hold!r}")
        blocks, canon = [], []
        # a pole with Re(s) dt beyond ~700 overflows exp(A dt): said below, not by NumPy
        with np.errstate(over="ignore", invalid="ignore"):
            for i, j, (a, b, c, d) in self._blocks():
                whole, r = split_delay(float(self.iodelay[i, j]), dt)
                blocks.append((i, j, sample_pair(a, b, c, d, dt, whole, r, hold)))
                canon.append((a, b, c, d))
            out = assemble(blocks, canon, self.noutputs, self.ninputs)
        require_finite_sampling([out[0], out[1], out[3], out[5]], self.poles(), dt)
        return out

    def simulate(self, u: Any, x0: Any = None, *, dt: float | None = None,
                 hold: str | None = None) -> np.ndarray:
        """Noise-free output ``(n_samples, noutputs)`` from rest.

        A continuous model needs the data's sample time ``dt``; between samples the input
        follows ``hold`` (default: the model's), and delays are sampled exactly.
        """
        u = as_2d(u, "u", ncols=self.ninputs)
        if self.dt > 0:
            if dt is not None and abs(dt - self.dt) > 1e-12 * self.dt:
                raise DataError(f"the model's dt is {self.dt}, not {dt}")
            return self._discrete_ss().simulate(u, x0)
        if dt is None:
            raise DataError("a continuous-time model needs the sample time of the data: pass "
                            "dt (or use sysid.compare with an IOData)")
        dt = as_dt(dt)
        Ad, Bt, Cd, Dt, taps, G = self.sampled_taps(dt, hold)
        z0 = -G @ u[0] if u.shape[0] else np.zeros(Ad.shape[0])
        if x0 is not None:
            x0 = np.asarray(x0, dtype=float).reshape(-1)
            if x0.size != z0.size:
                raise ShapeError(
                    f"x0 has {x0.size} entries but this model sampled every {dt:g} s has "
                    f"{z0.size} states; an initial state from sysid.compare is that of the "
                    "sampled form model.to_statespace(dt) (with its hold and delay states): "
                    "simulate that model with it")
            z0 = z0 + x0
        if Ad.shape[0] == 0:  # a pure gain
            return shift_taps(u, taps) @ Dt.T
        ss = StateSpaceModel(Ad, Bt, Cd, Dt, dt=dt)
        return ss.simulate(shift_taps(u, taps), z0 if np.any(z0) else None)

    def predict(self, u: Any, y: Any = None, horizon: int = 1, *, dt: float | None = None
                ) -> np.ndarray:
        """No noise model (output error): the prediction is the simulation."""
        from .._measured import predict_args, record_dt

        dt = record_dt(u, dt)
        u, y = predict_args(u, y)
        if np.shape(y)[0] != np.shape(u)[0]:
            raise DataError(f"u has {np.shape(u)[0]} samples but y has {np.shape(y)[0]}")
        return self.simulate(u, dt=dt)

    def sampled(self, dt: float) -> Any:
        """The model seen at sample time ``dt`` (what :func:`sysid.compare` uses)."""
        dt = as_dt(dt)
        if self.dt > 0:
            return self
        return _Sampled(self, dt)

    def step(self, n_samples: int | None = None, *, dt: float | None = None,
             std: bool = False) -> TimeResponse:
        """Unit-step response (continuous: sampled every ``dt``, by default 200 points over
        five time constants of the slowest pole plus the largest delay); ``std=True``
        (needs :attr:`uncertainty`): with its first-order std as a band."""
        if std:
            return self._banded("step", n_samples, dt)
        if self.dt > 0:
            return super().step(n_samples)
        N, h = self._time_grid(n_samples, dt)
        y = np.empty((N, self.noutputs, self.ninputs))
        for j in range(self.ninputs):
            u = np.zeros((N, self.ninputs))
            u[:, j] = 1.0
            y[:, :, j] = self.simulate(u, dt=h, hold="zoh")
        return TimeResponse("step", np.arange(N) * h, y, self)

    def _banded(self, kind: str, n_samples: int | None, dt: float | None) -> TimeResponse:
        """The ``kind`` response (``"step"`` or ``"impulse"``) with its first-order std from
        :attr:`uncertainty` (``std=True``), each model of the propagation on its grid."""
        from ..models.uncertainty import response_band

        resp = getattr(self, kind)(n_samples, dt=dt)
        h = resp.t[1] - resp.t[0] if len(resp.t) > 1 else dt
        return response_band(self, resp, lambda m, n: (getattr(m, kind)(n) if self.dt > 0
                                                       else getattr(m, kind)(n, dt=h)))

    def impulse(self, n_samples: int | None = None, *, dt: float | None = None,
                std: bool = False) -> TimeResponse:
        """Impulse response (continuous: ``c e^{A (t - tau)} b`` of each pair at the samples,
        zero before its delay ``tau``, the Dirac part left out; the grid as :meth:`step`);
        ``std=True`` (needs :attr:`uncertainty`): with its first-order std as a band.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> r = sysid.TransferFunction([3.0], [1.0, 2.0]).impulse(4, dt=0.5)
        >>> bool(np.allclose(r.y[:, 0, 0], 3 * np.exp(-2 * r.t)))
        True
        """
        if std:
            return self._banded("impulse", n_samples, dt)
        if self.dt > 0:
            return super().impulse(n_samples)
        from scipy.linalg import expm

        N, h = self._time_grid(n_samples, dt)
        y = np.zeros((N, self.noutputs, self.ninputs))
        for i, j, (A, b, c, _) in self._blocks():
            if A.shape[0] == 0:
                continue
            tau = float(self.iodelay[i, j])
            k0 = int(np.ceil(tau / h - 1e-12))
            if k0 >= N:
                continue
            x = expm(A * (k0 * h - tau)) @ b
            step = expm(A * h)
            for k in range(k0, N):
                y[k, i, j] = float(np.ravel(c) @ x)
                x = step @ x
        return TimeResponse("impulse", np.arange(N) * h, y, self)

    def _time_grid(self, n_samples: int | None, dt: float | None) -> tuple[int, float]:
        slow = slowest_decay(self.poles()) or 0.1
        t_final = 5.0 / slow + float(np.max(self.iodelay, initial=0.0))
        return continuous_grid(self.poles(), t_final, n_samples, dt, 100000)

    # -- interop ------------------------------------------------------------------------
    def to_control(self) -> Any:
        """A ``control.TransferFunction`` (python-control; delays are not representable)."""
        from .interop import to_control

        return to_control(self)

    def to_scipy(self) -> Any:
        """A ``scipy.signal.TransferFunction`` (single-input single-output, no delay)."""
        from .interop import to_scipy

        return to_scipy(self)

    @classmethod
    def from_control(cls, sys: Any) -> TransferFunction:
        """From a python-control ``TransferFunction`` (or any LTI object it converts)."""
        from .interop import from_control

        return from_control(cls, sys)

    @classmethod
    def from_scipy(cls, sys: Any) -> TransferFunction:
        """From a ``scipy.signal`` LTI object (``lti``/``dlti``, any representation)."""
        from .interop import from_scipy

        return from_scipy(cls, sys)

    # -- saving and presenting ------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Coefficients, delays, names and info (see :func:`sysid.save_model`)."""
        return {"num": [[c.tolist() for c in r] for r in self.num],
                "den": [[c.tolist() for c in r] for r in self.den],
                "dt": self.dt, "iodelay": self.iodelay, "hold": self.hold,
                "input_names": list(self.input_names), "output_names": list(self.output_names),
                "info": self.info}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TransferFunction:
        """Inverse of :meth:`to_dict`."""
        return cls(d["num"], d["den"], dt=float(d["dt"]), iodelay=d["iodelay"],
                   hold=d.get("hold", "zoh"), input_names=d.get("input_names"),
                   output_names=d.get("output_names"), info=d.get("info"))

    def _poly_text(self, c: np.ndarray) -> str:
        var = "z" if self.dt > 0 else "s"
        n = c.size - 1
        terms = []
        for k, v in enumerate(c):
            if v == 0 and c.size > 1:
                continue
            p = n - k
            mono = "" if p == 0 else var if p == 1 else f"{var}^{p}"
            coef = f"{abs(v):.6g}"
            if mono and coef == "1":
                coef = ""
            sign = "-" if v < 0 else "+"
            terms.append((sign, f"{coef} {mono}".strip() if coef and mono else coef or mono))
        if not terms:
            return "0"
        text = ("-" if terms[0][0] == "-" else "") + terms[0][1]
        for s, t in terms[1:]:
            text += f" {s} {t}"
        return text

    def __str__(self) -> str:
        lines = []
        for i, j in self.pairs():
            nm, dn = self._poly_text(self.num[i][j]), self._poly_text(self.den[i][j])
            tail = ""
            tau = self.iodelay[i, j]
            if tau > 0:
                tail = f" * z^-{int(tau)}" if self.dt > 0 else f" * exp(-{tau:.6g} s)"
            nm = f"({nm})" if len(self.num[i][j]) > 1 else nm
            lines.append(f"{self.output_names[i]} <- {self.input_names[j]}:  {nm} / ({dn}){tail}")
        return "\n".join(lines)

    def summary(self) -> str:
        """The transfer functions, the parameter table with standard deviations and how the
        model was obtained."""
        text = str(self)  # a process model's already starts with its repr
        out = [text] if text.startswith(repr(self)) else [repr(self), text]
        if self.parameters is not None:
            out.append(str(self.parameters))
        keys = ("method", "iterations", "stop", "fit_percent", "cost", "n_samples")
        info = ", ".join(f"{k}={_plain(self.info[k])}" for k in keys if k in self.info)
        if info:
            out.append(info)
        return "\n".join(out)

    def __repr__(self) -> str:
        l, m = self.noutputs, self.ninputs
        kind = f"dt={self.dt:g}" if self.dt > 0 else "continuous"
        stab = "stable" if self.is_stable() else "UNSTABLE"
        d = self.iodelay[self.iodelay > 0]
        delays = f", delays {', '.join(f'{v:.6g}' for v in d)}" if d.size else ""
        return (f"TransferFunction({l} output{'s' * (l != 1)} x {m} input{'s' * (m != 1)}, "
                f"{kind}, {stab}{delays})")


def assemble(blocks: list[tuple[int, int, tuple[Any, ...]]], canon: list[tuple[Any, ...]],
             l: int, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                      list[tuple[int, int]], np.ndarray]:
    """Block-diagonal sampled model over the union of the pairs' taps."""
    taps = sorted({(j, s) for _, j, (_, cols, _) in blocks for s, _, _ in cols})
    n = sum(Ad.shape[0] for _, _, (Ad, _, _) in blocks)
    Ad = np.zeros((n, n))
    Bt, Cd, Dt = np.zeros((n, len(taps))), np.zeros((l, n)), np.zeros((l, len(taps)))
    G = np.zeros((n, m))
    o = 0
    for (i, j, (a, cols, g)), (_, _, c, _) in zip(blocks, canon):
        k = a.shape[0]
        Ad[o:o + k, o:o + k] = a
        Cd[i, o:o + k] = c[0]
        for s, bc, dc in cols:
            col = taps.index((j, s))
            Bt[o:o + k, col] += bc
            Dt[i, col] += dc[0]
        G[o:o + k, j] = g
        o += k
    return Ad, Bt, Cd, Dt, taps, G


def _plain(v: Any) -> str:
    """A summary value as text: numbers to 6 digits, lists of them likewise (no
    ``np.float64(...)``)."""
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_plain(x) for x in v) + "]"
    if isinstance(v, (float, np.floating)):
        return f"{float(v):.6g}"
    if isinstance(v, (np.integer,)):
        return str(int(v))
    return str(v)


class _Sampled:
    """A continuous :class:`TransferFunction` at sample time ``dt`` (for compare/residuals)."""

    def __init__(self, tf: TransferFunction, dt: float) -> None:
        self.continuous, self.dt = tf, dt
        self.input_names, self.output_names = tf.input_names, tf.output_names
        self.info = tf.info
        self.ninputs, self.noutputs = tf.ninputs, tf.noutputs
        self.n_parameters = tf.n_parameters

    def __repr__(self) -> str:
        return f"{self.continuous!r} sampled every {self.dt:g} s"

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        return self.continuous.simulate(u, x0, dt=self.dt)

    def predict(self, u: Any, y: Any = None, horizon: int = 1) -> np.ndarray:
        return self.continuous.predict(u, y, horizon, dt=self.dt)

    def freqresp(self, omega: Any) -> np.ndarray:
        return np.asarray(self.continuous.to_statespace(self.dt).freqresp(omega))

    statespace_predicts = True  # no noise model: predictions are the simulation
    #: the sampled form differs from the simulation only by the initial state (a first-order
    #: hold starts from the first input): compare's fitted x0 takes it up
    statespace_up_to_x0 = True

    def to_statespace(self) -> Any:
        """The exact sampled state-space model (delays as extra states): what lets
        :func:`sysid.compare` estimate the initial state."""
        return self.continuous.to_statespace(self.dt)


def statespace_polynomials(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray
                           ) -> tuple[list[list[np.ndarray]], list[list[np.ndarray]]]:
    """Numerator and denominator of every output/input pair of ``(A, B, C, D)`` over
    ``det(xI - A)`` (:func:`sysid.ss2tf`'s map, the determinant lemma)."""
    den = np.real(np.poly(A)) if A.size else np.ones(1)
    nums, dens = [], []
    for i in range(C.shape[0]):
        rn, rd = [], []
        for j in range(B.shape[1]):
            if A.size:
                num = np.real(np.poly(A - np.outer(B[:, j], C[i]))) - den + D[i, j] * den
            else:
                num = np.array([D[i, j]])
            rn.append(num)
            rd.append(den.copy())
        nums.append(rn)
        dens.append(rd)
    return nums, dens


def _register() -> None:
    from ..models.serialize import register_model

    register_model(TransferFunction)


_register()
