"""The report page in a real headless browser (Chromium from the distribution, driven by
Selenium): it loads without console errors, every chart renders, the summary states the
chosen model, a chart zooms; a screenshot is kept in ``test-artifacts/``.

Skipped, with the reason, only where no Chromium/chromedriver or no selenium is installed
(``.ci/run`` installs them on Debian).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

import sysid
from sysid import _sysid

pytestmark = pytest.mark.skipif(not hasattr(_sysid, "Subspace"),
                                reason="the subspace engine is not in this build yet")
webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed "
                                "(make build installs it into .venv)")

ARTIFACTS = Path(__file__).resolve().parents[1] / "test-artifacts"


def _browser() -> tuple[str, str]:
    chrome = next((p for p in (shutil.which(n) for n in (
        "chromium", "chromium-browser", "google-chrome")) if p), None)
    driver = shutil.which("chromedriver")
    if not chrome or not driver:
        pytest.skip("no Chromium and chromedriver on PATH: on Debian `apt-get install "
                    "chromium chromium-driver` (.ci/run does this)")
    return chrome, driver


@pytest.fixture(scope="module")
def browser():
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    chrome, driver = _browser()
    opts = Options()
    opts.binary_location = chrome
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
              "--window-size=1200,1800", "--disable-extensions", "--no-first-run"):
        opts.add_argument(a)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    drv = webdriver.Chrome(service=Service(executable_path=driver), options=opts)
    drv.set_page_load_timeout(60)
    yield drv
    drv.quit()


@pytest.fixture(scope="module")
def dryer_report(tmp_path_factory):
    """The report of the bundled dryer record, as `sysid demo` writes it."""
    from sysid.cli import identify

    d = sysid.datasets.load_dryer()
    kw = {"dt": d.dt, "input_names": d.input_names, "output_names": d.output_names}
    est = sysid.IOData(u=d.u[:500], y=d.y[:500], **kw)
    val = sysid.IOData(u=d.u[500:], y=d.y[500:], **kw)
    root = tmp_path_factory.mktemp("report")
    out = identify(est, val, horizon=15, report=root, uncertainty="bootstrap", n_boot=30)
    return root / "index.html", out


def _severe(drv) -> list[str]:
    return [e["message"] for e in drv.get_log("browser") if e["level"] == "SEVERE"]


def test_report_renders_in_a_browser(browser, dryer_report):
    from selenium.webdriver.common.by import By

    page, out = dryer_report
    browser.get(page.as_uri())
    body = browser.find_element(By.TAG_NAME, "body")
    assert body.get_attribute("data-charts") == "done"
    assert _severe(browser) == []
    charts = browser.find_elements(By.CSS_SELECTOR, "div.sysid-chart")
    assert len(charts) >= 10
    for c in charts:  # every chart drew at least one line, band or marker set
        drawn = c.get_attribute("data-rendered")
        assert drawn is not None and drawn != "error" and int(drawn) >= 1, \
            c.get_attribute("data-spec")
        assert len(c.find_elements(By.CSS_SELECTOR, "path.ln, circle.mk, path.mk, "
                                                    "polygon.band")) >= 1
    chosen = browser.find_element(By.ID, "chosen-model").text
    n = out["model"].nstates
    assert f"StateSpaceModel of order {n}" in chosen
    summary = browser.find_element(By.ID, "summary").text
    assert "stable" in summary and "Warnings" in summary
    ARTIFACTS.mkdir(exist_ok=True)
    assert browser.save_screenshot(str(ARTIFACTS / "report_dryer.png"))


def test_charts_zoom_and_reset(browser, dryer_report):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    page, _ = dryer_report
    browser.get(page.as_uri())
    chart = browser.find_element(By.CSS_SELECTOR, "#fit div.sysid-chart")
    before = chart.get_attribute("data-view")
    svg = chart.find_element(By.TAG_NAME, "svg")
    browser.execute_script("arguments[0].scrollIntoView()", svg)
    w = svg.size["width"]
    (ActionChains(browser).move_to_element_with_offset(svg, int(-0.2 * w), 0).click_and_hold()
     .move_by_offset(int(0.25 * w), 10).release().perform())
    zoomed = chart.get_attribute("data-view")
    x0, x1 = (float(v) for v in before.split(",")[:2])
    z0, z1 = (float(v) for v in zoomed.split(",")[:2])
    assert z1 - z0 < 0.5 * (x1 - x0)  # the time axis zoomed in
    ActionChains(browser).double_click(svg).perform()
    assert chart.get_attribute("data-view") == before
    assert _severe(browser) == []


def test_warnings_of_the_run_are_in_the_page(tmp_path):
    import warnings

    m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], dt=0.1)
    import numpy as np

    u, e = np.random.default_rng(0).standard_normal((2, 300, 1))
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        warnings.warn("the input excites 2 frequencies", sysid.ExcitationWarning, stacklevel=1)
    files = sysid.report(m, (u, m.simulate(u) + 0.1 * e), tmp_path, warnings=w)
    text = files["html"].read_text()
    assert "ExcitationWarning" in text and "the input excites 2 frequencies" in text
    assert "What to do" in text and "sysid.check_excitation" in text
    assert "http://" not in text.replace('xmlns="http://www.w3.org/2000/svg"', "").replace(
        '"http://www.w3.org/2000/svg"', "")
