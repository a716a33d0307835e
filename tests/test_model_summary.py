"""Every model has a text ``summary()`` and a ``to_pandas()`` (the house's result
conventions): ``StateSpaceModel``, ``PolynomialModel`` and identify's ``IdentifiedModel``
had neither (AttributeError)."""

from __future__ import annotations

import warnings

import numpy as np

import sysid


def quiet(fn, *a, **k):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*a, **k)


def test_a_refined_model_says_what_it_is_how_it_was_found_and_how_sure():
    d = sysid.datasets.load_dryer()[:500]
    m = quiet(sysid.ssest, d, 2)
    text = m.summary()
    assert text.startswith(repr(m))
    assert f"iterations {m.info['pem']['iterations']}" in text
    assert "poles:" in text and "parameters:" in text and "std" in text
    df = m.to_pandas()
    assert len(df) == 2 and "std damping" in df.columns
    np.testing.assert_allclose(np.sort(np.abs(df["pole"])), np.sort(np.abs(m.poles())))


def test_polynomial_and_identified_models_have_them_too():
    d = sysid.datasets.load_dryer()[:500]
    p = quiet(sysid.oe, d, 2, 2, 3)
    assert "search: iterations" in p.summary() and "poles:" in p.summary()
    assert len(quiet(p.to_pandas)) == 2
    r = quiet(sysid.identify, d, progress=False)
    assert r.model.summary().startswith("IdentifiedModel around u = [")
    assert len(r.model.to_pandas()) == r.model.nstates
    plain = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1)
    assert "search:" not in plain.summary() and "\nparameters:" not in plain.summary()
