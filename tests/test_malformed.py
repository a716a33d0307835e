"""Malformed and edge-case input (issue 10): every bad input gives a sysid error that names
the problem, no Rust panic reaches Python, no silent guess.

Each case asserts the exception (or warning) type and the words that name the problem.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import sysid
from sysid import _sysid
from sysid.errors import DataError, InsufficientDataError, SysidError

RNG = np.random.default_rng(0)
U = RNG.standard_normal((400, 1))
TRUE = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], [[0.0]], dt=1.0)
Y = TRUE.simulate(U) + 0.01 * RNG.standard_normal((400, 1))
DATA = sysid.IOData(u=U, y=Y)
EST5 = sysid.SubspaceEstimator(DATA, 5)

try:  # pyo3's panic type derives from BaseException
    from pyo3_runtime import PanicException  # type: ignore[import-not-found]
except ImportError:  # pragma: no cover
    PanicException = None


def _no_panic(f, *args, **kw):
    """Run ``f``: success or a sysid error are fine; a panic or another type fails."""
    try:
        f(*args, **kw)
    except SysidError:
        pass
    except BaseException as e:  # noqa: BLE001
        if PanicException is not None and isinstance(e, PanicException):
            raise AssertionError(f"Rust panic reached Python: {e}") from None
        raise AssertionError(f"{type(e).__name__} instead of a sysid error: {e}") from None


# ---------------------------------------------------------------- 1. sizes never panic


@pytest.mark.parametrize(
    ("kw", "exc", "words"),
    [
        ({"horizon": 10**6}, InsufficientDataError, ["horizon", "1000000"]),
        ({"horizon": 2**62}, DataError, ["horizon", "too large"]),
        ({"horizon": 2**64}, DataError, ["horizon", "too large"]),
        ({"horizon": -3}, DataError, ["horizon", "positive"]),
        ({"horizon": 0}, DataError, ["horizon", "positive"]),
        ({"past": 2**40}, InsufficientDataError, ["past", "window"]),
        ({"future": 10**5}, InsufficientDataError, ["past/future", "samples"]),
        ({"past": -1}, DataError, ["past", "positive"]),
        ({"chunk_rows": 10**12, "horizon": 5}, DataError, ["chunk_rows", "GiB"]),
        ({"chunk_rows": 0, "horizon": 5}, DataError, ["chunk_rows", "positive"]),
        ({"chunk_rows": 2**70, "horizon": 5}, DataError, ["chunk_rows", "too large"]),
        ({"horizon": 2.5}, DataError, ["horizon", "integer"]),
        ({"horizon": True}, DataError, ["horizon"]),
    ],
)
def test_subspace_sizes(kw, exc, words):
    with pytest.raises(exc) as e:
        sysid.SubspaceEstimator(DATA, **kw)
    for w in words:
        assert w in str(e.value)


@pytest.mark.parametrize(
    ("kw", "words"),
    [
        ({"past": -2}, ["past", "positive"]),
        ({"past": 2**64}, ["past", "too large"]),
        ({"past": 3, "future": -1}, ["future", "positive"]),
        ({"past": 3, "chunk_size": 0}, ["chunk_size"]),
    ],
)
def test_compress_stream_sizes(kw, words):
    with pytest.raises(DataError) as e:
        sysid.compress_stream([(U, Y)], progress=False, **kw)
    for w in words:
        assert w in str(e.value)


def test_compress_stream_horizon_vs_data():
    with pytest.raises(InsufficientDataError, match="window"):
        sysid.compress_stream([(U[:10], Y[:10])], past=20, progress=False, compressor="qr")


@pytest.mark.parametrize(
    ("orders", "words"),
    [
        ((10**6, 10**6, 1), ["orders", "too many"]),
        ((2**64, 1, 1), ["na", "too large"]),
        ((1, 2**64, 1), ["nb", "too large"]),
        ((-1, 1, 1), ["na", "non-negative"]),
        ((1, 1, -5), ["nk", "non-negative"]),
        ((1.5, 1, 1), ["na", "integers"]),
        ((1, 1, 10**9), ["too many"]),
    ],
)
def test_arx_sizes(orders, words):
    with pytest.raises(DataError) as e:
        sysid.arx(DATA, *orders)
    for w in words:
        assert w in str(e.value)


@pytest.mark.parametrize(
    ("f", "words"),
    [
        (lambda: sysid.armax(DATA, 2**64, 1, 1, 1), ["na", "too large"]),
        (lambda: sysid.armax(DATA, 10**6, 1, 1, 1), ["parameters"]),
        (lambda: sysid.oe(DATA, 1, 10**7, 1), ["parameters"]),
        (lambda: sysid.oe(DATA, 1, 1, 10**7), ["nk"]),
        (lambda: sysid.bj(DATA, 1, 1, 1, 1, -2), ["nk", "non-negative"]),
        (lambda: sysid.ar(sysid.IOData(y=Y), 2**70), ["na", "too large"]),
        (lambda: sysid.armax(DATA, 1, 1, 1, 1, max_iter=-1), ["max_iter"]),
    ],
)
def test_polynomial_pem_sizes(f, words):
    with pytest.raises(DataError) as e:
        f()
    for w in words:
        assert w in str(e.value)


def test_core_size_guard_in_bindings():
    # the bindings themselves refuse sizes that would not fit in memory (no AllocError panic)
    with pytest.raises(DataError, match="horizon"):
        _sysid.StreamingCompressor(1, 1, 10**6, 10**6)
    with pytest.raises(DataError, match="horizon"):
        _sysid.StreamingCompressor(1, 1, 2**62, 2**62)
    with pytest.raises(DataError, match="chunk_rows"):
        _sysid.StreamingCompressor(1, 1, 5, 5, "qr", 10**12)
    with pytest.raises(InsufficientDataError, match="horizon"):
        _sysid.compress([(U, Y)], 10**3, 10**3)


SIZES = st.one_of(
    st.integers(-(2**70), 2**70),
    st.sampled_from([0, 1, 2, 3, -1, 2**31, 2**32, 2**62, 2**63, 2**64, 10**6, 10**12]),
)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(h=SIZES, p=st.none() | SIZES, c=st.none() | SIZES)
def test_no_panic_subspace_sizes(h, p, c):
    _no_panic(sysid.SubspaceEstimator, DATA, h, past=p, chunk_rows=c)


@settings(max_examples=40, deadline=None)
@given(p=SIZES, f=st.none() | SIZES, comp=st.sampled_from(["qr", "correlation"]))
def test_no_panic_compress_stream_sizes(p, f, comp):
    _no_panic(sysid.compress_stream, [(U, Y)], p, f, compressor=comp, progress=False)


@settings(max_examples=40, deadline=None)
@given(na=SIZES, nb=SIZES, nk=SIZES)
def test_no_panic_arx_sizes(na, nb, nk):
    _no_panic(sysid.arx, DATA, na, nb, nk)


@settings(max_examples=25, deadline=None)
@given(na=SIZES, nb=SIZES, nk=SIZES)
def test_no_panic_oe_armax_sizes(na, nb, nk):
    _no_panic(sysid.oe, DATA, nb, na, nk, max_iter=2)
    _no_panic(sysid.armax, DATA, na, nb, na, nk, max_iter=2)


@settings(max_examples=40, deadline=None)
@given(n=SIZES, r=st.none() | SIZES)
def test_no_panic_realization_sizes(n, r):
    h = TRUE.markov(40)
    _no_panic(sysid.era, h, order=n if n > 0 else 1, rows=r)
    _no_panic(sysid.impulse_response, DATA, n)


# lengths that fit in memory but take long to simulate are left out (not an error)
FEASIBLE_OR_ABSURD = SIZES.filter(lambda n: n <= 10**4 or n >= 2**33)


@settings(max_examples=30, deadline=None)
@given(n=FEASIBLE_OR_ABSURD)
def test_no_panic_model_sizes(n):
    _no_panic(TRUE.step, n)
    _no_panic(TRUE.impulse, n)
    _no_panic(TRUE.markov, n)


@settings(max_examples=30, deadline=None)
@given(n=SIZES)
def test_no_panic_fit_order(n):
    _no_panic(EST5.fit, n)


# ---------------------------------------------------------------- CLI: one line, exit 2


@pytest.fixture
def csv_file(tmp_path):
    p = tmp_path / "d.csv"
    np.savetxt(p, np.c_[U, Y], delimiter=",", header="u,y", comments="")
    return p


def _cli(capsys, *argv):
    from sysid.cli import main

    code = main([str(a) for a in argv])
    err = capsys.readouterr().err.strip()
    return code, err


def _one_error_line(err):
    lines = [ln for ln in err.splitlines() if ln.startswith("sysid: error")]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--horizon", "1000000"], ["horizon", "1000000"]),
        (["--horizon", "-2"], ["--horizon", "positive"]),
        (["--method", "ssest"], ["ssest", "pi-moesp"]),
        (["--order", "x"], ["--order"]),
        (["--split", "abc"], ["--split"]),
        (["--inputs", "nope"], ["nope", "not found"]),
    ],
)
def test_cli_errors_one_line(capsys, tmp_path, csv_file, extra, words):
    code, err = _cli(capsys, "identify", csv_file, "--inputs", "u", "--outputs", "y",
                     "--report", tmp_path / "r", "--quiet", *extra)
    assert code == 2
    line = _one_error_line(err)
    for w in words:
        assert w in line


def test_cli_method_checked_before_compression(capsys, tmp_path, csv_file):
    code, err = _cli(capsys, "identify", csv_file, "--inputs", "u", "--outputs", "y",
                     "--report", tmp_path / "r", "--method", "ssest")
    assert code == 2
    assert "compressing" not in err and "reading" not in err


def test_cli_binary_file(capsys, tmp_path):
    p = tmp_path / "b.csv"
    p.write_bytes(bytes(range(256)) * 4)
    code, err = _cli(capsys, "identify", p, "--outputs", "y", "--report", tmp_path / "r",
                     "--quiet")
    assert code == 2
    assert "not a text table" in _one_error_line(err)


def test_cli_report_is_a_file(capsys, tmp_path, csv_file):
    f = tmp_path / "taken.txt"
    f.write_text("x")
    code, err = _cli(capsys, "identify", csv_file, "--inputs", "u", "--outputs", "y",
                     "--report", f, "--quiet")
    assert code == 2
    assert "existing file" in _one_error_line(err)


def test_cli_help_lists_every_method(capsys):
    from sysid.cli import main
    from sysid.estimate.subspace import METHODS

    with pytest.raises(SystemExit):
        main(["identify", "--help"])
    out = capsys.readouterr().out
    for m in METHODS:
        assert m in out
