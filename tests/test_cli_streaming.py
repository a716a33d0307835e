"""The command line reads large CSV / Parquet files in blocks (pyarrow's streaming readers)
with a progress bar, and takes --compressor."""

from __future__ import annotations

import numpy as np
import pytest

from sysid import cli
from sysid.errors import DataError


def _record(n: int = 3000) -> np.ndarray:
    rng = np.random.default_rng(0)
    u = rng.standard_normal((n, 2))
    y = np.zeros(n)
    for t in range(1, n):
        y[t] = 0.7 * y[t - 1] + u[t - 1, 0] - 0.5 * u[t - 1, 1]
    y += 0.05 * rng.standard_normal(n)
    return np.column_stack([0.1 * np.arange(n), u, y])


def test_read_columns_csv_and_parquet_match_the_file(tmp_path, capsys):
    z = _record()
    path = tmp_path / "d.csv"
    np.savetxt(path, z, delimiter=",", header="t,u1,u2,y", comments="", fmt="%.17g")
    got = cli.read_columns(path, ["y", "u1"], progress=True)
    np.testing.assert_array_equal(got, z[:, [3, 1]])
    err = capsys.readouterr().err
    assert "reading d.csv" in err and "100%" in err  # a bar with rate, even in a log
    pq = pytest.importorskip("pyarrow.parquet")
    pa = pytest.importorskip("pyarrow")
    ppath = tmp_path / "d.parquet"
    pq.write_table(pa.table({"u1": z[:, 1], "u2": z[:, 2], "y": z[:, 3]}), ppath,
                   row_group_size=700)
    np.testing.assert_array_equal(cli.read_columns(ppath, ["u2", "y"], progress=False),
                                  z[:, [2, 3]])
    with pytest.raises(DataError, match="no column"):
        cli.read_columns(ppath, ["nope"], progress=False)
    with pytest.raises(DataError, match="d.csv"):
        cli.read_columns(path, ["nope"], progress=False)


@pytest.mark.parametrize("compressor", ["auto", "qr"])
def test_identify_streams_a_large_file_with_the_chosen_compressor(tmp_path, capsys,
                                                                  monkeypatch, compressor):
    z = _record()
    path = tmp_path / "big.csv"
    np.savetxt(path, z, delimiter=",", header="t,u1,u2,y", comments="", fmt="%.17g")
    monkeypatch.setattr(cli, "STREAM_BYTES", 0)  # treat the file as large
    code = cli.main(["identify", str(path), "--inputs", "u1,u2", "--outputs", "y", "--time",
                     "t", "--order", "1", "--report", str(tmp_path / "rep"),
                     "--compressor", compressor])
    assert code == 0
    err = capsys.readouterr().err
    assert "in blocks" in err
    assert f"compressed with {'correlation' if compressor == 'auto' else 'qr'}" in err
