"""The model structure of a Hammerstein-Wiener or NARX model, chosen on held-out blocks.

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

``nlarx``'s polynomial terms are chosen the same way (``basis="auto"``, its default). FROLS
picks them by their one-step error; run free, the model they make can do far worse than the
linear ARX model of the same lags: the EMPS servo -78 % against 84 %, the reversed thermal
wall below -100 % against 14 %. On the same 29 pairs (``nlarx(data, 2, 2)``; script outside
the project) the summed validation fit is 638 with the degree-2 polynomial always, 563 with
the linear ARX model always, and 1016 when the polynomial is taken only where the held-out
blocks insist on it over the linear model (9 of 29: the DC motor 45.5 -> 90.3 %, the CSTR
-100 -> 98.1 %); where not taken, the largest losses were the exchanger (-25 points) and the
reversed heating system (-17).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..data.iodata import IOData
from .hw_model import SigmoidNetwork

__all__ = ["AUTO", "UNITS", "StructureChoice", "choose_nonlinearities", "choose_structure",
           "is_auto"]

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
class StructureChoice:
    """The model structure ``"auto"`` chose, the held-out table it read and why.

    Attributes
    ----------
    kind : str
        The simpler candidate (``"identity"`` nonlinearities, a ``"linear"`` NARX model) or
        the richer one (``"sigmoid"`` networks of :data:`UNITS` units on every channel of
        each side given as ``"auto"``, ``"polynomial"`` terms of degree 2).
    table : dict
        ``{kind: median held-out simulation fit %}``.
    folds : dict
        Each candidate's per-block fits (at least -100 %).
    reason : str
    extra : dict
        What else the estimator records (``nlhw``: the ``sides`` chosen).
    """

    kind: str
    table: dict[str, float] = field(default_factory=dict)
    folds: dict[str, list[float]] = field(default_factory=dict)
    reason: str = ""
    extra: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """A plain-dict copy, for a model's ``info``."""
        return {"kind": self.kind, **self.extra, "table": dict(self.table),
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


def choose_structure(data: IOData, fit: Callable[[IOData, str], Any],
                     kinds: tuple[str, str], names: dict[str, str], where: str,
                     tick: Callable[[int, float], Any] | None = None) -> StructureChoice:
    """Choose the simpler of ``kinds`` or the richer, the richer only where the record's
    held-out blocks insist on it (:func:`sysid.validation.crossval.insists`).

    Parameters
    ----------
    data : IOData
        The estimation record.
    fit : callable
        ``fit(part, kind)`` returns candidate ``kind`` fitted on ``part``.
    kinds : (str, str)
        The simpler candidate, then the richer.
    names : dict
        ``{kind: what the reason calls it}``.
    where : str
        Where the choice applies, for the reason (``" on the output side"``).
    tick : callable, optional
        ``tick(count, fit)`` after each fold's fit (progress).

    Returns
    -------
    StructureChoice

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.nonlinear.choice import choose_structure
    >>> u = np.random.default_rng(0).uniform(-1, 1, (400, 1))
    >>> y = np.convolve(u[:, 0], [0, 1.0, 0.5])[:400, None]  # linear: no network insists
    >>> c = choose_structure(sysid.IOData(u, y), lambda part, kind: sysid.nlhw_ss(
    ...     part, 2, input_nl=None, progress=False,
    ...     output_nl=None if kind == "identity" else sysid.SigmoidNetwork(3)),
    ...     ("identity", "sigmoid"), {"identity": "the identity", "sigmoid": "networks"},
    ...     " on the output side")
    >>> c.kind
    'identity'
    """
    from ..validation.crossval import MIN_BLOCK, held_out_folds, insists, record_folds

    simple, rich = kinds
    n = sum(data.lengths)
    pairs = record_folds(data) if n >= 2 * MIN_BLOCK else []
    if len(pairs) < 2:
        return StructureChoice(simple, reason=(
            f"{names[simple]}{where}: the record ({n} samples) is too short to choose on "
            f"held-out blocks (two of {MIN_BLOCK} samples); give the model structure to fit "
            "it"))
    folds, failed = held_out_folds(pairs, kinds, lambda part, k, _: fit(part, k), tick, FLOOR)
    if all(len(failed[k]) == len(pairs) for k in kinds):
        # no candidate fits any part (the settings, or parts too short for them): the fit
        # on the whole record says which
        return StructureChoice(simple, folds=folds, reason=(
            f"{names[simple]}{where}: no candidate could be fitted on the record's parts "
            f"({failed[simple][0]})"))
    table = {k: float(np.median(v)) for k, v in folds.items()}
    kind = rich if insists(folds[rich], folds[simple]) else simple
    reason = (f"{names[kind]}{where}: held-out simulation fit {table[kind]:.1f} % (median "
              f"over {len(pairs)} blocks; {names[simple]} {table[simple]:.1f} %, "
              f"{names[rich]} {table[rich]:.1f} %)")
    if kind == simple and table[rich] > table[simple]:
        reason += (f"; the gain of {names[rich]} is within twice the standard error of the "
                   "blocks' differences")
    return StructureChoice(kind, table, folds, reason)


def choose_nonlinearities(data: IOData, fit: Callable[[IOData, str], Any],
                          sides: tuple[str, ...],
                          tick: Callable[[int, float], Any] | None = None
                          ) -> StructureChoice:
    """:func:`choose_structure` of the identity against sigmoid networks on the ``"auto"``
    ``sides`` of a Hammerstein-Wiener model (``fit(part, kind)`` with :func:`candidate`'s
    nonlinearities); ``extra["sides"]`` lists them."""
    where = " on the " + " and ".join(sides) + (" sides" if len(sides) > 1 else " side")
    choice = choose_structure(data, fit, ("identity", "sigmoid"),
                              {"identity": "the identity",
                               "sigmoid": f"sigmoid networks of {UNITS} units"}, where, tick)
    choice.extra["sides"] = list(sides)
    return choice


def auto_fit(data: Any, estimate: Callable[[IOData, Any, Any, Any], Any], input_nl: Any,
             output_nl: Any, channels: tuple[int, int], progress: Any, label: str) -> Any:
    """``estimate(data, input_nl, output_nl, progress)`` (``data`` checked to be a record by
    the caller) with the ``"auto"`` sides chosen
    by :func:`choose_nonlinearities` (a bar over the fold fits; a progress callable follows
    the final fit only), the choice in ``info["nonlinearity_choice"]``. ``channels``: the
    inputs and outputs a side's list needs (0: a single nonlinearity)."""
    from .._progress import iteration_callback
    from ..validation.crossval import fold_count

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
