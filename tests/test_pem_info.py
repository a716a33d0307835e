"""``info`` of a refined model describes the refined model: the start's noise covariances
are kept apart from it."""

from __future__ import annotations

import warnings

import numpy as np

import sysid


def test_the_starts_noise_covariances_are_not_the_refined_models():
    rng = np.random.default_rng(0)
    plant = sysid.StateSpaceModel([[0.9, 0.0], [0.0, 0.6]], [[1.0], [1.0]], [[1.0, -0.5]])
    u = rng.standard_normal(500)
    y = plant.simulate(u) + 0.2 * rng.standard_normal((500, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.ssest(sysid.IOData(u=u, y=y), 2, focus="simulation")
    assert not {"Q", "R", "S"} & set(m.info)
    assert set(m.info["start_noise"]) == {"Q", "R", "S"}
