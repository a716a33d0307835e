"""The fit % is dimensionless: the same model on the same record, one output in other units,
gets the same fits from ``compare`` (its fitted initial state included) and from the
held-out scorer of ``identify``."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.validation.crossval import simulation_fit


def _record():
    rng = np.random.default_rng(3)
    plant = sysid.StateSpaceModel([[0.9, 0.2, 0.0], [-0.2, 0.9, 0.0], [0.0, 0.0, 0.7]],
                                  [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]],
                                  [[1.0, 0.5, 0.0], [0.0, 1.0, 1.0]])
    u = rng.standard_normal((400, 2))
    y = plant.simulate(u, x0=[3.0, -2.0, 1.0]) + 0.3 * rng.standard_normal((400, 2))
    # a model that is not the plant (its initial state trades one output's error for the
    # other's), as every estimate is
    model = sysid.StateSpaceModel(plant.A * 0.97, plant.B, plant.C * 1.05)
    return model, u, y


@pytest.mark.parametrize("horizon", [None, 5])
def test_compare_is_the_same_in_any_units(horizon):
    model, u, y = _record()
    fits = []
    for s in (1.0, 1000.0):
        S = np.diag([s, 1.0])
        m = sysid.StateSpaceModel(model.A, model.B, S @ model.C, S @ model.D,
                                  K=np.zeros((3, 2)) if horizon else None)
        fits.append(sysid.compare(m, sysid.IOData(u=u, y=y @ S), horizon=horizon).fit)
    np.testing.assert_allclose(fits[0], fits[1], atol=1e-6)


def test_the_held_out_score_is_the_same_in_any_units():
    model, u, y = _record()
    fits = []
    for s in (1.0, 1000.0):
        S = np.diag([s, 1.0])
        m = sysid.StateSpaceModel(model.A, model.B, S @ model.C, S @ model.D)
        fits.append(simulation_fit(m, sysid.IOData(u=u, y=y @ S)))
    assert fits[0] == pytest.approx(fits[1], abs=1e-6)
