"""Reading numeric text tables: CSV, semicolon, tab or white-space separated, with or
without a header row.

One reader for :meth:`sysid.IOData.from_csv` and the command line (``sysid.cli``), so that
both name the same columns and report a bad cell the same way: by file line and column.
The rows are kept as strings; :func:`numeric` converts the columns asked for.
"""

from __future__ import annotations

import bz2
import csv
import gzip
import itertools
import lzma
import math
import re
import zlib
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import IO, NamedTuple

import numpy as np

from ..errors import DataError

__all__: list[str] = []

_STREAM = {".gz": gzip.open, ".bz2": bz2.open, ".xz": lzma.open, ".lzma": lzma.open}
#: What a damaged or foreign compressed file raises while it is decompressed.
_UNREADABLE = (OSError, EOFError, lzma.LZMAError, zlib.error)
#: Bytes at the start of a file looked at for NUL bytes (binary content).
_SNIFF = 65536
#: The compression of a table file, by its suffix, as an error names it.
_KIND = {".gz": "gzip", ".bz2": "bzip2", ".xz": "xz", ".lzma": "lzma"}
#: Bytes of a file read at a time by the block readers (line counts, the comment filter).
_BLOCK = 1 << 20


class Header(NamedTuple):
    """A table's first kept line: column names, whether it is data, its file line, the
    delimiter and its number of fields (trailing empty ones included)."""

    names: list[str]
    headerless: bool
    line: int
    delimiter: str
    width: int


class Table(NamedTuple):
    """Column names, the rows as strings and the file line of each row."""

    path: Path
    names: list[str]
    rows: list[list[str]]
    lines: list[int]
    headerless: bool


def is_number(s: str, decimal: str = ".") -> bool:
    """Whether ``s`` reads as a float to Python (with ``decimal`` as the decimal mark): the
    header test, lenient so that a first row written ``1_000`` is read as data, and refused
    by name (:func:`is_finite`), not taken for column names."""
    try:
        float(s.replace(decimal, ".") if decimal != "." else s)
    except ValueError:
        return False
    return True


def python_only(s: str) -> bool:
    """Whether ``s`` uses a number syntax only Python's ``float`` reads: ``_`` between
    digits (``1_000``) or non-ASCII digits and spaces (``１２``). pandas, ``numpy.loadtxt``
    and pyarrow (the streamed reader) refuse them, so every reader here refuses them too."""
    return "_" in s or not s.isascii()


def is_finite(s: str, decimal: str = ".") -> bool:
    """Whether ``s`` reads as a finite float (with ``decimal`` as the decimal mark) in the
    syntax every reader accepts (not :func:`python_only`).

    Examples
    --------
    >>> from sysid.data.table import is_finite
    >>> is_finite("1e3"), is_finite("1_000"), is_finite("nan")
    (True, False, False)
    """
    if python_only(s):
        return False
    try:
        return math.isfinite(float(s.replace(decimal, ".") if decimal != "." else s))
    except ValueError:
        return False


def guess_delimiter(first_line: str, decimal: str = ".") -> str:
    """The delimiter of a table whose first kept line is ``first_line``: a semicolon when it
    holds one, else a comma (not with ``decimal=","``), else a tab, else white space
    (``" "``)."""
    guesses = (";", ",", "\t") if decimal == "." else (";", "\t")
    return next((d for d in guesses if d in first_line), " ")


def splitter(delimiter: str) -> Callable[[str], list[str]]:
    """The function that splits one line into its fields (stripped; quotes allowed)."""
    if delimiter == " ":
        return lambda line: [c.strip('"') for c in line.split()]
    return lambda line: [c.strip() for c in next(csv.reader([line], delimiter=delimiter))]


def _kept(lines: Iterable[str]) -> Iterator[tuple[int, str]]:
    """``(file line, line)`` of the lines that are neither empty nor ``#`` comments."""
    for k, ln in enumerate(lines, 1):
        if ln.strip() and not ln.lstrip().startswith("#"):
            yield k, ln


def _header(head: list[str], decimal: str) -> tuple[list[str], bool]:
    """Column names from the first line's fields, and whether that line is data."""
    while head and head[-1] == "":  # a trailing delimiter ends every line
        head.pop()
    if all(is_number(c, decimal) for c in head):
        return [str(i) for i in range(len(head))], True
    return head, False


def _fields(path: Path, k: int, cells: list[str], n: int) -> list[str]:
    """The fields of data line ``k``, checked against the header's ``n`` columns."""
    while len(cells) > n and cells[-1] == "":
        cells.pop()
    if len(cells) != n:
        raise DataError(f"{path.name} line {k}: {len(cells)} fields but the header "
                        f"has {n} columns")
    return cells


#: How a record with missing cells is repaired: the readers' and the command's options.
REPAIR = ("missing values must be repaired before identification: IOData.from_csv(path, nan="
          "'interpolate' or 'split'), or the command's --fill-gaps N")


def cell_error(path: Path, line: int, column: str, cell: str, *, missing: bool = False,
               decimal: str = ".", hint: str = "") -> DataError:
    """The error for a field that is not a (finite) number: its file, line and column, what
    is wrong with it and the fix. One message for every reader of text tables."""
    what = ("is empty" if cell == "" else f"{cell!r} is not a finite number"
            if cell.strip().lower().lstrip("+-") in ("nan", "inf", "infinity")
            else f"{cell!r} is not a number")
    if cell and python_only(cell) and is_number(cell, decimal):
        what += (" (digits grouped with '_' are not read, as by pandas and numpy: write "
                 f"{cell.replace('_', '')})" if "_" in cell and cell.replace("_", "").isascii()
                 else " (only ASCII digits, signs, '.' and exponents are read)")
    if hint and decimal == "." and "," in cell and is_number(cell, ","):
        what += f" (a decimal comma? {hint})"
    fix = "fix or remove that row" if missing else f"fix or remove that row ({REPAIR})"
    return DataError(f"{path.name} line {line}, column {column!r}: {what}; {fix}")


def read_table(path: str | Path, delimiter: str | None = None, *,
               decimal: str = ".") -> Table:
    """Read a text table (see :func:`sysid.cli.read_csv` for the rules).

    The first line is a header of names unless every field in it is a number (then the
    columns are named ``"0", "1", ...``). The delimiter is guessed from the first line
    (semicolon when it holds one, else comma, else tab, else white space) unless given; a
    trailing delimiter at the end of every line is allowed; fields may be quoted. Empty
    lines and lines starting with ``#`` are skipped. A UTF-8 byte-order mark is dropped and
    files ending in ``.gz``, ``.bz2`` or ``.xz`` are decompressed.

    Examples
    --------
    >>> import os, tempfile
    >>> from sysid.data.table import read_table
    >>> path = os.path.join(tempfile.mkdtemp(), "d.dat")
    >>> with open(path, "w") as f:
    ...     _ = f.write("1.5 2\\n3 4\\n")
    >>> t = read_table(path)
    >>> t.names, t.rows, t.lines, t.headerless
    (['0', '1'], [['1.5', '2'], ['3', '4']], [1, 2], True)
    """
    path = Path(path)
    if not path.is_file():
        raise DataError(f"no data file at {str(path)!r}")
    blocks: list[bytes] = []
    try:
        with open_bytes(path) as f:
            while block := f.read1(_BLOCK):  # read1: the text before a damage is counted
                blocks.append(block)
    except _UNREADABLE as e:
        raise damaged(path, e, sum(b.count(b"\n") for b in blocks), bool(blocks)) from None
    raw = b"".join(blocks)
    del blocks
    try:
        if b"\0" in raw[:_SNIFF]:
            raise UnicodeDecodeError("utf-8", raw[:1], 0, 1, "NUL byte")
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise _binary(path) from None
    numbered = list(_kept(text.splitlines()))
    if not numbered:
        raise DataError(f"{str(path)!r} is empty")
    first_line = numbered[0][1]
    if delimiter is None:
        delimiter = guess_delimiter(first_line, decimal)
    split = splitter(delimiter)
    names, headerless = _header(split(first_line), decimal)
    body = numbered if headerless else numbered[1:]
    if not body:
        raise DataError(f"{str(path)!r} has a header but no data rows")
    rows, lines = [], []
    for k, line in body:
        rows.append(_fields(path, k, split(line), len(names)))
        lines.append(k)
    return Table(path, names, rows, lines, headerless)


def numeric(table: Table, cols: list[int], *, missing: bool = False,
            decimal: str = ".", hint: str = "") -> np.ndarray:
    """The columns ``cols`` of ``table`` as floats, shape ``(rows, len(cols))``.

    A field that is not a number raises a :class:`~sysid.DataError` naming its file line and
    column. With ``missing``, empty fields (and ``nan``) become NaN for the caller to repair;
    without, they are errors too. ``hint`` is added to a decimal-comma error (how to say
    ``decimal=","``).

    Examples
    --------
    >>> import os, tempfile
    >>> from sysid.data.table import numeric, read_table
    >>> path = os.path.join(tempfile.mkdtemp(), "d.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write('u,y\\n"1",2\\n3,\\n')
    >>> numeric(read_table(path), [1, 0], missing=True)
    array([[ 2.,  1.],
           [nan,  3.]])
    """
    cells = np.array([[r[c] for c in cols] for r in table.rows], dtype=str).reshape(
        len(table.rows), len(cols))
    if decimal != ".":
        cells = np.char.replace(cells, decimal, ".")
    try:
        values = cells.astype(float)
        bad = ~np.isfinite(values)
        if missing:
            bad &= ~np.isnan(values)
        if not bad.any() and not _python_only_any(cells):
            return values
    except ValueError:
        pass
    values = np.empty(cells.shape)
    for r, row in enumerate(table.rows):
        for k, c in enumerate(cols):
            cell = row[c]
            if missing and cell == "":
                values[r, k] = np.nan
                continue
            try:
                if python_only(cell):
                    raise ValueError(cell)
                values[r, k] = float(cells[r, k])
                if not (np.isfinite(values[r, k]) or missing and np.isnan(values[r, k])):
                    raise ValueError(cell)
            except ValueError:
                raise cell_error(table.path, table.lines[r], table.names[c], cell,
                                 missing=missing, decimal=decimal, hint=hint) from None
    return values


def _python_only_any(cells: np.ndarray) -> bool:
    """Whether a cell of a string array is :func:`python_only` (vectorised: its characters
    as code points)."""
    if cells.size == 0:
        return False
    codes = np.ascontiguousarray(cells).view(np.uint32)
    return bool(((codes > 127) | (codes == ord("_"))).any())


def first_bad_cell(path: str | Path, columns: list[str], *, delimiter: str | None = None,
                   start: int = 0, decimal: str = ".", hint: str = "") -> DataError | None:
    """The error :func:`numeric` gives for the named ``columns`` of a text table, found by
    reading the file line by line (bounded memory, for files too large to hold as strings).

    The rules are :func:`read_table`'s (empty and ``#`` lines skipped, the header, the
    delimiter guessed from the first kept line unless given, quotes, trailing delimiters,
    compressed files). Returns the :class:`~sysid.DataError` of the first data row from
    the ``start``-th (counting from 0, the header excluded) that has the wrong number of
    fields or a cell in ``columns`` that is not a finite number (empty, ``nan`` and
    ``inf`` included), naming its file line and column; ``None`` when there is none or a
    column is not in the header.

    Examples
    --------
    >>> import os, tempfile
    >>> from sysid.data.table import first_bad_cell
    >>> path = os.path.join(tempfile.mkdtemp(), "d.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("u,y\\n1,2\\n\\n# a comment\\n3,nan\\n")
    >>> str(first_bad_cell(path, ["u", "y"])).split(";")[0]
    "d.csv line 5, column 'y': 'nan' is not a finite number"
    >>> first_bad_cell(path, ["u"]) is None
    True
    """
    path = Path(path)
    try:
        head = header(path, delimiter, decimal=decimal)
    except (DataError, *_UNREADABLE):  # an empty or unreadable file has no bad cell to name
        return None
    if any(c not in head.names for c in columns):
        return None
    try:
        for _ in _data_rows(path, head, [head.names.index(c) for c in columns],
                            start=start, decimal=decimal, hint=hint):
            pass
    except DataError as e:
        return e
    except _UNREADABLE:
        return None
    return None


def first_line(path: str | Path) -> tuple[int, str]:
    """The file line number and text of a table's first line that is neither empty nor a
    ``#`` comment (its header, or its first row), read without reading the rest; ``(0,
    "")`` for a file without one."""
    path = Path(path)
    seen = [0]  # lines read, for the error of a damaged compressed file
    try:
        with _open_text(path) as f:
            return next(_kept(_counted(f, seen)), (0, ""))
    except _UNREADABLE as e:
        raise damaged(path, e, seen[0], seen[0] > 0) from None


def first_rows(path: str | Path, head: Header, k: int) -> Table:
    """The first ``k`` data rows of a text table (after its header, a units row included)
    as a :class:`Table`, read without reading the rest (the streamed reader's look ahead).

    Examples
    --------
    >>> import os, tempfile
    >>> from sysid.data.table import first_rows, header
    >>> path = os.path.join(tempfile.mkdtemp(), "d.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("t,y\\ns,m\\n0,1\\n1,2\\n2,3\\n")
    >>> first_rows(path, header(path), 2).rows
    [['s', 'm'], ['0', '1']]
    """
    path, split, out = Path(path), splitter(head.delimiter), []
    with _open_text(path) as f:
        for line, text in _kept(f.read(_SNIFF).splitlines()):
            if line > head.line or head.headerless:
                out.append((line, split(text)))
            if len(out) == k + 1:  # the last line of the sniffed text may be cut short
                break
    out = out[:k]
    return Table(path, head.names, [r for _, r in out], [n for n, _ in out], head.headerless)


def _counted(f: Iterable[str], seen: list[int]) -> Iterator[str]:
    """The lines of ``f`` without their line break, their number kept in ``seen[0]``."""
    for seen[0], line in enumerate(f, 1):  # noqa: B007 (seen[0] is read by the caller)
        yield line.rstrip("\r\n")


def damaged(path: str | Path, error: BaseException, lines: int, started: bool = True
            ) -> DataError:
    """The error for a table file whose decompression failed: a compressed file damaged or
    truncated (after ``lines`` whole lines of text when ``started``), or one that is not
    compressed as its suffix says; a plain file's read error is :func:`_binary`'s.

    Examples
    --------
    >>> from sysid.data.table import damaged
    >>> print(damaged("log.csv.gz", EOFError("end of stream"), 1200))  # doctest: +ELLIPSIS
    log.csv.gz: the gzip-compressed file is damaged or truncated: its text ends after line 1200 ...
    """
    path = Path(path)
    kind = _KIND.get(path.suffix.lower())
    if kind is None:
        return _binary(path)
    why = " ".join(str(error).split()) or type(error).__name__
    if not started:
        return DataError(f"{path.name}: not a readable {kind}-compressed file ({why}): it is "
                         f"damaged at its start, or not {kind}-compressed (then rename it "
                         f"without {path.suffix})")
    return DataError(f"{path.name}: the {kind}-compressed file is damaged or truncated: its "
                     f"text ends after line {lines} ({why}); nothing of it was used: copy or "
                     "export the file again")


def _binary(path: Path) -> DataError:
    """The error for a file that is not a text table (or not one compressed as its suffix
    says)."""
    fix = ("give a CSV or whitespace-separated text file with one column per channel"
           if path.suffix.lower() != ".zip" else "a zip archive is not read: unzip it, or "
           "compress the table alone with gzip (.gz), bzip2 (.bz2) or xz (.xz)")
    return DataError(f"{str(path)!r} is not a text table (binary content); {fix}")


def open_bytes(path: str | Path) -> IO[bytes]:
    """A table file's bytes, decompressed when its name ends in ``.gz``, ``.bz2``, ``.xz``
    or ``.lzma`` (as :func:`read_table` reads it), as a binary stream for the caller's
    ``with``."""
    path = Path(path)
    opener = _STREAM.get(path.suffix.lower())
    if opener is None:
        return open(path, "rb")  # noqa: SIM115 (the caller's with)
    return opener(path, "rb")  # type: ignore[no-any-return]


def decompressing(path: str | Path, raw: IO[bytes]) -> IO[bytes]:
    """``raw`` (the bytes of the file ``path``, read through another stream: a progress
    counter) decompressed as :func:`open_bytes` does; ``raw`` itself for a plain file.
    Closing the result leaves ``raw`` open."""
    opener = _STREAM.get(Path(path).suffix.lower())
    return raw if opener is None else opener(raw, "rb")  # type: ignore[no-any-return]


def text_bytes(path: str | Path, limit: int) -> int:
    """The bytes of text a table file holds once decompressed (what the readers read, not
    the file's size), counted up to ``limit + 1`` and no further.

    Raises the :class:`~sysid.DataError` of :func:`read_table` for a file that is not text
    (a NUL byte among its first 64 KiB, a damaged or foreign compressed stream, a zip
    archive), so that every reader refuses it the same way.

    Examples
    --------
    >>> import gzip, os, tempfile
    >>> from sysid.data.table import text_bytes
    >>> path = os.path.join(tempfile.mkdtemp(), "d.csv.gz")
    >>> with gzip.open(path, "wt") as f:
    ...     _ = f.write("u,y\\n" + "1,2\\n" * 1000)
    >>> os.path.getsize(path) < 100, text_bytes(path, 10**6), text_bytes(path, 100)
    (True, 4004, 101)
    """
    path = Path(path)
    n = lines = 0
    try:
        with open_bytes(path) as f:
            head = f.read1(_SNIFF)
            if b"\0" in head:
                raise _binary(path)
            n, lines = len(head), head.count(b"\n")
            while n <= limit:
                block = f.read1(min(_BLOCK, limit + 1 - n))
                if not block:
                    break
                n, lines = n + len(block), lines + block.count(b"\n")
    except _UNREADABLE as e:
        raise damaged(path, e, lines, n > 0) from None
    return min(n, limit + 1)


def count_lines(path: str | Path) -> int:
    """The lines of a table file once decompressed (a last line without a newline counted),
    read in binary blocks of 1 MiB into one buffer (no text decoded, no block allocated): a
    bound on its rows known before any row is held, for the reader that allocates them.

    Examples
    --------
    >>> import os, tempfile
    >>> from sysid.data.table import count_lines
    >>> path = os.path.join(tempfile.mkdtemp(), "d.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("u,y\\n1,2\\n3,4")
    >>> count_lines(path)
    3
    """
    path = Path(path)
    n, last, buf = 0, ord("\n"), bytearray(_BLOCK)
    try:
        with open_bytes(path) as f:
            while k := f.readinto1(buf):
                n, last = n + buf.count(b"\n", 0, k), buf[k - 1]
    except _UNREADABLE as e:
        raise damaged(path, e, n, n > 0) from None
    return n + (last != ord("\n"))


def header(path: str | Path, delimiter: str | None = None, *,
           decimal: str = ".") -> Header:
    """A table's column names, read from its first kept line by :func:`read_table`'s rules
    without reading the rest: a header of names, or, when every field of that line is a
    number, a first data row (the columns then named ``"0", "1", ...``). One rule for every
    reader, so that a column has the same name whatever the file's size.

    Examples
    --------
    >>> import os, tempfile
    >>> from sysid.data.table import header
    >>> path = os.path.join(tempfile.mkdtemp(), "d.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("# no header\\n1.5,2,\\n3,4,\\n")
    >>> header(path)
    Header(names=['0', '1'], headerless=True, line=2, delimiter=',', width=3)
    """
    path = Path(path)
    line, text = first_line(path)
    if not line:
        raise DataError(f"{str(path)!r} is empty")
    delim = delimiter or guess_delimiter(text, decimal)
    fields = splitter(delim)(text)
    names, headerless = _header(list(fields), decimal)
    return Header(names, headerless, line, delim, len(fields))


def read_named(path: str | Path, columns: list[str], rows: int, *,
               delimiter: str | None = None) -> np.ndarray:
    """The named columns of a text table as float64, shape ``(data rows, len(columns))``,
    read line by line into an array of ``rows`` rows at most (a bound the caller has
    checked, e.g. :func:`count_lines`): the other columns are never converted or held.

    The rules and errors are :func:`read_table` and :func:`numeric`'s: a cell that is not
    a finite number is named by file line and column, a missing column by the header.

    Examples
    --------
    >>> import os, tempfile
    >>> from sysid.data.table import read_named
    >>> path = os.path.join(tempfile.mkdtemp(), "d.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("t,note,y\\n0,start,2\\n1,,4\\n")
    >>> read_named(path, ["y", "t"], 3)
    array([[2., 0.],
           [4., 1.]])
    """
    path = Path(path)
    head = header(path, delimiter)
    missing = [c for c in columns if c not in head.names]
    if missing:
        raise DataError(f"{path.name}: no column(s) {missing}; it has {head.names}")
    out = np.empty((rows, len(columns)))
    r = 0
    for _, values in _data_rows(path, head, [head.names.index(c) for c in columns]):
        if r == rows:
            raise DataError(f"{path.name}: more than the {rows} rows counted; the file "
                            "changed while it was read")
        out[r] = values
        r += 1
    if r == 0:
        raise DataError(f"{str(path)!r} has a header but no data rows")
    return out[:r]


def _open_text(path: Path) -> IO[str]:
    opener = _STREAM.get(path.suffix.lower())
    if opener is not None:
        return opener(path, "rt", encoding="utf-8-sig", errors="replace")  # type: ignore
    return open(path, encoding="utf-8-sig", errors="replace")  # noqa: SIM115 (the caller's with)


def _data_rows(path: Path, head: Header, cols: list[int], *, start: int = 0,
               decimal: str = ".", hint: str = "") -> Iterator[tuple[int, list[float]]]:
    """``(file line, values of cols)`` of each data row from the ``start``-th, read line by
    line by :func:`read_table`'s rules; a row with the wrong number of fields or a cell that
    is not a finite number raises its :class:`~sysid.DataError` (file line and column)."""
    split, n = splitter(head.delimiter), len(head.names)
    seen = [0]  # lines read, for the error of a damaged compressed file
    try:
        with _open_text(path) as f:
            kept = _kept(_counted(f, seen))
            if not head.headerless:
                next(kept, None)
            for k, line in itertools.islice(kept, start, None):
                cells = _fields(path, k, split(line), n)
                for c in cols:
                    if not is_finite(cells[c], decimal):
                        raise cell_error(path, k, head.names[c], cells[c], decimal=decimal,
                                         hint=hint)
                yield k, [float(cells[c].replace(decimal, ".")) for c in cols]
    except _UNREADABLE as e:
        raise damaged(path, e, seen[0], seen[0] > 0) from None


#: A ``#`` comment line, and a comment or blank line, with its line break (any of them).
_COMMENT = re.compile(rb"(?:(?<=[\r\n])|\A)[ \t\f\v]*#[^\r\n]*(?:\r\n|\r|\n|\Z)")
_SKIPPED = re.compile(rb"(?:(?<=[\r\n])|\A)[ \t\f\v]*(?:#[^\r\n]*)?(?:\r\n|\r|\n|\Z)")


class ForwardReader:
    """A forward-only binary stream over ``self._src`` (what pyarrow's streaming readers
    ask of a file besides ``read``): readable, not seekable, closed with its source. A
    subclass sets ``_src`` and defines ``read``."""

    _src: IO[bytes]

    def readable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return False

    @property
    def closed(self) -> bool:
        return bool(self._src.closed)

    def close(self) -> None:
        self._src.close()


class Uncommented(ForwardReader):
    """The bytes of a table file (``src``, decompressed) without its ``#`` comment lines,
    for a reader that knows no comments (pyarrow's): the lines :func:`read_table` skips are
    skipped wherever they are, even with as many fields as the header. Its first block (1
    MiB at least) also loses its blank lines, so that the text starts at the header (or
    the first row); the UTF-8 byte-order mark is dropped.

    A damaged compressed stream raises :func:`damaged`'s error (the lines read before it);
    it is also kept in :attr:`error`, for a caller whose reader wraps it. Closing closes
    ``src``.

    Examples
    --------
    >>> import io
    >>> from sysid.data.table import Uncommented
    >>> f = Uncommented(io.BytesIO(b"# log\\n\\nu,y\\n1,2\\n# u,y\\n3,4"), "d.csv")
    >>> f.read()
    b'u,y\\n1,2\\n3,4'
    """

    def __init__(self, src: IO[bytes], path: str | Path) -> None:
        self._src, self._path = src, Path(path)
        # read1: a decompressor's text is counted up to its damage, not lost in a block
        self._read = getattr(src, "read1", src.read)
        self._carry, self._out = bytearray(), bytearray()
        self._first, self._eof, self.lines = True, False, 0
        self.error: DataError | None = None

    def read(self, n: int | None = -1) -> bytes:
        """At most ``n`` bytes (all that is left when ``n`` is negative or ``None``)."""
        while not self._eof and (n is None or n < 0 or len(self._out) < n):
            self._fill()
        k = len(self._out) if n is None or n < 0 else min(n, len(self._out))
        out = bytes(self._out[:k])
        del self._out[:k]
        return out

    def _fill(self) -> None:
        try:
            block = self._read(_BLOCK)
        except _UNREADABLE as e:
            self.error = damaged(self._path, e, self.lines, self.lines > 0 or self._seen)
            raise self.error from None
        self.lines += block.count(b"\n")
        self._carry += block
        self._eof = not block
        if self._eof:
            cut = len(self._carry)
        elif self._first and len(self._carry) < _BLOCK:
            return  # the first block whole: its blank lines before the header go
        else:  # whole lines only: a comment is not cut in two
            cut = max(self._carry.rfind(b"\n"), self._carry.rfind(b"\r")) + 1
        chunk = bytes(self._carry[:cut])
        del self._carry[:cut]
        if self._first:
            self._first = False
            chunk = _SKIPPED.sub(b"", chunk.removeprefix(b"\xef\xbb\xbf"))
        elif b"#" in chunk:
            chunk = _COMMENT.sub(b"", chunk)
        self._out += chunk

    @property
    def _seen(self) -> bool:
        return bool(self._carry or self._out) or not self._first


#: Cells that mark a missing value, not a unit, in the row under a header.
_MISSING_WORDS = {"na", "nan", "n/a", "null", "none", "-"}


def units_row(table: Table, decimal: str = ".") -> tuple[Table, dict[int, str]]:
    """``table`` without a row of units under its header, and the units by column.

    Loggers often write one: ``time,power,temp`` then ``s,W,degC``. It is taken for units
    when no cell of it is a number or a missing-value word (``NA``, ``nan``, ...), at least
    one is filled, and the row after it holds a number; else the table comes back as it is.

    Examples
    --------
    >>> import os, tempfile
    >>> from sysid.data.table import read_table, units_row
    >>> path = os.path.join(tempfile.mkdtemp(), "d.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("t,u,y\\ns,,m\\n0,1,2\\n1,3,4\\n")
    >>> t, units = units_row(read_table(path))
    >>> len(t.rows), units
    (2, {0: 's', 2: 'm'})
    """
    if table.headerless or len(table.rows) < 2:
        return table, {}
    first, second = table.rows[0], table.rows[1]
    filled = [c for c in first if c]
    if (not filled or any(is_number(c, decimal) or c.lower() in _MISSING_WORDS
                          for c in filled)
            or not any(is_number(c, decimal) for c in second if c)):
        return table, {}
    units = {k: c.strip("[]() ") for k, c in enumerate(first) if c}
    return table._replace(rows=table.rows[1:], lines=table.lines[1:]), units


_ZONE = re.compile(r"(Z|[+-]\d\d:?\d\d)$")


_CLOCK = re.compile(r"([01]?\d|2[0-3]):([0-5]\d):([0-5]\d|60)(\.\d+)?$")


def _clock_ns(cells: list[str]) -> tuple[np.ndarray, int]:
    """Time-of-day stamps (``12:52:35.2364630``: a logger's clock, its date in another
    column or nowhere) as nanoseconds after the first one's midnight, a day added at every
    step back of more than 12 h (midnight passed); the index of the first cell that is
    none (-1 when all are)."""
    out = np.zeros(len(cells), dtype=np.int64)
    for k, c in enumerate(cells):
        m = _CLOCK.match(c.strip())
        if m is None:
            return out[:k], k
        frac = (m.group(4) or ".")[1:]
        out[k] = ((int(m.group(1)) * 60 + int(m.group(2))) * 60 + int(m.group(3))) * 10**9 \
            + int((frac + "0" * 9)[:9])
    day = np.concatenate([[0], np.cumsum(np.diff(out) < -12 * 3600 * 10**9)])
    return out + day * 86400 * 10**9, -1


def stamps_ns(cells: list[str]) -> tuple[np.ndarray | None, int]:
    """Date-time stamps (ISO 8601, an optional ``Z`` or ``+hh:mm`` offset) as UTC
    nanoseconds (int64), or time-of-day stamps (``hh:mm:ss.fff``) as nanoseconds after
    their first midnight, and the index of the first cell that is no stamp (-1 when all
    are); ``(None, 0)`` when the first is none.

    Examples
    --------
    >>> from sysid.data.table import stamps_ns
    >>> t, bad = stamps_ns(["2026-01-01T01:00:00+01:00", "2026-01-01 00:00:01Z", "x"])
    >>> float(t[1] - t[0]) / 1e9, bad
    (1.0, 2)
    """
    if cells and _CLOCK.match(cells[0].strip()):
        return _clock_ns(cells)
    if not cells or not re.match(r"\d{4}-\d\d-\d\d", cells[0]):
        return None, 0
    stamps, shift = [], np.zeros(len(cells), dtype=np.int64)
    for k, c in enumerate(cells):
        m = _ZONE.search(c) if len(c) > 10 else None
        if m:
            z = m.group(1)
            if z != "Z":
                hh, mm = int(z[1:3]), int(z[-2:])
                shift[k] = (1 if z[0] == "+" else -1) * (3600 * hh + 60 * mm) * 10**9
            c = c[:m.start()]
        stamps.append(c)
    try:
        t = np.array(stamps, dtype="datetime64[ns]")
        if not np.isnat(t).any():
            return t.astype(np.int64) - shift, -1
    except ValueError:
        pass
    for k, c in enumerate(stamps):  # the first cell that is no stamp, one by one
        try:
            ok = not np.isnat(np.datetime64(c, "ns"))
        except ValueError:
            ok = False
        if not ok:
            if k == 0:
                return None, 0
            t = np.array([np.datetime64(x, "ns") for x in stamps[:k]])
            return t.astype(np.int64) - shift[:k], k
    t = np.array([np.datetime64(x, "ns") for x in stamps])
    return t.astype(np.int64) - shift, -1


def datetime_seconds(table: Table, col: int, decimal: str = ".") -> np.ndarray | None:
    """The column ``col`` of date-time stamps (ISO 8601: ``2026-01-01 08:00:00.250``, ``T``
    between date and time, an optional ``Z`` or ``+hh:mm`` offset) or of time-of-day
    stamps (``08:00:00.250``, midnight passed forward) as seconds after its first; ``None``
    when its first cell is a number or no stamp (the caller reads numbers). A later cell
    that is no stamp raises a :class:`~sysid.DataError` naming its line.

    Examples
    --------
    >>> import os, tempfile
    >>> from sysid.data.table import read_table, datetime_seconds
    >>> path = os.path.join(tempfile.mkdtemp(), "d.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("t,y\\n2026-01-01T00:59:59.5+01:00,1\\n2026-01-01 00:00:00Z,2\\n")
    >>> datetime_seconds(read_table(path), 0)
    array([0. , 0.5])
    """
    cells = [r[col] for r in table.rows]
    if not cells or is_number(cells[0], decimal):
        return None
    t, bad = stamps_ns(cells)
    if t is None:
        return None
    if bad >= 0:
        raise DataError(f"{table.path.name} line {table.lines[bad]}, column "
                        f"{table.names[col]!r}: {cells[bad]!r} is not a date-time "
                        f"stamp like the first ({cells[0]!r}); fix or remove that row")
    return (t - t[0]) * 1e-9
