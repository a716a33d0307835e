"""Files written whole or not at all.

Every file sysid writes (models, report pages and tables, the command line's outputs, the
Parquet parts of :func:`sysid.identify_many`) is first written to a hidden temporary file in
the same folder and then renamed over its target (``os.replace``, atomic on POSIX and
Windows within one file system). An error or Ctrl-C midway removes the temporary file and
leaves the target as it was: a reader never sees half a file.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["atomic_path", "write_text"]


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary path beside ``path`` to write to; renamed over ``path`` when the block ends
    normally, removed when it raises (``KeyboardInterrupt`` included). A ``path`` whose folder
does not exist raises :class:`FileNotFoundError` naming ``path``.

    Examples
    --------
    >>> import os, tempfile
    >>> from pathlib import Path
    >>> from sysid._atomic import atomic_path
    >>> target = os.path.join(tempfile.mkdtemp(), "out.txt")
    >>> with atomic_path(target) as tmp:
    ...     _ = tmp.write_text("complete")
    >>> Path(target).read_text()
    'complete'
    >>> try:
    ...     with atomic_path(target) as tmp:
    ...         _ = tmp.write_text("half")
    ...         raise KeyboardInterrupt
    ... except KeyboardInterrupt:
    ...     pass
    >>> Path(target).read_text(), sorted(os.listdir(os.path.dirname(target)))
    ('complete', ['out.txt'])
    """
    path = Path(path)
    if not path.parent.is_dir():  # else the error names the hidden temporary file
        raise FileNotFoundError(
            f"cannot write {str(path)!r}: the folder {str(path.parent)!r} does not exist; "
            "create it first (os.makedirs) or choose another path")
    # hidden, and unique per process and thread: concurrent writers never share one
    tmp = path.with_name(f".{path.name}.{os.getpid()}-{threading.get_ident()}.tmp")
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_text(path: str | Path, text: str, encoding: str = "utf-8") -> None:
    """Write ``text`` to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding=encoding)
