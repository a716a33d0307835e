"""Process models: :class:`ProcessModel` and :func:`procest` (issue 27)."""

from .model import ProcessModel
from .procest import procest

__all__ = ["ProcessModel", "procest"]
