"""identify_many's text records (CSV and the like): only the record's columns are read,
after the file's line count bounds their size against the limit and the memory available;
a record too large is an error row naming the file, its size and the fix, as for Parquet."""

from __future__ import annotations

import gzip
import re
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import sysid
from sysid.batch import records
from sysid.batch.records import Columns, load
from sysid.data import table

TRUE = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=0.1)


def _wide(path: Path, n: int = 2000, extra: int = 200, head: bool = True,
          note: bool = True) -> np.ndarray:
    """A record (u, y) after ``extra`` columns the fit does not use (and, with ``note`` and
    ``head``, a text column)."""
    rng = np.random.default_rng(0)
    u = rng.standard_normal(n)
    y = TRUE.simulate(u[:, None])[:, 0] + 0.01 * rng.standard_normal(n)
    z = np.column_stack([rng.standard_normal((n, extra)), u, y])
    lines = [",".join(f"{v:.17g}" for v in r) + (",ok" if head and note else "") for r in z]
    if head:
        names = [f"extra{i}" for i in range(extra)] + ["u", "y"] + ["note"] * note
        lines.insert(0, ",".join(names))
    text = "\n".join(lines) + "\n"
    if path.suffix == ".gz":
        path.write_bytes(gzip.compress(text.encode()))
    else:
        path.write_text(text)
    return np.column_stack([u, y])


def test_only_the_records_columns_are_read(tmp_path):
    path = tmp_path / "wide.csv"
    z = _wide(path)
    tracemalloc.start()
    try:
        d = load(path, Columns(("u",), ("y",), 0.1), "wide")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    np.testing.assert_array_equal(np.hstack([d.u, d.y]), z)
    # the two columns (32 kB), one line's fields and a 1 MiB block of the line count at a
    # time (2 MB), not the file's 202 columns as strings (held whole and every column
    # converted, 5 times the file; and the text column "note" was an error)
    assert peak < path.stat().st_size  # far from both: 2.1 MB now, 5 times the file before


@pytest.mark.parametrize("name", ["r.csv.gz", "r.txt"])
def test_headerless_and_compressed_records_are_read_as_read_csv(tmp_path, name):
    path = tmp_path / name
    z = _wide(path, n=300, extra=2, head=False)
    if name.endswith(".txt"):  # white-space separated
        path.write_text(path.read_text().replace(",", "  "))
    d = load(path, Columns(("2",), ("3",), 0.1), "r")
    np.testing.assert_array_equal(np.hstack([d.u, d.y]), z)


def test_a_record_too_large_is_an_error_row_before_it_is_read(tmp_path, monkeypatch):
    folder = tmp_path / "records"
    folder.mkdir()
    _wide(folder / "small.csv", n=400, extra=0, note=False)
    _wide(folder / "big.csv", n=4000, extra=3, note=False)
    monkeypatch.setattr(records, "MAX_RECORD_BYTES", 2 * 1500 * 8)  # 1500 samples of u, y
    read = getattr(table, "read_named", None)

    def guarded(path, columns, rows, **kwargs):
        if rows > 1500:
            raise AssertionError("a record over the limit was read")
        return read(path, columns, rows, **kwargs)

    monkeypatch.setattr(table, "read_named", guarded, raising=False)
    monkeypatch.setattr(table, "read_table", lambda *a, **k: pytest.fail("read whole"))
    res = sysid.identify_many(folder, fit=lambda d: sysid.n4sid(d, 1), workers=0,
                              inputs=["u"], outputs=["y"], dt=0.1,
                              out=tmp_path / "t.parquet", progress=False)
    monkeypatch.undo()
    df = res.to_pandas().set_index("record_id")
    assert df["error"].isna()["small"] and df.loc["small", "order"] == 1
    err = df.loc["big", "error"]
    assert err.startswith("DataError: big.csv: at most 4000 rows x 2 columns need 0.0 GiB")
    assert "more than the 2.24e-05 GiB limit per record" in err
    assert "cut the record into shorter ones" in err and "compress_stream" in err


def test_bad_cells_missing_columns_and_files_are_named(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("# log\nu,y,note\n1,2,a\n3,x,b\n")
    with pytest.raises(sysid.DataError, match=r"r\.csv line 4, column 'y': 'x' is not a "
                       "number"):
        load(path, Columns(("u",), ("y",), 0.1), "r")
    with pytest.raises(sysid.DataError, match=r"r\.csv: no column\(s\) \['v'\]"):
        load(path, Columns(("v",), ("y",), 0.1), "r")
    with pytest.raises(sysid.DataError, match="give outputs="):
        load(path, Columns(("u",), None, 0.1), "r")
    with pytest.raises(sysid.DataError, match="no data file"):
        load(tmp_path / "none.csv", Columns(("u",), ("y",), 0.1), "r")
    path.write_bytes(b"u,y\n\0\1\2")
    with pytest.raises(sysid.DataError, match="not a text table"):
        load(path, Columns(("u",), ("y",), 0.1), "r")


def _damaged_folder(tmp_path: Path) -> Path:
    """good.csv and ok.csv.gz, and two damaged: trunc.csv.gz cut in half, flip.csv.xz with 64
    bytes overwritten in its middle."""
    import lzma

    folder = tmp_path / "records"
    folder.mkdir()
    _wide(folder / "good.csv", n=3000, extra=0, note=False)
    text = (folder / "good.csv").read_bytes()
    (folder / "ok.csv.gz").write_bytes(gzip.compress(text))
    packed = gzip.compress(text)
    (folder / "trunc.csv.gz").write_bytes(packed[:len(packed) // 2])
    flipped = bytearray(lzma.compress(text))
    half = len(flipped) // 2
    flipped[half:half + 64] = b"\xff" * 64
    (folder / "flip.csv.xz").write_bytes(bytes(flipped))
    (folder / "notes.json.gz").write_bytes(gzip.compress(b"{}"))  # no record
    return folder


@pytest.mark.parametrize("as_paths", [False, True])
def test_a_damaged_compressed_record_is_an_error_row_naming_the_file(tmp_path, as_paths):
    """A damaged .gz/.xz record is an error row naming the file and the damage, as any
    unreadable record is; the others are fitted. A folder listed no compressed record at
    all before (ok.csv.gz, trunc.csv.gz and flip.csv.xz were silently left out)."""
    folder = _damaged_folder(tmp_path)
    source = sorted(str(p) for p in folder.glob("*.csv*")) if as_paths else folder
    res = sysid.identify_many(source, fit=lambda d: sysid.n4sid(d, 1), workers=0,
                              inputs=["u"], outputs=["y"], dt=0.1,
                              out=tmp_path / "t.parquet", progress=False)
    df = res.to_pandas()
    if as_paths:  # ids of a list: its positions
        df["record_id"] = [Path(source[int(i)]).name.split(".")[0] for i in df["record_id"]]
    df = df.set_index("record_id").sort_index()
    assert list(df.index) == ["flip", "good", "ok", "trunc"] and res.n_ok == 2
    assert df["error"].isna()["good"] and df["error"].isna()["ok"]
    assert df.loc["ok", "order"] == 1
    damaged = r"the {}-compressed file is damaged or truncated: its text ends after line \d+ "
    assert re.match(r"DataError: trunc\.csv\.gz: " + damaged.format("gzip"),
                    df.loc["trunc", "error"]), df.loc["trunc", "error"]
    assert re.match(r"DataError: flip\.csv\.xz: " + damaged.format("xz"),
                    df.loc["flip", "error"]), df.loc["flip", "error"]
    for err in df.loc[["trunc", "flip"], "error"]:
        assert "Traceback" not in err and "zlib" not in err and "LZMAError" not in err


def test_a_folder_refuses_two_files_of_one_record(tmp_path):
    folder = tmp_path / "records"
    folder.mkdir()
    _wide(folder / "a.csv", n=50, extra=0, note=False)
    (folder / "a.csv.gz").write_bytes(gzip.compress((folder / "a.csv").read_bytes()))
    with pytest.raises(sysid.DataError, match=r"a\.csv and a\.csv\.gz in .* are both record "
                       "'a': keep one of them"):
        sysid.identify_many(folder, workers=0, out=tmp_path / "t.parquet", progress=False)


@pytest.mark.parametrize("kind", ["csv", "parquet", "frame"])
def test_a_records_time_column_gives_its_sample_time(tmp_path, kind):
    """identify_many on a folder of logger files with a "Time [s]" column and no
    time_column= fitted every record at dt = 1 s (the dryer's 0.08 s record: a model whose
    every frequency was off by 12.5), silently; the column is now taken, as from_csv does."""
    rng = np.random.default_rng(1)
    u = rng.standard_normal(300)
    y = TRUE.simulate(u[:, None])[:, 0]
    t = 0.25 * np.arange(300)
    if kind == "frame":
        import pandas as pd

        src = pd.DataFrame({"Time [s]": t, "u": u, "y": y})
    elif kind == "csv":
        src = tmp_path / "r.csv"
        src.write_text("Time [s],u,y\n" + "\n".join(f"{a:.17g},{b:.17g},{c:.17g}"
                                                   for a, b, c in zip(t, u, y)) + "\n")
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq

        src = tmp_path / "r.parquet"
        pq.write_table(pa.table({"Time [s]": t, "u": u, "y": y}), src)
    rec = load(src, Columns(("u",), ("y",)), "r")
    assert rec.dt == pytest.approx(0.25) and rec.n_inputs == 1 and rec.n_outputs == 1
    np.testing.assert_array_equal(rec.y[:, 0], y)
    # dt given, or the time-named column chosen as an output: no time column taken
    assert load(src, Columns(("u",), ("y",), dt=0.5), "r").dt == 0.5
    assert load(src, Columns(("u",), ("y", "Time [s]")), "r").dt == 1.0
