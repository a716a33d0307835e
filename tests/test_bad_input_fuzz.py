"""Bad input found by calling the public functions with one thing wrong at a time (2026-12-01,
about 7 450 calls): each case raised an exception from inside the package, allocated
gigabytes, returned NaN, or named the wrong parameter. Each now fails with a SysidError that
names the problem and the fix (or, for the last, works)."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import DataError, InsufficientDataError

RNG = np.random.default_rng(0)
U = RNG.standard_normal((300, 1))
Y = np.convolve(U[:, 0], [0.0, 0.5, 0.3])[:300, None] + 0.01 * RNG.standard_normal((300, 1))
D = sysid.IOData(U, Y, 0.1)


@pytest.mark.parametrize("call, match", [
    # sizes checked before anything is allocated (each asked for 7.45 GiB or more)
    (lambda: sysid.lowpass(D, 1.0, 10**9), "order 1000000000 is beyond 50"),
    (lambda: sysid.drop_quiet(D, window=10**9), "longer than the longest experiment"),
    (lambda: sysid.spafdr(D, n_freq=10**9), "would allocate"),
    # wrong values named as themselves
    (lambda: sysid.check_excitation(U, -1), "order must be a positive integer, got -1"),
    (lambda: sysid.selstruc(0), "table must be the 2-D table of sysid.arxstruc"),
    (lambda: sysid.ssest(D, 2, focus=None), "focus must be 'prediction' or 'simulation'"),
    (lambda: sysid.ssest(D, 2, methods=("bogus",)), r"unknown subspace method\(s\) \['bogus'\]"),
    (lambda: sysid.nlarx(D, 2, 2, 1, focus="bogus"), "focus must be 'prediction' or"),
    (lambda: sysid.ProcessModel("P1", Kp=np.nan, Tp1=1.0), r"\['Kp'\] must be finite"),
    (lambda: sysid.delayest(sysid.IOData(U, Y * 1e200, 0.1)), "delayest cannot use it"),
    (lambda: sysid.nlhw_ss(sysid.IOData(np.zeros((300, 0)), Y, 0.1), 2),
     "needs at least one input"),
    (lambda: sysid.HammersteinWienerModel(sysid.Saturation(-1, 1), None, [1.0], [0.5], 1, 0.1),
     "parameters not set"),
    (lambda: sysid.HammersteinWienerModel(5, None, [1.0], [0.5], 1, 0.1),
     "input_nl must be a sysid nonlinearity"),
    # numpy's or SciPy's own words (LinAlgError, empty-axis ValueErrors) before
    (lambda: sysid.highpass(D, 1e-12), "below 1e-8 of the Nyquist frequency"),
    (lambda: sysid.filtfilt(D, [[1.0, 0.0, 0.0, 1.0, -2.0, 1.0]]), "cannot filter"),
    (lambda: sysid.persistent_excitation_order(U * 1e300, method="covariance"),
     "values of order"),
    (lambda: sysid.find_spikes(np.zeros((0, 1))), "with samples"),
    (lambda: sysid.detect_period(np.zeros((0, 1))), "with samples"),
    (lambda: sysid.nlarx(D, 2, 2, 1, criterion="validation",
                         validation=sysid.IOData(RNG.standard_normal((300, 2)),
                                                 RNG.standard_normal((300, 2)), 0.1)),
     "validation has 2 input"),
    # NaN results before: a NaN window, a Ljung-Box statistic of outputs near 1e200
    (lambda: sysid.spectra(D, window=np.nan), "non-finite or all-zero weights"),
    (lambda: sysid.periodogram(D, window=np.nan), "non-finite or all-zero weights"),
    (lambda: sysid.residuals(sysid.n4sid(D, 2), sysid.IOData(U, Y * 1e200, 0.1)),
     "residuals cannot use it"),
    (lambda: sysid.criteria(sysid.n4sid(D, 2), sysid.IOData(U, Y * 1e200, 0.1)),
     "criteria cannot use it"),
    # models of inputs or outputs that never change (0 / (s^2 + ...), a gain of 1.5e7)
    (lambda: sysid.tfest(sysid.IOData(np.zeros((300, 1)), Y, 0.1), 2), "every sample"),
    (lambda: sysid.procest(sysid.IOData(U, np.ones((300, 1)), 0.1), "P1"), "every sample"),
    # sample times that overflow pi / dt or N dt later (NaN coherence, "x has a non-finite
    # value" from procest's internals)
    (lambda: sysid.IOData(U, Y, 1e300), r"lies outside 1e-100 \.\. 1e\+100 s"),
    (lambda: sysid.IOData(U, Y, 1e-300), "other units"),
    # messages that named the wrong cause
    (lambda: sysid.augment_inputs(D, [lambda u: u * np.nan]), "returned a non-finite value"),
    (lambda: sysid.ar(sysid.IOData(None, np.tile([1.0, -1.0], 50)), 4, method="burg"),
     "predicted exactly by an AR model of order 1"),
    (lambda: sysid.pnlss(sysid.IOData(U, Y * 1e200, 0.1), 2, max_iter=2),
     "values of order"),  # was "output y0 is constant (0)"
    (lambda: sysid.spafdr(sysid.IOData(np.column_stack([U, U]), Y, 0.1)),
     "linearly dependent"),  # was "0.0 spectra ... widen the resolution"
    (lambda: sysid.spafdr(sysid.IOData(U[:1], Y[:1], 0.1)), "at least 2 samples"),
    (lambda: sysid.periodogram(sysid.IOData(U[:1], Y[:1], 0.1)), "at least 2 samples"),
    (lambda: sysid.ho_kalman(np.ones((30, 1, 1)), rank_tol=np.nan), "rank_tol must lie"),
    # a model with NaN coefficients simulated to NaN without a word
    (lambda: sysid.PolynomialModel([[np.array([np.nan])]], [[np.array([1.0])]], [[1]], 0.1),
     r"a\[0\]\[0\] has a non-finite coefficient"),
    (lambda: sysid.PolynomialModel([[np.array([0.5])]], [[np.array([1.0])]], [[-1]], 0.1),
     "nk must hold delays >= 0"),
])
def test_bad_input_gets_a_named_error(call, match):
    with pytest.raises(DataError, match=match):
        call()


def test_resampling_a_one_sample_experiment_is_refused_not_nan():
    with pytest.raises(InsufficientDataError, match="one sample"):
        sysid.resample(sysid.IOData(U[:1], Y[:1], 0.1), 0.2)


@pytest.mark.parametrize("fit", [
    lambda d: sysid.n4sid(d, 2), lambda d: sysid.ssest(d, 2), lambda d: sysid.arx(d, 2, 2, 1),
    lambda d: sysid.oe(d, 2, 2, 1), lambda d: sysid.nlhw(d, 2, 2, 1),
    lambda d: sysid.pnlss(d, 2, degree=2, progress=False)])
def test_a_one_sample_record_is_too_short_not_constant(fit):
    """On one sample every channel is "constant": n4sid said "output y0 is constant", arx
    "input u0 is 0.12573 in every sample", pnlss "input u0 is constant": the length is the
    problem, and the error says so."""
    with pytest.raises(InsufficientDataError, match="too few samples: .*one sample"):
        fit(sysid.IOData(U[:1], Y[:1], 0.1))


def test_what_was_refused_still_works_when_given_right():
    s = sysid.Saturation(-1.0, 1.0)
    s.params = s.initial(None)
    hw = sysid.HammersteinWienerModel(s, None, [1.0], [0.5], 1, 0.1)  # None: no output map
    assert np.all(np.isfinite(hw.simulate(U)))
    # a fixed delay beyond the bound on estimated ones ("lower bound 50 exceeds upper 30")
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        g = sysid.tfest(D, 2, iodelay=5.0)
    assert float(g.iodelay[0, 0]) == 5.0
    assert sysid.augment_inputs(D, "square").n_inputs == 2


def test_multi_output_polynomial_covariance_is_decomposed_by_blocks():
    # a 60-output ARX model (7320 parameters) took minutes in one dense eigendecomposition;
    # its per-output blocks give the same eigenpairs
    y = RNG.standard_normal((300, 3))
    m = sysid.arx(sysid.IOData(U, y, 1.0), 2, 2, 1)
    unc = m.uncertainty
    P = unc.covariance
    w, V = unc._eigen()
    np.testing.assert_allclose((V * w) @ V.T, P, atol=1e-12 * np.abs(P).max())
    assert unc.dof == np.linalg.matrix_rank(P) == w.size
    np.testing.assert_allclose(np.sort(w), np.sort(np.linalg.eigvalsh(P))[-w.size:],
                               rtol=1e-10)


@pytest.mark.parametrize("fit", [
    lambda d: sysid.arx(d, 2, [2, 2], [1, 1]),
    lambda d: sysid.oe(d, [[2, 2]], [[2, 2]], [[1, 1]]),
    lambda d: sysid.armax(d, 2, [[2, 2]], 1, [[1, 1]]),
    lambda d: sysid.n4sid(d, 2),
    lambda d: sysid.pbsid(d, 2),
    lambda d: sysid.ssregest(d, 2),
    lambda d: sysid.tfest(d, 2),
    lambda d: sysid.nlarx(d, 2, 2, 1),
])
def test_an_input_recorded_twice_is_refused_by_every_estimator(fit):
    # oe, armax, pbsid, ssregest and nlarx returned a model (arx and n4sid refused by rank)
    x = RNG.standard_normal(300)
    y = np.convolve(x, [0.0, 0.5, 0.3])[:300, None] + 0.01 * RNG.standard_normal((300, 1))
    twice = sysid.IOData(np.column_stack([x, -2.0 * x]), y, 1.0, input_names=["f", "g"])
    with pytest.raises(sysid.ExcitationError, match="inputs f, g are linearly dependent"):
        fit(twice)


H = np.ones((30, 1, 1)) * 0.5 ** np.arange(30)[:, None, None]


@pytest.mark.parametrize("call, match", [
    # a string or None where a number belongs: NumPy's TypeError/ValueError before
    (lambda: sysid.ssest(D, 2, tol="x"), "tol must be a finite number >= 0, got 'x'"),
    (lambda: sysid.pem(D, sysid.n4sid(D, 2), tol=None), "tol must be a finite number >= 0"),
    (lambda: sysid.oe(D, 2, 2, 1, max_iter="x"), "max_iter must be an integer >= 0"),
    (lambda: sysid.armax(D, 2, 2, 2, 1, max_iter=None), "max_iter must be an integer >= 0"),
    (lambda: sysid.bj(D, 2, 2, 2, 2, 1, max_iter=np.nan), "max_iter must be an integer >= 0"),
    (lambda: sysid.nlarx(D, 2, 2, 1, max_terms="x"), "max_terms must be a positive integer"),
    (lambda: sysid.nlarx(D, 2, 2, 1, noise_terms=None), "noise_terms must be an integer >= 0"),
    (lambda: sysid.nlarx(D, 2, 2, 1, n_iterations="5"), "n_iterations must be a positive"),
    (lambda: sysid.nlarx(D, 2, 2, 1, max_iter=None), "max_iter must be an integer >= 0"),
    (lambda: sysid.nlssest(D, 2, validation="x"), r"validation \(a fraction"),
    (lambda: sysid.etfe(D, confidence="x"), r"confidence must be a number in \(0, 1\)"),
    (lambda: sysid.spa(D, confidence=None), r"confidence must be a number in \(0, 1\)"),
    (lambda: sysid.spafdr(D, confidence=1.5), r"confidence must be a number in \(0, 1\)"),
    (lambda: sysid.residuals(sysid.n4sid(D, 2), D, alpha="x"), r"alpha must be a number in"),
    (lambda: sysid.identify(D, time_budget="x"), "time_budget .* must be a finite positive"),
    (lambda: sysid.minreal(sysid.n4sid(D, 2), tol="x"), "tol .* must be a finite positive"),
    # NaN (or out-of-range) tolerances accepted silently
    (lambda: sysid.nlarx(D, 2, 2, 1, err_tol=np.nan), r"err_tol must be a number in \[0, 1\)"),
    (lambda: sysid.nlarx(D, 2, 2, 1, err_tol=-1.0), r"err_tol must be a number in \[0, 1\)"),
    (lambda: sysid.etfe(D, min_power=np.nan), "min_power must be a finite number >= 0"),
    (lambda: sysid.era_stabilization(H, [2, 4], freq_tol=np.nan), "freq_tol must be a finite"),
    (lambda: sysid.era_stabilization(H, [2, 4], damping_tol=None), "damping_tol must be"),
    (lambda: sysid.era_stabilization(H, [2, 4], min_mac=np.nan), r"min_mac must be a number in"),
    (lambda: sysid.ssi(sysid.IOData(None, RNG.standard_normal((500, 1)), 0.1), [2, 4],
                       min_mac=np.nan), r"min_mac must be a number in \[0, 1\]"),
    (lambda: sysid.ssi(sysid.IOData(None, RNG.standard_normal((500, 1)), 0.1), [2, 4],
                       freq_tol="x"), "freq_tol must be a finite number"),
    (lambda: sysid.sample_time(np.arange(10.0), rtol=np.nan), "rtol must be a finite number"),
    (lambda: sysid.select_order(D, [1, 2], fit_tol=np.nan), "fit_tol must be a finite number"),
])
def test_numbers_are_checked_by_the_shared_validators(call, match):
    with pytest.raises(DataError, match=match):
        call()


@pytest.mark.parametrize("call", [
    lambda: sysid.nlhw_ss(D, 2, input_nl=sysid.SigmoidNetwork(10**6)),
    lambda: sysid.nlhw(D, 2, 2, 1, output_nl=sysid.SigmoidNetwork(10**6)),
    lambda: sysid.nlarx(D, 2, 2, 1, basis=sysid.SigmoidNetwork(10**6)),
])
def test_a_million_sigmoid_units_are_refused_before_allocating(call):
    # nlhw_ss ran for minutes towards a Jacobian of 300 x 3e6 values
    with pytest.raises(DataError, match="SigmoidNetwork of 1000000 units.*would allocate"):
        call()
    with pytest.raises(DataError, match="units must be a positive integer, got 'x'"):
        sysid.SigmoidNetwork("x")
    with pytest.raises(DataError, match="units = 1000000000000 would need"):
        sysid.SigmoidNetwork(10**12)


@pytest.mark.parametrize("model, x0, diverged", [
    (sysid.StateSpaceModel([[1.5]], [[1.0]], [[1.0]], dt=0.1), "estimate", True),
    (sysid.StateSpaceModel([[1.01]], [[1.0]], [[1.0]], dt=0.1), "zero", False),
    (sysid.ProcessModel("P1", Kp=1.0, Tp1=-1.0), "estimate", False),  # x0 holds it back
    (sysid.ProcessModel("P1", Kp=1.0, Tp1=-1.0), "zero", True),
    (sysid.PolynomialModel([[np.array([1.0, -1.5])]], [[np.array([1.0])]], [[1]], 0.1),
     "estimate", True),
    (sysid.TransferFunction([[[1.0]]], [[[1.0, -2.0]]]), "zero", True),
])
def test_compare_warns_of_every_unstable_model(model, x0, diverged):
    # compare flagged some with fit -inf and said nothing; the ProcessModel with a negative
    # time constant got a finite fit from a fitted initial state, without a word
    with pytest.warns(sysid.StabilityWarning, match="diverged" if diverged else "unstable"):
        r = sysid.compare(D, model, x0=x0)
    assert bool(r.diverged.any()) == diverged and (np.isneginf(r.fit).all() == diverged)


def test_compare_of_a_stable_model_says_nothing():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sysid.compare(D, sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1))
        sysid.compare(D, sysid.ProcessModel("P1", Kp=1.0, Tp1=1.0))


def test_nlarx_auto_basis_honours_the_validation_criterion():
    # basis="auto" chose on the estimation record's held-out blocks and ignored the
    # validation record the user gave with criterion="validation"
    def record(seed):
        u = np.random.default_rng(seed).uniform(-1, 1, (400, 1))
        y = np.zeros((400, 1))
        for t in range(1, 400):
            y[t] = 0.5 * y[t - 1] + u[t - 1] + 0.8 * u[t - 1] ** 2
        return sysid.IOData(u, y, 1.0)

    m = sysid.nlarx(record(1), 1, 1, 1, criterion="validation", validation=record(2))
    choice = m.info["basis_choice"]
    assert choice["criterion"] == "validation" and "validation record" in choice["reason"]
    assert choice["kind"] == "polynomial" == min(choice["table"], key=choice["table"].get)


def test_model_matrices_are_read_only_and_checked_when_replaced():
    # m.A[0, 0] = np.nan was accepted, and simulate/compare gave NaN without a word
    m = sysid.n4sid(D, 2)
    for name in ("A", "B", "C", "D", "K", "noise_cov"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(m, name)[0, 0] = np.nan
    with pytest.raises(sysid.NonFiniteError, match="A has non-finite entries"):
        m.A = np.full((2, 2), np.nan)
    with pytest.raises(sysid.ShapeError, match="another model: build it"):
        m.B = np.ones((3, 1))
    mine = np.array([[0.5]])
    h = sysid.StateSpaceModel(mine, [[1.0]], [[1.0]], dt=0.1)
    mine[0, 0] = np.nan  # the caller's array is not the model's
    assert np.isfinite(h.simulate(U)).all()
    # a whole matrix of the same shape is taken (MATLAB's sys.A = ...), a copy edited too
    h.A = [[0.8]]
    A = h.A.copy()
    A[0, 0] = 0.7
    assert h.poles()[0] == 0.8 and sysid.StateSpaceModel(A, h.B, h.C, dt=0.1).poles()[0] == 0.7
    import copy
    import pickle

    for twin in (copy.deepcopy(m), pickle.loads(pickle.dumps(m))):
        with pytest.raises(ValueError, match="read-only"):
            twin.A[0, 0] = 1.0


def test_inputs_on_one_line_about_their_means_are_not_called_recorded_twice():
    """Two heaters' controller outputs on one line, U2 = 30 - 0.3 U1 (a TCLab log's first
    half): ``identify`` removes the means, and the check then said 'linearly dependent in
    every sample ... a channel recorded twice?' of inputs neither equal nor proportional.
    On centred inputs it now says the dependence holds about their means."""
    u1 = np.repeat(RNG.uniform(20.0, 50.0, 40), 10)
    u = np.column_stack([u1, 30.0 - 0.3 * u1])
    y = sysid.StateSpaceModel([[0.9]], [[0.1, 0.05]], [[1.0]]).simulate(u)
    d = sysid.IOData(u, y, 1.0, input_names=["U1", "U2"])
    with pytest.raises(sysid.ExcitationError) as err:
        sysid.identify(d)
    msg = str(err.value)
    assert "inputs U1, U2 lie on one line or plane about their means" in msg
    assert "recorded twice" not in msg and "linearly dependent" not in msg
