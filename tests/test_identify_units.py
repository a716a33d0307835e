"""``identify`` gives the same model whatever the units of the inputs and outputs: the
subspace candidates compute on channels of unit root mean square, the refinements search on
channels of unit root mean square (:mod:`sysid.pem.units`), and the held-out scorer and
``compare`` fit the initial state with each output weighed by its spread. Before the
subspace scaling, one output in units 1000 times smaller changed the candidates and so, on
records like DaISy's CD player arm, the choice; before the search went unit-free, an input
100 times smaller changed a held-out fit from 72.9 % to 73.0 % here. Orders are capped at 8
(the plant has 4 states): fits far above the plant's order are unit-free only up to their
conditioning (a CVA fit of order 17 at horizon 18: 0.016 points on one held-out block for
outputs in units 1000 apart; the refinement of an order-9 start: 0.24 points), and the
board's early stop of a refinement below the best on most blocks can turn that into another
choice (open: the searches' paths through an over-parameterised model's flat directions)."""

from __future__ import annotations

import warnings

import numpy as np
from scipy.signal import lfilter

import sysid

A = np.array([[0.9, 0.25, 0, 0], [-0.25, 0.9, 0, 0], [0, 0, 0.6, 0], [0, 0, 0, -0.4]])
B = np.array([[1.0, 0.0], [0.0, 0.5], [0.7, -0.3], [0.2, 1.0]])
C = np.array([[1.0, 0.0, 0.5, 0.0], [0.0, 0.8, 0.0, 1.0]])


def test_identify_does_not_depend_on_the_channels_units():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((1500, 2))
    v = lfilter([1.0], [1.0, -0.9], rng.standard_normal((1500, 2)), axis=0)
    y = sysid.StateSpaceModel(A, B, C).simulate(u) + 0.3 * v
    out = []
    one = np.ones(2)
    for ku, ky in ((one, one), (one, np.array([1.0, 1e3])), (one, np.array([1e-2, 1.0])),
                   (np.array([1e-2, 1.0]), one), (np.array([1e3, 1e-4]), np.array([1e4, 1.0]))):
        d = sysid.IOData(u=u * ku, y=y * ky)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = sysid.identify(d, max_order=8, progress=False)
            fit = sysid.compare(r.model, d).fit.ravel()
        out.append((r.choice, fit, r.model.poles()))
    for other in out[1:]:
        assert other[0] == out[0][0]
        np.testing.assert_allclose(other[1], out[0][1], atol=1e-6)
        np.testing.assert_allclose(np.sort_complex(other[2]), np.sort_complex(out[0][2]),
                                   atol=1e-7)
