"""Out-of-core and distributed compression: records larger than memory, or than one machine.

Compression is the only step that touches every sample, and it streams: the Rust core keeps
``O(k^2)`` numbers whatever the record length. :func:`compress_stream` feeds it from numpy
arrays or memmaps, from iterators of ``(u, y)`` chunks, or from Parquet files (one row group
at a time); :func:`compress_dask` sums Dask array blocks on the workers and combines the
partial sums on the driver. Both return a :class:`~sysid._sysid.HankelFactor` for
``SubspaceEstimator.from_factor(factor, dt=..., method=...)``.
"""

from __future__ import annotations

import mmap
import os
import warnings
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any, Union

import numpy as np

from .. import _sysid
from .._checks import as_2d, as_int, as_option, user_stacklevel
from .._progress import Bar, show
from ..errors import DataError, ShapeError, SysidWarning

__all__ = [
    "compress_stream",
    "compress_dask",
    "warn_if_fallback",
    "CompressionFallbackWarning",
    "COMPRESSORS",
    "compression_info",
]

COMPRESSORS = ("auto", "qr", "correlation")

Source = Union[tuple[Any, Any], Iterable[tuple[Any, Any]], str, os.PathLike]


class CompressionFallbackWarning(SysidWarning, RuntimeWarning):
    """The correlation compressor met an ill-conditioned Gram matrix; the message says which
    fallback was used (the exact QR pass, or an eigenvalue-clipped factor)."""


def compression_info(factor: Any, requested: str) -> dict[str, Any]:
    """What the compressor decided, for ``model.info["compression"]``.

    ``requested`` is the compressor asked for; ``source`` the path that made the factor
    (``"correlation"``, ``"qr"``, ``"qr-fallback"`` or ``"correlation-ill-conditioned"``);
    ``relative_pivot`` the smallest relative Cholesky pivot of the centred, scaled Gram
    matrix (about ``1 / cond(H)^2``; ``None`` when only the exact path ran) and
    ``threshold`` the pivot below which ``"auto"`` takes the exact path.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid import _sysid
    >>> from sysid.subspace.streaming import compression_info
    >>> u = np.random.default_rng(0).standard_normal((2000, 1))
    >>> y = u + 0.1 * np.random.default_rng(1).standard_normal((2000, 1))
    >>> compression_info(_sysid.compress([(u, y)], 3, 3), "auto")["source"]
    'correlation'
    """
    return {
        "requested": requested,
        "source": getattr(factor, "source", "qr"),
        "relative_pivot": getattr(factor, "relative_pivot", None),
        "threshold": _sysid.AUTO_MIN_RELATIVE_PIVOT if requested == "auto" else 1e-10,
    }


def warn_if_fallback(factor: Any, stacklevel: int | None = None,
                     requested: str = "correlation") -> None:
    """Warn when a factor did not come from the requested path without a fallback.

    ``factor.source`` is ``"qr"`` or ``"correlation"`` normally; ``"qr-fallback"`` means the
    correlation Gram matrix was ill-conditioned and the in-memory data were compressed again
    exactly (expected, hence silent, with ``requested="auto"``);
    ``"correlation-ill-conditioned"`` means the data were streamed from a one-pass iterator,
    so the exact pass could not be rerun and singular values below about ``1e-8`` of the
    largest are not resolved.
    """
    src = getattr(factor, "source", "qr")
    level = user_stacklevel() if stacklevel is None else stacklevel + 1
    if src == "qr-fallback" and requested != "auto":
        warnings.warn(
            "the correlation compressor's Gram matrix was ill-conditioned (relative pivot "
            f"{factor.relative_pivot:.1e}); the data were compressed again with the exact QR "
            "compressor (factor.source == 'qr-fallback')",
            CompressionFallbackWarning,
            stacklevel=level,
        )
    elif src == "correlation-ill-conditioned":
        warnings.warn(
            "the correlation compressor's Gram matrix is ill-conditioned (relative pivot "
            f"{factor.relative_pivot:.1e}; eigenvalue-clipped factor when it is 0): singular "
            "values below about 1e-8 of the largest are not resolved; compress with "
            "compressor='qr' if they matter (noise-free data, constant channels)",
            CompressionFallbackWarning,
            stacklevel=level,
        )


def _release_pages(arr: np.ndarray, start: int, stop: int) -> None:
    """Drop the pages of rows ``start:stop`` of a memmap from this process's memory.

    Read-only file pages stay in the page cache; only the process's resident set shrinks,
    which keeps the memory of a pass over a huge memmap bounded. Best effort.
    """
    mm = getattr(arr, "_mmap", None)
    if mm is None or stop <= start or not hasattr(mm, "madvise"):
        return
    if getattr(arr, "mode", "r") in ("c", "copyonwrite"):
        return  # private copy-on-write pages: dropping them would drop the caller's edits
    try:
        base = np.frombuffer(mm, dtype=np.uint8).__array_interface__["data"][0]
        first = arr[start:stop].__array_interface__["data"][0] - base
        last = arr[stop - 1 : stop].__array_interface__["data"][0] - base + arr.strides[0]
        page = mmap.PAGESIZE
        lo = (first // page) * page
        hi = ((last + page - 1) // page) * page
        # keep the page holding the next row (it may be shared with it)
        hi = min(hi, len(mm)) - (page if stop < arr.shape[0] else 0)
        if hi > lo:
            mm.madvise(mmap.MADV_DONTNEED, lo, hi - lo)
    except (ValueError, OSError, TypeError, BufferError):
        return


def as_chunk(u: Any, y: Any, allow_empty: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """A chunk ``(u, y)`` of a stream checked whole (numeric, finite, ``(samples, channels)``,
    ``u`` and ``y`` equally long; ``u`` ``None`` or empty for output-only data), so that a
    bad first chunk is refused before it sizes a compressor.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.subspace.streaming import as_chunk
    >>> u, y = as_chunk(None, np.ones(4))
    >>> u.shape, y.shape
    ((4, 0), (4, 1))
    """
    y2 = as_2d(y, "y", allow_empty=allow_empty)
    u2 = np.zeros((y2.shape[0], 0)) if u is None else as_2d(u, "u", allow_empty=True)
    if u2.size == 0:
        u2 = np.zeros((y2.shape[0], 0))
    if u2.shape[0] != y2.shape[0]:
        raise ShapeError(f"u has {u2.shape[0]} samples but y has {y2.shape[0]} in a chunk; "
                         "each (u, y) chunk must be equally long")
    return np.ascontiguousarray(u2), np.ascontiguousarray(y2)


def _array_chunks(u: Any, y: Any, chunk_size: int) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    n = y.shape[0]
    if u.shape[0] != n:
        raise DataError(f"u has {u.shape[0]} samples but y has {n}; they must be equally long")
    for s in range(0, n, chunk_size):
        e = min(n, s + chunk_size)
        yield u[s:e], y[s:e]
        _release_pages(u, s, e)
        _release_pages(y, s, e)


def _parquet_chunks(
    path: Path, input_columns: list[str] | None, output_columns: list[str] | None
) -> tuple[Iterator[tuple[np.ndarray, np.ndarray]], int]:
    try:
        import pyarrow.parquet as pq
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("reading Parquet needs pyarrow: pip install pyarrow") from exc
    pf = pq.ParquetFile(path)
    names = pf.schema_arrow.names
    ins = input_columns if input_columns is not None else [c for c in names if c.startswith("u")]
    outs = (
        output_columns if output_columns is not None else [c for c in names if c.startswith("y")]
    )
    missing = [c for c in ins + outs if c not in names]
    if missing:
        raise DataError(f"{path}: no column(s) {missing}; the file has {names}")
    if not outs:
        raise DataError(
            f"{path}: no output columns; name them with output_columns= (the file has {names})"
        )

    def gen() -> Iterator[tuple[np.ndarray, np.ndarray]]:
        for g in range(pf.num_row_groups):
            t = pf.read_row_group(g, columns=ins + outs)
            cols = [t.column(c).to_numpy().astype(np.float64, copy=False) for c in ins + outs]
            z = np.column_stack(cols) if cols else np.zeros((t.num_rows, 0))
            yield z[:, : len(ins)], z[:, len(ins) :]

    return gen(), pf.metadata.num_rows


def _is_dask(x: Any) -> bool:
    return type(x).__module__.split(".")[0] == "dask"


def _experiments(
    source: Any, chunk_size: int, input_columns: list[str] | None,
    output_columns: list[str] | None,
) -> list[tuple[Iterator[tuple[Any, Any]], int | None]]:
    """Split a source into experiments, each an iterator of chunks and its length if known."""
    if isinstance(source, (str, os.PathLike)):
        return [_parquet_chunks(Path(source), input_columns, output_columns)]
    if isinstance(source, np.ndarray) or (
        isinstance(source, list) and source and not isinstance(source[0], (tuple, list, str))
        and not hasattr(source[0], "__next__") and not isinstance(source[0], os.PathLike)
    ):
        raise DataError(
            "source must be (u, y) pairs, not bare arrays: pass (u, y), a list of (u, y) "
            "(one per experiment), or (None, y) for output-only data"
        )
    if isinstance(source, tuple) and len(source) == 2 and (
        source[0] is None and (hasattr(source[1], "shape") or isinstance(source[1], list))
    ):
        y = np.asarray(source[1], dtype=float)
        y = y[:, None] if y.ndim == 1 else y
        source = (np.zeros((y.shape[0], 0)), y)
    if isinstance(source, tuple) and len(source) == 2 and all(
        hasattr(a, "shape") or isinstance(a, (list, np.ndarray)) for a in source
    ):
        u, y = source
        u = u if isinstance(u, np.ndarray) else np.asarray(u, dtype=float)
        y = y if isinstance(y, np.ndarray) else np.asarray(y, dtype=float)
        if y.ndim == 1:
            y = y[:, None]
        if u.ndim == 1:
            u = u[:, None]
        return [(_array_chunks(u, y, chunk_size), int(y.shape[0]))]
    if isinstance(source, list):
        out = []
        for s in source:
            out.extend(_experiments(s, chunk_size, input_columns, output_columns))
        return out
    if isinstance(source, Iterable):
        return [(iter(source), None)]
    raise DataError(
        "source must be a (u, y) pair of arrays or memmaps, an iterator of (u, y) chunks, a "
        f"Parquet file path, or a list of these (one per experiment); got {type(source).__name__}"
    )


def compress_stream(
    source: Source | list[Source],
    past: int,
    future: int | None = None,
    *,
    compressor: str = "auto",
    chunk_size: int = 1 << 18,
    input_columns: list[str] | None = None,
    output_columns: list[str] | None = None,
    progress: bool | None = None,
) -> Any:
    """Compress a record chunk by chunk with bounded memory.

    Parameters
    ----------
    source
        ``(u, y)`` arrays or ``np.memmap`` s (read ``chunk_size`` samples at a time, their
        pages released after use); an iterator of ``(u, y)`` chunks (one experiment); a
        Parquet file path (read one row group at a time; columns ``input_columns`` and
        ``output_columns``, by default those whose names start with ``u`` and ``y``); or a
        list of these, one per experiment (no Hankel column spans two).
    past, future : int
        Horizons (``future`` defaults to ``past``).
    compressor : {"auto", "correlation", "qr"}
        ``"auto"`` (default): the fast correlation path, and a second, exact pass when its
        Gram matrix is too ill-conditioned for the factor to match the exact one (relative
        pivot below ``sysid._sysid.AUTO_MIN_RELATIVE_PIVOT``; ``factor.source ==
        "qr-fallback"``); a one-pass iterator cannot be read twice, so there the factor is
        flagged ``"correlation-ill-conditioned"`` with a warning. ``"correlation"``: fast
        only (flagged and warned when ill-conditioned); ``"qr"``: exact.
    chunk_size : int
        Samples per push for array sources.
    progress : bool, optional
        Show a progress bar with rate and time left (tqdm if installed, else a counter line
        on stderr); default: when stderr is a terminal.

    Returns
    -------
    HankelFactor
        For :meth:`sysid.SubspaceEstimator.from_factor`.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.subspace.streaming import compress_stream
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((5000, 1))
    >>> e = 0.1 * rng.standard_normal((5000, 1))
    >>> y = np.convolve(u[:, 0], [1.0, 0.5, 0.25])[:5000, None] + e
    >>> chunks = ((u[s:s + 1000], y[s:s + 1000]) for s in range(0, 5000, 1000))
    >>> f = compress_stream(chunks, past=5, progress=False)
    >>> f.n_columns, f.source
    (4991, 'correlation')
    >>> f = compress_stream((u, 0 * e + y - e), past=5, progress=False)  # noise-free
    >>> f.source
    'qr-fallback'

    """
    compressor = as_option(compressor, "compressor")
    chunk_size = as_int(chunk_size, "chunk_size")
    past = as_int(past, "past")
    future = past if future is None else as_int(future, "future")
    if isinstance(source, tuple) and len(source) == 2 and _is_dask(source[1]):
        return compress_dask(source[0], source[1], past, future)
    exps = _experiments(source, int(chunk_size), input_columns, output_columns)
    if not exps:
        raise DataError("source has no experiments")
    totals = [n for _, n in exps]
    total = None if any(n is None for n in totals) else sum(n for n in totals if n is not None)
    # known lengths (arrays, memmaps, Parquet): the horizon is checked against the longest
    # experiment before the compressor is sized; a generator's record is checked at finish
    longest = None if total is None else max(n for n in totals if n is not None)
    bar = Bar(total, f"compress ({compressor})", unit="samples", enabled=show(progress),
              unit_scale=True)
    comp = None
    try:
        for chunks, _ in exps:
            for chunk in chunks:
                if not (isinstance(chunk, (tuple, list)) and len(chunk) == 2):
                    raise DataError(
                        "each chunk of the source must be a (u, y) pair (u may be None for "
                        f"output-only data), got {type(chunk).__name__}"
                    )
                u2, y2 = as_chunk(*chunk)
                if comp is None:
                    comp = _sysid.StreamingCompressor(
                        u2.shape[1], y2.shape[1], past, future, compressor, longest=longest
                    )
                comp.push(u2, y2)
                bar.update(y2.shape[0])
            if comp is not None:
                comp.end_experiment()
    finally:
        bar.close()
    if comp is None:
        raise DataError("source gave no samples")
    factor = comp.finish()
    if (compressor == "auto" and factor.source == "correlation-ill-conditioned"
            and _rereadable(source)):
        pivot = factor.relative_pivot
        exact = compress_stream(source, past, future, compressor="qr", chunk_size=chunk_size,
                                input_columns=input_columns, output_columns=output_columns,
                                progress=progress)
        factor = _sysid.HankelFactor.from_parts(
            exact.n_inputs, exact.n_outputs, exact.past, exact.future, exact.l,
            exact.n_columns, exact.n_experiments, "qr-fallback", pivot)
    warn_if_fallback(factor, requested=compressor)
    return factor


def _rereadable(source: Any) -> bool:
    """Whether a source can be read a second time (arrays, memmaps, file paths)."""
    if isinstance(source, list):
        return all(_rereadable(s) for s in source)
    if isinstance(source, (str, os.PathLike)):
        return True
    return isinstance(source, tuple) and len(source) == 2 and all(
        hasattr(a, "shape") or isinstance(a, (list, np.ndarray)) for a in source
    )


def _partial_sums(
    block: np.ndarray, m: int, past: int, future: int, center: np.ndarray, scale: np.ndarray,
    longest: int | None = None,
) -> Any:
    """Correlation sums of one Dask block (runs on a worker)."""
    block = np.asarray(block, dtype=np.float64)
    s = _sysid.CorrelationSums(m, block.shape[1] - m, past, future, center, scale,
                               longest=longest)
    s.push(block[:, :m], block[:, m:])
    return s


def _merge_tree(parts: list[Any]) -> Any:
    """Adjacent pairs first, in order: a fixed reduction tree."""
    while len(parts) > 1:
        nxt = [parts[i].merge(parts[i + 1]) for i in range(0, len(parts) - 1, 2)]
        if len(parts) % 2:
            nxt.append(parts[-1])
        parts = nxt
    return parts[0]


def compress_dask(
    u: Any, y: Any, past: int, future: int | None = None, *, min_relative_pivot: float = 1e-10
) -> Any:
    """Compress Dask arrays ``u`` (samples, m) and ``y`` (samples, l) with the correlation
    compressor, one block per task.

    Each block returns its lagged correlation sums and its first and last ``p + f - 1``
    samples (a few kilobytes); the driver merges them in a fixed order and factors the
    result. Runs on the active scheduler: a ``dask.distributed.Client`` if one is active.
    The result equals :func:`compress_stream` with ``compressor="correlation"`` up to
    round-off. Pass a list of ``(u, y)`` to :func:`compress_stream` for several experiments
    in memory; here, one record.

    Examples
    --------
    >>> import numpy as np, dask.array as da  # doctest: +SKIP
    >>> u = da.random.standard_normal((100_000, 2), chunks=(25_000, 2))  # doctest: +SKIP
    >>> f = compress_dask(u, u[:, :1] * 0.5, past=10)  # doctest: +SKIP
    """
    import dask
    import dask.array as da

    past = as_int(past, "past")
    future = past if future is None else as_int(future, "future")
    u = da.asarray(u)
    y = da.asarray(y)
    if u.ndim == 1:
        u = u[:, None]
    if y.ndim == 1:
        y = y[:, None]
    if u.shape[0] != y.shape[0]:
        raise DataError(f"u has {u.shape[0]} samples but y has {y.shape[0]}")
    m = int(u.shape[1])
    z = da.concatenate([u.astype(np.float64), y.astype(np.float64)], axis=1).rechunk({1: -1})
    head = np.asarray(z[: min(int(z.shape[0]), 10_000)].compute())
    if not np.isfinite(head).all():
        as_2d(head[:, m:], "y")
        as_2d(head[:, :m], "u", allow_empty=True)
    center, scale = _sysid.CorrelationSums.center_scale(
        np.ascontiguousarray(head[:, :m]), np.ascontiguousarray(head[:, m:])
    )
    # the horizon against the record's length, before any worker sizes its sums (an exact
    # compressor allocates nothing before its first window: a check that costs nothing)
    n = int(z.shape[0])
    _sysid.StreamingCompressor(m, int(z.shape[1]) - m, past, future, "qr", 1, longest=n)
    blocks = z.to_delayed().ravel()
    tasks = [dask.delayed(_partial_sums)(b, m, past, future, center, scale, n) for b in blocks]
    parts = list(dask.compute(*tasks))
    factor = _merge_tree(parts).to_factor(min_relative_pivot)
    warn_if_fallback(factor)
    return factor
