"""The prediction-error search converges on an unstable plant (issue 26).

An unstable plant's outputs grow over the record, and the predictor's parameters then differ
in effect by many orders of magnitude. The search moves in the complement of the similarity
orbit (data-driven local coordinates); a basis of it orthonormal in the raw parameters mixes
parameters of very different effect, the damped steps along it crawl, and the search stopped
at its iteration cap on about half of such records, short of the minimum by several residual
variances. Once its steps crawl while the parameters' effects span orders of magnitude, the
search changes to a basis orthonormal in its own (Marquardt) metric, and converges.
"""

from __future__ import annotations

import warnings

import numpy as np

import sysid


def unstable_record(seed: int) -> sysid.IOData:
    """A third-order plant with a real pole at 1.02 and a stable pair, white input, output
    noise 30 dB below the output's first 200 samples, 800 samples."""
    rng = np.random.default_rng(seed)
    r, th = rng.uniform(0.5, 0.9), rng.uniform(0.3, 2.0)
    A = np.zeros((3, 3))
    A[0, 0] = 1.02
    A[1:, 1:] = r * np.array([[np.cos(th), np.sin(th)], [-np.sin(th), np.cos(th)]])
    B, C = rng.standard_normal((3, 1)), rng.standard_normal((1, 3))
    true = sysid.StateSpaceModel(A, B, C, np.zeros((1, 1)), dt=1.0)
    u = rng.standard_normal((800, 1))
    y0 = true.simulate(u)
    y = y0 + 10 ** (-30 / 20) * y0[:200].std() * rng.standard_normal(y0.shape)
    return sysid.IOData(u=u, y=y, dt=1.0)


def test_prediction_search_on_an_unstable_plant_converges():
    gaps, capped = [], 0
    for seed in range(6):
        data = unstable_record(seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            start = sysid.ssest(data, 3, max_iter=0)
            fit = sysid.pem(data, start)
            # references: long searches in both coordinates (the full parameterisation does
            # not depend on the basis)
            refs = [sysid.pem(data, start, max_iter=500, tol=1e-12),
                    sysid.pem(data, start, max_iter=500, tol=1e-12, local_coordinates=False)]
        info = fit.info["pem"]
        # the criterion det(Lambda) in log-likelihood units (N/2 log): within a tenth of the
        # best reference, unless the search ended on the admissible set's edge (a predictor
        # pole on the unit circle: the data favour an unstable predictor; searches in
        # different coordinates stop at different points of that edge)
        best = min(m.info["pem"]["cost"][-1] for m in refs)
        gap = 0.5 * data.n_samples * np.log(info["cost"][-1] / best)
        edge = np.abs(np.linalg.eigvals(fit.A - fit.K @ fit.C)).max() > 0.999
        stopped = info["stop"] == "maximum iterations" and not edge
        capped += stopped
        gaps.append(0.0 if edge or stopped else gap)
    # before: five of the six stopped at the cap, up to 11 log-likelihood units short; now
    # at most one does (a search slowed by the curvature of its cost, not by its basis), and
    # every other ends within a tenth of a unit of the best reference
    assert max(gaps) < 0.1 and capped <= 1, (gaps, capped)
