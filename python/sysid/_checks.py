"""Argument checking shared by the public functions (one helper, SciPy style)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .errors import DataError, NonFiniteError, ShapeError


def as_2d(x: Any, name: str, *, ncols: int | None = None, allow_empty: bool = False) -> np.ndarray:
    """Return ``x`` as a float64 array shaped (samples, channels) without copying if possible.

    1-D input is read as one channel. Strings, objects, complex numbers, 3-D arrays and
    non-finite values raise a :class:`DataError` that names the argument.
    """
    if isinstance(x, (str, bytes)):
        raise ShapeError(f"{name} must be a numeric array, got a string")
    arr = np.asarray(x)
    if arr.dtype.kind not in "biuf":
        raise DataError(
            f"{name} must be a real numeric array, got dtype {arr.dtype}; convert it with "
            f"np.asarray({name}, dtype=float)"
        )
    arr = arr.astype(np.float64, copy=False)
    if arr.ndim == 1:
        arr = arr[:, None]
    elif arr.ndim == 0:
        raise ShapeError(f"{name} must be 1-D or 2-D (samples, channels), got a scalar")
    elif arr.ndim != 2:
        raise ShapeError(
            f"{name} must be 1-D or 2-D (samples, channels), "
            f"got {arr.ndim}-D with shape {arr.shape}"
        )
    if arr.shape[0] == 0 and not allow_empty:
        raise ShapeError(f"{name} has no samples (shape {arr.shape})")
    if ncols is not None and arr.shape[1] != ncols:
        raise ShapeError(f"{name} has shape {arr.shape} but should have {ncols} column(s)")
    if not np.isfinite(arr).all():
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise NonFiniteError(
            f"{name} has a non-finite value (NaN or Inf) at sample {bad[0]}, channel {bad[1]}; "
            "interpolate or cut it out before identification"
        )
    return arr


def as_matrix(x: Any, name: str, shape: tuple[int | None, int | None]) -> np.ndarray:
    """Return a finite float64 matrix, checking its shape (``None`` matches any size)."""
    if isinstance(x, (str, bytes)):
        raise ShapeError(f"{name} must be a numeric matrix, got a string")
    arr = np.asarray(x)
    if arr.dtype.kind not in "biuf":
        raise DataError(f"{name} must be real and numeric, got dtype {arr.dtype}")
    arr = np.atleast_2d(arr.astype(np.float64, copy=False))
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


def as_int(x: Any, name: str, lo: int = 1, hi: int | None = None, *, alt: str = "") -> int:
    """Return an integer argument (a Python or NumPy integer, not a bool) in ``[lo, hi]``.

    The message names the argument and the range; ``alt`` names another accepted value
    (e.g. ``"None (simulation)"``) that the caller has already handled.
    """
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
    raise DataError(f"{name} must be {alt + ' or ' if alt else ''}{want}, got {x!r}")


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
