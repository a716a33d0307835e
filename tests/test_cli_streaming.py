"""The command line reads large CSV / Parquet files in blocks (pyarrow's streaming readers)
with a progress bar, and takes --compressor."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid import cli
from sysid.cli import load as cli_load  # the file reader: its STREAM_BYTES
from sysid.data import blocks
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
    monkeypatch.setattr(cli_load, "STREAM_BYTES", 0)  # treat the file as large
    code = cli.main(["identify", str(path), "--inputs", "u1,u2", "--outputs", "y", "--time",
                     "t", "--order", "1", "--report", str(tmp_path / "rep"),
                     "--compressor", compressor])
    assert code == 0
    err = capsys.readouterr().err
    assert "in blocks" in err
    assert f"compressed with {'correlation' if compressor == 'auto' else 'qr'}" in err


def _bad_file(path, cell: str, row: int, preamble: bool = True) -> int:
    """``_record`` as CSV (after a comment, and with a blank line after the header, with
    ``preamble``) with ``cell`` in column u2 of data row ``row``; returns the file line of
    that cell."""
    z = _record()
    head = ["# logger 7", "t,u1,u2,y", ""] if preamble else ["t,u1,u2,y"]
    lines = head + [",".join(f"{v:.17g}" for v in r) for r in z]
    k = len(head) + row  # index of the row's line in `lines`
    fields = lines[k].split(",")
    fields[2] = cell
    lines[k] = ",".join(fields)
    path.write_text("\n".join(lines) + "\n")
    return k + 1


@pytest.mark.parametrize("cell", ["abc", "", "nan", "inf", "-Infinity", "NA"])
def test_a_streamed_bad_cell_is_named_by_line_and_column_as_in_memory(tmp_path, capsys,
                                                                      monkeypatch, cell):
    path = tmp_path / "big.csv"
    line = _bad_file(path, cell, 2900, preamble=False)
    argv = ["identify", str(path), "--inputs", "u1,u2", "--outputs", "y", "--order", "1",
            "--report", str(tmp_path / "rep"), "--quiet"]
    assert cli.main(argv) == 2  # in memory (a small file)
    in_memory = capsys.readouterr().err
    assert f"big.csv line {line}, column 'u2'" in in_memory
    monkeypatch.setattr(cli_load, "STREAM_BYTES", 0)  # streamed
    monkeypatch.setattr(blocks, "STREAM_BLOCK", 4096)  # in about 40 blocks: the cell in a late one
    assert cli.main(argv) == 2
    assert capsys.readouterr().err == in_memory


def test_read_columns_names_the_bad_cell_of_any_block(tmp_path):
    path = tmp_path / "d.csv"
    for row in (0, 1500, 2999):
        line = _bad_file(path, {0: "x", 1500: "1.2.3", 2999: ""}[row], row)
        with pytest.raises(DataError, match=rf"d\.csv line {line}, column 'u2'"):
            cli.read_columns(path, ["y", "u2"], progress=False, block_size=2048)
    # the column that holds it is not asked for: no error, and the others read whole
    got = cli.read_columns(path, ["y", "u1"], progress=False, block_size=2048)
    np.testing.assert_array_equal(got, _record()[:, [3, 1]])


def test_read_columns_skips_comments_and_blank_lines_as_read_table(tmp_path):
    path = tmp_path / "d.csv"
    path.write_text("# sensor log\n\n# units: V\nt,u,y\n0,1,2\n\n   \n# note\n1,3,4\n2,5,6\n")
    for block in (64, None):
        np.testing.assert_array_equal(
            cli.read_columns(path, ["u", "y"], progress=False, block_size=block),
            [[1, 2], [3, 4], [5, 6]])
    path.write_text("t,u,y\n0,1,2\n1,3\n")  # a short row
    with pytest.raises(DataError, match="d.csv line 3: 2 fields but the header has 3"):
        cli.read_columns(path, ["u", "y"], progress=False)



def test_a_large_white_space_separated_file_is_read_as_a_small_one(tmp_path, monkeypatch,
                                                                   capsys):
    z = _record()
    path = tmp_path / "big.txt"
    np.savetxt(path, z, delimiter=" ", header="t u1 u2 y", comments="", fmt="%.17g")
    monkeypatch.setattr(cli_load, "STREAM_BYTES", 0)  # large: pyarrow splits no runs of spaces
    code = cli.main(["identify", str(path), "--inputs", "u1,u2", "--outputs", "y", "--order",
                     "1", "--report", str(tmp_path / "rep"), "--quiet"])
    assert code == 0, capsys.readouterr().err


def _identify(path, io: list[str], tmp_path) -> list[str]:
    return ["identify", str(path), *io, "--order", "1", "--report", str(tmp_path / "rep")]


@pytest.mark.parametrize("suffix", [".gz", ".bz2", ".xz"])
def test_a_compressed_file_is_read_decompressed_whatever_its_size(tmp_path, monkeypatch,
                                                                  capsys, suffix):
    import bz2
    import gzip
    import lzma

    z = _record()
    plain = tmp_path / "d.csv"
    np.savetxt(plain, z, delimiter=",", header="t,u1,u2,y", comments="", fmt="%.17g")
    pack = {".gz": gzip.compress, ".bz2": bz2.compress, ".xz": lzma.compress}[suffix]
    path = tmp_path / f"big.csv{suffix}"
    path.write_bytes(pack(plain.read_bytes()))
    np.testing.assert_array_equal(
        cli.read_columns(path, ["y", "u1"], progress=False, block_size=4096), z[:, [3, 1]])
    argv = _identify(path, ["--inputs", "u1,u2", "--outputs", "y"], tmp_path)
    assert cli.main(argv) == 0  # small: in memory
    memory = capsys.readouterr()
    assert "in blocks" not in memory.err
    # the size that counts is the text's: a file of less than STREAM_BYTES that holds more
    monkeypatch.setattr(cli_load, "STREAM_BYTES", path.stat().st_size + 1)
    assert path.stat().st_size < cli_load.STREAM_BYTES < plain.stat().st_size
    assert cli.main(argv) == 0
    streamed = capsys.readouterr()
    assert "in blocks" in streamed.err
    assert streamed.out == memory.out  # the same record, the same model


@pytest.mark.parametrize("stream", [False, True])
def test_a_zip_archive_is_refused_the_same_way_whatever_its_size(tmp_path, monkeypatch,
                                                                 capsys, stream):
    import zipfile

    path = tmp_path / "big.zip"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as f:
        f.writestr("d.csv", "u,y\n" + "1,2\n" * 5000)
    if stream:
        monkeypatch.setattr(cli_load, "STREAM_BYTES", 0)
    assert cli.main(_identify(path, ["--inputs", "u", "--outputs", "y"], tmp_path)) == 2
    err = capsys.readouterr().err
    assert "big.zip' is not a text table (binary content); a zip archive is not read: " \
        "unzip it" in err


def test_a_headerless_file_has_the_same_columns_whatever_its_size(tmp_path, monkeypatch,
                                                                 capsys):
    z = _record()
    path = tmp_path / "big.csv"
    np.savetxt(path, z, delimiter=",", fmt="%.17g", header="logger 7")  # "# logger 7" first
    argv = _identify(path, ["--inputs", "1,2", "--outputs", "3", "--time", "0"], tmp_path)
    assert cli.main(argv) == 0
    memory = capsys.readouterr()
    monkeypatch.setattr(cli_load, "STREAM_BYTES", 0)
    assert cli.main(argv) == 0
    streamed = capsys.readouterr()
    assert "in blocks" in streamed.err and streamed.out == memory.out
    # every row is data (the first one too), with a trailing delimiter, in any block
    path.write_text("".join(",".join(f"{v:.17g}" for v in r) + ",\n" for r in z))
    np.testing.assert_array_equal(
        cli.read_columns(path, ["3", "0"], progress=False, block_size=2048), z[:, [3, 0]])
    with pytest.raises(DataError, match=r"big\.csv: Column '4' .* does not exist"):
        cli.read_columns(path, ["4"], progress=False)  # the empty field after the delimiter


def test_a_headerless_file_names_a_bad_cell_as_in_memory(tmp_path, monkeypatch, capsys):
    path = tmp_path / "big.csv"
    line = _bad_file(path, "abc", 2500, preamble=False)
    path.write_text(path.read_text().split("\n", 1)[1])  # no header: the lines move up one
    argv = _identify(path, ["--inputs", "1,2", "--outputs", "3", "--quiet"], tmp_path)
    assert cli.main(argv) == 2
    in_memory = capsys.readouterr().err
    assert f"big.csv line {line - 1}, column '2'" in in_memory
    monkeypatch.setattr(cli_load, "STREAM_BYTES", 0)
    monkeypatch.setattr(blocks, "STREAM_BLOCK", 4096)
    assert cli.main(argv) == 2
    assert capsys.readouterr().err == in_memory


def test_a_comment_with_as_many_fields_as_the_header_is_skipped_when_streamed(tmp_path):
    """pyarrow took '#a,b,c' for a row: it stopped the read (a column asked for held '#a')
    or, worse, was read as data (the columns asked for held numbers)."""
    path = tmp_path / "d.csv"
    path.write_text("t,u,y\n0,1,2\n#a,b,c\n1,3,4\n# 7,8,9\n   # x,9,9\n2,5,6\n")
    want = [[1, 2], [3, 4], [5, 6]]
    np.testing.assert_array_equal(cli.read_csv(path)[1][:, 1:], want)
    for block in (16, None):
        np.testing.assert_array_equal(
            cli.read_columns(path, ["u", "y"], progress=False, block_size=block), want)
    path.write_text("\ufeff# log\r\n\r\n  \r\nt,u,y\r\n0,1,2\r\n# 7,8,9\r\n1,3,4\r\n")
    np.testing.assert_array_equal(cli.read_columns(path, ["u", "y"], progress=False),
                                  [[1, 2], [3, 4]])


@pytest.mark.parametrize("cell", ["1_000", "1_0.5", "１２"])
def test_python_only_number_syntax_is_refused_by_both_readers(tmp_path, cell):
    """float() reads 1_000 and full-width digits; pandas, numpy.loadtxt and pyarrow do not.
    The in-memory reader accepted them and the streamed one refused them with a message
    that named no cell: both now refuse them, by line and column."""
    path = tmp_path / "d.csv"
    path.write_text(f"t,u,y\n0,1,2\n1,{cell},4\n", encoding="utf-8")
    want = rf"d\.csv line 3, column 'u': '{cell}' is not a number"
    with pytest.raises(DataError, match=want):
        cli.read_csv(path)
    with pytest.raises(DataError, match=want):
        cli.read_columns(path, ["u", "y"], progress=False)
    if cell == "1_000":
        with pytest.raises(DataError, match="digits grouped with '_' are not read.*write 1000"):
            cli.read_csv(path)


@pytest.mark.parametrize("suffix", [".gz", ".bz2", ".xz"])
@pytest.mark.parametrize("damage", ["truncated", "corrupted"])
def test_a_damaged_compressed_file_is_named_as_damaged(tmp_path, suffix, damage):
    import bz2
    import gzip
    import lzma

    text = ("t,u,y\n" + "".join(f"{i},{i % 7},{i % 5}\n" for i in range(400000))).encode()
    pack = {".gz": gzip.compress, ".bz2": bz2.compress, ".xz": lzma.compress}[suffix]
    packed = bytearray(pack(text))
    half = len(packed) // 2
    if damage == "truncated":
        del packed[half:]
    else:
        packed[half:half + 64] = b"\xff" * 64
    path = tmp_path / f"d.csv{suffix}"
    path.write_bytes(bytes(packed))
    kind = {".gz": "gzip", ".bz2": "bzip2", ".xz": "xz"}[suffix]
    want = rf"d\.csv{suffix}: the {kind}-compressed file is damaged or truncated: its text " \
        r"ends after line [1-9]\d+ "
    for read in (lambda: cli.read_columns(path, ["u", "y"], progress=False),
                 lambda: cli.read_csv(path)):
        with pytest.raises(DataError, match=want):
            read()


def _logger_file(path, stamps: bool, bad: str | None = None, row: int = 2500) -> None:
    """``_record`` as a logger exports it: a units row under the header and, with
    ``stamps``, ISO 8601 date-time stamps (with an offset) in the time column; ``bad``
    replaces the time cell (stamps) or u2 (numbers) of data row ``row``."""
    z = _record()
    lines = ["time,u1,u2,y", "s,V,V,m"]
    for k, r in enumerate(z):
        t = (f"2026-03-01T{8 + int(r[0] // 3600):02d}:{int(r[0] % 3600 // 60):02d}:"
             f"{r[0] % 60:06.3f}+02:00" if stamps else f"{r[0]:.1f}")
        cells = [t] + [f"{v:.17g}" for v in r[1:]]
        if bad is not None and k == row:
            cells[0 if stamps else 2] = bad
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("stamps", [False, True])
def test_a_streamed_loggers_file_reads_as_in_memory(tmp_path, monkeypatch, capsys, stamps):
    """A file over the streaming size with a units row under its header ("s,V,V,m") or
    date-time stamps in its time column was refused ("'s' is not a number"), though the
    same file under that size was read; both read alike now, bad cells named alike."""
    path = tmp_path / "log.csv"
    _logger_file(path, stamps)
    argv = _identify(path, ["--inputs", "u1,u2", "--outputs", "y", "--quiet"], tmp_path)
    assert cli.main(argv) == 0
    small = sysid.load_model(tmp_path / "rep" / "model.json")
    monkeypatch.setattr(cli_load, "STREAM_BYTES", 0)
    monkeypatch.setattr(blocks, "STREAM_BLOCK", 4096)
    got = blocks.read_columns(path, ["u1", "time"], progress=False, stamps="time")
    np.testing.assert_allclose(got[:, 1], 0.1 * np.arange(3000), atol=1e-9)
    assert cli.main(argv) == 0
    big = sysid.load_model(tmp_path / "rep" / "model.json")
    assert big.dt == pytest.approx(0.1) and small.dt == pytest.approx(0.1)
    np.testing.assert_allclose(big.poles(), small.poles(), rtol=1e-12)
    capsys.readouterr()
    _logger_file(path, stamps, bad="oops")
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    if stamps:  # by its data row (line 2503: header, units row)
        assert "data row 2501, column 'time': 'oops' is not a date-time stamp" in err
    else:  # by its file line, as in memory
        assert "log.csv line 2503, column 'u2': 'oops' is not a number" in err


@pytest.mark.parametrize("streamed", [False, True])
def test_a_european_logger_file_with_decimal_commas(tmp_path, monkeypatch, capsys, streamed):
    """``Zeit;Eingang;Ausgang`` with ``0,08;4,9;11,2`` rows: the command said "'0,08' is not a
    number" with no way to read it (the Python readers take ``decimal=","``), the German
    time column was not recognised (dt = 1 s), and a time column's steps gave dt =
    0.08000000000000007. Now ``--decimal ,`` reads it, the error names that option, "Zeit"
    is a time column and dt is the 0.08 the column was written with; in memory and streamed
    alike."""
    if streamed:
        monkeypatch.setattr(cli_load, "STREAM_BYTES", 0)
    d = np.loadtxt(sysid.datasets.path("dryer"))
    path = tmp_path / "messung.csv"
    path.write_text("Zeit;Eingang;Ausgang\n" + "".join(
        f"{0.08 * k:.2f};{u};{y}\n".replace(".", ",") for k, (u, y) in enumerate(d)))
    argv = ["identify", str(path), "--inputs", "Eingang", "--outputs", "Ausgang", "--split",
            "500", "--order", "4", "--report", str(tmp_path / "out")]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert "line 2, column 'Eingang'" in err and "(a decimal comma? pass --decimal ,)" in err
    assert cli.main(argv + ["--decimal", ","]) == 0
    assert "sample time from the time column 'Zeit'" in capsys.readouterr().err
    model = sysid.load_model(tmp_path / "out" / "model.json")
    assert model.nstates == 4 and model.dt == 0.08
    ref = tmp_path / "ref.csv"  # the same numbers with decimal points
    ref.write_text("time,Eingang,Ausgang\n" + "".join(
        f"{0.08 * k:.2f},{u},{y}\n" for k, (u, y) in enumerate(d)))
    assert cli.main(["identify", str(ref), *argv[2:-1], str(tmp_path / "ref"), "--quiet"]) == 0
    np.testing.assert_array_equal(model.statespace.A,
                                  sysid.load_model(tmp_path / "ref" / "model.json").statespace.A)
