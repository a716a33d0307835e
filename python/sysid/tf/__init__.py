"""Transfer-function models: :class:`TransferFunction` and :func:`tfest` (issue 27)."""

from .model import TransferFunction
from .tfest import tfest

__all__ = ["TransferFunction", "tfest"]
