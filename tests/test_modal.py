"""Modal analysis: natural frequencies (Hz, rad/s), damping ratios, mode shapes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm

import sysid


def structure(freqs_hz: list[float], zetas: list[float], dt: float,
              shapes: np.ndarray) -> sysid.StateSpaceModel:
    """Discretised modal model: modes with the given frequencies, damping and real shapes."""
    k = len(freqs_hz)
    ac = np.zeros((2 * k, 2 * k))
    for i, (f, z) in enumerate(zip(freqs_hz, zetas)):
        w = 2 * np.pi * f
        ac[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0.0, 1.0], [-w * w, -2 * z * w]]
    c = np.zeros((shapes.shape[0], 2 * k))
    c[:, 0::2] = shapes  # displacement outputs
    b = np.zeros((2 * k, 1))
    b[1::2, 0] = 1.0
    return sysid.StateSpaceModel(expm(ac * dt), b, c, dt=dt)


def test_frequencies_damping_and_shapes_of_a_known_structure() -> None:
    dt = 0.004
    shapes = np.array([[1.0, 0.5, -0.2], [0.4, -1.0, 1.0], [-0.3, 0.2, 0.6]])
    model = structure([15.46, 3.2, 40.0], [0.02, 0.05, 0.01], dt, shapes)
    res = sysid.modal_analysis(model)
    assert len(res) == 3
    np.testing.assert_allclose(res.frequencies_hz, [3.2, 15.46, 40.0], rtol=1e-10)
    np.testing.assert_allclose(res.omega, 2 * np.pi * res.frequencies_hz, rtol=1e-14)
    np.testing.assert_allclose(res.damping, [0.05, 0.02, 0.01], rtol=1e-9)
    expected = shapes[:, [1, 0, 2]].T  # one row per mode, sorted by frequency
    expected = expected / expected[np.arange(3), np.argmax(np.abs(expected), axis=1)][:, None]
    np.testing.assert_allclose(res.mode_shapes, expected, atol=1e-9)
    np.testing.assert_allclose(np.exp(res.s * dt), res.eigenvalues, rtol=1e-12)
    assert np.all(res.eigenvalues.imag > 0)
    text = repr(res)
    assert "ModalAnalysis(3 modes" in text and "15.4600" in text


def test_matches_numpy_eigenvalues_and_counts_real_poles_once() -> None:
    model = sysid.StateSpaceModel(
        [[0.5, 0, 0, 0], [0, -0.4, 0, 0], [0, 0, 0.8, 0.3], [0, 0, -0.3, 0.8]],
        np.ones((4, 1)), np.ones((2, 4)), dt=0.1)
    res = sysid.modal_analysis(model)
    assert len(res) == 3
    ev = np.linalg.eigvals(model.A)
    s = np.log(ev.astype(complex)) / 0.1
    np.testing.assert_allclose(np.sort(res.omega), np.sort(np.unique(np.round(np.abs(s), 10))))
    neg = res.select(np.isclose(res.eigenvalues.real, -0.4))
    # a negative real pole oscillates at the Nyquist frequency
    assert neg.s.imag[0] == pytest.approx(np.pi / 0.1)


def test_dt_contradicting_the_model_is_refused() -> None:
    model = structure([2.0], [0.1], 0.01, np.array([[1.0]]))
    with pytest.raises(sysid.DataError, match="contradicts the model's sample time"):
        sysid.modal_analysis(model, dt=0.02)
    same = sysid.modal_analysis(model, dt=0.01)
    assert same.frequencies_hz[0] == pytest.approx(2.0)
    assert same.damping[0] == pytest.approx(0.1)


def test_to_pandas_and_select() -> None:
    pytest.importorskip("pandas")
    res = sysid.modal_analysis(structure([1.0, 5.0], [0.01, 0.02], 0.01, np.eye(2)))
    df = res.to_pandas()
    assert list(df.columns[:3]) == ["frequency_hz", "omega", "damping"]
    assert len(res.select(res.frequencies_hz > 2)) == 1


def test_bad_arguments_raise_clear_errors() -> None:
    model = structure([1.0], [0.01], 0.01, np.eye(1))
    for dt in (0.0, -1.0, np.nan):
        with pytest.raises(sysid.DataError, match="dt"):
            sysid.modal_analysis(model, dt=dt)
    with pytest.raises(sysid.DataError, match="StateSpaceModel"):
        sysid.modal_analysis(np.eye(2))  # type: ignore[arg-type]
    defective = sysid.StateSpaceModel([[0.5, 1.0], [0.0, 0.5]], [[0.0], [1.0]], [[1.0, 0.0]])
    with pytest.raises(sysid.NumericalError, match="defective"):
        sysid.modal_analysis(defective)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_modes_do_not_depend_on_the_state_basis(seed: int) -> None:
    rng = np.random.default_rng(seed)
    model = structure(list(rng.uniform(1, 40, 2)), list(rng.uniform(0.005, 0.2, 2)), 0.004,
                      rng.standard_normal((2, 2)))
    # a well-conditioned change of basis (cond <= 4): eigenvalue round-off stays ~1e-13
    q, _ = np.linalg.qr(rng.standard_normal((4, 4)))
    t = q @ np.diag(rng.uniform(0.5, 2.0, 4))
    other = sysid.StateSpaceModel(np.linalg.solve(t, model.A @ t), np.linalg.solve(t, model.B),
                                  model.C @ t, dt=model.dt)
    a, b = sysid.modal_analysis(model), sysid.modal_analysis(other)
    np.testing.assert_allclose(a.frequencies_hz, b.frequencies_hz, rtol=1e-8)
    np.testing.assert_allclose(a.damping, b.damping, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(a.mode_shapes, b.mode_shapes, atol=1e-6)
