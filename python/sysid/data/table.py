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
import lzma
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import DataError

__all__: list[str] = []

_OPEN = {".gz": gzip.decompress, ".bz2": bz2.decompress, ".xz": lzma.decompress,
         ".lzma": lzma.decompress}


class Table(NamedTuple):
    """Column names, the rows as strings and the file line of each row."""

    path: Path
    names: list[str]
    rows: list[list[str]]
    lines: list[int]
    headerless: bool


def is_number(s: str, decimal: str = ".") -> bool:
    """Whether ``s`` reads as a float (with ``decimal`` as the decimal mark)."""
    try:
        float(s.replace(decimal, ".") if decimal != "." else s)
    except ValueError:
        return False
    return True


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
    raw = path.read_bytes()
    unpack = _OPEN.get(path.suffix.lower())
    try:
        if unpack is not None:
            raw = unpack(raw)
        if b"\0" in raw[:65536]:
            raise UnicodeDecodeError("utf-8", raw[:1], 0, 1, "NUL byte")
        text = raw.decode("utf-8-sig")
    except (UnicodeDecodeError, OSError, EOFError, lzma.LZMAError):
        raise DataError(
            f"{str(path)!r} is not a text table (binary content); give a CSV or whitespace-"
            "separated text file with one column per channel"
        ) from None
    numbered = [(k + 1, ln) for k, ln in enumerate(text.splitlines())
                if ln.strip() and not ln.lstrip().startswith("#")]
    if not numbered:
        raise DataError(f"{str(path)!r} is empty")
    first_line = numbered[0][1]
    if delimiter is None:
        guesses = (";", ",", "\t") if decimal == "." else (";", "\t")
        delimiter = next((d for d in guesses if d in first_line), " ")

    def split(line: str) -> list[str]:
        if delimiter == " ":
            return [c.strip('"') for c in line.split()]
        return [c.strip() for c in next(csv.reader([line], delimiter=delimiter))]

    head = split(first_line)
    while head and head[-1] == "":  # a trailing delimiter ends every line
        head.pop()
    headerless = all(is_number(c, decimal) for c in head)
    if headerless:
        names, body = [str(i) for i in range(len(head))], numbered
    else:
        names, body = head, numbered[1:]
    if not body:
        raise DataError(f"{str(path)!r} has a header but no data rows")
    rows, lines = [], []
    for k, line in body:
        cells = split(line)
        while len(cells) > len(names) and cells[-1] == "":
            cells.pop()
        if len(cells) != len(names):
            raise DataError(f"{path.name} line {k}: {len(cells)} fields but the header "
                            f"has {len(names)} columns")
        rows.append(cells)
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
        if not bad.any():
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
                values[r, k] = float(cells[r, k])
                if not (np.isfinite(values[r, k]) or missing and np.isnan(values[r, k])):
                    raise ValueError(cell)
            except ValueError:
                what = ("is empty" if cell == "" else f"{cell!r} is not a finite number"
                        if cell.strip().lower().lstrip("+-") in ("nan", "inf", "infinity")
                        else f"{cell!r} is not a number")
                if hint and decimal == "." and "," in cell and is_number(cell, ","):
                    what += f" (a decimal comma? {hint})"
                fix = ("fix or remove that row" if missing else "fix or remove that row "
                       "(missing values must be repaired before identification)")
                raise DataError(
                    f"{table.path.name} line {table.lines[r]}, column {table.names[c]!r}: "
                    f"{what}; {fix}"
                ) from None
    return values
