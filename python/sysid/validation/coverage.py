"""Does a validation record's input stay in the bands the estimation record excited?

A model is determined by the data only at the frequencies its estimation input excites. When
another record (the validation part, a new experiment) puts its input power where the
estimation input had almost none, a fit there scores an *extrapolation* of the model to
frequencies it was never fitted on, good or bad by luck of the model structure. A swept sine
(chirp) split in time does this to the full: each part holds its own frequency band (the
servo-hydraulic actuator's chirp of ``benches/results/chirp_feedback.md``: the first 2/3
estimate 0-15 Hz, the last third validates 15-25 Hz, and the held-out choices inside the
estimation part cannot rank the models where they are compared).

:func:`input_coverage` compares the two inputs' power spectra (the excitation check's
windowed periodogram, :mod:`sysid.data.excitation`, with segments of one common length, so
that both lie on one frequency grid) per input channel: the share of the
validation input's power in the bins where the estimation input's power is below ``floor``
times its peak. A share above ``limit`` is reported as an extrapolation; :func:`sysid.identify`
records it among its checks when it is given ``validation=`` data (:func:`coverage_note`).

Measured on the real records of ``benches/realdata.py`` (every sweep, both splits; 86 pairs,
``benches/results/chirp_feedback.md``): at the defaults (30 dB, 10 %) the chirp's two splits are
flagged (74 and 48 %), and four more: a step record whose estimation part has no step (100 %),
the ATTAS aircraft's aileron (28 %), the DaISy flutter record (18 %), the pH record's second
input (11 %); 146 of the 152 input channels stay below 5 %. The spectra are the excitation
check's (:mod:`sysid.data.excitation`: Blackman-Harris windows, whose sidelobes lie far below
the 30 dB floor; a Hann window's first one is at -31 dB, at the floor itself).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .._checks import as_between, constant_channels
from ..data.excitation import input_spectrum
from ..data.iodata import IOData, require_record
from ..errors import DataError

__all__ = ["InputCoverage", "coverage_note", "input_coverage"]


@dataclass(frozen=True)
class InputCoverage:
    """Result of :func:`input_coverage`.

    Attributes
    ----------
    outside : ndarray
        Per input channel, the share (0-1) of the validation input's power in the frequency
        bins where the estimation input's power is below ``floor`` times its peak.
    bands : list of list of (float, float)
        Per input channel, the frequency bands (in the records' units, cycles per time unit;
        per sample when ``dt`` is 1) of those bins that hold validation power.
    floor, limit : float
        The thresholds of the check.
    input_names : list of str
    """

    outside: np.ndarray
    bands: list[list[tuple[float, float]]]
    floor: float
    limit: float
    input_names: list[str]

    @property
    def extrapolates(self) -> bool:
        """Whether some input puts more than ``limit`` of its power outside the estimation
        input's bands."""
        return bool(np.any(self.outside > self.limit))

    def summary(self) -> str:
        """One line per input channel and the verdict."""
        lines = []
        for name, share, bands in zip(self.input_names, self.outside, self.bands):
            where = ", ".join(f"{lo:.3g}-{hi:.3g}" for lo, hi in bands[:4])
            more = f" and {len(bands) - 4} more" if len(bands) > 4 else ""
            lines.append(f"{name}: {100 * share:.1f} % of the validation input's power lies "
                         f"where the estimation input's is below {self.floor:.2g} of its peak"
                         + (f" (bands {where}{more})" if bands else ""))
        lines.append(repr(self))
        return "\n".join(lines)

    def __repr__(self) -> str:
        worst = float(np.max(self.outside)) if self.outside.size else 0.0
        if self.extrapolates:
            return (f"InputCoverage(extrapolation: up to {100 * worst:.1f} % of the validation "
                    f"input's power is in bands the estimation input did not excite; the fit "
                    f"there tests the model outside the data it was fitted on)")
        return f"InputCoverage(covered: at most {100 * worst:.1f} % outside)"


def _record(data: Any, name: str) -> IOData:
    data = require_record(data, name)
    if data.n_inputs == 0:
        raise DataError(f"input_coverage needs records with inputs; the {name} record has none")
    return data


def input_coverage(estimation: IOData | tuple[Any, Any], validation: IOData | tuple[Any, Any],
                   *, floor: float = 0.001, limit: float = 0.1, segment: int | None = None
                   ) -> InputCoverage:
    """Check whether the validation input excites bands the estimation input did not.

    Per input channel, the share of the validation input's power in the frequency bins
    where the estimation input's power (windowed periodogram averaged over half-overlapping
    segments, experiments weighted by their length) is below ``floor`` times its peak. A
    model's fit on such a record is an extrapolation in frequency (a chirp split in time:
    each part holds its own band).

    Parameters
    ----------
    estimation, validation : IOData or (u, y)
        The two records, with the same input channels and sample time.
    floor : float
        Power below this fraction of the estimation input's peak counts as not excited
        (default 0.001, 30 dB below the peak).
    limit : float
        Share of the validation input's power outside above which
        :attr:`InputCoverage.extrapolates` is set (default 0.1).
    segment : int, optional
        Segment length of the spectra (default: a power of two, at most 1024 and at most a
        quarter of the shortest experiment of the two records).

    Returns
    -------
    InputCoverage

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.coverage import input_coverage
    >>> t = np.arange(6000)
    >>> u = np.sin(2 * np.pi * (0.005 + 0.1 * t / 6000) * t)   # a sweep 0.005-0.2
    >>> y = np.zeros_like(u)
    >>> input_coverage((u[:4000], y[:4000]), (u[4000:], y[4000:])).extrapolates
    True
    >>> rng = np.random.default_rng(0)
    >>> w = rng.standard_normal(6000)
    >>> input_coverage((w[:4000], y[:4000]), (w[4000:], y[4000:])).extrapolates
    False
    """
    est, val = _record(estimation, "estimation"), _record(validation, "validation")
    if est.n_inputs != val.n_inputs:
        raise DataError(f"the estimation record has {est.n_inputs} inputs and the validation "
                        f"record {val.n_inputs}: compare records of the same channels")
    if est.dt != val.dt:
        raise DataError(f"the records' sample times differ ({est.dt} and {val.dt}): "
                        "resample one to the other's first")
    floor = as_between(floor, "floor", 0.0, 1.0)
    limit = as_between(limit, "limit", 0.0, 1.0)
    shortest = min(min(est.lengths), min(val.lengths))
    if segment is None:
        segment = int(2 ** np.floor(np.log2(max(min(1024, shortest // 4), 8))))
    if not (isinstance(segment, (int, np.integer)) and 8 <= segment <= shortest):
        raise DataError(f"segment must be an integer from 8 to the shortest experiment's "
                        f"length ({shortest}), got {segment!r}")
    segment = int(segment)

    pe, pv = input_spectrum(est, segment), input_spectrum(val, segment)
    freqs = np.fft.rfftfreq(segment, est.dt if est.dt else 1.0)
    outside, bands = np.zeros(est.n_inputs), []
    # a validation input that stands still excites nothing: its rounding is no extrapolation
    still = constant_channels([np.asarray(u) for u, _ in val.experiments], "all")
    for j in range(est.n_inputs):
        peak, total = float(pe[:, j].max()), 0.0 if still[j] else float(pv[:, j].sum())
        poor = pe[:, j] < floor * peak if peak > 0 else np.ones(len(freqs), bool)
        outside[j] = float(pv[poor, j].sum() / total) if total > 0 else 0.0
        # the poor bins holding at least 1 % of the validation power, merged into bands
        hit = poor & (pv[:, j] > 0.01 * total) if total > 0 else np.zeros(len(freqs), bool)
        edges = np.diff(np.r_[0, hit.astype(np.int8), 0])
        bands.append([(float(freqs[a]), float(freqs[b - 1])) for a, b in
                      zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1))])
    return InputCoverage(outside, bands, float(floor), float(limit), list(est.input_names))


def coverage_note(estimation: IOData, validation: IOData) -> str | None:
    """The line :func:`sysid.identify` adds to its checks when the validation record's input
    lies outside the estimation input's bands (None when it does not, or when the check
    cannot run on the two records).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.coverage import coverage_note
    >>> rng = np.random.default_rng(0)
    >>> w = rng.standard_normal((3000, 1))
    >>> coverage_note(sysid.IOData(w[:2000], w[:2000]), sysid.IOData(w[2000:], w[2000:])) is None
    True
    """
    from ..errors import SysidError

    try:
        cov = input_coverage(estimation, validation)
    except SysidError:  # records the check cannot compare (too short, other channels)
        return None
    if not cov.extrapolates:
        return None
    worst = int(np.argmax(cov.outside))
    bands = ", ".join(f"{lo:.3g}-{hi:.3g}" for lo, hi in cov.bands[worst][:3])
    return (f"{100 * cov.outside[worst]:.0f} % of the validation input's power "
            f"({cov.input_names[worst]}) lies in bands the estimation input did not excite "
            f"(below {cov.floor:.2g} of its peak" + (f"; frequencies {bands}" if bands else "")
            + "): the validation fit there tests the model outside the data it was fitted "
            "on (a chirp split in time does this), not the identification "
            "(sysid.validation.coverage.input_coverage)")
