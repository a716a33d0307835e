"""The schema of model files, checked before any model is built.

:func:`check_file` looks at the dict read from a JSON or NPZ file (tagged arrays not yet
decoded) and raises one :class:`~sysid.DataError` naming the field, what was found and what
was expected: the header (``format``, ``version``, ``family``), every tagged array anywhere in
the file (its ``shape`` against its values, numbers only), and for the state-space families the
whole body (sizes, matrix shapes agreeing with them, finite real entries, a positive sample
time, channel names). Other families get the header and array checks; their ``from_dict``
checks the rest.

Examples
--------
>>> import sysid
>>> from sysid.models.schema import check_file
>>> d = sysid.model_to_dict(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]))
>>> d["dt"] = -1.0
>>> check_file(d, 2)
Traceback (most recent call last):
...
sysid.errors.DataError: not a sysid model file: field 'dt': found -1.0, expected a finite ...
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import DataError
from .serialize import FORMAT

__all__ = ["check_file", "LEGACY_FORMAT"]

LEGACY_FORMAT = "sysid-state-space-model"  # version 1: state-space models only
_DTYPES = ("float64", "float32", "int64", "int32", "bool", "complex128")


def _fail(field: str, found: Any, expected: str) -> DataError:
    shown = repr(found)
    if len(shown) > 60:
        shown = shown[:57] + "..."
    return DataError(f"not a sysid model file: field {field!r}: found {shown}, expected {expected}")


def _kind(x: Any) -> str:
    if isinstance(x, np.ndarray):
        return f"an array of shape {x.shape}"
    return f"a {type(x).__name__}"


def check_header(d: Any, version: int) -> str:
    """Check ``format``, ``version`` and ``family``; returns the family name."""
    if not isinstance(d, dict):
        raise DataError(f"not a sysid model file: expected a JSON object, found {_kind(d)}")
    fmt = d.get("format")
    if fmt not in (FORMAT, LEGACY_FORMAT):
        raise _fail("format", fmt, f"{FORMAT!r}")
    v = d.get("version")
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise _fail("version", v, f"an integer 1..{version}")
    if v > version:
        raise DataError(f"not a sysid model file: field 'version': found {v}, expected at most "
                        f"{version} (the file was written by a newer sysid; upgrade sysid)")
    if fmt == LEGACY_FORMAT:
        return "StateSpaceModel"
    family = d.get("family")
    if not isinstance(family, str) or not family:
        raise _fail("family", family, "the name of a model family (a string)")
    return family


def check_arrays(x: Any, where: str) -> None:
    """Every tagged array (``{"__ndarray__": ..., "shape": ...}``) inside ``x`` is
    well formed: numbers only, as many as its shape says."""
    if isinstance(x, list):
        for k, v in enumerate(x):
            check_arrays(v, f"{where}[{k}]")
        return
    if not isinstance(x, dict):
        return
    if "__ndarray__" not in x:
        for k, v in x.items():
            check_arrays(v, f"{where}.{k}" if where else str(k))
        return
    shape = x.get("shape")
    if not isinstance(shape, list) or not all(
            isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in shape):
        raise _fail(f"{where}.shape", shape, "a list of non-negative integers")
    dtype = x.get("dtype", "float64")
    if dtype not in _DTYPES:
        raise _fail(f"{where}.dtype", dtype, f"one of {_DTYPES}")
    parts = [x["__ndarray__"]] + ([x["imag"]] if "imag" in x else [])
    for part in parts:
        flat: list[Any] = []
        stack = [part]
        while stack:
            v = stack.pop()
            if isinstance(v, list):
                stack.extend(v)
            else:
                flat.append(v)
        bad = next((v for v in flat if isinstance(v, str) or not isinstance(v, (int, float))),
                   None)
        if bad is not None:
            raise _fail(where, bad, "numbers only in an array")
        if len(flat) != math.prod(shape):
            raise _fail(where, f"{len(flat)} values", f"{math.prod(shape)} (shape {shape})")


def _int(d: dict[str, Any], key: str) -> int:
    v = d.get(key)
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
        raise _fail(key, v, "a non-negative integer")
    return int(v)


def _matrix(d: dict[str, Any], key: str, shape: tuple[int, ...], what: str,
            required: bool = True) -> None:
    if key not in d or d[key] is None:
        if required:
            raise DataError(f"not a sysid model file: field {key!r} is missing (expected "
                            f"{what}, shape {shape})")
        return
    v = d[key]
    if isinstance(v, dict) and "__ndarray__" in v:
        got = tuple(v["shape"])
        if "imag" in v or v.get("dtype", "float64") == "bool":
            raise _fail(key, "complex or boolean values", f"real numbers ({what})")
        vals = np.asarray(v["__ndarray__"], dtype=float)
    elif isinstance(v, np.ndarray):
        got = v.shape
        if not np.issubdtype(v.dtype, np.number) or np.iscomplexobj(v):
            raise _fail(key, f"dtype {v.dtype}", f"real numbers ({what})")
        vals = v.astype(float)
    elif isinstance(v, list):  # version-1 files: plain nested lists
        try:
            vals = np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            raise _fail(key, v, f"{what}: a rectangular list of numbers") from None
        got = vals.shape if vals.size else shape
    else:
        raise _fail(key, _kind(v), f"{what}, shape {shape}")
    if got != shape:
        raise _fail(key, f"shape {got}", f"shape {shape} ({what})")
    if not np.all(np.isfinite(vals)):
        raise _fail(key, "NaN or infinite entries", f"finite numbers ({what})")


def _names(d: dict[str, Any], key: str, count: int) -> None:
    v = d.get(key)
    if v is None:
        return
    if not isinstance(v, list) or not all(isinstance(s, str) for s in v):
        raise _fail(key, v, f"a list of {count} strings")
    if len(v) != count:
        raise _fail(key, f"{len(v)} names", f"{count} (one per channel)")


def _dt(d: dict[str, Any]) -> None:
    v = d.get("dt")
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not (
            math.isfinite(v) and v > 0):
        raise _fail("dt", v, "a finite number > 0 (the sample time in seconds)")


def _shape_of(v: Any) -> tuple[int, ...] | None:
    if isinstance(v, dict) and "__ndarray__" in v:
        return tuple(v["shape"])
    if isinstance(v, np.ndarray):
        return v.shape
    return None


def check_statespace(d: dict[str, Any]) -> None:
    n, m, l = _int(d, "nstates"), _int(d, "ninputs"), _int(d, "noutputs")
    _dt(d)
    sizes = f"nstates={n}, ninputs={m}, noutputs={l}"
    for key, shape, req in (("A", (n, n), True), ("B", (n, m), True), ("C", (l, n), True),
                            ("D", (l, m), True), ("K", (n, l), False),
                            ("noise_cov", (l, l), False), ("x0", (n,), False)):
        _matrix(d, key, shape, f"{key} of a model with {sizes}", req)
    _names(d, "input_names", m)
    _names(d, "output_names", l)


def check_continuous(d: dict[str, Any]) -> None:
    shape = _shape_of(d.get("A"))
    if shape is None or len(shape) != 2 or shape[0] != shape[1]:
        raise _fail("A", shape if shape is not None else d.get("A"), "a square matrix")
    n = shape[0]
    sb, sc = _shape_of(d.get("B")), _shape_of(d.get("C"))
    m = sb[1] if sb is not None and len(sb) == 2 else 0
    l = sc[0] if sc is not None and len(sc) == 2 else 0
    sizes = f"{n} states, {m} inputs, {l} outputs"
    for key, sh in (("A", (n, n)), ("B", (n, m)), ("C", (l, n)), ("D", (l, m))):
        _matrix(d, key, sh, f"{key} of a model with {sizes}")
    hold = d.get("hold", "zoh")
    if hold not in ("zoh", "foh"):
        raise _fail("hold", hold, "'zoh' or 'foh'")
    _names(d, "input_names", m)
    _names(d, "output_names", l)


_BODIES = {"StateSpaceModel": check_statespace, "ContinuousStateSpace": check_continuous}


def check_file(d: Any, version: int) -> str:
    """Check a model file's dict against its schema (see the module); returns its family."""
    family = check_header(d, version)
    check_arrays({k: v for k, v in d.items() if k not in ("format", "version", "family")}, "")
    info = d.get("info")
    if info is not None and not isinstance(info, dict):
        raise _fail("info", _kind(info), "a dict (JSON object)")
    body = _BODIES.get(family)
    if body is not None:
        body(d)
    return family
