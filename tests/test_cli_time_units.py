"""The command line reads a time column in the unit its header, units row or name gives
(``time_ms``, ``Time [ms]``, a logger's ``ms`` row, ``t_us``), as ``IOData.from_csv`` does:
a column of milliseconds 10 apart gave dt = 10 s (model.json, the printed model, the
report's frequencies 1000 times too low) where the reader gives 0.01 s. A ``--dt`` beside
a time column must agree with it, as ``dt=`` must for the readers."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid import cli
from sysid.cli import identify_command, parser
from sysid.cli import load as cli_load  # the file reader: its STREAM_BYTES
from sysid.errors import DataError

PLANT = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.0]], [[1.0, 0.5]])


def _write(path, head: list[str], scale: float, units_row: str | None = None) -> None:
    """400 samples 0.01 s apart, the time written in units of ``scale`` seconds."""
    rng = np.random.default_rng(11)
    u = rng.standard_normal(400)
    y = PLANT.simulate(u)[:, 0] + 0.05 * rng.standard_normal(400)
    t = np.arange(400) * 0.01 / scale
    lines = [",".join(head)] + ([units_row] if units_row else [])
    lines += [f"{a:.15g},{b:.8g},{c:.8g}" for a, b, c in zip(t, u, y)]
    path.write_text("\n".join(lines) + "\n")


def _run(path, out, *extra: str) -> int:
    return cli.main(["identify", str(path), "--inputs", "u", "--outputs", "y", "--order", "2",
                     "--method", "moesp", "--quiet", "--report", str(out), *extra])


@pytest.mark.parametrize(("head", "scale", "units_row"), [
    (["time_ms", "u", "y"], 1e-3, None),
    (["Time [ms]", "u", "y"], 1e-3, None),
    (["time", "u", "y"], 1e-3, "ms,V,degC"),
    (["t_us", "u", "y"], 1e-6, None),
    (["Time (min)", "u", "y"], 60.0, None),
    (["time", "u", "y"], 1.0, None),
])
def test_the_time_column_is_read_in_its_unit(tmp_path, head, scale, units_row):
    path = tmp_path / "d.csv"
    _write(path, head, scale, units_row)
    assert _run(path, tmp_path / "out") == 0
    dt = sysid.load_model(tmp_path / "out" / "model.json").dt
    assert dt == pytest.approx(0.01)  # 0.01 s, whatever the unit
    reader = sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"])
    assert dt == pytest.approx(reader.dt, rel=1e-9)
    # named with --time, the same
    assert _run(path, tmp_path / "named", "--time", head[0]) == 0
    assert sysid.load_model(tmp_path / "named" / "model.json").dt == pytest.approx(0.01)


def test_a_streamed_file_reads_its_time_column_in_its_unit(tmp_path, monkeypatch):
    monkeypatch.setattr(cli_load, "STREAM_BYTES", 0)  # read in blocks
    path = tmp_path / "d.csv"
    _write(path, ["Time [ms]", "u", "y"], 1e-3)
    assert _run(path, tmp_path / "out") == 0
    assert sysid.load_model(tmp_path / "out" / "model.json").dt == pytest.approx(0.01)
    with pytest.raises(DataError, match="disagrees with its time column 'Time \\[ms\\]'"):
        identify_command._identify(parser._parser().parse_args(
            ["identify", str(path), "--inputs", "u", "--outputs", "y", "--order", "2",
             "--method", "moesp", "--quiet", "--report", str(tmp_path / "o2"), "--dt", "10"]))


@pytest.mark.parametrize(("head", "scale"), [(["time_ms", "u", "y"], 1e-3),
                                             (["time", "u", "y"], 1.0)])
def test_a_dt_that_disagrees_with_the_time_column_is_refused(tmp_path, capsys, head, scale):
    path = tmp_path / "d.csv"
    _write(path, head, scale)
    with pytest.raises(DataError, match="disagrees"):  # what the reader says of dt=
        sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], dt=10.0)
    capsys.readouterr()
    assert _run(path, tmp_path / "bad", "--dt", "10") == 2
    err = capsys.readouterr().err
    assert "--dt 10 s disagrees with its time column" in err and "0.01 s apart" in err
    assert "leave --dt out" in err and not (tmp_path / "bad" / "model.json").exists()
    assert _run(path, tmp_path / "ok", "--dt", "0.01") == 0  # one that agrees is taken
    assert sysid.load_model(tmp_path / "ok" / "model.json").dt == 0.01


def test_a_dt_beside_a_text_column_named_time_is_taken(tmp_path):
    # a column named "time" that holds no times (labels) says nothing of the sample time
    rng = np.random.default_rng(0)
    u = rng.standard_normal(300)
    y = PLANT.simulate(u)[:, 0]
    path = tmp_path / "d.csv"
    path.write_text("time,u,y\n" + "\n".join(f"run{k},{a},{b}" for k, (a, b) in
                                            enumerate(zip(u, y))) + "\n")
    assert _run(path, tmp_path / "out", "--dt", "0.5") == 0
    assert sysid.load_model(tmp_path / "out" / "model.json").dt == 0.5


@pytest.mark.parametrize(("where", "step", "kind"), [(150, 0.06, "a gap"),
                                                      (150, 0.0095, "jitter")])
def test_an_irregular_time_column_is_refused_as_the_reader_refuses_it(tmp_path, capsys,
                                                                       where, step, kind):
    """A time column with missing samples (a logger's 5 samples lost at once) or jitter was
    read by the command line at its median spacing, every sample taken as one step apart
    (a balancing robot's log with 12 gaps, a heater log with 5 s +- 10 % stamps, both
    identified without a word), where ``IOData.from_csv`` refuses the same file. It is now
    refused the same way, naming the place and saying what to do."""
    rng = np.random.default_rng(12)
    u = rng.standard_normal(400)
    y = PLANT.simulate(u)[:, 0] + 0.05 * rng.standard_normal(400)
    t = np.arange(400) * 0.01
    t[where:] += step - 0.01
    path = tmp_path / "rec.csv"
    path.write_text("time,u,y\n" + "\n".join(f"{a:.15g},{b:.8g},{c:.8g}"
                                             for a, b, c in zip(t, u, y)) + "\n")
    with pytest.raises(DataError, match=f"irregular sampling: {kind} at sample {where}"):
        sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"])
    assert _run(path, tmp_path / "out") == 2
    err = capsys.readouterr().err
    assert f"irregular sampling: {kind} at sample {where}" in err
    assert "time column 'time'" in err and not (tmp_path / "out" / "model.json").exists()
