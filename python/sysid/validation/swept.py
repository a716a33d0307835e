"""Held-out blocks of a record whose input sweeps its band (a chirp): interleaved pieces.

The automatic choices (``identify``, ``order="auto"``, ``pnlss``'s degree, ``nlhw``'s
nonlinearities) fit their candidates on the record less one contiguous block and score them
on that block (:func:`sysid.validation.crossval.record_folds`). A swept sine puts one band in
each part of the record, so every such block holds a band the rest of the record never
excited: each score is an extrapolation in frequency, and every aggregate of them ranks the
candidates by how they guess outside their data. Measured on two real chirp records
(``benches/results/realdata_fresh4.md``, ``realdata_fresh12.md``): a servo-hydraulic
actuator, where every aggregate of the blocks preferred order 1 and identify validated 3.3
and 20.9 points below the best tool on its two splits, and an electromagnetic actuator's
0.5-1000 Hz sweep, where the blocks turned down the simulation-error refinement of order 5
for its subspace start (62.6 %; a simulation-error fit of order 5 validates at 86.5 %).

:func:`swept` detects the case: each contiguous block's input power (windowed periodogram of
the block as one segment, the rest of the record averaged over segments of the same length;
:mod:`sysid.data.excitation`'s window) is compared with the rest's, and the share of it in
bins where the rest's power is below :data:`FLOOR` of its peak is the block's share outside
the rest's band; the record is swept when the median block has more than :data:`SWEPT` of its
power there. On the real records at hand (the shipped DaISy records and F-16 levels, the sixth
and twelfth sweeps' records and the fourth sweep's servo-hydraulic chirp; each whole, its
first and last two thirds and its first half) the two chirps' medians were 0.99-1.0 on every
part; every other was at most 0.41 (an air duct's PID run; the DaISy flutter record's last two
thirds 0.35, the rest at most 0.04). A held-out input that stands still (a step test after its
step) is not checked: its power is rounding.

:func:`interleaved_folds` then cuts the record into ``k`` times :data:`PIECES` equal pieces
and holds out every ``k``-th piece in fold ``j`` (pieces ``j, j + k, ...``), so that every
held-out piece lies between fitted ones on the sweep (an interpolation in frequency), and
the fitted part of a fold is the runs of pieces between its held-out ones.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..data.excitation import SEGMENT, input_spectrum
from ..data.iodata import IOData

__all__ = ["FLOOR", "PIECES", "SWEPT", "held_out_design", "interleaved_folds", "outside_share",
           "swept"]

#: power below this fraction of the rest's peak counts as not excited by the rest (30 dB)
FLOOR = 1e-3
#: a record is swept when the median block holds more than this share of its input power
#: outside the rest's band
SWEPT = 0.8
#: held-out pieces per fold of a swept record
PIECES = 4
#: shortest spectral segment the check uses (shorter blocks are not checked)
SHORTEST = 64
#: a held-out input channel whose standard deviation is below this fraction of the rest's
#: stands still (its power is rounding): it is not checked
STILL = 1e-6


def outside_share(fit: IOData, held: IOData, segment: int) -> float:
    """The largest share, over the input channels, of ``held``'s input power in the bins
    where ``fit``'s input power is below :data:`FLOOR` times its peak (periodograms of
    ``segment`` samples; experiments shorter than that left out; 0 when either record has no
    such experiment or the held-out input stands still).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.swept import outside_share
    >>> t = np.arange(4000)
    >>> u = np.sin(2 * np.pi * (0.01 + 0.1 * t / 4000) * t)   # a sweep 0.01-0.21
    >>> d = lambda x: sysid.IOData(u=x, y=x)
    >>> round(outside_share(d(u[:3000]), d(u[3000:]), 512), 2)  # the last band is new
    1.0
    >>> w = np.random.default_rng(0).standard_normal(4000)
    >>> round(outside_share(d(w[:3000]), d(w[3000:]), 512), 2)
    0.0
    """
    pf, ph = input_spectrum(fit, segment), input_spectrum(held, segment)
    if pf is None or ph is None:
        return 0.0
    return _share(pf, ph, _spread(held) > STILL * _spread(fit))


def _share(pf: np.ndarray, ph: np.ndarray, moves: np.ndarray) -> float:
    """The largest share over the channels that ``moves`` (a held-out input that stands
    still, a step test after its step, excites nothing: its power is rounding) of ``ph`` in
    the bins where ``pf`` is below :data:`FLOOR` times its peak."""
    share = 0.0
    for j in range(pf.shape[1]):
        peak, total = float(pf[:, j].max()), float(ph[:, j].sum())
        if peak <= 0 or total <= 0 or not moves[j]:
            continue
        share = max(share, float(ph[pf[:, j] < FLOOR * peak, j].sum() / total))
    return share


def _spread(data: IOData) -> np.ndarray:
    """Per input channel, the largest standard deviation over the experiments."""
    return np.max([np.std(np.asarray(u, float), axis=0) for u, _ in data.experiments], axis=0)


def swept(pairs: list[tuple[IOData, IOData]]) -> bool:
    """Whether the median held-out block of ``pairs`` (fit, held-out; the held-out blocks
    partition the record, as :func:`sysid.validation.crossval.folds` cuts it) holds more than
    :data:`SWEPT` of its input power outside the band of the rest of the record (as
    :func:`outside_share`, the rest's spectrum the sum of the other blocks': one pass over
    the record; segments of the largest power of two within the shortest held-out
    experiment, at most :data:`sysid.data.excitation.SEGMENT`; False when that is below
    :data:`SHORTEST` or there are fewer than three blocks).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import folds
    >>> from sysid.validation.swept import swept
    >>> t = np.arange(20000)
    >>> u = np.sin(2 * np.pi * (0.001 + 0.2 * t / 20000) * t)
    >>> swept(folds(sysid.IOData(u=u, y=u), 5))
    True
    >>> w = np.random.default_rng(0).standard_normal(20000)
    >>> swept(folds(sysid.IOData(u=w, y=w), 5))
    False
    """
    if len(pairs) < 3:
        return False
    shortest = min(min(h.lengths) for _, h in pairs)
    if shortest < SHORTEST:
        return False
    # at most the excitation check's longest segment: a long record's blocks are averaged
    segment = min(1 << int(np.floor(np.log2(shortest))), SEGMENT)
    # the held-out blocks partition the record: the rest of each is the sum of the others
    # (one pass over the record, not one per block)
    blocks = [input_spectrum(h, segment) for _, h in pairs]
    spread = [_spread(h) for _, h in pairs]
    if any(b is None for b in blocks):
        return False
    shares = []
    for i, ph in enumerate(blocks):
        others = [j for j in range(len(blocks)) if j != i]
        pf = sum(blocks[j] for j in others)
        rest = np.max([spread[j] for j in others], axis=0)
        shares.append(_share(pf, ph, spread[i] > STILL * rest))
    return bool(np.median(shares) > SWEPT)


def interleaved_folds(data: IOData, k: int, pieces: int = PIECES
                      ) -> list[tuple[IOData, IOData]]:
    """(fit, held-out) pairs of a one-experiment record cut into ``k * pieces`` equal
    pieces: fold ``j`` holds out pieces ``j, j + k, j + 2k, ...`` (one experiment each) and
    fits on the runs of pieces between them.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.swept import interleaved_folds
    >>> d = sysid.IOData(u=np.arange(40.0), y=np.arange(40.0))
    >>> fit, held = interleaved_folds(d, 5, 2)[1]
    >>> [float(e[0][0, 0]) for e in held.experiments], fit.lengths
    ([4.0, 24.0], [4, 16, 12])
    """
    (u, y), = data.experiments
    kw: dict[str, Any] = {"dt": data.dt, "input_names": data.input_names,
                          "output_names": data.output_names}
    edges = np.linspace(0, u.shape[0], k * pieces + 1).astype(int)
    out = []
    for j in range(k):
        held = list(range(j, k * pieces, k))
        cuts = [(int(edges[i]), int(edges[i + 1])) for i in held]
        # the fitted runs: from the start to the first held piece, between them, to the end
        bounds = [0] + [c for a, b in cuts for c in (a, b)] + [u.shape[0]]
        runs = [(a, b) for a, b in zip(bounds[::2], bounds[1::2]) if b > a]

        def part(spans: list[tuple[int, int]]) -> IOData:
            return IOData(u=[u[a:b] for a, b in spans], y=[y[a:b] for a, b in spans], **kw)

        out.append((part(runs), part(cuts)))
    return out


def held_out_design(data: IOData, pairs: list[tuple[IOData, IOData]]) -> dict[str, str]:
    """``{"held_out_design": note}`` when the folds ``pairs`` of the one-experiment record
    ``data`` are interleaved pieces (:func:`sysid.validation.crossval.record_folds` on a
    swept input), else ``{}``: the note :func:`sysid.identify` adds to its checks.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.validation.crossval import record_folds
    >>> from sysid.validation.swept import held_out_design
    >>> t = np.arange(20000)
    >>> u = np.sin(2 * np.pi * (0.001 + 0.2 * t / 20000) * t)
    >>> d = sysid.IOData(u=u, y=u)
    >>> held_out_design(d, record_folds(d))["held_out_design"][:40]
    'the input sweeps its band over the recor'
    """
    if data.n_experiments != 1 or not pairs or pairs[0][1].n_experiments == 1:
        return {}
    return {"held_out_design": (
        f"the input sweeps its band over the record (a chirp): every contiguous block held a "
        f"band the rest of the record never excited, so each of the {len(pairs)} folds holds "
        f"out {pairs[0][1].n_experiments} interleaved pieces instead, each between fitted "
        f"pieces on the sweep (sysid.validation.swept)")}
