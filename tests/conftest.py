"""Shared test helpers: random stable systems, an independent numpy simulator, the DaISy
records split as their README says, a call with warnings silenced."""

from __future__ import annotations

import os
import signal
import warnings

import numpy as np
from hypothesis import settings

# CI runs the same examples every time (reproducible); locally hypothesis explores anew.
settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")

# A test run started in the background by a non-interactive shell inherits SIGINT ignored,
# and so would every process the Ctrl-C tests start (an ignored signal stays ignored across
# exec, and Python then installs no KeyboardInterrupt handler): catch it here, so that the
# children start with the default and the tests send a signal that is heard.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

# the shipped DaISy copies' (inputs, outputs, estimation samples), splits of their README:
# dryer 1:500 / 501:1000, robot arm 1:800 / 801:1024, winding first 2/3 / last 1/3
DAISY_SPLITS = {"dryer": ([0], [1], 500), "robot_arm": ([0], [1], 800),
                "winding": ([0, 1, 2, 3, 4], [5, 6], 1666)}


def daisy_split(name, centred=True):
    """(estimation, validation) IOData of a shipped DaISy record, the estimation part's
    means removed from both when ``centred``."""
    import sysid

    ins, outs, k = DAISY_SPLITS[name]
    d = np.loadtxt(sysid.datasets.path(name))
    u, y = d[:, ins], d[:, outs]
    if centred:
        u, y = u - u[:k].mean(0), y - y[:k].mean(0)
    return sysid.IOData(u=u[:k], y=y[:k]), sysid.IOData(u=u[k:], y=y[k:])


def feedthrough_record(d, n=800, noise=0.05, seed=1):
    """A record of a second-order plant with direct term ``d`` (the same poles for every
    ``d``): white input, output noise of standard deviation ``noise``."""
    import sysid

    rng = np.random.default_rng(seed)
    true = sysid.StateSpaceModel([[0.8, 0.2], [-0.2, 0.7]], [[1.0], [0.5]], [[1.0, 0.0]],
                                 [[d]])
    u = rng.standard_normal((n, 1))
    return sysid.IOData(u=u, y=true.simulate(u) + noise * rng.standard_normal((n, 1)))


def first_order_record():
    """``(model, u, y, IOData)``: 400 samples of ``y(t+1) = 0.8 y(t) + u(t)`` (dt 0.1) with
    noise 0.05, the record the bad-input tests perturb."""
    import sysid

    rng = np.random.default_rng(0)
    u = rng.standard_normal((400, 1))
    m = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=0.1)
    y = m.simulate(u) + 0.05 * rng.standard_normal((400, 1))
    return m, u, y, sysid.IOData(u=u, y=y, dt=0.1)


def pulsed_record(n, start, stop, level, noise, seed):
    """A helicopter-like record of two inputs: ``u0`` white, ``u1`` zero but ``level`` over
    samples ``start:stop`` (one pulse); one output of a first-order plant driven by both,
    with white noise of standard deviation ``noise``."""
    import sysid

    rng = np.random.default_rng(seed)
    u = np.c_[rng.standard_normal(n), np.zeros(n)]
    u[start:stop, 1] = level
    m = sysid.StateSpaceModel([[0.8]], [[1.0, 0.5]], [[1.0]])
    y = m.simulate(u) + noise * rng.standard_normal((n, 1))
    return sysid.IOData(u, y, 1.0)


def quiet(fn, *a, **k):
    """``fn(*a, **k)`` with every warning silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*a, **k)


def monte_carlo(fit, u, y0, dt, noise, seed, runs=200):
    """``(values, stds)`` of ``fit(data).parameters`` over ``runs`` records ``y0`` plus white
    noise of standard deviation ``noise`` (seeded)."""
    import sysid

    rng = np.random.default_rng(seed)
    est, std = [], []
    for _ in range(runs):
        p = fit(sysid.IOData(u, y0 + noise * rng.standard_normal(y0.shape), dt=dt)).parameters
        est.append(p.value)
        std.append(p.std)
    return np.array(est), np.array(std)


def assert_std_calibrated(est, std, truth):
    """Reported standard deviations against a Monte Carlo run (one row per run): the 95 %
    intervals ``est +- 1.96 std`` cover ``truth`` in 90-99 % of the runs and the mean
    reported std is within 20 % of the estimates' spread, per parameter."""
    est, std = np.asarray(est), np.asarray(std)
    cover = np.mean(np.abs(est - np.asarray(truth)) <= 1.96 * std, axis=0)
    assert np.all((cover >= 0.90) & (cover <= 0.99)), cover
    ratio = est.std(axis=0) / std.mean(axis=0)
    assert np.all((ratio > 0.8) & (ratio < 1.2)), ratio  # within 20 %


def random_system(n, m, l, rng, rmin=0.3, rmax=0.9, feedthrough=True):
    """A random stable (A, B, C, D) with well-separated pole moduli in [rmin, rmax]."""
    blocks = []
    i = 0
    radii = np.linspace(rmin, rmax, n) + 0.02 * rng.standard_normal(n)
    rng.shuffle(radii)
    while i < n:
        r = radii[i]
        if i + 1 < n and rng.random() < 0.6:
            th = 0.3 + 2.4 * rng.random()
            blocks.append(r * np.array([[np.cos(th), np.sin(th)], [-np.sin(th), np.cos(th)]]))
            i += 2
        else:
            blocks.append(np.array([[r if rng.random() < 0.5 else -r]]))
            i += 1
    a = np.zeros((n, n))
    k = 0
    for b in blocks:
        s = b.shape[0]
        a[k : k + s, k : k + s] = b
        k += s
    t = np.eye(n) + 0.3 * rng.standard_normal((n, n))
    a = t @ a @ np.linalg.inv(t)
    b = rng.standard_normal((n, m))
    c = rng.standard_normal((l, n))
    d = rng.standard_normal((l, m)) if feedthrough else np.zeros((l, m))
    return a, b, c, d


def simulate(a, b, c, d, u, x0=None, w=None, v=None):
    """x(t+1) = A x + B u + w, y = C x + D u + v (plain numpy, independent of sysid)."""
    n = a.shape[0]
    N = u.shape[0]
    x = np.zeros(n) if x0 is None else np.array(x0, dtype=float)
    xs = np.empty((N, n))
    bu = u @ b.T
    if w is not None:
        bu = bu + w
    for t in range(N):
        xs[t] = x
        x = a @ x + bu[t]
    y = xs @ c.T + u @ d.T
    if v is not None:
        y = y + v
    return y


def markov(a, b, c, d, count):
    out = [d]
    ab = b
    for _ in range(1, count):
        out.append(c @ ab)
        ab = a @ ab
    return np.array(out)


def match_poles(p_est, p_true):
    """Max distance between two pole sets after optimal pairing."""
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(np.subtract.outer(np.asarray(p_est), np.asarray(p_true)))
    r, c = linear_sum_assignment(cost)
    return float(cost[r, c].max())
