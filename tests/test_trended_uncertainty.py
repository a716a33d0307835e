"""A :class:`sysid.models.trended.TrendedModel` (a model fitted on a detrended record, with
its trend) carries the inner model's parameter uncertainty: ``dcgain(std=True)``,
``sysid.damp(model, std=True)``, ``to_pandas()`` and ``summary()`` read it, as
``poles(std=True)``, ``freqresp(std=True)`` and ``step(std=True)`` already did.

Before: ``dcgain(std=True)`` and ``damp(std=True)`` raised "this model carries no parameter
uncertainty", and ``to_pandas()``/``summary()`` silently left out the std columns and the
parameter table, although ``m.model.dcgain(std=True)`` gave (5.053, 0.0217).
"""

import numpy as np
import pytest

import sysid


@pytest.fixture(scope="module")
def pair():
    rng = np.random.default_rng(0)
    true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=1.0)
    du = rng.standard_normal(600)
    raw = sysid.IOData(u=20.0 + du, y=50.0 + true.simulate(du)[:, 0]
                       + 0.05 * rng.standard_normal(600), dt=1.0)
    d, tr = sysid.detrend(raw, "mean", return_trend=True)
    inner = sysid.n4sid(d, 1)
    return tr.attach(inner), inner


def test_uncertainty_is_the_inner_models(pair):
    m, inner = pair
    assert inner.uncertainty is not None
    assert m.uncertainty is inner.uncertainty


def test_dcgain_and_damp_with_std(pair):
    m, inner = pair
    g, sd = m.dcgain(std=True)
    g0, sd0 = inner.dcgain(std=True)
    np.testing.assert_allclose(g, g0)
    np.testing.assert_allclose(sd, sd0)
    assert sd[0, 0] > 0
    np.testing.assert_allclose(m.dcgain(), inner.dcgain())
    t, t0 = sysid.damp(m, std=True), sysid.damp(inner, std=True)
    np.testing.assert_allclose(t.wn_std, t0.wn_std)
    assert np.all(t.wn_std > 0)


def test_tables_show_the_std(pair):
    m, inner = pair
    df = m.to_pandas()
    assert "std damping" in df.columns
    np.testing.assert_allclose(df["std wn [Hz]"], inner.to_pandas()["std wn [Hz]"])
    text = m.summary()
    assert "\nparameters:" in text and "ParameterUncertainty(" in text
    assert "uncertainty" in m._repr_html_()


def test_saved_and_loaded_with_it(pair, tmp_path):
    m, inner = pair
    m.save(tmp_path / "m.json")
    back = sysid.load_model(tmp_path / "m.json")
    assert back.uncertainty is not None
    np.testing.assert_allclose(back.dcgain(std=True)[1], m.dcgain(std=True)[1], rtol=1e-6)


def test_without_uncertainty_the_error_is_the_usual_one():
    raw = sysid.IOData(u=[21.0, 19.0, 20.0, 20.0], y=[50.0, 51.0, 49.0, 50.0])
    d, tr = sysid.detrend(raw, "mean", return_trend=True)
    m = tr.attach(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]))
    assert m.uncertainty is None
    with pytest.raises(sysid.DataError, match="carries no parameter uncertainty"):
        m.dcgain(std=True)
    assert "std damping" not in m.to_pandas().columns
