"""The simulation focus keeps the model stable; when the record insists on an unstable plant
(its unstable start simulates it significantly better), a StabilityWarning says so and names
the prediction focus (:mod:`sysid.pem.held_stable`)."""

import warnings

import numpy as np
import pytest

import sysid
from sysid.pem.held_stable import check_held_stable
from sysid.validation.runner import fitted_simulation_errors


def _unstable_record(seed: int, pole: float, N: int = 600) -> sysid.IOData:
    # a real pole at 1.02-1.03 beside a stable one: the output grows 1e5 to 5e7-fold
    rng = np.random.default_rng(seed)
    true = sysid.StateSpaceModel([[0.7, 0.2], [0.0, pole]], [[1.0], [0.5]], [[1.0, 1.0]],
                                 [[0.0]], dt=1.0)
    u = rng.standard_normal((N, 1))
    y = true.simulate(u)
    return sysid.IOData(u, y + 0.01 * np.std(y[:200]) * rng.standard_normal(y.shape), 1.0)


@pytest.mark.parametrize(("seed", "pole"), [(0, 1.02), (0, 1.03), (1, 1.03)])
def test_a_stable_simulation_model_of_an_unstable_plant_says_the_data_insist(
        seed: int, pole: float) -> None:
    # these three came back stable (poles 0.95-0.99 inside the circle) and without a word
    data = _unstable_record(seed, pole)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = sysid.ssest(data, 2, focus="simulation")
    said = [str(w.message) for w in caught if issubclass(w.category, sysid.StabilityWarning)]
    assert np.max(np.abs(m.poles())) < 1.0  # the focus's promise is kept
    assert any("the data insist on an unstable one" in t and "focus='prediction'" in t
               for t in said), said
    test = m.info["pem"]["held_stable"]
    assert test["insists"] and test["start_radius"] > 1.0 and test["likelihood_ratio"] > 6.63
    # one warning about the held model, not a second on the pole the bound holds
    assert sum("keeps" in t and "of its mode" in t for t in said) == 0
    # and the prediction focus, which may return the unstable model, fits the plant
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = sysid.ssest(data, 2)
    assert np.max(np.abs(p.poles())) == pytest.approx(pole, abs=2e-3)


def test_a_stable_plant_is_silent_and_a_stable_start_not_tested() -> None:
    rng = np.random.default_rng(5)
    true = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.0]], [[1.0, 0.5]],
                                 [[0.0]], dt=1.0)
    u = rng.standard_normal((800, 1))
    y = true.simulate(u) + 0.05 * rng.standard_normal((800, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m = sysid.ssest(sysid.IOData(u, y, 1.0), 2, focus="simulation")
    assert m.info["pem"]["held_stable"] is None  # the start was stable: nothing held
    # a stable start is never tested; an unstable one that fits worse does not insist
    assert check_held_stable(m, m, sysid.IOData(u, y, 1.0)) is None
    worse = sysid.StateSpaceModel([[1.01]], [[1.0]], [[1.0]], [[0.0]], dt=1.0)
    held = sysid.StateSpaceModel(m.A, m.B, m.C, m.D, dt=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        test = check_held_stable(held, worse, sysid.IOData(u, y, 1.0))
    assert test is not None and not test["insists"] and test["error_ratio"] < 1.0


def test_the_initial_state_is_fitted_for_an_unstable_model_too() -> None:
    m = sysid.StateSpaceModel([[1.03, 0.0], [0.0, 0.5]], [[1.0], [1.0]], [[1.0, 2.0]],
                              [[0.1]], dt=1.0)
    u = np.random.default_rng(2).standard_normal((400, 1))
    y = m.simulate(u, x0=[-2.0, 4.0])  # grows 1.3e5-fold
    e = fitted_simulation_errors(m, u, y)
    assert np.max(np.abs(e)) < 1e-6 * np.max(np.abs(y))
