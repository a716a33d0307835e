"""Saving and loading models: JSON (readable, exact) and NPZ (compact, NumPy).

The file format and the registry of model families are described in
:mod:`sysid.models.serialize`; this module registers the built-in families and reads files
back. A saved model keeps everything needed to use it again and to know where it came from:
its matrices or polynomials, sample time, channel names and the whole ``info`` dict, which
by convention holds

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

from typing import Any

from ..errors import DataError
from .continuous import ContinuousStateSpace
from .hammerstein import HammersteinWienerModel
from .narx import NARXModel
from .polynomial import PolynomialModel
from .serialize import (
    FORMAT,
    REGISTRY,
    VERSION,
    PathLike,
    _decode,
    model_to_dict,
    read_model_file,
    register_model,
    save_model,
)
from .statespace import StateSpaceModel

__all__ = ["save_model", "load_model", "model_to_dict", "model_from_dict", "register_model"]

LEGACY_FORMAT = "sysid-state-space-model"  # version 1: state-space models only

for _cls in (StateSpaceModel, ContinuousStateSpace, PolynomialModel, NARXModel,
             HammersteinWienerModel):
    register_model(_cls)


def model_from_dict(d: dict[str, Any]) -> Any:
    """Inverse of :func:`sysid.model_to_dict`: the registered family's ``from_dict``.

    Checks the format tag and the version; version-1 files (state-space only) still load.

    Examples
    --------
    >>> import sysid
    >>> m = sysid.PolynomialModel([[[-0.5]]], [[[1.0]]], [[1]], 0.1)
    >>> sysid.model_from_dict(sysid.model_to_dict(m)).simulate([1.0, 1.0, 1.0])[:, 0]
    array([0. , 1. , 1.5])
    """
    if not isinstance(d, dict) or d.get("format") not in (FORMAT, LEGACY_FORMAT):
        raise DataError(f"not a sysid model file (expected format {FORMAT!r})")
    version = int(d.get("version", 0))
    if version > VERSION:
        raise DataError(f"model file version {version} is newer than this sysid "
                        f"understands ({VERSION}); upgrade sysid")
    body = {k: _decode(v) for k, v in d.items()}
    family = "StateSpaceModel" if d["format"] == LEGACY_FORMAT else str(d.get("family"))
    cls = REGISTRY.get(family)
    if cls is None:
        raise DataError(f"unknown model family {family!r}: import the module that defines it "
                        "and register the class with sysid.register_model before loading")
    try:
        return cls.from_dict(body)  # type: ignore[attr-defined]
    except (KeyError, ValueError, TypeError) as e:
        if isinstance(e, DataError):
            raise
        raise DataError(f"the {family} entry of this model file is incomplete or damaged: "
                        f"{e!r}") from e


def load_model(path: PathLike, *, format: str | None = None) -> Any:
    """Read a model written by :func:`sysid.save_model` (any registered family).

    Examples
    --------
    >>> import os, tempfile, sysid
    >>> path = os.path.join(tempfile.mkdtemp(), "m.json")
    >>> sysid.save_model(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), path)
    >>> sysid.load_model(path)
    StateSpaceModel(nstates=1, ninputs=1, noutputs=1, dt=1, stable, no noise model)
    """
    return model_from_dict(read_model_file(path, format))
