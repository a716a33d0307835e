"""Notes :func:`sysid.identify` adds to its checks about the model it chose: an order the
input's excitation does not determine (``checks["order_excitation"]``), a drift the input
does not explain (``checks["trend"]``), a mode that does not decay over the record
(``checks["persistent_mode"]``), a model that explains less than half of what the
outputs do on the held-out blocks (``checks["weak"]``), and a final re-fit stopped at its
iteration cap (``checks["final_refit"]``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import PERSISTENT_DECAY, mode_kept
from .._display import modulus
from ..data.iodata import IOData
from ..models.continuous import ContinuousStateSpace
from ..validation.crossval import insists, trend_share

__all__ = ["excitation_check", "excitation_count", "order_excitation_check",
           "undetermined_orders", "trend_check",
           "integrates_within", "persistent_mode_check", "weak_check", "refit_cap_check",
           "loop_checks", "loop_feedthrough_check", "loop_bias_check", "TREND_SHARE",
           "TREND_OUTPUT", "PERSISTENT_DECAY", "WEAK_FIT", "EXCITATION_CAP", "LONG_GAP",
           "whole_record_check"]

#: a held-out fit below this (in %) explains less than half of the outputs' variation
#: (``fit = 100 (1 - sqrt(1 - explained))``): ``checks["weak"]`` says so
WEAK_FIT = 100.0 * (1.0 - np.sqrt(0.5))

#: fit points by which the chosen model's simulation of the whole estimation record may fall
#: below its held-out fit before ``checks["whole_record"]`` says so (the trimmed, pooled
#: held-out score and the whole record's fit differ by a few points on most records)
LONG_GAP = 10.0

#: a straight line that takes out this share of the chosen model's simulation errors on some
#: output is noted (``checks["trend"]``): a fifth of the error is a drift the model misses
TREND_SHARE = 0.2
#: ... and at least this share of the output's own variation (a drift that small next to
#: what the output does is not worth a note, however much of a tiny error it is)
TREND_OUTPUT = 0.01


#: the largest persistent-excitation order ``checks["excitation"]`` counts to ("order >= 40")
EXCITATION_CAP = 40


def excitation_count(data: IOData, cols: list[int], cap: int = EXCITATION_CAP) -> int:
    """The spectral persistent-excitation order (:func:`sysid.persistent_excitation_order`, at
    most ``cap``) of the inputs ``cols`` of ``data``, its experiments counted separately."""
    from ..data.input_design import persistent_excitation_order

    us = [e[0][:, cols] for e in data.experiments]
    return int(persistent_excitation_order(us if len(us) > 1 else us[0], cap))


def excitation_check(data: IOData) -> tuple[str, int | None]:
    """``checks["excitation"]``: the order of persistent excitation of the inputs (the
    spectral count, :func:`excitation_count`), and the inputs that change at a few samples
    only (:func:`sysid.subspace.steptest.stepped_inputs`): a step's spectrum is its edges',
    so the count speaks for the other inputs only (a pulse beside a ramped input read "order
    >= 40" for both). Returned with the count of every input, for
    :func:`order_excitation_check` (``None`` when some input is stepped).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.notes import excitation_check
    >>> u = np.c_[np.random.default_rng(0).standard_normal(300), np.r_[np.zeros(100),
    ...                                                              np.ones(200)]]
    >>> text, count = excitation_check(sysid.IOData(u, np.zeros((300, 1)), 1.0))
    >>> text[:46], count
    ('input(s) u1 change only a few times (u1 at sam', None)
    """
    from ..subspace.steptest import stepped_inputs

    def order(pe: int) -> str:
        return f"{'>= ' if pe == EXCITATION_CAP else ''}{pe}"
    stepped = stepped_inputs(data)
    rest = [j for j, n in enumerate(data.input_names) if n not in stepped]
    if not stepped:
        pe = excitation_count(data, rest)
        return f"input persistently exciting of order {order(pe)}", pe
    said = "; ".join(f"{n} at sample(s) {', '.join(map(str, c))}" for n, c in stepped.items())
    return (f"input(s) {', '.join(stepped)} change only a few times ({said}): steps or "
            "pulses, whose responses alone determine their paths"
            + (f"; the other input(s) persistently exciting of order "
               f"{order(excitation_count(data, rest))}" if rest else "")), None


def _counted_to(data: IOData, counted: int, need: int) -> int:
    """The spectral count ``counted``, counted again up to ``need`` when it stopped at its
    cap below that."""
    if counted == EXCITATION_CAP < need:
        return excitation_count(data, list(range(data.n_inputs)), need)
    return counted


def order_excitation_check(order: int, data: IOData, checks: dict[str, Any],
                           counted: int | None) -> None:
    """``checks["order_excitation"]`` and an :class:`~sysid.ExcitationWarning` when the chosen
    model's ``order`` needs an input persistently exciting of order ``2 order`` and the
    input's spectral count ``counted`` (:func:`excitation_check`'s; counted again only past
    its cap) is less, as every estimator warns of its own fit: between the input's excited
    frequencies the model's response is then set by the noise, not by the input (a shaker's
    three tones, order 6, chose order 11: held out 80.9 %, 49.6 % on another test of the
    same tones). ``counted=None`` (an input stepped a few times, or no count): no note.

    Examples
    --------
    >>> import numpy as np, sysid, warnings
    >>> from sysid.identify.notes import excitation_check, order_excitation_check
    >>> u = np.sin(0.3 * np.arange(500))          # one sinusoid: order 2
    >>> d = sysid.IOData(u, u, 1.0)
    >>> checks = {}
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     order_excitation_check(3, d, checks, excitation_check(d)[1])
    >>> checks["order_excitation"][:52]
    'the chosen order 3 needs an input persistently excit'
    """
    from .._checks import user_stacklevel
    from ..data.input_design import warn_excitation

    if counted is None or data.n_inputs == 0:
        return
    got = _counted_to(data, counted, 2 * order)
    if got >= 2 * order:
        return
    checks["order_excitation"] = (
        f"the chosen order {order} needs an input persistently exciting of order "
        f"{2 * order}, and the input is of order {got}: between its excited frequencies the "
        f"model's response is set by the noise, not by the input, and the held-out blocks "
        f"(the same input) cannot tell; validate it on a record of another input, or fit "
        f"order {max(1, got // 2)} (sysid.ssest(data, {max(1, got // 2)}, "
        f"focus='simulation'))")
    warn_excitation(got, order, stacklevel=user_stacklevel())


def undetermined_orders(board: Any, data: IOData, counted: int | None) -> str | None:
    """Set aside, before the choice, the candidates whose order the input's excitation does
    not determine (an order ``n`` needs an input persistently exciting of order ``2 n``;
    ``counted``: :func:`excitation_check`'s spectral count), when some candidate the choice
    can take has an order it does determine; returns what was done, or ``None``.

    The held-out blocks cannot rank those orders: every block carries the same input, so
    between its excited frequencies their responses are set by the noise, and they score
    on the blocks like the determined ones, a little higher by chance (a servo swinging a
    pendulum through a sum of sines, order 7: order 9 held out 78.5 % against 77.8 % for
    order 3, and validated at -347 % on a chirp; a shaker's three tones, order 6: order 11
    held out 80.9 %, 49.6 % on another test of the same tones). A higher order stays a
    candidate where the blocks insist on it over the best determined one
    (:func:`~sysid.validation.crossval.insists`, as ``pnlss`` takes a larger degree): its
    transients and harmonics can show what the input's lines do not (a loudspeaker driven
    by one sine, order 2: order 3 held out 98.9 % against 95.7 % for order 1, and
    validated at 93.9 % against 91.5 % on another amplitude). A set-aside row keeps its
    score on the board, with a note. ``counted=None`` (a stepped input, whose spectral count
    says nothing of the model's order): nothing is set aside.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.board import Board
    >>> from sysid.identify.notes import undetermined_orders
    >>> b = Board.__new__(Board)
    >>> b.rows = [{"order": o, "held_out_fit": f, "fold_fits": ff, "stable": True, "note": ""}
    ...           for o, f, ff in ((9, 78.5, [80, 75, 79]), (3, 77.8, [79, 76, 78]))]
    >>> u = np.random.default_rng(0).standard_normal(600)
    >>> print(undetermined_orders(b, sysid.IOData(u, u, 1.0), 6)[:60])  # order 6 counted
    1 candidate(s) of order above 3 set aside before the choice:
    >>> [r.get("undetermined", False) for r in b.rows]
    [True, False]
    """
    if counted is None or data.n_inputs == 0:
        return None
    got = _counted_to(data, counted, 2 * max((r["order"] for r in board.rows), default=0))
    keep = got // 2
    # (eligible before the flag: scored, not below its start, stable)
    fine = [r for r in board.rows if r["order"] <= keep and board.eligible(r)]
    if not fine:
        return None  # none the choice could take instead: the note on the choice says so
    ref = max(fine, key=lambda r: r["held_out_fit"])["fold_fits"]
    over = [r for r in board.rows if r["order"] > keep and not (
        len(r.get("fold_fits") or []) == len(ref) and insists(r["fold_fits"], ref))]
    if not over:
        return None
    for r in over:
        r["undetermined"] = True
        r["note"] = ((r["note"] + "; ") if r["note"] else "") + (
            f"order not determined by the input (persistently exciting of order {got}): "
            "not chosen")
    return (f"{len(over)} candidate(s) of order above {keep} set aside before the choice: "
            f"the input is persistently exciting of order {got}, which determines models "
            f"of order {keep} at most; the held-out blocks (the same input) cannot rank "
            f"higher orders, whose responses between the excited frequencies are set by the "
            f"noise, unless they insist on one over the best of order {keep} at most (by more "
            f"than twice the standard error of their block-by-block differences)")


def trend_check(model: Any, data: IOData, checks: dict[str, Any]) -> None:
    """``checks["trend"]`` when, for some output, a straight line takes out at least
    ``TREND_SHARE`` of the chosen model's simulation errors on the record and at least
    ``TREND_OUTPUT`` of the output's variation: the output drifts in a way the input does not
    explain, the model cannot follow it, and that matters next to the output's movements."""
    try:
        of_errors, of_output = trend_share(model, data)
    except Exception:  # noqa: BLE001 - a model that cannot be simulated has no share to note
        return
    hit = (of_errors >= TREND_SHARE) & (of_output >= TREND_OUTPUT)
    if not hit.any():
        return
    k = int(np.argmax(np.where(hit, of_output, -1.0)))
    checks["trend"] = (
        f"the record drifts in a way the input does not explain: on {data.output_names[k]} a "
        f"straight line takes out {100 * of_errors[k]:.0f} % of the chosen model's simulation "
        f"errors ({100 * of_output[k]:.1f} % of the output's variation); if the drift is not "
        f"the plant's response (a sensor drift, a slow disturbance), remove it first "
        f"(sysid.detrend(data, 'linear')) and identify again")


def integrates_within(model: Any, data: IOData) -> bool:
    """Whether a pole of the stable discrete-time ``model`` keeps more than
    ``PERSISTENT_DECAY`` of its mode over the longest experiment of ``data`` while turning
    less than once there: within the record it acts as an integrator, and how far inside
    the unit circle it sits is not determined by the data (:func:`persistent_mode_check`).
    An integrator made explicit (``info["integrating"]``) is not such a pole.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.notes import integrates_within
    >>> d = sysid.IOData(u=np.ones(1000), y=np.arange(1000.0))
    >>> [integrates_within(sysid.StateSpaceModel([[p]], [[1.0]], [[1.0]]), d)
    ...  for p in (1 - 1e-8, 0.9)]
    [True, False]
    """
    poles = _discrete_poles(model)
    if poles is None or not 0.0 < float(np.max(np.abs(poles))) < 1.0:
        return False
    n = max(data.lengths)
    kept = np.array([mode_kept(float(abs(z)), n) for z in poles])
    turns = np.abs(np.angle(poles)) * n / (2 * np.pi)
    return bool(np.any((kept > PERSISTENT_DECAY) & (turns < 1.0)))


def _discrete_poles(model: Any) -> np.ndarray | None:
    """The poles of a discrete-time model, or None (continuous time, an explicit
    integrator, no poles, or none to be had)."""
    if isinstance(model, ContinuousStateSpace) or not hasattr(model, "poles") or (
            (getattr(model, "info", None) or {}).get("integrating")):
        return None
    try:
        poles = np.asarray(model.poles())
    except Exception:  # noqa: BLE001 - a model without poles has no mode to note
        return None
    return poles if poles.size else None


def persistent_mode_check(model: Any, data: IOData, checks: dict[str, Any]) -> None:
    """``checks["persistent_mode"]`` when a pole of the chosen (stable) discrete-time model
    decays by less than ``1 - PERSISTENT_DECAY`` over the longest experiment. How far inside
    the unit circle it sits (often just where the stability bound of the search held it) is
    then not determined by the data. A real pole, or one turning less than once over the
    record, acts there as an integrator: the static gain and the step response's final value
    grow as ``1 / (1 - |p|)``. A pair turning more often is an undamped oscillation: its
    damping and the height of its resonance peak are what the data leave open (its static
    gain is set by ``|1 - p|``, not by ``1 - |p|``), and the advice is not a drift's.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.notes import persistent_mode_check
    >>> m = sysid.StateSpaceModel([[1 - 1e-8]], [[1.0]], [[1.0]])
    >>> d = sysid.IOData(u=np.ones(1000), y=np.arange(1000.0))
    >>> checks = {}
    >>> persistent_mode_check(m, d, checks)
    >>> checks["persistent_mode"][:40]
    'a pole of modulus 1 - 1e-08 keeps 100 % '
    >>> r, a = 1 - 1e-8, 0.3  # modulus and angle: an undamped oscillation of period 21 samples
    >>> A = r * np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    >>> m = sysid.StateSpaceModel(A, [[1.0], [0.0]], [[1.0, 0.0]])
    >>> persistent_mode_check(m, d, checks)
    >>> "undamped oscillation of period 20.9 samples" in checks["persistent_mode"]
    True
    """
    poles = _discrete_poles(model)  # (an integrator made explicit: checks["integrating"])
    if poles is None:
        return
    rho = float(np.max(np.abs(poles)))
    n = max(data.lengths)
    if not 0.0 < rho < 1.0:
        return  # an unstable model is warned about where it is chosen
    kept = np.array([mode_kept(float(abs(z)), n) for z in poles])
    persistent = kept > PERSISTENT_DECAY
    if not persistent.any():
        return
    # turns over the record: below one the mode cannot be told from an integrator there
    turns = np.abs(np.angle(poles)) * n / (2 * np.pi)
    slow = persistent & (turns < 1.0)
    k = int(np.argmax(np.where(slow if slow.any() else persistent, kept, -1.0)))
    z = complex(poles[k])
    shown = f"1 - {1.0 - abs(z):.2g}" if abs(z) > 0.999 else modulus(abs(z))
    if slow.any():
        checks["persistent_mode"] = (
            f"a pole of modulus {shown} keeps {100 * kept[k]:.0f} % of its mode over the "
            f"record ({n} samples): within the record it acts as an integrator, and the data "
            f"do not say how far inside the unit circle it is (nor the static gain and the "
            f"step response's final value, which grow as 1 / (1 - |p|)); read the model's "
            f"response within the record's time span only. If the plant integrates, say so "
            f"in the structure (identify the differenced output, or enforce_stability=False); "
            f"if it does not, look for a drift in the output (sysid.detrend(data, 'linear'))")
        return
    period = 2 * np.pi / abs(float(np.angle(z)))
    what = "a pair of poles" if z.imag != 0.0 else "a pole"  # a real one: at -1
    checks["persistent_mode"] = (
        f"{what} of modulus {shown} keeps {100 * kept[k]:.0f} % of its mode over "
        f"the record ({n} samples): within the record it is an undamped oscillation of "
        f"period {period:.3g} samples, and the data do not say how far inside the unit circle "
        f"it is (nor its damping, nor the height of its resonance peak, which grows as "
        f"1 / (1 - |p|)); read the model's response within the record's time span only. Such "
        f"a pair often sits where the search's stability bound held it: if the plant is "
        f"lightly damped, a record in which its oscillations visibly decay (a longer one, or "
        f"a free decay) sets the damping; if it is not, look for a periodic disturbance in "
        f"the output (sysid.spectra(data)) or an order higher than the data support")


def weak_check(held_out_fit: float, checks: dict[str, Any]) -> None:
    """``checks["weak"]`` when the chosen model's held-out fit is below ``WEAK_FIT``: on data it
    was not fitted to, it explains less than half of the outputs' variation (``1 - (1 - fit /
    100)^2``). Most of what the outputs do is then not the input's doing (disturbances, a drift,
    an input not recorded, a nonlinearity), and a simulation of other data excited alike will be
    no better (one whose input moves the outputs more can be: a four-tank record held out at
    28.8 % validated at 55.3 % on another run): the note says so instead of letting the best of
    poor models pass as a model.

    Examples
    --------
    >>> from sysid.identify.notes import weak_check
    >>> checks = {}
    >>> weak_check(15.4, checks)
    >>> checks["weak"][:60]
    'the chosen model simulates the held-out blocks at 15.4 % fit'
    >>> weak_check(60.0, {})  # explains 84 %: no note
    """
    if not np.isfinite(held_out_fit) or held_out_fit >= WEAK_FIT:
        return
    explained = max(0.0, 1.0 - (1.0 - held_out_fit / 100.0) ** 2)
    checks["weak"] = (
        f"the chosen model simulates the held-out blocks at {held_out_fit:.1f} % fit: it "
        f"explains about {100 * explained:.0f} % of the outputs' variation there, so most of what "
        f"they do is not driven by the input as recorded (disturbances, a drift, an input "
        f"not in the record, a nonlinearity); expect no better on data excited alike (a "
        f"record whose input moves the outputs more can fit better): check the "
        f"record and its channels, add the missing inputs, or model the disturbance "
        f"(sysid.ssest(data, focus='prediction')) if prediction is what you need")


def whole_record_check(model: Any, data: IOData, held_out_fit: float, block: int,
                       checks: dict[str, Any]) -> None:
    """``checks["whole_record"]`` when the chosen (stable) model simulates the whole
    estimation record ``data`` (initial state and output offsets fitted, as on a block) more
    than :data:`LONG_GAP` fit points below ``held_out_fit`` (identify passes the lower of
    its held-out score and its blocks pooled without leaving out the extremes,
    :meth:`.board.Board.lower_score`: a gap that only the left-out worst block explains is
    not one of length). Each held-out block (``block`` samples, the shortest) is simulated
    from an initial state fitted to it, so an error that builds up over longer stretches
    does not show there: a slow mode that stands in for an integrator, a drift. On a
    hovercraft's yaw (an integrator) the model chosen at 96.4 % held out (95.9 % over every
    block) simulates its own record at 78.6 % and validates on another run at -136 %. Over
    the 80 real records at hand the note fires on four (the hovercraft, a ship's heading, a
    propeller-driven arm, a human operator's tracking), each of which validates 14-233
    points below its held-out fit and nearer the whole record's figure; it is silent on the
    other 76. An unstable model is left to its own warning.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.identify.notes import whole_record_check
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((3000, 1)) + 0.3  # a biased input drives an integrator
    >>> y = np.cumsum(u, axis=0) * 0.01
    >>> d = sysid.IOData(u=u - u.mean(0), y=y - y.mean(0))
    >>> slow = sysid.StateSpaceModel([[0.98]], [[0.01]], [[1.0]])  # a slow pole in its place
    >>> checks = {}
    >>> whole_record_check(slow, d, 95.0, 600, checks)
    >>> checks["whole_record"][:56]
    'the chosen model simulates the whole estimation record a'
    >>> y_slow = slow.simulate(u - u.mean(0))  # a record the slow pole does explain
    >>> checks = {}
    >>> whole_record_check(slow, sysid.IOData(u=u - u.mean(0), y=y_slow), 95.0, 600, checks)
    >>> "whole_record" in checks
    False
    """
    from ..validation.crossval import simulation_fit
    from .board import unstable

    if not np.isfinite(held_out_fit) or unstable(model):
        return
    whole = simulation_fit(model, data)
    if not whole < held_out_fit - LONG_GAP:
        return
    checks["whole_record"] = (
        f"the chosen model simulates the whole estimation record at {whole:.1f} % fit "
        f"(initial state and output offsets fitted), {held_out_fit - whole:.1f} points below "
        f"its fit on the held-out blocks ({held_out_fit:.1f} %): each block ({block} samples or "
        f"more) is simulated from an initial state fitted to it, so an error that builds up "
        f"over longer stretches does not show there (a slow mode standing in for an "
        f"integrator, a drift the model follows only for a while). Data longer than a block "
        f"may fit nearer {whole:.0f} % than {held_out_fit:.0f} %: validate on a long record "
        f"(sysid.compare)" + ("" if (getattr(model, "info", None) or {}).get("integrating")
                              else ", and if an output integrates (a position, an angle, a "
                              "level), fit its increments (sysid.IOData(u=u[:-1], "
                              "y=np.diff(y, axis=0)))"))


def refit_cap_check(model: Any, checks: dict[str, Any]) -> None:
    """``checks["final_refit"]`` when the chosen refinement's re-fit on the whole record
    stopped at its iteration cap (``info["pem"]["stop"]``), with how much its criterion fell
    in the last iteration: the held-out blocks chose the family, order and feedthrough, not
    how far to refine, and the user is told how to search on (a lower cost on the estimation
    record, which need not simulate other data better). A re-fit already bounded by work has
    its own note.

    Examples
    --------
    >>> import sysid
    >>> from sysid.identify.notes import refit_cap_check
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> m.info["pem"] = {"stop": "maximum iterations", "iterations": 300,
    ...                  "cost": [2.0, 1.0002, 1.0]}
    >>> checks = {}
    >>> refit_cap_check(m, checks)
    >>> checks["final_refit"][:60]
    "the chosen model's re-fit on the whole record stopped at its"
    """
    info = getattr(model, "info", None) or {}
    pem = info.get("pem") or {}
    if "final_refit" in checks or pem.get("stop") != "maximum iterations":
        return
    cost = [float(c) for c in pem.get("cost") or []]
    drop = (cost[-2] - cost[-1]) / abs(cost[-2]) if len(cost) >= 2 and cost[-2] else 0.0
    still = (f", its criterion still falling by {100 * drop:.2g} % in the last iteration"
             if drop > 0 else "")
    chosen = info.get("identify") or {}
    focus = chosen.get("focus") or "simulation"
    weighting = ", weighting='output'" if focus == "simulation" else ""
    checks["final_refit"] = (
        f"the chosen model's re-fit on the whole record stopped at its cap of "
        f"{pem.get('iterations')} iterations{still}: the held-out blocks chose its family, "
        f"order and feedthrough, not how far to refine it. To search on: "
        f"sysid.pem(res.model.remove_offsets(data), res.model.to_statespace(), "
        f"focus='{focus}', feedthrough={bool(chosen.get('feedthrough'))}{weighting}, "
        f"max_iter=1000) (a lower cost on this record, which need not simulate other data "
        f"better)")


def loop_feedthrough_check(feedthrough: bool, feedback: bool, checks: dict[str, Any]) -> None:
    """``checks["loop_feedthrough"]`` when the chosen model has a direct term (``D``) and the
    record shows feedback. A controller that computes its output from the same sample's
    measurement (most sampled loops log them in one row) ties ``u(t)`` to ``y(t)`` within the
    sample, and a closed-loop record cannot tell that tie from a plant's direct term: ``D``
    then carries the controller's, with the sign and size of its gain (a heated air duct with a
    0.12-0.2 s dead time, under PI control: ``D`` = -0.23 and -0.59 on two parts of its
    record, validation fits far below those of the fits without it). Whether the plant has a
    direct term is knowledge the data do not hold: the note says so and how to refit.

    Examples
    --------
    >>> from sysid.identify.notes import loop_feedthrough_check
    >>> checks = {}
    >>> loop_feedthrough_check(True, True, checks)
    >>> checks["loop_feedthrough"][:56]
    'the chosen model has a direct term (D) and the record sh'
    >>> loop_feedthrough_check(True, False, {})  # open loop: D is the plant's
    """
    if not (feedthrough and feedback):
        return
    checks["loop_feedthrough"] = (
        "the chosen model has a direct term (D) and the record shows feedback: if the "
        "controller acts within the sample (its output computed from the same sample's "
        "measurement), closed-loop data cannot tell its direct term from the plant's, and D "
        "may be the controller's; a plant with a dead time, or an output that cannot respond "
        "within a sample, has none: refit without it (sysid.ssest(data, order, "
        "feedthrough=False), or sysid.pbsid(data, order, feedthrough=False))")


def loop_bias_check(focus: str | None, family: str, feedback: bool,
                    checks: dict[str, Any]) -> None:
    """``checks["loop_bias"]`` when the record shows feedback and the chosen model has no
    noise model (a refinement with simulation focus, an ``oe`` model): its estimate is biased
    by the loop as the open-loop subspace fits' are (the input carries the noise the fit
    takes as independent of it), and identify sets those aside as biased. It is chosen
    because it simulates the held-out blocks best; the bias is small where the loop moves
    the input little, and a fit with a noise model (prediction focus, ``pbsid``) is the
    consistent one to compare with. The note says so, so that the feedback line's "biased"
    is not read as sparing the chosen model.

    Examples
    --------
    >>> from sysid.identify.notes import loop_bias_check
    >>> checks = {}
    >>> loop_bias_check("simulation", "pem", True, checks)
    >>> checks["loop_bias"][:50]
    'the chosen model has no noise model (simulation fo'
    >>> loop_bias_check("prediction", "pem", True, {})  # a noise model: consistent
    """
    if not feedback or not (focus == "simulation" or family == "oe"):
        return
    checks["loop_bias"] = (
        "the chosen model has no noise model (simulation focus, as an output-error fit), and "
        "feedback biases such an estimate as it does the open-loop subspace fits' (the input "
        "carries the noise the fit takes as independent of it); it is chosen because it "
        "simulates the held-out blocks best, and the bias is small where the loop moves the "
        "input little. The fit consistent under feedback has a noise model: compare "
        "sysid.ssest(data, order) (prediction focus) or sysid.pbsid(data, order) with it on "
        "validation data")


def loop_checks(chosen: dict[str, Any], feedback: bool, checks: dict[str, Any]) -> None:
    """The notes on a chosen candidate (``family``, ``focus``, ``feedthrough``) fitted to a
    record with feedback: :func:`loop_feedthrough_check` and :func:`loop_bias_check`.

    Examples
    --------
    >>> from sysid.identify.notes import loop_checks
    >>> checks = {}
    >>> loop_checks({"family": "oe", "focus": "simulation", "feedthrough": True}, True, checks)
    >>> sorted(checks)
    ['loop_bias', 'loop_feedthrough']
    """
    loop_feedthrough_check(bool(chosen["feedthrough"]), feedback, checks)
    loop_bias_check(chosen.get("focus"), str(chosen.get("family")), feedback, checks)
