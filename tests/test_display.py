"""Notebook displays (``_repr_html_``): well-formed HTML that holds the key numbers."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import sysid


def parse(html: str) -> ET.Element:
    """The fragment parses as XML (every tag closed, every text escaped)."""
    root = ET.fromstring(html)
    assert root.tag == "div" and root.get("class") == "sysid-repr"
    return root


def cells(root: ET.Element) -> list[str]:
    return ["".join(td.itertext()).strip() for td in root.iter() if td.tag in ("td", "th")]


def numbers(root: ET.Element) -> list[float]:
    out = []
    for c in cells(root):
        out += [float(x) for x in re.findall(r"[-+]?\d*\.?\d+(?:e[-+]?\d+)?", c)]
    return out


def close_to(values: list[float], x: float, rel: float = 1e-3) -> bool:
    return any(abs(v - x) <= rel * max(abs(x), 1e-12) for v in values)


@pytest.fixture(scope="module")
def dryer():
    return sysid.datasets.load_dryer()


def test_statespace_model_shows_its_facts_and_poles(dryer):
    m = sysid.n4sid(dryer, 4, horizon=15)
    root = parse(m._repr_html_())
    c = cells(root)
    assert "StateSpaceModel" in c and "4" in c  # family, states
    assert "heater voltage" in " ".join(c) and "air temperature" in " ".join(c)
    assert any(x.startswith("yes (largest |pole|") for x in c)
    vals = numbers(root)
    for p in m.poles():
        assert close_to(vals, abs(p))


def test_unstable_and_continuous_models_say_so():
    unstable = sysid.StateSpaceModel([[1.2]], [[1.0]], [[1.0]], dt=0.5)
    assert any(x.startswith("NO (largest |pole| 1.2") for x in cells(parse(
        unstable._repr_html_())))
    cont = sysid.ContinuousStateSpace([[-2.0, 0.0], [0.0, -0.5]], [[1.0], [1.0]],
                                      [[1.0, 1.0]])
    c = cells(parse(cont._repr_html_()))
    assert "continuous" in c and any(x.startswith("yes (largest Re(pole) -0.5") for x in c)


def test_polynomial_model_and_its_uncertainty(dryer):
    m = sysid.arx(dryer, 2, 2, 1)
    root = parse(m._repr_html_())
    assert "PolynomialModel" in cells(root) and "arx" in cells(root)
    vals = numbers(root)
    assert all(close_to(vals, abs(p)) for p in m.poles())
    unc = parse(m.uncertainty._repr_html_())
    assert len(cells(unc)) > 4


def test_frd_shows_its_range_and_a_plot(dryer):
    f = sysid.spa(dryer)
    html = f._repr_html_()
    root = parse(html)
    assert f"{f.omega[-1]:.4g}" in " ".join(cells(root))
    assert html.count("<svg") == 1 and "<polyline" in html


def test_greybox_structure_and_estimate():
    def motor(p, dt=None):
        return [[-1 / p.tau]], [[p.K / p.tau]], [[1.0]], [[0.0]]

    s = sysid.GreyBox(motor, params={"K": 2.0, "tau": sysid.param(0.5, bounds=(0.01, 10),
                                                                   unit="s")})
    root = parse(s._repr_html_())
    c = cells(root)
    assert "tau" in c and "s" in c and close_to(numbers(root), 0.5)
    assert close_to(numbers(root), 2.0)  # |pole| of -1/tau
    u = np.sign(np.sin(np.arange(400) * 0.05))
    y = sysid.GreyBox(motor, {"K": 2.0, "tau": 0.3}).model(dt=0.05).simulate(u)
    fit = sysid.greyest(sysid.IOData(u=u, y=y, dt=0.05), s, x0="zero")
    for obj in (fit, fit.parameters):
        vals = numbers(parse(obj._repr_html_()))
        assert close_to(vals, 0.3) and close_to(vals, 2.0)


def test_nonlinear_models():
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, (400, 1))
    y = np.zeros((400, 1))
    for t in range(2, 400):
        y[t] = -0.605 * y[t - 1] - 0.163 * y[t - 2] ** 2 + 0.588 * u[t - 1] - 0.24 * u[t - 2]
    m = sysid.nlarx(sysid.IOData(u, y, 1.0), 2, 2, basis=sysid.PolynomialBasis(2))
    assert "NARXModel" in cells(parse(m._repr_html_()))
    w = np.clip(u[:, 0], -0.4, 0.4)
    yh = np.zeros(400)
    for t in range(1, 400):
        yh[t] = 0.8 * yh[t - 1] + 0.5 * w[t - 1]
    h = sysid.nlhw(sysid.IOData(u[:, 0], yh, 1.0), 1, 1, 1, input_nl=sysid.Saturation(),
                   output_nl=None)
    root = parse(h._repr_html_())
    assert "HammersteinWienerModel" in cells(root) and close_to(numbers(root), 0.8, 1e-3)


def test_results_show_their_tables(dryer):
    m = sysid.n4sid(dryer, 4, horizon=15)
    cmp = sysid.compare(m, dryer)
    assert close_to(numbers(parse(cmp._repr_html_())), float(cmp.fit.mean()), 1e-3)
    res = sysid.residuals(m, dryer)
    assert close_to(numbers(parse(res._repr_html_())), float(res.ljung_box_pvalue[0]), 1e-3)
    sel = sysid.select_order(sysid.SubspaceEstimator(dryer, 15), range(1, 6))
    root = parse(sel._repr_html_())
    assert len(root.findall(".//tbody/tr")) == 5
    crit = sysid.criteria(m, dryer)
    assert close_to(numbers(parse(crit._repr_html_())), crit.bic, 1e-3)
    d = sysid.damp(m)
    assert close_to(numbers(parse(d._repr_html_())), float(d.wn_hz[0]), 1e-3)


def test_iodata_table_and_inline_plots(dryer):
    html = dryer._repr_html_()
    root = parse(html)
    c = cells(root)
    assert "heater voltage" in c and "air temperature" in c
    assert close_to(numbers(root), float(dryer.y.mean()), 1e-3)
    assert html.count("<svg") == 2 and "http" not in html.replace(
        'xmlns="http://www.w3.org/2000/svg"', "")
    assert len(html) < 40_000  # a long record is decimated, not drawn sample by sample
    big = sysid.IOData(u=np.zeros((200_000, 1)), y=np.random.default_rng(1).standard_normal(
        (200_000, 1)))
    assert len(big._repr_html_()) < 40_000


def test_text_is_escaped():
    d = sysid.IOData(u=np.zeros(10), y=np.ones(10), input_names=["a<b & c"])
    html = d._repr_html_()
    parse(html)
    assert "a&lt;b &amp; c" in html


def test_print_shows_a_results_summary_not_one_line(dryer, capsys):
    """``print(result)`` shows the text summary (every finding of ``advice``, each line of a
    ``compare``), the ``repr`` only where a result has no text summary."""
    a = sysid.advice(dryer)
    print(a)
    out = capsys.readouterr().out.strip()
    assert out == a.summary() and out != repr(a)
    assert all(f.topic in out for f in a.findings) and len(out.splitlines()) > len(a.findings)
    m = sysid.n4sid(dryer, 3)
    c = sysid.compare(dryer, m)
    assert str(c) == c.summary() != repr(c)
    table = m.damp()
    assert str(table) == repr(table)  # no text summary: the repr
