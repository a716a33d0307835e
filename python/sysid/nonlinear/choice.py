"""The nonlinearities of a Hammerstein-Wiener model, chosen on held-out blocks.

``nlhw`` and ``nlhw_ss`` fitted the identity on every channel unless given nonlinearities: a
linear output-error model under a nonlinear name (MATLAB's ``nlhw`` defaults to estimated
piecewise-linear maps on both sides). Sigmoid networks on both sides (3 units, the
benchmarks' setting) fit a record at least as well as the identity, since the search starts
from the linear model too; on data they were not fitted on they can do far worse. Measured
with ``nlhw_ss(data, 2)`` on 29 real record/split pairs (process, thermal, power electronics,
servo, robot and the Silverbox, Wiener-Hammerstein, cascaded-tanks, EMPS and pH benchmarks,
with the reversed splits of ``benches/realdata.py`` where they have one; script outside the
project), validation simulation fits clipped at -100 % and summed:

- the identity always (the old default): 1561.2;
- sigmoid networks always: 1452.8 (the heating system -100 % against 62.7 %, dryer2
  -27.3 % against -0.9 %, the ball and beam 24.2 % against 39.2 %);
- the sigmoid networks where the held-out blocks of the estimation record insist on them
  (:func:`sysid.validation.crossval.insists`, as ``pnlss`` takes its cubic terms): 1699.0.
  They were taken on 15 of the 29 (the DC motor 47.2 -> 68.9 %, the MR damper 51.7 ->
  72.9 %, the Wiener-Hammerstein benchmark 63.4 -> 70.3 %, the CSTR 87.8 -> 92.5 %); where
  taken, the validation fit fell on one, EMPS (79.6 -> 77.9 %).

So ``"auto"`` (the default of ``input_nl`` and ``output_nl``) fits both candidates on the
estimation record less each of its blocks (:func:`sysid.validation.crossval.record_folds`),
scores each on the block left out (:func:`sysid.compare`, initial state fitted, a block's
fit at least -100 %) and takes the networks only where the blocks insist. A record too
short for two blocks keeps the identity, and says so in the reason.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import SysidError
from .hw_model import SigmoidNetwork

__all__ = ["AUTO", "UNITS", "NonlinearityChoice", "choose_nonlinearities", "is_auto"]

#: the value of ``input_nl`` / ``output_nl`` that asks for the choice
AUTO = "auto"
#: sigmoid units per channel of the nonlinear candidate
UNITS = 3
#: a held-out block's fit counts at least this much
FLOOR = -100.0


def is_auto(nl: Any) -> bool:
    """Whether a side's nonlinearity argument is ``"auto"``."""
    return isinstance(nl, str) and nl == AUTO


@dataclass
class NonlinearityChoice:
    """The nonlinearities ``"auto"`` chose, the held-out table it read and why.

    Attributes
    ----------
    kind : str
        ``"identity"`` or ``"sigmoid"`` (:data:`UNITS` units on every channel of each side
        given as ``"auto"``).
    sides : tuple of str
        The sides chosen (``"input"``, ``"output"``).
    table : dict
        ``{kind: median held-out simulation fit %}``.
    folds : dict
        Each candidate's per-block fits (at least -100 %).
    reason : str
    """

    kind: str
    sides: tuple[str, ...]
    table: dict[str, float] = field(default_factory=dict)
    folds: dict[str, list[float]] = field(default_factory=dict)
    reason: str = ""

    def as_dict(self) -> dict[str, Any]:
        """A plain-dict copy, for a model's ``info``."""
        return {"kind": self.kind, "sides": list(self.sides), "table": dict(self.table),
                "folds": {k: list(v) for k, v in self.folds.items()}, "reason": self.reason}


def candidate(kind: str, given: Any, channels: int) -> Any:
    """A side's nonlinearity for candidate ``kind``: ``given`` unless it is ``"auto"``,
    then ``None`` (identity) or a fresh sigmoid network per channel (one when
    ``channels`` is 0: a single-channel estimator's scalar argument)."""
    if not is_auto(given):
        return given
    if kind == "identity":
        return None
    if channels == 0:
        return SigmoidNetwork(UNITS)
    return [SigmoidNetwork(UNITS) for _ in range(channels)]


def choose_nonlinearities(data: IOData, fit: Callable[[IOData, str], Any],
                          sides: tuple[str, ...],
                          tick: Callable[[int, float], Any] | None = None
                          ) -> NonlinearityChoice:
    """Choose the identity or sigmoid networks on the ``"auto"`` sides by held-out fit.

    Parameters
    ----------
    data : IOData
        The estimation record.
    fit : callable
        ``fit(part, kind)`` returns the model with candidate ``kind``'s nonlinearities
        (:func:`candidate`) fitted on ``part``.
    sides : tuple of str
        The sides given as ``"auto"`` (for the reason).
    tick : callable, optional
        ``tick(count, fit)`` after each fold's fit (progress).

    Returns
    -------
    NonlinearityChoice

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.nonlinear.choice import candidate, choose_nonlinearities
    >>> u = np.random.default_rng(0).uniform(-1, 1, (400, 1))
    >>> y = np.convolve(u[:, 0], [0, 1.0, 0.5])[:400, None]  # linear: no network insists
    >>> c = choose_nonlinearities(sysid.IOData(u, y), lambda part, kind: sysid.nlhw_ss(
    ...     part, 2, output_nl=candidate(kind, "auto", 1), progress=False), ("output",))
    >>> c.kind
    'identity'
    """
    from ..validation.crossval import MIN_BLOCK, held_out_fit, insists, record_folds

    n = sum(data.lengths)
    pairs = record_folds(data) if n >= 2 * MIN_BLOCK else []
    where = " and ".join(sides) + (" sides" if len(sides) > 1 else " side")
    if len(pairs) < 2:
        return NonlinearityChoice("identity", sides, reason=(
            f"the identity on the {where}: the record ({n} samples) is too short to "
            f"choose on held-out blocks (two of {MIN_BLOCK} samples); give the "
            "nonlinearities to fit them"))
    kinds = ("identity", "sigmoid")
    folds: dict[str, list[float]] = {k: [] for k in kinds}
    failed: dict[str, list[SysidError]] = {k: [] for k in kinds}
    with warnings.catch_warnings():
        # the fold fits are scored, not returned: their own warnings are not the user's
        warnings.simplefilter("ignore")
        for part, block in pairs:
            for k in kinds:
                try:
                    folds[k].append(held_out_fit(fit(part, k), block, FLOOR))
                except SysidError as e:
                    failed[k].append(e)
                    folds[k].append(FLOOR)
                if tick is not None:
                    tick(sum(map(len, folds.values())), folds[k][-1])
    if len(failed["identity"]) == len(pairs) and len(failed["sigmoid"]) == len(pairs):
        # no candidate fits any part (the settings, or parts too short for them): the fit
        # on the whole record says which
        return NonlinearityChoice("identity", sides, folds={k: list(v) for k, v in
                                                            folds.items()}, reason=(
            f"the identity on the {where}: no candidate could be fitted on the record's "
            f"parts ({failed['identity'][0]})"))
    table = {k: float(np.median(v)) for k, v in folds.items()}
    kind = "sigmoid" if insists(folds["sigmoid"], folds["identity"]) else "identity"
    what = {"identity": "the identity", "sigmoid": f"sigmoid networks of {UNITS} units"}
    reason = (f"{what[kind]} on the {where}: held-out simulation fit {table[kind]:.1f} % "
              f"(median over {len(pairs)} blocks; the identity {table['identity']:.1f} %, "
              f"sigmoid networks {table['sigmoid']:.1f} %)")
    if kind == "identity" and table["sigmoid"] > table["identity"]:
        reason += ("; the networks' gain is within twice the standard error of the blocks' "
                   "differences")
    return NonlinearityChoice(kind, sides, table, folds, reason)


def auto_fit(data: Any, estimate: Callable[[IOData, Any, Any, Any], Any], input_nl: Any,
             output_nl: Any, channels: tuple[int, int], progress: Any, label: str) -> Any:
    """``estimate(data, input_nl, output_nl, progress)`` with the ``"auto"`` sides chosen
    by :func:`choose_nonlinearities` (a bar over the fold fits; a progress callable follows
    the final fit only), the choice in ``info["nonlinearity_choice"]``. ``channels``: the
    inputs and outputs a side's list needs (0: a single nonlinearity)."""
    from .._checks import experiment_arrays
    from .._progress import iteration_callback
    from ..validation.crossval import fold_count

    experiment_arrays(data)  # not a record: that error first
    sides = tuple(s for s, nl in (("input", input_nl), ("output", output_nl)) if is_auto(nl))

    def pick(kind: str) -> tuple[Any, Any]:
        return candidate(kind, input_nl, channels[0]), candidate(kind, output_nl, channels[1])

    def fit(part: IOData, kind: str) -> Any:
        return estimate(part, *pick(kind), False)

    def line(i: int, f: float, *_: Any) -> None:
        print(f"{label} nonlinearity choice: fold fit {i}: held-out simulation fit {f:.1f} %")

    cb, close = iteration_callback(False if callable(progress) else progress,
                                   f"{label} nonlinearity choice", 2 * fold_count(data), line,
                                   unit="fit",
                                   postfix=lambda i, f, *a: {"held-out fit": f"{f:.1f} %"})
    try:
        choice = choose_nonlinearities(data, fit, sides,
                                       None if cb is None else (lambda i, f: cb(i, f, 0.0, 0.0,
                                                                                0.0)))
    finally:
        close()
    model = estimate(data, *pick(choice.kind), progress)
    model.info["nonlinearity_choice"] = choice.as_dict()
    return model
