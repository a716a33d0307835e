"""The spread that lets identify's final choice weigh candidates the held-out blocks cannot
tell apart leaves out the block both held-out scores leave out as their worst."""

import numpy as np

from sysid.identify.board import Board, held_out_score


def _board(shares):
    board = Board.__new__(Board)
    board.shares = np.asarray(shares, float)
    board.folds = [None] * len(shares)
    return board


def _row(fits, feedthrough=False):
    return {"family": "n4sid", "order": 3, "criterion": "subspace", "stable": True,
            "held_out_fit": held_out_score(fits), "fold_fits": fits, "focus": None,
            "feedthrough": feedthrough}


def test_a_block_both_fit_worst_does_not_widen_the_tie():
    """Three held-out blocks, the last one quiet (4 % of the output variation) and both
    candidates drifting there by hundreds of fit points (a helicopter resting on its stop
    while a ramp drives its motor): the trimmed scores leave that block out and put the two
    82 points apart (8.3 and -74.1 %), yet counted in their spread it made that spread 255
    points, so the worse candidate, with fewer parameters, 'tied' with the best and the
    whole-record BIC chose it. Without that block the spread is a few tens of points and the
    worse candidate stays out."""
    board = _board([0.837, 0.12, 0.044])
    best = _row([8.3, 12.5, -608.1], feedthrough=True)
    worse = _row([14.4, -74.1, -1850.5])
    board.rows = [best, worse]
    gap = best["held_out_fit"] - worse["held_out_fit"]
    assert gap > 80
    assert board.parameters(worse) < board.parameters(best)  # the spread may apply
    assert board.paired_se(worse, best) < gap / 2
    assert not board.is_near(worse, best, paired=True)


def test_the_other_blocks_still_count():
    """A block where both fit best counts (a fit is at most 100 %: it cannot widen the
    spread without bound; the flutter record, reversed, holds 35 % of its variation in such
    a block), and so does a block where only one of them fits worst."""
    w = np.array([0.623, 0.35, 0.027, 0.0])
    board = _board(w)
    a = _row([56.3, 61.8, 43.3, -460.1])  # both best in block 1, both worst in block 3
    b = _row([57.4, 60.4, 40.7, -341.7])

    def spread(d, w):
        w = w / np.sum(w)
        m = np.sum(w * d)
        return np.sqrt(np.sum(w * (d - m) ** 2) / max(1 / np.sum(w ** 2) - 1, 1))
    fa, fb = np.array(a["fold_fits"]), np.array(b["fold_fits"])
    assert np.isclose(board.paired_se(a, b), spread((fa - fb)[:3], w[:3]))
    c = _row([30.0, 61.0, 45.0, 50.0])  # its worst is block 0, b's block 3: all count
    fc = np.array(c["fold_fits"])
    assert np.isclose(board.paired_se(c, b), spread(fc - fb, w))
