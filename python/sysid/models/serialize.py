"""Saving models: a versioned format with one entry per model family, and a registry.

A saved model is a dict ``{"format": "sysid-model", "version": 2, "family": NAME,
"sysid_version": ..., **model.to_dict()}``. ``NAME`` is the family's registered name
(:class:`~sysid.StateSpaceModel`, :class:`~sysid.ContinuousStateSpace` and
:class:`~sysid.PolynomialModel` are built in); :func:`sysid.load_model` finds the class by
that name and calls its ``from_dict``. Files of format version 1 (state-space only,
``"format": "sysid-state-space-model"``) still load.

Your own model class is saved the same way once it has ``to_dict()`` (a dict of arrays,
numbers, strings, lists and dicts) and a classmethod ``from_dict(d)``, and is registered:

>>> import numpy as np, sysid
>>> @sysid.register_model
... class Gain:
...     def __init__(self, k):
...         self.k = float(k)
...     def to_dict(self):
...         return {"k": self.k}
...     @classmethod
...     def from_dict(cls, d):
...         return cls(d["k"])
>>> sysid.model_from_dict(sysid.model_to_dict(Gain(2.5))).k
2.5

Arrays survive the JSON round trip exactly (floats are written with ``repr``), complex
arrays included; in a ``.npz`` file the top-level arrays are stored as NumPy arrays and the
rest as a JSON string (loaded without pickle).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, TypeVar, Union

import numpy as np

from .._atomic import atomic_path
from .._sysid import __version__
from ..errors import DataError

__all__ = ["register_model", "model_to_dict", "save_model", "FORMAT", "VERSION"]

FORMAT = "sysid-model"
VERSION = 2
PathLike = Union[str, "os.PathLike[str]"]
T = TypeVar("T", bound=type)

#: family name -> class (with ``to_dict``/``from_dict``)
REGISTRY: dict[str, type] = {}


def register_model(cls: T | None = None, *, name: str | None = None) -> Any:
    """Register a model class for :func:`sysid.save_model`/:func:`sysid.load_model`.

    The class needs a method ``to_dict()`` and a classmethod ``from_dict(d)``. Use as a
    decorator (``@sysid.register_model``) or call ``sysid.register_model(cls, name=...)``;
    ``name`` (default: the class name) is written into the file and must be unique (a
    class defined again under the same module and name replaces the old one). Returns the
    class.

    Examples
    --------
    >>> import sysid
    >>> class Delay:
    ...     def __init__(self, k):
    ...         self.k = int(k)
    ...     def to_dict(self):
    ...         return {"k": self.k}
    ...     @classmethod
    ...     def from_dict(cls, d):
    ...         return cls(d["k"])
    >>> sysid.register_model(Delay, name="example.Delay") is Delay
    True
    >>> sysid.model_to_dict(Delay(3))["family"]
    'example.Delay'
    """

    def add(c: T) -> T:
        if not isinstance(c, type):
            raise DataError(f"register_model takes a model class, got {type(c).__name__} "
                            f"{c!r}: decorate the class (@sysid.register_model) or call "
                            "sysid.register_model(MyModel, name=...)")
        if name is not None and (not isinstance(name, str) or not name):
            raise DataError(f"name must be a non-empty string, got {name!r}")
        for attr in ("to_dict", "from_dict"):
            if not callable(getattr(c, attr, None)):
                raise DataError(f"{c.__name__} has no {attr}(); a saved model class needs "
                                "to_dict() and a classmethod from_dict(d)")
        key = name or c.__name__
        old = REGISTRY.get(key)
        redefined = old is not None and (old.__module__, old.__qualname__) == (
            c.__module__, c.__qualname__)  # the same class defined again (a notebook cell)
        if old is not None and old is not c and not redefined:
            raise DataError(f"a model family named {key!r} is already registered "
                            f"({REGISTRY[key].__module__}); pass another name=")
        REGISTRY[key] = c
        return c

    return add if cls is None else add(cls)


#: families in their own modules (issues 27, 29; wrappers), registered when first imported
LAZY_FAMILIES = {"TransferFunction": "sysid.tf.model", "ProcessModel": "sysid.process.model",
                 "PNLSSModel": "sysid.nlss.pnlss",
                 "NeuralStateSpaceModel": "sysid.nlss.neural",
                 "NetworkNARXModel": "sysid.nonlinear.narx_network_model",
                 "IdentifiedModel": "sysid.identify.result",
                 "TrendedModel": "sysid.models.trended", "Trend": "sysid.data.trend",
                 "AugmentedInputModel": "sysid.nonlinear.augmented",
                 "NARXStateSpace": "sysid.nonlinear.narx_ss"}


def family_class(family: str) -> type:
    """The class registered as ``family`` (its module imported first when it registers
    itself on import, :data:`LAZY_FAMILIES`); a :class:`~sysid.DataError` for an unknown one.

    Examples
    --------
    >>> from sysid.models.serialize import family_class
    >>> family_class("TransferFunction").__name__   # its module imported on first use
    'TransferFunction'
    """
    cls = REGISTRY.get(family)
    if cls is None and family in LAZY_FAMILIES:
        import importlib

        importlib.import_module(LAZY_FAMILIES[family])
        cls = REGISTRY.get(family)
    if cls is None:
        raise DataError(f"unknown model family {family!r}: import the module that defines it "
                        "and register the class with sysid.register_model before loading")
    return cls


def family_name(model: Any) -> str:
    """The registered name of ``model``'s class (its class name if it is not registered)."""
    for key, c in REGISTRY.items():
        if type(model) is c:
            return key
    return type(model).__name__


def _encode(x: Any) -> Any:
    """JSON-safe form of values (arrays tagged so they come back as arrays)."""
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


def model_to_dict(model: Any) -> dict[str, Any]:
    """A JSON-serialisable dict of the model (the content of a ``.json`` file).

    Examples
    --------
    >>> import sysid
    >>> d = sysid.model_to_dict(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]))
    >>> d["format"], d["version"], d["family"]
    ('sysid-model', 2, 'StateSpaceModel')
    """
    to_dict = getattr(model, "to_dict", None)
    if not callable(to_dict):
        raise DataError(f"{type(model).__name__} cannot be saved: it has no to_dict() (save a "
                        "sysid.StateSpaceModel, ContinuousStateSpace, PolynomialModel, or give "
                        "your class to_dict()/from_dict() and sysid.register_model it)")
    from .uncertainty_io import body_with_uncertainty

    body = body_with_uncertainty(model)  # the parameter covariance travels with the model
    if not isinstance(body, dict):
        raise DataError(f"{type(model).__name__}.to_dict() must return a dict")
    head = {"format": FORMAT, "version": VERSION, "family": family_name(model),
            "sysid_version": __version__}
    clash = set(head) & set(body)
    if clash:
        raise DataError(f"{type(model).__name__}.to_dict() uses reserved keys {sorted(clash)}")
    return {**head, **_encode(body)}


def file_format(path: Path, fmt: str | None) -> str:
    """``"json"`` or ``"npz"`` from ``fmt`` or the file extension."""
    key = (fmt or path.suffix.lstrip(".")).lower()
    if key not in ("json", "npz"):
        raise DataError(f"unknown model file format {key!r} for {str(path)!r}; "
                        "use a .json or .npz file name or format='json'/'npz'")
    return key


def save_model(model: Any, path: PathLike, *, format: str | None = None) -> None:
    """Write any registered model to ``path`` as JSON or NPZ (by extension or ``format``).

    NPZ stores top-level arrays (the matrices) as arrays and everything else as a JSON
    string; it is loaded without pickle. See :func:`sysid.register_model` for own classes.

    Examples
    --------
    >>> import os, tempfile, sysid
    >>> m = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]])
    >>> path = os.path.join(tempfile.mkdtemp(), "m.npz")
    >>> sysid.save_model(m, path)
    >>> sysid.load_model(path)
    ContinuousStateSpace(nstates=1, ninputs=1, noutputs=1, stable)
    """
    path = Path(path)
    fmt = file_format(path, format)
    d = model_to_dict(model)
    # written whole or not at all: a failure (or Ctrl-C) midway leaves the previous file as it
    # was (see sysid._atomic)
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        if fmt == "json":
            f.write((json.dumps(d, indent=1) + "\n").encode("utf-8"))
        else:
            arrays = {k: _decode(v) for k, v in d.items()
                      if isinstance(v, dict) and "__ndarray__" in v}
            meta = {k: v for k, v in d.items() if k not in arrays}
            np.savez(f, __meta__=np.array(json.dumps(meta)), **arrays)


def read_model_file(path: PathLike, fmt: str | None) -> dict[str, Any]:
    """The dict stored in a model file, as written (tagged arrays not decoded; the top-level
    arrays of an NPZ file as arrays): :func:`sysid.model_from_dict` checks it, then decodes."""
    path = Path(path)
    key = file_format(path, fmt)
    if not path.exists():
        raise FileNotFoundError(f"no model file at {str(path)!r}")
    if key == "json":
        try:
            d = json.loads(path.read_text(encoding="utf-8"))
        except json.JSONDecodeError as e:
            raise DataError(f"{str(path)!r} is not valid JSON: {e}") from e
        if not isinstance(d, dict):
            raise DataError(f"{str(path)!r} is not a sysid model file")
        return d
    with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
        if not isinstance(z, np.lib.npyio.NpzFile) or "__meta__" not in z:
            raise DataError(f"{str(path)!r} is not a sysid model file (no metadata)")
        d = json.loads(str(z["__meta__"]))
        if not isinstance(d, dict):
            raise DataError(f"{str(path)!r} is not a sysid model file (metadata is not a dict)")
        for k in z.files:
            if k != "__meta__":
                d[k] = z[k]
    return d
