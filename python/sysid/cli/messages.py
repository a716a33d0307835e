"""The command's warning and error lines on stderr: one line each, a warning once."""

from __future__ import annotations

import sys
from typing import Any

#: the warning lines printed by this run: the validation's residual test and the report's
#: both test the same residuals, and a warning said once is enough
_SHOWN: set[str] = set()


def _show_warning(message: Any, category: type[Warning], *_: Any, **__: Any) -> None:
    line = f"sysid: warning: {category.__name__}: {' '.join(str(message).split())}"
    if line not in _SHOWN:
        _SHOWN.add(line)
        print(line, file=sys.stderr)


def _one_line(e: BaseException) -> str:
    return " ".join(str(e).split()) or type(e).__name__

