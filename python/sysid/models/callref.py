"""References to importable functions (``"module:qualname"``), for saving models whose
equations are user code (a :class:`sysid.NonlinearGreyBox`'s ``f`` and ``h``).

Code is never written into a model file: a function is saved by where it can be imported
from and imported again on load. That works for functions defined with ``def`` at the top
level of an importable module (or as a static/class attribute inside one); lambdas, nested
functions and functions of a script or notebook (``__main__``) cannot be found by another
process, so saving them is refused with the fix.

Examples
--------
>>> import numpy as np
>>> from sysid.models.callref import callable_ref, resolve_ref
>>> callable_ref(np.sin, "f")
'numpy:sin'
>>> resolve_ref("numpy:sin", "f") is np.sin
True
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

from ..errors import DataError

__all__ = ["callable_ref", "resolve_ref"]

_FIX = ("define it with `def` at the top level of a module that can be imported (a .py file "
        "in your package or on sys.path) and import it from there before building the model")


def _lookup(module: str, qualname: str) -> Any:
    obj: Any = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return obj


def callable_ref(fn: Callable[..., Any], role: str) -> str:
    """``"module:qualname"`` of ``fn``, checked to import back to ``fn`` itself; a
    :class:`~sysid.DataError` naming ``role`` and the fix otherwise.

    Examples
    --------
    >>> from sysid.models.callref import callable_ref
    >>> try:
    ...     callable_ref(lambda t, x, u, p: x, "f")
    ... except Exception as e:
    ...     print(str(e).split(":")[0])
    f is a lambda
    """
    module = getattr(fn, "__module__", None)
    qualname = getattr(fn, "__qualname__", None)
    name = f"{role} ({getattr(fn, '__name__', type(fn).__name__)})"
    if qualname is not None and "<lambda>" in qualname:
        raise DataError(f"{role} is a lambda: a saved model refers to its functions by "
                        f"'module:name' and re-imports them on load, which a lambda cannot "
                        f"be; {_FIX}")
    if qualname is None or module is None:
        raise DataError(f"{name} has no module and qualified name, so a saved model cannot "
                        f"refer to it: {_FIX}")
    if "<locals>" in qualname:
        raise DataError(f"{name} is defined inside another function ({module}:{qualname}) "
                        f"and cannot be imported on load; {_FIX}")
    if module == "__main__":
        raise DataError(f"{name} is defined in __main__ (a script or a notebook), which "
                        f"another session cannot import on load; {_FIX}")
    try:
        found = _lookup(module, qualname)
    except (ImportError, AttributeError) as e:
        raise DataError(f"{name} = {module}:{qualname} cannot be imported back ({e}); "
                        f"{_FIX}") from e
    if found is not fn and getattr(found, "__func__", None) is not getattr(fn, "__func__", fn):
        raise DataError(f"{name}: importing {module}:{qualname} gives another object than the "
                        f"function given (redefined or a bound method?); {_FIX}")
    return f"{module}:{qualname}"


def resolve_ref(ref: str, role: str) -> Callable[..., Any]:
    """The function ``"module:qualname"`` refers to; a :class:`~sysid.DataError` naming the
    function and what to do when it cannot be imported.

    Examples
    --------
    >>> from sysid.models.callref import resolve_ref
    >>> try:
    ...     resolve_ref("no_such_module_xyz:rhs", "f")
    ... except Exception as e:
    ...     print(str(e)[:52])
    cannot import f = no_such_module_xyz:rhs saved with
    """
    module, sep, qualname = str(ref).partition(":")
    if not sep or not module or not qualname:
        raise DataError(f"{role} is saved as {ref!r}, expected 'module:qualname'")
    try:
        fn = _lookup(module, qualname)
    except (ImportError, AttributeError) as e:
        raise DataError(f"cannot import {role} = {ref} saved with the model ({e}): make the "
                        f"module {module!r} importable before loading (install it, or add "
                        f"its folder to sys.path) and check that it still defines "
                        f"{qualname}") from e
    if not callable(fn):
        raise DataError(f"{role} = {ref} is not callable")
    return fn
