"""``sysid identify --fill-gaps N``: a logger's missing cells. The command refused any
missing cell and its error named only the Python reader's remedy; a record with a few
dropped samples had to be repaired by hand before the command could read it."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

import sysid
from sysid.cli import load as cli_load
from sysid.cli import main
from sysid.cli.load import fill_gaps


def _dryer(path: Path, holes: dict[int, int]) -> np.ndarray:
    """The shipped dryer record as CSV with the temperature's cells of the rows in ``holes``
    (row -> run length) left empty; returns the record."""
    d = np.loadtxt(sysid.datasets.path("dryer"))
    gone = {r + k for r, n in holes.items() for k in range(n)}
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time", "heater", "temperature"])
        for k, (u, y) in enumerate(d):
            w.writerow([f"{0.08 * k:.2f}", u, "" if k in gone else y])
    return d


@pytest.mark.parametrize("streamed", [False, True], ids=["in memory", "in blocks"])
def test_short_gaps_are_filled_and_long_ones_named(tmp_path, capsys, monkeypatch, streamed):
    if streamed:
        monkeypatch.setattr(cli_load, "STREAM_BYTES", 0)
    path = tmp_path / "dryer.csv"
    d = _dryer(path, {0: 2, 300: 3, 620: 1})
    args = ["identify", str(path), "--inputs", "heater", "--outputs", "temperature",
            "--time", "time", "--split", "500", "--order", "4", "--quiet"]
    assert main(args + ["--report", str(tmp_path / "r0")]) == 2
    err = capsys.readouterr().err
    assert "column 'temperature'" in err and "--fill-gaps N" in err
    assert main(args + ["--fill-gaps", "3", "--report", str(tmp_path / "r1")]) == 0
    model = sysid.load_model(tmp_path / "r1" / "model.json")
    pre = model.info["preprocessing"]
    # the two rows at the start dropped; the runs of 3 and 1 inside filled
    assert pre["filled_gaps"] == {"filled_cells": 4, "max_gap": 3, "rows_kept": [2, 1000],
                                  "rows_in_file": 1000}
    assert pre["estimation_samples"] == [0, 500]
    # the model fits the record as well as the one from the complete file
    full = tmp_path / "full.csv"
    _dryer(full, {})
    argf = [a if a != str(path) else str(full) for a in args]
    assert main(argf + ["--report", str(tmp_path / "r2")]) == 0
    ref = sysid.load_model(tmp_path / "r2" / "model.json")
    val = sysid.IOData(u=d[500:, :1], y=d[500:, 1:], dt=0.08)
    fits = [float(np.mean(sysid.compare(val, m).fit)) for m in (model, ref)]
    assert fits[0] > fits[1] - 2.0, fits
    # a run longer than N is refused, naming its column, rows and length
    _dryer(path, {300: 5})
    assert main(args + ["--fill-gaps", "3", "--report", str(tmp_path / "r3")]) == 2
    err = capsys.readouterr().err
    assert "'temperature' misses 5 samples in a row (data rows 301-305)" in err
    assert "nan='split'" in err


def test_fill_gaps_interpolates_between_the_samples_around_a_run():
    y = np.array([[1.0], [np.nan], [np.nan], [4.0], [5.0], [np.nan]])
    u = np.arange(6.0)[:, None]
    t = np.arange(6.0) * 0.5
    said = []
    u2, y2, t2, note = fill_gaps(u, y, t, 2, ["u", "y"], said.append)
    assert y2.ravel().tolist() == [1.0, 2.0, 3.0, 4.0, 5.0]
    assert u2.ravel().tolist() == [0.0, 1.0, 2.0, 3.0, 4.0] and t2[-1] == 2.0
    assert note == {"filled_cells": 2, "max_gap": 2, "rows_kept": [0, 5], "rows_in_file": 6}
    assert "filled 2 missing cell(s)" in said[0] and "dropped 1 row(s)" in said[0]
    assert fill_gaps(u, np.ones((6, 1)), t, 2, ["u", "y"], said.append)[3] is None
    with pytest.raises(sysid.DataError, match="--fill-gaps must be a positive"):
        fill_gaps(u, y, t, 0, ["u", "y"], said.append)
    with pytest.raises(sysid.DataError, match="every row misses"):
        fill_gaps(u, np.full((6, 1), np.nan), t, 2, ["u", "y"], said.append)
