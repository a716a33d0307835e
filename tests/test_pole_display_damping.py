"""A pole at ``z = 0`` (a delay state: infinitely fast) has damping 1 in every table, by one
rule (:mod:`sysid.models.pole_map`): ``sysid.damp``, ``to_pandas()``, ``summary()`` and the
notebook display.

Before: ``summary()`` printed ``0+0j 0.0000 inf nan`` and the HTML table ``n/a`` for its
damping (``-(-inf) / inf``), while ``damp()`` and ``to_pandas()`` gave 1.0.
"""

import re

import numpy as np

import sysid
from sysid._display import pole_rows
from sysid.models.pole_map import continuous_equivalent, damping_ratio


def delayed():
    return sysid.StateSpaceModel([[0, 0], [1, 0.5]], [[1], [0]], [[0, 1]], dt=0.1)


def test_summary_shows_damping_one_for_the_delay():
    text = delayed().summary()
    row = next(line for line in text.splitlines() if line.strip().startswith("0+0j"))
    assert row.split()[-2:] == ["inf", "1.0000"], row
    assert "nan" not in text


def test_html_display_shows_damping_one_for_the_delay():
    html = delayed()._repr_html_()
    rows = re.findall(r"<tr><td>0\+0j</td>(.*?)</tr>", html)
    assert rows and rows[0].endswith("<td>1</td>"), rows


def test_every_table_agrees():
    m = delayed()
    rows = pole_rows(m.poles(), m.dt)
    table = sysid.damp(m)
    assert sorted(r[3] for r in rows) == sorted(table.zeta.tolist()) == [1.0, 1.0]
    assert m.to_pandas()["damping"].tolist() == [1.0, 1.0]
    at_zero = [r for r in rows if r[1] == 0.0][0]
    assert np.isinf(at_zero[2]) and at_zero[3] == 1.0


def test_the_shared_rule():
    s = continuous_equivalent(np.array([0.5, 0.0, 1.0, -0.5, 0.9j]), 0.1)
    assert s[1] == -np.inf and s[2] == 0.0
    np.testing.assert_allclose(s[0], np.log(0.5) / 0.1)
    zeta = damping_ratio(s)
    np.testing.assert_allclose(zeta[:3], [1.0, 1.0, -1.0])
    np.testing.assert_allclose(zeta[3:], -s[3:].real / np.abs(s[3:]))
    # continuous poles are their own equivalent; an integrator's damping is -1, as damp()
    c = continuous_equivalent(np.array([-1.0 + 2.0j, 0.0]), 0.0)
    np.testing.assert_allclose(damping_ratio(c), [1 / np.sqrt(5), -1.0])
    table = sysid.damp(sysid.ContinuousStateSpace(np.diag([-1.0, 0.0]), [[1.0], [1.0]],
                                                  [[1.0, 1.0]]))
    assert sorted(table.zeta) == sorted(damping_ratio(np.array([-1.0, 0.0]))) == [-1.0, 1.0]


def test_html_display_shows_the_infinite_frequency_as_the_summary():
    # before: the notebook table printed "n/a" where summary() prints "inf"
    html = delayed()._repr_html_()
    row = re.findall(r"<tr><td>0\+0j</td>(.*?)</tr>", html)[0]
    assert re.findall(r"<td>(.*?)</td>", row) == ["0", "inf", "1"], row
    assert "n/a" not in html
