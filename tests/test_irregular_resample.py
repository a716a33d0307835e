"""Records with jittered or gappy time stamps (a logger's, a PLC historian's) read with
``resample=``: ``IOData.from_csv`` and ``from_pandas`` refused them and pointed to
``IOData.from_irregular``, which takes arrays only; the command line refused them with no
way through. The readers and ``sysid identify --resample`` now interpolate them onto a
uniform grid with ``from_irregular``'s interpolation, note what they did
(``record.resampling``) and refuse an outage longer than ``resample_gap`` sample times."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import sysid
from sysid import cli
from sysid.errors import DataError, NonFiniteError

H = 0.01  # the logger's nominal sample time


def _u(t):
    return np.cos(2 * np.pi * 0.7 * t)


def _y(t):
    return np.sin(2 * np.pi * 0.5 * t) + 0.3 * np.cos(2 * np.pi * 1.3 * t)


#: the largest second derivatives of _u and _y
U2, Y2 = (2 * np.pi * 0.7) ** 2, (2 * np.pi * 0.5) ** 2 + 0.3 * (2 * np.pi * 1.3) ** 2


def _stamps(n=2000, seed=0, jitter=0.3 * H):
    t = np.arange(n) * H + np.random.default_rng(seed).uniform(-jitter, jitter, n)
    return t - t[0]


def _write(path, t, head="time,u,y", u=None, y=None):
    u = _u(t) if u is None else u
    y = _y(t) if y is None else y
    path.write_text(head + "\n" + "\n".join(f"{a:.9f},{b:.12g},{c:.12g}"
                                            for a, b, c in zip(t, u, y)) + "\n")


def _bound(t, second):
    """Linear interpolation's error bound, h^2 / 8 max |f''| over the longest interval
    (plus the file's rounding)."""
    return np.max(np.diff(t)) ** 2 / 8 * second + 1e-9


@pytest.mark.parametrize("resample", ["median", H])
def test_jittered_stamps_resampled_match_the_uniform_truth(tmp_path, resample):
    t = _stamps()
    path = tmp_path / "log.csv"
    _write(path, t)
    with pytest.raises(DataError, match="resample="):  # the refusal names the option
        sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"])
    d = sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample=resample)
    if resample == "median":
        assert d.dt == pytest.approx(np.median(np.diff(t)), rel=1e-6)
    else:
        assert d.dt == H
    assert d.time[0] == 0.0 and d.time[-1] <= t[-1] + 1e-12
    assert np.max(np.abs(d.y[:, 0] - _y(d.time))) < _bound(t, Y2)
    assert np.max(np.abs(d.u[:, 0] - _u(d.time))) < _bound(t, U2)
    # the error is interpolation's, not a shift: far below the signals' change per sample
    assert np.max(np.abs(d.y[:, 0] - _y(d.time))) < 0.1 * np.max(np.abs(np.diff(d.y[:, 0])))
    r = d.resampling
    assert (r.dt, r.n_stamps, r.n_samples, r.method) == (d.dt, t.size, d.n_samples, "linear")
    k = int(np.argmax(np.diff(t)))
    assert r.largest_gap == pytest.approx(np.diff(t)[k]) and r.gap_after == pytest.approx(t[k])
    assert f"dt = {d.dt:g} s" in str(r) and d.experiment(0).resampling == r  # kept on slices
    assert repr(d).endswith(", resampled")
    # a record read as it was sampled notes nothing
    assert sysid.IOData(u=np.ones(5), y=np.arange(5.0)).resampling is None


def test_from_pandas_resamples_as_from_csv_does(tmp_path):
    pd = pytest.importorskip("pandas")
    t = _stamps(seed=1)
    path = tmp_path / "log.csv"
    _write(path, t)
    df = pd.DataFrame({"time": t, "u": _u(t), "y": _y(t)})
    with pytest.raises(DataError, match="resample="):
        sysid.IOData.from_pandas(df, ["u"], ["y"])
    a = sysid.IOData.from_pandas(df, ["u"], ["y"], resample=H)
    b = sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample=H)
    assert a.lengths == b.lengths and np.allclose(a.y, b.y, atol=1e-9)
    assert a.resampling.n_samples == b.resampling.n_samples
    with pytest.raises(DataError, match="no time column"):
        sysid.IOData.from_pandas(df[["u", "y"]], ["u"], ["y"], resample=H)
    with pytest.raises(DataError, match="not both"):
        sysid.IOData.from_pandas(df, ["u"], ["y"], resample=H, dt=H)
    with pytest.raises(DataError, match="not both"):
        sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample=H, dt=H)


def test_a_gap_longer_than_the_limit_is_refused_naming_it(tmp_path):
    t = _stamps()
    t[1200:] += 0.5  # an outage of half a second after sample 1199
    path = tmp_path / "log.csv"
    _write(path, t)
    with pytest.raises(DataError) as e:
        sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample=H)
    msg = str(e.value)
    gap = t[1200] - t[1199]
    assert f"jump by {gap:g} s" in msg and f"after t = {t[1199]:g} s" in msg
    assert "(sample 1199)" in msg and "resample_gap = 5 " in msg
    assert f"resample_gap={int(np.ceil(gap / H))}" in msg
    # allowed: bridged, and noted
    d = sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample=H,
                              resample_gap=int(np.ceil(gap / H)))
    assert d.resampling.largest_gap == pytest.approx(gap)
    assert d.resampling.gap_after == pytest.approx(t[1199])
    assert sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample=H,
                                 resample_gap=np.inf).n_samples == d.n_samples
    with pytest.raises(DataError, match="resample_gap must be a positive"):
        sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample=H, resample_gap=0)
    with pytest.raises(DataError, match="resample must be"):
        sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample="mean")


def test_empty_values_and_experiments_with_resample(tmp_path):
    t = _stamps(400)
    y = _y(t)
    y[100] = np.nan
    path = tmp_path / "log.csv"
    path.write_text("time,u,y\n" + "\n".join(
        f"{a:.9f},{b:.12g}," + ("" if np.isnan(c) else f"{c:.12g}")
        for a, b, c in zip(t, _u(t), y)) + "\n")
    with pytest.raises(NonFiniteError, match="sample 100.*nan='interpolate'"):
        sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample=H)
    d = sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample=H,
                              nan="interpolate")
    assert d.resampling.n_stamps == 399
    assert np.max(np.abs(d.y[:, 0] - _y(d.time))) < _bound(np.delete(t, 100), Y2)
    # two experiments, each on its own grid at one sample time
    t2 = _stamps(300, seed=3) + 7.0
    rows = [(a, 0, _u(a), _y(a)) for a in t] + [(a, 1, _u(a), _y(a)) for a in t2]
    path.write_text("time,experiment,u,y\n" + "\n".join(
        f"{a:.9f},{k},{b:.12g},{c:.12g}" for a, k, b, c in rows) + "\n")
    d = sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample="median")
    assert d.n_experiments == 2 and d.resampling.n_stamps == 700
    assert d.times[1][0] == pytest.approx(t2[0])
    for e, tt in zip(d.experiments, d.times):
        assert np.max(np.abs(e[1][:, 0] - _y(tt))) < _bound(np.r_[t, t2], Y2)


def _run(path, out, *extra):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return cli.main(["identify", str(path), "--inputs", "u", "--outputs", "y", "--order",
                         "2", "--method", "moesp", "--report", str(out), *extra])


def _plant_log(path, t):
    """A second-order plant driven by white noise, logged at the stamps ``t``: the plant is
    simulated on a grid 10 times finer and read at the stamps."""
    rng = np.random.default_rng(5)
    fine = np.arange(int(t[-1] / H * 10) + 11) * H / 10
    u_fine = np.repeat(rng.standard_normal(fine.size // 10 + 1), 10)[: fine.size]
    plant = sysid.StateSpaceModel([[0.98, 0.03], [-0.03, 0.98]], [[0.1], [0.0]],
                                  [[1.0, 0.5]], dt=H / 10)
    y_fine = plant.simulate(u_fine)[:, 0]
    _write(path, t, u=np.interp(t, fine, u_fine), y=np.interp(t, fine, y_fine))


def test_the_command_line_resamples_with_resample(tmp_path, capsys):
    t = _stamps(1500, seed=4, jitter=0.1 * H)
    path = tmp_path / "log.csv"
    _plant_log(path, t)
    assert _run(path, tmp_path / "refused") == 2
    err = capsys.readouterr().err
    assert "time column 'time': irregular sampling" in err and "--resample median" in err
    assert not (tmp_path / "refused").exists() or not any((tmp_path / "refused").iterdir())
    assert _run(path, tmp_path / "out", "--resample", "0.01") == 0
    err = capsys.readouterr().err
    assert "resampled 1500 time stamps onto" in err
    assert sysid.load_model(tmp_path / "out" / "model.json").dt == H
    same = sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample=H)
    pre = json.dumps(json.loads((tmp_path / "out" / "model.json").read_text()))
    assert '"resampled"' in pre and f'"n_samples": {same.n_samples}' in pre
    assert _run(path, tmp_path / "median", "--resample", "median") == 0
    dt = sysid.load_model(tmp_path / "median" / "model.json").dt
    assert dt == pytest.approx(np.median(np.diff(t)), rel=1e-6)
    # an outage is refused, naming it and the option that bridges it
    t[900:] += 0.3
    _plant_log(path, t)
    assert _run(path, tmp_path / "gap", "--resample", "0.01") == 2
    err = capsys.readouterr().err
    need = str(int(np.ceil((t[900] - t[899]) / H)))
    assert f"after t = {t[899]:g} s" in err and f"--resample-gap {need} " in err
    assert _run(path, tmp_path / "gap", "--resample", "0.01", "--resample-gap", need) == 0
    # without a time column there is nothing to resample
    path.write_text("u,y\n" + "\n".join(f"{a},{a}" for a in range(50)) + "\n")
    assert _run(path, tmp_path / "none", "--resample", "0.01", "--dt", "0.01") == 2
    assert "--resample needs a time column" in capsys.readouterr().err


def _on_the_grid(d):
    """A "fit" that checks the record it is given was resampled at H."""
    assert d.resampling is not None and d.dt == H
    return sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=d.dt)


def test_identify_many_resamples_its_records_as_from_csv_does(tmp_path):
    pytest.importorskip("pyarrow")
    from sysid.batch.records import Columns, load

    t = _stamps(600, seed=6)
    _write(tmp_path / "a.csv", t)
    with pytest.raises(DataError, match="resample="):
        load(tmp_path / "a.csv", Columns(("u",), ("y",)), "a")
    got = load(tmp_path / "a.csv", Columns(("u",), ("y",), resample=H), "a")
    want = sysid.IOData.from_csv(tmp_path / "a.csv", inputs=["u"], outputs=["y"], resample=H)
    assert got == want and got.resampling == want.resampling
    with pytest.raises(DataError, match="no time column to resample"):
        Columns(("u",), ("y",), resample=H).record(["u", "y"], np.ones((5, 2)), "b")

    res = sysid.identify_many(tmp_path, fit=_on_the_grid, workers=0, inputs=["u"],
                              outputs=["y"], resample=H, out=tmp_path / "t.parquet")
    assert res.n_ok == 1 and res.to_pandas()["n_samples"].tolist() == [want.n_samples]
    with pytest.raises(DataError, match="not both"):
        sysid.identify_many(tmp_path, workers=0, outputs=["y"], resample=H, dt=H,
                            out=tmp_path / "u.parquet")
