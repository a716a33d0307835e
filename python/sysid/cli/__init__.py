"""The ``sysid`` command line (usage: :data:`sysid.cli.parser.USAGE`, ``sysid --help``).

:func:`main` parses the arguments (:mod:`~sysid.cli.parser`) and runs a subcommand
(:mod:`~sysid.cli.demo_command`, :mod:`~sysid.cli.identify_command`: the record read by
:mod:`~sysid.cli.load` and :mod:`~sysid.cli.time_column`, fitted by
:mod:`~sysid.cli.pipeline`), its warnings and errors printed one line each
(:mod:`~sysid.cli.messages`).
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Sequence

from ..errors import SysidError
from .load import read_columns, read_csv
from .messages import _SHOWN, _one_line, _show_warning
from .parser import _parser
from .pipeline import identify

__all__ = ["main", "read_csv", "read_columns", "identify"]


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``sysid`` command: errors become one readable line and exit code 2."""
    args = _parser().parse_args(argv)
    try:
        with warnings.catch_warnings():
            _SHOWN.clear()
            warnings.showwarning = _show_warning  # one line each, no source line
            return int(args.func(args))
    except (SysidError, ImportError) as e:
        print(f"sysid: error: {_one_line(e)}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"sysid: error: {_one_line(e)}", file=sys.stderr)
        return 2
    except Exception as e:  # noqa: BLE001 - every CLI failure is one line and exit 2
        print(f"sysid: error: unexpected {type(e).__name__}: {_one_line(e)} (please report "
              "this with the command line)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        # Ctrl-C: the computation stopped, every file written so far is whole (sysid._atomic)
        print("sysid: interrupted (KeyboardInterrupt); files already written are complete",
              file=sys.stderr)
        return 130



if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
