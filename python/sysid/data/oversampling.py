"""How far a record is sampled beyond what its inputs change: the inputs' band and the
decimation that would put it at a usual share of the Nyquist frequency.

A subspace window of 20 samples on an input that changes over thousands (a slow chirp logged
at 1 kHz) sees a smooth curve, and the estimators refuse the record as not persistently
exciting. MATLAB's advice is to resample so that the sampling frequency is about ten times
the band of interest (``idresamp``). :func:`sysid.identify` follows it when the record is
refused for that reason (:mod:`sysid.identify.oversampled`), and the subspace estimators'
refusal names the decimation (:func:`oversampled_note`).
"""

from __future__ import annotations

import numpy as np

from .iodata import IOData

__all__ = ["BAND_SHARE", "MIN_KEPT", "POWER", "decimation_factor", "input_band",
           "oversampled_note"]

#: the inputs' band is put at this share of the decimated record's Nyquist frequency (a
#: sampling frequency ten times the band, the usual advice)
BAND_SHARE = 0.2
#: the share of each input's power that its band holds
POWER = 0.999
#: fewest samples the shortest experiment keeps after decimation (a hundred per held-out
#: block of :func:`sysid.identify`). At 1 000, a record of 1 001 samples logged at twice the
#: rate its input needs (a reaction-wheel pendulum's chirp, 0.09-0.7 Hz at 20 Hz) could not
#: be decimated at all and identify refused it; decimated by 2 it validates at 67.6 %
MIN_KEPT = 500


def input_band(data: IOData) -> float:
    """The band that holds :data:`POWER` of each input's power (its mean removed; Welch's
    periodogram of every experiment long enough), the widest over the inputs, as a share of
    the Nyquist frequency (1: the whole band).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.data.oversampling import input_band
    >>> t = np.arange(20000)
    >>> slow = sysid.IOData(u=np.sin(2e-3 * np.pi * t), y=np.zeros(20000))
    >>> bool(input_band(slow) < 0.01)
    True
    >>> white = sysid.IOData(u=np.random.default_rng(0).standard_normal(20000), y=np.zeros(20000))
    >>> bool(input_band(white) > 0.9)
    True
    """
    from scipy import signal

    usable = [u for u, _ in data.experiments if u.shape[0] >= 64]
    if not usable:
        return 1.0  # too short to tell
    seg = min(4096, max(64, min(u.shape[0] for u in usable) // 4))  # one grid for all
    widest = 0.0
    for j in range(data.n_inputs):
        power = None
        for u in usable:
            f, p = signal.welch(u[:, j] - u[:, j].mean(), nperseg=seg)
            power = p * u.shape[0] if power is None else power + p * u.shape[0]
        if power is None or not np.sum(power) > 0:
            return 1.0  # a constant input: not an oversampled one
        share = np.cumsum(power) / np.sum(power)
        widest = max(widest, float(f[min(np.searchsorted(share, POWER), len(f) - 1)]) / 0.5)
    return widest


def decimation_factor(data: IOData, band: float | None = None) -> int | None:
    """The decimation that puts the inputs' band (``band``, by default :func:`input_band`)
    at :data:`BAND_SHARE` of the new Nyquist frequency, at most what keeps :data:`MIN_KEPT`
    samples of the shortest experiment; ``None`` when that is below 2 (the record is not
    oversampled, or too short).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.data.oversampling import decimation_factor
    >>> t = np.arange(40000)
    >>> d = sysid.IOData(u=np.sin(2 * np.pi * (1e-4 + 1e-7 * t) * t), y=np.zeros(40000))
    >>> decimation_factor(d)
    12
    """
    band = input_band(data) if band is None else band
    q = min(int(BAND_SHARE / max(band, 1e-12)), min(data.lengths) // MIN_KEPT)
    return q if q >= 2 else None


def oversampled_note(data: IOData) -> str | None:
    """What to do with a record refused as not persistently exciting when its inputs change
    slowly against its sample time (:func:`decimation_factor` is 2 or more); ``None``
    otherwise.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.data.oversampling import oversampled_note
    >>> t = np.arange(40000)
    >>> d = sysid.IOData(u=np.sin(2 * np.pi * (1e-4 + 1e-7 * t) * t), y=np.zeros(40000))
    >>> print(oversampled_note(d)[:56])
    the inputs change slowly against the sample time (99.9 %
    """
    band = input_band(data)
    q = decimation_factor(data, band)
    if q is None:
        return None
    return (f"the inputs change slowly against the sample time (99.9 % of their power lies "
            f"below {100 * band:.2g} % of the Nyquist frequency), so every window "
            f"of the data matrix sees a smooth curve: decimate the record first "
            f"(sysid.decimate(data, {q}) puts that band at a fifth of the new Nyquist "
            f"frequency), or use sysid.identify(data), which does so")
