"""Online estimators updated one sample at a time: :class:`RecursiveARX`,
:class:`RecursiveARMAX`, :class:`RecursiveOE` and :class:`RecursiveBJ` (MATLAB's
``recursiveARX`` family), on the Rust core ``sysid_core::recursive``."""

from .estimators import (
    RecursiveARMAX,
    RecursiveARX,
    RecursiveBJ,
    RecursiveOE,
    RecursiveResult,
)

__all__ = ["RecursiveARX", "RecursiveARMAX", "RecursiveOE", "RecursiveBJ", "RecursiveResult"]
