"""A saved model keeps its parameter uncertainty: pole and frequency-response standard
deviations after load equal those before, for every family that attaches one (before, every
one was dropped on saving: ``poles(std=True)`` raised on the loaded model)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid


def _data(n: int = 600, seed: int = 0) -> sysid.IOData:
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 1))
    true = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.7]], [[1.0], [0.3]], [[1.0, 0.0]],
                                 dt=0.1)
    return sysid.IOData(u, true.simulate(u) + 0.05 * rng.standard_normal((n, 1)), dt=0.1)


def _fits() -> dict:
    d = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {
            "arx": sysid.arx(d, 2, 2, 1),
            "oe": sysid.oe(d, 2, 2, 1),
            "armax": sysid.armax(d, 2, 2, 1, 1),
            "tfest": sysid.tfest(d, 2, 1),
            "tfest discrete": sysid.tfest(d, 2, 1, dt=0.1),  # build() makes PolynomialModels
            "procest": sysid.procest(d, "P2"),
            "ssest": sysid.ssest(d, 2),
            "identify": sysid.identify(d, refine=False).model,
        }


FITS = _fits()


@pytest.mark.parametrize("fmt", ["json", "npz"])
@pytest.mark.parametrize("name", sorted(FITS))
def test_uncertainty_survives_save_and_load(tmp_path, name, fmt):
    m = FITS[name]
    assert m.uncertainty is not None, name
    path = tmp_path / f"m.{fmt}"
    sysid.save_model(m, path)
    back = sysid.load_model(path)
    assert back.uncertainty is not None, name
    np.testing.assert_allclose(back.uncertainty.covariance, m.uncertainty.covariance)
    p0, s0 = m.poles(std=True)
    p1, s1 = back.poles(std=True)
    np.testing.assert_allclose(p1, p0, atol=1e-12)
    np.testing.assert_allclose(s1, s0, rtol=1e-5, atol=1e-12)
    w = np.linspace(0.1, 20.0, 7)
    if hasattr(m, "freqresp") and name != "identify":
        _, f0 = m.freqresp(w, std=True)
        _, f1 = back.freqresp(w, std=True)
        np.testing.assert_allclose(np.abs(f1), np.abs(f0), rtol=1e-5, atol=1e-12)


def test_the_restored_map_is_the_estimator_map_for_linear_parameters():
    """For parameters that enter the stored numbers linearly (polynomial coefficients), the
    restored ``build`` gives the same model as the estimator's away from the estimate too."""
    m = FITS["arx"]
    back = sysid.model_from_dict(sysid.model_to_dict(m))
    assert "restored" not in back.uncertainty.method
    t = m.uncertainty.theta + 0.1 * np.arange(m.uncertainty.n_parameters)
    a, b = m.uncertainty.build(t), back.uncertainty.build(t)
    np.testing.assert_allclose(np.sort_complex(b.poles()), np.sort_complex(a.poles()),
                               atol=1e-12)
    np.testing.assert_allclose(b.simulate(np.ones(20)), a.simulate(np.ones(20)), atol=1e-12)


def test_a_model_without_uncertainty_saves_none():
    m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    d = sysid.model_to_dict(m)
    assert "uncertainty" not in d
    assert sysid.model_from_dict(d).uncertainty is None


def test_models_with_uncertainty_pickle():
    # an estimator's build(theta) is a closure: pickle raised "Can't pickle local object
    # 'attach_uncertainty.<locals>.build'" (multiprocessing, joblib); it now travels as the
    # affine map save_model writes, with the same first-order standard deviations
    import copy
    import pickle

    d = sysid.detrend(sysid.datasets.load_dryer())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        models = [sysid.arx(d, 2, 2, 3), sysid.ssest(d, 3, progress=False),
                  sysid.procest(d, "P1D")]
    for m in models:
        back = pickle.loads(pickle.dumps(m))
        kw = {"dt": d.dt} if m.dt == 0 else {}
        np.testing.assert_allclose(back.simulate(d.u[:50], **kw), m.simulate(d.u[:50], **kw))
        np.testing.assert_allclose(np.sort(np.abs(back.poles(std=True)[1])),
                                   np.sort(np.abs(m.poles(std=True)[1])), rtol=1e-4)
        twin = copy.deepcopy(m)  # a deep copy keeps the estimator's own build
        assert type(twin.uncertainty.build) is type(m.uncertainty.build)
        np.testing.assert_allclose(twin.poles(std=True)[1], m.poles(std=True)[1])
