"""Argument checking shared by the public functions (one helper, SciPy style)."""

from __future__ import annotations

import sys
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from . import _sysid, errors
from .errors import DataError, ExcitationError, NonFiniteError, ShapeError, refuse_frd


def as_2d(x: Any, name: str, *, ncols: int | None = None, allow_empty: bool = False) -> np.ndarray:
    """Return ``x`` as a float64 array shaped (samples, channels) without copying if possible.

    1-D input is read as one channel. Strings, objects, complex numbers, 3-D arrays and
    non-finite values raise a :class:`DataError` that names the argument.
    """
    if isinstance(x, (str, bytes)):
        raise ShapeError(f"{name} must be a numeric array, got a string")
    if errors.is_record(x):  # an IOData record
        raise DataError(
            f"{name} must be an array of samples, got a whole record (IOData): pass its "
            f"signals (data.u for inputs, data.y for outputs), or hand the record to "
            "sysid.compare(data, model), which simulates the model on it")
    arr = real_array(x, name)
    if arr.ndim == 1:
        arr = arr[:, None]
    elif arr.ndim == 0:
        raise ShapeError(f"{name} must be 1-D or 2-D (samples, channels), got a scalar")
    elif arr.ndim != 2:
        raise ShapeError(
            f"{name} must be 1-D or 2-D (samples, channels), "
            f"got {arr.ndim}-D with shape {arr.shape}")
    if arr.shape[0] == 0 and not allow_empty:
        raise ShapeError(f"{name} has no samples (shape {arr.shape})")
    if ncols is not None and arr.shape[1] != ncols:
        hint = (f"; it looks transposed (arrays are (samples, channels)): pass {name}.T"
                if arr.shape[0] == ncols else "")
        raise ShapeError(f"{name} has shape {arr.shape} but should have {ncols} column(s)"
                         f"{hint}")
    # a NaN or Inf makes the sum non-finite; the sum is one vectorised pass with no
    # temporary (np.isfinite(arr).all() writes a boolean array as large as the record),
    # and only a non-finite (or overflowing) sum takes the elementwise check
    with np.errstate(over="ignore", invalid="ignore"):
        total = arr.sum()
    if not np.isfinite(total) and not np.isfinite(arr).all():
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise NonFiniteError(
            f"{name} has a non-finite value (NaN or Inf) at sample {bad[0]}, channel {bad[1]}; "
            "interpolate or cut it out before identification")
    return arr


def real_array(x: Any, name: str) -> np.ndarray:
    """``x`` as a float64 array (no copy if it is one), any shape, NaN allowed; strings,
    objects and complex numbers raise a :class:`DataError` naming ``name`` (complex ones are
    not cast: NumPy would drop the imaginary parts with only a ComplexWarning).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid._checks import real_array
    >>> real_array([1, 2], "y")
    array([1., 2.])
    >>> real_array(np.array([1 + 2j]), "y")
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: y must be a real numeric array, got complex values (dtype ...
    """
    x = unmask(x, name)
    try:
        arr = np.asarray(x)
    except ValueError:
        raise ShapeError(f"{name} must be a rectangular numeric array (rows of equal "
                         "length)") from None
    if arr.dtype.kind == "c":
        raise DataError(f"{name} must be a real numeric array, got complex values (dtype "
                        f"{arr.dtype}): sysid does not drop imaginary parts; pass "
                        f"np.real({name}) if the real part is what you mean")
    if arr.dtype.kind not in "biuf":
        raise DataError(
            f"{name} must be a real numeric array, got dtype {arr.dtype}; convert it with "
            f"np.asarray({name}, dtype=float)")
    return arr.astype(np.float64, copy=False)


def unmask(x: Any, name: str) -> Any:
    """The data of a masked array without masked entries; masked entries raise.

    A masked sample is a missing sample: it is never silently replaced by the value under
    the mask.
    """
    # `np.ma` is imported on first attribute access (0.1-0.2 s); a masked array cannot exist
    # before it is, so plain arrays skip it
    ma = sys.modules.get("numpy.ma")
    if ma is None or not isinstance(x, ma.MaskedArray):
        return x
    mask = np.ma.getmaskarray(x)
    if mask.any():
        first = np.argwhere(mask)[0]
        where = ", ".join(str(int(i)) for i in first)
        raise NonFiniteError(
            f"{name} is a masked array with {int(mask.sum())} masked value(s) (the first at "
            f"index {where}); masked samples are missing data: pass {name}.filled(np.nan) to "
            "IOData.from_raw (which interpolates short gaps) or cut them out")
    return np.ma.getdata(x)


def as_option(value: Any, option: str, name: str | None = None) -> str:
    """The canonical name of the option string ``value``: the core parses it (its list of
    names is the only one) and raises its own error for an unknown name; ``name`` is the
    argument's name in the message for a value that is not a string (default ``option``)."""
    if not isinstance(value, str):
        raise DataError(f"{name or option} must be a string, got {value!r}")
    return str(_sysid.option_name(option, value))


def as_dt(dt: Any, name: str = "dt") -> float:
    """A sample time in seconds: a finite positive number (not a bool, not None).

    A single-precision value (``np.float32(0.1)``, which is 0.10000000149...) becomes the
    double nearest its decimal form (0.1): the value the user wrote, so that it matches the
    sample time of other records and models.
    """
    if dt is None or isinstance(dt, (bool, np.bool_, str, bytes)):
        raise DataError(f"{name} must be a positive number of seconds, got {dt!r}")
    try:
        arr = np.asarray(dt)
        if arr.dtype.kind == "f" and arr.dtype.itemsize < 8 and arr.size == 1:
            dt = np.format_float_scientific(arr.reshape(())[()], unique=True)
        val = float(dt)
    except (TypeError, ValueError):
        raise DataError(f"{name} must be a positive number of seconds, got {dt!r}") from None
    if not np.isfinite(val) or val <= 0:
        raise DataError(f"{name} must be a positive number of seconds, got {val}")
    if not MIN_DT <= val <= MAX_DT:
        raise DataError(f"{name} = {val:g} s lies outside {MIN_DT:g} .. {MAX_DT:g} s: its "
                        "frequencies (pi / dt) and durations (N dt) would overflow or underflow "
                        "double precision; give the sample time in other units (ms, hours)")
    return val


#: the sample times :func:`as_dt` accepts: any unit a record is kept in, far from the
#: overflow of ``pi / dt`` and ``N dt`` (a dt of 1e-300 or 1e300 was accepted and broke
#: every spectral and continuous-time tool later)
MIN_DT, MAX_DT = 1e-100, 1e100


def as_matrix(x: Any, name: str, shape: tuple[int | None, int | None]) -> np.ndarray:
    """Return a finite float64 matrix, checking its shape (``None`` matches any size)."""
    if isinstance(x, (str, bytes)):
        raise ShapeError(f"{name} must be a numeric matrix, got a string")
    arr = np.atleast_2d(real_array(x, name))
    if arr.ndim != 2:
        raise ShapeError(f"{name}: expected 2-D, got {arr.ndim}-D")
    for got, want in zip(arr.shape, shape):
        if want is not None and got != want:
            expected = tuple("any" if s is None else s for s in shape)
            raise ShapeError(f"{name} has shape {arr.shape} but should have shape {expected}")
    if not np.isfinite(arr).all():
        raise NonFiniteError(f"{name} has non-finite entries (NaN or Inf)")
    return arr


#: Largest size argument (horizon, order, lag count...) accepted before it is compared with
#: the data: far beyond any record, small enough that no size computation overflows.
MAX_SIZE = 2**40


def as_orders(order: Any, name: str = "order") -> list[int]:
    """One model order or a sequence of them (``range(1, 11)``, a list, an array) as a
    sorted list of distinct positive integers.

    Examples
    --------
    >>> from sysid._checks import as_orders
    >>> as_orders(range(3, 0, -1)), as_orders([4, 2, 4]), as_orders(5)
    ([1, 2, 3], [2, 4], [5])
    """
    items = [order] if np.ndim(order) == 0 else np.ravel(np.asarray(list(order)))
    orders = sorted({as_int(o, name, 1) for o in items})
    if not orders:
        raise DataError(f"{name}: the sequence of orders is empty; give at least one order")
    return orders


def warn_iteration_limit(what: str, max_iter: int, history: Any, fix: str = "raise max_iter",
                         stacklevel: int | None = None, remaining: float | None = None,
                         category: type | None = None) -> None:
    """The :class:`~sysid.errors.IterationLimitWarning` of a search stopped at its cap: how
    much its last iteration still lowered the cost, how far the estimate stands from the
    minimum of the search's Gauss-Newton model (``remaining``: the optimiser's
    ``remaining_decrease``, in residual variances), and what to do; at the caller's line
    outside sysid unless ``stacklevel`` is given. No warning when ``remaining`` is below
    ``NEGLIGIBLE_REMAINING``: the rest of the way would move the estimate by less than half
    of its standard deviation. ``category``: a subclass of the warning (tfest's
    ``ConvergenceWarning``).

    Examples
    --------
    >>> import warnings
    >>> from sysid._checks import warn_iteration_limit
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_iteration_limit("the search", 5, [4.0, 2.0])
    ...     warn_iteration_limit("the search", 5, [4.0, 2.0], remaining=0.02)  # silent
    >>> len(w), str(w[0].message)[:60]
    (1, 'the search stopped at max_iter=5 before converging (the last')
    """
    import warnings

    from .errors import IterationLimitWarning

    far = ""
    if remaining is not None and np.isfinite(remaining):
        if remaining < NEGLIGIBLE_REMAINING:
            return
        far = (f"; its Gauss-Newton model puts the minimum about "
               f"{np.sqrt(2.0 * remaining):.2g} standard deviations of the estimate away")
    h = [float(c) for c in history]
    last = abs(h[-2] - h[-1]) / max(abs(h[-2]), 1e-300) if len(h) > 1 else 0.0
    if len(h) > RECENT:  # a crawl's last step is small: its last ten tell more
        ten = abs(h[-1 - RECENT] - h[-1]) / max(abs(h[-1 - RECENT]), 1e-300)
        far = f", the last {RECENT} by {100 * ten:.2g} %" + far
    warnings.warn(f"{what} stopped at max_iter={max_iter} before converging (the last "
                  f"iteration still lowered the cost by {100 * last:.2g} %{far}); the model "
                  f"is the best iterate: {fix}", category or IterationLimitWarning,
                  stacklevel=user_stacklevel() if stacklevel is None else stacklevel)


def warn_if_capped(info: dict[str, Any], what: str, max_iter: int,
                   fix: str = "raise max_iter", n_residuals: int | None = None,
                   category: type | None = None) -> None:
    """:func:`warn_iteration_limit` when a search's ``info["stop"]`` says it stopped at its
    cap (``info["cost"]``: its criterion per iteration) short of its minimum: its distance
    from its Gauss-Newton model's minimum (``info["remaining_decrease"]``) and, below
    ``DISTANT``, its history must say so. The distance alone misleads in flat network
    searches: a default ``nlhw`` capped 2.1 residual variances away went on 0.009 lower in
    336 iterations. A last step below ``SETTLED`` (relative) had settled, as had one below
    ``FLOOR`` of the start's cost (a noise-free fit at the rounding floor) or below
    ``STATISTICAL`` residual variances ``2 cost / n_residuals``; the last ``RECENT``
    iterations must be below ``RECENT`` times the bound too (an ``nlhw`` whose small last
    step followed a drop of 1.9 variances over ten went on 3.4 lower)."""
    stop = info.get("stop")
    stops = stop if isinstance(stop, list) else [stop]
    if max_iter > 0 and "maximum iterations" in stops:
        cost = info.get("cost") or []
        remaining = info.get("remaining_decrease")
        if cost and isinstance(cost[0], (list, tuple)):  # one history per output
            cost = cost[stops.index("maximum iterations")]
        if isinstance(remaining, (list, tuple)):
            remaining = remaining[stops.index("maximum iterations")] if remaining else None
        h = [float(c) for c in cost]
        stat = STATISTICAL * 2 * abs(h[-1]) / n_residuals if n_residuals and h else 0.0

        def small(k: int) -> bool:  # the last k iterations lowered the cost by a settled k
            return abs(h[-1 - k] - h[-1]) <= k * max(SETTLED * abs(h[-1 - k]),
                                                     FLOOR * abs(h[0]), stat, 1e-300)
        far = remaining is not None and np.isfinite(remaining) and remaining >= DISTANT
        if len(h) > 1 and small(1) and (len(h) <= RECENT or small(RECENT)) and not far:
            return
        warn_iteration_limit(what, max_iter, cost, fix, remaining=remaining,
                             category=category)


SETTLED = 1e-5  #: relative decrease of a capped search's last iteration: settled below
FLOOR = 1e-12  #: the same relative to the start's cost: a noise-free fit's rounding floor
STATISTICAL = 1e-2  #: in residual variances: converged statistically (``tol_statistical``)
RECENT = 10  #: iterations whose decrease together must be settled too (warn_if_capped)
#: a capped search's remaining predicted decrease (the optimiser's ``remaining_decrease``,
#: in residual variances) below which its stop is not warned about: the rest of the way
#: would move the estimate by less than half of its standard deviation (``sqrt(2 x 1/8)``)
NEGLIGIBLE_REMAINING = 0.125
#: a capped search's remaining predicted decrease (residual variances; three standard
#: deviations, ``sqrt(2 x 4.5)``) from which it is warned about whatever its history: crawling
#: ``bj``/``oe`` searches 5.7 and 9.5 away went on 0.18 % and 1.15 % lower; flat ``nlhw``
#: network searches stood at most 2.6 away (eight seeds)
DISTANT = 4.5


#: a stable pole whose mode keeps more than this share of its size over the longest
#: experiment cannot be told from an integrator by the record (:func:`mode_kept`)
PERSISTENT_DECAY = 0.99


def mode_kept(rho: float, n: int) -> float:
    """The share of a mode of pole modulus ``rho`` (below 1) left after ``n`` samples.

    Examples
    --------
    >>> from sysid._checks import mode_kept
    >>> round(mode_kept(0.5, 2), 2), mode_kept(1 - 1e-9, 1000) > 0.99
    (0.25, True)
    """
    return float(np.exp(n * np.log(rho))) if 0.0 < rho < 1.0 else float(rho >= 1.0)


def as_int(x: Any, name: str, lo: int = 1, hi: int | None = None, *, alt: str = "") -> int:
    """Return an integer argument (a Python or NumPy integer, not a bool) in ``[lo, hi]``.

    An integer-valued float (``2.0``, ``np.float64(2)``) is taken too: MATLAB's orders,
    counts and horizons are doubles. The message names the argument and the range; ``alt``
    names another accepted value (e.g. ``"None (simulation)"``) that the caller has already
    handled.
    """
    given = x  # quoted as given in the refusals
    if isinstance(x, (float, np.floating)) and np.isfinite(x) and float(x).is_integer() \
            and abs(x) <= MAX_SIZE:
        x = int(x)
    ok = isinstance(x, (int, np.integer)) and not isinstance(x, (bool, np.bool_))
    if ok and x >= lo and (hi is None or x <= hi) and x <= MAX_SIZE:
        return int(x)
    if ok and x > MAX_SIZE and (hi is None or hi > MAX_SIZE):
        raise DataError(
            f"{name} = {x} is far too large (more than 2**40); sizes must fit the data: "
            f"choose a {name} much smaller than the number of samples"
        )
    if hi is not None:
        want = f"an integer between {lo} and {hi}"
    elif lo == 1:
        want = "a positive integer"
    else:
        want = f"an integer >= {lo}"
    raise DataError(f"{name} must be {alt + ' or ' if alt else ''}{want}, got {given!r}")


def as_seed(seed: Any, name: str = "seed") -> int:
    """A random seed: a Python or NumPy integer (not a bool) in ``[0, 2**64)``.

    Examples
    --------
    >>> from sysid._checks import as_seed
    >>> as_seed(7)
    7
    """
    ok = isinstance(seed, (int, np.integer)) and not isinstance(seed, (bool, np.bool_))
    if ok and 0 <= seed < 2**64:
        return int(seed)
    raise DataError(f"{name} must be a non-negative integer (below 2**64), got {seed!r}")


def as_nonnegative(x: Any, name: str) -> float:
    """Return a real argument (a Python or NumPy number, not a bool) that is finite and
    ``>= 0``, as a float; the message names the argument."""
    ok = isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(
        x, (bool, np.bool_))
    if ok and np.isfinite(x) and x >= 0:
        return float(x)
    raise DataError(f"{name} must be a finite number >= 0, got {x!r}")


def as_real(x: Any, name: str, *, positive: bool = False) -> float:
    """Return a real argument (a Python or NumPy number, not a bool) that is finite (and
    ``> 0`` if ``positive``), as a float; the :class:`DataError` names the argument.

    Examples
    --------
    >>> from sysid._checks import as_real
    >>> as_real(2, "mean")
    2.0
    >>> as_real(float("inf"), "mean")
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: mean must be a finite number, got inf
    """
    ok = isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(
        x, (bool, np.bool_))
    if ok and np.isfinite(x) and (x > 0 or not positive):
        return float(x)
    raise DataError(f"{name} must be a finite{' positive' if positive else ''} number, "
                    f"got {x!r}")


def as_between(x: Any, name: str, lo: float, hi: float, *, closed: str = "neither") -> float:
    """Return a real argument (a Python or NumPy number, not a bool, not NaN) in the interval
    from ``lo`` to ``hi``, as a float; ``closed`` says which ends belong to it (``"neither"``,
    ``"left"``, ``"right"`` or ``"both"``). The :class:`DataError` names the argument and the
    interval, for tolerances, fractions and confidence levels.

    Examples
    --------
    >>> from sysid._checks import as_between
    >>> as_between(0.9, "min_mac", 0.0, 1.0, closed="both")
    0.9
    >>> as_between(float("nan"), "confidence", 0.0, 1.0)
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: confidence must be a number in (0, 1), got nan
    """
    left, right = closed in ("left", "both"), closed in ("right", "both")
    ok = isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(
        x, (bool, np.bool_))
    if ok and not np.isnan(x) and (lo <= x if left else lo < x) and (
            x <= hi if right else x < hi):
        return float(x)
    interval = f"{'[' if left else '('}{lo:g}, {hi:g}{']' if right else ')'}"
    raise DataError(f"{name} must be a number in {interval}, got {x!r}")


def stability_criteria(freq_tol: Any, damping_tol: Any, min_mac: Any
                       ) -> tuple[float, float, float]:
    """The criteria of a stabilisation diagram (``sysid.ssi``, ``sysid.era_stabilization``):
    relative frequency and damping tolerances (finite, ``>= 0``) and a MAC threshold in
    ``[0, 1]``; a NaN compared false and flagged no mode stable, without a word."""
    return (as_nonnegative(freq_tol, "freq_tol"), as_nonnegative(damping_tol, "damping_tol"),
            as_between(min_mac, "min_mac", 0.0, 1.0, closed="both"))


#: Largest array, in bytes, built for a length the caller chose (as in the Rust core).
MAX_BYTES = 1 << 32


def as_count(x: Any, name: str, bytes_per_item: int, lo: int = 1) -> int:
    """An integer length ``>= lo`` whose array (``bytes_per_item`` each) fits in memory."""
    n = as_int(x, name, lo)
    if n * max(1, bytes_per_item) > MAX_BYTES:
        raise DataError(
            f"{name} = {n} would need {n * bytes_per_item / 2**30:.1f} GiB, more than the "
            f"{MAX_BYTES >> 30} GiB limit; choose a smaller {name}"
        )
    return n


#: Most float64 values (a complex value counts two) one call builds for a size the caller
#: chose: 2**28, 2 GiB, far beyond any sensible frequency grid, horizon or resampled record.
MAX_ELEMENTS = 2**28


def check_elements(n_elements: int, what: str, fix: str) -> None:
    """Refuse, before allocating, a request whose arrays would hold ``n_elements`` float64
    values (count a complex value as two) when that exceeds :data:`MAX_ELEMENTS` (2**28
    values, 2 GiB): a :class:`DataError` naming the request (``what``), the memory it would
    take, and what to pass instead (``fix``).

    Examples
    --------
    >>> from sysid._checks import check_elements
    >>> check_elements(10**6, "n_freq = 1000000", "pass a smaller n_freq")
    >>> check_elements(10**9, "n_freq = 1000000000", "pass a smaller n_freq")
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: n_freq = 1000000000 would allocate 1e+09 values (7.45 GiB), ...
    """
    n = int(n_elements)
    if n > MAX_ELEMENTS:
        raise DataError(
            f"{what} would allocate {n:.3g} values ({8 * n / 2**30:.3g} GiB), beyond the "
            f"limit of {MAX_ELEMENTS:.3g} ({8 * MAX_ELEMENTS >> 30} GiB) for one call; {fix}")


def as_int_grid(v: Any, shape: tuple[int, int], name: str) -> list[list[int]]:
    """Non-negative integer orders/delays as a ``shape`` grid (a scalar fills it).

    Bools, fractions, negatives, values above :data:`MAX_SIZE` and wrong shapes raise a
    :class:`DataError` naming ``name``.
    """
    try:
        a = np.array(v, dtype=object)
    except (TypeError, ValueError):
        raise DataError(f"{name} must be a non-negative integer or an array of them, "
                        f"got {v!r}") from None
    if a.ndim == 0:
        a = np.full(shape, a.item(), dtype=object)
    elif a.ndim == 1 and shape[0] == 1:
        a = a.reshape(1, -1)
    if a.shape != shape:
        raise ShapeError(f"{name} has shape {a.shape} but should be {shape} or a scalar")
    out = []
    for row in a.tolist():
        r = []
        for x in row:
            integral = isinstance(x, (int, np.integer)) or (
                isinstance(x, (float, np.floating)) and np.isfinite(x) and float(x).is_integer()
            )
            if isinstance(x, (bool, np.bool_)) or not integral or x < 0:
                raise DataError(f"{name} must hold non-negative integers, got {a.tolist()}")
            if x > MAX_SIZE:
                raise DataError(
                    f"{name} = {int(x)} is far too large (more than 2**40); orders and delays "
                    "must be much smaller than the number of samples"
                )
            r.append(int(x))
        out.append(r)
    return out


def check_covariance(P: np.ndarray, name: str) -> np.ndarray:
    """A covariance matrix: symmetric (to round-off) and positive semi-definite."""
    scale = max(float(np.max(np.abs(P))), np.finfo(float).tiny) if P.size else 1.0
    asym = float(np.max(np.abs(P - P.T))) if P.size else 0.0
    if asym > 1e-8 * scale:
        raise DataError(
            f"{name} must be symmetric, but {name} - {name}.T has entries of size {asym:.3g}; "
            f"pass (P + P.T) / 2 if the asymmetry is round-off")
    P = 0.5 * (P + P.T)
    low = float(np.min(np.linalg.eigvalsh(P))) if P.size else 0.0
    if low < -1e-10 * scale:
        raise DataError(
            f"{name} must be positive semi-definite (a covariance), but it has the negative "
            f"eigenvalue {low:.3g}")
    return P


def experiment_arrays(data: Any) -> list[tuple[np.ndarray, np.ndarray]]:
    """The experiments of an IOData record as C-contiguous float64 ``(u, y)`` pairs (views when
    they already are); a clear DataError for anything that is not an IOData record.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid._checks import experiment_arrays
    >>> data = sysid.IOData(np.ones((5, 1)), np.ones(5))
    >>> [(u.shape, y.shape) for u, y in experiment_arrays(data)]
    [((5, 1), (5, 1))]
    """
    refuse_frd(data, "this estimator")
    try:
        exps = data.experiments
    except AttributeError:
        raise errors.not_a_record(data) from None
    return [(np.ascontiguousarray(u, float), np.ascontiguousarray(y, float)) for u, y in exps]


#: A channel is constant when its samples lie within this fraction of its largest
#: ``|value|`` of one level (:func:`constant_channels`): far above what arithmetic leaves of
#: a constant (round-off, 1e-16 of it), far below what a measurement varies by (a 24-bit
#: converter resolves 6e-8 of its range). A channel of 1 + 1e-13 noise was refused by the
#: spectral estimates and taken by ``oe`` (the time-domain check compared samples exactly).
CONSTANT_TOL = 1e-12


def constant_channels(arrays: list[np.ndarray], about: str = "each") -> np.ndarray:
    """Per column of the ``(samples, channels)`` arrays (one per experiment), whether the
    channel is constant (:data:`CONSTANT_TOL`): about each experiment's own level
    (``"each"``: no variation within any experiment, hence no spectrum) or about one level
    in every experiment (``"all"``: a channel at other levels in other experiments still
    moves what it drives); used by the estimators and the spectral estimates.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid._checks import constant_channels
    >>> parts = [np.array([[1.0, 0.0], [1.0, 1.0]]), np.array([[2.0, 0.0], [2.0 + 1e-15, 0.5]])]
    >>> constant_channels(parts).tolist(), constant_channels(parts, "all").tolist()
    ([True, False], [False, False])
    """
    parts = [np.asarray(a, float) for a in arrays if len(a)]
    if not parts:
        return np.zeros(arrays[0].shape[1] if len(arrays) else 0, dtype=bool)
    mag = np.max([np.max(np.abs(a), axis=0) for a in parts], axis=0)
    scaled = [a / np.where(mag > 0, mag, 1.0) for a in parts]  # no overflow, no underflow
    if about == "all":
        spread = np.max([a.max(0) for a in scaled], 0) - np.min([a.min(0) for a in scaled], 0)
    else:
        spread = np.max([np.ptp(a, axis=0) for a in scaled], axis=0)
    return spread <= CONSTANT_TOL


def require_samples(lengths: list[int], who: str) -> None:
    """Refuse (``InsufficientDataError``) a record of one sample per experiment, for ``who``."""
    if lengths and max(lengths) < 2:
        raise errors.InsufficientDataError(
            f"too few samples: each experiment has one sample, too few for {who}; give a "
            "longer record")


def require_inputs_vary(exps: list[tuple[np.ndarray, np.ndarray]], who: str,
                        names: Any = None, side: int = 0, error: type = DataError) -> None:
    """Refuse a record in which an input (``side=1``: an output) is constant in every
    experiment, at one level (:func:`constant_channels`): the dynamics ``who`` estimates
    would not be determined by the data; ``error``: the :class:`DataError` raised.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid._checks import require_inputs_vary
    >>> require_inputs_vary([(np.zeros((5, 1)), np.ones((5, 1)))], "bj")
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: input u0 is 0 in every sample: bj cannot estimate ...
    """
    kind = ("input", "output")[side]
    require_samples([len(e[side]) for e in exps], who)  # else every channel "constant"
    flat = constant_channels([e[side] for e in exps], "all")
    for j in np.flatnonzero(flat):
        first = next(e[side][0, j] for e in exps if len(e[side]))
        name = names[j] if names is not None and j < len(names) else f"{'uy'[side]}{j}"
        fix = ("drop it (data.select), or fit an output-only model (sysid.ar, sysid.arma)"
               if side == 0 else "drop it (data.select)")
        raise error(f"{kind} {name} is {first:g} in every sample: {who} cannot estimate "
                    f"{'how the output responds to it' if side == 0 else 'its dynamics'}"
                    f"; check the channel (the wrong column, a stuck "
                    f"{'actuator' if side == 0 else 'sensor'}?), {fix}")
    if side == 0:
        require_independent_inputs(exps, who, names, error)


def require_independent_inputs(exps: list[tuple[np.ndarray, np.ndarray]], who: str,
                               names: Any = None, error: type = ExcitationError) -> None:
    """Refuse inputs that are linearly dependent in every sample (a channel recorded twice,
    one a multiple or a sum of others): no estimator can tell their effects apart (``arx``
    and the subspace methods refused them by rank, ``oe``, ``armax``, ``pbsid``, ``nlarx``
    and others returned a model). Names the channels of the dependence; part of
    :func:`require_inputs_vary`.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid._checks import require_independent_inputs
    >>> x = np.arange(6.0)[:, None]
    >>> require_independent_inputs([(np.hstack([x, 2 * x]), x)], "oe")
    Traceback (most recent call last):
    ...
    sysid.errors.ExcitationError: inputs u0, u1 are linearly dependent in every sample ...
    """
    from ._dependence import TOL, input_dependence

    found = input_dependence([u for u, _ in exps])
    if found is None:
        return  # independent (overflow and all-zero channels have their own checks)
    w, v, d = found
    m = v.size
    involved = [j for j in range(m) if abs(v[j]) > 1e-3 * np.abs(v).max()]
    label = [names[j] if names is not None and j < len(names) else f"u{j}" for j in involved]
    r, n = int(np.sum(w > TOL * w[-1])), sum(len(u) for u, _ in exps)
    centred = np.all(np.abs(sum(u.sum(axis=0) for u, _ in exps)) <= 1e-9 * d * np.sqrt(n))
    # an ExcitationError (a DataError) whichever the caller raises for a constant channel
    raise (error if issubclass(error, ExcitationError) else ExcitationError)(
        f"inputs {', '.join(label)} " + (f"lie on one line or plane about their means in every "
        f"sample (rank {r} with the means removed: one is a constant "
        "plus a combination of the others)" if centred else f"are linearly dependent in every "
        f"sample (the {m} inputs have rank {r}: one is a combination of the others, a channel "
        f"recorded twice?)") + f": {who} cannot tell their effects apart; drop one of them "
        "(data.select) or record them excited independently")


#: Largest ``|value|`` of a channel an estimator accepts: every sum of products of samples
#: (covariances, Gram matrices, costs) stays far from double-precision overflow (1.8e308).
MAX_MAGNITUDE = 1e150
#: Smallest largest-``|value|`` of a varying channel an estimator accepts: the squares of its
#: samples stay far above double-precision underflow (2.2e-308).
MIN_MAGNITUDE = 1e-150


def record_stats(data: Any) -> dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """``(abs_max, mean, std)`` per channel of the inputs (key 0) and the outputs (key 1) of
    every experiment of ``data`` (a record, or a list of ``(u, y)`` arrays) with samples, one
    pass of the Rust core each; a side without
    channels or samples is left out. Shared by the checks records meet on entering an
    estimator (:func:`check_magnitudes`, the offset and constant-channel checks), so that
    they read the record once.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid._checks import record_stats
    >>> s = record_stats(sysid.IOData(u=np.array([1.0, -3.0]), y=np.array([2.0, 4.0])))
    >>> s[0][0].tolist(), s[1][1].tolist(), s[1][2].tolist()
    ([3.0], [3.0], [1.0])
    """
    out = {}
    for idx in (0, 1):
        parts = [np.ascontiguousarray(e[idx], float) for e in _pairs(data) if len(e[idx])]
        if parts and parts[0].shape[1]:
            out[idx] = tuple(np.asarray(x) for x in _sysid.channel_stats(parts))
    return out


def _pairs(data: Any) -> list[Any]:
    """The ``(u, y)`` experiments of a record, or ``data`` itself when it is a list of them."""
    return data if isinstance(data, list) else data.experiments


def check_magnitudes(data: Any, who: str = "identification",
                     stats: dict[int, Any] | None = None) -> None:
    """Refuse a record with a channel whose magnitude makes products of its samples overflow
    or underflow double precision: largest ``|value|`` above :data:`MAX_MAGNITUDE`, or a
    varying channel whose largest ``|value|`` is below :data:`MIN_MAGNITUDE` (a zero or
    constant channel is left to the estimators' own, more specific checks). The one range
    check of records entering an estimator (called by :func:`sysid.data.offsets.check_offsets`);
    ``data`` is a record or a list of ``(u, y)`` arrays. The :class:`DataError` names the
    channel, its magnitude and the fix (rescale it).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid._checks import check_magnitudes
    >>> check_magnitudes(sysid.IOData(u=np.arange(5.0) * 1e12, y=np.arange(5.0) * 1e-12))
    >>> check_magnitudes(sysid.IOData(u=np.arange(5.0), y=np.arange(5.0) * 1e200))
    Traceback (most recent call last):
    ...
    sysid.errors.DataError: output y0 has values of order 4e+200, outside the range ...
    """
    stats = record_stats(data) if stats is None else stats
    for kind, idx in (("output", 1), ("input", 0)):
        if idx not in stats:
            continue
        big = stats[idx][0]
        names = getattr(data, f"{kind}_names", None) or [
            f"{'uy'[idx]}{j}" for j in range(len(big))]
        for j, name in enumerate(names):
            b = float(big[j])
            if b > MAX_MAGNITUDE:
                side = "overflow"
            elif 0 < b < MIN_MAGNITUDE and not _constant(data, idx, j):
                side = "underflow"
            else:
                continue
            raise DataError(
                f"{kind} {name} has values of order {b:.0e}, outside the range sysid "
                f"computes with (|values| between {MIN_MAGNITUDE:g} and {MAX_MAGNITUDE:g}: "
                f"products of its samples {side} double precision); {who} cannot use it: "
                "rescale the channel to order 1 first: sysid.scale(data, 'max') (its "
                "standard deviation overflows too), or the data in other units"
            )


def _constant(data: Any, idx: int, j: int) -> bool:
    """Whether channel ``j`` of side ``idx`` holds one value in every sample
    (:func:`constant_channels`; its standard deviation of tiny values can underflow to 0
    while it varies: compared scaled)."""
    return bool(constant_channels([e[idx][:, j:j + 1] for e in _pairs(data)], "all")[0])


def user_stacklevel() -> int:
    """``stacklevel`` for the caller's ``warnings.warn`` that points at the first frame outside
    sysid and contextlib (the user's line, however deep inside sysid the warning is raised).

    Examples
    --------
    >>> from sysid._checks import user_stacklevel
    >>> user_stacklevel() >= 1
    True
    """
    import contextlib
    import os
    import sys

    skip = (os.path.dirname(os.path.abspath(__file__)) + os.sep, contextlib.__file__)
    frame, level = sys._getframe(1), 1
    while frame is not None and frame.f_code.co_filename.startswith(skip):
        frame, level = frame.f_back, level + 1
    return level


def reissue(said: Any) -> None:
    """Show recorded warnings (``warnings.catch_warnings(record=True)``) again, each distinct
    one once, at the user's line (:func:`user_stacklevel`): the warnings of the fit a
    function returns, not of those it tried and left out.

    Examples
    --------
    >>> import warnings
    >>> from sysid._checks import reissue
    >>> with warnings.catch_warnings(record=True) as said:
    ...     warnings.simplefilter("always")
    ...     for _ in range(2):
    ...         warnings.warn("stopped at max_iter")
    >>> with warnings.catch_warnings(record=True) as shown:
    ...     warnings.simplefilter("always")
    ...     reissue(said)
    >>> [str(w.message) for w in shown]
    ['stopped at max_iter']
    """
    seen = set()
    for w in said:
        key = (type(w.message), str(w.message))
        if key not in seen:
            seen.add(key)
            warnings.warn(w.message, stacklevel=user_stacklevel())


def recorded(fit: Callable[[], Any]) -> tuple[Any, list[warnings.WarningMessage]]:
    """``fit()`` and the warnings it gave, recorded instead of shown (shown, by
    :func:`reissue`, when it fails): for a function that tries several fits and returns one,
    then shows only that one's warnings.

    Examples
    --------
    >>> import warnings
    >>> from sysid._checks import recorded
    >>> out, said = recorded(lambda: warnings.warn("stopped at max_iter") or 3)
    >>> out, [str(w.message) for w in said]
    (3, ['stopped at max_iter'])
    """
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        err: BaseException | None = None
        try:
            out = fit()
        except BaseException as e:  # noqa: BLE001 - re-raised below, after its warnings
            err = e
    if err is not None:
        reissue(said)
        raise err
    return out, list(said)
