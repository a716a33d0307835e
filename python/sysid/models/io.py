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

import zipfile
from pathlib import Path
from typing import Any

from ..errors import DataError
from ..greybox.nlgreybox import NonlinearGreyBox
from ..nonlinear.hw_model import HammersteinWienerModel
from ..nonlinear.hw_ss_model import HammersteinWienerSSModel
from ..nonlinear.narx_model import NARXModel
from ..polynomial.model import PolynomialModel
from .continuous import ContinuousStateSpace
from .schema import check_file
from .serialize import (
    REGISTRY,
    VERSION,
    PathLike,
    _decode,
    family_class,
    model_to_dict,
    read_model_file,
    register_model,
    save_model,
)
from .statespace import StateSpaceModel

__all__ = ["save_model", "load_model", "model_to_dict", "model_from_dict", "register_model"]

for _cls in (StateSpaceModel, ContinuousStateSpace, PolynomialModel, NARXModel,
             HammersteinWienerModel, HammersteinWienerSSModel, NonlinearGreyBox):
    register_model(_cls)


def model_from_dict(d: dict[str, Any]) -> Any:
    """Inverse of :func:`sysid.model_to_dict`: the registered family's ``from_dict``.

    Checks the dict against the file schema first (:mod:`sysid.models.schema`: the format
    tag, the version, every array, and the body of the state-space families); version-1 files
    (state-space only) still load. Anything else raises one :class:`~sysid.DataError` "not a
    sysid model file: field <name>: found <what>, expected <what>".

    Examples
    --------
    >>> import sysid
    >>> m = sysid.PolynomialModel([[[-0.5]]], [[[1.0]]], [[1]], 0.1)
    >>> sysid.model_from_dict(sysid.model_to_dict(m)).simulate([1.0, 1.0, 1.0])[:, 0]
    array([0. , 1. , 1.5])
    """
    if isinstance(d, dict) and d and "format" not in d and "family" not in d:
        raise DataError(
            "this dict has no 'format' or 'family' field: it is a model's own to_dict() (the "
            "body of a file, without the header naming its family); rebuild it with that "
            "class's from_dict (e.g. sysid.StateSpaceModel.from_dict(d)), or pair "
            "sysid.model_to_dict(model) with sysid.model_from_dict(d)")
    family = check_file(d, VERSION)
    cls = family_class(family)
    try:
        body = {k: _decode(v) for k, v in d.items()}
        from .uncertainty_io import model_from_body

        return model_from_body(cls, body, REGISTRY)
    except KeyError as e:
        raise DataError(f"not a sysid model file: the {family} entry has no field "
                        f"{e.args[0]!r}") from None
    except (ValueError, TypeError, AttributeError, IndexError) as e:
        raise DataError(f"not a sysid model file: the {family} entry is inconsistent or "
                        f"damaged ({e})") from None


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
    p = Path(path)
    if format is None and p.suffix.lower() not in (".json", ".npz") and p.is_file():
        head = p.read_bytes()[:4]
        format = "npz" if head.startswith(b"PK") else "json" if head.lstrip()[:1] == b"{" else None
        if format is None:
            raise DataError(f"not a sysid model file: {str(p)!r} is neither JSON nor NPZ "
                            "(save models with sysid.save_model or model.save)")
    try:
        d = read_model_file(p, format)
    except FileNotFoundError:
        raise
    except DataError as e:
        msg = str(e)
        raise DataError(msg if msg.startswith("not a sysid model file")
                        else f"not a sysid model file: {msg}") from None
    except (UnicodeDecodeError, ValueError, OSError, zipfile.BadZipFile, KeyError,
            AttributeError, TypeError) as e:
        raise DataError(f"not a sysid model file: {str(p)!r} could not be read as "
                        f"{format or p.suffix.lstrip('.')} ({type(e).__name__}: {e})") from None
    return model_from_dict(d)
