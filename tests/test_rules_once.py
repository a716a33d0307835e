"""Issue 31 item 2: each rule once, in the core.

Option strings are parsed by the core (one list of names, one error), stabilisation by
pole reflection is the core's, and lagged covariances come from the core's lagged sums; the
Python layer asks the core and presents its answer.
"""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid import _sysid
from sysid.errors import DataError, NonFiniteError
from sysid.nonparametric.correlation import _lag_covariances
from sysid.pem.pem import _stabilize

OPTIONS = {
    "method": ("moesp", "po-moesp", "N4SID"),
    "closed_loop_method": ("pbsid", "pbsid-opt", "ssarx"),
    "compressor": ("auto", "qr", "correlation"),
    "regularization": ("none", "ridge", "tc"),
    "fir_regularization": ("none", "tc"),
    "factor_source": ("qr", "qr-fallback"),
    "realization": ("ho_kalman", "kung", "era"),
    "integrator": ("rk4", "adaptive"),
    "jacobian": ("fd", "sensitivity"),
    "terms": ("full", "states", "inputs"),
    "recursive_method": ("forgetting", "kalman", "normalized_gradient", "gradient"),
    "nonlinearity": ("identity", "saturation", "deadzone", "polynomial", "pwl", "sigmoid"),
}


@pytest.mark.parametrize("option", sorted(OPTIONS))
def test_every_option_is_parsed_by_the_core(option: str) -> None:
    for name in OPTIONS[option]:
        canon = _sysid.option_name(option, name)
        assert _sysid.option_name(option, canon) == canon
    with pytest.raises(DataError, match=r'unknown \w+ "nope"; \w+ must be "'):
        _sysid.option_name(option, "nope")


def test_aliases_and_case_map_to_one_name() -> None:
    assert _sysid.option_name("method", "PO-MOESP") == "moesp"
    assert _sysid.option_name("closed_loop_method", "pbsid-opt") == "pbsid"
    with pytest.raises(DataError, match="unknown option"):
        _sysid.option_name("colour", "red")


def test_python_presents_the_core_error() -> None:
    rng = np.random.default_rng(0)
    u, y = rng.standard_normal((200, 1)), rng.standard_normal((200, 1))
    core = str(pytest.raises(DataError, _sysid.option_name, "compressor", "fast").value)
    with pytest.raises(DataError) as e:
        sysid.compress_stream((u, y), 3, compressor="fast")
    assert str(e.value) == core
    with pytest.raises(DataError, match='"forgetting", "kalman"'):
        sysid.RecursiveARX(1, 1, method="rls")
    with pytest.raises(DataError, match='integrator must be "rk4" or "adaptive"'):
        sysid.NonlinearGreyBox(lambda t, x, u, p: -x, lambda t, x, u, p: x, {"a": 1.0}, nx=1,
                               integrator="euler")
    with pytest.raises(DataError, match="integrator must be a string"):
        sysid.NonlinearGreyBox(lambda t, x, u, p: -x, lambda t, x, u, p: x, {"a": 1.0}, nx=1,
                               integrator=4)


def _stabilize_by_eig(A: np.ndarray) -> np.ndarray:
    """The former Python rule: eigenvalues with |z| >= 1 moved to 0.99 / conj(z)."""
    w, V = np.linalg.eig(A)
    w = np.where(np.abs(w) >= 1.0, 0.99 / np.conj(w), w)
    return np.real(V @ np.diag(w) @ np.linalg.inv(V))


@pytest.mark.parametrize("seed", range(8))
def test_stabilisation_equals_the_eigenvalue_reflection(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 2 + seed % 5
    A = 1.5 * rng.standard_normal((n, n)) / np.sqrt(n)
    if np.max(np.abs(np.linalg.eigvals(A))) < 1.0:
        A *= 1.5 / np.max(np.abs(np.linalg.eigvals(A)))
    S = _stabilize(A)
    assert S.dtype == np.float64 and S.shape == A.shape
    np.testing.assert_allclose(S, _stabilize_by_eig(A), rtol=0, atol=1e-10 * np.abs(A).max())
    wa, ws = np.linalg.eigvals(A), np.linalg.eigvals(S)
    assert np.max(np.abs(ws)) < 1.0
    # stable poles kept, unstable ones reflected to 0.99 / conj(z)
    want = np.where(np.abs(wa) >= 1.0, 0.99 / np.conj(wa), wa)
    for z in want:
        assert np.min(np.abs(ws - z)) < 1e-8


def test_stabilisation_keeps_a_stable_matrix_and_refuses_bad_ones() -> None:
    A = np.array([[0.5, 0.1], [0.0, -0.3]])
    np.testing.assert_array_equal(_stabilize(A), A)
    np.testing.assert_allclose(_stabilize(np.array([[2.0]])), [[0.495]], rtol=1e-15)
    with pytest.raises(NonFiniteError):
        _stabilize(np.array([[np.nan]]))


def _lag_covariances_fft(zs: list[np.ndarray], max_lag: int, remove_mean: bool) -> np.ndarray:
    """The former FFT computation of ``(1/N) sum_t z(t + tau) z(t)^T``."""
    nc = zs[0].shape[1]
    R = np.zeros((max_lag + 1, nc, nc))
    total = 0
    for z in zs:
        x = z - z.mean(axis=0) if remove_mean else z
        n = x.shape[0]
        total += n
        nfft = int(2 ** np.ceil(np.log2(2 * n)))
        X = np.fft.rfft(x, n=nfft, axis=0)
        C = np.fft.irfft(np.einsum("fa,fb->fab", X, X.conj()), n=nfft, axis=0)
        L = min(max_lag, n - 1)
        R[: L + 1] += C[: L + 1]
    return R / total


@pytest.mark.parametrize("remove_mean", [True, False])
@pytest.mark.parametrize("max_lag", [0, 1, 25, 300])
def test_lag_covariances_equal_the_fft_ones(remove_mean: bool, max_lag: int) -> None:
    rng = np.random.default_rng(max_lag)
    zs = [rng.standard_normal((n, 3)) + 0.5 for n in (1000, 137, 5)]
    zs.append(np.asfortranarray(rng.standard_normal((64, 3))))  # any memory layout
    R, total = _lag_covariances(zs, max_lag, remove_mean)
    assert total == sum(z.shape[0] for z in zs) and R.shape == (max_lag + 1, 3, 3)
    np.testing.assert_allclose(R, _lag_covariances_fft(zs, max_lag, remove_mean),
                               rtol=0, atol=1e-12)
