"""``model[outputs, inputs]`` / ``model.select(...)`` (MATLAB's ``sys(i, j)``): the same
family, the chosen channels' responses exactly, the uncertainty carried through, names kept,
and a clear refusal where no model of the family holds the channels alone."""

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import DataError

W = np.array([0.05, 0.3, 1.2])


@pytest.fixture(scope="module")
def record():
    rng = np.random.default_rng(4)
    true = sysid.StateSpaceModel(
        [[0.8, 0.2, 0.0], [-0.2, 0.8, 0.0], [0.0, 0.0, 0.5]],
        [[1.0, 0.0, 0.3], [0.0, 1.0, 0.0], [0.5, 0.2, 1.0]],
        [[1.0, 0.0, 0.0], [0.0, 0.5, 1.0]], dt=0.1)
    u = rng.standard_normal((800, 3))
    y = true.simulate(u) + 0.02 * rng.standard_normal((800, 2))
    return sysid.IOData(u=u + [1.0, -2.0, 0.5], y=y + [3.0, 1.0], dt=0.1,
                        input_names=["a", "b", "c"], output_names=["p", "q"])


@pytest.fixture(scope="module")
def models(record):
    d = sysid.detrend(record)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {
            "statespace": sysid.ssest(d, 3),
            "continuous": sysid.d2c(sysid.n4sid(d, 3)),
            "transfer function": sysid.tfest(d, 1),
            "process": sysid.procest(d, "P1"),
            "polynomial": sysid.arx(d, np.diag([2, 2]), np.full((2, 3), 2), np.ones((2, 3), int)),
            "identified": sysid.identify(record, max_order=3, progress=False).model,
        }


@pytest.mark.parametrize("family", ["statespace", "continuous", "transfer function",
                                    "process", "polynomial", "identified"])
def test_a_subsystem_is_the_chosen_channels_of_the_model(models, family):
    m = models[family]
    for key, iy, iu in [((1, slice(None)), [1], [0, 1, 2]), (("p", ["c", "a"]), [0], [2, 0]),
                        ((slice(None, None, -1), 1), [1, 0], [1])]:
        s = m[key]
        assert type(s) is type(m)
        assert s.output_names == [m.output_names[i] for i in iy]
        assert s.input_names == [m.input_names[j] for j in iu]
        np.testing.assert_allclose(s.freqresp(W), m.freqresp(W)[:, iy][:, :, iu],
                                   rtol=1e-10, atol=1e-12)
        assert s.info["subsystem"] == {"outputs": s.output_names, "inputs": s.input_names}
    same = m.select(outputs=["q"], inputs=[1, 2])
    np.testing.assert_allclose(same.freqresp(W), m[1, 1:].freqresp(W))


def test_the_identified_model_keeps_the_operating_point_of_its_channels(models, record):
    m = models["identified"]
    s = m["q", ["b"]]
    u = record.u.copy()
    u[:, [0, 2]] = m.u_offset[[0, 2]]  # the inputs left out stay at their operating point
    np.testing.assert_allclose(s.simulate(u[:, [1]]), m.simulate(u)[:, [1]], atol=1e-9)
    np.testing.assert_allclose(s.predict(record.select(inputs="b", outputs="q"), horizon=2),
                               s.predict(record.u[:, [1]], record.y[:, [1]], 2))


def test_the_uncertainty_is_the_estimate_s_seen_through_the_selection(models):
    m = models["statespace"]
    g, sd = m.freqresp(W, std=True)
    gs, sds = m[0, 1:].freqresp(W, std=True)
    np.testing.assert_allclose(gs, g[:, :1, 1:])
    np.testing.assert_allclose(sds.real, sd.real[:, :1, 1:], rtol=1e-6)
    np.testing.assert_allclose(sds.imag, sd.imag[:, :1, 1:], rtol=1e-6)
    # the poles are the whole model's (a subsystem is not reduced), with their std
    np.testing.assert_allclose(m[0, 0].poles(std=True)[1], m.poles(std=True)[1], rtol=1e-6)


def test_the_innovations_of_the_outputs_kept(models):
    m = models["statespace"]
    s = m[1, :]
    np.testing.assert_array_equal(s.K, m.K[:, [1]])
    np.testing.assert_array_equal(s.noise_cov, m.noise_cov[1:, 1:])


def test_refusals_name_the_fix(models, record):
    coupled = sysid.arx(sysid.detrend(record), [[2, 1], [1, 2]], np.full((2, 3), 2),
                        np.ones((2, 3), int))
    with pytest.raises(DataError, match=r"couples its outputs.*to_statespace\(\)\.select"):
        coupled[0, :]
    np.testing.assert_allclose(coupled.to_statespace()[0, :].freqresp(W),
                               coupled.freqresp(W)[:, :1], rtol=1e-9, atol=1e-12)
    d1 = sysid.detrend(record).select(inputs=[0], outputs=[0])
    with pytest.raises(DataError, match=r"NARXModel has no channel selection.*data\.select"):
        sysid.nlarx(d1, [1, 1, 1])[0, 0]
    m = models["statespace"]
    with pytest.raises(DataError, match=r"two selections, \[outputs, inputs\]"):
        m[0]
    with pytest.raises(DataError, match=r"no input named 'd'; the inputs are \['a', 'b', 'c'\]"):
        m[:, "d"]
    with pytest.raises(DataError, match="selection .* is empty"):
        m[[], :]
    with pytest.raises(DataError, match="output 5 does not exist"):
        m.select(outputs=5)
