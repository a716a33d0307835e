"""Saving and loading models: JSON (readable, exact) and NPZ (compact, NumPy).

A saved model keeps everything needed to use it again and to know where it came from: the
matrices ``A, B, C, D, K``, the noise covariance, the initial state, the sample time, the
channel names and the whole ``info`` dict, which by convention holds

- ``info["units"]``: ``{"inputs": [...], "outputs": [...]}`` physical units of the channels;
- ``info["preprocessing"]``: what was done to the data before fitting (means removed,
  detrending, filters, scaling, sample ranges), so the model can be applied to raw data;
- ``info["settings"]``: the estimator settings (method, horizon, order, flags);
- whatever the estimator recorded (method, singular values, Q, R, S, ...).

Arrays inside ``info`` survive the round trip as NumPy arrays (real or complex); floats are
written with full precision (JSON uses ``repr``), so a loaded model equals the saved one
exactly.

Examples
--------
>>> import os, tempfile, sysid
>>> units = {"units": {"inputs": ["V"], "outputs": ["degC"]}}
>>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1, info=units)
>>> path = os.path.join(tempfile.mkdtemp(), "m.json")
>>> sysid.save_model(m, path)
>>> sysid.load_model(path).info["units"]["outputs"]
['degC']
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Union

import numpy as np

from .._sysid import __version__
from ..errors import DataError
from .statespace import StateSpaceModel

__all__ = ["save_model", "load_model", "model_to_dict", "model_from_dict"]

FORMAT = "sysid-state-space-model"
VERSION = 1
PathLike = Union[str, "os.PathLike[str]"]


def _encode(x: Any) -> Any:
    """JSON-safe form of info values (arrays tagged so they come back as arrays)."""
    if isinstance(x, np.ndarray):
        if np.iscomplexobj(x):
            return {"__ndarray__": x.real.tolist(), "imag": x.imag.tolist(), "shape": x.shape}
        return {"__ndarray__": x.tolist(), "dtype": str(x.dtype), "shape": list(x.shape)}
    if isinstance(x, (np.floating, np.integer, np.bool_)):
        return x.item()
    if isinstance(x, complex):
        return {"__complex__": [x.real, x.imag]}
    if isinstance(x, dict):
        return {str(k): _encode(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_encode(v) for v in x]
    if isinstance(x, float) and not np.isfinite(x):
        return {"__float__": repr(x)}
    if x is None or isinstance(x, (bool, int, float, str)):
        return x
    return {"__repr__": repr(x)}


def _decode(x: Any) -> Any:
    if isinstance(x, dict):
        if "__ndarray__" in x:
            shape = tuple(x["shape"])
            if "imag" in x:
                return (np.asarray(x["__ndarray__"], float)
                        + 1j * np.asarray(x["imag"], float)).reshape(shape)
            return np.asarray(x["__ndarray__"], dtype=x.get("dtype", "float64")).reshape(shape)
        if "__complex__" in x:
            return complex(*x["__complex__"])
        if "__float__" in x:
            return float(x["__float__"])
        if "__repr__" in x and len(x) == 1:
            return x["__repr__"]
        return {k: _decode(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_decode(v) for v in x]
    return x


def model_to_dict(model: StateSpaceModel) -> dict[str, Any]:
    """A JSON-serialisable dict of the model (the content of a ``.json`` file)."""
    if not isinstance(model, StateSpaceModel):
        raise DataError(f"expected a sysid.StateSpaceModel, got {type(model).__name__}")

    def mat(a: np.ndarray | None) -> Any:
        return None if a is None else np.asarray(a, dtype=float).tolist()

    return {
        "format": FORMAT,
        "version": VERSION,
        "sysid_version": __version__,
        "nstates": model.nstates, "ninputs": model.ninputs, "noutputs": model.noutputs,
        "dt": model.dt,
        "A": mat(model.A), "B": mat(model.B), "C": mat(model.C), "D": mat(model.D),
        "K": mat(model.K), "noise_cov": mat(model.noise_cov),
        "x0": None if model.x0 is None else model.x0.tolist(),
        "input_names": list(model.input_names), "output_names": list(model.output_names),
        "info": _encode(model.info),
    }


def model_from_dict(d: dict[str, Any]) -> StateSpaceModel:
    """Inverse of :func:`model_to_dict`, checking the format tag and the shapes."""
    if not isinstance(d, dict) or d.get("format") != FORMAT:
        raise DataError(f"not a sysid model file (expected format {FORMAT!r})")
    if int(d.get("version", 0)) > VERSION:
        raise DataError(f"model file version {d['version']} is newer than this sysid "
                        f"understands ({VERSION}); upgrade sysid")
    n, m, l = int(d["nstates"]), int(d["ninputs"]), int(d["noutputs"])

    def arr(key: str, shape: tuple[int, int]) -> np.ndarray | None:
        v = d.get(key)
        return None if v is None else np.asarray(v, dtype=float).reshape(shape)

    return StateSpaceModel(
        arr("A", (n, n)), arr("B", (n, m)), arr("C", (l, n)), arr("D", (l, m)), arr("K", (n, l)),
        dt=float(d["dt"]), noise_cov=arr("noise_cov", (l, l)),
        x0=None if d.get("x0") is None else np.asarray(d["x0"], dtype=float),
        input_names=d.get("input_names"), output_names=d.get("output_names"),
        info=_decode(d.get("info") or {}),
    )


def _format(path: Path, fmt: str | None) -> str:
    key = (fmt or path.suffix.lstrip(".")).lower()
    if key not in ("json", "npz"):
        raise DataError(f"unknown model file format {key!r} for {str(path)!r}; "
                        "use a .json or .npz file name or format='json'/'npz'")
    return key


def save_model(model: StateSpaceModel, path: PathLike, *, format: str | None = None) -> None:
    """Write a model to ``path`` as JSON or NPZ (chosen by the extension or ``format``).

    NPZ stores the matrices as arrays and the metadata (names, dt, info) as a JSON string;
    it is loaded without pickle.
    """
    path = Path(path)
    fmt = _format(path, format)
    d = model_to_dict(model)
    if fmt == "json":
        path.write_text(json.dumps(d, indent=1) + "\n", encoding="utf-8")
        return
    arrays = {k: np.asarray(d[k], dtype=float) for k in ("A", "B", "C", "D")}
    for k in ("K", "noise_cov", "x0"):
        if d[k] is not None:
            arrays[k] = np.asarray(d[k], dtype=float)
    meta = {k: v for k, v in d.items() if k not in arrays and k not in ("K", "noise_cov", "x0")}
    payload: dict[str, Any] = {"__meta__": np.array(json.dumps(meta)), **arrays}
    with open(path, "wb") as f:
        np.savez(f, **payload)


def load_model(path: PathLike, *, format: str | None = None) -> StateSpaceModel:
    """Read a model written by :func:`save_model`."""
    path = Path(path)
    fmt = _format(path, format)
    if not path.exists():
        raise FileNotFoundError(f"no model file at {str(path)!r}")
    if fmt == "json":
        try:
            d = json.loads(path.read_text(encoding="utf-8"))
        except json.JSONDecodeError as e:
            raise DataError(f"{str(path)!r} is not valid JSON: {e}") from e
        return model_from_dict(d)
    with np.load(path, allow_pickle=False) as z:
        if "__meta__" not in z:
            raise DataError(f"{str(path)!r} is not a sysid model file (no metadata)")
        d = json.loads(str(z["__meta__"]))
        for k in ("A", "B", "C", "D", "K", "noise_cov", "x0"):
            d[k] = z[k] if k in z else None
    return model_from_dict(d)
