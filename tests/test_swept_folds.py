"""Held-out blocks of a swept input (a chirp): interleaved pieces, each in the band the rest
of the record excites, so that the automatic choices compare interpolations, not guesses
outside the data."""

import warnings

import numpy as np
import pytest

import sysid
from sysid.data.excitation import _power
from sysid.validation.crossval import fold_count, folds, record_folds
from sysid.validation.swept import PIECES, outside_share


def _chirp(n=9000):
    t = np.arange(n)
    return np.sin(2 * np.pi * (0.002 + 0.2 * t / n) * t)


def _four_modes(seed):
    # four lightly damped modes across the chirp's band, output noise 10 % of the output
    rng = np.random.default_rng(seed)
    A = np.zeros((8, 8))
    for i, (f, r) in enumerate([(0.03, 0.98), (0.08, 0.96), (0.13, 0.95), (0.19, 0.9)]):
        th = 2 * np.pi * f
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = r * np.array([[np.cos(th), -np.sin(th)],
                                                            [np.sin(th), np.cos(th)]])
    m = sysid.StateSpaceModel(A, np.tile([[1.0], [0.0]], (4, 1)),
                              0.3 * rng.standard_normal((1, 8)), np.zeros((1, 1)), dt=1.0)
    u = _chirp()
    y0 = m.simulate(u)
    s = 0.1 * np.std(y0)
    return (sysid.IOData(u=u, y=y0 + s * rng.standard_normal(y0.shape)),
            sysid.IOData(u=u, y=y0 + s * rng.standard_normal(y0.shape)), m)


def _widest_gap(fit, held, segment=256):
    """The widest run of frequency bins the held-out input excites and the fitted part does
    not (power below 1e-3 of its peak), as a share of the bins the whole record excites."""
    def spectrum(data):
        return sum(_power(np.asarray(u, float), segment)[:segment // 2 + 1, 0] * u.shape[0]
                   for u, _ in data.experiments if u.shape[0] >= segment)

    pf, ph = spectrum(fit), spectrum(held)
    own = (ph > 1e-3 * ph.max()) & (pf < 1e-3 * pf.max())
    band = (pf + ph) > 1e-3 * (pf + ph).max()
    edges = np.diff(np.r_[0, own.astype(int), 0])
    runs = np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)
    return (runs.max() if runs.size else 0) / band.sum()


def test_a_chirps_held_out_pieces_sit_in_narrow_gaps_of_the_fitted_band():
    d = sysid.IOData(u=_chirp(), y=_chirp())
    contiguous = folds(d, fold_count(d))
    seg = 1 << int(np.floor(np.log2(min(min(h.lengths) for _, h in contiguous))))
    assert min(outside_share(f, h, seg) for f, h in contiguous) > 0.8
    # a contiguous block is a fifth of the sweep the fit never saw
    assert min(_widest_gap(f, h) for f, h in contiguous) > 0.12
    pairs = record_folds(d)
    assert len(pairs) == len(contiguous)
    assert all(h.n_experiments == PIECES for _, h in pairs)
    # every sample held out once
    held = np.sort(np.concatenate([e[0][:, 0] for _, h in pairs for e in h.experiments]))
    assert np.array_equal(held, np.sort(d.u[:, 0]))
    # an interleaved piece: a twentieth, between fitted pieces on both sides
    assert max(_widest_gap(f, h) for f, h in pairs) < 0.05


@pytest.mark.parametrize("kind", ["white", "multisine", "steps", "prbs"])
def test_other_inputs_keep_their_contiguous_blocks(kind):
    rng = np.random.default_rng(0)
    u = {"white": rng.standard_normal(6000),
         "multisine": sysid.multisine(1000, band=(0, 0.3), phases="random", seed=1,
                                      periods=6)[:, 0],
         "steps": np.repeat(rng.standard_normal(12), 500),
         "prbs": np.sign(rng.standard_normal(600)).repeat(10)}[kind]
    d = sysid.IOData(u=u, y=np.convolve(u, [0.5, 0.3, 0.1])[:u.size])
    assert all(h.n_experiments == 1 for _, h in record_folds(d))


@pytest.mark.parametrize("seed", [1, 2])
def test_automatic_order_on_a_chirp_reaches_the_noise_limit(seed):
    # contiguous blocks, each a band the rest never excited, chose orders 9 and 6 here
    # (validation fits 83.7 and 72.9 %); the true system's fit (the noise's limit) is 90 %
    d, v, truth = _four_modes(seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.n4sid(d)
    assert sysid.compare(v, m).fit[0, 0] > sysid.compare(v, truth).fit[0, 0] - 1.0


def test_identify_says_when_it_interleaves():
    d, _, _ = _four_modes(0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = sysid.identify(d, progress=False, refine=False)
    assert "interleaved pieces" in r.checks["held_out_design"]
    rng = np.random.default_rng(0)
    u = rng.standard_normal(3000)
    w = sysid.IOData(u=u, y=np.convolve(u, [0.5, 0.3])[:3000])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert "held_out_design" not in sysid.identify(w, progress=False, refine=False).checks
