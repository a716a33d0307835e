"""The monomial degree of a polynomial nonlinear state-space model, chosen on held-out blocks.

Cubic monomials fit the estimation record better than quadratic ones almost always; on
records whose validation part moves into other operating ranges they are also the terms that
run away. Measured with ``pnlss(data, 2)`` on 16 real records (process, thermal, power
electronics, servo and the Silverbox, Wiener-Hammerstein, cascaded-tanks and EMPS
benchmarks; script outside the project), the validation simulation fit of degrees 2-3
against its linear start (``ssest``, simulation focus) was far below it on six: the thermal
wall -415 % (linear 72 %), the gas furnace -437 % (45 %), the winding record diverged
(54 %), the heating system 10 % (67 %), the buck converter -201 % (52 %) and the cascaded
tanks -281 % (72 %); quadratic monomials alone gave 83, 46, 70, 78, -13 and 82 % there, but
96 % instead of 99.6 % on the Silverbox, whose nonlinearity is cubic. No single degree is
right for every record; what an engineer checks is how the candidates simulate data they
were not fitted on, without touching the validation data.

So ``degree="auto"`` fits each candidate (degrees 2, then 2-3) on the estimation record less
one of its contiguous blocks (:func:`sysid.validation.crossval.record_folds`) and simulates
it on the block left out (:func:`sysid.compare`, initial state estimated; a block's fit
clipped at -100 %: one runaway block must not decide alone). The larger degree is taken only
where the blocks insist on it (``insists``: its paired gain over the smaller exceeds
twice its standard error, and its median is higher;
:func:`sysid.validation.crossval.insists`). Weighed on 29 record/split pairs (the 16
records, the reversed splits of ``benches/realdata.py`` where they have one, the ball and
beam and DaISy dryer2), validation fits clipped at -100 % and summed:

- degrees 2-3 always (the old default): 439.5;
- degree 2 always: 1702.6;
- the better median held-out fit, the smaller degree within
  :func:`~sysid.validation.crossval.slack` (this module's first rule): 1518.5. It took the
  cubic terms wherever they scored a little higher on the blocks and lost 3.6 to 60 points
  on the heating system and the reversed CSTR, DC-motor and MR-damper splits;
- this rule: 1707.1, the cubic terms taken on the Silverbox and the Wiener-Hammerstein
  record only (99.6 % against 95.5 %, 72.2 % against 71.8 %).

A larger degree is fitted on the blocks only where the record gives at least
:data:`PER_PARAMETER` residuals (samples times outputs) per parameter of its model. Below
that its fold fits fit the noise: on the warning audit's clean single-input records of
order 5-6 (2 000-4 600 samples, degrees 2-3 with 504-840 parameters) each crawled to its
100-iteration cap (the Gauss-Newton model still expecting decreases far above its noise
level), the choice took 24-147 s, and degree 2 was chosen every time. Leaving those fits
out changes no choice the blocks made on the 16 such records (16 of 16 the same model,
58.7 s against 417.7 s in all) and none of the 29 pairs below, where only the Silverbox and
the Wiener-Hammerstein record, with thousands of samples per parameter, took the cubic
terms. ``DegreeChoice.untried`` and the reason say when a degree was left out.

The linear start of each fold is scored on the same blocks, and ``pnlss`` warns when it
insists over the chosen degree there. Over the 29 pairs that warned on three: the reversed
gas furnace and dryer2, where the linear model validates better (82.1 % against 77.4 %,
-47 % against -510 %), and the heating system, where it does not (66.9 % against 77.7 %); it
did not warn on the reversed heating system and the ball and beam, where the linear model
validates better (89.9 % against 32.1 %, 33.6 % against -47.8 %). A warning on the median
alone would have caught those and added two false ones. Table: ``docs/nlss.md``, "Which
degree?".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import InsufficientDataError
from ..validation.crossval import held_out_folds, insists

__all__ = ["CANDIDATES", "PER_PARAMETER", "DegreeChoice", "choose_degree", "insists",
           "too_large"]

#: the degrees ``degree="auto"`` tries (each an integer ``d``: all degrees ``2..d``)
CANDIDATES = (2, 3)
#: a held-out block's fit counts at least this much (a runaway block is one bad block)
FLOOR = -100.0
#: a larger degree is tried only where the record gives at least this many residuals
#: (samples times outputs) per parameter of its model
PER_PARAMETER = 10


@dataclass
class DegreeChoice:
    """The automatic degree, the held-out table it was read from, and why.

    Attributes
    ----------
    degree : int
        All monomial degrees ``2..degree``.
    table : dict
        ``{degree: median held-out simulation fit %}``, and ``"linear"``: the folds' linear
        starts on the same blocks.
    folds : dict
        Each candidate's per-block fits (clipped at -100 %).
    reason : str
    untried : dict
        ``{degree: parameters}`` of the candidates not fitted: too many parameters for the
        record (fewer than :data:`PER_PARAMETER` residuals each).
    """

    degree: int
    table: dict[Any, float] = field(default_factory=dict)
    folds: dict[Any, list[float]] = field(default_factory=dict)
    reason: str = ""
    untried: dict[int, int] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """A plain-dict copy, for a model's ``info``."""
        return {"degree": self.degree, "table": dict(self.table),
                "folds": {k: list(v) for k, v in self.folds.items()}, "reason": self.reason,
                "untried": dict(self.untried)}


#: what the user can do when the blocks cast doubt on the chosen degree's nonlinear terms
ADVICE = ("check the model on validation data before trusting its nonlinear terms, or use the "
          "linear model, fewer terms or a lower order")


def caution(choice: DegreeChoice) -> str | None:
    """What the held-out blocks say against the chosen degree, or ``None``: its linear start
    simulates them better (it insists, as a larger degree must to be taken), or the chosen
    model ran away (its fit at :data:`FLOOR`) on some blocks where the linear start did not.
    The median that chose the degree passes over up to half the blocks, and a model that
    diverges on a part of its own record is likely to diverge on other data (a sulfur recovery
    unit's five flows: degree 2 chosen at a median of 52.6 % against the linear start's
    36.2 %, at the floor on two of five blocks; validation -71 % against the linear start's
    39 %).

    Examples
    --------
    >>> from sysid.nlss.degree import DegreeChoice, caution
    >>> c = DegreeChoice(2, {2: 52.6, "linear": 36.2},
    ...                  {2: [-100.0, -100.0, 52.6, 54.9, 55.5], "linear": [36, 35, 41, 31, 39]})
    >>> caution(c)[:60]
    'the chosen model (degrees 2) ran away on 2 of the 5 blocks o'
    >>> caution(DegreeChoice(2, {}, {2: [50.0, 60.0], "linear": [40.0, 45.0]})) is None
    True
    """
    mine, lin = choice.folds.get(choice.degree), choice.folds.get("linear")
    if not mine or not lin:
        return None
    t = choice.table
    if insists(lin, mine):
        return (f"on blocks of this record held out of the fit its linear start simulates "
                f"better than the nonlinear model (median {t['linear']:.1f} % against "
                f"{t[choice.degree]:.1f} %; info['degree_choice']): {ADVICE}")
    bad = sum(1 for a, b in zip(mine, lin) if a <= FLOOR < b)
    if not bad:
        return None
    return (f"the chosen model (degrees {_degrees(choice.degree)}) ran away on {bad} of the "
            f"{len(mine)} blocks of this record held out of its fit (simulation fit at "
            f"{FLOOR:.0f} % or below), where its linear start did not (median "
            f"{t['linear']:.1f} %; info['degree_choice']): {ADVICE}")


def _degrees(k: int) -> str:
    """How a candidate ``k`` (all degrees ``2..k``) is named: ``"2"``, ``"2-3"``."""
    return "2" if k == 2 else f"2-{k}"


def too_large(data: IOData, size: Callable[[int], int]) -> dict[int, int]:
    """``{degree: parameters}`` of the candidates above the smallest that the record cannot
    judge: fewer than :data:`PER_PARAMETER` residuals (samples times outputs) per parameter
    of their model (``size(degree)``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.nlss.degree import too_large
    >>> d = sysid.IOData(u=np.zeros((1000, 1)), y=np.zeros((1000, 1)))
    >>> too_large(d, {2: 30, 3: 140}.get)
    {3: 140}
    """
    residuals = sum(data.lengths) * data.n_outputs
    sizes = {k: size(k) for k in CANDIDATES[1:]}
    return {k: p for k, p in sizes.items() if p * PER_PARAMETER > residuals}


def choose_degree(data: IOData, fit: Callable[[IOData, int, Any], Any],
                  linear: Callable[[IOData], Any] | None = None,
                  tick: Callable[[int, float], Any] | None = None,
                  size: Callable[[int], int] | None = None) -> DegreeChoice:
    """Choose among :data:`CANDIDATES` by held-out simulation fit.

    Parameters
    ----------
    data : IOData
        The estimation record.
    fit : callable
        ``fit(part, degree, start)`` returns the model of that degree fitted on ``part``
        from ``start``, the linear start ``linear`` fitted on that part (``None`` without
        ``linear`` or when it failed): each part's start is fitted once.
    linear : callable, optional
        ``linear(part)`` returns the linear start fitted on ``part`` (scored, not chosen).
    tick : callable, optional
        ``tick(count, fit)`` after each fold's fit (progress).
    size : callable, optional
        ``size(degree)``: the parameters of that degree's model. The candidates of
        :func:`too_large` are not fitted (``DegreeChoice.untried``).

    Returns
    -------
    DegreeChoice

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.nlss.degree import choose_degree
    >>> u = np.random.default_rng(0).standard_normal((400, 1))
    >>> y = np.convolve(u[:, 0], [0, 1.0, 0.5])[:400, None]
    >>> d = sysid.IOData(u, y)
    >>> c = choose_degree(d, lambda part, k, start: sysid.pnlss(part, 2, degree=k,
    ...                                                         progress=False, max_iter=5))
    >>> c.degree
    2
    """
    from ..validation.crossval import MIN_BLOCK, record_folds

    n = sum(data.lengths)
    pairs = record_folds(data) if n >= 2 * MIN_BLOCK else []
    if len(pairs) < 2:
        raise InsufficientDataError(
            f"the record is too short to choose the degree on held-out blocks ({n} samples; "
            f"two blocks of {MIN_BLOCK} need {2 * MIN_BLOCK}): give degree= to fit one model")
    residuals = n * data.n_outputs
    untried = {} if size is None else too_large(data, size)
    tried = [k for k in CANDIDATES if k not in untried]
    cands: list[Any] = tried + (["linear"] if linear is not None else [])

    def one(part: IOData, k: Any, fitted: dict[Any, Any]) -> Any:
        if k == "linear":
            return None if linear is None else linear(part)
        return fit(part, int(k), fitted.get("linear"))

    # the linear start first: every degree starts from it
    scored, failed = held_out_folds(pairs, cands[::-1], one, tick, FLOOR)
    folds = {k: scored[k] for k in cands}
    if all(len(failed[k]) == len(pairs) for k in tried):
        # no degree fits any part: the settings, not the blocks, are wrong
        raise failed[tried[-1]][0]
    table = {k: float(np.median(v)) for k, v in folds.items()}
    degree = tried[0]
    for k in tried[1:]:  # a larger degree only where the blocks insist on it
        if insists(folds[k], folds[degree]):
            degree = k
    reason = (f"held-out simulation fit {table[degree]:.1f} % with degrees "
              f"{_degrees(degree)} (median over {len(pairs)} blocks; "
              + ", ".join(f"degrees {_degrees(k)}: {table[k]:.1f} %" for k in tried)
              + (f"; the linear start: {table['linear']:.1f} %" if linear is not None else "")
              + ")")
    if degree == tried[0] and max(table[k] for k in tried) > table[degree]:
        reason += ("; the larger degree's gain is within twice the standard error of the "
                   "blocks' differences")
    for k, p in untried.items():
        reason += (f"; degrees {_degrees(k)} not tried: {p} parameters for {residuals} "
                   f"residuals (fewer than {PER_PARAMETER} each)")
    return DegreeChoice(degree, table, folds, reason, untried)
