"""identify_many's Parquet records: only the record's columns are read, after their size is
checked against the limit and the memory available; a record too large is an error row
naming the file, its size and the fix, not an out-of-memory crash."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import sysid
from sysid.batch import records
from sysid.batch.records import Columns, check_record_size, load

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")

TRUE = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=0.1)
PYTHON = str(Path(sysid.__file__).parents[1])


def _wide(path: Path, n: int = 20000, extra: int = 200) -> np.ndarray:
    """A record (u, y) and ``extra`` columns the fit does not use."""
    rng = np.random.default_rng(0)
    u = rng.standard_normal(n)
    y = TRUE.simulate(u[:, None])[:, 0] + 0.01 * rng.standard_normal(n)
    cols = {f"extra{i}": rng.standard_normal(n) for i in range(extra)}
    pq.write_table(pa.table({**cols, "y": y, "u": u}), path)
    return np.column_stack([u, y])


def test_only_the_records_columns_are_read(tmp_path):
    path = tmp_path / "wide.parquet"
    z = _wide(path)
    d = load(path, Columns(("u",), ("y",), 0.1), "wide")
    np.testing.assert_array_equal(np.hstack([d.u, d.y]), z)
    # pyarrow's peak allocation in a fresh process: the two columns (0.3 MB), not the file's
    # 202 (32 MB; read whole, and then as a pandas frame, it was 70 MB)
    code = ("import pyarrow as pa, sys; from sysid.batch.records import Columns, load; "
            "load(sys.argv[1], Columns(('u',), ('y',), 0.1), 'wide'); "
            "print(pa.default_memory_pool().max_memory())")
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True,
                         text=True, check=True, env={"PYTHONPATH": PYTHON, "PATH": ""})
    # (a bound far from both: pyarrow's pool peaks at 1.2-1.4 MB between runs for the two
    # columns; the file's 202 columns are 32 MB)
    assert int(out.stdout) < 202 * z.shape[0] * 8 / 4


def test_a_record_too_large_is_an_error_row_before_it_is_read(tmp_path, monkeypatch):
    folder = tmp_path / "records"
    folder.mkdir()
    _wide(folder / "small.parquet", n=400, extra=0)
    _wide(folder / "big.parquet", n=4000, extra=3)
    monkeypatch.setattr(records, "MAX_RECORD_BYTES", 2 * 1500 * 8)  # 1500 samples of u, y
    read = pq.ParquetFile.read

    def guarded(self, *args, **kwargs):
        if self.metadata.num_rows > 1500:
            raise AssertionError("a record over the limit was read")
        return read(self, *args, **kwargs)

    monkeypatch.setattr(pq.ParquetFile, "read", guarded)
    monkeypatch.setattr(pq, "read_table", lambda *a, **k: pytest.fail("the whole file read"))
    res = sysid.identify_many(folder, fit=lambda d: sysid.n4sid(d, 1), workers=0,
                              inputs=["u"], outputs=["y"], dt=0.1,
                              out=tmp_path / "t.parquet", progress=False)
    monkeypatch.undo()
    df = res.to_pandas().set_index("record_id")
    assert df["error"].isna()["small"] and df.loc["small", "order"] == 1
    err = df.loc["big", "error"]
    assert err.startswith("DataError: big.parquet: 4000 rows x 2 columns need 0.0 GiB")
    assert "more than the 2.24e-05 GiB limit per record" in err
    assert "cut the record into shorter ones" in err and "compress_stream" in err


def test_the_limit_follows_the_available_memory(monkeypatch):
    monkeypatch.setattr(records, "available_memory", lambda: 8 << 30)
    check_record_size("r.parquet", (2 << 30) // 8, 1)  # a quarter of it: read
    with pytest.raises(sysid.DataError, match=r"r\.parquet: .* more than 25% of the 8 GiB "
                       r"of memory available"):
        check_record_size("r.parquet", (2 << 30) // 8, 2)
    monkeypatch.setattr(records, "available_memory", lambda: None)
    with pytest.raises(sysid.DataError, match="more than the 4 GiB limit per record"):
        check_record_size("r.parquet", (4 << 30) // 8 + 1, 1)


def test_missing_columns_and_text_columns_are_named(tmp_path):
    path = tmp_path / "r.parquet"
    pq.write_table(pa.table({"u": [1.0, 2.0], "y": ["a", "b"]}), path)
    with pytest.raises(sysid.DataError, match=r"r\.parquet: no column\(s\) \['v'\]"):
        load(path, Columns(("v",), ("y",), 0.1), "r")
    with pytest.raises(sysid.DataError, match=r"r\.parquet: a column is not numeric"):
        load(path, Columns(("u",), ("y",), 0.1), "r")
    with pytest.raises(sysid.DataError, match="give outputs="):
        load(path, Columns(("u",), None, 0.1), "r")
