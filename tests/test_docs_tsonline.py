"""The guides of issue 27's time series, modal analysis and online estimators run and print
the numbers they show."""

from __future__ import annotations

import pytest
from _guides import assert_prints_shown, guide_text, run_guide

GUIDES = ["online.md", "timeseries.md", "oma.md"]


@pytest.mark.parametrize("guide", GUIDES)
def test_guide_runs_and_prints_what_it_shows(guide, capsys):
    run_guide(guide)
    assert_prints_shown(guide_text(guide), capsys.readouterr().out, atol=1e-3)
