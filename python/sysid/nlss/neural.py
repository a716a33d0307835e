"""Neural state-space models (MATLAB's ``nlssest``): small networks around a linear part.

.. code-block:: text

    x(t+1) = A x + B u + f(x, u)       y = C x + D u + g(x, u)       x(t0) = h(past)

in scaled channels and the start's real modal coordinates; ``f`` and ``g`` (unless
switched off) are tanh multilayer perceptrons whose last layer starts at zero, so training
starts at the linear model (the BLA's for periodic data), or at a Hammerstein-Wiener model
embedded exactly (its sigmoid units the networks' first hidden units, see
``neural_start``), whichever validates better; ``h`` is an encoder of the past ``L`` inputs
and outputs (a linear map fitted to the start's states, plus a network) that gives the
initial state of every training section.
Training (Rust core, no deep-learning framework): Adam on the mean squared simulation error
of short sections (truncated simulation, back-propagation through each section; slow modes
take proportionally smaller steps), the epoch whose free-run simulation from rest fits the
held-out data best kept, the start included (Beintema, Schoukens & Tóth 2023 describe this
encoder/truncated-simulation scheme); optionally an L2 penalty toward the start
(``regularization``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .. import _sysid
from .._progress import iteration_callback
from .._threads import one_blas_thread
from ..data.iodata import IOData, require_record
from ..errors import DataError, NumericalError, SysidWarning
from ..models.protocol import ModelMixin
from ..models.serialize import register_model
from ..models.statespace import StateSpaceModel
from ..nonlinear.hw_ss_model import HammersteinWienerSSModel
from .common import (
    LinearPart,
    Scaling,
    balanced,
    channels,
    check_order,
    linear_start,
    linear_states,
    scaled_data,
    signal,
)
from .memory import check_memory
from .neural_start import check_hw, embed_hw, hw_states
from .selection import validation_data

__all__ = ["NeuralStateSpaceModel", "nlssest"]


@register_model
class NeuralStateSpaceModel(LinearPart, ModelMixin):
    """A neural state-space model (see the module documentation) from :func:`nlssest`.

    Attributes
    ----------
    params : ndarray
        ``[A, B, C, D, f, g, h]`` (scaled channels, row-major; networks layer by layer:
        weights ``out x in`` then biases; the encoder's linear term first).
    hidden, output_hidden, encoder_hidden : tuple of int
        Hidden widths of ``f``, ``g`` (``None``: no output network) and the encoder.
    lags : int
        Past samples the encoder reads.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.NeuralStateSpaceModel.from_linear(
    ...     sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=1.0), hidden=(4,))
    >>> m.simulate([1.0, 1.0, 0.0])[:, 0]
    array([0. , 1. , 1.5])
    """

    def __init__(self, params: Any, *, dims: Sequence[int], hidden: Sequence[int],
                 output_hidden: Sequence[int] | None, encoder_hidden: Sequence[int],
                 lags: int, scaling: dict[str, Any] | None = None, dt: float = 1.0,
                 input_names: Any = None, output_names: Any = None,
                 info: dict[str, Any] | None = None) -> None:
        self.nstates, self.ninputs, self.noutputs = (int(v) for v in dims)
        self.hidden = tuple(int(h) for h in hidden)
        self.output_hidden = None if output_hidden is None else tuple(int(h) for h in
                                                                     output_hidden)
        self.encoder_hidden = tuple(int(h) for h in encoder_hidden)
        self.lags = int(lags)
        self.params = np.ascontiguousarray(params, dtype=float).ravel()
        need = _sysid.neural_ss_n_params(self._struct())
        if self.params.size != need:
            raise DataError(f"params has {self.params.size} values; the structure needs {need}")
        self.scaling, self.input_names, self.output_names = channels(
            scaling, self.ninputs, self.noutputs, input_names, output_names)
        self.dt = float(dt)
        self.info = dict(info or {"method": "nlssest"})

    @classmethod
    def from_linear(cls, lin: StateSpaceModel, *, hidden: Sequence[int] = (16,),
                    output_hidden: Sequence[int] | None = None,
                    encoder_hidden: Sequence[int] = (), lags: int = 1, seed: int = 0,
                    scaling: dict[str, Any] | None = None,
                    encoder_linear: Any = None) -> NeuralStateSpaceModel:
        """The linear model with networks whose outputs start at zero (random hidden
        weights of variance ``1/fan_in``, seeded)."""
        n, m, l_ = lin.nstates, lin.ninputs, lin.noutputs
        rng = np.random.default_rng(seed)
        parts = [np.ravel(a) for a in (lin.A, lin.B, lin.C, lin.D)]
        parts.append(_net(rng, n + m, hidden, n, skip=None))
        if output_hidden is not None:
            parts.append(_net(rng, n + m, output_hidden, l_, skip=None))
        nin = lags * (m + l_)
        skip = np.zeros((n, nin)) if encoder_linear is None else np.asarray(encoder_linear)
        parts.append(_net(rng, nin, encoder_hidden, n, skip=skip))
        return cls(np.concatenate(parts), dims=(n, m, l_), hidden=hidden,
                   output_hidden=output_hidden, encoder_hidden=encoder_hidden, lags=lags,
                   scaling=scaling, dt=lin.dt)

    def _struct(self) -> dict[str, Any]:
        return {"dims": (self.nstates, self.ninputs, self.noutputs), "f_hidden": list(self.hidden),
                "g_hidden": None if self.output_hidden is None else list(self.output_hidden),
                "h_hidden": list(self.encoder_hidden), "lags": self.lags}

    @property
    def n_parameters(self) -> int:
        """Parameters of the simulation model (the encoder's excluded)."""
        n, m, l_ = self.nstates, self.ninputs, self.noutputs
        enc = _sysid.neural_ss_n_params({**self._struct(), "f_hidden": [], "g_hidden": None}) \
            - (n * n + n * m + l_ * n + l_ * m + n * (n + m) + n)
        return int(self.params.size - enc)

    _arr = staticmethod(signal)  # the shared check of a signal argument

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Output ``(n_samples, noutputs)`` from ``x0`` (scaled-state coordinates; zero by
        default); :meth:`initial_state` estimates one from past data."""
        us = self.scaling.u(self._arr(u, self.ninputs, "u"))
        x = [0.0] * self.nstates if x0 is None else [float(v) for v in np.ravel(x0)]
        y = _sysid.neural_ss_simulate(self._struct(), self.params, us, x)
        return self.scaling.y_back(np.asarray(y).reshape(-1, self.noutputs))

    def initial_state(self, u_past: Any, y_past: Any) -> np.ndarray:
        """The encoder's state after the given past (at least ``lags`` samples)."""
        up = self.scaling.u(self._arr(u_past, self.ninputs, "u_past"))
        yp = self.scaling.y(self._arr(y_past, self.noutputs, "y_past"))
        if up.shape[0] != yp.shape[0]:
            raise DataError("u_past and y_past need the same number of samples")
        return np.asarray(_sysid.neural_ss_encode(self._struct(), self.params, up, yp,
                                                  up.shape[0]))

    def linear(self) -> StateSpaceModel:
        """The linear part ``(A, B, C, D)`` in engineering units."""
        n, m, l_ = self.nstates, self.ninputs, self.noutputs
        o = np.cumsum([0, n * n, n * m, l_ * n, l_ * m])
        A, B, C, D = (self.params[o[i]:o[i + 1]] for i in range(4))
        return self.scaling.to_units(A.reshape(n, n), B.reshape(n, m), C.reshape(l_, n),
                                     D.reshape(l_, m), self)

    def to_dict(self) -> dict[str, Any]:
        return {"params": self.params, "dims": [self.nstates, self.ninputs, self.noutputs],
                "hidden": list(self.hidden), "output_hidden": None if self.output_hidden is
                None else list(self.output_hidden), "encoder_hidden": list(self.encoder_hidden),
                "lags": self.lags, "scaling": self.scaling.to_dict(), "dt": self.dt,
                "input_names": self.input_names, "output_names": self.output_names,
                "info": self.info}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> NeuralStateSpaceModel:
        return cls(d["params"], dims=d["dims"], hidden=d["hidden"],
                   output_hidden=d["output_hidden"], encoder_hidden=d["encoder_hidden"],
                   lags=d["lags"], scaling=d["scaling"], dt=d["dt"],
                   input_names=d["input_names"], output_names=d["output_names"],
                   info=d.get("info"))

    def summary(self) -> str:
        t = self.info.get("training", {})
        return (f"{self!r}\n  parameters: {self.n_parameters} (+ encoder)\n  epochs: "
                f"{len(t.get('train', []))}, best {t.get('best_epoch', '-')}, stop: "
                f"{t.get('stop', '-')}")

    def __repr__(self) -> str:
        return (f"NeuralStateSpaceModel(nstates={self.nstates}, ninputs={self.ninputs}, "
                f"noutputs={self.noutputs}, hidden={self.hidden}, dt={self.dt:g})")


def _net(rng: np.random.Generator, nin: int, hidden: Sequence[int], nout: int,
         skip: Any) -> np.ndarray:
    sizes = [nin, *hidden, nout]
    parts = [] if skip is None else [np.ravel(skip)]
    for k in range(len(sizes) - 1):
        a, b = sizes[k], sizes[k + 1]
        last = k == len(sizes) - 2
        w = np.zeros((b, a)) if last else rng.standard_normal((b, a)) / np.sqrt(a)
        parts += [w.ravel(), np.zeros(b)]
    return np.concatenate(parts)


def _phi(u: np.ndarray, y: np.ndarray, lags: int) -> np.ndarray:
    """Rows ``[y(t-1..t-L), u(t-1..t-L)]`` for ``t = L .. N-1``."""
    N = u.shape[0]
    ys = [y[lags - 1 - k:N - 1 - k] for k in range(lags)]
    us = [u[lags - 1 - k:N - 1 - k] for k in range(lags)]
    return np.hstack(ys + us)


def _widths(h: Any, name: str) -> tuple[int, ...]:
    t = (h,) if np.ndim(h) == 0 else tuple(h)
    if not all(isinstance(v, (int, np.integer)) and v > 0 for v in t):
        raise DataError(f"{name} must be a positive integer or a tuple of them, got {h!r}")
    return tuple(int(v) for v in t)


@one_blas_thread
def nlssest(
    data: IOData | tuple[Any, Any],
    order: int,
    *,
    hidden: Any = 16,
    output_hidden: Any = "same",
    encoder_hidden: Any = (),
    lags: int | None = None,
    horizon: int | None = None,
    epochs: int = 200,
    batch: int = 16,
    learning_rate: float = 3e-3,
    patience: int = 20,
    regularization: float = 0.0,
    validation: Any = 0.2,
    periods: int | None = None,
    init: Any = "auto",
    seed: int = 0,
    progress: bool | None | Callable[..., Any] = None,
) -> NeuralStateSpaceModel:
    """Neural state-space model trained on truncated simulation errors.

    Parameters
    ----------
    data : IOData or (u, y)
        Estimation record(s).
    order : int
        Number of states.
    hidden, output_hidden, encoder_hidden : int or tuple of int
        Hidden widths of the state network ``f``, the output network ``g`` (default
        ``"same"``: those of ``f``; ``None``: the output equation stays linear, which a
        Wiener-type plant, a static nonlinearity after the dynamics, cannot be fitted
        with) and the encoder network (``()``: the encoder is linear).
    lags : int, optional
        Past samples the encoder reads (default ``max(2 order, 4)``).
    horizon : int, optional
        Samples per training section. Default: 100, or longer for a slow linear start:
        ``ln(10)`` times its slowest time constant ``1 / |1 - |lambda||`` (modes with
        ``|1 - |lambda|| < 1e-4``, drifts, left out), so that a section sees what its state
        map's errors accumulate to; at most half the shortest training part.
    epochs, batch, learning_rate : int, int, float
        Adam's passes over the data, sections per step and step size. The rows of the
        linear part and of the state network that move a mode ``lambda`` of the linear
        start (in its real modal coordinates) step ``min(1, |1 - |lambda||)`` times
        ``learning_rate``: a mode integrates a push over ``1 / |1 - |lambda||`` samples and
        a change of its row moves its pole by about as much, so a step that suits a fast
        mode makes a slow or lightly damped one drift or lose its stability.
    patience : int
        Stop after this many epochs without a lower validation error.
    regularization : float
        Weight ``lambda`` of an L2 penalty toward the start: each step's criterion (the
        mean squared section error of the scaled outputs, unit variance) plus ``lambda / 2``
        times the squared distance of the simulation model's parameters (linear part and
        networks; not the encoder's) from the start's, which keeps the trained model near
        the start where the data say little (regularisation toward a prior guess: Ljung,
        *System Identification*, 2nd ed., 1999, sec. 7.1; MATLAB's ``nlssest`` has the
        same term toward zero, ``Lambda``). Default 0: no penalty.
    validation : float, IOData or (u, y)
        The fraction of each experiment's end held out, or separate records. The criterion
        is the error of the free-run simulation from rest (as the model is used and
        compared: each experiment simulated whole, its held-out end scored); the start
        (the linear model) is a candidate, so the model returned never validates worse
        than it.
    periods : int, optional
        Periods per experiment: the linear start is then the BLA's model.
    init : "auto", "linear", None, StateSpaceModel or HammersteinWienerSSModel
        The start. ``"linear"`` (or ``None``): the linear model (see ``periods``).
        ``"auto"`` (default): that linear model and a Hammerstein-Wiener model
        (:func:`sysid.nlhw_ss` on the training parts in scaled channels, ``HW_UNITS = 3``
        sigmoid units per input and output, at most ``HW_ITER = 30`` iterations: the bound
        on its cost), each trained (same seed and settings, the one with the lower
        validation error first), the model with the lower validation error at its best
        epoch returned (where a start's training ends is not ranked by the start's own
        error); the Hammerstein-Wiener candidate is left out when the networks are not one
        hidden layer wide enough for its units or its search finds no admissible start. A
        :class:`~sysid.StateSpaceModel` (engineering units) is a given linear start; a
        :class:`~sysid.HammersteinWienerSSModel` (engineering units, sigmoid-network or
        identity channels, no direct term from a nonlinear input channel) is embedded
        exactly: its linear block is the linear part and each sigmoid unit a first hidden
        unit of the state or output network (the other units start with zero output), so
        the start simulates as the Hammerstein-Wiener model does.
    seed : int
        Seeds the weights and the section sampling (same seed, same model).
    progress : bool or callable, optional
        A bar over the epochs with the validation error (on a terminal by default; one per
        start trained); a callable gets ``(epoch, validation_mse, train_mse)`` (epochs
        counted per start) and may return ``False`` to stop: no further start is then
        trained.

    Returns
    -------
    NeuralStateSpaceModel
        ``info["training"]``: the validation and training errors per epoch, the best
        epoch, why it stopped; ``info["start"]``: ``"linear"`` or ``"hammerstein-wiener"``,
        ``info["start_validation"]``: each candidate start's validation error;
        ``info["starts"]``: each trained start's ``training`` summary (``info["training"]``
        is that of the start returned).

    Warns
    -----
    StabilityWarning
        When the model, simulated from rest at the middle of a training experiment, does not
        return to its simulation of the whole experiment (``info["memory"]``, see
        :mod:`sysid.nlss.memory`).
    IterationLimitWarning
        When the training returned stopped at ``epochs`` with its best epoch the last (the
        validation error still falling): raise ``epochs``.
    SysidWarning
        When no epoch improved on the start and steps diverged (the model is the untrained
        start): lower ``learning_rate``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(1500)
    >>> x = np.zeros(1501)
    >>> for t in range(1500):
    ...     x[t + 1] = 0.8 * x[t] + 0.5 * np.tanh(2 * u[t])
    >>> d = sysid.IOData(u, x[:-1], 1.0)
    >>> m = sysid.nlssest(d, 1, hidden=8, epochs=20, learning_rate=1e-2, progress=False)
    >>> m.info["start"]  # a Hammerstein plant: that start validates better than the linear
    'hammerstein-wiener'
    >>> sv = m.info["start_validation"]
    >>> bool(min(m.info["training"]["validation"]) < 0.05 * sv["linear"])
    True
    """
    data = require_record(data, "nlssest")
    from .._checks import as_int, as_nonnegative, as_seed

    n = check_order(order)
    hid, enc = _widths(hidden, "hidden"), _widths(encoder_hidden, "encoder_hidden") \
        if encoder_hidden != () else ()
    out = None if output_hidden is None else hid if isinstance(output_hidden, str) and \
        output_hidden == "same" else _widths(output_hidden, "output_hidden")
    L = max(2 * n, 4) if lags is None else as_int(lags, "lags", 1)
    H = None if horizon is None else as_int(horizon, "horizon", 2)
    if data.n_inputs == 0:
        raise DataError("nlssest needs inputs")
    _check_init(init)
    lam_reg = as_nonnegative(regularization, "regularization")
    epochs, batch = as_int(epochs, "epochs", 0), as_int(batch, "batch", 1)
    patience, seed = as_int(patience, "patience", 1), as_seed(seed)
    if not as_nonnegative(learning_rate, "learning_rate") > 0:
        raise DataError(f"learning_rate must be a finite number > 0, got {learning_rate!r}")
    sc = Scaling.of(data)
    sd = scaled_data(data, sc)
    # records (an IOData or a (u, y) pair) checked for the training data's channels
    validation = validation_data(validation, data)
    train, val = _split(sd, sc, validation, L, 2 if H is None else H)
    lin_data = IOData([u[:at] for u, _, at in train], [y[:at] for _, y, at in train], data.dt)
    whole = isinstance(validation, IOData) or float(validation) == 0.0
    args = (hid, out, enc, L, seed, sc, train, H)
    default = isinstance(hidden, int) and hidden == 16 and isinstance(output_hidden, str)
    if isinstance(init, HammersteinWienerSSModel):  # in engineering units
        check_hw(init, n, data.n_inputs, data.n_outputs, hid, out)
        units = Scaling(np.zeros(data.n_inputs), np.ones(data.n_inputs),
                        np.zeros(data.n_outputs), np.ones(data.n_outputs))
        _check_size(train, (n, data.n_inputs, data.n_outputs), hid, out, enc, L, default)
        cands = [_hw_start(init, units, *args)]
    else:
        # its linear start is capped at 30 iterations: from the converged ssest fit the
        # training validated worse on held-out data (pH, F-16; benches/results/nonlinear.md)
        lin0 = linear_start(data, lin_data, sc, n, None if isinstance(init, str) else init,
                            periods if whole else None, max_iter=30)
        # after the linear start, whose refusal of a record too short for the order comes
        # first: no network fits where no linear model does
        _check_size(train, (n, data.n_inputs, data.n_outputs), hid, out, enc, L, default)
        cands = [_linear_start(lin0, *args)]
        if isinstance(init, str) and init == "auto":
            hw = _hw_fit(lin_data, lin0, hid, out,  # in the scaled channels
                         progress if progress is None or isinstance(progress, bool) else False)
            if hw is not None:
                cands.append(_hw_start(hw, sc, *args))
    scores = [_score(c, train, val) for c in cands]
    done: dict[str, tuple[dict[str, Any], int]] = {}  # kind: (training, section length)
    for i in sorted(range(len(cands)), key=lambda i: scores[i]):  # the better start first
        start, lam, modal, H, kind = cands[i]
        label = "nlssest" if len(cands) == 1 else f"nlssest ({kind} start)"
        cb, close = iteration_callback(progress, label, epochs, unit="epoch", postfix=_errors)
        try:
            res = _sysid.neural_ss_train(start._struct(), start.params, train, val,
                                         epochs=epochs, batch=batch, horizon=H,
                                         learning_rate=learning_rate, patience=patience,
                                         seed=seed, progress=cb, rates=_rates(start, lam, modal),
                                         penalty=_penalty(start, lam_reg))
        finally:
            close()
        done[kind] = res, H
        if res["stop"] == "cancelled":  # the caller's progress said stop: no further start
            break
    kind = min(done, key=lambda k: _best(done[k][0]))  # a tie keeps the better start
    res, H = done[kind]
    runs = {k: {key: r[key] for key in ("validation", "train", "best_epoch", "stop",
                                        "diverged")} for k, (r, _) in done.items()}
    info = {"method": "nlssest", "start": kind, "start_validation": dict(
                zip([c[4] for c in cands], scores)),
            "training": runs[kind], "starts": runs, "horizon": H, "seed": seed,
            "regularization": lam_reg}
    _warn_short(res, epochs, learning_rate)
    model = NeuralStateSpaceModel(res["params"], dims=(n, data.n_inputs, data.n_outputs),
                                  hidden=hid, output_hidden=out, encoder_hidden=enc, lags=L,
                                  scaling=sc.to_dict(), dt=data.dt,
                                  input_names=data.input_names, output_names=data.output_names,
                                  info=info)
    return check_memory(model, data, "nlssest")


def _warn_short(res: dict[str, Any], epochs: int, learning_rate: float) -> None:
    """Say when the training returned did not train: every epoch's step diverged (the
    model is its start), or it stopped at ``epochs`` with its validation error still
    falling (its best epoch the last)."""
    import warnings

    from .._checks import user_stacklevel
    from ..errors import IterationLimitWarning

    best = int(res["best_epoch"])
    if epochs > 0 and best == 0 and int(res.get("diverged", 0)) > 0:
        warnings.warn(f"nlssest: no training epoch improved on the start (the simulation "
                      f"diverged {int(res['diverged'])} times); the model is the untrained "
                      f"start: lower learning_rate (now {learning_rate:g}) or the horizon",
                      SysidWarning, stacklevel=user_stacklevel())
    elif res["stop"] == "epochs" and epochs > 1 and best == epochs:
        v = [float(x) for x in res["validation"]]
        warnings.warn(f"nlssest stopped at epochs={epochs} with its validation error still "
                      f"falling (best at the last epoch, {v[-1]:.4g} after {v[-2]:.4g}); "
                      "the model is that epoch's: raise epochs", IterationLimitWarning,
                      stacklevel=user_stacklevel())


def _check_size(train: list, dims: tuple[int, int, int], hid: Sequence[int],
                out: Sequence[int] | None, enc: Sequence[int], L: int, default: bool) -> None:
    """Refuse networks with as many parameters as the training part has residuals, naming
    the widths (the defaults, when the caller gave none) and the widest single hidden layer
    that fits: the core's own refusal said "invalid hidden" to a call that passed no
    ``hidden`` (``nlssest(est, 3)`` on 333 samples: 319 parameters, 260 residuals)."""
    def count(h: Sequence[int], o: Sequence[int] | None) -> int:
        return int(_sysid.neural_ss_n_params({"dims": dims, "f_hidden": list(h), "g_hidden":
                                              None if o is None else list(o),
                                              "h_hidden": list(enc), "lags": L}))
    residuals = sum(max(at - L, 0) for _, _, at in train) * dims[2]
    have = count(hid, out)
    if have < residuals:
        return
    same = out is not None and tuple(out) == tuple(hid)
    fits = [w for w in range(max(hid) - 1, 0, -1)
            if len(hid) == 1 and count([w], [w] if same else out) < residuals]
    what = ("hidden=16, output_hidden='same' (the defaults)" if default else
            f"hidden={list(hid)}" + (f", output_hidden={list(out)}" if out is not None else ""))
    hint = (f"pass hidden={fits[0]} or narrower" + ("" if same or out is None else
                                                    " with these output widths")
            if fits else "give fewer states or hidden layers")
    raise DataError(f"nlssest: {what} give networks of {have} parameters, and the training "
                    f"part of the record has {residuals} residuals (samples after the {L} "
                    f"lags, times outputs): {hint}, or give more data")


def _split(sd: IOData, sc: Scaling, validation: Any, L: int, H: int) -> tuple[list, list]:
    """Training records ``(u, y, end)`` and validation records ``(u, y, start)``."""
    c = np.ascontiguousarray
    if isinstance(validation, IOData):
        train = [(c(u), c(y), u.shape[0]) for u, y in sd.experiments]
        val = [(sc.u(u), sc.y(y), 0) for u, y in validation.experiments]
        return train, val
    from .._checks import as_between

    frac = as_between(validation, "validation (a fraction of each record, or an IOData)",
                      0.0, 0.9, closed="left")
    train, val = [], []
    for u, y in sd.experiments:
        N = u.shape[0]
        at = int(round(N * (1 - frac)))
        if at < L + H:
            raise DataError(f"an experiment of {N} samples leaves {at} for training, fewer "
                            f"than lags + horizon = {L + H}; shorten them or give more data")
        train.append((c(u), c(y), at))
        if frac > 0 and N - at > 0:
            val.append((c(u), c(y), at))
    return train, val


def _encoder_fit(states: list[np.ndarray], train: list, L: int) -> np.ndarray:
    """Least-squares map from the past window to a start's simulated states (one array per
    training record, over its training part)."""
    P, X = [], []
    for (u, y, at), x in zip(train, states):
        P.append(_phi(u[:at], y[:at], L))
        X.append(x[L:at])
    Pm, Xm = np.vstack(P), np.vstack(X)
    skip = max(0, Pm.shape[0] // 10)  # the transient from rest is not the map's business
    W, *_ = np.linalg.lstsq(Pm[skip:], Xm[skip:], rcond=1e-10)
    return np.ascontiguousarray(W.T)


_INITS = ("auto", "linear")
#: The Hammerstein-Wiener start of ``init="auto"``: sigmoid units per channel and its
#: search's iterations (each a pass of sensitivities over the record: the bound on its cost).
HW_UNITS, HW_ITER = 3, 30


def _check_init(init: Any) -> None:
    if init is None or isinstance(init, (StateSpaceModel, HammersteinWienerSSModel)) or (
            isinstance(init, str) and init in _INITS) or (
            not isinstance(init, str) and hasattr(init, "to_statespace")):
        return
    raise DataError(f"init must be None or 'linear' (the linear start), 'auto' (the linear "
                    f"or a Hammerstein-Wiener start, whichever validates better), a "
                    f"sysid.StateSpaceModel or a sysid.HammersteinWienerSSModel; got {init!r}")


def _cand(lin: StateSpaceModel, lam: np.ndarray, modal: bool, states: list[np.ndarray],
          hid: tuple[int, ...], out: tuple[int, ...] | None, enc: tuple[int, ...], L: int,
          seed: int, sc: Scaling, train: list, H: int | None) -> tuple[Any, ...]:
    """A start from its linear part (final basis) and simulated states: the model (networks
    at zero output), its poles, whether in modal coordinates, and its section length."""
    if H is None:
        H = _horizon(lam, min(at for _, _, at in train) - L)
    start = NeuralStateSpaceModel.from_linear(lin, hidden=hid, output_hidden=out,
                                              encoder_hidden=enc, lags=L, seed=seed,
                                              scaling=sc.to_dict(),
                                              encoder_linear=_encoder_fit(states, train, L))
    return start, lam, modal, H


def _linear_start(lin: StateSpaceModel, hid: tuple[int, ...], out: tuple[int, ...] | None,
                  enc: tuple[int, ...], L: int, seed: int, sc: Scaling, train: list,
                  H: int | None) -> tuple[Any, ...]:
    """The linear model (scaled channels) as a start: modal, then balanced coordinates."""
    lin, lam, modal = _modal(lin)
    lin = balanced(lin, [u for u, _, _ in train])
    states = linear_states(lin, [u[:at] for u, _, at in train])
    return (*_cand(lin, lam, modal, states, hid, out, enc, L, seed, sc, train, H), "linear")


def _hw_start(hw: HammersteinWienerSSModel, hsc: Scaling, hid: tuple[int, ...],
              out: tuple[int, ...] | None, enc: tuple[int, ...], L: int, seed: int,
              sc: Scaling, train: list, H: int | None) -> tuple[Any, ...]:
    """The Hammerstein-Wiener model ``hw`` (in the units ``hsc`` scales engineering units
    to: no scaling, or ``sc`` for the scaled channels) embedded exactly: its linear block in
    modal coordinates with unit-variance states, its sigmoid units the networks' first
    hidden units."""
    import copy

    lin, lam, modal = _modal(StateSpaceModel(hw.A, hw.B, hw.C, hw.D, dt=hw.dt))
    hw = copy.copy(hw)
    hw.A, hw.B, hw.C = lin.A, lin.B, lin.C
    # scaled channels in hw's units, about its operating point (it maps u - u_offset and
    # adds y_offset: nlhw_ss keeps the record's means when they lie off zero)
    to_hw = Scaling(hsc.u(sc.u_offset) - hw.u_offset, sc.u_scale / hsc.u_scale,
                    hsc.y(sc.y_offset) - hw.y_offset, sc.y_scale / hsc.y_scale)
    s = np.vstack(hw_states(hw, to_hw, [u for u, _, _ in train])).std(axis=0)  # as balanced
    s = np.where(s > 1e-12 * max(s.max(), 1e-300), s, 1.0)
    hw.A, hw.B, hw.C = hw.A * s / s[:, None], hw.B / s[:, None], hw.C * s
    states = hw_states(hw, to_hw, [u[:at] for u, _, at in train])
    start, lam, modal, H = _cand(StateSpaceModel(hw.A, hw.B, hw.C, hw.D, dt=hw.dt), lam,
                                 modal, states, hid, out, enc, L, seed, sc, train, H)
    embed_hw(start, hw, to_hw)
    return start, lam, modal, H, "hammerstein-wiener"


def _hw_fit(lin_data: IOData, lin: StateSpaceModel, hid: tuple[int, ...],
            out: tuple[int, ...] | None, progress: bool | None = False
            ) -> HammersteinWienerSSModel | None:
    """The Hammerstein-Wiener start of ``init="auto"`` (scaled channels, training parts):
    ``HW_UNITS`` sigmoid units per channel, ``HW_ITER`` iterations from nlhw_ss's subspace
    start (a stable ``A`` enforced when it is unstable), or from the linear start ``lin``
    when that fit fails; ``None`` when the
    networks have no room for its units or neither start is admissible. ``progress``: its
    own bar (a terminal by default), as nlhw_ss shows it (it can take minutes on long
    records; a callable of nlssest's epochs does not fit its iterations, so none then)."""
    import warnings

    from ..errors import IterationLimitWarning
    from ..nonlinear.hw_model import SigmoidNetwork
    from ..nonlinear.hw_ss import nlhw_ss

    m, l_ = lin_data.n_inputs, lin_data.n_outputs
    if len(hid) != 1 or hid[0] < HW_UNITS * m or out is None or len(out) != 1 \
            or out[0] < HW_UNITS * l_:
        return None
    for start in (None, lin):  # nlhw_ss's own (subspace) start; if inadmissible, ``lin``
        try:
            with warnings.catch_warnings():  # a start: training goes on from its cap
                warnings.simplefilter("ignore", IterationLimitWarning)
                return nlhw_ss(lin_data, lin.nstates, input_nl=SigmoidNetwork(HW_UNITS),
                               output_nl=SigmoidNetwork(HW_UNITS), max_iter=HW_ITER,
                               progress=progress, linear=start)
        except (DataError, NumericalError):
            continue
    return None


def _score(cand: tuple[Any, ...], train: list, val: list) -> float:
    """A start's validation error, as training scores its epochs (epoch 0 of the core)."""
    start, _, _, H = cand[:4]
    r = _sysid.neural_ss_train(start._struct(), start.params, train, val, epochs=0,
                               horizon=H)
    return float(r["validation"][0])


def _best(res: dict[str, Any]) -> float:
    """A training's validation error at its best epoch (the one whose parameters it
    returns; a non-finite one ranks last)."""
    v = float(res["validation"][res["best_epoch"]])
    return v if np.isfinite(v) else np.inf


def _modal(m: StateSpaceModel) -> tuple[StateSpaceModel, np.ndarray, bool]:
    """The linear model in real modal coordinates (:func:`sysid.analysis.canon.
    real_modal_basis`: a state per real pole, two per complex pair), each state's pole and
    ``True``; the model as it is, its poles and ``False`` when its eigenvectors are (nearly)
    dependent."""
    from ..analysis.canon import real_modal_basis

    basis = real_modal_basis(m.A)
    if basis is None:
        return m, np.linalg.eigvals(m.A), False
    T, poles = basis
    Ti = np.linalg.inv(T)
    return (StateSpaceModel(Ti @ m.A @ T, Ti @ m.B, m.C @ T, m.D, dt=m.dt, info=m.info),
            poles, True)


def _margin(lam: np.ndarray) -> np.ndarray:
    """Each pole's distance from the unit circle, ``|1 - |lambda||``: the share of a mode
    that decays per sample (``1 / |1 - |lambda||`` samples its time constant)."""
    return np.abs(1 - np.abs(lam))


def _horizon(lam: np.ndarray, room: int) -> int:
    """Default section length: 100, or ``ln(10)`` slowest time constants ``1 / |1 -
    |lambda||`` (drifts, ``|1 - |lambda|| < 1e-4``, left out), at most ``room / 2``."""
    d = _margin(lam)
    d = d[d >= 1e-4]
    slow = int(np.ceil(np.log(10) / d.min())) if d.size else 0
    return int(max(2, min(max(100, slow), room // 2)))


def _rates(start: NeuralStateSpaceModel, lam: np.ndarray, modal: bool) -> np.ndarray:
    """Each parameter's step size relative to the learning rate: the rows of ``A``, ``B``
    and of the state network's last layer that move state ``i`` (of pole ``lam_i``, modal
    coordinates) ``min(1, |1 - |lam_i||)``, the rest 1. Adam moves every parameter by about
    the step size; a push ``d`` on a mode is integrated over ``1 / |1 - |lam||`` samples,
    and a change ``d`` of its row moves the pole by about ``d``, across the unit circle
    when ``d`` exceeds the margin. Without modal coordinates (``modal`` false) every state
    gets the slowest mode's."""
    n, m = start.nstates, start.ninputs
    d = _margin(lam)
    r = np.minimum(1.0, d) if modal else np.full(n, min(1.0, d.min()))
    rates = np.ones(start.params.size)
    rates[:n * n] = np.repeat(r, n)
    rates[n * n:n * (n + m)] = np.repeat(r, m)
    sizes = [n + m, *start.hidden, n]
    last = n * (n + m) + start.noutputs * (n + m) + sum(
        sizes[k] * sizes[k + 1] + sizes[k + 1] for k in range(len(sizes) - 2))
    h = sizes[-2]
    rates[last:last + n * h] = np.repeat(r, h)
    rates[last + n * h:last + n * h + n] = r
    return rates


def _penalty(start: NeuralStateSpaceModel, weight: float) -> np.ndarray | None:
    """Each parameter's weight in the L2 penalty toward the start: ``weight`` on the
    simulation model's (linear part and networks), 0 on the encoder's (it only sets the
    training sections' initial states); ``None`` without a penalty."""
    if weight == 0:
        return None
    w = np.zeros(start.params.size)
    w[:start.n_parameters] = weight
    return w


def _errors(epoch: int, val: float, train: float) -> dict[str, str]:
    """What the progress bar shows after an epoch."""
    return {"validation": f"{val:.4g}", "train": f"{train:.4g}"}
