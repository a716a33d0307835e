"""What :func:`sysid.identify` returns: the chosen model (with the offsets it was identified
around, so that it predicts raw data) and the leaderboard of every candidate tried."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_int
from .._display import HTMLResult, model_html
from ..data.iodata import IOData
from ..errors import DataError, several_records_hint
from ..models.subsystem import ChannelSelection
from .board import unstable

__all__ = ["IdentifiedModel", "IdentifyResult"]

COLUMNS = ("family", "order", "feedthrough", "focus", "criterion", "held_out_fit", "mean_fit",
           "stable", "max_abs_pole", "seconds", "note", "chosen")
#: leaderboard rows :meth:`IdentifyResult.summary` shows by default (a search scores a few
#: hundred candidates on a long record; the refined ones and the choice are always shown)
SUMMARY_ROWS = 30


def _family(row: dict[str, Any]) -> str:
    """The leaderboard's family column: a subspace candidate with a stable ``A`` enforced is
    told apart from the same weighting's plain one, a candidate with input delays
    (:mod:`.delay`) from one without."""
    delay = row.get("input_delay")
    kind = {"subspace, stable A": " (stable A)", "subspace, states": " (states)",
            "subspace, integrating": " (integrating)"}.get(row.get("criterion"), "")
    return row["family"] + kind + (f" (delay {', '.join(map(str, delay))})" if delay else "")


def reported_fit(model: IdentifiedModel, validation: IOData | None) -> float | None:
    """The simulation fit (%) of ``model`` on ``validation`` that identify reports (None
    without validation data; ``-inf`` for a model that diverges there: reported, not
    raised)."""
    import warnings

    from ..errors import NumericalError

    if validation is None:
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return float(model.compare(validation).mean_fit)
    except (NumericalError, FloatingPointError):
        return -np.inf


class IdentifiedModel(ChannelSelection):
    """A linear model identified around operating-point offsets.

    ``y = y_offset + G (u - u_offset)``: :meth:`simulate` and :meth:`predict` take and return
    raw (un-detrended) signals; :attr:`statespace` is the model of the deviations.

    Attributes
    ----------
    statespace : StateSpaceModel
        The model of the deviations from the offsets (``A, B, C, D, K``).
    u_offset, y_offset : ndarray
        The estimation record's input and output means, removed before identification.
    """

    def __init__(self, statespace: Any, u_offset: Any, y_offset: Any) -> None:
        self.statespace = statespace
        self.u_offset = np.asarray(u_offset, float).ravel()
        self.y_offset = np.asarray(y_offset, float).ravel()
        for k in ("dt", "ninputs", "noutputs", "input_names", "output_names", "nstates"):
            setattr(self, k, getattr(statespace, k))
        self.info = dict(statespace.info or {})
        self.info["offsets"] = {"u": self.u_offset.tolist(), "y": self.y_offset.tolist()}

    @property
    def n_parameters(self) -> int:
        return int(self.statespace.n_parameters)

    def _select(self, iy: list[int], iu: list[int]) -> IdentifiedModel:
        """Outputs ``iy`` from inputs ``iu`` around their offsets (:meth:`select`)."""
        return IdentifiedModel(self.statespace.select(outputs=iy, inputs=iu),
                               self.u_offset[iu], self.y_offset[iy])

    def _repr_html_(self) -> str:
        """Notebook display: the facts and poles of its model, as every model shows them."""
        return model_html(self)

    def summary(self) -> str:
        """The model of the deviations (:meth:`sysid.ModelMixin.summary`: facts, the search,
        poles, parameters) and the operating point it is identified around."""
        u = ", ".join(f"{v:.6g}" for v in self.u_offset)
        y = ", ".join(f"{v:.6g}" for v in self.y_offset)
        lines = self.statespace.summary().splitlines()
        return "\n".join([f"IdentifiedModel around u = [{u}], y = [{y}]"] + lines)

    def to_pandas(self) -> Any:
        """The poles of :attr:`statespace` as a :class:`pandas.DataFrame` (:func:`sysid.damp`)."""
        return self.statespace.to_pandas()

    def remove_offsets(self, data: Any) -> IOData:
        """``data`` (raw, an IOData or a ``(u, y)`` pair) minus the offsets."""
        if isinstance(data, tuple):
            data = IOData(u=data[0], y=data[1], dt=self.dt)
        if not isinstance(data, IOData):
            raise DataError(f"data must be a sysid.IOData or a (u, y) pair, got "
                            f"{type(data).__name__}" + several_records_hint(data))
        if data.n_inputs != self.ninputs or data.n_outputs != self.noutputs:
            raise DataError(f"the model has {self.ninputs} input(s) and {self.noutputs} "
                            f"output(s) but the data have {data.n_inputs} and "
                            f"{data.n_outputs}")
        us = [u - self.u_offset for u, _ in data.experiments]
        ys = [y - self.y_offset for _, y in data.experiments]
        kw = {"dt": data.dt, "input_names": data.input_names, "output_names": data.output_names}
        if len(us) == 1:
            return IOData(u=us[0], y=ys[0], **kw)
        return IOData(u=us, y=ys, **kw)

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Output for raw inputs ``(n_samples, ninputs)``, in raw units."""
        u = np.asarray(u, float).reshape(-1, self.ninputs)
        return self.statespace.simulate(u - self.u_offset, x0) + self.y_offset

    def predict(self, u: Any, y: Any = None, horizon: int = 1) -> np.ndarray:
        """``horizon``-step prediction from raw ``u`` and ``y`` (or a record), in raw units."""
        from .._measured import predict_args

        u, y = predict_args(u, y)
        u = np.asarray(u, float).reshape(-1, self.ninputs)
        y = np.asarray(y, float).reshape(-1, self.noutputs)
        return (self.statespace.predict(u - self.u_offset, y - self.y_offset, horizon)
                + self.y_offset)

    def freqresp(self, omega: Any, std: bool = False) -> Any:
        """Frequency response of :attr:`statespace` (offsets do not enter it); ``std=True``:
        with its standard deviations, as :meth:`StateSpaceModel.freqresp`."""
        return self.statespace.freqresp(omega, std=std)

    def step(self, n_samples: int | None = None, std: bool = False) -> Any:
        """Step response of the dynamics (:attr:`statespace`, from the operating point, as
        MATLAB's ``step``): the change of the outputs for a unit change of each input;
        ``std=True``: with its standard deviations, as :meth:`StateSpaceModel.step`."""
        return self.statespace.step(n_samples, std=std)

    def dcgain(self, std: bool = False) -> Any:
        """Steady-state gain of the dynamics (:attr:`statespace`: output change per unit input
        change, offsets do not enter it); ``std=True``: ``(gain, std)``, as
        :meth:`StateSpaceModel.dcgain`."""
        return self.statespace.dcgain(std=std)

    def zeros(self) -> np.ndarray:
        """Transmission zeros of :attr:`statespace` (offsets do not move them)."""
        return np.asarray(self.statespace.zeros())

    def impulse(self, n_samples: int | None = None, std: bool = False) -> Any:
        """Impulse response of the dynamics (:attr:`statespace`); ``std=True``: with its
        standard deviations, as :meth:`StateSpaceModel.impulse`."""
        return self.statespace.impulse(n_samples, std=std)

    def to_statespace(self) -> Any:
        """The model of the deviations from the offsets (:attr:`statespace`)."""
        return self.statespace

    def poles(self, std: bool = False, method: str = "linear") -> Any:
        """The poles (offsets do not move them); ``std=True``: with their standard deviations
        from the model's parameter uncertainty, as :meth:`StateSpaceModel.poles`."""
        return self.statespace.poles(std=std, method=method)

    def damp(self, std: bool = False) -> Any:
        """Pole frequencies and damping of :attr:`statespace` (offsets do not move them), as
        :meth:`StateSpaceModel.damp`; ``std=True``: with first-order standard deviations."""
        return self.statespace.damp(std=std)

    @property
    def uncertainty(self) -> Any:
        """The parameter uncertainty of :attr:`statespace` (None when it has none): pole,
        damping and frequency-response standard deviations (``sysid.damp(model, std=True)``)."""
        return getattr(self.statespace, "uncertainty", None)

    def is_stable(self) -> bool:
        return bool(self.statespace.is_stable())

    def compare(self, data: Any, horizon: int | None = None, **kw: Any) -> Any:
        """:func:`sysid.compare` on raw data: the measured and simulated outputs in the data's
        units (the model of the deviations runs on the offset-free record, its offsets added
        back)."""
        import sysid

        return sysid.compare(self, data, horizon=horizon, **kw)

    def to_dict(self) -> dict[str, Any]:
        """The state-space model of the deviations and the offsets (see
        :func:`sysid.save_model`; :func:`sysid.load_model` gives the model back, still
        predicting raw data).

        Examples
        --------
        >>> import os, tempfile, numpy as np, sysid
        >>> from sysid.identify.result import IdentifiedModel
        >>> m = IdentifiedModel(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), [2.0], [7.0])
        >>> path = os.path.join(tempfile.mkdtemp(), "m.json")
        >>> sysid.save_model(m, path)
        >>> sysid.load_model(path).simulate(np.full(3, 2.0)).ravel().tolist()
        [7.0, 7.0, 7.0]
        """
        from ..models.uncertainty_io import body_with_uncertainty

        return {"statespace": body_with_uncertainty(self.statespace), "u_offset": self.u_offset,
                "y_offset": self.y_offset}

    def save(self, path: Any, *, format: str | None = None) -> None:
        """Write the model (its offsets too) to a ``.json`` or ``.npz`` file, as every model
        saves itself; see :func:`sysid.save_model` and :meth:`to_dict`."""
        from ..models.serialize import save_model

        save_model(self, path, format=format)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> IdentifiedModel:
        """Inverse of :meth:`to_dict`."""
        from ..models.statespace import StateSpaceModel
        from ..models.uncertainty_io import model_from_body

        return cls(model_from_body(StateSpaceModel, d["statespace"]), d["u_offset"],
                   d["y_offset"])

    def __repr__(self) -> str:
        s = self.statespace
        spec = s.info.get("integrating") or {}
        names = [str(s.output_names[i]) for i in spec.get("outputs", [])]
        flags = (f", integrator on {', '.join(names)}" if names else "") + (
            ", UNSTABLE" if unstable(s) else "")
        return (f"IdentifiedModel({s.info.get('identify', {}).get('family', 'model')}, "
                f"order {s.nstates}, {s.ninputs} input(s), {s.noutputs} output(s), "
                f"offsets removed{flags})")


class IdentifyResult(HTMLResult):
    """The outcome of :func:`sysid.identify`.

    Attributes
    ----------
    model : IdentifiedModel
        The chosen model, re-fitted on the whole estimation record (predicts raw data).
    leaderboard : list of dict
        Every candidate: family, order, feedthrough, focus, criterion (``"subspace, stable
        A"``, ``"subspace, states"``: ``A`` enforced stable, or from the estimated state
        sequence; ``summary`` shows them as ``(stable A)``, ``(states)``), held-out fit (%, the
        simulation fit of the model fitted on the rest of the estimation record, on the
        held-out blocks pooled, without the one where it fits worst and the one where it
        fits best: :func:`sysid.identify.board.held_out_score`), mean fit and ``fold_fits``
        (every block's), stability (every fold's model), seconds, a note, and ``chosen``.
    choice : str
        The chosen row, in words.
    checks : dict
        Offsets, excitation and feedback findings.
    validation_fit : float or None
        Simulation fit (%) of :attr:`model` on the ``validation`` data, when given (reported
        only: it played no part in the choice).
    seconds : float
    """

    def __init__(self, model: IdentifiedModel, leaderboard: list[dict[str, Any]], choice: str,
                 checks: dict[str, Any], validation_fit: float | None, seconds: float,
                 interrupted: bool = False, score: str = "held-out") -> None:
        self.model, self.leaderboard, self.choice = model, leaderboard, choice
        self.checks, self.validation_fit, self.seconds = checks, validation_fit, seconds
        self.interrupted = interrupted
        #: whether ``time_budget`` ran out before every candidate was scored
        self.out_of_time = False
        #: what chose the model: ``"held-out"`` (the blocks held out of the record), or
        #: ``"BIC"`` (a step test, :mod:`sysid.identify.steptest`: no part can be held out)
        self.score = score

    def to_pandas(self) -> Any:
        """The leaderboard as a DataFrame, in the order of :meth:`summary`: the stable
        candidates the held-out blocks cannot tell apart from the best first, smallest order
        first; then the other stable ones by held-out fit; the unstable ones last. A column
        ``input_delay`` (samples per input; None for the others) when candidates with input
        delays were scored."""
        import pandas as pd

        delays = any("input_delay" in r for r in self.leaderboard)
        return pd.DataFrame(self.leaderboard,
                            columns=list(COLUMNS) + (["input_delay"] if delays else []))

    def summary(self, rows: int | None = SUMMARY_ROWS) -> str:
        """The choice, the checks and the leaderboard as text.

        Parameters
        ----------
        rows : int or None
            Leaderboard rows shown, in the leaderboard's order (a search scores a few hundred
            candidates on a long record); every refined candidate and the chosen one are shown
            as well, and a last line counts the rest. ``None`` shows every row
            (:meth:`to_pandas` has them all too).

        Examples
        --------
        >>> import numpy as np, sysid
        >>> rng = np.random.default_rng(0)
        >>> u = rng.standard_normal(600)
        >>> y = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]]).simulate(u)
        >>> res = sysid.identify(sysid.IOData(u=u, y=y + 0.1 * rng.standard_normal(y.shape)),
        ...                      progress=False)
        >>> text = res.summary(rows=5)
        >>> "more candidates" in text, len(res.summary(rows=None).splitlines()) > len(
        ...     text.splitlines())
        (True, True)
        """
        if rows is not None:
            rows = as_int(rows, "rows", lo=0)
        lines = [f"sysid.identify: {self.choice} ({self.seconds:.1f} s"
                 + (", interrupted" if self.interrupted else "")
                 + (", time budget spent" if self.out_of_time else "") + ")"]
        if self.validation_fit is not None:
            lines.append(f"validation fit (reported only): {self.validation_fit:.1f} %")
        for k, v in self.checks.items():
            lines.append(f"{k}: {v}")
        held = self.score == "held-out"  # else the fit to the record itself (a step test)
        lines.append(f"  {'family':<18} {'order':>5} {'D':>3} {'focus':<10} "
                     f"{'held-out fit %' if held else 'record fit %':>14} {'stable':>6} "
                     f"{'s':>6}  note")
        shown = [r for i, r in enumerate(self.leaderboard)
                 if rows is None or i < rows or r.get("chosen")
                 or not r["criterion"].startswith("subspace")]
        for r in shown:
            f = r["held_out_fit"] if held else r["mean_fit"]
            fs = f"{f:14.2f}" if np.isfinite(f) and f > -1e4 else f"{'< -1e4':>14}"
            ft = "yes" if r["feedthrough"] else "no"
            lines.append(f"{'*' if r.get('chosen') else ' '} {_family(r):<18} {r['order']:>5} "
                         f"{ft:>3} {r['focus'] or '-':<10} {fs} "
                         f"{'yes' if r['stable'] else 'NO':>6} {r['seconds']:6.2f}"
                         f"  {r.get('note') or ''}".rstrip())
        if len(shown) < len(self.leaderboard):
            lines.append(f"  ... {len(self.leaderboard) - len(shown)} more candidates, all "
                         "subspace ones ranked below these (every row: summary(rows=None) or "
                         "to_pandas())")
        if held and any(r.get("chosen") and not r["stable"] for r in self.leaderboard) \
                and self.model.is_stable():
            # the column is of the fits with a block held out: a test building's row said
            # "NO" above the stable model returned, with nothing to tell them apart
            rho = float(np.max(np.abs(self.model.poles())))
            lines.append(f"  stable: of the fits with a block held out; the chosen one, "
                         f"re-fitted on the whole record, is stable (largest pole modulus "
                         f"{rho:.4g})")
        lines.append("* chosen (re-fitted on the whole record; among those the held-out blocks "
                     "cannot tell apart, the smallest BIC)" if held else
                     "* chosen (the smallest BIC of the simulation errors from rest; within "
                     "2 of it, the fewest parameters)")
        return "\n".join(lines)

    def plot(self, ax: Any = None) -> Any:
        """Held-out fit against order, one colour per family (hollow markers: unstable
        candidates, which are not chosen unless the data insist; fits below -100 % drawn at
        -100 % as triangles); for a step test (:attr:`score` ``"BIC"``) the fit to the
        record; returns the axes."""
        import matplotlib.pyplot as plt
        from matplotlib.ticker import MaxNLocator

        if ax is None:
            _, ax = plt.subplots()
        key = "held_out_fit" if self.score == "held-out" else "mean_fit"
        fams = sorted({r["family"] for r in self.leaderboard})
        for k, fam in enumerate(fams):
            rows = [r for r in self.leaderboard if r["family"] == fam and np.isfinite(r[key])]
            label: str | None = fam  # on the family's first group drawn
            for stable in (True, False):
                for low in (False, True):
                    sel = [r for r in rows if bool(r["stable"]) == stable
                           and (r[key] < -100) == low]
                    if sel:
                        ax.plot([r["order"] for r in sel],
                                [max(r[key], -100) for r in sel], "v" if low else "o",
                                color=f"C{k}", mfc=f"C{k}" if stable else "none", alpha=0.7,
                                label=label)
                        label = None
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        chosen = next((r for r in self.leaderboard if r.get("chosen")), self.leaderboard[0])
        ax.plot([chosen["order"]], [max(chosen[key], -100)], "k*", ms=14, label="chosen")
        ax.set_xlabel("order")
        ax.set_ylabel("held-out simulation fit (%)" if key == "held_out_fit" else
                      "simulation fit to the record (%)")
        ax.legend(fontsize="small")
        return ax

    def __repr__(self) -> str:
        return (f"IdentifyResult({self.choice}; {len(self.leaderboard)} candidates, "
                f"{self.seconds:.1f} s)")


def _register() -> None:
    from ..models.serialize import register_model

    register_model(IdentifiedModel)


_register()
