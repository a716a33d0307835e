"""Monte Carlo draws of a parameter covariance are the same on every machine: the
eigenvectors' signs (LAPACK's choice, which differs between builds) are fixed."""

import numpy as np

import sysid
from sysid.models import uncertainty as U


def test_eigenvector_signs_are_fixed_whatever_lapack_returns(monkeypatch):
    rng = np.random.default_rng(3)
    a = rng.standard_normal((5, 5))
    P = a @ a.T
    draws = U.ParameterUncertainty(np.zeros(5), P, lambda t: t).sample_parameters(50, 7)
    w, V = U._block_eigen(P, [5])
    assert np.all(V[np.argmax(np.abs(V), axis=0), np.arange(5)] > 0)
    eigh = np.linalg.eigh

    def flipped(M):  # another build: every other eigenvector's sign reversed
        w_, v_ = eigh(M)
        return w_, v_ * np.where(np.arange(v_.shape[1]) % 2, -1.0, 1.0)

    monkeypatch.setattr(U.np.linalg, "eigh", flipped)
    other = U.ParameterUncertainty(np.zeros(5), P, lambda t: t).sample_parameters(50, 7)
    assert np.array_equal(draws, other)
    assert sysid.ParameterUncertainty is U.ParameterUncertainty
