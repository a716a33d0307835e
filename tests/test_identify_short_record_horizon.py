"""identify on a short record: the horizon allows more than order 1."""

import warnings

import numpy as np

import sysid


def test_a_short_record_is_not_held_to_order_one():
    # 100 samples of one input and output gave horizon 2 (ten Hankel columns a row), so
    # every candidate had order 1: a two-state plant validated at 35 % where ssest(data, 2)
    # gives 96 %. Up to horizon 4 while the data matrix keeps three columns a row.
    m = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.0]], [[1.0, 0.5]])
    for seed in range(2):
        rng = np.random.default_rng(seed)
        u = rng.standard_normal(1100)
        y = m.simulate(u) + 0.1 * rng.standard_normal((1100, 1))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = sysid.identify(sysid.IOData(u=u[:100], y=y[:100]),
                               validation=sysid.IOData(u=u[100:], y=y[100:]), progress=False)
        assert r.model.nstates >= 2
        assert float(np.ravel(r.validation_fit)[0]) > 85.0
