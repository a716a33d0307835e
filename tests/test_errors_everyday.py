"""Bad input to every function of issue 27 (tfest, procest, TransferFunction, ProcessModel, ar,
arma, forecast, ssi, mac, the online estimators, stepinfo, margin, nyquist, minreal,
delayest): a ``sysid.errors`` exception whose message names the problem and the fix.

One row per case: the call, the exception class, a pattern for the problem and one for the
fix (what to pass instead)."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import sysid
from sysid import errors

RNG = np.random.default_rng(0)
U = RNG.standard_normal(200)
D = sysid.IOData(U, np.cumsum(U) * 0.01, dt=0.1)
TS = sysid.IOData(None, RNG.standard_normal((200, 1)), dt=0.1)
W = np.logspace(-1, 1, 20)
G1 = sysid.TransferFunction([1.0], [1.0, 1.0])
FRD = sysid.FRD(W, G1.freqresp(W))
AR = sysid.ar(RNG.standard_normal(300), 2)
MIMO = sysid.TransferFunction([[[1.0], [1.0]]], [[[1.0, 1.0], [1.0, 2.0]]])
Y2 = sysid.IOData(None, RNG.standard_normal((2000, 2)), 0.1)

CASES = [
    # tfest
    ("tfest arrays", lambda: sysid.tfest(np.zeros((10, 2)), 1), errors.DataError,
     "needs a sysid.IOData", "wrap arrays as sysid.IOData"),
    ("tfest time series", lambda: sysid.tfest(TS, 1), errors.DataError,
     "at least one input", "sysid.ar"),
    ("tfest negative order", lambda: sysid.tfest(D, -1), errors.DataError,
     "n_poles", r"0\.\.30"),
    ("tfest fractional order", lambda: sysid.tfest(D, 1.5), errors.DataError,
     "whole number", "one per output/input pair"),
    ("tfest improper", lambda: sysid.tfest(D, 1, 2), errors.DataError,
     "must not exceed", "n_zeros <= n_poles"),
    ("tfest negative delay", lambda: sysid.tfest(D, 1, iodelay=-0.1), errors.DataError,
     "iodelay", ">= 0"),
    ("tfest delay word", lambda: sysid.tfest(D, 1, iodelay="guess"), errors.DataError,
     "iodelay", "'auto'"),
    ("tfest hold", lambda: sysid.tfest(D, 1, hold="cubic"), errors.DataError,
     "hold", "'zoh' or 'foh'"),
    ("tfest initial state", lambda: sysid.tfest(D, 1, initial_state="x"), errors.DataError,
     "initial_state", "'zero' or 'estimate'"),
    ("tfest dt mismatch", lambda: sysid.tfest(D, 1, dt=0.2), errors.DataError,
     "dt", "resample"),
    ("tfest init type", lambda: sysid.tfest(D, 1, init="G"), errors.DataError,
     "init", "continuous sysid.TransferFunction"),
    ("tfest max_iter", lambda: sysid.tfest(D, 1, max_iter=-1), errors.DataError,
     "max_iter", ">= 0"),
    ("tfest tol", lambda: sysid.tfest(D, 1, tol=float("nan")), errors.DataError,
     "tol", "positive finite number"),
    ("tfest max_delay", lambda: sysid.tfest(D, 1, iodelay="auto", max_delay=-1.0),
     errors.DataError, "max_delay", "None or a positive number of seconds"),
    ("tfest too short", lambda: sysid.tfest(sysid.IOData(np.ones(3), np.ones(3), dt=1.0), 2),
     errors.DataError, "3 samples", "give at least"),
    ("tfest FRD few points", lambda: sysid.tfest(sysid.FRD(W[:2], G1.freqresp(W[:2])), 3),
     errors.DataError, "too few", "measure more frequencies or lower n_poles"),
    ("tfest FRD dt", lambda: sysid.tfest(FRD, 1, dt=0.1), errors.DataError,
     "sample time", "FRD's sample time"),
    # TransferFunction
    ("tf improper", lambda: sysid.TransferFunction([1.0, 2.0, 3.0], [1.0, 1.0]),
     errors.DataError, "improper", "at most as many zeros as poles"),
    ("tf zero denominator", lambda: sysid.TransferFunction([1.0], [0.0]), errors.DataError,
     "denominator is zero", "give its coefficients"),
    ("tf simulate without dt", lambda: G1.simulate(np.ones(3)), errors.DataError,
     "sample time", "pass dt"),
    ("tf discrete fractional delay",
     lambda: sysid.TransferFunction([1.0], [1.0, 1.0], iodelay=0.5, dt=1.0), errors.DataError,
     "whole samples", "round it or use a continuous model"),
    ("tf shapes", lambda: sysid.TransferFunction([[[1.0], [1.0]]], [[[1.0, 1.0]]]),
     errors.ShapeError, "pairs", "one of each per output/input pair"),
    # procest and ProcessModel
    ("procest code", lambda: sysid.procest(D, "P4D"), errors.DataError,
     "invalid process type", "use a code like 'P1D'"),
    ("procest U", lambda: sysid.procest(D, "P1U"), errors.DataError,
     "needs 2 or 3", "'P2DU'"),
    ("procest type", lambda: sysid.procest(D, 3), errors.DataError,
     "must be a string", "use a code like"),
    ("procest arrays", lambda: sysid.procest(np.zeros((10, 2)), "P1D"), errors.DataError,
     "needs a sysid.IOData", "wrap arrays as sysid.IOData"),
    ("procest unknown fixed", lambda: sysid.procest(D, "P1D", fixed={"Tp2": 1.0}),
     errors.DataError, "not parameters of P1D", "its parameters are"),
    ("procest bounds", lambda: sysid.procest(D, "P1D", bounds={"Tp1": (2.0, 1.0)}),
     errors.DataError, r"bounds\['Tp1'\]", "lower must be below upper"),
    ("procest bounds shape", lambda: sysid.procest(D, "P1D", bounds={"Tp1": 1.0}),
     errors.DataError, r"bounds\['Tp1'\]", r"a pair \(lower, upper\)"),
    ("procest init nan", lambda: sysid.procest(D, "P1D", init={"Kp": float("nan")}),
     errors.DataError, "Kp must be finite", "got nan"),
    ("procest integrator foh", lambda: sysid.procest(D, "P1DI", hold="foh"),
     errors.DataError, "not supported", "hold='zoh'"),
    ("procest P0D", lambda: sysid.procest(D, "P0D"), errors.DataError,
     "not supported", "fit 'P1D'"),
    ("process model missing", lambda: sysid.ProcessModel("P1D", Kp=1.0), errors.DataError,
     "missing", "has the parameters"),
    # ar, arma, forecast
    ("ar method", lambda: sysid.ar(U, 2, "mle"), errors.DataError,
     "method must be", "'burg'"),
    ("ar with inputs", lambda: sysid.ar(D, 2), errors.DataError,
     "without inputs", "arx/armax"),
    ("ar channels", lambda: sysid.ar(Y2, 2), errors.DataError,
     "one channel", "sysid.n4sid"),
    ("ar short", lambda: sysid.ar(U[:5], 3), errors.InsufficientDataError,
     "needs more than 6 samples", "lower order or a longer record"),
    ("ar zero series", lambda: sysid.ar(np.zeros(50), 2), errors.DataError,
     "0 in every sample", "drop it"),
    ("ar order", lambda: sysid.ar(U, 0), errors.DataError, "na must be", "positive integer"),
    ("ar 2-D array", lambda: sysid.ar(np.ones((10, 3)), 1), errors.DataError,
     "shape", "1-D array"),
    ("arma orders", lambda: sysid.arma(U, 0, 0), errors.DataError,
     "na \\+ nc", ">= 1"),
    ("arma max_iter", lambda: sysid.arma(U, 1, 1, max_iter=-1), errors.DataError,
     "max_iter", ">= 0"),
    ("forecast horizon", lambda: sysid.forecast(AR, U, 0), errors.DataError,
     "horizon", "positive integer"),
    ("forecast level", lambda: sysid.forecast(AR, U, 3, level=95), errors.DataError,
     "level", "0.95"),
    ("forecast model", lambda: sysid.forecast(object(), U, 3), errors.DataError,
     "a StateSpaceModel, a polynomial model", "to_statespace"),
    ("forecast inputs", lambda: sysid.forecast(sysid.StateSpaceModel([[0.5]], [[1.0]],
                                                                     [[1.0]]), U, 3),
     errors.DataError, "1 input", "give future_inputs"),
    ("forecast past shape", lambda: sysid.forecast(AR, np.ones((10, 2)), 3),
     errors.ShapeError, "past has shape", "should have 1 column"),
    ("simulate transposed", lambda: sysid.StateSpaceModel(
        0.5 * np.eye(2), np.ones((2, 3)), np.ones((1, 2))).simulate(np.zeros((3, 50))),
     errors.ShapeError, "should have 3 column", r"looks transposed .*pass u\.T"),
    # ssi, mac
    ("ssi arrays", lambda: sysid.ssi(np.ones((100, 2)), [2]), errors.DataError,
     "IOData", r"sysid.IOData\(None, y, dt\)"),
    ("ssi method", lambda: sysid.ssi(Y2, [2], method="ssi"), errors.DataError,
     "method must be", "'cov'"),
    ("ssi orders", lambda: sysid.ssi(Y2, [4, 2]), errors.DataError,
     "orders must be", "non-empty increasing sequence"),
    ("ssi horizon", lambda: sysid.ssi(Y2, [2, 30], horizon=10), errors.DataError,
     "allows orders up to", "choose horizon"),
    ("ssi short", lambda: sysid.ssi(sysid.IOData(None, np.ones((100, 2)), 0.1), [2],
                                    horizon=10), errors.InsufficientDataError,
     "needs at least", "longer record"),
    ("ssi blocks", lambda: sysid.ssi(Y2, [2], blocks=1), errors.DataError,
     "blocks", ">= 2"),
    ("ssi order not in diagram", lambda: sysid.ssi(Y2, [2, 4]).modes_at(6), errors.DataError,
     "not in the diagram", "pick one of them"),
    ("mac channels", lambda: sysid.mac([1, 2], [1, 2, 3]), errors.DataError,
     "channels", "same channels"),
    # online estimators
    ("recursive kalman noise", lambda: sysid.RecursiveARX(1, 1, method="kalman",
                                                           process_noise=np.eye(3)),
     errors.ShapeError, r"process_noise has shape \(3, 3\)", r"should be \(2, 2\) or a number"),
    ("recursive forgetting", lambda: sysid.RecursiveARX(1, 1, forgetting=1.5),
     errors.DataError, "forgetting factor", r"in \(0, 1\]"),
    ("recursive method", lambda: sysid.RecursiveARX(1, 1, method="rls"), errors.DataError,
     "method must be", "\"forgetting\""),
    ("recursive orders", lambda: sysid.RecursiveARX(1, [1, 1], [1, 1, 1]), errors.DataError,
     "nk has 3 entries", "one per input"),
    ("recursive empty", lambda: sysid.RecursiveARX(0, 0), errors.DataError,
     "no parameters", "give at least one positive order"),
    ("recursive NaN", lambda: sysid.RecursiveARX(1, 1).run(np.ones(5),
                                                          np.r_[0, 0, 0, np.nan, 0]),
     errors.NonFiniteError, "sample 3", "interpolate or cut it out"),
    ("recursive lengths", lambda: sysid.RecursiveARX(1, 1).run(np.ones(5), np.ones(4)),
     errors.ShapeError, "u has 5 samples but y has 4", "samples"),
    ("recursive armax order", lambda: sysid.RecursiveARMAX(1, 1, -1), errors.DataError,
     "nc must be", ">= 0"),
    ("recursive oe step", lambda: sysid.RecursiveOE(1, 1).step([1.0, 2.0], 0.0),
     errors.ShapeError, "2 value", "pass one value per input"),
    # analysis helpers
    ("margin mimo", lambda: sysid.margin(MIMO), errors.DataError,
     "margin is defined for a single-input single-output", r"select one pair: model\[i, j\]"),
    ("margin type", lambda: sysid.margin("G"), errors.DataError, "got str",
     "a model with freqresp"),
    ("margin omega", lambda: sysid.margin(G1, omega=[-1.0, 2.0]), errors.DataError,
     "omega", "at least two positive finite frequencies"),
    ("nyquist mimo", lambda: sysid.nyquist(MIMO), errors.DataError,
     "nyquist is defined for a single-input single-output", "select one pair"),
    ("stepinfo bare array", lambda: sysid.stepinfo(np.ones(5)), errors.DataError,
     "needs their times", r"stepinfo\(y, t\)"),
    ("stepinfo threshold", lambda: sysid.stepinfo(G1, threshold=2.0), errors.DataError,
     "threshold", r"lie in \(0, 1\)"),
    ("stepinfo rise limits", lambda: sysid.stepinfo(G1, rise_limits=(0.9, 0.1)),
     errors.DataError, "rise_limits", "0 <= low < high <= 1"),
    ("minreal tol", lambda: sysid.minreal(G1, tol=-1), errors.DataError, "got -1",
     "must be a finite positive number"),
    ("minreal type", lambda: sysid.minreal(3), errors.DataError,
     "got int", "TransferFunction or a state-space model"),
    ("delayest range", lambda: sysid.delayest(D, nk_min=5, nk_max=2), errors.DataError,
     "got 5 and 2", "nk_min <= nk_max"),
    ("delayest short", lambda: sysid.delayest(sysid.IOData(U[:20], U[:20], 1.0), nk_max=10),
     errors.DataError, "too few", "smaller nk_max"),
    ("delayest very short", lambda: sysid.delayest(sysid.IOData(U[:10], U[:10], 1.0)),
     errors.DataError, "too few", "smaller na and nb"),
    ("delayest time series", lambda: sysid.delayest(TS), errors.DataError,
     "needs inputs", "no input delay"),
    # automatic orders where MATLAB has none: what to call instead
    ("ar auto", lambda: sysid.ar(TS, "auto"), errors.DataError, "got 'auto'",
     r"sysid\.selstruc\(sysid\.arxstruc\(est, val, sysid\.struc\(range"),
    ("tfest auto", lambda: sysid.tfest(D, "auto"), errors.DataError,
     "tfest has no automatic order", r"sysid\.select_order\(est, models="),
    ("struc half", lambda: sysid.struc([1, 2], [1]), errors.DataError,
     "give both nb and nk", "or neither"),
]


@pytest.mark.parametrize("call, exc, problem, fix", [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_bad_input_names_the_problem_and_the_fix(call, exc, problem, fix):
    with pytest.raises(exc) as info:
        call()
    msg = str(info.value)
    assert isinstance(info.value, errors.SysidError)
    assert re.search(problem, msg), msg
    assert re.search(fix, msg), msg


def test_matlab_names_point_at_sysids():
    # `sysid.resid(model, data)` (MATLAB's name) said only "no attribute 'resid'. Did you
    # mean: 'n4sid'?" (issue 26)
    with pytest.raises(AttributeError, match=r"sysid\.residuals\(model, data\)"):
        sysid.resid  # noqa: B018
    with pytest.raises(AttributeError, match="no attribute 'nothing_like_it'$"):
        sysid.nothing_like_it  # noqa: B018
    # every MATLAB name with a hint: the hint names sysid functions that exist
    import re

    from sysid import _MATLAB

    assert {"predict", "goodnessOfFit", "lsim", "isstable", "pe"} <= set(_MATLAB)
    assert not set(_MATLAB) & set(dir(sysid))  # a hint never hides a real function
    for name, hint in _MATLAB.items():
        with pytest.raises(AttributeError, match=re.escape(hint)):
            getattr(sysid, name)
        for ref in re.findall(r"sysid\.([A-Za-z_]\w*)", hint):
            assert hasattr(sysid, ref), (name, ref)
    # and every model.<attribute> / data.<attribute> a hint names exists on an estimated
    # model and a record (getpvec's hint named a model.parameters that no model has)
    rng = np.random.default_rng(0)
    d = sysid.IOData(rng.standard_normal((200, 1)), rng.standard_normal((200, 1)), 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        models = [sysid.oe(d, 1, 1, 1), sysid.ssest(d, 1)]  # polynomial, state space

    def has(target: object, path: str) -> bool:
        for attr in path.strip(".").split("."):
            if not hasattr(target, attr):
                return False
            target = getattr(target, attr)
        return True
    for name, hint in _MATLAB.items():
        for obj, path in re.findall(r"\b(model|data)((?:\.[A-Za-z_]\w*)+)", hint):
            assert any(has(t, path) for t in (models if obj == "model" else [d])), \
                (name, obj + path)


def test_simulating_a_whole_record_says_to_pass_its_inputs():
    # model.simulate(data) failed inside IOData indexing ("index IOData with a slice ...")
    m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    d = sysid.IOData(np.ones((10, 1)), np.ones((10, 1)))
    with pytest.raises(sysid.DataError, match=r"whole record \(IOData\).*data\.u"):
        m.simulate(d)


def test_a_capped_search_warns_only_while_it_still_moves():
    import warnings

    from sysid._checks import warn_if_capped

    with pytest.warns(sysid.IterationLimitWarning, match="stopped at max_iter=5"):
        warn_if_capped({"stop": "maximum iterations", "cost": [4.0, 2.0, 1.5]}, "the search", 5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warn_if_capped({"stop": "maximum iterations", "cost": [2.0, 1.0, 1.0 - 1e-9]},
                       "the search", 5)  # settled: a warning would be noise
        warn_if_capped({"stop": "cost tolerance", "cost": [4.0, 2.0]}, "the search", 5)
    with pytest.warns(sysid.IterationLimitWarning):  # one history per output
        warn_if_capped({"stop": ["cost tolerance", "maximum iterations"],
                        "cost": [[1.0, 1.0], [3.0, 2.0]]}, "the oe search", 5)


def test_pole_uncertainty_asked_of_a_nonlinear_model_is_named():
    # poles(std=True) raised "unexpected keyword argument 'std'" on NARX, Hammerstein-Wiener
    # and nonlinear state-space models; linear models without uncertainty name the fix
    rng = np.random.default_rng(0)
    u = rng.standard_normal((400, 1))
    y = np.tanh(sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]]).simulate(u))
    d = sysid.IOData(u, y, 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        models = [sysid.nlarx(d, 2, 2, 1), sysid.nlhw(d, [2, 2, 1])]
    for m in models[:1]:
        assert m.poles().size  # the linear part's
        with pytest.raises(sysid.DataError, match=r"poles\(std=True\).*no pole uncertainty"):
            m.poles(std=True)
    # a Hammerstein-Wiener fit carries its parameter uncertainty (issue 26): its linear
    # block's poles with their standard deviations
    p, sd = models[1].poles(std=True)
    assert p.size == sd.size == 2


def test_matlab_structure_choice_chain_on_several_inputs():
    # arx(data, selstruc(arxstruc(data, ...))) on a 2-input record: arxstruc's rows had one
    # shared nb and nk, selstruc returned 3 numbers and arx refused them; struc's rows were
    # refused by arxstruc(ze, zv, NN); a ragged order list was a raw NumPy ValueError
    rng = np.random.default_rng(0)
    u = rng.standard_normal((400, 2))
    y = np.zeros(400)
    for t in range(1, 400):
        y[t] = 0.5 * y[t - 1] + u[t - 1] @ [1.0, -0.4] + 0.05 * rng.standard_normal()
    d = sysid.IOData(u, y[:, None], 1.0)
    table = sysid.arxstruc(d, [1, 2], [1, 2], [1])
    assert table.shape[1] == 1 + 2 + 2 + 2
    nn = sysid.selstruc(table, "aic")
    assert nn == (1, 1, 1, 1, 1)
    assert np.allclose(sysid.arx(d, nn).a[0][0], [-0.5], atol=0.05)
    v = sysid.arxstruc(d[:200], d[200:], sysid.struc([1, 2], [1, 2], [1]))
    assert sysid.selstruc(v, 0)[:1] == (1,) and len(sysid.selstruc(v, 0)) == 5
    with pytest.raises(sysid.DataError, match="flat numbers"):
        sysid.arx(d, [1, [1, 1], [1, 1]])


def test_model_interconnection_names_python_control():
    # G * K, G + H and 2 * G gave Python's bare "unsupported operand type(s)"; MATLAB users
    # write them first. The error names the route (python-control's interconnections), and
    # the FRD's own algebra with a model is unchanged
    g = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=0.1)
    for op in (lambda: g * g, lambda: g + g, lambda: g - g, lambda: 2 * g, lambda: g + 1):
        with pytest.raises(TypeError, match=r"sysid.to_control\(model\).*series, parallel"):
            op()
    f = sysid.FRD.from_model(g, np.linspace(0.1, 30.0, 20))
    np.testing.assert_allclose((g * f).response, (f * f).response)
    np.testing.assert_allclose((f - g).response, 0.0, atol=1e-12)
    control = pytest.importorskip("control")
    loop = sysid.from_control(control.feedback(sysid.to_control(g) * 0.1, 1))
    np.testing.assert_allclose(loop.poles(), [0.7])
