"""The direct term a polynomial model with a one-sample delay leaves out.

``nk = 1`` (the default of :func:`sysid.arx`, :func:`sysid.armax`, :func:`sysid.oe`,
:func:`sysid.bj` and :func:`sysid.polyest`, and MATLAB's habitual ``[na nb 1]``) gives
``B(q) u(t - 1)``: the output cannot answer the input within the sample. A sensor that sees
the input within the sample (an accelerometer against a force, a heat flux against a
temperature) does, and such a model then explains the record's fastest part as noise; its
simulation on new data loses that part. The state-space estimators check their default
(no ``D``) against the record (:func:`sysid.subspace.feedthrough.warn_if_left_out`); this is the
same check for the polynomial family, by the same rule and threshold.

Two checks, either of which warns (the threshold ``LEFT_OUT_RATIO``, 2, the state-space
estimators' own):

* **ARX, per output** (every estimator): two ARX models fitted by least squares (the core's
  ``arx_fit``, over the first ``CHECK_SAMPLES`` samples of every experiment), one with every
  channel's delay as given, one where each channel with ``nk = 1`` also has ``u(t)``
  (``nk = 0``, one more ``B`` coefficient), both with ``n = min(max(orders, 4), 10)`` poles
  per output. ``u(t)`` dividing an output's one-step prediction errors by 2 names that output.
* **State space, all outputs** (the iterative estimators, ``oe``, ``armax``, ``bj``,
  ``polyest``, whose searches cost far more than the check): the state-space estimators' rule
  (:func:`_state_space_ratio`), MOESP fits at the model's order (the sum over outputs of
  each output's largest order: the state a realisation of the model carries)
  without and with ``D``. ``arx`` leaves it out: ``arxstruc`` fits it once per row.

Why both: an input that its own past predicts (a multisine, a periodic record) lets a rich
ARX model's past inputs stand in for ``u(t)``. On the shipped F-16 levels (three
accelerations against the shaker's force) the ARX ratio is 1.0-1.4 at every order while the
state-space ratio is 2-34 at orders 2 and 4 (states 6 and 12), where ``oe`` with ``nk = 0``
validates 10-18 points better; at order 8 (24 states) it is 0.8-1.2 and nothing warns,
though ``nk = 0`` still validates 15-19 points better (a miss). On the robot arm
(acceleration against torque) the ARX check flags orders 2 and 4 (29 times), where ``nk = 0``
validates 4-51 points better; at order 8 neither flags it and ``nk`` changes nothing. Neither
flags the dryer, the ball and beam or the pH record, nor six records the package does not
ship at orders 2 and 4 (a test tower, a soft actuator, a propeller pendulum, an air duct at
two settings, an LED and photoresistor: ``nk`` moves their validation fits by 0-4 points).
The state-space fit carries the model's whole state: at the largest order of one output
alone, the soft actuator (three outputs, order 2) read 6.7 where ``nk`` changes nothing. The
warning states a fact of the estimation record, which new data may not share: on the winding
record's second output ``nk = 0`` lowers ``oe``'s estimation cost from 82.8 to 23.1 and its
validation fit from 48 to 27 %; hence the advice to compare both on validation data.

An input independent of the same sample's noise (open loop, or a controller that acts on
earlier samples) leaves the ARX ratio near 1 whatever its spectrum; an input computed from
the same sample's output (an analogue loop sampled) gives a ratio above 1 that is the
controller's, and the warning says so.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _sysid
from ..subspace.feedthrough import CHECK_SAMPLES, LEFT_OUT_RATIO, _prediction_error

__all__ = ["check_polynomial_feedthrough", "left_out", "say_left_out"]

#: the fewest and the most poles per output of the check's ARX models
CHECK_ORDER = (4, 10)


def _losses(exps: list[tuple[np.ndarray, np.ndarray]], n: list[int], nb: list[list[int]],
            nk: list[list[int]]) -> np.ndarray:
    """Per output, the mean squared one-step error of the ARX fit with ``n`` poles (``A``
    coupling every output) and ``nb``, ``nk`` per channel."""
    ny = len(n)
    fits = _sysid.arx_fit(exps, [[n[i]] * ny for i in range(ny)], nb, nk, 0.0, None)
    return np.array([float(f["loss"]) for f in fits])


def _state_space_ratio(data: Any, order: int) -> float | None:
    """The state-space estimators' left-out ratio on ``data`` at ``order``: the one-step
    prediction errors of the MOESP fit without ``D`` over those with ``D``
    (:func:`sysid.subspace.feedthrough.warn_if_left_out`'s measure); None when the fits
    cannot be made."""
    import warnings

    from ..subspace.estimator import SubspaceEstimator

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            est = SubspaceEstimator(data)
            without, with_ = (_prediction_error(est._quiet_fit(order, method="moesp",
                                                               feedthrough=ft), data)
                              for ft in (False, True))
    except Exception:  # noqa: BLE001 - a check that cannot be made says nothing
        return None
    return without / with_ if with_ > 0 else np.inf


def left_out(check: dict[str, Any] | None) -> bool:
    """Whether :func:`check_polynomial_feedthrough` found a direct term left out (and said so).

    Examples
    --------
    >>> from sysid.polynomial.feedthrough import left_out
    >>> left_out(None), left_out({"shows": ""}), left_out({"shows": "y0 (5 times)"})
    (False, False, True)
    """
    return bool(check and check.get("shows"))


def check_polynomial_feedthrough(exps: list[tuple[np.ndarray, np.ndarray]], method: str,
                                 orders: list[int], nb_g: list[list[int]],
                                 nk_g: list[list[int]], data: Any = None, *,
                                 lag: str = "delays every input by nk = 1 sample",
                                 remedy: str = "Fit nk=0 for the channels with nk = 1"
                                 ) -> dict[str, Any] | None:
    """Warn (:class:`~sysid.errors.FeedthroughWarning`) when channels with ``nk = 1`` leave
    out a direct term the record shows (the module's rule); return the check for
    ``model.info["feedthrough_check"]``, or None where nothing is checked (no channel has
    ``nk = 1`` with ``B``, or the check's fits cannot be made).

    ``exps``: the experiments' ``(u, y)`` arrays; ``orders``: per output, the model's largest
    order (``na``, ``nb``, ``nf``, ``nc``, ``nd``); ``nb_g``, ``nk_g``: per output and input;
    ``data``: the record, for the state-space check (left out when None); ``lag`` and
    ``remedy``: how the warning names the structure's one-sample lag and its way out (another
    family's, as ``tfest``'s ``feedthrough=False``).

    Examples
    --------
    >>> import numpy as np, warnings
    >>> from sysid.polynomial.feedthrough import check_polynomial_feedthrough
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((800, 1)); y = np.zeros((800, 1))
    >>> for t in range(1, 800): y[t] = 0.8 * y[t - 1] + u[t - 1] + 0.7 * u[t]
    >>> y += 0.05 * rng.standard_normal((800, 1))
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     check = check_polynomial_feedthrough([(u, y)], "arx", [1], [[1]], [[1]])
    >>> [type(x.message).__name__ for x in w], check["ratio"] > 2
    (['FeedthroughWarning'], True)
    """
    ny = len(nb_g)
    one = [[nk_g[i][j] == 1 and nb_g[i][j] > 0 for j in range(len(nb_g[i]))] for i in range(ny)]
    if not any(any(row) for row in one):
        return None
    n = [min(max(int(o), CHECK_ORDER[0]), CHECK_ORDER[1]) for o in orders]
    nb = [[n[i] if nb_g[i][j] else 0 for j in range(len(nb_g[i]))] for i in range(ny)]
    nb0 = [[v + int(one[i][j]) for j, v in enumerate(nb[i])] for i in range(ny)]
    nk0 = [[0 if one[i][j] else int(nk_g[i][j]) for j in range(len(nb_g[i]))]
           for i in range(ny)]
    part = [(np.ascontiguousarray(u[:CHECK_SAMPLES], float),
             np.ascontiguousarray(y[:CHECK_SAMPLES], float)) for u, y in exps]
    try:
        without = _losses(part, n, nb, [[int(v) for v in row] for row in nk_g])
        with_ = _losses(part, n, nb0, nk0)
    except Exception:  # noqa: BLE001 - a check that cannot be made says nothing
        return None
    ratio = np.where(with_ > 0, without / np.where(with_ > 0, with_, 1.0), np.inf)
    ratio = np.where(np.array([any(r) for r in one]), ratio, 1.0)
    check: dict[str, Any] = {
        "ratio": float(np.max(ratio)), "ratios": [float(r) for r in ratio],
        "threshold": LEFT_OUT_RATIO,
        "what": "per output, the one-step prediction errors of an ARX model with the channels' "
                "delays as given over those of the same model with u(t) in every channel "
                "whose nk is 1 (least squares, at most "
                f"{CHECK_SAMPLES} samples per experiment, {n} poles per output)"}
    flagged = [i for i in range(ny) if ratio[i] >= LEFT_OUT_RATIO]
    where = ", ".join(f"y{i} ({ratio[i]:.3g} times)" for i in flagged)
    if data is not None:
        order = int(sum(orders))  # the model's state: one output's orders after another
        sub = _state_space_ratio(data, order)
        if sub is not None:
            check["subspace_ratio"] = float(sub)
            check["subspace_what"] = (f"one-step prediction errors of the MOESP fit of order "
                                      f"{order} without D over those with D (all outputs)")
            if sub >= LEFT_OUT_RATIO:
                check["ratio"] = max(check["ratio"], float(sub))
                where = ", ".join(filter(None, [where, f"a state-space model of order "
                                                f"{order} ({sub:.3g} times)"]))
    check["shows"] = where
    say_left_out(check, method, lag, remedy)
    return check


def say_left_out(check: dict[str, Any] | None, method: str,
                 lag: str = "delays every input by nk = 1 sample",
                 remedy: str = "Fit nk=0 for the channels with nk = 1") -> None:
    """The :class:`~sysid.errors.FeedthroughWarning` of a check
    (:func:`check_polynomial_feedthrough`) that found a direct term (``check["shows"]``
    names where), in the words of ``method``'s structure (``lag``) and its way out
    (``remedy``); nothing otherwise. ``tfest`` says what the ``oe`` it runs found.

    Examples
    --------
    >>> import warnings
    >>> from sysid.polynomial.feedthrough import say_left_out
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     say_left_out({"shows": "y0 (5 times)"}, "arx")
    >>> w[0].category.__name__
    'FeedthroughWarning'
    """
    import warnings

    from .._checks import user_stacklevel
    from ..errors import FeedthroughWarning

    if not check or not check.get("shows"):
        return
    warnings.warn(
        f"{method} {lag}, but the record shows a direct term: with u(t) in the model the "
        f"one-step prediction errors are smaller on {check['shows']} (the output answers the "
        f"input within the sample). {remedy} and compare both on validation data "
        f"(sysid.delayest estimates the delay); unless the input is a controller's answer to "
        f"the same sample's output (feedback within the sample), where the lag is right",
        FeedthroughWarning, stacklevel=user_stacklevel())
