"""State-space structures with fixed and free entries (``sysid.ssform``; MATLAB's ``ssform``,
``Structure.<M>.Free`` and ``ssest(data, init_sys)``): known systems recovered to machine
precision in every form, the forms' input-output maps unchanged (hypothesis), fixed entries
kept, identifiable canonical forms (no identifiability warning: the suite turns warnings
into errors), calibrated uncertainty (Monte Carlo), and clear errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid
from sysid.errors import DataError
from sysid.pem.ssform import observability_form

from conftest import assert_std_calibrated

A = np.array([[0.9, 0.2, 0.0], [-0.2, 0.9, 0.1], [0.0, 0.0, 0.5]])
B = np.array([[1.0, 0.2], [0.0, 1.0], [1.0, 0.3]])
C = np.array([[1.0, 0.5, 0.0], [0.0, 1.0, 1.0]])
K = np.array([[0.3, 0.0], [0.1, 0.1], [0.0, 0.2]])
TRUE = sysid.StateSpaceModel(A, B, C, K=K)


def _innovations(model: sysid.StateSpaceModel, u: np.ndarray, e: np.ndarray) -> np.ndarray:
    n, m = model.B.shape
    l = model.C.shape[0]
    aug = sysid.StateSpaceModel(model.A, np.hstack([model.B, model.K]), model.C,
                                np.hstack([np.zeros((l, m)), np.eye(l)]))
    return aug.simulate(np.hstack([u, e]))


def _response(m: sysid.StateSpaceModel) -> np.ndarray:
    return m.freqresp(np.linspace(0.05, 3.0, 25))


@pytest.mark.parametrize("form", ["canonical", "modal", "companion"])
def test_noise_free_recovery_in_every_form(form):
    rng = np.random.default_rng(3)
    u = rng.standard_normal((600, 2))
    data = sysid.IOData(u=u, y=TRUE.simulate(u))
    s = sysid.ssform(TRUE, form)
    scale = 0.002 if form == "companion" else 0.05  # polynomial coefficients: sensitive
    start = s.with_values(s.values * (1 + scale * rng.standard_normal(s.n_free)))
    m = sysid.ssest(data, start, focus="simulation", x0="zero", max_iter=200, tol=1e-14)
    assert np.allclose(_response(m), _response(TRUE), atol=1e-9)
    assert np.allclose(np.sort_complex(m.poles()), np.sort_complex(TRUE.poles()), atol=1e-10)
    fixed = {k: ~v for k, v in s.without_noise().free.items() if k != "K"}
    for k, mask in fixed.items():  # every fixed entry exactly where the structure put it
        assert np.array_equal(getattr(m, k)[mask], getattr(s.model, k)[mask])


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 4), st.integers(1, 3), st.integers(1, 3), st.integers(0, 10_000))
def test_forms_keep_the_input_output_map(n, m, l, seed):
    rng = np.random.default_rng(seed)
    Ar = rng.standard_normal((n, n))
    Ar *= 0.8 / max(1e-3, np.max(np.abs(np.linalg.eigvals(Ar))))
    model = sysid.StateSpaceModel(Ar, rng.standard_normal((n, m)), rng.standard_normal((l, n)),
                                  K=0.1 * rng.standard_normal((n, l)))
    c, nu = observability_form(model)
    assert sum(nu) == n
    assert np.allclose(_response(c), _response(model), atol=1e-7)
    s = sysid.ssform(model, "canonical")
    assert s.n_free == n * l + n * m + n * l  # A's block rows, B, K (no D: D is zero)
    assert np.allclose(_response(s.model), _response(model), atol=1e-7)


def test_canonical_form_is_identifiable_with_noise():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((1500, 2))
    y = _innovations(TRUE, u, 0.1 * rng.standard_normal((1500, 2)))
    s = sysid.ssform(sysid.n4sid(sysid.IOData(u=u, y=y), 3), "canonical", noise="estimate")
    m = sysid.pem(sysid.IOData(u=u, y=y), s)  # an IdentifiabilityWarning would fail this
    p, sd = m.poles(std=True)
    assert np.all(np.isfinite(sd)) and np.all(sd > 0)
    assert np.allclose(np.sort_complex(p), np.sort_complex(TRUE.poles()), atol=6 * sd.max())
    assert m.info["greyest"]["rank"] == s.n_free + 3  # full rank, with the initial state


def test_fixed_entries_stay_and_the_free_ones_move():
    rng = np.random.default_rng(1)
    true = sysid.StateSpaceModel([[0.8, 0.1], [0.0, 0.5]], [[1.0], [1.0]], [[1.0, 0.0]])
    u = rng.standard_normal(400)
    data = sysid.IOData(u=u, y=true.simulate(u) + 0.01 * rng.standard_normal((400, 1)))
    start = sysid.StateSpaceModel([[0.6, 0.0], [0.0, 0.3]], [[1.0], [1.0]], [[1.0, 0.0]])
    s = sysid.ssform(start, free={"A": [[True, True], [False, True]], "B": False, "C": False})
    assert s.names == ["A_0_0", "A_0_1", "A_1_1"]
    m = sysid.pem(data, s, x0="zero")
    assert m.A[1, 0] == 0.0 and m.B.tolist() == [[1.0], [1.0]] and m.C.tolist() == [[1, 0]]
    assert np.allclose(m.A, true.A, atol=0.02)
    table = m.info["parameters"].to_pandas()
    assert list(table.index) == s.names and np.all(table["std"] > 0)
    assert m.info["structure"].read(m).values.tolist() == m.info["structure"].values.tolist()


def test_uncertainty_is_calibrated_monte_carlo():
    """250 records of a second-order output-error system in the canonical form: the predicted
    standard deviation of each free A entry within 20 % of the sample one, and 95 % intervals
    covering 90-99 % (a binomial 99 % band around 95 % for 250 draws is about 91-98.5 %)."""
    true = sysid.StateSpaceModel([[0.0, 1.0], [-0.56, 1.5]], [[1.0], [0.4]], [[1.0, 0.0]])
    s0 = sysid.ssform(true, "canonical")
    assert s0.names[:2] == ["A_1_0", "A_1_1"]
    rng = np.random.default_rng(7)
    est, sds = [], []
    for _ in range(250):
        u = rng.standard_normal(300)
        y = true.simulate(u) + 0.2 * rng.standard_normal((300, 1))
        m = sysid.pem(sysid.IOData(u=u, y=y), s0, focus="simulation", x0="zero")
        t = m.info["parameters"]
        est.append(t.value[:2])
        sds.append(t.std[:2])
    assert_std_calibrated(est, sds, true.A[1])


def test_ssest_of_a_start_model_is_pem():
    rng = np.random.default_rng(2)
    u = rng.standard_normal((500, 2))
    data = sysid.IOData(u=u, y=_innovations(TRUE, u, 0.05 * rng.standard_normal((500, 2))))
    start = sysid.n4sid(data, 3)
    a = sysid.ssest(data, start, focus="simulation")
    b = sysid.pem(data, start, focus="simulation")
    assert np.allclose(_response(a), _response(b), atol=1e-12)
    everything = sysid.ssform(start, noise="none")  # nothing fixed: pem's own search
    c = sysid.ssest(data, everything, focus="simulation")
    assert np.allclose(_response(c), _response(b), atol=1e-12)
    assert c.info["structure"].form == "free" and "pem" in c.info


def test_structure_summary_and_repr():
    s = sysid.ssform(TRUE, "canonical")
    assert "canonical" in repr(s) and "18 free parameters" in repr(s)
    text = s.summary()
    assert "C:\n  x . . \n" not in text and "A:" in text and "K:" in text
    assert s.free["C"].sum() == 0 and s.free["A"].sum() == 6


def test_bad_structures_and_options_are_refused():
    with pytest.raises(DataError, match="shape"):
        sysid.ssform(TRUE, free={"A": np.ones((2, 2), bool)})
    with pytest.raises(DataError, match="matrices"):
        sysid.ssform(TRUE, free={"Q": True})
    with pytest.raises(DataError, match="form must be"):
        sysid.ssform(TRUE, "observer")
    with pytest.raises(DataError, match="no free parameter"):
        sysid.ssform(TRUE, free={"A": False, "B": False, "C": False, "K": False})
    with pytest.raises(DataError, match="GreyBox"):
        sysid.ssform(sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]]))
    with pytest.raises(DataError, match="observable"):
        sysid.ssform(sysid.StateSpaceModel(np.diag([0.5, 0.3]), [[1.0], [1.0]], [[1.0, 0.0]]),
                     "canonical")
    rng = np.random.default_rng(0)
    u = rng.standard_normal((200, 2))
    data = sysid.IOData(u=u, y=TRUE.simulate(u))
    s = sysid.ssform(TRUE, "canonical")
    with pytest.raises(DataError, match="regularization"):
        sysid.pem(data, s, regularization={"lambda": 1.0})
    with pytest.raises(DataError, match="feedthrough"):
        sysid.ssest(data, s, feedthrough=True)
    with pytest.raises(DataError, match="data have 1 and 2"):
        sysid.pem(sysid.IOData(u=u[:, :1], y=TRUE.simulate(u)), s)


def test_bounds_hold_and_are_reported():
    rng = np.random.default_rng(4)
    true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]])
    u = rng.standard_normal(300)
    data = sysid.IOData(u=u, y=true.simulate(u) + 0.01 * rng.standard_normal((300, 1)))
    s = sysid.ssform(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), free={"C": False})
    b = s.with_bounds(maximum={"A": 0.7})
    assert b.bounds == {"A_0_0": (-np.inf, 0.7)}
    m = sysid.pem(data, b, x0="zero")
    assert m.A[0, 0] <= 0.7 and np.isclose(m.A[0, 0], 0.7, atol=1e-6)
    assert m.info["structure"].bounds == b.bounds
    free_fit = sysid.pem(data, s, x0="zero")
    assert np.isclose(free_fit.A[0, 0], 0.8, atol=0.01)
    with pytest.raises(DataError, match="outside its bounds"):
        s.with_bounds(minimum={"A": 0.6})
    with pytest.raises(DataError, match="shape"):
        s.with_bounds(minimum={"A": [0.1, 0.2]})


def test_ssest_form_option_gives_the_same_model_in_identifiable_parameters():
    """MATLAB's ssest(..., 'Form', f): the same model (response, poles and their std) in
    every form, each with a full-rank parameter table."""
    rng = np.random.default_rng(5)
    true = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.0]], [[1.0, 0.5]],
                                 K=[[0.3], [0.1]])
    u = rng.standard_normal(800)
    y = _innovations(true, u[:, None], 0.05 * rng.standard_normal((800, 1)))
    data = sysid.IOData(u=u, y=y)
    free = sysid.ssest(data, 2)
    p0, s0 = free.poles(std=True)
    for form in ("canonical", "modal", "companion"):
        m = sysid.ssest(data, 2, form=form)
        assert m.info["structure"].form == form and m.info["structure"].n_free == 6
        assert np.allclose(_response(m), _response(free), rtol=1e-4, atol=1e-6)
        p, s = m.poles(std=True)
        assert np.allclose(np.sort_complex(p), np.sort_complex(p0), atol=1e-6)
        assert np.allclose(np.sort(np.abs(s)), np.sort(np.abs(s0)), rtol=0.05)
        assert np.all(np.isfinite(m.info["parameters"].std))
