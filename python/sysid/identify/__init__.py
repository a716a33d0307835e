"""The automatic path: :func:`sysid.identify` (see :mod:`sysid.identify.core`), and the
order and feedthrough choices it shares with the estimators
(:mod:`sysid.validation.crossval`, :mod:`.structure`).

``sysid.identify`` is both this package and the function: the package is callable, so
``sysid.identify(data)`` works whichever was imported first.
"""

from __future__ import annotations

import sys as _sys
import types as _types
from typing import Any

from .core import identify
from .result import IdentifiedModel, IdentifyResult

__all__ = ["identify", "IdentifyResult", "IdentifiedModel"]


class _CallableModule(_types.ModuleType):
    def __call__(self, *args: Any, **kwargs: Any) -> IdentifyResult:
        return identify(*args, **kwargs)


_sys.modules[__name__].__class__ = _CallableModule
