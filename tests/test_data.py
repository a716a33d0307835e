"""IOData: construction, metadata, selection, splitting, merging, file formats, bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _guides import guide_text, python_blocks, run_guide
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid
from sysid.errors import DataError, InsufficientDataError, NonFiniteError, ShapeError


def record(n: int = 50, m: int = 2, l: int = 1, dt: float = 0.1, seed: int = 0) -> sysid.IOData:
    rng = np.random.default_rng(seed)
    return sysid.IOData(
        u=rng.standard_normal((n, m)), y=rng.standard_normal((n, l)), dt=dt,
        input_names=[f"in{j}" for j in range(m)], output_names=[f"out{j}" for j in range(l)],
        input_units=["deg"] * m, output_units=["rad/s"] * l,
    )


# ------------------------------------------------------------------ construction

def test_existing_interface_kept() -> None:
    u, y = np.ones((10, 1)), np.zeros((10, 2))
    d = sysid.IOData(u, y, 0.5)
    assert d.n_inputs == 1 and d.n_outputs == 2 and d.n_experiments == 1
    assert d.n_samples == 10 and d.dt == 0.5
    assert d.input_names == ["u0"] and d.output_names == ["y0", "y1"]
    (uu, yy), = d.experiments
    assert uu.dtype == np.float64 and yy.shape == (10, 2)
    assert sysid.IOData(u=None, y=y).n_inputs == 0
    assert sysid.IOData(u, y).dt == 1.0


def test_single_precision_stamps_far_from_zero_are_rounding_not_jitter(tmp_path) -> None:
    # float32 seconds near 1e4 are 0.98 ms apart: at dt = 10 ms their spacings read 9.77 and
    # 10.74 ms, and the record was refused as "irregular sampling: a gap" (from_raw,
    # from_pandas, from_csv alike); two units of the stamps' own resolution are rounding
    pd = pytest.importorskip("pandas")
    n = 500
    y = np.random.default_rng(0).standard_normal(n)
    t = (1e4 + np.arange(n) * 0.01).astype(np.float32)
    assert sysid.IOData.from_raw(None, y, time=t).dt == 0.01
    assert sysid.IOData(y=y, time=t).dt == 0.01
    t5 = (1e5 + np.arange(n) * 0.1).astype(np.float32)      # 7.8 ms resolution, dt 0.1 s
    d = sysid.IOData.from_pandas(pd.DataFrame({"t": t5, "y": y}), outputs=["y"], time="t")
    assert d.dt == 0.1 and d.time[0] == pytest.approx(1e5, abs=0.01)
    path = tmp_path / "log.csv"                  # float32 stamps written in full (float64)
    path.write_text("time,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(t, y)))
    assert sysid.IOData.from_csv(path, outputs=["y"]).dt == 0.01
    # real jitter beyond the rounding is still refused: 3 ms on 10 ms, 1 ms resolution
    bad = t.copy()
    bad[200:] += np.float32(0.003)
    with pytest.raises(DataError, match="irregular sampling: (jitter|a gap) at sample 200"):
        sysid.IOData.from_raw(None, y, time=bad)
    # and double-precision stamps far from zero keep their fine resolution
    t64 = 1.7e9 + np.arange(n) * 0.01
    assert sysid.sample_time(t64) == 0.01
    with pytest.raises(DataError, match="jitter at sample 200"):
        sysid.sample_time(np.r_[t64[:200], t64[200:] - 0.002])


@pytest.mark.parametrize("start, dt", [(1e5, 1e-3), (1.7e9, 0.01), (3e3, 1e-3)])
def test_stamps_too_coarse_for_the_sample_time_name_the_resolution(start, dt) -> None:
    # float32 seconds near 1e5 are 7.8 ms apart, Unix seconds 128 s: a 1 ms (10 ms) record
    # was "time repeats at sample 1", which said to remove duplicates; near 3000 s (0.24 ms)
    # "irregular sampling"
    n = 500
    t = (np.float64(start) + np.arange(n) * dt).astype(np.float32)
    y = np.zeros(n)
    with pytest.raises(DataError, match=r"stored as float32 .* apart at best.*float64.*"
                                        r"relative to the first stamp"):
        sysid.IOData.from_raw(None, y, time=t)
    # the same stamps relative to the first (computed in float64), then float32, are fine
    rel = (np.float64(start) + np.arange(n) * dt - start).astype(np.float32)
    assert sysid.IOData.from_raw(None, y, time=rel).dt == dt


def test_time_vector_gives_dt_and_start() -> None:
    t = 3.0 + 0.02 * np.arange(100)
    d = sysid.IOData(u=np.ones(100), y=np.ones(100), time=t)
    assert d.dt == 0.02
    np.testing.assert_allclose(d.time, t)


def test_single_precision_time_and_dt_give_the_decimal_sample_time() -> None:
    # float32 instants at 0.1 s: their median spacing is 0.10000038147 (the rounding of one
    # spacing), and compare/merge then refused the record against dt = 0.1 with a message
    # printing both as 0.1; the mean spacing (end points) is 0.1 within the rounding
    pd = pytest.importorskip("pandas")
    t32 = (np.arange(300) * 0.1).astype(np.float32)
    assert float(np.median(np.diff(t32.astype(float)))) == pytest.approx(0.10000038147)
    assert sysid.sample_time(t32) == 0.1
    for start, dt in ((7.0, 0.05), (100.0, 0.02), (0.0, 0.001)):
        t = (start + np.arange(2000) * dt).astype(np.float32)
        assert sysid.sample_time(t) == dt
    # double-precision instants with jitter: the mean spacing, not the median
    t = np.cumsum(np.r_[0.0, np.tile([0.0995, 0.1, 0.1008], 40)])
    assert sysid.sample_time(t) == pytest.approx((t[-1] - t[0]) / (t.size - 1), rel=1e-9)
    assert sysid.sample_time(t) != pytest.approx(0.1, rel=1e-6)
    rng = np.random.default_rng(1)
    u = rng.standard_normal(300)
    m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], dt=0.1)
    y = m.simulate(u)[:, 0]
    d = sysid.IOData.from_pandas(pd.DataFrame({"t": t32, "u0": u, "y0": y}), ["u0"], ["y0"],
                                 time="t")
    assert d.dt == 0.1
    assert sysid.compare(m, d).fit[0, 0] > 99.99
    plain = sysid.IOData(u=u, y=y, dt=0.1)
    assert plain.merge(d).dt == 0.1
    # a float32 dt is the decimal the user wrote, not 0.10000000149
    d32 = sysid.IOData(u=u, y=y, dt=np.float32(0.1))
    assert d32.dt == 0.1 and plain.merge(d32).n_experiments == 2
    # a real mismatch prints enough digits to show it
    with pytest.raises(DataError, match=r"dt = 0\.1000001 s but the first has 0\.1 s"):
        plain.merge(sysid.IOData(u=u, y=y, dt=0.1000001))
    with pytest.raises(DataError, match=r"every 0\.1000001 s but the model every 0\.1 s"):
        sysid.compare(m, sysid.IOData(u=u, y=y, dt=0.1000001))


@pytest.mark.parametrize(
    "t, match",
    [
        (np.r_[0.0, 0.1, 0.2, 0.2, 0.4], "repeats at sample 3"),
        (np.r_[0.0, 0.1, 0.2, 0.15, 0.4], "goes back at sample 3"),
        (np.r_[np.arange(10) * 0.1, 2.0 + np.arange(10) * 0.1], "a gap at sample 10"),
        (np.r_[0.0, 0.1, 0.2, 0.33, 0.4, 0.5], "jitter|gap"),
    ],
)
def test_bad_time_vectors_say_where(t: np.ndarray, match: str) -> None:
    with pytest.raises(DataError, match=match):
        sysid.sample_time(t)
    with pytest.raises(DataError, match=match):
        sysid.IOData(u=None, y=np.ones(t.size), time=t)


def test_irregular_error_suggests_resampling_and_from_irregular_works() -> None:
    rng = np.random.default_rng(0)
    t = np.sort(rng.uniform(0, 10, 400))
    with pytest.raises(DataError, match="from_irregular"):
        sysid.sample_time(t)
    d = sysid.IOData.from_irregular(t, np.sin(t), np.cos(t), dt=0.05, method="cubic")
    assert d.dt == 0.05
    np.testing.assert_allclose(d.y[:, 0], np.cos(d.time), atol=1e-3)


def test_dt_disagreeing_with_time() -> None:
    with pytest.raises(DataError, match="disagrees"):
        sysid.IOData(u=None, y=np.ones(5), dt=0.2, time=np.arange(5) * 0.1)


@pytest.mark.parametrize(
    "kwargs, err, match",
    [
        ({"input_names": ["a", "b"]}, ShapeError, "2 input name"),
        ({"output_names": ["a", "a"]}, DataError, "duplicate output"),
        ({"input_names": ["x"], "output_names": ["x", "z"]}, DataError, "both an input"),
        ({"input_names": [""]}, DataError, "non-empty strings"),
        ({"output_units": ["m", "furlongs"]}, DataError, "unknown unit 'furlongs'"),
        ({"output_units": ["m"]}, ShapeError, "1 output unit"),
        ({"input_units": [3]}, DataError, "must be a string"),
    ],
)
def test_bad_names_and_units(kwargs: dict, err: type, match: str) -> None:
    with pytest.raises(err, match=match):
        sysid.IOData(u=np.ones((5, 1)), y=np.ones((5, 2)), **kwargs)


@pytest.mark.parametrize(
    "unit",
    ["m/s^2", "deg/s", "N*m", "kN", "degC", "%", "-", "", "V", "m s^-1", "mbar", "rad/s",
     "kg*m^2", "ft/s", "g0"],
)
def test_known_units(unit: str) -> None:
    assert sysid.check_unit(unit) == unit


def test_nan_rejected_by_constructor_with_pointer_to_from_raw() -> None:
    y = np.ones(10)
    y[4] = np.nan
    with pytest.raises(NonFiniteError, match="sample 4"):
        sysid.IOData(u=None, y=y)
    with pytest.raises(NonFiniteError, match="nan='interpolate'"):
        sysid.IOData.from_raw(None, y)


def test_from_raw_interpolates_short_and_splits_long_gaps() -> None:
    t = np.arange(200) * 0.1
    y = np.sin(t)
    u = np.cos(t)
    y[50] = np.nan              # short gap: filled
    u[120:140] = np.nan         # long gap: cut
    d = sysid.IOData.from_raw(u, y, 0.1, nan="interpolate", max_gap=3)
    assert d.lengths == [120, 60]
    np.testing.assert_allclose(d.experiment(0).y[50, 0], 0.5 * (y[49] + y[51]))
    np.testing.assert_allclose(d.times[1][0], 14.0)  # the second piece keeps its time
    s = sysid.IOData.from_raw(u, y, 0.1, nan="split")
    assert s.lengths == [50, 69, 60]
    with pytest.raises(DataError, match="nan must be"):
        sysid.IOData.from_raw(u, y, nan="drop")


def test_empty_segments_are_errors() -> None:
    with pytest.raises(ShapeError, match="no samples"):
        sysid.IOData(u=[np.ones(5), np.ones(0)], y=[np.ones(5), np.ones(0)])
    with pytest.raises(ShapeError, match="empty list"):
        sysid.IOData(u=None, y=[])
    d = record()
    with pytest.raises(InsufficientDataError, match="empty"):
        d.slice(10, 10)
    with pytest.raises(InsufficientDataError, match="no samples between"):
        d.time_slice(100.0, 200.0)
    y = np.full(10, np.nan)
    with pytest.raises(DataError):
        sysid.IOData.from_raw(None, y, nan="split")


# ------------------------------------------------------------------ selection

def test_slicing_by_samples_and_time() -> None:
    d = record(n=50, dt=0.1)
    s = d[10:20]
    np.testing.assert_array_equal(s.u, d.u[10:20])
    np.testing.assert_allclose(s.time[0], 1.0)
    ts = d.time_slice(1.0, 2.0)
    np.testing.assert_array_equal(ts.y, d.y[10:20])
    assert d.slice(0, None, 2).dt == pytest.approx(0.2)


def test_select_channels_by_name() -> None:
    d = record(m=3, l=2)
    s = d[["in2", "out1"]]
    assert s.input_names == ["in2"] and s.output_names == ["out1"]
    np.testing.assert_array_equal(s.u[:, 0], d.u[:, 2])
    assert d["out0"].n_inputs == 3  # an unnamed kind is kept whole
    assert s.input_units == ["deg"]
    with pytest.raises(DataError, match="unknown channel name"):
        d["nope"]
    with pytest.raises(DataError, match="no input named"):
        d.select(inputs=["out0"])
    with pytest.raises(DataError, match="repeats"):
        d.select(inputs=["in0", "in0"])
    assert d.select(inputs=[]).n_inputs == 0


@pytest.mark.parametrize("sel, message", [
    (0.0, "input 0.0 is not a channel.*integer index.*use 0"),      # was TypeError
    (np.float64(1.0), "is not a channel.*use 1"),                   # was TypeError
    ([1.0], "input 1.0 is not a channel.*use 1"),
    (1.5, "input 1.5 is not a channel.*integer index"),
    (True, "boolean reads as the index 1.*np.flatnonzero"),         # was input 1, silently
    (np.array([True, False, True]), "boolean reads as the index 1.*np.flatnonzero"),
])
def test_select_channels_refuses_what_models_refuse(sel, message) -> None:
    # the rule of model[i, j] and FRD[i, j] (sysid.data.segments.channel_index, one function)
    d = record(m=3, l=2)
    with pytest.raises(DataError, match=message):
        d.select(inputs=sel)
    with pytest.raises(DataError, match=message.replace("input", "output")):
        d.select(outputs=sel)
    m = sysid.StateSpaceModel(np.zeros((1, 1)), np.ones((1, 3)), np.ones((2, 1)))
    with pytest.raises(DataError, match=message):
        m.select(inputs=sel)
    assert d.select(inputs=np.int64(2), outputs=slice(1, None)).input_names == ["in2"]
    assert m.select(outputs=slice(1, None)).noutputs == 1


def test_split_and_merge() -> None:
    d = record(n=100)
    est, val = d.split(0.7)
    assert (est.n_samples, val.n_samples) == (70, 30)
    np.testing.assert_array_equal(np.vstack([est.u, val.u]), d.u)
    both = est.merge(val)
    assert both.n_experiments == 2 and both.lengths == [70, 30]
    a, b = both.split(0.5)
    assert a.lengths == [35, 15]
    with pytest.raises(DataError, match="between 0 and 1"):
        d.split(1.2)
    renamed = sysid.IOData(u=d.u, y=d.y, dt=0.1, input_names=d.input_names,
                           output_names=["other"])
    with pytest.raises(DataError, match="output_names"):
        d.merge(renamed)
    with pytest.raises(DataError, match="dt = "):
        d.merge(record(n=100, dt=0.2))
    with pytest.raises(DataError, match="units"):
        d.merge(sysid.IOData(u=d.u, y=d.y, dt=0.1, input_names=d.input_names,
                             output_names=d.output_names))


@settings(max_examples=25, deadline=None)
@given(st.lists(st.integers(3, 40), min_size=1, max_size=4), st.floats(0.2, 0.8))
def test_split_then_merge_keeps_every_sample(lengths: list[int], frac: float) -> None:
    rng = np.random.default_rng(1)
    d = sysid.IOData(u=[rng.standard_normal(n) for n in lengths],
                     y=[rng.standard_normal(n) for n in lengths])
    est, val = d.split(frac)
    assert est.n_samples + val.n_samples == d.n_samples
    for k in range(d.n_experiments):
        joined = np.vstack([est.experiments[k][1], val.experiments[k][1]])
        np.testing.assert_array_equal(joined, d.experiments[k][1])


def test_repr_and_summary() -> None:
    d = record(n=40)
    assert repr(d) == "IOData: 40 samples, 2 inputs, 1 output, dt = 0.1 s"
    s = d.summary()
    row = s.rows[2]
    assert row["channel"] == "out0" and row["unit"] == "rad/s"
    assert row["std"] == pytest.approx(d.y.std())
    assert "out0" in repr(s) and "rad/s" in repr(s)
    assert list(s.to_pandas().index) == ["in0", "in1", "out0"]


# ------------------------------------------------------------------ files

def test_pandas_round_trip_with_experiments() -> None:
    d = record(n=30).merge(record(n=20, seed=1))
    df = d.to_pandas()
    back = sysid.IOData.from_pandas(df)
    assert back == d
    assert back.output_units == ["rad/s"] and back.n_experiments == 2
    with pytest.raises(DataError, match="not in the DataFrame"):
        sysid.IOData.from_pandas(df, ["in0"], ["missing"])


def test_csv_npz_mat_round_trips(tmp_path: Path) -> None:
    d = record(n=30).merge(record(n=25, seed=2))
    d.to_csv(tmp_path / "r.csv")
    c = sysid.IOData.from_csv(tmp_path / "r.csv", ["in0", "in1"], ["out0"])
    assert c == d and c.input_units == ["deg", "deg"]
    d.to_npz(tmp_path / "r.npz")
    assert sysid.IOData.from_npz(tmp_path / "r.npz") == d
    d.to_mat(tmp_path / "r.mat")
    m = sysid.IOData.from_mat(tmp_path / "r.mat")
    assert m == d and m.output_units == ["rad/s"]
    with pytest.raises(DataError, match="inputs and outputs"):
        sysid.IOData.from_csv(tmp_path / "r.csv")
    with pytest.raises(DataError, match="no column"):
        sysid.IOData.from_csv(tmp_path / "r.csv", ["zz"], ["out0"])


@pytest.mark.parametrize("suffix", [".gz", ".bz2", ".xz"])
def test_compressed_csv_reads_like_the_plain_file(tmp_path: Path, suffix: str) -> None:
    import bz2
    import gzip
    import lzma

    d = record(n=30).merge(record(n=25, seed=2))
    d.to_csv(tmp_path / "r.csv")
    text = (tmp_path / "r.csv").read_bytes()
    pack = {".gz": gzip.compress, ".bz2": bz2.compress, ".xz": lzma.compress}[suffix]
    (tmp_path / f"r.csv{suffix}").write_bytes(pack(text))
    c = sysid.IOData.from_csv(tmp_path / f"r.csv{suffix}", ["in0", "in1"], ["out0"])
    assert c == d and c.input_units == ["deg", "deg"] and c.lengths == [30, 25]
    # the header (names, units) comes from the decompressed stream, not the raw bytes
    with pytest.raises(DataError, match="no column 'zz'.*'in0'"):
        sysid.IOData.from_csv(tmp_path / f"r.csv{suffix}", ["zz"], ["out0"])


def test_to_csv_gz_writes_a_gzip_file(tmp_path: Path) -> None:
    import gzip

    d = record(n=20)
    d.to_csv(tmp_path / "r.csv.gz")
    assert (tmp_path / "r.csv.gz").read_bytes()[:2] == b"\x1f\x8b"  # gzip magic
    assert gzip.decompress((tmp_path / "r.csv.gz").read_bytes()).startswith(b"time,experiment")
    assert sysid.IOData.from_csv(tmp_path / "r.csv.gz", ["in0", "in1"], ["out0"]) == d


def test_plain_mat_file(tmp_path: Path) -> None:
    from scipy.io import savemat

    rng = np.random.default_rng(0)
    savemat(tmp_path / "plain.mat", {"u": rng.standard_normal((50, 2)),
                                    "y": rng.standard_normal((50, 1)), "Ts": 0.25})
    d = sysid.IOData.from_mat(tmp_path / "plain.mat", dt="Ts")
    assert (d.n_inputs, d.n_outputs, d.dt) == (2, 1, 0.25)
    # without dt=, the file's Ts (MATLAB's iddata name) is taken: it was dt = 1 s, silently
    assert sysid.IOData.from_mat(tmp_path / "plain.mat").dt == 0.25
    savemat(tmp_path / "bare.mat", {"u": np.ones((50, 1)), "y": np.ones((50, 1))})
    with pytest.warns(UserWarning, match="no sample time.*assuming dt = 1 s"):
        assert sysid.IOData.from_mat(tmp_path / "bare.mat").dt == 1.0
    with pytest.raises(DataError, match="no variable"):
        sysid.IOData.from_mat(tmp_path / "plain.mat", y="out")


def test_csv_with_blanks_and_trailing_comma(tmp_path: Path) -> None:
    p = tmp_path / "raw.csv"
    rows = ["a,b,", "1,10,", "2,,", "3,30,", "4,40,"]
    p.write_text("\n".join(rows) + "\n")
    with pytest.raises(NonFiniteError):
        sysid.IOData.from_csv(p, ["a"], ["b"], dt=0.5)
    d = sysid.IOData.from_csv(p, ["a"], ["b"], dt=0.5, nan="interpolate")
    np.testing.assert_allclose(d.y.ravel(), [10, 20, 30, 40])


def test_reads_f16_csv_header() -> None:
    """The F-16 file as published (quoted header, trailing comma), gzip-compressed."""
    d = sysid.IOData.from_csv(sysid.datasets.path("f16"), ["Force"],
                              ["Acceleration1", "Acceleration2", "Acceleration3"], dt=1 / 400)
    assert d.n_samples == 73728 and d.output_names[0] == "Acceleration1"


def test_pandas_datetime_index_and_missing_values() -> None:
    import pandas as pd

    idx = pd.date_range("2024-01-01", periods=50, freq="20ms")
    y = np.sin(np.arange(50) / 5.0)
    y[10] = np.nan
    df = pd.DataFrame({"elev": np.cos(np.arange(50) / 5.0), "pitch": y}, index=idx)
    with pytest.raises(NonFiniteError):
        sysid.IOData.from_pandas(df, ["elev"], ["pitch"])
    d = sysid.IOData.from_pandas(df, ["elev"], ["pitch"], nan="interpolate",
                                 units={"elev": "deg", "pitch": "deg"})
    assert d.dt == pytest.approx(0.02) and d.n_samples == 50
    assert d.output_units == ["deg"]
    np.testing.assert_allclose(d.y[10, 0], 0.5 * (y[9] + y[11]))


@settings(max_examples=15, deadline=None)
@given(
    st.lists(st.integers(3, 30), min_size=1, max_size=3),
    st.integers(0, 3),
    st.integers(1, 3),
    st.floats(1e-3, 10.0),
)
def test_file_round_trips_for_any_shape(lengths: list[int], m: int, l: int, dt: float) -> None:
    import tempfile

    rng = np.random.default_rng(len(lengths) + 10 * m + 100 * l)
    d = sysid.IOData(
        u=[rng.standard_normal((n, m)) for n in lengths] if m else None,
        y=[rng.standard_normal((n, l)) for n in lengths],
        dt=dt,
        output_units=["m/s"] * l,
    )
    with tempfile.TemporaryDirectory() as tmp:
        d.to_npz(Path(tmp) / "r.npz")
        assert sysid.IOData.from_npz(Path(tmp) / "r.npz") == d
        d.to_mat(Path(tmp) / "r.mat")
        assert sysid.IOData.from_mat(Path(tmp) / "r.mat") == d
    assert sysid.IOData.from_pandas(d.to_pandas(), dt=dt) == d


def test_docs_data_examples_run_on_the_bundled_records() -> None:
    """docs/data.md's code blocks, run in order on the copies bundled with sysid."""
    assert len(python_blocks(guide_text("data.md"))) >= 2
    ns = run_guide("data.md")
    assert repr(ns["data"]) == "IOData: 2500 samples, 5 inputs, 2 outputs, dt = 0.1 s"
    frd = ns["frd"]
    assert isinstance(frd, sysid.FRD) and frd.omega.size == 267  # "keeps the 267 excited lines"
    assert ns["found"][:3] == (8192, 9, (0,))  # the measured force repeats up to its noise


def test_from_pandas_does_not_read_row_labels_as_seconds():
    # df.iloc[::2] became dt = 2 s and dropna() failed on a "2 s gap": unnamed integer row
    # labels were read as time in seconds
    import pandas as pd

    rng = np.random.default_rng(0)
    df = pd.DataFrame({"u": rng.standard_normal(50), "y": rng.standard_normal(50)})
    import warnings

    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        d = sysid.IOData.from_pandas(df.iloc[::2], inputs=["u"], outputs=["y"])
    said = [str(w.message) for w in rec]
    assert d.dt == 1.0 and len(said) == 2, said
    assert "row labels skip from 0 to 2" in said[0] and "no sample time" in said[1]
    df.loc[5, "y"] = np.nan
    with pytest.warns(UserWarning, match="skip from 4 to 6"):
        assert sysid.IOData.from_pandas(df.dropna(), inputs=["u"], outputs=["y"],
                                        dt=0.1).n_samples == 49
    timed = df.dropna().set_index(pd.Index(np.arange(49) * 0.5, name="time"))
    assert sysid.IOData.from_pandas(timed, inputs=["u"], outputs=["y"]).dt == 0.5


# ------------------------------------------ issue 26: the data layer's sweep (from_csv, ...)
def test_from_csv_reads_a_headerless_dat_whole() -> None:
    # the first row of dryer.dat was taken for column names: 999 samples named '6.41...'
    raw = np.loadtxt(sysid.datasets.path("dryer"))
    d = sysid.IOData.from_csv(sysid.datasets.path("dryer"), inputs=[0], outputs=[1], dt=0.08)
    assert d.n_samples == 1000 == len(raw) and d.input_names == ["u0"]
    np.testing.assert_array_equal(d.u[:, 0], raw[:, 0])
    np.testing.assert_array_equal(d.y[:, 0], raw[:, 1])
    assert d == sysid.IOData(raw[:, 0], raw[:, 1], 0.08)


def test_from_csv_bom_and_assumed_dt(tmp_path: Path) -> None:
    # Excel's "CSV UTF-8" starts with a BOM: the header read "\ufefftime", dt became 1 s
    p = tmp_path / "bom.csv"
    p.write_text("time,u,y\n0,1,2\n0.1,3,4\n0.2,5,6\n", encoding="utf-8-sig")
    d = sysid.IOData.from_csv(p, ["u"], ["y"])
    assert d.dt == pytest.approx(0.1) and d.n_samples == 3
    q = tmp_path / "plain.csv"
    q.write_text("u,y\n1,2\n3,4\n5,6\n")
    with pytest.warns(UserWarning, match="assuming dt = 1 s"):
        assert sysid.IOData.from_csv(q, ["u"], ["y"]).dt == 1.0


@pytest.mark.parametrize("name", ["Time [s]", "t", "TIME", "timestamp"])
def test_from_csv_finds_a_time_column_by_its_usual_names(tmp_path: Path, name: str) -> None:
    # only a column named exactly "time" was taken; "Time [s]" or "t" gave dt = 1 s
    p = tmp_path / "t.csv"
    p.write_text(f"{name},u,y\n0,1,2\n0.25,3,4\n0.5,5,6\n")
    assert sysid.IOData.from_csv(p, ["u"], ["y"]).dt == pytest.approx(0.25)
    # a time-named column chosen as a channel is a channel
    with pytest.warns(UserWarning, match="assuming dt = 1 s"):
        assert sysid.IOData.from_csv(p, ["u"], [name.split(" [")[0], "y"]).n_outputs == 2


def test_from_csv_names_a_bad_cell(tmp_path: Path) -> None:
    p = tmp_path / "txt.csv"
    p.write_text("time,u,y\n0,1,2\n\n0.1,abc,4\n0.2,5,6\n0.3,7,8\n")
    for nan in ("error", "interpolate"):  # interpolated over silently before
        with pytest.raises(DataError, match=r"txt.csv line 4, column 'u': 'abc' is not a "):
            sysid.IOData.from_csv(p, ["u"], ["y"], nan=nan)
    p.write_text("time,u,y\n0,1,2\n0.1,3\n")
    with pytest.raises(DataError, match="line 3: 2 fields but the header has 3"):
        sysid.IOData.from_csv(p, ["u"], ["y"])
    p.write_text("time,u,y\n")
    with pytest.raises(DataError, match="header but no data rows"):
        sysid.IOData.from_csv(p, ["u"], ["y"])
    # quoted numbers are numbers; an empty cell is still a missing value
    p.write_text('"time","u","y"\n"0","1","2"\n"0.1","","4"\n"0.2","5","6"\n')
    d = sysid.IOData.from_csv(p, ["u"], ["y"], nan="interpolate")
    np.testing.assert_allclose(d.u[:, 0], [1, 3, 5])
    np.testing.assert_allclose(d.y[:, 0], [2, 4, 6])


def test_from_csv_decimal_comma(tmp_path: Path) -> None:
    p = tmp_path / "dc.csv"
    p.write_text("time;u;y\n0;1,5;2,5\n0,1;3,5;4,5\n0,2;5,5;6,5\n")
    with pytest.raises(DataError, match=r"line 2, column 'u': '1,5' .*decimal=','"):
        sysid.IOData.from_csv(p, ["u"], ["y"])
    d = sysid.IOData.from_csv(p, ["u"], ["y"], decimal=",")
    assert d.dt == pytest.approx(0.1)
    np.testing.assert_allclose(d.u[:, 0], [1.5, 3.5, 5.5])
    np.testing.assert_allclose(d.y[:, 0], [2.5, 4.5, 6.5])


def test_from_csv_reads_a_loggers_units_row_stamps_and_headers_as_written(
        tmp_path: Path) -> None:
    # a logger's export: date-time stamps, a units row, "name [unit]" headers named as
    # written; each was refused ("'s' is not a number", "no column 'Heater Power [W]'")
    t = 0.08 * np.arange(6)
    u, y = np.sin(t), np.cos(t)
    p = tmp_path / "log.csv"
    p.write_text("time,power,temp\ns,W,degC\n"
                 + "".join(f"{a},{b},{c}\n" for a, b, c in zip(t, u, y)))
    d = sysid.IOData.from_csv(p, ["power"], ["temp"])
    assert d.dt == pytest.approx(0.08) and d.n_samples == 6
    assert d.input_units == ["W"] and d.output_units == ["degC"]
    np.testing.assert_allclose(d.u[:, 0], u)
    stamps = [f"2026-03-01T23:59:59.{k * 8:02d}+01:00" for k in range(6)]
    p.write_text("time,Heater Power [W],temp\n"
                 + "".join(f"{a},{b},{c}\n" for a, b, c in zip(stamps, u, y)))
    d = sysid.IOData.from_csv(p, ["Heater Power [W]"], ["temp"], time="time")
    assert d.dt == pytest.approx(0.08) and d.input_units == ["W"]
    assert d.input_names == ["Heater Power"]
    np.testing.assert_allclose(d.y[:, 0], y)
    # a first data row of missing values is data, not units; a bad stamp is named
    p.write_text("time,u,y\nNA,NA,NA\n1,2,3\n")
    with pytest.raises(DataError, match="line 2, column 'time'"):
        sysid.IOData.from_csv(p, ["u"], ["y"])
    p.write_text("time,u,y\n2026-03-01 00:00:00,1,2\n2026-03-01 00:00:xx,3,4\n")
    with pytest.raises(DataError, match="line 3, column 'time'"):
        sysid.IOData.from_csv(p, ["u"], ["y"])


def test_from_pandas_datetime_and_timedelta_time() -> None:
    # a datetime64 time column read as nanosecond counts: dt 10000.0 for 10 ms; a
    # TimedeltaIndex was ignored (dt 1 with a warning that there was no sample time)
    import pandas as pd

    n = 20
    stamps = pd.date_range("2024-01-01", periods=n, freq="10ms")
    df = pd.DataFrame({"u": np.ones(n), "y": np.arange(n, dtype=float), "time": stamps})
    deltas = pd.to_timedelta(np.arange(n) * 10, unit="ms")
    for frame in (df, df.assign(time=deltas), df.assign(time=deltas).set_index("time"),
                  df.assign(t=deltas + pd.Timedelta(seconds=3)).drop(columns="time")):
        d = sysid.IOData.from_pandas(frame, ["u"], ["y"])
        assert d.dt == pytest.approx(0.01, rel=1e-12) and d.time[0] == 0.0
        np.testing.assert_allclose(d.time, np.arange(n) * 0.01, atol=1e-12)
    d = sysid.IOData.from_pandas(df, ["u"], ["y"], time="time")
    assert d.dt == pytest.approx(0.01, rel=1e-12)


def test_from_mat_missing_input_variable(tmp_path: Path) -> None:
    # u="input" not in the file gave a time series (0 inputs) without a word
    from scipy.io import savemat

    y = np.arange(50.0).reshape(-1, 1)
    savemat(tmp_path / "p.mat", {"in1": np.ones((50, 1)), "y": y})
    with pytest.raises(DataError, match=r"no input variable 'input'.*\['in1', 'y'\].*u=None"):
        sysid.IOData.from_mat(tmp_path / "p.mat", u="input")
    with pytest.raises(DataError, match="no input variable 'u'"):
        sysid.IOData.from_mat(tmp_path / "p.mat")
    d = sysid.IOData.from_mat(tmp_path / "p.mat", u="in1", dt=0.5)
    assert (d.n_inputs, d.n_outputs, d.n_samples) == (1, 1, 50)
    ts = sysid.IOData.from_mat(tmp_path / "p.mat", u=None, dt=0.5)
    assert ts.n_inputs == 0 and np.array_equal(ts.y, y)


def test_a_list_of_numpy_scalars_is_one_signal() -> None:
    # list(np.arange(5.)) was read as 5 experiments of one scalar each
    d = sysid.IOData(u=list(np.arange(5.0)), y=list(np.arange(5.0) ** 2), dt=0.1)
    assert (d.n_experiments, d.n_samples) == (1, 5)
    np.testing.assert_array_equal(d.y[:, 0], np.arange(5.0) ** 2)
    e = sysid.IOData(None, np.arange(5.0), time=list(np.arange(5) * 0.1))
    assert e.dt == pytest.approx(0.1) and e.n_experiments == 1
    two = sysid.IOData(None, [np.arange(5.0), np.arange(4.0)], 0.1)  # arrays: experiments
    assert two.n_experiments == 2


@pytest.mark.parametrize("dt", [1 / 60, 1 / 3, 0.1, 1 / 400])
def test_pandas_and_csv_round_trips_keep_dt(tmp_path: Path, dt: float) -> None:
    # dt = 1/60 came back from to_pandas/from_pandas and to_csv/from_csv as 0.0166666666667
    d = sysid.IOData(np.ones(500), np.arange(500.0), dt=dt)
    b = sysid.IOData.from_pandas(d.to_pandas())
    d.to_csv(tmp_path / "r.csv")
    c = sysid.IOData.from_csv(tmp_path / "r.csv", ["u0"], ["y0"])
    assert b.dt == dt and c.dt == dt and b == d and c == d
    # a file with a time column and no experiment column goes through from_raw
    t = np.arange(500) * dt
    np.savetxt(tmp_path / "t.csv", np.column_stack([t, np.ones(500), t]), delimiter=",",
               header="time,u,y", comments="", fmt="%.17g")
    assert sysid.IOData.from_csv(tmp_path / "t.csv", ["u"], ["y"]).dt == dt
    assert sysid.IOData.from_raw(np.ones(500), t, dt, time=t).dt == dt
    # a frame whose time no longer matches the stored dt is read by its time
    df = d.to_pandas()
    df.index = df.index * 2
    assert sysid.IOData.from_pandas(df).dt == pytest.approx(2 * dt, rel=1e-9)


def test_from_pandas_named_integer_index_is_time_only_under_a_time_name() -> None:
    # an index named "sample" (read_csv(index_col=0)) was taken for seconds, dt = 1 silently
    import pandas as pd

    n = 20
    df = pd.DataFrame({"u": np.ones(n), "y": np.arange(n, dtype=float)})
    df.index.name = "sample"
    with pytest.warns(UserWarning, match="integer index named 'sample', read as row numbers"):
        assert sysid.IOData.from_pandas(df, ["u"], ["y"]).dt == 1.0
    assert sysid.IOData.from_pandas(df, ["u"], ["y"], dt=0.25).dt == 0.25
    df.index = pd.Index(np.arange(n) * 2, name="Seconds")  # a time name: seconds
    assert sysid.IOData.from_pandas(df, ["u"], ["y"]).dt == 2.0


@pytest.mark.parametrize("name", ["Time [s]", "timestamp", "T"])
def test_from_pandas_finds_a_time_column_by_its_usual_names(name: str) -> None:
    # "Time [s]" and "timestamp" columns were not taken: dt = 1 s with a warning
    import pandas as pd

    n = 20
    t = (pd.date_range("2026-03-01 08:00", periods=n, freq="250ms") if name == "timestamp"
         else 0.25 * np.arange(n))
    df = pd.DataFrame({name: t, "u": np.ones(n), "y": np.arange(n, dtype=float)})
    assert sysid.IOData.from_pandas(df, ["u"], ["y"]).dt == pytest.approx(0.25)


def test_from_pandas_takes_the_one_date_time_column_whatever_its_name() -> None:
    # a "stamp" column of datetime64 (or "elapsed" of timedelta64) was not taken: dt = 1 s
    # with a warning, though its type says it is the time; two such columns stay a choice
    import pandas as pd

    n = 20
    stamps = pd.date_range("2026-03-01 08:00", periods=n, freq="250ms")
    df = pd.DataFrame({"stamp": stamps, "u": np.ones(n), "y": np.arange(n, dtype=float)})
    assert sysid.IOData.from_pandas(df, ["u"], ["y"]).dt == pytest.approx(0.25)
    df = pd.DataFrame({"elapsed": pd.to_timedelta(0.5 * np.arange(n), unit="s"),
                       "u": np.ones(n), "y": np.arange(n, dtype=float)})
    assert sysid.IOData.from_pandas(df, ["u"], ["y"]).dt == pytest.approx(0.5)
    df["logged"] = stamps
    with pytest.warns(sysid.SysidWarning, match="no sample time"):
        assert sysid.IOData.from_pandas(df, ["u"], ["y"]).dt == 1.0


def test_from_raw_checks_dt_first() -> None:
    # dt=0 said "time repeats at sample 1"
    for bad in (0, -0.1, np.nan):
        with pytest.raises(DataError, match="dt must be a positive number of seconds"):
            sysid.IOData.from_raw(np.ones(5), np.ones(5), dt=bad)


def test_a_time_column_in_milliseconds_is_read_in_seconds(tmp_path):
    # a column headed "time [ms]" (or named time_ms) was read as seconds: dt = 10 for 10 ms
    # samples, every time constant 1000 times too long, silently
    import pandas as pd

    p = tmp_path / "ms.csv"
    p.write_text("time [ms],u,y\n0,1,2\n10,2,3\n20,3,4\n30,4,5\n")
    assert sysid.IOData.from_csv(p, inputs=["u"], outputs=["y"]).dt == pytest.approx(0.01)
    frame = pd.DataFrame({"time [ms]": [0, 10, 20, 30.0], "u": [1, 2, 3, 4.0],
                          "y": [2, 3, 4, 5.0]})
    assert sysid.IOData.from_pandas(frame, ["u"], ["y"]).dt == pytest.approx(0.01)
    indexed = frame.drop(columns="time [ms]").set_index(pd.Index([0, 10, 20, 30.0],
                                                                 name="time_ms"))
    assert sysid.IOData.from_pandas(indexed, ["u"], ["y"]).dt == pytest.approx(0.01)
    p.write_text("time [deg],u,y\n0,1,2\n10,2,3\n20,3,4\n30,4,5\n")
    with pytest.raises(sysid.DataError, match="not read as a unit of time"):
        sysid.IOData.from_csv(p, inputs=["u"], outputs=["y"])
    # dt= beside a time column that says otherwise: refused, as IOData(dt=, time=) is
    p.write_text("t,u,y\n0,1,2\n0.1,2,3\n0.2,3,4\n0.3,4,5\n")
    with pytest.raises(sysid.DataError, match="disagrees with its time column 't'"):
        sysid.IOData.from_csv(p, inputs=["u"], outputs=["y"], dt=0.2)
    assert sysid.IOData.from_csv(p, inputs=["u"], outputs=["y"], dt=0.1).dt == 0.1


def test_from_irregular_cuts_at_an_outage_instead_of_bridging_it():
    # a 30 s outage in a 0.1 s record was filled with a straight line (300 of 500 samples),
    # silently, by the very call IOData(time=...)'s gap error recommends
    rng = np.random.default_rng(0)
    t = np.r_[np.arange(0.0, 10.0, 0.1), np.arange(40.0, 50.0, 0.1)]
    t = t + 0.01 * rng.uniform(size=t.size)
    y = np.sin(t)
    with pytest.warns(sysid.SysidWarning, match="cut into 2 experiment"):
        d = sysid.IOData.from_irregular(t, None, y, dt=0.1)
    assert d.n_experiments == 2 and d.n_samples < 205
    for e in range(2):
        tt = d.experiment(e).time
        np.testing.assert_allclose(d.experiment(e).y[:, 0], np.sin(tt), atol=2e-3)
    # a larger max_gap bridges it as before
    whole = sysid.IOData.from_irregular(t, None, y, dt=0.1, max_gap=40.0)
    assert whole.n_experiments == 1 and whole.n_samples > 490


def test_float64_stamps_on_a_power_of_two_rate_are_not_taken_for_float32():
    # t = k / 1024 over 1100 s: every stamp is a float32 value, and the record was refused
    # as "time stamps ... stored as float32" (it is float64, on an exact grid)
    t = np.arange(1100 * 1024) / 1024.0
    assert sysid.sample_time(t) == 1 / 1024
    # float32 seconds far from zero, rounded off the grid, are still refused
    coarse = (1.7e9 + np.arange(200) * 0.01).astype(np.float32)
    with pytest.raises(sysid.DataError, match="stored as float32"):
        sysid.sample_time(coarse)


def test_a_jittering_clock_is_called_jitter_not_a_gap() -> None:
    """A trend recorder's clock steps 4.6 to 5.0 ms about a 4.8 ms median: the refusal named
    "a gap at sample 1" (the first spacing off by more than 1 %, longer than the median)
    and told the user to cut the record at it. It is jitter, with no sample lost; a real
    gap elsewhere in the record is the one named."""
    rng = np.random.default_rng(3)
    t = np.cumsum(np.r_[0.0, 0.0048 * (1 + 0.04 * (rng.random(999) - 0.5))])
    t[1] = t[0] + 0.0049  # the first spacing longer than the median by 2 %
    with pytest.raises(DataError, match="jitter at sample 1 ") as e:
        sysid.sample_time(t)
    assert "gap" not in str(e.value)
    t[600:] += 0.05  # ten samples lost
    with pytest.raises(DataError, match="a gap at sample 600 .*1 of them gaps") as e:
        sysid.sample_time(t)
    assert "cut the record at the gap" in str(e.value)
