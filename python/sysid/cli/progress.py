"""The command's progress: stage lines with elapsed time, and whether to draw bars."""

from __future__ import annotations

import argparse
import sys
import time


class _Progress:
    """Stage lines on stderr with elapsed time (quiet mode prints nothing)."""

    def __init__(self, quiet: bool) -> None:
        self.quiet, self.t0 = quiet, time.perf_counter()

    def __call__(self, msg: str) -> None:
        if not self.quiet:
            print(f"[sysid {time.perf_counter() - self.t0:6.1f} s] {msg}", file=sys.stderr,
                  flush=True)


def _bars(args: argparse.Namespace) -> bool | None:
    """Progress bars: asked (--progress), silenced (--quiet), else on a terminal only."""
    return True if args.progress else False if args.quiet else None

