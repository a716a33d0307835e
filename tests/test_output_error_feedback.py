"""The output-error fits warn of feedback (issue 26, honest diagnostics): one shared check
(:mod:`sysid.validation.output_error`), said once, in each estimator's words; identify runs its
own check and neither repeats it per candidate nor leaks the candidates' warnings."""

import warnings

import numpy as np
import pytest

import sysid
from sysid._parallel import ordered
from sysid.validation import output_error
from sysid.validation.output_error import _CHECKED, feedback_checked

DT = 0.1


def _loop(n=2000, seed=0, kind="p", noise=0.5):
    """A first-order plant under a proportional (``"p"``) or PI (``"pi"``) controller acting
    on the last measured output ``y(t-1)``, white output noise, a white reference."""
    rng = np.random.default_rng(seed)
    r, e = rng.standard_normal(n), noise * rng.standard_normal(n)
    u, y = np.zeros(n), np.zeros(n)
    x = integ = 0.0
    for t in range(n):
        y[t] = x + e[t]
        if t:
            integ += r[t] - y[t - 1]
            u[t] = (r[t] - 0.8 * y[t - 1] if kind == "p"
                    else 0.4 * (r[t] - y[t - 1]) + 0.05 * integ)
        x = 0.9 * x + 0.5 * u[t]
    return sysid.IOData(u=u, y=y, dt=DT)


def _open(kind, n=2000, seed=1):
    rng = np.random.default_rng(seed)
    u = (rng.standard_normal(n) if kind == "white"
         else sysid.multisine(n, band=(0, 0.6), phases="random", seed=seed))
    y = sysid.TransferFunction([0.0, 0.5], [1.0, -0.9], dt=DT).simulate(u)[:, 0]
    return sysid.IOData(u=u, y=y + 0.3 * rng.standard_normal(n), dt=DT)


def _motor(p, dt=None):
    return [[-1 / p.tau]], [[p.K / p.tau]], [[1.0]], [[0.0]]


def _grey():
    return sysid.GreyBox(_motor, {"K": 1.0, "tau": sysid.param(1.0, bounds=(0.01, 10))})


FITS = {
    "oe": lambda d: sysid.oe(d, 1, 1, 1),
    "tfest": lambda d: sysid.tfest(d, 1, dt=DT),  # discrete: runs oe inside
    "tfest(continuous)": lambda d: sysid.tfest(d, 1),
    "ssest": lambda d: sysid.ssest(d, 1, focus="simulation"),
    "pem": lambda d: sysid.pem(d, sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=DT),
                               focus="simulation"),
    "procest": lambda d: sysid.procest(d, "P1"),
    "polyest": lambda d: sysid.polyest(d, 0, 1, 0, 0, 1, 1),  # na = nc = nd = 0: output error
    "greyest": lambda d: sysid.greyest(d, _grey(), focus="simulation"),
}


def _feedback_warnings(fit, data):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        model = fit(data)
    return model, [str(x.message) for x in w if issubclass(x.category, sysid.FeedbackWarning)]


@pytest.mark.parametrize("name", list(FITS))
def test_each_output_error_fit_warns_once_in_its_words_on_a_closed_loop(name):
    model, said = _feedback_warnings(FITS[name], _loop())
    assert len(said) == 1, said  # tfest's inner oe, ssest's pem: not again
    who = name.split("(")[0]
    assert said[0].startswith(f"{who}: the record shows feedback"), said[0]
    assert "input u0" in said[0] and "% of the input's variance" in said[0]
    remedy = {"oe": "sysid.bj", "tfest": "sysid.bj", "ssest": "focus='prediction'",
              "pem": "focus='prediction'", "procest": "sysid.bj", "greyest": "focus='prediction'",
              "polyest": "Box-Jenkins"}
    assert remedy[who] in said[0]
    info = model.info["feedback_check"]
    assert info["warned"] and info["p_value"] < 1e-6


def test_a_pi_loop_is_warned_too():
    _, said = _feedback_warnings(FITS["oe"], _loop(kind="pi"))
    assert len(said) == 1


@pytest.mark.parametrize("kind", ["white", "multisine"])
@pytest.mark.parametrize("name", ["oe", "tfest", "ssest", "procest"])
def test_open_loop_records_are_not_warned(kind, name):
    model, said = _feedback_warnings(FITS[name], _open(kind))
    assert said == []
    assert model.info["feedback_check"]["warned"] is False  # the check ran and said no


@pytest.mark.parametrize("fit", [lambda d: sysid.armax(d, 1, 1, 1, 1),
                                 lambda d: sysid.bj(d, 1, 1, 1, 1, 1),
                                 lambda d: sysid.polyest(d, 0, 1, 1, 1, 1, 1),
                                 lambda d: sysid.ssest(d, 1)])
def test_fits_with_a_noise_model_do_not_run_the_check(fit, monkeypatch):
    calls = []
    real = output_error.feedback_test
    monkeypatch.setattr(output_error, "feedback_test", lambda d: calls.append(1) or real(d))
    _, said = _feedback_warnings(fit, _loop())
    assert said == [] and calls == []


def test_frequency_response_data_are_not_checked():
    g = sysid.TransferFunction([0.0, 0.5], [1.0, -0.9], dt=DT)
    w = np.linspace(0.05, 30.0, 60)
    f = sysid.FRD(w, np.asarray(g.freqresp(w)).reshape(-1, 1, 1), dt=DT)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        G = sysid.tfest(f, 1)
    assert "feedback_check" not in G.info  # no time record: no test
    assert "feedback_check" in sysid.oe(_open("white"), 1, 1, 1).info


def test_identify_checks_once_and_leaks_no_candidate_warning(monkeypatch):
    data = _loop(n=1000)
    per_fit, whole = [], []
    real_test = output_error.feedback_test
    monkeypatch.setattr(output_error, "feedback_test",
                        lambda d: per_fit.append(1) or real_test(d))
    real_check = sysid.validation.feedback.check_feedback
    monkeypatch.setattr(sysid.validation.feedback, "check_feedback",
                        lambda *a, **k: whole.append(1) or real_check(*a, **k))
    monkeypatch.setattr(sysid, "check_feedback", sysid.validation.feedback.check_feedback)
    res, said = _feedback_warnings(lambda d: sysid.identify(d, max_order=3), data)
    assert said == [] and per_fit == []  # candidates (oe, pem simulation): no check
    assert len(whole) == 1  # identify's own
    assert res.checks["feedback"].startswith("detected")


def test_the_skip_holds_in_fold_threads():
    with feedback_checked():
        seen = list(ordered([lambda: _CHECKED.get()] * 4, workers=2))
    assert seen == [True] * 4
    assert list(ordered([lambda: _CHECKED.get()] * 2, workers=2)) == [False, False]
