"""docs/nlss.md runs and prints the numbers it shows."""

from _guides import assert_prints_shown, guide_text, run_guide


def test_nlss_guide(capsys):
    ns = run_guide("nlss.md")
    assert_prints_shown(guide_text("nlss.md"), capsys.readouterr().out, atol=2e-3, rtol=0.1)
    # what the guide claims in words
    assert ns["pn"].info["fit"]["cost"][-1] < ns["pn"].info["fit"]["cost"][0]
