"""compress_dask on a real multi-process cluster (dask.distributed LocalCluster with
processes=True and two workers): the partial sums are pickled to other processes and back,
and the merged factor equals the single-machine one to round-off."""

from __future__ import annotations

import numpy as np
import pytest

from sysid import _sysid
from sysid.subspace.streaming import compress_dask, compress_stream

da = pytest.importorskip("dask.array")
distributed = pytest.importorskip("distributed")


def _gram(f: object) -> np.ndarray:
    return f.l @ f.l.T  # type: ignore[attr-defined]


def test_multiprocess_cluster_gives_the_single_machine_factor() -> None:
    rng = np.random.default_rng(11)
    n = 60_000
    u = rng.standard_normal((n, 2))
    y = np.zeros((n, 2))
    for t in range(1, n):
        y[t] = 0.6 * y[t - 1] + u[t - 1] @ np.array([[1.0, 0.2], [-0.3, 0.8]])
    y += 0.1 * rng.standard_normal((n, 2))
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        f = compress_dask(da.from_array(u, chunks=(7_000, 2)), da.from_array(y, chunks=(7_000, 2)),
                          past=6)
        pids = set(client.run(lambda: __import__("os").getpid()).values())
    assert len(pids) == 2 and __import__("os").getpid() not in pids
    single = compress_stream((u, y), 6, compressor="correlation", progress=False)
    exact = _sysid.compress([(u, y)], 6, 6, None, "qr")
    assert f.source == "correlation" and f.n_columns == single.n_columns == n - 11
    g, gs, ge = _gram(f), _gram(single), _gram(exact)
    scale = np.abs(ge).max()
    assert np.abs(g - gs).max() < 1e-12 * scale
    assert np.abs(g - ge).max() < 1e-11 * scale
