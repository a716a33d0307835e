"""Invariances of the compression and the estimators, checked with hypothesis."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid
from sysid import _sysid

from conftest import random_system, simulate

SETTINGS = settings(max_examples=25, deadline=None)


def _record(seed, n, m, l, N):
    rng = np.random.default_rng(seed)
    sysm = random_system(n, m, l, rng)
    u = rng.standard_normal((N, m))
    y = simulate(*sysm, u) + 0.01 * rng.standard_normal((N, l))
    return sysm, u, y


@SETTINGS
@given(
    seed=st.integers(0, 10_000),
    m=st.integers(0, 3),
    l=st.integers(1, 3),
    horizon=st.integers(2, 6),
    chunk=st.integers(1, 400),
)
def test_chunk_size_does_not_change_the_factor(seed, m, l, horizon, chunk):
    _, u, y = _record(seed, 2, max(m, 1), l, 300)
    u = u[:, :m]
    ref = _sysid.compress([(u, y)], horizon, horizon, None)
    got = _sysid.compress([(u, y)], horizon, horizon, chunk)
    scale = np.abs(ref.l).max()
    np.testing.assert_allclose(got.l, ref.l, atol=1e-11 * scale)


@SETTINGS
@given(seed=st.integers(0, 10_000), n1=st.integers(20, 200), n2=st.integers(20, 200))
def test_joint_compression_equals_merged_compressions(seed, n1, n2):
    _, u, y = _record(seed, 2, 2, 2, n1 + n2)
    a = (u[:n1], y[:n1])
    b = (u[n1:], y[n1:])
    joint = _sysid.compress([a, b], 3, 3)
    merged = _sysid.compress([a], 3, 3).merge(_sysid.compress([b], 3, 3))
    assert merged.n_columns == joint.n_columns == n1 + n2 - 2 * (6 - 1)
    np.testing.assert_allclose(merged.l, joint.l, atol=1e-11 * np.abs(joint.l).max())


@SETTINGS
@given(
    seed=st.integers(0, 10_000),
    col=st.integers(0, 1),
    scale=st.floats(0.01, 100.0),
    method=st.sampled_from(["moesp", "n4sid", "ordinary-moesp"]),
)
def test_scaling_an_input_scales_the_column_of_b(seed, col, scale, method):
    rng = np.random.default_rng(seed)
    a, b, c, d = random_system(3, 2, 2, rng)
    u = rng.standard_normal((400, 2))
    y = simulate(a, b, c, d, u)
    us = u.copy()
    us[:, col] *= scale
    m1 = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=4, method=method).fit(
        3, kalman=False
    )
    m2 = sysid.SubspaceEstimator(sysid.IOData(u=us, y=y), horizon=4, method=method).fit(
        3, kalman=False
    )
    h1, h2 = m1.markov(15), m2.markov(15)
    expected = h1.copy()
    expected[:, :, col] /= scale
    np.testing.assert_allclose(h2, expected, atol=1e-8 * np.abs(h1).max() / min(scale, 1.0))


@SETTINGS
@given(seed=st.integers(0, 10_000), perm=st.permutations([0, 1, 2]))
def test_permuting_outputs_permutes_c_and_the_response(seed, perm):
    rng = np.random.default_rng(seed)
    a, b, c, d = random_system(3, 1, 3, rng)
    u = rng.standard_normal((300, 1))
    y = simulate(a, b, c, d, u)
    perm = list(perm)
    m1 = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=3).fit(3, kalman=False)
    m2 = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y[:, perm]), horizon=3).fit(3, kalman=False)
    np.testing.assert_allclose(m2.markov(12), m1.markov(12)[:, perm, :], atol=1e-9)
    np.testing.assert_allclose(m2.simulate(u), m1.simulate(u)[:, perm], atol=1e-8)
    # C's rows are permuted in a common state basis
    o1 = np.vstack([m1.C @ np.linalg.matrix_power(m1.A, i) for i in range(3)])
    o2 = np.vstack([m2.C[np.argsort(perm)] @ np.linalg.matrix_power(m2.A, i) for i in range(3)])
    t = np.linalg.solve(o2.T @ o2, o2.T @ o1)  # x2 = t x1
    np.testing.assert_allclose(m2.C @ t, m1.C[perm], atol=1e-8)
