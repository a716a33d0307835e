"""Hostile inputs to the newer estimators (issue 31, "Also measured"): sizes refused before
anything is allocated, silent acceptance turned into a clear error, and a strided-input bug.
Each case failed before the fix (a Rust panic, an 8 GB allocation, a run without end, a
silent model or a wrong error)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import DataError, InsufficientDataError


@pytest.fixture(scope="module")
def data():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((400, 1))
    y = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]]).simulate(u)
    return sysid.IOData(u=u, y=y + 0.01 * rng.standard_normal(y.shape))


def test_nlarx_lag_beyond_the_record_is_refused_before_allocating(data):
    with pytest.raises(InsufficientDataError, match=r"largest lag \(4611686018427387904\)"):
        sysid.nlarx(data, 2**62, 2, 1)


def test_frd_subspace_horizon_beyond_the_frequencies_is_refused(data):
    frd = sysid.welch_frf(data)
    with pytest.raises(DataError, match=r"horizon=1000000 needs at least 500000 frequencies"):
        sysid.frd_subspace(frd, 2, horizon=10**6)


def test_frd_subspace_refuses_negative_frequencies(data):
    frd = sysid.welch_frf(data)
    two_sided = sysid.FRD(-frd.omega, frd.response, dt=frd.dt)
    with pytest.raises(DataError, match="frequencies must be finite and >= 0"):
        sysid.frd_subspace(two_sided, 2)


def test_polynomial_nonlinearity_degree_is_bounded():
    with pytest.raises(DataError, match="degree must be at most 100"):
        sysid.PolynomialNonlinearity(10**6)


def test_nlhw_refuses_more_parameters_than_samples(data):
    short = data.slice(0, 40)
    with pytest.raises(DataError, match="parameters but the record has 40 samples"):
        sysid.nlhw(short, 2, 2, 1, input_nl=sysid.PolynomialNonlinearity(50), output_nl=None)


def test_nonlinear_greybox_substeps_bounded():
    def f(t, x, u, p):
        return -x + u

    def h(t, x, u, p):
        return x

    with pytest.raises(DataError, match="substeps must be an integer from 1 to 10000"):
        sysid.NonlinearGreyBox(f, h, {"a": 1.0}, 1, substeps=10**9)
    with pytest.raises(DataError, match="substeps"):
        sysid.NonlinearGreyBox(f, h, {"a": 1.0}, 1, substeps=0)


def test_mimo_oe_simulates_a_c_contiguous_input():
    rng = np.random.default_rng(1)
    u = rng.standard_normal((300, 2))
    y = np.column_stack([np.convolve(u[:, 0], [0, 1, 0.5])[:300],
                         np.convolve(u[:, 1], [0, 0.7])[:300]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.oe(sysid.IOData(u=u, y=y), [[1, 1], [1, 1]], [[1, 1], [1, 1]],
                     [[1, 1], [1, 1]])
    u2 = np.ascontiguousarray(rng.standard_normal((300, 2)))
    out = m.simulate(u2)
    assert out.shape == (300, 2) and np.all(np.isfinite(out))
    # the memory layout of the input does not change the result
    assert np.allclose(out, m.simulate(np.asfortranarray(u2)))


@pytest.mark.parametrize("fit", [
    lambda d: sysid.bj(d, [[1]], [[1]], [[1]], [[1]], [[1]]),
    lambda d: sysid.nlhw(d, 2, 2, 1),
    lambda d: sysid.arx(d, 2, 2, 1),
    lambda d: sysid.oe(d, 2, 2, 1),
], ids=["bj", "nlhw", "arx", "oe"])
def test_all_zero_input_is_refused(data, fit):
    zero = sysid.IOData(u=np.zeros((400, 1)), y=data.y)
    with pytest.raises(DataError, match="input u0 is 0 in every sample"):
        fit(zero)


@pytest.mark.parametrize("fit", [
    lambda d: sysid.n4sid(d, 2),
    lambda d: sysid.ssest(d, "auto"),
    lambda d: sysid.identify(d, refine=False),
], ids=["n4sid", "ssest", "identify"])
def test_a_constant_input_channel_is_named_by_the_state_space_paths(data, fit):
    # a second input held at a set-point (a logged but unused channel): the subspace paths
    # refused it by the horizon's rank test, without saying which channel (issue 26)
    u = np.column_stack([data.u[:, 0], np.full(data.n_samples, 20.0)])
    held = sysid.IOData(u=u, y=data.y, input_names=["force", "setpoint"])
    with pytest.raises(DataError, match="input setpoint is 20 in every sample"):
        fit(held)


def test_all_zero_record_is_refused_with_the_channel_named():
    zero = sysid.IOData(u=np.zeros((400, 1)), y=np.zeros((400, 1)))
    with pytest.raises(DataError, match="output y0 is constant"):
        sysid.n4sid(zero, 2)
    with pytest.raises(DataError, match="output y0 is 0 in every sample: ar"):
        sysid.ar(sysid.IOData(u=None, y=np.zeros(400)), 2)


@pytest.mark.parametrize("cls", [sysid.Saturation, sysid.DeadZone])
def test_two_sided_nonlinearity_bounds_in_order(cls):
    with pytest.raises(DataError, match=r"lower \(1\) must be below upper \(-1\)"):
        cls(lower=1, upper=-1)
    with pytest.raises(DataError, match="must be finite"):
        cls(lower=float("nan"), upper=1)
    assert cls(lower=-1, upper=1).upper == 1.0


def test_pbsid_negative_ridge_is_refused(data):
    with pytest.raises(DataError, match="ridge must be a finite number >= 0, got -1"):
        sysid.pbsid(data, 1, regularization="ridge", ridge=-1)


def test_era_of_huge_markov_parameters_says_what_to_do():
    h = np.array([0.0] + [1e300 * 0.9**k for k in range(40)])
    with pytest.raises(DataError, match="too large to realise in double precision"):
        sysid.era(h, 2)
    # the advised scaling works: the same system scaled down realises
    r = sysid.era(h / 1e300, 1)
    assert np.allclose(r.model.poles(), 0.9, atol=1e-8)


def test_etfe_of_one_sample_is_refused():
    with pytest.raises(InsufficientDataError, match="at least 4 samples"):
        sysid.etfe(sysid.IOData(u=np.ones(1), y=np.ones(1)))


# -- the streaming and recursive paths: a bad input is refused before it sizes anything -----

def _never(what):
    """A stand-in for a constructor that allocates from its arguments: the test fails if it
    is reached."""
    def built(*args, **kwargs):
        raise AssertionError(f"{what} was built (and sized) before the input was checked")
    return built


@pytest.mark.parametrize("u, y, error", [
    (np.ones((10, 1)), np.ones((100, 1)), "u has 10 samples but y has 100"),
    (np.ones((100, 1)), np.r_[np.ones(50), np.nan, np.ones(49)], "non-finite"),
    (np.ones((100, 1)), np.full((100, 1), "a"), "real numeric"),
])
def test_recursive_subspace_checks_the_first_chunk_before_sizing_its_factor(
        monkeypatch, u, y, error):
    monkeypatch.setattr(sysid._sysid, "RecursiveFactor", _never("the recursive factor"))
    rs = sysid.RecursiveSubspace(order=1, horizon=2000)  # k = 8000: a 512 MB factor
    with pytest.raises(DataError, match=error):
        rs.update(u, y)


@pytest.mark.parametrize("u, y, error", [
    (np.ones((10, 1)), np.ones((100, 1)), "u has 10 samples but y has 100"),
    (np.ones((100, 1)), np.r_[np.ones(50), np.nan, np.ones(49)], "non-finite"),
])
def test_compress_stream_checks_the_first_chunk_before_sizing_the_compressor(
        monkeypatch, u, y, error):
    from sysid.subspace.streaming import compress_stream

    monkeypatch.setattr(sysid._sysid, "StreamingCompressor", _never("the compressor"))
    with pytest.raises(DataError, match=error):
        compress_stream(iter([(u, y)]), past=2000, compressor="qr", progress=False)


def test_recursive_process_noise_is_sized_from_the_checked_structure(monkeypatch):
    """A scalar process noise becomes a p x p matrix: p comes from the structure the core
    accepted (at most 4096 parameters), not from the orders as given."""
    eye = np.eye

    def small_eye(n, *args, **kwargs):
        assert n <= 4096, f"a {n} x {n} identity was built before the structure was checked"
        return eye(n, *args, **kwargs)

    monkeypatch.setattr(np, "eye", small_eye)
    with pytest.raises(DataError, match="more than an online estimator supports"):
        sysid.RecursiveARX(20000, 1, method="kalman", process_noise=1.0)
    rng = np.random.default_rng(0)
    u, y = rng.standard_normal(200), rng.standard_normal(200)
    runs = [sysid.RecursiveARX(2, 1, method="kalman", process_noise=q) for q in (None, 0.5)]
    for est in runs:
        est.run(u, y)
    assert not np.allclose(runs[0].parameters, runs[1].parameters)  # the noise is taken


@pytest.mark.parametrize("kwargs", [{"degree": 5}, {"degree": 3, "branches": 30}])
def test_pnlss_refuses_more_parameters_than_residuals(data, kwargs):
    """The parameter count is checked against the residuals before the optimiser sizes its
    normal equations by it (order 4, degree 9 on 300 samples panicked allocating 10 010^2)."""
    short = data.slice(0, 120)
    with pytest.raises(DataError, match=r"parameters but the record gives \d+ residuals"):
        sysid.pnlss(short, 2, progress=False, max_iter=2, **kwargs)


# -- sizes that reached the allocator (issue 31, "Sizes reach the allocator") ---------------

def _under_memory_limit(code, extra_gib=1.0):
    """Runs ``code`` in a fresh interpreter whose address space is limited to what it has
    after importing sysid plus ``extra_gib``: an allocation the input should have prevented
    fails there (a Rust panic or abort) instead of swapping the machine. Returns stdout."""
    import subprocess
    import sys
    import textwrap

    if not sys.platform.startswith("linux"):
        pytest.skip("the address-space limit is read from /proc")
    prelude = textwrap.dedent(f"""
        import resource, numpy as np, sysid
        from sysid import _sysid
        from sysid.errors import DataError
        vm = [int(line.split()[1]) for line in open("/proc/self/status")
              if line.startswith("VmSize")][0] * 1024
        lim = vm + int({extra_gib} * 2**30)
        resource.setrlimit(resource.RLIMIT_AS, (lim, lim))
    """)
    run = subprocess.run([sys.executable, "-c", prelude + textwrap.dedent(code)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    return run.stdout


def _sized_first(real, what):
    """Wraps a native constructor: building it means the input was not refused first."""
    def built(*args, **kwargs):
        real(*args, **kwargs)
        raise AssertionError(f"{what} was built (and sized) before the input was refused")
    return built


@pytest.mark.parametrize("compressor", ["qr", "auto", "correlation"])
def test_compress_stream_checks_a_known_length_before_sizing(monkeypatch, compressor):
    """past=2000 on 500 samples: the horizon is refused from the arrays' length, not after a
    4.9 GB ("qr") or 0.5 GB ("auto") compressor has read them."""
    from sysid.subspace.streaming import compress_stream

    real = sysid._sysid.StreamingCompressor
    monkeypatch.setattr(sysid._sysid, "StreamingCompressor", _sized_first(real, "the compressor"))
    u, y = np.ones((500, 1)), np.ones((500, 1))
    for source in [(u, y), [(u, y), (u[:300], y[:300])]]:
        with pytest.raises(InsufficientDataError, match=r"horizon <= 250"):
            compress_stream(source, past=2000, compressor=compressor, progress=False)


def test_compress_dask_checks_the_length_before_the_workers_size_their_sums(monkeypatch):
    da = pytest.importorskip("dask.array")
    from sysid.subspace import streaming

    monkeypatch.setattr(streaming, "_partial_sums", _never("a worker's correlation sums"))
    u = da.ones((500, 1), chunks=(250, 1))
    with pytest.raises(InsufficientDataError, match=r"horizon <= 250"):
        streaming.compress_dask(u, u, past=1000)


def test_streams_of_unknown_length_allocate_nothing_before_a_window_is_complete():
    """A generator's length is known only at its end: the exact compressor and the recursive
    factor size their work (2.5 GB, 0.5 GB + a copy for past = 2000) only when a first
    window is complete, so a stream too short for one is refused at finish within 1 GiB."""
    out = _under_memory_limit("""
        from sysid.errors import InsufficientDataError
        from sysid.subspace.streaming import compress_stream
        u, y = np.ones((500, 1)), np.ones((500, 1))
        try:
            compress_stream(iter([(u, y)]), past=2000, compressor="qr", progress=False)
        except InsufficientDataError as e:
            print("refused:", e)
        rs = sysid.RecursiveSubspace(order=1, horizon=2000)
        print("updated:", rs.update(u[:100], y[:100]))
    """)
    assert "refused:" in out and "needs at least 4000 but got 500" in out and "updated: None" in out


def test_a_short_stream_is_refused_before_the_correlation_gram_matrix_is_sized():
    """"auto" and "correlation" sized the k x k Gram matrix (0.5 GB for past = 2000) with
    the first chunk; it is sized when an experiment with a complete window closes, so a
    generator too short for one window is refused at finish within 0.3 GiB."""
    out = _under_memory_limit("""
        from sysid.errors import InsufficientDataError
        from sysid.subspace.streaming import compress_stream
        u, y = np.ones((300, 1)), np.ones((300, 1))
        for compressor in ["auto", "correlation"]:
            try:
                compress_stream(iter([(u, y), (u[:200], y[:200])]), past=2000,
                                compressor=compressor, progress=False)
            except InsufficientDataError as e:
                print("refused:", compressor, e)
        try:
            np.ones(2000 * 4 * 2000 * 4)
        except MemoryError:
            print("the limit holds a 0.5 GB matrix off")
    """, extra_gib=0.3)
    assert out.count("needs at least 4000 but got 500") == 2, out
    assert "the limit holds a 0.5 GB matrix off" in out


def test_recursive_subspace_checks_its_whole_working_set():
    """k = 10 000: the 0.8 GB triangle passed the check, the update's copy and (5 k x k)
    stack (5.6 GB in all) did not."""
    rs = sysid.RecursiveSubspace(order=1, horizon=2500)
    with pytest.raises(DataError, match="a recursive update holds the k x k factor"):
        rs.update(np.ones((100, 1)), np.ones((100, 1)))


def test_recursive_arx_delay_is_bounded():
    """nk = 10**12 sized a delay line of 8 TB and aborted the process."""
    with pytest.raises(DataError, match="delay line of more than 65536 samples"):
        sysid.RecursiveARX(2, 1, nk=10**12)
    est = sysid.RecursiveARX(1, 1, nk=1000)  # long but bounded
    est.run(np.ones(50), np.ones(50))


def test_pnlss_normal_equations_are_checked_before_allocating():
    """About 25 000 parameters (4 states, 2 inputs, degrees 2..9): a 5 GB J^T J panicked in
    the allocator (AllocError -> PanicException); refused by the search before any provider
    is evaluated."""
    out = _under_memory_limit("""
        nx, nu, ny = 4, 2, 1
        zeta = [[]] + _sysid.pnlss_monomials(nx, nu, "full", list(range(2, 10)))
        eta = [[]] + _sysid.pnlss_monomials(nx, nu, "full", list(range(2, 10)))
        p = nx * nx + nx * nu + ny * nx + ny * nu + nx * len(zeta) + ny * len(eta)
        theta0 = np.zeros(p)
        theta0[: nx * nx] = 0.5 * np.eye(nx).ravel()
        u = np.random.default_rng(0).standard_normal((300, nu))
        y = np.ascontiguousarray(u[:, :1])
        try:
            struct = {"nx": nx, "nu": nu, "ny": ny, "zeta": zeta, "eta": eta}
            _sysid.pnlss_estimate(struct, [(u, y, 0)], theta0, max_iter=1)
        except DataError as e:
            print("refused:", p, e)
    """)
    assert "refused:" in out and "normal equations" in out and "GiB limit" in out


def test_nlssest_refuses_absurd_batches_and_widths(data):
    """batch = 10**9 ran without end; hidden = 10**6 on 300 samples ran past 120 s."""
    short = data.slice(0, 300)
    with pytest.raises(DataError, match=r"batch <= \d+"):
        sysid.nlssest(short, 1, hidden=4, batch=10**9, progress=False)
    with pytest.raises(DataError, match=r"give networks of \d+ parameters, and the training "
                                        r"part of the record has \d+ residuals"):
        sysid.nlssest(short, 1, hidden=10**6, progress=False)


def test_ssest_order_beyond_the_horizon_names_the_largest_order():
    """A short record of many channels (a power plant: 133 samples, 5 inputs, 3 outputs)
    allows few states; ssest says how many, as n4sid does, not only "lower the order"."""
    rng = np.random.default_rng(0)
    u = rng.standard_normal((133, 5))
    y = u @ rng.standard_normal((5, 3)) + 0.1 * rng.standard_normal((133, 3))
    from sysid.errors import OrderError
    with pytest.raises(OrderError, match=r"order <= 18 "):  # horizon 7: 18 states at most
        sysid.ssest(sysid.IOData(u=u, y=y), 19)


def test_spa_on_a_short_drifting_record_reports_no_false_coherence():
    """A short record of drifting channels (a power plant: 133 samples, 5 inputs): the lag
    window can put an auto-spectrum estimate at or below zero, where the coherence is
    undefined. It is reported as 0, without an overflow (it was |Syu|^2 / tiny, clipped
    to 1: full coherence where the estimate has no power)."""
    rng = np.random.default_rng(0)
    u = np.cumsum(rng.standard_normal((133, 5)), 0) * 100
    y = u @ rng.standard_normal((5, 3)) + np.cumsum(rng.standard_normal((133, 3)), 0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning from NumPy
        frd = sysid.spa(sysid.IOData(u=u, y=y))
    assert np.all(np.isfinite(frd.response))
    assert np.all((frd.coherence >= 0) & (frd.coherence <= 1))
    # where the windowed estimate leaves no noise, the band is the smallest the estimate
    # resolves, never zero (106 zero standard deviations here claimed an exact response,
    # and tfest refused the FRD as data)
    assert np.all(np.asarray(frd.std) > 0)


def test_find_spikes_of_a_record_says_what_to_pass():
    """find_spikes takes an array; given a record it failed inside IOData's indexing with a
    message about slicing samples."""
    d = sysid.IOData(u=np.random.default_rng(0).standard_normal((100, 1)),
                     y=np.random.default_rng(1).standard_normal((100, 1)))
    with pytest.raises(DataError, match=r"data\.y"):
        sysid.find_spikes(d)
    assert sysid.find_spikes(d.y).shape == (100, 1)


def test_ssest_of_a_frequency_response_points_to_the_frequency_tools():
    """MATLAB's ssest takes frequency-response data; sysid's took time records only and said
    "data must be a sysid.IOData or a (u, y) pair, got FRD". It now fits the FRD (the
    frequency-domain subspace start refined on its lines); time-only estimators name the
    tools that take one."""
    rng = np.random.default_rng(0)
    u = rng.standard_normal(600)
    y = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]]).simulate(u)
    frd = sysid.spa(sysid.IOData(u=u, y=y))
    with pytest.raises(DataError, match=r"sysid\.ssest\(frd, order\)"):
        sysid.cva(frd, 1)
    with pytest.raises(DataError, match=r"sysid\.ssest\(frd, order\)"):
        sysid.arx(frd, 1, 1, 1)
    m = sysid.ssest(frd, 1)
    assert abs(m.poles()[0] - 0.8) < 0.05  # spa's lag window biases it a little
