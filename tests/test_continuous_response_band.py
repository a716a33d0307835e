"""The ``std=True`` band of a continuous-time model's step and impulse responses: every
model drawn from (or stepped along) the parameter covariance is evaluated on the estimate's
own time grid, so the band is the first-order std of the response at those instants.

Before: each perturbed ``ContinuousStateSpace`` chose its grid from its own slowest pole,
so the central differences compared responses at other times (step std 0.064 / 0.092 /
0.099 at t = 1.02 / 2.55 / 5.0 where the closed form gives 0.027 / 0.072 / 0.096, the
impulse std 0 everywhere), and ``c.step(std=True)`` raised a TypeError.
"""

import numpy as np
import pytest

import sysid
from sysid.errors import DataError


def build(t):
    return sysid.ContinuousStateSpace([[-t[0]]], [[1.0]], [[1.0]])


@pytest.fixture
def lag():
    """``1 / (s + a)`` at ``a = 1`` with ``std(a) = 0.1``."""
    c = build([1.0])
    c.uncertainty = sysid.ParameterUncertainty([1.0], [[0.01]], build)
    return c


def _step_std(t):
    # y = (1 - e^{-a t}) / a: dy/da = t e^{-a t} / a - (1 - e^{-a t}) / a^2, at a = 1
    return 0.1 * np.abs(t * np.exp(-t) - (1 - np.exp(-t)))


def _impulse_std(t):
    # y = e^{-a t}: dy/da = -t e^{-a t}
    return 0.1 * t * np.exp(-t)


def test_step_band_is_the_closed_form(lag):
    r = sysid.step(lag, 50, std=True)
    np.testing.assert_allclose(r.std[:, 0, 0], _step_std(r.t), rtol=1e-5, atol=1e-9)
    k = [10, 25, 49]
    np.testing.assert_allclose(r.t[k], [1.0204, 2.5510, 5.0], atol=1e-4)
    np.testing.assert_allclose(r.std[k, 0, 0], [0.0272, 0.0723, 0.0960], atol=1e-4)


def test_impulse_band_is_the_closed_form(lag):
    r = sysid.impulse(lag, 50, std=True)
    assert r.std[1:, 0, 0].min() > 0
    np.testing.assert_allclose(r.std[:, 0, 0], _impulse_std(r.t), rtol=1e-5, atol=1e-9)


def test_model_methods_take_std_as_the_other_families(lag):
    """``c.step(std=True)`` / ``c.impulse(std=True)`` work (they raised TypeError), on the
    default grid and on a given ``dt``, with the same numbers as ``sysid.step``."""
    for kind, exact in (("step", _step_std), ("impulse", _impulse_std)):
        r = getattr(lag, kind)(50, std=True)
        np.testing.assert_allclose(r.std[:, 0, 0], exact(r.t), rtol=1e-5, atol=1e-9)
        np.testing.assert_allclose(r.std, getattr(sysid, kind)(lag, 50, std=True).std)
        g = getattr(lag, kind)(30, dt=0.25, std=True)
        np.testing.assert_allclose(g.t, 0.25 * np.arange(30))
        np.testing.assert_allclose(g.std[:, 0, 0], exact(g.t), rtol=1e-5, atol=1e-9)
        d = getattr(lag, kind)(dt=0.5, std=True)          # the default length at that dt
        assert d.std.shape == d.y.shape


def test_default_grid_band_matches_monte_carlo(lag):
    """Against draws evaluated on the same instants: first order within sampling error."""
    r = lag.step(std=True)
    draws = lag.uncertainty.sample(4000, rng=1)
    ys = np.array([m.step(len(r.t), dt=r.t[1]).y[:, 0, 0] for m in draws])
    np.testing.assert_allclose(r.std[1:, 0, 0], ys.std(axis=0)[1:], rtol=0.08)


def test_continuous_transfer_function_through_sysid_step():
    """``sysid.step(G, std=True)`` of a continuous transfer function (its draws chose their
    own grids too) equals ``G.step(std=True)``, which already fixed the grid."""
    def tf(t):
        return sysid.TransferFunction([1.0], [1.0, t[0]])

    g = tf([1.0])
    g.uncertainty = sysid.ParameterUncertainty([1.0], [[0.01]], tf)
    r = sysid.step(g, 50, std=True)
    np.testing.assert_allclose(r.std[:, 0, 0], _step_std(r.t), rtol=1e-4, atol=1e-8)
    np.testing.assert_allclose(r.std, g.step(50, std=True).std, rtol=1e-9, atol=1e-12)


def test_a_draw_sampled_at_other_times_is_refused():
    """A model family whose response chooses its own grid and takes no ``dt=`` is refused
    with what to add, not differenced at other instants."""
    from sysid.models.protocol import TimeResponse
    from sysid.models.uncertainty import response_band

    class Drifting(sysid.ModelMixin):
        dt, ninputs, noutputs = 0.0, 1, 1
        input_names, output_names, info = ["u0"], ["y0"], {}
        n_parameters = 1

        def __init__(self, a):
            self.a = float(a)

        def simulate(self, u, x0=None):
            return np.zeros((len(u), 1))

        def freqresp(self, omega):
            return np.ones((len(omega), 1, 1), complex)

        def step(self, n_samples=None, std=False):
            t = np.linspace(0.0, 5.0 / self.a, n_samples)
            return TimeResponse("step", t, (1 - np.exp(-self.a * t))[:, None, None], self)

    m = Drifting(1.0)
    m.uncertainty = sysid.ParameterUncertainty([1.0], [[0.01]], lambda t: Drifting(t[0]))
    with pytest.raises(DataError, match="sampled at other times.*dt= keyword"):
        response_band(m, m.step(20), lambda p, n: p.step(n))


def test_discrete_band_unchanged():
    def ss(t):
        return sysid.StateSpaceModel([[0.5]], [[t[0]]], [[1.0]])

    m = ss([1.0])
    m.uncertainty = sysid.ParameterUncertainty([1.0], [[0.01]], ss)
    np.testing.assert_allclose(m.impulse(3, std=True).std[:, 0, 0], [0.0, 0.1, 0.05])
    np.testing.assert_allclose(sysid.step(m, 3, std=True).std[:, 0, 0], [0.0, 0.1, 0.15])
