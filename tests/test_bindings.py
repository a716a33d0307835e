"""The boundary: array layouts, dtypes, views, pickling, GIL release."""

from __future__ import annotations

import pickle
import threading

import numpy as np

import sysid
from sysid import _sysid

from conftest import random_system, simulate


def _data(N=400):
    rng = np.random.default_rng(1)
    sysm = random_system(3, 2, 2, rng)
    u = rng.standard_normal((N, 2))
    return sysm, u, simulate(*sysm, u)


def test_c_fortran_and_strided_views_give_the_same_factor():
    _, u, y = _data()
    ref = _sysid.compress([(u, y)], 4, 4).l
    uf, yf = np.asfortranarray(u), np.asfortranarray(y)
    np.testing.assert_array_equal(_sysid.compress([(uf, yf)], 4, 4).l, ref)
    big_u = np.zeros((800, 5))
    big_u[::2, 1:5:2] = u
    big_y = np.zeros((800, 3))
    big_y[::2, :2] = y
    view_u, view_y = big_u[::2, 1:5:2], big_y[::2, :2]
    assert not view_u.flags.c_contiguous
    np.testing.assert_array_equal(_sysid.compress([(view_u, view_y)], 4, 4).l, ref)


def test_integer_and_float32_inputs_are_accepted():
    _, u, y = _data()
    ui = np.round(u * 100).astype(np.int64)
    m1 = sysid.SubspaceEstimator(sysid.IOData(u=ui, y=y), horizon=4).singular_values
    m2 = sysid.SubspaceEstimator(sysid.IOData(u=ui.astype(float), y=y), horizon=4).singular_values
    np.testing.assert_array_equal(m1, m2)
    s32 = sysid.SubspaceEstimator(sysid.IOData(u=u.astype(np.float32), y=y), horizon=4)
    assert s32.singular_values.dtype == np.float64


def test_iodata_keeps_float64_views_without_copying():
    _, u, y = _data()
    d = sysid.IOData(u=u, y=y)
    assert np.shares_memory(d.experiments[0][0], u)
    assert np.shares_memory(d.experiments[0][1], y)


def test_factor_pickles_and_estimator_rebuilds_from_it():
    _, u, y = _data()
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=4)
    f2 = pickle.loads(pickle.dumps(est.factor))
    np.testing.assert_array_equal(f2.l, est.factor.l)
    assert (f2.n_columns, f2.n_experiments, f2.past, f2.future) == (est.factor.n_columns, 1, 4, 4)
    est2 = sysid.SubspaceEstimator.from_factor(f2)
    np.testing.assert_allclose(est2.fit(3).markov(10), est.fit(3).markov(10))
    assert "HankelFactor(n_inputs=2" in repr(f2)


def test_compression_releases_the_gil():
    # a Python thread keeps counting while another thread compresses a long record
    rng = np.random.default_rng(0)
    u = rng.standard_normal((400_000, 2))
    y = rng.standard_normal((400_000, 2))
    ticks = 0
    done = threading.Event()

    def count():
        nonlocal ticks
        while not done.is_set():
            ticks += 1

    t = threading.Thread(target=count)
    t.start()
    before = ticks
    _sysid.compress([(u, y)], 10, 10)
    during = ticks - before
    done.set()
    t.join()
    assert during > 1000


def test_reprs_are_readable():
    _, u, y = _data()
    data = sysid.IOData(u=u, y=y, dt=0.5)
    assert repr(data) == "IOData: 400 samples, 2 inputs, 2 outputs, dt = 0.5 s"
    est = sysid.SubspaceEstimator(data, horizon=4)
    assert repr(est).startswith("SubspaceEstimator(method='moesp', past=4, future=4")
    assert "nstates=3" in repr(est.fit(3))


def test_import_is_light():
    # SciPy's signal/statistics modules, pandas and matplotlib load only when used
    import subprocess
    import sys

    code = (
        "import sys, sysid; "
        "print(sorted(m for m in ('scipy.signal', 'scipy.stats', 'scipy.ndimage', 'pandas', "
        "'matplotlib', 'dask') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
    assert callable(sysid.compare) and callable(sysid.criteria)
    assert "spa" in dir(sysid)


def test_a_first_fit_does_not_import_scipy_stats_or_signal():
    # importing scipy.stats or scipy.signal takes about a second: it made the first `pem`
    # call of a process 30 times slower than the second (through the FRD model's module),
    # and `identify`'s first call 1.1 s slower (scipy.signal.tf2ss for an OE candidate)
    import subprocess
    import sys

    code = (
        "import sys, warnings, numpy as np, sysid; warnings.simplefilter('ignore'); "
        "u = np.random.default_rng(0).standard_normal((300, 1)); "
        "y = np.convolve(u[:, 0], [0.0, 1.0, 0.5])[:300, None]; "
        "d = sysid.IOData(u=u, y=y, dt=1.0); m = sysid.n4sid(d, 2); "
        "sysid.pem(d, m, focus='simulation'); sysid.ssest(d, 2); sysid.oe(d, 2, 2, 1); "
        "sysid.identify(d, progress=False); "
        "print([k for k in ('scipy.stats', 'scipy.signal') if k in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
