"""selstruc's "aic" and "mdl" are MATLAB's: the least ``V (1 + 2 d / N)`` (MATLAB's ``log(V (1
+ 2 d / N))``, the same choice) and the least ``V (1 + d log N / N)``; "bic" is ``log V + d log
N / N``. ``mdl`` was ``log V + d log N / N`` and ``aic`` ``log V + 2 d / N``, which choose
differently where ``d / N`` is not small. An empty table is refused by name."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

import sysid
from sysid.errors import DataError

# two structures on N = 20 samples: a small one and a large one with a much lower loss
N = 20


def _table(v_large):
    return np.array([[1, 1, 1, 1.0, 2], [5, 5, 1, v_large, 10]])


def test_mdl_is_matlabs_v_times_one_plus_d_log_n_over_n():
    """V(1 + d log N / N): 1.30 for the small structure, 0.874 for the large one (MATLAB
    picks it); log V + d log N / N (0.300 and 0.448) picked the small one."""
    t = _table(0.35)
    score = t[:, 3] * (1 + t[:, 4] * np.log(N) / N)
    np.testing.assert_allclose(score, [1.2996, 0.8743], atol=1e-4)
    assert sysid.selstruc(t, "mdl", N) == (5, 5, 1)
    assert sysid.selstruc(t, "bic", N) == (1, 1, 1)  # log V + d log N / N: 0.300 < 0.448


def test_aic_is_matlabs_v_times_one_plus_2d_over_n():
    """V(1 + 2d/N): 1.2 and 1.0, the large structure; log V + 2d/N (0.2 and 0.307) picked
    the small one."""
    t = _table(0.5)
    assert sysid.selstruc(t, "aic", N) == (5, 5, 1)
    # MATLAB's log(V (1 + 2 d / N)) orders the rows alike
    v = np.log(t[:, 3] * (1 + 2 * t[:, 4] / N))
    assert np.argmin(v) == 1
    # a numeric c = 2 is the same criterion
    assert sysid.selstruc(t, 2, N) == sysid.selstruc(t, "aic", N)


def test_on_an_arxstruc_table():
    rng = np.random.default_rng(0)
    u = rng.standard_normal(400)
    y = signal.lfilter([0, 1.0, 0.5], [1, -0.5], u) + 0.3 * rng.standard_normal(400)
    table = sysid.arxstruc(sysid.IOData(u[:, None], y[:, None], 1.0), [1, 2, 3], [1, 2, 3],
                           [1])
    n = table.n_samples
    for name, score in (("aic", table[:, 3] * (1 + 2 * table[:, 4] / n)),
                        ("mdl", table[:, 3] * (1 + table[:, 4] * np.log(n) / n))):
        want = tuple(int(v) for v in table[np.argmin(score), :3])
        assert sysid.selstruc(table, name) == want


def test_an_empty_table_is_refused():
    """An empty table raised numpy's "attempt to get argmin of an empty sequence"."""
    for criterion in ("aic", "mdl", 0, 2.0):
        with pytest.raises(DataError, match="table has no rows"):
            sysid.selstruc(np.zeros((0, 5)), criterion, 100)
