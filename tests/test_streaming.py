"""Fast compressor, out-of-core streaming and Dask: all against the exact in-memory pass."""

from __future__ import annotations

import pickle
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sysid import _sysid
from sysid.errors import DataError, InsufficientDataError, NonFiniteError
from sysid.subspace.streaming import CompressionFallbackWarning, compress_dask, compress_stream


def noisy_record(n: int, m: int, l: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A random stable system with process and measurement noise, and channel offsets."""
    rng = np.random.default_rng(seed)
    nx = 3
    a = rng.standard_normal((nx, nx))
    a *= 0.8 / max(abs(np.linalg.eigvals(a)))
    b = rng.standard_normal((nx, m))
    c = rng.standard_normal((l, nx))
    u = rng.standard_normal((n, m)) + np.arange(m) * 5.0
    x = np.zeros(nx)
    y = np.empty((n, l))
    for t in range(n):
        y[t] = c @ x + 0.1 * rng.standard_normal(l)
        x = a @ x + b @ u[t] + 0.1 * rng.standard_normal(nx)
    return u, y


def noise_free_record(n: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(1)
    u = rng.standard_normal((n, 1))
    y = np.zeros((n, 1))
    x = np.zeros(2)
    a = np.array([[0.7, 0.3], [-0.3, 0.7]])
    for t in range(n):
        y[t] = x[0]
        x = a @ x + np.array([1.0, 0.5]) * u[t, 0]
    return u, y


def gram(f) -> np.ndarray:
    return f.l @ f.l.T


def assert_same_gram(f1, f2, rtol: float = 1e-12) -> None:
    g1, g2 = gram(f1), gram(f2)
    assert np.max(np.abs(g1 - g2)) <= rtol * np.max(np.abs(g1))


@settings(max_examples=15, deadline=None)
@given(
    m=st.integers(0, 3),
    l=st.integers(1, 3),
    past=st.integers(1, 6),
    future=st.integers(1, 6),
    seed=st.integers(0, 10_000),
)
def test_fast_and_exact_agree_on_noisy_data(m, l, past, future, seed):
    u, y = noisy_record(1500, m, l, seed)
    exact = _sysid.compress([(u, y)], past, future, None, "qr")
    fast = _sysid.compress([(u, y)], past, future, None, "correlation")
    assert fast.source == "correlation"
    s1 = np.linalg.svd(exact.l, compute_uv=False)
    s2 = np.linalg.svd(fast.l, compute_uv=False)
    np.testing.assert_allclose(s2, s1, rtol=1e-8)
    assert fast.n_columns == exact.n_columns


def test_ill_conditioned_data_fall_back_to_the_exact_pass():
    u, y = noise_free_record(2000)
    fast = _sysid.compress([(u, y)], 5, 5, None, "correlation")
    exact = _sysid.compress([(u, y)], 5, 5, None, "qr")
    assert fast.source == "qr-fallback"
    assert fast.relative_pivot < 1e-10
    np.testing.assert_array_equal(fast.l, exact.l)
    # compressor="correlation" streams once: the factor is flagged and a warning says so
    with pytest.warns(CompressionFallbackWarning, match="ill-conditioned"):
        streamed = compress_stream((u, y), 5, chunk_size=300, progress=False,
                                   compressor="correlation")
    assert streamed.source == "correlation-ill-conditioned"
    assert_same_gram(streamed, exact, 1e-11)
    # the default reads arrays a second time, exactly, without a warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again = compress_stream((u, y), 5, chunk_size=300, progress=False)
    assert again.source == "qr-fallback" and again.relative_pivot < 1e-10
    np.testing.assert_array_equal(again.l, exact.l)
    # ... but not a one-pass iterator: flagged and warned
    chunks = ((u[s:s + 300], y[s:s + 300]) for s in range(0, 2000, 300))
    with pytest.warns(CompressionFallbackWarning, match="ill-conditioned"):
        once = compress_stream(chunks, 5, progress=False)
    assert once.source == "correlation-ill-conditioned"
    # the estimator turns the in-memory fallback into a warning naming it
    import sysid

    with pytest.warns(CompressionFallbackWarning, match="qr-fallback"):
        est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=5, compressor="correlation")
    assert est.factor.source == "qr-fallback"


def test_unknown_compressor_is_rejected():
    u, y = noisy_record(200, 1, 1, 0)
    with pytest.raises(DataError, match="unknown compressor"):
        _sysid.compress([(u, y)], 3, 3, None, "cholesky")
    with pytest.raises(DataError, match="compressor"):
        compress_stream((u, y), 3, compressor="fast")
    with pytest.raises(DataError, match="unknown compressor"):
        _sysid.StreamingCompressor(1, 1, 3, 3, "fast")


@pytest.mark.parametrize("compressor", ["qr", "correlation"])
def test_memmap_iterator_and_array_sources_match_in_memory(tmp_path, compressor):
    u, y = noisy_record(3000, 2, 2, 4)
    ref = _sysid.compress([(u, y)], 4, 4, None, compressor)
    mm = np.memmap(tmp_path / "rec.f64", dtype=np.float64, mode="w+", shape=(3000, 4))
    mm[:, :2], mm[:, 2:] = u, y
    mm.flush()
    ro = np.memmap(tmp_path / "rec.f64", dtype=np.float64, mode="r", shape=(3000, 4))
    f_mm = compress_stream((ro[:, :2], ro[:, 2:]), 4, compressor=compressor, chunk_size=777,
                           progress=False)
    chunks = ((u[s:s + 500], y[s:s + 500]) for s in range(0, 3000, 500))
    f_it = compress_stream(chunks, 4, compressor=compressor, progress=False)
    for f in (f_mm, f_it):
        assert f.n_columns == ref.n_columns and f.source == compressor
        assert_same_gram(f, ref)


def test_parquet_files_are_experiments(tmp_path):
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    exps = [noisy_record(1200, 1, 2, 7), noisy_record(900, 1, 2, 8)]
    paths = []
    for i, (u, y) in enumerate(exps):
        table = pa.table({"u0": u[:, 0], "y0": y[:, 0], "y1": y[:, 1], "note": np.arange(len(u))})
        p = tmp_path / f"exp{i}.parquet"
        pq.write_table(table, p, row_group_size=256)
        paths.append(p)
    ref = _sysid.compress(exps, 3, 3, None, "qr")
    f = compress_stream(paths, 3, progress=False)
    assert f.n_experiments == 2 and f.n_columns == ref.n_columns
    assert_same_gram(f, ref)
    f2 = compress_stream(str(paths[0]), 3, input_columns=["u0"], output_columns=["y1"],
                         progress=False)
    assert (f2.n_inputs, f2.n_outputs) == (1, 1)
    with pytest.raises(DataError, match="no column"):
        compress_stream(paths[0], 3, output_columns=["z"], progress=False)


def test_streaming_compressor_object():
    u, y = noisy_record(1000, 1, 1, 2)
    c = _sysid.StreamingCompressor(1, 1, 3, 3, "correlation")
    c.push(u[:600], y[:600])
    y_bad = y[600:].copy()
    y_bad[10, 0] = np.nan
    with pytest.raises(NonFiniteError, match="sample 610"):
        c.push(u[600:], y_bad)
    c.push(u[600:], y[600:])
    assert c.samples == 1000
    f = c.finish()
    assert_same_gram(f, _sysid.compress([(u, y)], 3, 3, None, "qr"))
    with pytest.raises(DataError, match="already called"):
        c.finish()
    short = _sysid.StreamingCompressor(1, 1, 3, 3, "qr")
    short.push(u[:4], y[:4])
    with pytest.raises(InsufficientDataError):
        short.end_experiment()


def test_correlation_sums_pickle_and_merge():
    u, y = noisy_record(2000, 2, 1, 3)
    center, scale = _sysid.CorrelationSums.center_scale(u[:500], y[:500])
    parts = []
    for s, e in [(0, 700), (700, 701), (701, 2000)]:
        p = _sysid.CorrelationSums(2, 1, 4, 4, center, scale)
        p.push(u[s:e], y[s:e])
        parts.append(pickle.loads(pickle.dumps(p)))
    total = parts[0].merge(parts[1]).merge(parts[2])
    assert total.open_samples == 2000
    f = total.to_factor()
    assert f.source == "correlation"
    assert_same_gram(f, _sysid.compress([(u, y)], 4, 4, None, "qr"))
    g = pickle.loads(pickle.dumps(f))
    assert g.source == "correlation"
    np.testing.assert_array_equal(g.l, f.l)
    other = _sysid.CorrelationSums(2, 1, 4, 4, center + 1.0, scale)
    with pytest.raises(DataError, match="shifts or scales"):
        total.merge(other)


def test_progress_line_on_stderr(capsys, monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_tqdm(name, *args, **kwargs):
        if name.startswith("tqdm"):
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_tqdm)
    u, y = noisy_record(1000, 1, 1, 5)
    compress_stream((u, y), 3, chunk_size=400, progress=True)
    err = capsys.readouterr().err
    assert "1,000/1,000 samples" in err


def test_bad_sources_are_rejected():
    with pytest.raises(DataError, match="source must be"):
        compress_stream(42, 3)
    with pytest.raises(DataError, match="no samples"):
        compress_stream(iter([]), 3, progress=False)
    u, y = noisy_record(100, 1, 1, 5)
    with pytest.raises(DataError, match="equally long"):
        compress_stream((u[:50], y), 3, progress=False)
    with pytest.raises(DataError, match="chunk_size"):
        compress_stream((u, y), 3, chunk_size=0)


def test_dask_on_a_local_cluster_matches_single_machine():
    da = pytest.importorskip("dask.array")
    distributed = pytest.importorskip("distributed")
    u, y = noisy_record(20_000, 2, 2, 9)
    ref = _sysid.compress([(u, y)], 5, 5, None, "correlation")
    du = da.from_array(u, chunks=(3_000, 2))
    dy = da.from_array(y, chunks=(3_000, 2))
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=False, dashboard_address=":0"
    ) as cluster, distributed.Client(cluster):
        f = compress_dask(du, dy, 5)
        f2 = compress_stream((du, dy), 5)
    for g in (f, f2):
        assert g.source == "correlation" and g.n_columns == ref.n_columns
        assert_same_gram(g, ref)


@settings(max_examples=20, deadline=None)
@given(
    cuts=st.lists(st.integers(1, 1199), min_size=1, max_size=5, unique=True),
    chunk=st.integers(1, 700),
)
def test_partial_sums_merged_in_any_split_equal_the_whole(cuts, chunk):
    u, y = noisy_record(1200, 1, 2, 11)
    center, scale = _sysid.CorrelationSums.center_scale(u, y)
    bounds = [0, *sorted(cuts), 1200]
    parts = []
    for s, e in zip(bounds[:-1], bounds[1:]):
        p = _sysid.CorrelationSums(1, 2, 3, 4, center, scale)
        for a in range(s, e, chunk):
            p.push(u[a:min(e, a + chunk)], y[a:min(e, a + chunk)])
        parts.append(p)
    total = parts[0]
    for p in parts[1:]:
        total = total.merge(p)
    assert_same_gram(total.to_factor(), _sysid.compress([(u, y)], 3, 4, None, "qr"))


def test_copy_on_write_memmap_edits_survive(tmp_path):
    u, y = noisy_record(2000, 1, 1, 12)
    np.save(tmp_path / "z.npy", np.hstack([u, y]))
    z = np.load(tmp_path / "z.npy", mmap_mode="c")
    z[:, 1] *= 2.0  # an edit that exists only in this process's private pages
    f = compress_stream((z[:, :1], z[:, 1:]), 3, chunk_size=100, progress=False)
    ref = _sysid.compress([(u, 2.0 * y)], 3, 3, None, "correlation")
    assert_same_gram(f, ref)
    np.testing.assert_array_equal(z[:, 1:], 2.0 * y)


def test_min_relative_pivot_sets_the_ill_conditioning_threshold():
    u, y = noisy_record(1000, 1, 1, 13)
    s = _sysid.CorrelationSums(1, 1, 3, 3, *_sysid.CorrelationSums.center_scale(u, y))
    s.push(u, y)
    assert s.to_factor().source == "correlation"
    strict = s.to_factor(min_relative_pivot=0.5)
    assert strict.source == "correlation-ill-conditioned"
    assert 0.0 < strict.relative_pivot < 0.5
    assert_same_gram(strict, s.to_factor())
