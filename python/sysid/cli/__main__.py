"""``python -m sysid.cli``: the command line (as ``python -m sysid``)."""

import sys

from . import main

if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
